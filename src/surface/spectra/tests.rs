//! The analyses against SurfaceTopography 1.27.1 on the same maps
//! (`tests/data/surfaces/make_surface_analyses_reference.py`).
use super::*;
use crate::surface::io::{read_height_map, ReadOptions};

fn repo(p: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

fn reference() -> serde_json::Value {
    let text = std::fs::read_to_string(repo("tests/data/surfaces/surface_analyses_reference.json"))
        .unwrap();
    serde_json::from_str(&text).unwrap()
}

/// The two reference maps as hdi reads them (the canonical surface is periodic by
/// construction; the ASCII reader cannot know that).
fn map(name: &str) -> HeightMap {
    let mut map = read_height_map(
        &repo(&format!("tests/data/surfaces/{name}")),
        &ReadOptions::default(),
    )
    .unwrap();
    map.periodic = name.starts_with("gaussian");
    map
}

const MAPS: [&str; 2] = ["di-3.di", "gaussian_acf_256_seed12345.txt"];
const TOLERANCE: f64 = 1e-9;

fn assert_curve(name: &str, what: &str, got: &Curve, want: &serde_json::Value) {
    let values = |k: &str| -> Vec<f64> {
        want[k]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    let (x, y) = (values("x"), values("y"));
    assert!(!x.is_empty(), "{name} {what}: empty reference");
    assert_eq!(got.x.len(), x.len(), "{name} {what}: number of points");
    let mut worst: f64 = 0.0;
    for (k, (g, w)) in got.x.iter().zip(&x).enumerate() {
        let rel = ((g - w) / w).abs();
        assert!(
            rel < TOLERANCE,
            "{name} {what} x #{k}: {g:e} vs {w:e} ({rel:e})"
        );
        worst = worst.max(rel);
    }
    // A smooth spectrum falls to the FFT's round-off floor at high q (the Gaussian-ACF
    // surface's PSD spans 22 decades): there both programs print noise. Relative agreement is
    // required above 1e-12 of the curve's largest value, where round-off (1e-16 of the largest
    // amplitude, so 1e-10 relative at most) is below the tolerance; below it, agreement to
    // 1e-12 of the largest value.
    let largest = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut floor = 0;
    for (k, (g, w)) in got.y.iter().zip(&y).enumerate() {
        if w.abs() < 1e-12 * largest {
            floor += 1;
            assert!(
                (g - w).abs() < 1e-12 * largest,
                "{name} {what} #{k}: {g:e} vs {w:e}"
            );
            continue;
        }
        let rel = ((g - w) / w).abs();
        assert!(
            rel < TOLERANCE,
            "{name} {what} #{k}: {g:e} vs {w:e} ({rel:e})"
        );
        worst = worst.max(rel);
    }
    eprintln!(
        "{name} {what}: {} points, worst relative difference {worst:.1e}, {floor} at the \
         round-off floor",
        x.len()
    );
}

#[test]
fn curves_agree_with_surface_topography() {
    let reference = reference();
    for name in MAPS {
        let want = &reference["maps"][name];
        let got = surface_analyses(&map(name)).unwrap();
        for (what, curve) in [
            ("psd_profile", &got.psd_profile),
            ("psd_area", &got.psd_area),
            ("acf_profile", &got.acf_profile),
            ("acf_area", &got.acf_area),
            ("slope_profile", &got.slope_profile),
            ("curvature_profile", &got.curvature_profile),
            ("slope_area", &got.slope_area),
            ("curvature_area", &got.curvature_area),
        ] {
            assert_curve(name, what, curve, &want[what]);
        }
    }
}

#[test]
fn tip_cutoffs_agree_with_surface_topography() {
    let reference = reference();
    let mut reached = 0;
    for name in MAPS {
        let m = map(name);
        for (radius, want) in reference["maps"][name]["tip_reliability_cutoff_m"]
            .as_object()
            .unwrap()
        {
            let radius: f64 = radius.parse().unwrap();
            let got = tip_reliability_cutoff(&m, radius).unwrap();
            match (got, want.as_f64()) {
                (TipCutoff::NoArtefacts, None) => {}
                (TipCutoff::At(l) | TipCutoff::NoReliableData(l), Some(w)) => {
                    let rel = ((l - w) / w).abs();
                    assert!(rel < TOLERANCE, "{name} R = {radius:e}: {l:e} vs {w:e}");
                    reached += matches!(got, TipCutoff::At(_)) as usize;
                    eprintln!("{name} R = {radius:e}: λc = {l:e} m ({rel:.1e})");
                }
                (got, want) => panic!("{name} R = {radius:e}: {got:?} vs {want:?}"),
            }
        }
    }
    assert!(reached >= 5, "the reference must exercise the root search");
}

#[test]
fn invalid_pixels_and_bad_radii_are_refused() {
    let mut m = map("di-3.di");
    assert!(tip_reliability_cutoff(&m, 0.0).is_err());
    assert!(tip_reliability_cutoff(&m, f64::NAN).is_err());
    let mut valid = ndarray::Array2::from_elem(m.z.dim(), true);
    valid[[3, 4]] = false;
    m.valid = Some(valid);
    let err = surface_analyses(&m).unwrap_err().to_string();
    assert!(err.contains("invalid pixels"), "{err}");
}
