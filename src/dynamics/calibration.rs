//! Class-D calibration (docs/calibration.md): fit the `[assumption]` knobs whose values the
//! dissertation dropped to its published class-D landmarks, reproducibly. Pure: no I/O.
//!
//! * **Knobs** ([`Knob`]) — DMW amplitude (the record's standard deviation was dropped),
//!   rear-spring stiffening β, work of adhesion Δγ, LJ spacing ε, contact damping ζ_c, the
//!   initial model's truncation `n` (S1c) and, as a what-if only, the summit density η (seeded
//!   124 µm⁻² for the improved model, so it is not in the default set). Each has physical bounds
//!   and is searched in `[0, 1]` (logarithmic for the scale-like ones).
//! * **Targets** ([`Target`]) — published numbers with the spec's tolerance; the objective is
//!   `Σ ((ours − published)/tolerance)²`, so a residual of 1 means "at the edge of the band".
//! * **Evaluation** — one objective value is a handful of 2-DOF cases at the target actuations
//!   (parallel) plus a touchdown search: the smallest actuation whose steady window reaches
//!   solid contact (min clearance < 0), bracketed by trisection to `touchdown_resolution`.
//! * **Search** — Nelder–Mead in the unit box from the spec defaults
//!   ([`crate::numerics::nelder_mead`]): deterministic, so the same inputs give the same fit.

use super::air_bearing::RearStiffening;
use super::geometry::ContactCriterion;
use super::metrics::{CaseMetrics, CaseParams};
use super::params::{optimised_bulge, Model2Dof, ModelVariant};
use super::two_dof::{DmwInput, SimOptions, TwoDofCase};
use super::{DynamicsError, Result, NM};
use crate::contact::isbl::{IsblModel, IsblParams, SurfaceEnergy};
use crate::contact::lookup::IsblLookup;
use crate::numerics::nelder_mead::{minimize_unit_box, NelderMeadOptions};
use rayon::prelude::*;

/// A calibration knob: a dropped input with its physical range.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
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

    /// Physical search range `[lo, hi]` (SI) [choice, stated in docs/calibration.md].
    pub fn default_bounds(self) -> (f64, f64) {
        match self {
            Knob::DmwScale => (0.25, 4.0),
            Knob::KrStiffeningBeta => (0.0, 5.0),
            // PFPE/DLC work of adhesion: a few to ~100 mJ/m².
            Knob::SurfaceEnergy => (0.005, 0.15),
            // LJ spacing of HDI adhesion models: 0.15–1 nm.
            Knob::LjSpacing => (0.15 * NM, 1.0 * NM),
            Knob::ContactDamping => (0.01, 1.0),
            Knob::TruncationN => (0.5, 2.5),
            Knob::AsperityDensity => (20e12, 3000e12),
        }
    }

    /// Searched on a logarithmic axis (scale-like quantities).
    fn logarithmic(self) -> bool {
        matches!(
            self,
            Knob::DmwScale | Knob::SurfaceEnergy | Knob::ContactDamping | Knob::AsperityDensity
        )
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
#[derive(Debug, Clone, Copy, PartialEq)]
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

/// What a target measures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Quantity {
    /// Smallest actuation with solid contact in the steady window (m).
    Touchdown,
    /// Mean clearance at an actuation (m; negative = interference).
    Clearance { actuation: f64 },
    /// Eq. 2.1 FHM/BV at an actuation (%).
    Vibration { actuation: f64 },
    /// Mean dynamic contact force (N).
    ContactForce { actuation: f64 },
    /// Mean ISBL adhesion force (N).
    Adhesion { actuation: f64 },
    /// Mean instantaneous friction coefficient over the loaded samples.
    FrictionCoefficient { actuation: f64 },
}

impl Quantity {
    fn actuation(self) -> Option<f64> {
        match self {
            Quantity::Touchdown => None,
            Quantity::Clearance { actuation }
            | Quantity::Vibration { actuation }
            | Quantity::ContactForce { actuation }
            | Quantity::Adhesion { actuation }
            | Quantity::FrictionCoefficient { actuation } => Some(actuation),
        }
    }
}

/// The bulge a target is measured on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TargetGeometry {
    Base,
    /// §2.3 optimised design, a = 4.86 µm, x = 6.35 µm, w = 50 µm [assumption].
    Optimised,
}

/// A published number and its tolerance (docs/validation.md). The objective is
/// `Σ weight·((value − published)/tolerance)²`.
#[derive(Debug, Clone, PartialEq)]
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
    /// Display unit and the factor SI → display.
    pub unit: &'static str,
    pub display_scale: f64,
    /// Which bulge the cases use: the base model's, or the optimised design of §2.3 (w = 50 µm
    /// assumed) — the spec asks for the calibration to be judged on both geometries at once.
    pub geometry: TargetGeometry,
    /// Weight of the squared residual: 1 for class D; 10 for a class-K anchor, which the
    /// dissertation's model meets regardless of the dropped inputs, so a fit must not trade it.
    pub weight: f64,
}

/// The class-D targets of the improved 2-DOF model (S2, dissertation geometry), plus the
/// class-K anchor at 8.5 nm that a calibration must not break.
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
        Target {
            weight: 10.0, // class-K anchor
            ..t(
                "clearance_8.5nm",
                Quantity::Clearance { actuation: nm(8.5) },
                nm(2.54),
                nm(0.05),
                "#18",
                "nm",
                1e9,
            )
        },
        t(
            "fhm_8.5nm",
            Quantity::Vibration { actuation: nm(8.5) },
            8.20,
            4.10,
            "#18",
            "%",
            1.0,
        ),
        // Reported, not fitted (weight 0): out of reach of every knob (docs/calibration.md) —
        // the 9.5 nm clearance needs a jump to contact from 8.6 nm that no LJ range in bounds
        // gives, the 12 nm interference a contact ~10× stiffer than the seeded η, R allow.
        Target {
            weight: 0.0,
            ..t(
                "clearance_9.5nm",
                Quantity::Clearance { actuation: nm(9.5) },
                nm(0.67),
                nm(0.2),
                "#19",
                "nm",
                1e9,
            )
        },
        Target {
            weight: 0.0,
            ..t(
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
        },
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
        Target {
            geometry: TargetGeometry::Optimised,
            ..t(
                "optimised_touchdown",
                Quantity::Touchdown,
                nm(9.9),
                nm(0.2),
                "#26",
                "nm",
                1e9,
            )
        },
        Target {
            geometry: TargetGeometry::Optimised,
            ..t(
                "optimised_clearance_8.6nm",
                Quantity::Clearance { actuation: nm(8.6) },
                nm(2.23),
                nm(0.15),
                "#26",
                "nm",
                1e9,
            )
        },
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
        unit,
        display_scale,
        geometry: TargetGeometry::Base,
        weight: 1.0,
    }
}

/// The catalogue of a model variant.
pub fn targets_for(variant: ModelVariant) -> Vec<Target> {
    match variant {
        ModelVariant::Improved => improved_targets(),
        ModelVariant::Initial => initial_targets(),
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
}

/// Search settings.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationSettings {
    pub knobs: Vec<KnobRange>,
    pub targets: Vec<Target>,
    pub search: NelderMeadOptions,
    /// Touchdown bracket and its final width (m).
    pub touchdown_range: (f64, f64),
    pub touchdown_resolution: f64,
}

impl CalibrationSettings {
    pub fn new(knobs: Vec<KnobRange>, targets: Vec<Target>) -> Self {
        CalibrationSettings {
            knobs,
            targets,
            search: NelderMeadOptions {
                initial_step: 0.2,
                max_evaluations: 120,
                f_tolerance: 1e-3,
                x_tolerance: 2e-3,
            },
            touchdown_range: (8.0 * NM, 12.0 * NM),
            touchdown_resolution: 0.02 * NM,
        }
    }
}

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
    /// At the spec defaults.
    pub initial: Evaluation,
    /// At the best point found.
    pub best: Evaluation,
    /// `(evaluation index, objective, best so far)`.
    pub history: Vec<(usize, f64, f64)>,
    pub converged: bool,
    pub evaluations: usize,
    pub cases: usize,
    /// Knob values where a case failed (counted as an infeasible point), with the error.
    pub failures: Vec<(KnobValues, String)>,
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
    IsblModel::new(isbl)
        .and_then(IsblLookup::build_standard)
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
        actuations.par_iter().map(|&a| self.case(a)).collect()
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
        lookup: std::sync::Arc::new(interface_table(isbl)?),
        dmw: std::sync::Arc::new(dmw),
        base,
    })
}

/// Evaluate the targets at given knob values (the spec defaults when `values` is empty).
pub fn evaluate(
    base: &CalibrationBase,
    settings: &CalibrationSettings,
    values: &[(Knob, f64)],
) -> Result<Evaluation> {
    let p = prepare(base, values)?;
    let mut by_id = Vec::new();
    let mut cases = 0;
    for geometry in [TargetGeometry::Base, TargetGeometry::Optimised] {
        let targets: Vec<&Target> = settings
            .targets
            .iter()
            .filter(|t| t.geometry == geometry)
            .collect();
        if targets.is_empty() {
            continue;
        }
        let optimised;
        let prepared = match geometry {
            TargetGeometry::Base => &p,
            TargetGeometry::Optimised => {
                optimised = Prepared {
                    model: p.model.with_bulge(optimised_bulge(OPTIMISED_WIDTH)?),
                    ..p.clone()
                };
                &optimised
            }
        };
        let (values, n) = evaluate_targets(prepared, settings, &targets)?;
        cases += n;
        by_id.extend(targets.iter().map(|t| t.id).zip(values));
    }
    let outcomes = settings
        .targets
        .iter()
        .map(|t| {
            let value = by_id
                .iter()
                .find(|(id, _)| *id == t.id)
                .and_then(|(_, v)| *v)
                .filter(|v| v.is_finite());
            // No contact → no force, no μ: the residual of a missing number is that of 0.
            let r = (value.unwrap_or(0.0) - t.published) / t.tolerance;
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
    Ok(Evaluation {
        knobs: values.to_vec(),
        outcomes,
        objective,
        cases,
    })
}

/// The values of targets on one geometry, and how many cases that took.
fn evaluate_targets(
    p: &Prepared,
    settings: &CalibrationSettings,
    targets: &[&Target],
) -> Result<(Vec<Option<f64>>, usize)> {
    let mut actuations: Vec<f64> = targets
        .iter()
        .filter_map(|t| t.quantity.actuation())
        .collect();
    actuations.sort_by(f64::total_cmp);
    actuations.dedup();
    let metrics = p.cases(&actuations)?;
    let mut cases = actuations.len();
    let at = |a: f64| actuations.iter().position(|x| *x == a).map(|i| &metrics[i]);
    let touchdown = if targets.iter().any(|t| t.quantity == Quantity::Touchdown) {
        let known: Vec<(f64, f64)> = actuations
            .iter()
            .zip(&metrics)
            .map(|(a, m)| (*a, m.clearance_m.min))
            .collect();
        let (td, n) = touchdown_search(p, settings, &known)?;
        cases += n;
        Some(td)
    } else {
        None
    };
    let values = targets
        .iter()
        .map(|t| match t.quantity {
            Quantity::Touchdown => touchdown,
            Quantity::Clearance { actuation } => at(actuation).map(|m| m.clearance_m.mean),
            Quantity::Vibration { actuation } => at(actuation).map(|m| m.vibration.percent),
            Quantity::ContactForce { actuation } => at(actuation)
                .and_then(|m| m.contact.as_ref())
                .map(|c| c.contact_force_n.mean),
            Quantity::Adhesion { actuation } => at(actuation)
                .and_then(|m| m.contact.as_ref())
                .and_then(|c| c.adhesion_n.as_ref())
                .map(|s| s.mean),
            Quantity::FrictionCoefficient { actuation } => at(actuation)
                .and_then(|m| m.contact.as_ref())
                .and_then(|c| c.friction_coefficient.as_ref())
                .map(|s| s.mean),
        })
        .collect();
    Ok((values, cases))
}

/// Smallest actuation whose steady window reaches solid contact (min clearance < 0), by
/// trisection (two cases per round, in parallel) inside `settings.touchdown_range`, seeded by
/// the cases already run. Returns the bracket's upper end (the first actuation known to touch)
/// clamped to the range, and how many cases it ran.
fn touchdown_search(
    p: &Prepared,
    settings: &CalibrationSettings,
    known: &[(f64, f64)],
) -> Result<(f64, usize)> {
    let (lo0, hi0) = settings.touchdown_range;
    let mut lo = known
        .iter()
        .filter(|(a, g)| *g >= 0.0 && *a >= lo0)
        .map(|(a, _)| *a)
        .fold(lo0, f64::max);
    let mut hi = known
        .iter()
        .filter(|(a, g)| *g < 0.0 && *a <= hi0)
        .map(|(a, _)| *a)
        .fold(hi0, f64::min);
    let mut runs = 0;
    // The range ends themselves, unless a known case already decides them.
    let mut ends = Vec::new();
    if !known.iter().any(|(a, g)| *a <= lo && *g >= 0.0) {
        ends.push(lo);
    }
    if !known.iter().any(|(a, g)| *a >= hi && *g < 0.0) {
        ends.push(hi);
    }
    if !ends.is_empty() {
        let m = p.cases(&ends)?;
        runs += ends.len();
        for (a, m) in ends.iter().zip(&m) {
            let touches = m.clearance_m.min < 0.0;
            if *a == lo && touches {
                return Ok((lo, runs)); // touches already at the bottom of the range
            }
            if *a == hi && !touches {
                return Ok((hi, runs)); // no contact in the range: report its top
            }
        }
    }
    if lo >= hi {
        return Ok((hi, runs));
    }
    while hi - lo > settings.touchdown_resolution {
        let (a, b) = (lo + (hi - lo) / 3.0, lo + 2.0 * (hi - lo) / 3.0);
        let m = p.cases(&[a, b])?;
        runs += 2;
        let (ta, tb) = (m[0].clearance_m.min < 0.0, m[1].clearance_m.min < 0.0);
        if ta {
            hi = a;
        } else if tb {
            (lo, hi) = (a, b);
        } else {
            lo = b;
        }
    }
    Ok((hi, runs))
}

/// Fit the knobs. `progress(evaluation, best objective)` is called after each evaluation.
pub fn calibrate(
    base: &CalibrationBase,
    settings: &CalibrationSettings,
    mut progress: impl FnMut(usize, f64),
) -> Result<CalibrationResult> {
    if settings.targets.is_empty() {
        return Err(DynamicsError::Numerical("no calibration target".into()));
    }
    for k in &settings.knobs {
        k.check()?;
    }
    let start: Vec<f64> = settings
        .knobs
        .iter()
        .map(|k| {
            k.knob
                .base_value(&base.model, &base.isbl)
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
    let fit = minimize_unit_box(
        |u| -> Result<f64> {
            // A point where a case fails (e.g. no static equilibrium) is infeasible, not fatal.
            let objective = match evaluate(base, settings, &to_values(u)) {
                Ok(e) => {
                    cases += e.cases;
                    e.objective
                }
                Err(e) => {
                    failures.push((to_values(u), e.to_string()));
                    f64::INFINITY
                }
            };
            best_so_far = best_so_far.min(objective);
            history.push((history.len(), objective, best_so_far));
            progress(history.len(), best_so_far);
            Ok(objective)
        },
        &start,
        &settings.search,
    )?;
    let best = evaluate(base, settings, &to_values(&fit.x))?;
    cases += best.cases;
    Ok(CalibrationResult {
        initial,
        best,
        history,
        converged: fit.converged,
        evaluations: fit.evaluations.len(),
        cases,
        failures,
    })
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
            knob: Knob::SurfaceEnergy,
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
        let base = CalibrationBase {
            model: improved_2dof(),
            isbl: IsblParams::improved_2dof(),
            dmw: None,
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
        };
        let settings = CalibrationSettings {
            touchdown_resolution: 0.01 * NM,
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
        assert!(e.cases > 2 && e.cases < 20, "{} cases", e.cases);
    }
}
