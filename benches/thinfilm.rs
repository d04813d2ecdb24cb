//! Thin-film reflectance evaluations per second (wavelength x angle), 1 and 3 layers, f32 and f64.
//! `cargo bench --bench thinfilm`
//!
//! Each iteration evaluates unpolarised R and T (s and p) on 380:780:1 nm (401 wavelengths) x 90
//! angles (0..89 degrees), 36,090 evaluations, with the optical constants of each wavelength
//! prepared once per wavelength (as a GPU would read them from a table).

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use specmap::spectrum::WavelengthGrid;
use specmap::thinfilm::{Film, Incidence, Index, Layer, Material, Polarization, Real, Stack};

fn stack(layers: &[(f64, f64)]) -> Stack {
    let m = |n: f64| Material::Constant(Index::real(n).unwrap());
    Stack::new(
        m(1.0),
        layers
            .iter()
            .map(|&(n, d)| Layer::new(m(n), d).unwrap())
            .collect(),
        m(1.45),
    )
}

fn films<T: Real>(stack: &Stack, grid: &WavelengthGrid) -> Vec<Film<T>> {
    grid.wavelengths_nm()
        .map(|w| stack.at::<T>(w).unwrap())
        .collect()
}

fn sweep<T: Real>(films: &[Film<T>], angles: &[Incidence]) -> T {
    let mut sum = T::zero();
    for f in films {
        for a in angles {
            sum += f.rt(a, Polarization::Unpolarized).r;
        }
    }
    sum
}

fn benches(c: &mut Criterion) {
    let grid = WavelengthGrid::visible_1nm();
    let angles: Vec<Incidence> = (0..90)
        .map(|a| Incidence::degrees(a as f64).unwrap())
        .collect();
    let one = stack(&[(2.7, 270.0)]);
    let three = stack(&[(1.38, 95.0), (2.1, 130.0), (1.46, 80.0)]);
    let mut g = c.benchmark_group("thinfilm R+T unpolarised, 401 wavelengths x 90 angles");
    g.throughput(Throughput::Elements((grid.len() * angles.len()) as u64));
    for (name, s) in [("1 layer", &one), ("3 layers", &three)] {
        let f64s = films::<f64>(s, &grid);
        let f32s = films::<f32>(s, &grid);
        g.bench_function(format!("{name}, f64"), |b| {
            b.iter(|| sweep(black_box(&f64s), black_box(&angles)))
        });
        g.bench_function(format!("{name}, f32"), |b| {
            b.iter(|| sweep(black_box(&f32s), black_box(&angles)))
        });
    }
    g.finish();
}

criterion_group!(thinfilm_benches, benches);
criterion_main!(thinfilm_benches);
