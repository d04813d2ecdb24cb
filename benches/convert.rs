//! Conversion throughput: envmaps/sunrise.exr (1024x512) to 81 bands, half, ZIP, in exact and
//! faithful modes, in input pixels per second; and the ZIP block encoder alone (OpenEXR's
//! predictor + libdeflate at level 4 and 1) in bytes per second. The comparison with Python is
//! `tools/bench_convert.py`; this bench keeps the measurement behind this crate's own
//! optimisations (`cargo bench --bench convert`).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use specmap::envmap::convert::{convert, ConvertOptions, LightSpec};
use specmap::envmap::zip::ZipEncoder;
use specmap::fit::Mode;
use std::path::Path;
use std::time::Duration;

fn bench(c: &mut Criterion) {
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("envmaps/sunrise.exr");
    let input = input.to_str().expect("a UTF-8 path").to_string();
    let dir = tempfile::tempdir().expect("a temporary folder");
    let out = dir.path().join("out.exr");
    let mut g = c.benchmark_group("convert sunrise 1024x512 81 bands half zip");
    g.sample_size(10).measurement_time(Duration::from_secs(10));
    g.throughput(Throughput::Elements(1024 * 512));
    for (name, opts) in [
        (
            "exact",
            ConvertOptions {
                mode: Mode::Exact,
                light: LightSpec::Named("D65".into()),
                sun: None,
                ..ConvertOptions::default()
            },
        ),
        ("faithful", ConvertOptions::faithful()),
    ] {
        g.bench_with_input(BenchmarkId::from_parameter(name), &opts, |b, opts| {
            b.iter(|| convert(&input, &out, opts, &|_, _| {}).expect("converts"))
        });
    }
    g.finish();

    // One 16-line block of 81 bands + 4 channels at 1024 wide, as the writer hands it over: a
    // smooth spectrum per pixel, in half floats.
    let raw: Vec<u8> = (0..16 * 1024 * 85)
        .flat_map(|i: usize| {
            let (band, x) = ((i / 1024) % 85, i % 1024);
            let v = 0.2 + 0.5 * ((band as f32) * 0.05 + (x as f32) * 0.01).sin().abs();
            half::f16::from_f32(v).to_le_bytes()
        })
        .collect();
    let mut g = c.benchmark_group("zip block 16 lines x 1024 x 85 half");
    g.sample_size(20).measurement_time(Duration::from_secs(3));
    g.throughput(Throughput::Bytes(raw.len() as u64));
    for level in [4u8, 1] {
        let mut enc = ZipEncoder::new(level);
        g.bench_with_input(BenchmarkId::new("level", level), &raw, |b, raw| {
            b.iter(|| enc.encode(raw))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
