//! The analysis grid: a lat-long view of a map in true (D65-referenced) linear RGB, with each
//! cell's luminance, solid angle and direction.
//!
//! Any layout is analysed the same way: a lat-long map up to [`MAX_ANALYSIS_WIDTH`] wide is used
//! cell for pixel; anything else (cube-like layouts, larger maps) is resampled to a lat-long of
//! matched density, energy-preserving, and each output pixel finds its cell by direction.

use crate::colorimetry::RgbSpace;
use crate::envmap::layout::{EnvMap, Layout};
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use std::f64::consts::PI;

/// The offsets (dx, dy) of a cell's eight neighbours, in the order they are visited.
const NEIGHBOURS: [(isize, isize); 8] = [
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

/// The widest lat-long analysed at its own resolution (wider maps are analysed at this width:
/// every light still covers whole cells, and the analysis stays in a few tens of MB).
pub(crate) const MAX_ANALYSIS_WIDTH: usize = 2048;

/// The lat-long cells of a map, in true linear RGB.
#[derive(Debug, Clone)]
pub struct Cells {
    /// Width in cells.
    pub width: usize,
    /// Height in cells (half the width: a lat-long).
    pub height: usize,
    /// True (D65-referenced) linear RGB of each cell, row-major from the top-left.
    pub rgb: Vec<[f32; 3]>,
    /// Luminance (>= 0; negative luminance counts as 0).
    pub y: Vec<f32>,
    /// RGB -> XYZ (Y = luminance).
    pub to_xyz: Matrix3<f64>,
    /// The cells are the map's own pixels (a lat-long at most MAX_ANALYSIS_WIDTH wide).
    pub identity: bool,
    /// What each channel was multiplied by (the white premise).
    pub balance: [f64; 3],
    /// Per row: the solid angle of a cell, sin and cos of its latitude; per column: sin and cos
    /// of its longitude (the analysis asks for them per cell, many times over).
    rows: Vec<[f64; 3]>,
    cols: Vec<[f64; 2]>,
}

impl Cells {
    /// The cells of `map`, each pixel multiplied by `balance` (the white premise: the main
    /// light's RGB when the map is white-balanced to it, else 1) to make it D65-referenced.
    pub fn new(map: &EnvMap, space: &RgbSpace, balance: [f64; 3]) -> Cells {
        let (identity, height) = grid_of(map);
        let resampled;
        let src = if identity {
            map
        } else {
            resampled = map.resample(Layout::LatLong, height);
            &resampled
        };
        let to_xyz = space.to_xyz_matrix();
        let row = [to_xyz[(1, 0)], to_xyz[(1, 1)], to_xyz[(1, 2)]];
        let rgb: Vec<[f32; 3]> = src
            .image
            .pixels
            .iter()
            .map(|p| std::array::from_fn(|k| (p[k] as f64 * balance[k]) as f32))
            .collect();
        let y = rgb
            .iter()
            .map(|p| {
                let l: f64 = (0..3).map(|k| row[k] * p[k] as f64).sum();
                if l.is_finite() {
                    l.max(0.0) as f32
                } else {
                    0.0
                }
            })
            .collect();
        let (w, h) = (src.image.width, src.image.height);
        Cells {
            rgb,
            y,
            ..Cells::grid(w, h, to_xyz, identity, balance)
        }
    }

    /// The cells of `map` without their colours (`rgb` and `y` empty): where each pixel falls,
    /// each cell's direction and solid angle. A scene left unanalysed needs no more, and the map
    /// is not resampled for it.
    pub fn geometry(map: &EnvMap, space: &RgbSpace) -> Cells {
        let (identity, height) = grid_of(map);
        let (w, h) = if identity {
            (map.image.width, map.image.height)
        } else {
            Layout::LatLong.dimensions(height)
        };
        Cells::grid(w, h, space.to_xyz_matrix(), identity, [1.0; 3])
    }

    /// A `w` x `h` lat-long grid of cells holding no colours yet.
    fn grid(w: usize, h: usize, to_xyz: Matrix3<f64>, identity: bool, balance: [f64; 3]) -> Cells {
        let rows = (0..h)
            .map(|y| {
                let t0 = PI * y as f64 / h as f64;
                let t1 = PI * (y + 1) as f64 / h as f64;
                let lat = -PI * ((y as f64 + 0.5) / h as f64 - 0.5);
                [
                    2.0 * PI / w as f64 * (t0.cos() - t1.cos()),
                    lat.sin(),
                    lat.cos(),
                ]
            })
            .collect();
        let cols = (0..w)
            .map(|x| {
                let lon = -2.0 * PI * ((x as f64 + 0.5) / w as f64 - 0.5);
                [lon.sin(), lon.cos()]
            })
            .collect();
        Cells {
            width: w,
            height: h,
            rgb: Vec::new(),
            y: Vec::new(),
            to_xyz,
            identity,
            balance,
            rows,
            cols,
        }
    }

    /// Number of cells (width x height).
    pub fn len(&self) -> usize {
        self.width * self.height
    }

    /// Whether there are no cells.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The solid angle of a cell (the same for every cell of a row).
    pub fn omega(&self, i: usize) -> f64 {
        self.rows[i / self.width][0]
    }

    /// The unit direction of a cell's centre (OpenEXR's lat-long: Y up, centre column +Z).
    pub fn direction(&self, i: usize) -> [f64; 3] {
        let [_, sin_lat, cos_lat] = self.rows[i / self.width];
        let [sin_lon, cos_lon] = self.cols[i % self.width];
        [sin_lon * cos_lat, sin_lat, cos_lon * cos_lat]
    }

    /// The cell that holds direction `d` (unit or not).
    pub fn cell_of(&self, d: [f64; 3]) -> usize {
        let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if !(n > 0.0 && n.is_finite()) {
            return 0;
        }
        let lon = d[0].atan2(d[2]);
        let lat = (d[1] / n).clamp(-1.0, 1.0).asin();
        let u = 0.5 - lon / (2.0 * PI);
        let v = 0.5 - lat / PI;
        let x = ((u * self.width as f64) as usize).min(self.width - 1);
        let y = ((v * self.height as f64) as usize).min(self.height - 1);
        y * self.width + x
    }

    /// The cell of each pixel of `map` (the map the cells were made from); None for the unused
    /// cells of a cross.
    pub fn cell_of_pixel(&self, map: &EnvMap, x: usize, y: usize) -> Option<usize> {
        if self.identity {
            return Some(y * self.width + x);
        }
        map.direction(x, y).map(|d| self.cell_of(d))
    }

    /// XYZ of a cell's true RGB.
    pub fn xyz(&self, i: usize) -> Vector3<f64> {
        let p = self.rgb[i];
        self.to_xyz * Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64)
    }

    /// The cells next to cell `i` (8-neighbourhood, in [`NEIGHBOURS`]' order), wrapping in
    /// longitude; across a pole the neighbours are the cells half a turn away on the same row.
    pub fn neighbours(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let (w, h) = (self.width as isize, self.height as isize);
        let (x, y) = ((i % self.width) as isize, (i / self.width) as isize);
        // Away from the map's edges a neighbour is an offset of the index: no wrap, no pole.
        let inside = x > 0 && x + 1 < w && y > 0 && y + 1 < h;
        NEIGHBOURS
            .into_iter()
            .map(move |(dx, dy)| {
                if inside {
                    return (i as isize + dy * w + dx) as usize;
                }
                let (mut nx, mut ny) = (x + dx, y + dy);
                if ny < 0 || ny >= h {
                    ny = ny.clamp(0, h - 1);
                    nx += w / 2;
                }
                (ny * w + nx.rem_euclid(w)) as usize
            })
            .filter(move |&j| j != i)
    }
}

/// Whether a map's own pixels are its cells (a lat-long at most [`MAX_ANALYSIS_WIDTH`] wide),
/// and the height of the lat-long it is otherwise resampled to.
fn grid_of(map: &EnvMap) -> (bool, usize) {
    let identity = map.layout == Layout::LatLong && map.image.width <= MAX_ANALYSIS_WIDTH;
    let height = (map.face_size() * 2).clamp(2, MAX_ANALYSIS_WIDTH / 2);
    (identity, height)
}

/// The solid-angle-weighted quantile `q` (0..1) of `values` over the cells.
pub(crate) fn weighted_quantile(cells: &Cells, values: &[f32], q: f64) -> f64 {
    // The values in `f32::total_cmp`'s order, ties in cell order (a stable sort's, so that the
    // weights are summed in one order whatever the threads): one u64 key per cell, the value's
    // order in the high half and the cell's index in the low, sorted in parallel.
    let mut keys: Vec<u64> = values
        .par_iter()
        .enumerate()
        .map(|(i, &x)| (total_order_key(x) as u64) << 32 | i as u64)
        .collect();
    keys.par_sort_unstable();
    let value = |k: u64| from_total_order_key((k >> 32) as u32) as f64;
    let omega = |k: u64| cells.omega((k & u32::MAX as u64) as usize);
    let total: f64 = keys.iter().map(|&k| omega(k)).sum();
    let mut acc = 0.0;
    for &k in &keys {
        acc += omega(k);
        if acc >= q * total {
            return value(k);
        }
    }
    keys.last().map_or(0.0, |&k| value(k))
}

/// An f32's bits as a u32 that orders as [`f32::total_cmp`] does: negatives (sign set) inverted,
/// the rest with the sign bit set.
fn total_order_key(x: f32) -> u32 {
    let b = x.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

/// The f32 whose [`total_order_key`] is `k`.
fn from_total_order_key(k: u32) -> f32 {
    f32::from_bits(if k & 0x8000_0000 != 0 {
        k & 0x7fff_ffff
    } else {
        !k
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::envmap::RgbImage;

    #[test]
    fn the_total_order_key_orders_as_total_cmp_and_goes_back() {
        let xs = [
            f32::NEG_INFINITY,
            -3.5,
            -1e-40,
            -0.0,
            0.0,
            1e-40,
            1.0,
            7e30,
            f32::INFINITY,
            f32::NAN,
        ];
        for a in xs {
            assert_eq!(
                from_total_order_key(total_order_key(a)).to_bits(),
                a.to_bits()
            );
            for b in xs {
                assert_eq!(
                    total_order_key(a).cmp(&total_order_key(b)),
                    a.total_cmp(&b),
                    "{a} {b}"
                );
            }
        }
    }

    #[test]
    fn the_weighted_quantile_is_the_value_where_the_solid_angle_crosses_it() {
        // A 64 x 32 lat-long whose cells hold their row index: a quantile by solid angle is
        // the first row where the sphere's area from the top reaches it (the quantiles chosen
        // away from rows' edges: 0.37 is row 13.3 of 32, by (1 - cos theta) / 2).
        let map = EnvMap::new(Layout::LatLong, RgbImage::new(64, 32)).unwrap();
        let c = Cells::new(&map, &RgbSpace::SRGB, [1.0; 3]);
        let values: Vec<f32> = (0..c.len()).map(|i| (i / c.width) as f32).collect();
        let want = |q: f64| {
            // The first row whose cumulative solid angle reaches q of the sphere.
            let mut acc = 0.0;
            (0..c.height)
                .find(|&y| {
                    acc += (0..c.width).map(|x| c.omega(y * c.width + x)).sum::<f64>();
                    acc >= q * 4.0 * PI
                })
                .unwrap() as f64
        };
        for q in [0.05, 0.37, 0.9] {
            assert_eq!(weighted_quantile(&c, &values, q), want(q), "q {q}");
        }
    }

    #[test]
    fn cells_are_the_maps_directions_and_solid_angles() {
        let map = EnvMap::new(Layout::LatLong, RgbImage::new(64, 32)).unwrap();
        let c = Cells::new(&map, &RgbSpace::SRGB, [1.0; 3]);
        assert!(c.identity);
        let total: f64 = (0..c.len()).map(|i| c.omega(i)).sum();
        assert!((total - 4.0 * PI).abs() < 1e-9);
        for i in [0, 100, 1000, 2047] {
            let d = map.direction(i % 64, i / 64).unwrap();
            let e = c.direction(i);
            assert!((0..3).all(|k| (d[k] - e[k]).abs() < 1e-12), "{d:?} {e:?}");
            assert_eq!(c.cell_of(e), i);
            assert!((c.omega(i) - map.solid_angle(i % 64, i / 64)).abs() < 1e-15);
        }
    }

    #[test]
    fn a_cube_is_analysed_through_a_latlong_of_its_density() {
        let mut img = RgbImage::new(8, 48);
        img.pixels.iter_mut().for_each(|p| *p = [2.0, 2.0, 2.0]);
        let map = EnvMap::new(Layout::Cube, img).unwrap();
        let c = Cells::new(&map, &RgbSpace::SRGB, [1.0; 3]);
        assert!(!c.identity);
        assert_eq!((c.width, c.height), (32, 16));
        let energy: f64 = (0..c.len()).map(|i| c.y[i] as f64 * c.omega(i)).sum();
        assert!((energy / (8.0 * PI) - 1.0).abs() < 1e-3, "{energy}");
        // Each cube pixel finds the cell of its direction.
        let d = map.direction(3, 20).unwrap();
        assert_eq!(c.cell_of_pixel(&map, 3, 20), Some(c.cell_of(d)));
    }

    #[test]
    fn neighbours_wrap_in_longitude_and_cross_the_poles() {
        let map = EnvMap::new(Layout::LatLong, RgbImage::new(8, 4)).unwrap();
        let c = Cells::new(&map, &RgbSpace::SRGB, [1.0; 3]);
        let n: Vec<usize> = c.neighbours(8).collect(); // (0, 1)
        assert!(n.contains(&15) && n.contains(&7) && n.contains(&23));
        let top: Vec<usize> = c.neighbours(1).collect(); // (1, 0): across the pole, x + 4
        assert!(top.contains(&5), "{top:?}");
    }
}
