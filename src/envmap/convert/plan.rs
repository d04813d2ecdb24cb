//! The conversion's third stage: every decision of the write as a value that can be printed
//! (`inspect --json` prints it whole): the sun's SPD, the wavelength grid, the fit, how pixels
//! become spectra ([`PixelPlan`]), what the white premise does to out-of-gamut colours, and the
//! file ([`FilePlan`]).

use crate::data;
use crate::envmap::convert::analyse::{light_rgb, Analysis};
use crate::envmap::convert::carrier_plan::carrier_plan;
use crate::envmap::convert::carriers::SunSpec;
use crate::envmap::convert::file_plan::{plan_file, FilePlan};
use crate::envmap::convert::measure::{self, Measured, Tally};
use crate::envmap::convert::options::{
    ConvertOptions, Lights, Method, OutputFormat, SkySpd, SunSpd,
};
use crate::envmap::convert::pixel_spectra::{Engine, Model, SunSource, WhitePremise};
use crate::envmap::convert::pixels::{PixelPlan, Pixels};
use crate::envmap::convert::planning::{Planning, SpectraPlan, SunTable};
use crate::envmap::convert::read::Input;
use crate::envmap::files::Precision;
use crate::envmap::scene::{LightKind, Scene, REFLECTOR};
use crate::error::Result;
use crate::fit::{self, Fit, FitInput};
use crate::spectrum::{Tabulated, WavelengthGrid};
use crate::tradeoff::{choose_grid, colorchecker_under, GridChoice};
use std::path::Path;

/// Every decision of the write.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Plan {
    /// How pixels become spectra.
    pub method: Method,
    /// The scene's lights, or the paper's one main light.
    pub lights: Lights,
    /// What daylight-coloured sky pixels take.
    pub sky: SkySpd,
    /// The sun's spectrum, if a sun was found.
    pub sun_spd: Option<String>,
    /// The output's wavelengths (nm).
    pub grid: WavelengthGrid,
    /// What `--tolerance` chose (None: the grid was given).
    pub grid_choice: Option<GridChoice>,
    /// Spectral channels, or the basis form.
    pub format: OutputFormat,
    /// The distinct light spectra pixels are carried by (the faithful method; the fit's light
    /// in the paper's modes).
    pub carriers: Vec<String>,
    /// How many mixes of the carriers light the reflectors.
    pub mixes: usize,
    /// What the conversion could not do as asked, in words.
    pub notes: Vec<String>,
    /// The file: its form, precision and EV, compression, attributes and path.
    pub file: FilePlan,
    /// The basis fit: the paper's weights and matrix for the main light.
    pub fit: Fit,
    /// How each pixel becomes a spectrum.
    #[serde(skip)]
    pub pixels: PixelPlan,
    /// The map as it is written (out-of-gamut colours kept under the space premise) and what
    /// reading it found.
    #[serde(skip)]
    pub input: Input,
    /// What measuring every pixel's spectrum counted, where the half-float EV scale needed the
    /// measure (the write then counts nothing itself).
    #[serde(skip)]
    pub(crate) measured: Option<Tally>,
    /// Seconds this stage took (the half-float EV's measure of every spectrum included; in a
    /// conversion's report, not in `inspect`'s, which stays the same from run to run).
    #[serde(skip)]
    pub seconds: f64,
}

/// Every pixel's spectrum measured, where a spectral file in half floats needs its EV scale
/// sized by them (None otherwise: the write measures as it goes).
fn measure_for_ev(
    input: &Input,
    analysis: &Analysis,
    s: &SpectraPlan,
    opts: &ConvertOptions,
) -> Option<Measured> {
    let half = opts.format == OutputFormat::Spectral && opts.precision != Precision::Float;
    half.then(|| {
        let px = Pixels {
            map: &input.map,
            cells: &analysis.scene.cells,
            plan: &s.pixels,
            mode: s.fit.mode,
        };
        measure::measure(&px, s.grid.len())
    })
}

/// Plans the write of `input` as analysed, to `output` (None: nothing will be written). The plan
/// keeps the input: the map as it will be written.
pub(crate) fn plan(
    mut input: Input,
    analysis: &Analysis,
    opts: &ConvertOptions,
    output: Option<&Path>,
) -> Result<Plan> {
    let t0 = std::time::Instant::now();
    let mut notes = Vec::new();
    if analysis.white.premise == WhitePremise::Space {
        notes.extend(input.keep_out_of_gamut());
    }
    let s = plan_spectra(&input, analysis, opts, &mut notes)?;
    notes.extend(input.space.note.clone());
    let measured = measure_for_ev(&input, analysis, &s, opts);
    let file = plan_file(analysis, &s, opts, measured.as_ref(), output, &mut notes);
    Ok(Plan {
        method: s.method,
        lights: opts.lights,
        sky: s.sky,
        sun_spd: s.sun_spd,
        grid: s.grid,
        grid_choice: s.grid_choice,
        format: opts.format,
        carriers: s.carriers,
        mixes: s.mixes,
        notes,
        file,
        fit: s.fit,
        pixels: s.pixels,
        input,
        measured: measured.map(|m| m.tally),
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// The sun's SPD, the grid, the fit and how pixels become spectra.
fn plan_spectra(
    input: &Input,
    analysis: &Analysis,
    opts: &ConvertOptions,
    notes: &mut Vec<String>,
) -> Result<SpectraPlan> {
    let space = input.space.space;
    let sun_choice = opts.sun_spd.clone().unwrap_or(match opts.method {
        Method::Faithful => SunSpd::Daylight,
        Method::Basis => SunSpd::D65,
    });
    let sun = sun_table(&analysis.scene, &sun_choice, analysis)?;
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
                space,
            )?,
            opts.mode,
        )?,
    };
    let method = opts.method;
    let sky = opts.sky.unwrap_or(match method {
        Method::Faithful => SkySpd::Daylight,
        Method::Basis => SkySpd::Light,
    });
    let p = Planning {
        analysis,
        opts,
        space,
        sun,
        grid,
        sky,
    };
    let (pixels, carriers, mixes) = match method {
        Method::Basis => basis_plan(&p, &fit, notes)?,
        Method::Faithful => carrier_plan(&p, notes)?,
    };
    Ok(SpectraPlan {
        method,
        sky,
        sun_spd: p.sun.map(|s| s.0),
        grid,
        grid_choice,
        fit,
        pixels,
        carriers,
        mixes,
    })
}

/// The paper's modes: one fit, and which analysis cells are the sun's.
fn basis_plan(
    p: &Planning,
    fit: &Fit,
    notes: &mut Vec<String>,
) -> Result<(PixelPlan, Vec<String>, usize)> {
    let scene = &p.analysis.scene;
    let engine = basis_engine(p, fit, notes)?;
    // None is the sun's where the scene has none (nor a cell to keep).
    let sun_cells = match scene.sun() {
        Some(_) => scene
            .label
            .iter()
            .map(|&l| l != REFLECTOR && scene.lights[l as usize].kind == LightKind::Sun)
            .collect(),
        None => Vec::new(),
    };
    let pixels = PixelPlan::Basis {
        engine: Box::new(engine),
        sun: sun_cells,
    };
    Ok((pixels, vec![fit.light.clone()], 0))
}

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
            let label = if crate::illuminant::natural_is_low_sun(k) {
                format!(
                    "CIE daylight family, the sun's colour (CCT {k:.0} K); where daylight goes \
                     negative, a black body of {k:.0} K modulated to it"
                )
            } else {
                format!("CIE daylight family, the sun's colour (CCT {k:.0} K)")
            };
            (
                label,
                crate::illuminant::natural(k)?,
                SunSpec::Colour {
                    rgb: rgb.into(),
                    cct_k: k,
                },
            )
        }
        SunSpd::Match => {
            let label = if crate::illuminant::natural_is_low_sun(k) {
                format!("low sun {k:.0} K")
            } else if k < crate::illuminant::DAYLIGHT_RANGE_K.0 {
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

/// The paper's modes' engine: the fit's basis under the white premise, the sun's SPD, and the
/// sky's daylight where the main light is daylight.
fn basis_engine(p: &Planning, fit: &Fit, notes: &mut Vec<String>) -> Result<Engine> {
    let premise = p.analysis.white.premise;
    let sky = p.sky;
    let model = Model {
        white: premise,
        sky_daylight: sky == SkySpd::Daylight,
        smooth: false,
    };
    let balance = light_rgb(&fit.light, p.space)?;
    let premise_rgb;
    let source = match &p.sun {
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
    let engine = Engine::with_model(fit, p.grid, p.opts.rule, source, model)?;
    if model.sky_daylight && !engine.sky_daylight_active() {
        notes.push(format!(
            "the main light {} is not daylight: sky pixels take its basis as any other",
            fit.light
        ));
    }
    Ok(engine)
}
