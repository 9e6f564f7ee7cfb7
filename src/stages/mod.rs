//! Stage implementations, one module per stage kind, and the registry that turns a parsed
//! `pipeline.toml` into stage instances.
pub mod analysis;
pub mod calibrate;
pub mod contact;
pub mod dmw;
pub mod doe;
pub mod excitation;
pub mod interface;
pub mod simulate;
pub mod surfaces;
pub mod three_dof;

use crate::core::config::{ConfigError, PipelineFile};
use crate::core::engine::Stage;

/// Names reserved for hdi's own entries under `processed/`.
const RESERVED: &[&str] = &["tables", ".hdi"];

/// Every declared stage instance, validated.
pub fn build(file: &PipelineFile) -> Result<Vec<Box<dyn Stage>>, ConfigError> {
    let mut stages: Vec<Box<dyn Stage>> = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
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
    for (name, cfg) in &file.raw.surface {
        check_name("surface", name)?;
        stages.push(Box::new(surfaces::SurfaceStage::from_config(
            file, name, cfg,
        )?));
    }
    for (name, cfg) in &file.raw.interface {
        check_name("interface", name)?;
        stages.push(Box::new(interface::InterfaceStage::from_config(
            file, name, cfg,
        )?));
    }
    for (name, cfg) in &file.raw.contact {
        check_name("contact", name)?;
        stages.push(Box::new(contact::ContactStage::from_config(
            file, name, cfg,
        )?));
    }
    for (name, cfg) in &file.raw.dmw {
        check_name("dmw", name)?;
        stages.push(Box::new(dmw::DmwStage::from_config(file, name, cfg)?));
    }
    for (name, cfg) in &file.raw.excitation {
        check_name("excitation", name)?;
        stages.push(Box::new(excitation::ExcitationStage::from_config(
            file, name, cfg,
        )?));
    }
    for (name, cfg) in &file.raw.simulate {
        check_name("simulate", name)?;
        stages.push(Box::new(simulate::SimulateStage::from_config(
            file, name, cfg,
        )?));
    }
    for (name, cfg) in &file.raw.calibrate {
        check_name("calibrate", name)?;
        stages.push(Box::new(calibrate::CalibrateStage::from_config(
            file, name, cfg,
        )?));
    }
    for (name, cfg) in &file.raw.doe {
        check_name("doe", name)?;
        stages.push(Box::new(doe::DoeStage::from_config(file, name, cfg)?));
    }
    for (name, cfg) in &file.raw.three_dof {
        check_name("three_dof", name)?;
        stages.push(Box::new(three_dof::ThreeDofStage::from_config(
            file, name, cfg,
        )?));
    }
    for (name, cfg) in &file.raw.analysis {
        check_name("analysis", name)?;
        stages.push(Box::new(analysis::AnalysisStage::from_config(
            file, name, cfg,
        )?));
    }
    Ok(stages)
}

/// The tidy summary table of a stage kind (`processed/tables/<name>.{parquet,csv}`):
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

/// After `hdi run`: the summary tables from the current entries, one per kind. A table is
/// rewritten when something ran and nothing failed (a failed instance keeps its earlier row),
/// or when it is missing.
pub fn write_summary_tables(
    store: &crate::core::cache::Store,
    report: &crate::core::engine::RunReport,
) -> crate::error::Result<()> {
    use crate::core::engine::Outcome;
    let tables_dir = store.processed().join("tables");
    let ran = report.count(|o| matches!(o, Outcome::Ran { .. }));
    let failed = report.failed();
    for (kind, rows) in crate::core::engine::summary_rows(store, &report.current) {
        let stem = tables_dir.join(summary_table_name(&kind));
        if (ran > 0 && failed == 0)
            || !stem.with_extension("parquet").exists()
            || !stem.with_extension("csv").exists()
        {
            crate::core::store::write_table(&rows, &stem)?;
        }
    }
    Ok(())
}
