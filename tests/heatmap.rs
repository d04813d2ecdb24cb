//! `specmap roundtrip --heatmap` through the binary, on the default mode's conversion of the
//! bundled sunrise map (an exact round trip but for the sun): the map shows its errors instead
//! of a black rectangle, a colour bar sits beneath it, and the range is stated.

use std::path::Path;

mod common;

use common::{sample, specmap};

/// Converts sunrise.exr (64 rows, the default mode) into `dir` and returns the output's path.
fn converted(dir: &Path) -> String {
    let out = dir.join("sunrise.spectral.exr").display().to_string();
    let o = specmap(&[
        "convert",
        &sample("sunrise.exr"),
        "-o",
        &out,
        "--light",
        "auto",
        "--size",
        "64",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

/// Runs `roundtrip FILE --heatmap PNG EXTRA...`; returns its stderr and the image.
fn heatmap(file: &str, png: &Path, extra: &[&str]) -> (String, image::RgbImage) {
    let mut args = vec!["roundtrip", file, "--heatmap", png.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = specmap(&args);
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{stderr}");
    (stderr, image::open(png).unwrap().to_rgb8())
}

/// Shares of the map's pixels (the top 128 x 64 map pixels, each drawn `zoom` x `zoom`) that
/// are black and that are white.
fn dark_and_white(img: &image::RgbImage) -> (f64, f64) {
    let zoom = img.width() / 128;
    let (mut dark, mut white, mut n) = (0, 0, 0);
    for y in 0..64 {
        for x in 0..128 {
            let p = img.get_pixel(x * zoom + zoom / 2, y * zoom + zoom / 2).0;
            n += 1;
            dark += usize::from(p.iter().all(|&c| c < 8));
            white += usize::from(p.iter().all(|&c| c > 247));
        }
    }
    (dark as f64 / n as f64, white as f64 / n as f64)
}

#[test]
fn the_default_heatmap_shows_the_map_and_its_colour_scale() {
    let d = tempfile::tempdir().unwrap();
    let file = converted(d.path());
    let png = d.path().join("h.png");
    let (said, img) = heatmap(&file, &png, &[]);

    // The map: almost every pixel has a colour inside the scale, neither black nor white.
    let zoom = img.width() / 128;
    assert!(zoom >= 1 && img.width() % 128 == 0, "{}", img.width());
    let (dark, white) = dark_and_white(&img);
    assert!(dark < 0.05 && white < 0.01, "black {dark}, white {white}");

    // Beneath it, the legend: a colour bar (one row of it holds a gradient of many colours) and
    // text (black on white).
    let legend = 64 * zoom..img.height();
    assert!(legend.len() >= 60, "no room for a legend: {}", img.height());
    let most = legend
        .clone()
        .map(|y| {
            let mut row: Vec<[u8; 3]> = (0..img.width()).map(|x| img.get_pixel(x, y).0).collect();
            row.dedup();
            row.len()
        })
        .max()
        .unwrap();
    assert!(
        most > 200,
        "no colour bar: {most} colours in the legend's richest row"
    );
    let ink = legend
        .flat_map(|y| (0..img.width()).map(move |x| (x, y)))
        .filter(|&(x, y)| img.get_pixel(x, y).0 == [0, 0, 0])
        .count();
    assert!(ink > 500, "no labels: {ink} black pixels");

    // The range is stated, from the percentiles, and below 1 CIEDE2000 (the map is exact but
    // for the sun and half-float storage).
    assert!(said.contains("log scale"), "{said}");
    assert!(said.contains("the 1st to 99.9th percentile"), "{said}");
    let range = said.split("log scale, ").nth(1).unwrap();
    let high: f64 = range
        .split(" to ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(high < 1.0, "{said}");
}

#[test]
fn a_given_range_is_drawn_and_stated() {
    let d = tempfile::tempdir().unwrap();
    let file = converted(d.path());
    let png = d.path().join("h.png");
    // The old fixed scale, linear 0..5, asked for: the map goes black but for the sun.
    let (said, img) = heatmap(
        &file,
        &png,
        &["--heatmap-scale", "linear", "--heatmap-max", "5"],
    );
    assert!(said.contains("linear scale, 0 to 5"), "{said}");
    let (dark, _) = dark_and_white(&img);
    assert!(dark > 0.99, "black {dark}");
    // Bounds are checked before any work.
    let o = specmap(&[
        "roundtrip",
        &file,
        "--heatmap",
        d.path().join("x.png").to_str().unwrap(),
        "--heatmap-min",
        "2",
        "--heatmap-max",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("--heatmap-min 2 --heatmap-max 1") && e.contains("empty"),
        "{e}"
    );
    assert!(!d.path().join("x.png").exists());
}
