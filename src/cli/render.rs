//! `specmap render`: a spectral preview of the paper's scenes (Eq. 1 Phong, Eq. 2-9 films) on
//! the GPU or the CPU, and the speed-for-accuracy sweep.

use super::outln;
use super::render_args::{fit_range, BackendArg, RenderArgs};
use super::render_scene::{load_env, scene_from, spectral_of};
use super::sequence::{film_range, Sequence, SequenceReport};
use anyhow::Context;
use specmap::render::gpu::Gpu;
use specmap::render::prepare::Prepared;
use specmap::render::{cpu, env, sweep, Backend, Image, Preset, Scene, Spectral};
use std::path::PathBuf;
use std::time::Instant;

/// `specmap render`: the options and files checked, the scene, the backend and the quadrature;
/// then the sweep, the sequence or the one image, written, and its report.
pub(crate) fn run(a: RenderArgs) -> anyhow::Result<()> {
    let output = a
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("render-{}.png", a.preset().name())));
    let job = Job::new(a, Some(output.clone()))?;
    let chosen = choose_quadrature(&job)?;
    if let Some(counts) = &job.a.sweep {
        return run_sweep(&job, counts);
    }
    if let Some(seq) = &job.sequence {
        return render_sequence(&job, seq, chosen, &output);
    }
    let one = render_one(&job, chosen)?;
    one.image
        .write(&output, job.a.exposure)
        .with_context(|| format!("writing {}", output.display()))?;
    let report = match job.a.json {
        true => serde_json::to_string_pretty(&one.json)? + "\n",
        false => one.text + &format!("wrote {}\n", output.display()),
    };
    super::emit(&report);
    Ok(())
}

/// One image rendered, not written, and its report.
pub(crate) struct Rendered {
    /// Linear RGB, before the exposure (what an .exr output holds at `--exposure 0`).
    pub(crate) image: Image,
    /// What `--json` prints ("output" only where the image is to be written).
    pub(crate) json: serde_json::Value,
    /// What the report without `--json` says, up to its last line ("wrote OUT").
    text: String,
}

/// The one image the options describe, rendered and reported but written nowhere (Python's
/// `specmap.render`): the same stages as [`run`]'s one image. A sweep or a sequence (many
/// images, written as files) is refused, as is `-o`.
#[allow(dead_code)] // Called by python/src/render.rs, which compiles this module in.
pub(crate) fn render_image(a: RenderArgs) -> anyhow::Result<Rendered> {
    if let Some(o) = &a.output {
        anyhow::bail!(
            "output {}: the image is returned, not written (write it yourself, or run `specmap \
             render -o`)",
            o.display()
        );
    }
    let job = Job::new(a, None)?;
    let chosen = choose_quadrature(&job)?;
    render_one(&job, chosen)
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
    output: Option<&std::path::Path>,
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
        (None, _) => match (sequence, output) {
            (Some(seq), Some(output)) => {
                for k in 0..seq.frames() {
                    guard.output("-o", seq.file(output, k));
                }
            }
            (None, Some(output)) => {
                guard.output("-o", output);
            }
            (_, None) => {}
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
struct Job {
    /// The options (a sequence's film at its ranges' starts; a turntable's without `--orbit`).
    a: RenderArgs,
    preset: Preset,
    /// The image size, WxH.
    size: (usize, usize),
    sequence: Option<Sequence>,
    /// What loading `--env` found.
    env_report: Option<env::EnvReport>,
    /// The scene as built (a sequence's frames orbit it or scale its films).
    scene: Scene,
    spectral: Spectral,
    backend: Backend,
    gpu: Option<Gpu>,
    /// The image, or the pattern of a sequence's frames; None where nothing is written.
    output: Option<PathBuf>,
}

impl Job {
    /// The options read and checked, in this order: the numbers, the size, the light, the
    /// sequence, the files, the environment, the scene, the spectral settings, the GPU.
    /// Without an `output` (nothing is written) a sweep or a sequence is refused.
    fn new(mut a: RenderArgs, output: Option<PathBuf>) -> anyhow::Result<Job> {
        check_numbers(&a)?;
        let preset = Preset::from(a.scene);
        let size = a.image_size()?;
        check_light(&a, preset)?;
        let sequence = take_sequence(&mut a)?;
        if output.is_none() {
            refuse_many(&a, sequence.as_ref())?;
        }
        check_files(&a, sequence.as_ref(), output.as_deref())?;
        let (lighting, env_report) = load_env(&a)?.unzip();
        let scene = scene_from(&a, preset, size, lighting)?;
        let spectral = spectral_of(&a)?;
        let gpu = open_gpu(a.backend)?;
        Ok(Job {
            preset,
            size,
            sequence,
            env_report,
            scene,
            spectral,
            backend: if gpu.is_some() {
                Backend::Gpu
            } else {
                Backend::Cpu
            },
            gpu,
            output,
            a,
        })
    }
}

/// Where one image is returned: a sweep or a sequence (many, written as files) refused.
fn refuse_many(a: &RenderArgs, sequence: Option<&Sequence>) -> anyhow::Result<()> {
    let many = match (&a.sweep, sequence) {
        (Some(_), _) => "--sweep measures many renders",
        (None, Some(Sequence::Turntable { .. })) => "--turntable renders many frames",
        (None, Some(Sequence::Thickness { .. })) => {
            "a thickness range (--film N:A..B with --frames) renders many frames"
        }
        (None, None) => return Ok(()),
    };
    anyhow::bail!("{many}, written as files: run `specmap render` for it; one image is returned")
}

/// The quadrature, for every frame's scene and the view's range, and what choosing it measured
/// (the first frame, on which a frame's cost is measured and, on the CPU, prepared once).
fn choose_quadrature(job: &Job) -> anyhow::Result<super::tolerance::Chosen> {
    let sequence = job.sequence.as_ref();
    let first = match sequence {
        Some(seq) => seq.frame(&job.scene, 0)?,
        None => job.scene.clone(),
    };
    let serving = super::tolerance::Serving {
        gpu: job.gpu.as_ref(),
        frames: sequence.map_or(1, Sequence::frames),
        first: &first,
    };
    let mut fit_scene = match sequence {
        Some(seq) => seq.fit_scene(&job.scene),
        None => job.scene.clone(),
    };
    if let Some(scales) = job.a.fit_range.as_deref().map(fit_range).transpose()? {
        fit_scene.for_any_view(scales);
    }
    super::tolerance::quadrature_for(&fit_scene, &job.spectral, &job.a, &serving)
}

/// `--sweep`: colour error against time for each wavelength count (and the CPU's too when auto
/// found a GPU), as a table or JSON, and written into `--sweep-out`.
fn run_sweep(job: &Job, counts: &[usize]) -> anyhow::Result<()> {
    if counts.is_empty() {
        anyhow::bail!("--sweep needs wavelength counts, e.g. 4,9,17,34,81,340");
    }
    let (scene, spectral, repeats) = (&job.scene, &job.spectral, job.a.repeats);
    let mut reports = vec![sweep::sweep(
        scene,
        spectral,
        counts,
        job.backend,
        job.gpu.as_ref(),
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
    output: &std::path::Path,
) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let frames = seq.render(
        (&job.scene, chosen.prepared),
        &chosen.quadrature,
        job.spectral.space,
        job.gpu.as_ref(),
        (output, job.a.exposure),
    )?;
    let report = SequenceReport {
        frames,
        seconds: t0.elapsed().as_secs_f64(),
        quadrature: &chosen.quadrature,
        selection: chosen.selection.as_ref(),
        plan: chosen.plan.as_ref(),
    };
    report.emit(
        &job.scene,
        job.a.json,
        job.backend,
        job.gpu.as_ref().map(|g| g.adapter()),
    )
}

/// What rendering one image used and measured.
struct Single {
    quadrature: specmap::quadrature::Quadrature,
    selection: Option<specmap::quadrature::choose::Selection>,
    plan: Option<specmap::render::plan::Plan>,
    prepare_s: f64,
    render_s: f64,
    gpu_timing: Option<specmap::render::gpu::GpuTiming>,
}

/// The one image: prepared (unless choosing the quadrature did), rendered, and reported.
fn render_one(job: &Job, chosen: super::tolerance::Chosen) -> anyhow::Result<Rendered> {
    let t0 = Instant::now();
    let prepared = match chosen.prepared {
        Some(p) => p,
        None => Prepared::with_quadrature(&job.scene, &chosen.quadrature, job.spectral.space)?,
    };
    let prepare_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let (image, gpu_timing) = match &job.gpu {
        Some(g) => {
            let (i, t) = g.render(&prepared)?;
            (i, Some(t))
        }
        None => (cpu::render(&prepared), None),
    };
    let render_s = t1.elapsed().as_secs_f64();
    let single = Single {
        quadrature: chosen.quadrature,
        selection: chosen.selection,
        plan: chosen.plan,
        prepare_s,
        render_s,
        gpu_timing,
    };
    Ok(Rendered {
        json: single_json(job, &single),
        text: single_text(job, &single),
        image,
    })
}

/// `--json` of the one image ("output" where it is to be written).
fn single_json(job: &Job, s: &Single) -> serde_json::Value {
    let uniform = s.quadrature.uniform_grid();
    let mut json = serde_json::json!({
        "scene": job.preset.name(),
        "size": [job.size.0, job.size.1],
        "backend": job.backend,
        "adapter": job.gpu.as_ref().map(|g| g.adapter()),
        "wavelengths": s.quadrature.len(),
        "range": uniform.map(|(g, _)| g.to_string()),
        "rule": uniform.map(|(_, r)| r),
        "quadrature": s.quadrature.summary(s.selection.as_ref().map(|s| s.estimate_de2000)),
        "quadrature_choice": s.selection,
        "quadrature_plan": s.plan,
        "light": job.scene.lightings.iter().map(|l| l.label.clone()).collect::<Vec<_>>(),
        "env": job.env_report,
        "prepare_s": s.prepare_s,
        "render_s": s.render_s,
        "gpu_timing": s.gpu_timing,
        "exposure_ev": job.a.exposure,
    });
    if let Some(output) = &job.output {
        json["output"] = output.display().to_string().into();
    }
    json
}

/// The report of the one image without `--json`, up to "wrote OUT".
fn single_text(job: &Job, s: &Single) -> String {
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
            .as_ref()
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
    if let Some(r) = &job.env_report {
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
