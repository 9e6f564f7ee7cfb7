//! High-shear extrapolation of the FWM measurement (dissertation (3.36)–(3.49),
//! (A.11)).
//!
//! The fibre-wobbling method measures a lubricant whose apparent viscosity saturates at `μ0`
//! once the gap reaches the bonded-layer limit `κ0`. At HDI shear rates (10¹⁰–10¹¹ 1/s) the
//! film is taken as solid-like and damping-free with the viscosity held at `μ0`; the FWM
//! formulas for the fully submerged probe (Kapitza load, Goldman–Cox–Brenner drag), rewritten
//! in the apparent shear rate `γ̇ = U0/d0`, give the force-versus-shear-rate laws whose
//! derivatives with respect to the gap at the application speed are the lubricant
//! stiffnesses.

use std::f64::consts::{LN_10, PI};

use super::{require_non_negative, require_positive};
use crate::contact::ContactError;

/// The FWM experiment the extrapolation is calibrated on (§3.1.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FwmExperiment {
    /// Limiting apparent viscosity `μ0 ≡ η0` reached at `d0 = κ0` [Pa·s].
    pub limiting_viscosity: f64,
    /// Shearing speed of the probe `U0` [m/s].
    pub speed: f64,
    /// Probe (fibre tip) radius `R0` [m].
    pub probe_radius: f64,
    /// Minimum liquid gap of the experiment `κ0` [m]; cancels from every extrapolated law
    /// when `m = 1/2` (eqs. 3.40–3.43), but fixes `γ̇0`, `P0`, `Q0`.
    pub min_liquid_gap: f64,
}

impl FwmExperiment {
    /// Validated constructor: every field finite and > 0.
    pub fn new(
        limiting_viscosity: f64,
        speed: f64,
        probe_radius: f64,
        min_liquid_gap: f64,
    ) -> Result<Self, ContactError> {
        require_positive("mu0", limiting_viscosity)?;
        require_positive("U0", speed)?;
        require_positive("R0", probe_radius)?;
        require_positive("kappa0", min_liquid_gap)?;
        if min_liquid_gap >= probe_radius {
            return Err(ContactError::parameter(
                "kappa0",
                min_liquid_gap,
                "must be smaller than the probe radius R0 (ln(R0/kappa0) > 0)",
            ));
        }
        Ok(Self {
            limiting_viscosity,
            speed,
            probe_radius,
            min_liquid_gap,
        })
    }

    /// The published FWM measurement the dissertation extrapolates (Fukuzawa et al., Fomblin
    /// Z03 on a magnetic disk): `μ0 = 0.31 Pa·s` [seed §3.1 viscosity model],
    /// `U0 = 200 µm/s` and `R0 = 102 µm` [seed §3.2 "Stiffness of MTL layers"],
    /// `κ0 = 1 nm` [seed §3.1.1].
    pub fn fukuzawa_z03() -> Self {
        Self {
            limiting_viscosity: 0.31,
            speed: 200e-6,
            probe_radius: 102e-6,
            min_liquid_gap: 1e-9,
        }
    }

    /// Same experiment with a different limiting viscosity (the lubricant cases of §4.6 change
    /// `μ0` by ±50 %).
    pub fn with_limiting_viscosity(self, limiting_viscosity: f64) -> Result<Self, ContactError> {
        Self::new(
            limiting_viscosity,
            self.speed,
            self.probe_radius,
            self.min_liquid_gap,
        )
    }

    /// Critical (maximum) experimental shear rate `γ̇0 = U0/κ0` [1/s] (2×10⁵ 1/s for FWM).
    pub fn critical_shear_rate(&self) -> f64 {
        self.speed / self.min_liquid_gap
    }

    /// Lubricant load at apparent shear rate `γ̇` (3.36):
    /// `P_lube = (6π/5)·μ0·R0·√(2·R0·U0·γ̇)` — the Kapitza load with `d0 = U0/γ̇`.
    /// 0 for `γ̇ ≤ 0` (no shearing).
    pub fn normal_force_at_shear_rate(&self, shear_rate: f64) -> f64 {
        if shear_rate.is_nan() || shear_rate <= 0.0 {
            return 0.0;
        }
        6.0 * PI / 5.0
            * self.limiting_viscosity
            * self.probe_radius
            * (2.0 * self.probe_radius * self.speed * shear_rate).sqrt()
    }

    /// Lubricant friction at apparent shear rate `γ̇` (3.37):
    /// `Q_lube = (16π/5)·μ0·U0·R0·ln(R0·γ̇/U0)` — the leading Goldman–Cox–Brenner term with
    /// `d0 = U0/γ̇`. Clamped at 0 where the logarithm turns negative (`d0 ≥ R0`, outside the
    /// lubrication regime).
    pub fn shear_force_at_shear_rate(&self, shear_rate: f64) -> f64 {
        if shear_rate.is_nan() || shear_rate <= 0.0 {
            return 0.0;
        }
        let log = (self.probe_radius * shear_rate / self.speed).ln();
        (16.0 * PI / 5.0 * self.limiting_viscosity * self.speed * self.probe_radius * log).max(0.0)
    }

    /// `P0 = P_lube(γ̇0) = (6π/5)·μ0·U0·√(2R0³/κ0)` (3.38 = A.11); 10.77 µN for FWM.
    pub fn p0(&self) -> f64 {
        self.normal_force_at_shear_rate(self.critical_shear_rate())
    }

    /// `Q0 = (16π/5)·μ0·U0·R0·ln(R0/κ0)` (3.39); 0.733 µN for FWM (seed 0.73 µN).
    pub fn q0(&self) -> f64 {
        self.shear_force_at_shear_rate(self.critical_shear_rate())
    }

    /// The dissertation's fits (3.40)–(3.43): `m` and `n` from two points six decades apart,
    /// `γ̇0` and `10⁶·γ̇0` (the dissertation fits "over the HDI range"). Because (3.36) is a
    /// pure power law and (3.37) a pure logarithm, the two-point fit is exact:
    /// `m = 1/2`, `n = (16π/5)·μ0·U0·R0·ln 10` (eqs. 3.40–3.43).
    pub fn high_shear_fit(&self) -> HighShearFit {
        let g1 = self.critical_shear_rate();
        let g2 = 1e6 * g1;
        let (p1, p2) = (
            self.normal_force_at_shear_rate(g1),
            self.normal_force_at_shear_rate(g2),
        );
        let (q1, q2) = (
            self.shear_force_at_shear_rate(g1),
            self.shear_force_at_shear_rate(g2),
        );
        HighShearFit {
            p0: p1,
            q0: q1,
            normal_exponent: (p2 / p1).ln() / (g2 / g1).ln(),
            shear_slope_per_decade: (q2 - q1) / (g2 / g1).log10(),
            critical_shear_rate: g1,
        }
    }

    /// Lowest application speed at which a liquid gap `kappa` still shears at `γ̇ ≥ γ̇0`:
    /// `U = γ̇0·κ` (60 µm/s for κ = 0.3 nm, seed). Below it the FWM range is not exceeded.
    pub fn critical_speed(&self, kappa: f64) -> f64 {
        self.critical_shear_rate() * kappa
    }
}

/// The extrapolated lubricant laws (3.40), (3.41) and their stiffnesses (3.44)–(3.47).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HighShearFit {
    /// `P0`: lubricant load at `γ̇0` [N].
    pub p0: f64,
    /// `Q0`: lubricant friction at `γ̇0` [N].
    pub q0: f64,
    /// `m` (`m_P`): power-law exponent of `P_lube(γ̇)` [–].
    pub normal_exponent: f64,
    /// `n` (`n_Q`): increase of `Q_lube` per decade of shear rate [N].
    pub shear_slope_per_decade: f64,
    /// `γ̇0` [1/s].
    pub critical_shear_rate: f64,
}

impl HighShearFit {
    /// Validated constructor for user-supplied fits (`P0, γ̇0, m > 0`; `Q0, n ≥ 0`).
    pub fn new(
        p0: f64,
        q0: f64,
        normal_exponent: f64,
        shear_slope_per_decade: f64,
        critical_shear_rate: f64,
    ) -> Result<Self, ContactError> {
        require_positive("P0", p0)?;
        require_non_negative("Q0", q0)?;
        require_positive("m", normal_exponent)?;
        require_non_negative("n", shear_slope_per_decade)?;
        require_positive("gamma_dot0", critical_shear_rate)?;
        Ok(Self {
            p0,
            q0,
            normal_exponent,
            shear_slope_per_decade,
            critical_shear_rate,
        })
    }

    /// `P_lube = P0·(γ̇/γ̇0)^m` (3.40); 0 for `γ̇ ≤ 0`.
    pub fn normal_force(&self, shear_rate: f64) -> f64 {
        if shear_rate.is_nan() || shear_rate <= 0.0 {
            return 0.0;
        }
        self.p0 * (shear_rate / self.critical_shear_rate).powf(self.normal_exponent)
    }

    /// `Q_lube = Q0 + n·log₁₀(γ̇/γ̇0)` (3.41), clamped at 0 (the log law is a fit for
    /// `γ̇ ≥ γ̇0`; far below it would turn negative).
    pub fn shear_force(&self, shear_rate: f64) -> f64 {
        if shear_rate.is_nan() || shear_rate <= 0.0 {
            return 0.0;
        }
        (self.q0 + self.shear_slope_per_decade * (shear_rate / self.critical_shear_rate).log10())
            .max(0.0)
    }

    /// `C_P = P0·(U/γ̇0)^m` [N·m^m]: the load law in the liquid gap at application speed `U`,
    /// `P_lube = C_P·d0^{−m}`.
    pub fn normal_force_coefficient(&self, speed: f64) -> f64 {
        if speed.is_nan() || speed <= 0.0 {
            return 0.0;
        }
        self.p0 * (speed / self.critical_shear_rate).powf(self.normal_exponent)
    }

    /// Normal lubricant stiffness `k_P = −∂P_lube/∂d0 = m·P0·(U/γ̇0)^m·d0^{−(m+1)}` (3.44)
    /// at liquid gap `d0` and application speed `U`. Requires `d0 > 0`; 0 for `U ≤ 0`.
    pub fn normal_stiffness(&self, liquid_gap: f64, speed: f64) -> Result<f64, ContactError> {
        require_positive("d0", liquid_gap)?;
        let m = self.normal_exponent;
        Ok(m * self.normal_force_coefficient(speed) * liquid_gap.powf(-(m + 1.0)))
    }

    /// Shear lubricant stiffness `k_Q = −∂Q_lube/∂d0 = n/(d0·ln 10)` (3.45); independent of
    /// `U` (set to 0 for `U ≤ 0`: no shearing, no friction). Requires `d0 > 0`.
    pub fn shear_stiffness(&self, liquid_gap: f64, speed: f64) -> Result<f64, ContactError> {
        require_positive("d0", liquid_gap)?;
        if speed.is_nan() || speed <= 0.0 {
            return Ok(0.0);
        }
        Ok(self.shear_slope_per_decade / (liquid_gap * LN_10))
    }

    /// `k_P = m·P0·γ̇^{m+1}/(U·γ̇0^m)` (3.46): the same stiffness in the apparent shear rate
    /// `γ̇ = U/d0`. Requires `U > 0`, `γ̇ > 0`.
    pub fn normal_stiffness_at_shear_rate(
        &self,
        shear_rate: f64,
        speed: f64,
    ) -> Result<f64, ContactError> {
        require_positive("gamma_dot", shear_rate)?;
        require_positive("U", speed)?;
        let m = self.normal_exponent;
        Ok(m * self.p0 * shear_rate.powf(m + 1.0) / (speed * self.critical_shear_rate.powf(m)))
    }

    /// `k_Q = n·γ̇/(U·ln 10)` (3.47). Requires `U > 0`, `γ̇ > 0`.
    pub fn shear_stiffness_at_shear_rate(
        &self,
        shear_rate: f64,
        speed: f64,
    ) -> Result<f64, ContactError> {
        require_positive("gamma_dot", shear_rate)?;
        require_positive("U", speed)?;
        Ok(self.shear_slope_per_decade * shear_rate / (speed * LN_10))
    }
}

/// Apparent shear-rate range in a film of total thickness `t` with minimum liquid gap `κ` at
/// sliding speed `U` (3.48), (3.49): `(U/(t − κ), U/κ)`. Requires `κ > 0`, `t > 2κ`, `U ≥ 0`.
pub fn shear_rate_range(
    speed: f64,
    film_thickness: f64,
    kappa: f64,
) -> Result<(f64, f64), ContactError> {
    require_non_negative("U", speed)?;
    require_positive("kappa", kappa)?;
    require_positive("t", film_thickness)?;
    if film_thickness <= 2.0 * kappa {
        return Err(ContactError::parameter(
            "t",
            film_thickness,
            "must exceed 2*kappa (no mobile lubricant otherwise)",
        ));
    }
    Ok((speed / (film_thickness - kappa), speed / kappa))
}
