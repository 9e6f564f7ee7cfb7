//! `hdi validate` rows of the 2-DOF models (dissertation Chapter 2 and App. B;
//! docs/validation.md): targets `dyn-1` … `dyn-29` and `dyn-36` … `dyn-38`.
//!
//! Geometry and AB rows are closed forms (class G). The landmarks come from three sweeps
//! computed now with the library's code under one set of conventions (docs/conventions.md):
//! the synthetic DMW of `dmw::excitation_tracks::synthetic_dmw` (σ 1 nm, seed 1) under every
//! case, touchdown by `dynamics::touchdown::find_touchdown` (scan from 0 nm, refined to
//! 0.02 nm), the regimes, slopes, critical point and optimum of `dynamics::metrics`, μ / P_m /
//! τ as ratio of means (the mean of the instantaneous ratios in the note). Class-D rows carry,
//! beside this uncalibrated value, the calibrated one: the same extractor applied to the
//! pipeline's calibrated sweeps (`[simulate.improved_calibrated]`,
//! `[simulate.optimised_calibrated]`, run with `[calibrate.improved_calibration]`'s fitted
//! knobs on the shipped DMW record), read from the cache when the pipeline has run.
//! The App. B rows read the excitation studies' spectra from the cache; the chirp is computed.

use super::pipeline::{self, Cache, Stored};
use super::{Calibrated, Class, Ordering, Origin, Relation, Row, Tolerance};
use crate::contact::isbl::{IsblModel, IsblParams};
use crate::contact::lookup::IsblLookup;
use crate::core::cache::Store;
use crate::core::cases::{get_or_compute, CaseError};
use crate::dmw::excitation_tracks::{quadratic_chirp, synthetic_dmw, Excitation};
use crate::dynamics::air_bearing::heave_pitch_modes;
use crate::dynamics::metrics::{
    optimum_operating_point, slopes, CaseParams, Regime, SlopeAnalysis, SlopeParams, SweepPoint,
};
use crate::dynamics::params::{improved_2dof, initial_2dof, Model2Dof};
use crate::dynamics::touchdown::{find_touchdown, TouchdownSearch};
use crate::dynamics::two_dof::{DmwInput, SimOptions, TwoDofCase};
use rayon::prelude::*;
use serde_json::{json, Value};
use std::path::Path;
use std::sync::Mutex;

const NM: f64 = 1e-9;

/// Metres to nanometres.
fn nm(x: f64) -> f64 {
    x / NM
}
/// Bonded (= mobile) lubricant thickness T0 of the improved model (m).
const T0: f64 = 0.75e-9;

// ------------------------------------------------------------------------------------------
// Geometry (class G)
// ------------------------------------------------------------------------------------------

fn or_nan<T, E>(r: Result<T, E>, f: impl Fn(T) -> f64) -> f64 {
    r.map(f).unwrap_or(f64::NAN)
}

/// Geometry and air-bearing rows (class G; the AB round trip is a consistency check).
fn geometry_rows() -> Vec<Row> {
    let mut rows = Vec::new();
    let initial = initial_2dof();
    let improved = improved_2dof();
    let variant = "closed-form lowest point and section at θ0";
    let g = |id: &str, q: &str, unit: &str, target: f64, value: f64, tol: f64, r: &str| {
        Row::new(
            id,
            Class::G,
            q,
            unit,
            target,
            value,
            Tolerance::Relative(tol),
        )
        .reference(r)
        .variant(variant)
        .inputs("geometry only")
    };
    for (k, (h, area, radius)) in [
        (5.0, 124.0, 1506.0),
        (10.0, 68.0, 827.0),
        (15.0, 47.0, 567.0),
    ]
    .into_iter()
    .enumerate()
    {
        let s = initial.nominal_contact_area(h * NM);
        let sub = ["5nm", "10nm", "15nm"][k];
        rows.push(g(
            &format!("dyn-1.{sub}"),
            &format!("initial model: nominal contact area at {h} nm (1.8σ cut)"),
            "μm²",
            area,
            or_nan(s.clone(), |s| s.area * 1e12),
            0.01,
            "dissertation §2.1.1",
        ));
        rows.push(g(
            &format!("dyn-2.{sub}"),
            &format!("initial model: protrusion curvature (chord radius) at {h} nm"),
            "μm",
            radius,
            or_nan(s, |s| s.chord_radius_x() * 1e6),
            0.01,
            "dissertation §2.1.1",
        ));
    }
    rows.push(g(
        "dyn-3",
        "initial model: nominal contact area at 11 nm",
        "μm²",
        62.0,
        or_nan(initial.nominal_contact_area(11.0 * NM), |s| s.area * 1e12),
        0.01,
        "dissertation §2.1.3",
    ));
    let s12 = improved.nominal_contact_area(12.0 * NM);
    rows.push(g(
        "dyn-4",
        "improved model: nominal contact area at 12 nm (3σ cut, σ = 0.5 nm)",
        "μm²",
        55.0,
        or_nan(s12.clone(), |s| s.area * 1e12),
        0.01,
        "dissertation §2.2.1",
    ));
    let composite = or_nan(s12, |s| s.composite_radius());
    rows.push(g(
        "dyn-5",
        "improved model: composite radius of the section at 12 nm",
        "mm",
        1.37,
        composite * 1e3,
        0.02,
        "dissertation §2.2.1",
    ));
    // Hertz line contact at F_c = 1.63 mN, E = 280 GPa, ν = 0.25 (E* = E/(2(1 − ν²)) for two
    // equal DLC bodies): semi-width a = (3FR/(4E*))^(1/3) with the published R = 1.37 mm.
    let e_star = 280e9 / (2.0 * (1.0 - 0.25f64.powi(2)));
    let a = (3.0 * 1.63e-3 * 1.37e-3 / (4.0 * e_star)).cbrt();
    rows.push(g(
        "dyn-5.hertz",
        "Hertz semi-width at F_c = 1.63 mN, R = 1.37 mm (ν = 0.25)",
        "μm",
        2.26,
        a * 1e6,
        0.02,
        "dissertation §2.2.1",
    ));
    rows.push(g(
        "dyn-5.range",
        "contact area range upper end π(3a)²",
        "μm²",
        144.0,
        std::f64::consts::PI * (3.0 * a).powi(2) * 1e12,
        0.02,
        "dissertation §2.2.1",
    ));
    rows.extend(air_bearing_mode_rows(&improved));
    let p = IsblParams::initial_2dof();
    rows.push(
        Row::new(
            "dyn-14",
            Class::K,
            "initial interface: plasticity index (E*/H)√(σ/R)",
            "1",
            0.52,
            (p.composite_modulus() / p.hardness) * (p.sigma / p.summit_radius).sqrt(),
            Tolerance::Absolute(0.02),
        )
        .reference("dissertation §2.1.3")
        .variant("E = 280 GPa, ν = 0.25, H = 13 GPa, σ = 0.87 nm, R = 0.43 μm")
        .inputs("interface parameters only"),
    );
    rows
}

/// Modal round trip: the assembled 2×2 AB model has the two frequencies it was inverted from.
fn air_bearing_mode_rows(improved: &Model2Dof) -> Vec<Row> {
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
    [(0usize, 110.0, "ab2-pitch"), (1, 300.0, "ab2-normal")]
        .into_iter()
        .map(|(i, target, id)| {
            Row::new(
                id,
                Class::C,
                &format!("2-DOF AB mode {} frequency from the inverted springs", i + 1),
                "kHz",
                target,
                modes.map_or(f64::NAN, |m| m[i].frequency_hz / 1e3),
                Tolerance::Relative(0.005),
            )
            .reference("dissertation §2.2 (AB stiffness from modal frequencies)")
            .variant("stiff rear spring")
            .inputs("no DMW, no contact")
            .note("consistency check: the 110/300 kHz are inputs (assumed); the row checks the inversion")
        })
        .collect()
}

// ------------------------------------------------------------------------------------------
// Sweeps
// ------------------------------------------------------------------------------------------

/// The metrics of one case that the rows use (SI).
#[derive(Debug, Clone, Copy)]
struct Pt {
    h: f64,
    clearance: f64,
    fhm: f64,
    solid: f64,
    fc: f64,
    q: f64,
    ar: f64,
    adhesion: f64,
    /// Mean of the instantaneous ratios over the loaded samples.
    mu_inst: f64,
    pm_inst: f64,
    tau_inst: f64,
}

impl Pt {
    fn ratio(a: f64, b: f64) -> f64 {
        if b > 0.0 {
            a / b
        } else {
            f64::NAN
        }
    }
    /// Ratio of means μ = Q̄/F̄_c.
    fn mu(&self) -> f64 {
        Pt::ratio(self.q, self.fc)
    }
    fn pm(&self) -> f64 {
        Pt::ratio(self.fc, self.ar)
    }
    fn tau(&self) -> f64 {
        Pt::ratio(self.q, self.ar)
    }

    fn from_json(m: &Value) -> Option<Pt> {
        let f = |v: &Value| v.as_f64().unwrap_or(f64::NAN);
        Some(Pt {
            h: m["actuation_m"].as_f64()?,
            clearance: m["clearance_m"]["mean"].as_f64()?,
            fhm: f(&m["vibration_percent"]),
            solid: f(&m["percent_solid_contact"]),
            fc: m["contact_force_N"]["mean"].as_f64().unwrap_or(0.0),
            q: m["friction_N"]["mean"].as_f64().unwrap_or(0.0),
            ar: m["real_area_m2"]["mean"].as_f64().unwrap_or(0.0),
            adhesion: m["adhesion_N"]["mean"].as_f64().unwrap_or(0.0),
            mu_inst: f(&m["friction_coefficient"]),
            pm_inst: f(&m["mean_pressure_Pa"]),
            tau_inst: f(&m["shear_traction_Pa"]),
        })
    }
}

/// A sweep's cases (sorted by actuation), its touchdown and where it comes from.
struct Sweep {
    pts: Vec<Pt>,
    touchdown: Option<f64>,
    slopes: Option<SlopeAnalysis>,
    inputs: String,
    origin: Origin,
}

impl Sweep {
    fn new(mut pts: Vec<Pt>, touchdown: Option<f64>, inputs: String, origin: Origin) -> Sweep {
        pts.sort_by(|a, b| a.h.total_cmp(&b.h));
        pts.dedup_by(|a, b| (a.h - b.h).abs() < 1e-15);
        let points: Vec<SweepPoint> = pts.iter().map(sweep_point).collect();
        let slopes = slopes(&points, &SlopeParams::new(T0)).ok();
        Sweep {
            pts,
            touchdown,
            slopes,
            inputs,
            origin,
        }
    }

    /// The case at `h` (m), or the linear interpolation of a metric between its neighbours.
    fn at(&self, h: f64, metric: impl Fn(&Pt) -> f64) -> f64 {
        if let Some(p) = self.pts.iter().find(|p| (p.h - h).abs() < 1e-15) {
            return metric(p);
        }
        let i = self.pts.iter().position(|p| p.h > h);
        match i {
            Some(i) if i > 0 => {
                let (a, b) = (&self.pts[i - 1], &self.pts[i]);
                let w = (h - a.h) / (b.h - a.h);
                (1.0 - w) * metric(a) + w * metric(b)
            }
            _ => f64::NAN,
        }
    }

    fn case(&self, h: f64) -> Option<&Pt> {
        self.pts.iter().find(|p| (p.h - h).abs() < 1e-15)
    }

    /// The case at touchdown (the first touching actuation).
    fn touchdown_case(&self) -> Option<&Pt> {
        self.touchdown.and_then(|h| self.case(h))
    }

    fn regime(p: &Pt) -> Option<Regime> {
        Regime::classify(p.clearance, T0).ok()
    }

    /// The first actuation in regime `r` (`NaN` if none).
    fn first_in(&self, r: Regime) -> f64 {
        self.pts
            .iter()
            .find(|p| Sweep::regime(p) == Some(r))
            .map_or(f64::NAN, |p| p.h / NM)
    }

    /// The last flying actuation before the first non-flying one.
    fn last_flying(&self) -> f64 {
        let first = self
            .pts
            .iter()
            .position(|p| Sweep::regime(p) != Some(Regime::Flying));
        match first {
            Some(i) if i > 0 => self.pts[i - 1].h / NM,
            _ => f64::NAN,
        }
    }

    fn cp(&self) -> Option<(f64, f64)> {
        self.slopes
            .as_ref()
            .and_then(|s| s.critical_point)
            .map(|c| (c.actuation_m, c.clearance_m))
    }

    fn slope(&self, which: char) -> f64 {
        let s = match &self.slopes {
            Some(s) => s,
            None => return f64::NAN,
        };
        let l = match which {
            'A' => &s.a,
            'B' => &s.b,
            'C' => &s.c,
            _ => &s.d,
        };
        l.as_ref().map_or(f64::NAN, |l| l.slope)
    }

    /// The optimum operating point (least FHM between CP and touchdown).
    fn optimum(&self) -> Option<&Pt> {
        let points: Vec<SweepPoint> = self.pts.iter().map(sweep_point).collect();
        let cp = self.slopes.as_ref().and_then(|s| s.critical_point);
        let td = self
            .touchdown
            .and_then(|h| self.pts.iter().position(|p| p.h >= h - 1e-15));
        optimum_operating_point(&points, cp.as_ref(), td)
            .ok()
            .flatten()
            .map(|i| &self.pts[i])
    }
}

fn sweep_point(p: &Pt) -> SweepPoint {
    SweepPoint {
        actuation_m: p.h,
        mean_clearance_m: p.clearance,
        any_solid_contact: p.solid > 0.0,
        vibration_percent: p.fhm,
    }
}

/// The options of every computed case.
fn case_options(static_init: bool) -> SimOptions {
    SimOptions {
        static_init,
        ..SimOptions::default()
    }
}

/// Where a computed sweep's cases are kept between runs once the pipeline has run: its
/// content-addressed case store (`core::cases`), keyed by everything a case depends on, so
/// `hdi validate` after `hdi run` (whose report computed them) reads them back (docs/validation.md).
struct CaseStore<'a> {
    store: &'a Store,
    /// What every case of the sweep shares: model, interface, DMW content, metrics.
    inputs: Value,
}

/// Version of the stored validation cases: the slider cases' own (the same integrator and
/// metrics) and of the stored record's layout.
fn case_version() -> String {
    // validate-2dof-2: the stored cases' keys hold the model, options and interface as plain
    // JSON fields instead of Rust Debug strings (docs/architecture.md, "The cache, precisely").
    format!("validate-2dof-2/{}", crate::slider::case::MODEL_VERSION)
}

/// Why a stored validation case has no result.
#[derive(Debug)]
enum StoredCaseError {
    /// The case did not run (its row shows no value, as without the store).
    Failed,
    /// The store could not take the case (e.g. a read-only project).
    Store,
}

impl From<CaseError> for StoredCaseError {
    fn from(_: CaseError) -> Self {
        StoredCaseError::Store
    }
}

impl Pt {
    /// Every field's bits: the stored record gives back exactly the computed numbers (NaN
    /// and infinities too, which JSON numbers cannot carry).
    fn to_bits_json(self) -> Value {
        json!([
            self.h.to_bits(),
            self.clearance.to_bits(),
            self.fhm.to_bits(),
            self.solid.to_bits(),
            self.fc.to_bits(),
            self.q.to_bits(),
            self.ar.to_bits(),
            self.adhesion.to_bits(),
            self.mu_inst.to_bits(),
            self.pm_inst.to_bits(),
            self.tau_inst.to_bits(),
        ])
    }

    fn from_bits_json(v: &Value) -> Option<Pt> {
        let a = v.as_array()?;
        if a.len() != 11 {
            return None;
        }
        let f = |i: usize| a[i].as_u64().map(f64::from_bits);
        Some(Pt {
            h: f(0)?,
            clearance: f(1)?,
            fhm: f(2)?,
            solid: f(3)?,
            fc: f(4)?,
            q: f(5)?,
            ar: f(6)?,
            adhesion: f(7)?,
            mu_inst: f(8)?,
            pm_inst: f(9)?,
            tau_inst: f(10)?,
        })
    }
}

/// One case: from the case store when there is one and it has the case, else run now (and
/// stored). A case that fails is not stored: it fails again next time, as without the store.
fn run_case(
    model: &Model2Dof,
    isbl: &IsblLookup,
    h: f64,
    dmw: &Excitation,
    static_init: bool,
    cases: Option<&CaseStore>,
) -> Option<Pt> {
    let Some(cs) = cases else {
        return simulate_case(model, isbl, h, dmw, static_init);
    };
    let params = json!({
        "sweep": cs.inputs,
        "options": case_options(static_init),
        "actuation_m": h,
    });
    let mut computed = None;
    let entry = get_or_compute(cs.store, &case_version(), &params, |_| {
        let pt = simulate_case(model, isbl, h, dmw, static_init).ok_or(StoredCaseError::Failed)?;
        computed = Some(pt);
        Ok::<_, StoredCaseError>(pt.to_bits_json())
    });
    match entry {
        Ok(e) => Pt::from_bits_json(&e.result)
            .or(computed)
            .or_else(|| simulate_case(model, isbl, h, dmw, static_init)),
        Err(StoredCaseError::Failed) => None,
        // The store could not take it: the value is what was computed.
        Err(StoredCaseError::Store) => computed,
    }
}

/// One case, run now.
fn simulate_case(
    model: &Model2Dof,
    isbl: &IsblLookup,
    h: f64,
    dmw: &Excitation,
    static_init: bool,
) -> Option<Pt> {
    let options = case_options(static_init);
    let input = DmwInput {
        displacement: &dmw.displacement,
        velocity: &dmw.velocity,
        sample_rate: dmw.fs,
    };
    let hist = TwoDofCase::new(model, h, isbl, Some(input), options)
        .ok()?
        .run()
        .ok()?;
    let m = hist.metrics(&CaseParams::improved_2dof()).ok()?;
    let c = m.contact.as_ref();
    let mean_of = |s: Option<crate::dynamics::metrics::SeriesStats>| s.map_or(f64::NAN, |s| s.mean);
    Some(Pt {
        h,
        clearance: m.clearance_m.mean,
        fhm: m.vibration.percent,
        solid: m.percent_solid_contact,
        fc: c.map_or(0.0, |c| c.contact_force_n.mean),
        q: c.map_or(0.0, |c| c.friction_n.mean),
        ar: c.map_or(0.0, |c| c.real_area_m2.mean),
        adhesion: c.and_then(|c| c.adhesion_n).map_or(0.0, |a| a.mean),
        mu_inst: mean_of(c.and_then(|c| c.friction_coefficient)),
        pm_inst: mean_of(c.and_then(|c| c.mean_pressure_pa)),
        tau_inst: mean_of(c.and_then(|c| c.shear_traction_pa)),
    })
}

/// A sweep computed now: `grid` (nm) in parallel, then touchdown by the one convention (scan
/// from 0 nm on a 0.5 nm grid, the sweep's own cases reused, refined to 0.02 nm), then the
/// `extra` actuations (nm) relative to touchdown (e.g. TD + 0.2 nm).
// The case's inputs one by one, as `run_case` takes them, plus the sweep's own.
#[allow(clippy::too_many_arguments)]
fn run_sweep(
    model: &Model2Dof,
    isbl: &IsblLookup,
    dmw: &Excitation,
    static_init: bool,
    grid: &[f64],
    after_touchdown: &[f64],
    inputs: &str,
    cases: Option<&CaseStore>,
) -> Sweep {
    let done: Mutex<Vec<Pt>> = Mutex::new(
        grid.par_iter()
            .filter_map(|&h| run_case(model, isbl, h * NM, dmw, static_init, cases))
            .collect(),
    );
    let known: Vec<(f64, bool)> = done
        .lock()
        .map(|d| d.iter().map(|p| (p.h, p.solid > 0.0)).collect())
        .unwrap_or_default();
    let stop = grid.iter().cloned().fold(0.0, f64::max) * NM;
    // A fixed batch, so the refinement's cases (and the result) do not depend on the machine.
    let search = TouchdownSearch::convention(stop, 0.5 * NM, 3);
    let td = find_touchdown(&search, &known, |hs: &[f64]| {
        let pts: Vec<Option<Pt>> = hs
            .par_iter()
            .map(|&h| run_case(model, isbl, h, dmw, static_init, cases))
            .collect();
        let touches = pts
            .iter()
            .map(|p| p.is_some_and(|p| p.solid > 0.0))
            .collect();
        if let Ok(mut d) = done.lock() {
            d.extend(pts.into_iter().flatten());
        }
        Ok::<_, ()>(touches)
    })
    .ok()
    .and_then(|t| t.actuation);
    if let Some(t) = td {
        let extra: Vec<Pt> = after_touchdown
            .par_iter()
            .filter_map(|&dh| run_case(model, isbl, t + dh * NM, dmw, static_init, cases))
            .collect();
        if let Ok(mut d) = done.lock() {
            d.extend(extra);
        }
    }
    Sweep::new(
        done.into_inner().unwrap_or_default(),
        td,
        inputs.to_string(),
        Origin::Computed,
    )
}

/// A calibrated sweep of the pipeline, read from the cache.
fn cached_sweep(cache: &Cache, name: &str) -> Option<Sweep> {
    let Stored { result, origin, .. } = cache.current(name)?;
    // The up branch of a continuation sweep (the branches coincide at the shipped inputs;
    // docs/conventions.md); sweeps without branches have no `branch` field.
    let pts: Vec<Pt> = result["cases"]
        .as_array()?
        .iter()
        .filter(|c| c["branch"].as_str().is_none_or(|b| b == "up"))
        .filter_map(|c| Pt::from_json(&c["metrics"]))
        .collect();
    // The grid touchdown: the rows at touchdown need the full metrics of a touching case, and
    // the stage stores those for its grid cases only (its refined touchdown is in result.json).
    let td = result["sweep"]["touchdown_m"].as_f64();
    let knobs = result["calibrated_knobs"]
        .as_array()
        .map(|k| {
            k.iter()
                .map(|k| {
                    format!(
                        "{} = {:.4e}",
                        k["knob"].as_str().unwrap_or("?"),
                        k["value"].as_f64().unwrap_or(f64::NAN)
                    )
                })
                .collect::<Vec<_>>()
                .join(", ")
        })
        .unwrap_or_default();
    let inputs = match result["calibration"].as_str() {
        Some(name) => format!(
            "shipped DMW record, static start (up branch), calibration [calibrate.{name}] \
             ({knobs}); the stage's own 0.2 nm grid and grid touchdown"
        ),
        None => "shipped DMW record, static start (up branch), no calibration; the stage's own \
                 0.2 nm grid and grid touchdown"
            .to_string(),
    };
    Some(Sweep::new(pts, td, inputs, origin))
}

// ------------------------------------------------------------------------------------------
// Row builders
// ------------------------------------------------------------------------------------------

/// A class-D (or K) target evaluated on the uncalibrated sweep and, if present, the calibrated.
struct Target<'a> {
    id: &'a str,
    class: Class,
    quantity: &'a str,
    unit: &'a str,
    target: f64,
    tolerance: Tolerance,
    reference: &'a str,
    value: &'a dyn Fn(&Sweep) -> f64,
    note: &'a str,
}

/// The pipeline's sweeps a computed D row is also evaluated on, when the pipeline has run.
#[derive(Clone, Copy, Default)]
struct CachedSweeps<'a> {
    /// Uncalibrated, on the shipped DMW record (e.g. `improved_sweep`).
    record: Option<&'a Sweep>,
    /// The same with the fitted knobs (e.g. `improved_calibrated`).
    calibrated: Option<&'a Sweep>,
}

fn target_row(t: Target, sweep: &Sweep, cached: CachedSweeps, variant: &str) -> Row {
    let on = |s: Option<&Sweep>| {
        (t.class == Class::D)
            .then_some(s)
            .flatten()
            .map(|c| Calibrated {
                value: (t.value)(c),
                inputs: c.inputs.clone(),
                origin: c.origin.clone(),
            })
    };
    let (record, cal) = (on(cached.record), on(cached.calibrated));
    Row::new(
        t.id,
        t.class,
        t.quantity,
        t.unit,
        t.target,
        (t.value)(sweep),
        t.tolerance,
    )
    .reference(t.reference)
    .variant(variant)
    .inputs(&sweep.inputs)
    .origin(sweep.origin.clone())
    .record(record)
    .calibrated(cal)
    .note(t.note)
}

const D_NOTE: &str =
    "class D: depends on dropped inputs (DMW spectrum, AB damping, rear stiffening \
                      β, Δγ, ε, ζ_c)";

/// Improved model, dissertation geometry (S2, targets #16–#25).
fn improved_rows(
    s: &Sweep,
    cached: CachedSweeps,
    summits: &[SummitSweep],
    initial_geometry_fhm86: &mut f64,
) -> Vec<Row> {
    let variant = "improved 2-DOF, default inputs, eq. 2.16 interference-tangent contact force";
    let r = "dissertation §2.2.2";
    let abs = Tolerance::Absolute;
    let rel = Tolerance::Relative;
    let range = |lo, hi| Tolerance::Range { lo, hi };
    *initial_geometry_fhm86 = s.at(8.6 * NM, |p| p.fhm);
    let td_note = "touchdown: first actuation whose steady window reaches c < 0, scanned from \
                   0 nm, refined to 0.02 nm";
    let targets: Vec<Target> = vec![
        Target { id: "dyn-16", class: Class::D, quantity: "touchdown", unit: "nm", target: 9.7, tolerance: abs(0.2), reference: "dissertation §2.2.1", value: &|s| s.touchdown.map_or(f64::NAN, nm), note: td_note },
        Target { id: "dyn-16.solid", class: Class::D, quantity: "solid-contact share at touchdown", unit: "%", target: 0.3, tolerance: range(0.0, 1.0), reference: "dissertation §2.2.1", value: &|s| s.touchdown_case().map_or(f64::NAN, |p| p.solid), note: "" },
        Target { id: "dyn-16.clearance", class: Class::D, quantity: "steady clearance at touchdown", unit: "nm", target: 0.49, tolerance: abs(0.2), reference: "dissertation §2.2.1", value: &|s| s.touchdown_case().map_or(f64::NAN, |p| nm(p.clearance)), note: "" },
        Target { id: "dyn-17", class: Class::D, quantity: "critical point (intersection of slopes A and B)", unit: "nm", target: 8.6, tolerance: abs(0.2), reference: r, value: &|s| s.cp().map_or(f64::NAN, |c| nm(c.0)), note: "" },
        Target { id: "dyn-17.clearance", class: Class::D, quantity: "clearance at the critical point", unit: "nm", target: 2.39, tolerance: abs(0.15), reference: r, value: &|s| s.cp().map_or(f64::NAN, |c| nm(c.1)), note: "" },
        Target { id: "dyn-17.fhm", class: Class::D, quantity: "FHM maximum of the flying branch", unit: "%", target: 14.01, tolerance: rel(0.5), reference: r, value: &|s| s.pts.iter().filter(|p| Sweep::regime(p) == Some(Regime::Flying)).map(|p| p.fhm).fold(f64::NAN, f64::max), note: "" },
        Target { id: "dyn-18", class: Class::K, quantity: "steady clearance at 8.5 nm", unit: "nm", target: 2.54, tolerance: abs(0.05), reference: r, value: &|s| s.at(8.5 * NM, |p| nm(p.clearance)), note: "" },
        Target { id: "dyn-18.hms", class: Class::K, quantity: "head–media spacing at 8.5 nm (c̄ − 2T0)", unit: "nm", target: 1.0, tolerance: abs(0.1), reference: r, value: &|s| s.at(8.5 * NM, |p| nm(p.clearance - 2.0 * T0)), note: "" },
        Target { id: "dyn-18.magnetic", class: Class::K, quantity: "magnetic spacing at 8.5 nm (HMS + t + DLC 2 nm + 3σ)", unit: "nm", target: 6.0, tolerance: abs(0.1), reference: r, value: &|s| s.at(8.5 * NM, |p| nm(p.clearance - 2.0 * T0) + 1.5 + 2.0 + 1.5), note: "" },
        Target { id: "dyn-18.fhm", class: Class::D, quantity: "FHM at 8.5 nm", unit: "%", target: 8.2, tolerance: rel(0.5), reference: r, value: &|s| s.at(8.5 * NM, |p| p.fhm), note: D_NOTE },
        Target { id: "dyn-19", class: Class::D, quantity: "steady clearance at 9.5 nm", unit: "nm", target: 0.67, tolerance: abs(0.2), reference: r, value: &|s| s.at(9.5 * NM, |p| nm(p.clearance)), note: "structural miss at the default inputs (docs/validation.md)" },
        Target { id: "dyn-19.fhm", class: Class::D, quantity: "FHM at 9.5 nm", unit: "%", target: 9.29, tolerance: rel(0.5), reference: r, value: &|s| s.at(9.5 * NM, |p| p.fhm), note: "" },
        Target { id: "dyn-20.flying", class: Class::D, quantity: "regimes: last flying actuation", unit: "nm", target: 8.5, tolerance: abs(0.3), reference: r, value: &|s| s.last_flying(), note: "regime of the steady mean clearance: flying c̄ > 2T0, mobile T0 < c̄ ≤ 2T0, bonded 0 ≤ c̄ ≤ T0, solid c̄ < 0" },
        Target { id: "dyn-20.mobile", class: Class::D, quantity: "regimes: first mobile-lubricant-contact actuation", unit: "nm", target: 8.8, tolerance: abs(0.3), reference: r, value: &|s| s.first_in(Regime::MobileLubricantContact), note: "" },
        Target { id: "dyn-20.bonded", class: Class::D, quantity: "regimes: first bonded-lubricant-contact actuation", unit: "nm", target: 9.5, tolerance: abs(0.3), reference: r, value: &|s| s.first_in(Regime::BondedLubricantContact), note: "" },
        Target { id: "dyn-20.solid", class: Class::D, quantity: "regimes: first solid-contact actuation (c̄ < 0)", unit: "nm", target: 10.4, tolerance: abs(0.3), reference: r, value: &|s| s.first_in(Regime::SolidContact), note: "published: solid > 10.4 nm" },
        Target { id: "dyn-21", class: Class::K, quantity: "slope A (approach, flying)", unit: "1", target: -1.0, tolerance: abs(0.02), reference: r, value: &|s| s.slope('A'), note: "" },
        Target { id: "dyn-21.B", class: Class::D, quantity: "slope B (jump to contact)", unit: "1", target: -4.4, tolerance: rel(0.3), reference: r, value: &|s| s.slope('B'), note: "published |B| > 4 (2.39 → ~1.5 nm over 8.6 → 8.8 nm)" },
        Target { id: "dyn-21.C", class: Class::D, quantity: "slope C (lubricant contact) ≈ A", unit: "1", target: -1.0, tolerance: rel(0.3), reference: r, value: &|s| s.slope('C'), note: "" },
        Target { id: "dyn-21.D", class: Class::D, quantity: "slope D (solid contact)", unit: "1", target: -0.2, tolerance: rel(0.3), reference: r, value: &|s| s.slope('D'), note: "published 0 → −0.34 nm over 10.4 → 12 nm" },
        Target { id: "dyn-22", class: Class::D, quantity: "first actuation with 100 % solid contact", unit: "nm", target: 11.4, tolerance: abs(0.4), reference: r, value: &|s| s.pts.iter().find(|p| p.solid >= 100.0 - 1e-9).map_or(f64::NAN, |p| nm(p.h)), note: "" },
        Target { id: "dyn-22.force", class: Class::D, quantity: "mean contact force 0.2 nm above touchdown", unit: "μN", target: 1.0, tolerance: range(0.1, 10.0), reference: r, value: &|s| s.touchdown.map_or(f64::NAN, |t| s.at(t + 0.2 * NM, |p| p.fc * 1e6)), note: "" },
        Target { id: "dyn-23", class: Class::D, quantity: "mean shear traction τ at 9.8 nm (ratio of means)", unit: "GPa", target: 3.24, tolerance: rel(0.5), reference: r, value: &|s| s.at(9.8 * NM, |p| p.tau() * 1e-9), note: "no value when 9.8 nm is below hdi's touchdown (no solid contact there); τ = Q/A_r is the ISBL junction shear strength, a constant of the interface (dyn-24.shear)" },
        Target { id: "dyn-23.instantaneous", class: Class::D, quantity: "mean shear traction τ at 9.8 nm (mean of Q/A_r over loaded samples)", unit: "GPa", target: 3.24, tolerance: rel(0.5), reference: r, value: &|s| s.at(9.8 * NM, |p| p.tau_inst * 1e-9), note: "" },
        Target { id: "dyn-24", class: Class::D, quantity: "12 nm steady interference (−c̄)", unit: "nm", target: 0.34, tolerance: abs(0.15), reference: r, value: &|s| s.at(12.0 * NM, |p| -nm(p.clearance)), note: "structural miss: no calibration knob reaches it (docs/validation.md)" },
        Target { id: "dyn-24.force", class: Class::D, quantity: "12 nm mean contact force F_c", unit: "mN", target: 1.63, tolerance: rel(0.5), reference: r, value: &|s| s.at(12.0 * NM, |p| p.fc * 1e3), note: "" },
        Target { id: "dyn-24.friction", class: Class::D, quantity: "12 nm mean friction Q", unit: "mN", target: 2.43, tolerance: rel(0.5), reference: r, value: &|s| s.at(12.0 * NM, |p| p.q * 1e3), note: "" },
        Target { id: "dyn-24.mu", class: Class::D, quantity: "12 nm friction coefficient Q̄/F̄_c", unit: "1", target: 1.49, tolerance: range(1.2, 1.8), reference: r, value: &|s| s.at(12.0 * NM, |p| p.mu()), note: "" },
        Target { id: "dyn-24.mu_instantaneous", class: Class::D, quantity: "12 nm friction coefficient (mean of Q/F_c over loaded samples)", unit: "1", target: 1.49, tolerance: range(1.2, 1.8), reference: r, value: &|s| s.at(12.0 * NM, |p| p.mu_inst), note: "" },
        Target { id: "dyn-24.pressure", class: Class::D, quantity: "12 nm mean real pressure P_m = F̄_c/Ā_r", unit: "GPa", target: 4.47, tolerance: rel(0.5), reference: r, value: &|s| s.at(12.0 * NM, |p| p.pm() * 1e-9), note: "" },
        Target { id: "dyn-24.shear", class: Class::D, quantity: "12 nm shear traction τ = Q̄/Ā_r", unit: "GPa", target: 6.68, tolerance: rel(0.5), reference: r, value: &|s| s.at(12.0 * NM, |p| p.tau() * 1e-9), note: "τ = Q/A_r is the ISBL junction shear strength, a constant of the interface: every contact case gives the same value" },
        Target { id: "dyn-24.area", class: Class::D, quantity: "12 nm mean real contact area", unit: "μm²", target: 0.36, tolerance: rel(0.5), reference: r, value: &|s| s.at(12.0 * NM, |p| p.ar * 1e12), note: "" },
        Target { id: "dyn-24.adhesion", class: Class::D, quantity: "12 nm mean adhesion force", unit: "mN", target: 0.98, tolerance: rel(0.5), reference: r, value: &|s| s.at(12.0 * NM, |p| p.adhesion * 1e3), note: "" },
        Target { id: "dyn-25", class: Class::D, quantity: "maximum steady shear traction over the sweep (ratio of means)", unit: "GPa", target: 6.69, tolerance: rel(0.5), reference: r, value: &|s| s.pts.iter().map(|p| p.tau() * 1e-9).filter(|x| x.is_finite()).fold(f64::NAN, f64::max), note: "published at 12.2 nm, below the DLC yield 7.2 GPa; hdi's τ is the constant junction shear strength (dyn-24.shear)" },
    ];
    targets
        .into_iter()
        .map(|t| {
            let summit_values: Vec<(&SummitSweep, f64)> = if SUMMIT_VARIANT_ROWS.contains(&t.id) {
                summits.iter().map(|v| (v, (t.value)(&v.sweep))).collect()
            } else {
                Vec::new()
            };
            let published = PUBLISHED_AT.iter().find(|(id, _)| *id == t.id).map(|p| p.1);
            let row = target_row(t, s, cached, variant);
            let row = match published {
                Some(at) => row.published(at),
                None => row,
            };
            summit_values.into_iter().fold(row, |row, (v, x)| {
                row.with_variant(&v.name, x, &v.sweep.inputs, v.sweep.origin.clone())
            })
        })
        .collect()
}

/// The rows evaluated under the other summit distributions (docs/model-form.md, "Summit
/// heights"): the two structural misses and the 12 nm contact quantities.
const SUMMIT_VARIANT_ROWS: [&str; 8] = [
    "dyn-19",
    "dyn-24",
    "dyn-24.force",
    "dyn-24.friction",
    "dyn-24.mu",
    "dyn-24.pressure",
    "dyn-24.area",
    "dyn-24.adhesion",
];

/// Where the dissertation prints the targets of the rows this module states a basis for.
const PUBLISHED_AT: [(&str, &str); 8] = [
    (
        "dyn-19",
        "dissertation §2.2.2 (9.5 nm: clearance 0.67 nm, FHM 9.29 %)",
    ),
    (
        "dyn-24",
        "dissertation §2.2.2, Fig. 2.13(a) (12 nm: interference 0.34 nm)",
    ),
    (
        "dyn-24.force",
        "dissertation §2.2.2, Fig. 2.13(b) (12 nm: F_c 1.63 mN)",
    ),
    (
        "dyn-24.friction",
        "dissertation §2.2.2, Fig. 2.13(c) (12 nm: Q 2.43 mN)",
    ),
    (
        "dyn-24.mu",
        "dissertation §2.2.2, Fig. 2.14(a) (12 nm: μ 1.49)",
    ),
    (
        "dyn-24.pressure",
        "dissertation §2.2.2, Fig. 2.20(a) (12 nm: P_m 4.47 GPa)",
    ),
    (
        "dyn-24.area",
        "dissertation §2.2.2 (12 nm: real area 0.36 μm²)",
    ),
    (
        "dyn-24.adhesion",
        "dissertation §2.2.2 (12 nm: adhesion 0.98 mN)",
    ),
];

/// The improved model's 9.4, 9.6 and 12 nm cases (dyn-19 interpolates 9.5 nm between the
/// first two, as on the full grid) under one other summit distribution.
struct SummitSweep {
    name: String,
    sweep: Sweep,
}

/// The actuations (nm) of a [`SummitSweep`].
const SUMMIT_VARIANT_ACTUATIONS: [f64; 3] = [9.4, 9.6, 12.0];

/// Initial model (S1, targets #7–#15): bulge-centre anchor, 1.2σ criterion, static start.
fn initial_rows(s: &Sweep) -> Vec<Row> {
    let variant = "initial 2-DOF (bulge-centre anchor, 1.2σ contact criterion)";
    let r = "dissertation §2.1.3";
    let abs = Tolerance::Absolute;
    let rel = Tolerance::Relative;
    let range = |lo, hi| Tolerance::Range { lo, hi };
    let targets: Vec<Target> = vec![
        Target { id: "dyn-7", class: Class::D, quantity: "initial model: touchdown", unit: "nm", target: 9.8, tolerance: abs(0.2), reference: "dissertation §2.1.1", value: &|s| s.touchdown.map_or(f64::NAN, nm), note: "the dissertation calibrated n to 9.8 nm (S1c); structural miss at the default inputs (docs/validation.md)" },
        Target { id: "dyn-8.4nm", class: Class::K, quantity: "initial model: steady clearance at 4 nm", unit: "nm", target: 5.8, tolerance: abs(0.2), reference: r, value: &|s| s.at(4.0 * NM, |p| nm(p.clearance)), note: "" },
        Target { id: "dyn-8.7nm", class: Class::K, quantity: "initial model: steady clearance at 7 nm", unit: "nm", target: 2.8, tolerance: abs(0.2), reference: r, value: &|s| s.at(7.0 * NM, |p| nm(p.clearance)), note: "" },
        Target { id: "dyn-9", class: Class::D, quantity: "initial model: mean FHM at 4–7 nm", unit: "%", target: 12.5, tolerance: rel(0.5), reference: r, value: &|s| [4.0, 5.0, 6.0, 7.0].iter().map(|h| s.at(h * NM, |p| p.fhm)).sum::<f64>() / 4.0, note: "structural miss: the DMW's high-frequency content and AB damping were dropped" },
        Target { id: "dyn-11", class: Class::D, quantity: "initial model: 11 nm steady interference (−c̄)", unit: "nm", target: 0.58, tolerance: abs(0.2), reference: r, value: &|s| s.at(11.0 * NM, |p| -nm(p.clearance)), note: "" },
        Target { id: "dyn-11.bv", class: Class::D, quantity: "initial model: BV at 11 nm", unit: "%", target: 2.0, tolerance: range(0.0, 5.0), reference: r, value: &|s| s.at(11.0 * NM, |p| p.fhm), note: "published < 2 %" },
        Target { id: "dyn-12", class: Class::D, quantity: "initial model: 11 nm mean contact force F_c", unit: "mN", target: 1.0, tolerance: rel(0.5), reference: r, value: &|s| s.at(11.0 * NM, |p| p.fc * 1e3), note: "" },
        Target { id: "dyn-12.mu", class: Class::D, quantity: "initial model: 11 nm friction coefficient Q̄/F̄_c", unit: "1", target: 1.2, tolerance: range(1.0, 1.6), reference: r, value: &|s| s.at(11.0 * NM, |p| p.mu()), note: "" },
        Target { id: "dyn-13", class: Class::D, quantity: "initial model: 11 nm mean real pressure P_m (ratio of means)", unit: "MPa", target: 359.0, tolerance: rel(0.5), reference: r, value: &|s| s.at(11.0 * NM, |p| p.pm() * 1e-6), note: "" },
        Target { id: "dyn-13.instantaneous", class: Class::D, quantity: "initial model: 11 nm P_m (mean of F_c/A_r over loaded samples)", unit: "MPa", target: 359.0, tolerance: rel(0.5), reference: r, value: &|s| s.at(11.0 * NM, |p| p.pm_inst * 1e-6), note: "" },
        Target { id: "dyn-13.p0", class: Class::D, quantity: "initial model: 11 nm Hertz maximum pressure P_0 = 1.5 P_m", unit: "MPa", target: 540.0, tolerance: rel(0.5), reference: r, value: &|s| s.at(11.0 * NM, |p| 1.5 * p.pm() * 1e-6), note: "" },
        Target { id: "dyn-13.shear", class: Class::D, quantity: "initial model: 11 nm shear traction τ (ratio of means)", unit: "MPa", target: 438.0, tolerance: rel(0.5), reference: r, value: &|s| s.at(11.0 * NM, |p| p.tau() * 1e-6), note: "" },
        Target { id: "dyn-13.area", class: Class::D, quantity: "initial model: 11 nm mean real contact area", unit: "μm²", target: 2.7, tolerance: rel(0.5), reference: r, value: &|s| s.at(11.0 * NM, |p| p.ar * 1e12), note: "" },
        Target { id: "dyn-15", class: Class::D, quantity: "initial model: optimum operating point (least FHM between CP and touchdown)", unit: "nm", target: 9.0, tolerance: abs(0.3), reference: r, value: &|s| s.optimum().map_or(f64::NAN, |p| nm(p.h)), note: "" },
        Target { id: "dyn-15.fhm", class: Class::D, quantity: "initial model: FHM at the optimum", unit: "%", target: 9.0, tolerance: rel(0.5), reference: r, value: &|s| s.optimum().map_or(f64::NAN, |p| p.fhm), note: "" },
        Target { id: "dyn-15.clearance", class: Class::D, quantity: "initial model: clearance at the optimum", unit: "nm", target: 0.8, tolerance: abs(0.3), reference: r, value: &|s| s.optimum().map_or(f64::NAN, |p| nm(p.clearance)), note: "the text also prints 2.4 nm" },
    ];
    let mut rows: Vec<Row> = targets
        .into_iter()
        .map(|t| target_row(t, s, CachedSweeps::default(), variant))
        .collect();
    // #10: the BV peaks above 20 % between touchdown and 11 nm.
    let peak = s
        .pts
        .iter()
        .filter(|p| s.touchdown.is_some_and(|t| p.h >= t - 1e-15) && p.h <= 11.0 * NM + 1e-15)
        .map(|p| p.fhm)
        .fold(f64::NAN, f64::max);
    rows.push(
        Row::ordering(
            "dyn-10",
            "initial model: BV peaks above 20 % between touchdown and 11 nm",
            Ordering::new(
                Relation::Ascending,
                &[("published floor", 20.0), ("hdi peak BV", peak)],
            ),
        )
        .reference(r)
        .variant(variant)
        .inputs(&s.inputs),
    );
    rows
}

/// Optimised design (S2o, targets #26–#29), w_TFC = 50 µm (assumed).
fn optimised_rows(s: &Sweep, cached: CachedSweeps, dissertation_fhm86: f64) -> Vec<Row> {
    let variant = "improved 2-DOF, optimised bulge a = 4.86 µm, x = 6.35 µm, w = 50 µm (assumed)";
    let r = "dissertation §2.3.2";
    let abs = Tolerance::Absolute;
    let rel = Tolerance::Relative;
    let range = |lo, hi| Tolerance::Range { lo, hi };
    let targets: Vec<Target> = vec![
        Target { id: "dyn-26", class: Class::D, quantity: "optimised: critical point", unit: "nm", target: 8.6, tolerance: abs(0.2), reference: r, value: &|s| s.cp().map_or(f64::NAN, |c| nm(c.0)), note: "" },
        Target { id: "dyn-26.clearance", class: Class::D, quantity: "optimised: steady clearance at 8.6 nm", unit: "nm", target: 2.23, tolerance: abs(0.15), reference: r, value: &|s| s.at(8.6 * NM, |p| nm(p.clearance)), note: "" },
        Target { id: "dyn-26.lubricant", class: Class::D, quantity: "optimised: lubricant-contact onset (first non-flying actuation)", unit: "nm", target: 9.0, tolerance: abs(0.2), reference: r, value: &|s| s.pts.iter().find(|p| Sweep::regime(p) != Some(Regime::Flying)).map_or(f64::NAN, |p| nm(p.h)), note: "" },
        Target { id: "dyn-26.touchdown", class: Class::D, quantity: "optimised: touchdown", unit: "nm", target: 9.9, tolerance: abs(0.2), reference: r, value: &|s| s.touchdown.map_or(f64::NAN, nm), note: "" },
        Target { id: "dyn-26.td_clearance", class: Class::D, quantity: "optimised: steady clearance at touchdown", unit: "nm", target: 0.55, tolerance: abs(0.15), reference: r, value: &|s| s.touchdown_case().map_or(f64::NAN, |p| nm(p.clearance)), note: "" },
        Target { id: "dyn-27.fhm86", class: Class::D, quantity: "optimised: FHM at 8.6 nm", unit: "%", target: 6.67, tolerance: rel(0.5), reference: r, value: &|s| s.at(8.6 * NM, |p| p.fhm), note: "" },
        Target { id: "dyn-27.fhm_td", class: Class::D, quantity: "optimised: FHM at touchdown", unit: "%", target: 11.42, tolerance: rel(0.5), reference: r, value: &|s| s.touchdown_case().map_or(f64::NAN, |p| p.fhm), note: "" },
        Target { id: "dyn-27.optimum", class: Class::D, quantity: "optimised: optimum operating point", unit: "nm", target: 9.3, tolerance: abs(0.3), reference: r, value: &|s| s.optimum().map_or(f64::NAN, |p| nm(p.h)), note: "" },
        Target { id: "dyn-27.optimum_fhm", class: Class::D, quantity: "optimised: FHM at the optimum", unit: "%", target: 9.19, tolerance: rel(0.5), reference: r, value: &|s| s.optimum().map_or(f64::NAN, |p| p.fhm), note: "" },
        Target { id: "dyn-28", class: Class::K, quantity: "optimised: HMS at the critical point (c̄(8.6) − 2T0)", unit: "nm", target: 0.73, tolerance: abs(0.15), reference: r, value: &|s| s.at(8.6 * NM, |p| nm(p.clearance - 2.0 * T0)), note: "" },
        Target { id: "dyn-28.touchdown", class: Class::D, quantity: "optimised: HMS at touchdown (c̄_TD − 2T0)", unit: "nm", target: -0.95, tolerance: abs(0.15), reference: r, value: &|s| s.touchdown_case().map_or(f64::NAN, |p| nm(p.clearance - 2.0 * T0)), note: "class D here (not K): the touchdown clearance depends on the dropped inputs (dyn-26.td_clearance)" },
        Target { id: "dyn-29", class: Class::D, quantity: "optimised: 13 nm shear traction τ (ratio of means)", unit: "GPa", target: 6.64, tolerance: rel(0.5), reference: r, value: &|s| s.at(13.0 * NM, |p| p.tau() * 1e-9), note: "" },
        Target { id: "dyn-29.pressure", class: Class::D, quantity: "optimised: 13 nm mean real pressure P_m (ratio of means)", unit: "GPa", target: 4.88, tolerance: rel(0.5), reference: r, value: &|s| s.at(13.0 * NM, |p| p.pm() * 1e-9), note: "" },
        Target { id: "dyn-29.mu", class: Class::D, quantity: "optimised: 12 nm friction coefficient Q̄/F̄_c", unit: "1", target: 1.0, tolerance: range(1.0, f64::INFINITY), reference: r, value: &|s| s.at(12.0 * NM, |p| p.mu()), note: "published μ > 1" },
    ];
    let mut rows: Vec<Row> = targets
        .into_iter()
        .map(|t| target_row(t, s, cached, variant))
        .collect();
    rows.push(
        Row::ordering(
            "dyn-27",
            "optimised design: no FHM spike at the critical point (FHM(8.6 nm) below the dissertation geometry's)",
            Ordering::new(
                Relation::Ascending,
                &[
                    ("optimised", s.at(8.6 * NM, |p| p.fhm)),
                    ("dissertation geometry", dissertation_fhm86),
                ],
            ),
        )
        .reference(r)
        .variant(variant)
        .inputs(&s.inputs),
    );
    rows
}

// ------------------------------------------------------------------------------------------
// App. B: excitation studies (#36–#38)
// ------------------------------------------------------------------------------------------

/// Peaks (frequency Hz, amplitude) of a cached analysis.
fn peaks(a: &Stored) -> Vec<(f64, f64)> {
    // Amplitudes in the series' SI unit: `amplitude_m` for a heave (docs/schemas/analyze.json).
    let unit = a.result["summary"]["unit"]
        .as_str()
        .unwrap_or("m")
        .replace('/', "_");
    let key = format!("amplitude_{unit}");
    a.result["summary"]["peaks"]
        .as_array()
        .map(|p| {
            p.iter()
                .filter_map(|p| Some((p["frequency_Hz"].as_f64()?, p[key.as_str()].as_f64()?)))
                .collect()
        })
        .unwrap_or_default()
}

/// The peak nearest `f` (Hz).
fn nearest(p: &[(f64, f64)], f: f64) -> Option<(f64, f64)> {
    p.iter()
        .copied()
        .min_by(|a, b| (a.0 - f).abs().total_cmp(&(b.0 - f).abs()))
}

fn not_run(
    id: &str,
    class: Class,
    quantity: &str,
    unit: &str,
    target: f64,
    tol: Tolerance,
    instance: &str,
) -> Row {
    Row::new(id, class, quantity, unit, target, f64::NAN, tol).note(&format!(
        "needs the pipeline's `{instance}` result: run `hdi run` first"
    ))
}

fn app_b_rows(cache: Option<&Cache>) -> Vec<Row> {
    let mut rows = Vec::new();
    let r = "dissertation App. B";
    let tol = Tolerance::Relative(0.1);
    let get = |name: &str| cache.and_then(|c| c.current(name));
    // #36: the DMW line dominates the flying response; the AB modes in the free decay.
    match get("dmw_response") {
        Some(a) => {
            let p = peaks(&a);
            let top = p.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1));
            rows.push(
                Row::new(
                    "dyn-36",
                    Class::K,
                    "strongest line of the flying response to the DMW record",
                    "kHz",
                    10.7,
                    top.map_or(f64::NAN, |t| t.0 / 1e3),
                    tol,
                )
                .reference(r)
                .variant("improved 2-DOF, 5 nm, wavelet spectrum of the heave (0.5–2 ms)")
                .inputs("shipped DMW record (track 1), static start, no calibration")
                .origin(a.origin.clone()),
            );
        }
        None => rows.push(not_run(
            "dyn-36",
            Class::K,
            "strongest line of the flying response to the DMW record",
            "kHz",
            10.7,
            tol,
            "analysis.dmw_response",
        )),
    }
    match (get("still_response"), get("dmw_response")) {
        (Some(still), Some(flight)) => {
            let pitch = nearest(&peaks(&still), 110e3);
            let response = peaks(&flight);
            let normal = nearest(&response, 275e3);
            let pitch_in_response = nearest(&response, 110e3);
            rows.push(
                Row::new(
                    "dyn-36.pitch",
                    Class::K,
                    "1st pitch mode in the free decay",
                    "kHz",
                    110.0,
                    pitch.map_or(f64::NAN, |v| v.0 / 1e3),
                    tol,
                )
                .reference(r)
                .variant(
                    "improved 2-DOF, 5 nm, free decay after a 1 nm heave kick, wavelet spectrum",
                )
                .inputs("no DMW (zero excitation), kicked start, no calibration")
                .origin(still.origin.clone()),
            );
            rows.push(
                Row::new(
                    "dyn-36.normal",
                    Class::K,
                    "normal mode in the flying response to the DMW record",
                    "kHz",
                    275.0,
                    normal.map_or(f64::NAN, |v| v.0 / 1e3),
                    tol,
                )
                .reference(r)
                .variant("improved 2-DOF, 5 nm, wavelet spectrum of the heave (0.5–2 ms)")
                .inputs("shipped DMW record (track 1), static start, no calibration")
                .origin(flight.origin.clone())
                .note(
                    "the 2-DOF model has no roll mode (100 kHz: dyn-33.roll); the AB springs are \
                         inverted from 110/300 kHz (assumed inputs)",
                ),
            );
            rows.push(
                Row::ordering(
                    "dyn-36.amplitudes",
                    "flying response: the 1st pitch peak is stronger than the normal-mode peak",
                    Ordering::new(
                        Relation::Ascending,
                        &[
                            ("normal-mode peak", normal.map_or(f64::NAN, |v| v.1)),
                            (
                                "1st pitch peak",
                                pitch_in_response.map_or(f64::NAN, |v| v.1),
                            ),
                        ],
                    ),
                )
                .reference(r)
                .variant("improved 2-DOF, 5 nm, wavelet spectrum of the heave (0.5–2 ms)")
                .inputs("shipped DMW record (track 1), static start, no calibration")
                .origin(flight.origin.clone())
                .note(&format!(
                    "peaks nearest 110 and 275 kHz: {:.1} and {:.1} kHz",
                    pitch_in_response.map_or(f64::NAN, |v| v.0 / 1e3),
                    normal.map_or(f64::NAN, |v| v.0 / 1e3)
                )),
            );
        }
        _ => rows.push(not_run(
            "dyn-36.pitch",
            Class::K,
            "1st pitch mode in the free decay",
            "kHz",
            110.0,
            tol,
            "analysis.still_response and analysis.dmw_response",
        )),
    }
    // #37: periodic response to a sinusoid, fixed point without excitation.
    let class_of = |name: &str| {
        get(name).map(|a| {
            (
                a.result["summary"]["class"]
                    .as_str()
                    .unwrap_or("")
                    .to_string(),
                a.origin,
            )
        })
    };
    match (class_of("sine_response"), class_of("still_response")) {
        (Some((sine, o)), Some((still, _))) => rows.push(
            Row::ordering(
                "dyn-37",
                "sinusoid → periodic response; zero excitation → fixed point",
                Ordering::new(
                    Relation::AllTrue,
                    &[
                        ("sinusoid response periodic", f64::from(sine.starts_with("periodic"))),
                        ("zero-excitation response a fixed point", f64::from(still == "fixed point")),
                    ],
                ),
            )
            .reference(r)
            .variant("improved 2-DOF, 5 nm; Poincaré-section classification")
            .inputs("10.7 kHz sinusoid 1 nm RMS / zero excitation")
            .origin(o)
            .note(&format!("classes: sinusoid `{sine}`, zero `{still}`")),
        ),
        _ => rows.push(
            Row::ordering("dyn-37", "sinusoid → periodic response; zero excitation → fixed point", Ordering::new(Relation::AllTrue, &[]))
                .note("needs the pipeline's analysis.sine_response and analysis.still_response: run `hdi run` first"),
        ),
    }
    rows.extend(chirp_rows());
    rows
}

/// #38: the quadratic chirp's region boundaries (K, by construction) and the response maximum
/// near the 110 kHz crossing (Q), computed now.
fn chirp_rows() -> Vec<Row> {
    let r = "dissertation App. B (S7e)";
    let (t_sweep, f0, f1, amp) = (1.923e-3, 40e3, 500e3, 0.5e-9);
    let mut rows = Vec::new();
    let Ok(x) = quadratic_chirp(t_sweep, 4e6, f0, f1, amp) else {
        return vec![Row::new(
            "dyn-38",
            Class::K,
            "chirp",
            "ms",
            0.75,
            f64::NAN,
            Tolerance::Relative(0.01),
        )
        .note("the chirp could not be built")];
    };
    // The crossing time of frequency f by bisection on the chirp's instantaneous frequency.
    let crossing = |f: f64| {
        let (mut lo, mut hi) = (0.0, t_sweep);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if x.model.instantaneous_frequency(mid).unwrap_or(f64::NAN) < f {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi) * 1e3
    };
    for (id, f, t) in [
        ("dyn-38", 110e3, 0.75),
        ("dyn-38.90kHz", 90e3, 0.634),
        ("dyn-38.120kHz", 120e3, 0.802),
        ("dyn-38.240kHz", 240e3, 1.268),
    ] {
        rows.push(
            Row::new(
                id,
                Class::K,
                &format!(
                    "chirp 40 → 500 kHz over 1.923 ms crosses {} kHz at",
                    f / 1e3
                ),
                "ms",
                t,
                crossing(f),
                Tolerance::Relative(0.01),
            )
            .reference(r)
            .variant("quadratic chirp f(t) = f0 + (f1 − f0)(t/T)²")
            .inputs("excitation only"),
        );
    }
    // The response: the deepest clearance dip should come when the chirp crosses the 1st
    // pitch mode (the dissertation's contact at ≈ 0.75 ms).
    let dip = (|| -> Result<(f64, f64), String> {
        let isbl = IsblModel::new(IsblParams::improved_2dof())
            .and_then(IsblLookup::build_standard_unverified)
            .map_err(|e| e.to_string())?;
        let model = improved_2dof();
        let input = DmwInput {
            displacement: &x.displacement,
            velocity: &x.velocity,
            sample_rate: x.fs,
        };
        // The record ends at T; the run stops 0.15 ms earlier: the DMW under the LE is the
        // bulge's delayed by the disk transit (≈ 0.08 ms).
        let options = SimOptions {
            duration: t_sweep - 0.15e-3,
            static_init: true,
            ..SimOptions::default()
        };
        let h = TwoDofCase::new(&model, 5.0 * NM, &isbl, Some(input), options)
            .and_then(|c| c.run())
            .map_err(|e| e.to_string())?;
        let mean = h.clearance.iter().sum::<f64>() / h.clearance.len() as f64;
        // Skip the first 0.2 ms (start transient).
        let k0 = (0.2e-3 / h.dt) as usize;
        let k = (k0..h.clearance.len())
            .min_by(|&a, &b| h.clearance[a].total_cmp(&h.clearance[b]))
            .ok_or("empty history")?;
        Ok((k as f64 * h.dt * 1e3, (mean - h.clearance[k]) / NM))
    })();
    rows.push(
        Row::ordering(
            "dyn-38.response",
            "the deepest clearance dip comes within 0.15 ms of the 110 kHz crossing (0.75 ms)",
            Ordering::new(
                Relation::Ascending,
                &[
                    (
                        "|t_dip − 0.75 ms|",
                        dip.as_ref().map_or(f64::NAN, |d| (d.0 - 0.75).abs()),
                    ),
                    ("0.15 ms", 0.15),
                ],
            ),
        )
        .reference(r)
        .variant("improved 2-DOF, 5 nm, chirp amplitude 0.5 nm")
        .inputs("chirp excitation, static start, no calibration")
        .note(&match dip {
            Ok(d) => format!(
                "dip at {:.3} ms ({:.0} kHz crossing), {:.2} nm below the mean clearance; the \
                 dissertation's response peaks at the 1st pitch crossing, hdi's at the normal mode",
                d.0,
                x.model
                    .instantaneous_frequency(d.0 * 1e-3)
                    .unwrap_or(f64::NAN)
                    / 1e3,
                d.1
            ),
            Err(e) => format!("the case failed: {e}"),
        }),
    );
    rows
}

// ------------------------------------------------------------------------------------------

fn interface(params: IsblParams) -> Result<IsblLookup, String> {
    IsblModel::new(params)
        .and_then(IsblLookup::build_standard_unverified)
        .map_err(|e| e.to_string())
}

/// The improved-model grid (nm): 2–8 nm by 0.5 nm for slope A, 8–12.4 nm by 0.2 nm, 8.5 nm.
fn improved_grid() -> Vec<f64> {
    let mut g: Vec<f64> = (4..=16).map(|i| i as f64 * 0.5).collect();
    g.extend((1..=22).map(|i| 8.0 + 0.2 * i as f64));
    g
}

/// Every 2-DOF row. `config`: the pipeline whose calibrated sweeps and spectra are read.
pub fn rows(config: Option<&Path>) -> Vec<Row> {
    let mut rows = geometry_rows();
    let cache = pipeline::open(config);
    let inputs = (|| {
        let improved = interface(IsblParams::improved_2dof())?;
        let initial = interface(IsblParams::initial_2dof())?;
        let track = synthetic_dmw(2.2e-3, 4e6, 1e-9, 1).map_err(|e| e.to_string())?;
        Ok::<_, String>((improved, initial, track))
    })();
    let (improved, initial, track) = match inputs {
        Ok(x) => x,
        Err(e) => {
            rows.push(
                Row::new(
                    "dyn-16",
                    Class::D,
                    "simulation inputs (interfaces, synthetic DMW)",
                    "-",
                    f64::NAN,
                    f64::NAN,
                    Tolerance::Absolute(0.0),
                )
                .note(&format!("could not be built: {e}")),
            );
            return rows;
        }
    };
    let synth =
        "synthetic DMW σ 1 nm seed 1 (docs/conventions.md), no calibration (default inputs)";
    let improved_model = improved_2dof();
    let optimised_model =
        crate::dynamics::params::optimised_bulge(50e-6).map(|b| improved_2dof().with_bulge(b));
    let initial_grid: Vec<f64> = [4.0, 5.0, 6.0, 7.0]
        .into_iter()
        .chain((0..=15).map(|i| 8.0 + 0.2 * i as f64))
        .collect();
    let mut optimised_grid: Vec<f64> = (4..=16).map(|i| i as f64 * 0.5).collect();
    optimised_grid.extend((1..=12).map(|i| 8.0 + 0.2 * i as f64));
    optimised_grid.extend([12.0, 13.0]);
    // The case store of a pipeline that has run (a validation before the first run creates
    // nothing in the project).
    let store = cache
        .as_ref()
        .map(|c| c.store())
        .filter(|s| s.processed().join(".hdi").is_dir());
    let dmw_blake3 = {
        let mut h = blake3::Hasher::new();
        h.update(&track.fs.to_le_bytes());
        for x in track.displacement.iter().chain(&track.velocity) {
            h.update(&x.to_le_bytes());
        }
        h.finalize().to_hex().to_string()
    };
    let case_store = |model: &Model2Dof, interface: IsblParams| {
        store.map(|store| CaseStore {
            store,
            inputs: json!({
                "model_parameters": model,
                // The contact stage's key form of the ISBL parameters (SI, unit suffixes).
                "interface": crate::artefacts::contact::ContactInputs::from(&interface),
                "dmw_blake3": dmw_blake3,
                "case_params": CaseParams::improved_2dof(),
            }),
        })
    };
    let improved_cases = case_store(&improved_model, IsblParams::improved_2dof());
    let initial_cases = case_store(&initial_2dof(), IsblParams::initial_2dof());
    let optimised_cases = optimised_model
        .as_ref()
        .ok()
        .and_then(|m| case_store(m, IsblParams::improved_2dof()));
    let ((s_improved, s_initial), s_optimised) = rayon::join(
        || {
            rayon::join(
                || {
                    run_sweep(
                        &improved_model,
                        &improved,
                        &track,
                        true,
                        &improved_grid(),
                        &[0.2],
                        &format!("{synth}, static start"),
                        improved_cases.as_ref(),
                    )
                },
                || {
                    run_sweep(
                        &initial_2dof(),
                        &initial,
                        &track,
                        true,
                        &initial_grid,
                        &[],
                        &format!("{synth}, static start"),
                        initial_cases.as_ref(),
                    )
                },
            )
        },
        || {
            optimised_model.as_ref().ok().map(|m| {
                run_sweep(
                    m,
                    &improved,
                    &track,
                    true,
                    &optimised_grid,
                    &[],
                    &format!("{synth}, static start"),
                    optimised_cases.as_ref(),
                )
            })
        },
    );
    // The summit-distribution variants of dyn-19 and dyn-24: 3 cases each (9 with measured
    // surfaces), on the same synthetic DMW and case store as the rows' own.
    let measured = cache
        .as_ref()
        .zip(config)
        .and_then(|(c, path)| pipeline::measured_summits(path, c));
    let summit_sweeps: Vec<SummitSweep> =
        super::contact::summit_variants(&IsblParams::improved_2dof(), measured.as_ref())
            .into_par_iter()
            .map(|v| {
                let inputs = format!("{synth}, static start; {}", v.inputs);
                let pts = match v.params.map(|p| (p, interface(p))) {
                    Some((p, Ok(lookup))) => {
                        let cases = case_store(&improved_model, p);
                        SUMMIT_VARIANT_ACTUATIONS
                            .par_iter()
                            .filter_map(|&h| {
                                run_case(
                                    &improved_model,
                                    &lookup,
                                    h * NM,
                                    &track,
                                    true,
                                    cases.as_ref(),
                                )
                            })
                            .collect()
                    }
                    _ => Vec::new(),
                };
                let origin = match v.origin {
                    Origin::Computed => Origin::Computed,
                    Origin::Cache { instance, key } | Origin::Recomputed { instance, key } => {
                        Origin::Recomputed { instance, key }
                    }
                };
                SummitSweep {
                    name: v.name,
                    sweep: Sweep::new(pts, None, inputs, origin),
                }
            })
            .collect();
    let sweep = |name: &str| cache.as_ref().and_then(|c| cached_sweep(c, name));
    let (rec_improved, cal_improved) = (sweep("improved_sweep"), sweep("improved_calibrated"));
    let (rec_optimised, cal_optimised) = (sweep("optimised_sweep"), sweep("optimised_calibrated"));
    let mut fhm86 = f64::NAN;
    let improved_cached = CachedSweeps {
        record: rec_improved.as_ref(),
        calibrated: cal_improved.as_ref(),
    };
    rows.extend(improved_rows(
        &s_improved,
        improved_cached,
        &summit_sweeps,
        &mut fhm86,
    ));
    rows.extend(initial_rows(&s_initial));
    if let Some(s) = s_optimised {
        let optimised_cached = CachedSweeps {
            record: rec_optimised.as_ref(),
            calibrated: cal_optimised.as_ref(),
        };
        rows.extend(optimised_rows(&s, optimised_cached, fhm86));
    }
    rows.extend(app_b_rows(cache.as_ref()));
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flying sweep whose clearance is `offset − h` (nm), from `instance`'s cache.
    fn line(offset_nm: f64, instance: &str) -> Sweep {
        let pts = (0..=10)
            .map(|i| {
                let h = 8.0 + 0.1 * i as f64;
                Pt {
                    h: h * NM,
                    clearance: (offset_nm - h) * NM,
                    fhm: 5.0,
                    solid: 0.0,
                    fc: 0.0,
                    q: 0.0,
                    ar: 0.0,
                    adhesion: 0.0,
                    mu_inst: f64::NAN,
                    pm_inst: f64::NAN,
                    tau_inst: f64::NAN,
                }
            })
            .collect();
        Sweep::new(
            pts,
            None,
            instance.to_string(),
            Origin::Cache {
                instance: instance.to_string(),
                key: "k".into(),
            },
        )
    }

    fn clearance_target<'a>(class: Class, value: &'a dyn Fn(&Sweep) -> f64) -> Target<'a> {
        Target {
            id: "dyn-18",
            class,
            quantity: "clearance at 8.5 nm",
            unit: "nm",
            target: 2.54,
            tolerance: Tolerance::Absolute(0.05),
            reference: "dissertation §2.2.2",
            value,
            note: "",
        }
    }

    #[test]
    fn d_rows_carry_the_record_and_the_calibrated_value_from_their_own_sweeps() {
        let value = |s: &Sweep| s.at(8.5 * NM, |p| p.clearance / NM);
        let (own, record, calibrated) = (
            line(11.05, "own"),
            line(11.0, "simulate.improved_sweep"),
            line(11.3, "simulate.improved_calibrated"),
        );
        let cached = CachedSweeps {
            record: Some(&record),
            calibrated: Some(&calibrated),
        };
        let r = target_row(clearance_target(Class::D, &value), &own, cached, "v");
        assert!((r.value - 2.55).abs() < 1e-9, "{}", r.value);
        let rec = r.record.as_ref().expect("record value");
        let cal = r.calibrated.as_ref().expect("calibrated value");
        assert!((rec.value - 2.5).abs() < 1e-9 && rec.inputs == "simulate.improved_sweep");
        assert!((cal.value - 2.8).abs() < 1e-9 && cal.inputs == "simulate.improved_calibrated");
        let j = r.to_json();
        assert_eq!(j["uncalibrated_record"]["pass"], true);
        assert_eq!(j["calibrated"]["pass"], false);
        // K rows do not depend on the dropped inputs: no alternative values.
        let k = target_row(clearance_target(Class::K, &value), &own, cached, "v");
        assert!(k.record.is_none() && k.calibrated.is_none());
    }

    /// A computed case stored and read back is the case computed directly, bit for bit
    /// (NaN fields too); a case of another model is another entry, not a hit.
    #[test]
    fn stored_cases_read_back_bit_for_bit_and_are_keyed_by_their_inputs() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let isbl = interface(IsblParams::improved_2dof()).unwrap();
        let track = synthetic_dmw(2.2e-3, 4e6, 1e-9, 1).unwrap();
        let model = improved_2dof();
        let bits = |p: &Pt| Pt::to_bits_json(*p);
        // 5 nm: flying, so μ, P_m and τ are NaN (no loaded sample).
        let direct = simulate_case(&model, &isbl, 5.0 * NM, &track, true).unwrap();
        assert!(direct.mu_inst.is_nan());
        let cs = |inputs: &str| CaseStore {
            store: &store,
            inputs: json!({ "model_parameters": inputs }),
        };
        let a = cs("improved");
        let first = run_case(&model, &isbl, 5.0 * NM, &track, true, Some(&a)).unwrap();
        let entries = store.entries().len();
        assert_eq!(entries, 1);
        // Under the same key a different model (which gives other numbers) reads the entry:
        // the store answered, nothing was recomputed.
        let other = initial_2dof();
        let second = run_case(&other, &isbl, 5.0 * NM, &track, true, Some(&a)).unwrap();
        assert_eq!(bits(&first), bits(&direct));
        assert_eq!(bits(&second), bits(&direct));
        let recomputed = simulate_case(&other, &isbl, 5.0 * NM, &track, true).unwrap();
        assert_ne!(bits(&recomputed), bits(&direct));
        assert_eq!(store.entries().len(), entries);
        // Other inputs: another key, a new entry.
        let b = cs("other");
        run_case(&model, &isbl, 5.0 * NM, &track, true, Some(&b)).unwrap();
        assert_eq!(store.entries().len(), entries + 1);
    }
}
