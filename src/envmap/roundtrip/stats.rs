//! The round-trip statistic, defined once: `convert` measures the spectra it writes with it and
//! `roundtrip` a file's spectra against its R, G, B preview, so the two report the same numbers
//! for the same map.
//!
//! Per pixel the CIEDE2000 compares the input colour and its round trip scaled so the input has
//! Y = 1 ([`crate::envmap::roundtrip::metric::RgbMetric::round_trip_error`]): colour and relative
//! brightness, whatever the pixel's level. That makes a pixel of 1e-7 count as much as the sky
//! in the maximum, although its error (half-float rounding, a colour no spectrum makes) cannot
//! be seen. So the statistic is taken over the pixels at or above a luminance floor relative to
//! the map ([`Floor`]):
//! - `weighted_mean_de2000`: the energy-weighted (luminance x solid angle) mean;
//! - `max_de2000`, with the pixel (x, y) where it is and that pixel's luminance;
//! - the pixels below the floor are counted, with their own maximum and share of the energy
//!   (nothing is dropped silently), and black pixels (luminance 0: no colour) are counted.
//!
//! The accumulator bins pixels by luminance (1/16 octave) as they stream, so the floor, which
//! depends on the whole map, is applied at the end without a second pass or a copy of the map.

/// Luminance bins per octave: the 99th percentile is known to 1/16 octave (4.4 %).
const BINS_PER_OCTAVE: i32 = 16;

/// The floor lies this many octaves below the reference luminance: 2^-13 = 1/8192.
pub const FLOOR_OCTAVES: i32 = 13;

/// The reference luminance: this percentile (by solid angle) of the map's luminance.
pub const FLOOR_PERCENTILE: f64 = 99.0;

/// The luminance floor of the round-trip statistic: 2^-13 (1/8192, about 1.2e-4) of the map's
/// 99th-percentile luminance by solid angle (rounded down to 1/16 octave), 0 for a map whose
/// 99th percentile is black.
///
/// Why these numbers. The 99th percentile is the map's bright content (sky, windows, lamps)
/// without the sun, which covers far less than 1 % of the sphere: it is what an exposure puts
/// at display white. At that exposure a pixel at 2^-13 of it has CIE L* = 903.3 x 2^-13 = 0.11,
/// a tenth of a just-noticeable lightness step; CIELAB's a* and b* shrink with L* there, so
/// even a colour swapped for its opposite differs from its round trip by about 1 CIEDE2000 in
/// the image, whereas the per-pixel (Y = 1) error of such a pixel can read 100. And in half
/// floats, at a 99th percentile of 0.5 or more, every pixel above the floor is a normal number
/// (above 6.1e-5), where half's relative precision of 2^-11 holds: the floor also keeps
/// half's subnormal rounding out of the maximum.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Floor {
    /// Pixels of at least this luminance are in the statistic.
    pub luminance: f64,
    /// The map's 99th-percentile luminance by solid angle (the lower edge of its 1/16-octave
    /// bin), of which the floor is 2^-13.
    pub reference_luminance: f64,
    /// The rule, in words.
    pub rule: &'static str,
}

const FLOOR_RULE: &str = "2^-13 of the map's 99th-percentile luminance by solid angle";

/// The pixels below the floor: counted, not in the statistic.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct BelowFloor {
    /// Pixels below the floor (black pixels aside).
    pub pixels: usize,
    /// Largest CIEDE2000 among them.
    pub max_de2000: f64,
    /// Their share of the energy (luminance x solid angle) of the set of pixels measured.
    pub energy_share: f64,
}

/// The round trip over a set of pixels (see the module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct RoundTripStats {
    /// Pixels in the statistic: luminance at or above the floor.
    pub pixels: usize,
    /// Energy-weighted (luminance x solid angle) mean CIEDE2000.
    pub weighted_mean_de2000: f64,
    /// Largest CIEDE2000 in the statistic.
    pub max_de2000: f64,
    /// Pixel (x, y) of the maximum (None without pixels).
    pub max_at: Option<[usize; 2]>,
    /// The luminance of that pixel.
    pub max_luminance: f64,
    /// The floor the statistic was taken at (see [`Floor`]).
    pub luminance_floor: f64,
    /// The pixels below the floor, counted apart.
    pub below_floor: BelowFloor,
    /// Pixels of no luminance (black, or negative): no colour to compare.
    pub black_pixels: usize,
}

/// One luminance bin's pixels.
#[derive(Debug, Clone, Copy, Default)]
struct Bin {
    pixels: usize,
    solid_angle: f64,
    /// Sum of luminance x solid angle, and of it x CIEDE2000.
    energy: f64,
    weighted: f64,
    max: f64,
    max_at: [u32; 2],
    max_luminance: f64,
}

impl Bin {
    fn merge(&mut self, o: &Bin) {
        let empty = self.pixels == 0;
        self.pixels += o.pixels;
        self.solid_angle += o.solid_angle;
        self.energy += o.energy;
        self.weighted += o.weighted;
        // On a tie the pixel first in scan order: the same whichever way threads split the map.
        let first = |at: [u32; 2]| (at[1], at[0]);
        let tie_first = o.max == self.max && first(o.max_at) < first(self.max_at);
        if empty || o.max > self.max || tie_first {
            self.max = o.max;
            self.max_at = o.max_at;
            self.max_luminance = o.max_luminance;
        }
    }
}

/// Collects pixels' round-trip errors by luminance; [`RoundTripAccumulator::floor`] and
/// [`RoundTripAccumulator::stats`] make the statistic at the end.
#[derive(Debug, Clone, Default)]
pub struct RoundTripAccumulator {
    /// Bin index of `bins[0]` (floor(log2(luminance) x 16)).
    first: i32,
    bins: Vec<Bin>,
    black_pixels: usize,
    black_solid_angle: f64,
}

/// The bin of a positive luminance.
fn bin_of(luminance: f64) -> i32 {
    // f32 maps hold luminances of 2^-149 to 2^128; EV-scaled files up to 2^228.
    (luminance.log2() * BINS_PER_OCTAVE as f64).floor().clamp(
        -160.0 * BINS_PER_OCTAVE as f64,
        240.0 * BINS_PER_OCTAVE as f64,
    ) as i32
}

/// One pixel's round trip, placed in its luminance bin once for every accumulator it joins
/// (the bin's logarithm is most of the cost of adding a pixel).
#[derive(Debug, Clone, Copy)]
pub struct Sample {
    at: [u32; 2],
    luminance: f64,
    solid_angle: f64,
    de2000: f64,
    bin: SampleBin,
}

/// Where a pixel goes in an accumulator.
#[derive(Debug, Clone, Copy)]
enum SampleBin {
    /// No solid angle: not a pixel of the map.
    Outside,
    /// No luminance (or NaN).
    Black,
    /// This luminance bin.
    Lit(i32),
}

impl Sample {
    /// Pixel (x, y) of `luminance` and `solid_angle`, whose round trip is `de2000` away (see
    /// [`RoundTripAccumulator::add`]).
    pub fn new(x: usize, y: usize, luminance: f64, solid_angle: f64, de2000: f64) -> Sample {
        let bin = if solid_angle.is_nan() || solid_angle <= 0.0 {
            SampleBin::Outside
        } else if luminance.is_nan() || luminance <= 0.0 {
            SampleBin::Black
        } else {
            SampleBin::Lit(bin_of(luminance))
        };
        Sample {
            at: [x as u32, y as u32],
            luminance,
            solid_angle,
            de2000,
            bin,
        }
    }
}

fn lower_edge(bin: i32) -> f64 {
    (bin as f64 / BINS_PER_OCTAVE as f64).exp2()
}

impl RoundTripAccumulator {
    /// Adds pixel (x, y) of `luminance` and `solid_angle` (sr; 1 where the layout is unknown)
    /// whose round trip is `de2000` away. Pixels of no solid angle (outside the faces of a cross
    /// or strip) are not pixels of the map and are not added.
    pub fn add(&mut self, x: usize, y: usize, luminance: f64, solid_angle: f64, de2000: f64) {
        self.add_sample(&Sample::new(x, y, luminance, solid_angle, de2000));
    }

    /// Adds a pixel placed in its bin (see [`RoundTripAccumulator::add`]).
    pub fn add_sample(&mut self, s: &Sample) {
        let Sample {
            at: [x, y],
            luminance,
            solid_angle,
            de2000,
            bin,
        } = *s;
        match bin {
            SampleBin::Outside => {}
            SampleBin::Black => {
                self.black_pixels += 1;
                self.black_solid_angle += solid_angle;
            }
            SampleBin::Lit(k) => {
                let b = self.bin_mut(k);
                let energy = luminance * solid_angle;
                b.pixels += 1;
                b.solid_angle += solid_angle;
                b.energy += energy;
                b.weighted += energy * de2000;
                if de2000 > b.max || b.pixels == 1 {
                    b.max = de2000;
                    b.max_at = [x, y];
                    b.max_luminance = luminance;
                }
            }
        }
    }

    /// The bin `k`, the window of bins grown to hold it.
    fn bin_mut(&mut self, k: i32) -> &mut Bin {
        if self.bins.is_empty() {
            self.first = k;
        }
        if k < self.first {
            let grow = (self.first - k) as usize;
            self.bins
                .splice(0..0, std::iter::repeat_n(Bin::default(), grow));
            self.first = k;
        }
        let i = (k - self.first) as usize;
        if i >= self.bins.len() {
            self.bins.resize(i + 1, Bin::default());
        }
        &mut self.bins[i]
    }

    /// Adds another accumulator's pixels (parallel parts of one map).
    pub fn merge(&mut self, o: &RoundTripAccumulator) {
        self.black_pixels += o.black_pixels;
        self.black_solid_angle += o.black_solid_angle;
        for (i, b) in o.bins.iter().enumerate() {
            if b.pixels > 0 {
                self.bin_mut(o.first + i as i32).merge(b);
            }
        }
    }

    /// The floor of this accumulator's pixels (those of the whole map: see [`Floor`]).
    pub fn floor(&self) -> Floor {
        let total: f64 =
            self.black_solid_angle + self.bins.iter().map(|b| b.solid_angle).sum::<f64>();
        let target = FLOOR_PERCENTILE / 100.0 * total;
        let mut cumulative = self.black_solid_angle;
        let reference = if total > 0.0 && cumulative < target {
            self.bins
                .iter()
                .position(|b| {
                    cumulative += b.solid_angle;
                    cumulative >= target
                })
                .map(|i| self.first + i as i32)
        } else {
            None
        };
        match reference {
            Some(k) => Floor {
                luminance: lower_edge(k - FLOOR_OCTAVES * BINS_PER_OCTAVE),
                reference_luminance: lower_edge(k),
                rule: FLOOR_RULE,
            },
            None => Floor {
                luminance: 0.0,
                reference_luminance: 0.0,
                rule: FLOOR_RULE,
            },
        }
    }

    /// The statistic of this accumulator's pixels at `floor` (the map's, from [`Self::floor`]
    /// of all its pixels, also for a subset such as the pixels without the sun).
    pub fn stats(&self, floor: &Floor) -> RoundTripStats {
        let mut s = RoundTripStats {
            luminance_floor: floor.luminance,
            black_pixels: self.black_pixels,
            ..RoundTripStats::default()
        };
        let (mut energy, mut weighted, mut energy_below, mut energy_all) = (0.0, 0.0, 0.0, 0.0);
        for (i, b) in self.bins.iter().enumerate().filter(|(_, b)| b.pixels > 0) {
            energy_all += b.energy;
            // A bin lies wholly on one side of the floor: the floor is a bin edge.
            if lower_edge(self.first + i as i32) >= floor.luminance {
                s.pixels += b.pixels;
                energy += b.energy;
                weighted += b.weighted;
                if s.max_at.is_none() || b.max > s.max_de2000 {
                    s.max_de2000 = b.max;
                    s.max_at = Some([b.max_at[0] as usize, b.max_at[1] as usize]);
                    s.max_luminance = b.max_luminance;
                }
            } else {
                s.below_floor.pixels += b.pixels;
                s.below_floor.max_de2000 = s.below_floor.max_de2000.max(b.max);
                energy_below += b.energy;
            }
        }
        if energy > 0.0 {
            s.weighted_mean_de2000 = weighted / energy;
        }
        if energy_all > 0.0 {
            s.below_floor.energy_share = energy_below / energy_all;
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A map of `n` pixels of one solid angle: luminances and errors as given.
    fn accumulate(pixels: &[(f64, f64)]) -> RoundTripAccumulator {
        let mut a = RoundTripAccumulator::default();
        for (i, &(l, de)) in pixels.iter().enumerate() {
            a.add(i, 0, l, 1.0, de);
        }
        a
    }

    #[test]
    fn the_floor_is_2_to_the_minus_13_of_the_99th_percentile() {
        // 1000 pixels: 985 at 1, 10 at 4 (the 99th percentile lies among them), 5 at 1000.
        let mut px = vec![(1.0, 0.1); 985];
        px.extend([(4.0, 0.2); 10]);
        px.extend([(1000.0, 0.3); 5]);
        let f = accumulate(&px).floor();
        assert_eq!(f.reference_luminance, 4.0);
        assert_eq!(f.luminance, 4.0 / 8192.0);
        // Off a bin edge, the reference is the edge below, within 1/16 octave.
        let f = accumulate(&[(3.0, 0.0); 100]).floor();
        assert!(
            f.reference_luminance <= 3.0 && f.reference_luminance > 3.0 / 2f64.powf(1.0 / 16.0)
        );
        // Mostly black: the 99th percentile is black and every lit pixel counts.
        let mut px = vec![(0.0, 0.0); 995];
        px.extend([(1e-9, 50.0); 5]);
        let a = accumulate(&px);
        assert_eq!(a.floor().luminance, 0.0);
        let s = a.stats(&a.floor());
        assert_eq!((s.pixels, s.black_pixels, s.max_de2000), (5, 995, 50.0));
    }

    #[test]
    fn near_black_pixels_are_counted_below_the_floor_not_in_the_maximum() {
        // The case: a lit room and one pixel of 1e-7 whose round trip is 121 away.
        let mut px = vec![(0.5, 1.0); 999];
        px[17] = (0.8, 2.5);
        px.push((1e-7, 121.0));
        let a = accumulate(&px);
        let s = a.stats(&a.floor());
        assert_eq!(s.max_de2000, 2.5);
        assert_eq!(s.max_at, Some([17, 0]));
        assert_eq!(s.max_luminance, 0.8);
        assert_eq!(s.pixels, 999);
        assert_eq!(s.below_floor.pixels, 1);
        assert_eq!(s.below_floor.max_de2000, 121.0);
        let share = 1e-7 / (998.0 * 0.5 + 0.8 + 1e-7);
        assert!((s.below_floor.energy_share - share).abs() < 1e-18);
        // The energy-weighted mean: (998 x 0.5 x 1 + 0.8 x 2.5) / (998 x 0.5 + 0.8).
        let mean = (499.0 + 2.0) / (499.0 + 0.8);
        assert!((s.weighted_mean_de2000 - mean).abs() < 1e-12);
    }

    #[test]
    fn merged_parts_equal_the_whole() {
        let px: Vec<(f64, f64)> = (0..500)
            .map(|i| (10f64.powf(-8.0 + 10.0 * i as f64 / 500.0), (i % 37) as f64))
            .collect();
        let whole = accumulate(&px);
        let mut parts = RoundTripAccumulator::default();
        for chunk in [&px[250..], &px[..100], &px[100..250]] {
            let offset = chunk.as_ptr() as usize - px.as_ptr() as usize;
            let mut a = RoundTripAccumulator::default();
            for (i, &(l, de)) in chunk.iter().enumerate() {
                a.add(
                    offset / std::mem::size_of::<(f64, f64)>() + i,
                    0,
                    l,
                    1.0,
                    de,
                );
            }
            parts.merge(&a);
        }
        let f = whole.floor();
        assert_eq!(parts.floor(), f);
        let (a, b) = (whole.stats(&f), parts.stats(&f));
        assert_eq!(a.pixels, b.pixels);
        assert_eq!(a.max_de2000, b.max_de2000);
        assert_eq!(a.below_floor, b.below_floor);
        assert!((a.weighted_mean_de2000 - b.weighted_mean_de2000).abs() < 1e-12);
    }

    #[test]
    fn pixels_outside_the_map_are_not_added() {
        let mut a = RoundTripAccumulator::default();
        a.add(0, 0, 1.0, 0.0, 99.0);
        a.add(1, 0, 1.0, 0.5, 1.0);
        let s = a.stats(&a.floor());
        assert_eq!((s.pixels, s.max_de2000, s.black_pixels), (1, 1.0, 0));
    }
}
