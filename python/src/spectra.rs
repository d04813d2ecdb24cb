//! Spectra, colour and the paper's fit: `table`, `resample`, `xyz`, `fit`.

use crate::errors::OrPy;
use clap::Parser;
use numpy::ndarray::{Array2, ArrayView2, Axis};
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1, PyReadonlyArrayDyn};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use specmap::colorimetry::{Cmfs, Observer};
use specmap::data;
use specmap::spectrum::{Interpolation, Rule, WavelengthGrid};

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(table, m)?)?;
    m.add_function(wrap_pyfunction!(resample, m)?)?;
    m.add_function(wrap_pyfunction!(xyz, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(names, m)?)?;
    Ok(())
}

/// `(label, wavelengths, values, kind)` of a spectrum named as the CLI names one: a built-in
/// table, `TABLE:COLUMN`, or a CSV file (`PATH` or `PATH:COLUMN`). `kind` is the built-in
/// table's kind ("illuminant", "light", "reflectance", "cmf", ...) or None for a file.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn table<'py>(
    py: Python<'py>,
    spec: &str,
) -> PyResult<(
    String,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Option<String>,
)> {
    let s = data::spectrum(spec).or_py()?;
    let kind = table_kind(spec)?;
    Ok((
        s.label,
        s.data.wavelengths_nm().to_vec().into_pyarray(py),
        s.data.values().to_vec().into_pyarray(py),
        kind,
    ))
}

/// The built-in kind of the table `spec` names, lower case (None for a user's file).
fn table_kind(spec: &str) -> PyResult<Option<String>> {
    let table = match spec.rsplit_once(':') {
        Some((t, c)) if !std::path::Path::new(spec).is_file() && !t.is_empty() && !c.is_empty() => {
            t
        }
        _ => spec,
    };
    let t = data::Table::load(table).or_py()?;
    Ok(t.kind().map(|k| format!("{k:?}").to_lowercase()))
}

/// Every built-in table as `(kind, name)`.
#[pyfunction]
fn names() -> Vec<(String, String)> {
    data::builtin_names()
        .map(|(k, n)| (format!("{k:?}").to_lowercase(), n.to_string()))
        .collect()
}

/// `values` sampled at `wavelengths`, at `at` (nm, any order): "linear" (lights, CIE 15) or
/// "cie167" (Sprague or a cubic spline, for smooth data); the end values held outside.
#[pyfunction]
fn resample<'py>(
    py: Python<'py>,
    wavelengths: PyReadonlyArray1<'py, f64>,
    values: PyReadonlyArray1<'py, f64>,
    at: PyReadonlyArray1<'py, f64>,
    interpolation: &str,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let method = match interpolation {
        "linear" => Interpolation::Linear,
        "cie167" => Interpolation::Cie167,
        other => {
            return Err(PyValueError::new_err(format!(
                "interpolation {other:?}: use \"linear\" or \"cie167\""
            )))
        }
    };
    let t = specmap::spectrum::Tabulated::new(
        wavelengths.as_array().to_vec(),
        values.as_array().to_vec(),
    )
    .or_py()?;
    let at = at.as_array().to_vec();
    Ok(t.at(&at, method).into_pyarray(py))
}

/// The uniform grid `wavelengths` lie on (nm), or a ValueError saying where they are not.
pub(crate) fn grid_of(wavelengths: &[f64]) -> PyResult<WavelengthGrid> {
    if wavelengths.len() < 2 {
        return Err(PyValueError::new_err(format!(
            "wavelengths: {} given; a grid needs at least 2",
            wavelengths.len()
        )));
    }
    let step = wavelengths[1] - wavelengths[0];
    if let Some(i) = wavelengths
        .windows(2)
        .position(|w| ((w[1] - w[0]) - step).abs() > 1e-6 * step.abs().max(1e-9))
    {
        return Err(PyValueError::new_err(format!(
            "wavelengths must be uniformly spaced: {} nm follows {} nm where the step is {step} \
             nm (resample the spectra first, e.g. with specmap.spectrum(..., wavelengths=...))",
            wavelengths[i + 1],
            wavelengths[i]
        )));
    }
    let last = wavelengths[wavelengths.len() - 1];
    let grid = WavelengthGrid::new(wavelengths[0], last, step).or_py()?;
    if grid.len() != wavelengths.len() {
        return Err(PyValueError::new_err(format!(
            "wavelengths {}..{last} nm by {step} nm make {} samples, not the {} given",
            wavelengths[0],
            grid.len(),
            wavelengths.len()
        )));
    }
    Ok(grid)
}

pub(crate) fn observer_of(name: &str) -> PyResult<Observer> {
    match name.to_lowercase().replace([' ', '_', '-'], "").as_str() {
        "cie1931" | "1931" | "cie19312" | "2" => Ok(Observer::Cie1931),
        "cie1964" | "1964" | "cie196410" | "10" => Ok(Observer::Cie1964),
        _ => Err(PyValueError::new_err(format!(
            "observer {name:?}: use \"CIE 1931\" (2 degrees) or \"CIE 1964\" (10 degrees)"
        ))),
    }
}

pub(crate) fn rule_of(name: &str) -> PyResult<Rule> {
    match name.to_lowercase().as_str() {
        "riemann" => Ok(Rule::Riemann),
        "trapezoid" => Ok(Rule::Trapezoid),
        "simpson" => Ok(Rule::Simpson),
        _ => Err(PyValueError::new_err(format!(
            "rule {name:?}: use \"riemann\", \"trapezoid\" or \"simpson\""
        ))),
    }
}

/// XYZ of each row of `values` (`(..., N)` over `wavelengths`, a uniform grid): with `light`
/// (N values) the rows are reflectances and XYZ is the paper's Eq. 10/11, `k = 100 /
/// integral(S ybar)`; without, the rows are lights and XYZ is `k integral(row xbar)` with the `k`
/// given (683.002 lm/W makes Y a luminance). Returns `(..., 3)`.
#[pyfunction]
#[pyo3(signature = (values, wavelengths, light=None, k=None, observer="CIE 1931", rule="riemann"))]
fn xyz<'py>(
    py: Python<'py>,
    values: PyReadonlyArrayDyn<'py, f64>,
    wavelengths: PyReadonlyArray1<'py, f64>,
    light: Option<PyReadonlyArray1<'py, f64>>,
    k: Option<f64>,
    observer: &str,
    rule: &str,
) -> PyResult<Bound<'py, numpy::PyArrayDyn<f64>>> {
    let grid = grid_of(wavelengths.as_slice()?)?;
    let n = grid.len();
    let v = values.as_array();
    let shape = v.shape().to_vec();
    if shape.last() != Some(&n) {
        return Err(PyValueError::new_err(format!(
            "values of shape {shape:?}: the last axis must hold the {n} wavelengths"
        )));
    }
    let rows = v.len() / n.max(1);
    let flat: Vec<f64> = v.iter().copied().collect();
    let light = light.map(|l| l.as_array().to_vec());
    let (observer, rule) = (observer_of(observer)?, rule_of(rule)?);
    let out = py.detach(move || -> PyResult<Array2<f64>> {
        let weights = xyz_weights(&grid, observer, rule, light.as_deref(), k)?;
        let values = ArrayView2::from_shape((rows, n), &flat).expect("rows x bands");
        Ok(values.dot(&weights))
    })?;
    let mut out_shape = shape;
    *out_shape.last_mut().expect("an axis") = 3;
    let out = out
        .into_shape_with_order(out_shape)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(out.into_pyarray(py))
}

/// The `(N, 3)` matrix taking a row of N samples to XYZ: the rule's weights times the
/// colour-matching functions, times the light and Eq. 11's k for reflectances.
fn xyz_weights(
    grid: &WavelengthGrid,
    observer: Observer,
    rule: Rule,
    light: Option<&[f64]>,
    k: Option<f64>,
) -> PyResult<Array2<f64>> {
    let cmfs = Cmfs::new(observer, grid).or_py()?;
    let n = grid.len();
    let w = rule.weights(n, grid.step_nm());
    let bars = [cmfs.x.values(), cmfs.y.values(), cmfs.z.values()];
    let s: Vec<f64> = match light {
        Some(l) if l.len() != n => {
            return Err(PyValueError::new_err(format!(
                "light: {} values for {n} wavelengths",
                l.len()
            )))
        }
        Some(l) => l.to_vec(),
        None => vec![1.0; n],
    };
    let k =
        match (light, k) {
            (Some(_), Some(_)) => return Err(PyValueError::new_err(
                "k is Eq. 11's 100 / integral(S ybar) when a light is given; give one or the other",
            )),
            (Some(_), None) => {
                let light = specmap::spectrum::Spectrum::new(*grid, s.clone()).or_py()?;
                cmfs.k(&light, rule).or_py()?
            }
            (None, k) => k.unwrap_or(1.0),
        };
    let mut m = Array2::zeros((n, 3));
    for (i, mut row) in m.axis_iter_mut(Axis(0)).enumerate() {
        for c in 0..3 {
            row[c] = k * w[i] * s[i] * bars[c][i];
        }
    }
    Ok(m)
}

/// The paper's fit for `argv` (the flags of `specmap fit`): `(report, fit)` as JSON text, the
/// report as `specmap fit --json` prints it and the fit as `specmap fit -o` writes it.
#[pyfunction]
fn fit(py: Python<'_>, argv: Vec<String>) -> PyResult<(String, String)> {
    let args: FitCommand = crate::parse_flags("fit", argv)?;
    py.detach(move || {
        let (report, fit) = crate::cli::fit::json(&args.args)?;
        Ok::<_, anyhow::Error>((report.to_string(), serde_json::to_string(&fit)?))
    })
    .or_py()
}

#[derive(Parser)]
struct FitCommand {
    #[command(flatten)]
    args: crate::cli::fit::FitArgs,
}
