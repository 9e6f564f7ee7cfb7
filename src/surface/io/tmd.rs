//! TrueMap `.tmd` (TrueMap / Keyence-style profilometry exports; docs/surfaces.md). The v2.0
//! layout as SurfaceTopography's `IO/TMD.py` and Gwyddion's TrueMap module read it: the
//! NUL-terminated magic `Binary TrueMap Data File v2.0\r\n`, a NUL-terminated comment, then
//! nx, ny (u32), length x, length y, offset x, offset y (f32), then ny rows of nx float32
//! heights, little-endian, the first row at the top (SurfaceTopography's y = 0). NaN marks
//! pixels without data.
//!
//! The file states no unit; lengths and heights share one. SurfaceTopography's released reader
//! (1.27.1) takes millimetres, its repository's newer reader micrometres. hdi takes
//! millimetres, which the public sample supports (a 19 mm field of 300 pixels with heights
//! under 1 mm, a GelSight-sized TrueMap v6 scan), and `z_unit` names another.
use super::le::{le_f32, le_u32};
use super::units::length_factor;
use super::{format_error, unsupported, RawMap, ReadOptions};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

/// The start of every TrueMap binary file.
pub(crate) const MAGIC: &[u8] = b"Binary TrueMap Data File";
const V2: &[u8] = b"Binary TrueMap Data File v2.0\r\n\0";
/// How far the comment may reach before its NUL.
const COMMENT_MAX: usize = 4096;

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let fail = |reason: String| format_error(path, reason);
    if !bytes.starts_with(V2) {
        return Err(if bytes.starts_with(MAGIC) {
            unsupported(path, "TrueMap files other than v2.0 are not supported")
        } else {
            fail("not a TrueMap file".into())
        });
    }
    let rest = &bytes[V2.len()..];
    let comment_len = rest
        .iter()
        .take(COMMENT_MAX)
        .position(|&b| b == 0)
        .ok_or_else(|| fail("truncated TrueMap header: no end to its comment".into()))?;
    let comment = String::from_utf8_lossy(&rest[..comment_len])
        .trim()
        .to_string();
    let at = V2.len() + comment_len + 1;
    if bytes.len() < at + 24 {
        return Err(fail(format!(
            "truncated TrueMap header: {} bytes, the header needs {}",
            bytes.len(),
            at + 24
        )));
    }
    let (nx, ny) = (le_u32(bytes, at) as usize, le_u32(bytes, at + 4) as usize);
    let (lx, ly) = (le_f32(bytes, at + 8), le_f32(bytes, at + 12));
    let (ox, oy) = (le_f32(bytes, at + 16), le_f32(bytes, at + 20));
    let data_at = at + 24;
    let need = nx
        .checked_mul(ny)
        .and_then(|n| n.checked_mul(4))
        .and_then(|n| n.checked_add(data_at));
    match need {
        Some(need) if nx > 0 && ny > 0 && need <= bytes.len() => {}
        _ => {
            return Err(fail(format!(
                "TrueMap grid {nx} × {ny} float32 does not fit the file ({} bytes)",
                bytes.len()
            )))
        }
    }
    for (name, v) in [("length x", lx), ("length y", ly)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(fail(format!(
                "TrueMap {name} = {v} is not a positive length"
            )));
        }
    }
    let unit = opts.z_unit.as_deref().unwrap_or("mm");
    let scale = length_factor(unit).ok_or_else(|| {
        fail(format!(
            "unit `{unit}` (option z_unit) is not a length (m, mm, µm, nm, pm, Å)"
        ))
    })?;
    let z = Array2::from_shape_fn((ny, nx), |(j, i)| {
        le_f32(bytes, data_at + 4 * (j * nx + i)) * scale
    });
    let mut header = BTreeMap::new();
    header.insert("comment".to_string(), comment);
    header.insert("version".to_string(), "2.0".to_string());
    header.insert("unit".to_string(), unit.to_string());
    Ok(RawMap {
        z,
        dx: lx / nx as f64 * scale,
        dy: ly / ny as f64 * scale,
        x0: ox * scale,
        y0: oy * scale,
        channel: "height".into(),
        format: "tmd",
        header,
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;

    /// A v2.0 file of `nx` × `ny` heights `f(i, j)`, lengths 6 × 4 (one unit, mm by default).
    fn tmd(nx: u32, ny: u32, f: impl Fn(u32, u32) -> f32) -> Vec<u8> {
        let mut b = super::V2.to_vec();
        b.extend(b"made by a test\0");
        for v in [nx, ny] {
            b.extend(v.to_le_bytes());
        }
        for v in [6.0f32, 4.0, 0.5, -1.0] {
            b.extend(v.to_le_bytes());
        }
        for j in 0..ny {
            for i in 0..nx {
                b.extend(f(i, j).to_le_bytes());
            }
        }
        b
    }

    #[test]
    fn heights_spacing_offsets_and_nan() {
        let bytes = tmd(6, 4, |i, j| {
            if (i, j) == (1, 2) {
                f32::NAN
            } else {
                0.125 * (i + 10 * j) as f32
            }
        });
        let map = read_bytes("a.tmd", &bytes).unwrap();
        assert_eq!(
            (map.nx(), map.ny(), map.source.format.as_str()),
            (6, 4, "tmd")
        );
        // Millimetres unless `z_unit` says otherwise.
        assert!(close(map.dx, 1e-3, 1e-12) && close(map.dy, 1e-3, 1e-12));
        assert!(close(map.x0, 0.5e-3, 1e-7) && close(map.y0, -1e-3, 1e-7));
        assert!(close(map.z[[3, 5]], 0.125 * 35.0 * 1e-3, 1e-12));
        assert!(!map.valid.as_ref().unwrap()[[2, 1]]);
        assert_eq!(map.source.header["comment"], "made by a test");
        let (_dir, path) = write_temp("a.tmd", &bytes);
        let opts = super::super::ReadOptions {
            z_unit: Some("um".into()),
            ..Default::default()
        };
        let um = super::super::read_height_map(&path, &opts).unwrap();
        assert!(close(um.dx, 1e-6, 1e-12) && close(um.z[[3, 5]], 0.125 * 35.0 * 1e-6, 1e-12));
    }

    #[test]
    fn truncated_and_other_versions_are_errors() {
        let bytes = tmd(6, 4, |i, _| i as f32);
        let e = read_bytes("b.tmd", &bytes[..bytes.len() - 3])
            .unwrap_err()
            .to_string();
        assert!(e.contains("b.tmd") && e.contains("does not fit"), "{e}");
        let mut v1 = bytes.clone();
        v1[26] = b'1';
        let e = read_bytes("c.tmd", &v1).unwrap_err().to_string();
        assert!(e.contains("other than v2.0"), "{e}");
        assert!(fuzz_reader("d.tmd", &bytes) > 0);
    }
}
