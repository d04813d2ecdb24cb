//! The window's widgets: the controls beside the picture (every `render` option), the
//! picture (drag to orbit, scroll to zoom, click to probe), the status line and the probe.

use super::app::App;
use super::ui_state::UiState;
use eframe::egui;
use egui::{Color32, Pos2, Stroke, Vec2};

/// A slider that keeps a value outside its range as it is (a film of 1200 nm, an exposure of
/// -10 EV from the command line): only the user's own drags are held to the range, so that
/// showing a control never changes the setting behind it.
fn slider<'a, N: egui::emath::Numeric>(
    value: &'a mut N,
    range: std::ops::RangeInclusive<N>,
) -> egui::Slider<'a> {
    egui::Slider::new(value, range).clamping(egui::SliderClamping::Edits)
}

fn film_text(layers: &[(String, f64)]) -> Option<String> {
    (!layers.is_empty()).then(|| {
        layers
            .iter()
            .map(|(n, d)| format!("{n}:{}", (d * 10.0).round() / 10.0))
            .collect::<Vec<_>>()
            .join(",")
    })
}

/// A text field applied to option `key` on Enter (empty: the default).
fn text_option(
    ui: &mut egui::Ui,
    app: &mut App,
    label: &str,
    key: &str,
    pick: fn(&mut UiState) -> &mut String,
) {
    ui.horizontal(|ui| {
        ui.label(label);
        let r = ui.add(egui::TextEdit::singleline(pick(&mut app.ui)).desired_width(150.0));
        if r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)) {
            let v = pick(&mut app.ui).trim().to_string();
            app.change(&[(key, (!v.is_empty()).then_some(v))]);
        }
    });
}

/// One of `values` for option `key` (`default` when unset), as buttons.
fn choice(ui: &mut egui::Ui, app: &mut App, key: &str, default: &str, values: &[&str]) {
    let now = app.settings.get(key).unwrap_or(default).to_string();
    ui.horizontal(|ui| {
        ui.label(key);
        for v in values {
            if ui.selectable_label(now == *v, *v).clicked() && now != *v {
                app.change(&[(key, Some(v.to_string()))]);
            }
        }
    });
}

fn number(
    ui: &mut egui::Ui,
    app: &mut App,
    key: &str,
    label: &str,
    value: f64,
    range: std::ops::RangeInclusive<f64>,
    log: bool,
) {
    let mut v = value;
    let r = ui.add(slider(&mut v, range).text(label).logarithmic(log));
    if r.changed() {
        app.change(&[(key, Some(format!("{}", (v * 1e4).round() / 1e4)))]);
    }
}

/// The controls beside the picture, top to bottom: the scene, the film and surfaces, the camera,
/// the wavelengths, the integration, and the exports.
fn controls(app: &mut App, ui: &mut egui::Ui) {
    scene_controls(app, ui);
    ui.separator();
    ui.heading("Film");
    film_layers(app, ui);
    surface_controls(app, ui);
    ui.separator();
    ui.heading("Camera");
    camera_controls(app, ui);
    ui.separator();
    wavelengths(app, ui);
    choice(
        ui,
        app,
        "rule",
        "riemann",
        &["riemann", "trapezoid", "simpson"],
    );
    choice(ui, app, "observer", "cie1931", &["cie1931", "cie1964"]);
    ui.separator();
    export_controls(app, ui);
}

/// The scene preset, the map, the light and the background.
fn scene_controls(app: &mut App, ui: &mut egui::Ui) {
    ui.heading("Scene");
    let scene = app.settings.get("scene").unwrap_or("ball").to_string();
    egui::ComboBox::from_id_salt("scene")
        .selected_text(scene.clone())
        .show_ui(ui, |ui| {
            for s in [
                "ball",
                "transparent-ball",
                "cylinders",
                "chart",
                "checker-spheres",
            ] {
                if ui.selectable_label(scene == s, s).clicked() {
                    app.change(&[("scene", Some(s.into()))]);
                }
            }
        });
    text_option(ui, app, "map", "env", |u| &mut u.env);
    text_option(ui, app, "light", "light", |u| &mut u.light);
    let bg = app.settings.get("background").unwrap_or("env").to_string();
    ui.horizontal(|ui| {
        ui.label("background");
        for b in ["env", "flat", "none"] {
            if ui.selectable_label(bg == b, b).clicked() {
                app.change(&[("background", Some(b.into()))]);
            }
        }
    });
}

/// The film's layers: each one's index and thickness, removed, added, and the first swept.
fn film_layers(app: &mut App, ui: &mut egui::Ui) {
    let mut layers = app.ui.layers.clone();
    let mut edited = false;
    let mut remove = None;
    for (i, (n, d)) in layers.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            ui.label(format!("{}", i + 1));
            let r = ui.add(egui::TextEdit::singleline(n).desired_width(44.0));
            edited |= r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            edited |= ui.add(slider(d, 0.0..=1000.0).suffix(" nm")).changed();
            if ui.small_button("x").clicked() {
                remove = Some(i);
            }
        });
    }
    if let Some(i) = remove {
        layers.remove(i);
        edited = true;
    }
    ui.horizontal(|ui| {
        if layers.len() < specmap::render::MAX_LAYERS && ui.button("add layer").clicked() {
            layers.push(("1.38".into(), 100.0));
            edited = true;
        }
        if let Some((_, d)) = layers.first_mut() {
            // The paper's sweep: the first layer from 100 to 400 nm.
            edited |= ui.add(slider(d, 100.0..=400.0).text("sweep")).changed();
        }
    });
    app.ui.layers = layers.clone();
    if edited {
        app.change(&[("film", film_text(&layers))]);
    }
}

/// The substrate, the pigment and the Phong coefficients.
fn surface_controls(app: &mut App, ui: &mut egui::Ui) {
    text_option(ui, app, "substrate", "substrate", |u| &mut u.substrate);
    text_option(ui, app, "pigment", "diffuse", |u| &mut u.diffuse);
    let a = &app.args;
    let (kd, ks, sh) = (a.kd, a.ks, a.shininess);
    number(ui, app, "kd", "k_d", kd.unwrap_or(1.0), 0.0..=1.0, false);
    number(ui, app, "ks", "k_s", ks.unwrap_or(0.0), 0.0..=1.0, false);
    number(
        ui,
        app,
        "shininess",
        "shininess",
        sh.unwrap_or(100.0),
        1.0..=10000.0,
        true,
    );
}

/// The orbit, the zoom, the exposure and the image size.
fn camera_controls(app: &mut App, ui: &mut egui::Ui) {
    let [mut yaw, mut pitch] = app.ui.orbit;
    let c1 = ui
        .add(slider(&mut yaw, -180.0..=180.0).text("yaw"))
        .changed();
    let c2 = ui
        .add(slider(&mut pitch, -90.0..=90.0).text("pitch"))
        .changed();
    if c1 || c2 {
        app.change(&[("orbit", Some(format!("{:.1},{:.1}", yaw, pitch)))]);
    }
    let zoom = app.args.zoom.unwrap_or(1.0);
    number(ui, app, "zoom", "zoom", zoom, 0.25..=8.0, true);
    let ev = app.args.exposure;
    let mut e = ev;
    if ui
        .add(slider(&mut e, -8.0..=8.0).text("exposure EV"))
        .changed()
    {
        app.change(&[("exposure", Some(format!("{:.2}", e)))]);
    }
    ui.horizontal(|ui| {
        ui.label("size");
        let r = ui.add(egui::TextEdit::singleline(&mut app.ui.size).desired_width(80.0));
        if r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)) {
            let v = app.ui.size.trim().to_string();
            app.change(&[("size", (!v.is_empty()).then_some(v))]);
        }
    });
}

/// The command, PNG, EXR and window buttons, and the last command printed.
fn export_controls(app: &mut App, ui: &mut egui::Ui) {
    ui.horizontal(|ui| {
        if ui.button("command (C)").clicked() {
            app.print_command();
        }
        if ui.button("PNG").clicked() {
            app.screenshot(&app.output.with_extension("png"));
        }
        if ui.button("EXR").clicked() {
            app.screenshot(&app.output.with_extension("exr"));
        }
        if ui.button("window").clicked() {
            app.screenshot_window(ui.ctx(), "view-window.png".into());
        }
    });
    if let Some(c) = app.report.commands.last() {
        ui.add(egui::Label::new(egui::RichText::new(c).monospace().small()).wrap());
    }
}

fn wavelengths(app: &mut App, ui: &mut egui::Ui) {
    ui.heading("Wavelengths");
    let a = &app.args;
    let mode = match (a.tolerance, a.max_nodes, a.quadrature) {
        (Some(_), Some(_), _) => "budget",
        (Some(_), None, _) => "fitted",
        (None, _, Some(crate::cli::render_args::QuadratureArg::Meyer)) => "meyer",
        _ => "uniform",
    };
    let clear = ["tolerance", "max-nodes", "quadrature", "step", "samples"];
    let set = |app: &mut App, extra: Vec<(&'static str, String)>| {
        let mut c: Vec<(&str, Option<String>)> = clear.iter().map(|k| (*k, None)).collect();
        c.extend(extra.into_iter().map(|(k, v)| (k, Some(v))));
        app.change(&c);
    };
    ui.horizontal(|ui| {
        for m in ["uniform", "meyer", "fitted", "budget"] {
            if ui.selectable_label(mode == m, m).clicked() && mode != m {
                let u = &app.ui;
                let extra = match m {
                    "uniform" => vec![("samples", u.samples.to_string())],
                    "meyer" => vec![("quadrature", "meyer".to_string())],
                    "fitted" => vec![("tolerance", u.tolerance.to_string())],
                    _ => vec![
                        ("tolerance", u.tolerance.to_string()),
                        ("max-nodes", u.budget.to_string()),
                    ],
                };
                set(app, extra);
            }
        }
    });
    let u = &mut app.ui;
    let (mut n, mut t, mut b) = (u.samples, u.tolerance, u.budget);
    match mode {
        "uniform" => {
            let r = ui.add(slider(&mut n, 2..=401).text("N").logarithmic(true));
            if r.drag_stopped() || (r.changed() && !r.dragged()) {
                app.ui.samples = n;
                set(app, vec![("samples", n.to_string())]);
            } else {
                app.ui.samples = n;
            }
        }
        "fitted" | "budget" => {
            let r1 = ui.add(
                slider(&mut t, 0.05..=5.0)
                    .text("tolerance ΔE")
                    .logarithmic(true),
            );
            let mut r2 = None;
            if mode == "budget" {
                r2 = Some(ui.add(slider(&mut b, 1..=32).text("max nodes")));
            }
            app.ui.tolerance = t;
            app.ui.budget = b;
            let done = |r: &egui::Response| r.drag_stopped() || (r.changed() && !r.dragged());
            if done(&r1) || r2.as_ref().is_some_and(done) {
                let mut e = vec![("tolerance", format!("{}", (t * 1000.0).round() / 1000.0))];
                if mode == "budget" {
                    e.push(("max-nodes", b.to_string()));
                }
                set(app, e);
            }
        }
        _ => {}
    }
}

fn status(app: &App) -> String {
    let w = &app.in_use;
    let mut s = format!(
        "{} | {} nodes ({})",
        app.backend,
        w.quadrature.len(),
        w.kind
    );
    if let Some(e) = w.estimate {
        s += &format!(", estimate ΔE {e:.3}");
    }
    if let Some(f) = &app.last {
        s += &format!(" | frame {:.0} ms", f.render_ms);
        if f.prepare_ms > 1.0 {
            s += &format!(" + prepare {:.0} ms", f.prepare_ms);
        }
    }
    if let Some(r) = &app.fit {
        let stage = r.stage.lock().map(|m| m.clone()).unwrap_or_default();
        s += &format!(
            " | {}: {stage} [{:.0} s]",
            app.fit_note,
            r.started.elapsed().as_secs_f64()
        );
    }
    s
}

pub(crate) fn draw(app: &mut App, ui: &mut egui::Ui) {
    if ui.input(|i| i.key_pressed(egui::Key::C)) && !ui.ctx().egui_wants_keyboard_input() {
        app.print_command();
    }
    egui::Panel::bottom("status").show(ui, |ui| {
        ui.label(status(app));
        if let Some(e) = &app.error {
            ui.colored_label(Color32::from_rgb(230, 90, 80), e);
        }
    });
    egui::Panel::left("controls")
        .default_size(330.0)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| controls(app, ui));
        });
    if app.probe.is_some() {
        egui::Panel::right("probe")
            .default_size(320.0)
            .show(ui, |ui| probe(app, ui));
    }
    egui::CentralPanel::default().show(ui, |ui| picture(app, ui));
}

fn picture(app: &mut App, ui: &mut egui::Ui) {
    let Some(tex) = app.texture() else {
        ui.label("rendering the first frame...");
        return;
    };
    let size = tex.size_vec2();
    let avail = ui.available_size();
    let k = (avail.x / size.x).min(avail.y / size.y).clamp(0.05, 1.0);
    let r = ui.add(egui::Image::new((tex.id(), size * k)).sense(egui::Sense::click_and_drag()));
    let d = r.drag_delta();
    if r.dragged() && d != Vec2::ZERO {
        let [y, p] = app.ui.orbit;
        let (y, p) = (
            y - d.x as f64 * 0.4,
            (p + d.y as f64 * 0.4).clamp(-90.0, 90.0),
        );
        app.ui.orbit = [y, p];
        app.change(&[("orbit", Some(format!("{y:.1},{p:.1}")))]);
    }
    if r.clicked() {
        if let Some(pos) = r.interact_pointer_pos() {
            let v = (pos - r.rect.min) / k;
            let (x, y) = (v.x.max(0.0) as usize, v.y.max(0.0) as usize);
            app.probe_at(x, y);
        }
    }
    if r.hovered() {
        let s = ui.input(|i| i.smooth_scroll_delta.y);
        if s != 0.0 {
            let z = app.args.zoom.unwrap_or(1.0) * (s as f64 / 200.0).exp();
            app.change(&[("zoom", Some(format!("{:.3}", z.clamp(0.25, 8.0))))]);
        }
    }
}

fn probe(app: &mut App, ui: &mut egui::Ui) {
    let Some(p) = &app.probe else { return };
    ui.heading(format!("Pixel ({}, {})", p.at[0], p.at[1]));
    let plot_size = Vec2::new(ui.available_width(), 180.0);
    let (rect, _) = ui.allocate_exact_size(plot_size, egui::Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, Color32::from_gray(24));
    let x = |wl: f64| rect.left() + ((wl - 380.0) / 400.0) as f32 * rect.width();
    let peak = p.radiance.iter().cloned().fold(0.0f64, f64::max).max(1e-12);
    let y = |v: f64| rect.bottom() - (v as f32).clamp(0.0, 1.05) * rect.height() * 0.92;
    for &n in &p.nodes_nm {
        painter.line_segment(
            [Pos2::new(x(n), rect.top()), Pos2::new(x(n), rect.bottom())],
            Stroke::new(1.0, Color32::from_rgb(90, 90, 140)),
        );
    }
    if let Some(r) = &p.film_reflectance {
        let pts: Vec<Pos2> = p
            .wavelengths_nm
            .iter()
            .zip(r)
            .map(|(w, v)| Pos2::new(x(*w), y(*v)))
            .collect();
        painter.add(egui::Shape::line(
            pts,
            Stroke::new(1.2, Color32::from_rgb(220, 170, 60)),
        ));
    }
    let pts: Vec<Pos2> = p
        .wavelengths_nm
        .iter()
        .zip(&p.radiance)
        .map(|(w, v)| Pos2::new(x(*w), y(v / peak)))
        .collect();
    painter.add(egui::Shape::line(pts, Stroke::new(1.6, Color32::WHITE)));
    ui.small("white: radiance (1 nm, peak scaled to the top); orange: film R(λ) (0..1); blue: nodes in use");
    ui.monospace(format!(
        "XYZ  {:.4} {:.4} {:.4}\nxy   {:.4} {:.4}\nLab  {:.2} {:.2} {:.2}\nsRGB {} {} {}\nview angle {}\nquadrature error ΔE2000 {:.4}\nradiance peak {:.4}",
        p.xyz[0], p.xyz[1], p.xyz[2], p.xy[0], p.xy[1], p.lab[0], p.lab[1], p.lab[2],
        p.srgb8[0], p.srgb8[1], p.srgb8[2],
        p.view_angle_deg.map_or("-".into(), |a| format!("{a:.1}°")),
        p.error_de2000, peak
    ));
    if ui.button("close").clicked() {
        app.probe = None;
    }
}

/// The window's frame: what came from the worker and the script, the next frame asked for,
/// the widgets drawn.
impl eframe::App for App {
    /// A window closed by hand leaves its report too (printed under --json).
    fn on_exit(&mut self) {
        self.leave_report();
    }

    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.before_draw(&ctx);
        draw(self, ui);
        self.after_draw(&ctx);
    }
}
