//! A sweep of 2-DOF cases over the actuation (the dissertation's Figs 2.16–2.22): the inputs
//! every case shares, prepared from the upstream artefacts; the cases run through the case
//! cache in parallel; the sweep-level metrics (touchdown, slopes, regimes, flyability; see
//! `docs/dynamics-metrics.md`) and one table row per case.

use crate::artefacts::calibration::upstream_fitted_knobs;
use crate::artefacts::cases;
use crate::artefacts::dmw_tracks::DmwTrack;
use crate::contact::bem::law::ContactCurve;
use crate::contact::isbl::{IsblModel, IsblParams};
use crate::contact::lookup::IsblLookup;
use crate::core::cache::Store;
use crate::core::cases::{get_or_compute, CaseEntry};
use crate::core::progress::Progress;
use crate::dynamics::metrics::{sweep_metrics, Regime, SlopeParams, SweepMetrics, SweepPoint};
use crate::error::{Error, Result};
use crate::slider::calibration::{apply_fitted, base_inputs};
use crate::slider::case::{simulate_case, SweepCaseResult, CASE_FILE, MODEL_VERSION};
use crate::slider::doe_design::design_params;
// Named here too, where the sweeps and their tables have always found them.
pub use crate::slider::case::{regime_name, vibration_kind_name};
pub use crate::slider::params::Branch;
use crate::slider::params::SimulateParams;
use serde_json::{json, Map, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The force–separation curve of the upstream `[contact_bem.*]` instance `name` as a contact
/// law (its mean gaps, pressures and real areas).
pub fn upstream_contact_law(
    upstream: &BTreeMap<String, Value>,
    name: &str,
) -> Result<std::sync::Arc<ContactCurve>> {
    let r: crate::artefacts::contact_bem::BemResult =
        crate::artefacts::upstream_result(upstream, "contact_bem", name)?;
    Ok(std::sync::Arc::new(r.contact_law()?))
}

/// One finished case: its actuation, result, and where its files are.
pub struct CaseOutcome {
    pub actuation: f64,
    pub metrics: SweepCaseResult,
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
        let law = match &params.contact_bem {
            Some(b) => Some(upstream_contact_law(upstream, b)?),
            None => None,
        };
        Self::assemble_with_law(calibrated, isbl_params, law, dmw_track, key_of)
    }

    /// The shared inputs of `params` as they stand (calibrated, bulge in place): its interface
    /// table from `isbl_params`, and the keys of the contact and DMW instances.
    pub fn assemble(
        params: SimulateParams,
        isbl_params: IsblParams,
        dmw_track: Option<DmwTrack>,
        key_of: impl Fn(&str) -> String,
    ) -> Result<PreparedSweep> {
        Self::assemble_with_law(params, isbl_params, None, dmw_track, key_of)
    }

    /// [`Self::assemble`] with the contact channels from a measured law (`contact_law =
    /// "bem"`), whose instance key joins the contact key of every case.
    fn assemble_with_law(
        params: SimulateParams,
        isbl_params: IsblParams,
        law: Option<std::sync::Arc<ContactCurve>>,
        dmw_track: Option<DmwTrack>,
        key_of: impl Fn(&str) -> String,
    ) -> Result<PreparedSweep> {
        let model = IsblModel::new(isbl_params)?;
        let isbl = match law {
            Some(l) => IsblLookup::build_with_contact_law(model, l)?,
            None => IsblLookup::build_standard_unverified(model)?,
        };
        let contact_key = match &params.contact_bem {
            Some(b) => format!("{}+{}", key_of(&params.contact), key_of(b)),
            None => key_of(&params.contact),
        };
        let dmw = match (&params.dmw, dmw_track) {
            (Some(d), Some(t)) => Some((t, key_of(d))),
            _ => None,
        };
        Ok(PreparedSweep {
            contact_key,
            params,
            isbl,
            dmw,
        })
    }

    /// The parameters of `case`: a DOE design point's bulge, or a continuation start, on the
    /// sweep's parameters (a design point keeps the configured start).
    fn case_model(&self, case: &SweepCase) -> Result<std::borrow::Cow<'_, SimulateParams>> {
        use std::borrow::Cow;
        Ok(match (case.design_m, case.static_start) {
            (Some(d), _) => Cow::Owned(design_params(&self.params, &d, case.actuation_m)?),
            (None, Some(s)) => Cow::Owned(with_start(&self.params, Some(s))),
            (None, None) => Cow::Borrowed(&self.params),
        })
    }

    /// The canonical parameters (cache key input) of `case`: the contact and DMW instances'
    /// keys are part of them.
    pub fn case_params(&self, case: &SweepCase) -> Result<Value> {
        Ok(self.case_model(case)?.case_params(
            case.actuation_m,
            &self.contact_key,
            self.dmw.as_ref().map(|d| d.1.as_str()),
        ))
    }

    /// Simulate `case` into `dir` (what the case cache calls, locally or on a Slurm worker).
    pub fn compute(&self, case: &SweepCase, dir: &Path) -> Result<Value> {
        simulate_case(
            &*self.case_model(case)?,
            case.actuation_m,
            &self.isbl,
            self.dmw.as_ref().map(|d| &d.0),
            dir,
        )
    }

    /// `case` from the case cache, simulated into it if missing.
    pub fn cached(&self, store: &Store, case: &SweepCase) -> Result<CaseEntry> {
        get_or_compute(store, MODEL_VERSION, &self.case_params(case)?, |dir| {
            self.compute(case, dir)
        })
    }

    /// The sweep's grid (sorted, without repeats), its branches and their continuation
    /// starts: what a run computes up front, locally or listed for an executor.
    pub fn plan(&self) -> Result<SweepPlan> {
        let p = &self.params;
        let mut grid = p.actuations.clone();
        grid.sort_by(|a, b| a.total_cmp(b));
        grid.dedup();
        let branches: Vec<Option<Branch>> = if p.branches.is_empty() {
            vec![None]
        } else {
            p.branches.iter().map(|b| Some(*b)).collect()
        };
        // Static init: each branch's equilibria by continuation, one after the other (cheap);
        // the dynamic cases of every branch then run in one parallel batch.
        let track = self.dmw.as_ref().map(|d| &d.0);
        let mut starts = Vec::new();
        for b in &branches {
            starts.push(match b {
                Some(b) => Some(continuation_starts(p, &grid, &self.isbl, track, *b)?),
                None => None,
            });
        }
        Ok(SweepPlan {
            grid,
            branches,
            starts,
        })
    }
}

/// A 2-DOF sweep case or DOE design case, as the stages list it and a recipe carries it
/// (docs/schemas/case-manifest.json).
#[derive(
    Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(deny_unknown_fields)]
pub struct SweepCase {
    /// TFC actuation of the case, m.
    pub actuation_m: f64,
    /// DOE design point (bulge semi-width, full width, offset from the trailing edge, m);
    /// null for a sweep case.
    pub design_m: Option<[f64; 3]>,
    /// Continuation equilibrium (z, ϑ) the case starts Newton from (branch-tracking sweeps);
    /// null otherwise.
    pub static_start: Option<[f64; 2]>,
}

impl SweepCase {
    pub fn at(actuation_m: f64, static_start: Option<[f64; 2]>) -> Self {
        SweepCase {
            actuation_m,
            design_m: None,
            static_start,
        }
    }
}

/// What a sweep computes up front: its grid, branches and each branch's starts.
pub struct SweepPlan {
    pub grid: Vec<f64>,
    /// `[None]` for a one-sweep (nominal-start) instance.
    pub branches: Vec<Option<Branch>>,
    /// Per branch, the continuation start of each grid point (`None`: nominal start).
    pub starts: Vec<Option<Vec<[f64; 2]>>>,
}

impl SweepPlan {
    /// Every case, branch by branch, in grid order.
    pub fn cases(&self) -> Vec<SweepCase> {
        self.starts
            .iter()
            .flat_map(|s| {
                self.grid
                    .iter()
                    .enumerate()
                    .map(move |(i, &a)| SweepCase::at(a, s.as_ref().map(|s| s[i])))
            })
            .collect()
    }
}

/// The static equilibria `(z, ϑ)` of `p`'s cases at `actuations` (ascending) along `branch`,
/// solved one after the other by continuation: each Newton solve starts from the previous
/// actuation's root (the first from the nominal state). Cheap next to the dynamic cases,
/// which then run in parallel from these starts.
pub fn continuation_starts(
    p: &SimulateParams,
    actuations: &[f64],
    isbl: &IsblLookup,
    dmw: Option<&DmwTrack>,
    branch: Branch,
) -> Result<Vec<[f64; 2]>> {
    use crate::dynamics::two_dof::{DmwInput, TwoDofCase};
    let mut order: Vec<usize> = (0..actuations.len()).collect();
    if branch == Branch::Down {
        order.reverse();
    }
    let mut roots = vec![[0.0; 2]; actuations.len()];
    let mut prev: Option<[f64; 2]> = None;
    for i in order {
        let input = dmw.map(|t| DmwInput {
            displacement: &t.displacement,
            velocity: &t.velocity,
            sample_rate: t.sample_rate,
        });
        let case = TwoDofCase::new(&p.model, actuations[i], isbl, input, p.options)?;
        let q = match prev {
            None => case.static_equilibrium()?,
            Some(q0) => case.static_equilibrium_near(q0)?,
        };
        roots[i] = q;
        prev = Some(q);
    }
    // The start enters the case's cache key: quantised (0.1 pm in heave, 0.1 nrad in pitch,
    // far below Newton's basin) so a root recomputed in an extended sweep keys the same case
    // again; the case's own Newton solve from it lands on the same equilibrium.
    Ok(roots
        .into_iter()
        .map(|[z, t]| [(z * 1e13).round() / 1e13, (t * 1e10).round() / 1e10])
        .collect())
}

/// `p` whose cases start Newton at `start` (a continuation start; `None`: as configured).
pub fn with_start(p: &SimulateParams, start: Option<[f64; 2]>) -> SimulateParams {
    let mut q = p.clone();
    q.options.static_start = start;
    q
}

/// Where a sweep's cases are computed.
pub enum CaseSink<'a> {
    /// One content-addressed store entry per case (`core::cases`), so a rerun or an extended
    /// sweep recomputes only what is missing: the pipeline's sweeps. The cache keys of the
    /// consumed contact and DMW entries are part of each case's key.
    Store {
        store: &'a Store,
        prepared: &'a PreparedSweep,
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
    let jobs: Vec<(f64, Option<[f64; 2]>)> = p.actuations.iter().map(|&a| (a, None)).collect();
    let mut done = run_jobs(p, sink, isbl, dmw, progress, &jobs, "")?;
    done.sort_by(|a, b| a.actuation.total_cmp(&b.actuation));
    Ok(done)
}

/// Run the cases `jobs` (actuation, Newton start) in parallel, in the order given; `tag`
/// names the cases' directories apart under [`CaseSink::Directory`] (`h_008.60nm{tag}`).
/// The first failed case (in `jobs` order) is the error.
pub fn run_jobs(
    p: &SimulateParams,
    sink: &CaseSink,
    isbl: &IsblLookup,
    dmw: Option<&DmwTrack>,
    progress: &dyn Progress,
    jobs: &[(f64, Option<[f64; 2]>)],
    tag: &str,
) -> Result<Vec<CaseOutcome>> {
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let total = jobs.len();
    let finished = AtomicUsize::new(0);
    progress.set_length(total as u64);
    progress.set_message(format!("0/{total} cases"));
    let outcomes: Vec<Result<CaseOutcome>> = jobs
        .par_iter()
        .map(|&(a, start)| {
            let entry = run_case(p, sink, a, start, isbl, dmw, tag).map_err(|e| Error::Case {
                actuation: a,
                source: Box::new(e),
            });
            let k = finished.fetch_add(1, Ordering::Relaxed) + 1;
            progress.set_message(format!("{k}/{total} cases"));
            progress.inc(1);
            let entry = entry?;
            Ok(CaseOutcome {
                actuation: a,
                metrics: SweepCaseResult::from_json(&entry.result)?,
                entry,
            })
        })
        .collect();
    let mut done = Vec::with_capacity(outcomes.len());
    for o in outcomes {
        done.push(o?);
    }
    Ok(done)
}

/// One case of [`run_cases`].
fn run_case(
    p: &SimulateParams,
    sink: &CaseSink,
    actuation: f64,
    start: Option<[f64; 2]>,
    isbl: &IsblLookup,
    dmw: Option<&DmwTrack>,
    tag: &str,
) -> Result<CaseEntry> {
    match sink {
        // The stage's prepared sweep computes the case, as a Slurm worker's does.
        CaseSink::Store { store, prepared } => {
            prepared.cached(store, &SweepCase::at(actuation, start))
        }
        CaseSink::Directory(root) => {
            let dir = root.join(format!("h_{:06.2}nm{tag}", actuation * 1e9));
            std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
            let result = match start {
                Some(_) => simulate_case(&with_start(p, start), actuation, isbl, dmw, &dir)?,
                None => simulate_case(p, actuation, isbl, dmw, &dir)?,
            };
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
    link_cases_tagged(out, outcomes, None)
}

/// [`link_cases`] with the names of a second branch set apart: `cases/down/h_008.60nm.h5`
/// (`None`: `cases/h_008.60nm.h5`, the first branch or the only sweep).
pub fn link_cases_tagged(
    out: &Path,
    outcomes: &[CaseOutcome],
    sub: Option<&str>,
) -> Result<Vec<String>> {
    let mut dir = out.join(cases::DIR);
    if let Some(s) = sub {
        dir = dir.join(s);
    }
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let mut names = Vec::new();
    for c in outcomes {
        let name = cases::sweep_case_name(c.actuation);
        let (from, to) = (c.entry.dir.join(CASE_FILE), dir.join(&name));
        if to.exists() {
            std::fs::remove_file(&to).map_err(|e| Error::io(&to, e))?;
        }
        if std::fs::hard_link(&from, &to).is_err() {
            std::fs::copy(&from, &to).map_err(|e| Error::io(&to, e))?;
        }
        names.push(match sub {
            Some(s) => format!("{}/{s}/{name}", cases::DIR),
            None => cases::sweep_case_file(c.actuation),
        });
    }
    Ok(names)
}

/// Touchdown by the convention (`dynamics::touchdown`, docs/conventions.md) of one branch:
/// the first case whose steady window reaches c < 0, scanned upward over the sweep's own
/// grid (`cases`, sorted; run already) and refined to 0.02 nm by running the extra cases,
/// each started from the equilibrium of its neighbour on the branch (`starts`, aligned with
/// `cases`; `None` for the nominal start). Returns the result and the extra cases.
pub fn convention_touchdown(
    p: &SimulateParams,
    sink: &CaseSink,
    isbl: &IsblLookup,
    dmw: Option<&DmwTrack>,
    cases: &[CaseOutcome],
    starts: Option<(&[[f64; 2]], Branch)>,
) -> Result<(crate::dynamics::touchdown::Touchdown, Vec<CaseOutcome>)> {
    use crate::dynamics::touchdown::{find_touchdown, TouchdownSearch};
    let grid: Vec<f64> = cases.iter().map(|c| c.actuation).collect();
    let touches = |c: &CaseOutcome| c.metrics.touches();
    let known: Vec<(f64, bool)> = cases.iter().map(|c| (c.actuation, touches(c))).collect();
    // The scan grid is the sweep's own: from its first actuation (0 nm in the shipped
    // sweeps) by its smallest spacing, so a uniform sweep needs no extra scan cases.
    let step = grid
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    let (Some(&first), Some(&last)) = (grid.first(), grid.last()) else {
        return Ok((
            crate::dynamics::touchdown::Touchdown {
                actuation: None,
                last_flying: None,
                cases_run: 0,
            },
            Vec::new(),
        ));
    };
    // A fixed batch (not the thread count): the refinement points, and so the result, must
    // not depend on the machine. Three cases per round: 0.2 nm → 0.05 → 0.0125 nm.
    if !p.refine_touchdown || !step.is_finite() {
        // Without refinement (or with one case) the bracket stays the grid's: no extra cases.
        let k = known.iter().position(|k| k.1);
        return Ok((
            crate::dynamics::touchdown::Touchdown {
                actuation: k.map(|k| known[k].0),
                last_flying: match k {
                    Some(0) => None,
                    Some(k) => Some(known[k - 1].0),
                    None => known.last().map(|k| k.0),
                },
                cases_run: 0,
            },
            Vec::new(),
        ));
    }
    let search = TouchdownSearch {
        start: first,
        stop: last,
        step,
        ..TouchdownSearch::convention(last, step, 3)
    };
    let start_near = |a: f64| -> Option<[f64; 2]> {
        let (roots, branch) = starts?;
        let i = match branch {
            // Up: the largest grid actuation below; down: the smallest above.
            Branch::Up => grid.iter().rposition(|&g| g <= a).unwrap_or(0),
            Branch::Down => grid.iter().position(|&g| g >= a).unwrap_or(grid.len() - 1),
        };
        roots.get(i).copied()
    };
    let silent = crate::core::progress::NoProgress;
    let mut extra: Vec<CaseOutcome> = Vec::new();
    let td = find_touchdown(&search, &known, |acts: &[f64]| -> Result<Vec<bool>> {
        let jobs: Vec<(f64, Option<[f64; 2]>)> = acts.iter().map(|&a| (a, start_near(a))).collect();
        let tag = starts.map_or("", |(_, b)| if b == Branch::Down { "_down" } else { "_up" });
        let done = run_jobs(p, sink, isbl, dmw, &silent, &jobs, tag)?;
        let t = done.iter().map(touches).collect();
        extra.extend(done);
        Ok(t)
    })?;
    extra.sort_by(|a, b| a.actuation.total_cmp(&b.actuation));
    Ok((td, extra))
}

/// The sweep-level analysis of finished cases (sorted by actuation).
pub fn sweep_analysis(p: &SimulateParams, cases: &[CaseOutcome]) -> Result<SweepMetrics> {
    let points: Vec<SweepPoint> = cases
        .iter()
        .map(|c| SweepPoint {
            actuation_m: c.actuation,
            mean_clearance_m: c.metrics.clearance_m.mean,
            any_solid_contact: c.metrics.touches(),
            vibration_percent: c.metrics.vibration_percent,
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

/// A case result's `vibration_kind` as named in the tables and `--json`; cases cached before
/// docs/json.md hold the debug form (`Fhm`, `Bv`).
fn vibration_kind_label(v: &str) -> String {
    match v {
        "Fhm" => "FHM".into(),
        "Bv" => "BV".into(),
        other => other.into(),
    }
}

/// A case result's `regime` as named in the tables (`regime_name`); cases cached before
/// docs/json.md hold the debug form (`SolidContact`, …).
pub fn regime_label(v: &Value) -> Value {
    let name = match v.as_str() {
        Some("Flying") => regime_name(Regime::Flying),
        Some("MobileLubricantContact") => regime_name(Regime::MobileLubricantContact),
        Some("BondedLubricantContact") => regime_name(Regime::BondedLubricantContact),
        Some("SolidContact") => regime_name(Regime::SolidContact),
        _ => return v.clone(),
    };
    json!(name)
}

/// One case: a row of the sweep table (`sweep.{parquet,csv,arrow}`; units in the column
/// names, docs/conventions.md); a non-finite value is null, as in the case's result.json. The
/// field order is the table's column order.
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, serde::Serialize, schemars::JsonSchema)]
pub struct SweepRow {
    /// TFC actuation h_TFC, nm (rounded to the femtometre: 8.8 nm, not 8.799999999999999).
    pub actuation_nm: f64,
    /// Steady mean clearance c̄, nm. `null` when not defined for this input (docs/json.md).
    #[schemars(with = "Option<f64>")]
    pub clearance_mean_nm: f64,
    /// Standard deviation of the clearance, nm. `null` when not defined for this input
    /// (docs/json.md).
    #[schemars(with = "Option<f64>")]
    pub clearance_std_nm: f64,
    /// Mean flying height, nm. `null` when not defined for this input (docs/json.md).
    #[schemars(with = "Option<f64>")]
    pub fh_mean_nm: f64,
    /// Mean head-media spacing, nm. `null` when not defined for this input (docs/json.md).
    #[schemars(with = "Option<f64>")]
    pub hms_mean_nm: f64,
    /// FHM/BV of eq. 2.1 over the steady window, %. `null` when not defined for this input
    /// (docs/json.md).
    #[schemars(with = "Option<f64>")]
    pub vibration_percent: f64,
    /// The same from the extrema, %. `null` when not defined for this input (docs/json.md).
    pub vibration_extrema_percent: Option<f64>,
    /// `FHM` (flying-height modulation: the case flies) or `BV` (bouncing vibration: it
    /// contacts).
    #[schemars(extend("enum" = ["FHM", "BV"]))]
    pub vibration_kind: String,
    /// Share of the steady window in solid contact, %. `null` when not defined for this input
    /// (docs/json.md).
    #[schemars(with = "Option<f64>")]
    pub solid_contact_percent: f64,
    /// Operating regime from c̄ (§1.2).
    #[schemars(extend("enum" = ["flying", "mobile lubricant", "bonded lubricant", "solid contact", null]))]
    pub regime: Option<&'static str>,
    /// Mean contact force, mN; null without a contact model. `null` when not defined for this
    /// input (docs/json.md).
    pub contact_force_mean_mN: Option<f64>,
    /// Mean friction force, mN. `null` when not defined for this input (docs/json.md).
    pub friction_mean_mN: Option<f64>,
    /// Mean adhesion force, mN. `null` when not defined for this input (docs/json.md).
    pub adhesion_mean_mN: Option<f64>,
    /// Mean real contact area, µm². `null` when not defined for this input (docs/json.md).
    pub real_area_mean_um2: Option<f64>,
    /// Mean friction / mean contact force (ratio of means; the headline, docs/conventions.md),
    /// dimensionless; null without contact force. `null` when not defined for this input
    /// (docs/json.md).
    pub friction_coefficient: Option<f64>,
    /// Mean of the instantaneous ratio over samples with F_c > 1 µN, dimensionless. `null`
    /// when not defined for this input (docs/json.md).
    pub friction_coefficient_mean_inst: Option<f64>,
    /// Mean contact pressure (ratio of means), GPa. `null` when not defined for this input
    /// (docs/json.md).
    pub mean_pressure_GPa: Option<f64>,
    /// Mean of the instantaneous contact pressure, GPa. `null` when not defined for this
    /// input (docs/json.md).
    pub mean_pressure_GPa_mean_inst: Option<f64>,
    /// Mean shear traction (ratio of means), GPa. `null` when not defined for this input
    /// (docs/json.md).
    pub shear_traction_GPa: Option<f64>,
    /// Mean of the instantaneous shear traction, GPa. `null` when not defined for this input
    /// (docs/json.md).
    pub shear_traction_GPa_mean_inst: Option<f64>,
    /// Nominal contact area of the bulge, µm². `null` when not defined for this input
    /// (docs/json.md).
    #[schemars(with = "Option<f64>")]
    pub nominal_area_um2: f64,
    /// Flyability ξ (§9), dimensionless. `null` when not defined for this input
    /// (docs/json.md).
    pub flyability: Option<f64>,
    /// Accepted integrator steps.
    pub steps: u64,
    /// Case-cache key; empty outside the pipeline (`hdi simulate` caches nothing).
    pub case_key: String,
    /// The continuation branch (`[simulate]` stage tables only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub branch: Option<&'static str>,
    /// A sweep in heater power (docs/bulge.md): each row also names its power, mW (null where
    /// the actuation has none; `[simulate]` stage tables only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heater_power_mW: Option<Option<f64>>,
}

/// One typed row per case.
pub fn sweep_rows(cases: &[CaseOutcome], sweep: &SweepMetrics) -> Vec<SweepRow> {
    cases
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let m = &c.metrics;
            let stat = |s: &Option<crate::slider::case::Stats>, scale: f64| {
                s.as_ref().map(|s| s.mean * scale)
            };
            let f = |v: Option<f64>, scale: f64| v.map(|x| x * scale);
            SweepRow {
                actuation_nm: (c.actuation * 1e15).round() / 1e6,
                clearance_mean_nm: m.clearance_m.mean * 1e9,
                clearance_std_nm: m.clearance_m.std * 1e9,
                fh_mean_nm: m.fh_m.mean * 1e9,
                hms_mean_nm: m.hms_mean_m * 1e9,
                vibration_percent: m.vibration_percent,
                vibration_extrema_percent: m.vibration_extrema_percent,
                vibration_kind: vibration_kind_label(&m.vibration_kind),
                solid_contact_percent: m.percent_solid_contact,
                regime: sweep.regimes.get(i).map(|r| regime_name(*r)),
                contact_force_mean_mN: stat(&m.contact_force_N, 1e3),
                friction_mean_mN: stat(&m.friction_N, 1e3),
                adhesion_mean_mN: stat(&m.adhesion_N, 1e3),
                real_area_mean_um2: stat(&m.real_area_m2, 1e12),
                friction_coefficient: m.friction_coefficient,
                friction_coefficient_mean_inst: m.friction_coefficient_mean_inst,
                mean_pressure_GPa: f(m.mean_pressure_Pa, 1e-9),
                mean_pressure_GPa_mean_inst: f(m.mean_pressure_Pa_mean_inst, 1e-9),
                shear_traction_GPa: f(m.shear_traction_Pa, 1e-9),
                shear_traction_GPa_mean_inst: f(m.shear_traction_Pa_mean_inst, 1e-9),
                nominal_area_um2: m.nominal_area_m2 * 1e12,
                flyability: sweep.flyability.get(i).copied(),
                steps: m.steps,
                case_key: c.entry.key.clone(),
                branch: None,
                heater_power_mW: None,
            }
        })
        .collect()
}

/// [`sweep_rows`] as table rows (`core::store::write_table`).
pub fn case_rows(cases: &[CaseOutcome], sweep: &SweepMetrics) -> Vec<Map<String, Value>> {
    crate::core::store::rows_of(&sweep_rows(cases, sweep))
}

/// Branches whose steady mean clearances differ by more than this (0.05 nm, a quarter of the
/// 0.2 nm actuation step, well above run-to-run integration noise) count as hysteresis.
pub const HYSTERESIS_TOLERANCE_M: f64 = 0.05e-9;

/// `(actuation, steady mean clearance)` of each case (m).
pub fn clearance_curve(cases: &[CaseOutcome]) -> Vec<(f64, f64)> {
    cases
        .iter()
        .map(|c| (c.actuation, c.metrics.clearance_m.mean))
        .collect()
}

/// Where two branches differ.
#[derive(Debug, Clone, PartialEq)]
pub struct Hysteresis {
    pub tolerance_m: f64,
    /// Lowest and highest actuation at which the branches differ by more than the tolerance
    /// (`None` when they never do).
    pub from_m: Option<f64>,
    pub to_m: Option<f64>,
    /// Largest |c̄_up − c̄_down| over the shared actuations, and where.
    pub max_difference_m: f64,
    pub max_at_m: Option<f64>,
    /// Every shared actuation beyond the tolerance.
    pub actuations_m: Vec<f64>,
}

/// Compare two branches' `(actuation, clearance)` curves at their shared actuations (matched
/// to 1e-15 m); non-finite clearances are skipped.
pub fn hysteresis(up: &[(f64, f64)], down: &[(f64, f64)], tolerance_m: f64) -> Hysteresis {
    let mut h = Hysteresis {
        tolerance_m,
        from_m: None,
        to_m: None,
        max_difference_m: 0.0,
        max_at_m: None,
        actuations_m: Vec::new(),
    };
    let mut pairs: Vec<(f64, f64)> = up
        .iter()
        .filter_map(|&(a, cu)| {
            let (_, cd) = down.iter().find(|(b, _)| (a - b).abs() <= 1e-15)?;
            let d = (cu - cd).abs();
            d.is_finite().then_some((a, d))
        })
        .collect();
    pairs.sort_by(|x, y| x.0.total_cmp(&y.0));
    for (a, d) in pairs {
        if d > h.max_difference_m {
            h.max_difference_m = d;
            h.max_at_m = Some(a);
        }
        if d > tolerance_m {
            h.from_m.get_or_insert(a);
            h.to_m = Some(a);
            h.actuations_m.push(a);
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    const NM: f64 = 1e-9;

    #[test]
    fn hysteresis_reports_the_interval_and_the_largest_gap() {
        // Branches agree except 9.2–9.6 nm, where the down branch sits 1 nm lower (the
        // contact branch surviving below the fold), and a sub-tolerance wobble at 10 nm.
        let grid: Vec<f64> = (40..=55).map(|i| i as f64 * 0.2 * NM).collect();
        let up: Vec<(f64, f64)> = grid.iter().map(|&a| (a, 12.0 * NM - a)).collect();
        let down: Vec<(f64, f64)> = grid
            .iter()
            .map(|&a| {
                let gap = if (9.1 * NM..9.7 * NM).contains(&a) {
                    1.0 * NM + (a - 9.2 * NM)
                } else if (a - 10.0 * NM).abs() < 1e-12 {
                    0.04 * NM
                } else {
                    0.0
                };
                (a, 12.0 * NM - a - gap)
            })
            .collect();
        let h = hysteresis(&up, &down, HYSTERESIS_TOLERANCE_M);
        assert!((h.from_m.unwrap() - 9.2 * NM).abs() < 1e-15);
        assert!((h.to_m.unwrap() - 9.6 * NM).abs() < 1e-15);
        assert_eq!(h.actuations_m.len(), 3);
        assert!((h.max_difference_m - 1.4 * NM).abs() < 1e-15);
        assert!((h.max_at_m.unwrap() - 9.6 * NM).abs() < 1e-15);
        // Identical branches: no interval.
        let same = hysteresis(&up, &up, HYSTERESIS_TOLERANCE_M);
        assert_eq!(
            (same.from_m, same.to_m, same.max_difference_m),
            (None, None, 0.0)
        );
    }

    #[test]
    fn branches_key() {
        assert_eq!(
            Branch::parse(None, true).unwrap(),
            vec![Branch::Up, Branch::Down]
        );
        assert_eq!(
            Branch::parse(Some("down"), true).unwrap(),
            vec![Branch::Down]
        );
        assert_eq!(Branch::parse(None, false).unwrap(), vec![]);
        assert!(Branch::parse(Some("both"), false).is_err());
        let e = Branch::parse(Some("sideways"), true).unwrap_err();
        assert!(
            e.contains("sideways") && e.contains("both, up, down"),
            "{e}"
        );
    }

    /// Case results cached before the enum names were made explicit (docs/json.md) still
    /// give the tables' names; new results already have them.
    #[test]
    fn legacy_debug_enum_names_read_as_explicit_names() {
        assert_eq!(vibration_kind_label("Fhm"), "FHM");
        assert_eq!(vibration_kind_label("Bv"), "BV");
        assert_eq!(vibration_kind_label("BV"), "BV");
        assert_eq!(regime_label(&json!("SolidContact")), "solid contact");
        assert_eq!(
            regime_label(&json!("MobileLubricantContact")),
            "mobile lubricant"
        );
        assert_eq!(regime_label(&json!("flying")), "flying");
        assert_eq!(regime_label(&Value::Null), Value::Null);
    }
}
