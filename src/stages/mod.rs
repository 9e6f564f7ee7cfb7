//! Stage implementations, one module per stage kind; the contract a stage kind fulfils
//! ([`FromConfig`] + [`StageKind`]); and the registry that turns a parsed `pipeline.toml` into
//! stage instances.
//!
//! Adding a stage kind: its module (config struct, `impl FromConfig`, `impl StageKind`) and
//! one line in [`KINDS`].
pub mod analysis;
pub mod bulge;
pub mod calibrate;
pub mod case_engine;
pub mod contact;
pub mod contact_bem;
pub mod dmw;
pub mod doe;
pub mod excitation;
pub mod interface;
pub mod simulate;
pub mod surfaces;
pub mod three_dof;

use crate::core::cache::{Fingerprint, Store};
use crate::core::config::{ConfigError, PipelineFile};
use crate::error::Result;
use case_engine::{CaseEngine, UpstreamEntries};
use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// One stage instance of the pipeline, as the engine drives it. Implementations hold
/// validated parameters; `run` is the only place that computes, and it writes only into
/// `ctx.out_dir`. Every stage kind gets it through [`Instance`].
pub trait Stage: Send + Sync {
    fn name(&self) -> &str;
    /// Stage kind (`surface`, `interface`, ...): the store's folder and the summary table.
    fn kind(&self) -> &'static str;
    /// Bumped by hand whenever the stage's numerics change: part of the cache key.
    fn model_version(&self) -> &'static str;
    /// Canonical parameters (defaults filled in, SI units): part of the cache key.
    fn params(&self) -> Value;
    /// Input files by role.
    fn inputs(&self) -> Vec<(String, PathBuf)>;
    /// Names of the stage instances this one consumes.
    fn upstream(&self) -> Vec<String>;
    fn run(&self, ctx: &StageContext) -> Result<StageOutput>;
    /// The kind's case kind and engine when its work splits into independent cases (the
    /// executors list and compute them through it; [`case_engine`]).
    fn cases(&self) -> Option<(&'static str, &dyn CaseEngine)>;
}

/// What a running stage gets.
pub struct StageContext<'a> {
    pub name: &'a str,
    pub key: &'a str,
    pub fingerprint: &'a Fingerprint,
    /// Temporary directory for outputs; renamed into the store on success.
    pub out_dir: &'a Path,
    /// Results (`result.json`) of the consumed stages, by name.
    pub upstream: BTreeMap<String, Value>,
    /// Store entry directory of each consumed stage (its files, e.g. `dmw.h5`), by name.
    pub upstream_dirs: BTreeMap<String, PathBuf>,
    /// The content-addressed store, for stages that cache sub-results of their own (one
    /// simulation case per sweep point).
    pub store: &'a Store,
    /// Where the stage reports what it is doing (`ctx.progress.set_message(…)`).
    pub progress: &'a dyn crate::core::progress::Progress,
    /// Facts about this run rather than results (how many cases came from the cache): they
    /// depend on what the store already held and on timing, so they go to the entry's
    /// `manifest.json` (`run_log`), never into `result.json` (docs/architecture.md).
    pub run_log: std::sync::Mutex<BTreeMap<String, Value>>,
    /// Where a stage with a sequential driver sends its rounds of independent cases (the
    /// calibration under `hdi run --executor slurm`); `None`: computed in this process.
    pub batch: Option<&'a dyn crate::core::executor::batch::BatchRunner>,
}

impl StageContext<'_> {
    /// Record a run fact (see [`StageContext::run_log`]).
    pub fn log_run(&self, key: &str, value: Value) {
        if let Ok(mut log) = self.run_log.lock() {
            log.insert(key.to_string(), value);
        }
    }

    /// The cache key of the consumed instance `name` (empty when it is not upstream): case
    /// keys include the keys of the entries their inputs came from.
    pub fn upstream_key(&self, name: &str) -> String {
        self.fingerprint
            .upstream
            .iter()
            .find(|u| u.name == name)
            .map(|u| u.key.clone())
            .unwrap_or_default()
    }

    /// The result of the consumed `kind` instance `name`, read through its type (the type
    /// the upstream kind writes, in `crate::artefacts`): a missing instance or a result
    /// that does not parse as `T` is an error naming it.
    pub fn upstream_as<T: DeserializeOwned>(&self, kind: &'static str, name: &str) -> Result<T> {
        crate::artefacts::upstream_result(&self.upstream, kind, name)
    }

    /// The consumed entries as a case engine reads them (what a worker reads from a recipe).
    pub fn upstream_entries(&self) -> UpstreamEntries {
        UpstreamEntries {
            results: self.upstream.clone(),
            dirs: self.upstream_dirs.clone(),
            keys: self
                .upstream
                .keys()
                .map(|n| (n.clone(), self.upstream_key(n)))
                .collect(),
        }
    }
}

/// What a stage returns besides its files: typed by the kind ([`StageKind::Result`],
/// [`StageKind::Row`]), as JSON once the engine has it ([`StageOutput`]).
pub struct Output<R, W> {
    /// Machine-readable result for downstream stages and tables; written as `result.json`.
    pub result: R,
    /// One row for the kind's tidy summary table (column names with unit suffixes).
    pub summary_row: Option<W>,
}

/// A stage's output as the engine stores it.
pub type StageOutput = Output<Value, serde_json::Map<String, Value>>;

impl<R: Serialize, W: Serialize> Output<R, W> {
    /// The JSON the engine writes: the result as serde writes the type (field order is key
    /// order), the row as one JSON object.
    pub fn into_json(self, kind: &'static str) -> Result<StageOutput> {
        let encode = |what: &str, e: serde_json::Error| crate::error::Error::Encode {
            kind,
            what: what.to_string(),
            message: e.to_string(),
        };
        let result = serde_json::to_value(&self.result).map_err(|e| encode("result", e))?;
        let summary_row = match self.summary_row {
            None => None,
            Some(row) => match serde_json::to_value(&row).map_err(|e| encode("summary row", e))? {
                Value::Object(m) => Some(m),
                other => {
                    return Err(crate::error::Error::Encode {
                        kind,
                        what: "summary row".into(),
                        message: format!("not a JSON object: {other}"),
                    })
                }
            },
        };
        Ok(Output {
            result,
            summary_row,
        })
    }
}

/// How a stage kind reads one `[KIND.NAME]` table: the table as written, then validation
/// into the kind's parameters (SI units, ranges, files and referenced instances checked,
/// errors via [`PipelineFile::error`]).
pub trait FromConfig: Sized {
    /// The table as written: serde with `deny_unknown_fields`.
    type Config: DeserializeOwned + 'static;
    fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &Self::Config,
    ) -> std::result::Result<Self, ConfigError>;
}

/// A stage kind: what is the same for all its instances, and what an instance computes.
/// [`Instance`] turns it into a [`Stage`].
pub trait StageKind: FromConfig + Send + Sync + 'static {
    /// Its `pipeline.toml` section, store folder and summary table.
    const KIND: &'static str;
    /// Bumped by hand whenever the kind's numerics change: part of the cache key.
    const MODEL_VERSION: &'static str;
    /// Canonical parameters (defaults filled in, SI units): part of the cache key.
    fn params(&self) -> Value;
    /// Input files by role.
    fn inputs(&self) -> Vec<(String, PathBuf)> {
        Vec::new()
    }
    /// Names of the stage instances this one consumes.
    fn upstream(&self) -> Vec<String> {
        Vec::new()
    }
    /// Its `result.json` as a type: downstream stages read it through the same type
    /// (`crate::artefacts`), `docs/schemas/` is generated from it.
    type Result: Serialize;
    /// One row of its tidy summary table (column names with unit suffixes).
    type Row: Serialize;
    fn run(&self, ctx: &StageContext) -> Result<Output<Self::Result, Self::Row>>;
    /// Its case kind (`hdi exec-cases` dispatches on it) when its work splits into
    /// independent cases.
    const CASE_KIND: Option<&'static str> = None;
    /// The case capability when [`StageKind::CASE_KIND`] is set.
    fn case_engine(&self) -> Option<&dyn CaseEngine> {
        None
    }
}

/// A named instance of a stage kind: the [`Stage`] the engine drives.
pub struct Instance<K> {
    pub name: String,
    pub stage: K,
}

impl<K: StageKind> Stage for Instance<K> {
    fn name(&self) -> &str {
        &self.name
    }
    fn kind(&self) -> &'static str {
        K::KIND
    }
    fn model_version(&self) -> &'static str {
        K::MODEL_VERSION
    }
    fn params(&self) -> Value {
        self.stage.params()
    }
    fn inputs(&self) -> Vec<(String, PathBuf)> {
        self.stage.inputs()
    }
    fn upstream(&self) -> Vec<String> {
        self.stage.upstream()
    }
    fn run(&self, ctx: &StageContext) -> Result<StageOutput> {
        self.stage.run(ctx)?.into_json(K::KIND)
    }
    fn cases(&self) -> Option<(&'static str, &dyn CaseEngine)> {
        K::CASE_KIND.zip(self.stage.case_engine())
    }
}

/// A stage kind in the registry: its section name and how its tables are read.
pub struct Registered {
    pub kind: &'static str,
    /// Its case kind, when its work splits into cases.
    pub case_kind: Option<&'static str>,
    read: fn(&PipelineFile) -> std::result::Result<Vec<Unbuilt>, ConfigError>,
}

/// An instance whose table is read but not yet validated.
type Unbuilt = (
    String,
    Box<dyn FnOnce(&PipelineFile, &str) -> std::result::Result<Box<dyn Stage>, ConfigError>>,
);

const fn kind<K: StageKind>() -> Registered {
    Registered {
        kind: K::KIND,
        case_kind: K::CASE_KIND,
        read: read::<K>,
    }
}

fn read<K: StageKind>(file: &PipelineFile) -> std::result::Result<Vec<Unbuilt>, ConfigError> {
    let instances = file.instances::<K::Config>(K::KIND)?;
    Ok(instances
        .into_iter()
        .map(|(name, cfg)| -> Unbuilt {
            let build = move |file: &PipelineFile, name: &str| {
                let stage = K::from_config(file, name, &cfg)?;
                let name = name.to_string();
                Ok(Box::new(Instance { name, stage }) as Box<dyn Stage>)
            };
            (name, Box::new(build))
        })
        .collect())
}

/// Every stage kind, one line each, in the order their instances are built.
pub const KINDS: &[Registered] = &[
    kind::<surfaces::SurfaceStage>(),
    kind::<bulge::BulgeStage>(),
    kind::<interface::InterfaceStage>(),
    kind::<contact::ContactStage>(),
    kind::<contact_bem::ContactBemStage>(),
    kind::<dmw::DmwStage>(),
    kind::<excitation::ExcitationStage>(),
    kind::<simulate::SimulateStage>(),
    kind::<calibrate::CalibrateStage>(),
    kind::<doe::DoeStage>(),
    kind::<three_dof::ThreeDofStage>(),
    kind::<analysis::AnalysisStage>(),
];

/// The stage sections a pipeline file may hold (besides `[project]`).
pub fn section_names() -> Vec<&'static str> {
    KINDS.iter().map(|k| k.kind).collect()
}

/// Every case kind a worker may be asked to compute, with the stage section it belongs to.
pub fn case_kinds() -> Vec<(&'static str, &'static str)> {
    KINDS
        .iter()
        .filter_map(|k| k.case_kind.map(|c| (c, k.kind)))
        .collect()
}

/// The instance `name` of section `kind`, validated alone (a worker needs one instance, not
/// the whole pipeline); `None` when the file has no such instance.
pub fn build_instance(
    file: &PipelineFile,
    kind: &str,
    name: &str,
) -> std::result::Result<Option<Box<dyn Stage>>, ConfigError> {
    let Some(k) = KINDS.iter().find(|k| k.kind == kind) else {
        return Ok(None);
    };
    for (n, build) in (k.read)(file)? {
        if n == name {
            return build(file, &n).map(Some);
        }
    }
    Ok(None)
}

/// Read and parse a pipeline file with the registered stage sections.
pub fn load(path: &Path) -> std::result::Result<PipelineFile, ConfigError> {
    PipelineFile::load(path, &section_names())
}

/// Names reserved for hdi's own entries under `processed/`.
const RESERVED: &[&str] = &["tables", "report", ".hdi"];

/// Every declared stage instance, validated.
pub fn build(file: &PipelineFile) -> std::result::Result<Vec<Box<dyn Stage>>, ConfigError> {
    // Every table is read before any instance is validated, kinds in name order (the order
    // one serde pass over the file met them), so a misspelt key anywhere is reported first.
    let by_name: BTreeMap<&str, &Registered> = KINDS.iter().map(|k| (k.kind, k)).collect();
    let mut read = BTreeMap::new();
    for (kind, k) in by_name {
        read.insert(kind, (k.read)(file)?);
    }
    let mut stages: Vec<Box<dyn Stage>> = Vec::new();
    let mut seen = BTreeSet::new();
    let mut check_name = |section: &str, name: &str| {
        let valid = !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
            && !name.starts_with('.');
        if !valid || RESERVED.contains(&name) {
            return Err(file.error(
                section,
                name,
                "",
                format!("`{name}` cannot be a stage name (letters, digits, - _ . ; not tables)"),
            ));
        }
        if !seen.insert(name.to_string()) {
            return Err(file.error(
                section,
                name,
                "",
                format!("stage name `{name}` is used twice"),
            ));
        }
        Ok(())
    };
    for k in KINDS {
        for (name, build) in read.remove(k.kind).unwrap_or_default() {
            check_name(k.kind, &name)?;
            stages.push(build(file, &name)?);
        }
    }
    Ok(stages)
}

/// The tidy summary table of a stage kind (`processed/tables/<name>.{parquet,csv,arrow}`):
/// `surfaces`, `interfaces`, `dmw` (a mass noun), `analyses`.
pub fn summary_table_name(kind: &str) -> String {
    match kind {
        "dmw" => "dmw".into(),
        "analysis" => "analyses".into(),
        "three_dof" => "three_dof".into(),
        "doe" => "doe".into(),
        k => format!("{k}s"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> PipelineFile {
        PipelineFile::parse(Path::new("pipeline.toml"), text.into(), &section_names()).unwrap()
    }

    #[test]
    fn every_kind_is_registered_once() {
        let names = section_names();
        let unique: BTreeSet<&str> = names.iter().copied().collect();
        assert_eq!(unique.len(), names.len(), "{names:?}");
        assert_eq!(names.len(), 12);
    }

    #[test]
    fn a_misspelt_key_is_reported_at_its_line_before_any_instance_is_validated() {
        // The surface's file does not exist: that error comes second, as with one serde pass.
        let text = "[surface.disk]\nfile = \"nope.gwy\"\n\n[simulate.x]\ncontact = \"c\"\n\
                    actuations = [\"5 nm\"]\nduraton = \"1 ms\"\n";
        let msg = build(&parse(text)).err().unwrap().to_string();
        assert!(
            msg.starts_with("pipeline.toml:7: unknown key `duraton` (did you mean `duration`?)"),
            "{msg}"
        );
    }

    #[test]
    fn names_are_checked_in_build_order() {
        let text = "[surface.tables]\nfile = \"a\"\n";
        let msg = build(&parse(text)).err().unwrap().to_string();
        assert_eq!(
            msg,
            "pipeline.toml:1: surface.tables: `tables` cannot be a stage name (letters, digits, \
             - _ . ; not tables)"
        );
    }
}
