//! Pixel directions and exact solid angles of every layout.

use super::faces::{locate, Face, Slot};
use super::EnvMap;
use std::f64::consts::PI;

/// The length of `d`.
fn norm(d: [f64; 3]) -> f64 {
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

/// `d` scaled to unit length.
fn normalize(d: [f64; 3]) -> [f64; 3] {
    let n = norm(d);
    [d[0] / n, d[1] / n, d[2] / n]
}

/// The dot product of `a` and `b`.
pub(super) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Lat-long direction at continuous image position (u, v) in [0, 1]^2 (`LatLongMap::direction`
/// with pixel centres at (i + 0.5) / N).
fn latlong_dir(u: f64, v: f64) -> [f64; 3] {
    let lat = -PI * (v - 0.5);
    let lon = -2.0 * PI * (u - 0.5);
    let (sl, cl) = lat.sin_cos();
    let (so, co) = lon.sin_cos();
    [so * cl, sl, co * cl]
}

/// Cube-face direction (not normalised) at face coordinates (s, t) in [0, 1]^2.
pub(super) fn face_dir(face: Face, s: &Slot, fs: f64, ft: f64) -> [f64; 3] {
    let a = face.axis();
    let (p, q) = (2.0 * fs - 1.0, 2.0 * ft - 1.0);
    [
        a[0] + p * s.right[0] + q * s.down[0],
        a[1] + p * s.right[1] + q * s.down[1],
        a[2] + p * s.right[2] + q * s.down[2],
    ]
}

/// The solid angle of the face region [0, x] x [0, y] seen from the cube's centre, face at
/// distance 1 (Mathar 2005; the same formula as cmft's `areaElement`).
fn area_element(x: f64, y: f64) -> f64 {
    (x * y).atan2((x * x + y * y + 1.0).sqrt())
}

impl EnvMap {
    /// The unit direction at sub-pixel offset (fx, fy) in [0, 1]^2 of pixel (x, y); None outside
    /// the image or in an unused cell.
    fn direction_at(&self, x: usize, y: usize, fx: f64, fy: f64) -> Option<[f64; 3]> {
        let (w, h) = (self.image.width, self.image.height);
        if x >= w || y >= h {
            return None;
        }
        match self.layout.slots() {
            None => Some(latlong_dir(
                (x as f64 + fx) / w as f64,
                (y as f64 + fy) / h as f64,
            )),
            Some(slots) => {
                let n = self.face_size().max(1);
                let (face, s, i, j) = locate(slots, n, x, y)?;
                let nf = n as f64;
                let d = face_dir(face, s, (i as f64 + fx) / nf, (j as f64 + fy) / nf);
                Some(normalize(d))
            }
        }
    }

    /// The unit direction of pixel (x, y)'s centre; None for the unused cells of a cross (and
    /// outside the image).
    pub fn direction(&self, x: usize, y: usize) -> Option<[f64; 3]> {
        self.direction_at(x, y, 0.5, 0.5)
    }

    /// Whether pixel (x, y) has a direction (every pixel of a lat-long does; a cross or strip's
    /// unused cells do not): `direction(x, y).is_some()` without computing it.
    pub fn has_direction(&self, x: usize, y: usize) -> bool {
        match self.layout.slots() {
            None => x < self.image.width && y < self.image.height,
            Some(_) => self.direction(x, y).is_some(),
        }
    }

    /// The solid angle every pixel of row `y` has, where they all have the same (a lat-long's
    /// row): `solid_angle(x, y)` for any x in the image. None for cube layouts.
    pub fn row_solid_angle(&self, y: usize) -> Option<f64> {
        match self.layout.slots() {
            None if self.image.width > 0 => Some(self.solid_angle(0, y)),
            _ => None,
        }
    }

    /// The exact solid angle of pixel (x, y) in steradians (0 in unused cells and outside the
    /// image); over all pixels these sum to 4π.
    pub fn solid_angle(&self, x: usize, y: usize) -> f64 {
        let (w, h) = (self.image.width, self.image.height);
        if x >= w || y >= h {
            return 0.0;
        }
        match self.layout.slots() {
            None => {
                // A band between two latitudes, split evenly in longitude.
                let t0 = PI * y as f64 / h as f64;
                let t1 = PI * (y + 1) as f64 / h as f64;
                2.0 * PI / w as f64 * (t0.cos() - t1.cos())
            }
            Some(slots) => {
                let n = self.face_size().max(1);
                let Some((_, _, i, j)) = locate(slots, n, x, y) else {
                    return 0.0;
                };
                let nf = n as f64;
                let (a0, a1) = (2.0 * i as f64 / nf - 1.0, 2.0 * (i + 1) as f64 / nf - 1.0);
                let (b0, b1) = (2.0 * j as f64 / nf - 1.0, 2.0 * (j + 1) as f64 / nf - 1.0);
                (area_element(a1, b1) - area_element(a0, b1) - area_element(a1, b0)
                    + area_element(a0, b0))
                .abs()
            }
        }
    }

    /// Every used pixel as (x, y, unit direction, solid angle, value), row by row; the unused
    /// cells of a cross are skipped.
    pub fn pixels_with_directions(
        &self,
    ) -> impl Iterator<Item = (usize, usize, [f64; 3], f64, [f32; 3])> + '_ {
        let w = self.image.width;
        (0..self.image.height).flat_map(move |y| {
            (0..w).filter_map(move |x| {
                self.direction(x, y)
                    .map(|d| (x, y, d, self.solid_angle(x, y), self.pixel(x, y)))
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn area_element_closed_form() {
        // A whole face: 4 * atan2(1, sqrt 3) = 4 * pi / 6.
        let face = area_element(1.0, 1.0) - area_element(-1.0, 1.0) - area_element(1.0, -1.0)
            + area_element(-1.0, -1.0);
        assert!((face - 4.0 * PI / 6.0).abs() < 1e-15);
        assert_eq!(area_element(0.0, 0.7), 0.0);
    }
}
