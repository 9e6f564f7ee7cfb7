//! `hdi contact`: ISBL contact curves (and the MTL lubricant law) for one interface.

use anyhow::Result;
use serde_json::json;

use super::args::ContactArgs;
use super::{flag, out_parent};
use hdi::stages::contact::{self, ContactConfig, SurfaceEnergyConfig};

pub(super) fn cmd_contact(a: ContactArgs) -> Result<()> {
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
    let analysis = contact::analyse(&params.params, &params, None)?;
    if let Some(out) = &a.out {
        let dir = out_parent(out)?;
        contact::write_outputs(&analysis, &params, out, Some(dir), "", &json!([]))?;
    }
    if a.json {
        println!(
            "{}",
            serde_json::to_string(&contact::report_json(&analysis, &params))?
        );
        return Ok(());
    }
    let p = analysis.model.params();
    let d = analysis.model.derived();
    println!(
        "ISBL interface ({}): σ = {:.3} nm, R = {:.3} µm, η = {:.1} µm⁻², β = {:.4}",
        params.parameter_set,
        p.sigma * 1e9,
        p.summit_radius * 1e6,
        p.summit_density * 1e-12,
        d.beta
    );
    println!(
        "  E* = {:.1} GPa, ω_c = {:.4} nm, ψ = {:.3}, t = {:.2} nm, ε = {:.2} nm",
        d.composite_modulus / 1e9,
        d.critical_interference * 1e9,
        d.plasticity_index,
        p.lubricant_thickness * 1e9,
        p.lj_spacing * 1e9
    );
    println!(
        "  summits ({}): σ_s = {:.4}σ, y_s = {:.4}σ above the mean plane",
        params.summits.name(p.summits),
        d.summit_sigma / p.sigma,
        d.summit_offset / p.sigma
    );
    if let Some(contact::SummitOrigin::Fig211 { nominal_area, fit }) = &analysis.summit_origin {
        println!(
            "    fitted to Fig. 2.11 on A_n = {:.1} µm²: P(3σ)·A_n = {:.3} µN, P(3σ)/P(2.5σ) = {:.4}",
            nominal_area * 1e12,
            fit.force * 1e6,
            fit.ratio
        );
    }
    println!(
        "  {:>6} {:>12} {:>12} {:>12} {:>12} {:>12}",
        "h/σ", "P (Pa)", "k_c (Pa/nm)", "A_r/A_n", "Q (Pa)", "F_s (Pa)"
    );
    for x in [0.0, 1.0, 2.0, 3.0, 4.0, 6.0] {
        if x < params.h_star_min || x > params.h_star_max {
            continue;
        }
        let q = analysis.lookup.at(x * p.sigma)?;
        println!(
            "  {:>6.2} {:>12.4e} {:>12.4e} {:>12.4e} {:>12.4e} {:>12.4e}",
            x,
            q.pressure,
            q.stiffness * 1e-9,
            q.real_area_fraction,
            q.friction,
            q.adhesion
        );
    }
    let worst = analysis
        .table_error()
        .iter()
        .map(|e| e.max_rel)
        .fold(0.0, f64::max);
    let (lo, hi) = analysis.table().range();
    println!(
        "  force table: h/σ {lo} … {hi} step {}, max relative error vs direct {worst:.1e}",
        analysis.table().step()
    );
    if let Some(m) = &analysis.mtl {
        let l = m.landmarks();
        println!(
            "MTL lubricant ({}): μ0 = {} Pa·s, κ = {} nm, U = {} m/s, A_n = {} µm²",
            l.lubricant,
            m.settings.limiting_viscosity,
            m.settings.kappa * 1e9,
            m.settings.speed,
            m.settings.nominal_area * 1e12
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
    Ok(())
}
