//! Frame time against wavelength count: the ball preset (Fig. 6, a one-layer film per pixel and
//! wavelength) at 128x128 on the CPU renderer and, where a wgpu adapter exists, on the GPU
//! (compute dispatch until idle, without upload and readback). Then the quadratures
//! `render --tolerance 0.5` chooses for the ball under D65 and FL2 (the scene's and the uniform
//! grid at its best rule) and Meyer's, the same way. Last, the checker spheres (24 matte
//! spheres) at 384x256 under A on uniform grids of 2, 6, 21 and 41 wavelengths: a matte pixel
//! costs little per wavelength, so these frames show what a pixel costs once (its hit, normal,
//! lookups and RGB), which bounds how much faster fewer wavelengths can render.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use specmap::colorimetry::{Observer, RgbSpace};
use specmap::quadrature::choose::Family;
use specmap::quadrature::fit::Options;
use specmap::quadrature::Quadrature;
use specmap::render::gpu::Gpu;
use specmap::render::prepare::Prepared;
use specmap::render::{cpu, Preset, Spectral};
use std::time::Duration;

const COUNTS: [usize; 6] = [4, 9, 17, 34, 81, 340];

/// One group of CPU frames.
fn cpu_group<N: std::fmt::Display>(c: &mut Criterion, name: &str, frames: &[(N, Prepared)]) {
    let mut g = c.benchmark_group(name);
    g.sample_size(10).measurement_time(Duration::from_secs(3));
    for (n, p) in frames {
        g.bench_with_input(BenchmarkId::from_parameter(n), p, |b, p| {
            b.iter(|| cpu::render(p))
        });
    }
    g.finish();
}

/// One group of GPU frames (the compute dispatch until idle).
fn gpu_group<N: std::fmt::Display>(
    c: &mut Criterion,
    gpu: &Gpu,
    name: &str,
    frames: &[(N, Prepared)],
) {
    let mut g = c.benchmark_group(format!("{name} ({})", gpu.adapter().name));
    g.sample_size(10).measurement_time(Duration::from_secs(3));
    for (n, p) in frames {
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

/// `scene`'s frames on uniform grids of each of `counts` wavelengths.
fn uniform_frames(scene: &specmap::render::Scene, counts: &[usize]) -> Vec<(usize, Prepared)> {
    counts
        .iter()
        .map(|&n| {
            let sp = Spectral::samples(n).expect("grid");
            (n, Prepared::new(scene, &sp).expect("prepared"))
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let scene = Preset::Ball.scene(128, 128, "D65", None).expect("preset");
    let frames = uniform_frames(&scene, &COUNTS);
    cpu_group(c, "render ball 128x128 cpu", &frames);
    match Gpu::new() {
        Ok(gpu) => gpu_group(c, &gpu, "render ball 128x128 gpu", &frames),
        Err(e) => eprintln!("notice: no GPU benchmark: {e}"),
    }
}

/// The frames of the quadratures chosen for `light` at tolerance 0.5, and Meyer's.
fn quadrature_frames(light: &str) -> Vec<(String, Prepared)> {
    let scene = Preset::Ball.scene(128, 128, light, None).expect("preset");
    let opts = Options::new(0.5).expect("tolerance");
    let s = scene
        .choose_quadrature(Observer::Cie1931, RgbSpace::SRGB, Family::Scene, &opts)
        .expect("a quadrature");
    let scene_fit = s.scene.expect("the scene fit").quadrature;
    let meyer = Quadrature::meyer(Observer::Cie1931).expect("Meyer's rule");
    [
        ("uniform", s.uniform.quadrature),
        ("scene", scene_fit),
        ("meyer", meyer),
    ]
    .into_iter()
    .map(|(kind, q)| {
        let p = Prepared::with_quadrature(&scene, &q, RgbSpace::SRGB).expect("prepared");
        (format!("{light} {kind} {}", q.len()), p)
    })
    .collect()
}

fn quadratures(c: &mut Criterion) {
    let frames: Vec<(String, Prepared)> = ["D65", "FL2"]
        .iter()
        .flat_map(|l| quadrature_frames(l))
        .collect();
    let name = "render ball 128x128 quadrature (tolerance 0.5)";
    cpu_group(c, &format!("{name} cpu"), &frames);
    if let Ok(gpu) = Gpu::new() {
        gpu_group(c, &gpu, &format!("{name} gpu"), &frames);
    }
}

fn matte(c: &mut Criterion) {
    let scene = Preset::CheckerSpheres
        .scene(384, 256, "A", None)
        .expect("preset");
    let frames = uniform_frames(&scene, &[2, 6, 21, 41]);
    cpu_group(c, "render checker-spheres 384x256 cpu", &frames);
    if let Ok(gpu) = Gpu::new() {
        gpu_group(c, &gpu, "render checker-spheres 384x256 gpu", &frames);
    }
}

criterion_group!(benches, bench, quadratures, matte);
criterion_main!(benches);
