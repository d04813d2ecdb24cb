//! `--tolerance` that pays for itself: the scene's fit is worth it only when it costs less
//! than the wavelengths it saves on the frames it serves.
//!
//! The pipeline, each stage a value the report prints ([`Plan`]):
//! 1. **cache**: a choice stored for this very scene and tolerance ([`crate::quadrature::cache`])
//!    is taken as it is;
//! 2. **uniform**: the cheapest uniform grid that meets the tolerance (`--quadrature uniform`'s
//!    choice, the path the fit must beat);
//! 3. **cost**: one frame on that grid, measured by the caller ([`Workload::frame_s`]), times
//!    the frames, and the fit's time budget: a tenth of that path (so that a fit which finds
//!    nothing better costs at most 10% more), or what the caller gives;
//! 4. **fit**: where the budget is worth starting (more than gathering the scene's spectra
//!    took once), the scene's fit as an anytime search within it; the fitted set where it meets
//!    the tolerance with fewer nodes, else the uniform grid, and the reason;
//! 5. **store**: a fit is stored in the cache, with whether its budget cut it short.

use super::Scene;
use crate::colorimetry::{Observer, RgbSpace};
use crate::error::Result;
use crate::quadrature::cache::{Cache, Key, Lookup};
use crate::quadrature::choose::{Family, Selection};
use crate::quadrature::fit::Options;
use crate::quadrature::progress::Report;
use crate::quadrature::{Kind, Quadrature};
use std::path::PathBuf;
use std::time::Instant;

/// The share of the uniform path's time a fit may spend by default.
pub const FIT_SHARE: f64 = 0.1;

/// The nodes of the image's check: the 1 nm grid over 380-780 nm.
const IMAGE_CHECK_NODES: f64 = 401.0;

/// How long the fit may search.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FitBudget {
    /// [`FIT_SHARE`] of the uniform path's predicted time.
    Auto,
    /// At most this many seconds.
    Seconds(f64),
    /// As long as it takes (`--quadrature scene`, `bench`, a viewer's background fit).
    Unlimited,
}

/// What the quadrature will serve.
pub struct Workload<'a> {
    /// Frames rendered on it (1 for a still; a sequence's length).
    pub frames: usize,
    /// Seconds to prepare and render one frame on a quadrature (the caller's backend).
    pub frame_s: &'a dyn Fn(&Quadrature) -> Result<f64>,
}

/// Where the chosen quadrature came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Source {
    /// A stored choice, used as it is.
    Cache,
    /// This run's fit.
    Fit,
    /// The uniform grid, without a fit (it would not pay).
    Uniform,
}

/// The plan: what the choice weighed, and what it took.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Plan {
    /// Frames the quadrature serves ([`Workload::frames`]).
    pub frames: usize,
    /// Where the chosen quadrature came from.
    pub source: Source,
    /// Why it was chosen, in words (the stages' reasons joined by "; ").
    pub reason: String,
    /// The uniform grid's nodes and its predicted time for every frame (not with a cache hit).
    pub uniform_nodes: Option<usize>,
    /// Predicted seconds of every frame on the uniform grid (None: no frame was measured).
    pub uniform_path_s: Option<f64>,
    /// The time the fit's search was given (None: unlimited, or no fit ran).
    pub fit_budget_s: Option<f64>,
    /// The predicted time of the fit's last check on the image (with a budget of its own).
    pub image_check_s: Option<f64>,
    /// The fit stopped at its budget before it was done.
    pub cut_short: bool,
    /// Seconds spent choosing, all stages.
    pub seconds: f64,
    /// The cache entry read or written, and a note on one that was ignored.
    pub cache_file: Option<PathBuf>,
    /// Why a cache entry was not used or not stored; None: nothing to note.
    pub cache_note: Option<String>,
}

/// The chosen quadrature's selection and the plan that chose it.
pub struct Planned {
    /// The chosen quadrature, with what it met.
    pub selection: Selection,
    /// How it was chosen.
    pub plan: Plan,
}

/// What choosing needs besides the scene.
pub struct Aim<'a> {
    /// The colour-matching functions the images are computed with.
    pub observer: Observer,
    /// The output linear RGB space.
    pub space: RgbSpace,
    /// The fit's target (tolerance in CIEDE2000, margin, node limits).
    pub opts: Options,
    /// How long the fit may search.
    pub budget: FitBudget,
    /// Where choices are stored and looked up; None: no cache.
    pub cache: Option<&'a Cache>,
}

impl Scene {
    /// `--tolerance` for `work`: the cheaper of a fit and the uniform grid (see the module
    /// docs).
    pub fn plan_quadrature(&self, aim: &Aim, work: &Workload, report: Report) -> Result<Planned> {
        let t0 = Instant::now();
        let key = Key::new(
            &self.fingerprint(),
            Family::Scene,
            &aim.opts,
            aim.observer,
            aim.space,
        );
        let mut plan = Plan {
            frames: work.frames,
            source: Source::Cache,
            reason: String::new(),
            uniform_nodes: None,
            uniform_path_s: None,
            fit_budget_s: None,
            image_check_s: None,
            cut_short: false,
            seconds: 0.0,
            cache_file: None,
            cache_note: None,
        };
        let selection = self.choose_planned(aim, work, &key, &mut plan, report)?;
        plan.seconds = t0.elapsed().as_secs_f64();
        Ok(Planned { selection, plan })
    }

    /// The stages of [`Scene::plan_quadrature`] after the key: the chosen selection, and the
    /// plan filled in.
    fn choose_planned(
        &self,
        aim: &Aim,
        work: &Workload,
        key: &Key,
        plan: &mut Plan,
        report: Report,
    ) -> Result<Selection> {
        // A fit cut short by its budget serves a run with no more time than it had: under
        // FitBudget::Auto that is known once the frame is measured, so such an entry is looked
        // at again then (and serves a run with up to twice its time). A lookup that misses
        // leaves the plan's reason as it was.
        let fixed = match aim.budget {
            FitBudget::Seconds(s) => Some(s),
            _ => None,
        };
        if let Some(hit) = look_up(aim.cache, key, fixed, plan) {
            return Ok(hit);
        }
        let (uniform, budget) = self.weigh(aim, work, plan, report)?;
        let cut_entry = plan.cache_note.is_some();
        let Some(budget) = budget else {
            // No fit pays; one cut short by a budget before costs nothing now.
            if cut_entry {
                if let Some(hit) = look_up(aim.cache, key, Some(0.0), plan) {
                    return Ok(hit);
                }
            }
            plan.source = Source::Uniform;
            return Ok(uniform);
        };
        if aim.budget == FitBudget::Auto && cut_entry {
            // A fit cut short at half this budget or more is as good as this run would make:
            // the measured frame, and so the budget, varies that much from run to run (28 s
            // and 46 s for the same 36 frames), and a fit improves slowly with time.
            if let Some(hit) = look_up(aim.cache, key, budget.map(|b| b / 2.0), plan) {
                return Ok(hit);
            }
        }
        let opts = aim.opts.within_seconds(budget);
        let fitted = self.choose_quadrature_reporting(
            aim.observer,
            aim.space,
            Family::Scene,
            &opts,
            report,
        )?;
        plan.cut_short = opts.out_of_time();
        plan.source = Source::Fit;
        let selection = cheaper(fitted, uniform, plan);
        if let Some(cache) = aim.cache {
            // What was chosen is stored (the uniform grid where a fit cut short missed), marked
            // whether the budget cut the fit short. A cache that cannot be written costs the
            // next run a fit, nothing more.
            match cache.put(key, &selection, budget, !plan.cut_short) {
                Ok(file) => plan.cache_file = Some(file),
                Err(e) => plan.cache_note = Some(format!("not stored: {e}")),
            }
        }
        Ok(selection)
    }

    /// The uniform grid at the tolerance, and the fit's budget in seconds: None where no fit
    /// runs, Some(None) for one without a limit.
    #[allow(clippy::type_complexity)]
    fn weigh(
        &self,
        aim: &Aim,
        work: &Workload,
        plan: &mut Plan,
        report: Report,
    ) -> Result<(Selection, Option<Option<f64>>)> {
        let t0 = Instant::now();
        let uniform = self.choose_quadrature_reporting(
            aim.observer,
            aim.space,
            Family::Uniform,
            &aim.opts,
            report,
        )?;
        let gather_s = t0.elapsed().as_secs_f64();
        plan.uniform_nodes = Some(uniform.quadrature.len());
        let budget = match aim.budget {
            FitBudget::Unlimited => {
                plan.reason = "a fit without a time budget".into();
                return Ok((uniform, Some(None)));
            }
            FitBudget::Seconds(s) => {
                plan.reason = format!("a fit within {s} s");
                plan.fit_budget_s = Some(s);
                return Ok((uniform, Some(Some(s))));
            }
            FitBudget::Auto => match self.auto_budget(&uniform, work, gather_s, plan)? {
                Some(b) => b,
                None => return Ok((no_fit(uniform), None)),
            },
        };
        plan.fit_budget_s = Some(budget.max(0.0));
        let frames = frames_word(work.frames);
        let path = plan.uniform_path_s.unwrap_or(0.0);
        let n = uniform.quadrature.len();
        // A fit gathers the spectra again before it can add a node.
        if budget > 2.0 * gather_s {
            plan.reason = format!(
                "the uniform grid of {n} takes about {path:.1} s for {frames}; a fit may spend \
                 {:.0}% of it: {budget:.1} s searching and {:.1} s checking the image",
                100.0 * FIT_SHARE,
                plan.image_check_s.unwrap_or(0.0)
            );
            return Ok((uniform, Some(Some(budget.max(0.0)))));
        }
        plan.reason = format!(
            "a fit would cost more than it saves: the uniform grid of {n} takes about \
             {path:.1} s for {frames}, and {:.0}% of that, less the image's check, leaves \
             {:.2} s, less than gathering the scene's spectra twice ({:.2} s)",
            100.0 * FIT_SHARE,
            budget.max(0.0),
            2.0 * gather_s
        );
        Ok((no_fit(uniform), None))
    }
}

impl Scene {
    /// [`FitBudget::Auto`]'s budget for the search, in seconds, with the `uniform` choice made
    /// in `gather_s`: [`FIT_SHARE`] of the uniform path's predicted time for `work`, less the
    /// time measuring a frame took and the fit's last check will take. None where even a tenth
    /// of the frames cannot pay for that check (no frame is measured then; the plan says why).
    fn auto_budget(
        &self,
        uniform: &Selection,
        work: &Workload,
        gather_s: f64,
        plan: &mut Plan,
    ) -> Result<Option<f64>> {
        // The fit's last check renders the image's lattice at 1 nm: in frames, about 401 / n
        // times the lattice's share of the pixels.
        let n = uniform.quadrature.len() as f64;
        let share = self.image_check_pixels() as f64 / (self.width * self.height) as f64;
        let check_frames = IMAGE_CHECK_NODES / n * share;
        if FIT_SHARE * (work.frames as f64) < check_frames {
            plan.reason = format!(
                "a fit would cost more than it saves: its check of the image alone (401 \
                 wavelengths on {:.1}% of the pixels) costs about {check_frames:.2} frames of \
                 the uniform grid of {}, more than {:.0}% of {}",
                100.0 * share,
                uniform.quadrature.len(),
                100.0 * FIT_SHARE,
                frames_word(work.frames)
            );
            return Ok(None);
        }
        let t1 = Instant::now();
        let frame = (work.frame_s)(&uniform.quadrature)?;
        let measure_s = t1.elapsed().as_secs_f64();
        let path = work.frames as f64 * frame;
        plan.uniform_path_s = Some(path);
        // The uniform path gathers the spectra too; measuring the frame is extra, and so is the
        // fit's last check, which runs after the search: the search stops in time for it.
        let check_s = frame * check_frames;
        plan.image_check_s = Some(check_s);
        Ok(Some(FIT_SHARE * (path + gather_s) - measure_s - check_s))
    }
}

/// The entry of `key` in `cache` for a run that may fit for `budget_s` seconds (None: as long as
/// it takes), noting in `plan` what was found.
fn look_up(
    cache: Option<&Cache>,
    key: &Key,
    budget_s: Option<f64>,
    plan: &mut Plan,
) -> Option<Selection> {
    match cache?.get(key, budget_s) {
        Lookup::Hit(selection, file) => {
            plan.source = Source::Cache;
            plan.reason = "the scene's fit at this tolerance, from the cache".into();
            plan.cache_file = Some(file);
            plan.cache_note = None;
            Some(*selection)
        }
        Lookup::Miss(note) => {
            plan.cache_note = note;
            None
        }
        Lookup::Ignored(file, why) => {
            plan.cache_note = Some(format!("ignored {}: it {why}", file.display()));
            None
        }
    }
}

/// The uniform choice, its reason saying why no fit ran.
fn no_fit(mut uniform: Selection) -> Selection {
    uniform.reason =
        "the cheapest uniform grid that meets the target (no fit: see the plan)".into();
    uniform
}

/// "1 frame", "36 frames".
fn frames_word(n: usize) -> String {
    match n {
        1 => "1 frame".to_string(),
        n => format!("{n} frames"),
    }
}

/// The fit's selection, or the uniform one where the fit missed the target (its budget cut it
/// short, say) and the uniform grid meets it, with the plan's reason.
fn cheaper(fitted: Selection, uniform: Selection, plan: &mut Plan) -> Selection {
    let took = format!("{:.1} s", fitted.seconds);
    let cut = if plan.cut_short {
        " (its budget cut it short)"
    } else {
        ""
    };
    if fitted.met || !uniform.met {
        let what = match fitted.kind {
            Kind::Scene => format!("{} fitted nodes", fitted.quadrature.len()),
            _ => format!("the uniform grid of {}", fitted.quadrature.len()),
        };
        plan.reason = join(&plan.reason, &format!("the fit took {took}{cut}: {what}"));
        return fitted;
    }
    plan.reason = join(
        &plan.reason,
        &format!(
            "the fit took {took}{cut} and misses the target with {} nodes: the uniform grid of {}",
            fitted.quadrature.len(),
            uniform.quadrature.len()
        ),
    );
    plan.source = Source::Uniform;
    uniform
}

fn join(a: &str, b: &str) -> String {
    if a.is_empty() {
        b.to_string()
    } else {
        format!("{a}; {b}")
    }
}
