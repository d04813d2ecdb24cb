//! The faithful method's plan: the light spectra that carry pixels (the scene's lights, or the
//! main light alone), the mixes of them that light the reflectors, and which one each analysis
//! cell takes.

use crate::data;
use crate::envmap::convert::carriers::{Assign, Carrier, CarrierEngine, SunSpec};
use crate::envmap::convert::options::{Lights, SkySpd};
use crate::envmap::convert::pixel_spectra::Colorimeter;
use crate::envmap::convert::pixel_spectra::{
    daylight_coloured, daylight_residual, WhitePremise, DAYLIGHT_RESIDUAL,
};
use crate::envmap::convert::pixels::PixelPlan;
use crate::envmap::convert::planning::Planning;
use crate::envmap::scene::{LightKind, Scene, REFLECTOR};
use crate::error::Result;
use crate::spectrum::{Interpolation, Spectrum, Tabulated};
use std::collections::HashMap;

/// Mixes are quantised to multiples of 1/MIX_STEPS (a carrier per distinct mix).
const MIX_STEPS: f32 = 16.0;

/// The faithful method's carriers and each cell's assignment.
pub(crate) fn carrier_plan(
    p: &Planning,
    notes: &mut Vec<String>,
) -> Result<(PixelPlan, Vec<String>, usize)> {
    let (analysis, opts, grid, sky) = (p.analysis, p.opts, p.grid, p.sky);
    let scene = &analysis.scene;
    let c = Colorimeter::new(grid, opts.observer, opts.rule, p.space)?;
    let mcc = opts
        .basis
        .each_ref()
        .map(|n| data::spectrum(n).map(|s| s.data.resample(&grid, Interpolation::SMOOTH)));
    let [m0, m1, m2] = mcc;
    let mcc = [m0?, m1?, m2?];
    let one = opts.lights == Lights::One;
    let bases = base_carriers(p, one, notes)?;
    let mut carriers: Vec<Carrier> = bases
        .iter()
        .map(|(name, t)| Carrier::new(name, &c.light(name, t)?, &c, &mcc))
        .collect::<Result<_>>()?;
    let base_names: Vec<String> = carriers.iter().map(|k| k.name.clone()).collect();
    let one = one || scene.reflectors.carriers.is_empty();
    let daylight_main = one && is_daylight(&bases[0].1, &c)?;
    let assign = if one {
        one_light_assign(scene, sky == SkySpd::Daylight && daylight_main)
    } else {
        scene_assign(scene, sky == SkySpd::Daylight, &mut carriers, &c, &mcc)?
    };
    if one && sky == SkySpd::Daylight && !daylight_main {
        notes.push(format!(
            "the main light {} is not daylight: sky pixels take its spectrum as any other",
            analysis.light
        ));
    }
    let mixes = carriers.len() - base_names.len();
    let sun_spec = p.sun.as_ref().map_or(SunSpec::None, |s| s.2.clone());
    // The balance on the output grid, as the round trip integrates it.
    let balance = match analysis.white.premise {
        WhitePremise::Light => {
            let t = data::spectrum(&analysis.light)?.data;
            c.rgb(&c.light(&analysis.light, &t)?)?.into()
        }
        WhitePremise::Space => [1.0; 3],
    };
    let engine = CarrierEngine::new(
        &c,
        carriers,
        sky == SkySpd::Daylight,
        &sun_spec,
        analysis.white.premise,
        balance,
    )?;
    let pixels = PixelPlan::Carriers {
        engine: Box::new(engine),
        assign,
    };
    Ok((pixels, base_names, mixes))
}

/// The base carriers: the scene's light spectra, or the main light alone (`--lights one`, or a
/// map where no light was found).
fn base_carriers(
    p: &Planning,
    one: bool,
    notes: &mut Vec<String>,
) -> Result<Vec<(String, Tabulated)>> {
    let (analysis, scene) = (p.analysis, &p.analysis.scene);
    if one || scene.reflectors.carriers.is_empty() {
        if !one {
            notes.push(format!(
                "no light was found in the map: every pixel is carried by {}",
                analysis.light
            ));
        }
        return Ok(vec![(
            analysis.light.clone(),
            data::spectrum(&analysis.light)?.data,
        )]);
    }
    scene
        .reflectors
        .carriers
        .iter()
        .map(|k| {
            let l = scene
                .lights
                .iter()
                .find(|l| l.spd == k.spd)
                .expect("its light");
            Ok((k.spd.clone(), l.spd_choice.table()?))
        })
        .collect()
}

/// Whether a light is daylight: its least-squares fit by S0, S1, S2 leaves at most
/// [`DAYLIGHT_RESIDUAL`] (the CIE D illuminants: ~0; FL2: 0.4; A: 0.1).
fn is_daylight(t: &Tabulated, c: &Colorimeter) -> Result<bool> {
    let grid = *c.grid();
    let [s0, s1, s2] =
        crate::illuminant::daylight_components()?.map(|b| b.resample(&grid, Interpolation::LIGHT));
    Ok(match c.basis3([s0, s1, s2])? {
        Some(d) => {
            daylight_residual(&t.resample(&grid, Interpolation::LIGHT), &d) <= DAYLIGHT_RESIDUAL
        }
        None => false,
    })
}

/// `--lights one`: the main light everywhere, the sun its own, daylight-coloured pixels of the
/// upper hemisphere daylight when the main light is.
fn one_light_assign(scene: &Scene, sky_daylight: bool) -> Vec<Assign> {
    let cells = &scene.cells;
    (0..cells.len())
        .map(|i| {
            let l = scene.label[i];
            Assign {
                carrier: 0,
                sun: l != REFLECTOR && scene.lights[l as usize].kind == LightKind::Sun,
                daylight: sky_daylight && cells.direction(i)[1] > 0.0,
                fixed: false,
            }
        })
        .collect()
}

/// The scene's lights: each light's pixels its own carrier (daylight for the sky and windows,
/// the lamp's SPD for a lamp, at the pixel's luminance where clipped), the reflectors the mix of
/// the lights around them.
fn scene_assign(
    scene: &Scene,
    sky_daylight: bool,
    carriers: &mut Vec<Carrier>,
    c: &Colorimeter,
    mcc: &[Spectrum; 3],
) -> Result<Vec<Assign>> {
    let cells = &scene.cells;
    let daylit = daylight_level(scene);
    let mut mixes: HashMap<Vec<u8>, u16> = HashMap::new();
    let mut out = Vec::with_capacity(cells.len());
    for i in 0..cells.len() {
        let l = scene.label[i];
        if l != REFLECTOR {
            let light = &scene.lights[l as usize];
            out.push(Assign {
                carrier: scene.reflectors.light_carrier[l as usize] as u16,
                sun: light.kind == LightKind::Sun,
                daylight: sky_daylight && matches!(light.kind, LightKind::Sky | LightKind::Window),
                fixed: light.kind == LightKind::Lamp && scene.levels.is_clipped(cells, i),
            });
            continue;
        }
        let mix = scene.reflectors.mix_at(cells.direction(i));
        let q: Vec<u8> = quantise(&mix);
        let carrier = match q.iter().position(|&v| v as f32 == MIX_STEPS) {
            Some(k) => k as u16,
            None => match mixes.get(&q) {
                Some(&k) => k,
                None => {
                    let parts: Vec<(&Carrier, f64)> = q
                        .iter()
                        .enumerate()
                        .filter(|(_, &v)| v > 0)
                        .map(|(k, &v)| (&carriers[k], v as f64 / MIX_STEPS as f64))
                        .collect();
                    let mixed = Carrier::mix(&parts, c, mcc)?;
                    carriers.push(mixed);
                    let k = (carriers.len() - 1) as u16;
                    mixes.insert(q, k);
                    k
                }
            },
        };
        let bright =
            daylit.is_some_and(|lvl| cells.y[i] as f64 >= lvl) && daylight_coloured(&cells.xyz(i));
        out.push(Assign {
            carrier,
            sun: false,
            daylight: sky_daylight && bright,
            fixed: false,
        });
    }
    Ok(out)
}

/// The luminance above which a daylight-coloured reflector is as bright as the sky (the 10th
/// percentile of the sky's and windows' cells), if the scene has daylight.
fn daylight_level(scene: &Scene) -> Option<f64> {
    let mut y: Vec<f32> = scene
        .lights
        .iter()
        .filter(|l| matches!(l.kind, LightKind::Sky | LightKind::Window))
        .flat_map(|l| l.cells.iter().map(|&i| scene.cells.y[i]))
        .collect();
    if y.is_empty() {
        return None;
    }
    y.sort_by(|a, b| a.total_cmp(b));
    Some(y[y.len() / 10] as f64)
}

/// A mix's weights in steps of 1/MIX_STEPS, summing to MIX_STEPS (largest remainders).
fn quantise(mix: &[f32]) -> Vec<u8> {
    let total: f32 = mix.iter().sum::<f32>().max(1e-12);
    let scaled: Vec<f32> = mix.iter().map(|v| v / total * MIX_STEPS).collect();
    let mut q: Vec<u8> = scaled.iter().map(|v| v.floor() as u8).collect();
    let mut rest = MIX_STEPS as i32 - q.iter().map(|&v| v as i32).sum::<i32>();
    let mut order: Vec<usize> = (0..mix.len()).collect();
    order.sort_by(|&a, &b| {
        (scaled[b] - scaled[b].floor()).total_cmp(&(scaled[a] - scaled[a].floor()))
    });
    for &k in order.iter().cycle() {
        if rest <= 0 {
            break;
        }
        q[k] += 1;
        rest -= 1;
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mixes_quantise_to_whole_steps() {
        assert_eq!(quantise(&[1.0, 0.0]), vec![16, 0]);
        assert_eq!(quantise(&[0.5, 0.5]), vec![8, 8]);
        let q = quantise(&[0.33, 0.33, 0.34]);
        assert_eq!(q.iter().map(|&v| v as u32).sum::<u32>(), 16);
        assert_eq!(
            quantise(&[0.0, 0.0]).iter().map(|&v| v as u32).sum::<u32>(),
            16
        );
    }
}
