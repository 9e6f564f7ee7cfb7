//! A sweep of 2-DOF cases over the actuation (the dissertation's Figs 2.16–2.22): the inputs
//! every case shares, prepared from the upstream artefacts; the cases run through the case
//! cache in parallel; the sweep-level metrics (touchdown, slopes, regimes, flyability; see
//! `docs/dynamics-metrics.md`) and one table row per case.

use crate::artefacts::calibration::upstream_fitted_knobs;
use crate::artefacts::cases;
use crate::artefacts::dmw_tracks::DmwTrack;
use crate::contact::isbl::IsblModel;
use crate::contact::lookup::IsblLookup;
use crate::core::cache::Store;
use crate::core::cases::{get_or_compute, CaseEntry};
use crate::core::progress::Progress;
use crate::dynamics::metrics::{sweep_metrics, Regime, SlopeParams, SweepMetrics, SweepPoint};
use crate::error::{Error, Result};
use crate::slider::calibration::{apply_fitted, base_inputs};
use crate::slider::case::{simulate_case, CASE_FILE, MODEL_VERSION};
use crate::slider::params::SimulateParams;
use serde_json::{json, Map, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One finished case: its actuation, metrics, and where its files are.
pub struct CaseOutcome {
    pub actuation: f64,
    pub metrics: Value,
    pub entry: CaseEntry,
}

/// What every case of one sweep shares: the (calibrated) parameters, the interface table, the
/// DMW track with its instance key, and the contact instance's key (both enter the case keys).
pub struct PreparedSweep {
    pub params: SimulateParams,
    pub isbl: IsblLookup,
    pub dmw: Option<(DmwTrack, String)>,
    pub contact_key: String,
}

impl PreparedSweep {
    /// Resolve the upstream artefacts (contact inputs, DMW track, calibration knobs) into the
    /// shared inputs of the cases of `params`; `key_of` gives an upstream instance's cache key.
    pub fn prepare(
        params: &SimulateParams,
        upstream: &BTreeMap<String, Value>,
        upstream_dirs: &BTreeMap<String, PathBuf>,
        key_of: impl Fn(&str) -> String,
    ) -> Result<PreparedSweep> {
        let (mut isbl_params, mut dmw_track) = base_inputs(params, upstream, upstream_dirs)?;
        let mut calibrated = params.clone();
        if let Some(cal) = &params.calibration {
            let fitted = upstream_fitted_knobs(upstream, cal)?;
            apply_fitted(
                &mut calibrated,
                &fitted,
                &mut isbl_params,
                dmw_track.as_mut(),
            )?;
        }
        if let Some(b) = &params.bulge {
            let fitted = crate::artefacts::bulge::upstream_bulge(upstream, b)?;
            calibrated.apply_bulge(&fitted, b)?;
        }
        let isbl = IsblLookup::build_standard(IsblModel::new(isbl_params)?)?;
        let dmw = match (&calibrated.dmw, dmw_track) {
            (Some(d), Some(t)) => Some((t, key_of(d))),
            _ => None,
        };
        Ok(PreparedSweep {
            contact_key: key_of(&calibrated.contact),
            params: calibrated,
            isbl,
            dmw,
        })
    }

    /// The canonical parameters (cache key input) of the case at `actuation`.
    pub fn case_params(&self, actuation: f64) -> Value {
        self.params.case_params(
            actuation,
            &self.contact_key,
            self.dmw.as_ref().map(|d| d.1.as_str()),
        )
    }

    /// Simulate the case at `actuation` into `dir` (what the case cache calls, locally or on
    /// a Slurm worker).
    pub fn compute_case(&self, actuation: f64, dir: &Path) -> Result<Value> {
        simulate_case(
            &self.params,
            actuation,
            &self.isbl,
            self.dmw.as_ref().map(|d| &d.0),
            dir,
        )
    }
}

/// The case of `p` at `actuation` from the case cache, simulated into it if missing; its key
/// includes the contact and DMW instances' keys.
pub fn cached_case(
    store: &Store,
    p: &SimulateParams,
    actuation: f64,
    isbl: &IsblLookup,
    contact_key: &str,
    dmw: Option<(&DmwTrack, &str)>,
) -> Result<CaseEntry> {
    let params = p.case_params(actuation, contact_key, dmw.map(|d| d.1));
    get_or_compute(store, MODEL_VERSION, &params, |dir| {
        simulate_case(p, actuation, isbl, dmw.map(|d| d.0), dir)
    })
}

/// Where a sweep's cases are computed.
pub enum CaseSink<'a> {
    /// One content-addressed store entry per case (`core::cases`), so a rerun or an extended
    /// sweep recomputes only what is missing: the pipeline's sweeps. The cache keys of the
    /// consumed contact and DMW entries are part of each case's key.
    Store {
        store: &'a Store,
        contact_key: &'a str,
        dmw_key: Option<&'a str>,
    },
    /// A directory `h_XXX.XXnm/` per case under this one, recomputed every time: `hdi simulate`.
    Directory(&'a Path),
}

/// Run every case of the sweep in parallel into `sink`, reporting to `progress` (its length
/// is the number of cases, one `inc` and a "k/n cases" message per finished case), and return
/// them sorted by actuation. The first failed case (in actuation order) is the error.
pub fn run_cases(
    p: &SimulateParams,
    sink: &CaseSink,
    isbl: &IsblLookup,
    dmw: Option<&DmwTrack>,
    progress: &dyn Progress,
) -> Result<Vec<CaseOutcome>> {
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let total = p.actuations.len();
    let finished = AtomicUsize::new(0);
    progress.set_length(total as u64);
    progress.set_message(format!("0/{total} cases"));
    let outcomes: Vec<Result<CaseOutcome>> = p
        .actuations
        .par_iter()
        .map(|&a| {
            let entry = run_case(p, sink, a, isbl, dmw).map_err(|e| Error::Case {
                actuation: a,
                source: Box::new(e),
            });
            let k = finished.fetch_add(1, Ordering::Relaxed) + 1;
            progress.set_message(format!("{k}/{total} cases"));
            progress.inc(1);
            let entry = entry?;
            Ok(CaseOutcome {
                actuation: a,
                metrics: entry.result.clone(),
                entry,
            })
        })
        .collect();
    let mut done = Vec::with_capacity(outcomes.len());
    for o in outcomes {
        done.push(o?);
    }
    done.sort_by(|a, b| a.actuation.total_cmp(&b.actuation));
    Ok(done)
}

/// One case of [`run_cases`].
fn run_case(
    p: &SimulateParams,
    sink: &CaseSink,
    actuation: f64,
    isbl: &IsblLookup,
    dmw: Option<&DmwTrack>,
) -> Result<CaseEntry> {
    match sink {
        CaseSink::Store {
            store,
            contact_key,
            dmw_key,
        } => {
            let params = p.case_params(actuation, contact_key, *dmw_key);
            get_or_compute(store, MODEL_VERSION, &params, |dir| {
                simulate_case(p, actuation, isbl, dmw, dir)
            })
        }
        CaseSink::Directory(root) => {
            let dir = root.join(format!("h_{:06.2}nm", actuation * 1e9));
            std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
            let result = simulate_case(p, actuation, isbl, dmw, &dir)?;
            Ok(CaseEntry {
                key: String::new(),
                dir,
                result,
                cached: false,
            })
        }
    }
}

/// Hard-link (or copy) each case's HDF5 into `out/cases/`.
pub fn link_cases(out: &Path, outcomes: &[CaseOutcome]) -> Result<Vec<String>> {
    let dir = out.join(cases::DIR);
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let mut names = Vec::new();
    for c in outcomes {
        let name = cases::sweep_case_name(c.actuation);
        let (from, to) = (c.entry.dir.join(CASE_FILE), dir.join(&name));
        if std::fs::hard_link(&from, &to).is_err() {
            std::fs::copy(&from, &to).map_err(|e| Error::io(&to, e))?;
        }
        names.push(cases::sweep_case_file(c.actuation));
    }
    Ok(names)
}

/// The sweep-level analysis of finished cases (sorted by actuation).
pub fn sweep_analysis(p: &SimulateParams, cases: &[CaseOutcome]) -> Result<SweepMetrics> {
    let points: Vec<SweepPoint> = cases
        .iter()
        .map(|c| SweepPoint {
            actuation_m: c.actuation,
            mean_clearance_m: c.metrics["clearance_m"]["mean"]
                .as_f64()
                .unwrap_or(f64::NAN),
            any_solid_contact: c.metrics["percent_solid_contact"].as_f64().unwrap_or(0.0) > 0.0,
            vibration_percent: c.metrics["vibration_percent"].as_f64().unwrap_or(f64::NAN),
        })
        .collect();
    let t0 = 0.5 * p.model.interface.lubricant_thickness;
    sweep_metrics(
        &points,
        &SlopeParams::new(t0),
        p.model.nominal_flying_height,
    )
    .map_err(Error::SweepMetrics)
}

pub fn regime_name(r: Regime) -> &'static str {
    match r {
        Regime::Flying => "flying",
        Regime::MobileLubricantContact => "mobile lubricant",
        Regime::BondedLubricantContact => "bonded lubricant",
        Regime::SolidContact => "solid contact",
    }
}

/// One table row per case (unit suffixes in the names).
pub fn case_rows(cases: &[CaseOutcome], sweep: &SweepMetrics) -> Vec<Map<String, Value>> {
    cases
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let m = &c.metrics;
            let f = |v: &Value, scale: f64| v.as_f64().map(|x| x * scale);
            let mut r = Map::new();
            // Rounded to the femtometre: 8.8 nm, not 8.799999999999999.
            r.insert(
                "actuation_nm".into(),
                json!((c.actuation * 1e15).round() / 1e6),
            );
            r.insert(
                "clearance_mean_nm".into(),
                json!(f(&m["clearance_m"]["mean"], 1e9)),
            );
            r.insert(
                "clearance_std_nm".into(),
                json!(f(&m["clearance_m"]["std"], 1e9)),
            );
            r.insert("fh_mean_nm".into(), json!(f(&m["fh_m"]["mean"], 1e9)));
            r.insert("hms_mean_nm".into(), json!(f(&m["hms_mean_m"], 1e9)));
            r.insert("vibration_percent".into(), m["vibration_percent"].clone());
            r.insert(
                "vibration_extrema_percent".into(),
                m["vibration_extrema_percent"].clone(),
            );
            r.insert("vibration_kind".into(), m["vibration_kind"].clone());
            r.insert(
                "solid_contact_percent".into(),
                m["percent_solid_contact"].clone(),
            );
            r.insert(
                "regime".into(),
                json!(sweep.regimes.get(i).map(|r| regime_name(*r))),
            );
            r.insert(
                "contact_force_mean_mN".into(),
                json!(f(&m["contact_force_N"]["mean"], 1e3)),
            );
            r.insert(
                "friction_mean_mN".into(),
                json!(f(&m["friction_N"]["mean"], 1e3)),
            );
            r.insert(
                "adhesion_mean_mN".into(),
                json!(f(&m["adhesion_N"]["mean"], 1e3)),
            );
            r.insert(
                "real_area_mean_um2".into(),
                json!(f(&m["real_area_m2"]["mean"], 1e12)),
            );
            r.insert(
                "friction_coefficient".into(),
                m["friction_coefficient"].clone(),
            );
            r.insert(
                "mean_pressure_GPa".into(),
                json!(f(&m["mean_pressure_Pa"], 1e-9)),
            );
            r.insert(
                "shear_traction_GPa".into(),
                json!(f(&m["shear_traction_Pa"], 1e-9)),
            );
            r.insert(
                "nominal_area_um2".into(),
                json!(f(&m["nominal_area_m2"], 1e12)),
            );
            r.insert("flyability".into(), json!(sweep.flyability.get(i)));
            r.insert("steps".into(), m["steps"].clone());
            r.insert("case_key".into(), json!(c.entry.key));
            r
        })
        .collect()
}
