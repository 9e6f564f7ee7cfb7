//! WSxM `.top` / `.stp` (Nanotec / WSxM SPM images; docs/surfaces.md), as SurfaceTopography's
//! `IO/WSXM.py` and Gwyddion's WSxM module read them: the text lines `WSxM file copyright …`,
//! `SxM Image file`, `Image header size: N`, then `[Section]` headers with `Key: Value` lines up
//! to `[Header end]`; the binary image starts at byte N: `Number of rows` × `Number of
//! columns` little-endian values of `Image Data Type` (`short`/`integer` int16, `float`
//! float32, `double` float64), row by row. The image is stored rotated by 180°: the last value
//! is the top-left pixel as Gwyddion shows it (SurfaceTopography 1.27.1 rotates it back the
//! same way, after Gwyddion's `wsxmfile.c`).
//!
//! Lengths: `X Amplitude`, `Y Amplitude` (value and unit) over the columns and rows, origin at
//! `X Offset`, `Y Offset`. Heights: float images are in the unit of `Z Amplitude`; integer
//! images are value · `Z Amplitude` / (`Maximum` − `Minimum`), the header's data range, as
//! SurfaceTopography 1.27.1 scales them (the header states that range to a fixed precision).
use super::units::length_factor;
use super::{format_error, RawMap};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

/// The start of every WSxM file.
pub(crate) const MAGIC: &[u8] = b"WSxM file copyright";
/// How far the header may reach.
const HEADER_MAX: usize = 1 << 20;

pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<RawMap> {
    let fail = |reason: String| format_error(path, reason);
    let (header, data_at) = parse_header(bytes).map_err(fail)?;
    let get = |section: &str, key: &str| {
        header
            .get(&format!("{section}/{key}"))
            .map(String::as_str)
            .ok_or_else(|| fail(format!("WSxM header has no `{key}` in [{section}]")))
    };
    let count = |key: &str| -> Result<usize> {
        let v = get("General Info", key)?;
        v.parse::<usize>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| fail(format!("WSxM `{key}` = `{v}` is not a positive count")))
    };
    let (nx, ny) = (count("Number of columns")?, count("Number of rows")?);
    let kind = get("General Info", "Image Data Type")?;
    let size = match kind {
        "short" | "integer" => 2,
        "float" => 4,
        "double" => 8,
        other => return Err(fail(format!("WSxM `Image Data Type` `{other}` is unknown"))),
    };
    let need = nx
        .checked_mul(ny)
        .and_then(|n| n.checked_mul(size))
        .and_then(|n| n.checked_add(data_at));
    if need.is_none_or(|need| need > bytes.len()) {
        return Err(fail(format!(
            "WSxM image of {nx} × {ny} {kind} values does not fit the file ({} bytes, data at {data_at})",
            bytes.len()
        )));
    }
    let length = |section: &str, key: &str| -> Result<f64> {
        let text = get(section, key)?;
        let (value, unit) = text.split_once(' ').unwrap_or((text, ""));
        let v: Option<f64> = value.trim().parse().ok();
        match (v, length_factor(unit.trim())) {
            (Some(v), Some(f)) if v.is_finite() => Ok(v * f),
            _ => Err(fail(format!("WSxM `{key}` = `{text}` is not a length"))),
        }
    };
    let lx = length("Control", "X Amplitude")?;
    // A missing y amplitude means a square scan (as SurfaceTopography reads it).
    let ly = match header.contains_key("Control/Y Amplitude") {
        true => length("Control", "Y Amplitude")?,
        false => lx,
    };
    let z_text = get("General Info", "Z Amplitude")?;
    let z_unit = z_text.rsplit(' ').next().unwrap_or("");
    let z_factor = length_factor(z_unit.trim()).ok_or_else(|| {
        fail(format!(
            "WSxM `Z Amplitude` = `{z_text}` has no length unit"
        ))
    })?;
    if !(lx > 0.0 && ly > 0.0) {
        return Err(fail(format!(
            "WSxM amplitudes {lx} × {ly} m are not positive lengths"
        )));
    }
    // Float images are in the Z unit; integer images span `Z Amplitude` over the header's
    // data range (its `Maximum` − `Minimum`; without a positive range, raw values in the Z
    // unit), as SurfaceTopography 1.27.1 reads them.
    let scale = if size == 2 {
        let number = |key: &str| -> Option<f64> {
            header
                .get(&format!("Miscellaneous/{key}"))
                .and_then(|v| v.trim().parse::<f64>().ok())
                .filter(|x| x.is_finite())
        };
        let range = number("Maximum").zip(number("Minimum")).map(|(a, b)| a - b);
        match range {
            Some(r) if r > 0.0 => length("General Info", "Z Amplitude")? / r,
            _ => z_factor,
        }
    } else {
        z_factor
    };
    let value = |k: usize| -> f64 {
        let at = data_at + k * size;
        let b = &bytes[at..at + size];
        match size {
            2 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            4 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            _ => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
        }
    };
    // Rotated by 180°: hdi's (row j, column i) is stored at (ny − 1 − j, nx − 1 − i).
    let z = Array2::from_shape_fn((ny, nx), |(j, i)| {
        value((ny - 1 - j) * nx + (nx - 1 - i)) * scale
    });
    let offset = |key: &str| length("Control", key).unwrap_or(0.0);
    let channel = header
        .get("General Info/Acquisition channel")
        .cloned()
        .unwrap_or_else(|| "Topography".into());
    Ok(RawMap {
        z,
        dx: lx / nx as f64,
        dy: ly / ny as f64,
        x0: offset("X Offset"),
        y0: offset("Y Offset"),
        channel,
        format: "wsxm",
        header,
    })
}

/// The header's `Section/Key` values and where the image starts.
fn parse_header(bytes: &[u8]) -> std::result::Result<(BTreeMap<String, String>, usize), String> {
    let text_end = bytes.len().min(HEADER_MAX);
    // Latin-1: every byte a character (units such as µ and Å are single bytes).
    let text: String = bytes[..text_end].iter().map(|&b| b as char).collect();
    let mut lines = text.split('\n');
    let mut line = |what: &str| {
        lines
            .next()
            .map(|l| l.trim().to_string())
            .ok_or_else(|| format!("truncated WSxM header: no {what}"))
    };
    if !line("first line")?.starts_with("WSxM file copyright") {
        return Err("not a WSxM file".into());
    }
    if line("second line")? != "SxM Image file" {
        return Err("not a WSxM image file (second line is not `SxM Image file`)".into());
    }
    let third = line("header size")?;
    let size = third
        .strip_prefix("Image header size:")
        .and_then(|s| s.trim().parse::<usize>().ok())
        .ok_or_else(|| format!("WSxM third line `{third}` is not `Image header size: N`"))?;
    if size > bytes.len() {
        return Err(format!(
            "truncated WSxM file: the header is {size} bytes, the file {}",
            bytes.len()
        ));
    }
    let mut header = BTreeMap::new();
    let mut section: Option<String> = None;
    loop {
        let l = line("`[Header end]`")?;
        if l == "[Header end]" {
            break;
        }
        if l.is_empty() {
            continue;
        }
        if let Some(name) = l.strip_prefix('[').and_then(|s| s.strip_suffix(']')) {
            section = Some(name.to_string());
            continue;
        }
        let s = section
            .as_deref()
            .ok_or_else(|| format!("WSxM header line `{l}` before any [section]"))?;
        if let Some((k, v)) = l.split_once(':') {
            header.insert(format!("{s}/{}", k.trim()), v.trim().to_string());
        }
    }
    Ok((header, size))
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;

    /// A WSxM image of 5 × 4 int16 values 100·j + i, amplitudes 2 × 1.6 µm, z 10 nm over 0…400.
    fn wsxm(kind: &str) -> Vec<u8> {
        let body = format!(
            "\n[Control]\n\n    X Amplitude: 2 \u{b5}m\n    Y Amplitude: 1.6 \u{b5}m\n    X Offset: 1 nm\n\n[General Info]\n\n    Image Data Type: {kind}\n    Number of columns: 5\n    Number of rows: 4\n    Z Amplitude: 10 nm\n\n[Miscellaneous]\n\n    Maximum: 400\n    Minimum: 0\n\n[Header end]\n"
        );
        // Latin-1, as WSxM writes: µ is one byte.
        let latin1 = |s: &str| s.chars().map(|c| c as u8).collect::<Vec<u8>>();
        let head = |n: usize| {
            latin1(&format!(
                "WSxM file copyright UAM\r\nSxM Image file\r\nImage header size: {n}\r\n{body}"
            ))
        };
        let mut n = head(0).len();
        n = head(n).len();
        let mut b = head(n);
        for j in 0..4 {
            for i in 0..5 {
                let v = 100 * j + i;
                match kind {
                    "short" => b.extend((v as i16).to_le_bytes()),
                    _ => b.extend((v as f64).to_le_bytes()),
                }
            }
        }
        b
    }

    #[test]
    fn int16_and_double_images() {
        for kind in ["short", "double"] {
            let map = read_bytes("a.top", &wsxm(kind)).unwrap();
            assert_eq!(
                (map.nx(), map.ny(), map.source.format.as_str()),
                (5, 4, "wsxm")
            );
            assert!(
                close(map.dx, 0.4e-6, 1e-12) && close(map.dy, 0.4e-6, 1e-12),
                "{kind}"
            );
            assert!(close(map.x0, 1e-9, 1e-12));
            // Integers: z = value · 10 nm / 400; floats: in nm. Rotated by 180°.
            let per = if kind == "short" { 10e-9 / 400.0 } else { 1e-9 };
            assert!(close(map.z[[0, 0]], 304.0 * per, 1e-12), "{kind}");
            assert!(close(map.z[[3, 3]], per, 1e-12), "{kind}");
            assert_eq!(map.source.header["General Info/Number of rows"], "4");
        }
    }

    #[test]
    fn bad_headers_are_errors_naming_the_file() {
        let good = wsxm("short");
        let e = read_bytes("b.top", &good[..good.len() - 1])
            .unwrap_err()
            .to_string();
        assert!(e.contains("b.top") && e.contains("does not fit"), "{e}");
        let at = good
            .windows(17)
            .position(|w| w == b"Number of rows: 4")
            .unwrap();
        let mut no_rows = good.clone();
        no_rows[at..at + 6].copy_from_slice(b"Nombre");
        let e = read_bytes("c.top", &no_rows).unwrap_err().to_string();
        assert!(e.contains("c.top") && e.contains("Number of rows"), "{e}");
        assert!(fuzz_reader("d.top", &good) > 0);
    }
}
