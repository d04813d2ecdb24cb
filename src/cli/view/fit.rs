//! The view's wavelengths: the quadrature the settings ask for, and the fit behind a fitted
//! one. A fit runs on its own thread while frames keep coming on an interim uniform grid; it
//! is made to cover what the view changes without refitting: every orientation of the camera
//! (zoom, orbit, exposure and size never refit) and, for a film, its thickness scaled by
//! [`COVER`] either way. A change outside that schedules a refit, and says why; one fit runs
//! at a time (a refit waits for the running fit, whose result is kept only if it still
//! covers the settings).

use crate::cli::render_args::{QuadratureArg, RenderArgs};
use crate::cli::tolerance::tolerance_options;
use specmap::quadrature::choose::{Family, Selection};
use specmap::quadrature::Kind;
use specmap::quadrature::Quadrature;
use specmap::render::plan::{FitBudget, Source, Workload};
use specmap::render::{Film, Scene};
use std::sync::mpsc::{channel, Receiver};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Options that never change what a fit covers.
pub(crate) const VIEW_ONLY: [&str; 6] = ["exposure", "orbit", "zoom", "size", "backend", "film"];

/// The thickness scales a fitted film covers: 1 -/+ COVER. A wider range costs the fit its
/// time: the stimuli sample a film's thickness range at a few thicknesses per cycle of its
/// phase, and the ball under envmaps/sunrise.exr took over two minutes to fit over the
/// paper's whole 100-400 nm sweep.
pub(crate) const COVER: f64 = 0.15;

/// What a fitted quadrature was made for.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Covers {
    /// The settings but [`VIEW_ONLY`]'s.
    pub(crate) key: Vec<(String, String)>,
    /// The main objects' films as fitted, and the thickness scales covered.
    pub(crate) films: Vec<Option<Film>>,
    pub(crate) scales: (f64, f64),
}

impl Covers {
    /// Why `other` (the settings now) is not covered, or None when it is.
    pub(crate) fn misses(&self, other: &Covers) -> Option<String> {
        if self.key != other.key {
            let changed: Vec<String> = other
                .key
                .iter()
                .filter(|p| !self.key.contains(p))
                .chain(self.key.iter().filter(|p| !other.key.contains(p)))
                .map(|(k, _)| format!("--{k}"))
                .collect();
            let mut changed = changed;
            changed.dedup();
            return Some(format!("{} changed", changed.join(", ")));
        }
        for (a, b) in self.films.iter().zip(&other.films) {
            match (a, b) {
                (None, None) => {}
                (Some(a), Some(b)) => match scale_between(a, b) {
                    Some(k) if k >= self.scales.0 - 1e-9 && k <= self.scales.1 + 1e-9 => {}
                    Some(_) => return Some("the film's thickness left the fitted range".into()),
                    None => return Some("the film's layers changed".into()),
                },
                _ => return Some("a film was added or removed".into()),
            }
        }
        None
    }
}

/// `k` with `b`'s layers `k` times `a`'s (same media), if there is one.
fn scale_between(a: &Film, b: &Film) -> Option<f64> {
    if a.ambient != b.ambient || a.substrate != b.substrate || a.layers.len() != b.layers.len() {
        return None;
    }
    let mut k: Option<f64> = None;
    for (la, lb) in a.layers.iter().zip(&b.layers) {
        if la.material() != lb.material() || la.thickness_nm() <= 0.0 {
            return None;
        }
        let r = lb.thickness_nm() / la.thickness_nm();
        match k {
            Some(k0) if (r - k0).abs() > 1e-9 * k0.abs().max(1.0) => return None,
            _ => k = Some(r),
        }
    }
    Some(k.unwrap_or(1.0))
}

/// The main objects' films of the scene `args` describe (no map needed).
pub(crate) fn films(args: &RenderArgs) -> anyhow::Result<Vec<Option<Film>>> {
    let scene = crate::cli::render_scene::scene_from(args, args.preset(), (8, 8), None)?;
    Ok(main_films(&scene))
}

fn main_films(scene: &Scene) -> Vec<Option<Film>> {
    scene
        .objects
        .iter()
        .filter(|o| o.main)
        .map(|o| {
            if o.ramp.is_some() {
                None
            } else {
                o.surface.film.clone()
            }
        })
        .collect()
}

/// The scales a fit covers: `--fit-range`'s, else [`COVER`] either way of the films'
/// thicknesses (none without a film).
fn sweep_scales(films: &[Option<Film>], range: Option<&str>) -> anyhow::Result<(f64, f64)> {
    if films.iter().flatten().next().is_none() {
        return Ok((1.0, 1.0));
    }
    match range {
        Some(r) => crate::cli::render_args::fit_range(r),
        None => Ok((1.0 - COVER, 1.0 + COVER)),
    }
}

/// The `--fit-range` that makes `render` fit what `fitted` covers, for the films `now` has
/// (`1:1` without a film: every orientation, as the view fits, and no thickness range).
pub(crate) fn range_for(fitted: &Covers, now: &Covers) -> String {
    let k = fitted
        .films
        .iter()
        .zip(&now.films)
        .find_map(|(a, b)| scale_between(a.as_ref()?, b.as_ref()?))
        .unwrap_or(1.0);
    format!("{}:{}", fitted.scales.0 / k, fitted.scales.1 / k)
}

/// How the settings choose wavelengths.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Mode {
    Uniform(Quadrature),
    Meyer(Quadrature),
    /// A fit at a tolerance (and a budget of nodes), of the scene's or the uniform family.
    Fitted {
        tolerance: f64,
        budget: Option<usize>,
        family: Family,
    },
}

pub(crate) fn mode(args: &RenderArgs) -> anyhow::Result<Mode> {
    let spectral = crate::cli::render_scene::spectral_of(args)?;
    Ok(match (args.tolerance, args.quadrature) {
        (None, Some(QuadratureArg::Meyer)) => Mode::Meyer(Quadrature::meyer(spectral.observer)?),
        (None, Some(QuadratureArg::Scene)) => anyhow::bail!(
            "--quadrature scene fits the wavelengths to a colour tolerance: give --tolerance"
        ),
        (None, _) => Mode::Uniform(Quadrature::uniform(
            spectral.grid,
            spectral.rule,
            spectral.observer,
        )?),
        (Some(t), kind) => {
            tolerance_options(t, args.max_nodes, kind)?;
            Mode::Fitted {
                tolerance: t,
                budget: args.max_nodes,
                family: match kind {
                    Some(QuadratureArg::Uniform) => Family::Uniform,
                    Some(QuadratureArg::Meyer) => anyhow::bail!(
                        "--quadrature meyer has four fixed wavelengths: it cannot follow --tolerance"
                    ),
                    _ => Family::Scene,
                },
            }
        }
    })
}

/// What the fit's thread sends: a set to draw with while it goes on, then its result.
pub(crate) enum Sent {
    Interim(Box<Selection>),
    Final(anyhow::Result<Box<Selection>>),
}

/// Seconds the view's first, quick fit may search ([`start`]).
pub(crate) const INTERIM_S: f64 = 2.0;

/// A fit on its own thread.
pub(crate) struct Running {
    pub(crate) covers: Covers,
    pub(crate) stage: Arc<Mutex<String>>,
    pub(crate) started: Instant,
    pub(crate) result: Receiver<Sent>,
}

/// Starts the fit for `args` (whose mode is [`Mode::Fitted`]); `wake` is called when it ends.
pub(crate) fn start(
    args: &RenderArgs,
    covers: Covers,
    wake: impl Fn() + Send + 'static,
) -> anyhow::Result<Running> {
    let Mode::Fitted {
        tolerance,
        budget,
        family,
    } = mode(args)?
    else {
        anyhow::bail!("the settings do not ask for a fit");
    };
    let opts = tolerance_options(tolerance, budget, args.quadrature)?;
    let spectral = crate::cli::render_scene::spectral_of(args)?;
    let stage = Arc::new(Mutex::new("starting".to_string()));
    let (tx, rx) = channel();
    let args = args.clone();
    let scales = covers.scales;
    let st = stage.clone();
    std::thread::Builder::new()
        .name("specmap fit".into())
        .spawn(move || {
            let run = || -> anyhow::Result<Selection> {
                let mut scene =
                    super::worker::scene(&args, &mut std::collections::HashMap::new())?.0;
                scene.for_any_view(scales);
                let report = |s: &specmap::quadrature::progress::Stage| {
                    if let Ok(mut m) = st.lock() {
                        *m = s.to_string();
                    }
                };
                if family == Family::Uniform {
                    return Ok(scene.choose_quadrature_reporting(
                        spectral.observer,
                        spectral.space,
                        family,
                        &opts,
                        &report,
                    )?);
                }
                // The scene's fit: from the cache where an earlier view or render made it, else
                // fitted and stored. Without --fit-budget, first within INTERIM_S seconds (the
                // view draws with its set at once), then for as long as it takes.
                let cache = crate::cli::tolerance::user_cache(args.no_cache);
                let plan = |budget| {
                    let aim = crate::cli::tolerance::aim(&spectral, opts, budget, cache.as_ref());
                    // Never called: a budget that is unlimited or given weighs no frames.
                    let frame_s = |_: &Quadrature| Ok(0.0);
                    let work = Workload {
                        frames: 1,
                        frame_s: &frame_s,
                    };
                    scene.plan_quadrature(&aim, &work, &report)
                };
                if let Some(s) = args.fit_budget {
                    return Ok(plan(FitBudget::Seconds(s))?.selection);
                }
                let quick = plan(FitBudget::Seconds(INTERIM_S))?;
                if quick.plan.source == Source::Fit && !quick.plan.cut_short {
                    return Ok(quick.selection);
                }
                if quick.selection.met && quick.selection.kind == Kind::Scene {
                    let _ = tx.send(Sent::Interim(Box::new(quick.selection)));
                    wake();
                }
                Ok(plan(FitBudget::Unlimited)?.selection)
            };
            let _ = tx.send(Sent::Final(run().map(Box::new)));
            wake();
        })?;
    Ok(Running {
        covers,
        stage,
        started: Instant::now(),
        result: rx,
    })
}

/// What a fit started now for `settings` would cover.
pub(crate) fn covers(
    settings: &super::settings::Settings,
    args: &RenderArgs,
) -> anyhow::Result<Covers> {
    let films = films(args)?;
    let scales = sweep_scales(&films, args.fit_range.as_deref())?;
    Ok(Covers {
        key: settings.without(&VIEW_ONLY),
        films,
        scales,
    })
}

/// What the settings now are, to hold against a fit's [`Covers`] (the fitted range kept).
pub(crate) fn now(
    settings: &super::settings::Settings,
    args: &RenderArgs,
) -> anyhow::Result<Covers> {
    Ok(Covers {
        key: settings.without(&VIEW_ONLY),
        films: films(args)?,
        scales: (1.0, 1.0),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::view::settings::Settings;

    fn at(pairs: &[(&str, &str)]) -> (Settings, RenderArgs) {
        let a = RenderArgs::parse_pairs(pairs.iter().copied()).unwrap();
        (Settings::from_args(&a), a)
    }

    #[test]
    fn camera_and_a_thickness_inside_the_sweep_are_covered_other_changes_are_not() {
        let (s, a) = at(&[("film", "2.7:270"), ("tolerance", "0.5")]);
        let fitted = covers(&s, &a).unwrap();
        assert_eq!(fitted.scales, (1.0 - COVER, 1.0 + COVER));
        let check = |pairs: &[(&str, &str)]| {
            let (s, a) = at(pairs);
            fitted.misses(&now(&s, &a).unwrap())
        };
        let base = [("tolerance", "0.5")];
        let with = |extra: &[(&'static str, &'static str)]| {
            let mut v: Vec<(&str, &str)> = base.to_vec();
            v.extend_from_slice(extra);
            v
        };
        assert_eq!(
            check(&with(&[
                ("film", "2.7:300"),
                ("orbit", "40,10"),
                ("zoom", "2")
            ])),
            None
        );
        assert_eq!(
            check(&with(&[("film", "2.7:240"), ("exposure", "-1")])),
            None
        );
        assert!(check(&with(&[("film", "2.7:350")]))
            .unwrap()
            .contains("range"));
        assert!(check(&with(&[("film", "2.3:270")]))
            .unwrap()
            .contains("layers"));
        // The command's range: the fitted scales relative to the film now; 1:1 without one.
        let (s2, a2) = at(&with(&[("film", "2.7:300")]));
        let r = range_for(&fitted, &now(&s2, &a2).unwrap());
        let (lo, hi) = crate::cli::render_args::fit_range(&r).unwrap();
        assert!(
            (lo * 300.0 - 0.85 * 270.0).abs() < 1e-9 && (hi * 300.0 - 1.15 * 270.0).abs() < 1e-9
        );
        let (s3, a3) = at(&[("scene", "checker-spheres"), ("tolerance", "0.5")]);
        let c3 = covers(&s3, &a3).unwrap();
        assert_eq!(range_for(&c3, &now(&s3, &a3).unwrap()), "1:1");
        assert!(check(&with(&[("film", "2.7:270"), ("light", "A")]))
            .unwrap()
            .contains("--light"));
    }
}
