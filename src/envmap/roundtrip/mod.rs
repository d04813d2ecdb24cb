//! `roundtrip`: re-read a spectral OpenEXR, integrate its spectra back to RGB and compare them
//! with the file's own R, G, B preview (the original pixels), pixel by pixel, streaming.

pub mod heatmap;
pub(crate) mod metric;
pub mod stats;

use crate::colorimetry::{Chromaticities, Observer, RgbSpace};
use crate::envmap::files::{read_spectral_rows, AttrValue, EnvmapAttr, SpectralInfo};
use crate::envmap::layout::{detect, EnvMap, Layout};
use crate::envmap::roundtrip::metric::RgbMetric;
use crate::envmap::roundtrip::stats::{Floor, RoundTripAccumulator, RoundTripStats, Sample};
use crate::envmap::RgbImage;
use crate::error::{Error, Result};
use crate::spectrum::{Interpolation, Rule, Tabulated, WavelengthGrid};
use std::path::Path;

/// The result of a file round trip.
#[derive(Debug, Clone, serde::Serialize)]
pub struct FileRoundTrip {
    /// The file's path, as given.
    pub file: String,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// The map's layout (its `envmap` attribute, else told from its size); None: neither tells it,
    /// and every pixel weighs the same.
    pub layout: Option<Layout>,
    /// Number of spectral bands.
    pub wavelengths: usize,
    /// Wavelengths of the first and last band (nm).
    pub range_nm: [f64; 2],
    /// The space of the R, G, B channels (its `chromaticities`, else `specmap.space`).
    pub space: String,
    /// That space's primaries and white (CIE 1931 xy).
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
    /// Pixels marked in the `sun` channel (0 when the file has none).
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
    heatmap: Option<&mut Vec<f32>>,
) -> Result<FileRoundTrip> {
    let header = checked_header(path)?;
    let wavelengths = header.wavelengths_nm.clone();
    let (width, height) = (header.width, header.height);
    let integration = Integration::new(&wavelengths, observer, rule)?;
    let (named, white_balance) = preview_attributes(&header.attributes);
    let space = preview_space(path, named, header.chromaticities)?;
    let layout = detect(width, height, header.envmap.map(layout_of)).ok();
    let comparison = Comparison {
        back: BackToRgb {
            integration,
            m: space.from_xyz_matrix(),
            white_balance,
        },
        metric: RgbMetric::new(&space),
        solid: layout.and_then(|l| EnvMap::new(l, RgbImage::new(width, height)).ok()),
        sun: crate::envmap::files::read_stored_channel(path, "sun"),
        width,
        bands: wavelengths.len(),
    };
    let tally = compare_file(path, &comparison, heatmap, width * height)?;
    let floor = tally.all.floor();
    let bands = wavelengths.len();
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
        all: tally.all.stats(&floor),
        without_sun: tally.no_sun.stats(&floor),
        sun_pixels: tally.sun_pixels,
        non_finite_pixels: tally.non_finite_pixels,
    })
}

/// The header once: size, the checked wavelengths (positive, each once, sorted) and the
/// attributes; the pixels follow in read_spectral_rows. A round trip needs two bands at least.
fn checked_header(path: &Path) -> Result<SpectralInfo> {
    let header = crate::envmap::files::read_spectral_info(path)?;
    if header.wavelengths_nm.len() < 2 {
        return Err(Error::invalid(format!(
            "{}: a round trip needs at least two S0.<wavelength>nm channels",
            path.display()
        )));
    }
    Ok(header)
}

/// The layout an `envmap` attribute names.
fn layout_of(attribute: EnvmapAttr) -> Layout {
    match attribute {
        EnvmapAttr::LatLong => Layout::LatLong,
        EnvmapAttr::Cube => Layout::Cube,
    }
}

/// The space `specmap.space` names and the white balance `specmap.lightRGB` holds, if present.
fn preview_attributes(attributes: &[(String, AttrValue)]) -> (Option<RgbSpace>, Option<[f64; 3]>) {
    let mut named = None;
    let mut white_balance = None;
    for (name, value) in attributes {
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
    (named, white_balance)
}

/// The colour matching functions at a file's wavelengths and the quadrature weights of its
/// bands.
struct Integration {
    xb: Vec<f64>,
    yb: Vec<f64>,
    zb: Vec<f64>,
    weights: Vec<f64>,
    /// The Y of a flat spectrum of 1: the normalisation of the integrals.
    y_norm: f64,
}

impl Integration {
    /// CMFs at the file's wavelengths, with the rule's weights (non-uniform grids: trapezoid).
    fn new(wavelengths: &[f64], observer: Observer, rule: Rule) -> Result<Integration> {
        let cmf_table = crate::data::Table::builtin(observer.table_name())?;
        let (xb, yb, zb) = (
            cmf_at(&cmf_table, "x", wavelengths)?,
            cmf_at(&cmf_table, "y", wavelengths)?,
            cmf_at(&cmf_table, "z", wavelengths)?,
        );
        let weights = band_weights(wavelengths, rule)?;
        let y_norm: f64 = yb.iter().zip(&weights).map(|(y, w)| y * w).sum();
        Ok(Integration {
            xb,
            yb,
            zb,
            weights,
            y_norm,
        })
    }

    /// The XYZ of a pixel's bands (the first `weights.len()` values of `p`).
    fn xyz(&self, p: &[f32]) -> nalgebra::Vector3<f64> {
        let (mut xx, mut yy, mut zz) = (0.0, 0.0, 0.0);
        for (i, &value) in p[..self.weights.len()].iter().enumerate() {
            let v = value as f64 * self.weights[i];
            xx += v * self.xb[i];
            yy += v * self.yb[i];
            zz += v * self.zb[i];
        }
        nalgebra::Vector3::new(xx, yy, zz) / self.y_norm
    }
}

/// One colour matching function (`col` of the observer's table) at `wavelengths`.
fn cmf_at(cmf_table: &crate::data::Table, col: &str, wavelengths: &[f64]) -> Result<Vec<f64>> {
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
}

/// The rule's weights on a uniform grid, trapezoid weights on a non-uniform one.
fn band_weights(wavelengths: &[f64], rule: Rule) -> Result<Vec<f64>> {
    Ok(
        match Tabulated::new(wavelengths.to_vec(), vec![0.0; wavelengths.len()])?.uniform_step_nm()
        {
            Some(step) => rule.weights(wavelengths.len(), step),
            None => trapezoid_weights(wavelengths),
        },
    )
}

/// Trapezoid weights on a non-uniform grid.
fn trapezoid_weights(wavelengths: &[f64]) -> Vec<f64> {
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

/// Spectra back to the preview's RGB: integrated, to the space, divided by the white balance.
struct BackToRgb {
    integration: Integration,
    m: nalgebra::Matrix3<f64>,
    white_balance: Option<[f64; 3]>,
}

impl BackToRgb {
    /// The RGB of a pixel's bands.
    fn rgb(&self, p: &[f32]) -> [f64; 3] {
        let xyz = self.integration.xyz(p);
        let mut back: [f64; 3] = (self.m * xyz).into();
        if let Some(t) = self.white_balance {
            for k in 0..3 {
                back[k] /= t[k];
            }
        }
        back
    }
}

/// What a pixel's comparison needs: the way back to RGB, the metric, the solid angles (None
/// for an unknown layout) and the `sun` channel (None when the file has none).
struct Comparison {
    back: BackToRgb,
    metric: RgbMetric,
    solid: Option<EnvMap>,
    sun: Option<Vec<f32>>,
    width: usize,
    bands: usize,
}

/// What the comparison gathers while the rows stream by.
struct Tally<'a> {
    all: RoundTripAccumulator,
    no_sun: RoundTripAccumulator,
    sun_pixels: usize,
    non_finite_pixels: usize,
    /// A row had fewer values per pixel than the bands and R, G, B.
    missing_rgb: bool,
    heatmap: Option<&'a mut Vec<f32>>,
}

/// Streams the file's rows through the comparison; an error when it has no R, G, B.
fn compare_file<'a>(
    path: &Path,
    comparison: &Comparison,
    mut heatmap: Option<&'a mut Vec<f32>>,
    pixels: usize,
) -> Result<Tally<'a>> {
    if let Some(h) = heatmap.as_deref_mut() {
        h.clear();
        h.resize(pixels, f32::NAN);
    }
    let mut tally = Tally {
        all: RoundTripAccumulator::default(),
        no_sun: RoundTripAccumulator::default(),
        sun_pixels: 0,
        non_finite_pixels: 0,
        missing_rgb: false,
        heatmap,
    };
    let info = read_spectral_rows(path, |y, row| comparison.row(y, row, &mut tally))?;
    if tally.missing_rgb || !info.has_rgb {
        return Err(Error::invalid(format!(
            "{}: the file has no R, G, B channels to compare the spectra with",
            path.display()
        )));
    }
    Ok(tally)
}

impl Comparison {
    /// Compares the pixels of row `y` (bands then R, G, B per pixel).
    fn row(&self, y: usize, row: &[f32], tally: &mut Tally) {
        let per = row.len() / self.width.max(1);
        if per < self.bands + 3 {
            tally.missing_rgb = true;
            return;
        }
        for x in 0..self.width {
            self.pixel(x, y, &row[x * per..(x + 1) * per], tally);
        }
    }

    /// Compares pixel (x, y): its bands back to RGB against its R, G, B.
    fn pixel(&self, x: usize, y: usize, p: &[f32], tally: &mut Tally) {
        let bands = self.bands;
        let back = self.back.rgb(p);
        let input = [p[bands], p[bands + 1], p[bands + 2]];
        if !(back.iter().all(|v| v.is_finite()) && input.iter().all(|v| v.is_finite())) {
            tally.non_finite_pixels += 1;
            return;
        }
        let lum = self.metric.luminance(input);
        let de = if lum > 0.0 {
            self.metric.round_trip_error(input, back)
        } else {
            0.0
        };
        let omega = self
            .solid
            .as_ref()
            .map(|s| s.solid_angle(x, y))
            .unwrap_or(1.0);
        let i = y * self.width + x;
        let sample = Sample::new(x, y, lum, omega, de);
        tally.all.add_sample(&sample);
        if self.sun.as_ref().is_some_and(|s| s[i] > 0.5) {
            tally.sun_pixels += 1;
        } else {
            tally.no_sun.add_sample(&sample);
        }
        if let Some(h) = tally
            .heatmap
            .as_deref_mut()
            .filter(|_| lum > 0.0 && omega > 0.0)
        {
            h[i] = de as f32;
        }
    }
}
