//! Reductions over one pixel's bands (its largest magnitude, its lowest and highest value),
//! computed in eight independent lanes so that they vectorise. A fold with one accumulator
//! cannot: `f32::max` is a chain of dependent steps, and at 81 bands it cost as much as computing
//! the spectrum. The largest or smallest of a set of numbers does not depend on the order they
//! are taken in, so the lanes give the same value as the one-accumulator fold. Each step is a
//! comparison (`x86`'s `maxps` and `minps`), which skips NaN as `f32::max` and `f32::min` do.

const LANES: usize = 8;

/// A spectrum is "negative" when some value is below -this x its peak.
pub(crate) const NEGATIVE_TOLERANCE: f64 = 1e-4;

/// `v` where it is larger than `m`, else `m` (NaN never is).
#[inline(always)]
fn larger(m: f32, v: f32) -> f32 {
    if v > m {
        v
    } else {
        m
    }
}

/// `v` where it is smaller than `m`, else `m` (NaN never is).
#[inline(always)]
fn smaller(m: f32, v: f32) -> f32 {
    if v < m {
        v
    } else {
        m
    }
}

/// Folds `values` with `step` in eight lanes from `init`, then the lanes into one.
#[inline(always)]
fn fold_lanes<T: Copy>(values: &[f32], init: T, step: impl Fn(T, f32) -> T) -> [T; LANES] {
    let mut acc = [init; LANES];
    let chunks = values.chunks_exact(LANES);
    let tail = chunks.remainder();
    for chunk in chunks {
        for (a, &v) in acc.iter_mut().zip(chunk) {
            *a = step(*a, v);
        }
    }
    for (a, &v) in acc.iter_mut().zip(tail) {
        *a = step(*a, v);
    }
    acc
}

/// The largest magnitude in `values` (0 for none).
#[inline]
pub(crate) fn max_abs(values: &[f32]) -> f32 {
    fold_lanes(values, 0f32, |m, v| larger(m, v.abs()))
        .into_iter()
        .fold(0f32, larger)
}

/// The lowest and highest of `values` and 0.
#[inline]
pub(crate) fn min_max(values: &[f32]) -> (f32, f32) {
    let lo = fold_lanes(values, 0f32, smaller);
    let hi = fold_lanes(values, 0f32, larger);
    (
        lo.into_iter().fold(0f32, smaller),
        hi.into_iter().fold(0f32, larger),
    )
}

/// Whether a spectrum whose values range over `(lo, hi)` (with 0, as [`min_max`] gives them)
/// goes below zero beyond rounding.
#[inline]
pub(crate) fn is_negative((lo, hi): (f32, f32)) -> bool {
    lo < -(NEGATIVE_TOLERANCE as f32) * hi
}

/// The largest magnitude of values that range over `(lo, hi)` (with 0): [`max_abs`] of them.
#[inline]
pub(crate) fn max_abs_of_range((lo, hi): (f32, f32)) -> f32 {
    larger(hi, -lo)
}

/// The range (as [`min_max`]) of `sum_j weights[j] * spectra[j]`, one or three spectra, each
/// value computed as [`crate::envmap::convert::pixel_spectra`] writes it (the f32 products
/// summed in j order), without storing it.
// Never inlined: inlined into its caller, the lanes were compiled as scalars in one build and
// vectors in the next (4x the instructions), as the caller changed around them.
#[inline(never)]
pub(crate) fn combination_range(spectra: &[Vec<f32>], weights: &[f32; 3]) -> (f32, f32) {
    let [w0, w1, w2] = *weights;
    let mut lanes = Lanes::default();
    match spectra {
        [s0] => {
            let c0 = s0.chunks_exact(LANES);
            for (i, &b0) in c0.remainder().iter().enumerate() {
                lanes.take(i, w0 * b0);
            }
            for a0 in c0 {
                let a0 = lane_array(a0);
                lanes.take_all(std::array::from_fn(|k| w0 * a0[k]));
            }
        }
        [s0, s1, s2] => {
            let (c0, c1, c2) = (
                s0.chunks_exact(LANES),
                s1.chunks_exact(LANES),
                s2.chunks_exact(LANES),
            );
            let tail = c0
                .remainder()
                .iter()
                .zip(c1.remainder())
                .zip(c2.remainder());
            for (i, ((&b0, &b1), &b2)) in tail.enumerate() {
                lanes.take(i, w0 * b0 + w1 * b1 + w2 * b2);
            }
            for ((a0, a1), a2) in c0.zip(c1).zip(c2) {
                let (a0, a1, a2) = (lane_array(a0), lane_array(a1), lane_array(a2));
                lanes.take_all(std::array::from_fn(|k| {
                    w0 * a0[k] + w1 * a1[k] + w2 * a2[k]
                }));
            }
        }
        _ => unreachable!("a pixel combines one spectrum or three"),
    }
    lanes.range()
}

/// A chunk of `chunks_exact(LANES)` as an array (whose length the compiler then knows).
#[inline(always)]
fn lane_array(chunk: &[f32]) -> [f32; LANES] {
    chunk.try_into().expect("chunks of the lanes' width")
}

/// Eight lanes of lowest and highest values (with 0).
#[derive(Default)]
struct Lanes {
    lo: [f32; LANES],
    hi: [f32; LANES],
}

impl Lanes {
    /// Takes `v` into lane `k`.
    #[inline(always)]
    fn take(&mut self, k: usize, v: f32) {
        self.lo[k] = smaller(self.lo[k], v);
        self.hi[k] = larger(self.hi[k], v);
    }

    /// Takes `v[k]` into lane `k`, every lane.
    #[inline(always)]
    fn take_all(&mut self, v: [f32; LANES]) {
        self.lo = std::array::from_fn(|k| smaller(self.lo[k], v[k]));
        self.hi = std::array::from_fn(|k| larger(self.hi[k], v[k]));
    }

    /// The lowest and highest over the lanes.
    fn range(&self) -> (f32, f32) {
        (
            self.lo.into_iter().fold(0f32, smaller),
            self.hi.into_iter().fold(0f32, larger),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The one-accumulator folds these replace.
    fn serial(values: &[f32]) -> (f32, f32, f32) {
        let m = values.iter().fold(0f32, |m, v| m.max(v.abs()));
        let (lo, hi) = values
            .iter()
            .fold((0f32, 0f32), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        (m, lo, hi)
    }

    #[test]
    fn lanes_give_the_serial_folds_values() {
        // Lengths around the lane count, values of both signs, a NaN, infinities and subnormals.
        let pool = [
            0.5,
            -3.25,
            f32::NAN,
            1e-40,
            -1e-40,
            7.0,
            -0.0,
            f32::INFINITY,
            -f32::INFINITY,
            2.5e4,
            -6e-8,
        ];
        for len in 0..40 {
            for shift in 0..pool.len() {
                let v: Vec<f32> = (0..len)
                    .map(|i| pool[(i * 7 + shift) % pool.len()] * (1.0 + i as f32 * 0.01))
                    .collect();
                let (m, lo, hi) = serial(&v);
                assert_eq!(max_abs(&v).to_bits(), m.to_bits(), "{v:?}");
                let (l, h) = min_max(&v);
                assert_eq!((l == lo, h == hi), (true, true), "{v:?}");
            }
        }
    }

    /// The values `combination_range` ranges over, written out as the engine writes them.
    fn written(spectra: &[Vec<f32>], w: &[f32; 3]) -> Vec<f32> {
        (0..spectra[0].len())
            .map(|i| match spectra {
                [s0] => w[0] * s0[i],
                [s0, s1, s2] => w[0] * s0[i] + w[1] * s1[i] + w[2] * s2[i],
                _ => unreachable!(),
            })
            .collect()
    }

    #[test]
    fn a_combination_ranges_as_its_written_values() {
        for bands in [1, 7, 8, 9, 16, 81, 401] {
            let spectrum = |phase: f32| -> Vec<f32> {
                (0..bands)
                    .map(|i| ((i as f32 * 0.37 + phase).sin() + 0.2) * 1e3)
                    .collect()
            };
            let three = [spectrum(0.0), spectrum(1.0), spectrum(2.5)];
            for w in [
                [1.0, 0.5, -0.25],
                [-3.0, 1e-3, 7.0],
                [2.0, 0.0, 0.0],
                [0.0; 3],
            ] {
                for spectra in [&three[..], &three[..1]] {
                    let want = min_max(&written(spectra, &w));
                    let got = combination_range(spectra, &w);
                    assert_eq!(
                        (got.0.to_bits(), got.1.to_bits()),
                        (want.0.to_bits(), want.1.to_bits()),
                        "{bands} bands, weights {w:?}"
                    );
                    assert_eq!(max_abs_of_range(got), max_abs(&written(spectra, &w)));
                }
            }
        }
    }

    #[test]
    fn the_largest_magnitude_can_be_negative_and_last() {
        let mut v = vec![1.0f32; 81];
        v[80] = -9.0;
        assert_eq!(max_abs(&v), 9.0);
        assert_eq!(min_max(&v), (-9.0, 1.0));
    }
}
