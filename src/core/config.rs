//! `pipeline.toml`: parsing with file/line/key errors, then typed access to its sections.
//!
//! Two levels, as ripgrep does for flags: serde structs with `deny_unknown_fields` (what the
//! user wrote) → validated stage instances (SI units, ranges, files checked). The core knows
//! only `[project]` and `[report]` (the HTML report, docs/report.md): every other top-level
//! table is a stage kind's, kept as written (with the source spans) until its consumer
//! deserializes it into its own config type. Every error
//! names the file, the line and the key, and for a misspelt key the nearest valid one.

use serde::de::DeserializeOwned;
use serde::Deserialize;
use std::collections::{BTreeMap, BTreeSet};
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::de::{DeTable, DeValue, ValueDeserializer};
use toml::Spanned;

/// Errors in a pipeline file. `line` is 1-based; 0 when unknown.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error("cannot read {path}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}:{line}: {}", file.display(), keyed(key, message))]
    Invalid {
        file: PathBuf,
        line: usize,
        key: String,
        message: String,
    },
}

/// A config check's failure, before it is located in a file: the offending key of the
/// section (empty for the section as a whole) and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{key}: {message}")]
pub struct KeyError {
    pub key: String,
    pub message: String,
}

impl KeyError {
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            key: key.into(),
            message: message.into(),
        }
    }

    /// The error located at `[section.name] key` in `file`.
    pub fn locate(self, file: &PipelineFile, section: &str, name: &str) -> ConfigError {
        file.error(section, name, &self.key, self.message)
    }
}

/// `[project]`: where outputs go.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ProjectConfig {
    /// Output directory, relative to the pipeline file.
    #[serde(default = "default_processed")]
    pub processed: PathBuf,
    /// Free text, kept in outputs' provenance.
    #[serde(default)]
    pub name: String,
}

fn default_processed() -> PathBuf {
    PathBuf::from("processed")
}

/// `[report]`: the HTML report `hdi run` writes at its end (docs/report.md).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ReportConfig {
    /// Write `processed/report/` at the end of `hdi run`.
    #[serde(default = "yes")]
    pub enabled: bool,
    /// Include the `hdi validate` table (seconds of computation when the report is rebuilt).
    #[serde(default = "yes")]
    pub validation: bool,
}

fn yes() -> bool {
    true
}

impl Default for ReportConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            validation: true,
        }
    }
}

impl Default for ProjectConfig {
    fn default() -> Self {
        Self {
            processed: default_processed(),
            name: String::new(),
        }
    }
}

/// A loaded pipeline file: its text (for line lookups), `[project]`, and one table per stage
/// kind with one sub-table per named instance, as written.
#[derive(Debug, Clone)]
pub struct PipelineFile {
    pub path: PathBuf,
    /// Directory that relative paths in the file are resolved against.
    pub dir: PathBuf,
    pub text: String,
    pub project: ProjectConfig,
    pub report: ReportConfig,
    /// The stage kinds the file has tables for, with their instance names. A kind's tables
    /// are deserialized from `text` when asked for, so their errors carry the same spans (and
    /// lines) as a whole-file parse gives.
    sections: BTreeMap<String, BTreeSet<String>>,
}

impl PipelineFile {
    /// Read and parse `path`; `kinds` are the stage sections the file may hold besides
    /// `[project]` (the registry's list).
    pub fn load(path: &Path, kinds: &[&str]) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(path, text, kinds)
    }

    /// Parse the TOML, check `[project]` and that every other top-level table is one of
    /// `kinds`. The stage tables themselves are checked when their kind reads them.
    pub fn parse(path: &Path, text: String, kinds: &[&str]) -> Result<Self, ConfigError> {
        let invalid =
            |span: Option<Range<usize>>, (key, message): (String, String)| ConfigError::Invalid {
                file: path.to_path_buf(),
                line: span.map(|s| line_of_offset(&text, s.start)).unwrap_or(0),
                key,
                message,
            };
        let root = DeTable::parse(&text)
            .map_err(|e| invalid(e.span(), explain_toml_error(e.message())))?
            .into_inner();
        let mut project = ProjectConfig::default();
        let mut report = ReportConfig::default();
        let mut sections = BTreeMap::new();
        // In key order, as one serde pass over the whole file met them.
        for (key, value) in root {
            let name: &str = key.get_ref();
            if name == "project" {
                let span = value.span();
                project =
                    ProjectConfig::deserialize(ValueDeserializer::from(value)).map_err(|e| {
                        invalid(e.span().or(Some(span)), explain_toml_error(e.message()))
                    })?;
            } else if name == "report" {
                let span = value.span();
                report =
                    ReportConfig::deserialize(ValueDeserializer::from(value)).map_err(|e| {
                        invalid(e.span().or(Some(span)), explain_toml_error(e.message()))
                    })?;
            } else if kinds.contains(&name) {
                let names = value.get_ref().as_table().map(|t| {
                    t.keys()
                        .map(|k| -> &str { k.get_ref() })
                        .map(str::to_string)
                        .collect()
                });
                sections.insert(name.to_string(), names.unwrap_or_default());
            } else {
                let mut known = vec!["project", "report"];
                known.extend_from_slice(kinds);
                return Err(invalid(Some(key.span()), unknown_key(name, &known)));
            }
        }
        let dir = path
            .parent()
            .map(|p| {
                if p.as_os_str().is_empty() {
                    PathBuf::from(".")
                } else {
                    p.to_path_buf()
                }
            })
            .unwrap_or_else(|| PathBuf::from("."));
        Ok(Self {
            path: path.to_path_buf(),
            dir,
            text,
            project,
            report,
            sections,
        })
    }

    /// Every `[kind.NAME]` instance deserialized into the kind's config type `C`, by name.
    pub fn instances<C: DeserializeOwned>(
        &self,
        kind: &str,
    ) -> Result<Vec<(String, C)>, ConfigError> {
        let all = self.with_section(kind, |section| {
            self.deserialize::<BTreeMap<String, C>>(section)
        })?;
        Ok(all.unwrap_or_default().into_iter().collect())
    }

    /// The `[kind.name]` instance deserialized into `C`, if the file declares it.
    pub fn instance<C: DeserializeOwned>(
        &self,
        kind: &str,
        name: &str,
    ) -> Result<Option<C>, ConfigError> {
        let found = self.with_section(kind, |section| match section.get_ref().as_table() {
            Some(table) => table
                .get(name)
                .map(|value| self.deserialize(value))
                .transpose(),
            // Not a table: the whole section's error.
            None => self
                .deserialize::<BTreeMap<String, C>>(section)
                .map(|mut all| all.remove(name)),
        })?;
        Ok(found.flatten())
    }

    /// Whether the file declares `[kind.name]`.
    pub fn has_instance(&self, kind: &str, name: &str) -> bool {
        self.sections.get(kind).is_some_and(|n| n.contains(name))
    }

    /// Whether the file declares an instance `name` of any kind.
    pub fn has_any_instance(&self, name: &str) -> bool {
        self.sections.values().any(|n| n.contains(name))
    }

    /// The instance names of `kind`, sorted.
    pub fn instance_names(&self, kind: &str) -> Vec<&str> {
        self.sections
            .get(kind)
            .map(|n| n.iter().map(String::as_str).collect())
            .unwrap_or_default()
    }

    /// `f` applied to the `kind` table of the file, if it has one. The text is parsed again:
    /// toml's spanned tree borrows it, and files are small.
    fn with_section<R>(
        &self,
        kind: &str,
        f: impl FnOnce(&Spanned<DeValue<'_>>) -> Result<R, ConfigError>,
    ) -> Result<Option<R>, ConfigError> {
        if !self.sections.contains_key(kind) {
            return Ok(None);
        }
        let root = DeTable::parse(&self.text).map_err(|e| self.toml_error(&e, None))?;
        root.get_ref().get(kind).map(f).transpose()
    }

    /// Deserialize a value of the file, reporting errors at their line in `text`.
    fn deserialize<C: DeserializeOwned>(
        &self,
        value: &Spanned<DeValue<'_>>,
    ) -> Result<C, ConfigError> {
        C::deserialize(ValueDeserializer::from(value.clone()))
            .map_err(|e| self.toml_error(&e, Some(value.span())))
    }

    /// A toml error at its line (or at `fallback`'s when it has no span of its own).
    fn toml_error(&self, e: &toml::de::Error, fallback: Option<Range<usize>>) -> ConfigError {
        let (key, message) = explain_toml_error(e.message());
        ConfigError::Invalid {
            file: self.path.clone(),
            line: e
                .span()
                .or(fallback)
                .map(|s| line_of_offset(&self.text, s.start))
                .unwrap_or(0),
            key,
            message,
        }
    }

    /// Resolve a path written in the file relative to the file's directory.
    pub fn resolve(&self, p: &Path) -> PathBuf {
        if p.is_absolute() || self.dir == Path::new(".") {
            p.to_path_buf()
        } else {
            self.dir.join(p)
        }
    }

    /// The output directory.
    pub fn processed_dir(&self) -> PathBuf {
        self.resolve(&self.project.processed)
    }

    /// The input file `written` (resolved against the file's directory), which must exist and
    /// be a file; otherwise an error at `[section.name] key` naming it as `what`.
    pub fn input_file(
        &self,
        section: &str,
        name: &str,
        key: &str,
        written: &Path,
        what: &str,
    ) -> Result<PathBuf, ConfigError> {
        let path = self.resolve(written);
        if path.is_file() {
            return Ok(path);
        }
        let why = if path.exists() {
            "is not a file"
        } else {
            "not found"
        };
        Err(self.error(
            section,
            name,
            key,
            format!("{what} {} {why}", path.display()),
        ))
    }

    /// A validation error located at `[section.name] key`.
    pub fn error(&self, section: &str, name: &str, key: &str, message: String) -> ConfigError {
        let line = find_key_line(&self.text, &format!("{section}.{name}"), key).unwrap_or(0);
        ConfigError::Invalid {
            file: self.path.clone(),
            line,
            key: if key.is_empty() {
                format!("{section}.{name}")
            } else {
                format!("{section}.{name}.{key}")
            },
            message,
        }
    }
}

/// Prefix the message with the key unless it already names it.
fn keyed(key: &str, message: &str) -> String {
    if key.is_empty() || message.contains(&format!("`{key}`")) {
        message.to_string()
    } else {
        format!("{key}: {message}")
    }
}

fn line_of_offset(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|b| **b == b'\n')
        .count()
        + 1
}

/// Line of `key = …` inside table `[table]` (or of the header itself when `key` is empty).
/// A plain line scan: enough for the block-style files hdi documents.
pub fn find_key_line(text: &str, table: &str, key: &str) -> Option<usize> {
    let mut current = String::new();
    for (idx, line) in text.lines().enumerate() {
        let t = line.trim();
        if let Some(h) = t.strip_prefix('[').and_then(|r| r.split(']').next()) {
            current = h.trim().trim_matches('[').replace(['"', ' '], "");
            if key.is_empty() && current == table {
                return Some(idx + 1);
            }
            continue;
        }
        if current == table && !key.is_empty() {
            if let Some((k, _)) = t.split_once('=') {
                if k.trim().trim_matches('"') == key {
                    return Some(idx + 1);
                }
            }
        }
    }
    None
}

/// Turn toml/serde's message into (key, message) with a "did you mean" for unknown keys.
fn explain_toml_error(msg: &str) -> (String, String) {
    let msg = msg.trim();
    if let Some(rest) = msg.strip_prefix("unknown field `") {
        let unknown = rest.split('`').next().unwrap_or("");
        let expected: Vec<&str> = rest
            .split_once("expected")
            .map(|(_, list)| list.split('`').skip(1).step_by(2).collect())
            .unwrap_or_default();
        return unknown_key(unknown, &expected);
    }
    (String::new(), msg.replace('\n', " "))
}

/// (key, message) for a key that is none of `expected`, with the nearest as a hint.
fn unknown_key(unknown: &str, expected: &[&str]) -> (String, String) {
    let hint = nearest(unknown, expected)
        .map(|n| format!(" (did you mean `{n}`?)"))
        .unwrap_or_default();
    let valid = if expected.is_empty() {
        String::new()
    } else {
        format!("; valid keys: {}", expected.join(", "))
    };
    (
        unknown.to_string(),
        format!("unknown key `{unknown}`{hint}{valid}"),
    )
}

/// The candidate with the smallest edit distance, if it is close enough to be a typo.
pub fn nearest<'a>(word: &str, candidates: &[&'a str]) -> Option<&'a str> {
    candidates
        .iter()
        .map(|c| (edit_distance(word, c), *c))
        .min()
        .filter(|(d, c)| *d <= 3.max(c.len() / 3))
        .map(|(_, c)| c)
}

fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != *cb))
                .min(prev[j + 1] + 1)
                .min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stage kind's table as the tests need one (the core names no real stage).
    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Surface {
        #[allow(dead_code)]
        file: String,
        #[serde(default)]
        #[allow(dead_code)]
        filter_l: Option<String>,
    }

    const KINDS: &[&str] = &["surface", "simulate"];

    fn parse(text: &str) -> Result<PipelineFile, ConfigError> {
        PipelineFile::parse(Path::new("pipeline.toml"), text.to_string(), KINDS)
    }

    #[test]
    fn unknown_key_names_file_line_and_nearest_key() {
        let text = "[surface.disk]\nfile = \"a.gwy\"\nfilter_k = \"5 um\"\n";
        let err = parse(text)
            .unwrap()
            .instances::<Surface>("surface")
            .unwrap_err();
        let msg = err.to_string();
        assert!(msg.starts_with("pipeline.toml:3:"), "{msg}");
        assert!(msg.contains("unknown key `filter_k`"), "{msg}");
        assert!(msg.contains("did you mean `filter_l`"), "{msg}");
    }

    #[test]
    fn the_report_table_defaults_to_on_and_names_a_misspelt_key() {
        let f = parse("[project]\nname = \"x\"\n").unwrap();
        assert_eq!(f.report, ReportConfig::default());
        assert!(f.report.enabled && f.report.validation);
        let f = parse("[report]\nvalidation = false\n").unwrap();
        assert!(f.report.enabled && !f.report.validation);
        let e = parse("[project]\n\n[report]\nvalidaton = false\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("pipeline.toml:4:"), "{e}");
        assert!(e.contains("did you mean `validation`"), "{e}");
    }

    #[test]
    fn unknown_stage_kind_is_rejected() {
        let text = "[surfac.disk]\nfile = \"a.gwy\"\n".to_string();
        let msg = PipelineFile::parse(Path::new("p.toml"), text, KINDS)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("did you mean `surface`"), "{msg}");
        assert_eq!(
            msg,
            "p.toml:1: unknown key `surfac` (did you mean `surface`?); valid keys: project, report, \
             surface, simulate"
        );
    }

    #[test]
    fn one_instance_reads_alone_and_reports_its_own_line() {
        let text = "[project]\nname = \"x\"\n\n[surface.a]\nfile = \"a\"\n\n[surface.b]\n\
                    file = \"b\"\nfilter = 1\n";
        let file = parse(text).unwrap();
        assert!(file.instance::<Surface>("surface", "a").unwrap().is_some());
        assert!(file.instance::<Surface>("surface", "c").unwrap().is_none());
        assert!(file.instance::<Surface>("simulate", "a").unwrap().is_none());
        let msg = file
            .instance::<Surface>("surface", "b")
            .unwrap_err()
            .to_string();
        assert!(
            msg.starts_with("pipeline.toml:9: unknown key `filter`"),
            "{msg}"
        );
        assert!(file.has_instance("surface", "b") && !file.has_instance("simulate", "b"));
        assert_eq!(file.instance_names("surface"), ["a", "b"]);
        assert_eq!(file.project.name, "x");
    }

    #[test]
    fn key_lines_are_found_in_their_table() {
        let text = "[surface.a]\nfile = 1\n\n[surface.b]\nfile = 2\n";
        assert_eq!(find_key_line(text, "surface.b", "file"), Some(5));
        assert_eq!(find_key_line(text, "surface.b", ""), Some(4));
    }
}
