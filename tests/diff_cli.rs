//! `hdi diff A B` (docs/diff.md): instances, params and metric deltas between two pipeline
//! files or two processed directories; exit 0 identical, 1 different, 2 error.

use crate::common::{
    self, assert_clean_failure, assert_matches_schema, hdi, stderr, stdout, Project,
};
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::process::Output;

fn diff_json(dir: &Path, a: &Path, b: &Path, extra: &[&str]) -> (Output, Value) {
    let o = hdi()
        .current_dir(dir)
        .arg("diff")
        .arg(a)
        .arg(b)
        .arg("--json")
        .args(extra)
        .output()
        .expect("run hdi diff");
    let text = stdout(&o);
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    let v: Value = serde_json::from_str(&text)
        .unwrap_or_else(|e| panic!("not JSON ({e}): {text}{}", stderr(&o)));
    assert_matches_schema("diff", &text);
    (o, v)
}

fn names_with_status(v: &Value, status: &str) -> BTreeSet<String> {
    v["instances"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|i| i["status"] == status)
        .map(|i| i["name"].as_str().unwrap().to_string())
        .collect()
}

/// The shipped pipeline as pipeline.toml and a copy with the slider's S-filter doubled.
#[test]
fn pipeline_files_differing_in_one_parameter_change_that_instance_and_its_consumers() {
    let p = Project::shipped();
    let cfg = p.config();
    // The slider's S-filter is the only uncommented `filter_s` line.
    let line = "\nfilter_s = \"16 nm\"\n";
    assert_eq!(cfg.matches(line).count(), 1);
    let changed_cfg = cfg.replace(line, "\nfilter_s = \"32 nm\"\n");
    std::fs::write(p.path().join("changed.toml"), changed_cfg).unwrap();
    let (o, v) = diff_json(
        p.path(),
        Path::new("pipeline.toml"),
        Path::new("changed.toml"),
        &[],
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!(v["identical"], false);
    assert_eq!(v["a"]["source"], "pipeline");
    // Who consumes whom, read off pipeline.toml: [interface.hdi] surfaces = ["disk",
    // "slider"]; [contact.measured] interface = "hdi"; [contact_bem.bem_measured] reads the
    // slider's map (through `hdi`) and `measured`'s curves; nothing names `bem_measured`.
    let expected: BTreeSet<String> = ["slider", "hdi", "measured", "bem_measured"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    assert_eq!(names_with_status(&v, "changed"), expected);
    assert!(names_with_status(&v, "added").is_empty());
    assert!(names_with_status(&v, "removed").is_empty());
    let n_instances = cfg
        .lines()
        // Instances are `[kind.name]` tables (`[project]`, `[report]` are settings).
        .filter(|l| l.starts_with('[') && l.trim_end().trim_end_matches(']').contains('.'))
        .count();
    assert_eq!(v["summary"]["unchanged"], n_instances as u64 - 4);
    // Exactly one parameter: the S-filter cut-off in metres.
    let params = v["params"].as_array().unwrap();
    assert_eq!(params.len(), 1, "{params:?}");
    assert_eq!(params[0]["instance"], "slider");
    assert_eq!(params[0]["key"], "surface.slider.filter_s_m");
    assert!((params[0]["old"].as_f64().unwrap() - 16e-9).abs() < 1e-21);
    assert!((params[0]["new"].as_f64().unwrap() - 32e-9).abs() < 1e-21);
    let hdi_why = &v["instances"]
        .as_array()
        .unwrap()
        .iter()
        .find(|i| i["name"] == "hdi")
        .unwrap()["why"];
    assert!(
        hdi_why.to_string().contains("upstream slider changed"),
        "{hdi_why}"
    );
    // Nothing ran: no metrics, and diff wrote nothing.
    assert!(v["metrics"].as_array().unwrap().is_empty());
    assert!(!p.processed().exists());

    // The text form names the same parameter and instance.
    let o = p.run(&["diff", "pipeline.toml", "changed.toml"]);
    assert_eq!(o.status.code(), Some(1));
    let text = stdout(&o);
    assert!(text.contains("surface.slider.filter_s_m"), "{text}");
    assert!(
        text.lines()
            .any(|l| l.starts_with("measured") && l.contains("changed")),
        "{text}"
    );

    // The same pipeline beside a copy of raw/ whose slider scan differs by one byte: no
    // parameter differs, the input hash does, and the change reaches the same consumers.
    let other = p.path().join("other");
    common::copy_dir(&p.path().join("raw"), &other.join("raw"));
    std::fs::write(other.join("pipeline.toml"), &cfg).unwrap();
    let scan = other.join("raw/afm/slider_tfc_1um.spm");
    let mut bytes = std::fs::read(&scan).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    std::fs::write(&scan, bytes).unwrap();
    let (o, v) = diff_json(
        p.path(),
        Path::new("pipeline.toml"),
        Path::new("other/pipeline.toml"),
        &[],
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!(names_with_status(&v, "changed"), expected);
    assert!(
        v["params"].as_array().unwrap().is_empty(),
        "{}",
        v["params"]
    );
    let slider_why = v["instances"]
        .as_array()
        .unwrap()
        .iter()
        .find(|i| i["name"] == "slider")
        .unwrap()["why"]
        .to_string();
    assert!(slider_why.contains("slider_tfc_1um.spm"), "{slider_why}");

    // A pipeline file against itself: identical.
    let o = p.run(&["diff", "pipeline.toml", "pipeline.toml"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(stdout(&o), "");
}

/// A JSON value as hdi diff reports it against the CSV cell it came from: empty → null,
/// numbers numerically, text as text.
fn cell_matches(v: &Value, cell: &str) -> bool {
    match (v, cell.parse::<f64>()) {
        (Value::Null, _) => cell.is_empty(),
        (Value::Number(n), Ok(x)) => n.as_f64() == Some(x),
        (Value::Bool(b), _) => cell == b.to_string(),
        (Value::String(s), _) => s == cell,
        _ => false,
    }
}

const SMALL: &str = "[project]\nname = \"diff test\"\n\n[report]\nvalidation = false\n\n[surface.disk]\nfile = \"raw/afm/disk_dlc_1um.gwy\"\n\n[surface.slider]\nfile = \"raw/afm/slider_tfc_1um.spm\"\nfilter_s = \"16 nm\"\n\n[interface.hdi]\nsurfaces = [\"disk\", \"slider\"]\nrule = \"sum_surface\"\n";

fn cp_a(from: &Path, to: &Path) {
    let o = std::process::Command::new("cp")
        .arg("-a")
        .arg(from)
        .arg(to)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A tiny pipeline run twice, the disk's L-filter set the second time: the diff of the two
/// processed directories equals what the two CSV tables say, cell by cell.
#[test]
fn processed_dirs_metric_deltas_match_the_tables() {
    let p = Project::shipped();
    p.set_config(SMALL);
    common::assert_ok(&p.run(&["run", "-j", "2"]));
    let before = p.path().join("before");
    cp_a(&p.processed(), &before);
    p.set_config(&SMALL.replace(
        "file = \"raw/afm/disk_dlc_1um.gwy\"\n",
        "file = \"raw/afm/disk_dlc_1um.gwy\"\nfilter_l = \"250 nm\"\n",
    ));
    common::assert_ok(&p.run(&["run", "-j", "2"]));

    // Identical directories: exit 0, nothing listed.
    let (o, v) = diff_json(p.path(), &before, &before, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(v["identical"], true);
    for k in ["instances", "params", "metrics"] {
        assert!(v[k].as_array().unwrap().is_empty(), "{k}: {}", v[k]);
    }
    assert_eq!(v["summary"]["unchanged"], 3);
    let o = p.run(&["diff", "before", "before"]);
    assert_eq!(o.status.code(), Some(0));
    assert_eq!(stdout(&o), "");

    // A processed directory and the pipeline that wrote it (mixed kinds): identical keys.
    let o = p.run(&["diff", "processed", "pipeline.toml"]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));

    let (o, v) = diff_json(p.path(), &before, &p.processed(), &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!(
        names_with_status(&v, "changed"),
        ["disk", "hdi"].iter().map(|s| s.to_string()).collect()
    );
    let params = v["params"].as_array().unwrap();
    assert_eq!(params.len(), 1, "{params:?}");
    assert_eq!(params[0]["key"], "surface.disk.filter_l_m");
    assert_eq!(params[0]["old"], Value::Null);
    assert!((params[0]["new"].as_f64().unwrap() - 250e-9).abs() < 1e-20);

    // Every cell of every table, compared independently of hdi's CSV reader.
    let mut expected: BTreeMap<(String, String, String), (String, String)> = BTreeMap::new();
    let mut n_cells = 0;
    for e in std::fs::read_dir(before.join("tables")).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().to_string();
        if !name.ends_with(".csv") {
            continue;
        }
        let old = common::csv_rows(&before.join("tables").join(&name));
        let new = common::csv_rows(&p.processed().join("tables").join(&name));
        assert_eq!(old.len(), new.len());
        for (ro, rn) in old.iter().zip(&new) {
            assert_eq!(ro["stage"], rn["stage"]);
            for (col, x) in ro {
                n_cells += 1;
                let y = &rn[col];
                if x != y {
                    expected.insert(
                        (ro["stage"].clone(), name.clone(), col.clone()),
                        (x.clone(), y.clone()),
                    );
                }
            }
        }
    }
    assert!(
        n_cells > 40,
        "tables too small to say much: {n_cells} cells"
    );
    let got: BTreeMap<(String, String, String), &Value> = v["metrics"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["source"].as_str().unwrap().ends_with(".csv"))
        .map(|m| {
            (
                (
                    m["instance"].as_str().unwrap().to_string(),
                    m["source"].as_str().unwrap().to_string(),
                    m["metric"].as_str().unwrap().to_string(),
                ),
                m,
            )
        })
        .collect();
    assert_eq!(
        got.keys().collect::<Vec<_>>(),
        expected.keys().collect::<Vec<_>>(),
        "changed table cells"
    );
    assert!(
        expected.contains_key(&(
            String::from("disk"),
            String::from("surfaces.csv"),
            String::from("sigma_nm")
        )),
        "the L-filter changes σ: {expected:?}"
    );
    let mut numeric = 0;
    for (k, (x, y)) in &expected {
        let m = got[k];
        match (x.parse::<f64>(), y.parse::<f64>()) {
            (Ok(x), Ok(y)) if x.is_finite() && y.is_finite() => {
                numeric += 1;
                let d = m["delta"].as_f64().unwrap();
                assert!((d - (y - x)).abs() <= 1e-12 * y.abs().max(x.abs()), "{k:?}");
                assert!(
                    (m["old"].as_f64().unwrap() - x).abs() <= 1e-15 * x.abs(),
                    "{k:?}"
                );
                if x != 0.0 {
                    let r = m["rel_delta"].as_f64().unwrap();
                    assert!((r - (y - x) / x.abs()).abs() <= 1e-12 * r.abs().max(1e-300));
                }
            }
            _ => {
                assert_eq!(m["delta"], Value::Null, "{k:?}");
                assert!(cell_matches(&m["old"], x), "{k:?}: {m}");
                assert!(cell_matches(&m["new"], y), "{k:?}: {m}");
            }
        }
    }
    assert!(numeric >= 3, "{expected:?}");

    // Tables present only as Parquet (CSV deleted) give the same changes and deltas.
    let (pa, pb) = (p.path().join("a_pq"), p.path().join("b_pq"));
    cp_a(&before, &pa);
    cp_a(&p.processed(), &pb);
    for d in [&pa, &pb] {
        for e in std::fs::read_dir(d.join("tables")).unwrap() {
            let f = e.unwrap().path();
            if f.extension().is_some_and(|x| x == "csv") {
                std::fs::remove_file(f).unwrap();
            }
        }
    }
    let (_, pq) = diff_json(p.path(), &pa, &pb, &[]);
    let from_parquet: BTreeMap<(String, String, String), &Value> = pq["metrics"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["source"].as_str().unwrap().ends_with(".parquet"))
        .map(|m| {
            (
                (
                    m["instance"].as_str().unwrap().to_string(),
                    m["source"].as_str().unwrap().replace(".parquet", ".csv"),
                    m["metric"].as_str().unwrap().to_string(),
                ),
                m,
            )
        })
        .collect();
    assert_eq!(
        from_parquet.keys().collect::<Vec<_>>(),
        got.keys().collect::<Vec<_>>()
    );
    for (k, m) in &from_parquet {
        match (m["delta"].as_f64(), got[k]["delta"].as_f64()) {
            (Some(x), Some(y)) => assert!((x - y).abs() <= 1e-12 * x.abs().max(y.abs()), "{k:?}"),
            (x, y) => assert_eq!(x, y, "{k:?}"),
        }
    }

    // --all lists the unchanged slider and its unchanged metrics too.
    let (_, all) = diff_json(p.path(), &before, &p.processed(), &["--all"]);
    assert_eq!(
        names_with_status(&all, "unchanged"),
        ["slider".to_string()].into()
    );
    assert!(all["metrics"]
        .as_array()
        .unwrap()
        .iter()
        .any(|m| m["instance"] == "slider" && m["changed"] == false));
    assert_eq!(
        all["metrics"].as_array().unwrap().len() as u64,
        all["summary"]["metrics_compared"].as_u64().unwrap()
    );

    // A huge --rtol hides every numeric change; the instance changes remain.
    let (o, loose) = diff_json(p.path(), &before, &p.processed(), &["--rtol", "1e9"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(loose["metrics"]
        .as_array()
        .unwrap()
        .iter()
        .all(|m| m["delta"].is_null()));
}

#[test]
fn bad_paths_are_one_clear_error_with_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let o = hdi()
        .current_dir(dir.path())
        .args(["diff", "nowhere", "nowhere2"])
        .output()
        .unwrap();
    assert_clean_failure(&o, "nowhere: no such file or directory");
    assert_eq!(o.status.code(), Some(2));

    std::fs::create_dir(dir.path().join("plain")).unwrap();
    let o = hdi()
        .current_dir(dir.path())
        .args(["diff", "plain", "plain"])
        .output()
        .unwrap();
    assert_clean_failure(&o, "plain: not a processed directory");
    assert_eq!(o.status.code(), Some(2));
    std::fs::write(dir.path().join("plain/pipeline.toml"), "").unwrap();
    let o = hdi()
        .current_dir(dir.path())
        .args(["diff", "plain", "plain"])
        .output()
        .unwrap();
    assert_clean_failure(&o, "(did you mean plain/pipeline.toml?)");

    std::fs::write(
        dir.path().join("bad.toml"),
        "[project]\nname = 1\n[surfac.x]\n",
    )
    .unwrap();
    let o = hdi()
        .current_dir(dir.path())
        .args(["diff", "bad.toml", "bad.toml"])
        .output()
        .unwrap();
    assert_clean_failure(&o, "bad.toml");
    assert_eq!(o.status.code(), Some(2));

    let o = hdi()
        .current_dir(dir.path())
        .args(["diff", "plain", "plain", "--rtol=-1"])
        .output()
        .unwrap();
    assert_clean_failure(&o, "--rtol must be a finite number");
    assert_eq!(o.status.code(), Some(2));
}

/// A model parameter changed in a `[simulate]` table shows up as a readable dotted key of the
/// model's fields (key params are plain data, docs/architecture.md), with SI numbers on both
/// sides — not as a changed `Debug` string of the whole model.
#[test]
fn a_changed_model_parameter_is_a_readable_dotted_key() {
    let p = Project::shipped();
    let cfg = p.config();
    // The optimised sweep's assumed bulge width (§2.3: dropped from the text, 50 µm assumed).
    let line = "[simulate.optimised_sweep]\nmodel = \"improved_2dof\"\ngeometry = \"optimised\"\nbulge_width = \"50 um\"\n";
    assert_eq!(cfg.matches(line).count(), 1);
    std::fs::write(
        p.path().join("wider.toml"),
        cfg.replace(line, &line.replace("50 um", "60 um")),
    )
    .unwrap();
    let (o, v) = diff_json(
        p.path(),
        Path::new("pipeline.toml"),
        Path::new("wider.toml"),
        &[],
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let mine: Vec<&Value> = v["params"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|d| d["instance"] == "optimised_sweep")
        .collect();
    assert_eq!(mine.len(), 1, "{mine:?}");
    let key = "simulate.optimised_sweep.model_parameters.bulge.full_width_y";
    assert_eq!(mine[0]["key"], key);
    assert!((mine[0]["old"].as_f64().unwrap() - 50e-6).abs() < 1e-18);
    assert!((mine[0]["new"].as_f64().unwrap() - 60e-6).abs() < 1e-18);
    // Every changed parameter (the sweep's and its consumers') is a number or a word.
    for d in v["params"].as_array().unwrap() {
        for side in ["old", "new"] {
            let s = d[side].as_str().unwrap_or("");
            assert!(!s.contains(" {") && !s.contains('('), "{d}");
        }
    }
    // The text form and `hdi status`'s reason name the same dotted field.
    let o = p.run(&["diff", "pipeline.toml", "wider.toml"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stdout(&o).contains(key), "{}", stdout(&o));
    let why = v["instances"]
        .as_array()
        .unwrap()
        .iter()
        .find(|i| i["name"] == "optimised_sweep")
        .unwrap()["why"]
        .to_string();
    assert!(
        why.contains("model_parameters.bulge.full_width_y: 0.00005 → 0.00006"),
        "{why}"
    );
}
