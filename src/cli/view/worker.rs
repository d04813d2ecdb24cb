//! The view's renderer thread: it builds the scene a frame asks for (the map loaded once per
//! file and light), prepares it for the frame's quadrature (once per scene and quadrature),
//! renders it on the GPU (or the CPU where `--backend cpu` says so) and probes pixels. The
//! window sends jobs and draws what comes back; the newest frame job replaces any still queued.

use crate::cli::render_args::{BackendArg, RenderArgs};
use crate::cli::render_scene;
use specmap::colorimetry::RgbSpace;
use specmap::quadrature::Quadrature;
use specmap::render::env::EnvReport;
use specmap::render::gpu::Gpu;
use specmap::render::prepare::Prepared;
use specmap::render::{cpu, Image, Lighting, Scene};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, Sender};
use std::sync::Arc;
use std::time::Instant;

/// The wavelengths a frame uses, and what they are called in the status line and report.
#[derive(Debug, Clone)]
pub(crate) struct Wavelengths {
    pub(crate) quadrature: Arc<Quadrature>,
    /// `uniform`, `meyer` or `scene` (fitted), as `render --json` names kinds.
    pub(crate) kind: String,
    /// A fitted set's estimate (CIEDE2000 over the scene's stimuli).
    pub(crate) estimate: Option<f64>,
    /// Changes whenever the set does.
    pub(crate) id: u64,
}

pub(crate) enum Job {
    /// Render `args` (the settings as parsed; `key` says what the scene depends on).
    Frame {
        args: Box<RenderArgs>,
        key: String,
        wavelengths: Wavelengths,
    },
    /// Pixel (x, y) of the last frame's scene: its spectrum at 1 nm and its colour both ways.
    Probe {
        x: usize,
        y: usize,
        observer: specmap::colorimetry::Observer,
    },
}

pub(crate) struct Frame {
    pub(crate) image: Image,
    /// Preparing the scene for the quadrature (0 when the last one was reused) and rendering.
    pub(crate) prepare_ms: f64,
    pub(crate) render_ms: f64,
    pub(crate) nodes: usize,
    pub(crate) kind: String,
}

pub(crate) enum Done {
    /// The backend the renderer opened, in words (sent first).
    Backend(String),
    Frame(Box<Frame>),
    Probe(Box<super::probe::Probe>),
    Failed(String),
}

/// What the renderer runs on, for the status line.
fn open_backend(backend: BackendArg) -> (Option<Gpu>, String) {
    let gpu = match backend {
        BackendArg::Cpu => None,
        _ => match Gpu::new() {
            Ok(g) => Some(g),
            Err(e) => {
                eprintln!(
                    "note: the view renders on the CPU: {}",
                    e.to_string().lines().next().unwrap_or_default()
                );
                None
            }
        },
    };
    let name = match &gpu {
        Some(g) => {
            let a = g.adapter();
            format!("GPU {} ({})", a.name, a.backend)
        }
        None => "CPU (rayon)".to_string(),
    };
    (gpu, name)
}

/// The last scene prepared, under (scene key, quadrature id).
struct Last {
    key: (String, u64),
    scene: Scene,
    prepared: Prepared,
}

struct Cache {
    envs: Envs,
    prepared: Option<Last>,
}

/// The maps loaded so far, by file and light.
pub(crate) type Envs = HashMap<(PathBuf, String), (Lighting, EnvReport)>;

/// Opens the backend (while the window opens), then runs jobs until the window hangs up.
pub(crate) fn run(
    backend: BackendArg,
    envs: Envs,
    jobs: Receiver<Job>,
    done: Sender<Done>,
    wake: impl Fn(),
) {
    let (gpu, name) = open_backend(backend);
    if let Some(g) = &gpu {
        warm_up(g);
    }
    let _ = done.send(Done::Backend(name));
    wake();
    let mut cache = Cache {
        envs,
        prepared: None,
    };
    while let Ok(mut job) = jobs.recv() {
        // A newer frame makes the queued ones moot; a probe is never dropped.
        while let Ok(next) = jobs.try_recv() {
            if matches!(job, Job::Frame { .. }) {
                job = next;
            } else {
                let _ = done.send(one(&gpu, &mut cache, job));
                job = next;
            }
        }
        if done.send(one(&gpu, &mut cache, job)).is_err() {
            return;
        }
        wake();
    }
}

fn one(gpu: &Option<Gpu>, cache: &mut Cache, job: Job) -> Done {
    let out = match job {
        Job::Frame {
            args,
            key,
            wavelengths,
        } => frame(gpu, cache, &args, key, &wavelengths).map(|f| Done::Frame(Box::new(f))),
        Job::Probe { x, y, observer } => match &cache.prepared {
            Some(l) => super::probe::probe(&l.scene, &l.prepared, x, y, observer)
                .map(|p| Done::Probe(Box::new(p))),
            None => Err(anyhow::anyhow!("no frame to probe yet")),
        },
    };
    out.unwrap_or_else(|e| Done::Failed(format!("{e:#}")))
}

/// One tiny frame, so that the driver compiles the shader (lavapipe does on the first
/// dispatch) before the first frame is asked for.
fn warm_up(gpu: &Gpu) {
    let tiny = specmap::render::Preset::Ball
        .scene(1, 1, "D65", None)
        .and_then(|s| Prepared::new(&s, &specmap::render::Spectral::samples(2)?));
    if let Ok(p) = tiny {
        let _ = gpu.render(&p);
    }
}

/// The scene `args` describe, its map loaded once per file and light.
pub(crate) fn scene(
    args: &RenderArgs,
    envs: &mut Envs,
) -> anyhow::Result<(Scene, Option<EnvReport>)> {
    let lighting = match &args.env {
        Some(p) => {
            let k = (p.clone(), args.light.clone());
            if !envs.contains_key(&k) {
                if let Some(l) = render_scene::load_env(args)? {
                    envs.insert(k.clone(), l);
                }
            }
            envs.get(&k).cloned()
        }
        None => None,
    };
    let (lighting, report) = lighting.unzip();
    let scene = render_scene::scene_from(args, args.preset(), args.image_size()?, lighting)?;
    Ok((scene, report))
}

fn frame(
    gpu: &Option<Gpu>,
    cache: &mut Cache,
    args: &RenderArgs,
    key: String,
    w: &Wavelengths,
) -> anyhow::Result<Frame> {
    let t0 = Instant::now();
    let k = (key, w.id);
    let reuse = matches!(&cache.prepared, Some(l) if l.key == k);
    if !reuse {
        let scene = scene(args, &mut cache.envs)?.0;
        let prepared = Prepared::with_quadrature(&scene, &w.quadrature, RgbSpace::SRGB)?;
        cache.prepared = Some(Last {
            key: k,
            scene,
            prepared,
        });
    }
    let Some(Last { prepared: p, .. }) = &cache.prepared else {
        unreachable!("prepared above")
    };
    let prepare_ms = t0.elapsed().as_secs_f64() * 1e3;
    let t1 = Instant::now();
    let image = match gpu {
        Some(g) => g.render(p)?.0,
        None => cpu::render(p),
    };
    Ok(Frame {
        image,
        prepare_ms,
        render_ms: t1.elapsed().as_secs_f64() * 1e3,
        nodes: w.quadrature.len(),
        kind: w.kind.clone(),
    })
}
