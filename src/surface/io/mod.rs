//! Height-map readers (detect by magic bytes, never by extension) and writers.
//!
//! Formats (docs/surfaces.md; the list is `registry::READERS`): Bruker NanoScope v4.3+ binary
//! (`nanoscope`), Gwyddion native (`gwy`), Gwyddion Simple Field (`gsf`), Asylum Research / Igor
//! binary wave (`ibw`), Digital Surf (`sur`), Surface Data File ISO 25178-71 (`sdf`), Zygo
//! MetroPro `.dat` (`metropro`), Zygo `.datx` (`datx`, HDF5), ISO 25178-71 `.x3p` (`x3p`), Wyko /
//! Vision `.opd` (`opd`), TrueMap `.tmd` (`tmd`), WSxM `.top`/`.stp` (`wsxm`), Alicona `.al3d`
//! (`al3d`), FRT MicroProf `.frt` (`frt`), Sensofar `.plu` (`plu`), NanoFocus `.nms` (`nms`),
//! Nanosurf `.nid`/`.ezd` (`nid`), Molecular Imaging `.mi` (`mi`), Image Metrology BCR-STM/BCRF
//! (`bcr`), Digital Surf Mountains `.mnt` (`mnt`), Park Systems TIFF (`park`, on the classic TIFF
//! structure of `tiff`), ASCII matrix / Gwyddion ASCII export / CSV
//! (`ascii`) and XYZ on a rectangular lattice (`xyz`). Every reader returns heights and lengths in
//! metres with row 0 = top of the image as the instrument software shows it. NaN and saturated
//! pixels come back as `valid = false` with `z = 0.0`.
//!
//! `ReadOptions::channel` only matters for the multi-channel formats (NanoScope, GWY, IBW layers,
//! SUR objects, MetroPro, datx, OPD, PLU layers and images, AL3D depth and texture, FRT images,
//! NMS height and intensity, NID data sets, MI buffers, MNT surfaces); the single-channel
//! formats ignore it.
use super::{HeightMap, Result, SourceInfo, SurfaceError};
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

mod ascii;
mod gsf;
mod gwy;
mod nanoscope;
// Asylum Igor .ibw, Digital Surf .sur, ISO 25178-71 .sdf (docs/surfaces.md).
mod ibw;
mod sdf;
mod sur;
mod units;
mod xyz;
// Zygo MetroPro .dat, Zygo .datx (HDF5), ISO 25178-71 .x3p (ZIP + XML).
mod datx;
mod metropro;
mod x3p;
// Wyko / Vision .opd (white-light interferometers), TrueMap .tmd.
mod le;
mod opd;
mod tmd;
// WSxM .top/.stp (Nanotec SPM images).
mod wsxm;
// Optical profilers: Alicona .al3d, FRT MicroProf .frt, Sensofar .plu, NanoFocus .nms.
mod al3d;
mod frt;
mod nms;
mod plu;
// Nanosurf .nid, Molecular Imaging .mi, Image Metrology BCR-STM/BCRF (SPM images).
mod bcr;
mod mi;
mod nid;
// Digital Surf Mountains .mnt (compound file; nothing shared with .sur).
mod mnt;
// TIFF structure, and the instrument format built on it: Park Systems.
mod park;
mod tiff;
// The list of readers: detection, dispatch, the docs' table.
pub mod registry;
// 1-D line profiles (stylus profilometers) for the bulge fit, with their own registry.
pub mod profile;

#[cfg(test)]
mod testutil;

pub use ascii::encode_ascii_matrix;
pub use gsf::encode_gsf;
pub use gwy::encode_gwy;
pub use nanoscope::encode_nanoscope;
pub use x3p::encode_x3p;
pub use xyz::encode_xyz;

/// Options a reader may need. Lengths in metres.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReadOptions {
    /// Channel to read (matched case-insensitively against the file's channel names);
    /// `None` = the format's default height channel.
    pub channel: Option<String>,
    /// Lateral size along x / y for formats that do not carry it (plain ASCII without header).
    pub size_x: Option<f64>,
    pub size_y: Option<f64>,
    /// Height unit for formats that do not carry it ("m", "mm", "um", "µm", "nm", "pm", "A").
    pub z_unit: Option<String>,
}

/// The formats `read_height_map` reads, for error messages (from the registry).
pub fn supported_formats() -> String {
    registry::supported()
}

/// How many leading bytes `read_height_map` shows `detect_format`: enough for several lines of
/// a wide ASCII matrix (a 256-column row is ~5 kB).
const SNIFF_BYTES: usize = 64 * 1024;

/// Short format id of a file's content, from its first bytes; `None` if not recognised. The
/// readers' sniffers are asked in the registry's order ([`registry::READERS`]): magic bytes,
/// then Igor's plausibility check (Igor waves have no magic; the reader then rejects variants
/// it does not support with a clear error), then text. Text is "xyz" if it has an XYZ unit
/// header (`# xy_unit:`, `# z_unit:`, `# Units:`) or its data lines have three columns whose
/// first two look like lattice coordinates (the first two lines share x or y), else "ascii".
pub fn detect_format(head: &[u8]) -> Option<&'static str> {
    registry::detect(head).map(|r| r.id)
}

fn sniff_text(head: &[u8]) -> Option<&'static str> {
    let is_binary = |b: &u8| *b == 0 || (*b < 0x20 && !matches!(*b, b'\t' | b'\n' | b'\r' | 0x0c));
    if head.is_empty() || head.iter().any(is_binary) {
        return None;
    }
    let text = units::decode_text(head);
    let last_line_complete = head.ends_with(b"\n");
    let lines: Vec<&str> = text.lines().collect();
    // Values of the first few data lines; the last line may be cut by the head limit.
    let mut rows: Vec<Vec<f64>> = Vec::new();
    let mut partial_row_len = None;
    let mut ascii_header = false;
    for (k, line) in lines.iter().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        if let Some(comment) = line.strip_prefix('#') {
            let key = comment
                .split(':')
                .next()
                .unwrap_or("")
                .trim()
                .to_lowercase();
            if matches!(key.as_str(), "xy_unit" | "z_unit" | "units") {
                return Some("xyz");
            }
            // XYZ keys win over ASCII ones (an XYZ file may also carry `# Channel:`).
            ascii_header |= ascii::is_header_key(&key);
            continue;
        }
        let toks: Vec<&str> = units::tokens(line).collect();
        if k + 1 == lines.len() && !last_line_complete {
            // Possibly cut mid-number: judge all but the last token.
            let whole = &toks[..toks.len().saturating_sub(1)];
            if whole.iter().all(|t| units::parse_value(t).is_some()) && !toks.is_empty() {
                partial_row_len = Some(toks.len());
            } else if rows.is_empty() {
                return None;
            }
            break;
        }
        let values: Option<Vec<f64>> = toks.iter().map(|t| units::parse_value(t)).collect();
        match values {
            Some(values) => rows.push(values),
            // A non-numeric first data line: not a height-map text file. Later bad lines are
            // left to the reader, which reports them with their line number.
            None if rows.is_empty() => return None,
            None => break,
        }
        if rows.len() >= 2 {
            break;
        }
    }
    if ascii_header {
        return (!rows.is_empty() || partial_row_len.is_some()).then_some("ascii");
    }
    match rows.as_slice() {
        [] => partial_row_len.map(|n| if n == 3 { "xyz" } else { "ascii" }),
        [first] => Some(if first.len() == 3 { "xyz" } else { "ascii" }),
        [first, second, ..] => {
            let lattice_like = first.len() == 3
                && second.len() == 3
                && (first[0] == second[0] || first[1] == second[1]);
            Some(if lattice_like { "xyz" } else { "ascii" })
        }
    }
}

/// Read one height map in SI units from any supported format.
pub fn read_height_map(path: &Path, opts: &ReadOptions) -> Result<HeightMap> {
    let bytes = std::fs::read(path).map_err(|source| SurfaceError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    read_height_map_bytes(path, &bytes, opts)
}

/// [`read_height_map`] of a file already in memory (`path` names it in errors).
pub fn read_height_map_bytes(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<HeightMap> {
    let head = &bytes[..bytes.len().min(SNIFF_BYTES)];
    let raw = match registry::detect(head) {
        Some(reader) => (reader.read)(path, bytes, opts)?,
        None => {
            let what = if bytes.is_empty() {
                "empty file"
            } else {
                "unrecognised content"
            };
            return Err(unsupported(
                path,
                format!("{what}; supported: {}", supported_formats()),
            ));
        }
    };
    finish(path, raw)
}

/// What a format reader produces: heights in metres with NaN marking invalid pixels.
pub(crate) struct RawMap {
    pub z: Array2<f64>,
    pub dx: f64,
    pub dy: f64,
    pub x0: f64,
    pub y0: f64,
    pub channel: String,
    pub format: &'static str,
    pub header: BTreeMap<String, String>,
}

/// Checks what every reader must guarantee and turns NaNs into the validity mask.
pub(crate) fn finish(path: &Path, raw: RawMap) -> Result<HeightMap> {
    let (ny, nx) = raw.z.dim();
    if nx < 3 || ny < 3 {
        return Err(SurfaceError::InvalidData(format!(
            "{}: height map is {nx}×{ny} pixels; at least 3×3 are needed",
            path.display()
        )));
    }
    for (name, value) in [("dx", raw.dx), ("dy", raw.dy)] {
        if !(value.is_finite() && value > 0.0) {
            return Err(format_error(
                path,
                format!("pixel spacing {name} = {value} m is not a positive length"),
            ));
        }
    }
    for (name, value) in [("x offset", raw.x0), ("y offset", raw.y0)] {
        if !value.is_finite() {
            return Err(format_error(path, format!("{name} is not finite")));
        }
    }
    let mut z = raw.z;
    let valid = z.mapv(f64::is_finite);
    let n_invalid = valid.iter().filter(|ok| !**ok).count();
    if n_invalid == valid.len() {
        return Err(SurfaceError::InvalidData(format!(
            "{}: all {nx}×{ny} pixels are invalid (NaN or saturated)",
            path.display()
        )));
    }
    z.mapv_inplace(|v| if v.is_finite() { v } else { 0.0 });
    // Every map lists the file's channels (`hdi surface FILE --info`): a single-channel
    // format's reader leaves it to here.
    let mut header = raw.header;
    header
        .entry("channels".into())
        .or_insert_with(|| raw.channel.clone());
    Ok(HeightMap {
        z,
        dx: raw.dx,
        dy: raw.dy,
        x0: raw.x0,
        y0: raw.y0,
        channel: raw.channel,
        valid: (n_invalid > 0).then_some(valid),
        periodic: false,
        source: SourceInfo {
            format: raw.format.to_string(),
            header,
        },
        history: vec![],
    })
}

pub(crate) fn format_error(path: &Path, reason: impl Into<String>) -> SurfaceError {
    SurfaceError::Format {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

pub(crate) fn unsupported(path: &Path, reason: impl Into<String>) -> SurfaceError {
    SurfaceError::Unsupported {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Index of the requested channel among channels known by several names each (e.g. internal
/// `ZSensor` and display `Height Sensor`): an exact case-insensitive match of any name wins,
/// else the single channel one of whose names contains the request.
pub(crate) fn find_channel(requested: &str, names: &[Vec<String>]) -> Option<usize> {
    let wanted = requested.trim().to_lowercase();
    let exact = names
        .iter()
        .position(|ns| ns.iter().any(|n| n.to_lowercase() == wanted));
    exact.or_else(|| {
        let partial: Vec<usize> = (0..names.len())
            .filter(|&k| names[k].iter().any(|n| n.to_lowercase().contains(&wanted)))
            .collect();
        (partial.len() == 1).then(|| partial[0])
    })
}

/// Heights of a map in metres with invalid pixels as NaN, for the writers.
pub(crate) fn heights_with_nan(map: &HeightMap) -> Array2<f64> {
    match &map.valid {
        None => map.z.clone(),
        Some(valid) => {
            let mut z = map.z.clone();
            ndarray::Zip::from(&mut z)
                .and(valid)
                .for_each(|v, &ok| *v = if ok { *v } else { f64::NAN });
            z
        }
    }
}

#[cfg(test)]
mod tests {
    use super::testutil::*;
    use super::*;

    #[test]
    fn detects_by_content() {
        assert_eq!(detect_format(b"GWYPGwyContainer\0"), Some("gwy"));
        assert_eq!(
            detect_format(b"\\*File list\r\n\\Version: 0x09200000"),
            Some("nanoscope")
        );
        assert_eq!(
            detect_format(b"Gwyddion Simple Field 1.0\nXRes = 3\n"),
            Some("gsf")
        );
        assert_eq!(detect_format(b"DIGITAL SURF\0\0\x01\0"), Some("sur"));
        assert_eq!(detect_format(b"DSCOMPRESSED\0\0\x01\0"), Some("sur"));
        assert_eq!(detect_format(b"aISO-1.0\nManufacID = x\n"), Some("sdf"));
        assert_eq!(detect_format(b"bBCR-1.0ISOTC213  "), Some("sdf"));
        // Igor v5, little-endian: version 5, wfmSize ≥ 320, float32 type, nDim[0] = 10.
        let mut ibw = vec![0u8; 384];
        ibw[0] = 5;
        ibw[4..8].copy_from_slice(&720i32.to_le_bytes());
        ibw[64 + 16] = 2;
        ibw[64 + 68..64 + 72].copy_from_slice(&10i32.to_le_bytes());
        assert_eq!(detect_format(&ibw), Some("ibw"));
        ibw[64 + 16] = 3; // not a number type
        assert_eq!(detect_format(&ibw), None);
        assert_eq!(detect_format(b"# Width: 1 um\n1 2 3\n"), Some("ascii"));
        assert_eq!(detect_format(b"1 2 3 4\n5 6 7 8\n"), Some("ascii"));
        assert_eq!(detect_format(b"0 0 1e-9\n1e-9 0 2e-9\n"), Some("xyz"));
        assert_eq!(detect_format(b"# xy_unit: um\n0 0 1\n"), Some("xyz"));
        assert_eq!(detect_format(b"1.5 2.5 3.5\n4.5 5.5 6.5\n"), Some("ascii"));
        // A long row cut by the head limit in the middle of a number.
        assert_eq!(detect_format(b"1e-9 2e-9 3e-9 4e-"), Some("ascii"));
        assert_eq!(detect_format(b"\x88\x1b\x03\x6f\x00\x01"), Some("metropro"));
        assert_eq!(detect_format(b"\x88\x1b\x03\x71\x00\x03"), Some("metropro"));
        assert_eq!(detect_format(b"PK\x03\x04\x14\x00"), Some("x3p"));
        assert_eq!(detect_format(b"\x89HDF\r\n\x1a\n\x00\x00"), Some("datx"));
        assert_eq!(detect_format(b"\x89HDF\r\n"), None);
        assert_eq!(detect_format(b"\x88\x1b\x03\x72\x00\x03"), None);
        assert_eq!(detect_format(b""), None);
        assert_eq!(detect_format(b"\x7fELF\x02\x01\x01\0\0"), None);
        assert_eq!(detect_format(b"hello world\n"), None);
    }

    #[test]
    fn unknown_empty_and_missing_files() {
        let dir = tempfile::tempdir().unwrap();
        for (name, bytes) in [
            ("empty.txt", &b""[..]),
            ("junk.gwy", &b"\x89PNG\r\n\x1a\n\0\0"[..]),
        ] {
            let path = dir.path().join(name);
            std::fs::write(&path, bytes).unwrap();
            let err = read_height_map(&path, &ReadOptions::default()).unwrap_err();
            assert!(matches!(err, SurfaceError::Unsupported { .. }), "{err}");
            let msg = err.to_string();
            assert!(msg.contains(name) && msg.contains("NanoScope"), "{msg}");
        }
        let missing = dir.path().join("missing.spm");
        let err = read_height_map(&missing, &ReadOptions::default()).unwrap_err();
        assert!(matches!(err, SurfaceError::Io { .. }), "{err}");
    }

    #[test]
    fn tiny_and_all_invalid_maps_are_refused() {
        let (_dir, path) = write_temp(
            "tiny.txt",
            b"# Width: 1 um\n# Height: 1 um\n# Value units: m\n1 2\n3 4\n",
        );
        let err = read_height_map(&path, &ReadOptions::default()).unwrap_err();
        assert!(err.to_string().contains("at least 3×3"), "{err}");
        let text = b"# Width: 1 um\n# Height: 1 um\n# Value units: m\nNaN NaN NaN\nnan nan nan\nNaN NaN NaN\n";
        let (_dir, path) = write_temp("nan.txt", text);
        let err = read_height_map(&path, &ReadOptions::default()).unwrap_err();
        assert!(
            err.to_string().contains("all 3×3 pixels are invalid"),
            "{err}"
        );
    }

    #[test]
    fn channel_matching() {
        let names = vec![
            vec!["Height".to_string(), "Height".to_string()],
            vec!["ZSensor".to_string(), "Height Sensor".to_string()],
        ];
        assert_eq!(find_channel("height", &names), Some(0));
        assert_eq!(find_channel("zsensor", &names), Some(1));
        assert_eq!(find_channel("sensor", &names), Some(1));
        assert_eq!(find_channel("eig", &names), None);
        assert_eq!(find_channel("phase", &names), None);
    }
}
