//! Environment maps, one folder per stage of their life:
//! - [`files`]: the EXR and HDR files (RGB in; spectral OpenEXR out and back in);
//! - [`layout`]: the map's geometry (lat-long, cube, cross, strip layouts; directions, solid
//!   angles, resampling);
//! - [`scene`]: what a map holds (its lights: sun, sky, windows, lamps; the reflectors; the main
//!   light and the white premise), drawn over the map;
//! - [`convert`]: RGB -> spectral, as read -> analyse -> plan -> write, and the basis form;
//! - [`roundtrip`]: a spectral map integrated back to RGB, its statistics and heat maps.

pub mod convert;
pub mod files;
pub mod layout;
pub mod roundtrip;
pub mod scene;

/// A linear RGB image in memory, row-major from the top-left pixel, f32 per channel.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Linear RGB per pixel, row-major from the top-left.
    pub pixels: Vec<[f32; 3]>,
}

impl RgbImage {
    /// A black image.
    pub fn new(width: usize, height: usize) -> RgbImage {
        RgbImage {
            width,
            height,
            pixels: vec![[0.0; 3]; width * height],
        }
    }
    /// The RGB of pixel (x, y).
    pub fn get(&self, x: usize, y: usize) -> [f32; 3] {
        self.pixels[y * self.width + x]
    }
    /// Sets pixel (x, y) to `rgb`.
    pub fn set(&mut self, x: usize, y: usize, rgb: [f32; 3]) {
        self.pixels[y * self.width + x] = rgb;
    }
}
