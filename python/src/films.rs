//! Thin films: `thinfilm`, R and T of a multilayer stack for every (thickness scale, angle,
//! wavelength) at once, computed in parallel with the GIL released.
//!
//! The stack's optical constants are built once per wavelength (the library's [`Stack::at`],
//! which checks every medium and names the one at fault); each (scale, angle) then evaluates
//! that [`Film`] with [`Film::rt_scaled`], which multiplies every layer's thickness without
//! rebuilding anything, or, for many scales, prepares each (angle, wavelength) once with
//! [`Film::sweep`] and evaluates it at every scale; no element allocates or calls Python.

use crate::errors::OrPy;
use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyArray3, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rayon::prelude::*;
use specmap::spectrum::fmt_num as num;
use specmap::thinfilm::{Film, Incidence, Index, Layer, Material, Polarization, Stack};

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(thinfilm, m)?)?;
    Ok(())
}

/// A medium as the Python wrapper passes it: a material's name (`"bk7"`, `"fused-silica"`) or
/// an index written as the CLI writes one (`"3.1+3.3i"`), or `(n, k)`.
#[derive(FromPyObject)]
enum MediumArg {
    Name(String),
    Nk(f64, f64),
}

impl MediumArg {
    fn material(&self, what: &str) -> PyResult<Material> {
        match self {
            MediumArg::Nk(n, k) => Index::new(*n, *k)
                .map(Material::constant)
                .map_err(|e| PyValueError::new_err(format!("{what}: {e}"))),
            MediumArg::Name(name) => {
                if let Some(m) = Material::named(name.trim()) {
                    return Ok(m);
                }
                let s = name.trim();
                if s.starts_with(|c: char| c.is_ascii_digit() || ".+-".contains(c)) {
                    return s
                        .parse::<Index>()
                        .map(Material::constant)
                        .map_err(|e| PyValueError::new_err(format!("{what}: {e}")));
                }
                Err(PyValueError::new_err(format!(
                    "{what}: {name:?} is not a material specmap knows (\"bk7\", \
                     \"fused-silica\") nor an index (1.5, 2+0.3j, \"3.1+3.3i\")"
                )))
            }
        }
    }
}

/// Scales per parallel task from which each (angle, wavelength) is prepared once
/// ([`Film::sweep`]) rather than evaluated afresh for each scale ([`Film::rt_scaled`]).
const SWEEP_MIN_SCALES: usize = 8;

/// Elements per parallel task: enough to amortise rayon's scheduling, few enough to balance.
const CHUNK: usize = 2048;

/// `(R, T)`, each `(len(scales), len(angles_deg), len(wavelengths))`: the stack `ambient |
/// layers | substrate` (layers `(medium, thickness nm)` from the ambient side) with every
/// thickness multiplied by each scale, at each angle of incidence (degrees, [0, 90)) and each
/// wavelength (nm), all layers coherent (tmm's `coh_tmm`). `pol` is "s", "p" or "u"
/// (unpolarised, the mean of s and p).
#[pyfunction]
#[pyo3(signature = (layers, substrate, ambient, wavelengths, angles_deg, scales, pol))]
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn thinfilm<'py>(
    py: Python<'py>,
    layers: Vec<(MediumArg, f64)>,
    substrate: MediumArg,
    ambient: MediumArg,
    wavelengths: PyReadonlyArray1<'py, f64>,
    angles_deg: PyReadonlyArray1<'py, f64>,
    scales: PyReadonlyArray1<'py, f64>,
    pol: &str,
) -> PyResult<(Bound<'py, PyArray3<f64>>, Bound<'py, PyArray3<f64>>)> {
    let pol = match pol.to_ascii_lowercase().as_str() {
        "s" | "te" => Polarization::S,
        "p" | "tm" => Polarization::P,
        "u" | "unpolarized" | "unpolarised" => Polarization::Unpolarized,
        _ => {
            return Err(PyValueError::new_err(format!(
                "pol {pol:?}: use \"s\", \"p\" or \"u\" (unpolarised, the mean of s and p)"
            )))
        }
    };
    let wavelengths = wavelengths.as_array().to_vec();
    let angles_deg = angles_deg.as_array().to_vec();
    let scales = scales.as_array().to_vec();
    let ambient = ambient.material("ambient")?;
    let substrate = substrate.material("substrate")?;
    let layers = layers
        .iter()
        .enumerate()
        .map(|(i, (m, d))| {
            let what = format!("layer {}", i + 1);
            let material = m.material(&what)?;
            Layer::new(material, *d).map_err(|e| PyValueError::new_err(format!("{what}: {e}")))
        })
        .collect::<PyResult<Vec<_>>>()?;
    let incidences = angles_deg
        .iter()
        .map(|&a| {
            if !(0.0..90.0).contains(&a) {
                return Err(PyValueError::new_err(format!(
                    "angle of incidence {} degrees: must be in [0, 90)",
                    num(a)
                )));
            }
            Incidence::degrees(a).or_py()
        })
        .collect::<PyResult<Vec<_>>>()?;
    if let Some(w) = wavelengths.iter().find(|w| !(w.is_finite() && **w > 0.0)) {
        return Err(PyValueError::new_err(format!(
            "wavelength {} nm: every wavelength must be finite and positive",
            num(*w)
        )));
    }
    if let Some(s) = scales.iter().find(|s| !(s.is_finite() && **s >= 0.0)) {
        return Err(PyValueError::new_err(format!(
            "thickness_scale {}: every factor must be finite and >= 0",
            num(*s)
        )));
    }
    // Every scaled film must be one the library accepts (layers at most 1e20 wavelengths
    // thick): checked on the stack at the largest scale, built here, evaluated with the rest.
    let largest = largest_scale(&scales);
    let largest_stack = match largest > 1.0 && !layers.is_empty() {
        true => Some(Stack::new(
            ambient.clone(),
            layers
                .iter()
                .map(|l| Layer::new(l.material().clone(), l.thickness_nm() * largest))
                .collect::<specmap::Result<Vec<_>>>()
                .map_err(|e| {
                    PyValueError::new_err(format!("thickness_scale {}: {e}", num(largest)))
                })?,
            substrate.clone(),
        )),
        false => None,
    };
    let stack = Stack::new(ambient, layers, substrate);
    let shape = (scales.len(), incidences.len(), wavelengths.len());
    let (r, t) = py.detach(move || {
        evaluate(
            &stack,
            largest_stack.as_ref(),
            &wavelengths,
            &incidences,
            &scales,
            pol,
        )
    })?;
    let to_array = |v: Vec<f64>| Array3::from_shape_vec(shape, v).expect("scales x angles x bands");
    Ok((to_array(r).into_pyarray(py), to_array(t).into_pyarray(py)))
}

/// R and T, flat in (scale, angle, wavelength) order; `largest`, the stack at the largest
/// scale, is checked at every wavelength after `stack`.
fn evaluate(
    stack: &Stack,
    largest: Option<&Stack>,
    wavelengths: &[f64],
    incidences: &[Incidence],
    scales: &[f64],
    pol: Polarization,
) -> PyResult<(Vec<f64>, Vec<f64>)> {
    // One film per wavelength, built and checked once.
    let films = wavelengths
        .iter()
        .map(|&w| stack.at::<f64>(w))
        .collect::<specmap::Result<Vec<Film<f64>>>>()
        .or_py()?;
    if let Some(check) = largest {
        for &w in wavelengths {
            check.at::<f64>(w).map_err(|e| {
                PyValueError::new_err(format!(
                    "thickness_scale {}: {e}",
                    num(largest_scale(scales))
                ))
            })?;
        }
    }
    let (nw, na, ns) = (wavelengths.len(), incidences.len(), scales.len());
    let total = ns * na * nw;
    let mut r = vec![0.0; total];
    let mut t = vec![0.0; total];
    // Scales per parallel task: up to 64, fewer where that leaves some threads idle.
    let block = (ns / (4 * rayon::current_num_threads())).clamp(1, 64);
    if block >= SWEEP_MIN_SCALES {
        // Each task takes a block of scales, contiguous in the output: each (angle,
        // wavelength) is prepared once ([`Film::sweep`]: media, interfaces, fluxes) and
        // evaluated at each of the block's scales.
        let plane = na * nw;
        r.par_chunks_mut(block * plane)
            .zip(t.par_chunks_mut(block * plane))
            .zip(scales.par_chunks(block))
            .for_each(|((r, t), scales)| {
                for (aw, film) in (0..plane).map(|aw| (aw, &films[aw % nw])) {
                    let sweep = film.sweep(&incidences[aw / nw], pol);
                    for (k, s) in scales.iter().enumerate() {
                        let rt = sweep.rt(*s);
                        r[k * plane + aw] = rt.r;
                        t[k * plane + aw] = rt.t;
                    }
                }
            });
    } else {
        r.par_chunks_mut(CHUNK)
            .zip(t.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(c, (r, t))| {
                let start = c * CHUNK;
                for (j, (r, t)) in r.iter_mut().zip(t.iter_mut()).enumerate() {
                    let i = start + j;
                    let (w, a, s) = (i % nw, (i / nw) % na, i / (nw * na));
                    let rt = films[w].rt_scaled(&incidences[a], pol, scales[s]);
                    *r = rt.r;
                    *t = rt.t;
                }
            });
    }
    if let Some(i) = (0..total).find(|&i| !(r[i].is_finite() && t[i].is_finite())) {
        let (w, a, s) = (i % nw, (i / nw) % na, i / (nw * na));
        return Err(PyValueError::new_err(format!(
            "no finite reflectance at {} nm, {} degrees, thickness scale {}: the stack has a \
             resonance (a pole of the recursion) exactly there",
            wavelengths[w],
            incidences[a].as_degrees(),
            scales[s]
        )));
    }
    Ok((r, t))
}

/// The largest thickness factor (0 for none).
fn largest_scale(scales: &[f64]) -> f64 {
    scales.iter().copied().fold(0.0f64, f64::max)
}
