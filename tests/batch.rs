//! `specmap batch` through the binary: a folder with a corrupt map among good ones, a batch
//! killed mid-way and resumed, two shards run at once by GNU parallel, and a second run that
//! skips everything. Each converted map is compared with `specmap convert` of the same map
//! (read back with the exr crate), and the manifests are read as JSON.

mod common;

use common::specmap;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A small RGB lat-long map whose colours depend on `seed`.
fn map(path: &Path, seed: usize, w: usize) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    let k = seed as f32;
    exr::prelude::write_rgb_file(path, w, w / 2, |x, y| {
        (
            0.1 + 0.01 * (x as f32 + k),
            0.2 + 0.3 * ((y as f32 + k) * 0.1).sin().abs(),
            0.05 + 0.02 * k,
        )
    })
    .unwrap();
}

/// The records of every manifest in `dir`.
fn records(dir: &Path) -> Vec<serde_json::Value> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if name.starts_with("specmap-batch") && name.ends_with(".jsonl") {
            // A line being appended by a running batch is not whole yet.
            let text = std::fs::read_to_string(&p).unwrap();
            for line in text.lines().filter(|l| l.ends_with('}')) {
                out.push(serde_json::from_str(line).unwrap_or_else(|e| panic!("{name}: {e}")));
            }
        }
    }
    out
}

/// How many records of each status each output has.
fn statuses(dir: &Path) -> BTreeMap<(String, String), usize> {
    let mut m = BTreeMap::new();
    for r in records(dir) {
        let key = (
            r["output"].as_str().unwrap().to_string(),
            r["status"].as_str().unwrap().to_string(),
        );
        *m.entry(key).or_insert(0) += 1;
    }
    m
}

fn files_below(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = walk(dir)
        .iter()
        .map(|p| p.strip_prefix(dir).unwrap().display().to_string())
        .collect();
    v.sort();
    v
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

/// The pixels of every channel of an EXR, by channel name.
fn pixels(path: &Path) -> BTreeMap<String, Vec<f32>> {
    let img = exr::prelude::read_all_flat_layers_from_file(path).unwrap();
    let layer = &img.layer_data[0];
    layer
        .channel_data
        .list
        .iter()
        .map(|c| {
            let v = c.sample_data.values_as_f32().collect();
            (c.name.to_string(), v)
        })
        .collect()
}

const FAST: [&str; 4] = ["--range", "400:700:20", "--sun", "off"];

#[test]
fn a_corrupt_map_fails_alone_and_a_second_run_skips_everything() {
    let d = tempfile::tempdir().unwrap();
    let lib = d.path().join("lib");
    map(&lib.join("a.exr"), 1, 32);
    map(&lib.join("sub/b.exr"), 2, 32);
    std::fs::write(lib.join("broken.exr"), b"v/1\x01 not an image").unwrap();
    std::fs::write(lib.join("notes.txt"), "not a map").unwrap();
    let out = d.path().join("out");
    // Two maps at once: one failing does not disturb the other.
    let mut args = vec!["batch", s(&lib), "--out-dir", s(&out), "--jobs", "2"];
    args.extend(FAST);
    let first = specmap(&args);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&first.stdout),
        String::from_utf8_lossy(&first.stderr),
    );
    assert_eq!(first.status.code(), Some(1), "{stdout}{stderr}");
    assert!(
        stdout.contains("3 inputs: 2 converted, 0 skipped, 1 failed"),
        "{stdout}"
    );
    assert!(
        stderr.contains("broken.exr") && stderr.contains("1 of 3 inputs failed"),
        "{stderr}"
    );
    assert_eq!(
        files_below(&out),
        [
            "a.spectral.exr",
            "specmap-batch.jsonl",
            "sub/b.spectral.exr"
        ]
    );
    let rs = records(&out);
    let broken = rs.iter().find(|r| r["status"] == "failed").unwrap();
    assert!(broken["input"].as_str().unwrap().ends_with("broken.exr"));
    assert!(
        broken["error"].as_str().unwrap().contains("broken.exr"),
        "{broken}"
    );
    let good = rs
        .iter()
        .find(|r| r["output"] == "sub/b.spectral.exr")
        .unwrap();
    assert_eq!(good["status"], "converted");
    // The lights the conversion found, as `convert --json` has them.
    let lights = good["lights"].as_array().expect("a lights array");
    assert!(
        lights
            .iter()
            .all(|l| l["kind"].is_string() && l["spd"].is_string()),
        "{lights:?}"
    );
    assert!(good["fingerprint"]["blake3"].as_str().unwrap().len() == 64);
    assert!(good["seconds"].as_f64().unwrap() > 0.0);

    // The batch's output is `convert`'s, pixel for pixel.
    let alone = d.path().join("alone.exr");
    let b = lib.join("sub/b.exr");
    let mut conv = vec!["convert", s(&b), "-o", s(&alone), "--quiet"];
    conv.extend(FAST);
    assert!(specmap(&conv).status.success());
    assert_eq!(pixels(&alone), pixels(&out.join("sub/b.spectral.exr")));

    // Again: the good ones are up to date, the broken one fails again; nothing is rewritten.
    let before: Vec<_> = ["a.spectral.exr", "sub/b.spectral.exr"]
        .map(|f| std::fs::metadata(out.join(f)).unwrap().modified().unwrap())
        .to_vec();
    std::fs::remove_file(lib.join("broken.exr")).unwrap();
    let second = specmap(&args);
    let stdout = String::from_utf8_lossy(&second.stdout);
    assert!(second.status.success(), "{stdout}");
    assert!(
        stdout.contains("2 inputs: 0 converted, 2 skipped, 0 failed"),
        "{stdout}"
    );
    let after: Vec<_> = ["a.spectral.exr", "sub/b.spectral.exr"]
        .map(|f| std::fs::metadata(out.join(f)).unwrap().modified().unwrap())
        .to_vec();
    assert_eq!(before, after);
    // Other settings convert again, and say why.
    let mut other = args.clone();
    other.extend(["--zip-level", "1", "--dry-run"]);
    let plan = String::from_utf8_lossy(&specmap(&other).stdout).into_owned();
    assert_eq!(
        plan.matches("convert  (the settings changed").count(),
        2,
        "{plan}"
    );
    // A changed input converts again.
    map(&lib.join("a.exr"), 7, 32);
    let mut dry = args.clone();
    dry.push("--dry-run");
    let plan = String::from_utf8_lossy(&specmap(&dry).stdout).into_owned();
    assert!(plan.contains("convert  (the input changed)"), "{plan}");
    assert!(plan.contains("skip     (up to date)"), "{plan}");
}

#[cfg(unix)]
#[test]
fn a_batch_killed_mid_way_leaves_no_partial_output_and_a_second_run_finishes_the_rest() {
    let d = tempfile::tempdir().unwrap();
    let lib = d.path().join("lib");
    let n = 12;
    for i in 0..n {
        map(&lib.join(format!("m{i:02}.exr")), i, 256);
    }
    let out = d.path().join("out");
    let args = [
        "batch",
        s(&lib),
        "--out-dir",
        s(&out),
        "--range",
        "380:780:1",
        "--threads",
        "1",
    ];
    let mut child = Command::new(env!("CARGO_BIN_EXE_specmap"))
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Killed once one map is done and the next is being written.
    let t0 = std::time::Instant::now();
    let converted = |out: &Path| match out.is_dir() {
        false => 0,
        true => records(out)
            .iter()
            .filter(|r| r["status"] == "converted")
            .count(),
    };
    loop {
        let writing = out.is_dir() && files_below(&out).iter().any(|f| f.ends_with(".tmp.exr"));
        if converted(&out) >= 1 && writing {
            break;
        }
        assert!(child.try_wait().unwrap().is_none(), "the batch ended early");
        assert!(t0.elapsed().as_secs() < 120, "no map converted in 120 s");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert_eq!(child.wait().unwrap().code(), Some(130));
    let done = converted(&out);
    assert!(done < n, "all {n} were done before the interrupt");
    // No temporary file is left, and every output there is a whole, recorded map.
    let files = files_below(&out);
    assert!(!files.iter().any(|f| f.contains(".tmp")), "{files:?}");
    let outputs: Vec<&String> = files
        .iter()
        .filter(|f| f.ends_with(".spectral.exr"))
        .collect();
    assert_eq!(outputs.len(), done, "{files:?}");
    for f in &outputs {
        assert_eq!(pixels(&out.join(f)).len(), 401 + 4, "{f}");
    }
    // The second run converts the rest and only the rest.
    let second = specmap(&args);
    let stdout = String::from_utf8_lossy(&second.stdout);
    assert!(second.status.success(), "{stdout}");
    let want = format!(
        "{n} inputs: {} converted, {done} skipped, 0 failed",
        n - done
    );
    assert!(stdout.contains(&want), "{stdout}");
    let st = statuses(&out);
    for i in 0..n {
        let name = format!("m{i:02}.spectral.exr");
        assert_eq!(
            st.get(&(name.clone(), "converted".into())),
            Some(&1),
            "{name}: {st:?}"
        );
    }
}

#[test]
fn two_shards_under_gnu_parallel_convert_every_map_once() {
    let found = Command::new("parallel").arg("--version").output();
    assert!(
        found.is_ok_and(|o| o.status.success()),
        "GNU parallel is needed (Debian package `parallel`; tools/test.sh installs it)"
    );
    let d = tempfile::tempdir().unwrap();
    let lib = d.path().join("lib");
    let n = 7;
    for i in 0..n {
        map(&lib.join(format!("m{i}.exr")), i, 64);
    }
    // The inputs as a list, one a line, relative to the list.
    let list = lib.join("maps.txt");
    let names: Vec<String> = (0..n).map(|i| format!("m{i}.exr")).collect();
    std::fs::write(&list, names.join("\n") + "\n").unwrap();
    let out = d.path().join("out");
    let command = format!(
        "{} batch {} --out-dir {} --threads 1 --range 400:700:10 --shard {{}}/2",
        env!("CARGO_BIN_EXE_specmap"),
        s(&list),
        s(&out)
    );
    let run = Command::new("parallel")
        .args(["--halt", "never", &command, ":::", "0", "1"])
        .output()
        .unwrap();
    let text =
        String::from_utf8_lossy(&run.stdout).into_owned() + &String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{text}");
    // Each shard wrote its own manifest, and between them every map was converted once.
    let mut files = files_below(&out);
    files.retain(|f| f.ends_with(".jsonl"));
    assert_eq!(
        files,
        [
            "specmap-batch.shard-0-of-2.jsonl",
            "specmap-batch.shard-1-of-2.jsonl"
        ]
    );
    assert!(text.contains("4 inputs (shard 0/2 of 7)"), "{text}");
    assert!(text.contains("3 inputs (shard 1/2 of 7)"), "{text}");
    let st = statuses(&out);
    assert_eq!(st.len(), n, "{st:?}");
    for name in &names {
        let out_name = name.replace(".exr", ".spectral.exr");
        assert_eq!(st.get(&(out_name, "converted".into())), Some(&1), "{st:?}");
    }
    // Unsharded, the same folder is up to date.
    let again = specmap(&[
        "batch",
        s(&list),
        "--out-dir",
        s(&out),
        "--range",
        "400:700:10",
    ]);
    let stdout = String::from_utf8_lossy(&again.stdout);
    assert!(
        stdout.contains("7 inputs: 0 converted, 7 skipped"),
        "{stdout}"
    );
}

/// The Slurm array script, run as two array tasks would run it (no Slurm needed: it reads the
/// task's variables), converts every map once between them.
#[cfg(unix)]
#[test]
fn the_slurm_array_script_gives_each_task_its_share() {
    let d = tempfile::tempdir().unwrap();
    let lib = d.path().join("lib");
    for i in 0..3 {
        map(&lib.join(format!("m{i}.exr")), i, 32);
    }
    let out = d.path().join("out");
    let script =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("integrations/slurm/specmap-batch.sbatch");
    for task in ["0", "1"] {
        let run = Command::new("bash")
            .arg(&script)
            .args([s(&lib), s(&out), "--range", "400:700:20"])
            .env("SPECMAP", env!("CARGO_BIN_EXE_specmap"))
            .env("SLURM_ARRAY_TASK_ID", task)
            .env("SLURM_ARRAY_TASK_COUNT", "2")
            .env("SLURM_CPUS_PER_TASK", "1")
            .output()
            .unwrap();
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
    }
    let st = statuses(&out);
    assert_eq!(st.len(), 3, "{st:?}");
    assert!(st.values().all(|&n| n == 1), "{st:?}");
    assert!(out.join("specmap-batch.shard-1-of-2.jsonl").is_file());
}
