//! Rendered images: linear RGB in memory, PNG (sRGB) and OpenEXR (linear) output, and the
//! CIEDE2000 comparison of two renders.

use crate::colorimetry::{delta_e_2000, srgb_encode, Lab, RgbSpace};
use crate::error::{Error, Result};
use std::path::Path;

/// A linear RGB image, row-major from the top-left pixel.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width * height` linear RGB values, row-major from the top-left pixel.
    pub pixels: Vec<[f32; 3]>,
}

impl Image {
    /// The linear RGB of pixel (x, y), y down from the top row.
    pub fn get(&self, x: usize, y: usize) -> [f32; 3] {
        self.pixels[y * self.width + x]
    }

    /// Writes an 8-bit sRGB PNG: linear values times 2^`exposure_ev`, clipped to [0, 1], encoded.
    pub fn write_png(&self, path: &Path, exposure_ev: f64) -> Result<()> {
        let k = exposure_ev.exp2();
        let mut bytes = Vec::with_capacity(self.pixels.len() * 3);
        for p in &self.pixels {
            for &v in p {
                let v = if v.is_finite() { v as f64 * k } else { 0.0 };
                bytes.push((srgb_encode(v.clamp(0.0, 1.0)) * 255.0).round() as u8);
            }
        }
        let img = ::image::RgbImage::from_raw(self.width as u32, self.height as u32, bytes)
            .ok_or_else(|| Error::invalid("image buffer does not match its size"))?;
        let tmp = crate::io::temp_path_for(path)?;
        img.save_with_format(&tmp, ::image::ImageFormat::Png)
            .map_err(|e| {
                crate::io::discard_temp(&tmp);
                Error::invalid(format!("{}: writing PNG: {e}", path.display()))
            })?;
        crate::io::rename_into_place(&tmp, path)
    }

    /// Writes a linear float OpenEXR (R, G, B), values times 2^`exposure_ev`.
    pub fn write_exr(&self, path: &Path, exposure_ev: f64) -> Result<()> {
        let k = exposure_ev.exp2() as f32;
        let tmp = crate::io::temp_path_for(path)?;
        exr::prelude::write_rgb_file(&tmp, self.width, self.height, |x, y| {
            let p = self.get(x, y);
            (p[0] * k, p[1] * k, p[2] * k)
        })
        .map_err(|e| {
            crate::io::discard_temp(&tmp);
            Error::invalid(format!("{}: writing OpenEXR: {e}", path.display()))
        })?;
        crate::io::rename_into_place(&tmp, path)
    }

    /// Writes PNG or EXR, chosen by the extension (`.png`, `.exr`).
    pub fn write(&self, path: &Path, exposure_ev: f64) -> Result<()> {
        match path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .as_deref()
        {
            Some("png") => self.write_png(path, exposure_ev),
            Some("exr") => self.write_exr(path, exposure_ev),
            _ => Err(Error::invalid(format!(
                "{}: the output must end in .png (sRGB) or .exr (linear)",
                path.display()
            ))),
        }
    }
}

/// CIEDE2000 between two renders of the same size.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Comparison {
    /// Mean CIEDE2000 over the pixels where both images are finite (0 where none are).
    #[serde(rename = "mean_dE2000")]
    pub mean: f64,
    /// Nearest-rank 99th percentile.
    #[serde(rename = "p99_dE2000")]
    pub p99: f64,
    /// Largest CIEDE2000 over the same pixels (0 where there are none).
    #[serde(rename = "max_dE2000")]
    pub max: f64,
    /// Pixel (x, y) of the largest difference.
    pub max_at: [usize; 2],
    /// Pixels where either image is not finite.
    pub non_finite: usize,
}

/// Per-pixel CIEDE2000 between linear RGB images in `space`, CIELAB relative to the space's
/// white at RGB (1, 1, 1) (values above 1 are kept: L* > 100 for highlights).
pub fn compare(a: &Image, b: &Image, space: &RgbSpace) -> Result<Comparison> {
    if a.width != b.width || a.height != b.height {
        return Err(Error::invalid(format!(
            "images of different sizes: {}x{} and {}x{}",
            a.width, a.height, b.width, b.height
        )));
    }
    let white = space.xyz_from_rgb([1.0, 1.0, 1.0]);
    let lab = |p: [f32; 3]| {
        Lab::from_xyz(
            space.xyz_from_rgb([p[0] as f64, p[1] as f64, p[2] as f64]),
            white,
        )
    };
    let mut des = Vec::with_capacity(a.pixels.len());
    let mut non_finite = 0;
    let (mut max, mut max_at) = (0.0f64, [0, 0]);
    for (i, (p, q)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        if !p.iter().chain(q.iter()).all(|v| v.is_finite()) {
            non_finite += 1;
            continue;
        }
        let de = delta_e_2000(lab(*p), lab(*q));
        if de > max {
            max = de;
            max_at = [i % a.width, i / a.width];
        }
        des.push(de);
    }
    let mean = if des.is_empty() {
        0.0
    } else {
        des.iter().sum::<f64>() / des.len() as f64
    };
    des.sort_by(f64::total_cmp);
    let p99 = if des.is_empty() {
        0.0
    } else {
        des[((0.99 * des.len() as f64).ceil() as usize).clamp(1, des.len()) - 1]
    };
    Ok(Comparison {
        mean,
        p99,
        max,
        max_at,
        non_finite,
    })
}
