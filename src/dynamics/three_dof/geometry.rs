//! Pure geometry of the 3-DOF slider (§4.1, eqs. 4.22–4.28; docs/dynamics-3dof-geometry.md).
//!
//! Frames and signs as in [`crate::dynamics::geometry`]: world `+Z` up, `+X` toward the LE, body
//! frame at the COM; pitch `θ > 0` raises the LE, roll `φ > 0` raises the `+y` side.
//!
//! * **Bulge** (§2.1, 3-DOF row): a constant half-ellipsoid (semi-axes `a_TFC, w_TFC/2, b_TFC`)
//!   on a base displaced by `h_TFC − b_TFC`; its centre is
//!   `(−l/2 + x_TFC, 0, −l_t/2 − (h_TFC − b_TFC))`. Actuation `h_TFC < b_TFC` is an error.
//! * **Features** (§2.5): bulge (closed-form lowest point), TFC-base corners, contact pads
//!   (spherical caps), recessed TE and LE corners, each on the `+y` or `−y` side;
//!   [`FeatureSides::Lower`] keeps only the lower side (`sign(y) = −sign(φ)`; both at `φ = 0`).
//! * **Spacings** (§5.2–5.3): the nominal state has the TE (ABS point `(−l/2, 0, −l_t/2)`) at
//!   solid spacing `FH_nom`, pitch `θ0`, roll 0 and `z = 0`; every spacing is that nominal value
//!   plus increments such as `(sinθ − sinθ0)·p_x`, accurate far below 1e-12 m. Spacings are to
//!   the disk's mean plane: the caller subtracts the DMW `z_d(x, track, t)` under the point.
//! * **Nominal areas** (§2.4): truncation height `h_T = clamp(6σ − s, 0, 3σ)`; ellipsoid section
//!   for the bulge, `2π R_PAD h_T` for pads, and for flat faces the part of the face rectangle
//!   whose altitude lies within `h_T` of the rectangle's lowest corner (one Sutherland–Hodgman
//!   clip against a line, then the shoelace formula; projection factor ignored).

use nalgebra::Vector3;

use crate::dynamics::geometry::{spacing_truncation_height, Attitude, BulgeDesign, HalfEllipsoid};
use crate::dynamics::{
    require_finite, require_in, require_non_negative, require_positive, DynamicsError, Result, NM,
    UM,
};

pub use super::face::{truncated_rectangle_area, BodyRectangle};

#[cfg(test)]
mod tests;

/// Which sides of the two-sided features (base corners, pads, TE/LE corners) are evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FeatureSides {
    /// Both sides (recommended: both can carry adhesion).
    Both,
    /// Faithful to eqs. 4.23–4.26: only the lower side, `sign(y) = −sign(φ)`. At exactly `φ = 0`
    /// the two sides are equally low and both are kept.
    Lower,
}

/// Side of a two-sided feature.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// `y > 0` (raised by a positive roll).
    PlusY,
    /// `y < 0`.
    MinusY,
}

impl Side {
    /// `+1` for `PlusY`, `−1` for `MinusY`.
    pub fn sign(self) -> f64 {
        match self {
            Side::PlusY => 1.0,
            Side::MinusY => -1.0,
        }
    }
}

/// DMW track under a feature (§6): centre line → track 1, `y > 0` → track 2, `y < 0` → track 3.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DmwTrack {
    /// Track 1 (original record): bulge and centre-line AB springs.
    Centre,
    /// Track 2 (time-flipped record): features at `y > 0`.
    PlusY,
    /// Track 3 (negated, time-flipped record): features at `y < 0`.
    MinusY,
}

impl DmwTrack {
    /// Zero-based index 0, 1, 2 (track number minus one).
    pub fn index(self) -> usize {
        match self {
            DmwTrack::Centre => 0,
            DmwTrack::PlusY => 1,
            DmwTrack::MinusY => 2,
        }
    }
}

/// A possible point of contact of the 3-DOF slider (§2.5).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feature {
    /// The TFC bulge (closed-form lowest point, §2.2).
    Bulge,
    /// TE-side corner of the displaced TFC base, `(−l/2 + l_S, ±w_BASE/2, z_base)`.
    BaseCorner(Side),
    /// Contact pad (spherical cap of radius `R_PAD` tangent to the ABS at `(x_PAD, ±y_PAD)`).
    Pad(Side),
    /// Recessed trailing-edge corner `(−l/2 + l_S, ±(l_w/2 − l_S), −l_t/2 + h_S)`.
    TrailingEdgeCorner(Side),
    /// Recessed leading-edge corner `(l/2 − l_S, ±(l_w/2 − l_S), −l_t/2 + h_S)`.
    LeadingEdgeCorner(Side),
}

/// Maximum number of features evaluated (bulge + 4 two-sided features × 2 sides).
pub const MAX_FEATURES: usize = 9;

/// Every feature, in evaluation order.
pub const ALL_FEATURES: [Feature; MAX_FEATURES] = [
    Feature::Bulge,
    Feature::BaseCorner(Side::PlusY),
    Feature::BaseCorner(Side::MinusY),
    Feature::Pad(Side::PlusY),
    Feature::Pad(Side::MinusY),
    Feature::TrailingEdgeCorner(Side::PlusY),
    Feature::TrailingEdgeCorner(Side::MinusY),
    Feature::LeadingEdgeCorner(Side::PlusY),
    Feature::LeadingEdgeCorner(Side::MinusY),
];

impl Feature {
    /// The side of a two-sided feature; `None` for the bulge.
    pub fn side(self) -> Option<Side> {
        match self {
            Feature::Bulge => None,
            Feature::BaseCorner(s)
            | Feature::Pad(s)
            | Feature::TrailingEdgeCorner(s)
            | Feature::LeadingEdgeCorner(s) => Some(s),
        }
    }

    /// The DMW track under the feature (§6).
    pub fn dmw_track(self) -> DmwTrack {
        match self.side() {
            None => DmwTrack::Centre,
            Some(Side::PlusY) => DmwTrack::PlusY,
            Some(Side::MinusY) => DmwTrack::MinusY,
        }
    }

    /// Whether the feature is evaluated at roll `φ` under `sides`.
    pub fn is_active(self, sides: FeatureSides, roll: f64) -> bool {
        match (sides, self.side()) {
            (_, None) | (FeatureSides::Both, _) => true,
            (FeatureSides::Lower, Some(side)) => roll == 0.0 || side.sign() == -roll.signum(),
        }
    }
}

/// Heave (COM displacement from the nominal state, m), pitch `θ`, roll `φ` (rad) and TFC
/// actuation `h_TFC` (total protrusion of the bulge bottom below the ABS, m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SliderPose {
    pub heave: f64,
    pub pitch: f64,
    pub roll: f64,
    pub actuation: f64,
}

impl SliderPose {
    pub fn attitude(&self) -> Attitude {
        Attitude::new(self.pitch, self.roll)
    }
}

/// Time derivatives of a [`SliderPose`] (m/s, rad/s, rad/s, m/s).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PoseRates {
    pub heave: f64,
    pub pitch: f64,
    pub roll: f64,
    pub actuation: f64,
}

/// Kinematics of one feature's lowest point in one state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeaturePoint {
    pub feature: Feature,
    /// Lowest point, body coordinates relative to the COM (m).
    pub body_point: Vector3<f64>,
    /// World offset `r = R p` from the COM (m): the lever arm of the feature's forces (§2.3).
    pub lever_arm: Vector3<f64>,
    /// Solid spacing above the disk's mean plane, no DMW (m).
    pub solid_spacing: f64,
    /// `ṡ` from the heave, pitch, roll and actuation rates, no DMW (m/s).
    pub spacing_rate: f64,
}

impl FeaturePoint {
    /// World `X` of the point relative to the COM (m): where to evaluate the DMW.
    pub fn world_x(&self) -> f64 {
        self.lever_arm.x
    }

    pub fn dmw_track(&self) -> DmwTrack {
        self.feature.dmw_track()
    }
}

/// Caller-owned storage for the per-evaluation fast path (no heap allocation).
#[derive(Debug, Clone, Copy)]
pub struct FeaturePoints {
    points: [FeaturePoint; MAX_FEATURES],
    len: usize,
}

impl Default for FeaturePoints {
    fn default() -> Self {
        Self::new()
    }
}

impl FeaturePoints {
    pub fn new() -> Self {
        let empty = FeaturePoint {
            feature: Feature::Bulge,
            body_point: Vector3::zeros(),
            lever_arm: Vector3::zeros(),
            solid_spacing: f64::INFINITY,
            spacing_rate: 0.0,
        };
        FeaturePoints {
            points: [empty; MAX_FEATURES],
            len: 0,
        }
    }

    /// The active features of the last evaluation, in [`ALL_FEATURES`] order.
    pub fn as_slice(&self) -> &[FeaturePoint] {
        &self.points[..self.len]
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The entry of `feature`, if it was active.
    pub fn get(&self, feature: Feature) -> Option<&FeaturePoint> {
        self.as_slice().iter().find(|p| p.feature == feature)
    }
}

/// Trigonometry of one pose, shared by every feature of an evaluation.
#[derive(Debug, Clone, Copy)]
struct PoseTrig {
    sin_pitch: f64,
    cos_pitch: f64,
    sin_roll: f64,
    cos_roll: f64,
    /// `sinθ − sinθ0`, without cancellation.
    sin_pitch_increment: f64,
    /// `cosθ cosφ − cosθ0`, without cancellation.
    vertical_z_increment: f64,
    /// `1 − cosθ cosφ`, without cancellation.
    one_minus_vertical_z: f64,
    sin_pitch0: f64,
    cos_pitch0: f64,
}

impl PoseTrig {
    fn new(pitch: f64, roll: f64, nominal_pitch: f64) -> Self {
        let (st, ct) = pitch.sin_cos();
        let (sp, cp) = roll.sin_cos();
        let (s0, c0) = nominal_pitch.sin_cos();
        let half_sum = 0.5 * (pitch + nominal_pitch);
        let half_diff_sin = (0.5 * (pitch - nominal_pitch)).sin();
        let d_sin = 2.0 * half_sum.cos() * half_diff_sin;
        let d_cos = -2.0 * half_sum.sin() * half_diff_sin;
        let half_roll_sin = (0.5 * roll).sin();
        let one_minus_cp = 2.0 * half_roll_sin * half_roll_sin;
        let half_pitch_sin = (0.5 * pitch).sin();
        let one_minus_ct = 2.0 * half_pitch_sin * half_pitch_sin;
        PoseTrig {
            sin_pitch: st,
            cos_pitch: ct,
            sin_roll: sp,
            cos_roll: cp,
            sin_pitch_increment: d_sin,
            vertical_z_increment: d_cos * cp - c0 * one_minus_cp,
            one_minus_vertical_z: one_minus_ct + ct * one_minus_cp,
            sin_pitch0: s0,
            cos_pitch0: c0,
        }
    }

    /// `n = Rᵀ e_z = (sinθ, cosθ sinφ, cosθ cosφ)`.
    fn vertical(&self) -> Vector3<f64> {
        Vector3::new(
            self.sin_pitch,
            self.cos_pitch * self.sin_roll,
            self.cos_pitch * self.cos_roll,
        )
    }

    /// `r = R p` with `R = R_y(−θ) R_x(φ)` (§1.1).
    fn world_offset(&self, p: &Vector3<f64>) -> Vector3<f64> {
        let (st, ct, sp, cp) = (self.sin_pitch, self.cos_pitch, self.sin_roll, self.cos_roll);
        Vector3::new(
            ct * p.x - st * sp * p.y - st * cp * p.z,
            cp * p.y - sp * p.z,
            st * p.x + ct * sp * p.y + ct * cp * p.z,
        )
    }

    /// `Ż_p − ż` of a fixed body point (§5.3).
    fn altitude_rate(&self, p: &Vector3<f64>, rates: &PoseRates) -> f64 {
        let (st, ct, sp, cp) = (self.sin_pitch, self.cos_pitch, self.sin_roll, self.cos_roll);
        rates.pitch * (ct * p.x - st * sp * p.y - st * cp * p.z)
            + rates.roll * (ct * cp * p.y - ct * sp * p.z)
    }
}

/// Geometry of the 3-DOF slider (Tables 4.1, 4.3; eqs. 4.22–4.28).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slider3DofGeometry {
    /// `l` along x (m); TE at `x = −l/2`.
    pub length: f64,
    /// `l_w` along y (m).
    pub width: f64,
    /// `l_t` along z (m); the ABS ("zero surface") is `z = −l_t/2`.
    pub thickness: f64,
    /// `a_TFC`, `w_TFC`, `x_TFC` of the bulge.
    pub bulge: BulgeDesign,
    /// `b_TFC`: constant bulge height (m).
    pub bulge_height: f64,
    /// `w_BASE`: width of the TFC base along y (m).
    pub base_width: f64,
    /// `L_BASE`: extent of the TFC base along x from `−l/2 + l_S` (m) [assumption].
    pub base_length: f64,
    /// `x_R`: read element offset from the bulge centre toward the LE (m).
    pub read_offset: f64,
    /// `x_W`: write element offset from the bulge centre toward the TE (m).
    pub write_offset: f64,
    /// `R_PAD`: radius of the spherical contact pads (m).
    pub pad_radius: f64,
    /// `x_PAD`: pad position along x from the COM (m).
    pub pad_x: f64,
    /// `y_PAD`: pads at `±y_PAD` (m).
    pub pad_y: f64,
    /// `l_S`: width of the un-recessed rim around the recessed surface (m).
    pub recess_inset: f64,
    /// `h_S`: depth of the recessed surface above the ABS (m).
    pub recess_depth: f64,
    /// `FH_nom`: solid spacing of the TE in the nominal state (m; ch. 4 measures from the solid
    /// mean plane).
    pub nominal_spacing: f64,
    /// `θ0`: pitch of the nominal state (rad).
    pub nominal_pitch: f64,
    /// Which sides of the two-sided features are evaluated.
    pub sides: FeatureSides,
}

impl Slider3DofGeometry {
    /// Tables 4.1 and 4.3 (docs/dynamics-3dof-geometry.md), both sides evaluated.
    pub fn dissertation() -> Self {
        Slider3DofGeometry {
            length: 1.23e-3,
            width: 0.70e-3,
            thickness: 0.30e-3,
            bulge: BulgeDesign {
                semi_width_x: 5.0 * UM,
                full_width_y: 50.0 * UM,
                offset_from_te: 15.0 * UM,
            },
            bulge_height: 5.0 * NM,
            base_width: 100.0 * UM,
            base_length: 35.0 * UM,
            read_offset: 3.0 * UM,
            write_offset: 3.0 * UM,
            pad_radius: 1.0e-3,
            pad_x: 0.6e-3,
            pad_y: 0.3e-3,
            recess_inset: 10.0 * UM,
            recess_depth: 0.16 * UM,
            nominal_spacing: 11.0 * NM,
            nominal_pitch: 100e-6,
            sides: FeatureSides::Both,
        }
    }

    pub fn validate(&self) -> Result<()> {
        require_positive("slider length l (m)", self.length)?;
        require_positive("slider width l_w (m)", self.width)?;
        require_positive("slider thickness l_t (m)", self.thickness)?;
        self.bulge.validate()?;
        require_positive("b_TFC (bulge height, m)", self.bulge_height)?;
        if self.bulge.offset_from_te + self.bulge.semi_width_x > self.length {
            return Err(DynamicsError::parameter(
                "x_TFC (bulge centre from the TE, m)",
                self.bulge.offset_from_te,
                format!("x_TFC + a_TFC must be <= l = {:e} m", self.length),
            ));
        }
        require_in(
            "w_BASE (TFC base width, m)",
            self.base_width,
            self.bulge.full_width_y,
            self.width,
            "m (between w_TFC and l_w)",
        )?;
        require_positive("L_BASE (TFC base length, m)", self.base_length)?;
        let a = self.bulge.semi_width_x;
        for (name, offset) in [
            ("x_R (read offset, m)", self.read_offset),
            ("x_W (write offset, m)", self.write_offset),
        ] {
            require_finite(name, offset)?;
            if offset.abs() >= a {
                return Err(DynamicsError::parameter(
                    name,
                    offset,
                    format!("|offset| must be < a_TFC = {a:e} m (element on the bulge)"),
                ));
            }
        }
        require_positive("R_PAD (pad radius, m)", self.pad_radius)?;
        require_in(
            "x_PAD (pad x from the COM, m)",
            self.pad_x,
            -0.5 * self.length,
            0.5 * self.length,
            "m",
        )?;
        require_in(
            "y_PAD (pad |y| from the COM, m)",
            self.pad_y,
            0.0,
            0.5 * self.width,
            "m",
        )?;
        require_in(
            "l_S (recess inset, m)",
            self.recess_inset,
            0.0,
            0.25 * self.length.min(self.width),
            "m",
        )?;
        if self.recess_inset + self.base_length > self.length {
            return Err(DynamicsError::parameter(
                "L_BASE (TFC base length, m)",
                self.base_length,
                format!("l_S + L_BASE must be <= l = {:e} m", self.length),
            ));
        }
        require_non_negative("h_S (recess depth, m)", self.recess_depth)?;
        require_in(
            "FH_nom (nominal TE spacing, m)",
            self.nominal_spacing,
            0.0,
            1e-6,
            "m",
        )?;
        require_in(
            "nominal pitch θ0 (rad)",
            self.nominal_pitch,
            -1e-2,
            1e-2,
            "rad",
        )?;
        Ok(())
    }

    /// Checks a state: finite heave, `|θ|, |φ| ≤ 0.1 rad` (small-angle rigid body) and
    /// `b_TFC ≤ h_TFC ≤ 1 µm` (the bulge sits on a base displaced by `h_TFC − b_TFC ≥ 0`).
    pub fn check_pose(&self, pose: &SliderPose) -> Result<()> {
        require_finite("heave z (m)", pose.heave)?;
        require_in("pitch θ (rad)", pose.pitch, -0.1, 0.1, "rad")?;
        require_in("roll φ (rad)", pose.roll, -0.1, 0.1, "rad")?;
        if !(pose.actuation >= self.bulge_height && pose.actuation <= 1e-6) {
            return Err(DynamicsError::parameter(
                "TFC actuation h_TFC (m)",
                pose.actuation,
                format!(
                    "must lie in [b_TFC = {:e}, 1e-6] m (3-DOF: constant bulge on a base displaced \
                     by h_TFC − b_TFC)",
                    self.bulge_height
                ),
            ));
        }
        Ok(())
    }

    /// The anchor of the nominal state: TE point at ABS level, `(−l/2, 0, −l_t/2)`.
    pub fn trailing_edge(&self) -> Vector3<f64> {
        Vector3::new(-0.5 * self.length, 0.0, -0.5 * self.thickness)
    }

    /// Body z of the displaced TFC base, `−l_t/2 − (h_TFC − b_TFC)` (m).
    pub fn base_level(&self, actuation: f64) -> f64 {
        -0.5 * self.thickness - (actuation - self.bulge_height)
    }

    /// Ellipsoid centre `(−l/2 + x_TFC, 0, −l_t/2 − (h_TFC − b_TFC))` (§2.1, 3-DOF row).
    pub fn bulge_centre(&self, actuation: f64) -> Vector3<f64> {
        Vector3::new(
            -0.5 * self.length + self.bulge.offset_from_te,
            0.0,
            self.base_level(actuation),
        )
    }

    /// The bulge at actuation `h_TFC ≥ b_TFC`: semi-axes `(a_TFC, w_TFC/2, b_TFC)`.
    pub fn bulge_at(&self, actuation: f64) -> Result<HalfEllipsoid> {
        require_finite("TFC actuation h_TFC (m)", actuation)?;
        if actuation < self.bulge_height {
            return Err(DynamicsError::parameter(
                "TFC actuation h_TFC (m)",
                actuation,
                format!("must be >= b_TFC = {:e} m", self.bulge_height),
            ));
        }
        HalfEllipsoid::new(self.bulge_centre(actuation), self.bulge_semi_axes())
    }

    fn bulge_semi_axes(&self) -> Vector3<f64> {
        Vector3::new(
            self.bulge.semi_width_x,
            0.5 * self.bulge.full_width_y,
            self.bulge_height,
        )
    }

    /// The features evaluated at roll `φ` (in [`ALL_FEATURES`] order).
    pub fn active_features(&self, roll: f64) -> impl Iterator<Item = Feature> + '_ {
        let sides = self.sides;
        ALL_FEATURES
            .into_iter()
            .filter(move |f| f.is_active(sides, roll))
    }

    /// Solid spacing above the disk's mean plane (no DMW) of a fixed body point at heave `z`,
    /// pitch `θ` and roll `φ` (§5.2–5.3): `FH_nom + z + n(θ,φ)·p − n(θ0,0)·q_TE`, evaluated as
    /// increments so that it is accurate far below 1e-12 m.
    pub fn spacing_of(&self, body_point: &Vector3<f64>, heave: f64, pitch: f64, roll: f64) -> f64 {
        self.spacing_with(
            &PoseTrig::new(pitch, roll, self.nominal_pitch),
            body_point,
            heave,
        )
    }

    fn spacing_with(&self, trig: &PoseTrig, p: &Vector3<f64>, heave: f64) -> f64 {
        let q = self.trailing_edge();
        self.nominal_spacing
            + heave
            + trig.sin_pitch_increment * p.x
            + trig.sin_pitch0 * (p.x - q.x)
            + trig.cos_pitch * trig.sin_roll * p.y
            + trig.vertical_z_increment * p.z
            + trig.cos_pitch0 * (p.z - q.z)
    }

    /// Rate of the spacing of a fixed body point (§5.3; no DMW, no actuation):
    /// `ż + θ̇ (cosθ p_x − sinθ sinφ p_y − sinθ cosφ p_z) + φ̇ (cosθ cosφ p_y − cosθ sinφ p_z)`.
    pub fn spacing_rate_of(
        &self,
        body_point: &Vector3<f64>,
        pitch: f64,
        roll: f64,
        rates: &PoseRates,
    ) -> f64 {
        let trig = PoseTrig::new(pitch, roll, self.nominal_pitch);
        rates.heave + trig.altitude_rate(body_point, rates)
    }

    /// Kinematics of one feature (lowest point, lever arm, spacing, spacing rate). Does not check
    /// whether the feature is active under [`Self::sides`].
    pub fn feature_point(
        &self,
        feature: Feature,
        pose: &SliderPose,
        rates: &PoseRates,
    ) -> Result<FeaturePoint> {
        self.check_pose(pose)?;
        let trig = PoseTrig::new(pose.pitch, pose.roll, self.nominal_pitch);
        Ok(self.feature_point_with(&trig, feature, pose, rates))
    }

    /// The per-evaluation fast path: fills `out` with every active feature (no heap
    /// allocation; one set of trigonometric evaluations shared by all features).
    pub fn evaluate_features(
        &self,
        pose: &SliderPose,
        rates: &PoseRates,
        out: &mut FeaturePoints,
    ) -> Result<()> {
        self.check_pose(pose)?;
        let trig = PoseTrig::new(pose.pitch, pose.roll, self.nominal_pitch);
        out.len = 0;
        for feature in ALL_FEATURES {
            if feature.is_active(self.sides, pose.roll) {
                out.points[out.len] = self.feature_point_with(&trig, feature, pose, rates);
                out.len += 1;
            }
        }
        Ok(())
    }

    fn feature_point_with(
        &self,
        trig: &PoseTrig,
        feature: Feature,
        pose: &SliderPose,
        rates: &PoseRates,
    ) -> FeaturePoint {
        let n = trig.vertical();
        // ∂s/∂h_TFC of anything carried by the base: the base moves by −h along body z.
        let actuation_rate_term = -n.z * rates.actuation;
        let (body_point, solid_spacing, spacing_rate) = match feature {
            Feature::Bulge => {
                let centre = self.bulge_centre(pose.actuation);
                let semi_axes = self.bulge_semi_axes();
                // Closed-form POC of §2.2 (fields set directly: the axes are validated).
                let low = HalfEllipsoid { centre, semi_axes }.lowest_point(&pose.attitude());
                let spacing = self.spacing_with(trig, &centre, pose.heave) - low.support_distance;
                // Envelope theorem: the POC moves like a fixed body point.
                let rate = rates.heave + trig.altitude_rate(&low.body, rates) + actuation_rate_term;
                (low.body, spacing, rate)
            }
            Feature::Pad(side) => {
                // Tangent point on the ABS; the sphere's lowest world point is R_PAD·(1 − n_z)
                // below it, at body point c − R_PAD n.
                let tangent =
                    Vector3::new(self.pad_x, side.sign() * self.pad_y, -0.5 * self.thickness);
                let centre = tangent + Vector3::new(0.0, 0.0, self.pad_radius);
                let low = centre - n * self.pad_radius;
                let spacing = self.spacing_with(trig, &tangent, pose.heave)
                    - self.pad_radius * trig.one_minus_vertical_z;
                let rate = rates.heave + trig.altitude_rate(&low, rates);
                (low, spacing, rate)
            }
            Feature::BaseCorner(_)
            | Feature::TrailingEdgeCorner(_)
            | Feature::LeadingEdgeCorner(_) => {
                let p = self.flat_feature_point(feature, pose.actuation);
                let spacing = self.spacing_with(trig, &p, pose.heave);
                let mut rate = rates.heave + trig.altitude_rate(&p, rates);
                if matches!(feature, Feature::BaseCorner(_)) {
                    rate += actuation_rate_term;
                }
                (p, spacing, rate)
            }
        };
        FeaturePoint {
            feature,
            body_point,
            lever_arm: trig.world_offset(&body_point),
            solid_spacing,
            spacing_rate,
        }
    }

    /// Body point of a flat feature (eqs. 4.23–4.26); the bulge and pads map to their tangent
    /// point on the base / ABS.
    fn flat_feature_point(&self, feature: Feature, actuation: f64) -> Vector3<f64> {
        let (half_l, half_w, half_t) = (0.5 * self.length, 0.5 * self.width, 0.5 * self.thickness);
        let (ls, hs) = (self.recess_inset, self.recess_depth);
        match feature {
            Feature::Bulge => self.bulge_centre(actuation),
            Feature::BaseCorner(s) => Vector3::new(
                -half_l + ls,
                s.sign() * 0.5 * self.base_width,
                self.base_level(actuation),
            ),
            Feature::Pad(s) => Vector3::new(self.pad_x, s.sign() * self.pad_y, -half_t),
            Feature::TrailingEdgeCorner(s) => {
                Vector3::new(-half_l + ls, s.sign() * (half_w - ls), -half_t + hs)
            }
            Feature::LeadingEdgeCorner(s) => {
                Vector3::new(half_l - ls, s.sign() * (half_w - ls), -half_t + hs)
            }
        }
    }

    /// The face rectangle whose truncation gives a flat feature's nominal area; `None` for the
    /// bulge and pads. Each two-sided feature owns the half of its §2.5 face on its own side of
    /// `y = 0`, and the TE / LE corners own the TE / LE half (`x ≤ 0` / `x ≥ 0`) of the recessed
    /// plane, so that the faces of all features partition the §2.5 faces (no area counted
    /// twice when both sides, or both ends, are within reach of the disk).
    pub fn feature_face(&self, feature: Feature, actuation: f64) -> Option<BodyRectangle> {
        let (half_l, half_w, half_t) = (0.5 * self.length, 0.5 * self.width, 0.5 * self.thickness);
        let ls = self.recess_inset;
        let side_half = |s: Side, half_extent: f64| match s {
            Side::PlusY => (0.0, half_extent),
            Side::MinusY => (-half_extent, 0.0),
        };
        match feature {
            Feature::Bulge | Feature::Pad(_) => None,
            Feature::BaseCorner(s) => {
                let (y_min, y_max) = side_half(s, 0.5 * self.base_width);
                Some(BodyRectangle {
                    x_min: -half_l + ls,
                    x_max: -half_l + ls + self.base_length,
                    y_min,
                    y_max,
                    z: self.base_level(actuation),
                })
            }
            Feature::TrailingEdgeCorner(s) | Feature::LeadingEdgeCorner(s) => {
                let (y_min, y_max) = side_half(s, half_w - ls);
                let (x_min, x_max) = if matches!(feature, Feature::TrailingEdgeCorner(_)) {
                    (-half_l + ls, 0.0)
                } else {
                    (0.0, half_l - ls)
                };
                Some(BodyRectangle {
                    x_min,
                    x_max,
                    y_min,
                    y_max,
                    z: -half_t + self.recess_depth,
                })
            }
        }
    }

    /// Nominal contact area `A_n` of a feature at truncation height `h_T` (§2.4): ellipsoid
    /// section (bulge), `2π R_PAD h_T` (pads), truncated face rectangle (flat features).
    /// Zero for `h_T = 0`; negative or non-finite `h_T` is an error.
    pub fn nominal_contact_area(
        &self,
        feature: Feature,
        pose: &SliderPose,
        truncation_height: f64,
    ) -> Result<f64> {
        require_non_negative("truncation height h_T (m)", truncation_height)?;
        self.check_pose(pose)?;
        if truncation_height == 0.0 {
            return Ok(0.0);
        }
        let attitude = pose.attitude();
        Ok(match feature {
            Feature::Bulge => {
                HalfEllipsoid {
                    centre: self.bulge_centre(pose.actuation),
                    semi_axes: self.bulge_semi_axes(),
                }
                .section(&attitude, truncation_height)?
                .area
            }
            Feature::Pad(_) => 2.0 * std::f64::consts::PI * self.pad_radius * truncation_height,
            _ => match self.feature_face(feature, pose.actuation) {
                Some(face) => truncated_rectangle_area(&face, &attitude, truncation_height),
                None => 0.0,
            },
        })
    }

    /// `A_n` with the 3-DOF truncation rule `h_T = clamp(6σ − s, 0, 3σ)` from the feature's
    /// contact spacing `s` (after the caller subtracted the DMW) and the combined roughness `σ`.
    pub fn nominal_contact_area_at_spacing(
        &self,
        feature: Feature,
        pose: &SliderPose,
        spacing: f64,
        sigma: f64,
    ) -> Result<f64> {
        require_finite("feature spacing s (m)", spacing)?;
        require_positive("roughness σ (m)", sigma)?;
        self.nominal_contact_area(feature, pose, spacing_truncation_height(spacing, sigma))
    }

    /// Angle `β = arccos(x/a)` of an element at offset `x` from the bulge centre on the
    /// cross-section `(a cosβ, 0, −b sinβ)` (§2.6); `|x| ≥ a` is an error.
    pub fn element_angle(&self, offset: f64) -> Result<f64> {
        let a = self.bulge.semi_width_x;
        require_finite("element offset (m)", offset)?;
        if offset.abs() >= a {
            return Err(DynamicsError::parameter(
                "element offset from the bulge centre (m)",
                offset,
                format!("|offset| must be < a_TFC = {a:e} m"),
            ));
        }
        Ok((offset / a).acos())
    }

    /// Body point of an element at offset `x` (toward the LE) from the bulge centre:
    /// `centre + (x, 0, −b sqrt(1 − (x/a)²))` (§2.6).
    pub fn element_point(&self, offset: f64, actuation: f64) -> Result<Vector3<f64>> {
        let beta = self.element_angle(offset)?;
        let bulge = self.bulge_at(actuation)?;
        Ok(bulge.centre + Vector3::new(offset, 0.0, -self.bulge_height * beta.sin()))
    }

    /// Read element, `x_R` toward the LE of the bulge centre.
    pub fn read_element(&self, actuation: f64) -> Result<Vector3<f64>> {
        self.element_point(self.read_offset, actuation)
    }

    /// Write element, `x_W` toward the TE of the bulge centre.
    pub fn write_element(&self, actuation: f64) -> Result<Vector3<f64>> {
        self.element_point(-self.write_offset, actuation)
    }

    /// Pole-tip flying height `PT` = solid spacing of the read element (no DMW) (§2.6).
    pub fn pole_tip_spacing(
        &self,
        heave: f64,
        pitch: f64,
        roll: f64,
        actuation: f64,
    ) -> Result<f64> {
        self.element_spacing(self.read_offset, heave, pitch, roll, actuation)
    }

    /// Solid spacing of the write element (no DMW).
    pub fn write_element_spacing(
        &self,
        heave: f64,
        pitch: f64,
        roll: f64,
        actuation: f64,
    ) -> Result<f64> {
        self.element_spacing(-self.write_offset, heave, pitch, roll, actuation)
    }

    fn element_spacing(
        &self,
        offset: f64,
        heave: f64,
        pitch: f64,
        roll: f64,
        actuation: f64,
    ) -> Result<f64> {
        self.check_pose(&SliderPose {
            heave,
            pitch,
            roll,
            actuation,
        })?;
        Ok(self.spacing_of(&self.element_point(offset, actuation)?, heave, pitch, roll))
    }
}
