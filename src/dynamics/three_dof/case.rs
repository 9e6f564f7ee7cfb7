//! One 3-DOF slider case (§4.1, eqs. 4.1–4.35; docs/three-dof.md): the Table 4.1–4.3 slider with
//! its features, the PT-dependent air bearing with TFC push-back, the ISBL or MTL interface per
//! feature, the three DMW tracks, an actuation profile and an optional shock → sampled time
//! histories. Pure: no I/O.
//!
//! State `y = [z, ϑ, φ, ż, ϑ̇, φ̇]`: COM heave from the nominal state, pitch offset `θ − θ0`,
//! roll. Per right-hand-side evaluation: actuation and its rate from the profile; every feature's
//! lowest point, spacing above its own DMW track (transit-delayed), nominal area by truncation
//! and interfacial forces; the two AB springs with `k(PT)` and `ΔF_AB(h_TFC)`; the roll spring
//! against the disk's roll under the slider; the shock; `M q̈ = f − C q̇ − K q`.
//!
//! **Roll input (our reading, docs/three-dof.md).** Eq. 4.3 puts the roll spring `k_l` in `K`
//! acting on `φ` alone (`RollSpring::Absolute`). By default we let it act on the roll
//! *relative to the disk surface* under the two halves of the ABS, `φ − φ_d` with
//! `φ_d = (z_d,+y − z_d,−y)/(2 y_AB)`, `y_AB = l_w/4` (the centroid of each half)
//! [assumption]. Without it the ±y tracks could only act through
//! features within 6σ of the disk, and the dissertation's three-track roll excitation (§4.1.7)
//! would vanish whenever the slider flies.

use super::geometry::{
    DmwTrack, Feature, FeaturePoints, PoseRates, Slider3DofGeometry, SliderPose,
};
use super::inputs::{ActuationProfile, ShockPulse};
use super::interface::{FeatureForces, FeatureInterface};
use crate::dynamics::geometry::generalised_force;
use crate::dynamics::three_dof::air_bearing::{
    DeltaFabTable, NominalForce, PushbackCurve, RollSpring, SpringSpacings, StaticCondition,
    StaticState, StiffnessArgument, ThreeDofAbParams, ThreeDofAirBearing,
};
use crate::dynamics::two_dof::{integration_error, DmwInput};
use crate::dynamics::DynamicsError;
use crate::numerics::ode::{integrate_capped, OdeOptions, OdeStats, Sampling};
use crate::signal::resample::HermiteTrack;
use nalgebra::{Matrix3, Vector3};
use std::cell::Cell;

/// The slider: geometry, air bearing and the TFC push-back curve (§11.3).
#[derive(Debug, Clone, PartialEq)]
pub struct Model3Dof {
    pub geometry: Slider3DofGeometry,
    pub air_bearing: ThreeDofAbParams,
    pub pushback: PushbackCurve,
    /// Disk speed under the slider `U` [m/s] (transit delay of the DMW, §6).
    pub disk_speed: f64,
    /// `φ0` [rad] (Table 4.1: −10 µrad).
    pub initial_roll: f64,
}

impl Model3Dof {
    /// Tables 4.1–4.3 with the spec's defaults (linear push-back `0.5·h`).
    pub fn dissertation() -> Self {
        Model3Dof {
            geometry: Slider3DofGeometry::dissertation(),
            air_bearing: ThreeDofAbParams::default(),
            pushback: PushbackCurve::default(),
            disk_speed: 19.5,
            initial_roll: -10e-6,
        }
    }
}

/// `ΔF_AB(h_TFC)` of a model's push-back calibration (docs/dynamics-3dof-air-bearing.md). Under
/// the printed nominal forces it is calibrated on the same AB with balanced ones: the push-back
/// data (Fig. 4.4) are an input to the AB model, not a property of how its springs are
/// preloaded; calibrated against the printed forces' own re-trimmed state instead, the TE spring
/// reaches `FH_lim` by h ≈ 10.5 nm (7 nm with the linear law), short of Table 4.4's 18 nm.
pub fn delta_force_table(model: &Model3Dof) -> Result<DeltaFabTable, DynamicsError> {
    let ab = match model.air_bearing.nominal_force {
        NominalForce::Balanced => ThreeDofAirBearing::new(&model.air_bearing)?,
        NominalForce::AsPrinted => ThreeDofAirBearing::new(&ThreeDofAbParams {
            nominal_force: NominalForce::Balanced,
            ..model.air_bearing.clone()
        })?,
    };
    DeltaFabTable::calibrate_default(&ab, &model.pushback)
}

/// The static state a case with `Init3Dof::AirBearingStatic` starts from at actuation `h`
/// (roll 0, no DMW, no interfacial forces). Balanced nominal forces: the calibration's own rise,
/// not its `ΔF_AB`, because with `k` tied to PT the same `ΔF_AB` also balances on a stiff branch
/// with a much smaller PT. Printed nominal forces: the balance under the calibrated `ΔF_AB(h)`,
/// found from the balanced calibration's state at the nearest grid point.
pub fn static_start(
    model: &Model3Dof,
    ab: &ThreeDofAirBearing,
    delta_force: &DeltaFabTable,
    h: f64,
) -> Result<StaticState, DynamicsError> {
    match model.air_bearing.nominal_force {
        NominalForce::Balanced => ab.solve_static(
            h,
            StaticCondition::TfcRise(model.pushback.rise_at(h)),
            None,
            false,
        ),
        NominalForce::AsPrinted => {
            let near = delta_force
                .points()
                .iter()
                .min_by(|a, b| (a.actuation - h).abs().total_cmp(&(b.actuation - h).abs()));
            let force = delta_force.delta_force_at(h);
            ab.solve_static(h, StaticCondition::GivenForce(force), near, false)
                .map_err(|e| {
                    DynamicsError::Numerical(format!(
                        "no static start under the printed nominal forces at h_TFC = {:.2} nm, \
                         ΔF_AB = {:.3} mN ({e}); with the linear spring law the TE spring \
                         reaches FH_lim first: start from the nominal state (init = \"nominal\")",
                        h * 1e9,
                        force * 1e3
                    ))
                })
        }
    }
}

/// Which DMW track each feature rides on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TrackAssignment {
    /// §6: bulge and centre line → D1, +y features → D2, −y features → D3.
    Three,
    /// D1 under every point (no roll input from the disk).
    One,
}

/// Initial state (§5.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Init3Dof {
    /// `z = 0`, `θ = θ0`, `φ = φ0`: the push-back develops as the initial transient.
    Nominal,
    /// Heave and pitch of the AB's static equilibrium at the initial actuation with the
    /// push-back curve's rise (no DMW, no interfacial forces), `φ = φ0`: the push-back is
    /// already there. (From the nominal state a constant high actuation lands on the stiff
    /// branch of the `k(PT)` equilibria instead; docs/three-dof.md.)
    AirBearingStatic,
}

/// Options of one case.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options3Dof {
    pub duration: f64,
    pub output_step: f64,
    pub rtol: f64,
    /// Step cap near a contact or lubricant boundary [s].
    pub contact_max_step: f64,
    pub max_step: f64,
    pub transit_delay: bool,
    pub wrap_dmw: bool,
    pub tracks: TrackAssignment,
    pub init: Init3Dof,
    /// Heave offset added to the start state [m] (0 by default): a kick whose free decay shows
    /// the heave/pitch AB modes (App. B's zero excitation; the initial roll `φ0` only excites
    /// the roll mode, which is decoupled from heave and pitch while no feature touches).
    pub initial_heave: f64,
}

impl Default for Options3Dof {
    fn default() -> Self {
        Options3Dof {
            duration: 2e-3,
            output_step: 0.25e-6,
            rtol: 1e-8,
            contact_max_step: 1e-8,
            max_step: 1e-6,
            transit_delay: true,
            wrap_dmw: false,
            tracks: TrackAssignment::Three,
            init: Init3Dof::AirBearingStatic,
            initial_heave: 0.0,
        }
    }
}

fn parameter(name: &str, value: f64, why: impl Into<String>) -> DynamicsError {
    DynamicsError::parameter(name, value, why)
}

impl Options3Dof {
    pub fn validate(&self) -> Result<(), DynamicsError> {
        if !(self.duration > 0.0 && self.duration <= 0.1) {
            return Err(parameter(
                "duration (s)",
                self.duration,
                "must lie in (0, 0.1] s",
            ));
        }
        if !(self.output_step > 0.0 && self.output_step <= self.duration)
            || self.duration / self.output_step > 5e7
        {
            return Err(parameter(
                "output step (s)",
                self.output_step,
                "must be > 0, at most the duration and give at most 5·10⁷ samples",
            ));
        }
        if !(self.rtol > 0.0 && self.rtol < 1e-2) {
            return Err(parameter("rtol", self.rtol, "must lie in (0, 0.01)"));
        }
        if !(self.initial_heave.is_finite() && self.initial_heave.abs() <= 5e-9) {
            return Err(parameter(
                "initial heave (m)",
                self.initial_heave,
                "|z0| ≤ 5 nm",
            ));
        }
        for (name, v) in [
            ("contact_max_step (s)", self.contact_max_step),
            ("max_step (s)", self.max_step),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(parameter(name, v, "must be finite and > 0"));
            }
        }
        Ok(())
    }
}

/// Sampled histories of one case (SI). Per-feature series follow [`Feature`] order of
/// `features`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct History3Dof {
    pub dt: f64,
    pub heave: Vec<f64>,
    pub pitch: Vec<f64>,
    pub roll: Vec<f64>,
    pub heave_rate: Vec<f64>,
    pub pitch_rate: Vec<f64>,
    pub roll_rate: Vec<f64>,
    pub actuation: Vec<f64>,
    /// Pole-tip FH (read element spacing above its local disk surface).
    pub pole_tip: Vec<f64>,
    /// Solid spacing of the bulge's lowest point (the FH series of §8).
    pub bulge_spacing: Vec<f64>,
    /// Sums over the features.
    pub contact_force: Vec<f64>,
    pub lubricant_force: Vec<f64>,
    pub adhesion: Vec<f64>,
    pub friction: Vec<f64>,
    pub real_area: Vec<f64>,
    /// AB spring forces.
    pub front_force: Vec<f64>,
    pub rear_force: Vec<f64>,
    pub shock_force: Vec<f64>,
    pub features: Vec<Feature>,
    /// `feature_spacing[i][k]`: spacing of feature i at sample k.
    pub feature_spacing: Vec<Vec<f64>>,
    /// `feature_normal[i][k]`: `N = F_c + P_lub − F_s` of feature i.
    pub feature_normal: Vec<Vec<f64>>,
    /// `feature_contact[i][k]`: solid contact force `F_c` of feature i, and its contact
    /// damper's part `−c_c ṡ` (`feature_contact_damping`; the rest is elastic).
    pub feature_contact: Vec<Vec<f64>>,
    pub feature_contact_damping: Vec<Vec<f64>>,
    /// Samples with an AB spring beyond `FH_lim` (carrying no force).
    pub ab_lost_samples: usize,
    pub clipped_samples: usize,
    pub stats: OdeStats,
    /// The largest total contact and lubricant force (N) over the integrator's accepted steps
    /// and the samples: an impact shorter than the output step (the S4 shock's, ~0.2 µs)
    /// peaks between samples.
    pub peak_contact_force: f64,
    pub peak_lubricant_force: f64,
}

impl History3Dof {
    pub fn len(&self) -> usize {
        self.heave.len()
    }
    pub fn is_empty(&self) -> bool {
        self.heave.is_empty()
    }
    /// BV/FHM (eq. 2.1: 5 largest/smallest samples, FH_nom 11 nm) of the bulge spacing over
    /// `[start, end)` seconds; `None` for fewer than 10 samples.
    pub fn bulge_vibration(&self, (start, end): (f64, f64)) -> Option<f64> {
        let n = self.bulge_spacing.len();
        let i0 = ((start / self.dt).round().max(0.0) as usize).min(n);
        let i1 = ((end / self.dt).round().max(0.0) as usize).clamp(i0, n);
        let w = &self.bulge_spacing[i0..i1];
        if w.len() < 10 {
            return None;
        }
        crate::dynamics::metrics::modulation(w, 11e-9, 5)
            .ok()
            .map(|m| m.percent)
    }

    /// First sample time at which any feature is below `spacing` (e.g. the lubricant surface).
    pub fn first_time_below(&self, spacing: f64) -> Option<f64> {
        (0..self.len())
            .find(|&k| self.feature_spacing.iter().any(|s| s[k] < spacing))
            .map(|k| k as f64 * self.dt)
    }

    /// Table 4.4 vibrations of a variable-actuation case (docs/dynamics-metrics.md windows): flying
    /// FHM, jump-to-contact BV, steady-contact BV. The flying window ends at the first ramp of the
    /// profile (over a ramp the formula measures the ramp, not vibration).
    pub fn table_4_4(&self, profile: &ActuationProfile, lubricant_surface: f64) -> Table44 {
        let entry = self.first_time_below(lubricant_surface);
        let Some(w) = self.regime_windows(profile, lubricant_surface) else {
            return Table44::default();
        };
        Table44 {
            first_lubricant_contact: entry,
            flying_fhm: self.bulge_vibration(w.flying),
            jump_to_contact_bv: w.jump_to_contact.and_then(|s| self.bulge_vibration(s)),
            steady_contact_bv: w.steady_contact.and_then(|s| self.bulge_vibration(s)),
        }
    }

    /// The Table 4.4 windows of this run (`None` for a constant profile): what
    /// [`Self::table_4_4`] measures and the regime bands of the variable-actuation plot.
    pub fn regime_windows(
        &self,
        profile: &ActuationProfile,
        lubricant_surface: f64,
    ) -> Option<super::inputs::RegimeWindows> {
        let plateau = profile.plateau().filter(|_| !profile.is_constant())?;
        let entry = self.first_time_below(lubricant_surface);
        let end = self.len().saturating_sub(1) as f64 * self.dt;
        let mut w = super::inputs::regime_windows(entry, plateau, end);
        if let Some(&ramp) = profile.breakpoints().first() {
            w.flying.1 = w.flying.1.min(ramp);
        }
        Some(w)
    }

    /// Index of `feature` in the per-feature series.
    pub fn feature_index(&self, feature: Feature) -> Option<usize> {
        self.features.iter().position(|f| *f == feature)
    }
}

/// Table 4.4 numbers of one variable-actuation case [%] and the first lubricant contact [s].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Table44 {
    pub first_lubricant_contact: Option<f64>,
    pub flying_fhm: Option<f64>,
    pub jump_to_contact_bv: Option<f64>,
    pub steady_contact_bv: Option<f64>,
}

/// Everything of one instant (what the right-hand side and the sampler share).
#[derive(Debug, Clone, Copy)]
struct Evaluation {
    generalised: Vector3<f64>,
    actuation: f64,
    pole_tip: f64,
    bulge_spacing: f64,
    totals: FeatureForces,
    front: f64,
    rear: f64,
    ab_lost: bool,
    shock: f64,
    clipped: bool,
    /// Smallest time to reach a contact/lubricant boundary over the features (step cap).
    closing_time: f64,
}

/// The closing time of the last right-hand-side evaluation (`None`: outside the geometry's
/// domain), for the step cap.
#[derive(Debug, Clone, Copy)]
struct ClosingCache {
    t: f64,
    y: [f64; 6],
    closing_time: Option<f64>,
    /// Total contact and lubricant force there (for the peaks over the accepted steps).
    contact_force: f64,
    lubricant_force: f64,
}

impl ClosingCache {
    /// Matches no state (NaN time).
    const EMPTY: Self = ClosingCache {
        t: f64::NAN,
        y: [f64::NAN; 6],
        closing_time: None,
        contact_force: f64::NAN,
        lubricant_force: f64::NAN,
    };
}

/// One prepared case.
pub struct ThreeDofCase<'a> {
    model: Model3Dof,
    ab: ThreeDofAirBearing,
    delta_force: DeltaFabTable,
    interface: FeatureInterface<'a>,
    profile: ActuationProfile,
    shock: Option<ShockPulse>,
    tracks: Option<[HermiteTrack<'a>; 3]>,
    dmw_duration: f64,
    options: Options3Dof,
    inverse_mass: Matrix3<f64>,
    damping: Matrix3<f64>,
    stiffness: Matrix3<f64>,
    roll_spring: (f64, f64),
    roll_span: f64,
    bulge_x: f64,
    record_offset: f64,
    spring_points: [Vector3<f64>; 2],
    features: Vec<Feature>,
}

impl<'a> ThreeDofCase<'a> {
    /// Prepare a case. `dmw`: tracks D1–D3 (displacement and velocity, same rate), covering the
    /// run plus the transit delays unless `wrap_dmw`.
    pub fn new(
        model: &Model3Dof,
        interface: FeatureInterface<'a>,
        profile: ActuationProfile,
        shock: Option<ShockPulse>,
        dmw: Option<[DmwInput<'a>; 3]>,
        options: Options3Dof,
    ) -> Result<Self, DynamicsError> {
        options.validate()?;
        model.geometry.validate()?;
        if !(model.disk_speed.is_finite() && model.disk_speed > 0.0) {
            return Err(parameter(
                "disk speed U (m/s)",
                model.disk_speed,
                "must be > 0",
            ));
        }
        if model.initial_roll.is_nan() || model.initial_roll.abs() > 1e-3 {
            return Err(parameter(
                "initial roll φ0 (rad)",
                model.initial_roll,
                "|φ0| ≤ 1 mrad",
            ));
        }
        let ab = ThreeDofAirBearing::new(&model.air_bearing)?;
        let delta_force = delta_force_table(model)?;
        let (lo, hi) = profile.range();
        let b = model.geometry.bulge_height;
        if lo < b || hi > delta_force.max_actuation() {
            return Err(parameter(
                "actuation h_TFC (m)",
                if lo < b { lo } else { hi },
                format!(
                    "must lie in [{:.1} nm (the bulge height b_TFC), {:.1} nm (where the push-back \
                     calibration still has an air bearing)]",
                    b * 1e9,
                    delta_force.max_actuation() * 1e9
                ),
            ));
        }
        if let Some(s) = &shock {
            if s.start + s.duration > options.duration {
                return Err(parameter(
                    "shock start (s)",
                    s.start,
                    "the pulse must end inside the run",
                ));
            }
        }
        let m = ab.eom_matrices();
        let inverse_mass = m
            .mass
            .try_inverse()
            .ok_or_else(|| DynamicsError::Numerical("singular mass matrix".into()))?;
        let g = &model.geometry;
        let bulge_x = g.bulge_centre(b).x;
        let u = model.disk_speed;
        let half_l = 0.5 * g.length;
        let (delay_front, delay_rear) = if options.transit_delay {
            ((half_l - bulge_x) / u, (-half_l - bulge_x) / u)
        } else {
            (0.0, 0.0)
        };
        let slack = if options.transit_delay {
            0.01 * g.length / u
        } else {
            0.0
        };
        let record_offset = (-delay_rear).max(0.0) + slack;
        let needed = record_offset + options.duration + delay_front.max(0.0) + slack;
        let (tracks, dmw_duration) = match dmw {
            None => (None, 0.0),
            Some(d) => {
                let mk = |k: usize| {
                    HermiteTrack::new(d[k].displacement, d[k].velocity, 0.0, d[k].sample_rate)
                        .map_err(|e| DynamicsError::Numerical(format!("DMW track {}: {e}", k + 1)))
                };
                let t = [mk(0)?, mk(1)?, mk(2)?];
                let have = t.iter().map(|t| t.duration()).fold(f64::INFINITY, f64::min);
                if have < needed && !options.wrap_dmw {
                    return Err(parameter(
                        "DMW record length (s)",
                        have,
                        format!(
                            "is shorter than the run plus the transit delays ({:.4} ms); shorten \
                             the run or set dmw_wrap = true",
                            needed * 1e3
                        ),
                    ));
                }
                (Some(t), have)
            }
        };
        let d = ab.damping();
        let features: Vec<Feature> = g.active_features(0.0).collect();
        Ok(ThreeDofCase {
            model: model.clone(),
            spring_points: ab.spring_points(),
            roll_spring: (ab.roll_stiffness(), d.roll),
            ab,
            delta_force,
            interface,
            profile,
            shock,
            tracks,
            dmw_duration,
            options,
            inverse_mass,
            damping: m.damping,
            stiffness: m.stiffness,
            roll_span: 0.25 * g.width,
            bulge_x,
            record_offset,
            features,
        })
    }

    /// `ΔF_AB(h_TFC)` of this slider's push-back calibration [N].
    pub fn delta_force_at(&self, actuation: f64) -> f64 {
        self.delta_force.delta_force_at(actuation)
    }

    /// DMW `(z_d, ż_d)` of `track` under world x (relative to the COM) at time `t`.
    #[inline]
    fn disk(&self, track: DmwTrack, x: f64, t: f64) -> (f64, f64) {
        let Some(tracks) = &self.tracks else {
            return (0.0, 0.0);
        };
        let k = match self.options.tracks {
            TrackAssignment::Three => track.index(),
            TrackAssignment::One => 0,
        };
        let delay = if self.options.transit_delay {
            (x - self.bulge_x) / self.model.disk_speed
        } else {
            0.0
        };
        let mut tau = self.record_offset + t + delay;
        if self.options.wrap_dmw && self.dmw_duration > 0.0 {
            tau = tau.rem_euclid(self.dmw_duration);
        }
        tracks[k].eval(tau)
    }

    /// Pose and rates at `t` (the actuation from the profile).
    fn pose(&self, t: f64, y: &[f64; 6]) -> (SliderPose, PoseRates) {
        let (h, h_rate) = self.profile.at(t);
        let pose = SliderPose {
            heave: y[0],
            pitch: self.model.geometry.nominal_pitch + y[1],
            roll: y[2],
            actuation: h,
        };
        let rates = PoseRates {
            heave: y[3],
            pitch: y[4],
            roll: y[5],
            actuation: h_rate,
        };
        (pose, rates)
    }

    fn evaluate(&self, t: f64, y: &[f64; 6]) -> Result<Evaluation, DynamicsError> {
        let g = &self.model.geometry;
        let (pose, rates) = self.pose(t, y);
        let (h, pitch) = (pose.actuation, pose.pitch);
        let att = pose.attitude();
        let mut points = FeaturePoints::new();
        g.evaluate_features(&pose, &rates, &mut points)?;
        let sigma = self.interface.sigma();
        let (solid, lube) = (
            self.interface.solid_threshold(),
            self.interface.lubricant_surface(),
        );
        let mut generalised = Vector3::zeros();
        let mut totals = FeatureForces::default();
        let (mut bulge_spacing, mut clipped) = (f64::NAN, false);
        let mut closing_time = f64::INFINITY;
        for p in points.as_slice() {
            let (zd, vd) = self.disk(p.dmw_track(), p.world_x(), t);
            let s = p.solid_spacing - zd;
            let rate = p.spacing_rate - vd;
            if p.feature == Feature::Bulge {
                bulge_spacing = s;
            }
            // Time to the nearest boundary this feature is closing on (either side).
            for b in [solid, lube] {
                let gap = s - b;
                let closing = -gap.signum() * rate;
                if closing > 0.0 {
                    closing_time = closing_time.min(gap.abs() / closing);
                }
            }
            if s >= 2.0 * solid {
                continue; // beyond 6σ: no area, no force
            }
            let area = g.nominal_contact_area_at_spacing(p.feature, &pose, s, sigma)?;
            let f = self.interface.forces(s, rate, area)?;
            let gf = generalised_force(&p.lever_arm, &att, f.normal(), f.friction);
            generalised += Vector3::new(gf.heave, gf.pitch_moment, gf.roll_moment);
            totals.contact_force += f.contact_force;
            totals.lubricant_force += f.lubricant_force;
            totals.adhesion += f.adhesion;
            totals.friction += f.friction;
            totals.real_area += f.real_area;
            clipped |= f.clipped;
        }
        // AB springs on the centre line (track 1), PT of the read element (track 1).
        let mut sp = SpringSpacings::default();
        let mut zd_rear = 0.0;
        for (j, p) in self.spring_points.iter().enumerate() {
            let x = att.world_offset(p).x;
            let (zd, vd) = self.disk(DmwTrack::Centre, x, t);
            if j == 1 {
                zd_rear = zd;
            }
            let s = g.spacing_of(p, y[0], pitch, y[2]) - zd;
            let r = g.spacing_rate_of(p, pitch, y[2], &rates) - vd;
            if j == 0 {
                (sp.front, sp.front_rate) = (s, r);
            } else {
                (sp.rear, sp.rear_rate) = (s, r);
            }
        }
        let read = g.read_element(h)?;
        let (zd_read, _) = self.disk(DmwTrack::Centre, att.world_offset(&read).x, t);
        let pole_tip_mean_plane = g.pole_tip_spacing(y[0], pitch, y[2], h)?;
        let pole_tip = pole_tip_mean_plane - zd_read;
        // The stiffness argument: PT over the disk under the rear spring, the same surface the
        // spring's own deflection is measured from. With the DMW under the read element 15 µm
        // away instead, k(PT) turns every short-wavelength DMW component into a spring force
        // independent of the spring's deflection (docs/three-dof.md).
        let stiffness_pole_tip = match self.model.air_bearing.stiffness_argument {
            StiffnessArgument::RearSpringDisk => pole_tip_mean_plane - zd_rear,
            StiffnessArgument::PoleTip => pole_tip,
            StiffnessArgument::StaticPoleTip => self.delta_force.pole_tip_at(h),
        };
        let ab = self.ab.forces(
            &sp,
            stiffness_pole_tip,
            self.delta_force.delta_force_at(h),
            &att,
        );
        generalised += ab.generalised;
        // Roll spring against the disk's roll under the two ABS halves (module doc), unless it
        // acts on φ alone as printed (then it is all in `K`).
        if self.tracks.is_some()
            && self.options.tracks == TrackAssignment::Three
            && self.model.air_bearing.roll_spring == RollSpring::DiskRelative
        {
            let (zp, vp) = self.disk(DmwTrack::PlusY, 0.0, t);
            let (zm, vm) = self.disk(DmwTrack::MinusY, 0.0, t);
            let span = 2.0 * self.roll_span;
            let (k_l, c_l) = self.roll_spring;
            generalised[2] += k_l * (zp - zm) / span + c_l * (vp - vm) / span;
        }
        let shock = self.shock.map_or(0.0, |s| s.force(t));
        generalised[0] -= shock;
        Ok(Evaluation {
            generalised,
            actuation: h,
            pole_tip,
            bulge_spacing,
            totals,
            front: ab.front,
            rear: ab.rear,
            ab_lost: ab.ab_lost(),
            shock,
            clipped,
            closing_time,
        })
    }

    /// `y' = f(t, y)`; with a `cache`, leaves the closing time of `(t, y)` there for the step
    /// cap (DP5's last stage is evaluated at the step's end state, where the next cap looks:
    /// the cap then needs no evaluation of its own).
    fn rhs(
        &self,
        t: f64,
        y: &[f64; 6],
        dy: &mut [f64; 6],
        cache: Option<&Cell<ClosingCache>>,
    ) -> Result<(), DynamicsError> {
        let e = self.evaluate(t, y);
        if let Some(c) = cache {
            let ok = e.as_ref().ok();
            c.set(ClosingCache {
                t,
                y: *y,
                closing_time: ok.map(|e| e.closing_time),
                contact_force: ok.map_or(f64::NAN, |e| e.totals.contact_force),
                lubricant_force: ok.map_or(f64::NAN, |e| e.totals.lubricant_force),
            });
        }
        let e = match e {
            Ok(e) => e,
            // A trial stage the controller will reject may leave the geometry's domain.
            Err(DynamicsError::Parameter { .. }) => {
                dy.fill(f64::NAN);
                return Ok(());
            }
            Err(e) => return Err(e),
        };
        let q = Vector3::new(y[0], y[1], y[2]);
        let q_rate = Vector3::new(y[3], y[4], y[5]);
        let acc = self.inverse_mass * (e.generalised - self.damping * q_rate - self.stiffness * q);
        dy[..3].copy_from_slice(&y[3..]);
        dy[3] = acc[0];
        dy[4] = acc[1];
        dy[5] = acc[2];
        Ok(())
    }

    /// Start state (§5.4), plus the options' heave kick.
    pub fn initial_state(&self) -> Result<[f64; 6], DynamicsError> {
        let roll = self.model.initial_roll;
        let kick = self.options.initial_heave;
        match self.options.init {
            Init3Dof::Nominal => Ok([kick, 0.0, roll, 0.0, 0.0, 0.0]),
            Init3Dof::AirBearingStatic => {
                let h = self.profile.at(0.0).0;
                let s = static_start(&self.model, &self.ab, &self.delta_force, h)?;
                Ok([
                    s.heave + kick,
                    s.pitch - self.model.geometry.nominal_pitch,
                    roll,
                    0.0,
                    0.0,
                    0.0,
                ])
            }
        }
    }

    /// Integrate and sample.
    pub fn run(&self) -> Result<History3Dof, DynamicsError> {
        let o = &self.options;
        let n = (o.duration / o.output_step * (1.0 + 4.0 * f64::EPSILON)).floor() as usize + 1;
        let nf = self.features.len();
        let mut h = History3Dof {
            dt: o.output_step,
            features: self.features.clone(),
            feature_spacing: vec![Vec::with_capacity(n); nf],
            feature_normal: vec![Vec::with_capacity(n); nf],
            feature_contact: vec![Vec::with_capacity(n); nf],
            feature_contact_damping: vec![Vec::with_capacity(n); nf],
            ..History3Dof::default()
        };
        let mut sample_error: Option<DynamicsError> = None;
        let observer = |t: f64, y: &[f64; 6]| {
            if sample_error.is_some() {
                return;
            }
            match self.sample(t, y, &mut h) {
                Ok(()) => {}
                Err(e) => sample_error = Some(e),
            }
        };
        let w = std::f64::consts::TAU * 1e6;
        let atol = [1e-14, 1e-11, 1e-11, 1e-14 * w, 1e-11 * w, 1e-11 * w];
        let mut opts = OdeOptions::adaptive_per_component(o.rtol, atol);
        opts.max_step = o.max_step;
        opts.max_steps = 50_000_000;
        let mut stops = self.profile.breakpoints();
        if let Some(s) = &self.shock {
            stops.extend(s.breakpoints());
        }
        stops.retain(|&t| t > 0.0 && t < o.duration);
        stops.sort_by(f64::total_cmp);
        stops.dedup();
        opts = opts.with_stop_times(stops);
        let shock = self.shock;
        let cache = Cell::new(ClosingCache::EMPTY);
        // The largest total contact and lubricant force over the accepted steps.
        let step_peaks = Cell::new((0.0f64, 0.0f64));
        let cap = |t: f64, y: &[f64; 6]| -> f64 {
            let c = cache.get();
            let (closing_time, contact, lubricant) = if c.t == t && c.y == *y {
                (c.closing_time, c.contact_force, c.lubricant_force)
            } else {
                self.evaluate(t, y)
                    .ok()
                    .map_or((None, f64::NAN, f64::NAN), |e| {
                        (
                            Some(e.closing_time),
                            e.totals.contact_force,
                            e.totals.lubricant_force,
                        )
                    })
            };
            // The cap sees every accepted state: the peaks over the steps, which resolve a
            // short impact that the output samples can miss (docs/three-dof.md).
            let (pc, pl) = step_peaks.get();
            step_peaks.set((pc.max(contact), pl.max(lubricant)));
            // Inside the pulse: resolve it (≥ 100 steps over 5 µs).
            if let Some(s) = &shock {
                if t >= s.start && t < s.start + s.duration {
                    return (s.duration / 100.0).max(o.contact_max_step.min(s.duration / 100.0));
                }
            }
            match closing_time {
                Some(closing_time) => (0.5 * closing_time).max(o.contact_max_step),
                None => o.contact_max_step,
            }
        };
        let start = self.initial_state()?;
        let result = integrate_capped(
            |t, y: &[f64; 6], dy: &mut [f64; 6]| self.rhs(t, y, dy, Some(&cache)),
            cap,
            0.0,
            start,
            o.duration,
            &opts,
            Sampling::Uniform { dt: o.output_step },
            observer,
        );
        let solution = result.map_err(integration_error)?;
        if let Some(e) = sample_error {
            return Err(e);
        }
        h.stats = solution.stats;
        let sampled = |x: &[f64]| x.iter().cloned().fold(0.0, f64::max);
        let (pc, pl) = step_peaks.get();
        h.peak_contact_force = pc.max(sampled(&h.contact_force));
        h.peak_lubricant_force = pl.max(sampled(&h.lubricant_force));
        if h.bulge_spacing
            .iter()
            .chain(&h.pole_tip)
            .any(|v| !v.is_finite())
        {
            return Err(DynamicsError::Numerical(
                "non-finite spacing in the sampled history".into(),
            ));
        }
        Ok(h)
    }

    fn sample(&self, t: f64, y: &[f64; 6], h: &mut History3Dof) -> Result<(), DynamicsError> {
        let e = self.evaluate(t, y)?;
        h.heave.push(y[0]);
        h.pitch.push(self.model.geometry.nominal_pitch + y[1]);
        h.roll.push(y[2]);
        h.heave_rate.push(y[3]);
        h.pitch_rate.push(y[4]);
        h.roll_rate.push(y[5]);
        h.actuation.push(e.actuation);
        h.pole_tip.push(e.pole_tip);
        h.bulge_spacing.push(e.bulge_spacing);
        h.contact_force.push(e.totals.contact_force);
        h.lubricant_force.push(e.totals.lubricant_force);
        h.adhesion.push(e.totals.adhesion);
        h.friction.push(e.totals.friction);
        h.real_area.push(e.totals.real_area);
        h.front_force.push(e.front);
        h.rear_force.push(e.rear);
        h.shock_force.push(e.shock);
        h.ab_lost_samples += usize::from(e.ab_lost);
        h.clipped_samples += usize::from(e.clipped);
        // Per-feature spacing and normal force (a second, cheap pass over the features).
        let g = &self.model.geometry;
        let (pose, rates) = self.pose(t, y);
        let mut points = FeaturePoints::new();
        g.evaluate_features(&pose, &rates, &mut points)?;
        for (i, f) in self.features.iter().enumerate() {
            let (s, forces) = match points.get(*f) {
                Some(p) => {
                    let (zd, vd) = self.disk(p.dmw_track(), p.world_x(), t);
                    let s = p.solid_spacing - zd;
                    let forces = if s < 2.0 * self.interface.solid_threshold() {
                        let area = g.nominal_contact_area_at_spacing(
                            *f,
                            &pose,
                            s,
                            self.interface.sigma(),
                        )?;
                        self.interface.forces(s, p.spacing_rate - vd, area)?
                    } else {
                        FeatureForces::default()
                    };
                    (s, forces)
                }
                None => (f64::NAN, FeatureForces::default()),
            };
            h.feature_spacing[i].push(s);
            h.feature_normal[i].push(forces.normal());
            h.feature_contact[i].push(forces.contact_force);
            h.feature_contact_damping[i].push(forces.contact_damping);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
