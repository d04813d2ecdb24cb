//! The scene and spectral settings that `render`'s options describe: the `--env` lighting, the
//! preset with its surfaces, background, zoom and orbit, and the grid, rule and observer.

use super::render_args::{diffuse, film_layers, index, orbit, BackgroundArg, RenderArgs};
use anyhow::Context;
use specmap::colorimetry::RgbSpace;
use specmap::render::{env, Film, Preset, Scene, Spectral};
use specmap::thinfilm::{Index, Material};

/// The environment of `--env` as a lighting, and what loading found.
pub(crate) fn load_env(
    a: &RenderArgs,
) -> anyhow::Result<Option<(specmap::render::Lighting, env::EnvReport)>> {
    a.env
        .as_ref()
        .map(|p| {
            env::load(p, &a.light)
                .with_context(|| format!("loading the environment {}", p.display()))
        })
        .transpose()
}

/// The scene `a` describes: the preset at `size`, lit by `lighting` (the loaded `--env`) or
/// the uniform `--light`, with the surface flags on its main objects, the background, the
/// zoom and the orbit.
pub(crate) fn scene_from(
    a: &RenderArgs,
    preset: Preset,
    (w, h): (usize, usize),
    lighting: Option<specmap::render::Lighting>,
) -> anyhow::Result<Scene> {
    let mut scene = preset.scene(w, h, &a.light, lighting)?;
    scene.backdrop = match a.background {
        BackgroundArg::Env => specmap::render::Backdrop::DEFAULT,
        BackgroundArg::Flat => specmap::render::Backdrop::Flat,
        BackgroundArg::None => specmap::render::Backdrop::Hidden,
    };
    surfaces(a, &mut scene)?;
    if let Some(z) = a.zoom {
        if !(z.is_finite() && (0.01..=100.0).contains(&z)) {
            anyhow::bail!("--zoom {z}: must be between 0.01 and 100");
        }
        scene.view.half_height /= z;
    }
    if let Some(o) = &a.orbit {
        scene.orbit(orbit(o)?);
    }
    Ok(scene)
}

/// `--film`, `--substrate`, `--diffuse`, `--kd`, `--ks` and `--shininess` on the scene's main
/// objects.
fn surfaces(a: &RenderArgs, scene: &mut Scene) -> anyhow::Result<()> {
    let layers = a.film.as_deref().map(film_layers).transpose()?;
    let substrate = a
        .substrate
        .as_deref()
        .map(|s| index(s, "substrate"))
        .transpose()?;
    let rd = a.diffuse.as_deref().map(diffuse).transpose()?;
    for o in scene.objects.iter_mut().filter(|o| o.main) {
        let s = &mut o.surface;
        if layers.is_some() || substrate.is_some() {
            let f = s.film.get_or_insert(Film {
                ambient: Material::constant(Index::real(1.0)?),
                layers: Vec::new(),
                substrate: Material::constant(Index::real(1.5)?),
            });
            if let Some(l) = &layers {
                f.layers = l.clone();
                o.ramp = None;
            }
            if let Some(m) = &substrate {
                f.substrate = m.clone();
            }
        }
        if let Some(r) = &rd {
            s.diffuse = Some(r.clone());
        }
        if let Some(v) = a.kd {
            s.kd = v;
        }
        if let Some(v) = a.ks {
            s.ks = v;
        }
        if let Some(v) = a.shininess {
            s.shininess = v;
        }
    }
    Ok(())
}

/// The grid, rule, observer and space of `--step`/`--samples`, `--rule` and `--observer`.
pub(crate) fn spectral_of(a: &RenderArgs) -> anyhow::Result<Spectral> {
    let base = match (a.step, a.samples) {
        (Some(s), _) => Spectral::step(s)?,
        (None, Some(n)) => Spectral::samples(n)?,
        (None, None) => Spectral::default(),
    };
    Ok(Spectral {
        rule: a.rule.into(),
        observer: a.observer.into(),
        space: RgbSpace::SRGB,
        ..base
    })
}
