//! Line plots of spectra to PNG or SVG (chosen by the file extension), with an embedded font so
//! they render the same on any machine.

use crate::error::{Error, Result};
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

/// One curve: a label, its points and its colour (sRGB 8-bit).
#[derive(Debug, Clone)]
pub struct Series {
    /// Name shown in the legend.
    pub label: String,
    /// The curve's (x, y) points, in drawing order.
    pub points: Vec<(f64, f64)>,
    /// Line colour, sRGB 8-bit.
    pub color: [u8; 3],
}

/// What to draw around the curves.
#[derive(Debug, Clone)]
pub struct Figure {
    /// Title above the plot.
    pub title: String,
    /// Label of the x axis.
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// The curves, drawn in order.
    pub series: Vec<Series>,
}

static FONT: Once = Once::new();

/// Registers the embedded font as "sans-serif" (once), for every text plotters draws.
pub(crate) fn register_font() {
    FONT.call_once(|| {
        // DejaVu Sans (Bitstream Vera licence, assets/fonts/LICENSE-DejaVu.txt).
        let bytes: &'static [u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");
        // Registration fails only for a malformed font, which a test catches.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, bytes);
    });
}

/// Writes an RGB image (row-major, 3 bytes a pixel) as a PNG through a temporary file renamed
/// into place; `what` names it in errors ("heatmap", "overlay").
pub(crate) fn write_rgb_png(
    path: &Path,
    (w, h): (usize, usize),
    rgb: Vec<u8>,
    what: &str,
) -> Result<()> {
    let drawn =
        |e: String| Error::invalid(format!("{}: cannot draw the {what}: {e}", path.display()));
    let img = image::RgbImage::from_raw(w as u32, h as u32, rgb)
        .ok_or_else(|| drawn("the image buffer does not match its size".into()))?;
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| drawn(e.to_string()))?;
    crate::io::write_atomic(path, &png)
}

/// Writes the figure to `path` (.png or .svg) through a temporary file renamed into place. The
/// figure is drawn in memory, so a file that cannot be written is reported by the operating
/// system's reason, naming `path`.
pub fn write(figure: &Figure, path: &Path) -> Result<()> {
    register_font();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let (w, h) = (960u32, 600u32);
    let drawn =
        |e: String| Error::invalid(format!("{}: cannot draw the plot: {e}", path.display()));
    let bytes = match ext.as_str() {
        "png" => {
            let mut rgb = vec![0u8; w as usize * h as usize * 3];
            draw(
                figure,
                BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area(),
            )
            .map_err(drawn)?;
            let img = image::RgbImage::from_raw(w, h, rgb)
                .ok_or_else(|| drawn("the image buffer does not match its size".into()))?;
            let mut png = Vec::new();
            img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
                .map_err(|e| drawn(e.to_string()))?;
            png
        }
        "svg" => {
            let mut svg = String::new();
            draw(
                figure,
                SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area(),
            )
            .map_err(drawn)?;
            svg.into_bytes()
        }
        _ => {
            return Err(Error::invalid(format!(
                "{}: plots are written as .png or .svg",
                path.display()
            )))
        }
    };
    crate::io::write_atomic(path, &bytes)
}

fn draw<DB: DrawingBackend>(
    figure: &Figure,
    root: DrawingArea<DB, plotters::coord::Shift>,
) -> std::result::Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let all = figure.series.iter().flat_map(|s| s.points.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, 0.0f64, f64::MIN);
    for &(x, y) in all {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if x0 >= x1 {
        x1 = x0 + 1.0;
    }
    if y1 <= y0 {
        y1 = y0 + 1.0;
    }
    let pad = 0.05 * (y1 - y0);
    let mut chart = ChartBuilder::on(&root)
        .caption(&figure.title, ("sans-serif", 24))
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, (y0 - if y0 < 0.0 { pad } else { 0.0 })..(y1 + pad))
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(&figure.x_label)
        .y_desc(&figure.y_label)
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(e)?;
    for (i, s) in figure.series.iter().enumerate() {
        let c = RGBColor(s.color[0], s.color[1], s.color[2]);
        let drawn = chart
            .draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2)))
            .map_err(e)?
            .label(s.label.clone());
        if s.points.len() > MAX_MARKED_POINTS {
            drawn.legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], c.stroke_width(3)));
            continue;
        }
        // A marker at each measured point, its shape by curve, so that curves which coincide
        // stay visible and the measured points stand out from the lines joining them.
        let shape = Marker::of(i);
        drawn.legend(move |(x, y)| {
            EmptyElement::at((x + 9, y))
                + PathElement::new([(-9, 0), (9, 0)], c.stroke_width(3))
                + shape.element(c)
        });
        chart
            .draw_series(
                s.points
                    .iter()
                    .map(|&p| EmptyElement::at(p) + shape.element(c)),
            )
            .map_err(e)?;
    }
    if figure.series.len() > 1 {
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.3))
            .label_font(("sans-serif", if figure.series.len() > 12 { 10 } else { 13 }))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(e)?;
    }
    root.present().map_err(e)?;
    Ok(())
}

/// Curves with at most this many points get a marker at each (measurements, not spectra).
pub const MAX_MARKED_POINTS: usize = 40;

/// The markers, one per curve in turn: circles of different sizes, open or filled, so that
/// markers of coinciding curves stay apart (a small disc inside a ring inside a larger ring).
#[derive(Debug, Clone, Copy)]
struct Marker {
    radius: i32,
    filled: bool,
}

impl Marker {
    fn of(i: usize) -> Marker {
        let (radius, filled) = [(5, false), (2, true), (8, false), (4, true)][i % 4];
        Marker { radius, filled }
    }

    /// The marker at the origin of an element, in colour `c`.
    fn element(self, c: RGBColor) -> Circle<(i32, i32), i32> {
        let style = if self.filled {
            c.filled()
        } else {
            c.stroke_width(2)
        };
        Circle::new((0, 0), self.radius, style)
    }
}

/// A distinct colour for curve `i` of `n` when the data have no colour of their own.
pub fn palette(i: usize) -> [u8; 3] {
    const P: [[u8; 3]; 10] = [
        [31, 119, 180],
        [255, 127, 14],
        [44, 160, 44],
        [214, 39, 40],
        [148, 103, 189],
        [140, 86, 75],
        [227, 119, 194],
        [127, 127, 127],
        [188, 189, 34],
        [23, 190, 207],
    ];
    P[i % P.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_png_and_svg_and_refuses_other_formats() {
        let dir = tempfile::tempdir().unwrap();
        let fig = Figure {
            title: "test".into(),
            x_label: "Wavelength (nm)".into(),
            y_label: "value".into(),
            series: vec![
                Series {
                    label: "a".into(),
                    points: vec![(400.0, 0.1), (700.0, 0.9)],
                    color: palette(0),
                },
                Series {
                    label: "b".into(),
                    points: vec![(400.0, 0.5), (700.0, 0.2)],
                    color: palette(1),
                },
            ],
        };
        for ext in ["png", "svg"] {
            let p = dir.path().join(format!("f.{ext}"));
            write(&fig, &p).unwrap();
            let bytes = std::fs::read(&p).unwrap();
            assert!(bytes.len() > 1000, "{ext}: {} bytes", bytes.len());
        }
        assert!(std::fs::read(dir.path().join("f.svg"))
            .map(|b| String::from_utf8_lossy(&b).contains("Wavelength"))
            .unwrap());
        assert!(write(&fig, &dir.path().join("f.jpg")).is_err());
        // Two-point curves are measurements: a marker at each point and in each legend entry,
        // a ring for the first curve and a disc for the second.
        let svg = String::from_utf8(std::fs::read(dir.path().join("f.svg")).unwrap()).unwrap();
        assert_eq!(svg.matches("<circle").count(), 2 * (2 + 1), "{svg}");
        assert_eq!(
            svg.matches("r=\"5\" opacity=\"1\" fill=\"none\"").count(),
            3
        );
        // Nothing but the two plots is left behind (no temporary files).
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }
}
