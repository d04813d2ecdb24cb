//! Scene analysis: the lights of an RGB environment map, from its pixels alone.
//!
//! A real HDR photograph holds a sun or not, a sky or windows, and any number of lamps of
//! different kinds; everything else reflects them. The analysis is a pipeline of named stages,
//! each a value that can be printed:
//! 1. [`cells`]: the map as lat-long cells in true (D65-referenced) RGB;
//! 2. [`emitters::Levels`]: the typical (median) luminance and the emitter threshold, the clip
//!    level;
//! 3. [`emitters::find`]: connected regions far brighter than the median, each with its core and
//!    its colour (from the unclipped halo where the core is clipped);
//! 4. [`enclosure`]: wide bright regions that go on below the horizon and that something
//!    outshines are the walls of a room or studio, not sky; their bright cores (softboxes,
//!    panels) are emitters of their own, and with no open sky in view the map is indoors;
//! 5. [`classify`]: each emitter becomes the sun, a sky or window, a lamp (matched to a family,
//!    [`families`]) or a bright reflector; daylight-coloured regions that no lamp explains become
//!    sky or windows;
//! 6. [`reflectors`]: the mix of lights that lights each remaining pixel.

pub(crate) mod cells;
pub(crate) mod classify;
pub(crate) mod emitters;
pub(crate) mod enclosure;
pub(crate) mod families;
pub mod main_light;
pub(crate) mod open_sky;
pub mod overlay;
pub mod reflectors;
pub(crate) mod regions;
pub mod sun;
pub(crate) mod twilight;

use crate::colorimetry::RgbSpace;
use crate::envmap::layout::EnvMap;
use crate::envmap::scene::sun::SunSettings;
use crate::error::Result;
pub use cells::Cells;
pub use emitters::Levels;
pub use families::{Family, LampMatch};
pub use reflectors::{ReflectorModel, Reflectors};

/// What kind of light an emitter is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LightKind {
    /// The sun: a compact, very bright emitter of daylight or Planckian colour, seen with daylight.
    Sun,
    /// The sky: the daylight-coloured regions above the horizon reaching high or wide, as one.
    Sky,
    /// A window: a daylight-coloured region that is not the sky (lower and smaller).
    Window,
    /// A lamp: any other emitter, matched to a lamp family.
    Lamp,
}

/// The spectrum a light is given.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum LightSpd {
    /// The CIE daylight (S0, S1, S2) of the light's own colour (the low sun, sunlight through the
    /// atmosphere, where the colour is warmer than the daylight family reaches: see
    /// [`crate::illuminant::natural`]).
    Daylight {
        /// Correlated colour temperature (K).
        cct_k: f64,
    },
    /// A table by name (a matched lamp, or `--light NAME`).
    Table {
        /// A spectrum name or file, as [`crate::data::spectrum`] reads it.
        name: String,
    },
    /// A black body (a filament lamp).
    Planckian {
        /// Temperature of the black body (K).
        cct_k: f64,
    },
    /// Two tables of one family mixed to the lamp's white (a sodium lamp between the standard
    /// and the colour-improved one).
    Mix(families::Mix),
}

impl LightSpd {
    /// The spectrum as a table.
    pub fn table(&self) -> Result<crate::spectrum::Tabulated> {
        match self {
            LightSpd::Daylight { cct_k } => crate::illuminant::natural(*cct_k),
            LightSpd::Table { name } => Ok(crate::data::spectrum(name)?.data),
            LightSpd::Planckian { cct_k } => crate::illuminant::planckian(*cct_k),
            LightSpd::Mix(mix) => mix.table(),
        }
    }

    /// A built-in name of the same kind of light, for the paper's one-light fit: the table
    /// itself, D65 for daylight, A for a filament.
    pub fn fit_name(&self) -> String {
        match self {
            LightSpd::Daylight { .. } => "D65".into(),
            LightSpd::Table { name } => name.clone(),
            LightSpd::Planckian { .. } => "A".into(),
            LightSpd::Mix(mix) if mix.share_b > 0.5 => mix.b.clone(),
            LightSpd::Mix(mix) => mix.a.clone(),
        }
    }

    /// The name the report gives it: `daylight 5200 K`, `low sun 1603 K` (daylight's choice
    /// below 4000 K), `FL11`, `Planckian 2700 K`.
    pub fn label(&self) -> String {
        match self {
            LightSpd::Daylight { cct_k } if crate::illuminant::natural_is_low_sun(*cct_k) => {
                format!("low sun {cct_k:.0} K")
            }
            LightSpd::Daylight { cct_k } => format!("daylight {cct_k:.0} K"),
            LightSpd::Table { name } => name.clone(),
            LightSpd::Planckian { cct_k } => format!("Planckian {cct_k:.0} K"),
            LightSpd::Mix(mix) => mix.label(),
        }
    }
}

/// One light of the scene.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Light {
    /// What kind of light it is.
    pub kind: LightKind,
    /// The spectrum's name (see [`LightSpd::label`]).
    pub spd: String,
    /// The spectrum it is given.
    #[serde(skip)]
    pub spd_choice: LightSpd,
    /// Correlated colour temperature of its colour (K); None more than 0.05 uv (CIE 1960) from
    /// the Planckian locus.
    #[serde(rename = "cct_K")]
    pub cct_k: Option<f64>,
    /// Its colour's signed distance from the Planckian locus in CIE 1960 uv (positive: greenish).
    pub duv: f64,
    /// Its colour's CIE 1931 xy chromaticity.
    pub xy: [f64; 2],
    /// Analysis cells (the map's pixels for a lat-long up to 2048 wide).
    pub pixels: usize,
    /// Solid angle of its cells (sr).
    pub solid_angle_sr: f64,
    /// Its share of the map's energy (luminance x solid angle).
    pub energy_share: f64,
    /// Energy-weighted mean direction (unit vector, OpenEXR's axes: Y up).
    pub direction: [f64; 3],
    /// Elevation of its direction above the horizon (degrees).
    pub elevation_deg: f64,
    /// Its analysis cells at the clip level.
    pub clipped_pixels: usize,
    /// Its colour was taken from outside its clipped core (the rest of its region or its halo).
    pub colour_from_halo: bool,
    /// The lamp match (lamps only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lamp: Option<LampMatch>,
    /// Why it is this kind of light, in words.
    pub reason: String,
    /// Its colour as XYZ with Y = 1.
    #[serde(skip)]
    pub colour: nalgebra::Vector3<f64>,
    /// Its analysis cells.
    #[serde(skip)]
    pub cells: Vec<usize>,
}

/// What the analysis needs besides the map.
#[derive(Debug, Clone)]
pub struct SceneSettings {
    /// None: no sun (`--sun off`).
    pub sun: Option<SunSettings>,
    /// Emitter candidates are at least this many times the median luminance.
    pub contrast: f64,
    /// `--light NAME`: every lamp has this spectrum (the sun, sky and windows keep daylight).
    pub lamps: Option<String>,
    /// How the light reaching each reflector is estimated (`--reflectors`).
    pub reflectors: ReflectorModel,
}

impl Default for SceneSettings {
    fn default() -> Self {
        SceneSettings {
            sun: Some(SunSettings::default()),
            contrast: 10.0,
            lamps: None,
            reflectors: ReflectorModel::default(),
        }
    }
}

/// Per analysis cell: which light it belongs to, if any.
pub const REFLECTOR: u16 = u16::MAX;

/// The analysed scene.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Scene {
    /// The luminance levels the emitters were found against.
    pub levels: Levels,
    /// The lights: the sun first, then the sky, the windows and the lamps.
    pub lights: Vec<Light>,
    /// Bright regions that are not lights, and why (sunlit walls, reflections of the sun).
    pub bright_reflectors: Vec<String>,
    /// The share of the energy the lights do not hold.
    pub reflector_energy_share: f64,
    /// The mixes of the lights' spectra that light the reflectors.
    pub reflectors: Reflectors,
    /// The analysis grid.
    #[serde(skip)]
    pub cells: Cells,
    /// Per cell: the index of its light, or [`REFLECTOR`].
    #[serde(skip)]
    pub label: Vec<u16>,
}

impl Scene {
    /// A scene left unanalysed because the flags decide every pixel's light: the analysis grid
    /// (each pixel's cell) and no light, level or reflector mix.
    pub fn unanalysed(map: &EnvMap, space: &RgbSpace, model: ReflectorModel) -> Scene {
        let cells = Cells::geometry(map, space);
        let label = vec![REFLECTOR; cells.len()];
        Scene {
            levels: Levels::default(),
            lights: Vec::new(),
            bright_reflectors: vec![format!("no sun: {}", sun::SUN_OFF)],
            reflector_energy_share: 1.0,
            reflectors: Reflectors::estimate(&cells, &label, &[], model),
            cells,
            label,
        }
    }

    /// The sun, if the scene has one.
    pub fn sun(&self) -> Option<&Light> {
        self.lights.iter().find(|l| l.kind == LightKind::Sun)
    }
}

/// Analyses `map` (linear RGB in `space`; `balance` makes it D65-referenced: the main light's
/// RGB under the light premise, else 1).
pub fn analyse(
    map: &EnvMap,
    space: &RgbSpace,
    balance: [f64; 3],
    settings: &SceneSettings,
) -> Result<Scene> {
    let cells = Cells::new(map, space, balance);
    let levels = Levels::of(&cells, settings.contrast);
    let emitters = emitters::find(&cells, &levels);
    let found = classify::classify(&cells, &levels, emitters, settings)?;
    let mut label = vec![REFLECTOR; cells.len()];
    for (k, l) in found.lights.iter().enumerate() {
        for &i in &l.cells {
            label[i] = k as u16;
        }
    }
    let reflectors = Reflectors::estimate(&cells, &label, &found.lights, settings.reflectors);
    let held: f64 = found.lights.iter().map(|l| l.energy_share).sum();
    Ok(Scene {
        levels,
        lights: found.lights,
        bright_reflectors: found.bright_reflectors,
        reflector_energy_share: (1.0 - held).max(0.0),
        reflectors,
        cells,
        label,
    })
}
