//! Arguments and inputs at the extremes: refused with a message naming the flag or the pixel,
//! or carried without NaN, never a crash, an overflowed image or a silent black result.

mod common;

use common::{sample, specmap, write_channels};
use std::path::Path;

/// Runs a command that must fail with exit 1 (or clap's 2) and a message holding `parts`,
/// leaving `dir` empty.
fn refused(dir: &Path, args: &[&str], parts: &[&str]) {
    let out = specmap(args);
    let msg = String::from_utf8_lossy(&out.stderr);
    assert!(
        matches!(out.status.code(), Some(1) | Some(2)),
        "{args:?}: exit {:?}, {msg}",
        out.status.code()
    );
    for p in parts {
        assert!(msg.contains(p), "{args:?}: {msg:?} does not mention {p:?}");
    }
    assert!(!msg.contains("panicked"), "{msg}");
    let left: Vec<_> = std::fs::read_dir(dir).unwrap().collect();
    assert!(left.is_empty(), "{args:?} left {left:?}");
}

/// A small lat-long spectral EXR (Fichet names, R, G, B) written by the exr crate, which, unlike
/// specmap's writer, lets a test put NaN or huge values in it.
fn spectral_exr(path: &Path, bad: Option<(usize, f32)>) {
    let (w, h) = (16usize, 8usize);
    let names = [
        "S0.400,000000nm",
        "S0.500,000000nm",
        "S0.600,000000nm",
        "S0.700,000000nm",
        "R",
        "G",
        "B",
    ];
    let mut channels: Vec<(&str, Vec<f32>)> =
        names.iter().map(|&n| (n, vec![0.5f32; w * h])).collect();
    if let Some((i, v)) = bad {
        channels[1].1[i] = v;
    }
    write_channels(path, w, h, channels);
}

#[test]
fn non_finite_and_extreme_arguments_name_the_flag() {
    let d = tempfile::tempdir().unwrap();
    let out_dir = d.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let o = |name: &str| out_dir.join(name).display().to_string();
    let (sunrise, forest) = (sample("sunrise.exr"), sample("forest.exr"));
    let x_exr = o("x.exr");
    let x_png = o("x.png");
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (
            vec!["render", "--size", "8x8", "--exposure", "NaN", "-o", &x_png],
            vec!["--exposure"],
        ),
        (
            vec![
                "render",
                "--size",
                "8x8",
                "--exposure",
                "1000",
                "-o",
                &x_png,
            ],
            vec!["--exposure"],
        ),
        (
            vec!["render", "--size", "8x8", "--kd", "1e308", "-o", &x_png],
            vec!["kd", "100"],
        ),
        (
            vec!["render", "--size", "8x8", "--sweep", "4", "--repeats", "0"],
            vec!["--repeats"],
        ),
        (
            vec!["fit", "--light", "D65", "--rgb", "1e308,0,0"],
            vec!["--rgb", "1e30"],
        ),
        (
            vec!["convert", &sunrise, "-o", &x_exr, "--size", "100000"],
            vec!["--size", "16384"],
        ),
        (
            vec!["convert", &sunrise, "-o", &x_exr, "--rotation", "NaN"],
            vec!["--rotation"],
        ),
        (
            vec!["convert", &sunrise, "-o", &x_exr, "--rotation", "inf"],
            vec!["--rotation"],
        ),
        // Checked before the work, even on a map without a sun.
        (
            vec!["convert", &forest, "-o", &x_exr, "--sun-spd", "nope"],
            vec!["nope"],
        ),
        (
            vec!["convert", &forest, "-o", &x_exr, "--range", "380:780:0.01"],
            vec!["40001", "--range"],
        ),
        (
            vec!["color", "D65", "--range", "380:780:0.000001"],
            vec!["at most 100001"],
        ),
        (
            vec!["color", "FL2", "--tolerance", "1e308"],
            vec!["--tolerance 1e308", "100"],
        ),
        // A budget of wavelengths: at least one, for the scene's quadrature, with a tolerance.
        (
            vec![
                "render",
                "--size",
                "8x8",
                "--tolerance",
                "0.5",
                "--max-nodes",
                "0",
                "-o",
                &x_png,
            ],
            vec!["--max-nodes 0", "at least 1"],
        ),
        (
            vec![
                "render",
                "--size",
                "8x8",
                "--tolerance",
                "0.5",
                "--max-nodes",
                "4",
                "--quadrature",
                "uniform",
                "-o",
                &x_png,
            ],
            vec!["--max-nodes", "--samples"],
        ),
        (
            vec![
                "color",
                "FL2",
                "--tolerance",
                "0.5",
                "--max-nodes",
                "4",
                "--quadrature",
                "uniform",
            ],
            vec!["--max-nodes", "--samples"],
        ),
        (
            vec!["color", "FL2", "--max-nodes", "4"],
            vec!["--tolerance"],
        ),
        // An output named for another format than the one written.
        (
            vec!["convert", &sunrise, "-o", &x_png],
            vec!["OpenEXR", ".exr"],
        ),
    ];
    for (args, parts) in &cases {
        refused(&out_dir, args, parts);
    }
}

#[test]
fn nan_in_a_spectral_map_is_left_out_and_huge_values_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let nan = d.path().join("nan.exr");
    spectral_exr(&nan, Some((37, f32::NAN)));
    // roundtrip: the NaN pixel is counted, the statistics stay finite.
    let out = specmap(&["roundtrip", nan.to_str().unwrap(), "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(r["non_finite_pixels"], 1);
    assert!(r["all"]["weighted_mean_de2000"]
        .as_f64()
        .unwrap()
        .is_finite());
    // --heatmap-max must be positive.
    let hm = d.path().join("h.png");
    let out = specmap(&[
        "roundtrip",
        nan.to_str().unwrap(),
        "--heatmap",
        hm.to_str().unwrap(),
        "--heatmap-max",
        "0",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--heatmap-max"));
    assert!(!hm.exists());
    let jpg = d.path().join("h.jpg");
    let out = specmap(&[
        "roundtrip",
        nan.to_str().unwrap(),
        "--heatmap",
        jpg.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains(".png"));
    assert!(!jpg.exists());

    // render: the NaN pixel is black, the image finite.
    let img = d.path().join("r.exr");
    let out = specmap(&[
        "render",
        "--env",
        nan.to_str().unwrap(),
        "--size",
        "16x12",
        "--backend",
        "cpu",
        "-o",
        img.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let read = exr::prelude::read_all_flat_layers_from_file(&img).unwrap();
    for ch in &read.layer_data[0].channel_data.list {
        assert!(
            ch.sample_data.values_as_f32().all(|v| v.is_finite()),
            "channel {} has non-finite values",
            ch.name
        );
    }

    // A value far beyond any photograph would overflow f32 spectra: refused, naming the pixel.
    let huge = d.path().join("huge.exr");
    spectral_exr(&huge, Some((37, 3e38)));
    let img2 = d.path().join("r2.exr");
    let out = specmap(&[
        "render",
        "--env",
        huge.to_str().unwrap(),
        "--size",
        "16x12",
        "--backend",
        "cpu",
        "-o",
        img2.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let msg = String::from_utf8_lossy(&out.stderr);
    assert!(
        msg.contains("pixel (5, 2)") && msg.contains("exceeds"),
        "{msg}"
    );
    assert!(!img2.exists());
}

#[test]
fn a_bench_report_that_is_a_file_is_refused_before_measuring() {
    let d = tempfile::tempdir().unwrap();
    let file = d.path().join("report.txt");
    std::fs::write(&file, "mine").unwrap();
    let out = specmap(&["bench", "--quick", "--report", file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("not a folder"), "{err}");
    // Nothing was measured (the bench logs each part on stderr as it starts).
    assert!(!err.contains("bench: grid"), "{err}");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
}

#[test]
fn a_map_with_absurd_values_is_refused_naming_the_pixel() {
    // 3e38 is a finite f32 but no radiance: the message names the input pixel, not the output.
    let d = tempfile::tempdir().unwrap();
    let src = d.path().join("in.exr");
    exr::prelude::write_rgb_file(&src, 8, 4, |x, y| {
        if (x, y) == (3, 1) {
            (1.0f32, -3e38f32, 1.0f32)
        } else {
            (0.5f32, 0.5, 0.5)
        }
    })
    .unwrap();
    let out_dir = d.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let out = out_dir.join("x.exr");
    for precision in ["half", "float"] {
        refused(
            &out_dir,
            &[
                "convert",
                src.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "--precision",
                precision,
            ],
            &["pixel (3, 1) channel G", "in.exr"],
        );
    }
}

#[test]
fn spectral_channels_that_are_not_wavelengths_are_named() {
    let d = tempfile::tempdir().unwrap();
    for (bad, says) in [
        ("S0.-5nm", "channel S0.-5nm"),
        ("S0.abcnm", "channel S0.abcnm"),
        ("S0.550nm", "two channels name the wavelength 550 nm"),
    ] {
        let path = d.path().join("bad.exr");
        let names = ["S0.450nm", "S0.550,000000nm", bad, "R", "G", "B"];
        write_channels(
            &path,
            8,
            4,
            names.iter().map(|&n| (n, vec![0.5f32; 8 * 4])).collect(),
        );
        for args in [
            vec!["roundtrip", path.to_str().unwrap()],
            vec![
                "render",
                "--size",
                "8x6",
                "--backend",
                "cpu",
                "--env",
                path.to_str().unwrap(),
            ],
        ] {
            let out = specmap(&args);
            let msg = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(1), "{args:?}: {msg}");
            assert!(msg.contains(says), "{args:?}: {msg}");
        }
    }
}
