//! `hdi bulge FILE…`: the TFC bulge of profilometer scans and the efficiency over heater power.

use anyhow::{anyhow, Result};

use super::args::BulgeArgs;
use hdi::stages::bulge::{self, BulgeParams};
use hdi::surface::bulge::BulgeOptions;

pub(super) fn cmd_bulge(a: BulgeArgs) -> Result<()> {
    let given: Vec<f64> = a.powers.iter().map(|p| p.0).collect();
    let powers = bulge::resolve_powers(&a.files, (!given.is_empty()).then_some(&given[..]))
        .map_err(|m| anyhow!("--power: {m}"))?;
    let te_margin = a.te_margin.map(|l| l.0).unwrap_or(2e-6);
    if te_margin.is_nan() || te_margin < 0.0 {
        return Err(anyhow!("--te-margin: {te_margin} m must be ≥ 0"));
    }
    let params = BulgeParams {
        files: a.files.clone(),
        powers,
        options: BulgeOptions {
            exclude: bulge::rects(&a.exclude),
            auto_te: !a.no_auto_te,
            te_margin,
        },
        channel: a.channel,
    };
    let analysis = bulge::analyse(&params)?;
    if let Some(dir) = &a.out {
        std::fs::create_dir_all(dir)?;
        bulge::write_outputs(
            &analysis,
            &serde_json::Value::Object(Default::default()),
            "",
            dir,
        )?;
        bulge::write_figures(&analysis, &params.options, dir)?;
    }
    if a.json {
        println!("{}", serde_json::to_string(&bulge::report(&analysis))?);
        return Ok(());
    }
    println!(
        "{:<24} {:>7} {:>16} {:>16} {:>16} {:>16} {:>9}",
        "file", "P (mW)", "h (nm)", "a (µm)", "w (µm)", "x_TFC (µm)", "rms (nm)"
    );
    for s in &analysis.scans {
        let f = &s.fit;
        let name = s
            .file
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let p = s
            .power
            .map(|p| format!("{:.1}", p * 1e3))
            .unwrap_or_else(|| "?".into());
        let pm = |v: f64, se: f64, k: f64| format!("{:.3} ± {:.3}", v * k, se * k);
        let x = f
            .x_tfc
            .map(|x| pm(x, f.xc_se, 1e6))
            .unwrap_or_else(|| "no edge".into());
        println!(
            "{:<24} {:>7} {:>16} {:>16} {:>16} {:>16} {:>9.3}",
            name,
            p,
            pm(f.height, f.height_se, 1e9),
            pm(f.a, f.a_se, 1e6),
            pm(f.w, f.w_se, 1e6),
            x,
            f.residual_rms * 1e9
        );
    }
    match analysis.efficiency {
        Some(e) => println!(
            "efficiency {:.4} ± {:.4} nm/mW, unpowered bulge {:.3} ± {:.3} nm ({} scans)",
            e.efficiency * 1e6,
            e.efficiency_se * 1e6,
            e.intercept * 1e9,
            e.intercept_se * 1e9,
            e.n
        ),
        None => println!("efficiency: needs two or more scans at different known powers"),
    }
    Ok(())
}
