//! Two-dimensional convolution of a real field with a real, even kernel given by its Fourier
//! transform: the operator an FFT boundary-element solver applies twice per iteration
//! (docs/contact.md, "Deterministic contact").
//!
//! The field (`nx × ny`, row-major, rows along x) is placed in an FFT grid of `px × py` (equal
//! for a periodic domain, doubled and zero-padded for a non-periodic one, Hockney's method).
//! Rows are transformed with the real-input FFT ([`RealFft`]: N/2 + 1 bins), the columns with a
//! complex FFT; each column is multiplied by the kernel and transformed back while it is in
//! cache, so one application is one pass of row transforms, one of columns and one of rows
//! back. Rows of the padding are zero and skipped; only the `nx × ny` block is returned.
//! Rows and columns run in parallel (rayon).

use crate::signal::rfft::RealFft;
use rayon::prelude::*;
use rustfft::num_complex::Complex64;
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

/// A planned convolution on one grid.
pub struct FftConvolver {
    nx: usize,
    ny: usize,
    px: usize,
    py: usize,
    /// Kernel spectrum at bin (kx, ky), stored `kx·py + ky` (column-major, like the work
    /// buffer), already divided by `px·py` (the unnormalised inverse).
    kernel: Vec<f64>,
    rows: RealFft<f64>,
    col_forward: Arc<dyn Fft<f64>>,
    col_inverse: Arc<dyn Fft<f64>>,
}

/// Buffers of one application; reused across calls (no allocation per iteration).
pub struct ConvolutionWork {
    /// Row spectra, `y·(px/2+1) + kx`.
    rows: Vec<Complex64>,
    /// Column-major spectra, `kx·py + ky`.
    cols: Vec<Complex64>,
}

impl FftConvolver {
    /// Plans a convolution of `nx × ny` fields on a `px × py` FFT grid (`px ≥ nx`, `py ≥ ny`)
    /// with the kernel spectrum `kernel(kx, ky)`, for kx in 0..=px/2 and ky in 0..py (the
    /// bins of a real-input transform).
    pub fn new(
        nx: usize,
        ny: usize,
        px: usize,
        py: usize,
        kernel: impl Fn(usize, usize) -> f64 + Sync,
    ) -> Self {
        assert!(
            px >= nx && py >= ny && nx > 0 && ny > 0,
            "FFT grid covers the field"
        );
        let mut planner = FftPlanner::new();
        let rows = RealFft::new(&mut planner, px);
        let nxh = px / 2 + 1;
        let scale = 1.0 / (px as f64 * py as f64);
        let mut spectrum = vec![0.0; nxh * py];
        spectrum
            .par_chunks_mut(py)
            .enumerate()
            .for_each(|(kx, col)| {
                for (ky, v) in col.iter_mut().enumerate() {
                    *v = kernel(kx, ky) * scale;
                }
            });
        FftConvolver {
            nx,
            ny,
            px,
            py,
            kernel: spectrum,
            rows,
            col_forward: planner.plan_fft_forward(py),
            col_inverse: planner.plan_fft_inverse(py),
        }
    }

    /// The FFT grid, `(px, py)`.
    pub fn fft_grid(&self) -> (usize, usize) {
        (self.px, self.py)
    }

    /// Buffers for [`Self::apply`].
    pub fn work(&self) -> ConvolutionWork {
        let nxh = self.px / 2 + 1;
        ConvolutionWork {
            rows: vec![Complex64::new(0.0, 0.0); nxh * self.ny],
            cols: vec![Complex64::new(0.0, 0.0); nxh * self.py],
        }
    }

    /// Bytes held by the kernel and one [`ConvolutionWork`].
    pub fn memory_bytes(&self) -> usize {
        let nxh = self.px / 2 + 1;
        8 * self.kernel.len() + 16 * nxh * (self.ny + self.py)
    }

    /// `output = kernel ∗ input` on the `nx × ny` block (both row-major, `y·nx + x`).
    pub fn apply(&self, input: &[f64], output: &mut [f64], work: &mut ConvolutionWork) {
        let (nx, ny, px, py) = (self.nx, self.ny, self.px, self.py);
        assert!(
            input.len() == nx * ny && output.len() == nx * ny,
            "field size"
        );
        let nxh = px / 2 + 1;
        let rows = &self.rows;
        work.rows
            .par_chunks_mut(nxh)
            .zip(input.par_chunks(nx))
            .for_each_init(
                || rows.make_scratch(),
                |scratch, (spec, row)| {
                    rows.forward_from_fn(|x| if x < nx { row[x] } else { 0.0 }, spec, scratch);
                },
            );
        let row_spectra = &work.rows;
        let kernel = &self.kernel;
        let (fwd, inv) = (&self.col_forward, &self.col_inverse);
        let scratch_len = fwd
            .get_inplace_scratch_len()
            .max(inv.get_inplace_scratch_len());
        work.cols.par_chunks_mut(py).enumerate().for_each_init(
            || vec![Complex64::new(0.0, 0.0); scratch_len],
            |scratch, (kx, col)| {
                for (y, c) in col.iter_mut().enumerate() {
                    *c = if y < ny {
                        row_spectra[y * nxh + kx]
                    } else {
                        Complex64::new(0.0, 0.0)
                    };
                }
                fwd.process_with_scratch(col, scratch);
                // Field by field: the same product as `*c *= k`, without a generic call
                // per element in unoptimised test builds.
                for (c, &k) in col.iter_mut().zip(&kernel[kx * py..(kx + 1) * py]) {
                    c.re *= k;
                    c.im *= k;
                }
                inv.process_with_scratch(col, scratch);
            },
        );
        let cols = &work.cols;
        work.rows
            .par_chunks_mut(nxh)
            .zip(output.par_chunks_mut(nx))
            .enumerate()
            .for_each_init(
                || (rows.make_scratch(), vec![0.0; px]),
                |(scratch, full), (y, (spec, out))| {
                    for (kx, s) in spec.iter_mut().enumerate() {
                        *s = cols[kx * py + y];
                    }
                    rows.inverse_with_scratch(spec, full, scratch);
                    out.copy_from_slice(&full[..nx]);
                },
            );
    }
}

/// Signed index of FFT bin `k` of `n`: 0, 1, …, ⌈n/2⌉−1, −⌊n/2⌋, …, −1.
pub fn signed_bin(k: usize, n: usize) -> f64 {
    if k <= (n - 1) / 2 {
        k as f64
    } else {
        k as f64 - n as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Direct circular convolution with the kernel `K(x, y)` whose spectrum the convolver has.
    fn direct(field: &[f64], nx: usize, ny: usize, px: usize, py: usize, k: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; nx * ny];
        for y in 0..ny {
            for x in 0..nx {
                let mut s = 0.0;
                for j in 0..ny {
                    for i in 0..nx {
                        let dx = (x + px - i) % px;
                        let dy = (y + py - j) % py;
                        s += k[dy * px + dx] * field[j * nx + i];
                    }
                }
                out[y * nx + x] = s;
            }
        }
        out
    }

    fn check(nx: usize, ny: usize, px: usize, py: usize) {
        // An even real kernel (so its spectrum is real): K depends on |signed offsets|.
        let kfun = |dx: f64, dy: f64| 1.0 / (1.0 + dx * dx + 0.5 * dy * dy);
        let mut k = vec![0.0; px * py];
        for y in 0..py {
            for x in 0..px {
                k[y * px + x] = kfun(signed_bin(x, px), signed_bin(y, py));
            }
        }
        // Its spectrum, by a direct DFT.
        let spectrum = |kx: usize, ky: usize| {
            let mut s = 0.0;
            for y in 0..py {
                for x in 0..px {
                    let ph = 2.0
                        * std::f64::consts::PI
                        * (kx as f64 * x as f64 / px as f64 + ky as f64 * y as f64 / py as f64);
                    s += k[y * px + x] * ph.cos();
                }
            }
            s
        };
        let conv = FftConvolver::new(nx, ny, px, py, spectrum);
        let field: Vec<f64> = (0..nx * ny)
            .map(|i| ((i * 7919) % 13) as f64 - 6.0)
            .collect();
        let mut out = vec![0.0; nx * ny];
        let mut work = conv.work();
        conv.apply(&field, &mut out, &mut work);
        let want = direct(&field, nx, ny, px, py, &k);
        for (a, b) in out.iter().zip(&want) {
            assert!((a - b).abs() < 1e-10 * (1.0 + b.abs()), "{a} vs {b}");
        }
        // The buffers are reused: a second call gives the same answer.
        let mut again = vec![0.0; nx * ny];
        conv.apply(&field, &mut again, &mut work);
        assert_eq!(out, again);
    }

    #[test]
    fn periodic_convolution_matches_the_direct_sum() {
        check(8, 6, 8, 6);
        check(7, 5, 7, 5);
    }

    #[test]
    fn padded_convolution_matches_the_direct_sum() {
        check(8, 6, 16, 12);
        check(5, 3, 10, 6);
    }
}
