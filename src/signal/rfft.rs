//! Real-input FFT on top of rustfft (docs/analysis.md, "Performance").
//!
//! A real series of even length N is packed as N/2 complex samples `z[m] = x[2m] + i·x[2m+1]`,
//! transformed with one complex FFT of N/2 points, and unpacked with the standard twiddle
//! post-process (`X_k = E_k + e^{−2πik/N}·O_k`, `E`/`O` the spectra of the even/odd samples,
//! separated through `Z_k` and `conj(Z_{N/2−k})`). That halves the work and the memory of a
//! complex transform of the same series. Odd N falls back to a complex FFT of N points.
//!
//! Conventions are numpy's `rfft`/`irfft` without the `1/N` of the inverse (rustfft's):
//! [`RealFft::forward`] returns the N/2 + 1 bins `X_0 … X_{⌊N/2⌋}`; [`RealFft::inverse`]
//! takes them and returns `N·x` (imaginary parts of `X_0` and, for even N, `X_{N/2}` are ignored,
//! as numpy's `irfft` does).
//!
//! Plans and twiddles are built once per length; `*_with_scratch` lets a caller that transforms
//! many series reuse one scratch buffer (no allocation per call).

use rustfft::num_complex::Complex;
use rustfft::num_traits::Float;
use rustfft::{Fft, FftNum, FftPlanner};
use std::sync::Arc;

/// A planned real FFT of one length, in precision `T` (`f64` or `f32`).
pub struct RealFft<T: FftNum> {
    n: usize,
    /// Even N: forward and inverse plans of N/2 points; odd N: of N points.
    forward: Arc<dyn Fft<T>>,
    inverse: Arc<dyn Fft<T>>,
    /// `e^{−2πik/N}` for k = 0…N/4 (even N only).
    twiddles: Vec<Complex<T>>,
}

impl<T: FftNum + Float> RealFft<T> {
    /// Plans both directions for length `n` (≥ 1) with `planner`.
    pub fn new(planner: &mut FftPlanner<T>, n: usize) -> Self {
        let n = n.max(1);
        let m = if n.is_multiple_of(2) { n / 2 } else { n };
        let twiddles = if n.is_multiple_of(2) {
            (0..=m / 2)
                .map(|k| {
                    // Evaluated in f64 so the f32 transform is not limited by its twiddles.
                    let phi = -2.0 * std::f64::consts::PI * k as f64 / n as f64;
                    Complex::new(from_f64(phi.cos()), from_f64(phi.sin()))
                })
                .collect()
        } else {
            Vec::new()
        };
        RealFft {
            n,
            forward: planner.plan_fft_forward(m),
            inverse: planner.plan_fft_inverse(m),
            twiddles,
        }
    }

    /// The real length N.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Never true (a plan has N ≥ 1); for clippy's `len_without_is_empty`.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Number of spectrum bins, N/2 + 1.
    pub fn spectrum_len(&self) -> usize {
        self.n / 2 + 1
    }

    /// Scratch length the `*_with_scratch` calls need.
    pub fn scratch_len(&self) -> usize {
        let inner = self
            .forward
            .get_inplace_scratch_len()
            .max(self.inverse.get_inplace_scratch_len());
        if self.n.is_multiple_of(2) {
            inner
        } else {
            // Odd N keeps the full complex series in the scratch too.
            inner + self.n
        }
    }

    /// Allocates a scratch buffer of [`Self::scratch_len`].
    pub fn make_scratch(&self) -> Vec<Complex<T>> {
        vec![Complex::new(T::zero(), T::zero()); self.scratch_len()]
    }

    /// Spectrum of `input` (length N) into `output` (length N/2 + 1).
    pub fn forward(&self, input: &[T], output: &mut [Complex<T>]) {
        let mut scratch = self.make_scratch();
        self.forward_with_scratch(input, output, &mut scratch);
    }

    /// [`Self::forward`] with a caller-owned scratch buffer of at least [`Self::scratch_len`].
    ///
    /// Panics if a length does not match (a programming error, not user input).
    pub fn forward_with_scratch(
        &self,
        input: &[T],
        output: &mut [Complex<T>],
        scratch: &mut [Complex<T>],
    ) {
        assert_eq!(input.len(), self.n, "real FFT input length");
        self.forward_from_fn(|i| input[i], output, scratch);
    }

    /// [`Self::forward_with_scratch`] reading sample `i` as `sample(i)`, called once per sample
    /// in order 0…N−1: a caller that windows or detrends on the fly needs no input buffer.
    pub fn forward_from_fn(
        &self,
        mut sample: impl FnMut(usize) -> T,
        output: &mut [Complex<T>],
        scratch: &mut [Complex<T>],
    ) {
        let n = self.n;
        assert_eq!(output.len(), n / 2 + 1, "real FFT output length");
        let zero = T::zero();
        if !n.is_multiple_of(2) {
            let (full, inner) = scratch.split_at_mut(n);
            for (i, c) in full.iter_mut().enumerate() {
                *c = Complex::new(sample(i), zero);
            }
            self.forward.process_with_scratch(full, inner);
            output.copy_from_slice(&full[..output.len()]);
            return;
        }
        let m = n / 2;
        for (i, c) in output[..m].iter_mut().enumerate() {
            let re = sample(2 * i);
            *c = Complex::new(re, sample(2 * i + 1));
        }
        self.forward.process_with_scratch(
            &mut output[..m],
            &mut scratch[..self.forward.get_inplace_scratch_len()],
        );
        let half = from_f64::<T>(0.5);
        let z0 = output[0];
        output[0] = Complex::new(z0.re + z0.im, zero);
        output[m] = Complex::new(z0.re - z0.im, zero);
        for k in 1..=m / 2 {
            let j = m - k;
            let a = output[k];
            let b = output[j].conj();
            // E = (Z_k + conj Z_j)/2, O = −i(Z_k − conj Z_j)/2; X_k = E + w·O,
            // X_j = conj(E − w·O) (w_j = −conj w_k).
            let e = (a + b) * half;
            let d = (a - b) * half;
            let o = Complex::new(d.im, -d.re);
            let wo = self.twiddles[k] * o;
            output[k] = e + wo;
            output[j] = (e - wo).conj();
        }
    }

    /// `N·x` from the N/2 + 1 bins of a real series' spectrum (unnormalised, like rustfft).
    /// `input` is used as workspace and left changed.
    pub fn inverse(&self, input: &mut [Complex<T>], output: &mut [T]) {
        let mut scratch = self.make_scratch();
        self.inverse_with_scratch(input, output, &mut scratch);
    }

    /// [`Self::inverse`] with a caller-owned scratch buffer of at least [`Self::scratch_len`].
    pub fn inverse_with_scratch(
        &self,
        input: &mut [Complex<T>],
        output: &mut [T],
        scratch: &mut [Complex<T>],
    ) {
        let n = self.n;
        assert_eq!(input.len(), n / 2 + 1, "real inverse FFT input length");
        assert_eq!(output.len(), n, "real inverse FFT output length");
        let zero = T::zero();
        if !n.is_multiple_of(2) {
            let (full, inner) = scratch.split_at_mut(n);
            full[0] = Complex::new(input[0].re, zero);
            for (k, &c) in input.iter().enumerate().skip(1) {
                full[k] = c;
                full[n - k] = c.conj();
            }
            self.inverse.process_with_scratch(full, inner);
            for (o, c) in output.iter_mut().zip(full.iter()) {
                *o = c.re;
            }
            return;
        }
        let m = n / 2;
        // Z_k = P + i·conj(w_k)·Q, Z_j = conj(P − i·conj(w_k)·Q), P = X_k + conj X_j,
        // Q = X_k − conj X_j: the even/odd spectra recombined (×2 so the result is N·x).
        let (x0, xm) = (input[0].re, input[m].re);
        input[0] = Complex::new(x0 + xm, x0 - xm);
        for k in 1..=m / 2 {
            let j = m - k;
            let p = input[k] + input[j].conj();
            let q = input[k] - input[j].conj();
            let wq = self.twiddles[k].conj() * q;
            let iwq = Complex::new(-wq.im, wq.re);
            input[k] = p + iwq;
            input[j] = (p - iwq).conj();
        }
        self.inverse.process_with_scratch(
            &mut input[..m],
            &mut scratch[..self.inverse.get_inplace_scratch_len()],
        );
        for (pair, c) in output.chunks_exact_mut(2).zip(&input[..m]) {
            pair[0] = c.re;
            pair[1] = c.im;
        }
    }
}

fn from_f64<T: FftNum + Float>(v: f64) -> T {
    // f64 → f32/f64 never fails for finite values.
    T::from(v).unwrap_or_else(T::zero)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rustfft::num_complex::{Complex32, Complex64};

    fn series(n: usize) -> Vec<f64> {
        // Deterministic, broadband: a few incommensurate tones plus a ramp.
        (0..n)
            .map(|i| {
                let t = i as f64;
                (0.37 * t).sin() + 0.5 * (1.91 * t + 0.3).cos() + 1e-3 * t - 0.25
            })
            .collect()
    }

    fn complex_fft(x: &[f64]) -> Vec<Complex64> {
        let mut buf: Vec<Complex64> = x.iter().map(|&v| Complex64::new(v, 0.0)).collect();
        FftPlanner::<f64>::new()
            .plan_fft_forward(x.len())
            .process(&mut buf);
        buf
    }

    #[test]
    fn forward_matches_the_complex_fft_for_even_and_odd_lengths() {
        let mut planner = FftPlanner::<f64>::new();
        for n in [
            1usize, 2, 3, 4, 5, 6, 8, 10, 15, 16, 30, 97, 128, 1000, 4096, 6000,
        ] {
            let x = series(n);
            let reference = complex_fft(&x);
            let r = RealFft::new(&mut planner, n);
            let mut out = vec![Complex64::default(); r.spectrum_len()];
            r.forward(&x, &mut out);
            let scale = reference.iter().map(|c| c.norm()).fold(1.0, f64::max);
            for (k, (a, b)) in out.iter().zip(&reference).enumerate() {
                assert!((a - b).norm() <= 1e-13 * scale, "n {n} bin {k}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn inverse_returns_n_times_the_series() {
        let mut planner = FftPlanner::<f64>::new();
        for n in [1usize, 2, 3, 4, 7, 8, 12, 64, 99, 1024, 6000] {
            let x = series(n);
            let r = RealFft::new(&mut planner, n);
            let mut spec = vec![Complex64::default(); r.spectrum_len()];
            r.forward(&x, &mut spec);
            let mut back = vec![0.0; n];
            r.inverse(&mut spec, &mut back);
            let scale = x.iter().map(|v| v.abs()).fold(1.0, f64::max);
            for (i, (a, b)) in back.iter().zip(&x).enumerate() {
                assert!(
                    (a / n as f64 - b).abs() <= 1e-13 * scale,
                    "n {n} sample {i}: {} vs {b}",
                    a / n as f64
                );
            }
        }
    }

    #[test]
    fn f32_forward_agrees_with_f64_to_single_precision() {
        let n = 1 << 14;
        let x = series(n);
        let x32: Vec<f32> = x.iter().map(|&v| v as f32).collect();
        let reference = complex_fft(&x);
        let r = RealFft::<f32>::new(&mut FftPlanner::new(), n);
        let mut out = vec![Complex32::default(); r.spectrum_len()];
        r.forward(&x32, &mut out);
        let scale = reference.iter().map(|c| c.norm()).fold(0.0, f64::max);
        let worst = out
            .iter()
            .zip(&reference)
            .map(|(a, b)| (Complex64::new(a.re as f64, a.im as f64) - b).norm())
            .fold(0.0, f64::max);
        // ~√(log2 N)·ε32 of the largest bin.
        assert!(worst <= 2e-6 * scale, "{worst} vs {scale}");
    }
}
