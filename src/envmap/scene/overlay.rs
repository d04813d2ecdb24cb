//! The scene analysis drawn on the map: each light's region tinted and outlined in the colour of
//! its kind on the tonemapped map, numbered, with a legend beneath naming its kind, spectrum and
//! share of the energy (`specmap inspect --overlay`).

use crate::colorimetry::srgb_encode;
use crate::envmap::layout::{EnvMap, Layout};
use crate::envmap::scene::{LightKind, Scene, REFLECTOR};
use crate::error::{Error, Result};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// Maps narrower than this are enlarged (whole pixels) so the labels fit.
pub const MIN_WIDTH: usize = 1024;
/// At most this many lights are numbered on the map and listed in the legend (by energy).
pub const MAX_LISTED: usize = 24;
const LINE: usize = 18;
const PAD: i32 = 10;

/// The colour of each kind of light.
pub fn kind_colour(kind: LightKind) -> [u8; 3] {
    match kind {
        LightKind::Sun => [255, 225, 0],
        LightKind::Sky => [0, 200, 255],
        LightKind::Window => [70, 110, 255],
        LightKind::Lamp => [255, 120, 0],
    }
}

/// What was drawn.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Overlay {
    /// The PNG's size in pixels (width, height): the map, enlarged to at least [`MIN_WIDTH`], and
    /// the legend beneath.
    pub image_size: [usize; 2],
    /// How many image pixels wide and high each map pixel is drawn.
    pub zoom: usize,
    /// The exposure that puts the map's median luminance at mid-grey.
    pub exposure: f64,
    /// Lights numbered on the map and named in the legend (at most [`MAX_LISTED`], by energy).
    pub lights_listed: usize,
}

/// Draws `scene` (analysed from `map`) over the tonemapped map and writes it as a PNG, through a
/// temporary file renamed into place.
pub fn write_overlay(path: &Path, map: &EnvMap, scene: &Scene) -> Result<Overlay> {
    let (width, height) = (map.image.width, map.image.height);
    if width == 0 || height == 0 {
        return Err(Error::invalid(format!(
            "{}: the map is empty",
            path.display()
        )));
    }
    let zoom = MIN_WIDTH.div_ceil(width).max(1);
    let (w, map_h) = (width * zoom, height * zoom);
    let listed = listed(scene);
    let h = map_h + (listed.len() + 2) * LINE + 2 * PAD as usize;
    let exposure = 0.18 / scene.levels.median.max(1e-12);
    let label = |x: usize, y: usize| -> u16 {
        scene
            .cells
            .cell_of_pixel(map, x, y)
            .map_or(REFLECTOR, |c| scene.label[c])
    };
    let mut rgb = vec![255u8; w * h * 3];
    for y in 0..height {
        for x in 0..width {
            let c = pixel_colour(map, scene, exposure, x, y, &label);
            for yy in y * zoom..(y + 1) * zoom {
                for xx in x * zoom..(x + 1) * zoom {
                    rgb[(yy * w + xx) * 3..][..3].copy_from_slice(&c);
                }
            }
        }
    }
    let drawn =
        |e: String| Error::invalid(format!("{}: cannot draw the overlay: {e}", path.display()));
    draw_text(&mut rgb, (w, h), map_h, map, scene, &listed, zoom).map_err(drawn)?;
    crate::plot::write_rgb_png(path, (w, h), rgb, "overlay")?;
    Ok(Overlay {
        image_size: [w, h],
        zoom,
        exposure,
        lights_listed: listed.len(),
    })
}

/// The lights numbered and listed: the most energetic, at most [`MAX_LISTED`], in the scene's
/// order.
fn listed(scene: &Scene) -> Vec<usize> {
    let mut k: Vec<usize> = (0..scene.lights.len()).collect();
    k.sort_by(|&a, &b| {
        scene.lights[b]
            .energy_share
            .total_cmp(&scene.lights[a].energy_share)
    });
    k.truncate(MAX_LISTED);
    k.sort_unstable();
    k
}

/// A pixel tonemapped (exposure, x / (1 + x), sRGB), tinted by its light's kind, outlined where
/// its neighbour belongs to another region.
fn pixel_colour(
    map: &EnvMap,
    scene: &Scene,
    exposure: f64,
    x: usize,
    y: usize,
    label: &dyn Fn(usize, usize) -> u16,
) -> [u8; 3] {
    if map.direction(x, y).is_none() {
        return [255; 3];
    }
    let p = map.image.get(x, y);
    let tone = |v: f32| {
        let v = (v as f64 * exposure).max(0.0);
        (srgb_encode(v / (1.0 + v)) * 255.0)
            .round()
            .clamp(0.0, 255.0) as u8
    };
    let base = [tone(p[0]), tone(p[1]), tone(p[2])];
    let l = label(x, y);
    if l == REFLECTOR {
        return base;
    }
    let k = kind_colour(scene.lights[l as usize].kind);
    let (w, h) = (map.image.width, map.image.height);
    let edge = [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|&(dx, dy)| {
        let (nx, ny) = (x as i64 + dx, y as i64 + dy);
        nx >= 0 && ny >= 0 && (nx as usize) < w && (ny as usize) < h && {
            label(nx as usize, ny as usize) != l
        }
    });
    if edge {
        k
    } else {
        std::array::from_fn(|c| ((base[c] as u16 * 3 + k[c] as u16 * 2) / 5) as u8)
    }
}

/// The image position (pixel) of direction `d` in `map`: by formula for a lat-long, else the
/// pixel whose centre is nearest.
fn position_of(map: &EnvMap, d: [f64; 3]) -> (usize, usize) {
    let (w, h) = (map.image.width, map.image.height);
    if map.layout == Layout::LatLong {
        let lon = d[0].atan2(d[2]);
        let lat = d[1].clamp(-1.0, 1.0).asin();
        let u = 0.5 - lon / (2.0 * std::f64::consts::PI);
        let v = 0.5 - lat / std::f64::consts::PI;
        return (
            ((u * w as f64) as usize).min(w - 1),
            ((v * h as f64) as usize).min(h - 1),
        );
    }
    map.pixels_with_directions()
        .max_by(|a, b| {
            let dot = |q: [f64; 3]| q[0] * d[0] + q[1] * d[1] + q[2] * d[2];
            dot(a.2).total_cmp(&dot(b.2))
        })
        .map_or((0, 0), |p| (p.0, p.1))
}

/// The numbers on the map and the legend beneath it.
#[allow(clippy::too_many_arguments)]
fn draw_text(
    rgb: &mut [u8],
    (w, h): (usize, usize),
    top: usize,
    map: &EnvMap,
    scene: &Scene,
    listed: &[usize],
    zoom: usize,
) -> std::result::Result<(), String> {
    crate::plot::register_font();
    let root = BitMapBackend::with_buffer(rgb, (w as u32, h as u32)).into_drawing_area();
    let e = |e: DrawingAreaErrorKind<_>| e.to_string();
    let font = ("sans-serif", 14).into_font();
    for (n, &k) in listed.iter().enumerate() {
        let l = &scene.lights[k];
        let (x, y) = position_of(map, l.direction);
        let (x, y) = ((x * zoom + zoom / 2) as i32, (y * zoom + zoom / 2) as i32);
        let [r, g, b] = kind_colour(l.kind);
        let style = font
            .clone()
            .color(&RGBColor(r, g, b))
            .pos(Pos::new(HPos::Center, VPos::Center));
        root.draw(&Circle::new((x, y), 9, BLACK.filled()))
            .map_err(e)?;
        root.draw(&Text::new(format!("{}", n + 1), (x, y), style))
            .map_err(e)?;
    }
    let black = font.clone().color(&BLACK);
    let mut y = top as i32 + PAD;
    let head = format!(
        "{} lights; median luminance {:.3e}, emitters from {:.3e}; {:.1}% of the energy in \
         reflectors",
        scene.lights.len(),
        scene.levels.median,
        scene.levels.threshold,
        100.0 * scene.reflector_energy_share
    );
    root.draw(&Text::new(head, (PAD, y), black.clone()))
        .map_err(e)?;
    for (n, &k) in listed.iter().enumerate() {
        y += LINE as i32;
        let l = &scene.lights[k];
        let [r, g, b] = kind_colour(l.kind);
        root.draw(&Rectangle::new(
            [(PAD, y + 2), (PAD + 12, y + 14)],
            RGBColor(r, g, b).filled(),
        ))
        .map_err(e)?;
        let text = format!(
            "{}. {} {}: {:.1}% of the energy, {:.3} sr, {}",
            n + 1,
            format!("{:?}", l.kind).to_lowercase(),
            l.spd,
            100.0 * l.energy_share,
            l.solid_angle_sr,
            l.cct_k.map_or("no CCT".into(), |k| format!(
                "CCT {k:.0} K, Duv {:+.4}",
                l.duv
            ))
        );
        root.draw(&Text::new(text, (PAD + 20, y), black.clone()))
            .map_err(e)?;
    }
    if scene.lights.len() > listed.len() {
        y += LINE as i32;
        let more = format!("... and {} more lights", scene.lights.len() - listed.len());
        root.draw(&Text::new(more, (PAD, y), black)).map_err(e)?;
    }
    root.present().map_err(e)?;
    Ok(())
}
