//! `specmap demo`: the whole pipeline on the bundled defaults (fit, convert, render, speed for
//! accuracy), written up as one self-contained HTML page with its images.
//!
//! Every step calls the library as the single-purpose commands do, and the page lists the
//! command that reproduces each artefact.

mod page;

use super::fit::{mode_name, write_basis_plot};
use anyhow::Context;
use clap::{Args, ValueEnum};
use specmap::colorimetry::{Cmfs, Observer, RgbSpace};
use specmap::envmap::convert::{self, ConvertOptions, ConvertReport};
use specmap::envmap::roundtrip::heatmap::{choose_range, write_heatmap, Scale};
use specmap::envmap::roundtrip::{round_trip_file, FileRoundTrip};
use specmap::envmap::scene::overlay::write_overlay;
use specmap::envmap::{files, layout};
use specmap::fit::{self, FitInput, Mode};
use specmap::render::gpu::{AdapterReport, Gpu};
use specmap::render::prepare::Prepared;
use specmap::render::{cpu, env, Backend, Lighting, Preset, Spectral};
use specmap::spectrum::{Rule, WavelengthGrid};
use specmap::tradeoff::{self, Measurement, Reference};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The map the demo converts and lights its renders with, relative to the repository root.
const DEFAULT_ENV: &str = "envmaps/sunrise.exr";

/// The lights of the speed-for-accuracy table (smooth, incandescent, fluorescent, LED, a line).
const TRADEOFF_LIGHTS: [&str; 6] = ["D65", "A", "FL2", "FL11", "LED-B3", "lps"];

#[derive(Debug, Args)]
#[command(after_help = "\
Writes DIR/index.html with the fitted basis plot, the converted map's round-trip heatmaps, the
four preset renders and the speed-for-accuracy table, and the command behind each of them.
Open it in a browser. No GPU is needed: without an adapter the CPU renderer draws the images.

Examples:
  specmap demo
  specmap demo -o /tmp/demo --quick
  specmap demo --env envmaps/forest.exr --backend cpu --json")]
pub(crate) struct DemoArgs {
    /// Folder for index.html, its images and the converted maps (created if missing).
    #[arg(short, long, value_name = "DIR", default_value = "out/demo")]
    output: PathBuf,
    /// The RGB environment map (OpenEXR or Radiance .hdr) to convert and light the renders with
    /// [default: envmaps/sunrise.exr of the repository].
    #[arg(long, value_name = "PATH")]
    env: Option<PathBuf>,
    /// Which renderer: the GPU if an adapter exists (auto), or one of them.
    #[arg(long, value_enum, default_value_t = BackendArg::Auto)]
    backend: BackendArg,
    /// Small maps and images and fewer wavelength steps: a first look in a few seconds.
    #[arg(long)]
    quick: bool,
    /// Machine-readable summary of what was written, on stdout.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BackendArg {
    /// the GPU when an adapter exists, else the CPU (with a one-line notice)
    Auto,
    /// wgpu compute; an error without an adapter
    Gpu,
    /// the rayon reference renderer
    Cpu,
}

/// How big the demo's work is.
struct Sizes {
    /// Height of the converted lat-long map (None: the input's).
    map: Option<usize>,
    /// Height of the paper-mode copy.
    paper_map: usize,
    /// Divides every preset's image size.
    shrink: usize,
    /// Riemann steps of the trade-off table, finest first.
    steps: &'static [f64],
    /// Seconds each trade-off timing repeats for, at least.
    min_seconds: f64,
    /// Timings per grid, the fastest kept (the machine may be shared).
    repeats: usize,
}

impl Sizes {
    fn new(quick: bool) -> Sizes {
        if quick {
            Sizes {
                // The sun is still one pixel of its own at 64 rows (at 32 it is not found).
                map: Some(64),
                paper_map: 64,
                shrink: 4,
                steps: &[5.0, 10.0, 20.0],
                min_seconds: 0.002,
                repeats: 1,
            }
        } else {
            Sizes {
                map: None,
                paper_map: 256,
                shrink: 1,
                steps: &[1.0, 2.0, 5.0, 10.0, 20.0],
                min_seconds: 0.02,
                repeats: 3,
            }
        }
    }

    /// A preset's image size: its own aspect ratio, 256 pixels high (the chart's 384x256).
    fn image(&self, p: Preset) -> (usize, usize) {
        let (w, h) = match p {
            Preset::Ball | Preset::Cylinders => (256, 256),
            Preset::TransparentBall => (384, 192),
            Preset::Chart | Preset::CheckerSpheres => (384, 256),
        };
        (w / self.shrink, h / self.shrink)
    }
}

/// One fitted mode and its round trip over the 17^3 RGB grid.
pub(super) struct FitRow {
    pub(crate) fit: fit::Fit,
    pub(crate) round_trip: fit::RoundTrip,
}

/// The lights of the demo's map, drawn over it.
pub(super) struct Inspected {
    pub(crate) lights: Vec<specmap::envmap::scene::Light>,
    pub(crate) overlay: String,
    pub(crate) command: String,
}

/// A converted map and its file round trip.
pub(super) struct Converted {
    pub(crate) report: ConvertReport,
    pub(crate) file: String,
    pub(crate) round_trip: FileRoundTrip,
    pub(crate) heatmap: String,
    pub(crate) command: String,
    pub(crate) roundtrip_command: String,
}

/// One rendered preset.
pub(super) struct Render {
    pub(crate) preset: Preset,
    pub(crate) size: (usize, usize),
    pub(crate) file: String,
    pub(crate) backend: Backend,
    pub(crate) seconds: f64,
    pub(crate) command: String,
}

/// One row of the trade-off table: None where the grid misses the light's lines.
pub(super) struct TradeoffRow {
    pub(crate) light: String,
    pub(crate) step_nm: f64,
    pub(crate) samples: usize,
    pub(crate) rule: Rule,
    pub(crate) measurement: Option<Measurement>,
}

/// Everything the page shows.
pub(super) struct Run {
    pub(crate) quick: bool,
    pub(crate) env: String,
    pub(crate) dir: PathBuf,
    pub(crate) fits: Vec<FitRow>,
    pub(crate) basis_plot: String,
    pub(crate) fit_commands: [String; 2],
    pub(crate) converted: Converted,
    pub(crate) paper: Converted,
    pub(crate) inspected: Inspected,
    pub(crate) renderer: String,
    pub(crate) adapter: Option<AdapterReport>,
    pub(crate) renders: Vec<Render>,
    pub(crate) render_spectral: Spectral,
    pub(crate) tradeoff: Vec<TradeoffRow>,
    /// (step, seconds)
    pub(crate) seconds: Vec<(&'static str, f64)>,
    pub(crate) demo_command: String,
}

/// The demo: where it reads and writes, checked; the renderer; fit, convert, render, trade-off;
/// the page; the summary on stdout.
pub(crate) fn run(a: DemoArgs) -> anyhow::Result<()> {
    let t_all = Instant::now();
    let paths = paths(&a)?;
    let sizes = Sizes::new(a.quick);
    check_outputs(&paths)?;
    check_map(&paths.env)?;
    let (gpu, renderer) = open_renderer(a.backend)?;
    let adapter = gpu.as_ref().map(|g| g.adapter());
    std::fs::create_dir_all(&paths.dir)
        .with_context(|| format!("creating the output folder {}", paths.dir.display()))?;
    let mut seconds = Vec::new();
    let fitted = timed(&mut seconds, "fit", || fit_basis(&paths))?;
    let maps = timed(&mut seconds, "convert", || convert_maps(&paths, &sizes))?;
    let stage = RenderStage {
        paths: &paths,
        sizes: &sizes,
        gpu: gpu.as_ref(),
        backend: a.backend,
        renderer: &renderer,
    };
    let (renders, render_spectral) = timed(&mut seconds, "render", || render_presets(&stage))?;
    let tradeoff = timed(&mut seconds, "trade-off", || measure_tradeoff(&sizes))?;
    let index = paths.out("index.html");
    eprintln!("demo [5/5] page: {}", index.display());
    let demo_command = demo_command(&a);
    seconds.push(("total", t_all.elapsed().as_secs_f64()));
    let run = Run {
        quick: a.quick,
        env: paths.env_str,
        dir: paths.dir,
        fits: fitted.fits,
        basis_plot: fitted.basis_plot,
        fit_commands: fitted.commands,
        converted: maps.converted,
        paper: maps.paper,
        inspected: maps.inspected,
        renderer,
        adapter,
        renders,
        render_spectral,
        tradeoff,
        seconds,
        demo_command,
    };
    specmap::io::write_atomic(&index, page::html(&run).as_bytes())?;
    let total = t_all.elapsed().as_secs_f64();
    let files = files_written(&run);
    let summary = if a.json {
        serde_json::to_string_pretty(&json_summary(&run, &index, &files))? + "\n"
    } else {
        text_summary(&run, &index, files.len(), total)
    };
    super::emit(&summary);
    Ok(())
}

/// Where the demo reads its map and writes its files.
struct Paths {
    /// The RGB map, resolved.
    env: PathBuf,
    /// The same, as text (the page and the commands print it).
    env_str: String,
    /// The output folder.
    dir: PathBuf,
    /// The converted map's file name.
    spectral_name: String,
    /// The paper-mode copy's file name.
    paper_name: String,
}

impl Paths {
    /// A file of the output folder.
    fn out(&self, name: &str) -> PathBuf {
        self.dir.join(name)
    }

    /// A file of the output folder as a shell word.
    fn shown(&self, name: &str) -> String {
        sh(&self.out(name).display().to_string())
    }
}

/// The map (`--env` or the bundled one, UTF-8) and the output folder (a folder if it exists).
fn paths(a: &DemoArgs) -> anyhow::Result<Paths> {
    let env = resolve_env(a.env.as_deref())?;
    let env_str = env
        .to_str()
        .with_context(|| format!("{}: the path is not UTF-8", env.display()))?
        .to_string();
    let dir = a.output.clone();
    if dir.exists() && !dir.is_dir() {
        anyhow::bail!(
            "-o {}: exists and is not a folder; the demo writes index.html and its images into a \
             folder",
            dir.display()
        );
    }
    let stem = file_stem(&env);
    Ok(Paths {
        env,
        env_str,
        dir,
        spectral_name: format!("{stem}.spectral.exr"),
        paper_name: format!("{stem}-paper.spectral.exr"),
    })
}

/// Every file the demo writes, checked against the map before any work.
fn check_outputs(paths: &Paths) -> anyhow::Result<()> {
    let mut guard = super::guard::Guard::new();
    guard.input("--env", &paths.env);
    let mut names = vec![
        "basis.png".to_string(),
        paths.spectral_name.clone(),
        "roundtrip.png".into(),
        paths.paper_name.clone(),
        "roundtrip-paper.png".into(),
    ];
    names.extend(Preset::ALL.map(|p| format!("{}.png", p.name())));
    names.push("index.html".into());
    for name in &names {
        guard.output("-o", paths.out(name));
    }
    guard.folder("-o", &paths.dir).check()
}

/// The map read once up front (a 1024x512 map in ~0.05 s): a file that is not an image, or not
/// an environment layout, fails before anything is written.
fn check_map(env: &Path) -> anyhow::Result<()> {
    let probe = files::read_rgb(env, None)?;
    layout::detect(
        probe.image.width,
        probe.image.height,
        probe.envmap.map(|a| match a {
            files::EnvmapAttr::LatLong => layout::Layout::LatLong,
            files::EnvmapAttr::Cube => layout::Layout::Cube,
        }),
    )
    .with_context(|| format!("--env {}", env.display()))?;
    Ok(())
}

/// The renderer and its name, first: `--backend gpu` without an adapter fails before any work.
fn open_renderer(backend: BackendArg) -> anyhow::Result<(Option<Gpu>, String)> {
    Ok(match backend {
        BackendArg::Cpu => (None, "CPU (--backend cpu)".to_string()),
        BackendArg::Gpu => {
            let g = Gpu::new().context("--backend gpu")?;
            let name = adapter_name(&g);
            (Some(g), name)
        }
        BackendArg::Auto => match Gpu::new() {
            Ok(g) => {
                let name = adapter_name(&g);
                (Some(g), name)
            }
            Err(e) => {
                let e = e.to_string();
                eprintln!(
                    "note: rendering on the CPU: {}",
                    e.lines().next().unwrap_or_default()
                );
                (None, "CPU (no GPU adapter found)".to_string())
            }
        },
    })
}

/// Runs one stage and adds its seconds under `name`.
fn timed<T>(
    seconds: &mut Vec<(&'static str, f64)>,
    name: &'static str,
    stage: impl FnOnce() -> anyhow::Result<T>,
) -> anyhow::Result<T> {
    let t = Instant::now();
    let value = stage()?;
    seconds.push((name, t.elapsed().as_secs_f64()));
    Ok(value)
}

/// The fit stage's results.
struct Fitted {
    /// Paper, exact and nonneg, in that order.
    fits: Vec<FitRow>,
    /// The basis plot's file name.
    basis_plot: String,
    /// The commands behind the table and the plot.
    commands: [String; 2],
}

/// 1. The paper's basis for D65 in the three modes, and its plot.
fn fit_basis(paths: &Paths) -> anyhow::Result<Fitted> {
    eprintln!("demo [1/5] fit: the paper's basis under D65, modes paper, exact and nonneg");
    let grid = WavelengthGrid::new(380.0, 780.0, 1.0)?;
    let input = FitInput::from_names(
        "D65",
        fit::PAPER_BASIS,
        &grid,
        Observer::Cie1931,
        Rule::Riemann,
        RgbSpace::SRGB,
    )?;
    let mut fits = Vec::new();
    for mode in [Mode::Paper, Mode::Exact, Mode::Nonneg] {
        let f = fit::fit(&input, mode)
            .with_context(|| format!("fitting the basis for D65 ({} mode)", mode_name(mode)))?;
        let round_trip = fit::round_trip(&f, 17, &RgbSpace::SRGB);
        fits.push(FitRow { fit: f, round_trip });
    }
    let basis_plot = "basis.png".to_string();
    write_basis_plot(&fits[0].fit, &paths.out(&basis_plot)).context("writing the basis plot")?;
    let commands = [
        "specmap fit --light D65 --mode paper,exact,nonneg".to_string(),
        format!(
            "specmap fit --light D65 --plot {}",
            paths.shown(&basis_plot)
        ),
    ];
    Ok(Fitted {
        fits,
        basis_plot,
        commands,
    })
}

/// The convert stage's results.
struct Maps {
    /// The map converted as `specmap convert --light auto` does.
    converted: Converted,
    /// The small paper-mode copy.
    paper: Converted,
    /// The lights of the map, drawn over it.
    inspected: Inspected,
}

/// 2. The map, converted as `specmap convert --light auto` does, and a small paper-mode copy.
fn convert_maps(paths: &Paths, sizes: &Sizes) -> anyhow::Result<Maps> {
    eprintln!(
        "demo [2/5] convert: {} -> {} (every light of the scene), and a paper-mode copy",
        paths.env.display(),
        paths.out(&paths.spectral_name).display()
    );
    let size = |n: Option<usize>| -> Vec<String> {
        n.map_or(Vec::new(), |n| vec!["--size".into(), n.to_string()])
    };
    let converted = convert_map(
        &paths.env_str,
        &paths.dir,
        &paths.spectral_name,
        "roundtrip.png",
        &size(sizes.map),
    )?;
    let mut paper_flags = vec!["--mode".to_string(), "paper".to_string()];
    paper_flags.extend(size(Some(sizes.paper_map)));
    let paper = convert_map(
        &paths.env_str,
        &paths.dir,
        &paths.paper_name,
        "roundtrip-paper.png",
        &paper_flags,
    )?;
    let inspected = inspect_map(&paths.env_str, &paths.dir, "lights.png")?;
    Ok(Maps {
        converted,
        paper,
        inspected,
    })
}

/// What the render stage works with.
struct RenderStage<'a> {
    paths: &'a Paths,
    sizes: &'a Sizes,
    /// The GPU, when one renders.
    gpu: Option<&'a Gpu>,
    /// `--backend` as given.
    backend: BackendArg,
    /// The renderer in words.
    renderer: &'a str,
}

/// The `--backend` flag as the commands print it (none for auto).
fn backend_flag(backend: BackendArg) -> &'static str {
    match backend {
        BackendArg::Auto => "",
        BackendArg::Gpu => " --backend gpu",
        BackendArg::Cpu => " --backend cpu",
    }
}

/// 3. The presets under the converted map (the chart has its own three lights).
fn render_presets(stage: &RenderStage) -> anyhow::Result<(Vec<Render>, Spectral)> {
    eprintln!(
        "demo [3/5] render: {} on {}",
        Preset::ALL.map(|p| p.name()).join(", "),
        stage.renderer
    );
    let map = stage.paths.out(&stage.paths.spectral_name);
    let (lighting, _) = env::load(&map, "D65")
        .with_context(|| format!("loading the environment {}", map.display()))?;
    let spectral = Spectral::default();
    let mut renders = Vec::new();
    for preset in Preset::ALL {
        renders.push(render_preset(stage, preset, &map, &lighting, &spectral)?);
    }
    Ok((renders, spectral))
}

/// One preset rendered, written as PNG, with the command that draws it again.
fn render_preset(
    stage: &RenderStage,
    preset: Preset,
    map: &Path,
    lighting: &Lighting,
    spectral: &Spectral,
) -> anyhow::Result<Render> {
    let (w, h) = stage.sizes.image(preset);
    let chart = preset == Preset::Chart;
    let scene = preset.scene(w, h, "D65", (!chart).then(|| lighting.clone()))?;
    let t = Instant::now();
    let prepared = Prepared::new(&scene, spectral)
        .with_context(|| format!("preparing the {} scene", preset.name()))?;
    let (image, backend) = match stage.gpu {
        Some(g) => match g.render(&prepared) {
            Ok((image, _)) => (image, Backend::Gpu),
            Err(e) if stage.backend == BackendArg::Auto => {
                eprintln!(
                    "note: the GPU could not render {}, using the CPU: {e}",
                    preset.name()
                );
                (cpu::render(&prepared), Backend::Cpu)
            }
            Err(e) => {
                return Err(e).with_context(|| format!("rendering {}", preset.name()));
            }
        },
        None => (cpu::render(&prepared), Backend::Cpu),
    };
    let file = format!("{}.png", preset.name());
    let path = stage.paths.out(&file);
    image
        .write_png(&path, 0.0)
        .with_context(|| format!("writing {}", path.display()))?;
    let env_flag = if chart {
        String::new()
    } else {
        format!(" --env {}", sh(&map.display().to_string()))
    };
    Ok(Render {
        preset,
        size: (w, h),
        command: format!(
            "specmap render --scene {}{env_flag} --size {w}x{h}{} -o {}",
            preset.name(),
            backend_flag(stage.backend),
            stage.paths.shown(&file)
        ),
        file,
        backend,
        seconds: t.elapsed().as_secs_f64(),
    })
}

/// 4. Speed for accuracy: the ColorChecker under six lights on coarser and coarser grids.
fn measure_tradeoff(sizes: &Sizes) -> anyhow::Result<Vec<TradeoffRow>> {
    let rows = sizes.steps.len() + 1;
    eprintln!(
        "demo [4/5] trade-off: the ColorChecker under {} lights, {rows} grids each, against 1 nm \
         Simpson",
        TRADEOFF_LIGHTS.len()
    );
    tradeoff_table(sizes)
}

/// The command that runs this demo again.
fn demo_command(a: &DemoArgs) -> String {
    let mut command = format!("specmap demo -o {}", sh(&a.output.display().to_string()));
    if let Some(e) = &a.env {
        command += &format!(" --env {}", sh(&e.display().to_string()));
    }
    command += backend_flag(a.backend);
    if a.quick {
        command += " --quick";
    }
    command
}

/// The files of the output folder, in the order the page shows them.
fn files_written(run: &Run) -> Vec<String> {
    let mut files: Vec<String> = vec![run.basis_plot.clone()];
    for c in [&run.converted, &run.paper] {
        files.push(c.file.clone());
        files.push(c.heatmap.clone());
    }
    files.push(run.inspected.overlay.clone());
    files.extend(run.renders.iter().map(|r| r.file.clone()));
    files.push("index.html".into());
    files
}

/// `--json`: what was written and measured.
fn json_summary(run: &Run, index: &Path, files: &[String]) -> serde_json::Value {
    serde_json::json!({
        "index": index.display().to_string(),
        "dir": run.dir.display().to_string(),
        "files": files,
        "env": run.env,
        "quick": run.quick,
        "renderer": run.renderer,
        "adapter": run.adapter,
        "seconds": run.seconds.iter().map(|(k, v)| (k.to_string(), serde_json::Value::from(*v)))
            .collect::<serde_json::Map<_, _>>(),
        "fit": run.fits.iter().map(|r| serde_json::json!({
            "mode": mode_name(r.fit.mode),
            "weights": r.fit.weights,
            "roundtrip": r.round_trip,
        })).collect::<Vec<_>>(),
        "convert": run.converted.report,
        "convert_command": run.converted.command,
        "roundtrip_command": run.converted.roundtrip_command,
        "lights": run.inspected.lights,
        "roundtrip": run.converted.round_trip,
        "roundtrip_paper": run.paper.round_trip,
        "renders": run.renders.iter().map(|r| serde_json::json!({
            "scene": r.preset.name(),
            "file": r.file,
            "size": [r.size.0, r.size.1],
            "backend": r.backend,
            "seconds": r.seconds,
        })).collect::<Vec<_>>(),
        "tradeoff": run.tradeoff.iter().map(tradeoff_json).collect::<Vec<_>>(),
    })
}

/// One trade-off row of `--json`.
fn tradeoff_json(r: &TradeoffRow) -> serde_json::Value {
    serde_json::json!({
        "light": r.light,
        "step_nm": r.step_nm,
        "samples": r.samples,
        "rule": r.rule.to_string(),
        "misses_the_line": r.measurement.is_none(),
        "mean_dE2000": r.measurement.as_ref().map(|m| m.mean_de2000),
        "max_dE2000": r.measurement.as_ref().map(|m| m.max_de2000),
        "worst": r.measurement.as_ref().map(|m| m.worst.clone()),
        "micros_per_colour": r.measurement.as_ref().map(|m| m.micros_per_colour),
    })
}

/// The summary without `--json`: the page, what was done, how many files in how long.
fn text_summary(run: &Run, index: &Path, files: usize, total: f64) -> String {
    let c = &run.converted.report;
    let lights = if c.lights.is_empty() {
        "none found".to_string()
    } else {
        c.lights
            .iter()
            .map(|l| format!("{} {}", format!("{:?}", l.kind).to_lowercase(), l.spd))
            .collect::<Vec<_>>()
            .join(", ")
    };
    format!(
        "wrote {}\ndemo: fitted D65 in 3 modes, converted {} (lights: {lights}), rendered {} \
         presets on {}, measured {} grids; {files} files in {total:.1} s. Open the page in a \
         browser.\n",
        index.display(),
        run.env,
        run.renders.len(),
        run.renderer,
        run.tradeoff.len(),
    )
}

/// The map to convert: `--env`, else envmaps/sunrise.exr here, else the one of the source tree
/// this binary was built from.
fn resolve_env(given: Option<&Path>) -> anyhow::Result<PathBuf> {
    if let Some(p) = given {
        if p.is_file() {
            return Ok(p.to_path_buf());
        }
        anyhow::bail!(
            "--env {}: {}; the demo needs an RGB environment map (OpenEXR or Radiance .hdr, \
             lat-long or cube)",
            p.display(),
            if p.exists() {
                "not a file"
            } else {
                "no such file"
            }
        );
    }
    let here = Path::new(DEFAULT_ENV);
    if here.is_file() {
        return Ok(here.to_path_buf());
    }
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join(DEFAULT_ENV);
    if built.is_file() {
        return Ok(built);
    }
    anyhow::bail!(
        "the demo needs the repository's envmaps/ folder: {DEFAULT_ENV} is neither in the \
         current folder nor at {}. Run it from the repository root, or point it at an RGB map \
         with --env PATH",
        built.display()
    )
}

/// The input's file name without extension, kept to characters safe in file names and links.
fn file_stem(p: &Path) -> String {
    let s: String = p
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() {
        "envmap".into()
    } else {
        s
    }
}

/// The convert flags as `specmap convert` parses them, so that what runs is what the page prints.
#[derive(Debug, clap::Parser)]
struct Flags {
    #[command(flatten)]
    options: super::convert::ConvertOptionArgs,
}

/// `specmap convert INPUT -o DIR/NAME FLAGS...`, then `specmap roundtrip DIR/NAME --heatmap
/// DIR/HEATMAP`: the options parsed from `flags` as the command line would parse them.
fn convert_map(
    input: &str,
    dir: &Path,
    name: &str,
    heatmap: &str,
    flags: &[String],
) -> anyhow::Result<Converted> {
    use clap::Parser;
    let output = dir.join(name);
    let opts =
        Flags::try_parse_from(std::iter::once("convert".to_string()).chain(flags.iter().cloned()))?
            .options
            .to_options()?;
    let report = convert::convert(input, &output, &opts, &|_, _| {})
        .with_context(|| format!("converting {input}"))?;
    let mut de = Vec::new();
    let round_trip = round_trip_file(&output, Observer::Cie1931, Rule::Riemann, Some(&mut de))?;
    // `specmap roundtrip`'s default range: each map's own, stated on its image.
    let heatmap_path = dir.join(heatmap);
    let range = choose_range(&de, Scale::Log, None, None)?;
    write_heatmap(
        &heatmap_path,
        round_trip.width,
        round_trip.height,
        &de,
        &range,
    )?;
    let out = sh(&output.display().to_string());
    let mut command = format!("specmap convert {} -o {out}", sh(input));
    for f in flags {
        command += &format!(" {}", sh(f));
    }
    Ok(Converted {
        report,
        file: name.to_string(),
        round_trip,
        heatmap: heatmap.to_string(),
        command,
        roundtrip_command: format!(
            "specmap roundtrip {out} --heatmap {}",
            sh(&heatmap_path.display().to_string())
        ),
    })
}

/// `specmap inspect INPUT --overlay DIR/NAME`: the lights of the map drawn over it.
fn inspect_map(input: &str, dir: &Path, name: &str) -> anyhow::Result<Inspected> {
    let path = dir.join(name);
    let opts = ConvertOptions::faithful();
    let inspection =
        convert::inspect(input, &opts).with_context(|| format!("inspecting {input}"))?;
    write_overlay(&path, inspection.map(), &inspection.scene)?;
    Ok(Inspected {
        lights: inspection.lights,
        overlay: name.to_string(),
        command: format!(
            "specmap inspect {} --overlay {}",
            sh(input),
            sh(&path.display().to_string())
        ),
    })
}

/// The adapter in words; a software one (lavapipe) is said to run on the CPU.
fn adapter_name(g: &Gpu) -> String {
    let a = g.adapter();
    format!(
        "GPU adapter {} via {}{}",
        a.name,
        a.backend,
        if g.is_software() {
            " (software, on the CPU)"
        } else {
            ""
        }
    )
}

/// The trade-off rows: each light, the Riemann steps and 5 nm Simpson, against 1 nm Simpson.
fn tradeoff_table(sizes: &Sizes) -> anyhow::Result<Vec<TradeoffRow>> {
    let mut grids: Vec<(f64, Rule)> = sizes.steps.iter().map(|&s| (s, Rule::Riemann)).collect();
    grids.push((5.0, Rule::Simpson));
    let mut rows = Vec::new();
    for name in TRADEOFF_LIGHTS {
        let light = specmap::data::spectrum(name)?;
        let stimuli = tradeoff::colorchecker_under(&light.label, &light.data)?;
        let reference = Reference::new(&stimuli, Observer::Cie1931, 380.0, 780.0)
            .with_context(|| format!("the 1 nm reference under {name}"))?;
        for &(step, rule) in &grids {
            let grid = reference
                .grid(step)
                .with_context(|| format!("a {step} nm step does not divide 380..780 nm"))?;
            // The light seen directly comes first: no energy on the grid means it missed the line.
            let cmfs = Cmfs::new(Observer::Cie1931, &grid)?;
            let measurement = if stimuli[0].xyz(&cmfs, rule).is_err() {
                None
            } else {
                let mut best: Option<Measurement> = None;
                for _ in 0..sizes.repeats.max(1) {
                    let m = tradeoff::measure(&reference, &stimuli, &grid, rule, sizes.min_seconds)
                        .with_context(|| format!("{name} at {step} nm ({rule})"))?;
                    if best
                        .as_ref()
                        .is_none_or(|b| m.micros_per_colour < b.micros_per_colour)
                    {
                        best = Some(m);
                    }
                }
                best
            };
            rows.push(TradeoffRow {
                light: light.label.clone(),
                step_nm: step,
                samples: grid.len(),
                rule,
                measurement,
            });
        }
    }
    Ok(rows)
}

/// A word for a POSIX shell: as is when it is plain, else single-quoted.
pub(crate) fn sh(s: &str) -> String {
    let plain = !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-./:=,+@%".contains(c));
    if plain {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shell_words_are_quoted_when_needed() {
        assert_eq!(sh("out/demo"), "out/demo");
        assert_eq!(sh("my maps/a b.exr"), "'my maps/a b.exr'");
        assert_eq!(sh("it's"), r"'it'\''s'");
        assert_eq!(sh(""), "''");
    }

    #[test]
    fn stems_are_safe_in_links() {
        assert_eq!(file_stem(Path::new("envmaps/sunrise.exr")), "sunrise");
        assert_eq!(file_stem(Path::new("a b&<c>.hdr")), "a_b__c_");
        assert_eq!(file_stem(Path::new("/")), "envmap");
    }
}
