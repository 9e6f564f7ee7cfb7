//! The elastic half-space's surface compliance, discretised on a grid of uniformly loaded
//! rectangular elements (docs/contact.md, "Deterministic contact").
//!
//! - Periodic: in Fourier space, `û(q) = 2·p̂(q)/(E*·|q|)` (the half-space's surface Green's function; Persson 2001),
//!   with the q = 0 mode set to zero: the mean displacement of a periodic half-space is not
//!   defined, so displacements have zero mean and the separation is the mean gap.
//! - Non-periodic: Love's (1929) displacement at the centre of element (i, j) under unit
//!   pressure on the element at the origin, in real space, circularly embedded in a doubled grid
//!   (Hockney's method) so that the FFT convolution equals the direct, non-periodic sum.

use crate::numerics::fft2::fft2_real;
use crate::signal::fft_convolution::{signed_bin, FftConvolver};
use ndarray::Array2;
use std::f64::consts::PI;

/// Periodic compliance on an `nx × ny` grid of spacing `dx × dy`.
pub fn periodic(nx: usize, ny: usize, dx: f64, dy: f64, e_star: f64) -> FftConvolver {
    let (lx, ly) = (nx as f64 * dx, ny as f64 * dy);
    FftConvolver::new(nx, ny, nx, ny, |kx, ky| {
        let qx = 2.0 * PI * signed_bin(kx, nx) / lx;
        let qy = 2.0 * PI * signed_bin(ky, ny) / ly;
        let q = qx.hypot(qy);
        if q == 0.0 {
            0.0
        } else {
            2.0 / (e_star * q)
        }
    })
}

/// Non-periodic compliance on an `nx × ny` grid, convolved on the zero-padded `2nx × 2ny`.
pub fn non_periodic(nx: usize, ny: usize, dx: f64, dy: f64, e_star: f64) -> FftConvolver {
    let (px, py) = (2 * nx, 2 * ny);
    let mut k = Array2::<f64>::zeros((py, px));
    for ((j, i), v) in k.indexed_iter_mut() {
        *v = love(
            signed_bin(i, px) * dx,
            signed_bin(j, py) * dy,
            dx,
            dy,
            e_star,
        );
    }
    let spectrum = fft2_real(&k);
    FftConvolver::new(nx, ny, px, py, |kx, ky| spectrum[[ky, kx]].re)
}

/// Love's (1929) normal displacement at (x, y) of an elastic half-space of reduced modulus
/// `E*` under unit pressure on the `dx × dy` rectangle centred at the origin:
/// `u = [F(x+a, y+b) − F(x+a, y−b) − F(x−a, y+b) + F(x−a, y−b)]/(π E*)`,
/// `F(X, Y) = X·ln(Y + r) + Y·ln(X + r)`, `r = √(X² + Y²)`, `a = dx/2`, `b = dy/2` — the
/// integral of the point-load solution `1/(π E* r)` over the rectangle.
pub fn love(x: f64, y: f64, dx: f64, dy: f64, e_star: f64) -> f64 {
    // Even in x and y: evaluating at |x|, |y| keeps every logarithm's argument positive on
    // the grid (X + r = 0 only for Y = 0, X < 0, where its factor Y is zero).
    let (x, y) = (x.abs(), y.abs());
    let (a, b) = (0.5 * dx, 0.5 * dy);
    let term = |c: f64, arg: f64| if c == 0.0 { 0.0 } else { c * arg.ln() };
    let f = |xx: f64, yy: f64| {
        let r = xx.hypot(yy);
        term(xx, yy + r) + term(yy, xx + r)
    };
    (f(x + a, y + b) - f(x + a, y - b) - f(x - a, y + b) + f(x - a, y - b)) / (PI * e_star)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn love_at_the_centre_of_a_square_is_the_closed_form() {
        // Centre of a uniformly loaded square of side c: u = 4·c·ln(1 + √2)/(π E*)
        // (the integral of 1/r over the square is 4·c·ln(1 + √2)).
        let (c, e) = (2.0e-9, 1.0e11);
        let want = 4.0 * c * (1.0 + 2f64.sqrt()).ln() / (PI * e);
        let got = love(0.0, 0.0, c, c, e);
        assert!((got - want).abs() < 1e-14 * want, "{got} vs {want}");
    }

    #[test]
    fn love_far_away_is_the_point_load() {
        let (c, e) = (1.0e-9, 1.0e11);
        let r = 200.0 * c;
        let got = love(r * 0.6, r * 0.8, c, c, e);
        let want = c * c / (PI * e * r);
        assert!((got / want - 1.0).abs() < 1e-5, "{got} vs {want}");
    }
}
