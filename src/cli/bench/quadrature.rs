//! `specmap bench`, quadrature section: every preset under every light and the ball under the
//! repository's two photographs, rendered with the uniform grid and the scene quadrature that
//! `render --tolerance` chooses at each tolerance and with Meyer's rule; per quadrature the node
//! count, the image's error against the 1 nm render (CPU, max and mean CIEDE2000), and the
//! frame time on both backends.

use super::Row;
use specmap::colorimetry::{Observer, RgbSpace};
use specmap::quadrature::choose::Family;
use specmap::quadrature::fit::Options;
use specmap::quadrature::Quadrature;
use specmap::render::gpu::Gpu;
use specmap::render::{sweep, Backend, Preset, Scene};

/// The lights of the table (the chart keeps its own three).
pub(crate) const LIGHTS: [&str; 7] = ["D65", "A", "FL2", "FL11", "hps", "lps", "LED-B3"];
/// The tolerances of the table.
pub(crate) const TOLERANCES: [f64; 2] = [0.5, 0.1];

/// Frames per quadrature: at least 5 rounds, more while a case's frames have taken under two
/// seconds (the short frames, where a slow spell weighs most), at most 40.
const ROUNDS: sweep::Rounds = sweep::Rounds {
    at_least: 5,
    seconds: 2.0,
    at_most: 40,
};

/// The photographs the ball is also lit by (the repository's envmaps/, converted under D65).
pub(crate) const MAPS: [&str; 2] = ["sunrise.exr", "forest.exr"];

/// The cases: (preset, light or map), each image `width` pixels wide.
fn cases(quick: bool) -> Vec<(Preset, &'static str)> {
    if quick {
        return vec![(Preset::Ball, "D65"), (Preset::Ball, "FL2")];
    }
    let mut out = Vec::new();
    let presets = [
        Preset::Ball,
        Preset::TransparentBall,
        Preset::Cylinders,
        Preset::CheckerSpheres,
    ];
    for p in presets {
        out.extend(LIGHTS.iter().map(|&l| (p, l)));
    }
    out.push((Preset::Chart, "D65"));
    out.extend(MAPS.iter().map(|&m| (Preset::Ball, m)));
    out
}

/// The preset under `light`, or lit by the map of that name in envmaps/.
fn scene(preset: Preset, light: &str, width: usize) -> anyhow::Result<Scene> {
    let (w, h) = preset.default_size();
    let lighting = if MAPS.contains(&light) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("envmaps")
            .join(light);
        Some(specmap::render::env::load(&path, "D65")?.0)
    } else {
        None
    };
    Ok(preset.scene(width, width * h / w, light, lighting)?)
}

/// A quadrature to measure, and what it was chosen by.
struct Method {
    setting: String,
    quadrature: Quadrature,
    estimate: Option<f64>,
    note: String,
}

/// The methods of one case: Meyer's rule, then per tolerance the uniform grid and the scene fit.
fn methods(scene: &Scene, quick: bool) -> anyhow::Result<Vec<Method>> {
    let mut out = vec![Method {
        setting: "meyer".into(),
        quadrature: Quadrature::meyer(Observer::Cie1931)?,
        estimate: None,
        note: "Gauss nodes of ybar, interpolatory weights".into(),
    }];
    let tolerances: &[f64] = if quick { &TOLERANCES[..1] } else { &TOLERANCES };
    for &tol in tolerances {
        let s = scene.choose_quadrature(
            Observer::Cie1931,
            RgbSpace::SRGB,
            Family::Scene,
            &Options::new(tol)?,
        )?;
        let u = &s.uniform;
        out.push(Method {
            setting: format!("uniform, tolerance {tol}"),
            quadrature: u.quadrature.clone(),
            estimate: Some(u.estimate_de2000),
            note: format!(
                "{} {}{}",
                u.grid,
                u.rule,
                if u.met { "" } else { "; misses the target" }
            ),
        });
        let f = s.scene.expect("a scene family fits the scene");
        out.push(Method {
            setting: format!("scene, tolerance {tol}"),
            note: format!(
                "{}{}",
                f.quadrature.describe(),
                if f.met { "" } else { "; misses the target" }
            ),
            quadrature: f.quadrature,
            estimate: Some(f.estimate_de2000),
        });
    }
    Ok(out)
}

/// Measures every case.
pub(crate) fn rows(quick: bool, gpu: Option<&Gpu>, cpu: bool) -> anyhow::Result<Vec<Row>> {
    let width = if quick { 24 } else { 96 };
    let rounds = if quick {
        sweep::Rounds {
            at_least: 1,
            seconds: 0.0,
            at_most: 1,
        }
    } else {
        ROUNDS
    };
    let space = RgbSpace::SRGB;
    let mut rows = Vec::new();
    for (preset, light) in cases(quick) {
        let scene = scene(preset, light, width)?;
        let case = match preset {
            Preset::Chart => format!("chart {}x{} (D65, A, lps)", scene.width, scene.height),
            _ => format!(
                "{} {}x{} under {light}",
                preset.name(),
                scene.width,
                scene.height
            ),
        };
        eprintln!("bench: quadratures, {case}");
        let backends: Vec<(Backend, Option<&Gpu>)> = gpu
            .map(|g| (Backend::Gpu, Some(g)))
            .into_iter()
            .chain(cpu.then_some((Backend::Cpu, None)))
            .collect();
        let references = backends
            .iter()
            .map(|&(b, g)| sweep::reference(&scene, Observer::Cie1931, space, b, g))
            .collect::<Result<Vec<_>, _>>()?;
        let methods = methods(&scene, quick)?;
        let qs: Vec<&Quadrature> = methods.iter().map(|m| &m.quadrature).collect();
        // Per backend, every method's frames interleaved (sweep::measure), so that the
        // speed-ups compare frames of the same spells of the machine.
        let measured = backends
            .iter()
            .zip(&references)
            .map(|(&(b, g), reference)| {
                let m = sweep::measure(&scene, &qs, space, b, g, rounds, reference)?;
                Ok((b, m))
            })
            .collect::<anyhow::Result<Vec<_>>>()?;
        for (k, m) in methods.into_iter().enumerate() {
            let on = |b: Backend| measured.iter().find(|(x, _)| *x == b).map(|(_, r)| &r[k]);
            // Errors from the CPU (the f64 reference renderer) when it ran, else the GPU.
            let judge = on(Backend::Cpu).or(on(Backend::Gpu));
            rows.push(Row {
                section: "quadrature",
                case: case.clone(),
                setting: m.setting,
                samples: Some(m.quadrature.len()),
                time: on(Backend::Cpu).map_or(f64::NAN, |r| r.frame_ms),
                time_unit: "ms per frame",
                mean: judge.map(|r| r.comparison.mean),
                max: judge.map(|r| r.comparison.max),
                gpu_ms: on(Backend::Gpu).map(|r| r.frame_ms),
                estimate: m.estimate,
                note: match on(Backend::Gpu).filter(|_| cpu) {
                    Some(g) => format!("{}; GPU image max {:.3}", m.note, g.comparison.max),
                    None => m.note,
                },
            });
        }
    }
    Ok(rows)
}

/// The section's table: per case and method, nodes, estimate, image error, frame times and the
/// speed-up over the uniform grid chosen for the same tolerance.
pub(crate) fn markdown(rows: &[Row]) -> String {
    let mut out = String::from(
        "| case | quadrature | nodes | estimate dE00 | image max dE00 | image mean dE00 | \
         CPU ms | GPU ms | x faster than uniform (CPU, GPU) | note |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---|\n",
    );
    let num = |v: Option<f64>, d: usize| {
        v.filter(|x| x.is_finite())
            .map_or("-".to_string(), |x| format!("{x:.d$}"))
    };
    for r in rows.iter().filter(|r| r.section == "quadrature") {
        let uniform = r.setting.strip_prefix("scene, ").and_then(|tol| {
            rows.iter().find(|u| {
                u.section == "quadrature"
                    && u.case == r.case
                    && u.setting == format!("uniform, {tol}")
            })
        });
        let speedup = uniform.map_or("-".to_string(), |u| {
            let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
                (Some(a), Some(b)) if a.is_finite() && b.is_finite() && b > 0.0 => {
                    format!("{:.1}", a / b)
                }
                _ => "-".into(),
            };
            format!(
                "{}, {}",
                ratio(Some(u.time), Some(r.time)),
                ratio(u.gpu_ms, r.gpu_ms)
            )
        });
        out.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.case,
            r.setting,
            r.samples.map_or("-".into(), |n| n.to_string()),
            num(r.estimate, 3),
            num(r.max, 3),
            num(r.mean, 4),
            num(Some(r.time), 2),
            num(r.gpu_ms, 2),
            speedup,
            r.note
        ));
    }
    out
}
