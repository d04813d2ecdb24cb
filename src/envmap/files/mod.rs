//! OpenEXR and Radiance HDR input, streaming spectral OpenEXR output (Fichet et al. 2021 layout).

pub mod block;
pub mod zip;

use crate::colorimetry::Chromaticities;
use crate::envmap::files::block::{BlockEncoder, BlockFormat, Encoded, Interleaved, LineSource};
use crate::envmap::RgbImage;
use crate::error::{Error, Result};
use exr::block::chunk::TileCoordinates;
use exr::block::reader::ChunksReader;
use exr::block::writer::ChunksWriter;
use exr::block::{BlockIndex, UncompressedBlock};
use exr::math::Vec2;
use exr::meta::attribute::{
    AttributeValue, ChannelDescription, ChannelList, EnvironmentMap, LineOrder, SampleType, Text,
};
use exr::meta::header::Header;
use exr::meta::{BlockDescription, MetaData};
use exr::prelude::f16;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, SyncSender};
use std::thread::JoinHandle;

/// Compressed blocks queued for the file-writing thread.
const QUEUED_CHUNKS: usize = 16;

/// The most pixels an input image may have (2^31: 24 GiB as f32 RGB).
const MAX_PIXELS: usize = 1 << 31;

/// OpenEXR's name of a compression (`ZIP`, `DWAB`...), without the crate's parameters.
fn compression_name(c: exr::compression::Compression) -> String {
    let debug = format!("{c:?}");
    debug.split('(').next().unwrap_or(&debug).to_uppercase()
}

/// The largest finite half-float value.
pub const HALF_MAX: f32 = 65504.0;

/// The OpenEXR `envmap` header attribute: the only two environment layouts OpenEXR names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EnvmapAttr {
    /// Latitude-longitude (equirectangular) map.
    LatLong,
    /// The OpenEXR cube: N x 6N, faces +X -X +Y -Y +Z -Z from top to bottom.
    Cube,
}

impl EnvmapAttr {
    fn to_exr(self) -> EnvironmentMap {
        match self {
            EnvmapAttr::LatLong => EnvironmentMap::LatitudeLongitude,
            EnvmapAttr::Cube => EnvironmentMap::Cube,
        }
    }
    fn from_exr(e: EnvironmentMap) -> EnvmapAttr {
        match e {
            EnvironmentMap::LatitudeLongitude => EnvmapAttr::LatLong,
            EnvironmentMap::Cube => EnvmapAttr::Cube,
        }
    }
}

/// An RGB image read from a file, with what the file says about itself.
#[derive(Debug, Clone)]
pub struct InputImage {
    pub image: RgbImage,
    /// The `envmap` attribute (OpenEXR only; `None` when absent or for HDR files).
    pub envmap: Option<EnvmapAttr>,
    /// A one-line description, e.g. "OpenEXR, DWAB, half, channels R,G,B".
    pub description: String,
    /// The primaries and white the file declares (OpenEXR's `chromaticities` attribute; `None`
    /// when absent, which OpenEXR reads as Rec.709 with D65, and for HDR files).
    pub chromaticities: Option<Chromaticities>,
}

fn parse_err(path: &Path, message: impl Into<String>) -> Error {
    Error::Parse {
        file: path.to_path_buf(),
        line: None,
        message: message.into(),
    }
}

fn exr_err(path: &Path, e: exr::error::Error) -> Error {
    match e {
        exr::error::Error::Io(source) => {
            if source.kind() == std::io::ErrorKind::UnexpectedEof {
                parse_err(path, "truncated OpenEXR file (unexpected end of file)")
            } else {
                Error::Io {
                    path: path.to_path_buf(),
                    source,
                }
            }
        }
        other => parse_err(
            path,
            format!("corrupt or unsupported OpenEXR file: {other}"),
        ),
    }
}

fn io_err(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

enum FileKind {
    Exr,
    Hdr,
}

fn sniff(path: &Path) -> Result<FileKind> {
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

/// Reads an RGB image from an OpenEXR or Radiance `.hdr` file, chosen by its magic bytes.
///
/// OpenEXR: every compression the `exr` crate reads, half, float or uint samples, scan lines or
/// tiles (the full-resolution level). Channels `R`, `G`, `B` (case-insensitive; `A` and others
/// are ignored), or `<layer>.R/G/B` when `layer` is given (or a part whose name is `layer`);
/// a file with a single `Y` channel is expanded to grey. In a multi-part file the first part
/// holding the channels is used.
pub fn read_rgb(path: &Path, layer: Option<&str>) -> Result<InputImage> {
    match sniff(path)? {
        FileKind::Exr => read_exr_rgb(path, layer),
        FileKind::Hdr => read_hdr(path),
    }
}

fn read_hdr(path: &Path) -> Result<InputImage> {
    let file = File::open(path).map_err(|e| io_err(path, e))?;
    let img = image::ImageReader::with_format(BufReader::new(file), image::ImageFormat::Hdr)
        .decode()
        .map_err(|e| parse_err(path, format!("corrupt Radiance HDR file: {e}")))?
        .into_rgb32f();
    let (w, h) = (img.width() as usize, img.height() as usize);
    let pixels = img.pixels().map(|p| p.0).collect();
    Ok(InputImage {
        image: RgbImage {
            width: w,
            height: h,
            pixels,
        },
        envmap: None,
        description: "Radiance HDR (RGBE)".into(),
        chromaticities: None,
    })
}

/// Where the R, G, B samples come from in one part: channel indices (equal for `Y`).
struct RgbSource {
    part: usize,
    channels: [usize; 3],
    names: [String; 3],
}

fn find_channel(channels: &ChannelList, name: &str) -> Option<usize> {
    channels
        .list
        .iter()
        .position(|c| c.name.to_string().eq_ignore_ascii_case(name))
}

fn channel_names(channels: &ChannelList) -> String {
    channels
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

fn select_rgb(path: &Path, headers: &[Header], layer: Option<&str>) -> Result<RgbSource> {
    let triple = |ch: &ChannelList, prefix: &str| -> Option<[usize; 3]> {
        let r = find_channel(ch, &format!("{prefix}R"))?;
        let g = find_channel(ch, &format!("{prefix}G"))?;
        let b = find_channel(ch, &format!("{prefix}B"))?;
        Some([r, g, b])
    };
    let make = |part: usize, idx: [usize; 3]| RgbSource {
        part,
        channels: idx,
        names: idx.map(|i| headers[part].channels.list[i].name.to_string()),
    };
    match layer {
        Some(layer) => {
            for (part, h) in headers.iter().enumerate() {
                if let Some(idx) = triple(&h.channels, &format!("{layer}.")) {
                    return Ok(make(part, idx));
                }
                let part_named = h
                    .own_attributes
                    .layer_name
                    .as_ref()
                    .is_some_and(|n| n.to_string().eq_ignore_ascii_case(layer));
                if part_named {
                    if let Some(idx) = triple(&h.channels, "") {
                        return Ok(make(part, idx));
                    }
                }
            }
        }
        None => {
            for (part, h) in headers.iter().enumerate() {
                if let Some(idx) = triple(&h.channels, "") {
                    return Ok(make(part, idx));
                }
            }
            for (part, h) in headers.iter().enumerate() {
                if let Some(y) = find_channel(&h.channels, "Y") {
                    return Ok(make(part, [y, y, y]));
                }
            }
        }
    }
    let have = headers
        .iter()
        .enumerate()
        .map(|(i, h)| {
            if headers.len() > 1 {
                format!("part {i}: {}", channel_names(&h.channels))
            } else {
                channel_names(&h.channels)
            }
        })
        .collect::<Vec<_>>()
        .join("; ");
    let wanted = match layer {
        Some(l) => format!("channels {l}.R, {l}.G, {l}.B"),
        None => "channels R, G, B (or a single Y)".to_string(),
    };
    Err(parse_err(
        path,
        format!("no {wanted}; the file has channels: {have}"),
    ))
}

fn sample_type_name(t: SampleType) -> &'static str {
    match t {
        SampleType::F16 => "half",
        SampleType::F32 => "float",
        SampleType::U32 => "uint",
    }
}

/// Reads one line of samples of any type as f32 into `out`.
fn line_to_f32(
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

/// Decompresses blocks on rayon's threads when the file is compressed, else in this thread.
/// Blocks may come out of file order.
enum Decompressor<R: ChunksReader> {
    Sequential(exr::block::reader::SequentialBlockDecompressor<R>),
    Parallel(exr::block::reader::ParallelBlockDecompressor<R>),
}

impl<R: ChunksReader> Decompressor<R> {
    fn new(chunks: R) -> Self {
        match chunks.parallel_decompressor(false) {
            Ok(p) => Decompressor::Parallel(p),
            Err(chunks) => Decompressor::Sequential(chunks.sequential_decompressor(false)),
        }
    }
    fn next_block(&mut self) -> Option<exr::error::Result<UncompressedBlock>> {
        match self {
            Decompressor::Sequential(d) => d.decompress_next_block(),
            Decompressor::Parallel(d) => d.decompress_next_block(),
        }
    }
}

fn envmap_of(header: &Header) -> Option<EnvmapAttr> {
    envmap_attr(&header.own_attributes)
}

/// A layer's `envmap` attribute (the exr crate reads it into its own field, not `other`).
pub fn envmap_attr(attrs: &exr::meta::header::LayerAttributes) -> Option<EnvmapAttr> {
    attrs.environment_map.map(EnvmapAttr::from_exr)
}

fn open_exr(path: &Path) -> Result<exr::block::reader::Reader<BufReader<File>>> {
    let file = File::open(path).map_err(|e| io_err(path, e))?;
    exr::block::read(BufReader::new(file), false).map_err(|e| exr_err(path, e))
}

fn read_exr_rgb(path: &Path, layer: Option<&str>) -> Result<InputImage> {
    let reader = open_exr(path)?;
    let headers = reader.headers().to_vec();
    let src = select_rgb(path, &headers, layer)?;
    let header = &headers[src.part];
    if header.deep {
        return Err(parse_err(path, "deep OpenEXR data is not supported"));
    }
    for &c in &src.channels {
        let ch = &header.channels.list[c];
        if ch.sampling != Vec2(1, 1) {
            return Err(parse_err(
                path,
                format!(
                    "channel {} is subsampled ({}x{}), which is not supported",
                    ch.name, ch.sampling.0, ch.sampling.1
                ),
            ));
        }
    }
    let (width, height) = (header.layer_size.0, header.layer_size.1);
    if width.checked_mul(height).is_none_or(|n| n > MAX_PIXELS) {
        return Err(parse_err(
            path,
            format!("image size {width}x{height} is too large (corrupt header?)"),
        ));
    }
    let mut image = RgbImage::new(width, height);
    let part = src.part;
    let chunks = reader
        .filter_chunks(
            false,
            |_meta: &MetaData, tile: TileCoordinates, block: BlockIndex| {
                block.layer == part && tile.is_largest_resolution_level()
            },
        )
        .map_err(|e| exr_err(path, e))?;
    let mut decompressor = Decompressor::new(chunks);
    let mut line_buf = vec![0f32; width];
    let mut blocks = 0usize;
    while let Some(block) = decompressor.next_block() {
        let block = block.map_err(|e| exr_err(path, e))?;
        blocks += 1;
        for line in block.lines(&header.channels) {
            let c = line.location.channel;
            let targets = src.channels.map(|s| s == c);
            if !targets.contains(&true) {
                continue;
            }
            let n = line.location.sample_count;
            let (x0, y) = (line.location.position.0, line.location.position.1);
            if y >= height || x0 + n > width {
                return Err(parse_err(
                    path,
                    "corrupt OpenEXR file: block outside the image",
                ));
            }
            let t = header.channels.list[c].sample_type;
            line_to_f32(&line, t, &mut line_buf[..n]).map_err(|e| exr_err(path, e))?;
            let row = &mut image.pixels[y * width + x0..y * width + x0 + n];
            for (p, v) in row.iter_mut().zip(&line_buf[..n]) {
                for (dst, &hit) in p.iter_mut().zip(&targets) {
                    if hit {
                        *dst = *v;
                    }
                }
            }
        }
    }
    let expected = header.chunk_count;
    if blocks < expected && header.blocks == BlockDescription::ScanLines {
        return Err(parse_err(
            path,
            format!("truncated OpenEXR file: {blocks} of {expected} blocks could be read"),
        ));
    }
    let types: Vec<&str> = src
        .channels
        .iter()
        .map(|&c| sample_type_name(header.channels.list[c].sample_type))
        .collect();
    let ty = if types.iter().all(|t| *t == types[0]) {
        types[0].to_string()
    } else {
        types.join("/")
    };
    let chans = if src.channels[0] == src.channels[1] {
        format!("channel {} (grey)", src.names[0])
    } else {
        format!("channels {}", src.names.join(","))
    };
    let mut description = format!(
        "OpenEXR, {}, {ty}, {chans}",
        compression_name(header.compression)
    );
    if headers.len() > 1 {
        description.push_str(&format!(" (part {part} of {})", headers.len()));
    }
    Ok(InputImage {
        image,
        envmap: envmap_of(header),
        description,
        chromaticities: chromaticities_of(header),
    })
}

/// The header's `chromaticities` attribute (shared by all parts of a file).
fn chromaticities_of(header: &Header) -> Option<Chromaticities> {
    header.shared_attributes.chromaticities.map(|c| {
        let xy = |v: Vec2<f32>| [v.0 as f64, v.1 as f64];
        Chromaticities {
            red: xy(c.red),
            green: xy(c.green),
            blue: xy(c.blue),
            white: xy(c.white),
        }
    })
}

/// The cube face names in OpenEXR order (+X -X +Y -Y +Z -Z), as used in `{face}` patterns.
pub const FACE_NAMES: [&str; 6] = ["px", "nx", "py", "ny", "pz", "nz"];
/// The same faces in the signed spelling (+x, -x, ...) that `{face}` patterns also accept.
pub const FACE_SIGNED: [&str; 6] = ["+x", "-x", "+y", "-y", "+z", "-z"];

/// Reads six square face images from a pattern with `{face}` replaced by px, nx, py, ny, pz, nz
/// (or +x, -x, ... when the px form does not exist), in OpenEXR order +X -X +Y -Y +Z -Z.
pub fn read_faces(pattern: &str, layer: Option<&str>) -> Result<[RgbImage; 6]> {
    Ok(read_face_files(pattern, layer)?.map(|f| f.image))
}

/// [`read_faces`], each face with what its file says about itself.
pub fn read_face_files(pattern: &str, layer: Option<&str>) -> Result<[InputImage; 6]> {
    if !pattern.contains("{face}") {
        return Err(Error::invalid(format!(
            "face pattern '{pattern}' has no {{face}} placeholder"
        )));
    }
    let mut faces: Vec<InputImage> = Vec::with_capacity(6);
    for (name, signed) in FACE_NAMES.iter().zip(FACE_SIGNED) {
        let primary = PathBuf::from(pattern.replace("{face}", name));
        let alt = PathBuf::from(pattern.replace("{face}", signed));
        let path = if primary.exists() {
            primary
        } else if alt.exists() {
            alt
        } else {
            return Err(Error::Io {
                path: primary.clone(),
                source: std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    format!(
                        "face file missing (tried {} and {})",
                        primary.display(),
                        alt.display()
                    ),
                ),
            });
        };
        let file = read_rgb(&path, layer)?;
        let img = &file.image;
        if img.width != img.height {
            return Err(parse_err(
                &path,
                format!("cube face is {}x{}, not square", img.width, img.height),
            ));
        }
        if let Some(first) = faces.first() {
            let first: &RgbImage = &first.image;
            if first.width != img.width {
                return Err(parse_err(
                    &path,
                    format!(
                        "cube face is {}x{} but the +X face is {}x{}",
                        img.width, img.height, first.width, first.height
                    ),
                ));
            }
        }
        faces.push(file);
    }
    faces
        .try_into()
        .map_err(|_| Error::invalid("six faces expected"))
}

/// Sample precision of the written channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// 16-bit half float: finite values up to 65504.
    Half,
    /// 32-bit float.
    Float,
}

/// OpenEXR compression for writing (DWAA/DWAB are read-only in the `exr` crate).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Compression {
    None,
    Rle,
    /// Zlib, 16 scan lines per block.
    Zip,
    /// Zlib, one scan line per block.
    Zips,
    Piz,
    /// Lossy for float channels (24-bit mantissa truncation), lossless for half.
    Pxr24,
    /// Lossy, half channels only (float channels are stored uncompressed).
    B44,
    /// Lossy, half channels only; flat areas are stored more compactly.
    B44a,
}

impl Compression {
    fn to_exr(self) -> exr::compression::Compression {
        use exr::compression::Compression as C;
        match self {
            Compression::None => C::Uncompressed,
            Compression::Rle => C::RLE,
            Compression::Zip => C::ZIP16,
            Compression::Zips => C::ZIP1,
            Compression::Piz => C::PIZ,
            Compression::Pxr24 => C::PXR24,
            Compression::B44 => C::B44,
            Compression::B44a => C::B44A,
        }
    }
    /// Scan lines per compressed block.
    pub fn lines_per_block(self) -> usize {
        self.to_exr().scan_lines_per_block()
    }
}

/// The channels of a written image, in the order the caller gives each pixel's values.
#[derive(Debug, Clone, PartialEq)]
pub enum ChannelSet {
    /// Emissive bands `S0.<nm>nm` in the given wavelength order, then (if `preview_rgb`) R, G, B.
    Spectral {
        wavelengths_nm: Vec<f64>,
        preview_rgb: bool,
    },
    /// Channels with the caller's names (e.g. c_R, c_G, c_B, sun), in the given order.
    Custom(Vec<String>),
}

impl ChannelSet {
    /// The channel names, in the caller's per-pixel order.
    pub fn names(&self) -> Vec<String> {
        match self {
            ChannelSet::Spectral {
                wavelengths_nm,
                preview_rgb,
            } => {
                let mut v: Vec<String> = wavelengths_nm
                    .iter()
                    .map(|&nm| spectral_channel_name(nm))
                    .collect();
                if *preview_rgb {
                    v.extend(["R", "G", "B"].map(String::from));
                }
                v
            }
            ChannelSet::Custom(names) => names.clone(),
        }
    }
}

/// A header attribute value.
#[derive(Debug, Clone, PartialEq)]
pub enum AttrValue {
    Text(String),
    F64(f64),
    F32(f32),
    I32(i32),
    /// Written as OpenEXR's `floatvector` attribute type.
    F32Vec(Vec<f32>),
    /// OpenEXR's `chromaticities` attribute type (xy of red, green, blue and white).
    Chromaticities(Chromaticities),
}

/// Everything that defines a written spectral (or custom-channel) OpenEXR file.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralLayout {
    pub width: usize,
    pub height: usize,
    pub channels: ChannelSet,
    pub precision: Precision,
    pub compression: Compression,
    pub envmap: Option<EnvmapAttr>,
    /// When set, every stored value is the given value divided by 2^ev, and the header carries
    /// `EV` = ev (float); `read_spectral_rows` multiplies it back.
    pub ev: Option<f64>,
    /// Extra header attributes (the fit's parameters...). Must not reuse reserved names.
    pub attributes: Vec<(String, AttrValue)>,
    /// The zlib level of ZIP and ZIPS (0 stores, 1 fastest, 12 smallest; OpenEXR's default is
    /// [`ZIP_DEFAULT_LEVEL`]). Other compressions ignore it.
    pub zip_level: u8,
    /// Channels stored as given whatever `ev` is (masks: a 0/1 channel stays 0/1).
    pub unscaled: Vec<String>,
}

pub use crate::envmap::files::zip::{
    DEFAULT_LEVEL as ZIP_DEFAULT_LEVEL, MAX_LEVEL as ZIP_MAX_LEVEL,
};

/// The channel name of an emissive band in the Fichet et al. (2021) layout: `S0.550,000000nm`.
pub fn spectral_channel_name(nm: f64) -> String {
    format!("S0.{}nm", format!("{nm:.6}").replace('.', ","))
}

/// Parses `S0.<number>nm` (comma or point as decimal separator) to nm.
pub fn parse_spectral_channel_name(name: &str) -> Option<f64> {
    let num = name.strip_prefix("S0.")?.strip_suffix("nm")?;
    if num.is_empty() {
        return None;
    }
    num.replace(',', ".").parse::<f64>().ok()
}

const RESERVED: [&str; 4] = ["spectralLayoutVersion", "emissiveUnits", "envmap", "EV"];

fn text(s: &str, what: &str) -> Result<Text> {
    Text::new_or_none(s)
        .ok_or_else(|| Error::invalid(format!("{what} '{s}' has characters OpenEXR cannot store")))
}

fn attr_to_exr(name: &str, v: &AttrValue) -> Result<AttributeValue> {
    Ok(match v {
        AttrValue::Text(s) => AttributeValue::Text(text(s, &format!("attribute {name}: value"))?),
        AttrValue::F64(x) => AttributeValue::F64(*x),
        AttrValue::F32(x) => AttributeValue::F32(*x),
        AttrValue::I32(x) => AttributeValue::I32(*x),
        AttrValue::F32Vec(xs) => AttributeValue::Custom {
            kind: Text::from("floatvector"),
            bytes: xs.iter().flat_map(|x| x.to_le_bytes()).collect(),
        },
        AttrValue::Chromaticities(c) => AttributeValue::Chromaticities(chromaticities_to_exr(c)),
    })
}

fn chromaticities_to_exr(c: &Chromaticities) -> exr::meta::attribute::Chromaticities {
    let xy = |p: [f64; 2]| Vec2(p[0] as f32, p[1] as f32);
    exr::meta::attribute::Chromaticities {
        red: xy(c.red),
        green: xy(c.green),
        blue: xy(c.blue),
        white: xy(c.white),
    }
}

pub fn attr_from_exr(v: &AttributeValue) -> Option<AttrValue> {
    Some(match v {
        AttributeValue::Text(t) => AttrValue::Text(t.to_string()),
        AttributeValue::F64(x) => AttrValue::F64(*x),
        AttributeValue::F32(x) => AttrValue::F32(*x),
        AttributeValue::I32(x) => AttrValue::I32(*x),
        AttributeValue::Custom { kind, bytes } if kind == "floatvector" => AttrValue::F32Vec(
            bytes
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect(),
        ),
        _ => return None,
    })
}

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
}

impl SpectralWriter {
    /// Validates the layout, writes the header to a temporary file beside `dest` and starts the
    /// compressor.
    pub fn create(dest: &Path, layout: SpectralLayout) -> Result<SpectralWriter> {
        let SpectralLayout {
            width,
            height,
            channels,
            precision,
            compression,
            envmap,
            ev,
            attributes,
            zip_level,
            unscaled,
        } = layout;
        if width == 0 || height == 0 {
            return Err(Error::invalid(format!(
                "{}: image size {width}x{height} is empty",
                dest.display()
            )));
        }
        if let ChannelSet::Spectral { wavelengths_nm, .. } = &channels {
            if let Some(w) = wavelengths_nm
                .iter()
                .find(|w| !(w.is_finite() && **w > 0.0))
            {
                return Err(Error::invalid(format!(
                    "{}: wavelength {w} nm is not a positive number",
                    dest.display()
                )));
            }
        }
        let names = channels.names();
        if names.is_empty() {
            return Err(Error::invalid(format!("{}: no channels", dest.display())));
        }
        let mut order: Vec<usize> = (0..names.len()).collect();
        order.sort_by(|&a, &b| names[a].as_bytes().cmp(names[b].as_bytes()));
        for w in order.windows(2) {
            if names[w[0]] == names[w[1]] {
                return Err(Error::invalid(format!(
                    "{}: channel {} appears twice",
                    dest.display(),
                    names[w[0]]
                )));
            }
        }
        let sample_type = match precision {
            Precision::Half => SampleType::F16,
            Precision::Float => SampleType::F32,
        };
        let mut list = smallvec_channels();
        for &i in &order {
            let name = text(&names[i], "channel name")?;
            // pLinear = 0, as OpenEXR sets for R, G, B: radiance is perceived logarithmically,
            // so the lossy B44 quantizes it in a perceptual space.
            list.push(ChannelDescription::new(name, sample_type, false));
        }
        let exr_compression = compression.to_exr();
        let mut header = Header::new(Text::from(""), Vec2(width, height), list).with_encoding(
            exr_compression,
            BlockDescription::ScanLines,
            LineOrder::Increasing,
        );
        header.own_attributes.layer_name = None;
        let mut put = |name: &str, value: AttributeValue| -> Result<()> {
            let key = text(name, "attribute name")?;
            match header.own_attributes.other.insert(key, value) {
                None => Ok(()),
                Some(_) => Err(Error::invalid(format!(
                    "{}: attribute {name} is given twice",
                    dest.display()
                ))),
            }
        };
        // Any emissive band makes the file spectral (a custom set may add masks beside them).
        if channels
            .names()
            .iter()
            .any(|n| parse_spectral_channel_name(n).is_some())
        {
            put(
                "spectralLayoutVersion",
                AttributeValue::Text(Text::from("1.0")),
            )?;
            put(
                "emissiveUnits",
                AttributeValue::Text(Text::from("W.m^-2.sr^-1")),
            )?;
        }
        let mut scale = 1.0f32;
        if let Some(ev) = ev {
            if !ev.is_finite() || ev.abs() > 100.0 {
                return Err(Error::invalid(format!(
                    "{}: EV {ev} is out of range",
                    dest.display()
                )));
            }
            scale = (-ev).exp2() as f32;
            put("EV", AttributeValue::F32(ev as f32))?;
        }
        for (name, value) in &attributes {
            if RESERVED.contains(&name.as_str()) {
                return Err(Error::invalid(format!(
                    "{}: attribute {name} is reserved (set by the writer)",
                    dest.display()
                )));
            }
            // OpenEXR's own attribute, which the `exr` crate keeps apart from custom ones.
            if let (AttrValue::Chromaticities(c), "chromaticities") = (value, name.as_str()) {
                header.shared_attributes.chromaticities = Some(chromaticities_to_exr(c));
                continue;
            }
            put(name, attr_to_exr(name, value)?)?;
        }

        header.own_attributes.environment_map = envmap.map(EnvmapAttr::to_exr);
        let headers: exr::meta::Headers = smallvec_headers(header);
        MetaData::validate(&headers, true).map_err(|e| {
            Error::invalid(format!("{}: invalid OpenEXR header: {e}", dest.display()))
        })?;

        let tmp = crate::io::temp_path_for(dest)?;
        let file = File::create(&tmp).map_err(|e| {
            crate::io::discard_temp(&tmp);
            io_err(dest, e)
        })?;
        let lines_per_block = exr_compression.scan_lines_per_block();
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
        Ok(SpectralWriter {
            dest: dest.to_path_buf(),
            tmp,
            width,
            height,
            per_pixel: names.len(),
            file_scales: order
                .iter()
                .map(|&c| {
                    if unscaled.contains(&names[c]) {
                        1.0
                    } else {
                        scale
                    }
                })
                .collect(),
            file_order: order,
            names,
            half: precision == Precision::Half,
            scale,
            lines_per_block,
            compression,
            zip_level,
            headers,
            pending: Vec::new(),
            next_y: 0,
            sender: Some(sender),
            worker: Some(worker),
            finished: false,
            encode_seconds: 0.0,
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
        let count = rows.len() / row_len;
        self.check_height(y0, count)?;
        self.check_values(y0, rows)?;
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
                || BlockEncoder::new(this.zip_level),
                |enc, &(block_y, src, row0)| {
                    enc.encode(&format, src, row0, block_y, this.block_lines(block_y))
                },
            )
            .collect();
        for chunk in chunks {
            self.send(chunk?)?;
        }
        Ok(())
    }

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
            return Err(crate::envmap::files::block::value_error(
                &format,
                rows[i],
                x,
                y,
                i % self.per_pixel,
            ));
        }
        Ok(())
    }

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
    fn drop(&mut self) {
        if !self.finished {
            self.sender = None;
            let _ = self.join_worker();
            crate::io::discard_temp(&self.tmp);
        }
    }
}

fn smallvec_channels() -> exr::prelude::SmallVec<[ChannelDescription; 5]> {
    exr::prelude::SmallVec::new()
}

fn smallvec_headers(header: Header) -> exr::meta::Headers {
    let mut h = exr::meta::Headers::new();
    h.push(header);
    h
}

/// What [`read_spectral_rows`] found in a spectral OpenEXR file.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralInfo {
    pub width: usize,
    pub height: usize,
    /// The `S0.<nm>nm` bands, sorted by wavelength.
    pub wavelengths_nm: Vec<f64>,
    /// Whether R, G, B preview channels follow the bands in each pixel.
    pub has_rgb: bool,
    pub envmap: Option<EnvmapAttr>,
    /// The `EV` attribute (already applied to the values passed to the callback).
    pub ev: Option<f64>,
    /// The custom header attributes of a type [`AttrValue`] holds (`spectralLayoutVersion`,
    /// `emissiveUnits`, `EV` and the writer's extra ones), sorted by name.
    pub attributes: Vec<(String, AttrValue)>,
    /// The `chromaticities` attribute: the space of the R, G, B channels (`None`: Rec.709, D65).
    pub chromaticities: Option<Chromaticities>,
}

/// Reads the header of a spectral OpenEXR only: size, wavelengths, attributes (no pixels).
pub fn read_spectral_info(path: &Path) -> Result<SpectralInfo> {
    Ok(spectral_header(path)?.info)
}

struct SpectralHeader {
    reader: exr::block::reader::Reader<BufReader<File>>,
    header: Header,
    info: SpectralInfo,
    /// For each channel of the file: its position within a pixel of the callback's rows.
    slot: Vec<Option<usize>>,
    per_pixel: usize,
    scale: f32,
}

fn spectral_header(path: &Path) -> Result<SpectralHeader> {
    if !matches!(sniff(path)?, FileKind::Exr) {
        return Err(parse_err(path, "a spectral image must be an OpenEXR file"));
    }
    let reader = open_exr(path)?;
    let header = reader.headers()[0].clone();
    let mut bands: Vec<(f64, usize)> = header
        .channels
        .list
        .iter()
        .enumerate()
        .filter_map(|(i, c)| parse_spectral_channel_name(&c.name.to_string()).map(|nm| (nm, i)))
        .collect();
    if bands.is_empty() {
        return Err(parse_err(
            path,
            format!(
                "no spectral channels S0.<wavelength>nm; the file has channels: {}",
                channel_names(&header.channels)
            ),
        ));
    }
    // Channels that look spectral must be: a positive wavelength, each once.
    for c in &header.channels.list {
        let name = c.name.to_string();
        if name.starts_with("S0.") && name.ends_with("nm") {
            match parse_spectral_channel_name(&name) {
                Some(nm) if nm.is_finite() && nm > 0.0 && nm < 1e6 => {}
                _ => {
                    return Err(parse_err(
                        path,
                        format!(
                            "channel {name}: not a wavelength in nm (a spectral channel is \
                             S0.<wavelength>nm with a positive wavelength, e.g. S0.550,000000nm)"
                        ),
                    ))
                }
            }
        }
    }
    bands.sort_by(|a, b| a.0.total_cmp(&b.0));
    if let Some(w) = bands.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(parse_err(
            path,
            format!("two channels name the wavelength {} nm", w[0].0),
        ));
    }
    let rgb: Option<Vec<usize>> = ["R", "G", "B"]
        .iter()
        .map(|n| {
            header
                .channels
                .list
                .iter()
                .position(|c| c.name.to_string() == *n)
        })
        .collect();
    // slot[channel index] = position within a pixel
    let mut slot = vec![None; header.channels.list.len()];
    for (k, &(_, i)) in bands.iter().enumerate() {
        slot[i] = Some(k);
    }
    if let Some(rgb) = &rgb {
        for (k, &i) in rgb.iter().enumerate() {
            slot[i] = Some(bands.len() + k);
        }
    }
    let per_pixel = bands.len() + if rgb.is_some() { 3 } else { 0 };
    let mut attributes = Vec::new();
    let mut ev = None;
    for (name, value) in header.own_attributes.other.iter() {
        let name = name.to_string();
        if name == "EV" {
            ev = match value {
                AttributeValue::F32(x) => Some(*x as f64),
                AttributeValue::F64(x) => Some(*x),
                AttributeValue::I32(x) => Some(*x as f64),
                _ => None,
            };
        }
        if let Some(v) = attr_from_exr(value) {
            attributes.push((name, v));
        }
    }
    attributes.sort_by(|a, b| a.0.cmp(&b.0));
    let scale = ev.map(|e| e.exp2() as f32).unwrap_or(1.0);
    let info = SpectralInfo {
        width: header.layer_size.0,
        height: header.layer_size.1,
        wavelengths_nm: bands.iter().map(|b| b.0).collect(),
        has_rgb: rgb.is_some(),
        envmap: envmap_of(&header),
        ev,
        attributes,
        chromaticities: chromaticities_of(&header),
    };
    Ok(SpectralHeader {
        reader,
        header,
        info,
        slot,
        per_pixel,
        scale,
    })
}

/// Streams a spectral OpenEXR (Fichet et al. 2021 emissive layout, first part) row by row:
/// `f(y, values)` gets each row in increasing y, per pixel the bands sorted by wavelength and
/// then R, G, B when present, multiplied by 2^EV when the header has `EV`. Scan-line and tiled
/// files (the full-resolution level of a mip-mapped one) are read. Blocks are decompressed on
/// rayon's threads a few at a time (blocks that arrive early wait for their turn), so memory
/// holds a few blocks or a row of tiles, never the image.
pub fn read_spectral_rows(path: &Path, mut f: impl FnMut(usize, &[f32])) -> Result<SpectralInfo> {
    let SpectralHeader {
        reader,
        header,
        info,
        slot,
        per_pixel,
        scale,
    } = spectral_header(path)?;
    let (width, height) = (info.width, info.height);
    let chunks = reader
        .filter_chunks(
            false,
            |_m: &MetaData, tile: TileCoordinates, block: BlockIndex| {
                block.layer == 0 && tile.is_largest_resolution_level()
            },
        )
        .map_err(|e| exr_err(path, e))?;
    let mut decompressor = Decompressor::new(chunks);
    // Blocks by the row they start at: a scan-line block is a whole band of rows; tiles of one
    // band (a tile row) are gathered until they cover its width, then the band is emitted.
    let mut stash: BTreeMap<usize, Vec<UncompressedBlock>> = BTreeMap::new();
    let mut next_y = 0usize;
    let mut line_buf = vec![0f32; width];
    let mut rows: Vec<f32> = Vec::new();
    let mut band = |blocks: Vec<UncompressedBlock>, rows: &mut Vec<f32>| -> Result<usize> {
        let by = blocks[0].index.pixel_position.1;
        let bh = blocks[0].index.pixel_size.1;
        rows.clear();
        rows.resize(bh * width * per_pixel, 0.0);
        for block in &blocks {
            let (bx, bw) = (block.index.pixel_position.0, block.index.pixel_size.0);
            if block.index.pixel_size.1 != bh || bx + bw > width {
                return Err(parse_err(
                    path,
                    "corrupt OpenEXR file: tiles of a row differ",
                ));
            }
            for line in block.lines(&header.channels) {
                let c = line.location.channel;
                let Some(k) = slot[c] else { continue };
                let n = line.location.sample_count;
                let ly = line.location.position.1.wrapping_sub(by);
                let lx = line.location.position.0.wrapping_sub(bx);
                if ly >= bh || lx != 0 || n != bw {
                    return Err(parse_err(path, "corrupt OpenEXR file: bad line in block"));
                }
                let t = header.channels.list[c].sample_type;
                line_to_f32(&line, t, &mut line_buf[..n]).map_err(|e| exr_err(path, e))?;
                let row = &mut rows[ly * width * per_pixel..(ly + 1) * width * per_pixel];
                for (x, v) in line_buf[..n].iter().enumerate() {
                    row[(bx + x) * per_pixel + k] = v * scale;
                }
            }
        }
        for ly in 0..bh {
            f(
                by + ly,
                &rows[ly * width * per_pixel..(ly + 1) * width * per_pixel],
            );
        }
        Ok(by + bh)
    };
    let covered = |blocks: &[UncompressedBlock]| -> usize {
        blocks.iter().map(|b| b.index.pixel_size.0).sum()
    };
    while let Some(block) = decompressor.next_block() {
        let block = block.map_err(|e| exr_err(path, e))?;
        stash
            .entry(block.index.pixel_position.1)
            .or_default()
            .push(block);
        while stash
            .get(&next_y)
            .is_some_and(|blocks| covered(blocks) >= width)
        {
            let blocks = stash.remove(&next_y).expect("present");
            next_y = band(blocks, &mut rows)?;
        }
    }
    if next_y != height {
        return Err(parse_err(
            path,
            format!("truncated or corrupt OpenEXR file: rows from {next_y} of {height} missing"),
        ));
    }
    Ok(info)
}

/// The values of channel `name` of the first part as stored (no EV scale applied: a mask such as
/// `sun` reads 0/1), if the file has it.
pub fn read_stored_channel(path: &Path, name: &str) -> Option<Vec<f32>> {
    use exr::prelude::*;
    // Only this channel is decoded into memory (a spectral file's bands would be 85 times as
    // much).
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .specific_channels()
        .required(name)
        .collect_pixels(
            |size: Vec2<usize>, _| (size.width(), vec![0f32; size.area()]),
            |(w, v): &mut (usize, Vec<f32>), pos: Vec2<usize>, (x,): (f32,)| {
                v[pos.y() * *w + pos.x()] = x
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .ok()?;
    Some(image.layer_data.channel_data.pixels.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channel_names_follow_fichet() {
        assert_eq!(spectral_channel_name(550.0), "S0.550,000000nm");
        assert_eq!(spectral_channel_name(382.5), "S0.382,500000nm");
        assert_eq!(parse_spectral_channel_name("S0.550,000000nm"), Some(550.0));
        assert_eq!(parse_spectral_channel_name("S0.382.5nm"), Some(382.5));
        assert_eq!(parse_spectral_channel_name("R"), None);
    }

    #[test]
    fn lines_per_block() {
        assert_eq!(Compression::Zip.lines_per_block(), 16);
        assert_eq!(Compression::Zips.lines_per_block(), 1);
        assert_eq!(Compression::Piz.lines_per_block(), 32);
    }
}
