//! The DOE's response surfaces (dissertation §2.3.2): per actuation level the degree-4
//! polynomial in the coded factors and the degree-5 one it is tested against, and the surrogate
//! ξ the annealing may use, linear in h_TFC between the levels.

use super::cases::DesignCase;
use super::params::DoeParams;
use crate::error::{Error, Result};
use crate::numerics::regression::{FitOptions, PolynomialBasis, ResponseSurface};

/// The response surfaces of one actuation level: the spec's degree-4 model and the degree-5
/// model kept for the residual comparison.
pub(crate) struct LevelFit {
    pub(crate) actuation: f64,
    pub(crate) fixed: usize,
    pub(crate) quartic: ResponseSurface,
    pub(crate) quintic: Option<ResponseSurface>,
}

fn fit_level(actuation: f64, fixed: usize, points: &[Vec<f64>], xi: &[f64]) -> Result<LevelFit> {
    let opts = FitOptions::default();
    let fit = |degree: u32| {
        ResponseSurface::fit(&PolynomialBasis::bounded(3, 2, degree), points, xi, &opts)
    };
    let quartic = fit(4).map_err(|source| Error::ResponseSurface { actuation, source })?;
    Ok(LevelFit {
        actuation,
        fixed,
        quartic,
        // A 3³ design leaves one residual df to the 26-term model; keep it if it fits.
        quintic: fit(5).ok(),
    })
}

/// The surrogate ξ at any actuation: the level fits, linear in h between neighbours.
pub(crate) fn surrogate_xi(fits: &[LevelFit], h: f64, coded_point: &[f64]) -> f64 {
    let k = fits
        .windows(2)
        .position(|w| w[0].actuation <= h && h <= w[1].actuation);
    match k {
        Some(k) => {
            let (lo, hi) = (&fits[k], &fits[k + 1]);
            let t = (h - lo.actuation) / (hi.actuation - lo.actuation);
            (1.0 - t) * lo.quartic.predict(coded_point) + t * hi.quartic.predict(coded_point)
        }
        None => fits
            .iter()
            .min_by(|a, b| (a.actuation - h).abs().total_cmp(&(b.actuation - h).abs()))
            .map_or(f64::NAN, |f| f.quartic.predict(coded_point)),
    }
}

/// The response surfaces of every actuation level, from the design's cases (level by level,
/// `designs.len()` per level).
pub(crate) fn fit_levels(
    p: &DoeParams,
    coded_points: &[Vec<f64>],
    designs: &[[f64; 3]],
    cases: &[DesignCase],
) -> Result<Vec<LevelFit>> {
    let per_level = designs.len();
    let mut fits = Vec::new();
    for (k, &h) in p.actuations.iter().enumerate() {
        let xi: Vec<f64> = cases[k * per_level..(k + 1) * per_level]
            .iter()
            .map(|c| c.xi)
            .collect();
        if let Some(i) = xi.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFiniteXi {
                design: designs[i],
                actuation: h,
            });
        }
        fits.push(fit_level(h, p.fixed[k], coded_points, &xi)?);
    }
    Ok(fits)
}

/// Does the degree-5 model explain significantly more than the degree-4 one? The
/// extra-sum-of-squares F test of the nested models (3 added terms against the larger model's
/// residual), at 5 %: the dissertation kept degree 4 where the added terms were not needed.
pub(crate) fn model_selection(lf: &LevelFit) -> (Option<f64>, Option<f64>, u32) {
    let Some(q) = &lf.quintic else {
        return (None, None, 4);
    };
    let (r4, r5) = (&lf.quartic.fit, &q.fit);
    let added = r5.parameters.saturating_sub(r4.parameters);
    if added == 0 || r5.residual_df == 0 || r5.rss <= 0.0 {
        return (None, None, 4);
    }
    let f = ((r4.rss - r5.rss) / added as f64) / (r5.rss / r5.residual_df as f64);
    let p = crate::numerics::special::f_sf(f, added as f64, r5.residual_df as f64);
    (Some(f), Some(p), if p < 0.05 { 5 } else { 4 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numerics::regression::full_factorial;

    #[test]
    fn surrogate_interpolates_linearly_between_levels() {
        let points = full_factorial(&[3, 3, 3]);
        let basis = PolynomialBasis::bounded(3, 2, 4);
        // ξ = 1 + x1 at 9 nm and 3 + x1 at 12 nm: exact on the quartic basis.
        let fit_of = |h: f64, c: f64| {
            let xi: Vec<f64> = points.iter().map(|p| c + p[0]).collect();
            LevelFit {
                actuation: h,
                fixed: 0,
                quartic: ResponseSurface::fit(&basis, &points, &xi, &FitOptions::default())
                    .unwrap(),
                quintic: None,
            }
        };
        let fits = [fit_of(9e-9, 1.0), fit_of(12e-9, 3.0)];
        let at = |h: f64| surrogate_xi(&fits, h, &[0.5, 0.0, 0.0]);
        assert!((at(9e-9) - 1.5).abs() < 1e-10);
        assert!((at(12e-9) - 3.5).abs() < 1e-10);
        // 9.75 nm is a quarter of the way: 1.5 + 0.25 · 2.
        assert!((at(9.75e-9) - 2.0).abs() < 1e-10);
        // Outside: the nearest level.
        assert!((at(20e-9) - 3.5).abs() < 1e-10);
    }

    #[test]
    fn degree_five_is_selected_only_when_its_terms_are_needed() {
        let points = full_factorial(&[3, 3, 3]);
        let mut rng = crate::numerics::rng::Rng::new(5);
        let noise: Vec<f64> = points.iter().map(|_| 1e-3 * rng.normal()).collect();
        let level = |y: Vec<f64>| {
            let opts = FitOptions::default();
            let fit =
                |d| ResponseSurface::fit(&PolynomialBasis::bounded(3, 2, d), &points, &y, &opts);
            LevelFit {
                actuation: 9e-9,
                fixed: 2,
                quartic: fit(4).unwrap(),
                quintic: fit(5).ok(),
            }
        };
        // A quartic surface plus noise: the added terms explain noise only.
        let quartic: Vec<f64> = points
            .iter()
            .zip(&noise)
            .map(|(x, e)| 1.0 + x[0] - 0.5 * x[1] * x[1] * x[2] * x[2] + e)
            .collect();
        assert_eq!(model_selection(&level(quartic)).2, 4);
        // A strong degree-5 term (x1² x2² x3) the quartic cannot represent.
        let quintic: Vec<f64> = points
            .iter()
            .zip(&noise)
            .map(|(x, e)| 1.0 + x[0] * x[0] * x[1] * x[1] * x[2] + e)
            .collect();
        let (f, p, d) = model_selection(&level(quintic));
        assert_eq!(d, 5, "F {f:?}, p {p:?}");
    }
}
