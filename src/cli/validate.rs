//! `hdi validate`: the published targets, one typed row each (docs/validation.md). Rows are
//! computed now by the library, or read from the pipeline's cache where the `origin` column
//! says so (calibrated values, the DOE optimum, the 3-DOF stage outputs, the spectra).

use anyhow::{bail, Context, Result};
use hdi::validation::document::ValidateDocument;
use hdi::validation::{class_counts, gate, ledger, Class, Row};
use std::path::Path;

/// Six significant digits, scientific for very small or large magnitudes; `–` for none.
fn fmt_number(x: f64) -> String {
    let a = x.abs();
    if !x.is_finite() {
        "–".into()
    } else if x != 0.0 && !(1e-3..1e7).contains(&a) {
        format!("{x:.5e}")
    } else {
        format!("{x:.6}")
    }
}

/// The `--class` list, parsed.
fn parse_classes(class: &[String]) -> Result<Vec<Class>> {
    class
        .iter()
        .filter(|c| !c.trim().is_empty())
        .map(|c| {
            Class::parse(c)
                .with_context(|| format!("--class: unknown class `{c}` (available: G, K, D, Q, C)"))
        })
        .collect()
}

/// `G 12/12, K 9/9, D 3/40, …` (passes/rows per class).
fn summary(rows: &[&Row]) -> String {
    class_counts(rows.iter().copied())
        .iter()
        .map(|(c, n, p)| format!("{} {p}/{n}", c.label()))
        .collect::<Vec<_>>()
        .join(", ")
}

fn print_table(areas: &[(&'static str, Vec<&Row>)]) {
    for (area, rows) in areas {
        println!("── {area} ──");
        println!(
            "{:<7} {:<22} {:<2} {:<15} {:<62} {:>12} {:>12} {:>14} {:>16} {:>10}  origin / variant / note",
            "", "id", "cl", "basis", "quantity", "target", "hdi", "synth. record", "calibrated", "tolerance"
        );
        for r in rows {
            let c = r.cells(fmt_number);
            let unit = c.unit.map_or(String::new(), |u| format!(" {u}"));
            println!(
                "{:<7} {:<22} {:<2} {:<15} {:<62} {:>12} {:>12} {:>14} {:>16} {:>10}  {}",
                r.verdict(),
                r.id,
                r.class.label(),
                c.basis,
                format!("{}{}", r.quantity, unit),
                c.target,
                c.value,
                c.record,
                c.calibrated,
                c.tolerance,
                c.notes
            );
        }
    }
}

pub(super) fn cmd_validate(
    as_json: bool,
    only: &[String],
    class: &[String],
    config: &Path,
) -> Result<()> {
    let known: Vec<&str> = hdi::validation::AREAS.iter().map(|a| a.name).collect();
    for o in only {
        if !known.contains(&o.as_str()) {
            bail!(
                "--only: unknown area `{o}` (available: {})",
                known.join(", ")
            );
        }
    }
    let classes = parse_classes(class)?;
    let wants = |a: &str| only.is_empty() || only.iter().any(|o| o == a);
    let mut computed: Vec<(&'static str, Vec<Row>)> = Vec::new();
    for area in hdi::validation::AREAS.iter().filter(|a| wants(a.name)) {
        // The fits of the pipeline in the working directory, when there is one (or when asked).
        if area.needs_pipeline() && !config.exists() && only.is_empty() {
            continue;
        }
        let rows = area
            .rows(config)
            .with_context(|| format!("{} rows from {}", area.name, config.display()))?;
        computed.push((area.name, rows));
    }
    let areas: Vec<(&'static str, Vec<&Row>)> = computed
        .iter()
        .map(|(a, rows)| {
            (
                *a,
                rows.iter()
                    .filter(|r| classes.is_empty() || classes.contains(&r.class))
                    .collect(),
            )
        })
        .collect();
    let all: Vec<&Row> = areas.iter().flat_map(|(_, r)| r.iter().copied()).collect();
    let failed = gate(all.iter().copied(), &classes);
    if as_json {
        let doc = ValidateDocument::new(&areas, &failed);
        println!("{}", serde_json::to_string(&doc)?);
    } else {
        print_table(&areas);
        for line in ledger(all.iter().copied()).lines() {
            eprintln!("{line}");
        }
        eprintln!(
            "{} rows (passes/rows per class: {}); {} gated row(s) failed{}",
            all.len(),
            summary(&all),
            failed.len(),
            if failed.is_empty() {
                String::new()
            } else {
                format!(
                    ": {}",
                    failed
                        .iter()
                        .map(|r| r.id.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            }
        );
    }
    if !failed.is_empty() {
        std::process::exit(1);
    }
    Ok(())
}
