//! Multilayer thin-film optics: complex Fresnel coefficients, Snell's law and the Airy recursion.
//!
//! The paper's single film (section 2.2, Eq. 2-7) generalised to any number of layers on a
//! substrate, as in Hirayama et al. (2000): the reflection amplitude of everything below a layer is
//! folded into the layer above it, bottom-up,
//!
//! ```text
//! r_j = (r_{j-1,j} + r_{j+1} e^{2 i delta_j}) / (1 + r_{j-1,j} r_{j+1} e^{2 i delta_j}),
//! delta_j = 2 pi n_j d_j cos(theta_j) / lambda,
//! ```
//!
//! and likewise for the transmission amplitude. Conventions are those of Byrnes' `tmm`
//! (arXiv:1603.02720), against which `tests/interop/test_thinfilm.py` checks this module:
//! - indices are `n + ik` with `k >= 0` absorbing (gain media, `k < 0`, are rejected);
//! - in every medium the wave's normal wavevector `q = n cos(theta) = sqrt(n^2 - (n_0 sin theta_0)^2)`
//!   takes the branch that decays forward (`Im q >= 0`) or, when lossless and propagating, carries
//!   power forward (`Re q >= 0`): tmm's `is_forward_angle`. Nothing divides by `n` or `cos theta`,
//!   so evanescent layers (total internal reflection) and grazing angles stay finite;
//! - `R = |r|^2`; `T` is the power entering the substrate: `Re(q_sub) / Re(q_0) |t|^2` for s,
//!   `Re(n_sub conj(cos theta_sub)) / Re(n_0 conj(cos theta_0)) |t|^2` for p (tmm's `T_from_t`).
//!   `1 - R - T` is the power absorbed by the layers; with an absorbing (metal) substrate the power
//!   `T` is absorbed within the substrate's skin depth;
//! - unpolarised light is the mean of s and p.
//!
//! The ambient medium must be transparent (`k = 0`): through an absorbing medium the incident power
//! is not defined. At exactly 90 degrees no power reaches the surface and the result is the limit
//! from below for any stack with an interface, `R = 1`, `T = 0`.
//!
//! The phase `exp(i delta)` is evaluated with its real part range-reduced in cycles
//! (`Re(q) d / lambda` minus its nearest integer, exact in floating point) before the sine and
//! cosine, so a 1 mm film is as accurate as a 100 nm one, in f64 and in f32 (the GPU's precision;
//! every evaluation is generic over [`Real`]). The factor `exp(-Im delta)` is at most 1, so thick
//! absorbing or evanescent layers underflow to 0 instead of overflowing.
//!
//! Fringes of a thick layer are about `lambda^2 / (2 Re(q) d)` apart. A grid resolves them only
//! with at least two samples per fringe (Nyquist): when the period is below twice the wavelength
//! step of the requested grid the coherent spectrum would be aliased, so [`Stack::response`]
//! treats the layer incoherently (intensities summed, phases averaged out, as tmm's `inc_tmm`)
//! and lists it in [`Response::incoherent_layers`].

use crate::data::Table;
use crate::error::{Error, Result};
use crate::spectrum::{Tabulated, WavelengthGrid};
use nalgebra::{Complex, RealField};
use std::fmt;
use std::str::FromStr;

/// The floating-point types the optics are evaluated in: `f64` on the CPU, `f32` as on the GPU.
pub trait Real: RealField + Copy + private::Sealed {
    /// `x` rounded to this type.
    fn of_f64(x: f64) -> Self;
    /// This value as an f64 (exact).
    fn as_f64(self) -> f64;
}

impl Real for f64 {
    #[inline]
    fn of_f64(x: f64) -> Self {
        x
    }
    #[inline]
    fn as_f64(self) -> f64 {
        self
    }
}

impl Real for f32 {
    #[inline]
    fn of_f64(x: f64) -> Self {
        x as f32
    }
    #[inline]
    fn as_f64(self) -> f64 {
        self as f64
    }
}

mod private {
    pub trait Sealed {}
    impl Sealed for f64 {}
    impl Sealed for f32 {}
}

// ---------------------------------------------------------------------------------------------
// Refractive indices and dispersion
// ---------------------------------------------------------------------------------------------

/// Largest accepted `n` or `k`: far above any material's, low enough that `n^2` and the optical
/// thickness in cycles stay finite in f32.
const MAX_INDEX: f64 = 1e6;
/// Largest accepted optical thickness, in wavelengths.
const MAX_CYCLES: f64 = 1e20;

/// A complex refractive index `n + ik` of a passive medium: finite, `n >= 0`, `k >= 0` (absorbing
/// when `k > 0`), not both zero, both below 1e6.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Index {
    n: f64,
    k: f64,
}

impl Index {
    /// `n + ik`; an error for a non-finite value, `n < 0`, `n = k = 0`, or a gain medium (`k < 0`).
    pub fn new(n: f64, k: f64) -> Result<Index> {
        if !(n.is_finite() && k.is_finite()) {
            return Err(Error::invalid(format!(
                "refractive index {n}+{k}i is not finite"
            )));
        }
        if k < 0.0 {
            return Err(Error::unsupported(format!(
                "refractive index {n}{k}i has k = {k} < 0, a gain medium; only passive media \
                 (k >= 0, absorbing when k > 0) are supported"
            )));
        }
        if n < 0.0 {
            return Err(Error::unsupported(format!(
                "refractive index {n}+{k}i has a negative real part; negative-index media are \
                 not supported"
            )));
        }
        if n == 0.0 && k == 0.0 {
            return Err(Error::invalid("refractive index 0 is not a medium"));
        }
        if n > MAX_INDEX || k > MAX_INDEX {
            return Err(Error::invalid(format!(
                "refractive index {n}+{k}i is implausibly large (n and k must be below {MAX_INDEX:e})"
            )));
        }
        // -0.0 would flip branch choices downstream.
        Ok(Index {
            n: n + 0.0,
            k: k + 0.0,
        })
    }

    /// A transparent medium, `n + 0i`.
    pub fn real(n: f64) -> Result<Index> {
        Index::new(n, 0.0)
    }

    /// The real part, the ordinary refractive index.
    pub fn n(&self) -> f64 {
        self.n
    }

    /// The extinction coefficient (imaginary part).
    pub fn k(&self) -> f64 {
        self.k
    }

    /// `n + ik` as a complex number in `T`.
    pub fn complex<T: Real>(&self) -> Complex<T> {
        Complex::new(T::of_f64(self.n), T::of_f64(self.k))
    }
}

impl fmt::Display for Index {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.k == 0.0 {
            write!(f, "{}", self.n)
        } else {
            write!(f, "{}+{}i", self.n, self.k)
        }
    }
}

/// Parses `2.7`, `3.1+3.3i` (or `j`), `3.3i`; `1.5-0.1i` is a gain medium and an error.
impl FromStr for Index {
    type Err = Error;
    fn from_str(s: &str) -> Result<Index> {
        let t = s.trim();
        let bad = || {
            Error::invalid(format!(
                "'{s}' is not a refractive index (write e.g. 2.7 or 3.1+3.3i)"
            ))
        };
        let num = |p: &str| p.trim().parse::<f64>().map_err(|_| bad());
        let Some(body) = t.strip_suffix(['i', 'j', 'I', 'J']) else {
            return Index::real(num(t)?);
        };
        // The sign that separates the real and imaginary parts: not the first character and not
        // an exponent's sign.
        let bytes = body.as_bytes();
        let split = (1..bytes.len()).rev().find(|&i| {
            (bytes[i] == b'+' || bytes[i] == b'-') && !matches!(bytes[i - 1], b'e' | b'E')
        });
        let (n, k) = match split {
            Some(i) => (num(&body[..i])?, num(&body[i..])?),
            None => (0.0, num(body)?),
        };
        Index::new(n, k)
    }
}

/// One of the material's dispersion laws: the refractive index as a function of wavelength.
#[derive(Debug, Clone, PartialEq)]
pub enum Material {
    /// The same index at every wavelength.
    Constant(Index),
    /// Cauchy: `n = A + B / lambda^2 + C / lambda^4` with lambda in micrometres, `k = 0`.
    Cauchy {
        /// A (dimensionless).
        a: f64,
        /// B in µm².
        b: f64,
        /// C in µm⁴.
        c: f64,
    },
    /// Sellmeier: `n^2 = 1 + sum_i B_i lambda^2 / (lambda^2 - C_i)` with lambda in micrometres
    /// (C_i in µm²), `k = 0`.
    Sellmeier {
        /// The (B_i, C_i) pairs, B_i dimensionless, C_i in µm².
        terms: Vec<(f64, f64)>,
    },
    /// Measured `n(lambda)`, `k(lambda)`, interpolated linearly; outside the table the nearest
    /// end value is held constant (the project's convention for every table).
    Table(IndexTable),
}

/// Tabulated optical constants: wavelengths in nm with `n` and `k` at each.
#[derive(Debug, Clone, PartialEq)]
pub struct IndexTable {
    n: Tabulated,
    k: Tabulated,
}

impl IndexTable {
    /// `n` and `k` at `wavelengths_nm` (strictly increasing); every entry must be a valid
    /// [`Index`].
    pub fn new(wavelengths_nm: Vec<f64>, n: Vec<f64>, k: Vec<f64>) -> Result<IndexTable> {
        let nt = Tabulated::new(wavelengths_nm.clone(), n)?;
        let kt = Tabulated::new(wavelengths_nm, k)?;
        for ((w, n), k) in nt.wavelengths_nm().iter().zip(nt.values()).zip(kt.values()) {
            Index::new(*n, *k).map_err(|e| Error::invalid(format!("at {w} nm: {e}")))?;
        }
        Ok(IndexTable { n: nt, k: kt })
    }

    /// The index at `wavelength_nm`, linearly interpolated (a convex combination of valid
    /// indices, so valid itself).
    pub fn at(&self, wavelength_nm: f64) -> Index {
        Index {
            n: lerp(&self.n, wavelength_nm),
            k: lerp(&self.k, wavelength_nm),
        }
    }
}

fn lerp(t: &Tabulated, x: f64) -> f64 {
    let w = t.wavelengths_nm();
    let v = t.values();
    let last = w.len() - 1;
    if x <= w[0] || last == 0 {
        return v[0];
    }
    if x >= w[last] {
        return v[last];
    }
    let i = w.partition_point(|&wi| wi <= x).clamp(1, last); // w[i-1] <= x < w[i]
    let f = (x - w[i - 1]) / (w[i] - w[i - 1]);
    v[i - 1] + f * (v[i] - v[i - 1])
}

/// Schott N-BK7 (Schott data sheet, Sellmeier coefficients).
const BK7: [(f64, f64); 3] = [
    (1.039_612_12, 0.006_000_698_67),
    (0.231_792_344, 0.020_017_914_4),
    (1.010_469_45, 103.560_653),
];
/// Fused silica (Malitson 1965).
const FUSED_SILICA: [(f64, f64); 3] = [
    (0.696_166_3, 0.068_404_3 * 0.068_404_3),
    (0.407_942_6, 0.116_241_4 * 0.116_241_4),
    (0.897_479_4, 9.896_161 * 9.896_161),
];

impl Material {
    /// A constant index.
    pub fn constant(index: Index) -> Material {
        Material::Constant(index)
    }

    /// Cauchy's formula (lambda in µm); the coefficients must be finite.
    pub fn cauchy(a: f64, b: f64, c: f64) -> Result<Material> {
        if ![a, b, c].iter().all(|v| v.is_finite()) {
            return Err(Error::invalid(format!(
                "Cauchy coefficients {a}, {b}, {c} must be finite"
            )));
        }
        Ok(Material::Cauchy { a, b, c })
    }

    /// Sellmeier's formula with terms `(B_i, C_i)` (lambda and sqrt(C_i) in µm).
    pub fn sellmeier(terms: &[(f64, f64)]) -> Result<Material> {
        if terms.is_empty() {
            return Err(Error::invalid(
                "a Sellmeier formula needs at least one term",
            ));
        }
        if !terms.iter().all(|(b, c)| b.is_finite() && c.is_finite()) {
            return Err(Error::invalid("Sellmeier coefficients must be finite"));
        }
        Ok(Material::Sellmeier {
            terms: terms.to_vec(),
        })
    }

    /// A table with columns `n` and (optionally) `k`, e.g. a CSV
    /// `wavelength_nm,n,k`.
    pub fn from_table(table: &Table) -> Result<Material> {
        let n = table.column("n").map_err(|_| {
            Error::invalid(format!(
                "table '{}' has no column 'n': an index table needs columns n and k (it has: {})",
                table.name(),
                table.columns().join(", ")
            ))
        })?;
        let k = match table.column_index("k") {
            Ok(i) => table.column_at(i)?.values().to_vec(),
            Err(_) => vec![0.0; n.values().len()],
        };
        let t = IndexTable::new(table.wavelengths_nm().to_vec(), n.values().to_vec(), k)
            .map_err(|e| Error::invalid(format!("table '{}': {e}", table.name())))?;
        Ok(Material::Table(t))
    }

    /// Built-in dispersion formulas by name: `bk7` (Schott N-BK7) and `fused-silica` (Malitson
    /// 1965). None for other names.
    pub fn named(name: &str) -> Option<Material> {
        match name.to_ascii_lowercase().replace('_', "-").as_str() {
            "bk7" | "n-bk7" => Some(Material::Sellmeier {
                terms: BK7.to_vec(),
            }),
            "fused-silica" | "silica" | "sio2" => Some(Material::Sellmeier {
                terms: FUSED_SILICA.to_vec(),
            }),
            _ => None,
        }
    }

    /// The index at `wavelength_nm`; an error where the formula gives no physical index (a
    /// Sellmeier pole or `n^2 <= 0`, a Cauchy `n <= 0`) or the wavelength is not positive.
    pub fn index_at(&self, wavelength_nm: f64) -> Result<Index> {
        if !(wavelength_nm.is_finite() && wavelength_nm > 0.0) {
            return Err(Error::invalid(format!(
                "wavelength {wavelength_nm} nm must be finite and positive"
            )));
        }
        let um2 = (wavelength_nm * 1e-3) * (wavelength_nm * 1e-3);
        match self {
            Material::Constant(i) => Ok(*i),
            Material::Cauchy { a, b, c } => {
                let n = a + b / um2 + c / (um2 * um2);
                if !(n.is_finite() && n > 0.0) {
                    return Err(Error::invalid(format!(
                        "Cauchy formula gives n = {n} at {wavelength_nm} nm"
                    )));
                }
                Index::real(n)
            }
            Material::Sellmeier { terms } => {
                let n2 = 1.0 + terms.iter().map(|(b, c)| b * um2 / (um2 - c)).sum::<f64>();
                if !(n2.is_finite() && n2 > 0.0) {
                    return Err(Error::invalid(format!(
                        "Sellmeier formula gives n^2 = {n2} at {wavelength_nm} nm (at or beyond \
                         a resonance)"
                    )));
                }
                Index::real(n2.sqrt())
            }
            Material::Table(t) => Ok(t.at(wavelength_nm)),
        }
    }
}

impl From<Index> for Material {
    fn from(i: Index) -> Material {
        Material::Constant(i)
    }
}

// ---------------------------------------------------------------------------------------------
// Geometry: angle of incidence and polarisation
// ---------------------------------------------------------------------------------------------

/// An angle of incidence in the ambient medium, 0 (normal) to 90 degrees (grazing).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Incidence {
    degrees: f64,
    sin: f64,
    cos: f64,
}

impl Incidence {
    /// Normal incidence.
    pub const NORMAL: Incidence = Incidence {
        degrees: 0.0,
        sin: 0.0,
        cos: 1.0,
    };

    /// The angle from the normal in degrees, in [0, 90]. 90 is exactly grazing (cos = 0).
    pub fn degrees(degrees: f64) -> Result<Incidence> {
        if !(0.0..=90.0).contains(&degrees) {
            return Err(Error::invalid(format!(
                "angle of incidence {degrees} degrees must be between 0 and 90"
            )));
        }
        let (sin, cos) = if degrees == 90.0 {
            (1.0, 0.0)
        } else {
            degrees.to_radians().sin_cos()
        };
        Ok(Incidence { degrees, sin, cos })
    }

    /// The angle from the normal in degrees.
    pub fn as_degrees(&self) -> f64 {
        self.degrees
    }
    /// Sine of the angle.
    pub fn sin(&self) -> f64 {
        self.sin
    }
    /// Cosine of the angle (0 at grazing).
    pub fn cos(&self) -> f64 {
        self.cos
    }
}

/// The polarisation of a plane wave relative to the plane of incidence.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Wave {
    /// Electric field perpendicular to the plane of incidence (TE, the paper's r-perp).
    S,
    /// Electric field parallel to the plane of incidence (TM, the paper's r-parallel).
    P,
}

/// The polarisation of the incident light: s, p, or unpolarised (the mean of s and p).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Polarization {
    /// s (TE) only.
    S,
    /// p (TM) only.
    P,
    /// The mean of the s and p responses.
    Unpolarized,
}

impl Polarization {
    fn waves(self) -> &'static [Wave] {
        match self {
            Polarization::S => &[Wave::S],
            Polarization::P => &[Wave::P],
            Polarization::Unpolarized => &[Wave::S, Wave::P],
        }
    }
}

impl fmt::Display for Polarization {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Polarization::S => "s",
            Polarization::P => "p",
            Polarization::Unpolarized => "unpolarized",
        })
    }
}

// ---------------------------------------------------------------------------------------------
// The optics at one wavelength, generic over f32 / f64
// ---------------------------------------------------------------------------------------------

/// Reflected and transmitted power fractions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rt<T> {
    /// Reflectance `R`.
    pub r: T,
    /// Transmittance `T`: the power entering the substrate.
    pub t: T,
}

impl<T: Real> Rt<T> {
    /// The power absorbed by the layers, `1 - R - T`.
    pub fn absorbed(&self) -> T {
        T::one() - self.r - self.t
    }
}

/// A medium seen by a wave with transverse invariant `xi = n_0 sin theta_0`.
#[derive(Debug, Clone, Copy)]
struct Medium<T> {
    n: Complex<T>,
    n2: Complex<T>,
    /// `n cos theta`, forward branch.
    q: Complex<T>,
}

impl<T: Real> Medium<T> {
    /// `q = sqrt(n^2 - xi^2)`, computed as `sqrt((n^2 - n_0^2) + q_0^2)`, which is the same
    /// number but does not cancel at grazing incidence, and gives `q = q_0` exactly when
    /// `n = n_0`. `g = (n_0^2, q_0^2)`.
    #[inline]
    fn new(n: Complex<T>, g: (T, T)) -> Medium<T> {
        let n2 = n * n;
        let z = Complex::new(n2.re - g.0 + g.1, n2.im);
        Medium {
            n,
            n2,
            q: forward_sqrt(z),
        }
    }
}

/// `sqrt(z)` on the forward branch: `Im >= 0`, and `Re >= 0` when the imaginary part is 0.
#[inline]
fn forward_sqrt<T: Real>(z: Complex<T>) -> Complex<T> {
    let two = T::one() + T::one();
    let m = z.re.hypot(z.im);
    if m == T::zero() {
        return Complex::new(T::zero(), T::zero());
    }
    let (a, b) = if z.re >= T::zero() {
        let a = ((m + z.re) / two).sqrt();
        (a, z.im / (two * a))
    } else {
        let b = ((m - z.re) / two).sqrt();
        (z.im / (two * b), b)
    };
    if b < T::zero() || (b == T::zero() && a < T::zero()) {
        Complex::new(-a, -b)
    } else {
        Complex::new(a, b)
    }
}

/// Fresnel amplitude coefficients `(r, t)` from medium `a` into medium `b`, in tmm's sign
/// conventions: paper Eq. 2 multiplied through by `n_a n_b` so that nothing divides by `n` or
/// `cos theta`.
#[inline]
fn interface<T: Real>(wave: Wave, a: &Medium<T>, b: &Medium<T>) -> (Complex<T>, Complex<T>) {
    if a.n == b.n {
        return (
            Complex::new(T::zero(), T::zero()),
            Complex::new(T::one(), T::zero()),
        );
    }
    let two = T::one() + T::one();
    match wave {
        Wave::S => {
            let den = a.q + b.q;
            ((a.q - b.q) / den, a.q * two / den)
        }
        Wave::P => {
            let x = b.n2 * a.q;
            let y = a.n2 * b.q;
            let den = x + y;
            ((x - y) / den, a.n * b.n * a.q * two / den)
        }
    }
}

/// `exp(i q d 2 pi / lambda)` with `Re(q) d / lambda` reduced to (-1/2, 1/2] cycles first.
#[inline]
fn propagate<T: Real>(q: Complex<T>, d_over_lambda: T) -> Complex<T> {
    let cycles = q.re * d_over_lambda;
    let frac = cycles - cycles.round();
    let (s, c) = (T::two_pi() * frac).sin_cos();
    let decay = (-(T::two_pi() * q.im * d_over_lambda)).exp();
    Complex::new(decay * c, decay * s)
}

/// Power carried across a plane by a unit amplitude in medium `m`, up to a common factor:
/// `Re(q)` for s, `Re(n conj(cos theta)) = Re(n^2 conj(q)) / |n|^2` for p (tmm's `T_from_t`).
#[inline]
fn flux<T: Real>(wave: Wave, m: &Medium<T>) -> T {
    match wave {
        Wave::S => m.q.re,
        Wave::P => (m.n2 * m.q.conj()).re / m.n.norm_sqr(),
    }
}

/// The s and p amplitude coefficients `(r, t)` of one interface (zeros for a wave not asked).
type Pair<T> = [(Complex<T>, Complex<T>); 2];

/// The s and p Fresnel coefficients from `a` into `b`, each only where asked.
#[inline]
fn interfaces<T: Real>(do_s: bool, do_p: bool, a: &Medium<T>, b: &Medium<T>) -> Pair<T> {
    let zero = Complex::new(T::zero(), T::zero());
    [
        if do_s {
            interface(Wave::S, a, b)
        } else {
            (zero, zero)
        },
        if do_p {
            interface(Wave::P, a, b)
        } else {
            (zero, zero)
        },
    ]
}

/// One step up the Airy recursion: a layer's `q` and `d / lambda`, and the interface from the
/// medium above it into it.
#[derive(Debug, Clone, Copy)]
struct Step<T> {
    q: Complex<T>,
    d_over_lambda: T,
    above: Pair<T>,
}

/// The stack's s and p amplitudes `(r, t)`: the bottom interface's, folded up through `steps`
/// (from the substrate side) with every thickness times `scale`: [`Film::coherent_rt`]'s loop
/// (the same [`airy_step`]) on a [`Sweep`]'s stored steps.
#[inline(always)]
fn airy<T: Real>(
    do_s: bool,
    do_p: bool,
    bottom: Pair<T>,
    steps: impl Iterator<Item = Step<T>>,
    scale: T,
) -> Pair<T> {
    let one = Complex::new(T::one(), T::zero());
    let [(mut rs, mut ts), (mut rp, mut tp)] = bottom;
    for step in steps {
        let e1 = propagate(step.q, step.d_over_lambda * scale);
        let e2 = e1 * e1;
        if do_s {
            (rs, ts) = airy_step((rs, ts), step.above[0], e1, e2, one);
        }
        if do_p {
            (rp, tp) = airy_step((rp, tp), step.above[1], e1, e2, one);
        }
    }
    [(rs, ts), (rp, tp)]
}

/// One layer of the Airy recursion: the amplitudes `(r, t)` below it seen through the interface
/// above it (`(ra, ta)`), the layer's phase `e1` and its square `e2`.
#[inline(always)]
fn airy_step<T: Real>(
    (r, t): (Complex<T>, Complex<T>),
    (ra, ta): (Complex<T>, Complex<T>),
    e1: Complex<T>,
    e2: Complex<T>,
    one: Complex<T>,
) -> (Complex<T>, Complex<T>) {
    let x = r * e2;
    let den = one + ra * x;
    ((ra + x) / den, ta * t * e1 / den)
}

/// R and T from the amplitudes: `|r|^2` and `|t|^2` times the flux out over the flux in
/// (`fluxes(wave)`, 0 when nothing comes in), unpolarised the mean of s and p.
#[inline(always)]
fn powers<T: Real>(
    pol: Polarization,
    amplitudes: Pair<T>,
    fluxes: impl Fn(Wave) -> (T, T),
) -> Rt<T> {
    let power = |wave: Wave, (r, t): (Complex<T>, Complex<T>)| {
        let (f_in, f_out) = fluxes(wave);
        Rt {
            r: r.norm_sqr(),
            t: if f_in > T::zero() {
                t.norm_sqr() * f_out / f_in
            } else {
                T::zero()
            },
        }
    };
    let [s, p] = amplitudes;
    match pol {
        Polarization::S => power(Wave::S, s),
        Polarization::P => power(Wave::P, p),
        Polarization::Unpolarized => {
            let (a, b) = (power(Wave::S, s), power(Wave::P, p));
            let half = T::of_f64(0.5);
            Rt {
                r: (a.r + b.r) * half,
                t: (a.t + b.t) * half,
            }
        }
    }
}

/// A film at one angle of incidence and polarisation, prepared by [`Film::sweep`] for many
/// thickness scales.
#[derive(Debug, Clone)]
pub struct Sweep<T> {
    pol: Polarization,
    /// Exactly 90 degrees: `R = 1`, `T = 0` whatever the layers.
    grazing: bool,
    bottom: Pair<T>,
    /// From the substrate side up.
    steps: Vec<Step<T>>,
    /// `(in, out)` fluxes for s and p.
    fluxes: [(T, T); 2],
}

impl<T: Real> Sweep<T> {
    /// R and T with every layer's thickness multiplied by `thickness_scale` (finite, `>= 0`,
    /// as for [`Film::rt_scaled`]; not checked).
    #[inline]
    pub fn rt(&self, thickness_scale: T) -> Rt<T> {
        if self.grazing {
            return Rt {
                r: T::one(),
                t: T::zero(),
            };
        }
        let (do_s, do_p) = (self.pol != Polarization::P, self.pol != Polarization::S);
        let amplitudes = airy(
            do_s,
            do_p,
            self.bottom,
            self.steps.iter().copied(),
            thickness_scale,
        );
        powers(self.pol, amplitudes, |wave| match wave {
            Wave::S => self.fluxes[0],
            Wave::P => self.fluxes[1],
        })
    }
}

/// The optical constants of a stack at one wavelength, in `T`: the ambient (transparent), the
/// layers from the ambient side with their thicknesses, and the substrate. Build with
/// [`Stack::at`] or [`Film::new`]; evaluating it never fails.
#[derive(Debug, Clone, PartialEq)]
pub struct Film<T> {
    wavelength_nm: T,
    /// ambient, layers..., substrate.
    n: Vec<Complex<T>>,
    /// `d / lambda` for each entry of `n` (0 for the ambient and the substrate).
    d_over_lambda: Vec<T>,
}

impl<T: Real> Film<T> {
    /// `layers` are `(index, thickness in nm)` from the ambient side. The ambient must be
    /// transparent (k = 0); thicknesses finite and >= 0; the wavelength finite and positive.
    pub fn new(
        wavelength_nm: f64,
        ambient: Index,
        layers: &[(Index, f64)],
        substrate: Index,
    ) -> Result<Film<T>> {
        if !(wavelength_nm.is_finite() && wavelength_nm > 0.0) {
            return Err(Error::invalid(format!(
                "wavelength {wavelength_nm} nm must be finite and positive"
            )));
        }
        check_ambient(&ambient)?;
        let mut n = vec![ambient.complex()];
        let mut d = vec![T::zero()];
        for (i, (index, thickness)) in layers.iter().enumerate() {
            check_thickness(*thickness)
                .map_err(|e| Error::invalid(format!("layer {}: {e}", i + 1)))?;
            let cycles = index.n.hypot(index.k) * thickness / wavelength_nm;
            if cycles.is_nan() || cycles > MAX_CYCLES {
                return Err(Error::invalid(format!(
                    "layer {}: {} nm is {cycles:e} wavelengths thick at {wavelength_nm} nm; at \
                     most {MAX_CYCLES:e}",
                    i + 1,
                    crate::spectrum::fmt_num(*thickness)
                )));
            }
            n.push(index.complex());
            d.push(T::of_f64(thickness / wavelength_nm));
        }
        n.push(substrate.complex());
        d.push(T::zero());
        Ok(Film {
            wavelength_nm: T::of_f64(wavelength_nm),
            n,
            d_over_lambda: d,
        })
    }

    /// The wavelength the film is evaluated at, nm.
    pub fn wavelength_nm(&self) -> T {
        self.wavelength_nm
    }

    /// Number of layers between the ambient and the substrate.
    pub fn layers(&self) -> usize {
        self.n.len() - 2
    }

    /// `n cos theta` in every medium (ambient, layers, substrate) on the forward branch.
    pub fn normal_wavevectors(&self, incidence: &Incidence) -> Vec<Complex<T>> {
        let g = self.xi2(incidence);
        (0..self.n.len())
            .map(|i| self.medium(i, incidence, g).q)
            .collect()
    }

    /// `(n_0^2, q_0^2)`: what every medium's `q` is computed from.
    #[inline]
    fn xi2(&self, incidence: &Incidence) -> (T, T) {
        let n0 = self.n[0].re;
        let q0 = n0 * T::of_f64(incidence.cos);
        (n0 * n0, q0 * q0)
    }

    #[inline]
    fn ambient(&self, incidence: &Incidence) -> Medium<T> {
        // q_0 = n_0 cos theta_0 directly: exact at grazing, where sqrt(n0^2 - xi^2) cancels.
        let n = self.n[0];
        Medium {
            n,
            n2: n * n,
            q: Complex::new(n.re * T::of_f64(incidence.cos), T::zero()),
        }
    }

    #[inline]
    fn medium(&self, i: usize, incidence: &Incidence, xi2: (T, T)) -> Medium<T> {
        if i == 0 {
            self.ambient(incidence)
        } else {
            Medium::new(self.n[i], xi2)
        }
    }

    /// The reflection and transmission amplitudes `(r, t)` of the whole stack, all layers
    /// coherent (tmm's `coh_tmm` `r` and `t`). At exactly 90 degrees, `(-1, 0)`.
    pub fn amplitudes(&self, incidence: &Incidence, wave: Wave) -> (Complex<T>, Complex<T>) {
        if incidence.cos == 0.0 {
            return (
                Complex::new(-T::one(), T::zero()),
                Complex::new(T::zero(), T::zero()),
            );
        }
        self.segment(incidence, wave, 0, self.n.len() - 1)
    }

    /// `(r, t)` of the coherent segment from medium `from` to medium `to` (either direction),
    /// bottom-up Airy recursion without allocation.
    #[inline]
    fn segment(
        &self,
        incidence: &Incidence,
        wave: Wave,
        from: usize,
        to: usize,
    ) -> (Complex<T>, Complex<T>) {
        let xi2 = self.xi2(incidence);
        let step = |i: usize| if to > from { i - 1 } else { i + 1 };
        let below = self.medium(to, incidence, xi2);
        let mut j = step(to);
        let mut here = self.medium(j, incidence, xi2);
        let (mut r, mut t) = interface(wave, &here, &below);
        let one = Complex::new(T::one(), T::zero());
        while j != from {
            let above_i = step(j);
            let above = self.medium(above_i, incidence, xi2);
            let e1 = propagate(here.q, self.d_over_lambda[j]);
            let x = r * e1 * e1;
            let (ra, ta) = interface(wave, &above, &here);
            let den = one + ra * x;
            r = (ra + x) / den;
            t = ta * t * e1 / den;
            here = above;
            j = above_i;
        }
        (r, t)
    }

    /// R and T of the whole stack, all layers coherent, every layer's thickness multiplied by
    /// `scale` (1 for the film as built; `x * 1 = x` exactly, so the results are the same bits):
    /// [`Film::segment`] for s and p at once, sharing each medium's `q` and phase factor (the hot
    /// path). [`Sweep::rt`] is the same recursion, one [`airy_step`] per layer, on stored media
    /// and interfaces ([`airy`]); `rt_scaled_and_sweep_are_the_film_with_scaled_layers` checks
    /// that they agree bit for bit.
    fn coherent_rt(&self, incidence: &Incidence, pol: Polarization, scale: T) -> Rt<T> {
        if incidence.cos == 0.0 {
            return Rt {
                r: T::one(),
                t: T::zero(),
            };
        }
        let (do_s, do_p) = (pol != Polarization::P, pol != Polarization::S);
        let g = self.xi2(incidence);
        let last = self.n.len() - 1;
        let sub = self.medium(last, incidence, g);
        let mut j = last - 1;
        let mut here = self.medium(j, incidence, g);
        let zero = Complex::new(T::zero(), T::zero());
        let one = Complex::new(T::one(), T::zero());
        let ((mut rs, mut ts), (mut rp, mut tp)) = (
            if do_s {
                interface(Wave::S, &here, &sub)
            } else {
                (zero, zero)
            },
            if do_p {
                interface(Wave::P, &here, &sub)
            } else {
                (zero, zero)
            },
        );
        while j != 0 {
            let above = self.medium(j - 1, incidence, g);
            let e1 = propagate(here.q, self.d_over_lambda[j] * scale);
            let e2 = e1 * e1;
            if do_s {
                let above_s = interface(Wave::S, &above, &here);
                (rs, ts) = airy_step((rs, ts), above_s, e1, e2, one);
            }
            if do_p {
                let above_p = interface(Wave::P, &above, &here);
                (rp, tp) = airy_step((rp, tp), above_p, e1, e2, one);
            }
            here = above;
            j -= 1;
        }
        let power = |wave: Wave, r: Complex<T>, t: Complex<T>| {
            let f_in = flux(wave, &here);
            Rt {
                r: r.norm_sqr(),
                t: if f_in > T::zero() {
                    t.norm_sqr() * flux(wave, &sub) / f_in
                } else {
                    T::zero()
                },
            }
        };
        match pol {
            Polarization::S => power(Wave::S, rs, ts),
            Polarization::P => power(Wave::P, rp, tp),
            Polarization::Unpolarized => {
                let (a, b) = (power(Wave::S, rs, ts), power(Wave::P, rp, tp));
                let half = T::of_f64(0.5);
                Rt {
                    r: (a.r + b.r) * half,
                    t: (a.t + b.t) * half,
                }
            }
        }
    }

    /// The film at one angle of incidence prepared for evaluating at many thickness scales:
    /// every medium's `q`, every interface's Fresnel coefficients and the fluxes computed once,
    /// so that each [`Sweep::rt`] costs only the layers' phase factors and the recursion, about
    /// half of [`Film::rt_scaled`]. `film.sweep(at, pol).rt(s)` is `film.rt_scaled(at, pol, s)`
    /// bit for bit.
    ///
    /// ```
    /// use specmap::thinfilm::{Film, Incidence, Index, Polarization};
    ///
    /// let (air, glass) = (Index::real(1.0)?, Index::real(1.52)?);
    /// let film = Film::<f64>::new(550.0, air, &[(Index::new(2.0, 0.3)?, 60.0)], glass)?;
    /// let at = Incidence::degrees(60.0)?;
    /// let sweep = film.sweep(&at, Polarization::Unpolarized);
    /// for s in [0.0, 0.5, 1.0, 3.0] {
    ///     assert_eq!(sweep.rt(s), film.rt_scaled(&at, Polarization::Unpolarized, s));
    /// }
    /// # Ok::<(), specmap::Error>(())
    /// ```
    pub fn sweep(&self, incidence: &Incidence, pol: Polarization) -> Sweep<T> {
        let (do_s, do_p) = (pol != Polarization::P, pol != Polarization::S);
        let g = self.xi2(incidence);
        let last = self.n.len() - 1;
        let sub = self.medium(last, incidence, g);
        let mut here = self.medium(last - 1, incidence, g);
        let bottom = interfaces(do_s, do_p, &here, &sub);
        let mut steps = Vec::with_capacity(last - 1);
        for j in (1..last).rev() {
            let above = self.medium(j - 1, incidence, g);
            steps.push(Step {
                q: here.q,
                d_over_lambda: self.d_over_lambda[j],
                above: interfaces(do_s, do_p, &above, &here),
            });
            here = above;
        }
        let ambient = self.ambient(incidence);
        Sweep {
            pol,
            grazing: incidence.cos == 0.0,
            bottom,
            steps,
            fluxes: [Wave::S, Wave::P].map(|w| (flux(w, &ambient), flux(w, &sub))),
        }
    }

    /// Power fractions of the coherent segment `from -> to`.
    #[inline]
    fn segment_rt(&self, incidence: &Incidence, wave: Wave, from: usize, to: usize) -> Rt<T> {
        let (r, t) = self.segment(incidence, wave, from, to);
        let xi2 = self.xi2(incidence);
        let f_in = flux(wave, &self.medium(from, incidence, xi2));
        let f_out = flux(wave, &self.medium(to, incidence, xi2));
        let tt = if f_in > T::zero() {
            t.norm_sqr() * f_out / f_in
        } else {
            T::zero()
        };
        Rt {
            r: r.norm_sqr(),
            t: tt,
        }
    }

    /// R and T with every layer coherent (tmm's `coh_tmm`).
    pub fn rt(&self, incidence: &Incidence, pol: Polarization) -> Rt<T> {
        self.rt_mixed(incidence, pol, &[])
    }

    /// R and T with every layer coherent (as [`Film::rt`]) and every layer's thickness
    /// multiplied by `thickness_scale`, without building the scaled film: for sweeping a
    /// design's thickness (a designer dragging it, a table of scale x angle x wavelength) from
    /// one `Film` per wavelength. `rt_scaled(incidence, pol, 1)` is `rt(incidence, pol)`, bit for
    /// bit.
    ///
    /// `thickness_scale` must be finite and `>= 0`, and the scaled layers within what
    /// [`Film::new`] accepts (at most 1e20 wavelengths thick): this is not checked here (it is
    /// the hot path); check once by building the film at the largest scale.
    ///
    /// ```
    /// use specmap::thinfilm::{Film, Incidence, Index, Polarization};
    ///
    /// let (air, glass, mgf2) = (Index::real(1.0)?, Index::real(1.52)?, Index::real(1.38)?);
    /// let thin = Film::<f64>::new(550.0, air, &[(mgf2, 50.0)], glass)?;
    /// let thick = Film::<f64>::new(550.0, air, &[(mgf2, 100.0)], glass)?;
    /// let at = Incidence::degrees(30.0)?;
    /// let (a, b) = (thin.rt_scaled(&at, Polarization::S, 2.0), thick.rt(&at, Polarization::S));
    /// assert!((a.r - b.r).abs() < 1e-15 && (a.t - b.t).abs() < 1e-15);
    /// # Ok::<(), specmap::Error>(())
    /// ```
    pub fn rt_scaled(&self, incidence: &Incidence, pol: Polarization, thickness_scale: T) -> Rt<T> {
        self.coherent_rt(incidence, pol, thickness_scale)
    }

    /// R and T with the layers listed in `incoherent` (0-based, from the ambient side) treated
    /// incoherently: their internal reflections add in intensity, not in amplitude (tmm's
    /// `inc_tmm`). Out-of-range entries are ignored.
    pub fn rt_mixed(
        &self,
        incidence: &Incidence,
        pol: Polarization,
        incoherent: &[usize],
    ) -> Rt<T> {
        if incoherent.is_empty() {
            return self.coherent_rt(incidence, pol, T::one());
        }
        let waves = pol.waves();
        let mut sum = Rt {
            r: T::zero(),
            t: T::zero(),
        };
        for &w in waves {
            let one = self.rt_wave(incidence, w, incoherent);
            sum.r += one.r;
            sum.t += one.t;
        }
        if waves.len() == 2 {
            let half = T::of_f64(0.5);
            sum.r *= half;
            sum.t *= half;
        }
        sum
    }

    fn rt_wave(&self, incidence: &Incidence, wave: Wave, incoherent: &[usize]) -> Rt<T> {
        if incidence.cos == 0.0 {
            return Rt {
                r: T::one(),
                t: T::zero(),
            };
        }
        let last = self.n.len() - 1;
        if incoherent.is_empty() {
            return self.segment_rt(incidence, wave, 0, last);
        }
        // Media that end coherent segments: the ambient, incoherent layers, the substrate.
        let mut cuts: Vec<usize> = Vec::new();
        cuts.push(0);
        for i in 1..last {
            if incoherent.contains(&(i - 1)) {
                cuts.push(i);
            }
        }
        cuts.push(last);
        if cuts.len() == 2 {
            return self.segment_rt(incidence, wave, 0, last);
        }
        // Bottom-up over incoherent media: `acc` is R and T of everything below medium m, seen
        // from inside m going down.
        let xi2 = self.xi2(incidence);
        let k = cuts.len() - 1;
        let mut acc = self.segment_rt(incidence, wave, cuts[k - 1], cuts[k]);
        for s in (1..k).rev() {
            let (top, m) = (cuts[s - 1], cuts[s]);
            let fwd = self.segment_rt(incidence, wave, top, m);
            let back = self.segment_rt(incidence, wave, m, top);
            let q = self.medium(m, incidence, xi2).q;
            // Single-pass power transmission of the incoherent layer.
            let p = (-(T::two_pi() + T::two_pi()) * q.im * self.d_over_lambda[m]).exp();
            let p2 = p * p;
            let den = T::one() - back.r * acc.r * p2;
            acc = Rt {
                r: fwd.r + fwd.t * back.t * p2 * acc.r / den,
                t: fwd.t * p * acc.t / den,
            };
        }
        acc
    }

    /// Fringe spacing `lambda^2 / (2 Re(q) d)` in nm of layer `layer` (0-based); infinite for a
    /// layer of zero thickness or with no propagating wave.
    pub fn fringe_period_nm(&self, layer: usize, incidence: &Incidence) -> f64 {
        let i = layer + 1;
        if i >= self.n.len() - 1 {
            return f64::INFINITY;
        }
        let q = Medium::new(self.n[i], self.xi2(incidence)).q.re.as_f64();
        let d_over_lambda = self.d_over_lambda[i].as_f64();
        let lambda = self.wavelength_nm.as_f64();
        if q > 0.0 && d_over_lambda > 0.0 {
            lambda / (2.0 * q * d_over_lambda)
        } else {
            f64::INFINITY
        }
    }
}

fn check_ambient(ambient: &Index) -> Result<()> {
    if ambient.k != 0.0 || ambient.n <= 0.0 {
        return Err(Error::invalid(format!(
            "ambient index {ambient}: the incident medium must be transparent (k = 0, n > 0)"
        )));
    }
    Ok(())
}

fn check_thickness(d: f64) -> Result<()> {
    if !d.is_finite() {
        return Err(Error::invalid(format!("thickness {d} nm is not finite")));
    }
    if d < 0.0 {
        return Err(Error::invalid(format!("thickness {d} nm is negative")));
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Stacks with dispersion, evaluated over a wavelength grid
// ---------------------------------------------------------------------------------------------

/// A layer: its material and thickness in nm.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    material: Material,
    thickness_nm: f64,
}

impl Layer {
    /// An error for a negative or non-finite thickness.
    pub fn new(material: Material, thickness_nm: f64) -> Result<Layer> {
        check_thickness(thickness_nm)?;
        Ok(Layer {
            material,
            thickness_nm: thickness_nm + 0.0,
        })
    }
    /// The layer's material.
    pub fn material(&self) -> &Material {
        &self.material
    }
    /// Thickness in nm (non-negative).
    pub fn thickness_nm(&self) -> f64 {
        self.thickness_nm
    }
}

/// Samples per fringe below which [`Coherence::Auto`] treats a layer incoherently: the Nyquist
/// rate of the fringes' cosine. Measured against the coherent film at 1 nm under D65 (the test
/// `nyquist_gives_the_truer_colour` prints the numbers), it picks a colour far nearer the truth
/// than the period-below-one-step rule it replaces.
pub const NYQUIST_SAMPLES: f64 = 2.0;

/// How [`Stack::response`] treats thick layers.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Coherence {
    /// Incoherent where the layer's fringe period is below twice the grid step (fewer than two
    /// samples per fringe, [`NYQUIST_SAMPLES`]) somewhere on the grid, coherent elsewhere.
    Auto,
    /// Every layer coherent, whatever the grid (aliased fringes for thick layers).
    Coherent,
    /// These layers (0-based from the ambient side) incoherent, the rest coherent.
    Incoherent(Vec<usize>),
}

/// R and T over a wavelength grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Response {
    /// The wavelengths the response is sampled on.
    pub grid: WavelengthGrid,
    /// Reflectance: the fraction of incident power reflected, one per wavelength.
    pub reflectance: Vec<f64>,
    /// Transmittance: the fraction of incident power entering the substrate, one per wavelength.
    pub transmittance: Vec<f64>,
    /// Layers (0-based from the ambient side) computed incoherently.
    pub incoherent_layers: Vec<usize>,
}

/// An ambient medium, layers from the ambient side, and a substrate.
#[derive(Debug, Clone, PartialEq)]
pub struct Stack {
    ambient: Material,
    layers: Vec<Layer>,
    substrate: Material,
}

impl Stack {
    /// A stack of `layers` (from the ambient side) between `ambient` and `substrate`.
    pub fn new(ambient: Material, layers: Vec<Layer>, substrate: Material) -> Stack {
        Stack {
            ambient,
            layers,
            substrate,
        }
    }

    /// The layers, from the ambient side.
    pub fn layers(&self) -> &[Layer] {
        &self.layers
    }

    /// The stack's optical constants at one wavelength; errors name the medium at fault.
    pub fn at<T: Real>(&self, wavelength_nm: f64) -> Result<Film<T>> {
        let ambient = self
            .ambient
            .index_at(wavelength_nm)
            .map_err(|e| Error::invalid(format!("ambient: {e}")))?;
        let layers = self
            .layers
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let n = l
                    .material
                    .index_at(wavelength_nm)
                    .map_err(|e| Error::invalid(format!("layer {}: {e}", i + 1)))?;
                Ok((n, l.thickness_nm))
            })
            .collect::<Result<Vec<_>>>()?;
        let substrate = self
            .substrate
            .index_at(wavelength_nm)
            .map_err(|e| Error::invalid(format!("substrate: {e}")))?;
        Film::new(wavelength_nm, ambient, &layers, substrate)
            .map_err(|e| Error::invalid(format!("at {wavelength_nm} nm: {e}")))
    }

    /// R and T on `grid` in f64. With [`Coherence::Auto`], a layer whose fringe period
    /// `lambda^2 / (2 Re(n cos theta) d)` is below [`NYQUIST_SAMPLES`] grid steps at some
    /// wavelength is computed incoherently over the whole grid, and listed in the result.
    ///
    /// Bare glass (n 1.5) reflects `((n - 1) / (n + 1))^2 = 4%` at normal incidence; a
    /// quarter-wave layer of MgF2 (n 1.38) on glass (n 1.52) brings that to
    /// `((1.52 - 1.38^2) / (1.52 + 1.38^2))^2`, about 1.26%, at its design wavelength:
    ///
    /// ```
    /// use specmap::spectrum::WavelengthGrid;
    /// use specmap::thinfilm::{Coherence, Incidence, Index, Layer, Material, Polarization, Stack};
    ///
    /// let n = |v: f64| Ok::<_, specmap::Error>(Material::constant(Index::real(v)?));
    /// let grid = WavelengthGrid::new(450.0, 650.0, 50.0)?; // 550 nm is sample 2
    /// let normal = Incidence::degrees(0.0)?;
    ///
    /// let bare = Stack::new(n(1.0)?, vec![], n(1.5)?);
    /// let r = bare.response(&grid, &normal, Polarization::Unpolarized, Coherence::Auto)?;
    /// assert!((r.reflectance[2] - 0.04).abs() < 1e-12);
    /// assert!((r.transmittance[2] - 0.96).abs() < 1e-12);
    ///
    /// let quarter_wave = Layer::new(n(1.38)?, 550.0 / (4.0 * 1.38))?;
    /// let coated = Stack::new(n(1.0)?, vec![quarter_wave], n(1.52)?);
    /// let r = coated.response(&grid, &normal, Polarization::Unpolarized, Coherence::Auto)?;
    /// let expected = ((1.52 - 1.38f64.powi(2)) / (1.52 + 1.38f64.powi(2))).powi(2);
    /// assert!((r.reflectance[2] - expected).abs() < 1e-12, "{}", r.reflectance[2]);
    /// assert!(r.reflectance[0] > expected); // the minimum is at the design wavelength
    /// # Ok::<(), specmap::Error>(())
    /// ```
    pub fn response(
        &self,
        grid: &WavelengthGrid,
        incidence: &Incidence,
        pol: Polarization,
        coherence: Coherence,
    ) -> Result<Response> {
        let films = grid
            .wavelengths_nm()
            .map(|w| self.at::<f64>(w))
            .collect::<Result<Vec<_>>>()?;
        let incoherent: Vec<usize> = match coherence {
            Coherence::Coherent => Vec::new(),
            Coherence::Incoherent(mut v) => {
                v.retain(|&i| i < self.layers.len());
                v.sort_unstable();
                v.dedup();
                v
            }
            Coherence::Auto => (0..self.layers.len())
                .filter(|&i| {
                    grid.len() > 1
                        && films.iter().any(|f| {
                            f.fringe_period_nm(i, incidence) < NYQUIST_SAMPLES * grid.step_nm()
                        })
                })
                .collect(),
        };
        let mut reflectance = Vec::with_capacity(grid.len());
        let mut transmittance = Vec::with_capacity(grid.len());
        for f in &films {
            let rt = f.rt_mixed(incidence, pol, &incoherent);
            if !(rt.r.is_finite() && rt.t.is_finite()) {
                return Err(Error::invalid(format!(
                    "no finite reflectance at {} nm and {} degrees: the stack has a resonance \
                     (a pole of the recursion) exactly there",
                    f.wavelength_nm(),
                    incidence.as_degrees()
                )));
            }
            reflectance.push(rt.r);
            transmittance.push(rt.t);
        }
        Ok(Response {
            grid: *grid,
            reflectance,
            transmittance,
            incoherent_layers: incoherent,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_index_out_of_reach_is_unsupported_and_a_malformed_one_invalid() {
        // Callers can tell what specmap does not do from a value that is wrong.
        assert!(matches!(
            Index::new(1.5, -0.1),
            Err(Error::Unsupported { file: None, .. })
        ));
        assert!(matches!(
            Index::new(-1.5, 0.0),
            Err(Error::Unsupported { .. })
        ));
        assert!(matches!(Index::new(f64::NAN, 0.0), Err(Error::Invalid(_))));
        assert!(matches!(Index::new(0.0, 0.0), Err(Error::Invalid(_))));
    }

    fn idx(n: f64, k: f64) -> Index {
        Index::new(n, k).unwrap()
    }

    #[test]
    fn parses_indices() {
        assert_eq!("2.7".parse::<Index>().unwrap(), idx(2.7, 0.0));
        assert_eq!("3.1+3.3i".parse::<Index>().unwrap(), idx(3.1, 3.3));
        assert_eq!(" 1e0+2.5e-1j ".parse::<Index>().unwrap(), idx(1.0, 0.25));
        assert_eq!("3.3i".parse::<Index>().unwrap(), idx(0.0, 3.3));
        let gain = "1.5-0.1i".parse::<Index>().unwrap_err().to_string();
        assert!(gain.contains("gain"), "{gain}");
        assert!("abc".parse::<Index>().is_err());
        assert!("1.5+i".parse::<Index>().is_err());
        assert!("nan".parse::<Index>().is_err());
        assert!("-1.5".parse::<Index>().is_err());
    }

    #[test]
    fn forward_branch_decays_or_propagates_forward() {
        for (re, im) in [
            (2.0f64, 0.0f64),
            (-2.0, 0.0),
            (-2.0, -0.0),
            (-9.0, 1e-300),
            (3.0, 4.0),
            (0.0, 0.0),
        ] {
            let w = forward_sqrt(Complex::new(re, im));
            assert!(w.im >= 0.0, "{re}+{im}i -> {w}");
            if w.im == 0.0 {
                assert!(w.re >= 0.0);
            }
            let back = w * w;
            assert!((back.re - re).abs() < 1e-12 && (back.im - im).abs() < 1e-12);
        }
    }

    #[test]
    fn phase_is_range_reduced() {
        // 1e6 + 0.25 cycles: exactly a quarter turn, even in f32 where 1e6 cycles of phase in
        // radians (6.3e6) has an ulp of 0.5 rad.
        let e = propagate(Complex::new(1.0f32, 0.0), 1_000_000.25);
        assert!((e.re).abs() < 1e-6 && (e.im - 1.0).abs() < 1e-6, "{e}");
    }

    /// CIEDE2000 under D65 of a reflectance on `grid` against the coherent one at 1 nm.
    fn colour_error(stack: &Stack, grid: &WavelengthGrid, coherence: Coherence) -> f64 {
        use crate::colorimetry::{delta_e_2000, Cmfs, Lab, Observer};
        use crate::spectrum::{Interpolation, Rule, Spectrum};
        let d65 = crate::data::spectrum("D65").unwrap().data;
        let xyz = |g: &WavelengthGrid, c: Coherence, rule: Rule| {
            let r = stack
                .response(g, &Incidence::NORMAL, Polarization::Unpolarized, c)
                .unwrap();
            let cmfs = Cmfs::new(Observer::Cie1931, g).unwrap();
            let light = d65.resample(g, Interpolation::LIGHT);
            let r = Spectrum::new(*g, r.reflectance).unwrap();
            (
                cmfs.reflectance_xyz(&r, &light, rule).unwrap(),
                cmfs.light_xyz(&light, rule).unwrap(),
            )
        };
        let (truth, white) = xyz(
            &WavelengthGrid::visible_1nm(),
            Coherence::Coherent,
            Rule::Simpson,
        );
        let (got, _) = xyz(grid, coherence, Rule::Riemann);
        delta_e_2000(Lab::from_xyz(got, white), Lab::from_xyz(truth, white))
    }

    /// A free-standing layer of index `n` and thickness `d` nm in air.
    fn slab(n: f64, d: f64) -> Stack {
        Stack::new(
            Index::real(1.0).unwrap().into(),
            vec![Layer::new(Index::real(n).unwrap().into(), d).unwrap()],
            Index::real(1.0).unwrap().into(),
        )
    }

    fn period(film: &Stack, wavelength_nm: f64) -> f64 {
        let f = film.at::<f64>(wavelength_nm).unwrap();
        f.fringe_period_nm(0, &Incidence::NORMAL)
    }

    #[test]
    fn auto_goes_incoherent_below_two_samples_per_fringe() {
        let auto = |n: f64, d: f64, step: f64| {
            let grid = WavelengthGrid::new(380.0, 780.0, step).unwrap();
            slab(n, d)
                .response(&grid, &Incidence::NORMAL, Polarization::S, Coherence::Auto)
                .unwrap()
                .incoherent_layers
        };
        // 5 um of n = 1.5: fringes 9.6 nm apart at 380 nm, fewer than two samples each on a
        // 5 nm grid. The period-below-the-step rule kept it coherent.
        assert!((period(&slab(1.5, 5000.0), 380.0) - 9.63).abs() < 0.01);
        assert_eq!(auto(1.5, 5000.0, 5.0), vec![0]);
        // 1.9 um of n = 2.7 on a 10 nm grid (fringes 14 nm apart at 380 nm): coherent, its
        // colour is 7.5 CIEDE2000 from the truth; incoherent, 0.3.
        let film = slab(2.7, 1916.0);
        assert!(
            (period(&film, 380.0) - 13.96).abs() < 0.01,
            "{}",
            period(&film, 380.0)
        );
        assert_eq!(auto(2.7, 1916.0, 10.0), vec![0]);
        let grid = WavelengthGrid::new(380.0, 780.0, 10.0).unwrap();
        let coherent = colour_error(&film, &grid, Coherence::Coherent);
        let incoherent = colour_error(&film, &grid, Coherence::Auto);
        assert!(
            incoherent < 0.5 && coherent > 5.0,
            "{incoherent} vs {coherent}"
        );
        // 1 um of n = 1.5: fringes of 48 nm at 380 nm, ten samples on a 5 nm grid: coherent.
        assert!(auto(1.5, 1000.0, 5.0).is_empty());
    }

    #[test]
    fn nyquist_gives_the_truer_colour() {
        // Films of n 1.33, 2 and 2.7 from 0.3 um to where the 1 nm reference still resolves
        // them (4 samples per fringe at 380 nm), on 5, 10 and 20 nm grids: how much further from
        // the coherent colour at 1 nm each rule's choice is than the better of coherent and
        // incoherent. Nyquist is at least three times nearer than the period-below-one-step
        // rule it replaces, on the mean and in the worst case.
        let rules = [("one step", 1.0), ("Nyquist", NYQUIST_SAMPLES)];
        let (mut worst, mut sum, mut count) = ([0.0f64; 2], [0.0f64; 2], 0);
        for n in [1.33, 2.0, 2.7] {
            for step in [5.0, 10.0, 20.0] {
                let grid = WavelengthGrid::new(380.0, 780.0, step).unwrap();
                let mut d = 300.0;
                while period(&slab(n, d), 380.0) >= 4.0 {
                    let film = slab(n, d);
                    let c = colour_error(&film, &grid, Coherence::Coherent);
                    let i = colour_error(&film, &grid, Coherence::Incoherent(vec![0]));
                    for (r, &(_, samples)) in rules.iter().enumerate() {
                        let chosen = if period(&film, 380.0) < samples * step {
                            i
                        } else {
                            c
                        };
                        worst[r] = worst[r].max(chosen - c.min(i));
                        sum[r] += chosen - c.min(i);
                    }
                    count += 1;
                    d *= 1.08;
                }
            }
        }
        for (r, (name, _)) in rules.iter().enumerate() {
            let mean = sum[r] / count as f64;
            eprintln!(
                "{name}: CIEDE2000 beyond the better choice: mean {mean:.3}, worst {:.3} over \
                 {count} films",
                worst[r]
            );
        }
        assert!(
            3.0 * worst[1] < worst[0] && 3.0 * sum[1] < sum[0],
            "{worst:?} {sum:?}"
        );
    }

    #[test]
    fn rt_scaled_and_sweep_are_the_film_with_scaled_layers() {
        // Two layers, one absorbing, on a metal: scaling every thickness by s in the evaluation
        // is the film built with the thicknesses times s, for s and p and both, at 0 and 70
        // degrees, including s = 0 (the bare substrate) and s = 1 (the film itself, bit for bit);
        // a sweep is rt_scaled bit for bit.
        let (air, metal) = (idx(1.0, 0.0), idx(3.1, 3.3));
        let layers = [(idx(1.38, 0.0), 95.0), (idx(2.0, 0.3), 60.0)];
        let base = Film::<f64>::new(520.0, air, &layers, metal).unwrap();
        for degrees in [0.0, 70.0] {
            let at = Incidence::degrees(degrees).unwrap();
            for pol in [Polarization::S, Polarization::P, Polarization::Unpolarized] {
                assert_eq!(base.rt_scaled(&at, pol, 1.0), base.rt(&at, pol));
                for s in [0.0, 0.37, 2.5] {
                    let scaled: Vec<_> = layers.iter().map(|&(n, d)| (n, d * s)).collect();
                    let want = Film::<f64>::new(520.0, air, &scaled, metal)
                        .unwrap()
                        .rt(&at, pol);
                    let got = base.rt_scaled(&at, pol, s);
                    assert!(
                        (got.r - want.r).abs() < 1e-13 && (got.t - want.t).abs() < 1e-13,
                        "{degrees} {pol} x{s}: {got:?} vs {want:?}"
                    );
                }
            }
            for pol in [Polarization::S, Polarization::P, Polarization::Unpolarized] {
                let sweep = base.sweep(&at, pol);
                for s in [0.0, 0.37, 1.0, 2.5] {
                    assert_eq!(
                        sweep.rt(s),
                        base.rt_scaled(&at, pol, s),
                        "{degrees} {pol} x{s}"
                    );
                }
            }
            let bare = Film::<f64>::new(520.0, air, &[], metal).unwrap();
            let zero = base.rt_scaled(&at, Polarization::Unpolarized, 0.0);
            let want = bare.rt(&at, Polarization::Unpolarized);
            assert!((zero.r - want.r).abs() < 1e-13, "{zero:?} vs {want:?}");
        }
    }

    #[test]
    fn table_interpolates_linearly_and_holds_ends() {
        let t = IndexTable::new(vec![400.0, 500.0], vec![1.0, 2.0], vec![0.0, 1.0]).unwrap();
        assert_eq!(t.at(450.0), idx(1.5, 0.5));
        assert_eq!(t.at(300.0), idx(1.0, 0.0));
        assert_eq!(t.at(900.0), idx(2.0, 1.0));
        assert!(IndexTable::new(vec![400.0], vec![1.0], vec![-0.1]).is_err());
    }
}
