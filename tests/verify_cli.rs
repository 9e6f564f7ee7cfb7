//! `hdi verify` (docs/reliability.md): on a small pipeline — two surfaces, a contact set and a
//! two-case 2-DOF sweep (so both stage entries and per-case entries are in the store) — a
//! clean store exits 0; a data file edited behind the manifest's back, a deleted file and an
//! extra file exit 1 naming the entry and the file; `--repair` recomputes the damaged entries
//! and the outputs come back byte-identical; entries the pipeline no longer references are
//! reported as orphans and left in place.

use crate::common::*;
use serde_json::Value;
use std::path::{Path, PathBuf};

const PIPELINE: &str = r#"[project]
name = "verify test"

[surface.disk]
file = "raw/afm/disk_dlc_1um.gwy"

[surface.slider]
file = "raw/afm/slider_tfc_1um.spm"
filter_s = "16 nm"

[contact.improved]
parameter_set = "improved_2dof"

[simulate.sweep]
model = "improved_2dof"
contact = "improved"
dmw = "none"
actuations = ["4 nm", "12 nm"]
duration = "0.4 ms"
steady_start = "0.2 ms"
refine_touchdown = false

[report]
validation = false
"#;

fn project() -> Project {
    let dir = tempfile::tempdir().expect("tempdir");
    copy_dir(&repo_root().join("raw/afm"), &dir.path().join("raw/afm"));
    std::fs::write(dir.path().join("pipeline.toml"), PIPELINE).unwrap();
    Project { dir }
}

/// `hdi verify ARGS --json`: exit code and the document, checked against its schema.
fn verify(p: &Project, args: &[&str]) -> (Option<i32>, Value) {
    let mut all = vec!["verify", "--json"];
    all.extend_from_slice(args);
    let o = p.run(&all);
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    let text = stdout(&o);
    assert_matches_schema("verify", &text);
    let v: Value = serde_json::from_str(&text).unwrap();
    (o.status.code(), v)
}

/// The result files (what the determinism test compares): the store without the manifests
/// and the engine's bookkeeping, plus the tables.
fn results(p: &Project) -> Vec<(String, String)> {
    snapshot(&p.processed())
        .into_iter()
        .filter(|(rel, _)| !rel.starts_with(".hdi/") || rel.starts_with(".hdi/store/"))
        .filter(|(rel, _)| !rel.ends_with("manifest.json"))
        .filter(|(rel, _)| !rel.starts_with("report/"))
        .collect()
}

fn entry(p: &Project, name: &str) -> PathBuf {
    std::fs::canonicalize(p.processed().join(name)).unwrap()
}

/// A case entry of the sweep (the first of its `case_keys`).
fn case_entry(p: &Project) -> PathBuf {
    let result: Value =
        serde_json::from_slice(&std::fs::read(entry(p, "sweep").join("result.json")).unwrap())
            .unwrap();
    let key = result["case_keys"][0]
        .as_str()
        .expect("case_keys")
        .to_string();
    p.processed().join(".hdi/store/case").join(key)
}

fn flip_middle_byte(path: &Path) {
    let mut bytes = std::fs::read(path).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0x01;
    std::fs::write(path, bytes).unwrap();
}

fn damaged_files(v: &Value) -> Vec<(String, String, String)> {
    v["damaged"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|d| {
            d["problems"].as_array().unwrap().iter().map(move |pr| {
                (
                    d["path"].as_str().unwrap().to_string(),
                    pr["file"].as_str().unwrap().to_string(),
                    pr["problem"].as_str().unwrap().to_string(),
                )
            })
        })
        .collect()
}

#[test]
fn verify_detects_edited_deleted_and_extra_files_and_repair_restores_the_bytes() {
    let p = project();
    assert_ok(&p.run(&["run"]));
    let original = results(&p);
    assert!(original.len() > 10, "{original:?}");

    // Clean store: exit 0, every referenced entry checked, the two cases among them.
    let (code, v) = verify(&p, &[]);
    assert_eq!(code, Some(0), "{v}");
    assert_eq!(v["clean"], true);
    assert!(v["damaged"].as_array().unwrap().is_empty(), "{v}");
    // 4 stage entries + 2 cases.
    assert_eq!(v["entries_checked"], 6, "{v}");
    assert!(v["orphans"].as_array().unwrap().is_empty(), "{v}");
    let o = p.run(&["verify"]);
    assert_ok(&o);

    // One byte of the disk's HDF5 flipped; its manifest untouched.
    let disk = entry(&p, "disk");
    let manifest_before = std::fs::read(disk.join("manifest.json")).unwrap();
    flip_middle_byte(&disk.join("surface.h5"));
    assert_eq!(
        std::fs::read(disk.join("manifest.json")).unwrap(),
        manifest_before
    );
    let disk_rel = format!(
        ".hdi/store/surface/{}",
        disk.file_name().unwrap().to_string_lossy()
    );
    let (code, v) = verify(&p, &[]);
    assert_eq!(code, Some(1), "{v}");
    assert_eq!(v["clean"], false);
    assert_eq!(
        damaged_files(&v),
        vec![(disk_rel.clone(), "surface.h5".into(), "changed".into())]
    );
    assert_eq!(v["damaged"][0]["referenced_by"][0], "disk");
    // The text output names the entry, the instance and the file.
    let o = p.run(&["verify"]);
    assert_eq!(o.status.code(), Some(1));
    let text = stdout(&o);
    assert!(
        text.contains(&format!("damaged  {disk_rel} (disk)")),
        "{text}"
    );
    assert!(text.contains("surface.h5: changed since written"), "{text}");

    // A case's file deleted and an extra file in the slider's entry.
    let case = case_entry(&p);
    let case_file = std::fs::read_dir(&case)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().to_string())
        .find(|f| f != "manifest.json" && f != "result.json")
        .expect("a case data file");
    std::fs::remove_file(case.join(&case_file)).unwrap();
    std::fs::write(entry(&p, "slider").join("notes.txt"), b"mine").unwrap();
    let (code, v) = verify(&p, &[]);
    assert_eq!(code, Some(1));
    let found = damaged_files(&v);
    let case_rel = format!(
        ".hdi/store/case/{}",
        case.file_name().unwrap().to_string_lossy()
    );
    assert!(
        found.contains(&(case_rel.clone(), case_file.clone(), "missing".into())),
        "{found:?}"
    );
    assert!(
        found
            .iter()
            .any(|(_, f, k)| f == "notes.txt" && k == "extra"),
        "{found:?}"
    );
    assert_eq!(found.len(), 3, "{found:?}");
    let case_damage = v["damaged"]
        .as_array()
        .unwrap()
        .iter()
        .find(|d| d["path"] == case_rel.as_str())
        .unwrap();
    assert_eq!(case_damage["referenced_by"][0], "case of sweep");

    // --repair: the damaged entries move aside, their instances re-run, the store verifies
    // clean and every result file is byte-for-byte what the first run wrote.
    let (code, v) = verify(&p, &["--repair"]);
    assert_eq!(code, Some(0), "{v}");
    assert_eq!(v["clean"], true);
    assert_eq!(v["repair"]["damaged_before"].as_array().unwrap().len(), 3);
    let rerun: Vec<&str> = v["repair"]["rerun"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r.as_str().unwrap())
        .collect();
    assert_eq!(rerun, ["disk", "slider", "sweep"]);
    for m in v["repair"]["moved"].as_array().unwrap() {
        assert!(m.as_str().unwrap().starts_with(".hdi/tmp/"), "{m}");
    }
    assert_eq!(
        results(&p),
        original,
        "repaired outputs differ from the originals"
    );
    assert!(!entry(&p, "slider").join("notes.txt").exists());
    let (code, _) = verify(&p, &[]);
    assert_eq!(code, Some(0));
}

#[test]
fn orphans_are_reported_not_removed_and_all_checks_them() {
    let p = project();
    assert_ok(&p.run(&["run"]));
    let old_disk = entry(&p, "disk");
    // A new cutoff: the disk's old entry (and its ref's target) is now unreferenced.
    p.set_config(&PIPELINE.replace(
        "file = \"raw/afm/disk_dlc_1um.gwy\"\n",
        "file = \"raw/afm/disk_dlc_1um.gwy\"\nfilter_l = \"250 nm\"\n",
    ));
    assert_ok(&p.run(&["run", "--only", "disk"]));
    assert_ne!(entry(&p, "disk"), old_disk);
    let (code, v) = verify(&p, &[]);
    assert_eq!(code, Some(0), "{v}");
    let orphans: Vec<&str> = v["orphans"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| o["path"].as_str().unwrap())
        .collect();
    let old_rel = format!(
        ".hdi/store/surface/{}",
        old_disk.file_name().unwrap().to_string_lossy()
    );
    assert_eq!(orphans, [old_rel.as_str()]);
    assert!(old_disk.is_dir(), "verify must not remove an orphan");
    assert_eq!(v["scope"], "pipeline");

    // A damaged orphan is damage only when --all checks it.
    flip_middle_byte(&old_disk.join("surface.h5"));
    let (code, v) = verify(&p, &[]);
    assert_eq!(code, Some(0), "{v}");
    let (code, v) = verify(&p, &["--all"]);
    assert_eq!(code, Some(1), "{v}");
    assert_eq!(v["scope"], "all");
    assert_eq!(
        damaged_files(&v),
        vec![(old_rel, "surface.h5".into(), "changed".into())]
    );
    assert!(v["damaged"][0]["referenced_by"]
        .as_array()
        .unwrap()
        .is_empty());
}
