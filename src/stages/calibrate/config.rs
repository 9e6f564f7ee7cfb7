//! Checks of `[calibrate]` keys, in the order `CalibrateStage::from_config` reports them: the
//! knobs and their boxes, the fitted and held-out targets with their weights, the warm start.

use super::{CalibrateConfig, FIT_INPUTS_DIGITS};
use crate::contact::isbl::IsblParams;
use crate::core::config::ConfigError;
use crate::dynamics::calibration::{
    apply_knobs, default_knobs, held_out_for, targets_for, CalibrationSettings, Knob, KnobRange,
    Target,
};
use crate::slider::params::SimulateParams;

/// The calibrated knobs and their boxes: each knob once, present in the base model (and
/// `dmw_scale` only with a DMW input), bounds inside the model's range and naming a knob.
pub(super) fn knob_ranges(
    cfg: &CalibrateConfig,
    base: &SimulateParams,
    err: &impl Fn(&str, String) -> ConfigError,
) -> std::result::Result<Vec<KnobRange>, ConfigError> {
    let variant = base.model.variant;
    let knobs: Vec<Knob> = match &cfg.knobs {
        None => default_knobs(variant),
        Some(names) => names
            .iter()
            .map(|n| {
                Knob::from_name(n).ok_or_else(|| {
                    err(
                        "knobs",
                        format!(
                            "unknown knob `{n}` (known: {})",
                            Knob::ALL.map(|k| k.name()).join(", ")
                        ),
                    )
                })
            })
            .collect::<std::result::Result<_, _>>()?,
    };
    let mut ranges = Vec::new();
    let isbl_probe = IsblParams::improved_2dof();
    for k in &knobs {
        if ranges.iter().any(|r: &KnobRange| r.knob == *k) {
            return Err(err("knobs", format!("knob `{}` listed twice", k.name())));
        }
        // The knob must exist in the base model (e.g. no β on the initial model).
        if !matches!(k, Knob::SurfaceEnergy) {
            k.base_value(&base.model, &isbl_probe)
                .map_err(|e| err("knobs", e.to_string()))?;
        }
        if *k == Knob::DmwScale && base.dmw.is_none() {
            return Err(err(
                "knobs",
                format!(
                    "dmw_scale needs a DMW input, but [simulate.{}] has dmw = \"none\"",
                    cfg.simulate
                ),
            ));
        }
        let mut r = KnobRange::new(*k);
        if let Some([lo, hi]) = cfg.bounds.get(k.name()) {
            (r.lo, r.hi) = (*lo, *hi);
            // A box wider than the model accepts would hand the fit points the model
            // rejects: refuse it here, naming the model's limit.
            for v in [*lo, *hi] {
                let (mut m, mut i) = (base.model, isbl_probe);
                apply_knobs(&[(*k, v)], &mut m, &mut i).map_err(|e| {
                    err(
                        "bounds",
                        format!("{} = {v:e} is outside the model's range: {e}", k.name()),
                    )
                })?;
            }
        }
        ranges.push(r);
    }
    for b in cfg.bounds.keys() {
        if !knobs.iter().any(|k| k.name() == b) {
            return Err(err(
                "bounds",
                format!("`{b}` is not one of the calibrated knobs"),
            ));
        }
    }
    Ok(ranges)
}

/// The fitted and the held-out targets (by id from the variant's catalogues) with the
/// configured weights; at least one fitted target must weigh.
pub(super) fn chosen_targets(
    cfg: &CalibrateConfig,
    base: &SimulateParams,
    err: &impl Fn(&str, String) -> ConfigError,
) -> std::result::Result<(Vec<Target>, Vec<Target>), ConfigError> {
    let variant = base.model.variant;
    let catalogue = targets_for(variant);
    let mut targets: Vec<_> = match &cfg.targets {
        None => catalogue,
        Some(ids) => ids
            .iter()
            .map(|id| {
                catalogue
                    .iter()
                    .find(|t| t.id == id)
                    .cloned()
                    .ok_or_else(|| {
                        err(
                            "targets",
                            format!(
                                "unknown target `{id}` for {} (known: {})",
                                base.model_name,
                                catalogue
                                    .iter()
                                    .map(|t| t.id)
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            ),
                        )
                    })
            })
            .collect::<std::result::Result<_, _>>()?,
    };
    let held_catalogue = held_out_for(variant);
    let held_out: Vec<_> = match &cfg.held_out {
        None => held_catalogue,
        Some(ids) => ids
            .iter()
            .map(|id| {
                held_catalogue
                    .iter()
                    .find(|t| t.id == id)
                    .cloned()
                    .ok_or_else(|| {
                        err(
                            "held_out",
                            format!(
                                "unknown held-out target `{id}` for {} (known: {})",
                                base.model_name,
                                held_catalogue
                                    .iter()
                                    .map(|t| t.id)
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            ),
                        )
                    })
            })
            .collect::<std::result::Result<_, _>>()?,
    };
    for (id, w) in &cfg.weights {
        let Some(t) = targets.iter_mut().find(|t| t.id == id) else {
            return Err(err(
                "weights",
                format!("`{id}` is not one of the calibration's fitted targets"),
            ));
        };
        if !(w.is_finite() && *w >= 0.0) {
            return Err(err("weights", format!("{id} = {w}: must be ≥ 0")));
        }
        t.weight = *w;
    }
    if !targets.iter().any(|t| t.weight > 0.0) {
        return Err(err("targets", "no target with a weight > 0 to fit".into()));
    }
    Ok((targets, held_out))
}

/// `start` (inside each knob's box, in the knobs' order) and `initial_step`.
pub(super) fn warm_start(
    cfg: &CalibrateConfig,
    settings: &mut CalibrationSettings,
    err: &impl Fn(&str, String) -> ConfigError,
) -> std::result::Result<(), ConfigError> {
    for (name, v) in &cfg.start {
        let Some(r) = settings.knobs.iter().find(|r| r.knob.name() == name) else {
            return Err(err(
                "start",
                format!("`{name}` is not one of the calibrated knobs"),
            ));
        };
        if !(v.is_finite() && *v >= r.lo && *v <= r.hi) {
            return Err(err(
                "start",
                format!("{name} = {v:e} is outside its box [{:e}, {:e}]", r.lo, r.hi),
            ));
        }
        settings.start.push((r.knob, *v));
    }
    // The knobs' order, not the file's: the settings (and the cache key) stay canonical.
    settings.start.sort_by_key(|(k, _)| {
        settings
            .knobs
            .iter()
            .position(|r| r.knob == *k)
            .unwrap_or(usize::MAX)
    });
    if let Some(step) = cfg.initial_step {
        if !(step > 0.0 && step <= 0.5) {
            return Err(err(
                "initial_step",
                format!("{step} is out of range: 0 < step ≤ 0.5 (unit box)"),
            ));
        }
        settings.search.initial_step = step;
    }
    Ok(())
}

/// `start_fitted_for`, lower case: a fit-inputs fingerprint guarding a `start`.
pub(super) fn start_fitted_for(
    cfg: &CalibrateConfig,
    err: &impl Fn(&str, String) -> ConfigError,
) -> std::result::Result<Option<String>, ConfigError> {
    let start_fitted_for = match &cfg.start_fitted_for {
        None => None,
        Some(f) => {
            let ok = (FIT_INPUTS_DIGITS..=64).contains(&f.len())
                && f.chars().all(|c| c.is_ascii_hexdigit());
            if !ok {
                return Err(err(
                    "start_fitted_for",
                    format!(
                        "\"{f}\" is not a fit-inputs fingerprint: {FIT_INPUTS_DIGITS}–64 hex \
                         digits, as in `convergence.fit_inputs` of the calibration's result.json"
                    ),
                ));
            }
            if cfg.start.is_empty() {
                return Err(err(
                    "start_fitted_for",
                    "guards a warm start, but there is no `start` to guard".into(),
                ));
            }
            Some(f.to_ascii_lowercase())
        }
    };
    Ok(start_fitted_for)
}
