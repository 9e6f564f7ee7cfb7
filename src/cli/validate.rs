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
    let known: Vec<&str> = hdi::validation::AREAS.iter().map(|a| a.name).collect();
    for o in only {
        if !known.contains(&o.as_str()) {
            bail!(
                "--only: unknown area `{o}` (available: {})",
                known.join(", ")
            );
        }
    }
    let wants = |a: &str| only.is_empty() || only.iter().any(|o| o == a);
    let mut areas: Vec<(&'static str, Vec<hdi::validation::Row>)> = Vec::new();
    for area in hdi::validation::AREAS.iter().filter(|a| wants(a.name)) {
        // The fits of the pipeline in the working directory, when there is one (or when asked).
        if area.needs_pipeline() && !config.exists() && only.is_empty() {
            continue;
        }
        let rows = area
            .rows(config)
            .with_context(|| format!("{} rows from {}", area.name, config.display()))?;
        areas.push((area.name, rows));
    }
    let failed = hdi::validation::failures(&areas);
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
                    hdi::validation::Tolerance::Relative(t) => format!("±{}%", short(t * 100.0)),
                    hdi::validation::Tolerance::Absolute(t) => format!("±{}", short(t)),
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
