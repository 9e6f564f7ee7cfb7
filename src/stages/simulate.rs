//! Simulation stage: 2-DOF slider cases (§2.1–2.2; docs/simulation.md) over an actuation
//! sweep, each case cached by content hash (`core::cases`), run in parallel reporting to a
//! progress observer; per-case HDF5 time histories, the sweep table, the flyability metrics
//! of §8 and the dissertation's plots (Figs 2.13–2.14, 2.16–2.19, 2.22).

use super::case_engine::{CaseEngine, Listing, PreparedCases, SweepCases, UpstreamEntries};
use super::{FromConfig, Output, StageContext, StageKind};
use crate::artefacts::ordered::OrderedMap;
use crate::artefacts::simulate::{
    BranchSweep, CalibratedKnob, CaseRegime, CriticalPoint, ExtraCase, HysteresisResult,
    SimulateCase, SimulateResult, SimulateSweep, SlopeFit, SweepSummary, TouchdownConvention,
};
use crate::core::config::{ConfigError, PipelineFile};
use crate::dynamics::metrics::{Regime, SweepMetrics};
use crate::dynamics::touchdown::Touchdown;
use crate::error::Result;
use crate::slider::case::{read_case_history, SweepCaseResult, CASE_FILE, MODEL_VERSION};
use crate::slider::params::SimulateParams;
use crate::slider::sweep::{
    clearance_curve, convention_touchdown, hysteresis, link_cases_tagged, regime_name, run_jobs,
    sweep_analysis, sweep_rows, Branch, CaseOutcome, CaseSink, Hysteresis, PreparedSweep,
    SweepPlan, SweepRow, HYSTERESIS_TOLERANCE_M,
};
use serde::Serialize;
use serde_json::Value;
use std::path::Path;
use std::sync::Arc;

/// The `[simulate.NAME]` table (checked by `SimulateParams`).
pub use crate::slider::params::SimulateConfig;

/// One branch's sweep metrics as the result writes them.
fn sweep_summary(cases: &[CaseOutcome], s: &SweepMetrics) -> SweepSummary {
    let line = |l: &Option<crate::dynamics::metrics::LineFit>| {
        l.as_ref().map(|l| SlopeFit {
            slope: l.slope,
            intercept_m: l.intercept_m,
            rms_residual_m: l.rms_residual_m,
            actuations_m: l.indices.iter().map(|&i| cases[i].actuation).collect(),
        })
    };
    SweepSummary {
        touchdown_m: s.touchdown_actuation_m,
        critical_point: s.slopes.critical_point.as_ref().map(|c| CriticalPoint {
            actuation_m: c.actuation_m,
            clearance_m: c.clearance_m,
        }),
        slope_A: line(&s.slopes.a),
        slope_B: line(&s.slopes.b),
        slope_C: line(&s.slopes.c),
        slope_D: line(&s.slopes.d),
        optimum_m: s.optimum_index.map(|i| cases[i].actuation),
        regimes: cases
            .iter()
            .zip(&s.regimes)
            .map(|(c, r)| CaseRegime {
                actuation_m: c.actuation,
                regime: regime_name(*r).to_string(),
            })
            .collect(),
    }
}

/// One branch of a sweep (or the only sweep, `branch` `None`, with the nominal start): its
/// grid cases, their sweep metrics, touchdown by the convention and the extra cases it ran.
pub struct BranchRun {
    pub branch: Option<Branch>,
    pub cases: Vec<CaseOutcome>,
    pub sweep: SweepMetrics,
    pub touchdown: Touchdown,
    pub extra: Vec<CaseOutcome>,
}

/// `up`, `down`, or `nominal` for a one-sweep (nominal-start) instance.
fn branch_name(b: Option<Branch>) -> &'static str {
    b.map_or("nominal", Branch::name)
}

/// The convention's touchdown of one branch (docs/conventions.md) with the cases it added.
fn touchdown_convention(r: &BranchRun) -> TouchdownConvention {
    TouchdownConvention {
        actuation_m: r.touchdown.actuation,
        last_flying_m: r.touchdown.last_flying,
        resolution_m: crate::dynamics::touchdown::TouchdownSearch::convention(1.0, 1.0, 1)
            .resolution,
        grid_touchdown_m: r.sweep.touchdown_actuation_m,
        extra_cases: r
            .extra
            .iter()
            .map(|c| ExtraCase {
                actuation_m: c.actuation,
                solid_contact_percent: c.metrics.percent_solid_contact,
                clearance_mean_m: c.metrics.clearance_m.mean,
                case_key: c.entry.key.clone(),
            })
            .collect(),
    }
}

/// Where the up and down branches' steady clearances differ, and whether their touchdowns
/// and critical points coincide.
fn hysteresis_result(h: &Hysteresis, runs: &[BranchRun]) -> HysteresisResult {
    let cp = |r: &BranchRun| {
        r.sweep
            .slopes
            .critical_point
            .as_ref()
            .map(|c| c.actuation_m)
    };
    let (u, d) = (&runs[0], &runs[1]);
    let res = crate::dynamics::touchdown::TouchdownSearch::convention(1.0, 1.0, 1).resolution;
    let same = |a: Option<f64>, b: Option<f64>, tol: f64| match (a, b) {
        (Some(a), Some(b)) => (a - b).abs() <= tol,
        (None, None) => true,
        _ => false,
    };
    HysteresisResult {
        tolerance_m: h.tolerance_m,
        from_m: h.from_m,
        to_m: h.to_m,
        max_difference_m: h.max_difference_m,
        max_difference_at_m: h.max_at_m,
        differing_actuations_m: h.actuations_m.clone(),
        touchdown_coincides: same(
            u.touchdown.actuation,
            d.touchdown.actuation,
            res * (1.0 + 1e-9),
        ),
        critical_point_coincides: same(cp(u), cp(d), 1e-12),
    }
}

/// Contiguous runs of the same regime as (x0, x1, regime) bands, x in nm, edges halfway
/// between neighbouring cases.
fn regime_bands(cases: &[CaseOutcome], s: &SweepMetrics) -> Vec<(f64, f64, Regime)> {
    let x: Vec<f64> = cases.iter().map(|c| c.actuation * 1e9).collect();
    let mut bands = Vec::new();
    let mut start = 0;
    for i in 1..=x.len() {
        if i == x.len() || s.regimes[i] != s.regimes[start] {
            let lo = if start == 0 {
                x[0]
            } else {
                0.5 * (x[start - 1] + x[start])
            };
            let hi = if i == x.len() {
                x[i - 1]
            } else {
                0.5 * (x[i - 1] + x[i])
            };
            bands.push((lo, hi, s.regimes[start]));
            start = i;
        }
    }
    bands
}

/// Figs 2.16/2.18 (clearance ± std with regimes, every branch), 2.19 (FHM/BV), 2.22 (% solid
/// contact) and time histories at the chosen actuations (Figs 2.13–2.14, 2.17) of the first
/// branch.
pub fn plots(dir: &Path, p: &SimulateParams, runs: &[BranchRun], title: &str) -> Result<()> {
    sweep_figures(dir, p, runs, title)?;
    let cases = &runs[0].cases;
    for &want in &p.histories {
        let Some(c) = cases.iter().min_by(|a, b| {
            (a.actuation - want)
                .abs()
                .total_cmp(&(b.actuation - want).abs())
        }) else {
            continue;
        };
        history_figure(dir, c, title)?;
    }
    Ok(())
}

/// Figs 2.16/2.18 (clearance ± std with regimes), 2.19 (FHM/BV) and 2.22 (% solid contact)
/// against the actuation.
fn sweep_figures(dir: &Path, p: &SimulateParams, runs: &[BranchRun], title: &str) -> Result<()> {
    let (cases, s) = (&runs[0].cases, &runs[0].sweep);
    use crate::figures::{clearance_sweep_png, metric_sweep_png, RegimeBand, SweepSeries};
    // A sweep stated in heater power is drawn against the power (docs/bulge.md):
    // P = actuation / efficiency; otherwise against the actuation in nm.
    let (per_m, axis, short, long) = match p.efficiency {
        Some(e) => (1e3 / e, "heater power (mW)", "heater power", "heater power"),
        None => (1e9, "TFC actuation (nm)", "actuation", "TFC actuation"),
    };
    let clearance = |cases: &[CaseOutcome]| -> Vec<(f64, f64, f64)> {
        cases
            .iter()
            .map(|c| {
                (
                    c.actuation * per_m,
                    c.metrics.clearance_m.mean * 1e9,
                    c.metrics.clearance_m.std * 1e9,
                )
            })
            .collect()
    };
    // Each branch labelled with its touchdown (the convention's, refined) and critical point.
    let fmt = |x: Option<f64>| x.map_or("none".to_string(), |v| format!("{:.2}", v * per_m));
    let labels: Vec<String> = runs
        .iter()
        .map(|r| {
            let name = match r.branch {
                None => "mean ± 1 std".to_string(),
                Some(b) => format!("{} branch, mean ± 1 std", b.name()),
            };
            format!(
                "{name}; TD {}, CP {}",
                fmt(r.touchdown.actuation),
                fmt(r
                    .sweep
                    .slopes
                    .critical_point
                    .as_ref()
                    .map(|c| c.actuation_m))
            )
        })
        .collect();
    let series: Vec<SweepSeries> = runs
        .iter()
        .zip(&labels)
        .map(|(r, l)| SweepSeries {
            label: l,
            points: clearance(&r.cases),
        })
        .collect();
    let bands = regime_bands(cases, s);
    let bands: Vec<RegimeBand> = bands
        .iter()
        .map(|(x0, x1, r)| RegimeBand {
            x0: x0 * (per_m / 1e9),
            x1: x1 * (per_m / 1e9),
            label: regime_name(*r),
        })
        .collect();
    let t0 = 0.5 * p.model.interface.lubricant_thickness * 1e9;
    clearance_sweep_png(
        &dir.join("clearance_sweep.png"),
        &format!("Steady clearance vs {long} — {title}"),
        axis,
        "clearance (nm)",
        &series,
        &bands,
        &[(0.0, "solid contact"), (t0, "T0"), (2.0 * t0, "2T0")],
    )?;
    let mut marks: Vec<(f64, &str)> = Vec::new();
    if let Some(td) = runs[0].touchdown.actuation {
        marks.push((td * per_m, "touchdown"));
    }
    if let Some(cp) = &s.slopes.critical_point {
        marks.push((cp.actuation_m * per_m, "critical point"));
    }
    let series = |of: fn(&SweepCaseResult) -> f64| -> Vec<(f64, f64)> {
        cases
            .iter()
            .map(|c| (c.actuation * per_m, of(&c.metrics)))
            .collect()
    };
    metric_sweep_png(
        &dir.join("vibration_sweep.png"),
        &format!("FHM (flying) / BV (contact) vs {short} — {title}"),
        axis,
        "FHM / BV (%)",
        &[
            (
                "eq. 2.1, 5 largest/smallest samples",
                series(|m| m.vibration_percent),
            ),
            (
                "5 largest/smallest local extrema",
                series(|m| m.vibration_extrema_percent.unwrap_or(f64::NAN)),
            ),
        ],
        &marks,
    )?;
    metric_sweep_png(
        &dir.join("solid_contact_sweep.png"),
        &format!("Time in solid contact vs {short} — {title}"),
        axis,
        "solid contact (% of the steady window)",
        &[("solid contact", series(|m| m.percent_solid_contact))],
        &marks,
    )?;
    Ok(())
}

/// Time histories of one case (Figs 2.13–2.14, 2.17): clearance, forces, μ, P_m and τ.
fn history_figure(dir: &Path, c: &CaseOutcome, title: &str) -> Result<()> {
    use crate::figures::{time_histories_png, Panel};
    let (time, series) = read_case_history(&c.entry.dir.join(CASE_FILE))?;
    let ms: Vec<f64> = time.iter().map(|t| t * 1e3).collect();
    let get = |n: &str| {
        series
            .iter()
            .find(|(k, _)| k == n)
            .map(|(_, v)| v.as_slice())
            .unwrap_or(&[])
    };
    let pair = |v: &[f64], scale: f64| -> Vec<(f64, f64)> {
        ms.iter().zip(v).map(|(t, y)| (*t, y * scale)).collect()
    };
    let fc = get("contact_force");
    let q = get("friction");
    let ar = get("real_area");
    // μ, P_m and τ only where F_c > 1 µN, as the metrics define them (docs/dynamics-metrics.md).
    let loaded = |num: &[f64], den: &[f64], scale: f64| -> Vec<(f64, f64)> {
        ms.iter()
            .zip(fc)
            .zip(num.iter().zip(den))
            .filter(|((_, f), _)| **f > 1e-6)
            .map(|((t, _), (n, d))| (*t, n / d * scale))
            .collect()
    };
    let mu = loaded(q, fc, 1.0);
    let pm = loaded(fc, ar, 1e-9);
    let tau = loaded(q, ar, 1e-9);
    let name = format!("history_{:.2}nm.png", c.actuation * 1e9);
    time_histories_png(
        &dir.join(name),
        &format!(
            "{title}: h_TFC = {:.2} nm (Figs 2.13–2.14, 2.17)",
            c.actuation * 1e9
        ),
        &[
            Panel {
                y_desc: "clearance (nm)",
                series: vec![("clearance", pair(get("clearance"), 1e9))],
            },
            Panel {
                y_desc: "force (mN)",
                series: vec![
                    ("contact F_c", pair(fc, 1e3)),
                    ("friction Q", pair(q, 1e3)),
                    ("adhesion F_s", pair(get("adhesion"), 1e3)),
                ],
            },
            Panel {
                y_desc: "μ = Q/F_c",
                series: vec![("μ", mu)],
            },
            Panel {
                y_desc: "GPa",
                series: vec![("P_m = F_c/A_r", pm), ("τ = Q/A_r", tau)],
            },
        ],
    )?;
    Ok(())
}

/// A `[simulate.NAME]` instance.
pub struct SimulateStage {
    pub name: String,
    pub params: SimulateParams,
}

impl FromConfig for SimulateStage {
    type Config = SimulateConfig;

    fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &SimulateConfig,
    ) -> std::result::Result<Self, ConfigError> {
        Ok(Self {
            name: name.to_string(),
            params: SimulateParams::from_config(file, name, cfg)?,
        })
    }
}

impl StageKind for SimulateStage {
    const KIND: &'static str = "simulate";
    const MODEL_VERSION: &'static str = MODEL_VERSION;
    type Result = SimulateResult;
    type Row = SimulateRow;

    fn params(&self) -> Value {
        self.params.canonical()
    }
    fn upstream(&self) -> Vec<String> {
        self.params.upstream()
    }
    const CASE_KIND: Option<&'static str> = Some(SIMULATE_CASE);
    fn case_engine(&self) -> Option<&dyn CaseEngine> {
        Some(self)
    }
    fn run(&self, ctx: &StageContext) -> Result<Output<SimulateResult, SimulateRow>> {
        ctx.progress.set_message("interface table");
        let prepared = self.prepare(&ctx.upstream_entries())?;
        let p = &prepared.params;
        let isbl = &prepared.isbl;
        let track = prepared.dmw.as_ref().map(|(t, _)| t);
        let sink = CaseSink::Store {
            store: ctx.store,
            prepared: &prepared,
        };
        ctx.progress
            .set_message("static equilibria by continuation");
        // The same plan an executor lists (`case_engine`): the grid, each branch's starts.
        let SweepPlan {
            grid,
            branches,
            starts,
        } = prepared.plan()?;
        let jobs = plan_jobs(&grid, &starts);
        ctx.progress.set_message(format!("{} cases", jobs.len()));
        let all = run_jobs(p, &sink, isbl, track, ctx.progress, &jobs, "")?;
        ctx.progress
            .set_message("touchdown refinement, sweep metrics, tables, plots");
        let case_keys: Vec<String> = all.iter().map(|c| c.entry.key.clone()).collect();
        // How many came from the store is a fact of this run, not a result (it depends on
        // what ran before and, for cases two branches share, on timing): manifest only.
        ctx.log_run(
            "cases_cached",
            Value::from(all.iter().filter(|c| c.entry.cached).count()),
        );
        let runs = branch_runs(&prepared, &sink, all, &branches, &starts, grid.len())?;
        let mut files: Vec<Vec<String>> = Vec::new();
        for (k, r) in runs.iter().enumerate() {
            let sub = (k > 0).then(|| branch_name(r.branch));
            files.push(link_cases_tagged(ctx.out_dir, &r.cases, sub)?);
        }
        let rows = crate::core::store::rows_of(&branch_rows(p, &runs));
        crate::core::store::write_table(&rows, &ctx.out_dir.join("sweep"))?;
        let hysteresis = match (runs.first(), runs.get(1)) {
            (Some(u), Some(d)) => Some(hysteresis(
                &clearance_curve(&u.cases),
                &clearance_curve(&d.cases),
                HYSTERESIS_TOLERANCE_M,
            )),
            _ => None,
        };
        plots(ctx.out_dir, p, &runs, &self.name)?;
        let touchdown_power = p
            .efficiency
            .and_then(|e| runs[0].sweep.touchdown_actuation_m.map(|td| td / e));
        let row = summary_row(p, &runs, jobs.len(), touchdown_power, hysteresis.as_ref());
        let result = stage_result(
            p,
            &runs,
            &files,
            case_keys,
            touchdown_power,
            hysteresis.as_ref(),
        );
        Ok(Output {
            result,
            summary_row: Some(row),
        })
    }
}

/// The sweep's jobs, branch by branch in grid order: each actuation with its continuation
/// start (`None`: nominal start).
fn plan_jobs(grid: &[f64], starts: &[Option<Vec<[f64; 2]>>]) -> Vec<(f64, Option<[f64; 2]>)> {
    starts
        .iter()
        .flat_map(|s| {
            grid.iter()
                .enumerate()
                .map(move |(i, &a)| (a, s.as_ref().map(|s| s[i])))
        })
        .collect()
}

/// Split the cases run (branch by branch, `grid_len` each) into branches, each with its sweep
/// metrics and its touchdown by the convention (which may run extra cases).
fn branch_runs(
    prepared: &PreparedSweep,
    sink: &CaseSink,
    all: Vec<CaseOutcome>,
    branches: &[Option<Branch>],
    starts: &[Option<Vec<[f64; 2]>>],
    grid_len: usize,
) -> Result<Vec<BranchRun>> {
    let p = &prepared.params;
    let isbl = &prepared.isbl;
    let track = prepared.dmw.as_ref().map(|(t, _)| t);
    let mut all = all.into_iter();
    let mut runs: Vec<BranchRun> = Vec::new();
    for (branch, start) in branches.iter().zip(starts) {
        let cases: Vec<CaseOutcome> = all.by_ref().take(grid_len).collect();
        let sweep = sweep_analysis(p, &cases)?;
        let (touchdown, extra) =
            convention_touchdown(p, sink, isbl, track, &cases, start.as_deref().zip(*branch))?;
        runs.push(BranchRun {
            branch: *branch,
            cases,
            sweep,
            touchdown,
            extra,
        });
    }
    Ok(runs)
}

/// The sweep table's rows: every branch's cases, each row naming its branch (and its heater
/// power in a sweep stated in power, docs/bulge.md).
fn branch_rows(p: &SimulateParams, runs: &[BranchRun]) -> Vec<SweepRow> {
    let mut rows = Vec::new();
    for r in runs {
        let mut branch_rows = sweep_rows(&r.cases, &r.sweep);
        for (row, c) in branch_rows.iter_mut().zip(&r.cases) {
            row.branch = Some(branch_name(r.branch));
            if p.efficiency.is_some() {
                row.heater_power_mW =
                    Some(p.power_of(c.actuation).map(|w| (w * 1e12).round() / 1e9));
            }
        }
        rows.extend(branch_rows);
    }
    rows
}

/// Femtometre-rounded nm: 10.2, not 10.200000000000001.
fn nm(x: f64) -> f64 {
    (x * 1e15).round() / 1e6
}

/// The instance's row of the run's summary table (lengths in nm, femtometre-rounded where
/// they are actuations): touchdown, critical point, slopes, optimum and hysteresis of the
/// sweep. The field order is the table's column order.
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SimulateRow {
    pub model: String,
    pub geometry: String,
    pub calibration: Option<String>,
    /// Grid cases run, every branch.
    pub cases: usize,
    /// The first branch's grid touchdown, the convention's refined one and critical point.
    pub touchdown_nm: Option<f64>,
    pub touchdown_refined_nm: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub critical_point_nm: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub critical_clearance_nm: Option<f64>,
    /// The same columns of every further branch, its name in them (`touchdown_down_nm`).
    #[serde(flatten)]
    pub other_branches: OtherBranches,
    pub slope_A: Option<f64>,
    pub slope_B: Option<f64>,
    pub slope_C: Option<f64>,
    pub slope_D: Option<f64>,
    /// A sweep stated in heater power only (docs/bulge.md).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub touchdown_power_mW: Option<Option<f64>>,
    pub optimum_nm: Option<f64>,
    /// Two branches only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hysteresis_from_nm: Option<Option<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hysteresis_to_nm: Option<Option<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hysteresis_max_nm: Option<f64>,
}

/// Touchdown and critical point columns of one branch after the first.
#[derive(Debug, Clone, PartialEq)]
pub struct BranchColumns {
    pub branch: &'static str,
    pub touchdown_nm: Option<f64>,
    pub touchdown_refined_nm: Option<f64>,
    /// Critical point actuation and clearance, nm.
    pub critical: Option<(f64, f64)>,
}

/// The columns of the branches after the first, each column named with its branch.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct OtherBranches(pub Vec<BranchColumns>);

impl Serialize for OtherBranches {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(None)?;
        for b in &self.0 {
            let sfx = b.branch;
            m.serialize_entry(&format!("touchdown_{sfx}_nm"), &b.touchdown_nm)?;
            m.serialize_entry(
                &format!("touchdown_refined_{sfx}_nm"),
                &b.touchdown_refined_nm,
            )?;
            if let Some((actuation, clearance)) = b.critical {
                m.serialize_entry(&format!("critical_point_{sfx}_nm"), &actuation)?;
                m.serialize_entry(&format!("critical_clearance_{sfx}_nm"), &clearance)?;
            }
        }
        m.end()
    }
}

/// The instance's row of the run's summary table (a second branch adds its touchdown and
/// critical point).
fn summary_row(
    p: &SimulateParams,
    runs: &[BranchRun],
    n_cases: usize,
    touchdown_power: Option<f64>,
    hysteresis: Option<&Hysteresis>,
) -> SimulateRow {
    let first = &runs[0];
    let (cases, sweep) = (&first.cases, &first.sweep);
    let critical = |r: &BranchRun| {
        r.sweep
            .slopes
            .critical_point
            .as_ref()
            .map(|cp| (cp.actuation_m * 1e9, cp.clearance_m * 1e9))
    };
    let slope = |l: &Option<crate::dynamics::metrics::LineFit>| l.as_ref().map(|l| l.slope);
    SimulateRow {
        model: p.model_name.clone(),
        geometry: p.geometry.clone(),
        calibration: p.calibration.clone(),
        cases: n_cases,
        touchdown_nm: sweep.touchdown_actuation_m.map(nm),
        touchdown_refined_nm: first.touchdown.actuation.map(nm),
        critical_point_nm: critical(first).map(|c| c.0),
        critical_clearance_nm: critical(first).map(|c| c.1),
        other_branches: OtherBranches(
            runs[1..]
                .iter()
                .map(|r| BranchColumns {
                    branch: branch_name(r.branch),
                    touchdown_nm: r.sweep.touchdown_actuation_m.map(nm),
                    touchdown_refined_nm: r.touchdown.actuation.map(nm),
                    critical: critical(r),
                })
                .collect(),
        ),
        slope_A: slope(&sweep.slopes.a),
        slope_B: slope(&sweep.slopes.b),
        slope_C: slope(&sweep.slopes.c),
        slope_D: slope(&sweep.slopes.d),
        touchdown_power_mW: p
            .efficiency
            .map(|_| touchdown_power.map(|w| (w * 1e9).round() / 1e6)),
        optimum_nm: sweep.optimum_index.map(|i| nm(cases[i].actuation)),
        hysteresis_from_nm: hysteresis.map(|h| h.from_m.map(nm)),
        hysteresis_to_nm: hysteresis.map(|h| h.to_m.map(nm)),
        hysteresis_max_nm: hysteresis.map(|h| (h.max_difference_m * 1e15).round() / 1e6),
    }
}

/// The stage's `result.json`: the first branch's sweep, every case with its HDF5 file, the case
/// keys, the calibration, and (with two branches) each branch and their hysteresis.
fn stage_result(
    p: &SimulateParams,
    runs: &[BranchRun],
    files: &[Vec<String>],
    case_keys: Vec<String>,
    touchdown_power: Option<f64>,
    hysteresis: Option<&Hysteresis>,
) -> SimulateResult {
    let first = &runs[0];
    let sweep = SimulateSweep {
        metrics: sweep_summary(&first.cases, &first.sweep),
        branch: branch_name(first.branch).to_string(),
        touchdown_convention: touchdown_convention(first),
        efficiency_m_per_W: p.efficiency,
        touchdown_power_W: p.efficiency.map(|_| touchdown_power),
    };
    let cases = runs
        .iter()
        .zip(files)
        .flat_map(|(r, f)| {
            r.cases.iter().zip(f).map(|(c, f)| SimulateCase {
                actuation_m: c.actuation,
                branch: branch_name(r.branch).to_string(),
                h5: f.clone(),
                metrics: c.metrics.clone(),
            })
        })
        .collect();
    let branches = runs.iter().any(|r| r.branch.is_some()).then(|| {
        OrderedMap(
            runs.iter()
                .map(|r| {
                    let b = BranchSweep {
                        metrics: sweep_summary(&r.cases, &r.sweep),
                        touchdown_convention: touchdown_convention(r),
                    };
                    (branch_name(r.branch).to_string(), b)
                })
                .collect(),
        )
    });
    SimulateResult {
        sweep,
        cases,
        case_keys,
        calibration: p.calibration.clone(),
        calibrated_knobs: p
            .calibrated_knobs
            .iter()
            .map(|(k, v)| CalibratedKnob {
                knob: k.clone(),
                value: *v,
            })
            .collect(),
        table: "sweep.parquet".to_string(),
        branches,
        hysteresis: hysteresis.map(|h| hysteresis_result(h, runs)),
    }
}

// ------------------------------------------------------------------------------------------
// The sweep's cases through the stage contract's case capability (`case_engine`)
// ------------------------------------------------------------------------------------------

/// Case kind of a 2-DOF sweep point.
pub const SIMULATE_CASE: &str = "simulate";

impl SimulateStage {
    /// The shared inputs of every case (calibrated parameters, interface table, DMW track):
    /// the one preparation a local run and a Slurm worker both make.
    pub fn prepare(&self, upstream: &UpstreamEntries) -> Result<PreparedSweep> {
        PreparedSweep::prepare(&self.params, &upstream.results, &upstream.dirs, |n| {
            upstream.key_of(n)
        })
    }
}

impl CaseEngine for SimulateStage {
    fn prepare_cases(&self, upstream: &UpstreamEntries) -> Result<Arc<dyn PreparedCases>> {
        Ok(Arc::new(SweepCases {
            kind: SIMULATE_CASE,
            sweep: self.prepare(upstream)?,
            listing: Listing::Plan,
        }))
    }
}
