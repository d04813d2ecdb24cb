//! Meyer's Gaussian quadrature (G. W. Meyer, "Wavelength selection for synthetic image
//! generation", CVGIP 41, 1988): the wavelengths are the nodes of the Gauss rule whose weight
//! function is the visual system's achromatic channel, and every channel is integrated on those
//! shared nodes.
//!
//! Constructed here as follows (the construction, not a copied table):
//! 1. the weight function is the CIE `ybar` of the observer (the luminance channel stands for
//!    Meyer's achromatic opponent fundamental), a discrete measure on 380..780 nm at 1 nm with
//!    Simpson masses;
//! 2. the recurrence of the polynomials orthogonal for that measure is found by Stieltjes'
//!    procedure (wavelengths scaled to [-1, 1]), and the `n` nodes are the eigenvalues of the
//!    n x n Jacobi matrix (Golub and Welsch, 1969);
//! 3. each channel's weights are those of the interpolatory rule on the nodes,
//!    `w_i,c = sum_j m_j cmf_c(lambda_j) l_i(lambda_j)`, `l_i` the Lagrange polynomials: exact for
//!    `ybar` times any polynomial of degree below `2n` (Gauss), and for `xbar`, `zbar` times any of
//!    degree below `n`.

use super::{Kind, Quadrature};
use crate::colorimetry::{Cmfs, Observer};
use crate::error::{Error, Result};
use crate::spectrum::{Rule, WavelengthGrid};
use nalgebra::{DMatrix, SymmetricEigen};

/// Meyer's four wavelengths.
pub(crate) const MEYER_NODES: usize = 4;

/// The range the rule is built on.
const RANGE_NM: (f64, f64) = (380.0, 780.0);

/// Meyer's rule with [`MEYER_NODES`] nodes.
pub(crate) fn meyer(observer: Observer) -> Result<Quadrature> {
    gauss(observer, MEYER_NODES)
}

/// The `n`-node Gauss rule for `ybar`, with interpolatory weights for all three functions.
pub(crate) fn gauss(observer: Observer, n: usize) -> Result<Quadrature> {
    if !(1..=12).contains(&n) {
        return Err(Error::invalid(format!(
            "a Gauss rule of {n} nodes: between 1 and 12"
        )));
    }
    let grid = WavelengthGrid::new(RANGE_NM.0, RANGE_NM.1, 1.0)?;
    let cmfs = Cmfs::new(observer, &grid)?;
    let h = Rule::Simpson.weights(grid.len(), 1.0);
    let (mid, half) = (
        0.5 * (RANGE_NM.0 + RANGE_NM.1),
        0.5 * (RANGE_NM.1 - RANGE_NM.0),
    );
    let t: Vec<f64> = grid.wavelengths_nm().map(|w| (w - mid) / half).collect();
    let mass: Vec<f64> = h.iter().zip(cmfs.y.values()).map(|(h, y)| h * y).collect();
    let nodes_t = gauss_nodes(&t, &mass, n)?;
    let channels = [cmfs.x.values(), cmfs.y.values(), cmfs.z.values()];
    let weights: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let mut w = [0.0; 3];
            for (j, &tj) in t.iter().enumerate() {
                let l = lagrange(&nodes_t, i, tj);
                for c in 0..3 {
                    w[c] += h[j] * channels[c][j] * l;
                }
            }
            w
        })
        .collect();
    let nodes_nm = nodes_t.iter().map(|x| mid + half * x).collect();
    Quadrature::new(Kind::Meyer, observer, nodes_nm, weights)
}

/// The Gauss nodes of the discrete measure (`t_j`, `m_j`): Stieltjes' recurrence, then the
/// eigenvalues of the Jacobi matrix, ascending.
fn gauss_nodes(t: &[f64], m: &[f64], n: usize) -> Result<Vec<f64>> {
    let inner = |p: &[f64], q: &[f64], x: bool| -> f64 {
        (0..t.len())
            .map(|j| m[j] * p[j] * q[j] * if x { t[j] } else { 1.0 })
            .sum()
    };
    let mut prev = vec![0.0; t.len()];
    let mut cur = vec![1.0; t.len()];
    let mut norm_prev = 1.0;
    let (mut alpha, mut beta) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for k in 0..n {
        let norm = inner(&cur, &cur, false);
        if !(norm.is_finite() && norm > 0.0) {
            return Err(Error::invalid(
                "the weight function has too few points for the rule",
            ));
        }
        let a = inner(&cur, &cur, true) / norm;
        let b = if k == 0 { 0.0 } else { norm / norm_prev };
        alpha.push(a);
        beta.push(b);
        let next: Vec<f64> = (0..t.len())
            .map(|j| (t[j] - a) * cur[j] - b * prev[j])
            .collect();
        prev = std::mem::replace(&mut cur, next);
        norm_prev = norm;
    }
    let jacobi = DMatrix::from_fn(n, n, |i, j| {
        if i == j {
            alpha[i]
        } else if i + 1 == j {
            beta[j].sqrt()
        } else if j + 1 == i {
            beta[i].sqrt()
        } else {
            0.0
        }
    });
    let mut nodes: Vec<f64> = SymmetricEigen::new(jacobi)
        .eigenvalues
        .iter()
        .copied()
        .collect();
    nodes.sort_by(f64::total_cmp);
    Ok(nodes)
}

/// The `i`-th Lagrange polynomial of `nodes` at `x`.
fn lagrange(nodes: &[f64], i: usize, x: f64) -> f64 {
    nodes
        .iter()
        .enumerate()
        .filter(|(k, _)| *k != i)
        .map(|(_, &xk)| (x - xk) / (nodes[i] - xk))
        .product()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The integral of `cmf * p` at 1 nm by Simpson's rule, and by the quadrature.
    fn both(q: &Quadrature, c: usize, p: impl Fn(f64) -> f64) -> (f64, f64) {
        let grid = WavelengthGrid::new(380.0, 780.0, 1.0).unwrap();
        let cmfs = Cmfs::new(q.observer(), &grid).unwrap();
        let f = [&cmfs.x, &cmfs.y, &cmfs.z][c];
        let h = Rule::Simpson.weights(grid.len(), 1.0);
        let exact: f64 = grid
            .wavelengths_nm()
            .enumerate()
            .map(|(j, w)| h[j] * f.values()[j] * p(w))
            .sum();
        let values: Vec<f64> = q.nodes_nm().iter().map(|&w| p(w)).collect();
        (exact, q.integrate(&values)[c])
    }

    #[test]
    fn the_rule_is_gaussian_for_ybar_and_interpolatory_for_xbar_and_zbar() {
        let q = meyer(Observer::Cie1931).unwrap();
        assert_eq!(q.len(), 4);
        // Nodes inside the range, where ybar is not negligible.
        assert!(q.nodes_nm()[0] > 400.0 && q.nodes_nm()[3] < 700.0, "{q}");
        let p = |k: i32| move |w: f64| ((w - 580.0) / 200.0).powi(k);
        for k in 0..8 {
            let (a, b) = both(&q, 1, p(k));
            assert!(
                (a - b).abs() < 1e-9 * both(&q, 1, p(0)).0,
                "ybar * t^{k}: {a} vs {b}"
            );
        }
        // Degree 8 is beyond a 4-node Gauss rule.
        let (a, b) = both(&q, 1, p(8));
        assert!((a - b).abs() > 1e-6 * a.abs(), "ybar * t^8: {a} vs {b}");
        for c in [0, 2] {
            for k in 0..4 {
                let (a, b) = both(&q, c, p(k));
                let scale = both(&q, c, p(0)).0;
                assert!(
                    (a - b).abs() < 1e-9 * scale,
                    "channel {c} t^{k}: {a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn one_node_is_the_ybar_centroid() {
        let q = gauss(Observer::Cie1931, 1).unwrap();
        let (m0, _) = both(&q, 1, |_| 1.0);
        let (m1, _) = both(&q, 1, |w| w);
        assert!((q.nodes_nm()[0] - m1 / m0).abs() < 1e-9, "{q}");
        assert!(gauss(Observer::Cie1931, 0).is_err());
    }
}
