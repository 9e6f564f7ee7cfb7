//! TFC-bulge and slider geometry (§2.1.1, eqs. 2.1–2.7; docs/dynamics-geometry.md).
//!
//! Frames: world `+Z` up (away from the disk), `+X` toward the leading edge (LE); body frame at
//! the slider centre of mass (COM), equal to the world axes at zero attitude. Pitch `θ > 0`
//! raises the LE, roll `φ > 0` raises the `+y` side, `R(θ, φ) = R_y(−θ)·R_x(φ)`.
//!
//! The bulge is the lower half of an ellipsoid with semi-axes `(a_TFC, w_TFC/2, c_z)`; its
//! lowest point, lever arm and horizontal sections are closed forms (the dissertation minimised
//! and sectioned numerically; the closed forms are exact and smooth in the attitude).

use nalgebra::{Matrix3, Vector2, Vector3};

use super::{
    require_finite, require_in, require_non_negative, require_positive, DynamicsError, Result,
};

/// Slider attitude: pitch `θ` and roll `φ` (rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Attitude {
    /// `θ > 0` raises the leading edge.
    pub pitch: f64,
    /// `φ > 0` raises the `+y` side.
    pub roll: f64,
}

impl Attitude {
    pub fn new(pitch: f64, roll: f64) -> Self {
        Attitude { pitch, roll }
    }

    /// The 2-DOF models have no roll.
    pub fn pitch_only(pitch: f64) -> Self {
        Attitude { pitch, roll: 0.0 }
    }

    /// Body → world rotation `R = R_y(−θ)·R_x(φ)` (§1.1; eq. 4.4 with its signs restored).
    pub fn rotation(&self) -> Matrix3<f64> {
        let (st, ct) = self.pitch.sin_cos();
        let (sp, cp) = self.roll.sin_cos();
        Matrix3::new(ct, -st * sp, -st * cp, 0.0, cp, -sp, st, ct * sp, ct * cp)
    }

    /// The world vertical in body axes, `n = Rᵀ e_z = (sinθ, cosθ sinφ, cosθ cosφ)`.
    pub fn body_vertical(&self) -> Vector3<f64> {
        let (st, ct) = self.pitch.sin_cos();
        let (sp, cp) = self.roll.sin_cos();
        Vector3::new(st, ct * sp, ct * cp)
    }

    /// World offset `r = R p` of a body point from the COM (the lever arm of §2.3).
    pub fn world_offset(&self, body_point: &Vector3<f64>) -> Vector3<f64> {
        self.rotation() * body_point
    }

    /// Altitude of a body point above the COM, `(R p)_z = n · p`.
    pub fn altitude_offset(&self, body_point: &Vector3<f64>) -> f64 {
        self.body_vertical().dot(body_point)
    }
}

/// Heave force and moments about the COM of an interfacial force (§1.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeneralisedForce {
    /// Vertical force (N), up positive.
    pub heave: f64,
    /// Pitch moment (N·m), positive raises the LE.
    pub pitch_moment: f64,
    /// Roll moment (N·m), positive raises the `+y` side.
    pub roll_moment: f64,
}

/// Generalised forces of an interfacial force applied at world offset `r` (= `R p`) from the COM:
/// upward normal force `normal` (`N = F_c − F_s`, negative when adhesion wins) and friction of
/// magnitude `friction ≥ 0` along `−X` (the disk moves LE → TE).
///
/// `M_θ = r_x N + r_z Q`; `M_φ = cosθ·r_y·N + sinθ·r_y·Q` (the exact §1.1 form with
/// `F = (−Q, 0, N)`; ≈ `r_y N`). With `r_z < 0` friction gives a nose-down moment.
pub fn generalised_force(
    lever_arm: &Vector3<f64>,
    attitude: &Attitude,
    normal: f64,
    friction: f64,
) -> GeneralisedForce {
    let (st, ct) = attitude.pitch.sin_cos();
    GeneralisedForce {
        heave: normal,
        pitch_moment: lever_arm.x * normal + lever_arm.z * friction,
        roll_moment: ct * lever_arm.y * normal + st * lever_arm.y * friction,
    }
}

/// Design of a TFC bulge (Tables 2.1, 4.3): what the DOE and the optimisation vary.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct BulgeDesign {
    /// `a_TFC`: semi-width along x (m).
    pub semi_width_x: f64,
    /// `w_TFC`: full width along y (m); the ellipsoid's y semi-axis is `w_TFC / 2` (eq. 2.2).
    pub full_width_y: f64,
    /// `x_TFC`: distance of the ellipsoid centre from the trailing edge (m).
    pub offset_from_te: f64,
}

impl BulgeDesign {
    /// Positive dimensions; the bulge must not overhang the trailing edge (`a_TFC ≤ x_TFC`).
    pub fn validate(&self) -> Result<()> {
        require_positive("a_TFC (bulge semi-width along x, m)", self.semi_width_x)?;
        require_positive("w_TFC (bulge full width along y, m)", self.full_width_y)?;
        require_positive("x_TFC (bulge centre from the TE, m)", self.offset_from_te)?;
        if self.semi_width_x > self.offset_from_te {
            return Err(DynamicsError::parameter(
                "a_TFC (bulge semi-width along x, m)",
                self.semi_width_x,
                format!(
                    "must be <= x_TFC = {:e} m (the bulge may not overhang the trailing edge)",
                    self.offset_from_te
                ),
            ));
        }
        Ok(())
    }
}

/// Lower half of an ellipsoid in the body frame: the protruding TFC bulge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfEllipsoid {
    /// Centre, body frame relative to the COM (m).
    pub centre: Vector3<f64>,
    /// Semi-axes `(a_TFC, w_TFC/2, c_z)` (m); `c_z` is the bulge height (2-DOF: `h_TFC`).
    pub semi_axes: Vector3<f64>,
}

/// Lowest point of a feature at a given attitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LowestPoint {
    /// Body coordinates relative to the COM (m).
    pub body: Vector3<f64>,
    /// Support distance `h_s = ‖D n‖`: how far the lowest point lies below the ellipsoid centre,
    /// measured along the world vertical (m).
    pub support_distance: f64,
}

/// Horizontal (world) section of a bulge at a truncation height above its lowest point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Section {
    /// Truncation height `h_T` used (m).
    pub truncation_height: f64,
    /// Semi-axis of the section ellipse that lies (nearly) along x, `d1` (m).
    pub semi_axis_x: f64,
    /// Semi-axis that lies (nearly) along y, `d2` (m).
    pub semi_axis_y: f64,
    /// Nominal area `A_n = π d1 d2` (m²).
    pub area: f64,
}

impl Section {
    /// Radius of the circle through the x-chord of the section and the lowest point,
    /// `d1² / (2 h_T)`: the dissertation's "protrusion curvature" (§2.7: 1506/827/567 µm).
    pub fn chord_radius_x(&self) -> f64 {
        chord_radius(self.semi_axis_x, self.truncation_height)
    }

    /// Same along y, `d2² / (2 h_T)`.
    pub fn chord_radius_y(&self) -> f64 {
        chord_radius(self.semi_axis_y, self.truncation_height)
    }

    /// Composite radius `2 / (1/R_x + 1/R_y)` of the two chord radii (§2.7: 1.37 mm at 12 nm).
    pub fn composite_radius(&self) -> f64 {
        let (rx, ry) = (self.chord_radius_x(), self.chord_radius_y());
        if rx <= 0.0 || ry <= 0.0 {
            return 0.0;
        }
        2.0 / (1.0 / rx + 1.0 / ry)
    }
}

fn chord_radius(semi_chord: f64, truncation_height: f64) -> f64 {
    if truncation_height > 0.0 {
        semi_chord * semi_chord / (2.0 * truncation_height)
    } else {
        f64::INFINITY
    }
}

impl HalfEllipsoid {
    /// Semi-axes along x and y must be positive; the height may be zero (no actuation).
    pub fn new(centre: Vector3<f64>, semi_axes: Vector3<f64>) -> Result<Self> {
        for (i, name) in ["centre x (m)", "centre y (m)", "centre z (m)"]
            .iter()
            .enumerate()
        {
            require_finite(name, centre[i])?;
        }
        require_positive("ellipsoid semi-axis along x (m)", semi_axes.x)?;
        require_positive("ellipsoid semi-axis along y (m)", semi_axes.y)?;
        require_non_negative("ellipsoid height along z (m)", semi_axes.z)?;
        Ok(HalfEllipsoid { centre, semi_axes })
    }

    /// Surface point of the parametric form of eqs. 2.2/4.18,
    /// `centre + (a cosα sinβ, (w/2) sinα sinβ, c_z cosβ)`, lower half for `β ∈ [π/2, 3π/2]`.
    pub fn surface_point(&self, alpha: f64, beta: f64) -> Vector3<f64> {
        let (sa, ca) = alpha.sin_cos();
        let (sb, cb) = beta.sin_cos();
        self.centre
            + Vector3::new(
                self.semi_axes.x * ca * sb,
                self.semi_axes.y * sa * sb,
                self.semi_axes.z * cb,
            )
    }

    /// `h_s = ‖D n‖`, `D = diag(a, w/2, c_z)`, `n` = world vertical in body axes (§2.2).
    pub fn support_distance(&self, attitude: &Attitude) -> f64 {
        self.semi_axes
            .component_mul(&attitude.body_vertical())
            .norm()
    }

    /// Lowest point (POC) in closed form: `p = centre − D² n / h_s` (§2.2). Exact for the lower
    /// half as long as `n_z = cosθ cosφ > 0`. When `h_s = 0` (a flat bulge parallel to the disk)
    /// every point is lowest; the centre is returned.
    pub fn lowest_point(&self, attitude: &Attitude) -> LowestPoint {
        let n = attitude.body_vertical();
        let h_s = self.support_distance(attitude);
        let body = if h_s > 0.0 {
            let d2 = self.semi_axes.component_mul(&self.semi_axes);
            self.centre - d2.component_mul(&n) / h_s
        } else {
            self.centre
        };
        LowestPoint {
            body,
            support_distance: h_s,
        }
    }

    /// Horizontal section at `h_T` above the lowest point (§2.4): an ellipse of area
    /// `π a (w/2) c_z / h_s · (2ρ' − ρ'²)`, `ρ' = h_T/h_s`, semi-axes from the singular values
    /// of the section map. Only the lower half is material, so a cut above the centre
    /// (`h_T > h_s`) is clamped to the section through the centre, the bulge's footprint
    /// (the ABS around the bulge is not part of the 2-DOF interface). Negative or non-finite
    /// `h_T` is an error; `h_T = 0` gives a zero area.
    pub fn section(&self, attitude: &Attitude, truncation_height: f64) -> Result<Section> {
        require_non_negative("truncation height h_T (m)", truncation_height)?;
        let (a, b) = (self.semi_axes.x, self.semi_axes.y);
        let n = attitude.body_vertical();
        let h_s = self.support_distance(attitude);
        if h_s == 0.0 {
            // A flat disc parallel to the disk: any positive cut contains all of it.
            let (dx, dy) = if truncation_height > 0.0 {
                (a, b)
            } else {
                (0.0, 0.0)
            };
            return Ok(Section {
                truncation_height,
                semi_axis_x: dx,
                semi_axis_y: dy,
                area: std::f64::consts::PI * dx * dy,
            });
        }
        // In u = D⁻¹ p the ellipsoid is the unit sphere and the cut plane lies at distance
        // ρ = 1 − h_T/h_s from the origin, normal m = D n / h_s: the section is a circle of
        // radius sqrt(1 − ρ²), mapped back by D restricted to that plane.
        let rho = (1.0 - truncation_height / h_s).max(0.0);
        let radius_u = (1.0 - rho * rho).max(0.0).sqrt();
        let m = self.semi_axes.component_mul(&n) / h_s;
        let (u1, u2) = plane_basis(&m);
        let d = Matrix3::from_diagonal(&self.semi_axes);
        let b1 = d * u1;
        let b2 = d * u2;
        // Gram matrix of the section map; its eigenvalues are the squared singular values.
        let g11 = b1.dot(&b1);
        let g12 = b1.dot(&b2);
        let g22 = b2.dot(&b2);
        let (l1, v1, l2, v2) = symmetric_2x2_eigen(g11, g12, g22);
        let w1 = b1 * v1.x + b2 * v1.y;
        let w2 = b1 * v2.x + b2 * v2.y;
        let s1 = radius_u * l1.max(0.0).sqrt();
        let s2 = radius_u * l2.max(0.0).sqrt();
        // Assign each semi-axis to the body axis its direction is closest to.
        let (dx, dy) = if w1.x.abs() * w2.y.abs() >= w1.y.abs() * w2.x.abs() {
            (s1, s2)
        } else {
            (s2, s1)
        };
        // The closed form of §2.4 (equal to π dx dy; zero for a flat, tilted bulge).
        let area = std::f64::consts::PI * a * b * self.semi_axes.z / h_s * radius_u * radius_u;
        Ok(Section {
            truncation_height,
            semi_axis_x: dx,
            semi_axis_y: dy,
            area,
        })
    }
}

/// Orthonormal basis of the plane perpendicular to the unit vector `m`.
fn plane_basis(m: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    // Project the coordinate axis least aligned with m (robust for any m).
    let axis = if m.x.abs() <= m.y.abs() && m.x.abs() <= m.z.abs() {
        Vector3::x()
    } else if m.y.abs() <= m.z.abs() {
        Vector3::y()
    } else {
        Vector3::z()
    };
    let u1 = (axis - m * m.dot(&axis)).normalize();
    let u2 = m.cross(&u1).normalize();
    (u1, u2)
}

/// Eigen-pairs `(λ1, v1, λ2, v2)`, `λ1 ≥ λ2`, of `[[p, q], [q, r]]`.
fn symmetric_2x2_eigen(p: f64, q: f64, r: f64) -> (f64, Vector2<f64>, f64, Vector2<f64>) {
    let mean = 0.5 * (p + r);
    let dev = (0.25 * (p - r) * (p - r) + q * q).sqrt();
    let (l1, l2) = (mean + dev, mean - dev);
    let v1 = if q.abs() > 1e-300 {
        Vector2::new(l1 - r, q).normalize()
    } else if p >= r {
        Vector2::x()
    } else {
        Vector2::y()
    };
    let v2 = Vector2::new(-v1.y, v1.x);
    (l1, v1, l2, v2)
}

/// Contact criterion and truncation rule of a 2-DOF model (§1.2, §2.4).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactCriterion {
    /// Initial model: contact when the separation `h < nσ` (`n = 1.2` from touchdown
    /// experiments); truncation at `(3 − n)σ` above the lowest point (1.8σ).
    NSigma { n: f64 },
    /// Improved model: contact when `s < 3σ` (clearance `c = s − 3σ < 0`); adhesion negligible
    /// beyond `6σ`, so the truncation height is `6σ − 3σ = 3σ`.
    ThreeSigma,
}

impl ContactCriterion {
    /// Spacing below which solid contact is active (m).
    pub fn contact_threshold(&self, sigma: f64) -> f64 {
        match self {
            ContactCriterion::NSigma { n } => n * sigma,
            ContactCriterion::ThreeSigma => 3.0 * sigma,
        }
    }

    /// Truncation height for the nominal area (m), evaluated once per actuation (§2.4).
    pub fn truncation_height(&self, sigma: f64) -> f64 {
        match self {
            ContactCriterion::NSigma { n } => (3.0 - n) * sigma,
            ContactCriterion::ThreeSigma => 3.0 * sigma,
        }
    }

    /// Clearance `spacing − threshold` (negative = interference), m.
    pub fn clearance(&self, spacing: f64, sigma: f64) -> f64 {
        spacing - self.contact_threshold(sigma)
    }

    pub fn validate(&self) -> Result<()> {
        if let ContactCriterion::NSigma { n } = self {
            // n ≥ 3 would leave no truncation band; the calibration S1c scans 0…2.8.
            require_in(
                "contact criterion n (contact when h < nσ)",
                *n,
                0.0,
                2.8,
                "",
            )?;
        }
        Ok(())
    }
}

/// 3-DOF / per-feature truncation height from the current spacing,
/// `h_T = clamp(6σ − s, 0, 3σ)` (§2.4): zero (no area, adhesion negligible) beyond `6σ`.
pub fn spacing_truncation_height(spacing: f64, sigma: f64) -> f64 {
    (6.0 * sigma - spacing).clamp(0.0, 3.0 * sigma)
}

/// Hertz contact radius `a = (3 F R / (4 E*))^(1/3)` of a sphere of radius `R` on a flat
/// (used for the §2.7 plausibility check of the nominal area: 2.26 µm at 12 nm).
pub fn hertz_contact_radius(force: f64, radius: f64, reduced_modulus: f64) -> Result<f64> {
    require_non_negative("Hertz normal force (N)", force)?;
    require_positive("Hertz sphere radius (m)", radius)?;
    require_positive("reduced modulus E* (Pa)", reduced_modulus)?;
    Ok((3.0 * force * radius / (4.0 * reduced_modulus)).cbrt())
}

/// Which slider point carries the altitude anchor of the nominal state (§5.1, check C2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AltitudeAnchor {
    /// Improved model: the trailing edge (ABS level) at solid spacing `s_TE = FH_nom + T0`
    /// (11.75 nm) in the nominal state (§1.2, check C1).
    TrailingEdge { solid_spacing: f64 },
    /// Initial model, reproduction recipe of check C2: the ABS point under the bulge centre at
    /// separation `h = FH_nom` in the nominal state (the naive TE anchoring leaves a 0.96 nm
    /// offset the text does not explain).
    BulgeCentre { solid_spacing: f64 },
}

impl AltitudeAnchor {
    pub fn solid_spacing(&self) -> f64 {
        match self {
            AltitudeAnchor::TrailingEdge { solid_spacing }
            | AltitudeAnchor::BulgeCentre { solid_spacing } => *solid_spacing,
        }
    }
}

/// Geometry of a 2-DOF slider (heave `z`, pitch `θ`, no roll) with its TFC bulge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slider2DofGeometry {
    /// Slider length `l` along x (m); TE at `x = −l/2`, LE at `+l/2`.
    pub length: f64,
    /// Slider thickness `l_t` (m); the ABS is the plane `z = −l_t/2`.
    pub thickness: f64,
    pub bulge: BulgeDesign,
    /// Nominal pitch `θ0` (rad) of the nominal state.
    pub nominal_pitch: f64,
    pub anchor: AltitudeAnchor,
}

/// The bulge's point of contact in a given state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BulgePoc {
    /// Body coordinates relative to the COM (m).
    pub body: Vector3<f64>,
    /// World offset COM → POC, `r = R p` (m): the lever arm of every interfacial force.
    pub lever_arm: Vector3<f64>,
    /// Solid spacing `s` of the POC above the disk's mean plane (no DMW) (m). Subtract the DMW
    /// under the POC, `z_d(x_POC, t)`, to get the spacing the contact laws use.
    pub solid_spacing: f64,
    /// `h_s` of the closed form (m).
    pub support_distance: f64,
    /// `∂s/∂h_TFC` at fixed heave and pitch (= `−c_z n_z²/h_s` ≈ −1): the bulge surface moves
    /// relative to the body when the actuation varies (§4).
    pub spacing_per_actuation: f64,
}

impl BulgePoc {
    /// Rate `ṡ` of the POC spacing (no DMW): heave rate, pitch rate and actuation rate (§4,
    /// §5.3). By the envelope theorem the POC may be treated as a fixed body point.
    pub fn spacing_rate(
        &self,
        pitch: f64,
        heave_rate: f64,
        pitch_rate: f64,
        actuation_rate: f64,
    ) -> f64 {
        let (st, ct) = pitch.sin_cos();
        heave_rate
            + pitch_rate * (ct * self.body.x - st * self.body.z)
            + self.spacing_per_actuation * actuation_rate
    }
}

impl Slider2DofGeometry {
    pub fn validate(&self) -> Result<()> {
        require_positive("slider length l (m)", self.length)?;
        require_positive("slider thickness l_t (m)", self.thickness)?;
        self.bulge.validate()?;
        if self.bulge.offset_from_te + self.bulge.semi_width_x > self.length {
            return Err(DynamicsError::parameter(
                "x_TFC (bulge centre from the TE, m)",
                self.bulge.offset_from_te,
                format!("x_TFC + a_TFC must be <= l = {:e} m", self.length),
            ));
        }
        // Small-angle models: |θ0| up to 10 mrad (the operating value is 100 µrad).
        require_in(
            "nominal pitch θ0 (rad)",
            self.nominal_pitch,
            -1e-2,
            1e-2,
            "rad",
        )?;
        require_in(
            "anchor solid spacing (m)",
            self.anchor.solid_spacing(),
            0.0,
            1e-6,
            "m",
        )?;
        Ok(())
    }

    /// Trailing-edge point at ABS level, `(−l/2, 0, −l_t/2)`.
    pub fn trailing_edge(&self) -> Vector3<f64> {
        Vector3::new(-0.5 * self.length, 0.0, -0.5 * self.thickness)
    }

    /// Leading-edge point at ABS level, `(+l/2, 0, −l_t/2)`.
    pub fn leading_edge(&self) -> Vector3<f64> {
        Vector3::new(0.5 * self.length, 0.0, -0.5 * self.thickness)
    }

    /// Ellipsoid centre `(−l/2 + x_TFC, 0, −l_t/2)` (§2.1, 2-DOF: on the ABS).
    pub fn bulge_centre(&self) -> Vector3<f64> {
        Vector3::new(
            -0.5 * self.length + self.bulge.offset_from_te,
            0.0,
            -0.5 * self.thickness,
        )
    }

    /// The bulge at actuation `h_TFC` (its height; §2.1 "the actuation is the bulge height").
    pub fn bulge_at(&self, actuation: f64) -> Result<HalfEllipsoid> {
        require_in("TFC actuation h_TFC (m)", actuation, 0.0, 1e-6, "m")?;
        HalfEllipsoid::new(
            self.bulge_centre(),
            Vector3::new(
                self.bulge.semi_width_x,
                0.5 * self.bulge.full_width_y,
                actuation,
            ),
        )
    }

    fn anchor_point(&self) -> Vector3<f64> {
        match self.anchor {
            AltitudeAnchor::TrailingEdge { .. } => self.trailing_edge(),
            AltitudeAnchor::BulgeCentre { .. } => self.bulge_centre(),
        }
    }

    /// Solid spacing above the disk mean plane (no DMW) of a body point at heave `z` (COM
    /// displacement from the nominal state) and pitch `θ`. Computed as the anchor's nominal
    /// spacing plus increments (§5.3), never as a difference of ~0.15 mm altitudes.
    pub fn spacing_of(&self, body_point: &Vector3<f64>, heave: f64, pitch: f64) -> f64 {
        let p = body_point;
        let q = self.anchor_point();
        let th0 = self.nominal_pitch;
        // sinθ − sinθ0 and cosθ − cosθ0 without cancellation.
        let half_sum = 0.5 * (pitch + th0);
        let half_diff_sin = (0.5 * (pitch - th0)).sin();
        let d_sin = 2.0 * half_sum.cos() * half_diff_sin;
        let d_cos = -2.0 * half_sum.sin() * half_diff_sin;
        let (s0, c0) = th0.sin_cos();
        self.anchor.solid_spacing()
            + heave
            + d_sin * p.x
            + s0 * (p.x - q.x)
            + d_cos * p.z
            + c0 * (p.z - q.z)
    }

    /// The bulge POC at heave `z`, pitch `θ` and actuation `h_TFC` (§2.2, §5.1):
    /// `s_POC = s_anchor + z + [(R c)_z − (R0 p_anchor)_z] − h_s`.
    pub fn bulge_poc(&self, heave: f64, pitch: f64, actuation: f64) -> Result<BulgePoc> {
        require_finite("heave z (m)", heave)?;
        require_in("pitch θ (rad)", pitch, -0.1, 0.1, "rad")?;
        let bulge = self.bulge_at(actuation)?;
        let attitude = Attitude::pitch_only(pitch);
        let low = bulge.lowest_point(&attitude);
        let n = attitude.body_vertical();
        let spacing = self.spacing_of(&bulge.centre, heave, pitch) - low.support_distance;
        let spacing_per_actuation = if low.support_distance > 0.0 {
            -actuation * n.z * n.z / low.support_distance
        } else {
            -1.0
        };
        Ok(BulgePoc {
            body: low.body,
            lever_arm: attitude.world_offset(&low.body),
            solid_spacing: spacing,
            support_distance: low.support_distance,
            spacing_per_actuation,
        })
    }

    /// [`Slider2DofGeometry::bulge_poc`] and [`Slider2DofGeometry::spacing_of`] at one actuation
    /// with every state-independent term computed once, for the 2-DOF right-hand side.
    pub fn poc_frame(&self, actuation: f64) -> Result<PocFrame> {
        let bulge = self.bulge_at(actuation)?;
        let (s0, c0) = self.nominal_pitch.sin_cos();
        Ok(PocFrame {
            semi_axes: bulge.semi_axes,
            semi_axes_sq: bulge.semi_axes.component_mul(&bulge.semi_axes),
            centre: bulge.centre,
            actuation,
            nominal_pitch: self.nominal_pitch,
            s0,
            c0,
            anchor: self.anchor_point(),
            anchor_spacing: self.anchor.solid_spacing(),
        })
    }

    /// Nominal contact area of the bulge at actuation `h_TFC`, truncation height `h_T` and pitch
    /// (§2.4). The faithful 2-DOF use evaluates it once per actuation at `θ0`.
    pub fn nominal_contact_area(
        &self,
        actuation: f64,
        truncation_height: f64,
        pitch: f64,
    ) -> Result<Section> {
        require_in("pitch θ (rad)", pitch, -0.1, 0.1, "rad")?;
        self.bulge_at(actuation)?
            .section(&Attitude::pitch_only(pitch), truncation_height)
    }
}

/// The pitch-dependent trigonometry of one state, computed once and shared by the POC, its
/// rate and any other body point's spacing ([`PocFrame::pitch_terms`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PitchTerms {
    pub pitch: f64,
    sin: f64,
    cos: f64,
    /// `sinθ − sinθ0`, `cosθ − cosθ0` without cancellation.
    d_sin: f64,
    d_cos: f64,
}

/// The bulge POC of a 2-DOF slider at one actuation with the state-independent terms
/// precomputed ([`Slider2DofGeometry::poc_frame`]): the same arithmetic, in the same order, as
/// [`Slider2DofGeometry::bulge_poc`] and [`Slider2DofGeometry::spacing_of`] (so bit-identical
/// results), with one `sin_cos(θ)` and one half-angle triple per state instead of nine
/// trigonometric calls and a validated ellipsoid per call (the 2-DOF inner loop,
/// docs/performance.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PocFrame {
    semi_axes: Vector3<f64>,
    semi_axes_sq: Vector3<f64>,
    centre: Vector3<f64>,
    actuation: f64,
    nominal_pitch: f64,
    s0: f64,
    c0: f64,
    anchor: Vector3<f64>,
    anchor_spacing: f64,
}

impl PocFrame {
    /// Trigonometry of pitch `θ`.
    #[inline]
    pub fn pitch_terms(&self, pitch: f64) -> PitchTerms {
        let th0 = self.nominal_pitch;
        let half_sum = 0.5 * (pitch + th0);
        let half_diff_sin = (0.5 * (pitch - th0)).sin();
        let (sin, cos) = pitch.sin_cos();
        PitchTerms {
            pitch,
            sin,
            cos,
            d_sin: 2.0 * half_sum.cos() * half_diff_sin,
            d_cos: -2.0 * half_sum.sin() * half_diff_sin,
        }
    }

    /// [`Slider2DofGeometry::spacing_of`] with the pitch's trigonometry given.
    #[inline]
    pub fn spacing_of(&self, p: &Vector3<f64>, heave: f64, tr: &PitchTerms) -> f64 {
        let q = &self.anchor;
        self.anchor_spacing
            + heave
            + tr.d_sin * p.x
            + self.s0 * (p.x - q.x)
            + tr.d_cos * p.z
            + self.c0 * (p.z - q.z)
    }

    /// [`Slider2DofGeometry::bulge_poc`] (same checks, same errors).
    #[inline]
    pub fn poc(&self, heave: f64, tr: &PitchTerms) -> Result<BulgePoc> {
        require_finite("heave z (m)", heave)?;
        require_in("pitch θ (rad)", tr.pitch, -0.1, 0.1, "rad")?;
        // n = Rᵀe_z at zero roll: (sinθ, cosθ·0, cosθ·1).
        let n = Vector3::new(tr.sin, tr.cos * 0.0, tr.cos);
        let h_s = self.semi_axes.component_mul(&n).norm();
        let body = if h_s > 0.0 {
            self.centre - self.semi_axes_sq.component_mul(&n) / h_s
        } else {
            self.centre
        };
        let (st, ct) = (tr.sin, tr.cos);
        let rotation = Matrix3::new(ct, -st * 0.0, -st, 0.0, 1.0, -0.0, st, ct * 0.0, ct);
        let spacing = self.spacing_of(&self.centre, heave, tr) - h_s;
        let spacing_per_actuation = if h_s > 0.0 {
            -self.actuation * n.z * n.z / h_s
        } else {
            -1.0
        };
        Ok(BulgePoc {
            body,
            lever_arm: rotation * body,
            solid_spacing: spacing,
            support_distance: h_s,
            spacing_per_actuation,
        })
    }

    /// [`BulgePoc::spacing_rate`] at zero actuation rate with the pitch's trigonometry given.
    #[inline]
    pub fn spacing_rate(
        &self,
        poc: &BulgePoc,
        tr: &PitchTerms,
        heave_rate: f64,
        pitch_rate: f64,
    ) -> f64 {
        let (st, ct) = (tr.sin, tr.cos);
        heave_rate
            + pitch_rate * (ct * poc.body.x - st * poc.body.z)
            + poc.spacing_per_actuation * 0.0
    }
}
