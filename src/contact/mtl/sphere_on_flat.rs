//! Sphere-on-flat hydrodynamics of a molecularly thin film (dissertation §3.1).
//!
//! A rigid smooth sphere of radius `R` slides at speed `U` over a rigid flat covered by a
//! lubricant film of total thickness `t`. The bonded layers on both surfaces leave a minimum
//! liquid gap `κ`; the liquid gap is `d0 = h0 − κ` for the solid–solid gap `h0`. The film is
//! isoviscous at the *apparent* viscosity `η` (the measured one, which already contains wall
//! slip), so every force here is written in `η` and never divides by the slip factor.
//!
//! Regimes of `h0` (§3.1): `h0 > t` no lubricant contact; `2κ ≤ h0 ≤ t` hydrodynamic;
//! `0 < h0 < 2κ` transition (linear between the fluid force at `d0 = κ` and the solid force at
//! a small interference `ω_min`); `h0 ≤ 0` solid contact (supplied by the caller).

use std::f64::consts::PI;

use super::{is_positive, require_non_negative, require_positive};
use crate::contact::ContactError;

/// Normal and friction force on the sphere [N] (magnitudes).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactForces {
    pub normal: f64,
    pub friction: f64,
}

// ---------------------------------------------------------------------------------------------
// Apparent viscosity (3.9)–(3.12)

/// Gap-dependent apparent viscosity `η(d0) = a·d0² + b·d0 + c` (3.9), bounded to
/// `[η_bulk, η0]`, equal to `η0` for `d0 ≤ κ` and to `η_bulk` for `d0 ≥ d_b`.
///
/// The dissertation's fitted `a, b, c` are lost (eqs. 3.9–3.12);
/// [`ViscosityModel::vertex_parabola`] is the spec's default curve through the two surviving
/// anchors. Only the low-shear sphere-on-flat curves depend on it: at HDI shear rates `η = η0`
/// everywhere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViscosityModel {
    /// `a` [Pa·s/m²].
    pub a: f64,
    /// `b` [Pa·s/m].
    pub b: f64,
    /// `c` [Pa·s].
    pub c: f64,
    /// Limiting viscosity `η0 ≡ μ0`, reached at `d0 = κ` [Pa·s].
    pub limiting: f64,
    /// Bulk viscosity `η_bulk` [Pa·s].
    pub bulk: f64,
    /// Minimum liquid gap `κ` at which the viscosity saturates [m].
    pub kappa: f64,
    /// Gap `d_b` beyond which the film is bulk-like [m].
    pub bulk_gap: f64,
}

impl ViscosityModel {
    /// Arbitrary quadratic (3.9) with its bounds. Requires `0 < η_bulk ≤ η0`, `0 < κ < d_b`,
    /// finite coefficients.
    pub fn from_coefficients(
        a: f64,
        b: f64,
        c: f64,
        limiting: f64,
        bulk: f64,
        kappa: f64,
        bulk_gap: f64,
    ) -> Result<Self, ContactError> {
        for (name, v) in [("a", a), ("b", b), ("c", c)] {
            if !v.is_finite() {
                return Err(ContactError::parameter(name, v, "must be finite"));
            }
        }
        require_positive("eta0", limiting)?;
        require_positive("eta_bulk", bulk)?;
        if bulk > limiting {
            return Err(ContactError::parameter(
                "eta_bulk",
                bulk,
                format!("must not exceed eta0 = {limiting}"),
            ));
        }
        require_positive("kappa", kappa)?;
        require_positive("d_b", bulk_gap)?;
        if bulk_gap <= kappa {
            return Err(ContactError::parameter(
                "d_b",
                bulk_gap,
                format!("must exceed kappa = {kappa}"),
            ));
        }
        Ok(Self {
            a,
            b,
            c,
            limiting,
            bulk,
            kappa,
            bulk_gap,
        })
    }

    /// Default of eqs. 3.9–3.12: `η = η_bulk + (η0 − η_bulk)·((d_b − d0)/(d_b − κ))²`, i.e. a
    /// parabola with its vertex (value `η_bulk`) at `d_b`, through `η0` at `κ`; expanded into
    /// (3.9).
    pub fn vertex_parabola(
        limiting: f64,
        bulk: f64,
        kappa: f64,
        bulk_gap: f64,
    ) -> Result<Self, ContactError> {
        // Validate the anchors before using them in the expansion.
        Self::from_coefficients(0.0, 0.0, 0.0, limiting, bulk, kappa, bulk_gap)?;
        let a = (limiting - bulk) / (bulk_gap - kappa).powi(2);
        Self::from_coefficients(
            a,
            -2.0 * a * bulk_gap,
            bulk + a * bulk_gap * bulk_gap,
            limiting,
            bulk,
            kappa,
            bulk_gap,
        )
    }

    /// The dissertation's FWM lubricant (§3.1.1): `η0 = 0.31 Pa·s`, `η_bulk = 0.06 Pa·s`
    /// [seed §3.1 viscosity model], `κ0 = 1 nm` [seed §3.1.1], `d_b = 500 nm` (gap where the
    /// FWM data reach bulk [seed]) — with the vertex-parabola assumption for the lost fit.
    pub fn fukuzawa_z03() -> Self {
        let a = (0.31 - 0.06) / (500e-9_f64 - 1e-9).powi(2);
        Self {
            a,
            b: -2.0 * a * 500e-9,
            c: 0.06 + a * 500e-9 * 500e-9,
            limiting: 0.31,
            bulk: 0.06,
            kappa: 1e-9,
            bulk_gap: 500e-9,
        }
    }

    /// `η(d0)` (3.9) with the caps; NaN gaps give `η_bulk` (no stiffening assumed).
    pub fn at_gap(&self, liquid_gap: f64) -> f64 {
        if liquid_gap <= self.kappa {
            return self.limiting;
        }
        if liquid_gap.is_nan() || liquid_gap >= self.bulk_gap {
            return self.bulk;
        }
        let eta = (self.a * liquid_gap + self.b) * liquid_gap + self.c;
        eta.clamp(self.bulk, self.limiting)
    }

    /// Coefficients of the shear-rate form (3.10) at speed `U`: `(a', b', c)` with
    /// `a' = a·U²` (3.11), `b' = b·U` (3.12).
    pub fn shear_rate_coefficients(&self, speed: f64) -> (f64, f64, f64) {
        (self.a * speed * speed, self.b * speed, self.c)
    }

    /// `η(γ̇) = a'·γ̇⁻² + b'·γ̇⁻¹ + c` (3.10) at measuring speed `U`, with `d0 = U/γ̇`; capped at
    /// `η0` for `γ̇ ≥ U/κ` and `η_bulk` for `γ̇ ≤ U/d_b`. `γ̇ ≤ 0` or `U ≤ 0` → `η_bulk`.
    pub fn at_shear_rate(&self, shear_rate: f64, speed: f64) -> f64 {
        if !is_positive(shear_rate) || !is_positive(speed) {
            return self.bulk;
        }
        self.at_gap(speed / shear_rate)
    }
}

/// Which apparent viscosity the sphere-on-flat forces use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ViscosityLaw {
    /// Isoviscous at a fixed apparent viscosity (e.g. `η0` at HDI shear rates, Fig. 3.8).
    Constant(f64),
    /// `η(d0)` as measured (valid when the sphere moves at the measuring speed).
    Gap(ViscosityModel),
    /// `η(γ̇)` with `γ̇ = U/d0` at the sphere's speed, read on the curve measured at
    /// `experiment_speed` (eqs. 3.9–3.12: capped at `η0` for `γ̇ ≥ γ̇0`).
    ShearRate {
        model: ViscosityModel,
        experiment_speed: f64,
    },
}

impl ViscosityLaw {
    fn validate(&self) -> Result<(), ContactError> {
        match *self {
            ViscosityLaw::Constant(eta) => require_positive("eta", eta).map(|_| ()),
            ViscosityLaw::Gap(model) => model.validate(),
            ViscosityLaw::ShearRate {
                model,
                experiment_speed,
            } => {
                require_positive("U0", experiment_speed)?;
                model.validate()
            }
        }
    }

    /// Apparent viscosity at liquid gap `d0` for a sphere sliding at `speed`.
    pub fn apparent_viscosity(&self, liquid_gap: f64, speed: f64) -> f64 {
        match *self {
            ViscosityLaw::Constant(eta) => eta,
            ViscosityLaw::Gap(model) => model.at_gap(liquid_gap),
            ViscosityLaw::ShearRate {
                model,
                experiment_speed,
            } => {
                if liquid_gap <= 0.0 {
                    return model.limiting; // closed past κ: saturated
                }
                if !is_positive(speed) || liquid_gap.is_nan() {
                    return model.bulk; // no shearing (or no gap): no stiffening
                }
                model.at_shear_rate(speed / liquid_gap, experiment_speed)
            }
        }
    }
}

impl ViscosityModel {
    fn validate(&self) -> Result<(), ContactError> {
        Self::from_coefficients(
            self.a,
            self.b,
            self.c,
            self.limiting,
            self.bulk,
            self.kappa,
            self.bulk_gap,
        )
        .map(|_| ())
    }
}

// ---------------------------------------------------------------------------------------------
// Slip (3.13)–(3.18), (3.23), Table 3.1

/// Navier-type wall slip (3.13)–(3.17): `u_s* = L_s/(η_w·d0)`, slip factor
/// `f* = H[1 − u_s*]·(1 − u_s*)`, `η = f*·η_true`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlipModel {
    /// Slip length `L_s` [m].
    pub slip_length: f64,
    /// Dimensionless "wall friction" `η_w` (> 0; `+∞` means no slip).
    pub wall_friction: f64,
}

/// Slip factors at or below this count as unbounded slip (docs/contact.md).
const UNBOUNDED_SLIP_FACTOR: f64 = 1e-12;

/// The viscosity with slip removed, or the statement that it is undefined.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TrueViscosity {
    /// `η_true = η/f*` [Pa·s].
    Finite(f64),
    /// `f* ≤ 10⁻¹²`: the wall does not drag the fluid (Table 3.1 "unbounded slip"); the
    /// decomposition `η = f*·η_true` carries no information about `η_true`.
    UnboundedSlip,
}

impl SlipModel {
    /// Requires `L_s ≥ 0` finite and `η_w > 0` (`+∞` allowed).
    pub fn new(slip_length: f64, wall_friction: f64) -> Result<Self, ContactError> {
        require_non_negative("L_s", slip_length)?;
        if wall_friction.is_nan() || wall_friction <= 0.0 {
            return Err(ContactError::parameter(
                "eta_w",
                wall_friction,
                "must be > 0 (infinity allowed: no slip)",
            ));
        }
        Ok(Self {
            slip_length,
            wall_friction,
        })
    }

    /// Default (§3.1.1): no slip (`η_w = ∞`) — the apparent viscosity already contains it.
    pub fn no_slip() -> Self {
        Self {
            slip_length: 0.0,
            wall_friction: f64::INFINITY,
        }
    }

    /// `L_s = 3 nm`, the high-speed plateau of Martini et al., PRL 100 (2008) 206001, used by
    /// the dissertation's decoupling examples (`η_w` = 1, 3, 5) [seed §3.1 "Decoupling"].
    pub fn martini_2008(wall_friction: f64) -> Result<Self, ContactError> {
        Self::new(3e-9, wall_friction)
    }

    fn slips(&self) -> bool {
        self.slip_length > 0.0 && self.wall_friction.is_finite()
    }

    /// Dimensionless slip velocity `u_s* = u_s/U = L_s/(η_w·d0)` (3.14). Requires `d0 > 0`.
    pub fn slip_velocity_ratio(&self, liquid_gap: f64) -> Result<f64, ContactError> {
        require_positive("d0", liquid_gap)?;
        if !self.slips() {
            return Ok(0.0);
        }
        Ok(self.slip_length / (self.wall_friction * liquid_gap))
    }

    /// Slip factor `f* = u_w/U ∈ [0, 1]` (3.17) at liquid gap `d0`; `u_s* ≥ 1 ⇒ f* = 0`.
    /// `d0 ≤ 0` counts as unbounded slip when the model slips at all. Values `f* ≤ 10⁻¹²` are
    /// set to 0: they are rounding at the Heaviside boundary (e.g. `3 nm/(3·1 nm)` evaluates
    /// to `1 − 2⁻⁵³`), and the same threshold marks unbounded slip in
    /// [`SlipModel::true_viscosity`].
    pub fn slip_factor(&self, liquid_gap: f64) -> f64 {
        if !self.slips() {
            return 1.0;
        }
        match self.slip_velocity_ratio(liquid_gap) {
            Ok(ratio) if 1.0 - ratio > UNBOUNDED_SLIP_FACTOR => (1.0 - ratio).min(1.0),
            _ => 0.0,
        }
    }

    /// Liquid gap below which `f* = 0`: `d0 = L_s/η_w` (3 nm for `L_s = 3 nm`, `η_w = 1`).
    /// 0 when the model does not slip.
    pub fn zero_slip_factor_gap(&self) -> f64 {
        if !self.slips() {
            return 0.0;
        }
        self.slip_length / self.wall_friction
    }

    /// Admissible for a film with minimum liquid gap `κ`: `L_s/κ < η_w` (eqs. 3.13–3.17), so the
    /// wall still drags the fluid at the smallest gap.
    pub fn is_bounded_at(&self, kappa: f64) -> bool {
        !self.slips() || (kappa > 0.0 && self.slip_length / kappa < self.wall_friction)
    }

    /// `η_true = η/f*` (3.23), or [`TrueViscosity::UnboundedSlip`] when `f* ≤ 10⁻¹²`.
    pub fn true_viscosity(&self, apparent_viscosity: f64, liquid_gap: f64) -> TrueViscosity {
        let f = self.slip_factor(liquid_gap);
        if f <= UNBOUNDED_SLIP_FACTOR {
            TrueViscosity::UnboundedSlip
        } else {
            TrueViscosity::Finite(apparent_viscosity / f)
        }
    }

    /// True shear rate `γ̇_true = f*·U/d0` (3.18). Requires `d0 > 0`.
    pub fn true_shear_rate(&self, speed: f64, liquid_gap: f64) -> Result<f64, ContactError> {
        require_positive("d0", liquid_gap)?;
        Ok(self.slip_factor(liquid_gap) * speed / liquid_gap)
    }
}

// ---------------------------------------------------------------------------------------------
// Closed forms (3.24)–(3.35), written in the apparent viscosity η = f*·η_true

fn check_sphere(eta: f64, speed: f64, radius: f64, liquid_gap: f64) -> Result<(), ContactError> {
    require_non_negative("eta", eta)?;
    require_non_negative("U", speed)?;
    require_positive("R", radius)?;
    require_positive("d0", liquid_gap)?;
    Ok(())
}

/// Kapitza pressure (3.24): `p = −24·η·U·R²·x / (5·(2·d0·R + x² + y²)²)`, the exact solution
/// of the Reynolds equation (3.22) for `h = d0 + (x² + y²)/(2R)` with the sphere moving along
/// `+x`; positive (load-carrying) for `x < 0`.
pub fn kapitza_pressure(
    eta: f64,
    speed: f64,
    radius: f64,
    liquid_gap: f64,
    x: f64,
    y: f64,
) -> Result<f64, ContactError> {
    check_sphere(eta, speed, radius, liquid_gap)?;
    let den = 2.0 * liquid_gap * radius + x * x + y * y;
    Ok(-24.0 * eta * speed * radius * radius * x / (5.0 * den * den))
}

/// Half-Sommerfeld load of the Kapitza pressure (3.26), (3.32):
/// `P_fluid = (6π/5)·η·U·R·√(2R/d0)`.
pub fn kapitza_normal_force(
    eta: f64,
    speed: f64,
    radius: f64,
    liquid_gap: f64,
) -> Result<f64, ContactError> {
    check_sphere(eta, speed, radius, liquid_gap)?;
    Ok(6.0 * PI / 5.0 * eta * speed * radius * (2.0 * radius / liquid_gap).sqrt())
}

/// Shear stress on the sphere (3.27):
/// `τ = (4/5)·η·U·R·(2·d0·R + 7x² + y²)/(2·d0·R + x² + y²)²`.
pub fn shear_stress(
    eta: f64,
    speed: f64,
    radius: f64,
    liquid_gap: f64,
    x: f64,
    y: f64,
) -> Result<f64, ContactError> {
    check_sphere(eta, speed, radius, liquid_gap)?;
    let base = 2.0 * liquid_gap * radius;
    let den = base + x * x + y * y;
    Ok(0.8 * eta * speed * radius * (base + 7.0 * x * x + y * y) / (den * den))
}

fn immersion(radius: f64, liquid_gap: f64, mobile_thickness: f64) -> Result<f64, ContactError> {
    require_positive("t - kappa", mobile_thickness)?;
    let delta = (mobile_thickness - liquid_gap).max(0.0);
    Ok(delta.min(radius))
}

/// Partially submerged shear force as printed (3.30)/(3.33):
/// `Q = (8π/5)·η·U·δ·(R² + 2·d0·R + 6·R·δ − 2δ²)/(R + 2·d0)²`, with immersion depth
/// `δ = (t − κ) − d0` (`mobile_thickness = t − κ`), 0 once the sphere leaves the film.
///
/// Faithful to the dissertation's algebra, which evaluates the stress at `x² = R² − y²`, far
/// outside the wetted zone (docs/contact.md); it gives `≈ 0.40×` the Couette form (3.31).
pub fn shear_force_partial_dissertation(
    eta: f64,
    speed: f64,
    radius: f64,
    liquid_gap: f64,
    mobile_thickness: f64,
) -> Result<f64, ContactError> {
    check_sphere(eta, speed, radius, liquid_gap)?;
    let (r, d0) = (radius, liquid_gap);
    let delta = immersion(r, d0, mobile_thickness)?;
    Ok(8.0 * PI / 5.0
        * eta
        * speed
        * delta
        * (r * r + 2.0 * d0 * r + 6.0 * r * delta - 2.0 * delta * delta)
        / (r + 2.0 * d0).powi(2))
}

/// Partially submerged shear force, lubrication-consistent alternative [derived from eqs.
/// 3.27–3.31]: (3.27) integrated over the projected wetted disc `r² ≤ 2Rδ`,
/// `Q = (4π/5)·η·U·R·[4·ln(1 + δ/d0) − 3δ/(d0 + δ)]`.
pub fn shear_force_partial_wetted_disc(
    eta: f64,
    speed: f64,
    radius: f64,
    liquid_gap: f64,
    mobile_thickness: f64,
) -> Result<f64, ContactError> {
    check_sphere(eta, speed, radius, liquid_gap)?;
    let delta = immersion(radius, liquid_gap, mobile_thickness)?;
    let d0 = liquid_gap;
    Ok(0.8 * PI * eta * speed * radius * (4.0 * (delta / d0).ln_1p() - 3.0 * delta / (d0 + delta)))
}

/// Couette-only shear force (3.31): `Q = 4π·η·U·R·δ/(2·d0 + R)`.
pub fn shear_force_couette(
    eta: f64,
    speed: f64,
    radius: f64,
    liquid_gap: f64,
    mobile_thickness: f64,
) -> Result<f64, ContactError> {
    check_sphere(eta, speed, radius, liquid_gap)?;
    let delta = immersion(radius, liquid_gap, mobile_thickness)?;
    Ok(4.0 * PI * eta * speed * radius * delta / (2.0 * liquid_gap + radius))
}

/// Fully submerged geometric factor (3.35), leading Goldman–Cox–Brenner term:
/// `Ω_fs = (16π/5)·R·ln(R/d0)` [m]; 0 for `d0 ≥ R` (outside the lubrication asymptote).
pub fn geometric_factor_fully_submerged(radius: f64, liquid_gap: f64) -> Result<f64, ContactError> {
    require_positive("R", radius)?;
    require_positive("d0", liquid_gap)?;
    Ok((16.0 * PI / 5.0 * radius * (radius / liquid_gap).ln()).max(0.0))
}

/// Partially submerged geometric factor (3.34): `Ω_ps = Q(3.33)/(η·U)` [m].
pub fn geometric_factor_partially_submerged(
    radius: f64,
    liquid_gap: f64,
    mobile_thickness: f64,
) -> Result<f64, ContactError> {
    shear_force_partial_dissertation(1.0, 1.0, radius, liquid_gap, mobile_thickness)
}

/// Fully submerged shear force `Q = Ω_fs·η·U` (3.7), (3.35).
pub fn shear_force_fully_submerged(
    eta: f64,
    speed: f64,
    radius: f64,
    liquid_gap: f64,
) -> Result<f64, ContactError> {
    check_sphere(eta, speed, radius, liquid_gap)?;
    Ok(geometric_factor_fully_submerged(radius, liquid_gap)? * eta * speed)
}

// ---------------------------------------------------------------------------------------------
// The sphere in its film: regimes and transitional forces (3.3), (3.4)

/// Which shear-force formula the hydrodynamic regime uses (eqs. 3.27–3.35).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShearModel {
    /// (3.30)/(3.33) as printed (default: reproduces the dissertation's equations).
    PartialDissertation,
    /// (3.27) over the wetted disc [derived].
    PartialWettedDisc,
    /// (3.35): leading GCB term (sphere immersed in a film thicker than itself).
    FullySubmerged,
}

/// Regime of the solid–solid gap `h0` (§3.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SphereRegime {
    /// `h0 > t` (also NaN gaps): the sphere does not touch the lubricant.
    NoContact,
    /// `2κ ≤ h0 ≤ t`.
    Hydrodynamic,
    /// `0 < h0 < 2κ`: bonded layers are ruptured/expelled.
    Transition,
    /// `h0 ≤ 0`: interference `ω = −h0`.
    Solid,
}

/// A sphere sliding over a lubricated flat (§3.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereOnFlat {
    /// Sphere radius `R` [m].
    pub radius: f64,
    /// Minimum liquid gap `κ` [m] (half the summed bonded-layer heights, (3.2)).
    pub kappa: f64,
    /// Total lubricant thickness `t` [m].
    pub film_thickness: f64,
    /// Sliding speed `U` [m/s].
    pub speed: f64,
    pub viscosity: ViscosityLaw,
    pub shear_model: ShearModel,
}

impl SphereOnFlat {
    /// Requires `R > 0`, `κ > 0`, `t > 2κ` (a mobile layer exists), `U ≥ 0`, a valid
    /// viscosity law. The thin-film assumption `R ≥ 100·t` is not enforced (it is a warning in
    /// the spec): see [`SphereOnFlat::thin_film_assumption_holds`].
    pub fn new(
        radius: f64,
        kappa: f64,
        film_thickness: f64,
        speed: f64,
        viscosity: ViscosityLaw,
        shear_model: ShearModel,
    ) -> Result<Self, ContactError> {
        require_positive("R", radius)?;
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
        viscosity.validate()?;
        Ok(Self {
            radius,
            kappa,
            film_thickness,
            speed,
            viscosity,
            shear_model,
        })
    }

    /// `t ≪ R`, taken as `R ≥ 100·t` (docs/contact.md); below it the Reynolds reduction is suspect.
    pub fn thin_film_assumption_holds(&self) -> bool {
        self.radius >= 100.0 * self.film_thickness
    }

    /// `d0 = h0 − κ` (3.1).
    pub fn liquid_gap(&self, solid_gap: f64) -> f64 {
        solid_gap - self.kappa
    }

    /// Apparent shear-rate range in the film, `(U/(t − κ), U/κ)` (3.48), (3.49).
    pub fn shear_rate_range(&self) -> (f64, f64) {
        (
            self.speed / (self.film_thickness - self.kappa),
            self.speed / self.kappa,
        )
    }

    pub fn regime(&self, solid_gap: f64) -> SphereRegime {
        if solid_gap.is_nan() || solid_gap > self.film_thickness {
            SphereRegime::NoContact
        } else if solid_gap >= 2.0 * self.kappa {
            SphereRegime::Hydrodynamic
        } else if solid_gap > 0.0 {
            SphereRegime::Transition
        } else {
            SphereRegime::Solid
        }
    }

    /// Hydrodynamic load and friction (3.32), (3.33)/(3.35) at solid gap `h0`; `None` outside
    /// `2κ ≤ h0 ≤ t`.
    pub fn hydrodynamic_forces(&self, solid_gap: f64) -> Option<ContactForces> {
        if self.regime(solid_gap) != SphereRegime::Hydrodynamic {
            return None;
        }
        // d0 ≥ κ > 0 and every parameter was validated: the closed forms cannot fail.
        let d0 = self.liquid_gap(solid_gap).max(self.kappa);
        let eta = self.viscosity.apparent_viscosity(d0, self.speed);
        let (u, r, tl) = (self.speed, self.radius, self.film_thickness - self.kappa);
        let normal = kapitza_normal_force(eta, u, r, d0).ok()?;
        let friction = match self.shear_model {
            ShearModel::PartialDissertation => shear_force_partial_dissertation(eta, u, r, d0, tl),
            ShearModel::PartialWettedDisc => shear_force_partial_wetted_disc(eta, u, r, d0, tl),
            ShearModel::FullySubmerged => shear_force_fully_submerged(eta, u, r, d0),
        }
        .ok()?;
        Some(ContactForces { normal, friction })
    }

    /// `P_fluid,max`, `Q_fluid,max`: the hydrodynamic forces at `d0 = κ` (`h0 = 2κ`).
    pub fn max_fluid_forces(&self) -> ContactForces {
        self.hydrodynamic_forces(2.0 * self.kappa)
            .unwrap_or_default()
    }

    /// Forces in every regime (§3.1, eqs. 3.3–3.4). `solid(ω)` is the caller's single-asperity
    /// solid model at interference `ω ≥ 0` (e.g. the ISBL/Kogut–Etsion asperity, or
    /// [`super::hertz_normal_force`]); it is used for `h0 ≤ 0` and, at `ω = omega_min` (1 Å
    /// in the dissertation), as the transition's inner anchor:
    /// `P_trans = P_solid,min + (P_fluid,max − P_solid,min)·h0/(2κ)` (3.3), likewise `Q` (3.4).
    ///
    /// Documented discontinuities: `P` drops from its half-Sommerfeld value to 0 at `h0 = t`
    /// (flooded-inlet model); at `h0 = 0` the transition meets `solid(ω_min)`, not `solid(0)`.
    pub fn forces<S>(&self, solid_gap: f64, omega_min: f64, solid: S) -> ContactForces
    where
        S: Fn(f64) -> ContactForces,
    {
        match self.regime(solid_gap) {
            SphereRegime::NoContact => ContactForces::default(),
            SphereRegime::Hydrodynamic => self.hydrodynamic_forces(solid_gap).unwrap_or_default(),
            SphereRegime::Transition => {
                let fluid = self.max_fluid_forces();
                let anchor = solid(omega_min.max(0.0));
                let w = solid_gap / (2.0 * self.kappa);
                ContactForces {
                    normal: anchor.normal + (fluid.normal - anchor.normal) * w,
                    friction: anchor.friction + (fluid.friction - anchor.friction) * w,
                }
            }
            SphereRegime::Solid => solid(-solid_gap),
        }
    }
}
