//! The conversion's second stage: what the map holds (its lights, found by
//! [`crate::envmap::scene`]), what RGB (1,1,1) is taken to be, and the main light.

use crate::colorimetry::{Observer, RgbSpace};
use crate::data;
use crate::envmap::convert::options::{ConvertOptions, LightSpec, Lights, Method, WhiteSpec};
use crate::envmap::convert::pixel_spectra::Colorimeter;
use crate::envmap::convert::pixel_spectra::WhitePremise;
use crate::envmap::convert::read::Input;
use crate::envmap::scene::main_light::{self, LightChoice, WhiteChoice};
use crate::envmap::scene::{self, Scene, SceneSettings};
use crate::error::Result;
use crate::spectrum::{Rule, WavelengthGrid};

/// What the scene is, and the premises taken of it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Analysis {
    /// The lights, levels and reflectors found in the map.
    pub scene: Scene,
    /// The one main light: the spectrum of every non-sun pixel with `--lights one` and in the
    /// paper's modes; with the scene's lights, the dominant one (the fit's light).
    pub light: String,
    /// How `--light auto` chose the main light (one light, or the paper's modes).
    pub light_choice: Option<LightChoice>,
    /// What RGB (1,1,1) is taken to be, and why.
    pub white: WhiteChoice,
    /// Why the scene was not analysed (the flags decide every pixel's light); None: it was.
    pub not_analysed: Option<String>,
    /// Seconds this stage took (in a conversion's report, not in `inspect`'s, which stays the
    /// same from run to run).
    #[serde(skip)]
    pub seconds: f64,
}

/// Where a write needs no scene analysis, the light that carries every pixel and why: one
/// named light does (the paper's modes, or `--lights one`) and there is no sun to find. None:
/// the write needs the analysis.
pub(crate) fn decided_by_flags(opts: &ConvertOptions) -> Option<(&str, String)> {
    let LightSpec::Named(name) = &opts.light else {
        return None;
    };
    let one = opts.method == Method::Basis || opts.lights == Lights::One;
    (one && opts.sun.is_none()).then(|| {
        let why = format!(
            "not analysed: --light {name} carries every pixel and --sun off leaves no sun to \
             find (inspect analyses it)"
        );
        (name.as_str(), why)
    })
}

/// The analysis a write needs: the whole of [`analyse`], or where the flags decide every light
/// ([`decided_by_flags`]) only the white premise, over a scene left unanalysed.
pub(crate) fn analyse_for_write(input: &Input, opts: &ConvertOptions) -> Result<Analysis> {
    match decided_by_flags(opts) {
        Some((light, why)) => {
            let t0 = std::time::Instant::now();
            let scene = Scene::unanalysed(&input.map, &input.space.space, opts.reflectors);
            Ok(Analysis {
                scene,
                light: light.to_string(),
                light_choice: None,
                white: white_premise(input, opts, light, true)?,
                not_analysed: Some(why),
                seconds: t0.elapsed().as_secs_f64(),
            })
        }
        None => analyse(input, opts),
    }
}

/// Analyses the map: its lights, then what RGB (1,1,1) is, then (for one light) the main light.
/// Under the light premise the scene is analysed again in true colours. The map is looked at,
/// never changed: what the premise does to it is the plan's (see [`super::plan`]).
pub(crate) fn analyse(input: &Input, opts: &ConvertOptions) -> Result<Analysis> {
    let t0 = std::time::Instant::now();
    let space = input.space.space;
    let settings = SceneSettings {
        sun: opts.sun,
        lamps: match &opts.light {
            LightSpec::Named(n) => Some(n.clone()),
            LightSpec::Auto => None,
        },
        reflectors: opts.reflectors,
        ..SceneSettings::default()
    };
    let mut scene = scene::analyse(&input.map, &space, [1.0; 3], &settings)?;
    let one = opts.method == Method::Basis || opts.lights == Lights::One;
    let (light, light_choice) = match (&opts.light, one) {
        (LightSpec::Named(n), _) => (n.clone(), None),
        (LightSpec::Auto, true) => {
            let sun = scene.sun().map(|s| (s.energy_share, s.elevation_deg));
            let c = main_light::choose(&input.map, sun, &space)?;
            (c.light.clone(), Some(c))
        }
        (LightSpec::Auto, false) => (dominant_light(&scene), None),
    };
    let white = white_premise(input, opts, &light, one)?;
    if white.premise == WhitePremise::Light {
        let balance = light_rgb(&light, space)?;
        scene = scene::analyse(&input.map, &space, balance, &settings)?;
    }
    Ok(Analysis {
        scene,
        light,
        light_choice,
        white,
        not_analysed: None,
        seconds: t0.elapsed().as_secs_f64(),
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

/// What RGB (1,1,1) is: as asked, or the method's default (see [`WhiteSpec`]).
fn white_premise(
    input: &Input,
    opts: &ConvertOptions,
    light: &str,
    one: bool,
) -> Result<WhiteChoice> {
    let space = input.space.space;
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
                space.white_name()
            ),
        },
        WhiteSpec::Auto if !one && opts.light == LightSpec::Auto => WhiteChoice {
            premise: WhitePremise::Space,
            reason: "the scene's lights keep their own colours; say --white light --light NAME \
                     for a map white-balanced to its lamps"
                .into(),
        },
        WhiteSpec::Auto => main_light::choose_white(&input.map, &space, light)?,
    })
}

/// The linear RGB (true, Y = 1) of a light, on a 1 nm grid.
pub(crate) fn light_rgb(name: &str, space: RgbSpace) -> Result<[f64; 3]> {
    let grid = WavelengthGrid::visible_1nm();
    let c = Colorimeter::new(grid, Observer::Cie1931, Rule::Riemann, space)?;
    let s = c.light(name, &data::spectrum(name)?.data)?;
    Ok(c.rgb(&s)?.into())
}
