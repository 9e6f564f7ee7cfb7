//! Small numeric kernels shared by stages (FFT helpers, ...).
pub mod fft2;
