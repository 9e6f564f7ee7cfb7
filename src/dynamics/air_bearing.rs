//! Linear air bearing of the 2-DOF models (§2.1, §2.2, eqs. 2.8–2.15; docs/dynamics-geometry.md).
//!
//! The AB is a front spring at `x = +d_f` and a rear spring at `x = −d_r` (ABS level). Their
//! stiffnesses come from the two AB natural frequencies by modal inversion (closed form,
//! suspension included); damping from damping ratios; the improved model stiffens the rear
//! spring with actuation. Forces are increments about the nominal state (the nominal AB force
//! balances the preload by construction, §5.1).

use nalgebra::{Matrix2, Vector2};

use super::{require_in, require_non_negative, require_positive, DynamicsError, Result, NM};

/// Which root of the modal inversion is the rear spring (`ab_root_assignment`, §3.1, §11.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RootAssignment {
    /// Default: the stiffer spring at the rear (TE). Gives the textbook mode shapes and puts the
    /// stiffness that grows as the pole tip approaches the disk at the TE.
    #[default]
    StiffRear,
    /// The other root pair; the same two frequencies, rejected on physical grounds.
    StiffFront,
}

/// Heave–pitch rigid body on two AB springs plus the suspension (what the inversion needs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeavePitchBody {
    /// Slider mass `m` (kg).
    pub mass: f64,
    /// Pitch moment of inertia `J_θ` about the COM (kg·m²).
    pub pitch_inertia: f64,
    /// Front spring arm `d_f` (m), spring at `x = +d_f`.
    pub front_arm: f64,
    /// Rear spring arm `d_r` (m), spring at `x = −d_r`.
    pub rear_arm: f64,
    /// Suspension heave stiffness `k` (N/m).
    pub suspension_heave_stiffness: f64,
    /// Suspension pitch stiffness `k_θ` (N·m/rad).
    pub suspension_pitch_stiffness: f64,
}

impl HeavePitchBody {
    pub fn validate(&self) -> Result<()> {
        require_positive("slider mass m (kg)", self.mass)?;
        require_positive("pitch inertia J_θ (kg·m²)", self.pitch_inertia)?;
        require_positive("front AB spring arm d_f (m)", self.front_arm)?;
        require_positive("rear AB spring arm d_r (m)", self.rear_arm)?;
        require_non_negative(
            "suspension stiffness k (N/m)",
            self.suspension_heave_stiffness,
        )?;
        require_non_negative(
            "suspension pitch stiffness k_θ (N·m/rad)",
            self.suspension_pitch_stiffness,
        )?;
        Ok(())
    }

    pub fn mass_matrix(&self) -> Matrix2<f64> {
        Matrix2::new(self.mass, 0.0, 0.0, self.pitch_inertia)
    }

    /// Stiffness matrix of `q = [z, ϑ]` with both AB springs and the suspension,
    /// springs acting on `z + d_f ϑ` (front) and `z − d_r ϑ` (rear).
    pub fn stiffness_matrix(&self, springs: &SpringPair) -> Matrix2<f64> {
        let (kf, kr) = (springs.front, springs.rear);
        let (df, dr) = (self.front_arm, self.rear_arm);
        let coupling = df * kf - dr * kr;
        Matrix2::new(
            self.suspension_heave_stiffness + kf + kr,
            coupling,
            coupling,
            self.suspension_pitch_stiffness + df * df * kf + dr * dr * kr,
        )
    }
}

/// Front and rear AB spring constants (N/m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpringPair {
    pub front: f64,
    pub rear: f64,
}

/// Front/rear AB stiffness that make the heave–pitch system (suspension included) have the
/// natural frequencies `f1 < f2` (Hz) — modal inversion in closed form (§3.1).
///
/// With `λ_i = (2π f_i)²`, trace and determinant of `M⁻¹K` give
/// `A k_f + B k_r = λ1 + λ2 − k/m − k_θ/J` (`A = 1/m + d_f²/J`, `B = 1/m + d_r²/J`) and
/// `k k_θ + (k d_f² + k_θ) k_f + (k d_r² + k_θ) k_r + (d_f + d_r)² k_f k_r = λ1 λ2 m J`:
/// a quadratic in `k_f`. Its two roots are the two assignments; no real root means the
/// frequency ratio is too small for any pair of positive springs (`f2/f1 ≥ 1.683` for the
/// 2-DOF slider).
pub fn springs_from_frequencies(
    body: &HeavePitchBody,
    f1_hz: f64,
    f2_hz: f64,
    assignment: RootAssignment,
) -> Result<SpringPair> {
    body.validate()?;
    require_positive("first AB natural frequency f1 (Hz)", f1_hz)?;
    require_positive("second AB natural frequency f2 (Hz)", f2_hz)?;
    if f2_hz <= f1_hz {
        return Err(DynamicsError::parameter(
            "second AB natural frequency f2 (Hz)",
            f2_hz,
            format!("must be > f1 = {f1_hz} Hz"),
        ));
    }
    let two_pi = 2.0 * std::f64::consts::PI;
    let (l1, l2) = ((two_pi * f1_hz).powi(2), (two_pi * f2_hz).powi(2));
    let (m, j) = (body.mass, body.pitch_inertia);
    let (df, dr) = (body.front_arm, body.rear_arm);
    let (k, kt) = (
        body.suspension_heave_stiffness,
        body.suspension_pitch_stiffness,
    );
    let a = 1.0 / m + df * df / j;
    let b = 1.0 / m + dr * dr / j;
    let s = l1 + l2 - k / m - kt / j;
    let alpha = k * df * df + kt;
    let beta = k * dr * dr + kt;
    let d2 = (df + dr).powi(2);
    // d2·A k_f² − (B α − β A + d2 S) k_f + B (m J λ1 λ2 − k k_θ) − β S = 0
    let qa = d2 * a;
    let qb = b * alpha - beta * a + d2 * s;
    let qc = b * (m * j * l1 * l2 - k * kt) - beta * s;
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return Err(DynamicsError::Numerical(format!(
            "no real AB spring pair has natural frequencies {f1_hz} and {f2_hz} Hz \
             (the frequency ratio {:.3} is too small for this slider)",
            f2_hz / f1_hz
        )));
    }
    let sq = disc.sqrt();
    // Stable roots: avoid subtracting nearly equal numbers.
    let big = (qb + sq.copysign(qb)) / (2.0 * qa);
    let small = if big != 0.0 { qc / (qa * big) } else { 0.0 };
    let pair = |kf: f64| SpringPair {
        front: kf,
        rear: (s - a * kf) / b,
    };
    let candidates = [pair(small), pair(big)];
    let chosen = candidates
        .iter()
        .filter(|p| p.front > 0.0 && p.rear > 0.0)
        .find(|p| match assignment {
            RootAssignment::StiffRear => p.rear >= p.front,
            RootAssignment::StiffFront => p.front >= p.rear,
        })
        .copied();
    chosen.ok_or_else(|| {
        DynamicsError::Numerical(format!(
            "modal inversion for {f1_hz} / {f2_hz} Hz has no positive root pair with the \
             {assignment:?} assignment (roots: {candidates:?})"
        ))
    })
}

/// One undamped mode of the heave–pitch system.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeavePitchMode {
    /// Natural frequency (Hz).
    pub frequency_hz: f64,
    /// Mode shape `[z, ϑ]` (m, rad), scaled to unit length in mass-normalised coordinates.
    pub shape: Vector2<f64>,
}

impl HeavePitchMode {
    /// Modal amplitude at body position `x` (linearised: `z + x ϑ`).
    pub fn amplitude_at(&self, x: f64) -> f64 {
        self.shape.x + x * self.shape.y
    }

    /// Node of the mode along x (where `z + x ϑ = 0`); infinite for pure heave.
    pub fn node_x(&self) -> f64 {
        if self.shape.y == 0.0 {
            f64::INFINITY
        } else {
            -self.shape.x / self.shape.y
        }
    }

    /// Equivalent modal damping ratio `φᵀCφ / (2 ω φᵀMφ)` (exact for proportional damping,
    /// the usual estimate otherwise).
    pub fn damping_ratio(&self, damping: &Matrix2<f64>, mass: &Matrix2<f64>) -> f64 {
        let phi = self.shape;
        let omega = 2.0 * std::f64::consts::PI * self.frequency_hz;
        (phi.transpose() * damping * phi)[0] / (2.0 * omega * (phi.transpose() * mass * phi)[0])
    }
}

/// Undamped modes of `M q̈ + K q = 0` for a diagonal positive `M` and symmetric `K`, by a
/// symmetric eigen-solve of `M^{-1/2} K M^{-1/2}` (nalgebra); sorted by frequency.
pub fn heave_pitch_modes(
    mass: &Matrix2<f64>,
    stiffness: &Matrix2<f64>,
) -> Result<[HeavePitchMode; 2]> {
    if mass[(0, 1)] != 0.0 || mass[(1, 0)] != 0.0 || !(mass[(0, 0)] > 0.0 && mass[(1, 1)] > 0.0) {
        return Err(DynamicsError::Numerical(
            "heave_pitch_modes needs a diagonal, positive mass matrix".into(),
        ));
    }
    if (stiffness[(0, 1)] - stiffness[(1, 0)]).abs() > 1e-12 * stiffness.norm()
        || !stiffness.iter().all(|v| v.is_finite())
    {
        return Err(DynamicsError::Numerical(
            "heave_pitch_modes needs a finite, symmetric stiffness matrix".into(),
        ));
    }
    let inv_sqrt = Matrix2::new(
        1.0 / mass[(0, 0)].sqrt(),
        0.0,
        0.0,
        1.0 / mass[(1, 1)].sqrt(),
    );
    let reduced = inv_sqrt * stiffness * inv_sqrt;
    let eig = nalgebra::SymmetricEigen::new(reduced);
    let mut modes = [0usize, 1].map(|i| {
        let lambda = eig.eigenvalues[i];
        let shape = inv_sqrt * eig.eigenvectors.column(i).into_owned();
        (lambda, shape)
    });
    modes.sort_by(|a, b| a.0.total_cmp(&b.0));
    if modes[0].0 <= 0.0 {
        return Err(DynamicsError::Numerical(format!(
            "stiffness matrix is not positive definite (eigenvalue {:e})",
            modes[0].0
        )));
    }
    Ok(modes.map(|(lambda, shape)| HeavePitchMode {
        frequency_hz: lambda.sqrt() / (2.0 * std::f64::consts::PI),
        shape,
    }))
}

/// Roll AB stiffness from the roll frequency, `k_l = J_φ (2π f_roll)² − k_φ` (§3.1; roll is
/// decoupled from pitch for a symmetric ABS at zero skew).
pub fn roll_stiffness_from_frequency(
    roll_inertia: f64,
    roll_frequency_hz: f64,
    suspension_roll_stiffness: f64,
) -> Result<f64> {
    require_positive("roll inertia J_φ (kg·m²)", roll_inertia)?;
    require_positive("roll AB frequency (Hz)", roll_frequency_hz)?;
    require_non_negative(
        "suspension roll stiffness k_φ (N·m/rad)",
        suspension_roll_stiffness,
    )?;
    let k = roll_inertia * (2.0 * std::f64::consts::PI * roll_frequency_hz).powi(2)
        - suspension_roll_stiffness;
    if k <= 0.0 {
        return Err(DynamicsError::Numerical(format!(
            "suspension roll stiffness {suspension_roll_stiffness:e} alone exceeds the roll \
             frequency {roll_frequency_hz} Hz"
        )));
    }
    Ok(k)
}

/// Damping coefficient of a lumped element from its damping ratio, `c = 2ζ sqrt(k·m)` with the
/// element's own stiffness and the slider inertia (§3.4; the dissertation's rule was not stated).
pub fn damping_coefficient(damping_ratio: f64, stiffness: f64, inertia: f64) -> Result<f64> {
    require_in("damping ratio ζ", damping_ratio, 0.0, 1.0, "")?;
    require_non_negative("stiffness for damping (N/m or N·m/rad)", stiffness)?;
    require_positive("inertia for damping (kg or kg·m²)", inertia)?;
    Ok(2.0 * damping_ratio * (stiffness * inertia).sqrt())
}

/// Actuation at which the default stiffening doubles the rear spring for `β = 1` (§3.2).
pub const STIFFENING_REFERENCE_ACTUATION: f64 = 15.0 * NM;

/// Flying height above which the AB is considered lost (third state of §2.1.3): a 2-DOF case
/// whose TE FH exceeds it must be stopped and reported, not continued with a linear spring.
pub const AB_LOSS_FLYING_HEIGHT: f64 = 15.0 * NM;

/// Rear AB spring versus TFC actuation (§3.2).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RearStiffening {
    /// Initial model: `k_r` constant (nominal FH held up to contact).
    Constant,
    /// Improved model (Zheng & Bogy stiffening; curve lost): assumption
    /// `k_r = k_r,nom (1 + β (h_TFC / 15 nm)²)`, `β` = switch `kr_stiffening_beta` (default 1,
    /// calibrate in [0, 3] to touchdown at 9.7 nm).
    Quadratic { beta: f64 },
}

impl RearStiffening {
    pub fn validate(&self) -> Result<()> {
        if let RearStiffening::Quadratic { beta } = self {
            require_in("kr_stiffening_beta β", *beta, 0.0, 3.0, "")?;
        }
        Ok(())
    }

    /// `k_r(h_TFC)` for a nominal rear stiffness.
    pub fn rear_stiffness(&self, nominal: f64, actuation: f64) -> f64 {
        match self {
            RearStiffening::Constant => nominal,
            RearStiffening::Quadratic { beta } => {
                let r = actuation / STIFFENING_REFERENCE_ACTUATION;
                nominal * (1.0 + beta * r * r)
            }
        }
    }
}

/// State of the 2-DOF models: heave and pitch offset from the nominal state and their rates.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HeavePitchState {
    /// COM heave `z` from the nominal state (m), up positive.
    pub heave: f64,
    /// Pitch offset `ϑ = θ − θ0` (rad).
    pub pitch_offset: f64,
    pub heave_rate: f64,
    pub pitch_rate: f64,
}

/// DMW displacement (m, up positive) and velocity under the two AB springs (`z_df`, `z_dr`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DmwAtSprings {
    pub front: f64,
    pub front_rate: f64,
    pub rear: f64,
    pub rear_rate: f64,
}

/// Incremental AB forces (about the nominal state) and their generalised forces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AbForces {
    /// Front spring force (N), up positive.
    pub front: f64,
    /// Rear spring force (N), up positive.
    pub rear: f64,
    /// `front + rear` (N).
    pub heave: f64,
    /// `d_f·front − d_r·rear` (N·m), positive raises the LE.
    pub pitch_moment: f64,
}

/// Lumped linear suspension elements of the 2-DOF models.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SuspensionCoefficients {
    /// `k` (N/m).
    pub heave_stiffness: f64,
    /// `c` (N·s/m).
    pub heave_damping: f64,
    /// `k_θ` (N·m/rad).
    pub pitch_stiffness: f64,
    /// `c_θ` (N·m·s/rad).
    pub pitch_damping: f64,
}

/// `M`, `C`, `K` of eqs. 2.9–2.11 (front spring inside, rear spring stiffness on the right).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EomMatrices {
    pub mass: Matrix2<f64>,
    pub damping: Matrix2<f64>,
    pub stiffness: Matrix2<f64>,
}

/// The air bearing of a 2-DOF slider: springs at `±l/2` on the ABS (`d_f = d_r = l/2`, §5.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AirBearing2Dof {
    /// `k_f` (N/m).
    pub front_stiffness: f64,
    /// `k_r,nom` (N/m).
    pub rear_stiffness_nominal: f64,
    /// `c_f` (N·s/m).
    pub front_damping: f64,
    /// `c_r` (N·s/m), from `k_r,nom` so it stays constant in time (§3.4).
    pub rear_damping: f64,
    /// Spring arm `l/2` (m).
    pub half_length: f64,
    pub stiffening: RearStiffening,
}

impl AirBearing2Dof {
    /// `k_r(h_TFC)`.
    pub fn rear_stiffness(&self, actuation: f64) -> f64 {
        self.stiffening
            .rear_stiffness(self.rear_stiffness_nominal, actuation)
    }

    /// Total incremental AB forces for a state, the DMW under the springs and the actuation:
    /// `F_f = k_f (z_df − z_f) + c_f (ż_df − ż_f)`, `F_r = k_r(h) (z_dr − z_r) + c_r (ż_dr − ż_r)`
    /// with the linearised kinematics `z_f = z + (l/2)ϑ`, `z_r = z − (l/2)ϑ` (§5.1).
    pub fn forces(&self, state: &HeavePitchState, dmw: &DmwAtSprings, actuation: f64) -> AbForces {
        let d = self.half_length;
        let z_f = state.heave + d * state.pitch_offset;
        let z_r = state.heave - d * state.pitch_offset;
        let v_f = state.heave_rate + d * state.pitch_rate;
        let v_r = state.heave_rate - d * state.pitch_rate;
        let front =
            self.front_stiffness * (dmw.front - z_f) + self.front_damping * (dmw.front_rate - v_f);
        let rear = self.rear_stiffness(actuation) * (dmw.rear - z_r)
            + self.rear_damping * (dmw.rear_rate - v_r);
        AbForces {
            front,
            rear,
            heave: front + rear,
            pitch_moment: d * (front - rear),
        }
    }

    /// `M`, `C`, `K` of eqs. 2.9–2.11 as written in §5.1.
    pub fn eom_matrices(
        &self,
        mass: f64,
        pitch_inertia: f64,
        suspension: &SuspensionCoefficients,
    ) -> EomMatrices {
        let d = self.half_length;
        let (cf, cr, kf) = (self.front_damping, self.rear_damping, self.front_stiffness);
        EomMatrices {
            mass: Matrix2::new(mass, 0.0, 0.0, pitch_inertia),
            damping: Matrix2::new(
                suspension.heave_damping + cf + cr,
                d * (cf - cr),
                d * (cf - cr),
                suspension.pitch_damping + d * d * (cf + cr),
            ),
            stiffness: Matrix2::new(
                suspension.heave_stiffness + kf,
                d * kf,
                d * kf,
                suspension.pitch_stiffness + d * d * kf,
            ),
        }
    }

    /// Right-hand side `f_a` of eqs. 2.12–2.13 (§5.1): DMW terms of the front spring, DMW
    /// rate of the rear damper and the rear spring force `F_ar = k_r(h)(z_dr − z_r)`.
    /// `M q̈ + C q̇ + K q = f_a` is identical to using [`Self::forces`] with the suspension alone
    /// on the left.
    pub fn eom_forcing(
        &self,
        state: &HeavePitchState,
        dmw: &DmwAtSprings,
        actuation: f64,
    ) -> Vector2<f64> {
        self.eom_forcing_at(state, dmw, self.rear_stiffness(actuation))
    }

    /// [`Self::eom_forcing`] with the rear stiffness `k_r(h)` given (constant per case, so the
    /// 2-DOF right-hand side computes it once).
    #[inline]
    pub fn eom_forcing_at(
        &self,
        state: &HeavePitchState,
        dmw: &DmwAtSprings,
        rear_stiffness: f64,
    ) -> Vector2<f64> {
        let d = self.half_length;
        let z_r = state.heave - d * state.pitch_offset;
        let f_ar = rear_stiffness * (dmw.rear - z_r);
        let front = self.front_stiffness * dmw.front + self.front_damping * dmw.front_rate;
        let rear = self.rear_damping * dmw.rear_rate + f_ar;
        Vector2::new(front + rear, d * front - d * rear)
    }

    /// Undamped heave–pitch modes at actuation `h_TFC` (rear spring `k_r(h)`), nalgebra
    /// eigen-solve.
    pub fn modes(
        &self,
        mass: f64,
        pitch_inertia: f64,
        suspension: &SuspensionCoefficients,
        actuation: f64,
    ) -> Result<[HeavePitchMode; 2]> {
        let body = HeavePitchBody {
            mass,
            pitch_inertia,
            front_arm: self.half_length,
            rear_arm: self.half_length,
            suspension_heave_stiffness: suspension.heave_stiffness,
            suspension_pitch_stiffness: suspension.pitch_stiffness,
        };
        body.validate()?;
        let springs = SpringPair {
            front: self.front_stiffness,
            rear: self.rear_stiffness(actuation),
        };
        heave_pitch_modes(&body.mass_matrix(), &body.stiffness_matrix(&springs))
    }
}
