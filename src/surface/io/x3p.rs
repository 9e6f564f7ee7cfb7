//! ISO 25178-71 (ISO 5436-2) `.x3p`: a ZIP archive with an XML header `main.xml` and the height
//! matrix, either in a binary member (`Record3/DataLink/PointDataLink`, little-endian, x fastest)
//! or inline as `Record3/DataList/Datum` text (docs/surfaces.md).
//!
//! Read: FeatureType `SUR`; CX/CY incremental axes (`AxisType` I, `Increment`, `Offset`, in
//! metres as the standard prescribes); CZ absolute (`AxisType` A) with DataType I/L/F/D =
//! int16/int32/float32/float64 and the optional `Increment`/`Offset` applied as z = Offset +
//! Increment·value; `SizeZ` = 1. Invalid points: NaN floats, empty `<Datum/>`, and the
//! validity bit array `ValidPointsLink` (1 bit per point, least significant bit first; 0 =
//! invalid). The point data's MD5 (`MD5ChecksumPointData`) is checked when present, on top of
//! the ZIP CRC-32. Row 0 of the map is the first y line of the file.
//!
//! Write ([`encode_x3p`]): the same layout back, heights as float64 (`D`) in metres so that
//! reading the file returns the map bit for bit, invalid points as NaN plus a validity bit array,
//! the MD5 sums of the point data, the validity array and `main.xml` (`md5checksum.hex`).
use super::{format_error, heights_with_nan, unsupported, RawMap, ReadOptions};
use crate::formats::md5::md5_hex;
use crate::formats::xml::{Event, Scanner};
use crate::formats::zip::{write_deflated, ZipArchive};
use crate::surface::{HeightMap, Result, SurfaceError};
use ndarray::Array2;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// The largest `main.xml` read (an inline DataList of a 4k × 4k map is ~300 MB of text).
const MAX_XML_BYTES: u64 = 1 << 30;

#[derive(Default)]
struct Axis {
    axis_type: Option<String>,
    data_type: Option<String>,
    increment: Option<String>,
    offset: Option<String>,
}

#[derive(Default)]
struct Header {
    feature_type: Option<String>,
    axes: [Axis; 3],
    size: [Option<String>; 3],
    point_link: Option<String>,
    point_md5: Option<String>,
    valid_link: Option<String>,
    list_dimension: bool,
    /// Inline data (`DataList`); empty `<Datum/>` = NaN.
    data_list: Option<Vec<f64>>,
    info: BTreeMap<String, String>,
}

pub(crate) fn read(path: &Path, bytes: &[u8], _opts: &ReadOptions) -> Result<RawMap> {
    let fail = |reason: String| format_error(path, reason);
    let zip = ZipArchive::parse(bytes).map_err(|e| fail(format!("x3p: {e}")))?;
    let main = zip.find("main.xml").ok_or_else(|| {
        fail("ZIP archive has no main.xml: not an ISO 25178-71 .x3p file".to_string())
    })?;
    let xml = zip
        .read(main, MAX_XML_BYTES)
        .map_err(|e| fail(format!("x3p: {e}")))?;
    let xml =
        std::str::from_utf8(&xml).map_err(|e| fail(format!("x3p main.xml is not UTF-8 ({e})")))?;
    let mut h = parse_header(xml).map_err(|e| fail(format!("x3p main.xml: {e}")))?;

    check_areal_matrix(path, &h)?;
    let axes = read_axes(path, &h)?;
    let (data_type, width) = height_data_type(path, &h.axes[2])?;
    let (nx, ny, n) = matrix_size(path, &h)?;

    let mut values: Vec<f64> = if let Some(list) = h.data_list.take() {
        if list.len() != n {
            return Err(fail(format!(
                "x3p DataList has {} Datum values, the matrix is {nx}×{ny} = {n}",
                list.len()
            )));
        }
        list
    } else {
        read_point_member(path, &zip, &h, data_type, width, (nx, ny))?
    };
    // Skipped for the identity scale, so that a float64 file reads back bit for bit (−0.0 too).
    if axes.z_inc != 1.0 || axes.z_off != 0.0 {
        for v in values.iter_mut() {
            *v = axes.z_off + axes.z_inc * *v;
        }
    }
    if let Some(link) = h.valid_link.as_deref().map(str::trim) {
        apply_validity_mask(path, &zip, link, &mut values)?;
    }
    let z = Array2::from_shape_vec((ny, nx), values)
        .map_err(|e| fail(format!("x3p data shape: {e}")))?;
    let mut header = h.info;
    header.insert("CZ/DataType".into(), data_type.to_string());
    Ok(RawMap {
        z,
        dx: axes.dx,
        dy: axes.dy,
        x0: axes.x0,
        y0: axes.y0,
        channel: "height".into(),
        format: "x3p",
        header,
    })
}

/// The map as an ISO 25178-71 `.x3p` archive (`main.xml`, `bin/data.bin`, `bin/valid.bin` when
/// some point is invalid, `md5checksum.hex`). `note` goes into an XML comment (provenance: the
/// source file and the processing). Deterministic: the same map and note give the same bytes.
pub fn encode_x3p(map: &HeightMap, note: &str) -> Result<Vec<u8>> {
    let (nx, ny) = (map.nx(), map.ny());
    let mut data = Vec::with_capacity(nx * ny * 8);
    for v in heights_with_nan(map).iter() {
        data.extend_from_slice(&v.to_le_bytes());
    }
    // One bit per point, least significant first, x fastest (ISO 25178-71, ValidPointsLink).
    let some_invalid = map.valid.as_ref().filter(|v| v.iter().any(|ok| !ok));
    let valid_bits = some_invalid.map(|valid| {
        let mut bits = vec![0u8; (nx * ny).div_ceil(8)];
        for (k, _) in valid.iter().enumerate().filter(|(_, ok)| **ok) {
            bits[k / 8] |= 1 << (k % 8);
        }
        bits
    });
    // A comment cannot hold `--` (XML 1.0 §2.5).
    let note = note.replace("--", "- -").replace(['\n', '\r'], " ");
    let mut xml = String::new();
    let _ = write!(
        xml,
        r#"<?xml version="1.0" encoding="UTF-8"?>
<p:ISO5436_2 xmlns:p="http://www.opengps.eu/2008/ISO5436_2" xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:schemaLocation="http://www.opengps.eu/2008/ISO5436_2 http://www.opengps.eu/2008/ISO5436_2/ISO5436_2.xsd">
<!-- {note} -->
<Record1>
<Revision>ISO5436 - 2000</Revision>
<FeatureType>SUR</FeatureType>
<Axes>
<CX><AxisType>I</AxisType><DataType>D</DataType><Increment>{dx:e}</Increment><Offset>{x0:e}</Offset></CX>
<CY><AxisType>I</AxisType><DataType>D</DataType><Increment>{dy:e}</Increment><Offset>{y0:e}</Offset></CY>
<CZ><AxisType>A</AxisType><DataType>D</DataType><Increment>1</Increment><Offset>0</Offset></CZ>
</Axes>
</Record1>
<Record3>
<MatrixDimension><SizeX>{nx}</SizeX><SizeY>{ny}</SizeY><SizeZ>1</SizeZ></MatrixDimension>
<DataLink><PointDataLink>bin/data.bin</PointDataLink><MD5ChecksumPointData>{md5}</MD5ChecksumPointData>"#,
        dx = map.dx,
        dy = map.dy,
        x0 = map.x0,
        y0 = map.y0,
        md5 = md5_hex(&data).to_uppercase(),
    );
    if let Some(bits) = &valid_bits {
        let _ = write!(
            xml,
            "<ValidPointsLink>bin/valid.bin</ValidPointsLink>\
             <MD5ChecksumValidPoints>{}</MD5ChecksumValidPoints>",
            md5_hex(bits).to_uppercase()
        );
    }
    xml.push_str(
        "</DataLink>\n</Record3>\n<Record4>\n<ChecksumFile>md5checksum.hex</ChecksumFile>\n\
         </Record4>\n</p:ISO5436_2>\n",
    );
    let checksum = format!("{} *main.xml\n", md5_hex(xml.as_bytes()).to_uppercase());
    let mut members: Vec<(&str, &[u8])> = vec![("main.xml", xml.as_bytes())];
    members.push(("bin/data.bin", &data));
    if let Some(bits) = &valid_bits {
        members.push(("bin/valid.bin", bits));
    }
    members.push(("md5checksum.hex", checksum.as_bytes()));
    write_deflated(&members).map_err(|e| SurfaceError::InvalidData(format!("x3p: {e}")))
}

/// Only areal surfaces stored as a matrix are height maps; profiles and point lists are not.
fn check_areal_matrix(path: &Path, h: &Header) -> Result<()> {
    match h.feature_type.as_deref().map(str::trim) {
        Some("SUR") => {}
        Some(other) => {
            return Err(unsupported(
                path,
                format!("x3p FeatureType `{other}`; only areal surfaces (SUR) are height maps"),
            ))
        }
        None => {
            return Err(format_error(
                path,
                "x3p main.xml has no Record1/FeatureType",
            ))
        }
    }
    if h.list_dimension {
        return Err(unsupported(
            path,
            "x3p point list (ListDimension); only matrix data (MatrixDimension) is read",
        ));
    }
    Ok(())
}

/// The sampling of the map and the linear height scale z = offset + increment·value.
struct Axes {
    dx: f64,
    dy: f64,
    x0: f64,
    y0: f64,
    z_inc: f64,
    z_off: f64,
}

/// A finite number from the header, or `default` when the element is absent.
fn header_number(
    path: &Path,
    what: &str,
    text: &Option<String>,
    default: Option<f64>,
) -> Result<f64> {
    match text.as_deref().map(str::trim) {
        None => default.ok_or_else(|| format_error(path, format!("x3p main.xml lacks {what}"))),
        Some(t) => t
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format_error(path, format!("x3p {what} = `{t}` is not a number"))),
    }
}

/// CX/CY must be incremental axes; CZ, when typed, absolute. The checks run in the order the
/// reader has always reported them (axis types, then numbers, then the CZ type).
fn read_axes(path: &Path, h: &Header) -> Result<Axes> {
    for (k, name) in ["CX", "CY"].iter().enumerate() {
        match h.axes[k].axis_type.as_deref().map(str::trim) {
            Some("I") => {}
            Some(t) => {
                return Err(unsupported(
                    path,
                    format!("x3p {name} AxisType `{t}`; only incremental (I) x/y axes are read"),
                ))
            }
            None => {
                return Err(format_error(
                    path,
                    format!("x3p main.xml lacks {name}/AxisType"),
                ))
            }
        }
    }
    let axes = Axes {
        dx: header_number(path, "CX/Increment", &h.axes[0].increment, None)?,
        dy: header_number(path, "CY/Increment", &h.axes[1].increment, None)?,
        x0: header_number(path, "CX/Offset", &h.axes[0].offset, Some(0.0))?,
        y0: header_number(path, "CY/Offset", &h.axes[1].offset, Some(0.0))?,
        z_inc: header_number(path, "CZ/Increment", &h.axes[2].increment, Some(1.0))?,
        z_off: header_number(path, "CZ/Offset", &h.axes[2].offset, Some(0.0))?,
    };
    if let Some(t) = h.axes[2].axis_type.as_deref().map(str::trim) {
        if t != "A" {
            return Err(unsupported(
                path,
                format!("x3p CZ AxisType `{t}`; heights must be absolute (A)"),
            ));
        }
    }
    Ok(axes)
}

/// The CZ DataType code and its width in bytes.
fn height_data_type<'h>(path: &Path, cz: &'h Axis) -> Result<(&'h str, usize)> {
    let data_type = cz
        .data_type
        .as_deref()
        .map(str::trim)
        .ok_or_else(|| format_error(path, "x3p main.xml lacks CZ/DataType"))?;
    let width = match data_type {
        "I" => 2,
        "L" | "F" => 4,
        "D" => 8,
        other => {
            return Err(format_error(
                path,
                format!("x3p CZ DataType `{other}` is not I, L, F or D"),
            ))
        }
    };
    Ok((data_type, width))
}

/// (SizeX, SizeY, SizeX·SizeY) of a single-layer matrix.
fn matrix_size(path: &Path, h: &Header) -> Result<(usize, usize, usize)> {
    let dim = |k: usize, name: &str| -> Result<usize> {
        let t = h.size[k].as_deref().map(str::trim).ok_or_else(|| {
            format_error(path, format!("x3p main.xml lacks MatrixDimension/{name}"))
        })?;
        t.parse::<usize>().ok().filter(|&n| n > 0).ok_or_else(|| {
            format_error(
                path,
                format!("x3p {name} = `{t}` is not a positive integer"),
            )
        })
    };
    let (nx, ny, nz) = (dim(0, "SizeX")?, dim(1, "SizeY")?, dim(2, "SizeZ")?);
    if nz != 1 {
        return Err(unsupported(
            path,
            format!("x3p SizeZ = {nz}; only one height layer (SizeZ = 1) is read"),
        ));
    }
    let n = nx
        .checked_mul(ny)
        .ok_or_else(|| format_error(path, format!("x3p matrix {nx}×{ny} is too large")))?;
    Ok((nx, ny, n))
}

/// The raw heights from the `PointDataLink` member, size- and MD5-checked.
fn read_point_member(
    path: &Path,
    zip: &ZipArchive<'_>,
    h: &Header,
    data_type: &str,
    width: usize,
    (nx, ny): (usize, usize),
) -> Result<Vec<f64>> {
    let fail = |reason: String| format_error(path, reason);
    let n = nx * ny;
    let link = h
        .point_link
        .as_deref()
        .map(str::trim)
        .ok_or_else(|| fail("x3p Record3 has neither DataLink nor DataList".into()))?;
    let entry = zip.find(link).ok_or_else(|| {
        fail(format!(
            "x3p data member `{link}` (PointDataLink) is not in the archive"
        ))
    })?;
    let needed = n.checked_mul(width).map(|b| b as u64);
    match needed {
        Some(needed) if needed <= entry.size => {}
        _ => {
            return Err(fail(format!(
                "truncated x3p data: {nx}×{ny} values of type {data_type} need {} bytes, \
                 `{link}` has {}",
                needed.map_or("more than addressable".into(), |b| b.to_string()),
                entry.size
            )))
        }
    }
    let data = zip
        .read(entry, entry.size)
        .map_err(|e| fail(format!("x3p: {e}")))?;
    if let Some(want) = h.point_md5.as_deref().map(str::trim) {
        let got = md5_hex(&data);
        if !got.eq_ignore_ascii_case(want) {
            return Err(fail(format!(
                "x3p `{link}` fails its MD5 checksum (main.xml says {want}, data is {got})"
            )));
        }
    }
    Ok(decode(&data[..n * width], data_type))
}

/// Marks the points whose bit in the `ValidPointsLink` member is 0 as NaN.
fn apply_validity_mask(
    path: &Path,
    zip: &ZipArchive<'_>,
    link: &str,
    values: &mut [f64],
) -> Result<()> {
    let fail = |reason: String| format_error(path, reason);
    let n = values.len();
    let entry = zip.find(link).ok_or_else(|| {
        fail(format!(
            "x3p validity member `{link}` (ValidPointsLink) is not in the archive"
        ))
    })?;
    let bits = zip
        .read(entry, entry.size)
        .map_err(|e| fail(format!("x3p: {e}")))?;
    if (bits.len() as u64) < (n as u64).div_ceil(8) {
        return Err(fail(format!(
            "truncated x3p validity mask `{link}`: {} bytes for {n} points",
            bits.len()
        )));
    }
    for (k, v) in values.iter_mut().enumerate() {
        if bits[k / 8] & (1 << (k % 8)) == 0 {
            *v = f64::NAN;
        }
    }
    Ok(())
}

/// Little-endian values of one ISO 5436-2 data type as f64.
fn decode(data: &[u8], data_type: &str) -> Vec<f64> {
    match data_type {
        "I" => data
            .chunks_exact(2)
            .map(|c| i16::from_le_bytes([c[0], c[1]]) as f64)
            .collect(),
        "L" => data
            .chunks_exact(4)
            .map(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
            .collect(),
        "F" => data
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
            .collect(),
        _ => data
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
            .collect(),
    }
}

/// The fields of `main.xml` the reader uses, by their element path below the root.
fn parse_header(xml: &str) -> std::result::Result<Header, String> {
    let mut h = Header::default();
    let mut scanner = Scanner::new(xml);
    let mut text = String::new();
    while let Some(event) = scanner.next() {
        match event.map_err(|e| e.to_string())? {
            Event::Start(name) => {
                text.clear();
                let open = scanner.open_elements();
                if open.len() == 3 && open[1] == "Record3" {
                    match name {
                        "DataList" => h.data_list = Some(Vec::new()),
                        "ListDimension" => h.list_dimension = true,
                        _ => {}
                    }
                }
            }
            Event::Text(t) => text.push_str(&t),
            Event::End(name) => {
                // The scanner has already popped `name`: the open elements are its parents.
                let parents = scanner.open_elements();
                let below_root = parents.get(1..).unwrap_or(&[]);
                let value = std::mem::take(&mut text);
                store(&mut h, below_root, name, value)?;
            }
        }
    }
    Ok(h)
}

fn store(
    h: &mut Header,
    parents: &[&str],
    name: &str,
    value: String,
) -> std::result::Result<(), String> {
    match (parents, name) {
        (["Record1"], "FeatureType") => h.feature_type = Some(value),
        (["Record1", "Axes", axis], field) => {
            let k = match *axis {
                "CX" => 0,
                "CY" => 1,
                "CZ" => 2,
                _ => return Ok(()),
            };
            let a = &mut h.axes[k];
            match field {
                "AxisType" => a.axis_type = Some(value),
                "DataType" => a.data_type = Some(value),
                "Increment" => a.increment = Some(value),
                "Offset" => a.offset = Some(value),
                _ => {}
            }
        }
        (["Record2", "Instrument"], field) => {
            h.info
                .insert(format!("Instrument/{field}"), value.trim().to_string());
        }
        (["Record2"], "Date") => {
            h.info.insert("Date".into(), value.trim().to_string());
        }
        (["Record3", "MatrixDimension"], field) => match field {
            "SizeX" => h.size[0] = Some(value),
            "SizeY" => h.size[1] = Some(value),
            "SizeZ" => h.size[2] = Some(value),
            _ => {}
        },
        (["Record3", "DataLink"], field) => match field {
            "PointDataLink" => h.point_link = Some(value),
            "MD5ChecksumPointData" => h.point_md5 = Some(value),
            "ValidPointsLink" => h.valid_link = Some(value),
            _ => {}
        },
        (["Record3", "DataList"], "Datum") => {
            let t = value.trim();
            // An empty Datum marks a missing point (ISO 25178-71, Record3 DataList).
            let v = if t.is_empty() {
                f64::NAN
            } else {
                t.parse::<f64>()
                    .map_err(|_| format!("DataList Datum `{}` is not a number", short(t)))?
            };
            if let Some(list) = h.data_list.as_mut() {
                list.push(v);
            }
        }
        _ => {}
    }
    Ok(())
}

fn short(t: &str) -> &str {
    match t.char_indices().nth(40) {
        Some((k, _)) => &t[..k],
        None => t,
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};
    use crate::surface::HeightMap;
    use std::path::PathBuf;

    fn sample(name: &str) -> PathBuf {
        surface_sample(name)
    }

    fn read(path: &std::path::Path) -> crate::surface::Result<HeightMap> {
        read_height_map(path, &ReadOptions::default())
    }

    #[test]
    fn python_written_files_match_numpy() {
        // Files and numbers from tests/data/surfaces/readers_b/make_samples.py (numpy + zipfile).
        let text = std::fs::read_to_string(sample("readers_b/expected.json")).unwrap();
        let expected: serde_json::Value = serde_json::from_str(&text).unwrap();
        let mut seen = 0;
        for (name, want) in expected.as_object().unwrap() {
            if !name.starts_with("x3p_") {
                continue;
            }
            seen += 1;
            let map = read(&sample(&format!("readers_b/{name}"))).unwrap();
            let f = |k: &str| want[k].as_f64().unwrap();
            assert_eq!(map.source.format, "x3p");
            assert_eq!(map.nx() as f64, f("nx"), "{name}");
            assert_eq!(map.ny() as f64, f("ny"), "{name}");
            for (got, k) in [
                (map.dx, "dx"),
                (map.dy, "dy"),
                (map.x0, "x0"),
                (map.y0, "y0"),
            ] {
                assert!(close(got, f(k), 1e-14), "{name} {k}: {got} vs {}", f(k));
            }
            let (ny, nx) = map.z.dim();
            for (got, k) in [
                (map.z[[0, 0]], "z_0_0"),
                (map.z[[1, 2]], "z_1_2"),
                (map.z[[ny - 1, nx - 1]], "z_last"),
            ] {
                assert!(close(got, f(k), 1e-14), "{name} {k}: {got} vs {}", f(k));
            }
            let (mean, std, invalid) = valid_stats(&map);
            assert_eq!(invalid as f64, f("n_invalid"), "{name}");
            assert!(close(std, f("std"), 1e-9), "{name} σ {std} vs {}", f("std"));
            assert!((mean - f("mean")).abs() <= 1e-9 * f("std"), "{name} mean");
        }
        assert_eq!(seen, 5);
    }

    #[test]
    fn surfacetopography_sample_x3p_2() {
        // Values asserted by SurfaceTopography's test/IO/test_x3p.py (MIT) for x3p-2.x3p.
        let map = read(&sample("x3p-2.x3p")).unwrap();
        assert_eq!((map.nx(), map.ny()), (650, 650));
        let (sx, sy) = map.size();
        assert!(close(sx, 8.29767313942749e-05, 1e-6), "{sx}");
        assert!(close(sy, 0.0002044783737930349, 1e-6), "{sy}");
        assert!(map.valid.is_none());
        let (_, rms, _) = valid_stats(&map);
        assert!(close(rms, 7.728033273597876e-08, 1e-6), "{rms}");
        assert_eq!(
            map.source
                .header
                .get("Instrument/Manufacturer")
                .map(String::as_str),
            Some("DIGITAL SURF")
        );
    }

    #[test]
    fn hostile_archives_are_clean_errors() {
        for (name, want) in [
            ("bad_md5.x3p", "MD5"),
            ("bad_no_main.x3p", "no main.xml"),
            ("bad_huge_size.x3p", "too large"),
            ("bad_short_data.x3p", "truncated x3p data"),
            ("bad_missing_member.x3p", "not in the archive"),
            ("bad_xml.x3p", "malformed XML"),
        ] {
            let err = read(&sample(&format!("readers_b/{name}"))).unwrap_err();
            let msg = err.to_string();
            assert!(msg.contains(name) && msg.contains(want), "{msg}");
        }
        // A flipped bit in the stored data member: the ZIP CRC-32 catches it.
        let mut bytes = std::fs::read(sample("readers_b/x3p_int32_mask.x3p")).unwrap();
        let at = bytes
            .windows(16)
            .position(|w| w == b"bindata/data.bin")
            .unwrap()
            + 16
            + 10;
        bytes[at] ^= 0x04;
        let msg = read_bytes("crc.x3p", &bytes).unwrap_err().to_string();
        assert!(msg.contains("crc.x3p") && msg.contains("CRC"), "{msg}");
    }

    #[test]
    fn truncations_and_byte_flips_never_panic() {
        // x3p_int32_mask.x3p is a registry sample (registry.rs corrupts it the same way).
        for name in ["x3p_datalist.x3p", "x3p_float32.x3p"] {
            let bytes = std::fs::read(sample(&format!("readers_b/{name}"))).unwrap();
            assert!(fuzz_reader(name, &bytes) > 0);
        }
    }

    /// Reader throughput on the two real samples (run with `--ignored --nocapture`; the test
    /// profile builds hdi at opt-level 1, so a release build is faster).
    #[test]
    #[ignore]
    fn reader_throughput() {
        for name in ["x3p-2.x3p", "metropro-1.dat"] {
            let path = sample(name);
            let mb = std::fs::metadata(&path).unwrap().len() as f64 / 1e6;
            let reps = 10;
            let t = std::time::Instant::now();
            for _ in 0..reps {
                read(&path).unwrap();
            }
            let s = t.elapsed().as_secs_f64() / reps as f64;
            println!(
                "{name}: {mb:.2} MB in {:.1} ms = {:.0} MB/s",
                s * 1e3,
                mb / s
            );
        }
    }

    /// Bit for bit: heights (negative zero included), spacing, offsets and the validity mask.
    #[test]
    fn written_x3p_reads_back_bit_for_bit() {
        let mut map = sample_map(37, 23, 2.5e-9, 3.125e-9);
        map.x0 = 1.5e-6;
        map.y0 = -0.25e-6;
        map.z[[0, 1]] = -0.0;
        map.z[[5, 7]] = 1e-300;
        let mut valid = ndarray::Array2::from_elem(map.z.dim(), true);
        for (j, i) in [(0, 0), (3, 36), (22, 5)] {
            valid[[j, i]] = false;
            map.z[[j, i]] = 0.0;
        }
        map.valid = Some(valid);
        let bytes = super::encode_x3p(&map, "test -- note").unwrap();
        assert_eq!(bytes, super::encode_x3p(&map, "test -- note").unwrap());
        let back = read_bytes("w.x3p", &bytes).unwrap();
        assert_eq!(back.z.dim(), map.z.dim());
        for (a, b) in back.z.iter().zip(map.z.iter()) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
        assert_eq!(back.valid, map.valid);
        for (a, b) in [
            (back.dx, map.dx),
            (back.dy, map.dy),
            (back.x0, map.x0),
            (back.y0, map.y0),
        ] {
            assert_eq!(a.to_bits(), b.to_bits());
        }
        // All valid: no validity member, and the map reads back without a mask.
        map.valid = None;
        let bytes = super::encode_x3p(&map, "").unwrap();
        let zip = crate::formats::zip::ZipArchive::parse(&bytes).unwrap();
        assert!(zip.find("bin/valid.bin").is_none());
        let checksum = zip.read(zip.find("md5checksum.hex").unwrap(), 100).unwrap();
        let xml = zip.read(zip.find("main.xml").unwrap(), 1 << 20).unwrap();
        let want = format!("{} *main.xml\n", crate::formats::md5::md5_hex(&xml));
        assert!(String::from_utf8(checksum)
            .unwrap()
            .eq_ignore_ascii_case(&want));
        assert_eq!(read_bytes("w.x3p", &bytes).unwrap().valid, None);
    }
}
