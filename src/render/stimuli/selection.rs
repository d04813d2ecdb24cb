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

use super::coverage::{self, Miss};
use super::{pixels, texels, TexelChoice};
use crate::colorimetry::{Observer, RgbSpace, Xyz};
use crate::error::Result;
use crate::quadrature::choose::{self, Family, ImageCheck, Selection, UniformChoice};
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
    ///
    /// ```no_run
    /// use specmap::colorimetry::{Observer, RgbSpace};
    /// use specmap::quadrature::choose::Family;
    /// use specmap::quadrature::fit::Options;
    /// use specmap::render::Preset;
    ///
    /// // The fewest nodes that keep the chart within 1 dE2000 of its 1 nm render.
    /// let scene = Preset::Chart.scene(96, 64, "D65", None)?;
    /// let opts = Options::new(1.0)?;
    /// let s = scene.choose_quadrature(Observer::Cie1931, RgbSpace::SRGB, Family::Scene, &opts)?;
    /// println!("{} nodes: {}", s.quadrature.len(), s.reason);
    /// # Ok::<(), specmap::error::Error>(())
    /// ```
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

    /// [`Scene::choose_quadrature_reporting`] without the timing: up to [`REFITS`] refits,
    /// each round a fit, the check on every texel, the image's, and a narrower margin.
    fn choose(
        &self,
        observer: Observer,
        space: RgbSpace,
        family: Family,
        opts: &Options,
        report: Report,
    ) -> Result<Selection> {
        let asked = Asked {
            observer,
            space,
            family,
            opts,
            report,
        };
        let mut rounds = Rounds::new(self, asked);
        for round in 0..=REFITS {
            match rounds.round(round)? {
                Next::Done(s) => return Ok(*s),
                Next::Stop => break,
                Next::Refit => {}
            }
        }
        rounds.finish()
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

/// What the caller asked the choice for.
struct Asked<'a> {
    observer: Observer,
    space: RgbSpace,
    family: Family,
    opts: &'a Options,
    report: Report<'a>,
}

/// What a round of [`Scene::choose`] leads to.
enum Next {
    /// This selection is the choice.
    Done(Box<Selection>),
    /// No refit can help: the best so far is.
    Stop,
    /// A refit, with more texels or a narrower margin.
    Refit,
}

/// The rounds of one choice: what every round shares (the maps the image can show, their
/// texels, the image's 1 nm render once made) and what they have found.
struct Rounds<'a> {
    scene: &'a Scene,
    asked: Asked<'a>,
    white: Xyz,
    /// The caller's target.
    target: f64,
    /// Whether a lighting is a map; of its own spectra.
    any_map: bool,
    own_map: bool,
    /// What the image can show of each seen map.
    seen: Vec<Option<CoeffMap>>,
    /// The image's 1 nm render, once a round made it.
    reference: Option<pixels::Reference>,
    texels: TexelChoice,
    /// The caller's options, the margin narrowed by the rounds so far.
    fit_opts: Options,
    /// The selection that came closest to passing, and how far it was.
    best: Option<(f64, Selection)>,
    /// The uniform grid beside the choice: the one for the caller's margin.
    uniform: Option<UniformChoice>,
}

impl<'a> Rounds<'a> {
    /// The rounds of `scene`'s choice as `asked`.
    fn new(scene: &'a Scene, asked: Asked<'a>) -> Rounds<'a> {
        let white = asked.space.xyz_from_rgb([1.0; 3]);
        let target = asked.opts.target();
        let map = |own: bool| {
            scene.lightings.iter().any(|l| {
                matches!(l.environment, Environment::Map(_))
                    && (!own || matches!(l.spectra, LightSpectra::Own { .. }))
            })
        };
        let fit_opts = *asked.opts;
        Rounds {
            scene,
            white,
            target,
            any_map: map(false),
            own_map: map(true),
            seen: scene.visible_seens(),
            reference: None,
            texels: TexelChoice::default(),
            fit_opts,
            best: None,
            uniform: None,
            asked,
        }
    }

    /// Round `round`: a fit, then (under a map) every texel the image can show, then where
    /// the texels pass the image itself; a miss kept if it is the closest yet, and the margin
    /// narrowed for the next round.
    fn round(&mut self, round: usize) -> Result<Next> {
        let selection = self.fit()?;
        if selection.kind != Kind::Scene {
            return Ok(Next::Done(Box::new(self.not_a_scene_fit(selection, round))));
        }
        let fitted = selection.estimate_de2000;
        let (mut selection, misses) = self.on_every_texel(selection, round)?;
        let every = selection.estimate_de2000;
        // The image itself, where the texels pass.
        if every <= self.target {
            // Under a map the reason already counts the refits.
            self.check_image(&mut selection, (!self.any_map).then_some(round))?;
            if selection.met {
                return Ok(Next::Done(Box::new(selection)));
            }
        }
        let opts = self.asked.opts;
        // How far this round is from passing, relative to what it must meet.
        let image = selection.image.map_or(0.0, |c| c.max_de2000);
        let excess = (every / self.target).max(image / opts.tolerance);
        let nodes = selection.quadrature.len();
        // The fit missed its own (perhaps narrowed) target at the budget's limit.
        let at_budget = opts.budget.is_some_and(|b| nodes >= b)
            && selection.scene.as_ref().is_some_and(|c| !c.met);
        if self.best.as_ref().is_none_or(|b| excess < b.0) {
            self.best = Some((excess, selection));
        }
        // A fit that misses the target itself (nothing meets it and the scene fit errs
        // least, or a budget of nodes binds) would only miss a narrower one: neither texels
        // added nor a refit can help. Without a map, that is every miss.
        if fitted > self.target || at_budget || self.fit_opts.out_of_time() {
            return Ok(Next::Stop);
        }
        if round < REFITS {
            let missed = Missed {
                round: round + 1,
                nodes,
                fitted,
                every,
                image,
            };
            self.narrow(&missed, misses);
        }
        Ok(Next::Refit)
    }

    /// One selection over the stimuli with the texels so far, beside the first round's
    /// uniform grid.
    fn fit(&mut self) -> Result<Selection> {
        let fitting = Fitting {
            seen: &self.seen,
            observer: self.asked.observer,
            white: self.white,
            family: self.asked.family,
            opts: &self.fit_opts,
            report: self.asked.report,
        };
        let mut selection = self
            .scene
            .fit_texels(&fitting, &mut self.texels, self.own_map)?;
        match &self.uniform {
            None => self.uniform = Some(selection.uniform.clone()),
            Some(u) => selection.uniform = u.clone(),
        }
        Ok(selection)
    }

    /// A selection that is not a scene fit is final: under a map, with the caller's target and
    /// a reason saying so.
    fn not_a_scene_fit(&self, selection: Selection, round: usize) -> Selection {
        if !self.any_map {
            return selection;
        }
        let e = selection.estimate_de2000;
        honest(selection, e, self.target, "", round)
    }

    /// Under a map, the selection judged on every texel the image can show, and the worst
    /// texels it misses; without one, judged by the caller's target (after a narrowed refit
    /// too).
    fn on_every_texel(
        &self,
        mut selection: Selection,
        round: usize,
    ) -> Result<(Selection, Vec<Miss>)> {
        if !self.any_map {
            selection.target_de2000 = self.target;
            return Ok((selection, Vec::new()));
        }
        let fitted = selection.estimate_de2000;
        let q = &selection.quadrature;
        let (max, misses) =
            coverage::worst_texels(self.scene, &self.seen, q, self.white, ADDED_PER_ROUND)?;
        let every = max.max(fitted);
        let through = misses
            .first()
            .map_or(String::new(), |m| format!("through {}", m.surface));
        Ok((
            honest(selection, every, self.target, &through, round),
            misses,
        ))
    }

    /// `s` checked on the image (its 1 nm render made once), after `refits` unless the reason
    /// counts them already.
    fn check_image(&mut self, s: &mut Selection, refits: Option<usize>) -> Result<()> {
        let Asked {
            observer,
            space,
            report,
            ..
        } = self.asked;
        let r = self
            .scene
            .image_reference(self.reference.take(), observer, space, report)?;
        let check = r.check(self.scene, &s.quadrature)?;
        self.reference = Some(r);
        on_the_image(s, check, refits);
        Ok(())
    }

    /// The next round's margin: narrowed by the gap between the fit's estimate and every
    /// texel's (the worst texels joining the fit), or else by the image's excess.
    fn narrow(&mut self, m: &Missed, misses: Vec<Miss>) {
        let report = self.asked.report;
        let narrow = if m.every > self.target {
            report(&Stage::Texels {
                round: m.round,
                nodes: m.nodes,
                fitted: m.fitted,
                every: m.every,
            });
            self.texels
                .added
                .extend(misses.into_iter().map(|m| (m.lighting, m.coefficients)));
            m.fitted / m.every
        } else {
            let tolerance = self.asked.opts.tolerance;
            report(&Stage::ImageMiss {
                round: m.round,
                nodes: m.nodes,
                image: m.image,
                tolerance,
            });
            tolerance / m.image
        };
        self.fit_opts.margin *= narrow.clamp(0.7, 0.9);
    }

    /// The closest selection, its image checked if no round did (a miss is final: what its
    /// image errs is reported too).
    fn finish(mut self) -> Result<Selection> {
        let mut s = self.best.take().expect("a round ran").1;
        if s.image.is_none() {
            self.check_image(&mut s, None)?;
        }
        Ok(s)
    }
}

/// How a round missed, for the next round's report: its number, nodes, the fit's estimate,
/// every texel's and the image's error.
struct Missed {
    round: usize,
    nodes: usize,
    fitted: f64,
    every: f64,
    image: f64,
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
