//! The conversion's last stage: stream the planned spectra into the OpenEXR file, a batch of
//! rows at a time, and measure what was written (round trip, which spectrum each pixel took).

use crate::envmap::carriers::{self, Written};
use crate::envmap::convert::OutputFormat;
use crate::envmap::engine::{Engine, PixelKind, Took};
use crate::envmap::exrio::{
    spectral_channel_name, AttrValue, ChannelSet, Compression, EnvmapAttr, Precision,
    SpectralLayout, SpectralWriter, HALF_MAX,
};
use crate::envmap::layout::{EnvMap, Layout};
use crate::envmap::metric::RgbMetric;
use crate::envmap::plan::{PixelPlan, Plan};
use crate::envmap::planes::{self, RowMut, SpectralRows};
use crate::envmap::scene::Cells;
use crate::error::Result;
use rayon::prelude::*;
use std::path::Path;
use std::time::Instant;

/// The most bytes of f32 rows computed before they are written (one batch; the writer's blocks
/// and their compressed form come on top, about as much again).
const BATCH_BYTES: usize = 96 << 20;

/// How many pixels got which spectrum.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct SpectraCount {
    pub sun: usize,
    /// CIE daylight family (sky, windows, daylight-coloured pixels as bright as them).
    pub daylight: usize,
    /// Carrier x smooth modulation.
    pub smooth: usize,
    /// Carrier x ColorChecker basis.
    pub colorchecker: usize,
    /// Carrier x non-negative Bernstein combination (exact).
    pub nonneg: usize,
    /// The nearest non-negative spectrum (the colour is not one its light can make).
    pub nearest: usize,
    /// Clipped lamp pixels given their lamp's SPD.
    pub clipped: usize,
    /// Pixels whose spectrum goes below zero somewhere.
    pub negative: usize,
}

impl SpectraCount {
    fn add(&mut self, took: Took, negative: bool) {
        match took {
            Took::Sun => self.sun += 1,
            Took::Daylight => self.daylight += 1,
            Took::Smooth => self.smooth += 1,
            Took::Colorchecker => self.colorchecker += 1,
            Took::Nonneg => self.nonneg += 1,
            Took::Nearest => self.nearest += 1,
            Took::Fixed => self.clipped += 1,
        }
        self.negative += negative as usize;
    }
    fn merge(&mut self, o: &SpectraCount) {
        self.sun += o.sun;
        self.daylight += o.daylight;
        self.smooth += o.smooth;
        self.colorchecker += o.colorchecker;
        self.nonneg += o.nonneg;
        self.nearest += o.nearest;
        self.clipped += o.clipped;
        self.negative += o.negative;
    }
}

/// RGB -> SPD -> RGB over a set of written pixels.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct RoundTripStats {
    /// Energy-weighted (luminance x solid angle) mean CIEDE2000.
    pub weighted_mean_de2000: f64,
    pub max_de2000: f64,
    pub pixels: usize,
}

#[derive(Debug, Clone, Copy, Default)]
struct Accumulator {
    weighted: f64,
    weight: f64,
    max: f64,
    pixels: usize,
}

impl Accumulator {
    fn add(&mut self, de: f64, w: f64) {
        self.weighted += de * w;
        self.weight += w;
        self.max = self.max.max(de);
        self.pixels += 1;
    }
    fn merge(&mut self, o: &Accumulator) {
        self.weighted += o.weighted;
        self.weight += o.weight;
        self.max = self.max.max(o.max);
        self.pixels += o.pixels;
    }
    fn stats(&self) -> RoundTripStats {
        RoundTripStats {
            weighted_mean_de2000: if self.weight > 0.0 {
                self.weighted / self.weight
            } else {
                0.0
            },
            max_de2000: self.max,
            pixels: self.pixels,
        }
    }
}

/// The round trip over all pixels, without the sun, and over the pixels that could not be
/// exact (the nearest non-negative spectra, clipped lamp pixels).
#[derive(Debug, Clone, Copy, Default)]
struct Tally {
    all: Accumulator,
    no_sun: Accumulator,
    inexact: Accumulator,
    count: SpectraCount,
}

impl Tally {
    fn merge(&mut self, o: &Tally) {
        self.all.merge(&o.all);
        self.no_sun.merge(&o.no_sun);
        self.inexact.merge(&o.inexact);
        self.count.merge(&o.count);
    }
}

/// One pixel's spectrum, whichever engine the plan chose.
struct Pixels<'a> {
    map: &'a EnvMap,
    cells: &'a Cells,
    plan: &'a Plan,
}

impl Pixels<'_> {
    fn metric(&self) -> &RgbMetric {
        match &self.plan.pixels {
            PixelPlan::Basis { engine, .. } => engine.metric(),
            PixelPlan::Carriers { engine, .. } => engine.metric(),
        }
    }

    /// The paper's modes: what pixel (x, y) is (the sun's, above the horizon, or plain), and
    /// whether it is the sun's.
    fn basis_kind(&self, x: usize, y: usize) -> (PixelKind, bool) {
        let PixelPlan::Basis { sun, .. } = &self.plan.pixels else {
            return (PixelKind::Plain, false);
        };
        let cell = self.cells.cell_of_pixel(self.map, x, y).unwrap_or(0);
        if sun[cell] {
            (PixelKind::Sun, true)
        } else if self.map.direction(x, y).is_some_and(|d| d[1] > 0.0) {
            (PixelKind::Sky, false)
        } else {
            (PixelKind::Plain, false)
        }
    }

    /// Writes pixel (x, y)'s spectrum into `out`; the basis format's coefficients into `coef`.
    fn spectrum(&self, x: usize, y: usize, out: &mut [f32], coef: &mut [f32]) -> (Written, bool) {
        let rgb = self.map.image.get(x, y);
        let cell = self.cells.cell_of_pixel(self.map, x, y).unwrap_or(0);
        match &self.plan.pixels {
            PixelPlan::Basis { engine, .. } => {
                let kind = self.basis_kind(x, y).0;
                if self.plan.format == OutputFormat::Basis {
                    let c = engine.coefficients(rgb, kind == PixelKind::Sun);
                    for k in 0..4 {
                        coef[k] = c[k] as f32;
                    }
                }
                let r = engine.spectrum(rgb, kind, out);
                let w = Written {
                    rgb_back: r.rgb_back,
                    took: r.took,
                    exact: true,
                };
                (w, kind == PixelKind::Sun && r.took == Took::Sun)
            }
            PixelPlan::Carriers { engine, assign } => {
                let a = assign[cell];
                let w = engine.spectrum(rgb, a, out);
                (w, a.sun && w.took == Took::Sun)
            }
        }
    }
}

/// What the EV scale and the precision came to.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Precisions {
    pub precision: Precision,
    /// Values were divided by 2^EV to fit half floats (None: not needed).
    pub ev: Option<f64>,
    /// Pixels whose every value is below half's smallest (written as 0 in half at any EV).
    pub below_half: usize,
    /// Why the precision is what it is, when it is not what was asked.
    pub reason: Option<String>,
}

/// The EV scale for half floats: the peak of every value written, and how many pixels an EV
/// scale would flush to zero. A scale that would flush pixels that half holds unscaled makes the
/// file float instead (nothing is lost silently).
pub fn precisions(map: &EnvMap, cells: &Cells, plan: &Plan, asked: Precision) -> Precisions {
    if asked == Precision::Float {
        return Precisions {
            precision: asked,
            ev: None,
            below_half: 0,
            reason: None,
        };
    }
    let px = Pixels { map, cells, plan };
    let bands = plan.grid.len();
    let width = map.image.width;
    // Per pixel: its largest magnitude, binned by binary exponent.
    let (peak, bins) = (0..map.image.height)
        .into_par_iter()
        .map(|y| {
            let mut out = vec![0f32; bands];
            let mut coef = [0f32; 4];
            let mut bins = [0usize; 300];
            let mut peak = 0f32;
            for x in 0..width {
                if map.direction(x, y).is_none() {
                    continue;
                }
                px.spectrum(x, y, &mut out, &mut coef);
                let values: &[f32] = match plan.format {
                    OutputFormat::Spectral => &out,
                    OutputFormat::Basis => &coef,
                };
                let rgb = map.image.get(x, y);
                let p = values.iter().chain(&rgb).fold(0f32, |m, v| m.max(v.abs()));
                peak = peak.max(p);
                if p > 0.0 && p.is_finite() {
                    bins[(p.log2().floor() as i32 + 150).clamp(0, 299) as usize] += 1;
                }
            }
            (peak, bins)
        })
        .reduce(
            || (0f32, [0usize; 300]),
            |a, b| (a.0.max(b.0), std::array::from_fn(|k| a.1[k] + b.1[k])),
        );
    // Half's smallest subnormal is 2^-24: values below 2^-25 round to 0.
    let flushed =
        |ev: i32| -> usize { bins[..(ev - 25 + 150).clamp(0, 300) as usize].iter().sum() };
    let below_half = flushed(0);
    let ev = (peak as f64 > HALF_MAX as f64).then(|| (peak as f64 / HALF_MAX as f64).log2().ceil());
    match ev {
        Some(e) if flushed(e as i32) > below_half => Precisions {
            precision: Precision::Float,
            ev: None,
            below_half: 0,
            reason: Some(format!(
                "half floats would need values / 2^{e} (EV), which would flush {} more pixels \
                 to zero: written as float instead",
                flushed(e as i32) - below_half
            )),
        },
        _ => Precisions {
            precision: asked,
            ev,
            below_half,
            reason: None,
        },
    }
}

/// What the write did.
#[derive(Debug, Clone)]
pub struct WriteStats {
    pub channels: usize,
    pub bytes: u64,
    pub spectra: SpectraCount,
    pub roundtrip: RoundTripStats,
    pub roundtrip_without_sun: RoundTripStats,
    /// Over the pixels whose spectrum could not reproduce their RGB.
    pub roundtrip_inexact: RoundTripStats,
    pub seconds: f64,
    pub seconds_encode: f64,
}

/// The output's channel names: the bands, R, G, B and the sun mask; or the basis form's.
fn channel_names(plan: &Plan) -> Vec<String> {
    match plan.format {
        OutputFormat::Spectral => plan
            .grid
            .wavelengths_nm()
            .map(spectral_channel_name)
            .chain(["R", "G", "B", "sun"].map(String::from))
            .collect(),
        OutputFormat::Basis => ["c_R", "c_G", "c_B", "sun"].map(String::from).to_vec(),
    }
}

/// Settings of the written file besides its pixels.
pub struct FileSettings {
    pub precision: Precisions,
    pub compression: Compression,
    pub zip_level: u8,
    pub attributes: Vec<(String, AttrValue)>,
}

/// Streams the map's spectra into `output`.
pub fn write(
    map: &EnvMap,
    cells: &Cells,
    plan: &Plan,
    file: FileSettings,
    output: &Path,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<WriteStats> {
    let names = channel_names(plan);
    let per_pixel = names.len();
    let envmap = match map.layout {
        Layout::LatLong => Some(EnvmapAttr::LatLong),
        Layout::Cube => Some(EnvmapAttr::Cube),
        _ => None,
    };
    let (width, height) = (map.image.width, map.image.height);
    let mut writer = SpectralWriter::create(
        output,
        SpectralLayout {
            width,
            height,
            channels: ChannelSet::Custom(names),
            precision: file.precision.precision,
            compression: file.compression,
            envmap,
            ev: file.precision.ev,
            attributes: file.attributes,
            zip_level: file.zip_level,
            unscaled: vec!["sun".into()],
        },
    )?;
    let t1 = Instant::now();
    // Rows are computed, then written, a batch at a time: whole compression blocks, enough for
    // the writer to compress them in parallel, within BATCH_BYTES.
    let lines = file.compression.lines_per_block();
    let block_bytes = lines * width * per_pixel * std::mem::size_of::<f32>();
    let blocks = (BATCH_BYTES / block_bytes.max(1)).clamp(1, height.div_ceil(lines));
    let rows_per_block = (blocks * lines).max(16).min(height);
    let px = Pixels { map, cells, plan };
    let tallies = match &plan.pixels {
        PixelPlan::Basis { engine, .. } => {
            stream_planes(&px, engine, &mut writer, rows_per_block, progress)?
        }
        PixelPlan::Carriers { .. } => {
            stream_rows(&px, &mut writer, rows_per_block, per_pixel, progress)?
        }
    };
    let mut tally = Tally::default();
    for t in tallies {
        tally.merge(&t);
    }
    let seconds_encode = writer.encode_seconds();
    let bytes = writer.finish()?;
    Ok(WriteStats {
        channels: per_pixel,
        bytes,
        spectra: tally.count,
        roundtrip: tally.all.stats(),
        roundtrip_without_sun: tally.no_sun.stats(),
        roundtrip_inexact: tally.inexact.stats(),
        seconds: t1.elapsed().as_secs_f64(),
        seconds_encode,
    })
}

/// The rows written pixel-interleaved, a batch at a time (the faithful method: each pixel's
/// carrier and modulation).
fn stream_rows(
    px: &Pixels,
    writer: &mut SpectralWriter,
    rows_per_block: usize,
    per_pixel: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Vec<Tally>> {
    let (width, height) = (px.map.image.width, px.map.image.height);
    let mut buffer = vec![0f32; rows_per_block * width * per_pixel];
    let mut tallies = Vec::with_capacity(height);
    let mut y0 = 0;
    while y0 < height {
        let rows = rows_per_block.min(height - y0);
        let buf = &mut buffer[..rows * width * per_pixel];
        let row_tallies: Vec<Tally> = buf
            .par_chunks_mut(width * per_pixel)
            .enumerate()
            .map(|(r, row)| write_row(px, y0 + r, row, per_pixel))
            .collect();
        tallies.extend(row_tallies);
        writer.write_rows(y0, buf)?;
        y0 += rows;
        progress(y0, height);
    }
    Ok(tallies)
}

/// The rows as coefficient planes of the engine's few spectra (the paper's modes), the next
/// batch filled while the last is compressed: a band's scan line is one multiply-add per pixel
/// and spectrum, computed as the writer asks for it.
fn stream_planes(
    px: &Pixels,
    engine: &Engine,
    writer: &mut SpectralWriter,
    rows_per_block: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Vec<Tally>> {
    let (width, height) = (px.map.image.width, px.map.image.height);
    let bands = match px.plan.format {
        OutputFormat::Spectral => px.plan.grid.len(),
        OutputFormat::Basis => 0,
    };
    let new_batch = || SpectralRows::new(engine.spectra_table(), bands, 4, width, rows_per_block);
    let mut planes = [new_batch(), new_batch()];
    let fill = |y: usize, mut row: RowMut| -> Tally {
        let mut t = Tally::default();
        // The spectrum itself is only looked at (negative values, the round trip).
        let mut scratch = vec![0f32; px.plan.grid.len()];
        for x in 0..width {
            let rgb = px.map.image.get(x, y);
            let (kind, is_sun) = px.basis_kind(x, y);
            let r = engine.spectrum(rgb, kind, &mut scratch);
            let extra = match px.plan.format {
                OutputFormat::Spectral => {
                    row.set(x, &r.combination);
                    [rgb[0], rgb[1], rgb[2], is_sun as u8 as f32]
                }
                OutputFormat::Basis => engine.coefficients(rgb, is_sun).map(|c| c as f32),
            };
            for (e, v) in extra.into_iter().enumerate() {
                row.set_extra(e, x, v);
            }
            t.count.add(r.took, r.negative);
            let w = Written {
                rgb_back: r.rgb_back,
                took: r.took,
                exact: true,
            };
            measure(&mut t, px, x, y, &w, is_sun && r.took == Took::Sun);
        }
        t
    };
    planes::stream(
        &mut planes,
        height,
        rows_per_block,
        &fill,
        &mut |y0, rows, batch| {
            writer.write_lines(y0, rows, batch)?;
            progress(y0 + rows, height);
            Ok(())
        },
    )
}

/// One row of the output: each pixel's values, and what it took.
fn write_row(px: &Pixels, y: usize, row: &mut [f32], per_pixel: usize) -> Tally {
    let width = px.map.image.width;
    let bands = px.plan.grid.len();
    let mut t = Tally::default();
    // The basis format writes coefficients; the round trip still needs the spectrum.
    let mut scratch = vec![0f32; bands];
    for x in 0..width {
        let rgb = px.map.image.get(x, y);
        let out = &mut row[x * per_pixel..(x + 1) * per_pixel];
        let (w, is_sun) = match px.plan.format {
            OutputFormat::Spectral => {
                let (spectrum, rest) = out.split_at_mut(bands);
                let r = px.spectrum(x, y, spectrum, &mut [0f32; 4]);
                rest[..3].copy_from_slice(&rgb);
                rest[3] = r.1 as u8 as f32;
                t.count.add(r.0.took, carriers::is_negative(spectrum));
                r
            }
            OutputFormat::Basis => {
                let r = px.spectrum(x, y, &mut scratch, out);
                t.count.add(r.0.took, carriers::is_negative(&scratch));
                r
            }
        };
        measure(&mut t, px, x, y, &w, is_sun);
    }
    t
}

/// Adds pixel (x, y)'s round trip to the tally (energy-weighted: luminance x solid angle).
fn measure(t: &mut Tally, px: &Pixels, x: usize, y: usize, w: &Written, is_sun: bool) {
    let metric = px.metric();
    let rgb = px.map.image.get(x, y);
    let omega = px.map.solid_angle(x, y);
    let lum = metric.luminance(rgb);
    if lum > 0.0 && omega > 0.0 {
        let de = metric.round_trip_error(rgb, w.rgb_back);
        t.all.add(de, lum * omega);
        if !is_sun {
            t.no_sun.add(de, lum * omega);
        }
        if !w.exact && !is_sun {
            t.inexact.add(de, lum * omega);
        }
    }
}
