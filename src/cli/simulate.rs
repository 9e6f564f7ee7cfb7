//! `hdi simulate`: ad-hoc 2-DOF slider cases through the library's sweep runner.

use anyhow::{Context, Result};
use hdi::slider::sweep::SweepRow;
use std::time::Instant;

use super::args::SimulateArgs;
use super::progress::CaseBar;
use json::print_json;
pub(crate) use json::SimulateOutput;

mod json;
use hdi::stages::contact::{self, ContactConfig, SurfaceEnergyConfig};

pub(super) fn cmd_simulate(a: SimulateArgs) -> Result<()> {
    use hdi::artefacts::dmw_tracks::read_dmw_track;
    use hdi::slider::sweep::{run_cases, sweep_analysis, sweep_rows, CaseSink};
    let params = simulate_params(&a)?;
    let isbl = interface_lookup(&a)?;
    let dmw = match &a.dmw {
        Some(p) => Some(read_dmw_track(p)?),
        None => None,
    };
    let (root, temporary) = match &a.out {
        Some(o) => (o.clone(), false),
        None => (
            std::env::temp_dir().join(format!("hdi-simulate-{}", std::process::id())),
            true,
        ),
    };
    std::fs::create_dir_all(root.join("cases"))
        .with_context(|| format!("creating {}", root.display()))?;
    let bar = CaseBar::new(params.actuations.len());
    let started = Instant::now();
    let cases = run_cases(
        &params,
        &CaseSink::Directory(&root.join("cases")),
        &isbl,
        dmw.as_ref(),
        &bar,
    );
    bar.finish();
    let cases = cases?;
    let wall = started.elapsed().as_secs_f64();
    let sweep = sweep_analysis(&params, &cases)?;
    let rows = sweep_rows(&cases, &sweep);
    if a.out.is_some() {
        write_sweep(&root, &params, &cases, &sweep, &rows, &a.model)?;
    }
    if temporary {
        let _ = std::fs::remove_dir_all(&root);
    }
    if a.json {
        return print_json(&cases, &sweep, rows, wall);
    }
    print_table(&a.model, &params, &cases, &sweep, &rows, wall);
    Ok(())
}

/// The case settings of the command line, checked as a `[simulate]` table is; an error names
/// the flag.
fn simulate_params(a: &SimulateArgs) -> Result<hdi::slider::params::SimulateParams> {
    use hdi::slider::params::{SimulateConfig, SimulateParams};
    let mut cfg: SimulateConfig =
        toml::from_str("contact = \"adhoc\"").context("default simulate settings")?;
    cfg.model = a.model.clone();
    if !a.actuation.is_empty() {
        cfg.actuations = Some(a.actuation.clone());
    }
    macro_rules! set {
        ($($f:ident),*) => { $( if let Some(v) = a.$f.clone() { cfg.$f = v; } )* };
    }
    set!(
        actuation_start,
        actuation_stop,
        actuation_step,
        duration,
        steady_start,
        output_step,
        contact_force,
        lubricant,
        integrator,
        rtol,
        contact_max_step,
        max_step,
        fixed_step,
        init
    );
    if let Some(g) = a.geometry.clone() {
        cfg.geometry = hdi::slider::params::GeometryConfig::Named(g);
    }
    cfg.transit_delay = !a.no_transit_delay;
    cfg.dmw_wrap = a.dmw_wrap;
    cfg.kr_stiffening_beta = a.kr_stiffening_beta;
    cfg.bulge_width = a.bulge_width;
    cfg.histories = a.histories.clone();
    SimulateParams::check(&cfg).map_err(|e| {
        // The list key is `actuations` in pipeline.toml, `--actuation` on the command line.
        let flag = if e.key == "actuations" {
            "actuation".to_string()
        } else {
            e.key.replace('_', "-")
        };
        anyhow::anyhow!("--{flag}: {}", e.message)
    })
}

/// The interface table of the command line's contact settings, checked as a `[contact]` table
/// is; an error names the flag.
fn interface_lookup(a: &SimulateArgs) -> Result<hdi::contact::lookup::IsblLookup> {
    let mut interface = ContactConfig::defaults();
    interface.parameter_set = a.contact_set.clone().unwrap_or_else(|| a.model.clone());
    interface.surface_energy = a.surface_energy.clone().map(SurfaceEnergyConfig::Text);
    interface.lj_spacing = a.lj_spacing;
    interface.r = a.r;
    interface.eta = a.eta;
    interface.hardness = a.hardness;
    if let Some(law) = &a.friction_law {
        interface.friction_law = law.clone();
    }
    let isbl_params = contact::check(&interface)
        .map_err(|e| {
            let flag = if e.key == "parameter_set" {
                "contact-set".to_string()
            } else {
                e.key.replace('_', "-")
            };
            anyhow::anyhow!("--{flag}: {}", e.message)
        })?
        .params;
    Ok(hdi::contact::lookup::IsblLookup::build_standard(
        hdi::contact::isbl::IsblModel::new(isbl_params)?,
    )?)
}

/// With `--out`: the sweep table and the sweep's plots beside the case directories.
fn write_sweep(
    root: &std::path::Path,
    params: &hdi::slider::params::SimulateParams,
    cases: &[hdi::slider::sweep::CaseOutcome],
    sweep: &hdi::dynamics::metrics::SweepMetrics,
    rows: &[SweepRow],
    model: &str,
) -> Result<()> {
    use hdi::slider::sweep::sweep_analysis;
    use hdi::stages::simulate::plots;
    hdi::core::store::write_table(&hdi::core::store::rows_of(rows), &root.join("sweep"))?;
    // One sweep (the ad hoc command does not track branches; the pipeline's
    // `[simulate]` does, docs/conventions.md), its grid touchdown.
    let run = hdi::stages::simulate::BranchRun {
        branch: None,
        cases: cases
            .iter()
            .map(|c| hdi::slider::sweep::CaseOutcome {
                actuation: c.actuation,
                metrics: c.metrics.clone(),
                entry: c.entry.clone(),
            })
            .collect(),
        touchdown: hdi::dynamics::touchdown::Touchdown {
            actuation: sweep.touchdown_actuation_m,
            last_flying: None,
            cases_run: 0,
        },
        sweep: sweep_analysis(params, cases)?,
        extra: Vec::new(),
    };
    plots(root, params, std::slice::from_ref(&run), model)?;
    Ok(())
}

/// The human-readable report: one line per case, then the sweep's touchdown, critical point
/// and slopes.
fn print_table(
    model: &str,
    params: &hdi::slider::params::SimulateParams,
    cases: &[hdi::slider::sweep::CaseOutcome],
    sweep: &hdi::dynamics::metrics::SweepMetrics,
    rows: &[SweepRow],
    wall: f64,
) {
    println!(
        "{} ({}), {} case(s) in {:.2} s",
        model,
        params.geometry,
        cases.len(),
        wall
    );
    println!(
        "  {:>8} {:>10} {:>9} {:>9} {:>8} {:>17} {:>10} {:>6} {:>8}",
        "h (nm)", "c̄ (nm)", "std (nm)", "FHM/BV %", "solid %", "regime", "F_c (mN)", "μ", "steps"
    );
    for r in rows {
        let s = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{x:.3}"));
        println!(
            "  {:>8.2} {:>10.4} {:>9.4} {:>9.2} {:>8.2} {:>17} {:>10} {:>6} {:>8}",
            r.actuation_nm,
            r.clearance_mean_nm,
            r.clearance_std_nm,
            r.vibration_percent,
            r.solid_contact_percent,
            r.regime.unwrap_or("-"),
            s(r.contact_force_mean_mN),
            s(r.friction_coefficient),
            r.steps as f64
        );
    }
    if cases.len() > 1 {
        let nm = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{:.2} nm", x * 1e9));
        println!("  touchdown {}", nm(sweep.touchdown_actuation_m));
        if let Some(cp) = &sweep.slopes.critical_point {
            println!(
                "  critical point {:.2} nm at clearance {:.3} nm",
                cp.actuation_m * 1e9,
                cp.clearance_m * 1e9
            );
        }
        for (k, l) in [
            ("A", &sweep.slopes.a),
            ("B", &sweep.slopes.b),
            ("C", &sweep.slopes.c),
            ("D", &sweep.slopes.d),
        ] {
            if let Some(l) = l {
                println!("  slope {k} {:.3}", l.slope);
            }
        }
    }
}
