//! 3-DOF slider stage `[three_dof.NAME]` (dissertation Chapter 4; docs/three-dof.md): one scenario —
//! constant actuation, impulse shock or a variable actuation profile — run for each requested
//! interface (ISBL, MTL with each lubricant case of Table 4.4), one cached case each, in
//! parallel. Outputs per case an HDF5 of the time histories and a PNG of them; per instance a
//! table with one row per case (PT, bulge spacing, BV/FHM overall and per Table 4.4 window,
//! contact shares, peak forces, the features that touched).

use super::case_engine::{
    case_value, typed_case, CaseEngine, ListedCase, PreparedCases, UpstreamEntries,
};
use super::{FromConfig, Output, StageContext, StageKind};
use crate::artefacts::cases::{self as case_files};
use crate::artefacts::three_dof::{FittedBulge, ThreeDofCaseResult, ThreeDofResult};
use crate::core::cases;
use crate::core::config::{ConfigError, PipelineFile};
use crate::error::{Error, Result};
use crate::slider::three_dof_case::{PreparedThreeDof, ThreeDofSolver};
use crate::slider::three_dof_params::{CaseInterface, ThreeDofParams};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::Path;
use std::sync::Arc;

/// The `[three_dof.NAME]` table (checked by `ThreeDofParams`).
pub use crate::slider::three_dof_params::ThreeDofConfig;

// three-dof-4: tracks, init, spring law, contact force as plain JSON in the key (same numbers).
// three-dof-5: the peak contact and lubricant forces over the integrator's steps, not only the
// output samples (the shock's impact peaks between two 0.25 µs samples).
pub const MODEL_VERSION: &str = "three-dof-5";

pub struct ThreeDofStage {
    pub name: String,
    pub params: ThreeDofParams,
}

impl FromConfig for ThreeDofStage {
    type Config = ThreeDofConfig;

    fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &ThreeDofConfig,
    ) -> std::result::Result<Self, ConfigError> {
        let params = ThreeDofParams::check(cfg).map_err(|e| e.locate(file, "three_dof", name))?;
        if !file.has_instance("contact", &cfg.contact) {
            return Err(file.error(
                "three_dof",
                name,
                "contact",
                format!("no [contact.{}] in this file", cfg.contact),
            ));
        }
        if let Some(d) = &params.dmw {
            if !file.has_instance("dmw", d) && !file.has_instance("excitation", d) {
                return Err(file.error(
                    "three_dof",
                    name,
                    "dmw",
                    format!("no [dmw.{d}] or [excitation.{d}] in this file (or \"none\")"),
                ));
            }
        }
        if let Some(b) = &params.bulge {
            if !file.has_instance("bulge", b) {
                return Err(file.error(
                    "three_dof",
                    name,
                    "geometry",
                    format!("no [bulge.{b}] in this file"),
                ));
            }
        }
        Ok(Self {
            name: name.to_string(),
            params,
        })
    }
}

impl StageKind for ThreeDofStage {
    const KIND: &'static str = "three_dof";
    const MODEL_VERSION: &'static str = MODEL_VERSION;
    type Result = ThreeDofResult;
    type Row = ThreeDofRow;

    fn params(&self) -> Value {
        self.params.canonical()
    }
    fn upstream(&self) -> Vec<String> {
        let mut u = vec![self.params.contact.clone()];
        u.extend(self.params.dmw.iter().cloned());
        u.extend(self.params.bulge.iter().cloned());
        u
    }
    const CASE_KIND: Option<&'static str> = Some(THREE_DOF_CASE);
    fn case_engine(&self) -> Option<&dyn CaseEngine> {
        Some(self)
    }
    fn run(&self, ctx: &StageContext) -> Result<Output<ThreeDofResult, ThreeDofRow>> {
        use rayon::prelude::*;
        let prepared = self.prepare(&ctx.upstream_entries())?;
        ctx.progress.set_message("interface tables");
        // The same preparation and case computation as a Slurm worker's (`case_engine`).
        let three_dof_cases = ThreeDofCases::new(prepared)?;
        let (prepared, p) = (&three_dof_cases.prepared, &three_dof_cases.prepared.params);
        ctx.progress.set_message(format!("{} cases", p.cases.len()));
        let outcomes: Vec<Result<(CaseInterface, cases::CaseEntry)>> = p
            .cases
            .par_iter()
            .map(|&which| {
                cases::get_or_compute(
                    ctx.store,
                    MODEL_VERSION,
                    &prepared.case_params(which),
                    |dir| three_dof_cases.compute_case(which, dir),
                )
                .map(|e| (which, e))
                .map_err(|e| Error::ThreeDofCase {
                    case: which.label(),
                    source: Box::new(e),
                })
            })
            .collect();
        let mut done = Vec::new();
        for o in outcomes {
            done.push(o?);
        }
        // How many cases came from the store (Slurm tasks, earlier runs): a run fact.
        ctx.log_run(
            "cases_cached",
            Value::from(done.iter().filter(|(_, e)| e.cached).count()),
        );
        let dir = ctx.out_dir.join(case_files::DIR);
        std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
        let mut cases_done = Vec::new();
        for (which, entry) in &done {
            for (file, suffix) in [
                ("case.h5", ".h5"),
                ("history.png", ".png"),
                ("regimes.png", "_regimes.png"),
                ("forces.png", "_forces.png"),
            ] {
                let (from, to) = (
                    entry.dir.join(file),
                    dir.join(format!("{}{suffix}", which.label())),
                );
                if !from.exists() {
                    continue; // the variable-actuation figures exist only for that scenario
                }
                if std::fs::hard_link(&from, &to).is_err() {
                    std::fs::copy(&from, &to).map_err(|e| Error::io(&to, e))?;
                }
            }
            cases_done.push(ThreeDofCaseResult::deserialize(&entry.result).map_err(|e| {
                Error::ThreeDofCase {
                    case: which.label(),
                    source: Box::new(Error::Encode {
                        kind: "three_dof",
                        what: "case result".into(),
                        message: e.to_string(),
                    }),
                }
            })?);
        }
        crate::core::store::write_table(
            &crate::core::store::rows_of(&cases_done),
            &ctx.out_dir.join("cases"),
        )?;
        let row = ThreeDofRow {
            scenario: p.scenario.clone(),
            cases: done.len(),
            first_case: cases_done.first().map(FirstCaseColumns::of),
        };
        let result = ThreeDofResult {
            cases: cases_done,
            case_keys: done.iter().map(|(_, e)| e.key.clone()).collect(),
            table: "cases.parquet".to_string(),
            // The bulge the cases ran with, when it came from a fit (docs/bulge.md).
            fitted_bulge: p.fitted.map(|d| FittedBulge {
                a_tfc_m: d.semi_width_x,
                w_tfc_m: d.full_width_y,
                x_tfc_m: d.offset_from_te,
            }),
        };
        Ok(Output {
            result,
            summary_row: Some(row),
        })
    }
}

/// The instance's row of the run's summary table: its scenario, how many cases, and the
/// headline numbers of its first case.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ThreeDofRow {
    pub scenario: String,
    pub cases: usize,
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub first_case: Option<FirstCaseColumns>,
}

/// Pole-tip mean, bulge vibration and peak contact force of the first case, each column
/// named with its case label (`isbl_pole_tip_mean_nm`).
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq)]
pub struct FirstCaseColumns {
    pub case: String,
    pub pole_tip_mean_nm: f64,
    pub bulge_vibration_percent: Option<f64>,
    pub peak_contact_force_mN: f64,
}

impl FirstCaseColumns {
    fn of(c: &ThreeDofCaseResult) -> Self {
        FirstCaseColumns {
            case: c.case.clone(),
            pole_tip_mean_nm: c.pole_tip_mean_nm,
            bulge_vibration_percent: c.bulge_vibration_percent,
            peak_contact_force_mN: c.peak_contact_force_mN,
        }
    }
}

impl Serialize for FirstCaseColumns {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(3))?;
        let case = &self.case;
        m.serialize_entry(&format!("{case}_pole_tip_mean_nm"), &self.pole_tip_mean_nm)?;
        m.serialize_entry(
            &format!("{case}_bulge_vibration_percent"),
            &self.bulge_vibration_percent,
        )?;
        m.serialize_entry(
            &format!("{case}_peak_contact_force_mN"),
            &self.peak_contact_force_mN,
        )?;
        m.end()
    }
}

// ------------------------------------------------------------------------------------------
// The instance's cases through the stage contract's case capability (`case_engine`)
// ------------------------------------------------------------------------------------------

/// Case kind of a `[three_dof]` case (one interface of the instance's scenario).
pub const THREE_DOF_CASE: &str = "three_dof";

impl ThreeDofStage {
    /// The instance with its upstream in place: the one preparation of a local run and a
    /// Slurm worker.
    pub fn prepare(&self, upstream: &UpstreamEntries) -> Result<PreparedThreeDof> {
        PreparedThreeDof::prepare(&self.params, &upstream.results, &upstream.dirs, |n| {
            upstream.key_of(n)
        })
    }
}

impl CaseEngine for ThreeDofStage {
    fn prepare_cases(&self, upstream: &UpstreamEntries) -> Result<Arc<dyn PreparedCases>> {
        Ok(Arc::new(ThreeDofCases::new(self.prepare(upstream)?)?))
    }
}

/// A prepared instance with the lookup tables and DMW tracks its cases share (built once per
/// process); a case is named by its interface label (`isbl`, `mtl_…`).
struct ThreeDofCases {
    prepared: PreparedThreeDof,
    solver: ThreeDofSolver,
}

impl ThreeDofCases {
    fn new(prepared: PreparedThreeDof) -> Result<Self> {
        let solver = prepared.solver()?;
        Ok(ThreeDofCases { prepared, solver })
    }

    fn compute_case(&self, which: CaseInterface, dir: &Path) -> Result<Value> {
        self.solver.compute_case(&self.prepared, which, dir)
    }

    /// The case a recipe's label names.
    fn case_of(&self, case: &Value) -> Result<CaseInterface> {
        let label: String = typed_case(THREE_DOF_CASE, case)?;
        self.prepared
            .params
            .cases
            .iter()
            .copied()
            .find(|c| c.label() == label)
            .ok_or(Error::UnknownCase {
                kind: THREE_DOF_CASE,
                case: label,
            })
    }
}

impl PreparedCases for ThreeDofCases {
    fn model_version(&self) -> &'static str {
        MODEL_VERSION
    }
    fn cases(&self) -> Result<Vec<ListedCase>> {
        Ok(self
            .prepared
            .params
            .cases
            .iter()
            .map(|&which| ListedCase {
                case: case_value(&which.label()),
                params: self.prepared.case_params(which),
            })
            .collect())
    }
    fn case_params(&self, case: &Value) -> Result<Value> {
        Ok(self.prepared.case_params(self.case_of(case)?))
    }
    fn compute(&self, case: &Value, dir: &Path) -> Result<Value> {
        self.compute_case(self.case_of(case)?, dir)
    }
}
