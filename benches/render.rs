//! Frame time against wavelength count: the ball preset (Fig. 6, a one-layer film per pixel and
//! wavelength) at 128x128 on the CPU renderer and, where a wgpu adapter exists, on the GPU
//! (compute dispatch until idle, without upload and readback).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use specmap::render::gpu::Gpu;
use specmap::render::prepare::Prepared;
use specmap::render::{cpu, Preset, Spectral};
use std::time::Duration;

const COUNTS: [usize; 6] = [4, 9, 17, 34, 81, 340];

fn bench(c: &mut Criterion) {
    let scene = Preset::Ball.scene(128, 128, "D65", None).expect("preset");
    let frames: Vec<(usize, Prepared)> = COUNTS
        .iter()
        .map(|&n| {
            let sp = Spectral::samples(n).expect("grid");
            (n, Prepared::new(&scene, &sp).expect("prepared"))
        })
        .collect();
    let mut g = c.benchmark_group("render ball 128x128 cpu");
    g.sample_size(10).measurement_time(Duration::from_secs(3));
    for (n, p) in &frames {
        g.bench_with_input(BenchmarkId::from_parameter(n), p, |b, p| {
            b.iter(|| cpu::render(p))
        });
    }
    g.finish();
    match Gpu::new() {
        Ok(gpu) => {
            let name = format!("render ball 128x128 gpu ({})", gpu.adapter().name);
            let mut g = c.benchmark_group(name);
            g.sample_size(10).measurement_time(Duration::from_secs(3));
            for (n, p) in &frames {
                g.bench_with_input(BenchmarkId::from_parameter(n), p, |b, p| {
                    b.iter_custom(|iters| {
                        let mut total = Duration::ZERO;
                        for _ in 0..iters {
                            let (_, t) = gpu.render(p).expect("GPU render");
                            total += Duration::from_secs_f64(t.compute_s);
                        }
                        total
                    })
                });
            }
            g.finish();
        }
        Err(e) => eprintln!("notice: no GPU benchmark: {e}"),
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
