//! The colour error of a quadrature on a set of stimuli: CIEDE2000 between each stimulus's colour
//! on the quadrature and its colour at 1 nm by Simpson's rule, both relative to the stimulus's
//! own light (a perfect white under it is Y = 100 on every quadrature, as in the renderer).
//!
//! The CIELAB white is either each light's own 1 nm white (as `specmap color` reports a colour)
//! or one fixed white (a render is compared in its output space, whatever the light), and each
//! stimulus is seen at its [`Stimulus::gain`] (a highlight at 30 times a white errs more than a
//! white).

use super::Quadrature;
use crate::colorimetry::{delta_e_2000, Lab, Observer, Xyz};
use crate::error::{Error, Result};
use crate::spectrum::{Rule, WavelengthGrid};
use crate::tradeoff::Stimulus;

/// The CIELAB white the errors are taken against.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum White {
    /// Each stimulus's light at 1 nm (Y = 100).
    OwnLight,
    /// One white for all (Y = 100 is a perfect white under any light at gain 1).
    Fixed(Xyz),
}

/// A set of stimuli sampled at 1 nm, with their reference colours.
#[derive(Debug, Clone)]
pub struct Estimator {
    pub(crate) observer: Observer,
    pub(crate) grid: WavelengthGrid,
    pub(crate) stimuli: Vec<Stimulus>,
    /// Per stimulus at 1 nm: the light scaled so that its white is Y = 100 at 1 nm.
    pub(crate) light: Vec<Vec<f64>>,
    /// Per stimulus at 1 nm: the stimulus on the same scale, times its gain.
    pub(crate) value: Vec<Vec<f64>>,
    /// Per stimulus: its colour at 1 nm by Simpson's rule.
    pub(crate) reference: Vec<Xyz>,
    /// Per stimulus: its CIELAB white.
    pub(crate) white: Vec<Xyz>,
    /// Per stimulus: its reference colour in CIELAB against that white.
    reference_lab: Vec<Lab>,
    /// Per stimulus: the factor from its light's tabulated values to the scale above.
    scale: Vec<f64>,
}

impl Estimator {
    /// Samples `stimuli` over `start..end` nm (whole nm) at 1 nm.
    pub fn new(
        stimuli: &[Stimulus],
        observer: Observer,
        start_nm: f64,
        end_nm: f64,
        white: White,
    ) -> Result<Estimator> {
        if stimuli.is_empty() {
            return Err(Error::invalid("no stimuli to estimate a colour error on"));
        }
        let grid = WavelengthGrid::new(start_nm.ceil(), end_nm.floor(), 1.0)?;
        let reference = Quadrature::uniform(grid, Rule::Simpson, observer)?;
        let wavelengths: Vec<f64> = grid.wavelengths_nm().collect();
        let mut out = Estimator {
            observer,
            grid,
            stimuli: stimuli.to_vec(),
            light: Vec::new(),
            value: Vec::new(),
            reference: Vec::new(),
            white: Vec::new(),
            reference_lab: Vec::new(),
            scale: Vec::new(),
        };
        for s in stimuli {
            if !(s.gain.is_finite() && s.gain > 0.0) {
                return Err(Error::invalid(format!(
                    "{}: gain {} must be positive",
                    s.name, s.gain
                )));
            }
            let (light, value) = s.values_at(&wavelengths)?;
            let y = reference.integrate(&light)[1];
            if !(y.is_finite() && y > 0.0) {
                return Err(Error::invalid(format!(
                    "{}: the light has no visible energy in {grid}",
                    s.name
                )));
            }
            let light: Vec<f64> = light.iter().map(|v| 100.0 * v / y).collect();
            let value: Vec<f64> = value.iter().map(|v| 100.0 * s.gain * v / y).collect();
            let [x, yy, z] = reference.integrate(&value);
            let [wx, wy, wz] = reference.integrate(&light);
            let colour = Xyz::new(x, yy, z);
            let lab_white = match white {
                White::OwnLight => Xyz::new(wx, wy, wz),
                White::Fixed(w) => w,
            };
            out.reference.push(colour);
            out.white.push(lab_white);
            out.reference_lab.push(Lab::from_xyz(colour, lab_white));
            out.light.push(light);
            out.value.push(value);
            out.scale.push(100.0 / y);
        }
        Ok(out)
    }

    /// Number of stimuli (never zero).
    pub fn len(&self) -> usize {
        self.stimuli.len()
    }
    /// Always false: an estimator holds at least one stimulus.
    pub fn is_empty(&self) -> bool {
        false
    }
    /// The stimuli, in the order given.
    pub fn stimuli(&self) -> &[Stimulus] {
        &self.stimuli
    }
    /// The observer colours are computed for.
    pub fn observer(&self) -> Observer {
        self.observer
    }
    /// Each stimulus's colour at 1 nm by Simpson's rule (a white under its light is Y = 100).
    pub fn references(&self) -> &[Xyz] {
        &self.reference
    }
    /// The 1 nm grid the stimuli are sampled on.
    pub fn grid(&self) -> WavelengthGrid {
        self.grid
    }

    /// CIEDE2000 of `xyz` against stimulus `s`'s reference.
    pub(crate) fn error_of(&self, s: usize, xyz: Xyz) -> f64 {
        delta_e_2000(Lab::from_xyz(xyz, self.white[s]), self.reference_lab[s])
    }

    /// The error of each stimulus on `q`; infinite where `q` misses a light altogether.
    pub fn errors(&self, q: &Quadrature) -> Result<Vec<f64>> {
        if q.observer() != self.observer {
            return Err(Error::invalid(format!(
                "the quadrature is for the {} observer, the stimuli for the {}",
                q.observer(),
                self.observer
            )));
        }
        let on_grid: Option<Vec<usize>> = q.nodes_nm().iter().map(|&w| self.index(w)).collect();
        (0..self.len())
            .map(|s| {
                let (light, value) = match &on_grid {
                    Some(idx) => (
                        idx.iter().map(|&j| self.light[s][j]).collect::<Vec<_>>(),
                        idx.iter().map(|&j| self.value[s][j]).collect::<Vec<_>>(),
                    ),
                    None => self.off_grid(s, q.nodes_nm())?,
                };
                Ok(q.relative_xyz(&value, &light)
                    .map_or(f64::INFINITY, |xyz| self.error_of(s, xyz)))
            })
            .collect()
    }

    /// The index on the 1 nm grid of a wavelength that lies on it.
    pub(crate) fn index(&self, wavelength_nm: f64) -> Option<usize> {
        let i = (wavelength_nm - self.grid.start_nm()).round();
        (i >= 0.0
            && (i as usize) < self.grid.len()
            && (self.grid.wavelength_nm(i as usize) - wavelength_nm).abs() < 1e-9)
            .then_some(i as usize)
    }

    /// Stimulus `s` at wavelengths off the grid, on the same scale as on it.
    fn off_grid(&self, s: usize, nodes: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
        let st = &self.stimuli[s];
        let (light, value) = st.values_at(nodes)?;
        let k = self.scale[s];
        Ok((
            light.iter().map(|v| k * v).collect(),
            value.iter().map(|v| k * st.gain * v).collect(),
        ))
    }
}

/// The largest of `errors`, its index, and the mean.
pub fn worst(errors: &[f64]) -> (usize, f64, f64) {
    let (i, max) =
        errors.iter().enumerate().fold(
            (0, 0.0f64),
            |a, (i, &e)| if e > a.1 || e.is_nan() { (i, e) } else { a },
        );
    let mean = errors.iter().sum::<f64>() / errors.len().max(1) as f64;
    (i, max, mean)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectrum::Rule;
    use crate::tradeoff::colorchecker_under;

    fn stimuli(light: &str) -> Vec<Stimulus> {
        colorchecker_under(light, &crate::data::spectrum(light).unwrap().data).unwrap()
    }

    #[test]
    fn the_reference_has_no_error_and_coarse_grids_err_more() {
        let s = stimuli("FL2");
        let e = Estimator::new(&s, Observer::Cie1931, 380.0, 780.0, White::OwnLight).unwrap();
        let err = |step: f64, rule: Rule| {
            let g = WavelengthGrid::new(380.0, 780.0, step).unwrap();
            let q = Quadrature::uniform(g, rule, Observer::Cie1931).unwrap();
            worst(&e.errors(&q).unwrap()).1
        };
        assert!(err(1.0, Rule::Simpson) < 1e-9);
        assert!(err(10.0, Rule::Riemann) > err(5.0, Rule::Riemann));
    }

    #[test]
    fn agrees_with_the_tradeoff_reference_on_uniform_grids() {
        // Same stimuli, white and rule: the two implementations give the same numbers.
        let s = stimuli("D65");
        let e = Estimator::new(&s, Observer::Cie1931, 380.0, 780.0, White::OwnLight).unwrap();
        let r = crate::tradeoff::Reference::new(&s, Observer::Cie1931, 380.0, 780.0).unwrap();
        let g = WavelengthGrid::new(380.0, 780.0, 10.0).unwrap();
        let q = Quadrature::uniform(g, Rule::Trapezoid, Observer::Cie1931).unwrap();
        let a = e.errors(&q).unwrap();
        let b = r.errors(&s, &g, Rule::Trapezoid).unwrap();
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-9, "{x} vs {y}");
        }
    }

    #[test]
    fn off_grid_nodes_sample_the_same_spectra() {
        // The same weights on nodes a millionth of a nm off the grid: sampled off the grid,
        // the same errors to that shift; Meyer's nodes are off the grid and finite.
        let s = stimuli("FL2");
        let e = Estimator::new(&s, Observer::Cie1931, 380.0, 780.0, White::OwnLight).unwrap();
        let g = WavelengthGrid::new(380.0, 780.0, 10.0).unwrap();
        let on = Quadrature::uniform(g, Rule::Riemann, Observer::Cie1931).unwrap();
        let shifted: Vec<f64> = on.nodes_nm().iter().map(|w| w + 1e-6).collect();
        assert!(e.index(shifted[3]).is_none() && e.index(on.nodes_nm()[3]) == Some(30));
        let off = Quadrature::new(
            crate::quadrature::Kind::Scene,
            Observer::Cie1931,
            shifted,
            on.weights().to_vec(),
        )
        .unwrap();
        for (a, b) in e.errors(&on).unwrap().iter().zip(e.errors(&off).unwrap()) {
            assert!((a - b).abs() < 1e-4, "{a} vs {b}");
        }
        let meyer = crate::quadrature::meyer::meyer(Observer::Cie1931).unwrap();
        assert!(e.errors(&meyer).unwrap().iter().all(|x| x.is_finite()));
    }
}
