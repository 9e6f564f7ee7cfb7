//! JPK Instruments (Bruker) image scans `.jpk` and QI images `.jpk-qi-image` (docs/surfaces.md),
//! as Gwyddion's `jpkscan.c`, SurfaceTopography's `IO/JPK.py` and AFMReader's `jpk.py` read
//! them: a classic TIFF (JPK writes big-endian) whose first IFD is an 8-bit thumbnail carrying
//! the scan's private tags (0x8000 file format version, 0x8042/0x8043 grid u/v lengths in
//! metres, 0x8040/0x8041 grid origin, …) and whose other IFDs are one channel each: an
//! uncompressed raster of raw integers with 0x8050 channel name, 0x8051 retrace flag, 0x8052
//! display name, 0x8080 number of slots, 0x8081 the default slot's name, and per slot k the
//! tags from 0x8090 + 0x30·k: +0x00 slot name, +0x12 unit, +0x13 scaling type (`LinearScaling`
//! or `NullScaling`), +0x14 multiplier and +0x15 offset (doubles) mapping raw to the unit.
//!
//! Heights: multiplier · raw + offset of the default slot (metres for height channels). The
//! first raster line is the bottom of the image unless the channel's 0x8045 reflect flag is
//! set (Gwyddion and SurfaceTopography 1.27.1 flip it so). Every channel is listed; the default
//! is the first whose unit is a length, as SurfaceTopography picks it.
use super::tiff::{first_ifd_entry, Tiff, ASCII, DOUBLE};
use super::units::length_factor;
use super::{find_channel, format_error, unsupported, RawMap, ReadOptions};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

const FILE_FORMAT_VERSION: u16 = 0x8000;
const START_DATE: u16 = 0x8003;
const NAME: u16 = 0x8004;
const GRID_X0: u16 = 0x8040;
const GRID_Y0: u16 = 0x8041;
const GRID_U_LENGTH: u16 = 0x8042;
const GRID_V_LENGTH: u16 = 0x8043;
const GRID_THETA: u16 = 0x8044;
const GRID_REFLECT: u16 = 0x8045;
const CHANNEL: u16 = 0x8050;
const CHANNEL_RETRACE: u16 = 0x8051;
const CHANNEL_FANCY_NAME: u16 = 0x8052;
const NR_OF_SLOTS: u16 = 0x8080;
const DEFAULT_SLOT: u16 = 0x8081;
const FIRST_SLOT: u16 = 0x8090;
const SLOT_STRIDE: u16 = 0x30;
const SLOT_UNIT: u16 = 0x12;
const SLOT_SCALING_TYPE: u16 = 0x13;
const SLOT_MULTIPLY: u16 = 0x14;
const SLOT_OFFSET: u16 = 0x15;

/// Whether the first IFD of a TIFF carries JPK's file format version (ASCII) and grid length
/// (double) tags.
pub(crate) fn looks_like(head: &[u8]) -> bool {
    matches!(
        first_ifd_entry(head, FILE_FORMAT_VERSION),
        Some((ASCII, _, _))
    ) && matches!(first_ifd_entry(head, GRID_U_LENGTH), Some((DOUBLE, 1, _)))
}

/// One channel page: its names and the default slot's scaling.
struct Channel {
    ifd: usize,
    /// Display name (SurfaceTopography's), `{channel}_{trace|retrace}` (AFMReader's) and
    /// `page {ifd}` (to tell apart channels of the same name).
    names: Vec<String>,
    unit: String,
    scaling: Option<(f64, f64)>,
    slot_problem: Option<String>,
}

fn channel(tiff: &Tiff, ifd: usize) -> Option<Channel> {
    let internal = tiff.text(ifd, CHANNEL)?;
    let fancy = tiff.text(ifd, CHANNEL_FANCY_NAME)?;
    let retrace = tiff.int(ifd, CHANNEL_RETRACE).unwrap_or(0) != 0;
    let display = match (retrace, fancy.strip_suffix(')')) {
        (false, _) => fancy.clone(),
        (true, Some(open)) => format!("{open}, retrace)"),
        (true, None) => format!("{fancy} (retrace)"),
    };
    let trace = if retrace { "retrace" } else { "trace" };
    let names = vec![
        display,
        format!("{internal}_{trace}"),
        format!("page {ifd}"),
    ];
    let (mut unit, mut scaling, mut slot_problem) = (String::new(), None, None);
    let default = tiff.text(ifd, DEFAULT_SLOT).unwrap_or_default();
    let n_slots = tiff.uint(ifd, NR_OF_SLOTS).unwrap_or(0);
    // Slot tags must stay below 0x10000.
    let max_slots = u64::from((u16::MAX - FIRST_SLOT) / SLOT_STRIDE);
    let slot = (0..n_slots.min(max_slots) as u16)
        .map(|k| FIRST_SLOT + SLOT_STRIDE * k)
        .find(|&base| tiff.text(ifd, base).as_deref() == Some(default.as_str()));
    match slot {
        None => {
            slot_problem = Some(format!(
                "its default slot `{default}` is not among its slots"
            ))
        }
        Some(base) => {
            unit = tiff.text(ifd, base + SLOT_UNIT).unwrap_or_default();
            let kind = tiff.text(ifd, base + SLOT_SCALING_TYPE).unwrap_or_default();
            match kind.as_str() {
                "LinearScaling" => {
                    let m = tiff.float(ifd, base + SLOT_MULTIPLY);
                    let o = tiff.float(ifd, base + SLOT_OFFSET);
                    match (m, o) {
                        (Some(m), Some(o)) if m.is_finite() && o.is_finite() => {
                            scaling = Some((m, o))
                        }
                        _ => {
                            slot_problem = Some(format!(
                                "slot `{default}` has no finite multiplier and offset"
                            ))
                        }
                    }
                }
                "NullScaling" => scaling = Some((1.0, 0.0)),
                other => {
                    slot_problem = Some(format!("slot `{default}` has scaling type `{other}`"))
                }
            }
        }
    }
    Some(Channel {
        ifd,
        names,
        unit,
        scaling,
        slot_problem,
    })
}

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let fail = |reason: String| format_error(path, reason);
    let tiff = Tiff::parse(bytes).map_err(fail)?;
    let channels: Vec<Channel> = (1..tiff.ifds.len())
        .filter_map(|ifd| channel(&tiff, ifd))
        .collect();
    let names: Vec<Vec<String>> = channels.iter().map(|c| c.names.clone()).collect();
    let listing = || {
        let all: Vec<String> = channels
            .iter()
            .map(|c| format!("{} [{}]", c.names[0], c.unit))
            .collect();
        all.join(", ")
    };
    let k = match &opts.channel {
        Some(want) => find_channel(want, &names)
            .ok_or_else(|| fail(format!("no channel `{want}`; the file has {}", listing())))?,
        None => channels
            .iter()
            .position(|c| length_factor(&c.unit).is_some())
            .ok_or_else(|| {
                fail(format!(
                    "JPK file has no channel in a length unit; the file has {}",
                    if channels.is_empty() {
                        "no channels".to_string()
                    } else {
                        listing()
                    }
                ))
            })?,
    };
    let c = &channels[k];
    let name = &c.names[0];
    if let Some(problem) = &c.slot_problem {
        return Err(fail(format!("JPK channel `{name}`: {problem}")));
    }
    let unit_factor = length_factor(&c.unit).ok_or_else(|| {
        unsupported(
            path,
            format!(
                "JPK channel `{name}` is in `{}`, not a length; only height channels are read",
                c.unit
            ),
        )
    })?;
    let (multiply, offset) = c.scaling.unwrap_or((1.0, 0.0));
    let image = tiff
        .strip_image(c.ifd)
        .map_err(|e| fail(format!("JPK channel `{name}`: {e}")))?;
    let grid = |tag: u16, what: &str| -> Result<f64> {
        match tiff.float(0, tag) {
            Some(v) if v.is_finite() && v > 0.0 => Ok(v),
            v => Err(fail(format!(
                "JPK grid {what} (tag {tag:#x}) = {v:?} is not a positive length"
            ))),
        }
    };
    let (u_length, v_length) = (
        grid(GRID_U_LENGTH, "u length")?,
        grid(GRID_V_LENGTH, "v length")?,
    );
    let (nx, ny) = (image.width, image.height);
    let reflect = tiff.int(c.ifd, GRID_REFLECT).unwrap_or(0) != 0;
    let z = Array2::from_shape_fn((ny, nx), |(r, i)| {
        let line = if reflect { r } else { ny - 1 - r };
        (multiply * image.values[line * nx + i] + offset) * unit_factor
    });
    let mut header = BTreeMap::new();
    for (key, tag) in [
        ("file_format_version", FILE_FORMAT_VERSION),
        ("start_date", START_DATE),
        ("name", NAME),
    ] {
        if let Some(v) = tiff.text(0, tag) {
            header.insert(key.to_string(), v);
        }
    }
    if let Some(theta) = tiff.float(0, GRID_THETA) {
        header.insert("grid_theta_rad".into(), theta.to_string());
    }
    header.insert("channels".into(), listing());
    header.insert("unit".into(), c.unit.clone());
    let origin = |tag: u16| tiff.float(0, tag).filter(|v| v.is_finite()).unwrap_or(0.0);
    Ok(RawMap {
        z,
        dx: u_length / nx as f64,
        dy: v_length / ny as f64,
        x0: origin(GRID_X0),
        y0: origin(GRID_Y0),
        channel: name.clone(),
        format: "jpk",
        header,
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::tiff::tests::tiff_pages;
    use super::super::tiff::{
        Order, BITS_PER_SAMPLE, IMAGE_LENGTH, IMAGE_WIDTH, LONG, ROWS_PER_STRIP, SAMPLE_FORMAT,
        SHORT, SLONG, SSHORT,
    };
    use super::*;

    /// A big-endian JPK file as the layout above describes it: the thumbnail page with the
    /// global tags, then one 3 × 3 int32 channel `height` (retrace; its default slot in `unit`:
    /// raw · 2 nm + 1 µm), raw value k = 100·k − 200 in file order.
    fn one_channel(unit: &str, reflect: i16) -> Vec<u8> {
        let be16 = |v: u16| v.to_be_bytes().to_vec();
        let be32 = |v: u32| v.to_be_bytes().to_vec();
        let f64b = |v: f64| v.to_be_bytes().to_vec();
        let text = |s: &str| [s.as_bytes(), b"\0"].concat();
        let ascii = |tag: u16, s: &str| (tag, ASCII, s.len() as u32 + 1, text(s));
        let thumbnail = vec![
            ascii(FILE_FORMAT_VERSION, "6.0"),
            (GRID_U_LENGTH, DOUBLE, 1, f64b(3e-6)),
            (GRID_V_LENGTH, DOUBLE, 1, f64b(4e-6)),
            (IMAGE_WIDTH, SHORT, 1, be16(1)),
            (IMAGE_LENGTH, SHORT, 1, be16(1)),
            ascii(CHANNEL, "thumbnail"),
        ];
        let slot = FIRST_SLOT;
        let height = vec![
            (IMAGE_WIDTH, SHORT, 1, be16(3)),
            (IMAGE_LENGTH, SHORT, 1, be16(3)),
            (BITS_PER_SAMPLE, SHORT, 1, be16(32)),
            (SAMPLE_FORMAT, SHORT, 1, be16(2)),
            (ROWS_PER_STRIP, LONG, 1, be32(3)),
            (GRID_REFLECT, SSHORT, 1, be16(reflect as u16)),
            ascii(CHANNEL, "height"),
            (CHANNEL_RETRACE, SSHORT, 1, be16(1)),
            ascii(CHANNEL_FANCY_NAME, "Height"),
            (NR_OF_SLOTS, SLONG, 1, be32(2)),
            ascii(DEFAULT_SLOT, "calibrated"),
            ascii(slot, "raw"),
            ascii(slot + SLOT_SCALING_TYPE, "NullScaling"),
            ascii(slot + SLOT_STRIDE, "calibrated"),
            ascii(slot + SLOT_STRIDE + SLOT_UNIT, unit),
            ascii(slot + SLOT_STRIDE + SLOT_SCALING_TYPE, "LinearScaling"),
            (slot + SLOT_STRIDE + SLOT_MULTIPLY, DOUBLE, 1, f64b(2e-9)),
            (slot + SLOT_STRIDE + SLOT_OFFSET, DOUBLE, 1, f64b(1e-6)),
        ];
        let raster: Vec<u8> = (0..9i32)
            .flat_map(|k| (100 * k - 200).to_be_bytes())
            .collect();
        tiff_pages(Order::Big, &[(thumbnail, None), (height, Some(raster))])
    }

    #[test]
    fn scaling_orientation_names_and_units() {
        let bytes = one_channel("m", 0);
        assert!(looks_like(&bytes));
        let map = read_bytes("a.jpk", &bytes).unwrap();
        assert_eq!(
            (map.nx(), map.ny(), map.source.format.as_str()),
            (3, 3, "jpk")
        );
        assert_eq!(map.channel, "Height (retrace)");
        assert!(close(map.dx, 1e-6, 1e-15) && close(map.dy, 4e-6 / 3.0, 1e-15));
        // Raw k = 100·k − 200 (k = 3·line + i); row r is line 2 − r unless reflected.
        let z = |k: i32| f64::from(100 * k - 200) * 2e-9 + 1e-6;
        assert!(close(map.z[[0, 0]], z(6), 1e-12) && close(map.z[[2, 2]], z(2), 1e-12));
        let reflected = read_bytes("b.jpk", &one_channel("m", 1)).unwrap();
        assert!(close(reflected.z[[0, 0]], z(0), 1e-12));
        let (dir, path) = write_temp("c.jpk", &bytes);
        let opts = |c: &str| ReadOptions {
            channel: Some(c.into()),
            ..ReadOptions::default()
        };
        for name in ["height_retrace", "page 1", "Height (retrace)"] {
            let m = super::super::read_height_map(&path, &opts(name)).unwrap();
            assert_eq!(m.channel, "Height (retrace)");
        }
        let e = super::super::read_height_map(&path, &opts("phase"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("c.jpk") && e.contains("Height (retrace) [m]"),
            "{e}"
        );
        drop(dir);
        let e = read_bytes("d.jpk", &one_channel("V", 0))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("d.jpk") && e.contains("no channel in a length unit"),
            "{e}"
        );
    }

    /// AFMReader's tests of its samples (tests/test_jpk.py at commit 062b984): the grid, the
    /// pixel size in nm and the sum of the heights in nm (its `image.sum()`, which does not
    /// depend on the orientation). AFMReader's `measuredHeight_trace` of the QI image is its
    /// second page of that name (a later page overwrites an earlier one in its channel dict),
    /// hdi's `page 3`.
    #[test]
    fn afmreader_samples_give_afmreaders_asserted_values() {
        for (file, channel, n, pixel_nm, sum_nm) in [
            (
                "sample_0.jpk",
                "height_trace",
                256,
                1.2770176335964876,
                219242202.8256843,
            ),
            (
                "sample_0.jpk-qi-image",
                "height_trace",
                100,
                4.999999999999986,
                31593146.16051172,
            ),
            (
                "sample_0.jpk-qi-image",
                "page 3",
                100,
                4.999999999999986,
                32181137.138706185,
            ),
        ] {
            let opts = ReadOptions {
                channel: Some(channel.into()),
                ..ReadOptions::default()
            };
            let map = super::super::read_height_map(&surface_sample(file), &opts).unwrap();
            assert_eq!((map.nx(), map.ny()), (n, n), "{file} {channel}");
            assert!(close(map.dx * 1e9, pixel_nm, 1e-12), "{file}: {}", map.dx);
            let sum: f64 = map.z.iter().map(|z| z * 1e9).sum();
            assert!(close(sum, sum_nm, 1e-9), "{file} {channel}: {sum}");
        }
    }
}
