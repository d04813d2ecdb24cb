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
use crate::colorimetry::{delta_e_2000, Lab, Xyz};
use crate::error::Result;
use crate::spectrum::Rule;
use nalgebra::{DMatrix, DVector};

/// The channel pairs (c <= d) of the coupled normal equations' blocks.
const BLOCKS: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];

/// Lawson iterations at most per node set (it stops after six without progress).
const LAWSON_ITERATIONS: usize = 40;

/// Relative weight of the pull towards `cmf * cell width`.
const PRIOR: f64 = 1e-7;

/// How much more a light's white weighs than one stimulus.
const WHITE_WEIGHT: f64 = 4.0;

/// One row of the least squares: a stimulus (or a light's white) at 1 nm.
struct Row<'a> {
    values: &'a [f64],
    /// The light the row's colour is divided by (a white's is its own values).
    light: &'a [f64],
    target: [f64; 3],
    /// How far CIELAB moves per unit of X, Y, Z (the cheap, per-channel form).
    scale: [f64; 3],
    /// CIEDE2000 to first order: a small step `d` in XYZ moves it by `sqrt(d' Q d)`.
    metric: [[f64; 3]; 3],
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
    /// The rows' values and lights by wavelength ([`Columns`]).
    columns: Columns,
    /// When the fit must stop searching ([`super::fit::Options::deadline`]).
    pub(super) deadline: Option<std::time::Instant>,
}

/// The rows' values and lights laid out by 1 nm wavelength: `values[j][r]` is row `r` at
/// wavelength `j`. A node set's matrix is then a few contiguous runs; gathered from the rows
/// it costs a cache line per row and node, which made the gathering most of a weighted solve
/// (the cylinders under a photograph: 38% of the greedy stage in `perf`).
struct Columns {
    values: Vec<Vec<f64>>,
    light: Vec<Vec<f64>>,
}

impl Columns {
    fn new(rows: &[Row], len: usize) -> Columns {
        let by = |which: Spectra| -> Vec<Vec<f64>> {
            let of = |r: &Row, j: usize| match which {
                Spectra::Values => r.values[j],
                Spectra::Light => r.light[j],
            };
            (0..len)
                .map(|j| rows.iter().map(|r| of(r, j)).collect())
                .collect()
        };
        Columns {
            values: by(Spectra::Values),
            light: by(Spectra::Light),
        }
    }
}

/// Which of a row's spectra [`Problem::gather`] reads.
#[derive(Clone, Copy)]
pub(super) enum Spectra {
    Values,
    Light,
}

/// Weights per node.
pub(crate) type Weights = Vec<[f64; 3]>;

impl<'a> Problem<'a> {
    pub(crate) fn new(est: &'a Estimator) -> Result<Problem<'a>> {
        let reference = Quadrature::uniform(est.grid, Rule::Simpson, est.observer)?;
        let mut rows: Vec<Row> = (0..est.len())
            .map(|s| Row {
                values: &est.value[s],
                light: &est.light[s],
                target: est.reference[s].0,
                scale: lab_scale(est.reference[s], est.white[s]),
                metric: local_metric(est.reference[s], est.white[s]),
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
                    light: l,
                    target: w.0,
                    scale: lab_scale(w, est.white[s]).map(|v| WHITE_WEIGHT.sqrt() * v),
                    metric: local_metric(w, est.white[s]),
                });
            }
        }
        let gram = std::array::from_fn(|c| {
            let j = est.grid.len();
            let a = DMatrix::from_fn(rows.len(), j, |r, k| rows[r].scale[c] * rows[r].values[k]);
            let b = DVector::from_fn(rows.len(), |r, _| rows[r].scale[c] * rows[r].target[c]);
            (a.tr_mul(&a), a.tr_mul(&b))
        });
        let columns = Columns::new(&rows, est.grid.len());
        Ok(Problem {
            est,
            rows,
            stimuli,
            cmf: reference.weights().to_vec(),
            gram,
            columns,
            deadline: None,
        })
    }

    /// Whether the fit's deadline has passed: the search stops and keeps the best it found.
    pub(super) fn out_of_time(&self) -> bool {
        self.deadline
            .is_some_and(|d| std::time::Instant::now() >= d)
    }

    /// Every row's `which` spectrum at the nodes `cols`: a rows x nodes matrix.
    pub(super) fn gather(&self, cols: &[usize], which: Spectra) -> DMatrix<f64> {
        let by = match which {
            Spectra::Values => &self.columns.values,
            Spectra::Light => &self.columns.light,
        };
        let runs = cols.iter().flat_map(|&j| by[j].iter().copied());
        DMatrix::from_iterator(self.rows.len(), cols.len(), runs)
    }

    /// Rows: the stimuli, then each light's white.
    pub(super) fn row_count(&self) -> usize {
        self.rows.len()
    }

    /// Row `r`'s stimulus at 1 nm, the light it is divided by, and its 1 nm colour.
    pub(super) fn row_spectra(&self, r: usize) -> (&[f64], &[f64], [f64; 3]) {
        let row = &self.rows[r];
        (row.values, row.light, row.target)
    }

    /// Row `r`'s local CIEDE2000 metric, unweighted (a white's error is a white's colour).
    pub(super) fn row_metric(&self, r: usize) -> &[[f64; 3]; 3] {
        &self.rows[r].metric
    }

    /// Row `r`'s metric in the least squares: a white's weighs as [`WHITE_WEIGHT`] stimuli.
    fn weighted_metric(&self, r: usize) -> [[f64; 3]; 3] {
        let m = self.rows[r].metric;
        if r < self.stimuli {
            m
        } else {
            m.map(|row| row.map(|v| WHITE_WEIGHT * v))
        }
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

    /// Least squares for `cols` with row weights `u` on the stimuli (whites: their mean), each
    /// residual measured by its row's full CIEDE2000 metric: the three channels' weights are solved
    /// together, since the metric couples them (a hue error moves X and Z together).
    pub(crate) fn solve_coupled_weighted(&self, cols: &[usize], u: &[f64]) -> Option<Weights> {
        let n = cols.len();
        let mean = u.iter().sum::<f64>() / u.len().max(1) as f64;
        let rows = self.rows.len();
        let ur = |r: usize| if r < self.stimuli { u[r] } else { mean };
        let v = self.gather(cols, Spectra::Values);
        let metric: Vec<[[f64; 3]; 3]> = (0..rows).map(|r| self.weighted_metric(r)).collect();
        let mut g = DMatrix::<f64>::zeros(3 * n, 3 * n);
        for (c, d) in BLOCKS {
            // Q_cd = V' diag(u q_cd) V, by a matrix product.
            let k = DVector::from_fn(rows, |r, _| ur(r) * metric[r][c][d]);
            let block = symmetric_gram(&v, &k);
            g.view_mut((c * n, d * n), (n, n)).copy_from(&block);
            if c != d {
                g.view_mut((d * n, c * n), (n, n))
                    .copy_from(&block.transpose());
            }
        }
        let t = DMatrix::from_fn(rows, 3, |r, c| {
            ur(r)
                * (0..3)
                    .map(|d| metric[r][c][d] * self.rows[r].target[d])
                    .sum::<f64>()
        });
        let ht = v.tr_mul(&t);
        let h = DVector::from_fn(3 * n, |x, _| ht[(x % n, x / n)]);
        self.solve_coupled(cols, g, h)
    }

    /// Least squares for `cols` with row weights `u` on the stimuli (whites: their mean), each
    /// channel on its own with its row's per-channel scale.
    pub(crate) fn solve_weighted(&self, cols: &[usize], u: &[f64]) -> Option<Weights> {
        let mean = u.iter().sum::<f64>() / u.len().max(1) as f64;
        let ur = |r: usize| if r < self.stimuli { u[r] } else { mean };
        let v = self.gather(cols, Spectra::Values);
        let eq: [(DMatrix<f64>, DVector<f64>); 3] = std::array::from_fn(|c| {
            // V' diag(u s_c^2) V and V' diag(u s_c^2) X_c.
            let k = DVector::from_fn(self.rows.len(), |r, _| {
                ur(r) * self.rows[r].scale[c].powi(2)
            });
            let t = DVector::from_fn(self.rows.len(), |r, _| k[r] * self.rows[r].target[c]);
            (symmetric_gram(&v, &k), v.tr_mul(&t))
        });
        self.solve(cols, eq)
    }

    /// Solves the coupled normal equations (channel-major blocks) with each channel's pull
    /// towards `cmf * cell width`.
    fn solve_coupled(
        &self,
        cols: &[usize],
        mut g: DMatrix<f64>,
        mut h: DVector<f64>,
    ) -> Option<Weights> {
        let n = cols.len();
        let cells = cell_widths(cols, self.est.grid.len());
        for c in 0..3 {
            let trace: f64 = (0..n).map(|i| g[(c * n + i, c * n + i)]).sum();
            let mu = PRIOR * trace / n as f64 + 1e-300;
            for i in 0..n {
                g[(c * n + i, c * n + i)] += mu;
                h[c * n + i] += mu * self.cmf[cols[i]][c] * cells[i];
            }
        }
        let x = g.cholesky()?.solve(&h);
        let w: Weights = (0..n).map(|i| [x[i], x[n + i], x[2 * n + i]]).collect();
        w.iter().flatten().all(|v| v.is_finite()).then_some(w)
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
        // X, Y, Z and the white's Y per stimulus, a node's column at a time.
        let mut sums = vec![[0.0; 4]; self.stimuli];
        for (i, &j) in cols.iter().enumerate() {
            let (v, l) = (&self.columns.values[j], &self.columns.light[j]);
            for (s, sum) in sums.iter_mut().enumerate() {
                for c in 0..3 {
                    sum[c] += w[i][c] * v[s];
                }
                sum[3] += w[i][1] * l[s];
            }
        }
        sums.iter()
            .enumerate()
            .map(|(s, &[x, y, z, white])| {
                if !(white.is_finite() && white > 0.0) {
                    return f64::INFINITY;
                }
                self.est
                    .error_of(s, Xyz([x, y, z].map(|v| 100.0 * v / white)))
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

    /// [`Problem::minimax_within`] with every Lawson step and no giving up.
    pub(crate) fn minimax(
        &self,
        cols: &[usize],
        start: Option<&[f64]>,
        metric: Metric,
    ) -> Option<Minimax> {
        self.minimax_within(cols, start, LAWSON_ITERATIONS, f64::INFINITY, metric)
    }

    /// Least squares under `metric`, then Lawson's reweighting, from the row weights `start`
    /// (a similar node set's, which makes it converge in a few iterations) or uniform ones: the
    /// weights with the smallest largest error found, the errors, and the row weights that gave
    /// them. At most `iterations` Lawson steps, given up after three when the largest error is
    /// still above `give_up` (a quick judge of many node sets, most of which are discarded).
    pub(crate) fn minimax_within(
        &self,
        cols: &[usize],
        start: Option<&[f64]>,
        iterations: usize,
        give_up: f64,
        metric: Metric,
    ) -> Option<Minimax> {
        let warm = start.is_some_and(|u| u.len() == self.stimuli);
        let mut u = match start {
            Some(u) if warm => u.to_vec(),
            _ => vec![1.0; self.stimuli],
        };
        let mut best: Option<Minimax> = None;
        let mut since_best = 0;
        for k in 0..iterations {
            if k == 3 && best.as_ref().is_some_and(|b| b.max > give_up) {
                break;
            }
            let solved = match metric {
                Metric::Channels => self.solve_weighted(cols, &u),
                Metric::Coupled => self.solve_coupled_weighted(cols, &u),
            };
            let Some(w) = solved else {
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

/// How a least-squares row measures its residual.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Metric {
    /// Each channel on its own, scaled by how far it moves CIELAB at most (cheap; the search).
    Channels,
    /// CIEDE2000's own quadratic form to first order, which couples the channels.
    Coupled,
}

/// Minimax weights of a node set.
pub(crate) struct Minimax {
    pub(crate) weights: Weights,
    pub(crate) errors: Vec<f64>,
    pub(crate) max: f64,
    /// Lawson's row weights at the best iteration (to start a similar node set from).
    pub(crate) rows: Vec<f64>,
}

/// `m' diag(k) m`: [`weighted_gram`] of a matrix with itself, each entry of the upper triangle
/// computed once and mirrored (half the products: the weighted solves spent a fifth of a fit in
/// Gram products).
pub(super) fn symmetric_gram(m: &DMatrix<f64>, k: &DVector<f64>) -> DMatrix<f64> {
    let n = m.ncols();
    let scaled = scale_rows(m.clone(), k);
    let mut g = DMatrix::zeros(n, n);
    for i in 0..n {
        for j in i..n {
            let v = scaled.column(i).dot(&m.column(j));
            g[(i, j)] = v;
            g[(j, i)] = v;
        }
    }
    g
}

/// `l' diag(k) m`: a Gram product with a weight per row.
pub(super) fn weighted_gram(l: &DMatrix<f64>, k: &DVector<f64>, m: &DMatrix<f64>) -> DMatrix<f64> {
    l.tr_mul(&scale_rows(m.clone(), k))
}

/// `m` with row `r` times `k[r]`.
pub(super) fn scale_rows(mut m: DMatrix<f64>, k: &DVector<f64>) -> DMatrix<f64> {
    for mut col in m.column_iter_mut() {
        col.component_mul_assign(k);
    }
    m
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

/// CIEDE2000 to first order at `xyz` (white `white`): the symmetric `Q` with
/// `dE00(xyz + d, xyz)^2 ~ d' Q d` for small `d`, from CIEDE2000 itself by differences (it is
/// a norm of the step to first order, so `dE00^2 / h^2` converges as `h` shrinks), its negative
/// eigenvalues (rounding) set to zero.
fn local_metric(xyz: Xyz, white: Xyz) -> [[f64; 3]; 3] {
    let h = 1e-4 * xyz.0.iter().fold(1e-2f64, |m, v| m.max(v.abs()));
    let base = Lab::from_xyz(xyz, white);
    let de2 = |d: [f64; 3]| {
        let moved = Xyz(std::array::from_fn(|c| xyz.0[c] + h * d[c]));
        let e = delta_e_2000(Lab::from_xyz(moved, white), base);
        if e.is_finite() {
            e * e / (h * h)
        } else {
            0.0
        }
    };
    let unit = |c: usize| std::array::from_fn(|k| if k == c { 1.0 } else { 0.0 });
    let diag: [f64; 3] = std::array::from_fn(|c| de2(unit(c)));
    let mut q = nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::from(diag));
    for c in 0..3 {
        for d in c + 1..3 {
            let both = std::array::from_fn(|k| if k == c || k == d { 1.0 } else { 0.0 });
            let v = 0.5 * (de2(both) - diag[c] - diag[d]);
            q[(c, d)] = v;
            q[(d, c)] = v;
        }
    }
    let eig = q.symmetric_eigen();
    let q = eig.eigenvectors
        * nalgebra::Matrix3::from_diagonal(&eig.eigenvalues.map(|v| v.max(0.0)))
        * eig.eigenvectors.transpose();
    std::array::from_fn(|c| std::array::from_fn(|d| q[(c, d)]))
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
pub(super) mod tests {
    use super::*;
    use crate::colorimetry::Observer;
    use crate::quadrature::estimate::White;
    use crate::tradeoff::colorchecker_under;

    /// The 24 ColorChecker patches under `light`, each against its light's own white.
    pub(in crate::quadrature) fn chart(light: &str) -> Estimator {
        let l = crate::data::spectrum(light).unwrap().data;
        let s = colorchecker_under(light, &l).unwrap();
        Estimator::new(&s, Observer::Cie1931, 380.0, 780.0, White::OwnLight).unwrap()
    }

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
    fn the_local_metric_is_ciede2000_to_first_order() {
        // Small steps in directions that mix the channels: sqrt(d' Q d) against CIEDE2000.
        let w = Xyz::new(95.047, 100.0, 108.883);
        for x in [
            Xyz::new(40.0, 42.0, 45.0),
            Xyz::new(20.0, 12.0, 5.0),
            Xyz::new(8.0, 15.0, 30.0),
        ] {
            let q = local_metric(x, w);
            for d in [[1.0, 0.0, 0.0], [1.0, -1.0, 0.5], [0.2, 0.3, -1.0]] {
                let h = 1e-3;
                let moved = Xyz(std::array::from_fn(|c| x.0[c] + h * d[c]));
                let want = delta_e_2000(Lab::from_xyz(moved, w), Lab::from_xyz(x, w));
                let quad: f64 = (0..3)
                    .flat_map(|c| (0..3).map(move |k| (c, k)))
                    .map(|(c, k)| d[c] * q[c][k] * d[k])
                    .sum();
                let got = h * quad.sqrt();
                assert!(
                    (got - want).abs() < 1e-2 * want,
                    "{x:?} {d:?}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn coupled_weights_beat_or_match_per_channel_ones() {
        // The same nodes: weights under CIEDE2000's own metric err no more than per channel.
        let e = chart("D65");
        let p = Problem::new(&e).unwrap();
        let cols = [60, 100, 150, 190, 240];
        let max = |m: Metric| p.minimax(&cols, None, m).unwrap().max;
        let (channels, coupled) = (max(Metric::Channels), max(Metric::Coupled));
        assert!(coupled <= 1.02 * channels, "{coupled} vs {channels}");
    }

    #[test]
    fn a_node_sets_columns_are_its_rows_spectra() {
        let e = chart("FL2");
        let p = Problem::new(&e).unwrap();
        let cols = [3, 57, 165, 200, 400];
        let (v, l) = (
            p.gather(&cols, Spectra::Values),
            p.gather(&cols, Spectra::Light),
        );
        assert_eq!(v.shape(), (p.row_count(), cols.len()));
        for r in 0..p.row_count() {
            let (values, light, _) = p.row_spectra(r);
            for (i, &j) in cols.iter().enumerate() {
                assert_eq!(
                    (v[(r, i)], l[(r, i)]),
                    (values[j], light[j]),
                    "row {r}, node {j}"
                );
            }
        }
    }

    #[test]
    fn the_symmetric_gram_is_the_general_product() {
        let m = DMatrix::from_fn(50, 4, |r, c| {
            ((r * 7 + c * 3) % 11) as f64 - 5.0 + 0.1 * c as f64
        });
        let k = DVector::from_fn(50, |r, _| 1.0 + (r % 5) as f64);
        let (got, want) = (symmetric_gram(&m, &k), weighted_gram(&m, &k, &m));
        assert!(
            (&got - &want).norm() <= 1e-12 * want.norm(),
            "{got} vs {want}"
        );
    }

    #[test]
    fn the_search_errs_as_the_estimator_does() {
        // The same weights on the same nodes: the least squares' errors, summed over the
        // nodes' columns, and the estimator's, integrated per stimulus by the quadrature.
        let e = chart("FL2");
        let p = Problem::new(&e).unwrap();
        let cols = [50, 90, 165, 200, 250, 300];
        let w = p.solve_unit(&cols).unwrap();
        let nodes = cols.iter().map(|&j| e.grid().wavelength_nm(j)).collect();
        let q = Quadrature::new(
            crate::quadrature::Kind::Scene,
            e.observer(),
            nodes,
            w.clone(),
        );
        let want = e.errors(&q.unwrap()).unwrap();
        let got = p.errors(&cols, &w);
        assert_eq!(got.len(), want.len());
        for (s, (g, w)) in got.iter().zip(&want).enumerate() {
            assert!(
                (g - w).abs() <= 1e-9 * w.max(1.0),
                "stimulus {s}: {g} vs {w}"
            );
        }
    }

    #[test]
    fn every_node_on_the_grid_reproduces_the_reference() {
        // All 401 nodes: least squares finds Simpson's weights (or as good), so no error.
        let e = chart("FL2");
        let p = Problem::new(&e).unwrap();
        let cols: Vec<usize> = (0..e.grid().len()).step_by(5).collect();
        let m = p.minimax(&cols, None, Metric::Channels).unwrap();
        assert_eq!(m.weights.len(), 81);
        assert!(m.max < 0.05, "{}", m.max);
    }
}
