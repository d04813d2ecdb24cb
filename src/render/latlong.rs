//! Lat-long maps of coefficients: texel directions and solid angles, bilinear lookups, and a
//! file's map at the lighting's and the background's resolutions.
//!
//! Maps are lat-long in OpenEXR's orientation ([`crate::envmap::layout`]): texel `(x, y)` looks
//! at longitude `-2 pi ((x + 0.5) / w - 0.5)` and latitude `pi / 2 - pi (y + 0.5) / h`. Lookups
//! are bilinear, wrapping in longitude and clamped in latitude; `sample` here and `sample_map` in
//! `gpu.wgsl` are the same function.

use rayon::prelude::*;
use std::f64::consts::PI;

/// Rows of the lat-long a file map is resampled to before filtering.
pub const SOURCE_ROWS: usize = 64;
/// Rows of the lat-long the background is seen in (the lighting's is coarser: it is filtered).
pub const BACKGROUND_ROWS: usize = 256;

/// A lat-long map of `4 groups` coefficients per texel: texel (x, y) holds the groups
/// `texels[(y w + x) groups + g]`, coefficients `4 g .. 4 g + 3`.
#[derive(Debug, Clone, PartialEq)]
pub struct CoeffMap {
    /// Texels per row (longitude).
    pub width: usize,
    /// Rows (latitude), the first looking up (+Y).
    pub height: usize,
    /// Groups of four coefficients per texel.
    pub groups: usize,
    /// `width * height * groups` groups, row-major, a texel's groups together.
    pub texels: Vec<[f32; 4]>,
}

impl CoeffMap {
    /// The same value everywhere (1 x 1).
    pub fn constant(c: [f32; 4]) -> CoeffMap {
        CoeffMap {
            width: 1,
            height: 1,
            groups: 1,
            texels: vec![c],
        }
    }

    /// A `2 rows x rows` map of one group computed per texel direction.
    pub fn from_fn(rows: usize, f: impl Fn([f64; 3]) -> [f32; 4] + Sync) -> CoeffMap {
        CoeffMap::from_fn_groups(rows, 1, |d, out| out[0] = f(d))
    }

    /// A `2 rows x rows` map of `groups` groups computed per texel direction.
    pub fn from_fn_groups(
        rows: usize,
        groups: usize,
        f: impl Fn([f64; 3], &mut [[f32; 4]]) + Sync,
    ) -> CoeffMap {
        let (w, h) = (2 * rows, rows);
        let mut texels = vec![[0f32; 4]; w * h * groups];
        texels
            .par_chunks_mut(groups)
            .enumerate()
            .for_each(|(i, out)| f(direction(w, h, i % w, i / w), out));
        CoeffMap {
            width: w,
            height: h,
            groups,
            texels,
        }
    }

    /// Bilinear lookup in direction `dir` (unit): `4 groups` coefficients.
    pub fn sample(&self, dir: [f64; 3]) -> Vec<f64> {
        sample(&self.texels, self.width, self.height, self.groups, dir)
    }

    /// The coefficients of texel `i` (row-major).
    pub fn texel(&self, i: usize) -> impl Iterator<Item = f32> + '_ {
        self.texels[i * self.groups..(i + 1) * self.groups]
            .iter()
            .flatten()
            .copied()
    }
}

/// A file's map at two resolutions: the one the lighting is filtered from, and the one seen as
/// the background (and behind transparent objects).
#[derive(Debug, Clone, PartialEq)]
pub struct Maps {
    /// [`SOURCE_ROWS`] rows.
    pub light: CoeffMap,
    /// Up to [`BACKGROUND_ROWS`] rows.
    pub seen: CoeffMap,
}

/// The unit direction of texel (x, y) of a `w x h` lat-long.
pub fn direction(w: usize, h: usize, x: usize, y: usize) -> [f64; 3] {
    let lon = -2.0 * PI * ((x as f64 + 0.5) / w as f64 - 0.5);
    let lat = PI / 2.0 - PI * (y as f64 + 0.5) / h as f64;
    [lon.sin() * lat.cos(), lat.sin(), lon.cos() * lat.cos()]
}

/// The solid angle of a texel in row `y` of a `w x h` lat-long.
pub fn solid_angle(w: usize, h: usize, y: usize) -> f64 {
    let t0 = PI * y as f64 / h as f64;
    let t1 = PI * (y + 1) as f64 / h as f64;
    2.0 * PI / w as f64 * (t0.cos() - t1.cos())
}

/// The four texels around direction `dir` in a `w x h` lat-long and their bilinear weights.
pub fn bilinear(w: usize, h: usize, dir: [f64; 3]) -> [(usize, f64); 4] {
    // A one-texel map (every uniform lighting's) has no direction to look up.
    if w * h == 1 {
        return [(0, 1.0), (0, 0.0), (0, 0.0), (0, 0.0)];
    }
    let u = 0.5 - dir[0].atan2(dir[2]) / (2.0 * PI);
    let v = dir[1].clamp(-1.0, 1.0).acos() / PI;
    let fx = u * w as f64 - 0.5;
    let fy = (v * h as f64 - 0.5).clamp(0.0, (h - 1) as f64);
    let x0f = fx.floor();
    let tx = fx - x0f;
    let y0f = fy.floor();
    let ty = fy - y0f;
    let x0 = (x0f as i64).rem_euclid(w as i64) as usize;
    let x1 = (x0 + 1) % w;
    let y0 = y0f as usize;
    let y1 = (y0 + 1).min(h - 1);
    [
        (y0 * w + x0, (1.0 - tx) * (1.0 - ty)),
        (y0 * w + x1, tx * (1.0 - ty)),
        (y1 * w + x0, (1.0 - tx) * ty),
        (y1 * w + x1, tx * ty),
    ]
}

/// Bilinear lookup of a `w x h` lat-long of `groups` groups per texel stored row-major in
/// `texels`: `4 groups` coefficients.
pub fn sample(texels: &[[f32; 4]], w: usize, h: usize, groups: usize, dir: [f64; 3]) -> Vec<f64> {
    let mut out = Vec::new();
    sample_into(texels, w, h, groups, dir, &mut out);
    out
}

/// [`sample`] into `out` (resized to `4 groups`), for callers that reuse one buffer.
pub fn sample_into(
    texels: &[[f32; 4]],
    w: usize,
    h: usize,
    groups: usize,
    dir: [f64; 3],
    out: &mut Vec<f64>,
) {
    out.clear();
    out.resize(4 * groups, 0.0);
    for (t, wt) in bilinear(w, h, dir) {
        for (g, c) in texels[t * groups..(t + 1) * groups].iter().enumerate() {
            for k in 0..4 {
                out[4 * g + k] += wt * c[k] as f64;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texel_centres_sample_to_themselves_and_solid_angles_tile_the_sphere() {
        let (w, h) = (16, 8);
        let m = CoeffMap {
            width: w,
            height: h,
            groups: 1,
            texels: (0..w * h).map(|i| [i as f32, 0.0, 0.0, 1.0]).collect(),
        };
        for y in 0..h {
            for x in 0..w {
                let v = m.sample(direction(w, h, x, y));
                assert!((v[0] - (y * w + x) as f64).abs() < 1e-6, "({x},{y}) {v:?}");
                assert!((v[3] - 1.0).abs() < 1e-12);
            }
        }
        let total: f64 = (0..h).map(|y| w as f64 * solid_angle(w, h, y)).sum();
        assert!((total - 4.0 * PI).abs() < 1e-12);
    }
}
