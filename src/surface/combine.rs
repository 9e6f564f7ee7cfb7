//! Combining two surfaces into the equivalent rough surface (Table 2.2; docs/surfaces.md).
//!
//! σ always adds in quadrature. `SumSurface` adds the spectral moments of the two independent
//! surfaces (McCool 1986) and derives η, R, α, β from Nayak's relations; `HarmonicR` is the
//! common shortcut 1/R = 1/R1 + 1/R2, η = min; `Explicit` takes the user's numbers.
use super::roughness::{bandwidth_alpha, nayak_estimate};
use super::{Result, SurfaceError};
use std::f64::consts::PI;

/// What the contact model needs of one surface; `m2`/`m4` when measured, else inverted from
/// (σ, R, η) through Nayak's relations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceStats {
    pub sigma: f64,
    pub r: f64,
    pub eta: f64,
    pub m2: Option<f64>,
    pub m4: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CombineRule {
    SumSurface,
    HarmonicR,
    Explicit { sigma: f64, r: f64, eta: f64 },
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InterfaceStats {
    pub sigma: f64,
    pub r: f64,
    pub eta: f64,
    pub beta: f64,
    pub m2: f64,
    pub m4: f64,
    pub alpha: f64,
    pub rule: CombineRule,
}

impl std::fmt::Display for CombineRule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CombineRule::SumSurface => write!(f, "sum_surface"),
            CombineRule::HarmonicR => write!(f, "harmonic_R"),
            CombineRule::Explicit { .. } => write!(f, "explicit"),
        }
    }
}

/// Nayak inversion: `m4 = π(0.375/R)²` (from R = 0.375√(π/m4)).
pub fn m4_from_radius(r: f64) -> f64 {
    PI * (0.375 / r).powi(2)
}

/// Nayak inversion: `m2 = m4/(6π√3·η)` (from η = m4/(6π√3·m2)).
pub fn m2_from_density(m4: f64, eta: f64) -> f64 {
    m4 / (6.0 * PI * 3f64.sqrt() * eta)
}

fn check_positive(name: &str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SurfaceError::Parameter {
            name: name.into(),
            value: format!("{value:e}"),
            expected: "a finite positive number".into(),
        })
    }
}

impl SurfaceStats {
    fn validate(&self, which: &str) -> Result<()> {
        check_positive(&format!("{which}.sigma"), self.sigma)?;
        check_positive(&format!("{which}.r"), self.r)?;
        check_positive(&format!("{which}.eta"), self.eta)?;
        if let Some(m2) = self.m2 {
            check_positive(&format!("{which}.m2"), m2)?;
        }
        if let Some(m4) = self.m4 {
            check_positive(&format!("{which}.m4"), m4)?;
        }
        Ok(())
    }

    /// (m2, m4): measured where given, else inverted from (R, η). m4 is inverted first because
    /// the inversion of m2 needs it.
    pub fn moments(&self) -> (f64, f64) {
        let m4 = self.m4.unwrap_or_else(|| m4_from_radius(self.r));
        let m2 = self.m2.unwrap_or_else(|| m2_from_density(m4, self.eta));
        (m2, m4)
    }
}

/// Interface numbers from (σ, R, η) alone: the moments are the Nayak inversion, so η and R
/// come back unchanged and α, β follow.
fn from_sigma_r_eta(sigma: f64, r: f64, eta: f64, rule: CombineRule) -> InterfaceStats {
    let m4 = m4_from_radius(r);
    let m2 = m2_from_density(m4, eta);
    InterfaceStats {
        sigma,
        r,
        eta,
        beta: sigma * r * eta,
        m2,
        m4,
        alpha: bandwidth_alpha(sigma * sigma, m2, m4),
        rule,
    }
}

pub fn combine(a: &SurfaceStats, b: &SurfaceStats, rule: CombineRule) -> Result<InterfaceStats> {
    match rule {
        CombineRule::Explicit { sigma, r, eta } => {
            // The two surfaces are not used; only the given numbers need to make sense.
            check_positive("explicit.sigma", sigma)?;
            check_positive("explicit.r", r)?;
            check_positive("explicit.eta", eta)?;
            Ok(from_sigma_r_eta(sigma, r, eta, rule))
        }
        CombineRule::SumSurface => {
            a.validate("surface_1")?;
            b.validate("surface_2")?;
            let sigma = a.sigma.hypot(b.sigma);
            let (m2a, m4a) = a.moments();
            let (m2b, m4b) = b.moments();
            let (m2, m4) = (m2a + m2b, m4a + m4b);
            let nayak = nayak_estimate(sigma, m2, m4);
            Ok(InterfaceStats {
                sigma,
                r: nayak.r,
                eta: nayak.eta,
                beta: nayak.beta,
                m2,
                m4,
                alpha: bandwidth_alpha(sigma * sigma, m2, m4),
                rule,
            })
        }
        CombineRule::HarmonicR => {
            a.validate("surface_1")?;
            b.validate("surface_2")?;
            let sigma = a.sigma.hypot(b.sigma);
            let r = 1.0 / (1.0 / a.r + 1.0 / b.r);
            Ok(from_sigma_r_eta(sigma, r, a.eta.min(b.eta), rule))
        }
    }
}

/// One surface's measured summit heights (the discrete summits of the surfaces stage): the
/// surface's σ, its summit density η and the mean and standard deviation of the summit
/// heights above its mean plane (SI). For a combination, `eta` is the mixture's summit count
/// `η1 + η2` (its weights), not the contact model's η.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SummitHeights {
    pub sigma: f64,
    pub eta: f64,
    pub mean: f64,
    pub std: f64,
}

impl SummitHeights {
    fn validate(&self, which: &str) -> Result<()> {
        check_positive(&format!("{which}.sigma"), self.sigma)?;
        check_positive(&format!("{which}.eta"), self.eta)?;
        check_positive(&format!("{which}.summit_std"), self.std)?;
        if !self.mean.is_finite() {
            return Err(SurfaceError::Parameter {
                name: format!("{which}.summit_mean"),
                value: format!("{:e}", self.mean),
                expected: "a finite number".into(),
            });
        }
        Ok(())
    }

    /// `σ_s/σ`.
    pub fn std_ratio(&self) -> f64 {
        self.std / self.sigma
    }

    /// `y_s/σ`.
    pub fn mean_ratio(&self) -> f64 {
        self.mean / self.sigma
    }
}

/// The summit heights of the sum surface `z1 + z2` of two independent surfaces, from each
/// surface's measured summits (docs/model-form.md, "Summit heights").
///
/// A summit of the sum surface is taken to be a summit of one surface standing on the other
/// surface at a point unrelated to it: with probability `w_i = η_i/(η1 + η2)` its height is
/// `S_i + Z_j`, `S_i` surface i's summit height (mean `m_i`, std `s_i`) and `Z_j` surface j's
/// height (mean 0, std `σ_j`). The mixture has mean `Σ w_i m_i` and variance
/// `Σ w_i (s_i² + σ_j² + (m_i − m̄)²)`; σ adds in quadrature as for the surface heights. Exact
/// when one surface carries all summits and the other is smooth at their scale; for two
/// comparable surfaces it ignores summits that merge or shift on the other's slope.
pub fn combine_summit_heights(a: &SummitHeights, b: &SummitHeights) -> Result<SummitHeights> {
    a.validate("surface_1")?;
    b.validate("surface_2")?;
    let eta = a.eta + b.eta;
    let (wa, wb) = (a.eta / eta, b.eta / eta);
    let mean = wa * a.mean + wb * b.mean;
    let variance = wa * (a.std.powi(2) + b.sigma.powi(2) + (a.mean - mean).powi(2))
        + wb * (b.std.powi(2) + a.sigma.powi(2) + (b.mean - mean).powi(2));
    Ok(SummitHeights {
        sigma: a.sigma.hypot(b.sigma),
        eta,
        mean,
        std: variance.sqrt(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disk() -> SurfaceStats {
        SurfaceStats {
            sigma: 0.34e-9,
            r: 0.43e-6,
            eta: 220e12,
            m2: None,
            m4: None,
        }
    }

    fn tfc() -> SurfaceStats {
        SurfaceStats {
            sigma: 0.80e-9,
            r: 5.40937e-6,
            eta: 1.77e12,
            m2: None,
            m4: None,
        }
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a / b - 1.0).abs()
    }

    #[test]
    fn sum_surface_reproduces_the_dissertation_interface() {
        let c = combine(&disk(), &tfc(), CombineRule::SumSurface).unwrap();
        assert!(rel(c.eta, 124.000e12) < 1e-4, "eta = {}", c.eta * 1e-12);
        assert!(rel(c.r, 0.42865e-6) < 2e-5, "R = {}", c.r * 1e6);
        assert!(rel(c.sigma, 0.8693e-9) < 1e-4, "sigma = {}", c.sigma * 1e9);
        assert!((c.beta - 0.046).abs() < 5e-4, "beta = {}", c.beta);
        // Nayak's identity holds for the combined numbers.
        let k = 0.375 / (6.0 * (3.0 * PI).sqrt());
        assert!(rel(c.beta, k * c.alpha.sqrt()) < 1e-12);
        assert_eq!(c.rule, CombineRule::SumSurface);
    }

    #[test]
    fn summit_heights_of_a_smooth_partner_add_its_variance_only() {
        // Surface b has (almost) no summits: the sum's summits are a's, shifted by b's heights
        // (mean unchanged, variance + σ_b²); σ adds in quadrature.
        let a = SummitHeights {
            sigma: 0.5e-9,
            eta: 300e12,
            mean: 0.6e-9,
            std: 0.4e-9,
        };
        let b = SummitHeights {
            sigma: 0.3e-9,
            eta: 1e-3,
            mean: 0.2e-9,
            std: 0.25e-9,
        };
        let c = combine_summit_heights(&a, &b).unwrap();
        assert!(rel(c.mean, 0.6e-9) < 1e-12);
        assert!(rel(c.std, 0.5e-9) < 1e-12); // √(0.4² + 0.3²)
        assert!(rel(c.sigma, 0.3e-9f64.hypot(0.5e-9)) < 1e-15);
        // Symmetric in the two surfaces; equal surfaces: mean kept, variance s² + σ².
        let c2 = combine_summit_heights(&b, &a).unwrap();
        assert!(rel(c.std, c2.std) < 1e-12 && rel(c.mean, c2.mean) < 1e-12);
        let e = combine_summit_heights(&a, &a).unwrap();
        assert!(rel(e.mean, a.mean) < 1e-15);
        assert!(rel(e.std, (0.4e-9f64.powi(2) + 0.5e-9f64.powi(2)).sqrt()) < 1e-12);
        let bad = SummitHeights { std: 0.0, ..a };
        assert!(combine_summit_heights(&a, &bad).is_err());
    }

    #[test]
    fn inversion_round_trips_a_single_surface() {
        let (m2, m4) = disk().moments();
        let n = nayak_estimate(1.0, m2, m4);
        assert!(rel(n.r, 0.43e-6) < 1e-14);
        assert!(rel(n.eta, 220e12) < 1e-14);
    }

    #[test]
    fn measured_moments_are_used_when_given() {
        let a = SurfaceStats {
            m2: Some(1e-3),
            m4: Some(2e13),
            ..disk()
        };
        let b = SurfaceStats {
            m2: Some(3e-3),
            m4: Some(6e13),
            ..tfc()
        };
        let c = combine(&a, &b, CombineRule::SumSurface).unwrap();
        assert!(rel(c.m2, 4e-3) < 1e-15 && rel(c.m4, 8e13) < 1e-15);
    }

    #[test]
    fn harmonic_and_explicit_rules() {
        let h = combine(&disk(), &tfc(), CombineRule::HarmonicR).unwrap();
        // §2.7: the harmonic rule gives R = 0.398 µm for this R_TFC, η = min = 1.77 µm⁻².
        assert!((h.r * 1e6 - 0.398).abs() < 5e-4, "{}", h.r * 1e6);
        assert_eq!(h.eta, 1.77e12);
        assert!(rel(h.beta, h.sigma * h.r * h.eta) < 1e-15);

        let rule = CombineRule::Explicit {
            sigma: 0.87e-9,
            r: 0.43e-6,
            eta: 124e12,
        };
        let e = combine(&disk(), &tfc(), rule).unwrap();
        assert_eq!((e.sigma, e.r, e.eta), (0.87e-9, 0.43e-6, 124e12));
        // §2.6: combined (0.87 nm, 0.43 µm, 124 µm⁻²) ⇒ β = 0.0464.
        assert!((e.beta - 0.0464).abs() < 5e-5, "{}", e.beta);
        assert_eq!(rule.to_string(), "explicit");
    }

    #[test]
    fn non_positive_inputs_are_parameter_errors() {
        let bad = SurfaceStats { eta: 0.0, ..disk() };
        assert!(matches!(
            combine(&bad, &tfc(), CombineRule::SumSurface),
            Err(SurfaceError::Parameter { .. })
        ));
        let bad = SurfaceStats {
            m4: Some(f64::NAN),
            ..disk()
        };
        assert!(combine(&tfc(), &bad, CombineRule::HarmonicR).is_err());
        let rule = CombineRule::Explicit {
            sigma: -1.0,
            r: 1.0,
            eta: 1.0,
        };
        assert!(combine(&disk(), &tfc(), rule).is_err());
    }
}
