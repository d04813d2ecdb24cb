//! Environment maps: `inspect`, `convert` (to a file, or into memory), `upsample_colours`,
//! `convert_image` and `read_spectral`. Options arrive as the CLI's flags (the wrapper in
//! specmap/_maps.py turns keyword arguments into them) and are parsed by the CLI's own clap code.

use crate::cli::convert::{input_guard, ConvertArgs, ConvertOptionArgs};
use crate::cli::inspect::InspectArgs;
use crate::errors::OrPy;
use crate::parse_flags;
use clap::Parser;
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use specmap::envmap::convert::{self, upsample::Upsample, Spectra};
use specmap::envmap::files::{read_spectral_info, read_spectral_rows};
use specmap::envmap::RgbImage;
use std::path::Path;

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(inspect, m)?)?;
    m.add_function(wrap_pyfunction!(convert_file, m)?)?;
    m.add_function(wrap_pyfunction!(convert_in_memory, m)?)?;
    m.add_function(wrap_pyfunction!(convert_image, m)?)?;
    m.add_function(wrap_pyfunction!(upsample_colours, m)?)?;
    m.add_function(wrap_pyfunction!(read_spectral, m)?)?;
    Ok(())
}

#[derive(Parser)]
#[command(name = "inspect")]
struct InspectCommand {
    #[command(flatten)]
    args: InspectArgs,
}

#[derive(Parser)]
#[command(name = "convert")]
struct ConvertCommand {
    #[command(flatten)]
    args: ConvertArgs,
}

/// A conversion with no output file: the input and the conversion's flags.
#[derive(Parser)]
#[command(name = "convert")]
struct InMemoryCommand {
    input: String,
    #[command(flatten)]
    options: ConvertOptionArgs,
}

/// The conversion's flags alone (for an array: its space, grid, light...).
#[derive(Parser)]
#[command(name = "upsample")]
struct OptionsCommand {
    #[command(flatten)]
    options: ConvertOptionArgs,
}

/// `specmap inspect ARGV --json`'s JSON text.
#[pyfunction]
fn inspect(py: Python<'_>, argv: Vec<String>) -> PyResult<String> {
    let a: InspectCommand = parse_flags("inspect", argv)?;
    py.detach(|| -> anyhow::Result<String> { Ok(crate::cli::inspect::json(&a.args)?.to_string()) })
        .or_py()
}

/// `specmap convert ARGV --json`'s report as JSON text; the file written as the CLI writes it.
#[pyfunction]
fn convert_file(py: Python<'_>, argv: Vec<String>) -> PyResult<String> {
    let a: ConvertCommand = parse_flags("convert", argv)?;
    py.detach(|| -> anyhow::Result<String> {
        let report = crate::cli::convert::report(&a.args, &|_, _| {})?;
        Ok(serde_json::to_string(&report)?)
    })
    .or_py()
}

/// The arrays of a conversion in memory: `(report JSON, wavelengths, spectra (H, W, N), rgb
/// (H, W, 3), sun (H, W))`.
type InMemory<'py> = (
    String,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray3<f32>>,
    Bound<'py, PyArray3<f32>>,
    Bound<'py, PyArray2<f32>>,
);

/// `specmap convert ARGV` without an output: the report and the spectra in memory.
#[pyfunction]
fn convert_in_memory(py: Python<'_>, argv: Vec<String>) -> PyResult<InMemory<'_>> {
    let a: InMemoryCommand = parse_flags("convert", argv)?;
    let (report, spectra) = py
        .detach(|| -> anyhow::Result<_> {
            let opts = a.options.to_options()?;
            input_guard(&a.input, &opts, &a.options).check()?;
            Ok(convert::convert_in_memory(&a.input, &opts, &|_, _| {})?)
        })
        .or_py()?;
    in_memory(py, &report, spectra)
}

/// The converter's scene analysis and spectra for an `(H, W, 3)` map in memory, with the
/// conversion's flags `argv`.
#[pyfunction]
fn convert_image<'py>(
    py: Python<'py>,
    rgb: PyReadonlyArray2<'py, f32>,
    width: usize,
    argv: Vec<String>,
) -> PyResult<InMemory<'py>> {
    let a: OptionsCommand = parse_flags("upsample", argv)?;
    let image = rgb_image(&rgb, width)?;
    let (report, spectra) = py
        .detach(|| -> anyhow::Result<_> {
            let opts = a.options.to_options()?;
            Ok(convert::convert_image(
                "the array",
                image,
                &opts,
                &|_, _| {},
            )?)
        })
        .or_py()?;
    in_memory(py, &report, spectra)
}

/// `(n, 3)` colours as an image `width` pixels wide.
fn rgb_image(rgb: &PyReadonlyArray2<'_, f32>, width: usize) -> PyResult<RgbImage> {
    let a = rgb.as_array();
    if a.ncols() != 3 || width == 0 || !a.nrows().is_multiple_of(width) {
        return Err(PyValueError::new_err(format!(
            "an RGB image of {} x {} values is not rows of {width} pixels of 3 channels",
            a.nrows(),
            a.ncols()
        )));
    }
    let mut image = RgbImage::new(width, a.nrows() / width);
    for (p, row) in image.pixels.iter_mut().zip(a.rows()) {
        *p = [row[0], row[1], row[2]];
    }
    Ok(image)
}

/// The report and the spectra as numpy arrays (the planes move, not copied).
fn in_memory<'py>(
    py: Python<'py>,
    report: &convert::ConvertReport,
    s: Spectra,
) -> PyResult<InMemory<'py>> {
    let json = serde_json::to_string(report).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let (h, w, n) = (s.height, s.width, s.wavelengths_nm.len());
    let shape_err = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
    Ok((
        json,
        Array1::from(s.wavelengths_nm).into_pyarray(py),
        Array3::from_shape_vec((h, w, n), s.spectra)
            .map_err(shape_err)?
            .into_pyarray(py),
        Array3::from_shape_vec((h, w, 3), s.rgb)
            .map_err(shape_err)?
            .into_pyarray(py),
        Array2::from_shape_vec((h, w), s.sun)
            .map_err(shape_err)?
            .into_pyarray(py),
    ))
}

/// `(n, 3)` linear RGB colours -> `(wavelengths, (n, N) spectra, inexact count)` under `light`
/// (None: D65 with daylight-coloured colours as CIE daylight), the conversion's flags `argv`
/// giving the space and the grid.
#[pyfunction]
#[pyo3(signature = (rgb, light, argv))]
#[allow(clippy::type_complexity)]
fn upsample_colours<'py>(
    py: Python<'py>,
    rgb: PyReadonlyArray2<'py, f32>,
    light: Option<String>,
    argv: Vec<String>,
) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f32>>, usize)> {
    let a: OptionsCommand = parse_flags("upsample", argv)?;
    let view = rgb.as_array();
    if view.ncols() != 3 {
        return Err(PyValueError::new_err(format!(
            "rgb has {} channels: the last axis must hold R, G, B",
            view.ncols()
        )));
    }
    let colours: Vec<[f32; 3]> = view
        .rows()
        .into_iter()
        .map(|r| [r[0], r[1], r[2]])
        .collect();
    let (grid, out, inexact) = py
        .detach(|| -> anyhow::Result<_> {
            let opts = a.options.to_options()?;
            let up = Upsample::new(light.as_deref(), &opts)?;
            let mut out = vec![0f32; colours.len() * up.bands()];
            let inexact = up.spectra(&colours, &mut out)?;
            Ok((opts.grid, out, inexact))
        })
        .or_py()?;
    let wavelengths: Vec<f64> = grid.wavelengths_nm().collect();
    let spectra = Array2::from_shape_vec((colours.len(), grid.len()), out)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok((
        Array1::from(wavelengths).into_pyarray(py),
        spectra.into_pyarray(py),
        inexact,
    ))
}

/// A spectral OpenEXR (Fichet et al. 2021, emissive `S0.<nm>nm` bands): `(wavelengths,
/// (H, W, N) spectra, (H, W, 3) rgb or None, header JSON)`, values times 2^EV where the file has
/// an `EV`.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn read_spectral<'py>(
    py: Python<'py>,
    path: &str,
) -> PyResult<(
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray3<f32>>,
    Option<Bound<'py, PyArray3<f32>>>,
    String,
)> {
    let (info, spectra, rgb) = py
        .detach(|| -> specmap::Result<_> {
            // Each row split as it comes: the bands, then R, G, B where the file has them.
            let info = read_spectral_info(Path::new(path))?;
            let (n, has_rgb) = (info.wavelengths_nm.len(), info.has_rgb);
            let per = n + if has_rgb { 3 } else { 0 };
            let mut bands = Vec::with_capacity(info.width * info.height * n);
            let mut rgb = Vec::with_capacity(if has_rgb {
                info.width * info.height * 3
            } else {
                0
            });
            let info = read_spectral_rows(Path::new(path), |_, row| {
                for p in row.chunks_exact(per) {
                    bands.extend_from_slice(&p[..n]);
                    rgb.extend_from_slice(&p[n..]);
                }
            })?;
            Ok((info, bands, rgb))
        })
        .or_py()?;
    let (h, w, n) = (info.height, info.width, info.wavelengths_nm.len());
    let shape_err = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
    let spectra = Array3::from_shape_vec((h, w, n), spectra).map_err(shape_err)?;
    let rgb = match info.has_rgb {
        true => Some(
            Array3::from_shape_vec((h, w, 3), rgb)
                .map_err(shape_err)?
                .into_pyarray(py),
        ),
        false => None,
    };
    let header = serde_json::json!({
        "envmap": info.envmap.map(|e| format!("{e:?}").to_lowercase()),
        "ev": info.ev,
        "chromaticities": info.chromaticities,
        "attributes": info.attributes.iter().map(|(k, v)| (k.clone(), format!("{v:?}"))).collect::<std::collections::BTreeMap<_, _>>(),
    });
    Ok((
        Array1::from(info.wavelengths_nm.clone()).into_pyarray(py),
        spectra.into_pyarray(py),
        rgb,
        header.to_string(),
    ))
}
