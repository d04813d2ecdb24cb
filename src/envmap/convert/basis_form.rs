//! The basis form (version 2) of a conversion: the spectral file the conversion wrote, factored
//! into K spectra of its own and K coefficients per pixel.
//!
//! Stages: [`analyse`] reads the spectral file once (the second moments of its pixels' spectra,
//! the sun's pixels summed apart), [`OwnBasis`] picks the components, and [`write`] reads it again
//! and writes, per pixel, the colour-keeping coefficients (the sun's pixels: their luminance on
//! the sun's spectrum), R, G, B, and in the header the spectra:
//! - channels `k00` .. `k{K-1}` and `R`, `G`, `B` as the spectral file's, in the conversion's
//!   precision (the components are orthonormal, so half floats round a pixel's spectrum by
//!   about as much as they round its bands), divided by 2^`EV` where half floats need it;
//! - `specmap.basisVersion` 2, `specmap.basisK` K, `specmap.wavelengths` (nm),
//!   `specmap.basis00` .. (float vectors, the spectra in the spectral file's radiance units),
//!   `specmap.basisSun` (the sun's spectrum's index, -1 without a sun), and the spectral file's
//!   own attributes. A pixel's radiance is `sum_j k_j basis_j`.

use crate::envmap::convert::own_basis::{
    relative_residual, BandColour, Moments, OwnBasis, DEFAULT_DISCARD, MAX_K,
};
use crate::envmap::files::{
    self, AttrValue, ChannelSet, Compression, Precision, SpectralLayout, SpectralWriter, HALF_MAX,
};
use crate::envmap::layout::{detect, EnvMap, Layout};
use crate::envmap::RgbImage;
use crate::error::{Error, Result};
use std::path::Path;

/// How the basis form holds its spectral file.
#[derive(Debug, Clone, serde::Serialize)]
pub struct BasisStats {
    /// Spectra, the sun's included.
    pub k: usize,
    /// Whether one of them is the sun's.
    pub sun: bool,
    /// The share of the non-sun pixels' spectral energy outside the spectra (see
    /// [`crate::envmap::convert::own_basis`]).
    pub discarded: f64,
    /// The largest relative spectral residual of a pixel, and where.
    pub max_residual: f64,
    /// The pixel (x, y) of the largest residual.
    pub max_residual_at: [usize; 2],
    /// Pixels whose spectrum the spectra hold to worse than 1%.
    pub pixels_over_1_percent: usize,
    /// Whether every pixel keeps its colour exactly.
    pub keeps_colour: bool,
    /// Half floats: the values were divided by 2^EV (None: not needed, or float).
    pub ev: Option<f64>,
    /// Half floats: pixels whose every coefficient is below half's smallest (written as 0).
    pub below_half: usize,
}

/// What the first read found.
pub struct Analysis {
    /// The map's own spectra (principal components) and their projection.
    pub basis: OwnBasis,
    /// The sun's SPD (the mean of its pixels' spectra) at luminance 1, and the mask.
    pub sun: Option<Vec<f64>>,
    mask: Vec<bool>,
    colour: BandColour,
    wavelengths: Vec<f64>,
    /// The largest spectrum norm (a bound on every coefficient) or sun luminance.
    peak: f64,
}

/// Reads `spectral` once: the moments of its non-sun pixels and the sun's pixels' mean spectrum.
pub fn analyse(spectral: &Path) -> Result<Analysis> {
    let info = files::read_spectral_info(spectral)?;
    let (w, h) = (info.width, info.height);
    let wl = info.wavelengths_nm.clone();
    let n = wl.len();
    let colour = BandColour::new(&wl)?;
    let mask: Vec<bool> = files::read_stored_channel(spectral, "sun")
        .map(|m| m.iter().map(|&v| v > 0.5).collect())
        .unwrap_or_else(|| vec![false; w * h]);
    let layout = detect(
        w,
        h,
        info.envmap.map(|a| match a {
            files::EnvmapAttr::LatLong => Layout::LatLong,
            files::EnvmapAttr::Cube => Layout::Cube,
        }),
    )
    .map_err(|e| Error::invalid(format!("{}: {e}", spectral.display())))?;
    let geo = EnvMap::new(layout, RgbImage::new(w, h))
        .map_err(|e| Error::invalid(format!("{}: {e}", spectral.display())))?;
    let mut moments = Moments::new(n);
    let mut peak = 0f64;
    let mut sun = vec![0.0; n];
    let mut s = vec![0.0; n];
    files::read_spectral_rows(spectral, |y, row| {
        let per = row.len() / w;
        for x in 0..w {
            for (a, v) in s.iter_mut().zip(&row[x * per..x * per + n]) {
                *a = if v.is_finite() { *v as f64 } else { 0.0 };
            }
            let omega = geo.solid_angle(x, y).max(1e-12);
            let norm = s.iter().map(|v| v * v).sum::<f64>().sqrt();
            peak = peak.max(norm);
            if mask[y * w + x] {
                peak = peak.max(colour.luminance(&s));
                for (a, v) in sun.iter_mut().zip(&s) {
                    *a += omega * v;
                }
            } else {
                moments.add(&s, omega, colour.luminance(&s));
            }
        }
    })?;
    let y = colour.luminance(&sun);
    let sun = (y > 0.0).then(|| sun.iter().map(|v| v / y).collect::<Vec<f64>>());
    let room = MAX_K - sun.is_some() as usize;
    let basis = OwnBasis::from_moments(&moments, &colour.weights, DEFAULT_DISCARD, room)?;
    Ok(Analysis {
        basis,
        sun,
        mask,
        colour,
        wavelengths: wl,
        peak,
    })
}

/// Whether `name` is one of the attributes the basis form writes itself (`specmap.basisVersion`,
/// `specmap.basisK`, `specmap.wavelengths`, `specmap.basis00`..., `specmap.basisSun`). The fit's
/// `specmap.basis` (its three reflectances' names) is not.
fn is_basis_form_attribute(name: &str) -> bool {
    match name.strip_prefix("specmap.basis") {
        Some(rest) => {
            matches!(rest, "Version" | "K" | "Sun")
                || (!rest.is_empty() && rest.bytes().all(|b| b.is_ascii_digit()))
        }
        None => name == "specmap.wavelengths",
    }
}

/// The basis form's header: the spectral file's `specmap.*` attributes and the K spectra.
fn header(spectral: &[(String, AttrValue)], a: &Analysis) -> Vec<(String, AttrValue)> {
    let kb = a.basis.len();
    let k = kb + a.sun.is_some() as usize;
    let floats = |v: &[f64]| AttrValue::F32Vec(v.iter().map(|&x| x as f32).collect());
    let mut attributes: Vec<(String, AttrValue)> = spectral
        .iter()
        .filter(|(n, _)| n.starts_with("specmap.") && !is_basis_form_attribute(n))
        .cloned()
        .collect();
    attributes.push(("specmap.basisVersion".into(), AttrValue::I32(2)));
    attributes.push(("specmap.basisK".into(), AttrValue::I32(k as i32)));
    attributes.push(("specmap.wavelengths".into(), floats(&a.wavelengths)));
    for (j, b) in a.basis.spectra.iter().enumerate() {
        attributes.push((format!("specmap.basis{j:02}"), floats(b)));
    }
    if let Some(s) = &a.sun {
        attributes.push((format!("specmap.basis{kb:02}"), floats(s)));
    }
    let sun_index = if a.sun.is_some() { kb as i32 } else { -1 };
    attributes.push(("specmap.basisSun".into(), AttrValue::I32(sun_index)));
    attributes
}

/// Writes the basis form of `spectral` to `output` (through a temporary file beside it).
pub fn write(
    spectral: &Path,
    a: &Analysis,
    output: &Path,
    precision: Precision,
    compression: Compression,
    zip_level: u8,
) -> Result<(BasisStats, u64)> {
    let info = files::read_spectral_info(spectral)?;
    let form = Form::new(&info, a, precision);
    let mut writer = SpectralWriter::create(
        output,
        SpectralLayout {
            width: info.width,
            height: info.height,
            channels: ChannelSet::Custom(form.names.clone()),
            precision,
            compression,
            envmap: info.envmap,
            ev: form.ev,
            attributes: header(&info.attributes, a),
            zip_level,
            unscaled: Vec::new(),
        },
    )?;
    let mut stats = BasisStats {
        k: form.k,
        sun: a.sun.is_some(),
        discarded: a.basis.discarded,
        max_residual: 0.0,
        max_residual_at: [0, 0],
        pixels_over_1_percent: 0,
        keeps_colour: a.basis.keeps_colour,
        ev: if precision == Precision::Half {
            form.ev
        } else {
            None
        },
        below_half: 0,
    };
    let mut failed = None;
    let mut scratch = Scratch {
        s: vec![0.0; a.wavelengths.len()],
        c: vec![0.0; a.basis.len()],
        out: Vec::new(),
    };
    files::read_spectral_rows(spectral, |y, row| {
        form.project_row(a, y, row, &mut scratch, &mut stats);
        if failed.is_none() {
            if let Err(e) = writer.write_rows(y, &scratch.out) {
                failed = Some(e);
            }
        }
    })?;
    if let Some(e) = failed {
        return Err(e);
    }
    let bytes = writer.finish()?;
    Ok((stats, bytes))
}

/// The basis form's channels and scale for a spectral file.
struct Form {
    width: usize,
    /// Bands of the spectral file.
    bands: usize,
    /// The map's own spectra, and with the sun's.
    kb: usize,
    k: usize,
    /// `k00`.., then R, G, B when the spectral file has them.
    names: Vec<String>,
    has_rgb: bool,
    half: bool,
    ev: Option<f64>,
    /// Half's smallest value at the EV scale: coefficients below it are written as 0.
    smallest: f64,
}

/// Per-row buffers: a pixel's spectrum and coefficients, and the row written.
struct Scratch {
    s: Vec<f64>,
    c: Vec<f64>,
    out: Vec<f32>,
}

impl Form {
    fn new(info: &files::SpectralInfo, a: &Analysis, precision: Precision) -> Form {
        let kb = a.basis.len();
        let k = kb + a.sun.is_some() as usize;
        let mut names: Vec<String> = (0..k).map(|j| format!("k{j:02}")).collect();
        if info.has_rgb {
            names.extend(["R", "G", "B"].map(String::from));
        }
        // A coefficient is at most the spectrum's norm for an orthogonal projection; the colour
        // constraint can take it a little beyond: a stop of margin.
        let bound = 2.0 * a.peak;
        let ev = (precision == Precision::Half && bound > HALF_MAX as f64)
            .then(|| (bound / HALF_MAX as f64).log2().ceil());
        Form {
            width: info.width,
            bands: a.wavelengths.len(),
            kb,
            k,
            names,
            has_rgb: info.has_rgb,
            half: precision == Precision::Half,
            ev,
            smallest: 2f64.powi(-25) * ev.unwrap_or(0.0).exp2(),
        }
    }

    /// Row `y` of the spectral file as the basis form's values (into `scratch.out`), each
    /// pixel's residual and flushed coefficients counted in `stats`.
    fn project_row(
        &self,
        a: &Analysis,
        y: usize,
        row: &[f32],
        scratch: &mut Scratch,
        stats: &mut BasisStats,
    ) {
        let (w, n, k, kb) = (self.width, self.bands, self.k, self.kb);
        let per = row.len() / w;
        let per_out = self.names.len();
        scratch.out.clear();
        scratch.out.resize(w * per_out, 0.0);
        let Scratch { s, c, out } = scratch;
        for x in 0..w {
            let px = &row[x * per..(x + 1) * per];
            for (a, v) in s.iter_mut().zip(&px[..n]) {
                *a = if v.is_finite() { *v as f64 } else { 0.0 };
            }
            let o = &mut out[x * per_out..(x + 1) * per_out];
            let r = match &a.sun {
                Some(sun) if a.mask[y * w + x] => {
                    let l = a.colour.luminance(s);
                    o[kb] = l as f32;
                    relative_residual(s, |i| l * sun[i])
                }
                _ => {
                    a.basis.project(s, c);
                    for (o, v) in o.iter_mut().zip(c.iter()) {
                        *o = *v as f32;
                    }
                    a.basis.relative_residual(s, c)
                }
            };
            if r > stats.max_residual {
                stats.max_residual = r;
                stats.max_residual_at = [x, y];
            }
            stats.pixels_over_1_percent += (r > 0.01) as usize;
            let lit = o[..k].iter().any(|v| *v != 0.0);
            if self.half && lit && o[..k].iter().all(|v| (v.abs() as f64) < self.smallest) {
                stats.below_half += 1;
            }
            if self.has_rgb {
                o[k..k + 3].copy_from_slice(&px[n..n + 3]);
            }
        }
    }
}
