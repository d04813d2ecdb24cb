//! The round-trip statistic (src/envmap/roundtrip/stats.rs) as `convert` and `roundtrip` report
//! it: one definition, a luminance floor relative to the map, and where the maximum is.

use std::path::Path;

mod common;

use common::{specmap, specmap_json as json};

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("{v} is not a number"))
}

/// A 64 x 32 lat-long room: grey walls of luminance 0.6, a band of saturated colours of the
/// same luminance, and `dark` grey pixels of luminance 2e-7.
fn room(path: &Path, dark: &[(usize, usize)]) {
    let colours = [
        [0.9f32, 0.45, 0.2],
        [0.2, 0.7, 0.9],
        [0.8, 0.6, 0.1],
        [0.5, 0.6, 0.9],
    ];
    let y_of = |p: [f32; 3]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let dark = dark.to_vec();
    exr::prelude::write_rgb_file(path, 64, 32, move |x, y| {
        let p = if dark.contains(&(x, y)) {
            [2e-7, 2e-7, 2e-7]
        } else if (12..20).contains(&y) {
            let c = colours[x % 4];
            let s = 0.6 / y_of(c);
            [c[0] * s, c[1] * s, c[2] * s]
        } else {
            [0.6, 0.6, 0.6]
        };
        (p[0], p[1], p[2])
    })
    .unwrap();
}

/// Which of `room`'s colours (without dark pixels) is at `[x, y]`: a band index or the wall.
fn colour_at(at: &serde_json::Value) -> Option<usize> {
    let (x, y) = (at[0].as_u64().unwrap(), at[1].as_u64().unwrap());
    (12..20).contains(&y).then_some(x as usize % 4)
}

#[test]
fn near_black_pixels_are_counted_below_the_floor_not_in_the_maximum() {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("room.exr");
    let dark = [(3, 25), (40, 28), (50, 2)];
    room(&input, &dark);
    let out = d.path().join("room.spectral.exr");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let c = json(&["convert", i, "-o", o, "--quiet"]);
    let r = json(&["roundtrip", o]);
    // The floor: 2^-13 of the 99th percentile, which is the walls' 0.6 rounded down to 1/16
    // octave: 2^(floor(16 log2 0.6) / 16) = 2^-0.75.
    let reference = (-0.75f64).exp2();
    for floor in [&c["roundtrip_floor"], &r["floor"]] {
        assert!(
            (f(&floor["reference_luminance"]) - reference).abs() < 1e-12,
            "{floor}"
        );
        assert!((f(&floor["luminance"]) - reference / 8192.0).abs() < 1e-15);
    }
    // Half floats round the dark pixels' spectra and preview to a few subnormal steps: their
    // round trip is far off, and counted below the floor, not in the maximum.
    let all = &r["all"];
    assert_eq!(all["below_floor"]["pixels"], dark.len(), "{all}");
    assert!(f(&all["below_floor"]["max_de2000"]) > 3.0, "{all}");
    assert!(f(&all["below_floor"]["energy_share"]) < 1e-9);
    assert!(f(&all["max_de2000"]) < 0.1, "{all}");
    assert_eq!(all["pixels"], 64 * 32 - dark.len());
    assert!(f(&all["max_luminance"]) >= f(&r["floor"]["luminance"]));
    // The conversion, which measures its spectra before rounding, counts the same pixels.
    assert_eq!(c["roundtrip"]["below_floor"]["pixels"], dark.len());
    assert_eq!(c["roundtrip"]["pixels"], all["pixels"]);
    // The text states the floor and where the maximum is.
    let text = specmap(&["roundtrip", o]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(
        text.contains("2^-13 of the map's 99th-percentile luminance") && text.contains(" at ("),
        "{text}"
    );
    assert!(text.contains("3 below the floor"), "{text}");
}

#[test]
fn convert_and_roundtrip_report_the_same_statistic_for_the_same_file() {
    // The paper mode's pixels are not exact: errors of several CIEDE2000 at every colour.
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("room.exr");
    room(&input, &[(10, 30)]);
    let out = d.path().join("room.spectral.exr");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let c = json(&[
        "convert",
        i,
        "-o",
        o,
        "--quiet",
        "--mode",
        "paper",
        "--precision",
        "float",
    ]);
    let r = json(&["roundtrip", o]);
    assert_eq!(c["roundtrip_floor"], r["floor"]);
    for (a, b) in [
        (&c["roundtrip"], &r["all"]),
        (&c["roundtrip_without_sun"], &r["without_sun"]),
    ] {
        assert!(f(&a["max_de2000"]) > 1.0, "{a}");
        assert!(
            (f(&a["max_de2000"]) - f(&b["max_de2000"])).abs() < 1e-3,
            "{a} {b}"
        );
        let mean = |v: &serde_json::Value| f(&v["weighted_mean_de2000"]);
        assert!((mean(a) - mean(b)).abs() < 1e-3, "{a} {b}");
        for k in ["pixels", "black_pixels"] {
            assert_eq!(a[k], b[k], "{k}: {a} {b}");
        }
        // Pixels of one colour tie to a few ulps (the file holds f32, the conversion measured
        // f64), so the maximum may be found at another pixel of the same colour.
        assert_eq!(colour_at(&a["max_at"]), colour_at(&b["max_at"]), "{a} {b}");
        assert_eq!(a["below_floor"]["pixels"], b["below_floor"]["pixels"]);
    }
    // In the paper's modes the pixels that do not keep their colour are counted as inexact
    // (here every one: even the grey walls, white by the sRGB white point, are a hair off the
    // main light's, the CIE D65 table's, which the paper's weights keep), in the
    // exact mode none.
    let inexact = &c["inexact"];
    assert_eq!(
        inexact["max_de2000"], c["roundtrip"]["max_de2000"],
        "{inexact}"
    );
    assert_eq!(inexact["pixels"], c["roundtrip"]["pixels"], "{inexact}");
    let c = json(&["convert", i, "-o", o, "--quiet", "--mode", "exact"]);
    assert_eq!(c["inexact"]["pixels"], 0, "{}", c["inexact"]);
    assert_eq!(c["inexact"]["below_floor"]["pixels"], 0);
}
