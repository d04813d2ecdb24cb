//! What a conversion tells: the report of a conversion ([`ConvertReport`], built from the plan
//! and the write's counts), of an inspection ([`Inspection`]: the analysis and the whole plan),
//! and the sun as both give it ([`SunReport`]).

use crate::envmap::convert::analyse::Analysis;
use crate::envmap::convert::basis_form::BasisStats;
use crate::envmap::convert::file_plan::Output;
use crate::envmap::convert::measure::SpectraCount;
use crate::envmap::convert::options::{mode_name, Lights, OutputFormat, SkySpd};
use crate::envmap::convert::plan::Plan;
use crate::envmap::convert::read::{Sanitized, SpaceChoice};
use crate::envmap::convert::sun_report::SunReport;
use crate::envmap::convert::write::WriteStats;
use crate::envmap::files::Precision;
use crate::envmap::layout::{EnvMap, Layout};
use crate::envmap::roundtrip::stats::{Floor, RoundTripStats};
use crate::envmap::scene::main_light::{LightChoice, WhiteChoice};
use crate::envmap::scene::{Levels, Light, ReflectorModel, Reflectors, Scene};
use crate::tradeoff::GridChoice;

/// What a conversion did.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ConvertReport {
    /// The input map as given.
    pub input: String,
    /// The input in words (format, compression, channels).
    pub input_description: String,
    /// The input's layout.
    pub input_layout: Layout,
    /// The input's size in pixels (width, height).
    pub input_size: [usize; 2],
    /// The file written.
    pub output: String,
    /// The output's layout.
    pub output_layout: Layout,
    /// The output's size in pixels (width, height).
    pub output_size: [usize; 2],
    /// Spectral channels, or the basis form.
    pub format: OutputFormat,
    /// `half` or `float`.
    pub precision: &'static str,
    /// The OpenEXR compression (`zip`, `piz`...).
    pub compression: String,
    /// Values were divided by 2^EV to fit half floats (None: not needed).
    pub ev: Option<f64>,
    /// Pixels whose every value is below half's smallest positive value (written as 0).
    pub below_half: usize,
    /// What sanitising changed.
    pub sanitized: Sanitized,
    /// The input's RGB space, and where it comes from.
    pub space: SpaceChoice,
    /// Why the scene was not analysed (the flags decide every light); None: it was.
    pub scene_not_analysed: Option<String>,
    /// Every light of the scene (see [`crate::envmap::scene::Light`]).
    pub lights: Vec<Light>,
    /// The sun found, or why there is none.
    pub sun: SunReport,
    /// The sun's SPD, if a sun was found.
    pub sun_spd: Option<String>,
    /// The main light: every non-sun pixel's with `--lights one` and in the paper's modes; the
    /// dominant light of the scene otherwise (the fit's light).
    pub light: String,
    /// How `--light auto` chose the main light.
    pub light_choice: Option<LightChoice>,
    /// `faithful`, or the paper's modes `paper`, `exact`, `nonneg`.
    pub mode: String,
    /// `all` (the scene's lights) or `one` (the paper's one main light).
    pub lights_mode: Lights,
    /// What RGB (1,1,1) was taken to be, and why.
    pub white: WhiteChoice,
    /// What daylight-coloured sky pixels took.
    pub sky: SkySpd,
    /// The light spectra pixels are carried by, and how many mixes of them reflectors take.
    pub carriers: Vec<String>,
    /// How many mixes of the carriers light the reflectors.
    pub carrier_mixes: usize,
    /// How the reflectors' light was estimated.
    pub reflectors: ReflectorModel,
    /// Bright regions that are not lights, and why.
    pub bright_reflectors: Vec<String>,
    /// How many pixels got which spectrum.
    pub spectra: SpectraCount,
    /// The basis form: how its K spectra hold the conversion's spectra.
    pub basis: Option<BasisStats>,
    /// The round trip over the pixels whose spectrum could not reproduce their colour (the
    /// nearest non-negative spectra, clipped lamp pixels, the paper mode's pixels but white; the
    /// sun aside).
    pub inexact: RoundTripStats,
    /// What the conversion could not do as asked, in words.
    pub notes: Vec<String>,
    /// The paper's w_R, w_G, w_B for the main light.
    pub weights: [f64; 3],
    /// The 2-norm condition number of the basis' RGB matrix.
    pub condition_number: f64,
    /// The basis was too ill-conditioned to invert: the reduced solution was used.
    pub regularized: bool,
    /// The output's wavelengths (nm).
    pub wavelengths_nm: Vec<f64>,
    /// Channels per pixel in the file.
    pub channels: usize,
    /// Bytes written.
    pub bytes: u64,
    /// The luminance floor of the round-trip statistics (see [`Floor`]).
    pub roundtrip_floor: Floor,
    /// Over all pixels, and over those not replaced by the sun's SPD (see
    /// [`crate::envmap::roundtrip::stats`]: the statistic `specmap roundtrip` reports).
    pub roundtrip: RoundTripStats,
    /// Over the pixels not given the sun's SPD.
    pub roundtrip_without_sun: RoundTripStats,
    /// Seconds spent reading the input.
    pub seconds_read: f64,
    /// Seconds spent analysing the scene (its lights, the white premise, the main light).
    pub seconds_analyse: f64,
    /// Seconds spent planning (the half-float EV's measure of every spectrum included).
    pub seconds_plan: f64,
    /// Seconds spent converting and writing.
    pub seconds_convert: f64,
    /// The part of `seconds_convert` spent encoding and compressing the EXR blocks.
    pub seconds_encode: f64,
    /// What `--tolerance` chose (None: the grid was given).
    pub grid_choice: Option<GridChoice>,
    /// Input megapixels converted per second, every stage included.
    pub megapixels_per_second: f64,
}

impl ConvertReport {
    /// The report of a conversion of `input` to the plan's file: what the plan decided and what
    /// the write counted.
    pub fn new(
        input: &str,
        analysis: &Analysis,
        plan: &Plan,
        written: WriteStats,
    ) -> ConvertReport {
        let read = &plan.input;
        let map = &read.map;
        let (precision, ev, below_half) = written_precision(plan, &written);
        let megapixels = (read.size[0] * read.size[1]) as f64 / 1e6;
        let mut notes = plan.notes.clone();
        notes.extend(written.notes);
        ConvertReport {
            input: input.to_string(),
            input_description: read.description.clone(),
            input_layout: read.layout,
            input_size: read.size,
            output: plan
                .file
                .path
                .as_ref()
                .map_or(String::new(), |p| p.display().to_string()),
            output_layout: map.layout,
            output_size: [map.image.width, map.image.height],
            format: plan.format,
            precision,
            compression: format!("{:?}", plan.file.compression).to_lowercase(),
            ev,
            below_half,
            sanitized: read.sanitized,
            space: read.space.clone(),
            scene_not_analysed: analysis.not_analysed.clone(),
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
            notes,
            weights: plan.fit.weights,
            condition_number: plan.fit.condition_number,
            regularized: plan.fit.regularized,
            wavelengths_nm: plan.grid.wavelengths_nm().collect(),
            channels: written.channels,
            bytes: written.bytes,
            basis: written.basis,
            roundtrip_floor: written.roundtrip_floor,
            roundtrip: written.roundtrip,
            roundtrip_without_sun: written.roundtrip_without_sun,
            seconds_read: read.seconds,
            seconds_analyse: analysis.seconds,
            seconds_plan: plan.seconds,
            seconds_convert: written.seconds,
            seconds_encode: written.seconds_encode,
            grid_choice: plan.grid_choice.clone(),
            megapixels_per_second: megapixels
                / (read.seconds + analysis.seconds + plan.seconds + written.seconds),
        }
    }
}

/// The file's precision, EV scale and pixels flushed to zero: the plan's for the spectral form,
/// the basis form's as written.
fn written_precision(plan: &Plan, written: &WriteStats) -> (&'static str, Option<f64>, usize) {
    let name = |p: Precision| match p {
        Precision::Half => "half",
        Precision::Float => "float",
    };
    match (&plan.file.output, &written.basis) {
        (Output::Basis { precision, .. }, Some(b)) => (name(*precision), b.ev, b.below_half),
        (Output::Spectral { precision: p }, _) => (name(p.precision), p.ev, p.below_half),
        (Output::Basis { precision, .. }, None) => (name(*precision), None, 0),
    }
}

/// The analysis and the plan of a conversion, without writing anything (`specmap inspect`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Inspection {
    /// The input map as given.
    pub input: String,
    /// The input in words (format, compression, channels).
    pub input_description: String,
    /// The input's layout.
    pub input_layout: Layout,
    /// The input's size in pixels (width, height).
    pub input_size: [usize; 2],
    /// What sanitising changed.
    pub sanitized: Sanitized,
    /// Every light of the scene (as `convert --json` has them).
    pub lights: Vec<Light>,
    /// The sun found, or why there is none.
    pub sun: SunReport,
    /// The main light (as `convert --json` has it).
    pub light: String,
    /// How `--light auto` chose the main light.
    pub light_choice: Option<LightChoice>,
    /// What RGB (1,1,1) is taken to be, and why.
    pub white: WhiteChoice,
    /// The map's luminance levels (median, clip level...).
    pub levels: Levels,
    /// Bright regions that are not lights, and why.
    pub bright_reflectors: Vec<String>,
    /// The reflectors' share of the map's energy.
    pub reflector_energy_share: f64,
    /// How the reflectors are lit: the carriers and the mix around each pixel.
    pub reflectors: Reflectors,
    /// `faithful`, or the paper's modes `paper`, `exact`, `nonneg`.
    pub mode: String,
    /// Every decision of the conversion.
    pub plan: Plan,
    /// The scene (for drawing over the map, [`Inspection::map`]).
    #[serde(skip)]
    pub scene: Scene,
}

impl Inspection {
    /// What `inspect` shows of `input`: the analysis and the whole plan.
    pub fn new(input: &str, plan: Plan, analysis: Analysis) -> Inspection {
        let scene = analysis.scene;
        let read = &plan.input;
        Inspection {
            input: input.to_string(),
            input_description: read.description.clone(),
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
            scene,
        }
    }

    /// The map as analysed and planned (for drawing).
    pub fn map(&self) -> &EnvMap {
        &self.plan.input.map
    }
}
