//! The line-profile registry's tests: every reader has samples that are detected and read,
//! survive corruption with an error naming the file, agree with SurfaceTopography 1.27.1's
//! reading (`tests/data/surfaces/make_surfacetopography_profile_reference.py`), and the docs'
//! table is the registry.

use super::*;
use crate::surface::io::testutil::{write_temp, Lcg};
use std::collections::BTreeSet;

fn repo(p: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

#[test]
fn every_reader_has_a_unique_id_and_a_sample() {
    let ids: BTreeSet<&str> = PROFILE_READERS.iter().map(|r| r.id).collect();
    assert_eq!(ids.len(), PROFILE_READERS.len());
    for r in PROFILE_READERS {
        assert!(!r.samples.is_empty(), "{}", r.id);
        assert!(!r.extensions.is_empty(), "{}", r.id);
    }
}

#[test]
fn every_sample_is_detected_and_read_by_its_reader() {
    for r in PROFILE_READERS {
        for s in r.samples {
            let bytes = std::fs::read(repo(s)).unwrap();
            let head = &bytes[..bytes.len().min(SNIFF_BYTES)];
            assert_eq!(detect(head).map(|d| d.id), Some(r.id), "{s}");
            let p = read_line_profile(&repo(s)).unwrap_or_else(|e| panic!("{s}: {e}"));
            assert_eq!(p.format, r.id);
            assert_eq!(p.x.len(), p.z.len());
        }
    }
}

/// Truncated and byte-flipped copies of every sample: a profile or an error naming the file,
/// never a panic; and some copies fail, so the error path ran.
#[test]
fn every_sample_survives_truncation_and_flipped_bytes() {
    for r in PROFILE_READERS {
        for s in r.samples {
            let bytes = std::fs::read(repo(s)).unwrap();
            let name = s.rsplit('/').next().unwrap();
            let (_dir, path) = write_temp(name, b"");
            let mut failed = 0;
            let mut check = |data: &[u8]| {
                if let Err(e) = read_profile_bytes(&path, data) {
                    let msg = e.to_string();
                    assert!(
                        msg.contains(name),
                        "{name}: error does not name the file: {msg}"
                    );
                    failed += 1;
                }
            };
            let mut rng = Lcg(0x5eed ^ bytes.len() as u64);
            for k in 0..40 {
                let cut = if k < 10 {
                    k * 3
                } else {
                    rng.below(bytes.len())
                };
                check(&bytes[..cut.min(bytes.len())]);
            }
            for _ in 0..200 {
                let mut copy = bytes.clone();
                let at = rng.below(copy.len().clamp(1, 4096));
                let at = if rng.below(2) == 0 {
                    at
                } else {
                    rng.below(copy.len())
                };
                copy[at] ^= 1 << rng.below(8);
                check(&copy);
            }
            assert!(failed > 0, "{s}: no corrupt copy was refused");
        }
    }
}

/// Point counts and spans exact (1e-12), RMS height about the mean to 1e-9 and four points
/// (position from the first point, height) to 1e-9, against SurfaceTopography's reading.
#[test]
fn samples_agree_with_surfacetopography() {
    let text = std::fs::read_to_string(repo(
        "tests/data/surfaces/surfacetopography_profile_reference.json",
    ))
    .unwrap();
    let reference: serde_json::Value = serde_json::from_str(&text).unwrap();
    let files = reference["files"].as_object().unwrap();
    assert_eq!(files.len(), 6);
    let rel = |a: f64, b: f64| {
        if b == 0.0 {
            a.abs()
        } else {
            ((a - b) / b).abs()
        }
    };
    for (name, want) in files {
        let p = read_line_profile(&repo(&format!("tests/data/surfaces/{name}"))).unwrap();
        let f = |k: &str| want[k].as_f64().unwrap();
        assert_eq!(p.len() as f64, f("n"), "{name}");
        assert!(p.valid.iter().all(|v| *v), "{name}");
        let span = p.x[p.len() - 1] - p.x[0];
        assert!(
            rel(span, f("span_m")) < 1e-12,
            "{name}: {span} vs {}",
            f("span_m")
        );
        // Uniform or not as SurfaceTopography classifies it.
        assert_eq!(
            p.uniform_spacing().is_some(),
            want["uniform"].as_bool().unwrap(),
            "{name}"
        );
        let n = p.len() as f64;
        let mean = p.z.iter().sum::<f64>() / n;
        let rms = (p.z.iter().map(|z| (z - mean).powi(2)).sum::<f64>() / n).sqrt();
        assert!(
            rel(rms, f("rms_height_m")) < 1e-9,
            "{name}: {rms} vs {}",
            f("rms_height_m")
        );
        for q in want["points_m"].as_array().unwrap() {
            let i = q[0].as_u64().unwrap() as usize;
            let (x, z) = (q[1].as_f64().unwrap(), q[2].as_f64().unwrap());
            // SurfaceTopography puts a scan it finds uniform on i·dx (xy-4.txt's positions are
            // printed to 6 decimals): there to 1 % of a step, else the file's positions exactly.
            let tol = if want["uniform"].as_bool().unwrap() {
                1e-2 * span / (n - 1.0)
            } else {
                1e-12 * span
            };
            assert!((p.x[i] - p.x[0] - x).abs() <= tol, "{name} x[{i}]");
            assert!(rel(p.z[i], z) < 1e-9, "{name} z[{i}]: {} vs {z}", p.z[i]);
        }
    }
}

/// The vendor's own text export of opdx-3 (8 significant digits) is a second, independent
/// reading of the binary: same points, positions and heights to its printed precision.
#[test]
fn opdx_agrees_with_the_vendors_text_export() {
    let bin = read_line_profile(&repo("tests/data/surfaces/opdx-3.opdx")).unwrap();
    let txt = read_line_profile(&repo("tests/data/surfaces/opdx-3.txt")).unwrap();
    assert_eq!(bin.len(), txt.len());
    let zmax = txt.z.iter().fold(0.0f64, |m, z| m.max(z.abs()));
    for k in 0..bin.len() {
        assert!(
            (bin.x[k] - txt.x[k]).abs() <= 1e-7 * bin.x[bin.len() - 1],
            "x[{k}]"
        );
        assert!((bin.z[k] - txt.z[k]).abs() <= 1e-7 * zmax, "z[{k}]");
    }
    assert_eq!(bin.header["DataKind"], "Surface Profile");
}

#[test]
fn units_invalid_points_and_errors() {
    let read = |name: &str, text: &str| {
        let (_d, p) = write_temp(name, text.as_bytes());
        read_line_profile(&p)
    };
    let p = read(
        "a.txt",
        "# x_unit: um\n# z_unit: nm\n0 1\n0.5 NaN\n1.5 3\n2 4\n",
    )
    .unwrap();
    assert_eq!(p.format, "xz");
    assert!((p.x[2] - 1.5e-6).abs() < 1e-18 && (p.z[3] - 4e-9).abs() < 1e-21);
    assert_eq!(p.valid, vec![true, false, true, true]);
    assert!(p.uniform_spacing().is_none());
    let p = read("b.txt", "µm nm\n0,1\n1,2\n2,3\n").unwrap();
    assert_eq!(p.uniform_spacing(), Some(1e-6));
    assert!((p.z[2] - 3e-9).abs() < 1e-21);
    let p = read(
        "c.hfm",
        "X;Y;valid\r\n[mm];[um];[1/0]\r\n0;1;1\r\n1;2;0\r\n2;3;1\r\n3;4;1\r\n",
    )
    .unwrap();
    assert_eq!(p.valid, vec![true, false, true, true]);
    assert!((p.x[3] - 3e-3).abs() < 1e-15 && (p.z[3] - 4e-6).abs() < 1e-18);
    let e = read("d.txt", "0 1\n1 2\n2 3 4\n3 4\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("d.txt") && e.contains("line 3"), "{e}");
    let e = read("e.txt", "0 1\n").unwrap_err().to_string();
    assert!(e.contains("e.txt") && e.contains("at least 3"), "{e}");
    let e = read("f.bin", "\u{0}\u{1}").unwrap_err().to_string();
    assert!(e.contains("f.bin") && e.contains("Dektak"), "{e}");
}

#[test]
fn the_docs_profile_table_is_the_registry() {
    let docs = std::fs::read_to_string(repo("docs/surfaces.md")).unwrap();
    let begin = "<!-- profiles:begin (generated from surface::io::profile::PROFILE_READERS) -->\n";
    let end = "<!-- profiles:end -->";
    let table = docs
        .split_once(begin)
        .and_then(|(_, rest)| rest.split_once(end))
        .map(|(t, _)| t);
    assert_eq!(
        table,
        Some(markdown_table().as_str()),
        "docs/surfaces.md's line-profile table is not the registry's; put this between the \
         markers:\n{begin}{}{end}",
        markdown_table()
    );
}
