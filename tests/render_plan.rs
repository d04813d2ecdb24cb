//! `render --tolerance` weighs the fit against what it saves: a still whose fit would not pay
//! is drawn on the uniform grid at the tolerance, a fit is stored in the cache and reused by
//! the next run, a corrupt entry is ignored with a note, and a fit cut short by its budget says
//! so and still meets the tolerance on the image.

use std::path::Path;
use std::process::Command;

/// `specmap render ARGS --json` with its cache in `cache`; the report and stderr.
fn render(cache: &Path, args: &[&str]) -> (serde_json::Value, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_specmap"))
        .arg("render")
        .args(args)
        .arg("--json")
        .env("SPECMAP_CACHE_DIR", cache)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{args:?}: {err}");
    (serde_json::from_slice(&out.stdout).unwrap(), err)
}

/// The ball at 48x48 on the CPU at tolerance 0.5, written to `dir`, with `more` options.
fn ball(dir: &Path, more: &[&str]) -> (serde_json::Value, String) {
    let png = dir.join("ball.png");
    let mut args = vec![
        "--scene",
        "ball",
        "--size",
        "48x48",
        "--backend",
        "cpu",
        "--tolerance",
        "0.5",
        "-o",
        png.to_str().unwrap(),
    ];
    args.extend_from_slice(more);
    render(&dir.join("cache"), &args)
}

fn entries(dir: &Path) -> Vec<std::path::PathBuf> {
    match std::fs::read_dir(dir.join("cache/quadrature")) {
        Ok(d) => d.map(|e| e.unwrap().path()).collect(),
        Err(_) => Vec::new(),
    }
}

#[test]
fn a_still_whose_fit_would_not_pay_is_drawn_on_the_uniform_grid() {
    let dir = tempfile::tempdir().unwrap();
    let (r, _) = ball(dir.path(), &[]);
    let plan = &r["quadrature_plan"];
    assert_eq!(plan["source"], "uniform", "{plan}");
    assert_eq!(r["quadrature"]["kind"], "uniform");
    let reason = plan["reason"].as_str().unwrap();
    assert!(reason.contains("would cost more than it saves"), "{reason}");
    // Its uniform grid is the one --quadrature uniform chooses at the tolerance.
    let (u, _) = ball(dir.path(), &["--quadrature", "uniform"]);
    assert_eq!(r["quadrature"]["nodes_nm"], u["quadrature"]["nodes_nm"]);
    // Its check of the image alone (all 2304 pixels at 401 wavelengths) costs more than a
    // tenth of the frame: decided before a frame is measured.
    assert!(reason.contains("its check of the image alone"), "{reason}");
    assert!(plan["uniform_path_s"].is_null());
    assert!(
        entries(dir.path()).is_empty(),
        "nothing fitted, nothing stored"
    );
}

#[test]
fn a_fit_is_stored_and_the_next_run_reuses_it() {
    let dir = tempfile::tempdir().unwrap();
    let (fitted, _) = ball(dir.path(), &["--quadrature", "scene"]);
    assert_eq!(fitted["quadrature_plan"]["source"], "fit");
    assert_eq!(fitted["quadrature"]["kind"], "scene");
    assert_eq!(entries(dir.path()).len(), 1);
    let (again, _) = ball(dir.path(), &[]);
    let plan = &again["quadrature_plan"];
    assert_eq!(plan["source"], "cache", "{plan}");
    assert_eq!(
        again["quadrature"]["nodes_nm"],
        fitted["quadrature"]["nodes_nm"]
    );
    assert_eq!(
        again["quadrature"]["weights"],
        fitted["quadrature"]["weights"]
    );
    // The same scene at another tolerance, size or light is another entry.
    let (other, _) = ball(dir.path(), &["--light", "A"]);
    assert_ne!(other["quadrature_plan"]["source"], "cache");
    // --no-cache neither reads nor stores.
    let (skip, _) = ball(dir.path(), &["--no-cache"]);
    assert_ne!(skip["quadrature_plan"]["source"], "cache");
    assert!(skip["quadrature_plan"]["cache_file"].is_null());
}

#[test]
fn a_corrupt_entry_is_ignored_with_a_note_and_replaced() {
    let dir = tempfile::tempdir().unwrap();
    ball(dir.path(), &["--quadrature", "scene"]);
    let file = entries(dir.path()).pop().unwrap();
    let text = std::fs::read_to_string(&file).unwrap();
    std::fs::write(&file, &text[..text.len() / 2]).unwrap();
    let (r, err) = ball(dir.path(), &["--quadrature", "scene"]);
    assert!(err.contains("note: quadrature cache: ignored"), "{err}");
    assert!(err.contains("not a cache entry"), "{err}");
    assert_eq!(r["quadrature_plan"]["source"], "fit");
    // Stored again, whole.
    let (again, _) = ball(dir.path(), &[]);
    assert_eq!(again["quadrature_plan"]["source"], "cache");
}

#[test]
fn a_fit_cut_short_by_its_budget_says_so_and_the_image_meets_the_tolerance() {
    let dir = tempfile::tempdir().unwrap();
    let (r, _) = ball(dir.path(), &["--fit-budget", "0", "--no-cache"]);
    let plan = &r["quadrature_plan"];
    assert_eq!(plan["cut_short"], true, "{plan}");
    assert!(plan["reason"].as_str().unwrap().contains("cut it short"));
    // Whatever was chosen, it meets the tolerance (the uniform grid where the fit missed).
    let c = &r["quadrature_choice"];
    assert_eq!(c["met"], true, "{c}");
    if let Some(image) = c["image"]["max_dE2000"].as_f64() {
        assert!(image <= 0.5, "{image}");
    }
    // Stored, marked cut short: a run with no more time reuses it, a longer one fits again.
    let (stored, _) = ball(dir.path(), &["--fit-budget", "0"]);
    assert_eq!(stored["quadrature_plan"]["source"], "fit");
    let (again, _) = ball(dir.path(), &["--fit-budget", "0"]);
    assert_eq!(again["quadrature_plan"]["source"], "cache");
    assert_eq!(again["quadrature"], stored["quadrature"]);
    let (longer, err) = ball(dir.path(), &["--fit-budget", "60"]);
    assert_eq!(longer["quadrature_plan"]["source"], "fit");
    assert!(err.contains("cut short"), "{err}");
    assert_eq!(longer["quadrature_plan"]["cut_short"], false);
    // Then complete: every run reuses it, whatever its budget.
    let (last, _) = ball(dir.path(), &["--fit-budget", "0"]);
    assert_eq!(last["quadrature_plan"]["source"], "cache");
    assert_eq!(last["quadrature"], longer["quadrature"]);
    for bad in ["--fit-budget=-1", "--fit-budget=nan"] {
        let out = Command::new(env!("CARGO_BIN_EXE_specmap"))
            .args(["render", "--tolerance", "0.5", bad])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains("--fit-budget"),
            "{err}"
        );
    }
}

/// The linear pixels of an EXR written by `render`.
fn pixels(path: &Path) -> Vec<f32> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |r, _| vec![0f32; r.width() * r.height() * 3],
        |v: &mut Vec<f32>, p, (r, g, b, _a): (f32, f32, f32, f32)| {
            let i = 3 * (p.y() * 48 + p.x());
            v[i..i + 3].copy_from_slice(&[r, g, b]);
        },
    )
    .unwrap();
    image.layer_data.channel_data.pixels
}

/// Each frame of a turntable is the still at its orbit, and each frame of a thickness sweep
/// the still at its thickness, on the same wavelengths.
#[test]
fn a_sequences_frames_are_the_stills_at_their_orbits_and_thicknesses() {
    let dir = tempfile::tempdir().unwrap();
    let at = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let common = ["--size", "48x48", "--backend", "cpu", "--samples", "41"];
    let run = |more: &[&str]| {
        let mut args: Vec<&str> = common.to_vec();
        args.extend_from_slice(more);
        render(&dir.path().join("cache"), &args).0
    };
    let turn = run(&[
        "--scene",
        "ball",
        "--turntable",
        "4",
        "--orbit",
        "30,20",
        "-o",
        &at("t.exr"),
    ]);
    assert_eq!(turn["frames"].as_array().unwrap().len(), 4);
    let sweep = run(&[
        "--scene",
        "ball",
        "--film",
        "2.7:100..400",
        "--frames",
        "4",
        "-o",
        &at("s.exr"),
    ]);
    assert_eq!(sweep["frames"][3]["at"], 4.0);
    for k in 0..4 {
        let yaw = format!("{},20", 30 + 90 * k);
        run(&[
            "--scene",
            "ball",
            "--orbit",
            &yaw,
            "-o",
            &at(&format!("still-t{k}.exr")),
        ]);
        let film = format!("2.7:{}", 100 * (k + 1));
        run(&[
            "--scene",
            "ball",
            "--film",
            &film,
            "-o",
            &at(&format!("still-s{k}.exr")),
        ]);
        for (seq, still) in [("t", "still-t"), ("s", "still-s")] {
            let a = pixels(&dir.path().join(format!("{seq}-{k:03}.exr")));
            let b = pixels(&dir.path().join(format!("{still}{k}.exr")));
            assert_eq!(a, b, "frame {k} of {seq}");
        }
    }
    // The frames differ: the sun turns, the film thickens.
    let f = |n: &str| pixels(&dir.path().join(n));
    assert_ne!(f("t-000.exr"), f("t-001.exr"));
    assert_ne!(f("s-000.exr"), f("s-003.exr"));
}

/// A sequence fits once, for every frame: one plan, one cache entry, every frame on it.
#[test]
fn a_sequence_fits_once_for_every_frame() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.png");
    let args = [
        "--scene",
        "ball",
        "--size",
        "48x48",
        "--backend",
        "cpu",
        "--turntable",
        "6",
        "--tolerance",
        "0.5",
        "--quadrature",
        "scene",
        "-o",
        out.to_str().unwrap(),
    ];
    let (r, _) = render(&dir.path().join("cache"), &args);
    assert_eq!(r["quadrature_plan"]["source"], "fit");
    assert_eq!(r["quadrature_plan"]["frames"], 6);
    assert_eq!(r["frames"].as_array().unwrap().len(), 6);
    assert_eq!(entries(dir.path()).len(), 1);
    for k in 0..6 {
        assert!(dir.path().join(format!("t-{k:03}.png")).exists());
    }
    // Run again, the same turntable reads its fit from the cache.
    let (again, _) = render(&dir.path().join("cache"), &args);
    assert_eq!(again["quadrature_plan"]["source"], "cache");
}

/// `color --tolerance` stores its fit too, and says when the next run read it.
#[test]
fn colour_fits_are_cached_too() {
    let dir = tempfile::tempdir().unwrap();
    let color = |more: &[&str]| -> serde_json::Value {
        let out = Command::new(env!("CARGO_BIN_EXE_specmap"))
            .args([
                "color",
                "colorchecker:red",
                "--under",
                "FL2",
                "--tolerance",
                "0.5",
            ])
            .args(more)
            .arg("--json")
            .env("SPECMAP_CACHE_DIR", dir.path())
            .output()
            .unwrap();
        assert!(out.status.success());
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let first = color(&[]);
    assert!(first["quadrature_choice"]["from_cache"].is_null());
    let second = color(&[]);
    assert!(
        second["quadrature_choice"]["from_cache"].is_string(),
        "{second}"
    );
    assert_eq!(second["quadrature"], first["quadrature"]);
    assert!(color(&["--no-cache"])["quadrature_choice"]["from_cache"].is_null());
}
