//! `specmap render`: a spectral preview of the paper's scenes (Eq. 1 Phong, Eq. 2-9 films) on
//! the GPU or the CPU, and the speed-for-accuracy sweep.

use super::outln;
use super::sequence::{film_range, Sequence, SequenceReport};
use super::{ObserverArg, RuleArg};
use anyhow::Context;
use clap::{Args, ValueEnum};
use specmap::colorimetry::RgbSpace;
use specmap::render::gpu::Gpu;
use specmap::render::prepare::Prepared;
use specmap::render::{cpu, env, sweep, Backend, Film, Preset, Scene, Spectral};
use specmap::spectrum::Tabulated;
use specmap::thinfilm::{Index, Layer, Material};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, Clone, Args)]
#[command(after_help = "\
Without --env the scene is lit by a uniform LIGHT and a key light of the same SPD
(transparent-ball: a bright sky over a dark floor). --film/--substrate/--diffuse/--kd/--ks/
--shininess change the scene's main objects (the chart's spheres).

Examples:
  specmap render --scene ball -o ball.png
  specmap render --scene ball --env envmaps/sunrise.exr --samples 81 -o ball.exr
  specmap render --scene cylinders --backend cpu --step 5 --json
  specmap render --scene cylinders --tolerance 0.5 --json   # the fewest wavelengths for CIEDE2000 0.5
  specmap render --scene cylinders --tolerance 0.5 --max-nodes 8   # at most 8: the best 8 if 8 miss
  specmap render --scene ball --light FL2 --quadrature meyer -o meyer.png
  specmap render --scene chart --size 768x512 --exposure -0.5 -o chart.png
  specmap render --scene ball --env envmaps/sunrise.exr --orbit 120,15 --zoom 1.5 -o turned.png
  specmap render --scene ball --film 1.38:100,2.1:130 --substrate bk7 -o coated.png
  specmap render --scene chart --size 384x256 --sweep 4,9,17,34,81,340 --sweep-out sweep/")]
pub(crate) struct RenderArgs {
    /// The scene preset (the paper's figures 6-9).
    #[arg(long, value_enum, default_value_t = SceneArg::Ball)]
    pub(crate) scene: SceneArg,
    /// Environment map: an RGB EXR/HDR (converted on the fly), or a basis or spectral EXR from
    /// `specmap convert`.
    #[arg(long, value_name = "MAP")]
    pub(crate) env: Option<PathBuf>,
    /// What rays that miss every object see: the environment through a 60 degree field of
    /// view (env), the environment straight behind the scene in one colour (flat), or black.
    #[arg(long, value_enum, value_name = "KIND", default_value_t = BackgroundArg::Env)]
    pub(crate) background: BackgroundArg,
    /// Main light: the uniform light without --env, the conversion's light with an RGB map
    /// (a spectral or basis map is lit by the spectra it holds; --light does not apply).
    #[arg(long, value_name = "LIGHT", default_value = "D65")]
    pub(crate) light: String,
    /// Film layers from the air side, INDEX:THICKNESS_NM[,...] (e.g. 2.7:270).
    #[arg(long, value_name = "N:D[,N:D...]")]
    pub(crate) film: Option<String>,
    /// Substrate index under the film (e.g. 1.45, bk7, 3.1+3.3i).
    #[arg(long, value_name = "N")]
    pub(crate) substrate: Option<String>,
    /// Pigment reflectance R_d: TABLE:COLUMN, a CSV, or a constant (e.g. 0.5).
    #[arg(long, value_name = "T:C|CSV")]
    pub(crate) diffuse: Option<String>,
    /// Diffuse coefficient k_d.
    #[arg(long)]
    pub(crate) kd: Option<f64>,
    /// Specular coefficient k_s (without a film).
    #[arg(long)]
    pub(crate) ks: Option<f64>,
    /// Phong exponent n.
    #[arg(long)]
    pub(crate) shininess: Option<f64>,
    /// Image size WxH (default: the preset's).
    #[arg(long, value_name = "WxH")]
    pub(crate) size: Option<String>,
    /// Wavelength step in nm over 380..780 (must divide 400).
    #[arg(long, value_name = "NM", conflicts_with = "samples")]
    pub(crate) step: Option<f64>,
    /// Number of wavelengths over 380..780 nm (default 81: 5 nm).
    #[arg(long, value_name = "N")]
    pub(crate) samples: Option<usize>,
    /// Choose the cheapest quadrature (fewest wavelengths) that keeps every spectrum the scene
    /// can produce (its lights, pigments and films over their angles and thicknesses) within
    /// this CIEDE2000 of the 1 nm render, and report it.
    #[arg(long, value_name = "DE", conflicts_with_all = ["step", "samples"])]
    pub(crate) tolerance: Option<f64>,
    /// With --tolerance: use at most N wavelengths (a renderer's fixed budget, e.g. 4 or 8
    /// SIMD lanes). Where no quadrature that small meets the tolerance, the scene's best N
    /// (searched from fresh starts), reported with how far it misses, on the image too.
    #[arg(long, value_name = "N", requires = "tolerance")]
    pub(crate) max_nodes: Option<usize>,
    /// With --tolerance: fit the wavelengths as `specmap view` does, for every orientation of
    /// the camera and each film's thickness scaled by 1 ± F, or from S0 to S1 times its
    /// thickness (the view's command carries its fit's range, so that `render` fits the same
    /// wavelengths; the view's default is 0.15).
    #[arg(long, value_name = "F|S0:S1", requires = "tolerance")]
    pub(crate) fit_range: Option<String>,
    /// With --tolerance: the most seconds the scene's fit may search (it returns the best
    /// wavelengths found by then). By default a tenth of the time the uniform grid that meets
    /// the tolerance would take for every frame, so that a fit which does not pay costs at most
    /// 10% more; where even that cannot pay, no fit runs. --quadrature scene: no limit.
    #[arg(long, value_name = "SECONDS", requires = "tolerance")]
    pub(crate) fit_budget: Option<f64>,
    /// Neither read nor store the chosen wavelengths in the cache
    /// ($XDG_CACHE_HOME/specmap/quadrature, else ~/.cache/specmap/quadrature).
    #[arg(long)]
    pub(crate) no_cache: bool,
    /// Which wavelengths and weights: `scene` fits them to the scene (needs --tolerance, and is
    /// its default), `uniform` is the --step/--samples grid (or, with --tolerance, the coarsest
    /// step at its best rule), `meyer` is Meyer's four-wavelength Gaussian quadrature.
    #[arg(long, value_enum, value_name = "KIND", conflicts_with = "sweep")]
    pub(crate) quadrature: Option<QuadratureArg>,
    /// Integration rule of the colour integrals.
    #[arg(long, value_enum, default_value_t = RuleArg::Riemann)]
    pub(crate) rule: RuleArg,
    /// Standard observer.
    #[arg(long, value_enum, default_value_t = ObserverArg::Cie1931)]
    pub(crate) observer: ObserverArg,
    /// Which renderer: the GPU if an adapter exists (auto), or one of them.
    #[arg(long, value_enum, default_value_t = BackendArg::Auto)]
    pub(crate) backend: BackendArg,
    /// The camera orbits the scene by YAW and PITCH degrees, the objects turning with it (a
    /// turntable): the map and the sun stay with the world. For a sphere, exactly the camera
    /// orbiting.
    #[arg(long, value_name = "YAW,PITCH", allow_hyphen_values = true)]
    pub(crate) orbit: Option<String>,
    /// Zoom: the view's height divided by F (2 shows half as much, twice as large).
    #[arg(long, value_name = "F")]
    pub(crate) zoom: Option<f64>,
    /// A turntable: N frames orbiting the scene once (from --orbit's yaw, at its pitch), drawn
    /// on one quadrature and written as numbered images (-o turn.png: turn-000.png, ...).
    #[arg(long, value_name = "N", conflicts_with_all = ["sweep", "frames"])]
    pub(crate) turntable: Option<usize>,
    /// A thickness sweep: N frames with the film from its ranges' starts to their ends
    /// (--film 2.7:100..400), on one quadrature, written as numbered images.
    #[arg(long, value_name = "N", conflicts_with = "sweep")]
    pub(crate) frames: Option<usize>,
    /// Exposure in stops applied to the written image.
    #[arg(
        long,
        value_name = "EV",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub(crate) exposure: f64,
    /// Output image: .png (8-bit sRGB) or .exr (linear float).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub(crate) output: Option<PathBuf>,
    /// Machine-readable report on stdout.
    #[arg(long)]
    pub(crate) json: bool,
    /// Instead of one image: the speed-for-accuracy curve at these wavelength counts.
    #[arg(long, value_name = "N,N,...", value_delimiter = ',')]
    pub(crate) sweep: Option<Vec<usize>>,
    /// Folder for the sweep's sweep.md, sweep.json and sweep.png.
    #[arg(long, value_name = "DIR", requires = "sweep")]
    pub(crate) sweep_out: Option<PathBuf>,
    /// Frames per wavelength count in the sweep (the fastest is kept).
    #[arg(long, value_name = "N", default_value_t = 3)]
    pub(crate) repeats: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum BackgroundArg {
    Env,
    Flat,
    None,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum SceneArg {
    /// Fig. 6: chrome-oxide film 270 nm (n 2.7) on black plastic (1.45)
    Ball,
    /// Fig. 7: TiO2 (2.3) on clear plastic (1.45), 150 nm and 350 nm
    TransparentBall,
    /// Fig. 8: chrome oxide, thickness rising from 100 nm (left) to 400 nm (right)
    Cylinders,
    /// Fig. 9: ColorChecker and plastic spheres under D65, A and low-pressure sodium (one row
    /// under --env)
    Chart,
    /// The 24 ColorChecker reflectances as Lambertian spheres, 6 x 4
    CheckerSpheres,
}

impl From<SceneArg> for Preset {
    fn from(s: SceneArg) -> Self {
        match s {
            SceneArg::Ball => Preset::Ball,
            SceneArg::TransparentBall => Preset::TransparentBall,
            SceneArg::Cylinders => Preset::Cylinders,
            SceneArg::Chart => Preset::Chart,
            SceneArg::CheckerSpheres => Preset::CheckerSpheres,
        }
    }
}

/// `--quadrature`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum QuadratureArg {
    /// fitted to the scene's spectra (with --tolerance)
    Scene,
    /// a uniform grid and integration rule
    Uniform,
    /// Meyer's (1988) four-wavelength Gaussian quadrature
    Meyer,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum BackendArg {
    /// the GPU when an adapter exists, else the CPU (with a one-line notice)
    Auto,
    /// wgpu compute; an error without an adapter
    Gpu,
    /// the rayon reference renderer
    Cpu,
}

fn index(spec: &str, what: &str) -> anyhow::Result<Material> {
    let s = spec.trim();
    if let Some(m) = Material::named(s) {
        return Ok(m);
    }
    let i: Index = s.parse().with_context(|| {
        format!("{what} '{spec}' is not an index (2.7, 3.1+3.3i) or a named material (bk7)")
    })?;
    Ok(Material::constant(i))
}

fn film_layers(spec: &str) -> anyhow::Result<Vec<Layer>> {
    spec.split(',')
        .filter(|p| !p.trim().is_empty())
        .enumerate()
        .map(|(i, part)| {
            let n = i + 1;
            let (m, d) = part.trim().rsplit_once(':').with_context(|| {
                format!("film layer {n}: '{part}' must be INDEX:THICKNESS_NM, e.g. 2.7:270")
            })?;
            let d: f64 = d.trim().parse().map_err(|_| {
                anyhow::anyhow!("film layer {n}: thickness '{d}' is not a number (nm)")
            })?;
            Ok(Layer::new(index(m, &format!("film layer {n}"))?, d)?)
        })
        .collect()
}

fn size(spec: &str) -> anyhow::Result<(usize, usize)> {
    let (w, h) = spec
        .split_once(['x', 'X'])
        .with_context(|| format!("--size '{spec}' must be WxH, e.g. 512x512"))?;
    let p = |v: &str| -> anyhow::Result<usize> {
        v.trim()
            .parse()
            .map_err(|_| anyhow::anyhow!("--size '{spec}': '{v}' is not a whole number"))
    };
    Ok((p(w)?, p(h)?))
}

fn diffuse(spec: &str) -> anyhow::Result<Tabulated> {
    if let Ok(v) = spec.trim().parse::<f64>() {
        if !(0.0..=1.0).contains(&v) {
            anyhow::bail!("--diffuse {v}: a constant reflectance must be between 0 and 1");
        }
        return Ok(Tabulated::new(vec![380.0, 780.0], vec![v, v])?);
    }
    Ok(specmap::data::spectrum(spec)?.data)
}

/// The options that take no value ([`RenderArgs::to_pairs`] gives them an empty one).
pub(crate) const FLAGS: [&str; 2] = ["no-cache", "json"];

/// `RenderArgs` parsed alone (for [`RenderArgs::parse_pairs`]).
#[derive(Debug, clap::Parser)]
#[command(name = "specmap render")]
struct RenderOnly {
    #[command(flatten)]
    args: RenderArgs,
}

impl RenderArgs {
    /// The options as `specmap render` spells them, `(long name, value)`, each one set away
    /// from its default (a flag's value is empty), in the order `--help` lists them.
    pub(crate) fn to_pairs(&self) -> Vec<(&'static str, String)> {
        fn name<T: ValueEnum>(v: &T) -> String {
            v.to_possible_value()
                .map_or(String::new(), |p| p.get_name().to_string())
        }
        let mut out: Vec<(&'static str, String)> = Vec::new();
        let mut opt = |k: &'static str, v: Option<String>| {
            if let Some(v) = v {
                out.push((k, v));
            }
        };
        let path = |p: &Option<PathBuf>| p.as_ref().map(|p| p.display().to_string());
        let num = |v: Option<f64>| v.map(|v| v.to_string());
        opt(
            "scene",
            (self.scene != SceneArg::Ball).then(|| name(&self.scene)),
        );
        opt("env", path(&self.env));
        opt(
            "background",
            (self.background != BackgroundArg::Env).then(|| name(&self.background)),
        );
        opt("light", (self.light != "D65").then(|| self.light.clone()));
        opt("film", self.film.clone());
        opt("substrate", self.substrate.clone());
        opt("diffuse", self.diffuse.clone());
        opt("kd", num(self.kd));
        opt("ks", num(self.ks));
        opt("shininess", num(self.shininess));
        opt("size", self.size.clone());
        opt("step", num(self.step));
        opt("samples", self.samples.map(|v| v.to_string()));
        opt("tolerance", num(self.tolerance));
        opt("max-nodes", self.max_nodes.map(|v| v.to_string()));
        opt("fit-range", self.fit_range.clone());
        opt("fit-budget", num(self.fit_budget));
        opt("no-cache", self.no_cache.then(String::new));
        opt("quadrature", self.quadrature.map(|q| name(&q)));
        opt(
            "rule",
            (self.rule != RuleArg::Riemann).then(|| name(&self.rule)),
        );
        opt(
            "observer",
            (self.observer != ObserverArg::Cie1931).then(|| name(&self.observer)),
        );
        opt(
            "backend",
            (self.backend != BackendArg::Auto).then(|| name(&self.backend)),
        );
        opt("turntable", self.turntable.map(|v| v.to_string()));
        opt("frames", self.frames.map(|v| v.to_string()));
        opt("orbit", self.orbit.clone());
        opt("zoom", num(self.zoom));
        opt(
            "exposure",
            (self.exposure != 0.0).then(|| self.exposure.to_string()),
        );
        opt("output", path(&self.output));
        out
    }

    /// The options `pairs` give (as [`RenderArgs::to_pairs`] writes them), parsed and checked
    /// as `specmap render` parses its command line.
    pub(crate) fn parse_pairs<'a>(
        pairs: impl IntoIterator<Item = (&'a str, &'a str)>,
    ) -> anyhow::Result<RenderArgs> {
        let mut argv = vec!["specmap render".to_string()];
        for (k, v) in pairs {
            argv.push(match FLAGS.contains(&k) {
                true => format!("--{k}"),
                false => format!("--{k}={v}"),
            });
        }
        let r = <RenderOnly as clap::Parser>::try_parse_from(&argv).map_err(|e| {
            let text = e.to_string();
            anyhow::anyhow!(
                "{}",
                text.lines()
                    .next()
                    .unwrap_or("invalid option")
                    .trim_start_matches("error: ")
            )
        })?;
        Ok(r.args)
    }

    pub(crate) fn preset(&self) -> Preset {
        Preset::from(self.scene)
    }

    /// The image size: `--size` or the preset's.
    pub(crate) fn image_size(&self) -> anyhow::Result<(usize, usize)> {
        match &self.size {
            Some(s) => size(s),
            None => Ok(self.preset().default_size()),
        }
    }
}

/// `specmap render`: the options and files checked, the scene, the backend and the quadrature;
/// then the sweep, the sequence or the one image, and its report.
pub(crate) fn run(mut a: RenderArgs) -> anyhow::Result<()> {
    check_numbers(&a)?;
    let preset = Preset::from(a.scene);
    let size = a.image_size()?;
    check_light(&a, preset)?;
    let output = a
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("render-{}.png", preset.name())));
    let sequence = take_sequence(&mut a)?;
    check_files(&a, sequence.as_ref(), &output)?;
    let (lighting, env_report) = load_env(&a)?.unzip();
    let scene = scene_from(&a, preset, size, lighting)?;
    let spectral = spectral_of(&a)?;
    let gpu = open_gpu(a.backend)?;
    let job = Job {
        a: &a,
        preset,
        size,
        scene: &scene,
        spectral: &spectral,
        backend: if gpu.is_some() {
            Backend::Gpu
        } else {
            Backend::Cpu
        },
        gpu: gpu.as_ref(),
        output: &output,
    };
    let chosen = choose_quadrature(&job, sequence.as_ref())?;
    if let Some(counts) = &a.sweep {
        return run_sweep(&job, counts);
    }
    if let Some(seq) = &sequence {
        return render_sequence(&job, seq, chosen);
    }
    let single = render_single(&job, chosen)?;
    let report = match a.json {
        true => {
            serde_json::to_string_pretty(&single_json(&job, &single, env_report.as_ref()))? + "\n"
        }
        false => single_text(&job, &single, env_report.as_ref()),
    };
    super::emit(&report);
    Ok(())
}

/// `--exposure` within 64 stops and `--repeats` at least 1.
fn check_numbers(a: &RenderArgs) -> anyhow::Result<()> {
    if !(a.exposure.is_finite() && a.exposure.abs() <= 64.0) {
        anyhow::bail!(
            "--exposure {}: stops must be between -64 and 64",
            a.exposure
        );
    }
    if a.repeats == 0 {
        anyhow::bail!("--repeats 0: the sweep needs at least one frame per wavelength count");
    }
    Ok(())
}

/// The chart brings its own three lights: `--light` applies to it only with `--env`.
fn check_light(a: &RenderArgs, preset: Preset) -> anyhow::Result<()> {
    if preset == Preset::Chart && a.env.is_none() && a.light != "D65" {
        anyhow::bail!("the chart compares D65, A and low-pressure sodium side by side; --light does not apply to it (--env lights one row of it)");
    }
    Ok(())
}

/// A sequence: the film at its ranges' starts, and the scene as built (each frame orbits it or
/// scales its films); `a` keeps the film's start and, for a turntable, no `--orbit`.
fn take_sequence(a: &mut RenderArgs) -> anyhow::Result<Option<Sequence>> {
    let (film, ratio) = a.film.as_deref().map(film_range).transpose()?.unzip();
    a.film = film;
    let sequence = Sequence::of(a, ratio.flatten())?;
    if matches!(sequence, Some(Sequence::Turntable { .. })) {
        a.orbit = None;
    }
    Ok(sequence)
}

/// The files read and written (the sweep's, the sequence's frames or the one image), checked
/// before any work.
fn check_files(
    a: &RenderArgs,
    sequence: Option<&Sequence>,
    output: &std::path::Path,
) -> anyhow::Result<()> {
    let mut guard = super::guard::Guard::new();
    if let Some(p) = &a.env {
        guard.input("--env", p);
    }
    guard.spec("--light", &a.light);
    if let Some(d) = &a.diffuse {
        guard.spec("--diffuse", d);
    }
    match (&a.sweep, &a.sweep_out) {
        (Some(_), Some(dir)) => {
            guard.folder("--sweep-out", dir);
            for name in ["sweep.md", "sweep.json", "sweep.png"] {
                guard.output("--sweep-out", dir.join(name));
            }
        }
        (Some(_), None) => {}
        (None, _) => match sequence {
            Some(seq) => {
                for k in 0..seq.frames() {
                    guard.output("-o", seq.file(output, k));
                }
            }
            None => {
                guard.output("-o", output);
            }
        },
    }
    guard.check()
}

/// The GPU of `--backend`: none for cpu, an error without an adapter for gpu, and for auto the
/// CPU with a notice when there is none.
fn open_gpu(backend: BackendArg) -> anyhow::Result<Option<Gpu>> {
    Ok(match backend {
        BackendArg::Cpu => None,
        BackendArg::Gpu => Some(Gpu::new().context("--backend gpu")?),
        BackendArg::Auto => match Gpu::new() {
            Ok(g) => Some(g),
            Err(e) => {
                let first = e.to_string();
                let first = first.lines().next().unwrap_or_default().to_string();
                eprintln!("note: falling back to the CPU renderer: {first}");
                None
            }
        },
    })
}

/// What a render works with once the options are read.
struct Job<'a> {
    a: &'a RenderArgs,
    preset: Preset,
    /// The image size, WxH.
    size: (usize, usize),
    /// The scene as built (a sequence's frames orbit it or scale its films).
    scene: &'a Scene,
    spectral: &'a Spectral,
    backend: Backend,
    gpu: Option<&'a Gpu>,
    /// The image, or the pattern of a sequence's frames.
    output: &'a std::path::Path,
}

/// The quadrature, for every frame's scene and the view's range, and what choosing it measured
/// (the first frame, on which a frame's cost is measured and, on the CPU, prepared once).
fn choose_quadrature(
    job: &Job,
    sequence: Option<&Sequence>,
) -> anyhow::Result<super::tolerance::Chosen> {
    let first = match sequence {
        Some(seq) => seq.frame(job.scene, 0)?,
        None => job.scene.clone(),
    };
    let serving = super::tolerance::Serving {
        gpu: job.gpu,
        frames: sequence.map_or(1, Sequence::frames),
        first: &first,
    };
    let mut fit_scene = match sequence {
        Some(seq) => seq.fit_scene(job.scene),
        None => job.scene.clone(),
    };
    if let Some(scales) = job.a.fit_range.as_deref().map(fit_range).transpose()? {
        fit_scene.for_any_view(scales);
    }
    super::tolerance::quadrature_for(&fit_scene, job.spectral, job.a, &serving)
}

/// `--sweep`: colour error against time for each wavelength count (and the CPU's too when auto
/// found a GPU), as a table or JSON, and written into `--sweep-out`.
fn run_sweep(job: &Job, counts: &[usize]) -> anyhow::Result<()> {
    if counts.is_empty() {
        anyhow::bail!("--sweep needs wavelength counts, e.g. 4,9,17,34,81,340");
    }
    let (scene, spectral, repeats) = (job.scene, job.spectral, job.a.repeats);
    let mut reports = vec![sweep::sweep(
        scene,
        spectral,
        counts,
        job.backend,
        job.gpu,
        repeats,
    )?];
    if job.backend == Backend::Gpu && job.a.backend == BackendArg::Auto {
        // Auto with a GPU: measure the CPU too, for the comparison.
        reports.push(sweep::sweep(
            scene,
            spectral,
            counts,
            Backend::Cpu,
            None,
            repeats,
        )?);
    }
    let table = sweep::markdown(&reports);
    if let Some(dir) = &job.a.sweep_out {
        write_sweep(dir, &table, &reports)?;
    }
    if job.a.json {
        super::emit(&(serde_json::to_string_pretty(&reports)? + "\n"));
    } else {
        let mut out = String::new();
        outln!(
            out,
            "speed for accuracy: {} {}x{}, colour error against the 1 nm render of the same backend",
            scene.name,
            scene.width,
            scene.height
        );
        out.push_str(&table);
        super::emit(&out);
    }
    Ok(())
}

/// `--sweep-out DIR`: sweep.md, sweep.json and sweep.png.
fn write_sweep(
    dir: &std::path::Path,
    table: &str,
    reports: &[sweep::SweepReport],
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    specmap::io::write_atomic(&dir.join("sweep.md"), table.as_bytes())?;
    specmap::io::write_atomic(
        &dir.join("sweep.json"),
        (serde_json::to_string_pretty(&reports)? + "\n").as_bytes(),
    )?;
    sweep::plot(reports, &dir.join("sweep.png")).context("writing the sweep plot")?;
    eprintln!("wrote {}/sweep.md, sweep.json, sweep.png", dir.display());
    Ok(())
}

/// `--turntable` or `--frames`: every frame rendered and written, then reported.
fn render_sequence(
    job: &Job,
    seq: &Sequence,
    chosen: super::tolerance::Chosen,
) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let frames = seq.render(
        (job.scene, chosen.prepared),
        &chosen.quadrature,
        job.spectral.space,
        job.gpu,
        (job.output, job.a.exposure),
    )?;
    let report = SequenceReport {
        frames,
        seconds: t0.elapsed().as_secs_f64(),
        quadrature: &chosen.quadrature,
        selection: chosen.selection.as_ref(),
        plan: chosen.plan.as_ref(),
    };
    report.emit(
        job.scene,
        job.a.json,
        job.backend,
        job.gpu.map(|g| g.adapter()),
    )
}

/// One image rendered and written, with its timings.
struct Single {
    quadrature: specmap::quadrature::Quadrature,
    selection: Option<specmap::quadrature::choose::Selection>,
    plan: Option<specmap::render::plan::Plan>,
    prepare_s: f64,
    render_s: f64,
    gpu_timing: Option<specmap::render::gpu::GpuTiming>,
}

/// The one image: prepared (unless choosing the quadrature did), rendered, written.
fn render_single(job: &Job, chosen: super::tolerance::Chosen) -> anyhow::Result<Single> {
    let t0 = Instant::now();
    let prepared = match chosen.prepared {
        Some(p) => p,
        None => Prepared::with_quadrature(job.scene, &chosen.quadrature, job.spectral.space)?,
    };
    let prepare_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let (image, gpu_timing) = match job.gpu {
        Some(g) => {
            let (i, t) = g.render(&prepared)?;
            (i, Some(t))
        }
        None => (cpu::render(&prepared), None),
    };
    let render_s = t1.elapsed().as_secs_f64();
    image
        .write(job.output, job.a.exposure)
        .with_context(|| format!("writing {}", job.output.display()))?;
    Ok(Single {
        quadrature: chosen.quadrature,
        selection: chosen.selection,
        plan: chosen.plan,
        prepare_s,
        render_s,
        gpu_timing,
    })
}

/// `--json` of the one image.
fn single_json(job: &Job, s: &Single, env_report: Option<&env::EnvReport>) -> serde_json::Value {
    let uniform = s.quadrature.uniform_grid();
    serde_json::json!({
        "scene": job.preset.name(),
        "size": [job.size.0, job.size.1],
        "backend": job.backend,
        "adapter": job.gpu.map(|g| g.adapter()),
        "wavelengths": s.quadrature.len(),
        "range": uniform.map(|(g, _)| g.to_string()),
        "rule": uniform.map(|(_, r)| r),
        "quadrature": s.quadrature.summary(s.selection.as_ref().map(|s| s.estimate_de2000)),
        "quadrature_choice": s.selection,
        "quadrature_plan": s.plan,
        "light": job.scene.lightings.iter().map(|l| l.label.clone()).collect::<Vec<_>>(),
        "env": env_report,
        "prepare_s": s.prepare_s,
        "render_s": s.render_s,
        "gpu_timing": s.gpu_timing,
        "exposure_ev": job.a.exposure,
        "output": job.output.display().to_string(),
    })
}

/// The report of the one image without `--json`.
fn single_text(job: &Job, s: &Single, env_report: Option<&env::EnvReport>) -> String {
    let (w, h) = job.size;
    let mut out = String::new();
    outln!(
        out,
        "rendered {} {w}x{h}, {} wavelengths ({}) on the {}{}",
        job.preset.name(),
        s.quadrature.len(),
        s.quadrature,
        job.backend,
        job.gpu
            .map(|g| g.adapter())
            .map(|a| format!(" ({}, {})", a.name, a.backend))
            .unwrap_or_default()
    );
    if let Some(p) = &s.plan {
        super::tolerance::write_plan(&mut out, p);
    }
    if let Some(c) = &s.selection {
        super::tolerance::write_selection(&mut out, c);
    }
    if let Some(r) = env_report {
        write_env_report(&mut out, r);
    }
    outln!(
        out,
        "  prepare {:.1} ms, render {:.1} ms{}",
        s.prepare_s * 1e3,
        s.render_s * 1e3,
        s.gpu_timing
            .as_ref()
            .map(|t| format!(" (GPU compute {:.1} ms)", t.compute_s * 1e3))
            .unwrap_or_default()
    );
    outln!(out, "wrote {}", job.output.display());
    out
}

/// The environment's lines of the report: its file, light and sun, and which spectra light it.
fn write_env_report(out: &mut String, r: &env::EnvReport) {
    outln!(
        out,
        "  environment {} ({}), made under {}, sun {}",
        r.file,
        r.kind,
        r.light,
        match r.sun_direction {
            Some(d) => format!(
                "at ({:.3}, {:.3}, {:.3}) as a directional light",
                d[0], d[1], d[2]
            ),
            None => "not found".into(),
        }
    );
    match &r.projection {
        Some(p) => outln!(out, "  lit by its own spectra: {}", p.summary),
        None if !r.light_used => outln!(
            out,
            "  lit by the {} spectra the file stores (--light does not apply)",
            r.spectra
        ),
        None => {}
    }
}

/// The environment of `--env` as a lighting, and what loading found.
pub(crate) fn load_env(
    a: &RenderArgs,
) -> anyhow::Result<Option<(specmap::render::Lighting, env::EnvReport)>> {
    a.env
        .as_ref()
        .map(|p| {
            env::load(p, &a.light)
                .with_context(|| format!("loading the environment {}", p.display()))
        })
        .transpose()
}

/// The scene `a` describes: the preset at `size`, lit by `lighting` (the loaded `--env`) or
/// the uniform `--light`, with the surface flags on its main objects, the background, the
/// zoom and the orbit.
pub(crate) fn scene_from(
    a: &RenderArgs,
    preset: Preset,
    (w, h): (usize, usize),
    lighting: Option<specmap::render::Lighting>,
) -> anyhow::Result<Scene> {
    let mut scene = preset.scene(w, h, &a.light, lighting)?;
    scene.backdrop = match a.background {
        BackgroundArg::Env => specmap::render::Backdrop::DEFAULT,
        BackgroundArg::Flat => specmap::render::Backdrop::Flat,
        BackgroundArg::None => specmap::render::Backdrop::Hidden,
    };
    surfaces(a, &mut scene)?;
    if let Some(z) = a.zoom {
        if !(z.is_finite() && (0.01..=100.0).contains(&z)) {
            anyhow::bail!("--zoom {z}: must be between 0.01 and 100");
        }
        scene.view.half_height /= z;
    }
    if let Some(o) = &a.orbit {
        scene.orbit(orbit(o)?);
    }
    Ok(scene)
}

/// `--fit-range F` (1 ± F) or `S0:S1`: the thickness scales a view's fit covers.
pub(crate) fn fit_range(spec: &str) -> anyhow::Result<(f64, f64)> {
    let bad = || {
        anyhow::anyhow!(
            "--fit-range '{spec}' must be a spread F between 0 and 1 (0.15: 15% either way) or \
             scales S0:S1 with 0 <= S0 <= S1"
        )
    };
    let (s0, s1) = match spec.split_once(':') {
        Some((a, b)) => (
            a.trim().parse::<f64>().map_err(|_| bad())?,
            b.trim().parse::<f64>().map_err(|_| bad())?,
        ),
        None => {
            let f: f64 = spec.trim().parse().map_err(|_| bad())?;
            if !(0.0..1.0).contains(&f) {
                return Err(bad());
            }
            (1.0 - f, 1.0 + f)
        }
    };
    if !(s0.is_finite() && s1.is_finite() && 0.0 <= s0 && s0 <= s1) {
        return Err(bad());
    }
    Ok((s0, s1))
}

/// `--orbit YAW,PITCH`.
pub(crate) fn orbit(spec: &str) -> anyhow::Result<specmap::render::Orbit> {
    let bad = || anyhow::anyhow!("--orbit '{spec}' must be YAW,PITCH in degrees, e.g. 30,-10");
    let (y, p) = spec.split_once(',').ok_or_else(bad)?;
    let yaw: f64 = y.trim().parse().map_err(|_| bad())?;
    let pitch: f64 = p.trim().parse().map_err(|_| bad())?;
    if !(yaw.is_finite() && pitch.is_finite() && pitch.abs() <= 90.0) {
        anyhow::bail!("--orbit '{spec}': the pitch must be between -90 and 90 degrees");
    }
    Ok(specmap::render::Orbit {
        yaw_deg: yaw,
        pitch_deg: pitch,
    })
}

/// `--film`, `--substrate`, `--diffuse`, `--kd`, `--ks` and `--shininess` on the scene's main
/// objects.
fn surfaces(a: &RenderArgs, scene: &mut Scene) -> anyhow::Result<()> {
    let layers = a.film.as_deref().map(film_layers).transpose()?;
    let substrate = a
        .substrate
        .as_deref()
        .map(|s| index(s, "substrate"))
        .transpose()?;
    let rd = a.diffuse.as_deref().map(diffuse).transpose()?;
    for o in scene.objects.iter_mut().filter(|o| o.main) {
        let s = &mut o.surface;
        if layers.is_some() || substrate.is_some() {
            let f = s.film.get_or_insert(Film {
                ambient: Material::constant(Index::real(1.0)?),
                layers: Vec::new(),
                substrate: Material::constant(Index::real(1.5)?),
            });
            if let Some(l) = &layers {
                f.layers = l.clone();
                o.ramp = None;
            }
            if let Some(m) = &substrate {
                f.substrate = m.clone();
            }
        }
        if let Some(r) = &rd {
            s.diffuse = Some(r.clone());
        }
        if let Some(v) = a.kd {
            s.kd = v;
        }
        if let Some(v) = a.ks {
            s.ks = v;
        }
        if let Some(v) = a.shininess {
            s.shininess = v;
        }
    }
    Ok(())
}

/// The grid, rule, observer and space of `--step`/`--samples`, `--rule` and `--observer`.
pub(crate) fn spectral_of(a: &RenderArgs) -> anyhow::Result<Spectral> {
    let base = match (a.step, a.samples) {
        (Some(s), _) => Spectral::step(s)?,
        (None, Some(n)) => Spectral::samples(n)?,
        (None, None) => Spectral::default(),
    };
    Ok(Spectral {
        rule: a.rule.into(),
        observer: a.observer.into(),
        space: RgbSpace::SRGB,
        ..base
    })
}
