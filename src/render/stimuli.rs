//! What a scene shows, as stimuli for a quadrature ([`crate::quadrature`]): every spectrum its
//! lights radiate, seen directly and through each object's pigment and film, at the angles and
//! thicknesses the image holds, each at the brightest it appears.
//!
//! Per lighting, the spectra are those its coefficients expand with (`E` for a uniform or
//! sky-and-ground environment and the sun; for a map also the three basis spectra `MCC_j * S`
//! and the mixtures of them that its most different texels radiate, since a mixture's error is
//! not bounded by its parts', and those of the texels the check on every texel found worst
//! ([`expansion`]); for a map of its own spectra its most different texels, as emissions at
//! their own luminance: [`texels`]).
//! Per object lit by it:
//! - opaque: the diffuse path `k_d R_d T_f(theta)` and the specular path `R_f(theta)` (or `k_s`
//!   without a film) of Eq. 1, and for a glossy pigment without a film their sums (a pixel
//!   shows the pigment plus part of the highlight) at several shares of the highlight;
//! - transparent: `R_f(theta)` in reflection and `T_f(theta)` in transmission (Eq. 9).
//!
//! Films are sampled at view angles from 0 to 89.5 degrees (and around the sun's highlight) and,
//! on a thickness ramp, at [`SAMPLES_PER_CYCLE`] thicknesses per cycle of the round-trip phase at
//! 380 nm ([`TINTED_SAMPLES_PER_CYCLE`] under a map's tinted spectra). The fit set and the
//! held-out set take different angles and thicknesses (the held-out ones lie between the fitted
//! ones), so the held-out set checks what the fit did not see.
//! Identical stimuli (objects that share a surface and a lighting) are taken once.
//!
//! The camera looks down -Z, so a surface seen at view angle `theta` has its normal `theta` from
//! +Z and its mirror direction `2 theta` from it. Each stimulus's gain is the brightest the
//! environment and the sun make it at its angle over the normals the shape has there (a sphere
//! has every azimuth, a cylinder along X only normals in the YZ plane, a quad only +Z): the sun's
//! `max(N.l, 0)` diffusely and its Phong lobe `(R_v.l)^n` in reflection.

mod coverage;
mod expansion;
mod pixels;
mod selection;
mod texels;
mod visible;

use super::{Environment, LightSpectra, Lighting, Scene, Shape};
use crate::error::Result;
use crate::thinfilm::{Incidence, Layer, Stack};
use crate::tradeoff::{Factor, Stimulus, Surface as Seen};
use std::f64::consts::PI;

/// View angles of the fit set (degrees).
pub(crate) const FIT_ANGLES: [f64; 11] = [
    0.0, 25.0, 40.0, 50.0, 58.0, 65.0, 71.0, 76.0, 81.0, 85.0, 89.5,
];
/// View angles of the held-out set, between the fitted ones.
pub(crate) const HELD_OUT_ANGLES: [f64; 10] =
    [12.0, 33.0, 45.0, 54.0, 61.5, 68.0, 73.5, 78.5, 83.0, 87.5];
/// Thickness samples per cycle of a ramp's round-trip phase at the shortest wavelength.
pub(crate) const SAMPLES_PER_CYCLE: f64 = 12.0;
/// The same under a map's tinted spectra (its basis and texel mixtures): the film's fringes are
/// sampled densely under the untinted light, and a smooth tint only weighs them; thinner, so
/// that a map's dozen spectra do not multiply a ramp's thousand films.
pub(crate) const TINTED_SAMPLES_PER_CYCLE: f64 = 4.0;

/// Angles around the sun's highlight (offsets in degrees from it): fitted, and held out.
const HIGHLIGHT_FIT: [f64; 5] = [-3.0, -1.5, 0.0, 1.5, 3.0];
const HIGHLIGHT_HELD_OUT: [f64; 4] = [-2.25, -0.75, 0.75, 2.25];

/// The fit set and the held-out set.
#[derive(Debug, Clone)]
pub struct Sets<T> {
    /// The ones the quadrature is fitted to.
    pub fit: Vec<T>,
    /// The ones only checked, to estimate its error elsewhere.
    pub held_out: Vec<T>,
}

/// The scene's stimuli: fitted, and held out.
pub(crate) type Stimuli = Sets<Stimulus>;

/// Which of a lighting's maps the renderer reads for a path: the map seen behind the objects
/// (the environment seen directly, a transparent object's transmission), the diffuse map, the
/// specular map of the object's shininess, or the last two (a glossy pigment's pixels show its
/// colour and part of its highlight).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Path {
    Seen,
    Diffuse,
    Specular,
    Glossy,
}

/// A spectrum a lighting radiates: its normalising light, what it carries over that light (an
/// RGB map's basis reflectance, a spectral map's texel emission; None for `E`), a label, the
/// brightest the environment radiates it (None: the environment's peak), how densely films
/// are sampled under it, and whether it is only checked, not fitted.
struct Radiated {
    label: String,
    light: crate::spectrum::Tabulated,
    tint: Option<Factor>,
    peak: Option<f64>,
    per_cycle: f64,
    held_out: bool,
    /// The sun's luminance in units of this spectrum's (1 but for a spectral map's texels).
    sun_scale: f64,
}

impl Radiated {
    fn fitted(label: String, light: crate::spectrum::Tabulated, tint: Option<Factor>) -> Self {
        let per_cycle = match tint {
            Some(_) => TINTED_SAMPLES_PER_CYCLE,
            None => SAMPLES_PER_CYCLE,
        };
        Radiated {
            label,
            light,
            tint,
            peak: None,
            per_cycle,
            held_out: false,
            sun_scale: 1.0,
        }
    }
}

fn radiated(
    l: &Lighting,
    seen: Option<&super::env::CoeffMap>,
    shininess: &[f64],
    texels_fitted: usize,
    added: &[&[f64]],
) -> Result<Vec<Radiated>> {
    let mut out = Vec::new();
    match &l.spectra {
        LightSpectra::Paper {
            light,
            basis_reflectance,
            e_spd,
            e_label,
        } => {
            if let Environment::Map(m) = &l.environment {
                for (j, b) in basis_reflectance.iter().enumerate() {
                    let label = format!("basis {} of {}", j + 1, l.label);
                    let tint = Some(Factor::Reflectance(b.clone()));
                    out.push(Radiated::fitted(label, light.clone(), tint));
                }
                // A texel radiates a mixture of the basis spectra, whose error the three alone
                // do not bound (a photograph's ball erred 0.48 on the image against an
                // estimate of 0.32 with the basis alone). Each mixture is taken as bright as
                // the brightest texel it stands for, not the map's peak.
                let mixtures = representative_spectra(&m.light, basis_reflectance, MIXTURES);
                for (k, (t, cell_peak)) in mixtures.into_iter().enumerate() {
                    let peak = t.values().iter().copied().fold(0.0, f64::max);
                    let values = t.values().iter().map(|v| v / peak).collect();
                    let Ok(tint) =
                        crate::spectrum::Tabulated::new(t.wavelengths_nm().to_vec(), values)
                    else {
                        continue;
                    };
                    let label = format!("texel mixture {} of {}", k + 1, l.label);
                    out.push(Radiated {
                        peak: Some(cell_peak),
                        ..Radiated::fitted(label, light.clone(), Some(Factor::Reflectance(tint)))
                    });
                }
                out.extend(expansion::paper_texels(l, basis_reflectance, light, added)?);
            }
            out.push(Radiated::fitted(e_label.clone(), e_spd.clone(), None));
        }
        LightSpectra::Own {
            spectra,
            sun_spd,
            sun_label,
        } => {
            if let (Environment::Map(m), Some(seen)) = (&l.environment, seen) {
                let shown = texels::Shown {
                    light: &m.light,
                    seen,
                };
                out.extend(texels::texels(
                    l,
                    &shown,
                    spectra,
                    sun_spd,
                    shininess,
                    texels_fitted,
                    added,
                )?);
            }
            if l.sun.is_some() {
                out.push(texels::sun(sun_label, sun_spd)?);
            }
        }
    }
    Ok(out)
}

/// How many texel mixtures of the basis stand for an RGB map's colours.
const MIXTURES: usize = 6;

/// The spectra of a few texels of `map` that differ most (farthest-point sampling in the
/// coefficients normalised to unit length, from the brightest texel), each with the brightest
/// texel it stands for: of those nearer to it than to any other chosen one, the largest sum of
/// absolute coefficients (as [`environment_peak`] measures the map).
fn representative_spectra(
    map: &super::env::CoeffMap,
    spectra: &[crate::spectrum::Tabulated],
    count: usize,
) -> Vec<(crate::spectrum::Tabulated, f64)> {
    let k = spectra.len();
    let texels: Vec<Vec<f64>> = (0..map.width * map.height)
        .map(|i| map.texel(i).take(k).map(|v| v as f64).collect())
        .collect();
    let norm = |c: &[f64]| c.iter().map(|v| v * v).sum::<f64>().sqrt();
    let unit: Vec<Vec<f64>> = texels
        .iter()
        .map(|c| {
            let n = norm(c);
            c.iter()
                .map(|v| if n > 0.0 { v / n } else { 0.0 })
                .collect()
        })
        .collect();
    let Some(first) =
        (0..texels.len()).max_by(|&a, &b| norm(&texels[a]).total_cmp(&norm(&texels[b])))
    else {
        return Vec::new();
    };
    let units: Vec<&[f64]> = unit.iter().map(Vec::as_slice).collect();
    let (chosen, cell) = farthest_points(&units, first, count);
    let mut cell_peak = vec![0.0f64; chosen.len()];
    for (i, &c) in cell.iter().enumerate() {
        let bright: f64 = map.texel(i).map(|v| (v as f64).abs()).sum();
        cell_peak[c] = cell_peak[c].max(bright);
    }
    let wl = spectra
        .first()
        .map(|s| s.wavelengths_nm().to_vec())
        .unwrap_or_default();
    chosen
        .into_iter()
        .zip(cell_peak)
        .filter_map(|(t, peak)| {
            let c = &texels[t];
            let v: Vec<f64> = (0..wl.len())
                .map(|i| {
                    (0..k)
                        .map(|j| c[j] * spectra[j].values()[i])
                        .sum::<f64>()
                        .max(0.0)
                })
                .collect();
            (norm(&v) > 0.0)
                .then(|| crate::spectrum::Tabulated::new(wl.clone(), v).ok())
                .flatten()
                .map(|s| (s, peak))
        })
        .collect()
}

/// Squared Euclidean distance.
fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum()
}

/// Farthest-point sampling of up to `count` of the vectors `unit`, from `first`, stopping where
/// every vector lies on a chosen one: the chosen indices, and for each vector the position
/// among them of the nearest (the first on a tie).
fn farthest_points(unit: &[&[f64]], first: usize, count: usize) -> (Vec<usize>, Vec<usize>) {
    let mut chosen = vec![first];
    let mut nearest: Vec<(f64, usize)> = unit.iter().map(|u| (dist(u, unit[first]), 0)).collect();
    while chosen.len() < count.min(unit.len()) {
        let (next, d) = nearest
            .iter()
            .enumerate()
            .max_by(|a, b| a.1 .0.total_cmp(&b.1 .0))
            .map_or((0, 0.0), |(i, d)| (i, d.0));
        if d <= 1e-12 {
            break;
        }
        let at = chosen.len();
        chosen.push(next);
        for (u, n) in unit.iter().zip(nearest.iter_mut()) {
            let d = dist(u, unit[next]);
            if d < n.0 {
                *n = (d, at);
            }
        }
    }
    (chosen, nearest.into_iter().map(|n| n.1).collect())
}

/// The brightest the environment gets, in units of its spectra's whites.
fn environment_peak(env: &Environment) -> f64 {
    match env {
        Environment::Uniform { radiance } => radiance.abs(),
        Environment::SkyGround { sky, ground, .. } => sky.abs().max(ground.abs()),
        Environment::Map(m) => m
            .light
            .texels
            .chunks(m.light.groups)
            .map(|t| t.iter().flatten().map(|v| (*v as f64).abs()).sum::<f64>())
            .fold(0.0, f64::max),
    }
}

/// The thickness scales a film is sampled at: (fit, held out).
fn thickness_scales(o: &super::Object, per_cycle: f64) -> (Vec<f64>, Vec<f64>) {
    let Some(r) = o.ramp else {
        return (vec![1.0], vec![1.0]);
    };
    let optical: f64 = o.surface.film.as_ref().map_or(0.0, |f| {
        f.layers
            .iter()
            .map(|l| l.material().index_at(550.0).map_or(1.0, |n| n.n()) * l.thickness_nm())
            .sum()
    });
    let cycles = 2.0 * optical * (r.s1 - r.s0).abs() / 380.0;
    let m = ((per_cycle * cycles).ceil() as usize).clamp(2, 400);
    let at = |t: f64| r.s0 + (r.s1 - r.s0) * t;
    let fit = (0..=m).map(|i| at(i as f64 / m as f64)).collect();
    let held = (0..m).map(|i| at((i as f64 + 0.5) / m as f64)).collect();
    (fit, held)
}

fn scaled_stack(f: &super::Film, k: f64) -> Result<Stack> {
    let layers = f
        .layers
        .iter()
        .map(|l| Layer::new(l.material().clone(), l.thickness_nm() * k))
        .collect::<Result<Vec<_>>>()?;
    Ok(Stack::new(f.ambient.clone(), layers, f.substrate.clone()))
}

/// How bright one lighting makes a surface at each view angle (see the module docs).
#[derive(Debug, Clone, Copy)]
struct Brightness {
    /// The environment's peak, in units of its spectra's whites.
    env: f64,
    /// The sun's irradiance and unit direction.
    sun: f64,
    sun_dir: [f64; 3],
}

/// The normals of `shape` seen at view angle `deg` (the camera looks down -Z): for a sphere the
/// two in the plane of the view and the sun (the extremes over all azimuths), for a cylinder
/// along X the two in the YZ plane, for a quad facing +Z only its normal, at 0 degrees.
fn normals(shape: &Shape, deg: f64, sun_dir: [f64; 3]) -> Vec<[f64; 3]> {
    let (s, c) = deg.to_radians().sin_cos();
    match shape {
        Shape::Sphere { .. } => {
            let h = sun_dir[0].hypot(sun_dir[1]);
            let (x, y) = if h > 0.0 {
                (sun_dir[0] / h, sun_dir[1] / h)
            } else {
                (1.0, 0.0)
            };
            vec![[s * x, s * y, c], [-s * x, -s * y, c]]
        }
        Shape::CylinderX { .. } => vec![[0.0, s, c], [0.0, -s, c]],
        Shape::Quad { .. } => {
            if deg == 0.0 {
                vec![[0.0, 0.0, 1.0]]
            } else {
                Vec::new()
            }
        }
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Brightness {
    /// `any_orientation`: the sun as it would face the camera ([`super::Scene::any_orientation`]).
    fn of(l: &Lighting, any_orientation: bool) -> Brightness {
        let (sun, sun_dir) = l.sun.map_or((0.0, [0.0, 0.0, 1.0]), |s| {
            let d = if any_orientation {
                [0.0, 0.0, 1.0]
            } else {
                s.direction
            };
            let len = dot(d, d).sqrt();
            if len > 0.0 {
                (s.irradiance.abs(), d.map(|v| v / len))
            } else {
                (0.0, [0.0, 0.0, 1.0])
            }
        });
        Brightness {
            env: environment_peak(&l.environment),
            sun,
            sun_dir,
        }
    }
    /// The brightest diffuse lighting (times `kd`) of `shape` at view angle `deg`.
    fn diffuse(&self, shape: &Shape, kd: f64, deg: f64) -> f64 {
        let c = normals(shape, deg, self.sun_dir)
            .iter()
            .map(|n| dot(*n, self.sun_dir).max(0.0))
            .fold(0.0, f64::max);
        kd * (self.env + self.sun * c / PI)
    }
    /// The brightest specular lighting (environment plus the sun's Phong lobe).
    fn specular(&self, shape: &Shape, shininess: f64, deg: f64) -> f64 {
        let lobe = normals(shape, deg, self.sun_dir)
            .iter()
            .map(|n| {
                let r = [
                    2.0 * n[2] * n[0],
                    2.0 * n[2] * n[1],
                    2.0 * n[2] * n[2] - 1.0,
                ];
                super::cpu::lobe(dot(r, self.sun_dir), shininess)
            })
            .fold(0.0, f64::max);
        self.env + self.sun * (shininess + 1.0) / (2.0 * PI) * lobe
    }
}

/// The view angles sampled on `shape`: (fit, held out). Around the sun's highlight, if it
/// reaches the shape, the angles are denser.
fn angles(shape: &Shape, b: &Brightness, shininess: f64) -> (Vec<f64>, Vec<f64>) {
    if matches!(shape, Shape::Quad { .. }) {
        return (vec![0.0], Vec::new());
    }
    let (mut fit, mut held) = (FIT_ANGLES.to_vec(), HELD_OUT_ANGLES.to_vec());
    let peak = (0..360)
        .map(|i| i as f64 * 0.25)
        .map(|d| (d, b.specular(shape, shininess, d) - b.env))
        .fold((0.0, 0.0), |a, x| if x.1 > a.1 { x } else { a });
    if peak.1 > 1e-3 * b.env.max(1e-9) {
        fit.extend(HIGHLIGHT_FIT.iter().map(|d| peak.0 + d));
        held.extend(HIGHLIGHT_HELD_OUT.iter().map(|d| peak.0 + d));
    }
    for v in [&mut fit, &mut held] {
        v.retain(|a| (0.0..90.0).contains(a));
        v.sort_by(f64::total_cmp);
        v.dedup();
    }
    (fit, held)
}

/// The highlight's share of a glossy pigment's pixels: its lighting over the brightest diffuse
/// lighting, fitted and held out.
const GLOSS_FIT: [f64; 5] = [0.05, 0.15, 0.35, 0.7, 1.0];
const GLOSS_HELD_OUT: [f64; 4] = [0.1, 0.25, 0.5, 0.85];

/// A glossy pigment's pixels are its diffuse colour plus part of the white highlight, not
/// either alone; a mixture is paler and brighter than the pigment and sits where CIEDE2000
/// weighs errors differently (the red plastic sphere of the chart erred 23% above an estimate
/// that took the two apart). Each mixture is the reflectance `(a R_d + b) / (a + b)` at gain
/// `a + b`, with `a` the brightest diffuse lighting and `b` a share of the brightest highlight.
fn glossy_pigment<T>(
    rd: &crate::spectrum::Tabulated,
    diffuse: f64,
    highlight: f64,
    make: &dyn Fn(String, Vec<Factor>, f64, Path) -> T,
    out: &mut Sets<T>,
) -> Result<()> {
    for (set, shares) in [
        (&mut out.fit, &GLOSS_FIT[..]),
        (&mut out.held_out, &GLOSS_HELD_OUT[..]),
    ] {
        for &t in shares {
            let (a, b) = (diffuse, t * highlight);
            let values = rd.values().iter().map(|v| (a * v + b) / (a + b)).collect();
            let mixed = crate::spectrum::Tabulated::new(rd.wavelengths_nm().to_vec(), values)?;
            let name = format!("with {t} of its highlight");
            set.push(make(
                name,
                vec![Factor::Reflectance(mixed)],
                a + b,
                Path::Glossy,
            ));
        }
    }
    Ok(())
}

/// Which texels stand for a spectral map: the first `fitted` of the most different fitted
/// (the next [`texels::CHECKED`] held out), and per lighting, texels added to the fit because a
/// chosen quadrature erred most on them ([`coverage`]).
#[derive(Debug, Clone)]
pub struct TexelChoice {
    /// How many of the most different texels are fitted.
    pub fitted: usize,
    /// Texels added to the fit: (index in [`Scene::lightings`], the texel's coefficients).
    pub added: Vec<(usize, Vec<f64>)>,
}

impl Default for TexelChoice {
    fn default() -> Self {
        TexelChoice {
            fitted: texels::FITTED,
            added: Vec::new(),
        }
    }
}

/// The shininess values of `objects`, each once.
fn shininess_of(objects: &[&super::Object]) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::new();
    for o in objects {
        if !out.contains(&o.surface.shininess) {
            out.push(o.surface.shininess);
        }
    }
    out
}

impl Scene {
    /// The objects lit by lighting `li`, those that look alike (same surface, same ramp) once:
    /// they give the same stimuli.
    fn distinct_objects(&self, li: usize) -> Vec<&super::Object> {
        let mut objects: Vec<&super::Object> = Vec::new();
        for o in self.objects.iter().filter(|o| o.lighting == li) {
            if !objects
                .iter()
                .any(|p| p.surface == o.surface && p.ramp == o.ramp)
            {
                objects.push(o);
            }
        }
        objects
    }

    /// The scene's stimuli (see the module docs).
    pub fn stimuli(&self) -> Result<Stimuli> {
        self.stimuli_with(&TexelChoice::default())
    }

    /// The scene's stimuli, a spectral map's texels as `texels` says.
    pub fn stimuli_with(&self, texels: &TexelChoice) -> Result<Stimuli> {
        self.stimuli_shown(texels, &self.visible_seens())
    }

    /// [`Scene::stimuli_with`], each lighting's seen map as `seen` holds it
    /// ([`Scene::visible_seens`]).
    fn stimuli_shown(
        &self,
        texels: &TexelChoice,
        seen: &[Option<super::env::CoeffMap>],
    ) -> Result<Stimuli> {
        let mut out = Stimuli {
            fit: Vec::new(),
            held_out: Vec::new(),
        };
        for (li, lighting) in self.lightings.iter().enumerate() {
            let b = Brightness::of(lighting, self.any_orientation);
            let objects = self.distinct_objects(li);
            let shininess = shininess_of(&objects);
            let added: Vec<&[f64]> = texels
                .added
                .iter()
                .filter(|(l, _)| *l == li)
                .map(|(_, c)| c.as_slice())
                .collect();
            for r in radiated(
                lighting,
                seen[li].as_ref(),
                &shininess,
                texels.fitted,
                &added,
            )? {
                let b = Brightness {
                    env: r.peak.unwrap_or(b.env),
                    sun: b.sun * r.sun_scale,
                    ..b
                };
                let base: Vec<Factor> = r.tint.iter().cloned().collect();
                let make = |name: String, mut f: Vec<Factor>, gain: f64, _: Path| {
                    let mut all = base.clone();
                    all.append(&mut f);
                    Stimulus::new(name, r.light.clone(), Seen::Product(all))
                        .with_gain(gain.max(1e-3))
                };
                let mut these = Stimuli {
                    fit: vec![make(
                        r.label.clone(),
                        Vec::new(),
                        b.env.max(1.0),
                        Path::Seen,
                    )],
                    held_out: Vec::new(),
                };
                for o in &objects {
                    object_stimuli(o, &r.label, r.per_cycle, &b, &make, &mut these)?;
                }
                if r.held_out {
                    out.held_out.append(&mut these.fit);
                } else {
                    out.fit.append(&mut these.fit);
                }
                out.held_out.append(&mut these.held_out);
            }
        }
        Ok(out)
    }
}

/// One object's stimuli under one radiated spectrum, each made by `make` from its name,
/// factors, gain and the path it takes.
fn object_stimuli<T>(
    o: &super::Object,
    label: &str,
    per_cycle: f64,
    b: &Brightness,
    make: &dyn Fn(String, Vec<Factor>, f64, Path) -> T,
    out: &mut Sets<T>,
) -> Result<()> {
    let s = &o.surface;
    let (fit_deg, held_deg) = angles(&o.shape, b, s.shininess);
    let shape = &o.shape;
    let pigment = s.diffuse.as_ref().filter(|_| s.kd > 0.0);
    let Some(film) = &s.film else {
        // No film: the pigment and the highlight do not change with the angle.
        let brightest = |f: &dyn Fn(f64) -> f64| fit_deg.iter().map(|&d| f(d)).fold(0.0, f64::max);
        if let Some(rd) = pigment {
            let gain = brightest(&|d| b.diffuse(shape, s.kd, d));
            let f = vec![Factor::Reflectance(rd.clone())];
            out.fit.push(make(
                format!("{} under {label}", s.label),
                f,
                gain,
                Path::Diffuse,
            ));
        }
        if s.ks > 0.0 {
            let gain = s.ks * brightest(&|d| b.specular(shape, s.shininess, d));
            let name = format!("{} highlight under {label}", s.label);
            out.fit.push(make(name, Vec::new(), gain, Path::Specular));
            if let Some(rd) = pigment {
                let diffuse = brightest(&|d| b.diffuse(shape, s.kd, d));
                glossy_pigment(
                    rd,
                    diffuse,
                    gain,
                    &|name, f, gain, path| {
                        make(format!("{} {name} under {label}", s.label), f, gain, path)
                    },
                    out,
                )?;
            }
        }
        return Ok(());
    };
    let (fit_k, held_k) = thickness_scales(o, per_cycle);
    for (set, scales, angles) in [
        (&mut out.fit, &fit_k, &fit_deg),
        (&mut out.held_out, &held_k, &held_deg),
    ] {
        for &k in scales {
            let stack = scaled_stack(film, k)?;
            for &deg in angles {
                let inc = Incidence::degrees(deg)?;
                let what = |part: &str| {
                    format!("{} film x{k:.3} {part} at {deg} deg under {label}", s.label)
                };
                let r = Factor::FilmReflectance(stack.clone(), inc);
                let t = Factor::FilmTransmittance(stack.clone(), inc);
                set.push(make(
                    what("reflected"),
                    vec![r],
                    b.specular(shape, s.shininess, deg),
                    Path::Specular,
                ));
                if s.transparent {
                    set.push(make(what("transmitted"), vec![t], b.env, Path::Seen));
                } else if let Some(rd) = pigment {
                    let f = vec![Factor::Reflectance(rd.clone()), t];
                    set.push(make(
                        what("over its pigment"),
                        f,
                        b.diffuse(shape, s.kd, deg),
                        Path::Diffuse,
                    ));
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::env::CoeffMap;
    use crate::spectrum::Tabulated;

    #[test]
    fn a_mixture_is_as_bright_as_the_brightest_texel_it_stands_for() {
        // A bright red cap over a dim blue sky: the red mixture carries the cap's brightness,
        // the blue one the sky's, not the map's peak.
        let map = CoeffMap::from_fn(16, |d| {
            if d[1] > 0.95 {
                [10.0, 0.0, 0.0, 0.0]
            } else {
                [0.0, 0.0, 0.5 + 0.5 * d[1].abs() as f32, 0.0]
            }
        });
        let flat = |v: f64| Tabulated::new(vec![380.0, 780.0], vec![v, v]).unwrap();
        let basis = [flat(0.2), flat(0.3), flat(0.5)];
        let reps = representative_spectra(&map, &basis, 2);
        assert_eq!(reps.len(), 2);
        let (red, blue) = (&reps[0], &reps[1]);
        assert!(
            (red.0.values()[0] - 10.0 * 0.2).abs() < 1e-6,
            "{:?}",
            red.0.values()
        );
        assert!(
            (red.1 - 10.0).abs() < 1e-6 && blue.1 < 1.0 + 1e-6,
            "{} {}",
            red.1,
            blue.1
        );
        let brightest_blue = (0..map.width * map.height)
            .map(|i| map.texel(i).nth(2).unwrap() as f64)
            .fold(0.0, f64::max);
        assert!(
            (blue.1 - brightest_blue).abs() < 1e-6,
            "{} {brightest_blue}",
            blue.1
        );
    }
}
