//! The shape each layout needs, and the layout of a map told from its size or its `envmap`
//! attribute.

use super::Layout;
use crate::error::{Error, Result};

impl Layout {
    /// Checks that a `width` x `height` image has this layout's shape.
    pub(super) fn check(self, width: usize, height: usize) -> Result<()> {
        let (cw, ch) = self.cells();
        let ok = width > 0 && height > 0 && width.is_multiple_of(cw) && width / cw * ch == height;
        if ok {
            return Ok(());
        }
        Err(Error::invalid(match self {
            Layout::LatLong => format!("lat-long must be 2:1, got {width}x{height}"),
            Layout::Cube => format!("a cube map must be N wide and 6N high, got {width}x{height}"),
            Layout::HCross => {
                format!("a horizontal cross must be 4N wide and 3N high, got {width}x{height}")
            }
            Layout::VCross => {
                format!("a vertical cross must be 3N wide and 4N high, got {width}x{height}")
            }
            Layout::HStrip => {
                format!("a horizontal strip must be 6N wide and N high, got {width}x{height}")
            }
            Layout::VStrip => {
                format!("a vertical strip must be N wide and 6N high, got {width}x{height}")
            }
        }))
    }
}

/// The layout of a `width` x `height` map: the file's `envmap` attribute if it has one (after
/// checking that the size fits it), else by aspect ratio (2:1 lat-long, 1:6 cube, 6:1 horizontal
/// strip, 4:3 horizontal cross, 3:4 vertical cross). A 1:6 map is taken as OpenEXR's cube; a
/// vertical strip must be asked for.
pub fn detect(width: usize, height: usize, envmap_attribute: Option<Layout>) -> Result<Layout> {
    if let Some(layout) = envmap_attribute {
        layout.check(width, height)?;
        return Ok(layout);
    }
    [
        Layout::LatLong,
        Layout::Cube,
        Layout::HStrip,
        Layout::HCross,
        Layout::VCross,
    ]
    .into_iter()
    .find(|l| l.check(width, height).is_ok())
    .ok_or_else(|| {
        Error::invalid(format!(
            "cannot tell the layout of a {width}x{height} environment map from its size \
             (expected 2:1 lat-long, 1:6 cube, 6:1 strip, 4:3 or 3:4 cross); \
             pass --in-layout latlong|cube|hcross|vcross|hstrip|vstrip"
        ))
    })
}
