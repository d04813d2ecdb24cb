//! A scene flattened for rendering: spectra at the quadrature's nodes (the weighted CMFs are
//! its weight triples), pre-filtered environment maps and
//! objects, in the `#[repr(C)]` layout the WGSL shader declares. The CPU renderer reads the same
//! arrays, so both backends see the same numbers.

use super::candidates;
use super::env::{self, CoeffMap};
pub use super::gpu_layout::{
    GpuLighting, GpuMaterial, GpuObject, Params, CYLINDER_X, HAS_DIFFUSE, HAS_FILM,
    HIDE_BACKGROUND, QUAD, SPHERE, TRANSPARENT,
};
use super::{Backdrop, LightSpectra, Lighting, Scene, Shape, Spectral, MAX_LAYERS};
use crate::colorimetry::RgbSpace;
use crate::error::{Error, Result};
use crate::quadrature::Quadrature;
use crate::spectrum::Interpolation;
use crate::thinfilm::{Film, Index, Stack};
use crate::tradeoff::sample;

/// The CPU's own copy of a film: the thin-film module's stack and its per-wavelength films.
#[derive(Debug, Clone)]
pub struct CpuFilm {
    /// The film as the thin-film module's stack of media and layers.
    pub stack: Stack,
    /// Per wavelength: ambient, layers, substrate indices.
    pub indices: Vec<(Index, Vec<Index>, Index)>,
    /// Nominal thickness of each layer in nm, from the ambient side.
    pub thickness_nm: Vec<f64>,
    /// Per wavelength, at the nominal thicknesses.
    pub films: Vec<Film<f64>>,
}

/// Everything both renderers read.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The frame constants (the shader's uniform buffer).
    pub params: Params,
    /// Every spectrum at the nodes, addressed by the records' offsets: weighted CMFs,
    /// wavelengths, lightings' spectra, diffuse spectra and film tables.
    pub spectra: Vec<f32>,
    /// One record per object of the scene, in its order.
    pub objects: Vec<GpuObject>,
    /// One record per object of the scene, in its order ([`GpuObject::material`]).
    pub materials: Vec<GpuMaterial>,
    /// One record per lighting of the scene, in its order.
    pub lightings: Vec<GpuLighting>,
    /// Per map: [offset in `texels`, width, height, groups of four coefficients per texel].
    pub maps: Vec<[u32; 4]>,
    /// Every map's texels, each map row-major as [`CoeffMap::texels`].
    pub texels: Vec<[f32; 4]>,
    /// Per pixel row and band, the objects it can hit ([`super::candidates`]).
    pub rows: Vec<u32>,
    /// The quadrature's nodes in nm.
    pub wavelengths_nm: Vec<f64>,
    /// Per material (CPU only).
    pub films: Vec<Option<CpuFilm>>,
}

/// The tangent of the background's vertical half field of view (0: straight down -Z).
pub fn pinhole_tangent(backdrop: Backdrop) -> f32 {
    match backdrop {
        Backdrop::Environment { fov_deg } => (0.5 * fov_deg.to_radians()).tan() as f32,
        _ => 0.0,
    }
}

/// Y of values at the nodes, relative to an equal-energy spectrum: `sum w_y s / sum w_y`.
fn luminance(s: &[f64], q: &Quadrature) -> f64 {
    q.integrate(s)[1] / q.sum()[1]
}

/// The spectra a lighting's coefficients expand with, at the quadrature's nodes, padded with
/// zeros to a whole number of groups of four, and the sun's SPD. The paper's:
/// `B_j = MCC_j * S * k` with `Y(S k) = 1`, and `E / Y(E)` (also the sun's); a map's own: as
/// tabulated (radiance units), the sun's at the file's Y = 1.
pub fn lighting_spectra(l: &Lighting, q: &Quadrature) -> Result<(Vec<Vec<f64>>, Vec<f64>)> {
    let nodes = q.nodes_nm();
    let on = || -> String { q.describe() };
    match &l.spectra {
        LightSpectra::Paper {
            light,
            basis_reflectance,
            e_spd,
            e_label,
        } => {
            let s = sample(light, nodes, Interpolation::LIGHT);
            let ys = luminance(&s, q);
            if !(ys.is_finite() && ys > 0.0) {
                return Err(Error::invalid(format!(
                    "the light {} has no visible energy on the wavelengths {}",
                    l.label,
                    on()
                )));
            }
            let b = |j: usize| -> Vec<f64> {
                sample(&basis_reflectance[j], nodes, Interpolation::SMOOTH)
                    .iter()
                    .zip(&s)
                    .map(|(r, s)| r * s / ys)
                    .collect()
            };
            let e = sample(e_spd, nodes, Interpolation::LIGHT);
            let ye = luminance(&e, q);
            if !(ye.is_finite() && ye > 0.0) {
                return Err(Error::invalid(format!(
                    "the SPD {e_label} has no visible energy on the wavelengths {}",
                    on()
                )));
            }
            let e: Vec<f64> = e.iter().map(|v| v / ye).collect();
            Ok((vec![b(0), b(1), b(2), e.clone()], e))
        }
        LightSpectra::Own {
            spectra, sun_spd, ..
        } => {
            let mut out: Vec<Vec<f64>> = spectra
                .iter()
                .map(|s| sample(s, nodes, Interpolation::LIGHT))
                .collect();
            while out.is_empty() || !out.len().is_multiple_of(4) {
                out.push(vec![0.0; nodes.len()]);
            }
            Ok((out, sample(sun_spd, nodes, Interpolation::LIGHT)))
        }
    }
}

fn offset(v: &[f32]) -> Result<u32> {
    u32::try_from(v.len()).map_err(|_| Error::invalid("scene data exceeds 4 G values"))
}

fn push_map(maps: &mut Vec<[u32; 4]>, texels: &mut Vec<[f32; 4]>, m: &CoeffMap) -> u32 {
    let i = maps.len() as u32;
    maps.push([
        texels.len() as u32,
        m.width as u32,
        m.height as u32,
        m.groups as u32,
    ]);
    texels.extend_from_slice(&m.texels);
    i
}

fn f4(v: [f64; 4]) -> [f32; 4] {
    v.map(|x| x as f32)
}

impl Prepared {
    /// Flattens `scene` for `spectral`'s uniform grid and rule (see [`Prepared::with_quadrature`]).
    pub fn new(scene: &Scene, spectral: &Spectral) -> Result<Prepared> {
        let q = Quadrature::uniform(spectral.grid, spectral.rule, spectral.observer)?;
        Prepared::with_quadrature(scene, &q, spectral.space)
    }

    /// Flattens `scene` for the quadrature `q` and the output space: spectra at its nodes, maps
    /// filtered per lighting and shininess.
    ///
    /// ```
    /// use specmap::colorimetry::{Observer, RgbSpace};
    /// use specmap::quadrature::Quadrature;
    /// use specmap::render::{cpu, prepare::Prepared, Preset};
    ///
    /// // Fig. 8's cylinders on Meyer's four-node quadrature, in linear sRGB.
    /// let scene = Preset::Cylinders.scene(32, 32, "D65", None)?;
    /// let q = Quadrature::meyer(Observer::Cie1931)?;
    /// let p = Prepared::with_quadrature(&scene, &q, RgbSpace::SRGB)?;
    /// assert_eq!(p.wavelengths_nm.len(), q.len());
    /// let image = cpu::render(&p);
    /// # Ok::<(), specmap::error::Error>(())
    /// ```
    pub fn with_quadrature(scene: &Scene, q: &Quadrature, space: RgbSpace) -> Result<Prepared> {
        scene.validate()?;
        let mut arrays = Arrays::default();
        let (cmf_offset, wl_offset) = arrays.push_cmfs(q)?;
        let lit = arrays.push_lightings(scene, q)?;
        let wavelengths_nm: Vec<f64> = q.nodes_nm().to_vec();
        let surfaces = arrays.push_surfaces(scene, &wavelengths_nm, &lit)?;
        if arrays.spectra.len() > u32::MAX as usize {
            return Err(Error::invalid("spectral data exceeds 4 G values"));
        }
        let frame = Frame {
            n_wl: q.len(),
            n_objects: surfaces.objects.len(),
            cmf_offset,
            wl_offset,
        };
        let params = frame_params(scene, space, &frame);
        let rows = candidates::index(&surfaces.objects, &params);
        Ok(Prepared {
            params,
            spectra: arrays.spectra,
            objects: surfaces.objects,
            materials: surfaces.materials,
            lightings: lit.lightings,
            maps: arrays.maps,
            texels: arrays.texels,
            rows,
            wavelengths_nm,
            films: surfaces.films,
        })
    }
}

/// The arrays being filled, in the order the shader reads them: spectra, then maps and their
/// texels.
#[derive(Default)]
struct Arrays {
    spectra: Vec<f32>,
    maps: Vec<[u32; 4]>,
    texels: Vec<[f32; 4]>,
}

/// The scene's lightings as the GPU reads them, and per lighting its specular maps:
/// `(shininess, map index)`.
struct Lit {
    lightings: Vec<GpuLighting>,
    specular: Vec<Vec<(f64, u32)>>,
}

/// Per object, its material, its CPU film and its record.
struct Surfaces {
    materials: Vec<GpuMaterial>,
    films: Vec<Option<CpuFilm>>,
    objects: Vec<GpuObject>,
}

/// What [`frame_params`] takes besides the scene: the node and object counts and the offsets of
/// the weighted CMFs and the wavelengths.
struct Frame {
    n_wl: usize,
    n_objects: usize,
    cmf_offset: u32,
    wl_offset: u32,
}

impl Arrays {
    /// The weighted CMFs (XYZ = sum_i cmf_w(i) I(i), a perfect white under a Y = 1 light ->
    /// Y = 1), then the wavelengths: their offsets.
    fn push_cmfs(&mut self, q: &Quadrature) -> Result<(u32, u32)> {
        let norm = q.sum()[1];
        let cmf_offset = offset(&self.spectra)?;
        for c in 0..3 {
            self.spectra
                .extend(q.weights().iter().map(|w| (w[c] / norm) as f32));
        }
        let wl_offset = offset(&self.spectra)?;
        self.spectra.extend(q.nodes_nm().iter().map(|&v| v as f32));
        Ok((cmf_offset, wl_offset))
    }

    /// Each lighting's spectra and maps, in scene order.
    fn push_lightings(&mut self, scene: &Scene, q: &Quadrature) -> Result<Lit> {
        let mut lit = Lit {
            lightings: Vec::new(),
            specular: Vec::new(),
        };
        for (li, l) in scene.lightings.iter().enumerate() {
            let (lighting, specular) = self.push_lighting(scene, li, l, q)?;
            lit.lightings.push(lighting);
            lit.specular.push(specular);
        }
        if self.texels.len() > u32::MAX as usize {
            return Err(Error::invalid("environment maps exceed 4 G texels"));
        }
        Ok(lit)
    }

    /// Lighting `li`: its spectra and sun SPD, then its filtered maps for the shininess of the
    /// objects it lights.
    fn push_lighting(
        &mut self,
        scene: &Scene,
        li: usize,
        l: &Lighting,
        q: &Quadrature,
    ) -> Result<(GpuLighting, Vec<(f64, u32)>)> {
        let (sp, sun_spd) = lighting_spectra(l, q)?;
        let groups = sp.len() / 4;
        let off = offset(&self.spectra)?;
        for s in &sp {
            self.spectra.extend(s.iter().map(|&v| v as f32));
        }
        let sun_offset = offset(&self.spectra)?;
        self.spectra.extend(sun_spd.iter().map(|&v| v as f32));
        check_map_groups(l, groups, sp.len())?;
        let f = env::prefilter(&l.environment, &shininess_lit_by(scene, li));
        let background_map = self.push_map(&f.background);
        let diffuse_map = self.push_map(&f.diffuse);
        let specular = f
            .specular
            .iter()
            .map(|(s, m)| (*s, self.push_map(m)))
            .collect();
        let (has_sun, sun) = gpu_sun(l)?;
        let lighting = GpuLighting {
            spectra: off,
            diffuse_map,
            background_map,
            has_sun,
            sun,
            layout: [groups as u32, sun_offset, 0, 0],
        };
        Ok((lighting, specular))
    }

    /// Appends a map's texels and its `[offset, width, height, groups]`: its index.
    fn push_map(&mut self, m: &CoeffMap) -> u32 {
        push_map(&mut self.maps, &mut self.texels, m)
    }

    /// Each object's material (its diffuse spectrum and film table appended) and record.
    fn push_surfaces(
        &mut self,
        scene: &Scene,
        wavelengths_nm: &[f64],
        lit: &Lit,
    ) -> Result<Surfaces> {
        let mut out = Surfaces {
            materials: Vec::new(),
            films: Vec::new(),
            objects: Vec::new(),
        };
        for (oi, o) in scene.objects.iter().enumerate() {
            let (material, film) = self.push_material(oi, &o.surface, wavelengths_nm)?;
            out.materials.push(material);
            out.films.push(film);
            let spec_map = lit.specular[o.lighting]
                .iter()
                .find(|(sh, _)| *sh == o.surface.shininess)
                .map(|(_, m)| *m)
                .unwrap_or(lit.lightings[o.lighting].background_map);
            out.objects.push(gpu_object(oi, o, spec_map));
        }
        Ok(out)
    }

    /// Object `oi`'s surface: its diffuse reflectance and film table appended, its material
    /// record and the CPU's film.
    fn push_material(
        &mut self,
        oi: usize,
        s: &super::Surface,
        wavelengths_nm: &[f64],
    ) -> Result<(GpuMaterial, Option<CpuFilm>)> {
        let mut flags = 0;
        let mut diffuse_offset = 0;
        if let Some(rd) = &s.diffuse {
            flags |= HAS_DIFFUSE;
            diffuse_offset = offset(&self.spectra)?;
            let r = sample(rd, wavelengths_nm, Interpolation::SMOOTH);
            self.spectra.extend(r.iter().map(|&v| v as f32));
        }
        if s.transparent {
            flags |= TRANSPARENT;
        }
        let mut film_offset = 0;
        let mut thickness = [[0f32; 4]; 2];
        let mut cpu_film = None;
        if let Some(f) = &s.film {
            flags |= HAS_FILM;
            let what = |e: Error| Error::invalid(format!("object {} ({}): {e}", oi + 1, s.label));
            let film = cpu_film_of(f, wavelengths_nm).map_err(what)?;
            film_offset = self.push_film_table(&film.indices)?;
            for (k, d) in film.thickness_nm.iter().enumerate() {
                thickness[k / 4][k % 4] = *d as f32;
            }
            cpu_film = Some(film);
        }
        let n_layers = s.film.as_ref().map_or(0, |f| f.layers.len());
        debug_assert!(n_layers <= MAX_LAYERS);
        let material = GpuMaterial {
            flags,
            n_layers: n_layers as u32,
            diffuse_offset,
            film_offset,
            coef: [s.kd as f32, s.ks as f32, s.shininess as f32, 0.0],
            thickness,
        };
        Ok((material, cpu_film))
    }

    /// A film's table (see [`GpuMaterial::film_offset`]): per medium, n then k at every node.
    fn push_film_table(&mut self, indices: &[(Index, Vec<Index>, Index)]) -> Result<u32> {
        let film_offset = offset(&self.spectra)?;
        let n_layers = indices.first().map_or(0, |(_, l, _)| l.len());
        for m in 0..n_layers + 2 {
            let idx = |i: usize| {
                let (a, l, s) = &indices[i];
                if m == 0 {
                    *a
                } else if m == n_layers + 1 {
                    *s
                } else {
                    l[m - 1]
                }
            };
            self.spectra
                .extend((0..indices.len()).map(|i| idx(i).n() as f32));
            self.spectra
                .extend((0..indices.len()).map(|i| idx(i).k() as f32));
        }
        Ok(film_offset)
    }
}

/// A lighting's map must hold a coefficient per spectrum it expands with.
fn check_map_groups(l: &Lighting, groups: usize, spectra: usize) -> Result<()> {
    let map_groups = match &l.environment {
        super::Environment::Map(m) => m.light.groups,
        _ => 1,
    };
    if map_groups != groups {
        return Err(Error::invalid(format!(
            "lighting {}: its map holds {} coefficients a texel for {} spectra",
            l.label,
            4 * map_groups,
            spectra
        )));
    }
    Ok(())
}

/// The distinct shininess values of the objects lighting `li` lights, in scene order.
fn shininess_lit_by(scene: &Scene, li: usize) -> Vec<f64> {
    let mut shininess: Vec<f64> = Vec::new();
    for o in scene.objects.iter().filter(|o| o.lighting == li) {
        if !shininess.contains(&o.surface.shininess) {
            shininess.push(o.surface.shininess);
        }
    }
    shininess
}

/// The lighting's sun as the GPU reads it: whether it has one, its unit direction and
/// irradiance.
fn gpu_sun(l: &Lighting) -> Result<(u32, [f32; 4])> {
    let Some(s) = l.sun else {
        return Ok((0, [0.0; 4]));
    };
    let d = s.direction;
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if !(len > 0.0 && len.is_finite() && s.irradiance.is_finite()) {
        return Err(Error::invalid(format!(
            "lighting {}: the sun needs a direction and a finite irradiance",
            l.label
        )));
    }
    Ok((1, f4([d[0] / len, d[1] / len, d[2] / len, s.irradiance])))
}

/// The CPU's film at the nodes: the indices of every medium (a transparent ambient), the
/// thicknesses and the thin-film module's films.
fn cpu_film_of(f: &super::Film, wavelengths_nm: &[f64]) -> Result<CpuFilm> {
    let indices: Vec<(Index, Vec<Index>, Index)> = wavelengths_nm
        .iter()
        .map(|&wl| -> Result<_> {
            Ok((
                f.ambient.index_at(wl)?,
                f.layers
                    .iter()
                    .map(|l| l.material().index_at(wl))
                    .collect::<Result<Vec<_>>>()?,
                f.substrate.index_at(wl)?,
            ))
        })
        .collect::<Result<_>>()?;
    if let Some(bad) = indices.iter().find(|(a, _, _)| a.k() != 0.0) {
        return Err(Error::invalid(format!(
            "the ambient medium must be transparent (index {})",
            bad.0
        )));
    }
    let thickness_nm: Vec<f64> = f.layers.iter().map(|l| l.thickness_nm()).collect();
    let stack = Stack::new(f.ambient.clone(), f.layers.clone(), f.substrate.clone());
    let films = wavelengths_nm
        .iter()
        .map(|&wl| stack.at::<f64>(wl))
        .collect::<Result<Vec<_>>>()?;
    Ok(CpuFilm {
        stack,
        indices,
        thickness_nm,
        films,
    })
}

/// Object `oi`'s record: its shape, material (one per object), lighting, specular map and ramp.
fn gpu_object(oi: usize, o: &super::Object, spec_map: u32) -> GpuObject {
    let (kind, p0, p1) = shape_record(&o.shape);
    let (ramp, has_ramp) = match o.ramp {
        Some(r) => ([r.x0, r.x1, r.s0, r.s1], 1),
        None => ([0.0, 1.0, 1.0, 1.0], 0),
    };
    GpuObject {
        kind,
        material: oi as u32,
        lighting: o.lighting as u32,
        spec_map,
        p0: f4(p0),
        p1: f4(p1),
        ramp: f4(ramp),
        flags: [has_ramp, 0, 0, 0],
    }
}

/// A shape's kind and its two parameter rows ([`GpuObject::p0`], [`GpuObject::p1`]).
fn shape_record(shape: &Shape) -> (u32, [f64; 4], [f64; 4]) {
    match *shape {
        Shape::Sphere { center, radius } => {
            (SPHERE, [center[0], center[1], center[2], radius], [0.0; 4])
        }
        Shape::CylinderX {
            center,
            radius,
            half_length,
        } => (
            CYLINDER_X,
            [center[0], center[1], center[2], radius],
            [half_length, 0.0, 0.0, 0.0],
        ),
        Shape::Quad { center, half_size } => (
            QUAD,
            [center[0], center[1], center[2], 0.0],
            [half_size[0], half_size[1], 0.0, 0.0],
        ),
    }
}

/// The frame constants: size, counts, offsets, backdrop, view, output matrix and orientation.
fn frame_params(scene: &Scene, space: RgbSpace, frame: &Frame) -> Params {
    let m = space.from_xyz_matrix();
    let row = |r: usize| [m[(r, 0)] as f32, m[(r, 1)] as f32, m[(r, 2)] as f32, 0.0];
    let pixel = 2.0 * scene.view.half_height / scene.height as f64;
    Params {
        width: scene.width as u32,
        height: scene.height as u32,
        n_wl: frame.n_wl as u32,
        n_objects: frame.n_objects as u32,
        background: scene.background as u32,
        cmf_offset: frame.cmf_offset,
        wl_offset: frame.wl_offset,
        flags: match scene.backdrop {
            Backdrop::Hidden => HIDE_BACKGROUND,
            _ => 0,
        },
        view: [
            scene.view.center[0] as f32,
            scene.view.center[1] as f32,
            pixel as f32,
            pinhole_tangent(scene.backdrop),
        ],
        rgb: [row(0), row(1), row(2)],
        orientation: scene
            .orientation
            .map(|r| [r[0] as f32, r[1] as f32, r[2] as f32, 0.0]),
    }
}
