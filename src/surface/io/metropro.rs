//! Zygo MetroPro `.dat` (docs/surfaces.md): a big-endian binary header (format 1/2 = 834 bytes,
//! format 3 = 4096 bytes, recognised by its magic number), then the intensity array
//! (`ac_n_buckets` × `ac_org_height` × `ac_org_width` u16) and the phase array
//! (`cn_org_height` × `cn_org_width` i32), rows top first.
//!
//! Field offsets are those of the MetroPro Reference Guide's header table (also used by
//! Gwyddion's `metropro.c` and SurfaceTopography's `IO/MetroPro.py`). Heights:
//! z = phase · intf_scale_factor · wavelength_in · obliquity_factor / R with R = 4096, 32768 or
//! 131072 for `phase_res` 0, 1, 2, negated when `sign` is set; phase values ≥ 2147483640 mark
//! invalid pixels. The pixel spacing is the header's camera resolution (`lateral_res`, metres),
//! the same in x and y.
use super::{find_channel, format_error, unsupported, RawMap, ReadOptions};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

pub(crate) const MAGICS: [[u8; 4]; 3] = [
    [0x88, 0x1b, 0x03, 0x6f],
    [0x88, 0x1b, 0x03, 0x70],
    [0x88, 0x1b, 0x03, 0x71],
];
/// Header length of formats 1 and 2 (format 3 is longer; its `header_size` says 4096).
const MIN_HEADER: usize = 834;
/// Phase values from here up mark pixels without data (MetroPro Reference Guide, "phase data").
const INVALID_PHASE: i32 = 2_147_483_640;

fn be_u16(b: &[u8], at: usize) -> u16 {
    u16::from_be_bytes([b[at], b[at + 1]])
}
fn be_i16(b: &[u8], at: usize) -> i16 {
    i16::from_be_bytes([b[at], b[at + 1]])
}
fn be_u32(b: &[u8], at: usize) -> u32 {
    u32::from_be_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}
fn be_f32(b: &[u8], at: usize) -> f64 {
    f32::from_be_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]) as f64
}

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let fail = |reason: String| format_error(path, reason);
    if bytes.len() < MIN_HEADER {
        return Err(fail(format!(
            "truncated MetroPro file: {} bytes, the header alone has {MIN_HEADER}",
            bytes.len()
        )));
    }
    let format = MAGICS
        .iter()
        .position(|m| bytes.starts_with(m))
        .ok_or_else(|| fail("no MetroPro magic number".into()))?
        + 1;
    let header_format = be_u16(bytes, 4);
    if usize::from(header_format) != format {
        return Err(fail(format!(
            "MetroPro header_format {header_format} does not match the magic of format {format}"
        )));
    }
    let header_size = be_u32(bytes, 6) as usize;
    if header_size < MIN_HEADER || header_size > bytes.len() {
        return Err(fail(format!(
            "MetroPro header_size {header_size} is outside {MIN_HEADER}..={} (the file length)",
            bytes.len()
        )));
    }
    let (ac_w, ac_h, buckets) = (
        usize::from(be_u16(bytes, 52)),
        usize::from(be_u16(bytes, 54)),
        usize::from(be_u16(bytes, 56)),
    );
    let (cn_w, cn_h) = (
        usize::from(be_u16(bytes, 68)),
        usize::from(be_u16(bytes, 70)),
    );
    let scale = be_f32(bytes, 164);
    let wavelength = be_f32(bytes, 168);
    let obliquity = be_f32(bytes, 176);
    let lateral = be_f32(bytes, 184);
    let phase_res = be_i16(bytes, 218);
    let sign = be_i16(bytes, 232);

    // All sizes are below 2^16 per axis: the products cannot overflow a usize.
    let intensity_len = 2 * buckets * ac_w * ac_h;
    let phase_at = header_size + intensity_len;
    let phase_len = 4 * cn_w * cn_h;
    if phase_at + phase_len > bytes.len() {
        return Err(fail(format!(
            "truncated MetroPro file: header {header_size} + intensity {intensity_len} + phase \
             {phase_len} bytes ({cn_w}×{cn_h}) exceed the file's {} bytes",
            bytes.len()
        )));
    }
    if !(lateral.is_finite() && lateral > 0.0) {
        return Err(fail(format!(
            "MetroPro camera resolution (lateral_res) = {lateral} m is not a positive length"
        )));
    }

    let names = vec![
        vec!["height".to_string(), "phase".to_string()],
        vec!["intensity".to_string()],
    ];
    let channel = match opts.channel.as_deref() {
        None => 0,
        Some(req) => find_channel(req, &names).ok_or_else(|| {
            unsupported(
                path,
                format!(
                    "MetroPro file has no channel `{req}`; channels: height (phase), intensity"
                ),
            )
        })?,
    };
    let mut header = BTreeMap::new();
    for (k, v) in [
        ("header_format", header_format.to_string()),
        ("intf_scale_factor", scale.to_string()),
        ("wavelength_in", wavelength.to_string()),
        ("obliquity_factor", obliquity.to_string()),
        ("lateral_res", lateral.to_string()),
        ("phase_res", phase_res.to_string()),
        ("sign", sign.to_string()),
        ("intensity", format!("{ac_w}×{ac_h}×{buckets}")),
    ] {
        header.insert(k.to_string(), v);
    }

    let z = if channel == 0 {
        if cn_w == 0 || cn_h == 0 {
            return Err(fail("MetroPro file has no phase data (0 pixels)".into()));
        }
        let resolution = match phase_res {
            0 => 4096.0,
            1 => 32768.0,
            2 => 131072.0,
            r => return Err(fail(format!("MetroPro phase_res {r} is not 0, 1 or 2"))),
        };
        let mut factor = scale * wavelength * obliquity / resolution;
        if sign != 0 {
            factor = -factor;
        }
        if !(factor.is_finite() && factor != 0.0) {
            return Err(fail(format!(
                "MetroPro height scale (intf_scale_factor {scale} · wavelength {wavelength} m · \
                 obliquity {obliquity}) is not a usable number"
            )));
        }
        let values = bytes[phase_at..phase_at + phase_len]
            .chunks_exact(4)
            .map(|c| {
                let p = i32::from_be_bytes([c[0], c[1], c[2], c[3]]);
                if p >= INVALID_PHASE {
                    f64::NAN
                } else {
                    p as f64 * factor
                }
            })
            .collect();
        Array2::from_shape_vec((cn_h, cn_w), values)
    } else {
        if ac_w == 0 || ac_h == 0 || buckets == 0 {
            return Err(fail("MetroPro file has no intensity data".into()));
        }
        // The first bucket; intensities are counts, not lengths.
        let values = bytes[header_size..header_size + 2 * ac_w * ac_h]
            .chunks_exact(2)
            .map(|c| u16::from_be_bytes([c[0], c[1]]) as f64)
            .collect();
        Array2::from_shape_vec((ac_h, ac_w), values)
    }
    .map_err(|e| fail(format!("MetroPro data shape: {e}")))?;
    header.insert("channels".into(), "height, intensity".into());
    Ok(RawMap {
        z,
        dx: lateral,
        dy: lateral,
        x0: 0.0,
        y0: 0.0,
        channel: if channel == 0 { "height" } else { "intensity" }.to_string(),
        format: "metropro",
        header,
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};
    use std::path::PathBuf;

    fn sample() -> PathBuf {
        PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/surfaces/metropro-1.dat"
        ))
    }

    #[test]
    fn surfacetopography_sample_metropro_1() {
        // Values asserted by SurfaceTopography's test/IO/test_metropro.py (MIT).
        let map = read_height_map(&sample(), &ReadOptions::default()).unwrap();
        assert_eq!(map.source.format, "metropro");
        assert_eq!((map.nx(), map.ny()), (640, 480));
        let (sx, sy) = map.size();
        assert!(close(sx, 0.0007028812979115173, 1e-6), "{sx}");
        assert!(close(sy, 0.000527160973433638, 1e-6), "{sy}");
        let n = map.z.len() as f64;
        let mean = map.z.sum() / n;
        let rms = (map.z.mapv(|z| (z - mean).powi(2)).sum() / n).sqrt();
        assert!(close(rms, 7.528822204734589e-08, 1e-6), "{rms}");
    }

    /// A byte-built header format 3 file: phase_res 0 (R = 4096), `sign` set, one invalid
    /// pixel, no intensity; heights checked against z = −phase · S · λ · O / R by hand.
    #[test]
    fn byte_built_format_3_file() {
        let (nx, ny) = (4usize, 3usize);
        let mut b = vec![0u8; 4096];
        b[..4].copy_from_slice(&super::MAGICS[2]);
        b[4..6].copy_from_slice(&3u16.to_be_bytes());
        b[6..10].copy_from_slice(&4096u32.to_be_bytes());
        b[68..70].copy_from_slice(&(nx as u16).to_be_bytes());
        b[70..72].copy_from_slice(&(ny as u16).to_be_bytes());
        b[164..168].copy_from_slice(&0.5f32.to_be_bytes());
        b[168..172].copy_from_slice(&632.8e-9f32.to_be_bytes());
        b[176..180].copy_from_slice(&1.0f32.to_be_bytes());
        b[184..188].copy_from_slice(&2e-6f32.to_be_bytes());
        b[232..234].copy_from_slice(&1i16.to_be_bytes());
        let phase: Vec<i32> = (0..12)
            .map(|k| if k == 5 { i32::MAX } else { 100 * k - 300 })
            .collect();
        for p in &phase {
            b.extend_from_slice(&p.to_be_bytes());
        }
        let map = read_bytes("f3.dat", &b).unwrap();
        assert_eq!((map.nx(), map.ny()), (nx, ny));
        assert!(close(map.dx, 2e-6f32 as f64, 1e-15) && close(map.dy, map.dx, 1e-15));
        let step = 0.5 * (632.8e-9f32 as f64) / 4096.0;
        let valid = map.valid.as_ref().unwrap();
        for (k, &p) in phase.iter().enumerate() {
            let (j, i) = (k / nx, k % nx);
            if k == 5 {
                assert!(!valid[[j, i]]);
            } else {
                assert!(valid[[j, i]]);
                let want = -(p as f64) * step;
                assert!((map.z[[j, i]] - want).abs() <= 1e-12 * step, "{k}");
            }
        }
        let msg = read_bytes("f3.dat", &b[..4096 + 4 * 11])
            .unwrap_err()
            .to_string();
        assert!(msg.contains("truncated MetroPro"), "{msg}");
    }

    #[test]
    fn intensity_channel_and_unknown_channel() {
        let opts = ReadOptions {
            channel: Some("intensity".into()),
            ..Default::default()
        };
        let map = read_height_map(&sample(), &opts).unwrap();
        assert_eq!(
            (map.nx(), map.ny(), map.channel.as_str()),
            (640, 480, "intensity")
        );
        let opts = ReadOptions {
            channel: Some("amplitude".into()),
            ..Default::default()
        };
        let msg = read_height_map(&sample(), &opts).unwrap_err().to_string();
        assert!(
            msg.contains("metropro-1.dat") && msg.contains("intensity"),
            "{msg}"
        );
    }

    #[test]
    fn truncated_and_hostile_files_are_errors() {
        let bytes = std::fs::read(sample()).unwrap();
        for cut in [0, 4, 100, 833, 834, 50_000, bytes.len() - 1] {
            let msg = read_bytes("t.dat", &bytes[..cut]).unwrap_err().to_string();
            assert!(msg.contains("t.dat"), "{cut}: {msg}");
        }
        let msg = read_bytes("t.dat", &bytes[..bytes.len() - 1])
            .unwrap_err()
            .to_string();
        assert!(msg.contains("truncated MetroPro"), "{msg}");
        // Garbled sizes: header_size, the phase array's width, phase_res.
        for (at, value) in [(6, 0xFFu8), (68, 0xFF), (219, 0x07), (184, 0x00)] {
            let mut bad = bytes.clone();
            bad[at] = value;
            if at == 184 {
                bad[184..188].fill(0);
            }
            let msg = read_bytes("g.dat", &bad).unwrap_err().to_string();
            assert!(
                msg.contains("g.dat") && msg.contains("MetroPro"),
                "{at}: {msg}"
            );
        }
        // Its 240 corrupt copies: registry.rs,
        // `every_sample_survives_truncation_and_flipped_bytes`.
    }
}
