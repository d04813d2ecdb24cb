//! A sky is open sky, smooth in colour and luminance. A sunlit facade under a low sun, a pale
//! tree or a bush on the skyline can be as dim as the sky beside it and of a daylight colour, so
//! the dim daylight-coloured region they belong to joins the sky. Three things tell them from
//! it, and a part of the dim sky is cut from the sky only when all three hold:
//! - its outline against the open sky is a sharp step in colour or luminance between
//!   neighbouring cells, where a sky's gradient, however steep, changes little from one cell to
//!   the next (the step allowed grows with the cells: [`coarseness`]), and its colour is not the
//!   sky's round it (sky seen through leaves is);
//! - it is textured: windows, cornices and leaves are peaks and dips of luminance, which a
//!   gradient has none of;
//! - it stands on what is not sky, where a cloud is sky all round.

use super::cells::Cells;
use super::regions::{components, mask};
use crate::colorimetry::Xyz;
use rayon::prelude::*;

/// Neighbouring cells (of 0.7 degrees) whose luminances differ by this factor or more are an
/// edge.
pub(crate) const SKY_EDGE_RATIO: f64 = 2.0;

/// Neighbouring cells (of 0.7 degrees) this far apart in CIE 1960 uv are an edge: a clear sky
/// changes by under 0.001 between them, a sunlit facade under a blue sky differs from it by 0.02
/// or more.
pub(crate) const SKY_EDGE_UV: f64 = 0.01;

/// A part cut off from the open sky is a surface only from this solid angle of dim sky up (sr).
pub(crate) const CUT_MIN_SR: f64 = 0.02;

/// A cell this many times brighter (or dimmer) than every neighbour in its part is a peak (a
/// dip).
pub(crate) const TEXTURE_STEP: f64 = 1.15;

/// A part is textured where at least this share of its cells are peaks or dips (the facades of
/// `square_sunset` 4 and 5%; a sky's gradient none).
pub(crate) const TEXTURED: f64 = 0.03;

/// A part stands on something where at least this share of the cells round it are not sky.
pub(crate) const CUT_STANDING: f64 = 0.25;

/// A part of the dim sky that is cut from the sky.
#[derive(Debug, Clone)]
pub(crate) struct Cut {
    /// Its cells, sorted.
    pub cells: Vec<usize>,
    /// Its solid angle (sr).
    pub solid_angle_sr: f64,
    /// The share of its cells that are peaks or dips of luminance.
    pub textured: f64,
    /// The share of the cells round it that are not sky.
    pub standing: f64,
}

/// Splits the sky's cells into the open sky and the parts of dim sky (cells where `dim` holds)
/// cut from it. Each connected part of the sky keeps its largest (in solid angle) connected part
/// of smooth cells (none on an edge: [`on_edge`]) and the edge cells touching it; each part of
/// the rest that is mostly dim sky, of [`CUT_MIN_SR`] or more, [`TEXTURED`] and standing
/// ([`CUT_STANDING`]) loses its dim cells. `sky` need not be sorted.
pub(crate) fn split(cells: &Cells, sky: &[usize], dim: &[bool]) -> (Vec<usize>, Vec<Cut>) {
    let in_sky = mask(cells, sky.iter().copied());
    let smooth = smooth_cells(cells, &in_sky);
    let mut kept = vec![false; cells.len()];
    let regions = components(cells, &in_sky);
    let open_parts = largest_smooth_parts(cells, &regions, &smooth);
    for (region, open) in regions.iter().zip(open_parts) {
        keep_open_part(cells, region, open, &smooth, &mut kept);
    }
    let rest: Vec<bool> = (0..cells.len()).map(|i| in_sky[i] && !kept[i]).collect();
    let open_mask = kept.clone();
    let mut cuts = Vec::new();
    for part in components(cells, &rest) {
        match judge(cells, &in_sky, &rest, &open_mask, dim, &part) {
            Some(cut) => {
                part.iter().for_each(|&i| kept[i] = !dim[i]);
                cuts.push(cut);
            }
            None => part.iter().for_each(|&i| kept[i] = true),
        }
    }
    let open = sky.iter().copied().filter(|&i| kept[i]).collect();
    (open, cuts)
}

fn solid_angle(cells: &Cells, part: &[usize]) -> f64 {
    part.iter().map(|&i| cells.omega(i)).sum()
}

/// The sky's cells none of whose sky neighbours is across an edge (cells in parallel).
fn smooth_cells(cells: &Cells, in_sky: &[bool]) -> Vec<bool> {
    let uv: Vec<[f64; 2]> = (0..cells.len())
        .into_par_iter()
        .map(|i| match in_sky[i] {
            true => Xyz::from(cells.xyz(i)).uv1960(),
            false => [0.0; 2],
        })
        .collect();
    let k = coarseness(cells);
    (0..cells.len())
        .into_par_iter()
        .map(|i| in_sky[i] && !on_edge(cells, in_sky, &uv, i, k))
        .collect()
}

/// How many times coarser than 0.7 degrees (a 512-wide lat-long) the cells are, at least 1: a
/// gradient's step between neighbours grows with the cells, a sharp edge's does not.
fn coarseness(cells: &Cells) -> f64 {
    let cell_deg = cells.omega(cells.len() / 2).sqrt().to_degrees();
    (cell_deg / 0.7).max(1.0)
}

/// Whether a sky neighbour of cell `i` is [`SKY_EDGE_RATIO`]`^k` brighter or dimmer, or
/// [`SKY_EDGE_UV`]` k` away in colour.
fn on_edge(cells: &Cells, in_sky: &[bool], uv: &[[f64; 2]], i: usize, k: f64) -> bool {
    let y = cells.y[i] as f64;
    let ratio = SKY_EDGE_RATIO.powf(k);
    cells.neighbours(i).any(|j| {
        let n = cells.y[j] as f64;
        let duv = (uv[i][0] - uv[j][0]).hypot(uv[i][1] - uv[j][1]);
        in_sky[j] && (n >= ratio * y || y >= ratio * n || duv >= SKY_EDGE_UV * k)
    })
}

/// For each region of the sky, its largest (in solid angle) connected part of smooth cells, the
/// last of equal ones in the order [`components`] gives them (None: no cell of it is smooth).
/// A smooth part lies in one region, as smooth cells are sky.
fn largest_smooth_parts(
    cells: &Cells,
    regions: &[Vec<usize>],
    smooth: &[bool],
) -> Vec<Option<Vec<usize>>> {
    let mut region_of = vec![usize::MAX; cells.len()];
    for (r, region) in regions.iter().enumerate() {
        region.iter().for_each(|&i| region_of[i] = r);
    }
    let mut largest: Vec<Option<(f64, Vec<usize>)>> = vec![None; regions.len()];
    for part in components(cells, smooth) {
        let sr = solid_angle(cells, &part);
        let best = &mut largest[region_of[part[0]]];
        if best.as_ref().is_none_or(|(most, _)| sr >= *most) {
            *best = Some((sr, part));
        }
    }
    largest
        .into_iter()
        .map(|b| b.map(|(_, part)| part))
        .collect()
}

/// Marks in `kept` the region's largest connected part of smooth cells (`open`) and the edge
/// cells that touch it (the whole region where none of it is smooth).
fn keep_open_part(
    cells: &Cells,
    region: &[usize],
    open: Option<Vec<usize>>,
    smooth: &[bool],
    kept: &mut [bool],
) {
    let Some(open) = open else {
        region.iter().for_each(|&i| kept[i] = true);
        return;
    };
    for &i in &open {
        kept[i] = true;
    }
    for &i in region {
        if !smooth[i] && cells.neighbours(i).any(|j| smooth[j] && kept[j]) {
            kept[i] = true;
        }
    }
}

/// The cut a part cut off from the open sky makes, if it is one: mostly dim sky, large enough,
/// not of the colour of the open sky round it (sky seen through leaves is), textured and
/// standing on what is not sky.
fn judge(
    cells: &Cells,
    in_sky: &[bool],
    rest: &[bool],
    open: &[bool],
    dim: &[bool],
    part: &[usize],
) -> Option<Cut> {
    let dim_cells: Vec<usize> = part.iter().copied().filter(|&i| dim[i]).collect();
    let sr = solid_angle(cells, &dim_cells);
    // The ring (a mask of the map to find it) only for a part that can be a cut.
    if sr < CUT_MIN_SR || 2 * dim_cells.len() < part.len() {
        return None;
    }
    let ring = ring(cells, part);
    if sky_coloured(cells, open, part, &ring) {
        return None;
    }
    let textured = texture(cells, rest, part);
    let standing = standing(in_sky, &ring);
    (textured >= TEXTURED && standing >= CUT_STANDING).then_some(Cut {
        cells: dim_cells,
        solid_angle_sr: sr,
        textured,
        standing,
    })
}

/// The share of `part`'s cells [`TEXTURE_STEP`] brighter or dimmer than every neighbour in
/// `mask` (a cell with none is neither).
fn texture(cells: &Cells, mask: &[bool], part: &[usize]) -> f64 {
    let extreme = |i: usize| {
        let y = cells.y[i] as f64;
        let mut n = cells.neighbours(i).filter(|&j| mask[j]).peekable();
        let some = n.peek().is_some();
        let (lo, hi) = n.fold((f64::INFINITY, 0f64), |(lo, hi), j| {
            let v = cells.y[j] as f64;
            (lo.min(v), hi.max(v))
        });
        some && (y >= TEXTURE_STEP * hi || TEXTURE_STEP * y <= lo)
    };
    let count = part.iter().filter(|&&i| extreme(i)).count();
    count as f64 / part.len().max(1) as f64
}

/// The cells next to `part` and not in it.
fn ring(cells: &Cells, part: &[usize]) -> Vec<usize> {
    let own = mask(cells, part.iter().copied());
    let ring: std::collections::BTreeSet<usize> = part
        .iter()
        .flat_map(|&i| cells.neighbours(i))
        .filter(|&j| !own[j])
        .collect();
    ring.into_iter().collect()
}

/// Whether `part`'s colour is within [`SKY_EDGE_UV`] of the open sky's in its `ring` (none
/// there: not).
fn sky_coloured(cells: &Cells, open: &[bool], part: &[usize], ring: &[usize]) -> bool {
    let uv = |set: &mut dyn Iterator<Item = usize>| {
        let xyz = set.fold(nalgebra::Vector3::zeros(), |a, i| {
            a + cells.xyz(i) * cells.omega(i)
        });
        Xyz::from(xyz).uv1960()
    };
    let mut open_ring = ring.iter().copied().filter(|&j| open[j]).peekable();
    if open_ring.peek().is_none() {
        return false;
    }
    let (a, b) = (uv(&mut part.iter().copied()), uv(&mut open_ring));
    (a[0] - b[0]).hypot(a[1] - b[1]) < SKY_EDGE_UV
}

/// The share of the cells of a part's `ring` that are not sky.
fn standing(in_sky: &[bool], ring: &[usize]) -> f64 {
    let not_sky = ring.iter().filter(|&&j| !in_sky[j]).count();
    not_sky as f64 / ring.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::RgbSpace;
    use crate::envmap::layout::{EnvMap, Layout};
    use crate::envmap::RgbImage;

    /// A 512 x 256 lat-long: a blue sky brightening steeply towards the horizon over dark
    /// ground, with `block` drawn on it, and the cells of its upper half as the sky (all dim).
    fn scene(block: impl Fn(usize, usize) -> Option<[f32; 3]>) -> (Cells, Vec<usize>) {
        let (w, h) = (512, 256);
        let mut img = RgbImage::new(w, h);
        for y in 0..h {
            for x in 0..w {
                let up = 1.0 - y as f32 / (h / 2) as f32;
                let sky = [0.3, 0.45, 0.8].map(|c| c * (1.0 + 3.0 * (1.0 - up)));
                let v = if y >= h / 2 { [0.05; 3] } else { sky };
                img.set(x, y, block(x, y).unwrap_or(v));
            }
        }
        let map = EnvMap::new(Layout::LatLong, img).unwrap();
        let cells = Cells::new(&map, &RgbSpace::SRGB, [1.0; 3]);
        let sky = (0..w * h / 2).collect();
        (cells, sky)
    }

    fn split_all_dim(cells: &Cells, sky: &[usize]) -> (Vec<usize>, Vec<Cut>) {
        split(cells, sky, &vec![true; cells.len()])
    }

    /// A warm stone facade, 60 x 40 cells on the horizon, with a dark window (a cell at 0.7
    /// degrees) every four cells.
    fn facade(x: usize, y: usize) -> Option<[f32; 3]> {
        let inside = (200..260).contains(&x) && (88..128).contains(&y);
        let window = x % 4 == 1 && y % 4 == 1;
        inside.then_some(if window {
            [0.15, 0.13, 0.1]
        } else {
            [0.9, 0.75, 0.6]
        })
    }

    #[test]
    fn a_smooth_sky_is_all_open() {
        let (cells, sky) = scene(|_, _| None);
        let (open, cuts) = split_all_dim(&cells, &sky);
        assert!(cuts.is_empty(), "{cuts:?}");
        assert_eq!(open.len(), sky.len());
    }

    #[test]
    fn a_textured_facade_on_the_ground_is_cut() {
        let (cells, sky) = scene(facade);
        let (open, cuts) = split_all_dim(&cells, &sky);
        assert_eq!(cuts.len(), 1, "{cuts:?}");
        // The facade's cells (and only those, give or take its outline) leave the sky.
        let in_facade = |i: usize| facade(i % 512, i / 512).is_some();
        let cut = &cuts[0].cells;
        assert!(cut.iter().all(|&i| in_facade(i)), "{:?}", cuts[0]);
        assert!(cut.len() >= 60 * 40 * 8 / 10, "{}", cut.len());
        assert!(open.iter().all(|&i| !cut.contains(&i)));
        assert!(cuts[0].textured >= TEXTURED && cuts[0].standing >= CUT_STANDING);
    }

    #[test]
    fn a_textured_cloud_in_the_sky_stays_sky() {
        // The facade's texture, but floating: sky all round.
        let (cells, sky) = scene(|x, y| facade(x, y + 40));
        let (open, cuts) = split_all_dim(&cells, &sky);
        assert!(cuts.is_empty(), "{cuts:?}");
        assert_eq!(open.len(), sky.len());
    }

    #[test]
    fn sky_through_leaves_stays_sky() {
        // The facade's shape, edges and texture, but of the sky's own colour (2.5 times as bright
        // as the sky beside it, as a sunlit haze is): sky seen through a tree's leaves, standing
        // on the ground.
        let leaves = |x: usize, y: usize| {
            facade(x, y).map(|c| match c[0] < 0.5 {
                true => c,
                false => [0.3, 0.45, 0.8].map(|v| v * 3.9 * 2.5),
            })
        };
        let (cells, sky) = scene(leaves);
        let (_, cuts) = split_all_dim(&cells, &sky);
        assert!(cuts.is_empty(), "{cuts:?}");
    }

    #[test]
    fn a_plain_facade_is_not_cut() {
        // Untextured (no windows): a sky could be that smooth, so it stays.
        let plain = |x: usize, y: usize| facade(x, y).map(|_| [0.9, 0.75, 0.6]);
        let (cells, sky) = scene(plain);
        let (_, cuts) = split_all_dim(&cells, &sky);
        assert!(cuts.is_empty(), "{cuts:?}");
    }
}
