//! The `#[repr(C)]` records the WGSL shader declares (frame constants, objects, materials,
//! lightings) and their kind and flag values: what [`super::prepare`] fills and both renderers
//! read.

use bytemuck::{Pod, Zeroable};

/// [`GpuObject::kind`] of a [`super::Shape::Sphere`].
pub const SPHERE: u32 = 0;
/// [`GpuObject::kind`] of a [`super::Shape::CylinderX`].
pub const CYLINDER_X: u32 = 1;
/// [`GpuObject::kind`] of a [`super::Shape::Quad`].
pub const QUAD: u32 = 2;

/// [`GpuMaterial::flags`] bit: the surface is transparent (Eq. 9).
pub const TRANSPARENT: u32 = 1;
/// [`GpuMaterial::flags`] bit: the surface has a film (its table at `film_offset`).
pub const HAS_FILM: u32 = 2;
/// [`GpuMaterial::flags`] bit: the surface has a diffuse spectrum (at `diffuse_offset`).
pub const HAS_DIFFUSE: u32 = 4;

/// `Params::flags`: rays that miss every object are black, not the environment.
pub const HIDE_BACKGROUND: u32 = 1;

/// Frame constants (a uniform buffer).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct Params {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Number of quadrature nodes (wavelengths).
    pub n_wl: u32,
    /// Number of records in `objects`.
    pub n_objects: u32,
    /// Index in `lightings` of the lighting seen where rays miss.
    pub background: u32,
    /// Offset in `spectra` of the quadrature's x, y, z weights over `sum w_y` (n_wl each).
    pub cmf_offset: u32,
    /// Offset in `spectra` of the quadrature's nodes in nm (n_wl).
    pub wl_offset: u32,
    /// [`HIDE_BACKGROUND`].
    pub flags: u32,
    /// World x, y of the image centre, world size of a pixel, and the tangent of half the
    /// vertical field of view the background is seen with (0: straight down −Z).
    pub view: [f32; 4],
    /// XYZ (Y = 1) -> linear RGB, rows (w unused).
    pub rgb: [[f32; 4]; 3],
    /// Camera to world for map lookups ([`super::Scene::orientation`]), rows (w unused).
    pub orientation: [[f32; 4]; 3],
}

/// An object: its shape, material, lighting and film ramp (`objects`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuObject {
    /// [`SPHERE`], [`CYLINDER_X`] or [`QUAD`].
    pub kind: u32,
    /// Index in `materials` of its surface.
    pub material: u32,
    /// Index in `lightings` of the lighting that lights it.
    pub lighting: u32,
    /// Index in `maps` of the specular map for this object's shininess and lighting.
    pub spec_map: u32,
    /// Centre xyz, radius (quad: unused).
    pub p0: [f32; 4],
    /// Quad: half width, half height; cylinder: half length.
    pub p1: [f32; 4],
    /// Thickness ramp x0, x1, s0, s1.
    pub ramp: [f32; 4],
    /// [has_ramp, 0, 0, 0].
    pub flags: [u32; 4],
}

/// A surface: its flags, diffuse spectrum, film table and coefficients (`materials`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuMaterial {
    /// [`TRANSPARENT`], [`HAS_FILM`], [`HAS_DIFFUSE`] or'ed.
    pub flags: u32,
    /// Layers of the film (0 without one), at most [`super::MAX_LAYERS`].
    pub n_layers: u32,
    /// Offset of R_d in `spectra`.
    pub diffuse_offset: u32,
    /// Offset of the film table: for medium m (0 ambient, 1..=L layers, L+1 substrate), n at
    /// `film_offset + 2 m n_wl + i`, k at `film_offset + (2 m + 1) n_wl + i`.
    pub film_offset: u32,
    /// kd, ks, shininess, unused.
    pub coef: [f32; 4],
    /// Layer thicknesses in nm.
    pub thickness: [[f32; 4]; 2],
}

/// A lighting: its spectra, maps and sun (`lightings`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuLighting {
    /// Offset of the first spectrum; the other `4 groups - 1` follow, n_wl apart.
    pub spectra: u32,
    /// Index in `maps` of its diffuse irradiance map (over pi).
    pub diffuse_map: u32,
    /// Index in `maps` of the environment itself, seen where rays miss and behind transparent
    /// objects.
    pub background_map: u32,
    /// 1 where the lighting has a sun, else 0.
    pub has_sun: u32,
    /// Direction to the sun xyz, irradiance.
    pub sun: [f32; 4],
    /// Groups of four coefficients per texel, offset of the sun's SPD, unused.
    pub layout: [u32; 4],
}
