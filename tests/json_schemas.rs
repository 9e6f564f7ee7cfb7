//! Every command's `--json` output against its schema in `docs/schemas/` (docs/json.md): each
//! command runs on small real inputs (the shipped `raw/` data, a tiny pipeline for `status`)
//! and its stdout is validated by Python `jsonschema` (Draft 2020-12, an independent
//! validator) through `common::assert_matches_schema`. The schemas forbid undocumented keys
//! (`additionalProperties: false`), so a key added without documenting it fails here.

use crate::common::*;
use serde_json::Value;
use std::path::Path;
use std::process::Command;

/// Run `hdi ARGS` in `dir` and return stdout; `ok` says whether a zero exit is required
/// (`status` exits 1 when anything is stale, `validate` when a gated row fails).
fn json_of(dir: &Path, args: &[&str], ok: bool) -> String {
    let o = hdi().current_dir(dir).args(args).output().expect("run hdi");
    assert!(!stderr(&o).contains("panicked"), "{args:?}: {}", stderr(&o));
    if ok {
        assert_ok(&o);
    }
    let text = stdout(&o);
    let v: Value = serde_json::from_str(&text)
        .unwrap_or_else(|e| panic!("{args:?}: stdout is not one JSON document ({e}): {text}"));
    assert_no_debug_strings(&v, "");
    text
}

/// No Rust `Debug` rendering anywhere in the output: no `Name { field: … }`, `Some(…)`,
/// `None`, or CamelCase enum variants (`JunctionShear`), which are what `{:?}` of structs and
/// enums prints (docs/json.md: explicit names only).
fn assert_no_debug_strings(v: &Value, path: &str) {
    match v {
        Value::String(s) => {
            let camel = s.len() > 3
                && s.chars().all(|c| c.is_ascii_alphabetic())
                && s.chars().next().is_some_and(|c| c.is_ascii_uppercase())
                && s.chars().skip(1).any(|c| c.is_ascii_uppercase())
                && s.chars().any(|c| c.is_ascii_lowercase());
            let debug_struct = s.contains(" { ") && s.contains(": ");
            let option = s == "None" || s.starts_with("Some(");
            assert!(
                !(camel || debug_struct || option),
                "{path}: Rust debug string `{s}`"
            );
        }
        Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| assert_no_debug_strings(x, &format!("{path}/{i}"))),
        Value::Object(m) => m
            .iter()
            .for_each(|(k, x)| assert_no_debug_strings(x, &format!("{path}/{k}"))),
        _ => {}
    }
}

fn root() -> std::path::PathBuf {
    repo_root()
}

fn raw(rel: &str) -> String {
    root().join("raw").join(rel).to_string_lossy().into_owned()
}

#[test]
fn surface_json_matches_its_schema() {
    let dir = tempfile::tempdir().unwrap();
    let gwy = raw("afm/disk_dlc_1um.gwy");
    let plain = json_of(dir.path(), &["surface", &gwy, "--json"], true);
    assert_matches_schema("surface", &plain);
    let v: Value = serde_json::from_str(&plain).unwrap();
    assert!(v["crop_m"].is_null() && v["filter_s_m"].is_null() && v["filter_l_m"].is_null());
    // The other shape of every optional key: a crop, both filters, 5-point Birmingham
    // summits; the filter cutoffs come back as numbers in metres.
    let spm = raw("afm/slider_tfc_1um.spm");
    let full = json_of(
        dir.path(),
        &[
            "surface",
            &spm,
            "--crop",
            "0um,0um,0.5um,0.5um",
            "--filter-s",
            "10 nm",
            "--filter-l",
            "0.25 um",
            "--summits",
            "5",
            "--birmingham",
            "--json",
        ],
        true,
    );
    assert_matches_schema("surface", &full);
    let v: Value = serde_json::from_str(&full).unwrap();
    assert_eq!(v["filter_s_m"].as_f64(), Some(10e-9));
    assert_eq!(v["filter_l_m"].as_f64(), Some(0.25e-6));
    assert_eq!(v["crop_m"][2].as_f64(), Some(0.5e-6));
    // Spectral moments (they need a periodic, uncropped map).
    let spectral = json_of(
        dir.path(),
        &[
            "surface",
            &gwy,
            "--moments",
            "spectral",
            "--periodic",
            "--json",
        ],
        true,
    );
    assert_matches_schema("surface", &spectral);
    let v: Value = serde_json::from_str(&spectral).unwrap();
    assert_eq!(v["moments_method"], "spectral");
}

#[test]
fn bulge_json_matches_its_schema() {
    let dir = tempfile::tempdir().unwrap();
    let files: Vec<String> = ["00", "30", "60", "90"]
        .iter()
        .map(|p| raw(&format!("bulge/tfc_{p}mW.gsf")))
        .collect();
    let mut args = vec!["bulge"];
    args.extend(files.iter().map(String::as_str));
    args.push("--json");
    assert_matches_schema("bulge", &json_of(dir.path(), &args, true));
    // One scan: no efficiency fit (null, as documented).
    let one = json_of(dir.path(), &["bulge", &files[1], "--json"], true);
    assert_matches_schema("bulge", &one);
    let v: Value = serde_json::from_str(&one).unwrap();
    assert!(v["efficiency_m_per_W"].is_null(), "{v}");
}

#[test]
fn dmw_json_matches_its_schema() {
    let dir = tempfile::tempdir().unwrap();
    let h5 = raw("ldv/disk_md_5425rpm.h5");
    let with_index = json_of(dir.path(), &["dmw", &h5, "--json"], true);
    assert_matches_schema("dmw", &with_index);
    let v: Value = serde_json::from_str(&with_index).unwrap();
    // The keys carry their units: the shipped record is sampled at 4 MHz (raw/ldv/README.md).
    assert_eq!(v["sample_rate_Hz"], 4e6);
    // Without an index channel: segmented by the spindle speed, trigger level null.
    let o = hdi()
        .args(["synth", "ldv", "--format", "csv", "--revolutions", "3"])
        .args(["--no-index", "--out-dir"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert_ok(&o);
    let csv = stdout(&o).lines().next().unwrap().trim().to_string();
    let no_index = json_of(dir.path(), &["dmw", &csv, "--rpm", "5425", "--json"], true);
    assert_matches_schema("dmw", &no_index);
    let v: Value = serde_json::from_str(&no_index).unwrap();
    assert!(v["trigger_level_V"].is_null(), "{v}");
}

/// `hdi contact --bem` on a real instrument file (a public NanoScope sample): the curve of the
/// map against a flat, its schema, and a pressure that rises as the separation falls.
#[test]
fn contact_bem_on_a_real_instrument_file() {
    let dir = tempfile::tempdir().unwrap();
    let map = repo_root().join("tests/data/surfaces/di-3.di");
    let args = [
        "contact",
        "--bem",
        map.to_str().unwrap(),
        "--step",
        "0.5",
        "--json",
    ];
    let out = json_of(dir.path(), &args, true);
    assert_matches_schema("contact-bem", &out);
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["grid"], serde_json::json!([256, 256]), "{}", v["grid"]);
    assert!(v["isbl_sigma_m"].is_null());
    let curve = v["curve"].as_array().unwrap();
    assert_eq!(curve.len(), 8, "h/σ = 4, 3.5, … 0.5");
    let p: Vec<f64> = curve
        .iter()
        .map(|c| c["pressure_Pa"].as_f64().unwrap())
        .collect();
    assert!(p.windows(2).all(|w| w[1] > w[0]), "{p:?}");
    for c in curve {
        let a = c["contact_fraction"].as_f64().unwrap();
        assert!(a > 0.0 && a < 1.0, "{c}");
        assert!(c["error"].as_f64().unwrap() <= 1e-10, "{c}");
    }
}

#[test]
fn contact_json_matches_its_schema() {
    let dir = tempfile::tempdir().unwrap();
    let isbl = json_of(dir.path(), &["contact", "--json"], true);
    assert_matches_schema("contact", &isbl);
    let v: Value = serde_json::from_str(&isbl).unwrap();
    assert!(v["mtl"].is_null());
    assert_eq!(v["inputs"]["friction_law"], "junction_shear");
    // The MTL block, the variable surface energy and the other enum values.
    let mtl = json_of(
        dir.path(),
        &[
            "contact",
            "--parameter-set",
            "mtl_table_3_2",
            "--lubricant",
            "reference",
            "--summit-offset",
            "mccool",
            "--friction-law",
            "seed_power_elastic",
            "--surface-energy",
            "variable",
            "--json",
        ],
        true,
    );
    assert_matches_schema("contact", &mtl);
    let v: Value = serde_json::from_str(&mtl).unwrap();
    assert_eq!(v["inputs"]["summit_offset"], "mccool");
    assert!(v["mtl"]["curves"].as_array().is_some_and(|c| !c.is_empty()));
    let ke = json_of(
        dir.path(),
        &["contact", "--friction-law", "ke_static", "--json"],
        true,
    );
    assert_matches_schema("contact", &ke);
    let v: Value = serde_json::from_str(&ke).unwrap();
    assert_eq!(v["inputs"]["friction_law"], "ke_static");
    // A fitted summit distribution: its ratios in the inputs, how they were obtained beside.
    let fit = json_of(
        dir.path(),
        &["contact", "--summit-distribution", "fig_2_11", "--json"],
        true,
    );
    assert_matches_schema("contact", &fit);
    let v: Value = serde_json::from_str(&fit).unwrap();
    assert_eq!(v["inputs"]["summit_offset"], "given");
    assert_eq!(v["summit_distribution"]["kind"], "fig_2_11");
    let force = v["summit_distribution"]["fitted"]["force_N"]
        .as_f64()
        .unwrap();
    assert!((force / 7.30e-6 - 1.0).abs() < 1e-9, "{force}");
}

#[test]
fn simulate_json_matches_both_shapes_of_its_schema() {
    let dir = tempfile::tempdir().unwrap();
    let one = json_of(
        dir.path(),
        &["simulate", "--actuation", "8.5 nm", "--json"],
        true,
    );
    assert_matches_schema("simulate", &one);
    let v: Value = serde_json::from_str(&one).unwrap();
    assert!(v.get("sweep").is_none(), "one case has no sweep block");
    // A sweep from flying into solid contact (tests/simulate_cli.rs: 12 nm contacts).
    let sweep = json_of(
        dir.path(),
        &[
            "simulate",
            "--actuation",
            "5 nm",
            "8.5 nm",
            "12 nm",
            "--json",
        ],
        true,
    );
    assert_matches_schema("simulate", &sweep);
    let v: Value = serde_json::from_str(&sweep).unwrap();
    let kinds: Vec<&str> = v["cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["vibration_kind"].as_str().unwrap())
        .collect();
    assert_eq!(kinds.first(), Some(&"FHM"), "{kinds:?}");
    assert_eq!(kinds.last(), Some(&"BV"), "{kinds:?}");
    assert!(v["sweep"]["touchdown_actuation_m"].is_number(), "{v}");
}

#[test]
fn validate_json_matches_its_schema() {
    // Every code area (no pipeline: the pipeline areas are skipped); ~20 s in a debug build.
    let dir = tempfile::tempdir().unwrap();
    let text = json_of(
        dir.path(),
        &["validate", "--json", "--config", "no-pipeline.toml"],
        false,
    );
    assert_matches_schema("validate", &text);
    let v: Value = serde_json::from_str(&text).unwrap();
    // Every row shape appears: classes G, K, D, Q, C; Q rows with an ordering.
    for c in ["G", "K", "D", "Q", "C"] {
        assert!(
            v["classes"][c]["rows"].as_u64().unwrap_or(0) > 0,
            "no {c} row"
        );
    }
}

#[test]
fn status_json_matches_its_schema_in_every_state() {
    let dir = tempfile::tempdir().unwrap();
    copy_dir(&root().join("raw").join("afm"), &dir.path().join("raw/afm"));
    let one = r#"[project]
name = "status"

[report]
validation = false

[surface.disk]
file = "raw/afm/disk_dlc_1um.gwy"
scale_sweep = false

[surface.slider]
file = "raw/afm/slider_tfc_1um.spm"
scale_sweep = false
"#;
    std::fs::write(dir.path().join("pipeline.toml"), one).unwrap();
    assert_ok(&hdi().current_dir(dir.path()).arg("run").output().unwrap());
    // slider: a changed parameter (stale); wafer: never run (missing); disk: fresh.
    let two = one.replace(
        "file = \"raw/afm/slider_tfc_1um.spm\"\nscale_sweep = false",
        "file = \"raw/afm/slider_tfc_1um.spm\"\nscale_sweep = false\nhistogram_bins = 32",
    ) + "\n[surface.wafer]\nfile = \"raw/afm/disk_dlc_1um.gwy\"\nsummits = 5\n";
    std::fs::write(dir.path().join("pipeline.toml"), two).unwrap();
    let text = json_of(dir.path(), &["status", "--json"], false);
    assert_matches_schema("status", &text);
    let v: Value = serde_json::from_str(&text).unwrap();
    let mut states: Vec<&str> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["state"].as_str().unwrap())
        .collect();
    states.sort();
    assert_eq!(states, ["fresh", "missing", "stale"], "{v}");
}

/// The schemas are only worth something if they reject what they do not describe: a real
/// output with an undocumented key, a wrong type, a missing key or a debug string in an enum
/// field must each fail validation.
#[test]
fn a_schema_rejects_an_extra_key_a_wrong_type_and_a_debug_string() {
    let dir = tempfile::tempdir().unwrap();
    let good: Value =
        serde_json::from_str(&json_of(dir.path(), &["contact", "--json"], true)).unwrap();
    let rejected = |v: &Value| {
        let text = v.to_string();
        std::panic::catch_unwind(|| assert_matches_schema("contact", &text)).is_err()
    };
    assert!(!rejected(&good), "the unmodified output must validate");
    let mut extra = good.clone();
    extra["derived"]["E_star"] = serde_json::json!(1.5e11);
    assert!(rejected(&extra), "an undocumented (unit-less) key passed");
    let mut wrong_type = good.clone();
    wrong_type["curves"][0]["P_Pa"] = serde_json::json!("5.6e8 Pa");
    assert!(rejected(&wrong_type), "a number as text passed");
    let mut missing = good.clone();
    missing["derived"].as_object_mut().unwrap().remove("psi");
    assert!(rejected(&missing), "a missing required key passed");
    let mut debug = good.clone();
    debug["inputs"]["friction_law"] = serde_json::json!("JunctionShear");
    assert!(rejected(&debug), "a Rust debug enum name passed");
}

/// `docs/schemas/` is what the printed types give (docs/json.md): a field added, renamed or
/// re-documented in a type without regenerating fails here, and so does a schema file written
/// by hand (one no type generates).
#[test]
fn schemas_are_generated_from_the_types() {
    let dir = root().join("docs").join("schemas");
    let o = hdi()
        .args(["schema", "--check"])
        .arg(&dir)
        .output()
        .expect("run hdi");
    assert_ok(&o);
    // The listing names every generated schema, one per file.
    let listed = stdout(&hdi().arg("schema").output().expect("run hdi"));
    let files = std::fs::read_dir(&dir).unwrap().count();
    assert_eq!(listed.lines().count(), files, "{listed}");
}

/// Every file in `docs/schemas/` is a valid Draft 2020-12 schema with a title, a versioned
/// `$id` (docs/json.md: `urn:hdi:json-schema:v1:<command>`) and `additionalProperties: false` on every object it declares (so undocumented keys
/// fail), and every command whose `--help` offers `--json` has one.
#[test]
fn every_json_command_has_a_valid_strict_schema() {
    let schemas = root().join("docs").join("schemas");
    let script = r#"
import json, re, sys, pathlib
from jsonschema import Draft202012Validator
bad = []
def walk(node, where):
    if isinstance(node, dict):
        if node.get("type") == "object" and "properties" in node and node.get("additionalProperties") is not False:
            bad.append(f"{where}: object without additionalProperties: false")
        for k, v in node.items():
            walk(v, f"{where}/{k}")
    elif isinstance(node, list):
        for i, v in enumerate(node):
            walk(v, f"{where}/{i}")
for p in sorted(pathlib.Path(sys.argv[1]).glob("*.json")):
    s = json.load(open(p))
    Draft202012Validator.check_schema(s)
    if s.get("$schema") != "https://json-schema.org/draft/2020-12/schema":
        bad.append(f"{p.name}: $schema is not Draft 2020-12")
    if not s.get("title") or not s.get("description"):
        bad.append(f"{p.name}: no title/description")
    if not re.search(r"(^|[^a-z])v[0-9]+([^0-9]|$)", s.get("$id", "")):
        bad.append(f"{p.name}: $id without a version")
    walk(s, p.name)
print("\n".join(bad))
sys.exit(1 if bad else 0)
"#;
    let out = Command::new(python())
        .arg("-c")
        .arg(script)
        .arg(&schemas)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );

    // The commands `hdi --help` lists, and which of them take --json.
    let help = stdout(&hdi().arg("--help").output().unwrap());
    let commands: Vec<String> = help
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .filter(|c| c != "help")
        .collect();
    assert!(commands.len() > 10, "parsed no commands from:\n{help}");
    let mut with_json = Vec::new();
    for c in &commands {
        let h = stdout(&hdi().args([c.as_str(), "--help"]).output().unwrap());
        if h.contains("--json") {
            with_json.push(c.clone());
        }
    }
    assert!(with_json.iter().any(|c| c == "surface"), "{with_json:?}");
    let missing: Vec<&String> = with_json
        .iter()
        .filter(|c| !schemas.join(format!("{c}.json")).exists())
        .collect();
    assert!(
        missing.is_empty(),
        "--json commands without docs/schemas/<command>.json: {missing:?}"
    );
}
