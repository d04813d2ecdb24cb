//! `specmap bench`: colour error against time for every knob that trades one for the other
//! (wavelength step, integration rule, upsampling mode, thin-film thickness, render sample count),
//! side by side, as a markdown table, JSON and plots.

use super::render_args::BackendArg;
use anyhow::Context;
use clap::Args;
use specmap::colorimetry::{Observer, RgbSpace};
use specmap::data;
use specmap::fit::{self, FitInput, Mode, PAPER_BASIS};
use specmap::plot::{self, Figure, Series};
use specmap::render::gpu::Gpu;
use specmap::render::{sweep, Backend, Preset, Spectral};
use specmap::spectrum::{Rule, WavelengthGrid};
use specmap::thinfilm::{Coherence, Incidence, Index, Layer, Material, Stack};
use specmap::tradeoff::{colorchecker_under, measure, Reference, Stimulus, Surface};
use std::path::PathBuf;
use std::time::Instant;

mod quadrature;

#[derive(Debug, Args)]
#[command(after_help = "\
Examples:
  specmap bench --quick
  specmap bench --report bench/        # bench.md, bench.json, grid.png, film.png, render.png")]
pub(crate) struct BenchArgs {
    /// Fewer settings and shorter timings (seconds instead of minutes).
    #[arg(long)]
    quick: bool,
    /// Machine-readable output (every row) on stdout.
    #[arg(long)]
    json: bool,
    /// Folder for bench.md, bench.json and the plots (grid.png, film.png, render.png).
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
    /// Renderer for the sample-count and quadrature rows.
    #[arg(long, value_enum, default_value_t = BackendArg::Auto)]
    backend: BackendArg,
    /// Measure only these sections (default: all).
    #[arg(long, value_enum, value_delimiter = ',', value_name = "SECTION")]
    only: Vec<Section>,
}

/// The sections of the report.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Section {
    /// wavelength step and integration rule
    Grid,
    /// thin films from 100 nm to 10 um
    Film,
    /// upsampling modes
    Mode,
    /// render sample counts
    Render,
    /// quadratures (uniform, Meyer's, the scene's) on every preset and light
    Quadrature,
}

/// One measured setting.
#[derive(Debug, Clone, serde::Serialize)]
struct Row {
    section: &'static str,
    case: String,
    setting: String,
    samples: Option<usize>,
    /// In `time_unit`.
    time: f64,
    time_unit: &'static str,
    #[serde(rename = "mean_dE2000")]
    mean: Option<f64>,
    #[serde(rename = "max_dE2000")]
    max: Option<f64>,
    /// Quadrature rows: the GPU frame (ms), and the estimate the quadrature was chosen by.
    gpu_ms: Option<f64>,
    #[serde(rename = "estimate_dE2000")]
    estimate: Option<f64>,
    note: String,
}

/// What `--report DIR` writes.
const REPORT_FILES: [&str; 5] = [
    "bench.md",
    "bench.json",
    "grid.png",
    "film.png",
    "render.png",
];

const LIGHTS: [&str; 6] = ["D65", "A", "FL2", "FL11", "LED-B3", "lps"];
const RULES: [Rule; 3] = [Rule::Riemann, Rule::Trapezoid, Rule::Simpson];

pub(crate) fn run(a: BenchArgs) -> anyhow::Result<()> {
    // The report folder is checked before the minutes of measuring, not after.
    if let Some(dir) = &a.report {
        if dir.exists() && !dir.is_dir() {
            anyhow::bail!(
                "--report {}: that is a file, not a folder; give a folder for bench.md, \
                 bench.json and the plots",
                dir.display()
            );
        }
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    if let Some(dir) = &a.report {
        let mut guard = super::guard::Guard::new();
        for name in REPORT_FILES {
            guard.output("--report", dir.join(name));
        }
        guard.check()?;
    }
    let t0 = Instant::now();
    let quick = a.quick;
    let wanted = |s: Section| a.only.is_empty() || a.only.contains(&s);
    let gpu = if wanted(Section::Render) || wanted(Section::Quadrature) {
        gpu_for(a.backend)?
    } else {
        None
    };
    let cpu = a.backend != BackendArg::Gpu;
    let mut rows = Vec::new();
    if wanted(Section::Grid) {
        rows.extend(grid_rows(quick)?);
    }
    if wanted(Section::Film) {
        rows.extend(film_rows(quick)?);
    }
    if wanted(Section::Mode) {
        rows.extend(mode_rows(quick)?);
    }
    let mut reports = Vec::new();
    if wanted(Section::Render) {
        reports = render_reports(quick, gpu.as_ref(), cpu)?;
        rows.extend(render_rows(&reports));
    }
    if wanted(Section::Quadrature) {
        rows.extend(quadrature::rows(quick, gpu.as_ref(), cpu)?);
    }

    let seconds = t0.elapsed().as_secs_f64();
    let table = markdown(&rows, seconds, quick);
    let doc = serde_json::json!({
        "quick": quick,
        "seconds": seconds,
        "threads": rayon::current_num_threads(),
        "reference": "380..780 nm at 1 nm, Simpson's rule (render and quadrature: the 1 nm render)",
        "rows": rows,
    });
    if let Some(dir) = &a.report {
        write_report(dir, &table, &doc, &rows, &reports)?;
    }
    if a.json {
        super::emit(&(serde_json::to_string_pretty(&doc)? + "\n"));
    } else {
        super::emit(&table);
    }
    Ok(())
}

/// `--report DIR`: bench.md, bench.json and the plots of the sections measured.
fn write_report(
    dir: &std::path::Path,
    table: &str,
    doc: &serde_json::Value,
    rows: &[Row],
    reports: &[sweep::SweepReport],
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    specmap::io::write_atomic(&dir.join("bench.md"), table.as_bytes())?;
    specmap::io::write_atomic(
        &dir.join("bench.json"),
        (serde_json::to_string_pretty(doc)? + "\n").as_bytes(),
    )?;
    let mut written = vec!["bench.md", "bench.json"];
    if rows.iter().any(|r| r.section == "grid") {
        plot::write(&error_count_figure(rows, "grid"), &dir.join("grid.png"))?;
        written.push("grid.png");
    }
    if rows.iter().any(|r| r.section == "film") {
        plot::write(&film_figure(rows), &dir.join("film.png"))?;
        written.push("film.png");
    }
    if !reports.is_empty() {
        sweep::plot(reports, &dir.join("render.png")).context("writing the render plot")?;
        written.push("render.png");
    }
    eprintln!("wrote {}/{}", dir.display(), written.join(", "));
    Ok(())
}

/// The GPU of `--backend` (auto: if an adapter exists, with a notice when none does).
fn gpu_for(backend: BackendArg) -> anyhow::Result<Option<Gpu>> {
    Ok(match backend {
        BackendArg::Cpu => None,
        BackendArg::Gpu => Some(Gpu::new().context("--backend gpu")?),
        BackendArg::Auto => Gpu::new()
            .map_err(|e| {
                eprintln!(
                    "note: no GPU adapter, the render rows use the CPU renderer: {}",
                    e.to_string().lines().next().unwrap_or_default()
                )
            })
            .ok(),
    })
}

/// Section 1, wavelength step x integration rule, for each light and the ColorChecker under it.
fn grid_rows(quick: bool) -> anyhow::Result<Vec<Row>> {
    let lights: &[&str] = if quick {
        &["D65", "FL2", "lps"]
    } else {
        &LIGHTS
    };
    let mut rows = Vec::new();
    for &name in lights {
        eprintln!("bench: grid and rule, {name}");
        let light = data::spectrum(name)?;
        let stimuli = colorchecker_under(&light.label, &light.data)?;
        let reference = Reference::new(&stimuli, Observer::Cie1931, 380.0, 780.0)?;
        for &step in steps(quick) {
            let grid = WavelengthGrid::new(380.0, 780.0, step)?;
            for rule in RULES {
                rows.push(grid_row(
                    "grid",
                    name,
                    &reference,
                    &stimuli,
                    &grid,
                    rule,
                    min_seconds(quick),
                ));
            }
        }
    }
    Ok(rows)
}

fn steps(quick: bool) -> &'static [f64] {
    if quick {
        &[1.0, 5.0, 10.0, 20.0]
    } else {
        &[1.0, 2.0, 5.0, 10.0, 20.0]
    }
}

fn min_seconds(quick: bool) -> f64 {
    if quick {
        0.005
    } else {
        0.05
    }
}

/// Section 2, thin films from 100 nm to 10 um: a soap-like film (n = 1.33) in air, normal
/// incidence, under D65, coherent at every step (the fringes alias on coarse grids) and with
/// the thin-film module's automatic incoherent fallback.
fn film_rows(quick: bool) -> anyhow::Result<Vec<Row>> {
    let thicknesses: &[f64] = if quick {
        &[100.0, 1000.0, 10000.0]
    } else {
        &[100.0, 300.0, 1000.0, 3000.0, 10000.0]
    };
    let d65 = data::spectrum("D65")?;
    let film = |d: f64, coherence: Coherence| -> anyhow::Result<Surface> {
        Ok(Surface::Film {
            stack: soap_film(d)?,
            incidence: Incidence::degrees(0.0)?,
            coherence,
        })
    };
    let mut rows = Vec::new();
    for &d in thicknesses {
        eprintln!("bench: film {d} nm");
        // The reference is coherent at 1 nm whatever the setting.
        let truth = [Stimulus::new(
            "",
            d65.data.clone(),
            film(d, Coherence::Coherent)?,
        )];
        let reference = Reference::new(&truth, Observer::Cie1931, 380.0, 780.0)?;
        for (coherence, label) in [(Coherence::Coherent, "coherent"), (Coherence::Auto, "auto")] {
            let name = format!("{d} nm film ({label})");
            let stimuli = [Stimulus::new(name, d65.data.clone(), film(d, coherence)?)];
            for &step in steps(quick) {
                let grid = WavelengthGrid::new(380.0, 780.0, step)?;
                let case = format!("{d} nm film, {label}");
                let mut row = grid_row(
                    "film",
                    &case,
                    &reference,
                    &stimuli,
                    &grid,
                    Rule::Riemann,
                    min_seconds(quick),
                );
                row.note = format!(
                    "fringe period at 550 nm about {:.1} nm",
                    550.0 * 550.0 / (2.0 * 1.33 * d)
                );
                rows.push(row);
            }
        }
    }
    Ok(rows)
}

/// Section 3, upsampling modes: the round trip RGB -> SPD -> RGB over an RGB cube.
fn mode_rows(quick: bool) -> anyhow::Result<Vec<Row>> {
    let n = if quick { 9 } else { 17 };
    let grid = WavelengthGrid::new(380.0, 780.0, 5.0)?;
    let lights: &[&str] = if quick {
        &["D65", "FL2"]
    } else {
        &["D65", "A", "FL2", "FL11"]
    };
    let mut rows = Vec::new();
    for &name in lights {
        eprintln!("bench: modes, {name}");
        let input = FitInput::from_names(
            name,
            PAPER_BASIS,
            &grid,
            Observer::Cie1931,
            Rule::Riemann,
            RgbSpace::SRGB,
        )?;
        for mode in [Mode::Paper, Mode::Exact, Mode::Nonneg] {
            let f = fit::fit(&input, mode)?;
            let t = Instant::now();
            let rt = fit::round_trip(&f, n, &RgbSpace::SRGB);
            let us = t.elapsed().as_secs_f64() * 1e6 / rt.colours.max(1) as f64;
            rows.push(Row {
                section: "mode",
                case: name.to_string(),
                setting: format!("{mode:?}").to_lowercase(),
                samples: Some(grid.len()),
                time: us,
                time_unit: "us per colour",
                mean: Some(rt.mean_de2000),
                max: Some(rt.max_de2000),
                gpu_ms: None,
                estimate: None,
                note: format!(
                    "{} colours of a {n}^3 sRGB cube; {:.1}% of SPDs go negative",
                    rt.colours,
                    100.0 * rt.negative_fraction
                ),
            });
        }
    }
    Ok(rows)
}

/// Section 4, render sample counts: the ball preset against its 1 nm render, on each backend.
fn render_reports(
    quick: bool,
    gpu: Option<&Gpu>,
    cpu: bool,
) -> anyhow::Result<Vec<sweep::SweepReport>> {
    eprintln!("bench: render sample counts");
    let (w, h) = if quick { (32, 32) } else { (64, 64) };
    let counts: &[usize] = if quick {
        &[4, 9, 17, 34, 81]
    } else {
        &[4, 9, 17, 34, 81, 340]
    };
    let scene = Preset::Ball.scene(w, h, "D65", None)?;
    let spectral = Spectral::default();
    let repeats = if quick { 1 } else { 3 };
    let mut reports = Vec::new();
    if let Some(g) = gpu {
        reports.push(sweep::sweep(
            &scene,
            &spectral,
            counts,
            Backend::Gpu,
            Some(g),
            repeats,
        )?);
    }
    if cpu {
        reports.push(sweep::sweep(
            &scene,
            &spectral,
            counts,
            Backend::Cpu,
            None,
            repeats,
        )?);
    }
    Ok(reports)
}

fn render_rows(reports: &[sweep::SweepReport]) -> Vec<Row> {
    let mut rows = Vec::new();
    for r in reports {
        let case = match &r.adapter {
            Some(adapter) => format!("ball {}x{}, GPU ({adapter})", r.width, r.height),
            None => format!(
                "ball {}x{}, CPU ({} threads)",
                r.width,
                r.height,
                rayon::current_num_threads()
            ),
        };
        for row in &r.rows {
            rows.push(Row {
                section: "render",
                case: case.clone(),
                setting: format!("{} wavelengths", row.samples),
                samples: Some(row.samples),
                time: row.frame_ms,
                time_unit: "ms per frame",
                mean: Some(row.mean_de2000),
                max: Some(row.max_de2000),
                gpu_ms: None,
                estimate: None,
                note: format!(
                    "step {:.2} nm; 1 nm frame {:.1} ms",
                    row.step_nm, r.reference_frame_ms
                ),
            });
        }
    }
    rows
}

fn soap_film(thickness_nm: f64) -> anyhow::Result<Stack> {
    let air = Material::constant(Index::real(1.0)?);
    Ok(Stack::new(
        air.clone(),
        vec![Layer::new(
            Material::constant(Index::real(1.33)?),
            thickness_nm,
        )?],
        air,
    ))
}

/// A measured grid and rule; a grid that misses a line light altogether is a row that says so.
fn grid_row(
    section: &'static str,
    case: &str,
    reference: &Reference,
    stimuli: &[Stimulus],
    grid: &WavelengthGrid,
    rule: Rule,
    min_s: f64,
) -> Row {
    let setting = format!("{} nm, {rule}", grid.step_nm());
    match measure(reference, stimuli, grid, rule, min_s) {
        Ok(m) => Row {
            section,
            case: case.to_string(),
            setting,
            samples: Some(m.samples),
            time: m.micros_per_colour,
            time_unit: "us per colour",
            mean: Some(m.mean_de2000),
            max: Some(m.max_de2000),
            gpu_ms: None,
            estimate: None,
            note: format!("worst: {}", m.worst),
        },
        Err(e) => Row {
            section,
            case: case.to_string(),
            setting,
            samples: Some(grid.len()),
            time: f64::NAN,
            time_unit: "us per colour",
            mean: None,
            max: None,
            gpu_ms: None,
            estimate: None,
            note: format!("unusable: {e}"),
        },
    }
}

/// A duration for the report: `450 ms`, `8.3 s`, `95 s`, `12 min 5 s` (a quick run of less
/// than half a second is not "0 s").
fn duration(seconds: f64) -> String {
    if !seconds.is_finite() || seconds < 0.0 {
        "-".into()
    } else if seconds < 1.0 {
        format!("{:.0} ms", seconds * 1e3)
    } else if seconds < 10.0 {
        format!("{seconds:.1} s")
    } else if seconds < 120.0 {
        format!("{seconds:.0} s")
    } else {
        let s = seconds.round() as u64;
        format!("{} min {} s", s / 60, s % 60)
    }
}

fn markdown(rows: &[Row], seconds: f64, quick: bool) -> String {
    let mut out = String::new();
    super::outln!(
        out,
        "# specmap bench{}\n\nColour error (CIEDE2000) against 380..780 nm at 1 nm by Simpson's rule \
         (render and quadrature rows: against the 1 nm render), and time, on {} threads; {} in all.\n",
        if quick { " --quick" } else { "" },
        rayon::current_num_threads(),
        duration(seconds)
    );
    for (section, title) in [
        ("grid", "Wavelength step and integration rule (a light and the 24 ColorChecker patches under it)"),
        ("film", "Thin film (n = 1.33 in air, normal incidence, under D65), Riemann rule"),
        ("mode", "Upsampling mode (round trip RGB -> SPD -> RGB, 5 nm)"),
        ("render", "Render sample count (ball preset)"),
    ] {
        let mine: Vec<&Row> = rows.iter().filter(|r| r.section == section).collect();
        if mine.is_empty() {
            continue;
        }
        super::outln!(out, "## {title}\n");
        super::outln!(
            out,
            "| case | setting | samples | time ({}) | mean dE00 | max dE00 | note |",
            mine[0].time_unit
        );
        super::outln!(out, "|---|---|---:|---:|---:|---:|---|");
        let num = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.4}"));
        for r in mine {
            super::outln!(
                out,
                "| {} | {} | {} | {} | {} | {} | {} |",
                r.case,
                r.setting,
                r.samples.map_or("-".into(), |s| s.to_string()),
                if r.time.is_finite() { format!("{:.2}", r.time) } else { "-".into() },
                num(r.mean),
                num(r.max),
                r.note
            );
        }
        out.push('\n');
    }
    if rows.iter().any(|r| r.section == "quadrature") {
        super::outln!(
            out,
            "## Quadratures: uniform (coarsest step at its best rule), Meyer's four wavelengths and \
             the scene's, as `render --tolerance` chooses them\n\nImage error on the CPU against \
             its 1 nm render; frame times are the fastest of the repeats (GPU: compute only).\n"
        );
        out.push_str(&quadrature::markdown(rows));
        out.push('\n');
    }
    out
}

/// log10 of an error, floored so that exact results stay on the plot.
fn log_de(v: f64) -> f64 {
    v.max(1e-6).log10()
}

/// The cases of a section, in order of appearance.
fn cases<'a>(rows: &'a [Row], section: &str) -> Vec<&'a str> {
    let mut cases: Vec<&str> = Vec::new();
    for r in rows.iter().filter(|r| r.section == section) {
        if !cases.contains(&r.case.as_str()) {
            cases.push(&r.case);
        }
    }
    cases
}

/// Max error against wavelength count (time is in the table; it follows the count), one curve
/// per case, for one rule (Riemann) of a section.
fn error_count_figure(rows: &[Row], section: &str) -> Figure {
    let series = cases(rows, section)
        .iter()
        .enumerate()
        .map(|(i, case)| Series {
            label: case.to_string(),
            points: rows
                .iter()
                .filter(|r| {
                    r.section == section && r.case == *case && r.setting.ends_with("riemann")
                })
                .filter_map(|r| Some((r.samples? as f64, log_de(r.max?))))
                .collect(),
            color: plot::palette(i),
        })
        .collect();
    Figure {
        title: "Largest colour error against wavelength count (Riemann rule)".into(),
        x_label: "wavelengths over 380-780 nm (20, 10, 5, 2, 1 nm steps)".into(),
        y_label: "log10 max CIEDE2000 vs 1 nm Simpson".into(),
        series,
    }
}

/// Film error against step, one curve per thickness and coherence; a thickness whose automatic
/// coherence gives the coherent curve exactly is one curve (two would hide one another).
fn film_figure(rows: &[Row]) -> Figure {
    let series = cases(rows, "film")
        .iter()
        .enumerate()
        .map(|(i, case)| Series {
            label: case.to_string(),
            points: rows
                .iter()
                .filter(|r| r.section == "film" && r.case == *case)
                .filter_map(|r| {
                    let step = r.setting.split(' ').next()?.parse::<f64>().ok()?;
                    Some((step, log_de(r.max?)))
                })
                .collect(),
            color: plot::palette(i),
        })
        .collect();
    Figure {
        title: "Thin films: colour error against wavelength step".into(),
        x_label: "wavelength step (nm)".into(),
        y_label: "log10 CIEDE2000 vs 1 nm Simpson (coherent)".into(),
        series: merge_identical(series),
    }
}

/// Curves with the same points become one, labelled `A, x = y` from `A, x` and `A, y`.
fn merge_identical(series: Vec<Series>) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    for s in series {
        let same = |o: &Series| {
            o.points.len() == s.points.len()
                && o.points
                    .iter()
                    .zip(&s.points)
                    .all(|(a, b)| a.0 == b.0 && (a.1 - b.1).abs() <= 1e-9)
        };
        match out.iter_mut().find(|o| same(o)) {
            Some(o) => {
                let tail = match (o.label.rsplit_once(", "), s.label.rsplit_once(", ")) {
                    (Some((a, _)), Some((b, t))) if a == b => t.to_string(),
                    _ => s.label.clone(),
                };
                o.label = format!("{} = {tail}", o.label);
            }
            None => out.push(s),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn film_row(case: &str, step: f64, max: f64) -> Row {
        Row {
            section: "film",
            case: case.into(),
            setting: format!("{step} nm, riemann"),
            samples: None,
            time: 1.0,
            time_unit: "us per colour",
            mean: Some(max),
            max: Some(max),
            gpu_ms: None,
            estimate: None,
            note: String::new(),
        }
    }

    #[test]
    fn a_short_run_is_not_reported_as_zero_seconds() {
        assert_eq!(duration(0.45), "450 ms");
        assert_eq!(duration(8.26), "8.3 s");
        assert_eq!(duration(95.0), "95 s");
        assert_eq!(duration(725.0), "12 min 5 s");
        let header = markdown(&[], 0.45, true);
        assert!(
            header.contains("450 ms in all") && !header.contains(" 0 s"),
            "{header}"
        );
    }

    #[test]
    fn coinciding_film_curves_are_drawn_once() {
        // A thin film is coherent at every step under the automatic rule: same curve.
        let mut rows = Vec::new();
        for (step, e) in [(1.0, 1e-4), (5.0, 1e-2), (20.0, 0.3)] {
            rows.push(film_row("100 nm film, coherent", step, e));
            rows.push(film_row("100 nm film, auto", step, e));
            rows.push(film_row("10000 nm film, coherent", step, 10.0 * e));
            rows.push(film_row("10000 nm film, auto", step, 2.0 * e));
        }
        let fig = film_figure(&rows);
        let labels: Vec<&str> = fig.series.iter().map(|s| s.label.as_str()).collect();
        assert_eq!(
            labels,
            [
                "100 nm film, coherent = auto",
                "10000 nm film, coherent",
                "10000 nm film, auto"
            ]
        );
    }
}
