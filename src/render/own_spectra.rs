//! Lighting from the spectra a map holds: a spectral OpenEXR (from `specmap convert` or any other
//! tool) or a basis OpenEXR of the K-spectrum form, whatever `--light` says.
//!
//! A spectral file's pixels are averaged into the renderer's lat-long ([`SOURCE_ROWS`] rows;
//! each pixel adds its spectrum times its solid angle to the texel its centre falls in), the sun's
//! pixels apart: they become the directional light, with the mean of their own spectra as its
//! SPD. The texels' spectra are then projected onto their own principal components
//! ([`crate::envmap::convert::own_basis`]), keeping each texel's colour: K coefficients per texel and K
//! spectra, exact for what `convert` writes (its spectra span a few dimensions), within a stated
//! share for a foreign file. [`Spectra::Full`] keeps every band instead (K = N, no projection):
//! the reference the projection is tested against.

use super::env_report::{EnvReport, SUN_SPD};
use super::file_layout::layout_of;
use super::latlong::{self, CoeffMap, Maps, BACKGROUND_ROWS, SOURCE_ROWS};
use super::radiance_limit::{too_bright, MAX_RADIANCE};
use super::{Environment, LightSpectra, Lighting, Sun};
use crate::colorimetry::RgbSpace;
use crate::envmap::convert::own_basis::{
    BandColour as Colour, Moments, OwnBasis, Projection, DEFAULT_DISCARD, MAX_K,
};
use crate::envmap::files::{self, AttrValue};
use crate::envmap::layout::{EnvMap, Layout};
use crate::envmap::scene::sun::{find_sun, SunSettings};
use crate::envmap::RgbImage;
use crate::error::{Error, Result};
use crate::spectrum::Tabulated;
use std::f64::consts::PI;
use std::path::Path;
use std::sync::Arc;

/// Which spectra a spectral file's texels expand with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spectra {
    /// Its own principal components (what `specmap render --env` does).
    Own,
    /// Every band (K = N): no projection, the CPU reference.
    Full,
}

/// Per-pixel values averaged into a lat-long of `rows` rows by solid angle.
struct Texels {
    w: usize,
    h: usize,
    per: usize,
    acc: Vec<f64>,
    weight: Vec<f64>,
}

impl Texels {
    fn new(rows: usize, per: usize) -> Texels {
        let (w, h) = (2 * rows, rows);
        Texels {
            w,
            h,
            per,
            acc: vec![0.0; w * h * per],
            weight: vec![0.0; w * h],
        }
    }

    fn index(&self, d: [f64; 3]) -> usize {
        let u = 0.5 - d[0].atan2(d[2]) / (2.0 * PI);
        let v = d[1].clamp(-1.0, 1.0).acos() / PI;
        let x = ((u * self.w as f64).floor() as i64).rem_euclid(self.w as i64) as usize;
        let y = ((v * self.h as f64).floor().max(0.0) as usize).min(self.h - 1);
        y * self.w + x
    }

    fn add(&mut self, d: [f64; 3], omega: f64, values: &[f64]) {
        let t = self.index(d);
        self.weight[t] += omega;
        for (a, v) in self.acc[t * self.per..(t + 1) * self.per]
            .iter_mut()
            .zip(values)
        {
            *a += omega * v;
        }
    }

    /// The means; a texel no pixel fell in takes its filled neighbours' mean (a map coarser
    /// than the renderer's near the poles or at a cube's seams).
    fn finish(mut self) -> Vec<f64> {
        let (w, h, per) = (self.w, self.h, self.per);
        for t in 0..w * h {
            if self.weight[t] > 0.0 {
                for v in &mut self.acc[t * per..(t + 1) * per] {
                    *v /= self.weight[t];
                }
            }
        }
        let mut filled: Vec<bool> = self.weight.iter().map(|&x| x > 0.0).collect();
        for _ in 0..w.max(h) {
            let missing: Vec<usize> = (0..w * h).filter(|&t| !filled[t]).collect();
            if missing.is_empty() || !filled.iter().any(|&f| f) {
                break;
            }
            let mut updates = Vec::new();
            for &t in &missing {
                let (x, y) = (t % w, t / w);
                let near = [
                    y * w + (x + 1) % w,
                    y * w + (x + w - 1) % w,
                    y.saturating_sub(1) * w + x,
                    (y + 1).min(h - 1) * w + x,
                ];
                let src: Vec<usize> = near.into_iter().filter(|&n| filled[n]).collect();
                if !src.is_empty() {
                    let mean: Vec<f64> = (0..per)
                        .map(|k| src.iter().map(|&n| self.acc[n * per + k]).sum::<f64>())
                        .map(|v| v / src.len() as f64)
                        .collect();
                    updates.push((t, mean));
                }
            }
            for (t, mean) in updates {
                self.acc[t * per..(t + 1) * per].copy_from_slice(&mean);
                filled[t] = true;
            }
        }
        self.acc
    }
}

/// The lat-long rows for a map of `used` pixels: at least two source pixels a texel side, at
/// most `max`.
fn rows_for(used: usize, max: usize) -> usize {
    let latlong_rows = ((used as f64) / 2.0).sqrt();
    ((latlong_rows / 2.0).floor() as usize).clamp(1, max)
}

/// The lighting's texels and the background's ([`Maps`]), filled together.
struct TexelPair {
    light: Texels,
    seen: Texels,
}

impl TexelPair {
    fn new(used: usize, per: usize) -> TexelPair {
        TexelPair {
            light: Texels::new(rows_for(used, SOURCE_ROWS), per),
            seen: Texels::new(rows_for(used, BACKGROUND_ROWS), per),
        }
    }

    fn add(&mut self, d: [f64; 3], omega: f64, values: &[f64]) {
        self.light.add(d, omega, values);
        self.seen.add(d, omega, values);
    }

    /// Both as coefficient maps of `k` values a texel, each from its values by `f`.
    fn pack(self, k: usize, f: impl Fn(&[f64], &mut [f64])) -> Maps {
        let per = self.light.per;
        let one = |t: Texels| {
            let (w, h) = (t.w, t.h);
            pack(&t.finish(), per, k, w, h, &f)
        };
        Maps {
            light: one(self.light),
            seen: one(self.seen),
        }
    }
}

/// An RGB-less map of the layout, for its directions and solid angles.
fn geometry(path: &Path, layout: Layout, w: usize, h: usize) -> Result<EnvMap> {
    EnvMap::new(layout, RgbImage::new(w, h))
        .map_err(|e| Error::invalid(format!("{}: {e}", path.display())))
}

/// The sun's pixels of a spectral file: its `sun` mask (what `convert` found), else the sun
/// found in its colours as `convert` would.
fn sun_mask(path: &Path, geo: &EnvMap, n: usize, colour: &Colour) -> Result<Vec<bool>> {
    if let Some(mask) = files::read_stored_channel(path, "sun") {
        return Ok(mask.iter().map(|&v| v > 0.5).collect());
    }
    let (w, h) = (geo.image.width, geo.image.height);
    let mut preview = RgbImage::new(w, h);
    let to_rgb = RgbSpace::SRGB.from_xyz_matrix();
    let y_norm = colour
        .weights
        .iter()
        .map(|c| c[1])
        .sum::<f64>()
        .max(f64::MIN_POSITIVE);
    files::read_spectral_rows(path, |y, row| {
        let per = row.len() / w;
        for x in 0..w {
            let px = &row[x * per..x * per + n];
            if !px.iter().all(|v| v.is_finite()) {
                continue;
            }
            let xyz = nalgebra::Vector3::from_fn(|r, _| {
                px.iter()
                    .zip(&colour.weights)
                    .map(|(v, c)| (*v as f64) * c[r])
                    .sum::<f64>()
                    / y_norm
            });
            let rgb = to_rgb * xyz;
            preview.pixels[y * w + x] = [0, 1, 2].map(|k| (rgb[k] as f32).max(0.0));
        }
    })?;
    let map = EnvMap::new(geo.layout, preview)
        .map_err(|e| Error::invalid(format!("{}: {e}", path.display())))?;
    let mut mask = vec![false; w * h];
    if let Some(sun) = find_sun(&map, &RgbSpace::SRGB, &SunSettings::default()).sun() {
        for &i in &sun.pixels {
            mask[i] = true;
        }
    }
    Ok(mask)
}

/// The sun's pixels summed: `sum omega s` and `sum omega Y(s) dir`.
struct SunSum {
    spectrum: Vec<f64>,
    dir: [f64; 3],
}

impl SunSum {
    /// Adds `weight` times the spectrum `s` of luminance `y` seen towards `d`.
    fn add(&mut self, weight: f64, s: &[f64], y: f64, d: [f64; 3]) {
        for (acc, v) in self.spectrum.iter_mut().zip(s) {
            *acc += weight * v;
        }
        for (acc, dk) in self.dir.iter_mut().zip(d) {
            *acc += weight * y * dk;
        }
    }

    /// The sun as a directional light of irradiance `Y`, and its SPD at `Y = 1` (None where
    /// the pixels summed hold no light or no direction).
    fn light(&self, colour: &Colour, wl: &[f64]) -> Result<Option<(Sun, Tabulated)>> {
        let e = colour.luminance(&self.spectrum);
        let n = (self.dir.iter().map(|v| v * v).sum::<f64>()).sqrt();
        if !(e > 0.0 && n > 0.0) {
            return Ok(None);
        }
        let spd = Tabulated::new(wl.to_vec(), self.spectrum.iter().map(|v| v / e).collect())?;
        let sun = Sun {
            direction: self.dir.map(|v| v / n),
            irradiance: e,
        };
        Ok(Some((sun, spd)))
    }
}

/// Loads a spectral OpenEXR as a lighting of its own spectra (see the module docs).
pub fn load_spectral(path: &Path, spectra: Spectra) -> Result<(Lighting, EnvReport)> {
    let info = files::read_spectral_info(path)?;
    let wl = info.wavelengths_nm.clone();
    let (w, h) = (info.width, info.height);
    let colour = Colour::new(&wl)?;
    let geo = geometry(path, layout_of(path, w, h, info.envmap)?, w, h)?;
    let mask = sun_mask(path, &geo, wl.len(), &colour)?;
    let (texels, sun) = spectral_texels(path, &geo, &mask, &colour)?;
    let sun = sun.light(&colour, &wl)?;
    let light = info.attributes.iter().find_map(|(k, v)| match v {
        AttrValue::Text(t) if k == "specmap.light" => Some(t.clone()),
        _ => None,
    });
    let (basis, coeffs, projection) = expand(texels, spectra, &colour)?;
    own_lighting(Own {
        path,
        kind: "spectral",
        input_size: [w, h],
        light: light.unwrap_or_else(|| "the file's own spectra".into()),
        wavelengths_nm: wl,
        spectra: basis,
        coeffs,
        sun,
        sun_label: "the sun pixels' own spectrum",
        projection,
    })
}

/// A spectral file's pixels averaged into the lighting's and the background's texels, the
/// sun's pixels (`mask`) summed apart; an error at a value beyond [`MAX_RADIANCE`].
fn spectral_texels(
    path: &Path,
    geo: &EnvMap,
    mask: &[bool],
    colour: &Colour,
) -> Result<(TexelPair, SunSum)> {
    let (w, n) = (geo.image.width, colour.weights.len());
    let mut texels = TexelPair::new(geo.used_pixels(), n);
    let mut sun = SunSum {
        spectrum: vec![0.0; n],
        dir: [0.0; 3],
    };
    let mut too_large = None;
    let mut px = vec![0.0f64; n];
    files::read_spectral_rows(path, |y, row| {
        let per = row.len() / w;
        for x in 0..w {
            let (Some(d), omega) = (geo.direction(x, y), geo.solid_angle(x, y)) else {
                continue;
            };
            let raw = &row[x * per..x * per + n];
            // A pixel with a NaN or infinite band is black (as `convert` treats them); one
            // beyond MAX_RADIANCE stops the load.
            if !raw.iter().all(|v| v.is_finite()) {
                continue;
            }
            let peak = raw.iter().fold(0f64, |m, &v| m.max((v as f64).abs()));
            if peak > MAX_RADIANCE {
                too_large.get_or_insert((x, y, peak));
                continue;
            }
            for (p, v) in px.iter_mut().zip(raw) {
                *p = *v as f64;
            }
            if mask[y * w + x] {
                let yl = colour.luminance(&px).max(0.0);
                sun.add(omega, &px, yl, d);
                // The background shows the sun; the lighting's texel keeps the sun's solid angle,
                // dark: its light is the directional light's now.
                texels.seen.add(d, omega, &px);
                px.iter_mut().for_each(|v| *v = 0.0);
                texels.light.add(d, omega, &px);
            } else {
                texels.add(d, omega, &px);
            }
        }
    })?;
    if let Some((x, y, v)) = too_large {
        return Err(too_bright(path, x, y, v));
    }
    Ok((texels, sun))
}

/// The spectra a spectral file's texels expand with, their coefficient maps and, projected
/// onto their own basis, how well it holds them.
fn expand(
    mut texels: TexelPair,
    spectra: Spectra,
    colour: &Colour,
) -> Result<(Vec<Vec<f64>>, Maps, Option<Projection>)> {
    let n = colour.weights.len();
    match spectra {
        Spectra::Full => {
            let basis: Vec<Vec<f64>> = (0..n)
                .map(|j| (0..n).map(|i| (i == j) as u8 as f64).collect())
                .collect();
            Ok((basis, texels.pack(n, |s, out| out.copy_from_slice(s)), None))
        }
        Spectra::Own => {
            let (tw, th) = (texels.light.w, texels.light.h);
            let light_values = std::mem::replace(&mut texels.light, Texels::new(1, 0)).finish();
            let (basis, p) = project(&light_values, n, tw, th, colour)?;
            let f = |s: &[f64], out: &mut [f64]| basis.project(s, out);
            let (sw, sh) = (texels.seen.w, texels.seen.h);
            let maps = Maps {
                light: pack(&light_values, n, basis.len(), tw, th, &f),
                seen: pack(&texels.seen.finish(), n, basis.len(), sw, sh, &f),
            };
            Ok((basis.spectra.clone(), maps, Some(p)))
        }
    }
}

/// What a file of its own spectra loaded as, for [`own_lighting`].
struct Own<'a> {
    path: &'a Path,
    /// [`EnvReport::kind`].
    kind: &'static str,
    input_size: [usize; 2],
    light: String,
    wavelengths_nm: Vec<f64>,
    /// The spectra the coefficients expand with, on `wavelengths_nm`.
    spectra: Vec<Vec<f64>>,
    coeffs: Maps,
    sun: Option<(Sun, Tabulated)>,
    /// What the sun's SPD is, where there is a sun.
    sun_label: &'static str,
    projection: Option<Projection>,
}

/// The lighting of a file's own spectra and its report (without a sun, its SPD is
/// [`SUN_SPD`]'s, labelled "none").
fn own_lighting(o: Own) -> Result<(Lighting, EnvReport)> {
    let (sun, sun_spd, sun_label) = match &o.sun {
        Some((s, spd)) => (Some(*s), spd.clone(), o.sun_label.to_string()),
        None => (
            None,
            crate::data::spectrum(SUN_SPD)?.data,
            "none".to_string(),
        ),
    };
    let spectra = o
        .spectra
        .into_iter()
        .map(|b| Tabulated::new(o.wavelengths_nm.clone(), b))
        .collect::<Result<Vec<_>>>()?;
    let k = spectra.len();
    let lighting = Lighting {
        label: o.light.clone(),
        spectra: LightSpectra::Own {
            spectra,
            sun_spd,
            sun_label: sun_label.clone(),
        },
        environment: Environment::Map(Arc::new(o.coeffs)),
        sun,
    };
    let report = EnvReport {
        file: o.path.display().to_string(),
        kind: o.kind,
        input_size: o.input_size,
        light: o.light,
        light_used: false,
        sun_spd: sun_label,
        sun_direction: sun.map(|s| s.direction),
        sun_irradiance: sun.map(|s| s.irradiance),
        spectra: k,
        projection: o.projection,
    };
    Ok((lighting, report))
}

/// A coefficient map of `k` values per texel, each texel's from its `per` values by `f`.
fn pack(
    values: &[f64],
    per: usize,
    k: usize,
    w: usize,
    h: usize,
    f: &impl Fn(&[f64], &mut [f64]),
) -> CoeffMap {
    let groups = k.div_ceil(4).max(1);
    let mut texels = vec![[0f32; 4]; w * h * groups];
    let mut c = vec![0.0; k];
    for t in 0..w * h {
        f(&values[t * per..(t + 1) * per], &mut c);
        for (j, v) in c.iter().enumerate() {
            texels[t * groups + j / 4][j % 4] = *v as f32;
        }
    }
    CoeffMap {
        width: w,
        height: h,
        groups,
        texels,
    }
}

/// The texels' own basis, their coefficients and how well they are held.
fn project(
    values: &[f64],
    n: usize,
    w: usize,
    h: usize,
    colour: &Colour,
) -> Result<(OwnBasis, Projection)> {
    let mut m = Moments::new(n);
    for t in 0..w * h {
        let s = &values[t * n..(t + 1) * n];
        m.add(s, latlong::solid_angle(w, h, t / w), colour.luminance(s));
    }
    let basis = OwnBasis::from_moments(&m, &colour.weights, DEFAULT_DISCARD, MAX_K)?;
    let k = basis.len();
    let (mut worst, mut at, mut sum, mut weight) = (0.0f64, 0usize, 0.0, 0.0);
    let mut c = vec![0.0; k];
    for t in 0..w * h {
        let s = &values[t * n..(t + 1) * n];
        basis.project(s, &mut c);
        let r = basis.relative_residual(s, &c);
        let e = latlong::solid_angle(w, h, t / w) * colour.luminance(s).max(0.0);
        sum += r * e;
        weight += e;
        if r > worst {
            (worst, at) = (r, t);
        }
    }
    let d = latlong::direction(w, h, at % w, at / w);
    let azimuth = d[0].atan2(d[2]).to_degrees();
    let elevation = d[1].clamp(-1.0, 1.0).asin().to_degrees();
    let mean = if weight > 0.0 { sum / weight } else { 0.0 };
    let summary = format!(
        "the map is held by {k} spectra of its own: {:.2e} of its spectral energy lies outside \
         them; the light from any direction is within {:.2}% of its spectrum (worst at azimuth \
         {azimuth:.0}, elevation {elevation:.0} degrees; {:.3}% on average){}",
        basis.discarded,
        100.0 * worst,
        100.0 * mean,
        if basis.keeps_colour {
            ", and keeps its colour exactly"
        } else {
            ""
        }
    );
    let p = Projection {
        k,
        discarded: basis.discarded,
        max_residual: worst,
        max_residual_at: [azimuth, elevation],
        mean_residual: mean,
        keeps_colour: basis.keeps_colour,
        summary,
    };
    Ok((basis, p))
}

/// Loads a basis OpenEXR of the K-spectrum form (`specmap convert --format basis`, version 2):
/// channels `k00`..`k{K-1}`, the spectra in `specmap.basis00`.. on `specmap.wavelengths`, the
/// sun's spectrum's index in `specmap.basisSun` (its coefficient becomes the directional light).
pub fn load_basis_k(path: &Path) -> Result<(Lighting, EnvReport)> {
    use exr::prelude::read_first_flat_layer_from_file;
    let image = read_first_flat_layer_from_file(path)
        .map_err(|e| bad(path, format!("reading the basis OpenEXR: {e}")))?;
    let layer = &image.layer_data;
    let (w, h) = (layer.size.0, layer.size.1);
    let attrs: Vec<(String, AttrValue)> = layer
        .attributes
        .other
        .iter()
        .chain(image.attributes.other.iter())
        .filter_map(|(n, v)| files::attr_from_exr(v).map(|a| (n.to_string(), a)))
        .collect();
    let header = KHeader::read(path, &attrs)?;
    let coef = k_channels(path, layer, header.spectra.len())?;
    let envmap = files::envmap_attr(&layer.attributes);
    let geo = geometry(path, layout_of(path, w, h, envmap)?, w, h)?;
    let (texels, sun) = header.texels(path, &geo, &coef)?;
    let k = header.spectra.len();
    let coeffs = texels.pack(k, |s, out| out.copy_from_slice(s));
    let sun = sun.light(&header.colour, &header.wavelengths_nm)?;
    own_lighting(Own {
        path,
        kind: "basis-k",
        input_size: [w, h],
        light: header.light,
        wavelengths_nm: header.wavelengths_nm,
        spectra: header.spectra,
        coeffs,
        sun,
        sun_label: "the file's sun spectrum",
        projection: None,
    })
}

/// The error `what` about the file `path`.
fn bad(path: &Path, what: String) -> Error {
    Error::invalid(format!("{}: {what}", path.display()))
}

/// What a K-spectrum basis file's header says.
struct KHeader {
    wavelengths_nm: Vec<f64>,
    colour: Colour,
    /// The K spectra, on `wavelengths_nm`.
    spectra: Vec<Vec<f64>>,
    /// Which of them is the sun's.
    sun_index: Option<usize>,
    /// `2^EV` (1 without `EV`).
    scale: f64,
    light: String,
}

impl KHeader {
    /// The header of the attributes `attrs`: an error without K (1 to 100), the wavelengths or
    /// a spectrum of as many values.
    fn read(path: &Path, attrs: &[(String, AttrValue)]) -> Result<KHeader> {
        let get = |name: &str| {
            attrs
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, v)| v.clone())
        };
        let floats = |name: &str| match get(name) {
            Some(AttrValue::F32Vec(v)) => Ok(v.iter().map(|&x| x as f64).collect::<Vec<f64>>()),
            _ => Err(bad(
                path,
                format!("a K-spectrum basis map needs the float-vector attribute {name}"),
            )),
        };
        let int = |name: &str| match get(name) {
            Some(AttrValue::I32(v)) => Some(v as i64),
            Some(AttrValue::F32(v)) => Some(v as i64),
            _ => None,
        };
        let k = int("specmap.basisK")
            .filter(|&k| k > 0 && k <= 100)
            .ok_or_else(|| {
                bad(
                    path,
                    "a K-spectrum basis map needs specmap.basisK (1 to 100)".into(),
                )
            })? as usize;
        let wl = floats("specmap.wavelengths")?;
        let colour = Colour::new(&wl)?;
        let spectra: Vec<Vec<f64>> = (0..k)
            .map(|j| {
                let s = floats(&format!("specmap.basis{j:02}"))?;
                if s.len() != wl.len() {
                    return Err(bad(
                        path,
                        format!(
                            "specmap.basis{j:02} has {} values for {} wavelengths",
                            s.len(),
                            wl.len()
                        ),
                    ));
                }
                Ok(s)
            })
            .collect::<Result<_>>()?;
        let sun_index = int("specmap.basisSun")
            .filter(|&i| i >= 0 && (i as usize) < k)
            .map(|i| i as usize);
        let ev = match get("EV") {
            Some(AttrValue::F32(x)) => x as f64,
            _ => 0.0,
        };
        let light = match get("specmap.light") {
            Some(AttrValue::Text(t)) => t,
            _ => "the file's own spectra".into(),
        };
        Ok(KHeader {
            wavelengths_nm: wl,
            colour,
            spectra,
            sun_index,
            scale: ev.exp2(),
            light,
        })
    }

    /// The coefficients `coef` (a channel per spectrum) averaged into the lighting's and the
    /// background's texels, the sun's coefficient summed apart as its spectrum; an error at a
    /// value beyond [`MAX_RADIANCE`].
    fn texels(&self, path: &Path, geo: &EnvMap, coef: &[Vec<f32>]) -> Result<(TexelPair, SunSum)> {
        let (w, h, k) = (geo.image.width, geo.image.height, self.spectra.len());
        let mut texels = TexelPair::new(geo.used_pixels(), k);
        let mut sun = SunSum {
            spectrum: vec![0.0; self.wavelengths_nm.len()],
            dir: [0.0; 3],
        };
        let sun_y = self
            .sun_index
            .map(|i| self.colour.luminance(&self.spectra[i]));
        let mut c = vec![0.0; k];
        for y in 0..h {
            for x in 0..w {
                let (Some(d), omega) = (geo.direction(x, y), geo.solid_angle(x, y)) else {
                    continue;
                };
                let i = y * w + x;
                for j in 0..k {
                    let v = coef[j][i] as f64 * self.scale;
                    c[j] = if v.is_finite() { v } else { 0.0 };
                }
                let peak = c.iter().fold(0f64, |m, v| m.max(v.abs()));
                if peak > MAX_RADIANCE {
                    return Err(too_bright(path, x, y, peak));
                }
                let (Some(si), Some(sy)) = (self.sun_index, sun_y) else {
                    texels.add(d, omega, &c);
                    continue;
                };
                let a = c[si].max(0.0);
                if a > 0.0 {
                    sun.add(omega * a, &self.spectra[si], sy, d);
                }
                texels.seen.add(d, omega, &c);
                c[si] = 0.0;
                texels.light.add(d, omega, &c);
            }
        }
        Ok((texels, sun))
    }
}

/// The coefficient channels `k00`..`k{K-1}` of `layer`.
fn k_channels(
    path: &Path,
    layer: &exr::image::Layer<exr::image::AnyChannels<exr::image::FlatSamples>>,
    k: usize,
) -> Result<Vec<Vec<f32>>> {
    let channel = |name: &str| -> Result<Vec<f32>> {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name)
            .map(|c| c.sample_data.values_as_f32().collect())
            .ok_or_else(|| bad(path, format!("no channel {name} (specmap.basisK is {k})")))
    };
    (0..k).map(|j| channel(&format!("k{j:02}"))).collect()
}
