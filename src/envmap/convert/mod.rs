//! RGB environment map -> spectral environment map, as a pipeline of named stages:
//! [`read`] (read, sanitise, resample) -> [`analyse`] (the scene's lights, the white premise,
//! the main light) -> [`plan`] (every decision of the write as a value, the file's included) ->
//! [`write`] (stream the spectra block by block; the basis form factored from them), and the
//! [`report`] built from the plan and what the write counted.
//!
//! The other files are the stages' parts: [`options`] (what is asked), [`pixels`],
//! [`pixel_spectra`] (the paper's basis) and [`carriers`] with [`carrier_plan`] (the faithful
//! method) make each pixel's spectrum; [`file_plan`] the file's form, precision and attributes;
//! [`coefficient_rows`] streams the spectra as planes; [`basis_form`] and [`own_basis`] factor a
//! spectral file into K spectra of its own.
//!
//! ```no_run
//! use specmap::envmap::convert::{convert, ConvertOptions};
//! use std::path::Path;
//!
//! let report = convert(
//!     "sunrise.exr",
//!     Path::new("sunrise.spectral.exr"),
//!     &ConvertOptions::faithful(),
//!     &|_done, _total| {},
//! )?;
//! let rt = &report.roundtrip_without_sun;
//! println!("{} wavelengths, CIEDE2000 {:.2}", report.wavelengths_nm.len(), rt.weighted_mean_de2000);
//! # Ok::<(), specmap::Error>(())
//! ```

pub(crate) mod analyse;
pub(crate) mod band_reduce;
pub mod basis_form;
pub(crate) mod carrier_plan;
pub(crate) mod carriers;
pub(crate) mod coefficient_rows;
pub(crate) mod file_plan;
pub(crate) mod measure;
pub(crate) mod options;
pub(crate) mod own_basis;
pub mod pixel_spectra;
pub(crate) mod pixels;
pub(crate) mod plan;
pub(crate) mod planning;
pub mod read;
pub(crate) mod report;
pub(crate) mod sun_report;
pub mod upsample;
pub(crate) mod write;

pub use analyse::Analysis;
pub use file_plan::{FilePlan, Output, Precisions};
pub use measure::SpectraCount;
pub use options::{
    input_files, mode_name, ConvertOptions, LightSpec, Lights, Method, OutputFormat, SkySpd,
    SunSpd, WhiteSpec, MAX_BANDS, MAX_INPUT,
};
pub use pixels::PixelPlan;
pub use plan::Plan;
pub use report::{ConvertReport, Inspection};
pub use sun_report::{SunFound, SunReport};
pub use write::WriteStats;

use crate::data;
use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// Reads and analyses `input` and plans its conversion, writing nothing.
pub fn inspect(input: &str, opts: &ConvertOptions) -> Result<Inspection> {
    let read = read::read(input, opts)?;
    let analysis = analyse::analyse(&read, opts)?;
    let plan = plan::plan(read, &analysis, opts, None)?;
    Ok(Inspection::new(input, plan, analysis))
}

/// Converts `input` to a spectral (or basis) OpenEXR at `output`. `progress(done, total)` is
/// called after each batch of rows.
pub fn convert(
    input: &str,
    output: &Path,
    opts: &ConvertOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<ConvertReport> {
    check_before(input, output, opts)?;
    let read = read::read(input, opts)?;
    let analysis = analyse::analyse_for_write(&read, opts)?;
    let plan = plan::plan(read, &analysis, opts, Some(output))?;
    let written = write::write(&plan, &analysis.scene.cells, progress)?;
    Ok(ConvertReport::new(input, &analysis, &plan, written))
}

/// A converted map held in memory: every pixel's spectrum, RGB and sun mask.
#[derive(Debug, Clone)]
pub struct Spectra {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// The bands' wavelengths (nm).
    pub wavelengths_nm: Vec<f64>,
    /// Row by row, each pixel's bands (`wavelengths_nm.len()` values): what a float spectral
    /// file holds.
    pub spectra: Vec<f32>,
    /// Row by row, each pixel's R, G, B (the file's preview channels).
    pub rgb: Vec<f32>,
    /// Row by row, 1 on the sun's pixels, else 0.
    pub sun: Vec<f32>,
}

/// Converts `input` as [`convert`] does and keeps the spectra in memory, writing no file (the
/// basis form, which is a file's, is refused).
pub fn convert_in_memory(
    input: &str,
    opts: &ConvertOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(ConvertReport, Spectra)> {
    let read = read::read(input, opts)?;
    to_memory(input, read, opts, progress)
}

/// Converts an RGB image already in memory (its layout from `opts.in_layout` or its shape, its
/// values in `opts.space`), as [`convert_in_memory`] converts a file; `name` names it in the
/// report and in messages.
pub fn convert_image(
    name: &str,
    image: crate::envmap::RgbImage,
    opts: &ConvertOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(ConvertReport, Spectra)> {
    let read = read::from_image(name, image, opts)?;
    to_memory(name, read, opts, progress)
}

/// Analyse, plan and compute `read`'s spectra into memory.
fn to_memory(
    input: &str,
    read: read::Input,
    opts: &ConvertOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(ConvertReport, Spectra)> {
    if opts.format == OutputFormat::Basis {
        return Err(Error::invalid(
            "the basis form is a file's (its spectra in the header): give an output path, or \
             convert to spectra in memory",
        ));
    }
    // Memory holds f32: no half-float EV scale to plan.
    let opts = &ConvertOptions {
        precision: crate::envmap::files::Precision::Float,
        ..opts.clone()
    };
    let analysis = analyse::analyse_for_write(&read, opts)?;
    let plan = plan::plan(read, &analysis, opts, None)?;
    let (written, planes) = write::in_memory(&plan, &analysis.scene.cells, progress)?;
    let image = &plan.input.map.image;
    let spectra = Spectra {
        width: image.width,
        height: image.height,
        wavelengths_nm: plan.grid.wavelengths_nm().collect(),
        spectra: planes.spectra,
        rgb: planes.rgb,
        sun: planes.sun,
    };
    Ok((
        ConvertReport::new(input, &analysis, &plan, written),
        spectra,
    ))
}

/// Checks what needs no input before any work: the output is not an input, a named sun SPD is
/// a usable one, the band count fits.
fn check_before(input: &str, output: &Path, opts: &ConvertOptions) -> Result<()> {
    for file in input_files(input, opts) {
        if crate::io::same_file(&file, output) {
            return Err(Error::invalid(format!(
                "the output {} is the input {}: choose another name (inputs are never \
                 overwritten)",
                output.display(),
                file.display()
            )));
        }
    }
    if let Some(SunSpd::Light(name)) = &opts.sun_spd {
        let s = data::spectrum(name)?;
        let (lo, hi) = s
            .data
            .values()
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        if !(lo >= 0.0 && hi > 0.0 && hi.is_finite()) {
            return Err(Error::invalid(format!(
                "--sun-spd {name}: a sun's SPD must be finite, non-negative and not all zero \
                 (values from {lo} to {hi})"
            )));
        }
    }
    if opts.format == OutputFormat::Spectral && opts.grid.len() > MAX_BANDS {
        return Err(Error::invalid(format!(
            "{} wavelengths would make {} channels per pixel; a spectral EXR here holds at most \
             {MAX_BANDS} bands (0.1 nm over 400 nm): choose a coarser --range step",
            opts.grid.len(),
            opts.grid.len() + 4
        )));
    }
    crate::io::check_output(output)
}

/// The default output path for an input: `NAME.spectral.exr` beside it.
pub fn default_output(input: &str) -> PathBuf {
    let p = Path::new(input);
    let stem = p
        .file_stem()
        .map(|s| s.to_string_lossy())
        .unwrap_or_default();
    p.with_file_name(format!("{stem}.spectral.exr"))
}
