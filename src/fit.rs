//! Basis fitting: the paper's per-light weights w_R, w_G, w_B (closed form and argmin), the exact
//! mode, and the RGB -> SPD -> RGB round trip every mode is judged by.
//!
//! Paper section 4: `SPD(R,G,B) = (R wR MCC_R + G wG MCC_G + B wB MCC_B) SPD_mls`, with the weights
//! chosen so that SPD(1,1,1) has the RGB of the main light. Everything is linear: with
//! `c_j = RGB(MCC_j * SPD_mls)` (Eq. 10/11, k from the main light) and `C = [c_R c_G c_B]`, the
//! RGB of `SPD(rgb)` is `C diag(w) rgb`, so the paper's objective `|RGB(SPD(1,1,1)) - RGB_mls|` is
//! the 3x3 linear system `C w = RGB_mls`.
//!
//! The modes differ in the coefficient matrix `W` (coefficients `a = W rgb`, SPD = sum_j a_j B_j
//! with `B_j = MCC_j * SPD_mls`):
//! - `paper`: `W = diag(w)`; exact for white only;
//! - `exact`: `W = C^-1 diag(RGB_mls)`; the round trip returns every input, but the SPD of a
//!   saturated colour may go negative.
//! - `nonneg`: the exact coefficients where their SPD is non-negative; elsewhere the coefficients
//!   of least CIEDE2000 error among those whose SPD is non-negative. Those form a convex cone K;
//!   the optimum lies on its boundary, which is parameterised exactly (rays from an interior point,
//!   the grey of the same luminance, cut by a ratio test) and searched by Nelder-Mead in 2-D.
//!
//! A near-monochromatic light (low-pressure sodium) gives the three basis spectra nearly one
//! colour, and C is singular. Then the fit is reduced: it is solved by truncated SVD within the
//! colour directions the light can still carry, `regularized` is set, and `lost_information`
//! says in words what cannot survive.

use crate::colorimetry::{delta_e_2000, Cmfs, Lab, Observer, RgbSpace};
use crate::error::{Error, Result};
use crate::spectrum::{Rule, Spectrum, WavelengthGrid};
use nalgebra::{Matrix3, Vector3};

/// A colour direction whose singular value in C is below 1/CONDITION_LIMIT of the largest needs
/// basis coefficients over CONDITION_LIMIT times those of white, cancelling one another: it is
/// treated as lost, and the fit is reduced to the directions that remain. (Under low-pressure
/// sodium the second singular value is 0.2% of the first; under high-pressure sodium, the worst
/// of the usual lights, the smallest is 5%.)
pub const CONDITION_LIMIT: f64 = 100.0;

/// How RGB becomes a spectrum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// The paper's three weights.
    Paper,
    /// A full 3x3 matrix: the round trip is exact for every colour.
    Exact,
    /// Exact where the exact SPD is non-negative; elsewhere the non-negative SPD of least
    /// CIEDE2000 error (a small constrained solve per colour).
    Nonneg,
}

/// What a fit starts from: the main light and the three basis reflectances, on one grid.
#[derive(Debug, Clone)]
pub struct FitInput {
    /// How the main light was named (for messages and the fit file).
    pub light_label: String,
    /// The main light's SPD, on the grid every spectrum here shares.
    pub light: Spectrum,
    /// How each basis reflectance was named, in R, G, B order.
    pub basis_labels: [String; 3],
    /// The basis reflectances MCC_R, MCC_G, MCC_B on the light's grid.
    pub basis: [Spectrum; 3],
    /// The colour-matching functions RGB is computed with.
    pub observer: Observer,
    /// The integration rule over the grid.
    pub rule: Rule,
    /// The RGB space the input colours are in.
    pub space: RgbSpace,
}

/// The argmin solution of the same objective, and how far it is from the closed form.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct ArgminCheck {
    /// The weights w_R, w_G, w_B that argmin found.
    pub weights: [f64; 3],
    /// Iterations argmin took.
    pub iterations: u64,
    /// Largest absolute difference between the argmin and closed-form weights.
    pub max_abs_difference: f64,
}

/// A solved fit: everything `convert` and `render` need to turn RGB into spectra.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Fit {
    /// File format version of the serialised fit.
    pub version: u32,
    /// How RGB becomes a spectrum.
    pub mode: Mode,
    /// Name of the main light, as given.
    pub light: String,
    /// Names of the basis reflectances, in R, G, B order.
    pub basis: [String; 3],
    /// The wavelengths every spectrum of the fit is on.
    pub grid: WavelengthGrid,
    /// The colour-matching functions the fit was solved with.
    pub observer: Observer,
    /// The integration rule over `grid`.
    pub rule: Rule,
    /// Name of the RGB space (or "declared", see `chromaticities`).
    pub space: String,
    /// The primaries and white of a space without a name (`space` is "declared": the input
    /// file's own chromaticities); absent for the named spaces.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chromaticities: Option<crate::colorimetry::Chromaticities>,
    /// The paper's w_R, w_G, w_B.
    pub weights: [f64; 3],
    /// Coefficients a = W rgb (row-major): diag(weights) in paper mode.
    pub matrix: [[f64; 3]; 3],
    /// Linear RGB of the main light (Y = 1).
    pub light_rgb: [f64; 3],
    /// RGB of each basis spectrum MCC_j * light (the columns of C).
    pub basis_rgb: [[f64; 3]; 3],
    /// 2-norm condition number of C.
    pub condition_number: f64,
    /// True when C was too ill-conditioned to invert: the reduced (truncated-SVD) solution is used,
    /// within the colour directions the light can carry.
    pub regularized: bool,
    /// In plain words, the colour information that cannot survive under this light (None when
    /// all of it does).
    pub lost_information: Option<String>,
    /// The same weights found by argmin, as a check on the closed form.
    pub argmin: ArgminCheck,
    /// The main light's SPD on `grid`.
    pub light_spd: Vec<f64>,
    /// The basis reflectances MCC_j on `grid`.
    pub basis_reflectance: [Vec<f64>; 3],
}

/// The fit file format version this build writes and reads.
pub const FIT_VERSION: u32 = 1;

/// The paper's basis: the ColorChecker's red, green and blue patches.
pub const PAPER_BASIS: [&str; 3] = [
    "colorchecker:red",
    "colorchecker:green",
    "colorchecker:blue",
];

impl FitInput {
    /// Resolves a light and three basis reflectances by name (a table, `TABLE:COLUMN` or a CSV
    /// path) and puts them on `grid`: the light interpolated linearly, the reflectances by
    /// CIE 167 (see [`crate::spectrum`]).
    pub fn from_names(
        light: &str,
        basis: [&str; 3],
        grid: &WavelengthGrid,
        observer: Observer,
        rule: Rule,
        space: RgbSpace,
    ) -> Result<FitInput> {
        let light = crate::data::spectrum(light)?;
        let [b0, b1, b2] = basis.map(crate::data::spectrum);
        let basis = [b0?, b1?, b2?];
        Ok(FitInput {
            light_label: light.label,
            light: light
                .data
                .resample(grid, crate::spectrum::Interpolation::LIGHT),
            basis_labels: basis.each_ref().map(|b| b.label.clone()),
            basis: basis.each_ref().map(|b| {
                b.data
                    .resample(grid, crate::spectrum::Interpolation::SMOOTH)
            }),
            observer,
            rule,
            space,
        })
    }

    fn check(&self) -> Result<()> {
        let grid = self.light.grid();
        for (l, b) in self.basis_labels.iter().zip(&self.basis) {
            if b.grid() != grid {
                return Err(Error::invalid(format!(
                    "basis {l} is not on the light's grid"
                )));
            }
        }
        if let Some((i, v)) = self
            .light
            .values()
            .iter()
            .enumerate()
            .find(|(_, v)| **v < 0.0)
        {
            return Err(Error::invalid(format!(
                "light {} is negative ({v:e}) at {} nm: a light's power cannot be negative",
                self.light_label,
                grid.wavelength_nm(i)
            )));
        }
        // Linear dependence of the basis spectra themselves (independent of the light): the
        // Gram matrix of the three reflectances.
        let g = Matrix3::from_fn(|i, j| {
            self.basis[i]
                .values()
                .iter()
                .zip(self.basis[j].values())
                .map(|(a, b)| a * b)
                .sum::<f64>()
        });
        let sv = g.singular_values();
        let (max, min) = (sv.max(), sv.min());
        if max.is_nan() || max <= 0.0 || min <= max * 1e-12 {
            return Err(Error::invalid(format!(
                "the basis spectra {} are linearly dependent: one is a combination of the others, \
                 so they cannot carry three colour channels",
                self.basis_labels.join(", ")
            )));
        }
        Ok(())
    }
}

/// The paper's objective as a linear system `C w = t`, with the space it is solved in.
#[derive(Debug, Clone)]
pub struct LinearSystem {
    /// Column j: linear RGB of basis spectrum j under the light (Eq. 10/11).
    pub c: Matrix3<f64>,
    /// The light's linear RGB.
    pub t: Vector3<f64>,
    space: nalgebra::DMatrix<f64>,
    reduced: bool,
}

impl LinearSystem {
    /// Checks the input and builds C and t.
    pub fn new(input: &FitInput) -> Result<LinearSystem> {
        input.check()?;
        let cmfs = Cmfs::new(input.observer, input.light.grid())?;
        let (c, t) = basis_colours(input, &cmfs)?;
        let (space, reduced) = solution_space(&c);
        Ok(LinearSystem {
            c,
            t,
            space,
            reduced,
        })
    }
    /// The weights in closed form.
    pub fn closed_form(&self) -> Result<[f64; 3]> {
        Ok(solve_closed(&self.c, &self.t, &self.space)?.into())
    }
    /// The weights by argmin, and its iteration count.
    pub fn argmin(&self) -> Result<([f64; 3], u64)> {
        solve_argmin(&self.c, &self.t, &self.space)
    }
}

/// The RGB of each basis spectrum (columns of C) and of the light, with k from the light.
fn basis_colours(input: &FitInput, cmfs: &Cmfs) -> Result<(Matrix3<f64>, Vector3<f64>)> {
    let mut c = Matrix3::zeros();
    for (j, b) in input.basis.iter().enumerate() {
        let xyz = cmfs.reflectance_xyz(b, &input.light, input.rule)?;
        c.set_column(j, &Vector3::from(input.space.rgb_from_xyz(xyz)));
    }
    let t = Vector3::from(
        input
            .space
            .rgb_from_xyz(cmfs.light_xyz(&input.light, input.rule)?),
    );
    Ok((c, t))
}

/// 2-norm condition number, finite even for a singular matrix.
fn condition_number(m: &Matrix3<f64>) -> f64 {
    let sv = m.singular_values();
    let max = sv.max();
    max / sv.min().max(max * 1e-16)
}

/// The solution space: all of R^3 when C is well conditioned, else the span of the right
/// singular vectors whose singular values are within [`CONDITION_LIMIT`] of the largest (the
/// colour directions the light can still carry). Columns are an orthonormal basis.
fn solution_space(c: &Matrix3<f64>) -> (nalgebra::DMatrix<f64>, bool) {
    let svd = c.svd(false, true);
    let v_t = svd.v_t.expect("requested");
    let sv = svd.singular_values;
    let max = sv.max();
    let keep: Vec<usize> = (0..3).filter(|&i| sv[i] * CONDITION_LIMIT >= max).collect();
    let reduced = keep.len() < 3;
    let basis = if reduced {
        nalgebra::DMatrix::from_fn(3, keep.len(), |r, k| v_t[(keep[k], r)])
    } else {
        nalgebra::DMatrix::identity(3, 3)
    };
    (basis, reduced)
}

/// Closed form: the least-squares solution of C w = t within the solution space V
/// (w = V (C V)^+ t; the plain inverse when V is all of R^3).
fn solve_closed(
    c: &Matrix3<f64>,
    t: &Vector3<f64>,
    v: &nalgebra::DMatrix<f64>,
) -> Result<Vector3<f64>> {
    let cd = nalgebra::DMatrix::from_fn(3, 3, |r, k| c[(r, k)]);
    let a = &cd * v; // 3 x k
    let td = nalgebra::DVector::from_column_slice(t.as_slice());
    let z = (a.transpose() * &a)
        .lu()
        .solve(&(a.transpose() * td))
        .ok_or_else(|| Error::invalid("the fit's normal equations are singular"))?;
    let w = v * z;
    Ok(Vector3::new(w[0], w[1], w[2]))
}

/// The same objective, min |C V z - t|^2, solved numerically by argmin (L-BFGS with
/// More-Thuente line search) from z = V^T (1,1,1).
fn solve_argmin(
    c: &Matrix3<f64>,
    t: &Vector3<f64>,
    v: &nalgebra::DMatrix<f64>,
) -> Result<([f64; 3], u64)> {
    use argmin::core::{CostFunction, Executor, Gradient, State};
    use argmin::solver::linesearch::MoreThuenteLineSearch;
    use argmin::solver::quasinewton::LBFGS;

    struct Objective {
        a: nalgebra::DMatrix<f64>,
        t: nalgebra::DVector<f64>,
    }
    impl Objective {
        fn residual(&self, z: &[f64]) -> nalgebra::DVector<f64> {
            &self.a * nalgebra::DVector::from_column_slice(z) - &self.t
        }
    }
    impl CostFunction for Objective {
        type Param = Vec<f64>;
        type Output = f64;
        fn cost(&self, z: &Vec<f64>) -> std::result::Result<f64, argmin::core::Error> {
            Ok(self.residual(z).norm_squared())
        }
    }
    impl Gradient for Objective {
        type Param = Vec<f64>;
        type Gradient = Vec<f64>;
        fn gradient(&self, z: &Vec<f64>) -> std::result::Result<Vec<f64>, argmin::core::Error> {
            Ok((2.0 * self.a.transpose() * self.residual(z))
                .as_slice()
                .to_vec())
        }
    }
    let err = |e: argmin::core::Error| Error::invalid(format!("argmin failed: {e}"));
    let cd = nalgebra::DMatrix::from_fn(3, 3, |r, k| c[(r, k)]);
    let objective = Objective {
        a: &cd * v,
        t: nalgebra::DVector::from_column_slice(t.as_slice()),
    };
    let z0 = (v.transpose() * nalgebra::DVector::from_element(3, 1.0))
        .as_slice()
        .to_vec();
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), 7)
        .with_tolerance_grad(1e-15)
        .map_err(err)?
        .with_tolerance_cost(0.0)
        .map_err(err)?;
    let res = Executor::new(objective, solver)
        .configure(|s| s.param(z0).max_iters(500))
        .run()
        .map_err(err)?;
    let state = res.state();
    let z = state
        .get_best_param()
        .ok_or_else(|| Error::invalid("argmin returned no solution"))?;
    let w = v * nalgebra::DVector::from_column_slice(z);
    Ok(([w[0], w[1], w[2]], state.get_iter()))
}

/// Plain words for the colour directions C cannot produce (singular values below the limit).
fn lost_information(c: &Matrix3<f64>, light: &str) -> Option<String> {
    let svd = c.svd(true, false);
    let u = svd.u.expect("requested");
    let sv = svd.singular_values;
    let max = sv.max();
    let lost: Vec<usize> = (0..3).filter(|&i| sv[i] * CONDITION_LIMIT < max).collect();
    match lost.len() {
        0 => None,
        1 => {
            let dir = u.column(lost[0]);
            let side = |sign: f64| -> Option<&'static str> {
                let chans: Vec<usize> = (0..3).filter(|&i| dir[i] * sign > 0.3).collect();
                match chans.as_slice() {
                    [0] => Some("red"),
                    [1] => Some("green"),
                    [2] => Some("blue"),
                    [0, 1] => Some("yellow"),
                    [1, 2] => Some("cyan"),
                    [0, 2] => Some("magenta"),
                    _ => None,
                }
            };
            let complement = |c: &str| match c {
                "red" => "cyan",
                "green" => "magenta",
                "blue" => "yellow",
                "yellow" => "blue",
                "cyan" => "red",
                _ => "green",
            };
            let (a, b) = match (side(1.0), side(-1.0)) {
                (Some(a), Some(b)) => (a, b),
                (Some(a), None) | (None, Some(a)) => (a, complement(a)),
                (None, None) => ("one hue", "its opposite"),
            };
            Some(format!(
                "Under {light} the basis colours span only two dimensions: the {a}-{b} axis is \
                 lost, so colours that differ only along it (at equal brightness) come out alike."
            ))
        }
        _ => Some(format!(
            "Under {light} the three basis spectra have nearly the same colour: only brightness \
             survives. Hue and saturation are lost; every colour renders as a shade of the light's \
             own colour."
        )),
    }
}

/// Fits the basis weights (and the mode's coefficient matrix) for one light.
///
/// In the paper's mode RGB (1, 1, 1) comes back as itself (the weights are chosen for it); in
/// the exact mode every colour does:
///
/// ```
/// use specmap::colorimetry::{Observer, RgbSpace};
/// use specmap::fit::{fit, FitInput, Mode, Upsampler, PAPER_BASIS};
/// use specmap::spectrum::{Rule, WavelengthGrid};
///
/// let grid = WavelengthGrid::visible_1nm();
/// let space = RgbSpace::SRGB;
/// let (observer, rule) = (Observer::Cie1931, Rule::Riemann);
/// let input = FitInput::from_names("A", PAPER_BASIS, &grid, observer, rule, space)?;
///
/// let paper = fit(&input, Mode::Paper)?;
/// let up = Upsampler::new(&paper, &space);
/// let white = up.rendered_rgb(up.coefficients([1.0, 1.0, 1.0]));
/// assert!(white.iter().all(|v| (v - 1.0).abs() < 1e-9), "{white:?}");
///
/// let exact = fit(&input, Mode::Exact)?;
/// let up = Upsampler::new(&exact, &space);
/// let orange = [0.8, 0.4, 0.1];
/// assert!(up.round_trip_error(orange, up.coefficients(orange)) < 1e-6);
/// assert_eq!(up.spd(orange).len(), grid.len());
/// # Ok::<(), specmap::Error>(())
/// ```
pub fn fit(input: &FitInput, mode: Mode) -> Result<Fit> {
    let grid = *input.light.grid();
    let system = LinearSystem::new(input)?;
    let (c, t, space, regularized) = (system.c, system.t, &system.space, system.reduced);
    let cond = condition_number(&c);
    let w = Vector3::from(system.closed_form()?);
    let (w_argmin, iterations) = system.argmin()?;
    let max_abs_difference = (0..3)
        .map(|i| (w[i] - w_argmin[i]).abs())
        .fold(0.0, f64::max);
    // The exact mode's W = C^+ diag(t): column j solves C w_j = t_j e_j in the solution space.
    let matrix = match mode {
        Mode::Paper => Matrix3::from_diagonal(&w),
        Mode::Exact | Mode::Nonneg => {
            let mut m = Matrix3::zeros();
            for j in 0..3 {
                let mut e = Vector3::zeros();
                e[j] = t[j];
                m.set_column(j, &solve_closed(&c, &e, space)?);
            }
            m
        }
    };
    let to_rows = |m: &Matrix3<f64>| -> [[f64; 3]; 3] {
        [0, 1, 2].map(|r| [m[(r, 0)], m[(r, 1)], m[(r, 2)]])
    };
    let fit = Fit {
        version: FIT_VERSION,
        mode,
        light: input.light_label.clone(),
        basis: input.basis_labels.clone(),
        grid,
        observer: input.observer,
        rule: input.rule,
        space: input.space.name.to_string(),
        chromaticities: (input.space.name == RgbSpace::DECLARED)
            .then(|| input.space.chromaticities()),
        weights: w.into(),
        matrix: to_rows(&matrix),
        light_rgb: t.into(),
        basis_rgb: to_rows(&c.transpose()),
        condition_number: cond,
        regularized,
        lost_information: if regularized {
            lost_information(&c, &input.light_label)
        } else {
            None
        },
        argmin: ArgminCheck {
            weights: w_argmin,
            iterations,
            max_abs_difference,
        },
        light_spd: input.light.values().to_vec(),
        basis_reflectance: input.basis.clone().map(|b| b.values().to_vec()),
    };
    if !fit.is_finite() {
        return Err(Error::invalid(format!(
            "the fit for {} produced non-finite numbers",
            input.light_label
        )));
    }
    Ok(fit)
}

impl Fit {
    /// Reads a fit written by `specmap fit -o`, checking its version and consistency.
    pub fn load(path: &std::path::Path) -> Result<Fit> {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let parse_err = |message: String| Error::Parse {
            file: path.to_path_buf(),
            line: None,
            message,
        };
        let value: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| parse_err(format!("not a fit file (invalid JSON: {e})")))?;
        match value.get("version").and_then(|v| v.as_u64()) {
            Some(v) if v == FIT_VERSION as u64 => {}
            Some(v) => {
                return Err(parse_err(format!(
                    "fit file version {v}; this specmap reads version {FIT_VERSION}"
                )))
            }
            None => return Err(parse_err("not a fit file (no \"version\")".into())),
        }
        let fit: Fit = serde_json::from_value(value)
            .map_err(|e| parse_err(format!("malformed fit file: {e}")))?;
        let n = fit.grid.len();
        if fit.light_spd.len() != n || fit.basis_reflectance.iter().any(|b| b.len() != n) {
            return Err(parse_err(format!(
                "the spectra do not match the grid {} ({n} samples)",
                fit.grid
            )));
        }
        if !fit.is_finite() {
            return Err(parse_err("the fit holds non-finite numbers".into()));
        }
        match (fit.space.as_str(), fit.chromaticities) {
            (RgbSpace::DECLARED, Some(c)) => {
                RgbSpace::from_chromaticities(c).map_err(|e| parse_err(e.to_string()))?;
            }
            (RgbSpace::DECLARED, None) => {
                return Err(parse_err(
                    "the space is \"declared\" but the fit has no \"chromaticities\"".into(),
                ))
            }
            (name, _) if RgbSpace::ALL.iter().all(|s| s.name != name) => {
                return Err(parse_err(format!("unknown colour space '{name}'")));
            }
            _ => {}
        }
        Ok(fit)
    }

    /// The colour space the fit was solved in.
    pub fn rgb_space(&self) -> RgbSpace {
        if let Some(c) = self
            .chromaticities
            .filter(|_| self.space == RgbSpace::DECLARED)
        {
            if let Ok(s) = RgbSpace::from_chromaticities(c) {
                return s;
            }
        }
        RgbSpace::ALL
            .into_iter()
            .find(|s| s.name == self.space)
            .unwrap_or(RgbSpace::SRGB)
    }

    fn is_finite(&self) -> bool {
        self.weights
            .iter()
            .chain(self.matrix.iter().flatten())
            .chain(self.light_rgb.iter())
            .chain(std::iter::once(&self.condition_number))
            .all(|v| v.is_finite())
    }

    fn w(&self) -> Matrix3<f64> {
        let m = self.matrix;
        Matrix3::from_fn(|r, c| m[r][c])
    }

    /// C: column j is the RGB of basis spectrum j.
    fn c(&self) -> Matrix3<f64> {
        let b = self.basis_rgb;
        Matrix3::from_fn(|r, c| b[c][r])
    }

    /// The basis spectra B_j = w_j MCC_j SPD_mls (paper mode's scaling), for plots.
    pub fn weighted_basis(&self) -> [Vec<f64>; 3] {
        [0, 1, 2].map(|j| {
            self.light_spd
                .iter()
                .zip(&self.basis_reflectance[j])
                .map(|(s, r)| self.weights[j] * s * r)
                .collect()
        })
    }
}

/// Round-trip statistics over an RGB grid.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct RoundTrip {
    /// Colours in the grid: n^3 less black.
    pub colours: usize,
    /// Mean CIEDE2000 over the colours.
    #[serde(rename = "mean_dE2000")]
    pub mean_de2000: f64,
    /// Nearest-rank 95th percentile.
    #[serde(rename = "p95_dE2000")]
    pub p95_de2000: f64,
    /// Largest CIEDE2000 over the colours.
    #[serde(rename = "max_dE2000")]
    pub max_de2000: f64,
    /// Share of the colours whose SPD goes negative at some wavelength.
    pub negative_fraction: f64,
}

/// Turns linear RGB into basis coefficients and spectra for one fit: the per-pixel engine.
#[derive(Debug, Clone)]
pub struct Upsampler {
    mode: Mode,
    c: Matrix3<f64>,
    w: Matrix3<f64>,
    t: Vector3<f64>,
    rgb_to_xyz: Matrix3<f64>,
    white: crate::colorimetry::Xyz,
    space: RgbSpace,
    /// The basis reflectances at the wavelengths where the light has power.
    lit_basis: Vec<Vector3<f64>>,
    light_spd: Vec<f64>,
    basis_reflectance: [Vec<f64>; 3],
}

impl Upsampler {
    /// `space` must be the space the fit was solved in.
    pub fn new(fit: &Fit, space: &RgbSpace) -> Upsampler {
        let lit_basis = (0..fit.light_spd.len())
            .filter(|&i| fit.light_spd[i] > 0.0)
            .map(|i| {
                Vector3::new(
                    fit.basis_reflectance[0][i],
                    fit.basis_reflectance[1][i],
                    fit.basis_reflectance[2][i],
                )
            })
            .collect();
        Upsampler {
            mode: fit.mode,
            c: fit.c(),
            w: fit.w(),
            t: Vector3::from(fit.light_rgb),
            rgb_to_xyz: space.to_xyz_matrix(),
            white: space.xyz_from_rgb([1.0, 1.0, 1.0]),
            space: *space,
            lit_basis,
            light_spd: fit.light_spd.clone(),
            basis_reflectance: fit.basis_reflectance.clone(),
        }
    }

    /// The coefficients of the three basis spectra for a linear RGB pixel.
    pub fn coefficients(&self, rgb: [f64; 3]) -> [f64; 3] {
        let a = self.w * Vector3::from(rgb);
        if self.mode != Mode::Nonneg || self.is_nonnegative(&a) {
            return a.into();
        }
        self.nonneg(Vector3::from(rgb), a).into()
    }

    /// The SPD of a linear RGB pixel on the fit's grid.
    pub fn spd(&self, rgb: [f64; 3]) -> Vec<f64> {
        let a = self.coefficients(rgb);
        (0..self.light_spd.len())
            .map(|i| {
                self.light_spd[i]
                    * (a[0] * self.basis_reflectance[0][i]
                        + a[1] * self.basis_reflectance[1][i]
                        + a[2] * self.basis_reflectance[2][i])
            })
            .collect()
    }

    /// Linear RGB of the SPD with coefficients `a`, white-balanced to the main light.
    pub fn rendered_rgb(&self, a: [f64; 3]) -> [f64; 3] {
        (self.c * Vector3::from(a)).component_div(&self.t).into()
    }

    /// CIEDE2000 between the input and its round trip through coefficients `a`.
    pub fn round_trip_error(&self, rgb: [f64; 3], a: [f64; 3]) -> f64 {
        let lab_in = Lab::from_xyz(self.space.xyz_from_rgb(rgb), self.white);
        let lab_out = Lab::from_xyz(self.space.xyz_from_rgb(self.rendered_rgb(a)), self.white);
        delta_e_2000(lab_in, lab_out)
    }

    /// Whether the SPD with coefficients `a` is non-negative wherever the light shines.
    pub fn is_nonnegative(&self, a: &Vector3<f64>) -> bool {
        let tol = -1e-12 * a.abs().max();
        self.lit_basis.iter().all(|m| m.dot(a) >= tol)
    }

    /// The `nonneg` search's interior point for a pixel: the grey of the same luminance (the
    /// paper weights, scaled), or equal positive coefficients if the basis makes that grey's SPD
    /// negative. None for a pixel of no (or negative) luminance, which becomes black.
    fn interior_point(&self, rgb: &Vector3<f64>) -> Option<Vector3<f64>> {
        let y = (self.rgb_to_xyz.row(1) * rgb)[0];
        if y.is_nan() || y <= 0.0 {
            return None;
        }
        let grey = self.w * Vector3::repeat(y);
        Some(if self.lit_basis.iter().all(|m| m.dot(&grey) > 0.0) {
            grey
        } else {
            Vector3::repeat(y)
        })
    }

    /// The non-negative coefficients of least CIEDE2000 error (see the module docs).
    fn nonneg(&self, rgb: Vector3<f64>, exact: Vector3<f64>) -> Vector3<f64> {
        use argmin::core::{CostFunction, Executor, State};
        use argmin::solver::neldermead::NelderMead;

        let Some(p) = self.interior_point(&rgb) else {
            return Vector3::zeros();
        };
        let e0 = (exact - p).normalize();
        let helper = if e0.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let e1 = e0.cross(&helper).normalize();
        let e2 = e0.cross(&e1);
        let reach = 2.0 * (exact - p).norm();
        let lab_in = Lab::from_xyz(self.space.xyz_from_rgb(rgb.into()), self.white);

        #[derive(Clone)]
        struct Boundary<'a> {
            up: &'a Upsampler,
            p: Vector3<f64>,
            frame: [Vector3<f64>; 3],
            reach: f64,
            lab_in: Lab,
        }
        impl Boundary<'_> {
            /// Where the ray from p along e0 + u e1 + v e2 leaves the cone (ratio test).
            fn point(&self, uv: &[f64]) -> Vector3<f64> {
                let d = self.frame[0] + uv[0] * self.frame[1] + uv[1] * self.frame[2];
                let d = d / d.norm();
                let s = self
                    .up
                    .lit_basis
                    .iter()
                    .filter_map(|m| {
                        let md = m.dot(&d);
                        (md < 0.0).then(|| m.dot(&self.p) / -md)
                    })
                    .fold(self.reach, f64::min);
                self.p + s * d
            }
        }
        impl CostFunction for Boundary<'_> {
            type Param = Vec<f64>;
            type Output = f64;
            fn cost(&self, uv: &Vec<f64>) -> std::result::Result<f64, argmin::core::Error> {
                let a = self.point(uv);
                let xyz = self.up.space.xyz_from_rgb(self.up.rendered_rgb(a.into()));
                Ok(delta_e_2000(self.lab_in, Lab::from_xyz(xyz, self.up.white)))
            }
        }
        let problem = Boundary {
            up: self,
            p,
            frame: [e0, e1, e2],
            reach,
            lab_in,
        };
        let start = problem.point(&[0.0, 0.0]);
        let solver = NelderMead::new(vec![vec![0.0, 0.0], vec![0.3, 0.0], vec![0.0, 0.3]])
            .with_sd_tolerance(1e-10);
        let best = solver
            .ok()
            .and_then(|solver| {
                Executor::new(problem.clone(), solver)
                    .configure(|s| s.max_iters(400))
                    .run()
                    .ok()
            })
            .and_then(|res| res.state().get_best_param().map(|uv| problem.point(uv)));
        match best {
            Some(a) if self.is_nonnegative(&a) => a,
            _ => start,
        }
    }
}

/// The round trip, defined once: linear RGB on an n^3 grid of `[0,1]^3` without black -> SPD ->
/// XYZ (k from the main light, Eq. 11) -> linear RGB -> divided by the main light's RGB (the white
/// balance the paper's objective implies) -> CIELAB (the space's white) -> CIEDE2000 against the
/// input.
pub fn round_trip(fit: &Fit, n: usize, space: &RgbSpace) -> RoundTrip {
    let up = Upsampler::new(fit, space);
    let mut des = Vec::with_capacity(n * n * n);
    let mut negative = 0usize;
    let step = 1.0 / (n - 1) as f64;
    for r in 0..n {
        for g in 0..n {
            for b in 0..n {
                if r + g + b == 0 {
                    continue;
                }
                let rgb = [r as f64 * step, g as f64 * step, b as f64 * step];
                let a = up.coefficients(rgb);
                negative += !up.is_nonnegative(&Vector3::from(a)) as usize;
                des.push(up.round_trip_error(rgb, a));
            }
        }
    }
    des.sort_by(f64::total_cmp);
    let count = des.len();
    RoundTrip {
        colours: count,
        mean_de2000: des.iter().sum::<f64>() / count as f64,
        p95_de2000: des[((count as f64 * 0.95).ceil() as usize).min(count) - 1],
        max_de2000: des[count - 1],
        negative_fraction: negative as f64 / count as f64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn input(light: &str) -> FitInput {
        FitInput::from_names(
            light,
            PAPER_BASIS,
            &WavelengthGrid::visible_1nm(),
            Observer::Cie1931,
            Rule::Riemann,
            RgbSpace::SRGB,
        )
        .unwrap()
    }

    #[test]
    fn paper_weights_make_white_the_light_and_argmin_agrees() {
        for light in ["D65", "A", "FL2", "FL11", "LED-B3"] {
            let f = fit(&input(light), Mode::Paper).unwrap();
            assert!(!f.regularized, "{light}: cond {}", f.condition_number);
            assert!(
                f.argmin.max_abs_difference < 1e-8,
                "{light}: {:?}",
                f.argmin
            );
            // RGB(SPD(1,1,1)) = RGB of the light: C w = t.
            let c = f.c();
            let out = c * Vector3::from(f.weights);
            for i in 0..3 {
                assert!((out[i] - f.light_rgb[i]).abs() < 1e-12, "{light}");
            }
        }
    }

    #[test]
    fn exact_mode_round_trip_is_exact() {
        for light in ["D65", "A", "FL2"] {
            let f = fit(&input(light), Mode::Exact).unwrap();
            let rt = round_trip(&f, 17, &RgbSpace::SRGB);
            assert_eq!(rt.colours, 17 * 17 * 17 - 1);
            assert!(rt.max_de2000 < 1e-3, "{light}: {rt:?}");
            let p = fit(&input(light), Mode::Paper).unwrap();
            let rp = round_trip(&p, 17, &RgbSpace::SRGB);
            assert!(rp.mean_de2000 > rt.mean_de2000, "{light}: paper {rp:?}");
            assert_eq!(
                rp.negative_fraction, 0.0,
                "non-negative weights give non-negative SPDs"
            );
        }
    }

    #[test]
    fn nonneg_mode_is_exact_inside_the_cone_and_never_negative() {
        let f = fit(&input("FL2"), Mode::Nonneg).unwrap();
        let exact = fit(&input("FL2"), Mode::Exact).unwrap();
        let up = Upsampler::new(&f, &RgbSpace::SRGB);
        let up_exact = Upsampler::new(&exact, &RgbSpace::SRGB);
        let mut outside = 0;
        for rgb in [
            [0.5, 0.5, 0.5],
            [0.8, 0.6, 0.4],
            [1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 1.0, 1.0],
        ] {
            let a = up.coefficients(rgb);
            let a_exact = up_exact.coefficients(rgb);
            assert!(up.spd(rgb).iter().all(|v| *v >= -1e-12), "{rgb:?}");
            if up.is_nonnegative(&Vector3::from(a_exact)) {
                assert_eq!(a, a_exact);
                assert!(up.round_trip_error(rgb, a) < 1e-6);
            } else {
                outside += 1;
                // On the cone's boundary: worse than the (negative) exact SPD, better than the
                // grey of the same luminance.
                let de = up.round_trip_error(rgb, a);
                assert!(de > 0.0);
                let y = (RgbSpace::SRGB.to_xyz_matrix().row(1) * Vector3::from(rgb))[0];
                let grey = up.coefficients([y, y, y]);
                assert!(de < up.round_trip_error(rgb, grey), "{rgb:?}: {de}");
            }
        }
        assert!(
            outside >= 2,
            "pure primaries have negative exact SPDs under FL2"
        );
        let rt = round_trip(&f, 9, &RgbSpace::SRGB);
        assert_eq!(rt.negative_fraction, 0.0);
    }

    #[test]
    fn low_pressure_sodium_is_reduced_finite_and_explained() {
        // Under LPS the basis colours are nearly one: the fit must be reduced, finite, explained,
        // and argmin must still agree with the closed form.
        let f = fit(&input("lps"), Mode::Paper).unwrap();
        assert!(f.regularized, "lps: cond {}", f.condition_number);
        assert!(
            f.weights.iter().all(|w| w.is_finite() && w.abs() < 1000.0),
            "{:?}",
            f.weights
        );
        assert!(f.argmin.max_abs_difference < 1e-8, "{:?}", f.argmin);
        assert!(f.lost_information.is_some());
        let rt = round_trip(&f, 9, &RgbSpace::SRGB);
        assert!(rt.max_de2000.is_finite());
    }

    #[test]
    fn fit_files_round_trip_and_bad_ones_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let f = fit(&input("A"), Mode::Exact).unwrap();
        let path = dir.path().join("fit.json");
        std::fs::write(&path, serde_json::to_string(&f).unwrap()).unwrap();
        let g = Fit::load(&path).unwrap();
        assert_eq!(g.matrix, f.matrix);
        assert_eq!(g.rgb_space(), RgbSpace::SRGB);
        let mut v: serde_json::Value = serde_json::to_value(&f).unwrap();
        v["version"] = 99.into();
        std::fs::write(&path, v.to_string()).unwrap();
        assert!(Fit::load(&path)
            .unwrap_err()
            .to_string()
            .contains("version 99"));
        v["version"] = 1.into();
        v["light_spd"] = serde_json::json!([1.0, 2.0]);
        std::fs::write(&path, v.to_string()).unwrap();
        assert!(Fit::load(&path)
            .unwrap_err()
            .to_string()
            .contains("do not match the grid"));
        std::fs::write(&path, "{}").unwrap();
        assert!(Fit::load(&path)
            .unwrap_err()
            .to_string()
            .contains("no \"version\""));
    }

    #[test]
    fn bad_inputs_are_errors() {
        let mut i = input("D65");
        i.light = i.light.map(|_| 0.0);
        assert!(fit(&i, Mode::Paper)
            .unwrap_err()
            .to_string()
            .contains("no visible energy"));
        let mut i = input("D65");
        i.light = i.light.map(|v| v - 50.0);
        assert!(fit(&i, Mode::Paper)
            .unwrap_err()
            .to_string()
            .contains("negative"));
        let mut i = input("D65");
        i.basis[2] = i.basis[0].scaled(2.0).try_add(&i.basis[1]).unwrap();
        assert!(fit(&i, Mode::Paper)
            .unwrap_err()
            .to_string()
            .contains("linearly dependent"));
    }
}
