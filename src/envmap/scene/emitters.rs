//! Emitter candidates: the connected regions far brighter than the scene's typical luminance,
//! each with its core, its colour (from its unclipped halo where the core is clipped) and shape.

use super::cells::{weighted_quantile, Cells};
use super::regions::{components, RegionStats};
use nalgebra::Vector3;

/// The scene's luminance levels that emitters are measured against (all 0 where the scene was
/// not analysed).
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct Levels {
    /// The solid-angle-weighted median luminance of the map: a typical reflector.
    pub median: f64,
    /// Cells at least this bright are emitter candidates (`contrast` x the median).
    pub threshold: f64,
    /// Sum of luminance x solid angle over the map.
    pub total_energy: f64,
    /// The largest channel value of the input (the clip level, if the map was clipped).
    pub max_channel: f64,
    /// The map holds a clipped plateau: several pixels with two or more channels at its largest
    /// value, or values at the half-float ceiling.
    pub clipped: bool,
}

/// Channels within this fraction of the map's largest value are at the clip level.
const CLIP_FRACTION: f64 = 0.98;
/// Values at or above this are at the half-float ceiling (65504).
const HALF_CEILING: f64 = 65000.0;
/// Pixels within this fraction of the brightest pixel's luminance belong to its core.
const CORE_FRACTION: f64 = 0.1;
/// How many rings of neighbours around a clipped core are searched for its halo.
const HALO_RINGS: usize = 3;

impl Levels {
    /// The levels of `cells`, emitter candidates at `contrast` times the median luminance.
    pub fn of(cells: &Cells, contrast: f64) -> Levels {
        let total_energy: f64 = (0..cells.len())
            .map(|i| cells.y[i] as f64 * cells.omega(i))
            .sum();
        let peak = cells.y.iter().fold(0f32, |m, &v| m.max(v)) as f64;
        // A mostly black map (a studio) has a median of 0: emitters are then what is lit at all.
        let median = weighted_quantile(cells, &cells.y, 0.5).max(1e-6 * peak);
        let max_channel = (0..cells.len())
            .flat_map(|i| cells.raw(i))
            .fold(0f64, f64::max);
        let at_clip = |i: usize| cells.clipped_channels(i, max_channel) >= 2;
        let plateau = (0..cells.len()).filter(|&i| at_clip(i)).take(2).count() >= 2;
        Levels {
            median,
            threshold: contrast * median,
            total_energy,
            max_channel,
            clipped: plateau || max_channel >= HALF_CEILING,
        }
    }

    /// Whether a cell is clipped: two or more channels at the clip level of a clipped map, or any
    /// at the half-float ceiling.
    pub fn is_clipped(&self, cells: &Cells, i: usize) -> bool {
        self.clipped
            && (cells.clipped_channels(i, self.max_channel) >= 2
                || cells.raw(i).iter().any(|&v| v >= HALF_CEILING))
    }

    /// Whether a cell's colour cannot be read from it: clipped ([`Levels::is_clipped`]), or a
    /// pure primary of the space (see [`Cells::pure_primary`]).
    pub fn colour_lost(&self, cells: &Cells, i: usize) -> bool {
        self.is_clipped(cells, i) || cells.pure_primary(i)
    }
}

/// A lit cell whose other two channels are at most this fraction of its largest is a pure
/// primary of the space.
const PURE_PRIMARY: f64 = 1e-3;

impl Cells {
    /// Whether the cell is lit in one channel only: its other two at most [`PURE_PRIMARY`] of it.
    /// No light or surface of a photograph is a pure primary of the space it was stored in; a
    /// lossy codec that lost a block's colour leaves one (the DWAB-compressed sun of
    /// @pmndrs/assets' `park` is a 6 x 6 patch of blue only, B from -1876 to 11800, R and G under
    /// 1e-5).
    pub fn pure_primary(&self, i: usize) -> bool {
        let mut v = self.raw(i);
        v.sort_by(|a, b| b.total_cmp(a));
        v[0] > 0.0 && v[1] <= PURE_PRIMARY * v[0]
    }

    /// The cell's channels as the input had them (before the white premise's balance).
    pub fn raw(&self, i: usize) -> [f64; 3] {
        std::array::from_fn(|k| self.rgb[i][k] as f64 / self.balance[k])
    }

    fn clipped_channels(&self, i: usize, max_channel: f64) -> usize {
        self.raw(i)
            .iter()
            .filter(|&&v| v >= CLIP_FRACTION * max_channel)
            .count()
    }
}

/// A connected region of emitter candidates.
#[derive(Debug, Clone)]
pub(crate) struct Emitter {
    /// Its cells (indices, sorted).
    pub cells: Vec<usize>,
    /// The region's measures: energy, solid angle, direction, colour, extent.
    pub stats: RegionStats,
    /// Solid angle of its core, the cells at least `CORE_FRACTION` (0.1) of its peak luminance:
    /// a sun's disc, a bulb (sr).
    pub core_solid_angle_sr: f64,
    /// Its colour as XYZ with Y = 1: of its core; where the core is clipped, of the rest of the
    /// region or of its halo (the unclipped glow around it).
    pub colour: Vector3<f64>,
    /// Its colour was taken from outside its clipped core (the rest of the region or its halo).
    pub colour_from_halo: bool,
    /// Its cells at the clip level ([`Levels::is_clipped`]).
    pub clipped_cells: usize,
    /// Its cells lit in one primary only ([`Cells::pure_primary`]): their colour is lost.
    pub primary_cells: usize,
}

impl Emitter {
    /// Where its colour came from when its core's was lost to a codec; "" otherwise (a clipped
    /// core says so in `colour_from_halo` and `clipped_pixels`).
    pub(crate) fn colour_note(&self) -> String {
        match (self.colour_from_halo, self.primary_cells) {
            (false, _) | (true, 0) => String::new(),
            (true, n) => format!(
                "; its core's colour is lost ({n} pixels lit in one primary only, as a lossy \
                 codec leaves a damaged block): its colour is that of the light around it"
            ),
        }
    }
}

/// The emitter candidates of the map, brightest peak first.
pub(crate) fn find(cells: &Cells, levels: &Levels) -> Vec<Emitter> {
    let mask: Vec<bool> = cells
        .y
        .iter()
        .map(|&y| y as f64 >= levels.threshold && y > 0.0)
        .collect();
    let mut out: Vec<Emitter> = components(cells, &mask)
        .into_iter()
        .map(|region| emitter(cells, levels, region))
        .collect();
    out.sort_by(|a, b| b.stats.peak.total_cmp(&a.stats.peak));
    out
}

pub(crate) fn emitter(cells: &Cells, levels: &Levels, region: Vec<usize>) -> Emitter {
    let stats = RegionStats::of(cells, &region);
    let core: Vec<usize> = region
        .iter()
        .copied()
        .filter(|&i| cells.y[i] as f64 >= CORE_FRACTION * stats.peak)
        .collect();
    let core_solid_angle_sr = core.iter().map(|&i| cells.omega(i)).sum();
    let clipped_cells = region
        .iter()
        .filter(|&&i| levels.is_clipped(cells, i))
        .count();
    let primary_cells = region.iter().filter(|&&i| cells.pure_primary(i)).count();
    let unclipped = |set: &[usize]| -> Vec<usize> {
        set.iter()
            .copied()
            .filter(|&i| !levels.colour_lost(cells, i))
            .collect()
    };
    let energy = |set: &[usize]| -> f64 {
        set.iter()
            .map(|&i| cells.y[i] as f64 * cells.omega(i))
            .sum()
    };
    // The core's own colour where it is not clipped; else the rest of the region's; else the
    // halo around it.
    let (core_ok, region_ok) = (unclipped(&core), unclipped(&region));
    let (source, from_halo) = if energy(&core_ok) >= 0.01 * energy(&core) && !core_ok.is_empty() {
        (core_ok, false)
    } else if energy(&region_ok) >= 0.01 * stats.energy && !region_ok.is_empty() {
        (region_ok, true)
    } else {
        let h = halo(cells, levels, &region);
        let found = !h.is_empty();
        (if found { h } else { region.clone() }, found)
    };
    let mut xyz = Vector3::zeros();
    for &i in &source {
        xyz += cells.xyz(i) * cells.omega(i);
    }
    let colour = if xyz[1] > 0.0 { xyz / xyz[1] } else { xyz };
    Emitter {
        cells: region,
        stats,
        core_solid_angle_sr,
        colour,
        colour_from_halo: from_halo,
        clipped_cells,
        primary_cells,
    }
}

/// The unclipped, lit cells in up to [`HALO_RINGS`] rings of neighbours around `region`.
fn halo(cells: &Cells, levels: &Levels, region: &[usize]) -> Vec<usize> {
    let mut inside = std::collections::HashSet::<usize>::from_iter(region.iter().copied());
    let mut ring: Vec<usize> = region.to_vec();
    let mut out = Vec::new();
    for _ in 0..HALO_RINGS {
        let mut next = Vec::new();
        for &i in &ring {
            for j in cells.neighbours(i) {
                if inside.insert(j) {
                    next.push(j);
                }
            }
        }
        out.extend(
            next.iter()
                .copied()
                .filter(|&j| cells.y[j] > 0.0 && !levels.colour_lost(cells, j)),
        );
        ring = next;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::RgbSpace;
    use crate::envmap::layout::{EnvMap, Layout};
    use crate::envmap::RgbImage;

    #[test]
    fn a_clipped_lamp_takes_its_colour_from_its_halo() {
        // A dim room, a lamp whose core is clipped white and whose halo is warm.
        let mut img = RgbImage::new(64, 32);
        img.pixels.iter_mut().for_each(|p| *p = [0.05, 0.05, 0.05]);
        for y in 8..15 {
            for x in 28..35 {
                let r2 = (x as f64 - 31.0).powi(2) + (y as f64 - 11.0).powi(2);
                let v = if r2 <= 1.0 {
                    [500.0, 500.0, 500.0]
                } else {
                    let k = 40.0 / r2 as f32;
                    [k, k * 0.75, k * 0.45]
                };
                img.set(x, y, v);
            }
        }
        let map = EnvMap::new(Layout::LatLong, img).unwrap();
        let cells = Cells::new(&map, &RgbSpace::SRGB, [1.0; 3]);
        let levels = Levels::of(&cells, 10.0);
        assert!(levels.clipped, "{levels:?}");
        let e = find(&cells, &levels);
        assert_eq!(e.len(), 1, "{e:?}");
        assert!(e[0].clipped_cells >= 4);
        // The halo's warm colour (x 0.366), not the clipped white (x 0.3127).
        assert!(e[0].colour_from_halo);
        let xyz = e[0].colour;
        let x = xyz[0] / xyz.sum();
        assert!((x - 0.366).abs() < 0.002, "x {x}");
    }

    #[test]
    fn a_core_of_one_primary_takes_its_colour_from_around_it() {
        // A sun whose 4 x 4 block a lossy codec left blue only (as in @pmndrs' `park`), in a warm
        // white glow.
        let mut img = RgbImage::new(128, 64);
        img.pixels.iter_mut().for_each(|p| *p = [0.1, 0.12, 0.2]);
        for y in 24..36 {
            for x in 56..68 {
                let r2 = (x as f64 - 61.5).powi(2) + (y as f64 - 29.5).powi(2);
                let k = 60.0 / (1.0 + r2 as f32);
                img.set(x, y, [k, k * 0.87, k * 0.63]);
            }
        }
        for y in 28..32 {
            for x in 60..64 {
                img.set(x, y, [1e-6, 0.0, 9000.0]);
            }
        }
        let map = EnvMap::new(Layout::LatLong, img).unwrap();
        let cells = Cells::new(&map, &RgbSpace::SRGB, [1.0; 3]);
        let levels = Levels::of(&cells, 10.0);
        let e = find(&cells, &levels);
        assert_eq!(e[0].primary_cells, 16, "{:?}", e[0]);
        assert!(e[0].colour_from_halo);
        assert!(e[0].colour_note().contains("one primary only"));
        // The glow's colour (RGB 1 : 0.87 : 0.63 in sRGB is x 0.3432, colour-science's
        // RGB_to_XYZ), not blue's (x 0.15).
        let xyz = e[0].colour;
        let x = xyz[0] / xyz.sum();
        assert!((x - 0.3432).abs() < 0.002, "x {x}");
    }

    #[test]
    fn an_unclipped_uniform_lamp_keeps_its_own_colour() {
        // Uniform tubes of a measured colour: one channel at the map's maximum, not a plateau.
        let mut img = RgbImage::new(64, 32);
        img.pixels.iter_mut().for_each(|p| *p = [0.05, 0.05, 0.05]);
        for x in 20..40 {
            img.set(x, 3, [1000.0, 900.0, 700.0]);
        }
        let map = EnvMap::new(Layout::LatLong, img).unwrap();
        let cells = Cells::new(&map, &RgbSpace::SRGB, [1.0; 3]);
        let levels = Levels::of(&cells, 10.0);
        assert!(!levels.clipped);
        let e = find(&cells, &levels);
        assert_eq!(e.len(), 1);
        assert!(!e[0].colour_from_halo && e[0].clipped_cells == 0);
        assert!(e[0].stats.elongation > 3.0);
    }
}
