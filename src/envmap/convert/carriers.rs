//! The per-pixel engine of the faithful method with many lights: each pixel's spectrum is a
//! carrier (a light's SPD, or a mix of the scene's lights' SPDs) times a modulation, exact in RGB
//! and never negative.
//!
//! Per pixel, in order, the first that applies and stays non-negative:
//! 1. a sun pixel: the sun's SPD at the pixel's luminance;
//! 2. a daylight-coloured pixel of the sky, a window or as bright as them: the CIE daylight
//!    (S0, S1, S2) of its colour;
//! 3. a clipped pixel of a lamp: the lamp's SPD at the pixel's luminance (its clipped colour is
//!    not the lamp's);
//! 4. the carrier times a smooth modulation `a0 + a1 x + a2 x^2`, x = (lambda - 580 nm) / 200 nm
//!    (a pixel of the carrier's colour is the carrier exactly);
//! 5. the carrier times the ColorChecker basis (the paper's reflectances);
//! 6. the carrier times a non-negative combination of Bernstein polynomials over the output range
//!    ([`BERNSTEIN_DEGREES`], smooth bumps), else of single bands: exact whenever the pixel's
//!    colour can be a reflectance under the carrier at all (single bands reach every such
//!    colour), otherwise the nearest such colour (in XYZ), counted and measured. Solved by
//!    non-negative least squares ([`nnls`], Lawson and Hanson 1974).

use crate::data;
use crate::envmap::convert::pixel_spectra::{
    daylight_coloured, Basis3, Colorimeter, Took, WhitePremise, SMOOTH_CENTRE_NM,
    SMOOTH_HALF_WIDTH_NM,
};
use crate::envmap::roundtrip::metric::RgbMetric;
use crate::error::{Error, Result};
use crate::illuminant;
use crate::spectrum::{Interpolation, Spectrum, Tabulated};
use nalgebra::{Matrix3, Vector3};

/// The degrees of the Bernstein polynomials of the non-negative fallback: nine bumps over the
/// range, then 25 narrower ones (single bands come last).
pub(crate) const BERNSTEIN_DEGREES: [usize; 2] = [8, 24];

/// A carrier spectrum with the bases of its modulations.
#[derive(Debug, Clone)]
pub struct Carrier {
    /// The light's name (a table, a lamp family member, or a mix of lights).
    pub name: String,
    spd: Vec<f32>,
    /// RGB of the SPD (Y = 1).
    rgb: Vector3<f64>,
    smooth: Option<Basis3>,
    colorchecker: Option<Basis3>,
    /// The non-negative families tried in turn: Bernstein polynomials of rising degree, then
    /// single bands.
    nonneg: Vec<Family>,
}

/// Generators of non-negative spectra under a carrier: `carrier x g_k`, each with its RGB and
/// XYZ.
#[derive(Debug, Clone)]
struct Family {
    /// The generators' spectra (None: single bands, `carrier` at band k).
    spectra: Option<Vec<Vec<f32>>>,
    carrier: Vec<f32>,
    rgb: Vec<Vector3<f64>>,
    xyz: Vec<Vector3<f64>>,
}

impl Family {
    /// Adds `c` x generator k to `out`.
    fn add(&self, k: usize, c: f64, out: &mut [f32]) {
        match &self.spectra {
            Some(g) => {
                for (o, &v) in out.iter_mut().zip(&g[k]) {
                    *o += c as f32 * v;
                }
            }
            None => out[k] += c as f32 * self.carrier[k],
        }
    }
}

impl Carrier {
    /// A carrier of the SPD `spd` (on the colorimeter's grid, any scale).
    pub fn new(name: &str, spd: &Spectrum, c: &Colorimeter, mcc: &[Spectrum; 3]) -> Result<Self> {
        let y = c.luminance(spd)?;
        if !(y.is_finite() && y > 0.0) {
            return Err(Error::invalid(format!(
                "the light {name} has no visible energy on the output grid {}",
                c.grid()
            )));
        }
        let spd = spd.scaled(1.0 / y);
        let grid = *c.grid();
        let times = |f: &dyn Fn(usize) -> f64| -> Result<Spectrum> {
            Spectrum::new(
                grid,
                (0..grid.len()).map(|i| spd.values()[i] * f(i)).collect(),
            )
        };
        let x = |i: usize| (grid.wavelength_nm(i) - SMOOTH_CENTRE_NM) / SMOOTH_HALF_WIDTH_NM;
        let smooth = c.basis3([
            times(&|_| 1.0)?,
            times(&|i| x(i))?,
            times(&|i| x(i) * x(i))?,
        ])?;
        let colorchecker = c.basis3([
            spd.try_mul(&mcc[0])?,
            spd.try_mul(&mcc[1])?,
            spd.try_mul(&mcc[2])?,
        ])?;
        let spd32: Vec<f32> = spd.values().iter().map(|&v| v as f32).collect();
        let to_xyz = c.space().to_xyz_matrix();
        let n = grid.len();
        let t = |i: usize| i as f64 / (n - 1).max(1) as f64;
        let mut nonneg = Vec::new();
        for degree in BERNSTEIN_DEGREES {
            let mut spectra = Vec::new();
            let mut rgb = Vec::new();
            for k in 0..=degree {
                let b = times(&|i| bernstein_poly(degree, k, t(i)))?;
                rgb.push(c.rgb(&b)?);
                spectra.push(b.values().iter().map(|&v| v as f32).collect());
            }
            nonneg.push(Family {
                spectra: Some(spectra),
                carrier: Vec::new(),
                xyz: rgb.iter().map(|v| to_xyz * v).collect(),
                rgb,
            });
        }
        let bands: Vec<Vector3<f64>> = (0..n)
            .map(|k| c.rgb(&times(&|i| if i == k { 1.0 } else { 0.0 })?))
            .collect::<Result<_>>()?;
        nonneg.push(Family {
            spectra: None,
            carrier: spd32.clone(),
            xyz: bands.iter().map(|v| to_xyz * v).collect(),
            rgb: bands,
        });
        Ok(Carrier {
            name: name.to_string(),
            rgb: c.rgb(&spd)?,
            spd: spd.values().iter().map(|&v| v as f32).collect(),
            smooth,
            colorchecker,
            nonneg,
        })
    }

    /// A mix of carriers (weights summing to 1; each carrier at Y = 1, so the mix is too).
    pub fn mix(parts: &[(&Carrier, f64)], c: &Colorimeter, mcc: &[Spectrum; 3]) -> Result<Carrier> {
        let grid = *c.grid();
        let v = (0..grid.len())
            .map(|i| parts.iter().map(|(p, w)| w * p.spd[i] as f64).sum())
            .collect();
        let name = parts
            .iter()
            .map(|(p, w)| format!("{:.0}% {}", 100.0 * w, p.name))
            .collect::<Vec<_>>()
            .join(" + ");
        Carrier::new(&name, &Spectrum::new(grid, v)?, c, mcc)
    }
}

/// The Bernstein basis polynomial b_{k,n}(t).
fn bernstein_poly(n: usize, k: usize, t: f64) -> f64 {
    let binom = (1..=k).fold(1.0, |acc, j| acc * (n + 1 - j) as f64 / j as f64);
    binom * t.powi(k as i32) * (1.0 - t).powi((n - k) as i32)
}

/// What a pixel is, for its spectrum.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Assign {
    /// Index into the engine's carriers.
    pub carrier: u16,
    /// The pixel is the sun's: it takes the sun's SPD.
    pub sun: bool,
    /// May take the daylight basis if daylight-coloured.
    pub daylight: bool,
    /// A clipped lamp pixel: the carrier at the pixel's luminance.
    pub fixed: bool,
}

/// What one pixel became.
#[derive(Debug, Clone, Copy)]
pub struct Written {
    /// RGB of the written spectrum under the white premise (compare with the input).
    pub rgb_back: [f64; 3],
    /// Which spectrum the pixel got.
    pub took: Took,
    /// The spectrum reproduces the pixel's RGB (to rounding).
    pub exact: bool,
}

/// Everything needed to turn pixels into spectra with many lights.
#[derive(Debug, Clone)]
pub struct CarrierEngine {
    /// The light spectra pixels are carried by, the reflectors' mixes after the lights.
    pub carriers: Vec<Carrier>,
    daylight: Option<Basis3>,
    /// The sun's SPD at Y = 1 and its RGB.
    sun: Option<(Vec<f32>, Vector3<f64>)>,
    premise: WhitePremise,
    /// The balance light's RGB (light premise: true RGB = rgb x balance).
    balance: Vector3<f64>,
    metric: RgbMetric,
    to_xyz: Matrix3<f64>,
}

/// The sun's SPD.
#[derive(Debug, Clone)]
pub enum SunSpec {
    /// No sun in the map.
    None,
    /// The daylight of this true RGB (the sun's colour), exactly; a Planckian radiator of its
    /// CCT times a smooth modulation where daylight would go negative (a red sun). The low sun
    /// ([`illuminant::low_sun`]) is not used here: modulated to the colour, the black body
    /// renders Mitsuba 3's low suns better (mean CIEDE2000 0.42 against 0.46 over 15 suns,
    /// tests/interop/test_low_sun.py) and the 5-degree truth skies 0.24 against 0.26.
    Colour {
        /// The sun's colour as true linear RGB (referenced to the space's white).
        rgb: [f64; 3],
        /// The sun's correlated colour temperature (K).
        cct_k: f64,
    },
    /// A given SPD (a named light, CIE D65, daylight or Planckian at the sun's CCT).
    Spd(Tabulated),
}

impl CarrierEngine {
    /// An engine for `carriers`, a daylight basis when `daylight`, and the sun.
    pub fn new(
        c: &Colorimeter,
        carriers: Vec<Carrier>,
        daylight: bool,
        sun: &SunSpec,
        premise: WhitePremise,
        balance: [f64; 3],
    ) -> Result<CarrierEngine> {
        let daylight_basis = c.daylight_basis()?;
        let sun = sun_spd(c, sun, daylight_basis.as_ref())?;
        Ok(CarrierEngine {
            carriers,
            daylight: if daylight { daylight_basis } else { None },
            sun,
            premise,
            balance: Vector3::from(balance),
            metric: RgbMetric::new(c.space()),
            to_xyz: c.space().to_xyz_matrix(),
        })
    }

    /// How pixels are measured (luminance, round trip).
    pub fn metric(&self) -> &RgbMetric {
        &self.metric
    }

    /// The RGB that the round trip divides by: the balance light's under the light premise,
    /// white under the D65 premise (the `specmap.lightRGB` attribute `roundtrip` reads).
    pub fn white_balance(&self) -> [f64; 3] {
        match self.premise {
            WhitePremise::Light => self.balance.into(),
            WhitePremise::Space => [1.0; 3],
        }
    }

    /// The sun's SPD (Y = 1), if any.
    pub fn sun_spectrum(&self) -> Option<&[f32]> {
        self.sun.as_ref().map(|(s, _)| s.as_slice())
    }

    fn true_rgb(&self, rgb: [f32; 3]) -> Vector3<f64> {
        let v = Vector3::new(rgb[0] as f64, rgb[1] as f64, rgb[2] as f64);
        match self.premise {
            WhitePremise::Light => v.component_mul(&self.balance),
            WhitePremise::Space => v,
        }
    }

    fn back(&self, v: Vector3<f64>) -> [f64; 3] {
        match self.premise {
            WhitePremise::Light => v.component_div(&self.balance).into(),
            WhitePremise::Space => v.into(),
        }
    }

    /// Writes the pixel's spectrum into `out` (one value per output wavelength).
    pub fn spectrum(&self, rgb: [f32; 3], a: Assign, out: &mut [f32]) -> Written {
        let r = self.true_rgb(rgb);
        let y = self
            .metric
            .luminance([r[0] as f32, r[1] as f32, r[2] as f32]);
        if a.sun {
            if let Some((s, srgb)) = &self.sun {
                return self.scaled(s, srgb, y.max(0.0), Took::Sun, out);
            }
        }
        if a.daylight {
            if let Some(d) = &self.daylight {
                if daylight_coloured(&(self.to_xyz * r)) {
                    let c = d.inv * r;
                    if !d.write(&c, out) {
                        return self.exact(d.rgb * c, Took::Daylight, out);
                    }
                }
            }
        }
        let carrier = &self.carriers[a.carrier as usize];
        if a.fixed {
            return self.scaled(&carrier.spd, &carrier.rgb, y.max(0.0), Took::Fixed, out);
        }
        for (basis, took) in [
            (&carrier.smooth, Took::Smooth),
            (&carrier.colorchecker, Took::Colorchecker),
        ] {
            if let Some(b) = basis {
                let c = b.inv * r;
                if !b.write(&c, out) {
                    return self.exact(b.rgb * c, took, out);
                }
            }
        }
        self.nonnegative(carrier, &r, out)
    }

    /// An accepted spectrum (negative nowhere beyond rounding): its rounding dips set to 0.
    fn exact(&self, back: Vector3<f64>, took: Took, out: &mut [f32]) -> Written {
        out.iter_mut().for_each(|v| *v = v.max(0.0));
        Written {
            rgb_back: self.back(back),
            took,
            exact: true,
        }
    }

    /// `spd` (Y = 1) at luminance `y`.
    fn scaled(
        &self,
        spd: &[f32],
        rgb: &Vector3<f64>,
        y: f64,
        took: Took,
        out: &mut [f32],
    ) -> Written {
        for (o, v) in out.iter_mut().zip(spd) {
            *o = y as f32 * v;
        }
        Written {
            rgb_back: self.back(rgb * y),
            took,
            exact: false,
        }
    }

    /// The carrier times a non-negative combination of Bernstein polynomials of rising degree,
    /// then of single bands: the first exact one, else the nearest colour (in XYZ) any
    /// non-negative spectrum under the carrier makes.
    fn nonnegative(&self, carrier: &Carrier, r: &Vector3<f64>, out: &mut [f32]) -> Written {
        let target = self.to_xyz * r;
        let tol = 1e-10 * target.norm().max(1e-300);
        let mut best: Option<(f64, &Family, Vec<f64>)> = None;
        for family in &carrier.nonneg {
            let (b, residual) = nnls(&family.xyz, &target);
            if best.as_ref().is_none_or(|(res, _, _)| residual < *res) {
                best = Some((residual, family, b));
            }
            if residual <= tol {
                break;
            }
        }
        let (residual, family, b) = best.expect("at least one family");
        out.iter_mut().for_each(|o| *o = 0.0);
        let mut back = Vector3::zeros();
        for (k, &c) in b.iter().enumerate() {
            if c > 0.0 {
                family.add(k, c, out);
                back += family.rgb[k] * c;
            }
        }
        let exact = residual <= tol;
        Written {
            rgb_back: self.back(back),
            took: if exact { Took::Nonneg } else { Took::Nearest },
            exact,
        }
    }
}

/// The sun's SPD at Y = 1 and its RGB.
fn sun_spd(
    c: &Colorimeter,
    sun: &SunSpec,
    daylight: Option<&Basis3>,
) -> Result<Option<(Vec<f32>, Vector3<f64>)>> {
    let of = |s: &Spectrum| -> Result<(Vec<f32>, Vector3<f64>)> {
        Ok((s.values().iter().map(|&v| v as f32).collect(), c.rgb(s)?))
    };
    match sun {
        SunSpec::None => Ok(None),
        SunSpec::Spd(t) => Ok(Some(of(&c.light("the sun's SPD", t)?)?)),
        SunSpec::Colour { rgb, cct_k } => {
            let r = Vector3::from(*rgb);
            if let Some(d) = daylight {
                let a = d.inv * r;
                let y = d.luminance(&a);
                let mut s = vec![0f32; c.grid().len()];
                if y > 0.0 && !d.write(&(a / y), &mut s) {
                    return Ok(Some((s, d.rgb * a / y)));
                }
            }
            // Warmer than daylight reaches: a carrier of its CCT modulated to its colour; the low
            // sun (sunlight through the atmosphere) below 4000 K, a black body above, where a
            // colour off the daylight family's reach is no low sun.
            let p = c.light("a Planckian sun", &illuminant::planckian(*cct_k)?)?;
            let mcc = crate::fit::PAPER_BASIS.map(|n| {
                data::spectrum(n).map(|s| s.data.resample(c.grid(), Interpolation::SMOOTH))
            });
            let [a, b, m] = mcc;
            let carrier = Carrier::new("sun", &p, c, &[a?, b?, m?])?;
            let mut s = vec![0f32; c.grid().len()];
            let engine = CarrierEngine {
                carriers: vec![carrier],
                daylight: None,
                sun: None,
                premise: WhitePremise::Space,
                balance: Vector3::repeat(1.0),
                metric: RgbMetric::new(c.space()),
                to_xyz: c.space().to_xyz_matrix(),
            };
            let w = engine.spectrum(
                [rgb[0] as f32, rgb[1] as f32, rgb[2] as f32],
                Assign::default(),
                &mut s,
            );
            let y = engine.metric.luminance(w.rgb_back.map(|v| v as f32));
            if y.is_nan() || y <= 0.0 {
                return Err(Error::invalid(format!(
                    "the sun's colour {rgb:?} has no luminance: no spectrum matches it"
                )));
            }
            s.iter_mut().for_each(|v| *v /= y as f32);
            Ok(Some((s, Vector3::from(w.rgb_back) / y)))
        }
    }
}

/// Non-negative least squares, min |G b - t| over b >= 0, for the three rows of `g`'s columns
/// (Lawson and Hanson 1974, active set). Returns b and the residual's norm.
pub(crate) fn nnls(g: &[Vector3<f64>], t: &Vector3<f64>) -> (Vec<f64>, f64) {
    let n = g.len();
    let mut x = vec![0.0; n];
    let mut passive = vec![false; n];
    let residual = |x: &[f64]| -> Vector3<f64> {
        let mut r = *t;
        for (k, &v) in x.iter().enumerate() {
            if v != 0.0 {
                r -= g[k] * v;
            }
        }
        r
    };
    let scale = g.iter().map(|v| v.norm()).fold(0.0, f64::max) * t.norm();
    let tol = 1e-13 * scale.max(1e-300);
    for _ in 0..3 * n {
        let r = residual(&x);
        let next = (0..n)
            .filter(|&k| !passive[k])
            .map(|k| (k, g[k].dot(&r)))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        match next {
            Some((k, w)) if w > tol => passive[k] = true,
            _ => break,
        }
        // Inner loop: least squares on the passive set, stepping back while it goes negative.
        for _ in 0..n {
            let z = passive_lstsq(g, &passive, t);
            if (0..n).all(|k| !passive[k] || z[k] > 0.0) {
                x = z;
                break;
            }
            let alpha = (0..n)
                .filter(|&k| passive[k] && z[k] <= 0.0)
                .map(|k| x[k] / (x[k] - z[k]))
                .fold(f64::INFINITY, f64::min);
            for k in 0..n {
                x[k] += alpha * (z[k] - x[k]);
                if passive[k] && x[k] <= 1e-15 * scale.max(1e-300) {
                    passive[k] = false;
                    x[k] = 0.0;
                }
            }
        }
    }
    let r = residual(&x).norm();
    (x, r)
}

/// Least squares on the passive columns (the others 0), by SVD (the set may be rank-deficient).
fn passive_lstsq(g: &[Vector3<f64>], passive: &[bool], t: &Vector3<f64>) -> Vec<f64> {
    let cols: Vec<usize> = (0..g.len()).filter(|&k| passive[k]).collect();
    let m = nalgebra::DMatrix::from_fn(3, cols.len(), |i, j| g[cols[j]][i]);
    let rhs = nalgebra::DVector::from_column_slice(t.as_slice());
    let sol = m
        .svd(true, true)
        .solve(&rhs, 1e-14)
        .unwrap_or_else(|_| nalgebra::DVector::zeros(cols.len()));
    let mut z = vec![0.0; g.len()];
    for (j, &k) in cols.iter().enumerate() {
        z[k] = sol[j];
    }
    z
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::{Observer, RgbSpace};
    use crate::spectrum::Rule;

    fn colorimeter() -> Colorimeter {
        Colorimeter::new(
            "380:780:5".parse().unwrap(),
            Observer::Cie1931,
            Rule::Riemann,
            RgbSpace::SRGB,
        )
        .unwrap()
    }

    fn mcc(c: &Colorimeter) -> [Spectrum; 3] {
        crate::fit::PAPER_BASIS.map(|n| {
            data::spectrum(n)
                .unwrap()
                .data
                .resample(c.grid(), Interpolation::SMOOTH)
        })
    }

    fn carrier(name: &str, c: &Colorimeter) -> Carrier {
        let t = data::spectrum(name).unwrap().data;
        Carrier::new(name, &c.light(name, &t).unwrap(), c, &mcc(c)).unwrap()
    }

    fn engine(carriers: Vec<Carrier>, c: &Colorimeter) -> CarrierEngine {
        CarrierEngine::new(
            c,
            carriers,
            true,
            &SunSpec::None,
            WhitePremise::Space,
            [1.0; 3],
        )
        .unwrap()
    }

    #[test]
    fn every_spectrum_is_non_negative_and_exact_where_it_can_be() {
        let c = colorimeter();
        let e = engine(vec![carrier("FL2", &c), carrier("hps", &c)], &c);
        let mut out = vec![0f32; c.grid().len()];
        let mut exact = 0;
        let colours = [
            [1.0f32, 1.0, 1.0],
            [0.9, 0.05, 0.02],
            [0.01, 0.02, 0.9],
            [0.05, 0.9, 0.01],
            [-0.02, 0.3, 0.9],
            [2.0, 0.5, -0.01],
        ];
        for carrier in [0u16, 1] {
            for rgb in colours {
                let a = Assign {
                    carrier,
                    ..Assign::default()
                };
                let w = e.spectrum(rgb, a, &mut out);
                assert!(out.iter().all(|&v| v >= 0.0), "{rgb:?} {:?}", w.took);
                if w.exact {
                    exact += 1;
                    let de = e.metric.round_trip_error(rgb, w.rgb_back);
                    assert!(de < 1e-3, "{rgb:?} {:?}: {de}", w.took);
                }
            }
        }
        // Most colours are reproduced under a fluorescent lamp; the sodium lamp cannot make a
        // saturated blue.
        assert!(exact >= 8, "{exact}");
    }

    #[test]
    fn a_pixel_of_the_carriers_colour_is_the_carrier() {
        let c = colorimeter();
        let fl2 = carrier("FL2", &c);
        let rgb = fl2.rgb.map(|v| 3.0 * v as f32);
        let spd = fl2.spd.clone();
        let e = engine(vec![fl2], &c);
        let mut out = vec![0f32; c.grid().len()];
        let w = e.spectrum([rgb[0], rgb[1], rgb[2]], Assign::default(), &mut out);
        assert_eq!(w.took, Took::Smooth);
        for (o, s) in out.iter().zip(&spd) {
            assert!((o - 3.0 * s).abs() <= 1e-4 * 3.0 * s.abs().max(1e-3));
        }
    }

    #[test]
    fn a_red_sun_beyond_the_daylight_family_is_a_modulated_black_body_and_exact() {
        let c = colorimeter();
        let sun_of = |rgb: [f64; 3], cct_k: f64| {
            CarrierEngine::new(
                &c,
                vec![carrier("D65", &c)],
                true,
                &SunSpec::Colour { rgb, cct_k },
                WhitePremise::Space,
                [1.0; 3],
            )
            .unwrap()
        };
        // A Planckian colour, beyond the daylight family at 1900 K: a black body of its CCT times
        // a modulation (the smooth quadratic or the paper's ColorChecker basis).
        let p = c
            .light("p", &illuminant::planckian(1900.0).unwrap())
            .unwrap();
        let rgb: [f64; 3] = c.rgb(&p).unwrap().into();
        let e = sun_of(rgb, 1900.0);
        let s = e.sun_spectrum().unwrap();
        assert!(s.iter().all(|&v| v >= 0.0));
        let grid = *c.grid();
        let ratio_to = |t: &Tabulated| -> Vec<f64> {
            let r = t.resample(&grid, Interpolation::LIGHT);
            (0..s.len()).map(|i| s[i] as f64 / r.values()[i]).collect()
        };
        let x = |i: usize| (grid.wavelength_nm(i) - SMOOTH_CENTRE_NM) / SMOOTH_HALF_WIDTH_NM;
        let smooth: [Vec<f64>; 3] = [
            (0..s.len()).map(|_| 1.0).collect(),
            (0..s.len()).map(x).collect(),
            (0..s.len()).map(|i| x(i) * x(i)).collect(),
        ];
        let paper = crate::fit::PAPER_BASIS.map(|n| {
            let t = data::spectrum(n).unwrap().data;
            t.resample(&grid, Interpolation::SMOOTH).values().to_vec()
        });
        // How far the ratio is from the span of a modulation's three functions (least squares).
        let off_span = |r: &[f64], f: &[Vec<f64>; 3]| -> f64 {
            let m: Matrix3<f64> =
                Matrix3::from_fn(|a, b| (0..r.len()).map(|i| f[a][i] * f[b][i]).sum::<f64>());
            let v: Vector3<f64> =
                Vector3::from_fn(|a, _| (0..r.len()).map(|i| f[a][i] * r[i]).sum::<f64>());
            let k = m.try_inverse().unwrap() * v;
            let scale = r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            (0..r.len())
                .map(|i| (r[i] - (0..3).map(|a| k[a] * f[a][i]).sum::<f64>()).abs())
                .fold(0.0, f64::max)
                / scale
        };
        let bb = ratio_to(&illuminant::planckian(1900.0).unwrap());
        let bb_off = off_span(&bb, &smooth).min(off_span(&bb, &paper));
        assert!(bb_off < 1e-4, "{bb_off}");
        let mut out = vec![0f32; c.grid().len()];
        let px = rgb.map(|v| 5000.0 * v as f32);
        let a = Assign {
            sun: true,
            ..Assign::default()
        };
        let w = e.spectrum(px, a, &mut out);
        assert!(e.metric.round_trip_error(px, w.rgb_back) < 1e-3);
    }

    #[test]
    fn nnls_solves_inside_the_cone_and_projects_outside() {
        let g = [Vector3::x(), Vector3::y(), Vector3::new(1.0, 1.0, 1.0)];
        let (b, r) = nnls(&g, &Vector3::new(2.0, 3.0, 1.0));
        assert!(r < 1e-12, "{b:?} {r}");
        assert!(b.iter().all(|&v| v >= 0.0));
        // Outside the cone (negative z): the nearest point has z = 0.
        let (b, r) = nnls(&g, &Vector3::new(1.0, 1.0, -1.0));
        assert!((r - 1.0).abs() < 1e-12, "{b:?} {r}");
        assert!((b[0] - 1.0).abs() < 1e-12 && (b[1] - 1.0).abs() < 1e-12 && b[2] == 0.0);
    }

    #[test]
    fn a_saturated_colour_inside_the_spectral_locus_is_exact_and_non_negative() {
        // Yellow-green foliage with no blue (a colour the smooth families cannot reach).
        let c = colorimeter();
        let e = engine(vec![carrier("D65", &c)], &c);
        let mut out = vec![0f32; c.grid().len()];
        let rgb = [0.2f32, 0.27, 0.001];
        let w = e.spectrum(rgb, Assign::default(), &mut out);
        assert!(out.iter().all(|&v| v >= 0.0));
        assert!(w.exact, "{:?}", w.took);
        assert!(e.metric.round_trip_error(rgb, w.rgb_back) < 1e-3);
    }

    #[test]
    fn bernstein_polynomials_partition_unity() {
        for t in [0.0, 0.3, 1.0] {
            let s: f64 = (0..=8).map(|k| bernstein_poly(8, k, t)).sum();
            assert!((s - 1.0).abs() < 1e-12);
        }
    }
}
