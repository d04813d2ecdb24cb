//! `rendition` on maps with closed-form answers: a uniform map's irradiance is pi L at every
//! normal; identical or rescaled maps render identically; a metamer of the light keeps the white
//! but not the patches; maps on different grids and layouts compare on what they share; bad
//! inputs get clear errors. And the committed truth scenes through the real binary.

use specmap::colorimetry::{Cmfs, Observer};
use specmap::data::Table;
use specmap::envmap::files::{
    ChannelSet, Compression, EnvmapAttr, Precision, SpectralLayout, SpectralWriter,
};
use specmap::envmap::layout::{EnvMap, Layout};
use specmap::envmap::RgbImage;
use specmap::rendition::{map_irradiance, rendition, Normal, RenditionOptions};
use specmap::spectrum::{Interpolation, WavelengthGrid};
use std::path::{Path, PathBuf};
use std::process::Command;

fn grid(start: f64, end: f64, step: f64) -> Vec<f64> {
    let g = WavelengthGrid::new(start, end, step).unwrap();
    g.wavelengths_nm().collect()
}

/// A light table on the wavelengths `wl` (linear interpolation), scaled by `k`.
fn light(name: &str, wl: &[f64], k: f64) -> Vec<f64> {
    let t = Table::builtin(name).unwrap().single_column().unwrap();
    let g = WavelengthGrid::new(wl[0], wl[wl.len() - 1], wl[1] - wl[0]).unwrap();
    t.resample(&g, Interpolation::LIGHT)
        .values()
        .iter()
        .map(|v| v * k)
        .collect()
}

/// Writes a spectral map whose radiance in direction d is `f(d)` (float, ZIP).
fn write_map(
    path: &Path,
    layout: Layout,
    size: usize,
    wl: &[f64],
    f: impl Fn([f64; 3]) -> Vec<f64>,
) -> PathBuf {
    let (w, h) = layout.dimensions(size);
    let geometry = EnvMap {
        layout,
        image: RgbImage::new(w, h),
    };
    let mut rows = Vec::with_capacity(w * h * wl.len());
    for y in 0..h {
        for x in 0..w {
            match geometry.direction(x, y) {
                Some(d) => rows.extend(f(d).iter().map(|v| *v as f32)),
                None => rows.extend(std::iter::repeat_n(0.0f32, wl.len())),
            }
        }
    }
    let envmap = match layout {
        Layout::LatLong => Some(EnvmapAttr::LatLong),
        Layout::Cube => Some(EnvmapAttr::Cube),
        _ => None,
    };
    let mut writer = SpectralWriter::create(
        path,
        SpectralLayout {
            width: w,
            height: h,
            channels: ChannelSet::Spectral {
                wavelengths_nm: wl.to_vec(),
                preview_rgb: false,
            },
            precision: Precision::Float,
            compression: Compression::Zip,
            envmap,
            ev: None,
            attributes: vec![],
            zip_level: specmap::envmap::files::ZIP_DEFAULT_LEVEL,
            unscaled: Vec::new(),
        },
    )
    .unwrap();
    writer.write_rows(0, &rows).unwrap();
    writer.finish().unwrap();
    path.to_path_buf()
}

fn all_normals() -> Vec<Normal> {
    ["up", "down", "px", "nx", "pz", "nz", "1:1:1"]
        .iter()
        .map(|s| s.parse().unwrap())
        .collect()
}

#[test]
fn a_uniform_map_gives_pi_l_at_every_normal() {
    let d = tempfile::tempdir().unwrap();
    let wl = grid(380.0, 780.0, 5.0);
    let d65 = light("D65", &wl, 0.01);
    for (layout, size) in [(Layout::LatLong, 128), (Layout::Cube, 48)] {
        let p = write_map(
            &d.path().join(format!("uniform-{}.exr", layout.name())),
            layout,
            size,
            &wl,
            |_| d65.clone(),
        );
        let m = map_irradiance(&p, &all_normals()).unwrap();
        assert_eq!(m.layout, layout);
        for (n, e) in all_normals().iter().zip(&m.irradiance) {
            for (k, (e, l)) in e.iter().zip(&d65).enumerate() {
                let rel = (e / (std::f64::consts::PI * l) - 1.0).abs();
                // The pixel-centre cosine rule converges as h^2: 128x64 and 6 x 48^2 are within 1e-3.
                assert!(
                    rel < 1e-3,
                    "{} normal {}: band {k}: E = {e}, pi L = {}",
                    layout.name(),
                    n.name,
                    std::f64::consts::PI * l
                );
            }
        }
    }
}

#[test]
fn a_light_in_one_direction_lights_by_its_cosine() {
    // Radiance only in the pixels within 5 degrees of +Y: E at a normal tilted by t is E(up) cos t.
    let d = tempfile::tempdir().unwrap();
    let wl = grid(380.0, 780.0, 10.0);
    let a = light("A", &wl, 1.0);
    let p = write_map(
        &d.path().join("spot.exr"),
        Layout::LatLong,
        256,
        &wl,
        |dir| {
            if dir[1] > 5f64.to_radians().cos() {
                a.clone()
            } else {
                vec![0.0; a.len()]
            }
        },
    );
    let t = 30f64.to_radians();
    let normals = vec![
        Normal::new("up", [0.0, 1.0, 0.0]).unwrap(),
        Normal::new("tilted", [t.sin(), t.cos(), 0.0]).unwrap(),
        Normal::new("down", [0.0, -1.0, 0.0]).unwrap(),
    ];
    let m = map_irradiance(&p, &normals).unwrap();
    for k in 0..wl.len() {
        let ratio = m.irradiance[1][k] / m.irradiance[0][k];
        assert!((ratio - t.cos()).abs() < 2e-3, "band {k}: ratio {ratio}");
        assert_eq!(m.irradiance[2][k], 0.0);
    }
}

/// A sky-like scene: daylight above, a warm ground below, a bright patch of sun.
fn scene(wl: &[f64]) -> impl Fn([f64; 3]) -> Vec<f64> {
    let sky = light("D65", wl, 0.01);
    let ground = light("A", wl, 0.002);
    let sun = light("D50", wl, 3.0);
    let s = [0.3f64, 0.8, 0.52];
    let sn = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
    move |d| {
        let c = (d[0] * s[0] + d[1] * s[1] + d[2] * s[2]) / sn;
        if c > 4f64.to_radians().cos() {
            sun.clone()
        } else if d[1] >= 0.0 {
            sky.clone()
        } else {
            ground.clone()
        }
    }
}

#[test]
fn identical_and_rescaled_maps_render_identically() {
    let d = tempfile::tempdir().unwrap();
    let wl = grid(380.0, 780.0, 5.0);
    let f = scene(&wl);
    let a = write_map(&d.path().join("a.exr"), Layout::LatLong, 64, &wl, &f);
    let b = write_map(&d.path().join("b.exr"), Layout::LatLong, 64, &wl, |dir| {
        f(dir).iter().map(|v| 4.0 * v).collect()
    });
    let opts = RenditionOptions {
        normals: all_normals(),
        ..Default::default()
    };
    let same = rendition(&a, &a, &opts).unwrap();
    assert_eq!(same.mean_de2000, 0.0);
    assert_eq!(same.max_de2000, 0.0);
    assert_eq!(same.white_max_de2000, 0.0);
    assert_eq!(same.normals.len(), 7);
    assert!(same.normals.iter().all(|n| n.patches.len() == 24));
    assert_eq!(same.wavelengths.to_string(), "380:780:5");
    // Four times as bright: adaptation to each map's own white removes the scale (to rounding).
    let scaled = rendition(&a, &b, &opts).unwrap();
    assert!(scaled.max_de2000 < 1e-9, "{}", scaled.max_de2000);
    assert!(scaled.white_max_de2000 < 1e-9);
    for n in &scaled.normals {
        assert!(
            (n.irradiance_ratio - 4.0).abs() < 1e-5,
            "{}",
            n.irradiance_ratio
        );
    }
}

#[test]
fn a_metamer_of_the_light_keeps_the_white_but_not_the_patches() {
    // Reconstruction: D65 plus a metameric black (a smooth ripple with its CMF components
    // projected out), so every pixel has D65's XYZ but not its spectrum.
    let d = tempfile::tempdir().unwrap();
    let wl = grid(380.0, 780.0, 5.0);
    let g = WavelengthGrid::new(380.0, 780.0, 5.0).unwrap();
    let cmfs = Cmfs::new(Observer::Cie1931, &g).unwrap();
    let cols = [cmfs.x.values(), cmfs.y.values(), cmfs.z.values()];
    let mut black: Vec<f64> = wl
        .iter()
        .map(|w| (2.0 * std::f64::consts::PI * (w - 380.0) / 100.0).sin())
        .collect();
    // Gram-Schmidt on the three CMFs, then remove their span from the ripple.
    let mut basis: Vec<Vec<f64>> = Vec::new();
    for c in cols {
        let mut v = c.to_vec();
        for b in &basis {
            let p: f64 = v.iter().zip(b).map(|(x, y)| x * y).sum();
            v.iter_mut().zip(b).for_each(|(x, y)| *x -= p * y);
        }
        let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        v.iter_mut().for_each(|x| *x /= n);
        basis.push(v);
    }
    for b in &basis {
        let p: f64 = black.iter().zip(b).map(|(x, y)| x * y).sum();
        black.iter_mut().zip(b).for_each(|(x, y)| *x -= p * y);
    }
    let d65 = light("D65", &wl, 0.01);
    let metamer: Vec<f64> = d65.iter().zip(&black).map(|(l, b)| l + 0.4 * b).collect();
    assert!(
        metamer.iter().all(|v| *v > 0.0),
        "a physical (positive) metamer"
    );
    let xyz = |s: &[f64]| {
        let s = specmap::spectrum::Spectrum::new(g, s.to_vec()).unwrap();
        cmfs.integrate(&s, specmap::spectrum::Rule::Riemann)
            .unwrap()
    };
    let (a, b) = (xyz(&d65), xyz(&metamer));
    for i in 0..3 {
        assert!((a[i] - b[i]).abs() < 1e-9 * a[i], "XYZ {a:?} vs {b:?}");
    }
    let t = write_map(&d.path().join("t.exr"), Layout::LatLong, 32, &wl, |_| {
        d65.clone()
    });
    let r = write_map(&d.path().join("r.exr"), Layout::LatLong, 32, &wl, |_| {
        metamer.clone()
    });
    let res = rendition(&t, &r, &RenditionOptions::default()).unwrap();
    assert!(res.white_max_de2000 < 1e-4, "{}", res.white_max_de2000);
    assert!(res.mean_de2000 > 0.3, "mean {}", res.mean_de2000);
    assert!(res.max_de2000 > res.mean_de2000);
    // The default normals: up and the four horizontal axes, all alike in a uniform map.
    let names: Vec<_> = res.normals.iter().map(|n| n.normal.name.as_str()).collect();
    assert_eq!(names, ["up", "px", "nx", "pz", "nz"]);
    for n in &res.normals {
        assert!((n.mean_de2000 - res.mean_de2000).abs() < 1e-3);
    }
}

#[test]
fn different_grids_and_layouts_compare_on_what_they_share() {
    let d = tempfile::tempdir().unwrap();
    // Truth 380-720 at 5 nm; reconstruction 380-780 at 10 nm, cube. The spectra are linear
    // between 10 nm knots, so the reconstruction's linear resampling recovers the truth's bands.
    let fine = grid(380.0, 720.0, 5.0);
    let coarse = grid(380.0, 780.0, 10.0);
    let on_knots = |wl: &[f64]| -> Vec<f64> {
        let c = light("D65", &coarse, 0.01);
        wl.iter()
            .map(|w| {
                let i = ((w - 380.0) / 10.0).floor() as usize;
                let f = (w - 380.0) / 10.0 - i as f64;
                if f == 0.0 {
                    c[i]
                } else {
                    c[i] * (1.0 - f) + c[i + 1] * f
                }
            })
            .collect()
    };
    let t = write_map(&d.path().join("t.exr"), Layout::LatLong, 64, &fine, |_| {
        on_knots(&fine)
    });
    let r = write_map(&d.path().join("r.exr"), Layout::Cube, 32, &coarse, |_| {
        on_knots(&coarse)
    });
    let res = rendition(&t, &r, &RenditionOptions::default()).unwrap();
    assert_eq!(res.wavelengths.to_string(), "380:720:5");
    assert_eq!(res.truth.layout, Layout::LatLong);
    assert_eq!(res.reconstructed.layout, Layout::Cube);
    assert_eq!(res.reconstructed.range_nm, [380.0, 780.0]);
    assert!(res.max_de2000 < 1e-3, "{}", res.max_de2000);
    assert!(res.white_max_de2000 < 1e-3);
    // The same non-uniform scene in two layouts: only quadrature separates them.
    let wl = grid(380.0, 780.0, 5.0);
    let f = scene(&wl);
    let a = write_map(&d.path().join("a.exr"), Layout::LatLong, 128, &wl, &f);
    let b = write_map(&d.path().join("b.exr"), Layout::Cube, 64, &wl, &f);
    let res = rendition(&a, &b, &RenditionOptions::default()).unwrap();
    assert!(res.mean_de2000 < 0.2, "{}", res.mean_de2000);
}

fn specmap(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_specmap"))
        .args(args)
        .output()
        .expect("the specmap binary runs")
}

/// Runs specmap, expecting exit code `code` (1: a failure; 2: clap's usage error) and a message
/// with every one of `parts`.
fn fails_with(code: i32, args: &[&str], parts: &[&str]) {
    let out = specmap(args);
    assert_eq!(out.status.code(), Some(code), "{args:?} was accepted");
    let msg = String::from_utf8(out.stderr).unwrap();
    for p in parts {
        assert!(msg.contains(p), "message lacks '{p}': {msg}");
    }
}

fn fails(args: &[&str], parts: &[&str]) {
    fails_with(1, args, parts)
}

#[test]
fn bad_inputs_get_clear_errors() {
    let d = tempfile::tempdir().unwrap();
    let wl = grid(380.0, 780.0, 10.0);
    let good = write_map(&d.path().join("good.exr"), Layout::LatLong, 16, &wl, |_| {
        vec![1.0; wl.len()]
    });
    let g = good.to_str().unwrap();
    let missing = d.path().join("missing.exr");
    fails(
        &["rendition", missing.to_str().unwrap(), g],
        &["reading the truth map", "missing.exr"],
    );
    fails(
        &["rendition", g, missing.to_str().unwrap()],
        &["reading the reconstructed map", "missing.exr"],
    );
    // An RGB map, as a user has before converting it.
    let rgb = root().join("tests/data/truth/street_hps.rgb.exr");
    fails(
        &["rendition", g, rgb.to_str().unwrap()],
        &["no spectral channels", "street_hps.rgb.exr"],
    );
    // Not an image at all.
    let text = d.path().join("notes.exr");
    std::fs::write(&text, "hello").unwrap();
    fails(&["rendition", text.to_str().unwrap(), g], &["notes.exr"]);
    // A spectral image that is no environment map (5x3).
    let odd = d.path().join("odd.exr");
    let mut w = SpectralWriter::create(
        &odd,
        SpectralLayout {
            width: 5,
            height: 3,
            channels: ChannelSet::Spectral {
                wavelengths_nm: wl.clone(),
                preview_rgb: false,
            },
            precision: Precision::Half,
            compression: Compression::Zip,
            envmap: None,
            ev: None,
            attributes: vec![],
            zip_level: specmap::envmap::files::ZIP_DEFAULT_LEVEL,
            unscaled: Vec::new(),
        },
    )
    .unwrap();
    w.write_rows(0, &vec![1.0; 15 * wl.len()]).unwrap();
    w.finish().unwrap();
    fails(
        &["rendition", g, odd.to_str().unwrap()],
        &["odd.exr", "not an environment map", "5x3"],
    );
    // No shared wavelengths.
    let ir = grid(800.0, 900.0, 10.0);
    let infrared = write_map(&d.path().join("ir.exr"), Layout::LatLong, 16, &ir, |_| {
        vec![1.0; ir.len()]
    });
    fails(
        &["rendition", g, infrared.to_str().unwrap()],
        &["share no wavelength range", "380..780", "800..900"],
    );
    // A normal that sees nothing of the map: a map lit only from below, measured facing up.
    let below = write_map(
        &d.path().join("below.exr"),
        Layout::LatLong,
        16,
        &wl,
        |dir| vec![if dir[1] < 0.0 { 1.0 } else { 0.0 }; wl.len()],
    );
    let b = below.to_str().unwrap();
    fails(
        &["rendition", b, b, "--normals", "up"],
        &["normal up", "no visible energy"],
    );
    fails_with(
        2,
        &["rendition", g, g, "--normals", "0:0:0"],
        &["no direction"],
    );
    fails_with(
        2,
        &["rendition", g, g, "--normals", "sideways"],
        &["sideways", "X:Y:Z"],
    );
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn committed_truth_scenes_through_the_binary() {
    let truth = root().join("tests/data/truth");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(truth.join("manifest.json")).unwrap())
            .unwrap();
    let scenes = manifest["scenes"].as_array().unwrap();
    assert!(
        scenes.len() >= 15,
        "clear skies, two interiors and a street"
    );
    for s in scenes {
        let spectral = truth.join(s["spectral"].as_str().unwrap());
        let info = specmap::envmap::files::read_spectral_info(&spectral).unwrap();
        let end = if s["name"].as_str().unwrap().starts_with("sky_") {
            720.0
        } else {
            780.0
        };
        assert_eq!(info.wavelengths_nm[0], 380.0);
        assert_eq!(*info.wavelengths_nm.last().unwrap(), end);
        assert_eq!(info.envmap, Some(EnvmapAttr::LatLong));
        assert!(info.has_rgb);
        assert!(truth.join(s["rgb"].as_str().unwrap()).is_file());
    }
    // A map against itself: zero everywhere, all six axes.
    let sky = truth.join("sky_e20_t4.spectral.exr");
    let s = sky.to_str().unwrap();
    let out = specmap(&["rendition", s, s, "--normals=up,down,+x,-x,+z,-z", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["mean_de2000"], 0.0);
    assert_eq!(v["white_max_de2000"], 0.0);
    assert_eq!(v["normals"].as_array().unwrap().len(), 6);
    assert_eq!(v["wavelengths"]["len"], 69);
    // The sky against the street: a different light, every number large, readable output.
    let street = truth.join("street_hps.spectral.exr");
    let out = specmap(&["rendition", s, street.to_str().unwrap()]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("rendition CIEDE2000: mean"), "{text}");
    assert!(text.contains("380:720:5"), "{text}");
}
