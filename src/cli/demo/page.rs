//! The demo's HTML page: one self-contained file, inline CSS, relative image links, no scripts.

use super::{mode_name, Converted, Run};
use crate::cli::outln;
use specmap::envmap::convert::ConvertReport;
use specmap::envmap::roundtrip::FileRoundTrip;

const CSS: &str = "\
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;max-width:1100px;margin:2em auto;
padding:0 1em;color:#222;line-height:1.45}
h1{margin-bottom:.2em}h2{margin-top:2em;border-bottom:1px solid #ccc;padding-bottom:.2em}
table{border-collapse:collapse;margin:1em 0;font-size:.92em}
th,td{border:1px solid #ccc;padding:.25em .6em;text-align:left}
td.n,th.n{text-align:right;font-variant-numeric:tabular-nums}
tr.miss td{color:#888;font-style:italic}
tbody.light tr:first-child td{border-top:2px solid #888}
pre{background:#f4f4f4;padding:.6em .8em;overflow-x:auto;font-size:.88em}
figure{display:inline-block;margin:.5em 1em .5em 0;vertical-align:top}
figure img{max-width:100%;border:1px solid #ddd;image-rendering:auto}
figcaption{font-size:.88em;color:#555;max-width:420px}
img.wide{width:100%}
.facts th{background:#f8f8f8;font-weight:normal;color:#555}
";

/// Escapes text for HTML element content and attribute values.
pub(crate) fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            _ => o.push(c),
        }
    }
    o
}

fn commands(out: &mut String, lines: &[&str]) {
    let text: Vec<String> = lines.iter().map(|l| esc(l)).collect();
    outln!(out, "<pre><code>{}</code></pre>", text.join("\n"));
}

fn figure(out: &mut String, src: &str, alt: &str, caption: &str, class: &str) {
    outln!(
        out,
        "<figure><img src=\"{}\" alt=\"{}\"{}><figcaption>{}</figcaption></figure>",
        esc(src),
        esc(alt),
        if class.is_empty() {
            String::new()
        } else {
            format!(" class=\"{class}\"")
        },
        caption
    );
}

fn seconds(run: &Run, step: &str) -> f64 {
    run.seconds
        .iter()
        .find(|(k, _)| *k == step)
        .map(|(_, v)| *v)
        .unwrap_or(f64::NAN)
}

/// The page.
pub(crate) fn html(run: &Run) -> String {
    let mut o = String::new();
    outln!(
        o,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">"
    );
    outln!(
        o,
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
    );
    outln!(o, "<title>specmap demo: {}</title>", esc(&run.env));
    outln!(o, "<style>\n{CSS}</style>\n</head>\n<body>");
    outln!(o, "<h1>specmap demo</h1>");
    outln!(
        o,
        "<p>RGB → spectral in four steps on <code>{}</code>: the paper's basis fit (Ďurikovič and \
         Kimura, section 4), the environment-map conversion, spectral preview renders of the \
         paper's figures 6-9, and what a coarser wavelength grid costs in colour. Every artefact \
         below comes with the command that makes it again (run from the folder the demo ran \
         in).</p>",
        esc(&run.env)
    );
    facts(&mut o, run);
    fit_section(&mut o, run);
    convert_section(&mut o, run);
    render_section(&mut o, run);
    tradeoff_section(&mut o, run);
    outln!(o, "<h2>The whole page again</h2>");
    commands(&mut o, &[&run.demo_command]);
    outln!(o, "</body>\n</html>");
    o
}

fn facts(o: &mut String, run: &Run) {
    outln!(o, "<table class=\"facts\">");
    let row = |o: &mut String, k: &str, v: String| {
        outln!(o, "<tr><th>{}</th><td>{}</td></tr>", esc(k), v);
    };
    row(o, "specmap", esc(env!("CARGO_PKG_VERSION")));
    row(
        o,
        "command",
        format!("<code>{}</code>", esc(&run.demo_command)),
    );
    row(
        o,
        "environment map",
        format!("<code>{}</code>", esc(&run.env)),
    );
    row(
        o,
        "output folder",
        format!("<code>{}</code>", esc(&run.dir.display().to_string())),
    );
    row(o, "renderer", esc(&run.renderer));
    if let Some(a) = &run.adapter {
        row(o, "driver", esc(&a.driver));
    }
    row(
        o,
        "CPU threads",
        esc(&rayon::current_num_threads().to_string()),
    );
    row(
        o,
        "size",
        esc(if run.quick {
            "--quick: small maps and images, fewer wavelength steps"
        } else {
            "full"
        }),
    );
    let times: Vec<String> = run
        .seconds
        .iter()
        .filter(|(k, _)| *k != "total")
        .map(|(k, v)| format!("{k} {v:.2} s"))
        .collect();
    row(
        o,
        "time",
        esc(&format!(
            "{:.1} s ({})",
            seconds(run, "total"),
            times.join(", ")
        )),
    );
    outln!(o, "</table>");
}

fn fit_section(o: &mut String, run: &Run) {
    outln!(o, "<h2>1. The basis fit under D65</h2>");
    let f = &run.fits[0].fit;
    outln!(
        o,
        "<p>The paper turns an RGB pixel into <code>SPD = (R w<sub>R</sub> MCC<sub>R</sub> + G \
         w<sub>G</sub> MCC<sub>G</sub> + B w<sub>B</sub> MCC<sub>B</sub>) · SPD<sub>light</sub></code> \
         with the ColorChecker's red, green and blue patches; the weights make white come back \
         white. <em>paper</em> is that; <em>exact</em> a full 3×3 matrix that returns every \
         colour (its SPD may go negative); <em>nonneg</em> exact where the SPD stays \
         non-negative, else the closest non-negative one. Round trip: {} linear sRGB colours → \
         SPD → RGB, CIEDE2000 against the input ({} nm, {} rule).</p>",
        run.fits[0].round_trip.colours,
        esc(&f.grid.to_string()),
        esc(&f.rule.to_string())
    );
    figure(
        o,
        &run.basis_plot,
        "The three weighted basis spectra and D65",
        &format!(
            "The weighted basis spectra w<sub>j</sub> · MCC<sub>j</sub> · D65 and the light \
             (w = {:.4}, {:.4}, {:.4}).",
            f.weights[0], f.weights[1], f.weights[2]
        ),
        "",
    );
    outln!(
        o,
        "<table><thead><tr><th>mode</th><th class=\"n\">w<sub>R</sub></th>\
         <th class=\"n\">w<sub>G</sub></th><th class=\"n\">w<sub>B</sub></th>\
         <th class=\"n\">condition</th><th class=\"n\">mean ΔE00</th><th class=\"n\">p95 ΔE00</th>\
         <th class=\"n\">max ΔE00</th><th class=\"n\">negative SPD</th></tr></thead><tbody>"
    );
    for r in &run.fits {
        let (f, rt) = (&r.fit, &r.round_trip);
        outln!(
            o,
            "<tr><td>{}</td><td class=\"n\">{:.4}</td><td class=\"n\">{:.4}</td>\
             <td class=\"n\">{:.4}</td><td class=\"n\">{:.3}</td><td class=\"n\">{:.4}</td>\
             <td class=\"n\">{:.4}</td><td class=\"n\">{:.4}</td><td class=\"n\">{:.1}%</td></tr>",
            mode_name(f.mode),
            f.weights[0],
            f.weights[1],
            f.weights[2],
            f.condition_number,
            rt.mean_de2000,
            rt.p95_de2000,
            rt.max_de2000,
            100.0 * rt.negative_fraction
        );
    }
    outln!(o, "</tbody></table>");
    let [table, plot] = &run.fit_commands;
    commands(o, &[table, plot]);
}

/// The facts table of one converted map.
fn convert_facts(o: &mut String, c: &Converted) {
    outln!(o, "<table class=\"facts\">");
    for (k, v) in convert_rows(c) {
        outln!(o, "<tr><th>{}</th><td>{}</td></tr>", esc(k), esc(&v));
    }
    outln!(o, "</table>");
}

/// The facts of one converted map, as (name, text) rows.
fn convert_rows(c: &Converted) -> Vec<(&'static str, String)> {
    let r = &c.report;
    let input = format!(
        "{} {}×{} ({})",
        r.input_layout.name(),
        r.input_size[0],
        r.input_size[1],
        r.input_description
    );
    let mut rows = vec![("input", input), ("lights", lights_text(r))];
    rows.extend(mode_rows(r));
    rows.push(("sun", crate::cli::convert::sun_text(r)));
    rows.push((
        "output",
        format!("{} {}", c.file, crate::cli::convert::output_text(r)),
    ));
    rows.push(("round trip (file)", round_trip_text(&c.round_trip)));
    rows.push((
        "time",
        format!(
            "read {:.2} s, convert + write {:.2} s (EXR encoding {:.2} s)",
            r.seconds_read, r.seconds_convert, r.seconds_encode
        ),
    ));
    rows
}

/// The map's lights, each with its share of the energy.
fn lights_text(r: &ConvertReport) -> String {
    r.lights
        .iter()
        .map(|l| {
            format!(
                "{} {} ({:.1}%)",
                format!("{:?}", l.kind).to_lowercase(),
                l.spd,
                100.0 * l.energy_share
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The rows of the conversion's mode: the carriers (faithful), else the main light and the fit.
fn mode_rows(r: &ConvertReport) -> Vec<(&'static str, String)> {
    if r.mode == "faithful" {
        return vec![(
            "spectra",
            format!(
                "{} carriers and {} mixes of them; {} pixels no non-negative spectrum under their \
                 light makes; {} negative",
                r.carriers.len(),
                r.carrier_mixes,
                r.spectra.nearest,
                r.spectra.negative
            ),
        )];
    }
    let light = match &r.light_choice {
        Some(l) => format!("{} (auto: {})", r.light, l.reason),
        None => r.light.clone(),
    };
    let fit = format!(
        "{} mode, weights {:.4} {:.4} {:.4}, condition {:.3}{}",
        r.mode,
        r.weights[0],
        r.weights[1],
        r.weights[2],
        r.condition_number,
        if r.regularized { " (reduced)" } else { "" }
    );
    vec![("main light", light), ("fit", fit)]
}

/// The file round trip's CIEDE2000, with and without the sun.
fn round_trip_text(rt: &FileRoundTrip) -> String {
    format!(
        "CIEDE2000 energy-weighted mean {:.4}, max {:.4}; without the {} sun pixels: mean {:.4}, \
         max {:.4}",
        rt.all.weighted_mean_de2000,
        rt.all.max_de2000,
        rt.sun_pixels,
        rt.without_sun.weighted_mean_de2000,
        rt.without_sun.max_de2000
    )
}

fn convert_section(o: &mut String, run: &Run) {
    outln!(o, "<h2>2. The environment map, RGB → spectral</h2>");
    outln!(
        o,
        "<p><code>{}</code> becomes a spectral OpenEXR (one channel per wavelength, an RGB \
         preview and a sun mask). First the map's lights are found and classified (the sun, the \
         sky or windows, each lamp of its family); then every pixel gets a non-negative spectrum \
         carried by the light that lights it. The heatmaps integrate each pixel's spectrum back \
         to RGB and compare it with the original (ΔE00); each has its own colour scale, drawn \
         beneath it with the range it spans. By default only the sun's pixels, which share one \
         spectrum, and the few colours no non-negative spectrum under their light makes, \
         differ; the paper's three weights desaturate every coloured pixel.</p>",
        esc(&run.env),
    );
    let i = &run.inspected;
    outln!(o, "<h3>the lights of the map</h3>");
    outln!(o, "<table class=\"facts\">");
    for l in &i.lights {
        outln!(
            o,
            "<tr><th>{}</th><td>{}: {:.1}% of the energy, {:.1}° up; {}</td></tr>",
            esc(&format!("{:?}", l.kind).to_lowercase()),
            esc(&l.spd),
            100.0 * l.energy_share,
            l.elevation_deg,
            esc(&l.reason)
        );
    }
    outln!(o, "</table>");
    figure(
        o,
        &i.overlay,
        "The map's lights drawn over it",
        "Each light's region tinted and outlined in its kind's colour, numbered, with its \
         spectrum and share of the energy.",
        "wide",
    );
    commands(o, &[&i.command]);
    for (c, what) in [
        (&run.converted, "the default (all lights, faithful)"),
        (&run.paper, "the paper's mode, a smaller copy"),
    ] {
        outln!(o, "<h3>{}</h3>", esc(what));
        convert_facts(o, c);
        figure(
            o,
            &c.heatmap,
            &format!("Round-trip CIEDE2000 heatmap, {what}"),
            &format!(
                "Round-trip CIEDE2000 per pixel of <code>{}</code>, {}.",
                esc(&c.file),
                esc(what)
            ),
            "wide",
        );
        commands(o, &[&c.command, &c.roundtrip_command]);
    }
}

fn render_section(o: &mut String, run: &Run) {
    outln!(o, "<h2>3. Spectral preview renders</h2>");
    let s = &run.render_spectral;
    outln!(
        o,
        "<p>The paper's figures 6-9 as the renderer's presets and the 24 ColorChecker spheres, \
         lit by the spectra the converted map holds (projected onto its own principal \
         components; its sun as a directional light) and seen against it; the chart compares \
         D65, A and low-pressure sodium side by side under its own lights. {} wavelengths ({} \
         nm, {} rule), Phong (Eq. 1) with thin films (Eq. 2-9). Renderer: <strong>{}</strong>.\
         </p>",
        s.grid.len(),
        esc(&s.grid.to_string()),
        esc(&s.rule.to_string()),
        esc(&run.renderer)
    );
    for r in &run.renders {
        figure(
            o,
            &r.file,
            &format!("The {} preset", r.preset.name()),
            &format!(
                "<strong>{}</strong> {}×{}, {} on the {}",
                esc(r.preset.name()),
                r.size.0,
                r.size.1,
                esc(&format!("{:.2} s", r.seconds)),
                esc(&r.backend.to_string().to_uppercase())
            ),
            "",
        );
    }
    let lines: Vec<&str> = run.renders.iter().map(|r| r.command.as_str()).collect();
    commands(o, &lines);
}

fn tradeoff_section(o: &mut String, run: &Run) {
    outln!(o, "<h2>4. Speed for accuracy</h2>");
    outln!(
        o,
        "<p>The 24 ColorChecker patches and the light itself, with light, reflectances and CMFs \
         sampled on a coarser grid, against the same at 1 nm by Simpson's rule (CIEDE2000 in \
         CIELAB of the light's white). µs per colour is the time to resample and integrate one \
         stimulus. A ΔE00 below 1 is hard to see. A grid can step over a line spectrum \
         (low-pressure sodium's 589 nm doublet): then it sees no light at all.</p>"
    );
    outln!(
        o,
        "<table class=\"tradeoff\"><thead><tr><th>light</th><th class=\"n\">step (nm)</th>\
         <th class=\"n\">samples</th><th>rule</th><th class=\"n\">mean ΔE00</th>\
         <th class=\"n\">max ΔE00</th><th>worst</th><th class=\"n\">µs per colour</th></tr>\
         </thead>"
    );
    let mut last = None;
    for r in &run.tradeoff {
        if last != Some(r.light.as_str()) {
            if last.is_some() {
                outln!(o, "</tbody>");
            }
            outln!(o, "<tbody class=\"light\">");
            last = Some(r.light.as_str());
        }
        let head = format!(
            "<td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td>{}</td>",
            esc(&r.light),
            r.step_nm,
            r.samples,
            esc(&r.rule.to_string())
        );
        match &r.measurement {
            Some(m) => outln!(
                o,
                "<tr>{head}<td class=\"n\">{:.4}</td><td class=\"n\">{:.4}</td><td>{}</td>\
                 <td class=\"n\">{:.2}</td></tr>",
                m.mean_de2000,
                m.max_de2000,
                esc(&m.worst),
                m.micros_per_colour
            ),
            None => outln!(
                o,
                "<tr class=\"miss\">{head}<td colspan=\"4\">misses the line (no light on this \
                 grid)</td></tr>"
            ),
        }
    }
    if last.is_some() {
        outln!(o, "</tbody>");
    }
    outln!(o, "</table>");
    outln!(
        o,
        "<p>One entry of the table by hand, and the coarsest step within a tolerance (the same \
         measurement, <code>specmap::tradeoff</code>):</p>"
    );
    commands(
        o,
        &[
            "specmap color colorchecker:red --under FL2 --range 380:780:10",
            "specmap color colorchecker:red --under FL2 --tolerance 0.5",
        ],
    );
}

#[cfg(test)]
mod tests {
    use super::esc;

    #[test]
    fn text_is_escaped() {
        assert_eq!(
            esc(r#"<a href="x">Tom & 'Jerry'</a>"#),
            "&lt;a href=&quot;x&quot;&gt;Tom &amp; &#39;Jerry&#39;&lt;/a&gt;"
        );
    }
}
