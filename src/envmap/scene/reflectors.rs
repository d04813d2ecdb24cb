//! The lights that light each reflector: a mix of the scene's light spectra per direction.
//!
//! A reflector's spectrum is its reflectance times the light that reaches it; in an RGB map only
//! the product is seen. Two models of the light reaching a pixel (`--reflectors`):
//! - `global`: every reflector is lit by all lights in the proportions of their energy (their
//!   share of luminance x solid angle), the irradiance at the camera's position;
//! - `local` (the default): the mix is read from the colours of the reflectors around the pixel
//!   (a local grey world): their solid-angle-weighted mean XYZ over a Gaussian window of
//!   [`LOCAL_SIGMA_DEG`] is the colour of the mix of light spectra (white XYZ each) nearest it,
//!   pulled towards the global mix by [`LOCAL_PRIOR`]. A wall beside a window is bluer than one
//!   under a warm lamp, and gets more daylight in its carrier.
//!
//! Mixes are kept on a coarse lat-long grid of [`GRID_WIDTH`] and interpolated per pixel.

use super::cells::Cells;
use super::{Light, REFLECTOR};
use crate::colorimetry::Xyz;
use nalgebra::Vector3;
use rayon::prelude::*;

/// How the light reaching each reflector is estimated (`--reflectors`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(tag = "model", rename_all = "lowercase")]
pub enum ReflectorModel {
    /// Every reflector is lit by all lights in the proportions of their energy.
    Global,
    /// The mix is read from the colours of the reflectors around each pixel (a local grey world).
    Local {
        /// How strongly the mix is pulled towards the global one (0: the colours alone).
        prior: f64,
    },
}

impl Default for ReflectorModel {
    fn default() -> Self {
        ReflectorModel::Local { prior: LOCAL_PRIOR }
    }
}

/// Width (sigma) of the `local` model's Gaussian window on the sphere (degrees).
pub const LOCAL_SIGMA_DEG: f64 = 20.0;
/// The default pull towards the global mix, chosen by measurement on the truth scenes
/// (docs/scenes.md): with the grey world read from the surfaces that could be grey
/// ([`NEUTRAL_UV`]), 0.1 lets the walls of a mixed office follow their window or their tubes
/// (mean rendition 0.57, against 0.65 at 0.5 and 0.52 at 0) and keeps a street of sodium lamps
/// and one LED at 0.41 (0.53 at 0: with no pull the shop fronts lit by the LED pull the walls
/// around them towards it).
pub const LOCAL_PRIOR: f64 = 0.1;
/// The CIE 1960 uv distance from the lights' whites at which a reflector counts half in its
/// neighbourhood's grey world (`neutral_weight`).
pub const NEUTRAL_UV: f64 = 0.003;
/// Width of the coarse lat-long grid the mixes are kept on (cells; its height is half).
pub const GRID_WIDTH: usize = 64;

/// A distinct light spectrum that reflectors can be lit by.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Carrier {
    /// The spectrum's name ([`super::LightSpd::label`]).
    pub spd: String,
    /// Its share of the lights' energy.
    pub share: f64,
    /// White XYZ (Y = 1).
    #[serde(skip)]
    pub xyz: Vector3<f64>,
}

/// The mixes of light spectra that light the reflectors.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Reflectors {
    /// The model the mixes were estimated with.
    pub model: ReflectorModel,
    /// The distinct light spectra, with their shares of the lights' energy.
    pub carriers: Vec<Carrier>,
    /// Per light of the scene: its carrier.
    #[serde(skip)]
    pub light_carrier: Vec<usize>,
    /// Per coarse cell: the weight of each carrier (summing to 1).
    #[serde(skip)]
    grid: Vec<Vec<f32>>,
    #[serde(skip)]
    grid_height: usize,
}

impl Reflectors {
    /// The reflectors' mixes for a scene's lights.
    pub fn estimate(
        cells: &Cells,
        label: &[u16],
        lights: &[Light],
        model: ReflectorModel,
    ) -> Reflectors {
        let (carriers, light_carrier) = carriers_of(lights);
        let prior: Vec<f64> = carriers.iter().map(|c| c.share).collect();
        let grid_height = GRID_WIDTH / 2;
        let grid = match model {
            ReflectorModel::Local { prior: weight } if carriers.len() >= 2 => {
                local_mixes(cells, label, &carriers, &prior, weight, grid_height)
            }
            _ => vec![prior.iter().map(|&v| v as f32).collect(); GRID_WIDTH * grid_height],
        };
        Reflectors {
            model,
            carriers,
            light_carrier,
            grid,
            grid_height,
        }
    }

    /// The carriers' weights at direction `d`, interpolated bilinearly between grid cells.
    pub fn mix_at(&self, d: [f64; 3]) -> Vec<f32> {
        let n = self.carriers.len();
        if n == 0 {
            return Vec::new();
        }
        let (w, h) = (GRID_WIDTH, self.grid_height);
        let lon = d[0].atan2(d[2]);
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(1e-300);
        let lat = (d[1] / len).clamp(-1.0, 1.0).asin();
        let u = (0.5 - lon / (2.0 * std::f64::consts::PI)) * w as f64 - 0.5;
        let v = ((0.5 - lat / std::f64::consts::PI) * h as f64 - 0.5).clamp(0.0, h as f64 - 1.0);
        let (x0, y0) = (u.floor(), v.floor());
        let (fx, fy) = ((u - x0) as f32, (v - y0) as f32);
        let y1 = (y0 as usize + 1).min(h - 1);
        let mut out = vec![0f32; n];
        for (yy, wy) in [(y0 as usize, 1.0 - fy), (y1, fy)] {
            for (xx, wx) in [(x0, 1.0 - fx), (x0 + 1.0, fx)] {
                let xi = (xx as isize).rem_euclid(w as isize) as usize;
                for (o, &g) in out.iter_mut().zip(&self.grid[yy * w + xi]) {
                    *o += wx * wy * g;
                }
            }
        }
        out
    }
}

/// The distinct spectra of the lights (by name), with their energy shares.
fn carriers_of(lights: &[Light]) -> (Vec<Carrier>, Vec<usize>) {
    let total: f64 = lights.iter().map(|l| l.energy_share).sum();
    let mut carriers: Vec<Carrier> = Vec::new();
    let mut index = Vec::with_capacity(lights.len());
    for l in lights {
        let k = match carriers.iter().position(|c| c.spd == l.spd) {
            Some(k) => k,
            None => {
                carriers.push(Carrier {
                    spd: l.spd.clone(),
                    share: 0.0,
                    xyz: l.colour,
                });
                carriers.len() - 1
            }
        };
        carriers[k].share += if total > 0.0 {
            l.energy_share / total
        } else {
            1.0 / lights.len() as f64
        };
        index.push(k);
    }
    (carriers, index)
}

/// The local grey-world mixes on the coarse grid.
fn local_mixes(
    cells: &Cells,
    label: &[u16],
    carriers: &[Carrier],
    prior: &[f64],
    weight: f64,
    grid_height: usize,
) -> Vec<Vec<f32>> {
    let coarse = GRID_WIDTH * grid_height;
    let coarse_dir = |c: usize| -> Vector3<f64> {
        let (x, y) = (c % GRID_WIDTH, c / GRID_WIDTH);
        let u = (x as f64 + 0.5) / GRID_WIDTH as f64;
        let v = (y as f64 + 0.5) / grid_height as f64;
        let (lat, lon) = (
            -std::f64::consts::PI * (v - 0.5),
            -2.0 * std::f64::consts::PI * (u - 0.5),
        );
        Vector3::new(lon.sin() * lat.cos(), lat.sin(), lon.cos() * lat.cos())
    };
    let whites: Vec<[f64; 2]> = carriers
        .iter()
        .map(|c| Xyz::new(c.xyz[0], c.xyz[1], c.xyz[2]).uv1960())
        .collect();
    // Reflectors' XYZ x solid angle x neutrality, computed on every core and gathered into
    // the coarse cells in cell order (the sums as a serial loop makes them).
    let weighed: Vec<Option<(usize, Vector3<f64>)>> = label
        .par_iter()
        .enumerate()
        .map(|(i, &l)| {
            (l == REFLECTOR).then(|| {
                let c = coarse_cell(cells.direction(i), grid_height);
                let xyz = cells.xyz(i);
                (c, xyz * cells.omega(i) * neutral_weight(&whites, &xyz))
            })
        })
        .collect();
    let mut sums = vec![Vector3::<f64>::zeros(); coarse];
    for (c, v) in weighed.into_iter().flatten() {
        sums[c] += v;
    }
    let dirs: Vec<Vector3<f64>> = (0..coarse).map(coarse_dir).collect();
    let kappa = 1.0 / LOCAL_SIGMA_DEG.to_radians().powi(2);
    (0..coarse)
        .into_par_iter()
        .map(|c| {
            let mut s = Vector3::zeros();
            for (k, sum) in sums.iter().enumerate() {
                if sum[1] > 0.0 {
                    s += sum * (kappa * (dirs[c].dot(&dirs[k]) - 1.0)).exp();
                }
            }
            let m = if s[1] > 0.0 {
                nearest_mix(carriers, prior, weight, &(s / s[1]))
            } else {
                prior.to_vec()
            };
            m.iter().map(|&v| v as f32).collect()
        })
        .collect()
}

/// How much a reflector counts in its neighbourhood's grey world: 1 for a colour some mix of the
/// lights' whites can make, falling off as `1 / (1 + (d / NEUTRAL_UV)^2)` with its CIE 1960 uv
/// distance `d` from the nearest such mix (the segments between the whites). A saturated
/// surface says more about itself than about its light (an orange shop front under a white lamp
/// is not orange light), so the mix is read mostly from the surfaces that could be grey.
fn neutral_weight(whites: &[[f64; 2]], xyz: &Vector3<f64>) -> f64 {
    if xyz.sum().is_nan() || xyz.sum() <= 0.0 || whites.is_empty() {
        return 1.0;
    }
    let p = Xyz::new(xyz[0], xyz[1], xyz[2]).uv1960();
    let mut d = f64::INFINITY;
    for (a, u) in whites.iter().enumerate() {
        for v in &whites[a..] {
            d = d.min(segment_distance(p, *u, *v));
        }
    }
    1.0 / (1.0 + (d / NEUTRAL_UV).powi(2))
}

/// The distance from `p` to the segment `u`-`v` (a point when they coincide).
fn segment_distance(p: [f64; 2], u: [f64; 2], v: [f64; 2]) -> f64 {
    let e = [v[0] - u[0], v[1] - u[1]];
    let l2 = e[0] * e[0] + e[1] * e[1];
    let t = if l2 > 0.0 {
        (((p[0] - u[0]) * e[0] + (p[1] - u[1]) * e[1]) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - u[0] - t * e[0]).hypot(p[1] - u[1] - t * e[1])
}

fn coarse_cell(d: [f64; 3], grid_height: usize) -> usize {
    let lon = d[0].atan2(d[2]);
    let lat = d[1].clamp(-1.0, 1.0).asin();
    let u = 0.5 - lon / (2.0 * std::f64::consts::PI);
    let v = 0.5 - lat / std::f64::consts::PI;
    let x = ((u * GRID_WIDTH as f64) as usize).min(GRID_WIDTH - 1);
    let y = ((v * grid_height as f64) as usize).min(grid_height - 1);
    y * GRID_WIDTH + x
}

/// The mix of the carriers' whites (on the simplex) nearest `target` (XYZ, Y = 1), pulled
/// towards `prior`: min |sum m_k xyz_k - target|^2 + weight |m - prior|^2, by projected
/// gradient descent.
pub fn nearest_mix(
    carriers: &[Carrier],
    prior: &[f64],
    weight: f64,
    target: &Vector3<f64>,
) -> Vec<f64> {
    let n = carriers.len();
    let mut m = prior.to_vec();
    let lipschitz: f64 =
        2.0 * carriers.iter().map(|c| c.xyz.norm_squared()).sum::<f64>() + 2.0 * weight;
    let step = 1.0 / lipschitz;
    for _ in 0..300 {
        let mut mix = Vector3::zeros();
        for (c, &w) in carriers.iter().zip(&m) {
            mix += c.xyz * w;
        }
        let r = mix - target;
        let grad: Vec<f64> = (0..n)
            .map(|k| 2.0 * carriers[k].xyz.dot(&r) + 2.0 * weight * (m[k] - prior[k]))
            .collect();
        let next: Vec<f64> = (0..n).map(|k| m[k] - step * grad[k]).collect();
        m = project_simplex(&next);
    }
    m
}

/// The Euclidean projection onto the probability simplex (Duchi et al. 2008).
pub fn project_simplex(v: &[f64]) -> Vec<f64> {
    let mut u = v.to_vec();
    u.sort_by(|a, b| b.total_cmp(a));
    let mut acc = 0.0;
    let mut theta = 0.0;
    for (j, &x) in u.iter().enumerate() {
        acc += x;
        let t = (acc - 1.0) / (j + 1) as f64;
        if x - t > 0.0 {
            theta = t;
        }
    }
    v.iter().map(|&x| (x - theta).max(0.0)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn carrier(spd: &str, xy: [f64; 2], share: f64) -> Carrier {
        let xyz = Vector3::new(xy[0] / xy[1], 1.0, (1.0 - xy[0] - xy[1]) / xy[1]);
        Carrier {
            spd: spd.into(),
            share,
            xyz,
        }
    }

    #[test]
    fn the_simplex_projection_is_a_projection() {
        let p = project_simplex(&[0.2, 0.9, -0.3]);
        assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!(p.iter().all(|&v| v >= 0.0));
        assert_eq!(project_simplex(&[0.3, 0.7]), vec![0.3, 0.7]);
    }

    #[test]
    fn a_surface_counts_in_the_grey_world_as_far_as_it_could_be_grey() {
        let whites = [[0.1978, 0.3122], [0.2560, 0.3495]]; // D65 and A, CIE 1960 uv
        let at = |uv: [f64; 2]| {
            // XYZ of CIE 1960 uv at Y = 1: x = 3u / (2u - 8v + 4), y = 2v / (2u - 8v + 4).
            let d = 2.0 * uv[0] - 8.0 * uv[1] + 4.0;
            let (x, y) = (3.0 * uv[0] / d, 2.0 * uv[1] / d);
            neutral_weight(&whites, &Vector3::new(x / y, 1.0, (1.0 - x - y) / y))
        };
        // On either white, and half way between them (a mix of the two lights): grey.
        assert!((at(whites[0]) - 1.0).abs() < 1e-9);
        assert!((at([0.2269, 0.33085]) - 1.0).abs() < 1e-9);
        // NEUTRAL_UV off the segment counts half; five times as far, 1/26.
        let (ex, ey) = (whites[1][0] - whites[0][0], whites[1][1] - whites[0][1]);
        let len = ex.hypot(ey);
        let off = |k: f64| [0.2269 - ey / len * k, 0.33085 + ex / len * k];
        assert!(
            (at(off(NEUTRAL_UV)) - 0.5).abs() < 1e-3,
            "{}",
            at(off(NEUTRAL_UV))
        );
        assert!((at(off(5.0 * NEUTRAL_UV)) - 1.0 / 26.0).abs() < 1e-3);
        // Beyond the segment's end the distance is to the end point.
        assert!((at([whites[1][0] + NEUTRAL_UV, whites[1][1]]) - 0.5).abs() < 1e-3);
    }

    #[test]
    fn a_colour_between_two_lights_is_their_mix() {
        let cs = [
            carrier("daylight", [0.3127, 0.3290], 0.5),
            carrier("A", [0.4476, 0.4074], 0.5),
        ];
        let prior = [0.5, 0.5];
        // 80% daylight, 20% A.
        let target = cs[0].xyz * 0.8 + cs[1].xyz * 0.2;
        let m = nearest_mix(&cs, &prior, 0.02, &target);
        assert!((m[0] - 0.8).abs() < 0.03, "{m:?}");
        // Pure A's colour: almost all A.
        let m = nearest_mix(&cs, &prior, 0.02, &cs[1].xyz);
        assert!(m[1] > 0.9, "{m:?}");
    }
}
