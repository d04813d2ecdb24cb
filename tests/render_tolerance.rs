//! `render --tolerance`: the grid chosen from the scene's stimuli (lights, pigments, films) gives
//! a render whose colours stay within the tolerance of the 1 nm render, measured on the image.

use specmap::colorimetry::Observer;
use specmap::render::{compare, Preset, Spectral};
use specmap::spectrum::Rule;
use specmap::tradeoff::choose_grid;

const TOL: f64 = 0.5;

fn check(preset: Preset, w: usize, h: usize) -> f64 {
    let scene = preset.scene(w, h, "D65", None).unwrap();
    let choice = choose_grid(
        &scene.stimuli().unwrap(),
        Observer::Cie1931,
        380.0,
        780.0,
        Rule::Riemann,
        TOL,
    )
    .unwrap();
    assert!(choice.met, "{preset:?}: {choice:?}");
    let chosen = Spectral {
        grid: choice.chosen,
        ..Spectral::default()
    };
    let reference = Spectral {
        grid: "380:780:1".parse().unwrap(),
        rule: Rule::Simpson,
        ..Spectral::default()
    };
    let a = scene.render_cpu(&chosen).unwrap();
    let b = scene.render_cpu(&reference).unwrap();
    let c = compare(&a, &b, &chosen.space).unwrap();
    // The estimate bounds the stimuli; the image mixes them (environment, sun, films at every
    // angle), so its mean must be within the tolerance and no pixel far beyond it.
    assert!(
        c.mean <= TOL,
        "{preset:?} at {} nm: mean {}",
        choice.step_nm,
        c.mean
    );
    assert!(
        c.max <= 2.0 * TOL,
        "{preset:?} at {} nm: max {}",
        choice.step_nm,
        c.max
    );
    choice.step_nm
}

#[test]
fn chosen_grids_keep_every_preset_within_the_tolerance() {
    let ball = check(Preset::Ball, 24, 24);
    check(Preset::TransparentBall, 32, 16);
    check(Preset::Cylinders, 24, 24);
    let chart = check(Preset::Chart, 48, 32);
    // The chart's low-pressure sodium row needs a finer grid than the ball under D65.
    assert!(chart < ball, "chart {chart} nm, ball {ball} nm");
}
