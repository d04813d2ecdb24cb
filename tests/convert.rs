//! `specmap convert` on the real sample maps and on bad input, through the binary.

use exr::prelude::*;
use std::path::Path;
use std::process::Command;

mod common;

use common::{sample, specmap};

fn convert_json(args: &[&str]) -> serde_json::Value {
    let mut all = vec!["convert"];
    all.extend_from_slice(args);
    all.push("--json");
    let out = specmap(&all);
    assert!(
        out.status.success(),
        "convert {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn fails(args: &[&str]) -> String {
    let mut all = vec!["convert"];
    all.extend_from_slice(args);
    let out = specmap(&all);
    assert!(!out.status.success(), "convert {args:?} succeeded");
    assert_eq!(out.status.code(), Some(1));
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Only `expected` files are left in `dir`: no partial output, no temporary file.
fn assert_only(dir: &Path, expected: &[&str]) {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let mut want: Vec<String> = expected.iter().map(|s| s.to_string()).collect();
    want.sort();
    assert_eq!(names, want);
}

fn write_rgb(path: &Path, w: usize, h: usize, f: impl Fn(usize, usize) -> [f32; 3] + Sync) {
    write_rgb_file(path, w, h, |x, y| {
        let p = f(x, y);
        (p[0], p[1], p[2])
    })
    .unwrap();
}

#[test]
fn sunrise_has_a_sun_and_forest_has_none_in_both_layouts() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("sunrise.exr");
    let r = convert_json(&[&sample("sunrise.exr"), "-o", out.to_str().unwrap()]);
    assert_eq!(r["input_layout"], "latlong");
    assert_eq!(r["output_size"], serde_json::json!([1024, 512]));
    assert_eq!(r["sun"]["found"], true);
    let elevation = r["sun"]["elevation_deg"].as_f64().unwrap();
    assert!((0.0..20.0).contains(&elevation), "a low sun: {elevation}");
    assert!(r["sun"]["energy_share"].as_f64().unwrap() > 0.4);
    // The default (faithful) gives the sun the daylight of its own colour; the paper gives D65.
    assert_eq!(r["mode"], "faithful");
    // The lights of the scene: the sun, then the sky.
    let kinds: Vec<&str> = r["lights"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["kind"].as_str().unwrap())
        .collect();
    assert_eq!(kinds, ["sun", "sky"], "{}", r["lights"]);
    assert!(
        r["sun_spd"].as_str().unwrap().starts_with("CIE daylight"),
        "{}",
        r["sun_spd"]
    );
    assert_eq!(r["wavelengths_nm"].as_array().unwrap().len(), 81);
    assert_eq!(r["channels"], 81 + 4);
    assert!(
        r["sanitized"]["negative"].as_u64().unwrap()
            + r["sanitized"]["negative_kept"].as_u64().unwrap()
            > 0,
        "DWAB leaves negatives"
    );
    // Every written spectrum is non-negative, and away from the sun the round trip is exact
    // (to half precision, not measured here: this is the analytic one) but for the few pixels
    // whose colour no non-negative spectrum under daylight makes (DWAB's negatives on dark
    // pixels), which are counted.
    assert_eq!(r["spectra"]["negative"], 0);
    assert!(
        r["roundtrip_without_sun"]["weighted_mean_de2000"]
            .as_f64()
            .unwrap()
            < 1e-3
    );
    // The inexact pixels: those in the statistic and those below its luminance floor.
    let inexact = r["inexact"]["pixels"].as_u64().unwrap()
        + r["inexact"]["below_floor"]["pixels"].as_u64().unwrap();
    assert!(inexact < 512 * 1024 / 1000, "{}", r["inexact"]);
    assert_eq!(inexact, r["spectra"]["nearest"].as_u64().unwrap());

    let cube = d.path().join("forest-cube.exr");
    let r = convert_json(&[
        &sample("forest.exr"),
        "-o",
        cube.to_str().unwrap(),
        "--out-layout",
        "cube",
        "--size",
        "64",
        "--light",
        "auto",
        "--quiet",
    ]);
    assert_eq!(r["output_layout"], "cube");
    assert_eq!(r["output_size"], serde_json::json!([64, 384]));
    assert_eq!(r["sun"]["found"], false);
    // The brightest region is sky between the trees, not a sun (at 64-pixel faces the gaps
    // blur into one region, too large for a sun).
    assert!(r["sun"]["reason"]
        .as_str()
        .unwrap()
        .contains("brightest region"));
    assert_eq!(r["lights"][0]["kind"], "sky", "{}", r["lights"]);
    assert!(r["lights"][0]["spd"]
        .as_str()
        .unwrap()
        .starts_with("daylight"));
    assert_eq!(r["light"], "D65");
    // The cube converts back to a lat-long map (the envmap attribute says cube).
    let back = d.path().join("forest-back.exr");
    let r = convert_json(&[
        cube.to_str().unwrap(),
        "-o",
        back.to_str().unwrap(),
        "--out-layout",
        "latlong",
        "--quiet",
    ]);
    assert_eq!(r["input_layout"], "cube");
    assert_eq!(r["output_size"], serde_json::json!([256, 128]));
    assert_only(
        d.path(),
        &["sunrise.exr", "forest-cube.exr", "forest-back.exr"],
    );
}

#[test]
fn up_and_rotation_turn_the_map_and_its_sun() {
    // The sun of sunrise.exr, found after the map is turned, sits where the orientation puts
    // it: a quarter turn about up takes map (x, y, z) to world (z, y, -x); Z-up takes it to
    // (x, z, -y), lifting the low sun to about 53 degrees.
    let d = tempfile::tempdir().unwrap();
    let sun_dir = |extra: &[&str]| {
        let out = d.path().join("turned.exr");
        let mut args = vec![
            sample("sunrise.exr"),
            "-o".into(),
            out.display().to_string(),
        ];
        args.extend(extra.iter().map(|s| s.to_string()));
        args.extend(["--quiet", "--range", "400:700:20"].map(String::from));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let r = convert_json(&args);
        assert_eq!(r["sun"]["found"], true, "{extra:?}: {}", r["sun"]);
        let v: Vec<f64> = r["sun"]["direction"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        [v[0], v[1], v[2]]
    };
    let [x, y, z] = sun_dir(&[]);
    let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|i| (a[i] - b[i]).abs() < 0.02);
    let turned = sun_dir(&["--rotation", "90"]);
    assert!(close(turned, [z, y, -x]), "{turned:?} vs {:?}", [z, y, -x]);
    let back = sun_dir(&["--rotation", "-90"]);
    assert!(close(back, [-z, y, x]), "{back:?}");
    let z_up = sun_dir(&["--up", "z"]);
    assert!(close(z_up, [x, z, -y]), "{z_up:?} vs {:?}", [x, z, -y]);
}

#[test]
fn a_progress_bar_on_a_terminal_only() {
    // util-linux's `script` gives the command a terminal (it is in every Debian install).
    let Some(script) = which_script() else {
        eprintln!("skipped: no `script` command to give the conversion a terminal");
        return;
    };
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("p.exr");
    let run = |extra: &str| {
        let cmd = format!(
            "{} convert {} -o {} --range 400:700:20 {extra}",
            env!("CARGO_BIN_EXE_specmap"),
            sample("sunrise.exr"),
            out.display()
        );
        let o = Command::new(&script)
            .args(["-qec", &cmd, "/dev/null"])
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{cmd}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let shown = run("");
    assert!(shown.contains("converting ["), "{shown}");
    assert!(shown.contains("512/512 rows"), "{shown}");
    assert!(
        !shown.contains("0/0 rows"),
        "drawn before the row count was known: {shown}"
    );
    // --quiet: nothing at all, on a terminal too.
    let quiet = run("--quiet");
    assert!(quiet.trim().is_empty(), "{quiet}");
    // Not a terminal: no bar (the tests above capture stderr through a pipe).
    let piped = specmap(&[
        "convert",
        &sample("sunrise.exr"),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!String::from_utf8_lossy(&piped.stderr).contains("converting ["));
}

fn which_script() -> Option<std::path::PathBuf> {
    ["/usr/bin/script", "/bin/script"]
        .iter()
        .map(std::path::PathBuf::from)
        .find(|p| p.exists())
}

#[test]
fn output_equal_to_input_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("in.exr");
    write_rgb(&input, 16, 8, |_, _| [1.0, 1.0, 1.0]);
    let before = std::fs::read(&input).unwrap();
    let msg = fails(&[input.to_str().unwrap(), "-o", input.to_str().unwrap()]);
    assert!(msg.contains("is the input"), "{msg}");
    assert_eq!(
        std::fs::read(&input).unwrap(),
        before,
        "the input is untouched"
    );
}

#[test]
fn a_map_that_is_not_2_to_1_asks_for_a_layout() {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("odd.exr");
    write_rgb(&input, 100, 30, |_, _| [1.0, 1.0, 1.0]);
    let out = d.path().join("out.exr");
    let msg = fails(&[input.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(
        msg.contains("100x30") && msg.contains("--in-layout"),
        "{msg}"
    );
    let msg = fails(&[
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--in-layout",
        "latlong",
    ]);
    assert!(msg.contains("2:1"), "{msg}");
    assert_only(d.path(), &["odd.exr"]);
}

#[test]
fn cube_faces_of_unequal_size_are_refused() {
    let d = tempfile::tempdir().unwrap();
    for (i, f) in ["px", "nx", "py", "ny", "pz", "nz"].iter().enumerate() {
        let n = if i == 3 { 8 } else { 16 };
        write_rgb(&d.path().join(format!("face_{f}.exr")), n, n, |_, _| {
            [1.0; 3]
        });
    }
    let pattern = d.path().join("face_{face}.exr");
    let out = d.path().join("out.exr");
    let msg = fails(&[
        pattern.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--in-layout",
        "faces",
    ]);
    assert!(
        msg.contains("-Y") || msg.contains("ny"),
        "names the face: {msg}"
    );
    assert!(!out.exists());
}

#[test]
fn truncated_and_corrupt_files_are_clear_errors_with_no_output() {
    let d = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(sample("forest.exr")).unwrap();
    let cut = d.path().join("cut.exr");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let out = d.path().join("out.exr");
    let msg = fails(&[cut.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(msg.contains("cut.exr"), "{msg}");
    let junk = d.path().join("junk.exr");
    std::fs::write(&junk, b"not an image at all").unwrap();
    let msg = fails(&[junk.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(msg.contains("junk.exr"), "{msg}");
    assert_only(d.path(), &["cut.exr", "junk.exr"]);
}

#[test]
fn a_missing_channel_names_what_the_file_has() {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("xyz.exr");
    let channels = SpecificChannels::build()
        .with_channel("X")
        .with_channel("Z")
        .with_pixel_fn(|_pos| (0.5f32, 0.5f32));
    Image::from_channels((16, 8), channels)
        .write()
        .to_file(&input)
        .unwrap();
    let out = d.path().join("out.exr");
    let msg = fails(&[input.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(msg.contains('X') && msg.contains('Z'), "{msg}");
    assert!(!out.exists());
}

#[test]
fn nan_and_negative_pixels_are_counted_or_refused() {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("nan.exr");
    write_rgb(&input, 32, 16, |x, y| match (x, y) {
        (3, 4) => [f32::NAN, 1.0, 1.0],
        (5, 6) => [f32::INFINITY, 1.0, -2.0],
        (7, 7) => [-0.5, 1.0, 1.0],
        _ => [0.5, 0.5, 0.5],
    });
    let out = d.path().join("out.exr");
    let r = convert_json(&[input.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(r["sanitized"]["non_finite"], 2);
    // (5, 6)'s -2 is clamped (the pixel was not finite); (7, 7) is an out-of-gamut colour of
    // positive luminance, kept under the D65 premise...
    assert_eq!(r["sanitized"]["negative"], 1);
    assert_eq!(r["sanitized"]["negative_kept"], 1);
    std::fs::remove_file(&out).unwrap();
    // ...and clamped under the paper's premise (the map white-balanced to its light).
    let r = convert_json(&[
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--mode",
        "exact",
        "--light",
        "A",
    ]);
    assert_eq!(r["white"]["premise"], "light");
    assert_eq!(r["sanitized"]["negative"], 2);
    assert_eq!(r["sanitized"]["negative_kept"], 0);
    std::fs::remove_file(&out).unwrap();
    let msg = fails(&[
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--strict",
    ]);
    assert!(msg.contains("(3, 4)") && msg.contains("NaN"), "{msg}");
    assert_only(d.path(), &["nan.exr"]);
}

#[test]
fn values_beyond_half_range_get_an_ev_scale_not_clipping() {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("bright.exr");
    write_rgb(&input, 32, 16, |x, y| {
        if (x, y) == (10, 5) {
            [1.0e6, 1.0e6, 1.0e6]
        } else {
            [0.2, 0.3, 0.4]
        }
    });
    let out = d.path().join("out.exr");
    let r = convert_json(&[
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--sun",
        "off",
    ]);
    let ev = r["ev"].as_f64().expect("an EV scale");
    assert!(ev >= 4.0, "{ev}");
    // The brightest value survives: read the R preview back and undo the EV scale.
    let image = read_first_flat_layer_from_file(&out).unwrap();
    let r_channel = image
        .layer_data
        .channel_data
        .list
        .iter()
        .find(|c| c.name == *"R")
        .unwrap();
    let max = r_channel.sample_data.values_as_f32().fold(0f32, f32::max);
    assert!(
        (max * 2f32.powf(ev as f32) / 1.0e6 - 1.0).abs() < 1e-3,
        "{max}"
    );
}

#[test]
fn basis_format_has_k_channels_and_the_spectra_in_the_header() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("basis.exr");
    let r = convert_json(&[
        &sample("sunrise.exr"),
        "-o",
        out.to_str().unwrap(),
        "--format",
        "basis",
        "--out-layout",
        "cube",
        "--size",
        "32",
        "--quiet",
    ]);
    // The default method is written in its own spectra: K of them, the sun's among them.
    assert_eq!(r["mode"], "faithful");
    let k = r["basis"]["k"].as_u64().unwrap() as usize;
    assert!((2..=32).contains(&k), "{}", r["basis"]);
    assert_eq!(r["basis"]["sun"], r["sun"]["found"], "{}", r["sun"]);
    assert_eq!(r["channels"], k + 3);
    let meta = exr::meta::MetaData::read_from_file(&out, false).unwrap();
    let h = &meta.headers[0];
    let mut names: Vec<String> = h.channels.list.iter().map(|c| c.name.to_string()).collect();
    names.sort();
    let mut want: Vec<String> = (0..k).map(|j| format!("k{j:02}")).collect();
    want.extend(["B", "G", "R"].map(String::from));
    want.sort();
    assert_eq!(names, want);
    let mut keys = vec![
        "specmap.basisVersion".to_string(),
        "specmap.basisK".into(),
        "specmap.basisSun".into(),
        "specmap.wavelengths".into(),
    ];
    keys.extend((0..k).map(|j| format!("specmap.basis{j:02}")));
    for key in keys {
        assert!(
            h.own_attributes
                .other
                .contains_key(&Text::from(key.as_str())),
            "{key} missing"
        );
    }
    // No intermediate file is left beside the output.
    let left: Vec<_> = std::fs::read_dir(d.path()).unwrap().collect();
    assert_eq!(left.len(), 1);
}

/// `--white`: what RGB (1,1,1) means is chosen, reported, and recorded for `roundtrip`.
#[test]
fn the_white_premise_is_chosen_reported_and_recorded() {
    let d = tempfile::tempdir().unwrap();
    // A room lit by a sodium lamp, D65-referenced: the lamp and the walls it lights are orange.
    let input = d.path().join("orange.exr");
    use specmap::envmap::scene::main_light::{rgb_of_xy, white_xy};
    let lamp = rgb_of_xy(
        white_xy("hps").unwrap(),
        &specmap::colorimetry::RgbSpace::SRGB,
    );
    write_rgb(&input, 64, 32, |_, y| {
        if y < 6 {
            lamp.map(|c| c * 30.0)
        } else {
            lamp.map(|c| c * 0.3)
        }
    });
    let out = d.path().join("out.exr");
    let o = out.to_str().unwrap();
    let i = input.to_str().unwrap();
    // --light auto --lights one chooses the lamp and, seeing it orange, the premise that RGB
    // (1,1,1) is the space's white (sRGB's: D65).
    let r = convert_json(&[i, "-o", o, "--light", "auto", "--lights", "one"]);
    assert_eq!(r["light"], "hps", "{}", r["light_choice"]);
    assert_eq!(r["white"]["premise"], "space");
    assert!(r["white"]["reason"]
        .as_str()
        .unwrap()
        .contains("colour of hps"));
    let meta = exr::meta::MetaData::read_from_file(&out, false).unwrap();
    let attrs = &meta.headers[0].own_attributes.other;
    assert!(matches!(
        attrs.get(&Text::from("specmap.white")),
        Some(AttributeValue::Text(t)) if t == "space"
    ));
    // The file round trip needs no white balance under the space's-white premise.
    let rt = specmap(&["roundtrip", o, "--json"]);
    assert!(
        rt.status.success(),
        "{}",
        String::from_utf8_lossy(&rt.stderr)
    );
    let rt: serde_json::Value = serde_json::from_slice(&rt.stdout).unwrap();
    assert!(
        rt["all"]["weighted_mean_de2000"].as_f64().unwrap() < 0.05,
        "{rt}"
    );
    std::fs::remove_file(&out).unwrap();
    // Explicit premises win over the scene.
    let r = convert_json(&[i, "-o", o, "--light", "hps", "--white", "light"]);
    assert_eq!(r["white"]["premise"], "light");
    std::fs::remove_file(&out).unwrap();
    // The paper's mode with a named light keeps the paper's premise.
    let r = convert_json(&[i, "-o", o, "--mode", "paper", "--light", "hps"]);
    assert_eq!(r["white"]["premise"], "light");
    assert_eq!(r["mode"], "paper");
    std::fs::remove_file(&out).unwrap();
    // A neutral map under a named lamp: balanced to it (the paper's case).
    let grey = d.path().join("grey.exr");
    write_rgb(
        &grey,
        64,
        32,
        |_, y| if y < 6 { [20.0; 3] } else { [0.2; 3] },
    );
    let r = convert_json(&[grey.to_str().unwrap(), "-o", o, "--light", "FL2"]);
    assert_eq!(r["white"]["premise"], "light");
    assert!(r["white"]["reason"].as_str().unwrap().contains("neutral"));
}

/// A vertical strip (N x 6N, +X -X +Y -Y +Z -Z) holds the pixels of OpenEXR's cube: the same
/// pixels read as either convert to the same lat-long, pixel for pixel. (Read with ±Y turned
/// 180°, a strip of OpenEXR's faces came out scrambled at the poles.)
#[test]
fn a_vertical_strip_converts_as_the_cube_of_the_same_pixels() {
    let d = tempfile::tempdir().unwrap();
    let n = 16;
    let input = d.path().join("faces.exr");
    // A different gradient on every face, so that a turned or swapped face shows.
    write_rgb(&input, n, 6 * n, |x, y| {
        let (face, j) = (y / n, y % n);
        [
            0.1 + (face as f32 + 1.0) * 0.2,
            0.2 + x as f32 / n as f32,
            0.3 + j as f32 / n as f32,
        ]
    });
    let preview = |layout: &str| {
        let out = d.path().join(format!("{layout}.exr"));
        let r = convert_json(&[
            input.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--in-layout",
            layout,
            "--out-layout",
            "latlong",
            "--size",
            "32",
            "--sun",
            "off",
            "--range",
            "400:700:50",
            "--precision",
            "float",
        ]);
        assert_eq!(r["input_layout"], layout);
        specmap::envmap::files::read_rgb(&out, None)
            .unwrap()
            .image
            .pixels
    };
    let (cube, strip) = (preview("cube"), preview("vstrip"));
    assert_eq!(cube.len(), 64 * 32);
    let differ = cube.iter().zip(&strip).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "{differ} of {} pixels differ", cube.len());
}

/// `--quiet` prints nothing but errors: nothing on success (with --json, the JSON alone), the
/// error alone on failure.
#[test]
fn quiet_prints_nothing_but_errors() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("q.exr");
    let args = |extra: &[&'static str]| {
        let mut v = vec![
            "convert".to_string(),
            sample("sunrise.exr"),
            "-o".into(),
            out.display().to_string(),
            "--range".into(),
            "400:700:20".into(),
            "--quiet".into(),
        ];
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let run = |extra: &[&'static str]| {
        let a = args(extra);
        specmap(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let ok = run(&[]);
    assert!(ok.status.success());
    assert_eq!(String::from_utf8_lossy(&ok.stdout), "");
    assert_eq!(String::from_utf8_lossy(&ok.stderr), "");
    assert!(out.is_file());
    let json = run(&["--json"]);
    assert!(json.status.success());
    assert_eq!(String::from_utf8_lossy(&json.stderr), "");
    let v: serde_json::Value = serde_json::from_slice(&json.stdout).expect("JSON alone");
    assert_eq!(v["input_layout"], "latlong");
    let bad = run(&["--rotation", "inf"]);
    assert_eq!(bad.status.code(), Some(1));
    assert_eq!(String::from_utf8_lossy(&bad.stdout), "");
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.starts_with("error: --rotation inf"), "{err}");
}

/// Half precision loses nothing silently: the EV scale leaves the sun mask 0/1 (roundtrip still
/// finds the sun), and a scale that would flush dim pixels to zero makes the file float.
#[test]
fn the_ev_scale_keeps_the_sun_mask_and_never_flushes_pixels() {
    let d = tempfile::tempdir().unwrap();
    // A blue sky and a sun of 200000: beyond half's 65504, so EV > 0.
    let input = d.path().join("bright.exr");
    write_rgb(&input, 128, 64, |x, y| {
        if (x, y) == (64, 20) {
            [200000.0, 190000.0, 170000.0]
        } else if y < 32 {
            [0.5, 0.7, 1.0]
        } else {
            [0.2, 0.2, 0.2]
        }
    });
    let out = d.path().join("bright.spectral.exr");
    let o = out.to_str().unwrap();
    let r = convert_json(&[input.to_str().unwrap(), "-o", o, "--quiet"]);
    assert_eq!(r["precision"], "half");
    assert!(r["ev"].as_f64().unwrap() >= 1.0, "{}", r["ev"]);
    assert_eq!(r["sun"]["found"], true, "{}", r["sun"]);
    let mask = specmap::envmap::files::read_stored_channel(&out, "sun").unwrap();
    assert!(mask.iter().all(|&v| v == 0.0 || v == 1.0));
    assert!(mask.iter().filter(|&&v| v == 1.0).count() >= 1);
    let rt = specmap(&["roundtrip", o, "--json"]);
    assert!(
        rt.status.success(),
        "{}",
        String::from_utf8_lossy(&rt.stderr)
    );
    let rt: serde_json::Value = serde_json::from_slice(&rt.stdout).unwrap();
    assert!(rt["sun_pixels"].as_u64().unwrap() >= 1, "{rt}");
    // A sun of 1e9 needs EV 14, which would flush pixels of 1e-4 (below 2^-25 after the scale):
    // the file is written as float instead, and the report says why.
    let input = d.path().join("extreme.exr");
    write_rgb(&input, 128, 64, |x, y| {
        if (x, y) == (64, 20) {
            [1e9, 1e9, 1e9]
        } else if y < 32 {
            [0.5, 0.7, 1.0]
        } else {
            [1e-4, 1e-4, 1e-4]
        }
    });
    std::fs::remove_file(&out).unwrap();
    let r = convert_json(&[input.to_str().unwrap(), "-o", o, "--quiet"]);
    assert_eq!(r["precision"], "float", "{}", r["notes"]);
    assert!(r["ev"].is_null());
    assert!(
        r["notes"]
            .as_array()
            .unwrap()
            .iter()
            .any(|n| n.as_str().unwrap().contains("flush")),
        "{}",
        r["notes"]
    );
    let dark = specmap::envmap::files::read_stored_channel(&out, "S0.550,000000nm").unwrap();
    assert!(dark.iter().all(|&v| v > 0.0), "no pixel is written as 0");
}

/// `--threads N` changes how the work is split, not what is written: one thread and two write
/// the same pixels, read back by the `exr` crate.
#[test]
fn threads_split_the_work_and_write_the_same_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let input = sample("forest.exr");
    let pixels = |threads: &str| {
        let out = dir.path().join(format!("t{threads}.exr"));
        let o = out.to_str().unwrap();
        convert_json(&[
            &input,
            "-o",
            o,
            "--threads",
            threads,
            "--size",
            "64",
            "--quiet",
        ]);
        channels_of(&out)
    };
    let one = pixels("1");
    assert!(one.len() > 80, "{} channels", one.len());
    assert_eq!(one, pixels("2"));
    // Refused by the flag's parser (a usage error: exit 2, nothing written).
    let zero = specmap(&["convert", &input, "-o", "x.exr", "--threads", "0"]);
    assert_eq!(zero.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&zero.stderr).contains("--threads"));
}

/// Every channel of an OpenEXR file as f32, sorted by name (read by the `exr` crate).
fn channels_of(path: &Path) -> Vec<(String, Vec<f32>)> {
    let image = read_all_flat_layers_from_file(path).unwrap();
    let mut channels: Vec<(String, Vec<f32>)> = image.layer_data[0]
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect();
    channels.sort_by(|a, b| a.0.cmp(&b.0));
    channels
}

/// Where the flags decide every pixel's light (one named light, `--sun off`) the scene is not
/// analysed, and the pixels are those of the same conversion with the scene analysed (forest has
/// no sun, so `--sun auto` finds none and changes nothing but the analysis).
#[test]
fn flags_that_decide_every_light_skip_the_analysis_and_write_the_same_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let input = sample("forest.exr");
    for flags in [
        &["--mode", "exact", "--light", "D65"][..],
        &["--lights", "one", "--light", "A"][..],
    ] {
        let run = |sun: &str| {
            let out = dir.path().join(format!("{sun}.exr"));
            let o = out.to_str().unwrap();
            let mut args = vec![input.as_str(), "-o", o, "--size", "64", "--sun", sun];
            args.extend_from_slice(flags);
            (convert_json(&args), channels_of(&out))
        };
        let (skipped, pixels) = run("off");
        let (analysed, want) = run("auto");
        let why = skipped["scene_not_analysed"].as_str().unwrap_or_default();
        assert!(why.contains("not analysed"), "{flags:?}: {why:?}");
        assert_eq!(skipped["lights"].as_array().map(Vec::len), Some(0));
        assert!(analysed["scene_not_analysed"].is_null(), "{flags:?}");
        assert!(!analysed["lights"].as_array().unwrap().is_empty());
        assert_eq!(analysed["sun"]["found"], serde_json::Value::Bool(false));
        assert!(pixels.len() > 80, "{} channels", pixels.len());
        assert_eq!(pixels, want, "{flags:?}");
    }
}
