//! OpenEXR's ZIP block encoding (byte split, delta predictor, zlib) on libdeflate, as OpenEXR does.
//!
//! The `exr` crate compresses ZIP blocks with miniz_oxide, which profiling showed to be 70% of a
//! conversion's time. OpenEXR itself (3.2 and later) compresses with libdeflate at level 4; this
//! module does the same on the same library, so files have OpenEXR's sizes and are written about
//! 2x faster than with miniz_oxide at the same level (`tools/bench_convert.py`).

/// OpenEXR's default zlib level (`Imf::getDefaultZipCompressionLevel`).
pub const DEFAULT_LEVEL: u8 = 4;

/// The highest level libdeflate accepts.
pub const MAX_LEVEL: u8 = 12;

/// A reusable compressor (one per thread: libdeflate keeps large match tables; the split and
/// output buffers are kept between blocks too, and the predictor works in place).
pub struct ZipEncoder {
    compressor: libdeflater::Compressor,
    split: Vec<u8>,
    out: Vec<u8>,
}

impl ZipEncoder {
    /// `level` is clamped to libdeflate's 0..=12 (0 stores, 1 fastest, 12 smallest).
    pub fn new(level: u8) -> ZipEncoder {
        let level = libdeflater::CompressionLvl::new(level.min(MAX_LEVEL) as i32)
            .unwrap_or_else(|_| libdeflater::CompressionLvl::default());
        ZipEncoder {
            compressor: libdeflater::Compressor::new(level),
            split: Vec::new(),
            out: Vec::new(),
        }
    }

    /// Encodes one block of little-endian samples (scan line by scan line, channels in file
    /// order) as an OpenEXR ZIP/ZIPS chunk. When compression does not make the block smaller,
    /// OpenEXR stores the raw bytes instead, and so does this.
    pub fn encode(&mut self, raw_le: &[u8]) -> Vec<u8> {
        let mut split = std::mem::take(&mut self.split);
        split_bytes(raw_le, &mut split);
        let chunk = self.encode_split_in_place(&mut split);
        self.split = split;
        chunk
    }

    /// [`ZipEncoder::encode`] of a block already split: the bytes at even offsets of the raw
    /// block (the low bytes of half samples), then those at odd offsets, as OpenEXR's predictor
    /// first arranges them. A writer that produces samples can lay them out so directly.
    pub fn encode_split(&mut self, split: &[u8]) -> Vec<u8> {
        let mut scratch = std::mem::take(&mut self.split);
        scratch.clear();
        scratch.extend_from_slice(split);
        let chunk = self.encode_split_in_place(&mut scratch);
        self.split = scratch;
        chunk
    }

    /// [`ZipEncoder::encode_split`] with the split block as scratch: the predictor replaces its
    /// bytes (so no second block-sized buffer is needed); what they hold after is unspecified.
    pub fn encode_split_in_place(&mut self, split: &mut [u8]) -> Vec<u8> {
        let n = split.len();
        if n == 0 {
            return Vec::new();
        }
        predict(split);
        self.out.resize(self.compressor.zlib_compress_bound(n), 0);
        match self.compressor.zlib_compress(split, &mut self.out) {
            Ok(size) if size < n => self.out[..size].to_vec(),
            _ => {
                unpredict(split);
                unsplit_bytes(split)
            }
        }
    }
}

/// OpenEXR's predictor, in place: each byte replaced by its difference to the previous one, plus
/// 128. A piece at a time from a copy of it (zipped slices: the compiler vectorises them), the
/// last byte of the piece before carried over.
fn predict(bytes: &mut [u8]) {
    const PIECE: usize = 4096;
    let mut before = [0u8; PIECE];
    let mut prev = bytes[0];
    for piece in bytes[1..].chunks_mut(PIECE) {
        let n = piece.len();
        before[0] = prev;
        before[1..n].copy_from_slice(&piece[..n - 1]);
        prev = piece[n - 1];
        for (d, &b) in piece.iter_mut().zip(&before[..n]) {
            *d = d.wrapping_sub(b).wrapping_add(128);
        }
    }
}

/// The bytes back from [`predict`]'s differences.
fn unpredict(bytes: &mut [u8]) {
    for i in 1..bytes.len() {
        bytes[i] = bytes[i].wrapping_add(bytes[i - 1]).wrapping_sub(128);
    }
}

/// Bytes of even offsets first, then odd ones (low and high bytes of each half sample
/// gathered).
fn split_bytes(raw_le: &[u8], split: &mut Vec<u8>) {
    let n = raw_le.len();
    split.clear();
    split.resize(n, 0);
    let (low, high) = split.split_at_mut(n.div_ceil(2));
    if n % 2 == 1 {
        low[n / 2] = raw_le[n - 1];
    }
    // Sixteen pairs at a time as fixed-size arrays, which the compiler turns into shuffles,
    // then the rest a pair at a time.
    let (low, high) = (&mut low[..n / 2], &mut high[..n / 2]);
    let done = n / 2 / 16 * 16;
    for ((l, h), p) in low
        .chunks_exact_mut(16)
        .zip(high.chunks_exact_mut(16))
        .zip(raw_le.chunks_exact(32))
    {
        let (l, h): (&mut [u8; 16], &mut [u8; 16]) = (l.try_into().unwrap(), h.try_into().unwrap());
        let p: &[u8; 32] = p.try_into().unwrap();
        for i in 0..16 {
            l[i] = p[2 * i];
            h[i] = p[2 * i + 1];
        }
    }
    for i in done..n / 2 {
        low[i] = raw_le[2 * i];
        high[i] = raw_le[2 * i + 1];
    }
}

/// The raw block back from its split (the rare block that does not compress).
fn unsplit_bytes(split: &[u8]) -> Vec<u8> {
    let n = split.len();
    let half = n.div_ceil(2);
    (0..n)
        .map(|i| {
            if i % 2 == 0 {
                split[i / 2]
            } else {
                split[half + i / 2]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The inverse, written from OpenEXR's `Zip::uncompress` (ImfZip.cpp): inflate, undo the
    /// predictor, interleave the two halves.
    fn decode(chunk: &[u8], n: usize) -> Vec<u8> {
        if chunk.len() == n {
            return chunk.to_vec();
        }
        let mut t = vec![0u8; n];
        let got = libdeflater::Decompressor::new()
            .zlib_decompress(chunk, &mut t)
            .unwrap();
        assert_eq!(got, n);
        for i in 1..n {
            t[i] = (t[i - 1] as i32 + t[i] as i32 - 128) as u8;
        }
        let half = n.div_ceil(2);
        (0..n)
            .map(|i| {
                if i % 2 == 0 {
                    t[i / 2]
                } else {
                    t[half + i / 2]
                }
            })
            .collect()
    }

    #[test]
    fn the_predictor_in_place_is_the_difference_to_the_byte_before_and_goes_back() {
        // Longer than a piece, so that pieces carry their last byte over.
        let raw: Vec<u8> = (0..10_000u32).map(|i| (i * i % 251) as u8).collect();
        let mut p = raw.clone();
        predict(&mut p);
        assert_eq!(p[0], raw[0]);
        for i in 1..raw.len() {
            assert_eq!(
                p[i],
                raw[i].wrapping_sub(raw[i - 1]).wrapping_add(128),
                "{i}"
            );
        }
        unpredict(&mut p);
        assert_eq!(p, raw);
    }

    #[test]
    fn round_trips_through_openexrs_decoder() {
        // A smooth ramp of half floats (compressible) and an odd length.
        let raw: Vec<u8> = (0..4001u32)
            .flat_map(|i| exr::prelude::f16::from_f32(i as f32 * 0.01).to_le_bytes())
            .chain([7u8])
            .collect();
        for level in [0, 1, DEFAULT_LEVEL, MAX_LEVEL] {
            let mut enc = ZipEncoder::new(level);
            let chunk = enc.encode(&raw);
            assert_eq!(decode(&chunk, raw.len()), raw, "level {level}");
            if level > 0 {
                assert!(
                    chunk.len() < raw.len() / 2,
                    "level {level}: {}",
                    chunk.len()
                );
            }
        }
    }

    #[test]
    fn a_block_given_split_encodes_as_the_raw_block() {
        let raw: Vec<u8> = (0..3000u32)
            .flat_map(|i| exr::prelude::f16::from_f32((i as f32 * 0.01).cos()).to_le_bytes())
            .collect();
        let mut split = Vec::new();
        split_bytes(&raw, &mut split);
        assert_eq!(unsplit_bytes(&split), raw);
        let mut enc = ZipEncoder::new(DEFAULT_LEVEL);
        let chunk = enc.encode_split(&split);
        assert_eq!(chunk, ZipEncoder::new(DEFAULT_LEVEL).encode(&raw));
        assert_eq!(decode(&chunk, raw.len()), raw);
        // Noise is stored raw, not split.
        let mut s = 7u32;
        let noise: Vec<u8> = (0..1000)
            .map(|_| {
                s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (s >> 24) as u8
            })
            .collect();
        split_bytes(&noise, &mut split);
        assert_eq!(enc.encode_split(&split), noise);
    }

    #[test]
    fn incompressible_blocks_are_stored_raw() {
        // xorshift noise does not compress: the chunk is the raw block, as OpenEXR writes it.
        let mut s = 0x2545_f491_u32;
        let raw: Vec<u8> = (0..1000)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 17;
                s ^= s << 5;
                s as u8
            })
            .collect();
        assert_eq!(ZipEncoder::new(DEFAULT_LEVEL).encode(&raw), raw);
    }

    #[test]
    fn matches_the_exr_crates_decoder() {
        // The exr crate's ZIP decompressor (zune-inflate) reads our chunk back.
        use exr::meta::attribute::{ChannelDescription, IntegerBounds, SampleType, Text};
        let (w, h) = (37usize, 16usize);
        let channels = exr::prelude::SmallVec::from_vec(vec![ChannelDescription::new(
            Text::from("Y"),
            SampleType::F16,
            false,
        )]);
        let header =
            exr::meta::header::Header::new(Text::from(""), exr::math::Vec2(w, h), channels)
                .with_encoding(
                    exr::compression::Compression::ZIP16,
                    exr::meta::BlockDescription::ScanLines,
                    exr::meta::attribute::LineOrder::Increasing,
                );
        let raw: Vec<u8> = (0..w * h)
            .flat_map(|i| exr::prelude::f16::from_f32((i as f32 * 0.37).sin()).to_le_bytes())
            .collect();
        let chunk = ZipEncoder::new(DEFAULT_LEVEL).encode(&raw);
        let bounds = IntegerBounds::new(exr::math::Vec2(0, 0), exr::math::Vec2(w, h));
        let decoded = exr::compression::Compression::ZIP16
            .decompress_image_section_from_le(&header, chunk, bounds, true)
            .unwrap();
        let ne: Vec<u8> = raw
            .chunks(2)
            .flat_map(|b| u16::from_le_bytes([b[0], b[1]]).to_ne_bytes())
            .collect();
        assert_eq!(decoded, ne);
    }
}
