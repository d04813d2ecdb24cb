//! What `render --tolerance 0.5` spends choosing its wavelengths (the scene fit and, under a
//! photograph, the check on every texel), before any frame: the transparent ball under D65, the
//! chart under its three lights, and the ball under the forest photograph (converted under
//! D65), each 48 pixels wide; then the cylinders' thickness ramp under D65, whose 1 167 fitted
//! stimuli at 401 wavelengths outgrow the caches (half a minute a fit, so that group alone
//! takes some six minutes). The least squares' inner loops
//! (gathering a node set's columns, the CIEDE2000 of every stimulus) are what this measures.
//! `cargo bench --bench choose`

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use specmap::colorimetry::{Observer, RgbSpace};
use specmap::quadrature::choose::Family;
use specmap::quadrature::fit::Options;
use specmap::render::{Preset, Scene};
use std::time::Duration;

fn scene(preset: Preset, light: &str) -> Scene {
    let (w, h) = preset.default_size();
    let map = light.ends_with(".exr").then(|| {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("envmaps")
            .join(light);
        specmap::render::env::load(&path, "D65").expect("map").0
    });
    let light = if map.is_some() { "D65" } else { light };
    preset.scene(48, 48 * h / w, light, map).expect("preset")
}

fn choose(c: &mut Criterion) {
    let mut g = c.benchmark_group("choose, tolerance 0.5");
    g.sample_size(10).measurement_time(Duration::from_secs(30));
    let cases = [
        (Preset::TransparentBall, "D65"),
        (Preset::Chart, "D65"),
        (Preset::Ball, "forest.exr"),
    ];
    let opts = Options::new(0.5).expect("tolerance");
    for (preset, light) in cases {
        let s = scene(preset, light);
        let id = format!("{} under {light}", preset.name());
        g.bench_with_input(BenchmarkId::from_parameter(id), &s, |b, s| {
            b.iter(|| {
                s.choose_quadrature(Observer::Cie1931, RgbSpace::SRGB, Family::Scene, &opts)
                    .expect("a choice")
            })
        });
    }
    g.finish();
    // `cargo test` runs each bench once in the test profile, where this one fit takes minutes.
    if !benchmarking() {
        eprintln!("choose: the cylinders' group runs under `cargo bench` only");
        return;
    }
    let mut g = c.benchmark_group("choose, tolerance 0.5, thickness ramp");
    g.sample_size(10).measurement_time(Duration::from_secs(360));
    let s = scene(Preset::Cylinders, "D65");
    g.bench_function("cylinders under D65", |b| {
        b.iter(|| {
            s.choose_quadrature(Observer::Cie1931, RgbSpace::SRGB, Family::Scene, &opts)
                .expect("a choice")
        })
    });
    g.finish();
}

/// Whether criterion measures (`cargo bench` passes `--bench`) rather than runs each bench once
/// as a test (`cargo test`, or `cargo bench -- --test`), as criterion itself decides.
fn benchmarking() -> bool {
    let has = |flag: &str| std::env::args().any(|a| a == flag);
    has("--bench") && !has("--test")
}

criterion_group!(benches, choose);
criterion_main!(benches);
