//! The probe: one pixel's spectral radiance at 1 nm (Simpson, the project's reference), the
//! nodes of the quadrature in use, its colour (XYZ, xy, CIELAB, sRGB), the film's reflectance
//! at the pixel's view angle, and what the quadrature errs on that pixel (CIEDE2000).

use specmap::colorimetry::{delta_e_2000, srgb_encode, Lab, Observer, RgbSpace};
use specmap::quadrature::Quadrature;
use specmap::render::prepare::Prepared;
use specmap::render::{cpu, Scene};
use specmap::spectrum::{Rule, WavelengthGrid};

/// What the probe found at one pixel.
#[derive(Debug, Clone, serde::Serialize)]
pub(crate) struct Probe {
    /// Image pixel, x to the right and y down.
    pub(crate) at: [usize; 2],
    /// 380..780 nm at 1 nm, and the pixel's radiance there.
    pub(crate) wavelengths_nm: Vec<f64>,
    pub(crate) radiance: Vec<f64>,
    /// The quadrature's nodes.
    pub(crate) nodes_nm: Vec<f64>,
    /// The colour of the 1 nm spectrum: XYZ (a white under the main light has Y = 100), xy,
    /// CIELAB (relative to RGB white), linear sRGB and 8-bit sRGB.
    pub(crate) xyz: [f64; 3],
    pub(crate) xy: [f64; 2],
    pub(crate) lab: [f64; 3],
    pub(crate) rgb_linear: [f64; 3],
    pub(crate) srgb8: [u8; 3],
    /// The pixel on the quadrature in use (linear sRGB), and its CIEDE2000 from the 1 nm one.
    pub(crate) rgb_quadrature: [f64; 3],
    pub(crate) error_de2000: f64,
    pub(crate) view_angle_deg: Option<f64>,
    /// The film's reflectance at 1 nm, at the pixel's angle.
    pub(crate) film_reflectance: Option<Vec<f64>>,
}

/// Probes pixel (x, y) of `scene`, whose frame `p` was prepared for the quadrature in use.
pub(crate) fn probe(
    scene: &Scene,
    p: &Prepared,
    x: usize,
    y: usize,
    observer: Observer,
) -> anyhow::Result<Probe> {
    if x >= scene.width || y >= scene.height {
        anyhow::bail!(
            "probe ({x}, {y}) is outside the {}x{} image",
            scene.width,
            scene.height
        );
    }
    let grid = WavelengthGrid::new(380.0, 780.0, 1.0)?;
    let q = Quadrature::uniform(grid, Rule::Simpson, observer)?;
    let space = RgbSpace::SRGB;
    let fine = Prepared::with_quadrature(scene, &q, space)?;
    let s = cpu::pixel_spectrum(&fine, x, y);
    let f64s = |v: [f32; 3]| v.map(|c| c as f64);
    let reference = f64s(cpu::render_pixels(&fine, &[[x, y]])[0]);
    let quadrature = f64s(cpu::render_pixels(p, &[[x, y]])[0]);
    let white = space.xyz_from_rgb([1.0; 3]);
    let xyz = space.xyz_from_rgb(reference);
    let lab = |rgb: [f64; 3]| Lab::from_xyz(space.xyz_from_rgb(rgb), white);
    Ok(Probe {
        at: [x, y],
        wavelengths_nm: s.wavelengths_nm,
        radiance: s.radiance,
        nodes_nm: p.wavelengths_nm.clone(),
        xyz: [xyz.x(), xyz.y(), xyz.z()],
        xy: xyz.xy(),
        lab: lab(reference).0,
        rgb_linear: reference,
        srgb8: reference.map(|v| (srgb_encode(v.clamp(0.0, 1.0)) * 255.0).round() as u8),
        rgb_quadrature: quadrature,
        error_de2000: delta_e_2000(lab(quadrature), lab(reference)),
        view_angle_deg: s.view_angle_deg,
        film_reflectance: s.film_reflectance,
    })
}
