//! What `specmap inspect --json` names in studios, rooms, city squares, dusk and night (issue
//! 41): nine real CC0 photographs (tests/data/real, README there) and the truth scenes of
//! tools/truth_studio.py. Each decision is read from the JSON (`kind`, `solid_angle_sr`,
//! `energy_share`, `reason`, the lamp's `family`), as a user's script would.

use serde_json::Value;
use std::path::Path;

mod common;

/// `specmap inspect PATH --json` of a file under the project's root.
fn inspect(path: &str) -> Value {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    common::specmap_json(&["inspect", &file.display().to_string()])
}

fn lights<'a>(j: &'a Value, kind: &str) -> Vec<&'a Value> {
    j["lights"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|l| l["kind"] == kind)
        .collect()
}

fn share(ls: &[&Value]) -> f64 {
    ls.iter().map(|l| l["energy_share"].as_f64().unwrap()).sum()
}

fn sr(ls: &[&Value]) -> f64 {
    ls.iter()
        .map(|l| l["solid_angle_sr"].as_f64().unwrap())
        .sum()
}

fn family(l: &Value) -> &str {
    l["lamp"]["family"].as_str().unwrap_or("")
}

fn reflectors(j: &Value) -> String {
    j["bright_reflectors"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r.as_str().unwrap())
        .collect::<Vec<_>>()
        .join("\n")
}

/// A studio of softboxes, a white cyclorama and black curtains: the softboxes are lamps, the
/// cyclorama and floor the walls of an enclosure, and there is neither sky nor sun.
#[test]
fn a_real_studio_names_its_softboxes_as_lamps_and_has_no_sky() {
    let j = inspect("tests/data/real/studio.exr");
    let text = j.to_string();
    assert!(lights(&j, "sky").is_empty(), "{text}");
    assert!(lights(&j, "sun").is_empty(), "{text}");
    let lamps = lights(&j, "lamp");
    assert!(lamps.len() >= 2, "{text}");
    assert!(share(&lamps) > 0.6, "{text}");
    assert!(
        reflectors(&j).contains("the walls of an enclosure"),
        "{text}"
    );
}

/// A foyer under a vaulted ceiling with spots and strip lights: the ceiling and walls are no
/// sky; what daylight there is covers under 2 sr; the lamps are named.
#[test]
fn a_real_room_keeps_its_walls_out_of_the_sky() {
    let j = inspect("tests/data/real/lobby.exr");
    let text = j.to_string();
    assert!(lights(&j, "sky").is_empty(), "{text}");
    assert!(sr(&lights(&j, "window")) < 2.0, "{text}");
    assert!(lights(&j, "lamp").len() >= 5, "{text}");
}

/// A living room with a glazed door and wall sconces: the daylight is the door's glass, a window
/// of about 0.17 sr in one direction, not the sunlit floor, the walls or the ceiling; no sky, no
/// sun.
#[test]
fn a_real_living_room_has_its_window_and_no_sky() {
    let j = inspect("tests/data/real/apartment.exr");
    let text = j.to_string();
    assert!(lights(&j, "sky").is_empty(), "{text}");
    assert!(lights(&j, "sun").is_empty(), "{text}");
    let windows = lights(&j, "window");
    assert!(!windows.is_empty(), "{text}");
    assert!((0.05..0.4).contains(&sr(&windows)), "{text}");
    // One opening (the door spans about 55 degrees): every window within 60 degrees of the
    // brightest one's direction.
    let dir = |l: &Value| -> Vec<f64> {
        l["direction"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    let brightest = windows
        .iter()
        .max_by(|a, b| share(&[a]).total_cmp(&share(&[b])))
        .unwrap();
    let main = dir(brightest);
    for w in &windows {
        let cos: f64 = dir(w).iter().zip(&main).map(|(a, b)| a * b).sum();
        assert!(cos > 60f64.to_radians().cos(), "{w}\n{text}");
    }
}

/// Two low suns whose colour the files' lossy codec (DWAB) lost: a 6 x 6 patch (park) and a
/// 6 x 7 one (sunrise_meadow) at each sun is blue only, B up to 11800 and 15008 and down to -1876
/// and -2306, R and G under 1e-5. Each sun is still the sun, its colour taken from the light
/// around the damaged patch and the damage said. Before, park's sun was "a sunlit surface" of
/// the blue primary's colour, and sunrise_meadow was read as an enclosure lit by one blue
/// phosphor-LED lamp, 93% of its energy in walls.
#[test]
fn a_sun_whose_colour_a_codec_lost_is_still_the_sun() {
    for map in ["park", "sunrise_meadow"] {
        let j = inspect(&format!("tests/data/real/{map}.exr"));
        let text = j.to_string();
        let sun = lights(&j, "sun");
        assert_eq!(sun.len(), 1, "{map}: {text}");
        let elevation = sun[0]["elevation_deg"].as_f64().unwrap();
        assert!((5.0..15.0).contains(&elevation), "{map}: {text}");
        assert_eq!(sun[0]["colour_from_halo"], true, "{map}: {text}");
        assert!(
            sun[0]["reason"]
                .as_str()
                .unwrap()
                .contains("one primary only"),
            "{map}: {text}"
        );
        // A white of daylight's or a black body's, nowhere near the blue primary (x 0.15).
        let x = sun[0]["xy"][0].as_f64().unwrap();
        assert!(x > 0.28, "{map}: {text}");
        assert_eq!(lights(&j, "sky").len(), 1, "{map}: {text}");
        assert!(lights(&j, "lamp").is_empty(), "{map}: {text}");
    }
}

/// Two city squares, as a courtyard is seen: under an overcast sky (plaza) and at sunset with the
/// sun on the horizon (square_sunset). The sky is one light above the horizon; no lamp or window
/// is named in the trees, the facades or the paving; the setting sun is the sun, given a low
/// sun's spectrum (a sun under 4000 K is outside the CIE daylight series), its reflection on
/// the paving is a reflector, and the palace's sunlit facade is no sky.
#[test]
fn city_squares_have_one_sky_and_their_sun() {
    for map in ["plaza", "square_sunset"] {
        let j = inspect(&format!("tests/data/real/{map}.exr"));
        let text = j.to_string();
        let sky = lights(&j, "sky");
        assert_eq!(sky.len(), 1, "{map}: {text}");
        assert!(sr(&sky) < 2.0 * std::f64::consts::PI, "{map}: {text}");
        assert!(share(&sky) > 0.7, "{map}: {text}");
        for kind in ["lamp", "window"] {
            assert!(lights(&j, kind).is_empty(), "{map} {kind}: {text}");
        }
    }
    let j = inspect("tests/data/real/square_sunset.exr");
    let text = j.to_string();
    let sun = lights(&j, "sun");
    assert_eq!(sun.len(), 1, "{text}");
    assert!(
        sun[0]["spd"].as_str().unwrap().starts_with("low sun"),
        "{text}"
    );
    assert!(sun[0]["cct_K"].as_f64().unwrap() < 2500.0, "{text}");
    assert!(
        reflectors(&j).contains("below the horizon in daylight"),
        "{text}"
    );
    // The palace's sunlit facade (0.8 sr, as dim as the sky beside it and of a daylight colour)
    // is a surface the sky lights, not sky: before, the sky covered 5.87 sr.
    let cut = reflectors(&j)
        .lines()
        .filter(|r| r.starts_with("a part of the dim sky") && r.contains("a facade"))
        .count();
    assert!(cut >= 1, "{text}");
    assert!(sr(&lights(&j, "sky")) < 5.0, "{text}");
}

/// Dawn over hills and a night field: the sky, glow and all, is the sky.
#[test]
fn dusk_and_night_keep_their_bright_sky_in_the_sky() {
    for (map, least) in [("dawn", 0.8), ("night", 0.8)] {
        let j = inspect(&format!("tests/data/real/{map}.exr"));
        let text = j.to_string();
        let sky = lights(&j, "sky");
        assert_eq!(sky.len(), 1, "{map}: {text}");
        assert!(share(&sky) > least, "{map}: {text}");
        assert!(
            sky[0]["reason"].as_str().unwrap().contains("twilight"),
            "{map}: {text}"
        );
        // No lamp holding more than 1% of the energy (the glow is no fluorescent tube).
        assert!(
            lights(&j, "lamp")
                .iter()
                .all(|l| l["energy_share"].as_f64().unwrap() < 0.01),
            "{map}: {text}"
        );
    }
}

/// The truth studios: three softboxes, three lamps of the right family, no sky, no window, no
/// sun, whatever the lamps' white.
#[test]
fn the_truth_studios_are_three_lamps_of_their_family() {
    for (scene, fam) in [
        ("studio_led", "led"),
        ("studio_flash", "xenon"),
        ("studio_tungsten", "incandescent"),
    ] {
        let j = inspect(&format!("tests/data/truth/{scene}.rgb.exr"));
        let text = j.to_string();
        let lamps = lights(&j, "lamp");
        assert_eq!(lamps.len(), 3, "{scene}: {text}");
        assert!(lamps.iter().all(|l| family(l) == fam), "{scene}: {text}");
        for kind in ["sky", "window", "sun"] {
            assert!(lights(&j, kind).is_empty(), "{scene} {kind}: {text}");
        }
    }
}

/// The living room: its window is a window under 2 sr, its three warm lamps are lamps.
#[test]
fn the_truth_room_has_its_window_and_its_lamps() {
    let j = inspect("tests/data/truth/room_window_lamps.rgb.exr");
    let text = j.to_string();
    let windows = lights(&j, "window");
    assert_eq!(windows.len(), 1, "{text}");
    assert!(sr(&windows) < 2.0 && share(&windows) > 0.3, "{text}");
    assert!(lights(&j, "sky").is_empty(), "{text}");
    assert_eq!(lights(&j, "lamp").len(), 3, "{text}");
}

/// The sodium street at night: its orange night sky, of the lamps' colour, is their light
/// scattered over a city and given their spectrum, not a low sun's; the dawn sky, violet and
/// orange, keeps daylight.
#[test]
fn a_night_sky_of_the_lamps_colour_is_their_glow() {
    let j = inspect("tests/data/truth/street_hps.rgb.exr");
    let text = j.to_string();
    let sky = lights(&j, "sky");
    assert_eq!(sky.len(), 1, "{text}");
    assert_eq!(sky[0]["spd"], "hps", "{text}");
    assert!(
        sky[0]["reason"]
            .as_str()
            .unwrap()
            .contains("scattered over a city"),
        "{text}"
    );
    let j = inspect("tests/data/real/dawn.exr");
    let sky = lights(&j, "sky");
    assert!(
        sky[0]["spd"].as_str().unwrap().starts_with("daylight"),
        "{j}"
    );
}

/// The dusk street: the twilight sky is the sky; the sodium lamps are sodium (a coated lamp's
/// white is a black body's), given the mix of sodium tables of their white, and the LED lamps
/// LEDs, not patches of sky.
#[test]
fn the_truth_dusk_street_names_sodium_and_led_lamps_under_its_sky() {
    let j = inspect("tests/data/truth/street_dusk.rgb.exr");
    let text = j.to_string();
    assert_eq!(lights(&j, "sky").len(), 1, "{text}");
    let lamps = lights(&j, "lamp");
    let count = |f: &str| lamps.iter().filter(|l| family(l) == f).count();
    assert!(count("high-pressure-sodium") >= 4, "{text}");
    // The coated lamps' white (2236 K) lies between the standard lamp's and HP2's: each sodium
    // lamp is given the mix of the two with its white.
    for l in lamps.iter().filter(|l| family(l) == "high-pressure-sodium") {
        let mix = &l["lamp"]["mix"];
        assert_eq!(
            (mix["a"].as_str(), mix["b"].as_str()),
            (Some("hps"), Some("HP2")),
            "{l}"
        );
        let share = mix["share_b"].as_f64().unwrap();
        assert!((0.3..0.55).contains(&share), "{l}");
    }
    assert!(count("led") >= 1, "{text}");
    assert!(lights(&j, "sun").is_empty(), "{text}");
}
