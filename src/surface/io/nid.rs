//! Nanosurf `.nid` / `.ezd` (easyScan, Flex, DriveAFM; docs/surfaces.md), as Gwyddion's
//! `ezdfile.c` and SurfaceTopography 1.27.1's `IO/EZD.py` read it: an INI-style latin-1 header
//! (`[DataSet]` first, `[Section]` lines, `Key=Value` lines), then a line starting `#!`, after
//! which the binary data sets follow back to back. `[DataSet]` lists them as `Gr<i>-Ch<j>` =
//! section name for `Gr<i>-Count` slots of `GroupCount` groups (empty slots have no entry).
//! Each data-set section gives `Points` × `Lines`, `SaveBits`, `SaveSign`, `SaveOrder`
//! (`Intel` = little-endian), the lateral ranges `Dim0Range`, `Dim1Range` (units `Dim0Unit`,
//! `Dim1Unit`) and the value range `Dim2Min`, `Dim2Range` in `Dim2Unit`: the raw integers span
//! the range, z = raw · Dim2Range / 2^bits + Dim2Min (+ Dim2Range / 2 for signed integers).
//! Lines are stored from the bottom of the image (both readers flip them; hdi's row 0 is the
//! last stored line).
use super::units::{decode_text, length_factor};
use super::{find_channel, format_error, unsupported, RawMap, ReadOptions};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

/// The first line of every Nanosurf file.
pub(crate) const MAGIC: &[u8] = b"[DataSet]\r\n";
/// How far the header may reach before its `#!` line.
const HEADER_MAX: usize = 4 << 20;

/// One data set (channel) of the file.
struct DataSet {
    /// `Frame (Dim2Name)`, e.g. `Scan forward (Z-Axis)`, as SurfaceTopography names it.
    name: String,
    section: String,
    dim2_name: String,
    nx: usize,
    ny: usize,
    bytes_per_value: usize,
    signed: bool,
    little_endian: bool,
    /// Where its values start in the file.
    data_at: usize,
    unit: String,
}

/// The header's sections (`name` → key → value) and where the data start.
type Sections = BTreeMap<String, BTreeMap<String, String>>;

fn parse_header(bytes: &[u8]) -> std::result::Result<(Sections, usize), String> {
    if !bytes.starts_with(MAGIC) {
        return Err("not a Nanosurf file (no `[DataSet]` first line)".into());
    }
    let mut sections: Sections = BTreeMap::new();
    let mut current = String::from("DataSet");
    let mut at = MAGIC.len();
    loop {
        if at >= bytes.len().min(HEADER_MAX) {
            return Err("truncated Nanosurf file: no `#!` line ends the header".into());
        }
        if bytes[at..].starts_with(b"#!") {
            return Ok((sections, at + 2));
        }
        let end = bytes[at..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |k| at + k + 1);
        // UTF-8 if valid, else latin-1 (units such as µ are single bytes in older files).
        let line = decode_text(&bytes[at..end]);
        let line = line.trim();
        at = end;
        if line.is_empty() {
            continue;
        }
        if let Some(name) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            current = name.to_string();
            continue;
        }
        let (key, value) = line
            .split_once('=')
            .ok_or_else(|| format!("Nanosurf header line `{line}` is not `Key=Value`"))?;
        sections
            .entry(current.clone())
            .or_default()
            .insert(key.to_string(), value.to_string());
    }
}

/// Every data set the `[DataSet]` section lists, in group and slot order, laid out in the file.
fn data_sets(sections: &Sections, data_start: usize) -> std::result::Result<Vec<DataSet>, String> {
    let empty = BTreeMap::new();
    let top = sections.get("DataSet").unwrap_or(&empty);
    let count = |map: &BTreeMap<String, String>, key: &str, what: &str| {
        let v = map
            .get(key)
            .ok_or_else(|| format!("Nanosurf {what} has no `{key}`"))?;
        v.trim()
            .parse::<usize>()
            .map_err(|_| format!("Nanosurf `{key}` = `{v}` in {what} is not a count"))
    };
    let groups = count(top, "GroupCount", "[DataSet]")?;
    let mut out = Vec::new();
    let mut at = data_start;
    for g in 0..groups {
        let slots = count(top, &format!("Gr{g}-Count"), "[DataSet]")?;
        for s in 0..slots.min(1024) {
            let Some(name) = top.get(&format!("Gr{g}-Ch{s}")) else {
                continue;
            };
            let Some(d) = sections.get(name) else {
                continue;
            };
            let what = format!("[{name}]");
            let get = |key: &str| {
                d.get(key)
                    .map(|v| v.trim())
                    .ok_or_else(|| format!("Nanosurf {what} has no `{key}`"))
            };
            if get("SaveMode")? != "Binary" {
                return Err(format!(
                    "Nanosurf {what}: SaveMode `{}` (only `Binary` is read)",
                    get("SaveMode")?
                ));
            }
            let bits = count(d, "SaveBits", &what)?;
            if !matches!(bits, 8 | 16 | 32) {
                return Err(format!("Nanosurf {what}: SaveBits {bits} (8, 16 or 32)"));
            }
            let (nx, ny) = (count(d, "Points", &what)?, count(d, "Lines", &what)?);
            let size = nx
                .checked_mul(ny)
                .and_then(|n| n.checked_mul(bits / 8))
                .ok_or_else(|| format!("Nanosurf {what}: {nx} × {ny} values overflow"))?;
            let frame = d.get("Frame").map_or("", |f| f.trim());
            let dim2_name = d.get("Dim2Name").map_or("", |f| f.trim()).to_string();
            out.push(DataSet {
                name: format!("{frame} ({dim2_name})"),
                section: name.clone(),
                dim2_name,
                nx,
                ny,
                bytes_per_value: bits / 8,
                signed: get("SaveSign")? == "Signed",
                little_endian: get("SaveOrder")? == "Intel",
                data_at: at,
                unit: d.get("Dim2Unit").map_or("", |u| u.trim()).to_string(),
            });
            at = at.saturating_add(size);
        }
    }
    Ok(out)
}

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let fail = |reason: String| format_error(path, reason);
    let (sections, data_start) = parse_header(bytes).map_err(fail)?;
    let sets = data_sets(&sections, data_start).map_err(fail)?;
    let is_height = |d: &DataSet| length_factor(&d.unit).is_some();
    let listing = || {
        let names: Vec<String> = sets
            .iter()
            .map(|d| format!("{} [{}]", d.name, d.unit))
            .collect();
        names.join(", ")
    };
    let k = match &opts.channel {
        Some(wanted) => {
            let names: Vec<Vec<String>> = sets
                .iter()
                .map(|d| vec![d.name.clone(), d.dim2_name.clone(), d.section.clone()])
                .collect();
            find_channel(wanted, &names)
                .ok_or_else(|| fail(format!("no channel `{wanted}`; channels: {}", listing())))?
        }
        // The first data set in a length unit, as SurfaceTopography's default channel.
        None => sets.iter().position(is_height).ok_or_else(|| {
            fail(format!(
                "Nanosurf file has no height channel; channels: {}",
                listing()
            ))
        })?,
    };
    let d = &sets[k];
    let section = &sections[&d.section];
    let z_factor = length_factor(&d.unit).ok_or_else(|| {
        unsupported(
            path,
            format!(
                "Nanosurf channel `{}` is in `{}`, not a length: not a height map",
                d.name, d.unit
            ),
        )
    })?;
    let number = |key: &str| -> Result<f64> {
        let v = section.get(key).map_or("", |v| v.trim());
        v.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| {
                fail(format!(
                    "Nanosurf [{}] `{key}` = `{v}` is not a number",
                    d.section
                ))
            })
    };
    let lateral = |axis: &str| -> Result<f64> {
        let range = number(&format!("{axis}Range"))?;
        let unit = section
            .get(&format!("{axis}Unit"))
            .map_or(d.unit.as_str(), |u| u.trim());
        let f = length_factor(unit).ok_or_else(|| {
            fail(format!(
                "Nanosurf [{}] `{axis}Unit` = `{unit}` is not a length",
                d.section
            ))
        })?;
        Ok(range * f)
    };
    let (lx, ly) = (lateral("Dim0")?, lateral("Dim1")?);
    let range = number("Dim2Range")?;
    let min = match section.contains_key("Dim2Min") {
        true => number("Dim2Min")?,
        false => 0.0,
    };
    let n = d.nx * d.ny;
    let end = d
        .data_at
        .checked_add(n * d.bytes_per_value)
        .filter(|&e| e <= bytes.len())
        .ok_or_else(|| {
            fail(format!(
                "truncated Nanosurf file: data set [{}] of {} × {} × {} bytes at {} runs past \
                 the end ({} bytes)",
                d.section,
                d.nx,
                d.ny,
                d.bytes_per_value,
                d.data_at,
                bytes.len()
            ))
        })?;
    let data = &bytes[d.data_at..end];
    let scale = range / 2f64.powi(8 * d.bytes_per_value as i32) * z_factor;
    let offset = (min + if d.signed { range / 2.0 } else { 0.0 }) * z_factor;
    let raw = |i: usize| -> f64 {
        let b = &data[i * d.bytes_per_value..(i + 1) * d.bytes_per_value];
        let mut w = [0u8; 4];
        w[..b.len()].copy_from_slice(b);
        if !d.little_endian {
            w[..b.len()].reverse();
        }
        match (d.bytes_per_value, d.signed) {
            (1, true) => f64::from(w[0] as i8),
            (1, false) => f64::from(w[0]),
            (2, true) => f64::from(i16::from_le_bytes([w[0], w[1]])),
            (2, false) => f64::from(u16::from_le_bytes([w[0], w[1]])),
            (_, true) => f64::from(i32::from_le_bytes(w)),
            (_, false) => f64::from(u32::from_le_bytes(w)),
        }
    };
    // Stored from the bottom line up: hdi's row r is stored line ny − 1 − r.
    let z = Array2::from_shape_fn((d.ny, d.nx), |(r, c)| {
        raw((d.ny - 1 - r) * d.nx + c) * scale + offset
    });
    let mut header = BTreeMap::new();
    header.insert("channels".into(), listing());
    for (key, value) in section {
        header.insert(key.clone(), value.clone());
    }
    if let Some(info) = sections.get("DataSet-Info") {
        for (key, value) in info {
            if !value.trim().starts_with("---") {
                header.insert(format!("DataSet-Info/{key}"), value.trim().to_string());
            }
        }
    }
    Ok(RawMap {
        z,
        dx: lx / d.nx as f64,
        dy: ly / d.ny as f64,
        x0: 0.0,
        y0: 0.0,
        channel: d.name.clone(),
        format: "nid",
        header,
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};

    /// A Nanosurf file as the layout above describes it: two 4 × 3 data sets (int16 `Z-Axis`
    /// in m, uint8 `Amplitude` in V), raw value 100·line + column.
    fn nid() -> Vec<u8> {
        let set = |bits: u32, sign: &str, name: &str, unit: &str| {
            format!(
                "Points=4\r\nLines=3\r\nFrame=Scan forward\r\nDim0Range=2e-06\r\nDim0Unit=m\r\n\
                 Dim1Range=1.5e-06\r\nDim1Unit=m\r\nDim2Name={name}\r\nDim2Unit={unit}\r\n\
                 Dim2Range=6.5536e-06\r\nDim2Min=-1e-06\r\nSaveMode=Binary\r\nSaveBits={bits}\r\n\
                 SaveSign={sign}\r\nSaveOrder=Intel\r\n"
            )
        };
        let mut b = format!(
            "[DataSet]\r\nVersion=2\r\nGroupCount=1\r\nGr0-Count=3\r\nGr0-Ch0=DataSet-0:0\r\n\
             Gr0-Ch2=DataSet-0:2\r\n\r\n[DataSet-Info]\r\nHead type=Test\r\n\r\n[DataSet-0:0]\r\n{}\r\n\
             [DataSet-0:2]\r\n{}\r\n#!",
            set(16, "Signed", "Z-Axis", "m"),
            set(8, "Unsigned", "Amplitude", "V")
        )
        .into_bytes();
        for line in 0..3i16 {
            for col in 0..4i16 {
                b.extend((100 * line + col).to_le_bytes());
            }
        }
        b.extend((0..12u8).collect::<Vec<_>>());
        b
    }

    #[test]
    fn scaling_orientation_and_channels() {
        let map = read_bytes("a.nid", &nid()).unwrap();
        assert_eq!(
            (map.nx(), map.ny(), map.source.format.as_str()),
            (4, 3, "nid")
        );
        assert_eq!(map.channel, "Scan forward (Z-Axis)");
        assert!(close(map.dx, 0.5e-6, 1e-12) && close(map.dy, 0.5e-6, 1e-12));
        // z = raw · 6.5536 µm / 2^16 + (−1 µm + 3.2768 µm); line 2 is row 0.
        let z = |raw: f64| raw * 1e-10 + 2.2768e-6;
        assert!(close(map.z[[0, 0]], z(200.0), 1e-12));
        assert!(close(map.z[[2, 3]], z(3.0), 1e-12));
        assert_eq!(map.source.header["DataSet-Info/Head type"], "Test");
        // The volt channel is listed, selectable by name, and refused as a height map.
        let (_dir, path) = write_temp("a.nid", &nid());
        let opts = ReadOptions {
            channel: Some("amplitude".into()),
            ..ReadOptions::default()
        };
        let e = read_height_map(&path, &opts).unwrap_err().to_string();
        assert!(e.contains("a.nid") && e.contains("not a length"), "{e}");
        assert!(map.source.header["channels"].contains("Scan forward (Amplitude) [V]"));
    }

    /// The real sample's eight data sets are listed; `Scan backward (Z-AxisSensor)` is selected
    /// by name and reads as SurfaceTopography 1.27.1 reads its channel 3 (σ and the pixel
    /// [x = 10, y = 20] from `open_topography(…).topography(channel_index=3)`).
    #[test]
    fn the_samples_backward_sensor_channel_is_selectable() {
        let path = surface_sample("nid-1.nid");
        let opts = ReadOptions {
            channel: Some("Scan backward (Z-AxisSensor)".into()),
            ..ReadOptions::default()
        };
        let map = read_height_map(&path, &opts).unwrap();
        assert_eq!(map.channel, "Scan backward (Z-AxisSensor)");
        assert_eq!(map.source.header["channels"].split(", ").count(), 8);
        let n = map.z.len() as f64;
        let mean = map.z.sum() / n;
        let rms = (map.z.mapv(|z| (z - mean).powi(2)).sum() / n).sqrt();
        assert!(close(rms, 3.029781629305204e-07, 1e-9), "{rms}");
        assert!(close(map.z[[20, 10]], -2.9431258055597543e-06, 1e-9));
    }

    #[test]
    fn truncated_and_broken_headers_are_errors_naming_the_file() {
        let good = nid();
        let e = read_bytes("b.nid", &good[..good.len() - 13])
            .unwrap_err()
            .to_string();
        assert!(e.contains("b.nid") && e.contains("truncated"), "{e}");
        let cut = good
            .windows(13)
            .position(|w| w == b"[DataSet-0:2]")
            .unwrap();
        let e = read_bytes("c.nid", &good[..cut]).unwrap_err().to_string();
        assert!(e.contains("c.nid") && e.contains("#!"), "{e}");
        assert!(fuzz_reader("d.nid", &good) > 0);
    }
}
