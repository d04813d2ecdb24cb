//! Rows of a spectral image held as coefficient planes: every pixel's spectrum is a combination
//! of a few spectra of the scene (the engine's [`Combination`]), so a band's scan line is one
//! multiply-add per pixel and spectrum in use, computed as the writer asks for it: no
//! pixel-interleaved copy of the bands is made, nor transposed.

use crate::envmap::convert::pixel_spectra::Combination;
use crate::envmap::files::block::LineSource;
use crate::error::Result;
use rayon::prelude::*;

/// A batch of rows: for each row, one coefficient plane per spectrum of the table and one plane
/// per extra channel (the channels after the bands: R, G, B and the sun mask, or a basis
/// format's coefficients).
#[derive(Debug, Clone)]
pub(crate) struct SpectralRows {
    width: usize,
    /// The spectra that have planes, in table order: spectra[k][band].
    spectra: Vec<Vec<f32>>,
    /// For each spectrum of the table: its plane, or [`NO_PLANE`] (no pixel can use it).
    plane_of: [u8; 64],
    bands: usize,
    extras: usize,
    /// Row r, spectrum k, pixel x at `r * stride + k * width + x` (see `strides`).
    coefficients: Vec<f32>,
    /// Row r, extra channel e, pixel x at `r * stride + e * width + x`.
    extra: Vec<f32>,
    /// For each row, which spectra some pixel uses (bit k).
    used: Vec<u64>,
}

/// A table spectrum that no pixel can use has no plane.
const NO_PLANE: u8 = u8::MAX;

/// One row being filled (see [`SpectralRows::rows_mut`]).
pub(crate) struct RowMut<'a> {
    width: usize,
    plane_of: &'a [u8; 64],
    coefficients: &'a mut [f32],
    extra: &'a mut [f32],
    used: &'a mut u64,
}

impl RowMut<'_> {
    /// Pixel `x`'s spectrum.
    pub(crate) fn set(&mut self, x: usize, c: &Combination) {
        for j in 0..c.count {
            let k = self.plane_of[c.first + j];
            assert!(
                k != NO_PLANE,
                "a pixel uses spectrum {} of no plane",
                c.first + j
            );
            self.coefficients[k as usize * self.width + x] = c.weights[j];
            *self.used |= 1 << k;
        }
    }

    /// Pixel `x`'s value of extra channel `e`.
    pub(crate) fn set_extra(&mut self, e: usize, x: usize, v: f32) {
        self.extra[e * self.width + x] = v;
    }
}

impl SpectralRows {
    /// Room for `rows` rows of `width` pixels: `bands` channels made of the table's `spectra`
    /// (each `bands` long; none when `bands` is 0), of which only those in `live` (bit k: the
    /// table's spectrum k) can be used and get a plane, then `extras` channels set directly.
    pub(crate) fn new(
        spectra: Vec<Vec<f32>>,
        live: u64,
        bands: usize,
        extras: usize,
        width: usize,
        rows: usize,
    ) -> Self {
        let spectra = if bands == 0 { Vec::new() } else { spectra };
        assert!(spectra.len() <= 64 && spectra.iter().all(|s| s.len() == bands));
        let mut plane_of = [NO_PLANE; 64];
        let mut kept = Vec::new();
        for (k, s) in spectra.into_iter().enumerate() {
            if live & (1 << k) != 0 {
                plane_of[k] = kept.len() as u8;
                kept.push(s);
            }
        }
        SpectralRows {
            width,
            bands,
            extras,
            coefficients: vec![0.0; rows * kept.len().max(1) * width],
            extra: vec![0.0; rows * extras.max(1) * width],
            used: vec![0; rows],
            spectra: kept,
            plane_of,
        }
    }

    /// Values per row of the coefficient and extra planes (at least one plane each, so that
    /// every row has its chunk).
    fn strides(&self) -> (usize, usize) {
        (
            self.spectra.len().max(1) * self.width,
            self.extras.max(1) * self.width,
        )
    }

    /// The first `rows` rows, cleared, to fill in parallel.
    pub(crate) fn rows_mut(
        &mut self,
        rows: usize,
    ) -> impl IndexedParallelIterator<Item = RowMut<'_>> {
        let width = self.width;
        let (k, e) = self.strides();
        let plane_of = &self.plane_of;
        self.coefficients[..rows * k]
            .par_chunks_mut(k)
            .zip(self.extra[..rows * e].par_chunks_mut(e))
            .zip(self.used[..rows].par_iter_mut())
            .map(move |((coefficients, extra), used)| {
                coefficients.fill(0.0);
                *used = 0;
                RowMut {
                    width,
                    plane_of,
                    coefficients,
                    extra,
                    used,
                }
            })
    }
}

impl LineSource for SpectralRows {
    fn line(&self, channel: usize, row: usize, out: &mut [f32]) {
        let w = self.width;
        if channel >= self.bands {
            let start = row * self.strides().1 + (channel - self.bands) * w;
            out.copy_from_slice(&self.extra[start..start + w]);
            return;
        }
        let stride = self.strides().0;
        let used = self.used[row];
        // Each used spectrum's value at this band and its coefficient plane in this row.
        let terms = (0..self.spectra.len())
            .filter(|k| used & (1 << k) != 0)
            .map(|k| {
                let start = row * stride + k * w;
                (
                    self.spectra[k][channel],
                    &self.coefficients[start..start + w],
                )
            });
        let mut terms = terms.peekable();
        if terms.peek().is_none() {
            out.fill(0.0);
            return;
        }
        // Three spectra a pass, summed in table order as the pixel's spectrum is.
        let mut first = true;
        while let Some(a) = terms.next() {
            match (terms.next(), terms.next()) {
                (None, _) => add_planes(out, [a], first),
                (Some(b), None) => add_planes(out, [a, b], first),
                (Some(b), Some(c)) => add_planes(out, [a, b, c], first),
            }
            first = false;
        }
    }
}

/// `out = sum_j s_j * plane_j` (`first`) or `out += ...`, the terms added left to right: one
/// pass over the line for up to three spectra.
#[inline(always)]
fn add_planes<const N: usize>(out: &mut [f32], terms: [(f32, &[f32]); N], first: bool) {
    let w = out.len();
    let s: [f32; N] = terms.map(|(s, _)| s);
    let planes: [&[f32]; N] = terms.map(|(_, p)| &p[..w]);
    for (i, o) in out.iter_mut().enumerate() {
        let head = planes[0][i] * s[0];
        let mut v = if first { head } else { *o + head };
        for j in 1..N {
            v += planes[j][i] * s[j];
        }
        *o = v;
    }
}

/// Computes and writes an image a batch of rows at a time, filling the next batch while the
/// current one is written (so neither stage waits for the other's slowest part): `fill(y, row)`
/// fills image row `y` and returns what it measured; `write(y0, rows, batch)` writes rows
/// `y0..y0 + rows` held in `batch`. Two batches of `batch` rows are in memory. What each row
/// measured is handed to `take` in row order, whatever thread filled it (so sums over the rows
/// do not depend on the threads).
pub(crate) fn stream<S: Send>(
    buffers: &mut [SpectralRows; 2],
    height: usize,
    batch: usize,
    fill: &(dyn Fn(usize, RowMut) -> S + Sync),
    write: &mut (dyn FnMut(usize, usize, &SpectralRows) -> Result<()> + Send),
    take: &mut dyn FnMut(S),
) -> Result<()> {
    let fill_batch = |buf: &mut SpectralRows, y0: usize, rows: usize| -> Vec<S> {
        buf.rows_mut(rows)
            .enumerate()
            .map(|(r, row)| fill(y0 + r, row))
            .collect()
    };
    let [a, b] = buffers;
    let (mut now, mut next) = (a, b);
    let mut rows = batch.clamp(1, height.max(1)).min(height);
    fill_batch(now, 0, rows).into_iter().for_each(&mut *take);
    let mut y0 = 0;
    while y0 < height {
        let next_y = y0 + rows;
        let next_rows = batch.min(height - next_y);
        let current = &*now;
        let (written, more) = rayon::join(
            || write(y0, rows, current),
            || fill_batch(next, next_y, next_rows),
        );
        written?;
        more.into_iter().for_each(&mut *take);
        std::mem::swap(&mut now, &mut next);
        (y0, rows) = (next_y, next_rows);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_band_line_is_each_pixels_combination_and_extras_come_as_set() {
        // Two spectra sets over 3 bands: pixel 0 takes set A (k 0, 1), pixel 1 set B (k 3).
        let spectra = [
            vec![1.0, 2.0, 3.0],
            vec![0.5, 0.0, -1.0],
            vec![4.0, 5.0, 6.0],
        ];
        // Spectrum 2 of the table is one no pixel uses: it gets no plane.
        let table = vec![
            spectra[0].clone(),
            spectra[1].clone(),
            vec![9.0; 3],
            spectra[2].clone(),
        ];
        let mut rows = SpectralRows::new(table, 0b1011, 3, 1, 2, 2);
        assert_eq!(rows.spectra.len(), 3);
        rows.rows_mut(2).enumerate().for_each(|(r, mut row)| {
            let k = r as f32 + 1.0;
            row.set(
                0,
                &Combination {
                    first: 0,
                    count: 2,
                    weights: [k, 2.0, 0.0],
                },
            );
            row.set(
                1,
                &Combination {
                    first: 3,
                    count: 1,
                    weights: [0.25, 0.0, 0.0],
                },
            );
            row.set_extra(0, 0, 7.0);
            row.set_extra(0, 1, -k);
        });
        let mut out = [0f32; 2];
        for (band, want) in [[2.0f32, 1.0], [4.0, 1.25], [4.0, 1.5]].iter().enumerate() {
            rows.line(band, 1, &mut out);
            assert_eq!(
                out[0],
                2.0 * [1.0, 2.0, 3.0][band] + 2.0 * [0.5, 0.0, -1.0][band]
            );
            assert_eq!(out[1], want[1]);
        }
        rows.line(3, 1, &mut out);
        assert_eq!(out, [7.0, -2.0]);
        // Rows are cleared when filled again: a row of no pixels set is black.
        rows.rows_mut(1).for_each(|_| {});
        rows.line(0, 0, &mut out);
        assert_eq!(out, [0.0, 0.0]);
    }

    #[test]
    fn streaming_writes_every_row_once_in_order_from_its_own_batch() {
        let spectra = vec![vec![1.0, 10.0]];
        let new = || SpectralRows::new(spectra.clone(), 1, 2, 0, 3, 4);
        let mut buffers = [new(), new()];
        let mut seen = Vec::new();
        let mut stats = Vec::new();
        stream(
            &mut buffers,
            10,
            4,
            &|y, mut row| {
                for x in 0..3 {
                    row.set(
                        x,
                        &Combination {
                            first: 0,
                            count: 1,
                            weights: [y as f32, 0.0, 0.0],
                        },
                    );
                }
                y
            },
            &mut |y0, rows, batch| {
                let mut out = [0f32; 3];
                for r in 0..rows {
                    batch.line(1, r, &mut out);
                    seen.push((y0 + r, out[0]));
                }
                Ok(())
            },
            &mut |y| stats.push(y),
        )
        .unwrap();
        assert_eq!(stats, (0..10).collect::<Vec<_>>());
        let want: Vec<(usize, f32)> = (0..10).map(|y| (y, 10.0 * y as f32)).collect();
        assert_eq!(seen, want);
    }
}
