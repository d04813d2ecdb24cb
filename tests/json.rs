//! One field, one meaning: what each command's `--json` says about one choice it says once, and
//! a name it uses means one thing (issue 17 item 8: `"method": "faithful"` beside `"mode":
//! "exact"`).

use std::path::Path;

mod common;

use common::{sample, specmap_json as json};

/// Every object of a JSON document with its path.
fn objects<'a>(
    v: &'a serde_json::Value,
    path: String,
    out: &mut Vec<(String, &'a serde_json::Map<String, serde_json::Value>)>,
) {
    match v {
        serde_json::Value::Object(m) => {
            out.push((path.clone(), m));
            for (k, x) in m {
                objects(x, format!("{path}.{k}"), out);
            }
        }
        serde_json::Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                objects(x, format!("{path}[{i}]"), out);
            }
        }
        _ => {}
    }
}

/// The double meanings found: a choice named twice, a value given twice under two names.
fn double_meanings(doc: &serde_json::Value) -> Vec<String> {
    let mut all = Vec::new();
    objects(doc, String::new(), &mut all);
    let mut found = Vec::new();
    for (path, m) in all {
        if m.contains_key("mode") && m.contains_key("method") {
            found.push(format!(
                "{path}: mode {} and method {}",
                m["mode"], m["method"]
            ));
        }
        // The fit's weights are its closed form: one name.
        if m.contains_key("weights") && m.contains_key("closed_form") {
            found.push(format!("{path}: weights and closed_form"));
        }
        // A count of the pixels that took a spectrum is not named after a mode.
        if let Some(serde_json::Value::Object(s)) = m.get("spectra") {
            for mode in ["faithful", "paper", "exact", "nonneg"] {
                if s.contains_key(mode) {
                    found.push(format!("{path}.spectra.{mode} beside mode {}", m["mode"]));
                }
            }
        }
        // RGB (1,1,1) is the space's white, whatever the space.
        if m.get("premise").is_some_and(|p| p == "d65") {
            found.push(format!("{path}: premise d65"));
        }
    }
    found
}

#[test]
fn no_command_says_one_thing_twice() {
    let d = tempfile::tempdir().unwrap();
    let out = |name: &str| d.path().join(name).display().to_string();
    let truth = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/truth");
    let fl2 = truth.join("interior_fl2.rgb.exr").display().to_string();
    let fl2_truth = truth
        .join("interior_fl2.spectral.exr")
        .display()
        .to_string();
    let converted = out("fl2.exr");
    let docs = [
        json(&["convert", &fl2, "-o", &converted, "--quiet"]),
        json(&[
            "convert",
            &fl2,
            "-o",
            &out("p.exr"),
            "--quiet",
            "--mode",
            "nonneg",
        ]),
        json(&["roundtrip", &converted]),
        json(&["rendition", &fl2_truth, &converted]),
        json(&["fit", "--light", "FL2", "--mode", "exact"]),
        json(&["fit", "--light", "D65,FL2", "--mode", "paper,nonneg"]),
        json(&["color", "FL2"]),
        json(&[
            "color",
            "colorchecker:red",
            "--under",
            "D65",
            "--space",
            "acescg",
        ]),
        json(&[
            "render",
            "--scene",
            "ball",
            "--backend",
            "cpu",
            "--size",
            "24x24",
            "--env",
            &converted,
            "-o",
            &out("ball.png"),
        ]),
        json(&[
            "demo",
            "-o",
            &out("demo"),
            "--quick",
            "--backend",
            "cpu",
            "--env",
            &sample("forest.exr"),
        ]),
    ];
    let found: Vec<String> = docs.iter().flat_map(double_meanings).collect();
    assert!(found.is_empty(), "{found:#?}");
}

#[test]
fn the_fit_s_weights_are_its_closed_form_and_argmin_checks_them() {
    let f = json(&["fit", "--light", "FL2"]);
    let w = f["weights"].as_array().unwrap();
    let a = f["argmin"]["weights"].as_array().unwrap();
    for k in 0..3 {
        let (w, a) = (w[k].as_f64().unwrap(), a[k].as_f64().unwrap());
        assert!((w - a).abs() < 1e-9, "{w} vs {a}");
    }
    assert!(f.get("closed_form").is_none());
}

#[test]
fn the_nonneg_mode_s_inexact_pixels_are_the_nearest_non_negative_spectra() {
    // Saturated colours the ColorChecker basis under D65 makes only with negative power.
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("saturated.exr");
    exr::prelude::write_rgb_file(&input, 64, 32, |x, y| {
        if y < 8 {
            (0.8, 0.8, 0.8)
        } else {
            [
                (0.9, 0.01, 0.01),
                (0.01, 0.9, 0.01),
                (0.01, 0.01, 0.9),
                (0.5, 0.3, 0.2),
            ][x % 4]
        }
    })
    .unwrap();
    let o = d.path().join("o.exr");
    let (i, o) = (input.to_str().unwrap(), o.to_str().unwrap());
    let r = json(&[
        "convert", i, "-o", o, "--quiet", "--mode", "nonneg", "--light", "D65",
    ]);
    let s = &r["spectra"];
    let nearest = s["nearest"].as_u64().unwrap();
    assert!(nearest > 0, "{s}");
    assert_eq!(
        s["nonneg_fallback"], 0,
        "the faithful method's fallback: {s}"
    );
    let inexact = &r["inexact"];
    let counted = inexact["pixels"].as_u64().unwrap()
        + inexact["below_floor"]["pixels"].as_u64().unwrap()
        + inexact["black_pixels"].as_u64().unwrap();
    assert_eq!(counted, nearest, "{inexact}");
    assert!(inexact["max_de2000"].as_f64().unwrap() > 0.1, "{inexact}");
}
