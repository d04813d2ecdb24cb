//! What a conversion is asked to do: [`ConvertOptions`] and the choices it is made of, with the
//! limits of what it accepts ([`MAX_INPUT`], [`MAX_BANDS`]) and the files it names.

use crate::colorimetry::{Observer, RgbSpace};
use crate::envmap::files::{self, Compression, Precision};
use crate::envmap::layout::{Layout, Orientation};
use crate::envmap::scene::sun::SunSettings;
use crate::envmap::scene::ReflectorModel;
use crate::fit::{self, Fit, Mode};
use crate::spectrum::{Rule, WavelengthGrid};
use std::path::PathBuf;

/// The main light: a spectrum name, or chosen from the scene.
#[derive(Debug, Clone, PartialEq)]
pub enum LightSpec {
    /// A table name or a CSV file.
    Named(String),
    /// Chosen from the scene.
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

/// What RGB (1,1,1) is (see [`crate::envmap::convert::pixel_spectra::WhitePremise`]), or chosen from the scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WhiteSpec {
    /// The main light (the map is white-balanced to it: the paper's premise).
    Light,
    /// The RGB space's own white.
    Space,
    /// The brightest regions decide (see [`crate::envmap::scene::main_light::choose_white`]).
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
    /// The scene's lights, or the paper's one main light.
    pub lights: Lights,
    /// How the reflectors' light is estimated (see [`crate::envmap::scene::reflectors`]).
    pub reflectors: ReflectorModel,
    /// A fit from `specmap fit -o`; otherwise the basis is fitted on the output grid.
    pub fit: Option<Fit>,
    /// The fit's mode: the ColorChecker basis of [`Method::Basis`], and the fallback of
    /// [`Method::Faithful`] where the smooth modulation would go negative.
    pub mode: Mode,
    /// How pixels become spectra.
    pub method: Method,
    /// None: the method's default (faithful: auto; basis: light, or auto with `--light auto`).
    pub white: Option<WhiteSpec>,
    /// None: the method's default (faithful: daylight; basis: light).
    pub sky: Option<SkySpd>,
    /// The input's RGB space when the file declares none (OpenEXR's `chromaticities`; a file
    /// without them is Rec.709 with D65, sRGB), or whatever it declares with
    /// `space_overrides_file`. [`super::read`] resolves it (see
    /// [`crate::envmap::convert::read::SpaceChoice`]).
    pub space: RgbSpace,
    /// `space` was asked for (`--space`, a fit's space): it replaces the file's chromaticities,
    /// with a note when they differ.
    pub space_overrides_file: bool,
    /// The three reflectance tables of the basis (the paper's ColorChecker red, green, blue).
    pub basis: [String; 3],
    /// The colour-matching functions colours are computed with.
    pub observer: Observer,
    /// How spectra are integrated over the grid.
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
    /// The output's wavelengths (nm).
    pub grid: WavelengthGrid,
    /// Spectral channels, or the basis form.
    pub format: OutputFormat,
    /// Half or float (half gets an EV scale where values exceed its range).
    pub precision: Precision,
    /// The OpenEXR compression.
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

/// The one name of how pixels became spectra: `faithful`, or the paper's modes.
pub fn mode_name(method: Method, mode: Mode) -> String {
    match method {
        Method::Faithful => "faithful".into(),
        Method::Basis => format!("{mode:?}").to_lowercase(),
    }
}
