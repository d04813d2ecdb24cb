//! `specmap view`: the renderer in a window, every option of `specmap render` live. Three
//! threads: the window (app.rs: the settings, the wavelengths in use, the script; ui.rs: the
//! widgets), the renderer (worker.rs: scenes, frames on the GPU, probes) and a fit at a time
//! (fit.rs). What the window shows is `render`'s image for the settings shown, and the
//! `specmap render` command that renders it is a key press away (settings.rs).

mod app;
mod fit;
mod probe;
mod script;
mod settings;
mod ui;
mod ui_state;
mod worker;

use crate::cli::render_args::RenderArgs;
use clap::Args;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Instant;

#[derive(Debug, Args)]
#[command(after_help = "\
Drag the picture to orbit, scroll to zoom, click a pixel to probe its spectrum; C prints the
`specmap render` command that renders what is shown. A fitted mode (--tolerance) shows frames
on a 20 nm grid while the fit runs, then its own nodes.

Examples:
  specmap view --scene ball --env envmaps/sunrise.exr --tolerance 0.5
  specmap view --scene cylinders --light FL2 --film 2.7:270
  specmap view --scene ball --script steps.json --json   # replay steps, report frames and probes

A script is a JSON array of steps: {\"set\": {\"film\": \"2.7:300\", \"light\": \"A\"}},
{\"orbit\": [30, -10]}, {\"zoom\": 1.5}, {\"frames\": 5}, {\"wait\": \"quadrature\"},
{\"probe\": [256, 200]}, {\"screenshot\": \"a.png\"} (or .exr, linear),
{\"screenshot_window\": \"w.png\"}, {\"command\": true}.")]
pub(crate) struct ViewArgs {
    #[command(flatten)]
    render: RenderArgs,
    /// Replay these steps (a JSON array), then close the window.
    #[arg(long, value_name = "FILE")]
    script: Option<PathBuf>,
}

/// Why no window can open here, if none can.
fn no_display() -> Option<String> {
    let set = |k: &str| std::env::var_os(k).is_some_and(|v| !v.is_empty());
    (!set("DISPLAY")).then(|| {
        let wayland = if set("WAYLAND_DISPLAY") {
            " (a Wayland session needs XWayland's DISPLAY)"
        } else {
            ""
        };
        format!(
            "no display to open a window on: DISPLAY is not set{wayland}; use `specmap render` \
             for still images (or run the view under Xvfb)"
        )
    })
}

pub(crate) fn run(a: ViewArgs) -> anyhow::Result<()> {
    if a.render.sweep.is_some() {
        anyhow::bail!("--sweep measures stills: use `specmap render --sweep`");
    }
    let steps = a.script.as_deref().map(script::load).transpose()?;
    if let Some(why) = no_display() {
        anyhow::bail!(why);
    }
    let started = Instant::now();
    let settings = settings::Settings::from_args(&a.render);
    let args = settings.parse()?;
    // Everything a frame needs is checked before the window opens.
    let mut envs = std::collections::HashMap::new();
    let (scene, _) = worker::scene(&args, &mut envs)?;
    scene.validate()?;
    let (w, h) = (scene.width as f32, scene.height as f32);
    let (jobs, jobs_rx) = std::sync::mpsc::channel();
    let (done_tx, done) = std::sync::mpsc::channel();
    let report = Arc::new(Mutex::new(None));
    let out = report.clone();
    let json = a.render.json;
    let output = a.render.output.clone();
    let options = eframe::NativeOptions {
        viewport: eframe::egui::ViewportBuilder::default()
            .with_title("specmap view")
            .with_inner_size([w.max(512.0) + 700.0, h.max(640.0) + 60.0]),
        ..Default::default()
    };
    eframe::run_native(
        "specmap view",
        options,
        Box::new(move |cc| {
            let ctx = cc.egui_ctx.clone();
            let backend = args.backend;
            std::thread::Builder::new()
                .name("specmap render".into())
                .spawn(move || {
                    worker::run(backend, envs, jobs_rx, done_tx, move || {
                        ctx.request_repaint()
                    })
                })?;
            let mut app = app::App::new(settings, jobs, done, steps, json, started, out)?;
            if let Some(o) = output {
                app.output = o;
            }
            Ok(Box::new(app))
        }),
    )
    .map_err(|e| anyhow::anyhow!("the view's window could not open: {e}; use `specmap render`"))?;
    let report = report.lock().ok().and_then(|mut r| r.take());
    if let Some(r) = report {
        if json {
            super::emit(&(serde_json::to_string_pretty(&r)? + "\n"));
        }
        let scripted = a.script.is_some();
        if let (true, Some(e)) = (scripted, r.errors.first()) {
            anyhow::bail!("the script hit {} error(s); the first: {e}", r.errors.len());
        }
    }
    Ok(())
}
