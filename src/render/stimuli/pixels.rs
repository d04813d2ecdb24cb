//! A chosen quadrature against the 1 nm render on the image's own pixels: the last check of
//! `render --tolerance`. The stimuli and the check on every texel sample what the image can
//! show, path by path; a pixel sums its paths, each lit by its own texel (a glossy sphere's
//! colour by the diffuse map at its normal, its highlight by the specular map at the
//! reflection), and the renderer filters and interpolates between texels. Neither is a
//! stimulus, so the image itself is rendered on the quadrature and at 1 nm (Simpson) and
//! compared, on a lattice of at most [`MAX_PIXELS`] of its pixels.

use crate::colorimetry::{Observer, RgbSpace};
use crate::error::Result;
use crate::quadrature::choose::ImageCheck;
use crate::quadrature::Quadrature;
use crate::render::{compare, Image, Scene};
use crate::spectrum::{Rule, WavelengthGrid};

/// The most pixels checked: an image with more is checked on every `stride`-th row and column.
pub(crate) const MAX_PIXELS: usize = 128 * 128;

/// The image's pixels checked, and their 1 nm render (made once, for every quadrature checked)
/// as a one-row image.
pub(crate) struct Reference {
    at: Vec<[usize; 2]>,
    stride: usize,
    one_nm: Image,
    space: RgbSpace,
}

/// The blocks of a `width x height` image at `stride`.
fn blocks(width: usize, height: usize, stride: usize) -> usize {
    width.div_ceil(stride) * height.div_ceil(stride)
}

/// The smallest stride whose lattice of a `width x height` image has at most [`MAX_PIXELS`].
fn stride(width: usize, height: usize) -> usize {
    (1..)
        .find(|&s| blocks(width, height, s) <= MAX_PIXELS)
        .expect("a stride")
}

/// `pixels` as an image of one row.
fn row(pixels: Vec<[f32; 3]>) -> Image {
    Image {
        width: pixels.len(),
        height: 1,
        pixels,
    }
}

/// The centre of each `stride x stride` block of a `width x height` image (clamped to it),
/// row by row.
fn lattice(width: usize, height: usize, stride: usize) -> Vec<[usize; 2]> {
    let centre = |i: usize, n: usize| (i * stride + stride / 2).min(n - 1);
    (0..height.div_ceil(stride))
        .flat_map(|j| {
            (0..width.div_ceil(stride)).map(move |i| [centre(i, width), centre(j, height)])
        })
        .collect()
}

/// The pixels checked of a `width x height` image.
pub(crate) fn lattice_len(width: usize, height: usize) -> usize {
    blocks(width, height, stride(width, height))
}

impl Reference {
    /// `scene`'s 1 nm render in `space` on its lattice, for `observer`.
    pub(crate) fn new(scene: &Scene, observer: Observer, space: RgbSpace) -> Result<Reference> {
        let stride = stride(scene.width, scene.height);
        let at = lattice(scene.width, scene.height, stride);
        let grid = WavelengthGrid::new(380.0, 780.0, 1.0)?;
        let reference = Quadrature::uniform(grid, Rule::Simpson, observer)?;
        let one_nm = row(scene.render_cpu_pixels(&reference, space, &at)?);
        Ok(Reference {
            at,
            stride,
            one_nm,
            space,
        })
    }

    /// `q`'s render of `scene` against the 1 nm one, on the lattice.
    pub(crate) fn check(&self, scene: &Scene, q: &Quadrature) -> Result<ImageCheck> {
        let on_q = row(scene.render_cpu_pixels(q, self.space, &self.at)?);
        let c = compare(&on_q, &self.one_nm, &self.space)?;
        Ok(ImageCheck {
            max_de2000: c.max,
            mean_de2000: c.mean,
            max_at: self.at[c.max_at[0]],
            pixels: self.at.len(),
            stride: self.stride,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::Observer;
    use crate::render::Preset;

    #[test]
    fn the_lattice_covers_the_image_within_the_pixel_budget() {
        for (w, h) in [
            (32, 32),
            (96, 64),
            (128, 128),
            (129, 128),
            (512, 512),
            (4096, 2048),
        ] {
            let s = stride(w, h);
            let at = lattice(w, h, s);
            assert!(at.len() <= MAX_PIXELS, "{w}x{h}: {}", at.len());
            assert!(
                s == 1 || lattice(w, h, s - 1).len() > MAX_PIXELS,
                "{w}x{h}: stride {s}"
            );
            assert!(at.iter().all(|&[x, y]| x < w && y < h));
            // Every pixel lies within half a stride of one checked.
            let near = |x: usize, y: usize| {
                at.iter()
                    .any(|&[a, b]| a.abs_diff(x) <= s / 2 && b.abs_diff(y) <= s / 2)
            };
            assert!(
                near(0, 0) && near(w - 1, h - 1) && near(w / 2, h / 3),
                "{w}x{h}"
            );
        }
        assert_eq!(stride(128, 128), 1);
        assert_eq!(stride(512, 512), 4);
    }

    /// On an image within the budget the check is the whole image's comparison: the largest
    /// and the mean difference, and where, as `compare` finds them on the two full renders.
    #[test]
    fn on_a_small_image_the_check_is_the_full_renders_comparison() {
        let scene = Preset::Chart.scene(24, 16, "D65", None).unwrap();
        let space = RgbSpace::SRGB;
        let q = Quadrature::new(
            crate::quadrature::Kind::Scene,
            Observer::Cie1931,
            vec![445.0, 540.0, 589.0],
            vec![[0.3, 0.1, 1.7], [0.2, 1.0, 0.1], [1.0, 0.4, 0.0]],
        )
        .unwrap();
        let r = Reference::new(&scene, Observer::Cie1931, space).unwrap();
        assert_eq!((r.at.len(), r.stride), (24 * 16, 1));
        let got = r.check(&scene, &q).unwrap();
        let grid = WavelengthGrid::new(380.0, 780.0, 1.0).unwrap();
        let one_nm = Quadrature::uniform(grid, Rule::Simpson, Observer::Cie1931).unwrap();
        let full = compare(
            &scene.render_cpu_with(&q, space).unwrap(),
            &scene.render_cpu_with(&one_nm, space).unwrap(),
            &space,
        )
        .unwrap();
        assert!(
            full.max > 1.0,
            "three nodes should err visibly: {}",
            full.max
        );
        assert_eq!(got.max_at, full.max_at);
        assert!((got.max_de2000 - full.max).abs() < 1e-9 * full.max);
        assert!((got.mean_de2000 - full.mean).abs() < 1e-9 * full.mean);
    }
}
