//! RGB environment map -> spectral environment map: read, sanitise, resample, find the sun,
//! choose the main light, fit, and stream the spectral OpenEXR out block by block.

use crate::colorimetry::{Observer, RgbSpace};
use crate::data;
use crate::envmap::engine::{Engine, Model, PixelKind, SunSource, Took, WhitePremise};
use crate::envmap::exrio::{
    self, spectral_channel_name, AttrValue, ChannelSet, Compression, EnvmapAttr, Precision,
    SpectralLayout, SpectralWriter, HALF_MAX,
};
use crate::envmap::layout::{detect, EnvMap, Layout, Orientation};
use crate::envmap::light::{self, LightChoice, WhiteChoice};
use crate::envmap::planes::{self, RowMut, SpectralRows};
use crate::envmap::sun::{find_sun, SunSearch, SunSettings};
use crate::error::{Error, Result};
use crate::fit::{self, Fit, FitInput, Mode};
use crate::illuminant;
use crate::spectrum::{Rule, Tabulated, WavelengthGrid};
use crate::tradeoff::{choose_grid, colorchecker_under, GridChoice};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The main light: a spectrum name, or chosen from the scene.
#[derive(Debug, Clone, PartialEq)]
pub enum LightSpec {
    Named(String),
    Auto,
}

/// The SPD given to the sun's pixels.
#[derive(Debug, Clone, PartialEq)]
pub enum SunSpd {
    /// CIE D65, as in the paper.
    D65,
    /// The member of the CIE daylight family (S0, S1, S2) whose colour is the sun pixels' mean
    /// colour, exactly (a low sun is not D65).
    Daylight,
    /// Daylight (or a Planckian radiator below 4000 K) at the sun pixels' CCT.
    Match,
    /// Any light by name.
    Light(String),
}

/// How pixels become spectra.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// The default: the sun as the daylight that has its colour, daylight-coloured sky pixels as
    /// CIE daylight, everything else as the main light times a smooth modulation; RGB taken as
    /// D65-referenced unless the scene says it is white-balanced to its light.
    Faithful,
    /// The paper's: every pixel on the ColorChecker basis of the fit's mode (paper, exact,
    /// nonneg), the sun given D65, RGB white-balanced to the main light.
    Basis,
}

/// What RGB (1,1,1) is (see [`WhitePremise`]), or chosen from the scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WhiteSpec {
    Light,
    D65,
    /// The brightest regions decide (see [`light::choose_white`]).
    Auto,
}

/// The spectra of daylight-coloured sky pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SkySpd {
    /// Members of the CIE daylight family (S0, S1, S2), exact in RGB.
    Daylight,
    /// As any other pixel (the main light's basis).
    Light,
}

/// The most bytes of f32 rows computed before they are written (one batch; the writer's blocks
/// and their compressed form come on top, about as much again).
const BATCH_BYTES: usize = 96 << 20;

/// What is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum OutputFormat {
    /// One channel per wavelength (Fichet et al. 2021), R, G, B previews and a sun mask.
    Spectral,
    /// Four channels (c_R, c_G, c_B, sun) and the basis spectra in the header.
    Basis,
}

/// Everything a conversion needs besides its input and output paths.
#[derive(Debug, Clone)]
pub struct ConvertOptions {
    pub light: LightSpec,
    /// A fit from `specmap fit -o`; otherwise the basis is fitted on the output grid.
    pub fit: Option<Fit>,
    /// The fit's mode: the ColorChecker basis of [`Method::Basis`], and the fallback of
    /// [`Method::Faithful`] where the smooth modulation would go negative.
    pub mode: Mode,
    pub method: Method,
    /// None: the method's default (faithful: auto; basis: light, or auto with `--light auto`).
    pub white: Option<WhiteSpec>,
    /// None: the method's default (faithful: daylight; basis: light).
    pub sky: Option<SkySpd>,
    pub space: RgbSpace,
    pub basis: [String; 3],
    pub observer: Observer,
    pub rule: Rule,
    /// None: no sun detection.
    pub sun: Option<SunSettings>,
    /// None: the method's default (faithful: daylight; basis: D65).
    pub sun_spd: Option<SunSpd>,
    /// Overrides the layout found from the `envmap` attribute or the aspect ratio.
    pub in_layout: Option<Layout>,
    /// The input is a pattern with `{face}` naming six face files.
    pub faces: bool,
    /// A named layer of the input (`<layer>.R`...).
    pub layer: Option<String>,
    /// None: the input's layout.
    pub out_layout: Option<Layout>,
    /// Output face size (cube-like) or height (lat-long); None: matched to the input.
    pub size: Option<usize>,
    /// How the input's directions relate to OpenEXR's (Y up): a Z-up map or a turn about the
    /// up axis. Anything but the identity resamples the map into OpenEXR's orientation.
    pub orientation: Orientation,
    pub grid: WavelengthGrid,
    pub format: OutputFormat,
    pub precision: Precision,
    pub compression: Compression,
    /// The zlib level of ZIP/ZIPS (OpenEXR's default 4; 1 is fastest, 12 smallest).
    pub zip_level: u8,
    /// Choose the coarsest wavelength step within `grid`'s range whose colours stay within this
    /// CIEDE2000 of a 1 nm reference (see [`crate::tradeoff`]).
    pub tolerance: Option<f64>,
    /// NaN or infinite pixels are an error instead of being set to 0.
    pub strict: bool,
}

impl ConvertOptions {
    /// The command line's default: the faithful method (see [`Method::Faithful`]).
    pub fn faithful() -> Self {
        ConvertOptions {
            method: Method::Faithful,
            ..ConvertOptions::default()
        }
    }
}

/// The library's default stays the paper's basis method in exact mode (D65 sun, light premise):
/// its spectra lie in the span of the ColorChecker basis and the sun's SPD, which is what the
/// renderer's spectral loader (`render::env`) projects onto. The CLI's default is
/// [`ConvertOptions::faithful`].
impl Default for ConvertOptions {
    fn default() -> Self {
        ConvertOptions {
            light: LightSpec::Named("D65".into()),
            fit: None,
            mode: Mode::Exact,
            method: Method::Basis,
            white: None,
            sky: None,
            space: RgbSpace::SRGB,
            basis: fit::PAPER_BASIS.map(String::from),
            observer: Observer::Cie1931,
            rule: Rule::Riemann,
            sun: Some(SunSettings::default()),
            sun_spd: None,
            in_layout: None,
            faces: false,
            layer: None,
            out_layout: None,
            size: None,
            orientation: Orientation::default(),
            grid: "380:780:5".parse().expect("a valid grid"),
            format: OutputFormat::Spectral,
            precision: Precision::Half,
            compression: Compression::Zip,
            zip_level: crate::envmap::exrio::ZIP_DEFAULT_LEVEL,
            tolerance: None,
            strict: false,
        }
    }
}

/// Pixels changed to make the input usable.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct Sanitized {
    /// NaN or infinite channel values set to 0.
    pub non_finite: usize,
    /// Negative channel values (lossy compression leaves small ones) set to 0.
    pub negative: usize,
    /// Negative channel values kept: under the D65 premise a pixel of positive luminance with a
    /// negative channel is a colour outside the RGB gamut (sodium light), which the spectrum can
    /// carry.
    pub negative_kept: usize,
}

/// How many pixels got which spectrum.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct SpectraCount {
    pub sun: usize,
    /// CIE daylight family (daylight-coloured sky).
    pub daylight: usize,
    /// Main light x smooth modulation.
    pub smooth: usize,
    /// Main light x ColorChecker basis.
    pub colorchecker: usize,
    /// Pixels whose spectrum goes below zero somewhere (the RGB round trip stays exact).
    pub negative: usize,
}

impl SpectraCount {
    fn add(&mut self, took: Took, negative: bool) {
        match took {
            Took::Sun => self.sun += 1,
            Took::Daylight => self.daylight += 1,
            Took::Smooth => self.smooth += 1,
            Took::Colorchecker => self.colorchecker += 1,
        }
        self.negative += negative as usize;
    }
    fn merge(&mut self, o: &SpectraCount) {
        self.sun += o.sun;
        self.daylight += o.daylight;
        self.smooth += o.smooth;
        self.colorchecker += o.colorchecker;
        self.negative += o.negative;
    }
}

/// RGB -> SPD -> RGB over the written pixels.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct RoundTripStats {
    /// Energy-weighted (luminance x solid angle) mean CIEDE2000.
    pub weighted_mean_de2000: f64,
    pub max_de2000: f64,
    pub pixels: usize,
}

/// What a conversion did.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ConvertReport {
    pub input: String,
    pub input_description: String,
    pub input_layout: Layout,
    pub input_size: [usize; 2],
    pub output: String,
    pub output_layout: Layout,
    pub output_size: [usize; 2],
    pub format: OutputFormat,
    pub precision: &'static str,
    pub compression: String,
    /// Values were divided by 2^EV to fit half floats (None: not needed).
    pub ev: Option<f64>,
    pub sanitized: Sanitized,
    pub sun: SunSearch,
    pub sun_spd: Option<String>,
    pub light: String,
    pub light_choice: Option<LightChoice>,
    pub method: Method,
    /// What RGB (1,1,1) was taken to be, and why.
    pub white: WhiteChoice,
    pub sky: SkySpd,
    /// The smooth modulation was used (faithful method, a light that can carry every colour).
    pub smooth: bool,
    pub spectra: SpectraCount,
    /// What the conversion could not do as asked, in words.
    pub notes: Vec<String>,
    pub mode: Mode,
    pub weights: [f64; 3],
    pub condition_number: f64,
    pub regularized: bool,
    pub wavelengths_nm: Vec<f64>,
    pub channels: usize,
    pub bytes: u64,
    /// Over all pixels, and over those not replaced by the sun's SPD.
    pub roundtrip: RoundTripStats,
    pub roundtrip_without_sun: RoundTripStats,
    pub seconds_read: f64,
    pub seconds_convert: f64,
    /// The part of `seconds_convert` spent encoding and compressing the EXR blocks.
    pub seconds_encode: f64,
    /// What `--tolerance` chose (None: the grid was given).
    pub grid_choice: Option<GridChoice>,
    pub megapixels_per_second: f64,
}

/// Reads the input map (one file or six face files) with its layout.
fn read_input(input: &str, opts: &ConvertOptions) -> Result<(EnvMap, String)> {
    if opts.faces || input.contains("{face}") {
        let faces = exrio::read_faces(input, opts.layer.as_deref())?;
        let map = EnvMap::from_faces(faces)?;
        return Ok((map, format!("six face files {input}")));
    }
    let img = exrio::read_rgb(Path::new(input), opts.layer.as_deref())?;
    let attr = img.envmap.map(|a| match a {
        EnvmapAttr::LatLong => Layout::LatLong,
        EnvmapAttr::Cube => Layout::Cube,
    });
    let layout = match opts.in_layout {
        Some(l) => l,
        None => detect(img.image.width, img.image.height, attr)
            .map_err(|e| Error::invalid(format!("{input}: {e}")))?,
    };
    let map =
        EnvMap::new(layout, img.image).map_err(|e| Error::invalid(format!("{input}: {e}")))?;
    Ok((map, img.description))
}

/// A pixel index and its RGB before negatives were clamped.
type OutOfGamut = (usize, [f32; 3]);

/// Sets NaN/infinite values to 0 (or refuses them) and clamps negatives, counting both. Pixels of
/// positive luminance with a negative channel (out-of-gamut colours) are returned as they were,
/// to be restored under the D65 premise.
fn sanitize(
    map: &mut EnvMap,
    strict: bool,
    input: &str,
    space: &RgbSpace,
) -> Result<(Sanitized, Vec<OutOfGamut>)> {
    let mut s = Sanitized::default();
    let m = space.to_xyz_matrix();
    let mut out_of_gamut = Vec::new();
    let width = map.image.width;
    for (i, p) in map.image.pixels.iter_mut().enumerate() {
        if p.iter().all(|v| v.is_finite()) && p.iter().any(|&v| v < 0.0) {
            let y = (0..3).map(|k| m[(1, k)] * p[k] as f64).sum::<f64>();
            if y > 0.0 {
                out_of_gamut.push((i, *p));
            }
        }
        for (c, v) in p.iter_mut().enumerate() {
            if !v.is_finite() {
                if strict {
                    return Err(Error::invalid(format!(
                        "{input}: pixel ({}, {}) channel {} is {v} (--strict refuses NaN and \
                         infinite values)",
                        i % width,
                        i / width,
                        ["R", "G", "B"][c]
                    )));
                }
                *v = 0.0;
                s.non_finite += 1;
            } else if (*v as f64).abs() > MAX_INPUT {
                return Err(Error::invalid(format!(
                    "{input}: pixel ({}, {}) channel {} is {v:e}, beyond {MAX_INPUT:e}: no \
                     radiance map holds that (the sun is about 1e9 cd/m^2); a corrupt or \
                     mis-scaled file? Scale it down first",
                    i % width,
                    i / width,
                    ["R", "G", "B"][c]
                )));
            } else if *v < 0.0 {
                *v = 0.0;
                s.negative += 1;
            }
        }
    }
    Ok((s, out_of_gamut))
}

/// The files a conversion reads: the map (or its six face files, in both spellings of the
/// `{face}` pattern) and the lights given as CSV files (`--light`, `--sun-spd`), that exist.
pub fn input_files(input: &str, opts: &ConvertOptions) -> Vec<PathBuf> {
    let mut files = Vec::new();
    if opts.faces || input.contains("{face}") {
        for (name, signed) in exrio::FACE_NAMES.iter().zip(exrio::FACE_SIGNED) {
            files.push(PathBuf::from(input.replace("{face}", name)));
            files.push(PathBuf::from(input.replace("{face}", signed)));
        }
    } else {
        files.push(PathBuf::from(input));
    }
    let mut spec = |s: &str| {
        files.push(PathBuf::from(s));
        if let Some((table, _)) = s.rsplit_once(':') {
            files.push(PathBuf::from(table));
        }
    };
    if let LightSpec::Named(n) = &opts.light {
        spec(n);
    }
    if let Some(SunSpd::Light(n)) = &opts.sun_spd {
        spec(n);
    }
    files.retain(|f| f.is_file());
    files
}

/// Converts `input` to a spectral (or basis) OpenEXR at `output`. `progress(done, total)` is
/// called after each batch of rows.
pub fn convert(
    input: &str,
    output: &Path,
    opts: &ConvertOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<ConvertReport> {
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
    // Settings that need no input are checked before the work starts; a named sun SPD is
    // loaded here once, for use if a sun is found.
    let mut sun_light = None;
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
        sun_light = Some((s.label, s.data));
    }
    if opts.format == OutputFormat::Spectral && opts.grid.len() > MAX_BANDS {
        return Err(Error::invalid(format!(
            "{} wavelengths would make {} channels per pixel; a spectral EXR here holds at most \
             {MAX_BANDS} bands (0.1 nm over 400 nm): choose a coarser --range step",
            opts.grid.len(),
            opts.grid.len() + 4
        )));
    }
    crate::io::check_output(output)?;
    let t0 = Instant::now();
    let (mut map, description) = read_input(input, opts)?;
    let (mut sanitized, out_of_gamut) = sanitize(&mut map, opts.strict, input, &opts.space)?;
    let input_layout = map.layout;
    let input_size = [map.image.width, map.image.height];
    let seconds_read = t0.elapsed().as_secs_f64();

    // Output layout and size.
    let out_layout = opts.out_layout.unwrap_or(input_layout);
    let in_size = map.face_size();
    let size = opts.size.unwrap_or(match (input_layout, out_layout) {
        (a, b) if a == b => in_size,
        // Matched pixel density: a lat-long 4N wide has about the pixels per radian of faces N.
        (Layout::LatLong, _) => (in_size / 2).max(1),
        (_, Layout::LatLong) => in_size * 2,
        _ => in_size,
    });
    if size == 0 {
        return Err(Error::invalid("--size must be at least 1"));
    }
    let resampled =
        out_layout != input_layout || size != in_size || !opts.orientation.is_identity();
    if resampled {
        map = map.resample_oriented(out_layout, size, &opts.orientation);
    }
    let mut notes = Vec::new();

    let sun = match &opts.sun {
        Some(settings) => find_sun(&map, &opts.space, settings),
        None => SunSearch::NotFound {
            reason: "sun detection is off (--sun off)".into(),
        },
    };

    // The main light.
    let (light_name, light_choice) = match &opts.light {
        LightSpec::Named(n) => (n.clone(), None),
        LightSpec::Auto => {
            let c = light::choose(&map, &sun, &opts.space)?;
            (c.light.clone(), Some(c))
        }
    };
    // The white premise.
    let white_spec = opts.white.unwrap_or(match (opts.method, &opts.light) {
        (Method::Faithful, _) | (Method::Basis, LightSpec::Auto) => WhiteSpec::Auto,
        (Method::Basis, LightSpec::Named(_)) => WhiteSpec::Light,
    });
    let white = match white_spec {
        WhiteSpec::Light => WhiteChoice {
            premise: WhitePremise::Light,
            reason: "--white light: RGB (1,1,1) is the main light (the paper's premise)".into(),
        },
        WhiteSpec::D65 => WhiteChoice {
            premise: WhitePremise::D65,
            reason: "--white d65: RGB (1,1,1) is D65 white".into(),
        },
        WhiteSpec::Auto => light::choose_white(&map, &opts.space, &light_name)?,
    };
    if white.premise == WhitePremise::D65 && !out_of_gamut.is_empty() {
        if resampled {
            notes.push(format!(
                "{} out-of-gamut pixels (negative channels) were set to 0 before resampling",
                out_of_gamut.len()
            ));
        } else {
            for &(i, p) in &out_of_gamut {
                let n = p.iter().filter(|&&v| v < 0.0).count();
                sanitized.negative -= n;
                sanitized.negative_kept += n;
                map.image.pixels[i] = p;
            }
        }
    }
    let sky = opts.sky.unwrap_or(match opts.method {
        Method::Faithful => SkySpd::Daylight,
        Method::Basis => SkySpd::Light,
    });
    let sun_choice = opts.sun_spd.clone().unwrap_or(match opts.method {
        Method::Faithful => SunSpd::Daylight,
        Method::Basis => SunSpd::D65,
    });
    // The sun's SPD.
    let sun_spd: Option<(String, Tabulated)> = match (sun.sun(), &sun_choice) {
        (None, _) => None,
        (Some(_), SunSpd::D65) => Some(("D65".into(), data::spectrum("D65")?.data)),
        (Some(s), SunSpd::Daylight) => {
            // Stands in for the SPD in the grid choice; the engine fits the exact one.
            let k = s.cct.kelvin.unwrap_or(6504.0);
            Some((
                format!("CIE daylight family, the sun's colour (CCT {k:.0} K)"),
                illuminant::natural(k)?,
            ))
        }
        (Some(s), SunSpd::Match) => {
            let k = s.cct.kelvin.unwrap_or(6504.0);
            let label = if k < illuminant::DAYLIGHT_RANGE_K.0 {
                format!("Planckian {k:.0} K")
            } else {
                format!(
                    "CIE daylight {:.0} K",
                    k.min(illuminant::DAYLIGHT_RANGE_K.1)
                )
            };
            Some((label, illuminant::natural(k)?))
        }
        (Some(_), SunSpd::Light(_)) => sun_light,
    };
    // The grid: as given, or the coarsest step within its range that keeps the ColorChecker
    // under the main light (and under the sun's SPD) within --tolerance.
    let grid_choice = match opts.tolerance {
        None => None,
        Some(tolerance) => {
            let light_spd = data::spectrum(&light_name)?;
            let mut stimuli = colorchecker_under(&light_spd.label, &light_spd.data)?;
            if let Some((label, spd)) = &sun_spd {
                stimuli.extend(colorchecker_under(&format!("sun ({label})"), spd)?);
            }
            let (start, end) = (opts.grid.start_nm(), opts.grid.end_nm());
            Some(choose_grid(
                &stimuli,
                opts.observer,
                start,
                end,
                opts.rule,
                tolerance,
            )?)
        }
    };
    let grid = grid_choice.as_ref().map_or(opts.grid, |c| c.chosen);
    let fit = match &opts.fit {
        Some(f) => f.clone(),
        None => {
            let input = FitInput::from_names(
                &light_name,
                opts.basis.each_ref().map(String::as_str),
                &grid,
                opts.observer,
                opts.rule,
                opts.space,
            )?;
            fit::fit(&input, opts.mode)?
        }
    };

    // The basis format holds three ColorChecker coefficients and a sun: the faithful method's
    // daylight sky and smooth modulation need the spectral format.
    let (method, sky) = match (opts.method, opts.format) {
        (Method::Faithful, OutputFormat::Basis) => {
            notes.push(
                "--format basis stores three coefficients on the ColorChecker basis: every \
                 pixel is written in the fit's mode on that basis (the faithful method's \
                 daylight sky and smooth modulation need --format spectral)"
                    .into(),
            );
            (Method::Basis, SkySpd::Light)
        }
        (m, _) => (m, sky),
    };
    let model = Model {
        white: white.premise,
        sky_daylight: sky == SkySpd::Daylight,
        smooth: method == Method::Faithful,
    };
    let sun_source = match (&sun_spd, sun.sun(), &sun_choice) {
        (None, _, _) | (_, None, _) => SunSource::None,
        (Some(_), Some(s), SunSpd::Daylight) => SunSource::DaylightFit(s.mean_rgb),
        (Some((_, t)), _, _) => SunSource::Spd(t),
    };
    let engine = Engine::with_model(&fit, grid, opts.rule, sun_source, model)?;
    if model.sky_daylight && !engine.sky_daylight_active() {
        notes.push(format!(
            "the main light {} is not daylight: sky pixels take its basis as any other",
            fit.light
        ));
    }
    if model.smooth && !engine.smooth_active() {
        notes.push(format!(
            "the main light {} is too narrow for the smooth modulation to carry every colour: \
             its pixels use the ColorChecker basis",
            fit.light
        ));
    }
    let kinds: Vec<PixelKind> = {
        let mut k = vec![PixelKind::Plain; map.image.pixels.len()];
        let width = map.image.width;
        if engine.sky_daylight_active() {
            k.par_iter_mut().enumerate().for_each(|(i, k)| {
                if map
                    .direction(i % width, i / width)
                    .is_some_and(|d| d[1] > 0.0)
                {
                    *k = PixelKind::Sky;
                }
            });
        }
        if sun_spd.is_some() {
            if let Some(s) = sun.sun() {
                for &i in &s.pixels {
                    k[i] = PixelKind::Sun;
                }
            }
        }
        k
    };

    // The channels.
    let wavelengths: Vec<f64> = grid.wavelengths_nm().collect();
    let bands = wavelengths.len();
    let names: Vec<String> = match opts.format {
        OutputFormat::Spectral => wavelengths
            .iter()
            .map(|&w| spectral_channel_name(w))
            .chain(["R", "G", "B", "sun"].map(String::from))
            .collect(),
        OutputFormat::Basis => ["c_R", "c_G", "c_B", "sun"].map(String::from).to_vec(),
    };
    let per_pixel = names.len();

    // Half floats top out at 65504: scale by 2^EV when the largest value would not fit.
    let ev = match opts.precision {
        Precision::Float => None,
        Precision::Half => {
            let bound = value_bound(&map, &engine, &kinds, opts.format);
            (bound > HALF_MAX as f64).then(|| (bound / HALF_MAX as f64).log2().ceil())
        }
    };

    let mut attributes = vec![
        (
            "specmap.version".to_string(),
            AttrValue::Text(env!("CARGO_PKG_VERSION").into()),
        ),
        ("specmap.light".into(), AttrValue::Text(fit.light.clone())),
        (
            "specmap.mode".into(),
            AttrValue::Text(format!("{:?}", fit.mode).to_lowercase()),
        ),
        ("specmap.space".into(), AttrValue::Text(fit.space.clone())),
        (
            "specmap.observer".into(),
            AttrValue::Text(fit.observer.table_name().into()),
        ),
        ("specmap.basis".into(), AttrValue::Text(fit.basis.join(","))),
        (
            "specmap.weights".into(),
            AttrValue::F32Vec(fit.weights.map(|v| v as f32).to_vec()),
        ),
        (
            "specmap.matrix".into(),
            AttrValue::F32Vec(fit.matrix.iter().flatten().map(|&v| v as f32).collect()),
        ),
        (
            "specmap.lightRGB".into(),
            AttrValue::F32Vec(engine.white_balance().map(|v| v as f32).to_vec()),
        ),
        (
            "specmap.white".into(),
            AttrValue::Text(
                match white.premise {
                    WhitePremise::Light => "light",
                    WhitePremise::D65 => "d65",
                }
                .into(),
            ),
        ),
        (
            "specmap.method".into(),
            AttrValue::Text(
                match method {
                    Method::Faithful => "faithful",
                    Method::Basis => "basis",
                }
                .into(),
            ),
        ),
        (
            "specmap.radiometry".into(),
            AttrValue::Text(
                match white.premise {
                    WhitePremise::Light => {
                        "relative radiance; Y = sum(L ybar) / sum(ybar); RGB (1,1,1) is the main \
                         light's SPD at Y = 1"
                    }
                    WhitePremise::D65 => {
                        "relative radiance; Y = sum(L ybar) / sum(ybar); RGB (1,1,1) is D65 \
                         white at Y = 1; the main light's SPD has Y = 1"
                    }
                }
                .into(),
            ),
        ),
        (
            "specmap.sun".into(),
            AttrValue::Text(serde_json::to_string(&sun).unwrap_or_default()),
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
    if opts.format == OutputFormat::Basis {
        attributes.push((
            "specmap.wavelengths".into(),
            AttrValue::F32Vec(wavelengths.iter().map(|&w| w as f32).collect()),
        ));
        for (j, b) in engine.basis_spectra().iter().enumerate() {
            attributes.push((format!("specmap.basis{j}"), AttrValue::F32Vec(b.clone())));
        }
        if let Some(s) = engine.sun_spectrum() {
            attributes.push(("specmap.sunSPD".into(), AttrValue::F32Vec(s.to_vec())));
        }
    }
    let envmap = match map.layout {
        Layout::LatLong => Some(EnvmapAttr::LatLong),
        Layout::Cube => Some(EnvmapAttr::Cube),
        _ => None,
    };
    let (width, height) = (map.image.width, map.image.height);
    let mut writer = SpectralWriter::create(
        output,
        SpectralLayout {
            width,
            height,
            channels: ChannelSet::Custom(names),
            precision: opts.precision,
            compression: opts.compression,
            envmap,
            ev,
            attributes,
            zip_level: opts.zip_level,
        },
    )?;

    // Stream blocks of rows, computed in parallel.
    let t1 = Instant::now();
    // Rows are computed a batch at a time, the next while the writer compresses the last:
    // whole compression blocks, enough for the writer to compress them in parallel, within
    // BATCH_BYTES (of f32 pixels; the coefficient planes of two batches take a third of it).
    let lines = opts.compression.lines_per_block();
    let block_bytes = lines * width * per_pixel * std::mem::size_of::<f32>();
    let blocks = (BATCH_BYTES / block_bytes.max(1)).clamp(1, height.div_ceil(lines));
    let rows_per_block = (blocks * lines).max(16).min(height);
    // The bands as coefficients of the engine's spectra; R, G, B and the sun mask (or the
    // basis format's coefficients) as the channels after them.
    let written_bands = per_pixel - 4;
    let new_batch = || {
        SpectralRows::new(
            engine.spectra_table(),
            written_bands,
            4,
            width,
            rows_per_block,
        )
    };
    let mut planes = [new_batch(), new_batch()];
    let fill = |y: usize, mut row: RowMut| {
        let (mut a, mut b) = (Accumulator::default(), Accumulator::default());
        let mut count = SpectraCount::default();
        // The spectrum itself is only looked at (negative values, the round trip).
        let mut scratch = vec![0f32; bands];
        for x in 0..width {
            let i = y * width + x;
            let rgb = map.image.pixels[i];
            let kind = kinds[i];
            let is_sun = kind == PixelKind::Sun;
            let r = engine.spectrum(rgb, kind, &mut scratch);
            let extra = match opts.format {
                OutputFormat::Spectral => {
                    row.set(x, &r.combination);
                    [rgb[0], rgb[1], rgb[2], is_sun as u8 as f32]
                }
                OutputFormat::Basis => engine.coefficients(rgb, is_sun).map(|c| c as f32),
            };
            for (e, v) in extra.into_iter().enumerate() {
                row.set_extra(e, x, v);
            }
            count.add(r.took, r.negative);
            let back = r.rgb_back;
            let omega = map.solid_angle(x, y);
            let lum = engine.luminance(rgb);
            if lum > 0.0 && omega > 0.0 {
                let de = engine.round_trip_error(rgb, back);
                a.add(de, lum * omega);
                if !is_sun {
                    b.add(de, lum * omega);
                }
            }
        }
        (a, b, count)
    };
    let stats = planes::stream(
        &mut planes,
        height,
        rows_per_block,
        &fill,
        &mut |y0, rows, batch| {
            writer.write_lines(y0, rows, batch)?;
            progress(y0 + rows, height);
            Ok(())
        },
    )?;
    let (mut all, mut no_sun) = (Accumulator::default(), Accumulator::default());
    let mut spectra = SpectraCount::default();
    for (a, b, c) in stats {
        all.merge(&a);
        no_sun.merge(&b);
        spectra.merge(&c);
    }
    let seconds_encode = writer.encode_seconds();
    let bytes = writer.finish()?;
    let seconds_convert = t1.elapsed().as_secs_f64();

    Ok(ConvertReport {
        input: input.to_string(),
        input_description: description,
        input_layout,
        input_size,
        output: output.display().to_string(),
        output_layout: map.layout,
        output_size: [width, height],
        format: opts.format,
        precision: match opts.precision {
            Precision::Half => "half",
            Precision::Float => "float",
        },
        compression: format!("{:?}", opts.compression).to_lowercase(),
        ev,
        sanitized,
        sun_spd: sun_spd.map(|(l, _)| l),
        sun,
        light: fit.light.clone(),
        light_choice,
        method,
        white,
        sky: if engine.sky_daylight_active() {
            SkySpd::Daylight
        } else {
            SkySpd::Light
        },
        smooth: engine.smooth_active(),
        spectra,
        notes,
        mode: fit.mode,
        weights: fit.weights,
        condition_number: fit.condition_number,
        regularized: fit.regularized,
        wavelengths_nm: wavelengths,
        channels: per_pixel,
        bytes,
        roundtrip: all.stats(),
        roundtrip_without_sun: no_sun.stats(),
        grid_choice,
        seconds_read,
        seconds_convert,
        seconds_encode,
        megapixels_per_second: (input_size[0] * input_size[1]) as f64
            / 1e6
            / (seconds_read + seconds_convert),
    })
}

/// An upper bound of the values written (to choose an EV scale for half floats).
fn value_bound(map: &EnvMap, engine: &Engine, kinds: &[PixelKind], format: OutputFormat) -> f64 {
    map.image
        .pixels
        .par_iter()
        .enumerate()
        .map(|(i, &rgb)| {
            let preview = rgb.iter().fold(0f32, |m, &v| m.max(v.abs())) as f64;
            let spectral = match format {
                OutputFormat::Spectral => engine.bound(rgb, kinds[i]),
                OutputFormat::Basis => engine.coefficient_bound(rgb, kinds[i] == PixelKind::Sun),
            };
            spectral.max(preview)
        })
        .reduce(|| 0.0, f64::max)
}

#[derive(Debug, Clone, Copy, Default)]
struct Accumulator {
    weighted: f64,
    weight: f64,
    max: f64,
    pixels: usize,
}

impl Accumulator {
    fn add(&mut self, de: f64, w: f64) {
        self.weighted += de * w;
        self.weight += w;
        self.max = self.max.max(de);
        self.pixels += 1;
    }
    fn merge(&mut self, o: &Accumulator) {
        self.weighted += o.weighted;
        self.weight += o.weight;
        self.max = self.max.max(o.max);
        self.pixels += o.pixels;
    }
    fn stats(&self) -> RoundTripStats {
        RoundTripStats {
            weighted_mean_de2000: if self.weight > 0.0 {
                self.weighted / self.weight
            } else {
                0.0
            },
            max_de2000: self.max,
            pixels: self.pixels,
        }
    }
}

/// The largest input value converted: far above any photograph, far below where spectra
/// (value x basis, in f32) or the half-float EV scale (at most 2^100) overflow.
pub const MAX_INPUT: f64 = 1e18;

/// The most wavelength bands a spectral output holds (0.1 nm over 400 nm): each is a channel of
/// every pixel, and the rows of a batch are held in memory.
pub const MAX_BANDS: usize = 4001;

/// The default output path for an input: `NAME.spectral.exr` beside it.
pub fn default_output(input: &str) -> PathBuf {
    let p = Path::new(input);
    let stem = p
        .file_stem()
        .map(|s| s.to_string_lossy())
        .unwrap_or_default();
    p.with_file_name(format!("{stem}.spectral.exr"))
}
