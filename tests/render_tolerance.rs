//! `render --tolerance`: the quadrature chosen from the scene's stimuli (lights, pigments, films
//! over their angles and thicknesses) gives a render whose every pixel stays within the
//! tolerance of the 1 nm render, measured on the image, not on the estimate; and it needs far
//! fewer wavelengths than the uniform grid chosen for the same tolerance.

use specmap::colorimetry::{Observer, RgbSpace};
use specmap::quadrature::choose::{Family, Selection};
use specmap::quadrature::fit::Options;
use specmap::quadrature::{Kind, Quadrature};
use specmap::render::{compare, Preset, Scene};
use specmap::spectrum::{Rule, WavelengthGrid};

const TOL: f64 = 0.5;

fn scene(preset: Preset, light: &str, width: usize) -> Scene {
    let (w, h) = preset.default_size();
    preset.scene(width, width * h / w, light, None).unwrap()
}

fn choose(scene: &Scene, family: Family) -> Selection {
    let opts = Options::new(TOL).unwrap();
    scene
        .choose_quadrature(Observer::Cie1931, RgbSpace::SRGB, family, &opts)
        .unwrap()
}

/// The largest CIEDE2000 of the render on `q` against the 1 nm Simpson render.
fn image_error(scene: &Scene, q: &Quadrature) -> f64 {
    let grid = WavelengthGrid::new(380.0, 780.0, 1.0).unwrap();
    let reference = Quadrature::uniform(grid, Rule::Simpson, Observer::Cie1931).unwrap();
    let a = scene.render_cpu_with(q, RgbSpace::SRGB).unwrap();
    let b = scene.render_cpu_with(&reference, RgbSpace::SRGB).unwrap();
    let c = compare(&a, &b, &RgbSpace::SRGB).unwrap();
    assert_eq!(c.non_finite, 0);
    c.max
}

/// Fits, renders, and checks the image against the tolerance; returns the node count.
fn check(preset: Preset, light: &str, width: usize) -> usize {
    let s = scene(preset, light, width);
    let c = choose(&s, Family::Scene);
    assert!(c.met, "{preset:?} under {light}: {c:?}");
    assert_eq!(
        c.kind,
        Kind::Scene,
        "{preset:?} under {light}: {}",
        c.reason
    );
    let max = image_error(&s, &c.quadrature);
    eprintln!(
        "{preset:?} under {light}: {} nodes, estimate {:.3}, image max {max:.3}; uniform {} ({})",
        c.quadrature.len(),
        c.estimate_de2000,
        c.uniform.grid,
        c.uniform.samples
    );
    assert!(
        max <= TOL,
        "{preset:?} under {light}: {} gives {max} on the image",
        c.quadrature
    );
    // The uniform grid chosen for the same tolerance needs at least three times the nodes.
    assert!(c.uniform.met && c.uniform.samples >= 3 * c.quadrature.len());
    c.quadrature.len()
}

#[test]
fn the_ball_meets_the_tolerance_on_the_image_under_smooth_and_spiky_lights() {
    let d65 = check(Preset::Ball, "D65", 32);
    let fl2 = check(Preset::Ball, "FL2", 32);
    let lps = check(Preset::Ball, "lps", 32);
    assert!(d65 <= 8 && fl2 <= 16 && lps <= 4, "{d65} {fl2} {lps}");
}

#[test]
fn the_transparent_ball_and_the_chart_meet_the_tolerance_on_the_image() {
    assert!(check(Preset::TransparentBall, "D65", 32) <= 8);
    assert!(check(Preset::TransparentBall, "hps", 32) <= 16);
    assert!(check(Preset::Chart, "D65", 48) <= 16);
}

/// 24 matte ColorChecker spheres: every stimulus is fitted (none held out), so the image, rendered
/// apart from the fit (f32 on the renderer's path, the background as seen), is what checks it.
#[test]
fn the_checker_spheres_meet_the_tolerance_on_the_image() {
    assert!(check(Preset::CheckerSpheres, "A", 48) <= 8);
    assert!(check(Preset::CheckerSpheres, "FL11", 48) <= 16);
}

#[test]
fn the_estimate_covers_a_glossy_pigments_mixture_of_colour_and_highlight() {
    // The chart's plastic spheres show their pigment plus part of the key light's white
    // highlight. With the pigment and the highlight sampled apart, the red sphere erred 23%
    // above the estimate; sampling their mixtures brings the image under it.
    let s = scene(Preset::Chart, "D65", 96);
    let c = choose(&s, Family::Scene);
    let max = image_error(&s, &c.quadrature);
    assert!(
        max <= 1.05 * c.estimate_de2000,
        "{} nodes: estimate {:.3}, image {max:.3}",
        c.quadrature.len(),
        c.estimate_de2000
    );
}

#[test]
fn the_estimate_covers_a_photographs_mixtures_of_its_basis() {
    // A texel of an RGB map radiates a mixture of the three basis spectra. With the three
    // alone as stimuli, the ball under the sunrise photograph erred 0.48 on the image against
    // an estimate of 0.32; with its most different texels' mixtures the image is under it.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("envmaps/sunrise.exr");
    let (lighting, _) = specmap::render::env::load(&path, "D65").unwrap();
    let s = Preset::Ball.scene(48, 48, "D65", Some(lighting)).unwrap();
    let c = choose(&s, Family::Scene);
    let max = image_error(&s, &c.quadrature);
    assert!(
        c.met && max <= TOL && max <= 1.05 * c.estimate_de2000,
        "{} nodes: estimate {:.3}, image {max:.3}",
        c.quadrature.len(),
        c.estimate_de2000
    );
}

#[test]
fn the_cylinders_meet_the_tolerance_on_the_image() {
    // A thickness ramp of 100-400 nm: the most varied spectra of the presets.
    assert!(check(Preset::Cylinders, "FL11", 24) <= 16);
}

#[test]
fn a_uniform_choice_meets_the_tolerance_too() {
    let s = scene(Preset::Ball, "FL2", 24);
    let c = choose(&s, Family::Uniform);
    assert_eq!(c.kind, Kind::Uniform);
    assert!(c.met && c.scene.is_none());
    assert!(image_error(&s, &c.quadrature) <= TOL);
}

/// `s`'s choice at the tolerance within `budget` nodes.
fn choose_within(s: &Scene, budget: usize) -> Selection {
    let opts = Options::with_budget(TOL, budget).unwrap();
    s.choose_quadrature(Observer::Cie1931, RgbSpace::SRGB, Family::Scene, &opts)
        .unwrap()
}

/// `s` chosen within `budget` nodes, fewer than it needs: the choice stays within the budget,
/// says it misses, and reports its image's error as `compare` finds it on the full renders.
fn a_miss_within(s: &Scene, budget: usize) -> Selection {
    let c = choose_within(s, budget);
    assert!(
        !c.met && c.kind == Kind::Scene && c.quadrature.len() <= budget,
        "{}",
        c.reason
    );
    let check = c.image.expect("a miss reports its image");
    let full = image_error(s, &c.quadrature);
    eprintln!(
        "at most {budget}: estimate {:.3}, image {full:.3} ({})",
        c.estimate_de2000, c.reason
    );
    assert!(
        (check.max_de2000 - full).abs() < 1e-9,
        "{check:?} against {full}"
    );
    c
}

/// A renderer's fixed budget (`render --max-nodes`). The checker spheres under A need 6 nodes at
/// 0.5; with a budget of 6 the choice is the same, with 5 no quadrature meets it and the scene's
/// best 5 are chosen, not the uniform grid that meets it with 21. Under a map of its own
/// spectra (the FL2 interior, 12 nodes) a budget of 8 is a miss too, taken without refits.
#[test]
fn a_budget_of_nodes_bounds_the_choice_and_a_miss_reports_its_image() {
    let s = scene(Preset::CheckerSpheres, "A", 48);
    let free = choose(&s, Family::Scene);
    let n = free.quadrature.len();
    assert!(free.met, "{}", free.reason);
    let roomy = choose_within(&s, n);
    assert!(roomy.met, "{}", roomy.reason);
    assert_eq!(roomy.quadrature.nodes_nm(), free.quadrature.nodes_nm());
    let tight = a_miss_within(&s, n - 1);
    assert!(tight.uniform.met && tight.uniform.samples >= n);
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/truth/interior_fl2.spectral.exr");
    let (lighting, _) = specmap::render::env::load(&path, "D65").unwrap();
    let s = Preset::Ball.scene(32, 32, "D65", Some(lighting)).unwrap();
    let c = a_miss_within(&s, 8);
    assert!(c.reason.contains("no refit"), "{}", c.reason);
}

/// The last check of `--tolerance` is the image itself, rendered on the quadrature and at 1 nm.
/// With a margin of 1.6 the stimuli alone let the chart's image err beyond the tolerance; the
/// image's check sees it and refits until the image is within the tolerance.
#[test]
fn the_image_is_checked_against_the_1nm_render_and_refitted_when_it_misses() {
    let s = scene(Preset::Chart, "D65", 48);
    let opts = Options {
        margin: 1.6,
        ..Options::new(TOL).unwrap()
    };
    // The stimuli alone, as the fit saw them before the image was checked.
    let st = s.stimuli().unwrap();
    let stimuli_only = specmap::quadrature::choose::select(
        &specmap::quadrature::choose::Scene {
            fit: &st.fit,
            held_out: &st.held_out,
            observer: Observer::Cie1931,
            start_nm: 380.0,
            end_nm: 780.0,
            white: specmap::quadrature::estimate::White::Fixed(
                RgbSpace::SRGB.xyz_from_rgb([1.0; 3]),
            ),
        },
        Family::Scene,
        &opts,
    )
    .unwrap();
    let before = image_error(&s, &stimuli_only.quadrature);
    assert!(before > TOL, "the stimuli alone: image {before:.3}");
    let c = s
        .choose_quadrature(Observer::Cie1931, RgbSpace::SRGB, Family::Scene, &opts)
        .unwrap();
    let after = image_error(&s, &c.quadrature);
    let check = c.image.expect("the image was checked");
    eprintln!(
        "margin 1.6: {} nodes, image {before:.3}; checked: {} nodes, image {after:.3} ({})",
        stimuli_only.quadrature.len(),
        c.quadrature.len(),
        c.reason
    );
    assert!(
        c.met && c.kind == Kind::Scene && after <= TOL,
        "{}",
        c.reason
    );
    assert!(
        (check.max_de2000 - after).abs() < 1e-9,
        "{check:?} against {after}"
    );
}

/// The ball under maps of their own spectra (spectral EXRs), which the renderer integrates as
/// they stand: each texel is an emission over an equal-energy light at its own luminance, the
/// texels fitted stand for the maps the renderer samples (diffuse and specular as well as raw),
/// and the quadrature is checked on every texel. Before, the FL11 interior gave 1.777 on the
/// image against an estimate of 0.279; with the texels as emissions but without the check on
/// every texel, the FL2 interior gave 0.519 against 0.274.
#[test]
fn a_maps_own_spectra_keep_the_image_within_the_tolerance_and_the_estimate() {
    for name in ["interior_fl11", "interior_fl2"] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(format!("tests/data/truth/{name}.spectral.exr"));
        let (lighting, _) = specmap::render::env::load(&path, "D65").unwrap();
        let s = Preset::Ball.scene(32, 32, "D65", Some(lighting)).unwrap();
        let c = choose(&s, Family::Scene);
        let max = image_error(&s, &c.quadrature);
        eprintln!(
            "{name}: {} nodes, estimate {:.3}, image max {max:.3}",
            c.quadrature.len(),
            c.estimate_de2000
        );
        assert!(
            c.met
                && c.kind == Kind::Scene
                && max <= TOL
                && max <= c.estimate_de2000
                && c.quadrature.len() <= 16,
            "{name}: {} nodes, estimate {:.3}, image {max:.3}",
            c.quadrature.len(),
            c.estimate_de2000
        );
    }
}

fn truth_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/truth")
}

/// The names of the ground-truth maps whose files end in `suffix`, sorted.
fn truth_maps(suffix: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(truth_dir())
        .unwrap()
        .filter_map(|e| {
            let n = e.ok()?.file_name().into_string().ok()?;
            n.strip_suffix(suffix).map(str::to_string)
        })
        .collect();
    names.sort();
    names
}

/// The quadrature chosen at `tol` for `preset` at 32x32 under the RGB rendition of truth map
/// `name` (converted with D65, as `render --env` takes an RGB file), with its image error.
fn under_rgb_map(preset: Preset, name: &str, tol: f64) -> (Selection, f64) {
    let path = truth_dir().join(format!("{name}.rgb.exr"));
    let (lighting, _) = specmap::render::env::load(&path, "D65").unwrap();
    let s = preset.scene(32, 32, "D65", Some(lighting)).unwrap();
    let opts = Options::new(tol).unwrap();
    let c = s
        .choose_quadrature(Observer::Cie1931, RgbSpace::SRGB, Family::Scene, &opts)
        .unwrap();
    let max = image_error(&s, &c.quadrature);
    eprintln!(
        "{preset:?} under {name} (RGB) at {tol}: {} nodes, estimate {:.3}, image max {max:.3}",
        c.quadrature.len(),
        c.estimate_de2000
    );
    (c, max)
}

/// An RGB map is checked on every texel the image can show, as a spectral map is: each texel
/// radiates its own mixture of the paper's basis, and six mixtures stood for the whole map.
/// Before, the ball under the yard's RGB rendition at tolerance 0.1 erred 0.120 on the image
/// against an estimate of 0.044, and the chart at 0.5 erred 0.504 against 0.290. The chart's
/// case (about 5 minutes in the test profile, 2 in release: its refit searches 14 nodes) is in
/// the sweep below, with the ball at 0.5, under all 20 maps.
#[test]
fn an_rgb_maps_texels_keep_the_image_within_the_tolerance_and_the_estimate() {
    let (c, max) = under_rgb_map(Preset::Ball, "yard_overcast", 0.1);
    assert!(
        c.met && c.kind == Kind::Scene && max <= 0.1 && max <= c.estimate_de2000,
        "{} nodes, estimate {:.3}, image {max:.3}",
        c.quadrature.len(),
        c.estimate_de2000
    );
}

/// The RGB rendition of every ground-truth map under the ball (tolerance 0.5 and 0.1) and the
/// chart (0.5), as docs/quadrature.md reports them: each image within the tolerance and the
/// estimate. Run with `cargo test --release --test render_tolerance every_rgb_rendition --
/// --ignored --nocapture`.
#[test]
#[ignore = "a sweep of 20 maps, about 10 minutes in release"]
fn every_rgb_rendition_keeps_the_image_within_the_tolerance_and_the_estimate() {
    let names = truth_maps(".rgb.exr");
    let mut misses = Vec::new();
    for name in &names {
        for (preset, tol) in [
            (Preset::Ball, 0.5),
            (Preset::Ball, 0.1),
            (Preset::Chart, 0.5),
        ] {
            let (c, max) = under_rgb_map(preset, name, tol);
            if !(c.met && max <= tol && max <= c.estimate_de2000) {
                misses.push(format!("{preset:?} under {name} at {tol}: image {max:.3}"));
            }
        }
    }
    assert!(misses.is_empty(), "{misses:?}");
}

/// Every ground-truth spectral map under the ball, as docs/quadrature.md reports it: the image
/// within the tolerance and within the estimate. Run with
/// `cargo test --release --test render_tolerance -- --ignored --nocapture`.
#[test]
#[ignore = "a sweep of 20 maps, about 7 minutes in release"]
fn every_truth_map_keeps_the_image_within_the_tolerance() {
    let dir = truth_dir();
    let names = truth_maps(".spectral.exr");
    let mut misses = Vec::new();
    for name in names {
        let path = dir.join(format!("{name}.spectral.exr"));
        let (lighting, _) = specmap::render::env::load(&path, "D65").unwrap();
        let s = Preset::Ball.scene(32, 32, "D65", Some(lighting)).unwrap();
        let t = std::time::Instant::now();
        let c = choose(&s, Family::Scene);
        let fit = t.elapsed();
        let max = image_error(&s, &c.quadrature);
        eprintln!(
            "{name}: {} nodes, estimate {:.3}, image max {max:.3}, uniform {}, fit {fit:.1?}",
            c.quadrature.len(),
            c.estimate_de2000,
            c.uniform.samples
        );
        eprintln!("  {}", c.reason);
        if !(c.met && max <= TOL && max <= c.estimate_de2000) {
            misses.push(format!("{name}: image {max:.3}"));
        }
    }
    assert!(misses.is_empty(), "{misses:?}");
}

/// A thickness ramp under a spectral map: the cylinders at 48x48 under the FL2 interior, the
/// image within the tolerance and within the estimate (docs/quadrature.md, "What is not
/// done", gives its time). Run with `cargo test --release --test render_tolerance
/// the_cylinders_under_a_spectral_map -- --ignored --nocapture`.
#[test]
#[ignore = "the fit takes about 4 minutes in release"]
fn the_cylinders_under_a_spectral_map_keep_the_image_within_the_estimate() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/truth/interior_fl2.spectral.exr");
    let (lighting, _) = specmap::render::env::load(&path, "D65").unwrap();
    let s = Preset::Cylinders
        .scene(48, 48, "D65", Some(lighting))
        .unwrap();
    let c = choose(&s, Family::Scene);
    let max = image_error(&s, &c.quadrature);
    eprintln!(
        "{} nodes, estimate {:.3}, image max {max:.3}",
        c.quadrature.len(),
        c.estimate_de2000
    );
    assert!(c.met && max <= TOL && max <= c.estimate_de2000);
}
