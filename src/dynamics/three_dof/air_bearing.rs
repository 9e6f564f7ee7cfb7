//! Pure 3-DOF air bearing (§4.1.1, eqs. 4.1–4.17; docs/dynamics-3dof-air-bearing.md).
//!
//! Two AB springs on the ABS centre line (front at `x = +d_f`, rear at `x = −d_r`) whose
//! stiffnesses follow the pole-tip flying height `PT` through a table of AB natural frequencies
//! (modal inversion per grid point, stiff rear, [`springs_from_frequencies`]), a constant roll
//! spring `k_l` inside `K`, dampers from damping ratios and the nominal stiffnesses, the
//! TFC-induced AB force increase `ΔF_AB(h_TFC)` distributed by the lever rule, and the
//! calibration of `ΔF_AB` against a push-back curve by a static solve.
//!
//! Conventions are those of §1.1: `+Z` up, `+X` toward the LE, pitch `θ > 0` raises the LE,
//! `R(θ, φ) = R_y(−θ)·R_x(φ)`. Spacings `s` are solid spacings (chapter 4 measures FH from the
//! solid mean plane). The nominal state is `s_TE = FH_nom`, pitch `θ0`, roll 0, heave `z = 0`.
//! Pure functions, no I/O, SI units inside.

use nalgebra::{Matrix3, Vector3};

use crate::dynamics::air_bearing::{
    damping_coefficient, roll_stiffness_from_frequency, springs_from_frequencies, HeavePitchBody,
    RootAssignment,
};
use crate::dynamics::geometry::{generalised_force, Attitude};
use crate::dynamics::params::{SliderBody, Suspension};
use crate::dynamics::{
    require_finite, require_in, require_non_negative, require_positive, DynamicsError, Result, NM,
    UM,
};

/// Default normal / 2nd-pitch AB frequency versus pole-tip FH (§3.3, assumption):
/// `f_n = 120 + 2351·PT^−1.071` kHz with `PT` in nm. Argument and result in SI (m, Hz).
pub fn default_normal_frequency_hz(pole_tip: f64) -> f64 {
    (120.0 + 2351.0 * (pole_tip / NM).powf(-1.071)) * 1e3
}

/// One row of the AB frequency table (Fig. 4.2 of the dissertation, digits lost).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AbFrequencyPoint {
    /// Pole-tip FH `PT` (m).
    pub pole_tip: f64,
    /// 1st pitch frequency (Hz).
    pub first_pitch_hz: f64,
    /// Normal / 2nd pitch frequency (Hz).
    pub normal_hz: f64,
    /// Roll frequency (Hz).
    pub roll_hz: f64,
}

/// AB natural frequencies versus pole-tip FH, strictly increasing in `PT`.
#[derive(Debug, Clone, PartialEq)]
pub struct AbFrequencyTable {
    points: Vec<AbFrequencyPoint>,
}

/// The default grid of §3.3 (nm).
pub const DEFAULT_POLE_TIP_GRID_NM: [f64; 6] = [2.5, 5.0, 10.0, 11.0, 15.0, 20.0];

impl AbFrequencyTable {
    /// A user table: at least two rows, `PT` strictly increasing and positive, frequencies
    /// positive, 1st pitch below the normal mode.
    pub fn new(points: Vec<AbFrequencyPoint>) -> Result<Self> {
        if points.len() < 2 {
            return Err(DynamicsError::parameter(
                "AB frequency table rows",
                points.len() as f64,
                "needs at least 2 rows",
            ));
        }
        let mut last = 0.0;
        for p in &points {
            require_positive("AB table pole-tip FH PT (m)", p.pole_tip)?;
            if p.pole_tip <= last {
                return Err(DynamicsError::parameter(
                    "AB table pole-tip FH PT (m)",
                    p.pole_tip,
                    format!("must increase strictly (previous row {last:e} m)"),
                ));
            }
            last = p.pole_tip;
            require_positive("AB table 1st pitch frequency (Hz)", p.first_pitch_hz)?;
            require_positive("AB table normal frequency (Hz)", p.normal_hz)?;
            require_positive("AB table roll frequency (Hz)", p.roll_hz)?;
            if p.normal_hz <= p.first_pitch_hz {
                return Err(DynamicsError::parameter(
                    "AB table normal frequency (Hz)",
                    p.normal_hz,
                    format!(
                        "must exceed the 1st pitch frequency {} Hz",
                        p.first_pitch_hz
                    ),
                ));
            }
        }
        Ok(AbFrequencyTable { points })
    }

    /// The default table of §3.3 [assumption]: `PT` = 2.5, 5, 10, 11, 15, 20 nm, normal mode
    /// from [`default_normal_frequency_hz`], 1st pitch 110 kHz, roll 100 kHz.
    pub fn default_table() -> Self {
        AbFrequencyTable {
            points: DEFAULT_POLE_TIP_GRID_NM
                .iter()
                .map(|&pt| AbFrequencyPoint {
                    pole_tip: pt * NM,
                    first_pitch_hz: 110e3,
                    normal_hz: default_normal_frequency_hz(pt * NM),
                    roll_hz: 100e3,
                })
                .collect(),
        }
    }

    pub fn points(&self) -> &[AbFrequencyPoint] {
        &self.points
    }
}

impl Default for AbFrequencyTable {
    fn default() -> Self {
        Self::default_table()
    }
}

/// Interpolation position of `x` in a strictly increasing grid: `(i, t)` with the value
/// `v[i] + t (v[i+1] − v[i])`; clamped (`t ∈ [0, 1]`; NaN → first point). No allocation.
fn bracket(grid: &[f64], x: f64) -> (usize, f64) {
    let n = grid.len();
    if x.is_nan() || x <= grid[0] {
        return (0, 0.0);
    }
    if x >= grid[n - 1] {
        return (n - 2, 1.0);
    }
    let i = grid.partition_point(|&g| g <= x) - 1;
    let i = i.min(n - 2);
    (i, (x - grid[i]) / (grid[i + 1] - grid[i]))
}

/// `∫ k dp` from grid point `i` to `p` on segment `i`, where `ln k` is linear in `ln p`:
/// `k = k_i (p/p_i)^b` → `k_i p_i ((p/p_i)^{b+1} − 1)/(b + 1)` (`k_i p_i ln(p/p_i)` at `b = −1`).
fn segment_integral(ln_grid: &[f64], ln_k: &[f64], i: usize, p: f64) -> f64 {
    let b = (ln_k[i + 1] - ln_k[i]) / (ln_grid[i + 1] - ln_grid[i]);
    let (pi, ki) = (ln_grid[i].exp(), ln_k[i].exp());
    let r = (p.ln() - ln_grid[i]).exp();
    if (b + 1.0).abs() < 1e-12 {
        ki * pi * r.ln()
    } else {
        ki * pi * (r.powf(b + 1.0) - 1.0) / (b + 1.0)
    }
}

/// AB spring stiffnesses per grid point, interpolated log–log (§3.3).
#[derive(Debug, Clone, PartialEq)]
pub struct AbStiffnessTable {
    ln_pole_tip: Vec<f64>,
    ln_front: Vec<f64>,
    ln_rear: Vec<f64>,
    /// `k_l` per grid point (N·m/rad).
    roll: Vec<f64>,
    /// `∫ k_f dPT`, `∫ k_r dPT` from the first grid point to each grid point (N).
    integral_front: Vec<f64>,
    integral_rear: Vec<f64>,
    /// `exp` of `ln_pole_tip`, `ln_front`, `ln_rear`: the integrals' per-node factors, computed
    /// once instead of in every right-hand-side call (the same values, bit for bit).
    pole_tip: Vec<f64>,
    front: Vec<f64>,
    rear: Vec<f64>,
}

/// One row of [`AbStiffnessTable`] in linear units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AbStiffnessPoint {
    pub pole_tip: f64,
    /// `k_f` (N/m).
    pub front: f64,
    /// `k_r` (N/m).
    pub rear: f64,
    /// `k_l` (N·m/rad).
    pub roll: f64,
}

impl AbStiffnessTable {
    /// Modal inversion at every row: `k_f, k_r` from (1st pitch, normal) with the heave–pitch
    /// body (suspension included, [`springs_from_frequencies`]); `k_l = J_φ (2π f_roll)² − k_φ`.
    pub fn from_frequencies(
        table: &AbFrequencyTable,
        body: &HeavePitchBody,
        roll_inertia: f64,
        suspension_roll_stiffness: f64,
        assignment: RootAssignment,
    ) -> Result<Self> {
        let n = table.points.len();
        let mut out = AbStiffnessTable {
            ln_pole_tip: Vec::with_capacity(n),
            ln_front: Vec::with_capacity(n),
            ln_rear: Vec::with_capacity(n),
            roll: Vec::with_capacity(n),
            integral_front: Vec::new(),
            integral_rear: Vec::new(),
            pole_tip: Vec::new(),
            front: Vec::new(),
            rear: Vec::new(),
        };
        for p in &table.points {
            let springs =
                springs_from_frequencies(body, p.first_pitch_hz, p.normal_hz, assignment)?;
            let k_l =
                roll_stiffness_from_frequency(roll_inertia, p.roll_hz, suspension_roll_stiffness)?;
            out.ln_pole_tip.push(p.pole_tip.ln());
            out.ln_front.push(springs.front.ln());
            out.ln_rear.push(springs.rear.ln());
            out.roll.push(k_l);
        }
        for ln_k in [&out.ln_front, &out.ln_rear] {
            let mut acc = vec![0.0];
            for i in 0..n - 1 {
                let last = acc[i];
                let p = out.ln_pole_tip[i + 1].exp();
                acc.push(last + segment_integral(&out.ln_pole_tip, ln_k, i, p));
            }
            if out.integral_front.is_empty() {
                out.integral_front = acc;
            } else {
                out.integral_rear = acc;
            }
        }
        let exp = |v: &[f64]| v.iter().map(|x| x.exp()).collect::<Vec<f64>>();
        out.pole_tip = exp(&out.ln_pole_tip);
        out.front = exp(&out.ln_front);
        out.rear = exp(&out.ln_rear);
        Ok(out)
    }

    /// `(∫k_f, ∫k_r)` over PT from the first grid point to `pole_tip` (N), with `k` as
    /// [`Self::stiffness_at`] gives it (log–log inside, constant outside): the antiderivative
    /// behind [`SpringLaw::Integrated`].
    pub fn stiffness_integral_at(&self, pole_tip: f64) -> (f64, f64) {
        (
            self.stiffness_integral_of(false, pole_tip),
            self.stiffness_integral_of(true, pole_tip),
        )
    }

    /// One spring's half of [`Self::stiffness_integral_at`]: `∫k_r` if `rear`, else `∫k_f`.
    pub fn stiffness_integral_of(&self, rear: bool, pole_tip: f64) -> f64 {
        let g = &self.ln_pole_tip;
        let n = g.len();
        let (ln_k, k, acc) = if rear {
            (&self.ln_rear, &self.rear, &self.integral_rear)
        } else {
            (&self.ln_front, &self.front, &self.integral_front)
        };
        let (p0, pn) = (self.pole_tip[0], self.pole_tip[n - 1]);
        if pole_tip.is_nan() || pole_tip <= p0 {
            let p = if pole_tip.is_nan() { p0 } else { pole_tip };
            return k[0] * (p - p0);
        }
        if pole_tip >= pn {
            return acc[n - 1] + k[n - 1] * (pole_tip - pn);
        }
        let ln_p = pole_tip.ln();
        let i = g.partition_point(|&x| x <= ln_p) - 1;
        let i = i.min(n - 2);
        // `segment_integral` with the node factors read from the table.
        let b = (ln_k[i + 1] - ln_k[i]) / (g[i + 1] - g[i]);
        let (pi, ki) = (self.pole_tip[i], k[i]);
        let r = (ln_p - g[i]).exp();
        let segment = if (b + 1.0).abs() < 1e-12 {
            ki * pi * r.ln()
        } else {
            ki * pi * (r.powf(b + 1.0) - 1.0) / (b + 1.0)
        };
        acc[i] + segment
    }

    /// `(k_f, k_r)` at pole-tip FH `PT` (m): `ln k` linear in `ln PT`, clamped outside the
    /// table (PT ≤ 0 or NaN → the smallest-PT row). Cheap, no allocation.
    pub fn stiffness_at(&self, pole_tip: f64) -> (f64, f64) {
        let x = if pole_tip > 0.0 {
            pole_tip.ln()
        } else {
            f64::NEG_INFINITY
        };
        let (i, t) = bracket(&self.ln_pole_tip, x);
        let lerp = |v: &[f64]| v[i] + t * (v[i + 1] - v[i]);
        (lerp(&self.ln_front).exp(), lerp(&self.ln_rear).exp())
    }

    /// `k_l` at `PT`, linear in `ln PT`, clamped (the roll spring itself is constant in `K`;
    /// this gives its value at the nominal FH).
    pub fn roll_at(&self, pole_tip: f64) -> f64 {
        let x = if pole_tip > 0.0 {
            pole_tip.ln()
        } else {
            f64::NEG_INFINITY
        };
        let (i, t) = bracket(&self.ln_pole_tip, x);
        self.roll[i] + t * (self.roll[i + 1] - self.roll[i])
    }

    /// The rows in linear units.
    pub fn points(&self) -> Vec<AbStiffnessPoint> {
        (0..self.ln_pole_tip.len())
            .map(|i| AbStiffnessPoint {
                pole_tip: self.ln_pole_tip[i].exp(),
                front: self.ln_front[i].exp(),
                rear: self.ln_rear[i].exp(),
                roll: self.roll[i],
            })
            .collect()
    }
}

/// Nominal spring forces `F_j,0` (switch `ab_nominal_force`, §3.3, §11.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NominalForce {
    /// Static balance at the nominal attitude with zero actuation (recommended default):
    /// `F_f,0 + F_r,0 = F`, `d_f F_f,0 − d_r F_r,0 = e F` (+ the suspension torque, zero at the
    /// nominal state because `θ_s = θ0`).
    #[default]
    Balanced,
    /// Eqs. 4.11–4.12 as printed: `F_j,0 = k_j,nom·FH_nom` (12.7 mN in total, not
    /// moment-balanced; "balanced by the preload … at slightly smaller FH", §4.1.1).
    AsPrinted,
}

/// How a spring force follows from its PT-dependent stiffness (switch `ab_spring_law`;
/// docs/dynamics-3dof-air-bearing.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SpringLaw {
    /// `F = F_0 + ∫_ŝ^FH_nom k(s' + PT − ŝ) ds'` (recommended default, ours): the local
    /// stiffness `−∂F/∂ŝ` is `k(PT)` itself, so every equilibrium is stable. Equals the linear
    /// law to first order in the deflection.
    #[default]
    Integrated,
    /// Eqs. 4.11–4.14 as rebuilt: `F = F_0 + k(PT)·(FH_nom − ŝ)`. With `k` tied to PT its
    /// local stiffness `k − (FH_nom − ŝ)·dk/dPT` turns negative once the TFC has pushed the
    /// TE up a few nm: the calibrated push-back states (PT 7.79 nm at 12 nm) are unstable and
    /// a case drifts to another root.
    Linear,
}

/// Where `ΔF_AB` is applied (switch `ab_stiffening_point`, §3.3, §11.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StiffeningPoint {
    /// At the TFC centre `x_A = −l/2 + x_TFC` (recommended default, `w_r ≈ 0.988`).
    #[default]
    TfcCentre,
    /// At the COM, `x_A = 0` (eqs. 4.11–4.14).
    Com,
}

/// Which pole-tip FH sets `k(PT)` in a running case (switch `ab_stiffness_argument`;
/// docs/three-dof.md). Without a DMW (static solves) both are the same number.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StiffnessArgument {
    /// The read element's height over the disk under the rear spring (ours, the default): the
    /// surface the spring's own deflection is measured from, so a short-wavelength DMW
    /// component under the read element does not change the spring force by itself.
    #[default]
    RearSpringDisk,
    /// PT as printed (§4.1.4, Fig. 4.2): the read element's spacing over its own disk.
    PoleTip,
    /// The PT of the push-back calibration's static state at the current actuation
    /// ([`DeltaFabTable::pole_tip_at`]): `k` follows the AB's operating point set by the TFC, not
    /// the slider's instantaneous motion. The spring is then linear in its deflection with
    /// stiffness `k > 0` under either spring law, and the calibration is unchanged (at a static
    /// state the two PTs are the same number).
    StaticPoleTip,
}

/// What the roll spring `k_l` (and its damper `c_l`) acts on (switch `ab_roll_spring`;
/// docs/three-dof.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RollSpring {
    /// `φ − φ_d`, the roll relative to the disk under the two ABS halves (ours, the default):
    /// the ±y DMW tracks excite roll even when no feature is near the disk.
    #[default]
    DiskRelative,
    /// `φ` as printed (eq. 4.3: "the roll AB moments depend only on the roll angle φ").
    Absolute,
}

/// Parameters of the 3-DOF AB (Tables 4.1, 4.3; §11.3).
#[derive(Debug, Clone, PartialEq)]
pub struct ThreeDofAbParams {
    /// Slider block (l, l_w, l_t, m, J_θ).
    pub slider: SliderBody,
    /// `J_φ` (kg·m²).
    pub roll_inertia: f64,
    /// Preload `F`, `k`, `k_θ`, `ζ`, `ζ_θ`.
    pub suspension: Suspension,
    /// `k_φ` (N·m/rad).
    pub suspension_roll_stiffness: f64,
    /// `ζ_φ`.
    pub suspension_roll_damping_ratio: f64,
    /// Preload offset `e` along x from the COM (m), Table 4.1: 0.
    pub preload_offset: f64,
    /// `d_f` (m).
    pub front_arm: f64,
    /// `d_r` (m).
    pub rear_arm: f64,
    /// `FH_nom` (m): TE spacing of the nominal state; also the PT of the nominal stiffnesses.
    pub nominal_flying_height: f64,
    /// `FH_lim` (m): a spring whose equivalent spacing reaches it carries no force (AB lost).
    pub limit_flying_height: f64,
    /// `θ0` (rad).
    pub nominal_pitch: f64,
    /// AB natural frequencies versus PT.
    pub frequencies: AbFrequencyTable,
    /// `ζ_f`, `ζ_r`, `ζ_l`.
    pub front_damping_ratio: f64,
    pub rear_damping_ratio: f64,
    pub roll_damping_ratio: f64,
    /// Switch `ab_root_assignment`.
    pub root_assignment: RootAssignment,
    /// Switch `ab_nominal_force`.
    pub nominal_force: NominalForce,
    /// Switch `ab_spring_law`.
    pub spring_law: SpringLaw,
    /// Switch `ab_stiffening_point`.
    pub stiffening_point: StiffeningPoint,
    /// Switch `ab_stiffness_argument` (used by the running case; static solves have no DMW).
    pub stiffness_argument: StiffnessArgument,
    /// Switch `ab_roll_spring` (used by the running case).
    pub roll_spring: RollSpring,
    /// `x_TFC`: TFC (ellipsoid) centre from the TE (m).
    pub tfc_offset_from_te: f64,
    /// `a_TFC` (m).
    pub bulge_semi_width_x: f64,
    /// `b_TFC` (m): constant bulge height on the actuated base.
    pub bulge_height: f64,
    /// `x_R`: read element offset from the ellipsoid centre toward the LE (m).
    pub read_offset: f64,
}

impl Default for ThreeDofAbParams {
    /// §11.3 defaults.
    fn default() -> Self {
        let slider = SliderBody::from_density(1.23e-3, 0.70e-3, 0.30e-3, 4250.0);
        let roll_inertia = slider.mass * (slider.width.powi(2) + slider.thickness.powi(2)) / 12.0;
        ThreeDofAbParams {
            slider,
            roll_inertia,
            suspension: Suspension {
                preload: 14.7e-3,
                heave_stiffness: 10.0,
                pitch_stiffness: 5e-5,
                heave_damping_ratio: 0.02,
                pitch_damping_ratio: 0.02,
            },
            suspension_roll_stiffness: 5e-5,
            suspension_roll_damping_ratio: 0.02,
            preload_offset: 0.0,
            front_arm: 0.5 * slider.length,
            rear_arm: 0.5 * slider.length,
            nominal_flying_height: 11.0 * NM,
            limit_flying_height: 22.0 * NM,
            nominal_pitch: 100e-6,
            frequencies: AbFrequencyTable::default_table(),
            front_damping_ratio: 0.03,
            rear_damping_ratio: 0.03,
            roll_damping_ratio: 0.03,
            root_assignment: RootAssignment::StiffRear,
            nominal_force: NominalForce::Balanced,
            spring_law: SpringLaw::Integrated,
            stiffening_point: StiffeningPoint::TfcCentre,
            stiffness_argument: StiffnessArgument::RearSpringDisk,
            roll_spring: RollSpring::DiskRelative,
            tfc_offset_from_te: 15.0 * UM,
            bulge_semi_width_x: 5.0 * UM,
            bulge_height: 5.0 * NM,
            read_offset: 3.0 * UM,
        }
    }
}

impl ThreeDofAbParams {
    pub fn validate(&self) -> Result<()> {
        self.slider.validate()?;
        let s = &self.slider;
        require_positive("roll inertia J_φ (kg·m²)", self.roll_inertia)?;
        let u = &self.suspension;
        require_positive("preload F (N)", u.preload)?;
        require_non_negative("suspension stiffness k (N/m)", u.heave_stiffness)?;
        require_non_negative("suspension pitch stiffness k_θ", u.pitch_stiffness)?;
        require_non_negative(
            "suspension roll stiffness k_φ",
            self.suspension_roll_stiffness,
        )?;
        require_finite("preload offset e (m)", self.preload_offset)?;
        require_in("d_f (m)", self.front_arm, 1e-12, 0.5 * s.length, "m")?;
        require_in("d_r (m)", self.rear_arm, 1e-12, 0.5 * s.length, "m")?;
        require_in(
            "nominal flying height FH_nom (m)",
            self.nominal_flying_height,
            1e-10,
            1e-7,
            "m",
        )?;
        if !self.limit_flying_height.is_finite()
            || self.limit_flying_height <= self.nominal_flying_height
        {
            return Err(DynamicsError::parameter(
                "limit flying height FH_lim (m)",
                self.limit_flying_height,
                "must be finite and > FH_nom",
            ));
        }
        require_in(
            "nominal pitch θ0 (rad)",
            self.nominal_pitch,
            -1e-2,
            1e-2,
            "rad",
        )?;
        for (name, z) in [
            ("ζ_f", self.front_damping_ratio),
            ("ζ_r", self.rear_damping_ratio),
            ("ζ_l", self.roll_damping_ratio),
            ("ζ", u.heave_damping_ratio),
            ("ζ_θ", u.pitch_damping_ratio),
            ("ζ_φ", self.suspension_roll_damping_ratio),
        ] {
            require_in(name, z, 0.0, 1.0, "")?;
        }
        require_in("x_TFC (m)", self.tfc_offset_from_te, 0.0, s.length, "m")?;
        require_positive("a_TFC (m)", self.bulge_semi_width_x)?;
        require_non_negative("b_TFC (m)", self.bulge_height)?;
        if !(self.read_offset.is_finite() && self.read_offset.abs() < self.bulge_semi_width_x) {
            return Err(DynamicsError::parameter(
                "read element offset x_R (m)",
                self.read_offset,
                format!(
                    "must satisfy |x_R| < a_TFC = {:e} m",
                    self.bulge_semi_width_x
                ),
            ));
        }
        Ok(())
    }

    /// Heave–pitch body for the modal inversion (springs at `±d`, suspension; the preload
    /// offset `e` is not part of the inversion — exact for `e = 0`).
    pub fn heave_pitch_body(&self) -> HeavePitchBody {
        HeavePitchBody {
            mass: self.slider.mass,
            pitch_inertia: self.slider.pitch_inertia,
            front_arm: self.front_arm,
            rear_arm: self.rear_arm,
            suspension_heave_stiffness: self.suspension.heave_stiffness,
            suspension_pitch_stiffness: self.suspension.pitch_stiffness,
        }
    }
}

/// Damping coefficients (§3.4), constant in time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Damping3Dof {
    /// `c_f = 2ζ_f sqrt(k_f,nom m)` (N·s/m).
    pub front: f64,
    /// `c_r = 2ζ_r sqrt(k_r,nom m)` (N·s/m).
    pub rear: f64,
    /// `c_l = 2ζ_l sqrt(k_l J_φ)` (N·m·s/rad).
    pub roll: f64,
    /// `c = 2ζ sqrt(k m)` (N·s/m).
    pub heave: f64,
    /// `c_θ = 2ζ_θ sqrt(k_θ J_θ)`.
    pub pitch: f64,
    /// `c_φ = 2ζ_φ sqrt(k_φ J_φ)`.
    pub suspension_roll: f64,
}

/// `M`, `C`, `K` of eqs. 4.1–4.3 (`q = [z, θ − θ_s, φ]`); the AB springs are on the
/// right-hand side, the roll spring inside `K` and `C`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EomMatrices3Dof {
    pub mass: Matrix3<f64>,
    pub damping: Matrix3<f64>,
    pub stiffness: Matrix3<f64>,
}

/// Solid spacings and their rates at the two spring points (the caller evaluates them with the
/// DMW: `s_j = Z_{p_j} − z_d(x_j)`, `ṡ_j = Ż_{p_j} − ż_d(x_j)`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SpringSpacings {
    pub front: f64,
    pub rear: f64,
    pub front_rate: f64,
    pub rear_rate: f64,
}

/// AB spring forces and the generalised AB force vector of eq. 4.17.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AbForces3Dof {
    /// `F_a,f ≥ 0` (N, up).
    pub front: f64,
    /// `F_a,r ≥ 0` (N, up).
    pub rear: f64,
    /// `k_f(PT)`, `k_r(PT)` used.
    pub front_stiffness: f64,
    pub rear_stiffness: f64,
    /// Equivalent spacing `ŝ_j ≥ FH_lim`: the spring carries no force (AB lost). The caller
    /// decides whether this stops the run.
    pub front_lost: bool,
    pub rear_lost: bool,
    /// `f_a = [F_f + F_r − F, r_x,f F_f + r_x,r F_r − e cosθ F, M_φ]` (eq. 4.17, with the exact
    /// §1.1 roll moment `cosθ r_y F`; `r = R p`).
    pub generalised: Vector3<f64>,
}

impl AbForces3Dof {
    /// Either spring lost (the AB-lost state of Table 4.1).
    pub fn ab_lost(&self) -> bool {
        self.front_lost || self.rear_lost
    }
}

/// The assembled 3-DOF air bearing.
#[derive(Debug, Clone, PartialEq)]
pub struct ThreeDofAirBearing {
    params: ThreeDofAbParams,
    table: AbStiffnessTable,
    nominal_front: f64,
    nominal_rear: f64,
    roll_stiffness: f64,
    damping: Damping3Dof,
    nominal_forces: [f64; 2],
    weights: [f64; 2],
    spring_points: [Vector3<f64>; 2],
    /// Nominal solid spacing of each spring point `s_j,0`.
    nominal_spacings: [f64; 2],
    /// Read element height above the bulge bottom (m).
    read_height: f64,
}

/// Which static problem [`ThreeDofAirBearing::solve_static`] solves (roll 0, no DMW, no
/// interfacial forces).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StaticCondition {
    /// `ΔF_AB` given (N); unknowns heave and pitch.
    GivenForce(f64),
    /// The ABS point under the TFC centre (base plane, not the bulge) sits `rise` (m) above its
    /// nominal spacing; unknowns heave, pitch and `ΔF_AB`.
    TfcRise(f64),
}

/// A static equilibrium.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StaticState {
    /// Actuation `h_TFC` (m).
    pub actuation: f64,
    /// COM heave `z` from the nominal state (m).
    pub heave: f64,
    /// Pitch `θ` (rad).
    pub pitch: f64,
    /// `ΔF_AB` (N).
    pub delta_force: f64,
    /// Pole-tip FH `PT` (m).
    pub pole_tip: f64,
    /// Spacing rise of the ABS under the TFC centre (m).
    pub tfc_rise: f64,
    /// Spacing rise of the TE and LE ABS points (m).
    pub te_rise: f64,
    pub le_rise: f64,
    /// Spring forces (N).
    pub front_force: f64,
    pub rear_force: f64,
    /// Whether a spring reached `FH_lim` (only possible with `linear_springs = true`, else the
    /// solve fails).
    pub ab_lost: bool,
}

impl ThreeDofAirBearing {
    pub fn new(params: &ThreeDofAbParams) -> Result<Self> {
        params.validate()?;
        let p = params;
        let table = AbStiffnessTable::from_frequencies(
            &p.frequencies,
            &p.heave_pitch_body(),
            p.roll_inertia,
            p.suspension_roll_stiffness,
            p.root_assignment,
        )?;
        let fh = p.nominal_flying_height;
        let (kf, kr) = table.stiffness_at(fh);
        let k_l = table.roll_at(fh);
        let m = p.slider.mass;
        let u = &p.suspension;
        let damping = Damping3Dof {
            front: damping_coefficient(p.front_damping_ratio, kf, m)?,
            rear: damping_coefficient(p.rear_damping_ratio, kr, m)?,
            roll: damping_coefficient(p.roll_damping_ratio, k_l, p.roll_inertia)?,
            heave: damping_coefficient(u.heave_damping_ratio, u.heave_stiffness, m)?,
            pitch: damping_coefficient(
                u.pitch_damping_ratio,
                u.pitch_stiffness,
                p.slider.pitch_inertia,
            )?,
            suspension_roll: damping_coefficient(
                p.suspension_roll_damping_ratio,
                p.suspension_roll_stiffness,
                p.roll_inertia,
            )?,
        };
        let (df, dr) = (p.front_arm, p.rear_arm);
        let half_t = 0.5 * p.slider.thickness;
        let spring_points = [
            Vector3::new(df, 0.0, -half_t),
            Vector3::new(-dr, 0.0, -half_t),
        ];
        let f = u.preload;
        let nominal_forces = match p.nominal_force {
            NominalForce::Balanced => {
                // F_f + F_r = F, r_x,f F_f + r_x,r F_r = e cosθ0 F at the nominal attitude.
                let att = Attitude::pitch_only(p.nominal_pitch);
                let (xf, xr) = (
                    att.world_offset(&spring_points[0]).x,
                    att.world_offset(&spring_points[1]).x,
                );
                let moment = p.preload_offset * p.nominal_pitch.cos() * f;
                let ff = (moment - xr * f) / (xf - xr);
                [ff, f - ff]
            }
            NominalForce::AsPrinted => [kf * fh, kr * fh],
        };
        let x_a = match p.stiffening_point {
            StiffeningPoint::TfcCentre => -0.5 * p.slider.length + p.tfc_offset_from_te,
            StiffeningPoint::Com => 0.0,
        };
        let weights = [(x_a + dr) / (df + dr), (df - x_a) / (df + dr)];
        let mut ab = ThreeDofAirBearing {
            params: p.clone(),
            table,
            nominal_front: kf,
            nominal_rear: kr,
            roll_stiffness: k_l,
            damping,
            nominal_forces,
            weights,
            spring_points,
            nominal_spacings: [0.0; 2],
            read_height: p.bulge_height
                * (1.0 - (1.0 - (p.read_offset / p.bulge_semi_width_x).powi(2)).sqrt()),
        };
        ab.nominal_spacings = [
            ab.nominal_spacing(&spring_points[0]),
            ab.nominal_spacing(&spring_points[1]),
        ];
        Ok(ab)
    }

    pub fn params(&self) -> &ThreeDofAbParams {
        &self.params
    }

    pub fn stiffness_table(&self) -> &AbStiffnessTable {
        &self.table
    }

    /// `(k_f, k_r)` at pole-tip FH `PT` (m), log–log interpolation, clamped.
    pub fn stiffness_at(&self, pole_tip: f64) -> (f64, f64) {
        self.table.stiffness_at(pole_tip)
    }

    /// `(k_f,nom, k_r,nom)` at `PT = FH_nom`.
    pub fn nominal_stiffness(&self) -> (f64, f64) {
        (self.nominal_front, self.nominal_rear)
    }

    /// `k_l` (N·m/rad), at `PT = FH_nom`.
    pub fn roll_stiffness(&self) -> f64 {
        self.roll_stiffness
    }

    pub fn damping(&self) -> Damping3Dof {
        self.damping
    }

    /// `[F_f,0, F_r,0]` (N).
    pub fn nominal_forces(&self) -> [f64; 2] {
        self.nominal_forces
    }

    /// Lever-rule weights `[w_f, w_r]` of `ΔF_AB`.
    pub fn weights(&self) -> [f64; 2] {
        self.weights
    }

    /// Body points of the front and rear springs `p_f = (d_f, 0, −l_t/2)`, `p_r = (−d_r, 0, −l_t/2)`.
    pub fn spring_points(&self) -> [Vector3<f64>; 2] {
        self.spring_points
    }

    /// `[s_f,0, s_r,0]` (m).
    pub fn nominal_spring_spacings(&self) -> [f64; 2] {
        self.nominal_spacings
    }

    /// Read element height above the bulge bottom (m); 1.000 nm for Table 4.3.
    pub fn read_height_above_bulge_bottom(&self) -> f64 {
        self.read_height
    }

    /// Body point of the ABS (base plane) under the TFC centre.
    pub fn tfc_abs_point(&self) -> Vector3<f64> {
        let p = &self.params;
        Vector3::new(
            -0.5 * p.slider.length + p.tfc_offset_from_te,
            0.0,
            -0.5 * p.slider.thickness,
        )
    }

    /// Body point of the ABS (base plane) under the read element.
    pub fn read_abs_point(&self) -> Vector3<f64> {
        self.tfc_abs_point() + Vector3::new(self.params.read_offset, 0.0, 0.0)
    }

    /// Nominal solid spacing of a body point (no DMW): `FH_nom + n0·(p − p_TE)`,
    /// `p_TE = (−l/2, 0, −l_t/2)`, `n0 = (sinθ0, 0, cosθ0)`.
    pub fn nominal_spacing(&self, body_point: &Vector3<f64>) -> f64 {
        let p = &self.params;
        let te = Vector3::new(-0.5 * p.slider.length, 0.0, -0.5 * p.slider.thickness);
        p.nominal_flying_height
            + Attitude::pitch_only(p.nominal_pitch).altitude_offset(&(body_point - te))
    }

    /// Altitude change of a body point from the nominal state for COM heave `z` and the
    /// attitude: `z + (n(θ,φ) − n(θ0,0))·p`, with the differences written as products so that
    /// nothing is lost to cancellation (§5.3).
    pub fn spacing_increment(&self, body_point: &Vector3<f64>, heave: f64, att: &Attitude) -> f64 {
        let t0 = self.params.nominal_pitch;
        let (t, f) = (att.pitch, att.roll);
        let half_sum = 0.5 * (t + t0);
        let half_diff = 0.5 * (t - t0);
        let d_sin_t = 2.0 * half_sum.cos() * half_diff.sin();
        let d_cos_t = -2.0 * half_sum.sin() * half_diff.sin();
        let sf = f.sin();
        let one_minus_cf = 2.0 * (0.5 * f).sin().powi(2);
        // n = (sinθ, cosθ sinφ, cosθ cosφ); n_z − cosθ0 = (cosθ − cosθ0) − cosθ (1 − cosφ).
        let dn_z = d_cos_t - t.cos() * one_minus_cf;
        heave + d_sin_t * body_point.x + t.cos() * sf * body_point.y + dn_z * body_point.z
    }

    /// Pole-tip FH in a static state (no DMW): spacing of the ABS point under the read element
    /// minus `h_TFC − (read height above the bulge bottom)` (the bulge tilt is neglected).
    pub fn static_pole_tip(&self, heave: f64, att: &Attitude, actuation: f64) -> f64 {
        let p = self.read_abs_point();
        self.nominal_spacing(&p) + self.spacing_increment(&p, heave, att)
            - (actuation - self.read_height)
    }

    /// AB spring forces (eqs. 4.11–4.14 rebuilt, §3.3) and `f_a` (eq. 4.17).
    ///
    /// `F_a,j = F_j,0 + k_j(PT)(FH_nom − ŝ_j) + w_j ΔF_AB − c_j ṡ_j`, `ŝ_j = FH_nom + s_j − s_j,0`;
    /// `F_a,j = 0` when `ŝ_j ≥ FH_lim` (flagged), and `F_a,j ≥ 0`.
    pub fn forces(
        &self,
        spacings: &SpringSpacings,
        pole_tip: f64,
        delta_f_ab: f64,
        attitude: &Attitude,
    ) -> AbForces3Dof {
        self.forces_impl(spacings, pole_tip, delta_f_ab, attitude, true)
    }

    fn forces_impl(
        &self,
        sp: &SpringSpacings,
        pole_tip: f64,
        delta_f_ab: f64,
        attitude: &Attitude,
        limits: bool,
    ) -> AbForces3Dof {
        let (kf, kr) = self.table.stiffness_at(pole_tip);
        let fh = self.params.nominal_flying_height;
        let lim = self.params.limit_flying_height;
        let one = |j: usize, s: f64, rate: f64, k: f64, c: f64| -> (f64, bool) {
            let s_hat = fh + (s - self.nominal_spacings[j]);
            if limits && s_hat >= lim {
                return (0.0, true);
            }
            let elastic = match self.params.spring_law {
                SpringLaw::Linear => k * (fh - s_hat),
                SpringLaw::Integrated => {
                    // ∫_ŝ^FH k(s' + δ) ds' with δ = PT − ŝ (the PT this spring would see).
                    let delta = pole_tip - s_hat;
                    let at = |p: f64| self.table.stiffness_integral_of(j != 0, p);
                    at(fh + delta) - at(pole_tip)
                }
            };
            let f = self.nominal_forces[j] + elastic + self.weights[j] * delta_f_ab - c * rate;
            (if limits { f.max(0.0) } else { f }, false)
        };
        let (front, front_lost) = one(0, sp.front, sp.front_rate, kf, self.damping.front);
        let (rear, rear_lost) = one(1, sp.rear, sp.rear_rate, kr, self.damping.rear);
        let gf = generalised_force(
            &attitude.world_offset(&self.spring_points[0]),
            attitude,
            front,
            0.0,
        );
        let gr = generalised_force(
            &attitude.world_offset(&self.spring_points[1]),
            attitude,
            rear,
            0.0,
        );
        let u = &self.params.suspension;
        AbForces3Dof {
            front,
            rear,
            front_stiffness: kf,
            rear_stiffness: kr,
            front_lost,
            rear_lost,
            generalised: Vector3::new(
                front + rear - u.preload,
                gf.pitch_moment + gr.pitch_moment
                    - self.params.preload_offset * attitude.pitch.cos() * u.preload,
                gf.roll_moment + gr.roll_moment,
            ),
        }
    }

    /// `M`, `C`, `K` of eqs. 4.1–4.3.
    pub fn eom_matrices(&self) -> EomMatrices3Dof {
        let p = &self.params;
        let u = &p.suspension;
        let e = p.preload_offset;
        let d = &self.damping;
        let (k, c) = (u.heave_stiffness, d.heave);
        EomMatrices3Dof {
            mass: Matrix3::from_diagonal(&Vector3::new(
                p.slider.mass,
                p.slider.pitch_inertia,
                p.roll_inertia,
            )),
            damping: Matrix3::new(
                c,
                e * c,
                0.0,
                e * c,
                e * e * c + d.pitch,
                0.0,
                0.0,
                0.0,
                d.suspension_roll + d.roll,
            ),
            stiffness: Matrix3::new(
                k,
                e * k,
                0.0,
                e * k,
                e * e * k + u.pitch_stiffness,
                0.0,
                0.0,
                0.0,
                p.suspension_roll_stiffness + self.roll_stiffness,
            ),
        }
    }

    /// Linearised stiffness of the whole AB + suspension at `PT`: `K` of eq. 4.3 plus the two
    /// AB springs at `x = +d_f`, `−d_r` (small-angle lever arms).
    pub fn linear_stiffness_matrix(&self, pole_tip: f64) -> Matrix3<f64> {
        let (kf, kr) = self.table.stiffness_at(pole_tip);
        let (df, dr) = (self.params.front_arm, self.params.rear_arm);
        let mut k = self.eom_matrices().stiffness;
        k[(0, 0)] += kf + kr;
        k[(0, 1)] += df * kf - dr * kr;
        k[(1, 0)] += df * kf - dr * kr;
        k[(1, 1)] += df * df * kf + dr * dr * kr;
        k
    }

    /// Undamped natural frequencies (Hz, ascending) of the linear AB at `PT`: symmetric eigen
    /// of `M^{-1/2} K M^{-1/2}` (nalgebra).
    pub fn modal_frequencies(&self, pole_tip: f64) -> Result<[f64; 3]> {
        let m = self.eom_matrices().mass;
        let inv = Matrix3::from_diagonal(&m.diagonal().map(|v| 1.0 / v.sqrt()));
        let reduced = inv * self.linear_stiffness_matrix(pole_tip) * inv;
        let eig = nalgebra::SymmetricEigen::new(reduced);
        let mut f = [0.0; 3];
        for (i, &lambda) in eig.eigenvalues.iter().enumerate() {
            if lambda.is_nan() || lambda <= 0.0 {
                return Err(DynamicsError::Numerical(format!(
                    "linear AB stiffness not positive definite (eigenvalue {lambda:e})"
                )));
            }
            f[i] = lambda.sqrt() / (2.0 * std::f64::consts::PI);
        }
        f.sort_by(|a, b| a.total_cmp(b));
        Ok(f)
    }

    /// Tangent heave–pitch stiffness `K_t = −∂f/∂(z, θ)` of the AB springs with the suspension
    /// at a static state (same actuation and `ΔF_AB`, roll 0, no DMW), by central differences
    /// of the force law this AB uses (spring law, nominal forces, stiffening point). With the
    /// linear spring law it carries the `(FH_nom − ŝ)·dk/dPT` term that
    /// [`Self::linear_stiffness_matrix`] leaves out; a negative eigenvalue of
    /// [`Self::heave_pitch_eigenvalues`] means the state diverges (docs/model-form.md).
    pub fn tangent_stiffness(&self, state: &StaticState) -> nalgebra::Matrix2<f64> {
        let (dz, dt) = (1e-12, 1e-9);
        // Under the static-PT argument `k` does not follow the motion.
        let frozen = (self.params.stiffness_argument == StiffnessArgument::StaticPoleTip)
            .then_some(state.pole_tip);
        let r = |z: f64, th: f64| {
            self.static_state_at(state.actuation, z, th, state.delta_force, false, frozen)
                .1
        };
        let (z, th) = (state.heave, state.pitch);
        let col_z = (r(z + dz, th) - r(z - dz, th)) / (2.0 * dz);
        let col_t = (r(z, th + dt) - r(z, th - dt)) / (2.0 * dt);
        nalgebra::Matrix2::new(-col_z.x, -col_t.x, -col_z.y, -col_t.y)
    }

    /// Eigenvalues `λ` of `M^{-1} K_t` for the heave–pitch pair at a static state
    /// ([`Self::tangent_stiffness`]; `K_t` need not be symmetric: `k(PT)` makes the force field
    /// non-conservative), ordered by real part. Undamped, `M q̈ + K_t q = 0` has solutions
    /// `exp(s t)` with `s² = −λ`: `λ` real and positive is a mode of `√λ/2π` Hz, real and
    /// negative a divergence growing as `exp(√−λ t)`, complex a flutter.
    pub fn heave_pitch_eigenvalues(&self, state: &StaticState) -> [nalgebra::Complex<f64>; 2] {
        let k = self.tangent_stiffness(state);
        let p = &self.params;
        let a = nalgebra::Matrix2::new(
            k[(0, 0)] / p.slider.mass,
            k[(0, 1)] / p.slider.mass,
            k[(1, 0)] / p.slider.pitch_inertia,
            k[(1, 1)] / p.slider.pitch_inertia,
        );
        let (tr, det) = (a.trace(), a.determinant());
        let disc = nalgebra::Complex::new(0.25 * tr * tr - det, 0.0).sqrt();
        let half = nalgebra::Complex::new(0.5 * tr, 0.0);
        let (l1, l2) = (half - disc, half + disc);
        if l1.re <= l2.re {
            [l1, l2]
        } else {
            [l2, l1]
        }
    }

    /// Static residual `[heave force, pitch moment, condition]` at unknowns
    /// `(z, θ, ΔF_AB)` (roll 0), and the state.
    fn static_state(
        &self,
        actuation: f64,
        heave: f64,
        pitch: f64,
        delta_force: f64,
        linear: bool,
    ) -> (StaticState, Vector3<f64>) {
        self.static_state_at(actuation, heave, pitch, delta_force, linear, None)
    }

    /// [`Self::static_state`] with `k` taken at `frozen_pole_tip` instead of the state's PT.
    fn static_state_at(
        &self,
        actuation: f64,
        heave: f64,
        pitch: f64,
        delta_force: f64,
        linear: bool,
        frozen_pole_tip: Option<f64>,
    ) -> (StaticState, Vector3<f64>) {
        let att = Attitude::pitch_only(pitch);
        let [pf, pr] = self.spring_points;
        let d_f = self.spacing_increment(&pf, heave, &att);
        let d_r = self.spacing_increment(&pr, heave, &att);
        let pole_tip =
            frozen_pole_tip.unwrap_or_else(|| self.static_pole_tip(heave, &att, actuation));
        let sp = SpringSpacings {
            front: self.nominal_spacings[0] + d_f,
            rear: self.nominal_spacings[1] + d_r,
            ..Default::default()
        };
        let f = self.forces_impl(&sp, pole_tip, delta_force, &att, !linear);
        let p = &self.params;
        let u = &p.suspension;
        let e = p.preload_offset;
        let dth = pitch - p.nominal_pitch;
        let suspension = Vector3::new(
            u.heave_stiffness * (heave + e * dth),
            u.pitch_stiffness * dth + e * u.heave_stiffness * (heave + e * dth),
            0.0,
        );
        let r = f.generalised - suspension;
        let le = Vector3::new(0.5 * p.slider.length, 0.0, -0.5 * p.slider.thickness);
        let te = Vector3::new(-0.5 * p.slider.length, 0.0, -0.5 * p.slider.thickness);
        let state = StaticState {
            actuation,
            heave,
            pitch,
            delta_force,
            pole_tip,
            tfc_rise: self.spacing_increment(&self.tfc_abs_point(), heave, &att),
            te_rise: self.spacing_increment(&te, heave, &att),
            le_rise: self.spacing_increment(&le, heave, &att),
            front_force: f.front,
            rear_force: f.rear,
            ab_lost: f.ab_lost() || {
                let lim = p.limit_flying_height - p.nominal_flying_height;
                d_f >= lim || d_r >= lim
            },
        };
        (state, Vector3::new(r.x, r.y, 0.0))
    }

    /// Static equilibrium at actuation `h_TFC` (roll 0, no DMW, no interfacial forces): heave
    /// and pitch balance with the preload, the PT-dependent springs and the suspension, plus
    /// the [`StaticCondition`]. Newton on a scaled 3×3 system (finite-difference Jacobian,
    /// backtracking) from `start` (or the nominal state). `linear_springs` drops the
    /// `FH_lim` cut-off and the `F ≥ 0` clip (to quantify states the AB could not hold);
    /// otherwise a state that loses a spring has no equilibrium and is an error.
    pub fn solve_static(
        &self,
        actuation: f64,
        condition: StaticCondition,
        start: Option<&StaticState>,
        linear_springs: bool,
    ) -> Result<StaticState> {
        require_finite("actuation h_TFC (m)", actuation)?;
        let p = &self.params;
        // Scaled unknowns: z/nm, (θ − θ0)/µrad, ΔF/mN; residuals: mN, mN·(l/2), nm.
        let (zs, ts, fs) = (NM, 1e-6, 1e-3);
        let ms = 1e-3 * 0.5 * p.slider.length;
        let residual = |y: &Vector3<f64>| -> (StaticState, Vector3<f64>) {
            let (z, th) = (y.x * zs, p.nominal_pitch + y.y * ts);
            let df = y.z * fs;
            let (state, r) = self.static_state(actuation, z, th, df, linear_springs);
            let c = match condition {
                StaticCondition::GivenForce(f) => (df - f) / fs,
                StaticCondition::TfcRise(rise) => (state.tfc_rise - rise) / NM,
            };
            (state, Vector3::new(r.x / fs, r.y / ms, c))
        };
        let mut y = match start {
            Some(s) => Vector3::new(
                s.heave / zs,
                (s.pitch - p.nominal_pitch) / ts,
                s.delta_force / fs,
            ),
            None => Vector3::zeros(),
        };
        if let StaticCondition::GivenForce(f) = condition {
            require_finite("ΔF_AB (N)", f)?;
            y.z = f / fs;
        }
        if let StaticCondition::TfcRise(rise) = condition {
            require_finite("TFC push-back rise (m)", rise)?;
        }
        let (mut state, mut r) = residual(&y);
        let h = 1e-6;
        for _ in 0..100 {
            if r.norm() < 1e-11 {
                return self.accept(state, linear_springs);
            }
            let mut jac = Matrix3::zeros();
            for i in 0..3 {
                let mut yp = y;
                let mut ym = y;
                yp[i] += h;
                ym[i] -= h;
                let col = (residual(&yp).1 - residual(&ym).1) / (2.0 * h);
                jac.set_column(i, &col);
            }
            let step = jac.lu().solve(&(-r)).ok_or_else(|| {
                DynamicsError::Numerical(format!(
                    "static 3-DOF AB solve at h_TFC = {:.3} nm: singular Jacobian \
                     (a spring lost or clipped?)",
                    actuation / NM
                ))
            })?;
            let mut lambda = 1.0;
            loop {
                let yn = y + step * lambda;
                let (sn, rn) = residual(&yn);
                if rn.norm() < r.norm() || lambda < 1e-6 {
                    y = yn;
                    state = sn;
                    r = rn;
                    break;
                }
                lambda *= 0.5;
            }
            if step.norm() * lambda < 1e-13 && r.norm() < 1e-8 {
                return self.accept(state, linear_springs);
            }
        }
        Err(DynamicsError::Numerical(format!(
            "static 3-DOF AB solve at h_TFC = {:.3} nm did not converge (residual {:e}; \
             lost spring: {})",
            actuation / NM,
            r.norm(),
            state.ab_lost
        )))
    }

    fn accept(&self, state: StaticState, linear: bool) -> Result<StaticState> {
        if state.ab_lost && !linear {
            return Err(DynamicsError::Numerical(format!(
                "static 3-DOF AB state at h_TFC = {:.3} nm loses a spring (FH_lim)",
                state.actuation / NM
            )));
        }
        Ok(state)
    }
}

/// Push-back curve `ΔFH(h_TFC)` (switch `pushback_curve`, §3.3): piecewise linear through the
/// points, extended linearly with the end segments.
#[derive(Debug, Clone, PartialEq)]
pub struct PushbackCurve {
    actuation: Vec<f64>,
    rise: Vec<f64>,
}

impl PushbackCurve {
    /// A table of `(h_TFC, ΔFH)` points (m): at least 2, `h` strictly increasing, finite.
    pub fn from_points(points: &[(f64, f64)]) -> Result<Self> {
        if points.len() < 2 {
            return Err(DynamicsError::parameter(
                "push-back curve points",
                points.len() as f64,
                "needs at least 2 points",
            ));
        }
        for (i, &(h, r)) in points.iter().enumerate() {
            require_finite("push-back h_TFC (m)", h)?;
            require_finite("push-back ΔFH (m)", r)?;
            if i > 0 && h <= points[i - 1].0 {
                return Err(DynamicsError::parameter(
                    "push-back h_TFC (m)",
                    h,
                    "must increase strictly",
                ));
            }
        }
        Ok(PushbackCurve {
            actuation: points.iter().map(|p| p.0).collect(),
            rise: points.iter().map(|p| p.1).collect(),
        })
    }

    /// `ΔFH = factor·h` (default factor 0.5).
    pub fn linear(factor: f64) -> Result<Self> {
        require_finite("push-back factor", factor)?;
        Self::from_points(&[(0.0, 0.0), (25.0 * NM, factor * 25.0 * NM)])
    }

    /// Validation variant: `0.5 h` up to 12 nm, `6 + 0.25 (h − 12)` nm above.
    pub fn flattened() -> Self {
        Self::from_points(&[
            (0.0, 0.0),
            (12.0 * NM, 6.0 * NM),
            (25.0 * NM, (6.0 + 0.25 * 13.0) * NM),
        ])
        .expect("static table")
    }

    /// `ΔFH(h)` (m).
    pub fn rise_at(&self, actuation: f64) -> f64 {
        let n = self.actuation.len();
        let i = self
            .actuation
            .partition_point(|&g| g <= actuation)
            .clamp(1, n - 1)
            - 1;
        let (h0, h1) = (self.actuation[i], self.actuation[i + 1]);
        self.rise[i] + (actuation - h0) / (h1 - h0) * (self.rise[i + 1] - self.rise[i])
    }
}

impl Default for PushbackCurve {
    fn default() -> Self {
        Self::linear(0.5).expect("finite factor")
    }
}

/// `ΔF_AB(h_TFC)` calibrated against a push-back curve (§3.3).
#[derive(Debug, Clone, PartialEq)]
pub struct DeltaFabTable {
    points: Vec<StaticState>,
    ab_lost_at: Option<f64>,
}

impl DeltaFabTable {
    /// For `h_TFC = 0, step, …, h_max`, solve the static problem with the condition that the
    /// ABS under the TFC centre rises by `ΔFH(h) − ΔFH(0)` relative to the unactuated static
    /// state (`ΔF_AB = 0`, `h = 0`; this is the nominal state under `Balanced` nominal forces).
    /// Continuation from the previous grid point.
    ///
    /// If at some grid point the push-back can only be had by lifting a spring to `FH_lim`
    /// (AB lost — with the linear `0.5·h` curve the TE spring reaches 22 nm at h ≈ 21.9 nm), the
    /// table stops at the last feasible point and [`Self::ab_lost_at`] names the first
    /// infeasible actuation; any other solver failure is an error.
    pub fn calibrate(
        ab: &ThreeDofAirBearing,
        curve: &PushbackCurve,
        max_actuation: f64,
        step: f64,
    ) -> Result<Self> {
        require_positive("calibration step (m)", step)?;
        require_positive("calibration max actuation (m)", max_actuation)?;
        let n = (max_actuation / step - 1e-9).ceil() as usize;
        if n > 100_000 {
            return Err(DynamicsError::parameter(
                "calibration step (m)",
                step,
                "gives more than 100 000 grid points",
            ));
        }
        let base = ab.solve_static(0.0, StaticCondition::GivenForce(0.0), None, false)?;
        let mut points: Vec<StaticState> = Vec::with_capacity(n + 1);
        let mut prev = base;
        for i in 0..=n {
            let h = (i as f64 * step).min(max_actuation);
            let target = base.tfc_rise + curve.rise_at(h) - curve.rise_at(0.0);
            let cond = StaticCondition::TfcRise(target);
            match ab.solve_static(h, cond, Some(&prev), false) {
                Ok(s) => {
                    points.push(s);
                    prev = s;
                }
                Err(e) => {
                    // AB lost (a genuine end of the table) or a solver failure?
                    let lost = ab
                        .solve_static(h, cond, Some(&prev), true)
                        .map(|s| s.ab_lost)
                        .unwrap_or(false);
                    if lost && !points.is_empty() {
                        return Ok(DeltaFabTable {
                            points,
                            ab_lost_at: Some(h),
                        });
                    }
                    return Err(e);
                }
            }
        }
        Ok(DeltaFabTable {
            points,
            ab_lost_at: None,
        })
    }

    /// Defaults: 0…25 nm in 0.5 nm steps.
    pub fn calibrate_default(ab: &ThreeDofAirBearing, curve: &PushbackCurve) -> Result<Self> {
        Self::calibrate(ab, curve, 25.0 * NM, 0.5 * NM)
    }

    /// The solved static states, one per grid point.
    pub fn points(&self) -> &[StaticState] {
        &self.points
    }

    /// First grid actuation at which the push-back would lose a spring (the table ends before).
    pub fn ab_lost_at(&self) -> Option<f64> {
        self.ab_lost_at
    }

    /// Largest calibrated actuation (m).
    pub fn max_actuation(&self) -> f64 {
        self.points[self.points.len() - 1].actuation
    }

    /// `ΔF_AB(h)` (N), linear between grid points, clamped to the end values outside (check
    /// [`Self::max_actuation`] / [`Self::ab_lost_at`] before running beyond the table).
    pub fn delta_force_at(&self, actuation: f64) -> f64 {
        self.interpolate(actuation, |s| s.delta_force)
    }

    /// The static states' pole-tip FH at `h` (m), interpolated like [`Self::delta_force_at`]
    /// (the argument of `k` under `StiffnessArgument::StaticPoleTip`).
    pub fn pole_tip_at(&self, actuation: f64) -> f64 {
        self.interpolate(actuation, |s| s.pole_tip)
    }

    fn interpolate(&self, actuation: f64, value: impl Fn(&StaticState) -> f64) -> f64 {
        let p = &self.points;
        if actuation.is_nan() || actuation <= p[0].actuation {
            return value(&p[0]);
        }
        let last = p.len() - 1;
        if actuation >= p[last].actuation {
            return value(&p[last]);
        }
        let i = p.partition_point(|s| s.actuation <= actuation) - 1;
        let (a, b) = (&p[i], &p[i + 1]);
        value(a) + (actuation - a.actuation) / (b.actuation - a.actuation) * (value(b) - value(a))
    }
}

#[cfg(test)]
mod tests;
