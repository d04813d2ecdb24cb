//! Colour rendition of a spectral environment map against its truth: test patches lit by each
//! map's irradiance, each rendering adapted to its own white (CAT02), compared in CIEDE2000.
//!
//! A round trip that returns the input RGB says nothing about whether a map's spectra are right:
//! every metamer passes it. What matters to a renderer is that objects lit by the map get the
//! colours they would get under the real light (the paper's Fig. 9). So, for each surface normal
//! n and each map:
//!
//! 1. the irradiance `E(λ) = Σ_pixels L(ω, λ) max(0, n·ω) dΩ`, with each pixel's exact solid angle
//!    and centre direction from [`crate::envmap::layout`] (any layout: the two maps may differ in
//!    layout and size, since irradiance does not depend on them);
//! 2. both irradiances resampled (linearly, as lights are) onto the wavelengths the two maps
//!    share: from the later start to the earlier end, at the finer of the two steps;
//! 3. each patch `ρ(λ) E(λ) / π` and the white (the perfect diffuser, `E / π`) to XYZ by the
//!    paper's Eq. 10/11 (Y = 100 for the white, so the irradiance's absolute scale drops out);
//! 4. each rendering adapted from its own white to D65 (x 0.3127, y 0.3290, Y = 100) by CAT02 von
//!    Kries with full adaptation, then CIELAB against D65, and CIEDE2000 between truth and
//!    reconstruction, patch by patch;
//! 5. the whites compared as an observer adapted to the truth's light sees them: both whites at
//!    Y = 100, both adapted by the truth's CAT02 transform (truth white -> D65), CIELAB against
//!    D65, CIEDE2000 (the truth's white lands on L* = 100, a* = b* = 0). Step 4 hides a wrong
//!    white by design; this number shows it.
//!
//! Samples that are NaN or infinite count as 0 and are reported; negative values (which exact
//! fits can produce) are kept, as they are part of the light.

use crate::colorimetry::{cct, delta_e_2000, Cat, Cmfs, Lab, Observer, Xyz, D65_XY};
use crate::data::Table;
use crate::envmap::files::{read_spectral_info, read_spectral_rows, EnvmapAttr};
use crate::envmap::layout::{detect, EnvMap, Layout};
use crate::envmap::RgbImage;
use crate::error::{Error, Result};
use crate::spectrum::{Interpolation, Rule, Spectrum, Tabulated, WavelengthGrid};
use std::path::Path;
use std::str::FromStr;

/// A surface normal the patches are lit at: a unit direction in the map's world space (OpenEXR's:
/// Y up; the lat-long centre column looks down +Z) and the name it was given by.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Normal {
    /// The name it was given by (`up`, `px`, ..., or the `X:Y:Z` text).
    pub name: String,
    /// Unit direction in the map's world space.
    pub direction: [f64; 3],
}

impl Normal {
    /// A normal along `direction` (any non-zero length; normalised here).
    pub fn new(name: impl Into<String>, direction: [f64; 3]) -> Result<Normal> {
        let n = direction.iter().map(|c| c * c).sum::<f64>().sqrt();
        if !(n.is_finite() && n > 0.0) {
            return Err(Error::invalid(format!(
                "normal {direction:?} has no direction (zero or non-finite length)"
            )));
        }
        Ok(Normal {
            name: name.into(),
            direction: direction.map(|c| c / n),
        })
    }

    /// Up and the four horizontal axes: `up`, `px`, `nx`, `pz`, `nz`.
    pub fn defaults() -> Vec<Normal> {
        ["up", "px", "nx", "pz", "nz"]
            .iter()
            .map(|s| s.parse().expect("known names"))
            .collect()
    }
}

/// `up`, `down`, an axis (`px`, `nx`, `py`, `ny`, `pz`, `nz`, or `+x`, `-x`, ...), or `X:Y:Z`.
impl FromStr for Normal {
    type Err = Error;
    fn from_str(s: &str) -> Result<Normal> {
        let t = s.trim();
        let axis = match t.to_ascii_lowercase().as_str() {
            "up" | "py" | "+y" => Some([0.0, 1.0, 0.0]),
            "down" | "ny" | "-y" => Some([0.0, -1.0, 0.0]),
            "px" | "+x" => Some([1.0, 0.0, 0.0]),
            "nx" | "-x" => Some([-1.0, 0.0, 0.0]),
            "pz" | "+z" => Some([0.0, 0.0, 1.0]),
            "nz" | "-z" => Some([0.0, 0.0, -1.0]),
            _ => None,
        };
        if let Some(d) = axis {
            return Normal::new(t.to_ascii_lowercase(), d);
        }
        let parts: Vec<&str> = t.split(':').collect();
        let bad = || {
            Error::invalid(format!(
                "normal '{s}': expected up, down, px, nx, py, ny, pz, nz (or +x, -x, ...) or X:Y:Z"
            ))
        };
        if parts.len() != 3 {
            return Err(bad());
        }
        let mut d = [0.0; 3];
        for (v, p) in d.iter_mut().zip(&parts) {
            *v = p.trim().parse::<f64>().map_err(|_| bad())?;
        }
        Normal::new(t, d)
    }
}

/// The irradiance of one spectral map at a set of normals, on the map's own wavelengths.
#[derive(Debug, Clone)]
pub struct MapIrradiance {
    /// The map's path, as given.
    pub file: String,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// The environment layout the map was read as.
    pub layout: Layout,
    /// The map's bands, increasing.
    pub wavelengths_nm: Vec<f64>,
    /// Per normal (in the order given), per band: W m^-2 nm^-1 if the map is in W m^-2 sr^-1 nm^-1.
    pub irradiance: Vec<Vec<f64>>,
    /// Samples that were NaN or infinite (counted as 0).
    pub nonfinite_values: usize,
}

/// Integrates a spectral OpenEXR (Fichet 2021 layout, any environment layout) against the
/// clamped cosine of each normal, streaming rows.
pub fn map_irradiance(path: &Path, normals: &[Normal]) -> Result<MapIrradiance> {
    let info = read_spectral_info(path)?;
    let attr = info.envmap.map(|e| match e {
        EnvmapAttr::LatLong => Layout::LatLong,
        EnvmapAttr::Cube => Layout::Cube,
    });
    let layout = detect(info.width, info.height, attr).map_err(|e| Error::Parse {
        file: path.to_path_buf(),
        line: None,
        message: format!("not an environment map: {e}"),
    })?;
    // Directions and solid angles depend on the layout and size only: a map without pixels.
    let geometry = EnvMap {
        layout,
        image: RgbImage {
            width: info.width,
            height: info.height,
            pixels: Vec::new(),
        },
    };
    let bands = info.wavelengths_nm.len();
    let per_pixel = bands + if info.has_rgb { 3 } else { 0 };
    let mut irradiance = vec![vec![0.0f64; bands]; normals.len()];
    let mut nonfinite = 0usize;
    let mut weights = vec![0.0f64; normals.len()];
    let width = info.width;
    read_spectral_rows(path, |y, row| {
        for x in 0..width {
            let Some(d) = geometry.direction(x, y) else {
                continue;
            };
            let omega = geometry.solid_angle(x, y);
            for (w, n) in weights.iter_mut().zip(normals) {
                let c = n.direction[0] * d[0] + n.direction[1] * d[1] + n.direction[2] * d[2];
                *w = c.max(0.0) * omega;
            }
            let px = &row[x * per_pixel..x * per_pixel + bands];
            for (e, &w) in irradiance.iter_mut().zip(&weights) {
                if w == 0.0 {
                    continue;
                }
                for (acc, &v) in e.iter_mut().zip(px) {
                    if v.is_finite() {
                        *acc += w * v as f64;
                    }
                }
            }
            nonfinite += px.iter().filter(|v| !v.is_finite()).count();
        }
    })?;
    Ok(MapIrradiance {
        file: path.display().to_string(),
        width: info.width,
        height: info.height,
        layout,
        wavelengths_nm: info.wavelengths_nm,
        irradiance,
        nonfinite_values: nonfinite,
    })
}

/// How [`rendition`] measures.
#[derive(Debug, Clone)]
pub struct RenditionOptions {
    /// The normals the patches are lit at (default: [`Normal::defaults`]).
    pub normals: Vec<Normal>,
    /// The colour-matching functions everything is integrated against.
    pub observer: Observer,
    /// The integration rule over the shared wavelengths.
    pub rule: Rule,
    /// A reflectance table whose every column is a test patch (default `colorchecker`).
    pub patches: String,
}

impl Default for RenditionOptions {
    fn default() -> Self {
        RenditionOptions {
            normals: Normal::defaults(),
            observer: Observer::Cie1931,
            rule: Rule::Riemann,
            patches: "colorchecker".into(),
        }
    }
}

/// What a map is, as the report shows it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct MapSummary {
    /// The map's path, as given.
    pub file: String,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// The environment layout the map was read as.
    pub layout: Layout,
    /// Number of spectral bands.
    pub bands: usize,
    /// First and last band, nm.
    pub range_nm: [f64; 2],
    /// Samples that were NaN or infinite (counted as 0).
    pub nonfinite_values: usize,
}

impl MapSummary {
    fn of(m: &MapIrradiance) -> MapSummary {
        MapSummary {
            file: m.file.clone(),
            width: m.width,
            height: m.height,
            layout: m.layout,
            bands: m.wavelengths_nm.len(),
            range_nm: [
                m.wavelengths_nm[0],
                m.wavelengths_nm[m.wavelengths_nm.len() - 1],
            ],
            nonfinite_values: m.nonfinite_values,
        }
    }
}

/// A light's white: the perfect diffuser under the irradiance.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct White {
    /// Y = 100.
    pub xyz: Xyz,
    /// Chromaticity x, y of `xyz`.
    pub xy: [f64; 2],
    /// Correlated colour temperature (None beyond 0.05 from the Planckian locus).
    pub cct_k: Option<f64>,
    /// Distance to the Planckian locus in CIE 1960 uv, positive above it (greenish).
    pub duv: f64,
}

/// One patch at one normal.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PatchResult {
    /// The patch's name: its column in the reflectance table.
    pub patch: String,
    /// The truth's CIELAB after adaptation to D65.
    pub truth_lab: Lab,
    /// The reconstruction's CIELAB after adaptation to D65.
    pub reconstructed_lab: Lab,
    /// CIEDE2000 between truth and reconstruction.
    pub de2000: f64,
}

/// Everything measured at one normal.
#[derive(Debug, Clone, serde::Serialize)]
pub struct NormalResult {
    /// The normal the patches are lit at.
    pub normal: Normal,
    /// The truth's white at this normal.
    pub truth_white: White,
    /// The reconstruction's white at this normal.
    pub reconstructed_white: White,
    /// Luminous irradiance of the reconstruction over the truth's (∫E ȳ, no adaptation): 1 when
    /// the reconstruction is as bright as the truth.
    pub irradiance_ratio: f64,
    /// The reconstruction's white as seen adapted to the truth's white.
    pub white_de2000: f64,
    /// Mean CIEDE2000 over the patches.
    pub mean_de2000: f64,
    /// Largest CIEDE2000 over the patches.
    pub max_de2000: f64,
    /// Name of the patch with the largest CIEDE2000.
    pub max_patch: String,
    /// Every patch, in the table's column order.
    pub patches: Vec<PatchResult>,
}

/// The whole comparison.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Rendition {
    /// The ground-truth map.
    pub truth: MapSummary,
    /// The reconstructed map.
    pub reconstructed: MapSummary,
    /// The shared wavelengths everything is integrated on.
    pub wavelengths: WavelengthGrid,
    /// The colour-matching functions used.
    pub observer: Observer,
    /// The integration rule used.
    pub rule: Rule,
    /// Name of the reflectance table the patches came from.
    pub patches: String,
    /// How each rendering was adapted before CIELAB, in words.
    pub adaptation: &'static str,
    /// How the two whites were compared, in words.
    pub white_comparison: &'static str,
    /// Mean CIEDE2000 over every patch and normal.
    pub mean_de2000: f64,
    /// Largest CIEDE2000 over every patch and normal.
    pub max_de2000: f64,
    /// Normal name and patch of the maximum.
    pub max_at: [String; 2],
    /// Mean white CIEDE2000 over the normals.
    pub white_mean_de2000: f64,
    /// Largest white CIEDE2000 over the normals.
    pub white_max_de2000: f64,
    /// Every normal, in the order given.
    pub normals: Vec<NormalResult>,
}

const ADAPTATION: &str = "CAT02 von Kries, full adaptation, each rendering from its own white \
                          to D65 (x 0.3127, y 0.3290); CIELAB against D65";
const WHITE_COMPARISON: &str = "both whites at Y = 100, adapted by the truth's transform (truth \
                                white -> D65), CIELAB against D65, CIEDE2000";

/// The wavelengths two maps share: from the later start to the earlier end, at the finer of
/// their smallest band spacings (shrunk, if needed, so that it divides the range).
pub fn shared_grid(a: &[f64], b: &[f64]) -> Result<WavelengthGrid> {
    let range = |w: &[f64]| (w[0], w[w.len() - 1]);
    let ((a0, a1), (b0, b1)) = (range(a), range(b));
    let (lo, hi) = (a0.max(b0), a1.min(b1));
    let spacing = |w: &[f64]| {
        w.windows(2)
            .map(|p| p[1] - p[0])
            .fold(f64::INFINITY, f64::min)
    };
    let step = spacing(a).min(spacing(b));
    if hi <= lo || !step.is_finite() {
        return Err(Error::invalid(format!(
            "the maps share no wavelength range: {a0}..{a1} nm and {b0}..{b1} nm \
             (each needs at least two bands, and their ranges must overlap)"
        )));
    }
    let intervals = ((hi - lo) / step - 1e-9).ceil().max(1.0);
    WavelengthGrid::new(lo, hi, (hi - lo) / intervals)
}

fn white_of(cmfs: &Cmfs, e: &Spectrum, rule: Rule) -> Result<White> {
    let xyz = cmfs.light_xyz(e, rule)?;
    let c = cct(xyz)?;
    Ok(White {
        xyz,
        xy: xyz.xy(),
        cct_k: c.kelvin,
        duv: c.duv,
    })
}

/// Compares two maps' irradiances (from [`map_irradiance`] with the same normals).
pub fn compare(
    truth: &MapIrradiance,
    reconstructed: &MapIrradiance,
    opts: &RenditionOptions,
) -> Result<Rendition> {
    check_normals(truth, reconstructed, opts)?;
    let grid = shared_grid(&truth.wavelengths_nm, &reconstructed.wavelengths_nm)?;
    let cmfs = Cmfs::new(opts.observer, &grid)?;
    let table = Table::load(&opts.patches)?;
    let bench = Bench {
        cmfs,
        patches: patches_on(&table, &grid)?,
        grid,
        rule: opts.rule,
        d65: Xyz::from_xy(D65_XY),
    };
    let normals = opts
        .normals
        .iter()
        .enumerate()
        .map(|(k, normal)| bench.at_normal(truth, reconstructed, k, normal))
        .collect::<Result<Vec<_>>>()?;
    Ok(summarise(
        truth,
        reconstructed,
        opts,
        &bench,
        &table,
        normals,
    ))
}

/// An error unless there are normals and both maps were integrated at as many.
fn check_normals(
    truth: &MapIrradiance,
    reconstructed: &MapIrradiance,
    opts: &RenditionOptions,
) -> Result<()> {
    if opts.normals.is_empty() {
        return Err(Error::invalid("no normals to light the patches at"));
    }
    for m in [truth, reconstructed] {
        if m.irradiance.len() != opts.normals.len() {
            return Err(Error::invalid(format!(
                "{}: irradiance at {} normals, but {} normals asked for",
                m.file,
                m.irradiance.len(),
                opts.normals.len()
            )));
        }
    }
    Ok(())
}

/// Every column of the patch table, named, resampled smoothly onto `grid`.
fn patches_on(table: &Table, grid: &WavelengthGrid) -> Result<Vec<(String, Spectrum)>> {
    (0..table.columns().len())
        .map(|i| {
            Ok((
                table.columns()[i].clone(),
                table.column_at(i)?.resample(grid, Interpolation::SMOOTH),
            ))
        })
        .collect()
}

/// What every normal is measured with: the shared grid, its CMFs, the patches on it, the rule
/// and the D65 white everything is adapted to.
struct Bench {
    cmfs: Cmfs,
    patches: Vec<(String, Spectrum)>,
    grid: WavelengthGrid,
    rule: Rule,
    d65: Xyz,
}

impl Bench {
    /// Map `m`'s irradiance at normal `k`, resampled (linearly, as a light) onto the grid.
    fn irradiance(&self, m: &MapIrradiance, k: usize) -> Result<Spectrum> {
        Ok(
            Tabulated::new(m.wavelengths_nm.clone(), m.irradiance[k].clone())?
                .resample(&self.grid, Interpolation::LIGHT),
        )
    }

    /// The white of irradiance `e` of map `m`, its errors naming the normal and the map.
    fn white(&self, e: &Spectrum, m: &MapIrradiance, normal: &Normal) -> Result<White> {
        white_of(&self.cmfs, e, self.rule).map_err(|e| {
            Error::invalid(format!(
                "normal {} ({:.3}, {:.3}, {:.3}): {}: {e}",
                normal.name, normal.direction[0], normal.direction[1], normal.direction[2], m.file
            ))
        })
    }

    /// CIELAB against D65 of `xyz` seen under `white`, adapted to D65 by CAT02.
    fn adapted_lab(&self, xyz: Xyz, white: Xyz) -> Lab {
        Lab::from_xyz(Cat::Cat02.adapt(xyz, white, self.d65), self.d65)
    }

    /// Everything measured at normal `k`: the whites, the brightness ratio and every patch.
    fn at_normal(
        &self,
        truth: &MapIrradiance,
        reconstructed: &MapIrradiance,
        k: usize,
        normal: &Normal,
    ) -> Result<NormalResult> {
        let et = self.irradiance(truth, k)?;
        let er = self.irradiance(reconstructed, k)?;
        let wt = self.white(&et, truth, normal)?;
        let wr = self.white(&er, reconstructed, normal)?;
        let irradiance_ratio =
            self.cmfs.integrate(&er, self.rule)?[1] / self.cmfs.integrate(&et, self.rule)?[1];
        let white_de2000 = delta_e_2000(
            self.adapted_lab(wt.xyz, wt.xyz),
            self.adapted_lab(wr.xyz, wt.xyz),
        );
        let results = self.patch_results([(&et, wt.xyz), (&er, wr.xyz)])?;
        let worst = results
            .iter()
            .max_by(|a, b| a.de2000.total_cmp(&b.de2000))
            .expect("at least one patch");
        Ok(NormalResult {
            normal: normal.clone(),
            truth_white: wt,
            reconstructed_white: wr,
            irradiance_ratio,
            white_de2000,
            mean_de2000: results.iter().map(|p| p.de2000).sum::<f64>() / results.len() as f64,
            max_de2000: worst.de2000,
            max_patch: worst.patch.clone(),
            patches: results,
        })
    }

    /// Each patch under the truth's and the reconstruction's irradiance (each with its own
    /// white), adapted to D65 and compared in CIEDE2000.
    fn patch_results(&self, lit: [(&Spectrum, Xyz); 2]) -> Result<Vec<PatchResult>> {
        let [(et, wt), (er, wr)] = lit;
        self.patches
            .iter()
            .map(|(name, rho)| {
                let t = self.adapted_lab(self.cmfs.reflectance_xyz(rho, et, self.rule)?, wt);
                let r = self.adapted_lab(self.cmfs.reflectance_xyz(rho, er, self.rule)?, wr);
                Ok(PatchResult {
                    patch: name.clone(),
                    truth_lab: t,
                    reconstructed_lab: r,
                    de2000: delta_e_2000(t, r),
                })
            })
            .collect()
    }
}

/// The whole comparison from the per-normal results: means and maxima over the normals.
fn summarise(
    truth: &MapIrradiance,
    reconstructed: &MapIrradiance,
    opts: &RenditionOptions,
    bench: &Bench,
    table: &Table,
    normals: Vec<NormalResult>,
) -> Rendition {
    let worst = normals
        .iter()
        .max_by(|a, b| a.max_de2000.total_cmp(&b.max_de2000))
        .expect("at least one normal");
    let n = normals.len() as f64;
    Rendition {
        truth: MapSummary::of(truth),
        reconstructed: MapSummary::of(reconstructed),
        wavelengths: bench.grid,
        observer: opts.observer,
        rule: opts.rule,
        patches: table.name().to_string(),
        adaptation: ADAPTATION,
        white_comparison: WHITE_COMPARISON,
        mean_de2000: normals.iter().map(|r| r.mean_de2000).sum::<f64>() / n,
        max_de2000: worst.max_de2000,
        max_at: [worst.normal.name.clone(), worst.max_patch.clone()],
        white_mean_de2000: normals.iter().map(|r| r.white_de2000).sum::<f64>() / n,
        white_max_de2000: normals.iter().map(|r| r.white_de2000).fold(0.0, f64::max),
        normals,
    }
}

/// Reads both spectral OpenEXR maps and compares their colour rendition.
pub fn rendition(truth: &Path, reconstructed: &Path, opts: &RenditionOptions) -> Result<Rendition> {
    let t = map_irradiance(truth, &opts.normals)?;
    let r = map_irradiance(reconstructed, &opts.normals)?;
    compare(&t, &r, opts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_parse() {
        let up: Normal = "up".parse().unwrap();
        assert_eq!(up.direction, [0.0, 1.0, 0.0]);
        assert_eq!("-x".parse::<Normal>().unwrap().direction, [-1.0, 0.0, 0.0]);
        assert_eq!("NZ".parse::<Normal>().unwrap().direction, [0.0, 0.0, -1.0]);
        let d = "1:1:0".parse::<Normal>().unwrap().direction;
        assert!((d[0] - 0.5f64.sqrt()).abs() < 1e-15 && d[2] == 0.0);
        assert!("0:0:0".parse::<Normal>().is_err());
        assert!("sideways".parse::<Normal>().is_err());
        assert_eq!(Normal::defaults().len(), 5);
    }

    #[test]
    fn shared_grid_takes_the_overlap_at_the_finer_step() {
        let a: Vec<f64> = (0..=68).map(|i| 380.0 + 5.0 * i as f64).collect(); // 380..720
        let b: Vec<f64> = (0..=40).map(|i| 380.0 + 10.0 * i as f64).collect(); // 380..780
        let g = shared_grid(&a, &b).unwrap();
        assert_eq!((g.start_nm(), g.end_nm(), g.step_nm()), (380.0, 720.0, 5.0));
        let c: Vec<f64> = (0..=10).map(|i| 800.0 + 5.0 * i as f64).collect();
        assert!(shared_grid(&a, &c).is_err());
        assert!(shared_grid(&a, &[500.0]).is_err());
        // A step that does not divide the overlap is shrunk until it does.
        let d = [400.0, 407.0, 414.0, 421.0];
        let g = shared_grid(&a, &d).unwrap();
        assert_eq!((g.start_nm(), g.end_nm()), (400.0, 421.0));
        assert!(g.step_nm() <= 5.0 && g.len() == 6);
    }
}
