//! `hdi surface FILE`: one height map's roughness parameters, as a one-instance pipeline
//! through the engine.

use anyhow::Result;

use super::args::SurfaceArgs;
use super::{flag, one_off, out_parent};
use hdi::artefacts::surface::SurfaceResult;
use hdi::stages::surfaces::{self, SurfaceConfig, SurfaceStage};
use hdi::stages::Instance;
use hdi::surface::io::{read_height_map, ReadOptions};

pub(super) fn cmd_surface(a: SurfaceArgs) -> Result<()> {
    if a.info {
        return show_info(&a);
    }
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
        x3p: a.x3p_out.is_some(),
        tip_radius: a.tip_radius,
    };
    let mut params = surfaces::check(&cfg, a.file.clone())
        .map_err(|e| anyhow::anyhow!("{}: {}", flag(&e.key), e.message))?;
    // The curves go to the HDF5 file and the PNGs only.
    params.analyses = a.out.is_some();
    let filter = surfaces::filter_text(&params);
    let stage = SurfaceStage {
        name: one_off::NAME.into(),
        params,
    };
    let ran = one_off::run::<SurfaceResult>(
        "surface",
        Box::new(Instance {
            name: one_off::NAME.into(),
            stage,
        }),
    )?;
    if let Some(out) = &a.out {
        one_off::deliver(&ran.dir, out_parent(out)?, "surface.h5", Some(out))?;
    }
    if let Some(path) = &a.x3p_out {
        one_off::deliver_file(&ran.dir, "surface.x3p", path)?;
    }
    let r = &ran.result.report;
    if a.json {
        println!("{}", serde_json::to_string(r)?);
        return Ok(());
    }
    // Non-finite values are `None` in the result; they print as before, as NaN.
    let f = |v: Option<f64>, scale: f64, digits: usize| {
        format!("{:.digits$}", v.map_or(f64::NAN, |v| v * scale))
    };
    println!(
        "{} ({}, channel {}), {} × {} px, dx = {:.3} nm",
        a.file.display(),
        r.format,
        r.channel,
        r.nx,
        r.ny,
        r.dx_m * 1e9
    );
    println!("  levelling  {}", serde_json::to_string(&r.levelling)?);
    println!("  filter     {filter}");
    println!(
        "  σ          {:.4} nm   (Sa {:.4} nm, Ssk {}, Sku {})",
        r.sigma_m * 1e9,
        r.sa_m * 1e9,
        f(r.ssk, 1.0, 3),
        f(r.sku, 1.0, 3)
    );
    println!(
        "  η          {} µm⁻²  ({} summits, {})",
        f(r.eta_per_m2, 1e-12, 2),
        r.n_summits,
        r.summit_scheme
    );
    println!(
        "  R          {} µm   ({})",
        f(r.r_m, 1e6, 4),
        r.r_definition
    );
    println!("  β = σRη    {}", f(r.beta, 1.0, 5));
    println!(
        "  Nayak      η {} µm⁻², R {} µm, β {} (α = {})",
        f(r.nayak.eta_per_m2, 1e-12, 2),
        f(r.nayak.r_m, 1e6, 4),
        f(r.nayak.beta, 1.0, 5),
        f(r.alpha, 1.0, 3)
    );
    for w in &r.warnings {
        println!("  warning: {w}");
    }
    Ok(())
}

/// `hdi surface FILE --info`: the file as read, before any processing.
fn show_info(a: &SurfaceArgs) -> Result<()> {
    let opts = ReadOptions {
        channel: a.channel.clone(),
        size_x: a.size_x.map(|l| l.0),
        size_y: a.size_y.map(|l| l.0),
        z_unit: a.z_unit.clone(),
    };
    let map = read_height_map(&a.file, &opts)?;
    let invalid = map
        .valid
        .as_ref()
        .map_or(0, |v| v.iter().filter(|ok| !**ok).count());
    let header = &map.source.header;
    if a.json {
        let info = serde_json::json!({
            "file": a.file,
            "format": map.source.format,
            "channel": map.channel,
            "channels": header.get("channels"),
            "nx": map.nx(),
            "ny": map.ny(),
            "dx_m": map.dx,
            "dy_m": map.dy,
            "x0_m": map.x0,
            "y0_m": map.y0,
            "invalid_pixels": invalid,
            "header": header,
        });
        println!("{}", serde_json::to_string(&info)?);
        return Ok(());
    }
    println!(
        "{} ({}), {} × {} px, dx = {:.4} nm, dy = {:.4} nm, {invalid} invalid",
        a.file.display(),
        map.source.format,
        map.nx(),
        map.ny(),
        map.dx * 1e9,
        map.dy * 1e9
    );
    println!("  channel read  {}", map.channel);
    if let Some(list) = header.get("channels") {
        println!("  channels      {list} (choose with --channel)");
    }
    for (key, value) in header.iter().filter(|(k, _)| *k != "channels") {
        // One line each: long values (notes, XML) are cut.
        let one_line = value.replace(['\n', '\r'], " ");
        let shown: String = one_line.chars().take(160).collect();
        let cut = if shown.len() < one_line.len() {
            " …"
        } else {
            ""
        };
        println!("  {key}: {shown}{cut}");
    }
    Ok(())
}
