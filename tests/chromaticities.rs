//! OpenEXR's `chromaticities` attribute: `convert` reads a map in the space its file declares
//! (`--space` overrides it, with a note), says what RGB (1,1,1) is in it, and declares the space
//! of its R, G, B preview in the output, which `roundtrip` reads back.

use exr::meta::attribute::Chromaticities;
use exr::prelude::*;
use std::path::Path;

mod common;

use common::specmap;

/// ACES AP1 primaries and the ACES white (ACES TB-2014-004).
const AP1: [f32; 8] = [0.713, 0.293, 0.165, 0.830, 0.128, 0.044, 0.32168, 0.33767];
/// Rec.709 primaries and D65 (IEC 61966-2-1).
const REC709: [f32; 8] = [0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290];

fn chromaticities(c: [f32; 8]) -> Chromaticities {
    Chromaticities {
        red: Vec2(c[0], c[1]),
        green: Vec2(c[2], c[3]),
        blue: Vec2(c[4], c[5]),
        white: Vec2(c[6], c[7]),
    }
}

/// Writes a 64 x 32 RGB map with the exr crate (an independent writer), declaring `declared`.
fn write_map(path: &Path, declared: Option<[f32; 8]>, f: impl Fn(usize, usize) -> [f32; 3] + Sync) {
    let layer = Layer::new(
        (64, 32),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        SpecificChannels::rgb(|p: Vec2<usize>| {
            let c = f(p.0, p.1);
            (c[0], c[1], c[2])
        }),
    );
    let mut image = Image::from_layer(layer);
    image.attributes.chromaticities = declared.map(chromaticities);
    image.write().to_file(path).unwrap();
}

fn convert(args: &[&str]) -> (serde_json::Value, String) {
    let mut all = vec!["convert"];
    all.extend_from_slice(args);
    let text = specmap(&all);
    assert!(
        text.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&text.stderr)
    );
    all.push("--json");
    let json = specmap(&all);
    (
        serde_json::from_slice(&json.stdout).unwrap(),
        String::from_utf8_lossy(&text.stdout).into_owned(),
    )
}

fn declared_by(path: &Path) -> Option<Chromaticities> {
    let meta = exr::meta::MetaData::read_from_file(path, false).unwrap();
    meta.headers[0].shared_attributes.chromaticities
}

/// A room of neutral grey walls under a bright neutral ceiling.
fn neutral(_: usize, y: usize) -> [f32; 3] {
    if y < 6 {
        [20.0; 3]
    } else {
        [0.3; 3]
    }
}

#[test]
fn a_declared_space_is_read_stated_and_passed_on() {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("aces.exr");
    write_map(&input, Some(AP1), |x, y| {
        [0.1 + x as f32 / 64.0, 0.2 + y as f32 / 32.0, 0.5]
    });
    let out = d.path().join("aces.spectral.exr");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let (r, text) = convert(&[i, "-o", o]);
    assert_eq!(r["space"]["name"], "acescg", "{}", r["space"]);
    assert_eq!(r["space"]["source"], "file");
    assert_eq!(r["space"]["white"], "ACES white (x 0.32168, y 0.33767)");
    assert!(
        text.contains("RGB (1,1,1) is the space's white, ACES white (x 0.32168, y 0.33767)"),
        "{text}"
    );
    assert!(!text.contains("D65 white"), "{text}");
    // The preview channels keep the input's values: the output declares their space.
    assert_eq!(declared_by(&out), Some(chromaticities(AP1)));
    let rt = specmap(&["roundtrip", o, "--json"]);
    let rt: serde_json::Value = serde_json::from_slice(&rt.stdout).unwrap();
    assert_eq!(rt["space"], "acescg");
    assert!(
        rt["all"]["max_de2000"].as_f64().unwrap() < 0.05,
        "{}",
        rt["all"]
    );
}

#[test]
fn space_overrides_what_the_file_declares_with_a_note() {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("aces.exr");
    write_map(&input, Some(AP1), neutral);
    let out = d.path().join("o.exr");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let (r, _) = convert(&[i, "-o", o, "--space", "srgb"]);
    assert_eq!(r["space"]["name"], "srgb");
    assert_eq!(r["space"]["source"], "given");
    assert!(r["space"]["declared"].is_object(), "{}", r["space"]);
    let notes = r["notes"].to_string();
    assert!(
        notes.contains("overrides the file's chromaticities"),
        "{notes}"
    );
    assert_eq!(declared_by(&out), Some(chromaticities(REC709)));
    // Asking for the space the file declares is no override: no note.
    let (r, _) = convert(&[i, "-o", o, "--space", "acescg"]);
    assert!(r["space"]["declared"].is_null());
    assert!(!r["notes"].to_string().contains("overrides"));
    // A file that declares nothing is Rec.709 with D65, and its output says so.
    let plain = d.path().join("plain.exr");
    write_map(&plain, None, neutral);
    let (r, _) = convert(&[plain.to_str().unwrap(), "-o", o]);
    assert_eq!(r["space"]["name"], "srgb");
    assert_eq!(r["space"]["source"], "default");
    assert_eq!(declared_by(&out), Some(chromaticities(REC709)));
}

#[test]
fn the_white_premise_is_judged_against_the_space_s_own_white() {
    // Neutral in ACEScg is ACES white: a map showing its D65 lamp as neutral is white-balanced
    // to it (the light premise), not referenced to D65 as it would be in sRGB.
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("aces.exr");
    write_map(&input, Some(AP1), neutral);
    let o = d.path().join("o.exr");
    let (i, o) = (input.to_str().unwrap(), o.to_str().unwrap());
    let (r, _) = convert(&[i, "-o", o, "--light", "D65", "--lights", "one"]);
    assert_eq!(r["white"]["premise"], "light", "{}", r["white"]);
    assert!(r["white"]["reason"]
        .as_str()
        .unwrap()
        .contains("ACES white"));
    let srgb = d.path().join("srgb.exr");
    write_map(&srgb, None, neutral);
    let (r, _) = convert(&[
        srgb.to_str().unwrap(),
        "-o",
        o,
        "--light",
        "D65",
        "--lights",
        "one",
    ]);
    assert_eq!(r["white"]["premise"], "space", "{}", r["white"]);
}

#[test]
fn chromaticities_that_make_no_space_or_disagree_between_faces_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let bad = d.path().join("bad.exr");
    write_map(
        &bad,
        Some([0.2, 0.2, 0.3, 0.3, 0.4, 0.4, 0.3127, 0.329]),
        neutral,
    );
    let out = d.path().join("o.exr");
    let r = specmap(&[
        "convert",
        bad.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success());
    assert!(
        err.contains("bad.exr") && err.contains("collinear"),
        "{err}"
    );
    assert!(!out.exists());
    // Six faces, one of another space.
    let w = 16;
    for (k, face) in ["px", "nx", "py", "ny", "pz", "nz"].iter().enumerate() {
        let layer = Layer::new(
            (w, w),
            LayerAttributes::default(),
            Encoding::FAST_LOSSLESS,
            SpecificChannels::rgb(|_: Vec2<usize>| (0.5f32, 0.5f32, 0.5f32)),
        );
        let mut image = Image::from_layer(layer);
        image.attributes.chromaticities = Some(chromaticities(if k == 3 { AP1 } else { REC709 }));
        image
            .write()
            .to_file(d.path().join(format!("sky_{face}.exr")))
            .unwrap();
    }
    let pattern = d.path().join("sky_{face}.exr");
    let r = specmap(&[
        "convert",
        pattern.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--in-layout",
        "faces",
    ]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success());
    assert!(
        err.contains("the ny face declares other chromaticities"),
        "{err}"
    );
}

/// Display P3's primaries and D65, and its XYZ -> RGB matrix (SMPTE EG 432-1, D65 white, as
/// colour-science gives it); sRGB's RGB -> XYZ (IEC 61966-2-1).
const P3: [f32; 8] = [0.680, 0.320, 0.265, 0.690, 0.150, 0.060, 0.3127, 0.3290];
const P3_FROM_XYZ: [[f64; 3]; 3] = [
    [2.4934969, -0.9313836, -0.4027108],
    [-0.8294890, 1.7626641, 0.0236247],
    [0.0358458, -0.0761724, 0.9568845],
];
const XYZ_FROM_SRGB: [[f64; 3]; 3] = [
    [0.4124, 0.3576, 0.1805],
    [0.2126, 0.7152, 0.0722],
    [0.0193, 0.1192, 0.9505],
];

fn mul(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| (0..3).map(|c| m[r][c] * v[c]).sum())
}

#[test]
fn render_reads_an_rgb_environment_in_its_declared_space() {
    // The same colours written as sRGB (no chromaticities) and as Display P3 (declared; the
    // same white, so the renderer's light premise maps both whites alike): the same light, so
    // the same render.
    let d = tempfile::tempdir().unwrap();
    let srgb = |x: usize, y: usize| -> [f64; 3] {
        let t = (x as f64 / 63.0, y as f64 / 31.0);
        [0.2 + 0.6 * t.0, 0.5, 0.2 + 0.6 * t.1].map(|v| v * if y < 8 { 4.0 } else { 1.0 })
    };
    let (a, b) = (d.path().join("srgb.exr"), d.path().join("p3.exr"));
    write_map(&a, None, |x, y| srgb(x, y).map(|v| v as f32));
    write_map(&b, Some(P3), |x, y| {
        mul(&P3_FROM_XYZ, mul(&XYZ_FROM_SRGB, srgb(x, y))).map(|v| v as f32)
    });
    let render = |env: &Path, out: &str| {
        let out = d.path().join(out);
        let r = specmap(&[
            "render",
            "--scene",
            "ball",
            "--backend",
            "cpu",
            "--size",
            "32x32",
            "--env",
            env.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        specmap::envmap::files::read_rgb(&out, None)
            .unwrap()
            .image
            .pixels
    };
    let (pa, pb) = (render(&a, "a.exr"), render(&b, "b.exr"));
    let peak = pa.iter().flatten().fold(0f32, |m, v| m.max(v.abs()));
    let worst = pa
        .iter()
        .flatten()
        .zip(pb.iter().flatten())
        .fold(0f32, |m, (x, y)| m.max((x - y).abs()));
    // The published sRGB matrix has 4 decimals: 1e-4 of the colours.
    assert!(worst < 2e-3 * peak, "{worst} of {peak}");
}
