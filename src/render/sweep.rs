//! The speed-for-accuracy curve: one scene rendered at several wavelength counts on one backend,
//! each frame timed and compared (CIEDE2000) with the 1 nm render of the same backend; and the
//! same measurement for any quadrature ([`measure`]).

use super::gpu::Gpu;
use super::prepare::Prepared;
use super::{compare, cpu, Backend, Image, Scene, Spectral};
use crate::error::{Error, Result};
use crate::plot::{self, Figure, Series};
use crate::quadrature::Quadrature;
use std::path::Path;
use std::time::Instant;

/// The reference: 380..780 nm at 1 nm.
pub const REFERENCE_STEP_NM: f64 = 1.0;

/// One wavelength count.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct SweepRow {
    /// Wavelengths rendered, evenly over 380..780 nm.
    pub samples: usize,
    /// Their spacing in nm.
    pub step_nm: f64,
    /// The fastest of the repeats: CPU render, or GPU dispatch until idle.
    pub frame_ms: f64,
    /// GPU only: with upload and readback.
    pub frame_with_transfers_ms: Option<f64>,
    /// Mean CIEDE2000 over the pixels against the 1 nm render.
    #[serde(rename = "mean_dE2000")]
    pub mean_de2000: f64,
    /// Nearest-rank 99th percentile CIEDE2000 against the 1 nm render.
    #[serde(rename = "p99_dE2000")]
    pub p99_de2000: f64,
    /// Largest CIEDE2000 against the 1 nm render.
    #[serde(rename = "max_dE2000")]
    pub max_de2000: f64,
}

/// A measured curve.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SweepReport {
    /// [`Scene::name`].
    pub scene: String,
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// The renderer measured.
    pub backend: Backend,
    /// The GPU adapter's name; None on the CPU.
    pub adapter: Option<String>,
    /// Frames rendered per wavelength count (the fastest is kept).
    pub repeats: usize,
    /// The reference's wavelength step in nm ([`REFERENCE_STEP_NM`]).
    pub reference_step_nm: f64,
    /// Time of the one reference frame in ms, measured as [`SweepRow::frame_ms`].
    pub reference_frame_ms: f64,
    /// One row per wavelength count, in the order asked for.
    pub rows: Vec<SweepRow>,
}

fn frame(
    p: &Prepared,
    backend: Backend,
    gpu: Option<&Gpu>,
    repeats: usize,
) -> Result<(Image, f64, Option<f64>)> {
    let mut best = f64::INFINITY;
    let mut best_total = f64::INFINITY;
    let mut img = None;
    for _ in 0..repeats.max(1) {
        match backend {
            Backend::Cpu => {
                let t = Instant::now();
                let i = cpu::render(p);
                best = best.min(t.elapsed().as_secs_f64());
                img = Some(i);
            }
            Backend::Gpu => {
                let g = gpu.ok_or_else(|| Error::invalid("the GPU sweep needs a GPU"))?;
                let (i, t) = g.render(p)?;
                best = best.min(t.compute_s);
                best_total = best_total.min(t.upload_s + t.compute_s + t.readback_s);
                img = Some(i);
            }
        }
    }
    let img = img.expect("at least one repeat");
    Ok((
        img,
        best * 1e3,
        (backend == Backend::Gpu).then_some(best_total * 1e3),
    ))
}

/// Renders `scene` at each count of `samples` (wavelengths over 380..780 nm) and at 1 nm.
pub fn sweep(
    scene: &Scene,
    base: &Spectral,
    samples: &[usize],
    backend: Backend,
    gpu: Option<&Gpu>,
    repeats: usize,
) -> Result<SweepReport> {
    let reference = Spectral {
        grid: Spectral::step(REFERENCE_STEP_NM)?.grid,
        ..*base
    };
    let p = Prepared::new(scene, &reference)?;
    let (ref_img, ref_ms, _) = frame(&p, backend, gpu, 1)?;
    let mut rows = Vec::new();
    for &n in samples {
        let sp = Spectral {
            grid: Spectral::samples(n)?.grid,
            ..*base
        };
        let p = Prepared::new(scene, &sp)?;
        let (img, ms, total) = frame(&p, backend, gpu, repeats)?;
        let c = compare(&ref_img, &img, &base.space)?;
        rows.push(SweepRow {
            samples: n,
            step_nm: sp.grid.step_nm(),
            frame_ms: ms,
            frame_with_transfers_ms: total,
            mean_de2000: c.mean,
            p99_de2000: c.p99,
            max_de2000: c.max,
        });
    }
    Ok(SweepReport {
        scene: scene.name.clone(),
        width: scene.width,
        height: scene.height,
        backend,
        adapter: gpu
            .filter(|_| backend == Backend::Gpu)
            .map(|g| g.adapter().name),
        repeats,
        reference_step_nm: REFERENCE_STEP_NM,
        reference_frame_ms: ref_ms,
        rows,
    })
}

/// One quadrature rendered on one backend: the fastest frame and the image's error against a
/// reference render.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Measured {
    /// The fastest frame in ms: CPU render, or GPU dispatch until idle.
    pub frame_ms: f64,
    /// GPU only: with upload and readback.
    pub frame_with_transfers_ms: Option<f64>,
    /// The last frame's image against the reference.
    pub comparison: super::Comparison,
}

/// The scene rendered at 1 nm by Simpson's rule on `backend`: what [`measure`] compares with.
pub fn reference(
    scene: &Scene,
    observer: crate::colorimetry::Observer,
    space: crate::colorimetry::RgbSpace,
    backend: Backend,
    gpu: Option<&Gpu>,
) -> Result<Image> {
    let grid = crate::spectrum::WavelengthGrid::new(380.0, 780.0, REFERENCE_STEP_NM)?;
    let q = Quadrature::uniform(grid, crate::spectrum::Rule::Simpson, observer)?;
    Ok(frame(
        &Prepared::with_quadrature(scene, &q, space)?,
        backend,
        gpu,
        1,
    )?
    .0)
}

/// How many frames [`measure`] renders of each quadrature: rounds of one frame each, at
/// least `at_least`, then more until `seconds` have passed, at most `at_most`.
#[derive(Debug, Clone, Copy)]
pub struct Rounds {
    /// Rounds always rendered (at least 1).
    pub at_least: usize,
    /// Seconds from the start after which no round beyond `at_least` begins.
    pub seconds: f64,
    /// Most rounds, unless `at_least` is more.
    pub at_most: usize,
}

/// Renders `scene` with each of `qs` on `backend` and compares each image with `reference` in
/// `space`. The frame times are to be compared: each round renders one frame of each in turn,
/// so a slow spell of the machine (frames here scatter by tens of percent) slows them all alike
/// rather than whichever happened to run then; each keeps its fastest frame.
pub fn measure(
    scene: &Scene,
    qs: &[&Quadrature],
    space: crate::colorimetry::RgbSpace,
    backend: Backend,
    gpu: Option<&Gpu>,
    rounds: Rounds,
    reference: &Image,
) -> Result<Vec<Measured>> {
    let prepared = qs
        .iter()
        .map(|q| Prepared::with_quadrature(scene, q, space))
        .collect::<Result<Vec<_>>>()?;
    let mut best = vec![(f64::INFINITY, None::<f64>, None::<Image>); qs.len()];
    let start = Instant::now();
    let mut done = 0;
    while done < rounds.at_least.max(1)
        || (done < rounds.at_most && start.elapsed().as_secs_f64() < rounds.seconds)
    {
        for (p, b) in prepared.iter().zip(&mut best) {
            let (img, ms, total) = frame(p, backend, gpu, 1)?;
            b.0 = b.0.min(ms);
            b.1 = total.map(|t| b.1.map_or(t, |x: f64| x.min(t)));
            b.2 = Some(img);
        }
        done += 1;
    }
    best.into_iter()
        .map(|(frame_ms, frame_with_transfers_ms, img)| {
            let img = img.expect("at least one round");
            Ok(Measured {
                frame_ms,
                frame_with_transfers_ms,
                comparison: compare(reference, &img, &space)?,
            })
        })
        .collect()
}

/// A markdown table of one or more curves.
pub fn markdown(reports: &[SweepReport]) -> String {
    let mut s = String::from(
        "| backend | adapter | wavelengths | step (nm) | frame (ms) | mean dE2000 | p99 dE2000 | max dE2000 |\n\
         |---|---|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in reports {
        for row in &r.rows {
            s.push_str(&format!(
                "| {} | {} | {} | {:.3} | {:.1} | {:.3} | {:.3} | {:.3} |\n",
                r.backend,
                r.adapter.as_deref().unwrap_or("-"),
                row.samples,
                row.step_nm,
                row.frame_ms,
                row.mean_de2000,
                row.p99_de2000,
                row.max_de2000
            ));
        }
    }
    s
}

/// Mean CIEDE2000 against frame time, one curve per report (PNG or SVG by extension).
pub fn plot(reports: &[SweepReport], path: &Path) -> Result<()> {
    let series = reports
        .iter()
        .enumerate()
        .map(|(i, r)| Series {
            label: format!(
                "{} {}",
                r.backend,
                r.adapter
                    .as_deref()
                    .map(|a| format!("({a})"))
                    .unwrap_or_default()
            ),
            points: r
                .rows
                .iter()
                .map(|row| (row.frame_ms.max(1e-3).log10(), row.mean_de2000))
                .collect(),
            color: plot::palette(i),
        })
        .collect();
    let r0 = reports
        .first()
        .ok_or_else(|| Error::invalid("no sweep to plot"))?;
    plot::write(
        &Figure {
            title: format!(
                "{} {}x{}: colour error vs frame time (points: {} wavelengths)",
                r0.scene,
                r0.width,
                r0.height,
                r0.rows
                    .iter()
                    .map(|r| r.samples.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            x_label: "log10 frame time (ms)".into(),
            y_label: "mean CIEDE2000 vs the 1 nm render".into(),
            series,
        },
        path,
    )
}
