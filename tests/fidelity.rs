//! The default conversion against the ground-truth scenes of `tests/data/truth` (issue 8, part 5,
//! and issue 13): each RGB map converted in-process, then `specmap::rendition` against its true
//! spectra. Targets: mean rendition CIEDE2000 under 0.6 on the clear skies, under 1.0 for the
//! fluorescent interiors, under 1.5 for the sodium street, and the white within 0.5 everywhere;
//! for the scenes of several lights (lit by measured lamps the converter does not match against)
//! under 0.6 for the street and the yard, under 0.4 for the incandescent room given
//! `--light A --white light`; the mixed office stays under 0.7 (its 0.6 target is not met: the
//! nearest catalogue tube, FL11, renders the ColorChecker 0.6 from the true f32t8-tl841 by
//! itself, `tools/lamp_rendition.py`). `tools/rendition_table.py` prints the same numbers.

use specmap::envmap::convert::{convert, ConvertOptions, LightSpec, Method, SunSpd, WhiteSpec};
use specmap::fit::Mode;
use specmap::rendition::{rendition, Rendition, RenditionOptions};
use std::path::{Path, PathBuf};

fn truth(name: &str, kind: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/truth")
        .join(format!("{name}.{kind}.exr"))
}

/// Converts a truth scene's RGB map with `opts` and measures its rendition.
fn measure(dir: &Path, name: &str, opts: &ConvertOptions) -> Rendition {
    let out = dir.join(format!("{name}.exr"));
    let input = truth(name, "rgb");
    let report = convert(input.to_str().unwrap(), &out, opts, &|_, _| {}).unwrap();
    // The round trip RGB -> SPD -> RGB stays exact (f64 maths before the half-float file), but
    // for the pixels judged clipped, which get their lamp's SPD (a flash softbox's hot spot at
    // the map's maximum is one: docs/scenes.md).
    let only_clipped = report.inexact.pixels == report.spectra.clipped;
    assert!(
        report.roundtrip.max_de2000 < 1e-3 || opts.method != Method::Faithful || only_clipped,
        "{name}: round trip {:?}",
        report.roundtrip
    );
    let r = rendition(&truth(name, "spectral"), &out, &RenditionOptions::default()).unwrap();
    eprintln!(
        "{name:14} light {:5} mean {:.3} max {:.3} white {:.3} / {:.3}",
        report.light, r.mean_de2000, r.max_de2000, r.white_mean_de2000, r.white_max_de2000
    );
    r
}

/// The mean rendition under `mean`, the white (at every normal) within 0.5.
fn within(r: Rendition, mean: f64, name: &str) {
    assert!(r.mean_de2000 < mean, "{name}: mean {}", r.mean_de2000);
    assert!(
        r.white_max_de2000 < 0.5,
        "{name}: white {}",
        r.white_max_de2000
    );
}

const SKIES: [&str; 12] = [
    "sky_e05_t2",
    "sky_e05_t4",
    "sky_e05_t6",
    "sky_e20_t2",
    "sky_e20_t4",
    "sky_e20_t6",
    "sky_e45_t2",
    "sky_e45_t4",
    "sky_e45_t6",
    "sky_e70_t2",
    "sky_e70_t4",
    "sky_e70_t6",
];

#[test]
fn the_default_renders_clear_skies_within_the_targets() {
    let d = tempfile::tempdir().unwrap();
    for name in SKIES {
        within(
            measure(d.path(), name, &ConvertOptions::faithful()),
            0.6,
            name,
        );
    }
}

#[test]
fn the_default_renders_fluorescent_interiors_within_the_targets_with_the_right_light() {
    let d = tempfile::tempdir().unwrap();
    for (name, light) in [("interior_fl2", "FL2"), ("interior_fl11", "FL11")] {
        let opts = ConvertOptions {
            light: LightSpec::Named(light.into()),
            ..ConvertOptions::faithful()
        };
        within(measure(d.path(), name, &opts), 1.0, name);
    }
}

#[test]
fn the_default_renders_scenes_of_several_lights_within_the_targets() {
    let d = tempfile::tempdir().unwrap();
    for (name, mean) in [
        ("street_mixed", 0.6),
        ("yard_overcast", 0.6),
        ("office_mixed", 0.6),
        // 3500 K tubes, whose white is the halophosphate FL3's: a triphosphor table is taken
        // (2.3 with FL3).
        ("office_warm_tubes", 0.65),
    ] {
        within(
            measure(d.path(), name, &ConvertOptions::faithful()),
            mean,
            name,
        );
    }
    // A room white-balanced to its bulbs: said so, and the bulbs named (A for 60w-soft-white).
    let opts = ConvertOptions {
        light: LightSpec::Named("A".into()),
        white: Some(WhiteSpec::Light),
        ..ConvertOptions::faithful()
    };
    let r = measure(d.path(), "room_incandescent_dusk", &opts);
    assert!(r.mean_de2000 < 0.4, "room: mean {}", r.mean_de2000);
}

/// The studios, the living room and the dusk street of tools/truth_studio.py (issue 41): LED
/// softboxes, xenon flash through a diffuser and tungsten under the default flags, a daylight
/// window beside warm LED lamps, and coated sodium lamps (c100s54c, not a table of the
/// catalogue) with two LED lamps under a twilight sky. The coated lamps' white is a black body's,
/// between the standard sodium lamp's and the colour-improved one's: their mix of that white
/// renders the ColorChecker 0.6 from c100s54c by itself, where the nearest table (HP2) is 2.7
/// (`tools/lamp_rendition.py`).
#[test]
fn the_default_renders_studios_rooms_and_the_dusk_street_within_the_targets() {
    let d = tempfile::tempdir().unwrap();
    for (name, mean) in [
        ("studio_led", 0.8),
        ("studio_flash", 0.8),
        ("studio_tungsten", 0.8),
        ("room_window_lamps", 0.6),
        ("street_dusk", 0.6),
    ] {
        within(
            measure(d.path(), name, &ConvertOptions::faithful()),
            mean,
            name,
        );
    }
}

#[test]
fn the_default_renders_the_sodium_street_within_the_targets_with_light_auto() {
    let d = tempfile::tempdir().unwrap();
    let opts = ConvertOptions {
        light: LightSpec::Auto,
        ..ConvertOptions::faithful()
    };
    within(measure(d.path(), "street_hps", &opts), 1.5, "street_hps");
}

/// The paper's method as written, beside the default: what the default improves on.
#[test]
fn the_papers_method_stays_available_and_is_what_the_default_improves_on() {
    let d = tempfile::tempdir().unwrap();
    let paper = ConvertOptions {
        method: Method::Basis,
        mode: Mode::Paper,
        white: Some(WhiteSpec::Light),
        sun_spd: Some(SunSpd::D65),
        ..ConvertOptions::faithful()
    };
    let p = measure(d.path(), "sky_e05_t2", &paper);
    // The numbers of the previous measurement (issue 8, part 2): the method is unchanged.
    assert!((p.mean_de2000 - 1.38).abs() < 0.01, "{}", p.mean_de2000);
    assert!((p.white_mean_de2000 - 13.25).abs() < 0.01);
    let f = measure(d.path(), "sky_e05_t2", &ConvertOptions::faithful());
    assert!(f.mean_de2000 < p.mean_de2000 / 3.0);
}
