//! The pipeline results `hdi validate` reads (calibrated sweeps, 3-DOF stage outputs, spectra):
//! only current ones — a stage whose cache entry matches its fingerprint now — each with the
//! [`Origin`] that names the instance and its cache key.

use super::Origin;
use crate::core::cache::{Manifest, Store};
use crate::engine::{plan, read_result, Plan, State};
use crate::error::Result;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// A planned pipeline and its store.
pub struct Cache {
    store: Store,
    plan: Plan,
    /// The project directory (the pipeline file's), against which input paths resolve.
    root: PathBuf,
}

/// One current stage result.
pub struct Stored {
    pub result: Value,
    pub dir: PathBuf,
    pub origin: Origin,
}

impl Cache {
    /// Plan the pipeline in `config` against its store (nothing is run).
    pub fn open(config: &Path) -> Result<Cache> {
        let file = crate::stages::load(config)?;
        let stages = crate::stages::build(&file)?;
        let store = Store::open_existing(&file.processed_dir());
        let plan = plan(stages, &store, &Default::default())?;
        let root = config
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .map_or_else(|| PathBuf::from("."), Path::to_path_buf);
        Ok(Cache { store, plan, root })
    }

    /// The pipeline's store (its case store holds `hdi validate`'s computed 2-DOF cases).
    pub fn store(&self) -> &Store {
        &self.store
    }

    /// The current result of the instance `name`, `None` if it has not run (or is stale).
    pub fn current(&self, name: &str) -> Option<Stored> {
        let p = self
            .plan
            .planned
            .iter()
            .find(|p| p.name == name && p.state == State::Fresh)?;
        let dir = self.store.entry_dir(&p.kind, &p.key);
        let result = read_result(&dir).ok()?;
        Some(Stored {
            result,
            dir,
            origin: Origin::Cache {
                instance: format!("{}.{}", p.kind, p.name),
                key: p.key.clone(),
            },
        })
    }
}

impl Cache {
    /// How the ledger names the DMW record under the instance `name` (a `[dmw.*]` instance, or
    /// one downstream of it): `synthetic DMW record \`disk_md\`` when its file sits beside a
    /// `samples.json` written by `hdi synth` (raw/ldv/README.md), `measured DMW record …`
    /// otherwise; `None` if no current `[dmw]` instance is upstream.
    pub fn record_label(&self, name: &str) -> Option<String> {
        let mut todo = vec![name.to_string()];
        let mut seen = std::collections::BTreeSet::new();
        while let Some(n) = todo.pop() {
            if !seen.insert(n.clone()) {
                continue;
            }
            let p = self
                .plan
                .planned
                .iter()
                .find(|p| p.name == n && p.state == State::Fresh)?;
            let dir = self.store.entry_dir(&p.kind, &p.key);
            if p.kind == "dmw" {
                let DmwRecordFile { file } =
                    serde_json::from_value(read_result(&dir).ok()?).ok()?;
                return Some(format!(
                    "{} DMW record `{n}`",
                    if synthesised(&self.root.join(file)) {
                        "synthetic"
                    } else {
                        "measured"
                    }
                ));
            }
            let manifest: Manifest =
                serde_json::from_slice(&std::fs::read(dir.join("manifest.json")).ok()?).ok()?;
            todo.extend(manifest.fingerprint.upstream.into_iter().map(|u| u.name));
        }
        None
    }
}

/// The one field of a `[dmw]` result (`DmwStageResult`, written by its stage) read here: the
/// record file, relative to the project directory.
#[derive(serde::Deserialize)]
struct DmwRecordFile {
    file: String,
}

/// Whether `file` was written by `hdi synth`: its folder's `samples.json` names it and that
/// generator.
fn synthesised(file: &Path) -> bool {
    let Some(samples) = file.parent().map(|d| d.join("samples.json")) else {
        return false;
    };
    let Ok(text) = std::fs::read(samples) else {
        return false;
    };
    let Ok(v) = serde_json::from_slice::<SynthSamples>(&text) else {
        return false;
    };
    let named = file
        .file_name()
        .and_then(|f| f.to_str())
        .is_some_and(|f| v.file.as_deref() == Some(f));
    named
        && v.generator
            .as_deref()
            .is_some_and(|g| g.starts_with("hdi synth"))
}

/// The two fields of `hdi synth`'s `samples.json` read here (a record it wrote: its file
/// name and the generator); either may be absent from a hand-written file.
#[derive(serde::Deserialize)]
struct SynthSamples {
    file: Option<String>,
    generator: Option<String>,
}

/// The cache of `config`, if it exists and plans.
pub fn open(config: Option<&Path>) -> Option<Cache> {
    config.and_then(|c| Cache::open(c).ok())
}

/// The summit distribution measured on the pipeline's surfaces (docs/model-form.md, "Summit
/// heights"): `(σ_s/σ, y_s/σ)` of the source a `[contact.*]` with
/// `summit_distribution = "measured"` names, else of the first `[interface.*]` of two surfaces
/// (shipped: `[interface.hdi]`, disk + slider), from their current results.
pub struct MeasuredSummits {
    pub sigma_ratio: f64,
    pub offset_ratio: f64,
    /// What they were measured on (for a row's `inputs`).
    pub inputs: String,
    pub origin: Origin,
}

/// The contact law of the pipeline's first `[contact_bem.*]` instance (its force–separation
/// curve on the measured map) for the `contact_law = bem` variants; `None` where it has not run.
pub struct BemLaw {
    pub law: std::sync::Arc<crate::contact::bem::law::ContactCurve>,
    pub inputs: String,
    pub origin: Origin,
}

pub fn bem_law(config: &Path, cache: &Cache) -> Option<BemLaw> {
    let file = crate::stages::load(config).ok()?;
    let name = file.instance_names("contact_bem").first()?.to_string();
    let stored = cache.current(&name)?;
    let up = std::collections::BTreeMap::from([(name.clone(), stored.result)]);
    let law = crate::slider::sweep::upstream_contact_law(&up, &name).ok()?;
    let (lo, hi) = law.measured_range();
    let key = match stored.origin {
        Origin::Cache { key, .. } => key,
        _ => String::new(),
    };
    Some(BemLaw {
        law,
        inputs: format!(
            "the FFT-BEM curve of [contact_bem.{name}] (mean gap {:.3}–{:.3} nm solved; \
             exponential beyond)",
            lo * 1e9,
            hi * 1e9
        ),
        origin: Origin::Recomputed {
            instance: format!("contact_bem.{name}"),
            key,
        },
    })
}

/// [`MeasuredSummits`] of the pipeline in `config`; `None` where its surfaces have not run.
pub fn measured_summits(config: &Path, cache: &Cache) -> Option<MeasuredSummits> {
    use crate::artefacts::interface::InterfaceSurfaces;
    use crate::stages::contact::{ContactConfig, SummitOrigin};
    let file = crate::stages::load(config).ok()?;
    let interfaces: Vec<(String, InterfaceSurfaces)> = file.instances("interface").ok()?;
    let named = file
        .instances::<ContactConfig>("contact")
        .ok()?
        .into_iter()
        .find(|(_, c)| c.summit_distribution.as_deref() == Some("measured"))
        .and_then(|(_, c)| c.summit_source.or(c.interface));
    let (source, surfaces) = match named {
        Some(n) if file.has_instance("surface", &n) => (n.clone(), vec![n]),
        Some(n) => {
            let i = interfaces.iter().find(|(name, _)| *name == n)?;
            (n, i.1.surfaces.clone())
        }
        None => interfaces
            .iter()
            .find(|(_, i)| i.has_two_surfaces())
            .map(|(n, i)| (n.clone(), i.surfaces.clone()))?,
    };
    let mut heights = Vec::new();
    let mut keys = Vec::new();
    for s in &surfaces {
        let stored = cache.current(s)?;
        let up = std::collections::BTreeMap::from([(s.clone(), stored.result)]);
        heights.push((
            s.clone(),
            crate::artefacts::surface::upstream_summit_heights(&up, s).ok()?,
        ));
        if let Origin::Cache { key, .. } = stored.origin {
            keys.push(key);
        }
    }
    let origin = SummitOrigin::measured(&source, heights).ok()?;
    let (sigma_ratio, offset_ratio) = origin.ratios();
    Some(MeasuredSummits {
        sigma_ratio,
        offset_ratio,
        inputs: format!(
            "summits measured on {} (σ_s/σ = {sigma_ratio:.4}, y_s/σ = {offset_ratio:.4})",
            surfaces
                .iter()
                .map(|s| format!("[surface.{s}]"))
                .collect::<Vec<_>>()
                .join(" + ")
        ),
        origin: Origin::Recomputed {
            instance: surfaces
                .iter()
                .map(|s| format!("surface.{s}"))
                .collect::<Vec<_>>()
                .join(" + "),
            key: keys.join("+"),
        },
    })
}
