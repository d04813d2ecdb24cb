//! What a map's coefficients expand into, for the check on every texel ([`super::coverage`])
//! and for the texels it hands back to the fit.
//!
//! The renderer ([`crate::render::prepare::lighting_spectra`]) takes a map of its own spectra
//! as tabulated, over an equal-energy normaliser; an RGB map's (the paper's) basis
//! `B_j = MCC_j * S` over the main light `S`, and `E` over itself, each normaliser's luminance
//! taken on the quadrature's own nodes. A [`Part`] is one coefficient's spectrum with its
//! normaliser, so that the check integrates each texel as the renderer does.

use super::{texels, Radiated};
use crate::error::Result;
use crate::quadrature::Quadrature;
use crate::render::{LightSpectra, Lighting};
use crate::spectrum::{Interpolation, Tabulated};
use crate::tradeoff::{sample, Factor};

/// One coefficient's spectrum: `reflectance * light`, over the luminance of `normaliser`.
pub(super) struct Part {
    reflectance: Option<Tabulated>,
    light: Tabulated,
    normaliser: Tabulated,
}

impl Part {
    /// The spectrum at `q`'s nodes, over its normaliser's luminance on them (zeros where that
    /// is not positive: the renderer refuses such a quadrature).
    pub(super) fn at(&self, q: &Quadrature) -> Vec<f64> {
        let nodes = q.nodes_nm();
        let y = q.integrate(&sample(&self.normaliser, nodes, Interpolation::LIGHT))[1] / q.sum()[1];
        let light = sample(&self.light, nodes, Interpolation::LIGHT);
        let reflectance = match &self.reflectance {
            Some(r) => sample(r, nodes, Interpolation::SMOOTH),
            None => vec![1.0; nodes.len()],
        };
        let k = if y.is_finite() && y > 0.0 {
            1.0 / y
        } else {
            0.0
        };
        light
            .iter()
            .zip(&reflectance)
            .map(|(l, r)| l * r * k)
            .collect()
    }

    /// [`Part::at`] on `reference`'s nodes, as a table.
    pub(super) fn table(&self, reference: &Quadrature) -> Result<Tabulated> {
        Tabulated::new(reference.nodes_nm().to_vec(), self.at(reference))
    }
}

/// The parts of lighting `l`'s coefficients, in their order.
pub(super) fn parts(l: &Lighting) -> Result<Vec<Part>> {
    Ok(match &l.spectra {
        LightSpectra::Own { spectra, .. } => {
            let flat = texels::equal_energy()?;
            spectra
                .iter()
                .map(|s| Part {
                    reflectance: None,
                    light: s.clone(),
                    normaliser: flat.clone(),
                })
                .collect()
        }
        LightSpectra::Paper {
            light,
            basis_reflectance,
            e_spd,
            ..
        } => {
            let mut out: Vec<Part> = basis_reflectance
                .iter()
                .map(|b| Part {
                    reflectance: Some(b.clone()),
                    light: light.clone(),
                    normaliser: light.clone(),
                })
                .collect();
            out.push(Part {
                reflectance: None,
                light: e_spd.clone(),
                normaliser: e_spd.clone(),
            });
            out
        }
    })
}

/// Texels of an RGB map that a chosen quadrature erred on, for the fit: each the mixture
/// `sum_j c_j MCC_j` of its first three coefficients as a tint of the main light, at unit
/// luminance under it and as bright as the texel. The fourth (`E`, the sun's part) is fitted
/// on its own already; where the two mix, the check on every texel still measures the sum.
pub(super) fn paper_texels(
    l: &Lighting,
    basis_reflectance: &[Tabulated; 3],
    light: &Tabulated,
    added: &[&[f64]],
) -> Result<Vec<Radiated>> {
    let wl = basis_reflectance[0].wavelengths_nm().to_vec();
    let basis: Vec<Vec<f64>> = basis_reflectance
        .iter()
        .map(|b| sample(b, &wl, Interpolation::SMOOTH))
        .collect();
    // Brightness as for a map's own texels ([`texels::Scale`]), relative to the light's.
    let scale = texels::Scale::new()?;
    let s = scale.at(light);
    let luminance = |values: &[f64]| -> Result<f64> {
        let r = Tabulated::new(wl.clone(), values.to_vec())?;
        let r = sample(&r, &scale.wavelengths, Interpolation::SMOOTH);
        let lit: Vec<f64> = s.iter().zip(&r).map(|(s, r)| s * r).collect();
        Ok(scale.luminance(&lit) / scale.luminance(&s))
    };
    let mut out = Vec::new();
    for (k, c) in added.iter().enumerate() {
        let mix: Vec<f64> = (0..wl.len())
            .map(|i| (0..3).map(|j| c[j] * basis[j][i]).sum::<f64>().max(0.0))
            .collect();
        let y = luminance(&mix)?;
        if !(y.is_finite() && y > 0.0) {
            continue;
        }
        let tint = Tabulated::new(wl.clone(), mix.iter().map(|v| v / y).collect())?;
        let label = format!("texel mixture {} (added) of {}", k + 1, l.label);
        out.push(Radiated {
            peak: Some(y),
            ..Radiated::fitted(label, light.clone(), Some(Factor::Reflectance(tint)))
        });
    }
    Ok(out)
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::render::env::{self, CoeffMap};
    use crate::render::prepare::lighting_spectra;
    use crate::render::Environment;
    use crate::spectrum::{Rule, WavelengthGrid};
    use std::sync::Arc;

    /// An RGB map (the paper's basis under A, `E` = A): a saturated red cap over a dim
    /// blue-green sky.
    pub(in crate::render::stimuli) fn paper_map() -> (Lighting, env::Maps) {
        let map = CoeffMap::from_fn(16, |d| {
            if d[1] > 0.9 {
                [8.0, 0.2, 0.0, 0.0]
            } else {
                [0.0, 0.4, 0.3 + 0.4 * d[1].abs() as f32, 0.0]
            }
        });
        let maps = env::Maps {
            light: map.clone(),
            seen: map,
        };
        (paper_lighting("A", maps.clone()), maps)
    }

    /// An RGB map's lighting: the paper's basis under `light` (also `E`), with `maps`.
    pub(in crate::render::stimuli) fn paper_lighting(light: &str, maps: env::Maps) -> Lighting {
        let mut l = Lighting::uniform(light, 1.0, None).unwrap();
        l.environment = Environment::Map(Arc::new(maps));
        l
    }

    #[test]
    fn each_part_is_the_spectrum_the_renderer_expands_with() {
        // The check must integrate a texel as the renderer does, normalisers included: the
        // paper's basis over the main light's luminance on the nodes, E over its own.
        let (paper, _) = paper_map();
        let (own, _) = texels::tests::cap_and_sky();
        let grid = WavelengthGrid::new(400.0, 700.0, 25.0).unwrap();
        let o = crate::colorimetry::Observer::Cie1931;
        let uniform = Quadrature::uniform(grid, Rule::Trapezoid, o).unwrap();
        let uneven = Quadrature::new(
            crate::quadrature::Kind::Scene,
            o,
            vec![447.0, 531.0, 604.0, 612.0],
            vec![
                [0.3, 0.1, 1.5],
                [0.1, 0.9, 0.2],
                [0.9, 0.5, 0.0],
                [0.2, 0.1, 0.0],
            ],
        )
        .unwrap();
        for l in [&paper, &own] {
            let parts = parts(l).unwrap();
            for q in [&uniform, &uneven] {
                let (want, _) = lighting_spectra(l, q).unwrap();
                assert_eq!(parts.len(), l.coefficients());
                for (j, p) in parts.iter().enumerate() {
                    let got = p.at(q);
                    for (g, w) in got.iter().zip(&want[j]) {
                        assert!((g - w).abs() <= 1e-12 * w.abs().max(1.0), "{j}: {g} vs {w}");
                    }
                }
            }
        }
    }

    #[test]
    fn an_added_rgb_texel_is_its_basis_mixture_at_its_own_luminance() {
        let (l, _) = paper_map();
        let LightSpectra::Paper {
            light,
            basis_reflectance,
            ..
        } = &l.spectra
        else {
            unreachable!()
        };
        let c = [0.5, 1.5, 0.25, 3.0];
        let r = paper_texels(&l, basis_reflectance, light, &[&c[..]]).unwrap();
        assert_eq!(r.len(), 1);
        let Some(Factor::Reflectance(tint)) = &r[0].tint else {
            panic!("not a reflectance")
        };
        // The tint is the mixture over its luminance: every value in proportion to it.
        let i = tint
            .wavelengths_nm()
            .iter()
            .position(|&w| w == 550.0)
            .unwrap();
        let mix: f64 = (0..3)
            .map(|j| c[j] * basis_reflectance[j].values()[i])
            .sum();
        let y = r[0].peak.unwrap();
        assert!(
            (tint.values()[i] * y - mix).abs() < 1e-9,
            "{} {mix}",
            tint.values()[i]
        );
        // Its luminance, by the parts at 1 nm: sum_j c_j Y(B_j), without E's share.
        let grid = WavelengthGrid::new(380.0, 780.0, 1.0).unwrap();
        let q1 = Quadrature::uniform(grid, Rule::Simpson, crate::colorimetry::Observer::Cie1931)
            .unwrap();
        let want: f64 = parts(&l).unwrap()[..3]
            .iter()
            .zip(c)
            .map(|(p, c)| c * q1.integrate(&p.at(&q1))[1] / q1.sum()[1])
            .sum();
        assert!((y - want).abs() < 1e-6 * want, "{y} vs {want}");
        assert!(!r[0].held_out);
    }
}
