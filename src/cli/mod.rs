//! Flag definitions and the dispatch to each command.

mod batch;
mod bench;
mod color;
pub(crate) mod convert;
mod data;
mod demo;
pub(crate) mod fit;
mod guard;
pub(crate) mod inspect;
pub(crate) mod render;
pub(crate) mod render_args;
pub(crate) mod render_scene;
mod rendition;
mod roundtrip;
pub(crate) mod runtime_dir;
mod sequence;
pub(crate) mod thinfilm;
mod tolerance;
mod view;

/// `writeln!` into a String (infallible).
macro_rules! outln {
    ($dst:expr, $($arg:tt)*) => {{
        use std::fmt::Write as _;
        let _ = writeln!($dst, $($arg)*);
    }};
}
pub(crate) use outln;

use clap::{Parser, Subcommand, ValueEnum};
use specmap::colorimetry::{Observer, RgbSpace};
use specmap::spectrum::Rule;

const AFTER_HELP: &str = "\
Examples:
  specmap demo -o out/demo          # the whole pipeline as one HTML page (no GPU needed)
  specmap bench --quick --report bench/
  specmap data list
  specmap data show D65 --range 380:780:5 --plot d65.png
  specmap color colorchecker:red --under D65 --json
  specmap color my_lamp.csv
  specmap convert envmaps/sunrise.exr -o sunrise.spectral.exr
  specmap inspect envmaps/sunrise.exr --overlay lights.png
  specmap batch envmaps --out-dir spectral --jobs 2
  specmap fit --light FL2 --mode exact -o fit.json --plot basis.png
  specmap rendition truth.spectral.exr converted.exr --normals up,px,nx,pz,nz
  specmap thinfilm --layers 2.7:270 --substrate 1.45 --json
  specmap render --scene ball --env envmaps/sunrise.exr -o ball.png
  specmap view --scene cylinders --env envmaps/sunrise.exr --tolerance 0.5

A spectrum is a built-in table name (see `specmap data list`), TABLE:COLUMN
(e.g. colorchecker:red) or a CSV file with the header `wavelength_nm,<column>,...`.";

/// Spectral data toolkit and RGB -> spectral environment-map converter.
#[derive(Debug, Parser)]
#[command(name = "specmap", version, about, after_help = AFTER_HELP)]
pub(crate) struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// The whole pipeline on the bundled map as one HTML page: fit, convert, render, trade-off.
    Demo(demo::DemoArgs),
    /// Colour error against time for every speed/accuracy knob: table, JSON and plots.
    Bench(bench::BenchArgs),
    /// List, print and plot the built-in spectral tables (and user CSVs).
    #[command(subcommand, after_help = data::EXAMPLES)]
    Data(data::DataCommand),
    /// Colour of a spectrum: XYZ (paper Eq. 10/11), xy, CCT, linear RGB, 8-bit sRGB, CIELAB.
    Color(color::ColorArgs),
    /// Convert an RGB environment map (EXR/HDR: lat-long, cube, cross, strip or six face files)
    /// to spectral OpenEXR.
    Convert(Box<convert::ConvertArgs>),
    /// The lights a map holds (sun, sky, windows, lamps) and the conversion's plan, drawn over
    /// the map if asked; writes no spectral file.
    Inspect(Box<inspect::InspectArgs>),
    /// Convert a library of maps (files, folders, lists) into one folder: resumable, shardable.
    #[command(after_help = batch::AFTER_HELP)]
    Batch(Box<batch::BatchArgs>),
    /// Fit the paper's basis weights w_R, w_G, w_B for a main light; exact and non-negative modes.
    Fit(fit::FitArgs),
    /// Spectral preview render (Eq. 1 Phong, thin films) of the paper's scenes, GPU or CPU.
    Render(Box<render_args::RenderArgs>),
    /// Colour rendition: ColorChecker patches lit by a spectral map and by its truth (CIEDE2000).
    Rendition(rendition::RenditionArgs),
    /// Integrate a spectral EXR back to RGB and compare with its RGB preview (CIEDE2000).
    Roundtrip(roundtrip::RoundtripArgs),
    /// The renderer in a window: every `render` option live, wavelengths fitted in the
    /// background and reused, a pixel's spectrum on a click, the `render` command of the view.
    View(Box<view::ViewArgs>),
    /// Multilayer thin film: R and T spectra (paper Eq. 2-9, N layers) and the reflected colour.
    Thinfilm(thinfilm::ThinfilmArgs),
}

impl Cli {
    /// Whether the command may open a GPU (and so load the Vulkan loader and its layers).
    pub(crate) fn may_use_gpu(&self) -> bool {
        matches!(
            self.command,
            Command::Demo(_) | Command::Bench(_) | Command::Render(_) | Command::View(_)
        )
    }
}

pub(crate) fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Demo(a) => demo::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Data(c) => data::run(c),
        Command::Color(a) => color::run(a),
        Command::Convert(a) => convert::run(*a),
        Command::Batch(a) => batch::run(*a),
        Command::Fit(a) => fit::run(a),
        Command::Inspect(a) => inspect::run(*a),
        Command::Render(a) => render::run(*a),
        Command::Rendition(a) => rendition::run(a),
        Command::Roundtrip(a) => roundtrip::run(a),
        Command::Thinfilm(a) => thinfilm::run(a),
        Command::View(a) => view::run(*a),
    }
}

/// The options every colour computation shares: observer, wavelength grid, integration rule.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct SpectralArgs {
    /// Standard observer.
    #[arg(long, value_enum, default_value_t = ObserverArg::Cie1931)]
    pub observer: ObserverArg,
    /// Wavelength range START:END:STEP in nm.
    #[arg(long, default_value = "380:780:1")]
    pub range: specmap::spectrum::WavelengthGrid,
    /// Integration rule.
    #[arg(long, value_enum, default_value_t = RuleArg::Riemann)]
    pub rule: RuleArg,
}

/// Appends the XYZ and xy lines of the human-readable colour summaries.
pub(crate) fn write_xyz(out: &mut String, xyz: specmap::colorimetry::Xyz) {
    let xy = xyz.xy();
    outln!(
        out,
        "  XYZ          {:>10.4} {:>10.4} {:>10.4}",
        xyz.x(),
        xyz.y(),
        xyz.z()
    );
    outln!(out, "  xy           {:>10.5} {:>10.5}", xy[0], xy[1]);
}

/// Appends what `--tolerance` chose.
pub(crate) fn write_grid_choice(out: &mut String, c: &specmap::tradeoff::GridChoice) {
    let tried: Vec<String> = c
        .tried
        .iter()
        .map(|(step, de)| format!("{step} nm: {de:.3}"))
        .collect();
    if c.met {
        outln!(
            out,
            "  grid         {} chosen: the coarsest step with CIEDE2000 <= {} against 1 nm \
             Simpson ({:.3}, largest for {}; {} stimuli; tried {})",
            c.grid,
            c.tolerance_de2000,
            c.max_de2000,
            c.worst,
            c.stimuli,
            tried.join(", ")
        );
    } else {
        outln!(
            out,
            "  grid         {}: NO step meets CIEDE2000 <= {}; the finest tried still gives {:.3} \
             (for {}; tried {})",
            c.grid,
            c.tolerance_de2000,
            c.max_de2000,
            c.worst,
            tried.join(", ")
        );
    }
}

/// Appends the 8-bit sRGB line (with its hex code).
pub(crate) fn write_srgb8(out: &mut String, code: [u8; 3]) {
    let [r, g, b] = code;
    outln!(
        out,
        "  sRGB 8-bit   {r:>10} {g:>10} {b:>10}   #{r:02X}{g:02X}{b:02X}"
    );
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum ModeArg {
    /// the paper's three weights (exact for white only)
    Paper,
    /// a full 3x3 matrix: the round trip is exact for every colour (the SPD may go negative)
    Exact,
    /// exact where the SPD stays non-negative, else the non-negative SPD of least CIEDE2000 error
    Nonneg,
}

impl From<ModeArg> for specmap::fit::Mode {
    fn from(m: ModeArg) -> Self {
        match m {
            ModeArg::Paper => specmap::fit::Mode::Paper,
            ModeArg::Exact => specmap::fit::Mode::Exact,
            ModeArg::Nonneg => specmap::fit::Mode::Nonneg,
        }
    }
}

/// CIE standard observers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ObserverArg {
    /// CIE 1931 2-degree
    Cie1931,
    /// CIE 1964 10-degree
    Cie1964,
}

impl From<ObserverArg> for Observer {
    fn from(o: ObserverArg) -> Self {
        match o {
            ObserverArg::Cie1931 => Observer::Cie1931,
            ObserverArg::Cie1964 => Observer::Cie1964,
        }
    }
}

/// Integration rules for the colour integrals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum RuleArg {
    /// h * sum: the paper's rule
    Riemann,
    /// composite trapezoid
    Trapezoid,
    /// composite Simpson (3/8 on the last three intervals when their number is odd)
    Simpson,
}

impl From<RuleArg> for Rule {
    fn from(r: RuleArg) -> Self {
        match r {
            RuleArg::Riemann => Rule::Riemann,
            RuleArg::Trapezoid => Rule::Trapezoid,
            RuleArg::Simpson => Rule::Simpson,
        }
    }
}

/// RGB colour spaces.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum SpaceArg {
    /// sRGB / Rec.709 primaries, D65, matrix derived exactly from the primaries
    Srgb,
    /// sRGB with the paper's rounded Eq. 12 matrix
    SrgbPaper,
    /// ITU-R BT.2020
    Rec2020,
    /// ACES AP1, ACES white (linear, no adaptation applied)
    Acescg,
    /// Display P3
    DisplayP3,
}

impl From<SpaceArg> for RgbSpace {
    fn from(s: SpaceArg) -> Self {
        match s {
            SpaceArg::Srgb => RgbSpace::SRGB,
            SpaceArg::SrgbPaper => RgbSpace::SRGB_PAPER,
            SpaceArg::Rec2020 => RgbSpace::REC2020,
            SpaceArg::Acescg => RgbSpace::ACESCG,
            SpaceArg::DisplayP3 => RgbSpace::DISPLAY_P3,
        }
    }
}

/// Prints to stdout; a closed pipe (`specmap data list | head`) ends the program quietly
/// instead of panicking.
pub(crate) fn emit(text: &str) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_all(text.as_bytes()).and_then(|_| out.flush()) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        eprintln!("error: writing to stdout: {e}");
        std::process::exit(1);
    }
}

/// One round-trip statistic in words (both `convert` and `roundtrip` print it).
pub(crate) fn round_trip_text(s: &specmap::envmap::roundtrip::stats::RoundTripStats) -> String {
    let at = s
        .max_at
        .map(|[x, y]| format!(" at ({x}, {y}), luminance {:.3e}", s.max_luminance))
        .unwrap_or_default();
    let mut t = format!(
        "{} pixels: CIEDE2000 energy-weighted mean {:.4}, max {:.4}{at}",
        s.pixels, s.weighted_mean_de2000, s.max_de2000
    );
    let b = &s.below_floor;
    if b.pixels > 0 {
        t += &format!(
            "; {} below the floor (max {:.4}, {:.2e} of the energy)",
            b.pixels, b.max_de2000, b.energy_share
        );
    }
    if s.black_pixels > 0 {
        t += &format!("; {} black", s.black_pixels);
    }
    t
}

/// The floor of the round-trip statistics in words.
pub(crate) fn floor_text(f: &specmap::envmap::roundtrip::stats::Floor) -> String {
    format!(
        "pixels of luminance {:.3e} or more ({}, {:.3e})",
        f.luminance, f.rule, f.reference_luminance
    )
}

#[cfg(test)]
mod tests {
    use super::Cli;
    use clap::{CommandFactory, Parser};

    /// The `specmap ...` lines of a help text's "Examples:" section, comments removed.
    fn examples(help: &str) -> Vec<String> {
        let Some((_, section)) = help.split_once("Examples:\n") else {
            return Vec::new();
        };
        section
            .lines()
            .take_while(|l| l.starts_with("  "))
            .map(|l| l.split(" #").next().unwrap_or(l).trim().to_string())
            .filter(|l| l.starts_with("specmap "))
            .collect()
    }

    /// Every command and subcommand, as the words after `specmap`, with its long help.
    fn commands(cmd: &clap::Command, path: &[String], out: &mut Vec<(Vec<String>, String)>) {
        for sub in cmd.get_subcommands() {
            let mut p = path.to_vec();
            p.push(sub.get_name().to_string());
            out.push((p.clone(), sub.clone().render_long_help().to_string()));
            commands(sub, &p, out);
        }
    }

    #[test]
    fn every_command_shows_examples_that_parse() {
        let mut root = Cli::command();
        root.build();
        let mut all = vec![(Vec::new(), root.clone().render_long_help().to_string())];
        commands(&root, &[], &mut all);
        let mut missing = Vec::new();
        for (path, help) in all.iter().filter(|(p, _)| !p.iter().any(|c| c == "help")) {
            let name = format!("specmap {}", path.join(" ")).trim_end().to_string();
            let ex = examples(help);
            // At least one example of the command itself (a step before it may show another).
            if !ex.iter().any(|e| e.starts_with(&name)) {
                missing.push(name.clone());
            }
            for e in ex {
                if let Err(err) = Cli::try_parse_from(e.split_whitespace()) {
                    panic!("the example `{e}` of `{name} --help` does not parse:\n{err}");
                }
            }
        }
        assert!(missing.is_empty(), "no examples in --help: {missing:?}");
    }

    #[test]
    fn convert_summary_names_every_input_layout() {
        let root = Cli::command();
        let convert = root.find_subcommand("convert").unwrap();
        let about = convert.get_about().unwrap().to_string();
        for layout in ["lat-long", "cube", "cross", "strip", "six face files"] {
            assert!(about.contains(layout), "{about}");
        }
    }
}
