//! The sun as the reports give it: found (where, how big, how bright, its colour) or why not.

use crate::envmap::scene::Scene;

/// The sun, as the report gives it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SunReport {
    /// Whether a sun was found.
    pub found: bool,
    /// Why it is the sun, or why the brightest region is not.
    pub reason: String,
    #[serde(flatten)]
    /// The sun, if found.
    pub sun: Option<SunFound>,
}

/// A sun found in the map.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SunFound {
    /// Pixels of the sun.
    pub pixel_count: usize,
    /// Energy-weighted mean direction (unit vector, OpenEXR's axes: Y up).
    pub direction: [f64; 3],
    /// Degrees above the horizon.
    pub elevation_deg: f64,
    /// Angle from +Z towards +X (degrees).
    pub azimuth_deg: f64,
    /// Solid angle of its pixels (sr).
    pub solid_angle_sr: f64,
    /// Share of the map's energy (luminance x solid angle).
    pub energy_share: f64,
    #[serde(rename = "cct_K")]
    /// Correlated colour temperature (K), if it has one.
    pub cct_k: Option<f64>,
    /// Distance from the Planckian locus (CIE 1960 uv).
    pub duv: f64,
    /// Pixels at the clip level: the sun's energy is an underestimate, its colour taken from
    /// its unclipped glow.
    pub clipped: bool,
}

impl SunReport {
    /// The sun of `scene`, or why there is none.
    pub fn of(scene: &Scene) -> SunReport {
        match scene.sun() {
            Some(s) => SunReport {
                found: true,
                reason: s.reason.clone(),
                sun: Some(SunFound {
                    pixel_count: s.pixels,
                    direction: s.direction,
                    elevation_deg: s.elevation_deg,
                    azimuth_deg: s.direction[0].atan2(s.direction[2]).to_degrees(),
                    solid_angle_sr: s.solid_angle_sr,
                    energy_share: s.energy_share,
                    cct_k: s.cct_k,
                    duv: s.duv,
                    clipped: s.clipped_pixels > 0,
                }),
            },
            None => SunReport {
                found: false,
                reason: scene
                    .bright_reflectors
                    .first()
                    .and_then(|r| r.strip_prefix("no sun: "))
                    .unwrap_or("nothing in the map stands out")
                    .to_string(),
                sun: None,
            },
        }
    }
}
