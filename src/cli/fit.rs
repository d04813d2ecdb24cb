//! `specmap fit`: the paper's basis weights for a main light, and the exact mode.

use super::{outln, ModeArg, SpaceArg};
use anyhow::Context;
use clap::Args;
use specmap::colorimetry::{Observer, RgbSpace};
use specmap::fit::{self, FitInput, Mode};
use specmap::plot::{self, Figure, Series};
use specmap::spectrum::Rule;
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
#[command(after_help = "\
Examples:
  specmap fit --light D65                        # the paper's weights w_R, w_G, w_B
  specmap fit --light FL2 --mode exact -o fit.json --plot basis.png
  specmap fit --light D65,A,FL2,lps --mode paper,exact,nonneg   # a comparison table
  specmap fit --light FL11 --rgb 1,0.5,0.2 --json
  specmap fit --light my_lamp.csv:spd --space acescg --range 380:780:5")]
pub(crate) struct FitArgs {
    /// The main light: a table name or CSV (e.g. D65, A, FL2, lps). Several, comma-separated,
    /// print a comparison table.
    #[arg(long, value_delimiter = ',', required = true)]
    light: Vec<String>,
    /// How RGB becomes a spectrum. Several, comma-separated, print a comparison table.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "paper")]
    mode: Vec<ModeArg>,
    /// The three basis reflectances for R, G and B.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "colorchecker:red,colorchecker:green,colorchecker:blue"
    )]
    basis: Vec<String>,
    /// The RGB space the weights are solved in.
    #[arg(long, value_enum, default_value_t = SpaceArg::Srgb)]
    space: SpaceArg,
    #[command(flatten)]
    spectral: super::SpectralArgs,
    /// Write the fit (versioned JSON: basis spectra, grid, light, weights, matrix) to this file.
    #[arg(short, long, value_name = "FIT.json")]
    output: Option<PathBuf>,
    /// Plot the three weighted basis spectra and the light (.png or .svg).
    #[arg(long, value_name = "OUT")]
    plot: Option<PathBuf>,
    /// Also show the basis coefficients, SPD and round-trip error of one linear RGB colour.
    #[arg(long, value_delimiter = ',', value_name = "R,G,B")]
    rgb: Option<Vec<f64>>,
    /// Machine-readable summary.
    #[arg(long)]
    json: bool,
}

/// `specmap fit`: the options and files checked, every light fitted in every mode; a table for
/// several, else the files, the one fit's report and `--rgb`'s pixel.
pub(crate) fn run(a: FitArgs) -> anyhow::Result<()> {
    check_args(&a)?;
    check_files(&a)?;
    let space = RgbSpace::from(a.space);
    let mut fits = fit_all(&a, space)?;
    if fits.len() > 1 {
        if a.output.is_some() || a.plot.is_some() || a.rgb.is_some() {
            anyhow::bail!("-o, --plot and --rgb take one light and one mode");
        }
        return table(&fits, a.json);
    }
    let (f, rt) = fits.pop().expect("one light and one mode");
    let pixel = a.rgb.as_deref().map(|v| pixel(&f, &space, v)).transpose()?;
    write_files(&a, &f)?;
    let report = match a.json {
        true => serde_json::to_string_pretty(&fit_json(&f, &rt, pixel))? + "\n",
        false => fit_text(&f, &rt, pixel.as_ref()),
    };
    super::emit(&report);
    Ok(())
}

/// One light in one mode, as values: `--json`'s report and the fit `-o` writes (the Python
/// package's `fit`, python/src/spectra.rs, which the binary does not call); no file is written.
#[allow(dead_code)]
pub(crate) fn json(a: &FitArgs) -> anyhow::Result<(serde_json::Value, fit::Fit)> {
    check_args(a)?;
    let space = RgbSpace::from(a.space);
    let mut fits = fit_all(a, space)?;
    if fits.len() != 1 {
        anyhow::bail!(
            "one light and one mode at a time ({} asked for)",
            fits.len()
        );
    }
    let (f, rt) = fits.pop().expect("one light and one mode");
    let pixel = a.rgb.as_deref().map(|v| pixel(&f, &space, v)).transpose()?;
    Ok((fit_json(&f, &rt, pixel), f))
}

/// Three basis spectra, and three values for `--rgb`.
fn check_args(a: &FitArgs) -> anyhow::Result<()> {
    if a.basis.len() != 3 {
        anyhow::bail!(
            "--basis takes three spectra (for R, G and B), comma-separated; got {}: {}",
            a.basis.len(),
            a.basis.join(",")
        );
    }
    if a.rgb.as_ref().is_some_and(|v| v.len() != 3) {
        anyhow::bail!("--rgb takes three comma-separated values, e.g. --rgb 1,0.5,0.2");
    }
    Ok(())
}

/// The spectra read and the files written, checked before any work.
fn check_files(a: &FitArgs) -> anyhow::Result<()> {
    let mut guard = super::guard::Guard::new();
    for light in &a.light {
        guard.spec("--light", light);
    }
    for b in &a.basis {
        guard.spec("--basis", b);
    }
    if let Some(p) = &a.output {
        guard.output("-o", p);
    }
    if let Some(p) = &a.plot {
        guard.output("--plot", p);
    }
    guard.check()
}

/// Every light in every mode, each fit with its round trip over the 17^3 RGB grid.
fn fit_all(a: &FitArgs, space: RgbSpace) -> anyhow::Result<Vec<(fit::Fit, fit::RoundTrip)>> {
    let modes: Vec<Mode> = a.mode.iter().map(|&m| Mode::from(m)).collect();
    let mut fits = Vec::new();
    for name in &a.light {
        let input = FitInput::from_names(
            name,
            [&a.basis[0], &a.basis[1], &a.basis[2]].map(String::as_str),
            &a.spectral.range,
            Observer::from(a.spectral.observer),
            Rule::from(a.spectral.rule),
            space,
        )?;
        for &mode in &modes {
            let f = fit::fit(&input, mode)
                .with_context(|| format!("fitting the basis for {}", input.light_label))?;
            let rt = fit::round_trip(&f, 17, &space);
            fits.push((f, rt));
        }
    }
    Ok(fits)
}

/// `--rgb`: the pixel's basis coefficients, SPD and round-trip error.
fn pixel(f: &fit::Fit, space: &RgbSpace, v: &[f64]) -> anyhow::Result<serde_json::Value> {
    let rgb = [v[0], v[1], v[2]];
    if rgb.iter().any(|x| !x.is_finite() || *x < 0.0 || *x > 1e30) {
        anyhow::bail!(
            "--rgb {rgb:?}: linear RGB values must be between 0 and 1e30 (HDR is fine; beyond \
             that the coefficients overflow)"
        );
    }
    let up = fit::Upsampler::new(f, space);
    let coefficients = up.coefficients(rgb);
    let spd = up.spd(rgb);
    Ok(serde_json::json!({
        "rgb": rgb,
        "coefficients": coefficients,
        "rendered_rgb": up.rendered_rgb(coefficients),
        "dE2000": up.round_trip_error(rgb, coefficients),
        "min_spd": spd.iter().cloned().fold(f64::INFINITY, f64::min),
        "spd": spd,
    }))
}

/// `-o` (the fit as JSON) and `--plot`.
fn write_files(a: &FitArgs, f: &fit::Fit) -> anyhow::Result<()> {
    if let Some(path) = &a.output {
        let text = serde_json::to_string_pretty(f)?;
        specmap::io::write_atomic(path, text.as_bytes())?;
        eprintln!("wrote {}", path.display());
    }
    if let Some(path) = &a.plot {
        write_basis_plot(f, path)?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// `--json` of one fit.
fn fit_json(
    f: &fit::Fit,
    rt: &fit::RoundTrip,
    pixel: Option<serde_json::Value>,
) -> serde_json::Value {
    serde_json::json!({
        "light": f.light,
        "mode": f.mode,
        "basis": f.basis,
        "space": f.space,
        "observer": f.observer,
        "range": f.grid.to_string(),
        "rule": f.rule,
        "weights": f.weights,
        "matrix": f.matrix,
        "condition_number": f.condition_number,
        "regularized": f.regularized,
        "lost_information": f.lost_information,
        "light_rgb": f.light_rgb,
        "argmin": f.argmin,
        "roundtrip": rt,
        "pixel": pixel,
    })
}

/// The report of one fit without `--json`.
fn fit_text(f: &fit::Fit, rt: &fit::RoundTrip, pixel: Option<&serde_json::Value>) -> String {
    let mut out = String::new();
    outln!(
        out,
        "{} fit under {} ({}, {} nm, {})",
        mode_name(f.mode),
        f.light,
        f.space,
        f.grid,
        f.rule
    );
    outln!(out, "  basis           {}", f.basis.join(", "));
    outln!(
        out,
        "  weights         wR {:.10}  wG {:.10}  wB {:.10}",
        f.weights[0],
        f.weights[1],
        f.weights[2]
    );
    outln!(
        out,
        "  argmin          wR {:.10}  wG {:.10}  wB {:.10}  ({} iterations, max |difference| {:.1e})",
        f.argmin.weights[0], f.argmin.weights[1], f.argmin.weights[2], f.argmin.iterations,
        f.argmin.max_abs_difference
    );
    if f.mode != Mode::Paper {
        write_matrix(&mut out, &f.matrix);
    }
    outln!(
        out,
        "  light RGB       {:.6} {:.6} {:.6}",
        f.light_rgb[0],
        f.light_rgb[1],
        f.light_rgb[2]
    );
    outln!(
        out,
        "  condition       {:.4e}{}",
        f.condition_number,
        if f.regularized {
            "   (singular: reduced solution)"
        } else {
            ""
        }
    );
    if let Some(lost) = &f.lost_information {
        outln!(out, "  note            {lost}");
    }
    outln!(
        out,
        "  round trip      {} colours: CIEDE2000 mean {:.4}, p95 {:.4}, max {:.4}; negative SPD for {:.1}%",
        rt.colours, rt.mean_de2000, rt.p95_de2000, rt.max_de2000, 100.0 * rt.negative_fraction
    );
    if let Some(p) = pixel {
        write_pixel(&mut out, p);
    }
    out
}

/// The matrix W of the exact and non-negative modes, one row a line.
fn write_matrix(out: &mut String, matrix: &[[f64; 3]; 3]) {
    for (i, row) in matrix.iter().enumerate() {
        outln!(
            out,
            "  {}  {:>12.6} {:>12.6} {:>12.6}",
            if i == 0 {
                "matrix W    "
            } else {
                "            "
            },
            row[0],
            row[1],
            row[2]
        );
    }
}

/// The line of `--rgb`'s pixel.
fn write_pixel(out: &mut String, p: &serde_json::Value) {
    outln!(
        out,
        "  rgb {}  coefficients {}, rendered {}, CIEDE2000 {:.4}, min SPD {:.3e}",
        p["rgb"],
        p["coefficients"],
        p["rendered_rgb"],
        p["dE2000"].as_f64().unwrap_or(f64::NAN),
        p["min_spd"].as_f64().unwrap_or(f64::NAN)
    );
}

/// The plot of `specmap fit --plot`: the three weighted basis spectra and the light (.png, .svg).
pub(super) fn write_basis_plot(f: &fit::Fit, path: &Path) -> anyhow::Result<()> {
    let w: Vec<f64> = f.grid.wavelengths_nm().collect();
    let max_light = f.light_spd.iter().cloned().fold(0.0, f64::max).max(1e-300);
    let basis = f.weighted_basis();
    let max_basis = basis
        .iter()
        .flatten()
        .cloned()
        .fold(0.0, f64::max)
        .max(1e-300);
    let mut series: Vec<Series> = ["R", "G", "B"]
        .iter()
        .zip(&basis)
        .zip([[200, 30, 30], [30, 150, 30], [30, 60, 200]])
        .zip(&f.basis)
        .map(|(((c, b), color), label)| Series {
            label: format!("w_{c} · {label} · {}", f.light),
            points: w
                .iter()
                .copied()
                .zip(b.iter().map(|v| v / max_basis))
                .collect(),
            color,
        })
        .collect();
    series.push(Series {
        label: format!("{} (scaled)", f.light),
        points: w
            .iter()
            .copied()
            .zip(f.light_spd.iter().map(|v| v / max_light))
            .collect(),
        color: [120, 120, 120],
    });
    plot::write(
        &Figure {
            title: format!(
                "Fitted basis under {} (w = {:.4}, {:.4}, {:.4})",
                f.light, f.weights[0], f.weights[1], f.weights[2]
            ),
            x_label: "Wavelength (nm)".into(),
            y_label: "Relative spectral power".into(),
            series,
        },
        path,
    )?;
    Ok(())
}

fn summary(f: &fit::Fit, rt: &fit::RoundTrip) -> serde_json::Value {
    serde_json::json!({
        "light": f.light,
        "mode": f.mode,
        "weights": f.weights,
        "condition_number": f.condition_number,
        "regularized": f.regularized,
        "light_rgb": f.light_rgb,
        "argmin_max_abs_difference": f.argmin.max_abs_difference,
        "roundtrip": rt,
    })
}

/// Several lights and modes side by side: markdown, or a JSON array.
fn table(fits: &[(fit::Fit, fit::RoundTrip)], json: bool) -> anyhow::Result<()> {
    if json {
        let rows: Vec<_> = fits.iter().map(|(f, rt)| summary(f, rt)).collect();
        super::emit(&(serde_json::to_string_pretty(&rows)? + "\n"));
        return Ok(());
    }
    let mut out = String::new();
    outln!(out, "| light | mode | w_R | w_G | w_B | condition | reduced | mean ΔE00 | p95 ΔE00 | max ΔE00 | negative SPD |");
    outln!(out, "|---|---|---:|---:|---:|---:|---|---:|---:|---:|---:|");
    for (f, rt) in fits {
        outln!(
            out,
            "| {} | {} | {:.4} | {:.4} | {:.4} | {:.3e} | {} | {:.4} | {:.4} | {:.4} | {:.1}% |",
            f.light,
            mode_name(f.mode),
            f.weights[0],
            f.weights[1],
            f.weights[2],
            f.condition_number,
            if f.regularized { "yes" } else { "no" },
            rt.mean_de2000,
            rt.p95_de2000,
            rt.max_de2000,
            100.0 * rt.negative_fraction
        );
    }
    super::emit(&out);
    Ok(())
}

pub(super) fn mode_name(m: Mode) -> &'static str {
    match m {
        Mode::Paper => "paper",
        Mode::Exact => "exact",
        Mode::Nonneg => "nonneg",
    }
}
