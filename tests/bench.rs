//! `specmap bench --quick`: every section is measured and the numbers behave as the physics says
//! (the reference setting has no error; coarser grids and spikier lights err more).

use std::process::Command;

#[test]
fn quick_bench_measures_every_knob() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_specmap"))
        .args(["bench", "--quick", "--json", "--backend", "cpu", "--report"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = doc["rows"].as_array().unwrap();
    let find = |section: &str, case: &str, setting: &str| {
        rows.iter()
            .find(|r| r["section"] == section && r["case"] == case && r["setting"] == setting)
            .unwrap_or_else(|| panic!("no row {section} / {case} / {setting}"))
    };
    let max = |r: &serde_json::Value| r["max_dE2000"].as_f64();
    for section in ["grid", "film", "mode", "render", "quadrature"] {
        assert!(rows.iter().any(|r| r["section"] == section), "{section}");
    }
    // 1 nm Simpson is the reference itself.
    assert!(max(find("grid", "D65", "1 nm, simpson")).unwrap() < 1e-9);
    // A spiky light errs more than D65 at 10 nm; the error grows from 5 to 20 nm for D65.
    let d65_10 = max(find("grid", "D65", "10 nm, riemann")).unwrap();
    assert!(max(find("grid", "FL2", "10 nm, riemann")).unwrap() > d65_10);
    assert!(
        max(find("grid", "D65", "20 nm, riemann")).unwrap()
            > max(find("grid", "D65", "5 nm, riemann")).unwrap()
    );
    // Low-pressure sodium's line falls between 20 nm samples: reported, not an error.
    let lps = find("grid", "lps", "20 nm, riemann");
    assert!(lps["max_dE2000"].is_null() && lps["note"].as_str().unwrap().contains("unusable"));
    // The exact mode's round trip is exact; the paper's is not.
    assert!(max(find("mode", "D65", "exact")).unwrap() < 1e-6);
    assert!(max(find("mode", "D65", "paper")).unwrap() > 1.0);
    // A 10 um film aliases at 20 nm far more than a 100 nm film.
    assert!(
        max(find("film", "10000 nm film, coherent", "20 nm, riemann")).unwrap()
            > 5.0 * max(find("film", "100 nm film, coherent", "20 nm, riemann")).unwrap()
    );
    // Quadratures, on the image against the 1 nm render: the scene's meets the tolerance with
    // at most a third of the uniform grid's nodes; Meyer's four wavelengths miss it by far.
    let nodes = |r: &serde_json::Value| r["samples"].as_u64().unwrap();
    for light in ["D65", "FL2"] {
        let case = format!("ball 24x24 under {light}");
        let scene = find("quadrature", &case, "scene, tolerance 0.5");
        let uniform = find("quadrature", &case, "uniform, tolerance 0.5");
        let meyer = find("quadrature", &case, "meyer");
        assert!(
            max(scene).unwrap() <= 0.5 && max(uniform).unwrap() <= 0.5,
            "{case}"
        );
        assert!(3 * nodes(scene) <= nodes(uniform), "{case}");
        assert!(nodes(meyer) == 4 && max(meyer).unwrap() > 5.0, "{case}");
        assert!(scene["estimate_dE2000"].as_f64().unwrap() <= 0.5);
    }
    // The header says how long the run took (a quick run is not "0 s").
    let md = std::fs::read_to_string(dir.path().join("bench.md")).unwrap();
    let seconds = doc["seconds"].as_f64().unwrap();
    assert!(
        seconds > 0.0 && !md.contains(" 0 s in all"),
        "{}",
        &md[..200]
    );
    for f in [
        "bench.md",
        "bench.json",
        "grid.png",
        "film.png",
        "render.png",
    ] {
        let p = dir.path().join(f);
        assert!(p.metadata().map(|m| m.len() > 100).unwrap_or(false), "{f}");
    }
    image::open(dir.path().join("grid.png")).unwrap();
}
