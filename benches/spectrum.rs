//! Cost of the spectral core: resampling, integration rules and one Eq. 10/11 colour.
//! `cargo bench --bench spectrum`

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use specmap::colorimetry::{Cmfs, Observer};
use specmap::data::{spectrum, Table};
use specmap::spectrum::{Interpolation, Rule, WavelengthGrid};

fn benches(c: &mut Criterion) {
    let grid = WavelengthGrid::visible_1nm();
    let red = spectrum("colorchecker:red").unwrap().data;
    let d65 = Table::builtin("D65").unwrap().single_column().unwrap();
    c.bench_function("resample sprague 10nm->1nm (colorchecker:red)", |b| {
        b.iter(|| black_box(&red).resample(&grid, Interpolation::SMOOTH))
    });
    c.bench_function("resample linear 5nm->1nm (D65)", |b| {
        b.iter(|| black_box(&d65).resample(&grid, Interpolation::LIGHT))
    });
    let cmfs = Cmfs::new(Observer::Cie1931, &grid).unwrap();
    let r = red.resample(&grid, Interpolation::SMOOTH);
    let s = d65.resample(&grid, Interpolation::LIGHT);
    for rule in Rule::ALL {
        c.bench_function(&format!("reflectance XYZ, 401 samples, {rule}"), |b| {
            b.iter(|| {
                cmfs.reflectance_xyz(black_box(&r), black_box(&s), rule)
                    .unwrap()
            })
        });
    }
}

criterion_group!(spectrum_benches, benches);
criterion_main!(spectrum_benches);
