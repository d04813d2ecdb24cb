//! The streaming spectral OpenEXR writer: rows in, blocks encoded and compressed in parallel,
//! a thread writing them to a temporary file that is renamed into place when complete.

use crate::envmap::files::block::{
    value_error, BlockEncoder, BlockFormat, Encoded, Interleaved, LineSource,
};
use crate::envmap::files::errors::io_err;
use crate::envmap::files::layout::{Compression, Precision, SpectralLayout, HALF_MAX};
use crate::envmap::files::write_header::{file_channels, file_header, FileChannels, FileHeader};
use crate::error::{Error, Result};
use exr::block::writer::ChunksWriter;
use rayon::prelude::*;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, SyncSender};
use std::sync::Mutex;
use std::thread::JoinHandle;

/// Compressed blocks queued for the file-writing thread.
const QUEUED_CHUNKS: usize = 16;

/// A block to encode: its first image row, its source and the source's row for it.
type Job<'a> = (usize, &'a dyn LineSource, usize);

/// Writes a spectral OpenEXR row by row. Complete blocks of rows are encoded (half or float
/// samples, channels in file order) and compressed in parallel on rayon's threads, then handed
/// to a thread that writes them, so memory holds the rows of one call and their compressed
/// blocks, never the image. ZIP and ZIPS use libdeflate as OpenEXR does ([`crate::envmap::files::zip`]); the
/// other compressions use the `exr` crate's compressors. The file is written to a temporary path
/// beside the destination and renamed into place by [`SpectralWriter::finish`]; dropping the
/// writer without finishing deletes the temporary file.
pub struct SpectralWriter {
    dest: PathBuf,
    tmp: PathBuf,
    width: usize,
    height: usize,
    /// Values per pixel in the caller's order.
    per_pixel: usize,
    /// For each channel in file (sorted) order: the index in the caller's per-pixel order.
    file_order: Vec<usize>,
    names: Vec<String>,
    half: bool,
    scale: f32,
    /// The scale of each channel in file order (1 for the unscaled ones).
    file_scales: Vec<f32>,
    lines_per_block: usize,
    compression: Compression,
    zip_level: u8,
    /// The file's header, for the `exr` crate's compressors.
    headers: exr::meta::Headers,
    /// Caller rows of the block being filled.
    pending: Vec<f32>,
    next_y: usize,
    sender: Option<SyncSender<Encoded>>,
    worker: Option<JoinHandle<exr::error::Result<()>>>,
    finished: bool,
    encode_seconds: f64,
    /// Block encoders kept between calls (their block-sized buffers and libdeflate's tables are
    /// allocated once, not per batch).
    encoders: Mutex<Vec<BlockEncoder>>,
}

/// An encoder taken from the writer's pool for one thread's share of a batch, given back when
/// dropped.
struct Pooled<'a> {
    encoder: Option<BlockEncoder>,
    pool: &'a Mutex<Vec<BlockEncoder>>,
}

impl<'a> Pooled<'a> {
    fn take(pool: &'a Mutex<Vec<BlockEncoder>>, zip_level: u8) -> Pooled<'a> {
        let kept = pool.lock().ok().and_then(|mut p| p.pop());
        Pooled {
            encoder: Some(kept.unwrap_or_else(|| BlockEncoder::new(zip_level))),
            pool,
        }
    }

    fn get(&mut self) -> &mut BlockEncoder {
        self.encoder.as_mut().expect("held until dropped")
    }
}

impl Drop for Pooled<'_> {
    fn drop(&mut self) {
        if let (Some(e), Ok(mut p)) = (self.encoder.take(), self.pool.lock()) {
            p.push(e);
        }
    }
}

impl SpectralWriter {
    /// Validates the layout, writes the header to a temporary file beside `dest` and starts the
    /// compressor.
    pub fn create(dest: &Path, layout: SpectralLayout) -> Result<SpectralWriter> {
        let channels = file_channels(dest, &layout)?;
        let FileHeader { headers, scale } = file_header(dest, &layout, &channels)?;
        let output = start_output(dest, &headers)?;
        let file_scales = file_scales(&channels, &layout.unscaled, scale);
        let FileChannels { names, order } = channels;
        Ok(SpectralWriter {
            dest: dest.to_path_buf(),
            tmp: output.tmp,
            width: layout.width,
            height: layout.height,
            per_pixel: names.len(),
            file_scales,
            file_order: order,
            names,
            half: layout.precision == Precision::Half,
            scale,
            lines_per_block: layout.compression.lines_per_block(),
            compression: layout.compression,
            zip_level: layout.zip_level,
            headers,
            pending: Vec::new(),
            next_y: 0,
            sender: Some(output.sender),
            worker: Some(output.worker),
            finished: false,
            encode_seconds: 0.0,
            encoders: Mutex::new(Vec::new()),
        })
    }

    /// The channel names in the caller's per-pixel order.
    pub fn channel_names(&self) -> &[String] {
        &self.names
    }

    /// Adds whole rows starting at row `y0` (rows come in order, any number at a time). Per
    /// pixel: the values in the channel set's order (bands in the given wavelength order, then
    /// R, G, B). Errors on a value that is not finite or, in half precision, beyond ±65504
    /// (after the EV scale), naming the pixel, channel and value.
    pub fn write_rows(&mut self, y0: usize, rows: &[f32]) -> Result<()> {
        self.check_rows(y0, rows)?;
        let row_len = self.width * self.per_pixel;
        let started = std::time::Instant::now();
        let mut rest = rows;
        // The block being filled, once complete, then the complete blocks within `rows`.
        let mut filled = Vec::new();
        if !self.pending.is_empty() {
            let block_y = self.next_y - self.pending.len() / row_len;
            let want = self.block_lines(block_y) * row_len - self.pending.len();
            let take = want.min(rest.len());
            self.pending.extend_from_slice(&rest[..take]);
            rest = &rest[take..];
            self.next_y += take / row_len;
            if take == want {
                filled = std::mem::take(&mut self.pending);
            }
        }
        let mut blocks: Vec<(usize, &[f32])> = Vec::new();
        if !filled.is_empty() {
            blocks.push((self.next_y - filled.len() / row_len, &filled));
        }
        if self.pending.is_empty() {
            while !rest.is_empty() {
                let n = self.block_lines(self.next_y) * row_len;
                if rest.len() < n {
                    break;
                }
                blocks.push((self.next_y, &rest[..n]));
                rest = &rest[n..];
                self.next_y += n / row_len;
            }
            self.pending.extend_from_slice(rest);
            self.next_y += rest.len() / row_len;
        }
        let sources: Vec<(usize, Interleaved)> = blocks
            .into_iter()
            .map(|(block_y, rows)| {
                let src = Interleaved {
                    rows,
                    width: self.width,
                    per_pixel: self.per_pixel,
                };
                (block_y, src)
            })
            .collect();
        let jobs: Vec<Job> = sources
            .iter()
            .map(|(block_y, src)| (*block_y, src as &dyn LineSource, 0))
            .collect();
        self.encode(&jobs)?;
        self.encode_seconds += started.elapsed().as_secs_f64();
        Ok(())
    }

    /// Adds `count` whole rows starting at row `y0`, asked of `src` a scan line and a channel
    /// at a time (its row 0 is image row `y0`): the rows must start a block and be whole blocks
    /// but at the end of the image, and no [`SpectralWriter::write_rows`] call may have left a
    /// block unfinished. Errors as `write_rows` on values the file cannot hold.
    pub fn write_lines(&mut self, y0: usize, count: usize, src: &dyn LineSource) -> Result<()> {
        let lines = self.lines_per_block;
        let whole = count.is_multiple_of(lines) || y0 + count == self.height;
        if y0 != self.next_y || !self.pending.is_empty() || !y0.is_multiple_of(lines) || !whole {
            return Err(Error::invalid(format!(
                "{}: write_lines needs whole blocks of {lines} rows in order: expected row {}, \
                 got rows {y0}..{}",
                self.dest.display(),
                self.next_y,
                y0 + count
            )));
        }
        self.check_height(y0, count)?;
        let started = std::time::Instant::now();
        let jobs: Vec<Job> = (y0..y0 + count)
            .step_by(lines)
            .map(|block_y| (block_y, src, block_y - y0))
            .collect();
        self.encode(&jobs)?;
        self.next_y += count;
        self.encode_seconds += started.elapsed().as_secs_f64();
        Ok(())
    }

    /// Encodes blocks in parallel (one [`BlockEncoder`] per thread) and queues them in order
    /// for the file; the error of the first failing block, if any.
    fn encode(&mut self, jobs: &[Job]) -> Result<()> {
        let format = self.block_format();
        let this = &*self;
        let chunks: Vec<Result<Encoded>> = jobs
            .par_iter()
            .map_init(
                || Pooled::take(&this.encoders, this.zip_level),
                |enc, &(block_y, src, row0)| {
                    enc.get()
                        .encode(&format, src, row0, block_y, this.block_lines(block_y))
                },
            )
            .collect();
        for chunk in chunks {
            self.send(chunk?)?;
        }
        Ok(())
    }

    /// Fails unless `rows` are whole rows that come next, fit in the image and hold values the
    /// file can store.
    fn check_rows(&self, y0: usize, rows: &[f32]) -> Result<()> {
        let row_len = self.width * self.per_pixel;
        if y0 != self.next_y {
            return Err(Error::invalid(format!(
                "{}: rows must come in order: expected row {}, got {y0}",
                self.dest.display(),
                self.next_y
            )));
        }
        if !rows.len().is_multiple_of(row_len) {
            return Err(Error::invalid(format!(
                "{}: {} values is not a whole number of rows of {} pixels x {} channels",
                self.dest.display(),
                rows.len(),
                self.width,
                self.per_pixel
            )));
        }
        self.check_height(y0, rows.len() / row_len)?;
        self.check_values(y0, rows)
    }

    /// Fails when rows `y0..y0 + count` go past the image.
    fn check_height(&self, y0: usize, count: usize) -> Result<()> {
        if y0 + count > self.height {
            return Err(Error::invalid(format!(
                "{}: rows {y0}..{} exceed the image height {}",
                self.dest.display(),
                y0 + count,
                self.height
            )));
        }
        Ok(())
    }

    /// What every block of the file shares.
    fn block_format(&self) -> BlockFormat<'_> {
        BlockFormat {
            dest: &self.dest,
            width: self.width,
            file_order: &self.file_order,
            names: &self.names,
            half: self.half,
            scale: self.scale,
            scales: &self.file_scales,
            compression: self.compression,
            lines_per_block: self.lines_per_block,
            headers: &self.headers,
        }
    }

    /// Scan lines in the block that starts at row `block_y`.
    fn block_lines(&self, block_y: usize) -> usize {
        self.lines_per_block.min(self.height - block_y)
    }

    /// Wall-clock seconds spent encoding and compressing blocks so far.
    pub fn encode_seconds(&self) -> f64 {
        self.encode_seconds
    }

    /// Fails on the first value of `rows` (starting at row `y0`) the file cannot hold.
    fn check_values(&self, y0: usize, rows: &[f32]) -> Result<()> {
        let limit = if self.half { HALF_MAX } else { f32::MAX };
        let scale = self.scale;
        let is_bad =
            |v: f32| !v.is_finite() || (v * scale).abs() > limit || !(v * scale).is_finite();
        // Checked a scan line at a time in parallel, then the first bad value found in its line.
        let row_len = self.width * self.per_pixel;
        let bad = rows
            .par_chunks(row_len.max(1))
            .position_first(|r| r.iter().any(|&v| is_bad(v)))
            .and_then(|r| {
                let start = r * row_len;
                rows[start..]
                    .iter()
                    .position(|&v| is_bad(v))
                    .map(|i| start + i)
            });
        if let Some(i) = bad {
            let pixel = i / self.per_pixel;
            let format = self.block_format();
            let (x, y) = (pixel % self.width, y0 + pixel / self.width);
            return Err(value_error(&format, rows[i], x, y, i % self.per_pixel));
        }
        Ok(())
    }

    /// Queues a block for the writing thread; its error when it has stopped.
    fn send(&mut self, block: Encoded) -> Result<()> {
        let ok = self.sender.as_ref().is_some_and(|s| s.send(block).is_ok());
        if ok {
            Ok(())
        } else {
            // The compressor stopped: report its error.
            self.sender = None;
            Err(self.join_worker().err().unwrap_or_else(|| {
                Error::invalid(format!("{}: the EXR writer stopped", self.dest.display()))
            }))
        }
    }

    /// Waits for the writing thread to end; its error, if any.
    fn join_worker(&mut self) -> Result<()> {
        match self.worker.take() {
            None => Ok(()),
            Some(h) => match h.join() {
                Ok(Ok(())) => Ok(()),
                Ok(Err(e)) => Err(match e {
                    exr::error::Error::Io(source) => io_err(&self.dest, source),
                    other => Error::invalid(format!(
                        "{}: writing OpenEXR failed: {other}",
                        self.dest.display()
                    )),
                }),
                Err(_) => Err(Error::invalid(format!(
                    "{}: the EXR writer thread panicked",
                    self.dest.display()
                ))),
            },
        }
    }

    /// Completes the file (all rows must have been written), renames it into place and returns
    /// its size in bytes.
    pub fn finish(mut self) -> Result<u64> {
        if self.next_y != self.height {
            return Err(Error::invalid(format!(
                "{}: only {} of {} rows were written",
                self.dest.display(),
                self.next_y,
                self.height
            )));
        }
        self.sender = None;
        self.join_worker()?;
        let bytes = std::fs::metadata(&self.tmp)
            .map_err(|e| io_err(&self.dest, e))?
            .len();
        crate::io::rename_into_place(&self.tmp, &self.dest)?;
        self.finished = true;
        Ok(bytes)
    }
}

impl Drop for SpectralWriter {
    /// An unfinished file is abandoned: the thread stopped, the temporary file deleted.
    fn drop(&mut self) {
        if !self.finished {
            self.sender = None;
            let _ = self.join_worker();
            crate::io::discard_temp(&self.tmp);
        }
    }
}

/// The scale of each channel in file order: `scale`, but 1 for the unscaled channels.
fn file_scales(channels: &FileChannels, unscaled: &[String], scale: f32) -> Vec<f32> {
    channels
        .order
        .iter()
        .map(|&c| {
            if unscaled.contains(&channels.names[c]) {
                1.0
            } else {
                scale
            }
        })
        .collect()
}

/// The temporary file being written and the thread writing it.
struct Output {
    tmp: PathBuf,
    sender: SyncSender<Encoded>,
    worker: JoinHandle<exr::error::Result<()>>,
}

/// Creates the temporary file beside `dest` and starts the thread that writes the header and
/// then the blocks sent to it (the temporary file is deleted when either fails).
fn start_output(dest: &Path, headers: &exr::meta::Headers) -> Result<Output> {
    let tmp = crate::io::temp_path_for(dest)?;
    let file = File::create(&tmp).map_err(|e| {
        crate::io::discard_temp(&tmp);
        io_err(dest, e)
    })?;
    let (sender, receiver) = sync_channel::<Encoded>(QUEUED_CHUNKS);
    let file_headers = headers.clone();
    let worker = std::thread::Builder::new()
        .name("specmap exr writer".into())
        .spawn(move || {
            exr::block::write(BufWriter::new(file), file_headers, true, |_, chunks| {
                for (i, chunk) in receiver {
                    chunks.write_chunk(i, chunk)?;
                }
                Ok(())
            })
        })
        .map_err(|e| {
            crate::io::discard_temp(&tmp);
            io_err(dest, e)
        })?;
    Ok(Output {
        tmp,
        sender,
        worker,
    })
}
