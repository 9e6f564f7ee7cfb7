//! Plain x–z text: two numeric columns (separated by white space, commas or semicolons), one
//! point per line, x not necessarily uniform. Units, optional: comment lines `# x_unit: um` and
//! `# z_unit: nm` (`# unit:` for both; Gwyddion's `# Lateral units:` / `# Value units:` too) or
//! a first line of two unit symbols (`µm µm`, as SurfaceTopography's xy-2.txt); without them
//! the numbers are metres. `NaN` heights are invalid points. docs/surfaces.md.

use super::{format_error, number, unit_factor, RawProfile};
use crate::surface::io::units::{decode_text, parse_value, tokens};
use crate::surface::Result;
use std::collections::BTreeMap;
use std::path::Path;

/// Which unit a `# key: value` comment sets: (x, z).
fn unit_key(key: &str) -> Option<(bool, bool)> {
    match key.trim().to_lowercase().as_str() {
        "x_unit" | "lateral units" | "lateral unit" => Some((true, false)),
        "z_unit" | "value units" | "value unit" => Some((false, true)),
        "unit" | "units" => Some((true, true)),
        _ => None,
    }
}

/// Two unit symbols on one line (`µm nm`): their factors.
fn unit_line(line: &str) -> Option<(f64, f64)> {
    let t: Vec<&str> = tokens(line).collect();
    match t.as_slice() {
        [a, b] => Some((unit_factor(a)?, unit_factor(b)?)),
        _ => None,
    }
}

fn is_pair(line: &str) -> bool {
    let t: Vec<&str> = tokens(line).collect();
    t.len() == 2 && t.iter().all(|v| parse_value(v).is_some())
}

/// Text whose first data lines (after comments and an optional unit line) are number pairs.
pub(crate) fn looks_like(head: &[u8]) -> bool {
    let is_binary = |b: &u8| *b == 0 || (*b < 0x20 && !matches!(*b, b'\t' | b'\n' | b'\r'));
    if head.is_empty() || head.iter().any(is_binary) {
        return false;
    }
    let text = decode_text(head);
    let complete = head.ends_with(b"\n");
    let lines: Vec<&str> = text.lines().collect();
    let mut pairs = 0;
    let mut first = true;
    for (k, line) in lines.iter().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if first && unit_line(line).is_some() {
            first = false;
            continue;
        }
        first = false;
        if k + 1 == lines.len() && !complete {
            break;
        }
        if !is_pair(line) {
            return false;
        }
        pairs += 1;
        if pairs == 2 {
            return true;
        }
    }
    pairs >= 1
}

pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<RawProfile> {
    let text = decode_text(bytes);
    let lines: Vec<&str> = text.lines().collect();
    let (mut fx, mut fz) = (None, None);
    let mut header = BTreeMap::new();
    let (mut x, mut z) = (Vec::new(), Vec::new());
    let mut first = true;
    for (i, line) in lines.iter().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        if let Some(comment) = line.strip_prefix('#') {
            if let Some((key, value)) = comment.split_once(':') {
                header.insert(key.trim().to_string(), value.trim().to_string());
                if let Some((sx, sz)) = unit_key(key) {
                    let f = unit_factor(value).ok_or_else(|| {
                        format_error(
                            path,
                            format!("line {}: `{}` is not a length unit", i + 1, value.trim()),
                        )
                    })?;
                    if sx {
                        fx = Some(f);
                    }
                    if sz {
                        fz = Some(f);
                    }
                }
            }
            continue;
        }
        if first {
            first = false;
            if let Some((a, b)) = unit_line(line) {
                header.insert("units".into(), line.to_string());
                fx = Some(a);
                fz = Some(b);
                continue;
            }
        }
        let t: Vec<&str> = tokens(line).collect();
        let [a, b] = t.as_slice() else {
            return Err(format_error(
                path,
                format!(
                    "line {}: expected two numbers (x z), found {}",
                    i + 1,
                    t.len()
                ),
            ));
        };
        let (a, b) = (number(path, i + 1, a)?, number(path, i + 1, b)?);
        x.push(a);
        z.push(b);
    }
    let (fx, fz) = (fx.unwrap_or(1.0), fz.unwrap_or(1.0));
    for v in &mut x {
        *v *= fx;
    }
    for v in &mut z {
        *v *= fz;
    }
    Ok(RawProfile { x, z, header })
}
