//! SPD -> XYZ (paper Eq. 10/11), RGB colour spaces, CIELAB, CIEDE2000, chromaticity and CCT.
//!
//! Scale convention: XYZ is on the paper's scale, Y = 100 for the reference white (a perfect
//! reflector under the light, or the light itself). RGB values are on the 0..1 scale, so
//! `rgb = M * XYZ / 100`.

use crate::data::Table;
use crate::error::{Error, Result};
use crate::spectrum::{Interpolation, Rule, Spectrum, WavelengthGrid};
use nalgebra::{Matrix3, Vector3};

/// A CIE standard observer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Observer {
    /// CIE 1931 2-degree.
    #[default]
    Cie1931,
    /// CIE 1964 10-degree.
    Cie1964,
}

impl std::fmt::Display for Observer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Observer::Cie1931 => "CIE 1931 2°",
            Observer::Cie1964 => "CIE 1964 10°",
        })
    }
}

impl Observer {
    /// Name of the observer's built-in CMF table (`cie1931`, `cie1964`).
    pub fn table_name(self) -> &'static str {
        match self {
            Observer::Cie1931 => "cie1931",
            Observer::Cie1964 => "cie1964",
        }
    }
}

/// Colour-matching functions resampled onto one grid.
#[derive(Debug, Clone)]
pub struct Cmfs {
    /// The observer the functions belong to.
    pub observer: Observer,
    /// x̄(λ) on the grid (0 outside the tables' 360-830 nm).
    pub x: Spectrum,
    /// ȳ(λ) on the grid (0 outside the tables' 360-830 nm).
    pub y: Spectrum,
    /// z̄(λ) on the grid (0 outside the tables' 360-830 nm).
    pub z: Spectrum,
}

impl Cmfs {
    /// The observer's built-in CMFs on `grid` (CIE 167 resampling; the tables are at 1 nm).
    /// Outside the tables' range (360-830 nm) the observer sees nothing: the functions are 0
    /// there, not their end values held (colour-science integrates over the CMFs' own domain).
    pub fn new(observer: Observer, grid: &WavelengthGrid) -> Result<Cmfs> {
        let t = Table::builtin(observer.table_name())?;
        let col = |c: &str| -> Result<Spectrum> {
            let data = t.column(c)?;
            let (lo, hi) = data.range_nm();
            let s = data.resample(grid, Interpolation::Cie167);
            let values = grid
                .wavelengths_nm()
                .zip(s.values())
                .map(|(l, &v)| if (lo..=hi).contains(&l) { v } else { 0.0 })
                .collect();
            Spectrum::new(*grid, values)
        };
        Ok(Cmfs {
            observer,
            x: col("x")?,
            y: col("y")?,
            z: col("z")?,
        })
    }

    /// The wavelengths the functions are sampled on.
    pub fn grid(&self) -> &WavelengthGrid {
        self.x.grid()
    }

    /// The raw integrals (sum of f * xbar etc. by `rule`), no normalisation.
    pub fn integrate(&self, f: &Spectrum, rule: Rule) -> Result<[f64; 3]> {
        Ok([
            f.try_mul(&self.x)?.integrate(rule),
            f.try_mul(&self.y)?.integrate(rule),
            f.try_mul(&self.z)?.integrate(rule),
        ])
    }

    /// Eq. 11: k = 100 / integral(S * ybar). An error if the light has no energy in range.
    pub fn k(&self, light: &Spectrum, rule: Rule) -> Result<f64> {
        let y = light.try_mul(&self.y)?.integrate(rule);
        if y.is_infinite() {
            return Err(Error::invalid(format!(
                "the light's values overflow: the integral of S * ybar over {} is {y:e}; scale \
                 the spectrum down",
                self.grid()
            )));
        }
        if !(y.is_finite() && y > 0.0) {
            return Err(Error::invalid(format!(
                "the light has no visible energy in {} (integral of S * ybar = {y:e})",
                self.grid()
            )));
        }
        Ok(100.0 / y)
    }

    /// Eq. 10/11: XYZ of reflectance `r` under `light`, Y = 100 for a perfect white.
    pub fn reflectance_xyz(&self, r: &Spectrum, light: &Spectrum, rule: Rule) -> Result<Xyz> {
        let k = self.k(light, rule)?;
        let [x, y, z] = self.integrate(&r.try_mul(light)?, rule)?;
        Ok(Xyz::new(k * x, k * y, k * z))
    }

    /// XYZ of a light alone, normalised to Y = 100.
    ///
    /// D65's chromaticity is about (0.3127, 0.3290), its CCT about 6504 K:
    ///
    /// ```
    /// use specmap::colorimetry::{cct, Cmfs, Observer};
    /// use specmap::spectrum::{Interpolation, Rule, WavelengthGrid};
    ///
    /// let grid = WavelengthGrid::visible_1nm();
    /// let cmfs = Cmfs::new(Observer::Cie1931, &grid)?;
    /// let d65 = specmap::data::spectrum("D65")?.data.resample(&grid, Interpolation::LIGHT);
    /// let xyz = cmfs.light_xyz(&d65, Rule::Riemann)?;
    /// assert!((xyz.y() - 100.0).abs() < 1e-9);
    /// let [x, y] = xyz.xy();
    /// assert!((x - 0.3127).abs() < 5e-4 && (y - 0.3290).abs() < 5e-4, "{x} {y}");
    /// let k = cct(xyz)?.kelvin.unwrap();
    /// assert!((k - 6504.0).abs() < 15.0, "{k}");
    /// # Ok::<(), specmap::Error>(())
    /// ```
    pub fn light_xyz(&self, light: &Spectrum, rule: Rule) -> Result<Xyz> {
        let k = self.k(light, rule)?;
        let [x, y, z] = self.integrate(light, rule)?;
        Ok(Xyz::new(k * x, k * y, k * z))
    }
}

/// CIE XYZ tristimulus values (Y = 100 for the reference white).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Xyz(pub [f64; 3]);

impl From<Vector3<f64>> for Xyz {
    fn from(v: Vector3<f64>) -> Xyz {
        Xyz([v[0], v[1], v[2]])
    }
}

impl Xyz {
    /// XYZ from its three components.
    pub fn new(x: f64, y: f64, z: f64) -> Self {
        Xyz([x, y, z])
    }
    /// The X component.
    pub fn x(&self) -> f64 {
        self.0[0]
    }
    /// The Y component (luminance; 100 for the reference white).
    pub fn y(&self) -> f64 {
        self.0[1]
    }
    /// The Z component.
    pub fn z(&self) -> f64 {
        self.0[2]
    }
    /// CIE 1931 xy chromaticity; (0, 0) for black.
    pub fn xy(&self) -> [f64; 2] {
        let s = self.0.iter().sum::<f64>();
        if s == 0.0 {
            [0.0, 0.0]
        } else {
            [self.0[0] / s, self.0[1] / s]
        }
    }
    /// CIE 1960 UCS uv chromaticity.
    pub fn uv1960(&self) -> [f64; 2] {
        let [x, y, z] = self.0;
        let d = x + 15.0 * y + 3.0 * z;
        if d == 0.0 {
            [0.0, 0.0]
        } else {
            [4.0 * x / d, 6.0 * y / d]
        }
    }
    /// The XYZ with Y = 100 at chromaticity xy.
    pub fn from_xy(xy: [f64; 2]) -> Xyz {
        let [x, y] = xy;
        Xyz::new(100.0 * x / y, 100.0, 100.0 * (1.0 - x - y) / y)
    }
    fn vector(&self) -> Vector3<f64> {
        Vector3::from(self.0)
    }
}

/// An RGB colour space: primaries and white point in CIE 1931 xy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RgbSpace {
    /// Short name, as the CLI takes it (`srgb`, `srgb-paper`, ...).
    pub name: &'static str,
    /// Red, green and blue primaries in CIE 1931 xy.
    pub primaries: [[f64; 2]; 3],
    /// White point (RGB 1, 1, 1) in CIE 1931 xy.
    pub white: [f64; 2],
    /// A published XYZ -> RGB matrix that replaces the one derived from the primaries (the
    /// paper's rounded Eq. 12).
    pub fixed_from_xyz: Option<[[f64; 3]; 3]>,
}

/// CIE D65 as sRGB, Rec.2020 and Display P3 define it.
pub const D65_XY: [f64; 2] = [0.3127, 0.3290];
/// The ACES white (about 6000 K).
pub const ACES_WHITE_XY: [f64; 2] = [0.32168, 0.33767];
/// CIE D50 as ICC's profile connection space defines it.
pub const D50_XY: [f64; 2] = [0.3457, 0.3585];

/// Whites with a name, for reports.
const NAMED_WHITES: [(&str, [f64; 2]); 3] = [
    ("D65", D65_XY),
    ("ACES white", ACES_WHITE_XY),
    ("D50", D50_XY),
];

/// Declared chromaticities within this of a named space's (each coordinate) are that space (see
/// [`Chromaticities::same_as`]).
const SAME_CHROMATICITY: f64 = 5e-5;

/// The primaries and white of an RGB space in CIE 1931 xy, as OpenEXR's `chromaticities`
/// attribute holds them.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Chromaticities {
    /// Red primary in CIE 1931 xy.
    pub red: [f64; 2],
    /// Green primary in CIE 1931 xy.
    pub green: [f64; 2],
    /// Blue primary in CIE 1931 xy.
    pub blue: [f64; 2],
    /// White point in CIE 1931 xy.
    pub white: [f64; 2],
}

impl Chromaticities {
    fn all(&self) -> [[f64; 2]; 4] {
        [self.red, self.green, self.blue, self.white]
    }
    /// Whether these are `other`'s, to 5e-5 in each coordinate (OpenEXR stores them as f32,
    /// and files round the published values differently).
    pub fn same_as(&self, other: &Chromaticities) -> bool {
        self.all()
            .iter()
            .flatten()
            .zip(other.all().iter().flatten())
            .all(|(a, b)| (a - b).abs() <= SAME_CHROMATICITY)
    }
}

impl std::fmt::Display for Chromaticities {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let xy = |p: [f64; 2]| format!("({:.4}, {:.4})", p[0], p[1]);
        write!(
            f,
            "R {} G {} B {} white {}",
            xy(self.red),
            xy(self.green),
            xy(self.blue),
            white_name(self.white)
        )
    }
}

/// A white in words: its name when it has one (to 5e-5), and its xy.
pub fn white_name(xy: [f64; 2]) -> String {
    let coords = format!("x {:.5}, y {:.5}", xy[0], xy[1]);
    match NAMED_WHITES.iter().find(|(_, w)| {
        (w[0] - xy[0]).abs() <= SAME_CHROMATICITY && (w[1] - xy[1]).abs() <= SAME_CHROMATICITY
    }) {
        Some((name, _)) => format!("{name} ({coords})"),
        None => coords,
    }
}

impl RgbSpace {
    /// IEC 61966-2-1 sRGB / Rec.709 primaries, D65; the matrix derived exactly.
    pub const SRGB: RgbSpace = RgbSpace {
        name: "srgb",
        primaries: [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]],
        white: D65_XY,
        fixed_from_xyz: None,
    };
    /// sRGB with the paper's rounded Eq. 12 XYZ -> RGB matrix.
    pub const SRGB_PAPER: RgbSpace = RgbSpace {
        name: "srgb-paper",
        primaries: [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]],
        white: D65_XY,
        fixed_from_xyz: Some([
            [3.2410, -1.5374, -0.4986],
            [-0.9692, 1.8760, 0.0416],
            [0.0556, -0.2040, 1.0570],
        ]),
    };
    /// ITU-R BT.2020.
    pub const REC2020: RgbSpace = RgbSpace {
        name: "rec2020",
        primaries: [[0.708, 0.292], [0.170, 0.797], [0.131, 0.046]],
        white: D65_XY,
        fixed_from_xyz: None,
    };
    /// ACES AP1 (ACEScg), ACES white.
    pub const ACESCG: RgbSpace = RgbSpace {
        name: "acescg",
        primaries: [[0.713, 0.293], [0.165, 0.830], [0.128, 0.044]],
        white: ACES_WHITE_XY,
        fixed_from_xyz: None,
    };
    /// Display P3 (DCI-P3 primaries, D65).
    pub const DISPLAY_P3: RgbSpace = RgbSpace {
        name: "display-p3",
        primaries: [[0.680, 0.320], [0.265, 0.690], [0.150, 0.060]],
        white: D65_XY,
        fixed_from_xyz: None,
    };

    /// The name of a space of declared chromaticities that are no named space's.
    pub const DECLARED: &'static str = "declared";

    /// The space of declared chromaticities (OpenEXR's `chromaticities` attribute): the named
    /// space whose primaries and white they are (to 5e-5), otherwise a space of them named
    /// [`RgbSpace::DECLARED`]. An error when they make no RGB space: a coordinate not finite,
    /// a y not positive, collinear primaries, or a white that is not a positive mix of them.
    pub fn from_chromaticities(c: Chromaticities) -> Result<RgbSpace> {
        if let Some(s) = RgbSpace::ALL
            .into_iter()
            .find(|s| s.chromaticities().same_as(&c))
        {
            return Ok(s);
        }
        let bad = |why: &str| Err(Error::invalid(format!("chromaticities {c}: {why}")));
        if !c.all().iter().flatten().all(|v| v.is_finite()) {
            return bad("a coordinate is not a finite number");
        }
        if !c
            .all()
            .iter()
            .all(|p| p[1] > 0.0 && p[0] >= 0.0 && p[0] + p[1] <= 1.0)
        {
            return bad("a chromaticity lies outside 0 <= x, 0 < y, x + y <= 1");
        }
        let s = RgbSpace {
            name: RgbSpace::DECLARED,
            primaries: [c.red, c.green, c.blue],
            white: c.white,
            fixed_from_xyz: None,
        };
        let col = |xy: [f64; 2]| Vector3::new(xy[0] / xy[1], 1.0, (1.0 - xy[0] - xy[1]) / xy[1]);
        let p = Matrix3::from_columns(&[col(c.red), col(c.green), col(c.blue)]);
        match p.try_inverse().map(|inv| inv * col(c.white)) {
            Some(scale) if p.determinant().abs() > 1e-9 => {
                if scale.iter().all(|&v| v > 0.0) {
                    Ok(s)
                } else {
                    bad("the white is not a positive mix of the primaries")
                }
            }
            _ => bad("the primaries are collinear (they span no colour space)"),
        }
    }

    /// The space's primaries and white.
    pub fn chromaticities(&self) -> Chromaticities {
        Chromaticities {
            red: self.primaries[0],
            green: self.primaries[1],
            blue: self.primaries[2],
            white: self.white,
        }
    }

    /// The white, RGB (1, 1, 1), in words (see [`white_name`]).
    pub fn white_name(&self) -> String {
        white_name(self.white)
    }

    /// Every built-in space.
    pub const ALL: [RgbSpace; 5] = [
        RgbSpace::SRGB,
        RgbSpace::SRGB_PAPER,
        RgbSpace::REC2020,
        RgbSpace::ACESCG,
        RgbSpace::DISPLAY_P3,
    ];

    /// The linear RGB -> XYZ (Y = 1 for white) matrix, from the primaries and white point
    /// (SMPTE RP 177), or the inverse of the fixed matrix where one is given.
    pub fn to_xyz_matrix(&self) -> Matrix3<f64> {
        if let Some(m) = self.fixed_from_xyz {
            return rows(m)
                .try_inverse()
                .expect("published matrices are invertible");
        }
        let col = |xy: [f64; 2]| Vector3::new(xy[0] / xy[1], 1.0, (1.0 - xy[0] - xy[1]) / xy[1]);
        let p = Matrix3::from_columns(&[
            col(self.primaries[0]),
            col(self.primaries[1]),
            col(self.primaries[2]),
        ]);
        let s = p.try_inverse().expect("primaries are not collinear") * col(self.white);
        p * Matrix3::from_diagonal(&s)
    }

    /// The XYZ (Y = 1) -> linear RGB matrix.
    pub fn from_xyz_matrix(&self) -> Matrix3<f64> {
        match self.fixed_from_xyz {
            Some(m) => rows(m),
            None => self
                .to_xyz_matrix()
                .try_inverse()
                .expect("primaries are not collinear"),
        }
    }

    /// Linear RGB (white = 1) of `xyz` (white Y = 100), with no chromatic adaptation.
    pub fn rgb_from_xyz(&self, xyz: Xyz) -> [f64; 3] {
        (self.from_xyz_matrix() * xyz.vector() / 100.0).into()
    }

    /// XYZ (Y = 100 for white) of linear RGB.
    pub fn xyz_from_rgb(&self, rgb: [f64; 3]) -> Xyz {
        Xyz((self.to_xyz_matrix() * Vector3::from(rgb) * 100.0).into())
    }
}

fn rows(m: [[f64; 3]; 3]) -> Matrix3<f64> {
    Matrix3::new(
        m[0][0], m[0][1], m[0][2], m[1][0], m[1][1], m[1][2], m[2][0], m[2][1], m[2][2],
    )
}

/// A von Kries chromatic adaptation transform (the cone-like space it scales in).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cat {
    /// CIECAM02's CAT02.
    Cat02,
    /// Bradford (Lam 1985), without the non-linear blue term.
    Bradford,
}

impl Cat {
    fn matrix(self) -> Matrix3<f64> {
        match self {
            Cat::Cat02 => rows([
                [0.7328, 0.4296, -0.1624],
                [-0.7036, 1.6975, 0.0061],
                [0.0030, 0.0136, 0.9834],
            ]),
            Cat::Bradford => rows([
                [0.8951, 0.2664, -0.1614],
                [-0.7502, 1.7135, 0.0367],
                [0.0389, -0.0685, 1.0296],
            ]),
        }
    }

    /// Adapts `xyz` seen under a source white to how it looks under a destination white.
    pub fn adapt(self, xyz: Xyz, source_white: Xyz, destination_white: Xyz) -> Xyz {
        let m = self.matrix();
        let ls = m * source_white.vector();
        let ld = m * destination_white.vector();
        let d = Matrix3::from_diagonal(&ld.component_div(&ls));
        let inv = m.try_inverse().expect("CAT matrices are invertible");
        Xyz((inv * d * m * xyz.vector()).into())
    }
}

/// IEC 61966-2-1 sRGB transfer: linear -> encoded (odd extension below 0).
pub fn srgb_encode(v: f64) -> f64 {
    if v.abs() <= 0.0031308 {
        12.92 * v
    } else {
        v.signum() * (1.055 * v.abs().powf(1.0 / 2.4) - 0.055)
    }
}

/// IEC 61966-2-1 sRGB transfer: encoded -> linear.
pub fn srgb_decode(v: f64) -> f64 {
    if v.abs() <= 0.04045 {
        v / 12.92
    } else {
        v.signum() * ((v.abs() + 0.055) / 1.055).powf(2.4)
    }
}

/// 8-bit sRGB code values of linear RGB: clipped to [0, 1], encoded, rounded.
pub fn srgb8(linear: [f64; 3]) -> [u8; 3] {
    linear.map(|v| (srgb_encode(v.clamp(0.0, 1.0)) * 255.0).round() as u8)
}

/// CIE 1976 L*a*b*.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Lab(pub [f64; 3]);

impl Lab {
    /// CIELAB of `xyz` relative to the reference white `white` (same scale).
    pub fn from_xyz(xyz: Xyz, white: Xyz) -> Lab {
        const E: f64 = 216.0 / 24389.0;
        const K: f64 = 24389.0 / 27.0;
        let f = |t: f64| {
            if t > E {
                t.cbrt()
            } else {
                (K * t + 16.0) / 116.0
            }
        };
        let fx = f(xyz.x() / white.x());
        let fy = f(xyz.y() / white.y());
        let fz = f(xyz.z() / white.z());
        Lab([116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)])
    }
}

/// CIEDE2000 colour difference (Sharma, Wu and Dalal 2005), kL = kC = kH = 1.
///
/// The first pair of Sharma, Wu and Dalal's test data:
///
/// ```
/// use specmap::colorimetry::{delta_e_2000, Lab};
///
/// let a = Lab([50.0, 2.6772, -79.7751]);
/// let b = Lab([50.0, 0.0, -82.7485]);
/// assert!((delta_e_2000(a, b) - 2.0425).abs() < 1e-4);
/// assert_eq!(delta_e_2000(a, a), 0.0);
/// ```
pub fn delta_e_2000(lab1: Lab, lab2: Lab) -> f64 {
    use std::f64::consts::PI;
    let [l1, a1, b1] = lab1.0;
    let [l2, a2, b2] = lab2.0;
    // sqrt(a^2 + b^2), not hypot: Lab's values are far from overflow, and the fit calls this
    // for every stimulus on every node set it tries.
    let norm = |a: f64, b: f64| (a * a + b * b).sqrt();
    let c1 = norm(a1, b1);
    let c2 = norm(a2, b2);
    let c_bar = (c1 + c2) / 2.0;
    let c7 = c_bar.powi(7);
    let g = 0.5 * (1.0 - (c7 / (c7 + 25f64.powi(7))).sqrt());
    let a1p = (1.0 + g) * a1;
    let a2p = (1.0 + g) * a2;
    let c1p = norm(a1p, b1);
    let c2p = norm(a2p, b2);
    let hue = |b: f64, a: f64| {
        if a == 0.0 && b == 0.0 {
            0.0
        } else {
            let h = b.atan2(a).to_degrees();
            if h < 0.0 {
                h + 360.0
            } else {
                h
            }
        }
    };
    let h1p = hue(b1, a1p);
    let h2p = hue(b2, a2p);
    let dlp = l2 - l1;
    let dcp = c2p - c1p;
    let dhp = if c1p * c2p == 0.0 {
        0.0
    } else if (h2p - h1p).abs() <= 180.0 {
        h2p - h1p
    } else if h2p - h1p > 180.0 {
        h2p - h1p - 360.0
    } else {
        h2p - h1p + 360.0
    };
    let dhp_big = 2.0 * (c1p * c2p).sqrt() * (dhp.to_radians() / 2.0).sin();
    let lp_bar = (l1 + l2) / 2.0;
    let cp_bar = (c1p + c2p) / 2.0;
    let hp_bar = if c1p * c2p == 0.0 {
        h1p + h2p
    } else if (h1p - h2p).abs() <= 180.0 {
        (h1p + h2p) / 2.0
    } else if h1p + h2p < 360.0 {
        (h1p + h2p + 360.0) / 2.0
    } else {
        (h1p + h2p - 360.0) / 2.0
    };
    // cos(k h + phase) for k = 1..4 from one sine and cosine of h, by the angle-sum formulas.
    let (s1, c1h) = hp_bar.to_radians().sin_cos();
    let (s2, c2h) = (2.0 * s1 * c1h, c1h * c1h - s1 * s1);
    let (s3, c3h) = (s2 * c1h + c2h * s1, c2h * c1h - s2 * s1);
    let (s4, c4h) = (2.0 * s2 * c2h, c2h * c2h - s2 * s2);
    // (cos, sin) of the phases 30, 6 and 63 degrees.
    const PHASES: [(f64, f64); 3] = [
        (0.866_025_403_784_438_7, 0.5),
        (0.994_521_895_368_273_3, 0.104_528_463_267_653_47),
        (0.453_990_499_739_546_8, 0.891_006_524_188_367_8),
    ];
    let [(cos30, sin30), (cos6, sin6), (cos63, sin63)] = PHASES;
    let t = 1.0 - 0.17 * (c1h * cos30 + s1 * sin30) + 0.24 * c2h + 0.32 * (c3h * cos6 - s3 * sin6)
        - 0.20 * (c4h * cos63 + s4 * sin63);
    let d_theta = 30.0 * (-((hp_bar - 275.0) / 25.0).powi(2)).exp();
    let cp7 = cp_bar.powi(7);
    let rc = 2.0 * (cp7 / (cp7 + 25f64.powi(7))).sqrt();
    let l50 = (lp_bar - 50.0).powi(2);
    let sl = 1.0 + 0.015 * l50 / (20.0 + l50).sqrt();
    let sc = 1.0 + 0.045 * cp_bar;
    let sh = 1.0 + 0.015 * cp_bar * t;
    let rt = -(2.0 * d_theta * PI / 180.0).sin() * rc;
    let (tl, tc, th) = (dlp / sl, dcp / sc, dhp_big / sh);
    (tl * tl + tc * tc + th * th + rt * tc * th).sqrt()
}

/// Correlated colour temperature and the signed distance from the Planckian locus.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Cct {
    /// Kelvin; None when the colour lies more than 0.05 from the locus in CIE 1960 uv, where CIE
    /// 15 calls a CCT meaningless.
    pub kelvin: Option<f64>,
    /// Distance to the locus in CIE 1960 uv, positive above it (greenish), negative below
    /// (pinkish).
    pub duv: f64,
}

/// Planck's law: spectral radiant exitance (relative) of a black body at `kelvin`.
pub fn planck(wavelength_nm: f64, kelvin: f64) -> f64 {
    const C1: f64 = 3.741_771_852e-16; // 2 pi h c^2, W m^2
    const C2: f64 = 1.438_776_877e-2; // h c / k, m K
    let l = wavelength_nm * 1e-9;
    C1 / (l.powi(5) * ((C2 / (l * kelvin)).exp_m1()))
}

/// CCT by direct search of the Planckian locus (black bodies integrated with the CIE 1931
/// observer at 1 nm over 360-830 nm): the nearest locus point in CIE 1960 uv, found by a
/// logarithmic scan over 1000-100000 K then golden-section refinement to 1e-9 relative.
pub fn cct(xyz: Xyz) -> Result<Cct> {
    let grid = WavelengthGrid::new(360.0, 830.0, 1.0)?;
    let cmfs = Cmfs::new(Observer::Cie1931, &grid)?;
    let target = xyz.uv1960();
    let locus = |t: f64| -> [f64; 2] {
        let s = Spectrum::from_fn(grid, |w| planck(w, t));
        let [x, y, z] = cmfs.integrate(&s, Rule::Riemann).expect("same grid");
        Xyz::new(x, y, z).uv1960()
    };
    let dist = |ln_t: f64| {
        let p = locus(ln_t.exp());
        (p[0] - target[0]).hypot(p[1] - target[1])
    };
    let (lo, hi) = (1000f64.ln(), 100_000f64.ln());
    let steps = 120;
    let best = (0..=steps)
        .map(|i| lo + (hi - lo) * i as f64 / steps as f64)
        .min_by(|a, b| dist(*a).total_cmp(&dist(*b)))
        .expect("non-empty scan");
    let h = (hi - lo) / steps as f64;
    let (mut a, mut b) = ((best - h).max(lo), (best + h).min(hi));
    let g = (5f64.sqrt() - 1.0) / 2.0;
    while b - a > 1e-9 {
        let c = b - g * (b - a);
        let d = a + g * (b - a);
        if dist(c) < dist(d) {
            b = d;
        } else {
            a = c;
        }
    }
    let ln_t = (a + b) / 2.0;
    let p = locus(ln_t.exp());
    let d = (target[0] - p[0]).hypot(target[1] - p[1]);
    let duv = if target[1] >= p[1] { d } else { -d };
    let at_edge = ln_t <= lo + 1e-6 || ln_t >= hi - 1e-6;
    Ok(Cct {
        kelvin: (duv.abs() <= 0.05 && !at_edge).then(|| ln_t.exp()),
        duv,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_matrix_matches_iec_61966() {
        // IEC 61966-2-1 publishes the RGB -> XYZ matrix to 4 decimals.
        let m = RgbSpace::SRGB.to_xyz_matrix();
        let published = [
            [0.4124, 0.3576, 0.1805],
            [0.2126, 0.7152, 0.0722],
            [0.0193, 0.1192, 0.9505],
        ];
        for (r, row) in published.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                assert!(
                    (m[(r, c)] - v).abs() < 1e-4,
                    "({r},{c}) {} vs {v}",
                    m[(r, c)]
                );
            }
        }
        // White maps to white.
        let w = RgbSpace::SRGB.rgb_from_xyz(Xyz::from_xy(D65_XY));
        assert!(w.iter().all(|v| (v - 1.0).abs() < 1e-12), "{w:?}");
        // The paper's rounded matrix is within 1e-3 of the exact inverse.
        let paper = RgbSpace::SRGB_PAPER.from_xyz_matrix();
        let exact = RgbSpace::SRGB.from_xyz_matrix();
        assert!((paper - exact).abs().max() < 1.5e-3);
    }

    #[test]
    fn acescg_matrix_matches_aces_documentation() {
        // ACES TB-2014-004: AP1 RGB -> XYZ.
        let m = RgbSpace::ACESCG.to_xyz_matrix();
        let published = [
            [0.6624541811, 0.1340042065, 0.1561876870],
            [0.2722287168, 0.6740817658, 0.0536895174],
            [-0.0055746495, 0.0040607335, 1.0103391003],
        ];
        for (r, row) in published.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                assert!(
                    (m[(r, c)] - v).abs() < 1e-9,
                    "({r},{c}) {} vs {v}",
                    m[(r, c)]
                );
            }
        }
    }

    #[test]
    fn declared_chromaticities_name_their_space_or_make_one() {
        // f32-rounded, as OpenEXR stores them: the named spaces.
        let f32ed = |s: RgbSpace| {
            let c = s.chromaticities();
            let r = |p: [f64; 2]| p.map(|v| v as f32 as f64);
            Chromaticities {
                red: r(c.red),
                green: r(c.green),
                blue: r(c.blue),
                white: r(c.white),
            }
        };
        for s in [
            RgbSpace::SRGB,
            RgbSpace::ACESCG,
            RgbSpace::REC2020,
            RgbSpace::DISPLAY_P3,
        ] {
            assert_eq!(
                RgbSpace::from_chromaticities(f32ed(s)).unwrap().name,
                s.name
            );
        }
        assert_eq!(
            RgbSpace::ACESCG.white_name(),
            "ACES white (x 0.32168, y 0.33767)"
        );
        // sRGB adapted to D50 by Bradford (the ICC sRGB profile's colorants): the xy of the
        // columns of Lindbloom's published D50 sRGB matrix make a space of its own, whose matrix
        // is that one.
        let d50 = Chromaticities {
            red: [0.648427, 0.330856],
            green: [0.321142, 0.597873],
            blue: [0.155883, 0.066041],
            white: [0.345669, 0.358496],
        };
        let s = RgbSpace::from_chromaticities(d50).unwrap();
        assert_eq!(s.name, RgbSpace::DECLARED);
        assert!(s.white_name().starts_with("D50"), "{}", s.white_name());
        let lindbloom = [
            [0.4360747, 0.3850649, 0.1430804],
            [0.2225045, 0.7168786, 0.0606169],
            [0.0139322, 0.0971045, 0.7141733],
        ];
        let m = s.to_xyz_matrix();
        for (r, row) in lindbloom.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                assert!(
                    (m[(r, c)] - v).abs() < 2e-6,
                    "({r},{c}) {} vs {v}",
                    m[(r, c)]
                );
            }
        }
        // RGB (1,1,1) is the declared white, unadapted.
        let w = s.xyz_from_rgb([1.0; 3]);
        let want = Xyz::from_xy(d50.white);
        assert!((0..3).all(|k| (w.0[k] - want.0[k]).abs() < 1e-9), "{w:?}");
        // What makes no space is refused, saying why.
        let collinear = Chromaticities {
            red: [0.2, 0.2],
            green: [0.3, 0.3],
            blue: [0.4, 0.4],
            white: D65_XY,
        };
        let e = RgbSpace::from_chromaticities(collinear)
            .unwrap_err()
            .to_string();
        assert!(e.contains("collinear"), "{e}");
        let outside = Chromaticities {
            white: [0.05, 0.9],
            ..d50
        };
        let e = RgbSpace::from_chromaticities(outside)
            .unwrap_err()
            .to_string();
        assert!(e.contains("positive mix"), "{e}");
        let nan = Chromaticities {
            red: [f64::NAN, 0.3],
            ..d50
        };
        assert!(RgbSpace::from_chromaticities(nan).is_err());
    }

    #[test]
    fn srgb_transfer_round_trips_and_is_continuous() {
        for i in 0..=1000 {
            let v = i as f64 / 1000.0;
            assert!((srgb_decode(srgb_encode(v)) - v).abs() < 1e-12);
        }
        assert!((srgb_encode(0.0031308) - 12.92 * 0.0031308).abs() < 1e-9);
        assert_eq!(srgb8([1.0, 0.0, 2.0]), [255, 0, 255]);
    }

    #[test]
    fn lab_of_white_and_black() {
        let w = Xyz::from_xy(D65_XY);
        let lab = Lab::from_xyz(w, w);
        assert!((lab.0[0] - 100.0).abs() < 1e-12 && lab.0[1].abs() < 1e-12);
        let lab = Lab::from_xyz(Xyz::new(0.0, 0.0, 0.0), w);
        assert_eq!(lab.0, [0.0, 0.0, 0.0]);
    }

    #[test]
    fn cat_maps_white_to_white() {
        let a = Xyz::from_xy([0.44757, 0.40745]);
        let d65 = Xyz::from_xy(D65_XY);
        for cat in [Cat::Cat02, Cat::Bradford] {
            let out = cat.adapt(a, a, d65);
            for i in 0..3 {
                assert!((out.0[i] - d65.0[i]).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn cct_of_planckian_and_daylight_chromaticities() {
        // Illuminant A is a 2856 K black body (CIE 15: c2 = 1.435e-2 gives 2848 K with the
        // modern c2, hence the tolerance); D65's CCT is about 6504 K.
        let grid = WavelengthGrid::new(360.0, 830.0, 1.0).unwrap();
        let cmfs = Cmfs::new(Observer::Cie1931, &grid).unwrap();
        for t in [1500.0, 2856.0, 4000.0, 6500.0, 12000.0] {
            let s = Spectrum::from_fn(grid, |w| planck(w, t));
            let xyz = cmfs.light_xyz(&s, Rule::Riemann).unwrap();
            let c = cct(xyz).unwrap();
            let k = c.kelvin.unwrap();
            assert!((k - t).abs() / t < 1e-6, "{t}: {k}");
            assert!(c.duv.abs() < 1e-9);
        }
        let d65 = cct(Xyz::from_xy([0.31271, 0.32902])).unwrap();
        assert!((d65.kelvin.unwrap() - 6504.0).abs() < 3.0, "{d65:?}");
        assert!(d65.duv > 0.0);
        // A saturated red is far from the locus.
        assert!(cct(Xyz::new(40.0, 20.0, 2.0)).unwrap().kelvin.is_none());
    }

    #[test]
    fn the_observer_sees_nothing_outside_its_tables() {
        // Beyond 360-830 nm the CMFs are 0, not their end values held: widening the range adds
        // nothing, and a range wholly outside has no visible energy (a clear error).
        let wide = Cmfs::new(Observer::Cie1931, &"300:900:5".parse().unwrap()).unwrap();
        for (l, v) in wide.grid().wavelengths_nm().zip(wide.x.values()) {
            if !(360.0..=830.0).contains(&l) {
                assert_eq!(*v, 0.0, "{l} nm");
            }
        }
        let d65 = crate::data::spectrum("D65").unwrap().data;
        let xyz = |g: &str| {
            let grid: WavelengthGrid = g.parse().unwrap();
            let c = Cmfs::new(Observer::Cie1931, &grid).unwrap();
            let s = d65.resample(&grid, Interpolation::Linear);
            c.integrate(&s, Rule::Riemann).unwrap()
        };
        let (a, b) = (xyz("300:900:5"), xyz("360:830:5"));
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() <= 1e-12 * b[k].abs(), "{a:?} vs {b:?}");
        }
        let uv = Cmfs::new(Observer::Cie1931, &"100:200:10".parse().unwrap()).unwrap();
        let s = d65.resample(uv.grid(), Interpolation::Linear);
        assert!(uv.k(&s, Rule::Riemann).is_err());
    }
}
