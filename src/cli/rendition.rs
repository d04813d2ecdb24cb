//! `specmap rendition`: colour rendition of a reconstructed spectral map against its truth.

use super::{outln, ObserverArg, RuleArg};
use anyhow::Context;
use clap::Args;
use specmap::rendition::{compare, map_irradiance, MapSummary, Normal, RenditionOptions};
use std::path::PathBuf;

#[derive(Debug, Args)]
#[command(after_help = "\
Examples:
  specmap convert tests/data/truth/interior_fl2.rgb.exr -o fl2.exr --light auto
  specmap rendition tests/data/truth/interior_fl2.spectral.exr fl2.exr
  specmap rendition truth.spectral.exr converted.exr --normals up,px,nx,pz,nz --json
  specmap rendition truth.spectral.exr converted.exr --normals 0:1:1 --patches my_patches.csv")]
pub(crate) struct RenditionArgs {
    /// The truth: a spectral OpenEXR (Fichet 2021 layout) whose spectra are known.
    truth: PathBuf,
    /// The reconstruction of the same scene, e.g. `specmap convert` of its RGB map.
    reconstructed: PathBuf,
    /// Surface normals to light the patches at, comma-separated: up, down, px, nx, py, ny, pz,
    /// nz (or +x, -x, ...) or X:Y:Z, in the maps' world space (Y up) [default: up,px,nx,pz,nz].
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        value_name = "NORMALS"
    )]
    normals: Option<Vec<Normal>>,
    /// A reflectance table (or CSV) whose every column is a test patch.
    #[arg(long, default_value = "colorchecker")]
    patches: String,
    /// Standard observer.
    #[arg(long, value_enum, default_value_t = ObserverArg::Cie1931)]
    observer: ObserverArg,
    /// Integration rule.
    #[arg(long, value_enum, default_value_t = RuleArg::Riemann)]
    rule: RuleArg,
    /// Machine-readable output (every patch at every normal).
    #[arg(long)]
    json: bool,
}

fn describe(m: &MapSummary) -> String {
    format!(
        "{}: {}x{} {}, {} bands {}..{} nm{}",
        m.file,
        m.width,
        m.height,
        m.layout.name(),
        m.bands,
        m.range_nm[0],
        m.range_nm[1],
        if m.nonfinite_values > 0 {
            format!(
                ", {} NaN or infinite samples counted as 0",
                m.nonfinite_values
            )
        } else {
            String::new()
        }
    )
}

pub(crate) fn run(a: RenditionArgs) -> anyhow::Result<()> {
    let opts = RenditionOptions {
        normals: a.normals.unwrap_or_else(Normal::defaults),
        observer: a.observer.into(),
        rule: a.rule.into(),
        patches: a.patches,
    };
    let truth = map_irradiance(&a.truth, &opts.normals)
        .with_context(|| format!("reading the truth map {}", a.truth.display()))?;
    let rec = map_irradiance(&a.reconstructed, &opts.normals).with_context(|| {
        format!(
            "reading the reconstructed map {}",
            a.reconstructed.display()
        )
    })?;
    let r = compare(&truth, &rec, &opts)?;
    if a.json {
        super::emit(&(serde_json::to_string_pretty(&r)? + "\n"));
        return Ok(());
    }
    let mut out = String::new();
    outln!(out, "truth          {}", describe(&r.truth));
    outln!(out, "reconstructed  {}", describe(&r.reconstructed));
    outln!(
        out,
        "{} patches of {} at {} normals, on the shared wavelengths {} nm ({}, {})",
        r.normals[0].patches.len(),
        r.patches,
        r.normals.len(),
        r.wavelengths,
        r.observer,
        r.rule
    );
    outln!(out, "adaptation: {}", r.adaptation);
    outln!(out, "whites: {}", r.white_comparison);
    outln!(out, "");
    outln!(
        out,
        "  {:<8} {:>16} {:>16} {:>8} {:>9} {:>9} {:>9}  worst patch",
        "normal",
        "white xy truth",
        "reconstructed",
        "E ratio",
        "white dE",
        "mean dE",
        "max dE"
    );
    for n in &r.normals {
        let xy = |w: &specmap::rendition::White| format!("{:.4} {:.4}", w.xy[0], w.xy[1]);
        outln!(
            out,
            "  {:<8} {:>16} {:>16} {:>8.4} {:>9.3} {:>9.3} {:>9.3}  {}",
            n.normal.name,
            xy(&n.truth_white),
            xy(&n.reconstructed_white),
            n.irradiance_ratio,
            n.white_de2000,
            n.mean_de2000,
            n.max_de2000,
            n.max_patch
        );
    }
    outln!(out, "");
    outln!(
        out,
        "rendition CIEDE2000: mean {:.3}, max {:.3} ({} at {}); white CIEDE2000: mean {:.3}, max {:.3}",
        r.mean_de2000,
        r.max_de2000,
        r.max_at[1],
        r.max_at[0],
        r.white_mean_de2000,
        r.white_max_de2000
    );
    super::emit(&out);
    Ok(())
}
