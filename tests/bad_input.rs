//! Bad input gets one clear error line, no panic, and loses nothing already computed.

use crate::common::*;

fn run_then_break(
    edit: impl Fn(&Project),
) -> (Project, std::process::Output, Vec<(String, String)>) {
    let p = Project::shipped();
    let o = p.run(&["run"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let before = snapshot(&p.processed());
    edit(&p);
    let o = p.run(&["run"]);
    (p, o, before)
}

#[test]
fn truncated_nanoscope_file_fails_cleanly_and_keeps_earlier_results() {
    let (p, o, before) = run_then_break(|p| {
        let f = p.path().join("raw/afm/slider_tfc_1um.spm");
        let bytes = std::fs::read(&f).unwrap();
        std::fs::write(&f, &bytes[..bytes.len() / 2]).unwrap();
    });
    assert_clean_failure(&o, "slider_tfc_1um.spm");
    assert!(stderr(&o).contains("truncated"), "{}", stderr(&o));
    assert_eq!(before, snapshot(&p.processed()), "earlier results changed");
}

#[test]
fn corrupt_gwy_file_fails_cleanly_and_keeps_earlier_results() {
    let (p, o, before) = run_then_break(|p| {
        let f = p.path().join("raw/afm/disk_dlc_1um.gwy");
        let mut bytes = std::fs::read(&f).unwrap();
        // Keep the magic, garble the object header and sizes.
        for b in bytes.iter_mut().skip(4).take(64) {
            *b = 0xA5;
        }
        std::fs::write(&f, &bytes).unwrap();
    });
    assert_clean_failure(&o, "disk_dlc_1um.gwy");
    assert_eq!(before, snapshot(&p.processed()), "earlier results changed");
}

#[test]
fn nan_filled_map_is_an_error_naming_the_file() {
    let (p, o, before) = run_then_break(|p| {
        let mut text = String::from("# Width: 1 um\n# Height: 1 um\n# Value units: nm\n");
        for _ in 0..16 {
            text.push_str(&vec!["nan"; 16].join(" "));
            text.push('\n');
        }
        std::fs::write(p.path().join("raw/afm/nan.txt"), text).unwrap();
        p.set_config(
            &p.config()
                .replace("raw/afm/slider_tfc_1um.spm", "raw/afm/nan.txt"),
        );
    });
    assert_clean_failure(&o, "nan.txt");
    assert_eq!(before, snapshot(&p.processed()), "earlier results changed");
}

#[test]
fn missing_file_in_config_names_key_file_and_line() {
    let (p, o, before) = run_then_break(|p| {
        p.set_config(
            &p.config()
                .replace("raw/afm/disk_dlc_1um.gwy", "raw/afm/nope.gwy"),
        );
    });
    assert_clean_failure(
        &o,
        "pipeline.toml:14: surface.disk.file: height map raw/afm/nope.gwy not found",
    );
    assert!(stderr(&o).contains("nope.gwy"), "{}", stderr(&o));
    assert_eq!(before, snapshot(&p.processed()));
}

#[test]
fn unknown_key_names_file_line_and_nearest_key() {
    let (p, o, before) = run_then_break(|p| {
        p.set_config(&p.config().replace(
            "rule = \"sum_surface\"",
            "rule = \"sum_surface\"\nsurfacez = 1",
        ));
    });
    assert_clean_failure(&o, "pipeline.toml:");
    let e = stderr(&o);
    assert!(
        e.contains("unknown key `surfacez`") && e.contains("did you mean `surfaces`"),
        "{e}"
    );
    assert_eq!(before, snapshot(&p.processed()));
}

#[test]
fn out_of_range_parameter_names_parameter_and_range() {
    let p = Project::shipped();
    p.set_config(&p.config().replace(
        "file = \"raw/afm/disk_dlc_1um.gwy\"\n",
        "file = \"raw/afm/disk_dlc_1um.gwy\"\nfilter_l = \"-5 um\"\n",
    ));
    let o = p.run(&["run"]);
    assert_clean_failure(&o, "surface.disk.filter_l");
    assert!(stderr(&o).contains("must be > 0"), "{}", stderr(&o));
    p.set_config(
        &p.config()
            .replace("filter_l = \"-5 um\"", "filter_l = \"5 parsecs\""),
    );
    assert_clean_failure(&p.run(&["run"]), "unknown unit `parsecs`");
    p.set_config(
        &p.config()
            .replace("filter_l = \"5 parsecs\"", "summits = 7"),
    );
    assert_clean_failure(&p.run(&["run"]), "use 9 or 5");
}

#[test]
fn ad_hoc_surface_errors_are_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.gwy");
    let o = hdi().arg("surface").arg(&missing).output().unwrap();
    assert_clean_failure(&o, "missing.gwy");
    let junk = dir.path().join("junk.bin");
    std::fs::write(&junk, [0u8, 159, 146, 150, 1, 2, 3, 4, 5]).unwrap();
    let o = hdi().arg("surface").arg(&junk).output().unwrap();
    assert_clean_failure(&o, "junk.bin");
    let empty = dir.path().join("empty.txt");
    std::fs::write(&empty, "").unwrap();
    assert_clean_failure(
        &hdi().arg("surface").arg(&empty).output().unwrap(),
        "empty.txt",
    );
    let no_size = dir.path().join("nosize.txt");
    std::fs::write(&no_size, "1 2 3\n4 5 6\n7 8 9\n1 2 3\n").unwrap();
    let o = hdi().arg("surface").arg(&no_size).output().unwrap();
    assert_clean_failure(&o, "size_x");
}

#[test]
fn a_failure_beside_a_successful_rerun_keeps_the_failed_instances_results() {
    let (p, o, before) = run_then_break(|p| {
        // The slider file breaks while the disk gets a new parameter.
        let f = p.path().join("raw/afm/slider_tfc_1um.spm");
        std::fs::write(&f, b"\\*File list\r\n\\Version: 0x09200000\r\n").unwrap();
        p.set_config(&p.config().replace(
            "file = \"raw/afm/disk_dlc_1um.gwy\"\n",
            "file = \"raw/afm/disk_dlc_1um.gwy\"\nsummits = 5\n",
        ));
    });
    assert_clean_failure(&o, "slider_tfc_1um.spm");
    let e = stderr(&o);
    assert!(
        e.contains("ran     disk") && e.contains("skipped hdi"),
        "{e}"
    );
    let after = snapshot(&p.processed());
    let keep = |s: &[(String, String)], prefix: &str| -> Vec<(String, String)> {
        s.iter()
            .filter(|(k, _)| k.starts_with(prefix))
            .cloned()
            .collect()
    };
    // The slider's and the interface's links and the tables are as before.
    for prefix in ["slider", "hdi", "tables/"] {
        assert_eq!(
            keep(&before, prefix),
            keep(&after, prefix),
            "{prefix} changed"
        );
    }
}

#[test]
fn cut_foreign_ldv_records_fail_cleanly_naming_the_file() {
    // One file per reader of tests/data/ldv/ (independent writers), cut in the data and in
    // the header: `hdi dmw` must print one error line naming the file, never panic.
    let dir = tempfile::tempdir().unwrap();
    for name in [
        "record_lz4.feather",
        "record_stream.arrows",
        "record_ascii.uff",
        "record_binary.uff",
        "record_c.npy",
        "record_deflate.npz",
        "record_int24.wav",
    ] {
        let bytes = std::fs::read(test_data().join("ldv").join(name)).unwrap();
        for (tag, keep) in [("half", bytes.len() / 2), ("head", 40)] {
            let cut = dir.path().join(format!("{tag}-{name}"));
            std::fs::write(&cut, &bytes[..keep]).unwrap();
            let o = hdi().arg("dmw").arg(&cut).output().unwrap();
            assert_clean_failure(&o, &format!("{tag}-{name}"));
        }
    }
}
