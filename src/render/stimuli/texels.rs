//! What a map of its own spectra (a spectral EXR) radiates, as stimuli.
//!
//! The renderer integrates such a map's spectra as they stand (radiance, over an equal-energy
//! normaliser: [`crate::render::prepare::lighting_spectra`]), so each texel here is an emission
//! over an equal-energy light, not a light of its own: a quadrature's error on a texel's
//! luminance shows, as it does in the image. The texels are taken from every map the renderer
//! samples (the light map, the map seen behind the objects, its diffuse and its specular
//! forms), since filtering mixes the raw texels into spectra none of them has; the most
//! different (farthest-point sampling in the coefficients weighted by their spectra's RMS),
//! each as bright as the brightest texel nearer to it than to any other chosen one.

use super::{dist, farthest_points, Radiated, SAMPLES_PER_CYCLE, TINTED_SAMPLES_PER_CYCLE};
use crate::colorimetry::Observer;
use crate::error::Result;
use crate::quadrature::Quadrature;
use crate::render::env::{self, CoeffMap};
use crate::render::Lighting;
use crate::spectrum::{Interpolation, Rule, Tabulated, WavelengthGrid};
use crate::tradeoff::{sample, Factor};

/// Texels fitted at first.
pub(crate) const FITTED: usize = 16;
/// Texels after those, only checked (the held-out set).
pub(crate) const CHECKED: usize = 16;
/// The most texels fitted: where the fit misses on the checked ones, half of them join the
/// fit ([`crate::render::Scene::choose_quadrature`]), up to this many.
pub(crate) const MAX_FITTED: usize = 32;

/// The equal-energy light a map's own spectra radiate over.
pub(super) fn equal_energy() -> Result<Tabulated> {
    Tabulated::new(vec![380.0, 780.0], vec![1.0, 1.0])
}

/// The 1 nm grid the texels' spectra are tabulated on, and luminance over it relative to an
/// equal-energy spectrum (CIE 1931: a weight for brightness, whatever the render's observer).
pub(super) struct Scale {
    pub(super) wavelengths: Vec<f64>,
    q: Quadrature,
}

impl Scale {
    pub(super) fn new() -> Result<Scale> {
        let grid = WavelengthGrid::new(380.0, 780.0, 1.0)?;
        Ok(Scale {
            wavelengths: grid.wavelengths_nm().collect(),
            q: Quadrature::uniform(grid, Rule::Simpson, Observer::Cie1931)?,
        })
    }
    pub(super) fn at(&self, s: &Tabulated) -> Vec<f64> {
        sample(s, &self.wavelengths, Interpolation::LIGHT)
    }
    pub(super) fn luminance(&self, values: &[f64]) -> f64 {
        self.q.integrate(values)[1] / self.q.sum()[1]
    }
}

/// The sun of a spectral map: its own SPD as it stands, lighting the objects only.
pub(super) fn sun(label: &str, spd: &Tabulated) -> Result<Radiated> {
    Ok(Radiated {
        label: label.to_string(),
        light: equal_energy()?,
        tint: Some(Factor::Emission(spd.clone())),
        peak: Some(0.0),
        per_cycle: SAMPLES_PER_CYCLE,
        held_out: false,
        sun_scale: 1.0,
    })
}

/// One texel a map stands for: its coefficients, luminance, direction for the sampling, and
/// the map it is read from.
pub(super) struct Candidate {
    pub(super) coefficients: Vec<f64>,
    luminance: f64,
    unit: Vec<f64>,
    pub(super) source: Source,
}

/// The map a texel comes from: the light map the others are filtered from (the renderer
/// reads it only through them), the seen map, the diffuse map, or the specular map of a
/// shininess.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Source {
    Light,
    Seen,
    Diffuse,
    Specular(f64),
}

/// Whether two texels radiate nearly the same spectrum (up to brightness).
pub(super) fn alike(a: &Candidate, b: &Candidate) -> bool {
    dist(&a.unit, &b.unit) < 1e-2
}

/// What the basis weighs for the sampling: each spectrum's luminance and RMS.
fn weights(scale: &Scale, spectra: &[Tabulated]) -> (Vec<Vec<f64>>, Vec<f64>, Vec<f64>) {
    let basis: Vec<Vec<f64>> = spectra.iter().map(|s| scale.at(s)).collect();
    let luminance: Vec<f64> = basis.iter().map(|b| scale.luminance(b)).collect();
    let rms: Vec<f64> = basis
        .iter()
        .map(|b| (b.iter().map(|v| v * v).sum::<f64>() / b.len() as f64).sqrt())
        .collect();
    (basis, luminance, rms)
}

/// Every texel of the maps the renderer samples for `l` (see [`candidates`]).
pub(super) fn all_candidates(
    l: &Lighting,
    maps: &Shown,
    spectra: &[Tabulated],
    shininess: &[f64],
) -> Result<Vec<Candidate>> {
    let (_, luminance, rms) = weights(&Scale::new()?, spectra);
    Ok(candidates(l, maps, &luminance, &rms, shininess))
}

/// A lighting's maps as the image can show them: the light map, and the seen map with the
/// texels no pixel shows set to zero ([`crate::render::Scene::visible_seen`]).
pub(super) struct Shown<'a> {
    pub(super) light: &'a CoeffMap,
    pub(super) seen: &'a CoeffMap,
}

/// Every texel of the maps the renderer samples for `l`, with a positive luminance.
fn candidates(
    l: &Lighting,
    maps: &Shown,
    luminance: &[f64],
    rms: &[f64],
    shininess: &[f64],
) -> Vec<Candidate> {
    let f = env::prefilter(&l.environment, shininess);
    let mut all: Vec<(&CoeffMap, Source)> = vec![
        (maps.light, Source::Light),
        (maps.seen, Source::Seen),
        (&f.diffuse, Source::Diffuse),
    ];
    all.extend(f.specular.iter().map(|(n, m)| (m, Source::Specular(*n))));
    let k = luminance.len();
    let mut out = Vec::new();
    for (m, source) in all {
        for i in 0..m.width * m.height {
            let c: Vec<f64> = m.texel(i).take(k).map(|v| v as f64).collect();
            let y: f64 = c.iter().zip(luminance).map(|(c, y)| c * y).sum();
            let w: Vec<f64> = c.iter().zip(rms).map(|(c, r)| c * r).collect();
            let n = w.iter().map(|v| v * v).sum::<f64>().sqrt();
            if y > 0.0 && y.is_finite() && n > 0.0 {
                out.push(Candidate {
                    coefficients: c,
                    luminance: y,
                    unit: w.iter().map(|v| v / n).collect(),
                    source,
                });
            }
        }
    }
    out
}

/// Farthest-point sampling of `count` candidates from the brightest, and each one's cell peak
/// (the largest luminance among the candidates nearest to it).
fn farthest(c: &[Candidate], count: usize) -> Vec<(usize, f64)> {
    let Some(first) = (0..c.len()).max_by(|&a, &b| c[a].luminance.total_cmp(&c[b].luminance))
    else {
        return Vec::new();
    };
    let units: Vec<&[f64]> = c.iter().map(|x| x.unit.as_slice()).collect();
    let (chosen, cell) = farthest_points(&units, first, count);
    let mut peak: Vec<f64> = chosen.iter().map(|&i| c[i].luminance).collect();
    for (x, &k) in c.iter().zip(&cell) {
        peak[k] = peak[k].max(x.luminance);
    }
    chosen.into_iter().zip(peak).collect()
}

/// The texels standing for map `maps` of `l`'s own `spectra` (see the module docs): the first
/// `fitted` fitted, the next [`CHECKED`] held out.
pub(super) fn texels(
    l: &Lighting,
    maps: &Shown,
    spectra: &[Tabulated],
    sun_spd: &Tabulated,
    shininess: &[f64],
    fitted: usize,
    added: &[&[f64]],
) -> Result<Vec<Radiated>> {
    let scale = Scale::new()?;
    let (basis, luminance, rms) = weights(&scale, spectra);
    let sun_scale = scale.luminance(&scale.at(sun_spd)).max(0.0);
    let mut c = candidates(l, maps, &luminance, &rms, shininess);
    let mut chosen = farthest(&c, fitted + CHECKED);
    let farthest_count = chosen.len();
    // Texels added because a chosen quadrature erred most on them: fitted, at their own
    // luminance, after the farthest ones.
    for a in added {
        let y: f64 = a.iter().zip(&luminance).map(|(c, y)| c * y).sum();
        if y > 0.0 && y.is_finite() {
            chosen.push((c.len(), y));
            c.push(Candidate {
                coefficients: a.to_vec(),
                luminance: y,
                unit: Vec::new(),
                source: Source::Light,
            });
        }
    }
    let mut out = Vec::new();
    for (n, (i, peak)) in chosen.into_iter().enumerate() {
        let t = &c[i];
        let values: Vec<f64> = (0..scale.wavelengths.len())
            .map(|w| {
                let v: f64 = (0..basis.len())
                    .map(|j| t.coefficients[j] * basis[j][w])
                    .sum();
                v / t.luminance
            })
            .collect();
        let held_out = n >= fitted && n < farthest_count;
        out.push(Radiated {
            label: format!(
                "texel spectrum {}{} of {}",
                n + 1,
                if n >= farthest_count { " (added)" } else { "" },
                l.label
            ),
            light: equal_energy()?,
            tint: Some(Factor::Emission(Tabulated::new(
                scale.wavelengths.clone(),
                values,
            )?)),
            peak: Some(peak),
            per_cycle: if held_out {
                TINTED_SAMPLES_PER_CYCLE
            } else {
                SAMPLES_PER_CYCLE
            },
            held_out,
            sun_scale,
        });
    }
    Ok(out)
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::render::{Environment, LightSpectra};
    use std::sync::Arc;

    /// A bright white cap (10 whites of a flat spectrum) over a dim sky of a blue ramp.
    pub(in crate::render::stimuli) fn cap_and_sky() -> (Lighting, env::Maps) {
        let map = CoeffMap::from_fn(16, |d| {
            if d[1] > 0.95 {
                [10.0, 0.0, 0.0, 0.0]
            } else {
                [0.0, 0.5 + 0.5 * d[1].abs() as f32, 0.0, 0.0]
            }
        });
        let flat = Tabulated::new(vec![380.0, 780.0], vec![1.0, 1.0]).unwrap();
        let blue = Tabulated::new(vec![380.0, 780.0], vec![2.0, 0.1]).unwrap();
        let maps = env::Maps {
            light: map.clone(),
            seen: map,
        };
        let l = Lighting {
            label: "test".into(),
            spectra: LightSpectra::Own {
                spectra: vec![flat.clone(), blue],
                sun_spd: flat,
                sun_label: "none".into(),
            },
            environment: Environment::Map(Arc::new(maps.clone())),
            sun: None,
        };
        (l, maps)
    }

    #[test]
    fn texels_radiate_at_their_own_luminance_over_an_equal_energy_light() {
        let (l, maps) = cap_and_sky();
        let LightSpectra::Own {
            spectra, sun_spd, ..
        } = &l.spectra
        else {
            unreachable!()
        };
        let shown = Shown {
            light: &maps.light,
            seen: &maps.seen,
        };
        let r = texels(&l, &shown, spectra, sun_spd, &[200.0], 1, &[]).unwrap();
        assert!(r.len() >= 2, "{}", r.len());
        let scale = Scale::new().unwrap();
        for t in &r {
            assert_eq!(t.light.values(), &[1.0, 1.0]);
            let Some(Factor::Emission(e)) = &t.tint else {
                panic!("{}: not an emission", t.label)
            };
            let y = scale.luminance(&scale.at(e));
            assert!((y - 1.0).abs() < 1e-9, "{}: luminance {y}", t.label);
        }
        // The brightest first, as bright as the cap; the rest held out.
        assert!((r[0].peak.unwrap() - 10.0).abs() < 1e-3, "{:?}", r[0].peak);
        assert!(!r[0].held_out && r[1..].iter().all(|t| t.held_out));
        // The sky's texels: no brighter than its brightest raw texel.
        let sky_y = scale.luminance(&scale.at(&spectra[1]));
        assert!(
            r[1].peak.unwrap() <= sky_y + 1e-6,
            "{:?} {sky_y}",
            r[1].peak
        );
    }
}
