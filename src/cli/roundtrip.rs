//! `specmap roundtrip`: integrate a spectral EXR back to RGB and compare with its RGB preview.

use super::{outln, ObserverArg, RuleArg};
use clap::{Args, ValueEnum};
use specmap::envmap::roundtrip::heatmap::{
    caption, check_bounds, choose_range, write_heatmap, Scale,
};
use specmap::envmap::roundtrip::{round_trip_file, FileRoundTrip};
use std::path::PathBuf;

#[derive(Debug, Args)]
#[command(after_help = "\
Examples:
  specmap convert envmaps/sunrise.exr -o sunrise.spectral.exr
  specmap roundtrip sunrise.spectral.exr
  specmap roundtrip sunrise.spectral.exr --heatmap roundtrip.png --json
  specmap roundtrip sunrise.spectral.exr --observer cie1964 --rule simpson")]
pub(crate) struct RoundtripArgs {
    /// A spectral OpenEXR (from `specmap convert`, or any Fichet-layout file with R, G, B).
    file: PathBuf,
    /// Write a per-pixel CIEDE2000 heatmap (PNG) with its colour bar and range beneath it.
    #[arg(long, value_name = "OUT.png")]
    heatmap: Option<PathBuf>,
    /// The heatmap's colour scale.
    #[arg(long, value_enum, default_value_t = ScaleArg::Log)]
    heatmap_scale: ScaleArg,
    /// CIEDE2000 shown as black in the heatmap [default: log: the 1st percentile of the pixels'
    /// errors, rounded down to 1, 2 or 5 x 10^k and at least a decade below the top; linear: 0].
    #[arg(long, value_name = "DE")]
    heatmap_min: Option<f64>,
    /// CIEDE2000 shown as white [default: the 99.9th percentile, rounded up to 1, 2 or 5 x 10^k].
    #[arg(long, value_name = "DE")]
    heatmap_max: Option<f64>,
    /// Standard observer.
    #[arg(long, value_enum, default_value_t = ObserverArg::Cie1931)]
    observer: ObserverArg,
    /// Integration rule.
    #[arg(long, value_enum, default_value_t = RuleArg::Riemann)]
    rule: RuleArg,
    /// Machine-readable output.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum ScaleArg {
    /// equal ratios of CIEDE2000 get equal lengths of the bar (errors span decades)
    Log,
    /// equal differences get equal lengths
    Linear,
}

/// `specmap roundtrip`: the heatmap's bounds and the files checked, the file integrated back to
/// RGB, the heatmap; then the statistics as JSON or text.
pub(crate) fn run(a: RoundtripArgs) -> anyhow::Result<()> {
    let scale = match a.heatmap_scale {
        ScaleArg::Log => Scale::Log,
        ScaleArg::Linear => Scale::Linear,
    };
    check_options(&a, scale)?;
    let mut de = Vec::new();
    let r = round_trip_file(
        &a.file,
        a.observer.into(),
        a.rule.into(),
        a.heatmap.as_ref().map(|_| &mut de),
    )?;
    if let Some(path) = &a.heatmap {
        let range = choose_range(&de, scale, a.heatmap_min, a.heatmap_max)?;
        let drawn = write_heatmap(path, r.width, r.height, &de, &range)?;
        let [range, counts] = caption(&drawn);
        eprintln!("wrote {}: {range}; {counts}", path.display());
    }
    let report = match a.json {
        true => serde_json::to_string_pretty(&r)? + "\n",
        false => round_trip_report(&r),
    };
    super::emit(&report);
    Ok(())
}

/// Checked before any work: the heatmap's bounds alone (the range itself needs the pixels), the
/// file read and written, and the heatmap's PNG name.
fn check_options(a: &RoundtripArgs, scale: Scale) -> anyhow::Result<()> {
    check_bounds(scale, a.heatmap_min, a.heatmap_max).map_err(|e| {
        anyhow::anyhow!(
            "--heatmap-min {} --heatmap-max {}: {e}",
            a.heatmap_min
                .map(|v| v.to_string())
                .unwrap_or("auto".into()),
            a.heatmap_max
                .map(|v| v.to_string())
                .unwrap_or("auto".into())
        )
    })?;
    let mut guard = super::guard::Guard::new();
    guard.input("", &a.file);
    if let Some(p) = &a.heatmap {
        guard.output("--heatmap", p);
    }
    guard.check()?;
    if let Some(p) = &a.heatmap {
        if !p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
            anyhow::bail!(
                "--heatmap {}: the heatmap is a PNG; name it .png",
                p.display()
            );
        }
    }
    Ok(())
}

/// The report without `--json`: the file, then CIEDE2000 over all pixels and without the sun.
fn round_trip_report(r: &FileRoundTrip) -> String {
    let mut out = String::new();
    outln!(
        out,
        "{}: {}x{}, {} wavelengths {}..{} nm, {} ({}){}",
        r.file,
        r.width,
        r.height,
        r.wavelengths,
        r.range_nm[0],
        r.range_nm[1],
        r.space,
        r.chromaticities,
        r.white_balance
            .map(|t| format!(", white-balanced by the main light's RGB {t:.4?}"))
            .unwrap_or_default()
    );
    outln!(
        out,
        "  statistic        over {}",
        super::floor_text(&r.floor)
    );
    for (name, s) in [("all pixels", &r.all), ("without the sun", &r.without_sun)] {
        outln!(out, "  {name:<16} {}", super::round_trip_text(s));
    }
    outln!(out, "  sun pixels       {}", r.sun_pixels);
    if r.non_finite_pixels > 0 {
        outln!(
            out,
            "  left out         {} pixels with NaN or infinite values",
            r.non_finite_pixels
        );
    }
    out
}
