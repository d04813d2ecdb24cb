//! `specmap demo` through the real binary: the page exists, every image it shows exists and is a
//! PNG, the trade-off table has its rows, text is escaped, and a missing map is a clear error
//! that writes nothing.

use std::collections::BTreeSet;
use std::path::Path;
use std::process::{Command, Output};

fn specmap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_specmap"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the specmap binary runs")
}

/// Runs the quick demo on the CPU into `dir` and returns the page and the JSON summary.
fn demo(dir: &Path, extra: &[&str]) -> (String, serde_json::Value) {
    let mut args = vec![
        "demo",
        "--quick",
        "--backend",
        "cpu",
        "--json",
        "-o",
        dir.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let out = specmap(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "demo failed: {stderr}");
    // One progress line per step, nothing else.
    let progress: Vec<&str> = stderr.lines().collect();
    assert_eq!(progress.len(), 5, "{stderr}");
    assert!(progress.iter().all(|l| l.starts_with("demo [")), "{stderr}");
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON summary");
    let page = std::fs::read_to_string(dir.join("index.html")).expect("index.html written");
    (page, json)
}

/// Every `src="..."` of the page.
fn images(page: &str) -> BTreeSet<String> {
    page.split("src=\"")
        .skip(1)
        .map(|rest| rest.split('"').next().unwrap().to_string())
        .collect()
}

/// The `<tr>` rows of the trade-off table's bodies.
fn tradeoff_rows(page: &str) -> Vec<&str> {
    let start = page
        .find("<table class=\"tradeoff\">")
        .expect("a trade-off table");
    let table = &page[start..start + page[start..].find("</table>").unwrap()];
    let body = &table[table.find("</thead>").unwrap()..];
    body.split("<tr").skip(1).collect()
}

#[test]
fn the_quick_demo_writes_a_page_whose_images_all_exist() {
    let t = tempfile::tempdir().unwrap();
    let dir = t.path().join("demo");
    let (page, json) = demo(&dir, &[]);

    // The images: the basis plot, two heatmaps, the lights, five renders; each a PNG of its
    // stated size.
    let shown = images(&page);
    let expected: BTreeSet<String> = [
        "basis.png",
        "roundtrip.png",
        "roundtrip-paper.png",
        "lights.png",
        "ball.png",
        "transparent-ball.png",
        "cylinders.png",
        "chart.png",
        "checker-spheres.png",
    ]
    .map(String::from)
    .into();
    assert_eq!(shown, expected);
    for name in &shown {
        let img = image::open(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(img.width() > 0 && img.height() > 0, "{name}");
    }
    for r in json["renders"].as_array().unwrap() {
        let img = image::open(dir.join(r["file"].as_str().unwrap())).unwrap();
        assert_eq!(
            [img.width() as u64, img.height() as u64],
            [
                r["size"][0].as_u64().unwrap(),
                r["size"][1].as_u64().unwrap()
            ]
        );
        assert_eq!(r["backend"], "cpu");
    }
    // Every PNG in the folder is on the page; every file the summary names exists; no leftovers.
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.contains(".tmp"), "temporary file left: {name}");
        if name.ends_with(".png") {
            assert!(shown.contains(&name), "{name} is not on the page");
        }
    }
    for f in json["files"].as_array().unwrap() {
        assert!(dir.join(f.as_str().unwrap()).is_file(), "{f}");
    }
    assert!(dir.join("sunrise.spectral.exr").is_file());

    // The renderer is named, and the commands that reproduce the artefacts are there.
    assert!(page.contains("CPU (--backend cpu)"));
    for c in [
        "specmap fit --light D65",
        "specmap convert envmaps/sunrise.exr -o",
        "specmap roundtrip ",
        "specmap render --scene chart",
        "specmap render --scene ball --env",
    ] {
        assert!(page.contains(c), "page lacks `{c}`");
    }
    assert!(!page.contains("<script"));

    // The trade-off table: 6 lights x (3 Riemann steps + Simpson at 5 nm), light by light; low-
    // pressure sodium at 20 nm steps over its line.
    let rows = tradeoff_rows(&page);
    assert_eq!(rows.len(), 24);
    for (i, light) in ["D65", "A", "FL2", "FL11", "LED-B3", "lps"]
        .iter()
        .enumerate()
    {
        for r in &rows[4 * i..4 * i + 4] {
            assert!(r.contains(&format!("<td>{light}</td>")), "{r}");
        }
    }
    let missed: Vec<&&str> = rows
        .iter()
        .filter(|r| r.contains("misses the line"))
        .collect();
    assert_eq!(missed.len(), 1, "{missed:?}");
    assert!(missed[0].contains("<td>lps</td><td class=\"n\">20</td>"));
    let t = json["tradeoff"].as_array().unwrap();
    assert_eq!(t.len(), 24);
    for r in t {
        let miss = r["light"] == "lps" && r["step_nm"] == 20.0;
        assert_eq!(r["misses_the_line"], miss, "{r}");
        assert_eq!(r["max_dE2000"].is_null(), miss, "{r}");
    }
    // The fit's exact mode returns every colour.
    assert!(json["fit"][1]["roundtrip"]["max_dE2000"].as_f64().unwrap() < 1e-6);
}

/// Every number of the page's conversion section comes from the command printed under it: the
/// printed `convert` and `roundtrip`, run again, give the page's numbers.
#[test]
fn the_conversion_numbers_come_from_the_commands_printed_under_them() {
    let t = tempfile::tempdir().unwrap();
    let dir = t.path().join("demo");
    let (page, json) = demo(&dir, &[]);
    let words = |c: &str| -> Vec<String> {
        c.split_whitespace()
            .skip(1)
            .map(|w| w.trim_matches('\'').to_string())
            .collect()
    };
    let convert = json["convert_command"].as_str().unwrap();
    let roundtrip = json["roundtrip_command"].as_str().unwrap();
    for c in [convert, roundtrip] {
        assert!(page.contains(c), "the page does not print `{c}`");
    }
    // The default: no --mode on the command, the faithful method in its report.
    assert!(!convert.contains("--mode"), "{convert}");
    assert_eq!(json["convert"]["mode"], "faithful");
    let mut args = words(convert);
    args.push("--json".into());
    let out = specmap(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let again: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(again["lights"], json["convert"]["lights"]);
    assert_eq!(again["spectra"], json["convert"]["spectra"]);
    let mut args = words(roundtrip);
    args.push("--json".into());
    let out = specmap(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rt: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let shown = format!(
        "CIEDE2000 energy-weighted mean {:.4}, max {:.4}",
        rt["all"]["weighted_mean_de2000"].as_f64().unwrap(),
        rt["all"]["max_de2000"].as_f64().unwrap()
    );
    assert!(page.contains(&shown), "the page lacks `{shown}`");
    assert!(!page.contains("exact mode (the default)"));
}

#[test]
fn text_from_the_input_is_escaped_and_file_names_made_safe() {
    let t = tempfile::tempdir().unwrap();
    let map = t.path().join("a&b <x>.exr");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("envmaps/sunrise.exr"),
        &map,
    )
    .unwrap();
    let dir = t.path().join("out");
    let (page, _) = demo(&dir, &["--env", map.to_str().unwrap()]);
    assert!(page.contains("a&amp;b &lt;x&gt;.exr"));
    assert!(!page.contains("<x>"));
    // The shell commands quote the path.
    assert!(page.contains("specmap convert &#39;"));
    assert!(dir.join("a_b__x_.spectral.exr").is_file());
}

/// `specmap demo --quick --backend cpu -o DIR --env MAP`, expected to fail.
fn quick_demo_on(dir: &Path, map: &Path) -> Output {
    specmap(&[
        "demo",
        "--quick",
        "--backend",
        "cpu",
        "-o",
        dir.to_str().unwrap(),
        "--env",
        map.to_str().unwrap(),
    ])
}

#[test]
fn a_missing_map_is_a_clear_error_and_writes_nothing() {
    let t = tempfile::tempdir().unwrap();
    let dir = t.path().join("demo");
    let missing = t.path().join("nope.exr");
    let out = quick_demo_on(&dir, &missing);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("--env") && stderr.contains("nope.exr") && stderr.contains("no such file"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(out.stdout.is_empty());
    assert!(!dir.join("index.html").exists());
    assert!(
        !dir.exists(),
        "nothing is created before the input is found"
    );
}

#[test]
fn a_map_that_is_not_an_image_fails_before_anything_is_written() {
    // Found but unreadable (text named .exr), or readable but no environment layout (3:1).
    let t = tempfile::tempdir().unwrap();
    let text = t.path().join("text.exr");
    std::fs::write(&text, "not an image").unwrap();
    let wide = t.path().join("wide.exr");
    exr::prelude::write_rgb_file(&wide, 12, 4, |_, _| (0.5f32, 0.5f32, 0.5f32)).unwrap();
    for (map, says) in [(&text, "unrecognised"), (&wide, "--in-layout")] {
        let dir = t.path().join("demo");
        let out = quick_demo_on(&dir, map);
        assert_eq!(out.status.code(), Some(1));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(says), "{stderr}");
        assert!(!stderr.contains("demo [1/5]"), "work started: {stderr}");
        assert!(!dir.exists(), "{} was created", dir.display());
    }
}

/// A new user's first run, from a shell without XDG_RUNTIME_DIR (ssh, CI, a container): the
/// README's main job, on whatever renderer the machine has, prints no line with "error" when
/// nothing is wrong. (Mesa's Vulkan device-select layer used to make libwayland print "error:
/// XDG_RUNTIME_DIR is invalid or not set" twice before the demo's own lines.)
#[test]
fn the_first_run_prints_no_error_without_a_runtime_dir() {
    let t = tempfile::tempdir().unwrap();
    let dir = t.path().join("demo");
    let out = Command::new(env!("CARGO_BIN_EXE_specmap"))
        .args(["demo", "--quick", "-o", dir.to_str().unwrap()])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .expect("the specmap binary runs");
    let text = String::from_utf8_lossy(&out.stderr) + String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    let errors: Vec<&str> = text
        .lines()
        .filter(|l| l.to_lowercase().contains("error"))
        .collect();
    assert!(errors.is_empty(), "{errors:#?}\nin:\n{text}");
    assert!(text.contains("demo [5/5] page"), "{text}");
}
