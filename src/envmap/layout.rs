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

use crate::envmap::RgbImage;
use crate::error::{Error, Result};
use rayon::prelude::*;
use std::f64::consts::PI;

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

/// A cube face, named by the axis its centre looks down.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Face {
    /// +X
    PosX,
    /// −X
    NegX,
    /// +Y (up)
    PosY,
    /// −Y (down)
    NegY,
    /// +Z
    PosZ,
    /// −Z
    NegZ,
}

impl Face {
    /// The six faces in OpenEXR's order.
    pub const ALL: [Face; 6] = [
        Face::PosX,
        Face::NegX,
        Face::PosY,
        Face::NegY,
        Face::PosZ,
        Face::NegZ,
    ];

    /// "+X", "-X", "+Y", "-Y", "+Z" or "-Z".
    pub fn name(self) -> &'static str {
        match self {
            Face::PosX => "+X",
            Face::NegX => "-X",
            Face::PosY => "+Y",
            Face::NegY => "-Y",
            Face::PosZ => "+Z",
            Face::NegZ => "-Z",
        }
    }

    /// The unit vector the face's centre looks down.
    pub fn axis(self) -> [f64; 3] {
        match self {
            Face::PosX => [1.0, 0.0, 0.0],
            Face::NegX => [-1.0, 0.0, 0.0],
            Face::PosY => [0.0, 1.0, 0.0],
            Face::NegY => [0.0, -1.0, 0.0],
            Face::PosZ => [0.0, 0.0, 1.0],
            Face::NegZ => [0.0, 0.0, -1.0],
        }
    }

    /// The face a direction falls on, with OpenEXR's tie-breaking
    /// (`CubeMap::faceAndPixelPosition`: X before Y before Z).
    pub fn of(dir: [f64; 3]) -> Face {
        let [x, y, z] = dir;
        let (ax, ay, az) = (x.abs(), y.abs(), z.abs());
        if ax >= ay && ax >= az {
            if x > 0.0 || ax == 0.0 {
                Face::PosX
            } else {
                Face::NegX
            }
        } else if ay >= az {
            if y > 0.0 {
                Face::PosY
            } else {
                Face::NegY
            }
        } else if z > 0.0 {
            Face::PosZ
        } else {
            Face::NegZ
        }
    }

    fn index(self) -> usize {
        self as usize
    }
}

/// Which world axis is up in a map's own space.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Up {
    /// Y up (OpenEXR, the world here).
    #[default]
    Y,
    /// Z up (Blender and most DCC tools); map +Z becomes world +Y, map +Y becomes world −Z.
    Z,
}

/// How a map's own directions relate to the world (OpenEXR's, Y up): first the up axis is made
/// Y, then the map is turned by `rotation_deg` about the (world) up axis, counter-clockwise seen
/// from above (+Z towards +X).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orientation {
    /// The map's up axis.
    pub up: Up,
    /// Rotation about the up axis, degrees.
    pub rotation_deg: f64,
}

impl Default for Orientation {
    fn default() -> Self {
        Orientation {
            up: Up::Y,
            rotation_deg: 0.0,
        }
    }
}

impl Orientation {
    /// A map-space direction in world space.
    pub fn to_world(&self, d: [f64; 3]) -> [f64; 3] {
        let [x, y, z] = match self.up {
            Up::Y => d,
            Up::Z => [d[0], d[2], -d[1]],
        };
        let (s, c) = self.rotation_deg.to_radians().sin_cos();
        [c * x + s * z, y, -s * x + c * z]
    }

    /// Whether this is the identity (OpenEXR's own orientation).
    pub fn is_identity(&self) -> bool {
        self.up == Up::Y && self.rotation_deg.rem_euclid(360.0) == 0.0
    }

    /// [`Orientation::to_map`] as a matrix (rows), for use per sample.
    pub fn to_map_matrix(&self) -> [[f64; 3]; 3] {
        let col = |d: [f64; 3]| self.to_map(d);
        let (x, y, z) = (
            col([1.0, 0.0, 0.0]),
            col([0.0, 1.0, 0.0]),
            col([0.0, 0.0, 1.0]),
        );
        [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]]
    }

    /// A world-space direction in map space (the inverse of [`Orientation::to_world`]).
    pub fn to_map(&self, d: [f64; 3]) -> [f64; 3] {
        let (s, c) = self.rotation_deg.to_radians().sin_cos();
        let [x, y, z] = [c * d[0] - s * d[2], d[1], s * d[0] + c * d[2]];
        match self.up {
            Up::Y => [x, y, z],
            Up::Z => [x, -z, y],
        }
    }
}

/// One face's cell in a cube-like layout: where it is (in face-size units) and which world
/// directions its image's right and down point to.
#[derive(Debug, Clone, Copy)]
struct Slot {
    col: usize,
    row: usize,
    right: [f64; 3],
    down: [f64; 3],
}

const PX: [f64; 3] = [1.0, 0.0, 0.0];
const NX: [f64; 3] = [-1.0, 0.0, 0.0];
const PY: [f64; 3] = [0.0, 1.0, 0.0];
const NY: [f64; 3] = [0.0, -1.0, 0.0];
const PZ: [f64; 3] = [0.0, 0.0, 1.0];
const NZ: [f64; 3] = [0.0, 0.0, -1.0];

const fn slot(col: usize, row: usize, right: [f64; 3], down: [f64; 3]) -> Slot {
    Slot {
        col,
        row,
        right,
        down,
    }
}

/// OpenEXR's cube: `CubeMap::pixelPosition` read as "right / down go towards".
const CUBE: [Slot; 6] = [
    slot(0, 0, PZ, NY),
    slot(0, 1, NZ, NY),
    slot(0, 2, PX, NZ),
    slot(0, 3, PX, PZ),
    slot(0, 4, NX, NY),
    slot(0, 5, PX, NY),
];
/// Horizontal cross: middle row −X, −Z, +X, +Z; +Y above and −Y below −Z; OpenEXR's faces.
const HCROSS: [Slot; 6] = [
    slot(2, 1, PZ, NY),
    slot(0, 1, NZ, NY),
    slot(1, 0, PX, NZ),
    slot(1, 2, PX, PZ),
    slot(3, 1, NX, NY),
    slot(1, 1, PX, NY),
];
/// Vertical cross: as the horizontal one, with +Z below −Y, turned 180°.
const VCROSS: [Slot; 6] = {
    let mut v = HCROSS;
    v[4] = slot(1, 3, PX, PY);
    v
};
/// Horizontal strip: OpenEXR's faces side by side, in its order, each as in the cube.
const HSTRIP: [Slot; 6] = {
    let mut h = CUBE;
    let mut i = 0;
    while i < 6 {
        h[i].col = i;
        h[i].row = 0;
        i += 1;
    }
    h
};
/// Vertical strip: OpenEXR's cube.
const VSTRIP: [Slot; 6] = CUBE;

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

    /// Checks that a `width` x `height` image has this layout's shape.
    fn check(self, width: usize, height: usize) -> Result<()> {
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

/// An environment map: an image and how its pixels map to directions.
#[derive(Debug, Clone)]
pub struct EnvMap {
    /// How directions are laid out.
    pub layout: Layout,
    /// The pixels.
    pub image: RgbImage,
}

fn norm(d: [f64; 3]) -> f64 {
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

fn normalize(d: [f64; 3]) -> [f64; 3] {
    let n = norm(d);
    [d[0] / n, d[1] / n, d[2] / n]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Lat-long direction at continuous image position (u, v) in [0, 1]^2 (`LatLongMap::direction`
/// with pixel centres at (i + 0.5) / N).
fn latlong_dir(u: f64, v: f64) -> [f64; 3] {
    let lat = -PI * (v - 0.5);
    let lon = -2.0 * PI * (u - 0.5);
    let (sl, cl) = lat.sin_cos();
    let (so, co) = lon.sin_cos();
    [so * cl, sl, co * cl]
}

/// Cube-face direction (not normalised) at face coordinates (s, t) in [0, 1]^2.
fn face_dir(face: Face, s: &Slot, fs: f64, ft: f64) -> [f64; 3] {
    let a = face.axis();
    let (p, q) = (2.0 * fs - 1.0, 2.0 * ft - 1.0);
    [
        a[0] + p * s.right[0] + q * s.down[0],
        a[1] + p * s.right[1] + q * s.down[1],
        a[2] + p * s.right[2] + q * s.down[2],
    ]
}

/// The solid angle of the face region [0, x] x [0, y] seen from the cube's centre, face at
/// distance 1 (Mathar 2005; the same formula as cmft's `areaElement`).
fn area_element(x: f64, y: f64) -> f64 {
    (x * y).atan2((x * x + y * y + 1.0).sqrt())
}

/// A weighted sum divided by its total weight, as a pixel value.
fn finish(acc: [f64; 3], wsum: f64) -> [f32; 3] {
    if wsum > 0.0 {
        [
            (acc[0] / wsum) as f32,
            (acc[1] / wsum) as f32,
            (acc[2] / wsum) as f32,
        ]
    } else {
        [0.0; 3]
    }
}

/// The slot of the pixel (x, y) of a cube-like layout of face size n, with the pixel's position
/// inside the face.
fn locate(slots: &[Slot; 6], n: usize, x: usize, y: usize) -> Option<(Face, &Slot, usize, usize)> {
    let (col, row) = (x / n, y / n);
    Face::ALL
        .iter()
        .zip(slots.iter())
        .find(|(_, s)| s.col == col && s.row == row)
        .map(|(f, s)| (*f, s, x % n, y % n))
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

    fn pixel(&self, x: usize, y: usize) -> [f32; 3] {
        self.image
            .pixels
            .get(y * self.image.width + x)
            .copied()
            .unwrap_or([0.0; 3])
    }

    /// The unit direction at sub-pixel offset (fx, fy) in [0, 1]^2 of pixel (x, y); None outside
    /// the image or in an unused cell.
    fn direction_at(&self, x: usize, y: usize, fx: f64, fy: f64) -> Option<[f64; 3]> {
        let (w, h) = (self.image.width, self.image.height);
        if x >= w || y >= h {
            return None;
        }
        match self.layout.slots() {
            None => Some(latlong_dir(
                (x as f64 + fx) / w as f64,
                (y as f64 + fy) / h as f64,
            )),
            Some(slots) => {
                let n = self.face_size().max(1);
                let (face, s, i, j) = locate(slots, n, x, y)?;
                let nf = n as f64;
                let d = face_dir(face, s, (i as f64 + fx) / nf, (j as f64 + fy) / nf);
                Some(normalize(d))
            }
        }
    }

    /// The unit direction of pixel (x, y)'s centre; None for the unused cells of a cross (and
    /// outside the image).
    pub fn direction(&self, x: usize, y: usize) -> Option<[f64; 3]> {
        self.direction_at(x, y, 0.5, 0.5)
    }

    /// The exact solid angle of pixel (x, y) in steradians (0 in unused cells and outside the
    /// image); over all pixels these sum to 4π.
    pub fn solid_angle(&self, x: usize, y: usize) -> f64 {
        let (w, h) = (self.image.width, self.image.height);
        if x >= w || y >= h {
            return 0.0;
        }
        match self.layout.slots() {
            None => {
                // A band between two latitudes, split evenly in longitude.
                let t0 = PI * y as f64 / h as f64;
                let t1 = PI * (y + 1) as f64 / h as f64;
                2.0 * PI / w as f64 * (t0.cos() - t1.cos())
            }
            Some(slots) => {
                let n = self.face_size().max(1);
                let Some((_, _, i, j)) = locate(slots, n, x, y) else {
                    return 0.0;
                };
                let nf = n as f64;
                let (a0, a1) = (2.0 * i as f64 / nf - 1.0, 2.0 * (i + 1) as f64 / nf - 1.0);
                let (b0, b1) = (2.0 * j as f64 / nf - 1.0, 2.0 * (j + 1) as f64 / nf - 1.0);
                (area_element(a1, b1) - area_element(a0, b1) - area_element(a1, b0)
                    + area_element(a0, b0))
                .abs()
            }
        }
    }

    /// The map's value in direction `dir` (any length; zero gives +X's value, NaN gives black):
    /// bilinear, wrapping in longitude for lat-long and clamped within a face for cube-like
    /// layouts.
    pub fn sample(&self, dir: [f64; 3]) -> [f32; 3] {
        let (w, h) = (self.image.width, self.image.height);
        if w == 0 || h == 0 || !dir.iter().all(|c| c.is_finite()) {
            return [0.0; 3];
        }
        match self.layout.slots() {
            None => {
                // LatLongMap::latLong / pixelPosition, pixel centres at (i + 0.5) / N.
                let [x, y, z] = dir;
                let r = (x * x + z * z).sqrt();
                let lat = y.atan2(r);
                let lon = if x == 0.0 && z == 0.0 {
                    0.0
                } else {
                    x.atan2(z)
                };
                let u = 0.5 - lon / (2.0 * PI);
                let v = 0.5 - lat / PI;
                let px = u * w as f64 - 0.5;
                let py = (v * h as f64 - 0.5).clamp(0.0, (h - 1) as f64);
                let fx0 = px.floor();
                let tx = px - fx0;
                let x0 = (fx0 as i64).rem_euclid(w as i64) as usize;
                let x1 = (x0 + 1) % w;
                let y0 = py.floor() as usize;
                let y1 = (y0 + 1).min(h - 1);
                let ty = py - y0 as f64;
                self.bilerp(x0, x1, y0, y1, tx, ty)
            }
            Some(slots) => {
                let n = self.face_size();
                if n == 0 {
                    return [0.0; 3];
                }
                let face = Face::of(dir);
                let s = &slots[face.index()];
                let m = dot(dir, face.axis());
                if m <= 0.0 {
                    // Only the zero vector gets here.
                    return self.pixel(s.col * n, s.row * n);
                }
                let p = [dir[0] / m, dir[1] / m, dir[2] / m];
                let nf = n as f64;
                let fs = (dot(p, s.right) + 1.0) * 0.5;
                let ft = (dot(p, s.down) + 1.0) * 0.5;
                let px = (fs * nf - 0.5).clamp(0.0, nf - 1.0);
                let py = (ft * nf - 0.5).clamp(0.0, nf - 1.0);
                let i0 = px.floor() as usize;
                let j0 = py.floor() as usize;
                let i1 = (i0 + 1).min(n - 1);
                let j1 = (j0 + 1).min(n - 1);
                let (ox, oy) = (s.col * n, s.row * n);
                self.bilerp(
                    ox + i0,
                    ox + i1,
                    oy + j0,
                    oy + j1,
                    px - i0 as f64,
                    py - j0 as f64,
                )
            }
        }
    }

    fn bilerp(&self, x0: usize, x1: usize, y0: usize, y1: usize, tx: f64, ty: f64) -> [f32; 3] {
        let (a, b, c, d) = (
            self.pixel(x0, y0),
            self.pixel(x1, y0),
            self.pixel(x0, y1),
            self.pixel(x1, y1),
        );
        let mut out = [0.0f32; 3];
        for k in 0..3 {
            let top = a[k] as f64 * (1.0 - tx) + b[k] as f64 * tx;
            let bot = c[k] as f64 * (1.0 - tx) + d[k] as f64 * tx;
            out[k] = (top * (1.0 - ty) + bot * ty) as f32;
        }
        out
    }

    pub fn used_pixels(&self) -> usize {
        let (w, h) = (self.image.width, self.image.height);
        match self.layout {
            Layout::HCross | Layout::VCross => w * h / 2,
            _ => w * h,
        }
    }

    /// This map in another layout: `size` is the lat-long height (width 2·size) or the face
    /// size (0 is taken as 1). Each destination pixel averages a k x k stratified grid of
    /// bilinear source samples, weighted by the solid angle each sub-cell covers, with k the
    /// square root of the source-to-destination pixel ratio rounded up (at least 2, at most 64).
    /// Unused cells of a cross are black.
    pub fn resample(&self, layout: Layout, size: usize) -> EnvMap {
        self.resample_oriented(layout, size, &Orientation::default())
    }

    /// [`EnvMap::resample`], with this map's directions related to the world's by
    /// `orientation`: the result is in world (OpenEXR, Y up) orientation, so a Z-up map or one
    /// turned about the up axis comes out upright and turned back.
    pub fn resample_oriented(
        &self,
        layout: Layout,
        size: usize,
        orientation: &Orientation,
    ) -> EnvMap {
        let source = Oriented {
            map: self,
            m: orientation.to_map_matrix(),
        };
        let size = size.max(1);
        let (w, h) = layout.dimensions(size);
        let mut dst = EnvMap {
            layout,
            image: RgbImage::new(w, h),
        };
        let grid = SubSamples::new(self, &dst, size);
        let slots = layout.slots();
        dst.image
            .pixels
            .par_chunks_mut(w)
            .enumerate()
            .for_each(|(y, row)| match slots {
                None => grid.latlong_row(&source, y, row),
                Some(slots) => grid.cube_row(&source, slots, y, row),
            });
        dst
    }

    /// Every used pixel as (x, y, unit direction, solid angle, value), row by row; the unused
    /// cells of a cross are skipped.
    pub fn pixels_with_directions(
        &self,
    ) -> impl Iterator<Item = (usize, usize, [f64; 3], f64, [f32; 3])> + '_ {
        let w = self.image.width;
        (0..self.image.height).flat_map(move |y| {
            (0..w).filter_map(move |x| {
                self.direction(x, y)
                    .map(|d| (x, y, d, self.solid_angle(x, y), self.pixel(x, y)))
            })
        })
    }
}

/// A map seen through an orientation: world directions in, the map's values out.
struct Oriented<'a> {
    map: &'a EnvMap,
    /// World to map directions.
    m: [[f64; 3]; 3],
}

impl Oriented<'_> {
    /// The map's value in world direction `d`.
    fn at(&self, d: [f64; 3]) -> [f32; 3] {
        let m = &self.m;
        self.map.sample([
            m[0][0] * d[0] + m[0][1] * d[1] + m[0][2] * d[2],
            m[1][0] * d[0] + m[1][1] * d[1] + m[1][2] * d[2],
            m[2][0] * d[0] + m[2][1] * d[1] + m[2][2] * d[2],
        ])
    }
}

/// The k x k stratified sub-samples of a resampling's destination pixels.
struct SubSamples {
    k: usize,
    /// Sub-sample offsets inside a pixel.
    offsets: Vec<f64>,
    /// For a lat-long destination, the sines and cosines of every sub-column's longitude
    /// (computed once, shared by all rows); empty otherwise.
    lon_trig: Vec<(f64, f64)>,
    /// The destination's lat-long height or face size.
    size: usize,
    /// The destination's height.
    height: usize,
}

impl SubSamples {
    /// k is the square root of the source-to-destination pixel ratio rounded up (at least 2, at
    /// most 64).
    fn new(src: &EnvMap, dst: &EnvMap, size: usize) -> SubSamples {
        let (w, h) = (dst.image.width, dst.image.height);
        let dst_used = dst.used_pixels().max(1) as f64;
        let ratio = src.used_pixels() as f64 / dst_used;
        let k = (ratio.sqrt().ceil() as usize).clamp(2, 64);
        let kf = k as f64;
        let offsets: Vec<f64> = (0..k).map(|a| (a as f64 + 0.5) / kf).collect();
        let lon_trig: Vec<(f64, f64)> = match dst.layout {
            Layout::LatLong => (0..w * k)
                .map(|c| (-2.0 * PI * ((c as f64 + 0.5) / (w * k) as f64 - 0.5)).sin_cos())
                .collect(),
            _ => Vec::new(),
        };
        SubSamples {
            k,
            offsets,
            lon_trig,
            size,
            height: h,
        }
    }

    /// Row `y` of a lat-long destination, each pixel weighted by the solid-angle density
    /// cos(latitude).
    fn latlong_row(&self, source: &Oriented, y: usize, row: &mut [[f32; 3]]) {
        let k = self.k;
        // Sines and cosines of this row's sub-row latitudes: k values, on the stack for k <= 64.
        let mut lat_trig = [(0.0f64, 0.0f64); 64];
        for (t, &fy) in lat_trig.iter_mut().zip(self.offsets.iter()) {
            *t = (-PI * ((y as f64 + fy) / self.height as f64 - 0.5)).sin_cos();
        }
        for (x, out) in row.iter_mut().enumerate() {
            let mut acc = [0.0f64; 3];
            let mut wsum = 0.0;
            for &(sl, cl) in &lat_trig[..k] {
                for &(so, co) in &self.lon_trig[x * k..(x + 1) * k] {
                    // Solid-angle density cos(latitude).
                    let v = source.at([so * cl, sl, co * cl]);
                    for c in 0..3 {
                        acc[c] += cl * v[c] as f64;
                    }
                    wsum += cl;
                }
            }
            *out = finish(acc, wsum);
        }
    }

    /// Row `y` of a cube-like destination; the unused cells of a cross stay black.
    fn cube_row(&self, source: &Oriented, slots: &[Slot; 6], y: usize, row: &mut [[f32; 3]]) {
        for (x, out) in row.iter_mut().enumerate() {
            let Some((face, s, i, j)) = locate(slots, self.size, x, y) else {
                continue;
            };
            *out = self.face_pixel(source, face, s, i, j);
        }
    }

    /// Pixel (i, j) of a destination face, each sub-sample weighted by the solid-angle density
    /// 1/r^3 on the face plane.
    fn face_pixel(&self, source: &Oriented, face: Face, s: &Slot, i: usize, j: usize) -> [f32; 3] {
        let nf = self.size as f64;
        let mut acc = [0.0f64; 3];
        let mut wsum = 0.0;
        for &fy in &self.offsets {
            for &fx in &self.offsets {
                let d = face_dir(face, s, (i as f64 + fx) / nf, (j as f64 + fy) / nf);
                let r2 = dot(d, d);
                // Solid-angle density 1/r^3 on the face plane.
                let wt = 1.0 / (r2 * r2.sqrt());
                let v = source.at(d);
                for c in 0..3 {
                    acc[c] += wt * v[c] as f64;
                }
                wsum += wt;
            }
        }
        finish(acc, wsum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn area_element_closed_form() {
        // A whole face: 4 * atan2(1, sqrt 3) = 4 * pi / 6.
        let face = area_element(1.0, 1.0) - area_element(-1.0, 1.0) - area_element(1.0, -1.0)
            + area_element(-1.0, -1.0);
        assert!((face - 4.0 * PI / 6.0).abs() < 1e-15);
        assert_eq!(area_element(0.0, 0.7), 0.0);
    }

    #[test]
    fn face_ties_follow_openexr() {
        // CubeMap::faceAndPixelPosition: X wins ties with Y and Z, Y wins ties with Z.
        assert_eq!(Face::of([1.0, 1.0, 1.0]), Face::PosX);
        assert_eq!(Face::of([-1.0, -1.0, 0.0]), Face::NegX);
        assert_eq!(Face::of([0.0, 1.0, -1.0]), Face::PosY);
        assert_eq!(Face::of([0.0, 0.0, -1.0]), Face::NegZ);
        assert_eq!(Face::of([0.0, 0.0, 0.0]), Face::PosX);
        let names: Vec<_> = Face::ALL.iter().map(|f| f.name()).collect();
        assert_eq!(names, ["+X", "-X", "+Y", "-Y", "+Z", "-Z"]);
    }

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
