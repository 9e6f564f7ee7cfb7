//! Image Metrology BCR-STM / BCRF (`.bcr`, `.bcrf`; SPIP's interchange format,
//! docs/surfaces.md), as Image Metrology's public description (BCR STM File Format) and
//! SurfaceTopography 1.27.1's `IO/BCR.py` read it: a text header of `headersize` characters
//! (2048 when the key is missing), latin-1 or UTF-16 (`*_unicode` formats: two bytes per
//! character, little-endian, or as a byte-order mark says), `key = value` lines, `%`/`#`
//! comments; `fileformat` is `bcrstm` (int16 values) or `bcrf` (float32). The values follow the
//! header, `ypixels` lines of `xpixels`, first line at the top; `intelmode` 0 means big-endian.
//! Void pixels: int16 32767, float values above 1.7e38 or NaN. Lengths `xlength`, `ylength` in
//! `xunit`, `yunit`; heights: int16 · `bit2nm` in `zunit`, floats in `zunit` (units default to
//! nm). SurfaceTopography applies `zunit` to float data; Gwyddion's `bcrfile.c` takes floats as
//! nm whatever `zunit` says. The public sample bcrf-1 (`zunit = um`) is the measurement of
//! mnt-1.mnt, whose Mountains file gives the same heights in µm: `zunit` is right.
use super::units::length_factor;
use super::{format_error, unsupported, RawMap};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

/// The key that starts every BCR file.
const MAGIC: &str = "fileformat = bcr";
/// Header length in characters when the file does not say.
const DEFAULT_HEADER_CHARS: usize = 2048;

/// How the header's characters are encoded.
#[derive(Clone, Copy)]
enum Encoding {
    Latin1,
    Utf16Le,
    Utf16Be,
}

fn encoding(head: &[u8]) -> Option<Encoding> {
    let utf16 = |big: bool| -> Vec<u8> {
        MAGIC
            .bytes()
            .flat_map(|b| if big { [0, b] } else { [b, 0] })
            .collect()
    };
    if head.starts_with(MAGIC.as_bytes()) {
        Some(Encoding::Latin1)
    } else if head.starts_with(&utf16(false))
        || (head.starts_with(b"\xff\xfe") && head[2..].starts_with(&utf16(false)))
    {
        Some(Encoding::Utf16Le)
    } else if head.starts_with(b"\xfe\xff") && head[2..].starts_with(&utf16(true)) {
        Some(Encoding::Utf16Be)
    } else {
        None
    }
}

/// Whether the file starts like a BCR-STM / BCRF file, in any of its header encodings.
pub(crate) fn looks_like(head: &[u8]) -> bool {
    encoding(head).is_some()
}

fn decode(bytes: &[u8], enc: Encoding) -> String {
    match enc {
        Encoding::Latin1 => bytes.iter().map(|&b| b as char).collect(),
        Encoding::Utf16Le | Encoding::Utf16Be => {
            let units = bytes.chunks_exact(2).map(|c| match enc {
                Encoding::Utf16Be => u16::from_be_bytes([c[0], c[1]]),
                _ => u16::from_le_bytes([c[0], c[1]]),
            });
            char::decode_utf16(units)
                .map(|c| c.unwrap_or('\u{fffd}'))
                .collect()
        }
    }
}

/// `key = value` lines of a header text.
fn parse(text: &str) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    for line in text.split('\n') {
        let line = line.trim_start_matches('\u{feff}');
        if line.starts_with('%') || line.starts_with('#') {
            continue;
        }
        if let Some((k, v)) = line.split_once('=') {
            let (k, v) = (k.trim(), v.trim().trim_end_matches('\0').trim());
            if !k.is_empty() && !v.is_empty() {
                out.insert(k.to_string(), v.to_string());
            }
        }
    }
    out
}

pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<RawMap> {
    let fail = |reason: String| format_error(path, reason);
    let enc =
        encoding(bytes).ok_or_else(|| fail("not a BCR file (no `fileformat = bcr`)".into()))?;
    let char_bytes = match enc {
        Encoding::Latin1 => 1,
        _ => 2,
    };
    // `headersize` is within the first 2048 bytes (SurfaceTopography's probe).
    let probe = decode(&bytes[..bytes.len().min(DEFAULT_HEADER_CHARS)], enc);
    let header_chars = match parse(&probe).get("headersize") {
        Some(v) => v
            .parse::<usize>()
            .ok()
            .filter(|&n| (64..=1 << 20).contains(&n))
            .ok_or_else(|| fail(format!("BCR `headersize` = `{v}` is not a header length")))?,
        None => DEFAULT_HEADER_CHARS,
    };
    let data_at = header_chars * char_bytes;
    if data_at > bytes.len() {
        return Err(fail(format!(
            "truncated BCR file: the header is {data_at} bytes, the file {}",
            bytes.len()
        )));
    }
    let header = parse(&decode(&bytes[..data_at], enc));
    let get = |key: &str| {
        header
            .get(key)
            .map(String::as_str)
            .ok_or_else(|| fail(format!("BCR header has no `{key}`")))
    };
    let float = match get("fileformat")? {
        "bcrstm" | "bcrstm_unicode" => false,
        "bcrf" | "bcrf_unicode" => true,
        other => {
            return Err(unsupported(
                path,
                format!("BCR `fileformat = {other}` is not bcrstm or bcrf"),
            ))
        }
    };
    let count = |key: &str| -> Result<usize> {
        let v = get(key)?;
        v.parse::<usize>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| fail(format!("BCR `{key}` = `{v}` is not a positive count")))
    };
    let number = |key: &str, default: &str| -> Result<f64> {
        let v = header.get(key).map_or(default, String::as_str);
        v.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| fail(format!("BCR `{key}` = `{v}` is not a number")))
    };
    let unit = |key: &str| -> Result<f64> {
        let u = header.get(key).map_or("nm", String::as_str);
        length_factor(u).ok_or_else(|| fail(format!("BCR `{key}` = `{u}` is not a length unit")))
    };
    let (nx, ny) = (count("xpixels")?, count("ypixels")?);
    let value_bytes = if float { 4 } else { 2 };
    let little = number("intelmode", "1")? != 0.0;
    let data = nx
        .checked_mul(ny)
        .and_then(|n| n.checked_mul(value_bytes))
        .and_then(|n| n.checked_add(data_at))
        .filter(|&end| end <= bytes.len())
        .map(|end| &bytes[data_at..end])
        .ok_or_else(|| {
            fail(format!(
                "truncated BCR file: {nx} × {ny} values of {value_bytes} bytes after the \
                 {data_at}-byte header do not fit in {} bytes",
                bytes.len()
            ))
        })?;
    let (lx, ly) = (
        number("xlength", "")? * unit("xunit")?,
        number("ylength", "")? * unit("yunit")?,
    );
    let z_scale = unit("zunit")? * if float { 1.0 } else { number("bit2nm", "1")? };
    let value = |i: usize| -> f64 {
        let b = &data[i * value_bytes..(i + 1) * value_bytes];
        if float {
            let w = [b[0], b[1], b[2], b[3]];
            let v = if little {
                f32::from_le_bytes(w)
            } else {
                f32::from_be_bytes(w)
            };
            if v.is_nan() || v > 1.7e38 {
                f64::NAN
            } else {
                f64::from(v) * z_scale
            }
        } else {
            let w = [b[0], b[1]];
            let v = if little {
                i16::from_le_bytes(w)
            } else {
                i16::from_be_bytes(w)
            };
            if v == i16::MAX {
                f64::NAN
            } else {
                f64::from(v) * z_scale
            }
        }
    };
    let z = Array2::from_shape_fn((ny, nx), |(r, c)| value(r * nx + c));
    let offset = |key: &str, unit_key: &str| -> f64 {
        let v = number(key, "0").unwrap_or(0.0);
        unit(unit_key).map_or(0.0, |f| v * f)
    };
    Ok(RawMap {
        z,
        dx: lx / nx as f64,
        dy: ly / ny as f64,
        x0: offset("xoffset", "xunit"),
        y0: offset("yoffset", "yunit"),
        channel: "Height".into(),
        format: "bcr",
        header,
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;

    /// A BCR file as the description above says: `fileformat`, a header of 2048 characters
    /// (UTF-16 for `_unicode`), 4 × 3 values 100·line + column, one void.
    fn bcr(format: &str) -> Vec<u8> {
        let text = format!(
            "fileformat = {format}\n%comment\nxpixels = 4\nypixels = 3\nxlength = 2\nylength = 1.5\n xunit = um\n yunit = um\nzunit = nm\nbit2nm = 0.5\n"
        );
        let text = format!("{text:\0<2048}");
        let mut b: Vec<u8> = if format.ends_with("_unicode") {
            text.encode_utf16().flat_map(u16::to_le_bytes).collect()
        } else {
            text.into_bytes()
        };
        for line in 0..3 {
            for col in 0..4 {
                let v = 100 * line + col;
                let void = (line, col) == (1, 2);
                if format.starts_with("bcrstm") {
                    b.extend((if void { i16::MAX } else { v as i16 }).to_le_bytes());
                } else {
                    b.extend((if void { f32::MAX } else { v as f32 }).to_le_bytes());
                }
            }
        }
        b
    }

    #[test]
    fn int16_and_float_utf16_files() {
        for (format, per) in [("bcrstm", 0.5e-9), ("bcrf_unicode", 1e-9)] {
            let map = read_bytes("a.bcr", &bcr(format)).unwrap();
            assert_eq!(
                (map.nx(), map.ny(), map.source.format.as_str()),
                (4, 3, "bcr")
            );
            assert!(close(map.dx, 0.5e-6, 1e-12) && close(map.dy, 0.5e-6, 1e-12));
            assert!(close(map.z[[2, 3]], 203.0 * per, 1e-12), "{format}");
            assert!(close(map.z[[0, 1]], per, 1e-12), "{format}");
            assert!(!map.valid.as_ref().unwrap()[[1, 2]], "{format}");
        }
    }

    #[test]
    fn truncated_and_broken_headers_are_errors_naming_the_file() {
        let good = bcr("bcrstm");
        let e = read_bytes("b.bcr", &good[..good.len() - 1])
            .unwrap_err()
            .to_string();
        assert!(e.contains("b.bcr") && e.contains("truncated"), "{e}");
        let e = read_bytes("c.bcr", &good[..1000]).unwrap_err().to_string();
        assert!(e.contains("c.bcr") && e.contains("truncated"), "{e}");
        assert!(fuzz_reader("d.bcr", &good) > 0);
    }
}
