//! Reading spectral OpenEXR files (Fichet et al. 2021 emissive layout): the header alone
//! ([`read_spectral_info`]), the rows streamed band by band ([`read_spectral_rows`]), or one
//! channel as stored ([`read_stored_channel`]).

use crate::colorimetry::Chromaticities;
use crate::envmap::files::attributes::{attr_from_exr, chromaticities_of, AttrValue};
use crate::envmap::files::decode::{
    channel_names, line_to_f32, open_exr, part_blocks, sniff, ExrReader, FileKind,
};
use crate::envmap::files::errors::{exr_err, parse_err};
use crate::envmap::files::layout::envmap_of;
use crate::envmap::files::layout::{parse_spectral_channel_name, EnvmapAttr};
use crate::error::Result;
use exr::block::UncompressedBlock;
use exr::meta::attribute::{AttributeValue, ChannelList};
use exr::meta::header::Header;
use std::collections::BTreeMap;
use std::path::Path;

/// What [`read_spectral_rows`] found in a spectral OpenEXR file.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralInfo {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// The `S0.<nm>nm` bands, sorted by wavelength.
    pub wavelengths_nm: Vec<f64>,
    /// Whether R, G, B preview channels follow the bands in each pixel.
    pub has_rgb: bool,
    /// The `envmap` attribute (None: absent).
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

/// A spectral file opened: its first part's header, what it says, and where each channel goes.
struct SpectralHeader {
    reader: ExrReader,
    header: Header,
    info: SpectralInfo,
    /// Where each channel's samples go in the callback's rows.
    pixels: PixelSlots,
}

/// For each channel of the file: its position within a pixel of the callback's rows, the
/// values per pixel, and the scale (2^EV) applied to them.
struct PixelSlots {
    slot: Vec<Option<usize>>,
    per_pixel: usize,
    scale: f32,
}

/// Opens a spectral OpenEXR file and reads its first part's header: the bands sorted by
/// wavelength, the R, G, B preview channels, the attributes and `EV`.
fn spectral_header(path: &Path) -> Result<SpectralHeader> {
    if !matches!(sniff(path)?, FileKind::Exr) {
        return Err(parse_err(path, "a spectral image must be an OpenEXR file"));
    }
    let reader = open_exr(path)?;
    let header = reader.headers()[0].clone();
    let bands = spectral_bands(path, &header.channels)?;
    let rgb = preview_rgb(&header.channels);
    let (attributes, ev) = custom_attributes(&header);
    let pixels = PixelSlots {
        slot: pixel_slots(header.channels.list.len(), &bands, rgb),
        per_pixel: bands.len() + if rgb.is_some() { 3 } else { 0 },
        scale: ev.map(|e| e.exp2() as f32).unwrap_or(1.0),
    };
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
        pixels,
    })
}

/// The emissive bands (wavelength, channel index), sorted by wavelength; fails when there are
/// none, on a channel that looks spectral but names no wavelength, and on a wavelength named
/// twice.
fn spectral_bands(path: &Path, channels: &ChannelList) -> Result<Vec<(f64, usize)>> {
    let mut bands: Vec<(f64, usize)> = channels
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
                channel_names(channels)
            ),
        ));
    }
    check_spectral_names(path, channels)?;
    bands.sort_by(|a, b| a.0.total_cmp(&b.0));
    if let Some(w) = bands.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(parse_err(
            path,
            format!("two channels name the wavelength {} nm", w[0].0),
        ));
    }
    Ok(bands)
}

/// Channels that look spectral must be: a positive wavelength.
fn check_spectral_names(path: &Path, channels: &ChannelList) -> Result<()> {
    for c in &channels.list {
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
    Ok(())
}

/// The indices of the `R`, `G`, `B` channels, when the file has all three.
fn preview_rgb(channels: &ChannelList) -> Option<[usize; 3]> {
    let find = |n: &str| channels.list.iter().position(|c| c.name.to_string() == n);
    Some([find("R")?, find("G")?, find("B")?])
}

/// For each channel: its position within a pixel (the bands in order, then R, G, B).
fn pixel_slots(
    channel_count: usize,
    bands: &[(f64, usize)],
    rgb: Option<[usize; 3]>,
) -> Vec<Option<usize>> {
    let mut slot = vec![None; channel_count];
    for (k, &(_, i)) in bands.iter().enumerate() {
        slot[i] = Some(k);
    }
    for (k, &i) in rgb.iter().flatten().enumerate() {
        slot[i] = Some(bands.len() + k);
    }
    slot
}

/// The custom attributes [`AttrValue`] holds, sorted by name, and the `EV` attribute.
fn custom_attributes(header: &Header) -> (Vec<(String, AttrValue)>, Option<f64>) {
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
    (attributes, ev)
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
        pixels,
    } = spectral_header(path)?;
    let mut blocks = part_blocks(reader, 0, path)?;
    let mut rows = RowAssembler::new(path, &header, &pixels, info.width);
    while let Some(block) = blocks.next_block() {
        rows.add(block.map_err(|e| exr_err(path, e))?, &mut f)?;
    }
    let (next_y, height) = (rows.next_y, info.height);
    if next_y != height {
        return Err(parse_err(
            path,
            format!("truncated or corrupt OpenEXR file: rows from {next_y} of {height} missing"),
        ));
    }
    Ok(info)
}

/// Puts decompressed blocks back in row order: blocks by the row they start at; a scan-line
/// block is a whole band of rows, tiles of one band (a tile row) are gathered until they cover
/// its width, then the band's rows are decoded and handed on.
struct RowAssembler<'a> {
    path: &'a Path,
    header: &'a Header,
    pixels: &'a PixelSlots,
    width: usize,
    stash: BTreeMap<usize, Vec<UncompressedBlock>>,
    /// The first row not yet handed on.
    next_y: usize,
    line_buf: Vec<f32>,
    rows: Vec<f32>,
}

impl<'a> RowAssembler<'a> {
    /// Nothing stashed, at row 0.
    fn new(
        path: &'a Path,
        header: &'a Header,
        pixels: &'a PixelSlots,
        width: usize,
    ) -> RowAssembler<'a> {
        RowAssembler {
            path,
            header,
            pixels,
            width,
            stash: BTreeMap::new(),
            next_y: 0,
            line_buf: vec![0f32; width],
            rows: Vec::new(),
        }
    }

    /// Stashes a block, then hands on every band that is complete and next in order.
    fn add(&mut self, block: UncompressedBlock, f: &mut impl FnMut(usize, &[f32])) -> Result<()> {
        self.stash
            .entry(block.index.pixel_position.1)
            .or_default()
            .push(block);
        while self
            .stash
            .get(&self.next_y)
            .is_some_and(|blocks| covered(blocks) >= self.width)
        {
            let blocks = self.stash.remove(&self.next_y).expect("present");
            self.next_y = self.band(&blocks, f)?;
        }
        Ok(())
    }

    /// Decodes the blocks of one band into rows and hands them to `f`; the row after the band.
    fn band(
        &mut self,
        blocks: &[UncompressedBlock],
        f: &mut impl FnMut(usize, &[f32]),
    ) -> Result<usize> {
        let by = blocks[0].index.pixel_position.1;
        let bh = blocks[0].index.pixel_size.1;
        let row_len = self.width * self.pixels.per_pixel;
        self.rows.clear();
        self.rows.resize(bh * row_len, 0.0);
        for block in blocks {
            self.decode_block(block, by, bh)?;
        }
        for ly in 0..bh {
            f(by + ly, &self.rows[ly * row_len..(ly + 1) * row_len]);
        }
        Ok(by + bh)
    }

    /// Decodes one block of the band at rows `by..by + bh` into its place in the rows.
    fn decode_block(&mut self, block: &UncompressedBlock, by: usize, bh: usize) -> Result<()> {
        let (bx, bw) = (block.index.pixel_position.0, block.index.pixel_size.0);
        let (path, width, per_pixel) = (self.path, self.width, self.pixels.per_pixel);
        if block.index.pixel_size.1 != bh || bx + bw > width {
            return Err(parse_err(
                path,
                "corrupt OpenEXR file: tiles of a row differ",
            ));
        }
        for line in block.lines(&self.header.channels) {
            let c = line.location.channel;
            let Some(k) = self.pixels.slot[c] else {
                continue;
            };
            let n = line.location.sample_count;
            let ly = line.location.position.1.wrapping_sub(by);
            let lx = line.location.position.0.wrapping_sub(bx);
            if ly >= bh || lx != 0 || n != bw {
                return Err(parse_err(path, "corrupt OpenEXR file: bad line in block"));
            }
            let t = self.header.channels.list[c].sample_type;
            let values = &mut self.line_buf[..n];
            line_to_f32(&line, t, values).map_err(|e| exr_err(path, e))?;
            let row = &mut self.rows[ly * width * per_pixel..(ly + 1) * width * per_pixel];
            for (x, v) in values.iter().enumerate() {
                row[(bx + x) * per_pixel + k] = v * self.pixels.scale;
            }
        }
        Ok(())
    }
}

/// The width the blocks of a band cover.
fn covered(blocks: &[UncompressedBlock]) -> usize {
    blocks.iter().map(|b| b.index.pixel_size.0).sum()
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
