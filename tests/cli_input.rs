//! Bad input through the real binary: each gets a clear message naming file, line and column,
//! and a non-zero exit; good but unusual input (non-uniform spacing, comments) is accepted.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn specmap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_specmap"))
        .args(args)
        .output()
        .expect("the specmap binary runs")
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Runs `color FILE` and returns stderr, asserting a failure exit.
fn fails(path: &Path) -> String {
    let out = specmap(&["color", path.to_str().unwrap()]);
    assert!(!out.status.success(), "{} was accepted", path.display());
    assert_eq!(out.status.code(), Some(1));
    assert!(out.stdout.is_empty(), "nothing on stdout for a failure");
    String::from_utf8(out.stderr).unwrap()
}

fn assert_mentions(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "message lacks '{p}': {msg}");
    }
}

#[test]
fn text_in_a_number_field() {
    let d = tempfile::tempdir().unwrap();
    let f = write(
        d.path(),
        "text.csv",
        "wavelength_nm,power\n400,1.0\n410,abc\n420,1.0\n",
    );
    assert_mentions(
        &fails(&f),
        &["text.csv:3", "column 2 ('power')", "'abc' is not a number"],
    );
}

#[test]
fn nan_and_infinity() {
    let d = tempfile::tempdir().unwrap();
    for bad in ["NaN", "inf", "-inf"] {
        let f = write(
            d.path(),
            "nan.csv",
            &format!("wavelength_nm,power\n400,1\n410,{bad}\n"),
        );
        assert_mentions(
            &fails(&f),
            &["nan.csv:3", "column 2 ('power')", "must be finite"],
        );
    }
}

#[test]
fn duplicate_and_decreasing_wavelengths() {
    let d = tempfile::tempdir().unwrap();
    let f = write(
        d.path(),
        "dup.csv",
        "wavelength_nm,p\n400,1\n410,1\n410,2\n",
    );
    assert_mentions(&fails(&f), &["dup.csv:4", "410 nm repeats line 3"]);
    let f = write(
        d.path(),
        "dec.csv",
        "wavelength_nm,p\n400,1\n410,1\n405,2\n",
    );
    assert_mentions(
        &fails(&f),
        &["dec.csv:4", "405 nm is below 410 nm on line 3"],
    );
}

#[test]
fn missing_column_and_extra_field() {
    let d = tempfile::tempdir().unwrap();
    let f = write(d.path(), "miss.csv", "wavelength_nm,a,b\n400,1,2\n410,1\n");
    assert_mentions(&fails(&f), &["miss.csv:3", "missing column 3 ('b')"]);
    let f = write(d.path(), "extra.csv", "wavelength_nm,a\n400,1,2\n");
    assert_mentions(&fails(&f), &["extra.csv:2", "header names only 2"]);
    // A named column that does not exist.
    let f = write(
        d.path(),
        "cols.csv",
        "wavelength_nm,a,b\n400,1,2\n410,1,2\n",
    );
    let out = specmap(&["color", &format!("{}:c", f.display())]);
    assert!(!out.status.success());
    assert_mentions(
        &String::from_utf8_lossy(&out.stderr),
        &["no column 'c'", "a, b"],
    );
}

#[test]
fn empty_header_only_and_headerless_files() {
    let d = tempfile::tempdir().unwrap();
    let f = write(d.path(), "empty.csv", "");
    assert_mentions(&fails(&f), &["empty.csv", "empty file"]);
    let f = write(d.path(), "blank.csv", "\n# only a comment\n\n");
    assert_mentions(&fails(&f), &["blank.csv", "empty file"]);
    let f = write(d.path(), "header.csv", "wavelength_nm,p\n");
    assert_mentions(&fails(&f), &["header.csv", "no data rows"]);
    let f = write(d.path(), "nohead.csv", "400,1\n410,2\n");
    assert_mentions(
        &fails(&f),
        &["nohead.csv:1", "wavelength_nm", "no header row"],
    );
    let f = write(d.path(), "um.csv", "wavelength_nm,p\n0.40,1\n0.41,2\n");
    assert_mentions(&fails(&f), &["um.csv", "micrometres"]);
}

#[test]
fn missing_file_and_unknown_names() {
    let out = specmap(&["color", "no/such/file.csv"]);
    assert!(!out.status.success());
    assert_mentions(&String::from_utf8_lossy(&out.stderr), &["no/such/file.csv"]);
    let out = specmap(&["color", "D56"]);
    assert!(!out.status.success());
    assert_mentions(
        &String::from_utf8_lossy(&out.stderr),
        &["'D56'", "did you mean", "D55"],
    );
    let out = specmap(&["color", "colorchecker:reed", "--under", "D65"]);
    assert_mentions(&String::from_utf8_lossy(&out.stderr), &["did you mean red"]);
    let out = specmap(&["color", "colorchecker:red", "--under", "incandescant"]);
    assert_mentions(&String::from_utf8_lossy(&out.stderr), &["incandescent"]);
}

#[test]
fn a_light_with_no_energy_in_range_is_an_error() {
    let d = tempfile::tempdir().unwrap();
    let f = write(
        d.path(),
        "ir.csv",
        "wavelength_nm,p\n380,0\n900,0\n950,1\n1000,1\n",
    );
    assert_mentions(&fails(&f), &["no visible energy"]);
}

#[test]
fn non_uniform_tables_are_accepted_and_resampled() {
    // A cubic sampled at irregular wavelengths; the not-a-knot spline reproduces it exactly.
    let cubic = |w: f64| {
        let x = (w - 550.0) / 100.0;
        0.5 + 0.2 * x - 0.1 * x * x + 0.05 * x * x * x
    };
    let knots = [
        380.0, 397.0, 420.0, 433.5, 470.0, 512.0, 560.0, 601.0, 655.0, 700.0, 780.0,
    ];
    let mut text = String::from("# irregular samples\nwavelength_nm,refl\n");
    for w in knots {
        text.push_str(&format!("{w},{}\n", cubic(w)));
    }
    let d = tempfile::tempdir().unwrap();
    let f = write(d.path(), "irregular.csv", &text);
    let out = specmap(&[
        "data",
        "show",
        f.to_str().unwrap(),
        "--range",
        "380:780:5",
        "--format",
        "json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let w = doc["wavelengths_nm"].as_array().unwrap();
    let v = doc["columns"]["refl"].as_array().unwrap();
    assert_eq!(w.len(), 81);
    for (w, v) in w.iter().zip(v) {
        let (w, v) = (w.as_f64().unwrap(), v.as_f64().unwrap());
        assert!((v - cubic(w)).abs() < 1e-12, "{w}: {v} vs {}", cubic(w));
    }
    // And usable as a reflectance under a built-in light.
    let out = specmap(&["color", f.to_str().unwrap(), "--under", "D65", "--json"]);
    assert!(out.status.success());
}

#[test]
fn bad_ranges_and_flags_are_refused() {
    for range in ["380:780", "380:781:5", "780:380:5", "380:780:0"] {
        let out = specmap(&["color", "D65", "--range", range]);
        assert!(!out.status.success(), "{range} accepted");
        let msg = String::from_utf8_lossy(&out.stderr);
        assert!(msg.contains(range) || msg.contains("step"), "{msg}");
    }
    let out = specmap(&["color", "D65", "--rule", "gauss"]);
    assert_eq!(out.status.code(), Some(2), "clap usage errors exit 2");
}

#[test]
fn help_has_examples() {
    let out = specmap(&["--help"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_mentions(
        &text,
        &[
            "Examples:",
            "specmap color colorchecker:red --under D65 --json",
        ],
    );
}

#[test]
fn data_list_json_names_every_kind() {
    let out = specmap(&["data", "list", "--json"]);
    assert!(out.status.success());
    let rows: Vec<serde_json::Value> = serde_json::from_slice(&out.stdout).unwrap();
    for kind in ["cmf", "illuminant", "light", "reflectance"] {
        assert!(rows.iter().any(|r| r["kind"] == kind), "no {kind}");
    }
    let cc = rows.iter().find(|r| r["name"] == "colorchecker").unwrap();
    assert_eq!(cc["columns"].as_array().unwrap().len(), 24);
    assert_eq!(cc["end_nm"], 730.0);
}

#[test]
fn data_show_writes_plots_and_refuses_unknown_formats() {
    let d = tempfile::tempdir().unwrap();
    let png = d.path().join("cc.png");
    let out = specmap(&[
        "data",
        "show",
        "colorchecker",
        "--plot",
        png.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
    let bad = d.path().join("cc.gif");
    let out = specmap(&["data", "show", "D65", "--plot", bad.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(!bad.exists());
    assert_eq!(
        std::fs::read_dir(d.path()).unwrap().count(),
        1,
        "no temporary file left"
    );
}

#[test]
fn fit_refuses_bad_lights_and_dependent_bases() {
    let d = tempfile::tempdir().unwrap();
    let dark = write(d.path(), "dark.csv", "wavelength_nm,p\n380,0\n780,0\n");
    let out = specmap(&["fit", "--light", dark.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert_mentions(
        &String::from_utf8_lossy(&out.stderr),
        &["no visible energy"],
    );
    let neg = write(
        d.path(),
        "neg.csv",
        "wavelength_nm,p\n380,1\n500,-0.5\n780,1\n",
    );
    let out = specmap(&["fit", "--light", neg.to_str().unwrap()]);
    assert_mentions(&String::from_utf8_lossy(&out.stderr), &["negative", "nm"]);
    // Two copies of one patch cannot carry three channels.
    let out = specmap(&[
        "fit",
        "--light",
        "D65",
        "--basis",
        "colorchecker:red,colorchecker:red,colorchecker:blue",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert_mentions(
        &String::from_utf8_lossy(&out.stderr),
        &["linearly dependent"],
    );
    let out = specmap(&["fit", "--light", "D65", "--basis", "colorchecker:red"]);
    assert_eq!(out.status.code(), Some(1));
    assert_mentions(&String::from_utf8_lossy(&out.stderr), &["three spectra"]);
}

#[test]
fn fit_writes_a_versioned_file_and_a_plot() {
    let d = tempfile::tempdir().unwrap();
    let json = d.path().join("fit.json");
    let svg = d.path().join("basis.svg");
    let out = specmap(&[
        "fit",
        "--light",
        "A",
        "--mode",
        "exact",
        "-o",
        json.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let f: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(f["version"], 1);
    assert_eq!(f["mode"], "exact");
    assert_eq!(f["light_spd"].as_array().unwrap().len(), 401);
    assert_eq!(f["basis_reflectance"][2].as_array().unwrap().len(), 401);
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    // Several lights print a table; -o with several is refused.
    let out = specmap(&["fit", "--light", "D65,lps", "--mode", "paper,exact"]);
    assert!(out.status.success());
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 2 + 4);
    let out = specmap(&["fit", "--light", "D65,A", "-o", json.to_str().unwrap()]);
    assert!(!out.status.success());
}

#[test]
fn cielab_against_a_white_with_a_zero_component_is_undefined_not_nan() {
    // Low-pressure sodium has no power where the CIE 1964 z-bar is non-zero: the white's Z is 0
    // and b* is 0/0. The command says so instead of printing NaN, and JSON has null plus a note.
    let args = [
        "color",
        "colorchecker:red",
        "--under",
        "lps",
        "--observer",
        "cie1964",
        "--range",
        "380:780:5",
    ];
    let out = specmap(&args);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!text.contains("NaN"), "{text}");
    assert!(
        text.contains("undefined") && text.contains("Z = 0"),
        "{text}"
    );
    let mut json_args = args.to_vec();
    json_args.push("--json");
    let doc: serde_json::Value = serde_json::from_slice(&specmap(&json_args).stdout).expect("JSON");
    assert!(doc["XYZ"][2].as_f64().unwrap() == 0.0);
    assert!(doc["lab"][2].is_null());
    assert!(doc["lab_note"].as_str().unwrap().contains("Z = 0"));
    // A white with every component is unaffected.
    let doc: serde_json::Value = serde_json::from_slice(
        &specmap(&["color", "colorchecker:red", "--under", "D65", "--json"]).stdout,
    )
    .unwrap();
    assert!(doc["lab_note"].is_null());
    assert!(doc["lab"][2].as_f64().unwrap() > 0.0);
}
