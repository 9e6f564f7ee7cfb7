use super::*;
use serde_json::json;
use std::time::Instant;

fn spec(kind: &str, i: usize) -> CaseSpec {
    CaseSpec::new(
        kind,
        "test-1",
        json!({"actuation_m": i as f64 * 1e-10, "contact_key": "abc"}),
        json!({"index": i}),
    )
}

/// Writes `value.txt` and returns `{"value": 2i}`; recipe `{"fail": true}` fails.
fn registry() -> CaseRegistry {
    let mut r = CaseRegistry::new();
    r.register("double", |recipe: &Value, _: &Store, dir: &Path| {
        if recipe["fail"] == true {
            return Err(std::io::Error::other("integrator step size underflow"));
        }
        let v = recipe["index"].as_u64().unwrap() * 2;
        std::fs::write(dir.join("value.txt"), v.to_string()).unwrap();
        Ok(json!({ "value": v }))
    });
    r
}

#[test]
fn spec_key_is_the_case_cache_key() {
    let s = spec("double", 3);
    assert_eq!(s.key, cases::case_fingerprint("test-1", &s.params).key());
    assert_eq!(
        "slurm".parse::<ExecutorKind>().unwrap(),
        ExecutorKind::Slurm
    );
    assert_eq!(ExecutorKind::default(), ExecutorKind::Local);
    assert!("pbs".parse::<ExecutorKind>().is_err());
}

#[test]
fn manifest_round_trips_and_refuses_other_schemas() {
    let dir = tempfile::tempdir().unwrap();
    let mut specs: Vec<CaseSpec> = (0..5).map(|i| spec("double", i)).collect();
    specs.push(spec("double", 2)); // duplicate key: dropped
    let m = CaseManifest::new(specs, 2).unwrap();
    assert_eq!(m.cases.len(), 5);
    assert_eq!(m.task_count(), 3);
    assert_eq!(m.task_range(2).unwrap(), 4..5);
    assert!(matches!(
        m.task_range(3),
        Err(ExecutorError::TaskOutOfRange {
            task: 3,
            tasks: 3,
            ..
        })
    ));
    assert!(CaseManifest::new(Vec::new(), 0).is_err());

    let path = manifest_path(dir.path(), &m.id());
    assert!(path.starts_with(dir.path().join(".hdi/slurm/manifests")));
    m.write(&path).unwrap();
    assert_eq!(CaseManifest::read(&path).unwrap(), m);
    // No temp files left beside it.
    assert_eq!(
        std::fs::read_dir(path.parent().unwrap()).unwrap().count(),
        1
    );

    let mut v: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    assert_eq!(v["cases"][0]["status"], json!({"state": "pending"}));
    assert_eq!(v["cases"][0]["kind"], "double");
    v["schema_version"] = json!(99);
    std::fs::write(&path, v.to_string()).unwrap();
    let e = CaseManifest::read(&path).unwrap_err();
    assert!(e.to_string().contains("schema version 99"), "{e}");
}

/// Every versioned file names itself and both versions when refused; a file of issue 9's
/// layout (manifest `schema_version: 1`, outcomes and job records without one) is version 1.
#[test]
fn manifests_outcomes_and_job_records_of_other_versions_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let m = CaseManifest::new((0..2).map(|i| spec("double", i)).collect(), 1).unwrap();
    let path = manifest_path(dir.path(), &m.id());
    m.write(&path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.starts_with("{\"schema_version\":3,"), "{text}");
    let expect_refusal = |e: ExecutorError, file: &Path, found: &str| {
        let msg = e.to_string();
        assert!(
            msg.contains(&file.display().to_string())
                && msg.contains(&format!("schema version {found}"))
                && msg.contains("reads schema version 3"),
            "{msg}"
        );
    };
    // The manifest: version 1, missing, and not a number.
    let mut v: Value = serde_json::from_str(&text).unwrap();
    v["schema_version"] = json!(1);
    let e = CaseManifest::from_json_slice(v.to_string().as_bytes(), &path).unwrap_err();
    expect_refusal(e, &path, "1");
    v.as_object_mut().unwrap().remove("schema_version");
    let e = CaseManifest::from_json_slice(v.to_string().as_bytes(), &path).unwrap_err();
    expect_refusal(e, &path, "1");
    // Issue 21's layout (its recipes were per kind).
    v["schema_version"] = json!(2);
    let e = CaseManifest::from_json_slice(v.to_string().as_bytes(), &path).unwrap_err();
    expect_refusal(e, &path, "2");
    v["schema_version"] = json!(2.5);
    let e = CaseManifest::from_json_slice(v.to_string().as_bytes(), &path).unwrap_err();
    assert!(e.to_string().contains("not a version number"), "{e}");
    // Garbage and a zero task size are errors, not panics.
    for bad in [
        &b""[..],
        b"[",
        b"{\"schema_version\":2}",
        b"\xff\xfe",
        b"null",
    ] {
        assert!(CaseManifest::from_json_slice(bad, &path).is_err());
    }
    v["schema_version"] = json!(MANIFEST_SCHEMA_VERSION);
    v["cases_per_task"] = json!(0);
    let e = CaseManifest::from_json_slice(v.to_string().as_bytes(), &path).unwrap_err();
    assert!(e.to_string().contains("cases_per_task is 0"), "{e}");

    // An outcome file without a version (issue 9's layout).
    let out = outcome_dir(&path);
    std::fs::create_dir_all(&out).unwrap();
    let outcome = out.join("0.json");
    std::fs::write(
        &outcome,
        json!({"index": 0, "key": m.cases[0].spec.key, "status": {"state": "done"}}).to_string(),
    )
    .unwrap();
    let e = m.clone().merge_outcomes(&path).unwrap_err();
    expect_refusal(e, &outcome, "1");
    // The current layout is read.
    let current = CaseOutcome {
        schema_version: MANIFEST_SCHEMA_VERSION,
        index: 0,
        key: m.cases[0].spec.key.clone(),
        status: CaseStatus::Done,
    };
    std::fs::write(&outcome, serde_json::to_vec(&current).unwrap()).unwrap();
    let mut merged = m.clone();
    assert_eq!(merged.merge_outcomes(&path).unwrap(), 1);
    assert_eq!(merged.cases[0].status, CaseStatus::Done);

    // Job records: issue 9 wrote a bare array; version 2 on an object with the version.
    let jobs = submissions_path(&path);
    let record = SubmissionRecord {
        job_id: 7,
        offset: 0,
        tasks: 2,
        submitted: "2026-01-01T00:00:00Z".into(),
    };
    write_submissions(&path, std::slice::from_ref(&record)).unwrap();
    let written: Value = serde_json::from_slice(&std::fs::read(&jobs).unwrap()).unwrap();
    assert_eq!(written["schema_version"], json!(MANIFEST_SCHEMA_VERSION));
    assert_eq!(read_submissions(&path).unwrap(), vec![record.clone()]);
    std::fs::write(&jobs, json!([record]).to_string()).unwrap();
    let e = read_submissions(&path).unwrap_err();
    expect_refusal(e, &jobs, "1");
}

#[test]
fn tasks_fill_the_cache_record_failures_and_resubmit_only_those() {
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    let mut specs: Vec<CaseSpec> = (0..5).map(|i| spec("double", i)).collect();
    specs[3].recipe = json!({"fail": true});
    let mut m = CaseManifest::new(specs, 2).unwrap();
    let path = manifest_path(dir.path(), &m.id());
    m.write(&path).unwrap();

    let reg = registry();
    let identity = TaskIdentity {
        job_id: Some(4242),
        task_id: Some(1),
        log: Some(slurm::log_path(dir.path(), 4242, 1)),
    };
    let mut reports = Vec::new();
    for task in 0..m.task_count() {
        reports.push(exec_task(&store, &path, task, &reg, &identity).unwrap());
    }
    let computed: usize = reports.iter().map(|r| r.computed).sum();
    assert_eq!(computed, 4);
    assert_eq!(reports[1].failed, 1);
    assert!(
        store.tmp_dirs().is_empty(),
        "a failed case leaves no work dir"
    );

    assert_eq!(m.merge_outcomes(&path).unwrap(), 5);
    assert_eq!(m.counts(), (0, 4, 1));
    let failed: Vec<_> = m.failed().collect();
    assert_eq!(failed.len(), 1);
    let (index, entry) = failed[0];
    assert_eq!(index, 3);
    match &entry.status {
        CaseStatus::Failed {
            error,
            job_id,
            task_id,
            log,
        } => {
            assert!(error.contains("step size underflow"), "{error}");
            assert_eq!((*job_id, *task_id), (Some(4242), Some(1)));
            assert!(log.as_ref().unwrap().ends_with(".hdi/slurm/4242_1.log"));
        }
        other => panic!("{other:?}"),
    }
    // Merging again changes nothing.
    assert_eq!(m.merge_outcomes(&path).unwrap(), 0);

    // The cache holds the four good cases, byte for byte what a local run writes.
    let local = cases::get_or_compute(
        &store,
        "test-1",
        &m.cases[4].spec.params,
        |_| -> Result<Value, CaseFailure> { panic!("must be cached") },
    )
    .unwrap();
    assert!(local.cached && local.result == json!({"value": 8}));

    // Resubmission: only the failed case is missing; fixed, it completes.
    let mut missing = m.still_missing(&store);
    assert_eq!(missing.len(), 1);
    assert_eq!(missing[0].key, m.cases[3].spec.key);
    missing[0].recipe = json!({"index": 3});
    let mut again = CaseManifest::new(missing, 2).unwrap();
    let path2 = manifest_path(dir.path(), &format!("{}-retry", again.id()));
    again.write(&path2).unwrap();
    let r = exec_task(&store, &path2, 0, &reg, &TaskIdentity::default()).unwrap();
    assert_eq!(
        r,
        TaskReport {
            computed: 1,
            cached: 0,
            failed: 0
        }
    );
    again.merge_outcomes(&path2).unwrap();
    assert_eq!(again.counts(), (0, 1, 0));
    assert!(m.still_missing(&store).is_empty());

    // A re-run task (pre-empted and requeued) finds its cases cached.
    let r = exec_task(&store, &path, 0, &reg, &identity).unwrap();
    assert_eq!(
        r,
        TaskReport {
            computed: 0,
            cached: 2,
            failed: 0
        }
    );
    assert!(exec_task(&store, &path, 3, &reg, &identity).is_err());
}

#[test]
fn unregistered_kinds_fail_per_case_naming_what_is_missing() {
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    let m = CaseManifest::new(vec![spec("simulate", 1)], 1).unwrap();
    let path = manifest_path(dir.path(), &m.id());
    m.write(&path).unwrap();
    let r = exec_task(
        &store,
        &path,
        0,
        &CaseRegistry::new(),
        &TaskIdentity::default(),
    );
    assert_eq!(r.unwrap().failed, 1);
    let mut m = m;
    m.merge_outcomes(&path).unwrap();
    let (_, entry) = m.failed().next().unwrap();
    let CaseStatus::Failed { error, job_id, .. } = &entry.status else {
        panic!("{:?}", entry.status)
    };
    assert!(job_id.is_none());
    assert!(
        error.contains("`simulate` has no worker registered (registered: none)"),
        "{error}"
    );
    let partial = registry();
    let e = partial
        .compute_case("doe", &json!({}), &store, dir.path())
        .unwrap_err()
        .to_string();
    assert!(e.contains("(registered: double)"), "{e}");
}

#[test]
fn a_key_from_another_hdi_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    let mut s = spec("double", 1);
    s.key = "0".repeat(64);
    let m = CaseManifest::new(vec![s], 1).unwrap();
    let path = manifest_path(dir.path(), &m.id());
    m.write(&path).unwrap();
    let r = exec_task(&store, &path, 0, &registry(), &TaskIdentity::default()).unwrap();
    assert_eq!(r.failed, 1);
    let mut m = m;
    m.merge_outcomes(&path).unwrap();
    let (_, e) = m.failed().next().unwrap();
    assert!(
        matches!(&e.status, CaseStatus::Failed { error, .. } if error.contains("key mismatch"))
    );
}

/// Not a pass/fail timing (shared CI machines vary); run with `--nocapture` to see the
/// numbers recorded in docs/slurm.md. The budget is < 2 s to submit.
#[test]
fn ten_thousand_case_manifest_timing_note() {
    let dir = tempfile::tempdir().unwrap();
    let t0 = Instant::now();
    let specs: Vec<CaseSpec> = (0..10_000).map(|i| spec("double", i)).collect();
    let t_specs = t0.elapsed();
    let m = CaseManifest::new(specs, 10).unwrap();
    let path = manifest_path(dir.path(), &m.id());
    let t1 = Instant::now();
    m.write(&path).unwrap();
    let t_write = t1.elapsed();
    let t2 = Instant::now();
    let back = CaseManifest::read(&path).unwrap();
    let t_read = t2.elapsed();
    let arrays = plan_arrays(back.cases.len(), back.cases_per_task, 1000).unwrap();
    assert_eq!(arrays.len(), 1);
    assert_eq!(arrays[0].tasks, 1000);
    let bytes = std::fs::metadata(&path).unwrap().len();
    eprintln!(
        "10,000 cases: specs+keys {t_specs:?}, write {t_write:?} ({} kB), read {t_read:?}",
        bytes / 1024
    );
}
