//! Per-pixel CIEDE2000 heatmaps: the error image of a map with, beneath it, a labelled colour
//! bar and the range it spans, the range chosen so that the map shows something.
//!
//! The range is a value ([`Range`]) chosen before drawing ([`choose_range`]) and stated on the
//! image. By default the scale is logarithmic between the 1st and the 99.9th percentile of the
//! pixels' errors, rounded outwards to 1, 2 or 5 times a power of ten: an exact conversion's map
//! (half-float errors of about 0.002, a few sun pixels at 14) and the paper's mode (errors of 1
//! to 15) both fill the bar, where one linear 0..5 scale drew the first as a black rectangle with
//! one white dot. The colour map is black, red, yellow, white; pixels not compared (zero
//! luminance, NaN) are blue, a colour the map never takes.

use crate::error::{Error, Result};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// How errors map to the colour bar.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Scale {
    /// Equal ratios get equal lengths of the bar (the default: errors span decades).
    Log,
    /// Equal differences get equal lengths.
    Linear,
}

/// Where a bound of the range came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Bound {
    /// Given by the caller.
    Given,
    /// A percentile of the compared pixels' errors ([`LOW_PERCENTILE`], [`HIGH_PERCENTILE`]),
    /// rounded outwards to 1, 2 or 5 times a power of ten.
    Percentile,
    /// The linear scale's zero.
    Zero,
    /// No pixel has a positive error: a fixed decade, stated as such.
    Fixed,
    /// Kept clear of the other, given end (its percentile fell beyond it).
    Apart,
}

/// The percentile of the compared pixels' errors at the bottom of an automatic log range.
pub const LOW_PERCENTILE: f64 = 1.0;
/// The percentile at the top of an automatic range: at most 0.1% of the pixels (a sun) saturate.
pub const HIGH_PERCENTILE: f64 = 99.9;

/// The colour bar's range: errors at `low` and below are black, at `high` and above white.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Range {
    /// How errors map to the colour bar.
    pub scale: Scale,
    /// CIEDE2000 at the bottom of the bar (drawn black).
    pub low: f64,
    /// CIEDE2000 at the top of the bar (drawn white).
    pub high: f64,
    /// Where `low` came from.
    pub low_from: Bound,
    /// Where `high` came from.
    pub high_from: Bound,
}

/// What was drawn: the range, how many pixels fell outside it and how many were not compared.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Heatmap {
    /// The colour bar's range.
    pub range: Range,
    /// Pixels above `high` (drawn white).
    pub above: usize,
    /// Pixels below `low` (drawn black).
    pub below: usize,
    /// Pixels without an error (NaN: zero luminance or not finite), drawn blue.
    pub not_compared: usize,
    /// The PNG's size in pixels (the map, enlarged to at least [`MIN_WIDTH`], and the legend).
    pub image_size: [usize; 2],
    /// How many image pixels wide and high each map pixel is drawn.
    pub zoom: usize,
}

/// The narrowest image: a smaller map is enlarged by a whole factor, so the legend's text fits.
pub const MIN_WIDTH: usize = 640;
/// The colour of pixels not compared.
pub const NOT_COMPARED: [u8; 3] = [40, 90, 200];
const LEGEND_HEIGHT: usize = 96;
const PAD: i32 = 12;
const BAR_HEIGHT: i32 = 16;

/// Checks given bounds before any work: each finite and positive (log) or at least 0 (linear),
/// and `low` below `high` when both are given.
pub fn check_bounds(scale: Scale, low: Option<f64>, high: Option<f64>) -> Result<()> {
    for (name, v) in [("lowest", low), ("highest", high)] {
        if let Some(v) = v {
            let ok = v.is_finite()
                && if scale == Scale::Log {
                    v > 0.0
                } else {
                    v >= 0.0
                };
            if !ok {
                return Err(Error::invalid(format!(
                    "the heatmap's {name} value {v} must be a finite number{}",
                    if scale == Scale::Log {
                        " above 0 on a log scale"
                    } else {
                        ", at least 0"
                    }
                )));
            }
        }
    }
    if let (Some(l), Some(h)) = (low, high) {
        if l >= h {
            return Err(Error::invalid(format!(
                "the heatmap's range {l}..{h} is empty: the lowest value must be below the \
                 highest"
            )));
        }
    }
    Ok(())
}

/// The range for `de` (one error per pixel, NaN where not compared): `low` and `high` where
/// given ([`check_bounds`]), else from the percentiles (log) or zero (linear low). An automatic
/// end keeps clear of a given one: on a log scale a decade at least, on a linear one a factor 2.
pub fn choose_range(
    de: &[f32],
    scale: Scale,
    low: Option<f64>,
    high: Option<f64>,
) -> Result<Range> {
    check_bounds(scale, low, high)?;
    let mut positive: Vec<f64> = de
        .iter()
        .filter(|v| v.is_finite() && **v > 0.0)
        .map(|&v| v as f64)
        .collect();
    positive.sort_by(f64::total_cmp);
    let at = |p: f64| positive[((positive.len() - 1) as f64 * p / 100.0).round() as usize];
    let apart = if scale == Scale::Log { 10.0 } else { 2.0 };
    let (high, high_from) = match (high, positive.is_empty()) {
        (Some(h), _) => (h, Bound::Given),
        (None, true) => (if scale == Scale::Log { 1e-2 } else { 1.0 }, Bound::Fixed),
        (None, false) => (nice(at(HIGH_PERCENTILE), true), Bound::Percentile),
    };
    let (high, high_from) = match low {
        Some(l) if high_from != Bound::Given && high <= l => (nice(apart * l, true), Bound::Apart),
        _ => (high, high_from),
    };
    let (low, low_from) = match (scale, low, positive.is_empty()) {
        (_, Some(l), _) => (l, Bound::Given),
        (Scale::Linear, None, _) => (0.0, Bound::Zero),
        (Scale::Log, None, true) => (high / 10.0, Bound::Fixed),
        // At least a decade below the top, so the bar has one.
        (Scale::Log, None, false) => (
            nice(at(LOW_PERCENTILE), false).min(nice(high / 10.0, false)),
            Bound::Percentile,
        ),
    };
    Ok(Range {
        scale,
        low,
        high,
        low_from,
        high_from,
    })
}

/// 1, 2 or 5 times a power of ten: the next at or above `v` (`up`), else at or below.
fn nice(v: f64, up: bool) -> f64 {
    let e = v.log10().floor();
    let base = 10f64.powf(e);
    let steps = [1.0, 2.0, 5.0, 10.0];
    let m = v / base;
    let pick = if up {
        steps
            .iter()
            .find(|&&s| s >= m * (1.0 - 1e-12))
            .copied()
            .unwrap_or(10.0)
    } else {
        steps
            .iter()
            .rev()
            .find(|&&s| s <= m * (1.0 + 1e-12))
            .copied()
            .unwrap_or(1.0)
    };
    pick * base
}

impl Range {
    /// Where `v` falls on the bar, 0 at `low` and 1 at `high` (clamped).
    pub fn position(&self, v: f64) -> f64 {
        let t = match self.scale {
            Scale::Log => (v.max(f64::MIN_POSITIVE) / self.low).ln() / (self.high / self.low).ln(),
            Scale::Linear => (v - self.low) / (self.high - self.low),
        };
        t.clamp(0.0, 1.0)
    }

    /// The values labelled under the bar: both ends, and the powers of ten (log) or a few round
    /// steps (linear) between them.
    fn ticks(&self) -> Vec<f64> {
        let mut t = vec![self.low];
        match self.scale {
            Scale::Log => {
                let mut p = 10f64.powf(self.low.log10().floor() + 1.0);
                while p < self.high * (1.0 - 1e-9) {
                    if p > self.low * (1.0 + 1e-9) {
                        t.push(p);
                    }
                    p *= 10.0;
                }
            }
            Scale::Linear => {
                let step = nice((self.high - self.low) / 5.0, true);
                let mut v = (self.low / step).floor() * step + step;
                while v < self.high - step * 0.3 {
                    t.push(v);
                    v += step;
                }
            }
        }
        t.push(self.high);
        t
    }
}

/// The hot colour map: black at 0, through red and yellow, white at 1.
pub fn hot(t: f64) -> [u8; 3] {
    let t = t.clamp(0.0, 1.0);
    let c = [3.0 * t, 3.0 * t - 1.0, 3.0 * t - 2.0];
    c.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// A number as the legend prints it: up to three significant digits, exponent form beyond
/// 0.001..9999.
pub fn label(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let e = v.abs().log10().floor() as i32;
    if !(-3..=3).contains(&e) {
        let m = v / 10f64.powi(e);
        let m = format!("{m:.2}");
        let m = m.trim_end_matches('0').trim_end_matches('.');
        return format!("{m}e{e}");
    }
    let s = format!("{:.*}", (2 - e).max(0) as usize, v);
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Writes the heatmap of `de` (a `width` x `height` map, row-major, NaN where not compared) as a
/// PNG: the map in `range`'s colours, enlarged to at least [`MIN_WIDTH`] pixels wide, and
/// beneath it the colour bar with its labels and the range in words. Written through a
/// temporary file renamed into place.
pub fn write_heatmap(
    path: &Path,
    width: usize,
    height: usize,
    de: &[f32],
    range: &Range,
) -> Result<Heatmap> {
    if width == 0 || height == 0 || de.len() != width * height {
        return Err(Error::invalid(format!(
            "{}: a heatmap needs one value per pixel of a {width}x{height} map, got {}",
            path.display(),
            de.len()
        )));
    }
    let zoom = MIN_WIDTH.div_ceil(width).max(1);
    let (w, map_h) = (width * zoom, height * zoom);
    let h = map_h + LEGEND_HEIGHT;
    let mut rgb = vec![255u8; w * h * 3];
    let mut summary = Heatmap {
        range: *range,
        above: 0,
        below: 0,
        not_compared: 0,
        image_size: [w, h],
        zoom,
    };
    for (i, &v) in de.iter().enumerate() {
        let c = if !v.is_finite() {
            summary.not_compared += 1;
            NOT_COMPARED
        } else {
            let v = v as f64;
            summary.above += usize::from(v > range.high);
            summary.below += usize::from(v < range.low);
            hot(range.position(v))
        };
        let (x, y) = (i % width, i / width);
        for yy in y * zoom..(y + 1) * zoom {
            for xx in x * zoom..(x + 1) * zoom {
                rgb[(yy * w + xx) * 3..][..3].copy_from_slice(&c);
            }
        }
    }
    let drawn =
        |e: String| Error::invalid(format!("{}: cannot draw the heatmap: {e}", path.display()));
    draw_legend(&mut rgb, (w, h), map_h, &summary).map_err(drawn)?;
    crate::plot::write_rgb_png(path, (w, h), rgb, "heatmap")?;
    Ok(summary)
}

/// The range in words, as the legend's caption says it.
pub fn caption(s: &Heatmap) -> [String; 2] {
    let r = &s.range;
    let (lo, hi) = (label(LOW_PERCENTILE), label(HIGH_PERCENTILE));
    let from = match (r.low_from, r.high_from) {
        (_, Bound::Fixed) => " (no pixel has a positive error)".into(),
        (Bound::Percentile, Bound::Percentile) => format!(" (the {lo}st to {hi}th percentile)"),
        (Bound::Zero, Bound::Percentile) => format!(" (to the {hi}th percentile)"),
        (Bound::Percentile, _) => format!(" (from the {lo}st percentile)"),
        (_, Bound::Percentile) => format!(" (to the {hi}th percentile)"),
        (_, Bound::Apart) => " (the top: clear of the given bottom)".into(),
        _ => String::new(),
    };
    let scale = match r.scale {
        Scale::Log => "log",
        Scale::Linear => "linear",
    };
    [
        format!(
            "CIEDE2000 per pixel, {scale} scale, {} to {}{from}",
            label(r.low),
            label(r.high)
        ),
        format!(
            "{} pixels above (white), {} below (black), {} not compared (blue)",
            s.above, s.below, s.not_compared
        ),
    ]
}

/// Draws the colour bar, its labels and the caption into the white strip below the map.
fn draw_legend(
    rgb: &mut [u8],
    (w, h): (usize, usize),
    top: usize,
    s: &Heatmap,
) -> std::result::Result<(), String> {
    crate::plot::register_font();
    let root = BitMapBackend::with_buffer(rgb, (w as u32, h as u32)).into_drawing_area();
    let e = |e: DrawingAreaErrorKind<_>| e.to_string();
    let (x0, x1) = (PAD, w as i32 - PAD);
    let y0 = top as i32 + PAD;
    for x in x0..x1 {
        let t = (x - x0) as f64 / (x1 - x0 - 1).max(1) as f64;
        let [r, g, b] = hot(t);
        root.draw(&PathElement::new(
            [(x, y0), (x, y0 + BAR_HEIGHT - 1)],
            RGBColor(r, g, b),
        ))
        .map_err(e)?;
    }
    root.draw(&Rectangle::new(
        [(x0 - 1, y0 - 1), (x1, y0 + BAR_HEIGHT)],
        BLACK.stroke_width(1),
    ))
    .map_err(e)?;
    let font = ("sans-serif", 13).into_font().color(&BLACK);
    let r = &s.range;
    for v in r.ticks() {
        let x = x0 + (r.position(v) * (x1 - x0 - 1) as f64).round() as i32;
        let anchor = if x < x0 + 20 {
            HPos::Left
        } else if x > x1 - 20 {
            HPos::Right
        } else {
            HPos::Center
        };
        root.draw(&PathElement::new(
            [(x, y0 + BAR_HEIGHT), (x, y0 + BAR_HEIGHT + 4)],
            BLACK,
        ))
        .map_err(e)?;
        let style = font.clone().pos(Pos::new(anchor, VPos::Top));
        root.draw(&Text::new(label(v), (x, y0 + BAR_HEIGHT + 6), style))
            .map_err(e)?;
    }
    let [first, second] = caption(s);
    root.draw(&Text::new(first, (x0, y0 + BAR_HEIGHT + 28), font.clone()))
        .map_err(e)?;
    root.draw(&Text::new(second, (x0, y0 + BAR_HEIGHT + 48), font))
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_rounds_outwards_to_one_two_five() {
        assert_eq!(nice(0.0023, true), 0.005);
        assert_eq!(nice(0.0023, false), 0.002);
        assert_eq!(nice(14.3, true), 20.0);
        assert_eq!(nice(7.0, false), 5.0);
        assert_eq!(nice(0.001, false), 0.001);
        assert_eq!(nice(0.001, true), 0.001);
    }

    #[test]
    fn labels_are_short() {
        assert_eq!(label(0.001), "0.001");
        assert_eq!(label(0.02), "0.02");
        assert_eq!(label(20.0), "20");
        assert_eq!(label(1e-4), "1e-4");
        assert_eq!(label(2.5e-5), "2.5e-5");
        assert_eq!(label(14.2857), "14.3");
        assert_eq!(label(99.9), "99.9");
    }

    /// An exact conversion's errors: half-float noise around 0.002 and a few sun pixels at 14.
    fn exact_like() -> Vec<f32> {
        let mut de: Vec<f32> = (0..10000)
            .map(|i| 1e-3 * (1.0 + 4.0 * ((i * 7919) % 1000) as f32 / 1000.0))
            .collect();
        de[17] = 14.3;
        de[4242] = 9.0;
        de[5000] = f32::NAN;
        de
    }

    #[test]
    fn the_automatic_range_spans_the_bulk_not_the_outliers() {
        let de = exact_like();
        let r = choose_range(&de, Scale::Log, None, None).unwrap();
        assert_eq!(
            (r.low_from, r.high_from),
            (Bound::Percentile, Bound::Percentile)
        );
        // The bulk spans 0.001..0.005; the bar spans at least a decade.
        assert_eq!((r.low, r.high), (5e-4, 5e-3));
        // Every compared pixel but the two outliers gets a colour strictly inside the bar, and
        // the bulk spreads over most of it.
        let t: Vec<f64> = de
            .iter()
            .filter(|v| v.is_finite())
            .map(|&v| r.position(v as f64))
            .collect();
        assert_eq!(t.iter().filter(|t| **t > 0.0 && **t < 1.0).count(), 9997);
        let spread = t
            .iter()
            .filter(|t| **t < 1.0)
            .fold(0.0f64, |a, b| a.max(*b))
            - t.iter().fold(1.0f64, |a, b| a.min(*b));
        assert!(spread > 0.6, "{spread}");
        // The old fixed linear 0..5: everything but the outliers within 0.1% of black.
        let old = Range {
            scale: Scale::Linear,
            low: 0.0,
            high: 5.0,
            low_from: Bound::Zero,
            high_from: Bound::Given,
        };
        let dark = de
            .iter()
            .filter(|v| v.is_finite() && old.position(**v as f64) < 0.002)
            .count();
        assert_eq!(dark, 9997);
    }

    #[test]
    fn given_bounds_win_and_bad_ones_are_refused() {
        let de = exact_like();
        let r = choose_range(&de, Scale::Log, None, Some(10.0)).unwrap();
        assert_eq!((r.high, r.high_from), (10.0, Bound::Given));
        assert_eq!(r.low, 1e-3);
        let r = choose_range(&de, Scale::Linear, None, None).unwrap();
        assert_eq!((r.low, r.low_from, r.high), (0.0, Bound::Zero, 5e-3));
        for (lo, hi) in [
            (Some(0.0), None),
            (Some(1.0), Some(1.0)),
            (None, Some(f64::NAN)),
        ] {
            let e = choose_range(&de, Scale::Log, lo, hi)
                .unwrap_err()
                .to_string();
            assert!(e.contains("heatmap"), "{e}");
        }
        let r = choose_range(&[f32::NAN, 0.0], Scale::Log, None, None).unwrap();
        assert_eq!((r.low, r.high, r.high_from), (1e-3, 1e-2, Bound::Fixed));
    }

    #[test]
    fn ticks_are_the_ends_and_the_decades_between() {
        let r = Range {
            scale: Scale::Log,
            low: 2e-4,
            high: 20.0,
            low_from: Bound::Given,
            high_from: Bound::Given,
        };
        let t: Vec<String> = r.ticks().into_iter().map(label).collect();
        assert_eq!(t, ["2e-4", "0.001", "0.01", "0.1", "1", "10", "20"]);
        let r = Range {
            scale: Scale::Linear,
            low: 0.0,
            high: 5.0,
            ..r
        };
        let t: Vec<String> = r.ticks().into_iter().map(label).collect();
        assert_eq!(t, ["0", "1", "2", "3", "4", "5"]);
    }

    #[test]
    fn the_image_holds_the_map_the_bar_and_the_counts() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("h.png");
        let de = exact_like();
        let r = choose_range(&de, Scale::Log, None, None).unwrap();
        let s = write_heatmap(&p, 100, 100, &de, &r).unwrap();
        assert_eq!((s.above, s.not_compared, s.zoom), (2, 1, 7));
        let img = image::open(&p).unwrap().to_rgb8();
        assert_eq!([img.width() as usize, img.height() as usize], s.image_size);
        assert_eq!(img.get_pixel(17 * 7 + 3, 3).0, [255, 255, 255]);
        assert_eq!(img.get_pixel(0, 50 * 7 + 3).0, NOT_COMPARED);
        // The bar: many distinct colours along one row of the legend.
        let y = (700 + PAD + BAR_HEIGHT / 2) as u32;
        let mut colours: Vec<[u8; 3]> = (0..img.width()).map(|x| img.get_pixel(x, y).0).collect();
        colours.dedup();
        assert!(colours.len() > 200, "{}", colours.len());
        assert!(caption(&s)[0].contains("log scale, 5e-4 to 0.005 (the 1st to 99.9th"));
    }
}
