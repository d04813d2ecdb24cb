//! RGB environment map -> spectral environment map: read, sanitise, resample, find the sun,
//! choose the main light, fit, and stream the spectral OpenEXR out block by block.

use crate::colorimetry::{Observer, RgbSpace};
use crate::data;
use crate::envmap::engine::Engine;
use crate::envmap::exrio::{
    self, spectral_channel_name, AttrValue, ChannelSet, Compression, EnvmapAttr, Precision,
    SpectralLayout, SpectralWriter, HALF_MAX,
};
use crate::envmap::layout::{detect, EnvMap, Layout};
use crate::envmap::light::{self, LightChoice};
use crate::envmap::sun::{find_sun, SunSearch, SunSettings};
use crate::error::{Error, Result};
use crate::fit::{self, Fit, FitInput, Mode};
use crate::illuminant;
use crate::spectrum::{Rule, Tabulated, WavelengthGrid};
use crate::tradeoff::{choose_grid, colorchecker_under, GridChoice};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The main light: a spectrum name, or chosen from the scene.
#[derive(Debug, Clone, PartialEq)]
pub enum LightSpec {
    Named(String),
    Auto,
}

/// The SPD given to the sun's pixels.
#[derive(Debug, Clone, PartialEq)]
pub enum SunSpd {
    /// CIE D65, as in the paper.
    D65,
    /// Daylight (or a Planckian radiator below 4000 K) at the sun pixels' CCT.
    Match,
    /// Any light by name.
    Light(String),
}

/// The most bytes of f32 rows computed before they are written (one batch; the writer's blocks
/// and their compressed form come on top, about as much again).
const BATCH_BYTES: usize = 96 << 20;

/// What is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum OutputFormat {
    /// One channel per wavelength (Fichet et al. 2021), R, G, B previews and a sun mask.
    Spectral,
    /// Four channels (c_R, c_G, c_B, sun) and the basis spectra in the header.
    Basis,
}

/// Everything a conversion needs besides its input and output paths.
#[derive(Debug, Clone)]
pub struct ConvertOptions {
    pub light: LightSpec,
    /// A fit from `specmap fit -o`; otherwise the basis is fitted on the output grid.
    pub fit: Option<Fit>,
    pub mode: Mode,
    pub space: RgbSpace,
    pub basis: [String; 3],
    pub observer: Observer,
    pub rule: Rule,
    /// None: no sun detection.
    pub sun: Option<SunSettings>,
    pub sun_spd: SunSpd,
    /// Overrides the layout found from the `envmap` attribute or the aspect ratio.
    pub in_layout: Option<Layout>,
    /// The input is a pattern with `{face}` naming six face files.
    pub faces: bool,
    /// A named layer of the input (`<layer>.R`...).
    pub layer: Option<String>,
    /// None: the input's layout.
    pub out_layout: Option<Layout>,
    /// Output face size (cube-like) or height (lat-long); None: matched to the input.
    pub size: Option<usize>,
    pub grid: WavelengthGrid,
    pub format: OutputFormat,
    pub precision: Precision,
    pub compression: Compression,
    /// The zlib level of ZIP/ZIPS (OpenEXR's default 4; 1 is fastest, 12 smallest).
    pub zip_level: u8,
    /// Choose the coarsest wavelength step within `grid`'s range whose colours stay within this
    /// CIEDE2000 of a 1 nm reference (see [`crate::tradeoff`]).
    pub tolerance: Option<f64>,
    /// NaN or infinite pixels are an error instead of being set to 0.
    pub strict: bool,
}

impl Default for ConvertOptions {
    fn default() -> Self {
        ConvertOptions {
            light: LightSpec::Named("D65".into()),
            fit: None,
            mode: Mode::Exact,
            space: RgbSpace::SRGB,
            basis: fit::PAPER_BASIS.map(String::from),
            observer: Observer::Cie1931,
            rule: Rule::Riemann,
            sun: Some(SunSettings::default()),
            sun_spd: SunSpd::D65,
            in_layout: None,
            faces: false,
            layer: None,
            out_layout: None,
            size: None,
            grid: "380:780:5".parse().expect("a valid grid"),
            format: OutputFormat::Spectral,
            precision: Precision::Half,
            compression: Compression::Zip,
            zip_level: crate::envmap::exrio::ZIP_DEFAULT_LEVEL,
            tolerance: None,
            strict: false,
        }
    }
}

/// Pixels changed to make the input usable.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct Sanitized {
    /// NaN or infinite channel values set to 0.
    pub non_finite: usize,
    /// Negative channel values (lossy compression leaves small ones) set to 0.
    pub negative: usize,
}

/// RGB -> SPD -> RGB over the written pixels.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct RoundTripStats {
    /// Energy-weighted (luminance x solid angle) mean CIEDE2000.
    pub weighted_mean_de2000: f64,
    pub max_de2000: f64,
    pub pixels: usize,
}

/// What a conversion did.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ConvertReport {
    pub input: String,
    pub input_description: String,
    pub input_layout: Layout,
    pub input_size: [usize; 2],
    pub output: String,
    pub output_layout: Layout,
    pub output_size: [usize; 2],
    pub format: OutputFormat,
    pub precision: &'static str,
    pub compression: String,
    /// Values were divided by 2^EV to fit half floats (None: not needed).
    pub ev: Option<f64>,
    pub sanitized: Sanitized,
    pub sun: SunSearch,
    pub sun_spd: Option<String>,
    pub light: String,
    pub light_choice: Option<LightChoice>,
    pub mode: Mode,
    pub weights: [f64; 3],
    pub condition_number: f64,
    pub regularized: bool,
    pub wavelengths_nm: Vec<f64>,
    pub channels: usize,
    pub bytes: u64,
    /// Over all pixels, and over those not replaced by the sun's SPD.
    pub roundtrip: RoundTripStats,
    pub roundtrip_without_sun: RoundTripStats,
    pub seconds_read: f64,
    pub seconds_convert: f64,
    /// The part of `seconds_convert` spent encoding and compressing the EXR blocks.
    pub seconds_encode: f64,
    /// What `--tolerance` chose (None: the grid was given).
    pub grid_choice: Option<GridChoice>,
    pub megapixels_per_second: f64,
}

/// Reads the input map (one file or six face files) with its layout.
fn read_input(input: &str, opts: &ConvertOptions) -> Result<(EnvMap, String)> {
    if opts.faces || input.contains("{face}") {
        let faces = exrio::read_faces(input, opts.layer.as_deref())?;
        let map = EnvMap::from_faces(faces)?;
        return Ok((map, format!("six face files {input}")));
    }
    let img = exrio::read_rgb(Path::new(input), opts.layer.as_deref())?;
    let attr = img.envmap.map(|a| match a {
        EnvmapAttr::LatLong => Layout::LatLong,
        EnvmapAttr::Cube => Layout::Cube,
    });
    let layout = match opts.in_layout {
        Some(l) => l,
        None => detect(img.image.width, img.image.height, attr)
            .map_err(|e| Error::invalid(format!("{input}: {e}")))?,
    };
    let map =
        EnvMap::new(layout, img.image).map_err(|e| Error::invalid(format!("{input}: {e}")))?;
    Ok((map, img.description))
}

/// Sets NaN/infinite values to 0 (or refuses them) and clamps negatives, counting both.
fn sanitize(map: &mut EnvMap, strict: bool, input: &str) -> Result<Sanitized> {
    let mut s = Sanitized::default();
    let width = map.image.width;
    for (i, p) in map.image.pixels.iter_mut().enumerate() {
        for (c, v) in p.iter_mut().enumerate() {
            if !v.is_finite() {
                if strict {
                    return Err(Error::invalid(format!(
                        "{input}: pixel ({}, {}) channel {} is {v} (--strict refuses NaN and \
                         infinite values)",
                        i % width,
                        i / width,
                        ["R", "G", "B"][c]
                    )));
                }
                *v = 0.0;
                s.non_finite += 1;
            } else if *v < 0.0 {
                *v = 0.0;
                s.negative += 1;
            }
        }
    }
    Ok(s)
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

/// Converts `input` to a spectral (or basis) OpenEXR at `output`. `progress(done, total)` is
/// called after each batch of rows.
pub fn convert(
    input: &str,
    output: &Path,
    opts: &ConvertOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<ConvertReport> {
    if same_file(Path::new(input), output) {
        return Err(Error::invalid(format!(
            "the output {} is the input: choose another name (inputs are never overwritten)",
            output.display()
        )));
    }
    let t0 = Instant::now();
    let (mut map, description) = read_input(input, opts)?;
    let sanitized = sanitize(&mut map, opts.strict, input)?;
    let input_layout = map.layout;
    let input_size = [map.image.width, map.image.height];
    let seconds_read = t0.elapsed().as_secs_f64();

    // Output layout and size.
    let out_layout = opts.out_layout.unwrap_or(input_layout);
    let in_size = map.face_size();
    let size = opts.size.unwrap_or(match (input_layout, out_layout) {
        (a, b) if a == b => in_size,
        // Matched pixel density: a lat-long 4N wide has about the pixels per radian of faces N.
        (Layout::LatLong, _) => (in_size / 2).max(1),
        (_, Layout::LatLong) => in_size * 2,
        _ => in_size,
    });
    if size == 0 {
        return Err(Error::invalid("--size must be at least 1"));
    }
    if out_layout != input_layout || size != in_size {
        map = map.resample(out_layout, size);
    }

    let sun = match &opts.sun {
        Some(settings) => find_sun(&map, &opts.space, settings),
        None => SunSearch::NotFound {
            reason: "sun detection is off (--sun off)".into(),
        },
    };

    // The main light.
    let (light_name, light_choice) = match &opts.light {
        LightSpec::Named(n) => (n.clone(), None),
        LightSpec::Auto => {
            let c = light::choose(&map, &sun, &opts.space)?;
            (c.light.clone(), Some(c))
        }
    };
    // The sun's SPD.
    let sun_spd: Option<(String, Tabulated)> = match (sun.sun(), &opts.sun_spd) {
        (None, _) => None,
        (Some(_), SunSpd::D65) => Some(("D65".into(), data::spectrum("D65")?.data)),
        (Some(s), SunSpd::Match) => {
            let k = s.cct.kelvin.unwrap_or(6504.0);
            let label = if k < illuminant::DAYLIGHT_RANGE_K.0 {
                format!("Planckian {k:.0} K")
            } else {
                format!(
                    "CIE daylight {:.0} K",
                    k.min(illuminant::DAYLIGHT_RANGE_K.1)
                )
            };
            Some((label, illuminant::natural(k)?))
        }
        (Some(_), SunSpd::Light(name)) => {
            let s = data::spectrum(name)?;
            Some((s.label, s.data))
        }
    };
    // The grid: as given, or the coarsest step within its range that keeps the ColorChecker
    // under the main light (and under the sun's SPD) within --tolerance.
    let grid_choice = match opts.tolerance {
        None => None,
        Some(tolerance) => {
            let light_spd = data::spectrum(&light_name)?;
            let mut stimuli = colorchecker_under(&light_spd.label, &light_spd.data)?;
            if let Some((label, spd)) = &sun_spd {
                stimuli.extend(colorchecker_under(&format!("sun ({label})"), spd)?);
            }
            let (start, end) = (opts.grid.start_nm(), opts.grid.end_nm());
            Some(choose_grid(
                &stimuli,
                opts.observer,
                start,
                end,
                opts.rule,
                tolerance,
            )?)
        }
    };
    let grid = grid_choice.as_ref().map_or(opts.grid, |c| c.chosen);
    let fit = match &opts.fit {
        Some(f) => f.clone(),
        None => {
            let input = FitInput::from_names(
                &light_name,
                opts.basis.each_ref().map(String::as_str),
                &grid,
                opts.observer,
                opts.rule,
                opts.space,
            )?;
            fit::fit(&input, opts.mode)?
        }
    };

    let engine = Engine::new(&fit, grid, opts.rule, sun_spd.as_ref().map(|(_, t)| t))?;
    let sun_mask = {
        let mut m = vec![false; map.image.pixels.len()];
        if sun_spd.is_some() {
            if let Some(s) = sun.sun() {
                for &i in &s.pixels {
                    m[i] = true;
                }
            }
        }
        m
    };

    // The channels.
    let wavelengths: Vec<f64> = grid.wavelengths_nm().collect();
    let bands = wavelengths.len();
    let names: Vec<String> = match opts.format {
        OutputFormat::Spectral => wavelengths
            .iter()
            .map(|&w| spectral_channel_name(w))
            .chain(["R", "G", "B", "sun"].map(String::from))
            .collect(),
        OutputFormat::Basis => ["c_R", "c_G", "c_B", "sun"].map(String::from).to_vec(),
    };
    let per_pixel = names.len();

    // Half floats top out at 65504: scale by 2^EV when the largest value would not fit.
    let ev = match opts.precision {
        Precision::Float => None,
        Precision::Half => {
            let bound = value_bound(&map, &engine, &sun_mask, opts.format);
            (bound > HALF_MAX as f64).then(|| (bound / HALF_MAX as f64).log2().ceil())
        }
    };

    let mut attributes = vec![
        (
            "specmap.version".to_string(),
            AttrValue::Text(env!("CARGO_PKG_VERSION").into()),
        ),
        ("specmap.light".into(), AttrValue::Text(fit.light.clone())),
        (
            "specmap.mode".into(),
            AttrValue::Text(format!("{:?}", fit.mode).to_lowercase()),
        ),
        ("specmap.space".into(), AttrValue::Text(fit.space.clone())),
        (
            "specmap.observer".into(),
            AttrValue::Text(fit.observer.table_name().into()),
        ),
        ("specmap.basis".into(), AttrValue::Text(fit.basis.join(","))),
        (
            "specmap.weights".into(),
            AttrValue::F32Vec(fit.weights.map(|v| v as f32).to_vec()),
        ),
        (
            "specmap.matrix".into(),
            AttrValue::F32Vec(fit.matrix.iter().flatten().map(|&v| v as f32).collect()),
        ),
        (
            "specmap.lightRGB".into(),
            AttrValue::F32Vec(engine.light_rgb().map(|v| v as f32).to_vec()),
        ),
        (
            "specmap.radiometry".into(),
            AttrValue::Text(
                "relative radiance; Y = sum(L ybar) / sum(ybar); RGB (1,1,1) is the main \
                 light's SPD at Y = 1"
                    .into(),
            ),
        ),
        (
            "specmap.sun".into(),
            AttrValue::Text(serde_json::to_string(&sun).unwrap_or_default()),
        ),
    ];
    // OpenEXR text attributes are bytes that readers decode as UTF-8 or Latin-1: keep them ASCII.
    for (_, v) in attributes.iter_mut() {
        if let AttrValue::Text(t) = v {
            *t = t
                .chars()
                .map(|c| if c.is_ascii() { c } else { '?' })
                .collect();
        }
    }
    if opts.format == OutputFormat::Basis {
        attributes.push((
            "specmap.wavelengths".into(),
            AttrValue::F32Vec(wavelengths.iter().map(|&w| w as f32).collect()),
        ));
        for (j, b) in engine.basis_spectra().iter().enumerate() {
            attributes.push((format!("specmap.basis{j}"), AttrValue::F32Vec(b.clone())));
        }
        if let Some(s) = engine.sun_spectrum() {
            attributes.push(("specmap.sunSPD".into(), AttrValue::F32Vec(s.to_vec())));
        }
    }
    let envmap = match map.layout {
        Layout::LatLong => Some(EnvmapAttr::LatLong),
        Layout::Cube => Some(EnvmapAttr::Cube),
        _ => None,
    };
    let (width, height) = (map.image.width, map.image.height);
    let mut writer = SpectralWriter::create(
        output,
        SpectralLayout {
            width,
            height,
            channels: ChannelSet::Custom(names),
            precision: opts.precision,
            compression: opts.compression,
            envmap,
            ev,
            attributes,
            zip_level: opts.zip_level,
        },
    )?;

    // Stream blocks of rows, computed in parallel.
    let t1 = Instant::now();
    // Rows are computed, then written, a batch at a time: whole compression blocks, enough for
    // the writer to compress them in parallel, within BATCH_BYTES.
    let lines = opts.compression.lines_per_block();
    let block_bytes = lines * width * per_pixel * std::mem::size_of::<f32>();
    let blocks = (BATCH_BYTES / block_bytes.max(1)).clamp(1, height.div_ceil(lines));
    let rows_per_block = (blocks * lines).max(16).min(height);
    let mut buffer = vec![0f32; rows_per_block * width * per_pixel];
    let (mut all, mut no_sun) = (Accumulator::default(), Accumulator::default());
    let mut y0 = 0;
    while y0 < height {
        let rows = rows_per_block.min(height - y0);
        let buf = &mut buffer[..rows * width * per_pixel];
        let stats: Vec<(Accumulator, Accumulator)> = buf
            .par_chunks_mut(width * per_pixel)
            .enumerate()
            .map(|(r, row)| {
                let y = y0 + r;
                let (mut a, mut b) = (Accumulator::default(), Accumulator::default());
                // The basis format writes coefficients; the round trip still needs the spectrum.
                let mut scratch = vec![0f32; bands];
                for x in 0..width {
                    let i = y * width + x;
                    let rgb = map.image.pixels[i];
                    let is_sun = sun_mask[i];
                    let out = &mut row[x * per_pixel..(x + 1) * per_pixel];
                    let back = match opts.format {
                        OutputFormat::Spectral => {
                            let r = engine.spectrum(rgb, is_sun, &mut out[..bands]);
                            out[bands..bands + 3].copy_from_slice(&rgb);
                            out[bands + 3] = is_sun as u8 as f32;
                            r.rgb_back
                        }
                        OutputFormat::Basis => {
                            let c = engine.coefficients(rgb, is_sun);
                            for k in 0..4 {
                                out[k] = c[k] as f32;
                            }
                            engine.spectrum(rgb, is_sun, &mut scratch).rgb_back
                        }
                    };
                    let omega = map.solid_angle(x, y);
                    let lum = engine.luminance(rgb);
                    if lum > 0.0 && omega > 0.0 {
                        let de = engine.round_trip_error(rgb, back);
                        a.add(de, lum * omega);
                        if !is_sun {
                            b.add(de, lum * omega);
                        }
                    }
                }
                (a, b)
            })
            .collect();
        for (a, b) in stats {
            all.merge(&a);
            no_sun.merge(&b);
        }
        writer.write_rows(y0, buf)?;
        y0 += rows;
        progress(y0, height);
    }
    let seconds_encode = writer.encode_seconds();
    let bytes = writer.finish()?;
    let seconds_convert = t1.elapsed().as_secs_f64();

    Ok(ConvertReport {
        input: input.to_string(),
        input_description: description,
        input_layout,
        input_size,
        output: output.display().to_string(),
        output_layout: map.layout,
        output_size: [width, height],
        format: opts.format,
        precision: match opts.precision {
            Precision::Half => "half",
            Precision::Float => "float",
        },
        compression: format!("{:?}", opts.compression).to_lowercase(),
        ev,
        sanitized,
        sun_spd: sun_spd.map(|(l, _)| l),
        sun,
        light: fit.light.clone(),
        light_choice,
        mode: fit.mode,
        weights: fit.weights,
        condition_number: fit.condition_number,
        regularized: fit.regularized,
        wavelengths_nm: wavelengths,
        channels: per_pixel,
        bytes,
        roundtrip: all.stats(),
        roundtrip_without_sun: no_sun.stats(),
        grid_choice,
        seconds_read,
        seconds_convert,
        seconds_encode,
        megapixels_per_second: (input_size[0] * input_size[1]) as f64
            / 1e6
            / (seconds_read + seconds_convert),
    })
}

/// An upper bound of the values written (to choose an EV scale for half floats).
fn value_bound(map: &EnvMap, engine: &Engine, sun: &[bool], format: OutputFormat) -> f64 {
    let peak: Vec<f64> = engine
        .basis_spectra()
        .iter()
        .map(|b| b.iter().fold(0f32, |m, &v| m.max(v.abs())) as f64)
        .collect();
    let sun_peak = engine
        .sun_spectrum()
        .map(|s| s.iter().fold(0f32, |m, &v| m.max(v.abs())) as f64)
        .unwrap_or(0.0);
    map.image
        .pixels
        .par_iter()
        .enumerate()
        .map(|(i, &rgb)| {
            let c = engine.coefficients(rgb, sun[i]);
            let preview = rgb.iter().fold(0f32, |m, &v| m.max(v)) as f64;
            let spectral = match format {
                OutputFormat::Spectral => {
                    (0..3).map(|j| c[j].abs() * peak[j]).sum::<f64>() + c[3] * sun_peak
                }
                OutputFormat::Basis => c.iter().fold(0f64, |m, v| m.max(v.abs())),
            };
            spectral.max(preview)
        })
        .reduce(|| 0.0, f64::max)
}

#[derive(Debug, Clone, Copy, Default)]
struct Accumulator {
    weighted: f64,
    weight: f64,
    max: f64,
    pixels: usize,
}

impl Accumulator {
    fn add(&mut self, de: f64, w: f64) {
        self.weighted += de * w;
        self.weight += w;
        self.max = self.max.max(de);
        self.pixels += 1;
    }
    fn merge(&mut self, o: &Accumulator) {
        self.weighted += o.weighted;
        self.weight += o.weight;
        self.max = self.max.max(o.max);
        self.pixels += o.pixels;
    }
    fn stats(&self) -> RoundTripStats {
        RoundTripStats {
            weighted_mean_de2000: if self.weight > 0.0 {
                self.weighted / self.weight
            } else {
                0.0
            },
            max_de2000: self.max,
            pixels: self.pixels,
        }
    }
}

/// The default output path for an input: `NAME.spectral.exr` beside it.
pub fn default_output(input: &str) -> PathBuf {
    let p = Path::new(input);
    let stem = p
        .file_stem()
        .map(|s| s.to_string_lossy())
        .unwrap_or_default();
    p.with_file_name(format!("{stem}.spectral.exr"))
}
