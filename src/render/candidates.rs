//! Which objects a pixel can hit: the renderers test only those, not every object of the
//! scene, so that a frame's cost is its wavelengths' rather than its objects' (the chart's 80
//! objects cost as much per pixel as 13 wavelengths when each pixel tested them all).
//!
//! The camera looks down −Z with an orthographic view, so a pixel row is a line `y = py` on the
//! image plane and a band of [`BAND`] pixels on it a segment; an object can be hit there only
//! where its extent reaches it (in y a sphere's or cylinder's radius, a quad's half height; in x
//! a sphere's radius, a cylinder's or quad's half width). The index lists, per row and band,
//! those objects in scene order (the nearest-hit rule is the same whatever the order), one pixel
//! of margin all round so that the GPU's f32 and the CPU's f64 agree on every candidate. At
//! 96x64 a chart pixel tests 2.5 of the 84 objects on average; by rows alone it tested 10.
//!
//! Layout (one `u32` array, the GPU's binding 8): `height * bands + 1` offsets into the same
//! array, then the object indices; the objects of row `y`, band `b` are
//! `index[index[t]..index[t + 1]]` with `t = y * bands + b` ([`bands`] of the width).

use super::gpu_layout::{GpuObject, Params, CYLINDER_X, QUAD, SPHERE};

/// Pixels per band (`BAND` in gpu.wgsl).
pub const BAND: usize = 8;

/// Bands across an image `width` pixels wide.
pub fn bands(width: usize) -> usize {
    width.div_ceil(BAND)
}

/// The index of `objects` for the frame `params` (see the module docs).
pub fn index(objects: &[GpuObject], params: &Params) -> Vec<u32> {
    let (w, h) = (params.width as usize, params.height as usize);
    let nb = bands(w);
    let pixel = params.view[2] as f64;
    // Per object, its centre and reach on the image plane, the margin included.
    let extents: Vec<([f64; 2], [f64; 2])> = objects
        .iter()
        .map(|o| {
            let [rx, ry] = reach(o);
            ([o.p0[0] as f64, o.p0[1] as f64], [rx + pixel, ry + pixel])
        })
        .collect();
    let mut out: Vec<u32> = vec![0; h * nb + 1];
    let mut in_row = Vec::new();
    for y in 0..h {
        let py = row_y(params, y);
        in_row.clear();
        in_row.extend((0..objects.len()).filter(|&k| {
            let ([_, cy], [_, ry]) = extents[k];
            (py - cy).abs() <= ry
        }));
        for b in 0..nb {
            out[y * nb + b] = out.len() as u32;
            let (x0, x1) = (
                column_x(params, b * BAND),
                column_x(params, ((b + 1) * BAND).min(w) - 1),
            );
            out.extend(
                in_row
                    .iter()
                    .filter(|&&k| {
                        let ([cx, _], [rx, _]) = extents[k];
                        cx + rx >= x0 && cx - rx <= x1
                    })
                    .map(|&k| k as u32),
            );
        }
    }
    out[h * nb] = out.len() as u32;
    out
}

/// How far from its centre an object reaches in x and y on the image plane (an unknown
/// kind everywhere, so that the index never hides what `hit` would find).
fn reach(o: &GpuObject) -> [f64; 2] {
    let (r, half) = (o.p0[3] as f64, [o.p1[0] as f64, o.p1[1] as f64]);
    match o.kind {
        SPHERE => [r, r],
        CYLINDER_X => [half[0], r],
        QUAD => half,
        _ => [f64::INFINITY, f64::INFINITY],
    }
}

/// The objects pixel (x, y) can hit, in an image `width` pixels wide.
pub fn candidates(index: &[u32], width: usize, x: usize, y: usize) -> &[u32] {
    let t = y * bands(width) + x / BAND;
    &index[index[t] as usize..index[t + 1] as usize]
}

/// World y on the image plane of row `y`'s pixel centres (cpu.rs: `pixel_position`).
fn row_y(params: &Params, y: usize) -> f64 {
    params.view[1] as f64 - (y as f64 + 0.5 - 0.5 * params.height as f64) * params.view[2] as f64
}

/// World x on the image plane of column `x`'s pixel centres (cpu.rs: `pixel_position`).
fn column_x(params: &Params, x: usize) -> f64 {
    params.view[0] as f64 + (x as f64 + 0.5 - 0.5 * params.width as f64) * params.view[2] as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::Quadrature;
    use crate::render::cpu;
    use crate::render::prepare::Prepared;
    use crate::render::Preset;

    #[test]
    fn the_shader_bands_as_this_module_does() {
        let line = format!("const BAND: u32 = {BAND}u;");
        assert!(
            crate::render::gpu::SHADER.contains(&line),
            "gpu.wgsl lacks {line:?}"
        );
    }

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
            let mut hits = 0;
            for y in 0..p.params.height as usize {
                for x in 0..p.params.width as usize {
                    let [px, py] = cpu::pixel_position(&p, x, y);
                    let here = candidates(&index, p.params.width as usize, x, y);
                    let culled = cpu::hit(&p.objects, here, px, py);
                    assert_eq!(
                        culled,
                        cpu::hit(&p.objects, &all, px, py),
                        "{preset:?} {x} {y}"
                    );
                    hits += culled.is_some() as usize;
                }
            }
            assert!(hits > 0, "{preset:?}");
        }
    }

    /// The index is worth having: at the bench's 96x64 a chart pixel tests 2.5 of the 84
    /// objects, against 10 for its row's (the union of the row's bands). Printed with
    /// `cargo test --lib candidates -- --nocapture`.
    #[test]
    fn a_chart_pixel_tests_a_few_objects() {
        let q = Quadrature::meyer(crate::colorimetry::Observer::Cie1931).unwrap();
        let scene = Preset::Chart.scene(96, 64, "D65", None).unwrap();
        let p = Prepared::with_quadrature(&scene, &q, crate::colorimetry::RgbSpace::SRGB).unwrap();
        let (w, h) = (p.params.width as usize, p.params.height as usize);
        let (mut banded, mut by_row) = (0, 0);
        for y in 0..h {
            let mut row = std::collections::BTreeSet::<u32>::new();
            for x in 0..w {
                let here = candidates(&p.rows, w, x, y);
                banded += here.len();
                row.extend(here);
            }
            by_row += row.len() * w;
        }
        let per_pixel = |n: usize| n as f64 / (w * h) as f64;
        let (banded, by_row) = (per_pixel(banded), per_pixel(by_row));
        println!(
            "chart {w}x{h}, {} objects: {banded:.2} per pixel, {by_row:.2} by row",
            p.objects.len()
        );
        assert!(
            banded < 3.0 && by_row > 3.0 * banded,
            "{banded} and {by_row}"
        );
    }
}
