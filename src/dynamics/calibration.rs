//! Class-D calibration (docs/calibration.md): fit the `[assumption]` knobs whose values the
//! dissertation dropped to its published class-D landmarks, reproducibly. Pure: no I/O.
//!
//! * **Knobs** ([`Knob`]) — DMW amplitude (the record's standard deviation was dropped),
//!   rear-spring stiffening β, work of adhesion Δγ, LJ spacing ε, contact damping ζ_c, the
//!   initial model's truncation `n` (S1c) and, as a what-if only, the summit density η (seeded
//!   124 µm⁻² for the improved model, so it is not in the default set). Each box is the model's
//!   accepted range where it has one, and is searched in `[0, 1]`.
//! * **Targets** ([`Target`]) — published numbers with the spec's tolerance, in two sets: the
//!   fitted set (the objective `Σ weight·((ours − published)/tolerance)²`, so a residual of 1
//!   means "at the edge of the band") and the held-out set, evaluated before and after the fit
//!   on the base sweep's grid and never inside it.
//! * **Evaluation** — one objective value is a handful of 2-DOF cases at the target actuations
//!   (parallel) plus the touchdown of [`find_touchdown`] (scan from 0 nm, first crossing
//!   refined to 0.02 nm; docs/conventions.md).
//! * **Search** — Nelder–Mead in the unit box from the spec defaults
//!   ([`crate::numerics::nelder_mead`]) to its tolerance or budget, which the result says:
//!   deterministic, so the same inputs give the same fit.

use super::air_bearing::RearStiffening;
use super::geometry::ContactCriterion;
use super::metrics::{sweep_metrics, Regime, SlopeParams, SweepMetrics, SweepPoint};
use super::metrics::{CaseMetrics, CaseParams};
use super::params::{optimised_bulge, Model2Dof, ModelVariant};
use super::touchdown::{find_touchdown, TouchdownSearch};
use super::two_dof::{DmwInput, SimOptions, TwoDofCase};
use super::{DynamicsError, Result, NM};
use crate::contact::isbl::{IsblModel, IsblParams, SurfaceEnergy};
use crate::contact::lookup::IsblLookup;
use crate::numerics::nelder_mead::{
    minimize_unit_box_with_cutoff, Cutoff, NelderMeadOptions, StopReason, Trial,
};
use rayon::prelude::*;

/// A calibration knob: a dropped input with its physical range.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Knob {
    /// Multiplier on the DMW track (displacement and velocity): its σ was dropped.
    DmwScale,
    /// Improved model's rear-spring stiffening amplitude β (§3.2).
    KrStiffeningBeta,
    /// Work of adhesion Δγ (N/m), constant surface energy only.
    SurfaceEnergy,
    /// Lennard-Jones equilibrium spacing ε (m).
    LjSpacing,
    /// Contact damping ratio ζ_c.
    ContactDamping,
    /// Initial model's contact criterion / truncation `n` (`nσ`, S1c).
    TruncationN,
    /// Combined summit density η (1/m²) — seeded for the improved model; a what-if knob.
    AsperityDensity,
}

impl Knob {
    pub const ALL: [Knob; 7] = [
        Knob::DmwScale,
        Knob::KrStiffeningBeta,
        Knob::SurfaceEnergy,
        Knob::LjSpacing,
        Knob::ContactDamping,
        Knob::TruncationN,
        Knob::AsperityDensity,
    ];

    /// The `pipeline.toml` name.
    pub fn name(self) -> &'static str {
        match self {
            Knob::DmwScale => "dmw_scale",
            Knob::KrStiffeningBeta => "kr_stiffening_beta",
            Knob::SurfaceEnergy => "surface_energy",
            Knob::LjSpacing => "lj_spacing",
            Knob::ContactDamping => "contact_damping",
            Knob::TruncationN => "truncation_n",
            Knob::AsperityDensity => "asperity_density",
        }
    }

    pub fn from_name(s: &str) -> Option<Knob> {
        Knob::ALL.into_iter().find(|k| k.name() == s)
    }

    /// SI unit of the value.
    pub fn unit(self) -> &'static str {
        match self {
            Knob::DmwScale | Knob::KrStiffeningBeta | Knob::ContactDamping | Knob::TruncationN => {
                "1"
            }
            Knob::SurfaceEnergy => "N/m",
            Knob::LjSpacing => "m",
            Knob::AsperityDensity => "1/m^2",
        }
    }

    /// Search box `[lo, hi]` (SI), docs/calibration.md. Where the model bounds a knob the box
    /// is the model's accepted range (β: `RearStiffening::validate`, 0–3; ζ_c: `Model2Dof::
    /// validate`, 0–1; n: `ContactCriterion::validate`, 0–2.8). Where the model accepts an open
    /// range the box starts at the model's own limit and its other end is a stated choice:
    /// the DMW multiplier and Δγ accept any value ≥ 0 (box 0–4, 0–150 mN/m); ε any value > 0
    /// (box 0.1–1 nm: below an atomic spacing the LJ form means nothing); η any value > 0
    /// (what-if box 20–3000 µm⁻²).
    pub fn default_bounds(self) -> (f64, f64) {
        match self {
            Knob::DmwScale => (0.0, 4.0),
            Knob::KrStiffeningBeta => (0.0, 3.0),
            Knob::SurfaceEnergy => (0.0, 0.15),
            Knob::LjSpacing => (0.1 * NM, 1.0 * NM),
            Knob::ContactDamping => (0.0, 1.0),
            Knob::TruncationN => (0.0, 2.8),
            Knob::AsperityDensity => (20e12, 3000e12),
        }
    }

    /// Searched on a logarithmic axis: only the what-if summit density, whose box spans two
    /// decades; the others start at 0, which a logarithmic axis cannot hold.
    fn logarithmic(self) -> bool {
        matches!(self, Knob::AsperityDensity)
    }

    /// Value of the knob in the base inputs.
    pub fn base_value(self, model: &Model2Dof, isbl: &IsblParams) -> Result<f64> {
        Ok(match self {
            Knob::DmwScale => 1.0,
            Knob::KrStiffeningBeta => match model.air_bearing.stiffening {
                RearStiffening::Constant => 0.0,
                RearStiffening::Quadratic { beta } => beta,
            },
            Knob::SurfaceEnergy => match isbl.surface_energy {
                SurfaceEnergy::Constant { delta_gamma } => delta_gamma,
                SurfaceEnergy::Variable { .. } => return Err(DynamicsError::Numerical(
                    "knob surface_energy needs a constant Δγ in the contact set (it is variable)"
                        .into(),
                )),
            },
            Knob::LjSpacing => isbl.lj_spacing,
            Knob::ContactDamping => model.interface.contact_damping_ratio,
            Knob::TruncationN => match model.interface.criterion {
                ContactCriterion::NSigma { n } => n,
                _ => {
                    return Err(DynamicsError::Numerical(
                        "knob truncation_n belongs to the initial model (nσ criterion)".into(),
                    ))
                }
            },
            Knob::AsperityDensity => isbl.summit_density,
        })
    }

    fn unit_coordinate(self, v: f64, (lo, hi): (f64, f64)) -> f64 {
        let u = if self.logarithmic() {
            (v.ln() - lo.ln()) / (hi.ln() - lo.ln())
        } else {
            (v - lo) / (hi - lo)
        };
        u.clamp(0.0, 1.0)
    }

    fn value_at(self, u: f64, (lo, hi): (f64, f64)) -> f64 {
        let u = u.clamp(0.0, 1.0);
        if self.logarithmic() {
            (lo.ln() + u * (hi.ln() - lo.ln())).exp()
        } else {
            lo + u * (hi - lo)
        }
    }
}

/// A knob with its bounds.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct KnobRange {
    pub knob: Knob,
    pub lo: f64,
    pub hi: f64,
}

impl KnobRange {
    pub fn new(knob: Knob) -> Self {
        let (lo, hi) = knob.default_bounds();
        KnobRange { knob, lo, hi }
    }

    /// Bounds finite, ordered, non-negative (positive on a logarithmic axis).
    pub fn check(&self) -> Result<()> {
        let ok = self.lo.is_finite()
            && self.hi.is_finite()
            && self.lo < self.hi
            && (!self.knob.logarithmic() || self.lo > 0.0)
            && self.lo >= 0.0;
        if ok {
            Ok(())
        } else {
            Err(DynamicsError::parameter(
                format!("bounds of knob {}", self.knob.name()),
                self.lo,
                format!(
                    "need 0 ≤ lo < hi (lo > 0 for a logarithmic knob); hi = {:e}",
                    self.hi
                ),
            ))
        }
    }
}

/// A slope of the clearance curve `c̄(h_TFC)` (§8 of docs/dynamics-metrics.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SlopeName {
    A,
    B,
    C,
    D,
}

/// What a target measures.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// Smallest actuation with solid contact in the steady window (m), by
    /// [`find_touchdown`] (scan from 0 nm, first crossing refined).
    Touchdown,
    /// Mean clearance at an actuation (m; negative = interference).
    Clearance { actuation: f64 },
    /// Eq. 2.1 FHM/BV at an actuation (%).
    Vibration { actuation: f64 },
    /// Mean dynamic contact force (N).
    ContactForce { actuation: f64 },
    /// Mean friction force Q (N).
    FrictionForce { actuation: f64 },
    /// Mean ISBL adhesion force (N).
    Adhesion { actuation: f64 },
    /// Mean instantaneous friction coefficient over the loaded samples.
    FrictionCoefficient { actuation: f64 },
    /// Mean instantaneous real contact pressure `P_m = F_c/A_r` over the loaded samples (Pa).
    MeanPressure { actuation: f64 },
    /// Mean instantaneous shear traction `τ = Q/A_r` over the loaded samples (Pa).
    ShearTraction { actuation: f64 },
    /// Mean real contact area `A_r` (m²).
    RealArea { actuation: f64 },
    // ── Sweep quantities: need the whole sweep grid (held-out targets only) ──────────────
    /// Critical point: actuation where lines A and B meet (m).
    CriticalPointActuation,
    /// Critical point: clearance of line A there (m).
    CriticalPointClearance,
    /// Largest FHM of the flying branch (cases before the first non-flying one) (%).
    FlyingFhmMax,
    /// Slope of a segment of `c̄(h)` (nm/nm).
    Slope(SlopeName),
    /// Regime boundary above `below`: midpoint between the last case whose regime is `below`
    /// or lower and the first case past it (m).
    RegimeBoundary { below: Regime },
    /// First sweep actuation that is not flying (lubricant contact onset) (m).
    LubricantContactOnset,
    /// First sweep actuation with 100 % of the steady window in solid contact (m).
    FullContactOnset,
    /// Mean clearance of the first sweep case that touches (m).
    TouchdownClearance,
    /// FHM/BV of the first sweep case that touches (%).
    TouchdownVibration,
    /// Largest mean shear traction over the sweep (Pa).
    MaxShearTraction,
}

impl Quantity {
    fn actuation(self) -> Option<f64> {
        match self {
            Quantity::Clearance { actuation }
            | Quantity::Vibration { actuation }
            | Quantity::ContactForce { actuation }
            | Quantity::FrictionForce { actuation }
            | Quantity::Adhesion { actuation }
            | Quantity::FrictionCoefficient { actuation }
            | Quantity::MeanPressure { actuation }
            | Quantity::ShearTraction { actuation }
            | Quantity::RealArea { actuation } => Some(actuation),
            _ => None,
        }
    }

    /// Needs the sweep grid (a held-out quantity: too costly to evaluate inside the fit).
    pub fn needs_sweep(self) -> bool {
        self.actuation().is_none() && self != Quantity::Touchdown
    }
}

/// The bulge a target is measured on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TargetGeometry {
    Base,
    /// §2.3 optimised design, a = 4.86 µm, x = 6.35 µm, w = 50 µm [assumption].
    Optimised,
}

/// Which set a target belongs to (docs/calibration.md): the fit's objective sees only the
/// fitted set; the held-out sets judge the fit on numbers it never saw. Of those, the
/// *selection* set is what model-form switches are chosen on (docs/model-form.md), and the
/// *final* set is evaluated once per adopted configuration and never tuned on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum TargetSet {
    Fitted,
    Selection,
    Final,
}

impl TargetSet {
    pub fn name(self) -> &'static str {
        match self {
            TargetSet::Fitted => "fitted",
            TargetSet::Selection => "selection",
            TargetSet::Final => "final",
        }
    }

    /// Not in the fit's objective.
    pub fn held_out(self) -> bool {
        self != TargetSet::Fitted
    }
}

/// A published number and its tolerance (docs/validation.md). The objective is
/// `Σ weight·((value − published)/tolerance)²` over the fitted set.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Target {
    /// Stable id used in `pipeline.toml` (`targets = [...]`) and tables.
    pub id: &'static str,
    pub quantity: Quantity,
    /// SI value (%, for vibration).
    pub published: f64,
    /// Half-width of the spec's band, same unit.
    pub tolerance: f64,
    /// Row of the published-number table (docs/validation.md).
    pub source: &'static str,
    /// Class of the spec's target table (K or D).
    pub class: &'static str,
    /// Display unit and the factor SI → display.
    pub unit: &'static str,
    pub display_scale: f64,
    /// Which bulge the cases use: the base model's, or the optimised design of §2.3 (w = 50 µm
    /// assumed).
    pub geometry: TargetGeometry,
    pub set: TargetSet,
    /// Weight of the squared residual in the objective (fitted set only): 1 for class D; 10
    /// for the class-K anchor, which the dissertation's model meets regardless of the dropped
    /// inputs, so a fit must not trade it; 0 for a target reported with the fitted set but out
    /// of reach of every knob.
    pub weight: f64,
}

impl Target {
    fn optimised(self) -> Target {
        Target {
            geometry: TargetGeometry::Optimised,
            ..self
        }
    }
    fn held_out(self) -> Target {
        Target {
            set: TargetSet::Selection,
            ..self
        }
    }
    fn weight(self, weight: f64) -> Target {
        Target { weight, ..self }
    }
    fn class_k(self) -> Target {
        Target { class: "K", ..self }
    }
}

/// The fitted set of the improved 2-DOF model (S2, dissertation geometry): the class-D
/// numbers of dynamics.md §12.2 #16, #18, #19, #23, #24 that one case (or the touchdown
/// search) gives, plus the class-K anchor at 8.5 nm that a calibration must not break.
pub fn improved_targets() -> Vec<Target> {
    let nm = |v: f64| v * NM;
    vec![
        t(
            "touchdown",
            Quantity::Touchdown,
            nm(9.7),
            nm(0.2),
            "#16",
            "nm",
            1e9,
        ),
        // Class-K anchor as a penalty (weight 10): the dissertation's model meets it whatever
        // the dropped inputs were, so the fit may not buy class-D numbers with it.
        t(
            "clearance_8.5nm",
            Quantity::Clearance { actuation: nm(8.5) },
            nm(2.54),
            nm(0.05),
            "#18",
            "nm",
            1e9,
        )
        .class_k()
        .weight(10.0),
        t(
            "fhm_8.5nm",
            Quantity::Vibration { actuation: nm(8.5) },
            8.20,
            4.10,
            "#18",
            "%",
            1.0,
        ),
    ]
    .into_iter()
    .chain(reported_with_the_fitted_set())
    .collect()
}

/// The fitted set's weight-0 members: reported beside the fit, out of reach of every knob.
fn reported_with_the_fitted_set() -> Vec<Target> {
    let nm = |v: f64| v * NM;
    let gpa = |v: f64| v * 1e9;
    vec![
        // Reported with the fitted set, weight 0: out of reach of every knob
        // (docs/calibration.md) — the 9.5 nm clearance needs a jump to contact from 8.6 nm that
        // no LJ range in bounds gives, the 12 nm interference a contact ~10× stiffer than the
        // seeded η, R allow; fitting them drags the reachable targets out of their bands.
        t(
            "clearance_9.5nm",
            Quantity::Clearance { actuation: nm(9.5) },
            nm(0.67),
            nm(0.2),
            "#19",
            "nm",
            1e9,
        )
        .weight(0.0),
        t(
            "fhm_9.5nm",
            Quantity::Vibration { actuation: nm(9.5) },
            9.29,
            4.645,
            "#19",
            "%",
            1.0,
        ),
        t(
            "shear_traction_9.8nm",
            Quantity::ShearTraction { actuation: nm(9.8) },
            gpa(3.24),
            gpa(1.62),
            "#23",
            "GPa",
            1e-9,
        ),
        t(
            "clearance_12nm",
            Quantity::Clearance {
                actuation: nm(12.0),
            },
            nm(-0.34),
            nm(0.15),
            "#24",
            "nm",
            1e9,
        )
        .weight(0.0),
        t(
            "contact_force_12nm",
            Quantity::ContactForce {
                actuation: nm(12.0),
            },
            1.63e-3,
            0.815e-3,
            "#24",
            "mN",
            1e3,
        ),
        t(
            "friction_force_12nm",
            Quantity::FrictionForce {
                actuation: nm(12.0),
            },
            2.43e-3,
            1.215e-3,
            "#24",
            "mN",
            1e3,
        ),
        t(
            "adhesion_12nm",
            Quantity::Adhesion {
                actuation: nm(12.0),
            },
            0.98e-3,
            0.49e-3,
            "#24",
            "mN",
            1e3,
        ),
        t(
            "friction_coefficient_12nm",
            Quantity::FrictionCoefficient {
                actuation: nm(12.0),
            },
            1.49,
            0.30,
            "#24",
            "1",
            1.0,
        ),
        t(
            "mean_pressure_12nm",
            Quantity::MeanPressure {
                actuation: nm(12.0),
            },
            gpa(4.47),
            gpa(2.235),
            "#24",
            "GPa",
            1e-9,
        ),
        t(
            "shear_traction_12nm",
            Quantity::ShearTraction {
                actuation: nm(12.0),
            },
            gpa(6.68),
            gpa(3.34),
            "#24",
            "GPa",
            1e-9,
        ),
        t(
            "real_area_12nm",
            Quantity::RealArea {
                actuation: nm(12.0),
            },
            0.36e-12,
            0.18e-12,
            "#24",
            "µm²",
            1e12,
        ),
    ]
}

/// The held-out set of the improved 2-DOF model: targets the fit never sees — the
/// dissertation geometry's sweep landmarks (critical point #17, regimes #20, slopes #21,
/// full contact #22, c̄ at touchdown #16, peak shear traction #25) and the optimised design of
/// §2.3 (#26, #27, #29). Judged on the sweep grid of the base instance before and after the fit.
///
/// The dissertation geometry's landmarks are the *selection* set; the optimised design's are
/// the *final* set: another bulge, which no fit and no choice of model form has looked at, so
/// it tests whether a choice generalises (docs/model-form.md, "Selection discipline").
pub fn improved_held_out() -> Vec<Target> {
    improved_held_out_targets()
        .into_iter()
        .map(|t| match t.geometry {
            TargetGeometry::Base => t,
            TargetGeometry::Optimised => Target {
                set: TargetSet::Final,
                ..t
            },
        })
        .collect()
}

fn improved_held_out_targets() -> Vec<Target> {
    let mut targets = held_out_on_the_dissertation_geometry();
    targets.extend(held_out_on_the_optimised_design());
    targets
}

/// Held out on the dissertation geometry (§12.2 #16–#25): the selection set.
fn held_out_on_the_dissertation_geometry() -> Vec<Target> {
    let nm = |v: f64| v * NM;
    let gpa = |v: f64| v * 1e9;
    let s = |id, q, p, tol, src, unit, scale| t(id, q, p, tol, src, unit, scale).held_out();
    vec![
        s(
            "cp_actuation",
            Quantity::CriticalPointActuation,
            nm(8.6),
            nm(0.2),
            "#17",
            "nm",
            1e9,
        ),
        s(
            "cp_clearance",
            Quantity::CriticalPointClearance,
            nm(2.39),
            nm(0.15),
            "#17",
            "nm",
            1e9,
        ),
        s(
            "fhm_max_flying",
            Quantity::FlyingFhmMax,
            14.01,
            7.005,
            "#17",
            "%",
            1.0,
        ),
        s(
            "touchdown_clearance",
            Quantity::TouchdownClearance,
            nm(0.49),
            nm(0.2),
            "#16",
            "nm",
            1e9,
        ),
        s(
            "regime_flying_end",
            Quantity::RegimeBoundary {
                below: Regime::Flying,
            },
            nm(8.65),
            nm(0.3),
            "#20",
            "nm",
            1e9,
        ),
        s(
            "regime_bonded_start",
            Quantity::RegimeBoundary {
                below: Regime::MobileLubricantContact,
            },
            nm(9.5),
            nm(0.3),
            "#20",
            "nm",
            1e9,
        ),
        s(
            "regime_solid_start",
            Quantity::RegimeBoundary {
                below: Regime::BondedLubricantContact,
            },
            nm(10.4),
            nm(0.3),
            "#20",
            "nm",
            1e9,
        ),
        s(
            "slope_A",
            Quantity::Slope(SlopeName::A),
            -1.0,
            0.02,
            "#21",
            "1",
            1.0,
        )
        .class_k(),
        s(
            "slope_B",
            Quantity::Slope(SlopeName::B),
            -4.4,
            1.32,
            "#21",
            "1",
            1.0,
        ),
        s(
            "slope_C",
            Quantity::Slope(SlopeName::C),
            -1.0,
            0.3,
            "#21",
            "1",
            1.0,
        ),
        s(
            "slope_D",
            Quantity::Slope(SlopeName::D),
            -0.2,
            0.06,
            "#21",
            "1",
            1.0,
        ),
        s(
            "full_contact_onset",
            Quantity::FullContactOnset,
            nm(11.4),
            nm(0.4),
            "#22",
            "nm",
            1e9,
        ),
        s(
            "max_shear_traction",
            Quantity::MaxShearTraction,
            gpa(6.69),
            gpa(3.345),
            "#25",
            "GPa",
            1e-9,
        ),
    ]
}

/// Held out on the optimised design (§12.2 #26–#29): the final set.
fn held_out_on_the_optimised_design() -> Vec<Target> {
    let nm = |v: f64| v * NM;
    let gpa = |v: f64| v * 1e9;
    let s = |id, q, p, tol, src, unit, scale| t(id, q, p, tol, src, unit, scale).held_out();
    vec![
        s(
            "optimised_touchdown",
            Quantity::Touchdown,
            nm(9.9),
            nm(0.2),
            "#26",
            "nm",
            1e9,
        )
        .optimised(),
        s(
            "optimised_cp_actuation",
            Quantity::CriticalPointActuation,
            nm(8.6),
            nm(0.2),
            "#26",
            "nm",
            1e9,
        )
        .optimised(),
        s(
            "optimised_cp_clearance",
            Quantity::CriticalPointClearance,
            nm(2.23),
            nm(0.15),
            "#26",
            "nm",
            1e9,
        )
        .optimised(),
        s(
            "optimised_clearance_8.6nm",
            Quantity::Clearance { actuation: nm(8.6) },
            nm(2.23),
            nm(0.15),
            "#26",
            "nm",
            1e9,
        )
        .optimised(),
        s(
            "optimised_lubricant_onset",
            Quantity::LubricantContactOnset,
            nm(9.0),
            nm(0.2),
            "#26",
            "nm",
            1e9,
        )
        .optimised(),
        s(
            "optimised_touchdown_clearance",
            Quantity::TouchdownClearance,
            nm(0.55),
            nm(0.15),
            "#26",
            "nm",
            1e9,
        )
        .optimised(),
        s(
            "optimised_fhm_8.6nm",
            Quantity::Vibration { actuation: nm(8.6) },
            6.67,
            3.335,
            "#27",
            "%",
            1.0,
        )
        .optimised(),
        s(
            "optimised_fhm_touchdown",
            Quantity::TouchdownVibration,
            11.42,
            5.71,
            "#27",
            "%",
            1.0,
        )
        .optimised(),
        s(
            "optimised_shear_traction_13nm",
            Quantity::ShearTraction {
                actuation: nm(13.0),
            },
            gpa(6.64),
            gpa(3.32),
            "#29",
            "GPa",
            1e-9,
        )
        .optimised(),
        s(
            "optimised_mean_pressure_13nm",
            Quantity::MeanPressure {
                actuation: nm(13.0),
            },
            gpa(4.88),
            gpa(2.44),
            "#29",
            "GPa",
            1e-9,
        )
        .optimised(),
    ]
}

/// The class-D targets of the initial 2-DOF model (S1; S1c calibrates `n` to the touchdown).
pub fn initial_targets() -> Vec<Target> {
    let nm = |v: f64| v * NM;
    vec![
        t(
            "touchdown",
            Quantity::Touchdown,
            nm(9.8),
            nm(0.2),
            "#7",
            "nm",
            1e9,
        ),
        t(
            "fhm_5.5nm",
            Quantity::Vibration { actuation: nm(5.5) },
            12.5,
            6.25,
            "#9",
            "%",
            1.0,
        ),
        t(
            "clearance_11nm",
            Quantity::Clearance {
                actuation: nm(11.0),
            },
            nm(-0.58),
            nm(0.2),
            "#11",
            "nm",
            1e9,
        ),
        t(
            "contact_force_11nm",
            Quantity::ContactForce {
                actuation: nm(11.0),
            },
            1.0e-3,
            0.5e-3,
            "#12",
            "mN",
            1e3,
        ),
        t(
            "friction_coefficient_11nm",
            Quantity::FrictionCoefficient {
                actuation: nm(11.0),
            },
            1.3,
            0.3,
            "#12",
            "1",
            1.0,
        ),
    ]
}

fn t(
    id: &'static str,
    quantity: Quantity,
    published: f64,
    tolerance: f64,
    source: &'static str,
    unit: &'static str,
    display_scale: f64,
) -> Target {
    Target {
        id,
        quantity,
        published,
        tolerance,
        source,
        class: "D",
        unit,
        display_scale,
        geometry: TargetGeometry::Base,
        set: TargetSet::Fitted,
        weight: 1.0,
    }
}

/// The fitted-set catalogue of a model variant.
pub fn targets_for(variant: ModelVariant) -> Vec<Target> {
    match variant {
        ModelVariant::Improved => improved_targets(),
        ModelVariant::Initial => initial_targets(),
    }
}

/// The held-out catalogue of a model variant (none for the initial model: the dissertation
/// gives it no sweep landmarks beyond its fitted ones).
pub fn held_out_for(variant: ModelVariant) -> Vec<Target> {
    match variant {
        ModelVariant::Improved => improved_held_out(),
        ModelVariant::Initial => Vec::new(),
    }
}
/// The knobs calibrated by default for a model variant (docs/calibration.md: DMW content, β, Δγ,
/// ε, ζ_c; the initial model has no stiffening and calibrates `n` instead, S1c).
pub fn default_knobs(variant: ModelVariant) -> Vec<Knob> {
    match variant {
        ModelVariant::Improved => vec![
            Knob::DmwScale,
            Knob::KrStiffeningBeta,
            Knob::SurfaceEnergy,
            Knob::LjSpacing,
            Knob::ContactDamping,
        ],
        ModelVariant::Initial => vec![
            Knob::DmwScale,
            Knob::TruncationN,
            Knob::SurfaceEnergy,
            Knob::LjSpacing,
            Knob::ContactDamping,
        ],
    }
}

/// What the cases of the calibration start from.
pub struct CalibrationBase<'a> {
    pub model: Model2Dof,
    pub isbl: IsblParams,
    pub dmw: Option<DmwInput<'a>>,
    pub options: SimOptions,
    pub case_params: CaseParams,
    /// `contact_law = "bem"`: the measured contact law replacing ISBL's contact channels in
    /// every table (docs/model-form.md, "Contact law"); `None`: ISBL.
    pub contact_law: Option<std::sync::Arc<crate::contact::bem::law::ContactCurve>>,
    /// Who computes the cases of a round: `None` is this process's thread pool (the fit's
    /// own code path); a [`CaseRounds`] can send them elsewhere (Slurm arrays, docs/slurm.md
    /// "Calibration on Slurm"). The driver (the search, the touchdown scan) stays here.
    pub rounds: Option<&'a dyn CaseRounds>,
}

/// One round of the fit's cases: independent cases at one point of knob space on one
/// geometry, at several actuations (a trial point's target cases, a touchdown scan or
/// refinement batch, a held-out sweep). Everything a case depends on besides the base.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CaseRound<'r> {
    pub knobs: &'r [(Knob, f64)],
    pub geometry: TargetGeometry,
    pub actuations: &'r [f64],
}

/// Computes a round's cases somewhere else than this process's thread pool; each metric must
/// be what [`round_case`] gives for that case (bit for bit: the fit's decisions compare
/// them), in the order of `round.actuations`.
pub trait CaseRounds: Sync {
    fn run_round(&self, round: &CaseRound) -> Result<Vec<CaseMetrics>>;
}

/// One case of a round, computed here: what [`CaseRounds::run_round`] must reproduce (a
/// worker process calls this with the same base, rebuilt from the same inputs).
pub fn round_case(
    base: &CalibrationBase,
    knobs: &[(Knob, f64)],
    geometry: TargetGeometry,
    actuation: f64,
) -> Result<CaseMetrics> {
    let p = prepare(base, knobs)?;
    on_geometry(&p, geometry)?.case(actuation)
}

/// The prepared cases of `p` on `geometry` (the optimised bulge replaces the base's).
fn on_geometry<'a>(p: &Prepared<'a>, geometry: TargetGeometry) -> Result<Prepared<'a>> {
    Ok(match geometry {
        TargetGeometry::Base => p.clone(),
        TargetGeometry::Optimised => Prepared {
            model: p.model.with_bulge(optimised_bulge(OPTIMISED_WIDTH)?),
            geometry,
            ..p.clone()
        },
    })
}

/// Search settings.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CalibrationSettings {
    pub knobs: Vec<KnobRange>,
    /// The fitted set: the only targets the objective sees.
    pub targets: Vec<Target>,
    /// The held-out set: evaluated before and after the fit, never inside it.
    pub held_out: Vec<Target>,
    /// Actuations of the held-out sweeps (the base instance's grid), sorted.
    pub sweep_grid: Vec<f64>,
    pub search: NelderMeadOptions,
    /// Touchdown search of the fitted set (the one convention, docs/conventions.md): scan from
    /// 0 nm on `step`, refine the first crossing to `resolution`.
    pub touchdown: TouchdownSearch,
    /// Start point of the search (SI) for the knobs listed; the others start at the spec
    /// defaults. The fitted set at the spec defaults is evaluated (and reported) either way.
    pub start: KnobValues,
    /// Skip the touchdown search of a trial point whose other targets already decide its
    /// Nelder–Mead comparison (same trajectory, fewer cases; off only to test that).
    pub early_rejection: bool,
}

impl CalibrationSettings {
    pub fn new(knobs: Vec<KnobRange>, targets: Vec<Target>) -> Self {
        CalibrationSettings {
            knobs,
            targets,
            held_out: Vec::new(),
            sweep_grid: Vec::new(),
            search: NelderMeadOptions {
                initial_step: 0.2,
                max_evaluations: DEFAULT_MAX_EVALUATIONS,
                f_tolerance: 1e-3,
                x_tolerance: 2e-3,
            },
            // 0.5 nm scan, 4 cases at a time [choice, docs/calibration.md]: flying cases are
            // cheap, the scan costs ~20 of them, and 4 keeps both cores busy with little waste
            // past the crossing; the refinement is 4 rounds of 4.
            touchdown: TouchdownSearch::convention(15.0 * NM, 0.5 * NM, 4),
            start: Vec::new(),
            early_rejection: true,
        }
    }
}

/// Default Nelder–Mead budget (objective evaluations) [choice, measured in docs/calibration.md].
pub const DEFAULT_MAX_EVALUATIONS: usize = 400;
/// Values of the calibrated knobs (SI), in the order of the settings.
pub type KnobValues = Vec<(Knob, f64)>;

/// What one target evaluated to.
#[derive(Debug, Clone, PartialEq)]
pub struct TargetOutcome {
    pub target: Target,
    /// SI; `None` when the case gives no such number (e.g. no contact force while flying).
    pub value: Option<f64>,
    /// `(value − published)/tolerance`; a missing value (no contact: no force, no μ) counts
    /// as 0.
    pub normalised_residual: f64,
}

impl TargetOutcome {
    pub fn within_tolerance(&self) -> bool {
        self.value.is_some() && self.normalised_residual.abs() <= 1.0
    }
}

/// One objective evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    pub knobs: KnobValues,
    pub outcomes: Vec<TargetOutcome>,
    /// `Σ weight·residual²`.
    pub objective: f64,
    /// Cases simulated for this evaluation.
    pub cases: usize,
}

/// The fit.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationResult {
    /// Fitted set at the spec defaults.
    pub initial: Evaluation,
    /// Fitted set at the best point found.
    pub best: Evaluation,
    /// Held-out set at the spec defaults and at the best point (`None` without a held-out set).
    pub held_out_initial: Option<Evaluation>,
    pub held_out_best: Option<Evaluation>,
    /// `(evaluation index, objective, best so far, exact)`; an early-rejected trial point
    /// (`exact` false) records the lower bound that decided it (docs/calibration.md).
    pub history: Vec<(usize, f64, f64, bool)>,
    /// The simplex met both tolerances (`stop` says what ended the run).
    pub converged: bool,
    pub stop: StopReason,
    /// Objective spread (worst − best) and unit-box edge of the final simplex.
    pub final_f_spread: f64,
    pub final_x_spread: f64,
    pub evaluations: usize,
    /// Trial points rejected early (their touchdown search skipped).
    pub rejected: usize,
    pub cases: usize,
    /// Knob values where a case failed (counted as an infeasible point), with the error.
    pub failures: Vec<(KnobValues, String)>,
    /// Knobs that ended on a face of their box (within [`AT_BOUND_UNIT`] of the unit box).
    pub at_bound: Vec<(Knob, Bound)>,
}

/// Targets in band / targets of an evaluation.
pub fn in_band(e: &Evaluation) -> (usize, usize) {
    (
        e.outcomes.iter().filter(|o| o.within_tolerance()).count(),
        e.outcomes.len(),
    )
}

/// Apply knob values to copies of the base inputs; returns the DMW scale.
pub fn apply_knobs(
    values: &[(Knob, f64)],
    model: &mut Model2Dof,
    isbl: &mut IsblParams,
) -> Result<f64> {
    let mut dmw_scale = 1.0;
    for &(k, v) in values {
        if !v.is_finite() {
            return Err(DynamicsError::parameter(k.name(), v, "must be finite"));
        }
        match k {
            Knob::DmwScale => dmw_scale = v,
            Knob::KrStiffeningBeta => {
                if model.variant != ModelVariant::Improved {
                    return Err(DynamicsError::Numerical(
                        "knob kr_stiffening_beta belongs to the improved model".into(),
                    ));
                }
                model.air_bearing.stiffening = if v == 0.0 {
                    RearStiffening::Constant
                } else {
                    RearStiffening::Quadratic { beta: v }
                };
            }
            Knob::SurfaceEnergy => {
                isbl.surface_energy = SurfaceEnergy::Constant { delta_gamma: v };
                model.interface.surface_energy = v;
            }
            Knob::LjSpacing => {
                isbl.lj_spacing = v;
                model.interface.equilibrium_spacing = v;
            }
            Knob::ContactDamping => model.interface.contact_damping_ratio = v,
            Knob::TruncationN => match model.interface.criterion {
                ContactCriterion::NSigma { .. } => {
                    model.interface.criterion = ContactCriterion::NSigma { n: v }
                }
                _ => {
                    return Err(DynamicsError::Numerical(
                        "knob truncation_n belongs to the initial model (nσ criterion)".into(),
                    ))
                }
            },
            Knob::AsperityDensity => {
                isbl.summit_density = v;
                model.interface.asperity_density = Some(v);
            }
        }
    }
    model.validate()?;
    Ok(dmw_scale)
}

/// ISBL table of the 2-DOF cases (the simulate stage's grid).
pub fn interface_table(isbl: IsblParams) -> Result<IsblLookup> {
    interface_table_with(isbl, None)
}

/// [`interface_table`] with the contact channels from a measured law when given.
pub fn interface_table_with(
    isbl: IsblParams,
    law: Option<&std::sync::Arc<crate::contact::bem::law::ContactCurve>>,
) -> Result<IsblLookup> {
    IsblModel::new(isbl)
        .and_then(|m| match law {
            Some(l) => IsblLookup::build_with_contact_law(m, std::sync::Arc::clone(l)),
            None => IsblLookup::build_standard_unverified(m),
        })
        .map_err(|e| DynamicsError::Numerical(format!("interface table: {e}")))
}

/// Full width of the optimised bulge (dropped in the text) [assumption, as the shipped
/// `optimised_sweep`].
const OPTIMISED_WIDTH: f64 = 50e-6;

/// The DMW track times the `dmw_scale` knob.
struct ScaledDmw {
    displacement: Vec<f64>,
    velocity: Vec<f64>,
    sample_rate: f64,
}

#[derive(Clone)]
struct Prepared<'a> {
    model: Model2Dof,
    lookup: std::sync::Arc<IsblLookup>,
    dmw: std::sync::Arc<Option<ScaledDmw>>,
    base: &'a CalibrationBase<'a>,
    /// What a [`CaseRound`] names (knobs applied above, geometry of `model`'s bulge).
    knobs: std::sync::Arc<KnobValues>,
    geometry: TargetGeometry,
}

impl Prepared<'_> {
    fn case(&self, actuation: f64) -> Result<CaseMetrics> {
        let input = self.dmw.as_ref().as_ref().map(|d| DmwInput {
            displacement: &d.displacement,
            velocity: &d.velocity,
            sample_rate: d.sample_rate,
        });
        let case = TwoDofCase::new(
            &self.model,
            actuation,
            &self.lookup,
            input,
            self.base.options,
        )?;
        let h = case.run().map_err(|e| {
            DynamicsError::Numerical(format!("case h_TFC = {:.3} nm: {e}", actuation / NM))
        })?;
        h.metrics(&self.base.case_params)
    }

    fn cases(&self, actuations: &[f64]) -> Result<Vec<CaseMetrics>> {
        match self.base.rounds {
            Some(rounds) => rounds.run_round(&CaseRound {
                knobs: &self.knobs,
                geometry: self.geometry,
                actuations,
            }),
            None => actuations.par_iter().map(|&a| self.case(a)).collect(),
        }
    }
}

fn prepare<'a>(base: &'a CalibrationBase<'a>, values: &[(Knob, f64)]) -> Result<Prepared<'a>> {
    let (mut model, mut isbl) = (base.model, base.isbl);
    let scale = apply_knobs(values, &mut model, &mut isbl)?;
    let dmw = match &base.dmw {
        Some(d) => Some(ScaledDmw {
            displacement: d.displacement.iter().map(|x| x * scale).collect(),
            velocity: d.velocity.iter().map(|x| x * scale).collect(),
            sample_rate: d.sample_rate,
        }),
        None if values.iter().any(|(k, _)| *k == Knob::DmwScale) => {
            return Err(DynamicsError::Numerical(
                "knob dmw_scale needs a DMW input (dmw = \"none\")".into(),
            ))
        }
        None => None,
    };
    Ok(Prepared {
        model,
        lookup: std::sync::Arc::new(interface_table_with(isbl, base.contact_law.as_ref())?),
        dmw: std::sync::Arc::new(dmw),
        base,
        knobs: std::sync::Arc::new(values.to_vec()),
        geometry: TargetGeometry::Base,
    })
}

/// Evaluate the fitted set at given knob values (the spec defaults when `values` is empty):
/// exactly what the objective sees.
pub fn evaluate(
    base: &CalibrationBase,
    settings: &CalibrationSettings,
    values: &[(Knob, f64)],
) -> Result<Evaluation> {
    match evaluate_set(base, settings, &settings.targets, &[], values, None)? {
        Scored::Full(e) => Ok(e),
        Scored::Rejected { .. } => unreachable!("no cutoff offered"),
    }
}

/// The fitted set at `values`, or only a lower bound of its objective when that already
/// decides `cutoff`: the target cases run first, and the touchdown search (most of an
/// evaluation's cases) is skipped when the other targets' terms reach the cutoff.
fn evaluate_with_cutoff(
    base: &CalibrationBase,
    settings: &CalibrationSettings,
    values: &[(Knob, f64)],
    cutoff: Option<Cutoff>,
) -> Result<Scored> {
    evaluate_set(base, settings, &settings.targets, &[], values, cutoff)
}

/// An evaluation, or the lower bound of its objective that rejected it.
enum Scored {
    Full(Evaluation),
    Rejected { lower_bound: f64, cases: usize },
}

/// Evaluate the held-out set at given knob values: the base instance's sweep grid on each
/// geometry, with the sweep metrics (`dynamics::metrics`) of that grid.
pub fn evaluate_held_out(
    base: &CalibrationBase,
    settings: &CalibrationSettings,
    values: &[(Knob, f64)],
) -> Result<Evaluation> {
    match evaluate_set(
        base,
        settings,
        &settings.held_out,
        &settings.sweep_grid,
        values,
        None,
    )? {
        Scored::Full(e) => Ok(e),
        Scored::Rejected { .. } => unreachable!("no cutoff offered"),
    }
}

/// `(value − published)/tolerance`; a missing or non-finite number counts as 0 (no contact →
/// no force, no μ).
fn residual(t: &Target, value: Option<f64>) -> f64 {
    (value.filter(|v| v.is_finite()).unwrap_or(0.0) - t.published) / t.tolerance
}

fn evaluate_set(
    base: &CalibrationBase,
    settings: &CalibrationSettings,
    all: &[Target],
    grid: &[f64],
    values: &[(Knob, f64)],
    cutoff: Option<Cutoff>,
) -> Result<Scored> {
    let p = prepare(base, values)?;
    let mut by_id = Vec::new();
    let mut cases = 0;
    for geometry in [TargetGeometry::Base, TargetGeometry::Optimised] {
        let targets: Vec<&Target> = all.iter().filter(|t| t.geometry == geometry).collect();
        if targets.is_empty() {
            continue;
        }
        let prepared = on_geometry(&p, geometry)?;
        let (values, n, rejected) = evaluate_targets(&prepared, settings, &targets, grid, cutoff)?;
        cases += n;
        if let Some(lower_bound) = rejected {
            return Ok(Scored::Rejected { lower_bound, cases });
        }
        by_id.extend(targets.iter().map(|t| t.id).zip(values));
    }
    let outcomes = all
        .iter()
        .map(|t| {
            let value = by_id
                .iter()
                .find(|(id, _)| *id == t.id)
                .and_then(|(_, v)| *v)
                .filter(|v| v.is_finite());
            // No contact → no force, no μ: the residual of a missing number is that of 0.
            let r = residual(t, value);
            TargetOutcome {
                target: t.clone(),
                value,
                normalised_residual: r,
            }
        })
        .collect::<Vec<_>>();
    let objective = outcomes
        .iter()
        .map(|o| o.target.weight * o.normalised_residual * o.normalised_residual)
        .sum();
    Ok(Scored::Full(Evaluation {
        knobs: values.to_vec(),
        outcomes,
        objective,
        cases,
    }))
}

/// The values of targets on one geometry, how many cases that took, and — when `cutoff`
/// rejected the point before the touchdown search — the lower bound of the objective that
/// did (the weighted squared residuals of the other targets: every term is ≥ 0, and a
/// rounded sum of non-negative terms never exceeds the rounded sum with more of them).
/// `grid` is the sweep of the held-out set (empty for the fitted set: then only the target
/// actuations run).
fn evaluate_targets(
    p: &Prepared,
    settings: &CalibrationSettings,
    targets: &[&Target],
    grid: &[f64],
    cutoff: Option<Cutoff>,
) -> Result<(Vec<Option<f64>>, usize, Option<f64>)> {
    let needs_sweep = targets.iter().any(|t| t.quantity.needs_sweep());
    let mut actuations: Vec<f64> = targets
        .iter()
        .filter_map(|t| t.quantity.actuation())
        .collect();
    if needs_sweep || !grid.is_empty() {
        actuations.extend_from_slice(grid);
    }
    actuations.sort_by(f64::total_cmp);
    actuations.dedup_by(|a, b| (*a - *b).abs() <= 1e-6 * NM);
    let metrics = p.cases(&actuations)?;
    let mut cases = actuations.len();
    let at = |a: f64| {
        actuations
            .iter()
            .position(|x| (*x - a).abs() <= 1e-6 * NM)
            .map(|i| &metrics[i])
    };
    let contact = |a: f64| at(a).and_then(|m| m.contact.as_ref());
    let sweep = if needs_sweep && actuations.len() >= 2 {
        let points: Vec<SweepPoint> = actuations
            .iter()
            .zip(&metrics)
            .map(|(a, m)| SweepPoint::from_case(*a, m))
            .collect();
        let cp = &p.base.case_params;
        let m = sweep_metrics(&points, &SlopeParams::new(cp.t0_m), cp.fh_nom_m)
            .map_err(|e| DynamicsError::Numerical(format!("sweep metrics: {e}")))?;
        Some((points, m))
    } else {
        None
    };
    // Every value but the touchdown's comes from the cases above.
    let mut values: Vec<Option<f64>> = targets
        .iter()
        .map(|t| match t.quantity {
            Quantity::Touchdown => None,
            Quantity::Clearance { actuation } => at(actuation).map(|m| m.clearance_m.mean),
            Quantity::Vibration { actuation } => at(actuation).map(|m| m.vibration.percent),
            Quantity::ContactForce { actuation } => {
                contact(actuation).map(|c| c.contact_force_n.mean)
            }
            Quantity::FrictionForce { actuation } => contact(actuation).map(|c| c.friction_n.mean),
            Quantity::Adhesion { actuation } => contact(actuation)
                .and_then(|c| c.adhesion_n.as_ref())
                .map(|s| s.mean),
            // μ, P_m and τ as ratios of means over the steady window (docs/conventions.md).
            Quantity::FrictionCoefficient { actuation } => {
                contact(actuation).and_then(|c| c.friction_coefficient_ratio_of_means)
            }
            Quantity::MeanPressure { actuation } => {
                contact(actuation).and_then(|c| c.mean_pressure_pa_ratio_of_means)
            }
            Quantity::ShearTraction { actuation } => {
                contact(actuation).and_then(|c| c.shear_traction_pa_ratio_of_means)
            }
            Quantity::RealArea { actuation } => contact(actuation).map(|c| c.real_area_m2.mean),
            q => sweep
                .as_ref()
                .and_then(|(pts, m)| sweep_value(q, pts, m, &metrics)),
        })
        .collect();
    let needs_touchdown = targets.iter().any(|t| t.quantity == Quantity::Touchdown);
    if let (Some(c), true) = (cutoff, needs_touchdown) {
        let partial: f64 = targets
            .iter()
            .zip(&values)
            .filter(|(t, _)| t.quantity != Quantity::Touchdown)
            .map(|(t, v)| {
                let r = residual(t, *v);
                t.weight * r * r
            })
            .sum();
        if c.rejects(partial) {
            return Ok((values, cases, Some(partial)));
        }
    }
    if needs_touchdown {
        let known: Vec<(f64, bool)> = actuations
            .iter()
            .zip(&metrics)
            .map(|(a, m)| (*a, touches(m)))
            .collect();
        // With a sweep, its own grid is the scan (when uniform from its first point): the
        // sweep's cases are then reused and only the refinement runs.
        let search = uniform_scan(grid, settings.touchdown).unwrap_or(settings.touchdown);
        let td = find_touchdown(&search, &known, |a| {
            Ok::<_, DynamicsError>(p.cases(a)?.iter().map(touches).collect())
        })?;
        cases += td.cases_run;
        for (t, v) in targets.iter().zip(values.iter_mut()) {
            if t.quantity == Quantity::Touchdown {
                *v = td.actuation;
            }
        }
    }
    Ok((values, cases, None))
}

/// Solid contact anywhere in the steady window (the touchdown criterion).
fn touches(m: &CaseMetrics) -> bool {
    m.clearance_m.min < 0.0
}

/// The scan of a uniform sweep grid (with the search's resolution and batch), if it is one.
fn uniform_scan(grid: &[f64], base: TouchdownSearch) -> Option<TouchdownSearch> {
    let (first, last) = (*grid.first()?, *grid.last()?);
    if grid.len() < 2 {
        return None;
    }
    let step = (last - first) / (grid.len() - 1) as f64;
    let uniform = grid
        .iter()
        .enumerate()
        .all(|(i, a)| (a - (first + i as f64 * step)).abs() <= 1e-6 * step);
    uniform.then_some(TouchdownSearch {
        start: first,
        stop: last,
        step,
        ..base
    })
}

/// A sweep quantity from the sweep's points and metrics.
fn sweep_value(
    q: Quantity,
    points: &[SweepPoint],
    m: &SweepMetrics,
    cases: &[CaseMetrics],
) -> Option<f64> {
    let first_not_flying = m.regimes.iter().position(|r| *r != Regime::Flying);
    match q {
        Quantity::CriticalPointActuation => m.slopes.critical_point.map(|c| c.actuation_m),
        Quantity::CriticalPointClearance => m.slopes.critical_point.map(|c| c.clearance_m),
        Quantity::FlyingFhmMax => points[..first_not_flying.unwrap_or(points.len())]
            .iter()
            .map(|p| p.vibration_percent)
            .reduce(f64::max),
        Quantity::Slope(s) => match s {
            SlopeName::A => m.slopes.a.as_ref(),
            SlopeName::B => m.slopes.b.as_ref(),
            SlopeName::C => m.slopes.c.as_ref(),
            SlopeName::D => m.slopes.d.as_ref(),
        }
        .map(|l| l.slope),
        Quantity::RegimeBoundary { below } => m
            .regimes
            .iter()
            .position(|r| *r > below)
            .filter(|&i| i > 0)
            .map(|i| 0.5 * (points[i - 1].actuation_m + points[i].actuation_m)),
        Quantity::LubricantContactOnset => first_not_flying.map(|i| points[i].actuation_m),
        Quantity::FullContactOnset => cases
            .iter()
            .position(|c| c.percent_solid_contact >= 100.0 - 1e-9)
            .map(|i| points[i].actuation_m),
        Quantity::TouchdownClearance => m.touchdown_index.map(|i| points[i].mean_clearance_m),
        Quantity::TouchdownVibration => m.touchdown_index.map(|i| points[i].vibration_percent),
        Quantity::MaxShearTraction => cases
            .iter()
            .filter_map(|c| c.contact.as_ref()?.shear_traction_pa_ratio_of_means)
            .reduce(f64::max),
        _ => None,
    }
}

/// Fit the knobs on the fitted set, then judge the fit on the held-out set (before and after).
/// `progress(evaluation, best objective)` is called after each evaluation.
pub fn calibrate(
    base: &CalibrationBase,
    settings: &CalibrationSettings,
    mut progress: impl FnMut(usize, f64),
) -> Result<CalibrationResult> {
    if settings.targets.is_empty() {
        return Err(DynamicsError::Numerical("no calibration target".into()));
    }
    if let Some(t) = settings.targets.iter().find(|t| t.quantity.needs_sweep()) {
        return Err(DynamicsError::Numerical(format!(
            "target {} needs the sweep grid: it can only be held out",
            t.id
        )));
    }
    for k in &settings.knobs {
        k.check()?;
    }
    if let Some((k, _)) = settings
        .start
        .iter()
        .find(|(k, _)| !settings.knobs.iter().any(|r| r.knob == *k))
    {
        return Err(DynamicsError::Numerical(format!(
            "start value for {}, which is not a calibrated knob",
            k.name()
        )));
    }
    let start: Vec<f64> = settings
        .knobs
        .iter()
        .map(|k| {
            let given = settings.start.iter().find(|(s, _)| *s == k.knob);
            given
                .map(|(_, v)| Ok(*v))
                .unwrap_or_else(|| k.knob.base_value(&base.model, &base.isbl))
                .map(|v| k.knob.unit_coordinate(v.clamp(k.lo, k.hi), (k.lo, k.hi)))
        })
        .collect::<Result<_>>()?;
    let to_values = |u: &[f64]| -> KnobValues {
        settings
            .knobs
            .iter()
            .zip(u)
            .map(|(k, u)| (k.knob, k.knob.value_at(*u, (k.lo, k.hi))))
            .collect()
    };
    let initial = evaluate(base, settings, &[])?;
    let mut cases = initial.cases;
    let mut best_so_far = f64::INFINITY;
    let mut history = Vec::new();
    let mut failures = Vec::new();
    let mut rejected = 0;
    // Exact evaluations by unit-box point: a point met again (the best one at the end, a
    // projected trial point that coincides with a vertex) is not simulated again — the cases
    // are deterministic, so this changes nothing but the case count.
    let mut memo: Vec<(Vec<f64>, Evaluation)> = Vec::new();
    let fit = minimize_unit_box_with_cutoff(
        |u, cutoff| -> Result<Trial> {
            // A point where a case fails (e.g. no static equilibrium) is infeasible, not fatal.
            let known = memo.iter().find(|(x, _)| x == u).map(|(_, e)| e.objective);
            let trial = match known {
                Some(f) => Trial::Exact(f),
                None => match evaluate_with_cutoff(
                    base,
                    settings,
                    &to_values(u),
                    cutoff.filter(|_| settings.early_rejection),
                ) {
                    Ok(Scored::Full(e)) => {
                        cases += e.cases;
                        let f = e.objective;
                        memo.push((u.to_vec(), e));
                        Trial::Exact(f)
                    }
                    Ok(Scored::Rejected {
                        lower_bound,
                        cases: n,
                    }) => {
                        cases += n;
                        rejected += 1;
                        Trial::AtLeast(lower_bound)
                    }
                    Err(e) => {
                        failures.push((to_values(u), e.to_string()));
                        Trial::Exact(f64::INFINITY)
                    }
                },
            };
            let (objective, exact) = match trial {
                Trial::Exact(f) => (f, true),
                Trial::AtLeast(f) => (f, false),
            };
            // A rejected point's bound is at least a simplex value, so never a new best.
            best_so_far = best_so_far.min(objective);
            history.push((history.len(), objective, best_so_far, exact));
            progress(history.len(), best_so_far);
            Ok(trial)
        },
        &start,
        &settings.search,
    )?;
    let best = match memo.iter().position(|(x, _)| *x == fit.x) {
        Some(i) => memo.swap_remove(i).1,
        None => {
            let e = evaluate(base, settings, &to_values(&fit.x))?;
            cases += e.cases;
            e
        }
    };
    let (held_out_initial, held_out_best) = if settings.held_out.is_empty() {
        (None, None)
    } else {
        let before = evaluate_held_out(base, settings, &[])?;
        let after = evaluate_held_out(base, settings, &best.knobs)?;
        cases += before.cases + after.cases;
        (Some(before), Some(after))
    };
    let at_bound = settings
        .knobs
        .iter()
        .zip(&fit.x)
        .filter_map(|(k, u)| {
            if *u <= AT_BOUND_UNIT {
                Some((k.knob, Bound::Lower))
            } else if *u >= 1.0 - AT_BOUND_UNIT {
                Some((k.knob, Bound::Upper))
            } else {
                None
            }
        })
        .collect();
    Ok(CalibrationResult {
        initial,
        best,
        held_out_initial,
        held_out_best,
        history,
        converged: fit.converged,
        stop: fit.stop,
        final_f_spread: fit.f_spread,
        final_x_spread: fit.x_spread,
        evaluations: fit.evaluations.len(),
        rejected,
        cases,
        failures,
        at_bound,
    })
}

/// A knob within this distance of a face of the unit box counts as "on its bound".
pub const AT_BOUND_UNIT: f64 = 1e-3;

/// Which bound a knob ended on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Bound {
    Lower,
    Upper,
}

impl Bound {
    pub fn name(self) -> &'static str {
        match self {
            Bound::Lower => "lower",
            Bound::Upper => "upper",
        }
    }
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::params::{improved_2dof, initial_2dof};

    #[test]
    fn knob_unit_maps_round_trip_and_respect_bounds() {
        for k in Knob::ALL {
            let r = KnobRange::new(k);
            r.check().unwrap();
            for u in [0.0, 0.25, 0.5, 1.0] {
                let v = k.value_at(u, (r.lo, r.hi));
                assert!(
                    v >= r.lo * (1.0 - 1e-12) && v <= r.hi * (1.0 + 1e-12),
                    "{k:?}"
                );
                assert!(
                    (k.unit_coordinate(v, (r.lo, r.hi)) - u).abs() < 1e-12,
                    "{k:?}"
                );
            }
            assert_eq!(Knob::from_name(k.name()), Some(k));
        }
        let bad = KnobRange {
            knob: Knob::AsperityDensity,
            lo: 0.0,
            hi: 1.0,
        };
        assert!(bad.check().is_err(), "log knob with lo = 0");
    }

    #[test]
    fn knobs_apply_to_the_right_inputs_and_refuse_the_wrong_model() {
        let (mut m, mut i) = (improved_2dof(), IsblParams::improved_2dof());
        let s = apply_knobs(
            &[
                (Knob::DmwScale, 2.0),
                (Knob::KrStiffeningBeta, 0.5),
                (Knob::SurfaceEnergy, 0.03),
                (Knob::LjSpacing, 0.5e-9),
                (Knob::ContactDamping, 0.2),
            ],
            &mut m,
            &mut i,
        )
        .unwrap();
        assert_eq!(s, 2.0);
        assert_eq!(
            m.air_bearing.stiffening,
            RearStiffening::Quadratic { beta: 0.5 }
        );
        assert_eq!(
            i.surface_energy,
            SurfaceEnergy::Constant { delta_gamma: 0.03 }
        );
        assert_eq!(i.lj_spacing, 0.5e-9);
        assert_eq!(m.interface.contact_damping_ratio, 0.2);
        assert!(apply_knobs(&[(Knob::TruncationN, 1.0)], &mut m, &mut i).is_err());
        let (mut m0, mut i0) = (initial_2dof(), IsblParams::initial_2dof());
        assert!(apply_knobs(&[(Knob::KrStiffeningBeta, 1.0)], &mut m0, &mut i0).is_err());
        apply_knobs(&[(Knob::TruncationN, 1.5)], &mut m0, &mut i0).unwrap();
        assert_eq!(m0.interface.criterion, ContactCriterion::NSigma { n: 1.5 });
        assert!(apply_knobs(&[(Knob::ContactDamping, f64::NAN)], &mut m0, &mut i0).is_err());
    }

    /// Without DMW the steady clearance is the static equilibrium, so the touchdown search must
    /// land where the static clearance crosses zero — found independently here by bisection on
    /// the static equilibrium alone.
    #[test]
    fn touchdown_search_matches_the_static_crossing_without_dmw() {
        let base = short_base(None);
        let mut settings = CalibrationSettings {
            ..CalibrationSettings::new(
                vec![],
                vec![t(
                    "touchdown",
                    Quantity::Touchdown,
                    10e-9,
                    0.2e-9,
                    "",
                    "nm",
                    1e9,
                )],
            )
        };
        settings.touchdown.resolution = 0.01 * NM;
        settings.touchdown.step = 1.0 * NM;
        let e = evaluate(&base, &settings, &[]).unwrap();
        let td = e.outcomes[0].value.unwrap();
        let lookup = interface_table(base.isbl).unwrap();
        let static_clearance = |h: f64| {
            let case = TwoDofCase::new(&base.model, h, &lookup, None, base.options).unwrap();
            let z = case.static_equilibrium().unwrap();
            case.clearance_at_rest(z).unwrap()
        };
        let (mut lo, mut hi) = (8e-9, 12e-9);
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if static_clearance(mid) < 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        assert!(
            (td - hi).abs() < 0.011 * NM,
            "search {:.4} nm vs static crossing {:.4} nm",
            td / NM,
            hi / NM
        );
        // Scan 0, 1, … nm (4 at a time) to the first touching point, then 4 rounds of 4.
        assert!(e.cases > 10 && e.cases < 40, "{} cases", e.cases);
    }

    /// The boxes are the models' accepted ranges where the model has one: the box ends are
    /// accepted by the model, a step past them is rejected.
    #[test]
    fn knob_boxes_are_the_models_accepted_ranges() {
        let improved = |k: Knob, v: f64| {
            let (mut m, mut i) = (improved_2dof(), IsblParams::improved_2dof());
            apply_knobs(&[(k, v)], &mut m, &mut i)
        };
        let initial = |k: Knob, v: f64| {
            let (mut m, mut i) = (initial_2dof(), IsblParams::initial_2dof());
            apply_knobs(&[(k, v)], &mut m, &mut i)
        };
        for (k, check) in [
            (
                Knob::KrStiffeningBeta,
                &improved as &dyn Fn(Knob, f64) -> Result<f64>,
            ),
            (Knob::ContactDamping, &improved),
            (Knob::TruncationN, &initial),
        ] {
            let (lo, hi) = k.default_bounds();
            assert!(
                check(k, lo).is_ok() && check(k, hi).is_ok(),
                "{k:?} box ends"
            );
            assert!(check(k, hi * (1.0 + 1e-6)).is_err(), "{k:?} above the box");
        }
        assert_eq!(Knob::KrStiffeningBeta.default_bounds(), (0.0, 3.0));
        // Open model ranges: the box starts at the model's own limit.
        assert_eq!(Knob::SurfaceEnergy.default_bounds().0, 0.0);
        assert_eq!(Knob::DmwScale.default_bounds().0, 0.0);
        assert!(improved(Knob::SurfaceEnergy, 0.0).is_ok());
        assert!(improved(Knob::ContactDamping, -1e-9).is_err());
    }

    /// A short, cheap base for fits in debug builds: a 0.4 ms case (steady window 0.2–0.4 ms)
    /// from the static equilibrium, with a 50 kHz, 0.5 nm sinusoidal DMW when `dmw` is given.
    fn short_base(dmw: Option<DmwInput<'_>>) -> CalibrationBase<'_> {
        CalibrationBase {
            model: improved_2dof(),
            isbl: IsblParams::improved_2dof(),
            contact_law: None,
            dmw,
            options: SimOptions {
                duration: 0.4e-3,
                static_init: true,
                ..Default::default()
            },
            case_params: CaseParams {
                window: super::super::metrics::SteadyWindow {
                    start_s: 0.2e-3,
                    end_s: 0.4e-3,
                },
                ..CaseParams::improved_2dof()
            },
            rounds: None,
        }
    }

    fn sinusoid() -> (Vec<f64>, Vec<f64>, f64) {
        let (fs, f, amp) = (4e6, 50e3, 0.5e-9);
        let w = 2.0 * std::f64::consts::PI * f;
        let n = (0.6e-3 * fs) as usize;
        let t = |k: usize| k as f64 / fs;
        (
            (0..n).map(|k| amp * (w * t(k)).sin()).collect(),
            (0..n).map(|k| amp * w * (w * t(k)).cos()).collect(),
            fs,
        )
    }

    /// Targets generated by the model itself at chosen knob values (β = 2.2, DMW × 1.8) are
    /// recovered by a fit from the spec defaults (β = 1, × 1), run to the simplex tolerance.
    #[test]
    fn the_fit_recovers_known_knob_values_on_a_synthetic_problem() {
        let (d, v, fs) = sinusoid();
        let base = short_base(Some(DmwInput {
            displacement: &d,
            velocity: &v,
            sample_rate: fs,
        }));
        let nm = |x: f64| x * NM;
        let templates = [
            // Tight bands: the objective is then far from 0 at the defaults (β moves the 8.5 nm
            // clearance by a few hundredths of a nm); recovery depends only on the minimum.
            t(
                "c",
                Quantity::Clearance { actuation: nm(8.5) },
                0.0,
                nm(0.002),
                "",
                "nm",
                1e9,
            ),
            t(
                "f",
                Quantity::Vibration { actuation: nm(8.5) },
                0.0,
                0.05,
                "",
                "%",
                1.0,
            ),
        ];
        let truth = [(Knob::KrStiffeningBeta, 2.2), (Knob::DmwScale, 1.8)];
        let probe = CalibrationSettings::new(vec![], templates.to_vec());
        let generated = evaluate(&base, &probe, &truth).unwrap();
        let targets: Vec<Target> = generated
            .outcomes
            .iter()
            .map(|o| Target {
                published: o.value.unwrap(),
                ..o.target.clone()
            })
            .collect();
        let defaults = evaluate(
            &base,
            &CalibrationSettings::new(vec![], targets.clone()),
            &[],
        )
        .unwrap();
        assert!(
            defaults.objective > 1.0,
            "the defaults must miss: {}",
            defaults.objective
        );
        let mut settings = CalibrationSettings::new(
            vec![
                KnobRange::new(Knob::KrStiffeningBeta),
                KnobRange::new(Knob::DmwScale),
            ],
            targets,
        );
        settings.search.f_tolerance = 1e-4;
        settings.search.x_tolerance = 1e-3;
        settings.search.max_evaluations = 200;
        let r = calibrate(&base, &settings, |_, _| {}).unwrap();
        assert!(r.converged, "{} evaluations", r.evaluations);
        for ((k, v), (_, want)) in r.best.knobs.iter().zip(truth) {
            assert!(
                (v - want).abs() < 0.01 * want,
                "{k:?}: fitted {v}, generated at {want}"
            );
        }
    }

    /// Early rejection (the touchdown search skipped when the other targets already decide a
    /// trial point's comparison) changes neither the trajectory nor the fit: the same
    /// evaluations in the same order, the exact ones bit for bit, the rejected ones recorded
    /// with a lower bound; and it saves cases.
    #[test]
    fn early_rejection_gives_the_same_fit_with_fewer_cases() {
        let base = short_base(None);
        let nm = |x: f64| x * NM;
        let targets = vec![
            // The touchdown term small, the clearance term large and moving with the knobs:
            // many trial points are then decided by the clearance case alone.
            t("td", Quantity::Touchdown, nm(10.5), nm(5.0), "", "nm", 1e9),
            t(
                "c",
                Quantity::Clearance { actuation: nm(6.0) },
                0.0,
                nm(0.002),
                "",
                "nm",
                1e9,
            ),
        ];
        // The clearance's published value is the model's own at β = 2.2: a minimum inside
        // the box.
        let probe = CalibrationSettings::new(vec![], targets[1..].to_vec());
        let generated = evaluate(&base, &probe, &[(Knob::KrStiffeningBeta, 2.2)]).unwrap();
        let mut targets = targets;
        targets[1].published = generated.outcomes[0].value.unwrap();
        let mut settings = CalibrationSettings::new(
            vec![
                KnobRange::new(Knob::KrStiffeningBeta),
                KnobRange::new(Knob::ContactDamping),
            ],
            targets,
        );
        // A coarse search keeps the debug build's cases few; the convention is the same.
        settings.touchdown = TouchdownSearch {
            start: 0.0,
            stop: nm(14.0),
            step: nm(2.0),
            resolution: nm(0.25),
            batch: 2,
        };
        settings.search.max_evaluations = 24;
        let with = calibrate(&base, &settings, |_, _| {}).unwrap();
        settings.early_rejection = false;
        let without = calibrate(&base, &settings, |_, _| {}).unwrap();
        assert_eq!(with.evaluations, without.evaluations);
        assert_eq!(with.history.len(), without.history.len());
        for (a, b) in with.history.iter().zip(&without.history) {
            assert!(b.3, "no rejection without early rejection");
            assert_eq!((a.0, a.2.to_bits()), (b.0, b.2.to_bits()));
            if a.3 {
                assert_eq!(a.1.to_bits(), b.1.to_bits());
            } else {
                assert!(a.1 <= b.1, "bound {} above the objective {}", a.1, b.1);
            }
        }
        assert_eq!(with.best, without.best);
        assert_eq!(
            (with.final_f_spread, with.final_x_spread),
            (without.final_f_spread, without.final_x_spread)
        );
        assert!(
            with.rejected > 0,
            "no trial point was rejected early: {:?} {:?}",
            with.history,
            with.failures
        );
        assert_eq!(without.rejected, 0);
        assert!(
            with.cases < without.cases,
            "{} ≥ {}",
            with.cases,
            without.cases
        );
    }

    /// Rounds computed elsewhere (here: one case at a time through `round_case`, the metrics
    /// through JSON as a store entry carries them) give the in-process fit exactly: same
    /// trajectory, knobs, objective and counts, early rejection included; and every case of
    /// the fit, the held-out sweep's too, went through the runner.
    #[test]
    fn rounds_run_elsewhere_give_the_same_fit() {
        struct Serial<'b> {
            base: CalibrationBase<'b>,
            rounds: std::sync::Mutex<Vec<usize>>,
        }
        impl CaseRounds for Serial<'_> {
            fn run_round(&self, round: &CaseRound) -> Result<Vec<CaseMetrics>> {
                self.rounds.lock().unwrap().push(round.actuations.len());
                round
                    .actuations
                    .iter()
                    .map(|&a| {
                        let m = round_case(&self.base, round.knobs, round.geometry, a)?;
                        let text = serde_json::to_string(&m).unwrap();
                        Ok(serde_json::from_str(&text).unwrap())
                    })
                    .collect()
            }
        }
        let nm = |x: f64| x * NM;
        let mut settings = CalibrationSettings::new(
            vec![
                KnobRange::new(Knob::KrStiffeningBeta),
                KnobRange::new(Knob::ContactDamping),
            ],
            vec![
                t("td", Quantity::Touchdown, nm(10.5), nm(5.0), "", "nm", 1e9),
                t(
                    "c",
                    Quantity::Clearance { actuation: nm(6.0) },
                    1.5e-9,
                    nm(0.002),
                    "",
                    "nm",
                    1e9,
                ),
            ],
        );
        settings.held_out = vec![t(
            "tdc",
            Quantity::TouchdownClearance,
            0.5e-9,
            0.2e-9,
            "",
            "nm",
            1e9,
        )
        .held_out()];
        settings.sweep_grid = vec![0.0, nm(7.0), nm(14.0)];
        settings.touchdown = TouchdownSearch {
            start: 0.0,
            stop: nm(14.0),
            step: nm(2.0),
            resolution: nm(0.25),
            batch: 2,
        };
        settings.search.max_evaluations = 5;
        let local = calibrate(&short_base(None), &settings, |_, _| {}).unwrap();
        let runner = Serial {
            base: short_base(None),
            rounds: Default::default(),
        };
        let mut base = short_base(None);
        base.rounds = Some(&runner);
        let remote = calibrate(&base, &settings, |_, _| {}).unwrap();
        assert_eq!(remote, local);
        assert!(local.held_out_best.is_some());
        let rounds = runner.rounds.into_inner().unwrap();
        assert!(rounds.len() > 10, "{rounds:?}");
        assert_eq!(rounds.iter().sum::<usize>(), local.cases);
    }

    /// The held-out set never reaches the objective: moving a held-out target's published
    /// value leaves the fitted knobs bit-identical, while its own residual moves.
    #[test]
    fn held_out_targets_do_not_influence_the_fit() {
        let base = short_base(None);
        let nm = |x: f64| x * NM;
        let fitted = vec![t(
            "c",
            Quantity::Clearance { actuation: nm(8.5) },
            nm(2.3),
            nm(0.05),
            "",
            "nm",
            1e9,
        )];
        let held = |published: f64| {
            vec![
                t(
                    "h",
                    Quantity::Clearance { actuation: nm(7.0) },
                    published,
                    nm(0.1),
                    "",
                    "nm",
                    1e9,
                )
                .held_out(),
                t(
                    "onset",
                    Quantity::LubricantContactOnset,
                    nm(9.0),
                    nm(0.2),
                    "",
                    "nm",
                    1e9,
                )
                .held_out(),
            ]
        };
        let run = |published: f64| {
            let mut s = CalibrationSettings::new(
                vec![KnobRange::new(Knob::KrStiffeningBeta)],
                fitted.clone(),
            );
            s.held_out = held(published);
            s.sweep_grid = vec![nm(6.0), nm(8.0)];
            s.search.max_evaluations = 8;
            calibrate(&base, &s, |_, _| {}).unwrap()
        };
        let (a, b) = (run(nm(3.5)), run(nm(1.0)));
        assert_eq!(a.best.knobs, b.best.knobs);
        assert_eq!(a.history, b.history);
        let (ha, hb) = (a.held_out_best.unwrap(), b.held_out_best.unwrap());
        assert_eq!(ha.outcomes[0].value, hb.outcomes[0].value);
        assert_ne!(
            ha.outcomes[0].normalised_residual,
            hb.outcomes[0].normalised_residual
        );
        // The held-out sweep ran: 6, 7 and 8 nm, all flying, so no lubricant-contact onset.
        assert_eq!(ha.cases, 3);
        assert_eq!(ha.outcomes[1].value, None);
        assert!(!ha.outcomes[1].within_tolerance());
    }

    /// The held-out sweep quantities on a hand-made curve (T0 = 0.75 nm: flying above 1.5 nm,
    /// mobile to 0.75, bonded to 0, solid below), each derived by hand.
    #[test]
    fn sweep_quantities_on_a_hand_made_curve() {
        let c = [3.0, 2.5, 1.2, 0.9, 0.5, 0.2, -0.3];
        let vib = [5.0, 7.0, 9.0, 8.0, 6.0, 4.0, 3.0];
        let points: Vec<SweepPoint> = (0..c.len())
            .map(|i| SweepPoint {
                actuation_m: (8.0 + 0.5 * i as f64) * NM,
                mean_clearance_m: c[i] * NM,
                // The 10.5 nm case touches by vibration although its mean is 0.2 nm.
                any_solid_contact: c[i] < 0.25,
                vibration_percent: vib[i],
            })
            .collect();
        let m = sweep_metrics(&points, &SlopeParams::new(0.75 * NM), 11.0 * NM).unwrap();
        let v = |q| sweep_value(q, &points, &m, &[]);
        let close = |a: Option<f64>, b: f64| (a.unwrap() - b).abs() < 1e-12 * b.abs().max(1e-9);
        assert!(close(
            v(Quantity::RegimeBoundary {
                below: Regime::Flying
            }),
            8.75 * NM
        ));
        assert!(close(
            v(Quantity::RegimeBoundary {
                below: Regime::MobileLubricantContact
            }),
            9.75 * NM
        ));
        assert!(close(
            v(Quantity::RegimeBoundary {
                below: Regime::BondedLubricantContact
            }),
            10.75 * NM
        ));
        assert!(close(v(Quantity::LubricantContactOnset), 9.0 * NM));
        assert!(close(v(Quantity::FlyingFhmMax), 7.0));
        assert!(close(v(Quantity::TouchdownClearance), 0.2 * NM));
        assert!(close(v(Quantity::TouchdownVibration), 4.0));
        // Lubricant-contact points 9.0–10.5 nm: c = 1.2, 0.9, 0.5, 0.2 → least-squares slope
        // Σ(x−x̄)(y−ȳ)/Σ(x−x̄)² = −1.5/1.25 = −0.68 (x̄ = 9.75, ȳ = 0.7).
        assert!(close(v(Quantity::Slope(SlopeName::C)), -0.68));
        // Needs the cases' contact metrics: none given here.
        assert_eq!(v(Quantity::FullContactOnset), None);
    }
}
