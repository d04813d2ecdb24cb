//! The conversion's last stage: stream the planned spectra into the OpenEXR file, a batch of
//! rows at a time, and measure what was written (round trip, which spectrum each pixel took).

use crate::envmap::convert::carriers::{self, Written};
use crate::envmap::convert::coefficient_rows::{self, RowMut, SpectralRows};
use crate::envmap::convert::pixel_spectra::{Engine, PixelKind, Took};
use crate::envmap::convert::plan::{PixelPlan, Plan};
use crate::envmap::convert::OutputFormat;
use crate::envmap::files::{
    spectral_channel_name, AttrValue, ChannelSet, Compression, EnvmapAttr, Precision,
    SpectralLayout, SpectralWriter, HALF_MAX,
};
use crate::envmap::layout::{EnvMap, Layout};
use crate::envmap::roundtrip::metric::RgbMetric;
use crate::envmap::roundtrip::stats::{Floor, RoundTripAccumulator, RoundTripStats};
use crate::envmap::scene::Cells;
use crate::error::Result;
use crate::fit::Mode;
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
    /// Carrier x non-negative Bernstein combination (exact): the faithful method's fallback where
    /// the smooth modulation and the ColorChecker basis go negative. Not the paper's `nonneg`
    /// mode, whose pixels count as `colorchecker` where exact and `nearest` where not.
    pub nonneg_fallback: usize,
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
            Took::Nonneg => self.nonneg_fallback += 1,
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
        self.nonneg_fallback += o.nonneg_fallback;
        self.nearest += o.nearest;
        self.clipped += o.clipped;
        self.negative += o.negative;
    }
}

/// The round trip over all pixels, without the sun, and over the pixels that could not be
/// exact (the nearest non-negative spectra, clipped lamp pixels, the paper modes' inexact ones).
#[derive(Debug, Clone, Default)]
struct Tally {
    all: RoundTripAccumulator,
    no_sun: RoundTripAccumulator,
    inexact: RoundTripAccumulator,
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
    /// What a written pixel took and whether its round trip is exact. The carriers say so
    /// themselves; the paper's basis is exact in its exact mode, for white only in the paper
    /// mode, and where the spectrum stays non-negative in the nonneg mode, whose other pixels
    /// get the nearest non-negative spectrum: so its pixels are exact when their round trip is.
    fn exactness(&self, w: Written, de: f64) -> (Took, bool) {
        match &self.plan.pixels {
            PixelPlan::Carriers { .. } => (w.took, w.exact),
            PixelPlan::Basis { .. } => {
                let exact = de == 0.0;
                let nearest =
                    !exact && w.took == Took::Colorchecker && self.plan.fit.mode == Mode::Nonneg;
                (if nearest { Took::Nearest } else { w.took }, exact)
            }
        }
    }

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
    /// The luminance floor of the round-trip statistics (the map's).
    pub roundtrip_floor: Floor,
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
    let tally = match &plan.pixels {
        PixelPlan::Basis { engine, .. } => {
            stream_planes(&px, engine, &mut writer, rows_per_block, progress)?
        }
        PixelPlan::Carriers { .. } => {
            stream_rows(&px, &mut writer, rows_per_block, per_pixel, progress)?
        }
    };
    let seconds_encode = writer.encode_seconds();
    let bytes = writer.finish()?;
    let floor = tally.all.floor();
    Ok(WriteStats {
        channels: per_pixel,
        bytes,
        spectra: tally.count,
        roundtrip_floor: floor,
        roundtrip: tally.all.stats(&floor),
        roundtrip_without_sun: tally.no_sun.stats(&floor),
        roundtrip_inexact: tally.inexact.stats(&floor),
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
) -> Result<Tally> {
    let (width, height) = (px.map.image.width, px.map.image.height);
    let mut buffer = vec![0f32; rows_per_block * width * per_pixel];
    let mut tally = Tally::default();
    let mut y0 = 0;
    while y0 < height {
        let rows = rows_per_block.min(height - y0);
        let buf = &mut buffer[..rows * width * per_pixel];
        let batch = buf
            .par_chunks_mut(width * per_pixel)
            .enumerate()
            .fold(Tally::default, |mut t, (r, row)| {
                write_row(px, y0 + r, row, per_pixel, &mut t);
                t
            })
            .reduce(Tally::default, |mut a, b| {
                a.merge(&b);
                a
            });
        tally.merge(&batch);
        writer.write_rows(y0, buf)?;
        y0 += rows;
        progress(y0, height);
    }
    Ok(tally)
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
) -> Result<Tally> {
    let (width, height) = (px.map.image.width, px.map.image.height);
    let bands = match px.plan.format {
        OutputFormat::Spectral => px.plan.grid.len(),
        OutputFormat::Basis => 0,
    };
    let new_batch = || SpectralRows::new(engine.spectra_table(), bands, 4, width, rows_per_block);
    let mut planes = [new_batch(), new_batch()];
    // Each row's tally is merged as it is done (a map's rows of luminance bins would not fit).
    let tally = std::sync::Mutex::new(Tally::default());
    let fill = |y: usize, mut row: RowMut| {
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
            let w = Written {
                rgb_back: r.rgb_back,
                took: r.took,
                exact: true,
            };
            measure(
                &mut t,
                px,
                x,
                y,
                w,
                r.negative,
                is_sun && r.took == Took::Sun,
            );
        }
        tally
            .lock()
            .expect("no tally is merged by a panicking thread")
            .merge(&t);
    };
    coefficient_rows::stream(
        &mut planes,
        height,
        rows_per_block,
        &fill,
        &mut |y0, rows, batch| {
            writer.write_lines(y0, rows, batch)?;
            progress(y0 + rows, height);
            Ok(())
        },
    )?;
    Ok(tally
        .into_inner()
        .expect("no tally is merged by a panicking thread"))
}

/// One row of the output: each pixel's values, and what it took, added to `t`.
fn write_row(px: &Pixels, y: usize, row: &mut [f32], per_pixel: usize, t: &mut Tally) {
    let width = px.map.image.width;
    let bands = px.plan.grid.len();
    // The basis format writes coefficients; the round trip still needs the spectrum.
    let mut scratch = vec![0f32; bands];
    for x in 0..width {
        let rgb = px.map.image.get(x, y);
        let out = &mut row[x * per_pixel..(x + 1) * per_pixel];
        let (w, is_sun, negative) = match px.plan.format {
            OutputFormat::Spectral => {
                let (spectrum, rest) = out.split_at_mut(bands);
                let (w, is_sun) = px.spectrum(x, y, spectrum, &mut [0f32; 4]);
                rest[..3].copy_from_slice(&rgb);
                rest[3] = is_sun as u8 as f32;
                (w, is_sun, carriers::is_negative(spectrum))
            }
            OutputFormat::Basis => {
                let (w, is_sun) = px.spectrum(x, y, &mut scratch, out);
                (w, is_sun, carriers::is_negative(&scratch))
            }
        };
        measure(t, px, x, y, w, negative, is_sun);
    }
}

/// Adds pixel (x, y) to the tally: which spectrum it took, and its round trip (see
/// [`crate::envmap::roundtrip::stats`]) over all pixels, without the sun, and if inexact.
fn measure(
    t: &mut Tally,
    px: &Pixels,
    x: usize,
    y: usize,
    w: Written,
    negative: bool,
    is_sun: bool,
) {
    let metric = px.metric();
    let rgb = px.map.image.get(x, y);
    let lum = metric.luminance(rgb);
    let de = if lum > 0.0 {
        metric.round_trip_error(rgb, w.rgb_back)
    } else {
        0.0
    };
    let (took, exact) = px.exactness(w, de);
    t.count.add(took, negative);
    let omega = px.map.solid_angle(x, y);
    t.all.add(x, y, lum, omega, de);
    if !is_sun {
        t.no_sun.add(x, y, lum, omega, de);
        if !exact {
            t.inexact.add(x, y, lum, omega, de);
        }
    }
}
