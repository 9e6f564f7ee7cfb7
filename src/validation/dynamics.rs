//! `hdi validate` rows of the 2-DOF models (Tables 2.1–2.4; docs/validation.md): geometry and AB
//! (class G: must pass), kinematic landmarks (class K), and the landmarks that depend on
//! dropped inputs (class D), computed live with the same code the simulation stage runs.
//! Class-D rows here are the spec defaults (not reproducible: they show hdi's number and why,
//! docs/validation.md); the same targets after the §12 calibration are the area `calibration`
//! (`[calibrate.*]` fits of the pipeline, docs/calibration.md).

use super::{Row, Tolerance};
use crate::contact::isbl::{IsblModel, IsblParams};
use crate::contact::lookup::IsblLookup;
use crate::dmw::excitation_tracks::{synthetic_dmw, Excitation};
use crate::dynamics::air_bearing::heave_pitch_modes;
use crate::dynamics::params::{improved_2dof, initial_2dof, Model2Dof};
use crate::dynamics::two_dof::{DmwInput, SimOptions, TwoDofCase};
use rayon::prelude::*;

#[allow(clippy::too_many_arguments)]
fn row(
    source: &str,
    quantity: &str,
    unit: &str,
    target: f64,
    ours: f64,
    tolerance: Tolerance,
    reproducible: bool,
    variant: &str,
    note: &str,
) -> Row {
    Row {
        source: source.into(),
        quantity: quantity.into(),
        unit: unit.into(),
        target,
        ours,
        tolerance,
        reproducible,
        variant: variant.into(),
        note: note.into(),
    }
}

fn or_nan<T, E>(r: Result<T, E>, f: impl Fn(T) -> f64) -> f64 {
    r.map(f).unwrap_or(f64::NAN)
}

/// Geometry and air-bearing rows (class G).
fn geometry_rows() -> Vec<Row> {
    let mut rows = Vec::new();
    let initial = initial_2dof();
    let improved = improved_2dof();
    let variant = "closed-form POC and section at θ0 (dynamics.md §2.2, §2.4)";
    for (h, area, radius) in [
        (5.0, 124.0, 1506.0),
        (10.0, 68.0, 827.0),
        (15.0, 47.0, 567.0),
    ] {
        let s = initial.nominal_contact_area(h * 1e-9);
        rows.push(row(
            "dynamics §12.2 #1 [seed §2.1.1]",
            &format!("initial model: nominal contact area at {h} nm (1.8σ cut)"),
            "μm²",
            area,
            or_nan(s.clone(), |s| s.area * 1e12),
            Tolerance::Relative(0.02),
            true,
            variant,
            "",
        ));
        rows.push(row(
            "dynamics §12.2 #2 [seed §2.1.1]",
            &format!("initial model: protrusion curvature (chord radius) at {h} nm"),
            "μm",
            radius,
            or_nan(s, |s| s.chord_radius_x() * 1e6),
            Tolerance::Relative(0.01),
            true,
            variant,
            "",
        ));
    }
    rows.push(row(
        "dynamics §12.2 #3 [seed §2.1.3]",
        "initial model: nominal contact area at 11 nm",
        "μm²",
        62.0,
        or_nan(initial.nominal_contact_area(11e-9), |s| s.area * 1e12),
        Tolerance::Relative(0.02),
        true,
        variant,
        "",
    ));
    let s12 = improved.nominal_contact_area(12e-9);
    rows.push(row(
        "dynamics §12.2 #4 [seed §2.2.1]",
        "improved model: nominal contact area at 12 nm (3σ cut, σ = 0.5 nm)",
        "μm²",
        55.0,
        or_nan(s12.clone(), |s| s.area * 1e12),
        Tolerance::Relative(0.02),
        true,
        variant,
        "",
    ));
    rows.push(row(
        "dynamics §12.2 #5 [seed §2.2.1]",
        "improved model: composite radius of the section at 12 nm",
        "mm",
        1.37,
        or_nan(s12, |s| s.composite_radius() * 1e3),
        Tolerance::Relative(0.02),
        true,
        variant,
        "",
    ));
    rows.extend(air_bearing_mode_rows(&improved));
    rows.push(row(
        "dynamics §12.2 #14 [seed §2.1.3]",
        "initial interface: plasticity index (E*/H)√(σ/R)",
        "1",
        0.52,
        {
            let p = IsblParams::initial_2dof();
            (p.composite_modulus() / p.hardness) * (p.sigma / p.summit_radius).sqrt()
        },
        Tolerance::Absolute(0.02),
        true,
        "E = 280 GPa, ν = 0.25, H = 13 GPa, σ = 0.87 nm, R = 0.43 μm",
        "",
    ));
    rows
}

/// Modal round trip (§3.1, §10 item 7): the assembled 2×2 AB model has the two target
/// frequencies.
fn air_bearing_mode_rows(improved: &Model2Dof) -> Vec<Row> {
    let mut rows = Vec::new();
    let modes = (|| {
        let ab = improved.air_bearing_model().ok()?;
        let susp = improved.suspension_coefficients().ok()?;
        let m = ab.eom_matrices(improved.slider.mass, improved.slider.pitch_inertia, &susp);
        let mut k = m.stiffness;
        // The rear spring sits on the right-hand side of eq. 2.13: add it for the eigenproblem.
        let (d, kr) = (ab.half_length, ab.rear_stiffness_nominal);
        k[(0, 0)] += kr;
        k[(0, 1)] -= d * kr;
        k[(1, 0)] -= d * kr;
        k[(1, 1)] += d * d * kr;
        heave_pitch_modes(&m.mass, &k).ok()
    })();
    for (i, target) in [(0usize, 110.0), (1, 300.0)] {
        rows.push(row(
            "dynamics §3.1, §10 item 7",
            &format!("AB mode {} frequency from the inverted springs", i + 1),
            "kHz",
            target,
            modes.map_or(f64::NAN, |m| m[i].frequency_hz / 1e3),
            Tolerance::Relative(0.005),
            true,
            "stiff rear spring (§3.1)",
            "the 110/300 kHz inputs are assumptions (§3.2); the row checks the inversion",
        ));
    }
    rows
}

/// Steady metrics of one improved-2-DOF case.
#[derive(Clone, Copy)]
struct CaseMetrics {
    /// Mean clearance (m).
    clearance: f64,
    /// FHM/BV (%).
    fhm_percent: f64,
    /// Share of time in solid contact (%).
    solid_contact_percent: f64,
    /// Mean contact force F_c (N).
    contact_force: f64,
    /// Mean friction Q (N).
    friction: f64,
    /// Mean real contact area A_r (m²).
    real_area: f64,
    /// Friction coefficient μ = Q̄/F̄_c.
    mu: f64,
}

/// Steady metrics of one improved-2-DOF case.
fn case(
    model: &Model2Dof,
    isbl: &IsblLookup,
    h: f64,
    dmw: Option<DmwInput>,
) -> Option<CaseMetrics> {
    case_with(model, isbl, h, dmw, false)
}

/// As [`case`], optionally starting from the static equilibrium.
fn case_with(
    model: &Model2Dof,
    isbl: &IsblLookup,
    h: f64,
    dmw: Option<DmwInput>,
    static_init: bool,
) -> Option<CaseMetrics> {
    let options = SimOptions {
        static_init,
        ..SimOptions::default()
    };
    let c = TwoDofCase::new(model, h, isbl, dmw, options).ok()?;
    let hist = c.run().ok()?;
    let m = hist
        .metrics(&crate::dynamics::metrics::CaseParams::improved_2dof())
        .ok()?;
    let contact = m.contact.as_ref();
    Some(CaseMetrics {
        clearance: m.clearance_m.mean,
        fhm_percent: m.vibration.percent,
        solid_contact_percent: m.percent_solid_contact,
        contact_force: contact.map_or(0.0, |c| c.contact_force_n.mean),
        friction: contact.map_or(0.0, |c| c.friction_n.mean),
        real_area: contact.map_or(0.0, |c| c.real_area_m2.mean),
        mu: contact
            .and_then(|c| c.friction_coefficient_ratio_of_means)
            .unwrap_or(f64::NAN),
    })
}

/// One actuation (nm) and its case's metrics, if the case ran.
type Actuated = (f64, Option<CaseMetrics>);

/// The first actuation whose case has solid contact (the touchdown), NaN if none.
fn touchdown<'a>(cases: impl IntoIterator<Item = &'a Actuated>) -> f64 {
    cases
        .into_iter()
        .find(|(_, m)| m.is_some_and(|m| m.solid_contact_percent > 0.0))
        .map_or(f64::NAN, |(h, _)| *h)
}

const NM: f64 = 1e-9;

/// Why the class-D rows of the improved model are not reproducible.
const CLASS_D_NOTE: &str = "class D: depends on dropped inputs (DMW spectrum, AB damping, rear \
                            stiffening β, Δγ, ε, ζ_c); spec defaults here, the fitted knobs in \
                            area `calibration` (docs/calibration.md)";
const CLASS_D_VARIANT: &str = "improved 2-DOF, spec defaults, synthetic DMW σ = 1 nm (seed 1)";

/// Kinematic (K) and dropped-input (D) landmarks of the improved model (§12.2 rows 16–24).
fn dynamics_rows(isbl: &IsblLookup, track: &Excitation) -> Vec<Row> {
    let model = improved_2dof();
    let mut rows = flying_rows(&model, isbl);
    rows.extend(dmw_landmark_rows(&model, isbl, track));
    rows.extend(twelve_nm_rows(&model, isbl, track));
    rows
}

/// The least-squares slope of `(actuation, clearance)` points, NaN below two points.
fn approach_slope(pts: &[(f64, f64)]) -> f64 {
    if pts.len() >= 2 {
        let n = pts.len() as f64;
        let (sx, sy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
        let (mx, my) = (sx / n, sy / n);
        let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
        sxy / sxx
    } else {
        f64::NAN
    }
}

/// Class K without DMW (§12.2 #18, #21): the static flying line and its slope.
fn flying_rows(model: &Model2Dof, isbl: &IsblLookup) -> Vec<Row> {
    let flying: Vec<Actuated> = [4.0, 5.0, 6.0, 7.0, 8.5]
        .par_iter()
        .map(|&h| (h, case(model, isbl, h * NM, None)))
        .collect();
    let c85 = flying
        .iter()
        .find(|(h, _)| *h == 8.5)
        .and_then(|(_, m)| *m)
        .map_or(f64::NAN, |m| m.clearance / NM);
    let variant = "improved 2-DOF, spec defaults, no DMW";
    let pts: Vec<(f64, f64)> = flying
        .iter()
        .filter_map(|(h, m)| m.map(|m| (*h, m.clearance / NM)))
        .collect();
    vec![
        row(
            "dynamics §12.2 #18 (K) [seed §2.2.2]",
            "steady clearance at 8.5 nm",
            "nm",
            2.54,
            c85,
            Tolerance::Absolute(0.05),
            true,
            variant,
            "",
        ),
        row(
            "dynamics §12.2 #18 (K), §1.2",
            "head–media spacing at 8.5 nm (c − 2T0)",
            "nm",
            1.0,
            c85 - 1.5,
            Tolerance::Absolute(0.1),
            true,
            variant,
            "",
        ),
        row(
            "dynamics §12.2 #21 (K) [seed §2.2.2]",
            "approach slope A (flying, 4–8.5 nm)",
            "1",
            -1.0,
            approach_slope(&pts),
            Tolerance::Absolute(0.02),
            true,
            variant,
            "",
        ),
    ]
}

/// Class D with the spec's synthetic DMW (σ 1 nm, §6), before calibration (§12.2 #16, #18,
/// #19): touchdown, FHM at 8.5 nm and the clearance at 9.5 nm.
fn dmw_landmark_rows(model: &Model2Dof, isbl: &IsblLookup, track: &Excitation) -> Vec<Row> {
    let dmw = || Some(dmw_input(track));
    let actuations: Vec<f64> = (0..=15).map(|i| 9.0 + 0.2 * i as f64).collect();
    let mut scan: Vec<Actuated> = actuations
        .par_iter()
        .map(|&h| (h, case(model, isbl, h * NM, dmw())))
        .collect();
    scan.sort_by(|a, b| a.0.total_cmp(&b.0));
    let fhm85 = case(model, isbl, 8.5 * NM, dmw());
    vec![
        row(
            "dynamics §12.2 #16 (D) [seed §2.2.1]",
            "touchdown (first actuation with solid contact, 0.2 nm steps)",
            "nm",
            9.7,
            touchdown(&scan),
            Tolerance::Absolute(0.2),
            false,
            CLASS_D_VARIANT,
            CLASS_D_NOTE,
        ),
        row(
            "dynamics §12.2 #18 (D) [seed §2.2.2]",
            "FHM at 8.5 nm",
            "%",
            8.2,
            fhm85.map_or(f64::NAN, |m| m.fhm_percent),
            Tolerance::Relative(0.5),
            false,
            CLASS_D_VARIANT,
            CLASS_D_NOTE,
        ),
        row(
            "dynamics §12.2 #19 (D) [seed §2.2.2]",
            "steady clearance at 9.5 nm",
            "nm",
            0.67,
            case(model, isbl, 9.5 * NM, dmw()).map_or(f64::NAN, |m| m.clearance / NM),
            Tolerance::Absolute(0.2),
            false,
            CLASS_D_VARIANT,
            CLASS_D_NOTE,
        ),
    ]
}

/// One 12 nm steady-contact landmark of §12.2 #24: a case metric in the row's unit.
struct Landmark {
    quantity: &'static str,
    unit: &'static str,
    target: f64,
    metric: fn(&CaseMetrics) -> f64,
    /// Factor from the metric's SI unit to `unit` (negative: the interference is −c̄).
    scale: f64,
    tolerance: Tolerance,
}

/// The 12 nm steady-contact landmarks (§12.2 #24, class D) of one synthetic-DMW case.
fn twelve_nm_rows(model: &Model2Dof, isbl: &IsblLookup, track: &Excitation) -> Vec<Row> {
    let c12 = case(model, isbl, 12.0 * NM, Some(dmw_input(track)));
    let landmarks = [
        Landmark {
            quantity: "12 nm steady interference (−c̄)",
            unit: "nm",
            target: 0.34,
            metric: |m| m.clearance,
            scale: -1e9,
            tolerance: Tolerance::Absolute(0.15),
        },
        Landmark {
            quantity: "12 nm mean contact force F_c",
            unit: "mN",
            target: 1.63,
            metric: |m| m.contact_force,
            scale: 1e3,
            tolerance: Tolerance::Relative(0.5),
        },
        Landmark {
            quantity: "12 nm mean friction Q",
            unit: "mN",
            target: 2.43,
            metric: |m| m.friction,
            scale: 1e3,
            tolerance: Tolerance::Relative(0.5),
        },
        Landmark {
            quantity: "12 nm mean real contact area",
            unit: "μm²",
            target: 0.36,
            metric: |m| m.real_area,
            scale: 1e12,
            tolerance: Tolerance::Relative(0.5),
        },
        Landmark {
            quantity: "12 nm friction coefficient Q̄/F̄_c",
            unit: "1",
            target: 1.49,
            metric: |m| m.mu,
            scale: 1.0,
            tolerance: Tolerance::Relative(0.2),
        },
    ];
    landmarks
        .into_iter()
        .map(|l| {
            row(
                "dynamics §12.2 #24 (D) [seed §2.2.2]",
                l.quantity,
                l.unit,
                l.target,
                c12.map_or(f64::NAN, |m| (l.metric)(&m) * l.scale),
                l.tolerance,
                false,
                CLASS_D_VARIANT,
                CLASS_D_NOTE,
            )
        })
        .collect()
}

/// Initial 2-DOF model landmarks (§12.2 rows 7–9), static init, synthetic DMW.
fn initial_model_rows(isbl: &IsblLookup, track: &Excitation) -> Vec<Row> {
    let mut rows = Vec::new();
    let model = initial_2dof();
    let dmw = || Some(dmw_input(track));
    let nm = 1e-9;
    let actuations: Vec<f64> = [4.0, 5.0, 6.0, 7.0]
        .into_iter()
        .chain((0..=10).map(|i| 8.0 + 0.2 * i as f64))
        .collect();
    let mut cases: Vec<Actuated> = actuations
        .par_iter()
        .map(|&h| (h, case_with(&model, isbl, h * nm, dmw(), true)))
        .collect();
    cases.sort_by(|a, b| a.0.total_cmp(&b.0));
    let at = |h: f64| {
        cases
            .iter()
            .find(|(x, _)| (x - h).abs() < 1e-9)
            .and_then(|(_, m)| *m)
    };
    let variant = "initial 2-DOF (bulge-centre anchor, 1.2σ criterion), static init, synthetic DMW";
    for (h, target) in [(4.0, 5.8), (7.0, 2.8)] {
        rows.push(row(
            "dynamics §12.2 #8 (K) [seed §2.1.3]",
            &format!("initial model: steady clearance at {h} nm"),
            "nm",
            target,
            at(h).map_or(f64::NAN, |m| m.clearance / nm),
            Tolerance::Absolute(0.2),
            true,
            variant,
            "",
        ));
    }
    let fhm: Vec<f64> = [4.0, 5.0, 6.0, 7.0]
        .iter()
        .filter_map(|h| at(*h).map(|m| m.fhm_percent))
        .collect();
    rows.push(row(
        "dynamics §12.2 #9 (D) [seed §2.1.3]",
        "initial model: mean FHM at 4–7 nm",
        "%",
        12.5,
        fhm.iter().sum::<f64>() / fhm.len().max(1) as f64,
        Tolerance::Relative(0.5),
        false,
        variant,
        "class D: DMW high-frequency content and AB damping were dropped (docs/validation.md)",
    ));
    let td = touchdown(&cases);
    rows.push(row(
        "dynamics §12.2 #7 (D) [seed §2.1.1]",
        "initial model: touchdown (0.2 nm steps)",
        "nm",
        9.8,
        td,
        Tolerance::Absolute(0.2),
        false,
        variant,
        "class D: ISBL adhesion inputs, AB damping and the DMW were dropped; the dissertation \
         calibrated n to 9.8 nm (S1c); `[calibrate]` with model initial_2dof fits n \
         (docs/calibration.md)",
    ));
    rows
}

/// The optimised design of §2.3 (S2o, §12.2 row 26), w_TFC = 50 µm [assumption].
fn optimised_rows(isbl: &IsblLookup, track: &Excitation) -> Vec<Row> {
    let mut rows = Vec::new();
    let Ok(bulge) = crate::dynamics::params::optimised_bulge(50e-6) else {
        return rows;
    };
    let model = improved_2dof().with_bulge(bulge);
    let dmw = || Some(dmw_input(track));
    let nm = 1e-9;
    let actuations: Vec<f64> = std::iter::once(8.6)
        .chain((0..=8).map(|i| 9.0 + 0.2 * i as f64))
        .collect();
    let mut cases: Vec<Actuated> = actuations
        .par_iter()
        .map(|&h| (h, case_with(&model, isbl, h * nm, dmw(), true)))
        .collect();
    cases.sort_by(|a, b| a.0.total_cmp(&b.0));
    let variant = "optimised bulge a = 4.86 µm, x = 6.35 µm, w = 50 µm (assumed), static init, \
                   synthetic DMW";
    let c86 = cases
        .iter()
        .find(|(h, _)| (*h - 8.6).abs() < 1e-9)
        .and_then(|(_, m)| *m)
        .map_or(f64::NAN, |m| m.clearance / nm);
    rows.push(row(
        "dynamics §12.2 #26 (D) [seed §2.3.2]",
        "optimised design: clearance at 8.6 nm (critical point)",
        "nm",
        2.23,
        c86,
        Tolerance::Absolute(0.15),
        false,
        variant,
        "class D: w_TFC and the adhesion inputs were dropped (docs/validation.md)",
    ));
    let td = touchdown(cases.iter().filter(|(h, _)| *h >= 9.0));
    rows.push(row(
        "dynamics §12.2 #26 (D) [seed §2.3.2]",
        "optimised design: touchdown (0.2 nm steps)",
        "nm",
        9.9,
        td,
        Tolerance::Absolute(0.2),
        false,
        variant,
        "class D: w_TFC and the adhesion inputs were dropped (docs/validation.md)",
    ));
    rows
}

/// Track 1 of a synthetic excitation as the simulation's DMW input.
fn dmw_input(track: &Excitation) -> DmwInput<'_> {
    DmwInput {
        displacement: &track.displacement,
        velocity: &track.velocity,
        sample_rate: track.fs,
    }
}

fn interface(params: IsblParams) -> Result<IsblLookup, String> {
    IsblModel::new(params)
        .and_then(IsblLookup::build_standard)
        .map_err(|e| e.to_string())
}

/// Every 2-DOF row. The interfaces and the spec's synthetic DMW (σ 1 nm, seed 1, §6) are built
/// once for all landmark rows; if they cannot be built, one failing row says why.
pub fn rows() -> Vec<Row> {
    let mut rows = geometry_rows();
    let inputs = (|| {
        let improved = interface(IsblParams::improved_2dof())?;
        let initial = interface(IsblParams::initial_2dof())?;
        let track = synthetic_dmw(2.2e-3, 4e6, 1e-9, 1).map_err(|e| e.to_string())?;
        Ok::<_, String>((improved, initial, track))
    })();
    match inputs {
        Ok((improved, initial, track)) => {
            rows.extend(dynamics_rows(&improved, &track));
            rows.extend(initial_model_rows(&initial, &track));
            rows.extend(optimised_rows(&improved, &track));
        }
        Err(e) => rows.push(row(
            "dynamics §12",
            "simulation inputs (interfaces, synthetic DMW)",
            "-",
            f64::NAN,
            f64::NAN,
            Tolerance::Absolute(0.0),
            true,
            "-",
            &format!("could not be built: {e}"),
        )),
    }
    rows
}
