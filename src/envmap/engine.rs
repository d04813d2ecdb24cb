//! The per-pixel engine of the conversion: linear RGB -> basis coefficients -> spectral radiance,
//! and the spectrum's RGB back, on the output wavelength grid.
//!
//! Radiometric scale (the convention of pbrt-v4 and Mitsuba 3): luminance is
//! `Y = sum(L ybar) / sum(ybar)`, and one global factor makes the main light's SPD, the spectrum
//! of RGB (1,1,1), have Y = 1. So RGB (1,1,1) under D65 becomes D65 scaled to Y = 1.
//! Sun pixels get the sun's SPD at the luminance their own conversion would have had.

use crate::colorimetry::{delta_e_2000, Cmfs, Lab, Xyz};
use crate::error::{Error, Result};
use crate::fit::{Fit, Upsampler};
use crate::spectrum::{Interpolation, Rule, Spectrum, Tabulated, WavelengthGrid};
use nalgebra::{Matrix3, Vector3};

/// Everything needed to turn one pixel into a spectrum.
#[derive(Debug, Clone)]
pub struct Engine {
    grid: WavelengthGrid,
    upsampler: Upsampler,
    /// B_j = MCC_j * S * k on the output grid, k making Y(S) = 1.
    basis: [Vec<f32>; 3],
    /// Luminance of each basis spectrum.
    basis_y: [f64; 3],
    /// Linear RGB of each basis spectrum (columns).
    basis_rgb: Matrix3<f64>,
    /// The main light's RGB at Y = 1: the white balance the paper's premise implies.
    light_rgb: Vector3<f64>,
    /// The sun's SPD at Y = 1 and its RGB.
    sun: Option<(Vec<f32>, Vector3<f64>)>,
    /// RGB -> luminance row of the space.
    y_row: [f64; 3],
    /// RGB -> XYZ (x100, as `RgbSpace::xyz_from_rgb`), computed once: the round trip needs it
    /// per pixel.
    to_xyz: nalgebra::Matrix3<f64>,
    white: Xyz,
}

/// What one pixel became.
#[derive(Debug, Clone, Copy)]
pub struct PixelResult {
    /// Linear RGB of the written spectrum, white-balanced to the main light (compare with input).
    pub rgb_back: [f64; 3],
    /// The spectrum's luminance.
    pub luminance: f64,
}

impl Engine {
    /// `fit` gives the mode, basis reflectances and main light (on its own grid); `grid` is the
    /// output grid; `sun_spd` the sun's SPD if sun pixels are to be replaced.
    pub fn new(
        fit: &Fit,
        grid: WavelengthGrid,
        rule: Rule,
        sun_spd: Option<&Tabulated>,
    ) -> Result<Engine> {
        let space = fit.rgb_space();
        let fit_grid = fit.grid;
        let on_grid = |values: &[f64], interp: Interpolation| -> Result<Spectrum> {
            let w: Vec<f64> = fit_grid.wavelengths_nm().collect();
            Ok(Tabulated::new(w, values.to_vec())?.resample(&grid, interp))
        };
        let light = on_grid(&fit.light_spd, Interpolation::LIGHT)?;
        let cmfs = Cmfs::new(fit.observer, &grid)?;
        let y_norm = cmfs.y.integrate(rule);
        let luminance_of =
            |s: &Spectrum| -> Result<f64> { Ok(s.try_mul(&cmfs.y)?.integrate(rule) / y_norm) };
        let rgb_of = |s: &Spectrum| -> Result<Vector3<f64>> {
            let [x, y, z] = cmfs.integrate(s, rule)?;
            // XYZ with Y = luminance, on the 0..100 scale the colour spaces expect.
            let xyz = Xyz::new(100.0 * x / y_norm, 100.0 * y / y_norm, 100.0 * z / y_norm);
            Ok(Vector3::from(space.rgb_from_xyz(xyz)))
        };
        let light_y = luminance_of(&light)?;
        if !light_y.is_finite() || light_y <= 0.0 {
            return Err(Error::invalid(format!(
                "the main light {} has no visible energy on the output grid {grid}",
                fit.light
            )));
        }
        let light = light.scaled(1.0 / light_y);
        let mut basis: [Vec<f32>; 3] = Default::default();
        let mut basis_y = [0.0; 3];
        let mut basis_rgb = Matrix3::zeros();
        for j in 0..3 {
            let b = on_grid(&fit.basis_reflectance[j], Interpolation::SMOOTH)?.try_mul(&light)?;
            basis_y[j] = luminance_of(&b)?;
            basis_rgb.set_column(j, &rgb_of(&b)?);
            basis[j] = b.values().iter().map(|&v| v as f32).collect();
        }
        let sun = match sun_spd {
            Some(t) => {
                let s = t.resample(&grid, Interpolation::LIGHT);
                let y = luminance_of(&s)?;
                if !y.is_finite() || y <= 0.0 {
                    return Err(Error::invalid(format!(
                        "the sun's SPD has no visible energy on {grid}"
                    )));
                }
                let s = s.scaled(1.0 / y);
                let rgb = rgb_of(&s)?;
                Some((s.values().iter().map(|&v| v as f32).collect(), rgb))
            }
            None => None,
        };
        let m = space.to_xyz_matrix();
        Ok(Engine {
            grid,
            upsampler: Upsampler::new(fit, &space),
            basis,
            basis_y,
            basis_rgb,
            light_rgb: rgb_of(&light)?,
            sun,
            y_row: [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
            to_xyz: m * 100.0,
            white: space.xyz_from_rgb([1.0, 1.0, 1.0]),
        })
    }

    pub fn grid(&self) -> &WavelengthGrid {
        &self.grid
    }

    /// The basis spectra on the output grid (for the compact `basis` output).
    pub fn basis_spectra(&self) -> &[Vec<f32>; 3] {
        &self.basis
    }

    /// The sun's SPD at Y = 1 on the output grid, if any.
    pub fn sun_spectrum(&self) -> Option<&[f32]> {
        self.sun.as_ref().map(|(s, _)| s.as_slice())
    }

    /// The main light's RGB at Y = 1 (what RGB (1,1,1) integrates back to before white balance).
    pub fn light_rgb(&self) -> [f64; 3] {
        self.light_rgb.into()
    }

    /// Luminance of a linear RGB pixel in the fit's space.
    pub fn luminance(&self, rgb: [f32; 3]) -> f64 {
        self.y_row[0] * rgb[0] as f64
            + self.y_row[1] * rgb[1] as f64
            + self.y_row[2] * rgb[2] as f64
    }

    /// The basis coefficients of a pixel, and whether it is a sun pixel: `(c_R, c_G, c_B, s)`,
    /// where the spectrum is `sum c_j B_j + s * SUN` (the compact form the renderer loads).
    pub fn coefficients(&self, rgb: [f32; 3], is_sun: bool) -> [f64; 4] {
        let a = self
            .upsampler
            .coefficients([rgb[0] as f64, rgb[1] as f64, rgb[2] as f64]);
        if is_sun && self.sun.is_some() {
            let y: f64 = (0..3).map(|j| a[j] * self.basis_y[j]).sum();
            [0.0, 0.0, 0.0, y.max(0.0)]
        } else {
            [a[0], a[1], a[2], 0.0]
        }
    }

    /// Writes the pixel's spectral radiance into `out` (one value per output wavelength) and
    /// returns its RGB back and luminance.
    pub fn spectrum(&self, rgb: [f32; 3], is_sun: bool, out: &mut [f32]) -> PixelResult {
        let c = self.coefficients(rgb, is_sun);
        let back = match (&self.sun, c[3] > 0.0) {
            (Some((sun, sun_rgb)), true) => {
                let s = c[3] as f32;
                for (o, v) in out.iter_mut().zip(sun) {
                    *o = s * v;
                }
                sun_rgb * c[3]
            }
            _ => {
                let (a0, a1, a2) = (c[0] as f32, c[1] as f32, c[2] as f32);
                for (i, o) in out.iter_mut().enumerate() {
                    *o = a0 * self.basis[0][i] + a1 * self.basis[1][i] + a2 * self.basis[2][i];
                }
                self.basis_rgb * Vector3::new(c[0], c[1], c[2])
            }
        };
        let luminance = if c[3] > 0.0 {
            c[3]
        } else {
            (0..3).map(|j| c[j] * self.basis_y[j]).sum()
        };
        PixelResult {
            rgb_back: back.component_div(&self.light_rgb).into(),
            luminance,
        }
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
        let xyz = |v: [f64; 3]| Xyz((self.to_xyz * nalgebra::Vector3::from(v)).into());
        delta_e_2000(
            Lab::from_xyz(xyz(input), self.white),
            Lab::from_xyz(xyz(out), self.white),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::{Observer, RgbSpace};
    use crate::data;
    use crate::fit::{fit, FitInput, Mode, PAPER_BASIS};

    fn engine(light: &str, mode: Mode, grid: &str, sun: bool) -> Engine {
        let grid: WavelengthGrid = grid.parse().unwrap();
        let input = FitInput::from_names(
            light,
            PAPER_BASIS,
            &grid,
            Observer::Cie1931,
            Rule::Riemann,
            RgbSpace::SRGB,
        )
        .unwrap();
        let f = fit(&input, mode).unwrap();
        let d65 = data::spectrum("D65").unwrap().data;
        Engine::new(&f, grid, Rule::Riemann, sun.then_some(&d65)).unwrap()
    }

    #[test]
    fn white_under_d65_is_d65_at_unit_luminance() {
        let e = engine("D65", Mode::Exact, "380:780:5", false);
        let mut out = vec![0.0f32; e.grid().len()];
        let r = e.spectrum([1.0, 1.0, 1.0], false, &mut out);
        assert!((r.luminance - 1.0).abs() < 1e-9, "{}", r.luminance);
        // White's spectrum is sum_j w_j MCC_j D65: its colour, not its shape, is D65's, so it
        // integrates back to white and stays positive.
        assert!(
            r.rgb_back.iter().all(|v| (v - 1.0).abs() < 1e-6),
            "{:?}",
            r.rgb_back
        );
        assert!(out.iter().all(|&v| v > 0.0));
        // Its luminance by direct integration of the written values.
        let grid = e.grid();
        let cmfs = Cmfs::new(Observer::Cie1931, grid).unwrap();
        let y: f64 = out
            .iter()
            .zip(cmfs.y.values())
            .map(|(o, y)| *o as f64 * y)
            .sum::<f64>()
            / cmfs.y.values().iter().sum::<f64>();
        assert!((y - 1.0).abs() < 1e-6, "{y}");
    }

    #[test]
    fn exact_mode_round_trips_on_the_output_grid() {
        for light in ["D65", "A", "FL2"] {
            let e = engine(light, Mode::Exact, "380:780:10", false);
            let mut out = vec![0.0f32; e.grid().len()];
            for rgb in [
                [0.2f32, 0.5, 0.9],
                [3.0, 1.0, 0.1],
                [1e4, 2e4, 5e3],
                [1e-6, 2e-6, 1e-6],
            ] {
                let r = e.spectrum(rgb, false, &mut out);
                let de = e.round_trip_error(rgb, r.rgb_back);
                // f32 spectra: the error is rounding only.
                assert!(de < 1e-3, "{light} {rgb:?}: {de}");
            }
        }
    }

    #[test]
    fn sun_pixels_get_the_sun_spd_at_their_luminance() {
        let e = engine("A", Mode::Exact, "380:780:5", true);
        let mut plain = vec![0.0f32; e.grid().len()];
        let mut sunny = vec![0.0f32; e.grid().len()];
        let rgb = [500.0, 400.0, 300.0];
        let a = e.spectrum(rgb, false, &mut plain);
        let b = e.spectrum(rgb, true, &mut sunny);
        assert!((a.luminance - b.luminance).abs() < 1e-9 * a.luminance);
        let sun = e.sun_spectrum().unwrap();
        for (s, v) in sunny.iter().zip(sun) {
            assert!((s / v - b.luminance as f32).abs() < 1e-3 * b.luminance as f32);
        }
        assert_eq!(e.coefficients(rgb, true)[..3], [0.0, 0.0, 0.0]);
    }
}
