//! The scene analysis on maps with the traits of real photographs (issue 13): each is built here
//! from light colours and luminances a photograph of that kind has, and the analysis must name
//! the lights a colour scientist would name. The truth scenes of tests/data/truth (physically
//! built spectra) are in tests/fidelity.rs; the two real photographs in envmaps/ in
//! tests/convert.rs.

use specmap::colorimetry::{RgbSpace, Xyz};
use specmap::envmap::layout::{EnvMap, Layout};
use specmap::envmap::scene::{analyse, Family, LightKind, Scene, SceneSettings};
use specmap::envmap::RgbImage;
use specmap::illuminant;

const W: usize = 512;
const H: usize = 256;

/// Linear sRGB of a chromaticity at luminance `y` (may be out of gamut: kept).
fn rgb(xy: [f64; 2], y: f64) -> [f32; 3] {
    // Xyz::from_xy has Y = 100, which rgb_from_xyz takes as luminance 1.
    let xyz = Xyz::from_xy(xy);
    RgbSpace::SRGB
        .rgb_from_xyz(Xyz::new(xyz.x() * y, xyz.y() * y, xyz.z() * y))
        .map(|v| v as f32)
}

/// The chromaticity of a black body, or of CIE daylight from 4000 K.
fn white(kelvin: f64) -> [f64; 2] {
    if kelvin >= 4000.0 {
        illuminant::daylight_xy(kelvin).unwrap()
    } else {
        let t = illuminant::planckian(kelvin).unwrap();
        let grid = specmap::spectrum::WavelengthGrid::visible_1nm();
        let cmfs = specmap::colorimetry::Cmfs::new(specmap::colorimetry::Observer::Cie1931, &grid)
            .unwrap();
        let s = t.resample(&grid, specmap::spectrum::Interpolation::LIGHT);
        cmfs.light_xyz(&s, specmap::spectrum::Rule::Riemann)
            .unwrap()
            .xy()
    }
}

/// A lat-long map painted by `f(direction)`.
fn map(f: impl Fn([f64; 3]) -> [f32; 3]) -> EnvMap {
    let mut m = EnvMap::new(Layout::LatLong, RgbImage::new(W, H)).unwrap();
    for y in 0..H {
        for x in 0..W {
            let d = m.direction(x, y).unwrap();
            m.image.set(x, y, f(d));
        }
    }
    m
}

/// The unit direction at `elevation` and `azimuth` (degrees; azimuth from +Z towards +X).
fn dir(elevation: f64, azimuth: f64) -> [f64; 3] {
    let (e, a) = (elevation.to_radians(), azimuth.to_radians());
    [a.sin() * e.cos(), e.sin(), a.cos() * e.cos()]
}

/// The angle between two unit directions, in degrees.
fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    (a[0] * b[0] + a[1] * b[1] + a[2] * b[2])
        .clamp(-1.0, 1.0)
        .acos()
        .to_degrees()
}

fn scene(m: &EnvMap) -> Scene {
    analyse(m, &RgbSpace::SRGB, [1.0; 3], &SceneSettings::default()).unwrap()
}

fn kinds(s: &Scene, kind: LightKind) -> usize {
    s.lights.iter().filter(|l| l.kind == kind).count()
}

fn describe(s: &Scene) -> String {
    let mut t: Vec<String> = s
        .lights
        .iter()
        .map(|l| format!("{:?} {} {:.3}: {}", l.kind, l.spd, l.energy_share, l.reason))
        .collect();
    t.extend(s.bright_reflectors.iter().cloned());
    t.join("\n")
}

/// A sunset over water: a low sun 3 degrees up holding a few percent of the energy, an 8000 K
/// sky, its reflection in the water below with the sun's glint.
#[test]
fn a_low_sun_over_water_is_the_sun_and_its_glint_is_not_a_lamp() {
    let sun = dir(3.0, 20.0);
    let glint = dir(-3.0, 20.0);
    let (red, sky) = (white(2300.0), white(8000.0));
    let m = map(|d| {
        let up = d[1];
        if angle(d, sun) < 0.5 {
            rgb(red, 3000.0)
        } else if up > 0.0 {
            rgb(sky, 1.0 + 2.0 * (1.0 - up))
        } else if angle(d, glint) < 1.5 {
            rgb(red, 60.0)
        } else {
            rgb(sky, 0.3)
        }
    });
    let s = scene(&m);
    let text = describe(&s);
    let found = s.sun().expect(&text);
    assert!(angle(found.direction, sun) < 1.0, "{text}");
    assert!(found.energy_share < 0.2, "{text}");
    assert!(found.cct_k.is_some_and(|k| k < 3000.0), "{text}");
    assert_eq!(kinds(&s, LightKind::Sky), 1, "{text}");
    assert_eq!(kinds(&s, LightKind::Lamp), 0, "{text}");
}

/// A night field: a dozen street lamps of 2500 K to 7200 K under a dim, daylight-coloured
/// moonlit sky. No sun (the lamps are many and alike), the sky is the sky, every lamp a lamp.
#[test]
fn a_dozen_lamps_under_a_moonlit_sky_are_lamps_and_the_sky_is_sky() {
    let lamps: Vec<([f64; 3], [f32; 3])> = (0..12)
        .map(|k| {
            let cct = 2500.0 + (7200.0 - 2500.0) * k as f64 / 11.0;
            let d = dir(2.0 + (k % 4) as f64 * 2.5, -160.0 + 28.0 * k as f64);
            (d, rgb(white(cct), 800.0 + cct / 10.0))
        })
        .collect();
    let (moonlit, field) = (rgb(white(4500.0), 0.01), rgb(white(3000.0), 0.004));
    let m = map(|d| {
        if let Some((_, c)) = lamps.iter().find(|(l, _)| angle(d, *l) < 0.6) {
            return *c;
        }
        if d[1] > 0.0 {
            moonlit
        } else {
            field
        }
    });
    let s = scene(&m);
    let text = describe(&s);
    assert!(s.sun().is_none(), "{text}");
    assert_eq!(kinds(&s, LightKind::Sky), 1, "{text}");
    assert_eq!(kinds(&s, LightKind::Lamp), 12, "{text}");
    for l in s.lights.iter().filter(|l| l.kind == LightKind::Lamp) {
        let m = l.lamp.as_ref().unwrap();
        assert!(m.distance_uv < 0.01, "{}: {m:?}", l.spd);
    }
}

/// A hotel room lit by warm ceiling spots whose cores are clipped white, their halos 3900 K:
/// lamps of their halo's colour, not an exterior lit by daylight.
#[test]
fn clipped_ceiling_spots_are_lamps_of_their_halos_colour() {
    let spots: Vec<[f64; 3]> = (0..4).map(|k| dir(60.0, 90.0 * k as f64)).collect();
    let warm = white(3900.0);
    let m = map(|d| {
        let a = spots.iter().map(|s| angle(d, *s)).fold(180.0, f64::min);
        if a < 0.8 {
            [65504.0; 3]
        } else if a < 6.0 {
            rgb(warm, 400.0 / (a * a))
        } else if d[1] > 0.0 {
            rgb(warm, 0.4)
        } else {
            rgb([0.40, 0.38], 0.2)
        }
    });
    let s = scene(&m);
    let text = describe(&s);
    assert!(s.levels.clipped, "{text}");
    assert!(s.sun().is_none(), "{text}");
    assert_eq!(
        kinds(&s, LightKind::Sky) + kinds(&s, LightKind::Window),
        0,
        "{text}"
    );
    assert_eq!(kinds(&s, LightKind::Lamp), 4, "{text}");
    for l in &s.lights {
        assert!(l.clipped_pixels > 0 && l.colour_from_halo, "{text}");
        let k = l.cct_k.unwrap();
        assert!((3600.0..4200.0).contains(&k), "{k} K\n{text}");
    }
}

/// A night street with four sodium lamps: none of them is taken for the sun, each is sodium; the
/// sodium-lit sky above is a night sky.
#[test]
fn four_sodium_lamps_are_sodium_lamps_not_a_sun() {
    let sodium = specmap::envmap::scene::main_light::white_xy("hps").unwrap();
    let lamps: Vec<[f64; 3]> = (0..4)
        .map(|k| dir(35.0 - 7.0 * k as f64, if k % 2 == 0 { 30.0 } else { -30.0 }))
        .collect();
    let m = map(|d| {
        let a = lamps.iter().map(|l| angle(d, *l)).fold(180.0, f64::min);
        if a < 0.7 {
            rgb(sodium, 5000.0)
        } else if d[1] > 0.0 {
            rgb(sodium, 0.02)
        } else {
            rgb(sodium, 0.5 / (1.0 + a / 10.0))
        }
    });
    let s = scene(&m);
    let text = describe(&s);
    assert!(s.sun().is_none(), "{text}");
    assert_eq!(kinds(&s, LightKind::Lamp), 4, "{text}");
    for l in s.lights.iter().filter(|l| l.kind == LightKind::Lamp) {
        assert_eq!(
            l.lamp.as_ref().unwrap().family,
            Family::HighPressureSodium,
            "{text}"
        );
    }
    // The sodium glow of the sky over a city is a night sky (issue 41), one light, of its colour.
    assert!(kinds(&s, LightKind::Sky) <= 1, "{text}");
    for l in s.lights.iter().filter(|l| l.kind == LightKind::Sky) {
        assert!(l.cct_k.is_some_and(|k| k < 2400.0), "{text}");
    }
}

/// A sunlit courtyard seen from under a roof: blue sky through the opening, no sun in view, the
/// brightest pixels a small sunlit yellow wall. The sky is found; the wall is a reflector.
#[test]
fn a_sunlit_yellow_wall_beside_the_sky_is_a_reflector() {
    let wall = dir(25.0, 0.0);
    let (blue, roof) = (white(10000.0), white(6500.0));
    let m = map(|d| {
        let up = d[1];
        if angle(d, wall) < 6.0 {
            rgb([0.46, 0.47], 9.0)
        } else if up > 0.25 && d[2] > 0.3 {
            rgb(blue, 3.0)
        } else if up > 0.0 {
            rgb(roof, 0.08)
        } else {
            rgb([0.36, 0.36], 0.3)
        }
    });
    let s = scene(&m);
    let text = describe(&s);
    assert!(s.sun().is_none(), "{text}");
    assert_eq!(kinds(&s, LightKind::Lamp), 0, "{text}");
    assert!(
        kinds(&s, LightKind::Sky) + kinds(&s, LightKind::Window) >= 1,
        "{text}"
    );
    assert!(
        s.bright_reflectors
            .iter()
            .any(|r| r.contains("sunlit") || r.contains("daylit")),
        "{text}"
    );
}

/// A courtyard open to the sky on one side, its sunlit paving below the horizon as bright as the
/// sky above it and joined to it: the sky is only what lies above the horizon (issue 41).
#[test]
fn a_sky_never_runs_below_the_horizon_onto_the_paving() {
    let sky = white(8000.0);
    let m = map(|d| {
        let azimuth = d[0].atan2(d[2]).to_degrees();
        let elevation = d[1].clamp(-1.0, 1.0).asin().to_degrees();
        if azimuth.abs() > 30.0 || elevation < -20.0 {
            rgb(white(3000.0), 0.05)
        } else if elevation > 0.0 {
            rgb(sky, 10.0)
        } else {
            rgb(sky, 8.0)
        }
    });
    let s = scene(&m);
    let text = describe(&s);
    let found: Vec<_> = s
        .lights
        .iter()
        .filter(|l| l.kind == LightKind::Sky)
        .collect();
    assert_eq!(found.len(), 1, "{text}");
    assert!(
        found[0]
            .cells
            .iter()
            .all(|&i| s.cells.direction(i)[1] > 0.0),
        "{text}"
    );
    assert!(found[0].solid_angle_sr < 1.2, "{text}");
}
