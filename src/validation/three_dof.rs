//! `hdi validate` area `three_dof`: the 3-DOF numbers that exist without a stage (Fig. 4.8,
//! Table 4.3, the §4.1 air bearing; docs/three-dof.md), computed now by the same code a case runs.

use super::{Row, Tolerance};
use crate::contact::isbl::{IsblModel, IsblParams};
use crate::contact::lookup::IsblLookup;
use crate::contact::mtl::LubricantCase;
use crate::dynamics::three_dof::air_bearing::ThreeDofAirBearing;
use crate::dynamics::three_dof::case::{Model3Dof, Options3Dof, ThreeDofCase};
use crate::dynamics::three_dof::geometry::{Feature, SliderPose};
use crate::dynamics::three_dof::inputs::ActuationProfile;
use crate::dynamics::three_dof::interface::{FeatureInterface, InterfaceLaw};
use crate::dynamics::two_dof::ContactForceForm;
use crate::dynamics::{NM, UM};

/// Fig. 4.8 truncation example through the 3-DOF feature API (class G, ours 187.9 µm²).
fn truncation_row(model: &Model3Dof) -> Row {
    let ours = model
        .geometry
        .nominal_contact_area(
            Feature::Bulge,
            &SliderPose {
                heave: 0.0,
                pitch: 100e-6,
                roll: -50e-6,
                actuation: 20.0 * NM,
            },
            1.5 * NM,
        )
        .map_or(f64::NAN, |a| a / (UM * UM));
    Row::reproducible(
        "dynamics §2.7 (Fig. 4.8)",
        "3-DOF bulge nominal area, a = 5 µm, b = 5 nm, h = 20 nm, θ 100 µrad, φ −50 µrad, cut 1.5 nm",
        "μm²",
        187.9,
        ours,
        Tolerance::Relative(0.01),
        "closed-form tilted section",
        "the dissertation's value was dropped; 187.9 µm² is the spec's independent derivation",
    )
}

/// AB modes at the nominal PT from the inverted springs (§3.3 table; the normal mode of the
/// fit formula is 300.27 kHz at 11 nm).
fn modal_rows(model: &Model3Dof) -> Vec<Row> {
    let modes = ThreeDofAirBearing::new(&model.air_bearing)
        .and_then(|ab| ab.modal_frequencies(11.0 * NM))
        .map(|mut f| {
            f.sort_by(f64::total_cmp);
            f
        })
        .unwrap_or([f64::NAN; 3]);
    [
        ("roll", 100.0),
        ("1st pitch", 110.0),
        ("normal / 2nd pitch", 300.0),
    ]
    .iter()
    .zip(modes)
    .map(|(&(name, target), f)| {
        Row::reproducible(
            "dynamics §3.3",
            &format!("3-DOF AB {name} mode at PT = 11 nm"),
            "kHz",
            target,
            f / 1e3,
            Tolerance::Relative(0.005),
            "k(PT) table by modal inversion, stiff rear",
            "the 110/100 kHz and the f_n(PT) curve are the spec's assumptions; the row checks \
                 the inversion (f_n(11 nm) = 300.27 kHz by the fit formula)",
        )
    })
    .collect()
}

/// A 0.3 ms case at constant 12 nm (ISBL interface, no DMW): pole-tip FH and TE push-back.
fn twelve_nm_rows(model: &Model3Dof) -> Vec<Row> {
    let run = || -> Result<(f64, f64), String> {
        let isbl = IsblModel::new(IsblParams::three_dof())
            .and_then(IsblLookup::build_standard)
            .map_err(|e| e.to_string())?;
        let interface = FeatureInterface::new(
            &isbl,
            InterfaceLaw::Isbl,
            ContactForceForm::InterferenceTangent,
            0.05,
            model.air_bearing.slider.mass,
        )
        .map_err(|e| e.to_string())?;
        let options = Options3Dof {
            duration: 0.3e-3,
            ..Options3Dof::default()
        };
        let profile = ActuationProfile::constant(12.0 * NM).map_err(|e| e.to_string())?;
        let case = ThreeDofCase::new(model, interface, profile, None, None, options)
            .map_err(|e| e.to_string())?;
        let h = case.run().map_err(|e| e.to_string())?;
        let k = h.len() - 1;
        let g = &model.geometry;
        let te = g.spacing_of(&g.trailing_edge(), h.heave[k], h.pitch[k], h.roll[k]);
        Ok((h.pole_tip[k], te - g.nominal_spacing))
    };
    let (pt, rise, note) = match run() {
        Ok((pt, rise)) => (pt / NM, rise / NM, String::new()),
        Err(e) => (f64::NAN, f64::NAN, format!("the case failed: {e}")),
    };
    let variant = "3-DOF, ISBL, no DMW, AB static init, balanced F_j,0, ΔF_AB at the TFC, \
                   integrated spring law, linear push-back 0.5·h";
    vec![
        Row::reproducible(
            "dynamics §12 row 30 (K)",
            "3-DOF pole-tip FH at 12 nm constant actuation",
            "nm",
            7.5,
            pt,
            Tolerance::Absolute(1.0),
            variant,
            if note.is_empty() {
                "ours holds the push-back calibration's static PT (7.79 nm); the linear spring \
                 law of eqs. 4.11–4.14 is unstable there (docs/dynamics-3dof-air-bearing.md)"
            } else {
                &note
            },
        ),
        Row::reproducible(
            "dynamics §3.3 (push-back ΔFH ≈ 0.5·h_TFC)",
            "3-DOF TE rise above the nominal FH at 12 nm",
            "nm",
            6.0,
            rise,
            Tolerance::Absolute(0.5),
            variant,
            "ΔF_AB is calibrated so the ABS under the TFC centre rises 0.5·h; the TE rise of the \
             running case checks that the slider holds that state",
        ),
    ]
}

/// One lubricant case of Table 4.4 with its published BVs (%).
struct PublishedCase {
    case: LubricantCase,
    name: &'static str,
    jump_to_contact_bv: f64,
    steady_contact_bv: f64,
}

/// Table 4.4's four lubricant cases as published.
const PUBLISHED: [PublishedCase; 4] = [
    PublishedCase {
        case: LubricantCase::Reference,
        name: "case 0 (reference)",
        jump_to_contact_bv: 61.7,
        steady_contact_bv: 5.7,
    },
    PublishedCase {
        case: LubricantCase::HumidityTemperature,
        name: "case 1 (μ0 −50 %)",
        jump_to_contact_bv: 623.9,
        steady_contact_bv: 19.4,
    },
    PublishedCase {
        case: LubricantCase::MoreBonding,
        name: "case 2 (μ0 +50 %)",
        jump_to_contact_bv: 61.8,
        steady_contact_bv: 1.7,
    },
    PublishedCase {
        case: LubricantCase::LargerGyrationRadius,
        name: "case 3 (μ0 +50 %, κ 0.45 nm)",
        jump_to_contact_bv: 900.0,
        steady_contact_bv: 23.6,
    },
];

/// The BVs (%) one Table 4.4 case gives here.
#[derive(Clone, Copy)]
struct CaseBv {
    jump_to_contact: f64,
    steady_contact: f64,
}

/// Table 4.4 (S6; docs/validation.md): the variable profile with the flattened push-back
/// for the four lubricant cases on the MTL interface, synthetic DMW (σ 1 nm, seed 1) as tracks
/// D1, D2 = flipped, D3 = negated flipped. Class Q: the values depend on dropped inputs; the
/// orderings are what the dissertation's text claims.
fn table_4_4_rows() -> Vec<Row> {
    use crate::dynamics::three_dof::air_bearing::PushbackCurve;
    let mut model = Model3Dof::dissertation();
    model.pushback = PushbackCurve::flattened();
    let variant = "3-DOF, MTL (variable Δγ), S5 profile 5 → 18 → 5 nm, flattened push-back, \
                   synthetic DMW σ 1 nm seed 1, integrated AB spring law";
    match run_table_4_4(&model) {
        Ok(values) => table_4_4_case_rows(&values, variant),
        Err(e) => vec![Row {
            reproducible: false,
            ..Row::reproducible(
                "dynamics §12 row 35",
                "Table 4.4 cases",
                "%",
                f64::NAN,
                f64::NAN,
                Tolerance::Absolute(0.0),
                variant,
                &format!("the cases failed: {e}"),
            )
        }],
    }
}

/// Runs the four Table 4.4 cases (in parallel) on the variable-Δγ MTL interface.
fn run_table_4_4(model: &Model3Dof) -> Result<Vec<CaseBv>, String> {
    use crate::contact::isbl::SurfaceEnergy;
    use crate::contact::mtl::{FwmExperiment, RoughFilm, RoughMtl};
    use crate::dmw::excitation_tracks::synthetic_dmw;
    use crate::dynamics::two_dof::DmwInput;
    use rayon::prelude::*;
    let mut ip = IsblParams::three_dof();
    ip.surface_energy = SurfaceEnergy::seed_variable();
    let isbl = IsblModel::new(ip)
        .and_then(IsblLookup::build_standard)
        .map_err(|e| e.to_string())?;
    let d = synthetic_dmw(2.2e-3, 4e6, 1e-9, 1).map_err(|e| e.to_string())?;
    let flip = |x: &[f64], sign: f64| x.iter().rev().map(|v| sign * v).collect::<Vec<_>>();
    let (d2, v2) = (flip(&d.displacement, 1.0), flip(&d.velocity, -1.0));
    let (d3, v3) = (flip(&d.displacement, -1.0), flip(&d.velocity, 1.0));
    let lubricant_surface = 3.0 * ip.sigma + ip.lubricant_thickness;
    PUBLISHED
        .par_iter()
        .map(|p| {
            let case = &p.case;
            let film = RoughFilm::new(
                ip.sigma,
                case.kappa(),
                ip.lubricant_thickness,
                model.disk_speed,
            )
            .map_err(|e| e.to_string())?;
            let exp = FwmExperiment::fukuzawa_z03()
                .with_limiting_viscosity(case.limiting_viscosity())
                .map_err(|e| e.to_string())?;
            let law = RoughMtl::from_experiment(film, &exp).map_err(|e| e.to_string())?;
            let interface = FeatureInterface::new(
                &isbl,
                InterfaceLaw::Mtl(law),
                ContactForceForm::InterferenceTangent,
                0.05,
                model.air_bearing.slider.mass,
            )
            .map_err(|e| e.to_string())?;
            let profile = ActuationProfile::variable_default();
            let fs = d.fs;
            let tracks = [
                DmwInput {
                    displacement: &d.displacement,
                    velocity: &d.velocity,
                    sample_rate: fs,
                },
                DmwInput {
                    displacement: &d2,
                    velocity: &v2,
                    sample_rate: fs,
                },
                DmwInput {
                    displacement: &d3,
                    velocity: &v3,
                    sample_rate: fs,
                },
            ];
            let h = ThreeDofCase::new(
                model,
                interface,
                profile.clone(),
                None,
                Some(tracks),
                Options3Dof::default(),
            )
            .and_then(|c| c.run())
            .map_err(|e| e.to_string())?;
            let t = h.table_4_4(&profile, lubricant_surface);
            Ok(CaseBv {
                jump_to_contact: t.jump_to_contact_bv.unwrap_or(f64::NAN),
                steady_contact: t.steady_contact_bv.unwrap_or(f64::NAN),
            })
        })
        .collect()
}

/// "holds" or `otherwise`.
fn holds(ok: bool, otherwise: &'static str) -> &'static str {
    if ok {
        "holds"
    } else {
        otherwise
    }
}

/// Two rows per case (steady, then jump-to-contact BV), their notes saying whether the
/// orderings the dissertation's text claims hold.
fn table_4_4_case_rows(values: &[CaseBv], variant: &str) -> Vec<Row> {
    let (jtc, steady): (Vec<f64>, Vec<f64>) = values
        .iter()
        .map(|v| (v.jump_to_contact, v.steady_contact))
        .unzip();
    let steady_order = steady[2] < steady[0] && steady[0] < steady[1];
    let jtc_soft = jtc[1] > jtc[0] && jtc[1] > jtc[2];
    let jtc_gyration = jtc[3] > jtc[0] && jtc[3] > jtc[2];
    let mut rows = Vec::new();
    for (k, p) in PUBLISHED.iter().enumerate() {
        let name = p.name;
        let note_steady = format!(
            "class Q; steady BV order case 2 < 0 < 1 (stiffer lubricant → smaller BV): {}",
            holds(steady_order, "does not hold")
        );
        let note_jtc = format!(
            "class Q; JTC BV of case 1 above cases 0, 2: {}; of case 3 above cases 0, 2: {}",
            holds(jtc_soft, "does not hold"),
            holds(
                jtc_gyration,
                "does not hold (the radius of gyration enters only through κ)"
            )
        );
        rows.push(Row {
            reproducible: false,
            ..Row::reproducible(
                "dynamics §12 row 35 (Table 4.4)",
                &format!("{name}: steady-contact BV"),
                "%",
                p.steady_contact_bv,
                steady[k],
                Tolerance::Relative(0.5),
                variant,
                &note_steady,
            )
        });
        rows.push(Row {
            reproducible: false,
            ..Row::reproducible(
                "dynamics §12 row 35 (Table 4.4)",
                &format!("{name}: jump-to-contact BV"),
                "%",
                p.jump_to_contact_bv,
                jtc[k],
                Tolerance::Relative(0.5),
                variant,
                &note_jtc,
            )
        });
    }
    rows
}

/// Every 3-DOF row.
pub fn rows() -> Vec<Row> {
    let model = Model3Dof::dissertation();
    let mut rows = vec![truncation_row(&model)];
    rows.extend(modal_rows(&model));
    rows.extend(twelve_nm_rows(&model));
    rows.extend(table_4_4_rows());
    rows
}
