//! The slider figures: 2-DOF cases per accepted step, the 76-case sweep, one 3-DOF case.

use super::{time_best, Details, Figure, Figures, Group, Result, Unit};
use crate::contact::isbl::{IsblModel, IsblParams};
use crate::contact::lookup::IsblLookup;
use crate::dmw::excitation_tracks::synthetic_dmw;
use crate::dynamics::two_dof::DmwInput;

/// The 2-DOF slider figures: one 2 ms case at 8.5 and 12 nm (µs per accepted step) and the
/// 76-case sweep 0–15 nm on all threads; improved model, spec defaults, the spec's synthetic
/// DMW (σ 1 nm), static initialisation (what the sweep stage runs).
pub(super) fn two_dof(
    out: &mut Figures,
    cases: bool,
    sweep: bool,
    repeats: usize,
    sweep_repeats: usize,
) -> Result<()> {
    use crate::dynamics::params::improved_2dof;
    use crate::dynamics::two_dof::{SimOptions, TwoDofCase};
    use crate::numerics::ode::OdeStats;
    use rayon::prelude::*;
    let isbl = IsblLookup::build_standard(IsblModel::new(IsblParams::improved_2dof())?)?;
    let track = synthetic_dmw(2.2e-3, 4e6, 1e-9, 1)?;
    let dmw = || {
        Some(DmwInput {
            displacement: &track.displacement,
            velocity: &track.velocity,
            sample_rate: track.fs,
        })
    };
    let model = improved_2dof();
    let options = SimOptions {
        static_init: true,
        ..SimOptions::default()
    };
    let run = |h: f64| -> Result<OdeStats> {
        let case = TwoDofCase::new(&model, h, &isbl, dmw(), options)?;
        Ok(case.run()?.stats)
    };
    if cases {
        for h in [8.5e-9, 12e-9] {
            let ((best, median), stats) = time_best(repeats, || run(h))?;
            let steps = stats.accepted_steps.max(1) as f64;
            out.push(Figure::best(
                Group::TwoDof,
                format!("two_dof_{}nm_us_per_step", fmt_nm(h)),
                format!(
                    "2-DOF, one 2 ms case at {} nm: time per accepted step",
                    fmt_nm(h)
                ),
                (best / steps * 1e6, median / steps * 1e6),
                Unit::MicrosecondsPerStep,
                repeats,
                Details {
                    accepted_steps: Some(stats.accepted_steps),
                    rejected_steps: Some(stats.rejected_steps),
                    rhs_evaluations: Some(stats.rhs_evaluations),
                    case_ms: Some(best * 1e3),
                    us_per_rhs_evaluation: Some(best / stats.rhs_evaluations.max(1) as f64 * 1e6),
                    ..Details::default()
                },
            ));
        }
    }
    if sweep {
        let (times, steps) = time_best(sweep_repeats, || {
            let stats: Vec<Result<OdeStats>> = (0..76)
                .into_par_iter()
                .map(|i| run(i as f64 * 0.2e-9))
                .collect();
            let mut steps = 0;
            for s in stats {
                steps += s?.accepted_steps;
            }
            Ok(steps)
        })?;
        out.push(Figure::best(
            Group::Sweep,
            "two_dof_sweep_76_cases",
            format!(
                "2-DOF, 76-case sweep 0–15 nm on {} threads",
                rayon::current_num_threads()
            ),
            times,
            Unit::Seconds,
            sweep_repeats,
            Details {
                cases: Some(76),
                accepted_steps: Some(steps),
                threads: Some(rayon::current_num_threads()),
                ..Details::default()
            },
        ));
    }
    Ok(())
}

fn fmt_nm(h: f64) -> String {
    let nm = h * 1e9;
    if (nm - nm.round()).abs() < 1e-9 {
        format!("{}", nm.round() as i64)
    } else {
        format!("{nm:.1}")
    }
}

/// One 2 ms 3-DOF case at constant 12 nm with the ISBL interface on the spec's synthetic DMW
/// (tracks D1–D3 as in benches/three_dof.rs).
pub(super) fn three_dof(out: &mut Figures, repeats: usize) -> Result<()> {
    use crate::dynamics::three_dof::case::{Model3Dof, Options3Dof, ThreeDofCase};
    use crate::dynamics::three_dof::inputs::ActuationProfile;
    use crate::dynamics::three_dof::interface::{FeatureInterface, InterfaceLaw};
    use crate::dynamics::two_dof::ContactForceForm;
    let isbl = IsblLookup::build_standard(IsblModel::new(IsblParams::three_dof())?)?;
    let d = synthetic_dmw(2.2e-3, 4e6, 1e-9, 1)?;
    let flip = |x: &[f64], s: f64| x.iter().rev().map(|v| s * v).collect::<Vec<_>>();
    let (d2, v2, d3, v3) = (
        flip(&d.displacement, 1.0),
        flip(&d.velocity, -1.0),
        flip(&d.displacement, -1.0),
        flip(&d.velocity, 1.0),
    );
    fn track<'a>(x: &'a [f64], v: &'a [f64], fs: f64) -> DmwInput<'a> {
        DmwInput {
            displacement: x,
            velocity: v,
            sample_rate: fs,
        }
    }
    let model = Model3Dof::dissertation();
    let mass = model.air_bearing.slider.mass;
    let ((best, median), stats) = time_best(repeats, || {
        let interface = FeatureInterface::new(
            &isbl,
            InterfaceLaw::Isbl,
            ContactForceForm::InterferenceTangent,
            0.05,
            mass,
        )?;
        let case = ThreeDofCase::new(
            &model,
            interface,
            ActuationProfile::constant(12e-9)?,
            None,
            Some([
                track(&d.displacement, &d.velocity, d.fs),
                track(&d2, &v2, d.fs),
                track(&d3, &v3, d.fs),
            ]),
            Options3Dof::default(),
        )?;
        Ok(case.run()?.stats)
    })?;
    let steps = stats.accepted_steps.max(1) as f64;
    out.push(Figure::best(
        Group::ThreeDof,
        "three_dof_12nm_case",
        "3-DOF, one 2 ms case at 12 nm (ISBL, synthetic DMW)",
        (best * 1e3, median * 1e3),
        Unit::Milliseconds,
        repeats,
        Details {
            accepted_steps: Some(stats.accepted_steps),
            rejected_steps: Some(stats.rejected_steps),
            rhs_evaluations: Some(stats.rhs_evaluations),
            us_per_step: Some(best / steps * 1e6),
            ..Details::default()
        },
    ));
    Ok(())
}
