//! How the quadrature's values are stored as JSON (the cache's entries, `--json` reports read
//! back): JSON has no infinity, so an error without bound is written as null.

/// A colour error as stored: JSON has no infinity, so an error that was not finite (a uniform
/// grid that misses a lamp's line entirely) is written as null, and read back as infinite.
pub(crate) fn error_or_infinite<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let v: Option<f64> = serde::Deserialize::deserialize(d)?;
    Ok(v.unwrap_or(f64::INFINITY))
}
