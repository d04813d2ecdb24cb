//! RGB environment map -> spectral environment map, as a pipeline of named stages:
//! read ([`crate::envmap::convert::read`]: read, sanitise, resample) -> analyse
//! ([`crate::envmap::convert::plan::analyse`]: the scene's lights, the white premise) -> plan
//! ([`crate::envmap::convert::plan::plan`]: every decision as a value) -> write
//! ([`crate::envmap::convert::write`]: stream the spectra block by block).

pub mod basis_form;
pub mod carriers;
pub mod coefficient_rows;
pub mod own_basis;
pub mod pixel_spectra;
pub mod plan;
pub mod read;
pub mod write;

use crate::colorimetry::{Observer, RgbSpace};
use crate::data;
use crate::envmap::convert::pixel_spectra::WhitePremise;
use crate::envmap::convert::plan::{Analysis, PixelPlan, Plan};
use crate::envmap::convert::read::{Sanitized, SpaceChoice};
use crate::envmap::convert::write::{FileSettings, SpectraCount};
use crate::envmap::files::{self, AttrValue, Compression, Precision};
use crate::envmap::layout::{EnvMap, Layout, Orientation};
use crate::envmap::roundtrip::stats::{Floor, RoundTripStats};
use crate::envmap::scene::main_light::{LightChoice, WhiteChoice};
use crate::envmap::scene::sun::SunSettings;
use crate::envmap::scene::{Levels, Light, ReflectorModel, Reflectors, Scene};
use crate::error::{Error, Result};
use crate::fit::{self, Fit, Mode};
use crate::spectrum::{Rule, WavelengthGrid};
use crate::tradeoff::GridChoice;
use std::path::{Path, PathBuf};

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
    /// The RGB space's own white.
    Space,
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

/// What is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum OutputFormat {
    /// One channel per wavelength (Fichet et al. 2021), R, G, B previews and a sun mask.
    Spectral,
    /// Four channels (c_R, c_G, c_B, sun) and the basis spectra in the header.
    Basis,
}

/// Which lights a map is converted with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Lights {
    /// Every light the scene analysis finds: the sun, the sky and windows, each lamp; the
    /// reflectors lit by the mix of lights around them.
    #[default]
    All,
    /// The paper's premise: one main light for every pixel but the sun's.
    One,
}

/// Everything a conversion needs besides its input and output paths.
#[derive(Debug, Clone)]
pub struct ConvertOptions {
    /// `auto`: the scene's lights; a name: the spectrum of the lamps (the sun, sky and windows
    /// keep daylight), or with [`Lights::One`] of every non-sun pixel.
    pub light: LightSpec,
    pub lights: Lights,
    /// How the reflectors' light is estimated (see [`crate::envmap::scene::reflectors`]).
    pub reflectors: ReflectorModel,
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
    /// The input's RGB space when the file declares none (OpenEXR's `chromaticities`; a file
    /// without them is Rec.709 with D65, sRGB), or whatever it declares with
    /// `space_overrides_file`. [`convert`] and [`inspect`] resolve it before the analysis (see
    /// [`crate::envmap::convert::read::SpaceChoice`]).
    pub space: RgbSpace,
    /// `space` was asked for (`--space`, a fit's space): it replaces the file's chromaticities,
    /// with a note when they differ.
    pub space_overrides_file: bool,
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
            light: LightSpec::Auto,
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
            lights: Lights::All,
            reflectors: ReflectorModel::default(),
            fit: None,
            mode: Mode::Exact,
            method: Method::Basis,
            white: None,
            sky: None,
            space: RgbSpace::SRGB,
            space_overrides_file: false,
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
            zip_level: crate::envmap::files::ZIP_DEFAULT_LEVEL,
            tolerance: None,
            strict: false,
        }
    }
}

/// The sun, as the report gives it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SunReport {
    pub found: bool,
    /// Why it is the sun, or why the brightest region is not.
    pub reason: String,
    #[serde(flatten)]
    pub sun: Option<SunFound>,
}

/// A sun found in the map.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SunFound {
    pub pixel_count: usize,
    /// Energy-weighted mean direction (unit vector, OpenEXR's axes: Y up).
    pub direction: [f64; 3],
    pub elevation_deg: f64,
    /// Angle from +Z towards +X (degrees).
    pub azimuth_deg: f64,
    pub solid_angle_sr: f64,
    pub energy_share: f64,
    #[serde(rename = "cct_K")]
    pub cct_k: Option<f64>,
    pub duv: f64,
    /// Pixels at the clip level: the sun's energy is an underestimate, its colour taken from
    /// its unclipped glow.
    pub clipped: bool,
}

impl SunReport {
    pub fn of(scene: &Scene) -> SunReport {
        match scene.sun() {
            Some(s) => SunReport {
                found: true,
                reason: s.reason.clone(),
                sun: Some(SunFound {
                    pixel_count: s.pixels,
                    direction: s.direction,
                    elevation_deg: s.elevation_deg,
                    azimuth_deg: s.direction[0].atan2(s.direction[2]).to_degrees(),
                    solid_angle_sr: s.solid_angle_sr,
                    energy_share: s.energy_share,
                    cct_k: s.cct_k,
                    duv: s.duv,
                    clipped: s.clipped_pixels > 0,
                }),
            },
            None => SunReport {
                found: false,
                reason: scene
                    .bright_reflectors
                    .first()
                    .and_then(|r| r.strip_prefix("no sun: "))
                    .unwrap_or("nothing in the map stands out")
                    .to_string(),
                sun: None,
            },
        }
    }
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
    /// Pixels whose every value is below half's smallest positive value (written as 0).
    pub below_half: usize,
    pub sanitized: Sanitized,
    /// The input's RGB space, and where it comes from.
    pub space: SpaceChoice,
    /// Every light of the scene (see [`crate::envmap::scene::Light`]).
    pub lights: Vec<Light>,
    pub sun: SunReport,
    pub sun_spd: Option<String>,
    /// The main light: every non-sun pixel's with `--lights one` and in the paper's modes; the
    /// dominant light of the scene otherwise (the fit's light).
    pub light: String,
    pub light_choice: Option<LightChoice>,
    /// `faithful`, or the paper's modes `paper`, `exact`, `nonneg`.
    pub mode: String,
    /// `all` (the scene's lights) or `one` (the paper's one main light).
    pub lights_mode: Lights,
    /// What RGB (1,1,1) was taken to be, and why.
    pub white: WhiteChoice,
    pub sky: SkySpd,
    /// The light spectra pixels are carried by, and how many mixes of them reflectors take.
    pub carriers: Vec<String>,
    pub carrier_mixes: usize,
    pub reflectors: ReflectorModel,
    /// Bright regions that are not lights, and why.
    pub bright_reflectors: Vec<String>,
    pub spectra: SpectraCount,
    /// The basis form: how its K spectra hold the conversion's spectra.
    pub basis: Option<crate::envmap::convert::basis_form::BasisStats>,
    /// The round trip over the pixels whose spectrum could not reproduce their colour (the
    /// nearest non-negative spectra, clipped lamp pixels, the paper mode's pixels but white; the
    /// sun aside).
    pub inexact: RoundTripStats,
    /// What the conversion could not do as asked, in words.
    pub notes: Vec<String>,
    pub weights: [f64; 3],
    pub condition_number: f64,
    pub regularized: bool,
    pub wavelengths_nm: Vec<f64>,
    pub channels: usize,
    pub bytes: u64,
    /// The luminance floor of the round-trip statistics (see [`Floor`]).
    pub roundtrip_floor: Floor,
    /// Over all pixels, and over those not replaced by the sun's SPD (see
    /// [`crate::envmap::roundtrip::stats`]: the statistic `specmap roundtrip` reports).
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

/// The analysis and the plan of a conversion, without writing anything (`specmap inspect`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Inspection {
    pub input: String,
    pub input_description: String,
    pub input_layout: Layout,
    pub input_size: [usize; 2],
    pub sanitized: Sanitized,
    /// Every light of the scene (as `convert --json` has them).
    pub lights: Vec<Light>,
    pub sun: SunReport,
    pub light: String,
    pub light_choice: Option<LightChoice>,
    pub white: WhiteChoice,
    pub levels: Levels,
    pub bright_reflectors: Vec<String>,
    pub reflector_energy_share: f64,
    pub reflectors: Reflectors,
    pub mode: String,
    pub plan: Plan,
    /// The map as analysed, and the scene (for drawing).
    #[serde(skip)]
    pub map: EnvMap,
    #[serde(skip)]
    pub scene: Scene,
}

/// Reads `input` and settles its RGB space (see [`input::SpaceChoice`]): the options every
/// later stage sees have that space.
fn read_input(input: &str, opts: &ConvertOptions) -> Result<(read::Input, ConvertOptions)> {
    let read = read::read(input, opts)?;
    let opts = ConvertOptions {
        space: read.space.space,
        space_overrides_file: true,
        ..opts.clone()
    };
    Ok((read, opts))
}

/// Reads and analyses `input` and plans its conversion, writing nothing.
pub fn inspect(input: &str, opts: &ConvertOptions) -> Result<Inspection> {
    let (mut read, opts) = read_input(input, opts)?;
    let opts = &opts;
    let analysis = plan::analyse(&mut read, opts)?;
    let plan = plan::plan(&analysis, opts)?;
    let scene = analysis.scene;
    Ok(Inspection {
        input: input.to_string(),
        input_description: read.description,
        input_layout: read.layout,
        input_size: read.size,
        sanitized: read.sanitized,
        lights: scene.lights.clone(),
        sun: SunReport::of(&scene),
        light: analysis.light,
        light_choice: analysis.light_choice,
        white: analysis.white,
        levels: scene.levels,
        bright_reflectors: scene.bright_reflectors.clone(),
        reflector_energy_share: scene.reflector_energy_share,
        reflectors: scene.reflectors.clone(),
        mode: mode_name(plan.method, plan.fit.mode),
        plan,
        map: read.map,
        scene,
    })
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
    let (mut read, opts) = read_input(input, opts)?;
    let opts = &opts;
    let analysis = plan::analyse(&mut read, opts)?;
    let mut plan = plan::plan(&analysis, opts)?;
    plan.notes.extend(read.space.note.clone());
    let cells = &analysis.scene.cells;
    let precisions = write::precisions(&read.map, cells, &plan, opts.precision);
    plan.notes.extend(precisions.reason.clone());
    if precisions.below_half > 0 {
        plan.notes.push(format!(
            "{} pixels are darker than half floats hold (below 3e-8 in every value): written \
             as 0 (--precision float keeps them)",
            precisions.below_half
        ));
    }
    let file = FileSettings {
        precision: precisions.clone(),
        compression: opts.compression,
        zip_level: opts.zip_level,
        attributes: attributes(&analysis, &plan),
    };
    // The basis form is factored from the spectral form: written first, as float, beside the
    // output, then read twice (crate::envmap::convert::basis_form) and removed.
    let basis_form = plan.format == OutputFormat::Basis;
    let spectral_out = if basis_form {
        plan.format = OutputFormat::Spectral;
        intermediate(output)
    } else {
        output.to_path_buf()
    };
    let file = if basis_form {
        FileSettings {
            precision: write::Precisions {
                precision: Precision::Float,
                ev: None,
                below_half: 0,
                reason: None,
            },
            ..file
        }
    } else {
        file
    };
    let written = write::write(&read.map, cells, &plan, file, &spectral_out, progress)?;
    let (basis, bytes) = if basis_form {
        let done = (|| {
            let a = crate::envmap::convert::basis_form::analyse(&spectral_out)?;
            crate::envmap::convert::basis_form::write(
                &spectral_out,
                &a,
                output,
                opts.precision,
                opts.compression,
                opts.zip_level,
            )
        })();
        let _ = std::fs::remove_file(&spectral_out);
        let (stats, bytes) = done?;
        plan.format = OutputFormat::Basis;
        if stats.below_half > 0 {
            plan.notes.push(format!(
                "{} pixels' coefficients are all below what half floats hold after the EV \
                 scale: written as 0 (--precision float keeps them)",
                stats.below_half
            ));
        }
        (Some(stats), bytes)
    } else {
        (None, written.bytes)
    };
    let size = [read.map.image.width, read.map.image.height];
    let megapixels = (read.size[0] * read.size[1]) as f64 / 1e6;
    Ok(ConvertReport {
        input: input.to_string(),
        input_description: read.description,
        input_layout: read.layout,
        input_size: read.size,
        output: output.display().to_string(),
        output_layout: read.map.layout,
        output_size: size,
        format: plan.format,
        precision: match precisions.precision {
            Precision::Half => "half",
            Precision::Float => "float",
        },
        compression: format!("{:?}", opts.compression).to_lowercase(),
        ev: match &basis {
            Some(b) => b.ev,
            None => precisions.ev,
        },
        below_half: match &basis {
            Some(b) => b.below_half,
            None => precisions.below_half,
        },
        sanitized: read.sanitized,
        space: read.space.clone(),
        lights: analysis.scene.lights.clone(),
        sun: SunReport::of(&analysis.scene),
        sun_spd: plan.sun_spd.clone(),
        light: analysis.light.clone(),
        light_choice: analysis.light_choice.clone(),
        mode: mode_name(plan.method, plan.fit.mode),
        lights_mode: plan.lights,
        white: analysis.white.clone(),
        sky: plan.sky,
        carriers: plan.carriers.clone(),
        carrier_mixes: plan.mixes,
        reflectors: analysis.scene.reflectors.model,
        bright_reflectors: analysis.scene.bright_reflectors.clone(),
        spectra: written.spectra,
        inexact: written.roundtrip_inexact,
        notes: plan.notes.clone(),
        weights: plan.fit.weights,
        condition_number: plan.fit.condition_number,
        regularized: plan.fit.regularized,
        wavelengths_nm: plan.grid.wavelengths_nm().collect(),
        channels: match &basis {
            Some(b) => b.k + 3,
            None => written.channels,
        },
        bytes,
        basis,
        roundtrip_floor: written.roundtrip_floor,
        roundtrip: written.roundtrip,
        roundtrip_without_sun: written.roundtrip_without_sun,
        seconds_read: read.seconds,
        seconds_convert: written.seconds,
        seconds_encode: written.seconds_encode,
        grid_choice: plan.grid_choice.clone(),
        megapixels_per_second: megapixels / (read.seconds + written.seconds),
    })
}

/// The one name of how pixels became spectra: `faithful`, or the paper's modes.
pub fn mode_name(method: Method, mode: Mode) -> String {
    match method {
        Method::Faithful => "faithful".into(),
        Method::Basis => format!("{mode:?}").to_lowercase(),
    }
}

/// The header attributes: the fit, the premises, the lights, and the basis form's spectra.
fn attributes(analysis: &Analysis, plan: &Plan) -> Vec<(String, AttrValue)> {
    let fit = &plan.fit;
    let text = |k: &str, v: String| (k.to_string(), AttrValue::Text(v));
    let floats = |k: &str, v: Vec<f32>| (k.to_string(), AttrValue::F32Vec(v));
    let premise = analysis.white.premise;
    let balance = match &plan.pixels {
        PixelPlan::Basis { engine, .. } => engine.white_balance(),
        PixelPlan::Carriers { engine, .. } => engine.white_balance(),
    };
    let mut attributes = vec![
        text("specmap.version", env!("CARGO_PKG_VERSION").into()),
        text("specmap.light", analysis.light.clone()),
        text("specmap.mode", mode_name(plan.method, fit.mode)),
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
    if plan.format == OutputFormat::Basis {
        attributes.push(floats(
            "specmap.wavelengths",
            plan.grid.wavelengths_nm().map(|w| w as f32).collect(),
        ));
        if let PixelPlan::Basis { engine, .. } = &plan.pixels {
            for (j, b) in engine.basis_spectra().iter().enumerate() {
                attributes.push(floats(&format!("specmap.basis{j}"), b.clone()));
            }
            if let Some(s) = engine.sun_spectrum() {
                attributes.push(floats("specmap.sunSPD", s.to_vec()));
            }
        }
    }
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

/// The files a conversion reads: the map (or its six face files, in both spellings of the
/// `{face}` pattern) and the lights given as CSV files (`--light`, `--sun-spd`), that exist.
pub fn input_files(input: &str, opts: &ConvertOptions) -> Vec<PathBuf> {
    let mut files = Vec::new();
    if opts.faces || input.contains("{face}") {
        for (name, signed) in files::FACE_NAMES.iter().zip(files::FACE_SIGNED) {
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

/// The largest input value converted: far above any photograph, far below where spectra
/// (value x basis, in f32) or the half-float EV scale (at most 2^100) overflow.
pub const MAX_INPUT: f64 = 1e18;

/// The most wavelength bands a spectral output holds (0.1 nm over 400 nm): each is a channel of
/// every pixel, and the rows of a batch are held in memory.
pub const MAX_BANDS: usize = 4001;

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

/// The default output path for an input: `NAME.spectral.exr` beside it.
pub fn default_output(input: &str) -> PathBuf {
    let p = Path::new(input);
    let stem = p
        .file_stem()
        .map(|s| s.to_string_lossy())
        .unwrap_or_default();
    p.with_file_name(format!("{stem}.spectral.exr"))
}
