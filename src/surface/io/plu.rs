//! Sensofar `.plu` / `.apx` (confocal, interferometric and focus-variation profilers;
//! docs/surfaces.md). The layout, as Gwyddion's `sensofar.c` and SurfaceTopography's
//! `IO/PLU.py` read it (little-endian, no magic: the file starts with its date):
//!
//! - 0: the date as C's `asctime` writes it (`Fri Mar 10 16:35:59 2023`, 128 bytes), 128: time
//!   (u32), 132: comment (256 bytes);
//! - 388: calibration: yres, xres, N_tall (u32), dy_multip, µm per pixel x, y, offset x, y,
//!   µm per pixel z, offset z (f32);
//! - 428: measurement: type (3 = topography), algorithm, method, objective, area type (u32),
//!   then 40 bytes of scan settings (field-of-view or point-scan variant, same size);
//! - 488: restore, number of layers, format version (0 = 2000, then 0xff = 2006 counting down to
//!   0xfa = 2013), hardware configuration, number of RGB images per layer (u8 each), a reserved
//!   byte, two bytes of padding, decimation factor (u32);
//! - 500: per layer: yres, xres (u32), yres rows of xres float32 heights in µm (1000001 = no
//!   data), the layer's min and max (f32), then its RGB images (3 bytes a pixel, same grid).
//!
//! Rows are stored top first (both readers show row 0 at the top). Channels: `layer<k>` (the
//! heights) and `layer<k> image<i> red|green|blue` (intensities in counts 0–255, not lengths).
use super::le::{le_f32, le_f64, le_u32};
use super::units::nul_terminated;
use super::{find_channel, format_error, unsupported, RawMap, ReadOptions};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

/// Bytes before the first layer.
const HEADER: usize = 500;
/// Where the format-version byte is.
const VERSION_AT: usize = 490;
/// The height that marks a pixel without data.
const NO_DATA: f32 = 1_000_001.0;
/// Measurement type of a topography (the only one read: profiles and images are not maps).
const TOPOGRAPHY: u32 = 3;

/// Whether a file starts like a Sensofar PLU file: an `asctime` date (`Www Mmm ` with known day
/// and month names) and a format-version byte of 0 (2000) or ≥ 0xf0 (2006 and later), as
/// Gwyddion's detector checks.
pub(crate) fn looks_like(head: &[u8]) -> bool {
    const DAYS: [&[u8]; 7] = [b"Mon", b"Tue", b"Wed", b"Thu", b"Fri", b"Sat", b"Sun"];
    const MONTHS: [&[u8]; 12] = [
        b"Jan", b"Feb", b"Mar", b"Apr", b"May", b"Jun", b"Jul", b"Aug", b"Sep", b"Oct", b"Nov",
        b"Dec",
    ];
    head.len() >= HEADER
        && DAYS.contains(&&head[0..3])
        && head[3] == b' '
        && MONTHS.contains(&&head[4..7])
        && head[7] == b' '
        && head[8..24]
            .iter()
            .all(|b| b.is_ascii_graphic() || *b == b' ')
        && (head[VERSION_AT] == 0 || head[VERSION_AT] >= 0xf0)
}

/// One layer: its grid and where its heights and images start.
struct Layer {
    nx: usize,
    ny: usize,
    heights_at: usize,
    images_at: usize,
}

/// What a channel is: a layer's heights, or one colour of one of its images.
enum Source {
    Heights(usize),
    Colour {
        layer: usize,
        image: usize,
        colour: usize,
    },
}

const COLOURS: [&str; 3] = ["red", "green", "blue"];

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let fail = |reason: String| format_error(path, reason);
    if !looks_like(bytes) {
        return Err(fail(format!(
            "not a Sensofar PLU file, or its {HEADER}-byte header is truncated ({} bytes)",
            bytes.len()
        )));
    }
    let kind = le_u32(bytes, 428);
    if kind != TOPOGRAPHY {
        return Err(unsupported(
            path,
            format!("Sensofar measurement type {kind} (only 3, topography, is a height map)"),
        ));
    }
    let (n_layers, n_images) = (usize::from(bytes[489]), usize::from(bytes[492]));
    if n_layers == 0 {
        return Err(fail("Sensofar file has no data layers".into()));
    }
    let mut layers = Vec::with_capacity(n_layers);
    let mut at = HEADER;
    for k in 0..n_layers {
        let truncated = |need: usize| {
            fail(format!(
                "truncated Sensofar file: layer {k} needs {need} bytes, the file has {}",
                bytes.len()
            ))
        };
        if at + 8 > bytes.len() {
            return Err(truncated(at + 8));
        }
        let (ny, nx) = (le_u32(bytes, at) as usize, le_u32(bytes, at + 4) as usize);
        let pixels = nx
            .checked_mul(ny)
            .filter(|&n| n > 0)
            .ok_or_else(|| fail(format!("Sensofar layer {k} has a {nx} × {ny} grid")))?;
        let heights_at = at + 8;
        let images_at = pixels
            .checked_mul(4)
            .and_then(|n| n.checked_add(heights_at + 8))
            .ok_or_else(|| truncated(usize::MAX))?;
        let end = pixels
            .checked_mul(3 * n_images)
            .and_then(|n| n.checked_add(images_at))
            .ok_or_else(|| truncated(usize::MAX))?;
        if end > bytes.len() {
            return Err(truncated(end));
        }
        layers.push(Layer {
            nx,
            ny,
            heights_at,
            images_at,
        });
        at = end;
    }

    let mut names: Vec<Vec<String>> = Vec::new();
    let mut sources = Vec::new();
    for (k, _) in layers.iter().enumerate() {
        names.push(vec![format!("layer{k}")]);
        sources.push(Source::Heights(k));
        for i in 0..n_images {
            for (c, colour) in COLOURS.iter().enumerate() {
                names.push(vec![format!("layer{k} image{i} {colour}")]);
                sources.push(Source::Colour {
                    layer: k,
                    image: i,
                    colour: c,
                });
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

    let (mppx, mppy) = (le_f32(bytes, 388 + 16).abs(), le_f32(bytes, 388 + 20).abs());
    for (name, v) in [("x", mppx), ("y", mppy)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(fail(format!(
                "Sensofar µm per pixel along {name} = {v} is not a positive length"
            )));
        }
    }
    let z = match sources[chosen] {
        Source::Heights(k) => {
            let l = &layers[k];
            Array2::from_shape_fn((l.ny, l.nx), |(j, i)| {
                let v = f32::from_le_bytes(
                    bytes[l.heights_at + 4 * (j * l.nx + i)..][..4]
                        .try_into()
                        .expect("4 bytes"),
                );
                if v == NO_DATA || !v.is_finite() {
                    f64::NAN
                } else {
                    f64::from(v) * 1e-6
                }
            })
        }
        Source::Colour {
            layer,
            image,
            colour,
        } => {
            let l = &layers[layer];
            let start = l.images_at + image * 3 * l.nx * l.ny + colour;
            Array2::from_shape_fn((l.ny, l.nx), |(j, i)| {
                f64::from(bytes[start + 3 * (j * l.nx + i)])
            })
        }
    };

    let version = bytes[VERSION_AT];
    let mut header = BTreeMap::new();
    header.insert("channels".to_string(), listing);
    header.insert("date".to_string(), nul_terminated(&bytes[..128]));
    header.insert("comment".to_string(), nul_terminated(&bytes[132..388]));
    header.insert(
        "format_version".to_string(),
        match version {
            0x00 => "2000".to_string(),
            0xff => "2006".to_string(),
            0xfe => "2010A".to_string(),
            0xfd => "2011".to_string(),
            0xfc => "2011B".to_string(),
            0xfb => "2012".to_string(),
            0xfa => "2013".to_string(),
            v => format!("0x{v:02x}"),
        },
    );
    let objective = le_u32(bytes, 440);
    header.insert(
        "objective".to_string(),
        OBJECTIVES
            .iter()
            .find(|(id, _)| *id == objective)
            .map_or_else(|| format!("#{objective}"), |(_, name)| name.to_string()),
    );
    header.insert("algorithm".to_string(), le_u32(bytes, 432).to_string());
    // The hardware field is only meaningful from format 2012 on (Gwyddion's note).
    let hardware = bytes[491];
    if version != 0 && version <= 0xfb {
        if let Some(name) = HARDWARE.get(usize::from(hardware)) {
            header.insert("instrument".to_string(), format!("Sensofar {name}"));
        }
    }
    for (key, at) in [
        ("x0_um", 388 + 24),
        ("y0_um", 388 + 28),
        ("z0_um", 388 + 36),
    ] {
        header.insert(key.to_string(), le_f32(bytes, at).to_string());
    }
    if le_u32(bytes, 444) != 6 {
        // Field-of-view scan settings: the z step and range of the scan.
        header.insert("scan_z_step_um".to_string(), le_f64(bytes, 468).to_string());
        header.insert(
            "scan_z_range_um".to_string(),
            le_f32(bytes, 476).to_string(),
        );
        header.insert("scan_planes".to_string(), le_u32(bytes, 480).to_string());
    }
    header.insert("layers".to_string(), n_layers.to_string());
    if !matches!(sources[chosen], Source::Heights(_)) {
        header.insert("z_unit".to_string(), "counts".to_string());
    }
    Ok(RawMap {
        z,
        dx: mppx * 1e-6,
        dy: mppy * 1e-6,
        x0: 0.0,
        y0: 0.0,
        channel: names[chosen][0].clone(),
        format: "plu",
        header,
    })
}

/// Hardware configurations by id (Gwyddion's `sensofar.c`, SurfaceTopography's `PLU.py`).
const HARDWARE: [&str; 12] = [
    "PLu",
    "PLu 2300 XGA",
    "PLu 2300 XGA T5",
    "PLu 2300 SXGA",
    "PLu 3300",
    "DCM 3D",
    "PLu neox",
    "DCM 3D rev. 2",
    "PLu Apex (prototype)",
    "S neox",
    "DCM8",
    "PLu Apex",
];

/// Objectives by id (the same two sources; ids 65–71 are not assigned).
const OBJECTIVES: &[(u32, &str)] = &[
    (0, "Unknown"),
    (1, "Nikon CFI Fluor Plan EPI SLWD 20x"),
    (2, "Nikon CFI Fluor Plan EPI SLWD 50x"),
    (3, "Nikon CFI Fluor Plan EPI SLWD 100x"),
    (4, "Nikon CFI Fluor Plan EPI 20x"),
    (5, "Nikon CFI Fluor Plan EPI 50x"),
    (6, "Nikon CFI Fluor Plan EPI 10x"),
    (7, "Nikon CFI Fluor Plan EPI 100x"),
    (8, "Nikon CFI Fluor Plan EPI ELWD 10x"),
    (9, "Nikon CFI Fluor Plan EPI ELWD 20x"),
    (10, "Nikon CFI Fluor Plan EPI ELWD 50x"),
    (11, "Nikon CFI Fluor Plan EPI ELWD 100x"),
    (12, "Nikon CFI Plan Interferential 2.5X"),
    (13, "Nikon CFI Plan Interferential 5X T"),
    (14, "Nikon CFI Plan Interferential 10X"),
    (15, "Nikon CFI Plan Interferential 20X"),
    (16, "Nikon CFI Plan Interferential 50X"),
    (17, "Nikon CFI Fluor Plan EPI 5X"),
    (18, "Nikon CFI Fluor Plan EPI 150X"),
    (19, "Nikon CFI Fluor Plan Apo EPI 50X"),
    (20, "Nikon CFI Fluor Plan EPI 1.5X"),
    (21, "Nikon CFI Fluor Plan EPI 2.5X"),
    (22, "Nikon CFI Fluor Plan Apo EPI 100X"),
    (23, "Nikon CFI Fluor Plan EPI 200X"),
    (24, "Nikon CFI Plan Water Immersion 10X"),
    (25, "Nikon CFI Plan Water Immersion 20X"),
    (26, "Nikon CFI Plan Water Immersion 150X"),
    (27, "Nikon CFI Plan EPI CR ELWD 10X"),
    (28, "Nikon CFI Plan EPI CR 20X"),
    (29, "Nikon CFI Plan EPI CR 50X"),
    (30, "Nikon CFI Plan EPI CR 100X A"),
    (31, "Nikon CFI Plan EPI CR 100X B"),
    (32, "Leica HCX FL Plan 2.5X"),
    (33, "Leica HC PL Fluotar EPI 5X"),
    (34, "Leica HC PL Fluotar EPI 10X"),
    (35, "Leica HC PL Fluotar EPI 20X"),
    (36, "Leica HC PL Fluotar EPI 50X"),
    (37, "Leica HC PL Fluotar EPI 50X HNA"),
    (38, "Leica HC PL Fluotar EPI 100X"),
    (39, "Leica HC PL Fluotar EPI 50X"),
    (40, "Leica N Plan EPI LWD 10X"),
    (41, "Leica N Plan EPI LWD 20X"),
    (42, "Leica HCX PL Fluotar LWD 50X"),
    (43, "Leica HCX PL Fluotar LWD 100X"),
    (44, "Leica HC PL Fluotar – Interferential Michelson MR 5X"),
    (45, "Leica HC PL Fluotar – Interferential Mirau MR 10X"),
    (46, "Leica N PLAN H - Interferential Mirau MR 20X"),
    (47, "Leica N PLAN H -Interferential Mirau MR 50X"),
    (48, "Nikon Interferential Linnik EPI 20X"),
    (49, "Nikon CFI Plan Interferential 100X DI"),
    (50, "Leica HCX PL FLUOTAR 1.25X"),
    (51, "Leica N PLAN EPI 20X"),
    (52, "Leica N PLAN EPI 40X"),
    (53, "Leica N PLAN L 50X"),
    (54, "Leica PL APO 100X"),
    (55, "Leica HCX APO L U-V-I 20X"),
    (56, "Leica HCX APO L U-V-I 40X"),
    (57, "Leica HCX APO L U-V-I 63X"),
    (58, "Leica HCX PL FLUOTAR 20X"),
    (59, "Leica N PLAN L 40X"),
    (60, "Leica Interferential Mirau SR 5X"),
    (61, "Leica Interferential Mirau SR 10X"),
    (62, "Leica Interferential Mirau SR 20X"),
    (63, "Leica Interferential Mirau SR 50X"),
    (64, "Leica Interferential Mirau SR 100X"),
    (72, "Leica HC PL Fluotar EPI 50X 0.8"),
    (73, "Leica HC PL Fluotar EPI 100X 0.9"),
    (74, "Nikon CFI T Plan EPI 1X"),
    (75, "Nikon CFI T Plan EPI 2.5X"),
    (76, "Nikon CFI TU Plan Fluor EPI 5X"),
    (77, "Nikon CFI TU Plan Fluor EPI 10X"),
    (78, "Nikon CFI TU Plan Fluor EPI 20X"),
    (79, "Nikon CFI LU Plan Fluor EPI 50X"),
    (80, "Nikon CFI TU Plan Fluor EPI 100X"),
    (81, "Nikon CFI EPI Plan Apo 150X"),
    (82, "Nikon CFI T Plan EPI ELWD 20X (AV 3.5)"),
    (83, "Nikon CFI T Plan EPI ELWD 50X (AV 3.5)"),
    (84, "Nikon CFI T Plan EPI ELWD 100X (AV 3.5)"),
    (85, "Nikon CFI T Plan EPI SLWD 10X (AV 3.5)"),
    (86, "Nikon CFI T Plan EPI SLWD 20X (AV 3.5)"),
    (87, "Nikon CFI T Plan EPI SLWD 50X (AV 3.5)"),
    (88, "Nikon CFI T Plan EPI SLWD 100X (AV 3.5)"),
    (89, "Nikon CFI Fluor Water Immersion 63X"),
    (90, "Nikon CFI TU Plan Fluor EPI 50X"),
    (91, "Nikon CFI TU Plan Apo EPI 100X"),
    (92, "Nikon CFI TU Plan Apo EPI 150X"),
];

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};

    fn sample() -> Vec<u8> {
        std::fs::read(surface_sample("plu-1.plu")).unwrap()
    }

    /// The instrument metadata SurfaceTopography 1.27.1 reads from plu-1.plu (its `info`):
    /// date, instrument, objective; and the channels the file has.
    #[test]
    fn metadata_and_channels_of_the_real_sample() {
        let map = read_height_map(&surface_sample("plu-1.plu"), &ReadOptions::default()).unwrap();
        let h = &map.source.header;
        assert_eq!(map.channel, "layer0");
        assert_eq!(h["date"], "Fri Mar 10 16:35:59 2023");
        assert_eq!(h["instrument"], "Sensofar PLu neox");
        assert_eq!(h["objective"], "Nikon CFI Plan Interferential 10X");
        assert_eq!(h["format_version"], "2012");
        assert_eq!(
            h["channels"],
            "layer0, layer0 image0 red, layer0 image0 green, layer0 image0 blue"
        );
        let opts = ReadOptions {
            channel: Some("image0 green".into()),
            ..ReadOptions::default()
        };
        let green = read_height_map(&surface_sample("plu-1.plu"), &opts).unwrap();
        assert_eq!((green.nx(), green.ny()), (768, 576));
        assert_eq!(green.source.header["z_unit"], "counts");
        assert!(green.z.iter().all(|&v| (0.0..=255.0).contains(&v)));
        let opts = ReadOptions {
            channel: Some("image".into()),
            ..ReadOptions::default()
        };
        let e = read_height_map(&surface_sample("plu-1.plu"), &opts)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("plu-1.plu") && e.contains("channels: layer0"),
            "{e}"
        );
    }

    /// The no-data marker 1000001 (Gwyddion's `LOST_PIXELS`) becomes an invalid pixel; a
    /// profile (measurement type 1) is refused as not a map.
    #[test]
    fn no_data_marker_and_profiles() {
        let mut bytes = sample();
        let at = 508 + 4 * (2 * 768 + 5); // row 2, column 5
        bytes[at..at + 4].copy_from_slice(&1_000_001f32.to_le_bytes());
        let map = read_bytes("a.plu", &bytes).unwrap();
        let valid = map.valid.as_ref().unwrap();
        assert!(!valid[[2, 5]] && valid[[2, 4]] && valid[[5, 2]]);
        assert_eq!(valid.iter().filter(|v| !**v).count(), 1);
        bytes[428] = 1;
        let e = read_bytes("b.plu", &bytes).unwrap_err().to_string();
        assert!(e.contains("b.plu") && e.contains("type 1"), "{e}");
    }
}
