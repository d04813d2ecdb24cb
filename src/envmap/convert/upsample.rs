//! RGB colours to spectra without a map (the Python package's `upsample` of any array): each
//! colour is its light's SPD times a modulation, exact in RGB and never negative wherever the
//! colour can be a reflectance under that light, the nearest such colour otherwise (see
//! [`super::carriers`]: the faithful method's per-pixel engine with one carrier). Under `auto`
//! the light is CIE D65 and daylight-coloured colours take the CIE daylight of their own colour.
//!
//! ```
//! use specmap::envmap::convert::{upsample::Upsample, ConvertOptions};
//!
//! let up = Upsample::new(Some("A"), &ConvertOptions::faithful())?;
//! let mut out = vec![0f32; 2 * up.bands()];
//! let inexact = up.spectra(&[[1.0, 1.0, 1.0], [0.2, 0.5, 0.1]], &mut out)?;
//! assert_eq!(inexact, 0);
//! assert!(out.iter().all(|&v| v >= 0.0));
//! # Ok::<(), specmap::Error>(())
//! ```

use crate::data;
use crate::envmap::convert::carriers::{Assign, Carrier, CarrierEngine, SunSpec};
use crate::envmap::convert::pixel_spectra::{Colorimeter, WhitePremise};
use crate::envmap::convert::ConvertOptions;
use crate::error::{Error, Result};
use crate::spectrum::Interpolation;
use rayon::prelude::*;

/// Colours to spectra under one light, on the options' grid, observer, rule and RGB space.
#[derive(Debug, Clone)]
pub struct Upsample {
    engine: CarrierEngine,
    bands: usize,
    daylight: bool,
}

impl Upsample {
    /// Under `light` (a table name or CSV), or with None CIE D65 with daylight-coloured colours
    /// given CIE daylight; colours are read in `opts.space` as they are (its white is RGB 1,1,1).
    pub fn new(light: Option<&str>, opts: &ConvertOptions) -> Result<Upsample> {
        let c = Colorimeter::new(opts.grid, opts.observer, opts.rule, opts.space)?;
        let mcc = opts
            .basis
            .each_ref()
            .map(|n| data::spectrum(n).map(|s| s.data.resample(&opts.grid, Interpolation::SMOOTH)));
        let [m0, m1, m2] = mcc;
        let mcc = [m0?, m1?, m2?];
        let name = light.unwrap_or("D65");
        let table = data::spectrum(name)?.data;
        let carrier = Carrier::new(name, &c.light(name, &table)?, &c, &mcc)?;
        let daylight = light.is_none();
        let engine = CarrierEngine::new(
            &c,
            vec![carrier],
            daylight,
            &SunSpec::None,
            WhitePremise::Space,
            [1.0; 3],
        )?;
        Ok(Upsample {
            engine,
            bands: opts.grid.len(),
            daylight,
        })
    }

    /// Values per spectrum.
    pub fn bands(&self) -> usize {
        self.bands
    }

    /// Each colour's spectrum into `out` (`bands()` values per colour, in order), in parallel.
    /// Returns how many colours could not be exact (their spectrum is the nearest non-negative
    /// one). A non-finite channel is an error naming the colour.
    pub fn spectra(&self, rgb: &[[f32; 3]], out: &mut [f32]) -> Result<usize> {
        if out.len() != rgb.len() * self.bands {
            return Err(Error::invalid(format!(
                "{} colours need {} values, not {}",
                rgb.len(),
                rgb.len() * self.bands,
                out.len()
            )));
        }
        if let Some(i) = rgb.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
            return Err(Error::invalid(format!(
                "colour {i} is {:?}: RGB must be finite",
                rgb[i]
            )));
        }
        let assign = Assign {
            daylight: self.daylight,
            ..Assign::default()
        };
        let inexact = out
            .par_chunks_mut(self.bands)
            .zip(rgb.par_iter())
            .map(|(s, &p)| !self.engine.spectrum(p, assign, s).exact as usize)
            .sum();
        Ok(inexact)
    }
}
