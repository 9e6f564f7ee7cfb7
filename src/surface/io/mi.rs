//! Molecular Imaging / Agilent `.mi` (PicoView, PicoSPM; docs/surfaces.md), as Gwyddion's
//! `mifile.c` and SurfaceTopography 1.27.1's `IO/MI.py` read it: text lines of a key in a
//! fixed 14-character column and its value (`fileType Image` first); indented lines continue
//! a value and are skipped. Each `bufferLabel` line opens one channel (its `bufferRange`,
//! `bufferUnit`, `direction`, …); the line with the key `data` ends the header and says how
//! the channels' values follow it, back to back: `BINARY_32` little-endian int32, `BINARY`
//! (or empty) int16. Heights: z = raw · bufferRange / 2^31 (int16: / 2^15) in `bufferUnit`;
//! `xLength`, `yLength` are in metres over `xPixels` × `yPixels`. The last stored line is the
//! top of the image whatever `scanUp` says (both readers flip it; hdi's row 0 is the last line).
use super::units::{decode_text, length_factor};
use super::{find_channel, format_error, unsupported, RawMap, ReadOptions};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

/// The first key of every MI file.
pub(crate) const MAGIC: &[u8] = b"fileType";
/// Width of the key column.
const KEY_WIDTH: usize = 14;
/// How far the header may reach before its `data` line.
const HEADER_MAX: usize = 1 << 20;

/// The file-wide keys, one map per channel, and where the data start.
struct Header {
    global: BTreeMap<String, String>,
    buffers: Vec<BTreeMap<String, String>>,
    data_kind: String,
    data_at: usize,
}

fn parse_header(bytes: &[u8]) -> std::result::Result<Header, String> {
    let mut global = BTreeMap::new();
    let mut buffers: Vec<BTreeMap<String, String>> = Vec::new();
    let mut at = 0;
    loop {
        if at >= bytes.len().min(HEADER_MAX) {
            return Err("truncated MI file: no `data` line ends the header".into());
        }
        let end = bytes[at..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |k| at + k + 1);
        let raw = &bytes[at..end];
        at = end;
        if raw.first() == Some(&b' ') {
            continue;
        }
        let line = decode_text(raw);
        let line = line.trim_end_matches(['\r', '\n']);
        if line.trim().is_empty() {
            continue;
        }
        let split = line
            .char_indices()
            .nth(KEY_WIDTH)
            .map_or(line.len(), |(k, _)| k);
        let (key, value) = (line[..split].trim(), line[split..].trim());
        if key == "data" {
            return Ok(Header {
                global,
                buffers,
                data_kind: value.to_string(),
                data_at: at,
            });
        }
        if key == "bufferLabel" {
            buffers.push(BTreeMap::new());
        }
        match buffers.last_mut() {
            Some(b) => b.insert(key.to_string(), value.to_string()),
            None => global.insert(key.to_string(), value.to_string()),
        };
    }
}

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let fail = |reason: String| format_error(path, reason);
    let h = parse_header(bytes).map_err(fail)?;
    match h.global.get("fileType").map(String::as_str) {
        Some("Image") => {}
        Some("Spectroscopy") => {
            return Err(unsupported(
                path,
                "MI spectroscopy files are not height maps",
            ))
        }
        other => return Err(fail(format!("MI `fileType` {other:?} is not `Image`"))),
    }
    let (value_bytes, full_scale) = match h.data_kind.as_str() {
        "BINARY_32" => (4, 2f64.powi(31)),
        "BINARY" | "" => (2, 2f64.powi(15)),
        "ASCII" => return Err(unsupported(path, "MI files with text data are not read")),
        other => return Err(fail(format!("MI `data` = `{other}` is unknown"))),
    };
    let global = |key: &str| -> Result<&str> {
        h.global
            .get(key)
            .map(String::as_str)
            .ok_or_else(|| fail(format!("MI header has no `{key}`")))
    };
    let count = |key: &str| -> Result<usize> {
        let v = global(key)?;
        v.parse::<usize>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| fail(format!("MI `{key}` = `{v}` is not a positive count")))
    };
    let length = |key: &str| -> Result<f64> {
        let v = global(key)?;
        v.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite() && *x > 0.0)
            .ok_or_else(|| fail(format!("MI `{key}` = `{v}` is not a positive length")))
    };
    let (nx, ny) = (count("xPixels")?, count("yPixels")?);
    let channel_bytes = nx
        .checked_mul(ny)
        .and_then(|n| n.checked_mul(value_bytes))
        .ok_or_else(|| fail(format!("MI image of {nx} × {ny} values overflows")))?;
    let label = |b: &BTreeMap<String, String>| -> String {
        let name = b.get("bufferLabel").map_or("", String::as_str);
        match b.get("direction") {
            Some(d) if !d.is_empty() => format!("{name} ({d})"),
            _ => name.to_string(),
        }
    };
    let unit = |b: &BTreeMap<String, String>| b.get("bufferUnit").cloned().unwrap_or_default();
    let listing = || {
        let names: Vec<String> = h
            .buffers
            .iter()
            .map(|b| format!("{} [{}]", label(b), unit(b)))
            .collect();
        names.join(", ")
    };
    let k = match &opts.channel {
        Some(wanted) => {
            let names: Vec<Vec<String>> = h
                .buffers
                .iter()
                .map(|b| vec![label(b), b.get("bufferLabel").cloned().unwrap_or_default()])
                .collect();
            find_channel(wanted, &names)
                .ok_or_else(|| fail(format!("no channel `{wanted}`; channels: {}", listing())))?
        }
        // The first channel in a length unit (SurfaceTopography's default is the first channel,
        // which is the topography in MI files).
        None => h
            .buffers
            .iter()
            .position(|b| length_factor(&unit(b)).is_some())
            .ok_or_else(|| {
                fail(format!(
                    "MI file has no height channel; channels: {}",
                    listing()
                ))
            })?,
    };
    let b = &h.buffers[k];
    let z_factor = length_factor(&unit(b)).ok_or_else(|| {
        unsupported(
            path,
            format!(
                "MI channel `{}` is in `{}`, not a length: not a height map",
                label(b),
                unit(b)
            ),
        )
    })?;
    let range = b
        .get("bufferRange")
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|x| x.is_finite())
        .ok_or_else(|| {
            fail(format!(
                "MI channel `{}` has no numeric `bufferRange`",
                label(b)
            ))
        })?;
    let start = h.data_at + k * channel_bytes;
    let data = start
        .checked_add(channel_bytes)
        .filter(|&end| end <= bytes.len())
        .map(|end| &bytes[start..end])
        .ok_or_else(|| {
            fail(format!(
                "truncated MI file: channel {k} of {nx} × {ny} × {value_bytes} bytes at \
                 {start} runs past the end ({} bytes)",
                bytes.len()
            ))
        })?;
    let scale = range / full_scale * z_factor;
    let raw = |i: usize| -> f64 {
        let at = i * value_bytes;
        if value_bytes == 4 {
            f64::from(super::le::le_i32(data, at))
        } else {
            f64::from(i16::from_le_bytes([data[at], data[at + 1]]))
        }
    };
    // The last stored line is the top: hdi's row r is stored line ny − 1 − r.
    let z = Array2::from_shape_fn((ny, nx), |(r, c)| raw((ny - 1 - r) * nx + c) * scale);
    let mut header = h.global.clone();
    header.insert("channels".into(), listing());
    for (key, value) in b {
        header.insert(format!("channel/{key}"), value.clone());
    }
    let offset = |key: &str| {
        h.global
            .get(key)
            .and_then(|v| v.parse::<f64>().ok())
            .filter(|x| x.is_finite())
            .unwrap_or(0.0)
    };
    Ok(RawMap {
        z,
        dx: length("xLength")? / nx as f64,
        dy: length("yLength")? / ny as f64,
        x0: offset("xOffset"),
        y0: offset("yOffset"),
        channel: label(b),
        format: "mi",
        header,
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};

    /// An MI image as the layout above describes it: 4 × 3 pixels, a topography channel (µm)
    /// and a deflection channel (V), int32 values 100·line + column (deflection: negated).
    fn mi() -> Vec<u8> {
        let key = |k: &str, v: &str| format!("{k:<14}{v}\n");
        let mut text = String::new();
        for (k, v) in [
            ("fileType", "Image"),
            ("xPixels", "4"),
            ("yPixels", "3"),
            ("xLength", "2e-6"),
            ("yLength", "1.5e-6"),
            ("bufferLabel", "Topography"),
            ("direction", "Trace"),
            ("bufferRange", "2147483.648"),
            ("bufferUnit", "um"),
            ("bufferLabel", "Deflection"),
            ("direction", "Trace"),
            ("bufferRange", "10"),
            ("bufferUnit", "V"),
            ("data", "BINARY_32"),
        ] {
            text.push_str(&key(k, v));
            if k == "xLength" {
                text.push_str("  a continuation line\n");
            }
        }
        let mut b = text.into_bytes();
        for sign in [1i32, -1] {
            for line in 0..3 {
                for col in 0..4 {
                    b.extend((sign * (100 * line + col)).to_le_bytes());
                }
            }
        }
        b
    }

    #[test]
    fn scaling_orientation_and_channels() {
        let map = read_bytes("a.mi", &mi()).unwrap();
        assert_eq!(
            (map.nx(), map.ny(), map.source.format.as_str()),
            (4, 3, "mi")
        );
        assert_eq!(map.channel, "Topography (Trace)");
        assert!(close(map.dx, 0.5e-6, 1e-12) && close(map.dy, 0.5e-6, 1e-12));
        // z = raw · 2147483.648 µm / 2^31 = raw nm; the last line is row 0.
        assert!(close(map.z[[0, 1]], 201e-9, 1e-12));
        assert!(close(map.z[[2, 3]], 3e-9, 1e-12));
        assert_eq!(map.source.header["channel/bufferUnit"], "um");
        let (_dir, path) = write_temp("a.mi", &mi());
        let opts = ReadOptions {
            channel: Some("deflection".into()),
            ..ReadOptions::default()
        };
        let e = read_height_map(&path, &opts).unwrap_err().to_string();
        assert!(e.contains("a.mi") && e.contains("not a length"), "{e}");
    }

    #[test]
    fn truncated_and_broken_headers_are_errors_naming_the_file() {
        let good = mi();
        let e = read_bytes("b.mi", &good[..good.len() - 60])
            .unwrap_err()
            .to_string();
        assert!(e.contains("b.mi") && e.contains("truncated"), "{e}");
        let e = read_bytes("c.mi", &good[..100]).unwrap_err().to_string();
        assert!(e.contains("c.mi") && e.contains("data"), "{e}");
        assert!(fuzz_reader("d.mi", &good) > 0);
    }
}
