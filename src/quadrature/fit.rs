//! A quadrature fitted to a scene: the fewest nodes, and their weights, that keep every stimulus
//! the scene can produce within a colour tolerance of its 1 nm colour.
//!
//! The pipeline, each stage a value that [`Choice`] reports:
//! 1. **lines**: a node on every emission line of the scene's lights that carries at least
//!    [`LINE_SHARE`] of the light's X, Y or Z (a knot of the light standing above the continuum
//!    around it);
//! 2. **greedy nodes**: while the largest error over the fit set or the held-out set exceeds the
//!    target, add the 1 nm wavelength whose least-squares weights ([`super::lsq`]) give the
//!    smallest largest residual, then move each node to the nearby wavelength that lowers it most
//!    (the continuum gets as few nodes as the materials' smoothness allows: a film with fringes
//!    needs more than a pigment);
//! 3. **minimax weights** for each node set tried (Lawson), checked on the held-out set;
//! 4. **pruning**: drop every node the target does not need;
//! 5. **reseeding**: one node fewer from evenly spread seeds, each improved by an exchange and a
//!    descent ([`reseed`]), while the target holds;
//! 6. **final weights**: the kept nodes' weights solved again under CIEDE2000's full metric and
//!    by the p-norm continuation ([`super::pnorm`]), kept if the largest error drops.
//!
//! With a budget of nodes ([`Options::budget`]) a fit that comes out beyond it searches for the
//! best set of exactly the budget, before its final weights ([`within_budget`]).
//!
//! The target is `margin * tolerance`: the stimuli sample the scene's angles, thicknesses and
//! pigments, and the image mixes them, so the estimate keeps room for what the samples miss.

use super::estimate::{worst, Estimator};
use super::lsq::{Metric, Minimax, Problem};
use super::pnorm::{P_LEVELS, QUICK_LEVELS};
use super::progress::{self, Report, Stage};
use super::{Kind, Quadrature};
use crate::error::{Error, Result};
use crate::spectrum::Rule;
use rayon::prelude::*;

/// A knot of a light is a line when the light's excess over its continuum there carries this
/// share of the light's X, Y or Z.
pub const LINE_SHARE: f64 = 0.02;

/// How far (nm) a node may move in one refinement step.
const MOVES_NM: [isize; 8] = [-6, -3, -2, -1, 1, 2, 3, 6];

/// The greedy stage goes on until the largest error is this fraction of the target, so that
/// pruning has nodes to choose among.
const OVERSHOOT: f64 = 0.5;

/// Candidate nodes judged by their minimax error at each greedy step.
const SHORTLIST: usize = 6;

/// The greedy stage stops after this many nodes without a lower largest error.
const PATIENCE: usize = 6;

/// What the fit aims at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// The CIEDE2000 every stimulus must stay within.
    pub tolerance: f64,
    /// The estimate must be at most `margin * tolerance`.
    pub margin: f64,
    /// Give up (and report the best found) beyond this many nodes.
    pub max_nodes: usize,
    /// A renderer's fixed wavelength budget (4 or 8 SIMD lanes, say): no quadrature of more
    /// nodes is chosen. Where the fit needs more, the best set of exactly this many is searched
    /// from fresh starts ([`within_budget`]), and where it misses the target the choice says by
    /// how much. A budget the fit does not need changes nothing.
    pub budget: Option<usize>,
    /// When to stop searching (`--fit-budget`): the fit is an anytime search, and returns the
    /// best quadrature found by then ([`Choice::cut_short`] says it was stopped).
    pub deadline: Option<std::time::Instant>,
}

impl Options {
    /// The defaults for a tolerance: margin 0.8, at most 40 nodes, no budget.
    pub fn new(tolerance: f64) -> Result<Options> {
        check_tolerance(tolerance)?;
        Ok(Options {
            tolerance,
            margin: 0.8,
            max_nodes: 40,
            budget: None,
            deadline: None,
        })
    }
    /// The defaults with at most `nodes` nodes (see [`Options::budget`]).
    pub fn with_budget(tolerance: f64, nodes: usize) -> Result<Options> {
        if nodes == 0 {
            return Err(Error::invalid(
                "a budget of 0 wavelengths: a quadrature needs at least 1",
            ));
        }
        Ok(Options {
            budget: Some(nodes),
            ..Options::new(tolerance)?
        })
    }
    /// The CIEDE2000 the estimate must meet: `margin * tolerance`.
    pub fn target(&self) -> f64 {
        self.margin * self.tolerance
    }
    /// These options with a deadline `seconds` from now (None: no deadline).
    pub fn within_seconds(self, seconds: Option<f64>) -> Options {
        let deadline = seconds.map(|s| {
            let s = std::time::Duration::from_secs_f64(s.clamp(0.0, 1e9));
            std::time::Instant::now() + s
        });
        Options { deadline, ..self }
    }
    /// Whether the deadline has passed.
    pub fn out_of_time(&self) -> bool {
        self.deadline
            .is_some_and(|d| std::time::Instant::now() >= d)
    }
    /// Whether a quadrature of `nodes` nodes is within the budget.
    pub fn within_budget(&self, nodes: usize) -> bool {
        self.budget.is_none_or(|b| nodes <= b)
    }
}

/// A tolerance must be a CIEDE2000 difference in (0, 100].
pub fn check_tolerance(tolerance: f64) -> Result<()> {
    if !(tolerance.is_finite() && tolerance > 0.0 && tolerance <= 100.0) {
        return Err(Error::invalid(format!(
            "--tolerance {}: a CIEDE2000 difference between 0 and 100 (1 is about a just \
             noticeable difference)",
            crate::spectrum::fmt_num(tolerance)
        )));
    }
    Ok(())
}

/// One node count tried.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct Tried {
    /// Number of nodes.
    pub nodes: usize,
    /// Largest CIEDE2000 over the fit set.
    #[serde(rename = "fit_max_dE2000")]
    #[serde(deserialize_with = "crate::quadrature::stored::error_or_infinite")]
    pub fit_max: f64,
    /// Largest CIEDE2000 over the held-out set (0 with none).
    #[serde(rename = "held_out_max_dE2000")]
    #[serde(deserialize_with = "crate::quadrature::stored::error_or_infinite")]
    pub held_out_max: f64,
}

/// What the fit chose, and why.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Choice {
    /// The quadrature chosen.
    pub quadrature: Quadrature,
    /// The CIEDE2000 every stimulus must stay within.
    pub tolerance_de2000: f64,
    /// `margin * tolerance`, what the estimate had to meet.
    pub target_de2000: f64,
    /// The largest error over the fit set and the held-out set: the estimate.
    #[serde(deserialize_with = "crate::quadrature::stored::error_or_infinite")]
    pub estimate_de2000: f64,
    /// Largest CIEDE2000 over the fit set.
    #[serde(rename = "fit_max_dE2000")]
    #[serde(deserialize_with = "crate::quadrature::stored::error_or_infinite")]
    pub fit_max: f64,
    /// Largest CIEDE2000 over the held-out set (0 with none).
    #[serde(rename = "held_out_max_dE2000")]
    #[serde(deserialize_with = "crate::quadrature::stored::error_or_infinite")]
    pub held_out_max: f64,
    /// Mean CIEDE2000 over the held-out set (0 with none).
    #[serde(rename = "held_out_mean_dE2000")]
    #[serde(deserialize_with = "crate::quadrature::stored::error_or_infinite")]
    pub held_out_mean: f64,
    /// The stimulus with the largest error.
    pub worst: String,
    /// Whether the estimate met the target.
    pub met: bool,
    /// The deadline stopped the search before it was done ([`Options::deadline`]).
    pub cut_short: bool,
    /// The nodes put on emission lines.
    pub lines_nm: Vec<f64>,
    /// Node counts on the way, with their errors.
    pub tried: Vec<Tried>,
    /// Stimuli fitted and held out.
    pub stimuli: usize,
    /// Stimuli held out (0 with none).
    pub held_out: usize,
}

/// Grid indices of the lines of the estimator's lights (see [`LINE_SHARE`]).
pub fn lines(est: &Estimator) -> Vec<usize> {
    let grid = est.grid;
    let Ok(reference) = Quadrature::uniform(grid, Rule::Simpson, est.observer) else {
        return Vec::new();
    };
    let mut out: Vec<usize> = Vec::new();
    let mut seen: Vec<&[f64]> = Vec::new();
    for l in &est.light {
        if seen.contains(&&l[..]) {
            continue;
        }
        seen.push(l);
        let total = reference.integrate(l);
        let n = l.len();
        for j in 1..n.saturating_sub(1) {
            if !(l[j] >= l[j - 1] && l[j] >= l[j + 1] && l[j] > l[j - 1].min(l[j + 1])) {
                continue;
            }
            let side = |r: std::ops::Range<usize>| r.map(|k| l[k]).fold(f64::INFINITY, f64::min);
            let base = side(j.saturating_sub(10)..j).max(side(j + 1..(j + 11).min(n)));
            let excess: Vec<f64> = (0..n)
                .map(|k| {
                    if k.abs_diff(j) <= 6 {
                        (l[k] - base).max(0.0)
                    } else {
                        0.0
                    }
                })
                .collect();
            let e = reference.integrate(&excess);
            if (0..3).any(|c| total[c] > 0.0 && e[c] >= LINE_SHARE * total[c]) && !out.contains(&j)
            {
                out.push(j);
            }
        }
    }
    out.sort_unstable();
    out
}

/// Fits the quadrature (see the module docs). `held_out` checks what the fit did not see; a
/// scene without continuous parameters (no film) may have none.
pub fn fit(train: &Estimator, held_out: Option<&Estimator>, opts: &Options) -> Result<Choice> {
    fit_reporting(train, held_out, opts, &progress::quiet)
}

/// [`fit`], telling `report` each stage as it starts.
pub fn fit_reporting(
    train: &Estimator,
    held_out: Option<&Estimator>,
    opts: &Options,
    report: Report,
) -> Result<Choice> {
    check_tolerance(opts.tolerance)?;
    if held_out.is_some_and(|h| train.grid != h.grid || train.observer != h.observer) {
        return Err(Error::invalid(
            "the held-out stimuli are on another grid or for another observer",
        ));
    }
    let mut p = Problem::new(train)?;
    p.deadline = opts.deadline;
    let mut line_nodes = lines(train);
    line_nodes.truncate(opts.max_nodes);
    let target = opts.target();
    let greedy = greedy(&p, held_out, &line_nodes, opts, report)?;
    let mut best = greedy.best;
    if best.max() <= target {
        best = prune(&p, held_out, best, target, &line_nodes, report)?;
        best = reseed(&p, held_out, best, target, &line_nodes, report)?;
    }
    if let Some(b) = opts.budget.filter(|&b| best.cols.len() > b) {
        best = within_budget(&p, held_out, b, &line_nodes, greedy.within, target, report)?;
    }
    report(&Stage::Reweighing {
        nodes: best.cols.len(),
    });
    let best = reweigh(&p, held_out, best)?;
    let mut choice = best.into_choice(train, held_out, opts, &line_nodes);
    choice.tried = greedy.tried;
    choice.cut_short = p.out_of_time();
    Ok(choice)
}

/// What the greedy stage found: the node set with the smallest largest error, the same among
/// the sets within the budget (if there is one), and every node count on the way.
struct Greedy {
    best: Candidate,
    within: Option<Candidate>,
    tried: Vec<Tried>,
}

/// The greedy stage: from the lines, the node that lowers the largest error most is added and
/// the nodes moved into place, until the largest error is [`OVERSHOOT`] of the target, stops
/// falling for [`PATIENCE`] nodes, or the nodes reach [`Options::max_nodes`].
fn greedy(
    p: &Problem,
    held_out: Option<&Estimator>,
    line_nodes: &[usize],
    opts: &Options,
    report: Report,
) -> Result<Greedy> {
    let target = opts.target();
    let mut cols = line_nodes.to_vec();
    let mut tried = Vec::new();
    let mut best: Option<Candidate> = None;
    let mut within: Option<Candidate> = None;
    let mut since_best = 0;
    loop {
        if let Some(c) = Candidate::new(p, held_out, &cols, None)? {
            tried.push(Tried {
                nodes: cols.len(),
                fit_max: c.fit_max,
                held_out_max: c.held_out_max,
            });
            report(&Stage::Greedy {
                nodes: cols.len(),
                max: c.max(),
            });
            // Beyond the target, a few more nodes give pruning room to choose from.
            let done = c.max() <= OVERSHOOT * target;
            let in_budget = opts.budget.is_some_and(|b| cols.len() <= b);
            if in_budget && within.as_ref().is_none_or(|w| c.max() < w.max()) {
                within = Some(c.clone());
            }
            if best.as_ref().is_none_or(|b| c.max() < 0.99 * b.max()) {
                best = Some(c);
                since_best = 0;
            } else {
                since_best += 1;
            }
            // More nodes that fit better but not the held-out set: the fit set is exhausted.
            if done || since_best >= PATIENCE || p.out_of_time() {
                break;
            }
        }
        if cols.len() >= opts.max_nodes {
            break;
        }
        let Some(j) = next_node(p, held_out, &cols, best.as_ref())? else {
            break;
        };
        cols.push(j);
        cols.sort_unstable();
        refine(p, &mut cols, line_nodes);
    }
    let best = best.ok_or_else(|| {
        Error::invalid("no node set gives finite colours: the lights have no visible energy")
    })?;
    Ok(Greedy {
        best,
        within,
        tried,
    })
}

/// The fit came out beyond the `budget`: the best set of exactly the budget from fresh starts
/// ([`best_of_seeds`]), or the greedy's best `within` it if that errs less. The seeds keep the
/// lines where the budget leaves room beside them, and are also searched without them (a
/// budget as small as a lamp's lines is better spent on the continuum too: FL2's three lines
/// alone err 19.8 on `color FL2 --tolerance 0.5`'s colours). Where the best meets the target
/// after all, it is pruned and reseeded as a fit is.
fn within_budget(
    p: &Problem,
    held_out: Option<&Estimator>,
    budget: usize,
    line_nodes: &[usize],
    within: Option<Candidate>,
    target: f64,
    report: Report,
) -> Result<Candidate> {
    let mut fixings: Vec<&[usize]> = vec![&[]];
    if !line_nodes.is_empty() && line_nodes.len() < budget {
        fixings.insert(0, line_nodes);
    }
    let mut best = within;
    for &fixed in &fixings {
        let kept = best.as_ref();
        let aim = SeedAim {
            reach: f64::INFINITY,
            enough: 0.0,
        };
        let searched = best_of_seeds(p, held_out, budget, fixed, aim, kept, report)?;
        let max = kept.map_or(f64::INFINITY, Candidate::max);
        if let Some(c) = searched.filter(|c| c.max() < max) {
            best = Some(c);
        }
    }
    let best = best
        .ok_or_else(|| Error::invalid(format!("no set of {budget} nodes gives finite colours")))?;
    if best.max() > target {
        return Ok(best);
    }
    // Fewer nodes, keeping the lines the fit started from where they are among them.
    let fixed: Vec<usize> = line_nodes
        .iter()
        .copied()
        .filter(|j| best.cols.contains(j))
        .collect();
    let best = prune(p, held_out, best, target, &fixed, report)?;
    reseed(p, held_out, best, target, &fixed, report)
}

/// A node set with its minimax weights and errors.
#[derive(Clone)]
struct Candidate {
    cols: Vec<usize>,
    /// Lawson's row weights.
    rows: Vec<f64>,
    quadrature: Quadrature,
    fit: Vec<f64>,
    fit_max: f64,
    held_out: Vec<f64>,
    held_out_max: f64,
}

impl Candidate {
    /// Minimax weights for `cols` (the search's per-channel metric), Lawson started from
    /// `start`'s row weights.
    fn new(
        p: &Problem,
        held_out: Option<&Estimator>,
        cols: &[usize],
        start: Option<&Candidate>,
    ) -> Result<Option<Candidate>> {
        Candidate::with_metric(p, held_out, cols, start, Metric::Channels)
    }

    /// [`Candidate::new`] with the least squares measured by `metric`.
    fn with_metric(
        p: &Problem,
        held_out: Option<&Estimator>,
        cols: &[usize],
        start: Option<&Candidate>,
        metric: Metric,
    ) -> Result<Option<Candidate>> {
        if cols.is_empty() {
            return Ok(None);
        }
        let Some(m) = p.minimax(cols, start.map(|c| &c.rows[..]), metric) else {
            return Ok(None);
        };
        Candidate::from_minimax(p, held_out, cols, m)
    }

    /// The candidate of weights `m` on `cols`, checked on the held-out set.
    fn from_minimax(
        p: &Problem,
        held_out: Option<&Estimator>,
        cols: &[usize],
        m: Minimax,
    ) -> Result<Option<Candidate>> {
        let (w, fit) = (m.weights, m.errors);
        let nodes = cols.iter().map(|&j| p.est.grid.wavelength_nm(j)).collect();
        let Ok(quadrature) = Quadrature::new(Kind::Scene, p.est.observer, nodes, w) else {
            return Ok(None);
        };
        let h = match held_out {
            Some(e) => e.errors(&quadrature)?,
            None => Vec::new(),
        };
        Ok(Some(Candidate {
            cols: cols.to_vec(),
            rows: m.rows,
            fit_max: worst(&fit).1,
            held_out_max: worst(&h).1,
            fit,
            held_out: h,
            quadrature,
        }))
    }

    fn max(&self) -> f64 {
        self.fit_max.max(self.held_out_max)
    }

    fn into_choice(
        self,
        train: &Estimator,
        held_out: Option<&Estimator>,
        opts: &Options,
        lines: &[usize],
    ) -> Choice {
        let (fi, fmax, _) = worst(&self.fit);
        let (hi, hmax, hmean) = worst(&self.held_out);
        let worst = match held_out {
            Some(h) if hmax > fmax => format!("{} (held out)", h.stimuli()[hi].name),
            _ => train.stimuli()[fi].name.clone(),
        };
        Choice {
            tolerance_de2000: opts.tolerance,
            target_de2000: opts.target(),
            estimate_de2000: self.max(),
            fit_max: fmax,
            held_out_max: hmax,
            held_out_mean: hmean,
            worst,
            met: self.max() <= opts.target(),
            cut_short: false,
            lines_nm: lines.iter().map(|&j| train.grid.wavelength_nm(j)).collect(),
            tried: Vec::new(),
            stimuli: train.len(),
            held_out: held_out.map_or(0, |h| h.len()),
            quadrature: self.quadrature,
        }
    }
}

/// The plain least-squares residual of a node set (infinite when it cannot be solved).
fn residual(p: &Problem, cols: &[usize]) -> f64 {
    p.solve_unit(cols)
        .map_or(f64::INFINITY, |w| p.surrogate(cols, &w))
}

/// The wavelength (grid index) not in `cols` to add: of the [`SHORTLIST`] with the smallest
/// least-squares residual, the one whose minimax weights give the smallest largest error.
fn next_node(
    p: &Problem,
    held_out: Option<&Estimator>,
    cols: &[usize],
    current: Option<&Candidate>,
) -> Result<Option<usize>> {
    let mut ranked: Vec<(usize, f64)> = (0..p.est.grid.len())
        .into_par_iter()
        .filter(|j| !cols.contains(j))
        .map(|j| (j, residual(p, &with(cols, j))))
        .filter(|(_, r)| r.is_finite())
        .collect();
    ranked.sort_by(|a, b| a.1.total_cmp(&b.1));
    ranked.truncate(SHORTLIST);
    let judged = ranked
        .par_iter()
        .map(|&(j, _)| {
            Ok(Candidate::new(p, held_out, &with(cols, j), current)?.map(|c| (j, c.max())))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(judged
        .into_iter()
        .flatten()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(j, _)| j))
}

/// `cols` with `j` added, sorted.
fn with(cols: &[usize], j: usize) -> Vec<usize> {
    let mut c = cols.to_vec();
    c.push(j);
    c.sort_unstable();
    c
}

/// Moves each node (not the lines) to the nearby wavelength that lowers the residual, until no
/// move does.
fn refine(p: &Problem, cols: &mut Vec<usize>, fixed: &[usize]) {
    let len = p.est.grid.len() as isize;
    let mut current = residual(p, cols);
    for _ in 0..8 {
        let mut improved = false;
        for i in 0..cols.len() {
            if fixed.contains(&cols[i]) {
                continue;
            }
            let best = MOVES_NM
                .par_iter()
                .filter_map(|&d| {
                    let j = cols[i] as isize + d;
                    if !(0..len).contains(&j) || cols.contains(&(j as usize)) {
                        return None;
                    }
                    let mut c = cols.clone();
                    c[i] = j as usize;
                    c.sort_unstable();
                    Some((c.clone(), residual(p, &c)))
                })
                .min_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((c, r)) = best {
                if r < current {
                    *cols = c;
                    current = r;
                    improved = true;
                }
            }
        }
        if !improved {
            return;
        }
    }
}

/// Moves each node (not the lines) to the nearby wavelength that lowers the largest error of
/// the minimax weights (fit and held out), until no move does. Per node, the two moves with the
/// smallest least-squares residual are tried.
fn polish(
    p: &Problem,
    held_out: Option<&Estimator>,
    mut best: Candidate,
    fixed: &[usize],
) -> Result<Candidate> {
    let len = p.est.grid.len() as isize;
    for _ in 0..4 {
        let mut improved = false;
        for i in 0..best.cols.len() {
            if fixed.contains(&best.cols[i]) {
                continue;
            }
            let tries: Vec<(Vec<usize>, f64)> = MOVES_NM
                .par_iter()
                .filter_map(|&d| {
                    let j = best.cols[i] as isize + d;
                    if !(0..len).contains(&j) || best.cols.contains(&(j as usize)) {
                        return None;
                    }
                    let mut c = best.cols.clone();
                    c[i] = j as usize;
                    c.sort_unstable();
                    let r = residual(p, &c);
                    Some((c, r))
                })
                .collect();
            let found = judge_best(p, held_out, tries, 2, &best)?;
            if let Some(c) = found.filter(|c| c.max() < best.max()) {
                best = c;
                improved = true;
            }
        }
        if !improved {
            break;
        }
    }
    Ok(best)
}

/// Of node sets ranked by a cheap score (lower first), the `keep` best judged by their own
/// minimax weights (Lawson started from `start`'s): the one with the smallest largest error.
fn judge_best(
    p: &Problem,
    held_out: Option<&Estimator>,
    mut ranked: Vec<(Vec<usize>, f64)>,
    keep: usize,
    start: &Candidate,
) -> Result<Option<Candidate>> {
    ranked.sort_by(|a, b| a.1.total_cmp(&b.1));
    ranked.truncate(keep);
    Ok(ranked
        .par_iter()
        .map(|(c, _)| Candidate::new(p, held_out, c, Some(start)))
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .flatten()
        .min_by(|a, b| a.max().total_cmp(&b.max())))
}

/// Node sets with their minimax weights from scratch, the smallest largest error first (sets
/// that cannot be solved left out).
fn judge_all(
    p: &Problem,
    held_out: Option<&Estimator>,
    sets: Vec<Vec<usize>>,
) -> Result<Vec<Candidate>> {
    let mut judged: Vec<Candidate> = sets
        .par_iter()
        .map(|c| Candidate::new(p, held_out, c, None))
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .flatten()
        .collect();
    judged.sort_by(|a, b| a.max().total_cmp(&b.max()));
    Ok(judged)
}

/// Drops nodes while the target stays met: each round tries every removal (minimax weights
/// from scratch), moves the nodes of the two best into place, and keeps the first that meets
/// the target.
fn prune(
    p: &Problem,
    held_out: Option<&Estimator>,
    mut best: Candidate,
    target: f64,
    fixed: &[usize],
    report: Report,
) -> Result<Candidate> {
    'rounds: while best.cols.len() > 1 && !p.out_of_time() {
        report(&Stage::Pruning {
            nodes: best.cols.len(),
            max: best.max(),
        });
        let removals = judge_all(
            p,
            held_out,
            (0..best.cols.len())
                .map(|i| {
                    let mut c = best.cols.clone();
                    c.remove(i);
                    c
                })
                .collect(),
        )?;
        // The two most promising, with their nodes moved into place, are judged.
        for c in removals.into_iter().take(2) {
            let c = polish(p, held_out, c, fixed)?;
            if c.max() <= target {
                best = c;
                continue 'rounds;
            }
        }
        break;
    }
    Ok(best)
}

/// Where the reseeding stage spreads its seeds: every span from a first node in
/// `SEED_FIRST_NM` to a last in `SEED_LAST_NM` (first, last, step).
const SEED_FIRST_NM: (usize, usize, usize) = (400, 460, 5);
const SEED_LAST_NM: (usize, usize, usize) = (600, 720, 10);

/// Seeds ranked best by a quick minimax that are judged fully, at each node count.
const SEEDS_JUDGED: usize = 12;

/// A node count whose best seed errs more than this times the target is not searched: on the
/// presets no descent brought a seed's largest error below about 0.57 of it (the cylinders
/// under A at 7 nodes, 0.70 to 0.40).
const SEED_REACH: f64 = 2.0;

/// Seeds improved by [`exchange`] and [`descend`] at each node count.
const SEEDS_DESCENDED: usize = 3;

/// Lawson steps of the quick judge of a seed or a move.
const QUICK_LAWSON: usize = 10;

/// A move whose largest error is still this many times the current one after three Lawson
/// steps is given up.
const GIVE_UP: f64 = 2.0;

/// A descent's moves, ranked by a quick Lawson, whose weights are solved by the p-norm.
const MOVES_JUDGED: usize = 3;

/// How far (nm) a descent moves a node, and in what steps: a wide pass, then a fine one.
const DESCENT_PASSES: [(usize, usize); 2] = [(40, 4), (10, 1)];

/// How the free nodes of a seed are spread over its span.
#[derive(Debug, Clone, Copy)]
enum Spread {
    /// Evenly in wavelength: a smooth pigment's continuum.
    Wavelength,
    /// Evenly in wavenumber (1/lambda): a film's fringes, whose period in wavelength grows as
    /// lambda^2.
    Wavenumber,
}

/// The free nodes of one seed: `free` wavelengths from `a` to `b` nm.
fn spread(a: f64, b: f64, free: usize, how: Spread) -> Vec<f64> {
    let t = |i: usize| i as f64 / (free - 1).max(1) as f64;
    (0..free)
        .map(|i| match how {
            Spread::Wavelength => a + (b - a) * t(i),
            Spread::Wavenumber => 1.0 / (1.0 / a + (1.0 / b - 1.0 / a) * t(i)),
        })
        .collect()
}

/// The seeds of the reseeding stage with `count` nodes: the lines plus the other nodes spread
/// over each span of [`SEED_FIRST_NM`] x [`SEED_LAST_NM`], both ways ([`Spread`]).
fn seeds(p: &Problem, fixed: &[usize], count: usize) -> Vec<Vec<usize>> {
    let start_nm = p.est.grid.wavelength_nm(0);
    let len = p.est.grid.len();
    let free = count - fixed.len();
    let mut out: Vec<Vec<usize>> = Vec::new();
    for how in [Spread::Wavelength, Spread::Wavenumber] {
        for a in (SEED_FIRST_NM.0..=SEED_FIRST_NM.1).step_by(SEED_FIRST_NM.2) {
            for b in (SEED_LAST_NM.0..=SEED_LAST_NM.1).step_by(SEED_LAST_NM.2) {
                let mut c: Vec<usize> = fixed.to_vec();
                for nm in spread(a as f64, b as f64, free, how) {
                    let j = ((nm - start_nm + 1e-9).floor().max(0.0) as usize).min(len - 1);
                    if !c.contains(&j) {
                        c.push(j);
                    }
                }
                c.sort_unstable();
                if c.len() == count && !out.contains(&c) {
                    out.push(c);
                }
            }
        }
    }
    out
}

/// After pruning: one node fewer, from fresh starts. Greedy nodes and their pruning keep the
/// shape of the sets they grew from; a smooth scene is often better served by nodes spread
/// evenly over the span the observer sees. Per node count, the best of the [`seeds`]
/// ([`best_of_seeds`]) is kept while it meets the target.
fn reseed(
    p: &Problem,
    held_out: Option<&Estimator>,
    mut best: Candidate,
    target: f64,
    fixed: &[usize],
    report: Report,
) -> Result<Candidate> {
    while best.cols.len() > fixed.len() + 2 && !p.out_of_time() {
        let count = best.cols.len() - 1;
        let aim = SeedAim {
            reach: SEED_REACH * target,
            enough: target,
        };
        match best_of_seeds(p, held_out, count, fixed, aim, Some(&best), report)? {
            Some(c) if c.max() <= target => best = c,
            _ => break,
        }
    }
    Ok(best)
}

/// What [`best_of_seeds`] aims at: seeds whose best judged errs beyond `reach` are not searched
/// (too far for a descent to bring within it), and a set that errs at most `enough` ends the
/// search (pruning needs a set that meets the target, not the best one: the next count starts
/// from fresh seeds anyway).
#[derive(Debug, Clone, Copy)]
struct SeedAim {
    reach: f64,
    enough: f64,
}

/// The best set of `count` nodes from fresh starts: the [`seeds`] ranked by a quick minimax,
/// the [`SEEDS_JUDGED`] best judged fully, and the [`SEEDS_DESCENDED`] best of those improved
/// by [`exchange`] and, unless the exchange already erred at most `aim.enough`, by [`descend`],
/// and [`reweigh`]ed; the first set within `aim.enough` ends the search. None where no seed can
/// be solved, or where the best judged seed errs beyond `aim.reach`. `kept` is the set the
/// caller holds, for the report.
fn best_of_seeds(
    p: &Problem,
    held_out: Option<&Estimator>,
    count: usize,
    fixed: &[usize],
    aim: SeedAim,
    kept: Option<&Candidate>,
    report: Report,
) -> Result<Option<Candidate>> {
    let kept = kept.map(|c| (c.cols.len(), c.max()));
    let mut quick: Vec<(Vec<usize>, f64)> = seeds(p, fixed, count)
        .into_par_iter()
        .filter_map(|c| {
            let m = p.minimax_within(&c, None, QUICK_LAWSON, f64::INFINITY, Metric::Channels)?;
            Some((c, m.max))
        })
        .collect();
    quick.sort_by(|a, b| a.1.total_cmp(&b.1));
    quick.truncate(SEEDS_JUDGED);
    let judged = judge_all(p, held_out, quick.into_iter().map(|(c, _)| c).collect())?;
    if judged.first().is_none_or(|c| c.max() > aim.reach) {
        return Ok(None);
    }
    let mut found: Option<Candidate> = None;
    let of = judged.len().min(SEEDS_DESCENDED);
    for (k, seed) in judged.into_iter().take(SEEDS_DESCENDED).enumerate() {
        if p.out_of_time() {
            break;
        }
        let stage = |search| Stage::Reseeding {
            nodes: seed.cols.len(),
            seed: k + 1,
            of,
            search,
            kept,
        };
        // Two searches from the seed: a wide exchange ranked by a cheap score (pigments'
        // smooth landscapes) and a descent judging every move (films' abrupt ones).
        report(&stage("exchange"));
        let wide = exchange(p, held_out, seed.clone(), fixed)?;
        let better = if wide.max() <= aim.enough {
            wide
        } else {
            report(&stage("descent"));
            let fine = descend(p, held_out, seed, fixed)?;
            if wide.max() < fine.max() {
                wide
            } else {
                fine
            }
        };
        let c = reweigh(p, held_out, better)?;
        if found.as_ref().is_none_or(|f| c.max() < f.max()) {
            found = Some(c);
        }
        if found.as_ref().is_some_and(|f| f.max() <= aim.enough) {
            break;
        }
    }
    Ok(found)
}

/// How far (nm) and in what steps an exchange moves a node.
const EXCHANGE_REACH_NM: usize = 40;
const EXCHANGE_STEP_NM: usize = 2;

/// Moves each node (not the lines) to the wavelength within [`EXCHANGE_REACH_NM`] that gives
/// the smallest largest error with the candidate's Lawson row weights held (a weighted least
/// squares per move); the three best moves are judged by their own minimax weights, and the
/// best is taken if it lowers the largest error. Rounds go on while one does.
fn exchange(
    p: &Problem,
    held_out: Option<&Estimator>,
    mut best: Candidate,
    fixed: &[usize],
) -> Result<Candidate> {
    let len = p.est.grid.len();
    for _ in 0..6 {
        let mut improved = false;
        for i in 0..best.cols.len() {
            if p.out_of_time() {
                return Ok(best);
            }
            let at = best.cols[i];
            if fixed.contains(&at) {
                continue;
            }
            let lo = at.saturating_sub(EXCHANGE_REACH_NM);
            let hi = (at + EXCHANGE_REACH_NM).min(len - 1);
            let moves: Vec<(Vec<usize>, f64)> = (lo..=hi)
                .step_by(EXCHANGE_STEP_NM)
                .filter(|j| !best.cols.contains(j))
                .collect::<Vec<_>>()
                .into_par_iter()
                .filter_map(|j| {
                    let mut c = best.cols.clone();
                    c[i] = j;
                    c.sort_unstable();
                    let w = p.solve_weighted(&c, &best.rows)?;
                    let e = worst(&p.errors(&c, &w)).1;
                    Some((c, e))
                })
                .collect();
            let judged = judge_best(p, held_out, moves, 3, &best)?;
            if let Some(c) = judged.filter(|c| c.max() < 0.999 * best.max()) {
                best = c;
                improved = true;
            }
        }
        if !improved {
            break;
        }
    }
    Ok(best)
}

/// The same nodes with their weights solved again, kept when that lowers the largest error
/// over the fit and held-out sets: by Lawson under CIEDE2000's full metric
/// ([`Metric::Coupled`], started from the candidate's row weights), then by the p-norm
/// continuation ([`super::pnorm`]) from the better weights. The search ranks node sets by the
/// cheaper per-channel metric; the nodes it keeps are then worth the better weights.
fn reweigh(p: &Problem, held_out: Option<&Estimator>, c: Candidate) -> Result<Candidate> {
    let c = match Candidate::with_metric(p, held_out, &c.cols, Some(&c), Metric::Coupled)? {
        Some(better) if better.max() < c.max() => better,
        _ => c,
    };
    let smooth = match p.minimax_pnorm(&c.cols, c.quadrature.weights(), P_LEVELS) {
        Some(m) => Candidate::from_minimax(p, held_out, &c.cols, m)?,
        None => None,
    };
    Ok(match smooth {
        Some(better) if better.max() < c.max() => better,
        _ => c,
    })
}

/// Coordinate descent on the minimax error, in the passes of [`DESCENT_PASSES`] (a reach and a
/// step each): each node (not the lines) tries every wavelength within the reach at the step,
/// ranked by a quick Lawson over the fit set (started from the current row weights); the
/// [`MOVES_JUDGED`] best are solved by a quick p-norm continuation ([`QUICK_LEVELS`]) from
/// Lawson's weights, and the best taken if it lowers the largest error. Rounds go on while a
/// move does. The result is solved fully ([`P_LEVELS`]) and checked on the held-out set.
///
/// Lawson's reweighting, started from another node set's row weights, can stall far from the
/// minimax (nearly twice the p-norm's error on node sets near the best 7 for the cylinders
/// under A), so it only ranks the moves; the p-norm, nearly convex in the weights, judges them.
fn descend(
    p: &Problem,
    held_out: Option<&Estimator>,
    start: Candidate,
    fixed: &[usize],
) -> Result<Candidate> {
    let mut cols = start.cols.clone();
    let mut weights = start.quadrature.weights().to_vec();
    let mut rows = start.rows.clone();
    let mut max = start.fit_max;
    let n = cols.len();
    for pass in DESCENT_PASSES {
        // Rounds over the nodes, at most 12. A node's moves depend only on the nodes and the
        // weights, so once every node has been tried since the last move the pass is over: the
        // rest of the round would try each in the same state again and move none.
        let mut unmoved = 0;
        for k in 0..12 * n {
            if unmoved >= n || p.out_of_time() {
                break;
            }
            let i = k % n;
            let found = if fixed.contains(&cols[i]) {
                None
            } else {
                best_move(p, &cols, i, pass, &rows, max)
            };
            match found.filter(|(_, m)| m.max < 0.999 * max) {
                Some((c, m)) => {
                    (cols, weights, rows, max) = (c, m.weights, m.rows, m.max);
                    unmoved = 0;
                }
                None => unmoved += 1,
            }
        }
    }
    let Some(m) = p.minimax_pnorm(&cols, &weights, P_LEVELS) else {
        return Ok(start);
    };
    Ok(match Candidate::from_minimax(p, held_out, &cols, m)? {
        Some(c) if c.max() < start.max() => c,
        _ => start,
    })
}

/// The best move of node `i` of `cols` within `reach` nm at `step` nm (a descent's pass): the
/// moves ranked by a quick Lawson started from `rows` (given up beyond [`GIVE_UP`] times the
/// current largest error `max`), the [`MOVES_JUDGED`] best solved by a quick p-norm
/// continuation; the nodes and weights of the best, if any can be solved.
fn best_move(
    p: &Problem,
    cols: &[usize],
    i: usize,
    (reach, step): (usize, usize),
    rows: &[f64],
    max: f64,
) -> Option<(Vec<usize>, Minimax)> {
    let at = cols[i];
    let lo = at.saturating_sub(reach);
    let hi = (at + reach).min(p.est.grid.len() - 1);
    let mut ranked: Vec<(Vec<usize>, Minimax)> = (lo..=hi)
        .step_by(step)
        .filter(|j| !cols.contains(j))
        .collect::<Vec<_>>()
        .into_par_iter()
        .filter_map(|j| {
            let mut c = cols.to_vec();
            c[i] = j;
            c.sort_unstable();
            let m = p.minimax_within(
                &c,
                Some(rows),
                QUICK_LAWSON,
                GIVE_UP * max,
                Metric::Channels,
            )?;
            Some((c, m))
        })
        .collect();
    ranked.sort_by(|a, b| a.1.max.total_cmp(&b.1.max));
    ranked.truncate(MOVES_JUDGED);
    ranked
        .into_par_iter()
        .filter_map(|(c, l)| {
            let m = p.minimax_pnorm(&c, &l.weights, QUICK_LEVELS)?;
            Some((c, Minimax { rows: l.rows, ..m }))
        })
        .min_by(|a, b| a.1.max.total_cmp(&b.1.max))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::Observer;
    use crate::quadrature::estimate::White;
    use crate::thinfilm::{Incidence, Index, Layer, Stack};
    use crate::tradeoff::{Factor, Stimulus, Surface};

    /// A 2.0-index film of `d` nm on glass at `deg` degrees under FL2, and FL2 itself.
    fn films(thicknesses: &[f64], angles: &[f64]) -> Vec<Stimulus> {
        let fl2 = crate::data::spectrum("FL2").unwrap().data;
        let mut out = vec![Stimulus::emitter("FL2", fl2.clone())];
        for &d in thicknesses {
            let stack = Stack::new(
                Index::real(1.0).unwrap().into(),
                vec![Layer::new(Index::real(2.0).unwrap().into(), d).unwrap()],
                Index::real(1.5).unwrap().into(),
            );
            for &deg in angles {
                let f = Factor::FilmReflectance(stack.clone(), Incidence::degrees(deg).unwrap());
                let name = format!("{d} nm at {deg} deg");
                out.push(Stimulus::new(name, fl2.clone(), Surface::Product(vec![f])));
            }
        }
        out
    }

    fn estimator(s: &[Stimulus]) -> Estimator {
        Estimator::new(s, Observer::Cie1931, 380.0, 780.0, White::OwnLight).unwrap()
    }

    #[test]
    fn a_fit_holds_on_stimuli_it_never_saw_and_a_starved_one_says_it_misses() {
        let every = |a: f64, b: f64, step: f64| -> Vec<f64> {
            (0..)
                .map(|i| a + step * i as f64)
                .take_while(|&x| x <= b)
                .collect()
        };
        let fit_set = estimator(&films(&every(150.0, 450.0, 10.0), &[0.0, 30.0, 55.0, 75.0]));
        let held = estimator(&films(
            &every(155.0, 445.0, 10.0),
            &[15.0, 45.0, 65.0, 85.0],
        ));
        let opts = Options::new(0.5).unwrap();
        let c = fit(&fit_set, Some(&held), &opts).unwrap();
        assert!(c.met && c.estimate_de2000 <= opts.target(), "{c:?}");
        assert_eq!(c.lines_nm, [435.0, 545.0, 580.0]);
        assert!(c.quadrature.len() <= 16, "{}", c.quadrature);
        // Thicknesses and angles on neither grid.
        let fresh = estimator(&films(&every(153.7, 450.0, 23.1), &[7.0, 38.0, 61.0, 80.0]));
        let e = fresh.errors(&c.quadrature).unwrap();
        let (i, max, _) = worst(&e);
        assert!(max <= opts.tolerance, "{}: {max}", fresh.stimuli()[i].name);
        // Two nodes cannot do it, and the choice says so rather than claiming the tolerance.
        let starved = Options {
            max_nodes: 2,
            ..opts
        };
        let c = fit(&fit_set, Some(&held), &starved).unwrap();
        assert!(!c.met && c.estimate_de2000 > opts.tolerance && c.quadrature.len() <= 2);
    }

    /// A budget the fit does not need changes nothing; a tighter one bounds the nodes, says it
    /// misses, and keeps at least as good a set as the greedy stage found within it.
    #[test]
    fn a_budget_bounds_the_nodes_and_a_tight_one_reports_the_miss() {
        let thicknesses: Vec<f64> = (0..=12).map(|i| 150.0 + 25.0 * i as f64).collect();
        let fit_set = estimator(&films(&thicknesses, &[0.0, 40.0, 70.0]));
        let opts = Options::new(0.5).unwrap();
        let free = fit(&fit_set, None, &opts).unwrap();
        let n = free.quadrature.len();
        assert!(free.met && n > 5, "{n} nodes: {free:?}");
        let roomy = fit(&fit_set, None, &Options::with_budget(0.5, n).unwrap()).unwrap();
        assert_eq!(roomy.quadrature.nodes_nm(), free.quadrature.nodes_nm());
        let b = n - 2;
        let tight = fit(&fit_set, None, &Options::with_budget(0.5, b).unwrap()).unwrap();
        assert!(tight.quadrature.len() <= b, "{}", tight.quadrature);
        assert!(
            !tight.met && tight.estimate_de2000 > opts.target(),
            "{tight:?}"
        );
        // The estimate is the quadrature's own error over the stimuli.
        let (_, max, _) = worst(&fit_set.errors(&tight.quadrature).unwrap());
        assert!((max - tight.estimate_de2000).abs() < 1e-9 * max, "{max}");
        let greedy_within = tight
            .tried
            .iter()
            .filter(|t| t.nodes <= b)
            .map(|t| t.fit_max)
            .fold(f64::INFINITY, f64::min);
        assert!(
            tight.estimate_de2000 <= greedy_within,
            "{} against the greedy's {greedy_within}",
            tight.estimate_de2000
        );
        assert!(Options::with_budget(0.5, 0).is_err());
    }

    #[test]
    fn a_fit_reports_its_stages_in_order_ending_with_the_nodes_it_keeps() {
        let thicknesses: Vec<f64> = (0..=10).map(|i| 150.0 + 30.0 * i as f64).collect();
        let fit_set = estimator(&films(&thicknesses, &[0.0, 45.0, 75.0]));
        let stages = std::cell::RefCell::new(Vec::new());
        let report = |s: &Stage| stages.borrow_mut().push(s.clone());
        let c = fit_reporting(&fit_set, None, &Options::new(0.5).unwrap(), &report).unwrap();
        let stages = stages.into_inner();
        assert!(matches!(stages[0], Stage::Greedy { .. }), "{stages:?}");
        assert_eq!(
            stages.last(),
            Some(&Stage::Reweighing {
                nodes: c.quadrature.len()
            })
        );
        // The greedy stage adds nodes one at a time, then pruning starts from as many or fewer.
        let greedy: Vec<usize> = stages
            .iter()
            .filter_map(|s| match s {
                Stage::Greedy { nodes, .. } => Some(*nodes),
                _ => None,
            })
            .collect();
        assert!(greedy.windows(2).all(|w| w[1] == w[0] + 1), "{greedy:?}");
        assert!(stages.iter().any(|s| matches!(s, Stage::Pruning { .. })));
    }

    #[test]
    fn seeds_spread_evenly_in_wavelength_or_in_wavenumber() {
        let even = spread(400.0, 700.0, 4, Spread::Wavelength);
        assert_eq!(even, [400.0, 500.0, 600.0, 700.0]);
        let k = spread(400.0, 700.0, 4, Spread::Wavenumber);
        assert!((k[0] - 400.0).abs() < 1e-9 && (k[3] - 700.0).abs() < 1e-9);
        let steps: Vec<f64> = k.windows(2).map(|p| 1.0 / p[0] - 1.0 / p[1]).collect();
        assert!(steps.iter().all(|s| (s - steps[0]).abs() < 1e-12), "{k:?}");
        // A film's fringe period grows as lambda^2: so do these gaps.
        assert!(k[1] - k[0] < k[2] - k[1] && k[2] - k[1] < k[3] - k[2]);
    }

    #[test]
    fn lines_are_the_knots_that_carry_a_share_of_the_light() {
        let one = |name: &str| {
            let l = crate::data::spectrum(name).unwrap().data;
            lines(&estimator(&[Stimulus::emitter(name, l)]))
                .iter()
                .map(|&j| 380 + j)
                .collect::<Vec<_>>()
        };
        assert_eq!(one("FL2"), [435, 545, 580]);
        assert_eq!(one("lps"), [590]);
        assert!(one("A").is_empty() && one("D65").is_empty());
    }
}
