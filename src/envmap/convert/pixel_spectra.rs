//! The per-pixel engine of the conversion: linear RGB -> spectral radiance on the output grid,
//! and the spectrum's RGB back.
//!
//! Radiometric scale (the convention of pbrt-v4 and Mitsuba 3): luminance is
//! `Y = sum(L ybar) / sum(ybar)`, and one global factor makes the main light's SPD have Y = 1.
//!
//! The white premise ([`WhitePremise`]) says what RGB (1,1,1) means: the main light (the paper's
//! premise: the map is white-balanced to it) or the RGB space's own white (D65 for sRGB, ACES
//! white for ACEScg, the declared white of a file's chromaticities: the map is referenced to it,
//! as a renderer or a camera in a fixed white balance writes it). Internally every pixel is first
//! made referenced to the space's white ("true" RGB, `r`): `r = diag(RGB_light) rgb` under the
//! light premise. No chromatic adaptation is applied: a pixel's spectrum has the XYZ the space's
//! RGB -> XYZ matrix gives its true RGB.
//!
//! Three ways to make a spectrum of `r`, all linear and exact in RGB (one 3x3 solve each):
//! - the ColorChecker basis of the paper, `sum a_j MCC_j * light` ([`crate::fit`]'s modes);
//! - the CIE daylight basis `a_0 S0 + a_1 S1 + a_2 S2`, for sky pixels whose chromaticity lies on
//!   the daylight locus (the family real skylight belongs to);
//! - the main light times a smooth modulation, `light * (a_0 + a_1 x + a_2 x^2)` with
//!   `x = (lambda - 580 nm) / 200 nm`: a pixel of the light's own colour is the light exactly,
//!   and what a lamp lights gets the lamp's lines, gently reweighted. Where that goes negative,
//!   the ColorChecker basis is used if it does not.
//!
//! Sun pixels get the sun's SPD at the luminance their own conversion would have had.

use crate::colorimetry::{Cmfs, Observer, RgbSpace, Xyz};
use crate::envmap::convert::band_reduce::{self, NEGATIVE_TOLERANCE};
use crate::envmap::roundtrip::metric::RgbMetric;
#[cfg(test)]
use crate::envmap::roundtrip::metric::ROUND_TRIP_ZERO;
use crate::error::{Error, Result};
use crate::fit::{Fit, Upsampler, CONDITION_LIMIT};
use crate::illuminant;
use crate::spectrum::{Interpolation, Rule, Spectrum, Tabulated, WavelengthGrid};
use nalgebra::{Matrix3, Vector3};

/// What RGB (1,1,1) is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum WhitePremise {
    /// The main light's SPD (the paper: the map is white-balanced to its main light).
    Light,
    /// The RGB space's own white, unadapted (D65 for sRGB, Rec.2020 and Display P3; ACES white
    /// for ACEScg; a file's declared white): the map is referenced to it whatever lights it, so
    /// a sodium lamp looks orange.
    Space,
}

/// What a pixel is, for choosing its spectrum.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PixelKind {
    /// Below the horizon, or a layout without directions.
    Plain,
    /// Above the horizon: daylight-coloured pixels may take the daylight basis.
    Sky,
    /// Part of the sun.
    Sun,
}

/// The model the engine follows beyond the fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Model {
    /// What RGB (1,1,1) is: the main light or the space's white.
    pub white: WhitePremise,
    /// Daylight-coloured sky pixels as members of the CIE daylight family.
    pub sky_daylight: bool,
    /// Pixels other than sun and daylight sky as the main light times a smooth modulation
    /// (otherwise the ColorChecker basis of the fit).
    pub smooth: bool,
}

impl Model {
    /// The paper's model: one ColorChecker basis, white-balanced to the main light.
    pub const PAPER: Model = Model {
        white: WhitePremise::Light,
        sky_daylight: false,
        smooth: false,
    };
}

/// The SPD of the sun's pixels.
#[derive(Debug, Clone, Copy)]
pub enum SunSource<'a> {
    /// Sun pixels are converted as any other pixel.
    None,
    /// This SPD, at each pixel's luminance.
    Spd(&'a Tabulated),
    /// The member of the CIE daylight family (S0, S1, S2) whose RGB is this input RGB (the sun
    /// region's mean colour), at each pixel's luminance.
    DaylightFit([f64; 3]),
}

/// Whether an XYZ colour is daylight-coloured: its xy within [`SKY_LOCUS_TOLERANCE`] of the
/// daylight locus, between the x of [`SKY_LOCUS_X`].
pub fn daylight_coloured(xyz: &Vector3<f64>) -> bool {
    let sum = xyz.sum();
    if !(xyz[1] > 0.0 && sum > 0.0) {
        return false;
    }
    let (x, y) = (xyz[0] / sum, xyz[1] / sum);
    (SKY_LOCUS_X.0..=SKY_LOCUS_X.1).contains(&x)
        && (y - illuminant::daylight_locus_y(x)).abs() <= SKY_LOCUS_TOLERANCE
}

/// A pixel's sky test: within this distance in CIE 1931 y of the daylight locus...
pub const SKY_LOCUS_TOLERANCE: f64 = 0.02;
/// ...and between these x (25000 K and, extended below CIE's 4000 K, about 3000 K).
pub const SKY_LOCUS_X: (f64, f64) = (0.2000, 0.4400);
/// The smooth modulation's variable: x = (lambda - centre) / half width.
pub(crate) const SMOOTH_CENTRE_NM: f64 = 580.0;
pub(crate) const SMOOTH_HALF_WIDTH_NM: f64 = 200.0;

/// A main light is daylight when its least-squares fit by S0, S1, S2 leaves at most this relative
/// RMS residual (CIE D illuminants: ~0; FL2: 0.4; A: 0.1; see the tests).
pub const DAYLIGHT_RESIDUAL: f64 = 0.03;

/// The relative RMS residual of `light`'s least-squares fit by the daylight basis.
pub(crate) fn daylight_residual(light: &Spectrum, d: &Basis3) -> f64 {
    let l = light.values();
    let b = |j: usize, i: usize| d.spectra[j][i] as f64;
    let g = Matrix3::from_fn(|p, q| (0..l.len()).map(|i| b(p, i) * b(q, i)).sum::<f64>());
    let rhs = Vector3::from_fn(|p, _| (0..l.len()).map(|i| b(p, i) * l[i]).sum::<f64>());
    let Some(c) = g.try_inverse().map(|gi| gi * rhs) else {
        return f64::INFINITY;
    };
    let (mut res, mut norm) = (0.0, 0.0);
    for (i, &v) in l.iter().enumerate() {
        let fit: f64 = (0..3).map(|j| c[j] * b(j, i)).sum();
        res += (fit - v).powi(2);
        norm += v * v;
    }
    (res / norm).sqrt()
}

/// Writes `sum a_j B_j` into `out` and returns whether it is negative somewhere.
pub(crate) fn write_combination(
    spectra: &[Vec<f32>; 3],
    a: &Vector3<f64>,
    out: &mut [f32],
) -> bool {
    let (a0, a1, a2) = (a[0] as f32, a[1] as f32, a[2] as f32);
    // Zipped slices (no bounds checks) and a separate min/max pass: both vectorise.
    for (((o, &b0), &b1), &b2) in out
        .iter_mut()
        .zip(&spectra[0])
        .zip(&spectra[1])
        .zip(&spectra[2])
    {
        *o = a0 * b0 + a1 * b1 + a2 * b2;
    }
    is_negative(out)
}

/// Whether a written spectrum goes below zero (beyond rounding).
pub(crate) fn is_negative(out: &[f32]) -> bool {
    band_reduce::is_negative(band_reduce::min_max(out))
}

/// The smallest value of `sum a_j B_j` relative to its peak (negative: how negative).
pub(crate) fn relative_min(spectra: &[Vec<f32>; 3], a: &Vector3<f64>) -> f64 {
    let (mut lo, mut hi) = (0f64, 0f64);
    for ((&b0, &b1), &b2) in spectra[0].iter().zip(&spectra[1]).zip(&spectra[2]) {
        let v = a[0] * b0 as f64 + a[1] * b1 as f64 + a[2] * b2 as f64;
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if hi > 0.0 {
        lo / hi
    } else {
        lo
    }
}

/// Three spectra on the output grid and the 3x3 maps between their coefficients and RGB.
#[derive(Debug, Clone)]
pub(crate) struct Basis3 {
    pub(crate) spectra: [Vec<f32>; 3],
    pub(crate) y: [f64; 3],
    /// Columns: linear RGB of each spectrum.
    pub(crate) rgb: Matrix3<f64>,
    /// rgb^-1: coefficients of a (true) RGB.
    pub(crate) inv: Matrix3<f64>,
}

impl Basis3 {
    pub(crate) fn new(spectra: [Spectrum; 3], y: [f64; 3], rgb: Matrix3<f64>) -> Option<Basis3> {
        let sv = rgb.singular_values();
        let (hi, lo) = (sv.max(), sv.min());
        if !(lo > 0.0 && hi / lo <= CONDITION_LIMIT) {
            return None;
        }
        let inv = rgb.try_inverse()?;
        Some(Basis3 {
            spectra: spectra.map(|s| s.values().iter().map(|&v| v as f32).collect()),
            y,
            rgb,
            inv,
        })
    }

    /// Writes `sum a_j B_j` into `out` and returns whether it is negative somewhere.
    pub(crate) fn write(&self, a: &Vector3<f64>, out: &mut [f32]) -> bool {
        write_combination(&self.spectra, a, out)
    }

    pub(crate) fn luminance(&self, a: &Vector3<f64>) -> f64 {
        (0..3).map(|j| a[j] * self.y[j]).sum()
    }
}

/// Everything needed to turn one pixel into a spectrum.
#[derive(Debug, Clone)]
pub struct Engine {
    grid: WavelengthGrid,
    upsampler: Upsampler,
    model: Model,
    /// B_j = MCC_j * S * k on the output grid, k making Y(S) = 1.
    basis: [Vec<f32>; 3],
    /// Luminance of each basis spectrum.
    basis_y: [f64; 3],
    /// Linear RGB of each basis spectrum (columns).
    basis_rgb: Matrix3<f64>,
    /// The main light's RGB at Y = 1: the white balance the paper's premise implies.
    light_rgb: Vector3<f64>,
    /// The sun's SPD at Y = 1 and its RGB (true, D65-referenced).
    sun: Option<(Vec<f32>, Vector3<f64>)>,
    /// The CIE daylight basis (when sky pixels take it).
    daylight: Option<Basis3>,
    /// The main light times (1, x, x^2) (when the model is smooth and the light can carry it).
    smooth: Option<Basis3>,
    metric: RgbMetric,
}

/// Where each set of spectra sits in [`Engine::spectra_table`]: three ColorChecker x light,
/// three CIE daylight, three smooth x light, the sun.
pub const TABLE_COLORCHECKER: usize = 0;
/// Where the three CIE daylight spectra (S0, S1, S2) start.
pub const TABLE_DAYLIGHT: usize = 3;
/// Where the three smooth-modulation spectra start.
pub const TABLE_SMOOTH: usize = 6;
/// Where the sun's spectrum is.
pub const TABLE_SUN: usize = 9;
/// The number of spectra in [`Engine::spectra_table`].
pub const TABLE_LEN: usize = 10;

/// A pixel's spectrum as a combination of the engine's spectra:
/// `sum_j weights[j] * table[first + j]` for j below `count` (f32 products summed in j order,
/// exactly as the spectrum written by [`Engine::spectrum`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Combination {
    /// Index of the first spectrum in the table.
    pub first: usize,
    /// How many spectra (from `first`) the pixel combines.
    pub count: usize,
    /// The weights of those spectra.
    pub weights: [f32; 3],
}

impl Combination {
    fn of(first: usize, a: &Vector3<f64>) -> Combination {
        Combination {
            first,
            count: 3,
            weights: [a[0] as f32, a[1] as f32, a[2] as f32],
        }
    }
}

/// A pixel's spectrum decided before it is computed ([`Engine::decide`]).
#[derive(Debug, Clone, Copy)]
enum Chosen {
    /// The sun's SPD times `scale` (in f32, as written), of luminance `luminance`.
    Sun { scale: f32, luminance: f64 },
    /// The CIE daylight basis with these coefficients.
    Daylight(Vector3<f64>),
    /// The ColorChecker basis with these coefficients.
    Colorchecker(Vector3<f64>),
}

impl Chosen {
    /// The spectrum as a combination of [`Engine::spectra_table`].
    fn combination(&self) -> Combination {
        match self {
            Chosen::Sun { scale, .. } => Combination {
                first: TABLE_SUN,
                count: 1,
                weights: [*scale, 0.0, 0.0],
            },
            Chosen::Daylight(a) => Combination::of(TABLE_DAYLIGHT, a),
            Chosen::Colorchecker(a) => Combination::of(TABLE_COLORCHECKER, a),
        }
    }
}

/// What one pixel became.
#[derive(Debug, Clone, Copy)]
pub struct PixelResult {
    /// Linear RGB of the written spectrum, under the white premise (compare with the input).
    pub rgb_back: [f64; 3],
    /// The spectrum's luminance.
    pub luminance: f64,
    /// The written spectrum goes below zero somewhere.
    pub negative: bool,
    /// Which spectrum the pixel got.
    pub took: Took,
    /// The written spectrum as a combination of [`Engine::spectra_table`].
    pub combination: Combination,
}

/// Which spectrum a pixel got.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Took {
    /// The sun's SPD.
    Sun,
    /// A member of the CIE daylight family.
    Daylight,
    /// The main light times a smooth modulation.
    Smooth,
    /// The main light times the ColorChecker basis (the paper's).
    Colorchecker,
    /// The carrier times a non-negative Bernstein combination, exact in RGB.
    Nonneg,
    /// The nearest non-negative spectrum: the colour is not one the carrier can light.
    Nearest,
    /// A clipped lamp pixel: the lamp's SPD at the pixel's luminance.
    Fixed,
}

/// Integrates spectra on the output grid to luminance and (true, D65-referenced) RGB.
#[derive(Debug, Clone)]
pub struct Colorimeter {
    cmfs: Cmfs,
    y_norm: f64,
    rule: Rule,
    space: RgbSpace,
    grid: WavelengthGrid,
}

impl Colorimeter {
    /// Integrates on `grid` with `observer`'s colour-matching functions and `rule`, in `space`.
    pub fn new(
        grid: WavelengthGrid,
        observer: Observer,
        rule: Rule,
        space: RgbSpace,
    ) -> Result<Self> {
        let cmfs = Cmfs::new(observer, &grid)?;
        let y_norm = cmfs.y.integrate(rule);
        Ok(Colorimeter {
            cmfs,
            y_norm,
            rule,
            space,
            grid,
        })
    }

    /// The grid spectra are sampled on.
    pub fn grid(&self) -> &WavelengthGrid {
        &self.grid
    }

    /// The RGB space colours are given in.
    pub fn space(&self) -> &RgbSpace {
        &self.space
    }

    /// Luminance of `s` (specmap's scale: `Y = sum(L ybar) / sum(ybar)`).
    pub fn luminance(&self, s: &Spectrum) -> Result<f64> {
        Ok(s.try_mul(&self.cmfs.y)?.integrate(self.rule) / self.y_norm)
    }

    /// Linear RGB of `s` in the space, Y = 1 for a spectrum of luminance 1.
    pub fn rgb(&self, s: &Spectrum) -> Result<Vector3<f64>> {
        let [x, y, z] = self.cmfs.integrate(s, self.rule)?;
        let n = self.y_norm;
        let xyz = Xyz::new(100.0 * x / n, 100.0 * y / n, 100.0 * z / n);
        Ok(Vector3::from(self.space.rgb_from_xyz(xyz)))
    }

    /// The CIE daylight components S0, S1, S2, scaled to Y ~ 1 each (S1 and S2 have little
    /// luminance: their own scale would do).
    pub(crate) fn daylight_basis(&self) -> Result<Option<Basis3>> {
        let [s0, s1, s2] = illuminant::daylight_components()?
            .map(|t| t.resample(&self.grid, Interpolation::LIGHT));
        let k = 1.0 / self.luminance(&s0)?;
        self.basis3([s0.scaled(k), s1.scaled(k), s2.scaled(k)])
    }

    /// Three spectra as a basis (None when they cannot carry every colour).
    pub(crate) fn basis3(&self, spectra: [Spectrum; 3]) -> Result<Option<Basis3>> {
        let mut y = [0.0; 3];
        let mut rgb = Matrix3::zeros();
        for j in 0..3 {
            y[j] = self.luminance(&spectra[j])?;
            rgb.set_column(j, &self.rgb(&spectra[j])?);
        }
        Ok(Basis3::new(spectra, y, rgb))
    }

    /// A light's table on the grid at luminance 1, or an error naming it when it has none.
    pub fn light(&self, name: &str, t: &Tabulated) -> Result<Spectrum> {
        let s = t.resample(&self.grid, Interpolation::LIGHT);
        let y = self.luminance(&s)?;
        if !(y.is_finite() && y > 0.0) {
            return Err(Error::invalid(format!(
                "the light {name} has no visible energy on the output grid {}",
                self.grid
            )));
        }
        Ok(s.scaled(1.0 / y))
    }
}

/// The fit's spectra put on the output grid and measured there: what the engine's stages share.
struct Measure {
    c: Colorimeter,
    fit_grid: WavelengthGrid,
}

/// The light's three basis spectra (f32), their luminances, and their RGB as columns.
type LightBasis = ([Vec<f32>; 3], [f64; 3], Matrix3<f64>);

/// The sun's spectrum (f32, at Y = 1) and its RGB.
type SunSpectrum = (Vec<f32>, Vector3<f64>);

impl Measure {
    fn new(fit: &Fit, grid: WavelengthGrid, rule: Rule, space: RgbSpace) -> Result<Measure> {
        Ok(Measure {
            c: Colorimeter::new(grid, fit.observer, rule, space)?,
            fit_grid: fit.grid,
        })
    }

    /// Values on the fit's grid, resampled to the output grid.
    fn on_grid(&self, values: &[f64], interp: Interpolation) -> Result<Spectrum> {
        let w: Vec<f64> = self.fit_grid.wavelengths_nm().collect();
        Ok(Tabulated::new(w, values.to_vec())?.resample(self.c.grid(), interp))
    }

    /// The fit's main light on the output grid, at Y = 1.
    fn light(&self, fit: &Fit) -> Result<Spectrum> {
        let light = self.on_grid(&fit.light_spd, Interpolation::LIGHT)?;
        let light_y = self.c.luminance(&light)?;
        if !light_y.is_finite() || light_y <= 0.0 {
            return Err(Error::invalid(format!(
                "the main light {} has no visible energy on the output grid {}",
                fit.light,
                self.c.grid()
            )));
        }
        Ok(light.scaled(1.0 / light_y))
    }

    /// The fit's three basis reflectances times the light: spectra, luminances and RGB.
    fn light_basis(&self, fit: &Fit, light: &Spectrum) -> Result<LightBasis> {
        let mut basis: [Vec<f32>; 3] = Default::default();
        let mut basis_y = [0.0; 3];
        let mut basis_rgb = Matrix3::zeros();
        for j in 0..3 {
            let b = self
                .on_grid(&fit.basis_reflectance[j], Interpolation::SMOOTH)?
                .try_mul(light)?;
            basis_y[j] = self.c.luminance(&b)?;
            basis_rgb.set_column(j, &self.c.rgb(&b)?);
            basis[j] = b.values().iter().map(|&v| v as f32).collect();
        }
        Ok((basis, basis_y, basis_rgb))
    }

    /// The light times 1, x and x^2 of the wavelength's offset from the smooth model's centre.
    fn smooth_basis(&self, light: &Spectrum) -> Result<Option<Basis3>> {
        let grid = *self.c.grid();
        let x = |i: usize| (grid.wavelength_nm(i) - SMOOTH_CENTRE_NM) / SMOOTH_HALF_WIDTH_NM;
        let with = |p: i32| -> Result<Spectrum> {
            let v = (0..grid.len())
                .map(|i| light.values()[i] * x(i).powi(p))
                .collect();
            Spectrum::new(grid, v)
        };
        self.c.basis3([with(0)?, with(1)?, with(2)?])
    }

    /// A sun given its SPD: on the output grid at Y = 1.
    fn sun_of_spd(&self, t: &Tabulated) -> Result<SunSpectrum> {
        let s = t.resample(self.c.grid(), Interpolation::LIGHT);
        let y = self.c.luminance(&s)?;
        if !y.is_finite() || y <= 0.0 {
            return Err(Error::invalid(format!(
                "the sun's SPD has no visible energy on {}",
                self.c.grid()
            )));
        }
        let s = s.scaled(1.0 / y);
        let rgb = self.c.rgb(&s)?;
        Ok((s.values().iter().map(|&v| v as f32).collect(), rgb))
    }
}

/// A sun given its colour (`rgb` as the input has it, `r` under the premise): the member of
/// the daylight family that has it, at Y = 1.
fn sun_of_colour(
    daylight: Option<&Basis3>,
    rgb: [f64; 3],
    r: Vector3<f64>,
    grid: WavelengthGrid,
) -> Result<SunSpectrum> {
    let d = daylight
        .ok_or_else(|| Error::invalid("the CIE daylight basis is singular on the output grid"))?;
    let a = d.inv * r;
    let y = d.luminance(&a);
    if !y.is_finite() || y <= 0.0 {
        return Err(Error::invalid(format!(
            "the sun's mean colour {rgb:?} has no luminance: no daylight matches it"
        )));
    }
    let a = a / y;
    let mut s = vec![0f32; grid.len()];
    d.write(&a, &mut s);
    Ok((s, d.rgb * a))
}

impl Engine {
    /// The paper's model (ColorChecker basis, light premise). `fit` gives the mode, basis
    /// reflectances and main light (on its own grid); `grid` is the output grid; `sun_spd` the
    /// sun's SPD if sun pixels are to be replaced.
    pub fn new(
        fit: &Fit,
        grid: WavelengthGrid,
        rule: Rule,
        sun_spd: Option<&Tabulated>,
    ) -> Result<Engine> {
        let sun = sun_spd.map_or(SunSource::None, SunSource::Spd);
        Engine::with_model(fit, grid, rule, sun, Model::PAPER)
    }

    /// An engine following `model`: the fit's light at Y = 1 and its three basis spectra on
    /// `grid`, the daylight and smooth bases the model asks for, and the sun's spectrum.
    pub fn with_model(
        fit: &Fit,
        grid: WavelengthGrid,
        rule: Rule,
        sun_source: SunSource,
        model: Model,
    ) -> Result<Engine> {
        let space = fit.rgb_space();
        let m = Measure::new(fit, grid, rule, space)?;
        let light = m.light(fit)?;
        let light_rgb = m.c.rgb(&light)?;
        let (basis, basis_y, basis_rgb) = m.light_basis(fit, &light)?;
        let need_daylight = model.sky_daylight || matches!(sun_source, SunSource::DaylightFit(_));
        let daylight = if need_daylight {
            m.c.daylight_basis()?
        } else {
            None
        };
        let smooth = if model.smooth {
            m.smooth_basis(&light)?
        } else {
            None
        };
        // Daylight sky only under a daylight main light: a lamp whose white happens to lie on the
        // daylight locus (FL2, 4200 K) lights walls of daylight colour that are not daylight.
        let is_daylight = match &daylight {
            Some(d) => daylight_residual(&light, d) <= DAYLIGHT_RESIDUAL,
            None => false,
        };
        let premise = |rgb: [f64; 3]| -> Vector3<f64> {
            match model.white {
                WhitePremise::Light => Vector3::from(rgb).component_mul(&light_rgb),
                WhitePremise::Space => Vector3::from(rgb),
            }
        };
        let sun = match sun_source {
            SunSource::None => None,
            SunSource::Spd(t) => Some(m.sun_of_spd(t)?),
            SunSource::DaylightFit(rgb) => {
                Some(sun_of_colour(daylight.as_ref(), rgb, premise(rgb), grid)?)
            }
        };
        Ok(Engine {
            grid,
            upsampler: Upsampler::new(fit, &space),
            model,
            basis,
            basis_y,
            basis_rgb,
            light_rgb,
            sun,
            daylight: if model.sky_daylight && is_daylight {
                daylight
            } else {
                None
            },
            smooth,
            metric: RgbMetric::new(&space),
        })
    }

    /// The output grid.
    pub fn grid(&self) -> &WavelengthGrid {
        &self.grid
    }

    /// How pixels are measured (luminance, round trip).
    pub fn metric(&self) -> &RgbMetric {
        &self.metric
    }

    /// The model the engine follows.
    pub fn model(&self) -> Model {
        self.model
    }

    /// Whether daylight-coloured sky pixels take the daylight basis (the model asks for it and
    /// the main light is daylight).
    pub fn sky_daylight_active(&self) -> bool {
        self.daylight.is_some()
    }

    /// Whether the smooth modulation is in use (the model asks for it and the light can carry
    /// every colour with it: not a near-monochromatic lamp).
    pub fn smooth_active(&self) -> bool {
        self.smooth.is_some()
    }

    /// The basis spectra on the output grid (for the compact `basis` output).
    pub fn basis_spectra(&self) -> &[Vec<f32>; 3] {
        &self.basis
    }

    /// Every spectrum a pixel's [`Combination`] refers to, at the `TABLE_*` positions (a set
    /// the engine does not use is zeros there).
    pub fn spectra_table(&self) -> Vec<Vec<f32>> {
        let zeros = || vec![0f32; self.grid.len()];
        let three = |b: &Option<Basis3>| match b {
            Some(b) => b.spectra.to_vec(),
            None => vec![zeros(), zeros(), zeros()],
        };
        let mut table = self.basis.to_vec();
        table.extend(three(&self.daylight));
        table.extend(three(&self.smooth));
        table.push(self.sun.as_ref().map_or_else(zeros, |(s, _)| s.clone()));
        table
    }

    /// Which spectra of [`Engine::spectra_table`] a pixel's [`Combination`] can use (bit k:
    /// spectrum k): the ColorChecker basis, and the daylight, smooth and sun spectra where the
    /// engine has them.
    pub fn live_spectra(&self) -> u64 {
        let set = |on: bool, first: usize, count: usize| -> u64 {
            if on {
                ((1u64 << count) - 1) << first
            } else {
                0
            }
        };
        set(true, TABLE_COLORCHECKER, 3)
            | set(self.daylight.is_some(), TABLE_DAYLIGHT, 3)
            | set(self.smooth.is_some(), TABLE_SMOOTH, 3)
            | set(self.sun.is_some(), TABLE_SUN, 1)
    }

    /// The sun's SPD at Y = 1 on the output grid, if any.
    pub fn sun_spectrum(&self) -> Option<&[f32]> {
        self.sun.as_ref().map(|(s, _)| s.as_slice())
    }

    /// The main light's RGB at Y = 1 (what RGB (1,1,1) integrates back to before white balance).
    pub fn light_rgb(&self) -> [f64; 3] {
        self.light_rgb.into()
    }

    /// The RGB that the round trip divides by: the main light's under the light premise, white
    /// under the D65 premise (the `specmap.lightRGB` attribute `roundtrip` reads).
    pub fn white_balance(&self) -> [f64; 3] {
        match self.model.white {
            WhitePremise::Light => self.light_rgb.into(),
            WhitePremise::Space => [1.0; 3],
        }
    }

    /// Luminance of a linear RGB pixel in the fit's space.
    pub fn luminance(&self, rgb: [f32; 3]) -> f64 {
        self.metric.luminance(rgb)
    }

    /// The ColorChecker-basis coefficients of a pixel under the white premise.
    fn colorchecker(&self, rgb: [f32; 3]) -> [f64; 3] {
        self.upsampler.coefficients(self.balanced(rgb))
    }

    /// A pixel balanced to the main light, as the fit takes it.
    fn balanced(&self, rgb: [f32; 3]) -> [f64; 3] {
        let rgb = [rgb[0] as f64, rgb[1] as f64, rgb[2] as f64];
        match self.model.white {
            WhitePremise::Light => rgb,
            WhitePremise::Space => [
                rgb[0] / self.light_rgb[0],
                rgb[1] / self.light_rgb[1],
                rgb[2] / self.light_rgb[2],
            ],
        }
    }

    /// The pixel's true (D65-referenced) RGB.
    fn true_rgb(&self, rgb: [f32; 3]) -> Vector3<f64> {
        let v = Vector3::new(rgb[0] as f64, rgb[1] as f64, rgb[2] as f64);
        match self.model.white {
            WhitePremise::Light => v.component_mul(&self.light_rgb),
            WhitePremise::Space => v,
        }
    }

    /// Whether a true RGB is daylight-coloured: its xy within [`SKY_LOCUS_TOLERANCE`] of the
    /// daylight locus, between the x of [`SKY_LOCUS_X`].
    pub fn is_daylight_coloured(&self, r: &Vector3<f64>) -> bool {
        daylight_coloured(&self.metric.xyz(r))
    }

    /// The basis coefficients of a pixel, and whether it is a sun pixel: `(c_R, c_G, c_B, s)`,
    /// where the spectrum is `sum c_j B_j + s * SUN` (the compact form the renderer loads), on
    /// the ColorChecker basis whatever the model (the `basis` format's content).
    pub fn coefficients(&self, rgb: [f32; 3], is_sun: bool) -> [f64; 4] {
        let a = self.colorchecker(rgb);
        if is_sun && self.sun.is_some() {
            let y: f64 = (0..3).map(|j| a[j] * self.basis_y[j]).sum();
            [0.0, 0.0, 0.0, y.max(0.0)]
        } else {
            [a[0], a[1], a[2], 0.0]
        }
    }

    /// Writes the pixel's spectral radiance into `out` (one value per output wavelength) and
    /// returns its RGB back and luminance.
    pub fn spectrum(&self, rgb: [f32; 3], kind: PixelKind, out: &mut [f32]) -> PixelResult {
        match self.decide(rgb, kind) {
            Some(chosen) => self.write_chosen(chosen, out),
            None => self.smooth_or_colorchecker(rgb, out),
        }
    }

    /// What [`Engine::spectrum`] returns for a pixel, and the range of the values it would
    /// write (its lowest and highest, with 0), without writing them. None where the smooth
    /// model is in use, which chooses by looking at the spectrum.
    pub(crate) fn spectrum_range(
        &self,
        rgb: [f32; 3],
        kind: PixelKind,
    ) -> Option<(PixelResult, (f32, f32))> {
        self.decide(rgb, kind).map(|c| self.range_chosen(c))
    }

    /// Whether a pixel's kind can change its spectrum: the engine has a sun's SPD or a daylight
    /// sky (else every pixel is taken as plain).
    pub fn looks_at_kind(&self) -> bool {
        self.sun.is_some() || self.daylight.is_some()
    }

    /// The pixel's spectrum as a combination of [`Engine::spectra_table`], without computing
    /// it: what [`Engine::spectrum`] returns as `combination`. None where the smooth model is in
    /// use, which chooses by looking at the spectrum.
    pub fn combination(&self, rgb: [f32; 3], kind: PixelKind) -> Option<Combination> {
        self.decide(rgb, kind).map(|c| c.combination())
    }

    /// The spectrum a pixel takes where no choice needs the spectrum itself: the sun's SPD for
    /// a sun pixel, daylight for a daylight-coloured sky pixel, else the ColorChecker basis
    /// unless the smooth model is in use (None: it chooses).
    fn decide(&self, rgb: [f32; 3], kind: PixelKind) -> Option<Chosen> {
        if kind == PixelKind::Sun && self.sun.is_some() {
            let c = self.coefficients(rgb, true);
            if c[3] > 0.0 {
                return Some(Chosen::Sun {
                    scale: c[3] as f32,
                    luminance: c[3],
                });
            }
        }
        let r = self.true_rgb(rgb);
        if kind != PixelKind::Plain {
            if let Some(d) = &self.daylight {
                if self.is_daylight_coloured(&r) {
                    return Some(Chosen::Daylight(d.inv * r));
                }
            }
        }
        match self.smooth {
            Some(_) => None,
            None => Some(Chosen::Colorchecker(Vector3::from(self.colorchecker(rgb)))),
        }
    }

    /// The RGB of a spectrum back under the white premise (compare with the input).
    fn premise_back(&self, back: Vector3<f64>) -> [f64; 3] {
        match self.model.white {
            WhitePremise::Light => back.component_div(&self.light_rgb).into(),
            WhitePremise::Space => back.into(),
        }
    }

    /// Writes a decided spectrum into `out`.
    fn write_chosen(&self, chosen: Chosen, out: &mut [f32]) -> PixelResult {
        let negative = match chosen {
            Chosen::Sun { scale, .. } => {
                for (o, v) in out.iter_mut().zip(self.chosen_spectra(chosen)[0].iter()) {
                    *o = scale * v;
                }
                self.sun_is_negative()
            }
            Chosen::Daylight(a) => {
                let d = self.daylight.as_ref().expect("decided only with daylight");
                d.write(&a, out)
            }
            Chosen::Colorchecker(a) => write_combination(&self.basis, &a, out),
        };
        self.chosen_result(chosen, negative)
    }

    /// A decided spectrum's result and the range of its values (see
    /// [`band_reduce::combination_range`]), without writing it: the same values as
    /// [`Engine::write_chosen`] writes, each computed as it computes them.
    fn range_chosen(&self, chosen: Chosen) -> (PixelResult, (f32, f32)) {
        let c = chosen.combination();
        let range = band_reduce::combination_range(self.chosen_spectra(chosen), &c.weights);
        let negative = match chosen {
            Chosen::Sun { .. } => self.sun_is_negative(),
            _ => band_reduce::is_negative(range),
        };
        (self.chosen_result(chosen, negative), range)
    }

    /// The spectra a decided pixel combines.
    fn chosen_spectra(&self, chosen: Chosen) -> &[Vec<f32>] {
        match chosen {
            Chosen::Sun { .. } => {
                let (sun, _) = self.sun.as_ref().expect("decided only with a sun");
                std::slice::from_ref(sun)
            }
            Chosen::Daylight(_) => {
                let d = self.daylight.as_ref().expect("decided only with daylight");
                &d.spectra
            }
            Chosen::Colorchecker(_) => &self.basis,
        }
    }

    /// Whether the sun's SPD goes below zero anywhere (a sun pixel's spectrum is a positive
    /// multiple of it).
    fn sun_is_negative(&self) -> bool {
        self.sun
            .as_ref()
            .is_some_and(|(sun, _)| sun.iter().any(|&v| v < 0.0))
    }

    /// What a decided pixel became, `negative` or not.
    fn chosen_result(&self, chosen: Chosen, negative: bool) -> PixelResult {
        let (rgb, luminance, took) = match chosen {
            Chosen::Sun { luminance, .. } => {
                let (_, sun_rgb) = self.sun.as_ref().expect("decided only with a sun");
                (sun_rgb * luminance, luminance, Took::Sun)
            }
            Chosen::Daylight(a) => {
                let d = self.daylight.as_ref().expect("decided only with daylight");
                (d.rgb * a, d.luminance(&a), Took::Daylight)
            }
            Chosen::Colorchecker(mcc) => (
                self.basis_rgb * mcc,
                (0..3).map(|j| mcc[j] * self.basis_y[j]).sum(),
                Took::Colorchecker,
            ),
        };
        PixelResult {
            rgb_back: self.premise_back(rgb),
            luminance,
            negative,
            took,
            combination: chosen.combination(),
        }
    }

    /// The smooth model where it stays non-negative or the ColorChecker basis goes more
    /// negative; else the ColorChecker basis.
    fn smooth_or_colorchecker(&self, rgb: [f32; 3], out: &mut [f32]) -> PixelResult {
        let r = self.true_rgb(rgb);
        let mcc = Vector3::from(self.colorchecker(rgb));
        let s = self.smooth.as_ref().expect("decided unless smooth");
        let a = s.inv * r;
        // The ColorChecker basis only where it stays non-negative and the smooth one does
        // not; otherwise the smooth one, the less negative of the two.
        let negative = s.write(&a, out);
        let use_smooth = !negative || {
            let cc = relative_min(&self.basis, &mcc);
            cc < -NEGATIVE_TOLERANCE && cc <= relative_min(&s.spectra, &a)
        };
        if use_smooth {
            return PixelResult {
                rgb_back: self.premise_back(s.rgb * a),
                luminance: s.luminance(&a),
                negative,
                took: Took::Smooth,
                combination: Combination::of(TABLE_SMOOTH, &a),
            };
        }
        self.colorchecker_result(mcc, out)
    }

    /// The ColorChecker basis with coefficients `mcc`, written into `out`.
    fn colorchecker_result(&self, mcc: Vector3<f64>, out: &mut [f32]) -> PixelResult {
        self.write_chosen(Chosen::Colorchecker(mcc), out)
    }

    /// CIEDE2000 between an input pixel and its round trip (see [`RgbMetric::round_trip_error`]).
    pub fn round_trip_error(&self, rgb: [f32; 3], back: [f64; 3]) -> f64 {
        self.metric.round_trip_error(rgb, back)
    }

    #[cfg(test)]
    fn delta_e(&self, a: [f64; 3], b: [f64; 3]) -> f64 {
        self.metric.delta_e(a, b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::{Observer, RgbSpace};
    use crate::data;
    use crate::fit::{fit, FitInput, Mode, PAPER_BASIS};

    fn fitted(light: &str, mode: Mode, grid: &WavelengthGrid) -> Fit {
        let input = FitInput::from_names(
            light,
            PAPER_BASIS,
            grid,
            Observer::Cie1931,
            Rule::Riemann,
            RgbSpace::SRGB,
        )
        .unwrap();
        fit(&input, mode).unwrap()
    }

    fn engine(light: &str, mode: Mode, grid: &str, sun: bool) -> Engine {
        let grid: WavelengthGrid = grid.parse().unwrap();
        let f = fitted(light, mode, &grid);
        let d65 = data::spectrum("D65").unwrap().data;
        Engine::new(&f, grid, Rule::Riemann, sun.then_some(&d65)).unwrap()
    }

    const FAITHFUL: Model = Model {
        white: WhitePremise::Space,
        sky_daylight: true,
        smooth: true,
    };

    fn faithful(light: &str, model: Model, sun: SunSource) -> Engine {
        let grid: WavelengthGrid = "380:780:5".parse().unwrap();
        let f = fitted(light, Mode::Exact, &grid);
        Engine::with_model(&f, grid, Rule::Riemann, sun, model).unwrap()
    }

    /// Linear sRGB (Y = luminance) of a spectrum on the engine's grid, and the spectrum there.
    fn rgb_and_values(e: &Engine, t: &Tabulated) -> ([f32; 3], Vec<f64>) {
        let s = t.resample(e.grid(), Interpolation::LIGHT);
        let cmfs = Cmfs::new(Observer::Cie1931, e.grid()).unwrap();
        let n = cmfs.y.integrate(Rule::Riemann);
        let [x, y, z] = cmfs.integrate(&s, Rule::Riemann).unwrap();
        let xyz = Xyz::new(100.0 * x / n, 100.0 * y / n, 100.0 * z / n);
        let rgb = RgbSpace::SRGB.rgb_from_xyz(xyz).map(|v| v as f32);
        (rgb, s.values().to_vec())
    }

    /// `a` is `b` up to a scale, to `tol` of its peak.
    fn assert_proportional(a: &[f32], b: &[f64], tol: f64, what: &str) {
        let peak = b.iter().fold(0f64, |m, v| m.max(v.abs()));
        let k = a.iter().map(|&v| v as f64).sum::<f64>() / b.iter().sum::<f64>();
        for (i, (&x, &y)) in a.iter().zip(b).enumerate() {
            assert!(
                (x as f64 - k * y).abs() <= tol * k * peak,
                "{what}: band {i}: {x} vs {}",
                k * y
            );
        }
    }

    #[test]
    fn the_combination_decided_without_the_spectrum_is_the_one_written() {
        // The paper's engine with a sun and daylight sky: every choice is made without the
        // spectrum, so `combination` must name exactly what `spectrum` writes.
        let model = Model {
            white: WhitePremise::Light,
            sky_daylight: true,
            smooth: false,
        };
        let d65 = data::spectrum("D65").unwrap().data;
        let e = faithful("D65", model, SunSource::Spd(&d65));
        let table = e.spectra_table();
        let mut out = vec![0f32; e.grid().len()];
        let mut seen = std::collections::HashSet::new();
        for (i, kind) in [PixelKind::Plain, PixelKind::Sky, PixelKind::Sun]
            .into_iter()
            .enumerate()
        {
            for k in 0..200u32 {
                // Greys, saturated colours, dark and bright values, and negatives.
                let f = |j: u32| ((k * 37 + j * 101 + i as u32 * 7) % 97) as f32 / 48.0 - 0.1;
                let rgb = [f(0) * 3.0, f(1) * 3.0, f(2) * 3.0];
                let r = e.spectrum(rgb, kind, &mut out);
                let c = e.combination(rgb, kind).expect("no smooth model");
                assert_eq!(c, r.combination, "{rgb:?} {kind:?}");
                for j in 0..c.count {
                    assert!(e.live_spectra() & (1 << (c.first + j)) != 0, "{c:?}");
                }
                seen.insert(format!("{:?}", r.took));
                for (b, &v) in out.iter().enumerate() {
                    let w: f32 =
                        (0..c.count).fold(0.0, |s, j| s + c.weights[j] * table[c.first + j][b]);
                    assert_eq!(v, w, "{rgb:?} {kind:?} band {b}");
                }
            }
        }
        assert_eq!(
            seen.len(),
            3,
            "sun, daylight and ColorChecker pixels: {seen:?}"
        );
        // The smooth model chooses by the spectrum: no combination without it.
        let smooth = faithful("D65", FAITHFUL, SunSource::None);
        assert_eq!(smooth.combination([0.2, 0.3, 0.4], PixelKind::Plain), None);
    }

    #[test]
    fn daylight_coloured_sky_pixels_are_the_cie_daylight_of_their_colour() {
        let e = faithful("D65", FAITHFUL, SunSource::None);
        assert!(e.sky_daylight_active());
        let mut out = vec![0f32; e.grid().len()];
        for k in [4500.0, 6504.0, 12000.0, 20000.0] {
            let (rgb, d) = rgb_and_values(&e, &illuminant::daylight(k).unwrap());
            let r = e.spectrum(rgb, PixelKind::Sky, &mut out);
            assert_eq!(r.took, Took::Daylight, "{k} K");
            assert!(!r.negative);
            assert_proportional(&out, &d, 1e-4, &format!("daylight {k} K"));
            assert!(e.round_trip_error(rgb, r.rgb_back) < 1e-3);
            // Below the horizon the same colour is ground lit by daylight: the smooth model.
            let r = e.spectrum(rgb, PixelKind::Plain, &mut out);
            assert_eq!(r.took, Took::Smooth);
        }
        // A saturated sky pixel is not daylight.
        let r = e.spectrum([0.1, 0.8, 0.1], PixelKind::Sky, &mut out);
        assert_ne!(r.took, Took::Daylight);
    }

    #[test]
    fn only_a_daylight_main_light_turns_sky_pixels_into_daylight() {
        // FL2's white lies on the daylight locus, but its walls are not daylight.
        for (light, daylight) in [("D65", true), ("D50", true), ("FL2", false), ("A", false)] {
            let e = faithful(light, FAITHFUL, SunSource::None);
            assert_eq!(e.sky_daylight_active(), daylight, "{light}");
        }
    }

    #[test]
    fn a_pixel_of_the_lights_colour_is_the_light_under_the_smooth_model() {
        for light in ["FL2", "FL11", "hps", "A"] {
            let spd = data::spectrum(light).unwrap().data;
            // D65 premise: the light's own RGB.
            let e = faithful(light, FAITHFUL, SunSource::None);
            assert!(e.smooth_active(), "{light}");
            let (rgb, l) = rgb_and_values(&e, &spd);
            let mut out = vec![0f32; e.grid().len()];
            let r = e.spectrum(rgb, PixelKind::Plain, &mut out);
            assert_eq!(r.took, Took::Smooth);
            assert_proportional(&out, &l, 1e-4, light);
            // Light premise: RGB (1,1,1).
            let e = faithful(
                light,
                Model {
                    white: WhitePremise::Light,
                    ..FAITHFUL
                },
                SunSource::None,
            );
            let r = e.spectrum([2.0; 3], PixelKind::Plain, &mut out);
            assert_proportional(&out, &l, 1e-4, light);
            assert!((r.luminance - 2.0).abs() < 1e-9);
        }
        // Low-pressure sodium is too narrow to carry every colour with a smooth modulation.
        assert!(!faithful("lps", FAITHFUL, SunSource::None).smooth_active());
    }

    /// A grey card lit by a sodium lamp, in a D65-referenced map, is orange: under the D65
    /// premise it is the lamp's SPD; under the light premise the same RGB is taken as balanced
    /// to the lamp, so the lamp's colour is applied twice.
    #[test]
    fn an_orange_lamp_lit_grey_depends_on_the_white_premise() {
        let hps = data::spectrum("hps").unwrap().data;
        let d65 = faithful("hps", FAITHFUL, SunSource::None);
        let (grey, l) = rgb_and_values(&d65, &hps);
        let mut out = vec![0f32; d65.grid().len()];
        let r = d65.spectrum(grey, PixelKind::Plain, &mut out);
        assert_proportional(&out, &l, 1e-4, "d65 premise");
        assert!(d65.round_trip_error(grey, r.rgb_back) < 1e-3);
        let light = faithful(
            "hps",
            Model {
                white: WhitePremise::Light,
                ..FAITHFUL
            },
            SunSource::None,
        );
        let r = light.spectrum(grey, PixelKind::Plain, &mut out);
        // Its round trip still returns the input under its own premise...
        assert!(light.round_trip_error(grey, r.rgb_back) < 1e-3);
        // ...but the spectrum is redder than the lamp: its x is well beyond the lamp's.
        let xy = |rgb: [f64; 3]| RgbSpace::SRGB.xyz_from_rgb(rgb).xy();
        let lamp_xy = xy(grey.map(|v| v as f64));
        let true_rgb: [f64; 3] = light.true_rgb(grey).into();
        assert!(xy(true_rgb)[0] > lamp_xy[0] + 0.05, "{true_rgb:?}");
        assert_eq!(light.white_balance(), light.light_rgb());
        assert_eq!(d65.white_balance(), [1.0; 3]);
    }

    #[test]
    fn the_sun_gets_the_daylight_of_its_own_colour() {
        // A sun on the Planckian locus warmer than CIE daylight's 4000 K: the family still
        // reproduces its colour (a low sun's own colour, above the locus, may take it negative).
        for k in [2700.0, 3500.0, 5000.0, 6504.0] {
            let (rgb, _) = {
                let e = faithful("D65", FAITHFUL, SunSource::None);
                let t = if k < illuminant::DAYLIGHT_RANGE_K.0 {
                    illuminant::planckian(k)
                } else {
                    illuminant::natural(k)
                };
                rgb_and_values(&e, &t.unwrap())
            };
            let mean = rgb.map(|v| v as f64 * 1000.0);
            let e = faithful("D65", FAITHFUL, SunSource::DaylightFit(mean));
            let mut out = vec![0f32; e.grid().len()];
            let px = rgb.map(|v| v * 5000.0);
            let r = e.spectrum(px, PixelKind::Sun, &mut out);
            assert_eq!(r.took, Took::Sun);
            assert!(e.round_trip_error(px, r.rgb_back) < 1e-3, "{k} K");
            assert!(!r.negative, "{k} K");
            assert!((r.luminance / e.luminance(px) - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn white_under_d65_is_d65_at_unit_luminance() {
        let e = engine("D65", Mode::Exact, "380:780:5", false);
        let mut out = vec![0.0f32; e.grid().len()];
        let r = e.spectrum([1.0, 1.0, 1.0], PixelKind::Plain, &mut out);
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
                let r = e.spectrum(rgb, PixelKind::Plain, &mut out);
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
        let a = e.spectrum(rgb, PixelKind::Plain, &mut plain);
        let b = e.spectrum(rgb, PixelKind::Sun, &mut sunny);
        assert!((a.luminance - b.luminance).abs() < 1e-9 * a.luminance);
        let sun = e.sun_spectrum().unwrap();
        for (s, v) in sunny.iter().zip(sun) {
            assert!((s / v - b.luminance as f32).abs() < 1e-3 * b.luminance as f32);
        }
        assert_eq!(e.coefficients(rgb, true)[..3], [0.0, 0.0, 0.0]);
    }

    #[test]
    fn round_trips_within_rounding_count_as_zero_and_are_that_small() {
        // The shortcut in round_trip_error must not hide a real difference: at the threshold,
        // the full CIEDE2000 of saturated, dark, negative and HDR pixels stays negligible.
        let e = engine("D65", Mode::Exact, "380:780:5", false);
        let mut worst = 0f64;
        for rgb in [
            [1.0, 1.0, 1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.02, 0.0, 1.0],
            [-0.1, 0.3, 1.0],
            [1e-6, 2e-6, 1e-7],
            [4e4, 1e3, 10.0],
        ] {
            let y = e.luminance(rgb);
            let input = rgb.map(|v| v as f64 / y);
            let scale = input.iter().fold(1f64, |m, v| m.max(v.abs()));
            for k in 0..3 {
                for sign in [-1.0, 1.0] {
                    let mut out = input;
                    out[k] += sign * ROUND_TRIP_ZERO * scale;
                    worst = worst.max(e.delta_e(input, out));
                    // Half the threshold, to leave room for the rounding of * y / y.
                    let mut half = input;
                    half[k] += sign * 0.5 * ROUND_TRIP_ZERO * scale;
                    assert_eq!(e.round_trip_error(rgb, half.map(|v| v * y)), 0.0);
                }
            }
        }
        assert!(worst < 1e-7, "CIEDE2000 at the threshold: {worst:e}");
        // And a difference just above it is measured.
        let back = [1.0 + 1e-6, 1.0, 1.0];
        assert!(e.round_trip_error([1.0, 1.0, 1.0], back) > 0.0);
    }
}
