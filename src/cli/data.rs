//! `specmap data list|show`.

use super::outln;
use anyhow::Context;
use clap::{Args, Subcommand, ValueEnum};
use specmap::colorimetry::{srgb8, Cmfs, Observer, RgbSpace};
use specmap::data::{self, Kind, Table};
use specmap::plot::{self, Figure, Series};
use specmap::spectrum::{Interpolation, Rule, Tabulated, WavelengthGrid};
use std::path::PathBuf;

/// The examples of `specmap data --help`; each subcommand shows its own.
pub(crate) const EXAMPLES: &str = "\
Examples:
  specmap data list
  specmap data show D65 --range 380:780:5 --plot d65.png
  specmap data show colorchecker:red --format json";

#[derive(Debug, Subcommand)]
pub(crate) enum DataCommand {
    /// The built-in tables by kind (cmf, illuminant, light, reflectance).
    #[command(after_help = "\
Examples:
  specmap data list
  specmap data list --json")]
    List {
        /// Machine-readable output.
        #[arg(long)]
        json: bool,
    },
    /// Print a table (or one column) as CSV or JSON, optionally resampled and plotted.
    Show(ShowArgs),
}

#[derive(Debug, Args)]
#[command(after_help = "\
Examples:
  specmap data show D65                          # the published table as CSV
  specmap data show colorchecker:red --format json
  specmap data show FL2 --range 380:780:1 --interp linear --plot fl2.svg
  specmap data show my_lamp.csv --range 400:700:10")]
pub(crate) struct ShowArgs {
    /// TABLE, TABLE:COLUMN or a CSV path.
    name: String,
    /// Resample onto START:END:STEP nm (e.g. 380:780:5); default: the published wavelengths.
    #[arg(long)]
    range: Option<WavelengthGrid>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Csv)]
    format: Format,
    /// Interpolation for --range: default linear for lights, Sprague/spline for the rest.
    #[arg(long, value_enum)]
    interp: Option<InterpArg>,
    /// Also write a plot (.png or .svg).
    #[arg(long, value_name = "OUT")]
    plot: Option<PathBuf>,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum Format {
    Csv,
    Json,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum InterpArg {
    /// piecewise linear (CIE 15 for lights)
    Linear,
    /// Sprague (1880) for uniform data, not-a-knot cubic spline otherwise (CIE 167)
    Cie167,
}

pub(crate) fn run(cmd: DataCommand) -> anyhow::Result<()> {
    match cmd {
        DataCommand::List { json } => list(json),
        DataCommand::Show(a) => show(a),
    }
}

#[derive(serde::Serialize)]
struct Listing {
    name: String,
    kind: Kind,
    columns: Vec<String>,
    start_nm: f64,
    end_nm: f64,
    /// None when the table is not uniformly spaced.
    step_nm: Option<f64>,
    samples: usize,
}

fn list(json: bool) -> anyhow::Result<()> {
    let mut rows = Vec::new();
    for (kind, name) in data::builtin_names() {
        let t = Table::builtin(name)?;
        let w = t.wavelengths_nm();
        let step = t.column_at(0)?.uniform_step_nm();
        rows.push(Listing {
            name: name.to_string(),
            kind,
            columns: t.columns().to_vec(),
            start_nm: w[0],
            end_nm: w[w.len() - 1],
            step_nm: step,
            samples: w.len(),
        });
    }
    if json {
        super::emit(&(serde_json::to_string_pretty(&rows)? + "\n"));
        return Ok(());
    }
    let mut out = String::new();
    let mut current = None;
    for r in &rows {
        if current != Some(r.kind) {
            let n = rows.iter().filter(|x| x.kind == r.kind).count();
            outln!(
                out,
                "{}{} ({n})",
                if current.is_some() { "\n" } else { "" },
                r.kind
            );
            current = Some(r.kind);
        }
        let cols = if r.columns.len() == 1 {
            String::new()
        } else if r.columns.len() <= 3 {
            r.columns.join(",")
        } else {
            format!(
                "{} columns: {}, ...",
                r.columns.len(),
                r.columns[..3].join(", ")
            )
        };
        let step = r
            .step_nm
            .map(|s| format!("{s} nm"))
            .unwrap_or_else(|| "non-uniform".into());
        outln!(
            out,
            "  {:<24} {:>4}-{:<4} nm / {:<7} {cols}",
            r.name,
            r.start_nm,
            r.end_nm,
            step
        );
    }
    outln!(
        out,
        "\nUse TABLE:COLUMN for one column of a multi-column table, e.g. colorchecker:red."
    );
    super::emit(&out);
    Ok(())
}

/// `specmap data show`: the plot's files checked, the table (or its column) read and resampled,
/// the plot, then the values as CSV or JSON.
fn show(a: ShowArgs) -> anyhow::Result<()> {
    if let Some(p) = &a.plot {
        super::guard::Guard::new()
            .spec("", &a.name)
            .output("--plot", p)
            .check()?;
    }
    let shown = read_shown(&a)?;
    if let Some(path) = &a.plot {
        write_plot(&a, &shown, path)?;
    }
    let report = match a.format {
        Format::Csv => shown_csv(&shown),
        Format::Json => serde_json::to_string_pretty(&shown_json(&a, &shown))? + "\n",
    };
    super::emit(&report);
    Ok(())
}

/// The columns `data show` prints, on the wavelengths it prints them at.
struct Shown {
    table: Table,
    /// The one column of TABLE:COLUMN.
    only: Option<usize>,
    /// Each column's name and table.
    columns: Vec<(String, Tabulated)>,
    wavelengths: Vec<f64>,
    /// Each column's values at `wavelengths`.
    values: Vec<Vec<f64>>,
}

/// NAME is a whole table, or TABLE:COLUMN for one column.
fn table_of(name: &str) -> anyhow::Result<(Table, Option<usize>)> {
    Ok(match Table::load(name) {
        Ok(t) => (t, None),
        Err(whole_err) => match name.rsplit_once(':') {
            Some((t, c)) if !t.is_empty() && !c.is_empty() => {
                let t = Table::load(t)?;
                let idx = t.column_index(c)?;
                (t, Some(idx))
            }
            _ => return Err(whole_err.into()),
        },
    })
}

/// The table's columns, resampled onto `--range` (with `--interp`, else the kind's) if given.
fn read_shown(a: &ShowArgs) -> anyhow::Result<Shown> {
    let (table, only) = table_of(&a.name)?;
    let indices: Vec<usize> = match only {
        Some(i) => vec![i],
        None => (0..table.columns().len()).collect(),
    };
    let interp = match (a.interp, table.kind()) {
        (Some(InterpArg::Linear), _) => Interpolation::Linear,
        (Some(InterpArg::Cie167), _) => Interpolation::Cie167,
        (None, Some(Kind::Illuminant | Kind::Light)) => Interpolation::LIGHT,
        (None, _) => Interpolation::SMOOTH,
    };
    let columns: Vec<(String, Tabulated)> = indices
        .iter()
        .map(|&i| Ok((table.columns()[i].clone(), table.column_at(i)?)))
        .collect::<anyhow::Result<_>>()?;
    let wavelengths: Vec<f64> = match &a.range {
        Some(g) => g.wavelengths_nm().collect(),
        None => table.wavelengths_nm().to_vec(),
    };
    let values: Vec<Vec<f64>> = columns
        .iter()
        .map(|(_, t)| match &a.range {
            Some(g) => t.resample(g, interp).values().to_vec(),
            None => t.values().to_vec(),
        })
        .collect();
    Ok(Shown {
        table,
        only,
        columns,
        wavelengths,
        values,
    })
}

/// `--plot`: every column against wavelength, titled and labelled by the table's kind.
fn write_plot(a: &ShowArgs, s: &Shown, path: &std::path::Path) -> anyhow::Result<()> {
    let colors = curve_colors(&s.table, &s.columns)?;
    let series = s
        .columns
        .iter()
        .zip(&s.values)
        .zip(colors)
        .map(|(((name, _), v), color)| Series {
            label: name.clone(),
            points: s
                .wavelengths
                .iter()
                .copied()
                .zip(v.iter().copied())
                .collect(),
            color,
        })
        .collect();
    let y_label = match s.table.kind() {
        Some(Kind::Reflectance) => "Reflectance",
        Some(Kind::Cmf) => "Tristimulus value",
        Some(_) => "Relative spectral power",
        None => "Value",
    };
    let title = match s.only {
        Some(i) => format!("{}:{}", s.table.name(), s.table.columns()[i]),
        None => s.table.name().to_string(),
    };
    plot::write(
        &Figure {
            title,
            x_label: "Wavelength (nm)".into(),
            y_label: y_label.into(),
            series,
        },
        path,
    )
    .with_context(|| format!("writing the plot of {}", a.name))?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// `--format csv`: a `wavelength_nm` column and one per shown column.
fn shown_csv(s: &Shown) -> String {
    let mut out = String::from("wavelength_nm");
    for (n, _) in &s.columns {
        out.push(',');
        out.push_str(n);
    }
    out.push('\n');
    for (i, w) in s.wavelengths.iter().enumerate() {
        out.push_str(&w.to_string());
        for v in &s.values {
            out.push(',');
            out.push_str(&v[i].to_string());
        }
        out.push('\n');
    }
    out
}

/// `--format json`: the table's name and kind, the wavelengths and each column's values.
fn shown_json(a: &ShowArgs, s: &Shown) -> serde_json::Value {
    let cols: serde_json::Map<String, serde_json::Value> = s
        .columns
        .iter()
        .zip(&s.values)
        .map(|((n, _), v)| (n.clone(), serde_json::json!(v)))
        .collect();
    serde_json::json!({
        "name": s.table.name(),
        "kind": s.table.kind().map(|k| k.to_string()),
        "range": a.range.map(|g| g.to_string()),
        "wavelengths_nm": s.wavelengths,
        "columns": cols,
    })
}

/// Reflectances are drawn in their own colour under D65; CMFs as red/green/blue.
fn curve_colors(table: &Table, columns: &[(String, Tabulated)]) -> anyhow::Result<Vec<[u8; 3]>> {
    match table.kind() {
        Some(Kind::Reflectance) => {
            let grid = WavelengthGrid::visible_1nm();
            let cmfs = Cmfs::new(Observer::Cie1931, &grid)?;
            let d65 = Table::builtin("D65")?
                .single_column()?
                .resample(&grid, Interpolation::LIGHT);
            columns
                .iter()
                .map(|(_, t)| {
                    let r = t.resample(&grid, Interpolation::SMOOTH);
                    let xyz = cmfs.reflectance_xyz(&r, &d65, Rule::Riemann)?;
                    // Darken very light patches so the curve stays visible on white.
                    let c = srgb8(RgbSpace::SRGB.rgb_from_xyz(xyz));
                    Ok(c.map(|v| (v as f64 * 0.85) as u8))
                })
                .collect()
        }
        Some(Kind::Cmf) => Ok(vec![[200, 30, 30], [30, 150, 30], [30, 60, 200]]
            .into_iter()
            .cycle()
            .take(columns.len())
            .collect()),
        _ => Ok((0..columns.len()).map(plot::palette).collect()),
    }
}
