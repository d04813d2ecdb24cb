//! The conversion's middle stages: analyse the scene (its lights, the white premise, the main
//! light), then plan every decision of the write as a value that can be printed.

use crate::colorimetry::{Observer, RgbSpace};
use crate::data;
use crate::envmap::convert::carriers::{Assign, Carrier, CarrierEngine, Colorimeter, SunSpec};
use crate::envmap::convert::pixel_spectra::{
    daylight_coloured, daylight_residual, Engine, Model, SunSource, WhitePremise, DAYLIGHT_RESIDUAL,
};
use crate::envmap::convert::read::Input;
use crate::envmap::convert::{
    ConvertOptions, LightSpec, Lights, Method, OutputFormat, SkySpd, SunSpd, WhiteSpec,
};
use crate::envmap::scene::main_light::{self, LightChoice, WhiteChoice};
use crate::envmap::scene::{self, LightKind, Scene, SceneSettings, REFLECTOR};
use crate::error::Result;
use crate::fit::{self, Fit, FitInput};
use crate::spectrum::{Interpolation, Rule, Spectrum, Tabulated, WavelengthGrid};
use crate::tradeoff::{choose_grid, colorchecker_under, GridChoice};
use std::collections::HashMap;

/// What the scene is, and the premises taken of it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Analysis {
    pub scene: Scene,
    /// The one main light: the spectrum of every non-sun pixel with `--lights one` and in the
    /// paper's modes; with the scene's lights, the dominant one (the fit's light).
    pub light: String,
    /// How `--light auto` chose the main light (one light, or the paper's modes).
    pub light_choice: Option<LightChoice>,
    pub white: WhiteChoice,
    pub notes: Vec<String>,
}

/// Analyses the map: its lights, then what RGB (1,1,1) is, then (for one light) the main light.
/// Under the light premise the scene is analysed again in true colours.
pub fn analyse(input: &mut Input, opts: &ConvertOptions) -> Result<Analysis> {
    let settings = SceneSettings {
        sun: opts.sun,
        lamps: match &opts.light {
            LightSpec::Named(n) => Some(n.clone()),
            LightSpec::Auto => None,
        },
        reflectors: opts.reflectors,
        ..SceneSettings::default()
    };
    let mut scene = scene::analyse(&input.map, &opts.space, [1.0; 3], &settings)?;
    let one = opts.method == Method::Basis || opts.lights == Lights::One;
    let (light, light_choice) = match (&opts.light, one) {
        (LightSpec::Named(n), _) => (n.clone(), None),
        (LightSpec::Auto, true) => {
            let sun = scene.sun().map(|s| (s.energy_share, s.elevation_deg));
            let c = main_light::choose(&input.map, sun, &opts.space)?;
            (c.light.clone(), Some(c))
        }
        (LightSpec::Auto, false) => (dominant_light(&scene), None),
    };
    let white = white_premise(input, opts, &light, one)?;
    let mut notes = Vec::new();
    if white.premise == WhitePremise::Space {
        notes.extend(input.keep_out_of_gamut());
    } else {
        let balance = light_rgb(&light, opts.space)?;
        scene = scene::analyse(&input.map, &opts.space, balance, &settings)?;
    }
    Ok(Analysis {
        scene,
        light,
        light_choice,
        white,
        notes,
    })
}

/// The name of the light holding the most energy (D65 when the scene has none).
fn dominant_light(scene: &Scene) -> String {
    scene
        .lights
        .iter()
        .max_by(|a, b| a.energy_share.total_cmp(&b.energy_share))
        .map_or("D65".into(), |l| l.spd_choice.fit_name())
}

fn white_premise(
    input: &Input,
    opts: &ConvertOptions,
    light: &str,
    one: bool,
) -> Result<WhiteChoice> {
    let spec = opts.white.unwrap_or(match (opts.method, &opts.light) {
        (Method::Faithful, _) | (Method::Basis, LightSpec::Auto) => WhiteSpec::Auto,
        (Method::Basis, LightSpec::Named(_)) => WhiteSpec::Light,
    });
    Ok(match spec {
        WhiteSpec::Light => WhiteChoice {
            premise: WhitePremise::Light,
            reason: format!(
                "--white light: RGB (1,1,1) is the main light {light} (the paper's premise)"
            ),
        },
        WhiteSpec::Space => WhiteChoice {
            premise: WhitePremise::Space,
            reason: format!(
                "--white space: RGB (1,1,1) is the space's white, {}",
                opts.space.white_name()
            ),
        },
        WhiteSpec::Auto if !one && opts.light == LightSpec::Auto => WhiteChoice {
            premise: WhitePremise::Space,
            reason: "the scene's lights keep their own colours; say --white light --light NAME \
                     for a map white-balanced to its lamps"
                .into(),
        },
        WhiteSpec::Auto => main_light::choose_white(&input.map, &opts.space, light)?,
    })
}

/// The linear RGB (true, Y = 1) of a light, on a 1 nm grid.
fn light_rgb(name: &str, space: RgbSpace) -> Result<[f64; 3]> {
    let grid = WavelengthGrid::visible_1nm();
    let c = Colorimeter::new(grid, Observer::Cie1931, Rule::Riemann, space)?;
    let s = c.light(name, &data::spectrum(name)?.data)?;
    Ok(c.rgb(&s)?.into())
}

/// Every decision of the write.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Plan {
    pub method: Method,
    pub lights: Lights,
    pub sky: SkySpd,
    /// The sun's spectrum, if a sun was found.
    pub sun_spd: Option<String>,
    pub grid: WavelengthGrid,
    pub grid_choice: Option<GridChoice>,
    pub format: OutputFormat,
    /// The distinct light spectra pixels are carried by (faithful method), and how many mixes
    /// of them the reflectors take.
    pub carriers: Vec<String>,
    pub mixes: usize,
    pub notes: Vec<String>,
    #[serde(skip)]
    pub fit: Fit,
    #[serde(skip)]
    pub pixels: PixelPlan,
}

/// How pixels become spectra.
#[derive(Debug, Clone)]
pub enum PixelPlan {
    /// The paper's modes: one fit; per analysis cell, whether it is the sun's.
    Basis { engine: Box<Engine>, sun: Vec<bool> },
    /// The faithful method: carriers, and per analysis cell what it is.
    Carriers {
        engine: Box<CarrierEngine>,
        assign: Vec<Assign>,
    },
}

/// Plans the write of `input` as analysed.
pub fn plan(analysis: &Analysis, opts: &ConvertOptions) -> Result<Plan> {
    let mut notes = analysis.notes.clone();
    let scene = &analysis.scene;
    let sun_choice = opts.sun_spd.clone().unwrap_or(match opts.method {
        Method::Faithful => SunSpd::Daylight,
        Method::Basis => SunSpd::D65,
    });
    let sun = sun_table(scene, &sun_choice, analysis)?;
    let grid_choice = grid_for(analysis, opts, sun.as_ref().map(|s| &s.1))?;
    let grid = grid_choice.as_ref().map_or(opts.grid, |c| c.chosen);
    let fit = match &opts.fit {
        Some(f) => f.clone(),
        None => fit::fit(
            &FitInput::from_names(
                &analysis.light,
                opts.basis.each_ref().map(String::as_str),
                &grid,
                opts.observer,
                opts.rule,
                opts.space,
            )?,
            opts.mode,
        )?,
    };
    // The basis format holds the K spectra of whatever the method writes.
    let method = opts.method;
    let sky = opts.sky.unwrap_or(match method {
        Method::Faithful => SkySpd::Daylight,
        Method::Basis => SkySpd::Light,
    });
    let premise = analysis.white.premise;
    let (pixels, carriers, mixes) = match method {
        Method::Basis => {
            let engine = basis_engine(&fit, grid, opts, &sun, premise, sky, &mut notes)?;
            let sun_cells = scene
                .label
                .iter()
                .map(|&l| l != REFLECTOR && scene.lights[l as usize].kind == LightKind::Sun)
                .collect();
            let pixels = PixelPlan::Basis {
                engine: Box::new(engine),
                sun: sun_cells,
            };
            (pixels, vec![fit.light.clone()], 0)
        }
        Method::Faithful => carrier_plan(analysis, opts, grid, &sun, sky, &mut notes)?,
    };
    Ok(Plan {
        method,
        lights: opts.lights,
        sky,
        sun_spd: sun.map(|s| s.0),
        grid,
        grid_choice,
        format: opts.format,
        carriers,
        mixes,
        notes,
        fit,
        pixels,
    })
}

/// The sun's SPD (label, table, and how the engine makes it), if the scene has a sun.
type SunTable = (String, Tabulated, SunSpec);

fn sun_table(scene: &Scene, choice: &SunSpd, analysis: &Analysis) -> Result<Option<SunTable>> {
    let Some(s) = scene.sun() else {
        return Ok(None);
    };
    let k = s.cct_k.unwrap_or(6504.0);
    Ok(Some(match choice {
        SunSpd::D65 => {
            let t = data::spectrum("D65")?.data;
            ("D65".into(), t.clone(), SunSpec::Spd(t))
        }
        SunSpd::Daylight => {
            let rgb = analysis
                .scene
                .cells
                .to_xyz
                .try_inverse()
                .unwrap_or_default()
                * s.colour;
            (
                format!("CIE daylight family, the sun's colour (CCT {k:.0} K)"),
                crate::illuminant::natural(k)?,
                SunSpec::Colour {
                    rgb: rgb.into(),
                    cct_k: k,
                },
            )
        }
        SunSpd::Match => {
            let label = if k < crate::illuminant::DAYLIGHT_RANGE_K.0 {
                format!("Planckian {k:.0} K")
            } else {
                format!(
                    "CIE daylight {:.0} K",
                    k.min(crate::illuminant::DAYLIGHT_RANGE_K.1)
                )
            };
            let t = crate::illuminant::natural(k)?;
            (label, t.clone(), SunSpec::Spd(t))
        }
        SunSpd::Light(name) => {
            let t = data::spectrum(name)?.data;
            (name.clone(), t.clone(), SunSpec::Spd(t))
        }
    }))
}

/// The grid: as given, or the coarsest step within its range that keeps the ColorChecker under
/// each light of the scene (and the sun's SPD) within --tolerance.
fn grid_for(
    analysis: &Analysis,
    opts: &ConvertOptions,
    sun: Option<&Tabulated>,
) -> Result<Option<GridChoice>> {
    let Some(tolerance) = opts.tolerance else {
        return Ok(None);
    };
    let mut stimuli = Vec::new();
    let mut names = vec![analysis.light.clone()];
    if opts.method == Method::Faithful && opts.lights == Lights::All {
        for l in &analysis.scene.lights {
            if l.kind != LightKind::Sun && !names.contains(&l.spd) {
                names.push(l.spd.clone());
            }
        }
    }
    for (k, name) in names.iter().enumerate() {
        let t = if k == 0 {
            data::spectrum(name)?.data
        } else {
            let l = analysis.scene.lights.iter().find(|l| &l.spd == name);
            l.expect("a light of the scene").spd_choice.table()?
        };
        stimuli.extend(colorchecker_under(name, &t)?);
    }
    if let Some(spd) = sun {
        stimuli.extend(colorchecker_under("sun", spd)?);
    }
    let (start, end) = (opts.grid.start_nm(), opts.grid.end_nm());
    Ok(Some(choose_grid(
        &stimuli,
        opts.observer,
        start,
        end,
        opts.rule,
        tolerance,
    )?))
}

#[allow(clippy::too_many_arguments)]
fn basis_engine(
    fit: &Fit,
    grid: WavelengthGrid,
    opts: &ConvertOptions,
    sun: &Option<SunTable>,
    premise: WhitePremise,
    sky: SkySpd,
    notes: &mut Vec<String>,
) -> Result<Engine> {
    let model = Model {
        white: premise,
        sky_daylight: sky == SkySpd::Daylight,
        smooth: false,
    };
    let balance = light_rgb(&fit.light, opts.space)?;
    let premise_rgb;
    let source = match sun {
        None => SunSource::None,
        Some((_, _, SunSpec::Colour { rgb, .. })) => {
            // The engine takes the sun's colour as the input has it.
            premise_rgb = match premise {
                WhitePremise::Light => std::array::from_fn(|k| rgb[k] / balance[k]),
                WhitePremise::Space => *rgb,
            };
            SunSource::DaylightFit(premise_rgb)
        }
        Some((_, t, _)) => SunSource::Spd(t),
    };
    let engine = Engine::with_model(fit, grid, opts.rule, source, model)?;
    if model.sky_daylight && !engine.sky_daylight_active() {
        notes.push(format!(
            "the main light {} is not daylight: sky pixels take its basis as any other",
            fit.light
        ));
    }
    Ok(engine)
}

/// Mixes are quantised to multiples of 1/MIX_STEPS (a carrier per distinct mix).
const MIX_STEPS: f32 = 16.0;

/// The faithful method's carriers and each cell's assignment.
fn carrier_plan(
    analysis: &Analysis,
    opts: &ConvertOptions,
    grid: WavelengthGrid,
    sun: &Option<SunTable>,
    sky: SkySpd,
    notes: &mut Vec<String>,
) -> Result<(PixelPlan, Vec<String>, usize)> {
    let scene = &analysis.scene;
    let c = Colorimeter::new(grid, opts.observer, opts.rule, opts.space)?;
    let mcc = opts
        .basis
        .each_ref()
        .map(|n| data::spectrum(n).map(|s| s.data.resample(&grid, Interpolation::SMOOTH)));
    let [m0, m1, m2] = mcc;
    let mcc = [m0?, m1?, m2?];
    let one = opts.lights == Lights::One;
    // The base carriers: the scene's light spectra, or the main light alone.
    let bases: Vec<(String, Tabulated)> = if one || scene.reflectors.carriers.is_empty() {
        if !one {
            notes.push(format!(
                "no light was found in the map: every pixel is carried by {}",
                analysis.light
            ));
        }
        vec![(
            analysis.light.clone(),
            data::spectrum(&analysis.light)?.data,
        )]
    } else {
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
            .collect::<Result<_>>()?
    };
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
    let sun_spec = sun.as_ref().map_or(SunSpec::None, |s| s.2.clone());
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
