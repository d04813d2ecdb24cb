//! Paper-mode weights: closed form against argmin (the 3x3 system already built), and a whole
//! fit (colorimetry of the basis, both solves, the exact matrix) per light.
//! `cargo bench --bench fit`

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use specmap::colorimetry::{Observer, RgbSpace};
use specmap::fit::{fit, FitInput, LinearSystem, Mode, Upsampler, PAPER_BASIS};
use specmap::spectrum::{Rule, WavelengthGrid};

fn input(light: &str) -> FitInput {
    FitInput::from_names(
        light,
        PAPER_BASIS,
        &WavelengthGrid::visible_1nm(),
        Observer::Cie1931,
        Rule::Riemann,
        RgbSpace::SRGB,
    )
    .unwrap()
}

fn benches(c: &mut Criterion) {
    for light in ["D65", "lps"] {
        let inp = input(light);
        let system = LinearSystem::new(&inp).unwrap();
        c.bench_function(&format!("weights closed form ({light})"), |b| {
            b.iter(|| black_box(&system).closed_form().unwrap())
        });
        c.bench_function(&format!("weights argmin L-BFGS ({light})"), |b| {
            b.iter(|| black_box(&system).argmin().unwrap())
        });
        c.bench_function(&format!("whole fit, exact mode ({light})"), |b| {
            b.iter(|| fit(black_box(&inp), Mode::Exact).unwrap())
        });
    }
}

/// The nonneg mode's price per colour: inside the cone it is the exact mode's 3x3 product plus a
/// feasibility test; outside, a Nelder-Mead search of the cone's boundary.
fn nonneg(c: &mut Criterion) {
    let f = fit(&input("FL2"), Mode::Nonneg).unwrap();
    let up = Upsampler::new(&f, &RgbSpace::SRGB);
    c.bench_function(
        "nonneg per colour, inside the cone (FL2, 0.6,0.5,0.4)",
        |b| b.iter(|| up.coefficients(black_box([0.6, 0.5, 0.4]))),
    );
    c.bench_function("nonneg per colour, outside the cone (FL2, 1,0,0)", |b| {
        b.iter(|| up.coefficients(black_box([1.0, 0.0, 0.0])))
    });
    let exact = fit(&input("FL2"), Mode::Exact).unwrap();
    let up_exact = Upsampler::new(&exact, &RgbSpace::SRGB);
    c.bench_function("exact per colour (FL2)", |b| {
        b.iter(|| up_exact.coefficients(black_box([1.0, 0.0, 0.0])))
    });
}

criterion_group!(fit_benches, benches, nonneg);
criterion_main!(fit_benches);
