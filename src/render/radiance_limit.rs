//! The brightest value an environment file may hold, and the error naming a pixel beyond it.

use crate::error::Error;
use std::path::Path;

/// The largest radiance an environment may hold: far above any photograph (the sun is about
/// 1e9 cd/m^2), far below where f32 products of spectra and filters overflow (3.4e38).
pub const MAX_RADIANCE: f64 = 1e18;

/// The error for pixel (x, y) of the file `path` holding `v`, beyond [`MAX_RADIANCE`].
pub(super) fn too_bright(path: &Path, x: usize, y: usize, v: f64) -> Error {
    Error::invalid(format!(
        "{}: pixel ({x}, {y}) value {v:e} exceeds {MAX_RADIANCE:e}, beyond what the renderer's \
         f32 arithmetic carries; scale the map down (e.g. convert it with an exposure)",
        path.display()
    ))
}
