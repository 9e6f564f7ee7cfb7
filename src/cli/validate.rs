//! `hdi validate`: every reproducible number of the specs against hdi's value.

use anyhow::{bail, Context, Result};
use serde_json::{json, Value};
use std::path::Path;

/// Six significant digits, scientific for very small or large magnitudes.
fn fmt_number(x: f64) -> String {
    let a = x.abs();
    if x != 0.0 && !(1e-3..1e7).contains(&a) {
        format!("{x:.5e}")
    } else {
        format!("{x:.6}")
    }
}

pub(super) fn cmd_validate(as_json: bool, only: &[String], config: &Path) -> Result<()> {
    let mut known: Vec<&str> = hdi::validate::AREAS.iter().map(|(a, _)| *a).collect();
    known.push("calibration");
    known.push("optimisation");
    for o in only {
        if !known.contains(&o.as_str()) {
            bail!(
                "--only: unknown area `{o}` (available: {})",
                known.join(", ")
            );
        }
    }
    let wants = |a: &str| only.is_empty() || only.iter().any(|o| o == a);
    let mut areas: Vec<(&'static str, Vec<hdi::validate::Row>)> = hdi::validate::AREAS
        .iter()
        .filter(|(a, _)| wants(a))
        .map(|(a, rows)| (*a, rows()))
        .collect();
    // The fits of the pipeline in the working directory, when there is one (or when asked).
    if wants("calibration") && (config.exists() || !only.is_empty()) {
        let rows = hdi::stages::calibrate::validation_rows(config)
            .with_context(|| format!("calibration rows from {}", config.display()))?;
        areas.push(("calibration", rows));
    }
    if wants("optimisation") && (config.exists() || !only.is_empty()) {
        let rows = hdi::stages::doe::validation_rows(config)
            .with_context(|| format!("optimisation rows from {}", config.display()))?;
        areas.push(("optimisation", rows));
    }
    let failed = hdi::validate::failures(&areas);
    let total: usize = areas.iter().map(|(_, r)| r.len()).sum();
    if as_json {
        let out: serde_json::Map<String, Value> = areas
            .iter()
            .map(|(a, rows)| {
                (
                    a.to_string(),
                    Value::Array(rows.iter().map(|r| r.to_json()).collect()),
                )
            })
            .collect();
        println!("{}", json!({"areas": out, "rows": total, "failed": failed}));
    } else {
        for (area, rows) in &areas {
            println!("── {area} ──");
            println!(
                "{:<6} {:<58} {:>12} {:>12} {:>10}  variant / note",
                "", "quantity", "target", "hdi", "tolerance"
            );
            for r in rows {
                let status = match (r.pass(), r.reproducible) {
                    (true, _) => "pass",
                    (false, true) => "FAIL",
                    (false, false) => "differs",
                };
                // Tolerances span 1e-12 … 50 %: short forms, scientific when tiny.
                let short = |x: f64| {
                    if x != 0.0 && x.abs() < 1e-3 {
                        format!("{x:.0e}")
                    } else {
                        format!("{}", (x * 1e4).round() / 1e4)
                    }
                };
                let tol = match r.tolerance {
                    hdi::validate::Tolerance::Relative(t) => format!("±{}%", short(t * 100.0)),
                    hdi::validate::Tolerance::Absolute(t) => format!("±{}", short(t)),
                };
                let unit = if r.unit == "1" {
                    String::new()
                } else {
                    format!(" {}", r.unit)
                };
                println!(
                    "{:<6} {:<58} {:>12} {:>12} {:>10}  {}{}",
                    status,
                    format!("{}{}", r.quantity, unit),
                    fmt_number(r.target),
                    fmt_number(r.ours),
                    tol,
                    r.variant,
                    if r.note.is_empty() {
                        String::new()
                    } else {
                        format!(" — {}", r.note)
                    }
                );
            }
        }
        eprintln!("{} rows, {} reproducible failed", total, failed);
    }
    if failed > 0 {
        std::process::exit(1);
    }
    Ok(())
}
