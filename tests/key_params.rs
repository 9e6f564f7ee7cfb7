//! Key params are plain data (docs/architecture.md, "The cache, precisely"): the `params` of
//! every stage instance of the shipped pipeline and of the slider cases its sweeps, DOE
//! designs and Slurm manifests key are JSON objects, numbers, booleans and words, never a
//! Rust `Debug` rendering such as `"Model2Dof { variant: Improved, … }"` or `"Some(…)"`.

use crate::common::Project;
use hdi::slider::params::{SimulateConfig, SimulateParams};
use serde_json::{json, Value};

/// Whether a string looks like Rust `Debug` output: `Name {`, `Name(`, `Some(`, or a bare
/// CamelCase identifier such as `Integrated` or `StaticCurve` (an enum variant).
fn debug_looking(s: &str) -> bool {
    let b = s.as_bytes();
    for (i, &c) in b.iter().enumerate() {
        let word_start = i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        if !(c.is_ascii_uppercase() && word_start) {
            continue;
        }
        let end = i + b[i..]
            .iter()
            .take_while(|x| x.is_ascii_alphanumeric())
            .count();
        let rest = &s[end..];
        if rest.starts_with(" {") || rest.starts_with('(') {
            return true;
        }
    }
    let camel = |w: &str| {
        w.len() > 1
            && w.as_bytes()[0].is_ascii_uppercase()
            && w.bytes().all(|c| c.is_ascii_alphanumeric())
            && w.bytes().any(|c| c.is_ascii_lowercase())
    };
    // A bare variant, or a Debug list of them (`[Up, Down]`).
    camel(s)
        || (s.starts_with('[')
            && s.split(['[', ']', ',', ' '])
                .filter(|w| !w.is_empty())
                .any(camel))
}

/// Every string in `v` (keys and values) that looks like `Debug` output, with its path.
fn debug_strings(path: &str, v: &Value, out: &mut Vec<String>) {
    match v {
        Value::String(s) if debug_looking(s) => out.push(format!("{path}: {s}")),
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                debug_strings(&format!("{path}[{i}]"), x, out);
            }
        }
        Value::Object(m) => {
            for (k, x) in m {
                if debug_looking(k) {
                    out.push(format!("{path}: key {k}"));
                }
                debug_strings(&format!("{path}.{k}"), x, out);
            }
        }
        _ => {}
    }
}

#[test]
fn the_detector_flags_debug_output_and_passes_plain_words() {
    for s in [
        "Model2Dof { variant: Improved, nominal_flying_height: 1.1e-8 }",
        "SimOptions { duration: 0.002 }",
        "Some([1.0, 2.0])",
        "[Up, Down]",
        "Integrated",
        "StaticCurve",
        "Dopri5 { rtol: 1e-8 }",
    ] {
        assert!(debug_looking(s), "{s}");
    }
    for s in [
        "improved_2dof",
        "integrated_stiffness",
        "bulge:tfc",
        "raw/afm/disk_dlc_1um.gwy",
        "mtl_reference",
        "σ = 0.5 nm (K)",
        "E1_Pa",
        "R_m",
    ] {
        assert!(!debug_looking(s), "{s}");
    }
}

/// The shipped pipeline's stage keys and the keys of its `[simulate]` instances' cases
/// (sweep points, DOE designs and Slurm manifests use `SimulateParams::case_params`; the
/// 3-DOF cases carry their instance's canonical params) hold no `Debug` string, and the model
/// is there field by field.
#[test]
fn shipped_key_params_are_plain_data() {
    let p = Project::shipped();
    let path = p.path().join("pipeline.toml");
    let snap = hdi::engine::diff::load_pipeline(&path).expect("plan the shipped pipeline");
    let mut found = Vec::new();
    for (name, inst) in &snap.instances {
        debug_strings(
            &format!("{}.{name}", inst.kind),
            &inst.fingerprint.params,
            &mut found,
        );
    }
    let file = hdi::stages::load(&path).expect("read pipeline.toml");
    let sims = file
        .instances::<SimulateConfig>("simulate")
        .expect("[simulate] tables");
    assert!(sims.len() >= 3, "{}", sims.len());
    for (name, cfg) in &sims {
        let sp = SimulateParams::from_config(&file, name, cfg).expect("a shipped [simulate]");
        let a = sp.actuations.first().copied().unwrap_or(10e-9);
        let params = sp.case_params(a, "contact-key", Some("dmw-key"));
        debug_strings(&format!("case of {name}"), &params, &mut found);
        let with_start = hdi::slider::sweep::with_start(&sp, Some([1e-9, 2e-6]));
        let params = with_start.case_params(a, "contact-key", None);
        debug_strings(&format!("branch case of {name}"), &params, &mut found);
        // Readable fields, SI: the nominal flying height of Table 2.1 and the options.
        let m = &params["model_parameters"];
        assert_eq!(m["variant"], json!("improved"), "{name}: {m}");
        let fh = m["nominal_flying_height"].as_f64().unwrap_or(f64::NAN);
        assert!((fh - 11e-9).abs() < 1e-21, "{name}: {m}");
        assert_eq!(params["options"]["static_start"], json!([1e-9, 2e-6]));
        assert!(params["options"]["integrator"].is_object(), "{params}");
    }
    assert!(
        found.is_empty(),
        "Debug strings in key params:\n{}",
        found.join("\n")
    );
    // The instance keys carry the same structure.
    let sweep = &snap.instances["improved_sweep"].fingerprint.params;
    assert_eq!(
        sweep["model_parameters"]["suspension"]["heave_stiffness"],
        json!(10.0),
        "{sweep}"
    );
    assert_eq!(
        sweep["options"]["contact_force"],
        json!("interference_tangent")
    );
    // SI numbers that read back bit for bit from the key's JSON text (the slider mass is
    // derived, ρ·l·l_w·l_t of Table 2.1, so not a short decimal).
    let text = sweep.to_string();
    let back: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(&back, sweep);
    let model = hdi::dynamics::params::improved_2dof();
    let mass = back["model_parameters"]["slider"]["mass"].as_f64().unwrap();
    assert_eq!(mass.to_bits(), model.slider.mass.to_bits(), "{text}");
    let beta = &back["model_parameters"]["air_bearing"]["stiffening"]["quadratic"]["beta"];
    assert_eq!(beta, &json!(1.0), "{text}");
}

/// The shipped calibration's warm start names the fit-inputs fingerprint it was fitted for
/// (`start_fitted_for`, docs/calibration.md). The fingerprint hashes the base instance's key
/// params, so a change of their form (as to plain data) must come with the new fingerprint in
/// pipeline.toml, or the shipped run silently drops its warm start and runs the full fit.
#[test]
fn the_shipped_warm_start_matches_the_shipped_fit_inputs() {
    use hdi::stages::calibrate::{CalibrateConfig, CalibrateStage};
    use hdi::stages::FromConfig;
    let dir = tempfile::tempdir().unwrap();
    crate::common::copy_dir(
        &crate::common::repo_root().join("raw"),
        &dir.path().join("raw"),
    );
    let path = dir.path().join("pipeline.toml");
    std::fs::copy(crate::common::repo_root().join("pipeline.toml"), &path).unwrap();
    let snap = hdi::engine::diff::load_pipeline(&path).expect("plan the shipped pipeline");
    let file = hdi::stages::load(&path).expect("read pipeline.toml");
    let name = "improved_calibration";
    let cfg: CalibrateConfig = file
        .instance("calibrate", name)
        .expect("a [calibrate] table")
        .expect("the shipped calibration");
    let stage = CalibrateStage::from_config(&file, name, &cfg).expect("a valid calibration");
    let given = stage.start_fitted_for.clone().expect("start_fitted_for");
    let now = stage.fit_inputs(|n| snap.instances[n].key.clone());
    assert!(
        now.starts_with(&given) || given.starts_with(&now),
        "pipeline.toml has start_fitted_for = \"{given}\", the shipped fit's inputs are {now}"
    );
}
