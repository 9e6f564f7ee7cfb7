//! `hdi contact`: ISBL contact curves (and the MTL lubricant law) for one interface, as a
//! one-instance pipeline through the engine.

use anyhow::Result;

use super::args::ContactArgs;
use super::{flag, one_off, out_parent};
use hdi::artefacts::contact::SummitDistributionReport;
use hdi::artefacts::contact_bem::{BemResult, BEM_FILE};
use hdi::stages::contact::mtl::MtlReport;
use hdi::stages::contact::{
    self, ContactConfig, ContactReport, ContactStage, ContactStageResult, SurfaceEnergyConfig,
};
use hdi::stages::contact_bem::{self, ContactBemConfig, ContactBemStage, MapSource};
use hdi::stages::Instance;

pub(super) fn cmd_contact(a: ContactArgs) -> Result<()> {
    if !a.bem.is_empty() {
        return cmd_contact_bem(a);
    }
    let mut cfg = ContactConfig::defaults();
    if let Some(v) = a.parameter_set {
        cfg.parameter_set = v;
    }
    cfg.sigma = a.sigma;
    cfg.r = a.r;
    cfg.eta = a.eta;
    cfg.hardness = a.hardness;
    cfg.modulus = a.modulus;
    cfg.poisson = a.poisson;
    cfg.lj_spacing = a.lj_spacing;
    cfg.lubricant_thickness = a.lubricant_thickness;
    cfg.surface_energy = a.surface_energy.map(SurfaceEnergyConfig::Text);
    cfg.summit_offset = a.summit_offset;
    cfg.summit_distribution = a.summit_distribution;
    cfg.fig_2_11_nominal_area = a.fig_2_11_nominal_area;
    if let Some(v) = a.friction_law {
        cfg.friction_law = v;
    }
    if let Some(v) = a.h_star_min {
        cfg.h_star_min = v;
    }
    if let Some(v) = a.h_star_max {
        cfg.h_star_max = v;
    }
    if let Some(v) = a.step {
        cfg.step = v;
    }
    cfg.lubricant = a.lubricant;
    cfg.nominal_area = a.nominal_area;
    cfg.sliding_speed = a.sliding_speed;
    cfg.lubricant_viscosity = a.lubricant_viscosity;
    cfg.gyration_radius = a.gyration_radius;
    let params =
        contact::check(&cfg).map_err(|e| anyhow::anyhow!("{}: {}", flag(&e.key), e.message))?;
    let summits = params.summits.name(params.params.summits);
    let (h_star_min, h_star_max) = (params.h_star_min, params.h_star_max);
    let stage = Instance {
        name: one_off::NAME.into(),
        stage: ContactStage {
            name: one_off::NAME.into(),
            params,
        },
    };
    let ran = one_off::run::<ContactStageResult>("contact", Box::new(stage))?;
    if let Some(out) = &a.out {
        one_off::deliver(&ran.dir, out_parent(out)?, &ran.result.h5, Some(out))?;
    }
    let r = &ran.result.report;
    if a.json {
        println!("{}", serde_json::to_string(r)?);
        return Ok(());
    }
    print_isbl(r, summits, (h_star_min, h_star_max));
    if let Some(m) = &r.mtl {
        print_mtl(m);
    }
    Ok(())
}

/// The interface, its derived quantities, the curves at a few h/σ and the table's accuracy.
fn print_isbl(r: &ContactReport, summits: &str, (h_star_min, h_star_max): (f64, f64)) {
    let (p, d) = (&r.inputs, &r.derived);
    println!(
        "ISBL interface ({}): σ = {:.3} nm, R = {:.3} µm, η = {:.1} µm⁻², β = {:.4}",
        r.parameter_set,
        p.sigma * 1e9,
        p.summit_radius * 1e6,
        p.summit_density * 1e-12,
        d.beta
    );
    println!(
        "  E* = {:.1} GPa, ω_c = {:.4} nm, ψ = {:.3}, t = {:.2} nm, ε = {:.2} nm",
        d.E_star_Pa / 1e9,
        d.omega_c_m * 1e9,
        d.psi,
        p.lubricant_thickness * 1e9,
        p.lj_spacing * 1e9
    );
    println!(
        "  summits ({summits}): σ_s = {:.4}σ, y_s = {:.4}σ above the mean plane",
        d.sigma_s_m / p.sigma,
        d.y_s_m / p.sigma
    );
    if let Some(SummitDistributionReport::Fig211 {
        nominal_area_m2,
        fitted,
        ..
    }) = &r.summit_distribution
    {
        println!(
            "    fitted to Fig. 2.11 on A_n = {:.1} µm²: P(3σ)·A_n = {:.3} µN, P(3σ)/P(2.5σ) = {:.4}",
            nominal_area_m2 * 1e12,
            fitted.force_N * 1e6,
            fitted.ratio
        );
    }
    println!(
        "  {:>6} {:>12} {:>12} {:>12} {:>12} {:>12}",
        "h/σ", "P (Pa)", "k_c (Pa/nm)", "A_r/A_n", "Q (Pa)", "F_s (Pa)"
    );
    // The curve points at (or, off the output grid, nearest) these h/σ.
    let mut shown: Vec<usize> = Vec::new();
    for x in [0.0, 1.0, 2.0, 3.0, 4.0, 6.0] {
        if x < h_star_min || x > h_star_max {
            continue;
        }
        let nearest = (0..r.curves.len()).min_by(|&i, &j| {
            let d = |k: usize| (r.curves[k].h_star - x).abs();
            d(i).total_cmp(&d(j))
        });
        let Some(k) = nearest.filter(|k| !shown.contains(k)) else {
            continue;
        };
        shown.push(k);
        let q = &r.curves[k];
        println!(
            "  {:>6.2} {:>12.4e} {:>12.4e} {:>12.4e} {:>12.4e} {:>12.4e}",
            q.h_star,
            q.P_Pa,
            q.k_c_Pa_per_m * 1e-9,
            q.A_r_fraction,
            q.Q_Pa,
            q.F_s_Pa
        );
    }
    let worst = r
        .table
        .max_rel_error
        .0
        .iter()
        .map(|e| e.1)
        .fold(0.0, f64::max);
    let (lo, hi) = r.table.h_star_range;
    println!(
        "  force table: h/σ {lo} … {hi} step {}, max relative error vs direct {worst:.1e}",
        r.table.h_star_step
    );
}

/// The MTL lubricant law's settings and landmarks.
fn print_mtl(m: &MtlReport) {
    let (s, l) = (&m.settings, &m.landmarks);
    println!(
        "MTL lubricant ({}): μ0 = {} Pa·s, κ = {} nm, U = {} m/s, A_n = {} µm²",
        l.lubricant,
        s.mu0_Pa_s,
        s.kappa_m * 1e9,
        s.speed_m_per_s,
        s.nominal_area_m2 * 1e12
    );
    println!(
        "  k_P,max = {:.4e} N/m at h/σ = {:.4}; k_Q,max = {:.2} N/m",
        l.k_P_max_N_per_m, l.h_star_max_stiffness, l.k_Q_max_N_per_m
    );
    println!(
        "  total stiffness there: normal {:.4e} N/m, lateral {:.4e} N/m",
        l.k_normal_total_at_peak_N_per_m, l.k_lateral_total_at_peak_N_per_m
    );
    println!(
        "  lubricant bearing force: {:.4} mN at 3σ + 2κ, {:.4} mN at 3σ; Q_lub {:.4} µN",
        l.P_lub_transition_end_mN, l.P_lub_onset_mN, l.Q_lub_transition_end_uN
    );
}

/// `hdi contact --bem FILE [FILE]`: the FFT-BEM force–separation curve of one map (or the sum
/// of two), as a one-instance `[contact_bem]` pipeline.
fn cmd_contact_bem(a: ContactArgs) -> Result<()> {
    let cfg = ContactBemConfig {
        modulus: a.modulus,
        poisson: a.poisson,
        boundary: a.boundary.clone(),
        h_star_min: a.h_star_min,
        h_star_max: a.h_star_max,
        step: a.step,
        map_at: a.map_at,
        tolerance: a.tolerance,
        ..Default::default()
    };
    for f in &a.bem {
        if !f.is_file() {
            anyhow::bail!("--bem: {} not found", f.display());
        }
    }
    let params = contact_bem::check(&cfg, MapSource::Files(a.bem.clone()))
        .map_err(|e| anyhow::anyhow!("{}: {}", flag(e.key), e.message))?;
    let stage = Instance {
        name: one_off::NAME.into(),
        stage: ContactBemStage {
            name: one_off::NAME.into(),
            params,
        },
    };
    let ran = one_off::run::<BemResult>("contact", Box::new(stage))?;
    if let Some(out) = &a.out {
        one_off::deliver(&ran.dir, out_parent(out)?, BEM_FILE, Some(out))?;
    }
    let r = &ran.result;
    if a.json {
        println!("{}", serde_json::to_string(r)?);
        return Ok(());
    }
    println!(
        "BEM {} × {} elements of {:.3} × {:.3} nm ({}), σ = {:.4} nm, E* = {:.1} GPa, \
         tolerance {:e}",
        r.grid[0],
        r.grid[1],
        r.spacing_m[0] * 1e9,
        r.spacing_m[1] * 1e9,
        r.boundary,
        r.sigma_m * 1e9,
        r.e_star_Pa * 1e-9,
        r.tolerance
    );
    println!(
        "{:>6} {:>12} {:>12} {:>10} {:>6}",
        "h/σ", "P (MPa)", "A_r/A_0", "gap (nm)", "iter"
    );
    let every = (r.curve.len() / 16).max(1);
    for p in r.curve.iter().step_by(every) {
        println!(
            "{:>6.2} {:>12.5e} {:>12.5e} {:>10.4} {:>6}",
            p.h_star,
            p.pressure_Pa * 1e-6,
            p.contact_fraction,
            p.mean_gap_m * 1e9,
            p.iterations
        );
    }
    if let Some(v) = r.ratio_3_over_2_5.bem {
        println!("P(3σ)/P(2.5σ) = {v:.4}");
    }
    Ok(())
}
