//! Spectral preview renderer: the paper's spectral Phong model (Eq. 1) and multilayer thin films
//! (Eq. 2-9) on analytic scenes, on the GPU (wgpu compute, WGSL) and on the CPU (rayon), from one
//! scene description.
//!
//! # The model, per pixel and wavelength
//! An orthographic camera looks down −Z (world: OpenEXR's, Y up). A ray hits the nearest sphere,
//! cylinder or quad; `N` is the normal, `V = +Z` the direction to the camera, `R_v` the mirror
//! direction of the view ray. The light is an environment plus an optional sun:
//!
//! - the environment is linear in K coefficients per direction: `L(w, lambda) = sum_j c_j(w)
//!   S_j(lambda)`. For an RGB map or a uniform light (GUIDE.md) K = 4: `S_0..2 = B_j` the fitted
//!   basis spectra of the main light and `S_3 = E` the sun's (or, for a uniform light, the main
//!   light's) SPD, all scaled to luminance Y = 1 on the render's wavelengths. For a spectral or
//!   basis map the `S_j` are the map's own spectra ([`own_spectra`]: the K spectra a basis file
//!   stores, or a spectral file's principal components), so the render does not depend on
//!   `--light`. Lighting integrals are taken in coefficient space on the CPU
//!   ([`env`](mod@env)): a diffuse irradiance map `D(N) = 1/pi int L max(N.w, 0) dw` and, per
//!   shininess `n`, a specular map `P_n(R) = int L (R.w)^n dw / int (R.w)^n dw`, both lat-long;
//!   the renderers expand the sampled coefficients with the spectra per wavelength;
//! - the sun is a directional light with irradiance `E_sun` (in units of `E`) and direction `l`;
//! - an opaque surface reflects (Eq. 1, diffuse Lambertian, specular the normalised Phong lobe
//!   so that the sun and the environment share one radiometric scale):
//!   `I = k_d R_d(lambda) T_f [D(N) + E_sun max(N.l, 0) / pi]
//!      + k_s' [P_n(R_v) + E_sun (n + 1) / (2 pi) max(R_v.l, 0)^n]`,
//!   where, with a film, `k_s'` is the film's reflectance `R_f(theta_v, lambda)` and `T_f` its
//!   transmittance (light reaching the pigment; both from [`crate::thinfilm`], unpolarised), and
//!   without a film `k_s' = k_s`, `T_f = 1`;
//! - a transparent surface (Eq. 9) is thin-walled: `I = R_f [P_n(R_v) + sun lobe] + T_f L(d)`,
//!   `L(d)` the environment behind, along the view ray `d`;
//! - `XYZ = sum_i W_i I(lambda_i) / sum_i W_y,i` over the nodes `lambda_i` of a quadrature
//!   ([`crate::quadrature`]) with a weight triple `W_i` per node: for a uniform grid
//!   `W_i = w_i cmf(lambda_i)` by the chosen integration rule, for a scene's quadrature the
//!   fitted weights (Eq. 10/11: a perfect white under the main light has Y = 1); then linear
//!   RGB by the output space's matrix. No white balance: a scene under illuminant A looks warm.
//!
//! Both backends consume the same [`prepare::Prepared`] data (f32 spectra, maps and objects); the
//! CPU computes in f64 with the thin-film module itself, the GPU in f32 with a WGSL port of it.
//!
//! # Use
//! A scene (a [`Preset`] of the paper's figures, or one's own [`Scene`]), flattened once for a
//! spectral sampling ([`prepare::Prepared`]), rendered on the CPU ([`cpu::render`]) or the GPU
//! ([`gpu::Gpu::render`]); an environment map file lights it through [`env::load`]:
//!
//! ```
//! use specmap::render::{cpu, env, prepare::Prepared, Preset, Spectral};
//! use std::path::Path;
//!
//! // The chrome-oxide ball of Fig. 6 under a sunrise photograph (converted with D65 as the
//! // main light), 24 x 24 pixels at 5 nm.
//! let (lighting, report) = env::load(Path::new("envmaps/sunrise.exr"), "D65")?;
//! assert_eq!(report.kind, "rgb");
//! let scene = Preset::Ball.scene(24, 24, "D65", Some(lighting))?;
//! let prepared = Prepared::new(&scene, &Spectral::default())?;
//! let image = cpu::render(&prepared);
//! assert_eq!(image.pixels.len(), 24 * 24);
//! # Ok::<(), specmap::error::Error>(())
//! ```
//!
//! # Modules
//! - [`presets`]: the paper's figures as scenes; [`fingerprint`]: a scene's identity for caches.
//! - [`env`](mod@env): environment lighting (pre-filtering, loading files): RGB and version-1
//!   basis files there, files of their own spectra in [`own_spectra`]; [`latlong`]: the
//!   coefficient maps; [`env_report`]: what a load found; [`radiance_limit`]: the brightest
//!   value allowed; `file_layout`: a file's layout.
//! - [`prepare`]: a scene flattened for both renderers, in [`gpu_layout`]'s records, with
//!   [`candidates`]: the objects each row and 8-pixel band can hit.
//! - [`cpu`] and [`gpu`] (with `gpu.wgsl`): the renderers; [`image`]: images and comparisons.
//! - [`plan`], [`stimuli`]: choosing a scene's quadrature (`--tolerance`); [`sweep`]: renders
//!   over spectral samplings, timed and compared.

pub mod candidates;
pub mod cpu;
pub mod env;
pub(crate) mod env_report;
mod file_layout;
pub(crate) mod fingerprint;
pub mod gpu;
pub(crate) mod gpu_layout;
pub(crate) mod image;
pub(crate) mod latlong;
pub mod own_spectra;
pub mod plan;
mod prefiltered;
pub mod prepare;
pub mod presets;
pub(crate) mod radiance_limit;
pub(crate) mod stimuli;
pub mod sweep;

pub use self::image::{compare, Comparison, Image};
pub use presets::Preset;

use crate::colorimetry::{Observer, RgbSpace};
use crate::error::{Error, Result};
use crate::spectrum::{Rule, Tabulated, WavelengthGrid};
use crate::thinfilm::{Layer, Material as Optical};
use std::sync::Arc;

/// The most layers a film may have on the GPU.
pub const MAX_LAYERS: usize = 8;

/// Where a ray goes: an orthographic window centred at `center`, `half_height` world units from
/// the centre to the top edge (the width follows the image's aspect ratio).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Centre of the window, world (x, y).
    pub center: [f64; 2],
    /// World units from the centre to the top edge.
    pub half_height: f64,
}

/// A shape, all seen by an orthographic camera looking down −Z.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// A sphere.
    Sphere {
        /// Centre, world (x, y, z).
        center: [f64; 3],
        /// Radius in world units.
        radius: f64,
    },
    /// A cylinder with its axis along X, from `center.x - half_length` to `center.x + half_length`.
    CylinderX {
        /// Centre of the axis, world (x, y, z).
        center: [f64; 3],
        /// Radius in world units.
        radius: f64,
        /// Half the length along X, in world units.
        half_length: f64,
    },
    /// A rectangle facing +Z.
    Quad {
        /// Centre, world (x, y, z).
        center: [f64; 3],
        /// Half the width (X) and half the height (Y), in world units.
        half_size: [f64; 2],
    },
}

/// Film thickness scaled linearly with world x: `scale(x)` goes from `s0` at `x0` to `s1` at
/// `x1` (held beyond), multiplying every layer's thickness (the paper's Fig. 8).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ramp {
    /// World x where the scale is `s0`.
    pub x0: f64,
    /// World x where the scale is `s1`.
    pub x1: f64,
    /// Thickness factor at `x0` and on its side beyond it.
    pub s0: f64,
    /// Thickness factor at `x1` and on its side beyond it.
    pub s1: f64,
}

impl Ramp {
    /// The thickness factor at world `x`: linear from `s0` at `x0` to `s1` at `x1`, clamped
    /// (`s0` where `x0 == x1`).
    pub fn scale(&self, x: f64) -> f64 {
        let t = if self.x1 == self.x0 {
            0.0
        } else {
            ((x - self.x0) / (self.x1 - self.x0)).clamp(0.0, 1.0)
        };
        self.s0 + (self.s1 - self.s0) * t
    }
}

/// A multilayer film: ambient, layers from the ambient side, substrate (see [`crate::thinfilm`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Film {
    /// The incident medium, on the viewer's side; must be transparent (air in the presets).
    pub ambient: Optical,
    /// The layers, from the ambient side, at most [`MAX_LAYERS`].
    pub layers: Vec<Layer>,
    /// The medium under the last layer.
    pub substrate: Optical,
}

/// A surface's optical description.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    /// Name of the surface in messages and reports.
    pub label: String,
    /// `R_d(lambda)` of the pigment; None is black.
    pub diffuse: Option<Tabulated>,
    /// Diffuse coefficient `k_d` (0..=100; 1 reflects all light).
    pub kd: f64,
    /// Specular coefficient without a film (a film's reflectance replaces it).
    pub ks: f64,
    /// Phong exponent `n`.
    pub shininess: f64,
    /// The thin film on the surface; None: a plain Phong surface.
    pub film: Option<Film>,
    /// Eq. 9: light from behind is transmitted through the film (requires a film).
    pub transparent: bool,
}

/// One object: a shape, its surface, and which [`Lighting`] of the scene lights it.
#[derive(Debug, Clone, PartialEq)]
pub struct Object {
    /// Its geometry.
    pub shape: Shape,
    /// Its optical description.
    pub surface: Surface,
    /// Index into [`Scene::lightings`] of the lighting that lights it.
    pub lighting: usize,
    /// The film's thickness ramp over world x; None: the film as given everywhere.
    pub ramp: Option<Ramp>,
    /// Whether the surface flags of `specmap render` (--film, --diffuse, --kd...) apply to it.
    pub main: bool,
}

/// The environment's radiance, in coefficient space.
#[derive(Debug, Clone)]
pub enum Environment {
    /// The same radiance in every direction: `radiance * E(lambda)`.
    Uniform {
        /// Radiance in units of the lighting's `E` spectrum.
        radiance: f64,
    },
    /// `sky * E` above the horizon, `ground * E` below, blended over `blend_deg` degrees of
    /// elevation around it.
    SkyGround {
        /// Radiance above the horizon, in units of `E`.
        sky: f64,
        /// Radiance below the horizon, in units of `E`.
        ground: f64,
        /// Width of the blend around the horizon, in degrees of elevation.
        blend_deg: f64,
    },
    /// A map in coefficient space: per texel one coefficient per spectrum of the lighting
    /// ([`LightSpectra`]: c_R, c_G, c_B on the basis and s on E, or the map's own K), from a file.
    Map(Arc<env::Maps>),
}

/// A directional light: unit direction towards the light and irradiance at normal incidence in
/// units of the lighting's `E` spectrum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sun {
    /// Unit vector towards the light, in the objects' frame (the camera's: see [`Scene::orbit`]).
    pub direction: [f64; 3],
    /// Irradiance at normal incidence, in units of the sun's SPD at Y = 1 (`E` or `sun_spd`).
    pub irradiance: f64,
}

/// The spectra a lighting's coefficients expand with.
#[derive(Debug, Clone)]
pub enum LightSpectra {
    /// The paper's: `B_j = basis_reflectance_j * light` and `E`, the fourth coefficient's SPD
    /// (the sun's for a map, the main light's for a uniform or sky-and-ground environment). At
    /// the render's wavelengths the light is scaled to luminance Y = 1 (so are the `B_j`, by the
    /// light's factor) and `E` to Y = 1 (as [`crate::envmap::convert::pixel_spectra::Engine`] does).
    Paper {
        /// The main light.
        light: Tabulated,
        /// The basis reflectances (the paper's ColorChecker red, green, blue).
        basis_reflectance: [Tabulated; 3],
        /// `E`: the SPD of the fourth coefficient and of the sun.
        e_spd: Tabulated,
        /// Label of `e_spd`.
        e_label: String,
    },
    /// A map's own spectra, in the map's radiance units (coefficient `j` multiplies
    /// `spectra[j]`, unnormalised), and the sun's SPD at luminance Y = 1 on the file's
    /// wavelengths (the sun's irradiance is in its units).
    Own {
        /// The K spectra, in the map's radiance units; coefficient `j` multiplies `spectra[j]`.
        spectra: Vec<Tabulated>,
        /// The sun's SPD, at luminance Y = 1 on the file's wavelengths.
        sun_spd: Tabulated,
        /// Label of `sun_spd` ("none" where the file has no sun).
        sun_label: String,
    },
}

/// The light of (part of) a scene: the spectra its coefficients expand with, the environment and
/// the sun.
#[derive(Debug, Clone)]
pub struct Lighting {
    /// Label of the main light (for a map, the light it was converted with).
    pub label: String,
    /// The spectra the coefficients expand with.
    pub spectra: LightSpectra,
    /// The radiance from every direction, in coefficient space.
    pub environment: Environment,
    /// The directional light; None: no sun.
    pub sun: Option<Sun>,
}

impl Lighting {
    /// A light by name (a table, `TABLE:COLUMN` or CSV), as the uniform environment with
    /// `radiance` and optionally a sun of the same SPD.
    pub fn uniform(light: &str, radiance: f64, sun: Option<Sun>) -> Result<Lighting> {
        let l = crate::data::spectrum(light)?;
        let basis = basis_reflectances()?;
        Ok(Lighting {
            label: l.label.clone(),
            spectra: LightSpectra::Paper {
                light: l.data.clone(),
                basis_reflectance: basis,
                e_spd: l.data,
                e_label: l.label,
            },
            environment: Environment::Uniform { radiance },
            sun,
        })
    }

    /// How many coefficients a texel of this lighting's maps holds.
    pub fn coefficients(&self) -> usize {
        match &self.spectra {
            LightSpectra::Paper { .. } => 4,
            LightSpectra::Own { spectra, .. } => spectra.len(),
        }
    }

    /// The label of the SPD the sun (and a uniform environment) radiates.
    pub fn sun_label(&self) -> &str {
        match &self.spectra {
            LightSpectra::Paper { e_label, .. } => e_label,
            LightSpectra::Own { sun_label, .. } => sun_label,
        }
    }
}

/// The paper's basis reflectances (ColorChecker red, green, blue).
pub fn basis_reflectances() -> Result<[Tabulated; 3]> {
    let [a, b, c] = crate::fit::PAPER_BASIS.map(crate::data::spectrum);
    Ok([a?.data, b?.data, c?.data])
}

/// A whole scene: image size, view, lightings, objects and the lighting of the background.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Name of the scene (a preset's [`Preset::name`]).
    pub name: String,
    /// Image width in pixels (at most 16384).
    pub width: usize,
    /// Image height in pixels (at most 16384).
    pub height: usize,
    /// The camera's orthographic window.
    pub view: View,
    /// The lightings, indexed by [`Object::lighting`] and [`Scene::background`]; at least one.
    pub lightings: Vec<Lighting>,
    /// The objects; a ray sees the nearest it hits.
    pub objects: Vec<Object>,
    /// The lighting whose environment is seen where rays miss.
    pub background: usize,
    /// How the background is seen.
    pub backdrop: Backdrop,
    /// Camera to world for the lightings' maps: a map is looked up in direction
    /// `orientation · d` for a direction `d` of the camera's frame ([`Scene::orbit`]; the
    /// identity by default).
    pub orientation: [[f64; 3]; 3],
    /// Whether a choice of quadrature ([`Scene::choose_quadrature`]) must hold for every
    /// orientation, not only this one: every texel of a seen map counts as shown and the sun
    /// as facing the camera (its brightest). A viewer that orbits without refitting sets it.
    pub any_orientation: bool,
}

/// The identity rotation, [`Scene::orientation`]'s default.
pub const IDENTITY: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// The camera's orbit, in degrees: `yaw` about the world's vertical (Y), then `pitch` about the
/// camera's horizontal (X). The camera then looks along
/// `(-sin yaw cos pitch, sin pitch, -cos yaw cos pitch)` in the world (down −Z at 0, 0).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Orbit {
    /// Rotation about the world's vertical (Y), in degrees.
    pub yaw_deg: f64,
    /// Rotation about the camera's horizontal (X), in degrees; positive looks up.
    pub pitch_deg: f64,
}

impl Orbit {
    /// Camera to world: `R_y(yaw) · R_x(pitch)`.
    pub fn rotation(&self) -> [[f64; 3]; 3] {
        let (sy, cy) = self.yaw_deg.to_radians().sin_cos();
        let (sp, cp) = self.pitch_deg.to_radians().sin_cos();
        // R_y = [[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]], R_x = [[1, 0, 0], [0, cp, -sp], [0, sp, cp]].
        [
            [cy, sy * sp, sy * cp],
            [0.0, cp, -sp],
            [-sy, cy * sp, cy * cp],
        ]
    }
}

/// `m · v`.
pub fn rotate(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

/// `mᵀ · v` (the inverse of a rotation).
pub fn rotate_back(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|c| m[0][c] * v[0] + m[1][c] * v[1] + m[2][c] * v[2])
}

/// What a ray that misses every object sees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Backdrop {
    /// The background lighting's environment through a pinhole at the image centre looking
    /// down −Z with this vertical field of view (the objects stay orthographic): a map shows
    /// as a photograph would.
    Environment {
        /// Vertical field of view of the pinhole, in degrees.
        fov_deg: f64,
    },
    /// The environment straight down −Z: one colour.
    Flat,
    /// Black.
    Hidden,
}

impl Backdrop {
    /// The previews' default: the environment through a 60 degree field of view.
    pub const DEFAULT: Backdrop = Backdrop::Environment { fov_deg: 60.0 };
}

/// How spectra become colours: grid, integration rule, observer, output RGB space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spectral {
    /// The wavelengths the render samples, in nm.
    pub grid: WavelengthGrid,
    /// The integration rule over `grid`.
    pub rule: Rule,
    /// The colour-matching functions.
    pub observer: Observer,
    /// The output linear RGB space.
    pub space: RgbSpace,
}

impl Spectral {
    /// `samples` wavelengths evenly over 380..780 nm (at least 2).
    pub fn samples(samples: usize) -> Result<Spectral> {
        if samples < 2 {
            return Err(Error::invalid(format!(
                "{samples} wavelength sample(s): at least 2 are needed"
            )));
        }
        Ok(Spectral {
            grid: WavelengthGrid::new(380.0, 780.0, 400.0 / (samples - 1) as f64)?,
            ..Spectral::default()
        })
    }
    /// 380..780 nm at `step_nm` (the step must divide 400 nm).
    pub fn step(step_nm: f64) -> Result<Spectral> {
        Ok(Spectral {
            grid: WavelengthGrid::new(380.0, 780.0, step_nm)?,
            ..Spectral::default()
        })
    }
}

impl Default for Spectral {
    /// 380..780 nm at 5 nm, Riemann (the paper's rule), CIE 1931, sRGB.
    fn default() -> Self {
        Spectral {
            grid: WavelengthGrid::new(380.0, 780.0, 5.0).expect("a valid grid"),
            rule: Rule::Riemann,
            observer: Observer::Cie1931,
            space: RgbSpace::SRGB,
        }
    }
}

/// Which renderer computes the image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// [`cpu::render`], in f64 on the CPU.
    Cpu,
    /// [`gpu::Gpu::render`], in f32 on the GPU.
    Gpu,
}

impl std::fmt::Display for Backend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Backend::Cpu => "cpu",
            Backend::Gpu => "gpu",
        })
    }
}

impl Scene {
    /// The camera orbits the scene as a turntable would show it: the objects turn with the
    /// camera, the lightings (maps and suns) stay with the world. Sets [`Scene::orientation`]
    /// and turns each sun into the camera's frame; for a sphere this is exactly the camera
    /// orbiting. Applied to a scene as built (its orientation the identity).
    pub fn orbit(&mut self, orbit: Orbit) {
        let r = orbit.rotation();
        self.orientation = r;
        for l in &mut self.lightings {
            if let Some(s) = &mut l.sun {
                s.direction = rotate_back(&r, s.direction);
            }
        }
    }

    /// The scene a choice of quadrature must hold for when the camera may turn and each main
    /// film's thickness may scale from `scales.0` to `scales.1` (what `specmap view` fits, so
    /// that orbiting and a thickness drag inside the range need no refit):
    /// [`Scene::any_orientation`] set, and each main object's film without a ramp given one
    /// over those scales (the stimuli sample a ramp's whole range).
    pub fn for_any_view(&mut self, scales: (f64, f64)) {
        self.any_orientation = true;
        self.for_thicknesses(scales);
    }

    /// The scene a choice of quadrature must hold for when each main film's thickness may scale
    /// from `scales.0` to `scales.1` (a thickness sweep's frames): each main object's film
    /// without a ramp given one over those scales.
    pub fn for_thicknesses(&mut self, scales: (f64, f64)) {
        let half = self.view.half_height * self.width as f64 / self.height as f64;
        let (x0, x1) = (self.view.center[0] - half, self.view.center[0] + half);
        for o in self.objects.iter_mut().filter(|o| o.main) {
            if o.surface.film.is_some() && o.ramp.is_none() && scales.0 != scales.1 {
                o.ramp = Some(Ramp {
                    x0,
                    x1,
                    s0: scales.0,
                    s1: scales.1,
                });
            }
        }
    }

    /// Checks the scene's consistency (indices, sizes, films) before any work is done.
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::invalid(format!(
                "image size {}x{} is empty",
                self.width, self.height
            )));
        }
        if self.width > 16384 || self.height > 16384 {
            return Err(Error::invalid(format!(
                "image size {}x{}: at most 16384 pixels a side",
                self.width, self.height
            )));
        }
        if !(self.view.half_height.is_finite() && self.view.half_height > 0.0) {
            return Err(Error::invalid("the view's half height must be positive"));
        }
        if self.lightings.is_empty() {
            return Err(Error::invalid("a scene needs at least one lighting"));
        }
        if self.background >= self.lightings.len() {
            return Err(Error::invalid("the background lighting does not exist"));
        }
        for (i, o) in self.objects.iter().enumerate() {
            let s = &o.surface;
            let what = format!("object {} ({})", i + 1, s.label);
            if o.lighting >= self.lightings.len() {
                return Err(Error::invalid(format!(
                    "{what}: lighting {} does not exist",
                    o.lighting
                )));
            }
            if !(s.shininess.is_finite() && s.shininess >= 0.0 && s.shininess <= 1e5) {
                return Err(Error::invalid(format!(
                    "{what}: shininess {} must be between 0 and 1e5",
                    s.shininess
                )));
            }
            for (name, v) in [("kd", s.kd), ("ks", s.ks)] {
                // Phong's factors are reflectances: 1 is a perfect reflector; 100 leaves room
                // for a brighter preview without overflowing f32 radiance.
                if !(v.is_finite() && (0.0..=100.0).contains(&v)) {
                    return Err(Error::invalid(format!(
                        "{what}: {name} {v} must be between 0 and 100 (1 reflects all light)"
                    )));
                }
            }
            if s.transparent && s.film.is_none() {
                return Err(Error::invalid(format!(
                    "{what}: a transparent surface needs a film (at least a substrate index)"
                )));
            }
            if let Some(f) = &s.film {
                if f.layers.len() > MAX_LAYERS {
                    return Err(Error::invalid(format!(
                        "{what}: {} layers; the renderer handles at most {MAX_LAYERS}",
                        f.layers.len()
                    )));
                }
            }
            if let Some(r) = &o.ramp {
                if ![r.x0, r.x1, r.s0, r.s1].iter().all(|v| v.is_finite())
                    || r.s0 < 0.0
                    || r.s1 < 0.0
                {
                    return Err(Error::invalid(format!("{what}: invalid thickness ramp")));
                }
            }
        }
        Ok(())
    }

    /// Renders on the CPU.
    pub fn render_cpu(&self, spectral: &Spectral) -> Result<Image> {
        let p = prepare::Prepared::new(self, spectral)?;
        Ok(cpu::render(&p))
    }

    /// Renders on the CPU with the quadrature `q`, in the output space `space`.
    pub fn render_cpu_with(
        &self,
        q: &crate::quadrature::Quadrature,
        space: RgbSpace,
    ) -> Result<Image> {
        let p = prepare::Prepared::with_quadrature(self, q, space)?;
        Ok(cpu::render(&p))
    }

    /// The pixels `at` ((x, y) each) of [`Scene::render_cpu_with`]'s image, in order.
    pub fn render_cpu_pixels(
        &self,
        q: &crate::quadrature::Quadrature,
        space: RgbSpace,
        at: &[[usize; 2]],
    ) -> Result<Vec<[f32; 3]>> {
        let p = prepare::Prepared::with_quadrature(self, q, space)?;
        Ok(cpu::render_pixels(&p, at))
    }
}

#[cfg(test)]
mod orbit_tests {
    use super::*;

    #[test]
    fn an_orbit_is_a_rotation_whose_view_direction_is_the_documented_one() {
        let o = Orbit {
            yaw_deg: 37.0,
            pitch_deg: -21.0,
        };
        let r = o.rotation();
        for i in 0..3 {
            for j in 0..3 {
                let d: f64 = (0..3).map(|k| r[k][i] * r[k][j]).sum();
                assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12);
            }
        }
        let (y, p) = (37f64.to_radians(), (-21f64).to_radians());
        let view = rotate(&r, [0.0, 0.0, -1.0]);
        let want = [-y.sin() * p.cos(), p.sin(), -y.cos() * p.cos()];
        for k in 0..3 {
            assert!((view[k] - want[k]).abs() < 1e-12, "{view:?} {want:?}");
        }
        let v = [0.3, -0.5, 0.81];
        let back = rotate_back(&r, rotate(&r, v));
        assert!((0..3).all(|k| (back[k] - v[k]).abs() < 1e-12));
    }

    /// The sun turns into the camera's frame: the world's sun direction seen from the camera.
    #[test]
    fn orbiting_turns_the_sun_into_the_cameras_frame() {
        let sun = Sun {
            direction: [0.0, 0.0, -1.0],
            irradiance: 1.0,
        };
        let mut s = Preset::Ball.scene(8, 8, "D65", None).unwrap();
        s.lightings[0].sun = Some(sun);
        // Turned 180 degrees about Y, the camera looks along +Z: a sun along -Z is behind it.
        s.orbit(Orbit {
            yaw_deg: 180.0,
            pitch_deg: 0.0,
        });
        let d = s.lightings[0].sun.unwrap().direction;
        assert!((d[2] - 1.0).abs() < 1e-12, "{d:?}");
    }
}
