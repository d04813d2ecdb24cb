//! What each emitter is: the sun, a sky or window, a lamp of a family, or a bright reflector;
//! and which dim daylight-coloured regions are sky or windows.
//!
//! The rules, each with its reason in the report:
//! - **sun**: the brightest emitter, if its core is compact (at most the sun settings' solid
//!   angle), at least [`SUN_CONTRAST`] times the median luminance, no lower than
//!   [`SUN_MIN_ELEVATION_DEG`], of a daylight or Planckian colour (|Duv| <= [`SUN_MAX_DUV`]),
//!   unique (no other emitter's peak within [`SUN_UNIQUE`] of its own, reflections of it
//!   aside), and seen with daylight: a daylight sky or window in the map, or (no sky) at least the
//!   settings' share of the energy in a daylight colour. A red sun on the horizon is the sun; four
//!   similar lamps are not; a sodium lamp at night has no daylight around it.
//! - **sky / window**: an emitter of daylight colour (CIE 1931 xy within 0.02 of the daylight
//!   locus) at least [`WINDOW_MIN_K`] and [`WINDOW_MIN_SR`]; or a dim daylight-coloured region of
//!   the upper hemisphere at least [`SKY_MIN_K`] and [`SKY_MIN_SR`] whose colour no lamp explains
//!   (farther than [`EXPLAINED_UV`] from every lamp's white and the mixes of two, or of a lamp and
//!   a window; a region reaching [`SKY_TOP_DEG`] [`NIGHT_SKY_CONTRAST`] of the brightest lamp's
//!   luminance or less is a night sky whatever its colour) and that is not a wall lit by a window ([`LIT_BY_WINDOW`] times dimmer and of its colour). It is the sky when it
//!   reaches [`SKY_TOP_DEG`] or covers [`SKY_LARGE_SR`], otherwise a window; all sky regions are
//!   one light.
//!   With a sky in view, every bright daylight-coloured patch above the horizon (sky between
//!   leaves, through a gap in the clouds) is part of it, unless it is
//!   [`DAYLIGHT_LAMP_CONTRAST`] times brighter than the sky (a cool lamp under a night sky).
//! - **lamp**: any other emitter, matched to a lamp family ([`super::families`]). With daylight
//!   about, an emitter that is not [`DAYLIGHT_LAMP_CONTRAST`] times brighter than the sky is a
//!   sunlit surface when it lies below the horizon or its colour matches no lamp (farther than
//!   [`LAMP_MATCH_UV`]), and one below the horizon of the sun's colour is a reflection of the
//!   sun; an emitter candidate at most [`LIT_BY_LAMP`] of a lamp's luminance and within
//!   [`LIT_COLOUR_UV`] of its colour is a surface it lights (a lamp's radiance does not fall with
//!   distance, a lit wall's is orders of magnitude below it): reflectors, all.

use super::cells::Cells;
use super::emitters::{Emitter, Levels};
use super::enclosure::{split_surface, surface_reason, Indoors, WINDOW_BLUE_K};
use super::families::{match_lamp, LampMatch};
use super::regions::{components, mask, RegionStats};
use super::{Light, LightKind, LightSpd, SceneSettings};
use crate::colorimetry::{cct, Xyz};
use crate::envmap::convert::pixel_spectra::daylight_coloured;
use crate::error::Result;
use nalgebra::Vector3;
use rayon::prelude::*;

/// The sun's peak is at least this many times the map's median luminance.
pub(crate) const SUN_CONTRAST: f64 = 100.0;
/// Lowest elevation of the sun's direction (degrees; just below 0, for a sun on the horizon).
pub(crate) const SUN_MIN_ELEVATION_DEG: f64 = -1.0;
/// The sun's colour lies at most this far from the Planckian locus (|Duv|, CIE 1960 uv).
pub(crate) const SUN_MAX_DUV: f64 = 0.02;
/// No other emitter's peak (the sun's reflections aside) reaches this fraction of the sun's.
pub(crate) const SUN_UNIQUE: f64 = 0.1;
/// A bright daylight-coloured emitter is a window or sky from this CCT up (K).
pub(crate) const WINDOW_MIN_K: f64 = 5000.0;
/// A bright daylight-coloured emitter is a window or sky from this solid angle up (sr).
pub(crate) const WINDOW_MIN_SR: f64 = 0.002;
/// A dim daylight-coloured region, or a bright patch above the horizon, is sky or a window from
/// this CCT up (K).
pub(crate) const SKY_MIN_K: f64 = 4000.0;
/// A dim daylight-coloured region is sky or a window from this solid angle up (sr).
pub(crate) const SKY_MIN_SR: f64 = 0.02;
/// A colour within this CIE 1960 uv distance of a lamp's white, or of a mix of two lamps' or of a
/// lamp's and a window's, is explained by them: a surface they light.
pub(crate) const EXPLAINED_UV: f64 = 0.006;
/// A daylight-coloured region of a window's colour and this many times dimmer than it is a wall the
/// window lights.
pub(crate) const LIT_BY_WINDOW: f64 = 20.0;
/// A region reaching the zenith this much dimmer than the brightest lamp is a night sky even of a
/// lamp's colour (moonlight: 1e-5 of a street lamp; a wall a lamp lights: 1e-2).
pub(crate) const NIGHT_SKY_CONTRAST: f64 = 1e-3;
/// A daylight region reaching this elevation (degrees above the horizon) is the sky, not a window.
pub(crate) const SKY_TOP_DEG: f64 = 60.0;
/// In a map with an enclosure, a bright region is sky only if its core (within a tenth of its
/// peak) covers this fraction of it or more: a sky is smooth.
pub(crate) const SKY_SMOOTH: f64 = 0.25;
/// A daylight region covering this solid angle (sr) is the sky, however low.
pub(crate) const SKY_LARGE_SR: f64 = 1.0;
/// CIE 1960 uv distance within which a colour matches: a lamp's white (in daylight, an emitter
/// farther from every white is a surface), or the sun's (below the horizon, a reflection of it).
pub(crate) const LAMP_MATCH_UV: f64 = 0.01;
/// With daylight about, an emitter this many times brighter than the sky's and windows' bright
/// parts is a lamp wherever it lies and whatever its colour.
pub(crate) const DAYLIGHT_LAMP_CONTRAST: f64 = 10.0;
/// An emitter candidate this much dimmer than a lamp, and near its colour, is a surface it lights.
pub(crate) const LIT_BY_LAMP: f64 = 0.05;
/// CIE 1960 uv distance from a lamp's colour within which a far dimmer emitter ([`LIT_BY_LAMP`]) is
/// a surface it lights.
pub(crate) const LIT_COLOUR_UV: f64 = 0.05;
/// A lamp's pixels are those at least this fraction of its peak luminance.
pub(crate) const LAMP_CORE: f64 = 0.25;
/// A glow touching a twilight sky joins it when its core covers this solid angle (sr) or more:
/// a lamp's core is far smaller.
pub(crate) const GLOW_MIN_SR: f64 = 0.01;
/// Indoors, a daylight-white lamp of this CCT (K) or more whose white no LED or xenon table
/// matches is given the daylight of its colour (a flash, a daylight panel, a D-simulator tube,
/// a lamp the camera was balanced to).
pub(crate) const DAYLIGHT_PANEL_K: f64 = 5500.0;
/// A sky holding less of the map's energy than this is a dusk or night sky: a daylight-white
/// emitter ten times brighter is a lamp there (in daylight it is a patch of sky, a cloud in the
/// sun between leaves).
pub(crate) const DUSK_SKY_SHARE: f64 = 0.25;
/// A glow joins a twilight sky at most this many times the sky's median luminance: the
/// afterglow over the sunset (about 100 times the sky at the zenith) or a city's glow over a
/// night sky (300 times), not a street lamp (thousands).
pub(crate) const GLOW_CONTRAST: f64 = 1000.0;
/// A window holding this share of the map's energy shows the map is a room: its sky is seen
/// through it, and what is grown from the zenith is a ceiling.
pub(crate) const ROOM_WINDOW_SHARE: f64 = 0.01;
/// A sun blurred by a small map or haze has a core of this solid angle or less (sr).
pub(crate) const BLURRED_SUN_SR: f64 = 0.05;
/// The sky is at least this many times the sun's CCT.
pub(crate) const SKY_BLUER: f64 = 1.1;
/// Emitters holding less of the energy than this are left to the reflectors (glints, noise).
pub(crate) const MIN_LIGHT_SHARE: f64 = 1e-4;
/// A lamp holding less of the energy than this is too small and faint to matter: its pixels are
/// left to the reflectors around it (a glint in a tree, a star, an indicator light).
pub(crate) const MIN_LAMP_SHARE: f64 = 5e-4;
/// At most this many emitters are classified (the most energetic).
pub(crate) const MAX_EMITTERS: usize = 256;

/// A colour and where it lies.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Colour {
    /// XYZ with Y = 1.
    pub xyz: Vector3<f64>,
    /// CIE 1931 xy chromaticity.
    pub xy: [f64; 2],
    /// CIE 1960 uv chromaticity.
    pub uv: [f64; 2],
    /// Correlated colour temperature (K); None more than 0.05 uv (CIE 1960) from the locus.
    pub cct_k: Option<f64>,
    /// Signed distance from the Planckian locus in CIE 1960 uv (positive: greenish).
    pub duv: f64,
}

impl Colour {
    /// Measures the colour `xyz` (any scale; scaled to Y = 1 where Y > 0).
    pub(crate) fn of(xyz: Vector3<f64>) -> Result<Colour> {
        let xyz = if xyz[1] > 0.0 { xyz / xyz[1] } else { xyz };
        let x = Xyz::new(xyz[0], xyz[1], xyz[2]);
        let c = cct(x)?;
        Ok(Colour {
            xyz,
            xy: x.xy(),
            uv: x.uv1960(),
            cct_k: c.kelvin,
            duv: c.duv,
        })
    }

    fn daylight(&self) -> bool {
        daylight_coloured(&self.xyz)
    }

    fn uv_distance(&self, o: &Colour) -> f64 {
        (self.uv[0] - o.uv[0]).hypot(self.uv[1] - o.uv[1])
    }

    fn describe(&self) -> String {
        match self.cct_k {
            Some(k) => format!("CCT {k:.0} K, Duv {:+.4}", self.duv),
            None => format!(
                "xy {:.3} {:.3}, far from the Planckian locus",
                self.xy[0], self.xy[1]
            ),
        }
    }
}

/// The lights found, and the bright regions that are not lights.
#[derive(Debug, Clone, Default)]
pub(crate) struct Classified {
    /// The lights: the sun first, then the sky, the windows and the lamps.
    pub lights: Vec<Light>,
    /// Bright regions that are not lights, each with why in words (first: why there is no sun).
    pub bright_reflectors: Vec<String>,
}

/// An emitter with its colour.
struct Candidate {
    e: Emitter,
    colour: Colour,
    /// A bright core inside a surface of an enclosure (a softbox, a panel): never sky.
    core: bool,
}

/// Classifies the emitters of a scene (brightest peak first) and finds its dim skies: the
/// daylight first (windows, sky, the sun seen with them), then the lamps.
pub(crate) fn classify(
    cells: &Cells,
    levels: &Levels,
    emitters: Vec<Emitter>,
    settings: &SceneSettings,
) -> Result<Classified> {
    let mut indoors = Indoors::default();
    let candidates = open_enclosures(
        cells,
        levels,
        candidates_of(levels, emitters)?,
        settings,
        &mut indoors,
    )?;
    let mut taken = vec![false; candidates.len()];
    let Daylight {
        mut daylight,
        dim,
        inside,
        twilight,
    } = find_daylight(cells, levels, &candidates, &mut indoors)?;
    let sun = if inside {
        Err("the map is inside an enclosure with no sky in view".to_string())
    } else {
        sun_of(
            &candidates,
            levels,
            !daylight.is_empty() || !dim.is_empty(),
            settings,
        )
    };
    let mut out = Classified::default();
    let sun_index = sun.as_ref().ok().copied();
    if let Some(k) = sun_index {
        taken[k] = true;
        daylight.retain(|d| d.0 != k);
        out.lights
            .push(sun_light(cells, levels, &candidates[k], settings)?);
    }
    let sky_cells = daylight_lights(cells, levels, &candidates, &daylight, &dim, &mut out)?;
    let mut sky_cells = open_sky_cells(cells, levels, sky_cells, &dim, &mut out);
    if let (Some(k), false) = (sun_index, sky_cells.is_empty()) {
        add_circumsolar_sky(cells, &out.lights[0].cells, &candidates[k], &mut sky_cells);
    }
    for &(k, _) in &daylight {
        taken[k] = true;
    }
    let context = Context {
        daylight: !daylight.is_empty() || !dim.is_empty() || sun_index.is_some(),
        daylight_level: daylight_level(cells, &candidates, &daylight, &dim),
        sun: sun_index.map(|k| candidates[k].colour),
        sky: !sky_cells.is_empty(),
        inside,
    };
    let free: Vec<&Candidate> = (0..candidates.len())
        .filter(|&k| !taken[k])
        .map(|k| &candidates[k])
        .collect();
    lamp_lights(
        cells,
        levels,
        &free,
        &context,
        settings,
        &mut sky_cells,
        &mut out,
    )?;
    if !sky_cells.is_empty() {
        let mut light = sky_light(cells, levels, sky_cells, twilight)?;
        if twilight {
            city_glow(&mut light, &out.lights);
        }
        out.lights.insert(sun_index.is_some() as usize, light);
    }
    if let (Err(why), Some(_)) = (&sun, candidates.first()) {
        out.bright_reflectors.insert(0, format!("no sun: {why}"));
    }
    out.bright_reflectors.extend(indoors.surfaces);
    Ok(out)
}

/// The daylight among the candidates (each with its kind), the dim skies, and whether the map is
/// inside an enclosure with no sky in view (see [`indoor_daylight`] and
/// [`outshining_the_sky`] for the emitters that leave the daylight for the lamps).
struct Daylight {
    daylight: Vec<(usize, LightKind)>,
    dim: Vec<Region>,
    inside: bool,
    /// The sky is a twilight or night sky ([`twilight_sky`]).
    twilight: bool,
}

fn find_daylight(
    cells: &Cells,
    levels: &Levels,
    candidates: &[Candidate],
    indoors: &mut Indoors,
) -> Result<Daylight> {
    let mut daylight: Vec<(usize, LightKind)> = (0..candidates.len())
        .filter(|&k| is_window(&candidates[k]))
        .map(|k| match open_sky_shape(&candidates[k], indoors) {
            true => (k, kind_of(&candidates[k].e.stats)),
            false => (k, LightKind::Window),
        })
        .collect();
    let lamp_whites: Vec<Colour> = (0..candidates.len())
        .filter(|k| !daylight.iter().any(|d| d.0 == *k))
        .map(|k| candidates[k].colour)
        .collect();
    let window_colours: Vec<(Colour, f64)> = daylight
        .iter()
        .map(|&(k, _)| (candidates[k].colour, candidates[k].e.stats.mean_xyz[1]))
        .collect();
    let mut dim = dim_skies(cells, candidates, &lamp_whites, &window_colours, indoors)?;
    let no_sky = !daylight.iter().any(|d| d.1 == LightKind::Sky)
        && !dim.iter().any(|d| kind_of(&d.stats) == LightKind::Sky);
    let twilight = no_sky
        && !indoors.enclosed
        && twilight_sky(cells, levels, candidates, &mut daylight, &mut dim)?;
    let inside = indoors.enclosed
        && !daylight.iter().any(|d| d.1 == LightKind::Sky)
        && !dim.iter().any(|d| kind_of(&d.stats) == LightKind::Sky);
    if inside {
        indoor_daylight(candidates, &mut daylight);
    } else {
        outshining_the_sky(
            cells,
            candidates,
            &dim,
            indoors.blurred_sun,
            levels.total_energy,
            &mut daylight,
        );
    }
    Ok(Daylight {
        daylight,
        dim,
        inside,
        twilight,
    })
}

/// Where the daylight rules found no sky and no window shows daylight ([`ROOM_WINDOW_SHARE`]):
/// the twilight or night sky grown from the zenith ([`super::twilight`]) joins `dim`, and its
/// glows join `daylight` as sky: the emitters touching it above the horizon with cores of
/// [`GLOW_MIN_SR`] or more, at most [`GLOW_CONTRAST`] times its median luminance, of a colour
/// with a CCT (the afterglow, a city's sky glow). A region the other emitters light as lamps
/// light walls ([`surface_reason`]) is a ceiling, not a sky. Whether a twilight sky was found.
fn twilight_sky(
    cells: &Cells,
    levels: &Levels,
    candidates: &[Candidate],
    daylight: &mut Vec<(usize, LightKind)>,
    dim: &mut Vec<Region>,
) -> Result<bool> {
    let window_share = (daylight.iter())
        .map(|&(k, _)| candidates[k].e.stats.energy / levels.total_energy.max(f64::MIN_POSITIVE))
        .fold(0f64, f64::max);
    let in_emitter = emitter_mask(cells, candidates);
    let open = (window_share < ROOM_WINDOW_SHARE)
        .then(|| super::twilight::open_sky(cells, &in_emitter))
        .flatten();
    let Some((region, stats)) = open else {
        return Ok(false);
    };
    let median = super::enclosure::median_luminance(cells, &region);
    let in_sky = mask(cells, region.iter().copied());
    let glow = |c: &Candidate| {
        c.e.stats.elevation_deg() > 0.0
            && c.e.core_solid_angle_sr >= GLOW_MIN_SR
            && c.e.stats.peak <= GLOW_CONTRAST * median
            && c.colour.cct_k.is_some()
            && (c.e.cells.iter()).any(|&i| cells.neighbours(i).any(|j| in_sky[j]))
    };
    let glows: Vec<usize> = (0..candidates.len())
        .filter(|&k| glow(&candidates[k]))
        .collect();
    let lamps: Vec<&[usize]> = (0..candidates.len())
        .filter(|k| !glows.contains(k))
        .map(|k| candidates[k].e.cells.as_slice())
        .collect();
    let lit = surface_reason(cells, &region, &lamps).is_some();
    if lit || Colour::of(stats.mean_xyz)?.cct_k.is_none() {
        return Ok(false);
    }
    for k in glows {
        if !daylight.iter().any(|d| d.0 == k) {
            daylight.push((k, LightKind::Sky));
        }
    }
    dim.push(Region {
        cells: region,
        stats,
    });
    Ok(true)
}

/// Per cell: whether it belongs to one of the candidates.
fn emitter_mask(cells: &Cells, candidates: &[Candidate]) -> Vec<bool> {
    mask(
        cells,
        candidates.iter().flat_map(|c| c.e.cells.iter().copied()),
    )
}

/// Each candidate's cells.
fn emitter_cells(candidates: &[Candidate]) -> Vec<&[usize]> {
    candidates.iter().map(|c| c.e.cells.as_slice()).collect()
}

/// Whether the brightest emitter is a sun seen through blur or haze: unique, of a daylight or
/// Planckian colour, its core at most [`BLURRED_SUN_SR`], under an upper hemisphere (its cells
/// outside every emitter) [`SKY_BLUER`] times its CCT or bluer. Scattered skylight is bluer than
/// the sun; the walls a lamp lights have the lamp's colour or a warmer one.
fn sun_under_a_bluer_sky(cells: &Cells, candidates: &[Candidate]) -> Result<bool> {
    let Some(c) = candidates.first() else {
        return Ok(false);
    };
    let sun_like = unique(c, &candidates[1..])
        && c.colour.duv.abs() <= SUN_MAX_DUV
        && c.e.core_solid_angle_sr <= BLURRED_SUN_SR;
    let Some(sun_k) = c.colour.cct_k.filter(|_| sun_like) else {
        return Ok(false);
    };
    let in_emitter = emitter_mask(cells, candidates);
    let sky: Vec<usize> = (0..cells.len())
        .filter(|&i| !in_emitter[i] && cells.direction(i)[1] > 0.0)
        .collect();
    let sky = Colour::of(RegionStats::of(cells, &sky).mean_xyz)?;
    Ok(sky.cct_k.is_some_and(|k| k >= SKY_BLUER * sun_k))
}

/// The candidates with every surface of an enclosure (see [`super::enclosure`]) replaced by the
/// bright cores inside it, brightest peak first; `indoors` records each surface. A map whose
/// brightest emitter is a sun by its shape is outdoors and kept as it is.
fn open_enclosures(
    cells: &Cells,
    levels: &Levels,
    candidates: Vec<Candidate>,
    settings: &SceneSettings,
    indoors: &mut Indoors,
) -> Result<Vec<Candidate>> {
    indoors.blurred_sun = sun_under_a_bluer_sky(cells, &candidates)?;
    if indoors.blurred_sun || sun_of(&candidates, levels, true, settings).is_ok() {
        indoors.outdoors = true;
        return Ok(candidates);
    }
    let splits: Vec<_> = (0..candidates.len())
        .map(|k| {
            let mut others = emitter_cells(&candidates);
            others.remove(k);
            split_surface(cells, levels, &candidates[k].e, &others)
        })
        .collect();
    let mut out = Vec::new();
    for (c, split) in candidates.into_iter().zip(splits) {
        match split {
            Some((cores, why)) => {
                indoors.enclosed = true;
                indoors.surfaces.push(why);
                let cores = candidates_of(levels, cores)?;
                out.extend(cores.into_iter().map(|c| Candidate { core: true, ..c }));
            }
            None => out.push(c),
        }
    }
    out.sort_by(|a, b| b.e.stats.peak.total_cmp(&a.e.stats.peak));
    Ok(out)
}

/// The sun's glow above the horizon, where daylight-coloured, is circumsolar sky: the cells of
/// the sun's emitter outside its core (`sun_cells`, sorted) join `sky_cells`.
fn add_circumsolar_sky(
    cells: &Cells,
    sun_cells: &[usize],
    sun: &Candidate,
    sky_cells: &mut Vec<usize>,
) {
    sky_cells.extend(sun.e.cells.iter().copied().filter(|i| {
        sun_cells.binary_search(i).is_err()
            && cells.direction(*i)[1] > 0.0
            && daylight_coloured(&cells.xyz(*i))
    }));
}

/// The sky's cells above the horizon that are open sky; the parts of dim sky sharp edges cut
/// off from it are named among the bright reflectors.
fn open_sky_cells(
    cells: &Cells,
    levels: &Levels,
    mut sky_cells: Vec<usize>,
    dim: &[Region],
    out: &mut Classified,
) -> Vec<usize> {
    sky_cells.retain(|&i| cells.direction(i)[1] > 0.0);
    let dim_mask = mask(cells, dim.iter().flat_map(|d| d.cells.iter().copied()));
    let (open, cuts) = super::open_sky::split(cells, &sky_cells, &dim_mask);
    for cut in cuts {
        let st = RegionStats::of(cells, &cut.cells);
        out.bright_reflectors.push(format!(
            "a part of the dim sky ({} pixels, {:.3} sr, {:.1}% of the energy, {:.1} degrees \
             up) that sharp edges of colour or luminance cut off from the open sky, textured \
             ({:.0}% of its pixels peaks or dips of luminance) and standing on what is not sky \
             ({:.0}% of the pixels round it): a surface the sky lights (a facade, a tree)",
            cut.cells.len(),
            cut.solid_angle_sr,
            100.0 * share(levels, &st),
            st.elevation_deg(),
            100.0 * cut.textured,
            100.0 * cut.standing
        ));
    }
    open
}

/// All the sky's cells as one light.
fn sky_light(
    cells: &Cells,
    levels: &Levels,
    mut sky_cells: Vec<usize>,
    twilight: bool,
) -> Result<Light> {
    // A sky is above the horizon: what of it lies below (a daylit floor joined to it, haze
    // over the paving) is a surface it lights.
    sky_cells.retain(|&i| cells.direction(i)[1] > 0.0);
    sky_cells.sort_unstable();
    let why = match twilight {
        true => {
            "a twilight or night sky: open, from the zenith down to the horizon, its glow with it"
        }
        false => "daylight-coloured, in the upper hemisphere, reaching high or wide",
    };
    daylight_light(cells, levels, sky_cells, LightKind::Sky, why.into())
}

/// A night sky warmer than the daylight series (under [`SKY_MIN_K`]) and of the colour of the
/// scene's lamps (within [`EXPLAINED_UV`] of the nearest) is their light scattered by the air
/// over a city: it is given their spectrum, where the low sun's would say a sun lit it.
fn city_glow(sky: &mut Light, lights: &[Light]) {
    if sky.cct_k.is_none_or(|k| k >= SKY_MIN_K) {
        return;
    }
    let uv = |l: &Light| Xyz::from(l.colour).uv1960();
    let s = uv(sky);
    let nearest = lights
        .iter()
        .filter(|l| l.kind == LightKind::Lamp)
        .map(|l| (l, (uv(l)[0] - s[0]).hypot(uv(l)[1] - s[1])))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    if let Some((lamp, d)) = nearest.filter(|&(_, d)| d <= EXPLAINED_UV) {
        sky.reason += &format!(
            "; of the colour of its {} lamps ({d:.4} uv): their light scattered over a city, \
             given their spectrum",
            lamp.spd
        );
        sky.spd_choice = lamp.spd_choice.clone();
        sky.spd = lamp.spd.clone();
    }
}

/// The luminance of the sky's and windows' bright parts: the 95th percentile of their cells.
fn daylight_level<'a>(
    cells: &Cells,
    candidates: &[Candidate],
    daylight: &[(usize, LightKind)],
    dim: impl IntoIterator<Item = &'a Region>,
) -> f64 {
    let mut y: Vec<f32> = daylight
        .iter()
        .flat_map(|&(k, _)| candidates[k].e.cells.iter())
        .chain(dim.into_iter().flat_map(|d| d.cells.iter()))
        .map(|&i| cells.y[i])
        .collect();
    if y.is_empty() {
        return 0.0;
    }
    y.sort_by(|a, b| a.total_cmp(b));
    y[(y.len() - 1) * 95 / 100] as f64
}

/// The emitters worth classifying (at least [`MIN_LIGHT_SHARE`] of the energy, at most
/// [`MAX_EMITTERS`]), with their colours.
fn candidates_of(levels: &Levels, emitters: Vec<Emitter>) -> Result<Vec<Candidate>> {
    emitters
        .into_iter()
        .filter(|e| e.stats.energy >= MIN_LIGHT_SHARE * levels.total_energy)
        .take(MAX_EMITTERS)
        .map(|e| {
            Ok(Candidate {
                colour: Colour::of(e.colour)?,
                e,
                core: false,
            })
        })
        .collect()
}

/// The windows (one light each) and the cells of the sky (one light, made by the caller once
/// the lamps have added their sky patches). With any sky in view, the windows above the horizon
/// are more of it.
fn daylight_lights(
    cells: &Cells,
    levels: &Levels,
    candidates: &[Candidate],
    daylight: &[(usize, LightKind)],
    dim: &[Region],
    out: &mut Classified,
) -> Result<Vec<usize>> {
    let sky_seen = daylight.iter().any(|d| d.1 == LightKind::Sky)
        || dim.iter().any(|d| kind_of(&d.stats) == LightKind::Sky);
    let mut sky_cells = Vec::new();
    let regions = daylight
        .iter()
        .map(|&(k, kind)| {
            let above = candidates[k].e.stats.elevation_deg() > 0.0;
            let kind = if sky_seen && above {
                LightKind::Sky
            } else {
                kind
            };
            (&candidates[k].e.cells, kind, "bright and daylight-coloured")
        })
        .chain(dim.iter().map(|d| {
            (
                &d.cells,
                kind_of(&d.stats),
                "daylight-coloured and lit by no lamp found",
            )
        }));
    for (set, kind, why) in regions {
        match kind {
            LightKind::Sky => sky_cells.extend(set),
            _ => out.lights.push(daylight_light(
                cells,
                levels,
                set.clone(),
                LightKind::Window,
                why.into(),
            )?),
        }
    }
    Ok(sky_cells)
}

/// The lamps among the emitters left: surfaces far dimmer than a lamp and of its colour are lit
/// by it; sky patches join the sky; the rest are lamps or bright reflectors.
fn lamp_lights(
    cells: &Cells,
    levels: &Levels,
    free: &[&Candidate],
    context: &Context,
    settings: &SceneSettings,
    sky_cells: &mut Vec<usize>,
    out: &mut Classified,
) -> Result<()> {
    // With a sky in view, a bright daylight-coloured patch above the horizon is more of it
    // (sky between leaves, through a gap in the clouds).
    // (not a lamp far brighter than the sky: a cool street lamp under a night sky).
    let sky_patch = |c: &Candidate| {
        context.sky
            && is_sky_patch(c)
            && c.e.stats.mean_xyz[1] < DAYLIGHT_LAMP_CONTRAST * context.daylight_level
    };
    let lamps: Vec<&Candidate> = free.iter().copied().filter(|c| !sky_patch(c)).collect();
    let lamp_peak = lamps.iter().map(|c| c.e.stats.peak).fold(0f64, f64::max);
    // (A core of an enclosure's surface is a lamp however much dimmer than the key light.)
    let lit_by_lamp = |c: &Candidate| {
        !c.core
            && c.e.stats.peak < LIT_BY_LAMP * lamp_peak
            && lamps.iter().any(|l| {
                l.e.stats.peak > c.e.stats.peak / LIT_BY_LAMP
                    && l.colour.uv_distance(&c.colour) <= LIT_COLOUR_UV
            })
    };
    for &c in free {
        let share = c.e.stats.energy / levels.total_energy.max(f64::MIN_POSITIVE);
        if lit_by_lamp(c) {
            out.bright_reflectors.push(format!(
                "a bright region ({} pixels, {:.1} degrees up, {}) at {:.1e} of the brightest \
                 lamp's luminance and near a lamp's colour: a surface lamps light",
                c.e.cells.len(),
                c.e.stats.elevation_deg(),
                c.colour.describe(),
                c.e.stats.peak / lamp_peak
            ));
        } else if sky_patch(c) {
            sky_cells.extend(&c.e.cells);
        } else {
            match lamp_or_reflector(c, context, settings)? {
                Ok(_) if share < MIN_LAMP_SHARE => out.bright_reflectors.push(format!(
                    "a bright region ({} pixels, {:.1} degrees up, {}) holds {:.3}% of the \
                     energy: too small and faint to matter, left to its surroundings",
                    c.e.cells.len(),
                    c.e.stats.elevation_deg(),
                    c.colour.describe(),
                    100.0 * share
                )),
                Ok(lamp) => {
                    out.lights
                        .push(lamp_light(cells, levels, c, lamp, settings, context.inside))
                }
                Err(why) => out.bright_reflectors.push(why),
            }
        }
    }
    Ok(())
}

/// A daylight-white lamp (of the daylight locus' colours, [`DAYLIGHT_PANEL_K`] and up, not a
/// strip; warmer whites indoors are most often LEDs of the catalogue's kinds) whose
/// white is no LED's or xenon table's within a just noticeable difference: a panel, a softbox
/// or a flash of unknown kind, or a lamp the camera was white-balanced to. The daylight of its
/// colour is the proxy that costs least across them (the ColorChecker's mean CIEDE2000 from a
/// xenon flash 0.45, from FL7 1.1, FL8 0.5; a wrong table costs 1.3 to 2.5:
/// `tools/lamp_rendition.py`).
fn unknown_daylight_white(c: &Candidate, m: &LampMatch) -> bool {
    let known = m.distance_uv <= super::families::SAME_WHITE_UV
        && matches!(m.family, super::Family::Led | super::Family::Xenon);
    c.colour.daylight()
        && c.colour.cct_k.is_some_and(|k| k >= DAYLIGHT_PANEL_K)
        && c.e.stats.elongation < super::families::STRIP_ELONGATION
        && !known
}

/// Inside an enclosure with no sky in view, a daylight-white emitter below [`WINDOW_BLUE_K`] is a
/// lamp (a white lamp's CCT tops out near 7000 K; skylight through a window is bluer), and one
/// at most [`LIT_BY_LAMP`] of the brightest lamp is a surface the lamps light: both leave
/// `daylight` for the lamps' rules.
fn indoor_daylight(candidates: &[Candidate], daylight: &mut Vec<(usize, LightKind)>) {
    let peak = |k: usize| candidates[k].e.stats.peak;
    let lamp = |k: usize| {
        candidates[k]
            .colour
            .cct_k
            .is_some_and(|t| t < WINDOW_BLUE_K)
    };
    let lamp_peak = (0..candidates.len())
        .filter(|&k| lamp(k) || !daylight.iter().any(|d| d.0 == k))
        .map(peak)
        .fold(0f64, f64::max);
    daylight.retain(|&(k, _)| !lamp(k) && peak(k) > LIT_BY_LAMP * lamp_peak);
}

/// At dusk (the sky holding under [`DUSK_SKY_SHARE`] of the energy), a daylight-white emitter
/// smaller than a sky whose mean luminance is
/// [`DAYLIGHT_LAMP_CONTRAST`] times the sky's bright parts (the 95th percentile of its cells) is
/// a lamp (a cool LED street lamp at dusk), not a patch of sky or a window: it leaves `daylight`
/// (a blurred sun, the brightest candidate, stays).
fn outshining_the_sky(
    cells: &Cells,
    candidates: &[Candidate],
    dim: &[Region],
    blurred_sun: bool,
    total_energy: f64,
    daylight: &mut Vec<(usize, LightKind)>,
) {
    let skies: Vec<(usize, LightKind)> = (daylight.iter().copied())
        .filter(|d| d.1 == LightKind::Sky)
        .collect();
    let dim_skies: Vec<&Region> = dim
        .iter()
        .filter(|d| kind_of(&d.stats) == LightKind::Sky)
        .collect();
    let sky_energy: f64 = (skies.iter().map(|&(k, _)| candidates[k].e.stats.energy))
        .chain(dim_skies.iter().map(|d| d.stats.energy))
        .sum();
    if sky_energy >= DUSK_SKY_SHARE * total_energy || (skies.is_empty() && dim_skies.is_empty()) {
        return;
    }
    let level = daylight_level(cells, candidates, &skies, dim_skies.iter().copied());
    daylight.retain(|&(k, kind)| {
        kind == LightKind::Sky
            || (k == 0 && blurred_sun)
            || candidates[k].e.stats.mean_xyz[1] < DAYLIGHT_LAMP_CONTRAST * level
    });
}

/// Whether an emitter could be open sky by its shape: not a core inside an enclosure's surface,
/// reaching above the horizon, and, in a map with an enclosure, wide ([`SKY_LARGE_SR`]) and smooth (its core, the cells
/// within a tenth of its peak, [`SKY_SMOOTH`] of it or more): a softbox's glow on a ceiling is a
/// bright blob and a lit strip of the ceiling is narrow; neither is sky, and a small opening is
/// a window.
fn open_sky_shape(c: &Candidate, indoors: &Indoors) -> bool {
    let st = &c.e.stats;
    !c.core
        && st.top_elevation_deg > 0.0
        && (!indoors.enclosed
            || (c.e.core_solid_angle_sr >= SKY_SMOOTH * st.solid_angle_sr
                && st.solid_angle_sr >= SKY_LARGE_SR))
}

/// A bright patch of daylight colour above the horizon, at least [`SKY_MIN_K`].
fn is_sky_patch(c: &Candidate) -> bool {
    c.colour.daylight()
        && c.colour.cct_k.is_some_and(|k| k >= SKY_MIN_K)
        && c.e.stats.elevation_deg() > 0.0
}

/// A bright daylight-coloured emitter large enough to be a window or a patch of sky.
fn is_window(c: &Candidate) -> bool {
    c.colour.daylight()
        && c.colour.cct_k.is_some_and(|k| k >= WINDOW_MIN_K)
        && c.e.stats.solid_angle_sr >= WINDOW_MIN_SR
}

/// Sky when it reaches high or covers much of the sky, otherwise a window.
fn kind_of(s: &RegionStats) -> LightKind {
    if s.top_elevation_deg >= SKY_TOP_DEG || s.solid_angle_sr >= SKY_LARGE_SR {
        LightKind::Sky
    } else {
        LightKind::Window
    }
}

/// A dim daylight-coloured region.
struct Region {
    cells: Vec<usize>,
    stats: RegionStats,
}

/// The dim daylight-coloured regions of the upper hemisphere that no lamp explains and no window
/// lights.
fn dim_skies(
    cells: &Cells,
    emitters: &[Candidate],
    lamp_whites: &[Colour],
    windows: &[(Colour, f64)],
    indoors: &mut Indoors,
) -> Result<Vec<Region>> {
    let lights = emitter_cells(emitters);
    let lamp_peak = emitters
        .iter()
        .filter(|c| !is_window(c))
        .map(|c| c.e.stats.peak)
        .fold(0f64, f64::max);
    let in_emitter = emitter_mask(cells, emitters);
    let mask: Vec<bool> = (0..cells.len())
        .into_par_iter()
        .map(|i| {
            !in_emitter[i]
                && cells.y[i] > 0.0
                && cells.direction(i)[1] > 0.0
                && daylight_coloured(&cells.xyz(i))
        })
        .collect();
    let mut out = Vec::new();
    for region in components(cells, &mask) {
        let stats = RegionStats::of(cells, &region);
        if stats.solid_angle_sr < SKY_MIN_SR {
            continue;
        }
        let surface = (!indoors.outdoors)
            .then(|| surface_reason(cells, &region, &lights))
            .flatten();
        if let Some(why) = surface {
            indoors.enclosed = true;
            indoors.surfaces.push(format!(
                "a dim daylight-coloured region ({} pixels, {:.2} sr) is no sky: {why}",
                region.len(),
                stats.solid_angle_sr
            ));
            continue;
        }
        let colour = Colour::of(stats.mean_xyz)?;
        // A night sky may share a lamp's colour, but no lamp lights a region reaching the zenith
        // this dimly: far below what lit walls get.
        let night_sky = stats.top_elevation_deg >= SKY_TOP_DEG
            && stats.mean_xyz[1] < NIGHT_SKY_CONTRAST * lamp_peak;
        let lit = explained(&colour, lamp_whites, windows) && !night_sky;
        if !colour.cct_k.is_some_and(|k| k >= SKY_MIN_K) || lit {
            continue;
        }
        let lit_by_window = windows.iter().any(|(w, y)| {
            colour.uv_distance(w) <= EXPLAINED_UV && stats.mean_xyz[1] * LIT_BY_WINDOW <= *y
        });
        if !lit_by_window {
            out.push(Region {
                cells: region,
                stats,
            });
        }
    }
    Ok(out)
}

/// Whether a colour is a lamp's white, a mix of two lamps' or of a lamp's and a window's (within
/// [`EXPLAINED_UV`]): the colour of a surface they light.
fn explained(c: &Colour, lamps: &[Colour], windows: &[(Colour, f64)]) -> bool {
    let p = c.uv;
    let near_segment = |a: [f64; 2], b: [f64; 2]| {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len2 = dx * dx + dy * dy;
        let t = if len2 > 0.0 {
            (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy) <= EXPLAINED_UV
    };
    lamps.iter().enumerate().any(|(i, a)| {
        lamps[i..].iter().any(|b| near_segment(a.uv, b.uv))
            || windows.iter().any(|(w, _)| near_segment(a.uv, w.uv))
    })
}

/// The index of the sun among the candidates, or why there is none.
fn sun_of(
    candidates: &[Candidate],
    levels: &Levels,
    daylight: bool,
    settings: &SceneSettings,
) -> std::result::Result<usize, String> {
    let Some(s) = &settings.sun else {
        return Err(super::sun::SUN_OFF.into());
    };
    let Some(c) = candidates.first() else {
        return Err("nothing in the map stands out".into());
    };
    let st = &c.e.stats;
    let region = format!(
        "the brightest region ({} pixels, core {:.2e} sr, {:.1}% of the energy, {:.1} degrees \
         up, {})",
        c.e.cells.len(),
        c.e.core_solid_angle_sr,
        100.0 * st.energy / levels.total_energy,
        st.elevation_deg(),
        c.colour.describe()
    );
    let share = st.energy / levels.total_energy;
    let checks: [(bool, String); 6] = [
        (
            c.e.core_solid_angle_sr <= s.max_solid_angle_sr,
            format!(
                "its core is not compact (a sun covers at most {:.2e} sr)",
                s.max_solid_angle_sr
            ),
        ),
        (
            st.peak >= SUN_CONTRAST * levels.median,
            format!("it is not {SUN_CONTRAST:.0} times brighter than the map's median"),
        ),
        (
            st.elevation_deg() >= SUN_MIN_ELEVATION_DEG,
            "it is below the horizon".into(),
        ),
        (
            c.colour.cct_k.is_some() && c.colour.duv.abs() <= SUN_MAX_DUV,
            "its colour is neither daylight nor Planckian".into(),
        ),
        (
            unique(c, &candidates[1..]),
            format!(
                "it is not unique: another emitter's peak is within {:.0}x of its own",
                1.0 / SUN_UNIQUE
            ),
        ),
        (
            daylight
                || (share >= s.min_energy_share && c.colour.cct_k.is_some_and(|k| k >= 4000.0)),
            format!(
                "no daylight sky or window is seen with it, and it does not hold {:.0}% of the \
                 energy in a daylight colour",
                100.0 * s.min_energy_share
            ),
        ),
    ];
    match checks.iter().find(|(ok, _)| !ok) {
        Some((_, why)) => Err(format!("{region}: {why}")),
        None => Ok(0),
    }
}

/// No other emitter rivals `c`'s peak, but for its reflections (below the horizon, its colour).
fn unique(c: &Candidate, others: &[Candidate]) -> bool {
    others.iter().all(|o| {
        let reflection =
            o.e.stats.elevation_deg() < 0.0 && o.colour.uv_distance(&c.colour) <= LAMP_MATCH_UV;
        reflection || o.e.stats.peak < SUN_UNIQUE * c.e.stats.peak
    })
}

fn share(levels: &Levels, s: &RegionStats) -> f64 {
    if levels.total_energy > 0.0 {
        s.energy / levels.total_energy
    } else {
        0.0
    }
}

/// A light from a set of cells, measured.
fn light_of(
    cells: &Cells,
    levels: &Levels,
    set: Vec<usize>,
    kind: LightKind,
    colour: Colour,
    spd: LightSpd,
    reason: String,
) -> Light {
    let st = RegionStats::of(cells, &set);
    Light {
        kind,
        spd: spd.label(),
        spd_choice: spd,
        cct_k: colour.cct_k,
        duv: colour.duv,
        xy: colour.xy,
        pixels: set.len(),
        solid_angle_sr: st.solid_angle_sr,
        energy_share: share(levels, &st),
        direction: st.direction,
        elevation_deg: st.elevation_deg(),
        clipped_pixels: set.iter().filter(|&&i| levels.is_clipped(cells, i)).count(),
        colour_from_halo: false,
        lamp: None,
        reason,
        colour: colour.xyz,
        cells: set,
    }
}

/// The daylight of a colour: CIE daylight within its range, Planckian below.
fn daylight_spd(c: &Colour) -> LightSpd {
    LightSpd::Daylight {
        cct_k: c.cct_k.unwrap_or(6504.0),
    }
}

fn sun_light(
    cells: &Cells,
    levels: &Levels,
    c: &Candidate,
    settings: &SceneSettings,
) -> Result<Light> {
    let s = settings.sun.as_ref().expect("a sun was searched for");
    let peak_dir = Vector3::from(cells.direction(c.e.stats.peak_cell));
    let cos_max = s.max_radius_deg.to_radians().cos();
    let core: Vec<usize> =
        c.e.cells
            .iter()
            .copied()
            .filter(|&i| {
                cells.y[i] as f64 >= s.peak_fraction * c.e.stats.peak
                    && Vector3::from(cells.direction(i)).dot(&peak_dir) >= cos_max
            })
            .collect();
    let mut l = light_of(
        cells,
        levels,
        core,
        LightKind::Sun,
        c.colour,
        daylight_spd(&c.colour),
        format!(
            "compact, {:.0} times the median luminance, {:.1} degrees up, {}, unique, with \
             daylight about{}",
            c.e.stats.peak / levels.median,
            c.e.stats.elevation_deg(),
            c.colour.describe(),
            c.e.colour_note()
        ),
    );
    l.colour_from_halo = c.e.colour_from_halo;
    Ok(l)
}

fn daylight_light(
    cells: &Cells,
    levels: &Levels,
    set: Vec<usize>,
    kind: LightKind,
    why: String,
) -> Result<Light> {
    let st = RegionStats::of(cells, &set);
    let colour = Colour::of(st.mean_xyz)?;
    let reason = format!(
        "{why} ({}, {:.3} sr, mean luminance {:.3e})",
        colour.describe(),
        st.solid_angle_sr,
        st.mean_xyz[1]
    );
    Ok(light_of(
        cells,
        levels,
        set,
        kind,
        colour,
        daylight_spd(&colour),
        reason,
    ))
}

/// What is known about daylight when a lamp candidate is judged.
struct Context {
    daylight: bool,
    /// A sky is in view.
    sky: bool,
    /// The luminance of the sky's and windows' bright parts.
    daylight_level: f64,
    sun: Option<Colour>,
    /// Inside an enclosure with no sky in view.
    inside: bool,
}

/// A lamp's match, or why the emitter is a bright reflector instead.
fn lamp_or_reflector(
    c: &Candidate,
    ctx: &Context,
    settings: &SceneSettings,
) -> Result<std::result::Result<LampMatch, String>> {
    let st = &c.e.stats;
    let m = match_lamp(c.colour.uv, c.colour.cct_k, st.elongation)?;
    let what = format!(
        "a bright region ({} pixels, {:.1} degrees up, {})",
        c.e.cells.len(),
        st.elevation_deg(),
        c.colour.describe()
    );
    if let Some(sun) = &ctx.sun {
        if st.elevation_deg() < 0.0 && c.colour.uv_distance(sun) <= LAMP_MATCH_UV {
            return Ok(Err(format!(
                "{what} below the horizon of the sun's colour: a reflection of the sun"
            )));
        }
    }
    let named = settings.lamps.is_some();
    let outshines = st.mean_xyz[1] >= DAYLIGHT_LAMP_CONTRAST * ctx.daylight_level;
    if ctx.daylight && !outshines && st.elevation_deg() < 0.0 {
        return Ok(Err(format!(
            "{what} below the horizon in daylight and not {DAYLIGHT_LAMP_CONTRAST:.0} times \
             brighter than the sky: a sunlit surface or a reflection"
        )));
    }
    if ctx.daylight && !named && m.nearest_uv > LAMP_MATCH_UV && !outshines {
        return Ok(Err(format!(
            "{what} matches no lamp (nearest white at {:.4} uv) and is not \
             {DAYLIGHT_LAMP_CONTRAST:.0} times brighter than the sky: a sunlit or daylit surface",
            m.nearest_uv
        )));
    }
    Ok(Ok(m))
}

/// A lamp's spectrum: `--light`'s table; the daylight of its colour for a daylight-white panel
/// of unknown kind; the sodium mix of its white; a black body for a filament; else the matched
/// table.
fn lamp_spd(
    c: &Candidate,
    m: &LampMatch,
    settings: &SceneSettings,
    daylight_panel: bool,
) -> LightSpd {
    match &settings.lamps {
        Some(name) => LightSpd::Table { name: name.clone() },
        None if daylight_panel => daylight_spd(&c.colour),
        None => match (&m.mix, m.family) {
            (Some(mix), _) => LightSpd::Mix(mix.clone()),
            (None, super::Family::Incandescent) => LightSpd::Planckian {
                cct_k: c
                    .colour
                    .cct_k
                    .unwrap_or(2856.0)
                    .clamp(super::families::FILAMENT_K.0, super::families::FILAMENT_K.1),
            },
            (None, _) => LightSpd::Table {
                name: m.spd.clone(),
            },
        },
    }
}

fn lamp_light(
    cells: &Cells,
    levels: &Levels,
    c: &Candidate,
    m: LampMatch,
    settings: &SceneSettings,
    inside: bool,
) -> Light {
    let what = if inside && c.colour.daylight() {
        "a daylight-white emitter inside an enclosure with no sky in view"
    } else {
        "an emitter not of daylight"
    };
    let daylight_panel = inside && unknown_daylight_white(c, &m);
    let spd = lamp_spd(c, &m, settings, daylight_panel);
    let mixed = m.mix.as_ref().map_or(String::new(), |mix| {
        format!(
            "; its white lies between the standard and the colour-improved sodium lamp's: {}",
            mix.label()
        )
    });
    let reason = match &settings.lamps {
        Some(name) => format!(
            "{what}; its spectrum is {name} (--light); its colour is nearest {} ({}, {:.4} uv)",
            m.spd,
            m.family.name(),
            m.distance_uv
        ),
        None if daylight_panel => format!(
            "{what} ({}); no LED or xenon table has its white (nearest {}, {}, {:.4} uv): a \
             daylight-white panel or flash of unknown kind, given the daylight of its colour",
            c.colour.describe(),
            m.spd,
            m.family.name(),
            m.distance_uv
        ),
        None => format!(
            "{what} ({}); {} ({}, {:.4} uv from its white: {}){mixed}",
            c.colour.describe(),
            m.spd,
            m.family.name(),
            m.distance_uv,
            m.why
        ),
    };
    // The lamp itself: its brightest part (its glow and the surfaces round it are reflectors).
    let lamp_cells: Vec<usize> =
        c.e.cells
            .iter()
            .copied()
            .filter(|&i| cells.y[i] as f64 >= LAMP_CORE * c.e.stats.peak)
            .collect();
    let mut l = light_of(
        cells,
        levels,
        lamp_cells,
        LightKind::Lamp,
        c.colour,
        spd,
        reason,
    );
    l.colour_from_halo = c.e.colour_from_halo;
    l.clipped_pixels = c.e.clipped_cells;
    l.lamp = Some(m);
    l
}
