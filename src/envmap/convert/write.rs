//! The conversion's last stage: stream the planned spectra into the OpenEXR file, a batch of
//! rows at a time, and measure what was written (round trip, which spectrum each pixel took).

use crate::envmap::convert::basis_form::{self, BasisStats};
use crate::envmap::convert::coefficient_rows::{self, RowMut, SpectralRows};
use crate::envmap::convert::file_plan::{FilePlan, Output, Precisions};
use crate::envmap::convert::measure::{SpectraCount, Tally};
use crate::envmap::convert::pixel_spectra::Engine;
use crate::envmap::convert::pixels::{basis_written, PixelPlan, Pixels};
use crate::envmap::convert::plan::Plan;
use crate::envmap::files::block::LineSource;
use crate::envmap::files::{
    spectral_channel_name, ChannelSet, EnvmapAttr, Precision, SpectralLayout, SpectralWriter,
};
use crate::envmap::layout::Layout;
use crate::envmap::roundtrip::stats::{Floor, RoundTripStats};
use crate::envmap::scene::Cells;
use crate::error::{Error, Result};
use rayon::prelude::*;
use rayon::slice::ChunksMut;
use std::path::Path;
use std::time::Instant;

/// The most bytes a batch of rows holds between computing and writing: the f32 rows of the
/// pixel-interleaved write, or the two batches of coefficient planes of the planes write and
/// their encoded samples; at least a block per thread (the writer's per-thread block buffers
/// come on top).
const BATCH_BYTES: usize = 32 << 20;

/// What the write did.
#[derive(Debug, Clone)]
pub struct WriteStats {
    /// Channels per pixel in the file.
    pub channels: usize,
    /// Bytes written.
    pub bytes: u64,
    /// How many pixels got which spectrum.
    pub spectra: SpectraCount,
    /// The luminance floor of the round-trip statistics (the map's).
    pub roundtrip_floor: Floor,
    /// Over all pixels.
    pub roundtrip: RoundTripStats,
    /// Over the pixels not given the sun's SPD.
    pub roundtrip_without_sun: RoundTripStats,
    /// Over the pixels whose spectrum could not reproduce their RGB.
    pub roundtrip_inexact: RoundTripStats,
    /// The basis form: how its K spectra hold the spectral form's.
    pub basis: Option<BasisStats>,
    /// What the write found it could not keep, in words.
    pub notes: Vec<String>,
    /// Seconds spent converting and writing.
    pub seconds: f64,
    /// The part of `seconds` spent encoding and compressing the EXR blocks.
    pub seconds_encode: f64,
}

/// Writes the planned file: the spectral form, or the basis form factored from a spectral
/// intermediate (written as float beside the output, read twice, removed).
pub(crate) fn write(
    plan: &Plan,
    cells: &Cells,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<WriteStats> {
    let Some(path) = plan.file.path.as_deref() else {
        return Err(Error::invalid(
            "this conversion was planned without an output file (inspect's plan): nothing to \
             write",
        ));
    };
    match &plan.file.output {
        Output::Spectral { precision } => write_spectral(plan, cells, precision, path, progress),
        Output::Basis {
            intermediate,
            precision,
        } => {
            let spectral = intermediate.as_deref().unwrap_or(path);
            let stats = write_spectral(plan, cells, &Precisions::float(), spectral, progress)?;
            let basis = write_basis(spectral, path, *precision, &plan.file);
            let _ = std::fs::remove_file(spectral);
            with_basis(stats, basis?)
        }
    }
}

/// The basis form of the spectral file at `spectral`, written to `output`.
fn write_basis(
    spectral: &Path,
    output: &Path,
    precision: Precision,
    file: &FilePlan,
) -> Result<(BasisStats, u64)> {
    let a = basis_form::analyse(spectral)?;
    basis_form::write(
        spectral,
        &a,
        output,
        precision,
        file.compression,
        file.zip_level,
    )
}

/// The spectral write's statistics with the basis form's file in place of the intermediate.
fn with_basis(stats: WriteStats, (basis, bytes): (BasisStats, u64)) -> Result<WriteStats> {
    let mut notes = stats.notes;
    if basis.below_half > 0 {
        notes.push(format!(
            "{} pixels' coefficients are all below what half floats hold after the EV \
             scale: written as 0 (--precision float keeps them)",
            basis.below_half
        ));
    }
    Ok(WriteStats {
        channels: basis.k + 3,
        bytes,
        basis: Some(basis),
        notes,
        ..stats
    })
}

/// The output's channel names: the bands, R, G, B and the sun mask.
fn channel_names(plan: &Plan) -> Vec<String> {
    plan.grid
        .wavelengths_nm()
        .map(spectral_channel_name)
        .chain(["R", "G", "B", "sun"].map(String::from))
        .collect()
}

/// Streams the map's spectra into a spectral OpenEXR at `output`, in `precision`.
fn write_spectral(
    plan: &Plan,
    cells: &Cells,
    precision: &Precisions,
    output: &Path,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<WriteStats> {
    let map = &plan.input.map;
    let names = channel_names(plan);
    let per_pixel = names.len();
    let envmap = match map.layout {
        Layout::LatLong => Some(EnvmapAttr::LatLong),
        Layout::Cube => Some(EnvmapAttr::Cube),
        _ => None,
    };
    let (width, height) = (map.image.width, map.image.height);
    let file = &plan.file;
    let mut writer = SpectralWriter::create(
        output,
        SpectralLayout {
            width,
            height,
            channels: ChannelSet::Custom(names),
            precision: precision.precision,
            compression: file.compression,
            envmap,
            ev: precision.ev,
            attributes: file.attributes.clone(),
            zip_level: file.zip_level,
            unscaled: vec!["sun".into()],
        },
    )?;
    let t1 = Instant::now();
    let lines = file.compression.lines_per_block();
    let tally = stream_spectra(plan, cells, &mut writer, lines, progress)?;
    let seconds_encode = writer.encode_seconds();
    let bytes = writer.finish()?;
    Ok(stats(per_pixel, bytes, tally, t1, seconds_encode))
}

/// The map's spectra computed as [`write`] writes them, kept in memory: the stats and the
/// planes (each pixel's bands, its R, G, B and its sun mask, row by row, as f32).
pub(crate) fn in_memory(
    plan: &Plan,
    cells: &Cells,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(WriteStats, Memory)> {
    let image = &plan.input.map.image;
    let mut sink = Memory::new(image.width, image.height, plan.grid.len());
    let t1 = Instant::now();
    // Batches of 16 rows: what the writer's ZIP blocks hold (the values do not depend on it).
    let tally = stream_spectra(plan, cells, &mut sink, 16, progress)?;
    let per_pixel = channel_names(plan).len();
    Ok((stats(per_pixel, 0, tally, t1, 0.0), sink))
}

/// The statistics of a write that counted `tally` and wrote `bytes`.
fn stats(per_pixel: usize, bytes: u64, tally: Tally, t1: Instant, encode: f64) -> WriteStats {
    let floor = tally.all.floor();
    WriteStats {
        channels: per_pixel,
        bytes,
        spectra: tally.count,
        roundtrip_floor: floor,
        roundtrip: tally.all.stats(&floor),
        roundtrip_without_sun: tally.no_sun.stats(&floor),
        roundtrip_inexact: tally.inexact.stats(&floor),
        basis: None,
        notes: Vec::new(),
        seconds: t1.elapsed().as_secs_f64(),
        seconds_encode: encode,
    }
}

/// Computes the map's spectra a batch of rows at a time (whole blocks of `lines` rows, enough
/// for the writer to compress them in parallel, within [`BATCH_BYTES`]) into `sink`; the tally
/// the plan's measure counted, or else the one counted as they are written.
fn stream_spectra(
    plan: &Plan,
    cells: &Cells,
    sink: &mut dyn Sink,
    lines: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Tally> {
    let map = &plan.input.map;
    let per_pixel = channel_names(plan).len();
    let height = map.image.height;
    let rows = BATCH_BYTES / row_bytes(plan, per_pixel).max(1);
    let blocks = (rows / lines)
        .max(rayon::current_num_threads())
        .clamp(1, height.div_ceil(lines));
    let rows_per_block = (blocks * lines).max(16).min(height);
    let px = Pixels {
        map,
        cells,
        plan: &plan.pixels,
        mode: plan.fit.mode,
    };
    let s = Stream {
        px,
        bands: plan.grid.len(),
        rows_per_block,
        counting: plan.measured.is_none(),
    };
    let counted = match &plan.pixels {
        PixelPlan::Basis { engine, .. } => stream_planes(&s, engine, sink, progress)?,
        PixelPlan::Carriers { .. } => stream_rows(&s, sink, per_pixel, progress)?,
    };
    Ok(plan.measured.clone().unwrap_or(counted))
}

/// What the streaming of rows shares: the pixels, the bands, the rows of a batch, and whether
/// the write counts the tally (the plan's measure has not).
struct Stream<'a> {
    px: Pixels<'a>,
    bands: usize,
    rows_per_block: usize,
    counting: bool,
}

/// The bytes a row of the batch holds (see [`BATCH_BYTES`]): `per_pixel` f32 values a pixel, or
/// two batches of the engine's coefficient planes and extra channels as f32 and the row's
/// encoded samples (uncompressed at worst).
fn row_bytes(plan: &Plan, per_pixel: usize) -> usize {
    let width = plan.input.map.image.width;
    let f32_bytes = std::mem::size_of::<f32>();
    match &plan.pixels {
        PixelPlan::Carriers { .. } => width * per_pixel * f32_bytes,
        PixelPlan::Basis { engine, .. } => {
            // The coefficients and the sun mask (R, G, B are read from the map).
            let planes = engine.live_spectra().count_ones() as usize + 1;
            let sample = match &plan.file.output {
                Output::Spectral { precision } if precision.precision == Precision::Half => 2,
                _ => 4,
            };
            width * (2 * planes * f32_bytes + per_pixel * sample)
        }
    }
}

/// Where computed rows go: the OpenEXR writer, or memory.
trait Sink: Send {
    /// Rows from `y0`, each pixel's channels interleaved.
    fn rows(&mut self, y0: usize, rows: &[f32]) -> Result<()>;
    /// `count` rows from `y0`, a channel's scan line at a time from `src`.
    fn lines(&mut self, y0: usize, count: usize, src: &dyn LineSource) -> Result<()>;
}

impl Sink for SpectralWriter {
    fn rows(&mut self, y0: usize, rows: &[f32]) -> Result<()> {
        self.write_rows(y0, rows)
    }
    fn lines(&mut self, y0: usize, count: usize, src: &dyn LineSource) -> Result<()> {
        self.write_lines(y0, count, src)
    }
}

/// The whole image in memory as three planes, so that a caller takes each as it is: every
/// pixel's bands, its R, G, B, and its sun mask ([`channel_names`]' order split).
pub(crate) struct Memory {
    width: usize,
    bands: usize,
    /// `bands` values per pixel, row by row.
    pub(crate) spectra: Vec<f32>,
    /// R, G, B per pixel, row by row.
    pub(crate) rgb: Vec<f32>,
    /// The sun mask per pixel, row by row.
    pub(crate) sun: Vec<f32>,
}

/// One row of [`Memory`]'s three planes.
type MemoryRow<'a> = ((&'a mut [f32], &'a mut [f32]), &'a mut [f32]);

impl Memory {
    fn new(width: usize, height: usize, bands: usize) -> Memory {
        Memory {
            width,
            bands,
            spectra: vec![0.0; width * height * bands],
            rgb: vec![0.0; width * height * 3],
            sun: vec![0.0; width * height],
        }
    }

    /// Rows `y0..y0 + count` of the three planes, a row at a time, to fill in parallel.
    fn rows_mut(
        &mut self,
        y0: usize,
        count: usize,
    ) -> impl IndexedParallelIterator<Item = MemoryRow<'_>> {
        // Rows y0.. of a plane of `per` values a pixel, one chunk a row.
        fn rows(
            plane: &mut [f32],
            y0: usize,
            count: usize,
            w: usize,
            per: usize,
        ) -> ChunksMut<'_, f32> {
            plane[y0 * w * per..(y0 + count) * w * per].par_chunks_mut(w * per)
        }
        let w = self.width;
        rows(&mut self.spectra, y0, count, w, self.bands)
            .zip(rows(&mut self.rgb, y0, count, w, 3))
            .zip(rows(&mut self.sun, y0, count, w, 1))
    }
}

impl Sink for Memory {
    fn rows(&mut self, y0: usize, rows: &[f32]) -> Result<()> {
        let (width, b) = (self.width, self.bands);
        let per = b + 4;
        let count = rows.len() / (width * per);
        self.rows_mut(y0, count)
            .zip(rows.par_chunks(width * per))
            .for_each(|(((s, c), m), src)| {
                for (x, p) in src.chunks_exact(per).enumerate() {
                    s[x * b..(x + 1) * b].copy_from_slice(&p[..b]);
                    c[x * 3..x * 3 + 3].copy_from_slice(&p[b..b + 3]);
                    m[x] = p[b + 3];
                }
            });
        Ok(())
    }
    fn lines(&mut self, y0: usize, count: usize, src: &dyn LineSource) -> Result<()> {
        let (width, b) = (self.width, self.bands);
        self.rows_mut(y0, count)
            .enumerate()
            .for_each(|(r, ((s, c), m))| {
                let mut line = vec![0f32; width];
                for channel in 0..b + 4 {
                    src.line(channel, r, &mut line);
                    let (plane, per, k) = match channel {
                        ch if ch < b => (&mut *s, b, ch),
                        ch if ch < b + 3 => (&mut *c, 3, ch - b),
                        _ => (&mut *m, 1, 0),
                    };
                    for (x, &v) in line.iter().enumerate() {
                        plane[x * per + k] = v;
                    }
                }
            });
        Ok(())
    }
}

/// The rows written pixel-interleaved, a batch at a time (the faithful method: each pixel's
/// carrier and modulation).
fn stream_rows(
    s: &Stream,
    writer: &mut dyn Sink,
    per_pixel: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Tally> {
    let (width, height) = (s.px.map.image.width, s.px.map.image.height);
    let mut buffer = vec![0f32; s.rows_per_block * width * per_pixel];
    let mut tally = Tally::default();
    let mut y0 = 0;
    while y0 < height {
        let rows = s.rows_per_block.min(height - y0);
        let buf = &mut buffer[..rows * width * per_pixel];
        // Each row's tally, merged in row order: the sums do not depend on the threads.
        let rows_tallies: Vec<Tally> = buf
            .par_chunks_mut(width * per_pixel)
            .enumerate()
            .map(|(r, row)| {
                let mut t = Tally::default();
                write_row(s, y0 + r, row, per_pixel, &mut t);
                t
            })
            .collect();
        rows_tallies.iter().for_each(|t| tally.merge(t));
        writer.rows(y0, buf)?;
        y0 += rows;
        progress(y0, height);
    }
    Ok(tally)
}

/// The rows as coefficient planes of the engine's few spectra (the paper's modes), the next
/// batch filled while the last is compressed: a band's scan line is one multiply-add per pixel
/// and spectrum, computed as the writer asks for it.
fn stream_planes(
    s: &Stream,
    engine: &Engine,
    writer: &mut dyn Sink,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Tally> {
    let (width, height) = (s.px.map.image.width, s.px.map.image.height);
    let new_batch = || {
        SpectralRows::new(
            engine.spectra_table(),
            engine.live_spectra(),
            s.bands,
            1,
            width,
            s.rows_per_block,
        )
    };
    let mut planes = [new_batch(), new_batch()];
    // Each row's tally is merged in row order as its batch is done (a map's rows of luminance
    // bins would not fit; merged as threads finish, the sums' last bits moved with them).
    let mut tally = Tally::default();
    let fill = |y: usize, mut row: RowMut| plane_row(s, engine, y, &mut row);
    coefficient_rows::stream(
        &mut planes,
        height,
        s.rows_per_block,
        &fill,
        &mut |y0, rows, batch| {
            let source = WithRgb {
                planes: batch,
                image: &s.px.map.image,
                y0,
                bands: s.bands,
            };
            writer.lines(y0, rows, &source)?;
            progress(y0 + rows, height);
            Ok(())
        },
        &mut |t| {
            if s.counting {
                tally.merge(&t);
            }
        },
    )?;
    Ok(tally)
}

/// A batch of coefficient planes with the sun mask as their one extra channel, and R, G, B read
/// from the map itself: the file's channels (bands, R, G, B, sun) without a copy of the map's
/// values in the batch.
struct WithRgb<'a> {
    planes: &'a SpectralRows,
    image: &'a crate::envmap::RgbImage,
    /// The image row of the batch's first row.
    y0: usize,
    bands: usize,
}

impl LineSource for WithRgb<'_> {
    fn line(&self, channel: usize, row: usize, out: &mut [f32]) {
        match channel.checked_sub(self.bands) {
            Some(c @ 0..=2) => {
                let w = self.image.width;
                let start = (self.y0 + row) * w;
                for (o, p) in out.iter_mut().zip(&self.image.pixels[start..start + w]) {
                    *o = p[c];
                }
            }
            Some(_) => self.planes.line(self.bands, row, out),
            None => self.planes.line(channel, row, out),
        }
    }
}

/// Row `y` of the coefficient planes: each pixel's combination and sun mask. Counted
/// (and so computed in full) only where the plan's measure has not counted it; else each
/// pixel's combination is decided without its spectrum.
fn plane_row(s: &Stream, engine: &Engine, y: usize, row: &mut RowMut) -> Tally {
    let (px, width) = (&s.px, s.px.map.image.width);
    let mut t = Tally::default();
    // The spectrum itself is only looked at (negative values, the round trip).
    let mut scratch = Vec::new();
    let omega_row = px.map.row_solid_angle(y);
    for x in 0..width {
        let rgb = px.map.image.get(x, y);
        let (kind, is_sun) = px.basis_kind(x, y);
        let decided = (!s.counting)
            .then(|| engine.combination(rgb, kind))
            .flatten();
        let combination = match decided {
            Some(c) => c,
            None => {
                scratch.resize(s.bands, 0.0);
                let r = engine.spectrum(rgb, kind, &mut scratch);
                if s.counting {
                    let (w, flags) = basis_written(&r, kind);
                    let omega = omega_row.unwrap_or_else(|| px.map.solid_angle(x, y));
                    t.add(px, (x, y, omega), w, flags);
                }
                r.combination
            }
        };
        row.set(x, &combination);
        row.set_extra(0, x, is_sun as u8 as f32);
    }
    t
}

/// One row of the output: each pixel's values, and (where the write counts) what it took,
/// added to `t`.
fn write_row(s: &Stream, y: usize, row: &mut [f32], per_pixel: usize, t: &mut Tally) {
    let (px, bands) = (&s.px, s.bands);
    let width = px.map.image.width;
    let omega_row = px.map.row_solid_angle(y);
    for x in 0..width {
        let rgb = px.map.image.get(x, y);
        let out = &mut row[x * per_pixel..(x + 1) * per_pixel];
        let (spectrum, rest) = out.split_at_mut(bands);
        let (w, flags) = px.spectrum(x, y, spectrum);
        rest[..3].copy_from_slice(&rgb);
        rest[3] = flags.is_sun as u8 as f32;
        if s.counting {
            let omega = omega_row.unwrap_or_else(|| px.map.solid_angle(x, y));
            t.add(px, (x, y, omega), w, flags);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A source whose channel c of row r at pixel x is `100 r + 10 c + x`.
    struct Ramp;
    impl LineSource for Ramp {
        fn line(&self, channel: usize, row: usize, out: &mut [f32]) {
            for (x, v) in out.iter_mut().enumerate() {
                *v = (100 * row + 10 * channel + x) as f32;
            }
        }
    }

    #[test]
    fn memory_holds_lines_and_rows_in_their_planes_where_they_belong() {
        // Two bands, then R, G, B and the sun mask: six channels.
        let (width, bands) = (3, 2);
        let mut m = Memory::new(width, 4, bands);
        m.spectra.fill(-1.0);
        // Rows 1 and 2 as lines (rows counted from the source's first), row 3 as interleaved.
        m.lines(1, 2, &Ramp).unwrap();
        let row3: Vec<f32> = (0..width * 6).map(|i| (i % 6) as f32 + 0.5).collect();
        m.rows(3, &row3).unwrap();
        let at = |y: usize, x: usize, c: usize| match c {
            c if c < bands => m.spectra[(y * width + x) * bands + c],
            c if c < bands + 3 => m.rgb[(y * width + x) * 3 + c - bands],
            _ => m.sun[y * width + x],
        };
        assert_eq!(at(0, 2, 1), -1.0, "row 0 untouched");
        assert_eq!(at(1, 2, 1), 12.0);
        assert_eq!(at(2, 0, 0), 100.0);
        assert_eq!(at(2, 1, 1), 111.0);
        assert_eq!(at(2, 1, 4), 141.0, "B");
        assert_eq!(at(2, 0, 5), 150.0, "the sun mask");
        for c in 0..6 {
            assert_eq!(at(3, 2, c), c as f32 + 0.5);
        }
    }
}
