//! XYZ text (three columns x y z) on a rectangular lattice.
//!
//! Units: header `# xy_unit: um` and `# z_unit: nm` (or `# Units: xy=um z=nm`); the height unit
//! may instead come from `ReadOptions::z_unit`. The lateral unit has no option and is never
//! assumed, so a file without `xy_unit` is refused.
//!
//! Convention (Gwyddion's: y grows downwards in the image): row j holds the j-th smallest y,
//! column i the i-th smallest x; `x0`, `y0` are the smallest x and y. `encode_xyz` writes
//! `x = x0 + i·dx`, `y = y0 + j·dy`, row by row, so the pair round-trips.
use super::units::{decode_text, length_factor, parse_value, tokens};
use super::{format_error, heights_with_nan, RawMap, ReadOptions};
use crate::surface::{HeightMap, Result};
use ndarray::Array2;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;

const REGULARISE_HINT: &str = "rasterise it onto a regular grid first (e.g. Gwyddion's XYZ \
    import with regularisation); a 3-column height matrix needs a `# Width:` header instead";

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let text = decode_text(bytes);
    let mut header = BTreeMap::new();
    let mut points: Vec<[f64; 3]> = Vec::new();
    for (index, line) in text.lines().enumerate() {
        let line_no = index + 1;
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        if let Some(comment) = line.strip_prefix('#') {
            parse_header_line(comment, &mut header);
            continue;
        }
        let mut values = [0.0; 3];
        let mut count = 0;
        for token in tokens(line) {
            let value = parse_value(token).ok_or_else(|| {
                format_error(
                    path,
                    format!("line {line_no}: `{token}` is not a number (XYZ)"),
                )
            })?;
            if count < 3 {
                values[count] = value;
            }
            count += 1;
        }
        if count != 3 {
            return Err(format_error(
                path,
                format!("line {line_no} has {count} values; XYZ needs exactly 3 (x y z)"),
            ));
        }
        if !(values[0].is_finite() && values[1].is_finite()) {
            return Err(format_error(
                path,
                format!("line {line_no}: x or y is not finite"),
            ));
        }
        points.push(values);
    }

    let xy_unit = header.get("xy_unit").cloned().ok_or_else(|| {
        format_error(
            path,
            "no lateral unit in XYZ header; add a line `# xy_unit: m`",
        )
    })?;
    let (z_unit, z_source) = match (header.get("z_unit"), &opts.z_unit) {
        (Some(unit), _) => (unit.clone(), "header"),
        (None, Some(unit)) => (unit.clone(), "option z_unit"),
        (None, None) => {
            return Err(format_error(
                path,
                "no height unit in XYZ header (# z_unit: m); give z_unit",
            ))
        }
    };
    let not_length = |unit: &str, source: &str| {
        format_error(
            path,
            format!("{source} unit `{unit}` is not a length (m, µm, nm, ...)"),
        )
    };
    let xy_factor = length_factor(&xy_unit).ok_or_else(|| not_length(&xy_unit, "xy"))?;
    let z_factor = length_factor(&z_unit).ok_or_else(|| not_length(&z_unit, z_source))?;

    let lattice_error = |what: String| format_error(path, format!("{what}; {REGULARISE_HINT}"));
    let x_axis =
        Axis::of(points.iter().map(|p| p[0])).map_err(|e| lattice_error(format!("x: {e}")))?;
    let y_axis =
        Axis::of(points.iter().map(|p| p[1])).map_err(|e| lattice_error(format!("y: {e}")))?;
    let (nx, ny) = (x_axis.count, y_axis.count);
    if nx.checked_mul(ny) != Some(points.len()) {
        return Err(lattice_error(format!(
            "{} points are not a rectangular lattice ({nx} distinct x × {ny} distinct y)",
            points.len()
        )));
    }
    let mut z = Array2::from_elem((ny, nx), f64::NAN);
    let mut seen = Array2::from_elem((ny, nx), false);
    for p in &points {
        let (i, j) = match (x_axis.index(p[0]), y_axis.index(p[1])) {
            (Some(i), Some(j)) => (i, j),
            _ => {
                return Err(lattice_error(format!(
                    "point ({}, {}) is off the lattice",
                    p[0], p[1]
                )))
            }
        };
        if seen[[j, i]] {
            return Err(lattice_error(format!(
                "lattice point ({}, {}) appears twice",
                p[0], p[1]
            )));
        }
        seen[[j, i]] = true;
        z[[j, i]] = p[2] * z_factor;
    }
    header.insert("points".into(), points.len().to_string());
    header.insert("z_unit".into(), z_unit);
    Ok(RawMap {
        z,
        dx: x_axis.spacing * xy_factor,
        dy: y_axis.spacing * xy_factor,
        x0: x_axis.min * xy_factor,
        y0: y_axis.min * xy_factor,
        channel: "height".to_string(),
        format: "xyz",
        header,
    })
}

/// `# xy_unit: um`, `# z_unit: nm` or `# Units: xy=um z=nm`.
fn parse_header_line(comment: &str, header: &mut BTreeMap<String, String>) {
    let Some((key, value)) = comment.split_once(':') else {
        return;
    };
    match key.trim().to_lowercase().as_str() {
        "xy_unit" => {
            header.insert("xy_unit".into(), value.trim().to_string());
        }
        "z_unit" => {
            header.insert("z_unit".into(), value.trim().to_string());
        }
        "units" => {
            for item in tokens(value) {
                if let Some((k, v)) = item.split_once('=') {
                    let k = k.trim().to_lowercase();
                    if k == "xy" || k == "z" {
                        header.insert(format!("{k}_unit"), v.trim().to_string());
                    }
                }
            }
        }
        _ => {}
    }
}

/// The distinct coordinate values along one axis, checked to be uniformly spaced.
struct Axis {
    min: f64,
    spacing: f64,
    count: usize,
}

impl Axis {
    fn of(values: impl Iterator<Item = f64>) -> std::result::Result<Axis, String> {
        let mut sorted: Vec<f64> = values.collect();
        sorted.sort_by(f64::total_cmp);
        let (Some(&min), Some(&max)) = (sorted.first(), sorted.last()) else {
            return Err("no points".into());
        };
        if max <= min {
            return Err("all points share one coordinate".into());
        }
        // Values within 1e-9 of the range are the same lattice line (text rounding).
        let same = 1e-9 * (max - min);
        let mut distinct = vec![min];
        for &v in &sorted[1..] {
            if v - distinct[distinct.len() - 1] > same {
                distinct.push(v);
            }
        }
        let count = distinct.len();
        let spacing = (max - min) / (count - 1) as f64;
        for pair in distinct.windows(2) {
            let step = pair[1] - pair[0];
            if (step - spacing).abs() > 1e-6 * spacing {
                return Err(format!(
                    "spacing {step} between {} and {} differs from the mean {spacing}",
                    pair[0], pair[1]
                ));
            }
        }
        Ok(Axis {
            min,
            spacing,
            count,
        })
    }

    fn index(&self, v: f64) -> Option<usize> {
        let position = (v - self.min) / self.spacing;
        let k = position.round();
        let on_lattice = (position - k).abs() <= 1e-6 && k >= 0.0 && k < self.count as f64;
        on_lattice.then_some(k as usize)
    }
}

/// Encode as XYZ text in metres (`# xy_unit: m`, `# z_unit: m`), x fastest, invalid pixels as
/// `NaN`. See the module doc for the row ↔ y convention.
pub fn encode_xyz(map: &HeightMap) -> Vec<u8> {
    let mut out = String::new();
    let _ = writeln!(out, "# Channel: {}", map.channel.replace('\n', " "));
    let _ = writeln!(out, "# xy_unit: m");
    let _ = writeln!(out, "# z_unit: m");
    for ((j, i), z) in heights_with_nan(map).indexed_iter() {
        let x = map.x0 + i as f64 * map.dx;
        let y = map.y0 + j as f64 * map.dy;
        let _ = writeln!(out, "{x:e} {y:e} {z:e}");
    }
    out.into_bytes()
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};

    #[test]
    fn round_trip_with_unequal_spacing_and_offsets() {
        let mut map = sample_map(64, 48, 2.5e-9, 7.0e-9);
        map.x0 = 1e-6;
        map.y0 = -3e-7;
        let mut valid = ndarray::Array2::from_elem((48, 64), true);
        valid[[5, 7]] = false;
        map.z[[5, 7]] = 0.0;
        map.valid = Some(valid);
        let back = read_bytes("m.xyz", &super::encode_xyz(&map)).unwrap();
        assert_eq!(back.source.format, "xyz");
        assert_same_map(&back, &map, 1e-13, 1e-15, 0.0);
        assert!(close(back.x0, 1e-6, 1e-15) && close(back.y0, -3e-7, 1e-15));
        assert!(!back.is_valid(5, 7) && back.is_valid(5, 8));
    }

    #[test]
    fn units_from_header_or_options() {
        // y order in the file is irrelevant: row 0 is the smallest y.
        let mut text = String::from("# Units: xy=um\n");
        for j in (0..3).rev() {
            for i in 0..4 {
                text += &format!("{} {} {}\n", i as f64 * 0.5, j as f64 * 2.0, 10 * j + i);
            }
        }
        let (_dir, path) = write_temp("p.xyz", text.as_bytes());
        let err = read_height_map(&path, &ReadOptions::default()).unwrap_err();
        assert!(err.to_string().contains("z_unit"), "{err}");
        let opts = ReadOptions {
            z_unit: Some("nm".into()),
            ..Default::default()
        };
        let map = read_height_map(&path, &opts).unwrap();
        assert_eq!(map.z.dim(), (3, 4));
        assert!(close(map.dx, 0.5e-6, 1e-15) && close(map.dy, 2e-6, 1e-15));
        assert!(close(map.z[[2, 3]], 23e-9, 1e-15));
        assert!(close(map.z[[0, 1]], 1e-9, 1e-15));

        let no_xy = text.replace("# Units: xy=um\n", "# z_unit: nm\n");
        let (_dir, path) = write_temp("q.xyz", no_xy.as_bytes());
        let err = read_height_map(&path, &ReadOptions::default()).unwrap_err();
        assert!(err.to_string().contains("xy_unit"), "{err}");
    }

    #[test]
    fn scattered_points_are_refused() {
        let text = "# xy_unit: m\n# z_unit: m\n0 0 1\n1 0 1\n2 0 1\n0 1 1\n1 1 1\n2.3 1 1\n\
                    0 2 1\n1 2 1\n2 2 1\n";
        let (_dir, path) = write_temp("s.xyz", text.as_bytes());
        let msg = read_height_map(&path, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(msg.contains("Gwyddion") && msg.contains("s.xyz"), "{msg}");
        let missing = "# xy_unit: m\n# z_unit: m\n0 0 1\n1 0 1\n2 0 1\n0 1 1\n1 1 1\n\
                       0 2 1\n1 2 1\n2 2 1\n";
        let (_dir, path) = write_temp("m.xyz", missing.as_bytes());
        let msg = read_height_map(&path, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(msg.contains("rectangular lattice"), "{msg}");
        // Nine points, 3 × 3 distinct coordinates, but (1, 1) twice and (2, 1) missing.
        let twice = "# xy_unit: m\n# z_unit: m\n0 0 1\n1 0 1\n2 0 1\n0 1 1\n1 1 1\n1 1 1\n\
                     0 2 1\n1 2 1\n2 2 1\n";
        let (_dir, path) = write_temp("t.xyz", twice.as_bytes());
        let msg = read_height_map(&path, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(msg.contains("twice"), "{msg}");
    }
}
