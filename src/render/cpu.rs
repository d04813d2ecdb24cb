//! The CPU reference renderer: the same model as `gpu.wgsl`, in f64, rows in parallel (rayon),
//! films by the thin-film module itself ([`crate::thinfilm::Film`]).

use super::env;
use super::prepare::{
    CpuFilm, GpuLighting, GpuObject, Prepared, CYLINDER_X, HAS_DIFFUSE, HAS_FILM, HIDE_BACKGROUND,
    QUAD, SPHERE, TRANSPARENT,
};
use super::Image;
use crate::thinfilm::{Film, Incidence, Polarization};
use rayon::prelude::*;
use std::f64::consts::{FRAC_1_PI, PI};

/// Renders the prepared scene.
///
/// ```
/// use specmap::render::{cpu, prepare::Prepared, Preset, Spectral};
///
/// let scene = Preset::Chart.scene(48, 32, "D65", None)?;
/// let image = cpu::render(&Prepared::new(&scene, &Spectral::step(10.0)?)?);
/// let [r, g, b] = image.get(24, 16);
/// assert!(r.is_finite() && g.is_finite() && b.is_finite());
/// # Ok::<(), specmap::error::Error>(())
/// ```
pub fn render(p: &Prepared) -> Image {
    let (w, h) = (p.params.width as usize, p.params.height as usize);
    let mut pixels = vec![[0f32; 3]; w * h];
    let constant = constant_maps(p);
    pixels.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let mut scratch = Scratch::default();
        for (x, out) in row.iter_mut().enumerate() {
            *out = pixel(p, &constant, x, y, &mut scratch);
        }
    });
    Image {
        width: w,
        height: h,
        pixels,
    }
}

/// Renders only the pixels `at` ((x, y) each), in order, as [`render`] renders them.
pub fn render_pixels(p: &Prepared, at: &[[usize; 2]]) -> Vec<[f32; 3]> {
    let constant = constant_maps(p);
    at.par_iter()
        .map_init(Scratch::default, |scratch, &[x, y]| {
            pixel(p, &constant, x, y, scratch)
        })
        .collect()
}

/// The world position on the image plane of pixel (x, y)'s centre.
pub fn pixel_position(p: &Prepared, x: usize, y: usize) -> [f64; 2] {
    let v = p.params.view.map(|c| c as f64);
    let (w, h) = (p.params.width as f64, p.params.height as f64);
    [
        v[0] + (x as f64 + 0.5 - 0.5 * w) * v[2],
        v[1] - (y as f64 + 0.5 - 0.5 * h) * v[2],
    ]
}

/// The nearest hit through pixel (x, y)'s centre, among the objects its row and band can hit.
pub fn hit_pixel(p: &Prepared, x: usize, y: usize) -> Option<(usize, [f64; 3])> {
    let [px, py] = pixel_position(p, x, y);
    hit(&p.objects, candidates(p, x, y), px, py)
}

/// The objects pixel (x, y) can hit ([`super::candidates`]).
fn candidates(p: &Prepared, x: usize, y: usize) -> &[u32] {
    super::candidates::candidates(&p.rows, p.params.width as usize, x, y)
}

/// The nearest hit along the ray down −Z through (px, py) among the objects `candidates`
/// (indices into `objects`, in order): object index, unit normal.
pub fn hit(
    objects: &[GpuObject],
    candidates: &[u32],
    px: f64,
    py: f64,
) -> Option<(usize, [f64; 3])> {
    let mut best: Option<(usize, [f64; 3])> = None;
    let mut best_z = f64::NEG_INFINITY;
    for &k in candidates {
        let (i, o) = (k as usize, &objects[k as usize]);
        let p0 = o.p0.map(|v| v as f64);
        let p1 = o.p1.map(|v| v as f64);
        let found = match o.kind {
            SPHERE => {
                let (dx, dy, r) = (px - p0[0], py - p0[1], p0[3]);
                let q = r * r - dx * dx - dy * dy;
                (q >= 0.0).then(|| {
                    let s = q.sqrt();
                    let k = 1.0 / r;
                    (p0[2] + s, [dx * k, dy * k, s * k])
                })
            }
            CYLINDER_X => {
                let (dy, r) = (py - p0[1], p0[3]);
                let q = r * r - dy * dy;
                ((px - p0[0]).abs() <= p1[0] && q >= 0.0).then(|| {
                    let s = q.sqrt();
                    let k = 1.0 / r;
                    (p0[2] + s, [0.0, dy * k, s * k])
                })
            }
            QUAD => ((px - p0[0]).abs() <= p1[0] && (py - p0[1]).abs() <= p1[1])
                .then_some((p0[2], [0.0, 0.0, 1.0])),
            _ => None,
        };
        if let Some((z, n)) = found {
            if z > best_z {
                best_z = z;
                best = Some((i, n));
            }
        }
    }
    // Each normal is unit already: (dx, dy, s) / r with s^2 = r^2 - dx^2 - dy^2, to rounding.
    best
}

/// A pixel's coefficients, kept between the pixels of a row so that none allocates: per map
/// sampled, the nonzero coefficients as (index of the lighting's spectrum, value), and the
/// bilinear lookup they are taken from.
#[derive(Default)]
struct Scratch {
    diffuse: Terms,
    specular: Terms,
    behind: Terms,
    lookup: Vec<f64>,
}

/// Nonzero coefficients of a map, as (index of the lighting's spectrum, value).
type Terms = Vec<(usize, f64)>;

/// Per map, its nonzero coefficients if it is one texel (every uniform lighting's maps are):
/// the same in every direction, so taken once per frame instead of once per pixel.
fn constant_maps(p: &Prepared) -> Vec<Option<Terms>> {
    (0..p.maps.len())
        .map(|m| {
            let [_, w, h, _] = p.maps[m];
            let mut terms = Vec::new();
            (w * h == 1).then(|| {
                sample_terms(p, m as u32, [0.0, 0.0, 1.0], &mut Vec::new(), &mut terms);
                terms
            })
        })
        .collect()
}

/// The nonzero coefficients of `map` in direction `dir`: `constant`'s if it has them (the
/// direction is then not computed), else looked up into `out`. A uniform lighting's maps hold
/// one nonzero coefficient, so this skips the three zero terms of every wavelength's expansion.
fn map_sample<'a>(
    p: &Prepared,
    constant: &'a [Option<Terms>],
    map: u32,
    dir: impl FnOnce() -> [f64; 3],
    lookup: &mut Vec<f64>,
    out: &'a mut Terms,
) -> &'a [(usize, f64)] {
    if let Some(terms) = &constant[map as usize] {
        return terms;
    }
    sample_terms(p, map, dir(), lookup, out);
    out
}

/// The nonzero coefficients of `map` in direction `dir` into `out`, by way of `lookup`.
fn sample_terms(p: &Prepared, map: u32, dir: [f64; 3], lookup: &mut Vec<f64>, out: &mut Terms) {
    let [off, w, h, groups] = p.maps[map as usize];
    let off = off as usize;
    let (w, h, g) = (w as usize, h as usize, groups as usize);
    let o = &p.params.orientation;
    let dir = [0, 1, 2]
        .map(|r| o[r][0] as f64 * dir[0] + o[r][1] as f64 * dir[1] + o[r][2] as f64 * dir[2]);
    env::sample_into(&p.texels[off..off + w * h * g], w, h, g, dir, lookup);
    out.clear();
    out.extend(
        lookup
            .iter()
            .copied()
            .enumerate()
            .filter(|(_, c)| *c != 0.0),
    );
}

/// The direction the background is seen in at pixel (x, y): a pinhole at the image centre
/// with the vertical field of view of `params.view.w` (its half angle's tangent), looking
/// down −Z; straight down −Z when that is 0.
pub fn background_direction(p: &Prepared, x: usize, y: usize) -> [f64; 3] {
    let (w, h) = (p.params.width as usize, p.params.height as usize);
    pinhole_direction(p.params.view[3] as f64, w, h, x, y)
}

/// [`background_direction`] for a `width x height` image whose vertical half field of view
/// has tangent `t` (f32, as the renderers are handed it).
pub fn pinhole_direction(t: f64, width: usize, height: usize, x: usize, y: usize) -> [f64; 3] {
    let (w, h) = (width as f64, height as f64);
    let u = (x as f64 + 0.5 - 0.5 * w) / (0.5 * h) * t;
    let v = -(y as f64 + 0.5 - 0.5 * h) / (0.5 * h) * t;
    let n = (u * u + v * v + 1.0).sqrt();
    let k = 1.0 / n;
    [u * k, v * k, -k]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `max(c, 0)^n`, 0 where `c <= 0` (also for n = 0).
pub fn lobe(c: f64, n: f64) -> f64 {
    if c > 0.0 {
        c.powf(n)
    } else {
        0.0
    }
}

/// Film R and T at `cos_v` and wavelength index `i`, thicknesses scaled by `scale`.
fn film_rt(f: &CpuFilm, i: usize, cos_v: f64, scale: Option<f64>) -> (f64, f64) {
    let deg = cos_v.clamp(0.0, 1.0).acos().to_degrees().clamp(0.0, 90.0);
    let inc = Incidence::degrees(deg).unwrap_or(Incidence::NORMAL);
    let rt = match scale {
        None => f.films[i].rt(&inc, Polarization::Unpolarized),
        Some(s) => {
            let (a, layers, sub) = &f.indices[i];
            let l: Vec<_> = layers
                .iter()
                .zip(&f.thickness_nm)
                .map(|(n, d)| (*n, d * s))
                .collect();
            match Film::<f64>::new(f.films[i].wavelength_nm(), *a, &l, *sub) {
                Ok(film) => film.rt(&inc, Polarization::Unpolarized),
                Err(_) => return (0.0, 0.0),
            }
        }
    };
    (rt.r, rt.t)
}

fn pixel(
    p: &Prepared,
    constant: &[Option<Terms>],
    x: usize,
    y: usize,
    scratch: &mut Scratch,
) -> [f32; 3] {
    let n_wl = p.params.n_wl as usize;
    let mut xyz = [0.0f64; 3];
    let cmf = p.params.cmf_offset as usize;
    radiance(p, constant, x, y, scratch, |i, l| {
        for (c, v) in xyz.iter_mut().enumerate() {
            *v += p.spectra[cmf + c * n_wl + i] as f64 * l;
        }
    });
    let rgb = p.params.rgb;
    let row = |r: usize| {
        (rgb[r][0] as f64 * xyz[0] + rgb[r][1] as f64 * xyz[1] + rgb[r][2] as f64 * xyz[2]) as f32
    };
    [row(0), row(1), row(2)]
}

/// What one pixel shows, wavelength by wavelength: [`pixel_spectrum`].
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PixelSpectrum {
    /// The quadrature's nodes.
    pub wavelengths_nm: Vec<f64>,
    /// The radiance reaching the camera at each node.
    pub radiance: Vec<f64>,
    /// The object hit (its index in the scene), if any.
    pub object: Option<usize>,
    /// The angle between the view and the surface normal, where an object is hit.
    pub view_angle_deg: Option<f64>,
    /// The film's reflectance at that angle (unpolarised, its thickness at that point), where
    /// the object has a film.
    pub film_reflectance: Option<Vec<f64>>,
}

/// Pixel (x, y)'s spectral radiance at the prepared quadrature's nodes: the terms [`render`]
/// weights by the colour-matching functions, and the film's reflectance there.
pub fn pixel_spectrum(p: &Prepared, x: usize, y: usize) -> PixelSpectrum {
    let n_wl = p.params.n_wl as usize;
    let mut radiance_nm = vec![0.0; n_wl];
    radiance(
        p,
        &constant_maps(p),
        x,
        y,
        &mut Scratch::default(),
        |i, l| radiance_nm[i] += l,
    );
    let hit = hit_pixel(p, x, y);
    let film = hit.and_then(|(oi, n)| {
        let o = &p.objects[oi];
        let f = p.films[o.material as usize].as_ref()?;
        let cos_v = n[2].clamp(0.0, 1.0);
        let scale = ramp_scale(o, pixel_position(p, x, y)[0]);
        Some((0..n_wl).map(|i| film_rt(f, i, cos_v, scale).0).collect())
    });
    PixelSpectrum {
        wavelengths_nm: p.wavelengths_nm.clone(),
        radiance: radiance_nm,
        object: hit.map(|(oi, _)| oi),
        view_angle_deg: hit.map(|(_, n)| n[2].clamp(-1.0, 1.0).acos().to_degrees()),
        film_reflectance: film,
    }
}

/// The film's thickness scale at world x on object `o`'s ramp (None without one).
fn ramp_scale(o: &GpuObject, px: f64) -> Option<f64> {
    (o.flags[0] != 0).then(|| {
        let r = o.ramp.map(|v| v as f64);
        let t = if r[1] == r[0] {
            0.0
        } else {
            ((px - r[0]) / (r[1] - r[0])).clamp(0.0, 1.0)
        };
        r[2] + (r[3] - r[2]) * t
    })
}

/// The radiance of pixel (x, y) at each node `i`, handed to `add(i, radiance)`: the
/// environment where the ray misses (nothing where the background is hidden), else what the
/// surface it hits sends to the camera.
fn radiance(
    p: &Prepared,
    constant: &[Option<Terms>],
    x: usize,
    y: usize,
    scratch: &mut Scratch,
    mut add: impl FnMut(usize, f64),
) {
    let [px, py] = pixel_position(p, x, y);
    match hit(&p.objects, candidates(p, x, y), px, py) {
        None if p.params.flags & HIDE_BACKGROUND != 0 => {}
        None => background(p, constant, [x, y], scratch, &mut add),
        Some((oi, n)) => {
            let at = Hit {
                oi,
                n,
                px,
                pixel: [x, y],
            };
            let shading = Shading::of(p, &p.objects[oi]);
            let lit = hit_lighting(p, constant, &at, &shading, scratch);
            surface(p, &at, &shading, &lit, &mut add);
        }
    }
}

/// Where a pixel's ray hit: the object, its unit normal, the world x of the pixel's centre and
/// the pixel.
struct Hit {
    oi: usize,
    n: [f64; 3],
    px: f64,
    pixel: [usize; 2],
}

/// How the surface hit reflects: its coefficients, whether it is transparent, its film, whether
/// it reflects specularly at all, and where its diffuse reflectance is (None: black).
struct Shading<'a> {
    kd: f64,
    ks: f64,
    shininess: f64,
    transparent: bool,
    film: Option<&'a CpuFilm>,
    specular: bool,
    diffuse: Option<u32>,
}

impl<'a> Shading<'a> {
    /// The shading of object `o`'s material.
    fn of(p: &'a Prepared, o: &GpuObject) -> Shading<'a> {
        let m = &p.materials[o.material as usize];
        let [kd, ks, shininess, _] = m.coef.map(|v| v as f64);
        let film = (m.flags & HAS_FILM != 0)
            .then(|| p.films[o.material as usize].as_ref())
            .flatten();
        Shading {
            kd,
            ks,
            shininess,
            transparent: m.flags & TRANSPARENT != 0,
            film,
            // A matte surface (no film, ks = 0) reflects nothing specularly: its specular
            // lighting is not looked up (most of the chart: the patches and the backdrop).
            specular: film.is_some() || ks != 0.0,
            diffuse: (m.flags & HAS_DIFFUSE != 0).then_some(m.diffuse_offset),
        }
    }
}

/// The light reaching a hit: the diffuse, specular and (transparent) behind coefficients of
/// its lighting's maps, and the sun's diffuse and specular factors (in units of its SPD).
struct Lit<'a> {
    diffuse: &'a [(usize, f64)],
    specular: &'a [(usize, f64)],
    behind: &'a [(usize, f64)],
    sun_diffuse: f64,
    sun_specular: f64,
}

/// Value `i` of the spectrum at offset `off` of the prepared spectra.
fn spectrum_at(p: &Prepared, off: u32, i: usize) -> f64 {
    p.spectra[off as usize + i] as f64
}

/// The coefficients `c` expanded with the lighting's spectra (from offset `off`) at node `i`.
fn expand(p: &Prepared, c: &[(usize, f64)], off: u32, i: usize) -> f64 {
    let n_wl = p.params.n_wl as usize;
    c.iter()
        .map(|&(j, c)| c * spectrum_at(p, off, j * n_wl + i))
        .sum()
}

/// The mirror direction of the view ray (+Z towards the camera) about the normal `n`.
fn mirror(n: [f64; 3]) -> [f64; 3] {
    [
        2.0 * n[2] * n[0],
        2.0 * n[2] * n[1],
        2.0 * n[2] * n[2] - 1.0,
    ]
}

/// The environment seen through pixel `[x, y]`, at each node.
fn background(
    p: &Prepared,
    constant: &[Option<Terms>],
    [x, y]: [usize; 2],
    scratch: &mut Scratch,
    add: &mut impl FnMut(usize, f64),
) {
    let Scratch { behind, lookup, .. } = scratch;
    let lt = &p.lightings[p.params.background as usize];
    let d = || background_direction(p, x, y);
    let ct = map_sample(p, constant, lt.background_map, d, lookup, behind);
    for i in 0..p.params.n_wl as usize {
        add(i, expand(p, ct, lt.spectra, i));
    }
}

/// The light reaching the hit `at` from its lighting: the maps looked up where the surface
/// needs them (specular: only if it reflects so; behind: only if transparent), and the sun.
fn hit_lighting<'a>(
    p: &Prepared,
    constant: &'a [Option<Terms>],
    at: &Hit,
    s: &Shading,
    scratch: &'a mut Scratch,
) -> Lit<'a> {
    let Scratch {
        diffuse,
        specular,
        behind,
        lookup,
    } = scratch;
    let o = &p.objects[at.oi];
    let lt = &p.lightings[o.lighting as usize];
    let n = at.n;
    let d = || background_direction(p, at.pixel[0], at.pixel[1]);
    let diffuse = map_sample(p, constant, lt.diffuse_map, || n, lookup, diffuse);
    let specular = if s.specular {
        map_sample(p, constant, o.spec_map, || mirror(n), lookup, specular)
    } else {
        &[]
    };
    let behind = if s.transparent {
        map_sample(p, constant, lt.background_map, d, lookup, behind)
    } else {
        &[]
    };
    let (sun_diffuse, sun_specular) = sun_factors(lt, n, s);
    Lit {
        diffuse,
        specular,
        behind,
        sun_diffuse,
        sun_specular,
    }
}

/// The sun's diffuse factor `E max(N.l, 0) / pi` and specular one
/// `E (n + 1) / (2 pi) max(R_v.l, 0)^n` (0 without a specular reflection), 0 without a sun.
fn sun_factors(lt: &GpuLighting, n: [f64; 3], s: &Shading) -> (f64, f64) {
    if lt.has_sun == 0 {
        return (0.0, 0.0);
    }
    let sv = lt.sun.map(|v| v as f64);
    let l = [sv[0], sv[1], sv[2]];
    let s_lobe = if s.specular {
        sv[3] * (s.shininess + 1.0) / (2.0 * PI) * lobe(dot(mirror(n), l), s.shininess)
    } else {
        0.0
    };
    (sv[3] * dot(n, l).max(0.0) * FRAC_1_PI, s_lobe)
}

/// What the surface hit sends to the camera at each node (the module docs' model): a
/// transparent one its reflection and the environment behind through its film, an opaque one
/// its diffuse reflection under its film and its specular one.
fn surface(p: &Prepared, at: &Hit, s: &Shading, lit: &Lit, add: &mut impl FnMut(usize, f64)) {
    let o = &p.objects[at.oi];
    let lt = &p.lightings[o.lighting as usize];
    let cos_v = at.n[2].clamp(0.0, 1.0);
    let scale = ramp_scale(o, at.px);
    let sun_spd = lt.layout[1];
    for i in 0..p.params.n_wl as usize {
        let e = spectrum_at(p, sun_spd, i);
        let ld = expand(p, lit.diffuse, lt.spectra, i) + lit.sun_diffuse * e;
        let ls = expand(p, lit.specular, lt.spectra, i) + lit.sun_specular * e;
        let (fr, ft) = match s.film {
            Some(f) => film_rt(f, i, cos_v, scale),
            None => (s.ks, 1.0),
        };
        let l = if s.transparent {
            fr * ls + ft * expand(p, lit.behind, lt.spectra, i)
        } else {
            let rd = match s.diffuse {
                Some(off) => spectrum_at(p, off, i),
                None => 0.0,
            };
            s.kd * rd * ft * ld + fr * ls
        };
        add(i, l);
    }
}
