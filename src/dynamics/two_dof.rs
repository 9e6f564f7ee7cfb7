//! One 2-DOF slider case (eqs. 2.8–2.16; docs/simulation.md): a parameter set, a constant TFC
//! actuation, an interface (the contact stage's ISBL table) and a DMW track → time histories of
//! the bulge spacing, clearance and interfacial forces, sampled uniformly. Pure: no I/O.
//!
//! State `y = [z, ϑ, ż, ϑ̇]` (heave of the COM and pitch offset from the nominal state). Per
//! right-hand-side evaluation: DMW under the LE, TE and POC (one track, transit delay), the AB
//! forcing of eqs. 2.12–2.13, the closed-form POC at the current pitch, the contact force of
//! eq. 2.16 with friction and real area from `P⁻¹`, ISBL adhesion, and the generalised forces.

use super::air_bearing::{AirBearing2Dof, DmwAtSprings, HeavePitchState, AB_LOSS_FLYING_HEIGHT};
use super::geometry::{ContactCriterion, PitchTerms, PocFrame, Slider2DofGeometry};
use super::metrics::{case_metrics, CaseMetrics, CaseParams, CaseSeries, ContactSeries};
use super::params::{Model2Dof, ModelVariant};
use super::three_dof::interface::AreaIsbl;
use super::DynamicsError;
use crate::contact::lookup::IsblLookup;
use crate::contact::mtl::{FwmExperiment, LubricantCase, MtlInterface, RoughFilm, RoughMtl};
use crate::numerics::ode::{integrate_capped, OdeError, OdeOptions, OdeStats, Sampling};
use crate::signal::resample::HermiteTrack;
use nalgebra::{Matrix2, Vector2};
use std::cell::Cell;

// Shared with the 3-DOF interface (its own module: neither model owns the other).
pub use super::contact_force::ContactForceForm;

/// The lubricant layer's force on the bulge (switch `lubricant`; docs/model-form.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LubricantForce {
    /// Chapter 2's assumption: the lubricant is displaced and offers no resistance (§2.2.1).
    #[default]
    None,
    /// Chapter 3's rough-surface MTL law (eqs. 3.55–3.60, reference lubricant of Table 4.4
    /// case 0) acting while the bulge spacing is inside the film, `s < 3σ + t`, on the ISBL
    /// solid scaled by the nominal area, as the 3-DOF's `contact_model = "mtl"` does (§4.1).
    Mtl,
}

/// Time integration (docs/integrator.md).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Integrator {
    /// Dormand–Prince 5(4), `rtol`, with the step capped at `contact_max_step` while the POC is
    /// in contact and shortened on approach so a step never jumps deep into contact.
    Dopri5 {
        rtol: f64,
        contact_max_step: f64,
        max_step: f64,
    },
    /// The same tableau at a fixed step (the dissertation's "small fixed step" reproduction).
    Rk5Fixed { step: f64 },
}

impl Integrator {
    pub fn recommended() -> Self {
        Integrator::Dopri5 {
            rtol: 1e-8,
            contact_max_step: 1e-8,
            // Inside DP5's stability limit for the 300 kHz mode (|hλ| ≲ 3.3 → 1.7 µs), so a
            // quiet free flight cannot grow the step into instability.
            max_step: 1e-6,
        }
    }
}

/// Options of one case.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SimOptions {
    /// Simulated time [s] (2 ms).
    pub duration: f64,
    /// Output sampling step [s] (0.25 µs = the DMW rate).
    pub output_step: f64,
    pub contact_force: ContactForceForm,
    /// Lubricant bearing and shear force (default none, Chapter 2).
    pub lubricant: LubricantForce,
    pub integrator: Integrator,
    /// The DMW under a point is the bulge's delayed by its distance along x over U (§6).
    pub transit_delay: bool,
    /// Periodic extension of a DMW record shorter than the run (warned by the caller).
    pub wrap_dmw: bool,
    /// Initial `[z, ϑ, ż, ϑ̇]` relative to the nominal state (§5.4: zero), or, with
    /// `static_init`, relative to the static equilibrium.
    pub initial_state: [f64; 4],
    /// §5.4 `init = "static"`: start from the static equilibrium at the case's actuation
    /// (DMW frozen at t = 0, interfacial forces on) instead of the nominal state. Shortens the
    /// transient and avoids the violent start of a deep initial interference.
    pub static_init: bool,
    /// With `static_init`: the `(z, ϑ)` Newton starts from (e.g. the neighbouring actuation's
    /// equilibrium, for branch-tracking sweeps; docs/conventions.md). `None`: the nominal
    /// state, then heave offsets on either side of it.
    pub static_start: Option<[f64; 2]>,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            duration: 2e-3,
            output_step: 0.25e-6,
            contact_force: ContactForceForm::InterferenceTangent,
            lubricant: LubricantForce::None,
            integrator: Integrator::recommended(),
            transit_delay: true,
            wrap_dmw: false,
            initial_state: [0.0; 4],
            static_init: false,
            static_start: None,
        }
    }
}

impl SimOptions {
    /// Every option within its range (errors name the option), independent of the model.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        let o = self;
        if let Some(v) = o.initial_state.iter().find(|v| !v.is_finite()) {
            return Err(parameter("initial state", *v, "must be finite"));
        }
        if let Some(v) = o.static_start.iter().flatten().find(|v| !v.is_finite()) {
            return Err(parameter("static start", *v, "must be finite"));
        }
        if !(o.duration.is_finite() && o.duration > 0.0 && o.duration <= 1.0) {
            return Err(parameter(
                "duration (s)",
                o.duration,
                "must lie in (0, 1] s",
            ));
        }
        if !(o.output_step.is_finite() && o.output_step > 0.0 && o.output_step <= o.duration) {
            return Err(parameter(
                "output step (s)",
                o.output_step,
                "must be > 0 and at most the duration",
            ));
        }
        if o.duration / o.output_step > 5e7 {
            return Err(parameter(
                "output step (s)",
                o.output_step,
                "gives more than 5·10⁷ samples",
            ));
        }
        match o.integrator {
            Integrator::Dopri5 {
                rtol,
                contact_max_step,
                max_step,
            } => {
                if !(rtol > 0.0 && rtol < 1e-2) {
                    return Err(parameter("rtol", rtol, "must lie in (0, 0.01)"));
                }
                if !(contact_max_step > 0.0 && contact_max_step.is_finite()) {
                    return Err(parameter(
                        "contact_max_step (s)",
                        contact_max_step,
                        "must be finite and > 0",
                    ));
                }
                if max_step.is_nan() || max_step <= 0.0 {
                    return Err(parameter("max_step (s)", max_step, "must be > 0"));
                }
            }
            Integrator::Rk5Fixed { step } => {
                if !(step > 0.0 && step.is_finite() && o.duration / step <= 1e9) {
                    return Err(parameter(
                        "fixed step (s)",
                        step,
                        "must be > 0 and give at most 10⁹ steps",
                    ));
                }
            }
        }
        Ok(())
    }
}

/// A DMW displacement track and its velocity, uniformly sampled from t = 0.
#[derive(Debug, Clone, Copy)]
pub struct DmwInput<'a> {
    pub displacement: &'a [f64],
    pub velocity: &'a [f64],
    pub sample_rate: f64,
}

/// Everything the interface gives at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct InterfaceState {
    /// Solid spacing of the bulge POC above the local disk surface `s` [m].
    pub spacing: f64,
    /// `ṡ` [m/s].
    pub spacing_rate: f64,
    /// Clearance `s − s_c` (`s_c` = 3σ improved, nσ initial) [m]; negative in solid contact.
    pub clearance: f64,
    /// Dynamic contact force `F_c ≥ 0` [N].
    pub contact_force: f64,
    /// Lubricant bearing force `P_lub ≥ 0` [N] (0 unless `lubricant = mtl`).
    pub lubricant_force: f64,
    /// Friction `Q ≥ 0` [N], solid + lubricant (acts along −X).
    pub friction: f64,
    /// Adhesion `F_s ≥ 0` [N] (pulls the slider down).
    pub adhesion: f64,
    /// Real contact area [m²].
    pub real_area: f64,
    /// DMW displacement under the POC [m].
    pub disk_displacement: f64,
    /// The damper would have pulled (`F_c` clipped to 0).
    pub clipped: bool,
    /// World offset COM → POC, x and z [m] (lever arm).
    pub lever_x: f64,
    pub lever_z: f64,
}

/// Where the bulge POC is and how it moves (what the step cap needs; no forces).
#[derive(Debug, Clone, Copy, PartialEq)]
struct PocKinematics {
    spacing: f64,
    spacing_rate: f64,
    disk_displacement: f64,
    lever_x: f64,
    lever_z: f64,
}

/// The POC kinematics of the last right-hand-side call (`None`: outside the geometry's
/// domain), for the step cap.
#[derive(Debug, Clone, Copy)]
struct KinematicsCache {
    t: f64,
    y: [f64; 4],
    kinematics: Option<PocKinematics>,
}

impl KinematicsCache {
    /// Matches no state (NaN time).
    const EMPTY: Self = KinematicsCache {
        t: f64::NAN,
        y: [f64::NAN; 4],
        kinematics: None,
    };
}

/// What one right-hand-side call leaves for the next call and for the step cap.
struct RhsCache {
    kinematics: Cell<KinematicsCache>,
    /// The DMW under the AB springs at time `.0` (NaN: none yet). It depends on the time
    /// alone, and DP5's sixth and seventh stages share theirs, so the seventh reuses the
    /// sixth's two track lookups.
    springs: Cell<(f64, DmwAtSprings)>,
}

impl RhsCache {
    fn new() -> Self {
        RhsCache {
            kinematics: Cell::new(KinematicsCache::EMPTY),
            springs: Cell::new((f64::NAN, DmwAtSprings::default())),
        }
    }
}

/// Sampled time histories of one case (SI).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CaseHistory {
    /// Sampling step [s]; sample k is at `k·dt`.
    pub dt: f64,
    pub heave: Vec<f64>,
    pub pitch_offset: Vec<f64>,
    pub heave_rate: Vec<f64>,
    pub pitch_rate: Vec<f64>,
    pub spacing: Vec<f64>,
    pub clearance: Vec<f64>,
    /// Flying height as the dissertation reports it (`s − T0` improved, `h = s` initial).
    pub flying_height: Vec<f64>,
    pub contact_force: Vec<f64>,
    /// Lubricant bearing force (0 unless `lubricant = mtl`).
    pub lubricant_force: Vec<f64>,
    pub friction: Vec<f64>,
    pub adhesion: Vec<f64>,
    pub real_area: Vec<f64>,
    pub disk_displacement: Vec<f64>,
    pub trailing_edge_spacing: Vec<f64>,
    /// Samples where the contact damper would have pulled and `F_c` was clipped to 0.
    pub clipped_samples: usize,
    pub stats: OdeStats,
    /// Nominal contact area of the bulge at this actuation [m²].
    pub nominal_area: f64,
}

impl CaseHistory {
    /// Steady-state metrics (docs/dynamics-metrics.md).
    pub fn metrics(&self, params: &CaseParams) -> Result<CaseMetrics, DynamicsError> {
        let series = CaseSeries {
            t0_s: 0.0,
            dt_s: self.dt,
            fh_m: &self.flying_height,
            clearance_m: &self.clearance,
            contact: Some(ContactSeries {
                contact_force_n: &self.contact_force,
                friction_n: &self.friction,
                real_area_m2: &self.real_area,
                adhesion_n: Some(&self.adhesion),
            }),
        };
        case_metrics(&series, params).map_err(|e| DynamicsError::Numerical(e.to_string()))
    }

    pub fn len(&self) -> usize {
        self.spacing.len()
    }

    pub fn is_empty(&self) -> bool {
        self.spacing.is_empty()
    }
}

/// One prepared case: every constant of the right-hand side computed once.
pub struct TwoDofCase<'a> {
    model: Model2Dof,
    actuation: f64,
    isbl: &'a IsblLookup,
    dmw: Option<HermiteTrack<'a>>,
    dmw_duration: f64,
    options: SimOptions,
    geometry: Slider2DofGeometry,
    /// The bulge POC at this actuation, state-independent terms precomputed.
    poc_frame: PocFrame,
    air_bearing: AirBearing2Dof,
    /// `k_r(h_TFC)` of the AB's rear spring at this actuation.
    rear_stiffness: f64,
    inverse_mass: Matrix2<f64>,
    damping: Matrix2<f64>,
    stiffness: Matrix2<f64>,
    nominal_area: f64,
    sigma: f64,
    bonded_lubricant: f64,
    contact_threshold: f64,
    contact_damping: f64,
    /// `A_n P(s_c)` [N]: the offset of the integrated-stiffness reading.
    threshold_force: f64,
    /// The MTL law on the area-scaled ISBL solid (`lubricant = mtl`).
    lubricant: Option<MtlInterface<AreaIsbl<'a>>>,
    /// DMW time shift of the LE, TE (and the bulge, 0) and the record offset of t = 0 [s].
    delay_front: f64,
    delay_rear: f64,
    bulge_x: f64,
    record_offset: f64,
    criterion: ContactCriterion,
}

fn parameter(name: &str, value: f64, why: impl Into<String>) -> DynamicsError {
    DynamicsError::parameter(name, value, why)
}

impl<'a> TwoDofCase<'a> {
    /// Prepare a case. The interface's σ and t replace the model's (the contact stage owns
    /// them); the DMW record must cover the run plus the transit delays unless `wrap_dmw`.
    pub fn new(
        model: &Model2Dof,
        actuation: f64,
        isbl: &'a IsblLookup,
        dmw: Option<DmwInput<'a>>,
        options: SimOptions,
    ) -> Result<Self, DynamicsError> {
        let mut model = *model;
        let ip = isbl.model().params();
        model.interface.sigma = ip.sigma;
        model.interface.lubricant_thickness = ip.lubricant_thickness;
        model.validate()?;
        if !(actuation.is_finite() && actuation >= 0.0 && actuation <= model.max_actuation) {
            return Err(parameter(
                "actuation h_TFC (m)",
                actuation,
                format!(
                    "must lie in [0, {} nm], the model's actuation range",
                    model.max_actuation * 1e9
                ),
            ));
        }
        options.validate()?;
        let o = &options;
        let geometry = model.geometry();
        let air_bearing = model.air_bearing_model()?;
        let suspension = model.suspension_coefficients()?;
        let m =
            air_bearing.eom_matrices(model.slider.mass, model.slider.pitch_inertia, &suspension);
        let inverse_mass = m
            .mass
            .try_inverse()
            .ok_or_else(|| DynamicsError::Numerical("singular mass matrix".into()))?;
        let nominal_area = model.nominal_contact_area(actuation)?.area;
        let sigma = model.interface.sigma;
        let criterion = model.interface.criterion;
        let contact_threshold = criterion.contact_threshold(sigma);
        // c_c = 2ζ_c √(k_c,ref m), k_c,ref at 0.5σ interference (docs/dynamics-geometry.md).
        let reference = isbl
            .at(contact_threshold - 0.5 * sigma)
            .map_err(|e| DynamicsError::Numerical(e.to_string()))?;
        let k_ref = reference.stiffness * nominal_area;
        let contact_damping =
            2.0 * model.interface.contact_damping_ratio * (k_ref * model.slider.mass).sqrt();
        let threshold_force = nominal_area
            * isbl
                .at(contact_threshold)
                .map_err(|e| DynamicsError::Numerical(e.to_string()))?
                .pressure;
        let lubricant = match o.lubricant {
            LubricantForce::None => None,
            LubricantForce::Mtl => {
                if !matches!(criterion, ContactCriterion::ThreeSigma) {
                    return Err(DynamicsError::Numerical(
                        "lubricant = mtl needs the improved model's 3σ contact criterion (the \
                         MTL law puts solid contact at 3σ, §3.2)"
                            .into(),
                    ));
                }
                Some(
                    reference_mtl(sigma, ip.lubricant_thickness, model.disk_speed)?.with_solid(
                        AreaIsbl {
                            lookup: isbl,
                            area: nominal_area,
                        },
                    ),
                )
            }
        };

        let speed = model.disk_speed;
        let bulge_x = geometry.bulge_centre().x;
        let (delay_front, delay_rear) = if o.transit_delay {
            (
                (geometry.leading_edge().x - bulge_x) / speed,
                (geometry.trailing_edge().x - bulge_x) / speed,
            )
        } else {
            (0.0, 0.0)
        };
        // The POC sits within a few µm of the bulge centre: allow 1 % of the slider length.
        let slack = if o.transit_delay {
            0.01 * model.slider.length / speed
        } else {
            0.0
        };
        let record_offset = (-delay_rear).max(0.0) + slack;
        let needed = record_offset + o.duration + delay_front.max(0.0) + slack;
        let (dmw, dmw_duration) = match dmw {
            None => (None, 0.0),
            Some(d) => {
                let track = HermiteTrack::new(d.displacement, d.velocity, 0.0, d.sample_rate)
                    .map_err(|e| DynamicsError::Numerical(format!("DMW track: {e}")))?;
                let have = track.duration();
                if have < needed && !o.wrap_dmw {
                    return Err(parameter(
                        "DMW record length (s)",
                        have,
                        format!(
                            "is shorter than the run plus the transit delays ({:.4} ms); \
                             shorten the run or set dmw_wrap = true",
                            needed * 1e3
                        ),
                    ));
                }
                (Some(track), have)
            }
        };
        let poc_frame = geometry.poc_frame(actuation)?;
        Ok(TwoDofCase {
            model,
            actuation,
            isbl,
            dmw,
            dmw_duration,
            options,
            geometry,
            poc_frame,
            rear_stiffness: air_bearing.rear_stiffness(actuation),
            air_bearing,
            inverse_mass,
            damping: m.damping,
            stiffness: m.stiffness,
            nominal_area,
            sigma,
            bonded_lubricant: model.interface.bonded_lubricant(),
            contact_threshold,
            contact_damping,
            threshold_force,
            lubricant,
            delay_front,
            delay_rear,
            bulge_x,
            record_offset,
            criterion,
        })
    }

    pub fn nominal_area(&self) -> f64 {
        self.nominal_area
    }

    pub fn contact_damping(&self) -> f64 {
        self.contact_damping
    }

    /// DMW displacement and velocity under a point delayed by `delay` [s]. Always inlined:
    /// three per right-hand side, on its critical path (the POC's).
    #[inline(always)]
    fn disk(&self, t: f64, delay: f64) -> (f64, f64) {
        match &self.dmw {
            None => (0.0, 0.0),
            Some(track) => {
                let mut tau = self.record_offset + t + delay;
                if self.options.wrap_dmw && self.dmw_duration > 0.0 {
                    tau = tau.rem_euclid(self.dmw_duration);
                }
                track.eval(tau)
            }
        }
    }

    /// The DMW under the front and rear AB springs at time `t`.
    #[inline]
    fn dmw_at_springs(&self, t: f64) -> DmwAtSprings {
        let (front, front_rate) = self.disk(t, self.delay_front);
        let (rear, rear_rate) = self.disk(t, self.delay_rear);
        DmwAtSprings {
            front,
            front_rate,
            rear,
            rear_rate,
        }
    }

    fn flying_height(&self, spacing: f64) -> f64 {
        match self.model.variant {
            ModelVariant::Improved => spacing - self.bonded_lubricant,
            ModelVariant::Initial => spacing,
        }
    }

    /// Kinematics of the bulge POC at state `y` and time `t`: spacing above the local disk
    /// surface, its rate, the DMW under it and the lever arm (no forces).
    fn poc_kinematics(&self, t: f64, y: &[f64; 4]) -> Result<PocKinematics, DynamicsError> {
        let pitch = self.model.nominal_pitch + y[1];
        self.poc_kinematics_with(t, y, &self.poc_frame.pitch_terms(pitch))
    }

    /// [`Self::poc_kinematics`] with the pitch's trigonometry given.
    #[inline]
    fn poc_kinematics_with(
        &self,
        t: f64,
        y: &[f64; 4],
        tr: &PitchTerms,
    ) -> Result<PocKinematics, DynamicsError> {
        let (z, z_rate, pitch_rate) = (y[0], y[2], y[3]);
        // Same as `geometry.bulge_poc(z, pitch, actuation)` (PocFrame's contract).
        let poc = self.poc_frame.poc(z, tr)?;
        // The POC sits a fraction of a µm from the bulge centre (the delay reference).
        let poc_delay = if self.options.transit_delay {
            (poc.lever_arm.x - self.bulge_x) / self.model.disk_speed
        } else {
            0.0
        };
        let (zd, vd) = self.disk(t, poc_delay);
        Ok(PocKinematics {
            spacing: poc.solid_spacing - zd,
            spacing_rate: self.poc_frame.spacing_rate(&poc, tr, z_rate, pitch_rate) - vd,
            disk_displacement: zd,
            lever_x: poc.lever_arm.x,
            lever_z: poc.lever_arm.z,
        })
    }

    /// Spacing of the TE above the local disk surface (for the AB-loss check and output).
    fn trailing_edge_spacing(&self, t: f64, y: &[f64; 4], tr: &PitchTerms) -> f64 {
        let te = self.geometry.trailing_edge();
        self.poc_frame.spacing_of(&te, y[0], tr) - self.disk(t, self.delay_rear).0
    }

    /// The interface at state `y` and time `t`.
    #[cfg(test)]
    fn interface(&self, t: f64, y: &[f64; 4]) -> Result<InterfaceState, DynamicsError> {
        self.interface_of(self.poc_kinematics(t, y)?, true, self.contact_damping)
    }

    /// The interface at state `y` and time `t` and the TE spacing (one sample's outputs).
    fn sample(&self, t: f64, y: &[f64; 4]) -> Result<(InterfaceState, f64), DynamicsError> {
        let tr = self.poc_frame.pitch_terms(self.model.nominal_pitch + y[1]);
        let i = self.interface_of(
            self.poc_kinematics_with(t, y, &tr)?,
            true,
            self.contact_damping,
        )?;
        Ok((i, self.trailing_edge_spacing(t, y, &tr)))
    }

    /// The interface at POC kinematics `k`. With `full = false` (the right-hand side) the
    /// real area is left at 0: the equations of motion do not use it, and skipping its
    /// lookup saves an `exp` per call; every other field is the same, bit for bit.
    /// `contact_damping`: the damper's coefficient (the case's own, or 0 for the damper-free
    /// rest state of [`Self::static_equilibrium`]).
    #[inline]
    fn interface_of(
        &self,
        k: PocKinematics,
        full: bool,
        contact_damping: f64,
    ) -> Result<InterfaceState, DynamicsError> {
        let (spacing, spacing_rate) = (k.spacing, k.spacing_rate);
        let clearance = self.criterion.clearance(spacing, self.sigma);
        let area = self.nominal_area;
        let numerical = |e: crate::contact::ContactError| DynamicsError::Numerical(e.to_string());
        let at_spacing = self.isbl.at_lazy(spacing).map_err(numerical)?;
        let adhesion = area * at_spacing.adhesion();
        let (mut contact_force, mut clipped) = (0.0, false);
        if clearance < 0.0 && area > 0.0 {
            let elastic = match self.options.contact_force {
                ContactForceForm::InterferenceTangent => {
                    area * at_spacing.stiffness() * (self.contact_threshold - spacing)
                }
                ContactForceForm::StaticCurve => area * at_spacing.pressure(),
                ContactForceForm::IntegratedStiffness => {
                    area * at_spacing.pressure() - self.threshold_force
                }
            };
            contact_force = elastic - contact_damping * spacing_rate;
            if contact_force < 0.0 {
                contact_force = 0.0;
                clipped = true;
            }
        }
        let (mut friction, mut real_area) = (0.0, 0.0);
        if contact_force > 0.0 {
            // Quasi-static equivalence P(h*) = F_c / A_n (eq. 2.16).
            if let Some(h_star) = self.isbl.separation_for_pressure(contact_force / area) {
                let at = self.isbl.at_lazy(h_star).map_err(numerical)?;
                friction = area * at.friction();
                if full {
                    real_area = area * at.real_area_fraction();
                }
            }
        }
        let mut lubricant_force = 0.0;
        if let Some(mtl) = &self.lubricant {
            if spacing < mtl.model().lubricant_surface() {
                let lub = mtl.lubricant(spacing);
                lubricant_force = lub.normal.max(0.0);
                friction += lub.friction.max(0.0);
            }
        }
        Ok(InterfaceState {
            spacing,
            spacing_rate,
            clearance,
            contact_force,
            lubricant_force,
            friction,
            adhesion,
            real_area,
            disk_displacement: k.disk_displacement,
            clipped,
            lever_x: k.lever_x,
            lever_z: k.lever_z,
        })
    }

    /// `y' = f(t, y)` (the tests' entry; the integrator and the rest state call
    /// `rhs_cached`).
    #[cfg(test)]
    fn rhs(&self, t: f64, y: &[f64; 4], dy: &mut [f64; 4]) -> Result<(), DynamicsError> {
        self.rhs_cached(t, y, dy, None, self.contact_damping)
    }

    /// [`Self::rhs`], leaving the POC kinematics of `(t, y)` in `cache` for the step cap:
    /// DP5's last stage is evaluated at the step's end state, which is where the next step
    /// cap looks, so the cap needs no POC of its own (FSAL for the kinematics).
    fn rhs_cached(
        &self,
        t: f64,
        y: &[f64; 4],
        dy: &mut [f64; 4],
        cache: Option<&RhsCache>,
        contact_damping: f64,
    ) -> Result<(), DynamicsError> {
        let state = HeavePitchState {
            heave: y[0],
            pitch_offset: y[1],
            heave_rate: y[2],
            pitch_rate: y[3],
        };
        let dmw = match cache.map(|c| c.springs.get()) {
            Some((t_cached, dmw)) if t_cached == t => dmw,
            _ => {
                let dmw = self.dmw_at_springs(t);
                if let Some(c) = cache {
                    c.springs.set((t, dmw));
                }
                dmw
            }
        };
        let f_a = self
            .air_bearing
            .eom_forcing_at(&state, &dmw, self.rear_stiffness);
        // AB loss is checked on the sampled (accepted) states in `run`: trial stages of a step
        // the controller will reject may overshoot.
        let kinematics = self.poc_kinematics(t, y);
        if let Some(c) = cache {
            c.kinematics.set(KinematicsCache {
                t,
                y: *y,
                kinematics: kinematics.as_ref().ok().copied(),
            });
        }
        let i = match kinematics.and_then(|k| self.interface_of(k, false, contact_damping)) {
            Ok(i) => i,
            // A trial stage of a step the controller will reject can leave the geometry's
            // domain (e.g. a pitch of radians): NaN makes the integrator shrink the step.
            Err(DynamicsError::Parameter { .. }) => {
                dy.fill(f64::NAN);
                return Ok(());
            }
            Err(e) => return Err(e),
        };
        // f_c = [F_c; r_x F_c + r_z Q], f_s = [−F_s; −r_x F_s] (eqs. 2.14–2.15, §1.1); the
        // lubricant bearing force acts at the POC like F_c (§4.1).
        let normal = i.contact_force + i.lubricant_force - i.adhesion;
        let f_interface = Vector2::new(normal, i.lever_x * normal + i.lever_z * i.friction);
        let q = Vector2::new(y[0], y[1]);
        let q_rate = Vector2::new(y[2], y[3]);
        let acc =
            self.inverse_mass * (f_a + f_interface - self.damping * q_rate - self.stiffness * q);
        dy[0] = y[2];
        dy[1] = y[3];
        dy[2] = acc[0];
        dy[3] = acc[1];
        Ok(())
    }

    /// Largest step allowed from state `y`: while the POC moves toward the contact threshold
    /// (from either side), at most half the time it needs to reach it, but never below
    /// `contact_max_step` — so a step ends close to every contact switch (onset, release, the
    /// damper clip that happens next to it) and the error control resolves it, while smooth
    /// steady contact and free flight run at the steps accuracy needs.
    fn step_cap(&self, t: f64, y: &[f64; 4], contact_max_step: f64, cache: &RhsCache) -> f64 {
        let c = cache.kinematics.get();
        let kinematics = if c.t == t && c.y == *y {
            c.kinematics
        } else {
            self.poc_kinematics(t, y).ok()
        };
        match kinematics {
            None => contact_max_step,
            Some(k) => {
                let clearance = self.criterion.clearance(k.spacing, self.sigma);
                let closing = -clearance.signum() * k.spacing_rate;
                if clearance == 0.0 {
                    contact_max_step
                } else if closing > 0.0 {
                    (0.5 * clearance.abs() / closing).max(contact_max_step)
                } else {
                    f64::INFINITY
                }
            }
        }
    }

    /// Accelerations at rest at `(z, ϑ)` and `t = 0` with the contact damper's coefficient
    /// `contact_damping`; `None` outside the model's domain.
    fn rest_acceleration(
        &self,
        z: f64,
        pitch_offset: f64,
        contact_damping: f64,
    ) -> Option<[f64; 2]> {
        let mut dy = [0.0; 4];
        self.rhs_cached(
            0.0,
            &[z, pitch_offset, 0.0, 0.0],
            &mut dy,
            None,
            contact_damping,
        )
        .ok()?;
        (dy[2].is_finite() && dy[3].is_finite()).then_some([dy[2], dy[3]])
    }

    /// Newton from each of `offsets` (nm of heave around `start`) with the case's contact
    /// damper, then — only if every start fails — from each again without it.
    ///
    /// The frozen DMW moves the disk at t = 0, so at rest the POC spacing changes at the
    /// DMW's rate and the contact damper adds `−c_c·ṡ` as soon as the clearance is negative:
    /// the rest force jumps by `c_c|ṡ|` at the threshold. Where the damper-free equilibrium
    /// lies just inside it (within ≈ 0.1 nm, measured: docs/model-form.md, "Summit
    /// heights") and the disk approaches, the jump straddles zero and no rest state exists;
    /// the case then starts from the damper-free one (the elastic, adhesive and AB forces
    /// balanced), the damper acting from the first step. Where a rest state with the damper
    /// exists it is returned, as before.
    fn static_equilibrium_over(
        &self,
        start: [f64; 2],
        offsets: &[f64],
    ) -> Result<[f64; 2], DynamicsError> {
        let mut first_error = None;
        for damping in [self.contact_damping, 0.0] {
            for dz in offsets {
                match self.static_equilibrium_from([start[0] + dz * 1e-9, start[1]], damping) {
                    Ok(q) => return Ok(q),
                    Err(e) => {
                        first_error.get_or_insert(e);
                    }
                }
            }
            if self.contact_damping == 0.0 {
                break;
            }
        }
        Err(first_error.expect("at least one start"))
    }

    /// Static equilibrium `(z, ϑ)` at this actuation with the DMW frozen at t = 0 (§5.4):
    /// damped Newton on the rest accelerations with a finite-difference Jacobian (without
    /// the contact damper where no rest state with it exists: `static_equilibrium_over`).
    pub fn static_equilibrium(&self) -> Result<[f64; 2], DynamicsError> {
        // Newton from the nominal state first; where strong adhesion makes the rest forces
        // fold (a jump to contact), the root lies on the other side of the fold and Newton
        // from the nominal state stalls on it, so retry from heave offsets on either side.
        self.static_equilibrium_over(
            [0.0, 0.0],
            &[0.0, -0.5, 0.5, -1.0, 1.0, -2.0, 2.0, -4.0, 4.0],
        )
    }

    /// Static equilibrium by continuation from `start` (a neighbouring equilibrium): Newton
    /// from `start` itself, then from heave offsets around it. The root nearest in the
    /// Newton sense to `start` is kept, so a sweep stepping along the actuation stays on
    /// its branch until the branch ends at a fold (docs/conventions.md).
    pub fn static_equilibrium_near(&self, start: [f64; 2]) -> Result<[f64; 2], DynamicsError> {
        self.static_equilibrium_over(
            start,
            &[0.0, -0.25, 0.25, -0.5, 0.5, -1.0, 1.0, -2.0, 2.0, -4.0, 4.0],
        )
    }

    fn static_equilibrium_from(
        &self,
        start: [f64; 2],
        contact_damping: f64,
    ) -> Result<[f64; 2], DynamicsError> {
        let fail = |why: &str| {
            DynamicsError::Numerical(format!(
                "static equilibrium at h_TFC = {:.3} nm: {why}",
                self.actuation * 1e9
            ))
        };
        // Accelerations scaled to comparable size: heave in m/s², pitch × the TE arm.
        let arm = 0.5 * self.model.slider.length;
        let norm = |a: [f64; 2]| a[0].hypot(a[1] * arm);
        let mut q = start;
        let mut a = self
            .rest_acceleration(q[0], q[1], contact_damping)
            .ok_or_else(|| fail("the start state is outside the model's domain"))?;
        for _ in 0..100 {
            let (dz, dp) = (1e-13, 1e-13 / arm);
            let az = self
                .rest_acceleration(q[0] + dz, q[1], contact_damping)
                .ok_or_else(|| fail("Jacobian probe left the domain"))?;
            let ap = self
                .rest_acceleration(q[0], q[1] + dp, contact_damping)
                .ok_or_else(|| fail("Jacobian probe left the domain"))?;
            let j = Matrix2::new(
                (az[0] - a[0]) / dz,
                (ap[0] - a[0]) / dp,
                (az[1] - a[1]) / dz,
                (ap[1] - a[1]) / dp,
            );
            let Some(step) = j.try_inverse().map(|ji| -(ji * Vector2::new(a[0], a[1]))) else {
                return Err(fail("singular Jacobian"));
            };
            let mut lambda = 1.0;
            let mut accepted = None;
            for _ in 0..40 {
                let trial = [q[0] + lambda * step[0], q[1] + lambda * step[1]];
                if let Some(at) = self.rest_acceleration(trial[0], trial[1], contact_damping) {
                    if norm(at) < norm(a) || norm(at) == 0.0 {
                        accepted = Some((trial, at));
                        break;
                    }
                }
                lambda *= 0.5;
            }
            let Some((trial, at)) = accepted else {
                // No decrease along the Newton direction: converged to rounding.
                break;
            };
            let moved = (trial[0] - q[0]).abs().max((trial[1] - q[1]).abs() * arm);
            q = trial;
            a = at;
            if moved < 1e-18 {
                break;
            }
        }
        // At rest the residual force must be negligible against the preload scale.
        let residual = norm(a) * self.model.slider.mass;
        if residual.is_nan() || residual >= 1e-9 * self.model.suspension.preload {
            return Err(fail(&format!(
                "Newton did not converge (residual force {residual:e} N)"
            )));
        }
        Ok(q)
    }

    /// Clearance of the bulge at rest at `(z, ϑ)` with the DMW frozen at t = 0 (e.g. at the
    /// static equilibrium).
    pub fn clearance_at_rest(&self, q: [f64; 2]) -> Result<f64, DynamicsError> {
        let k = self.poc_kinematics(0.0, &[q[0], q[1], 0.0, 0.0])?;
        Ok(self.criterion.clearance(k.spacing, self.sigma))
    }

    /// Integrate from the nominal state (§5.4) and sample the histories.
    pub fn run(&self) -> Result<CaseHistory, DynamicsError> {
        let o = &self.options;
        let n_samples =
            (o.duration / o.output_step * (1.0 + 4.0 * f64::EPSILON)).floor() as usize + 1;
        let mut h = CaseHistory {
            dt: o.output_step,
            nominal_area: self.nominal_area,
            ..CaseHistory::default()
        };
        for v in [
            &mut h.heave,
            &mut h.pitch_offset,
            &mut h.heave_rate,
            &mut h.pitch_rate,
            &mut h.spacing,
            &mut h.clearance,
            &mut h.flying_height,
            &mut h.contact_force,
            &mut h.lubricant_force,
            &mut h.friction,
            &mut h.adhesion,
            &mut h.real_area,
            &mut h.disk_displacement,
            &mut h.trailing_edge_spacing,
        ] {
            v.reserve_exact(n_samples);
        }
        // The observer only records the sampled times and states; their interface outputs are
        // computed after the integration (`sample` is pure, so the values are the same):
        // independent of one another there, their trigonometry and table lookups overlap,
        // where inside the step loop each waited on the integrator's serial chain of stages.
        let mut times: Vec<f64> = Vec::with_capacity(n_samples);
        let observer = |t: f64, y: &[f64; 4]| {
            times.push(t);
            h.heave.push(y[0]);
            h.pitch_offset.push(y[1]);
            h.heave_rate.push(y[2]);
            h.pitch_rate.push(y[3]);
        };
        // atol: 1e-14 m, 1e-11 rad; rates × 2π × 1 MHz (docs/integrator.md).
        let w = 2.0 * std::f64::consts::PI * 1e6;
        let atol = [1e-14, 1e-11, 1e-14 * w, 1e-11 * w];
        let mut start = o.initial_state;
        if o.static_init {
            let q = match o.static_start {
                Some(q0) => self.static_equilibrium_near(q0)?,
                None => self.static_equilibrium()?,
            };
            start[0] += q[0];
            start[1] += q[1];
        }
        let cache = RhsCache::new();
        let rhs = |t: f64, y: &[f64; 4], dy: &mut [f64; 4]| {
            self.rhs_cached(t, y, dy, Some(&cache), self.contact_damping)
        };
        let sampling = Sampling::Uniform { dt: o.output_step };
        let result = match o.integrator {
            Integrator::Dopri5 {
                rtol,
                contact_max_step,
                max_step,
            } => {
                let mut opts = OdeOptions::adaptive_per_component(rtol, atol);
                opts.max_step = max_step;
                opts.max_steps = 50_000_000;
                integrate_capped(
                    rhs,
                    |t, y| self.step_cap(t, y, contact_max_step, &cache),
                    0.0,
                    start,
                    o.duration,
                    &opts,
                    sampling,
                    observer,
                )
            }
            Integrator::Rk5Fixed { step } => {
                let mut opts = OdeOptions::fixed(step);
                opts.max_steps = u64::MAX;
                crate::numerics::ode::integrate(
                    rhs, 0.0, start, o.duration, &opts, sampling, observer,
                )
            }
        };
        let mut sample_error: Option<DynamicsError> = None;
        let mut ab_lost: Option<(f64, f64)> = None;
        for (k, &t) in times.iter().enumerate() {
            let y = [
                h.heave[k],
                h.pitch_offset[k],
                h.heave_rate[k],
                h.pitch_rate[k],
            ];
            match self.sample(t, &y) {
                Ok((i, te_spacing)) => {
                    let te_fh = self.flying_height(te_spacing);
                    if te_fh > AB_LOSS_FLYING_HEIGHT && ab_lost.is_none() {
                        ab_lost = Some((t, te_fh));
                    }
                    h.spacing.push(i.spacing);
                    h.clearance.push(i.clearance);
                    h.flying_height.push(self.flying_height(i.spacing));
                    h.contact_force.push(i.contact_force);
                    h.lubricant_force.push(i.lubricant_force);
                    h.friction.push(i.friction);
                    h.adhesion.push(i.adhesion);
                    h.real_area.push(i.real_area);
                    h.disk_displacement.push(i.disk_displacement);
                    h.trailing_edge_spacing.push(te_spacing);
                    h.clipped_samples += usize::from(i.clipped);
                }
                Err(e) => {
                    if sample_error.is_none() {
                        sample_error = Some(e);
                    }
                }
            }
        }
        // The first sample beyond the AB limit decides, whatever happened after it.
        if let Some((t, fh)) = ab_lost {
            return Err(DynamicsError::Numerical(format!(
                "air bearing lost at t = {:.4} ms: the TE flying height reached {:.2} nm (> {:.0} \
                 nm, docs/simulation.md); the linear AB model does not hold there",
                t * 1e3,
                fh * 1e9,
                AB_LOSS_FLYING_HEIGHT * 1e9
            )));
        }
        let solution = result.map_err(integration_error)?;
        if let Some(e) = sample_error {
            return Err(e);
        }
        h.stats = solution.stats;
        if h.spacing.iter().any(|v| !v.is_finite()) {
            return Err(DynamicsError::Numerical(
                "non-finite spacing in the sampled history".into(),
            ));
        }
        Ok(h)
    }
}

/// The reference lubricant (Table 4.4 case 0: the FWM fit at μ0 = 0.31 Pa·s, κ = 0.3 nm) on a
/// film of the interface's σ and t at the disk speed, as the 3-DOF builds it (§4.1).
pub fn reference_mtl(sigma: f64, thickness: f64, speed: f64) -> Result<RoughMtl, DynamicsError> {
    let case = LubricantCase::Reference;
    let numerical = |e: crate::contact::ContactError| DynamicsError::Numerical(e.to_string());
    let film = RoughFilm::new(sigma, case.kappa(), thickness, speed).map_err(numerical)?;
    let exp = FwmExperiment::fukuzawa_z03()
        .with_limiting_viscosity(case.limiting_viscosity())
        .map_err(numerical)?;
    RoughMtl::from_experiment(film, &exp).map_err(numerical)
}

/// A failed integration as one clear error (shared by the 2-DOF and 3-DOF cases).
pub(crate) fn integration_error(e: OdeError<DynamicsError>) -> DynamicsError {
    DynamicsError::Numerical(match e {
        OdeError::Rhs { t, source: m } => format!("at t = {:.6} ms: {m}", t * 1e3),
        OdeError::StepUnderflow { t, h } => format!(
            "integration failed: the step fell to {h:e} s at t = {:.6} ms (no convergence)",
            t * 1e3
        ),
        OdeError::NonFinite { t, component } => format!(
            "integration failed: state component {component} became non-finite at t = {:.6} ms",
            t * 1e3
        ),
        OdeError::MaxStepsExceeded { t, steps } => format!(
            "integration failed: more than {steps} steps by t = {:.6} ms",
            t * 1e3
        ),
        OdeError::InvalidInput(m) => format!("integration failed: {m}"),
    })
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod model_form_tests;
