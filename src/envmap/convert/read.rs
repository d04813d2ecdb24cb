//! The conversion's first stage: read the map (one file or six face files), make its values
//! usable (NaN, infinities and negatives counted), and resample it to the output layout.

use crate::colorimetry::{Chromaticities, RgbSpace};
use crate::envmap::convert::{ConvertOptions, MAX_INPUT};
use crate::envmap::files::{self, EnvmapAttr};
use crate::envmap::layout::{detect, EnvMap, Layout};
use crate::envmap::RgbImage;
use crate::error::{Error, Result};
use std::path::Path;
use std::time::Instant;

/// Pixels changed to make the input usable.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct Sanitized {
    /// NaN or infinite channel values set to 0.
    pub non_finite: usize,
    /// Negative channel values (lossy compression leaves small ones) set to 0.
    pub negative: usize,
    /// Negative channel values kept: under the D65 premise a pixel of positive luminance with a
    /// negative channel is a colour outside the RGB gamut (sodium light), which the spectrum can
    /// carry.
    pub negative_kept: usize,
}

/// Where the input's RGB space comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SpaceSource {
    /// The file's `chromaticities` attribute.
    File,
    /// Asked for (`--space`, or the fit's space), whatever the file declares.
    Given,
    /// The file declares none: OpenEXR reads that as Rec.709 primaries with D65 (sRGB), and a
    /// Radiance HDR file is taken as sRGB too.
    Default,
}

/// The input's RGB space: its primaries and white, and why it is that one.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SpaceChoice {
    /// The space's name (`declared`: the file's chromaticities, which no named space has).
    pub name: &'static str,
    /// The xy of its primaries and white.
    pub chromaticities: Chromaticities,
    /// What RGB (1,1,1) is in the space, in words, e.g. "D50 (x 0.34570, y 0.35850)". It is
    /// taken unadapted: a spectrum has the XYZ the space's RGB -> XYZ matrix gives.
    pub white: String,
    /// Where the space comes from.
    pub source: SpaceSource,
    /// What the file declares, when that is not the space used.
    pub declared: Option<Chromaticities>,
    /// Why the space differs from the file's, in words.
    pub note: Option<String>,
    #[serde(skip)]
    /// The space itself.
    pub space: RgbSpace,
}

impl SpaceChoice {
    /// The space of a file that declares `declared`, for `opts`.
    pub fn resolve(
        input: &str,
        declared: Option<Chromaticities>,
        opts: &ConvertOptions,
    ) -> Result<SpaceChoice> {
        let choice = |space: RgbSpace, source, note| SpaceChoice {
            name: space.name,
            chromaticities: space.chromaticities(),
            white: space.white_name(),
            source,
            declared: declared.filter(|c| !c.same_as(&space.chromaticities())),
            note,
            space,
        };
        // A fit was solved in its own space; otherwise `--space` when asked.
        let given = match &opts.fit {
            Some(f) => Some((f.rgb_space(), "the fit's space")),
            None => opts
                .space_overrides_file
                .then_some((opts.space, "the space asked for")),
        };
        Ok(match (declared, given) {
            (Some(c), None) => {
                let space = RgbSpace::from_chromaticities(c)
                    .map_err(|e| Error::invalid(format!("{input}: {e}")))?;
                choice(space, SpaceSource::File, None)
            }
            (Some(c), Some((space, what))) if !c.same_as(&space.chromaticities()) => {
                let note = format!(
                    "{what}, {} ({}), overrides the file's chromaticities ({c}): its RGB is \
                     read in {}",
                    space.name,
                    space.chromaticities(),
                    space.name
                );
                choice(space, SpaceSource::Given, Some(note))
            }
            (_, Some((space, _))) => choice(space, SpaceSource::Given, None),
            (None, None) => choice(opts.space, SpaceSource::Default, None),
        })
    }
}

/// A pixel index and its RGB before negatives were clamped.
pub type OutOfGamut = (usize, [f32; 3]);

/// The map as read, sanitised and laid out for the output.
#[derive(Debug, Clone)]
pub struct Input {
    /// The map, sanitised and laid out for the output.
    pub map: EnvMap,
    /// The input in words (format, compression, channels).
    pub description: String,
    /// The input's layout.
    pub layout: Layout,
    /// The input's size in pixels (width, height).
    pub size: [usize; 2],
    /// What sanitising changed.
    pub sanitized: Sanitized,
    /// The RGB space the map's values are in.
    pub space: SpaceChoice,
    /// Out-of-gamut pixels as they were (restored under the D65 premise when not resampled).
    pub out_of_gamut: Vec<OutOfGamut>,
    /// The map was resampled (layout, size or orientation changed).
    pub resampled: bool,
    /// Seconds spent reading.
    pub seconds: f64,
}

impl Input {
    /// Restores the out-of-gamut pixels (the D65 premise keeps them); a note when resampling
    /// already set them to 0.
    pub fn keep_out_of_gamut(&mut self) -> Option<String> {
        if self.out_of_gamut.is_empty() {
            return None;
        }
        if self.resampled {
            return Some(format!(
                "{} out-of-gamut pixels (negative channels) were set to 0 before resampling",
                self.out_of_gamut.len()
            ));
        }
        for &(i, p) in &self.out_of_gamut {
            let n = p.iter().filter(|&&v| v < 0.0).count();
            self.sanitized.negative -= n;
            self.sanitized.negative_kept += n;
            self.map.image.pixels[i] = p;
        }
        None
    }
}

/// Reads, sanitises and lays out `input` for `opts`.
pub fn read(input: &str, opts: &ConvertOptions) -> Result<Input> {
    let t0 = Instant::now();
    let (map, description, declared) = read_input(input, opts)?;
    prepare(input, map, description, declared, opts, t0)
}

/// An RGB image already in memory (a Python array), named `name` in messages, as the conversion
/// reads a file: its layout from `opts.in_layout` or its shape, its values in `opts.space`.
pub fn from_image(name: &str, image: RgbImage, opts: &ConvertOptions) -> Result<Input> {
    let t0 = Instant::now();
    let layout = match opts.in_layout {
        Some(l) => l,
        None => detect(image.width, image.height, None)
            .map_err(|e| Error::invalid(format!("{name}: {e}")))?,
    };
    let description = format!("an RGB array of {} x {} pixels", image.width, image.height);
    let map = EnvMap::new(layout, image).map_err(|e| Error::invalid(format!("{name}: {e}")))?;
    prepare(name, map, description, None, opts, t0)
}

/// The map as read: its space resolved, its values sanitised, laid out for the output.
fn prepare(
    input: &str,
    mut map: EnvMap,
    description: String,
    declared: Option<Chromaticities>,
    opts: &ConvertOptions,
    t0: Instant,
) -> Result<Input> {
    let space = SpaceChoice::resolve(input, declared, opts)?;
    let (sanitized, out_of_gamut) = sanitize(&mut map, opts.strict, input, &space.space)?;
    let layout = map.layout;
    let size = [map.image.width, map.image.height];
    let out_layout = opts.out_layout.unwrap_or(layout);
    let in_size = map.face_size();
    let face = opts.size.unwrap_or(match (layout, out_layout) {
        (a, b) if a == b => in_size,
        // Matched pixel density: a lat-long 4N wide has about the pixels per radian of faces N.
        (Layout::LatLong, _) => (in_size / 2).max(1),
        (_, Layout::LatLong) => in_size * 2,
        _ => in_size,
    });
    if face == 0 {
        return Err(Error::invalid("--size must be at least 1"));
    }
    let resampled = out_layout != layout || face != in_size || !opts.orientation.is_identity();
    if resampled {
        map = map.resample_oriented(out_layout, face, &opts.orientation);
    }
    Ok(Input {
        map,
        description,
        layout,
        size,
        sanitized,
        space,
        out_of_gamut,
        resampled,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Reads the input map (one file or six face files) with its layout and the chromaticities it
/// declares.
fn read_input(
    input: &str,
    opts: &ConvertOptions,
) -> Result<(EnvMap, String, Option<Chromaticities>)> {
    if opts.faces || input.contains("{face}") {
        let faces = files::read_face_files(input, opts.layer.as_deref())?;
        let declared = faces[0].chromaticities;
        if let Some(k) = (1..6).find(|&k| faces[k].chromaticities != declared) {
            return Err(Error::invalid(format!(
                "{input}: the {} face declares other chromaticities than the {} face ({} and \
                 {}): one map is in one RGB space",
                files::FACE_NAMES[k],
                files::FACE_NAMES[0],
                describe(faces[k].chromaticities),
                describe(declared)
            )));
        }
        let map = EnvMap::from_faces(faces.map(|f| f.image))?;
        return Ok((map, format!("six face files {input}"), declared));
    }
    let img = files::read_rgb(Path::new(input), opts.layer.as_deref())?;
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
    Ok((map, img.description, img.chromaticities))
}

fn describe(c: Option<Chromaticities>) -> String {
    c.map_or("none".into(), |c| c.to_string())
}

/// Sets NaN/infinite values to 0 (or refuses them) and clamps negatives, counting both. Pixels of
/// positive luminance with a negative channel (out-of-gamut colours) are returned as they were,
/// to be restored under the D65 premise.
fn sanitize(
    map: &mut EnvMap,
    strict: bool,
    input: &str,
    space: &RgbSpace,
) -> Result<(Sanitized, Vec<OutOfGamut>)> {
    let mut s = Sanitized::default();
    let m = space.to_xyz_matrix();
    let mut out_of_gamut = Vec::new();
    let width = map.image.width;
    for (i, p) in map.image.pixels.iter_mut().enumerate() {
        if p.iter().all(|v| v.is_finite()) && p.iter().any(|&v| v < 0.0) {
            let y = (0..3).map(|k| m[(1, k)] * p[k] as f64).sum::<f64>();
            if y > 0.0 {
                out_of_gamut.push((i, *p));
            }
        }
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
            } else if (*v as f64).abs() > MAX_INPUT {
                return Err(Error::invalid(format!(
                    "{input}: pixel ({}, {}) channel {} is {v:e}, beyond {MAX_INPUT:e}: no \
                     radiance map holds that (the sun is about 1e9 cd/m^2); a corrupt or \
                     mis-scaled file? Scale it down first",
                    i % width,
                    i / width,
                    ["R", "G", "B"][c]
                )));
            } else if *v < 0.0 {
                *v = 0.0;
                s.negative += 1;
            }
        }
    }
    Ok((s, out_of_gamut))
}
