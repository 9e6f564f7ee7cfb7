//! Bruker Dektak CSV export: `Scan Parameters` and `Analytical Results` as `key,value` lines,
//! then `Scan Data`, a column header with the units (`Lateral um,Raw Micrometer,`) and
//! `x,z,,` rows (Dektak 150 / XT "Export to CSV"; the layout SurfaceTopography 1.27.1's
//! `read_text_header_dektak` documents). Lines may end in `\r\r\n`.

use super::{format_error, number, unit_factor, RawProfile};
use crate::surface::io::units::decode_text;
use crate::surface::Result;
use std::collections::BTreeMap;
use std::path::Path;

pub(crate) const MAGIC: &[u8] = b"Scan Parameters";

/// The length unit named by one column header (`Lateral um`, `Raw Micrometer`).
fn column_unit(path: &Path, header: &str, what: &str) -> Result<f64> {
    header
        .split_whitespace()
        .rev()
        .find_map(unit_factor)
        .ok_or_else(|| {
            format_error(
                path,
                format!("no length unit in the {what} column header `{header}`"),
            )
        })
}

pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<RawProfile> {
    let text = decode_text(bytes);
    let mut lines = text
        .split('\n')
        .map(|l| l.trim_end_matches('\r'))
        .enumerate();
    let mut header = BTreeMap::new();
    let mut found = false;
    for (_, line) in lines.by_ref() {
        if line.trim() == "Scan Data" {
            found = true;
            break;
        }
        if let Some((k, v)) = line.split_once(',') {
            header.insert(k.trim().to_string(), v.trim().to_string());
        }
    }
    if !found {
        return Err(format_error(path, "no `Scan Data` section"));
    }
    let Some((_, columns)) = lines.by_ref().find(|(_, l)| !l.trim().is_empty()) else {
        return Err(format_error(path, "no column header after `Scan Data`"));
    };
    let cols: Vec<&str> = columns.split(',').collect();
    if cols.len() < 2 {
        return Err(format_error(
            path,
            format!("column header `{columns}` has fewer than two columns"),
        ));
    }
    let fx = column_unit(path, cols[0], "position")?;
    let fz = column_unit(path, cols[1], "height")?;
    header.insert("x column".into(), cols[0].trim().to_string());
    header.insert("z column".into(), cols[1].trim().to_string());
    let (mut x, mut z) = (Vec::new(), Vec::new());
    let ends_with_newline = bytes.ends_with(b"\n");
    let rest: Vec<(usize, &str)> = lines.collect();
    for (k, &(i, line)) in rest.iter().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        if k + 1 == rest.len() && !ends_with_newline {
            return Err(format_error(
                path,
                format!(
                    "line {}: the last data line has no line end; the file is probably truncated",
                    i + 1
                ),
            ));
        }
        let mut f = line.split(',');
        let (Some(a), Some(b)) = (f.next(), f.next()) else {
            return Err(format_error(path, format!("line {}: expected x,z", i + 1)));
        };
        x.push(number(path, i + 1, a)? * fx);
        z.push(number(path, i + 1, b)? * fz);
    }
    Ok(RawProfile { x, z, header })
}
