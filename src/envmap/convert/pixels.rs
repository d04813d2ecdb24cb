//! How pixels become spectra: the plan's per-pixel engine ([`PixelPlan`]: the paper's basis or
//! the faithful method's carriers) and one pixel's spectrum, whichever it is ([`Pixels`]).

use crate::envmap::convert::carriers::{Assign, CarrierEngine, Written};
use crate::envmap::convert::pixel_spectra::{self, Engine, PixelKind, PixelResult, Took};
use crate::envmap::layout::EnvMap;
use crate::envmap::roundtrip::metric::RgbMetric;
use crate::envmap::scene::Cells;
use crate::fit::Mode;

/// How pixels become spectra.
#[derive(Debug, Clone)]
pub enum PixelPlan {
    /// The paper's modes: one fit; per analysis cell, whether it is the sun's.
    Basis {
        /// The fit's per-pixel engine.
        engine: Box<Engine>,
        /// Per analysis cell, whether it is the sun's (empty: no cell is).
        sun: Vec<bool>,
    },
    /// The faithful method: carriers, and per analysis cell what it is.
    Carriers {
        /// The carriers' per-pixel engine.
        engine: Box<CarrierEngine>,
        /// Per analysis cell, its carrier and what it is (sun, daylight, clipped lamp).
        assign: Vec<Assign>,
    },
}

/// What a pixel's spectrum is, beyond what it took: below zero somewhere, the sun's.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Flags {
    pub negative: bool,
    pub is_sun: bool,
}

/// What the paper's engine wrote for a pixel of `kind`, as the tally takes it.
pub(crate) fn basis_written(r: &PixelResult, kind: PixelKind) -> (Written, Flags) {
    let w = Written {
        rgb_back: r.rgb_back,
        took: r.took,
        exact: true,
    };
    let flags = Flags {
        negative: r.negative,
        is_sun: kind == PixelKind::Sun && r.took == Took::Sun,
    };
    (w, flags)
}

/// One pixel's spectrum, whichever engine the plan chose.
pub(crate) struct Pixels<'a> {
    pub map: &'a EnvMap,
    pub cells: &'a Cells,
    pub plan: &'a PixelPlan,
    /// The fit's mode (the paper's modes tell an exact pixel from a nearest one by it).
    pub mode: Mode,
}

impl Pixels<'_> {
    /// What a written pixel took and whether its round trip is exact. The carriers say so
    /// themselves; the paper's basis is exact in its exact mode, for white only in the paper
    /// mode, and where the spectrum stays non-negative in the nonneg mode, whose other pixels
    /// get the nearest non-negative spectrum: so its pixels are exact when their round trip is.
    pub(crate) fn exactness(&self, w: Written, de: f64) -> (Took, bool) {
        match &self.plan {
            PixelPlan::Carriers { .. } => (w.took, w.exact),
            PixelPlan::Basis { .. } => {
                let exact = de == 0.0;
                let nearest = !exact && w.took == Took::Colorchecker && self.mode == Mode::Nonneg;
                (if nearest { Took::Nearest } else { w.took }, exact)
            }
        }
    }

    pub(crate) fn metric(&self) -> &RgbMetric {
        match &self.plan {
            PixelPlan::Basis { engine, .. } => engine.metric(),
            PixelPlan::Carriers { engine, .. } => engine.metric(),
        }
    }

    /// The paper's modes: what pixel (x, y) is (the sun's, above the horizon, or plain), and
    /// whether it is the sun's.
    pub(crate) fn basis_kind(&self, x: usize, y: usize) -> (PixelKind, bool) {
        let PixelPlan::Basis { sun, engine } = &self.plan else {
            return (PixelKind::Plain, false);
        };
        if !engine.looks_at_kind() {
            // No sun and no daylight sky: every pixel is plain, none the sun's.
            return (PixelKind::Plain, false);
        }
        let cell = self.cells.cell_of_pixel(self.map, x, y).unwrap_or(0);
        if sun.get(cell).copied().unwrap_or(false) {
            (PixelKind::Sun, true)
        } else if self.map.direction(x, y).is_some_and(|d| d[1] > 0.0) {
            (PixelKind::Sky, false)
        } else {
            (PixelKind::Plain, false)
        }
    }

    /// What [`Pixels::spectrum`] returns for pixel (x, y), and the range of the values it would
    /// write (its lowest and highest, with 0), without writing them: for the paper's basis,
    /// where the pixel's spectrum is decided without looking at it (None otherwise).
    pub(crate) fn spectrum_range(
        &self,
        x: usize,
        y: usize,
    ) -> Option<(Written, Flags, (f32, f32))> {
        let PixelPlan::Basis { engine, .. } = self.plan else {
            return None;
        };
        let kind = self.basis_kind(x, y).0;
        let (r, range) = engine.spectrum_range(self.map.image.get(x, y), kind)?;
        let (w, flags) = basis_written(&r, kind);
        Some((w, flags, range))
    }

    /// Writes pixel (x, y)'s spectrum into `out`: what it took, whether it goes negative and
    /// whether it is the sun's.
    pub(crate) fn spectrum(&self, x: usize, y: usize, out: &mut [f32]) -> (Written, Flags) {
        let rgb = self.map.image.get(x, y);
        match self.plan {
            PixelPlan::Basis { engine, .. } => {
                let kind = self.basis_kind(x, y).0;
                basis_written(&engine.spectrum(rgb, kind, out), kind)
            }
            PixelPlan::Carriers { engine, assign } => {
                let cell = self.cells.cell_of_pixel(self.map, x, y).unwrap_or(0);
                let a = assign[cell];
                let w = engine.spectrum(rgb, a, out);
                let flags = Flags {
                    negative: pixel_spectra::is_negative(out),
                    is_sun: a.sun && w.took == Took::Sun,
                };
                (w, flags)
            }
        }
    }
}
