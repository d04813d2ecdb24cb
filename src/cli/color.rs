//! `specmap color`: the colour of a light, or of a reflectance under a light.

use super::outln;
use super::render_args::QuadratureArg;
use super::tolerance::tolerance_options;
use super::SpaceArg;
use clap::Args;
use specmap::colorimetry::{cct, srgb8, Cct, Cmfs, Lab, Observer, RgbSpace, Xyz, D65_XY};
use specmap::data;
use specmap::quadrature::choose::{self, Family, Selection};
use specmap::quadrature::estimate::White;
use specmap::quadrature::Quadrature;
use specmap::spectrum::{Interpolation, Rule};
use specmap::tradeoff::{choose_grid, GridChoice, Stimulus, Surface};

#[derive(Debug, Args)]
#[command(after_help = "\
Examples:
  specmap color D65                              # a light: XYZ (Y = 100), xy, CCT, RGB, CIELAB
  specmap color colorchecker:red --under D65 --json
  specmap color FL2 --range 380:780:5 --rule simpson --observer cie1964
  specmap color lps --tolerance 0.5              # the coarsest step within 0.5 CIEDE2000
  specmap color my_lamp.csv:spd --space rec2020")]
pub(crate) struct ColorArgs {
    /// The spectrum: TABLE, TABLE:COLUMN or a CSV path. Alone it is a light (normalised to
    /// Y = 100); with --under it is a reflectance.
    spd: String,
    /// Light for a reflectance (paper Eq. 11: k = 100 / integral(S * ybar)).
    #[arg(long, value_name = "LIGHT")]
    under: Option<String>,
    #[command(flatten)]
    spectral: super::SpectralArgs,
    /// RGB space for `linear_rgb` (linear_srgb and srgb8 are always sRGB).
    #[arg(long, value_enum, default_value_t = SpaceArg::Srgb)]
    space: SpaceArg,
    /// Choose the cheapest quadrature (within --range) whose colours stay within this CIEDE2000
    /// of a 1 nm Simpson reference: for the colour asked for and, so that the wavelengths hold
    /// for its light, the ColorChecker under that light (see --quadrature); and report it.
    #[arg(long, value_name = "DE")]
    tolerance: Option<f64>,
    /// With --tolerance: use at most N wavelengths (a renderer's fixed budget). Where no
    /// quadrature that small meets the tolerance, the best N fitted, with how far it misses.
    #[arg(long, value_name = "N", requires = "tolerance")]
    max_nodes: Option<usize>,
    /// `scene` (the default with --tolerance) fits nodes and weights to the light and the
    /// colours under it; `uniform` is --range and --rule (with --tolerance: the coarsest step
    /// of the colour alone); `meyer` is Meyer's four-wavelength Gaussian quadrature.
    #[arg(long, value_enum, value_name = "KIND")]
    quadrature: Option<QuadratureArg>,
    /// Neither read nor store the fitted wavelengths in the cache
    /// ($XDG_CACHE_HOME/specmap/quadrature, else ~/.cache/specmap/quadrature).
    #[arg(long)]
    no_cache: bool,
    /// Machine-readable output.
    #[arg(long)]
    json: bool,
}

/// `specmap color`: the spectrum (and its light) read, the quadrature chosen, the colour
/// measured, then reported as JSON or text.
pub(crate) fn run(a: ColorArgs) -> anyhow::Result<()> {
    let c = measure(&a)?;
    let report = match a.json {
        true => serde_json::to_string_pretty(&colour_json(&c))? + "\n",
        false => colour_text(&c),
    };
    super::emit(&report);
    Ok(())
}

/// The colour of the spectrum and how it was measured.
struct Measured {
    /// The spectrum's label.
    spd: String,
    /// The light's label, for a reflectance.
    under: Option<String>,
    observer: Observer,
    quadrature: Quadrature,
    grid_choice: Option<GridChoice>,
    selection: Option<Selection>,
    xyz: Xyz,
    temperature: Cct,
    linear_srgb: [f64; 3],
    /// The RGB space of `--space` and the colour in it.
    space: RgbSpace,
    linear_rgb: [f64; 3],
    srgb8: [u8; 3],
    /// Whether linear sRGB leaves [0, 1] (8-bit clips it).
    clipped: bool,
    lab: Lab,
    /// Why CIELAB is undefined, where the light's white has a zero.
    lab_note: Option<String>,
}

/// The spectrum (under its light) read, its quadrature chosen, and its colour in every form.
fn measure(a: &ColorArgs) -> anyhow::Result<Measured> {
    let observer = Observer::from(a.spectral.observer);
    let rule = Rule::from(a.spectral.rule);
    let space = RgbSpace::from(a.space);
    let spd = data::spectrum(&a.spd)?;
    let under = a.under.as_deref().map(data::spectrum).transpose()?;
    let stimulus = match &under {
        Some(light) => Stimulus::new(
            format!("{} under {}", spd.label, light.label),
            light.data.clone(),
            Surface::Reflectance(spd.data.clone()),
        ),
        None => Stimulus::emitter(spd.label.clone(), spd.data.clone()),
    };
    let light_label = under
        .as_ref()
        .map_or(spd.label.clone(), |l| l.label.clone());
    let (quadrature, grid_choice, selection) =
        quadrature_for(a, &stimulus, &light_label, observer, rule)?;
    let (xyz, white) = colour(&stimulus, &quadrature, under.is_some(), &light_label)?;
    let linear_srgb = RgbSpace::SRGB.rgb_from_xyz(xyz);
    Ok(Measured {
        spd: spd.label,
        under: under.map(|l| l.label),
        observer,
        quadrature,
        grid_choice,
        selection,
        xyz,
        temperature: cct(xyz)?,
        linear_srgb,
        space,
        linear_rgb: space.rgb_from_xyz(xyz),
        srgb8: srgb8(linear_srgb),
        clipped: linear_srgb.iter().any(|&v| !(0.0..=1.0).contains(&v)),
        lab: Lab::from_xyz(xyz, white),
        lab_note: lab_note(white),
    })
}

/// CIELAB divides by the white: a light with no power under an observer's function (low-
/// pressure sodium has none where the 1964 z-bar is non-zero) leaves that ratio 0/0.
fn lab_note(white: Xyz) -> Option<String> {
    let lab_undefined = ["X", "Y", "Z"]
        .iter()
        .zip(white.0)
        .filter(|(_, w)| w.is_nan() || *w <= 0.0)
        .map(|(n, _)| *n)
        .collect::<Vec<_>>();
    (!lab_undefined.is_empty()).then(|| {
        format!(
            "the light's white has {} = 0: it has no power where that colour-matching function \
             is non-zero, so CIELAB, which divides by it, is undefined there",
            lab_undefined.join(", ")
        )
    })
}

/// `--json` of the colour.
fn colour_json(c: &Measured) -> serde_json::Value {
    let uniform = c.quadrature.uniform_grid();
    serde_json::json!({
        "spd": c.spd,
        "under": c.under,
        "observer": c.observer,
        "range": uniform.map(|(g, _)| g.to_string()),
        "rule": uniform.map(|(_, r)| r),
        "wavelengths": c.quadrature.len(),
        "quadrature": c.quadrature.summary(c.selection.as_ref().map(|s| s.estimate_de2000)),
        "quadrature_choice": c.selection,
        "XYZ": c.xyz.0,
        "xy": c.xyz.xy(),
        "cct_K": c.temperature.kelvin,
        "duv": c.temperature.duv,
        "linear_srgb": c.linear_srgb,
        "srgb8": c.srgb8,
        "srgb_clipped": c.clipped,
        "space": c.space.name,
        "linear_rgb": c.linear_rgb,
        "lab": c.lab.0,
        "lab_note": c.lab_note,
        "grid_choice": c.grid_choice,
        "lab_white": if c.under.is_some() { "the light (perfect reflector = L* 100)" } else { "D65, Y = 100" },
    })
}

/// The colour's report without `--json`: how it was measured, then XYZ, CCT, RGB and CIELAB.
fn colour_text(c: &Measured) -> String {
    let what = match &c.under {
        Some(l) => format!("{} under {l}", c.spd),
        None => format!("{} (as a light, Y = 100)", c.spd),
    };
    let observer = c.observer;
    let mut out = String::new();
    match c.quadrature.uniform_grid() {
        Some((grid, rule)) => outln!(out, "{what}\n  {observer}, {grid} nm, {rule} rule"),
        None => outln!(out, "{what}\n  {observer}, {}", c.quadrature),
    }
    if let Some(g) = &c.grid_choice {
        super::write_grid_choice(&mut out, g);
    }
    if let Some(s) = &c.selection {
        super::tolerance::write_selection(&mut out, s);
    }
    super::write_xyz(&mut out, c.xyz);
    write_cct(&mut out, &c.temperature);
    write_rgb(&mut out, c);
    super::write_srgb8(&mut out, c.srgb8);
    write_lab(&mut out, &c.lab, c.lab_note.as_deref());
    out
}

/// The CCT line: the temperature and Duv, or how far from the Planckian locus it is.
fn write_cct(out: &mut String, temperature: &Cct) {
    match temperature.kelvin {
        Some(k) => outln!(
            out,
            "  CCT          {k:>10.1} K   (Duv {:+.5})",
            temperature.duv
        ),
        None => outln!(
            out,
            "  CCT          undefined: {:.3} from the Planckian locus in uv (limit 0.05)",
            temperature.duv.abs()
        ),
    }
}

/// The linear sRGB line, and the line of `--space` when it is another space.
fn write_rgb(out: &mut String, c: &Measured) {
    let s = c.linear_srgb;
    outln!(
        out,
        "  linear sRGB  {:>10.5} {:>10.5} {:>10.5}{}",
        s[0],
        s[1],
        s[2],
        if c.clipped {
            "   (outside [0,1]: clipped for 8-bit)"
        } else {
            ""
        }
    );
    if c.space != RgbSpace::SRGB {
        outln!(
            out,
            "  linear {:<6}{:>10.5} {:>10.5} {:>10.5}",
            c.space.name,
            c.linear_rgb[0],
            c.linear_rgb[1],
            c.linear_rgb[2]
        );
    }
}

/// The CIELAB line (undefined components said so), and why they are undefined.
fn write_lab(out: &mut String, lab: &Lab, note: Option<&str>) {
    let lab_text = lab.0.map(|v| {
        if v.is_finite() {
            format!("{v:>10.4}")
        } else {
            format!("{:>10}", "undefined")
        }
    });
    outln!(
        out,
        "  CIELAB       {} {} {}",
        lab_text[0],
        lab_text[1],
        lab_text[2]
    );
    if let Some(note) = note {
        outln!(out, "               {note}");
    }
}

/// The quadrature of `--quadrature`, `--tolerance`, `--range` and `--rule`, and what
/// `--tolerance` chose (a uniform grid's choice, or the scene fit's selection).
fn quadrature_for(
    a: &ColorArgs,
    stimulus: &Stimulus,
    light_label: &str,
    observer: Observer,
    rule: Rule,
) -> anyhow::Result<(Quadrature, Option<GridChoice>, Option<Selection>)> {
    let range = a.spectral.range;
    let (start, end) = (range.start_nm(), range.end_nm());
    // A budget of nodes with uniform grids is refused before any work.
    let opts = a
        .tolerance
        .map(|t| tolerance_options(t, a.max_nodes, a.quadrature))
        .transpose()?;
    Ok(match (opts, a.quadrature) {
        (None, Some(QuadratureArg::Scene)) => anyhow::bail!(
            "--quadrature scene fits the wavelengths to a colour tolerance: give --tolerance \
             (e.g. --tolerance 0.5)"
        ),
        (Some(_), Some(QuadratureArg::Meyer)) => anyhow::bail!(
            "--quadrature meyer has four fixed wavelengths: it cannot follow --tolerance"
        ),
        (None, Some(QuadratureArg::Meyer)) => (Quadrature::meyer(observer)?, None, None),
        (None, _) => (Quadrature::uniform(range, rule, observer)?, None, None),
        (Some(opts), Some(QuadratureArg::Uniform)) => {
            let one = std::slice::from_ref(stimulus);
            let c = choose_grid(one, observer, start, end, rule, opts.tolerance)?;
            (
                Quadrature::uniform(c.chosen, rule, observer)?,
                Some(c),
                None,
            )
        }
        (Some(opts), _) => {
            let (fit, held_out) = choose::for_colour(stimulus.clone(), light_label)?;
            let scene = choose::Scene {
                fit: &fit,
                held_out: &held_out,
                observer,
                start_nm: start,
                end_nm: end,
                white: White::OwnLight,
            };
            let s = cached_select(&scene, &opts, !a.no_cache)?;
            (s.quadrature.clone(), None, Some(s))
        }
    })
}

/// The scene fit of `scene` at `opts`: from the user's cache where a run before made it (when
/// `use_cache`), else fitted and stored. A note on stderr says which.
fn cached_select(
    scene: &choose::Scene,
    opts: &specmap::quadrature::fit::Options,
    use_cache: bool,
) -> anyhow::Result<Selection> {
    use specmap::quadrature::cache::{Cache, Key, Lookup};
    let cache = use_cache.then(Cache::in_user_folder).flatten();
    let Some(cache) = cache else {
        return Ok(choose::select(scene, Family::Scene, opts)?);
    };
    let stimuli = format!(
        "{:?} {:?} {:?} {} {} {:?}",
        scene.fit, scene.held_out, scene.white, scene.start_nm, scene.end_nm, scene.observer
    );
    let key = Key::new(
        stimuli.as_bytes(),
        Family::Scene,
        opts,
        scene.observer,
        RgbSpace::SRGB,
    );
    match cache.get(&key, None) {
        Lookup::Hit(s, _) => return Ok(*s),
        Lookup::Ignored(file, why) => {
            eprintln!(
                "note: quadrature cache: ignored {}: it {why}",
                file.display()
            )
        }
        Lookup::Miss(_) => {}
    }
    let s = choose::select(scene, Family::Scene, opts)?;
    if let Err(e) = cache.put(&key, &s, None, true) {
        eprintln!("note: quadrature cache: not stored: {e}");
    }
    Ok(s)
}

/// XYZ of the stimulus on the quadrature (Eq. 10/11: a white under the light is Y = 100) and
/// its CIELAB white: the light for a reflectance, D65 for a light.
fn colour(
    stimulus: &Stimulus,
    q: &Quadrature,
    reflectance: bool,
    light_label: &str,
) -> anyhow::Result<(Xyz, Xyz)> {
    if let Some((grid, rule)) = q.uniform_grid() {
        let cmfs = Cmfs::new(q.observer(), &grid)?;
        let s = stimulus.light.resample(&grid, Interpolation::LIGHT);
        return Ok(match &stimulus.surface {
            Surface::Reflectance(r) if reflectance => {
                let r = r.resample(&grid, Interpolation::SMOOTH);
                (
                    cmfs.reflectance_xyz(&r, &s, rule)?,
                    cmfs.light_xyz(&s, rule)?,
                )
            }
            _ => (cmfs.light_xyz(&s, rule)?, Xyz::from_xy(D65_XY)),
        });
    }
    let (light, value) = stimulus.values_at(q.nodes_nm())?;
    let rel = |v: &[f64]| {
        q.relative_xyz(v, &light).ok_or_else(|| {
            anyhow::anyhow!("{light_label}: no visible energy at the wavelengths {q}")
        })
    };
    Ok(if reflectance {
        (rel(&value)?, rel(&light)?)
    } else {
        (rel(&light)?, Xyz::from_xy(D65_XY))
    })
}
