//! `--tolerance` on the command line: which quadrature `render` draws with, and what it
//! reports. The scene's choice runs through [`specmap::render::plan`] (the cache, the uniform
//! grid, the cost, the fit within its budget), with a spinner saying which stage it is at.

use super::outln;
use super::render_args::{QuadratureArg, RenderArgs};
use specmap::colorimetry::RgbSpace;
use specmap::quadrature::cache::Cache;
use specmap::quadrature::choose::{Family, Selection};
use specmap::quadrature::fit::Options;
use specmap::quadrature::progress::Stage;
use specmap::quadrature::Quadrature;
use specmap::render::gpu::Gpu;
use specmap::render::plan::{Aim, FitBudget, Plan, Source, Workload};
use specmap::render::prepare::Prepared;
use specmap::render::{cpu, Scene, Spectral};
use std::io::IsTerminal;
use std::time::Instant;

/// What the quadrature is chosen for: the renderer that will draw (None: the CPU), how many
/// frames, and the first of them (a frame's cost is measured on it).
pub(crate) struct Serving<'a> {
    pub(crate) gpu: Option<&'a Gpu>,
    pub(crate) frames: usize,
    pub(crate) first: &'a Scene,
}

/// The quadrature chosen, what `--tolerance` chose (and how, when it planned), and the first
/// frame prepared on it where measuring its cost did that already (on the CPU, when the plan
/// keeps the uniform grid it measured).
pub(crate) struct Chosen {
    pub(crate) quadrature: Quadrature,
    pub(crate) selection: Option<Selection>,
    pub(crate) plan: Option<Plan>,
    pub(crate) prepared: Option<Prepared>,
}

/// The quadrature of `--quadrature`, `--tolerance` (and `--max-nodes`, `--fit-budget`),
/// `--step`/`--samples` and `--rule` for `scene`.
pub(crate) fn quadrature_for(
    scene: &Scene,
    spectral: &Spectral,
    a: &RenderArgs,
    serving: &Serving,
) -> anyhow::Result<Chosen> {
    let kind = a.quadrature;
    let fixed = |quadrature| Chosen {
        quadrature,
        selection: None,
        plan: None,
        prepared: None,
    };
    let Some(tolerance) = a.tolerance else {
        return Ok(match kind {
            Some(QuadratureArg::Scene) => anyhow::bail!(
                "--quadrature scene fits the wavelengths to a colour tolerance: give --tolerance \
                 (e.g. --tolerance 0.5)"
            ),
            Some(QuadratureArg::Meyer) => fixed(Quadrature::meyer(spectral.observer)?),
            Some(QuadratureArg::Uniform) | None => fixed(Quadrature::uniform(
                spectral.grid,
                spectral.rule,
                spectral.observer,
            )?),
        });
    };
    let opts = tolerance_options(tolerance, a.max_nodes, kind)?;
    let budget = match (a.fit_budget, kind) {
        (Some(s), _) if !(s.is_finite() && s >= 0.0) => {
            anyhow::bail!("--fit-budget {s}: seconds must be a number of at least 0")
        }
        (Some(s), _) => FitBudget::Seconds(s),
        (None, Some(QuadratureArg::Scene)) => FitBudget::Unlimited,
        (None, _) => FitBudget::Auto,
    };
    let spinner = Spinner::new(match a.max_nodes {
        Some(n) => format!("at most {n} wavelengths for CIEDE2000 {tolerance}"),
        None => format!("wavelengths for CIEDE2000 {tolerance}"),
    });
    let report = |stage: &Stage| spinner.stage(stage);
    let chosen = match kind {
        Some(QuadratureArg::Meyer) => anyhow::bail!(
            "--quadrature meyer has four fixed wavelengths: it cannot follow --tolerance"
        ),
        Some(QuadratureArg::Uniform) => {
            let s = scene.choose_quadrature_reporting(
                spectral.observer,
                spectral.space,
                Family::Uniform,
                &opts,
                &report,
            )?;
            Chosen {
                quadrature: s.quadrature.clone(),
                selection: Some(s),
                plan: None,
                prepared: None,
            }
        }
        Some(QuadratureArg::Scene) | None => {
            let cache = user_cache(a.no_cache);
            let aim = aim(spectral, opts, budget, cache.as_ref());
            planned(scene, &aim, spectral.space, serving, &report)?
        }
    };
    Ok(chosen)
}

/// The plan's choice for `scene` at `aim`, each frame's cost measured on `serving`'s first
/// frame in `space`, and that frame prepared where the plan keeps the grid it measured.
fn planned(
    scene: &Scene,
    aim: &Aim,
    space: RgbSpace,
    serving: &Serving,
    report: specmap::quadrature::progress::Report,
) -> anyhow::Result<Chosen> {
    let kept = std::cell::RefCell::new(None);
    let frame_s = |q: &Quadrature| {
        let (seconds, prepared) = frame_seconds(serving.first, q, space, serving.gpu)?;
        *kept.borrow_mut() = prepared.map(|p| (q.clone(), p));
        Ok(seconds)
    };
    let work = Workload {
        frames: serving.frames,
        frame_s: &frame_s,
    };
    let p = scene.plan_quadrature(aim, &work, report)?;
    if let Some(note) = &p.plan.cache_note {
        eprintln!("note: quadrature cache: {note}");
    }
    let prepared = kept
        .take()
        .filter(|(q, _)| *q == p.selection.quadrature)
        .map(|(_, prepared)| prepared);
    Ok(Chosen {
        quadrature: p.selection.quadrature.clone(),
        selection: Some(p.selection),
        plan: Some(p.plan),
        prepared,
    })
}

/// The user's quadrature cache, unless `--no-cache`.
pub(crate) fn user_cache(no_cache: bool) -> Option<Cache> {
    (!no_cache).then(Cache::in_user_folder).flatten()
}

/// What the plan aims at: `spectral`'s observer and space, `opts`, the fit's `budget`, `cache`.
pub(crate) fn aim<'a>(
    spectral: &Spectral,
    opts: Options,
    budget: FitBudget,
    cache: Option<&'a Cache>,
) -> Aim<'a> {
    Aim {
        observer: spectral.observer,
        space: spectral.space,
        opts,
        budget,
        cache,
    }
}

/// A spinner on a terminal saying what the choice is doing, stage by stage (a scene's fit
/// takes seconds, minutes for a thickness ramp under a photograph); nothing elsewhere.
struct Spinner {
    doing: String,
    bar: Option<indicatif::ProgressBar>,
}

impl Spinner {
    fn new(doing: String) -> Spinner {
        let bar = std::io::stderr().is_terminal().then(|| {
            let b = indicatif::ProgressBar::new_spinner();
            if let Ok(style) =
                indicatif::ProgressStyle::with_template("{spinner} {msg} [{elapsed}]")
            {
                b.set_style(style);
            }
            b.set_message(doing.clone());
            b.enable_steady_tick(std::time::Duration::from_millis(120));
            b
        });
        Spinner { doing, bar }
    }

    fn stage(&self, stage: &Stage) {
        if let Some(b) = &self.bar {
            b.set_message(format!("{}: {stage}", self.doing));
        }
    }
}

impl Drop for Spinner {
    fn drop(&mut self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

/// Seconds to prepare and draw one frame of `scene` on `q`, measured on a sample: on the CPU,
/// rows spread over the image, about [`CPU_SAMPLE`] pixels; on the GPU, the image at a quarter
/// of its width and height. The draw's time is scaled up by the pixels left out. On the CPU the
/// frame prepared is returned too (drawn on `q` after all, it is not prepared twice).
fn frame_seconds(
    scene: &Scene,
    q: &Quadrature,
    space: RgbSpace,
    gpu: Option<&Gpu>,
) -> specmap::error::Result<(f64, Option<Prepared>)> {
    let pixels = (scene.width * scene.height) as f64;
    let t0 = Instant::now();
    match gpu {
        None => {
            let p = Prepared::with_quadrature(scene, q, space)?;
            let prepare_s = t0.elapsed().as_secs_f64();
            // Whole rows: the renderer draws a row's pixels one after another, and a lattice of
            // single pixels costs 2-3 times as much each (the ball at 256x256).
            let rows = (CPU_SAMPLE / scene.width).clamp(1, scene.height);
            let step = scene.height / rows;
            let at: Vec<[usize; 2]> = (step / 2..scene.height)
                .step_by(step)
                .flat_map(|y| (0..scene.width).map(move |x| [x, y]))
                .collect();
            // A first row warms the threads and caches up; the sample is timed after it.
            cpu::render_pixels(&p, &at[..scene.width.min(at.len())]);
            let t1 = Instant::now();
            cpu::render_pixels(&p, &at);
            let draw_s = t1.elapsed().as_secs_f64();
            Ok((
                prepare_s + draw_s * pixels / at.len().max(1) as f64,
                Some(p),
            ))
        }
        Some(g) => {
            let mut small = scene.clone();
            small.width = (scene.width / 4).max(1);
            small.height = (scene.height / 4).max(1);
            let p = Prepared::with_quadrature(&small, q, space)?;
            let prepare_s = t0.elapsed().as_secs_f64();
            let t1 = Instant::now();
            g.render(&p)?;
            let draw_s = t1.elapsed().as_secs_f64();
            let s = prepare_s + draw_s * pixels / (small.width * small.height) as f64;
            Ok((s, None))
        }
    }
}

/// The CPU's sample for [`frame_seconds`]: about this many pixels (fewer leave the threads
/// idle; a 512x512 image is sampled on every 64th row).
const CPU_SAMPLE: usize = 4096;

/// The fit's options for `--tolerance` and `--max-nodes`: a budget bounds the scene's
/// quadrature, not a uniform grid (whose count `--samples` sets).
pub(crate) fn tolerance_options(
    tolerance: f64,
    budget: Option<usize>,
    kind: Option<QuadratureArg>,
) -> anyhow::Result<Options> {
    Ok(match budget {
        None => Options::new(tolerance)?,
        Some(0) => anyhow::bail!("--max-nodes 0: a quadrature needs at least 1 wavelength"),
        Some(_) if kind == Some(QuadratureArg::Uniform) => anyhow::bail!(
            "--max-nodes bounds the scene's quadrature, not --quadrature uniform (a uniform \
             grid of N wavelengths is --samples N, without --tolerance)"
        ),
        Some(n) => Options::with_budget(tolerance, n)?,
    })
}

/// Appends what `--tolerance` chose, and why.
pub(crate) fn write_selection(out: &mut String, s: &Selection) {
    outln!(
        out,
        "  quadrature   {}: estimate {:.3} {} target {:.3} (tolerance {} x margin {:.2}{}); {}",
        s.kind,
        s.estimate_de2000,
        if s.met { "<=" } else { "MISSES the" },
        s.target_de2000,
        s.tolerance_de2000,
        s.target_de2000 / s.tolerance_de2000,
        s.budget
            .map_or(String::new(), |b| format!(", at most {b} nodes")),
        s.reason
    );
    if let Some(f) = &s.scene {
        outln!(
            out,
            "               scene fit: {} stimuli fitted, {} held out (max {:.3}, mean {:.3}); \
             nodes on lines at {:?} nm; largest error: {}",
            f.stimuli,
            f.held_out,
            f.held_out_max,
            f.held_out_mean,
            f.lines_nm,
            f.worst
        );
    }
    if let Some(c) = &s.image {
        outln!(
            out,
            "               image: max {:.3} (pixel {}, {}), mean {:.3} against the 1 nm render, \
             on {}",
            c.max_de2000,
            c.max_at[0],
            c.max_at[1],
            c.mean_de2000,
            c.lattice()
        );
    }
    if !s.stages.is_empty() {
        outln!(
            out,
            "               {} in {:.1} s: {}",
            if s.from_cache.is_some() {
                "fitted (when stored)"
            } else {
                "chosen"
            },
            s.seconds,
            s.stages
                .iter()
                .map(|t| format!("{} {:.1}", t.stage, t.seconds))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let u = &s.uniform;
    outln!(
        out,
        "               uniform: {} {} ({} wavelengths), estimate {:.3}{}",
        u.grid,
        u.rule,
        u.samples,
        u.estimate_de2000,
        if u.met { "" } else { " (misses the target)" }
    );
}

/// Appends how `--tolerance` planned its choice: from the cache, a fit, or the uniform grid
/// without one, and why.
pub(crate) fn write_plan(out: &mut String, p: &Plan) {
    let source = match p.source {
        Source::Cache => "from the cache",
        Source::Fit => "fitted",
        Source::Uniform => "uniform",
    };
    outln!(
        out,
        "  plan         {source} in {:.2} s: {}",
        p.seconds,
        p.reason
    );
    if let Some(f) = &p.cache_file {
        let verb = match p.source {
            Source::Cache => "read",
            _ => "stored",
        };
        outln!(out, "               cache: {verb} {}", f.display());
    }
}
