//! A map's own spectral basis: the K spectra that span the spectra of a map's pixels, found from
//! the pixels themselves (principal components), and the projection of a pixel's spectrum onto
//! them that keeps its colour.
//!
//! Every spectrum `specmap convert` writes is a combination of a few spectra (the ColorChecker
//! basis times each light, each light's smooth modulation, the daylight basis, each lamp's and the
//! sun's SPD): their span has a small dimension, and its principal components hold every pixel
//! exactly. A foreign spectral map (another tool's, measured data) is held approximately: K is the
//! fewest components whose discarded share of the map's spectral energy is under a tolerance.
//!
//! # The statistic
//! Each pixel's spectrum `s` counts by its direction `s / |s|` twice: weighted by its solid angle
//! (every part of the map alike) and by its solid angle times luminance (where the light is). The
//! two second-moment matrices, each normalised to trace 1, are summed; their eigenvectors are the
//! components, and the sum of the dropped eigenvalues over the total is the `discarded` share: the
//! mean squared relative residual, averaged over area and over energy.
//!
//! # The projection
//! A least-squares fit `c = B^T s` (B orthonormal) would shift the colour of a spectrum outside the
//! span; the projection instead minimises `|B c - s|` subject to `C B c = C s` (C the colour
//! matching functions' weights), so every pixel, and every filtered mix of pixels, keeps its XYZ
//! exactly. With fewer than three components, or colours the components cannot span, the fit is
//! the plain least-squares one.

use crate::colorimetry::{Cmfs, Observer};
use crate::error::{Error, Result};
use crate::spectrum::{Interpolation, Tabulated, WavelengthGrid};
use crate::tradeoff::sample;
use nalgebra::DMatrix;

/// The most spectra a basis holds (the GPU renderer's limit: 8 groups of 4).
pub(crate) const MAX_K: usize = 32;

/// The default share of the spectral energy a basis may discard. What `convert` writes spans a
/// few tens of dimensions (per light: the ColorChecker basis and the smooth modulation; the
/// daylight basis; the sun) whose smallest components hold about 1e-7 of the energy on
/// envmaps/sunrise.exr; beyond them lie the few hundred pixels given a Bernstein or nearest
/// spectrum, and rounding noise (a half-float map averaged into the renderer's texels: well
/// under 1e-8).
pub(crate) const DEFAULT_DISCARD: f64 = 1e-7;

/// The second moments of a map's pixel spectra (see the module docs).
#[derive(Debug, Clone)]
pub struct Moments {
    n: usize,
    area: Vec<f64>,
    energy: Vec<f64>,
    area_sum: f64,
    energy_sum: f64,
}

impl Moments {
    /// Empty moments of spectra of `n` bands.
    pub fn new(n: usize) -> Moments {
        Moments {
            n,
            area: vec![0.0; n * n],
            energy: vec![0.0; n * n],
            area_sum: 0.0,
            energy_sum: 0.0,
        }
    }

    /// Adds a pixel's spectrum of solid angle `omega` and luminance `y` (a black or non-finite
    /// spectrum adds nothing).
    pub fn add(&mut self, s: &[f64], omega: f64, y: f64) {
        let norm2: f64 = s.iter().map(|v| v * v).sum();
        if !(norm2 > 0.0 && norm2.is_finite() && omega > 0.0) {
            return;
        }
        let (wa, we) = (omega / norm2, omega * y.max(0.0) / norm2);
        self.area_sum += omega;
        self.energy_sum += omega * y.max(0.0);
        for i in 0..self.n {
            let (ra, re) = (wa * s[i], we * s[i]);
            let row = i * self.n;
            for (j, sj) in s.iter().enumerate().take(i + 1) {
                self.area[row + j] += ra * sj;
                self.energy[row + j] += re * sj;
            }
        }
    }

    /// The sum of two partial moments.
    pub fn merge(mut self, o: &Moments) -> Moments {
        for (a, b) in self.area.iter_mut().zip(&o.area) {
            *a += b;
        }
        for (a, b) in self.energy.iter_mut().zip(&o.energy) {
            *a += b;
        }
        self.area_sum += o.area_sum;
        self.energy_sum += o.energy_sum;
        self
    }

    fn matrix(&self) -> DMatrix<f64> {
        let n = self.n;
        let mut m = DMatrix::zeros(n, n);
        for i in 0..n {
            for j in 0..=i {
                let mut v = 0.0;
                if self.area_sum > 0.0 {
                    v += self.area[i * n + j] / self.area_sum;
                }
                if self.energy_sum > 0.0 {
                    v += self.energy[i * n + j] / self.energy_sum;
                }
                m[(i, j)] = v;
                m[(j, i)] = v;
            }
        }
        m
    }
}

/// How well a spectral map's own spectra hold it, per texel of the renderer's map.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Projection {
    /// How many spectra.
    pub k: usize,
    /// The share of the map's spectral energy outside them (averaged over area and energy).
    pub discarded: f64,
    /// The largest relative spectral residual `|s - B c| / |s|` of a texel.
    pub max_residual: f64,
    /// Where: azimuth and elevation in degrees (OpenEXR's: azimuth 0 looks at +Z, 90 at +X).
    pub max_residual_at: [f64; 2],
    /// The luminance-weighted mean relative residual.
    pub mean_residual: f64,
    /// Whether every texel keeps its colour exactly.
    pub keeps_colour: bool,
    /// The same in words.
    pub summary: String,
}

/// The colour-matching functions on a file's wavelengths: per band the luminance weight
/// (specmap's convention, `Y = sum L ybar / sum ybar`) and the x, y, z integration weights.
pub(crate) struct BandColour {
    /// ybar on the file's wavelengths.
    pub ybar: Vec<f64>,
    /// The sum of `ybar` (the luminance scale's denominator).
    pub ybar_sum: f64,
    /// Per band, the x, y, z integration weights (the CMFs times the band's width).
    pub weights: Vec<[f64; 3]>,
}

impl BandColour {
    /// The weights for the wavelengths `wl` (nm), the CIE 1931 observer sampled smoothly at them.
    pub(crate) fn new(wl: &[f64]) -> Result<BandColour> {
        let grid = WavelengthGrid::visible_1nm();
        let cmfs = Cmfs::new(Observer::Cie1931, &grid)?;
        let nm: Vec<f64> = grid.wavelengths_nm().collect();
        let at = |s: &crate::spectrum::Spectrum| -> Result<Vec<f64>> {
            let t = Tabulated::new(nm.clone(), s.values().to_vec())?;
            Ok(sample(&t, wl, Interpolation::SMOOTH))
        };
        let (x, y, z) = (at(&cmfs.x)?, at(&cmfs.y)?, at(&cmfs.z)?);
        let n = wl.len();
        let width = |i: usize| -> f64 {
            let lo = if i > 0 { wl[i - 1] } else { wl[i] };
            let hi = if i + 1 < n { wl[i + 1] } else { wl[i] };
            ((hi - lo) / 2.0).max(f64::MIN_POSITIVE)
        };
        let weights = (0..n)
            .map(|i| [x[i], y[i], z[i]].map(|c| c * width(i)))
            .collect();
        Ok(BandColour {
            ybar_sum: y.iter().sum(),
            ybar: y,
            weights,
        })
    }

    /// Luminance of the spectrum `s` on the file's wavelengths.
    pub(crate) fn luminance(&self, s: &[f64]) -> f64 {
        s.iter().zip(&self.ybar).map(|(a, b)| a * b).sum::<f64>() / self.ybar_sum
    }
}

/// K orthonormal spectra and the colour-keeping projection onto them.
#[derive(Debug, Clone)]
pub struct OwnBasis {
    /// K spectra of n bands, orthonormal.
    pub spectra: Vec<Vec<f64>>,
    /// The share of the map's spectral energy outside them (see the module docs).
    pub discarded: f64,
    /// Whether the projection keeps colours exactly (K >= 3 and the colours span).
    pub keeps_colour: bool,
    /// K x n: coefficients = projection * spectrum.
    projection: DMatrix<f64>,
}

impl OwnBasis {
    /// The fewest components (at most `max_k`) whose discarded share is at most `discard`;
    /// `cmf` holds the x, y, z weights per band. An empty map has an empty basis.
    pub fn from_moments(
        m: &Moments,
        cmf: &[[f64; 3]],
        discard: f64,
        max_k: usize,
    ) -> Result<OwnBasis> {
        let n = m.n;
        if cmf.len() != n {
            return Err(Error::invalid(format!(
                "{} colour-matching weights for {n} bands",
                cmf.len()
            )));
        }
        let eig = nalgebra::SymmetricEigen::new(m.matrix());
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
        let total: f64 = eig.eigenvalues.iter().map(|v| v.max(0.0)).sum();
        let mut k = 0;
        let mut kept = 0.0;
        while k < max_k.min(n) && total > 0.0 && (total - kept) > discard * total {
            kept += eig.eigenvalues[order[k]].max(0.0);
            k += 1;
        }
        let discarded = if total > 0.0 {
            ((total - kept) / total).max(0.0)
        } else {
            0.0
        };
        let b = DMatrix::from_fn(n, k, |i, j| eig.eigenvectors[(i, order[j])]);
        let c = DMatrix::from_fn(3, n, |r, i| cmf[i][r]);
        let (projection, keeps_colour) = colour_keeping(&b, &c);
        Ok(OwnBasis {
            spectra: (0..k)
                .map(|j| b.column(j).iter().copied().collect())
                .collect(),
            discarded,
            keeps_colour,
            projection,
        })
    }

    /// K.
    pub fn len(&self) -> usize {
        self.spectra.len()
    }

    /// Whether there are no spectra.
    pub fn is_empty(&self) -> bool {
        self.spectra.is_empty()
    }

    /// The coefficients of spectrum `s` (n bands) into `out` (K).
    pub fn project(&self, s: &[f64], out: &mut [f64]) {
        for (j, o) in out.iter_mut().enumerate() {
            *o = self
                .projection
                .row(j)
                .iter()
                .zip(s)
                .map(|(p, v)| p * v)
                .sum();
        }
    }

    /// `|B c - s| / |s|` (0 for a black spectrum).
    pub fn relative_residual(&self, s: &[f64], c: &[f64]) -> f64 {
        relative_residual(s, |i| {
            self.spectra.iter().zip(c).map(|(b, c)| b[i] * c).sum()
        })
    }
}

/// `|fit - s| / |s|` with `fit(i)` the fitted spectrum's band `i` (0 for a black spectrum).
pub(crate) fn relative_residual(s: &[f64], fit: impl Fn(usize) -> f64) -> f64 {
    let (mut r2, mut s2) = (0.0, 0.0);
    for (i, v) in s.iter().enumerate() {
        r2 += (fit(i) - v).powi(2);
        s2 += v * v;
    }
    if s2 > 0.0 {
        (r2 / s2).sqrt()
    } else {
        0.0
    }
}

/// The K x n map `(I - P A) B^T + P C` with `A = C B` and `P = A^T (A A^T)^-1`: the least-squares
/// fit on B constrained to C's three colour values; the plain `B^T` where that is not possible.
fn colour_keeping(b: &DMatrix<f64>, c: &DMatrix<f64>) -> (DMatrix<f64>, bool) {
    let bt = b.transpose();
    let k = b.ncols();
    if k < 3 {
        return (bt, false);
    }
    let a = c * b;
    let aat = &a * a.transpose();
    // A badly conditioned A A^T (components with nearly no colour difference) would amplify
    // noise: keep the plain fit.
    let eig = nalgebra::SymmetricEigen::new(aat.clone());
    let (lo, hi) = eig
        .eigenvalues
        .iter()
        .fold((f64::INFINITY, 0f64), |(l, h), &v| (l.min(v), h.max(v)));
    let Some(inv) = aat.try_inverse().filter(|_| lo > hi * 1e-12) else {
        return (bt, false);
    };
    let p = a.transpose() * inv;
    let id = DMatrix::<f64>::identity(k, k);
    ((id - &p * &a) * bt + p * c, true)
}

/// The coefficients of `s` as a vector (a convenience for tests).
#[cfg(test)]
pub(crate) fn coefficients(basis: &OwnBasis, s: &[f64]) -> nalgebra::DVector<f64> {
    let mut out = vec![0.0; basis.len()];
    basis.project(s, &mut out);
    nalgebra::DVector::from_vec(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three smooth spectra over 41 bands, and colour weights (three Gaussian lobes).
    fn setup() -> (Vec<Vec<f64>>, Vec<[f64; 3]>) {
        let n = 41;
        let g = |c: f64, w: f64| -> Vec<f64> {
            (0..n)
                .map(|i| (-(((i as f64) - c) / w).powi(2)).exp())
                .collect()
        };
        let spectra = vec![g(10.0, 6.0), g(20.0, 9.0), g(32.0, 5.0), g(26.0, 3.0)];
        let (x, y, z) = (g(28.0, 6.0), g(22.0, 6.0), g(9.0, 5.0));
        let cmf = (0..n).map(|i| [x[i], y[i], z[i]]).collect();
        (spectra, cmf)
    }

    #[test]
    fn spectra_in_a_span_of_three_are_held_exactly_by_three_components() {
        let (s, cmf) = setup();
        let mut m = Moments::new(41);
        let mix = |a: f64, b: f64, c: f64| -> Vec<f64> {
            (0..41)
                .map(|i| a * s[0][i] + b * s[1][i] + c * s[2][i])
                .collect()
        };
        let pixels = [
            mix(1.0, 0.2, 0.0),
            mix(0.0, 3.0, 1.0),
            mix(0.5, 0.5, 7.0),
            mix(2.0, 0.0, 0.1),
        ];
        for (k, p) in pixels.iter().enumerate() {
            m.add(p, 0.1 * (k + 1) as f64, 1.0 + k as f64);
        }
        let b = OwnBasis::from_moments(&m, &cmf, 1e-12, MAX_K).unwrap();
        assert_eq!(b.len(), 3);
        assert!(b.keeps_colour);
        for p in &pixels {
            let c = coefficients(&b, p);
            assert!(b.relative_residual(p, c.as_slice()) < 1e-10);
        }
    }

    #[test]
    fn a_truncated_basis_keeps_each_spectrums_colour() {
        let (s, cmf) = setup();
        let mut m = Moments::new(41);
        // Many pixels in the span of the first three spectra, one faint pixel off it.
        for k in 0..50 {
            let t = k as f64 / 49.0;
            let p: Vec<f64> = (0..41)
                .map(|i| t * s[0][i] + (1.0 - t) * s[1][i] + 0.2 * t * t * s[2][i])
                .collect();
            m.add(&p, 1.0, 1.0);
        }
        let odd: Vec<f64> = (0..41).map(|i| s[3][i] + 0.3 * s[0][i]).collect();
        m.add(&odd, 1e-9, 1.0);
        assert_eq!(
            OwnBasis::from_moments(&m, &cmf, 1e-14, MAX_K)
                .unwrap()
                .len(),
            4
        );
        // Three components: the faint pixel's direction is dropped, its colour is kept.
        let b = OwnBasis::from_moments(&m, &cmf, 1e-6, MAX_K).unwrap();
        assert_eq!(b.len(), 3);
        assert!(b.keeps_colour && b.discarded > 0.0 && b.discarded < 1e-6);
        let one = OwnBasis::from_moments(&m, &cmf, 0.5, MAX_K).unwrap();
        assert!(one.len() < 3 && !one.keeps_colour);
        let xyz = |v: &[f64]| -> [f64; 3] {
            [0, 1, 2].map(|r| v.iter().zip(&cmf).map(|(a, w)| a * w[r]).sum())
        };
        let c = coefficients(&b, &odd);
        let back: Vec<f64> = (0..41)
            .map(|i| (0..3).map(|j| c[j] * b.spectra[j][i]).sum())
            .collect();
        assert!(b.relative_residual(&odd, c.as_slice()) > 0.1);
        let (a, bb) = (xyz(&odd), xyz(&back));
        for r in 0..3 {
            assert!(
                (a[r] - bb[r]).abs() < 1e-9 * a[r].abs().max(1.0),
                "{a:?} {bb:?}"
            );
        }
    }
}
