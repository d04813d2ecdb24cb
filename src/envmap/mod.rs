//! Environment maps: layouts and directions, EXR and HDR I/O, sun detection, and the conversion
//! of RGB maps to spectral ones.

pub mod basis_k;
pub mod block;
pub mod carriers;
pub mod convert;
pub mod engine;
pub mod exrio;
pub mod heatmap;
pub mod input;
pub mod layout;
pub mod light;
pub mod metric;
pub mod overlay;
pub mod own_basis;
pub mod plan;
pub mod planes;
pub mod roundtrip;
pub mod roundtrip_stats;
pub mod scene;
pub mod sun;
pub mod write;
pub mod zip;

/// A linear RGB image in memory, row-major from the top-left pixel, f32 per channel.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
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
    pub fn get(&self, x: usize, y: usize) -> [f32; 3] {
        self.pixels[y * self.width + x]
    }
    pub fn set(&mut self, x: usize, y: usize, rgb: [f32; 3]) {
        self.pixels[y * self.width + x] = rgb;
    }
}
