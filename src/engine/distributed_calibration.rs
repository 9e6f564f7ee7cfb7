//! The worker of a calibration case on a Slurm node (docs/slurm.md, "Calibration on Slurm"):
//! rebuilds the `[calibrate]` instance's base from the pipeline file and the upstream entries
//! the submitting fit used, checks that it arrives at the submitter's key, and computes the
//! case with `dynamics::calibration::round_case` — the function the fit's own rounds run.

use crate::core::cache::Store;
use crate::core::cases::case_fingerprint;
use crate::core::executor::CaseFailure;
use crate::dynamics::calibration::round_case;
use crate::engine::read_result;
use crate::error::{Error, Result};
use crate::slider::calibration::{base_inputs, base_of};
use crate::stages::calibrate::{
    case_params, case_result, geometry_from_name, knobs_from_json, CalibrateConfig, CalibrateStage,
    CALIBRATION_CASE, CASE_MODEL_VERSION,
};
use crate::stages::FromConfig;
use serde_json::Value;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::sync::{Arc, Mutex};

/// A `[calibrate]` instance's base as a worker rebuilds it (once per process and instance:
/// a task runs a round's cases of one fit).
struct Inputs {
    stage: CalibrateStage,
    isbl: crate::contact::isbl::IsblParams,
    dmw: Option<crate::artefacts::dmw_tracks::DmwTrack>,
    base_params: Value,
}

/// Computes `calibration` cases.
#[derive(Default)]
pub struct CalibrationWorker {
    inputs: Mutex<HashMap<(String, String, String), Arc<Inputs>>>,
}

fn field(recipe: &Value, k: &str) -> Result<String> {
    super::distributed::recipe_field(recipe, CALIBRATION_CASE, k)
}

impl CalibrationWorker {
    fn inputs(&self, recipe: &Value, store: &Store) -> Result<Arc<Inputs>> {
        let (config, instance) = (field(recipe, "config")?, field(recipe, "instance")?);
        let upstream = recipe["upstream"].as_array().ok_or(Error::RecipeField {
            kind: CALIBRATION_CASE,
            field: "upstream".into(),
        })?;
        let id = (
            config.clone(),
            instance.clone(),
            recipe["upstream"].to_string(),
        );
        let mut cache = self
            .inputs
            .lock()
            .map_err(|_| Error::Stage("a worker thread panicked".into()))?;
        if let Some(i) = cache.get(&id) {
            return Ok(Arc::clone(i));
        }
        let file = crate::stages::load(Path::new(&config))?;
        let cfg = file
            .instance::<CalibrateConfig>("calibrate", &instance)?
            .ok_or_else(|| Error::MissingInstance {
                kind: "calibrate",
                name: instance.clone(),
            })?;
        let stage = CalibrateStage::from_config(&file, &instance, &cfg)?;
        // The entries the submitting fit read (by key, not by what the pipeline file would
        // plan now): the key check below then proves both sides hash the same inputs.
        let (mut results, mut dirs, mut keys) = (BTreeMap::new(), BTreeMap::new(), BTreeMap::new());
        for u in upstream {
            let bad = || Error::RecipeField {
                kind: CALIBRATION_CASE,
                field: "upstream".into(),
            };
            let name = u["name"].as_str().ok_or_else(bad)?.to_string();
            let dir = store.processed().join(u["dir"].as_str().ok_or_else(bad)?);
            results.insert(name.clone(), read_result(&dir)?);
            dirs.insert(name.clone(), dir);
            keys.insert(name, u["key"].as_str().ok_or_else(bad)?.to_string());
        }
        let (isbl, dmw) = base_inputs(&stage.base, &results, &dirs)?;
        let base_params = stage.case_base_params(|n| keys.get(n).cloned().unwrap_or_default());
        let inputs = Arc::new(Inputs {
            stage,
            isbl,
            dmw,
            base_params,
        });
        cache.insert(id, Arc::clone(&inputs));
        Ok(inputs)
    }

    fn compute_recipe(&self, recipe: &Value, store: &Store) -> Result<Value> {
        let bad = |f: &str| Error::RecipeField {
            kind: CALIBRATION_CASE,
            field: f.to_string(),
        };
        let inputs = self.inputs(recipe, store)?;
        let knobs = knobs_from_json(&recipe["knobs"]).ok_or_else(|| bad("knobs"))?;
        let geometry = recipe["geometry"]
            .as_str()
            .and_then(geometry_from_name)
            .ok_or_else(|| bad("geometry"))?;
        let actuation = recipe["actuation_m"]
            .as_f64()
            .ok_or_else(|| bad("actuation_m"))?;
        let params = case_params(&inputs.base_params, &knobs, geometry, actuation);
        let key = case_fingerprint(CASE_MODEL_VERSION, &params).key();
        let wanted = field(recipe, "key")?;
        if key != wanted {
            return Err(Error::Stage(format!(
                "calibration case: the submitter's key is {wanted}, this node rebuilds {key} \
                 (pipeline file or hdi changed since the round was submitted?)"
            )));
        }
        let base = base_of(&inputs.stage.base, inputs.isbl, inputs.dmw.as_ref());
        let outcome = round_case(&base, &knobs, geometry, actuation);
        let result = case_result(&outcome);
        // The fit compares these numbers: they must come back bit for bit (a non-finite value
        // would not survive JSON).
        if let Ok(m) = &outcome {
            let back = serde_json::from_value(result["metrics"].clone()).ok();
            if back.as_ref() != Some(m) {
                return Err(Error::Stage(format!(
                    "calibration case {key}: its metrics do not survive JSON exactly"
                )));
            }
        }
        Ok(result)
    }
}

impl crate::core::executor::CaseComputer for CalibrationWorker {
    fn compute(
        &self,
        recipe: &Value,
        store: &Store,
        _dir: &Path,
    ) -> std::result::Result<Value, CaseFailure> {
        Ok(self.compute_recipe(recipe, store)?)
    }
}
