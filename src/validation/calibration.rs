//! `hdi validate` area `calibration`: the fits of the pipeline in the working directory,
//! re-evaluated now with the current code.

use super::{Class, Origin, Row, Tolerance};
use crate::artefacts::calibration::{fitted_knobs, CalibrateResult, TargetRecord};
use crate::core::cache::Store;
use crate::dynamics::calibration::{evaluate, evaluate_held_out, Evaluation, Knob};
use crate::engine::{plan, read_result, State};
use crate::error::{Error, Result};
use crate::slider::calibration::{base_inputs, base_of};
use crate::stages::calibrate::{describe_knobs, CalibrateConfig, CalibrateStage};
use crate::stages::{FromConfig, StageKind};
use serde::Deserialize;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Re-evaluate a finished calibration now (for `hdi validate`): the targets at its fitted
/// knobs, computed with the current code from its upstream inputs.
pub fn re_evaluate(
    stage: &CalibrateStage,
    fitted: &[(Knob, f64)],
    upstream: &BTreeMap<String, Value>,
    upstream_dirs: &BTreeMap<String, PathBuf>,
) -> Result<Evaluation> {
    let (isbl, dmw) = base_inputs(&stage.base, upstream, upstream_dirs)?;
    let base = base_of(&stage.base, isbl, dmw.as_ref());
    Ok(evaluate(&base, &stage.settings, fitted)?)
}

/// The held-out sets of `[calibrate.NAME]` in the pipeline `config`, evaluated now at the spec
/// defaults (no fitted knobs) on the calibration's own base, grid and upstream inputs, after
/// `adjust` has changed the base's case options and interface (a model-form variant; the
/// selection discipline of docs/model-form.md). The upstream instances must be current (`hdi
/// run --only NAME` has run); the calibration itself need not be.
pub fn held_out_under(
    config: &Path,
    name: &str,
    contact_law: Option<std::sync::Arc<crate::contact::bem::law::ContactCurve>>,
    adjust: impl Fn(&mut crate::slider::params::SimulateParams, &mut crate::contact::isbl::IsblParams),
) -> Result<Evaluation> {
    let file = crate::stages::load(config)?;
    let stages = crate::stages::build(&file)?;
    let store = Store::open_existing(&file.processed_dir());
    let plan = plan(stages, &store, &Default::default())?;
    let cfg = file
        .instances::<CalibrateConfig>("calibrate")?
        .into_iter()
        .find(|(n, _)| n == name)
        .map(|(_, c)| c)
        .ok_or_else(|| Error::UpstreamField {
            kind: "calibrate",
            name: name.to_string(),
            what: "an instance of that name in the pipeline".into(),
        })?;
    let stage = CalibrateStage::from_config(&file, name, &cfg)?;
    let mut up = BTreeMap::new();
    let mut dirs = BTreeMap::new();
    for u in stage.upstream() {
        let p = plan
            .planned
            .iter()
            .find(|p| p.name == u && p.state == State::Fresh)
            .ok_or_else(|| Error::UpstreamField {
                kind: "calibrate",
                name: name.to_string(),
                what: format!("a current `{u}` (run `hdi run --only {name}` first)"),
            })?;
        let dir = store.entry_dir(&p.kind, &p.key);
        up.insert(u.clone(), read_result(&dir)?);
        dirs.insert(u, dir);
    }
    let (mut isbl, dmw) = base_inputs(&stage.base, &up, &dirs)?;
    let mut params = stage.base.clone();
    adjust(&mut params, &mut isbl);
    let mut base = base_of(&params, isbl, dmw.as_ref());
    base.contact_law = contact_law;
    Ok(evaluate_held_out(&base, &stage.settings, &[])?)
}

/// `hdi validate` area `calibration`: for every `[calibrate.*]` of the pipeline whose result is
/// current, its targets re-evaluated now at the fitted knobs (one row per target, class D, the
/// fitted values in the variant column). A fit that has not run (or is stale) gives one row
/// without a number that says so.
pub fn rows(config: &Path) -> Result<Vec<Row>> {
    let file = crate::stages::load(config)?;
    let stages = crate::stages::build(&file)?;
    let store = Store::open_existing(&file.processed_dir());
    let plan = plan(stages, &store, &Default::default())?;
    let mut rows = Vec::new();
    for (name, cfg) in &file.instances::<CalibrateConfig>("calibrate")? {
        let stage = CalibrateStage::from_config(&file, name, cfg)?;
        let planned = |n: &str| plan.planned.iter().find(|p| p.name == n);
        let current = |n: &str| planned(n).is_some_and(|p| p.state == State::Fresh);
        let upstream = stage.upstream();
        if !current(name) || !upstream.iter().all(|u| current(u)) {
            rows.push(
                Row::new(
                    &format!("cal-{name}"),
                    Class::D,
                    &format!("calibration of {}", stage.base_name),
                    "1",
                    f64::NAN,
                    f64::NAN,
                    Tolerance::Absolute(1.0),
                )
                .variant("not run")
                .by_construction("the fit's own record")
                .not_run(&format!(
                    "a current result of [calibrate.{name}]: `hdi run --only {name}`"
                )),
            );
            continue;
        }
        let entry = |n: &str| {
            let p = planned(n).expect("checked above");
            store.entry_dir(&p.kind, &p.key)
        };
        let result = CalibrateResult::deserialize(read_result(&entry(name))?).map_err(|e| {
            Error::UpstreamField {
                kind: "calibrate",
                name: name.to_string(),
                what: format!("readable result ({e})"),
            }
        })?;
        let fitted = fitted_knobs(&result).ok_or_else(|| Error::UpstreamField {
            kind: "calibrate",
            name: name.to_string(),
            what: "usable `fitted`".into(),
        })?;
        let mut up = BTreeMap::new();
        let mut dirs = BTreeMap::new();
        for u in &upstream {
            up.insert(u.clone(), read_result(&entry(u))?);
            dirs.insert(u.clone(), entry(u));
        }
        let e = re_evaluate(&stage, &fitted, &up, &dirs)?;
        let (defaults, fit) = (&result.defaults.targets, &result.calibrated.targets);
        let key = planned(name).map_or(String::new(), |p| p.key.clone());
        for o in &e.outcomes {
            let t = &o.target;
            let scale = t.display_scale;
            let of = |set: &[TargetRecord]| set.iter().find(|d| d.id == t.id).and_then(|d| d.value);
            let before = of(defaults).map_or("–".into(), |v| format!("{:.3}", v * scale));
            let now = o.value.map_or(f64::NAN, |v| v * scale);
            let in_band = (now - t.published * scale).abs() <= t.tolerance * scale;
            // The fit's own record at its knobs is the target: the row checks that the fit
            // still holds with the current code. The published number it was fitted to is in
            // the note; whether that is in band says how well the fit did, not what hdi
            // reproduces (a fitted target is no reproduction).
            let recorded = of(fit).map_or(f64::NAN, |v| v * scale);
            rows.push(
                Row::new(
                    &format!("cal-{}", t.id),
                    Class::C,
                    &format!("{} at the fitted knobs, re-evaluated now", t.id),
                    t.unit,
                    recorded,
                    now,
                    Tolerance::Absolute(1e-9 * recorded.abs().max(t.tolerance * scale)),
                )
                .by_construction(&format!(
                    "the value [calibrate.{name}] recorded at its fitted knobs (a fit's own \
                     output)"
                ))
                .reference(&format!(
                    "dissertation Ch. 2, target dyn-{}",
                    t.source.trim_start_matches('#')
                ))
                .variant(&format!("{}: {}", stage.base.model_name, describe_knobs(&fitted)))
                .inputs(&format!("the calibration's own inputs (base sweep `{}`), fitted knobs of [calibrate.{name}]", stage.base_name))
                .origin(Origin::Recomputed {
                    instance: format!("calibrate.{name}"),
                    key: key.clone(),
                })
                .note(&format!(
                    "fitted to the published {} ± {} {}: {} (residual/tolerance {:+.2}{}); \
                     default inputs {before}",
                    super::sig(t.published * scale),
                    super::sig(t.tolerance * scale),
                    t.unit,
                    if in_band { "in band" } else { "out of band" },
                    o.normalised_residual,
                    if t.weight == 0.0 {
                        ", reported, not fitted"
                    } else {
                        ""
                    }
                )),
            );
        }
    }
    Ok(rows)
}
