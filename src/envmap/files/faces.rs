//! Reading a cube map from six face files named by a `{face}` pattern.

use crate::envmap::files::errors::parse_err;
use crate::envmap::files::rgb::{read_rgb, InputImage};
use crate::envmap::RgbImage;
use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// The cube face names in OpenEXR order (+X -X +Y -Y +Z -Z), as used in `{face}` patterns.
pub const FACE_NAMES: [&str; 6] = ["px", "nx", "py", "ny", "pz", "nz"];
/// The same faces in the signed spelling (+x, -x, ...) that `{face}` patterns also accept.
pub const FACE_SIGNED: [&str; 6] = ["+x", "-x", "+y", "-y", "+z", "-z"];

/// Reads six square face images from a pattern with `{face}` replaced by px, nx, py, ny, pz, nz
/// (or +x, -x, ... when the px form does not exist), in OpenEXR order +X -X +Y -Y +Z -Z.
pub fn read_faces(pattern: &str, layer: Option<&str>) -> Result<[RgbImage; 6]> {
    Ok(read_face_files(pattern, layer)?.map(|f| f.image))
}

/// [`read_faces`], each face with what its file says about itself.
pub fn read_face_files(pattern: &str, layer: Option<&str>) -> Result<[InputImage; 6]> {
    if !pattern.contains("{face}") {
        return Err(Error::invalid(format!(
            "face pattern '{pattern}' has no {{face}} placeholder"
        )));
    }
    let mut faces: Vec<InputImage> = Vec::with_capacity(6);
    for (name, signed) in FACE_NAMES.iter().zip(FACE_SIGNED) {
        let path = face_path(pattern, name, signed)?;
        let file = read_rgb(&path, layer)?;
        check_face_size(&path, &file.image, faces.first().map(|f| &f.image))?;
        faces.push(file);
    }
    faces
        .try_into()
        .map_err(|_| Error::invalid("six faces expected"))
}

/// The file of one face: the px spelling if it exists, else the +x one, else an error naming
/// both.
fn face_path(pattern: &str, name: &str, signed: &str) -> Result<PathBuf> {
    let primary = PathBuf::from(pattern.replace("{face}", name));
    let alt = PathBuf::from(pattern.replace("{face}", signed));
    if primary.exists() {
        Ok(primary)
    } else if alt.exists() {
        Ok(alt)
    } else {
        Err(Error::Io {
            path: primary.clone(),
            source: std::io::Error::new(
                std::io::ErrorKind::NotFound,
                format!(
                    "face file missing (tried {} and {})",
                    primary.display(),
                    alt.display()
                ),
            ),
        })
    }
}

/// Fails on a face that is not square or not the size of the first (+X) face.
fn check_face_size(path: &Path, img: &RgbImage, first: Option<&RgbImage>) -> Result<()> {
    if img.width != img.height {
        return Err(parse_err(
            path,
            format!("cube face is {}x{}, not square", img.width, img.height),
        ));
    }
    if let Some(first) = first {
        if first.width != img.width {
            return Err(parse_err(
                path,
                format!(
                    "cube face is {}x{} but the +X face is {}x{}",
                    img.width, img.height, first.width, first.height
                ),
            ));
        }
    }
    Ok(())
}
