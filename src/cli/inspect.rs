//! `specmap inspect`: the scene analysis and the conversion plan of a map, without writing a
//! spectral file; optionally drawn over the map.

use super::convert::{input_guard, light_lines, ConvertOptionArgs};
use super::outln;
use anyhow::Context;
use clap::Args;
use specmap::envmap::convert;
use specmap::envmap::scene::overlay::{write_overlay, Overlay};
use specmap::envmap::scene::ReflectorModel;
use std::path::PathBuf;

#[derive(Debug, Args)]
#[command(after_help = "\
Examples:
  specmap inspect envmaps/sunrise.exr
  specmap inspect envmaps/forest.exr --json
  specmap inspect envmaps/sunrise.exr --overlay sunrise-lights.png
  specmap inspect street.exr --light hps --overlay street.png")]
pub(crate) struct InspectArgs {
    /// Input map: OpenEXR or Radiance .hdr (any layout `convert` reads).
    input: String,
    /// Draw each light's region on the tonemapped map, numbered, with a legend (PNG).
    #[arg(long, value_name = "OUT.png")]
    overlay: Option<PathBuf>,
    #[command(flatten)]
    options: ConvertOptionArgs,
    /// Machine-readable analysis and plan.
    #[arg(long)]
    json: bool,
}

pub(crate) fn run(a: InspectArgs) -> anyhow::Result<()> {
    if a.json {
        super::emit(&(serde_json::to_string_pretty(&json(&a)?)? + "\n"));
        return Ok(());
    }
    let (inspection, _) = inspect(&a)?;
    super::emit(&summary(&inspection, a.overlay.as_ref()));
    Ok(())
}

/// What `--json` prints: the analysis and plan, and the overlay drawn if asked (the Python
/// package's `inspect`).
pub(crate) fn json(a: &InspectArgs) -> anyhow::Result<serde_json::Value> {
    let (inspection, overlay) = inspect(a)?;
    let mut v = serde_json::to_value(&inspection)?;
    v["overlay"] = serde_json::to_value(&overlay)?;
    Ok(v)
}

/// The files checked, the map inspected, the overlay drawn if asked.
fn inspect(a: &InspectArgs) -> anyhow::Result<(convert::Inspection, Option<Overlay>)> {
    let opts = a.options.to_options()?;
    let mut guard = input_guard(&a.input, &opts, &a.options);
    if let Some(o) = &a.overlay {
        if !o.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
            anyhow::bail!(
                "--overlay {}: the overlay is a PNG; name it .png",
                o.display()
            );
        }
        guard.output("--overlay", o);
    }
    guard.check()?;
    let inspection =
        convert::inspect(&a.input, &opts).with_context(|| format!("inspecting {}", a.input))?;
    let overlay = match &a.overlay {
        Some(path) => Some(write_overlay(path, inspection.map(), &inspection.scene)?),
        None => None,
    };
    Ok((inspection, overlay))
}

/// The analysis and plan in words.
fn summary(r: &convert::Inspection, overlay: Option<&PathBuf>) -> String {
    let mut out = String::new();
    outln!(out, "{}", r.input);
    outln!(
        out,
        "  input        {} {}x{} ({})",
        r.input_layout.name(),
        r.input_size[0],
        r.input_size[1],
        r.input_description
    );
    outln!(
        out,
        "  levels       median luminance {:.4e}; emitters from {:.4e}{}",
        r.levels.median,
        r.levels.threshold,
        if r.levels.clipped {
            format!("; clipped at {:.4e}", r.levels.max_channel)
        } else {
            String::new()
        }
    );
    light_lines(&mut out, &r.lights, &r.bright_reflectors);
    outln!(
        out,
        "  reflectors   {:.1}% of the energy, lit by {} ({} model)",
        100.0 * r.reflector_energy_share,
        r.reflectors
            .carriers
            .iter()
            .map(|c| format!("{} {:.0}%", c.spd, 100.0 * c.share))
            .collect::<Vec<_>>()
            .join(", "),
        match r.reflectors.model {
            ReflectorModel::Global => "global".to_string(),
            ReflectorModel::Local { prior } => format!("local, prior {prior}"),
        }
    );
    outln!(out, "  white        {}", r.white.reason);
    let p = &r.plan;
    outln!(
        out,
        "  plan         {} mode, {} lights, {} carriers and {} mixes, {} wavelengths {}, {:?} \
         format; sun: {}",
        r.mode,
        format!("{:?}", p.lights).to_lowercase(),
        p.carriers.len(),
        p.mixes,
        p.grid.len(),
        p.grid,
        p.format,
        p.sun_spd.as_deref().unwrap_or("none")
    );
    for n in &p.notes {
        outln!(out, "  note         {n}");
    }
    if let Some(o) = overlay {
        outln!(out, "  overlay      {}", o.display());
    }
    out
}
