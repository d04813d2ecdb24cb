//! The layout of an environment file: the one its `envmap` attribute names, else the one its
//! size says ([`crate::envmap::layout::detect`]).

use crate::envmap::files::EnvmapAttr;
use crate::envmap::layout::{detect, Layout};
use crate::error::{Error, Result};
use std::path::Path;

/// The layout of the `w x h` file `path` of the `envmap` attribute `attr`: an error naming the
/// file where neither says one.
pub(super) fn layout_of(
    path: &Path,
    w: usize,
    h: usize,
    attr: Option<EnvmapAttr>,
) -> Result<Layout> {
    let attr = attr.map(|a| match a {
        EnvmapAttr::LatLong => Layout::LatLong,
        EnvmapAttr::Cube => Layout::Cube,
    });
    detect(w, h, attr).map_err(|e| Error::invalid(format!("{}: {e}", path.display())))
}
