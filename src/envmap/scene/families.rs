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
    /// Fluorescent tubes and compact lamps (CIE FL1-FL12).
    Fluorescent,
    /// White LEDs (CIE LED-*).
    Led,
    /// High-pressure sodium (CIE HP1, HP2 and the `hps` table).
    HighPressureSodium,
    /// Low-pressure sodium (the `lps` table).
    LowPressureSodium,
    /// Mercury vapour (the `mercury` table).
    Mercury,
    /// Metal halide (CIE HP3-HP5 and the `metal-halide` table).
    MetalHalide,
    /// Xenon: a flash or an arc (the measured `kinoton-75p`).
    Xenon,
}

impl Family {
    /// The family's name in the report: `incandescent/halogen`, `LED`, `high-pressure sodium`.
    pub fn name(self) -> &'static str {
        match self {
            Family::Incandescent => "incandescent/halogen",
            Family::Fluorescent => "fluorescent",
            Family::Led => "LED",
            Family::HighPressureSodium => "high-pressure sodium",
            Family::LowPressureSodium => "low-pressure sodium",
            Family::Mercury => "mercury",
            Family::MetalHalide => "metal halide",
            Family::Xenon => "xenon",
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
/// white LEDs light stages, not rooms). Two measured lamps light studios: `phosphor-led` (NIST's
/// phosphor-converted YAG LED, 6814 K), since no CIE LED table renders it within 1.9, and the
/// xenon arc `kinoton-75p` (6343 K), for flash: between any two daylight-white lamps of different
/// kinds a wrong pick costs 1.4 to 2.5 (`tools/lamp_rendition.py`). The other measured lamps of
/// spectra/light/ are left out on purpose: the truth scenes of tools/make_truth.py are lit by
/// them, so a good score cannot come from recognising a table (`studio_led` is lit by
/// `phosphor-led` and so measures the naming, not the proxy).
pub(crate) const CATALOGUE: [(&str, Family, u8); 31] = [
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
    ("phosphor-led", Family::Led, 0),
    ("kinoton-75p", Family::Xenon, 1),
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
pub(crate) const SODIUM_BELOW_K: f64 = 2400.0;

/// The Planckian temperatures of the catalogue's filament (a candle's 1500 K to a halogen's
/// 3600 K).
pub(crate) const FILAMENT_K: (f64, f64) = (1500.0, 3600.0);

/// The temperatures where a compact source on the locus is taken for a filament rather than its
/// near twins: from a dimmed lamp's 2400 K to a halogen's 3600 K (below, high-pressure sodium
/// shares the locus, and is the likelier street lamp).
pub(crate) const FILAMENT_PREFERRED_K: (f64, f64) = (2400.0, 3600.0);

/// A lamp this near a table's white (CIE 1960 uv; about a just noticeable difference), and no
/// other family's, is taken for that table whatever the rules below prefer.
pub(crate) const SAME_WHITE_UV: f64 = 0.0015;

/// Matches within this uv distance of the nearest are alternatives the shape can choose among.
pub(crate) const AMBIGUITY_UV: f64 = 0.003;

/// How far (CIE 1960 uv) a strip's white may lie from a triphosphor table's for that table to
/// be taken over a halophosphate one (`triphosphor_instead`): about 1000 K at 3500 K.
pub(crate) const TRIPHOSPHOR_REACH_UV: f64 = 0.02;

/// A region this elongated (long axis over short) is a tube or a strip.
pub(crate) const STRIP_ELONGATION: f64 = 3.0;

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
pub(crate) fn planckian_uv(kelvin: f64) -> [f64; 2] {
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
    /// The matched table's family.
    pub family: Family,
    /// Distance in CIE 1960 uv from the lamp's colour to the matched white.
    pub distance_uv: f64,
    /// Distance in CIE 1960 uv to the nearest white of the catalogue (the matched one or
    /// another): how well the lamp's colour is explained at all.
    pub nearest_uv: f64,
    /// Why this match among the near ones.
    pub why: String,
    /// Other matches within [`AMBIGUITY_UV`] of the nearest: (spd, distance).
    pub alternatives: Vec<(String, f64)>,
    /// A sodium lamp whose white lies between the standard and the colour-improved lamp's: the
    /// mix of the two with its white (see [`sodium_mix`]), its spectrum in place of `spd`'s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mix: Option<Mix>,
}

/// Two tables of one family mixed in proportion to their luminance: `share_b` of the mix's
/// luminance is `b`'s.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Mix {
    /// The first table (a built-in name).
    pub a: String,
    /// The second table (a built-in name).
    pub b: String,
    /// The share of `b` in the mix's luminance, 0 to 1.
    pub share_b: f64,
}

impl Mix {
    /// `hps 58% + HP2 42%`.
    pub fn label(&self) -> String {
        format!(
            "{} {:.0}% + {} {:.0}%",
            self.a,
            100.0 * (1.0 - self.share_b),
            self.b,
            100.0 * self.share_b
        )
    }

    /// The mix as a table: both tables at 1 nm over the range they share, each at luminance 1
    /// (CIE 1931), weighted by their shares.
    pub fn table(&self) -> Result<crate::spectrum::Tabulated> {
        let a = data::spectrum(&self.a)?.data;
        let b = data::spectrum(&self.b)?.data;
        let lo = a.range_nm().0.max(b.range_nm().0).ceil();
        let hi = a.range_nm().1.min(b.range_nm().1).floor();
        let grid = WavelengthGrid::new(lo, hi, 1.0)?;
        let cmfs = Cmfs::new(Observer::Cie1931, &grid)?;
        let unit = |t: &crate::spectrum::Tabulated| -> Result<Spectrum> {
            let s = t.resample(&grid, Interpolation::LIGHT);
            let y = cmfs.integrate(&s, Rule::Riemann)?[1];
            Ok(s.scaled(1.0 / y))
        };
        let (sa, sb) = (unit(&a)?, unit(&b)?);
        let values = sa
            .values()
            .iter()
            .zip(sb.values())
            .map(|(&va, &vb)| (1.0 - self.share_b) * va + self.share_b * vb)
            .collect();
        crate::spectrum::Tabulated::new(grid.wavelengths_nm().collect(), values)
    }
}

/// The high-pressure sodium lamps run from the standard lamp (`hps`, about 2000 K) to the
/// colour-improved one (CIE HP2, 2500 K), whose higher sodium pressure widens the self-reversed
/// D line: a coated or higher-pressure lamp lies between them.
pub(crate) const SODIUM_SERIES: (&str, &str) = ("hps", "HP2");

/// The mix of [`SODIUM_SERIES`] whose white is nearest `uv`: where the line between their
/// whites passes nearest `uv` (CIE 1960 uv is a projection of XYZ, so mixes lie on that line),
/// strictly between the two. None beyond either end, where the end table is the nearer lamp, and
/// within a just noticeable difference ([`SAME_WHITE_UV`]) of either end's white.
/// Measured (`tools/lamp_rendition.py`, ColorChecker mean CIEDE2000): the coated c100s54c
/// (2236 K) is 0.6 from its mix, 3.6 from `hps` and 2.7 from HP2; the standard c100s54 lies
/// beyond `hps`'s end and keeps `hps` (0.5).
pub(crate) fn sodium_mix(uv: [f64; 2]) -> Option<Mix> {
    let white = |name: &str| entries().iter().find(|e| e.name == name).map(|e| e.uv);
    let (a, b) = (white(SODIUM_SERIES.0)?, white(SODIUM_SERIES.1)?);
    let d = [b[0] - a[0], b[1] - a[1]];
    let s = ((uv[0] - a[0]) * d[0] + (uv[1] - a[1]) * d[1]) / (d[0] * d[0] + d[1] * d[1]);
    let near_end = |e: [f64; 2]| (uv[0] - e[0]).hypot(uv[1] - e[1]) <= SAME_WHITE_UV;
    if !(s > 0.0 && s < 1.0) || near_end(a) || near_end(b) {
        return None;
    }
    // At luminance 1 a table's X + 15Y + 3Z is 6 / v: the uv fraction s of the way from a to b
    // is this share of b's luminance.
    let (da, db) = (6.0 / a[1], 6.0 / b[1]);
    let share_b = s * da / (s * da + (1.0 - s) * db);
    Some(Mix {
        a: SODIUM_SERIES.0.into(),
        b: SODIUM_SERIES.1.into(),
        share_b,
    })
}

/// A candidate white: name, family, prevalence rank, distance.
type Near = (String, Family, u8, f64);

/// Matches a lamp of colour `uv` (CIE 1960), correlated colour temperature `cct_k` (None far from
/// the locus) and shape `elongation`. A colour within [`SAME_WHITE_UV`] of a white is that
/// table. Otherwise, among the whites within [`AMBIGUITY_UV`] of the nearest, in order: a warm white below [`SODIUM_BELOW_K`] near a sodium table is sodium; a strip is the
/// most common near fluorescent; a compact source between 2400 and 3600 K on the locus is a
/// filament; a compact one near a white LED is the most common such LED; otherwise the nearest.
pub(crate) fn match_lamp(uv: [f64; 2], cct_k: Option<f64>, elongation: f64) -> Result<LampMatch> {
    let found = whites_by_distance(uv, cct_k);
    let best = found[0].3;
    let near: Vec<&Near> = found
        .iter()
        .filter(|f| f.3 <= best + AMBIGUITY_UV)
        .collect();
    let strip = elongation >= STRIP_ELONGATION;
    let (chosen, why) = match same_white(&near) {
        Some(f) => (f, "its white, within a just noticeable difference"),
        None => match (by_shape(&near, cct_k, strip), warm_sodium(&found, cct_k)) {
            ((f, _), Some(s)) if f.1 == Family::Incandescent => (s, WARM_SODIUM_WHY),
            (shaped, _) => shaped,
        },
    };
    let (chosen, why) = match triphosphor_instead(&found, chosen, strip) {
        Some(t) => (t, TRIPHOSPHOR_WHY),
        None => (chosen, why),
    };
    let mix = (chosen.1 == Family::HighPressureSodium)
        .then(|| sodium_mix(uv))
        .flatten();
    Ok(LampMatch {
        spd: chosen.0.clone(),
        family: chosen.1,
        distance_uv: chosen.3,
        nearest_uv: best,
        why: why.to_string(),
        alternatives: near
            .iter()
            .filter(|f| f.0 != chosen.0)
            .map(|f| (f.0.clone(), f.3))
            .collect(),
        mix,
    })
}

/// The catalogue's whites (and, given a CCT, the Planckian one of that CCT within the
/// filaments' range), nearest to `uv` first.
fn whites_by_distance(uv: [f64; 2], cct_k: Option<f64>) -> Vec<Near> {
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
    found
}

/// A colour within a just noticeable difference of a table's white is that table, unless
/// tables of other families are as near, or the filaments' Planckian locus (a continuum
/// every warm white is near).
fn same_white<'a>(near: &[&'a Near]) -> Option<&'a Near> {
    let on_locus = near
        .iter()
        .any(|f| f.1 == Family::Incandescent && f.3 <= SAME_WHITE_UV);
    let within: Vec<&&Near> = near.iter().filter(|f| f.3 <= SAME_WHITE_UV).collect();
    let one_family = within.iter().all(|f| f.1 == within[0].1);
    within
        .first()
        .filter(|f| f.1 != Family::Incandescent && one_family && !on_locus)
        .map(|&&f| f)
}

/// The white the lamp's shape and CCT choose among the near ones, and why: the first rule
/// that applies and has a near white of its family, else the nearest.
fn by_shape<'a>(near: &[&'a Near], cct_k: Option<f64>, strip: bool) -> (&'a Near, &'static str) {
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
    rules
        .iter()
        .find_map(|&(applies, family, why)| {
            applies
                .then(|| most_common(near, family))
                .flatten()
                .map(|f| (f, why))
        })
        .unwrap_or((near[0], "the nearest white"))
}

/// The most common of a family among the near whites, then the nearest.
fn most_common<'a>(near: &[&'a Near], family: Family) -> Option<&'a Near> {
    near.iter()
        .filter(|f| f.1 == family)
        .min_by(|a, b| {
            (a.2, a.3)
                .partial_cmp(&(b.2, b.3))
                .expect("finite distances")
        })
        .copied()
}

/// Why a warm white took a sodium table farther than the nearest white.
const WARM_SODIUM_WHY: &str = "a warm white below 2400 K: a sodium lamp, the street lamp of that \
    white (a coated lamp's white lies on the Planckian locus)";

/// Below [`SODIUM_BELOW_K`], the nearest sodium table within [`SODIUM_REACH_UV`], taken where the
/// shape rules would name a filament: a coated high-pressure sodium lamp (c100s54c, 2236 K) has a
/// black body's white, 0.012 uv from `hps`'s, and at that temperature a lamp is far likelier
/// sodium than a filament.
fn warm_sodium(found: &[Near], cct_k: Option<f64>) -> Option<&Near> {
    cct_k.filter(|&k| k < SODIUM_BELOW_K)?;
    found
        .iter()
        .filter(|f| f.1 == Family::HighPressureSodium && f.3 <= SODIUM_REACH_UV)
        .min_by(|a, b| {
            (a.2, a.3)
                .partial_cmp(&(b.2, b.3))
                .expect("finite distances")
        })
}

/// How far (CIE 1960 uv) a warm white below [`SODIUM_BELOW_K`] may lie from a sodium table's.
pub(crate) const SODIUM_REACH_UV: f64 = 0.015;

/// Why a strip took a triphosphor table over a halophosphate one of its white.
const TRIPHOSPHOR_WHY: &str = "a strip: a triphosphor tube (today's usual one) of the nearest \
    white, rather than a legacy halophosphate table of its own";

/// A strip matched to a legacy or less common fluorescent table (rank above 0): the nearest
/// triphosphor table (rank 0) within [`TRIPHOSPHOR_REACH_UV`] instead. Measured
/// (`tools/lamp_rendition.py`): modern tubes of 2900-4100 K (f32t8-tl830/835/841, t8-polylux,
/// tl84) render the ColorChecker 0.1-0.8 CIEDE2000 from a triphosphor table shifted to their
/// white, and 2.1-3.5 from FL2 or FL3 even where those share their white.
fn triphosphor_instead<'a>(found: &'a [Near], chosen: &'a Near, strip: bool) -> Option<&'a Near> {
    if !strip || chosen.1 != Family::Fluorescent || chosen.2 == 0 {
        return None;
    }
    found
        .iter()
        .filter(|f| f.1 == Family::Fluorescent && f.2 == 0 && f.3 <= TRIPHOSPHOR_REACH_UV)
        .min_by(|a, b| a.3.total_cmp(&b.3))
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
        // A tube of the halophosphate FL3's white (3450 K) is a triphosphor tube all the same,
        // the nearest one; a compact source of that white stays FL3 or another near twin.
        let uv = uv_of("FL3");
        let tube = match_lamp(uv, Some(3450.0), 8.0).unwrap();
        assert_eq!(tube.spd, "FL11", "{tube:?}");
        assert!(tube.distance_uv > tube.nearest_uv && tube.nearest_uv < 1e-9);
        assert_ne!(match_lamp(uv, Some(3450.0), 1.0).unwrap().spd, "FL11");
        // A 4000 K tube is triphosphor, a 4000 K spot an LED (LED-B3's white is within a just
        // noticeable difference of FL11's), a 2000 K white sodium.
        let uv = uv_of("FL11");
        assert_eq!(match_lamp(uv, Some(4000.0), 8.0).unwrap().spd, "FL11");
        assert_eq!(
            match_lamp(uv, Some(4000.0), 1.0).unwrap().family,
            Family::Led
        );
        let spot = match_lamp(planckian_uv(4050.0), Some(4050.0), 1.0).unwrap();
        assert_eq!(spot.family, Family::Led, "{spot:?}");
        let m = match_lamp(planckian_uv(1970.0), Some(1970.0), 1.0).unwrap();
        assert_eq!(m.family, Family::HighPressureSodium, "{m:?}");
        // A coated sodium lamp's white is a 2236 K black body's: sodium all the same.
        let m = match_lamp(planckian_uv(2236.0), Some(2236.0), 1.0).unwrap();
        assert_eq!(m.family, Family::HighPressureSodium, "{m:?}");
        let m = match_lamp(planckian_uv(2700.0), Some(2700.0), 1.0).unwrap();
        assert_eq!(m.family, Family::Incandescent, "{m:?}");
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

    /// The sodium mix's own white (its table integrated) is the lamp's, wherever the lamp lies
    /// between the two ends; beyond them there is no mix.
    #[test]
    fn a_sodium_mix_has_the_lamps_white() {
        let grid = WavelengthGrid::visible_1nm();
        let cmfs = Cmfs::new(Observer::Cie1931, &grid).unwrap();
        let (a, b) = (uv_of("hps"), uv_of("HP2"));
        for s in [0.1, 0.42, 0.9] {
            let uv = [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])];
            let mix = sodium_mix(uv).unwrap();
            assert!(mix.share_b > 0.0 && mix.share_b < 1.0, "{mix:?}");
            let t = mix.table().unwrap().resample(&grid, Interpolation::LIGHT);
            let got = cmfs.light_xyz(&t, Rule::Riemann).unwrap().uv1960();
            let d = (got[0] - uv[0]).hypot(got[1] - uv[1]);
            assert!(d < 2e-4, "s {s}: {got:?} against {uv:?} ({d})");
        }
        let beyond = |s: f64| [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])];
        assert!(sodium_mix(beyond(-0.2)).is_none());
        assert!(sodium_mix(beyond(1.2)).is_none());
        // A coated lamp's white (a 2236 K black body) is mixed; the standard lamp's is not.
        let m = match_lamp(planckian_uv(2236.0), Some(2236.0), 1.0).unwrap();
        let share = m.mix.as_ref().unwrap().share_b;
        assert!((0.3..0.55).contains(&share), "{m:?}");
        assert!(match_lamp(a, Some(2050.0), 1.0).unwrap().mix.is_none());
    }
}
