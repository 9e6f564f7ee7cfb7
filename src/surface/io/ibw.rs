//! Igor binary wave (`.ibw`) as Asylum Research AFMs write it (Igor Technical Note PTN003).
//!
//! Version 5 only: a 64-byte `BinHeader5` (version, checksum, section sizes), a 320-byte
//! `WaveHeader5` (type, dimensions `nDim[4]`, spacing `sfA[4]`, units), the data, then the
//! formula, the note, the extended units and the dimension labels, in that order. Both byte
//! orders (the version field, 5, tells which). Versions 1–3 hold 1-D waves only, which cannot
//! be height maps; they are refused.
//!
//! Igor stores column-major: dim 0 (x, the fast-scan direction) varies fastest, then dim 1
//! (y, lines), then dim 2 (layers = channels). Asylum's software shows images with y growing
//! upwards (line 0 at the bottom), so line `ny − 1 − j` becomes hdi row `j` (row 0 = top).
use super::units::{decode_text, length_factor};
use super::{find_channel, format_error, unsupported, RawMap, ReadOptions};
use crate::surface::{Result, SurfaceError};
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

const BIN_HEADER: usize = 64;
const WAVE_HEADER: usize = 320;
/// Igor dimension labels are 31 characters plus a NUL.
const LABEL_BYTES: usize = 32;

/// Number type codes of `WaveHeader5::type` (PTN003): float32, float64, int8, int16, int32,
/// each integer optionally with the unsigned flag 0x40. Complex (0x01) and text (0) are not
/// height data.
fn element_size(code: u16) -> Option<usize> {
    match code & !0x40 {
        0x02 if code & 0x40 == 0 => Some(4),
        0x04 if code & 0x40 == 0 => Some(8),
        0x08 => Some(1),
        0x10 => Some(2),
        0x20 => Some(4),
        _ => None,
    }
}

/// Byte order of an Igor file from its first two bytes (the version), if it looks like one.
fn byte_order(head: &[u8]) -> Option<(bool, u16)> {
    let bytes = [*head.first()?, *head.get(1)?];
    let le = u16::from_le_bytes(bytes);
    let be = u16::from_be_bytes(bytes);
    if matches!(le, 1 | 2 | 3 | 5) {
        Some((true, le))
    } else if matches!(be, 1 | 2 | 3 | 5) {
        Some((false, be))
    } else {
        None
    }
}

/// Whether `head` starts like an Igor binary wave: a known version and, where the header is
/// long enough to check, a known number type and positive first dimension (v5) — a two-byte
/// version alone would claim too many unrelated binary files.
pub(crate) fn looks_like(head: &[u8]) -> bool {
    let Some((le, version)) = byte_order(head) else {
        return false;
    };
    let r = Bytes { b: head, le };
    match version {
        5 => {
            let (Some(wfm), Some(code), Some(n0)) =
                (r.i32(4), r.u16(BIN_HEADER + 16), r.i32(BIN_HEADER + 68))
            else {
                return false;
            };
            wfm >= WAVE_HEADER as i32 && element_size(code).is_some() && n0 > 0
        }
        // v1: 8-byte BinHeader1, v2: 16-byte BinHeader2, v3: 20-byte BinHeader3; the wave
        // header starts with the type.
        1..=3 => {
            let at = [0, 8, 16, 20][version as usize];
            r.u16(at).is_some_and(|code| element_size(code).is_some())
        }
        _ => false,
    }
}

/// Little helper reading fixed-size fields in the file's byte order; `None` past the end.
struct Bytes<'a> {
    b: &'a [u8],
    le: bool,
}

impl Bytes<'_> {
    fn take<const N: usize>(&self, at: usize) -> Option<[u8; N]> {
        self.b.get(at..at.checked_add(N)?)?.try_into().ok()
    }
    fn u16(&self, at: usize) -> Option<u16> {
        let b = self.take::<2>(at)?;
        Some(if self.le {
            u16::from_le_bytes(b)
        } else {
            u16::from_be_bytes(b)
        })
    }
    fn i32(&self, at: usize) -> Option<i32> {
        let b = self.take::<4>(at)?;
        Some(if self.le {
            i32::from_le_bytes(b)
        } else {
            i32::from_be_bytes(b)
        })
    }
    fn f64(&self, at: usize) -> Option<f64> {
        let b = self.take::<8>(at)?;
        Some(if self.le {
            f64::from_le_bytes(b)
        } else {
            f64::from_be_bytes(b)
        })
    }
    /// One element of number type `code` at `at`, as f64.
    fn value(&self, code: u16, at: usize) -> Option<f64> {
        let unsigned = code & 0x40 != 0;
        macro_rules! num {
            ($t:ty, $n:literal) => {{
                let b = self.take::<$n>(at)?;
                (if self.le {
                    <$t>::from_le_bytes(b)
                } else {
                    <$t>::from_be_bytes(b)
                }) as f64
            }};
        }
        Some(match (code & !0x40, unsigned) {
            (0x02, _) => num!(f32, 4),
            (0x04, _) => num!(f64, 8),
            (0x08, false) => num!(i8, 1),
            (0x08, true) => num!(u8, 1),
            (0x10, false) => num!(i16, 2),
            (0x10, true) => num!(u16, 2),
            (0x20, false) => num!(i32, 4),
            (0x20, true) => num!(u32, 4),
            _ => return None,
        })
    }
}

/// A NUL-terminated string of a fixed-size field.
fn c_string(bytes: &[u8]) -> String {
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    decode_text(&bytes[..end]).trim().to_string()
}

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let Some((le, version)) = byte_order(bytes) else {
        return Err(format_error(path, "not an Igor binary wave (bad version)"));
    };
    if version != 5 {
        return Err(unsupported(
            path,
            format!(
                "Igor binary wave version {version} holds only 1-D waves; height maps need \
                 version 5"
            ),
        ));
    }
    let r = Bytes { b: bytes, le };
    if bytes.len() < BIN_HEADER + WAVE_HEADER {
        return Err(truncated(path, bytes, "wave header"));
    }
    let sizes = read_section_sizes(path, &r)?;
    let mut wave = read_wave_header(path, &r, sizes.wfm)?;
    let (note, layer_labels) = read_trailing_sections(path, bytes, &sizes, &mut wave)?;
    let names = layer_names(&layer_labels, wave.n_layers);

    let mut header = note_header(&note);
    header.insert("igor_version".into(), version.to_string());
    header.insert("channels".into(), names.join(", "));
    header.insert("wave_name".into(), wave.name.clone());

    let layer = choose_layer(path, opts, &names)?;
    let (nx, ny) = (wave.nx, wave.ny);
    let dx = lateral_spacing(path, &wave, 0, opts.size_x)?;
    let dy = lateral_spacing(path, &wave, 1, opts.size_y)?;
    let offset = |d: usize| length_factor(&wave.dim_units[d]).map_or(0.0, |f| wave.sf_b[d] * f);
    let z_unit = if wave.data_units.is_empty() {
        opts.z_unit
            .clone()
            .ok_or_else(|| format_error(path, "Igor wave has no data unit; give z_unit"))?
    } else {
        wave.data_units.clone()
    };
    let z_factor = length_factor(&z_unit).ok_or_else(|| {
        format_error(
            path,
            format!(
                "Igor data unit `{z_unit}` of channel `{}` is not a length",
                names[layer]
            ),
        )
    })?;
    header.insert("z_unit".into(), z_unit);

    let elem = wave.elem;
    let data_start = BIN_HEADER + WAVE_HEADER;
    let layer_start = data_start + layer * nx * ny * elem;
    debug_assert!(layer_start + nx * ny * elem <= data_start + wave.data_bytes);
    let z = Array2::from_shape_fn((ny, nx), |(row, col)| {
        let j = ny - 1 - row;
        r.value(wave.code, layer_start + (j * nx + col) * elem)
            .map_or(f64::NAN, |v| v * z_factor)
    });
    Ok(RawMap {
        z,
        dx,
        dy,
        x0: offset(0),
        y0: offset(1),
        channel: names[layer].clone(),
        format: "ibw",
        header,
    })
}

fn truncated(path: &Path, bytes: &[u8], what: &str) -> SurfaceError {
    format_error(
        path,
        format!(
            "truncated Igor binary wave: {what} missing ({} bytes)",
            bytes.len()
        ),
    )
}

/// Section sizes of `BinHeader5`, in bytes.
struct SectionSizes {
    /// The wave: header plus data.
    wfm: usize,
    formula: usize,
    note: usize,
    data_eunits: usize,
    dim_eunits: [usize; 4],
    dim_labels: [usize; 4],
}

fn read_section_sizes(path: &Path, r: &Bytes<'_>) -> Result<SectionSizes> {
    let size = |at: usize, what: &str| -> Result<usize> {
        let v = r.i32(at).ok_or_else(|| truncated(path, r.b, what))?;
        usize::try_from(v)
            .map_err(|_| format_error(path, format!("Igor {what} size {v} is negative")))
    };
    let wfm = size(4, "wave")?;
    let formula = size(8, "formula")?;
    let note = size(12, "note")?;
    let data_eunits = size(16, "data units")?;
    let mut dim_eunits = [0usize; 4];
    let mut dim_labels = [0usize; 4];
    for d in 0..4 {
        dim_eunits[d] = size(20 + 4 * d, "dimension units")?;
        dim_labels[d] = size(36 + 4 * d, "dimension labels")?;
    }
    Ok(SectionSizes {
        wfm,
        formula,
        note,
        data_eunits,
        dim_eunits,
        dim_labels,
    })
}

/// The fields of `WaveHeader5` the reader uses; the units may be replaced by the extended
/// units of the trailing sections.
struct WaveHeader {
    code: u16,
    elem: usize,
    nx: usize,
    ny: usize,
    n_layers: usize,
    data_bytes: usize,
    sf_a: [f64; 2],
    sf_b: [f64; 2],
    data_units: String,
    dim_units: Vec<String>,
    name: String,
}

fn read_wave_header(path: &Path, r: &Bytes<'_>, wfm_size: usize) -> Result<WaveHeader> {
    let bytes = r.b;
    let truncated = |what: &str| truncated(path, bytes, what);
    let w = BIN_HEADER;
    let code = r.u16(w + 16).ok_or_else(|| truncated("wave type"))?;
    let elem = element_size(code).ok_or_else(|| {
        unsupported(
            path,
            format!("Igor wave number type 0x{code:02x} (text or complex) is not height data"),
        )
    })?;
    let mut n_dim = [0usize; 4];
    for (d, n) in n_dim.iter_mut().enumerate() {
        let v = r
            .i32(w + 68 + 4 * d)
            .ok_or_else(|| truncated("dimensions"))?;
        *n = usize::try_from(v)
            .map_err(|_| format_error(path, format!("Igor nDim[{d}] = {v} is negative")))?;
    }
    let [nx, ny, n_layers, n_chunks] = n_dim;
    if nx == 0 || ny == 0 {
        return Err(format_error(
            path,
            format!("Igor wave is {nx}×{ny}: a height map needs 2 dimensions"),
        ));
    }
    if n_chunks > 1 {
        return Err(unsupported(path, "4-D Igor waves are not height maps"));
    }
    let n_layers = n_layers.max(1);
    // Every size is checked against the file before anything is allocated from it.
    let data_start = BIN_HEADER + WAVE_HEADER;
    let data_bytes = nx
        .checked_mul(ny)
        .and_then(|n| n.checked_mul(n_layers))
        .and_then(|n| n.checked_mul(elem))
        .filter(|&n| n <= bytes.len() - data_start && n <= wfm_size)
        .ok_or_else(|| {
            format_error(
                path,
                format!(
                    "truncated or corrupt Igor binary wave: {nx}×{ny}×{n_layers} values of \
                     {elem} bytes do not fit in the {} bytes after the header",
                    bytes.len() - data_start
                ),
            )
        })?;

    let mut sf_a = [0f64; 2];
    for (d, v) in sf_a.iter_mut().enumerate() {
        *v = r.f64(w + 84 + 8 * d).ok_or_else(|| truncated("sfA"))?;
    }
    let mut sf_b = [0f64; 2];
    for (d, v) in sf_b.iter_mut().enumerate() {
        *v = r.f64(w + 116 + 8 * d).ok_or_else(|| truncated("sfB"))?;
    }
    Ok(WaveHeader {
        code,
        elem,
        nx,
        ny,
        n_layers,
        data_bytes,
        sf_a,
        sf_b,
        data_units: c_string(&bytes[w + 148..w + 152]),
        dim_units: (0..4)
            .map(|d| c_string(&bytes[w + 152 + 4 * d..w + 156 + 4 * d]))
            .collect(),
        name: c_string(&bytes[w + 28..w + 60]),
    })
}

/// Reads the sections after the data, in file order (PTN003): the wave (header + data,
/// wfmSize bytes), formula, note, extended data units, extended dimension units, dimension
/// labels. Extended units replace the wave header's; returns the note and the labels of
/// dimension 2 (one per layer).
fn read_trailing_sections(
    path: &Path,
    bytes: &[u8],
    sizes: &SectionSizes,
    wave: &mut WaveHeader,
) -> Result<(String, Vec<String>)> {
    let mut at = BIN_HEADER
        .checked_add(sizes.wfm)
        .ok_or_else(|| truncated(path, bytes, "wave"))?;
    let mut section = |len: usize, what: &str| -> Result<&[u8]> {
        let end = at
            .checked_add(len)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| truncated(path, bytes, what))?;
        let s = &bytes[at..end];
        at = end;
        Ok(s)
    };
    section(sizes.formula, "formula")?;
    let note = decode_text(section(sizes.note, "note")?);
    let eunits = section(sizes.data_eunits, "extended data units")?;
    if !eunits.is_empty() {
        wave.data_units = c_string(eunits);
    }
    for (d, unit) in wave.dim_units.iter_mut().enumerate() {
        let s = section(sizes.dim_eunits[d], "extended dimension units")?;
        if !s.is_empty() {
            *unit = c_string(s);
        }
    }
    // Labels of dimension 2: the first is the dimension's own label, then one per layer.
    let mut layer_labels = Vec::new();
    for (d, &len) in sizes.dim_labels.iter().enumerate() {
        let s = section(len, "dimension labels")?;
        if d == 2 {
            layer_labels = s.chunks(LABEL_BYTES).skip(1).map(c_string).collect();
        }
    }
    Ok((note, layer_labels))
}

/// One name per layer: its label, or `layer k` where it has none.
fn layer_names(layer_labels: &[String], n_layers: usize) -> Vec<String> {
    (0..n_layers)
        .map(|k| {
            layer_labels
                .get(k)
                .filter(|n| !n.is_empty())
                .cloned()
                .unwrap_or_else(|| format!("layer {k}"))
        })
        .collect()
}

/// Asylum's note: `Key: Value` lines separated by CR.
fn note_header(note: &str) -> BTreeMap<String, String> {
    let mut header = BTreeMap::new();
    for line in note.split(['\r', '\n']) {
        if let Some((key, value)) = line.split_once(':') {
            let key = key.trim();
            if !key.is_empty() {
                header.insert(key.to_string(), value.trim().to_string());
            }
        }
    }
    header
}

fn choose_layer(path: &Path, opts: &ReadOptions, names: &[String]) -> Result<usize> {
    Ok(match &opts.channel {
        Some(wanted) => {
            let options: Vec<Vec<String>> = names.iter().map(|n| vec![n.clone()]).collect();
            find_channel(wanted, &options).ok_or_else(|| {
                format_error(
                    path,
                    format!("no channel `{wanted}`; channels: {}", names.join(", ")),
                )
            })?
        }
        // Asylum's height channels: HeightTrace/HeightRetrace; else the first layer.
        None => names
            .iter()
            .position(|n| n.to_lowercase().starts_with("height"))
            .unwrap_or(0),
    })
}

/// Spacing along dimension `d` (0 = x, 1 = y) in metres: sfA in the dimension's unit, or the
/// user's size over the point count when the wave has no unit.
fn lateral_spacing(path: &Path, wave: &WaveHeader, d: usize, given: Option<f64>) -> Result<f64> {
    let n = [wave.nx, wave.ny][d];
    let unit = &wave.dim_units[d];
    if unit.is_empty() {
        let axis = ["x", "y"][d];
        return given.map(|size| size / n as f64).ok_or_else(|| {
            format_error(
                path,
                format!("Igor wave has no {axis} unit; give size_{axis}"),
            )
        });
    }
    let factor = length_factor(unit).ok_or_else(|| {
        format_error(
            path,
            format!("Igor dimension {d} unit `{unit}` is not a length"),
        )
    })?;
    Ok(wave.sf_a[d].abs() * factor)
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};
    use crate::surface::SurfaceError;
    use std::path::PathBuf;

    fn sample(name: &str) -> PathBuf {
        surface_sample(name)
    }

    fn with_channel(channel: &str) -> ReadOptions {
        ReadOptions {
            channel: Some(channel.into()),
            ..Default::default()
        }
    }

    fn sigma(z: &ndarray::Array2<f64>) -> f64 {
        let mean = z.mean().unwrap();
        (z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / z.len() as f64).sqrt()
    }

    /// SurfaceTopography's `test_ibw_kpfm_file`: 20 µm × 20 µm for every channel; heights
    /// against the independent `igor2` reader (make_ibw_sdf_fixtures.py prints them).
    #[test]
    fn asylum_kpfm_sample() {
        let path = sample("spot_1-1000nm.ibw");
        let map = read_height_map(&path, &ReadOptions::default()).unwrap();
        assert_eq!(map.source.format, "ibw");
        assert_eq!(map.channel, "HeightTrace");
        assert_eq!(map.z.dim(), (256, 256));
        // Asylum's sfA = ScanSize / (points − 1) (note: ScanSize 2e-05); SurfaceTopography's
        // physical size is points · sfA = 20.078 µm, asserted there as 20 µm ± 0.01 m.
        assert!(close(map.dx, 20e-6 / 255.0, 1e-6) && close(map.dy, 20e-6 / 255.0, 1e-6));
        let (w, h) = map.size();
        assert!(
            close(w, 256.0 * 20e-6 / 255.0, 1e-6) && close(h, w, 1e-12),
            "{w} × {h}"
        );
        assert!(close(sigma(&map.z), 8.94548149125641e-08, 1e-6));
        assert_eq!(map.source.header["ScanSize"], "2e-05");
        assert_eq!(map.source.header["ImagingMode"], "AC Mode");

        let map = read_height_map(&path, &with_channel("heightretrace")).unwrap();
        assert_eq!(map.channel, "HeightRetrace");
        assert!(close(sigma(&map.z), 1.10284572132635e-07, 1e-6));
        // Row 0 = Igor line 255 (top), column = x.
        assert!(close(map.z[[0, 0]], -3.09850463509065e-07, 1e-6));
        assert!(close(map.z[[255, 0]], -2.91554385967174e-07, 1e-6));
        assert!(close(map.z[[255 - 20, 10]], -2.96780768849203e-07, 1e-6));

        // An unknown channel name is an error listing the file's channels.
        let err = read_height_map(&path, &with_channel("Deflection")).unwrap_err();
        assert!(err.to_string().contains("NapPotentialRetrace"), "{err}");
    }

    /// SurfaceTopography's `test_ibw_file_with_one_channel_without_name`: one unnamed layer,
    /// 10 × 10, no units (so hdi needs size and z unit).
    #[test]
    fn unnamed_channel_without_units() {
        let path = sample("10x10-one_channel_without_name.ibw");
        let err = read_height_map(&path, &ReadOptions::default()).unwrap_err();
        assert!(err.to_string().contains("size_x"), "{err}");
        let opts = ReadOptions {
            size_x: Some(10e-6),
            size_y: Some(5e-6),
            z_unit: Some("nm".into()),
            ..Default::default()
        };
        let map = read_height_map(&path, &opts).unwrap();
        assert_eq!(map.z.dim(), (10, 10));
        assert_eq!(map.channel, "layer 0");
        assert!(close(map.dx, 1e-6, 1e-12) && close(map.dy, 0.5e-6, 1e-12));
        assert!(close(sigma(&map.z), 4.80049350063276e-01 * 1e-9, 1e-6));
    }

    /// A big-endian int16 wave written by an independent struct-based writer
    /// (make_ibw_sdf_fixtures.py, checked with igor2): 8 × 6 × 3 layers, data unit nm.
    #[test]
    fn big_endian_int16_layers() {
        let path = sample("igor_be_int16_3layers.ibw");
        let map = read_height_map(&path, &ReadOptions::default()).unwrap();
        assert_eq!(map.channel, "HeightRetrace", "Height* is the default");
        assert_eq!(map.z.dim(), (6, 8));
        assert!(close(map.dx, 2e-9, 1e-12) && close(map.dy, 3e-9, 1e-12));
        assert!(close(sigma(&map.z), 1.60955491820634e-06, 1e-12));
        assert!(close(map.z[[0, 0]], -7.28e-07, 1e-12));
        assert!(close(map.z[[5, 7]], 5.51e-07, 1e-12));
        let map = read_height_map(&path, &with_channel("zsensor")).unwrap();
        assert_eq!(map.channel, "ZSensorRetrace");
        assert!(close(sigma(&map.z), 1.65527817190613e-06, 1e-12));
        assert!(close(map.z[[0, 0]], 1.682e-06, 1e-12));
        assert_eq!(map.source.header["ImagingMode"], "AC Mode");
    }

    #[test]
    fn truncated_and_hostile_files_are_errors() {
        let bytes = std::fs::read(sample("igor_be_int16_3layers.ibw")).unwrap();
        for cut in [10, 100, 383, 400, 384 + 8 * 6 * 3 * 2 - 1] {
            let err = read_bytes("t.ibw", &bytes[..cut]).unwrap_err();
            let msg = err.to_string();
            assert!(msg.contains("t.ibw"), "{msg}");
            assert!(
                matches!(
                    err,
                    SurfaceError::Format { .. } | SurfaceError::Unsupported { .. }
                ),
                "{msg}"
            );
        }
        // Huge dimensions: an error from the size check, no allocation.
        let mut huge = bytes.clone();
        huge[64 + 68..64 + 72].copy_from_slice(&i32::MAX.to_be_bytes());
        huge[64 + 72..64 + 76].copy_from_slice(&i32::MAX.to_be_bytes());
        let msg = read_bytes("h.ibw", &huge).unwrap_err().to_string();
        assert!(msg.contains("do not fit"), "{msg}");
        let mut negative = bytes.clone();
        negative[12..16].copy_from_slice(&(-5i32).to_be_bytes());
        assert!(read_bytes("n.ibw", &negative).is_err());
        // Corrupt copies of this sample: registry.rs,
        // `every_sample_survives_truncation_and_flipped_bytes`; the small one here.
        let small = std::fs::read(sample("10x10-one_channel_without_name.ibw")).unwrap();
        assert!(fuzz_reader("g.ibw", &small) > 0);
    }
}
