//! Small numeric kernels shared by stages (FFT helpers, the ODE integrator, ...).
pub mod annealing;
pub mod bootstrap;
pub mod buffer;
pub mod fft2;
pub mod nelder_mead;
pub mod ode;
pub mod regression;
pub mod rng;
pub mod special;
