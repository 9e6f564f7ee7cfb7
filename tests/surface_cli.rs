//! `hdi surface FILE --json` on every supported format, and the analytic surfaces.

use crate::common::*;
use hdi::surface::io::{encode_ascii_matrix, encode_gsf, encode_gwy, encode_nanoscope, encode_xyz};
use hdi::surface::synth::{egg_crate, gaussian_acf_surface, GaussianSurfaceSpec};
use serde_json::Value;

fn surface_json(file: &std::path::Path, extra: &[&str]) -> Value {
    let o = hdi()
        .arg("surface")
        .arg(file)
        .args(extra)
        .arg("--json")
        .output()
        .unwrap();
    assert!(o.status.success(), "hdi surface failed: {}", stderr(&o));
    serde_json::from_str(&stdout(&o)).expect("one JSON object on stdout")
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

#[test]
fn every_format_gives_sigma_r_eta_beta_in_si() {
    let spec = GaussianSurfaceSpec {
        n: 128,
        size: 0.5e-6,
        sigma: 0.5e-9,
        correlation_length: 20e-9,
        seed: 42,
    };
    let map = gaussian_acf_surface(&spec);
    let dir = tempfile::tempdir().unwrap();
    let files = [
        ("gwy", encode_gwy(&map)),
        ("spm", encode_nanoscope(&map, 4)),
        ("txt", encode_ascii_matrix(&map)),
        ("xyz", encode_xyz(&map)),
        ("gsf", encode_gsf(&map)),
    ];
    let mut sigmas = Vec::new();
    for (ext, bytes) in files {
        let f = dir.path().join(format!("map.{ext}"));
        std::fs::write(&f, bytes).unwrap();
        let j = surface_json(&f, &[]);
        for key in [
            "sigma_m",
            "R_m",
            "eta_per_m2",
            "beta",
            "n_summits",
            "m2",
            "m4_per_m2",
            "alpha",
        ] {
            assert!(j[key].is_number(), "{ext}: {key} missing in {j}");
        }
        assert_eq!(j["nx"], 128, "{ext}");
        assert!(
            rel(j["dx_m"].as_f64().unwrap(), 0.5e-6 / 128.0) < 1e-6,
            "{ext}: dx {}",
            j["dx_m"]
        );
        let sigma = j["sigma_m"].as_f64().unwrap();
        // Same field in every format: σ agrees (int32 NanoScope and f32 GSF quantise a little).
        assert!(sigma > 0.3e-9 && sigma < 0.6e-9, "{ext}: sigma {sigma}");
        sigmas.push((ext, sigma, j["eta_per_m2"].as_f64().unwrap()));
    }
    let (_, s0, e0) = sigmas[0];
    for (ext, s, e) in &sigmas {
        assert!(rel(*s, s0) < 1e-6, "{ext}: sigma {s} vs gwy {s0}");
        assert!(rel(*e, e0) < 0.02, "{ext}: eta {e} vs gwy {e0}");
    }
}

#[test]
fn egg_crate_summit_density_and_radius_match_the_analytic_values() {
    // z = A cos(2πx/λ) cos(2πy/λ): maxima where both cosines are ±1 with the same sign, i.e.
    // 2 per λ² cell; curvature at a maximum A(2π/λ)² in both directions ⇒ R = 1/(A(2π/λ)²).
    let (n, dx, a, lambda) = (256, 4e-9, 1e-9, 64.0 * 4e-9);
    let map = egg_crate(n, dx, a, lambda);
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("egg.gwy");
    std::fs::write(&f, encode_gwy(&map)).unwrap();
    let j = surface_json(&f, &["--periodic", "--level", "mean"]);
    let eta = j["eta_per_m2"].as_f64().unwrap();
    let r = j["R_m"].as_f64().unwrap();
    let eta_exact = 2.0 / (lambda * lambda);
    let r_exact = 1.0 / (a * (2.0 * std::f64::consts::PI / lambda).powi(2));
    assert!(rel(eta, eta_exact) < 0.02, "eta {eta} vs {eta_exact}");
    assert!(rel(r, r_exact) < 0.02, "R {r} vs {r_exact}");
}

#[test]
fn gaussian_surface_sigma_is_the_sample_rms_after_levelling() {
    use hdi::surface::level::{level, LevelOp};
    use hdi::surface::roughness::{roughness, RoughnessOptions};
    let spec = GaussianSurfaceSpec {
        n: 200,
        size: 1e-6,
        sigma: 0.4e-9,
        correlation_length: 25e-9,
        seed: 9,
    };
    let mut map = gaussian_acf_surface(&spec);
    map.periodic = false;
    let recipe: Vec<LevelOp> = ["rows:median", "plane", "mean"]
        .iter()
        .map(|s| s.parse().unwrap())
        .collect();
    level(&mut map, &recipe).unwrap();
    let n = map.z.len() as f64;
    let mean = map.z.sum() / n;
    let rms = (map.z.iter().map(|z| (z - mean).powi(2)).sum::<f64>() / n).sqrt();
    let rep = roughness(&map, &RoughnessOptions::default()).unwrap();
    assert!(
        rel(rep.sigma, rms) < 1e-12,
        "sigma {} vs sample rms {rms}",
        rep.sigma
    );
    // And through the CLI on a file, with levelling "mean" only, σ is the generator's σ.
    let raw = gaussian_acf_surface(&spec);
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("g.gwy");
    std::fs::write(&f, encode_gwy(&raw)).unwrap();
    let j = surface_json(&f, &["--level", "mean"]);
    assert!(
        rel(j["sigma_m"].as_f64().unwrap(), 0.4e-9) < 1e-12,
        "{}",
        j["sigma_m"]
    );
}

#[test]
fn out_option_writes_hdf5_and_plots() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("res").join("disk.h5");
    let f = repo_root().join("raw/afm/disk_dlc_1um.gwy");
    let o = hdi()
        .arg("surface")
        .arg(&f)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.is_file());
    assert!(dir.path().join("res/height_map.png").is_file());
    let text = stdout(&o);
    assert!(text.contains("β = σRη"), "{text}");
}

/// The tip reliability cutoff through the CLI on a real AFM file, against SurfaceTopography
/// 1.27.1's on the same heights (`tests/data/surfaces/surface_analyses_reference.json`). The
/// default levelling (row medians, plane) leaves the x second differences unchanged up to
/// round-off, so the cutoff is the one of the map as read. Without `--tip-radius` the report
/// has no `tip_reliability`.
#[test]
fn tip_radius_gives_surface_topographys_reliability_cutoff() {
    let f = repo_root().join("tests/data/surfaces/di-3.di");
    let reference: Value = serde_json::from_str(
        &std::fs::read_to_string(
            repo_root().join("tests/data/surfaces/surface_analyses_reference.json"),
        )
        .unwrap(),
    )
    .unwrap();
    let want = reference["maps"]["di-3.di"]["tip_reliability_cutoff_m"]["4e-08"]
        .as_f64()
        .unwrap();
    let j = surface_json(&f, &["--tip-radius", "40nm"]);
    let t = &j["tip_reliability"];
    assert_eq!(t["status"], "cutoff", "{t}");
    let got = t["cutoff_m"].as_f64().unwrap();
    assert!(rel(got, want) < 1e-9, "{got:e} vs {want:e}");
    // Above the cutoff the small summits are gone: fewer, blunter summits.
    assert!(t["n_summits"].as_u64().unwrap() < j["n_summits"].as_u64().unwrap());
    assert!(t["R_m"].as_f64().unwrap() > j["R_m"].as_f64().unwrap());
    let j = surface_json(&f, &["--tip-radius", "10nm"]);
    assert_eq!(j["tip_reliability"]["status"], "no_artefacts");
    assert_eq!(j["tip_reliability"]["R_m"], j["R_m"]);
    let j = surface_json(&f, &[]);
    assert!(j.get("tip_reliability").is_none(), "{j}");
    let o = hdi()
        .args(["surface", "--tip-radius=-3nm"])
        .arg(&f)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(stderr(&o).contains("tip-radius"), "{}", stderr(&o));
}

#[test]
fn out_option_writes_the_surface_analyses() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("res").join("di.h5");
    let f = repo_root().join("tests/data/surfaces/di-3.di");
    let o = hdi()
        .arg("surface")
        .arg(&f)
        .args(["--tip-radius", "40nm", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    for png in [
        "psd_profile.png",
        "psd_area.png",
        "acf.png",
        "slope.png",
        "curvature.png",
    ] {
        assert!(dir.path().join("res").join(png).is_file(), "{png}");
    }
    let h5 = hdf5::File::open(&out).unwrap();
    for (path, units) in [
        ("surface/analyses/psd_profile/q", "1/m"),
        ("surface/analyses/psd_profile/C", "m^3"),
        ("surface/analyses/psd_area/C", "m^4"),
        ("surface/analyses/acf_area/A", "m^2"),
        ("surface/analyses/slope_profile/slope", "1"),
        ("surface/analyses/curvature_area/curvature", "1/m"),
        ("surface/tip_reliability/cutoff", "m"),
        ("surface/tip_reliability/R", "m"),
    ] {
        let ds = h5.dataset(path).unwrap();
        let u: hdf5::types::VarLenUnicode = ds.attr("units").unwrap().read_scalar().unwrap();
        assert_eq!(u.as_str(), units, "{path}");
    }
}

/// The docs/surfaces.md reference table on the canonical surface in tests/data, through the
/// real reader and the CLI (the unit tests in roughness.rs check the full table).
#[test]
fn canonical_surface_reproduces_the_reference_table_through_the_cli() {
    let f = test_data().join("surfaces/gaussian_acf_256_seed12345.txt");
    assert!(
        f.is_file(),
        "{} missing (tests/data ships with the repository)",
        f.display()
    );
    // The table prints rounded numbers: `got` must round to the printed value, i.e. lie
    // within half a unit of its last printed digit (×10^exp for the unit).
    let close = |got: f64, printed: &str, exp: i32, what: &str| {
        let want: f64 = printed.parse().unwrap();
        let decimals = printed
            .split('.')
            .nth(1)
            .map_or(0, |d| d.split(['e', 'E']).next().unwrap().len());
        let mantissa_exp = printed
            .split(['e', 'E'])
            .nth(1)
            .map_or(0, |e| e.parse::<i32>().unwrap());
        let half_unit = 0.5 * 10f64.powi(mantissa_exp - decimals as i32);
        let got_scaled = got / 10f64.powi(exp);
        assert!(
            (got_scaled - want).abs() <= half_unit * (1.0 + 1e-9),
            "{what}: got {got_scaled}, reference prints {printed}"
        );
    };
    // 9-point summits, finite-difference moments (the defaults), periodic field.
    let j = surface_json(&f, &["--periodic", "--level", "mean"]);
    assert_eq!(j["nx"], 256);
    // σ was rescaled to 0.5 nm exactly; the ASCII file carries 13 significant digits.
    assert!(
        rel(j["sigma_m"].as_f64().unwrap(), 5.0e-10) < 1e-11,
        "sigma {}",
        j["sigma_m"]
    );
    close(j["m2"].as_f64().unwrap(), "1.26478e-3", 0, "m2 FD");
    close(j["m4_per_m2"].as_f64().unwrap(), "1.82771e13", 0, "m4 FD");
    close(j["alpha"].as_f64().unwrap(), "2.8564", 0, "alpha FD");
    close(
        j["nayak"]["eta_per_m2"].as_f64().unwrap(),
        "442.62",
        12,
        "eta FD",
    );
    close(j["nayak"]["R_m"].as_f64().unwrap(), "155.47", -9, "R FD");
    assert_eq!(
        j["n_summits"], 451,
        "9-point summit count (η = 451 µm⁻² on 1 µm²)"
    );
    close(j["R_m"].as_f64().unwrap(), "158.12", -9, "R 9-pt 1/mean κ");
    close(
        j["R_mean_of_inverse_m"].as_f64().unwrap(),
        "180.18",
        -9,
        "R 9-pt mean 1/κ",
    );
    close(j["beta"].as_f64().unwrap(), "0.035657", 0, "beta 9-pt");
    close(
        j["sigma_s_m"].as_f64().unwrap(),
        "0.38142e-9",
        0,
        "sigma_s 9-pt",
    );
    // 5-point summits.
    let j = surface_json(&f, &["--periodic", "--level", "mean", "--summits", "5"]);
    assert_eq!(j["n_summits"], 583);
    close(j["R_m"].as_f64().unwrap(), "163.86", -9, "R 5-pt");
    close(j["beta"].as_f64().unwrap(), "0.047765", 0, "beta 5-pt");
    // Birmingham-14 summits.
    let j = surface_json(&f, &["--periodic", "--level", "mean", "--birmingham"]);
    assert_eq!(j["n_summits"], 407);
    close(j["R_m"].as_f64().unwrap(), "154.05", -9, "R Birmingham");
    close(
        j["beta"].as_f64().unwrap(),
        "0.031350",
        0,
        "beta Birmingham",
    );
    // Spectral moments.
    let j = surface_json(
        &f,
        &["--periodic", "--level", "mean", "--moments", "spectral"],
    );
    close(j["m2"].as_f64().unwrap(), "1.28921e-3", 0, "m2 spectral");
    close(
        j["m4_per_m2"].as_f64().unwrap(),
        "1.94575e13",
        0,
        "m4 spectral",
    );
    close(
        j["nayak"]["eta_per_m2"].as_f64().unwrap(),
        "462.28",
        12,
        "eta spectral",
    );
    close(
        j["nayak"]["R_m"].as_f64().unwrap(),
        "150.68",
        -9,
        "R spectral",
    );
    close(
        j["nayak"]["beta"].as_f64().unwrap(),
        "0.034828",
        0,
        "beta spectral",
    );
}

#[test]
fn crop_analyses_only_the_rectangle() {
    let f = repo_root().join("raw/afm/disk_dlc_1um.gwy");
    let whole = surface_json(&f, &[]);
    let half = surface_json(&f, &["--crop", "0.5um,0um,0.5um,1um"]);
    assert_eq!(whole["nx"], 256);
    assert_eq!(half["nx"], 128);
    assert_eq!(half["ny"], 256);
    assert_eq!(
        half["crop_m"],
        serde_json::json!([0.5e-6, 0.0, 0.5e-6, 1e-6])
    );
    // A different area of the same surface: same statistics within sampling scatter.
    let (s1, s2) = (
        whole["sigma_m"].as_f64().unwrap(),
        half["sigma_m"].as_f64().unwrap(),
    );
    assert!(rel(s2, s1) < 0.15, "sigma {s2} vs {s1}");
    let o = hdi()
        .arg("surface")
        .arg(&f)
        .args(["--crop", "0.9um,0um,0.5um,1um"])
        .output()
        .unwrap();
    assert_clean_failure(&o, "crop x");
}

/// Two crops of the shipped disk scan in one `[surface.NAME]`: each area is the single-crop
/// analysis (the same numbers as `hdi surface --crop`), the table has one row per area, and
/// the mean and sample std are those of the rows.
#[test]
fn two_crops_give_an_area_table_with_mean_spread_and_bootstrap_interval() {
    let dir = tempfile::tempdir().unwrap();
    copy_dir(&repo_root().join("raw"), &dir.path().join("raw"));
    std::fs::write(
        dir.path().join("pipeline.toml"),
        r#"[project]
name = "areas"

[report]
validation = false

[surface.disk]
file = "raw/afm/disk_dlc_1um.gwy"
scale_sweep = false
crops = [
  { x0 = "0 um", y0 = "0 um", width = "0.5 um", height = "0.5 um" },
  { x0 = "0.5 um", y0 = "0.5 um", width = "0.5 um", height = "0.5 um" },
]
"#,
    )
    .unwrap();
    let o = hdi()
        .current_dir(dir.path())
        .args(["run"])
        .output()
        .unwrap();
    assert_ok(&o);
    let out = dir.path().join("processed");
    let found = |name: &str| {
        walk(&out)
            .into_iter()
            .find(|p| p.file_name().is_some_and(|f| f == name))
            .unwrap_or_else(|| panic!("{name} not written under {}", out.display()))
    };
    let rows = csv_rows(&found("areas.csv"));
    assert_eq!(rows.len(), 2);
    assert!(found("areas.parquet").exists() && found("areas.png").exists());
    let f = repo_root().join("raw/afm/disk_dlc_1um.gwy");
    let mut sig = Vec::new();
    for (row, crop) in rows
        .iter()
        .zip(["0um,0um,0.5um,0.5um", "0.5um,0.5um,0.5um,0.5um"])
    {
        let single = surface_json(&f, &["--crop", crop]);
        let s = row["sigma_nm"].parse::<f64>().unwrap();
        let want = single["sigma_m"].as_f64().unwrap() * 1e9;
        assert!(rel(s, want) < 1e-12, "{s} vs {want}");
        let r = row["R_um"].parse::<f64>().unwrap();
        assert!(rel(r, single["R_m"].as_f64().unwrap() * 1e6) < 1e-12);
        sig.push(s);
    }
    let mean = 0.5 * (sig[0] + sig[1]);
    // Sample std of two values: |a − b|/√2.
    let std = (sig[0] - sig[1]).abs() / 2f64.sqrt();
    let summary = csv_rows(&found("surfaces.csv"));
    let row = &summary[0];
    let got = |k: &str| row[k].parse::<f64>().unwrap();
    assert_eq!(got("n_areas"), 2.0);
    assert!(
        rel(got("sigma_nm_mean"), mean) < 1e-9,
        "{} vs {mean}",
        got("sigma_nm_mean")
    );
    assert!(
        rel(got("sigma_nm_std"), std) < 1e-9,
        "{} vs {std}",
        got("sigma_nm_std")
    );
    // With two areas the bootstrap means are a, b or (a + b)/2: the interval lies within
    // [min, max] and contains the mean.
    let (lo, hi) = (got("sigma_nm_ci95_low"), got("sigma_nm_ci95_high"));
    let (a, b) = (sig[0].min(sig[1]), sig[0].max(sig[1]));
    assert!(
        a - 1e-9 <= lo && lo <= mean && mean <= hi && hi <= b + 1e-9,
        "{lo} {hi}"
    );
}

fn walk(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                out.extend(walk(&p));
            } else {
                out.push(p);
            }
        }
    }
    out
}

/// `hdi surface FILE --out` is a one-instance pipeline run through the engine: its files are,
/// byte for byte, those of `hdi run` on a pipeline that declares the same map with the same
/// settings (the X3P of `--x3p-out` and `x3p = true` included), and its scratch store is gone
/// afterwards.
#[test]
fn a_one_off_surface_is_the_pipeline_instance_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    // A small map (64²) written by Gwyddion's format, so that the test costs little.
    let map = gaussian_acf_surface(&GaussianSurfaceSpec {
        n: 64,
        size: 0.25e-6,
        sigma: 0.5e-9,
        correlation_length: 20e-9,
        seed: 3,
    });
    let raw = dir.path().join("map.gwy");
    std::fs::write(&raw, encode_gwy(&map)).unwrap();
    let scratch = tempfile::tempdir().unwrap();
    let o = hdi()
        .env("TMPDIR", scratch.path())
        .arg("surface")
        .arg(&raw)
        .arg("--out")
        .arg(dir.path().join("one/disk.h5"))
        .arg("--x3p-out")
        .arg(dir.path().join("disk.x3p"))
        .output()
        .unwrap();
    assert_ok(&o);
    let left: Vec<_> = std::fs::read_dir(scratch.path()).unwrap().collect();
    assert!(left.is_empty(), "scratch store left behind: {left:?}");
    std::fs::write(
        dir.path().join("pipeline.toml"),
        format!(
            // (The report without the validation table, which costs seconds here.)
            "[project]\nname = \"t\"\n\n[report]\nvalidation = false\n\n[surface.disk]\nfile = {:?}\nx3p = true\n",
            raw.to_string_lossy()
        ),
    )
    .unwrap();
    let o = hdi()
        .current_dir(dir.path())
        .args(["run", "--config", "pipeline.toml"])
        .output()
        .unwrap();
    assert_ok(&o);
    let entry = dir.path().join("processed/disk");
    let mut compared = 0;
    for f in std::fs::read_dir(&entry).unwrap() {
        let name = f.unwrap().file_name().to_string_lossy().into_owned();
        if name == "result.json" || name == "manifest.json" {
            continue;
        }
        let one = dir.path().join("one").join(if name == "surface.h5" {
            "disk.h5"
        } else {
            name.as_str()
        });
        let same = std::fs::read(&one).unwrap() == std::fs::read(entry.join(&name)).unwrap();
        assert!(same, "{name} differs from the one-off's {}", one.display());
        compared += 1;
    }
    assert!(compared >= 5, "{compared} files compared");
    let x3p = std::fs::read(dir.path().join("disk.x3p")).unwrap();
    assert!(x3p == std::fs::read(entry.join("surface.x3p")).unwrap());
}

/// `hdi surface FILE --info`: what the file holds, every channel listed, without analysing it;
/// `--channel` picks another one (the NanoScope sample's four channels, two of them heights).
#[test]
fn info_lists_the_channels_and_the_metadata() {
    let file = test_data().join("surfaces/di-3.di");
    let o = hdi()
        .args(["surface", "--info", "--json"])
        .arg(&file)
        .output()
        .unwrap();
    assert_ok(&o);
    let info: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(info["format"], "nanoscope");
    assert_eq!(info["channel"], "Height Sensor");
    assert_eq!(
        (info["nx"].as_u64(), info["ny"].as_u64()),
        (Some(256), Some(256))
    );
    let channels = info["channels"].as_str().unwrap();
    for name in ["Height Sensor", "Amplitude Error", "Phase", "Height"] {
        assert!(channels.contains(name), "{channels}");
    }
    assert!(info["header"]["version"].is_string());
    let o = hdi()
        .args(["surface", "--info", "--channel", "Height"])
        .arg(&file)
        .output()
        .unwrap();
    assert_ok(&o);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.lines().any(|l| l == "  channel read  Height"),
        "{text}"
    );
}
