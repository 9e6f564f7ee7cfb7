//! Plain ASCII matrix / Gwyddion ASCII export / CSV: one row per scan line, row 0 = top.
//!
//! Optional `#` header as Gwyddion writes it (`# Channel:`, `# Width: 12.34 µm`,
//! `# Height: 5678.9 nm`, `# Value units: m`; German `Kanal`, `Breite`, `Höhe`,
//! `Werteinheiten`). Missing sizes / height unit must come from the options: never guessed.
use super::units::{decode_text, length_factor, parse_length, parse_value, tokens};
use super::{format_error, heights_with_nan, RawMap, ReadOptions};
use crate::surface::{HeightMap, Result};
use ndarray::Array2;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;

/// Header key → the quantity it names (Gwyddion's English and German ASCII export).
fn header_quantity(key: &str) -> Option<&'static str> {
    match key {
        "channel" | "kanal" => Some("channel"),
        "width" | "breite" => Some("width"),
        "height" | "höhe" | "hoehe" => Some("height"),
        "value units" | "werteinheiten" | "werteeinheiten" | "einheiten der werte" => {
            Some("value units")
        }
        _ => None,
    }
}

/// Whether a lower-cased `# key:` is one of the ASCII-matrix header keys (for sniffing).
pub(crate) fn is_header_key(key: &str) -> bool {
    header_quantity(key).is_some()
}

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let text = decode_text(bytes);
    let mut header = BTreeMap::new();
    let mut values: Vec<f64> = Vec::new();
    let mut ncols = 0;
    let mut nrows = 0;
    for (index, line) in text.lines().enumerate() {
        let line_no = index + 1;
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        if let Some(comment) = line.strip_prefix('#') {
            if let Some((key, value)) = comment.split_once(':') {
                if let Some(quantity) = header_quantity(&key.trim().to_lowercase()) {
                    header.insert(quantity.to_string(), value.trim().to_string());
                }
            }
            continue;
        }
        let before = values.len();
        for token in tokens(line) {
            let value = parse_value(token).ok_or_else(|| {
                format_error(
                    path,
                    format!("line {line_no}: `{token}` is not a number (ASCII height matrix)"),
                )
            })?;
            values.push(value);
        }
        let n = values.len() - before;
        if nrows == 0 {
            ncols = n;
        } else if n != ncols {
            return Err(format_error(
                path,
                format!(
                    "line {line_no} has {n} values but the first data row has {ncols} \
                     (ragged ASCII matrix)"
                ),
            ));
        }
        nrows += 1;
    }
    if nrows == 0 {
        return Err(format_error(path, "no data rows in ASCII height matrix"));
    }

    let size = |key: &str, option: Option<f64>| -> Result<Option<f64>> {
        match header.get(key) {
            Some(text) => parse_length(text).map(Some).ok_or_else(|| {
                format_error(
                    path,
                    format!("header `# {key}: {text}` is not a length like `12.34 µm`"),
                )
            }),
            None => Ok(option),
        }
    };
    let (width, height) = match (size("width", opts.size_x)?, size("height", opts.size_y)?) {
        (Some(w), Some(h)) => (w, h),
        (w, h) => {
            let missing: Vec<&str> = [("size_x", w), ("size_y", h)]
                .iter()
                .filter(|(_, v)| v.is_none())
                .map(|(name, _)| *name)
                .collect();
            return Err(format_error(
                path,
                format!(
                    "no lateral size in header (# Width / # Height); give {}",
                    missing.join(" and ")
                ),
            ));
        }
    };
    let (z_unit, z_unit_source) = match (header.get("value units"), &opts.z_unit) {
        (Some(unit), _) => (unit.clone(), "header"),
        (None, Some(unit)) => (unit.clone(), "option z_unit"),
        (None, None) => {
            return Err(format_error(
                path,
                "no height unit in header (# Value units); give z_unit",
            ))
        }
    };
    let z_factor = length_factor(&z_unit).ok_or_else(|| {
        format_error(
            path,
            format!(
                "height unit `{z_unit}` ({z_unit_source}) is not a length (m, mm, µm, nm, pm, Å)"
            ),
        )
    })?;

    let z = Array2::from_shape_vec((nrows, ncols), values)
        .map_err(|e| format_error(path, format!("ASCII matrix shape: {e}")))?
        .mapv(|v| v * z_factor);
    header.insert("z_unit".into(), z_unit);
    header.insert("columns".into(), ncols.to_string());
    header.insert("rows".into(), nrows.to_string());
    Ok(RawMap {
        z,
        dx: width / ncols as f64,
        dy: height / nrows as f64,
        x0: 0.0,
        y0: 0.0,
        channel: header
            .get("channel")
            .cloned()
            .unwrap_or_else(|| "height".to_string()),
        format: "ascii",
        header,
    })
}

/// Encode as a Gwyddion-style ASCII matrix with `# Width/Height/Value units` header.
/// Sizes in µm and heights in metres, printed with the shortest text that reads back exactly;
/// invalid pixels as `NaN`.
pub fn encode_ascii_matrix(map: &HeightMap) -> Vec<u8> {
    let (width, height) = map.size();
    let mut out = String::new();
    let _ = writeln!(out, "# Channel: {}", map.channel.replace('\n', " "));
    let _ = writeln!(out, "# Width: {} µm", width * 1e6);
    let _ = writeln!(out, "# Height: {} µm", height * 1e6);
    let _ = writeln!(out, "# Value units: m");
    for row in heights_with_nan(map).rows() {
        let line: Vec<String> = row.iter().map(|v| format!("{v:e}")).collect();
        out.push_str(&line.join("\t"));
        out.push('\n');
    }
    out.into_bytes()
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};

    #[test]
    fn canonical_surface_reads_with_its_size() {
        let path = std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/surfaces/gaussian_acf_256_seed12345.txt"
        ));
        let map = read_height_map(path, &ReadOptions::default()).unwrap();
        assert_eq!(map.z.dim(), (256, 256));
        assert!(close(map.dx, 1e-6 / 256.0, 1e-15) && close(map.dy, 1e-6 / 256.0, 1e-15));
        assert_eq!(map.source.format, "ascii");
        assert!(map.valid.is_none());
        assert!(close(map.z[[0, 0]], 1.098457988982e-10, 1e-15));
    }

    #[test]
    fn round_trip() {
        let mut map = sample_map(64, 48, 3.1e-9, 4.7e-9);
        map.x0 = 0.0;
        let back = read_bytes("m.txt", &super::encode_ascii_matrix(&map)).unwrap();
        assert_same_map(&back, &map, 1e-15, 1e-15, 0.0);
        assert_eq!(back.channel, "Height");
        assert_eq!(back.source.format, "ascii");
    }

    #[test]
    fn headerless_needs_sizes_and_unit() {
        let text = b"1 2 3\n4 5 6\n7 8 9\n";
        let (_dir, path) = write_temp("plain.txt", text);
        let err = read_height_map(&path, &ReadOptions::default()).unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("size_x") && msg.contains("plain.txt"), "{msg}");
        let sized = ReadOptions {
            size_x: Some(3e-6),
            size_y: Some(6e-6),
            ..Default::default()
        };
        let err = read_height_map(&path, &sized).unwrap_err();
        assert!(err.to_string().contains("z_unit"), "{err}");
        let opts = ReadOptions {
            z_unit: Some("nm".into()),
            ..sized
        };
        let map = read_height_map(&path, &opts).unwrap();
        assert!(close(map.dx, 1e-6, 1e-15) && close(map.dy, 2e-6, 1e-15));
        assert!(close(map.z[[2, 1]], 8e-9, 1e-15));
    }

    #[test]
    fn csv_german_header_and_nan() {
        let text = "# Kanal: Höhe\n# Breite: 3 µm\n# Höhe: 1500 nm\n# Werteinheiten: nm\n\
                    1;2;3\n4,NaN,6\n7 8 9\n";
        let (_dir, path) = write_temp("de.csv", text.as_bytes());
        let map = read_height_map(&path, &ReadOptions::default()).unwrap();
        assert!(close(map.dx, 1e-6, 1e-15) && close(map.dy, 0.5e-6, 1e-15));
        let valid = map.valid.as_ref().unwrap();
        assert!(!valid[[1, 1]] && valid[[1, 0]]);
        assert_eq!(map.z[[1, 1]], 0.0);
        assert!(close(map.z[[2, 2]], 9e-9, 1e-15));
        assert_eq!(map.channel, "Höhe");
    }

    #[test]
    fn ragged_and_non_numeric_rows_name_the_line() {
        let text = b"# Width: 1 um\n# Height: 1 um\n# Value units: m\n1 2 3\n4 5 6\n7 8\n";
        let (_dir, path) = write_temp("ragged.txt", text);
        let msg = read_height_map(&path, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(msg.contains("line 6") && msg.contains("ragged"), "{msg}");
        let text = b"# Width: 1 um\n# Height: 1 um\n# Value units: m\n1 2 3\n4 x 6\n7 8 9\n";
        let (_dir, path) = write_temp("word.txt", text);
        let msg = read_height_map(&path, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(msg.contains("line 5") && msg.contains("`x`"), "{msg}");
        let text = b"# Width: 1 um\n# Height: 1 um\n# Value units: V\n1 2 3\n4 5 6\n7 8 9\n";
        let (_dir, path) = write_temp("volt.txt", text);
        let msg = read_height_map(&path, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(msg.contains("not a length"), "{msg}");
    }
}
