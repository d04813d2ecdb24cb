//! `specmap thinfilm`: reflectance and transmittance of a multilayer film, and the colour it
//! reflects under a light.

use super::outln;
use anyhow::Context;
use clap::{Args, ValueEnum};
use specmap::colorimetry::{srgb8, Cmfs, Observer, RgbSpace, Xyz};
use specmap::data::{self, Table};
use specmap::plot::{self, Figure, Series};
use specmap::spectrum::{Interpolation, Rule, Spectrum};
use specmap::thinfilm::{
    Coherence, Incidence, Index, Layer, Material, Polarization, Response, Stack,
};
use std::path::PathBuf;

#[derive(Debug, Args)]
#[command(after_help = "\
Indices: 2.7, 3.1+3.3i (k >= 0 absorbs), bk7, fused-silica, cauchy:A:B[:C] and
sellmeier:B1:C1[:B2:C2...] (lambda in micrometres), or a CSV with columns
wavelength_nm,n,k.

Examples:
  specmap thinfilm --layers 2.7:270 --substrate 1.45             # the paper's chrome oxide
  specmap thinfilm --layers 2.3:350 --substrate 1.45 --angle 60 --pol s --json
  specmap thinfilm --layers 1.38:100,2.1:130 --substrate bk7 --plot film.png
  specmap thinfilm --layers 1.33:400 --substrate 1.0 --under A   # a soap film in air")]
pub(crate) struct ThinfilmArgs {
    /// Layers from the ambient side, INDEX:THICKNESS_NM[,INDEX:THICKNESS_NM...]; empty for a bare
    /// interface.
    #[arg(long, value_name = "N:D[,N:D...]", default_value = "")]
    layers: String,
    /// The substrate's index (a metal: e.g. 3.1+3.3i).
    #[arg(long, value_name = "N")]
    substrate: String,
    /// The ambient (incident) medium's index; must be transparent.
    #[arg(long, value_name = "N", default_value = "1.0")]
    ambient: String,
    /// Angle of incidence in degrees from the normal (0 to 90).
    #[arg(long, value_name = "DEG", default_value_t = 0.0)]
    angle: f64,
    /// Polarisation of the incident light.
    #[arg(long, value_enum, default_value_t = PolArg::Unpolarized)]
    pol: PolArg,
    /// Layers whose fringes get fewer than two samples (Nyquist): computed incoherently (auto)
    /// or not.
    #[arg(long, value_enum, default_value_t = CoherenceArg::Auto)]
    coherence: CoherenceArg,
    /// Light under which the reflected colour is computed.
    #[arg(long, value_name = "LIGHT", default_value = "D65")]
    under: String,
    #[command(flatten)]
    spectral: super::SpectralArgs,
    /// Machine-readable output.
    #[arg(long)]
    json: bool,
    /// Also write a plot of R and T (.png or .svg).
    #[arg(long, value_name = "OUT")]
    plot: Option<PathBuf>,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum PolArg {
    /// electric field perpendicular to the plane of incidence (TE)
    S,
    /// electric field in the plane of incidence (TM)
    P,
    /// the mean of s and p
    Unpolarized,
}

impl From<PolArg> for Polarization {
    fn from(p: PolArg) -> Self {
        match p {
            PolArg::S => Polarization::S,
            PolArg::P => Polarization::P,
            PolArg::Unpolarized => Polarization::Unpolarized,
        }
    }
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum CoherenceArg {
    /// incoherent where a layer's fringe period is below two wavelength steps
    Auto,
    /// every layer coherent (thick layers alias)
    Coherent,
}

/// A material from the command line: a number, a complex number, a named formula, a Cauchy or
/// Sellmeier formula, or a table with columns n and k.
fn material(spec: &str) -> anyhow::Result<Material> {
    let s = spec.trim();
    if s.is_empty() {
        anyhow::bail!("an empty refractive index");
    }
    if s.starts_with(|c: char| c.is_ascii_digit() || c == '.' || c == '+' || c == '-') {
        return Ok(Material::Constant(s.parse::<Index>()?));
    }
    if let Some(m) = Material::named(s) {
        return Ok(m);
    }
    let lower = s.to_ascii_lowercase();
    let numbers = |rest: &str| -> anyhow::Result<Vec<f64>> {
        rest.split(':')
            .map(|p| {
                p.trim()
                    .parse::<f64>()
                    .with_context(|| format!("'{spec}': '{p}' is not a number"))
            })
            .collect()
    };
    if let Some(rest) = lower.strip_prefix("cauchy:") {
        let v = numbers(rest)?;
        if !(2..=3).contains(&v.len()) {
            anyhow::bail!("'{spec}': write cauchy:A:B or cauchy:A:B:C (lambda in micrometres)");
        }
        return Ok(Material::cauchy(
            v[0],
            v[1],
            v.get(2).copied().unwrap_or(0.0),
        )?);
    }
    if let Some(rest) = lower.strip_prefix("sellmeier:") {
        let v = numbers(rest)?;
        if v.is_empty() || v.len() % 2 != 0 {
            anyhow::bail!("'{spec}': write sellmeier:B1:C1[:B2:C2...] (C in square micrometres)");
        }
        let terms: Vec<(f64, f64)> = v.chunks(2).map(|c| (c[0], c[1])).collect();
        return Ok(Material::sellmeier(&terms)?);
    }
    let table = Table::load(s).map_err(|e| {
        anyhow::anyhow!(
            "'{spec}' is not an index (2.7, 3.1+3.3i), a named material (bk7, fused-silica), \
             cauchy:A:B[:C], sellmeier:B1:C1[:B2:C2...] or an index table: {e}"
        )
    })?;
    Ok(Material::from_table(&table)?)
}

fn layers(spec: &str) -> anyhow::Result<Vec<Layer>> {
    let spec = spec.trim();
    if spec.is_empty() {
        return Ok(Vec::new());
    }
    spec.split(',')
        .enumerate()
        .map(|(i, part)| {
            let n = i + 1;
            let (m, d) = part.trim().rsplit_once(':').with_context(|| {
                format!("layer {n}: '{part}' must be INDEX:THICKNESS_NM, e.g. 2.7:270")
            })?;
            let d: f64 = d
                .trim()
                .parse()
                .map_err(|_| anyhow::anyhow!("layer {n}: thickness '{d}' is not a number (nm)"))?;
            let m = material(m).map_err(|e| anyhow::anyhow!("layer {n}: {e}"))?;
            Layer::new(m, d).map_err(|e| anyhow::anyhow!("layer {n}: {e}"))
        })
        .collect()
}

/// `specmap thinfilm`: the plot's files checked, the stack's R, T and A, the colour it
/// reflects, the plot; then the report as JSON or text.
pub(crate) fn run(a: ThinfilmArgs) -> anyhow::Result<()> {
    if let Some(p) = &a.plot {
        super::guard::Guard::new()
            .spec_list("--layers", &a.layers)
            .spec("--substrate", &a.substrate)
            .spec("--ambient", &a.ambient)
            .spec("--under", &a.under)
            .output("--plot", p)
            .check()?;
    }
    let film = film_response(&a)?;
    let colour = reflected_colour(&a, &film)?;
    if let Some(path) = &a.plot {
        write_plot(&a, &film, colour.srgb8, path)?;
    }
    let report = match a.json {
        true => serde_json::to_string_pretty(&film_json(&a, &film, &colour))? + "\n",
        false => film_text(&a, &film, &colour),
    };
    super::emit(&report);
    Ok(())
}

/// The stack's response over the grid.
struct Film {
    pol: Polarization,
    /// R, T, the grid and the layers computed incoherently.
    response: Response,
    wavelengths: Vec<f64>,
    /// 1 - R - T.
    absorbed: Vec<f64>,
    /// The incoherent layers, counted from 1.
    incoherent: Vec<usize>,
}

/// The stack of `--ambient`, `--layers` and `--substrate` at `--angle`: R, T and A.
fn film_response(a: &ThinfilmArgs) -> anyhow::Result<Film> {
    let layer_list = layers(&a.layers)?;
    let substrate = material(&a.substrate).map_err(|e| anyhow::anyhow!("substrate: {e}"))?;
    let ambient = material(&a.ambient).map_err(|e| anyhow::anyhow!("ambient: {e}"))?;
    let incidence = Incidence::degrees(a.angle)?;
    let pol = Polarization::from(a.pol);
    let grid = a.spectral.range;
    let stack = Stack::new(ambient, layer_list, substrate);
    let coherence = match a.coherence {
        CoherenceArg::Auto => Coherence::Auto,
        CoherenceArg::Coherent => Coherence::Coherent,
    };
    let response = stack.response(&grid, &incidence, pol, coherence)?;
    let absorbed: Vec<f64> = response
        .reflectance
        .iter()
        .zip(&response.transmittance)
        .map(|(r, t)| {
            // Rounding noise of a lossless stack reads as 0, not -1e-17.
            let a = 1.0 - r - t;
            if a.abs() < 1e-12 {
                0.0
            } else {
                a
            }
        })
        .collect();
    Ok(Film {
        pol,
        wavelengths: grid.wavelengths_nm().collect(),
        absorbed,
        incoherent: response.incoherent_layers.iter().map(|i| i + 1).collect(),
        response,
    })
}

/// The colour the film reflects under `--under`.
struct Reflected {
    /// The light's label.
    light: String,
    observer: Observer,
    rule: Rule,
    xyz: Xyz,
    linear_srgb: [f64; 3],
    srgb8: [u8; 3],
}

/// The film's reflectance under `--under`, integrated with `--observer` and `--rule`.
fn reflected_colour(a: &ThinfilmArgs, film: &Film) -> anyhow::Result<Reflected> {
    let grid = a.spectral.range;
    let rule = Rule::from(a.spectral.rule);
    let observer = Observer::from(a.spectral.observer);
    let cmfs = Cmfs::new(observer, &grid)?;
    let light = data::spectrum(&a.under)?;
    let s = light.data.resample(&grid, Interpolation::LIGHT);
    let r = Spectrum::new(grid, film.response.reflectance.clone())?;
    let xyz = cmfs.reflectance_xyz(&r, &s, rule)?;
    let linear_srgb = RgbSpace::SRGB.rgb_from_xyz(xyz);
    Ok(Reflected {
        light: light.label,
        observer,
        rule,
        xyz,
        linear_srgb,
        srgb8: srgb8(linear_srgb),
    })
}

/// `--plot`: R (in the reflected colour), T and A against wavelength.
fn write_plot(
    a: &ThinfilmArgs,
    film: &Film,
    code: [u8; 3],
    path: &std::path::Path,
) -> anyhow::Result<()> {
    let series = [
        ("R", &film.response.reflectance),
        ("T", &film.response.transmittance),
        ("A", &film.absorbed),
    ]
    .into_iter()
    .enumerate()
    .map(|(i, (label, v))| Series {
        label: label.to_string(),
        points: film
            .wavelengths
            .iter()
            .copied()
            .zip(v.iter().copied())
            .collect(),
        color: if i == 0 { code } else { plot::palette(i) },
    })
    .collect();
    plot::write(
        &Figure {
            title: format!("Thin film {} at {}°, {}", describe(a), a.angle, film.pol),
            x_label: "Wavelength (nm)".into(),
            y_label: "Fraction of incident power".into(),
            series,
        },
        path,
    )
    .context("writing the plot")?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// `--json`: the stack, its spectra and the reflected colour.
fn film_json(a: &ThinfilmArgs, film: &Film, c: &Reflected) -> serde_json::Value {
    serde_json::json!({
        "ambient": a.ambient,
        "layers": a.layers,
        "substrate": a.substrate,
        "angle_deg": a.angle,
        "pol": film.pol,
        "range": a.spectral.range.to_string(),
        "wavelengths_nm": film.wavelengths,
        "R": film.response.reflectance,
        "T": film.response.transmittance,
        "A": film.absorbed,
        "incoherent_layers": film.incoherent,
        "under": c.light,
        "rule": c.rule,
        "XYZ": c.xyz.0,
        "xy": c.xyz.xy(),
        "linear_srgb": c.linear_srgb,
        "srgb8": c.srgb8,
    })
}

/// The report without `--json`: the stack, the reflected colour, then R, T and A per wavelength.
fn film_text(a: &ThinfilmArgs, film: &Film, c: &Reflected) -> String {
    let grid = a.spectral.range;
    let mut out = String::new();
    outln!(
        out,
        "thin film {}\n  {}°, {}, {} nm",
        describe(a),
        a.angle,
        film.pol,
        grid
    );
    if !film.incoherent.is_empty() {
        outln!(
            out,
            "  layer(s) {:?} computed incoherently: their fringes get fewer than two samples \
             at the {} nm step",
            film.incoherent,
            grid.step_nm()
        );
    }
    outln!(
        out,
        "reflected colour under {} ({}, {} rule)",
        c.light,
        c.observer,
        c.rule
    );
    super::write_xyz(&mut out, c.xyz);
    super::write_srgb8(&mut out, c.srgb8);
    outln!(out, "\n  wavelength_nm         R         T         A");
    for (i, w) in film.wavelengths.iter().enumerate() {
        outln!(
            out,
            "  {w:>13} {:>9.6} {:>9.6} {:>9.6}",
            film.response.reflectance[i],
            film.response.transmittance[i],
            film.absorbed[i]
        );
    }
    out
}

/// `1.0 | 2.7:270 | 1.45` for titles.
fn describe(a: &ThinfilmArgs) -> String {
    let mut parts = vec![a.ambient.trim().to_string()];
    parts.extend(
        a.layers
            .split(',')
            .map(|l| l.trim().to_string())
            .filter(|l| !l.is_empty()),
    );
    parts.push(a.substrate.trim().to_string());
    parts.join(" | ")
}
