//! `hdi surface FILE`: one height map's roughness parameters.

use anyhow::Result;

use super::args::SurfaceArgs;
use super::{flag, out_parent};
use hdi::stages::surfaces::{self, SurfaceConfig};

pub(super) fn cmd_surface(a: SurfaceArgs) -> Result<()> {
    let cfg = SurfaceConfig {
        file: a.file.clone(),
        files: None,
        channel: a.channel,
        size_x: a.size_x,
        size_y: a.size_y,
        z_unit: a.z_unit,
        crop: a.crop,
        crops: None,
        level: a.level.unwrap_or_else(surfaces::default_level),
        filter_s: a.filter_s,
        filter_l: a.filter_l,
        summits: a.summits,
        radius: a.radius,
        birmingham: a.birmingham,
        moments: a.moments,
        periodic: a.periodic,
        histogram_bins: a.histogram_bins,
        scale_sweep: a.out.is_some(),
    };
    let params = surfaces::check(&cfg, a.file.clone())
        .map_err(|e| anyhow::anyhow!("{}: {}", flag(&e.key), e.message))?;
    let analysis = surfaces::analyse(&params)?;
    if let Some(out) = &a.out {
        let dir = out_parent(out)?;
        surfaces::write_outputs(
            &analysis,
            &params,
            out,
            Some(dir),
            "",
            &serde_json::Value::from(vec![a.file.to_string_lossy().into_owned()]),
        )?;
    }
    let report = surfaces::report(&analysis, &params);
    if a.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        let r = &analysis.report;
        println!(
            "{} ({}, channel {}), {} × {} px, dx = {:.3} nm",
            a.file.display(),
            analysis.raw.source.format,
            analysis.raw.channel,
            analysis.final_map().nx(),
            analysis.final_map().ny(),
            analysis.final_map().dx * 1e9
        );
        println!("  levelling  {}", serde_json::to_string(&report.levelling)?);
        println!("  filter     {}", surfaces::filter_text(&params));
        println!(
            "  σ          {:.4} nm   (Sa {:.4} nm, Ssk {:.3}, Sku {:.3})",
            r.sigma * 1e9,
            r.sa * 1e9,
            r.ssk,
            r.sku
        );
        println!(
            "  η          {:.2} µm⁻²  ({} summits, {})",
            r.eta * 1e-12,
            r.n_summits,
            r.summit_scheme
        );
        println!("  R          {:.4} µm   ({})", r.r * 1e6, r.r_definition);
        println!("  β = σRη    {:.5}", r.beta);
        println!(
            "  Nayak      η {:.2} µm⁻², R {:.4} µm, β {:.5} (α = {:.3})",
            r.nayak.eta * 1e-12,
            r.nayak.r * 1e6,
            r.nayak.beta,
            r.alpha
        );
        for w in &r.warnings {
            println!("  warning: {w}");
        }
    }
    Ok(())
}
