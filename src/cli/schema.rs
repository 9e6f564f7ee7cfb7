//! `hdi schema`: the JSON Schemas of the `--json` outputs, generated from the Rust types the
//! commands print (docs/json.md). `docs/schemas/` holds them as generated; the tests fail when
//! a file there differs from what the types give (`hdi schema --check docs/schemas`).

use anyhow::{bail, Context, Result};
use schemars::generate::SchemaSettings;
use schemars::transform::{transform_subschemas, Transform};
use schemars::{JsonSchema, Schema};
use serde_json::Value;
use std::path::Path;

/// One documented output: its file stem, the command it describes, its layout version (in
/// `$id`), the generator.
struct Documented {
    name: &'static str,
    title: &'static str,
    version: u32,
    schema: fn() -> Schema,
}

const fn doc<T: JsonSchema>(name: &'static str, title: &'static str) -> Documented {
    Documented {
        name,
        title,
        version: 1,
        schema: generate::<T>,
    }
}

/// Every `--json` output with a schema, in file-name order.
const DOCUMENTED: &[Documented] = &[
    doc::<hdi::artefacts::analysis::StoredAnalysisResult>(
        "analysis-result",
        "analysis stage result.json",
    ),
    doc::<super::analyze::AnalyzeOutput>("analyze", "hdi analyze --json"),
    doc::<super::analyze_stream::StreamOutput>(
        "analyze-stream",
        "hdi analyze FILE --stream --json",
    ),
    doc::<hdi::bench::BenchDocument>("bench", "hdi bench --json"),
    doc::<hdi::artefacts::bulge::BulgeReport>("bulge", "hdi bulge FILE… --json"),
    Documented {
        name: "case-manifest",
        title: "Slurm case manifest",
        version: hdi::core::executor::MANIFEST_SCHEMA_VERSION,
        schema: case_manifest,
    },
    doc::<hdi::stages::contact::ContactReport>("contact", "hdi contact --json"),
    doc::<hdi::artefacts::contact_bem::BemResult>("contact-bem", "hdi contact --bem FILE… --json"),
    doc::<hdi::engine::diff::Diff>("diff", "hdi diff --json"),
    doc::<hdi::stages::dmw::DmwReport>("dmw", "hdi dmw FILE --json"),
    doc::<super::simulate::SimulateOutput>("simulate", "hdi simulate --json"),
    doc::<Vec<super::run::InstanceStatus>>("status", "hdi status --json"),
    doc::<hdi::artefacts::surface::SurfaceReport>("surface", "hdi surface FILE --json"),
    doc::<hdi::validation::document::ValidateDocument>("validate", "hdi validate --json"),
    doc::<super::verify::VerifyDocument>("verify", "hdi verify --json"),
];

/// The schema of `T` as the output writes it (serialisation contract: a key always written
/// is required), subschemas inline, every object closed (`additionalProperties: false`, so
/// an undocumented key fails validation).
fn generate<T: JsonSchema>() -> Schema {
    SchemaSettings::draft2020_12()
        .for_serialize()
        .with(|s| s.inline_subschemas = true)
        .with_transform(Closed)
        .into_generator()
        .into_root_schema_for::<T>()
}

/// Case kinds and the schema of their recipes' `case`.
type CaseType = (&'static [&'static str], fn() -> Schema);

/// The case types a manifest's recipes carry, by case kind: the schema of `recipe.case` for
/// entries of those kinds. A case kind without one fails `hdi schema --check`.
const CASE_TYPES: &[CaseType] = &[
    (
        &["simulate", "doe"],
        generate::<hdi::slider::sweep::SweepCase>,
    ),
    (&["three_dof"], three_dof_case),
    (
        &["calibration"],
        generate::<hdi::stages::calibrate::CalibrationCase>,
    ),
];

/// A 3-DOF case is its interface label.
fn three_dof_case() -> Schema {
    let mut s = generate::<String>();
    s.insert(
        "description".into(),
        Value::from("case label: isbl, or mtl_<lubricant case of Table 4.4>"),
    );
    s
}

/// The manifest with each entry's recipe as [`CaseRecipe`](hdi::stages::case_engine::CaseRecipe)
/// and its `case` in the type of the entry's kind (core, which writes the manifest, knows
/// neither).
fn case_manifest() -> Schema {
    let mut s = generate::<hdi::core::executor::CaseManifest>();
    let mut recipe = generate::<hdi::stages::case_engine::CaseRecipe>().to_value();
    if let Some(m) = recipe.as_object_mut() {
        m.remove("$schema");
        m.remove("title");
    }
    let cases: Vec<Value> = CASE_TYPES
        .iter()
        .map(|(kinds, schema)| {
            let mut case = schema().to_value();
            if let Some(m) = case.as_object_mut() {
                m.remove("$schema");
                m.remove("title");
            }
            serde_json::json!({
                "if": {"properties": {"kind": {"enum": kinds}}},
                "then": {"properties": {"recipe": {"properties": {"case": case}}}}
            })
        })
        .collect();
    if let Some(Value::Object(entry)) = s.pointer_mut("/properties/cases/items") {
        if let Some(Value::Object(props)) = entry.get_mut("properties") {
            props.insert("recipe".into(), recipe);
        }
        entry.insert("allOf".into(), Value::Array(cases));
    }
    s
}

/// Case kinds the registry has no case type for.
fn case_kinds_without_a_type() -> Vec<&'static str> {
    hdi::stages::case_kinds()
        .into_iter()
        .map(|(case_kind, _)| case_kind)
        .filter(|k| !CASE_TYPES.iter().any(|(kinds, _)| kinds.contains(k)))
        .collect()
}

/// Closes every object schema that lists its properties and says nothing about others, and
/// reflows descriptions (a doc comment's line breaks are not the text's).
#[derive(Clone)]
struct Closed;

impl Transform for Closed {
    fn transform(&mut self, schema: &mut Schema) {
        if let Some(obj) = schema.as_object_mut() {
            if obj.contains_key("properties") && !obj.contains_key("additionalProperties") {
                obj.insert("additionalProperties".into(), Value::Bool(false));
            }
            if let Some(Value::String(d)) = obj.get_mut("description") {
                *d = reflow(d);
            }
        }
        transform_subschemas(self, schema);
    }
}

/// Single line breaks become spaces; paragraphs (blank lines) stay.
fn reflow(text: &str) -> String {
    text.split("\n\n")
        .map(|p| p.split('\n').map(str::trim).collect::<Vec<_>>().join(" "))
        .collect::<Vec<_>>()
        .join("\n\n")
}

/// The document written to `docs/schemas/NAME.json`: `$schema`, `$id`, title, then the
/// generated schema (its description is the type's doc comment).
fn document(d: &Documented) -> Value {
    let generated = (d.schema)().to_value();
    let mut out = serde_json::Map::new();
    out.insert(
        "$schema".into(),
        Value::from("https://json-schema.org/draft/2020-12/schema"),
    );
    out.insert(
        "$id".into(),
        Value::from(format!("urn:hdi:json-schema:v{}:{}", d.version, d.name)),
    );
    out.insert("title".into(), Value::from(d.title));
    let mut generated = generated;
    // A list's description is its element type's doc comment: the document's own.
    if let Some(m) = generated.as_object_mut() {
        if !m.contains_key("description") {
            let items = m.get_mut("items").and_then(Value::as_object_mut);
            if let Some(d) = items.and_then(|i| i.remove("description")) {
                m.insert("description".into(), d);
            }
        }
    }
    if let Value::Object(mut m) = generated {
        if let Some(d) = m.remove("description") {
            out.insert("description".into(), d);
        }
        for (k, v) in m {
            if !matches!(k.as_str(), "$schema" | "$id" | "title") {
                out.insert(k, v);
            }
        }
    }
    Value::Object(out)
}

fn text(d: &Documented) -> String {
    let mut s = serde_json::to_string_pretty(&document(d)).unwrap_or_default();
    s.push('\n');
    s
}

pub(super) fn cmd_schema(
    name: Option<String>,
    write: Option<&Path>,
    check: Option<&Path>,
) -> Result<()> {
    if let Some(dir) = write {
        std::fs::create_dir_all(dir).with_context(|| dir.display().to_string())?;
        for d in DOCUMENTED {
            let path = dir.join(format!("{}.json", d.name));
            hdi::core::cache::write_atomic(&path, text(d).as_bytes())
                .with_context(|| path.display().to_string())?;
        }
        return Ok(());
    }
    if let Some(dir) = check {
        let mut drifted = Vec::new();
        for d in DOCUMENTED {
            let path = dir.join(format!("{}.json", d.name));
            let on_disk = std::fs::read_to_string(&path).unwrap_or_default();
            if on_disk != text(d) {
                drifted.push(path.display().to_string());
            }
        }
        let known: Vec<&str> = DOCUMENTED.iter().map(|d| d.name).collect();
        let mut stray = Vec::new();
        for e in std::fs::read_dir(dir).with_context(|| dir.display().to_string())? {
            let p = e?.path();
            let stem = p.file_stem().and_then(|s| s.to_str()).unwrap_or("");
            if p.extension().is_some_and(|x| x == "json") && !known.contains(&stem) {
                stray.push(p.display().to_string());
            }
        }
        let untyped = case_kinds_without_a_type();
        if !untyped.is_empty() {
            bail!(
                "case kinds without a case type in the manifest schema: {}",
                untyped.join(", ")
            );
        }
        if !drifted.is_empty() || !stray.is_empty() {
            bail!(
                "schemas out of date (regenerate with `hdi schema --write {}`): {}{}",
                dir.display(),
                drifted.join(", "),
                if stray.is_empty() {
                    String::new()
                } else {
                    format!("; not generated from a type: {}", stray.join(", "))
                }
            );
        }
        return Ok(());
    }
    match name {
        None => {
            for d in DOCUMENTED {
                println!("{:<16} {}", d.name, d.title);
            }
        }
        Some(n) => match DOCUMENTED.iter().find(|d| d.name == n) {
            Some(d) => print!("{}", text(d)),
            None => {
                let names: Vec<&str> = DOCUMENTED.iter().map(|d| d.name).collect();
                bail!("no schema `{n}` (have: {})", names.join(", "))
            }
        },
    }
    Ok(())
}
