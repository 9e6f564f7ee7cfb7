//! Gwyddion Simple Field (`.gsf`): `Gwyddion Simple Field 1.0\n`, `Key = Value` lines, 1–4 NUL
//! bytes so that header + padding is a multiple of 4, then XRes·YRes f32 LE, row 0 = top.
use super::units::{decode_text, length_factor};
use super::{format_error, heights_with_nan, unsupported, RawMap, ReadOptions};
use crate::surface::{HeightMap, Result};
use ndarray::Array2;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;

const MAGIC: &[u8] = b"Gwyddion Simple Field 1.0\n";

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    if !bytes.starts_with(MAGIC) {
        let first_line = bytes.split(|&b| b == b'\n').next().unwrap_or_default();
        return Err(unsupported(
            path,
            format!(
                "Gwyddion Simple Field header `{}`; only version 1.0 is read",
                String::from_utf8_lossy(&first_line[..first_line.len().min(40)])
            ),
        ));
    }
    let header_len = bytes.iter().position(|&b| b == 0).ok_or_else(|| {
        format_error(
            path,
            "GSF header has no NUL padding before the data (truncated?)",
        )
    })?;
    let data_start = (header_len / 4 + 1) * 4;
    let mut header = BTreeMap::new();
    for line in decode_text(&bytes[MAGIC.len()..header_len]).lines() {
        if let Some((key, value)) = line.split_once('=') {
            header.insert(key.trim().to_string(), value.trim().to_string());
        }
    }
    // Keys are case-sensitive in the GSF spec; accept any case.
    let get = |key: &str| {
        header
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(key))
            .map(|(_, v)| v.as_str())
    };
    let res = |key: &str| -> Result<usize> {
        let text = get(key).ok_or_else(|| format_error(path, format!("GSF header lacks {key}")))?;
        text.parse::<usize>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| {
                format_error(
                    path,
                    format!("GSF {key} = `{text}` is not a positive integer"),
                )
            })
    };
    let real = |key: &str, default: Option<f64>| -> Result<f64> {
        match get(key) {
            None => default.ok_or_else(|| format_error(path, format!("GSF header lacks {key}"))),
            Some(text) => text
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format_error(path, format!("GSF {key} = `{text}` is not a number"))),
        }
    };
    let (nx, ny) = (res("XRes")?, res("YRes")?);
    let (x_real, y_real) = (real("XReal", None)?, real("YReal", None)?);
    let (x_off, y_off) = (real("XOffset", Some(0.0))?, real("YOffset", Some(0.0))?);

    let xy_unit = get("XYUnits").ok_or_else(|| {
        format_error(
            path,
            "GSF header lacks XYUnits; the lateral unit is not guessed",
        )
    })?;
    let xy_factor = length_factor(xy_unit)
        .ok_or_else(|| format_error(path, format!("GSF XYUnits `{xy_unit}` is not a length")))?;
    let z_unit = get("ZUnits")
        .map(str::to_string)
        .or_else(|| opts.z_unit.clone())
        .ok_or_else(|| format_error(path, "GSF header lacks ZUnits; give z_unit"))?;
    let z_factor = length_factor(&z_unit)
        .ok_or_else(|| format_error(path, format!("GSF ZUnits `{z_unit}` is not a length")))?;

    let needed = nx.checked_mul(ny).and_then(|n| n.checked_mul(4));
    let available = bytes.len().saturating_sub(data_start);
    match needed {
        Some(needed) if needed <= available => {}
        _ => {
            return Err(format_error(
                path,
                format!(
                    "truncated GSF file: {nx}×{ny} f32 values need {} bytes at offset \
                     {data_start} but the file has {}",
                    needed.map_or("more than addressable".to_string(), |n| n.to_string()),
                    bytes.len()
                ),
            ))
        }
    }
    let values: Vec<f64> = bytes[data_start..data_start + nx * ny * 4]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64 * z_factor)
        .collect();
    let z = Array2::from_shape_vec((ny, nx), values)
        .map_err(|e| format_error(path, format!("GSF data shape: {e}")))?;
    let channel = get("Title").unwrap_or("height").to_string();
    Ok(RawMap {
        z,
        dx: x_real * xy_factor / nx as f64,
        dy: y_real * xy_factor / ny as f64,
        x0: x_off * xy_factor,
        y0: y_off * xy_factor,
        channel,
        format: "gsf",
        header,
    })
}

/// Encode as Gwyddion Simple Field: f32 heights in metres, invalid pixels as NaN.
pub fn encode_gsf(map: &HeightMap) -> Vec<u8> {
    let (width, height) = map.size();
    let mut text = String::from_utf8_lossy(MAGIC).into_owned();
    let _ = writeln!(text, "XRes = {}", map.nx());
    let _ = writeln!(text, "YRes = {}", map.ny());
    let _ = writeln!(text, "XReal = {width:e}");
    let _ = writeln!(text, "YReal = {height:e}");
    let _ = writeln!(text, "XOffset = {:e}", map.x0);
    let _ = writeln!(text, "YOffset = {:e}", map.y0);
    let _ = writeln!(text, "XYUnits = m");
    let _ = writeln!(text, "ZUnits = m");
    let _ = writeln!(text, "Title = {}", map.channel.replace(['\n', '\0'], " "));
    let mut out = text.into_bytes();
    let padding = 4 - out.len() % 4;
    out.resize(out.len() + padding, 0);
    for v in heights_with_nan(map).iter() {
        out.extend_from_slice(&(*v as f32).to_le_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::encode_gsf;

    #[test]
    fn round_trip() {
        let mut map = sample_map(64, 48, 2.5e-9, 7.0e-9);
        map.x0 = 1e-6;
        map.channel = "ZSensor".into();
        let bytes = encode_gsf(&map);
        let header_len = bytes.iter().position(|&b| b == 0).unwrap();
        assert_eq!((bytes.len() - 64 * 48 * 4) % 4, 0);
        assert!((1..=4).contains(&(bytes.len() - 64 * 48 * 4 - header_len)));
        let back = read_bytes("m.gsf", &bytes).unwrap();
        assert_eq!(back.source.format, "gsf");
        assert_eq!(back.channel, "ZSensor");
        assert_same_map(&back, &map, 1e-15, 1e-7, 0.0);
        assert!(close(back.x0, 1e-6, 1e-15));
    }

    #[test]
    fn truncated_and_hostile_files_are_errors() {
        let map = sample_map(16, 12, 1e-9, 1e-9);
        let bytes = encode_gsf(&map);
        let msg = read_bytes("t.gsf", &bytes[..bytes.len() - 1])
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("truncated GSF") && msg.contains("t.gsf"),
            "{msg}"
        );
        let huge = String::from_utf8_lossy(&bytes)
            .replace("XRes = 16", "XRes = 18446744073709551615")
            .into_bytes();
        assert!(read_bytes("h.gsf", &huge).is_err());
        assert!(fuzz_reader("f.gsf", &bytes) > 0);
    }
}
