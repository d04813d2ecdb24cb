//! `specmap bench`: colour error against time for every knob that trades one for the other
//! (wavelength step, integration rule, upsampling mode, thin-film thickness, render sample count),
//! side by side, as a markdown table, JSON and plots.

use super::render::BackendArg;
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

#[derive(Debug, Args)]
#[command(after_help = "\
Examples:
  specmap bench --quick
  specmap bench --report bench/        # bench.md, bench.json, grid.png, film.png, render.png")]
pub struct BenchArgs {
    /// Fewer settings and shorter timings (seconds instead of minutes).
    #[arg(long)]
    quick: bool,
    /// Machine-readable output (every row) on stdout.
    #[arg(long)]
    json: bool,
    /// Folder for bench.md, bench.json and the plots (grid.png, film.png, render.png).
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
    /// Renderer for the sample-count rows.
    #[arg(long, value_enum, default_value_t = BackendArg::Auto)]
    backend: BackendArg,
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

pub fn run(a: BenchArgs) -> anyhow::Result<()> {
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
    let min_s = if quick { 0.005 } else { 0.05 };
    let steps: &[f64] = if quick {
        &[1.0, 5.0, 10.0, 20.0]
    } else {
        &[1.0, 2.0, 5.0, 10.0, 20.0]
    };
    let mut rows = Vec::new();

    // 1. Wavelength step x integration rule, for each light and the ColorChecker under it.
    let lights: &[&str] = if quick {
        &["D65", "FL2", "lps"]
    } else {
        &LIGHTS
    };
    for &name in lights {
        eprintln!("bench: grid and rule, {name}");
        let light = data::spectrum(name)?;
        let stimuli = colorchecker_under(&light.label, &light.data)?;
        let reference = Reference::new(&stimuli, Observer::Cie1931, 380.0, 780.0)?;
        for &step in steps {
            let grid = WavelengthGrid::new(380.0, 780.0, step)?;
            for rule in RULES {
                rows.push(grid_row(
                    "grid", name, &reference, &stimuli, &grid, rule, min_s,
                ));
            }
        }
    }

    // 2. Thin films from 100 nm to 10 um: a soap-like film (n = 1.33) in air, normal incidence,
    // under D65, coherent at every step (the fringes alias on coarse grids) and with the
    // thin-film module's automatic incoherent fallback.
    let thicknesses: &[f64] = if quick {
        &[100.0, 1000.0, 10000.0]
    } else {
        &[100.0, 300.0, 1000.0, 3000.0, 10000.0]
    };
    let d65 = data::spectrum("D65")?;
    for &d in thicknesses {
        eprintln!("bench: film {d} nm");
        for (coherence, label) in [(Coherence::Coherent, "coherent"), (Coherence::Auto, "auto")] {
            let stimuli = vec![Stimulus::new(
                format!("{d} nm film ({label})"),
                d65.data.clone(),
                Surface::Film {
                    stack: soap_film(d)?,
                    incidence: Incidence::degrees(0.0)?,
                    coherence: coherence.clone(),
                },
            )];
            // The reference is coherent at 1 nm whatever the setting.
            let truth = vec![Stimulus {
                surface: Surface::Film {
                    stack: soap_film(d)?,
                    incidence: Incidence::degrees(0.0)?,
                    coherence: Coherence::Coherent,
                },
                ..stimuli[0].clone()
            }];
            let reference = Reference::new(&truth, Observer::Cie1931, 380.0, 780.0)?;
            for &step in steps {
                let grid = WavelengthGrid::new(380.0, 780.0, step)?;
                let mut row = grid_row(
                    "film",
                    &format!("{d} nm film, {label}"),
                    &reference,
                    &stimuli,
                    &grid,
                    Rule::Riemann,
                    min_s,
                );
                row.note = format!(
                    "fringe period at 550 nm about {:.1} nm",
                    550.0 * 550.0 / (2.0 * 1.33 * d)
                );
                rows.push(row);
            }
        }
    }

    // 3. Upsampling modes: the round trip RGB -> SPD -> RGB over an RGB cube.
    let n = if quick { 9 } else { 17 };
    let grid = WavelengthGrid::new(380.0, 780.0, 5.0)?;
    let mode_lights: &[&str] = if quick {
        &["D65", "FL2"]
    } else {
        &["D65", "A", "FL2", "FL11"]
    };
    for &name in mode_lights {
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
                note: format!(
                    "{} colours of a {n}^3 sRGB cube; {:.1}% of SPDs go negative",
                    rt.colours,
                    100.0 * rt.negative_fraction
                ),
            });
        }
    }

    // 4. Render sample counts: the ball preset against its 1 nm render.
    eprintln!("bench: render sample counts");
    let (w, h) = if quick { (32, 32) } else { (64, 64) };
    let counts: &[usize] = if quick {
        &[4, 9, 17, 34, 81]
    } else {
        &[4, 9, 17, 34, 81, 340]
    };
    let scene = Preset::Ball.scene(w, h, "D65", None)?;
    let spectral = Spectral::default();
    let gpu = match a.backend {
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
    };
    let repeats = if quick { 1 } else { 3 };
    let mut reports = Vec::new();
    if gpu.is_some() {
        reports.push(sweep::sweep(
            &scene,
            &spectral,
            counts,
            Backend::Gpu,
            gpu.as_ref(),
            repeats,
        )?);
    }
    if a.backend != BackendArg::Gpu {
        reports.push(sweep::sweep(
            &scene,
            &spectral,
            counts,
            Backend::Cpu,
            None,
            repeats,
        )?);
    }
    for r in &reports {
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
                note: format!(
                    "step {:.2} nm; 1 nm frame {:.1} ms",
                    row.step_nm, r.reference_frame_ms
                ),
            });
        }
    }

    let seconds = t0.elapsed().as_secs_f64();
    let table = markdown(&rows, seconds, quick);
    let doc = serde_json::json!({
        "quick": quick,
        "seconds": seconds,
        "threads": rayon::current_num_threads(),
        "reference": "380..780 nm at 1 nm, Simpson's rule (render: the 1 nm render)",
        "rows": rows,
    });
    if let Some(dir) = &a.report {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        specmap::io::write_atomic(&dir.join("bench.md"), table.as_bytes())?;
        specmap::io::write_atomic(
            &dir.join("bench.json"),
            (serde_json::to_string_pretty(&doc)? + "\n").as_bytes(),
        )?;
        plot::write(&error_count_figure(&rows, "grid"), &dir.join("grid.png"))?;
        plot::write(&film_figure(&rows), &dir.join("film.png"))?;
        sweep::plot(&reports, &dir.join("render.png")).context("writing the render plot")?;
        eprintln!(
            "wrote {0}/bench.md, bench.json, grid.png, film.png, render.png",
            dir.display()
        );
    }
    if a.json {
        super::emit(&(serde_json::to_string_pretty(&doc)? + "\n"));
    } else {
        super::emit(&table);
    }
    Ok(())
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
            note: format!("unusable: {e}"),
        },
    }
}

fn markdown(rows: &[Row], seconds: f64, quick: bool) -> String {
    let mut out = String::new();
    super::outln!(
        out,
        "# specmap bench{}\n\nColour error (CIEDE2000) against 380..780 nm at 1 nm by Simpson's rule \
         (render rows: against the 1 nm render), and time, on {} threads; {seconds:.0} s in all.\n",
        if quick { " --quick" } else { "" },
        rayon::current_num_threads()
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

/// Film error against step, one curve per thickness and coherence.
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
        series,
    }
}
