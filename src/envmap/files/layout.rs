//! What a written file is: sample precision, compression, the `envmap` layout, the channel set
//! and its Fichet et al. (2021) spectral channel names, gathered in a [`SpectralLayout`].

use crate::envmap::files::attributes::AttrValue;
use exr::meta::attribute::EnvironmentMap;

pub use crate::envmap::files::zip::{
    DEFAULT_LEVEL as ZIP_DEFAULT_LEVEL, MAX_LEVEL as ZIP_MAX_LEVEL,
};

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
    /// The `exr` crate's value of this layout.
    pub(crate) fn to_exr(self) -> EnvironmentMap {
        match self {
            EnvmapAttr::LatLong => EnvironmentMap::LatitudeLongitude,
            EnvmapAttr::Cube => EnvironmentMap::Cube,
        }
    }
    /// The layout of the `exr` crate's value.
    pub(crate) fn from_exr(e: EnvironmentMap) -> EnvmapAttr {
        match e {
            EnvironmentMap::LatitudeLongitude => EnvmapAttr::LatLong,
            EnvironmentMap::Cube => EnvmapAttr::Cube,
        }
    }
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
    /// Uncompressed, one scan line per block.
    None,
    /// Run-length encoding (lossless), one scan line per block.
    Rle,
    /// Zlib, 16 scan lines per block.
    Zip,
    /// Zlib, one scan line per block.
    Zips,
    /// Wavelet (lossless), 32 scan lines per block.
    Piz,
    /// Lossy for float channels (24-bit mantissa truncation), lossless for half.
    Pxr24,
    /// Lossy, half channels only (float channels are stored uncompressed).
    B44,
    /// Lossy, half channels only; flat areas are stored more compactly.
    B44a,
}

impl Compression {
    /// The `exr` crate's value of this compression.
    pub(crate) fn to_exr(self) -> exr::compression::Compression {
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
        /// Band wavelengths in nm, in the caller's per-pixel order.
        wavelengths_nm: Vec<f64>,
        /// Whether R, G, B preview channels follow the bands in each pixel.
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

/// Everything that defines a written spectral (or custom-channel) OpenEXR file.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralLayout {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// The channels, in the order the caller gives each pixel's values.
    pub channels: ChannelSet,
    /// Sample precision of every channel.
    pub precision: Precision,
    /// The file's compression.
    pub compression: Compression,
    /// The `envmap` attribute to write (None: none, a plain image).
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

/// The `envmap` attribute of a header's own attributes.
pub(crate) fn envmap_of(header: &exr::meta::header::Header) -> Option<EnvmapAttr> {
    envmap_attr(&header.own_attributes)
}

/// A layer's `envmap` attribute (the exr crate reads it into its own field, not `other`).
pub fn envmap_attr(attrs: &exr::meta::header::LayerAttributes) -> Option<EnvmapAttr> {
    attrs.environment_map.map(EnvmapAttr::from_exr)
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
