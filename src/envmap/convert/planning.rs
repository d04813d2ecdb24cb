//! What the plan's stages share: the spectra's part of the plan ([`SpectraPlan`]) and what
//! its stages read ([`Planning`]: the analysis, the options, the RGB space, the sun's SPD, the
//! grid and the sky's spectra).

use crate::colorimetry::RgbSpace;
use crate::envmap::convert::analyse::Analysis;
use crate::envmap::convert::carriers::SunSpec;
use crate::envmap::convert::options::{ConvertOptions, Method, SkySpd};
use crate::envmap::convert::pixels::PixelPlan;
use crate::fit::Fit;
use crate::spectrum::{Tabulated, WavelengthGrid};
use crate::tradeoff::GridChoice;

/// The sun's SPD (label, table, and how the engine makes it), if the scene has a sun.
pub(crate) type SunTable = (String, Tabulated, SunSpec);

/// The spectra's part of the plan: everything but the file.
pub(crate) struct SpectraPlan {
    pub method: Method,
    pub sky: SkySpd,
    pub sun_spd: Option<String>,
    pub grid: WavelengthGrid,
    pub grid_choice: Option<GridChoice>,
    pub fit: Fit,
    pub pixels: PixelPlan,
    pub carriers: Vec<String>,
    pub mixes: usize,
}

/// What the spectra's planning stages share: the analysis, the options, the input's RGB space,
/// and what is settled first (the sun's SPD, the grid, the sky's spectra).
pub(crate) struct Planning<'a> {
    pub analysis: &'a Analysis,
    pub opts: &'a ConvertOptions,
    pub space: RgbSpace,
    pub sun: Option<SunTable>,
    pub grid: WavelengthGrid,
    pub sky: SkySpd,
}
