//! The weights of a node set: least squares over a set of stimuli, scaled so that a residual
//! is a CIELAB distance to first order, then Lawson's reweighting towards the smallest largest
//! CIEDE2000 (minimax).
//!
//! Per channel `c` and node set `N`, the weights solve
//! `min sum_r u_r s_rc^2 (sum_{i in N} w_ic v_r(lambda_i) - X_rc)^2 + mu sum_i (w_ic - p_ic)^2`:
//! `v_r` a stimulus at 1 nm (on the scale where its light's white is Y = 100), `X_rc` its colour
//! at 1 nm by Simpson's rule, `s_rc` how far CIELAB moves per unit of that channel there (over
//! CIEDE2000's lightness and chroma weights), `u_r` Lawson's row weights, and a faint pull (`mu`)
//! towards `p_ic = cmf_c(lambda_i)` times the width of the interval node `i` stands for, which
//! only matters where the stimuli leave a weight free. Each distinct light's white is a row too,
//! weighted as several stimuli, since every colour is divided by it.

use super::estimate::{worst, Estimator};
use super::Quadrature;
use crate::colorimetry::{Lab, Xyz};
use crate::error::Result;
use crate::spectrum::Rule;
use nalgebra::{DMatrix, DVector};

/// Lawson iterations at most per node set (it stops after six without progress).
const LAWSON_ITERATIONS: usize = 40;

/// Relative weight of the pull towards `cmf * cell width`.
const PRIOR: f64 = 1e-7;

/// How much more a light's white weighs than one stimulus.
const WHITE_WEIGHT: f64 = 4.0;

/// One row of the least squares: a stimulus (or a light's white) at 1 nm.
struct Row<'a> {
    values: &'a [f64],
    target: [f64; 3],
    /// How far CIELAB moves per unit of X, Y, Z.
    scale: [f64; 3],
}

/// The least-squares problem of an estimator's stimuli.
pub(crate) struct Problem<'a> {
    pub(crate) est: &'a Estimator,
    rows: Vec<Row<'a>>,
    /// Rows that are stimuli (the rest are whites).
    stimuli: usize,
    /// `cmf_c` times the Simpson weight at 1 nm, for the prior.
    cmf: Vec<[f64; 3]>,
    /// Per channel, the normal equations over every 1 nm wavelength with unit row weights: a
    /// node set's are their sub-blocks (the search reads them).
    gram: [(DMatrix<f64>, DVector<f64>); 3],
}

/// Weights per node.
pub(crate) type Weights = Vec<[f64; 3]>;

impl<'a> Problem<'a> {
    pub(crate) fn new(est: &'a Estimator) -> Result<Problem<'a>> {
        let reference = Quadrature::uniform(est.grid, Rule::Simpson, est.observer)?;
        let mut rows: Vec<Row> = (0..est.len())
            .map(|s| Row {
                values: &est.value[s],
                target: est.reference[s].0,
                scale: lab_scale(est.reference[s], est.white[s]),
            })
            .collect();
        let stimuli = rows.len();
        let mut seen: Vec<&[f64]> = Vec::new();
        for s in 0..est.len() {
            let l = &est.light[s][..];
            if !seen.contains(&l) {
                seen.push(l);
                let w = Xyz(reference.integrate(l));
                rows.push(Row {
                    values: l,
                    target: w.0,
                    scale: lab_scale(w, est.white[s]).map(|v| WHITE_WEIGHT.sqrt() * v),
                });
            }
        }
        let gram = std::array::from_fn(|c| {
            let j = est.grid.len();
            let a = DMatrix::from_fn(rows.len(), j, |r, k| rows[r].scale[c] * rows[r].values[k]);
            let b = DVector::from_fn(rows.len(), |r, _| rows[r].scale[c] * rows[r].target[c]);
            (a.tr_mul(&a), a.tr_mul(&b))
        });
        Ok(Problem {
            est,
            rows,
            stimuli,
            cmf: reference.weights().to_vec(),
            gram,
        })
    }

    /// Plain least squares (unit row weights) for `cols`, from the precomputed equations.
    pub(crate) fn solve_unit(&self, cols: &[usize]) -> Option<Weights> {
        let n = cols.len();
        let eq: [(DMatrix<f64>, DVector<f64>); 3] = std::array::from_fn(|c| {
            let (g, h) = &self.gram[c];
            (
                DMatrix::from_fn(n, n, |a, b| g[(cols[a], cols[b])]),
                DVector::from_fn(n, |a, _| h[cols[a]]),
            )
        });
        self.solve(cols, eq)
    }

    /// Least squares for `cols` with row weights `u` on the stimuli (whites: their mean).
    pub(crate) fn solve_weighted(&self, cols: &[usize], u: &[f64]) -> Option<Weights> {
        let mean = u.iter().sum::<f64>() / u.len().max(1) as f64;
        let root: Vec<f64> = (0..self.rows.len())
            .map(|r| if r < self.stimuli { u[r] } else { mean }.sqrt())
            .collect();
        let eq: [(DMatrix<f64>, DVector<f64>); 3] = std::array::from_fn(|c| {
            let k = |r: usize| root[r] * self.rows[r].scale[c];
            let a = DMatrix::from_fn(self.rows.len(), cols.len(), |r, i| {
                k(r) * self.rows[r].values[cols[i]]
            });
            let b = DVector::from_fn(self.rows.len(), |r, _| k(r) * self.rows[r].target[c]);
            (a.tr_mul(&a), a.tr_mul(&b))
        });
        self.solve(cols, eq)
    }

    /// Solves the normal equations with the pull towards `cmf * cell width`.
    fn solve(&self, cols: &[usize], eq: [(DMatrix<f64>, DVector<f64>); 3]) -> Option<Weights> {
        let n = cols.len();
        let cells = cell_widths(cols, self.est.grid.len());
        let mut w = vec![[0.0; 3]; n];
        for (c, (mut g, mut h)) in eq.into_iter().enumerate() {
            let mu = PRIOR * g.trace() / n as f64 + 1e-300;
            for i in 0..n {
                g[(i, i)] += mu;
                h[i] += mu * self.cmf[cols[i]][c] * cells[i];
            }
            let x = g.cholesky()?.solve(&h);
            for i in 0..n {
                w[i][c] = x[i];
            }
        }
        w.iter().flatten().all(|v| v.is_finite()).then_some(w)
    }

    /// CIEDE2000 of every stimulus (not the whites) on nodes `cols` with weights `w`, each
    /// colour divided by its light's white on the same nodes, as the renderer divides.
    pub(crate) fn errors(&self, cols: &[usize], w: &[[f64; 3]]) -> Vec<f64> {
        (0..self.stimuli)
            .map(|s| {
                let (mut xyz, mut y) = ([0.0; 3], 0.0);
                for (i, &j) in cols.iter().enumerate() {
                    let v = self.est.value[s][j];
                    for c in 0..3 {
                        xyz[c] += w[i][c] * v;
                    }
                    y += w[i][1] * self.est.light[s][j];
                }
                if !(y.is_finite() && y > 0.0) {
                    return f64::INFINITY;
                }
                self.est.error_of(s, Xyz(xyz.map(|v| 100.0 * v / y)))
            })
            .collect()
    }

    /// The scaled residuals over the stimuli, squared and summed: CIELAB distance squared to
    /// first order, what the least squares minimises. Cheap enough to rank every candidate
    /// node with; unlike the largest residual it never grows when a node is added.
    pub(crate) fn surrogate(&self, cols: &[usize], w: &[[f64; 3]]) -> f64 {
        self.rows[..self.stimuli]
            .iter()
            .map(|row| {
                let mut d2 = 0.0;
                for c in 0..3 {
                    let x: f64 = cols.iter().zip(w).map(|(&j, w)| w[c] * row.values[j]).sum();
                    d2 += (row.scale[c] * (x - row.target[c])).powi(2);
                }
                d2
            })
            .sum()
    }

    /// Least squares, then Lawson's reweighting, from the row weights `start` (a similar node
    /// set's, which makes it converge in a few iterations) or uniform ones: the weights with
    /// the smallest largest error found, the errors, and the row weights that gave them.
    pub(crate) fn minimax(&self, cols: &[usize], start: Option<&[f64]>) -> Option<Minimax> {
        let warm = start.is_some_and(|u| u.len() == self.stimuli);
        let mut u = match start {
            Some(u) if warm => u.to_vec(),
            _ => vec![1.0; self.stimuli],
        };
        let mut best: Option<Minimax> = None;
        let mut since_best = 0;
        for _ in 0..LAWSON_ITERATIONS {
            let Some(w) = self.solve_weighted(cols, &u) else {
                break;
            };
            let e = self.errors(cols, &w);
            let max = worst(&e).1;
            if best.as_ref().is_none_or(|b| max < b.max) {
                best = Some(Minimax {
                    weights: w,
                    errors: e.clone(),
                    max,
                    rows: u.clone(),
                });
                since_best = 0;
            } else {
                since_best += 1;
            }
            let total: f64 = u.iter().zip(&e).map(|(u, e)| u * e).sum();
            if !(max.is_finite() && total > 0.0) || since_best >= if warm { 4 } else { 6 } {
                break;
            }
            for (u, e) in u.iter_mut().zip(&e) {
                // Floored, so a stimulus met early can come back when the nodes move.
                *u = (*u * e / total * self.stimuli as f64).max(1e-6);
            }
        }
        best
    }
}

/// Minimax weights of a node set.
pub(crate) struct Minimax {
    pub(crate) weights: Weights,
    pub(crate) errors: Vec<f64>,
    pub(crate) max: f64,
    /// Lawson's row weights at the best iteration (to start a similar node set from).
    pub(crate) rows: Vec<f64>,
}

/// How far CIELAB moves per unit of X, Y and Z at `xyz` (white `white`), each over CIEDE2000's
/// weight (S_L for L*, S_C for a* and b*): the largest coefficient the channel enters with.
fn lab_scale(xyz: Xyz, white: Xyz) -> [f64; 3] {
    const E: f64 = 216.0 / 24389.0;
    const K: f64 = 24389.0 / 27.0;
    let df = |t: f64| {
        if t > E {
            t.powf(-2.0 / 3.0) / 3.0
        } else {
            K / 116.0
        }
    };
    let lab = Lab::from_xyz(xyz, white).0;
    let sc = 1.0 + 0.045 * lab[1].hypot(lab[2]);
    let l50 = (lab[0] - 50.0).powi(2);
    let sl = 1.0 + 0.015 * l50 / (20.0 + l50).sqrt();
    let w = white.0;
    [
        500.0 / sc * df(xyz.0[0] / w[0]) / w[0],
        (116.0 / sl).max(700.0 / sc) * df(xyz.0[1] / w[1]) / w[1],
        200.0 / sc * df(xyz.0[2] / w[2]) / w[2],
    ]
    .map(|v: f64| if v.is_finite() { v } else { 0.0 })
}

/// The width (in grid steps) of the interval each node stands for: half way to its neighbours,
/// to the grid's ends at the ends.
fn cell_widths(cols: &[usize], len: usize) -> Vec<f64> {
    let n = cols.len();
    (0..n)
        .map(|i| {
            let lo = if i == 0 {
                0.0
            } else {
                0.5 * (cols[i] + cols[i - 1]) as f64
            };
            let hi = if i + 1 == n {
                (len - 1) as f64
            } else {
                0.5 * (cols[i] + cols[i + 1]) as f64
            };
            (hi - lo).max(1.0)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::Observer;
    use crate::quadrature::estimate::White;
    use crate::tradeoff::colorchecker_under;

    #[test]
    fn lab_scale_is_the_derivative_of_cielab() {
        // A small step in X moves a* by about the scale times the step (S_C ~ 1 near grey).
        let w = Xyz::new(95.047, 100.0, 108.883);
        let x = Xyz::new(40.0, 42.0, 45.0);
        let s = lab_scale(x, w);
        let h = 1e-4;
        let a = |xyz: Xyz| Lab::from_xyz(xyz, w).0;
        let da = (a(Xyz::new(40.0 + h, 42.0, 45.0))[1] - a(x)[1]) / h;
        let c = a(x)[1].hypot(a(x)[2]);
        assert!(
            (s[0] * (1.0 + 0.045 * c) - da).abs() < 1e-3 * da,
            "{} vs {da}",
            s[0]
        );
    }

    #[test]
    fn every_node_on_the_grid_reproduces_the_reference() {
        // All 401 nodes: least squares finds Simpson's weights (or as good), so no error.
        let light = crate::data::spectrum("FL2").unwrap().data;
        let s = colorchecker_under("FL2", &light).unwrap();
        let e = Estimator::new(&s, Observer::Cie1931, 380.0, 780.0, White::OwnLight).unwrap();
        let p = Problem::new(&e).unwrap();
        let cols: Vec<usize> = (0..e.grid().len()).step_by(5).collect();
        let m = p.minimax(&cols, None).unwrap();
        assert_eq!(m.weights.len(), 81);
        assert!(m.max < 0.05, "{}", m.max);
    }
}
