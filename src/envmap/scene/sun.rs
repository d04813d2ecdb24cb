//! Sun detection: a compact, very bright region that carries a large share of a map's energy.
//!
//! The sun of a real HDR photograph covers a few pixels (often clipped at the half-float maximum)
//! yet lights most of the scene; an overcast sky's brightest patch is neither as compact nor as
//! dominant. The test, on radiance-weighted luminance `Y * solid angle`:
//! 1. the region: pixels within [`SunSettings::max_radius_deg`] of the brightest pixel whose
//!    luminance is at least [`SunSettings::peak_fraction`] of its;
//! 2. it is a sun if its solid angle is at most [`SunSettings::max_solid_angle_sr`] and it carries
//!    at least [`SunSettings::min_energy_share`] of the map's energy.

use crate::colorimetry::{cct, Cct, RgbSpace};
use crate::envmap::layout::EnvMap;

/// Why a scene has no sun when none was looked for.
pub const SUN_OFF: &str = "sun detection is off (--sun off)";

/// Thresholds of the sun test.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SunSettings {
    /// Largest solid angle of a sun region (steradians). The sun's disc is 6.8e-5 sr; blooming and
    /// resampling spread it, so the default allows about 70 times that.
    pub max_solid_angle_sr: f64,
    /// Smallest share of the map's energy (luminance x solid angle) the region must carry.
    pub min_energy_share: f64,
    /// Pixels at least this fraction of the peak luminance belong to the region.
    pub peak_fraction: f64,
    /// Pixels farther than this from the peak do not belong to the region (degrees).
    pub max_radius_deg: f64,
}

impl Default for SunSettings {
    fn default() -> Self {
        SunSettings {
            max_solid_angle_sr: 0.005,
            min_energy_share: 0.2,
            peak_fraction: 0.1,
            max_radius_deg: 5.0,
        }
    }
}

/// A sun found in a map.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Sun {
    /// Indices (y * width + x) of the sun's pixels.
    #[serde(skip)]
    pub pixels: Vec<usize>,
    /// Number of the sun's pixels.
    pub pixel_count: usize,
    /// Energy-weighted mean direction (unit vector, map space: Y up).
    pub direction: [f64; 3],
    /// Angle above the horizon (degrees).
    pub elevation_deg: f64,
    /// Angle from +Z towards +X (degrees).
    pub azimuth_deg: f64,
    /// Solid angle of the region (sr).
    pub solid_angle_sr: f64,
    /// The region's share of the map's energy.
    pub energy_share: f64,
    /// Energy-weighted mean linear RGB of the region.
    pub mean_rgb: [f64; 3],
    /// Luminance of its brightest pixel (Y, in the map's units).
    pub peak_luminance: f64,
    /// Correlated colour temperature of the region's mean colour.
    pub cct: Cct,
    /// True when the peak sits at the half-float maximum: the sun was clipped by the camera or the
    /// file, so its energy and colour are underestimates.
    pub clipped: bool,
}

/// What the search found.
#[derive(Debug, Clone, serde::Serialize)]
#[serde(tag = "found", rename_all = "lowercase")]
pub enum SunSearch {
    /// A sun, measured.
    #[serde(rename = "true")]
    Found(Sun),
    /// No sun.
    #[serde(rename = "false")]
    NotFound {
        /// Why the brightest region is not a sun, in words.
        reason: String,
    },
}

impl SunSearch {
    /// The sun, if one was found.
    pub fn sun(&self) -> Option<&Sun> {
        match self {
            SunSearch::Found(s) => Some(s),
            SunSearch::NotFound { .. } => None,
        }
    }
}

/// Finds the sun of `map` (linear RGB in `space`), if it has one.
pub fn find_sun(map: &EnvMap, space: &RgbSpace, settings: &SunSettings) -> SunSearch {
    let luminance = Luminance(space.to_xyz_matrix());
    let (total, (peak_l, peak_i)) = energy_and_peak(map, &luminance);
    if total.is_nan() || total <= 0.0 || peak_i == usize::MAX {
        return SunSearch::NotFound {
            reason: "the map holds no light".into(),
        };
    }
    let width = map.image.width;
    let Some(peak_dir) = map.direction(peak_i % width, peak_i / width) else {
        return SunSearch::NotFound {
            reason: "the brightest pixel has no direction".into(),
        };
    };
    let threshold = settings.peak_fraction * peak_l;
    let region = Region::around(map, &luminance, peak_dir, threshold, settings);
    let share = region.energy / total;
    match region.why_not_a_sun(share, peak_l, settings) {
        Some(reason) => SunSearch::NotFound { reason },
        None => SunSearch::Found(region.into_sun(map, space, share, peak_l)),
    }
}

/// A space's RGB-to-XYZ matrix, for the luminance (its Y row) of a pixel.
struct Luminance(nalgebra::Matrix3<f64>);

impl Luminance {
    /// The luminance of linear RGB `p`, negative values taken as 0.
    fn of(&self, p: [f32; 3]) -> f64 {
        let m = &self.0;
        (m[(1, 0)] * p[0] as f64 + m[(1, 1)] * p[1] as f64 + m[(1, 2)] * p[2] as f64).max(0.0)
    }
}

/// The map's energy (luminance x solid angle) and its brightest pixel (luminance, index;
/// `usize::MAX` when none is lit), over the pixels of a direction and a finite luminance.
fn energy_and_peak(map: &EnvMap, luminance: &Luminance) -> (f64, (f64, usize)) {
    let img = &map.image;
    let mut total = 0.0;
    let mut peak = (0.0f64, usize::MAX);
    for y in 0..img.height {
        for x in 0..img.width {
            let i = y * img.width + x;
            let l = luminance.of(img.pixels[i]);
            let omega = map.solid_angle(x, y);
            if omega <= 0.0 || !l.is_finite() {
                continue;
            }
            total += l * omega;
            if l > peak.0 {
                peak = (l, i);
            }
        }
    }
    (total, peak)
}

/// The brightest region: its pixels and their sums.
struct Region {
    pixels: Vec<usize>,
    /// Sum of luminance x solid angle.
    energy: f64,
    omega_sum: f64,
    /// Energy-weighted sum of the directions.
    dir_sum: [f64; 3],
    /// Solid-angle-weighted sum of the RGB values.
    rgb_sum: [f64; 3],
}

impl Region {
    /// The pixels of at least `threshold` luminance within the settings' radius of `peak_dir`.
    fn around(
        map: &EnvMap,
        luminance: &Luminance,
        peak_dir: [f64; 3],
        threshold: f64,
        settings: &SunSettings,
    ) -> Region {
        let img = &map.image;
        let cos_max = settings.max_radius_deg.to_radians().cos();
        let mut region = Region {
            pixels: Vec::new(),
            energy: 0.0,
            omega_sum: 0.0,
            dir_sum: [0.0f64; 3],
            rgb_sum: [0.0f64; 3],
        };
        for y in 0..img.height {
            for x in 0..img.width {
                let i = y * img.width + x;
                let p = img.pixels[i];
                let l = luminance.of(p);
                if l < threshold {
                    continue;
                }
                let Some(d) = map.direction(x, y) else {
                    continue;
                };
                if d[0] * peak_dir[0] + d[1] * peak_dir[1] + d[2] * peak_dir[2] < cos_max {
                    continue;
                }
                region.add(i, l, map.solid_angle(x, y), d, p);
            }
        }
        region
    }

    /// Adds pixel `i` of luminance `l`, solid angle `omega`, direction `d` and value `p`.
    fn add(&mut self, i: usize, l: f64, omega: f64, d: [f64; 3], p: [f32; 3]) {
        let e = l * omega;
        self.pixels.push(i);
        self.energy += e;
        self.omega_sum += omega;
        for k in 0..3 {
            self.dir_sum[k] += e * d[k];
            self.rgb_sum[k] += omega * p[k] as f64;
        }
    }

    /// Why the region, carrying `share` of the energy, is not a sun; None when it is one.
    fn why_not_a_sun(&self, share: f64, peak_l: f64, settings: &SunSettings) -> Option<String> {
        let rejected =
            self.omega_sum > settings.max_solid_angle_sr || share < settings.min_energy_share;
        rejected.then(|| {
            format!(
                "the brightest region ({} pixels, {:.2e} sr, peak luminance {:.3}) carries {:.1}% \
                 of the energy; a sun covers at most {:.2e} sr and carries at least {:.0}%",
                self.pixels.len(),
                self.omega_sum,
                peak_l,
                100.0 * share,
                settings.max_solid_angle_sr,
                100.0 * settings.min_energy_share
            )
        })
    }

    /// The sun this region is: its direction, colour and whether it was clipped.
    fn into_sun(self, map: &EnvMap, space: &RgbSpace, share: f64, peak_l: f64) -> Sun {
        let dir_sum = self.dir_sum;
        let norm = (dir_sum[0].powi(2) + dir_sum[1].powi(2) + dir_sum[2].powi(2)).sqrt();
        let direction = dir_sum.map(|v| v / norm);
        let mean_rgb = self.rgb_sum.map(|v| v / self.omega_sum);
        let xyz = space.xyz_from_rgb(mean_rgb);
        let cct = cct(xyz).unwrap_or(Cct {
            kelvin: None,
            duv: f64::NAN,
        });
        let max_channel = self
            .pixels
            .iter()
            .flat_map(|&i| map.image.pixels[i])
            .fold(0.0f32, f32::max);
        Sun {
            pixel_count: self.pixels.len(),
            pixels: self.pixels,
            direction,
            elevation_deg: direction[1].clamp(-1.0, 1.0).asin().to_degrees(),
            azimuth_deg: direction[0].atan2(direction[2]).to_degrees(),
            solid_angle_sr: self.omega_sum,
            energy_share: share,
            mean_rgb,
            peak_luminance: peak_l,
            cct,
            clipped: max_channel >= 65000.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::envmap::layout::Layout;
    use crate::envmap::RgbImage;

    /// A lat-long sky of constant radiance with an optional disc of radiance `sun` and angular
    /// radius `radius_deg` towards `dir`.
    fn sky(width: usize, sun: Option<(f32, f64, [f64; 3])>) -> EnvMap {
        let mut map = EnvMap::new(Layout::LatLong, RgbImage::new(width, width / 2)).unwrap();
        for y in 0..width / 2 {
            for x in 0..width {
                let d = map.direction(x, y).unwrap();
                let mut v = [0.8f32, 0.9, 1.0];
                if let Some((l, r, s)) = sun {
                    if d[0] * s[0] + d[1] * s[1] + d[2] * s[2] >= r.to_radians().cos() {
                        v = [l, l, l * 0.9];
                    }
                }
                map.image.set(x, y, v);
            }
        }
        map
    }

    #[test]
    fn finds_a_compact_dominant_sun_and_its_direction() {
        let s = 0.5f64.sqrt();
        let dir = [s * 0.0, s, s]; // 45 degrees up, towards +Z
        let map = sky(512, Some((50000.0, 1.5, dir)));
        let found = find_sun(&map, &RgbSpace::SRGB, &SunSettings::default());
        let sun = found.sun().expect("a sun");
        assert!((sun.elevation_deg - 45.0).abs() < 0.5, "{sun:?}");
        assert!(sun.azimuth_deg.abs() < 0.5, "{sun:?}");
        // The disc's solid angle: 2 pi (1 - cos r).
        let expected = 2.0 * std::f64::consts::PI * (1.0 - 1.5f64.to_radians().cos());
        assert!(
            (sun.solid_angle_sr / expected - 1.0).abs() < 0.15,
            "{sun:?}"
        );
        assert!(sun.energy_share > 0.5);
        assert!(!sun.clipped);
        assert!(sun.cct.kelvin.is_some());
    }

    #[test]
    fn a_bright_but_weak_spot_or_a_broad_glow_is_not_a_sun() {
        let none = find_sun(&sky(256, None), &RgbSpace::SRGB, &SunSettings::default());
        assert!(none.sun().is_none());
        // Bright but carrying little energy.
        let weak = sky(512, Some((30.0, 1.0, [0.0, 0.5f64.sqrt(), 0.5f64.sqrt()])));
        let r = find_sun(&weak, &RgbSpace::SRGB, &SunSettings::default());
        assert!(r.sun().is_none(), "{r:?}");
        // Dominant but broad (a 20-degree glow).
        let broad = sky(256, Some((200.0, 20.0, [0.0, 1.0, 0.0])));
        let r = find_sun(&broad, &RgbSpace::SRGB, &SunSettings::default());
        assert!(r.sun().is_none(), "{r:?}");
        let black = EnvMap::new(Layout::LatLong, RgbImage::new(8, 4)).unwrap();
        assert!(find_sun(&black, &RgbSpace::SRGB, &SunSettings::default())
            .sun()
            .is_none());
    }
}
