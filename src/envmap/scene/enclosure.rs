//! Open sky, or the inside of a room: whether a wide bright region is the sky or the walls,
//! ceiling and floor of an enclosure that its own lamps light.
//!
//! An open sky ends at the horizon: what lies under it (the ground, a street, the sea) is another
//! surface, far darker or far brighter. A room's walls and a studio's cyclorama go on below the
//! horizon as bright as above it, and the lamps inside are far brighter than they are. So a wide
//! region is a surface of an enclosure when both hold:
//! 1. **it goes on below the horizon**: along [`CONTINUES_COLUMNS`] of its cells at the horizon,
//!    the band under them (down to [`BAND_DEG`] below) is between [`CONTINUES`] and its inverse
//!    times as bright as they are;
//! 2. **lamps light it**: emitters in the map, or cores inside the region, peak at [`OUTSHONE`]
//!    times the region's median luminance or more (a ceiling spot, a softbox) and hold
//!    [`LIT_SHARE`] of its energy (a star or a far street lamp cannot light a sky);
//! 3. it covers [`MIN_SURFACE_SR`] or more.
//!
//! A surface of an enclosure is not a light. The bright cores inside one ([`CORE_CONTRAST`] times
//! its level, the lower quartile of its luminance: softboxes, panels, spots) are emitters of their
//! own. With a surface found and no
//! open sky in view the map is indoors ([`Indoors`]): there is no sun, and a daylight-white
//! emitter below [`WINDOW_BLUE_K`] is a lamp (an LED panel, a flash, a tube), not a window; a
//! bluer one is a window showing the sky.

use super::cells::Cells;
use super::emitters::{self, Emitter, Levels};
use super::regions::{components, mask, RegionStats};

/// A region goes on below the horizon where the band under it is at least this fraction (and
/// at most its inverse) of its luminance at the horizon.
pub(crate) const CONTINUES: f64 = 0.5;
/// ...along at least this fraction of its cells at the horizon.
pub(crate) const CONTINUES_COLUMNS: f64 = 0.7;
/// The band under the horizon a region is compared with (degrees).
pub(crate) const BAND_DEG: f64 = 8.0;
/// A region touches the horizon when it has at least this many cells in the row above it.
pub(crate) const MIN_EDGE_CELLS: usize = 8;
/// An emitter or core this many times the region's median luminance outshines it.
pub(crate) const OUTSHONE: f64 = 30.0;
/// The emitters that outshine a surface hold at least this fraction of its energy: lamps that
/// light the walls (a wall lit by a lamp returns about rho / pi of the lamp's energy per sr), not
/// a star or a far street lamp over a night sky.
pub(crate) const LIT_SHARE: f64 = 0.1;
/// A surface of an enclosure covers at least this solid angle (sr): a wall, not a patch.
pub(crate) const MIN_SURFACE_SR: f64 = 0.25;
/// The cores of an enclosure's surface are its cells this many times its level (the lower
/// quartile of its luminance).
pub(crate) const CORE_CONTRAST: f64 = 10.0;
/// Indoors, a daylight-white emitter below this CCT (K) is a lamp, one at or above it a window:
/// white lamps reach about 7000 K (CIE LED-B5 6598 K, FL7 6500 K, a xenon flash 6000-6500 K),
/// skylight through a window is bluer.
pub(crate) const WINDOW_BLUE_K: f64 = 8000.0;

/// What is known of the map's enclosure.
#[derive(Debug, Clone, Default)]
pub(crate) struct Indoors {
    /// Surfaces of an enclosure were found (each described in `surfaces`).
    pub enclosed: bool,
    /// Why each surface is one, in words.
    pub surfaces: Vec<String>,
    /// The brightest emitter is a sun by its shape: the map is outdoors, and no region is
    /// judged a surface of an enclosure.
    pub outdoors: bool,
    /// The brightest emitter is a sun seen through blur or haze under a bluer sky.
    pub blurred_sun: bool,
}

/// How a region meets the horizon: the fraction of its cells in the row just above the horizon
/// whose band below is about as bright as they are (None: it does not touch the horizon).
pub(crate) fn continuation(cells: &Cells, region: &[usize]) -> Option<f64> {
    let (w, h) = (cells.width, cells.height);
    let edge_row = h / 2 - 1;
    let band = ((BAND_DEG / 180.0 * h as f64).round() as usize).max(1);
    let edge: Vec<usize> = region
        .iter()
        .copied()
        .filter(|&i| i / w == edge_row)
        .collect();
    if edge.len() < MIN_EDGE_CELLS {
        return None;
    }
    let continues = edge
        .iter()
        .filter(|&&i| {
            let x = i % w;
            let mut below: Vec<f32> = (h / 2..(h / 2 + band).min(h))
                .map(|r| cells.y[r * w + x])
                .collect();
            below.sort_by(|a, b| a.total_cmp(b));
            let ratio = below[below.len() / 2] as f64 / (cells.y[i] as f64).max(1e-30);
            (CONTINUES..=1.0 / CONTINUES).contains(&ratio)
        })
        .count();
    Some(continues as f64 / edge.len() as f64)
}

/// The level of a surface: the lower quartile of its cells' luminance, whatever lamps it holds.
pub(crate) fn surface_level(cells: &Cells, region: &[usize]) -> f64 {
    luminance_quantile(cells, region, 4)
}

/// The median luminance of a region's cells.
pub(crate) fn median_luminance(cells: &Cells, region: &[usize]) -> f64 {
    luminance_quantile(cells, region, 2)
}

/// The luminance below which `1 / parts` of a region's cells lie (0 for no cells).
fn luminance_quantile(cells: &Cells, region: &[usize], parts: usize) -> f64 {
    let mut y: Vec<f32> = region.iter().map(|&i| cells.y[i]).collect();
    if y.is_empty() {
        return 0.0;
    }
    y.sort_by(|a, b| a.total_cmp(b));
    y[y.len() / parts] as f64
}

/// Why `region` is a surface of an enclosure (see the module), or None. `others` are the cells
/// of the map's other emitters; their cells and the region's own that outshine it count.
pub(crate) fn surface_reason(
    cells: &Cells,
    region: &[usize],
    others: &[&[usize]],
) -> Option<String> {
    let st = RegionStats::of(cells, region);
    if st.solid_angle_sr < MIN_SURFACE_SR {
        return None;
    }
    let goes_on = continuation(cells, region)?;
    let floor = OUTSHONE * median_luminance(cells, region);
    let bright = (others.iter().copied().chain([region]).flatten())
        .map(|&i| (cells.y[i] as f64, cells.omega(i)))
        .filter(|&(y, _)| y >= floor);
    let (peak, energy) = bright.fold((0f64, 0f64), |(p, e), (y, w)| (p.max(y), e + y * w));
    let lit = energy >= LIT_SHARE * st.energy;
    (goes_on >= CONTINUES_COLUMNS && peak > 0.0 && lit).then(|| {
        format!(
            "it goes on below the horizon as bright along {:.0}% of its edge there, and emitters \
             up to {:.0} times its median luminance, holding {:.0}% of its energy, outshine it: \
             the walls of an enclosure its lamps light",
            100.0 * goes_on,
            peak * OUTSHONE / floor,
            100.0 * energy / st.energy
        )
    })
}

/// An emitter that is a surface of an enclosure: its bright cores as emitters of their own (see
/// the module), and why it is a surface; None when it is not one.
pub(crate) fn split_surface(
    cells: &Cells,
    levels: &Levels,
    e: &Emitter,
    others: &[&[usize]],
) -> Option<(Vec<Emitter>, String)> {
    let reason = surface_reason(cells, &e.cells, others)?;
    let floor = CORE_CONTRAST * surface_level(cells, &e.cells);
    let bright = mask(
        cells,
        e.cells
            .iter()
            .copied()
            .filter(|&i| cells.y[i] as f64 >= floor),
    );
    let cores = components(cells, &bright)
        .into_iter()
        .map(|core| emitters::emitter(cells, levels, core))
        .collect();
    let what = format!(
        "a wide bright region ({} pixels, {:.2} sr, {:.1} degrees up) is no light: {reason}",
        e.cells.len(),
        e.stats.solid_angle_sr,
        e.stats.elevation_deg()
    );
    Some((cores, what))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::RgbSpace;
    use crate::envmap::layout::{EnvMap, Layout};
    use crate::envmap::RgbImage;

    /// A 64 x 32 map: `above` over the horizon, `below` under it.
    fn cells(above: f32, below: f32) -> Cells {
        let mut img = RgbImage::new(64, 32);
        for y in 0..32 {
            for x in 0..64 {
                let v = if y < 16 { above } else { below };
                img.set(x, y, [v, v, v]);
            }
        }
        let map = EnvMap::new(Layout::LatLong, img).unwrap();
        Cells::new(&map, &RgbSpace::SRGB, [1.0; 3])
    }

    #[test]
    fn a_wall_goes_on_below_the_horizon_and_a_sky_over_dark_ground_does_not() {
        let upper: Vec<usize> = (0..16 * 64).collect();
        assert_eq!(continuation(&cells(1.0, 0.9), &upper), Some(1.0));
        assert_eq!(continuation(&cells(1.0, 0.1), &upper), Some(0.0));
        // A lit street far brighter than a night sky is another surface too.
        assert_eq!(continuation(&cells(0.01, 1.0), &upper), Some(0.0));
        // A region that never reaches the horizon is not judged.
        let high: Vec<usize> = (0..8 * 64).collect();
        assert_eq!(continuation(&cells(1.0, 1.0), &high), None);
    }

    #[test]
    fn a_wall_is_a_surface_only_when_something_outshines_it() {
        let upper: Vec<usize> = (0..16 * 64).collect();
        // The region is 1.0 above the horizon, 0.9 below; lamps are painted over it.
        let lamp = |c: &mut Cells, at: &[usize], y: f32| {
            for &i in at {
                c.y[i] = y;
            }
        };
        let (small, big): (Vec<usize>, Vec<usize>) = ((0..2).collect(), (0..64).collect());
        let mut c = cells(1.0, 0.9);
        lamp(&mut c, &small, 5.0);
        // A lamp not bright enough, a bright one too small to light it, one that lights it.
        assert!(surface_reason(&c, &upper, &[&small]).is_none());
        lamp(&mut c, &small, 100.0);
        assert!(surface_reason(&c, &upper, &[&small]).is_none());
        lamp(&mut c, &big, 100.0);
        let why = surface_reason(&c, &upper, &[&big]).unwrap();
        assert!(why.contains("100 times"), "{why}");
    }
}
