//! Surface Data File (`.sdf`): the BCR format of the EU "3-D surface topography" project,
//! standardised as ISO 25178-71. Two variants share one header:
//!
//! * ASCII (`aBCR-1.0` / `aISO-1.0`): `Key = Value` lines (ManufacID, CreateDate, ModDate,
//!   NumPoints, NumProfiles, Xscale, Yscale, Zscale, Zresolution, Compression, DataType,
//!   CheckType), a line `*`, the values separated by white space (`BAD` = invalid), a line `*`,
//!   then optional free text ending in `*`.
//! * binary (`bBCR-1.0` / `bISO-1.0`): the same fields packed little-endian in 81 bytes
//!   (8 + 10 + 12 + 12 + 2·u16 + 4·f64 + 3·u8), then the values, then the optional text.
//!
//! DataType: 0 u8, 1 u16, 2 u32, 3 f32, 4 i8, 5 i16, 6 i32, 7 f64. Scales are metres per unit;
//! height = value · Zscale. Profiles are rows (row 0 = first profile, as in the file), points
//! run along x. Invalid pixels: `BAD` (ASCII), NaN (floats), the type's minimum for signed
//! 16/32-bit integers (the ISO 25178-71 convention SurfaceTopography follows).
use super::units::decode_text;
use super::{format_error, unsupported, RawMap};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

/// Leading bytes of the four variants.
pub(crate) const MAGICS: [&[u8]; 4] = [b"aISO-1.0", b"bISO-1.0", b"aBCR-1.0", b"bBCR-1.0"];
const BINARY_HEADER: usize = 81;

/// Bytes per value of a binary DataType.
fn value_size(data_type: u8) -> Option<usize> {
    match data_type {
        0 | 4 => Some(1),
        1 | 5 => Some(2),
        2 | 3 | 6 => Some(4),
        7 => Some(8),
        _ => None,
    }
}

struct Header {
    fields: BTreeMap<String, String>,
    nx: usize,
    ny: usize,
    xscale: f64,
    yscale: f64,
    zscale: f64,
    data_type: u8,
}

pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<RawMap> {
    let binary = bytes.first() == Some(&b'b');
    let (header, z) = if binary {
        read_binary(path, bytes)?
    } else {
        read_ascii(path, bytes)?
    };
    let mut fields = header.fields;
    fields.insert(
        "variant".into(),
        if binary { "binary" } else { "ascii" }.into(),
    );
    Ok(RawMap {
        z,
        dx: header.xscale,
        dy: header.yscale,
        x0: 0.0,
        y0: 0.0,
        channel: "height".to_string(),
        format: "sdf",
        header: fields,
    })
}

fn check_header(path: &Path, fields: BTreeMap<String, String>) -> Result<Header> {
    let get = |key: &str| -> Result<&str> {
        fields
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(key))
            .map(|(_, v)| v.as_str())
            .ok_or_else(|| format_error(path, format!("SDF header lacks {key}")))
    };
    let count = |key: &str| -> Result<usize> {
        let text = get(key)?;
        text.parse::<usize>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| {
                format_error(
                    path,
                    format!("SDF {key} = `{text}` is not a positive integer"),
                )
            })
    };
    let scale = |key: &str| -> Result<f64> {
        let text = get(key)?;
        text.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format_error(path, format!("SDF {key} = `{text}` is not a number")))
    };
    let compression = get("Compression").unwrap_or("0");
    if compression != "0" {
        return Err(unsupported(
            path,
            format!("SDF Compression = {compression}: only uncompressed files are read"),
        ));
    }
    let data_type_text = get("DataType")?;
    let data_type = data_type_text
        .parse::<u8>()
        .ok()
        .filter(|&t| value_size(t).is_some())
        .ok_or_else(|| {
            format_error(
                path,
                format!("SDF DataType = `{data_type_text}` is not one of 0–7"),
            )
        })?;
    Ok(Header {
        nx: count("NumPoints")?,
        ny: count("NumProfiles")?,
        xscale: scale("Xscale")?,
        yscale: scale("Yscale")?,
        zscale: scale("Zscale")?,
        data_type,
        fields,
    })
}

fn read_ascii(path: &Path, bytes: &[u8]) -> Result<(Header, Array2<f64>)> {
    let text = decode_text(bytes);
    let mut lines = text.lines().skip(1);
    let mut fields = BTreeMap::new();
    let mut terminated = false;
    for line in lines.by_ref() {
        let line = line.trim();
        if line.starts_with('*') {
            terminated = true;
            break;
        }
        if let Some((key, value)) = line.split_once('=') {
            fields.insert(key.trim().to_string(), value.trim().to_string());
        }
    }
    if !terminated {
        return Err(format_error(
            path,
            "truncated SDF file: no `*` line after the header",
        ));
    }
    let header = check_header(path, fields)?;
    let (nx, ny) = (header.nx, header.ny);
    // Each value takes at least two bytes (a digit and a separator): cap by the file length.
    if nx.checked_mul(ny).is_none_or(|n| n > bytes.len() / 2) {
        return Err(format_error(
            path,
            format!(
                "truncated SDF file: {nx}×{ny} values cannot fit in {} bytes",
                bytes.len()
            ),
        ));
    }
    let mut values = Vec::with_capacity(nx * ny);
    'lines: for (k, line) in lines.enumerate() {
        if line.trim_start().starts_with('*') {
            break;
        }
        for token in line.split_whitespace() {
            let value = if token.eq_ignore_ascii_case("BAD") {
                f64::NAN
            } else {
                token.parse::<f64>().map_err(|_| {
                    format_error(
                        path,
                        format!(
                            "SDF data line {} (after the header): `{token}` is not a number",
                            k + 1
                        ),
                    )
                })?
            };
            values.push(value * header.zscale);
            if values.len() > nx * ny {
                break 'lines;
            }
        }
    }
    if values.len() != nx * ny {
        return Err(format_error(
            path,
            format!(
                "SDF data section has {}{} values, header says {nx}×{ny} = {}",
                values.len().min(nx * ny),
                if values.len() > nx * ny { "+" } else { "" },
                nx * ny
            ),
        ));
    }
    let z = Array2::from_shape_vec((ny, nx), values)
        .map_err(|e| format_error(path, format!("SDF data shape: {e}")))?;
    Ok((header, z))
}

fn read_binary(path: &Path, bytes: &[u8]) -> Result<(Header, Array2<f64>)> {
    let h = bytes.get(..BINARY_HEADER).ok_or_else(|| {
        format_error(
            path,
            format!(
                "truncated SDF file: the binary header needs {BINARY_HEADER} bytes, file has {}",
                bytes.len()
            ),
        )
    })?;
    let text = |at: usize, len: usize| {
        let s = &h[at..at + len];
        let end = s.iter().position(|&b| b == 0).unwrap_or(len);
        decode_text(&s[..end]).trim().to_string()
    };
    let u16_at = |at: usize| u16::from_le_bytes([h[at], h[at + 1]]);
    let f64_at = |at: usize| {
        let mut b = [0u8; 8];
        b.copy_from_slice(&h[at..at + 8]);
        f64::from_le_bytes(b)
    };
    let mut fields = BTreeMap::new();
    fields.insert("ManufacID".to_string(), text(8, 10));
    fields.insert("CreateDate".to_string(), text(18, 12));
    fields.insert("ModDate".to_string(), text(30, 12));
    fields.insert("NumPoints".to_string(), u16_at(42).to_string());
    fields.insert("NumProfiles".to_string(), u16_at(44).to_string());
    for (k, key) in ["Xscale", "Yscale", "Zscale", "Zresolution"]
        .iter()
        .enumerate()
    {
        fields.insert(key.to_string(), format!("{:e}", f64_at(46 + 8 * k)));
    }
    fields.insert("Compression".to_string(), h[78].to_string());
    fields.insert("DataType".to_string(), h[79].to_string());
    fields.insert("CheckType".to_string(), h[80].to_string());
    let header = check_header(path, fields)?;
    let (nx, ny) = (header.nx, header.ny);
    let size = value_size(header.data_type).unwrap_or(8);
    // nx, ny ≤ 65535: the product cannot overflow, but the file may be short.
    let needed = nx * ny * size;
    let data = bytes
        .get(BINARY_HEADER..BINARY_HEADER + needed)
        .ok_or_else(|| {
            format_error(
                path,
                format!(
                    "truncated SDF file: {nx}×{ny} values of {size} bytes need {} bytes, file \
                     has {}",
                    BINARY_HEADER + needed,
                    bytes.len()
                ),
            )
        })?;
    let dt = header.data_type;
    let values: Vec<f64> = data
        .chunks_exact(size)
        .map(|c| {
            let v = match dt {
                0 => c[0] as f64,
                1 => u16::from_le_bytes([c[0], c[1]]) as f64,
                2 => u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64,
                3 => f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64,
                4 => c[0] as i8 as f64,
                5 => match i16::from_le_bytes([c[0], c[1]]) {
                    i16::MIN => f64::NAN,
                    v => v as f64,
                },
                6 => match i32::from_le_bytes([c[0], c[1], c[2], c[3]]) {
                    i32::MIN => f64::NAN,
                    v => v as f64,
                },
                _ => f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]),
            };
            v * header.zscale
        })
        .collect();
    let z = Array2::from_shape_vec((ny, nx), values)
        .map_err(|e| format_error(path, format!("SDF data shape: {e}")))?;
    Ok((header, z))
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};
    use std::path::PathBuf;

    fn sample(name: &str) -> PathBuf {
        surface_sample(name)
    }

    /// SurfaceTopography's `test_sdf_ascii_metadata`: 7 × 4 points, 7 µm × 4 µm.
    #[test]
    fn ascii_iso_sample() {
        let map = read_height_map(&sample("sdf-1.sdf"), &ReadOptions::default()).unwrap();
        assert_eq!(map.source.format, "sdf");
        assert_eq!(map.z.dim(), (4, 7));
        let (w, h) = map.size();
        assert!(close(w, 7e-6, 1e-9) && close(h, 4e-6, 1e-9), "{w}×{h}");
        // Values printed in the file times Zscale = 1e-6 m.
        assert!(close(map.z[[0, 0]], 1.0e-6, 1e-12));
        assert!(close(map.z[[3, 5]], 0.94907e-6, 1e-12));
        assert!(close(map.z[[1, 2]], 0.99369e-6, 1e-12));
        assert_eq!(map.source.header["ManufacID"], "ISOTC213");
    }

    /// A bBCR-1.0 int16 file from the independent writer make_ibw_sdf_fixtures.py; σ of the
    /// valid points by numpy.
    #[test]
    fn binary_int16_with_invalid_point() {
        let map =
            read_height_map(&sample("bcr_binary_int16.sdf"), &ReadOptions::default()).unwrap();
        assert_eq!(map.z.dim(), (5, 9));
        assert!(close(map.dx, 0.5e-6, 1e-15) && close(map.dy, 0.25e-6, 1e-15));
        let valid = map.valid.as_ref().unwrap();
        assert!(!valid[[2, 3]]);
        assert_eq!(valid.iter().filter(|v| **v).count(), 44);
        let vals: Vec<f64> = map
            .z
            .iter()
            .zip(valid.iter())
            .filter(|(_, &ok)| ok)
            .map(|(&z, _)| z)
            .collect();
        let mean = vals.iter().sum::<f64>() / vals.len() as f64;
        let sd = (vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / vals.len() as f64).sqrt();
        assert!(close(sd, 2.74729667089921e-07, 1e-12), "{sd}");
        assert!(close(map.z[[0, 0]], -2.87e-07, 1e-12));
        assert!(close(map.z[[4, 8]], -1.4e-08, 1e-12));
    }

    #[test]
    fn ascii_bad_points_and_wrong_counts() {
        let text = "aBCR-1.0\nManufacID = x\nNumPoints = 3\nNumProfiles = 3\nXscale = 1e-6\n\
                    Yscale = 1e-6\nZscale = 1e-9\nCompression = 0\nDataType = 5\n*\n\
                    1 2 3\n4 BAD 6\n7 8 9\n*\n";
        let map = read_bytes("a.sdf", text.as_bytes()).unwrap();
        assert!(!map.valid.as_ref().unwrap()[[1, 1]]);
        assert!(close(map.z[[2, 0]], 7e-9, 1e-12));
        let short = text.replace("7 8 9", "7 8");
        let msg = read_bytes("s.sdf", short.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(msg.contains("s.sdf") && msg.contains("8 values"), "{msg}");
        let huge = text.replace("NumPoints = 3", "NumPoints = 99999999999");
        let msg = read_bytes("h.sdf", huge.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(msg.contains("cannot fit"), "{msg}");
        let junk = text.replace("4 BAD 6", "4 x 6");
        let msg = read_bytes("j.sdf", junk.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(msg.contains("`x` is not a number"), "{msg}");
        let compressed = text.replace("Compression = 0", "Compression = 1");
        assert!(read_bytes("c.sdf", compressed.as_bytes()).is_err());
    }

    #[test]
    fn truncated_and_hostile_files_are_errors() {
        let bytes = std::fs::read(sample("bcr_binary_int16.sdf")).unwrap();
        for cut in [8, 50, 80, 81, 100, bytes.len() - 2] {
            let msg = read_bytes("t.sdf", &bytes[..cut]).unwrap_err().to_string();
            assert!(
                msg.contains("t.sdf") && msg.contains("truncated"),
                "{cut}: {msg}"
            );
        }
        let mut huge = bytes.clone();
        huge[42..46].copy_from_slice(&[0xFF; 4]);
        let msg = read_bytes("h.sdf", &huge).unwrap_err().to_string();
        assert!(msg.contains("truncated"), "{msg}");
        // Corrupt copies of both samples: registry.rs,
        // `every_sample_survives_truncation_and_flipped_bytes`.
    }
}
