//! `hdi validate` area `optimisation`: the DOE optima of the pipeline in the working directory
//! beside the dissertation's (§2.3.2).

use super::{Class, Origin, Row, Tolerance};
use crate::artefacts::doe::DoeResult;
use crate::artefacts::upstream_result;
use crate::core::cache::Store;
use crate::dynamics::UM;
use crate::engine::{plan, read_result, State};
use crate::error::Result;
use crate::stages::doe::DoeConfig;
use std::collections::BTreeMap;
use std::path::Path;

/// `hdi validate` rows (area `optimisation`): each current `[doe]` optimum beside the
/// dissertation's (a = 4.86 µm, x = 6.35 µm; w and ξ_min were dropped).
pub fn rows(config: &Path) -> Result<Vec<Row>> {
    let file = crate::stages::load(config)?;
    let stages = crate::stages::build(&file)?;
    let store = Store::open_existing(&file.processed_dir());
    let plan = plan(stages, &store, &Default::default())?;
    let mut rows = Vec::new();
    for (name, cfg) in &file.instances::<DoeConfig>("doe")? {
        if !cfg.optimise {
            continue;
        }
        let planned = plan.planned.iter().find(|p| &p.name == name);
        let Some(entry) = planned.filter(|p| p.state == State::Fresh) else {
            rows.push(
                Row::new(
                    &format!("doe-{name}"),
                    Class::D,
                    "optimised a_TFC",
                    "um",
                    4.86,
                    f64::NAN,
                    Tolerance::Absolute(0.5),
                )
                .published("dissertation §2.3.2")
                .not_run(&format!(
                    "a current result of [doe.{name}]: `hdi run --only {name}`"
                )),
            );
            continue;
        };
        let result = read_result(&store.entry_dir(&entry.kind, &entry.key))?;
        let result: DoeResult =
            upstream_result(&BTreeMap::from([(name.clone(), result)]), "doe", name)?;
        let optimum = result.optimum.as_ref();
        let variant = format!(
            "ξ = (c̄/FH_nom)(V/100) [assumed]; SA on the {} objective, {} evaluations ({}), seed {}",
            optimum.map_or("?".into(), |o| o.objective.to_lowercase()),
            optimum.map_or("null".into(), |o| o.evaluations.to_string()),
            optimum.map_or("?", |o| o.stop.as_str()),
            cfg.sa_seed
        );
        let w = optimum.map_or(f64::NAN, |o| o.w_m) / UM;
        let note = format!(
            "class D: ξ's formula, the DOE levels and the DMW were dropped from the text and the \
             model runs at the spec's default inputs (touchdown 10.4 nm, not 9.7); our w_TFC = \
             {w:.2} µm (dropped); most sensitive: {}",
            optimum
                .and_then(|o| o.most_sensitive.as_deref())
                .unwrap_or("?")
        );
        let (a, x) = optimum.map_or((f64::NAN, f64::NAN), |o| (o.a_m, o.x_m));
        for (q, value, target) in [("a_TFC", a, 4.86), ("x_TFC", x, 6.35)] {
            rows.push(
                Row::new(
                    &format!("doe-{name}.{q}"),
                    Class::D,
                    &format!("optimised {q}"),
                    "um",
                    target,
                    value / UM,
                    Tolerance::Absolute(0.5),
                )
                .published("dissertation §2.3.2")
                .variant(&variant)
                .inputs(&format!(
                    "the DOE's base sweep `{}` (the pipeline's DMW record), no calibration",
                    cfg.simulate
                ))
                .origin(Origin::Cache {
                    instance: format!("doe.{name}"),
                    key: entry.key.clone(),
                })
                .note(&note),
            );
        }
    }
    Ok(rows)
}
