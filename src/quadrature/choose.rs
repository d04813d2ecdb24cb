//! `--tolerance`: the cheapest quadrature (fewest nodes) whose estimated error over a scene's
//! stimuli meets the target, among the scene's fitted quadrature and the uniform grids at their
//! best rule.

use super::estimate::{worst, Estimator, White};
use super::fit::{self, Options};
use super::{Kind, Quadrature};
use crate::colorimetry::Observer;
use crate::error::{Error, Result};
use crate::spectrum::{Rule, WavelengthGrid};
use crate::tradeoff::{Stimulus, STEPS_NM};

/// Which quadratures to choose among.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Family {
    /// The scene's fitted quadrature, or a uniform grid where that is cheaper or the fit fails.
    Scene,
    /// Uniform grids only.
    Uniform,
}

/// One uniform grid and rule tried.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct UniformTried {
    /// Grid step, nm.
    pub step_nm: f64,
    /// Number of wavelengths on the grid.
    pub samples: usize,
    /// The step's best rule.
    pub rule: Rule,
    /// Largest CIEDE2000 over the fit and held-out stimuli with that rule.
    #[serde(rename = "max_dE2000")]
    #[serde(deserialize_with = "crate::quadrature::stored::error_or_infinite")]
    pub max: f64,
}

/// The cheapest uniform grid that meets the target.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct UniformChoice {
    /// The chosen grid and rule as a quadrature.
    pub quadrature: Quadrature,
    /// The chosen grid, `start:end:step`.
    pub grid: String,
    /// The chosen grid's best rule.
    pub rule: Rule,
    /// Number of wavelengths on the chosen grid.
    pub samples: usize,
    /// The chosen grid's largest CIEDE2000 over the fit and held-out stimuli.
    #[serde(deserialize_with = "crate::quadrature::stored::error_or_infinite")]
    pub estimate_de2000: f64,
    /// Whether the chosen grid met the target (else it is the finest tried).
    pub met: bool,
    /// The best rule of every step tried, coarsest first.
    pub tried: Vec<UniformTried>,
}

/// The stimuli of a scene and how to judge them.
#[derive(Debug, Clone)]
pub struct Scene<'a> {
    /// The stimuli quadratures are fitted on.
    pub fit: &'a [Stimulus],
    /// The stimuli held back to check the fit (may be empty).
    pub held_out: &'a [Stimulus],
    /// The observer colours are computed for.
    pub observer: Observer,
    /// Start of the range the stimuli are sampled over, nm.
    pub start_nm: f64,
    /// End of the range the stimuli are sampled over, nm.
    pub end_nm: f64,
    /// The CIELAB white the errors are taken against.
    pub white: White,
}

/// What `--tolerance` chose.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Selection {
    /// The quadrature chosen.
    pub quadrature: Quadrature,
    /// Where the chosen quadrature came from.
    pub kind: Kind,
    /// The family it was chosen among.
    pub family: Family,
    /// The CIEDE2000 every stimulus must stay within.
    pub tolerance_de2000: f64,
    /// `margin * tolerance`, what the estimate had to meet.
    pub target_de2000: f64,
    /// The most nodes the caller allows ([`Options::budget`]).
    #[serde(rename = "max_nodes")]
    pub budget: Option<usize>,
    /// The chosen quadrature's largest error over the fit and held-out stimuli.
    #[serde(deserialize_with = "crate::quadrature::stored::error_or_infinite")]
    pub estimate_de2000: f64,
    /// Whether the estimate met the target.
    pub met: bool,
    /// Why this one.
    pub reason: String,
    /// The scene fit (with `--quadrature scene`).
    pub scene: Option<fit::Choice>,
    /// The cheapest uniform grid that meets the target (computed with either family).
    pub uniform: UniformChoice,
    /// The quadrature against the 1 nm render on the image's own pixels, where the caller
    /// renders one and checked it (`render --tolerance` with a scene quadrature).
    pub image: Option<ImageCheck>,
    /// Seconds the choice took, and where they went (a scene's choice fills them).
    pub seconds: f64,
    /// Per stage, the seconds it took.
    pub stages: Vec<super::progress::StageTime>,
    /// The cache entry it was read from ([`super::cache`]); None for a choice made now.
    #[serde(default)]
    pub from_cache: Option<std::path::PathBuf>,
}

/// A quadrature's render against the 1 nm Simpson render of the same image, on a lattice of
/// its pixels (every `stride`-th row and column, each block's centre).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ImageCheck {
    /// Largest CIEDE2000 over the pixels checked.
    #[serde(deserialize_with = "crate::quadrature::stored::error_or_infinite")]
    pub max_de2000: f64,
    /// Mean CIEDE2000 over the pixels checked.
    #[serde(deserialize_with = "crate::quadrature::stored::error_or_infinite")]
    pub mean_de2000: f64,
    /// The pixel (x, y) of the largest.
    pub max_at: [usize; 2],
    /// Number of pixels checked.
    pub pixels: usize,
    /// Every `stride`-th row and column is checked (1: every pixel).
    pub stride: usize,
}

impl ImageCheck {
    /// The pixels checked, in words: "all 9216 pixels", "16384 pixels, every 4th row and
    /// column".
    pub fn lattice(&self) -> String {
        let n = self.pixels;
        match (self.stride, n) {
            (1, 1) => "its one pixel".to_string(),
            (1, _) => format!("all {n} pixels"),
            (k, _) => format!("{n} pixels, every {} row and column", ordinal(k)),
        }
    }
}

/// "2nd", "3rd", "4th", "11th", "21st".
fn ordinal(k: usize) -> String {
    let suffix = match (k % 10, k % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{k}{suffix}")
}

/// The error of `q` over both sets.
fn estimate(fit: &Estimator, held: Option<&Estimator>, q: &Quadrature) -> Result<f64> {
    let mut e = fit.errors(q)?;
    if let Some(h) = held {
        e.extend(h.errors(q)?);
    }
    Ok(worst(&e).1)
}

/// The coarsest step of [`STEPS_NM`] dividing the range whose best rule meets `target`; the
/// finest step tried when none does.
pub fn cheapest_uniform(
    fit: &Estimator,
    held: Option<&Estimator>,
    target: f64,
) -> Result<UniformChoice> {
    let g = fit.grid();
    let mut tried = Vec::new();
    let mut last = None;
    for step in STEPS_NM {
        let Ok(grid) = WavelengthGrid::new(g.start_nm(), g.end_nm(), step) else {
            continue;
        };
        let mut best: Option<(Quadrature, f64)> = None;
        for rule in Rule::ALL {
            let q = Quadrature::uniform(grid, rule, fit.observer())?;
            let e = estimate(fit, held, &q)?;
            if best.as_ref().is_none_or(|b| e < b.1) {
                best = Some((q, e));
            }
        }
        let (q, e) = best.expect("three rules");
        let rule = q.uniform_grid().map_or(Rule::Riemann, |(_, r)| r);
        tried.push(UniformTried {
            step_nm: step,
            samples: grid.len(),
            rule,
            max: e,
        });
        let choice = UniformChoice {
            grid: grid.to_string(),
            rule,
            samples: grid.len(),
            estimate_de2000: e,
            met: e <= target,
            tried: tried.clone(),
            quadrature: q,
        };
        if choice.met {
            return Ok(choice);
        }
        last = Some(choice);
    }
    last.ok_or_else(|| {
        Error::invalid(format!(
            "no step of {STEPS_NM:?} nm divides the range {}..{} nm",
            g.start_nm(),
            g.end_nm()
        ))
    })
}

/// Chooses the quadrature for `scene` at `opts` (see the module docs).
pub fn select(scene: &Scene, family: Family, opts: &Options) -> Result<Selection> {
    select_reporting(scene, family, opts, &super::progress::quiet)
}

/// [`select`], telling `report` the scene fit's stages ([`fit::fit_reporting`]).
pub fn select_reporting(
    scene: &Scene,
    family: Family,
    opts: &Options,
    report: super::progress::Report,
) -> Result<Selection> {
    check_request(family, opts)?;
    let (fit_set, held) = estimators(scene)?;
    report(&super::progress::Stage::UniformGrids {
        stimuli: scene.fit.len() + scene.held_out.len(),
    });
    let uniform = cheapest_uniform(&fit_set, held.as_ref(), opts.target())?;
    let fitted = match family {
        Family::Scene => Some(fit::fit_reporting(&fit_set, held.as_ref(), opts, report)?),
        Family::Uniform => None,
    };
    let chosen = pick(fitted.as_ref(), &uniform, opts).chosen(fitted.as_ref(), &uniform, opts);
    Ok(Selection {
        kind: chosen.quadrature.kind(),
        quadrature: chosen.quadrature,
        family,
        tolerance_de2000: opts.tolerance,
        target_de2000: opts.target(),
        budget: opts.budget,
        estimate_de2000: chosen.estimate_de2000,
        met: chosen.met,
        reason: chosen.reason,
        scene: fitted,
        uniform,
        image: None,
        seconds: 0.0,
        stages: Vec::new(),
        from_cache: None,
    })
}

/// An error for a tolerance out of range, or a budget of nodes with uniform grids only.
fn check_request(family: Family, opts: &Options) -> Result<()> {
    fit::check_tolerance(opts.tolerance)?;
    if family == Family::Uniform && opts.budget.is_some() {
        return Err(Error::invalid(
            "a budget of nodes applies to the scene's quadrature, not to uniform grids",
        ));
    }
    Ok(())
}

/// The estimators of the scene's fit stimuli and, if it has any, of its held-out ones.
fn estimators(scene: &Scene) -> Result<(Estimator, Option<Estimator>)> {
    let est = |s: &[Stimulus]| {
        Estimator::new(s, scene.observer, scene.start_nm, scene.end_nm, scene.white)
    };
    let fit_set = est(scene.fit)?;
    let held = if scene.held_out.is_empty() {
        None
    } else {
        Some(est(scene.held_out)?)
    };
    Ok((fit_set, held))
}

/// Which quadrature [`select_reporting`] takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Pick {
    /// The scene fit meets the target, with no more nodes than a uniform grid that does.
    SceneMeets,
    /// Nothing within the budget meets the target, and the scene fit errs least.
    SceneErrsLeast,
    /// A uniform grid: as cheap as a scene fit that meets the target, or better than one that
    /// misses it.
    UniformOverScene,
    /// Uniform grids only were asked for.
    UniformAsked,
}

/// The choice between the scene fit (None: not asked for) and the cheapest uniform grid. A
/// uniform grid beyond the budget is not chosen, however well it does.
fn pick(fitted: Option<&fit::Choice>, uniform: &UniformChoice, opts: &Options) -> Pick {
    let within = opts.within_budget(uniform.samples);
    let uniform_meets = uniform.met && within;
    match fitted {
        Some(f) if f.met && (!uniform_meets || f.quadrature.len() <= uniform.samples) => {
            Pick::SceneMeets
        }
        Some(f)
            if !(f.met || uniform_meets)
                && (!within || f.estimate_de2000 < uniform.estimate_de2000) =>
        {
            Pick::SceneErrsLeast
        }
        Some(_) => Pick::UniformOverScene,
        None => Pick::UniformAsked,
    }
}

/// The quadrature picked, its estimate, whether it meets the target, and why it was picked.
struct Chosen {
    quadrature: Quadrature,
    estimate_de2000: f64,
    met: bool,
    reason: String,
}

impl Pick {
    /// The quadrature this pick names, with the reason in words.
    fn chosen(
        self,
        fitted: Option<&fit::Choice>,
        uniform: &UniformChoice,
        opts: &Options,
    ) -> Chosen {
        let reason = self.reason(fitted, uniform, opts);
        match (self, fitted) {
            (Pick::SceneMeets | Pick::SceneErrsLeast, Some(f)) => Chosen {
                quadrature: f.quadrature.clone(),
                estimate_de2000: f.estimate_de2000,
                met: self == Pick::SceneMeets,
                reason,
            },
            _ => Chosen {
                quadrature: uniform.quadrature.clone(),
                estimate_de2000: uniform.estimate_de2000,
                met: uniform.met,
                reason,
            },
        }
    }

    /// Why this pick, in words.
    fn reason(
        self,
        fitted: Option<&fit::Choice>,
        uniform: &UniformChoice,
        opts: &Options,
    ) -> String {
        match (self, fitted) {
            (Pick::SceneMeets, Some(f)) => format!(
                "{} the target; the cheapest uniform grid that does has {}",
                super::nodes_verb(f.quadrature.len(), "meet"),
                if uniform.met {
                    uniform.samples.to_string()
                } else {
                    "none".into()
                }
            ),
            (Pick::SceneErrsLeast, _) => match opts.budget {
                Some(b) => format!(
                    "no quadrature of at most {b} nodes meets the target; of those, the \
                     scene fit errs least"
                ),
                None => "nothing meets the target; the scene fit errs least".into(),
            },
            (Pick::UniformOverScene, Some(f)) if f.met => "the uniform grid is as cheap".into(),
            (Pick::UniformOverScene, Some(f)) => format!(
                "the scene fit misses the target with {} nodes",
                f.quadrature.len()
            ),
            _ => "--quadrature uniform".into(),
        }
    }
}

/// The stimuli `color --tolerance` fits a quadrature to: the colour asked for, its light seen
/// directly, the 24 ColorChecker patches and smooth reflectances ([`smooth_reflectances`])
/// centred every 10 nm under it; held out, those centred half way between. So the
/// quadrature holds for the light and smooth colours under it, not only for the one colour (one
/// node and three free weights reproduce any single colour exactly, and say nothing about the
/// next).
pub fn for_colour(stimulus: Stimulus, light_label: &str) -> Result<(Vec<Stimulus>, Vec<Stimulus>)> {
    let light = stimulus.light.clone();
    let under = |set: Vec<(String, crate::spectrum::Tabulated)>| -> Vec<Stimulus> {
        set.into_iter()
            .map(|(name, r)| {
                Stimulus::new(
                    format!("{name} under {light_label}"),
                    light.clone(),
                    crate::tradeoff::Surface::Reflectance(r),
                )
            })
            .collect()
    };
    let mut fit = vec![stimulus.clone()];
    fit.extend(crate::tradeoff::colorchecker_under(light_label, &light)?);
    fit.extend(under(smooth_reflectances(420.0, 10.0)?));
    Ok((fit, under(smooth_reflectances(425.0, 10.0)?)))
}

/// Smooth reflectances between 0.05 and 0.95 at 5 nm, centred every `step_nm` from
/// `first_nm` to 720 nm (where xbar fades: a red edge such as foliage's lies there): rising and
/// falling edges (logistic, 15 and 50 nm wide) and bumps (Gaussian, 25, 50 and 100 nm wide).
pub fn smooth_reflectances(
    first_nm: f64,
    step_nm: f64,
) -> Result<Vec<(String, crate::spectrum::Tabulated)>> {
    let wl: Vec<f64> = (0..=80).map(|i| 380.0 + 5.0 * i as f64).collect();
    let mut out = Vec::new();
    let mut c = first_nm;
    while c <= 720.0 {
        let edge = |s: f64| move |w: f64| 1.0 / (1.0 + (-(w - c) / s).exp());
        let bump = |s: f64| move |w: f64| (-0.5 * ((w - c) / s).powi(2)).exp();
        let (sharp, slow) = (edge(15.0), edge(50.0));
        let shapes: [(&str, &dyn Fn(f64) -> f64); 7] = [
            ("edge up", &sharp),
            ("edge down", &|w| 1.0 - sharp(w)),
            ("slow edge up", &slow),
            ("slow edge down", &|w| 1.0 - slow(w)),
            ("25 nm bump", &bump(25.0)),
            ("50 nm bump", &bump(50.0)),
            ("100 nm bump", &bump(100.0)),
        ];
        for (name, f) in shapes {
            let values = wl.iter().map(|&w| 0.05 + 0.9 * f(w)).collect();
            out.push((
                format!("{name} at {c} nm"),
                crate::spectrum::Tabulated::new(wl.clone(), values)?,
            ));
        }
        c += step_nm;
    }
    Ok(out)
}

/// `color colorchecker:red --under FL2 --tolerance`'s stimuli: fitted, and held out.
#[cfg(test)]
pub(crate) fn red_under_fl2() -> (Vec<Stimulus>, Vec<Stimulus>) {
    let fl2 = crate::data::spectrum("FL2").unwrap().data;
    let red = crate::data::spectrum("colorchecker:red").unwrap().data;
    let colour = Stimulus::new(
        "red under FL2",
        fl2,
        crate::tradeoff::Surface::Reflectance(red),
    );
    for_colour(colour, "FL2").unwrap()
}

/// The scene of `fit` and `held_out` over 380-780 nm for CIE 1931, each relative to its light.
#[cfg(test)]
pub(crate) fn own_light<'a>(fit: &'a [Stimulus], held_out: &'a [Stimulus]) -> Scene<'a> {
    Scene {
        fit,
        held_out,
        observer: Observer::Cie1931,
        start_nm: 380.0,
        end_nm: 780.0,
        white: White::OwnLight,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With a budget below what the tolerance needs, the uniform grid that meets it is not
    /// chosen: the scene's best within the budget is, and the choice says it misses.
    #[test]
    fn a_budget_keeps_the_choice_within_it() {
        let (fit, held_out) = red_under_fl2();
        let scene = own_light(&fit, &held_out);
        let free = select(&scene, Family::Scene, &Options::new(0.5).unwrap()).unwrap();
        let n = free.quadrature.len();
        assert!(free.met && free.kind == Kind::Scene && n > 3, "{free:?}");
        let tight = select(
            &scene,
            Family::Scene,
            &Options::with_budget(0.5, 3).unwrap(),
        )
        .unwrap();
        assert!(tight.uniform.met && tight.uniform.samples > 3);
        assert!(
            tight.kind == Kind::Scene && tight.quadrature.len() <= 3 && !tight.met,
            "{tight:?}"
        );
        assert!(tight.reason.contains("at most 3 nodes"), "{}", tight.reason);
        assert_eq!(tight.budget, Some(3));
        let uniform = Options::with_budget(0.5, 3).unwrap();
        assert!(select(&scene, Family::Uniform, &uniform).is_err());
    }

    #[test]
    fn the_lattice_reads_as_english() {
        let check = |pixels, stride| ImageCheck {
            max_de2000: 0.0,
            mean_de2000: 0.0,
            max_at: [0, 0],
            pixels,
            stride,
        };
        assert_eq!(check(1, 1).lattice(), "its one pixel");
        assert_eq!(check(9216, 1).lattice(), "all 9216 pixels");
        assert_eq!(
            check(8192, 2).lattice(),
            "8192 pixels, every 2nd row and column"
        );
        let ords: Vec<String> = [1, 3, 4, 11, 12, 13, 21, 22, 112].map(ordinal).into();
        assert_eq!(
            ords,
            ["1st", "3rd", "4th", "11th", "12th", "13th", "21st", "22nd", "112th"]
        );
    }
}
