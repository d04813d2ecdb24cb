//! Minimax weights by a smooth, convex stand-in: the largest CIEDE2000 over the stimuli is
//! approached by the p-norm of the errors, `(sum_r e_r^p)^(1/p)`, for `p` rising from
//! [`P_LEVELS`]'s first to its last, each level minimised by damped Newton steps.
//!
//! Each error is taken to first order in the colour, `e_r^2 = d_r' Q_r d_r` (`Q_r` the
//! stimulus's local CIEDE2000 metric, `d_r` its colour's step from the 1 nm colour), and the
//! colour is divided by its light's white on the same nodes, as the renderer divides. In the
//! weights the step is nearly linear, so each level is nearly convex: unlike Lawson's
//! reweighting (a heuristic on a per-channel least squares), where it ends does not depend on
//! where it starts. The true CIEDE2000 of each level's result is measured and the best kept.

use super::estimate::worst;
use super::lsq::{scale_rows, symmetric_gram, weighted_gram, Minimax, Problem, Spectra, Weights};
use nalgebra::{DMatrix, DVector};

/// The p-norm's exponents, one Newton solve each: the last is within `N^(1/p)` (under 3% for a
/// thousand stimuli) of the largest error.
pub(crate) const P_LEVELS: &[f64] = &[8.0, 32.0, 128.0, 256.0];

/// The exponents of a quick solve from a nearby node set's weights (a descent's move).
pub(crate) const QUICK_LEVELS: &[f64] = &[16.0, 64.0, 256.0];

/// A level ends when a step moves the weights by less than this, relatively.
const SETTLED: f64 = 1e-4;

/// Newton steps at most per level.
const NEWTON_STEPS: usize = 40;

/// Halvings of a step at most in its line search.
const HALVINGS: usize = 20;

/// One row's colour step on a node set, divided by its light's white.
struct Step {
    /// `d`: the relative colour minus the 1 nm colour.
    d: [f64; 3],
    /// The undivided colour and the light's Y on the nodes.
    xyz: [f64; 3],
    y: f64,
}

impl Problem<'_> {
    /// Minimax weights for `cols` by the p-norm continuation, from the weights `start` (Lawson's,
    /// say): the iterate with the smallest largest true CIEDE2000, its errors, and row weights
    /// that stand for its active set (`e_r^(p-2)` at the last level, mean 1). `None` when no
    /// iterate gives finite colours.
    pub(crate) fn minimax_pnorm(
        &self,
        cols: &[usize],
        start: &[[f64; 3]],
        levels: &[f64],
    ) -> Option<Minimax> {
        let n = cols.len();
        let mut x = DVector::from_fn(3 * n, |k, _| start[k % n][k / n]);
        let mut best: Option<Minimax> = None;
        let keep = |x: &DVector<f64>, p: f64, best: &mut Option<Minimax>| {
            let w = weights_of(x, n);
            let e = self.errors(cols, &w);
            let max = worst(&e).1;
            if max.is_finite() && best.as_ref().is_none_or(|b| max < b.max) {
                let rows = row_weights(&e, p);
                *best = Some(Minimax {
                    weights: w,
                    errors: e,
                    max,
                    rows,
                });
            }
        };
        keep(&x, 2.0, &mut best);
        for &p in levels {
            for _ in 0..NEWTON_STEPS {
                let Some(next) = self.newton_step(cols, &x, p) else {
                    break;
                };
                let moved = (&next - &x).norm() / x.norm().max(1e-300);
                x = next;
                if moved < SETTLED {
                    break;
                }
            }
            keep(&x, p, &mut best);
        }
        best
    }

    /// One damped Newton step on `sum_r (q_r / s)^(p/2)` (`s` the current largest `q_r`, so the
    /// terms stay finite), with a backtracking line search; `None` when it cannot descend.
    ///
    /// Row `r`'s relative colour moves by `a_i` in channel `c` per unit of `w_ic` and by
    /// `-xyz_c b_i` in every channel per unit of `w_iY` (the division by the white), so its
    /// derivative in block `c` is `e_c a' - [c = Y] xyz b'`, and the Hessian's blocks are sums
    /// of `a a'`, `a b'` and `b b'` with per-row coefficients: eleven weighted Gram products.
    fn newton_step(&self, cols: &[usize], x: &DVector<f64>, p: f64) -> Option<DVector<f64>> {
        let at = self.linearise(cols, x, p / 2.0)?;
        let (a, b) = self.jacobian_factors(cols, &at.steps);
        let k = self.row_coefficients(&at);
        let (h, g) = assemble(&a, &b, &k, cols.len());
        self.line_search(cols, x, &at, &h, &g)
    }

    /// Every row's colour step at `x`, its quadratic error `q_r` and their largest `s`; `None`
    /// when a light has no Y on the nodes or no row errs.
    fn linearise(&self, cols: &[usize], x: &DVector<f64>, half: f64) -> Option<Linearised> {
        let rows = self.row_count();
        let steps: Vec<Step> = (0..rows)
            .map(|r| self.colour_step(r, cols, x))
            .collect::<Option<_>>()?;
        let qs: Vec<f64> = (0..rows).map(|r| self.quad(r, &steps[r].d)).collect();
        let s = qs.iter().fold(0.0f64, |m, &q| m.max(q));
        if !(s.is_finite() && s > 0.0) {
            return None;
        }
        Some(Linearised { steps, qs, s, half })
    }

    /// The rows' spectra on the nodes divided by their light's Y (`a`) and by its square (`b`):
    /// how the relative colour moves with the weights.
    fn jacobian_factors(&self, cols: &[usize], steps: &[Step]) -> (DMatrix<f64>, DMatrix<f64>) {
        let rows = self.row_count();
        let per_row = |f: &dyn Fn(&Step) -> f64| DVector::from_fn(rows, |r, _| f(&steps[r]));
        let a = scale_rows(
            self.gather(cols, Spectra::Values),
            &per_row(&|s| 100.0 / s.y),
        );
        let b = scale_rows(
            self.gather(cols, Spectra::Light),
            &per_row(&|s| 100.0 / (s.y * s.y)),
        );
        (a, b)
    }

    /// Per row: the coefficients of `a a'` in block (c, d), of `a b'` in (c, Y), of `b b'` in
    /// (Y, Y), and of `a` and `b` in the gradient's block c.
    fn row_coefficients(&self, at: &Linearised) -> Coefficients {
        let rows = self.row_count();
        let mut k = Coefficients::zeros(rows);
        let (s, half) = (at.s, at.half);
        for r in 0..rows {
            let t = at.qs[r] / s;
            if t < 1e-12 {
                continue;
            }
            // f = t^half: df/dq and d2f/dq2.
            let f1 = half * t.powf(half - 1.0) / s;
            let f2 = half * (half - 1.0) * t.powf(half - 2.0) / (s * s);
            k.set_row(r, self.row_metric(r), &at.steps[r], [f1, f2]);
        }
        k
    }

    /// The Newton step from the Hessian `h` and gradient `g`, damped by the smallest of three
    /// levels whose Cholesky factor exists, halved until the objective falls enough (Armijo).
    fn line_search(
        &self,
        cols: &[usize],
        x: &DVector<f64>,
        at: &Linearised,
        h: &DMatrix<f64>,
        g: &DVector<f64>,
    ) -> Option<DVector<f64>> {
        let (s, half) = (at.s, at.half);
        let rows = self.row_count();
        let objective = |x: &DVector<f64>| -> f64 {
            (0..rows)
                .map(|r| match self.colour_step(r, cols, x) {
                    Some(st) => (self.quad(r, &st.d) / s).powf(half),
                    None => f64::INFINITY,
                })
                .sum()
        };
        let dim = 3 * cols.len();
        let trace = h.trace() / dim as f64;
        let f0: f64 = at.qs.iter().map(|q| (q / s).powf(half)).sum();
        for damping in [1e-9, 1e-6, 1e-3] {
            let mut hd = h.clone();
            for k in 0..dim {
                hd[(k, k)] += damping * trace + 1e-300;
            }
            let Some(ch) = hd.cholesky() else {
                continue;
            };
            let step = ch.solve(&(-g));
            let slope = g.dot(&step);
            let mut alpha = 1.0;
            for _ in 0..HALVINGS {
                let next = x + alpha * &step;
                if objective(&next) <= f0 + 1e-4 * alpha * slope {
                    return Some(next);
                }
                alpha *= 0.5;
            }
        }
        None
    }

    /// Row `r`'s colour step on nodes `cols` with weights `x` (channel-major); `None` when its
    /// light has no Y on the nodes.
    fn colour_step(&self, r: usize, cols: &[usize], x: &DVector<f64>) -> Option<Step> {
        let n = cols.len();
        let (values, light, target) = self.row_spectra(r);
        let mut xyz = [0.0; 3];
        let mut y = 0.0;
        for (i, &j) in cols.iter().enumerate() {
            for (c, v) in xyz.iter_mut().enumerate() {
                *v += x[c * n + i] * values[j];
            }
            y += x[n + i] * light[j];
        }
        if !(y.is_finite() && y > 0.0) {
            return None;
        }
        Some(Step {
            d: std::array::from_fn(|c| 100.0 * xyz[c] / y - target[c]),
            xyz,
            y,
        })
    }

    /// `d' Q_r d`.
    fn quad(&self, r: usize, d: &[f64; 3]) -> f64 {
        let q = self.row_metric(r);
        (0..3)
            .map(|c| d[c] * (0..3).map(|k| q[c][k] * d[k]).sum::<f64>())
            .sum::<f64>()
            .max(0.0)
    }
}

/// The rows at one iterate: their colour steps, quadratic errors `q_r`, the largest `s`, and
/// half the level's exponent.
struct Linearised {
    steps: Vec<Step>,
    qs: Vec<f64>,
    s: f64,
    half: f64,
}

/// The per-row coefficients of the Hessian's Gram products and of the gradient (see
/// [`Problem::row_coefficients`]).
struct Coefficients {
    kaa: [[DVector<f64>; 3]; 3],
    kab: [DVector<f64>; 3],
    kbb: DVector<f64>,
    ga: [DVector<f64>; 3],
    gb: DVector<f64>,
}

impl Coefficients {
    /// Every coefficient 0 for `rows` rows.
    fn zeros(rows: usize) -> Coefficients {
        let zeros = || DVector::<f64>::zeros(rows);
        Coefficients {
            kaa: std::array::from_fn(|_| std::array::from_fn(|_| zeros())),
            kab: std::array::from_fn(|_| zeros()),
            kbb: zeros(),
            ga: std::array::from_fn(|_| zeros()),
            gb: zeros(),
        }
    }

    /// Row `r`'s coefficients from its metric `q`, its step and `[f1, f2]`, the first and second
    /// derivatives of its term in `q_r`: grad q = 2 J' Q d; Hessian 2 f1 J'QJ (Gauss-Newton) +
    /// f2 grad q grad q'.
    fn set_row(&mut self, r: usize, q: &[[f64; 3]; 3], step: &Step, [f1, f2]: [f64; 2]) {
        let xyz = step.xyz;
        let qv = |v: &[f64; 3]| -> [f64; 3] {
            std::array::from_fn(|c| (0..3).map(|k| q[c][k] * v[k]).sum())
        };
        let (alpha, qx) = (qv(&step.d), qv(&xyz));
        let beta: f64 = (0..3).map(|c| xyz[c] * alpha[c]).sum();
        let xqx: f64 = (0..3).map(|c| xyz[c] * qx[c]).sum();
        for c in 0..3 {
            for d in 0..3 {
                self.kaa[c][d][r] = 2.0 * f1 * q[c][d] + 4.0 * f2 * alpha[c] * alpha[d];
            }
            self.kab[c][r] = -2.0 * f1 * qx[c] - 4.0 * f2 * alpha[c] * beta;
            self.ga[c][r] = 2.0 * f1 * alpha[c];
        }
        self.kbb[r] = 2.0 * f1 * xqx + 4.0 * f2 * beta * beta;
        self.gb[r] = -2.0 * f1 * beta;
    }
}

/// The Hessian (3n x 3n, channel-major blocks) and gradient from the Jacobian factors `a`, `b`
/// and the per-row coefficients `k`.
fn assemble(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    k: &Coefficients,
    n: usize,
) -> (DMatrix<f64>, DVector<f64>) {
    let mut h = DMatrix::<f64>::zeros(3 * n, 3 * n);
    let mut g = DVector::<f64>::zeros(3 * n);
    for c in 0..3 {
        for d in c..3 {
            let mut block = symmetric_gram(a, &k.kaa[c][d]);
            if d == 1 {
                block += weighted_gram(a, &k.kab[c], b);
            }
            if c == 1 {
                block += weighted_gram(b, &k.kab[d], a);
            }
            if c == 1 && d == 1 {
                block += symmetric_gram(b, &k.kbb);
            }
            h.view_mut((c * n, d * n), (n, n)).copy_from(&block);
            if c != d {
                h.view_mut((d * n, c * n), (n, n))
                    .copy_from(&block.transpose());
            }
        }
        let mut gc = a.tr_mul(&k.ga[c]);
        if c == 1 {
            gc += b.tr_mul(&k.gb);
        }
        g.rows_mut(c * n, n).copy_from(&gc);
    }
    (h, g)
}

fn weights_of(x: &DVector<f64>, n: usize) -> Weights {
    (0..n).map(|i| [x[i], x[n + i], x[2 * n + i]]).collect()
}

/// Row weights like Lawson's for an iterate at exponent `p`: `e^(p-2)`, scaled to mean 1 and
/// floored as Lawson floors them.
fn row_weights(e: &[f64], p: f64) -> Vec<f64> {
    let m = worst(e).1.max(1e-300);
    let u: Vec<f64> = e.iter().map(|v| (v / m).powf(p - 2.0)).collect();
    let mean = u.iter().sum::<f64>() / u.len().max(1) as f64;
    u.iter().map(|v| (v / mean.max(1e-300)).max(1e-6)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::Observer;
    use crate::quadrature::lsq::tests::chart;
    use crate::quadrature::lsq::Metric;

    #[test]
    fn no_small_step_of_the_weights_lowers_the_largest_error() {
        // A minimax: along every direction tried, a small step of the weights raises the largest
        // CIEDE2000 or leaves it within the p-norm's N^(1/p) of it (at the errors the fit aims
        // for, a few tenths, where CIEDE2000 is its first-order form).
        let e = chart("D65");
        let p = Problem::new(&e).unwrap();
        let cols = [45, 75, 105, 135, 165, 200, 240, 280];
        let start = p.minimax(&cols, None, Metric::Channels).unwrap();
        let m = p.minimax_pnorm(&cols, &start.weights, P_LEVELS).unwrap();
        assert!(
            m.max <= start.max * 1.001,
            "{} vs Lawson {}",
            m.max,
            start.max
        );
        let slack = (e.len() as f64).powf(1.0 / P_LEVELS[P_LEVELS.len() - 1]);
        let mut seed = 12345u64;
        let mut unit = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for _ in 0..200 {
            let w: Weights = m
                .weights
                .iter()
                .map(|w| w.map(|v| v * (1.0 + 2e-3 * unit())))
                .collect();
            let moved = worst(&p.errors(&cols, &w)).1;
            assert!(moved * slack >= m.max, "{moved} < {} / {slack}", m.max);
        }
    }

    #[test]
    fn the_result_does_not_depend_on_where_it_starts() {
        // From Lawson's weights or from the colour-matching functions times 40 nm cells, the
        // same largest error (the levels are nearly convex in the weights).
        let e = chart("A");
        let p = Problem::new(&e).unwrap();
        let cols = [50, 90, 130, 170, 210, 250];
        let lawson = p.minimax(&cols, None, Metric::Channels).unwrap().weights;
        let cmf = crate::quadrature::Quadrature::uniform(
            e.grid(),
            crate::spectrum::Rule::Riemann,
            Observer::Cie1931,
        )
        .unwrap();
        let plain: Weights = cols
            .iter()
            .map(|&j| cmf.weights()[j].map(|v| 40.0 * v))
            .collect();
        let a = p.minimax_pnorm(&cols, &lawson, P_LEVELS).unwrap().max;
        let b = p.minimax_pnorm(&cols, &plain, P_LEVELS).unwrap().max;
        assert!((a - b).abs() < 0.01 * a, "{a} vs {b}");
    }
}
