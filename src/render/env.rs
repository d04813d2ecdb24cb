//! Environment light in coefficient space: the sun taken out as a directional light, the
//! diffuse and specular pre-filtering both renderers sample, and loading maps from RGB, `basis`
//! and spectral OpenEXR files. The maps themselves are [`super::latlong`]'s (re-exported here,
//! as are [`EnvReport`] and [`MAX_RADIANCE`]).

pub use super::env_report::{EnvReport, SUN_SPD};
pub use super::latlong::{
    bilinear, direction, sample, sample_into, solid_angle, CoeffMap, Maps, BACKGROUND_ROWS,
    SOURCE_ROWS,
};
pub use super::radiance_limit::MAX_RADIANCE;

use super::file_layout::layout_of;
use super::own_spectra::{self, Spectra};
use super::prefiltered::Lobe;
use super::radiance_limit::too_bright;
use super::{Environment, LightSpectra, Lighting, Sun};
use crate::colorimetry::{Observer, RgbSpace};
use crate::envmap::files::{self, AttrValue};
use crate::envmap::layout::{EnvMap, Layout};
use crate::envmap::scene::sun::{find_sun, SunSettings};
use crate::envmap::RgbImage;
use crate::error::{Error, Result};
use crate::fit::{self, FitInput, Mode, Upsampler};
use crate::spectrum::{Rule, Tabulated, WavelengthGrid};
use rayon::prelude::*;
use std::path::Path;
use std::sync::Arc;

/// Rows of the diffuse irradiance map.
pub const DIFFUSE_ROWS: usize = 16;
/// Rows of each specular map.
pub const SPECULAR_ROWS: usize = 32;

/// What both renderers sample for one lighting: the environment itself (seen where rays miss
/// and behind transparent objects), its diffuse irradiance over pi, and one specular map per
/// shininess.
#[derive(Debug, Clone)]
pub struct Filtered {
    /// The environment itself, seen where rays miss and behind transparent objects.
    pub background: CoeffMap,
    /// Cosine-weighted mean radiance per normal direction: irradiance over pi, `D(N)`.
    pub diffuse: CoeffMap,
    /// `(shininess, map)` in the order asked for.
    pub specular: Vec<(f64, CoeffMap)>,
}

/// Pre-filters an environment for the given shininess values.
pub fn prefilter(env: &Environment, shininess: &[f64]) -> Filtered {
    let (source, seen): (Arc<CoeffMap>, Option<&CoeffMap>) = match env {
        Environment::Uniform { radiance } => {
            let c = CoeffMap::constant([0.0, 0.0, 0.0, *radiance as f32]);
            return Filtered {
                background: c.clone(),
                diffuse: c.clone(),
                specular: shininess.iter().map(|&n| (n, c.clone())).collect(),
            };
        }
        Environment::SkyGround {
            sky,
            ground,
            blend_deg,
        } => {
            let (sky, ground) = (*sky, *ground);
            let b = blend_deg.to_radians().sin().max(1e-6);
            let m = CoeffMap::from_fn(SOURCE_ROWS, |d| {
                let t = ((d[1] / b) * 0.5 + 0.5).clamp(0.0, 1.0);
                let t = t * t * (3.0 - 2.0 * t);
                [0.0, 0.0, 0.0, (ground + (sky - ground) * t) as f32]
            });
            (Arc::new(m), None)
        }
        Environment::Map(m) => (Arc::new(m.light.clone()), Some(&m.seen)),
    };
    let src = &*source;
    let dirs: Vec<([f64; 3], f64)> = (0..src.width * src.height)
        .map(|i| {
            let (x, y) = (i % src.width, i / src.width);
            (
                direction(src.width, src.height, x, y),
                solid_angle(src.width, src.height, y),
            )
        })
        .collect();
    // Cosine-weighted mean radiance = irradiance / pi (normalised by the discrete weights, so a
    // constant map stays exactly constant).
    let g = src.groups;
    // A map's filtered maps are kept while it lives (a viewer prepares its scene again for
    // every film it shows); a sky-and-ground environment's are made each time.
    let kept = |lobe: Lobe, make: &dyn Fn() -> CoeffMap| match env {
        Environment::Map(m) => super::prefiltered::get_or_make(m, lobe, make),
        _ => make(),
    };
    let diffuse = kept(Lobe::Diffuse, &|| {
        CoeffMap::from_fn_groups(DIFFUSE_ROWS, g, |n, out| {
            filtered(src, &dirs, n, |c| c.max(0.0) as f32 as f64, out)
        })
    });
    let specular = shininess
        .iter()
        .map(|&s| {
            let m = kept(Lobe::Specular(s.to_bits()), &|| {
                CoeffMap::from_fn_groups(SPECULAR_ROWS, g, |r, out| {
                    filtered(
                        src,
                        &dirs,
                        r,
                        |c| if c > 0.0 { c.powf(s) } else { 0.0 },
                        out,
                    )
                })
            });
            (s, m)
        })
        .collect();
    Filtered {
        background: seen.cloned().unwrap_or_else(|| src.clone()),
        diffuse,
        specular,
    }
}

/// `sum c_i w_i / sum w_i` with `w_i = lobe(d . w_i) * omega_i`, into `out` (the source's
/// groups); the source's own value where the lobe is too narrow for any texel.
fn filtered(
    src: &CoeffMap,
    dirs: &[([f64; 3], f64)],
    d: [f64; 3],
    lobe: impl Fn(f64) -> f64,
    out: &mut [[f32; 4]],
) {
    let g = src.groups;
    let mut acc = vec![0.0f64; 4 * g];
    let mut wsum = 0.0;
    for (t, (w, omega)) in src.texels.chunks_exact(g).zip(dirs) {
        let c = d[0] * w[0] + d[1] * w[1] + d[2] * w[2];
        let wt = lobe(c) * omega;
        if wt > 0.0 {
            wsum += wt;
            for (a, v) in acc.iter_mut().zip(t.iter().flatten()) {
                *a += wt * *v as f64;
            }
        }
    }
    let value = if wsum > 0.0 && wsum.is_finite() {
        acc.iter().map(|v| v / wsum).collect()
    } else {
        src.sample(d)
    };
    for (k, v) in value.iter().enumerate() {
        out[k / 4][k % 4] = *v as f32;
    }
}

/// Loads an environment map file as a lighting: an RGB EXR/HDR (converted on the fly with
/// `light` as the main light, exact mode, the sun found and given D65), or a file from
/// `specmap convert`, lit by the spectra it holds whatever `light` says
/// ([`super::own_spectra`]: a basis EXR of either version, or a spectral EXR projected onto its own
/// principal components). The sun becomes a directional light and leaves the map.
///
/// ```
/// use specmap::render::env;
/// use std::path::Path;
///
/// let (lighting, report) = env::load(Path::new("envmaps/forest.exr"), "D65")?;
/// println!("{} {:?}: sun {:?}", report.kind, report.input_size, report.sun_direction);
/// assert_eq!(lighting.coefficients(), report.spectra);
/// # Ok::<(), specmap::error::Error>(())
/// ```
pub fn load(path: &Path, light: &str) -> Result<(Lighting, EnvReport)> {
    let channels = exr_channels(path).unwrap_or_default();
    let has = |n: &str| channels.iter().any(|c| c == n);
    if has("k00") {
        own_spectra::load_basis_k(path)
    } else if has("c_R") && has("c_G") && has("c_B") {
        load_basis(path)
    } else if channels
        .iter()
        .any(|c| files::parse_spectral_channel_name(c).is_some())
    {
        own_spectra::load_spectral(path, Spectra::Own)
    } else {
        load_rgb(path, light)
    }
}

fn exr_channels(path: &Path) -> Option<Vec<String>> {
    let meta = exr::meta::MetaData::read_from_file(path, false).ok()?;
    Some(
        meta.headers
            .first()?
            .channels
            .list
            .iter()
            .map(|c| c.name.to_string())
            .collect(),
    )
}

fn fit_upsampler(light: &str, basis: [&str; 3], space: RgbSpace) -> Result<(Upsampler, String)> {
    let grid = WavelengthGrid::new(380.0, 780.0, 5.0)?;
    let input = FitInput::from_names(light, basis, &grid, Observer::Cie1931, Rule::Riemann, space)?;
    let f = fit::fit(&input, Mode::Exact)?;
    Ok((Upsampler::new(&f, &space), f.light))
}

/// The paper's lighting of a light and basis by name, its sun given [`SUN_SPD`].
fn paper_lighting(light: &str, basis: [&str; 3], env: Maps, sun: Option<Sun>) -> Result<Lighting> {
    let l = crate::data::spectrum(light)?;
    let [a, b, c] = basis.map(crate::data::spectrum);
    let e = crate::data::spectrum(SUN_SPD)?;
    Ok(Lighting {
        label: l.label,
        spectra: LightSpectra::Paper {
            light: l.data,
            basis_reflectance: [a?.data, b?.data, c?.data],
            e_spd: e.data,
            e_label: e.label,
        },
        environment: Environment::Map(Arc::new(env)),
        sun,
    })
}

/// NaN, infinite and negative values become 0 (as `convert` does). Values beyond
/// [`MAX_RADIANCE`] are an error naming the first one: f32 spectral arithmetic would overflow.
fn sanitize(path: &Path, img: &mut RgbImage) -> Result<()> {
    let w = img.width.max(1);
    for (i, p) in img.pixels.iter_mut().enumerate() {
        for v in p.iter_mut() {
            if !v.is_finite() || *v < 0.0 {
                *v = 0.0;
            } else if *v as f64 > MAX_RADIANCE {
                return Err(too_bright(path, i % w, i / w, *v as f64));
            }
        }
    }
    Ok(())
}

/// Sum of `s * omega` and the energy-weighted mean direction of the pixels `s` (a value per
/// pixel of `map`).
fn directional(map: &EnvMap, s: &[f64]) -> Option<Sun> {
    let w = map.image.width;
    let (mut e, mut d) = (0.0, [0.0f64; 3]);
    for (i, &v) in s.iter().enumerate() {
        if v > 0.0 {
            let (x, y) = (i % w, i / w);
            let (Some(dir), omega) = (map.direction(x, y), map.solid_angle(x, y)) else {
                continue;
            };
            e += v * omega;
            for k in 0..3 {
                d[k] += v * omega * dir[k];
            }
        }
    }
    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    (e > 0.0 && n > 0.0).then(|| Sun {
        direction: d.map(|v| v / n),
        irradiance: e,
    })
}

/// Resamples a map (any layout) to the renderer's lat-long of `rows` rows and expands each
/// texel with `f`.
fn to_coefficients(
    map: &EnvMap,
    rows: usize,
    f: &(impl Fn([f32; 3]) -> [f64; 3] + Sync),
) -> CoeffMap {
    let ll = map.resample(Layout::LatLong, rows);
    let texels = ll
        .image
        .pixels
        .par_iter()
        .map(|&p| {
            let c = f(p);
            [c[0] as f32, c[1] as f32, c[2] as f32, 0.0]
        })
        .collect();
    CoeffMap {
        width: ll.image.width,
        height: ll.image.height,
        groups: 1,
        texels,
    }
}

/// The lighting's map of `map` and the background's of `seen` (the same map with its sun), each
/// texel expanded with `f`; the background at most as fine as the map.
fn maps(map: &EnvMap, seen: &EnvMap, f: impl Fn([f32; 3]) -> [f64; 3] + Sync) -> Maps {
    Maps {
        light: to_coefficients(map, SOURCE_ROWS, &f),
        seen: to_coefficients(seen, seen_rows(seen), &f),
    }
}

fn seen_rows(map: &EnvMap) -> usize {
    let rows = (map.used_pixels() as f64 / 2.0).sqrt() as usize;
    rows.clamp(SOURCE_ROWS, BACKGROUND_ROWS)
}

/// The map, its size and its RGB space (its `chromaticities`, else sRGB as OpenEXR has it).
fn read_map(path: &Path) -> Result<(EnvMap, [usize; 2], RgbSpace)> {
    let img = files::read_rgb(path, None)?;
    let space = match img.chromaticities {
        Some(c) => RgbSpace::from_chromaticities(c)
            .map_err(|e| Error::invalid(format!("{}: {e}", path.display())))?,
        None => RgbSpace::SRGB,
    };
    let size = [img.image.width, img.image.height];
    let layout = layout_of(path, img.image.width, img.image.height, img.envmap)?;
    let mut image = img.image;
    sanitize(path, &mut image)?;
    let map = EnvMap::new(layout, image)
        .map_err(|e| Error::invalid(format!("{}: {e}", path.display())))?;
    Ok((map, size, space))
}

fn load_rgb(path: &Path, light: &str) -> Result<(Lighting, EnvReport)> {
    let (mut map, input_size, space) = read_map(path)?;
    let seen = map.clone();
    let search = find_sun(&map, &space, &SunSettings::default());
    let m = space.to_xyz_matrix();
    let y_row = [m[(1, 0)], m[(1, 1)], m[(1, 2)]];
    let mut s = vec![0.0; map.image.pixels.len()];
    if let Some(sun) = search.sun() {
        for &i in &sun.pixels {
            let p = map.image.pixels[i];
            s[i] = (0..3).map(|k| y_row[k] * p[k] as f64).sum::<f64>().max(0.0);
            map.image.pixels[i] = [0.0; 3];
        }
    }
    let sun = directional(&map, &s);
    let basis = fit::PAPER_BASIS;
    let (up, light_label) = fit_upsampler(light, basis, space)?;
    let coeffs = maps(&map, &seen, |p| {
        up.coefficients([p[0] as f64, p[1] as f64, p[2] as f64])
    });
    let report = EnvReport {
        file: path.display().to_string(),
        kind: "rgb",
        input_size,
        light: light_label,
        light_used: true,
        sun_spd: SUN_SPD.into(),
        sun_direction: sun.map(|s| s.direction),
        sun_irradiance: sun.map(|s| s.irradiance),
        spectra: 4,
        projection: None,
    };
    Ok((paper_lighting(light, basis, coeffs, sun)?, report))
}

/// The text attribute `name`, if there is one.
fn text_attr(attrs: &[(String, AttrValue)], name: &str) -> Option<String> {
    attrs.iter().find_map(|(n, v)| match v {
        AttrValue::Text(t) if n == name => Some(t.clone()),
        _ => None,
    })
}

/// A version-1 basis file's first layer, as flat samples.
type FlatLayer = exr::image::Layer<exr::image::AnyChannels<exr::image::FlatSamples>>;

/// Reads the four channels of a `basis` EXR (version 1) into two RGB maps (c and s) of its
/// layout: a pipeline of reading the layer, its header, its pixels, its maps and its spectra.
fn load_basis(path: &Path) -> Result<(Lighting, EnvReport)> {
    use exr::prelude::read_first_flat_layer_from_file;
    let image = read_first_flat_layer_from_file(path).map_err(|e| {
        Error::invalid(format!(
            "{}: reading the basis OpenEXR: {e}",
            path.display()
        ))
    })?;
    let layer = &image.layer_data;
    let (w, h) = (layer.size.0, layer.size.1);
    let channels = V1Channels::read(path, layer)?;
    let header = V1Header::read(path, layer)?;
    let layout = v1_layout(path, layer, w, h)?;
    let (c_img, s) = channels.pixels(path, header.scale, w, h)?;
    let (coeffs, sun) = v1_maps(path, layout, c_img, &s)?;
    let (lit, sun_label) = header.lighting(path, layer, coeffs, sun)?;
    let report = EnvReport {
        file: path.display().to_string(),
        kind: "basis",
        input_size: [w, h],
        light: header.light,
        light_used: false,
        sun_spd: sun_label,
        sun_direction: sun.map(|s| s.direction),
        sun_irradiance: sun.map(|s| s.irradiance),
        spectra: 4,
        projection: None,
    };
    Ok((lit, report))
}

/// A version-1 file's channels: `c_R`, `c_G`, `c_B` and the sun's (zero where it has none).
struct V1Channels {
    c: [Vec<f32>; 3],
    sun: Vec<f32>,
}

impl V1Channels {
    /// The channels of `layer`: an error naming the first colour channel missing.
    fn read(path: &Path, layer: &FlatLayer) -> Result<V1Channels> {
        let channel = |name: &str| flat_channel(path, layer, name);
        let (cr, cg, cb) = (channel("c_R")?, channel("c_G")?, channel("c_B")?);
        let sun = channel("sun").unwrap_or_else(|_| vec![0.0; layer.size.0 * layer.size.1]);
        Ok(V1Channels {
            c: [cr, cg, cb],
            sun,
        })
    }

    /// The coefficients times the exposure's `scale` (non-finite ones black) and the sun's
    /// values (non-negative); an error at a sun overflowed in half floats or a value beyond
    /// [`MAX_RADIANCE`].
    fn pixels(&self, path: &Path, scale: f32, w: usize, h: usize) -> Result<(RgbImage, Vec<f64>)> {
        let [cr, cg, cb] = &self.c;
        let mut c_img = RgbImage::new(w, h);
        let mut s = vec![0.0; w * h];
        for i in 0..w * h {
            c_img.pixels[i] = [cr[i] * scale, cg[i] * scale, cb[i] * scale];
            // The version-1 writer stored the sun channel as given, unscaled by EV (as a mask
            // is): a sun beyond half floats' range is infinite there, and lost.
            let v = self.sun[i] as f64;
            if v.is_infinite() {
                return Err(Error::invalid(format!(
                    "{}: pixel ({}, {}) of the sun channel overflowed half floats; convert the \
                     map again (--format basis now writes the K-spectrum form, which scales it)",
                    path.display(),
                    i % w,
                    i / w
                )));
            }
            s[i] = if v.is_finite() { v.max(0.0) } else { 0.0 };
            if !c_img.pixels[i].iter().all(|v| v.is_finite()) {
                c_img.pixels[i] = [0.0; 3];
            }
            let peak = c_img.pixels[i]
                .iter()
                .fold(s[i], |m, &v| m.max((v as f64).abs()));
            if peak > MAX_RADIANCE {
                return Err(too_bright(path, i % w, i / w, peak));
            }
        }
        Ok((c_img, s))
    }
}

/// Channel `name` of `layer` as f32, whatever its sample type.
fn flat_channel(path: &Path, layer: &FlatLayer, name: &str) -> Result<Vec<f32>> {
    use exr::image::FlatSamples;
    let c = layer
        .channel_data
        .list
        .iter()
        .find(|c| c.name.to_string() == name)
        .ok_or_else(|| Error::invalid(format!("{}: no channel {name}", path.display())))?;
    Ok(match &c.sample_data {
        FlatSamples::F16(v) => v.iter().map(|x| x.to_f32()).collect(),
        FlatSamples::F32(v) => v.clone(),
        FlatSamples::U32(v) => v.iter().map(|&x| x as f32).collect(),
    })
}

/// What a version-1 file's header says: its light, the names of its basis, its exposure.
struct V1Header {
    light: String,
    basis_names: Vec<String>,
    /// `2^EV` (1 without `EV`).
    scale: f32,
}

impl V1Header {
    /// The header of `layer`: an error without `specmap.light` or with a basis not of three.
    fn read(path: &Path, layer: &FlatLayer) -> Result<V1Header> {
        use exr::meta::attribute::AttributeValue;
        let mut attrs = Vec::new();
        for (name, value) in layer.attributes.other.iter() {
            if let AttributeValue::Text(t) = value {
                attrs.push((name.to_string(), AttrValue::Text(t.to_string())));
            }
        }
        let ev =
            layer
                .attributes
                .other
                .iter()
                .find_map(|(n, v)| match (n.to_string().as_str(), v) {
                    ("EV", AttributeValue::F32(x)) => Some(*x as f64),
                    ("EV", AttributeValue::F64(x)) => Some(*x),
                    _ => None,
                });
        let scale = ev.map(|e| e.exp2()).unwrap_or(1.0) as f32;
        let light = text_attr(&attrs, "specmap.light").ok_or_else(|| {
            Error::invalid(format!(
                "{}: a basis map needs the specmap.light attribute that `specmap convert \
                 --format basis` writes",
                path.display()
            ))
        })?;
        let basis_names: Vec<String> = text_attr(&attrs, "specmap.basis")
            .map(|b| b.split(',').map(String::from).collect())
            .unwrap_or_else(|| fit::PAPER_BASIS.map(String::from).to_vec());
        if basis_names.len() != 3 {
            return Err(Error::invalid(format!(
                "{}: specmap.basis must name three spectra",
                path.display()
            )));
        }
        Ok(V1Header {
            light,
            basis_names,
            scale,
        })
    }

    /// The lighting of the maps: the spectra the file stores (the ones its pixels were made
    /// of), else the light and basis by name, and the label of its sun's SPD.
    fn lighting(
        &self,
        path: &Path,
        layer: &FlatLayer,
        coeffs: Maps,
        sun: Option<Sun>,
    ) -> Result<(Lighting, String)> {
        let Some((mut spectra, sun_spd)) = v1_stored_spectra(layer) else {
            let b = &self.basis_names;
            let names = [&b[0], &b[1], &b[2]].map(|s| s.trim());
            let lit = paper_lighting(&self.light, names, coeffs, sun).map_err(|e| {
                Error::invalid(format!(
                    "{}: the map's light or basis ({}; {}) is not a known spectrum: {e}",
                    path.display(),
                    self.light,
                    b.join(", ")
                ))
            })?;
            return Ok((lit, SUN_SPD.to_string()));
        };
        let label = "the file's sunSPD".to_string();
        spectra.push(sun_spd.clone());
        let lit = Lighting {
            label: self.light.clone(),
            spectra: LightSpectra::Own {
                spectra,
                sun_spd,
                sun_label: label.clone(),
            },
            environment: Environment::Map(Arc::new(coeffs)),
            sun,
        };
        Ok((lit, label))
    }
}

/// The layout of a `w x h` version-1 file: its `envmap` attribute's, else the one its size
/// says.
fn v1_layout(path: &Path, layer: &FlatLayer, w: usize, h: usize) -> Result<Layout> {
    layout_of(path, w, h, files::envmap_attr(&layer.attributes))
}

/// The lighting's and the background's maps of the coefficients `c_img` and the sun `s` (a
/// value per pixel), and the sun as a directional light. Coefficients resample linearly
/// (negative ones included: EnvMap's filter is linear). The background shows the sun: its
/// pixels' fourth coefficient, on the sun's SPD.
fn v1_maps(path: &Path, layout: Layout, c_img: RgbImage, s: &[f64]) -> Result<(Maps, Option<Sun>)> {
    let bad = |e| Error::invalid(format!("{}: {e}", path.display()));
    let (w, h) = (c_img.width, c_img.height);
    let map = EnvMap::new(layout, c_img).map_err(bad)?;
    let sun = directional(&map, s);
    let mut coeffs = maps(&map, &map, |p| [p[0] as f64, p[1] as f64, p[2] as f64]);
    let mut sun_img = RgbImage::new(w, h);
    for (p, v) in sun_img.pixels.iter_mut().zip(s) {
        p[0] = *v as f32;
    }
    let sun_map = EnvMap::new(layout, sun_img).map_err(bad)?;
    let sun_seen = sun_map.resample(Layout::LatLong, coeffs.seen.height);
    for (t, p) in coeffs.seen.texels.iter_mut().zip(&sun_seen.image.pixels) {
        t[3] = p[0];
    }
    Ok((coeffs, sun))
}

/// The three basis spectra and the sun's SPD (D65 without one) a version-1 file stores, if it
/// stores its wavelengths and basis (files written before they were stored have names only).
fn v1_stored_spectra(layer: &FlatLayer) -> Option<(Vec<Tabulated>, Tabulated)> {
    let floats = |name: &str| {
        layer
            .attributes
            .other
            .iter()
            .find_map(|(n, v)| (*n == *name).then(|| files::attr_from_exr(v)).flatten())
            .and_then(|v| match v {
                AttrValue::F32Vec(x) => Some(x.iter().map(|&v| v as f64).collect::<Vec<_>>()),
                _ => None,
            })
    };
    let wl = floats("specmap.wavelengths")?;
    let tab = |v: Vec<f64>| Tabulated::new(wl.clone(), v).ok();
    let b: Option<Vec<Tabulated>> = (0..3)
        .map(|j| tab(floats(&format!("specmap.basis{j}"))?))
        .collect();
    let sun = floats("specmap.sunSPD").and_then(tab).or_else(|| {
        let d65 = crate::data::spectrum(SUN_SPD).ok()?.data;
        Some(d65)
    })?;
    Some((b?, sun))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prefiltering_keeps_a_constant_environment_constant() {
        let env = Environment::SkyGround {
            sky: 0.7,
            ground: 0.7,
            blend_deg: 10.0,
        };
        let f = prefilter(&env, &[0.0, 50.0]);
        for m in std::iter::once(&f.diffuse).chain(f.specular.iter().map(|(_, m)| m)) {
            assert!(m.texels.iter().all(|t| (t[3] - 0.7).abs() < 1e-5));
        }
    }
}
