//! The spine end to end on the shipped data: outputs, caching, staleness reasons, damage
//! detection, gc, locking.

use crate::common::*;

#[test]
fn default_pipeline_writes_hdf5_tables_and_plots_readable_by_others() {
    // The shared cold run of the shipped project (one per test process).
    let (p, o) = Project::shipped_with_cold_run();
    assert_ok(&o);
    assert!(
        stderr(&o).contains("ran 57, cached 0, failed 0, skipped 0 of 57"),
        "{}",
        stderr(&o)
    );
    let proc = p.processed();
    // The map tamaas solved for the `bem` validation rows is the one the shipped pipeline
    // solves, byte for byte (tests/data/README.md, `bem/`: its composite.x3p).
    assert_eq!(
        std::fs::read(proc.join("bem_measured/composite.x3p")).unwrap(),
        std::fs::read(test_data().join("bem/interface_hdi.x3p")).unwrap(),
        "the shipped composite map is not tests/data/bem/interface_hdi.x3p: regenerate the \
         tamaas reference (tests/data/bem/make_tamaas_reference.py)"
    );
    for f in [
        "disk/surface.h5",
        "disk/height_map.png",
        "disk/height_histogram.png",
        "disk/scale_sweep.png",
        "slider/surface.h5",
        "hdi/interface.h5",
        "table_2_2/interface.h5",
        "tables/surfaces.parquet",
        "tables/surfaces.csv",
        "tables/interfaces.parquet",
        "tables/interfaces.csv",
        "disk_md/dmw.h5",
        "improved/contact.h5",
        "improved/isbl_forces.png",
        "improved/isbl_area_stiffness.png",
        "measured/contact.h5",
        "tables/contacts.parquet",
        "disk_md/tracks.png",
        "disk_md/spectrum.png",
        "tables/dmw.parquet",
        "tables/dmw.csv",
        "tables/surfaces.arrow",
        "tables/dmw.arrow",
    ] {
        assert!(proc.join(f).is_file(), "missing {f}");
    }
    // h5py opens the files with no plugins, and every numeric dataset has units;
    // pyarrow opens the Parquet table.
    let script = r#"
import sys, h5py, pyarrow.parquet as pq
root = sys.argv[1]
n = 0
def check(name, obj):
    global n
    if isinstance(obj, h5py.Dataset) and obj.dtype.kind in 'fiu':
        assert 'units' in obj.attrs, name
        assert isinstance(obj.attrs['units'], str), name
        obj[()]
        n += 1
for f in ['disk/surface.h5', 'slider/surface.h5', 'hdi/interface.h5', 'disk_md/dmw.h5', 'improved/contact.h5']:
    with h5py.File(f'{root}/{f}', 'r') as h:
        assert h.attrs['NX_class'] == 'NXroot'
        assert len(h.attrs['cache_key']) == 64
        h.visititems(check)
with h5py.File(f'{root}/disk/surface.h5', 'r') as h:
    s = h['surface/parameters/sigma'][()]
    assert 0.2e-9 < s < 0.5e-9, s
    assert h['surface/levelled/height'].shape == (256, 256)
    assert h['surface/levelled/height'].compression == 'gzip'
with h5py.File(f'{root}/disk_md/dmw.h5', 'r') as h:
    assert h.attrs['default'] == 'dmw'
    assert h['dmw/tracks/D1'].compression == 'gzip' or h['dmw/tracks/D1'].size * 8 < 65536
    assert 0.5e-9 < h['dmw/qa/dmw_std'][()] < 1.0e-9
t = pq.read_table(f'{root}/tables/dmw.parquet')
assert 'dmw_std_nm' in t.column_names and t.num_rows == 1
t = pq.read_table(f'{root}/tables/surfaces.parquet')
assert t.num_rows == 2, t.num_rows
assert 'sigma_nm' in t.column_names and 'eta_per_um2' in t.column_names
print('datasets', n)
"#;
    let out = std::process::Command::new(python())
        .args(["-c", script])
        .arg(&proc)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "python check failed: {}",
        stderr(&out)
    );
    let n: usize = stdout(&out)
        .trim()
        .trim_start_matches("datasets ")
        .parse()
        .unwrap();
    assert!(n > 40, "only {n} datasets checked");
}

#[test]
fn second_run_recomputes_nothing_and_a_cutoff_change_reruns_only_its_dependents() {
    let p = Project::shipped_after_run();
    let before = snapshot(&p.processed());

    let o = p.run(&["run"]);
    assert_ok(&o);
    assert!(
        stderr(&o).contains("nothing to do: all 57 stage instances fresh"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        before,
        snapshot(&p.processed()),
        "a no-op run changed processed/"
    );
    let st = p.run(&["status"]);
    assert!(st.status.success(), "status: {}", stdout(&st));

    // Change one surface's filter cutoff.
    let cfg = p.config().replace(
        "[surface.disk]\nfile = \"raw/afm/disk_dlc_1um.gwy\"\n",
        "[surface.disk]\nfile = \"raw/afm/disk_dlc_1um.gwy\"\nfilter_l = \"250 nm\"\n",
    );
    assert_ne!(cfg, p.config());
    p.set_config(&cfg);
    let st = p.run(&["status"]);
    assert_eq!(st.status.code(), Some(1), "status must exit 1 when stale");
    let s = stdout(&st);
    assert!(
        s.contains("stale    disk: filter_l_m: null → 2.5e-7"),
        "{s}"
    );
    assert!(s.contains("stale    hdi: upstream disk changed"), "{s}");
    assert!(s.contains("stale    measured: upstream hdi changed"), "{s}");
    assert!(s.contains("stale    bem_measured: upstream "), "{s}");
    assert!(s.contains("fresh    improved"), "{s}");
    assert!(s.contains("fresh    slider"), "{s}");
    assert!(s.contains("fresh    table_2_2"), "{s}");

    let dry = p.run(&["run", "--dry-run"]);
    assert_ok(&dry);
    assert!(stdout(&dry).contains("would run  disk"), "{}", stdout(&dry));

    let o = p.run(&["run"]);
    assert_ok(&o);
    let e = stderr(&o);
    assert!(e.contains("ran 4, cached 53"), "{e}");
    assert!(
        e.contains("ran     disk") && e.contains("ran     hdi"),
        "{e}"
    );

    // Reverting the parameter re-uses the first result: nothing recomputed.
    let reverted = p.config().replace("filter_l = \"250 nm\"\n", "");
    p.set_config(&reverted);
    let o = p.run(&["run"]);
    assert!(stderr(&o).contains("nothing to do"), "{}", stderr(&o));
}

#[test]
fn damaged_or_deleted_cached_outputs_are_recomputed_not_trusted() {
    let p = Project::shipped_after_run();
    let h5 = std::fs::canonicalize(p.processed().join("disk/surface.h5")).unwrap();
    let good = std::fs::read(&h5).unwrap();
    // Corrupt one byte in the middle.
    let mut bad = good.clone();
    let mid = bad.len() / 2;
    bad[mid] ^= 0xff;
    std::fs::write(&h5, &bad).unwrap();
    let st = p.run(&["status"]);
    assert!(
        stdout(&st).contains("disk: cached output damaged: surface.h5 changed since written"),
        "{}",
        stdout(&st)
    );
    let o = p.run(&["run"]);
    assert_ok(&o);
    assert!(stderr(&o).contains("ran     disk"), "{}", stderr(&o));
    // Same key, same numbers: the recomputed dataset equals the original.
    let st = p.run(&["status"]);
    assert!(st.status.success(), "{}", stdout(&st));

    // A deleted plot is also noticed.
    std::fs::remove_file(p.processed().join("slider/height_map.png")).unwrap();
    let o = p.run(&["run"]);
    assert!(stderr(&o).contains("ran     slider"), "{}", stderr(&o));
    assert!(p.processed().join("slider/height_map.png").is_file());
}

#[test]
fn gc_removes_what_the_pipeline_no_longer_references() {
    let p = Project::shipped_after_run();
    // A stale entry: change the slider's summit scheme and run again.
    p.set_config(&p.config().replace(
        "level = [\"rows:median\", \"plane\", \"mean\"]",
        "level = [\"rows:median\", \"plane\", \"mean\"]\nsummits = 5",
    ));
    assert_ok(&p.run(&["run"]));
    // Drop the explicit interface from the file.
    let cfg = p.config();
    let cut = cfg.find("# The dissertation's tabulated").unwrap();
    p.set_config(&cfg[..cut]);
    let dry = p.run(&["gc", "--dry-run"]);
    assert_ok(&dry);
    let d = stdout(&dry);
    assert!(d.contains("would remove"), "{d}");
    assert!(p.processed().join("table_2_2").exists());
    let o = p.run(&["gc"]);
    assert_ok(&o);
    assert!(!p.processed().join("table_2_2").exists());
    // The superseded slider entry is kept while its ref points at the newest; the 9-point one
    // is gone. Everything the pipeline needs is still fresh.
    let st = p.run(&["status"]);
    assert!(st.status.success(), "{}", stdout(&st));
    assert!(
        p.path().join("raw/afm/disk_dlc_1um.gwy").is_file(),
        "gc must never touch raw/"
    );
}

#[test]
fn concurrent_runs_on_one_processed_dir_are_safe() {
    let p = Project::shipped();
    let a = hdi().current_dir(p.path()).arg("run").spawn().unwrap();
    let b = hdi().current_dir(p.path()).arg("run").spawn().unwrap();
    let (a, b) = (a.wait_with_output().unwrap(), b.wait_with_output().unwrap());
    assert!(a.status.success() && b.status.success());
    let st = p.run(&["status"]);
    assert!(st.status.success(), "{}", stdout(&st));
}

#[test]
fn only_runs_the_named_instance_and_what_it_needs() {
    let p = Project::shipped();
    let o = p.run(&["run", "--only", "hdi"]);
    assert_ok(&o);
    let e = stderr(&o);
    assert!(
        e.contains("ran 3, cached 0, failed 0, skipped 0 of 3"),
        "{e}"
    );
    assert!(!p.processed().join("table_2_2").exists());
    let o = p.run(&["run", "--only", "hdii"]);
    assert_clean_failure(&o, "did you mean `hdi`");
}

#[test]
fn a_leftover_temp_dir_from_a_crash_is_never_trusted_and_gc_cleans_it() {
    let p = Project::shipped_after_run();
    // Simulate a crash mid-write: a half-written work dir with a partial HDF5.
    let tmp = p.processed().join(".hdi/tmp/disk-deadbeef0000-1-1");
    std::fs::create_dir_all(&tmp).unwrap();
    std::fs::write(tmp.join("surface.h5"), b"\x89HDF\r\n\x1a\n partial").unwrap();
    let o = p.run(&["run"]);
    assert!(stderr(&o).contains("nothing to do"), "{}", stderr(&o));
    let o = p.run(&["gc"]);
    assert_ok(&o);
    assert!(!tmp.exists());
}

/// Identical inputs give byte-identical results whatever the thread count: no wall time and no
/// creation timestamp inside tables, JSON, HDF5 or PNG (docs/architecture.md). Only the store
/// manifests and the engine's bookkeeping under `.hdi/` carry times.
#[test]
fn two_cold_runs_with_different_thread_counts_write_identical_results() {
    let results = |jobs: &str| {
        // `--jobs 2`: the shared cold run (`Project::shipped_with_cold_run`); `--jobs 1` cold
        // here.
        let p = if jobs == "2" {
            Project::shipped_after_run()
        } else {
            let p = Project::shipped();
            assert_ok(&p.run(&["run", "--jobs", jobs]));
            p
        };
        let all = snapshot(&p.processed());
        let kept: Vec<(String, String)> = all
            .into_iter()
            .filter(|(rel, _)| !rel.starts_with(".hdi/") || rel.starts_with(".hdi/store/"))
            .filter(|(rel, _)| !rel.ends_with("manifest.json"))
            // The HTML report is a view with wall times and dates, like the run log
            // (docs/report.md).
            .filter(|(rel, _)| !rel.starts_with("report/"))
            .collect();
        (p, kept)
    };
    let (_a, two) = results("2");
    let (_b, one) = results("1");
    assert!(two.len() > 100, "{} result files", two.len());
    let differ: Vec<&String> = two
        .iter()
        .zip(&one)
        .filter(|(x, y)| x != y)
        .map(|(x, _)| &x.0)
        .collect();
    assert_eq!(two.len(), one.len());
    assert!(
        differ.is_empty(),
        "differ between --jobs 2 and 1: {differ:?}"
    );
}
