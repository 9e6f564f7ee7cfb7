//! `hdi bulge FILE…`: the TFC bulge of profilometer scans and the efficiency over heater power,
//! as a one-instance pipeline through the engine.

use anyhow::{anyhow, Result};

use super::args::BulgeArgs;
use super::one_off;
use hdi::artefacts::bulge::BulgeReport;
use hdi::stages::bulge::{self, BulgeParams, BulgeStage};
use hdi::stages::Instance;
use hdi::surface::bulge::BulgeOptions;

pub(super) fn cmd_bulge(a: BulgeArgs) -> Result<()> {
    let given: Vec<f64> = a.powers.iter().map(|p| p.0).collect();
    let powers = bulge::resolve_powers(&a.files, (!given.is_empty()).then_some(&given[..]))
        .map_err(|m| anyhow!("--power: {m}"))?;
    let te_margin = a.te_margin.map(|l| l.0).unwrap_or(2e-6);
    if te_margin.is_nan() || te_margin < 0.0 {
        return Err(anyhow!("--te-margin: {te_margin} m must be ≥ 0"));
    }
    let lines = a
        .lines
        .iter()
        .map(|l| bulge::line_spec(l.file.clone(), l))
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(|m| anyhow!("--line: {m}"))?;
    let params = BulgeParams {
        files: a.files.clone(),
        powers,
        lines,
        options: BulgeOptions {
            exclude: bulge::rects(&a.exclude),
            auto_te: !a.no_auto_te,
            te_margin,
        },
        channel: a.channel,
    };
    let stage = Instance {
        name: one_off::NAME.into(),
        stage: BulgeStage { params },
    };
    let ran = one_off::run::<BulgeReport>("bulge", Box::new(stage))?;
    if let Some(dir) = &a.out {
        std::fs::create_dir_all(dir).map_err(|e| anyhow!("creating {}: {e}", dir.display()))?;
        one_off::deliver(&ran.dir, dir, "", None)?;
    }
    let r = &ran.result;
    if a.json {
        println!("{}", serde_json::to_string(r)?);
        return Ok(());
    }
    println!(
        "{:<24} {:>7} {:>16} {:>16} {:>16} {:>16} {:>9}",
        "file", "P (mW)", "h (nm)", "a (µm)", "w (µm)", "x_TFC (µm)", "rms (nm)"
    );
    // Non-finite values are `None` in the result; they print as NaN.
    let nan = |v: Option<f64>| v.unwrap_or(f64::NAN);
    let pm =
        |v: Option<f64>, se: Option<f64>, k: f64| format!("{:.3} ± {:.3}", nan(v) * k, nan(se) * k);
    for s in &r.scans {
        let p = s
            .heater_power_mw
            .map(|p| format!("{p:.1}"))
            .unwrap_or_else(|| "?".into());
        let x = s
            .x_tfc_m
            .map(|x| pm(Some(x), s.x_tfc_se_m, 1e6))
            .unwrap_or_else(|| "no edge".into());
        println!(
            "{:<24} {:>7} {:>16} {:>16} {:>16} {:>16} {:>9.3}",
            s.file,
            p,
            pm(s.height_m, s.height_se_m, 1e9),
            pm(s.a_tfc_m, s.a_tfc_se_m, 1e6),
            pm(s.w_tfc_m, s.w_tfc_se_m, 1e6),
            x,
            nan(s.residual_rms_m) * 1e9
        );
    }
    match r.efficiency_m_per_w {
        Some(e) => println!(
            "efficiency {:.4} ± {:.4} nm/mW, unpowered bulge {:.3} ± {:.3} nm ({} scans)",
            e * 1e6,
            nan(r.efficiency_se_m_per_w) * 1e6,
            nan(r.intercept_m) * 1e9,
            nan(r.intercept_se_m) * 1e9,
            // The efficiency is fitted over the scans with a known power.
            r.scans
                .iter()
                .filter(|s| s.heater_power_mw.is_some())
                .count()
        ),
        None => println!("efficiency: needs two or more scans at different known powers"),
    }
    Ok(())
}
