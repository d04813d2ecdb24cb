//! `roundtrip`: re-read a spectral OpenEXR, integrate its spectra back to RGB and compare them
//! with the file's own R, G, B preview (the original pixels), pixel by pixel, streaming.

pub mod heatmap;
pub mod metric;
pub mod stats;

use crate::colorimetry::{Chromaticities, Observer, RgbSpace};
use crate::envmap::files::{read_spectral_rows, AttrValue, EnvmapAttr};
use crate::envmap::layout::{detect, EnvMap, Layout};
use crate::envmap::roundtrip::metric::RgbMetric;
use crate::envmap::roundtrip::stats::{Floor, RoundTripAccumulator, RoundTripStats};
use crate::envmap::RgbImage;
use crate::error::{Error, Result};
use crate::spectrum::{Interpolation, Rule, Tabulated, WavelengthGrid};
use std::path::Path;

/// The result of a file round trip.
#[derive(Debug, Clone, serde::Serialize)]
pub struct FileRoundTrip {
    pub file: String,
    pub width: usize,
    pub height: usize,
    pub layout: Option<Layout>,
    pub wavelengths: usize,
    pub range_nm: [f64; 2],
    /// The space of the R, G, B channels (its `chromaticities`, else `specmap.space`).
    pub space: String,
    pub chromaticities: Chromaticities,
    /// The main light's RGB the spectra were divided by (the paper's white balance), from the
    /// `specmap.lightRGB` attribute; None for files without it.
    pub white_balance: Option<[f64; 3]>,
    /// The luminance floor of the statistics (see [`Floor`]).
    pub floor: Floor,
    /// The statistic `convert` reports too (see [`crate::envmap::roundtrip::stats`]).
    pub all: RoundTripStats,
    /// Pixels not marked in the `sun` channel (all pixels when the file has none).
    pub without_sun: RoundTripStats,
    pub sun_pixels: usize,
    /// Pixels left out because a band or an R, G, B value is NaN or infinite (or their
    /// integral overflows).
    pub non_finite_pixels: usize,
}

/// The space of a file's R, G, B: its `chromaticities` (the space `specmap.space` names when it
/// has them: sRGB and the paper's sRGB share them), else the named one, else sRGB (OpenEXR's
/// Rec.709 with D65).
fn preview_space(
    path: &Path,
    named: Option<RgbSpace>,
    declared: Option<Chromaticities>,
) -> Result<RgbSpace> {
    Ok(match (named, declared) {
        (Some(n), Some(c)) if n.chromaticities().same_as(&c) => n,
        (_, Some(c)) => RgbSpace::from_chromaticities(c)
            .map_err(|e| Error::invalid(format!("{}: {e}", path.display())))?,
        (Some(n), None) => n,
        (None, None) => RgbSpace::SRGB,
    })
}

/// Integrates every pixel's spectrum back to RGB and compares it with the preview channels.
/// `heatmap`, if given, receives the per-pixel CIEDE2000 (row-major; NaN for a pixel not
/// compared), for [`crate::envmap::roundtrip::heatmap::write_heatmap`].
pub fn round_trip_file(
    path: &Path,
    observer: Observer,
    rule: Rule,
    mut heatmap: Option<&mut Vec<f32>>,
) -> Result<FileRoundTrip> {
    // The header once: size, the checked wavelengths (positive, each once, sorted) and the
    // attributes; the pixels follow in read_spectral_rows.
    let header = crate::envmap::files::read_spectral_info(path)?;
    let wavelengths = header.wavelengths_nm.clone();
    if wavelengths.len() < 2 {
        return Err(Error::invalid(format!(
            "{}: a round trip needs at least two S0.<wavelength>nm channels",
            path.display()
        )));
    }
    let (width, height) = (header.width, header.height);
    // CMFs at the file's wavelengths, with the rule's weights (non-uniform grids: trapezoid).
    let cmf_table = crate::data::Table::builtin(observer.table_name())?;
    let at = |col: &str| -> Result<Vec<f64>> {
        let t: Tabulated = cmf_table.column(col)?;
        let (lo, hi) = t.range_nm();
        wavelengths
            .iter()
            .map(|&w| {
                // The observer sees nothing outside its tables (as `Cmfs::new`).
                if !(lo..=hi).contains(&w) {
                    return Ok(0.0);
                }
                let g = WavelengthGrid::new(w, w, 1.0)?;
                Ok(t.resample(&g, Interpolation::SMOOTH).values()[0])
            })
            .collect()
    };
    let (xb, yb, zb) = (at("x")?, at("y")?, at("z")?);
    let weights: Vec<f64> = match Tabulated::new(wavelengths.clone(), vec![0.0; wavelengths.len()])?
        .uniform_step_nm()
    {
        Some(step) => rule.weights(wavelengths.len(), step),
        None => {
            // Trapezoid weights on a non-uniform grid.
            let n = wavelengths.len();
            (0..n)
                .map(|i| {
                    let l = if i > 0 {
                        wavelengths[i] - wavelengths[i - 1]
                    } else {
                        0.0
                    };
                    let r = if i + 1 < n {
                        wavelengths[i + 1] - wavelengths[i]
                    } else {
                        0.0
                    };
                    (l + r) / 2.0
                })
                .collect()
        }
    };
    let y_norm: f64 = yb.iter().zip(&weights).map(|(y, w)| y * w).sum();
    let mut named = None;
    let mut white_balance = None;
    for (name, value) in &header.attributes {
        match (name.as_str(), value) {
            ("specmap.space", AttrValue::Text(t)) => {
                named = RgbSpace::ALL.into_iter().find(|s| s.name == *t);
            }
            ("specmap.lightRGB", AttrValue::F32Vec(v)) if v.len() == 3 => {
                white_balance = Some([v[0] as f64, v[1] as f64, v[2] as f64]);
            }
            _ => {}
        }
    }
    let space = preview_space(path, named, header.chromaticities)?;
    let m = space.from_xyz_matrix();
    let metric = RgbMetric::new(&space);
    let envmap = header.envmap.map(|e| match e {
        EnvmapAttr::LatLong => Layout::LatLong,
        EnvmapAttr::Cube => Layout::Cube,
    });
    let layout = detect(width, height, envmap).ok();
    let solid = layout.and_then(|l| EnvMap::new(l, RgbImage::new(width, height)).ok());
    let sun = crate::envmap::files::read_stored_channel(path, "sun");
    let bands = wavelengths.len();
    let (mut all, mut no_sun) = (
        RoundTripAccumulator::default(),
        RoundTripAccumulator::default(),
    );
    let mut sun_pixels = 0;
    let mut non_finite_pixels = 0;
    let mut missing_rgb = false;
    if let Some(h) = heatmap.as_deref_mut() {
        h.clear();
        h.resize(width * height, f32::NAN);
    }
    let info = read_spectral_rows(path, |y, row| {
        let per = row.len() / width.max(1);
        if per < bands + 3 {
            missing_rgb = true;
            return;
        }
        for x in 0..width {
            let p = &row[x * per..(x + 1) * per];
            let (mut xx, mut yy, mut zz) = (0.0, 0.0, 0.0);
            for i in 0..bands {
                let v = p[i] as f64 * weights[i];
                xx += v * xb[i];
                yy += v * yb[i];
                zz += v * zb[i];
            }
            let xyz = nalgebra::Vector3::new(xx, yy, zz) / y_norm;
            let mut back: [f64; 3] = (m * xyz).into();
            if let Some(t) = white_balance {
                for k in 0..3 {
                    back[k] /= t[k];
                }
            }
            let input = [p[bands], p[bands + 1], p[bands + 2]];
            if !(back.iter().all(|v| v.is_finite()) && input.iter().all(|v| v.is_finite())) {
                non_finite_pixels += 1;
                continue;
            }
            let lum = metric.luminance(input);
            let de = if lum > 0.0 {
                metric.round_trip_error(input, back)
            } else {
                0.0
            };
            let omega = solid.as_ref().map(|s| s.solid_angle(x, y)).unwrap_or(1.0);
            let i = y * width + x;
            all.add(x, y, lum, omega, de);
            if sun.as_ref().is_some_and(|s| s[i] > 0.5) {
                sun_pixels += 1;
            } else {
                no_sun.add(x, y, lum, omega, de);
            }
            if let Some(h) = heatmap.as_deref_mut().filter(|_| lum > 0.0 && omega > 0.0) {
                h[i] = de as f32;
            }
        }
    })?;
    if missing_rgb || !info.has_rgb {
        return Err(Error::invalid(format!(
            "{}: the file has no R, G, B channels to compare the spectra with",
            path.display()
        )));
    }
    let floor = all.floor();
    Ok(FileRoundTrip {
        file: path.display().to_string(),
        width,
        height,
        layout,
        wavelengths: bands,
        range_nm: [wavelengths[0], wavelengths[bands - 1]],
        space: space.name.to_string(),
        chromaticities: space.chromaticities(),
        white_balance,
        floor,
        all: all.stats(&floor),
        without_sun: no_sun.stats(&floor),
        sun_pixels,
        non_finite_pixels,
    })
}
