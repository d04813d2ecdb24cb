//! Sampling a map in any direction, and resampling it to another layout and orientation.

use super::directions::{dot, face_dir};
use super::faces::{locate, Face, Slot};
use super::{EnvMap, Layout, Orientation};
use crate::envmap::RgbImage;
use rayon::prelude::*;
use std::f64::consts::PI;

/// A weighted sum divided by its total weight, as a pixel value.
fn finish(acc: [f64; 3], wsum: f64) -> [f32; 3] {
    if wsum > 0.0 {
        [
            (acc[0] / wsum) as f32,
            (acc[1] / wsum) as f32,
            (acc[2] / wsum) as f32,
        ]
    } else {
        [0.0; 3]
    }
}

impl EnvMap {
    /// The map's value in direction `dir` (any length; zero gives +X's value, NaN gives black):
    /// bilinear, wrapping in longitude for lat-long and clamped within a face for cube-like
    /// layouts.
    pub fn sample(&self, dir: [f64; 3]) -> [f32; 3] {
        let (w, h) = (self.image.width, self.image.height);
        if w == 0 || h == 0 || !dir.iter().all(|c| c.is_finite()) {
            return [0.0; 3];
        }
        match self.layout.slots() {
            None => {
                // LatLongMap::latLong / pixelPosition, pixel centres at (i + 0.5) / N.
                let [x, y, z] = dir;
                let r = (x * x + z * z).sqrt();
                let lat = y.atan2(r);
                let lon = if x == 0.0 && z == 0.0 {
                    0.0
                } else {
                    x.atan2(z)
                };
                let u = 0.5 - lon / (2.0 * PI);
                let v = 0.5 - lat / PI;
                let px = u * w as f64 - 0.5;
                let py = (v * h as f64 - 0.5).clamp(0.0, (h - 1) as f64);
                let fx0 = px.floor();
                let tx = px - fx0;
                let x0 = (fx0 as i64).rem_euclid(w as i64) as usize;
                let x1 = (x0 + 1) % w;
                let y0 = py.floor() as usize;
                let y1 = (y0 + 1).min(h - 1);
                let ty = py - y0 as f64;
                self.bilerp(x0, x1, y0, y1, tx, ty)
            }
            Some(slots) => {
                let n = self.face_size();
                if n == 0 {
                    return [0.0; 3];
                }
                let face = Face::of(dir);
                let s = &slots[face.index()];
                let m = dot(dir, face.axis());
                if m <= 0.0 {
                    // Only the zero vector gets here.
                    return self.pixel(s.col * n, s.row * n);
                }
                let p = [dir[0] / m, dir[1] / m, dir[2] / m];
                let nf = n as f64;
                let fs = (dot(p, s.right) + 1.0) * 0.5;
                let ft = (dot(p, s.down) + 1.0) * 0.5;
                let px = (fs * nf - 0.5).clamp(0.0, nf - 1.0);
                let py = (ft * nf - 0.5).clamp(0.0, nf - 1.0);
                let i0 = px.floor() as usize;
                let j0 = py.floor() as usize;
                let i1 = (i0 + 1).min(n - 1);
                let j1 = (j0 + 1).min(n - 1);
                let (ox, oy) = (s.col * n, s.row * n);
                self.bilerp(
                    ox + i0,
                    ox + i1,
                    oy + j0,
                    oy + j1,
                    px - i0 as f64,
                    py - j0 as f64,
                )
            }
        }
    }

    /// Bilinear interpolation between pixels (x0, y0), (x1, y0), (x0, y1) and (x1, y1).
    fn bilerp(&self, x0: usize, x1: usize, y0: usize, y1: usize, tx: f64, ty: f64) -> [f32; 3] {
        let (a, b, c, d) = (
            self.pixel(x0, y0),
            self.pixel(x1, y0),
            self.pixel(x0, y1),
            self.pixel(x1, y1),
        );
        let mut out = [0.0f32; 3];
        for k in 0..3 {
            let top = a[k] as f64 * (1.0 - tx) + b[k] as f64 * tx;
            let bot = c[k] as f64 * (1.0 - tx) + d[k] as f64 * tx;
            out[k] = (top * (1.0 - ty) + bot * ty) as f32;
        }
        out
    }

    /// This map in another layout: `size` is the lat-long height (width 2·size) or the face
    /// size (0 is taken as 1). Each destination pixel averages a k x k stratified grid of
    /// bilinear source samples, weighted by the solid angle each sub-cell covers, with k the
    /// square root of the source-to-destination pixel ratio rounded up (at least 2, at most 64).
    /// Unused cells of a cross are black.
    pub fn resample(&self, layout: Layout, size: usize) -> EnvMap {
        self.resample_oriented(layout, size, &Orientation::default())
    }

    /// [`EnvMap::resample`], with this map's directions related to the world's by
    /// `orientation`: the result is in world (OpenEXR, Y up) orientation, so a Z-up map or one
    /// turned about the up axis comes out upright and turned back.
    pub fn resample_oriented(
        &self,
        layout: Layout,
        size: usize,
        orientation: &Orientation,
    ) -> EnvMap {
        let source = Oriented {
            map: self,
            m: orientation.to_map_matrix(),
        };
        let size = size.max(1);
        let (w, h) = layout.dimensions(size);
        let mut dst = EnvMap {
            layout,
            image: RgbImage::new(w, h),
        };
        let grid = SubSamples::new(self, &dst, size);
        let slots = layout.slots();
        dst.image
            .pixels
            .par_chunks_mut(w)
            .enumerate()
            .for_each(|(y, row)| match slots {
                None => grid.latlong_row(&source, y, row),
                Some(slots) => grid.cube_row(&source, slots, y, row),
            });
        dst
    }
}

/// A map seen through an orientation: world directions in, the map's values out.
struct Oriented<'a> {
    map: &'a EnvMap,
    /// World to map directions.
    m: [[f64; 3]; 3],
}

impl Oriented<'_> {
    /// The map's value in world direction `d`.
    fn at(&self, d: [f64; 3]) -> [f32; 3] {
        let m = &self.m;
        self.map.sample([
            m[0][0] * d[0] + m[0][1] * d[1] + m[0][2] * d[2],
            m[1][0] * d[0] + m[1][1] * d[1] + m[1][2] * d[2],
            m[2][0] * d[0] + m[2][1] * d[1] + m[2][2] * d[2],
        ])
    }
}

/// The k x k stratified sub-samples of a resampling's destination pixels.
struct SubSamples {
    k: usize,
    /// Sub-sample offsets inside a pixel.
    offsets: Vec<f64>,
    /// For a lat-long destination, the sines and cosines of every sub-column's longitude
    /// (computed once, shared by all rows); empty otherwise.
    lon_trig: Vec<(f64, f64)>,
    /// The destination's lat-long height or face size.
    size: usize,
    /// The destination's height.
    height: usize,
}

impl SubSamples {
    /// k is the square root of the source-to-destination pixel ratio rounded up (at least 2, at
    /// most 64).
    fn new(src: &EnvMap, dst: &EnvMap, size: usize) -> SubSamples {
        let (w, h) = (dst.image.width, dst.image.height);
        let dst_used = dst.used_pixels().max(1) as f64;
        let ratio = src.used_pixels() as f64 / dst_used;
        let k = (ratio.sqrt().ceil() as usize).clamp(2, 64);
        let kf = k as f64;
        let offsets: Vec<f64> = (0..k).map(|a| (a as f64 + 0.5) / kf).collect();
        let lon_trig: Vec<(f64, f64)> = match dst.layout {
            Layout::LatLong => (0..w * k)
                .map(|c| (-2.0 * PI * ((c as f64 + 0.5) / (w * k) as f64 - 0.5)).sin_cos())
                .collect(),
            _ => Vec::new(),
        };
        SubSamples {
            k,
            offsets,
            lon_trig,
            size,
            height: h,
        }
    }

    /// Row `y` of a lat-long destination, each pixel weighted by the solid-angle density
    /// cos(latitude).
    fn latlong_row(&self, source: &Oriented, y: usize, row: &mut [[f32; 3]]) {
        let k = self.k;
        // Sines and cosines of this row's sub-row latitudes: k values, on the stack for k <= 64.
        let mut lat_trig = [(0.0f64, 0.0f64); 64];
        for (t, &fy) in lat_trig.iter_mut().zip(self.offsets.iter()) {
            *t = (-PI * ((y as f64 + fy) / self.height as f64 - 0.5)).sin_cos();
        }
        for (x, out) in row.iter_mut().enumerate() {
            let mut acc = [0.0f64; 3];
            let mut wsum = 0.0;
            for &(sl, cl) in &lat_trig[..k] {
                for &(so, co) in &self.lon_trig[x * k..(x + 1) * k] {
                    // Solid-angle density cos(latitude).
                    let v = source.at([so * cl, sl, co * cl]);
                    for c in 0..3 {
                        acc[c] += cl * v[c] as f64;
                    }
                    wsum += cl;
                }
            }
            *out = finish(acc, wsum);
        }
    }

    /// Row `y` of a cube-like destination; the unused cells of a cross stay black.
    fn cube_row(&self, source: &Oriented, slots: &[Slot; 6], y: usize, row: &mut [[f32; 3]]) {
        for (x, out) in row.iter_mut().enumerate() {
            let Some((face, s, i, j)) = locate(slots, self.size, x, y) else {
                continue;
            };
            *out = self.face_pixel(source, face, s, i, j);
        }
    }

    /// Pixel (i, j) of a destination face, each sub-sample weighted by the solid-angle density
    /// 1/r^3 on the face plane.
    fn face_pixel(&self, source: &Oriented, face: Face, s: &Slot, i: usize, j: usize) -> [f32; 3] {
        let nf = self.size as f64;
        let mut acc = [0.0f64; 3];
        let mut wsum = 0.0;
        for &fy in &self.offsets {
            for &fx in &self.offsets {
                let d = face_dir(face, s, (i as f64 + fx) / nf, (j as f64 + fy) / nf);
                let r2 = dot(d, d);
                // Solid-angle density 1/r^3 on the face plane.
                let wt = 1.0 / (r2 * r2.sqrt());
                let v = source.at(d);
                for c in 0..3 {
                    acc[c] += wt * v[c] as f64;
                }
                wsum += wt;
            }
        }
        finish(acc, wsum)
    }
}
