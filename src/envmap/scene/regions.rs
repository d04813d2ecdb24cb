//! Connected regions of the analysis grid, and what is measured of each: energy, solid angle,
//! direction, colour, extent.

use super::cells::Cells;
use nalgebra::Vector3;

/// A mask over the cells that holds at `set`'s cells.
pub(crate) fn mask(cells: &Cells, set: impl IntoIterator<Item = usize>) -> Vec<bool> {
    let mut mask = vec![false; cells.len()];
    set.into_iter().for_each(|i| mask[i] = true);
    mask
}

/// The connected components (8-neighbourhood, wrapping in longitude) of the cells where `mask`
/// holds, each a list of cell indices; largest first.
pub(crate) fn components(cells: &Cells, mask: &[bool]) -> Vec<Vec<usize>> {
    let mut seen = vec![false; mask.len()];
    let mut out = Vec::new();
    for start in 0..mask.len() {
        if !mask[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        let mut stack = vec![start];
        let mut region = Vec::new();
        while let Some(i) = stack.pop() {
            region.push(i);
            for j in cells.neighbours(i) {
                if mask[j] && !seen[j] {
                    seen[j] = true;
                    stack.push(j);
                }
            }
        }
        region.sort_unstable();
        out.push(region);
    }
    out.sort_by_key(|r| std::cmp::Reverse(r.len()));
    out
}

/// What a region is made of, measured.
#[derive(Debug, Clone)]
pub(crate) struct RegionStats {
    /// Sum of luminance x solid angle.
    pub energy: f64,
    /// Solid angle of its cells (sr).
    pub solid_angle_sr: f64,
    /// Energy-weighted mean direction (unit).
    pub direction: [f64; 3],
    /// Solid-angle-weighted mean XYZ (the region's colour and mean luminance).
    pub mean_xyz: Vector3<f64>,
    /// Highest luminance of a cell.
    pub peak: f64,
    /// The cell of that highest luminance.
    pub peak_cell: usize,
    /// Largest elevation of a cell (degrees): how near the zenith the region reaches.
    pub top_elevation_deg: f64,
    /// Ratio of the region's long to short axis on the sphere (1 for a disc, large for a strip).
    pub elongation: f64,
}

impl RegionStats {
    /// Measures the cells `region` of `cells`.
    pub(crate) fn of(cells: &Cells, region: &[usize]) -> RegionStats {
        let (mut energy, mut omega) = (0.0, 0.0);
        let mut dir = [0.0f64; 3];
        let mut geo = [0.0f64; 3];
        let mut xyz = Vector3::zeros();
        let (mut peak, mut peak_cell) = (0.0f64, region.first().copied().unwrap_or(0));
        let mut top = f64::NEG_INFINITY;
        for &i in region {
            let w = cells.omega(i);
            let y = cells.y[i] as f64;
            let d = cells.direction(i);
            energy += y * w;
            omega += w;
            for k in 0..3 {
                dir[k] += y * w * d[k];
                geo[k] += w * d[k];
            }
            xyz += cells.xyz(i) * w;
            if y > peak {
                (peak, peak_cell) = (y, i);
            }
            top = top.max(d[1].clamp(-1.0, 1.0).asin().to_degrees());
        }
        // A region without light still has a place: its geometric centre.
        let dir = if energy > 0.0 { dir } else { geo };
        let n = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
        let direction = if n > 0.0 {
            dir.map(|v| v / n)
        } else {
            [0.0, 1.0, 0.0]
        };
        RegionStats {
            energy,
            solid_angle_sr: omega,
            direction,
            mean_xyz: if omega > 0.0 { xyz / omega } else { xyz },
            peak,
            peak_cell,
            top_elevation_deg: top,
            elongation: elongation(cells, region, direction),
        }
    }

    /// Elevation of the energy-weighted direction above the horizon (degrees).
    pub(crate) fn elevation_deg(&self) -> f64 {
        self.direction[1].clamp(-1.0, 1.0).asin().to_degrees()
    }
}

/// The ratio of the principal axes of a region's cells projected on the plane tangent to the
/// sphere at `centre` (solid-angle weighted second moments).
fn elongation(cells: &Cells, region: &[usize], centre: [f64; 3]) -> f64 {
    if region.len() < 3 {
        return 1.0;
    }
    // A tangent frame at the centre.
    let c = Vector3::from(centre);
    let helper = if c[1].abs() < 0.9 {
        Vector3::y()
    } else {
        Vector3::x()
    };
    let t1 = c.cross(&helper).normalize();
    let t2 = c.cross(&t1);
    let (mut sxx, mut sxy, mut syy, mut sw) = (0.0, 0.0, 0.0, 0.0);
    for &i in region {
        let d = Vector3::from(cells.direction(i));
        let (a, b) = (d.dot(&t1), d.dot(&t2));
        let w = cells.omega(i);
        sxx += w * a * a;
        sxy += w * a * b;
        syy += w * b * b;
        sw += w;
    }
    let (sxx, sxy, syy) = (sxx / sw, sxy / sw, syy / sw);
    let tr = sxx + syy;
    let disc = ((sxx - syy).powi(2) + 4.0 * sxy * sxy).sqrt();
    let (l1, l2) = ((tr + disc) / 2.0, (tr - disc) / 2.0);
    if l2 > 0.0 {
        (l1 / l2).sqrt()
    } else {
        f64::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::RgbSpace;
    use crate::envmap::layout::{EnvMap, Layout};
    use crate::envmap::RgbImage;

    fn cells_with(width: usize, lit: &[(usize, usize)]) -> Cells {
        let mut img = RgbImage::new(width, width / 2);
        for &(x, y) in lit {
            img.set(x, y, [1.0, 1.0, 1.0]);
        }
        Cells::new(
            &EnvMap::new(Layout::LatLong, img).unwrap(),
            &RgbSpace::SRGB,
            [1.0; 3],
        )
    }

    #[test]
    fn regions_join_across_the_seam_and_stay_apart_otherwise() {
        let c = cells_with(16, &[(0, 3), (15, 3), (15, 4), (7, 2)]);
        let mask: Vec<bool> = c.y.iter().map(|&y| y > 0.5).collect();
        let r = components(&c, &mask);
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].len(), 3);
        assert_eq!(r[1], vec![2 * 16 + 7]);
    }

    #[test]
    fn a_strip_is_elongated_and_a_square_is_not() {
        let strip: Vec<(usize, usize)> = (20..44).map(|x| (x, 16)).collect();
        let c = cells_with(64, &strip);
        let region: Vec<usize> = strip.iter().map(|&(x, y)| y * 64 + x).collect();
        assert!(RegionStats::of(&c, &region).elongation > 8.0);
        let square: Vec<(usize, usize)> = (0..16).map(|k| (30 + k % 4, 14 + k / 4)).collect();
        let c = cells_with(64, &square);
        let region: Vec<usize> = square.iter().map(|&(x, y)| y * 64 + x).collect();
        let s = RegionStats::of(&c, &region);
        assert!(s.elongation < 1.3, "{}", s.elongation);
        assert!(s.elevation_deg().abs() < 10.0);
    }
}
