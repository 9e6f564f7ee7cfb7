//! `.hfm` profile text: a header `X;Y;valid`, a unit line `[mm];[mm];[1/0]`, then
//! `x;z;valid` rows (the layout SurfaceTopography 1.27.1's `read_text_header_hfm` documents;
//! the second column is the height). Points with `valid` 0 are invalid.

use super::{format_error, number, unit_factor, RawProfile};
use crate::surface::io::units::decode_text;
use crate::surface::Result;
use std::collections::BTreeMap;
use std::path::Path;

pub(crate) const MAGIC: &[u8] = b"X;Y;valid";

pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<RawProfile> {
    let text = decode_text(bytes);
    let mut lines = text
        .split('\n')
        .map(|l| l.trim_end_matches('\r'))
        .enumerate();
    if lines.next().map(|(_, l)| l.trim()) != Some("X;Y;valid") {
        return Err(format_error(path, "first line is not `X;Y;valid`"));
    }
    let Some((_, units)) = lines.next() else {
        return Err(format_error(path, "no unit line after `X;Y;valid`"));
    };
    let u: Vec<&str> = units.split(';').collect();
    let unit = |k: usize, what: &str| {
        u.get(k).and_then(|w| unit_factor(w)).ok_or_else(|| {
            format_error(
                path,
                format!("unit line `{units}`: no length unit for {what}"),
            )
        })
    };
    let (fx, fz) = (unit(0, "X")?, unit(1, "Y (the height)")?);
    let header = BTreeMap::from([("units".to_string(), units.trim().to_string())]);
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
        let f: Vec<&str> = line.split(';').collect();
        let [a, b, v] = f.as_slice() else {
            return Err(format_error(
                path,
                format!("line {}: expected x;z;valid", i + 1),
            ));
        };
        let valid = match v.trim() {
            "1" => true,
            "0" => false,
            other => {
                return Err(format_error(
                    path,
                    format!("line {}: valid flag `{other}` is not 0 or 1", i + 1),
                ))
            }
        };
        x.push(number(path, i + 1, a)? * fx);
        let h = number(path, i + 1, b)? * fz;
        z.push(if valid { h } else { f64::NAN });
    }
    Ok(RawProfile { x, z, header })
}
