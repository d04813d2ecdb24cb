//! The plan's file: the form written (spectral, or the basis form factored from a spectral
//! intermediate), its precision and EV scale, compression and header attributes, and where.

use crate::envmap::convert::analyse::Analysis;
use crate::envmap::convert::measure::Measured;
use crate::envmap::convert::options::mode_name;
use crate::envmap::convert::options::{ConvertOptions, OutputFormat};
use crate::envmap::convert::pixel_spectra::WhitePremise;
use crate::envmap::convert::pixels::PixelPlan;
use crate::envmap::convert::planning::SpectraPlan;
use crate::envmap::convert::sun_report::SunReport;
use crate::envmap::files::{AttrValue, Compression, Precision, HALF_MAX};
use std::path::{Path, PathBuf};

/// What is written, where and how.
#[derive(Debug, Clone, serde::Serialize)]
pub struct FilePlan {
    /// The file written (None: nothing is, as `inspect` plans).
    pub path: Option<PathBuf>,
    /// The file's form and precision.
    pub output: Output,
    #[serde(serialize_with = "compression_name")]
    /// The OpenEXR compression of every block.
    pub compression: Compression,
    /// The zlib level of ZIP/ZIPS.
    pub zip_level: u8,
    /// The header's attributes (besides OpenEXR's own and the spectral layout's).
    #[serde(serialize_with = "attributes_json")]
    pub attributes: Vec<(String, AttrValue)>,
}

/// The form of the file.
#[derive(Debug, Clone, serde::Serialize)]
#[serde(tag = "form", rename_all = "lowercase")]
pub enum Output {
    /// One channel per wavelength (Fichet et al. 2021), R, G, B previews and a sun mask, in the
    /// precision and EV scale the map's spectra need.
    Spectral {
        /// The precision and EV scale decided for the spectra.
        precision: Precisions,
    },
    /// The spectral form written first, as float without an EV scale, at `intermediate` (None:
    /// nothing is written), then factored into K spectra of its own (see [`super::basis_form`]),
    /// written in `precision` with an EV scale chosen from the coefficients' bound.
    Basis {
        /// Where the spectral form is written first (None: nothing is written).
        intermediate: Option<PathBuf>,
        /// The basis form's precision (its EV scale follows from the coefficients).
        precision: Precision,
    },
}

/// Plans the file of a conversion whose spectra are planned (`s`) for the map as written.
pub(crate) fn plan_file(
    analysis: &Analysis,
    s: &SpectraPlan,
    opts: &ConvertOptions,
    measured: Option<&Measured>,
    path: Option<&Path>,
    notes: &mut Vec<String>,
) -> FilePlan {
    let output = match opts.format {
        OutputFormat::Spectral => {
            let precision = spectral_precision(measured, opts.precision);
            notes.extend(precision.reason.clone());
            if precision.below_half > 0 {
                notes.push(format!(
                    "{} pixels are darker than half floats hold (below 3e-8 in every value): \
                     written as 0 (--precision float keeps them)",
                    precision.below_half
                ));
            }
            Output::Spectral { precision }
        }
        OutputFormat::Basis => Output::Basis {
            intermediate: path.map(intermediate),
            precision: opts.precision,
        },
    };
    FilePlan {
        path: path.map(Path::to_path_buf),
        output,
        compression: opts.compression,
        zip_level: opts.zip_level,
        attributes: attributes(analysis, s),
    }
}

impl Precisions {
    /// Float, as asked or as the basis form's intermediate is written: no EV scale.
    pub fn float() -> Precisions {
        Precisions {
            precision: Precision::Float,
            ev: None,
            below_half: 0,
            reason: None,
        }
    }
}

/// A compression by its name, as the report gives it (`zip`, `piz`...).
fn compression_name<S: serde::Serializer>(
    c: &Compression,
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    s.serialize_str(&format!("{c:?}").to_lowercase())
}

/// Attributes as a JSON object (text, numbers, float vectors, chromaticities).
fn attributes_json<S: serde::Serializer>(
    attributes: &[(String, AttrValue)],
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut map = s.serialize_map(Some(attributes.len()))?;
    for (name, value) in attributes {
        match value {
            AttrValue::Text(t) => map.serialize_entry(name, t)?,
            AttrValue::F64(v) => map.serialize_entry(name, v)?,
            AttrValue::F32(v) => map.serialize_entry(name, v)?,
            AttrValue::I32(v) => map.serialize_entry(name, v)?,
            AttrValue::F32Vec(v) => map.serialize_entry(name, v)?,
            AttrValue::Chromaticities(c) => map.serialize_entry(name, c)?,
        }
    }
    map.end()
}

/// What the EV scale and the precision came to.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Precisions {
    /// Half or float.
    pub precision: Precision,
    /// Values were divided by 2^EV to fit half floats (None: not needed).
    pub ev: Option<f64>,
    /// Pixels whose every value is below half's smallest (written as 0 in half at any EV).
    pub below_half: usize,
    /// Why the precision is what it is, when it is not what was asked.
    pub reason: Option<String>,
}

/// The EV scale for half floats from the measure of every value written (`measured`; None
/// where float was asked): its peak, and how many pixels an EV scale would flush to zero. A
/// scale that would flush pixels that half holds unscaled makes the file float instead (nothing
/// is lost silently).
fn spectral_precision(measured: Option<&Measured>, asked: Precision) -> Precisions {
    let Some(m) = measured.filter(|_| asked != Precision::Float) else {
        return Precisions::float();
    };
    let peak = m.peak;
    // Half's smallest subnormal is 2^-24: values below 2^-25 round to 0.
    let flushed = |ev: i32| m.pixels_below(ev - 25);
    let below_half = flushed(0);
    let ev = (peak as f64 > HALF_MAX as f64).then(|| (peak as f64 / HALF_MAX as f64).log2().ceil());
    match ev {
        Some(e) if flushed(e as i32) > below_half => Precisions {
            precision: Precision::Float,
            ev: None,
            below_half: 0,
            reason: Some(format!(
                "half floats would need values / 2^{e} (EV), which would flush {} more pixels \
                 to zero: written as float instead",
                flushed(e as i32) - below_half
            )),
        },
        _ => Precisions {
            precision: asked,
            ev,
            below_half,
            reason: None,
        },
    }
}

/// The header attributes: the fit, the premises, the lights.
fn attributes(analysis: &Analysis, s: &SpectraPlan) -> Vec<(String, AttrValue)> {
    let fit = &s.fit;
    let text = |k: &str, v: String| (k.to_string(), AttrValue::Text(v));
    let floats = |k: &str, v: Vec<f32>| (k.to_string(), AttrValue::F32Vec(v));
    let premise = analysis.white.premise;
    let balance = match &s.pixels {
        PixelPlan::Basis { engine, .. } => engine.white_balance(),
        PixelPlan::Carriers { engine, .. } => engine.white_balance(),
    };
    let mut attributes = vec![
        text("specmap.version", env!("CARGO_PKG_VERSION").into()),
        text("specmap.light", analysis.light.clone()),
        text("specmap.mode", mode_name(s.method, fit.mode)),
        text("specmap.space", fit.space.clone()),
        (
            "chromaticities".into(),
            AttrValue::Chromaticities(fit.rgb_space().chromaticities()),
        ),
        text("specmap.observer", fit.observer.table_name().into()),
        text("specmap.basis", fit.basis.join(",")),
        floats("specmap.weights", fit.weights.map(|v| v as f32).to_vec()),
        floats(
            "specmap.matrix",
            fit.matrix.iter().flatten().map(|&v| v as f32).collect(),
        ),
        floats("specmap.lightRGB", balance.map(|v| v as f32).to_vec()),
        text(
            "specmap.white",
            match premise {
                WhitePremise::Light => "light",
                WhitePremise::Space => "space",
            }
            .into(),
        ),
        text("specmap.radiometry", radiometry(premise).into()),
        text(
            "specmap.sun",
            serde_json::to_string(&SunReport::of(&analysis.scene)).unwrap_or_default(),
        ),
        text(
            "specmap.lights",
            serde_json::to_string(&analysis.scene.lights).unwrap_or_default(),
        ),
    ];
    // OpenEXR text attributes are bytes that readers decode as UTF-8 or Latin-1: keep them ASCII.
    for (_, v) in attributes.iter_mut() {
        if let AttrValue::Text(t) = v {
            *t = t
                .chars()
                .map(|c| if c.is_ascii() { c } else { '?' })
                .collect();
        }
    }
    attributes
}

fn radiometry(premise: WhitePremise) -> &'static str {
    match premise {
        WhitePremise::Light => {
            "relative radiance; Y = sum(L ybar) / sum(ybar); RGB (1,1,1) is the main light's SPD \
             at Y = 1"
        }
        WhitePremise::Space => {
            "relative radiance; Y = sum(L ybar) / sum(ybar); RGB (1,1,1) is the RGB space's white \
             (the chromaticities attribute's) at Y = 1; \
             each light's SPD has Y = 1"
        }
    }
}

/// A path beside `output` for the spectral form a basis form is factored from.
fn intermediate(output: &Path) -> PathBuf {
    let name = output
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut k = std::process::id();
    loop {
        let p = output.with_file_name(format!(".{name}.spectral-{k}.exr"));
        if !p.exists() {
            return p;
        }
        k = k.wrapping_add(1);
    }
}
