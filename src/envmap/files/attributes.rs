//! Header attributes between the crate's values and the `exr` crate's: [`AttrValue`], the
//! `envmap` and `chromaticities` attributes, and names and texts OpenEXR can store.

use crate::colorimetry::Chromaticities;
use crate::error::{Error, Result};
use exr::math::Vec2;
use exr::meta::attribute::{AttributeValue, Text};
use exr::meta::header::Header;

/// A header attribute value.
#[derive(Debug, Clone, PartialEq)]
pub enum AttrValue {
    /// OpenEXR's `string` attribute type.
    Text(String),
    /// OpenEXR's `double` attribute type.
    F64(f64),
    /// OpenEXR's `float` attribute type.
    F32(f32),
    /// OpenEXR's `int` attribute type.
    I32(i32),
    /// Written as OpenEXR's `floatvector` attribute type.
    F32Vec(Vec<f32>),
    /// OpenEXR's `chromaticities` attribute type (xy of red, green, blue and white).
    Chromaticities(Chromaticities),
}

/// `s` as an OpenEXR text, or an error naming `what` when it has characters OpenEXR cannot store.
pub(crate) fn text(s: &str, what: &str) -> Result<Text> {
    Text::new_or_none(s)
        .ok_or_else(|| Error::invalid(format!("{what} '{s}' has characters OpenEXR cannot store")))
}

/// The `exr` crate's value of attribute `name`.
pub(crate) fn attr_to_exr(name: &str, v: &AttrValue) -> Result<AttributeValue> {
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

/// The `exr` crate's `chromaticities` value (single precision, as OpenEXR stores it).
pub(crate) fn chromaticities_to_exr(c: &Chromaticities) -> exr::meta::attribute::Chromaticities {
    let xy = |p: [f64; 2]| Vec2(p[0] as f32, p[1] as f32);
    exr::meta::attribute::Chromaticities {
        red: xy(c.red),
        green: xy(c.green),
        blue: xy(c.blue),
        white: xy(c.white),
    }
}

/// The crate's value of a custom attribute, for the types [`AttrValue`] holds.
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

/// The header's `chromaticities` attribute (shared by all parts of a file).
pub(crate) fn chromaticities_of(header: &Header) -> Option<Chromaticities> {
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
