//! OpenEXR and Radiance HDR input, streaming spectral OpenEXR output (Fichet et al. 2021 layout).
//!
//! - [`layout`]: what a written file is (precision, compression, `envmap`, channel set and the
//!   spectral channel names), gathered in a [`SpectralLayout`];
//! - [`attributes`]: header attribute values ([`AttrValue`]) to and from the `exr` crate's;
//! - `errors`, `decode`: the errors naming a file; the file kind by magic bytes and the blocks
//!   of an OpenEXR part decoded as f32;
//! - [`rgb`], [`faces`]: reading RGB maps (OpenEXR, Radiance HDR) and six cube face files;
//! - `write_header`, [`spectral_writer`]: the written file's header from its layout; the
//!   streaming writer ([`SpectralWriter`]);
//! - [`block`], [`zip`]: one scan-line block encoded and compressed (ZIP on libdeflate);
//! - [`spectral_reader`]: reading a spectral file back (header, rows, one stored channel).

pub(crate) mod attributes;
pub(crate) mod block;
mod decode;
mod errors;
pub(crate) mod faces;
pub(crate) mod layout;
pub(crate) mod rgb;
pub(crate) mod spectral_reader;
pub(crate) mod spectral_writer;
mod write_header;
pub mod zip;

pub use attributes::{attr_from_exr, AttrValue};
pub use faces::{read_face_files, read_faces, FACE_NAMES, FACE_SIGNED};
pub use layout::{
    envmap_attr, parse_spectral_channel_name, spectral_channel_name, ChannelSet, Compression,
    EnvmapAttr, Precision, SpectralLayout, HALF_MAX, ZIP_DEFAULT_LEVEL, ZIP_MAX_LEVEL,
};
pub use rgb::{read_rgb, InputImage};
pub use spectral_reader::{
    read_spectral_info, read_spectral_rows, read_stored_channel, SpectralInfo,
};
pub use spectral_writer::SpectralWriter;
