//! Design-of-experiments stage (dissertation §2.3; docs/doe.md): a 3³ full factorial in the
//! bulge geometry (`a_TFC`, `w_TFC`, `x_TFC`) crossed with actuation levels, every point a cached
//! improved-2-DOF case (the `[simulate]` stage's own case cache, so a killed run loses no
//! finished case); polynomial response surfaces of the flyability parameter ξ with ANOVA and
//! residual diagnostics per level; Table 2.7's predictive equations; simulated annealing on ξ
//! with a sensitivity check; and Table 2.8, the 2-DOF sweep on the initial and optimised designs.

use super::case_engine::{CaseEngine, Listing, PreparedCases, SweepCases, UpstreamEntries};
use super::{FromConfig, Output, StageContext, StageKind};
use crate::artefacts::doe::{DesignM, DesignSpread, DoeOptimum, DoeResult};
use crate::core::config::{ConfigError, PipelineFile};
use crate::core::store::rows_of;
use crate::error::Result;
use crate::numerics::annealing::StopReason;
use crate::numerics::regression::full_factorial;
use crate::slider::calibration::base_inputs;
use crate::slider::doe::cases::{CaseRunner, DesignCase};
use crate::slider::doe::figures::{
    annealing_convergence_png, comparison_png, contour_png, residuals_png,
};
use crate::slider::doe::optimise::{self, Annealing, Comparison, Objective, Sensitivity};
use crate::slider::doe::params::{NM, UM};
use crate::slider::doe::surface::{fit_levels, model_selection, LevelFit};
use crate::slider::doe::tables::{
    annealing_rows, anova_rows, coefficient_rows, design_rows, fit_summary, predictive_rows,
    table_value,
};
use crate::slider::doe_design::design_cases;
use crate::slider::params::uncalibrated_base;
use crate::slider::sweep::{PreparedSweep, SweepCase};
use rayon::prelude::*;
use serde::Serialize;
use serde_json::Value;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

pub use crate::slider::doe::params::{check, DoeConfig, DoeParams, SaObjective, FACTORS};

/// Bump when the numbers the stage derives from its cases change (the cases themselves carry
/// the simulate stage's model version).
/// doe-3: annealing settings and objective as plain JSON in the key (same numbers).
pub const MODEL_VERSION: &str = "doe-3";

/// Validated stage instance.
pub struct DoeStage {
    pub name: String,
    pub params: DoeParams,
}

impl FromConfig for DoeStage {
    type Config = DoeConfig;

    fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &DoeConfig,
    ) -> std::result::Result<Self, ConfigError> {
        let err = |k: &str, m: String| file.error("doe", name, k, m);
        let base = uncalibrated_base(file, "doe", name, &cfg.simulate)?;
        let params = check(cfg, base, &cfg.simulate).map_err(|e| err(&e.key, e.message))?;
        if let Some(b) = &params.bulge {
            if !file.has_instance("bulge", b) {
                return Err(err("geometry", format!("no [bulge.{b}] in this file")));
            }
        }
        Ok(DoeStage {
            name: name.to_string(),
            params,
        })
    }
}

impl StageKind for DoeStage {
    const KIND: &'static str = "doe";
    const MODEL_VERSION: &'static str = MODEL_VERSION;
    type Result = DoeResult;
    type Row = DoeRow;
    const CASE_KIND: Option<&'static str> = Some(DOE_CASE);
    fn case_engine(&self) -> Option<&dyn CaseEngine> {
        Some(self)
    }

    fn params(&self) -> Value {
        self.params.canonical()
    }
    fn upstream(&self) -> Vec<String> {
        // The base is uncalibrated: its contact and DMW instances (and its bulge).
        let mut u = self.params.base.upstream();
        if let Some(b) = &self.params.bulge {
            if !u.contains(b) {
                u.push(b.clone());
            }
        }
        u
    }
    fn run(&self, ctx: &StageContext) -> Result<Output<DoeResult, DoeRow>> {
        ctx.progress.set_message("interface table");
        let (p, sweep) = self.prepare(&ctx.upstream_entries())?;
        let p = &p;
        let runner = CaseRunner {
            base: &p.base,
            sweep: &sweep,
            store: ctx.store,
        };
        // Annealing on simulations needs neither the design nor its fits, and is sequential
        // (each step a slider case): it runs beside the design's parallel cases instead of
        // after them, where it held one core of a 2-core cold run for ~3 s (docs/doe.md).
        // The same cases in the same order: the outputs are those of the sequential order.
        let early = p.optimise && p.sa_objective == SaObjective::Simulation;
        let (design_and_fits, early_annealing) = rayon::join(
            || -> Result<_> {
                let design = run_design(p, ctx, &runner)?;
                let surfaces = fit_surfaces(p, ctx, &design)?;
                draw_fit_figures(p, ctx, &surfaces.fits, &design.designs)?;
                Ok((design, surfaces))
            },
            || {
                early.then(|| {
                    let objective = Objective {
                        p,
                        runner: &runner,
                        fits: &[],
                    };
                    anneal(p, ctx, &objective)
                })
            },
        );
        let (design, surfaces) = design_and_fits?;
        let optimum = if p.optimise {
            let objective = Objective {
                p,
                runner: &runner,
                fits: &surfaces.fits,
            };
            let annealing = match early_annealing {
                Some(a) => a?,
                None => anneal(p, ctx, &objective)?,
            };
            let sensitivity = check_sensitivity(p, ctx, &objective, &annealing)?;
            let comparison = if p.compare {
                Some(compare_designs(p, ctx, &runner, annealing.best)?)
            } else {
                None
            };
            Some(Optimum {
                annealing,
                sensitivity,
                comparison,
            })
        } else {
            None
        };
        // A fact of this run, not a result (it depends on what the store held): manifest only.
        ctx.log_run(
            "cases_cached",
            Value::from(design.cases.iter().filter(|c| c.entry.cached).count()),
        );
        Ok(assemble_output(p, &design, &surfaces, optimum))
    }
}

// ---- The phases of `DoeStage::run`, in order ----

impl DoeStage {
    /// The parameters with a fitted bulge applied (docs/doe.md: the measured design replaces
    /// the base's bulge, so it is Table 2.8's initial design; the factorial levels stay as
    /// configured) and the base sweep every case shares (interface table, DMW track, the keys
    /// of the instances they come from): the one preparation of a local run and a Slurm
    /// worker.
    pub fn prepare(&self, upstream: &UpstreamEntries) -> Result<(DoeParams, PreparedSweep)> {
        let mut p = self.params.clone();
        if let Some(b) = &p.bulge {
            let fitted = crate::artefacts::bulge::upstream_bulge(&upstream.results, b)?;
            p.base.powers = None;
            p.base.apply_bulge(&fitted, b)?;
        }
        let (isbl_params, dmw_track) = base_inputs(&p.base, &upstream.results, &upstream.dirs)?;
        let sweep = PreparedSweep::assemble(p.base.clone(), isbl_params, dmw_track, |n| {
            upstream.key_of(n)
        })?;
        Ok((p, sweep))
    }
}

/// Case kind of a DOE design point (a 2-DOF case of the base sweep with another bulge).
pub const DOE_CASE: &str = "doe";

impl CaseEngine for DoeStage {
    /// The design cases, level by level; the annealing is sequential and runs locally.
    fn prepare_cases(&self, upstream: &UpstreamEntries) -> Result<Arc<dyn PreparedCases>> {
        let (p, sweep) = self.prepare(upstream)?;
        let cases = design_cases(&p.levels, &p.actuations)
            .into_iter()
            .map(|(d, a)| SweepCase {
                actuation_m: a,
                design_m: Some(d),
                static_start: None,
            })
            .collect();
        Ok(Arc::new(SweepCases {
            kind: DOE_CASE,
            sweep,
            listing: Listing::Cases(cases),
        }))
    }
}

/// The finished design: the coded points, their bulges [m], and every case, level by level.
struct DesignRun {
    coded_points: Vec<Vec<f64>>,
    designs: Vec<[f64; 3]>,
    cases: Vec<DesignCase>,
}

/// The 27 coded points × the actuation levels, in parallel through the case cache; writes the
/// design table. The same list the Slurm executor submits (`design_cases`), level by level.
fn run_design(p: &DoeParams, ctx: &StageContext, runner: &CaseRunner) -> Result<DesignRun> {
    let coded_points = full_factorial(&[3, 3, 3]);
    let designs = p.design_points();
    let jobs = design_cases(&p.levels, &p.actuations);
    let total = jobs.len();
    let finished = AtomicUsize::new(0);
    ctx.progress.set_message(format!("0/{total} DOE cases"));
    let outcomes: Vec<Result<DesignCase>> = jobs
        .par_iter()
        .map(|&(design, actuation)| {
            let r = runner.run(design, actuation);
            let n = finished.fetch_add(1, Ordering::Relaxed) + 1;
            ctx.progress.set_message(format!("{n}/{total} DOE cases"));
            r
        })
        .collect();
    let mut cases = Vec::with_capacity(total);
    for o in outcomes {
        cases.push(o?);
    }
    crate::core::store::write_table(
        &rows_of(&design_rows(&coded_points, designs.len(), &cases)),
        &ctx.out_dir.join("design"),
    )?;
    Ok(DesignRun {
        coded_points,
        designs,
        cases,
    })
}

/// The response surfaces of every actuation level and the degree each selects.
struct SurfaceFits {
    fits: Vec<LevelFit>,
    selected_degrees: Vec<String>,
}

/// Fits the surfaces per level; writes the coefficient, ANOVA and predictive-equation tables.
fn fit_surfaces(p: &DoeParams, ctx: &StageContext, design: &DesignRun) -> Result<SurfaceFits> {
    ctx.progress.set_message("response surfaces");
    let fits = fit_levels(p, &design.coded_points, &design.designs, &design.cases)?;
    let selected_degrees: Vec<String> = fits
        .iter()
        .map(|f| model_selection(f).2.to_string())
        .collect();
    crate::core::store::write_table(
        &rows_of(&coefficient_rows(&fits)),
        &ctx.out_dir.join("coefficients"),
    )?;
    crate::core::store::write_table(&rows_of(&anova_rows(&fits)), &ctx.out_dir.join("anova"))?;
    crate::core::store::write_table(
        &rows_of(&predictive_rows(p, &fits)?),
        &ctx.out_dir.join("predictive_equations"),
    )?;
    Ok(SurfaceFits {
        fits,
        selected_degrees,
    })
}

/// Contour and residual plots of every level (Figs 2.26–2.29).
fn draw_fit_figures(
    p: &DoeParams,
    ctx: &StageContext,
    fits: &[LevelFit],
    designs: &[[f64; 3]],
) -> Result<()> {
    ctx.progress.set_message("contour and residual plots");
    for lf in fits {
        let tag = format!("{:.1}nm", lf.actuation / NM).replace('.', "p");
        contour_png(
            &ctx.out_dir.join(format!("contours_{tag}.png")),
            p,
            lf,
            designs,
        )?;
        residuals_png(&ctx.out_dir.join(format!("residuals_{tag}.png")), lf)?;
    }
    Ok(())
}

/// Simulated annealing on ξ at `sa_actuation`; writes the annealing table and its
/// convergence plot (Fig. 2.30).
fn anneal(p: &DoeParams, ctx: &StageContext, objective: &Objective) -> Result<Annealing> {
    let annealing = optimise::anneal(p, ctx.progress, objective)?;
    crate::core::store::write_table(
        &rows_of(&annealing_rows(p, &annealing.history, &annealing.xis)),
        &ctx.out_dir.join("annealing"),
    )?;
    annealing_convergence_png(&ctx.out_dir.join("annealing.png"), p, &annealing.history)?;
    Ok(annealing)
}

/// The sensitivity check around the optimum; writes the sensitivity table.
fn check_sensitivity(
    p: &DoeParams,
    ctx: &StageContext,
    objective: &Objective,
    annealing: &Annealing,
) -> Result<Sensitivity> {
    let sensitivity = optimise::check_sensitivity(p, ctx.progress, objective, annealing)?;
    crate::core::store::write_table(
        &rows_of(&sensitivity.rows),
        &ctx.out_dir.join("sensitivity"),
    )?;
    Ok(sensitivity)
}

/// Table 2.8 on the initial and the optimised design; writes the comparison table and plot.
fn compare_designs(
    p: &DoeParams,
    ctx: &StageContext,
    runner: &CaseRunner,
    best: [f64; 3],
) -> Result<Comparison> {
    let comparison = optimise::compare_designs(p, ctx.progress, runner, best)?;
    crate::core::store::write_table(&rows_of(&comparison.rows), &ctx.out_dir.join("comparison"))?;
    comparison_png(&ctx.out_dir.join("comparison.png"), p, &comparison.sweeps)?;
    Ok(comparison)
}

/// What the optimisation found, when it ran.
struct Optimum {
    annealing: Annealing,
    sensitivity: Sensitivity,
    comparison: Option<Comparison>,
}

/// The instance's row of the run's summary table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DoeRow {
    /// The `[simulate]` instance the design varies.
    pub simulate: String,
    pub cases: usize,
    /// The degree each actuation level selects, space-separated.
    pub selected_degrees: String,
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub optimum: Option<OptimumColumns>,
}

/// The annealing's optimum (µm, seven significant digits) when the instance optimised.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OptimumColumns {
    pub optimum_a_um: Option<f64>,
    pub optimum_w_um: Option<f64>,
    pub optimum_x_um: Option<f64>,
    pub optimum_xi: Option<f64>,
    pub sa_evaluations: usize,
    pub most_sensitive: Option<&'static str>,
}

/// Every table the stage may write, as its result lists them.
const TABLES: [&str; 7] = [
    "design",
    "coefficients",
    "anova",
    "predictive_equations",
    "annealing",
    "sensitivity",
    "comparison",
];

/// The result and the summary row.
fn assemble_output(
    p: &DoeParams,
    design: &DesignRun,
    surfaces: &SurfaceFits,
    optimum: Option<Optimum>,
) -> Output<DoeResult, DoeRow> {
    let total = design.cases.len();
    // Every case this instance used, so `hdi gc` keeps them with it.
    let mut case_keys: Vec<String> = design.cases.iter().map(|c| c.entry.key.clone()).collect();
    // The fitted (measured) bulge: Table 2.8's initial design.
    let initial_design_m = p.bulge.is_some().then(|| {
        let b = p.base.model.bulge;
        DesignM {
            a_tfc: b.semi_width_x,
            w_tfc: b.full_width_y,
            x_tfc: b.offset_from_te,
        }
    });
    let mut row = DoeRow {
        simulate: p.base_name.clone(),
        cases: total,
        selected_degrees: surfaces.selected_degrees.join(" "),
        optimum: None,
    };
    let mut result_optimum = None;
    let mut result_comparison = None;
    if let Some(Optimum {
        annealing: a,
        sensitivity: s,
        comparison,
    }) = optimum
    {
        case_keys.extend(a.case_keys);
        case_keys.extend(s.case_keys);
        let best = a.best;
        let spread = s.spread;
        result_optimum = Some(DoeOptimum {
            a_m: best[0],
            w_m: best[1],
            x_m: best[2],
            xi: a.best_xi,
            objective: format!("{:?}", p.sa_objective).to_lowercase(),
            evaluations: a.evaluations,
            reanneals: a.reanneals,
            stop: match a.stop {
                StopReason::Stalled => "converged (stalled)",
                StopReason::MaxEvaluations => "evaluation budget",
            }
            .to_string(),
            sensitivity_one_step: DesignSpread {
                a_tfc: spread[0],
                w_tfc: spread[1],
                x_tfc: spread[2],
            },
            most_sensitive: s.most_sensitive.map(str::to_string),
        });
        row.optimum = Some(OptimumColumns {
            optimum_a_um: table_value(best[0] / UM),
            optimum_w_um: table_value(best[1] / UM),
            optimum_x_um: table_value(best[2] / UM),
            optimum_xi: table_value(a.best_xi),
            sa_evaluations: a.evaluations,
            most_sensitive: s.most_sensitive,
        });
        if let Some(c) = comparison {
            case_keys.extend(c.case_keys);
            result_comparison = Some(c.rows);
        }
    }
    case_keys.sort();
    case_keys.dedup();
    let result = DoeResult {
        cases: total,
        fits: surfaces.fits.iter().map(fit_summary).collect(),
        tables: TABLES.iter().map(|t| t.to_string()).collect(),
        initial_design_m,
        optimum: result_optimum,
        comparison: result_comparison,
        case_keys,
    };
    Output {
        result,
        summary_row: Some(row),
    }
}
