//! A chosen quadrature against every texel of a spectral map, not only the few that stand for
//! it ([`super::texels`]): the texels a fit sees are the most different ones, not those whose
//! errors matter, and an image shows all of them (the ball under the FL2 interior erred 0.519
//! on the image against an estimate of 0.274 from 32 texels).
//!
//! A texel's colour is linear in its coefficients, so each surface the scene shows (the
//! emitter itself, each object's paths at each angle and thickness, as [`super::object_stimuli`]
//! samples them) gives one `K x 3` matrix on the quadrature and one at 1 nm, and every texel's
//! colour is its coefficients times them: tens of thousands of texels cost a few matrix
//! products each. Each texel is seen at its own radiance (the environment's part of the
//! stimulus gains, without the sun).

use super::texels::{self, Candidate};
use super::{object_stimuli, Brightness, Stimuli};
use crate::colorimetry::{delta_e_2000, Lab, Xyz};
use crate::error::Result;
use crate::quadrature::Quadrature;
use crate::render::{Environment, LightSpectra, Scene};
use crate::spectrum::{Interpolation, Rule, WavelengthGrid};
use crate::tradeoff::{sample, Stimulus, Surface};
use rayon::prelude::*;

/// A texel the quadrature errs on.
#[derive(Debug, Clone)]
pub struct Miss {
    pub lighting: usize,
    pub coefficients: Vec<f64>,
    pub error: f64,
    /// The surface it errs most through.
    pub surface: String,
}

/// One surface's colour matrices: per coefficient, XYZ on the quadrature and at 1 nm.
struct Template {
    name: String,
    on_q: Vec<[f64; 3]>,
    at_1nm: Vec<[f64; 3]>,
}

/// The surfaces lighting `li` shows, each for a unit-luminance white texel (the emitter first).
fn surfaces(scene: &Scene, li: usize) -> Result<Vec<Stimulus>> {
    let objects = scene.distinct_objects(li);
    let flat = texels::equal_energy()?;
    let b = Brightness {
        env: 1.0,
        sun: 0.0,
        sun_dir: [0.0, 0.0, 1.0],
    };
    let make = |name: String, f: Vec<crate::tradeoff::Factor>, gain: f64| {
        Stimulus::new(name, flat.clone(), Surface::Product(f)).with_gain(gain.max(1e-3))
    };
    let mut s = Stimuli {
        fit: vec![make("seen directly".into(), Vec::new(), 1.0)],
        held_out: Vec::new(),
    };
    for o in objects {
        object_stimuli(
            o,
            "a texel",
            super::TINTED_SAMPLES_PER_CYCLE,
            &b,
            &make,
            &mut s,
        )?;
    }
    s.fit.append(&mut s.held_out);
    Ok(s.fit)
}

/// XYZ (Y = 100 for a white under an equal-energy light) of `values` on `q`.
fn xyz(q: &Quadrature, values: &[f64]) -> [f64; 3] {
    let y = q.sum()[1];
    q.integrate(values).map(|v| 100.0 * v / y)
}

fn templates(
    surfaces: &[Stimulus],
    basis: &[crate::spectrum::Tabulated],
    q: &Quadrature,
    reference: &Quadrature,
) -> Result<Vec<Template>> {
    // The basis at each quadrature's nodes, once for every surface.
    let at = |q: &Quadrature| -> Vec<Vec<f64>> {
        basis
            .iter()
            .map(|s| sample(s, q.nodes_nm(), Interpolation::LIGHT))
            .collect()
    };
    let (basis_q, basis_1nm) = (at(q), at(reference));
    let one = |q: &Quadrature, basis: &[Vec<f64>], f: &[f64]| -> Vec<[f64; 3]> {
        basis
            .iter()
            .map(|s| {
                let v: Vec<f64> = s.iter().zip(f).map(|(s, f)| s * f).collect();
                xyz(q, &v)
            })
            .collect()
    };
    surfaces
        .iter()
        .map(|t| {
            let fq: Vec<f64> = t
                .surface_at(q.nodes_nm())?
                .iter()
                .map(|v| v * t.gain)
                .collect();
            let fr: Vec<f64> = t
                .surface_at(reference.nodes_nm())?
                .iter()
                .map(|v| v * t.gain)
                .collect();
            Ok(Template {
                name: t.name.clone(),
                on_q: one(q, &basis_q, &fq),
                at_1nm: one(reference, &basis_1nm, &fr),
            })
        })
        .collect()
}

/// The largest error of `q` on texel `c` over the templates, and where.
fn texel_error(c: &Candidate, t: &[Template], white: Xyz) -> (f64, usize) {
    let colour = |m: &[[f64; 3]]| {
        let mut v = [0.0; 3];
        for (k, row) in c.coefficients.iter().zip(m) {
            for (a, r) in v.iter_mut().zip(row) {
                *a += k * r;
            }
        }
        Lab::from_xyz(Xyz(v), white)
    };
    t.iter()
        .enumerate()
        .map(|(i, t)| (delta_e_2000(colour(&t.on_q), colour(&t.at_1nm)), i))
        .fold((0.0, 0), |a, x| if x.0 > a.0 { x } else { a })
}

/// The texels of `scene`'s spectral maps on which `q` errs most, worst first: up to `count`,
/// no two alike, and the largest error over all of them.
pub fn worst_texels(
    scene: &Scene,
    q: &Quadrature,
    white: Xyz,
    count: usize,
) -> Result<(f64, Vec<Miss>)> {
    let grid = WavelengthGrid::new(380.0, 780.0, 1.0)?;
    let reference = Quadrature::uniform(grid, Rule::Simpson, q.observer())?;
    let mut all: Vec<Miss> = Vec::new();
    for (li, l) in scene.lightings.iter().enumerate() {
        let (LightSpectra::Own { spectra, .. }, Environment::Map(maps)) =
            (&l.spectra, &l.environment)
        else {
            continue;
        };
        let shininess = super::shininess_of(&scene.distinct_objects(li));
        let candidates = texels::all_candidates(l, maps, spectra, &shininess)?;
        let t = templates(&surfaces(scene, li)?, spectra, q, &reference)?;
        let errors: Vec<(f64, usize)> = candidates
            .par_iter()
            .map(|c| texel_error(c, &t, white))
            .collect();
        let mut order: Vec<usize> = (0..candidates.len()).collect();
        order.sort_by(|&a, &b| errors[b].0.total_cmp(&errors[a].0));
        let mut kept: Vec<usize> = Vec::new();
        for i in order {
            if kept.len() >= count {
                break;
            }
            if kept
                .iter()
                .any(|&k| texels::alike(&candidates[k], &candidates[i]))
            {
                continue;
            }
            kept.push(i);
        }
        all.extend(kept.into_iter().map(|i| Miss {
            lighting: li,
            coefficients: candidates[i].coefficients.clone(),
            error: errors[i].0,
            surface: t[errors[i].1].name.clone(),
        }));
    }
    all.sort_by(|a, b| b.error.total_cmp(&a.error));
    let max = all.first().map_or(0.0, |m| m.error);
    all.truncate(count);
    Ok((max, all))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::{Observer, RgbSpace};
    use crate::quadrature::estimate::{Estimator, White};
    use crate::render::Preset;
    use crate::spectrum::Tabulated;
    use crate::tradeoff::Factor;

    #[test]
    fn a_texels_error_is_the_estimators_on_that_texel_through_that_surface() {
        // The linear shortcut against the estimator's own sampling of the same stimulus.
        let (l, _) = texels::tests::cap_and_sky();
        let LightSpectra::Own { spectra, .. } = &l.spectra else {
            unreachable!()
        };
        let spectra = spectra.clone();
        let scene = Preset::Ball.scene(8, 8, "D65", Some(l)).unwrap();
        let grid = WavelengthGrid::new(380.0, 780.0, 40.0).unwrap();
        let q = Quadrature::uniform(grid, Rule::Trapezoid, Observer::Cie1931).unwrap();
        let white = RgbSpace::SRGB.xyz_from_rgb([1.0; 3]);
        let (max, misses) = worst_texels(&scene, &q, white, 3).unwrap();
        assert!(!misses.is_empty() && max > 0.0 && max == misses[0].error);
        let wl: Vec<f64> = (380..=780).map(f64::from).collect();
        for m in &misses {
            let emission: Vec<f64> = wl
                .iter()
                .map(|&w| {
                    let at = |s: &Tabulated| sample(s, &[w], Interpolation::LIGHT)[0];
                    m.coefficients
                        .iter()
                        .zip(&spectra)
                        .map(|(c, s)| c * at(s))
                        .sum()
                })
                .collect();
            let t = surfaces(&scene, 0)
                .unwrap()
                .into_iter()
                .find(|t| t.name == m.surface)
                .unwrap();
            let Surface::Product(mut f) = t.surface.clone() else {
                unreachable!()
            };
            f.insert(
                0,
                Factor::Emission(Tabulated::new(wl.clone(), emission).unwrap()),
            );
            let s = Stimulus::new(
                "texel",
                texels::equal_energy().unwrap(),
                Surface::Product(f),
            )
            .with_gain(t.gain);
            let e = Estimator::new(&[s], Observer::Cie1931, 380.0, 780.0, White::Fixed(white))
                .unwrap()
                .errors(&q)
                .unwrap()[0];
            assert!(
                (e - m.error).abs() < 1e-6 * e.max(1.0),
                "{}: {e} vs {}",
                m.surface,
                m.error
            );
        }
    }
}
