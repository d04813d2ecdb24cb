//! `specmap color`: the colour of a light, or of a reflectance under a light.

use super::outln;
use super::SpaceArg;
use clap::Args;
use specmap::colorimetry::{cct, srgb8, Cmfs, Lab, Observer, RgbSpace, Xyz, D65_XY};
use specmap::data;
use specmap::spectrum::{Interpolation, Rule};
use specmap::tradeoff::{choose_grid, Stimulus, Surface};

#[derive(Debug, Args)]
#[command(after_help = "\
Examples:
  specmap color D65                              # a light: XYZ (Y = 100), xy, CCT, RGB, CIELAB
  specmap color colorchecker:red --under D65 --json
  specmap color FL2 --range 380:780:5 --rule simpson --observer cie1964
  specmap color lps --tolerance 0.5              # the coarsest step within 0.5 CIEDE2000
  specmap color my_lamp.csv:spd --space rec2020")]
pub struct ColorArgs {
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
    /// Choose the coarsest wavelength step (within --range) whose colour stays within this
    /// CIEDE2000 of a 1 nm Simpson reference, and report it.
    #[arg(long, value_name = "DE")]
    tolerance: Option<f64>,
    /// Machine-readable output.
    #[arg(long)]
    json: bool,
}

pub fn run(a: ColorArgs) -> anyhow::Result<()> {
    let observer = Observer::from(a.spectral.observer);
    let rule = Rule::from(a.spectral.rule);
    let mut range = a.spectral.range;
    let space = RgbSpace::from(a.space);
    let spd = data::spectrum(&a.spd)?;
    let choice = match a.tolerance {
        None => None,
        Some(tolerance) => {
            let stimulus = match &a.under {
                Some(light) => {
                    let light = data::spectrum(light)?;
                    Stimulus {
                        name: format!("{} under {}", spd.label, light.label),
                        light: light.data,
                        surface: Surface::Reflectance(spd.data.clone()),
                    }
                }
                None => Stimulus::emitter(spd.label.clone(), spd.data.clone()),
            };
            let (start, end) = (range.start_nm(), range.end_nm());
            let c = choose_grid(&[stimulus], observer, start, end, rule, tolerance)?;
            range = c.chosen;
            Some(c)
        }
    };
    let cmfs = Cmfs::new(observer, &range)?;
    let (xyz, white, under_label) = match &a.under {
        Some(light) => {
            let light = data::spectrum(light)?;
            let s = light.data.resample(&range, Interpolation::LIGHT);
            let r = spd.data.resample(&range, Interpolation::SMOOTH);
            let xyz = cmfs.reflectance_xyz(&r, &s, rule)?;
            let white = cmfs.light_xyz(&s, rule)?;
            (xyz, white, Some(light.label))
        }
        None => {
            let s = spd.data.resample(&range, Interpolation::LIGHT);
            (cmfs.light_xyz(&s, rule)?, Xyz::from_xy(D65_XY), None)
        }
    };
    let xy = xyz.xy();
    let temperature = cct(xyz)?;
    let linear_srgb = RgbSpace::SRGB.rgb_from_xyz(xyz);
    let linear_rgb = space.rgb_from_xyz(xyz);
    let code = srgb8(linear_srgb);
    let lab = Lab::from_xyz(xyz, white);
    // CIELAB divides by the white: a light with no power under an observer's function (low-
    // pressure sodium has none where the 1964 z-bar is non-zero) leaves that ratio 0/0.
    let lab_undefined = ["X", "Y", "Z"]
        .iter()
        .zip(white.0)
        .filter(|(_, w)| w.is_nan() || *w <= 0.0)
        .map(|(n, _)| *n)
        .collect::<Vec<_>>();
    let lab_note = (!lab_undefined.is_empty()).then(|| {
        format!(
            "the light's white has {} = 0: it has no power where that colour-matching function \
             is non-zero, so CIELAB, which divides by it, is undefined there",
            lab_undefined.join(", ")
        )
    });
    let clipped = linear_srgb.iter().any(|&v| !(0.0..=1.0).contains(&v));

    if a.json {
        let doc = serde_json::json!({
            "spd": spd.label,
            "under": under_label,
            "observer": observer,
            "range": range.to_string(),
            "rule": rule,
            "XYZ": xyz.0,
            "xy": xy,
            "cct_K": temperature.kelvin,
            "duv": temperature.duv,
            "linear_srgb": linear_srgb,
            "srgb8": code,
            "srgb_clipped": clipped,
            "space": space.name,
            "linear_rgb": linear_rgb,
            "lab": lab.0,
            "lab_note": lab_note,
            "grid_choice": choice,
            "lab_white": if under_label.is_some() { "the light (perfect reflector = L* 100)" } else { "D65, Y = 100" },
        });
        super::emit(&(serde_json::to_string_pretty(&doc)? + "\n"));
        return Ok(());
    }
    let what = match &under_label {
        Some(l) => format!("{} under {l}", spd.label),
        None => format!("{} (as a light, Y = 100)", spd.label),
    };
    let mut out = String::new();
    outln!(out, "{what}\n  {observer}, {} nm, {rule} rule", range);
    if let Some(c) = &choice {
        super::write_grid_choice(&mut out, c);
    }
    super::write_xyz(&mut out, xyz);
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
    outln!(
        out,
        "  linear sRGB  {:>10.5} {:>10.5} {:>10.5}{}",
        linear_srgb[0],
        linear_srgb[1],
        linear_srgb[2],
        if clipped {
            "   (outside [0,1]: clipped for 8-bit)"
        } else {
            ""
        }
    );
    if space != RgbSpace::SRGB {
        outln!(
            out,
            "  linear {:<6}{:>10.5} {:>10.5} {:>10.5}",
            space.name,
            linear_rgb[0],
            linear_rgb[1],
            linear_rgb[2]
        );
    }
    super::write_srgb8(&mut out, code);
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
    if let Some(note) = &lab_note {
        outln!(out, "               {note}");
    }
    super::emit(&out);
    Ok(())
}
