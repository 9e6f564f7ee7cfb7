use super::html::{esc, num, render, unit_of};
use super::*;

const EVIL: &str = "a<&\">'b";

fn evil_page() -> Page {
    let inst = Instance {
        name: EVIL.into(),
        kind: "surface".into(),
        key: "k".into(),
        model_version: "surface-1".into(),
        state: "stale".into(),
        why: vec![format!("input file changed (raw/{EVIL})")],
        last_run: Some(RunInstance {
            name: EVIL.into(),
            outcome: "failed".into(),
            wall_time_s: None,
            message: format!("cannot read raw/{EVIL}"),
        }),
        manifest: None,
        numbers: vec![
            (format!("{EVIL}_nm"), json!(1.5)),
            ("note".into(), json!(EVIL)),
        ],
        figures: vec![(
            format!("../{}", url_path(&[EVIL.to_string(), "f.png".into()])),
            format!("{EVIL}.png"),
        )],
        files: vec![(
            format!("../{}", url_path(&[EVIL.to_string(), "t.csv".into()])),
            format!("{EVIL}.csv"),
            12,
        )],
        inputs: vec![("file".into(), format!("raw/{EVIL}"), "00".into())],
        upstream: vec![(EVIL.into(), "11".into())],
    };
    Page {
        project: EVIL.into(),
        config_name: format!("{EVIL}.toml"),
        config_blake3: "cc".into(),
        hdi_version: "0.1.0".into(),
        generated: "2026-01-01T00:00:00Z".into(),
        run: None,
        instances: vec![inst],
        tables: vec![("../tables/x.csv".into(), EVIL.into())],
        validation: None,
        key: "kk".into(),
    }
}

#[test]
fn every_string_from_names_and_values_is_escaped() {
    let html = render(&evil_page());
    // The raw string never appears; only its escaped form does.
    assert!(!html.contains(EVIL), "unescaped name in the page");
    assert!(!html.contains("<&"), "unescaped `<&`");
    assert!(html.contains("a&lt;&amp;&quot;&gt;&#39;b"));
    // In URLs the name is percent-encoded (what a browser then resolves on disk).
    assert!(html.contains("../a%3C%26%22%3E%27b/f.png"), "{html}");
    // Every `<` opens a tag the renderer wrote: a tag name or `/`/`!` follows.
    for (i, _) in html.match_indices('<') {
        let next = html[i + 1..].chars().next().unwrap();
        assert!(
            next.is_ascii_alphabetic() || next == '/' || next == '!',
            "stray `<` at {i}: {}",
            &html[i..(i + 20).min(html.len())]
        );
    }
    // No network: nothing loads from http(s).
    assert!(!html.contains("http://") && !html.contains("https://"));
}

#[test]
fn escaping_is_the_html_one() {
    assert_eq!(
        esc("x<y & \"z\" 'w'>"),
        "x&lt;y &amp; &quot;z&quot; &#39;w&#39;&gt;"
    );
}

#[test]
fn units_come_from_the_name_suffix() {
    assert_eq!(unit_of("sigma_nm"), "nm");
    assert_eq!(unit_of("sigma_nm_mean"), "nm");
    assert_eq!(unit_of("sigma_nm_ci95_low"), "nm");
    assert_eq!(unit_of("eta_um2"), "µm²");
    assert_eq!(unit_of("efficiency_nm_per_mW"), "nm/mW");
    assert_eq!(unit_of("eta_per_um2"), "1/µm²");
    assert_eq!(unit_of("cases_per_branch"), "");
    assert_eq!(unit_of("peak_Hz"), "Hz");
    assert_eq!(unit_of("Ssk"), "");
    assert_eq!(unit_of("n_summits"), "");
    assert_eq!(unit_of("fhm_percent"), "%");
    // Velocities: `_mm_s` is mm/s, not seconds (the tables' suffix list decides).
    assert_eq!(unit_of("velocity_std_mm_s"), "mm/s");
    assert_eq!(unit_of("noise_floor_um_s"), "µm/s");
}

#[test]
fn numbers_have_six_significant_digits() {
    assert_eq!(num(0.0), "0");
    assert_eq!(num(1.5), "1.5");
    assert_eq!(num(123.456789), "123.457");
    assert_eq!(num(2.5e-7), "2.50000e-7");
    assert_eq!(num(f64::NAN), "–");
}

#[test]
fn relative_links_point_from_the_report_to_processed() {
    let d = tempfile::tempdir().unwrap();
    let processed = d.path().join("processed");
    std::fs::create_dir_all(&processed).unwrap();
    assert_eq!(
        relative_prefix(&processed.join("report"), &processed),
        "../"
    );
    assert_eq!(
        relative_prefix(&d.path().join("elsewhere/deep"), &processed),
        "../../processed/"
    );
}

#[test]
fn the_report_directory_is_replaced_whole() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("report");
    write_dir(&out, &[("index.html", b"one"), ("old.txt", b"x")]).unwrap();
    write_dir(&out, &[("index.html", b"two")]).unwrap();
    assert_eq!(std::fs::read(out.join("index.html")).unwrap(), b"two");
    assert!(!out.join("old.txt").exists());
    // No temp or old directories are left beside it.
    let left: Vec<_> = std::fs::read_dir(d.path()).unwrap().flatten().collect();
    assert_eq!(left.len(), 1);
}
