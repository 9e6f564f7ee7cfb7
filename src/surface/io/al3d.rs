//! Alicona Imaging `.al3d` (InfiniteFocus focus-variation microscopes; docs/surfaces.md). The
//! layout, as Gwyddion's `alicona.c` and SurfaceTopography's `IO/AL3D.py` read it: the magic
//! `AliconaImaging\0\r\n`, then 52-byte tags (key, 20 bytes, and value, 30 bytes, both
//! NUL-padded text, then CRLF): `Version`, `TagCount` (how many tags follow), those tags, then
//! a 256-byte comment. Tags give the grid (`Cols`, `Rows`), the pixel size in metres
//! (`PixelSizeXMeter`, `PixelSizeYMeter`), where the depth image is (`DepthImageOffset`, from
//! the start of the file), the marker of pixels without data (`InvalidPixelValue`) and the
//! texture (`TextureImageOffset`, `NumberOfPlanes`, and `TexturePtr`, the planes of the colour
//! image, e.g. `0;1;2`).
//!
//! The depth image is `Rows` rows of `Cols` float32 heights in metres, little-endian, each row
//! padded to a multiple of 8 bytes, the first row at the top (both readers). NaN, and values
//! within 1.5e-7 (relative) of `InvalidPixelValue` (a float32 stored as text), mark pixels
//! without data. Texture planes are 8-bit, rows padded to a multiple of 8 bytes.
//!
//! Channels: `Depth` (heights), and the planes each `…Ptr` tag names, as Gwyddion lists them
//! (`DepthImageRes`, `Texture (R)`, `(G)`, `(B)`, …; counts 0–255, not lengths).
use super::units::nul_terminated;
use super::{find_channel, format_error, RawMap, ReadOptions};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

/// The start of every AL3D file.
pub(crate) const MAGIC: &[u8] = b"AliconaImaging\x00\r\n";
const TAG: usize = 52;
const COMMENT: usize = 256;
/// Tag keys that hold binary values or layout, left out of the header.
const NOT_METADATA: [&str; 9] = [
    "DirSpacer",
    "PlaceHolder",
    "Cols",
    "Rows",
    "NumberOfPlanes",
    "ImageCode",
    "PixelSizeXMeter",
    "PixelSizeYMeter",
    "InvalidPixelValue",
];

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let fail = |reason: String| format_error(path, reason);
    let tag_at = |k: usize| MAGIC.len().saturating_add(k.saturating_mul(TAG));
    let tag = |k: usize| -> Result<(String, String)> {
        let at = tag_at(k);
        let t = bytes.get(at..at.saturating_add(TAG)).ok_or_else(|| {
            fail(format!(
                "truncated AL3D header: tag {k} needs {} bytes, the file has {}",
                at.saturating_add(TAG),
                bytes.len()
            ))
        })?;
        if &t[50..52] != b"\r\n" {
            return Err(fail(format!("AL3D tag {k} does not end in CRLF")));
        }
        Ok((nul_terminated(&t[..20]), nul_terminated(&t[20..50])))
    };
    if !bytes.starts_with(MAGIC) {
        return Err(fail("not an Alicona AL3D file".into()));
    }
    let (version_key, version) = tag(0)?;
    let (count_key, count) = tag(1)?;
    if version_key != "Version" || count_key != "TagCount" {
        return Err(fail(format!(
            "AL3D header starts with tags `{version_key}`, `{count_key}`, not `Version`, `TagCount`"
        )));
    }
    let n_tags: usize = count
        .parse()
        .map_err(|_| fail(format!("AL3D TagCount `{count}` is not a number")))?;
    let comment_at = tag_at(2usize.saturating_add(n_tags));
    if comment_at.saturating_add(COMMENT) > bytes.len() {
        return Err(fail(format!(
            "truncated AL3D header: {n_tags} tags and the comment need {} bytes, the file has {}",
            comment_at.saturating_add(COMMENT),
            bytes.len()
        )));
    }
    // In file order (channels are listed in it), and by key.
    let mut ordered = Vec::with_capacity(n_tags);
    for k in 0..n_tags {
        ordered.push(tag(2 + k)?);
    }
    let tags: BTreeMap<String, String> = ordered.iter().cloned().collect();
    let get = |key: &str| {
        tags.get(key)
            .ok_or_else(|| fail(format!("AL3D file has no `{key}` tag")))
    };
    let count_of = |key: &str| -> Result<usize> {
        let v = get(key)?;
        v.parse()
            .map_err(|_| fail(format!("AL3D `{key}` = `{v}` is not a count")))
    };
    let length_of = |key: &str| -> Result<f64> {
        let v = get(key)?;
        v.parse::<f64>()
            .ok()
            .map(f64::abs)
            .filter(|l| l.is_finite() && *l > 0.0)
            .ok_or_else(|| fail(format!("AL3D `{key}` = `{v}` is not a positive length")))
    };
    let (nx, ny) = (count_of("Cols")?, count_of("Rows")?);
    let (dx, dy) = (length_of("PixelSizeXMeter")?, length_of("PixelSizeYMeter")?);
    if nx == 0 || ny == 0 {
        return Err(fail(format!("AL3D grid is {nx} × {ny}")));
    }
    // Image `rows` rows of `row_bytes`, padded to 8 bytes, at `at`, inside the file?
    let fits = |at: usize, row_bytes: usize, rows: usize| {
        row_bytes
            .checked_add(7)
            .map(|r| r / 8 * 8)
            .and_then(|stride| stride.checked_mul(rows).map(|n| (stride, n)))
            .filter(|(_, n)| at.checked_add(*n).is_some_and(|end| end <= bytes.len()))
            .map(|(stride, _)| stride)
    };
    let depth_at = count_of("DepthImageOffset")?;
    let depth_stride = nx
        .checked_mul(4)
        .and_then(|row| fits(depth_at, row, ny))
        .filter(|_| depth_at > 0)
        .ok_or_else(|| {
            fail(format!(
                "AL3D depth image of {nx} × {ny} float32 at byte {depth_at} does not fit the \
                 file ({} bytes)",
                bytes.len()
            ))
        })?;

    // Texture planes named by `…Ptr` tags (Gwyddion names them after the tag, without `Ptr`).
    let mut names = vec![vec!["Depth".to_string()]];
    let mut planes: Vec<usize> = vec![];
    let n_planes = tags
        .get("NumberOfPlanes")
        .and_then(|v| v.parse::<usize>().ok());
    let texture_at = tags
        .get("TextureImageOffset")
        .and_then(|v| v.parse::<usize>().ok());
    let texture_stride = match (n_planes, texture_at) {
        (Some(n), Some(at)) if n > 0 && at > 0 => fits(at, nx, ny.saturating_mul(n)),
        _ => None,
    };
    if texture_stride.is_some() {
        for (key, value) in &ordered {
            let Some(name) = key.strip_suffix("Ptr") else {
                continue;
            };
            if name.is_empty() || name.ends_with("Lo") || name.ends_with("Hi") {
                continue;
            }
            let list: Vec<usize> = value
                .split(';')
                .filter_map(|p| p.trim().parse().ok())
                .filter(|&p| Some(p) < n_planes)
                .collect();
            for (j, &plane) in list.iter().enumerate() {
                let title = match (list.len(), j) {
                    (1, _) => name.to_string(),
                    (_, 0) => format!("{name} (R)"),
                    (_, 1) => format!("{name} (G)"),
                    (_, 2) => format!("{name} (B)"),
                    (_, j) => format!("{name} ({j})"),
                };
                names.push(vec![title]);
                planes.push(plane);
            }
        }
    }
    let listing = names
        .iter()
        .map(|n| n[0].as_str())
        .collect::<Vec<_>>()
        .join(", ");
    let chosen = match &opts.channel {
        None => 0,
        Some(wanted) => find_channel(wanted, &names)
            .ok_or_else(|| fail(format!("no channel `{wanted}`; channels: {listing}")))?,
    };

    let z = if chosen == 0 {
        let invalid = tags
            .get("InvalidPixelValue")
            .and_then(|v| v.parse::<f64>().ok())
            .filter(|v| !v.is_nan());
        Array2::from_shape_fn((ny, nx), |(j, i)| {
            let at = depth_at + j * depth_stride + 4 * i;
            let v = f64::from(f32::from_le_bytes(
                bytes[at..at + 4].try_into().expect("4 bytes"),
            ));
            let is_marker = invalid.is_some_and(|m| (v - m).abs() < 1.5e-7 * m.abs());
            if v.is_finite() && !is_marker {
                v
            } else {
                f64::NAN
            }
        })
    } else {
        let (at, stride) = (
            texture_at.expect("checked"),
            texture_stride.expect("checked"),
        );
        let plane_at = at + planes[chosen - 1] * stride * ny;
        Array2::from_shape_fn((ny, nx), |(j, i)| {
            f64::from(bytes[plane_at + j * stride + i])
        })
    };

    let mut header = BTreeMap::new();
    header.insert("channels".to_string(), listing);
    header.insert("Version".to_string(), version);
    for (key, value) in &tags {
        if NOT_METADATA.contains(&key.as_str()) || key.contains("Ptr") || key.ends_with("Offset") {
            continue;
        }
        header.insert(key.clone(), value.clone());
    }
    if chosen > 0 {
        header.insert("z_unit".to_string(), "counts".to_string());
    }
    let comment = nul_terminated(&bytes[comment_at..comment_at + COMMENT]);
    if !comment.is_empty() {
        header.insert("comment".to_string(), comment);
    }
    Ok(RawMap {
        z,
        dx,
        dy,
        x0: 0.0,
        y0: 0.0,
        channel: names[chosen][0].clone(),
        format: "al3d",
        header,
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};

    /// Metadata SurfaceTopography 1.27.1 reads from al3d-1.al3d (its `raw_metadata`), the
    /// channels, and the texture planes as counts.
    #[test]
    fn metadata_and_channels_of_the_real_sample() {
        let path = surface_sample("al3d-1.al3d");
        let map = read_height_map(&path, &ReadOptions::default()).unwrap();
        let h = &map.source.header;
        assert_eq!(map.channel, "Depth");
        assert_eq!(h["CreatingApplication"], "MeasureSuite 5.3.6");
        assert_eq!(h["DepthResFilterVal"], "6.06e-07");
        assert_eq!(h["Version"], "1");
        assert!(!h.contains_key("DirSpacer") && !h.contains_key("DepthImageOffset"));
        assert_eq!(
            h["channels"],
            "Depth, DepthImageRes, Texture (R), Texture (G), Texture (B)"
        );
        let opts = ReadOptions {
            channel: Some("texture (b)".into()),
            ..ReadOptions::default()
        };
        let blue = read_height_map(&path, &opts).unwrap();
        assert_eq!(
            (blue.nx(), blue.ny(), blue.channel.as_str()),
            (200, 296, "Texture (B)")
        );
        assert_eq!(blue.source.header["z_unit"], "counts");
    }

    /// A pixel equal to `InvalidPixelValue` (3.000000028082e+15 in the sample, a float32 written
    /// as text) or NaN is invalid.
    #[test]
    fn invalid_pixel_value_and_nan() {
        let mut bytes = std::fs::read(surface_sample("al3d-1.al3d")).unwrap();
        let at = |row: usize, col: usize| 1261 + row * 800 + 4 * col;
        let (a, b) = (at(0, 3), at(7, 9));
        bytes[a..a + 4].copy_from_slice(&(3.000000028082e15_f64 as f32).to_le_bytes());
        bytes[b..b + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        let map = read_bytes("a.al3d", &bytes).unwrap();
        let valid = map.valid.as_ref().unwrap();
        assert!(!valid[[0, 3]] && !valid[[7, 9]]);
        assert_eq!(valid.iter().filter(|v| !**v).count(), 2);
        // A tag count beyond the file, a depth image beyond the file.
        let mut bad = bytes.clone();
        bad[17 + 52 + 20..17 + 52 + 24].copy_from_slice(b"9999");
        let e = read_bytes("b.al3d", &bad).unwrap_err().to_string();
        assert!(e.contains("b.al3d") && e.contains("truncated"), "{e}");
        let e = read_bytes("c.al3d", &bytes[..200_000])
            .unwrap_err()
            .to_string();
        assert!(e.contains("c.al3d") && e.contains("does not fit"), "{e}");
    }
}
