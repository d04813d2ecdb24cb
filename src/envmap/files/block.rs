//! One OpenEXR scan-line block encoded from lines of samples: each channel's scan line is asked
//! of a [`LineSource`] in file order, checked, scaled, converted to half (F16C where the CPU has
//! it) and laid out as the compressor wants it; for ZIP that is the predictor's byte split
//! directly (low bytes of every half sample, then high bytes), so no planar or interleaved copy
//! of the block is ever made. The scratch buffers live in a [`BlockEncoder`], one per thread.

use crate::envmap::files::layout::{Compression, HALF_MAX};
use crate::envmap::files::zip::ZipEncoder;
use crate::error::{Error, Result};
use exr::block::chunk::{Chunk, CompressedBlock, CompressedScanLineBlock};
use exr::block::{BlockIndex, UncompressedBlock};
use exr::math::Vec2;
use exr::prelude::f16;
use half::slice::HalfFloatSliceExt;
use std::path::Path;

/// Rows of an image, one scan line of one channel at a time.
pub trait LineSource: Sync {
    /// Writes channel `channel` (in the caller's per-pixel order) of row `row` (counted from the
    /// first row the source holds) into `out`, one value per pixel.
    fn line(&self, channel: usize, row: usize, out: &mut [f32]);
}

/// Rows of pixels with `per_pixel` interleaved values each (the caller's order).
pub(crate) struct Interleaved<'a> {
    /// The rows' values, row-major from the source's first row, `per_pixel` per pixel.
    pub rows: &'a [f32],
    /// Row length in pixels.
    pub width: usize,
    /// Values per pixel.
    pub per_pixel: usize,
}

impl LineSource for Interleaved<'_> {
    /// Picks the channel's value out of each pixel of the row.
    fn line(&self, channel: usize, row: usize, out: &mut [f32]) {
        let start = row * self.width * self.per_pixel;
        let row = &self.rows[start..start + self.width * self.per_pixel];
        for (o, px) in out.iter_mut().zip(row.chunks_exact(self.per_pixel)) {
            *o = px[channel];
        }
    }
}

/// What every block of a file shares.
pub(crate) struct BlockFormat<'a> {
    /// The file being written (named in errors).
    pub dest: &'a Path,
    /// Image width in pixels.
    pub width: usize,
    /// For each channel in file order: its index in the caller's per-pixel order.
    pub file_order: &'a [usize],
    /// Channel names in the caller's order (for errors).
    pub names: &'a [String],
    /// Whether samples are stored as half floats (else as 32-bit floats).
    pub half: bool,
    /// Every value is multiplied by this (2^-EV) before it is stored...
    pub scale: f32,
    /// ...but in the channels (file order) whose scale here is 1: masks stay 0/1.
    pub scales: &'a [f32],
    /// The file's compression.
    pub compression: Compression,
    /// Scan lines per block (the compression's; the last block of the image may have fewer).
    pub lines_per_block: usize,
    /// The file's header, for the `exr` crate's compressors.
    pub headers: &'a exr::meta::Headers,
}

/// A compressed block and its index in increasing-y order.
pub(crate) type Encoded = (usize, Chunk);

/// Per-thread scratch: the compressor, one scan line as f32 and as half, the block's bytes.
pub(crate) struct BlockEncoder {
    zip: ZipEncoder,
    line: Vec<f32>,
    halves: Vec<f16>,
    bytes: Vec<u8>,
}

impl BlockEncoder {
    /// Empty scratch and a ZIP compressor at `zip_level`.
    pub(crate) fn new(zip_level: u8) -> BlockEncoder {
        BlockEncoder {
            zip: ZipEncoder::new(zip_level),
            line: Vec::new(),
            halves: Vec::new(),
            bytes: Vec::new(),
        }
    }

    /// Encodes rows `row0..row0 + lines` of `src` as the block that starts at image row
    /// `block_y`. Fails on a value that is not finite or, after the scale, beyond the sample
    /// type's range, naming the pixel, channel and value.
    pub(crate) fn encode(
        &mut self,
        f: &BlockFormat,
        src: &dyn LineSource,
        row0: usize,
        block_y: usize,
        lines: usize,
    ) -> Result<Encoded> {
        let bytes = SampleBytes::of(f);
        self.size_buffers(f, bytes, lines);
        let mut at = 0;
        for l in 0..lines {
            for (&c, &scale) in f.file_order.iter().zip(f.scales) {
                src.line(c, row0 + l, &mut self.line);
                check_line(f, &self.line, block_y + l, c)?;
                if scale != 1.0 {
                    self.line.iter_mut().for_each(|v| *v *= scale);
                }
                at = self.put_line(bytes, at);
            }
        }
        self.compress(f, block_y, lines)
    }

    /// Sizes the scratch for a block of `lines` scan lines: one line as f32 (and as half), the
    /// block's bytes.
    fn size_buffers(&mut self, f: &BlockFormat, bytes: SampleBytes, lines: usize) {
        let w = f.width;
        self.line.resize(w, 0.0);
        self.halves.resize(if f.half { w } else { 0 }, f16::ZERO);
        let n = lines * f.file_order.len() * w * bytes.size();
        if self.bytes.capacity() < n {
            // A fresh buffer (the last one was handed over, or was smaller) comes zeroed from
            // the allocator, where fresh pages need no zeroing: every byte is written anyway.
            self.bytes = vec![0; n];
        }
        self.bytes.resize(n, 0);
    }

    /// Lays the current scan line out at byte `at` of the block; the byte after it (for the
    /// predictor's split: the sample after it in each half).
    fn put_line(&mut self, bytes: SampleBytes, at: usize) -> usize {
        let w = self.line.len();
        match bytes {
            SampleBytes::SplitHalves => {
                // The ZIP predictor's split: the low bytes of every sample in the first half of
                // the block, the high bytes in the second.
                self.halves.convert_from_f32_slice(&self.line);
                let half = self.bytes.len() / 2;
                let (low, high) = self.bytes.split_at_mut(half);
                for ((lo, hi), h) in low[at..at + w]
                    .iter_mut()
                    .zip(&mut high[at..at + w])
                    .zip(&self.halves)
                {
                    let b = h.to_bits();
                    *lo = b as u8;
                    *hi = (b >> 8) as u8;
                }
                at + w
            }
            SampleBytes::Half { native } => {
                self.halves.convert_from_f32_slice(&self.line);
                let dst = &mut self.bytes[at..at + w * 2];
                put_samples(
                    dst,
                    &self.halves,
                    native,
                    f16::to_ne_bytes,
                    f16::to_le_bytes,
                );
                at + w * 2
            }
            SampleBytes::Float { native } => {
                let dst = &mut self.bytes[at..at + w * 4];
                put_samples(dst, &self.line, native, f32::to_ne_bytes, f32::to_le_bytes);
                at + w * 4
            }
        }
    }

    /// Compresses the block's bytes into its chunk.
    fn compress(&mut self, f: &BlockFormat, block_y: usize, lines: usize) -> Result<Encoded> {
        let index = block_y / f.lines_per_block;
        let compressed_pixels_le = match f.compression {
            // Handed over whole: the next block allocates its own.
            Compression::None => std::mem::take(&mut self.bytes),
            Compression::Zip | Compression::Zips if f.half => {
                self.zip.encode_split_in_place(&mut self.bytes)
            }
            Compression::Zip | Compression::Zips => self.zip.encode(&self.bytes),
            _ => return self.compress_with_exr(f, index, block_y, lines),
        };
        let chunk = Chunk {
            layer_index: 0,
            compressed_block: CompressedBlock::ScanLine(CompressedScanLineBlock {
                y_coordinate: block_y as i32,
                compressed_pixels_le,
            }),
        };
        Ok((index, chunk))
    }

    /// The other compressions, by the `exr` crate, from native-endian samples.
    fn compress_with_exr(
        &mut self,
        f: &BlockFormat,
        index: usize,
        block_y: usize,
        lines: usize,
    ) -> Result<Encoded> {
        let block = UncompressedBlock {
            index: BlockIndex {
                layer: 0,
                pixel_position: Vec2(0, block_y),
                pixel_size: Vec2(f.width, lines),
                level: Vec2(0, 0),
            },
            data: self.bytes.clone(),
        };
        let chunk = block.compress_to_chunk(f.headers).map_err(|e| {
            Error::invalid(format!(
                "{}: compressing rows {block_y}..{} failed: {e}",
                f.dest.display(),
                block_y + lines
            ))
        })?;
        Ok((index, chunk))
    }
}

/// Writes the values into `dst` one after another, each as its `N` bytes: native-endian
/// (`ne`) or little-endian (`le`).
fn put_samples<T: Copy, const N: usize>(
    dst: &mut [u8],
    values: &[T],
    native: bool,
    ne: impl Fn(T) -> [u8; N],
    le: impl Fn(T) -> [u8; N],
) {
    for (d, &v) in dst.chunks_exact_mut(N).zip(values) {
        d.copy_from_slice(&if native { ne(v) } else { le(v) });
    }
}

/// How a block's samples are laid out as bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SampleBytes {
    /// Half samples for ZIP: the predictor's byte split (low bytes, then high bytes).
    SplitHalves,
    /// Half samples, native-endian for the `exr` crate's compressors, else little-endian.
    Half { native: bool },
    /// Float samples, native-endian for the `exr` crate's compressors, else little-endian.
    Float { native: bool },
}

impl SampleBytes {
    /// The layout the block's sample type and compression want.
    fn of(f: &BlockFormat) -> SampleBytes {
        let zip = matches!(f.compression, Compression::Zip | Compression::Zips);
        // The exr crate's compressors take native-endian samples; the file holds little-endian.
        let native = !matches!(f.compression, Compression::None) && !zip;
        match (f.half, zip) {
            (true, true) => SampleBytes::SplitHalves,
            (true, false) => SampleBytes::Half { native },
            (false, _) => SampleBytes::Float { native },
        }
    }

    /// Bytes per sample.
    fn size(self) -> usize {
        match self {
            SampleBytes::SplitHalves | SampleBytes::Half { .. } => 2,
            SampleBytes::Float { .. } => 4,
        }
    }
}

/// Fails on the first value of a scan line that is not finite or, after the scale, beyond the
/// sample type's range (one pass without branches; the search only when one is found).
fn check_line(f: &BlockFormat, line: &[f32], y: usize, channel: usize) -> Result<()> {
    let limit = if f.half { HALF_MAX } else { f32::MAX };
    // NaN compares false: `<=` then negated catches it with the rest, without a branch.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    let bad = |v: f32| !((v * f.scale).abs() <= limit);
    if !line.iter().fold(false, |b, &v| b | bad(v)) {
        return Ok(());
    }
    let x = line.iter().position(|&v| bad(v)).unwrap_or(0);
    Err(value_error(f, line[x], x, y, channel))
}

/// The error for a value the file cannot hold.
pub(crate) fn value_error(f: &BlockFormat, v: f32, x: usize, y: usize, channel: usize) -> Error {
    let why = if !v.is_finite() {
        "is not finite".to_string()
    } else if f.half {
        format!(
            "exceeds the half-float range (65504){}; write float or set an EV scale",
            if f.scale != 1.0 {
                " after the EV scale"
            } else {
                ""
            }
        )
    } else {
        "exceeds the float range after the EV scale".to_string()
    };
    Error::invalid(format!(
        "{}: pixel ({x}, {y}) channel {}: value {v} {why}",
        f.dest.display(),
        f.names[channel]
    ))
}
