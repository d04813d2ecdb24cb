//! Every pixel's spectrum computed once, before the write, and measured: which spectrum it took,
//! its round trip (the report's statistics), and its largest value (what sizes the half-float EV
//! scale). With this measure done, the write only lays each pixel's few coefficients into its
//! planes.

use crate::envmap::convert::band_reduce;
use crate::envmap::convert::carriers::Written;
use crate::envmap::convert::pixel_spectra::Took;
use crate::envmap::convert::pixels::{Flags, Pixels};
use crate::envmap::roundtrip::stats::{RoundTripAccumulator, Sample};
use rayon::prelude::*;

/// Binary exponents of a pixel's largest value are binned from 2^-150 to 2^149.
const PEAK_BINS: usize = 300;
/// The exponent of the first bin is -PEAK_OFFSET.
const PEAK_OFFSET: i32 = 150;

/// The bin of a pixel's largest value `p` (> 0 and finite).
fn peak_bin(p: f32) -> usize {
    (p.log2().floor() as i32 + PEAK_OFFSET).clamp(0, PEAK_BINS as i32 - 1) as usize
}

/// How many pixels got which spectrum.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct SpectraCount {
    /// The sun's SPD.
    pub sun: usize,
    /// CIE daylight family (sky, windows, daylight-coloured pixels as bright as them).
    pub daylight: usize,
    /// Carrier x smooth modulation.
    pub smooth: usize,
    /// Carrier x ColorChecker basis.
    pub colorchecker: usize,
    /// Carrier x non-negative Bernstein combination (exact): the faithful method's fallback where
    /// the smooth modulation and the ColorChecker basis go negative. Not the paper's `nonneg`
    /// mode, whose pixels count as `colorchecker` where exact and `nearest` where not.
    pub nonneg_fallback: usize,
    /// The nearest non-negative spectrum (the colour is not one its light can make).
    pub nearest: usize,
    /// Clipped lamp pixels given their lamp's SPD.
    pub clipped: usize,
    /// Pixels whose spectrum goes below zero somewhere.
    pub negative: usize,
}

impl SpectraCount {
    fn add(&mut self, took: Took, negative: bool) {
        match took {
            Took::Sun => self.sun += 1,
            Took::Daylight => self.daylight += 1,
            Took::Smooth => self.smooth += 1,
            Took::Colorchecker => self.colorchecker += 1,
            Took::Nonneg => self.nonneg_fallback += 1,
            Took::Nearest => self.nearest += 1,
            Took::Fixed => self.clipped += 1,
        }
        self.negative += negative as usize;
    }
    fn merge(&mut self, o: &SpectraCount) {
        self.sun += o.sun;
        self.daylight += o.daylight;
        self.smooth += o.smooth;
        self.colorchecker += o.colorchecker;
        self.nonneg_fallback += o.nonneg_fallback;
        self.nearest += o.nearest;
        self.clipped += o.clipped;
        self.negative += o.negative;
    }
}

/// The round trip over all pixels, without the sun, and over the pixels that could not be
/// exact (the nearest non-negative spectra, clipped lamp pixels, the paper modes' inexact ones).
#[derive(Debug, Clone, Default)]
pub(crate) struct Tally {
    pub all: RoundTripAccumulator,
    pub no_sun: RoundTripAccumulator,
    pub inexact: RoundTripAccumulator,
    pub count: SpectraCount,
}

impl Tally {
    pub(crate) fn merge(&mut self, o: &Tally) {
        self.all.merge(&o.all);
        self.no_sun.merge(&o.no_sun);
        self.inexact.merge(&o.inexact);
        self.count.merge(&o.count);
    }

    /// Adds pixel (x, y), of solid angle `omega`, to the tally: which spectrum it took, and its
    /// round trip (see [`crate::envmap::roundtrip::stats`]) over all pixels, without the sun,
    /// and if inexact.
    pub(crate) fn add(&mut self, px: &Pixels, at: (usize, usize, f64), w: Written, flags: Flags) {
        let (x, y, omega) = at;
        let metric = px.metric();
        let rgb = px.map.image.get(x, y);
        let lum = metric.luminance(rgb);
        let de = if lum > 0.0 {
            metric.round_trip_error(rgb, w.rgb_back)
        } else {
            0.0
        };
        let (took, exact) = px.exactness(w, de);
        self.count.add(took, flags.negative);
        let sample = Sample::new(x, y, lum, omega, de);
        self.all.add_sample(&sample);
        if !flags.is_sun {
            self.no_sun.add_sample(&sample);
            if !exact {
                self.inexact.add_sample(&sample);
            }
        }
    }
}

/// What measuring every pixel found.
pub(crate) struct Measured {
    /// The round trip and the count of each spectrum.
    pub tally: Tally,
    /// The largest magnitude of any value written (bands and R, G, B).
    pub peak: f32,
    /// Per binary exponent (from 2^-150): how many pixels have their largest magnitude there.
    bins: [usize; PEAK_BINS],
}

impl Measured {
    /// How many pixels have their largest magnitude below 2^`exponent` (and above 0).
    pub(crate) fn pixels_below(&self, exponent: i32) -> usize {
        let end = (exponent + PEAK_OFFSET).clamp(0, PEAK_BINS as i32) as usize;
        self.bins[..end].iter().sum()
    }
}

/// Rows measured together: their tallies are merged in row order once all are done.
const ROWS_PER_MERGE: usize = 64;

/// Computes and measures every pixel's spectrum (`bands` values), rows in parallel. Each row's
/// tally is merged in row order, a batch of rows at a time (a map's rows of luminance bins would
/// not fit at once; merged as threads finish, the sums' last bits moved with them).
pub(crate) fn measure(px: &Pixels, bands: usize) -> Measured {
    let height = px.map.image.height;
    let mut tally = Tally::default();
    let mut peak = 0f32;
    let mut bins = [0usize; PEAK_BINS];
    for y0 in (0..height).step_by(ROWS_PER_MERGE) {
        let rows: Vec<(Tally, f32, [usize; PEAK_BINS])> = (y0..(y0 + ROWS_PER_MERGE).min(height))
            .into_par_iter()
            .map(|y| measure_row(px, bands, y))
            .collect();
        for (t, p, b) in &rows {
            tally.merge(t);
            peak = peak.max(*p);
            bins.iter_mut().zip(b).for_each(|(n, k)| *n += k);
        }
    }
    Measured { tally, peak, bins }
}

/// Row `y`'s tally, largest magnitude, and per binary exponent how many of its pixels have
/// their largest magnitude there.
fn measure_row(px: &Pixels, bands: usize, y: usize) -> (Tally, f32, [usize; PEAK_BINS]) {
    let map = px.map;
    let mut t = Tally::default();
    let mut out = vec![0f32; bands];
    let mut bins = [0usize; PEAK_BINS];
    let mut peak = 0f32;
    let omega_row = map.row_solid_angle(y);
    for x in 0..map.image.width {
        let omega = omega_row.unwrap_or_else(|| map.solid_angle(x, y));
        let (w, flags, bands_peak) = match px.spectrum_range(x, y) {
            Some((w, flags, range)) => (w, flags, band_reduce::max_abs_of_range(range)),
            None => {
                let (w, flags) = px.spectrum(x, y, &mut out);
                (w, flags, band_reduce::max_abs(&out))
            }
        };
        t.add(px, (x, y, omega), w, flags);
        if !map.has_direction(x, y) {
            continue;
        }
        let rgb = map.image.get(x, y);
        let p = bands_peak.max(band_reduce::max_abs(&rgb));
        peak = peak.max(p);
        if p > 0.0 && p.is_finite() {
            bins[peak_bin(p)] += 1;
        }
    }
    (t, peak, bins)
}
