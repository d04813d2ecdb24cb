//! `specmap convert`: RGB environment map -> spectral OpenEXR.

use super::{outln, SpaceArg};
use anyhow::Context;
use clap::{Args, ValueEnum};
use specmap::envmap::convert::basis_form::BasisStats;
use specmap::envmap::convert::pixel_spectra::WhitePremise;
use specmap::envmap::convert::{
    self, ConvertOptions, ConvertReport, LightSpec, Lights, Method, OutputFormat, SkySpd, SunSpd,
    WhiteSpec,
};
use specmap::envmap::files::{Compression, Precision};
use specmap::envmap::layout::{Layout, Orientation, Up};
use specmap::envmap::scene::sun::SunSettings;
use specmap::envmap::scene::ReflectorModel;
use specmap::fit::Fit;
use std::io::IsTerminal;
use std::path::PathBuf;

#[derive(Debug, Args)]
#[command(after_help = "\
Layouts: latlong (2:1), cube (OpenEXR's N x 6N), hcross (4:3), vcross (3:4), hstrip (6:1),
vstrip (1:6) and faces (six files); see docs/conversion.md's layout table for each face's orientation.

Examples:
  specmap convert envmaps/sunrise.exr -o sunrise.spectral.exr --light auto
  specmap convert envmaps/forest.exr -o forest.exr --mode exact --precision float
  specmap convert cross.hdr -o cube.exr --in-layout hcross --out-layout cube --size 256
  specmap convert sky_{face}.exr -o sky.exr --in-layout faces
  specmap convert blender.exr -o b.exr --up z --rotation 90
  specmap convert envmaps/sunrise.exr -o s.exr --format basis --tolerance 0.5 --quiet")]
pub(crate) struct ConvertArgs {
    /// Input map: OpenEXR or Radiance .hdr; with --in-layout faces, a pattern with {face}
    /// (px, nx, py, ny, pz, nz).
    input: String,
    /// Output OpenEXR (written to a temporary file, then renamed).
    #[arg(short, long, value_name = "OUT.exr")]
    output: PathBuf,
    #[command(flatten)]
    options: ConvertOptionArgs,
    /// Print nothing but errors: no progress bar, no summary (with --json, the JSON only).
    #[arg(long)]
    quiet: bool,
    /// Machine-readable summary.
    #[arg(long)]
    json: bool,
    /// Threads reading, computing and compressing (default: every core), as `batch --threads`.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    threads: Option<u16>,
}

/// The flags that say how a map is converted (shared by `convert`, `inspect` and `batch`).
#[derive(Debug, Args)]
pub(crate) struct ConvertOptionArgs {
    /// `auto` (the default): every light the scene holds, found and classified (sun, sky,
    /// windows, lamps of their families); a table name or CSV: the spectrum of the lamps (the
    /// sun, sky and windows keep daylight), or with --lights one of every non-sun pixel.
    #[arg(long, default_value = "auto")]
    light: String,
    /// `all`: the scene's lights, each pixel carried by the light(s) that light it; `one`: the
    /// paper's premise, one main light for every pixel but the sun's.
    #[arg(long, value_enum, default_value_t = LightsArg::All)]
    lights: LightsArg,
    /// How reflectors' light is estimated: `local` (from the colour of the reflectors around
    /// each pixel, a local grey world) or `global` (every light in the proportions of its
    /// energy).
    #[arg(long, value_enum, default_value_t = ReflectorsArg::Local)]
    reflectors: ReflectorsArg,
    /// With --reflectors local: how strongly each reflector's mix is pulled towards the global
    /// one (0: its surroundings' colour alone).
    #[arg(long, value_name = "W", default_value_t = specmap::envmap::scene::reflectors::LOCAL_PRIOR)]
    reflector_prior: f64,
    /// What RGB (1,1,1) is: `light` (the map is white-balanced to its main light, the paper's
    /// premise), `space` (the RGB space's own white, unadapted: D65 for sRGB, ACES white for
    /// ACEScg; a sodium lamp looks orange; `d65` is an old name of it), or `auto` (the brightest
    /// regions decide). Default: auto, except `light` for paper/exact/nonneg with a named light.
    #[arg(long, value_enum)]
    white: Option<WhiteArg>,
    /// Sky pixels of daylight colour: `daylight` (the CIE daylight family, S0 S1 S2) or `light`
    /// (the main light's basis). Default: daylight for faithful, light otherwise.
    #[arg(long, value_enum)]
    sky: Option<SkyArg>,
    /// A fit from `specmap fit -o` (its light, basis, mode and space win).
    #[arg(long, value_name = "FIT.json")]
    fit: Option<PathBuf>,
    /// How RGB becomes a spectrum.
    #[arg(long, value_enum, default_value_t = ConvertModeArg::Faithful)]
    mode: ConvertModeArg,
    /// RGB space of the input [default: the one the file's OpenEXR `chromaticities` attribute
    /// declares, else srgb (OpenEXR's Rec.709 with D65)]. Given, it overrides the file's, with a
    /// note when they differ.
    #[arg(long, value_enum)]
    space: Option<SpaceArg>,
    /// Find the sun and give its pixels their own SPD.
    #[arg(long, value_enum, default_value_t = SunArg::Auto)]
    sun: SunArg,
    /// The sun's SPD: `daylight` (the CIE daylight family member of the sun's own colour,
    /// exactly), D65 (the paper), `match` (daylight or Planckian at the sun's CCT), or a light.
    /// Default: daylight for faithful, D65 otherwise.
    #[arg(long)]
    sun_spd: Option<String>,
    /// Input layout (default: the `envmap` attribute, else the aspect ratio).
    #[arg(long, value_enum, default_value_t = InLayout::Auto)]
    in_layout: InLayout,
    /// Output layout.
    #[arg(long, value_enum, default_value_t = OutLayout::Same)]
    out_layout: OutLayout,
    /// Output size: lat-long height or cube face size (default: matched to the input).
    #[arg(long)]
    size: Option<usize>,
    /// The input's up axis: y (OpenEXR, most HDRI sites) or z (a map made for a Z-up world).
    /// The output is always Y up, as OpenEXR's convention has it.
    #[arg(long, value_enum, default_value_t = UpArg::Y)]
    up: UpArg,
    /// Turn the input about the up axis by DEG degrees, counter-clockwise seen from above
    /// (+Z towards +X), e.g. to put the sun where a scene expects it. Resamples the map.
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    rotation: f64,
    /// A named layer of the input (`<layer>.R` ...).
    #[arg(long)]
    layer: Option<String>,
    /// Output wavelengths START:END:STEP in nm.
    #[arg(long, default_value = "380:780:5")]
    range: specmap::spectrum::WavelengthGrid,
    /// Choose the coarsest wavelength step within --range that keeps the ColorChecker under the
    /// main light (and the sun's SPD) within this CIEDE2000 of a 1 nm reference; report it.
    #[arg(long, value_name = "DE")]
    tolerance: Option<f64>,
    /// `spectral`: one channel per wavelength (Fichet 2021) + RGB preview + sun mask; `basis`:
    /// c_R, c_G, c_B, sun with the basis spectra in the header.
    #[arg(long, value_enum, default_value_t = FormatArg::Spectral)]
    format: FormatArg,
    /// Sample precision (half: values over 65504 are scaled by 2^EV, never clipped).
    #[arg(long, value_enum, default_value_t = PrecisionArg::Half)]
    precision: PrecisionArg,
    /// OpenEXR compression.
    #[arg(long, value_enum, default_value_t = CompressionArg::Zip)]
    compression: CompressionArg,
    /// zlib level of zip/zips: 4 is OpenEXR's default (its file sizes); 1 writes faster and
    /// larger files, 12 slower and smaller.
    #[arg(long, default_value_t = specmap::envmap::files::ZIP_DEFAULT_LEVEL,
          value_parser = clap::value_parser!(u8).range(0..=specmap::envmap::files::ZIP_MAX_LEVEL as i64))]
    zip_level: u8,
    /// NaN and infinite pixels are an error (default: set to 0 and counted).
    #[arg(long)]
    strict: bool,
}

/// The largest `--size`: a lat-long height or a cube face (the renderer's limit too).
const MAX_SIZE: usize = 16384;

#[derive(Debug, Clone, Copy, ValueEnum)]
enum LightsArg {
    All,
    One,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum ReflectorsArg {
    Local,
    Global,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum UpArg {
    Y,
    Z,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum ConvertModeArg {
    /// the default: the sun and daylight-coloured sky as CIE daylight of their own colour, the
    /// rest as the main light times a smooth modulation (exact round trip)
    Faithful,
    /// the paper's three weights on the ColorChecker basis (exact for white only)
    Paper,
    /// the ColorChecker basis with a full 3x3 matrix: exact round trip (the SPD may go negative)
    Exact,
    /// exact where the SPD stays non-negative, else the non-negative SPD of least CIEDE2000 error
    Nonneg,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum WhiteArg {
    Light,
    #[value(alias = "d65")]
    Space,
    Auto,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum SkyArg {
    Daylight,
    Light,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum SunArg {
    Auto,
    Off,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum InLayout {
    Auto,
    Latlong,
    Cube,
    Hcross,
    Vcross,
    Hstrip,
    Vstrip,
    /// six files named by a {face} pattern
    Faces,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum OutLayout {
    Same,
    Latlong,
    Cube,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum FormatArg {
    Spectral,
    Basis,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum PrecisionArg {
    Half,
    Float,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum CompressionArg {
    None,
    Rle,
    Zip,
    Zips,
    Piz,
    Pxr24,
    B44,
    B44a,
}

impl ConvertOptionArgs {
    /// The input is six face files named by a `{face}` pattern.
    pub(crate) fn faces(&self) -> bool {
        matches!(self.in_layout, InLayout::Faces)
    }

    /// The `--fit` file, an input of the command.
    pub(crate) fn fit_file(&self) -> Option<&std::path::Path> {
        self.fit.as_deref()
    }

    /// The flags checked and turned into the library's options (a `--fit` file is loaded).
    pub(crate) fn to_options(&self) -> anyhow::Result<ConvertOptions> {
        let a = self;
        a.check_numbers()?;
        let fit = match &a.fit {
            Some(p) => Some(Fit::load(p)?),
            None => None,
        };
        let (mode, method) = a.mode.mode_and_method();
        Ok(ConvertOptions {
            light: if a.light.eq_ignore_ascii_case("auto") {
                LightSpec::Auto
            } else {
                LightSpec::Named(a.light.clone())
            },
            lights: a.lights.into(),
            reflectors: match a.reflectors {
                ReflectorsArg::Local => ReflectorModel::Local {
                    prior: a.reflector_prior,
                },
                ReflectorsArg::Global => ReflectorModel::Global,
            },
            space: a
                .space
                .map_or(specmap::colorimetry::RgbSpace::SRGB, Into::into),
            space_overrides_file: a.space.is_some(),
            fit,
            mode,
            method,
            white: a.white.map(Into::into),
            sky: a.sky.map(Into::into),
            sun: match a.sun {
                SunArg::Auto => Some(SunSettings::default()),
                SunArg::Off => None,
            },
            sun_spd: a.sun_spd.as_deref().map(sun_spd),
            in_layout: a.in_layout.layout(),
            faces: matches!(a.in_layout, InLayout::Faces),
            layer: a.layer.clone(),
            out_layout: a.out_layout.layout(),
            size: a.size,
            orientation: Orientation {
                up: a.up.into(),
                rotation_deg: a.rotation,
            },
            grid: a.range,
            format: a.format.into(),
            precision: a.precision.into(),
            compression: a.compression.into(),
            zip_level: a.zip_level,
            strict: a.strict,
            tolerance: a.tolerance,
            ..ConvertOptions::default()
        })
    }

    /// The numbers clap cannot check: a finite rotation, a prior from 0 to 100, a size in reach.
    fn check_numbers(&self) -> anyhow::Result<()> {
        if !self.rotation.is_finite() {
            anyhow::bail!(
                "--rotation {}: the angle must be a finite number of degrees",
                self.rotation
            );
        }
        if !(self.reflector_prior.is_finite() && (0.0..=100.0).contains(&self.reflector_prior)) {
            anyhow::bail!(
                "--reflector-prior {}: a weight from 0 to 100",
                self.reflector_prior
            );
        }
        if let Some(n) = self.size {
            if n > MAX_SIZE {
                anyhow::bail!(
                    "--size {n}: at most {MAX_SIZE} (a {0}x{MAX_SIZE} lat-long or \
                     {MAX_SIZE}-pixel cube faces already hold billions of values)",
                    2 * MAX_SIZE
                );
            }
        }
        Ok(())
    }
}

/// `--sun-spd`: `d65`, `match`, `daylight`, or any light by name.
fn sun_spd(s: &str) -> SunSpd {
    match s.to_ascii_lowercase().as_str() {
        "d65" => SunSpd::D65,
        "match" => SunSpd::Match,
        "daylight" => SunSpd::Daylight,
        _ => SunSpd::Light(s.to_string()),
    }
}

impl ConvertModeArg {
    /// The fit's mode and the method: `faithful` is the faithful method (its fallback fit
    /// exact), the others the paper's basis method in their mode.
    fn mode_and_method(self) -> (specmap::fit::Mode, Method) {
        use specmap::fit::Mode;
        match self {
            ConvertModeArg::Faithful => (Mode::Exact, Method::Faithful),
            ConvertModeArg::Paper => (Mode::Paper, Method::Basis),
            ConvertModeArg::Exact => (Mode::Exact, Method::Basis),
            ConvertModeArg::Nonneg => (Mode::Nonneg, Method::Basis),
        }
    }
}

impl InLayout {
    /// The layout asked for (None: found from the file, or six face files).
    fn layout(self) -> Option<Layout> {
        match self {
            InLayout::Auto | InLayout::Faces => None,
            InLayout::Latlong => Some(Layout::LatLong),
            InLayout::Cube => Some(Layout::Cube),
            InLayout::Hcross => Some(Layout::HCross),
            InLayout::Vcross => Some(Layout::VCross),
            InLayout::Hstrip => Some(Layout::HStrip),
            InLayout::Vstrip => Some(Layout::VStrip),
        }
    }
}

impl OutLayout {
    /// The output's layout (None: the input's).
    fn layout(self) -> Option<Layout> {
        match self {
            OutLayout::Same => None,
            OutLayout::Latlong => Some(Layout::LatLong),
            OutLayout::Cube => Some(Layout::Cube),
        }
    }
}

impl From<LightsArg> for Lights {
    fn from(a: LightsArg) -> Lights {
        match a {
            LightsArg::All => Lights::All,
            LightsArg::One => Lights::One,
        }
    }
}

impl From<WhiteArg> for WhiteSpec {
    fn from(a: WhiteArg) -> WhiteSpec {
        match a {
            WhiteArg::Light => WhiteSpec::Light,
            WhiteArg::Space => WhiteSpec::Space,
            WhiteArg::Auto => WhiteSpec::Auto,
        }
    }
}

impl From<SkyArg> for SkySpd {
    fn from(a: SkyArg) -> SkySpd {
        match a {
            SkyArg::Daylight => SkySpd::Daylight,
            SkyArg::Light => SkySpd::Light,
        }
    }
}

impl From<UpArg> for Up {
    fn from(a: UpArg) -> Up {
        match a {
            UpArg::Y => Up::Y,
            UpArg::Z => Up::Z,
        }
    }
}

impl From<FormatArg> for OutputFormat {
    fn from(a: FormatArg) -> OutputFormat {
        match a {
            FormatArg::Spectral => OutputFormat::Spectral,
            FormatArg::Basis => OutputFormat::Basis,
        }
    }
}

impl From<PrecisionArg> for Precision {
    fn from(a: PrecisionArg) -> Precision {
        match a {
            PrecisionArg::Half => Precision::Half,
            PrecisionArg::Float => Precision::Float,
        }
    }
}

impl From<CompressionArg> for Compression {
    fn from(a: CompressionArg) -> Compression {
        match a {
            CompressionArg::None => Compression::None,
            CompressionArg::Rle => Compression::Rle,
            CompressionArg::Zip => Compression::Zip,
            CompressionArg::Zips => Compression::Zips,
            CompressionArg::Piz => Compression::Piz,
            CompressionArg::Pxr24 => Compression::Pxr24,
            CompressionArg::B44 => Compression::B44,
            CompressionArg::B44a => Compression::B44a,
        }
    }
}

/// A guard that knows a conversion's inputs: the map (or its face files), the light CSVs and the
/// `--fit` file.
pub(crate) fn input_guard(
    input: &str,
    opts: &ConvertOptions,
    args: &ConvertOptionArgs,
) -> super::guard::Guard {
    let mut guard = super::guard::Guard::new();
    for file in convert::input_files(input, opts) {
        guard.input("", file);
    }
    if let Some(p) = args.fit_file() {
        guard.input("--fit", p);
    }
    guard
}

/// `specmap convert`: check the flags and files, convert with a progress bar, report.
pub(crate) fn run(a: ConvertArgs) -> anyhow::Result<()> {
    let bar = (!a.quiet && std::io::stderr().is_terminal()).then(rows_bar);
    let progress = |done: usize, total: usize| {
        if let Some(b) = &bar {
            // Drawn from the first report on, when the number of rows is known.
            if b.length() != Some(total as u64) {
                b.set_length(total as u64);
                b.set_message("converting");
            }
            b.set_position(done as u64);
        }
    };
    let report = report(&a, &progress)?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    if a.json {
        super::emit(&(serde_json::to_string_pretty(&report)? + "\n"));
    } else if !a.quiet {
        super::emit(&report_text(&report));
    }
    Ok(())
}

/// The flags read, the files checked, the map converted: the report `--json` prints (the
/// Python package's `convert` with an output).
pub(crate) fn report(
    a: &ConvertArgs,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> anyhow::Result<ConvertReport> {
    let opts = a.options.to_options()?;
    check_files(a, &opts)?;
    let work = || {
        convert::convert(&a.input, &a.output, &opts, progress)
            .with_context(|| format!("converting {}", a.input))
    };
    match a.threads {
        // A pool of its own, not the global one: the Python package calls this once per map.
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build()
            .context("--threads: starting the thread pool")?
            .install(work),
        None => work(),
    }
}

/// The inputs exist and are not the output, which is an OpenEXR file that can be written.
fn check_files(a: &ConvertArgs, opts: &ConvertOptions) -> anyhow::Result<()> {
    input_guard(&a.input, opts, &a.options)
        .output("-o", &a.output)
        .check()?;
    let is_exr = a
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr {
        anyhow::bail!(
            "-o {}: convert writes OpenEXR; name the output .exr",
            a.output.display()
        );
    }
    Ok(())
}

/// A progress bar of rows, its length set by the first report.
fn rows_bar() -> indicatif::ProgressBar {
    let b = indicatif::ProgressBar::new(0);
    b.set_style(
        indicatif::ProgressStyle::with_template(
            "{msg} [{bar:40}] {pos}/{len} rows, {elapsed} (eta {eta})",
        )
        .expect("a valid template")
        .progress_chars("=> "),
    );
    b
}

/// The report in words: the input, its space and lights, the premises, the spectra, the file,
/// the round trip and the time.
fn report_text(r: &ConvertReport) -> String {
    let mut out = String::new();
    write_input(&mut out, r);
    write_lights(&mut out, r);
    outln!(
        out,
        "  white        RGB (1,1,1) is {} ({})",
        match r.white.premise {
            WhitePremise::Light => "the main light".to_string(),
            WhitePremise::Space => format!("the space's white, {}, unadapted", r.space.white),
        },
        r.white.reason
    );
    if let Some(c) = &r.grid_choice {
        super::write_grid_choice(&mut out, c);
    }
    if r.mode != "faithful" {
        outln!(
            out,
            "  fit          {} mode, weights {:.4} {:.4} {:.4}, condition {:.3e}{}",
            r.mode,
            r.weights[0],
            r.weights[1],
            r.weights[2],
            r.condition_number,
            if r.regularized { " (reduced)" } else { "" }
        );
    }
    write_spectra(&mut out, r);
    for n in &r.notes {
        outln!(out, "  note         {n}");
    }
    outln!(out, "  sun          {}", sun_text(r));
    outln!(out, "  output       {}", output_text(r));
    if let Some(b) = &r.basis {
        outln!(out, "  basis form   {}", basis_text(b));
    }
    write_round_trip(&mut out, r);
    out
}

/// The input line, what sanitising changed, and the RGB space.
fn write_input(out: &mut String, r: &ConvertReport) {
    outln!(out, "{} -> {}", r.input, r.output);
    outln!(
        out,
        "  input        {} {}x{} ({})",
        r.input_layout.name(),
        r.input_size[0],
        r.input_size[1],
        r.input_description
    );
    if r.sanitized.non_finite + r.sanitized.negative + r.sanitized.negative_kept > 0 {
        outln!(
            out,
            "  sanitized    {} NaN/infinite and {} negative values set to 0; {} negative values \
             of out-of-gamut colours kept",
            r.sanitized.non_finite,
            r.sanitized.negative,
            r.sanitized.negative_kept
        );
    }
    outln!(out, "  space        {}", space_text(&r.space));
}

/// How the basis form holds the spectral form.
fn basis_text(b: &BasisStats) -> String {
    format!(
        "{} spectra of the map's own{}: {:.1e} of the spectral energy outside them, {} pixels \
         held to worse than 1% (worst {:.1}% at ({}, {})){}",
        b.k,
        if b.sun { ", the sun's among them" } else { "" },
        b.discarded,
        b.pixels_over_1_percent,
        100.0 * b.max_residual,
        b.max_residual_at[0],
        b.max_residual_at[1],
        if b.keeps_colour {
            "; every pixel keeps its colour"
        } else {
            ""
        }
    )
}

/// The round trip over all pixels and without the sun, and the time.
fn write_round_trip(out: &mut String, r: &ConvertReport) {
    outln!(
        out,
        "  round trip   over {}",
        super::floor_text(&r.roundtrip_floor)
    );
    outln!(
        out,
        "    all        {}",
        super::round_trip_text(&r.roundtrip)
    );
    outln!(
        out,
        "    no sun     {}",
        super::round_trip_text(&r.roundtrip_without_sun)
    );
    outln!(
        out,
        "  time         read {:.2} s, analyse {:.2} s, plan {:.2} s, convert + write {:.2} s \
         (EXR encoding {:.2} s): {:.1} input Mpixel/s",
        r.seconds_read,
        r.seconds_analyse,
        r.seconds_plan,
        r.seconds_convert,
        r.seconds_encode,
        r.megapixels_per_second
    );
}

/// The lights lines of the report: each light of the scene, or the main light.
fn write_lights(out: &mut String, r: &convert::ConvertReport) {
    match &r.scene_not_analysed {
        Some(why) => outln!(out, "  scene        {why}"),
        None => light_lines(out, &r.lights, &r.bright_reflectors),
    }
    match &r.light_choice {
        Some(c) => outln!(out, "  main light   {} (auto: {})", r.light, c.reason),
        None if r.lights_mode == Lights::One || r.mode != "faithful" => {
            outln!(out, "  main light   {}", r.light)
        }
        None => {}
    }
}

/// A line per light of the scene, then one per bright region that is not a light.
pub(super) fn light_lines(
    out: &mut String,
    lights: &[specmap::envmap::scene::Light],
    bright_reflectors: &[String],
) {
    for l in lights {
        outln!(
            out,
            "  light        {:6} {} ({:.1}% of the energy, {} pixels, {:.1} deg up): {}",
            format!("{:?}", l.kind).to_lowercase(),
            l.spd,
            100.0 * l.energy_share,
            l.pixels,
            l.elevation_deg,
            l.reason
        );
    }
    if lights.is_empty() {
        outln!(out, "  light        none found in the map");
    }
    for b in bright_reflectors {
        outln!(out, "  reflector    {b}");
    }
}

/// The spectra line: which spectrum pixels took, and what could not be exact.
fn write_spectra(out: &mut String, r: &convert::ConvertReport) {
    let sp = &r.spectra;
    outln!(
        out,
        "  spectra      {} ({} carriers{}): {} sun, {} daylight, {} smooth x carrier, {} \
         ColorChecker x carrier, {} non-negative fallback, {} clipped lamp pixels, {} nearest \
         non-negative; {} go negative somewhere",
        r.mode,
        r.carriers.len(),
        if r.carrier_mixes > 0 {
            format!(" and {} mixes of them", r.carrier_mixes)
        } else {
            String::new()
        },
        sp.sun,
        sp.daylight,
        sp.smooth,
        sp.colorchecker,
        sp.nonneg_fallback,
        sp.clipped,
        sp.nearest,
        sp.negative
    );
    if r.inexact.pixels + r.inexact.below_floor.pixels > 0 {
        outln!(
            out,
            "  inexact      could not keep their colour: {}",
            super::round_trip_text(&r.inexact)
        );
    }
}

/// The space line of the report: the space, its primaries and white, and where it comes from.
fn space_text(s: &specmap::envmap::convert::read::SpaceChoice) -> String {
    use specmap::envmap::convert::read::SpaceSource;
    let from = match s.source {
        SpaceSource::File => "declared by the file's chromaticities",
        SpaceSource::Given => "as asked",
        SpaceSource::Default => "the file declares none: OpenEXR's Rec.709 primaries with D65",
    };
    format!("{} ({}; {from})", s.name, s.chromaticities)
}

/// The sun line of the report: where it is, how much energy, the SPD it was given.
pub(super) fn sun_text(r: &convert::ConvertReport) -> String {
    match &r.sun.sun {
        Some(s) => format!(
            "{} pixels, elevation {:.1}°, azimuth {:.1}°, {:.2e} sr, {:.1}% of the energy, {}{} -> \
             {}",
            s.pixel_count,
            s.elevation_deg,
            s.azimuth_deg,
            s.solid_angle_sr,
            100.0 * s.energy_share,
            s.cct_k
                .map(|k| format!("CCT {k:.0} K"))
                .unwrap_or_else(|| "no CCT".into()),
            if s.clipped { ", clipped" } else { "" },
            r.sun_spd.as_deref().unwrap_or("kept")
        ),
        None => format!("none: {}", r.sun.reason),
    }
}

/// The output line of the report: layout, size, channels, wavelengths, encoding, bytes.
pub(super) fn output_text(r: &convert::ConvertReport) -> String {
    format!(
        "{} {}x{}, {} channels ({} wavelengths {}..{} nm), {}, {}{}, {:.1} MB",
        r.output_layout.name(),
        r.output_size[0],
        r.output_size[1],
        r.channels,
        r.wavelengths_nm.len(),
        r.wavelengths_nm.first().unwrap_or(&0.0),
        r.wavelengths_nm.last().unwrap_or(&0.0),
        r.precision,
        r.compression,
        r.ev.map(|e| format!(", values / 2^{e} (EV)"))
            .unwrap_or_default(),
        r.bytes as f64 / 1e6
    )
}
