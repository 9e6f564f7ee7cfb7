//! The height-map readers, in one list: each declares its id, name, file extensions, how it is
//! recognised, a content sniffer, its reader and the real (or independently written) files the
//! tests read it on. Detection (`detect_format`), dispatch (`read_height_map`), the error's
//! "supported:" list and the format table of docs/surfaces.md are all made from [`READERS`];
//! the tests below fail when a reader has no sample, does not read or survive corruption of its
//! samples, or is missing from the docs' table.

use super::{
    al3d, ascii, bcr, datx, finish, frt, gsf, gwy, ibw, metropro, mi, mnt, nanoscope, nid, nms,
    opd, park, plu, sdf, sniff_text, sur, tmd, wsxm, x3p, xyz, RawMap, ReadOptions,
};
use crate::surface::{HeightMap, Result, SurfaceError};
use std::path::Path;

/// One height-map format.
pub struct Reader {
    /// Short id: `HeightMap::source.format`, the `format` of `hdi surface --json`.
    pub id: &'static str,
    /// What users call it.
    pub name: &'static str,
    /// The extensions its files usually have (informative: detection is by content).
    pub extensions: &'static [&'static str],
    /// How the sniffer recognises it, for the docs.
    pub detected_by: &'static str,
    /// Whether the first bytes of a file (up to 64 kB) are this format's.
    pub(crate) sniff: fn(&[u8]) -> bool,
    /// Heights in metres, NaN where invalid, row 0 at the top.
    pub(crate) read: fn(&Path, &[u8], &ReadOptions) -> Result<RawMap>,
    /// Files the tests read it on, from the repository root: public instrument files or files
    /// written by an independent library (provenance in tests/data/README.md).
    pub samples: &'static [&'static str],
}

/// Every reader, in detection order: magic bytes first, then Igor's plausibility check (it has
/// no magic), then the two text formats.
pub const READERS: &[Reader] = &[
    Reader {
        id: "gwy",
        name: "Gwyddion native",
        extensions: &["gwy"],
        detected_by: "`GWYP` / `GWYO`",
        sniff: |h| h.starts_with(b"GWYP") || h.starts_with(b"GWYO"),
        read: gwy::read,
        samples: &["src/surface/io/testdata/gwyfile_writer.gwy"],
    },
    Reader {
        id: "nanoscope",
        name: "Bruker NanoScope v4.3+ binary",
        extensions: &["spm", "di", "001"],
        detected_by: "`\\*File list` / `?*File list`",
        sniff: |h| h.starts_with(b"\\*File list") || h.starts_with(b"?*File list"),
        read: nanoscope::read,
        samples: &["tests/data/surfaces/di-3.di"],
    },
    Reader {
        id: "gsf",
        name: "Gwyddion Simple Field",
        extensions: &["gsf"],
        detected_by: "`Gwyddion Simple Field `",
        sniff: |h| h.starts_with(b"Gwyddion Simple Field "),
        read: gsf::read,
        samples: &["tests/data/surfaces/numpy_float32.gsf"],
    },
    Reader {
        id: "sur",
        name: "Digital Surf",
        extensions: &["sur"],
        detected_by: "`DIGITAL SURF` (`DSCOMPRESSED`: refused)",
        sniff: |h| h.starts_with(sur::MAGIC) || h.starts_with(sur::MAGIC_COMPRESSED),
        read: sur::read,
        samples: &[
            "tests/data/surfaces/sur-2.sur",
            "tests/data/surfaces/sur-3.sur",
        ],
    },
    Reader {
        id: "sdf",
        name: "Surface Data File (ISO 25178-71, BCR)",
        extensions: &["sdf"],
        detected_by: "`aISO-1.0`, `bISO-1.0`, `aBCR-1.0`, `bBCR-1.0`",
        sniff: |h| sdf::MAGICS.iter().any(|m| h.starts_with(m)),
        read: |path, bytes, _| sdf::read(path, bytes),
        samples: &[
            "tests/data/surfaces/sdf-1.sdf",
            "tests/data/surfaces/bcr_binary_int16.sdf",
        ],
    },
    Reader {
        id: "metropro",
        name: "Zygo MetroPro",
        extensions: &["dat"],
        detected_by: "`88 1B 03 6F/70/71`",
        sniff: |h| metropro::MAGICS.iter().any(|m| h.starts_with(m)),
        read: metropro::read,
        samples: &["tests/data/surfaces/metropro-1.dat"],
    },
    Reader {
        id: "datx",
        name: "Zygo .datx (HDF5)",
        extensions: &["datx"],
        detected_by: "HDF5 signature; `/MetaData` must exist",
        sniff: |h| h.starts_with(datx::MAGIC),
        read: datx::read,
        samples: &[
            "tests/data/surfaces/readers_b/datx_fixed.datx",
            "tests/data/surfaces/readers_b/datx_vlen.datx",
        ],
    },
    Reader {
        id: "x3p",
        name: "ISO 25178-71 XML 3D surface profile",
        extensions: &["x3p"],
        detected_by: "ZIP signature; `main.xml` must be inside",
        sniff: crate::formats::zip::is_zip,
        read: x3p::read,
        samples: &[
            "tests/data/surfaces/x3p-2.x3p",
            "tests/data/surfaces/readers_b/x3p_int32_mask.x3p",
        ],
    },
    Reader {
        id: "opd",
        name: "Wyko / Vision OPD",
        extensions: &["opd"],
        detected_by: "a `Directory` block at byte 2",
        sniff: opd::looks_like,
        read: opd::read,
        samples: &["tests/data/surfaces/opd-1.opd"],
    },
    Reader {
        id: "tmd",
        name: "TrueMap",
        extensions: &["tmd"],
        detected_by: "`Binary TrueMap Data File` (versions other than 2.0: refused)",
        sniff: |h| h.starts_with(tmd::MAGIC),
        read: tmd::read,
        samples: &["tests/data/surfaces/tmd-1.tmd"],
    },
    Reader {
        id: "wsxm",
        name: "WSxM SPM image",
        extensions: &["top", "stp", "tom", "cur"],
        detected_by: "`WSxM file copyright`",
        sniff: |h| h.starts_with(wsxm::MAGIC),
        read: |path, bytes, _| wsxm::read(path, bytes),
        samples: &[
            "tests/data/surfaces/top-1.top",
            "tests/data/surfaces/stp-1.stp",
        ],
    },
    Reader {
        id: "al3d",
        name: "Alicona Imaging AL3D",
        extensions: &["al3d"],
        detected_by: "`AliconaImaging\\0\\r\\n`",
        sniff: |h| h.starts_with(al3d::MAGIC),
        read: al3d::read,
        samples: &["tests/data/surfaces/al3d-1.al3d"],
    },
    Reader {
        id: "frt",
        name: "FRT MicroProf",
        extensions: &["frt"],
        detected_by: "`FRTM_GLIDERV` (versions other than 1.00, 1.01: refused)",
        sniff: |h| h.starts_with(frt::MAGIC),
        read: frt::read,
        samples: &[
            "tests/data/surfaces/frt-1.frt",
            "tests/data/surfaces/frt-2.frt",
        ],
    },
    Reader {
        id: "nid",
        name: "Nanosurf NID / EZD",
        extensions: &["nid", "ezd"],
        detected_by: "`[DataSet]` + CR LF",
        sniff: |h| h.starts_with(nid::MAGIC),
        read: nid::read,
        samples: &["tests/data/surfaces/nid-1.nid"],
    },
    Reader {
        id: "mi",
        name: "Molecular Imaging / Agilent PicoView",
        extensions: &["mi"],
        detected_by: "`fileType`",
        sniff: |h| h.starts_with(mi::MAGIC),
        read: mi::read,
        samples: &["tests/data/surfaces/mi-1.mi"],
    },
    Reader {
        id: "bcr",
        name: "Image Metrology BCR-STM / BCRF",
        extensions: &["bcr", "bcrf"],
        detected_by: "`fileformat = bcr` (latin-1 or UTF-16)",
        sniff: bcr::looks_like,
        read: |path, bytes, _| bcr::read(path, bytes),
        samples: &["tests/data/surfaces/bcrf-1.bcrf"],
    },
    Reader {
        id: "mnt",
        name: "Digital Surf Mountains document",
        extensions: &["mnt"],
        detected_by: "compound-file signature `D0 CF 11 E0`; a `ScopedContents` stream must exist",
        sniff: |h| h.starts_with(mnt::MAGIC),
        read: mnt::read,
        samples: &[
            "tests/data/surfaces/mnt-1.mnt",
            "tests/data/surfaces/mnt-2.mnt",
        ],
    },
    Reader {
        id: "plu",
        name: "Sensofar PLu",
        extensions: &["plu", "apx"],
        detected_by: "an `asctime` date at byte 0 and a format version (0 or ≥ 0xF0) at byte 490",
        sniff: plu::looks_like,
        read: plu::read,
        samples: &["tests/data/surfaces/plu-1.plu"],
    },
    Reader {
        id: "nms",
        name: "NanoFocus NMS",
        extensions: &["nms"],
        detected_by: "`OM_MS_` at byte 32 and a plausible grid at byte 1368",
        sniff: nms::looks_like,
        read: nms::read,
        samples: &[
            "tests/data/surfaces/nms-1.nms",
            "tests/data/surfaces/nms-2.nms",
        ],
    },
    Reader {
        id: "park",
        name: "Park Systems TIFF",
        extensions: &["tiff", "tif"],
        detected_by: "TIFF whose first IFD has Park's tag 50432 = `0x0E031301`",
        sniff: park::looks_like,
        read: |path, bytes, _| park::read(path, bytes),
        samples: &["tests/data/surfaces/example_ps.tiff"],
    },
    Reader {
        id: "ibw",
        name: "Igor binary wave (Asylum Research)",
        extensions: &["ibw"],
        detected_by: "a version field (1, 2, 3, 5, either byte order) with a known number type",
        sniff: ibw::looks_like,
        read: ibw::read,
        samples: &[
            "tests/data/surfaces/spot_1-1000nm.ibw",
            "tests/data/surfaces/igor_be_int16_3layers.ibw",
        ],
    },
    Reader {
        id: "xyz",
        name: "XYZ on a rectangular lattice",
        extensions: &["xyz", "txt", "csv"],
        detected_by: "text: an XYZ unit header, or three columns on a lattice",
        sniff: |h| sniff_text(h) == Some("xyz"),
        read: xyz::read,
        samples: &["tests/data/surfaces/numpy_lattice.xyz"],
    },
    Reader {
        id: "ascii",
        name: "ASCII matrix / Gwyddion ASCII export / CSV",
        extensions: &["txt", "asc", "csv"],
        detected_by: "text: numeric rows (other than XYZ)",
        sniff: |h| sniff_text(h) == Some("ascii"),
        read: ascii::read,
        samples: &["tests/data/surfaces/gaussian_acf_256_seed12345.txt"],
    },
];

impl Reader {
    /// Reads `path` with this reader, whatever its sniffer would say, through the checks every
    /// map passes (`read_height_map` without the detection; the `every_reader` fuzz target).
    pub fn read_file(&self, path: &Path, opts: &ReadOptions) -> Result<HeightMap> {
        let bytes = std::fs::read(path).map_err(|source| SurfaceError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        finish(path, (self.read)(path, &bytes, opts)?)
    }
}

/// The reader whose sniffer claims `head` first.
pub fn detect(head: &[u8]) -> Option<&'static Reader> {
    READERS.iter().find(|r| (r.sniff)(head))
}

/// The list of the error message for a file no reader claims.
pub fn supported() -> String {
    supported_list(READERS.iter().map(|r| (r.name, r.extensions)))
}

/// "Name (.ext .ext), …" of formats given as (name, extensions): the "supported:" list of the
/// height-map and the line-profile registries.
pub(crate) fn supported_list<'a>(
    formats: impl Iterator<Item = (&'a str, &'a [&'a str])>,
) -> String {
    formats
        .map(|(name, extensions)| {
            let ext: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
            format!("{name} ({})", ext.join(" "))
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The format table of docs/surfaces.md, between its `readers:begin`/`readers:end` markers.
pub fn markdown_table() -> String {
    markdown_table_of(
        READERS
            .iter()
            .map(|r| (r.name, r.id, r.extensions, r.detected_by, r.samples)),
    )
}

/// A docs table of formats given as (name, id, extensions, detected by, samples): the
/// height-map and the line-profile registries.
pub(crate) fn markdown_table_of<'a>(
    formats: impl Iterator<Item = (&'a str, &'a str, &'a [&'a str], &'a str, &'a [&'a str])>,
) -> String {
    let mut s = String::from(
        "| format | id | extensions | detected by | read in the tests on |\n|---|---|---|---|---|\n",
    );
    for (name, id, extensions, detected_by, samples) in formats {
        let ext: Vec<String> = extensions.iter().map(|e| format!("`.{e}`")).collect();
        let samples: Vec<String> = samples
            .iter()
            .map(|p| format!("`{}`", p.rsplit('/').next().unwrap_or(p)))
            .collect();
        s.push_str(&format!(
            "| {name} | `{id}` | {} | {detected_by} | {} |\n",
            ext.join(" "),
            samples.join(", ")
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::super::testutil::fuzz_reader;
    use super::super::{read_height_map, SNIFF_BYTES};
    use super::*;
    use std::collections::BTreeSet;

    fn repo(p: &str) -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
    }

    #[test]
    fn every_reader_has_a_unique_id_and_a_sample() {
        let ids: BTreeSet<&str> = READERS.iter().map(|r| r.id).collect();
        assert_eq!(ids.len(), READERS.len(), "duplicate reader ids");
        for r in READERS {
            assert!(!r.samples.is_empty(), "{}: no real sample", r.id);
            assert!(!r.extensions.is_empty(), "{}: no extension", r.id);
        }
    }

    /// Each sample is detected as its reader's format and read by it, and lists its channels.
    #[test]
    fn every_sample_is_detected_and_read_by_its_reader() {
        for r in READERS {
            for s in r.samples {
                let path = repo(s);
                let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{s}: {e}"));
                let head = &bytes[..bytes.len().min(SNIFF_BYTES)];
                assert_eq!(detect(head).map(|d| d.id), Some(r.id), "{s}");
                let map = read_height_map(&path, &ReadOptions::default())
                    .unwrap_or_else(|e| panic!("{s}: {e}"));
                assert_eq!(map.source.format, r.id, "{s}");
                // The file's channels are listed, the one read among them.
                let channels = map.source.header.get("channels").map(|c| c.to_lowercase());
                let listed = channels
                    .as_ref()
                    .is_some_and(|c| c.contains(&map.channel.to_lowercase()));
                assert!(listed, "{s}: `{}` not in {channels:?}", map.channel);
            }
        }
    }

    /// Truncated and byte-flipped copies of every sample: an error that names the file, or a
    /// map, never a panic; and some of them fail, so the error path ran.
    #[test]
    fn every_sample_survives_truncation_and_flipped_bytes() {
        use rayon::prelude::*;
        // The longest unit test (~7000 corrupt copies of multi-MB files): samples in parallel,
        // so that it does not hold the end of `cargo test` on one core.
        let samples: Vec<&str> = READERS
            .iter()
            .flat_map(|r| r.samples.iter().copied())
            .collect();
        samples.par_iter().for_each(|s| {
            let bytes = std::fs::read(repo(s)).unwrap();
            let name = s.rsplit('/').next().unwrap();
            let failed = fuzz_reader(name, &bytes);
            assert!(failed > 0, "{s}: no corrupt copy was refused");
        });
    }

    /// Each reader given every other reader's samples (what its sniffer would keep from it):
    /// a clean error naming the file, or a map, never a panic (the `every_reader` fuzz target
    /// does the same with AFL's inputs).
    #[test]
    fn every_reader_survives_the_other_formats() {
        let opts = ReadOptions {
            size_x: Some(1e-5),
            size_y: Some(1e-5),
            z_unit: Some("nm".into()),
            ..ReadOptions::default()
        };
        for r in READERS {
            for other in READERS.iter().filter(|o| o.id != r.id) {
                // The HDF5 reader forks a child per file: HDF5 inputs only, as in the fuzz target.
                if r.id == "datx" && other.id != "datx" {
                    continue;
                }
                for s in other.samples {
                    if let Err(e) = r.read_file(&repo(s), &opts) {
                        let name = s.rsplit('/').next().unwrap();
                        assert!(e.to_string().contains(name), "{}: {s}: {e}", r.id);
                    }
                }
            }
            // And the shortest files: the first bytes of every sample, the empty file included.
            let dir = tempfile::tempdir().unwrap();
            for s in READERS.iter().flat_map(|o| o.samples) {
                let bytes = std::fs::read(repo(s)).unwrap();
                for n in (0..bytes.len().min(40)).chain([64, 200, 1000]) {
                    if r.id == "datx" || n > bytes.len() {
                        continue;
                    }
                    let path = dir.path().join("short");
                    std::fs::write(&path, &bytes[..n]).unwrap();
                    if let Err(e) = r.read_file(&path, &opts) {
                        assert!(e.to_string().contains("short"), "{}: {s}[..{n}]: {e}", r.id);
                    }
                }
            }
        }
    }

    /// RMS height about the mean of the valid pixels, and how many are invalid.
    fn rms_and_invalid(map: &crate::surface::HeightMap) -> (f64, usize) {
        let ok = |j: usize, i: usize| map.valid.as_ref().is_none_or(|v| v[[j, i]]);
        let vals: Vec<f64> = map
            .z
            .indexed_iter()
            .filter(|((j, i), _)| ok(*j, *i))
            .map(|(_, &z)| z)
            .collect();
        let mean = vals.iter().sum::<f64>() / vals.len() as f64;
        let ms = vals.iter().map(|z| (z - mean).powi(2)).sum::<f64>() / vals.len() as f64;
        (ms.sqrt(), map.z.len() - vals.len())
    }

    /// The public instrument samples read as SurfaceTopography reads them
    /// (`tests/data/surfaces/make_surfacetopography_reference.py`): pixel counts, invalid
    /// pixels and sizes exact, the RMS height to 1e-9, four pixels (its `[x, y]` is hdi's row
    /// y, column x) to 1e-9.
    #[test]
    fn instrument_samples_agree_with_surfacetopography() {
        let text =
            std::fs::read_to_string(repo("tests/data/surfaces/surfacetopography_reference.json"))
                .unwrap();
        let reference: serde_json::Value = serde_json::from_str(&text).unwrap();
        let files = reference["files"].as_object().unwrap();
        assert!(files.len() >= 2);
        for (name, want) in files {
            let path = repo(&format!("tests/data/surfaces/{name}"));
            let map = read_height_map(&path, &ReadOptions::default()).unwrap();
            let f = |k: &str| want[k].as_f64().unwrap();
            assert_eq!(map.nx() as f64, f("nx"), "{name}");
            assert_eq!(map.ny() as f64, f("ny"), "{name}");
            let rel = |a: f64, b: f64| ((a - b) / b).abs();
            assert!(
                rel(map.dx * map.nx() as f64, f("size_x_m")) < 1e-12,
                "{name}"
            );
            assert!(
                rel(map.dy * map.ny() as f64, f("size_y_m")) < 1e-12,
                "{name}"
            );
            let (rms, invalid) = rms_and_invalid(&map);
            assert_eq!(invalid as f64, f("n_undefined"), "{name}");
            assert!(
                rel(rms, f("rms_height_m")) < 1e-9,
                "{name}: {rms} vs {}",
                f("rms_height_m")
            );
            for p in want["pixels_m"].as_array().unwrap() {
                let (x, y, z) = (
                    p[0].as_u64().unwrap() as usize,
                    p[1].as_u64().unwrap() as usize,
                    p[2].as_f64().unwrap(),
                );
                assert!(
                    rel(map.z[[y, x]], z) < 1e-9,
                    "{name} [{x}, {y}]: {} vs {z}",
                    map.z[[y, x]]
                );
            }
        }
    }

    /// The GSF and XYZ files numpy wrote (`make_gsf_xyz_fixtures.py`): sizes, invalid pixels
    /// and the RMS height numpy computed, to 1e-9.
    #[test]
    fn numpy_written_gsf_and_xyz_give_numpys_values() {
        for (file, json) in [
            ("numpy_float32.gsf", "numpy_float32.json"),
            ("numpy_lattice.xyz", "numpy_lattice.json"),
        ] {
            let dir = "tests/data/surfaces/";
            let want: serde_json::Value = serde_json::from_str(
                &std::fs::read_to_string(repo(&format!("{dir}{json}"))).unwrap(),
            )
            .unwrap();
            let map =
                read_height_map(&repo(&format!("{dir}{file}")), &ReadOptions::default()).unwrap();
            let f = |k: &str| want[k].as_f64().unwrap();
            assert_eq!(map.nx() as f64, f("nx"), "{file}");
            assert_eq!(map.ny() as f64, f("ny"), "{file}");
            assert!(((map.dx - f("dx_m")) / f("dx_m")).abs() < 1e-12, "{file}");
            let (rms, invalid) = rms_and_invalid(&map);
            assert_eq!(invalid as f64, f("n_invalid"), "{file}");
            let r = f("rms_about_mean_m");
            assert!(((rms - r) / r).abs() < 1e-9, "{file}: {rms} vs {r}");
        }
    }

    #[test]
    fn the_docs_format_table_is_the_registry() {
        let docs = std::fs::read_to_string(repo("docs/surfaces.md")).unwrap();
        let begin = "<!-- readers:begin (generated from surface::io::registry::READERS) -->\n";
        let end = "<!-- readers:end -->";
        let table = docs
            .split_once(begin)
            .and_then(|(_, rest)| rest.split_once(end))
            .map(|(t, _)| t);
        assert_eq!(
            table,
            Some(markdown_table().as_str()),
            "docs/surfaces.md's reader table is not the registry's; put this between the \
             markers:\n{begin}{}{end}",
            markdown_table()
        );
    }

    #[test]
    fn the_unsupported_message_names_every_reader() {
        let list = supported();
        for r in READERS {
            assert!(list.contains(r.name), "{}", r.id);
        }
    }
}
