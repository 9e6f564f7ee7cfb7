//! Globally adaptive Gauss–Kronrod (G7/K15) quadrature of vector-valued integrands.
//!
//! The ISBL curves are several integrals over the same Gaussian density (load, stiffness,
//! area, count, adhesion …); integrating them as one vector shares every density evaluation
//! and every (expensive) asperity-law evaluation. Each component must meet its own relative
//! tolerance, so a small component (e.g. a stiffness that changes sign under the integral)
//! is not sacrificed to a large one.

use crate::contact::ContactError;

/// Kronrod abscissae of the 15-point rule on [−1, 1] (non-negative half, descending).
const XGK: [f64; 8] = [
    0.991_455_371_120_812_6,
    0.949_107_912_342_758_5,
    0.864_864_423_359_769_1,
    0.741_531_185_599_394_4,
    0.586_087_235_467_691_1,
    0.405_845_151_377_397_2,
    0.207_784_955_007_898_5,
    0.0,
];
/// Kronrod weights matching `XGK`.
const WGK: [f64; 8] = [
    0.022_935_322_010_529_225,
    0.063_092_092_629_978_55,
    0.104_790_010_322_250_18,
    0.140_653_259_715_525_92,
    0.169_004_726_639_267_9,
    0.190_350_578_064_785_4,
    0.204_432_940_075_298_9,
    0.209_482_141_084_727_83,
];
/// Gauss 7-point weights at the odd-indexed Kronrod abscissae `XGK[1], XGK[3], XGK[5], XGK[7]`.
const WG: [f64; 4] = [
    0.129_484_966_168_869_7,
    0.279_705_391_489_276_7,
    0.381_830_050_505_118_9,
    0.417_959_183_673_469_4,
];

/// Round-off floor of the error criterion, relative to `∫|f|`.
const ROUNDOFF_FLOOR: f64 = 50.0 * f64::EPSILON;

/// Absolute floor of the error criterion: integrands near the bottom of the f64 range
/// (a Gaussian 38σ out) lose precision to subnormal numbers and could never meet a relative
/// tolerance; values this small are zero for any physical use.
const ABSOLUTE_FLOOR: f64 = 1e-280;

/// One sub-interval of the adaptive partition. `piece` tells the integrand which
/// formula/variable applies (the ISBL pieces are regimes with different asperity laws).
#[derive(Clone, Copy)]
struct Segment<const M: usize> {
    piece: usize,
    a: f64,
    b: f64,
    value: [f64; M],
    error: [f64; M],
    abs_value: [f64; M],
}

fn gk15<const M: usize>(
    f: &mut impl FnMut(usize, f64) -> [f64; M],
    piece: usize,
    a: f64,
    b: f64,
) -> Segment<M> {
    let centre = 0.5 * (a + b);
    let half = 0.5 * (b - a);
    let mut kronrod = [0.0; M];
    let mut gauss = [0.0; M];
    let mut abs_value = [0.0; M];
    let mut add = |fx: [f64; M], wk: f64, wg: f64| {
        for i in 0..M {
            kronrod[i] += wk * fx[i];
            gauss[i] += wg * fx[i];
            abs_value[i] += wk * fx[i].abs();
        }
    };
    add(f(piece, centre), WGK[7], WG[3]);
    for j in 0..7 {
        let dx = half * XGK[j];
        let wg = if j % 2 == 1 { WG[j / 2] } else { 0.0 };
        add(f(piece, centre - dx), WGK[j], wg);
        add(f(piece, centre + dx), WGK[j], wg);
    }
    let mut value = [0.0; M];
    let mut error = [0.0; M];
    for i in 0..M {
        value[i] = kronrod[i] * half;
        error[i] = ((kronrod[i] - gauss[i]) * half).abs();
        abs_value[i] *= half.abs();
    }
    Segment {
        piece,
        a,
        b,
        value,
        error,
        abs_value,
    }
}

/// Integrates `f(piece, x)` over the given `(piece, a, b)` intervals (their sum), refining
/// the worst interval until every component `i` satisfies
/// `Σ error_i ≤ rel_tol·|Σ value_i| + 50·ε_mach·Σ |value|_i + 1e-280`. The second term is the
/// round-off floor (as in QUADPACK): it only matters for components whose integrand cancels
/// to a tiny fraction of `∫|f|`, e.g. a stiffness far out in the tail, whose relative accuracy
/// is then limited by round-off rather than making the routine fail. Empty intervals
/// (`a == b`) are skipped.
///
/// Errors with `ContactError::Numerical` if `max_segments` is reached or the integrand is
/// not finite.
pub(crate) fn integrate<const M: usize>(
    mut f: impl FnMut(usize, f64) -> [f64; M],
    pieces: &[(usize, f64, f64)],
    rel_tol: f64,
    max_segments: usize,
) -> Result<[f64; M], ContactError> {
    let mut segments: Vec<Segment<M>> = pieces
        .iter()
        .filter(|(_, a, b)| b > a)
        .map(|&(piece, a, b)| gk15(&mut f, piece, a, b))
        .collect();
    loop {
        let mut value = [0.0; M];
        let mut error = [0.0; M];
        let mut abs_value = [0.0; M];
        for s in &segments {
            for i in 0..M {
                value[i] += s.value[i];
                error[i] += s.error[i];
                abs_value[i] += s.abs_value[i];
            }
        }
        if value.iter().chain(error.iter()).any(|v| !v.is_finite()) {
            return Err(ContactError::Numerical(
                "ISBL quadrature: integrand is not finite".into(),
            ));
        }
        let tol: [f64; M] = std::array::from_fn(|i| {
            rel_tol * value[i].abs() + ROUNDOFF_FLOOR * abs_value[i] + ABSOLUTE_FLOOR
        });
        if (0..M).all(|i| error[i] <= tol[i]) {
            return Ok(value);
        }
        if segments.len() >= max_segments {
            return Err(ContactError::Numerical(format!(
                "ISBL quadrature: {max_segments} segments without reaching relative tolerance {rel_tol:e}"
            )));
        }
        // Worst segment: largest error relative to its component's tolerance.
        let badness = |s: &Segment<M>| {
            (0..M)
                .map(|i| {
                    if tol[i] > 0.0 {
                        s.error[i] / tol[i]
                    } else if s.error[i] > 0.0 {
                        f64::MAX
                    } else {
                        0.0
                    }
                })
                .fold(0.0, f64::max)
        };
        let (worst_index, _) = segments
            .iter()
            .enumerate()
            .map(|(k, s)| (k, badness(s)))
            .fold(
                (0, -1.0),
                |best, cur| if cur.1 > best.1 { cur } else { best },
            );
        let worst = segments.swap_remove(worst_index);
        let mid = 0.5 * (worst.a + worst.b);
        if !(mid > worst.a && mid < worst.b) {
            return Err(ContactError::Numerical(
                "ISBL quadrature: interval cannot be bisected further".into(),
            ));
        }
        segments.push(gk15(&mut f, worst.piece, worst.a, mid));
        segments.push(gk15(&mut f, worst.piece, mid, worst.b));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_polynomial_exponential_and_sqrt_endpoint() {
        // ∫_0^1 x^5 dx = 1/6, ∫_0^2 e^x dx = e² − 1, ∫_0^1 √x dx = 2/3 (endpoint singularity
        // in the derivative, needs refinement). Closed forms.
        let r = integrate(
            |_, x: f64| [x.powi(5), (2.0 * x).exp() * 2.0, x.sqrt()],
            &[(0, 0.0, 1.0)],
            1e-12,
            200,
        )
        .unwrap();
        assert!((r[0] - 1.0 / 6.0).abs() < 1e-14);
        assert!((r[1] - (2f64.exp() - 1.0)).abs() < 1e-12);
        assert!((r[2] - 2.0 / 3.0).abs() < 1e-11, "{}", r[2] - 2.0 / 3.0);
    }

    #[test]
    fn reports_non_convergence_as_error() {
        let r = integrate(|_, x: f64| [1.0 / x], &[(0, 0.0, 1.0)], 1e-12, 20);
        assert!(matches!(r, Err(ContactError::Numerical(_))));
    }
}
