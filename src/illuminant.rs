//! Illuminants computed from a colour temperature: the CIE daylight series, the low sun (direct
//! sunlight through the atmosphere) and Planckian radiators.

use crate::colorimetry::{cct, planck, Cmfs, Observer, Xyz};
use crate::data::Table;
use crate::error::{Error, Result};
use crate::spectrum::{Interpolation, Rule, Tabulated, WavelengthGrid};

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

/// Daylight where CIE defines it (4000-25000 K), the low sun ([`low_sun`]) from
/// [`LOW_SUN_MIN_K`] to 4000 K, a Planckian radiator below that (colder than any sun: the CCT of
/// a measured colour never is), and daylight at 25000 K above: the natural light of a given
/// colour temperature.
pub fn natural(cct_k: f64) -> Result<Tabulated> {
    let (lo, hi) = DAYLIGHT_RANGE_K;
    if natural_is_low_sun(cct_k) {
        low_sun(cct_k)
    } else if cct_k < lo {
        planckian(cct_k)
    } else {
        daylight(cct_k.min(hi))
    }
}

/// Whether [`natural`] gives the low sun at `cct_k` (from [`LOW_SUN_MIN_K`] up to, not
/// including, the daylight range's 4000 K).
pub fn natural_is_low_sun(cct_k: f64) -> bool {
    (LOW_SUN_MIN_K..DAYLIGHT_RANGE_K.0).contains(&cct_k)
}

/// The lowest CCT [`natural`] gives the low sun for: the CCT of a measured colour starts here
/// (`colorimetry::cct` searches 1000-100000 K), and the sun on the horizon (about 990 K with the
/// defaults below) is redder still, so [`low_sun`] reaches every CCT from here to 4000 K.
pub const LOW_SUN_MIN_K: f64 = 1000.0;

/// The built-in table of the extraterrestrial solar spectral irradiance: the `extraterrestrial`
/// column of the ASTM G173-03 reference spectra (W m^-2 nm^-1, 280-4000 nm at 0.5-5 nm; see
/// spectra/README.md).
pub const SOLAR_TABLE: &str = "astm-g173-etr";

/// The Linke-like turbidity T of the low sun's aerosol (Preetham, Shirley and Smits 1999: T = 2
/// very clear, 3 clear, 6 hazy); the Angstrom coefficient is `beta = 0.04608 T - 0.04586`
/// (ibid., appendix), 0.092 at T = 3, Angstrom's "clear" atmosphere (0.1).
pub const LOW_SUN_TURBIDITY: f64 = 3.0;

/// The Angstrom exponent alpha of the aerosol optical depth `beta (lambda / 1 um)^-alpha`: 1.3,
/// Angstrom's (1929) mean for continental aerosol, the value Preetham et al. (1999) use.
pub const ANGSTROM_ALPHA: f64 = 1.3;

/// The ozone column: 0.3 atm-cm (300 Dobson units), the mid-latitude mean.
pub const OZONE_ATM_CM: f64 = 0.3;

/// The height of the ozone layer's maximum (km) and the Earth's radius (km), for the ozone's air
/// mass (Bird and Riordan 1986, Eq. 2-8, after Paltridge and Platt 1976).
const OZONE_HEIGHT_KM: f64 = 22.0;
const EARTH_RADIUS_KM: f64 = 6370.0;

/// Ozone absorption coefficients (per atm-cm, base e) over the Chappuis band and the Huggins
/// band's tail: Leckner (1978) as tabulated by Bird and Riordan (1986, Table 1, SPCTRAL2);
/// 0 from 780 nm on. No ozone cross-section table ships with specmap or colour-science 0.4.7:
/// these 47 points are the published ones, interpolated linearly.
const OZONE_K: [(f64, f64); 47] = [
    (300.0, 10.0),
    (305.0, 4.8),
    (310.0, 2.7),
    (315.0, 1.35),
    (320.0, 0.8),
    (325.0, 0.38),
    (330.0, 0.16),
    (335.0, 0.075),
    (340.0, 0.04),
    (345.0, 0.019),
    (350.0, 0.007),
    (360.0, 0.0),
    (370.0, 0.0),
    (380.0, 0.0),
    (390.0, 0.0),
    (400.0, 0.0),
    (410.0, 0.0),
    (420.0, 0.0),
    (430.0, 0.0),
    (440.0, 0.0),
    (450.0, 0.003),
    (460.0, 0.006),
    (470.0, 0.009),
    (480.0, 0.014),
    (490.0, 0.021),
    (500.0, 0.03),
    (510.0, 0.04),
    (520.0, 0.048),
    (530.0, 0.063),
    (540.0, 0.075),
    (550.0, 0.085),
    (570.0, 0.12),
    (593.0, 0.119),
    (610.0, 0.12),
    (630.0, 0.09),
    (656.0, 0.065),
    (667.6, 0.051),
    (690.0, 0.028),
    (710.0, 0.018),
    (718.0, 0.015),
    (724.4, 0.012),
    (740.0, 0.01),
    (752.5, 0.008),
    (757.5, 0.007),
    (762.5, 0.006),
    (767.5, 0.005),
    (780.0, 0.0),
];

/// The Rayleigh optical depth of the whole atmosphere at sea level (1013.25 hPa) at `nm`:
/// `0.008569 l^-4 (1 + 0.0113 l^-2 + 0.00013 l^-4)`, l in micrometres (Hansen and Travis 1974,
/// Eq. 2.29).
pub fn rayleigh_optical_depth(nm: f64) -> f64 {
    let l2 = (nm / 1000.0).powi(-2);
    0.008569 * l2 * l2 * (1.0 + 0.0113 * l2 + 0.00013 * l2 * l2)
}

/// The aerosol optical depth at `nm`, Angstrom's law `beta (l / 1 um)^-alpha` with
/// [`ANGSTROM_ALPHA`] and beta of [`LOW_SUN_TURBIDITY`].
pub fn aerosol_optical_depth(nm: f64) -> f64 {
    let beta = 0.04608 * LOW_SUN_TURBIDITY - 0.04586;
    beta * (nm / 1000.0).powf(-ANGSTROM_ALPHA)
}

/// The ozone optical depth at `nm`: [`OZONE_ATM_CM`] times Leckner's coefficient, interpolated
/// linearly (0 outside 300-780 nm; the coefficients rise below 300 nm, where specmap has no
/// output).
pub fn ozone_optical_depth(nm: f64) -> f64 {
    let k = match OZONE_K.iter().position(|&(w, _)| w >= nm) {
        None | Some(0) => 0.0,
        Some(i) => {
            let ((w0, k0), (w1, k1)) = (OZONE_K[i - 1], OZONE_K[i]);
            k0 + (k1 - k0) * (nm - w0) / (w1 - w0)
        }
    };
    OZONE_ATM_CM * k
}

/// The relative optical air mass at a solar elevation (degrees, 0 to 90): Kasten and Young
/// (1989), `1 / (cos z + 0.50572 (96.07995 - z)^-1.6364)`, z the zenith angle in degrees: 1 at
/// the zenith, 38 on the horizon (a flat atmosphere's 1 / cos z is infinite there).
pub fn relative_air_mass(elevation_deg: f64) -> f64 {
    let z = 90.0 - elevation_deg;
    1.0 / (z.to_radians().cos() + 0.50572 * (96.07995 - z).powf(-1.6364))
}

/// The ozone's air mass at a solar elevation (degrees): the path through a thin layer at
/// 22 km over a spherical Earth, `(1 + h / R) / sqrt(cos^2 z + 2 h / R)` (Bird and Riordan 1986,
/// Eq. 2-8): 12 on the horizon, where the air's is 38.
pub fn ozone_air_mass(elevation_deg: f64) -> f64 {
    let c = (90.0 - elevation_deg).to_radians().cos();
    let r = OZONE_HEIGHT_KM / EARTH_RADIUS_KM;
    (1.0 + r) / (c * c + 2.0 * r).sqrt()
}

/// The direct beam's transmittance at `nm` with the sun at `elevation_deg`:
/// `exp(-m (tau_R + tau_a) - m_o tau_o)`, Rayleigh and aerosol along the air mass m, ozone along
/// its own air mass m_o (Beer-Bouguer-Lambert). Water vapour and oxygen, which absorb in narrow
/// bands at and beyond 690 nm, are left out.
pub fn sun_transmittance(nm: f64, elevation_deg: f64) -> f64 {
    let m = relative_air_mass(elevation_deg);
    let mo = ozone_air_mass(elevation_deg);
    (-m * (rayleigh_optical_depth(nm) + aerosol_optical_depth(nm)) - mo * ozone_optical_depth(nm))
        .exp()
}

/// Direct sunlight at the ground with the sun at `elevation_deg` (0-90): the extraterrestrial
/// spectrum ([`SOLAR_TABLE`]) times [`sun_transmittance`], at 1 nm over 300-830 nm (the table's
/// own samples) and normalised to 100 at 560 nm.
pub fn sun_at_elevation(elevation_deg: f64) -> Result<Tabulated> {
    sun_through(&extraterrestrial_1nm()?, elevation_deg)
}

/// The extraterrestrial spectrum's samples at 300, 301, ..., 830 nm (the table has each).
fn extraterrestrial_1nm() -> Result<Vec<f64>> {
    let etr = Table::builtin(SOLAR_TABLE)?.single_column()?;
    let (tw, tv) = (etr.wavelengths_nm(), etr.values());
    (300..=830)
        .map(|l| {
            let i = tw.iter().position(|&x| x == f64::from(l)).ok_or_else(|| {
                Error::invalid(format!("the table {SOLAR_TABLE} has no sample at {l} nm"))
            })?;
            Ok(tv[i])
        })
        .collect()
}

/// [`sun_at_elevation`] of the extraterrestrial samples `etr` (300-830 nm, 1 nm).
fn sun_through(etr: &[f64], elevation_deg: f64) -> Result<Tabulated> {
    if !(0.0..=90.0).contains(&elevation_deg) {
        return Err(Error::invalid(format!(
            "the sun's elevation must be 0-90 degrees, not {elevation_deg}"
        )));
    }
    let w: Vec<f64> = (300..=830).map(f64::from).collect();
    let mut v: Vec<f64> = w
        .iter()
        .zip(etr)
        .map(|(&l, e)| e * sun_transmittance(l, elevation_deg))
        .collect();
    let norm = 100.0 / v[260];
    v.iter_mut().for_each(|x| *x *= norm);
    Tabulated::new(w, v)
}

/// The low sun: direct sunlight through a clear atmosphere at the elevation (so the air mass)
/// whose colour has the correlated colour temperature `cct_k` (CIE 1931 observer, 360-830 nm):
///
/// `E(l) = E0(l) exp(-m(h) (tau_R(l) + tau_a(l)) - m_o(h) tau_o(l))`
///
/// with E0 the extraterrestrial solar spectrum (ASTM G173-03, [`SOLAR_TABLE`]), tau_R the
/// Rayleigh optical depth ([`rayleigh_optical_depth`], Hansen and Travis 1974), tau_a the aerosol's
/// ([`aerosol_optical_depth`], Angstrom's law, [`ANGSTROM_ALPHA`] = 1.3, turbidity
/// [`LOW_SUN_TURBIDITY`] = 3 after Preetham et al. 1999), tau_o the ozone's ([`ozone_optical_depth`],
/// Leckner 1978 via Bird and Riordan 1986, [`OZONE_ATM_CM`] = 0.3 atm-cm: the Chappuis band), m the
/// air mass of Kasten and Young (1989) and m_o the ozone layer's (Bird and Riordan 1986). The
/// elevation h is solved by bisection (the CCT rises with it) to 1e-9 degrees. Its reach:
/// [`LOW_SUN_MIN_K`] (the horizon, m = 38, is about 990 K) to 5177 K (the zenith); outside it is
/// an error. Sampled at 1 nm,
/// 300-830 nm, 100 at 560 nm. Its colour lies a little above the Planckian locus (Duv up to
/// +0.004 around 2500-3500 K; a low sun of Mitsuba 3's sunsky, Hosek and Wilkie 2013, is at
/// +0.002 to +0.006).
pub fn low_sun(cct_k: f64) -> Result<Tabulated> {
    let grid = WavelengthGrid::new(360.0, 830.0, 1.0)?;
    let cmfs = Cmfs::new(Observer::Cie1931, &grid)?;
    let etr = extraterrestrial_1nm()?;
    let cct_at = |h: f64| -> Result<(f64, Tabulated)> {
        let t = sun_through(&etr, h)?;
        let s = t.resample(&grid, Interpolation::LIGHT);
        let [x, y, z] = cmfs.integrate(&s, Rule::Riemann)?;
        // No CCT: redder than the 1000 K the search starts at (the sun near the horizon).
        let k = cct(Xyz::new(x, y, z))?.kelvin.unwrap_or(0.0);
        Ok((k, t))
    };
    let (k_lo, t_lo) = cct_at(0.0)?;
    let (k_hi, t_hi) = cct_at(90.0)?;
    if !(cct_k >= k_lo.max(LOW_SUN_MIN_K) && cct_k <= k_hi) {
        return Err(Error::invalid(format!(
            "the low sun reaches from {:.0} K to {k_hi:.0} K (at the zenith), not {cct_k:.0} K",
            k_lo.max(LOW_SUN_MIN_K)
        )));
    }
    if cct_k == k_lo {
        return Ok(t_lo);
    }
    if cct_k == k_hi {
        return Ok(t_hi);
    }
    let (mut lo, mut hi) = (0.0f64, 90.0f64);
    let mut best = t_hi;
    while hi - lo > 1e-9 {
        let h = 0.5 * (lo + hi);
        let (k, t) = cct_at(h)?;
        if (k - cct_k).abs() < 1e-6 {
            return Ok(t);
        }
        if k < cct_k {
            lo = h;
        } else {
            hi = h;
            best = t;
        }
    }
    Ok(best)
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

    #[test]
    fn atmosphere_has_its_closed_forms() {
        // The formulas' values worked by hand: Rayleigh 0.09727 at 550 nm, 0.3601 at 400 nm.
        assert!((rayleigh_optical_depth(550.0) - 0.09727).abs() < 1e-5);
        assert!((rayleigh_optical_depth(400.0) - 0.3601).abs() < 1e-4);
        assert!((aerosol_optical_depth(1000.0) - (0.04608 * 3.0 - 0.04586)).abs() < 1e-15);
        let ratio = aerosol_optical_depth(500.0) / aerosol_optical_depth(1000.0);
        assert!((ratio - 2f64.powf(1.3)).abs() < 1e-12);
        // Between 593 nm (0.119) and 610 nm (0.12), times 0.3 atm-cm; none at 400 or 800 nm.
        let o = 0.3 * (0.119 + 0.001 * 7.0 / 17.0);
        assert!((ozone_optical_depth(600.0) - o).abs() < 1e-15);
        assert_eq!(
            (ozone_optical_depth(400.0), ozone_optical_depth(800.0)),
            (0.0, 0.0)
        );
        // Kasten and Young: 0.99971 at the zenith, 37.92 on the horizon; the ozone layer's air
        // mass is (1 + r) / sqrt(1 + 2 r) at the zenith and sqrt((1 + r)^2 / (2 r)) on the horizon, r = 22 / 6370.
        assert!((relative_air_mass(90.0) - 0.99971).abs() < 1e-5);
        assert!((relative_air_mass(0.0) - 37.92).abs() < 0.01);
        assert!(
            (relative_air_mass(30.0)
                - 1.0 / (60f64.to_radians().cos() + 0.50572 * 36.07995f64.powf(-1.6364)))
            .abs()
                < 1e-12
        );
        let r: f64 = 22.0 / 6370.0;
        assert!((ozone_air_mass(90.0) - (1.0 + r) / (1.0 + 2.0 * r).sqrt()).abs() < 1e-12);
        assert!((ozone_air_mass(0.0) - (1.0 + r) / (2.0 * r).sqrt()).abs() < 1e-9);
        // Beer-Lambert: the transmittance is the product of the three constituents'.
        for (nm, h) in [(450.0, 2.0), (600.0, 5.0), (700.0, 45.0)] {
            let m = relative_air_mass(h);
            let t = (-m * rayleigh_optical_depth(nm)).exp()
                * (-m * aerosol_optical_depth(nm)).exp()
                * (-ozone_air_mass(h) * ozone_optical_depth(nm)).exp();
            assert!(
                (sun_transmittance(nm, h) / t - 1.0).abs() < 1e-12,
                "{nm} {h}"
            );
        }
        // The extraterrestrial table is kept exactly: 1.786 W m^-2 nm^-1 at 560 nm.
        let etr = Table::builtin(SOLAR_TABLE)
            .unwrap()
            .single_column()
            .unwrap();
        let i = etr
            .wavelengths_nm()
            .iter()
            .position(|&w| w == 560.0)
            .unwrap();
        assert_eq!(etr.values()[i], 1.786);
        assert!(sun_at_elevation(-1.0).is_err() && sun_at_elevation(91.0).is_err());
    }

    #[test]
    fn low_sun_hits_the_cct_stays_near_the_locus_and_is_positive() {
        let grid = WavelengthGrid::new(360.0, 830.0, 1.0).unwrap();
        let cmfs = Cmfs::new(Observer::Cie1931, &grid).unwrap();
        let measure = |t: &Tabulated| {
            let s = t.resample(&grid, Interpolation::LIGHT);
            cct(cmfs.light_xyz(&s, Rule::Riemann).unwrap()).unwrap()
        };
        for k in [1000.01, 1603.0, 2000.0, 2700.0, 3500.0, 3999.0, 4500.0] {
            let s = low_sun(k).unwrap();
            let c = measure(&s);
            assert!((c.kelvin.unwrap() - k).abs() < 1e-3, "{k}: {c:?}");
            // Slightly above the Planckian locus, as real low suns are.
            assert!(c.duv > 0.0 && c.duv < 0.004, "{k}: {c:?}");
            assert!(s.values().iter().all(|&v| v > 0.0 && v.is_finite()), "{k}");
            assert_eq!(s.range_nm(), (300.0, 830.0));
        }
        // Redder the lower the sun; out of reach beyond the horizon's and the zenith's CCT.
        // On the horizon the sun is redder than the CCT search's 1000 K: no CCT.
        assert_eq!(measure(&sun_at_elevation(0.0).unwrap()).kelvin, None);
        let c0 = measure(&sun_at_elevation(0.5).unwrap()).kelvin.unwrap();
        let c10 = measure(&sun_at_elevation(10.0).unwrap()).kelvin.unwrap();
        let c90 = measure(&sun_at_elevation(90.0).unwrap()).kelvin.unwrap();
        assert!(
            c0 < 1200.0 && c0 < c10 && c10 < c90 && c90 > 4000.0,
            "{c0} {c10} {c90}"
        );
        assert!(low_sun(900.0).is_err() && low_sun(6000.0).is_err());
    }

    #[test]
    fn natural_light_is_the_low_sun_below_4000_k_and_nearly_continuous() {
        let grid = WavelengthGrid::new(360.0, 830.0, 1.0).unwrap();
        let cmfs = Cmfs::new(Observer::Cie1931, &grid).unwrap();
        let uv = |t: &Tabulated| {
            let s = t.resample(&grid, Interpolation::LIGHT);
            cmfs.light_xyz(&s, Rule::Riemann).unwrap().uv1960()
        };
        assert_eq!(natural(2500.0).unwrap(), low_sun(2500.0).unwrap());
        assert_eq!(natural(999.0).unwrap(), planckian(999.0).unwrap());
        assert!(natural_is_low_sun(1000.0) && !natural_is_low_sun(4000.0));
        // Across 4000 K the colour jumps from the low sun's to CIE daylight's, both a little
        // above the Planckian locus: less than 0.003 in uv.
        let (a, b) = (
            uv(&natural(3999.999).unwrap()),
            uv(&natural(4000.0).unwrap()),
        );
        let d = (a[0] - b[0]).hypot(a[1] - b[1]);
        assert!(d < 0.003, "{d}");
    }
}
