//! The inputs a calibration (and a calibrated or DOE sweep) starts from: the base instance's
//! interface and DMW track from the upstream artefacts, the calibration base the fit evaluates
//! against the dissertation's class-D landmarks (`docs/calibration.md`), and a fit's knobs
//! applied to a sweep.

pub mod report;

use crate::artefacts::contact::upstream_isbl_params;
use crate::artefacts::dmw_tracks::{self, DmwTrack};
use crate::contact::isbl::IsblParams;
use crate::dynamics::calibration::{apply_knobs, CalibrationBase, Knob};
use crate::dynamics::two_dof::DmwInput;
use crate::error::Result;
use crate::slider::params::SimulateParams;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// The base inputs of a calibration (or of a calibrated run): ISBL parameters from the contact
/// result, the DMW track from the DMW entry.
pub fn base_inputs(
    p: &SimulateParams,
    upstream: &BTreeMap<String, Value>,
    upstream_dirs: &BTreeMap<String, PathBuf>,
) -> Result<(IsblParams, Option<DmwTrack>)> {
    let isbl = upstream_isbl_params(upstream, &p.contact)?;
    let dmw = match &p.dmw {
        Some(d) => Some(dmw_tracks::read_dmw_track(&dmw_tracks::upstream_file(
            upstream_dirs,
            d,
        )?)?),
        None => None,
    };
    Ok((isbl, dmw))
}

/// What the calibration evaluates: the base instance's model, case options and metric
/// settings on the given interface and DMW track.
pub fn base_of<'a>(
    p: &SimulateParams,
    isbl: IsblParams,
    dmw: Option<&'a DmwTrack>,
) -> CalibrationBase<'a> {
    CalibrationBase {
        model: p.model,
        isbl,
        contact_law: None,
        dmw: dmw.map(|t| DmwInput {
            displacement: &t.displacement,
            velocity: &t.velocity,
            sample_rate: t.sample_rate,
        }),
        options: p.options,
        case_params: p.case_metric_params(),
        rounds: None,
    }
}

/// Apply fitted knobs to a sweep's parameters, interface and DMW track (scaled by the fitted
/// DMW scale); the knobs are recorded in `calibrated_knobs`, which enters every case key.
pub fn apply_fitted(
    params: &mut SimulateParams,
    fitted: &[(Knob, f64)],
    isbl: &mut IsblParams,
    dmw: Option<&mut DmwTrack>,
) -> Result<()> {
    let scale = apply_knobs(fitted, &mut params.model, isbl)?;
    if let Some(t) = dmw {
        t.displacement.iter_mut().for_each(|x| *x *= scale);
        t.velocity.iter_mut().for_each(|x| *x *= scale);
    }
    params.calibrated_knobs = fitted
        .iter()
        .map(|(k, v)| (k.name().to_string(), *v))
        .collect();
    Ok(())
}

/// How the warm start of one run was decided.
#[derive(Debug, Clone, PartialEq)]
pub enum WarmStart {
    /// No `start`: the spec defaults.
    None,
    /// `start` without `start_fitted_for`: used as written.
    Unguarded,
    /// `start_fitted_for` matches the current fit inputs: used.
    Matched,
    /// `start_fitted_for` differs: `start` and `initial_step` dropped, the reason.
    Ignored(String),
}

impl WarmStart {
    pub fn name(&self) -> &'static str {
        match self {
            WarmStart::None => "none",
            WarmStart::Unguarded => "unguarded",
            WarmStart::Matched => "matched",
            WarmStart::Ignored(_) => "ignored",
        }
    }
}
