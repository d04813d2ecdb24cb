//! Lamp families and the tables a lamp's colour is matched against.
//!
//! A lamp seen in an RGB map shows only its chromaticity, so it is matched in CIE 1960 uv to the
//! nearest of a catalogue of measured and CIE tables, one family each: incandescent and halogen
//! (the Planckian locus itself, 1500-3600 K), fluorescent (CIE F1-F12), LED (CIE LED-*), high-
//! and low-pressure sodium, mercury and metal halide. Several families share whites (a 4000 K
//! fluorescent tube, LED and metal-halide lamp lie within 0.002 of each other), so among the
//! matches within [`AMBIGUITY_UV`] of the nearest, the shape decides as a lighting designer would:
//! a warm white below 2400 K is sodium; a long strip is a fluorescent tube; a compact source on
//! the Planckian locus between 2400 and 3600 K is a filament, another compact one a white LED;
//! within a family, the kind most common in lighting today; otherwise the nearest wins. The match says how near it is and what else was near.

use crate::colorimetry::{planck, Cmfs, Observer, Xyz};
use crate::data;
use crate::error::Result;
use crate::spectrum::{Interpolation, Rule, Spectrum, WavelengthGrid};
use std::sync::OnceLock;

/// A lamp family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Family {
    /// Incandescent and halogen: a Planckian radiator.
    Incandescent,
    Fluorescent,
    Led,
    HighPressureSodium,
    LowPressureSodium,
    Mercury,
    MetalHalide,
}

impl Family {
    pub fn name(self) -> &'static str {
        match self {
            Family::Incandescent => "incandescent/halogen",
            Family::Fluorescent => "fluorescent",
            Family::Led => "LED",
            Family::HighPressureSodium => "high-pressure sodium",
            Family::LowPressureSodium => "low-pressure sodium",
            Family::Mercury => "mercury",
            Family::MetalHalide => "metal halide",
        }
    }
}

/// The tables lamps are matched against (built-in names), their families, and how common each
/// kind is in lighting today (0: the usual choice; 1: less common; 2: legacy or special), which
/// decides among near whites of one family: a 4000 K tube is far likelier a triphosphor (F10-F12)
/// than a halophosphate (F1-F6) one, a white LED a phosphor-converted (B series) than an RGB mix.
/// The ranks follow what a wrong pick costs, measured as the ColorChecker's mean CIEDE2000 under
/// one lamp against another (CAT02 to D65; `tools/lamp_rendition.py`): a measured 100 W sodium
/// lamp (c100s54) is 0.5 from `hps` and 0.8 from CIE HP1; a 4100 K triphosphor tube (f32t8-tl841)
/// 0.6 from FL11 and 3.1 from the halophosphate FL6; a warm phosphor LED (luxeon-ww-2880) 1.3 to
/// 1.9 from LED-V1 and LED-B1 and 3.9 from the RGB-mixed LED-RGB1, which is left out (RGB-mixed
/// white LEDs light stages, not rooms). Measured lamps of spectra/light/ that are not listed here
/// are left out on purpose: the truth scenes of tools/make_truth.py are lit by them, so a good
/// score cannot come from recognising a table.
pub const CATALOGUE: [(&str, Family, u8); 29] = [
    ("FL1", Family::Fluorescent, 2),
    ("FL2", Family::Fluorescent, 2),
    ("FL3", Family::Fluorescent, 2),
    ("FL4", Family::Fluorescent, 2),
    ("FL5", Family::Fluorescent, 2),
    ("FL6", Family::Fluorescent, 2),
    ("FL7", Family::Fluorescent, 1),
    ("FL8", Family::Fluorescent, 1),
    ("FL9", Family::Fluorescent, 1),
    ("FL10", Family::Fluorescent, 0),
    ("FL11", Family::Fluorescent, 0),
    ("FL12", Family::Fluorescent, 0),
    ("LED-B1", Family::Led, 0),
    ("LED-B2", Family::Led, 0),
    ("LED-B3", Family::Led, 0),
    ("LED-B4", Family::Led, 0),
    ("LED-B5", Family::Led, 0),
    ("LED-BH1", Family::Led, 1),
    ("LED-V1", Family::Led, 1),
    ("LED-V2", Family::Led, 1),
    ("HP1", Family::HighPressureSodium, 1),
    ("HP2", Family::HighPressureSodium, 1),
    ("hps", Family::HighPressureSodium, 0),
    ("lps", Family::LowPressureSodium, 0),
    ("mercury", Family::Mercury, 1),
    ("HP3", Family::MetalHalide, 1),
    ("HP4", Family::MetalHalide, 1),
    ("HP5", Family::MetalHalide, 1),
    ("metal-halide", Family::MetalHalide, 0),
];

/// Below this a warm white on the locus near a sodium table is high-pressure sodium, the
/// likelier lamp than a filament at a candle's temperature.
pub const SODIUM_BELOW_K: f64 = 2400.0;

/// The Planckian temperatures of the catalogue's filament (a candle's 1500 K to a halogen's
/// 3600 K).
pub const FILAMENT_K: (f64, f64) = (1500.0, 3600.0);

/// The temperatures where a compact source on the locus is taken for a filament rather than its
/// near twins: from a dimmed lamp's 2400 K to a halogen's 3600 K (below, high-pressure sodium
/// shares the locus, and is the likelier street lamp).
pub const FILAMENT_PREFERRED_K: (f64, f64) = (2400.0, 3600.0);

/// Matches within this uv distance of the nearest are alternatives the shape can choose among.
pub const AMBIGUITY_UV: f64 = 0.003;

/// A region this elongated (long axis over short) is a tube or a strip.
pub const STRIP_ELONGATION: f64 = 3.0;

/// One table's white.
#[derive(Debug, Clone)]
struct Entry {
    name: &'static str,
    family: Family,
    rank: u8,
    uv: [f64; 2],
}

/// The catalogue's whites, computed once (CIE 1931, 1 nm).
fn entries() -> &'static [Entry] {
    static ENTRIES: OnceLock<Vec<Entry>> = OnceLock::new();
    ENTRIES.get_or_init(|| {
        let grid = WavelengthGrid::visible_1nm();
        let cmfs = Cmfs::new(Observer::Cie1931, &grid).expect("built-in CMFs");
        CATALOGUE
            .iter()
            .map(|&(name, family, rank)| {
                let s = data::spectrum(name)
                    .expect("a built-in table")
                    .data
                    .resample(&grid, Interpolation::LIGHT);
                let uv = cmfs
                    .light_xyz(&s, Rule::Riemann)
                    .expect("same grid")
                    .uv1960();
                Entry {
                    name,
                    family,
                    rank,
                    uv,
                }
            })
            .collect()
    })
}

/// The uv of a black body at `kelvin` (CIE 1931, 360-830 nm at 1 nm).
pub fn planckian_uv(kelvin: f64) -> [f64; 2] {
    let grid = WavelengthGrid::new(360.0, 830.0, 1.0).expect("a valid grid");
    let cmfs = Cmfs::new(Observer::Cie1931, &grid).expect("built-in CMFs");
    let s = Spectrum::from_fn(grid, |w| planck(w, kelvin));
    let [x, y, z] = cmfs.integrate(&s, Rule::Riemann).expect("same grid");
    Xyz::new(x, y, z).uv1960()
}

/// What a lamp's colour matched.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LampMatch {
    /// A built-in table name, or `Planckian <K> K` for a filament.
    pub spd: String,
    pub family: Family,
    /// Distance in CIE 1960 uv from the lamp's colour to the matched white.
    pub distance_uv: f64,
    /// Why this match among the near ones.
    pub why: String,
    /// Other matches within [`AMBIGUITY_UV`] of the nearest: (spd, distance).
    pub alternatives: Vec<(String, f64)>,
}

/// A candidate white: name, family, prevalence rank, distance.
type Near = (String, Family, u8, f64);

/// Matches a lamp of colour `uv` (CIE 1960), correlated colour temperature `cct_k` (None far from
/// the locus) and shape `elongation`. Among the whites within [`AMBIGUITY_UV`] of the nearest, in
/// order: a warm white below [`SODIUM_BELOW_K`] near a sodium table is sodium; a strip is the
/// most common near fluorescent; a compact source between 2400 and 3600 K on the locus is a
/// filament; a compact one near a white LED is the most common such LED; otherwise the nearest.
pub fn match_lamp(uv: [f64; 2], cct_k: Option<f64>, elongation: f64) -> Result<LampMatch> {
    let dist = |a: [f64; 2]| (a[0] - uv[0]).hypot(a[1] - uv[1]);
    let mut found: Vec<Near> = entries()
        .iter()
        .map(|e| (e.name.to_string(), e.family, e.rank, dist(e.uv)))
        .collect();
    if let Some(k) = cct_k {
        let k = k.clamp(FILAMENT_K.0, FILAMENT_K.1);
        let planck = (
            format!("Planckian {k:.0} K"),
            Family::Incandescent,
            0,
            dist(planckian_uv(k)),
        );
        found.push(planck);
    }
    found.sort_by(|a, b| a.3.total_cmp(&b.3));
    let best = found[0].3;
    let near: Vec<&Near> = found
        .iter()
        .filter(|f| f.3 <= best + AMBIGUITY_UV)
        .collect();
    // The most common of a family among the near whites, then the nearest.
    let pick = |family: Family| {
        near.iter()
            .filter(|f| f.1 == family)
            .min_by(|a, b| {
                (a.2, a.3)
                    .partial_cmp(&(b.2, b.3))
                    .expect("finite distances")
            })
            .copied()
    };
    let strip = elongation >= STRIP_ELONGATION;
    let k = cct_k.unwrap_or(f64::NAN);
    let filament = (FILAMENT_PREFERRED_K.0..=FILAMENT_PREFERRED_K.1).contains(&k);
    let rules: [(bool, Family, &str); 4] = [
        (
            k < SODIUM_BELOW_K,
            Family::HighPressureSodium,
            "a warm white near sodium's",
        ),
        (
            strip,
            Family::Fluorescent,
            "a strip: the most common near fluorescent",
        ),
        (
            !strip && filament,
            Family::Incandescent,
            "compact and on the Planckian locus: a filament",
        ),
        (
            !strip,
            Family::Led,
            "compact: the most common near white LED",
        ),
    ];
    let (chosen, why) = rules
        .iter()
        .find_map(|&(applies, family, why)| {
            applies.then(|| pick(family)).flatten().map(|f| (f, why))
        })
        .unwrap_or((near[0], "the nearest white"));
    Ok(LampMatch {
        spd: chosen.0.clone(),
        family: chosen.1,
        distance_uv: chosen.3,
        why: why.to_string(),
        alternatives: near
            .iter()
            .filter(|f| f.0 != chosen.0)
            .map(|f| (f.0.clone(), f.3))
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn uv_of(name: &str) -> [f64; 2] {
        entries().iter().find(|e| e.name == name).unwrap().uv
    }

    #[test]
    fn a_tables_own_white_matches_that_table_or_a_near_twin() {
        for (name, family, _) in CATALOGUE {
            let m = match_lamp(uv_of(name), None, 1.0).unwrap();
            assert!(m.distance_uv <= AMBIGUITY_UV, "{name}: {m:?}");
            assert!(
                m.spd == name || m.alternatives.iter().any(|a| a.0 == name),
                "{name} ({family:?}): {m:?}"
            );
        }
        // Sodium is its own.
        let m = match_lamp(uv_of("lps"), None, 1.0).unwrap();
        assert_eq!(m.family, Family::LowPressureSodium);
    }

    #[test]
    fn shape_decides_among_near_whites() {
        // A warm white on the locus: compact, a filament; a strip, a triphosphor tube.
        let uv = planckian_uv(3000.0);
        let spot = match_lamp(uv, Some(3000.0), 1.0).unwrap();
        assert_eq!(spot.family, Family::Incandescent, "{spot:?}");
        assert_eq!(spot.spd, "Planckian 3000 K");
        let tube = match_lamp(uv, Some(3000.0), 8.0).unwrap();
        assert_eq!(tube.spd, "FL12", "{tube:?}");
        // A 4000 K tube is triphosphor, a 4000 K spot an LED, a 2000 K white sodium.
        let uv = uv_of("FL11");
        assert_eq!(match_lamp(uv, Some(4000.0), 8.0).unwrap().spd, "FL11");
        assert_eq!(
            match_lamp(uv, Some(4000.0), 1.0).unwrap().family,
            Family::Led
        );
        let m = match_lamp(planckian_uv(1970.0), Some(1970.0), 1.0).unwrap();
        assert_eq!(m.family, Family::HighPressureSodium, "{m:?}");
        // Planckian uv agrees with the table of illuminant A (a 2856 K black body).
        let a = planckian_uv(2856.0);
        let d = {
            let grid = WavelengthGrid::visible_1nm();
            let cmfs = Cmfs::new(Observer::Cie1931, &grid).unwrap();
            let s = data::spectrum("A")
                .unwrap()
                .data
                .resample(&grid, Interpolation::LIGHT);
            let t = cmfs.light_xyz(&s, Rule::Riemann).unwrap().uv1960();
            (t[0] - a[0]).hypot(t[1] - a[1])
        };
        assert!(d < 5e-4, "{d}");
    }
}
