//! `hdi diff A B`: the library compares (`hdi::engine::diff`), this prints.

use anyhow::Result;
use serde_json::Value;

use super::args::DiffArgs;
use hdi::engine::diff::{self, Diff, Options};

/// Exit status 1 for "A and B differ" (like `diff`).
pub struct Differs;
impl std::fmt::Debug for Differs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "differs")
    }
}
impl std::fmt::Display for Differs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "A and B differ")
    }
}
impl std::error::Error for Differs {}

pub(super) fn cmd_diff(args: DiffArgs) -> Result<()> {
    let opts = Options {
        rtol: args.rtol,
        all: args.all,
    };
    opts.check()?;
    let a = diff::load(&args.a)?;
    let b = diff::load(&args.b)?;
    let d = diff::compare(&a, &b, &opts)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&d)?);
    } else {
        print_text(&d);
    }
    if d.identical {
        Ok(())
    } else {
        Err(Differs.into())
    }
}

fn print_text(d: &Diff) {
    let s = &d.summary;
    let mut blocks: Vec<Vec<Vec<String>>> = Vec::new();
    if !d.instances.is_empty() {
        let mut rows = vec![row(&["instance", "kind", "status", "why"])];
        for i in &d.instances {
            rows.push(vec![
                i.name.clone(),
                i.kind.clone(),
                i.status.as_str().to_string(),
                i.why.join("; "),
            ]);
        }
        blocks.push(rows);
    }
    if !d.params.is_empty() {
        let mut rows = vec![row(&["instance", "parameter (SI)", "old", "new"])];
        for p in &d.params {
            rows.push(vec![
                p.instance.clone(),
                p.key.clone(),
                value(&p.old),
                value(&p.new),
            ]);
        }
        blocks.push(rows);
    }
    if !d.metrics.is_empty() {
        let mut rows = vec![row(&[
            "instance", "source", "metric", "old", "new", "delta", "rel",
        ])];
        for m in &d.metrics {
            rows.push(vec![
                m.instance.clone(),
                m.source.clone(),
                m.metric.clone(),
                value(&m.old),
                value(&m.new),
                m.delta.map(number).unwrap_or_default(),
                m.rel_delta
                    .map(|r| format!("{:+.3}%", r * 100.0))
                    .unwrap_or_default(),
            ]);
        }
        blocks.push(rows);
    }
    for (i, b) in blocks.iter().enumerate() {
        if i > 0 {
            println!();
        }
        print_aligned(b);
    }
    let verdict = if d.identical { "identical" } else { "differ" };
    eprintln!(
        "{verdict}: {} changed, {} added, {} removed, {} unchanged instance(s); {} parameter(s) \
         changed; {} of {} metric(s) differ{}",
        s.changed,
        s.added,
        s.removed,
        s.unchanged,
        s.params_changed,
        s.metrics_changed,
        s.metrics_compared,
        if d.rtol > 0.0 {
            format!(" (rtol {})", d.rtol)
        } else {
            String::new()
        }
    );
}

fn row(cells: &[&str]) -> Vec<String> {
    cells.iter().map(|c| c.to_string()).collect()
}

/// Columns padded to their widest cell (the last one left ragged).
fn print_aligned(rows: &[Vec<String>]) {
    let n = rows.iter().map(Vec::len).max().unwrap_or(0);
    let widths: Vec<usize> = (0..n)
        .map(|c| {
            rows.iter()
                .filter_map(|r| r.get(c))
                .map(|s| s.chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    for r in rows {
        let mut line = String::new();
        for (c, cell) in r.iter().enumerate() {
            if c + 1 == r.len() {
                line.push_str(cell);
            } else {
                let pad = widths[c] - cell.chars().count();
                line.push_str(cell);
                line.push_str(&" ".repeat(pad + 2));
            }
        }
        println!("{}", line.trim_end());
    }
}

/// A value as written in the source (numbers in shortest round-trip form), `-` for none.
fn value(v: &Value) -> String {
    match v {
        Value::Null => "-".into(),
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// A delta to 7 significant digits: fixed-point for 1e-3 ≤ |x| < 1e6, else exponent form.
fn number(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let e = x.abs().log10().floor() as i32;
    if (-3..6).contains(&e) {
        let decimals = (6 - e).max(0) as usize;
        let s = format!("{x:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{x:.6e}")
    }
}
