//! Lubricant stiffness and force between rough surfaces versus mean-plane separation `h`
//! (dissertation (3.54)–(3.60), App. A.2).
//!
//! With the liquid gap `d0 = h − 3σ − κ` and `s = h − 3σ`:
//! - `h ≥ 3σ + t`: no lubricant contact;
//! - `3σ + 2κ ≤ h < 3σ + t`: hydrodynamic, `k_P = m·C_P·d0^{−(m+1)}`, `k_Q = n/(d0·ln 10)`
//!   with `C_P = P0·(U/γ̇0)^m` (A.9), (A.10);
//! - `3σ ≤ h < 3σ + 2κ`: transition, total stiffness a straight line from the solid stiffness
//!   at `3σ` to the maximum lubricant stiffness at `3σ + 2κ` (A.14), (A.15);
//! - `h < 3σ`: solid contact; the lubricant stiffness is zero and its force is held.
//!
//! The lubricant stiffness is the single-probe law calibrated on the FWM probe, applied to
//! the whole interface without asperity scaling (docs/contact.md). Forces are the
//! integrals of the total stiffness from the lubricant surface inward minus the solid force
//! (decision 2), so they are continuous everywhere and zero outside the film. The solid
//! contribution (`P_solid`, `Q_solid`, `k_c`, `k_fr`, untruncated GW integrals) comes from the
//! caller through [`SolidContact`], so this module composes with `contact::isbl` without
//! depending on it.

use std::f64::consts::LN_10;

use super::extrapolation::{FwmExperiment, HighShearFit};
use super::{require_non_negative, require_positive};
use crate::contact::ContactError;

/// Forces [N] and stiffnesses `−dF/dh` [N/m] at one separation.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ForceStiffness {
    /// Normal (bearing) force `P`.
    pub normal: f64,
    /// Friction force `Q`.
    pub friction: f64,
    /// Normal stiffness `−dP/dh` (`k_c` for the solid, `k_P` for the lubricant).
    pub normal_stiffness: f64,
    /// Friction stiffness `−dQ/dh` (`k_fr` for the solid, `k_Q` for the lubricant).
    pub friction_stiffness: f64,
}

impl ForceStiffness {
    fn plus(self, other: Self) -> Self {
        Self {
            normal: self.normal + other.normal,
            friction: self.friction + other.friction,
            normal_stiffness: self.normal_stiffness + other.normal_stiffness,
            friction_stiffness: self.friction_stiffness + other.friction_stiffness,
        }
    }
}

/// What the caller's solid model returns: `P_solid(h)`, `Q_solid(h)`, `k_c(h)`, `k_fr(h)`.
pub type SolidResponse = ForceStiffness;

/// The solid (ISBL) contribution at mean-plane separation `h`. Must be evaluated with the
/// untruncated GW integrals (non-zero above `3σ`) and tend to zero as `h → ∞`, because the
/// lubricant forces are defined as `∫_h^∞ k_total − P_solid(h)`.
///
/// Implemented for closures `Fn(f64) -> SolidResponse`, so the ISBL model can be passed as
/// `|h| isbl_response(&params, h)` without a dependency from this module on `contact::isbl`.
pub trait SolidContact {
    fn response(&self, separation: f64) -> SolidResponse;
}

impl<F: Fn(f64) -> SolidResponse> SolidContact for F {
    fn response(&self, separation: f64) -> SolidResponse {
        self(separation)
    }
}

/// No solid contribution (lubricant alone; also the spec's "no solid" reference values).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NoSolid;

impl SolidContact for NoSolid {
    fn response(&self, _separation: f64) -> SolidResponse {
        SolidResponse::default()
    }
}

/// Film and sliding parameters of the rough interface (Table 3.2 subset used by the
/// lubricant law).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoughFilm {
    /// Combined RMS roughness `σ` [m]; solid contact for `h < 3σ`.
    pub sigma: f64,
    /// Minimum liquid gap `κ` [m] (radius of gyration `r_g` in the dissertation); the
    /// bonded layer of the ISBL model is `T0 = 2κ`.
    pub kappa: f64,
    /// Total average lubricant thickness `t` [m].
    pub film_thickness: f64,
    /// Sliding speed `U` [m/s].
    pub speed: f64,
}

impl RoughFilm {
    /// Requires `σ ≥ 0`, `κ > 0`, `t > 2κ` (a mobile layer exists), `U ≥ 0`.
    pub fn new(
        sigma: f64,
        kappa: f64,
        film_thickness: f64,
        speed: f64,
    ) -> Result<Self, ContactError> {
        require_non_negative("sigma", sigma)?;
        require_positive("kappa", kappa)?;
        require_positive("t", film_thickness)?;
        if film_thickness <= 2.0 * kappa {
            return Err(ContactError::parameter(
                "t",
                film_thickness,
                format!("must exceed 2*kappa = {} (no mobile layer)", 2.0 * kappa),
            ));
        }
        require_non_negative("U", speed)?;
        Ok(Self {
            sigma,
            kappa,
            film_thickness,
            speed,
        })
    }

    /// Table 3.2 [seed]: `σ = 0.82 nm`, `κ = r_g = 0.3 nm`, `t = 1.5 nm`, `U = 30 m/s`.
    pub fn table_3_2() -> Self {
        Self {
            sigma: 0.82e-9,
            kappa: 0.3e-9,
            film_thickness: 1.5e-9,
            speed: 30.0,
        }
    }

    /// Same film at another speed (the §3.2 stiffness example uses 15 m/s [seed]).
    pub fn with_speed(self, speed: f64) -> Result<Self, ContactError> {
        Self::new(self.sigma, self.kappa, self.film_thickness, speed)
    }

    /// Same film with another minimum liquid gap (lubricant case 4).
    pub fn with_kappa(self, kappa: f64) -> Result<Self, ContactError> {
        Self::new(self.sigma, kappa, self.film_thickness, self.speed)
    }
}

/// The four lubricant cases (Fig. 3.22 cases 1–4 = Table 4.4 cases 0–3): `μ0`
/// changed by exactly ±50 % [derived; Table 4.4 prints 0.16 / 0.46], `κ` by +50 %.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LubricantCase {
    /// Case 1 / 0: the published FWM lubricant, `μ0 = 0.31 Pa·s`, `κ = 0.3 nm`.
    Reference,
    /// Case 2 / 1: humidity or temperature lowers the limiting viscosity, `μ0 = 0.155`.
    HumidityTemperature,
    /// Case 3 / 2: more bonding stiffens the film, `μ0 = 0.465`.
    MoreBonding,
    /// Case 4 / 3: larger radius of gyration, `μ0 = 0.465`, `κ = 0.45 nm`.
    LargerGyrationRadius,
}

impl LubricantCase {
    pub const ALL: [LubricantCase; 4] = [
        LubricantCase::Reference,
        LubricantCase::HumidityTemperature,
        LubricantCase::MoreBonding,
        LubricantCase::LargerGyrationRadius,
    ];

    /// `μ0` [Pa·s].
    pub fn limiting_viscosity(self) -> f64 {
        match self {
            LubricantCase::Reference => 0.31,
            LubricantCase::HumidityTemperature => 0.31 * 0.5,
            LubricantCase::MoreBonding | LubricantCase::LargerGyrationRadius => 0.31 * 1.5,
        }
    }

    /// `κ` of the application [m] (the experiment's `κ0` also changes by +50 % in case 4, but
    /// cancels from the extrapolated laws, eqs. 3.40–3.43, so the FWM `κ0` is kept).
    pub fn kappa(self) -> f64 {
        match self {
            LubricantCase::LargerGyrationRadius => 0.45e-9,
            _ => 0.3e-9,
        }
    }

    /// The case on the Table 3.2 film at `U = 30 m/s`, extrapolated from the FWM experiment.
    pub fn model(self) -> Result<RoughMtl, ContactError> {
        let experiment =
            FwmExperiment::fukuzawa_z03().with_limiting_viscosity(self.limiting_viscosity())?;
        let film = RoughFilm::table_3_2().with_kappa(self.kappa())?;
        RoughMtl::from_experiment(film, &experiment)
    }
}

/// Regime of the mean-plane separation `h` (§3.2, App. A.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RoughRegime {
    /// `h ≥ 3σ + t` (also NaN): only the solid tail and adhesion act.
    NoLubricantContact,
    /// `3σ + 2κ ≤ h < 3σ + t`.
    Hydrodynamic,
    /// `3σ ≤ h < 3σ + 2κ`.
    Transition,
    /// `h < 3σ`.
    SolidContact,
}

/// The rough-surface lubricant law with its per-parameter-set constants precomputed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoughMtl {
    film: RoughFilm,
    fit: HighShearFit,
    /// `C_P = P0·(U/γ̇0)^m` [N·m^m].
    normal_coefficient: f64,
    /// `n` in effect (0 when `U = 0`) [N/decade].
    shear_slope: f64,
    /// `k_P,max = m·C_P·κ^{−(m+1)}` [N/m].
    max_normal_stiffness: f64,
    /// `k_Q,max = n/(κ·ln 10)` [N/m] (0 when `U = 0`).
    max_shear_stiffness: f64,
    /// `P_lub(3σ + 2κ) = C_P·[κ^{−m} − (t − κ)^{−m}]` [N].
    normal_at_transition_end: f64,
    /// `Q_lub(3σ + 2κ) = n·log₁₀((t − κ)/κ)` [N].
    friction_at_transition_end: f64,
}

impl RoughMtl {
    /// Builds the law from a fit (3.40), (3.41) on a film. `U = 0` gives a lubricant that
    /// carries nothing (no shearing; docs/contact.md).
    pub fn new(film: RoughFilm, fit: HighShearFit) -> Result<Self, ContactError> {
        let film = RoughFilm::new(film.sigma, film.kappa, film.film_thickness, film.speed)?;
        let fit = HighShearFit::new(
            fit.p0,
            fit.q0,
            fit.normal_exponent,
            fit.shear_slope_per_decade,
            fit.critical_shear_rate,
        )?;
        Ok(Self::build(film, fit))
    }

    /// Precomputes the constants; inputs already validated.
    fn build(film: RoughFilm, fit: HighShearFit) -> Self {
        let (kappa, mobile) = (film.kappa, film.film_thickness - film.kappa);
        let m = fit.normal_exponent;
        let c_p = fit.normal_force_coefficient(film.speed);
        // No shearing, no friction: k_Q does not contain U, so switch it off explicitly.
        let n = if film.speed > 0.0 {
            fit.shear_slope_per_decade
        } else {
            0.0
        };
        Self {
            film,
            fit,
            normal_coefficient: c_p,
            shear_slope: n,
            max_normal_stiffness: m * c_p * kappa.powf(-(m + 1.0)),
            max_shear_stiffness: n / (kappa * LN_10),
            normal_at_transition_end: c_p * (kappa.powf(-m) - mobile.powf(-m)),
            friction_at_transition_end: n * (mobile / kappa).log10(),
        }
    }

    /// The law extrapolated from an FWM experiment (exact fit, eqs. 3.40–3.43).
    pub fn from_experiment(
        film: RoughFilm,
        experiment: &FwmExperiment,
    ) -> Result<Self, ContactError> {
        let experiment = FwmExperiment::new(
            experiment.limiting_viscosity,
            experiment.speed,
            experiment.probe_radius,
            experiment.min_liquid_gap,
        )?;
        Self::new(film, experiment.high_shear_fit())
    }

    /// The dissertation's reference case: Table 3.2 film, FWM fit (Case 1).
    pub fn reference() -> Self {
        Self::build(
            RoughFilm::table_3_2(),
            FwmExperiment::fukuzawa_z03().high_shear_fit(),
        )
    }

    /// The film and sliding parameters (read-only: the constants are precomputed from them).
    pub fn film(&self) -> RoughFilm {
        self.film
    }

    /// The high-shear fit in use.
    pub fn fit(&self) -> HighShearFit {
        self.fit
    }

    /// `3σ`: onset of solid contact.
    pub fn solid_onset(&self) -> f64 {
        3.0 * self.film.sigma
    }

    /// `3σ + 2κ`: end of the transition, where the lubricant stiffness is largest.
    pub fn transition_end(&self) -> f64 {
        self.solid_onset() + 2.0 * self.film.kappa
    }

    /// `3σ + t`: the lubricant surface.
    pub fn lubricant_surface(&self) -> f64 {
        self.solid_onset() + self.film.film_thickness
    }

    pub fn regime(&self, separation: f64) -> RoughRegime {
        if separation.is_nan() || separation >= self.lubricant_surface() {
            RoughRegime::NoLubricantContact
        } else if separation >= self.transition_end() {
            RoughRegime::Hydrodynamic
        } else if separation >= self.solid_onset() {
            RoughRegime::Transition
        } else {
            RoughRegime::SolidContact
        }
    }

    /// Liquid gap `d0 = h − 3σ − κ`.
    pub fn liquid_gap(&self, separation: f64) -> f64 {
        separation - self.solid_onset() - self.film.kappa
    }

    /// Apparent shear rate `γ̇ = U/d0` (3.55) in the hydrodynamic range, else `None`.
    pub fn shear_rate(&self, separation: f64) -> Option<f64> {
        (self.regime(separation) == RoughRegime::Hydrodynamic)
            .then(|| self.film.speed / self.liquid_gap(separation))
    }

    /// `k_P,max = k_P(d0 = κ)` [N/m].
    pub fn max_normal_stiffness(&self) -> f64 {
        self.max_normal_stiffness
    }

    /// `k_Q,max = k_Q(d0 = κ)` [N/m].
    pub fn max_shear_stiffness(&self) -> f64 {
        self.max_shear_stiffness
    }

    /// Lubricant forces and stiffnesses of the hydrodynamic range (A.9), (A.10) and their
    /// integrals from the lubricant surface; zero for `h ≥ 3σ + t`. `None` for `h < 3σ + 2κ`
    /// (there the lubricant part depends on the solid: use [`MtlInterface`]).
    pub fn hydrodynamic(&self, separation: f64) -> Option<ForceStiffness> {
        match self.regime(separation) {
            RoughRegime::NoLubricantContact => Some(ForceStiffness::default()),
            RoughRegime::Hydrodynamic => {
                // d0 ≥ κ > 0 in this branch.
                let d0 = self.liquid_gap(separation).max(self.film.kappa);
                let mobile = self.film.film_thickness - self.film.kappa;
                let m = self.fit.normal_exponent;
                let n = self.shear_slope;
                Some(ForceStiffness {
                    normal: self.normal_coefficient * (d0.powf(-m) - mobile.powf(-m)),
                    friction: n * (mobile / d0).log10(),
                    normal_stiffness: m * self.normal_coefficient * d0.powf(-(m + 1.0)),
                    friction_stiffness: n / (d0 * LN_10),
                })
            }
            _ => None,
        }
    }

    /// Composes the lubricant with a solid model; precomputes the solid at `3σ` and `3σ + 2κ`.
    pub fn with_solid<S: SolidContact>(self, solid: S) -> MtlInterface<S> {
        let at_onset = solid.response(self.solid_onset());
        let at_end = solid.response(self.transition_end());
        let mut interface = MtlInterface {
            mtl: self,
            solid,
            solid_at_onset: at_onset,
            solid_at_transition_end: at_end,
            held: ForceStiffness::default(),
        };
        let held = interface.transition_lubricant(self.solid_onset(), at_onset);
        interface.held = ForceStiffness {
            normal: held.normal,
            friction: held.friction,
            normal_stiffness: 0.0,
            friction_stiffness: 0.0,
        };
        interface
    }
}

/// Lubricant, solid and total response at one separation.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct InterfaceResponse {
    pub lubricant: ForceStiffness,
    pub solid: SolidResponse,
    /// `lubricant + solid`.
    pub total: ForceStiffness,
}

/// "Lubricant + solid" interface: the MTL law composed with the caller's solid model.
#[derive(Debug, Clone)]
pub struct MtlInterface<S> {
    mtl: RoughMtl,
    solid: S,
    solid_at_onset: SolidResponse,
    solid_at_transition_end: SolidResponse,
    /// Lubricant forces held for `h < 3σ` (`P_lub(3σ)`, `Q_lub(3σ)`), zero stiffness.
    held: ForceStiffness,
}

impl<S: SolidContact> MtlInterface<S> {
    /// Lubricant part in the transition `3σ ≤ h < 3σ + 2κ` (eqs. 3.55–3.60; docs/contact.md):
    /// total stiffness `k_c(3σ) + (k_P,max − k_c(3σ))·s/(2κ)`, lubricant stiffness that minus
    /// `k_c(h)`; `P_lub = P_lub(3σ+2κ) + k_c(3σ)(2κ − s) + (k_P,max − k_c(3σ))(4κ² − s²)/(4κ)
    /// − [P_solid(h) − P_solid(3σ+2κ)]`, likewise for friction.
    fn transition_lubricant(&self, separation: f64, solid: SolidResponse) -> ForceStiffness {
        let mtl = &self.mtl;
        let kappa = mtl.film.kappa;
        let s = (separation - mtl.solid_onset()).clamp(0.0, 2.0 * kappa);
        let (c0, c1) = (self.solid_at_onset, self.solid_at_transition_end);
        let line = |k0: f64, k_max: f64| k0 + (k_max - k0) * s / (2.0 * kappa);
        let area = |k0: f64, k_max: f64| {
            k0 * (2.0 * kappa - s) + (k_max - k0) * (4.0 * kappa * kappa - s * s) / (4.0 * kappa)
        };
        ForceStiffness {
            normal: mtl.normal_at_transition_end
                + area(c0.normal_stiffness, mtl.max_normal_stiffness)
                - (solid.normal - c1.normal),
            friction: mtl.friction_at_transition_end
                + area(c0.friction_stiffness, mtl.max_shear_stiffness)
                - (solid.friction - c1.friction),
            normal_stiffness: line(c0.normal_stiffness, mtl.max_normal_stiffness)
                - solid.normal_stiffness,
            friction_stiffness: line(c0.friction_stiffness, mtl.max_shear_stiffness)
                - solid.friction_stiffness,
        }
    }

    /// Lubricant, solid and total forces and stiffnesses at mean-plane separation `h`.
    ///
    /// Forces are continuous everywhere. Stiffnesses jump at `3σ + t` (by the outermost film
    /// stiffness) and at `3σ + 2κ` (by the solid tail `k_c(3σ + 2κ)`), as in the spec.
    /// With `U = 0` the lubricant contributes nothing and the total is the solid.
    pub fn evaluate(&self, separation: f64) -> InterfaceResponse {
        let solid = self.solid.response(separation);
        let lubricant = if self.mtl.film.speed > 0.0 {
            match self.mtl.regime(separation) {
                RoughRegime::NoLubricantContact | RoughRegime::Hydrodynamic => {
                    self.mtl.hydrodynamic(separation).unwrap_or_default()
                }
                RoughRegime::Transition => self.transition_lubricant(separation, solid),
                RoughRegime::SolidContact => self.held,
            }
        } else {
            ForceStiffness::default()
        };
        InterfaceResponse {
            lubricant,
            solid,
            total: lubricant.plus(solid),
        }
    }

    /// Lubricant part only (same as `evaluate(h).lubricant`).
    pub fn lubricant(&self, separation: f64) -> ForceStiffness {
        self.evaluate(separation).lubricant
    }

    /// `P_lub(3σ)`, `Q_lub(3σ)`: the lubricant forces held in solid contact.
    pub fn held_lubricant_forces(&self) -> ForceStiffness {
        self.held
    }

    /// The lubricant law (read-only: the solid anchors were computed for it).
    pub fn model(&self) -> &RoughMtl {
        &self.mtl
    }

    /// The caller's solid model.
    pub fn solid_model(&self) -> &S {
        &self.solid
    }

    /// The solid response at `3σ` used to anchor the transition.
    pub fn solid_at_onset(&self) -> SolidResponse {
        self.solid_at_onset
    }
}
