//! `pipeline.toml`: parsing with file/line/key errors, then validation into stage instances.
//!
//! Two levels, as ripgrep does for flags: serde structs with `deny_unknown_fields` (what the
//! user wrote) → validated stage instances (SI units, ranges, files checked). Every error names
//! the file, the line and the key, and for a misspelt key the nearest valid one.

use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::stages::contact::ContactConfig;
use crate::stages::dmw::DmwConfig;
use crate::stages::interface::InterfaceConfig;
use crate::stages::surfaces::SurfaceConfig;

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

impl Default for ProjectConfig {
    fn default() -> Self {
        Self {
            processed: default_processed(),
            name: String::new(),
        }
    }
}

/// The file as written: one table per stage kind, one sub-table per named instance.
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct RawConfig {
    #[serde(default)]
    pub project: ProjectConfig,
    /// `[surface.NAME]`: one height map → roughness parameters.
    #[serde(default)]
    pub surface: BTreeMap<String, SurfaceConfig>,
    /// `[interface.NAME]`: two surfaces (or explicit values) → combined σ, R, η, β.
    #[serde(default)]
    pub interface: BTreeMap<String, InterfaceConfig>,
    /// `[dmw.NAME]`: one LDV record → the three dynamic-microwaviness tracks.
    #[serde(default)]
    pub dmw: BTreeMap<String, DmwConfig>,
    /// `[contact.NAME]`: an interface → ISBL curves and the force table.
    #[serde(default)]
    pub contact: BTreeMap<String, ContactConfig>,
    /// `[simulate.NAME]`: 2-DOF slider cases over an actuation sweep.
    #[serde(default)]
    pub simulate: BTreeMap<String, crate::stages::simulate::SimulateConfig>,
    /// `[three_dof.NAME]`: the 3-DOF slider of Chapter 4 in one scenario.
    #[serde(default)]
    pub three_dof: BTreeMap<String, crate::stages::three_dof::ThreeDofConfig>,
    /// `[excitation.NAME]`: a synthetic disk-motion track (Appendix B) in the DMW layout.
    #[serde(default)]
    pub excitation: BTreeMap<String, crate::stages::excitation::ExcitationConfig>,
    /// `[analysis.NAME]`: spectrum, wavelet transform, Poincaré section of an upstream series.
    #[serde(default)]
    pub analysis: BTreeMap<String, crate::stages::analysis::AnalysisConfig>,
    /// `[calibrate.NAME]`: fit the dropped knobs of a `[simulate]` instance to the published
    /// class-D landmarks.
    #[serde(default)]
    pub calibrate: BTreeMap<String, crate::stages::calibrate::CalibrateConfig>,
    /// `[doe.NAME]`: the §2.3 design of experiments, response surfaces and optimisation.
    #[serde(default)]
    pub doe: BTreeMap<String, crate::stages::doe::DoeConfig>,
}

/// A loaded pipeline file: its text (for line lookups) and parsed content.
#[derive(Debug, Clone)]
pub struct PipelineFile {
    pub path: PathBuf,
    /// Directory that relative paths in the file are resolved against.
    pub dir: PathBuf,
    pub text: String,
    pub raw: RawConfig,
}

impl PipelineFile {
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(path, text)
    }

    pub fn parse(path: &Path, text: String) -> Result<Self, ConfigError> {
        let raw: RawConfig = toml::from_str(&text).map_err(|e| {
            let line = e
                .span()
                .map(|s| line_of_offset(&text, s.start))
                .unwrap_or(0);
            let (key, message) = explain_toml_error(e.message());
            ConfigError::Invalid {
                file: path.to_path_buf(),
                line,
                key,
                message,
            }
        })?;
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
            raw,
        })
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
        self.resolve(&self.raw.project.processed)
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
        let unknown = rest.split('`').next().unwrap_or("").to_string();
        let expected: Vec<&str> = rest
            .split_once("expected")
            .map(|(_, list)| list.split('`').skip(1).step_by(2).collect())
            .unwrap_or_default();
        let hint = nearest(&unknown, &expected)
            .map(|n| format!(" (did you mean `{n}`?)"))
            .unwrap_or_default();
        let valid = if expected.is_empty() {
            String::new()
        } else {
            format!("; valid keys: {}", expected.join(", "))
        };
        return (
            unknown.clone(),
            format!("unknown key `{unknown}`{hint}{valid}"),
        );
    }
    (String::new(), msg.replace('\n', " "))
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

    #[test]
    fn unknown_key_names_file_line_and_nearest_key() {
        let text = "[surface.disk]\nfile = \"a.gwy\"\nfilter_k = \"5 um\"\n".to_string();
        let err = PipelineFile::parse(Path::new("pipeline.toml"), text).unwrap_err();
        let msg = err.to_string();
        assert!(msg.starts_with("pipeline.toml:3:"), "{msg}");
        assert!(msg.contains("unknown key `filter_k`"), "{msg}");
        assert!(msg.contains("did you mean `filter_l`"), "{msg}");
    }

    #[test]
    fn unknown_stage_kind_is_rejected() {
        let text = "[surfac.disk]\nfile = \"a.gwy\"\n".to_string();
        let msg = PipelineFile::parse(Path::new("p.toml"), text)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("did you mean `surface`"), "{msg}");
    }

    #[test]
    fn key_lines_are_found_in_their_table() {
        let text = "[surface.a]\nfile = 1\n\n[surface.b]\nfile = 2\n";
        assert_eq!(find_key_line(text, "surface.b", "file"), Some(5));
        assert_eq!(find_key_line(text, "surface.b", ""), Some(4));
    }
}
