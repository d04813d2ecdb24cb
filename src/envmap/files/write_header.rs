//! The header of a written spectral (or custom-channel) OpenEXR file, from its
//! [`SpectralLayout`]: the channels checked and sorted into file order, the channel list, and the
//! attributes (spectral layout, `EV`, the caller's, `chromaticities`, `envmap`).

use crate::envmap::files::attributes::{attr_to_exr, chromaticities_to_exr, text, AttrValue};
use crate::envmap::files::layout::{
    parse_spectral_channel_name, ChannelSet, EnvmapAttr, Precision, SpectralLayout,
};
use crate::error::{Error, Result};
use exr::math::Vec2;
use exr::meta::attribute::{AttributeValue, ChannelDescription, LineOrder, SampleType, Text};
use exr::meta::header::Header;
use exr::meta::{BlockDescription, MetaData};
use std::path::Path;

/// Attributes the writer sets itself, which the caller may not give.
const RESERVED: [&str; 4] = ["spectralLayoutVersion", "emissiveUnits", "envmap", "EV"];

/// The channels of a written file: names in the caller's order, and the file (sorted) order.
pub(crate) struct FileChannels {
    pub names: Vec<String>,
    /// For each channel in file order: its index in the caller's per-pixel order.
    pub order: Vec<usize>,
}

/// Checks the layout's size and channels (positive wavelengths, at least one channel, none
/// twice) and sorts the channels into file order.
pub(crate) fn file_channels(dest: &Path, layout: &SpectralLayout) -> Result<FileChannels> {
    let (width, height) = (layout.width, layout.height);
    if width == 0 || height == 0 {
        return Err(Error::invalid(format!(
            "{}: image size {width}x{height} is empty",
            dest.display()
        )));
    }
    check_wavelengths(dest, &layout.channels)?;
    let names = layout.channels.names();
    if names.is_empty() {
        return Err(Error::invalid(format!("{}: no channels", dest.display())));
    }
    let mut order: Vec<usize> = (0..names.len()).collect();
    order.sort_by(|&a, &b| names[a].as_bytes().cmp(names[b].as_bytes()));
    if let Some(w) = order.windows(2).find(|w| names[w[0]] == names[w[1]]) {
        return Err(Error::invalid(format!(
            "{}: channel {} appears twice",
            dest.display(),
            names[w[0]]
        )));
    }
    Ok(FileChannels { names, order })
}

/// Fails on a spectral set's wavelength that is not a positive number.
fn check_wavelengths(dest: &Path, channels: &ChannelSet) -> Result<()> {
    if let ChannelSet::Spectral { wavelengths_nm, .. } = channels {
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
    Ok(())
}

/// The file's header, and the scale (2^-EV, else 1) of its stored values.
pub(crate) struct FileHeader {
    pub headers: exr::meta::Headers,
    pub scale: f32,
}

/// The header of the file: its channel list and encoding, then its attributes, validated.
pub(crate) fn file_header(
    dest: &Path,
    layout: &SpectralLayout,
    channels: &FileChannels,
) -> Result<FileHeader> {
    let list = channel_list(channels, layout.precision)?;
    let mut header = Header::new(Text::from(""), Vec2(layout.width, layout.height), list)
        .with_encoding(
            layout.compression.to_exr(),
            BlockDescription::ScanLines,
            LineOrder::Increasing,
        );
    header.own_attributes.layer_name = None;
    let mut attrs = Attributes {
        header: &mut header,
        dest,
    };
    attrs.put_spectral(&channels.names)?;
    let scale = attrs.put_ev(layout.ev)?;
    attrs.put_callers(&layout.attributes)?;
    header.own_attributes.environment_map = layout.envmap.map(EnvmapAttr::to_exr);
    let mut headers = exr::meta::Headers::new();
    headers.push(header);
    MetaData::validate(&headers, true)
        .map_err(|e| Error::invalid(format!("{}: invalid OpenEXR header: {e}", dest.display())))?;
    Ok(FileHeader { headers, scale })
}

/// The channel descriptions in file order, all of the layout's sample type.
fn channel_list(
    channels: &FileChannels,
    precision: Precision,
) -> Result<exr::prelude::SmallVec<[ChannelDescription; 5]>> {
    let sample_type = match precision {
        Precision::Half => SampleType::F16,
        Precision::Float => SampleType::F32,
    };
    let mut list = exr::prelude::SmallVec::new();
    for &i in &channels.order {
        let name = text(&channels.names[i], "channel name")?;
        // pLinear = 0, as OpenEXR sets for R, G, B: radiance is perceived logarithmically,
        // so the lossy B44 quantizes it in a perceptual space.
        list.push(ChannelDescription::new(name, sample_type, false));
    }
    Ok(list)
}

/// The custom attributes of a header being made, each name given once.
struct Attributes<'a> {
    header: &'a mut Header,
    dest: &'a Path,
}

impl Attributes<'_> {
    /// Adds an attribute; fails when its name is not storable or already given.
    fn put(&mut self, name: &str, value: AttributeValue) -> Result<()> {
        let key = text(name, "attribute name")?;
        match self.header.own_attributes.other.insert(key, value) {
            None => Ok(()),
            Some(_) => Err(Error::invalid(format!(
                "{}: attribute {name} is given twice",
                self.dest.display()
            ))),
        }
    }

    /// `spectralLayoutVersion` and `emissiveUnits` when any channel is an emissive band (a
    /// custom set may add masks beside them).
    fn put_spectral(&mut self, names: &[String]) -> Result<()> {
        if names
            .iter()
            .any(|n| parse_spectral_channel_name(n).is_some())
        {
            self.put(
                "spectralLayoutVersion",
                AttributeValue::Text(Text::from("1.0")),
            )?;
            self.put(
                "emissiveUnits",
                AttributeValue::Text(Text::from("W.m^-2.sr^-1")),
            )?;
        }
        Ok(())
    }

    /// `EV` when given (within ±100); the scale 2^-EV of the stored values (1 without it).
    fn put_ev(&mut self, ev: Option<f64>) -> Result<f32> {
        let Some(ev) = ev else { return Ok(1.0) };
        if !ev.is_finite() || ev.abs() > 100.0 {
            return Err(Error::invalid(format!(
                "{}: EV {ev} is out of range",
                self.dest.display()
            )));
        }
        self.put("EV", AttributeValue::F32(ev as f32))?;
        Ok((-ev).exp2() as f32)
    }

    /// The caller's attributes: none reserved; `chromaticities` as OpenEXR's own attribute.
    fn put_callers(&mut self, attributes: &[(String, AttrValue)]) -> Result<()> {
        for (name, value) in attributes {
            if RESERVED.contains(&name.as_str()) {
                return Err(Error::invalid(format!(
                    "{}: attribute {name} is reserved (set by the writer)",
                    self.dest.display()
                )));
            }
            // OpenEXR's own attribute, which the `exr` crate keeps apart from custom ones.
            if let (AttrValue::Chromaticities(c), "chromaticities") = (value, name.as_str()) {
                self.header.shared_attributes.chromaticities = Some(chromaticities_to_exr(c));
                continue;
            }
            self.put(name, attr_to_exr(name, value)?)?;
        }
        Ok(())
    }
}
