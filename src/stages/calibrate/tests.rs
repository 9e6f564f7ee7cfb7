use super::*;
use std::path::Path;

/// A two-knob calibration of a one-point base (only its parameters matter here).
const BASE: &str = "[simulate.s]\nmodel = \"improved_2dof\"\ncontact = \"c\"\ndmw = \"d\"\n\
                        actuations = [\"8.5 nm\"]\n";
const CAL: &str =
    "\n[calibrate.k]\nsimulate = \"s\"\nknobs = [\"dmw_scale\", \"kr_stiffening_beta\"]\n";
const START: &str = "start = { dmw_scale = 1.5, kr_stiffening_beta = 0.4 }\ninitial_step = 1e-3\n";

fn stage_of(simulate_extra: &str, extra: &str) -> std::result::Result<CalibrateStage, ConfigError> {
    let text = format!("{BASE}{simulate_extra}{CAL}{extra}");
    let file = PipelineFile::parse(
        Path::new("pipeline.toml"),
        text,
        &crate::stages::section_names(),
    )?;
    let cfg = file
        .instance::<CalibrateConfig>("calibrate", "k")?
        .expect("[calibrate.k]");
    CalibrateStage::from_config(&file, "k", &cfg)
}
fn stage(extra: &str) -> CalibrateStage {
    stage_of("", extra).unwrap()
}
fn keys(n: &str) -> String {
    format!("entry-key-of-{n}")
}

#[test]
fn the_fingerprint_ignores_how_the_search_is_run() {
    let plain = stage("").fit_inputs(keys);
    assert_eq!(plain.len(), FIT_INPUTS_DIGITS);
    assert!(plain.chars().all(|c| c.is_ascii_hexdigit()), "{plain}");
    // Deterministic: a second stage from the same text, keys in another order of calls.
    assert_eq!(stage("").fit_inputs(keys), plain);
    for extra in [
        START.to_string(),
        "max_evaluations = 17\n".into(),
        format!("{START}start_fitted_for = \"0123456789abcdef\"\n"),
        // The held-out set is judged before and after the fit, never inside it.
        "held_out = []\n".into(),
    ] {
        assert_eq!(stage(&extra).fit_inputs(keys), plain, "{extra}");
    }
    // …and so does the base's actuation grid (the held-out sweeps' only).
    let text = BASE.replace("[\"8.5 nm\"]", "[\"8.5 nm\", \"12 nm\"]");
    let file = PipelineFile::parse(
        Path::new("pipeline.toml"),
        format!("{text}{CAL}"),
        &crate::stages::section_names(),
    )
    .unwrap();
    let cfg = file
        .instance::<CalibrateConfig>("calibrate", "k")
        .unwrap()
        .unwrap();
    let s = CalibrateStage::from_config(&file, "k", &cfg).unwrap();
    assert_eq!(s.fit_inputs(keys), plain);
}

#[test]
fn the_fingerprint_changes_with_every_input_of_the_fit() {
    let plain = stage("").fit_inputs(keys);
    let changed = [
        (
            "weight",
            stage("weights = { \"clearance_8.5nm\" = 2.0 }\n").fit_inputs(keys),
        ),
        (
            "bounds",
            stage("bounds = { dmw_scale = [0.5, 3.0] }\n").fit_inputs(keys),
        ),
        (
            "targets",
            stage("targets = [\"clearance_8.5nm\", \"fhm_8.5nm\"]\n").fit_inputs(keys),
        ),
        ("knobs", {
            let t = format!("{BASE}\n[calibrate.k]\nsimulate = \"s\"\nknobs = [\"dmw_scale\"]\n");
            let file = PipelineFile::parse(Path::new("p.toml"), t, &crate::stages::section_names())
                .unwrap();
            let cfg = file
                .instance::<CalibrateConfig>("calibrate", "k")
                .unwrap()
                .unwrap();
            CalibrateStage::from_config(&file, "k", &cfg)
                .unwrap()
                .fit_inputs(keys)
        }),
        (
            "touchdown",
            stage("touchdown_step = \"0.25 nm\"\n").fit_inputs(keys),
        ),
        (
            "base parameter",
            stage_of("kr_stiffening_beta = 0.5\n", "")
                .unwrap()
                .fit_inputs(keys),
        ),
        (
            "base option",
            stage_of("transit_delay = false\n", "")
                .unwrap()
                .fit_inputs(keys),
        ),
        // The contact set's or DMW record's entry (its parameters or raw-file hash).
        (
            "upstream key",
            stage("").fit_inputs(|n| if n == "d" { "other".into() } else { keys(n) }),
        ),
    ];
    for (what, f) in &changed {
        assert_ne!(f, &plain, "{what}");
    }
}

#[test]
fn a_guarded_start_is_used_only_for_its_own_inputs() {
    let plain = stage("");
    let fp = plain.fit_inputs(keys);
    // Matching (also as a longer or upper-case spelling of the same hash).
    for given in [fp.clone(), fp.to_ascii_uppercase()] {
        let s = stage(&format!("{START}start_fitted_for = \"{given}\"\n"));
        let (used, warm) = s.effective_settings(&s.fit_inputs(keys));
        assert_eq!(warm, WarmStart::Matched);
        assert_eq!(used.start.len(), 2);
        assert_eq!(used.search.initial_step, 1e-3);
    }
    // Mismatching: the settings are exactly those of the same block without a start, so
    // the run is the full fit from the spec defaults with the default simplex.
    let other = if fp.starts_with('0') { "1" } else { "0" }.repeat(FIT_INPUTS_DIGITS);
    let s = stage(&format!("{START}start_fitted_for = \"{other}\"\n"));
    let (used, warm) = s.effective_settings(&s.fit_inputs(keys));
    let WarmStart::Ignored(reason) = warm else {
        panic!("{warm:?}")
    };
    assert!(reason.contains(&other) && reason.contains(&fp), "{reason}");
    assert_eq!(used, plain.settings);
    assert_eq!(used.search.initial_step, 0.2);
    // Unguarded: used as written; no start: nothing to decide.
    let s = stage(START);
    let (used, warm) = s.effective_settings(&s.fit_inputs(keys));
    assert_eq!((warm, used.start.len()), (WarmStart::Unguarded, 2));
    assert_eq!(plain.effective_settings(&fp).1, WarmStart::None);
    // The guard is in the cache key (it decides what runs).
    assert_ne!(
        stage(&format!("{START}start_fitted_for = \"{other}\"\n")).params(),
        stage(START).params()
    );
}

#[test]
fn a_bad_start_fitted_for_names_the_key() {
    for (extra, says) in [
        (
            format!("{START}start_fitted_for = \"not-hex-at-all!!\"\n"),
            "hex digits",
        ),
        (format!("{START}start_fitted_for = \"abc\"\n"), "hex digits"),
        (
            "start_fitted_for = \"0123456789abcdef\"\n".into(),
            "no `start`",
        ),
    ] {
        let msg = stage_of("", &extra).err().expect(&extra).to_string();
        assert!(
            msg.contains("start_fitted_for") && msg.contains(says),
            "{msg}"
        );
    }
}
