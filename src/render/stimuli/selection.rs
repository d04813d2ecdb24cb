//! `--tolerance` on a scene: the cheapest quadrature over its stimuli
//! ([`crate::quadrature::choose`]), and under a map (RGB or of its own spectra), rounds that
//! make the texels the fit sees stand for the whole map: under a map of its own spectra,
//! held-out texels join the fit where it misses on them; then every texel of the map the image
//! can show is checked ([`super::coverage`]); where the quadrature misses on some, the worst
//! join the fit and the fit's margin narrows by the gap between its estimate and theirs. The
//! estimate reported is the largest over every texel. Last, with or without a map, the image
//! itself is rendered on the quadrature and at 1 nm ([`super::pixels`]); where it errs beyond
//! the tolerance, the margin narrows by the ratio and the fit runs again. A fit that misses its
//! own target (nothing meets it, or a budget of nodes binds) is final, and its image is checked
//! for the report.

use super::{coverage, pixels, texels, TexelChoice};
use crate::colorimetry::{Observer, RgbSpace, Xyz};
use crate::error::Result;
use crate::quadrature::choose::{self, Family, ImageCheck, Selection};
use crate::quadrature::estimate::White;
use crate::quadrature::fit::Options;
use crate::quadrature::progress::{Report, Stage, Timings};
use crate::quadrature::{nodes_verb, Kind};
use crate::render::env::CoeffMap;
use crate::render::{Environment, LightSpectra, Scene};

/// Texels added to the fit per round of [`coverage`], and the most refits (after the texels'
/// check or the image's).
const ADDED_PER_ROUND: usize = 8;
const REFITS: usize = 3;

impl Scene {
    /// `--tolerance`: the cheapest quadrature over the scene's stimuli in the output `space`
    /// (see the module docs).
    pub fn choose_quadrature(
        &self,
        observer: Observer,
        space: RgbSpace,
        family: Family,
        opts: &Options,
    ) -> Result<Selection> {
        let quiet = &crate::quadrature::progress::quiet;
        self.choose_quadrature_reporting(observer, space, family, opts, quiet)
    }

    /// [`Scene::choose_quadrature`], telling `report` the scene fit's stages.
    pub fn choose_quadrature_reporting(
        &self,
        observer: Observer,
        space: RgbSpace,
        family: Family,
        opts: &Options,
        report: Report,
    ) -> Result<Selection> {
        let t0 = std::time::Instant::now();
        let timings = Timings::new();
        let report = &|s: &Stage| {
            timings.mark(s);
            report(s)
        };
        let mut s = self.choose(observer, space, family, opts, report)?;
        s.stages = timings.finish();
        s.seconds = t0.elapsed().as_secs_f64();
        Ok(s)
    }

    /// [`Scene::choose_quadrature_reporting`] without the timing.
    fn choose(
        &self,
        observer: Observer,
        space: RgbSpace,
        family: Family,
        opts: &Options,
        report: Report,
    ) -> Result<Selection> {
        let white = space.xyz_from_rgb([1.0; 3]);
        let target = opts.target();
        let map = |own: bool| {
            self.lightings.iter().any(|l| {
                matches!(l.environment, Environment::Map(_))
                    && (!own || matches!(l.spectra, LightSpectra::Own { .. }))
            })
        };
        let (any_map, own_map) = (map(false), map(true));
        // What the image can show of each seen map, and its 1 nm render: the same every round.
        let seen = self.visible_seens();
        let mut reference: Option<pixels::Reference> = None;
        let mut texels = TexelChoice::default();
        let mut fit_opts = *opts;
        let mut best: Option<(f64, Selection)> = None;
        // The uniform grid beside the choice is the one for the caller's margin.
        let mut uniform = None;
        for round in 0..=REFITS {
            let fitting = Fitting {
                seen: &seen,
                observer,
                white,
                family,
                opts: &fit_opts,
                report,
            };
            let mut selection = self.fit_texels(&fitting, &mut texels, own_map)?;
            match &uniform {
                None => uniform = Some(selection.uniform.clone()),
                Some(u) => selection.uniform = u.clone(),
            }
            if selection.kind != Kind::Scene {
                return Ok(if any_map {
                    let e = selection.estimate_de2000;
                    honest(selection, e, target, "", round)
                } else {
                    selection
                });
            }
            // Every texel the image can show (under a map).
            let fitted = selection.estimate_de2000;
            let (mut selection, misses) = if any_map {
                let q = &selection.quadrature;
                let (max, misses) = coverage::worst_texels(self, &seen, q, white, ADDED_PER_ROUND)?;
                let every = max.max(fitted);
                let through = misses
                    .first()
                    .map_or(String::new(), |m| format!("through {}", m.surface));
                (honest(selection, every, target, &through, round), misses)
            } else {
                // Judged by the caller's target, as under a map, after a narrowed refit too.
                selection.target_de2000 = target;
                (selection, Vec::new())
            };
            let every = selection.estimate_de2000;
            // The image itself, where the texels pass.
            if every <= target {
                let r = self.image_reference(reference.take(), observer, space, report)?;
                let check = r.check(self, &selection.quadrature)?;
                reference = Some(r);
                // Under a map the reason already counts the refits.
                let refits = (!any_map).then_some(round);
                on_the_image(&mut selection, check, refits);
                if selection.met {
                    return Ok(selection);
                }
            }
            // How far this round is from passing, relative to what it must meet.
            let image = selection.image.map_or(0.0, |c| c.max_de2000);
            let excess = (every / target).max(image / opts.tolerance);
            let nodes = selection.quadrature.len();
            // The fit missed its own (perhaps narrowed) target at the budget's limit.
            let at_budget = opts.budget.is_some_and(|b| nodes >= b)
                && selection.scene.as_ref().is_some_and(|c| !c.met);
            if best.as_ref().is_none_or(|b| excess < b.0) {
                best = Some((excess, selection));
            }
            // A fit that misses the target itself (nothing meets it and the scene fit errs
            // least, or a budget of nodes binds) would only miss a narrower one: neither texels
            // added nor a refit can help. Without a map, that is every miss.
            if fitted > target || at_budget || fit_opts.out_of_time() {
                break;
            }
            if round < REFITS {
                let round = round + 1;
                let narrow = if every > target {
                    report(&Stage::Texels {
                        round,
                        nodes,
                        fitted,
                        every,
                    });
                    texels
                        .added
                        .extend(misses.into_iter().map(|m| (m.lighting, m.coefficients)));
                    fitted / every
                } else {
                    report(&Stage::ImageMiss {
                        round,
                        nodes,
                        image,
                        tolerance: opts.tolerance,
                    });
                    opts.tolerance / image
                };
                fit_opts.margin *= narrow.clamp(0.7, 0.9);
            }
        }
        let mut s = best.expect("a round ran").1;
        // A miss is final: what its image errs is reported too (no refit follows).
        if s.image.is_none() {
            let r = self.image_reference(reference, observer, space, report)?;
            let check = r.check(self, &s.quadrature)?;
            on_the_image(&mut s, check, None);
        }
        Ok(s)
    }

    /// The pixels the last check of a fit renders at 1 nm ([`pixels`]).
    pub fn image_check_pixels(&self) -> usize {
        pixels::lattice_len(self.width, self.height)
    }

    /// The image's 1 nm render on its lattice: `made` if an earlier round made it.
    fn image_reference(
        &self,
        made: Option<pixels::Reference>,
        observer: Observer,
        space: RgbSpace,
        report: Report,
    ) -> Result<pixels::Reference> {
        match made {
            Some(r) => Ok(r),
            None => {
                let pixels = pixels::lattice_len(self.width, self.height);
                report(&Stage::Image { pixels });
                pixels::Reference::new(self, observer, space)
            }
        }
    }

    /// One selection over the stimuli with `texels`; under a spectral map, while the fit misses
    /// on the held-out texels, half of them join the fit (up to [`texels::MAX_FITTED`]).
    fn fit_texels(
        &self,
        f: &Fitting,
        texels: &mut TexelChoice,
        own_map: bool,
    ) -> Result<Selection> {
        let mut round = 0;
        loop {
            (f.report)(&Stage::Stimuli { round });
            round += 1;
            let s = self.stimuli_shown(texels, f.seen)?;
            let scene = choose::Scene {
                fit: &s.fit,
                held_out: &s.held_out,
                observer: f.observer,
                start_nm: 380.0,
                end_nm: 780.0,
                white: White::Fixed(f.white),
            };
            let selection = choose::select_reporting(&scene, f.family, f.opts, f.report)?;
            let missed = selection.scene.as_ref().is_some_and(|c| !c.met);
            // Texels added to the fit cannot buy nodes a budget withholds.
            let bound = f
                .opts
                .budget
                .is_some_and(|b| selection.quadrature.len() >= b);
            let more = texels.fitted < texels::MAX_FITTED && !f.opts.out_of_time();
            if !(own_map && missed && !bound && more) {
                return Ok(selection);
            }
            texels.fitted += texels::CHECKED / 2;
        }
    }
}

/// What one selection is made with.
struct Fitting<'a> {
    seen: &'a [Option<CoeffMap>],
    observer: Observer,
    white: Xyz,
    family: Family,
    opts: &'a Options,
    report: Report<'a>,
}

/// `s` with the image's `check`: met only if the image is within the tolerance too, and the
/// reason saying so (and after how many `refits`, unless it says already).
fn on_the_image(s: &mut Selection, check: ImageCheck, refits: Option<usize>) {
    s.image = Some(check);
    let max = check.max_de2000;
    let within = max <= s.tolerance_de2000;
    let lattice = check.lattice();
    let after = refits.map_or(String::new(), |k| format!(" ({})", refit_count(k)));
    s.reason = if within || !s.met {
        // A miss keeps its reason: the image is what it errs on the pixels.
        format!(
            "{}; the image errs at most {max:.3} on {lattice}{after}",
            s.reason
        )
    } else {
        format!(
            "{} {max:.3} on the image ({lattice}), beyond the tolerance{after}",
            nodes_verb(s.quadrature.len(), "err"),
        )
    };
    s.met &= within;
}

/// "no refit", "1 refit", "k refits".
fn refit_count(refits: usize) -> String {
    match refits {
        0 => "no refit".to_string(),
        1 => "1 refit".to_string(),
        k => format!("{k} refits"),
    }
}

/// `s` with its estimate raised to `every` (the largest over every texel the image can show,
/// worst `through` a surface) after `refits` rounds, the caller's target, and a reason saying
/// so.
fn honest(mut s: Selection, every: f64, target: f64, through: &str, refits: usize) -> Selection {
    s.estimate_de2000 = every;
    s.target_de2000 = target;
    s.met = every <= target;
    if s.kind == Kind::Scene {
        let n = s.quadrature.len();
        let u = &s.uniform;
        let uniform = if u.met {
            format!("the cheapest uniform grid that meets it has {}", u.samples)
        } else {
            "no uniform grid meets it".into()
        };
        let refits = refit_count(refits);
        s.reason = if s.met {
            format!(
                "{} the target on every texel the image can show ({refits}); {uniform}",
                nodes_verb(n, "meet")
            )
        } else {
            format!(
                "{} the target on the map's texels ({refits}), worst {every:.3} {through}",
                nodes_verb(n, "miss")
            )
        };
    }
    s
}
