//! Twilight and night skies: open sky of any natural colour, found from the zenith down.
//!
//! A sky at dusk or at night is no daylight colour: blue-purple after sunset, orange where the
//! sun has set, the sodium glow of a city over a night sky. It is still the sky: open, reaching
//! from high up to the horizon, the brightest of it near the horizon. Where the daylight rules
//! found no sky, the twilight sky is grown from the zenith: the upper hemisphere's cells outside
//! every emitter from [`SKY_FLOOR`] to [`SKY_CEILING`] times the luminance around the zenith
//! (trees, roofs and hills against it are far darker, facades lit by street lamps far brighter),
//! connected to the zenith cap (elevation [`ZENITH_DEG`] and
//! up). It is a sky when it covers [`MIN_SR`], reaches down to [`HORIZON_DEG`] and its colour lies
//! on the Planckian locus or the daylight locus (a CCT within 0.05 uv); the bright glows touching
//! it above the horizon join it (see `classify`).

use super::cells::Cells;
use super::enclosure::median_luminance;
use super::regions::{components, RegionStats};
use rayon::prelude::*;

/// The zenith cap the sky is grown from (degrees of elevation and up).
pub(crate) const ZENITH_DEG: f64 = 70.0;
/// A cell is sky-bright at this fraction of the zenith cap's median luminance or more.
pub(crate) const SKY_FLOOR: f64 = 0.3;
/// ...and at most this many times it (brighter: a lit facade; the glow near the horizon
/// brighter still is an emitter, joined later).
pub(crate) const SKY_CEILING: f64 = 10.0;
/// A twilight sky covers at least this solid angle (sr).
pub(crate) const MIN_SR: f64 = 1.0;
/// ...and reaches down to this elevation (degrees).
pub(crate) const HORIZON_DEG: f64 = 10.0;

/// The cells of the open sky grown from the zenith, and their measure; None when there is none
/// (see the module). `in_emitter` marks the emitters' cells, left out.
pub(crate) fn open_sky(cells: &Cells, in_emitter: &[bool]) -> Option<(Vec<usize>, RegionStats)> {
    let elevation = |i: usize| cells.direction(i)[1].clamp(-1.0, 1.0).asin().to_degrees();
    let free = |i: usize| !in_emitter[i] && cells.y[i] > 0.0;
    let cap: Vec<usize> = (0..cells.len())
        .into_par_iter()
        .filter(|&i| free(i) && elevation(i) >= ZENITH_DEG)
        .collect();
    if cap.is_empty() {
        return None;
    }
    let zenith = median_luminance(cells, &cap);
    let (floor, ceiling) = (SKY_FLOOR * zenith, SKY_CEILING * zenith);
    let mask: Vec<bool> = (0..cells.len())
        .into_par_iter()
        .map(|i| {
            let y = cells.y[i] as f64;
            free(i) && elevation(i) > 0.0 && y >= floor && y <= ceiling
        })
        .collect();
    let in_cap = |r: &[usize]| {
        let n = r.iter().filter(|&&i| elevation(i) >= ZENITH_DEG).count();
        2 * n >= cap.len()
    };
    let region = components(cells, &mask).into_iter().find(|r| in_cap(r))?;
    let stats = RegionStats::of(cells, &region);
    let lowest = region.iter().map(|&i| elevation(i)).fold(90.0, f64::min);
    (stats.solid_angle_sr >= MIN_SR && lowest <= HORIZON_DEG).then_some((region, stats))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::RgbSpace;
    use crate::envmap::layout::{EnvMap, Layout};
    use crate::envmap::RgbImage;

    /// A 128 x 64 dusk: a sky brightening towards the horizon, a dark tree line up to `trees`
    /// degrees on half the columns, dark ground.
    fn dusk(trees: f64) -> Cells {
        let mut img = RgbImage::new(128, 64);
        for y in 0..64 {
            let el = 90.0 - (y as f64 + 0.5) * 180.0 / 64.0;
            for x in 0..128 {
                let v = if el < 0.0 || (x < 64 && el < trees) {
                    0.002
                } else {
                    0.05 * (1.0 + 3.0 * (1.0 - el / 90.0))
                };
                img.set(x, y, [v as f32, (v * 0.9) as f32, (v * 1.2) as f32]);
            }
        }
        Cells::new(
            &EnvMap::new(Layout::LatLong, img).unwrap(),
            &RgbSpace::SRGB,
            [1.0; 3],
        )
    }

    #[test]
    fn the_sky_is_grown_from_the_zenith_down_to_the_horizon_and_not_over_the_trees() {
        let c = dusk(20.0);
        let (region, stats) = open_sky(&c, &vec![false; c.len()]).unwrap();
        assert!(stats.solid_angle_sr > 4.0, "{}", stats.solid_angle_sr);
        let over_trees = region
            .iter()
            .filter(|&&i| i % 128 < 64 && c.direction(i)[1] < 20f64.to_radians().sin())
            .count();
        assert_eq!(over_trees, 0);
    }

    #[test]
    fn a_sky_hidden_below_a_high_skyline_is_no_open_sky() {
        // Trees up to 80 degrees on half the map: the sky never reaches the horizon there, but
        // it does on the other half, so it is open; a map dark everywhere has none.
        assert!(open_sky(&dusk(80.0), &vec![false; 128 * 64]).is_some());
        let dark = Cells::new(
            &EnvMap::new(Layout::LatLong, RgbImage::new(128, 64)).unwrap(),
            &RgbSpace::SRGB,
            [1.0; 3],
        );
        assert!(open_sky(&dark, &vec![false; dark.len()]).is_none());
    }
}
