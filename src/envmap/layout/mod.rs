//! Environment-map layouts (lat-long, OpenEXR cube, crosses, strips) and their pixel directions.
//!
//! # Conventions
//!
//! World space is OpenEXR's: right-handed, **Y up**. The formulas follow `Imf::LatLongMap` and
//! `Imf::CubeMap` in OpenEXR's `src/lib/OpenEXR/ImfEnvmap.cpp`
//! (AcademySoftwareFoundation/openexr, commit 41253757e6bbc8be5b0c4cafebe52f9b3e51a074):
//!
//! - **Lat-long** (2:1): `longitude = atan2(x, z)`, decreasing to the right; `latitude` from +π/2
//!   (top row, +Y) to −π/2 (bottom row, −Y); the centre column looks down +Z, the column a quarter
//!   from the left looks down +X; `dir = (sin lon cos lat, sin lat, cos lon cos lat)`.
//! - **Cube** (N wide, 6N high): faces stacked +X, −X, +Y, −Y, +Z, −Z, each with the pixel
//!   orientation of `CubeMap::pixelPosition` / `CubeMap::direction`. Moving right along a row /
//!   down along a column goes towards:
//!   +X: +Z / −Y; −X: −Z / −Y; +Y: +X / −Z; −Y: +X / +Z; +Z: −X / −Y; −Z: +X / −Y.
//!
//! One deliberate difference from OpenEXR: OpenEXR puts the first and last pixel *centres* on the
//! edges (`(p - min) / (max - min)`, so the lat-long's first row sits on the pole and cube edge
//! pixels are shared by two faces). Here pixel centres sit at `(i + 0.5) / N`, so every pixel
//! covers an equal share of its row / face and the pixels tile the sphere exactly, which the
//! solid angles and the filtered resampling rely on. Orientation is exactly OpenEXR's.
//!
//! **Every face of every cube-like layout has OpenEXR's cube-face orientation** (the images of
//! `CubeMap`'s faces); the layouts differ only in where the faces sit:
//!
//! - **Strips** hold the six faces in OpenEXR's order +X, −X, +Y, −Y, +Z, −Z, side by side
//!   (horizontal, 6N x N) or stacked (vertical, N x 6N: pixel for pixel OpenEXR's cube).
//! - **Crosses** use the cells of cmft (dariomanesku/cmft, commit cad5f31b: `imageCubemapFromCross`
//!   in `src/cmft/image.cpp`, the diagram above `s_faceUvVectors` in `src/cmft/cubemaputils.h`):
//!   horizontal cross 4N x 3N, a middle row of four faces with one face above and one below its
//!   second cell; vertical cross 3N x 4N, the same with the fourth middle-row face moved below,
//!   turned 180°. cmft's face frame (`s_faceUvVectors`, the OpenGL/Direct3D cube-map convention)
//!   is left-handed: with z negated, each of its face images is exactly OpenEXR's face of that
//!   axis (cmft's "+Z" face is OpenEXR's −Z). Read so, the middle row is **−X, −Z, +X, +Z**, with
//!   +Y above and −Y below −Z, every face as in OpenEXR's cube (the vertical cross's +Z, below −Y,
//!   turned 180° as cmft turns it); no other placement of OpenEXR's unturned faces in these cells
//!   is seamless. cmft's own lat-long is a quarter turn from OpenEXR's: a cross that cmft makes
//!   from a lat-long reads back as that lat-long with `--rotation 90`.

mod detect;
mod directions;
mod faces;
mod orientation;
mod resample;

pub use detect::detect;
pub use faces::Face;
pub use orientation::{Orientation, Up};

use crate::envmap::RgbImage;
use crate::error::{Error, Result};
use faces::{Slot, CUBE, HCROSS, HSTRIP, VCROSS, VSTRIP};

/// How the directions of an environment map are laid out in its image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Layout {
    /// Equirectangular, 2:1, OpenEXR's `envmap = latlong`.
    LatLong,
    /// OpenEXR's cube: N wide, 6N high, faces stacked +X, −X, +Y, −Y, +Z, −Z.
    Cube,
    /// Horizontal cross, 4N x 3N.
    HCross,
    /// Vertical cross, 3N x 4N.
    VCross,
    /// Horizontal strip, 6N x N.
    HStrip,
    /// Vertical strip, N x 6N.
    VStrip,
}

impl Layout {
    /// Every layout.
    pub const ALL: [Layout; 6] = [
        Layout::LatLong,
        Layout::Cube,
        Layout::HCross,
        Layout::VCross,
        Layout::HStrip,
        Layout::VStrip,
    ];

    /// The name used on the command line and in the `envmap` attribute.
    pub fn name(self) -> &'static str {
        match self {
            Layout::LatLong => "latlong",
            Layout::Cube => "cube",
            Layout::HCross => "hcross",
            Layout::VCross => "vcross",
            Layout::HStrip => "hstrip",
            Layout::VStrip => "vstrip",
        }
    }

    /// Image size, in face sizes (lat-long: in heights).
    fn cells(self) -> (usize, usize) {
        match self {
            Layout::LatLong => (2, 1),
            Layout::Cube | Layout::VStrip => (1, 6),
            Layout::HCross => (4, 3),
            Layout::VCross => (3, 4),
            Layout::HStrip => (6, 1),
        }
    }

    /// The image width and height for face size (lat-long: height) `size`.
    pub fn dimensions(self, size: usize) -> (usize, usize) {
        let (cw, ch) = self.cells();
        (cw * size, ch * size)
    }

    /// Where the six faces sit in a cube-like layout (in [`Face::ALL`] order); None for a
    /// lat-long.
    fn slots(self) -> Option<&'static [Slot; 6]> {
        match self {
            Layout::LatLong => None,
            Layout::Cube => Some(&CUBE),
            Layout::HCross => Some(&HCROSS),
            Layout::VCross => Some(&VCROSS),
            Layout::HStrip => Some(&HSTRIP),
            Layout::VStrip => Some(&VSTRIP),
        }
    }
}

/// An environment map: an image and how its pixels map to directions.
#[derive(Debug, Clone)]
pub struct EnvMap {
    /// How directions are laid out.
    pub layout: Layout,
    /// The pixels.
    pub image: RgbImage,
}

impl EnvMap {
    /// A map of the given layout, checking that the image has its shape.
    pub fn new(layout: Layout, image: RgbImage) -> Result<EnvMap> {
        layout.check(image.width, image.height)?;
        if image.pixels.len() != image.width * image.height {
            return Err(Error::invalid(format!(
                "a {}x{} image needs {} pixels, got {}",
                image.width,
                image.height,
                image.width * image.height,
                image.pixels.len()
            )));
        }
        Ok(EnvMap { layout, image })
    }

    /// OpenEXR's cube from six square faces of equal size, given in +X, −X, +Y, −Y, +Z, −Z order,
    /// each in OpenEXR's orientation (as in [`Layout::Cube`]).
    pub fn from_faces(faces: [RgbImage; 6]) -> Result<EnvMap> {
        let n = faces[0].width;
        for (face, img) in Face::ALL.iter().zip(faces.iter()) {
            if img.width != img.height || img.width == 0 {
                return Err(Error::invalid(format!(
                    "face {} is {}x{}: faces must be square and not empty",
                    face.name(),
                    img.width,
                    img.height
                )));
            }
            if img.width != n {
                return Err(Error::invalid(format!(
                    "face {} is {}x{} but face +X is {n}x{n}: all faces must be the same size",
                    face.name(),
                    img.width,
                    img.height
                )));
            }
            if img.pixels.len() != n * n {
                return Err(Error::invalid(format!(
                    "face {} has {} pixels, expected {}",
                    face.name(),
                    img.pixels.len(),
                    n * n
                )));
            }
        }
        let mut pixels = Vec::with_capacity(6 * n * n);
        for img in faces.iter() {
            pixels.extend_from_slice(&img.pixels);
        }
        EnvMap::new(
            Layout::Cube,
            RgbImage {
                width: n,
                height: 6 * n,
                pixels,
            },
        )
    }

    /// The face size N of a cube-like layout; the height of a lat-long.
    pub fn face_size(&self) -> usize {
        let (cw, _) = self.layout.cells();
        match self.layout {
            Layout::LatLong => self.image.height,
            _ => self.image.width / cw,
        }
    }

    /// The value of pixel (x, y); black outside the pixels.
    fn pixel(&self, x: usize, y: usize) -> [f32; 3] {
        self.image
            .pixels
            .get(y * self.image.width + x)
            .copied()
            .unwrap_or([0.0; 3])
    }

    /// The pixels the layout uses: all but the unused cells of a cross.
    pub fn used_pixels(&self) -> usize {
        let (w, h) = (self.image.width, self.image.height);
        match self.layout {
            Layout::HCross | Layout::VCross => w * h / 2,
            _ => w * h,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inconsistent_maps_do_not_panic() {
        // The fields are public: a map built by hand may not match its layout.
        for layout in Layout::ALL {
            for (w, h) in [(0, 0), (1, 1), (3, 2), (5, 17)] {
                let m = EnvMap {
                    layout,
                    image: RgbImage {
                        width: w,
                        height: h,
                        pixels: vec![[1.0; 3]; w * h / 2],
                    },
                };
                let _ = m.sample([0.2, -0.3, 0.9]);
                let _ = m.direction(1, 1);
                let _ = m.solid_angle(2, 0);
                let _ = m.pixels_with_directions().count();
                let r = m.resample(Layout::Cube, 2);
                assert_eq!(r.image.pixels.len(), 24);
            }
        }
    }
}
