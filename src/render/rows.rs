//! Which objects a pixel row can hit: the renderers test only those, not every object of the
//! scene, so that a frame's cost is its wavelengths' rather than its objects' (the chart's 80
//! objects cost as much per pixel as 13 wavelengths when each pixel tested them all).
//!
//! The camera looks down −Z with an orthographic view, so a row of pixels is a line `y = py` on
//! the image plane; an object can be hit on it only where its extent in y reaches it (a
//! sphere's or cylinder's radius, a quad's half height). The index lists, per row, those
//! objects in scene order (the nearest-hit rule is the same whatever the order), one pixel of
//! margin either side so that the GPU's f32 and the CPU's f64 agree on every candidate.
//!
//! Layout (one `u32` array, the GPU's binding 8): `height + 1` offsets into the same array,
//! then the object indices; row `y`'s objects are `index[index[y]..index[y + 1]]`.

use super::prepare::{GpuObject, Params, QUAD};

/// The row index of `objects` for the frame `params` (see the module docs).
pub fn index(objects: &[GpuObject], params: &Params) -> Vec<u32> {
    let h = params.height as usize;
    let pixel = params.view[2] as f64;
    let mut out: Vec<u32> = vec![0; h + 1];
    for y in 0..h {
        out[y] = out.len() as u32;
        let py = row_y(params, y);
        for (k, o) in objects.iter().enumerate() {
            let reach = if o.kind == QUAD { o.p1[1] } else { o.p0[3] } as f64;
            if (py - o.p0[1] as f64).abs() <= reach + pixel {
                out.push(k as u32);
            }
        }
    }
    out[h] = out.len() as u32;
    out
}

/// The objects row `y` can hit.
pub fn row(index: &[u32], y: usize) -> &[u32] {
    &index[index[y] as usize..index[y + 1] as usize]
}

/// World y on the image plane of row `y`'s pixel centres (cpu.rs: `pixel_position`).
fn row_y(params: &Params, y: usize) -> f64 {
    params.view[1] as f64 - (y as f64 + 0.5 - 0.5 * params.height as f64) * params.view[2] as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::Quadrature;
    use crate::render::cpu;
    use crate::render::prepare::Prepared;
    use crate::render::Preset;

    #[test]
    fn every_pixel_hits_what_it_hit_testing_every_object() {
        let q = Quadrature::meyer(crate::colorimetry::Observer::Cie1931).unwrap();
        for preset in Preset::ALL {
            let (w, h) = preset.default_size();
            let scene = preset.scene(w / 4, h / 4, "D65", None).unwrap();
            let p =
                Prepared::with_quadrature(&scene, &q, crate::colorimetry::RgbSpace::SRGB).unwrap();
            let index = index(&p.objects, &p.params);
            let all: Vec<u32> = (0..p.objects.len() as u32).collect();
            let (mut tested, mut hits) = (0, 0);
            for y in 0..p.params.height as usize {
                for x in 0..p.params.width as usize {
                    let [px, py] = cpu::pixel_position(&p, x, y);
                    let culled = cpu::hit(&p.objects, row(&index, y), px, py);
                    assert_eq!(
                        culled,
                        cpu::hit(&p.objects, &all, px, py),
                        "{preset:?} {x} {y}"
                    );
                    hits += culled.is_some() as usize;
                }
                tested += row(&index, y).len();
            }
            assert!(hits > 0, "{preset:?}");
            // The index is worth having: the chart's rows see a fraction of its objects.
            if preset == Preset::Chart {
                let per_row = tested as f64 / p.params.height as f64;
                assert!(
                    per_row < 0.4 * p.objects.len() as f64,
                    "{per_row} of {}",
                    p.objects.len()
                );
            }
        }
    }
}
