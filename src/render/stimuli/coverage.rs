//! A chosen quadrature against every texel of a map, not only the few that stand for it (a
//! spectral map's [`super::texels`], an RGB map's mixtures): the texels a fit sees are the most
//! different ones, not those whose errors matter, and an image shows all of them. The ball
//! under the FL2 interior's spectral map erred 0.519 on the image against an estimate of 0.274
//! from 32 texels; under the yard's RGB map at tolerance 0.1, 0.120 against 0.044 from six
//! mixtures.
//!
//! A texel's colour is linear in its coefficients, so each surface the scene shows (the
//! emitter itself, each object's paths at each angle and thickness, as [`super::object_stimuli`]
//! samples them) gives one `K x 3` matrix on the quadrature and one at 1 nm, and every texel's
//! colour is its coefficients times them: tens of thousands of texels cost a few matrix
//! products each. Each texel is seen at its own radiance (the environment's part of the
//! stimulus gains, without the sun), each coefficient's spectrum normalised as the renderer
//! does ([`super::expansion`]).
//!
//! A texel is checked only where the image can show it: through the surfaces whose path reads
//! its map (the seen map seen directly or through a transparent object, the diffuse map by the
//! diffuse paths, an object's specular map by its specular paths, a glossy pigment's pixels by
//! both), and a seen-map texel only if some pixel looks it up ([`super::visible`]). Checked
//! through every surface, the chart under the FL11 interior's RGB map erred 0.694 on a lamp of
//! the background seen through the colour checker's blue, which no pixel shows, and took 13
//! nodes and 65 s where 11 nodes (0.344, image 0.241) and 31 s do.

use super::expansion::{self, Part};
use super::texels::{self, Candidate, Source};
use super::{object_stimuli, Brightness, Path, Sets};
use crate::colorimetry::{delta_e_2000, Lab, Xyz};
use crate::error::Result;
use crate::quadrature::Quadrature;
use crate::render::{Environment, Scene};
use crate::spectrum::{Rule, WavelengthGrid};
use crate::tradeoff::{Factor, Stimulus, Surface};
use rayon::prelude::*;

/// A texel the quadrature errs on.
#[derive(Debug, Clone)]
pub(crate) struct Miss {
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

/// A surface the scene shows, for a unit-luminance white texel, with the path it takes and the
/// shininess of its object (which specular map it reads).
struct Lit {
    stimulus: Stimulus,
    path: Path,
    shininess: f64,
}

impl Lit {
    /// Whether the renderer reads texels of `source` for this surface.
    fn reads(&self, source: Source) -> bool {
        match source {
            Source::Light => false,
            Source::Seen => self.path == Path::Seen,
            Source::Diffuse => matches!(self.path, Path::Diffuse | Path::Glossy),
            Source::Specular(n) => {
                matches!(self.path, Path::Specular | Path::Glossy) && n == self.shininess
            }
        }
    }
}

/// The surfaces lighting `li` shows (the emitter first).
fn surfaces(scene: &Scene, li: usize) -> Result<Vec<Lit>> {
    let flat = texels::equal_energy()?;
    let b = Brightness {
        env: 1.0,
        sun: 0.0,
        sun_dir: [0.0, 0.0, 1.0],
    };
    let make = |shininess: f64| {
        let flat = flat.clone();
        move |name: String, f: Vec<Factor>, gain: f64, path: Path| Lit {
            stimulus: Stimulus::new(name, flat.clone(), Surface::Product(f))
                .with_gain(gain.max(1e-3)),
            path,
            shininess,
        }
    };
    let mut s = Sets {
        fit: vec![make(0.0)(
            "seen directly".into(),
            Vec::new(),
            1.0,
            Path::Seen,
        )],
        held_out: Vec::new(),
    };
    for o in scene.distinct_objects(li) {
        let per_cycle = super::TINTED_SAMPLES_PER_CYCLE;
        object_stimuli(
            o,
            "a texel",
            per_cycle,
            &b,
            &make(o.surface.shininess),
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
    surfaces: &[Lit],
    parts: &[Part],
    q: &Quadrature,
    reference: &Quadrature,
) -> Result<Vec<Template>> {
    // The parts at each quadrature's nodes, once for every surface.
    let at = |q: &Quadrature| -> Vec<Vec<f64>> { parts.iter().map(|p| p.at(q)).collect() };
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
        .map(|s| {
            let t = &s.stimulus;
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

/// The largest error of `q` on texel `c` over the templates `which`, and where.
fn texel_error(c: &Candidate, t: &[Template], which: &[usize], white: Xyz) -> (f64, usize) {
    let colour = |m: &[[f64; 3]]| {
        let mut v = [0.0; 3];
        for (k, row) in c.coefficients.iter().zip(m) {
            for (a, r) in v.iter_mut().zip(row) {
                *a += k * r;
            }
        }
        Lab::from_xyz(Xyz(v), white)
    };
    which
        .iter()
        .map(|&i| (delta_e_2000(colour(&t[i].on_q), colour(&t[i].at_1nm)), i))
        .fold((0.0, 0), |a, x| if x.0 > a.0 { x } else { a })
}

/// The texels of `scene`'s maps on which `q` errs most, worst first: up to `count`, no two
/// alike, and the largest error over all of them. `seen` holds each lighting's seen map as the
/// image can show it ([`Scene::visible_seens`]).
pub(crate) fn worst_texels(
    scene: &Scene,
    seen: &[Option<crate::render::env::CoeffMap>],
    q: &Quadrature,
    white: Xyz,
    count: usize,
) -> Result<(f64, Vec<Miss>)> {
    let grid = WavelengthGrid::new(380.0, 780.0, 1.0)?;
    let reference = Quadrature::uniform(grid, Rule::Simpson, q.observer())?;
    let mut all: Vec<Miss> = Vec::new();
    for (li, l) in scene.lightings.iter().enumerate() {
        let (Environment::Map(maps), Some(seen)) = (&l.environment, &seen[li]) else {
            continue;
        };
        let shown = texels::Shown {
            light: &maps.light,
            seen,
        };
        let parts = expansion::parts(l)?;
        let tables = parts
            .iter()
            .map(|p| p.table(&reference))
            .collect::<Result<Vec<_>>>()?;
        let shininess = super::shininess_of(&scene.distinct_objects(li));
        let candidates = texels::all_candidates(l, &shown, &tables, &shininess)?;
        let lit = surfaces(scene, li)?;
        let t = templates(&lit, &parts, q, &reference)?;
        // Per map, the surfaces that read it.
        let mut reading: Vec<(Source, Vec<usize>)> = Vec::new();
        for c in &candidates {
            if !reading.iter().any(|(s, _)| *s == c.source) {
                let which = (0..lit.len()).filter(|&i| lit[i].reads(c.source));
                reading.push((c.source, which.collect()));
            }
        }
        let which = |s: Source| &reading.iter().find(|(r, _)| *r == s).expect("listed").1;
        let errors: Vec<(f64, usize)> = candidates
            .par_iter()
            .map(|c| texel_error(c, &t, which(c.source), white))
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
    use crate::render::{LightSpectra, Preset};
    use crate::spectrum::Interpolation;
    use crate::spectrum::Tabulated;
    use crate::tradeoff::sample;

    /// Asserts that the estimator errs as the shortcut said on miss `m`'s texel, as `first`
    /// (its radiance) under `light`, through the surface it erred most through.
    fn agrees_with_the_estimator(
        scene: &Scene,
        m: &Miss,
        first: Factor,
        light: Tabulated,
        q: &Quadrature,
        white: Xyz,
    ) {
        let t = surfaces(scene, 0)
            .unwrap()
            .into_iter()
            .find(|t| t.stimulus.name == m.surface)
            .unwrap()
            .stimulus;
        let Surface::Product(mut f) = t.surface.clone() else {
            unreachable!()
        };
        f.insert(0, first);
        let s = Stimulus::new("texel", light, Surface::Product(f)).with_gain(t.gain);
        let e = Estimator::new(&[s], Observer::Cie1931, 380.0, 780.0, White::Fixed(white))
            .unwrap()
            .errors(q)
            .unwrap()[0];
        assert!(
            (e - m.error).abs() < 1e-6 * e.max(1.0),
            "{}: {e} vs {}",
            m.surface,
            m.error
        );
    }

    /// A three-node quadrature, coarse enough to err visibly.
    fn three_nodes() -> Quadrature {
        Quadrature::new(
            crate::quadrature::Kind::Scene,
            Observer::Cie1931,
            vec![445.0, 540.0, 600.0],
            vec![[0.3, 0.1, 1.7], [0.2, 1.0, 0.1], [1.0, 0.4, 0.0]],
        )
        .unwrap()
    }

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
        let (max, misses) = worst_texels(&scene, &scene.visible_seens(), &q, white, 3).unwrap();
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
            let emission = Factor::Emission(Tabulated::new(wl.clone(), emission).unwrap());
            let flat = texels::equal_energy().unwrap();
            agrees_with_the_estimator(&scene, m, emission, flat, &q, white);
        }
    }

    #[test]
    fn an_rgb_texels_error_is_the_estimators_on_its_basis_mixture() {
        // Under an RGB map a texel radiates `sum_j c_j MCC_j` of the main light, over the
        // light's white on the same nodes: the estimator's stimulus of that mixture under the
        // light, through the same surface, must err as the shortcut says.
        let (l, _) = super::expansion::tests::paper_map();
        let LightSpectra::Paper {
            light,
            basis_reflectance,
            ..
        } = l.spectra.clone()
        else {
            unreachable!()
        };
        let scene = Preset::Chart.scene(16, 12, "A", Some(l)).unwrap();
        let q = three_nodes();
        let white = RgbSpace::SRGB.xyz_from_rgb([1.0; 3]);
        let (max, misses) = worst_texels(&scene, &scene.visible_seens(), &q, white, 3).unwrap();
        assert!(!misses.is_empty() && max > 0.0 && max == misses[0].error);
        let wl: Vec<f64> = (380..=780).map(f64::from).collect();
        for m in &misses {
            assert_eq!(m.coefficients.len(), 4);
            let mix: Vec<f64> = wl
                .iter()
                .map(|&w| {
                    (0..3)
                        .map(|j| {
                            m.coefficients[j]
                                * sample(&basis_reflectance[j], &[w], Interpolation::SMOOTH)[0]
                        })
                        .sum()
                })
                .collect();
            let tint = Factor::Reflectance(Tabulated::new(wl.clone(), mix).unwrap());
            agrees_with_the_estimator(&scene, m, tint, light.clone(), &q, white);
        }
    }

    #[test]
    fn a_texel_is_checked_only_through_the_surfaces_that_read_its_map() {
        // A grey light map, and a seen map with a saturated red patch straight behind the
        // chart: the patches read the diffuse map (grey), so the red is checked as seen, not
        // through the colour checker's blue.
        let grey = crate::render::env::CoeffMap::from_fn(16, |_| [0.3, 0.3, 0.3, 0.0]);
        let seen = crate::render::env::CoeffMap::from_fn(16, |d| {
            if d[2] < -0.9 {
                [40.0, -5.0, -3.0, 0.0]
            } else {
                [0.3, 0.3, 0.3, 0.0]
            }
        });
        let maps = crate::render::env::Maps { light: grey, seen };
        let l = super::expansion::tests::paper_lighting("A", maps);
        let scene = Preset::Chart.scene(16, 12, "A", Some(l)).unwrap();
        let q = three_nodes();
        let white = RgbSpace::SRGB.xyz_from_rgb([1.0; 3]);
        let (_, misses) = worst_texels(&scene, &scene.visible_seens(), &q, white, 8).unwrap();
        let red = misses
            .iter()
            .find(|m| m.coefficients[0] > 10.0)
            .expect("the red patch is among the worst");
        assert_eq!(red.surface, "seen directly");
        for m in misses.iter().filter(|m| m.surface != "seen directly") {
            assert!(
                m.coefficients[0] < 1.0,
                "{}: {:?}",
                m.surface,
                m.coefficients
            );
        }
    }
}
