//! The selection discipline of docs/model-form.md: a model-form variant of the improved 2-DOF
//! slider judged on the **selection set** of `[calibrate.improved_calibration]` (the
//! dissertation geometry's held-out landmarks), at the spec defaults (no fitted knobs), on the
//! calibration's own base sweep, grid and DMW record. The **final set** (the optimised design's
//! landmarks) is printed only with `--final`, which docs/model-form.md uses once per adopted
//! configuration: no choice is made on it.
//!
//! ```text
//! hdi run --only improved_calibration        # its upstream (contact, DMW record) must be current
//! cargo run --release --example selection -- [--final] [--config pipeline.toml]
//!     [contact_force=interference_tangent|static_curve|integrated_stiffness]
//!     [lubricant=none|mtl] [surface_energy=constant|variable]
//!     [friction_law=junction_shear|seed_power_elastic|ke_static]
//!     [summit_distribution=surface|mccool|fig_2_11] [summits=S,Y]   (σ_s/σ, y_s/σ given)
//!     [contact_law=bem [bem_result=processed/bem_measured/result.json]]
//! ```
//!
//! `contact_law=bem`: contact pressure, real area and junction-shear friction from the BEM
//! curve of a `[contact_bem]` instance's `result.json` (docs/model-form.md, "Contact law").

use hdi::contact::isbl::summits::{fit_two_point, TwoPointTarget, FIG_2_11_NOMINAL_AREA};
use hdi::contact::isbl::{FrictionLaw, SummitDistribution, SurfaceEnergy};
use hdi::dynamics::calibration::{Evaluation, TargetSet};
use hdi::dynamics::two_dof::{ContactForceForm, LubricantForce};
use std::path::PathBuf;

fn print_set(e: &Evaluation, set: TargetSet) -> (usize, usize) {
    let mut n = (0, 0);
    for o in e.outcomes.iter().filter(|o| o.target.set == set) {
        let t = &o.target;
        let ok = o.within_tolerance();
        n.1 += 1;
        n.0 += usize::from(ok);
        println!(
            "  {:<32} {:>10}   published {:>7.3} ± {:<6.3} {}",
            t.id,
            o.value
                .map_or("–".into(), |v| format!("{:.3}", v * t.display_scale)),
            t.published * t.display_scale,
            t.tolerance * t.display_scale,
            if ok { "in" } else { "OUT" }
        );
    }
    n
}

fn main() {
    let mut config = PathBuf::from("pipeline.toml");
    let mut show_final = false;
    let mut switches: Vec<(String, String)> = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--final" => show_final = true,
            "--config" => config = PathBuf::from(args.next().expect("--config FILE")),
            kv => {
                let (k, v) = kv.split_once('=').expect("key=value");
                switches.push((k.into(), v.into()));
            }
        }
    }
    let label = if switches.is_empty() {
        "defaults".to_string()
    } else {
        switches
            .iter()
            .map(|(k, v)| format!("{k} = {v}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let bem_result = switches
        .iter()
        .find(|(k, _)| k == "bem_result")
        .map_or("processed/bem_measured/result.json".into(), |(_, v)| {
            v.clone()
        });
    let law = switches
        .iter()
        .any(|(k, v)| k == "contact_law" && v == "bem")
        .then(|| {
            let text = std::fs::read_to_string(&bem_result)
                .expect("bem_result: a [contact_bem] result.json");
            let r: hdi::artefacts::contact_bem::BemResult =
                serde_json::from_str(&text).expect("BEM result");
            std::sync::Arc::new(r.contact_law().expect("BEM curve"))
        });
    let e = hdi::validation::calibration::held_out_under(
        &config,
        "improved_calibration",
        law,
        |p, isbl| {
            for (k, v) in &switches {
                match (k.as_str(), v.as_str()) {
                    ("contact_law", _) | ("bem_result", _) => {}
                    ("contact_force", "interference_tangent") => {
                        p.options.contact_force = ContactForceForm::InterferenceTangent
                    }
                    ("contact_force", "static_curve") => {
                        p.options.contact_force = ContactForceForm::StaticCurve
                    }
                    ("contact_force", "integrated_stiffness") => {
                        p.options.contact_force = ContactForceForm::IntegratedStiffness
                    }
                    ("lubricant", "none") => p.options.lubricant = LubricantForce::None,
                    ("lubricant", "mtl") => p.options.lubricant = LubricantForce::Mtl,
                    ("surface_energy", "constant") => {}
                    ("surface_energy", "variable") => {
                        isbl.surface_energy = SurfaceEnergy::seed_variable()
                    }
                    ("friction_law", "junction_shear") => {
                        isbl.friction_law = FrictionLaw::JunctionShear
                    }
                    ("friction_law", "seed_power_elastic") => {
                        isbl.friction_law = FrictionLaw::SeedPowerElastic
                    }
                    ("friction_law", "ke_static") => isbl.friction_law = FrictionLaw::KeStatic,
                    ("summit_distribution", "surface") => {
                        isbl.summits = SummitDistribution::Surface
                    }
                    ("summit_distribution", "mccool") => isbl.summits = SummitDistribution::McCool,
                    ("summit_distribution", "fig_2_11") => {}
                    ("summits", r) => {
                        let (a, b) = r.split_once(',').expect("summits=S,Y");
                        isbl.summits = SummitDistribution::Given {
                            sigma_ratio: a.parse().expect("σ_s/σ"),
                            offset_ratio: b.parse().expect("y_s/σ"),
                        };
                    }
                    _ => panic!("unknown switch {k} = {v}"),
                }
            }
            // The Fig. 2.11 fit on the variant's own interface, as `[contact]` resolves it.
            if switches
                .iter()
                .any(|(k, v)| k == "summit_distribution" && v == "fig_2_11")
            {
                let target = TwoPointTarget::fig_2_11(FIG_2_11_NOMINAL_AREA);
                isbl.summits = fit_two_point(isbl, &target)
                    .expect("Fig. 2.11 fit")
                    .distribution();
            }
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    println!("variant: {label} (spec defaults, no fitted knobs; the calibration's base and grid)");
    println!("selection set (dissertation geometry):");
    let (s, st) = print_set(&e, TargetSet::Selection);
    println!("  selection: {s}/{st} in band");
    if show_final {
        println!("final set (optimised design, w = 50 µm assumed):");
        let (f, ft) = print_set(&e, TargetSet::Final);
        println!("  final: {f}/{ft} in band");
    }
}
