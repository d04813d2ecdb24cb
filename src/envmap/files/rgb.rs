//! Reading RGB maps: OpenEXR (any compression, sample type, scan lines or tiles; `R, G, B`, a
//! layer's, or a grey `Y`) and Radiance HDR, chosen by the file's magic bytes.

use crate::colorimetry::Chromaticities;
use crate::envmap::files::attributes::chromaticities_of;
use crate::envmap::files::decode::{
    channel_names, compression_name, line_to_f32, open_exr, part_blocks, sample_type_name, sniff,
    FileKind,
};
use crate::envmap::files::errors::{exr_err, io_err, parse_err, unsupported_err};
use crate::envmap::files::layout::envmap_of;
use crate::envmap::files::layout::EnvmapAttr;
use crate::envmap::RgbImage;
use crate::error::Result;
use exr::block::UncompressedBlock;
use exr::math::Vec2;
use exr::meta::attribute::ChannelList;
use exr::meta::header::Header;
use exr::meta::BlockDescription;
use std::fs::File;
use std::io::BufReader;
use std::path::Path;

/// The most pixels an input image may have (2^31: 24 GiB as f32 RGB).
const MAX_PIXELS: usize = 1 << 31;

/// An RGB image read from a file, with what the file says about itself.
#[derive(Debug, Clone)]
pub struct InputImage {
    /// The pixels, linear RGB as the file stores them (a grey `Y` file's value in all three).
    pub image: RgbImage,
    /// The `envmap` attribute (OpenEXR only; `None` when absent or for HDR files).
    pub envmap: Option<EnvmapAttr>,
    /// A one-line description, e.g. "OpenEXR, DWAB, half, channels R,G,B".
    pub description: String,
    /// The primaries and white the file declares (OpenEXR's `chromaticities` attribute; `None`
    /// when absent, which OpenEXR reads as Rec.709 with D65, and for HDR files).
    pub chromaticities: Option<Chromaticities>,
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

/// Reads a Radiance HDR (RGBE) file.
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

/// The index of the channel called `name` (case-insensitive).
fn find_channel(channels: &ChannelList, name: &str) -> Option<usize> {
    channels
        .list
        .iter()
        .position(|c| c.name.to_string().eq_ignore_ascii_case(name))
}

/// The part and channels that hold the RGB image (see [`read_rgb`]), or an error listing the
/// channels the file has.
fn select_rgb(path: &Path, headers: &[Header], layer: Option<&str>) -> Result<RgbSource> {
    let found = match layer {
        Some(layer) => find_layer_rgb(headers, layer),
        None => find_plain_rgb(headers),
    };
    let (part, channels) = found.ok_or_else(|| missing_rgb_error(path, headers, layer))?;
    Ok(RgbSource {
        part,
        channels,
        names: channels.map(|i| headers[part].channels.list[i].name.to_string()),
    })
}

/// The indices of channels `<prefix>R`, `<prefix>G`, `<prefix>B`, if all are there.
fn rgb_triple(channels: &ChannelList, prefix: &str) -> Option<[usize; 3]> {
    let r = find_channel(channels, &format!("{prefix}R"))?;
    let g = find_channel(channels, &format!("{prefix}G"))?;
    let b = find_channel(channels, &format!("{prefix}B"))?;
    Some([r, g, b])
}

/// The first part with `<layer>.R/G/B`, or named `layer` with `R, G, B`.
fn find_layer_rgb(headers: &[Header], layer: &str) -> Option<(usize, [usize; 3])> {
    headers.iter().enumerate().find_map(|(part, h)| {
        let part_named = h
            .own_attributes
            .layer_name
            .as_ref()
            .is_some_and(|n| n.to_string().eq_ignore_ascii_case(layer));
        rgb_triple(&h.channels, &format!("{layer}."))
            .or_else(|| part_named.then(|| rgb_triple(&h.channels, "")).flatten())
            .map(|idx| (part, idx))
    })
}

/// The first part with `R, G, B`, else the first with `Y` (as grey).
fn find_plain_rgb(headers: &[Header]) -> Option<(usize, [usize; 3])> {
    let rgb = headers
        .iter()
        .enumerate()
        .find_map(|(part, h)| rgb_triple(&h.channels, "").map(|idx| (part, idx)));
    rgb.or_else(|| {
        headers
            .iter()
            .enumerate()
            .find_map(|(part, h)| find_channel(&h.channels, "Y").map(|y| (part, [y, y, y])))
    })
}

/// The error for a file without the wanted channels, listing those it has.
fn missing_rgb_error(path: &Path, headers: &[Header], layer: Option<&str>) -> crate::error::Error {
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
    parse_err(path, format!("no {wanted}; the file has channels: {have}"))
}

/// Reads the RGB image of an OpenEXR file: the part and channels, a check that they can be
/// read, the blocks copied into the image, and the file's description.
fn read_exr_rgb(path: &Path, layer: Option<&str>) -> Result<InputImage> {
    let reader = open_exr(path)?;
    let headers = reader.headers().to_vec();
    let src = select_rgb(path, &headers, layer)?;
    let header = &headers[src.part];
    check_readable(path, header, &src)?;
    let mut blocks = part_blocks(reader, src.part, path)?;
    let mut copier = RgbCopier::new(path, header, &src);
    let mut count = 0usize;
    while let Some(block) = blocks.next_block() {
        copier.copy(&block.map_err(|e| exr_err(path, e))?)?;
        count += 1;
    }
    check_complete(path, header, count)?;
    Ok(InputImage {
        image: copier.image,
        envmap: envmap_of(header),
        description: describe_exr(header, &src, headers.len()),
        chromaticities: chromaticities_of(header),
    })
}

/// Fails on what is not read: deep data, subsampled channels, an image too large.
fn check_readable(path: &Path, header: &Header, src: &RgbSource) -> Result<()> {
    if header.deep {
        return Err(unsupported_err(path, "deep OpenEXR data is not supported"));
    }
    for &c in &src.channels {
        let ch = &header.channels.list[c];
        if ch.sampling != Vec2(1, 1) {
            return Err(unsupported_err(
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
    Ok(())
}

/// Copies the R, G, B lines of decompressed blocks into the image.
struct RgbCopier<'a> {
    path: &'a Path,
    header: &'a Header,
    channels: [usize; 3],
    image: RgbImage,
    line_buf: Vec<f32>,
}

impl<'a> RgbCopier<'a> {
    /// A black image of the part's size.
    fn new(path: &'a Path, header: &'a Header, src: &RgbSource) -> RgbCopier<'a> {
        let (width, height) = (header.layer_size.0, header.layer_size.1);
        RgbCopier {
            path,
            header,
            channels: src.channels,
            image: RgbImage::new(width, height),
            line_buf: vec![0f32; width],
        }
    }

    /// Copies the block's lines of the R, G, B channels (a `Y` line into all three).
    fn copy(&mut self, block: &UncompressedBlock) -> Result<()> {
        let (width, height) = (self.image.width, self.image.height);
        for line in block.lines(&self.header.channels) {
            let c = line.location.channel;
            let targets = self.channels.map(|s| s == c);
            if !targets.contains(&true) {
                continue;
            }
            let n = line.location.sample_count;
            let (x0, y) = (line.location.position.0, line.location.position.1);
            if y >= height || x0 + n > width {
                return Err(parse_err(
                    self.path,
                    "corrupt OpenEXR file: block outside the image",
                ));
            }
            let t = self.header.channels.list[c].sample_type;
            let values = &mut self.line_buf[..n];
            line_to_f32(&line, t, values).map_err(|e| exr_err(self.path, e))?;
            let row = &mut self.image.pixels[y * width + x0..y * width + x0 + n];
            for (p, v) in row.iter_mut().zip(values.iter()) {
                for (dst, &hit) in p.iter_mut().zip(&targets) {
                    if hit {
                        *dst = *v;
                    }
                }
            }
        }
        Ok(())
    }
}

/// Fails when a scan-line file had fewer blocks than its header says.
fn check_complete(path: &Path, header: &Header, blocks: usize) -> Result<()> {
    let expected = header.chunk_count;
    if blocks < expected && header.blocks == BlockDescription::ScanLines {
        return Err(parse_err(
            path,
            format!("truncated OpenEXR file: {blocks} of {expected} blocks could be read"),
        ));
    }
    Ok(())
}

/// "OpenEXR, <compression>, <sample type>, <channels>" and the part of a multi-part file.
fn describe_exr(header: &Header, src: &RgbSource, parts: usize) -> String {
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
    if parts > 1 {
        description.push_str(&format!(" (part {} of {parts})", src.part));
    }
    description
}
