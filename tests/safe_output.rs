//! Nothing the user had is lost, through the binary: an output that is one of the command's
//! inputs is refused before any work, naming both; an output that is not a regular file is never
//! replaced; an interrupted run leaves no temporary file; each error cause is printed once.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn specmap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_specmap"))
        .args(args)
        .output()
        .expect("the specmap binary runs")
}

fn repo(rel: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(rel)
        .display()
        .to_string()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Runs `args`, asserts exit code 1 and nothing on stdout, returns stderr.
fn fails(args: &[&str]) -> String {
    let out = specmap(args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(
        out.status.code(),
        Some(1),
        "{args:?} gave {:?}: {err}",
        out.status
    );
    assert!(out.stdout.is_empty(), "{args:?} printed on stdout");
    err
}

fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

const LAMP_CSV: &str = "wavelength_nm,power\n380,1\n480,2\n580,3\n680,2\n780,1\n";

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// A small RGB lat-long OpenEXR.
fn rgb_exr(path: &Path, w: usize, h: usize) {
    exr::prelude::write_rgb_file(path, w, h, |x, y| {
        (1.0 + x as f32 * 0.1, 0.5, 0.2 + y as f32)
    })
    .unwrap();
}

/// `args` must fail naming `input` as an input that the output would overwrite, and leave the
/// folder exactly as it was.
fn refused_as_input(dir: &Path, input: &Path, args: &[&str]) {
    let before = std::fs::read(input).unwrap();
    let files = listing(dir);
    let err = fails(args);
    assert!(err.contains("is the input"), "{args:?}: {err}");
    assert!(
        err.contains("inputs are never overwritten"),
        "{args:?}: {err}"
    );
    let name = input.file_name().unwrap().to_str().unwrap();
    assert!(
        err.matches(name).count() >= 2,
        "names output and input: {err}"
    );
    assert_eq!(
        std::fs::read(input).unwrap(),
        before,
        "{args:?} changed the input"
    );
    assert_eq!(listing(dir), files, "{args:?} wrote something");
}

#[test]
fn roundtrip_heatmap_over_its_input_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let x = d.path().join("X.exr");
    std::fs::copy(repo("tests/data/truth/sky_e45_t4.spectral.exr"), &x).unwrap();
    refused_as_input(d.path(), &x, &["roundtrip", s(&x), "--heatmap", s(&x)]);
    // Another spelling of the same file.
    let spelled = format!("{}/./X.exr", d.path().display());
    refused_as_input(d.path(), &x, &["roundtrip", s(&x), "--heatmap", &spelled]);
}

#[test]
fn fit_and_data_outputs_over_their_spectrum_files_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let good = write(d.path(), "good.csv", LAMP_CSV.as_bytes());
    refused_as_input(
        d.path(),
        &good,
        &["fit", "--light", s(&good), "-o", s(&good)],
    );
    // A CSV named .png, read as a light and given as the plot.
    let png = write(d.path(), "lamp2.png", LAMP_CSV.as_bytes());
    refused_as_input(
        d.path(),
        &png,
        &["fit", "--light", s(&png), "--plot", s(&png)],
    );
    // TABLE.csv:column form, in the basis.
    let basis = write(
        d.path(),
        "basis.csv",
        b"wavelength_nm,r,g,b\n380,0.9,0.1,0.1\n580,0.5,0.9,0.1\n780,0.9,0.1,0.2\n",
    );
    let b = s(&basis);
    refused_as_input(
        d.path(),
        &basis,
        &[
            "fit",
            "--light",
            "D65",
            "--basis",
            &format!("{b}:r,{b}:g,{b}:b"),
            "-o",
            b,
        ],
    );
    let svg = write(d.path(), "lamp.svg", LAMP_CSV.as_bytes());
    refused_as_input(
        d.path(),
        &svg,
        &["data", "show", s(&svg), "--plot", s(&svg)],
    );
    refused_as_input(
        d.path(),
        &svg,
        &[
            "data",
            "show",
            &format!("{}:power", s(&svg)),
            "--plot",
            s(&svg),
        ],
    );
}

#[test]
fn two_outputs_of_one_command_must_differ() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("same.svg");
    let err = fails(&["fit", "--light", "D65", "-o", s(&out), "--plot", s(&out)]);
    assert!(err.contains("are the same file"), "{err}");
    assert!(listing(d.path()).is_empty());
}

#[test]
fn thinfilm_and_render_outputs_over_their_tables_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let nk = write(
        d.path(),
        "nk.csv",
        b"wavelength_nm,n,k\n380,1.5,0\n580,1.5,0\n780,1.5,0\n",
    );
    let layers = format!("2.7:270,{}:100", s(&nk));
    refused_as_input(
        d.path(),
        &nk,
        &[
            "thinfilm",
            "--layers",
            &layers,
            "--substrate",
            "1.45",
            "--plot",
            s(&nk),
        ],
    );
    refused_as_input(
        d.path(),
        &nk,
        &["thinfilm", "--substrate", s(&nk), "--plot", s(&nk)],
    );
    let lamp = write(d.path(), "lamp.csv", LAMP_CSV.as_bytes());
    refused_as_input(
        d.path(),
        &lamp,
        &[
            "thinfilm",
            "--substrate",
            "1.45",
            "--under",
            s(&lamp),
            "--plot",
            s(&lamp),
        ],
    );
    refused_as_input(
        d.path(),
        &lamp,
        &[
            "render",
            "--backend",
            "cpu",
            "--size",
            "8x8",
            "--diffuse",
            &format!("{}:power", s(&lamp)),
            "-o",
            s(&lamp),
        ],
    );
    let map = d.path().join("map.exr");
    rgb_exr(&map, 16, 8);
    refused_as_input(
        d.path(),
        &map,
        &[
            "render",
            "--backend",
            "cpu",
            "--size",
            "8x8",
            "--env",
            s(&map),
            "-o",
            s(&map),
        ],
    );
}

#[test]
fn convert_refuses_every_face_file_and_its_light_and_fit() {
    let d = tempfile::tempdir().unwrap();
    for f in ["px", "nx", "py", "ny", "pz", "nz"] {
        rgb_exr(&d.path().join(format!("f_{f}.exr")), 8, 8);
    }
    let pattern = format!("{}/f_{{face}}.exr", d.path().display());
    for f in ["px", "nz"] {
        let face = d.path().join(format!("f_{f}.exr"));
        refused_as_input(
            d.path(),
            &face,
            &["convert", &pattern, "--in-layout", "faces", "-o", s(&face)],
        );
    }
    // The signed spelling of the pattern (+x, -x, ...).
    let e = tempfile::tempdir().unwrap();
    for f in ["+x", "-x", "+y", "-y", "+z", "-z"] {
        rgb_exr(&e.path().join(format!("g{f}.exr")), 8, 8);
    }
    let face = e.path().join("g-y.exr");
    let pattern = format!("{}/g{{face}}.exr", e.path().display());
    refused_as_input(e.path(), &face, &["convert", &pattern, "-o", s(&face)]);

    let map = d.path().join("map.exr");
    rgb_exr(&map, 16, 8);
    let lamp = write(d.path(), "lamp.csv", LAMP_CSV.as_bytes());
    refused_as_input(
        d.path(),
        &lamp,
        &["convert", s(&map), "--light", s(&lamp), "-o", s(&lamp)],
    );
    refused_as_input(
        d.path(),
        &lamp,
        &["convert", s(&map), "--sun-spd", s(&lamp), "-o", s(&lamp)],
    );
    let fit = d.path().join("fit.json");
    let out = specmap(&["fit", "--light", "D65", "-o", s(&fit)]);
    assert!(out.status.success());
    refused_as_input(
        d.path(),
        &fit,
        &["convert", s(&map), "--fit", s(&fit), "-o", s(&fit)],
    );
}

#[test]
fn demo_refuses_a_folder_whose_files_include_its_map() {
    let d = tempfile::tempdir().unwrap();
    // An EXR named like one of the demo's renders.
    let chart = d.path().join("chart.png");
    rgb_exr(&chart, 16, 8);
    refused_as_input(
        d.path(),
        &chart,
        &[
            "demo",
            "--quick",
            "--backend",
            "cpu",
            "--env",
            s(&chart),
            "-o",
            s(d.path()),
        ],
    );
}

#[cfg(unix)]
#[test]
fn a_fifo_or_a_directory_is_never_replaced() {
    use std::os::unix::fs::FileTypeExt;
    let d = tempfile::tempdir().unwrap();
    let map = d.path().join("in.exr");
    rgb_exr(&map, 16, 8);
    let fifo = d.path().join("pipe.exr");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let err = fails(&["convert", s(&map), "-o", s(&fifo)]);
    assert!(
        err.contains("pipe.exr exists and is not a regular file"),
        "{err}"
    );
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());
    let err = fails(&["fit", "--light", "D65", "--plot", s(&fifo)]);
    assert!(err.contains("exists and is not a regular file"), "{err}");
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());

    let o = d.path().join("o");
    std::fs::create_dir(&o).unwrap();
    for out in [s(&o).to_string(), format!("{}/", o.display())] {
        let err = fails(&["convert", s(&map), "-o", &out]);
        assert!(err.contains("is a directory: give a file name"), "{err}");
        assert!(!err.contains("Not a directory"), "{err}");
    }
    assert!(listing(&o).is_empty());
    assert_eq!(listing(d.path()), ["in.exr", "o", "pipe.exr"]);
}

#[cfg(target_os = "linux")]
#[test]
fn an_unwritable_folder_is_named_by_the_users_path() {
    let d = tempfile::tempdir().unwrap();
    let map = d.path().join("in.exr");
    rgb_exr(&map, 16, 8);
    let err = fails(&["convert", s(&map), "-o", "/proc/x.exr"]);
    assert!(err.contains("/proc/x.exr"), "{err}");
    assert!(!err.contains(".x.exr."), "no temporary name: {err}");
    for args in [
        &["fit", "--light", "D65", "--plot", "/proc/x.png"][..],
        &["data", "show", "D65", "--plot", "/proc/x.png"],
        &["thinfilm", "--substrate", "1.45", "--plot", "/proc/x.png"],
    ] {
        let err = fails(args);
        assert!(err.contains("/proc/x.png"), "{err}");
        assert!(err.contains("os error"), "the system's reason: {err}");
        assert!(
            !err.contains("Drawing backend") && !err.contains("Os {"),
            "{err}"
        );
        assert_eq!(err.lines().count(), 1, "{err}");
    }
}

#[test]
fn a_missing_input_is_reported_once() {
    let d = tempfile::tempdir().unwrap();
    let nope = d.path().join("nope.csv");
    let nope_exr = d.path().join("nope.exr");
    let out = d.path().join("out.exr");
    for args in [
        &["data", "show", s(&nope)][..],
        &["color", s(&nope)],
        &["convert", s(&nope_exr), "-o", s(&out)],
        &[
            "render",
            "--backend",
            "cpu",
            "--size",
            "8x8",
            "--env",
            s(&nope_exr),
            "-o",
            s(&out),
        ],
        &["rendition", s(&nope_exr), s(&nope_exr)],
        &["roundtrip", s(&nope_exr)],
    ] {
        let err = fails(args);
        assert!(err.contains("nope."), "{args:?}: {err}");
        assert_eq!(err.matches("os error 2").count(), 1, "{args:?}: {err}");
    }
    assert!(listing(d.path()).is_empty());
}

/// Starts a slow conversion into an empty folder, waits for its temporary file, sends `signal`,
/// and checks the exit status, the message naming the signal and the removed file, and that the
/// folder is empty again.
#[cfg(unix)]
fn interrupted(signal: &str, code: i32) {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("k.exr");
    let mut child = Command::new(env!("CARGO_BIN_EXE_specmap"))
        .args(["convert", &repo("envmaps/forest.exr"), "-o", s(&out)])
        .args(["--range", "380:780:1", "--compression", "zip"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // The writer's temporary file, once it holds data (not the empty probe made up front).
    let writing = || {
        listing(d.path()).into_iter().find(|n| {
            n.ends_with(".tmp.exr")
                && std::fs::metadata(d.path().join(n)).is_ok_and(|m| m.len() > 0)
        })
    };
    let t0 = std::time::Instant::now();
    let temp = loop {
        if let Some(t) = writing() {
            break t;
        }
        assert!(
            t0.elapsed().as_secs() < 20,
            "no temporary file appeared in 20 s"
        );
        assert!(child.try_wait().unwrap().is_none(), "convert ended early");
        std::thread::sleep(std::time::Duration::from_millis(10));
    };
    let sent = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
    let done = child.wait_with_output().unwrap();
    assert!(!done.status.success());
    assert_eq!(done.status.code(), Some(code), "{:?}", done.status);
    assert!(listing(d.path()).is_empty(), "{:?}", listing(d.path()));
    let stderr = String::from_utf8_lossy(&done.stderr);
    let said = format!("interrupted by SIG{}: removed", &signal[1..]);
    assert!(stderr.contains(&said), "{stderr}");
    assert!(
        stderr.contains(&d.path().join(&temp).display().to_string()),
        "{temp} not named: {stderr}"
    );
    assert!(!stderr.contains("error"), "{stderr}");
}

#[cfg(unix)]
#[test]
fn sigint_removes_the_temporary_file_and_exits_130() {
    interrupted("-INT", 130);
}

#[cfg(unix)]
#[test]
fn sigterm_removes_the_temporary_file_and_exits_143() {
    interrupted("-TERM", 143);
}

#[cfg(unix)]
#[test]
fn sighup_removes_the_temporary_file_and_exits_129() {
    interrupted("-HUP", 129);
}

/// One behaviour for every command: the folder of an output file is never created; a missing
/// one is refused before any work, named (a folder output such as `demo -o` creates itself).
#[test]
fn a_missing_output_folder_is_refused_by_every_command() {
    let d = tempfile::tempdir().unwrap();
    let map = d.path().join("in.exr");
    rgb_exr(&map, 16, 8);
    let missing = d.path().join("new").join("folder");
    let file = |name: &str| missing.join(name).display().to_string();
    let (exr, png, json) = (file("x.exr"), file("x.png"), file("x.json"));
    let truth = repo("tests/data/truth/sky_e45_t4.spectral.exr");
    for args in [
        &["convert", s(&map), "-o", &exr][..],
        &["fit", "--light", "D65", "-o", &json],
        &["data", "show", "D65", "--plot", &png],
        &["thinfilm", "--substrate", "1.45", "--plot", &png],
        &["render", "--backend", "cpu", "--size", "8x8", "-o", &png],
        &["roundtrip", &truth, "--heatmap", &png],
    ] {
        let err = fails(args);
        assert!(
            err.contains(&format!("the folder {} does not exist", missing.display())),
            "{args:?}: {err}"
        );
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    }
    assert_eq!(listing(d.path()), ["in.exr"]);
}
