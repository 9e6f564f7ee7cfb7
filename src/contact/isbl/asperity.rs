//! Single-asperity laws: Kogut–Etsion (2002) elastic-plastic sphere-on-flat load and area,
//! the static-friction laws (App. A.1, eq. A.6), and the elastic DMT/LJ adhesion factor
//! `f_el` (docs/contact.md).
//!
//! Everything is in Kogut–Etsion units: interference `ω* = ω/ω_c`, load `P/L_c`, area
//! `A/A_c`. The published fits jump slightly at `ω* = 1, 6, 110`; they are kept exactly as
//! published (eq. A.3) because the Gaussian summit sums are smooth in `h` regardless.

use super::quadrature;
use crate::contact::ContactError;

/// Kogut–Etsion deformation regime of one summit, by `ω* = ω/ω_c`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeRegime {
    /// `0 ≤ ω* ≤ 1`: Hertz.
    Elastic,
    /// `1 < ω* ≤ 6`.
    ElasticPlasticI,
    /// `6 < ω* ≤ 110`.
    ElasticPlasticII,
    /// `ω* > 110`: `P = 2πRωH`, `A = 2πRω`.
    FullyPlastic,
}

impl KeRegime {
    /// Regime of a dimensionless interference `ω*` (boundaries belong to the lower regime,
    /// as in App. A.1).
    pub fn of(omega_star: f64) -> Self {
        if omega_star <= 1.0 {
            KeRegime::Elastic
        } else if omega_star <= 6.0 {
            KeRegime::ElasticPlasticI
        } else if omega_star <= 110.0 {
            KeRegime::ElasticPlasticII
        } else {
            KeRegime::FullyPlastic
        }
    }
}

/// `P/L_c` of one summit in the given regime (KE 2002 fits; `k_factor` = `K` enters only
/// the fully plastic law `(3/K)·ω*`). Zero for `ω* ≤ 0` (no contact).
pub fn ke_load_ratio_in(regime: KeRegime, omega_star: f64, k_factor: f64) -> f64 {
    if omega_star <= 0.0 {
        return 0.0;
    }
    match regime {
        KeRegime::Elastic => omega_star.powf(1.5),
        KeRegime::ElasticPlasticI => 1.03 * omega_star.powf(1.425),
        KeRegime::ElasticPlasticII => 1.40 * omega_star.powf(1.263),
        KeRegime::FullyPlastic => 3.0 / k_factor * omega_star,
    }
}

/// `A/A_c` of one summit in the given regime (KE 2002 fits). Zero for `ω* ≤ 0`.
pub fn ke_area_ratio_in(regime: KeRegime, omega_star: f64) -> f64 {
    if omega_star <= 0.0 {
        return 0.0;
    }
    match regime {
        KeRegime::Elastic => omega_star,
        KeRegime::ElasticPlasticI => 0.93 * omega_star.powf(1.136),
        KeRegime::ElasticPlasticII => 0.94 * omega_star.powf(1.146),
        KeRegime::FullyPlastic => 2.0 * omega_star,
    }
}

/// `P/L_c` of one summit at `ω*` (regime chosen from `ω*`).
pub fn ke_load_ratio(omega_star: f64, k_factor: f64) -> f64 {
    ke_load_ratio_in(KeRegime::of(omega_star), omega_star, k_factor)
}

/// `A/A_c` of one summit at `ω*` (regime chosen from `ω*`).
pub fn ke_area_ratio(omega_star: f64) -> f64 {
    ke_area_ratio_in(KeRegime::of(omega_star), omega_star)
}

/// Seed power law for the static friction of an elastic summit (eq. A.6, back-solved from
/// the two Ch. 3.1 numbers): `Q_max/L_c = 0.4155·ω*^0.970` for `0 < ω* ≤ 1`, zero otherwise.
pub fn seed_power_friction_ratio(omega_star: f64) -> f64 {
    if omega_star > 0.0 && omega_star <= 1.0 {
        0.4155 * omega_star.powf(0.970)
    } else {
        0.0
    }
}

/// Coefficient `C` of the static-friction power law in the contact load,
/// `Q_max/L_c = C·(P/L_c)^m` (friction law `ke_static`, docs/contact.md, "Friction").
///
/// Kogut & Etsion's own fit constants (KE 2003, J. Tribol. 125:499, sliding inception of an
/// elastic-plastic sphere; used by KE 2004, J. Tribol. 126:34, whose rough-surface sum is
/// eq. A.6) could not be recovered: eq. A.6's exponents and coefficients were lost in the
/// extraction of the dissertation, and the stored copies of the papers give their abstracts
/// (and KE 2004's first page) only. What is known: KE 2003 give `Q_max` of one sphere as a
/// function of its normal load through "an internal static friction coefficient" that falls
/// with the load (their abstract), and the dissertation prints two single-sphere values of the model it used
/// (Ch. 3.1: 120 µN at ω = 0.1 nm and 1120 µN at 1 nm for R = 102 µm, E = 180 GPa, ν = 0.24,
/// H = 18 GPa, no adhesion input named). A power law in the Hertz load through those two
/// points is `Q_max/L_c = 0.4155·(P/L_c)^(0.970/1.5)` — the same curve as
/// [`seed_power_friction_ratio`] on elastic summits, written in the load instead of `ω*`
/// so that it can take the adhesion-augmented load.
pub const KE_STATIC_COEFFICIENT: f64 = 0.4155;
/// Exponent `m` of [`KE_STATIC_COEFFICIENT`]'s law: 0.970 (the Ch. 3.1 back-solve in `ω*`)
/// over the Hertz exponent 1.5. `μ = Q_max/P ∝ P^(m−1)` falls with the load, as KE 2003's
/// internal static friction coefficient does.
pub const KE_STATIC_EXPONENT: f64 = 0.970 / 1.5;
/// `Q_max/L_c` of one summit under the `ke_static` law (docs/contact.md, "Friction"): the
/// static-friction power law [`KE_STATIC_COEFFICIENT`]`·(P*_aug)^`[`KE_STATIC_EXPONENT`] at
/// the adhesion-augmented load `P*_aug = P/L_c + F_s/L_c`, with `P/L_c` from the KE 2002
/// fits of `regime` and `adhesion_load = F_s/L_c` the summit's adhesion force (the caller's
/// `2πΔγ_max·R·f_el(ω/ε)/L_c`). Zero for `ω* ≤ 0` and for fully plastic summits
/// (`ω* > 110`): the dissertation sums the friction over "elastically and
/// elastically-plastically deforming asperities" (Ch. 2.1; eq. A.6's elastic and
/// elastic-plastic ranges).
pub fn ke_static_friction_ratio_in(
    regime: KeRegime,
    omega_star: f64,
    k_factor: f64,
    adhesion_load: f64,
) -> f64 {
    if omega_star <= 0.0 || regime == KeRegime::FullyPlastic {
        return 0.0;
    }
    let load = ke_load_ratio_in(regime, omega_star, k_factor) + adhesion_load;
    KE_STATIC_COEFFICIENT * load.powf(KE_STATIC_EXPONENT)
}

/// Hertz gap outside the contact, `G(x) = √(x²−1) − (2−x²)·arccos(1/x)` for `x = r/a ≥ 1`,
/// written in `w = √(x²−1)` as `G = w − (1−w²)·atan(w)`, with its Taylor series
/// `Σ_{m≥1} (−1)^{m+1}·4m/(4m²−1)·w^{2m+1}` for small `w` where the closed form cancels.
fn hertz_gap(w: f64) -> f64 {
    if w < 0.05 {
        let w2 = w * w;
        let mut term = w * w2;
        let mut sum = 0.0;
        let mut sign = 1.0;
        for m in 1..=6 {
            let mf = m as f64;
            sum += sign * 4.0 * mf / (4.0 * mf * mf - 1.0) * term;
            term *= w2;
            sign = -sign;
        }
        sum
    } else {
        w - (1.0 - w * w) * w.atan()
    }
}

/// Below this `λ = ω/ε`, `f_el(λ) = 1` to better than 1e-10 (`f_el ≈ 1 + 0.2·λ`).
const F_EL_SMALL_LAMBDA: f64 = 1e-11;

/// Elastic DMT/LJ adhesion factor of a contacting summit (eq. A.1; docs/contact.md):
/// `F_s = 2π·Δγ·R·f_el(λ)`, `λ = ω/ε`,
/// `f_el(λ) = (8/3)·λ·∫_1^∞ [q⁻³ − q⁻⁹]·x dx`, `q = 1 + (λ/π)·G(x)`.
///
/// Evaluated by adaptive quadrature in `u` with `x = 1 + u²`, which makes `G` analytic at the
/// contact edge; the breakpoints `λ^{−1/3}` and `λ^{−1/4}` are the widths (in `u`) of the
/// attractive ring for large and small `λ`. Relative accuracy ~1e-12.
pub fn adhesion_factor_elastic(lambda: f64) -> Result<f64, ContactError> {
    if !lambda.is_finite() || lambda < 0.0 {
        return Err(ContactError::parameter(
            "lambda",
            lambda,
            "omega/epsilon must be finite and >= 0",
        ));
    }
    if lambda < F_EL_SMALL_LAMBDA {
        return Ok(1.0);
    }
    let scale = lambda / std::f64::consts::PI;
    let integrand_u = |u: f64| {
        let u2 = u * u;
        let x = 1.0 + u2;
        let w = u * (2.0 + u2).sqrt();
        let q = 1.0 + scale * hertz_gap(w);
        let q3 = 1.0 / (q * q * q);
        (q3 - q3 * q3 * q3) * x * 2.0 * u
    };
    let s1 = lambda.powf(-1.0 / 3.0);
    let s2 = lambda.powf(-0.25);
    let (lo, hi) = (s1.min(s2), s1.max(s2));
    let tail_start = 4.0 * hi;
    // Tail [tail_start, ∞) mapped by u = tail_start + v/(1−v), v ∈ [0, 1).
    let integral = quadrature::integrate(
        |piece, v: f64| {
            if piece == 0 {
                [integrand_u(v)]
            } else {
                let one_minus = 1.0 - v;
                let u = tail_start + v / one_minus;
                [integrand_u(u) / (one_minus * one_minus)]
            }
        },
        &[
            (0, 0.0, lo),
            (0, lo, hi),
            (0, hi, tail_start),
            (1, 0.0, 1.0),
        ],
        1e-12,
        400,
    )?;
    Ok(8.0 / 3.0 * lambda * integral[0])
}

/// Piecewise Chebyshev table of `f_el` in `y = ln λ` (one unit of `ln λ` per segment),
/// built once per process: the universal function is needed at every node of every GW
/// adhesion integral, and direct quadrature (~9 μs) would dominate an ISBL evaluation.
struct AdhesionTable {
    /// `ln λ` of the first segment's left edge.
    y_min: f64,
    /// Chebyshev coefficients per segment.
    segments: Vec<[f64; CHEB_DEGREE]>,
}

/// Table range `λ ∈ [e^-19, e^19]` (≈ 5.6e-9 … 1.8e8); ω/ε beyond it is evaluated directly
/// (above) or by the linear small-λ limit (below, error < 1e-16 there).
const TABLE_Y_MIN: f64 = -19.0;
const TABLE_SEGMENTS: usize = 38;
/// Nodes per segment; the interpolation error is checked (< 1e-12 relative) in the tests.
const CHEB_DEGREE: usize = 20;

impl AdhesionTable {
    fn build() -> Result<Self, ContactError> {
        let n = CHEB_DEGREE;
        let mut segments = Vec::with_capacity(TABLE_SEGMENTS);
        for seg in 0..TABLE_SEGMENTS {
            let y0 = TABLE_Y_MIN + seg as f64;
            let mut values = [0.0; CHEB_DEGREE];
            for (k, v) in values.iter_mut().enumerate() {
                let theta = std::f64::consts::PI * (k as f64 + 0.5) / n as f64;
                let y = y0 + 0.5 * (1.0 - theta.cos());
                *v = adhesion_factor_elastic(y.exp())?;
            }
            let mut coefficients = [0.0; CHEB_DEGREE];
            for (j, c) in coefficients.iter_mut().enumerate() {
                let sum: f64 = values
                    .iter()
                    .enumerate()
                    .map(|(k, v)| {
                        v * (std::f64::consts::PI * j as f64 * (k as f64 + 0.5) / n as f64).cos()
                    })
                    .sum();
                *c = 2.0 / n as f64 * sum;
            }
            coefficients[0] *= 0.5;
            segments.push(coefficients);
        }
        Ok(AdhesionTable {
            y_min: TABLE_Y_MIN,
            segments,
        })
    }

    /// `f_el(e^y)` if `y` lies inside the table.
    fn eval(&self, y: f64) -> Option<f64> {
        let position = y - self.y_min;
        if position.is_nan() || position < 0.0 || position > self.segments.len() as f64 {
            return None;
        }
        let index = (position.floor() as usize).min(self.segments.len() - 1);
        // The nodes were placed at y = y0 + (1 − cos θ)/2, i.e. at Chebyshev abscissa
        // cos θ = 1 − 2(y − y0); evaluate Σ c_j T_j at that abscissa by Clenshaw.
        let xr = 1.0 - 2.0 * (position - index as f64);
        let c = &self.segments[index];
        let (mut b1, mut b2) = (0.0, 0.0);
        for &cj in c.iter().skip(1).rev() {
            let b0 = 2.0 * xr * b1 - b2 + cj;
            b2 = b1;
            b1 = b0;
        }
        Some(xr * b1 - b2 + c[0])
    }
}

static ADHESION_TABLE: std::sync::OnceLock<Option<AdhesionTable>> = std::sync::OnceLock::new();

/// Fast `f_el(λ)` for the GW integrals: the once-built Chebyshev table inside
/// `λ ∈ [e^-19, e^19]`, the linear limit `1 + (f_el(λ_min) − 1)·λ/λ_min` below it, direct
/// quadrature above it (and if the table could not be built).
pub fn adhesion_factor_elastic_fast(lambda: f64) -> Result<f64, ContactError> {
    if !lambda.is_finite() || lambda < 0.0 {
        return adhesion_factor_elastic(lambda);
    }
    let table = ADHESION_TABLE.get_or_init(|| AdhesionTable::build().ok());
    let Some(table) = table else {
        return adhesion_factor_elastic(lambda);
    };
    let y_min_lambda = TABLE_Y_MIN.exp();
    if lambda < y_min_lambda {
        let edge = table.eval(TABLE_Y_MIN).unwrap_or(1.0);
        return Ok(1.0 + (edge - 1.0) * lambda / y_min_lambda);
    }
    match table.eval(lambda.ln()) {
        Some(v) => Ok(v),
        None => adhesion_factor_elastic(lambda),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adhesion_factor_matches_spec_values() {
        // docs/contact.md values (5 significant digits); the 16-digit values were produced
        // independently with scipy.integrate.quad on the same integral (x = 1 + u²,
        // epsrel 1e-13, split at λ^-1/3 and λ^-1/4) and agree with the spec's digits.
        let cases = [
            (0.1, 1.020_621_731_420_317_6),
            (1.0, 1.180_224_534_224_218_6),
            (3.0, 1.399_745_861_596_586_8),
            (10.0, 1.831_128_123_597_837_4),
            (100.0, 3.560_264_913_682_545_3),
            (1000.0, 7.485_045_964_026_879),
        ];
        for (lambda, want) in cases {
            let got = adhesion_factor_elastic(lambda).unwrap();
            assert!(
                (got / want - 1.0).abs() < 1e-10,
                "f_el({lambda}) = {got}, want {want}"
            );
        }
        assert_eq!(adhesion_factor_elastic(0.0).unwrap(), 1.0);
        // Continuity at λ → 0 (f_el(0) = 1, docs/contact.md): f_el(1e-6) − 1 is O(1e-6).
        let small = adhesion_factor_elastic(1e-6).unwrap();
        assert!((small - 1.0).abs() < 1e-5, "{small}");
        // Large-λ asymptote 0.739·λ^{1/3} (docs/contact.md; ratio → 1 slowly).
        let big = adhesion_factor_elastic(1e7).unwrap();
        assert!(
            (big / (0.739 * 1e7f64.powf(1.0 / 3.0)) - 1.0).abs() < 0.03,
            "{big}"
        );
        assert!(adhesion_factor_elastic(f64::NAN).is_err());
        assert!(adhesion_factor_elastic(-1.0).is_err());
    }

    #[test]
    fn tabulated_adhesion_factor_matches_direct_quadrature() {
        // Table vs direct quadrature at log-spaced λ off the nodes, across the table, at its
        // edges and outside it.
        let mut worst = 0.0f64;
        for i in 0..=400 {
            let lambda = 10f64.powf(-9.0 + 18.0 * (i as f64 + 0.37) / 400.0);
            let fast = adhesion_factor_elastic_fast(lambda).unwrap();
            let direct = adhesion_factor_elastic(lambda).unwrap();
            worst = worst.max((fast / direct - 1.0).abs());
        }
        assert!(worst < 1e-11, "worst relative error {worst:e}");
        for lambda in [0.0, 1e-12, (-19f64).exp(), 19f64.exp(), 1e9] {
            let fast = adhesion_factor_elastic_fast(lambda).unwrap();
            let direct = adhesion_factor_elastic(lambda).unwrap();
            assert!(
                (fast / direct - 1.0).abs() < 1e-11,
                "λ = {lambda}: {fast} vs {direct}"
            );
        }
        assert!(adhesion_factor_elastic_fast(f64::NAN).is_err());
    }

    #[test]
    fn hertz_gap_series_matches_closed_form_at_switch() {
        // Series (just below the switch) vs closed form (at it): at w = 0.05 the closed form
        // loses only ~3 digits to cancellation (ε/w² ≈ 1e-13), so both must agree to 1e-9.
        let w: f64 = 0.05;
        let closed = w - (1.0 - w * w) * w.atan();
        assert!((hertz_gap(0.049_999_999_999) / closed - 1.0).abs() < 1e-9);
    }

    #[test]
    fn ke_fit_jumps_at_regime_boundaries_are_the_published_ones() {
        // KE 2002 (eq. A.3): the fits jump by ~3 % at ω* = 1, ~2 % at 6, up to 12 % at 110 (P). The
        // expected jumps are recomputed here from the published coefficients by hand:
        // 1.03·1 / 1 = 1.03; 1.40·6^1.263 / (1.03·6^1.425) = 1.0168;
        // (3/K)·110 / (1.40·110^1.263) = 1.1185 with K = 0.5565 (python one-liner).
        let k = 0.454 + 0.41 * 0.25;
        let jump = |b: f64, lo: KeRegime, hi: KeRegime| {
            ke_load_ratio_in(hi, b, k) / ke_load_ratio_in(lo, b, k)
        };
        let j1 = jump(1.0, KeRegime::Elastic, KeRegime::ElasticPlasticI);
        let j6 = jump(6.0, KeRegime::ElasticPlasticI, KeRegime::ElasticPlasticII);
        let j110 = jump(110.0, KeRegime::ElasticPlasticII, KeRegime::FullyPlastic);
        assert!((j1 - 1.03).abs() < 1e-12);
        assert!((j6 - 1.40 * 6f64.powf(1.263) / (1.03 * 6f64.powf(1.425))).abs() < 1e-12);
        assert!((j6 - 1.0168).abs() < 5e-4, "{j6}");
        assert!((j110 - 1.1185).abs() < 5e-4, "{j110}");
        // Area: 0.93 at 1 (−7 %), 0.94·6^1.146/(0.93·6^1.136) = 1.0290, 2·110/(0.94·110^1.146)
        // = 1.0712 (same arithmetic).
        let a =
            |b: f64, lo: KeRegime, hi: KeRegime| ke_area_ratio_in(hi, b) / ke_area_ratio_in(lo, b);
        assert!((a(1.0, KeRegime::Elastic, KeRegime::ElasticPlasticI) - 0.93).abs() < 1e-12);
        assert!(
            (a(6.0, KeRegime::ElasticPlasticI, KeRegime::ElasticPlasticII) - 1.0290).abs() < 5e-4
        );
        assert!(
            (a(110.0, KeRegime::ElasticPlasticII, KeRegime::FullyPlastic) - 1.0712).abs() < 5e-4
        );
        // Boundaries belong to the lower regime; values just above are within the jumps.
        assert_eq!(KeRegime::of(1.0), KeRegime::Elastic);
        assert_eq!(KeRegime::of(6.0), KeRegime::ElasticPlasticI);
        assert_eq!(KeRegime::of(110.0), KeRegime::ElasticPlasticII);
        assert_eq!(KeRegime::of(110.000_001), KeRegime::FullyPlastic);
        for b in [1.0, 6.0, 110.0] {
            let below = ke_load_ratio(b * (1.0 - 1e-12), k);
            let above = ke_load_ratio(b * (1.0 + 1e-12), k);
            assert!(below.is_finite() && above.is_finite());
            assert!(above / below > 0.99 && above / below < 1.13);
        }
    }

    #[test]
    fn ke_mean_pressure_reproduces_published_fits_for_nu_0_3() {
        // Consistency check (eq. A.4): (P/P_c)/(A/A_c)·(2/3)·K·H/Y with H = 2.8·Y and ν = 0.3
        // reproduces KE 2002's p/Y ≈ 1.19·ω*^0.289 (1–6) and 1.61·ω*^0.117 (6–110).
        let k = 0.454 + 0.41 * 0.3;
        let mean_pressure = |w: f64| ke_load_ratio(w, k) / ke_area_ratio(w) * 2.0 / 3.0 * k * 2.8;
        for w in [1.5, 3.0, 5.9] {
            let fit = 1.19 * f64::powf(w, 0.289);
            assert!((mean_pressure(w) / fit - 1.0).abs() < 0.005, "ω* = {w}");
        }
        for w in [7.0, 30.0, 100.0] {
            let fit = 1.61 * f64::powf(w, 0.117);
            assert!((mean_pressure(w) / fit - 1.0).abs() < 0.005, "ω* = {w}");
        }
    }

    #[test]
    fn seed_power_friction_is_elastic_only() {
        assert_eq!(seed_power_friction_ratio(0.0), 0.0);
        assert_eq!(seed_power_friction_ratio(1.0), 0.4155);
        assert_eq!(seed_power_friction_ratio(1.5), 0.0);
    }
}
