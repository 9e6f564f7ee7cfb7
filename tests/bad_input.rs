//! Bad input gets one clear error line, no panic, and loses nothing already computed.

use crate::common::*;

fn run_then_break(
    edit: impl Fn(&Project),
) -> (Project, std::process::Output, Vec<(String, String)>) {
    let p = Project::shipped_after_run();
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

/// Truncated and garbled copies of the `.ibw`, `.sur` and `.sdf` samples (tests/data/README.md):
/// one error line naming the file, no panic, no huge allocation from a size field.
#[test]
fn corrupt_ibw_sur_sdf_files_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let surfaces = test_data().join("surfaces");
    // (sample, where to cut (fractions of the length, before any optional trailer), byte
    // ranges [from, to) of size fields to garble)
    type Case<'a> = (&'a str, &'a [f64], &'a [(usize, usize)]);
    let cases: [Case; 4] = [
        // 0.94 cuts Asylum's note; the file's last 131 kB follow every section the header
        // lists, so cutting there loses nothing hdi reads.
        (
            "spot_1-1000nm.ibw",
            &[0.1, 0.5, 0.9, 0.94],
            &[(4, 8), (64 + 68, 64 + 76)],
        ),
        (
            "sur-2.sur",
            &[0.1, 0.5, 0.9, 0.999],
            &[(108, 116), (334, 338)],
        ),
        ("bcr_binary_int16.sdf", &[0.1, 0.5, 0.9], &[(42, 46)]),
        // NumPoints starts at byte 79.
        ("sdf-1.sdf", &[0.05, 0.3, 0.6], &[(60, 80)]),
    ];
    for (name, cuts, fields) in cases {
        let bytes = std::fs::read(surfaces.join(name)).unwrap();
        let mut variants: Vec<(String, Vec<u8>)> = cuts
            .iter()
            .map(|f| {
                let cut = (bytes.len() as f64 * f) as usize;
                (format!("cut{cut}-{name}"), bytes[..cut].to_vec())
            })
            .collect();
        for (k, &(from, to)) in fields.iter().enumerate() {
            let mut garbled = bytes.clone();
            for b in &mut garbled[from..to] {
                *b = 0x7F;
            }
            variants.push((format!("garbled{k}-{name}"), garbled));
        }
        for (file, content) in variants {
            let path = dir.path().join(&file);
            std::fs::write(&path, &content).unwrap();
            let o = hdi().arg("surface").arg(&path).output().unwrap();
            assert_clean_failure(&o, &file);
        }
    }
}

/// Truncated and garbled Zygo MetroPro `.dat` and ISO 25178-71 `.x3p` files (the real samples
/// in `tests/data/surfaces/`) and Zygo `.datx` files: one error line naming the file, no panic.
#[test]
fn truncated_and_garbled_metropro_and_x3p_files_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let surfaces = test_data().join("surfaces");
    let run = |name: &str, bytes: &[u8], needle: &str| {
        let f = dir.path().join(name);
        std::fs::write(&f, bytes).unwrap();
        let o = hdi().arg("surface").arg(&f).output().unwrap();
        assert_clean_failure(&o, name);
        assert_clean_failure(&o, needle);
    };
    let dat = std::fs::read(surfaces.join("metropro-1.dat")).unwrap();
    for cut in [10, 834, 700_000, dat.len() - 3] {
        run(&format!("cut{cut}.dat"), &dat[..cut], "truncated MetroPro");
    }
    let mut garbled = dat.clone();
    garbled[68..72].fill(0xFF); // cn_org_width/height: 65535 × 65535 phase pixels
    run("garbled.dat", &garbled, "truncated MetroPro");

    let x3p = std::fs::read(surfaces.join("x3p-2.x3p")).unwrap();
    for cut in [100, x3p.len() / 2, x3p.len() - 30] {
        run(&format!("cut{cut}.x3p"), &x3p[..cut], "ZIP");
    }
    let mut flipped = x3p.clone();
    flipped[5000] ^= 0x10; // inside the deflated data member: CRC or inflate error
    run("flipped.x3p", &flipped, "bindata/data.bin");
    let readers_b = surfaces.join("readers_b");
    for (name, needle) in [
        ("bad_no_main.x3p", "no main.xml"),
        ("bad_md5.x3p", "MD5"),
        ("bad_huge_size.x3p", "too large"),
    ] {
        run(name, &std::fs::read(readers_b.join(name)).unwrap(), needle);
    }
    // Zygo .datx (HDF5) written by h5py: truncated, and valid HDF5 with wrong content.
    let datx = std::fs::read(readers_b.join("datx_vlen.datx")).unwrap();
    for cut in [100, datx.len() / 2] {
        run(&format!("cut{cut}.datx"), &datx[..cut], "HDF5");
    }
    for (name, needle) in [
        ("bad_no_metadata.datx", "HDF5 but not Zygo .datx"),
        ("bad_path.datx", "names no dataset"),
        ("bad_category.datx", "expected `LateralCat`"),
    ] {
        run(name, &std::fs::read(readers_b.join(name)).unwrap(), needle);
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

/// `hdi analyze` on broken series files: one error line naming the file and the column.
#[test]
fn analyze_bad_series_files_name_the_file_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let rows =
        |n: usize, f: &dyn Fn(usize) -> String| -> String { (0..n).map(|i| f(i) + "\n").collect() };
    let good = rows(64, &|i| {
        format!("{},{}", i as f64 * 1e-6, (i as f64 * 0.3).sin())
    });
    let two = write(
        "two.csv",
        &format!(
            "time_s,a_m,b_m\n{}",
            rows(64, &|i| format!("{},{},{}", i as f64 * 1e-6, i % 3, i % 5))
        ),
    );
    let words = write("words.csv", &format!("time_s,x_m\n{good}0.001,abc\n"));
    let mut nan_rows: Vec<String> = good.lines().map(str::to_string).collect();
    nan_rows[20] = format!("{},", 20.0 * 1e-6);
    let nan = write("nan.csv", &format!("time_s,x_m\n{}\n", nan_rows.join("\n")));
    let short = write("short.csv", "time_s,x_m\n0,1\n1e-6,2\n2e-6,3\n");
    let mut uneven_rows: Vec<String> = good.lines().map(str::to_string).collect();
    uneven_rows[30] = format!("{},0.5", 30.5e-6);
    let uneven = write(
        "uneven.csv",
        &format!("time_s,x_m\n{}\n", uneven_rows.join("\n")),
    );
    let ok = write("ok.csv", &format!("time_s,x_m\n{good}"));
    let untimed = write(
        "untimed.csv",
        &format!("x_m\n{}", rows(64, &|i| format!("{}", (i as f64).sin()))),
    );
    let parquet = write("cut.parquet", "PAR1 this is not a parquet file at all");
    let arrow = write("cut.arrow", "ARROW1\0\0 garbage, no footer");
    let analyze = |p: &std::path::Path, args: &[&str]| {
        hdi().arg("analyze").arg(p).args(args).output().unwrap()
    };
    for (path, args, needles) in [
        (
            &ok,
            &["--column", "nope"][..],
            &["ok.csv", "no column `nope`", "x_m"][..],
        ),
        (
            &two,
            &[][..],
            &["two.csv", "several data columns", "a_m, b_m"][..],
        ),
        (
            &words,
            &[][..],
            &["words.csv", "`x_m` is not numeric", "abc", "line 66"][..],
        ),
        (
            &nan,
            &[][..],
            &["nan.csv", "`x_m`", "non-finite value NaN at sample 20"][..],
        ),
        (&short, &[][..], &["short.csv", "`x_m`", "too few"][..]),
        (
            &uneven,
            &[][..],
            &["uneven.csv", "`time_s`", "not uniformly sampled"][..],
        ),
        (
            &ok,
            &["--sample-rate", "2 MHz"][..],
            &["ok.csv", "--sample-rate says"][..],
        ),
        (
            &untimed,
            &[][..],
            &["untimed.csv", "no time column and no sample rate"][..],
        ),
        (&parquet, &[][..], &["cut.parquet"][..]),
        (&arrow, &[][..], &["cut.arrow"][..]),
    ] {
        let o = analyze(path, args);
        assert_clean_failure(&o, needles[0]);
        let err = stderr(&o);
        for n in needles {
            assert!(err.contains(n), "{}: lacks `{n}`: {err}", path.display());
        }
    }
    // The same good file with the rate it has: fine.
    assert_ok(&analyze(
        &ok,
        &[
            "--sample-rate",
            "1 MHz",
            "--f-min",
            "10 kHz",
            "--f-max",
            "200 kHz",
        ],
    ));
}

/// Inputs the coverage-guided fuzzer found (docs/reliability.md, "Coverage-guided fuzzing")
/// that crash Debian's libhdf5 1.10.8 inside the C library (an out-of-bounds read in the local
/// heap of a group lookup, another in the global heap of a variable-length string, an invalid
/// `free` on close), below anything hdi's readers can check. hdi reads HDF5 in a child process
/// (`formats::isolated`), so each is one clear error naming the file, with hdi's own exit
/// status rather than a signal.
#[test]
fn fuzzed_hdf5_files_fail_cleanly() {
    for (command, name) in [
        ("surface", "hdf5_local_heap.datx"),
        ("dmw", "hdf5_global_heap.h5"),
        ("dmw", "hdf5_invalid_free.h5"),
    ] {
        let file = test_data().join("fuzz").join(name);
        let o = hdi().arg(command).arg(&file).output().expect("run hdi");
        assert!(o.status.code().is_some(), "{name}: killed by a signal");
        assert_clean_failure(&o, name);
        assert!(stderr(&o).contains("corrupt"), "{name}: {}", stderr(&o));
    }
}

/// An HDF5 record the `ldv` fuzz target found on which libhdf5 1.10.8 loops for ever (in its
/// object-header code; `hdi dmw` spun at 100 % CPU until killed). The child reading it is
/// killed at the time limit: here 2 s, set through the library (the size rule gives this
/// 9.7 kB file one minute, which `hdi dmw` then reports the same way).
#[test]
fn an_hdf5_file_that_spins_libhdf5_is_a_timeout_error() {
    use hdi::formats::isolated::set_time_limit;
    let file = test_data().join("fuzz").join("hdf5_endless_loop.h5");
    set_time_limit(Some(std::time::Duration::from_secs(2)));
    let started = std::time::Instant::now();
    let r = hdi::dmw::io::read_ldv(&file, &hdi::dmw::io::ReadOptions::default());
    set_time_limit(None);
    let e = r.expect_err("a record from a spinning library").to_string();
    assert!(e.contains("still busy after 2.0 s"), "{e}");
    assert!(e.contains("hdf5_endless_loop.h5"), "{e}");
    assert!(started.elapsed() < std::time::Duration::from_secs(20));
}

/// An Arrow IPC file the `ldv` fuzz target found: its LZ4 buffer declares 2.4·10¹⁸ bytes
/// decompressed, and arrow-ipc's allocation of that aborted `hdi dmw` (SIGABRT, no panic to
/// catch). Now one clear error naming the file.
#[test]
fn fuzzed_arrow_file_with_a_huge_decompressed_length_fails_cleanly() {
    let name = "arrow_lz4_huge_length.arrow";
    let file = test_data().join("fuzz").join(name);
    let o = hdi().arg("dmw").arg(&file).output().expect("run hdi");
    assert_clean_failure(&o, name);
    assert!(stderr(&o).contains("decompressed"), "{}", stderr(&o));
}

/// The same defect in an Arrow IPC stream (tests/data/README.md): arrow-ipc's `StreamReader`
/// aborted on the allocation; the messages are now checked before it decodes them.
#[test]
fn an_arrow_stream_with_a_huge_decompressed_length_fails_cleanly() {
    let name = "arrow_stream_lz4_huge_length.arrows";
    let file = test_data().join("fuzz").join(name);
    let o = hdi().arg("dmw").arg(&file).output().expect("run hdi");
    assert!(o.status.code().is_some(), "killed by a signal");
    assert_clean_failure(&o, name);
    assert!(stderr(&o).contains("decompressed"), "{}", stderr(&o));
}

#[test]
fn contact_bem_errors_name_the_key_or_the_file() {
    let p = Project::shipped();
    // An explicit interface has no map to solve.
    p.set_config(&p.config().replace(
        "[contact_bem.bem_measured]\ninterface = \"hdi\"",
        "[contact_bem.bem_measured]\ninterface = \"table_2_2\"",
    ));
    let o = p.run(&["run"]);
    assert_clean_failure(&o, "contact_bem.bem_measured.interface");
    assert!(
        stderr(&o).contains("two measured surfaces"),
        "{}",
        stderr(&o)
    );
    p.set_config(&p.config().replace(
        "interface = \"table_2_2\"\ncontact = \"measured\"",
        "interface = \"hdi\"\ncontact = \"measured\"\nh_star_min = -1",
    ));
    assert_clean_failure(&p.run(&["run"]), "contact_bem.bem_measured.h_star_min");
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.gwy");
    let o = hdi()
        .args(["contact", "--bem"])
        .arg(&missing)
        .output()
        .unwrap();
    assert_clean_failure(&o, "missing.gwy");
    let map = repo_root().join("tests/data/surfaces/di-3.di");
    let o = hdi()
        .args(["contact", "--bem"])
        .arg(&map)
        .args(["--tolerance", "0"])
        .output()
        .unwrap();
    assert_clean_failure(&o, "--tolerance");
}
