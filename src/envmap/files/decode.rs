//! Opening image files and decoding OpenEXR blocks: the file kind by its magic bytes, the
//! blocks of one part decompressed in parallel, scan lines of any sample type as f32, and the
//! names that describe a file.

use crate::envmap::files::errors::{exr_err, io_err, parse_err};
use crate::error::Result;
use exr::block::chunk::TileCoordinates;
use exr::block::reader::{ChunksReader, FilteredChunksReader, Reader};
use exr::block::{BlockIndex, UncompressedBlock};
use exr::meta::attribute::{ChannelList, SampleType};
use exr::meta::MetaData;
use exr::prelude::f16;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

/// The two image formats read, told apart by their magic bytes.
pub(crate) enum FileKind {
    Exr,
    Hdr,
}

/// The kind of the image file at `path`, by its first bytes (not its extension).
pub(crate) fn sniff(path: &Path) -> Result<FileKind> {
    let mut file = File::open(path).map_err(|e| io_err(path, e))?;
    let mut magic = [0u8; 4];
    let mut n = 0;
    while n < 4 {
        match file.read(&mut magic[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) => return Err(io_err(path, e)),
        }
    }
    if n == 4 && magic == [0x76, 0x2f, 0x31, 0x01] {
        Ok(FileKind::Exr)
    } else if n >= 2 && &magic[..2] == b"#?" {
        Ok(FileKind::Hdr)
    } else {
        Err(parse_err(
            path,
            "not an OpenEXR or Radiance HDR image (unrecognised magic bytes)",
        ))
    }
}

/// An OpenEXR file with its headers read, its blocks not yet.
pub(crate) type ExrReader = Reader<BufReader<File>>;

/// Opens an OpenEXR file and reads its headers.
pub(crate) fn open_exr(path: &Path) -> Result<ExrReader> {
    let file = File::open(path).map_err(|e| io_err(path, e))?;
    exr::block::read(BufReader::new(file), false).map_err(|e| exr_err(path, e))
}

/// Decompresses blocks on rayon's threads when the file is compressed, else in this thread.
/// Blocks may come out of file order.
pub(crate) enum Decompressor<R: ChunksReader> {
    Sequential(exr::block::reader::SequentialBlockDecompressor<R>),
    Parallel(exr::block::reader::ParallelBlockDecompressor<R>),
}

impl<R: ChunksReader> Decompressor<R> {
    /// The parallel decompressor where the chunks allow it, else the sequential one.
    pub(crate) fn new(chunks: R) -> Self {
        match chunks.parallel_decompressor(false) {
            Ok(p) => Decompressor::Parallel(p),
            Err(chunks) => Decompressor::Sequential(chunks.sequential_decompressor(false)),
        }
    }
    /// The next decompressed block, `None` after the last.
    pub(crate) fn next_block(&mut self) -> Option<exr::error::Result<UncompressedBlock>> {
        match self {
            Decompressor::Sequential(d) => d.decompress_next_block(),
            Decompressor::Parallel(d) => d.decompress_next_block(),
        }
    }
}

/// The decompressed blocks of one part of an OpenEXR file.
pub(crate) type PartBlocks = Decompressor<FilteredChunksReader<BufReader<File>>>;

/// The blocks of part `part` at full resolution (the largest level of a mip-mapped file).
pub(crate) fn part_blocks(reader: ExrReader, part: usize, path: &Path) -> Result<PartBlocks> {
    let chunks = reader
        .filter_chunks(
            false,
            |_meta: &MetaData, tile: TileCoordinates, block: BlockIndex| {
                block.layer == part && tile.is_largest_resolution_level()
            },
        )
        .map_err(|e| exr_err(path, e))?;
    Ok(Decompressor::new(chunks))
}

/// Reads one line of samples of any type as f32 into `out`.
pub(crate) fn line_to_f32(
    line: &exr::block::lines::LineRef<'_>,
    t: SampleType,
    out: &mut [f32],
) -> exr::error::Result<()> {
    match t {
        SampleType::F16 => {
            for (o, v) in out.iter_mut().zip(line.read_samples::<f16>()) {
                *o = v?.to_f32();
            }
        }
        SampleType::F32 => {
            for (o, v) in out.iter_mut().zip(line.read_samples::<f32>()) {
                *o = v?;
            }
        }
        SampleType::U32 => {
            for (o, v) in out.iter_mut().zip(line.read_samples::<u32>()) {
                *o = v? as f32;
            }
        }
    }
    Ok(())
}

/// The channels' names, comma-separated (for messages).
pub(crate) fn channel_names(channels: &ChannelList) -> String {
    channels
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// OpenEXR's name of a sample type: half, float or uint.
pub(crate) fn sample_type_name(t: SampleType) -> &'static str {
    match t {
        SampleType::F16 => "half",
        SampleType::F32 => "float",
        SampleType::U32 => "uint",
    }
}

/// OpenEXR's name of a compression (`ZIP`, `DWAB`...), without the crate's parameters.
pub(crate) fn compression_name(c: exr::compression::Compression) -> String {
    let debug = format!("{c:?}");
    debug.split('(').next().unwrap_or(&debug).to_uppercase()
}
