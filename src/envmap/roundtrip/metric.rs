//! Luminance and round-trip colour difference of linear RGB pixels of one colour space: what
//! every conversion engine measures its pixels by.

use crate::colorimetry::{delta_e_2000, Lab, RgbSpace, Xyz};
use nalgebra::{Matrix3, Vector3};

/// Relative difference between a pixel and its round trip below which the CIEDE2000 is taken
/// as 0 (rounding, not a colour difference).
pub(crate) const ROUND_TRIP_ZERO: f64 = 1e-12;

/// Measures linear RGB pixels of a space.
#[derive(Debug, Clone)]
pub struct RgbMetric {
    /// RGB -> luminance row of the space.
    y_row: [f64; 3],
    /// RGB -> XYZ (x100, as `RgbSpace::xyz_from_rgb`), computed once: the round trip needs it
    /// per pixel.
    to_xyz: Matrix3<f64>,
    white: Xyz,
}

impl RgbMetric {
    /// The metric of linear RGB pixels of `space`.
    pub fn new(space: &RgbSpace) -> RgbMetric {
        let m = space.to_xyz_matrix();
        RgbMetric {
            y_row: [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
            to_xyz: m * 100.0,
            white: space.xyz_from_rgb([1.0, 1.0, 1.0]),
        }
    }

    /// Luminance of a linear RGB pixel.
    pub fn luminance(&self, rgb: [f32; 3]) -> f64 {
        self.y_row[0] * rgb[0] as f64
            + self.y_row[1] * rgb[1] as f64
            + self.y_row[2] * rgb[2] as f64
    }

    /// XYZ (Y = luminance) of a linear RGB colour.
    pub fn xyz(&self, rgb: &Vector3<f64>) -> Vector3<f64> {
        self.to_xyz * rgb / 100.0
    }

    /// CIEDE2000 between an input pixel and its round trip, both scaled so the input has Y = 1
    /// (the comparison is of colour and relative brightness, whatever the HDR level).
    pub fn round_trip_error(&self, rgb: [f32; 3], back: [f64; 3]) -> f64 {
        let y = self.luminance(rgb);
        if y.is_nan() || y <= 0.0 {
            return 0.0;
        }
        let input = [rgb[0] as f64 / y, rgb[1] as f64 / y, rgb[2] as f64 / y];
        let out = back.map(|v| v / y);
        // A round trip exact to rounding (the exact and faithful modes) is 0, without the cost
        // of CIEDE2000: at 1e-12 of the pixel's scale its CIEDE2000 would be below 1e-7.
        let scale = input.iter().fold(1f64, |m, v| m.max(v.abs()));
        if (0..3).all(|k| (input[k] - out[k]).abs() <= ROUND_TRIP_ZERO * scale) {
            return 0.0;
        }
        self.delta_e(input, out)
    }

    /// CIEDE2000 between two linear RGB colours of the space.
    pub fn delta_e(&self, a: [f64; 3], b: [f64; 3]) -> f64 {
        let xyz = |v: [f64; 3]| Xyz((self.to_xyz * Vector3::from(v)).into());
        delta_e_2000(
            Lab::from_xyz(xyz(a), self.white),
            Lab::from_xyz(xyz(b), self.white),
        )
    }
}
