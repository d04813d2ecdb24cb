//! Illuminants computed from a colour temperature: the CIE daylight series and Planckian radiators.

use crate::colorimetry::planck;
use crate::data::Table;
use crate::error::{Error, Result};
use crate::spectrum::Tabulated;

/// The CIE daylight locus's valid range of correlated colour temperature, in kelvin.
pub const DAYLIGHT_RANGE_K: (f64, f64) = (4000.0, 25000.0);

/// Chromaticity of CIE daylight at a correlated colour temperature (CIE 15:2018, Eq. 4.7-4.8).
/// `cct_k` is the actual CCT; the nominal temperatures of the D illuminants (D65 = 6500 K) are
/// `actual = nominal * 1.4388 / 1.4380`.
pub fn daylight_xy(cct_k: f64) -> Result<[f64; 2]> {
    let (lo, hi) = DAYLIGHT_RANGE_K;
    if !(lo..=hi).contains(&cct_k) {
        return Err(Error::invalid(format!(
            "CIE daylight is defined from {lo} to {hi} K, not at {cct_k:.0} K"
        )));
    }
    let t = cct_k;
    let x = if t <= 7000.0 {
        -4.607e9 / t.powi(3) + 2.9678e6 / (t * t) + 0.09911e3 / t + 0.244063
    } else {
        -2.0064e9 / t.powi(3) + 1.9018e6 / (t * t) + 0.24748e3 / t + 0.23704
    };
    Ok([x, daylight_locus_y(x)])
}

/// The relative SPD of CIE daylight at `cct_k` (S0 + M1 S1 + M2 S2, with M1 and M2 rounded to
/// three decimals as CIE 15 prescribes), at the basis functions' 5 nm sampling, 300-830 nm.
pub fn daylight(cct_k: f64) -> Result<Tabulated> {
    let [x, y] = daylight_xy(cct_k)?;
    let m = 0.0241 + 0.2562 * x - 0.7341 * y;
    let round3 = |v: f64| (v * 1000.0).round() / 1000.0;
    let m1 = round3((-1.3515 - 1.7703 * x + 5.9114 * y) / m);
    let m2 = round3((0.0300 - 31.4424 * x + 30.0717 * y) / m);
    let [s0, s1, s2] = daylight_components()?;
    let values = (0..s0.values().len())
        .map(|i| s0.values()[i] + m1 * s1.values()[i] + m2 * s2.values()[i])
        .collect();
    Tabulated::new(s0.wavelengths_nm().to_vec(), values)
}

/// The CIE daylight basis functions S0, S1, S2 (CIE 15:2018, Table 6), 5 nm, 300-830 nm: every
/// CIE daylight is `S0 + M1 S1 + M2 S2`, and any three coefficients span the family's plane, in
/// which each chromaticity has exactly one member of a given luminance.
pub fn daylight_components() -> Result<[Tabulated; 3]> {
    let basis = Table::builtin("cie-daylight")?;
    Ok([
        basis.column("S0")?,
        basis.column("S1")?,
        basis.column("S2")?,
    ])
}

/// The CIE daylight locus in the CIE 1931 xy diagram: `y = -3 x^2 + 2.87 x - 0.275`, defined
/// between x = 0.2524 (25000 K) and x = 0.3823 (4000 K).
pub fn daylight_locus_y(x: f64) -> f64 {
    -3.0 * x * x + 2.870 * x - 0.275
}

/// A black body at `cct_k`, sampled at 1 nm over 300-830 nm and normalised to 100 at 560 nm.
pub fn planckian(cct_k: f64) -> Result<Tabulated> {
    if !(cct_k.is_finite() && cct_k > 0.0) {
        return Err(Error::invalid(format!(
            "a black body needs a positive temperature, not {cct_k} K"
        )));
    }
    let w: Vec<f64> = (300..=830).map(f64::from).collect();
    let norm = 100.0 / planck(560.0, cct_k);
    let v = w.iter().map(|&l| planck(l, cct_k) * norm).collect();
    Tabulated::new(w, v)
}

/// Daylight where CIE defines it (4000-25000 K), a Planckian radiator below, and daylight at
/// 25000 K above: the natural light of a given colour temperature.
pub fn natural(cct_k: f64) -> Result<Tabulated> {
    let (lo, hi) = DAYLIGHT_RANGE_K;
    if cct_k < lo {
        planckian(cct_k)
    } else {
        daylight(cct_k.min(hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::{cct, Cmfs, Observer};
    use crate::spectrum::{Interpolation, Rule, WavelengthGrid};

    #[test]
    fn daylight_reproduces_d65_and_d50() {
        // D65 and D50 are daylight at nominal 6500 and 5000 K: the generated SPD must match the
        // published tables (which CIE computed with this formula) to their 4-5 digits.
        for (name, nominal) in [("D65", 6500.0), ("D50", 5000.0), ("D75", 7500.0)] {
            let ours = daylight(nominal * 1.4388 / 1.4380).unwrap();
            let table = Table::builtin(name).unwrap().single_column().unwrap();
            for (w, v) in table.wavelengths_nm().iter().zip(table.values()) {
                if let Some(i) = ours.wavelengths_nm().iter().position(|x| x == w) {
                    let o = ours.values()[i];
                    assert!(
                        (o - v).abs() < 0.01 * v.max(1.0),
                        "{name} at {w}: {o} vs {v}"
                    );
                }
            }
        }
    }

    #[test]
    fn natural_light_has_the_requested_cct() {
        let grid = WavelengthGrid::new(360.0, 830.0, 1.0).unwrap();
        let cmfs = Cmfs::new(Observer::Cie1931, &grid).unwrap();
        for t in [2000.0, 3200.0, 4500.0, 6500.0, 12000.0] {
            let s = natural(t).unwrap().resample(&grid, Interpolation::LIGHT);
            let c = cct(cmfs.light_xyz(&s, Rule::Riemann).unwrap()).unwrap();
            // Planckian: exact; daylight: the CIE formula is a fit, good to a few kelvin.
            let tol = if t < 4000.0 { 1e-3 } else { 0.01 * t };
            assert!((c.kelvin.unwrap() - t).abs() < tol, "{t}: {:?}", c);
        }
        assert!(daylight(3000.0).is_err());
        assert!(planckian(-5.0).is_err());
    }
}
