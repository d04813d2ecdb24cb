//! `--light auto`: the main light of a scene, from the chromaticity of its brightest regions.
//!
//! The paper's rule: an exterior is lit by the sun or daylight (D65); an interior by its lamps.
//! A map with a sun, or whose brightest regions are daylight-coloured (CCT >= 4500 K within 0.01
//! of the Planckian locus), is an exterior; otherwise the main light is the lamp among
//! [`CANDIDATES`] whose white point lies nearest the brightest regions' colour (CIE 1960 uv).

use crate::colorimetry::{cct, Cct, Cmfs, Observer, RgbSpace, Xyz};
use crate::data;
use crate::envmap::convert::pixel_spectra::WhitePremise;
use crate::envmap::layout::EnvMap;
use crate::error::Result;
use crate::spectrum::{Interpolation, Rule, WavelengthGrid};

/// The lights `auto` chooses among (built-in names).
pub const CANDIDATES: [&str; 7] = ["D65", "A", "FL2", "FL11", "LED-B3", "hps", "lps"];

/// The share of the map's energy, taken from its brightest pixels, that defines "the brightest
/// regions".
const BRIGHT_SHARE: f64 = 0.25;

/// What `auto` chose and why.
#[derive(Debug, Clone, serde::Serialize)]
pub struct LightChoice {
    /// A built-in light name.
    pub light: String,
    /// Exterior (daylight) or interior (lamps).
    pub exterior: bool,
    /// The reason, in words.
    pub reason: String,
    /// CIE 1931 xy chromaticity of the brightest regions (energy-weighted).
    pub bright_xy: [f64; 2],
    /// CCT and Duv of the brightest regions' colour.
    pub bright_cct: Cct,
}

/// The energy-weighted mean linear RGB of a map's brightest regions: its brightest pixels that
/// together carry `BRIGHT_SHARE` (a quarter) of its energy (luminance x solid angle).
pub fn bright_regions(map: &EnvMap, space: &RgbSpace) -> [f64; 3] {
    let img = &map.image;
    let m = space.to_xyz_matrix();
    // Energy (luminance x solid angle) of every pixel, brightest first.
    let mut px: Vec<(f64, f64, usize)> = Vec::with_capacity(img.pixels.len());
    let mut total = 0.0;
    for y in 0..img.height {
        for x in 0..img.width {
            let i = y * img.width + x;
            let p = img.pixels[i];
            let l = m[(1, 0)] * p[0] as f64 + m[(1, 1)] * p[1] as f64 + m[(1, 2)] * p[2] as f64;
            let omega = map.solid_angle(x, y);
            if l > 0.0 && omega > 0.0 {
                px.push((l, l * omega, i));
                total += l * omega;
            }
        }
    }
    px.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut rgb = [0.0f64; 3];
    let mut taken = 0.0;
    for &(_, e, i) in &px {
        if taken >= BRIGHT_SHARE * total {
            break;
        }
        let p = img.pixels[i];
        let omega =
            e / (m[(1, 0)] * p[0] as f64 + m[(1, 1)] * p[1] as f64 + m[(1, 2)] * p[2] as f64);
        for k in 0..3 {
            rgb[k] += p[k] as f64 * omega;
        }
        taken += e;
    }
    rgb
}

/// Chooses the main light of `map` (linear RGB in `space`).
/// `sun`: the energy share and elevation of the map's sun, if it has one.
pub fn choose(map: &EnvMap, sun: Option<(f64, f64)>, space: &RgbSpace) -> Result<LightChoice> {
    let rgb = bright_regions(map, space);
    let xyz = space.xyz_from_rgb(rgb);
    let bright_xy = xyz.xy();
    let bright_cct = cct(xyz)?;
    let describe = |c: &Cct| match c.kelvin {
        Some(k) => format!("CCT {k:.0} K, Duv {:+.4}", c.duv),
        None => format!("far from the Planckian locus, Duv {:+.3}", c.duv),
    };
    if let Some((share, elevation)) = sun {
        return Ok(LightChoice {
            light: "D65".into(),
            exterior: true,
            reason: format!(
                "exterior: a sun carries {:.0}% of the energy ({:.1} degrees above the horizon), \
                 so the main light is daylight, D65 as in the paper",
                100.0 * share,
                elevation
            ),
            bright_xy,
            bright_cct,
        });
    }
    if let Some(k) = bright_cct.kelvin {
        if k >= 4500.0 && bright_cct.duv.abs() <= 0.01 {
            return Ok(LightChoice {
                light: "D65".into(),
                exterior: true,
                reason: format!(
                    "exterior: no sun, but the brightest regions are daylight-coloured ({}), so \
                     the main light is daylight, D65",
                    describe(&bright_cct)
                ),
                bright_xy,
                bright_cct,
            });
        }
    }
    // Interior: the lamp whose white is nearest in CIE 1960 uv.
    let grid = WavelengthGrid::visible_1nm();
    let cmfs = Cmfs::new(Observer::Cie1931, &grid)?;
    let target = xyz.uv1960();
    let mut best: Option<(f64, &str)> = None;
    for name in CANDIDATES.iter().filter(|n| **n != "D65") {
        let s = data::spectrum(name)?
            .data
            .resample(&grid, Interpolation::LIGHT);
        let uv = cmfs.light_xyz(&s, Rule::Riemann)?.uv1960();
        let d = (uv[0] - target[0]).hypot(uv[1] - target[1]);
        if best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, name));
        }
    }
    let (d, name) = best.expect("candidates are not empty");
    Ok(LightChoice {
        light: name.to_string(),
        exterior: false,
        reason: format!(
            "interior: no sun and the brightest regions are not daylight ({}); the nearest lamp \
             white is {name} (distance {d:.4} in CIE 1960 uv)",
            describe(&bright_cct)
        ),
        bright_xy,
        bright_cct,
    })
}

/// What the white premise is, and why.
#[derive(Debug, Clone, serde::Serialize)]
pub struct WhiteChoice {
    /// The premise chosen: what RGB (1,1,1) is.
    pub premise: WhitePremise,
    /// The reason, in words.
    pub reason: String,
}

/// Chooses the white premise of `map` for the main light `light` (a spectrum name or CSV): a
/// map white-balanced to its main light shows that light as neutral, one referenced to its RGB
/// space's white (D65 for sRGB) shows it in its own colour. So the brightest regions'
/// chromaticity decides: nearer the light's white than the space's (CIE 1960 uv), the map is
/// referenced to the space's white; otherwise it is balanced to the light. When the light's
/// white is the space's (within 0.002 uv) the two premises are one.
pub fn choose_white(map: &EnvMap, space: &RgbSpace, light: &str) -> Result<WhiteChoice> {
    let grid = WavelengthGrid::visible_1nm();
    let cmfs = Cmfs::new(Observer::Cie1931, &grid)?;
    let s = data::spectrum(light)?
        .data
        .resample(&grid, Interpolation::LIGHT);
    let light_uv = cmfs.light_xyz(&s, Rule::Riemann)?.uv1960();
    let white_uv = Xyz::from_xy(space.white).uv1960();
    let white = space.white_name();
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    if dist(light_uv, white_uv) <= 0.002 {
        return Ok(WhiteChoice {
            premise: WhitePremise::Space,
            reason: format!(
                "the main light {light} has the space's white, {white}: both premises are one"
            ),
        });
    }
    let rgb = bright_regions(map, space);
    let xyz = space.xyz_from_rgb(rgb);
    if xyz.y().is_nan() || xyz.y() <= 0.0 {
        return Ok(WhiteChoice {
            premise: WhitePremise::Space,
            reason: format!("the map holds no light: RGB taken as referenced to {white}"),
        });
    }
    let uv = xyz.uv1960();
    let (to_light, to_white) = (dist(uv, light_uv), dist(uv, white_uv));
    Ok(if to_light < to_white {
        WhiteChoice {
            premise: WhitePremise::Space,
            reason: format!(
                "the brightest regions have the colour of {light} (uv distance {to_light:.4}, \
                 {to_white:.4} from the space's white {white}): the map is referenced to that \
                 white, not white-balanced to its light"
            ),
        }
    } else {
        WhiteChoice {
            premise: WhitePremise::Light,
            reason: format!(
                "the brightest regions are neutral (uv distance {to_white:.4} from the space's \
                 white {white}, {to_light:.4} from {light}): the map is white-balanced to its \
                 light, as the paper assumes"
            ),
        }
    })
}

/// The xy of a built-in light (for messages and tests).
pub fn white_xy(name: &str) -> Result<[f64; 2]> {
    let grid = WavelengthGrid::visible_1nm();
    let cmfs = Cmfs::new(Observer::Cie1931, &grid)?;
    let s = data::spectrum(name)?
        .data
        .resample(&grid, Interpolation::LIGHT);
    Ok(cmfs.light_xyz(&s, Rule::Riemann)?.xy())
}

/// Linear RGB (Y = 1) of an xy chromaticity, for synthetic test maps.
pub fn rgb_of_xy(xy: [f64; 2], space: &RgbSpace) -> [f32; 3] {
    space
        .rgb_from_xyz(Xyz::from_xy(xy))
        .map(|v| v.max(0.0) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::envmap::layout::Layout;
    use crate::envmap::scene::sun::{find_sun, SunSettings};
    use crate::envmap::RgbImage;

    /// A dim grey room with a bright patch of the given colour overhead.
    fn room(lamp: [f32; 3], scale: f32) -> EnvMap {
        let mut map = EnvMap::new(Layout::LatLong, RgbImage::new(128, 64)).unwrap();
        for y in 0..64 {
            for x in 0..128 {
                let v = if y < 12 {
                    lamp.map(|c| c * scale)
                } else {
                    [0.05, 0.05, 0.05]
                };
                map.image.set(x, y, v);
            }
        }
        map
    }

    #[test]
    fn lamps_are_recognised_by_their_colour() {
        for lamp in ["A", "FL2", "hps", "lps"] {
            let xy = white_xy(lamp).unwrap();
            let map = room(rgb_of_xy(xy, &RgbSpace::SRGB), 20.0);
            let sun = find_sun(&map, &RgbSpace::SRGB, &SunSettings::default());
            let sun = sun.sun().map(|s| (s.energy_share, s.elevation_deg));
            let c = choose(&map, sun, &RgbSpace::SRGB).unwrap();
            // Out-of-gamut lamp colours (LPS) are clipped to the sRGB gamut by rgb_of_xy, so
            // only require the nearest lamp to be the one painted, or a lamp of its family.
            assert!(!c.exterior, "{lamp}: {c:?}");
            assert_eq!(c.light, lamp, "{c:?}");
        }
    }

    #[test]
    fn daylight_rooms_and_suns_are_exteriors() {
        let map = room(rgb_of_xy(white_xy("D65").unwrap(), &RgbSpace::SRGB), 5.0);
        let sun = find_sun(&map, &RgbSpace::SRGB, &SunSettings::default());
        let sun = sun.sun().map(|s| (s.energy_share, s.elevation_deg));
        let c = choose(&map, sun, &RgbSpace::SRGB).unwrap();
        assert!(c.exterior && c.light == "D65", "{c:?}");
        assert!(c.reason.contains("daylight-coloured"));
    }
}
