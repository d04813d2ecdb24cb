//! Speed for accuracy: the colour error of a wavelength grid and integration rule against a 1 nm
//! Simpson reference, and the coarsest grid that a scene's lights, surfaces and films need.
//!
//! A *stimulus* is what reaches the eye: a light seen directly, a reflectance under a light, or
//! a thin film under a light. Its colour on a grid is the paper's Eq. 10/11 with the light, the
//! surface and the CMFs all sampled on that grid (lights interpolated linearly, smooth data by
//! Sprague/spline, films evaluated at each wavelength), as a spectral renderer working at that
//! step would see it. The error is CIEDE2000 between that colour and the same stimulus at 1 nm by
//! Simpson's rule, both in CIELAB relative to the light's white at 1 nm.

use crate::colorimetry::{delta_e_2000, Cmfs, Lab, Observer, Xyz};
use crate::data;
use crate::error::{Error, Result};
use crate::spectrum::{Interpolation, Rule, Spectrum, Tabulated, WavelengthGrid};
use crate::thinfilm::{Coherence, Incidence, Polarization, Stack};
use std::time::Instant;

/// The steps `--tolerance` tries, coarsest first (those that divide the range).
pub const STEPS_NM: [f64; 7] = [20.0, 10.0, 5.0, 4.0, 2.0, 1.0, 0.5];

/// What a light falls on before it reaches the eye.
// A scene has tens of stimuli: boxing the film would buy nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub enum Surface {
    /// Nothing: the light itself, seen directly.
    Emitter,
    /// A tabulated reflectance factor (smooth data).
    Reflectance(Tabulated),
    /// A thin-film stack, unpolarised light at an incidence angle.
    Film {
        /// The layers between ambient and substrate.
        stack: Stack,
        /// The angle of incidence in the ambient medium.
        incidence: Incidence,
        /// Which layers are treated coherently.
        coherence: Coherence,
    },
    /// Everything the light passes through, multiplied: a basis reflectance of the map, a
    /// film's reflectance or transmittance, a pigment (films coherent, unpolarised light).
    Product(Vec<Factor>),
}

/// One factor of a [`Surface::Product`].
// Tens of factors per scene: boxing the film would buy nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub enum Factor {
    /// A tabulated reflectance factor (smooth data).
    Reflectance(Tabulated),
    /// A tabulated emission (light data, interpolated linearly as a renderer samples a light):
    /// a spectral map's texel, radiating over an equal-energy normaliser.
    Emission(Tabulated),
    /// The film's reflectance at an incidence angle.
    FilmReflectance(Stack, Incidence),
    /// The power the film lets through to what lies under it, at an incidence angle.
    FilmTransmittance(Stack, Incidence),
}

impl Factor {
    /// The factor at each wavelength.
    fn values_at(&self, wavelengths_nm: &[f64]) -> Result<Vec<f64>> {
        match self {
            Factor::Reflectance(r) => Ok(sample(r, wavelengths_nm, Interpolation::SMOOTH)),
            Factor::Emission(e) => Ok(sample(e, wavelengths_nm, Interpolation::LIGHT)),
            Factor::FilmReflectance(stack, incidence)
            | Factor::FilmTransmittance(stack, incidence) => {
                let reflect = matches!(self, Factor::FilmReflectance(..));
                wavelengths_nm
                    .iter()
                    .map(|&wl| {
                        let rt = stack
                            .at::<f64>(wl)?
                            .rt(incidence, Polarization::Unpolarized);
                        Ok(if reflect { rt.r } else { rt.t })
                    })
                    .collect()
            }
        }
    }
}

/// `t` at arbitrary wavelengths by `method` (one uniform grid when they form one).
pub fn sample(t: &Tabulated, wavelengths_nm: &[f64], method: Interpolation) -> Vec<f64> {
    if let Some(grid) = uniform_grid(wavelengths_nm) {
        return t.resample(&grid, method).values().to_vec();
    }
    wavelengths_nm
        .iter()
        .map(|&w| match WavelengthGrid::new(w, w, 1.0) {
            Ok(g) => t.resample(&g, method).values()[0],
            Err(_) => f64::NAN,
        })
        .collect()
}

/// The uniform grid the wavelengths form, if they do (two or more, equally spaced).
fn uniform_grid(wavelengths_nm: &[f64]) -> Option<WavelengthGrid> {
    let (first, last) = (*wavelengths_nm.first()?, *wavelengths_nm.last()?);
    if wavelengths_nm.len() < 2 {
        return None;
    }
    let step = (last - first) / (wavelengths_nm.len() - 1) as f64;
    let grid = WavelengthGrid::new(first, last, step).ok()?;
    (grid.len() == wavelengths_nm.len()
        && grid
            .wavelengths_nm()
            .zip(wavelengths_nm)
            .all(|(a, b)| (a - b).abs() <= 1e-9 * b.abs()))
    .then_some(grid)
}

/// A light and what it falls on.
#[derive(Debug, Clone)]
pub struct Stimulus {
    /// Name for reports.
    pub name: String,
    /// The light's SPD, at its own wavelengths.
    pub light: Tabulated,
    /// What the light falls on.
    pub surface: Surface,
    /// How bright it appears, in units of its light's perfect white (1: as bright as a white
    /// surface under the light). Colour errors grow with brightness, so a quadrature's estimate
    /// ([`crate::quadrature`]) is taken at this brightness; [`choose_grid`] ignores it.
    pub gain: f64,
}

impl Stimulus {
    /// `light` falling on `surface`, at gain 1.
    pub fn new(name: impl Into<String>, light: Tabulated, surface: Surface) -> Stimulus {
        Stimulus {
            name: name.into(),
            light,
            surface,
            gain: 1.0,
        }
    }

    /// The light seen directly.
    pub fn emitter(name: impl Into<String>, light: Tabulated) -> Stimulus {
        Stimulus::new(name, light, Surface::Emitter)
    }

    /// The same stimulus at another brightness.
    pub fn with_gain(self, gain: f64) -> Stimulus {
        Stimulus { gain, ..self }
    }

    /// The light and the stimulus (light times surface) at each wavelength.
    pub fn values_at(&self, wavelengths_nm: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
        let light = sample(&self.light, wavelengths_nm, Interpolation::LIGHT);
        let factor = self.surface_at(wavelengths_nm)?;
        let total = light.iter().zip(&factor).map(|(l, f)| l * f).collect();
        Ok((light, total))
    }

    /// What the surface passes of the light at each wavelength (1 for an emitter).
    pub fn surface_at(&self, wavelengths_nm: &[f64]) -> Result<Vec<f64>> {
        Ok(match &self.surface {
            Surface::Emitter => vec![1.0; wavelengths_nm.len()],
            Surface::Reflectance(r) => sample(r, wavelengths_nm, Interpolation::SMOOTH),
            Surface::Film {
                stack,
                incidence,
                coherence,
            } => match uniform_grid(wavelengths_nm) {
                Some(grid) => {
                    stack
                        .response(
                            &grid,
                            incidence,
                            Polarization::Unpolarized,
                            coherence.clone(),
                        )?
                        .reflectance
                }
                None => {
                    Factor::FilmReflectance(stack.clone(), *incidence).values_at(wavelengths_nm)?
                }
            },
            Surface::Product(factors) => {
                let mut v = vec![1.0; wavelengths_nm.len()];
                for f in factors {
                    for (a, b) in v.iter_mut().zip(f.values_at(wavelengths_nm)?) {
                        *a *= b;
                    }
                }
                v
            }
        })
    }

    /// XYZ (Y = 100 for the light's perfect white) with everything sampled on the CMFs' grid.
    pub fn xyz(&self, cmfs: &Cmfs, rule: Rule) -> Result<Xyz> {
        let grid = cmfs.grid();
        let light = self.light.resample(grid, Interpolation::LIGHT);
        match &self.surface {
            Surface::Emitter => cmfs.light_xyz(&light, rule),
            Surface::Reflectance(r) => {
                cmfs.reflectance_xyz(&r.resample(grid, Interpolation::SMOOTH), &light, rule)
            }
            Surface::Film { .. } | Surface::Product(_) => {
                let wavelengths: Vec<f64> = grid.wavelengths_nm().collect();
                let r = Spectrum::new(*grid, self.surface_at(&wavelengths)?)?;
                cmfs.reflectance_xyz(&r, &light, rule)
            }
        }
        .map_err(|e| Error::invalid(format!("{}: {e}", self.name)))
    }
}

/// The 24 ColorChecker patches (BabelColor averages) under a light, and the light itself.
pub fn colorchecker_under(light_name: &str, light: &Tabulated) -> Result<Vec<Stimulus>> {
    let table = data::Table::load("colorchecker")?;
    let mut out = vec![Stimulus::emitter(light_name, light.clone())];
    for (i, column) in table.columns().iter().enumerate() {
        out.push(Stimulus::new(
            format!("{column} under {light_name}"),
            light.clone(),
            Surface::Reflectance(table.column_at(i)?),
        ));
    }
    Ok(out)
}

/// Colours of a set of stimuli at 1 nm by Simpson's rule: what every grid is compared with.
pub struct Reference {
    observer: Observer,
    start_nm: f64,
    end_nm: f64,
    xyz: Vec<Xyz>,
    white: Vec<Xyz>,
}

impl Reference {
    /// Colours over `start..end` nm (whole nm) at 1 nm by Simpson's rule.
    pub fn new(
        stimuli: &[Stimulus],
        observer: Observer,
        start_nm: f64,
        end_nm: f64,
    ) -> Result<Self> {
        let cmfs = Cmfs::new(observer, &WavelengthGrid::new(start_nm, end_nm, 1.0)?)?;
        let mut xyz = Vec::with_capacity(stimuli.len());
        let mut white = Vec::with_capacity(stimuli.len());
        for s in stimuli {
            xyz.push(s.xyz(&cmfs, Rule::Simpson)?);
            white.push(cmfs.light_xyz(
                &s.light.resample(cmfs.grid(), Interpolation::LIGHT),
                Rule::Simpson,
            )?);
        }
        Ok(Reference {
            observer,
            start_nm,
            end_nm,
            xyz,
            white,
        })
    }

    /// CIEDE2000 of each stimulus on `grid` by `rule` against the reference.
    pub fn errors(
        &self,
        stimuli: &[Stimulus],
        grid: &WavelengthGrid,
        rule: Rule,
    ) -> Result<Vec<f64>> {
        if stimuli.len() != self.xyz.len() {
            return Err(Error::invalid("the stimuli are not the reference's"));
        }
        let cmfs = Cmfs::new(self.observer, grid)?;
        stimuli
            .iter()
            .zip(self.xyz.iter().zip(&self.white))
            .map(|(s, (reference, white))| {
                let x = s.xyz(&cmfs, rule)?;
                Ok(delta_e_2000(
                    Lab::from_xyz(x, *white),
                    Lab::from_xyz(*reference, *white),
                ))
            })
            .collect()
    }

    /// The grid with `step` over the reference's range, if the step divides it.
    pub fn grid(&self, step_nm: f64) -> Option<WavelengthGrid> {
        WavelengthGrid::new(self.start_nm, self.end_nm, step_nm).ok()
    }
}

/// Error and time of one grid and rule on a set of stimuli.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Measurement {
    /// Grid step, nm.
    pub step_nm: f64,
    /// Number of wavelengths on the grid.
    pub samples: usize,
    /// The integration rule, in words.
    pub rule: String,
    /// Mean CIEDE2000 against the reference over the stimuli.
    #[serde(rename = "mean_dE2000")]
    pub mean_de2000: f64,
    /// Largest CIEDE2000 against the reference over the stimuli.
    #[serde(rename = "max_dE2000")]
    pub max_de2000: f64,
    /// The stimulus with the largest error.
    pub worst: String,
    /// Microseconds per stimulus colour (resampling, film evaluation and integration).
    pub micros_per_colour: f64,
}

/// Measures one grid and rule: the errors, and the time per colour (repeated for at least
/// `min_seconds`).
pub fn measure(
    reference: &Reference,
    stimuli: &[Stimulus],
    grid: &WavelengthGrid,
    rule: Rule,
    min_seconds: f64,
) -> Result<Measurement> {
    let errors = reference.errors(stimuli, grid, rule)?;
    let (mut runs, t0) = (0usize, Instant::now());
    loop {
        let cmfs = Cmfs::new(reference.observer, grid)?;
        for s in stimuli {
            std::hint::black_box(s.xyz(&cmfs, rule)?);
        }
        runs += 1;
        if t0.elapsed().as_secs_f64() >= min_seconds {
            break;
        }
    }
    let micros = t0.elapsed().as_secs_f64() * 1e6 / (runs * stimuli.len().max(1)) as f64;
    let (worst, max) =
        errors.iter().enumerate().fold(
            (0, 0.0f64),
            |(wi, wm), (i, &e)| if e > wm { (i, e) } else { (wi, wm) },
        );
    Ok(Measurement {
        step_nm: grid.step_nm(),
        samples: grid.len(),
        rule: rule.to_string(),
        mean_de2000: errors.iter().sum::<f64>() / errors.len().max(1) as f64,
        max_de2000: max,
        worst: stimuli
            .get(worst)
            .map(|s| s.name.clone())
            .unwrap_or_default(),
        micros_per_colour: micros,
    })
}

/// What `--tolerance` chose.
#[derive(Debug, Clone, serde::Serialize)]
pub struct GridChoice {
    /// The chosen grid, `start:end:step`.
    pub grid: String,
    /// The chosen step, nm.
    pub step_nm: f64,
    /// The integration rule, in words.
    pub rule: String,
    /// The largest CIEDE2000 allowed.
    pub tolerance_de2000: f64,
    /// The largest error over the scene's stimuli on the chosen grid (the estimate).
    #[serde(rename = "max_dE2000")]
    pub max_de2000: f64,
    /// Name of the stimulus with the largest error on the chosen grid.
    pub worst: String,
    /// Whether some step met the tolerance (else the finest tried is chosen).
    pub met: bool,
    /// Every step tried, coarsest first, with its largest error.
    pub tried: Vec<(f64, f64)>,
    /// Number of stimuli in the scene.
    pub stimuli: usize,
    /// The chosen grid itself (not serialised).
    #[serde(skip)]
    pub chosen: WavelengthGrid,
}

/// The coarsest step of [`STEPS_NM`] (dividing `start..end`) whose largest error over
/// `stimuli` is at most `tolerance`; the finest step if none is.
pub fn choose_grid(
    stimuli: &[Stimulus],
    observer: Observer,
    start_nm: f64,
    end_nm: f64,
    rule: Rule,
    tolerance: f64,
) -> Result<GridChoice> {
    if !(tolerance.is_finite() && tolerance > 0.0 && tolerance <= 100.0) {
        return Err(Error::invalid(format!(
            "--tolerance {}: a CIEDE2000 difference between 0 and 100 (1 is about a just \
             noticeable difference)",
            crate::spectrum::fmt_num(tolerance)
        )));
    }
    if stimuli.is_empty() {
        return Err(Error::invalid("no stimuli to choose a grid for"));
    }
    let reference = Reference::new(stimuli, observer, start_nm.ceil(), end_nm.floor())?;
    let mut tried = Vec::new();
    let mut last = None;
    let mut failure = None;
    for step in STEPS_NM {
        let Some(grid) = WavelengthGrid::new(start_nm, end_nm, step).ok() else {
            continue;
        };
        // A coarse grid can miss a line spectrum altogether (no energy): try a finer one.
        let errors = match reference.errors(stimuli, &grid, rule) {
            Ok(e) => e,
            Err(e) => {
                tried.push((step, f64::INFINITY));
                failure = Some(e);
                continue;
            }
        };
        let (worst, max) =
            errors.iter().enumerate().fold(
                (0, 0.0f64),
                |(wi, wm), (i, &e)| if e > wm { (i, e) } else { (wi, wm) },
            );
        tried.push((step, max));
        let choice = GridChoice {
            grid: grid.to_string(),
            step_nm: step,
            rule: rule.to_string(),
            tolerance_de2000: tolerance,
            max_de2000: max,
            worst: stimuli[worst].name.clone(),
            met: max <= tolerance,
            tried: tried.clone(),
            stimuli: stimuli.len(),
            chosen: grid,
        };
        if choice.met {
            return Ok(choice);
        }
        last = Some(choice);
    }
    match (last, failure) {
        (Some(choice), _) => Ok(choice),
        (None, Some(e)) => Err(e),
        (None, None) => Err(Error::invalid(format!(
            "no step of {STEPS_NM:?} nm divides the range {start_nm}..{end_nm} nm"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::thinfilm::{Layer, Material};

    fn light(name: &str) -> Tabulated {
        data::spectrum(name).unwrap().data
    }

    fn film(thickness_nm: f64) -> Stimulus {
        let stack = Stack::new(
            Material::constant(crate::thinfilm::Index::real(1.0).unwrap()),
            vec![Layer::new(
                Material::constant(crate::thinfilm::Index::real(1.5).unwrap()),
                thickness_nm,
            )
            .unwrap()],
            Material::constant(crate::thinfilm::Index::real(1.0).unwrap()),
        );
        Stimulus::new(
            format!("{thickness_nm} nm film"),
            light("D65"),
            Surface::Film {
                stack,
                incidence: Incidence::degrees(0.0).unwrap(),
                coherence: Coherence::Coherent,
            },
        )
    }

    #[test]
    fn the_reference_grid_has_no_error() {
        let s = colorchecker_under("FL2", &light("FL2")).unwrap();
        let r = Reference::new(&s, Observer::Cie1931, 380.0, 780.0).unwrap();
        let e = r.errors(&s, &r.grid(1.0).unwrap(), Rule::Simpson).unwrap();
        assert!(e.iter().all(|&x| x < 1e-9), "{e:?}");
        assert_eq!(e.len(), 25);
    }

    #[test]
    fn spiky_lights_need_finer_grids_than_smooth_ones() {
        let pick = |name: &str| {
            let s = colorchecker_under(name, &light(name)).unwrap();
            choose_grid(&s, Observer::Cie1931, 380.0, 780.0, Rule::Riemann, 0.5).unwrap()
        };
        let (d65, fl2) = (pick("D65"), pick("FL2"));
        assert!(d65.met && fl2.met);
        assert!(
            fl2.step_nm < d65.step_nm,
            "FL2 {} vs D65 {}",
            fl2.step_nm,
            d65.step_nm
        );
        assert!(d65.max_de2000 <= 0.5 && fl2.max_de2000 <= 0.5);
    }

    #[test]
    fn thick_films_need_finer_grids_than_thin_ones() {
        let pick = |d: f64| {
            choose_grid(
                &[film(d)],
                Observer::Cie1931,
                380.0,
                780.0,
                Rule::Riemann,
                0.5,
            )
            .unwrap()
        };
        let (thin, thick) = (pick(150.0), pick(3000.0));
        assert!(
            thick.step_nm < thin.step_nm,
            "{} vs {}",
            thick.step_nm,
            thin.step_nm
        );
    }

    #[test]
    fn a_line_spectrum_missed_by_a_coarse_grid_is_tried_finer() {
        // Low-pressure sodium's 589 nm doublet falls between the 20 nm samples: no energy.
        let s = colorchecker_under("lps", &light("lps")).unwrap();
        let c = choose_grid(&s, Observer::Cie1931, 380.0, 780.0, Rule::Riemann, 1.0).unwrap();
        assert_eq!(c.tried[0], (20.0, f64::INFINITY));
        assert!(c.step_nm < 20.0 && c.max_de2000.is_finite());
    }

    #[test]
    fn a_bad_tolerance_is_an_error() {
        let s = [Stimulus::emitter("D65", light("D65"))];
        for t in [0.0, -1.0, f64::NAN] {
            assert!(choose_grid(&s, Observer::Cie1931, 380.0, 780.0, Rule::Riemann, t).is_err());
        }
    }
}
