//! The window's state and its loop: settings changed by the controls or the script become
//! frame jobs for the renderer thread; the wavelengths in use follow the settings' mode, a fit
//! running beside the frames where the mode asks for one.

use super::fit::{self, Covers, Mode, Running};
use super::probe::Probe;
use super::script::{FrameRecord, Report, Step};
use super::settings::Settings;
use super::worker::{Done, Frame, Job, Wavelengths};
use crate::cli::render_args::RenderArgs;
use eframe::egui;
use specmap::quadrature::choose::Selection;
use specmap::quadrature::Quadrature;
use specmap::spectrum::WavelengthGrid;
use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, Sender};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Nodes of the uniform grid frames use until a fit is ready (20 nm: a first frame within a
/// second on lavapipe at 512x512).
pub(crate) const INTERIM_STEP_NM: f64 = 20.0;

/// What a script step waits for.
#[derive(Debug, Clone, PartialEq)]
enum Wait {
    Frames(usize),
    Quadrature,
    Probe(usize),
    Screenshot(PathBuf),
    Window(PathBuf),
}

pub(crate) struct App {
    pub(super) settings: Settings,
    pub(super) args: RenderArgs,
    /// The last settings error (a bad value typed), shown until the next good change.
    pub(super) error: Option<String>,
    jobs: Sender<Job>,
    done: Receiver<Done>,
    pub(super) backend: String,
    pub(super) in_use: Wavelengths,
    fitted: Option<(Covers, Selection, Wavelengths)>,
    pub(super) fit: Option<Running>,
    /// Why the last fit started (a refit says what changed).
    pub(super) fit_note: String,
    next_id: u64,
    texture: Option<egui::TextureHandle>,
    pub(super) last: Option<Frame>,
    /// The frame key and wavelengths id of the frame asked for last, and of the one shown.
    asked: Option<(String, u64)>,
    shown: Option<(String, u64)>,
    pending: bool,
    extra_frames: usize,
    started: Instant,
    pub(super) report: Report,
    pub(super) probe: Option<Probe>,
    steps: VecDeque<Step>,
    scripted: bool,
    waiting: Option<Wait>,
    window_shot: Arc<Mutex<Option<Arc<egui::ColorImage>>>>,
    out: Arc<Mutex<Option<Report>>>,
    pub(super) json: bool,
    pub(super) ui: super::ui_state::UiState,
    /// Where the PNG and EXR buttons write (`-o`'s path, by extension; view.png by default).
    pub(super) output: PathBuf,
}

impl App {
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        settings: Settings,
        jobs: Sender<Job>,
        done: Receiver<Done>,
        steps: Option<Vec<Step>>,
        json: bool,
        started: Instant,
        out: Arc<Mutex<Option<Report>>>,
    ) -> anyhow::Result<App> {
        let args = settings.parse()?;
        let interim = interim(&args)?;
        let mut app = App {
            ui: super::ui_state::UiState::new(&settings),
            settings,
            args,
            error: None,
            jobs,
            done,
            report: Report::default(),
            backend: "opening the renderer".into(),
            in_use: interim,
            fitted: None,
            fit: None,
            fit_note: String::new(),
            next_id: 1,
            texture: None,
            last: None,
            asked: None,
            shown: None,
            pending: false,
            extra_frames: 0,
            started,
            probe: None,
            scripted: steps.is_some(),
            steps: steps.unwrap_or_default().into(),
            waiting: None,
            window_shot: Arc::default(),
            out,
            json,
            output: PathBuf::from("view.png"),
        };
        app.follow_mode(None);
        Ok(app)
    }

    /// Applies option changes; a bad one is reported and changes nothing.
    pub(super) fn change(&mut self, changes: &[(&str, Option<String>)]) -> bool {
        match self.settings.set_many(changes) {
            Ok(changed) => {
                self.error = None;
                if changed {
                    self.args = self.settings.parse().expect("checked by set_many");
                    self.ui = super::ui_state::UiState::new(&self.settings);
                    self.follow_mode(None);
                }
                changed
            }
            Err(e) => {
                self.error = Some(format!("{e:#}"));
                self.report.errors.push(format!("{e:#}"));
                false
            }
        }
    }

    fn id(&mut self) -> u64 {
        self.next_id += 1;
        self.next_id
    }

    /// The wavelengths the settings ask for: a uniform or Meyer set at once; a fitted one
    /// when a fit covers the settings, else the interim grid while a fit runs.
    fn follow_mode(&mut self, ctx: Option<&egui::Context>) {
        let mode = match fit::mode(&self.args) {
            Ok(m) => m,
            Err(e) => {
                self.error = Some(format!("{e:#}"));
                return;
            }
        };
        let fixed = |q: Quadrature, kind: &str, id: u64| Wavelengths {
            quadrature: Arc::new(q),
            kind: kind.into(),
            estimate: None,
            id,
        };
        match mode {
            Mode::Uniform(q) if self.in_use.kind != "uniform" || *self.in_use.quadrature != q => {
                let id = self.id();
                self.in_use = fixed(q, "uniform", id);
            }
            Mode::Meyer(q) if self.in_use.kind != "meyer" => {
                let id = self.id();
                self.in_use = fixed(q, "meyer", id);
            }
            Mode::Uniform(_) | Mode::Meyer(_) => {}
            Mode::Fitted { .. } => self.follow_fit(ctx),
        }
    }

    fn follow_fit(&mut self, ctx: Option<&egui::Context>) {
        let now = match fit::now(&self.settings, &self.args) {
            Ok(c) => c,
            Err(e) => {
                self.error = Some(format!("{e:#}"));
                return;
            }
        };
        if let Some((covers, _, w)) = &self.fitted {
            if covers.misses(&now).is_none() {
                if self.in_use.id != w.id {
                    self.in_use = w.clone();
                }
                return;
            }
        }
        if let Some(r) = &self.fit {
            if r.covers.misses(&now).is_none() {
                return;
            }
            // One fit at a time: the refit starts when this one ends.
            self.fit_note = format!("refit waits: {}", r.covers.misses(&now).unwrap_or_default());
            self.use_interim();
            return;
        }
        let why = match (&self.fitted, &self.fit) {
            (Some((c, ..)), _) | (None, Some(Running { covers: c, .. })) => {
                format!("refit: {}", c.misses(&now).unwrap_or_default())
            }
            (None, None) => "fitting the scene's wavelengths".to_string(),
        };
        let covers = match fit::covers(&self.settings, &self.args) {
            Ok(c) => c,
            Err(e) => {
                self.error = Some(format!("{e:#}"));
                return;
            }
        };
        let wake = ctx.cloned();
        match fit::start(&self.args, covers, move || {
            if let Some(c) = &wake {
                c.request_repaint();
            }
        }) {
            Ok(r) => {
                self.fit = Some(r);
                self.fit_note = why;
                self.use_interim();
            }
            Err(e) => self.error = Some(format!("{e:#}")),
        }
    }

    /// The interim grid while no fit covers the settings.
    fn use_interim(&mut self) {
        if let Ok(w) = interim(&self.args) {
            if self.in_use.kind != w.kind || *self.in_use.quadrature != *w.quadrature {
                let id = self.id();
                self.in_use = Wavelengths { id, ..w };
            }
        }
    }

    /// Takes what the renderer and the fit sent.
    fn poll(&mut self, ctx: &egui::Context) {
        while let Ok(d) = self.done.try_recv() {
            match d {
                Done::Backend(b) => {
                    self.report.backend = b.clone();
                    self.backend = b;
                }
                Done::Frame(f) => self.show(ctx, *f),
                Done::Probe(p) => {
                    self.report.probes.push((*p).clone());
                    self.probe = Some(*p);
                    if let Some(Wait::Probe(n)) = self.waiting {
                        if self.report.probes.len() >= n {
                            self.waiting = None;
                        }
                    }
                }
                Done::Failed(e) => {
                    self.pending = false;
                    self.error = Some(e.clone());
                    self.report.errors.push(e);
                    if self.scripted {
                        // Nothing the script waits for will come: it ends here (and the
                        // command exits non-zero with the error).
                        self.steps.clear();
                        self.waiting = None;
                    }
                }
            }
        }
        let sent = self.fit.as_ref().and_then(|r| r.result.try_recv().ok());
        let finished = match sent {
            Some(fit::Sent::Interim(s)) => {
                // A first set, found quickly: drawn with while the fit goes on.
                let covers = self.fit.as_ref().expect("a running fit").covers.clone();
                self.take_fitted(covers, *s, ctx);
                None
            }
            Some(fit::Sent::Final(result)) => Some(result),
            None => None,
        };
        if let Some(result) = finished {
            let r = self.fit.take().expect("a running fit");
            let seconds = r.started.elapsed().as_secs_f64();
            match result {
                Ok(s) => {
                    self.report.fits.push(serde_json::json!({
                        "seconds": seconds,
                        "why": self.fit_note,
                        "nodes": s.quadrature.len(),
                        "estimate_de2000": s.estimate_de2000,
                        "met": s.met,
                        "kind": s.kind,
                        "thickness_scales": [r.covers.scales.0, r.covers.scales.1],
                    }));
                    self.take_fitted(r.covers, *s, ctx);
                }
                Err(e) => {
                    let e = format!("the fit failed: {e:#}");
                    self.error = Some(e.clone());
                    self.report.errors.push(e);
                }
            }
        }
    }

    /// Frames are drawn with the fitted `s`, made for `covers`, from now on.
    fn take_fitted(&mut self, covers: Covers, s: Selection, ctx: &egui::Context) {
        let id = self.id();
        let w = Wavelengths {
            quadrature: Arc::new(s.quadrature.clone()),
            kind: "scene".into(),
            estimate: Some(s.estimate_de2000),
            id,
        };
        self.fitted = Some((covers, s, w));
        self.follow_mode(Some(ctx));
    }

    /// A frame arrived: onto the screen, into the report.
    fn show(&mut self, ctx: &egui::Context, f: Frame) {
        self.pending = false;
        self.shown = self.asked.clone();
        if self.report.first_frame_ms.is_none() {
            self.report.first_frame_ms = Some(self.started.elapsed().as_secs_f64() * 1e3);
        }
        self.report.frames.push(FrameRecord {
            ms: f.render_ms,
            prepare_ms: f.prepare_ms,
            nodes: f.nodes,
            kind: f.kind.clone(),
            fitting: self.fit.is_some(),
        });
        if let Some(Wait::Frames(n)) = self.waiting {
            if self.report.frames.len() >= n {
                self.waiting = None;
            }
        }
        self.last = Some(f);
        self.retexture(ctx);
    }

    /// The last frame, exposed and encoded, as the texture shown.
    pub(super) fn retexture(&mut self, ctx: &egui::Context) {
        let Some(f) = &self.last else { return };
        let k = self.args.exposure.exp2();
        let mut rgb = Vec::with_capacity(f.image.pixels.len() * 3);
        for p in &f.image.pixels {
            for &v in p {
                let v = if v.is_finite() { v as f64 * k } else { 0.0 };
                rgb.push(
                    (specmap::colorimetry::srgb_encode(v.clamp(0.0, 1.0)) * 255.0).round() as u8,
                );
            }
        }
        let img = egui::ColorImage::from_rgb([f.image.width, f.image.height], &rgb);
        match &mut self.texture {
            Some(t) => t.set(img, egui::TextureOptions::NEAREST),
            None => {
                self.texture = Some(ctx.load_texture("frame", img, egui::TextureOptions::NEAREST))
            }
        }
    }

    pub(super) fn texture(&self) -> Option<&egui::TextureHandle> {
        self.texture.as_ref()
    }

    /// What a frame depends on: the settings but the exposure (applied when shown).
    fn frame_key(&self) -> String {
        format!("{:?}", self.settings.without(&["exposure"]))
    }

    /// Asks for a frame when the settings or wavelengths changed, or a script wants more.
    fn request_frame(&mut self) {
        if self.pending {
            return;
        }
        let want = (self.frame_key(), self.in_use.id);
        if self.asked.as_ref() == Some(&want) && self.extra_frames == 0 {
            return;
        }
        if self.asked.as_ref() == Some(&want) {
            self.extra_frames -= 1;
        }
        self.pending = true;
        self.asked = Some(want.clone());
        let _ = self.jobs.send(Job::Frame {
            args: Box::new(self.args.clone()),
            key: want.0,
            wavelengths: self.in_use.clone(),
        });
    }

    /// Whether the picture shows the settings and wavelengths as they are now.
    pub(super) fn up_to_date(&self) -> bool {
        !self.pending && self.shown == Some((self.frame_key(), self.in_use.id))
    }

    pub(super) fn probe_at(&mut self, x: usize, y: usize) {
        let _ = self.jobs.send(Job::Probe {
            x,
            y,
            observer: crate::cli::render_scene::spectral_of(&self.args)
                .map(|s| s.observer)
                .unwrap_or_default(),
        });
    }

    /// The command that renders the view, printed (stderr under --json) and kept.
    pub(super) fn print_command(&mut self) {
        // A fitted view's nodes come from a fit over a range of thicknesses: render fits the
        // same range (relative to the film now) to use the same nodes.
        let range = match (&self.fitted, fit::now(&self.settings, &self.args)) {
            (Some((covers, ..)), Ok(now)) if self.in_use.kind == "scene" => {
                Some(fit::range_for(covers, &now))
            }
            _ if self.args.tolerance.is_some() => Some(fit::COVER.to_string()),
            _ => None,
        };
        let c = self.settings.command("view.png", range);
        if self.json {
            eprintln!("{c}");
        } else {
            println!("{c}");
        }
        self.report.commands.push(c);
    }

    /// Writes the picture: PNG (sRGB, exposed) or EXR (linear, exposed) by the extension.
    pub(super) fn screenshot(&mut self, path: &std::path::Path) {
        let Some(f) = &self.last else { return };
        match f.image.write(path, self.args.exposure) {
            Ok(()) => {
                eprintln!("wrote {}", path.display());
                self.report.screenshots.push(path.display().to_string());
            }
            Err(e) => {
                self.error = Some(e.to_string());
                self.report.errors.push(e.to_string());
            }
        }
    }

    pub(super) fn screenshot_window(&mut self, ctx: &egui::Context, path: PathBuf) {
        let slot = self.window_shot.clone();
        let c = ctx.clone();
        ctx.request_screenshot(move |img| {
            if let Ok(mut s) = slot.lock() {
                *s = Some(img);
            }
            c.request_repaint();
        });
        self.waiting = Some(Wait::Window(path));
    }

    fn window_shot_arrived(&mut self) {
        let Some(Wait::Window(path)) = self.waiting.clone() else {
            return;
        };
        let Some(img) = self.window_shot.lock().ok().and_then(|mut s| s.take()) else {
            return;
        };
        self.waiting = None;
        let [w, h] = img.size;
        let rgb: Vec<u8> = img
            .pixels
            .iter()
            .flat_map(|c| [c.r(), c.g(), c.b()])
            .collect();
        let written = ::image::RgbImage::from_raw(w as u32, h as u32, rgb)
            .ok_or_else(|| anyhow::anyhow!("the window's screenshot has the wrong size"))
            .and_then(|i| {
                let mut bytes = Vec::new();
                i.write_to(
                    &mut std::io::Cursor::new(&mut bytes),
                    ::image::ImageFormat::Png,
                )?;
                specmap::io::write_atomic(&path, &bytes)?;
                Ok(())
            });
        match written {
            Ok(()) => {
                eprintln!("wrote {}", path.display());
                self.report.screenshots.push(path.display().to_string());
            }
            Err(e) => self
                .report
                .errors
                .push(format!("{}: {e:#}", path.display())),
        }
    }

    /// Runs script steps until one must wait; after the last, closes the window.
    fn advance_script(&mut self, ctx: &egui::Context) {
        loop {
            match self.waiting.clone() {
                Some(Wait::Screenshot(p)) if self.up_to_date() && self.last.is_some() => {
                    self.waiting = None;
                    self.screenshot(&p);
                }
                Some(Wait::Window(_)) => self.window_shot_arrived(),
                Some(Wait::Quadrature) if self.fit.is_none() => {
                    self.waiting = None;
                }
                _ => {}
            }
            if self.waiting.is_some() {
                return;
            }
            let Some(step) = self.steps.pop_front() else {
                if self.scripted {
                    self.scripted = false;
                    if let Ok(mut o) = self.out.lock() {
                        *o = Some(self.report.clone());
                    }
                    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                }
                return;
            };
            self.step(ctx, step);
        }
    }

    fn step(&mut self, ctx: &egui::Context, step: Step) {
        match step {
            Step::Set(pairs) => {
                let changes: Vec<(&str, Option<String>)> =
                    pairs.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
                self.change(&changes);
            }
            Step::Orbit([dy, dp]) => {
                let [y, p] = self.ui.orbit;
                let (y, p) = (y + dy, (p + dp).clamp(-90.0, 90.0));
                self.change(&[("orbit", Some(format!("{y},{p}")))]);
            }
            Step::Zoom(z) => {
                let z = self.args.zoom.unwrap_or(1.0) * z;
                self.change(&[("zoom", Some(z.to_string()))]);
            }
            Step::Frames(n) => {
                self.extra_frames += n;
                self.waiting = Some(Wait::Frames(self.report.frames.len() + n));
            }
            Step::WaitQuadrature => self.waiting = Some(Wait::Quadrature),
            Step::Probe([x, y]) => {
                self.waiting = Some(Wait::Probe(self.report.probes.len() + 1));
                self.probe_at(x, y);
            }
            Step::Screenshot(p) => self.waiting = Some(Wait::Screenshot(p)),
            Step::ScreenshotWindow(p) => self.screenshot_window(ctx, p),
            Step::Command => self.print_command(),
        }
    }
}

/// The interim uniform grid: `--samples`/`--step` if given, else every [`INTERIM_STEP_NM`].
pub(crate) fn interim(args: &RenderArgs) -> anyhow::Result<Wavelengths> {
    let s = crate::cli::render_scene::spectral_of(args)?;
    let grid = if args.samples.is_some() || args.step.is_some() {
        s.grid
    } else {
        WavelengthGrid::new(380.0, 780.0, INTERIM_STEP_NM)?
    };
    Ok(Wavelengths {
        quadrature: Arc::new(Quadrature::uniform(grid, s.rule, s.observer)?),
        kind: "uniform (interim)".into(),
        estimate: None,
        id: 1,
    })
}

impl App {
    /// The report as the window leaves it, unless the script left one already.
    pub(super) fn leave_report(&mut self) {
        if let Ok(mut o) = self.out.lock() {
            if o.is_none() {
                *o = Some(self.report.clone());
            }
        }
    }

    /// Before a frame's widgets: what came from the worker and the script, the next frame
    /// asked for.
    pub(super) fn before_draw(&mut self, ctx: &egui::Context) {
        self.poll(ctx);
        self.advance_script(ctx);
        self.request_frame();
    }

    /// After a frame's widgets: frames and fits wake the window when they end; while a fit
    /// runs, its status line ticks once a second. (Redrawing the window more often takes
    /// lavapipe's cores from the frames: a 512x512 frame took twice as long while the window
    /// redrew every 30 ms.)
    pub(super) fn after_draw(&self, ctx: &egui::Context) {
        if self.fit.is_some() || matches!(self.waiting, Some(Wait::Quadrature)) {
            ctx.request_repaint_after(std::time::Duration::from_secs(1));
        }
    }
}
