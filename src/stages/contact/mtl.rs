//! The molecularly-thin-lubricant part of the contact stage: when `[contact.NAME]` names a
//! `lubricant`, the MTL law (§3.3, eqs. 3.55–3.60; docs/contact.md) on top of the stage's ISBL solid, as curves
//! against separation and penetration (the dissertation's Figs 3.19–3.22), in HDF5 and PNGs.

use crate::contact::isbl::IsblParams;
use crate::contact::lookup::{IsblLookup, ScaledIsbl};
use crate::contact::mtl::rough::{
    ForceStiffness, InterfaceResponse, LubricantCase, MtlInterface, RoughFilm, RoughMtl,
};
use crate::contact::mtl::FwmExperiment;
use crate::contact::ContactError;
use crate::core::config::KeyError;
use crate::core::store::H5Out;
use crate::error::Result;
use crate::figures;
use crate::units::{Area, Length, Velocity, Viscosity};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::Path;
use std::sync::Arc;

/// Table 3.2 [seed]: nominal area 2,500 µm² and sliding speed 30 m/s.
pub const DEFAULT_NOMINAL_AREA: f64 = 2500e-12;
pub const DEFAULT_SPEED: f64 = 30.0;

/// Names of the four lubricant cases as `pipeline.toml` writes them.
pub const CASE_NAMES: [&str; 4] = [
    "reference",
    "humidity_temperature",
    "more_bonding",
    "larger_gyration_radius",
];

pub fn case_by_name(name: &str) -> Option<LubricantCase> {
    CASE_NAMES
        .iter()
        .position(|n| *n == name)
        .map(|i| LubricantCase::ALL[i])
}

pub fn case_name(case: LubricantCase) -> &'static str {
    let i = LubricantCase::ALL
        .iter()
        .position(|c| *c == case)
        .unwrap_or(0);
    CASE_NAMES[i]
}

/// The lubricant keys of `[contact.NAME]`, resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MtlSettings {
    pub case: LubricantCase,
    /// `A_n` the solid forces are scaled to [m²] (the lubricant law itself has no area).
    pub nominal_area: f64,
    /// Sliding speed `U` [m/s].
    pub speed: f64,
    /// Limiting viscosity `μ0` [Pa·s] (the case's value unless overridden).
    pub limiting_viscosity: f64,
    /// Minimum liquid gap `κ` [m] (the case's value unless overridden).
    pub kappa: f64,
}

/// The raw keys (all optional) as they come from `pipeline.toml` or the command line.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MtlKeys {
    pub lubricant: Option<String>,
    pub nominal_area: Option<Area>,
    pub sliding_speed: Option<Velocity>,
    pub lubricant_viscosity: Option<Viscosity>,
    pub gyration_radius: Option<Length>,
}

/// Check and resolve the lubricant-model keys.
pub fn resolve(
    keys: &MtlKeys,
    isbl: &IsblParams,
) -> std::result::Result<Option<MtlSettings>, KeyError> {
    let Some(name) = &keys.lubricant else {
        for (key, set) in [
            ("nominal_area", keys.nominal_area.is_some()),
            ("sliding_speed", keys.sliding_speed.is_some()),
            ("lubricant_viscosity", keys.lubricant_viscosity.is_some()),
            ("gyration_radius", keys.gyration_radius.is_some()),
        ] {
            if set {
                return Err(KeyError::new(
                    key,
                    "only used by the lubricant model: also set `lubricant` (reference, \
                     humidity_temperature, more_bonding, larger_gyration_radius)",
                ));
            }
        }
        return Ok(None);
    };
    let Some(case) = case_by_name(name) else {
        return Err(KeyError::new(
            "lubricant",
            format!(
                "unknown lubricant case `{name}` ({})",
                CASE_NAMES.join(", ")
            ),
        ));
    };
    let s = MtlSettings {
        case,
        nominal_area: keys.nominal_area.map_or(DEFAULT_NOMINAL_AREA, |a| a.0),
        speed: keys.sliding_speed.map_or(DEFAULT_SPEED, |v| v.0),
        limiting_viscosity: keys
            .lubricant_viscosity
            .map_or(case.limiting_viscosity(), |v| v.0),
        kappa: keys.gyration_radius.map_or(case.kappa(), |l| l.0),
    };
    if !(s.nominal_area > 0.0 && s.nominal_area <= 1e-6) {
        return Err(KeyError::new(
            "nominal_area",
            format!(
                "{} m² is out of range: 0 < A_n ≤ 1 mm² (slider contacts are µm²)",
                s.nominal_area
            ),
        ));
    }
    if !(0.0..=200.0).contains(&s.speed) {
        return Err(KeyError::new(
            "sliding_speed",
            format!("{} m/s is out of range: 0 ≤ U ≤ 200 m/s", s.speed),
        ));
    }
    if !(s.limiting_viscosity > 0.0 && s.limiting_viscosity <= 100.0) {
        return Err(KeyError::new(
            "lubricant_viscosity",
            format!(
                "{} Pa·s is out of range: 0 < μ0 ≤ 100 Pa·s",
                s.limiting_viscosity
            ),
        ));
    }
    if !(s.kappa > 0.0 && 2.0 * s.kappa < isbl.lubricant_thickness) {
        return Err(KeyError::new(
            "gyration_radius",
            format!(
                "κ = {} nm is out of range: 0 < 2κ < t = {} nm (no mobile layer otherwise)",
                s.kappa * 1e9,
                isbl.lubricant_thickness * 1e9
            ),
        ));
    }
    Ok(Some(s))
}

/// The lubricant settings as the result and the cache key state them.
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct MtlSettingsReport {
    /// MTL lubricant case.
    #[schemars(extend("enum" = ["reference", "humidity_temperature", "more_bonding", "larger_gyration_radius"]))]
    pub lubricant: String,
    /// Nominal area A_n, m².
    pub nominal_area_m2: f64,
    /// Sliding speed U, m/s.
    pub speed_m_per_s: f64,
    /// Limiting viscosity μ0, Pa·s.
    pub mu0_Pa_s: f64,
    /// Minimum liquid gap κ, m.
    pub kappa_m: f64,
}

impl MtlSettings {
    pub fn report(&self) -> MtlSettingsReport {
        MtlSettingsReport {
            lubricant: case_name(self.case).into(),
            nominal_area_m2: self.nominal_area,
            speed_m_per_s: self.speed,
            mu0_Pa_s: self.limiting_viscosity,
            kappa_m: self.kappa,
        }
    }

    /// Its part of the contact instance's cache key.
    pub fn canonical(&self) -> Value {
        serde_json::to_value(self.report()).unwrap_or(Value::Null)
    }

    /// The MTL law on the film of `isbl` (σ, t) with these settings' μ0, κ, U.
    pub fn model(&self, isbl: &IsblParams) -> std::result::Result<RoughMtl, ContactError> {
        model_for(isbl, self.speed, self.limiting_viscosity, self.kappa)
    }
}

fn model_for(
    isbl: &IsblParams,
    speed: f64,
    limiting_viscosity: f64,
    kappa: f64,
) -> std::result::Result<RoughMtl, ContactError> {
    let film = RoughFilm::new(isbl.sigma, kappa, isbl.lubricant_thickness, speed)?;
    let fwm = FwmExperiment::fukuzawa_z03().with_limiting_viscosity(limiting_viscosity)?;
    RoughMtl::from_experiment(film, &fwm)
}

/// The MTL curves of one stage instance.
pub struct MtlAnalysis {
    pub settings: MtlSettings,
    pub interface: MtlInterface<ScaledIsbl>,
    /// Separations of the curves [m] (uniform, plus both sides of each regime boundary).
    pub h: Vec<f64>,
    pub response: Vec<InterfaceResponse>,
    /// Adhesion of the ISBL model times `A_n` [N] at `h`.
    pub adhesion: Vec<f64>,
    /// Fig. 3.22: the four lubricant cases' total contact force [N] at `h` (same solid).
    pub cases: Vec<(LubricantCase, Vec<f64>)>,
}

/// Evaluate the lubricant + solid interface over `3σ − 1 nm … 3σ + t + 0.5 nm`.
pub fn analyse(settings: &MtlSettings, isbl: &Arc<IsblLookup>) -> Result<MtlAnalysis> {
    let params = *isbl.model().params();
    let solid = isbl.as_solid(settings.nominal_area);
    let interface = settings.model(&params)?.with_solid(solid.clone());
    let m = interface.model();
    let (lo, hi) = (m.solid_onset() - 1e-9, m.lubricant_surface() + 0.5e-9);
    let n = 700;
    let mut h: Vec<f64> = (0..=n)
        .map(|i| lo + (hi - lo) * i as f64 / n as f64)
        .collect();
    // Both sides of each boundary, so plots show the stiffness jumps as jumps.
    for b in [m.solid_onset(), m.transition_end(), m.lubricant_surface()] {
        h.push(b * (1.0 - 1e-9));
        h.push(b);
    }
    h.sort_by(f64::total_cmp);
    let response: Vec<InterfaceResponse> = h.iter().map(|&x| interface.evaluate(x)).collect();
    let mut adhesion = Vec::with_capacity(h.len());
    for &x in &h {
        adhesion.push(isbl.at(x)?.adhesion * settings.nominal_area);
    }
    let mut cases = Vec::new();
    for case in LubricantCase::ALL {
        let iface = model_for(
            &params,
            settings.speed,
            case.limiting_viscosity(),
            case.kappa(),
        )?
        .with_solid(solid.clone());
        cases.push((
            case,
            h.iter().map(|&x| iface.evaluate(x).total.normal).collect(),
        ));
    }
    Ok(MtlAnalysis {
        settings: *settings,
        interface,
        h,
        response,
        adhesion,
        cases,
    })
}

/// The MTL lubricant law (with --lubricant).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct MtlReport {
    pub settings: MtlSettingsReport,
    /// Landmarks of Figs 3.19–3.22 (docs/contact.md).
    pub landmarks: MtlLandmarks,
    /// The MTL law against separation.
    pub curves: Vec<MtlCurvePoint>,
}

/// Landmarks of the reference discussion (Figs 3.19–3.22; docs/contact.md).
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct MtlLandmarks {
    /// MTL lubricant case.
    #[schemars(extend("enum" = ["reference", "humidity_temperature", "more_bonding", "larger_gyration_radius"]))]
    pub lubricant: String,
    /// h/σ of the maximum lubricant stiffness (3σ + 2κ), dimensionless.
    pub h_star_max_stiffness: f64,
    /// Maximum lubricant normal stiffness, N/m.
    pub k_P_max_N_per_m: f64,
    /// Maximum lubricant shear stiffness, N/m.
    pub k_Q_max_N_per_m: f64,
    /// Total normal stiffness there, N/m.
    pub k_normal_total_at_peak_N_per_m: f64,
    /// Total lateral stiffness there, N/m.
    pub k_lateral_total_at_peak_N_per_m: f64,
    /// Lubricant bearing force at 3σ + 2κ, mN.
    pub P_lub_transition_end_mN: f64,
    /// Lubricant bearing force at 3σ, mN.
    pub P_lub_onset_mN: f64,
    /// Lubricant friction at 3σ + 2κ, µN.
    pub Q_lub_transition_end_uN: f64,
}

impl MtlLandmarks {
    /// The numbers by name (`contact/mtl/landmarks` in contact.h5), in key order.
    fn scalars(&self) -> [(&'static str, f64); 8] {
        [
            ("h_star_max_stiffness", self.h_star_max_stiffness),
            ("k_P_max_N_per_m", self.k_P_max_N_per_m),
            ("k_Q_max_N_per_m", self.k_Q_max_N_per_m),
            (
                "k_normal_total_at_peak_N_per_m",
                self.k_normal_total_at_peak_N_per_m,
            ),
            (
                "k_lateral_total_at_peak_N_per_m",
                self.k_lateral_total_at_peak_N_per_m,
            ),
            ("P_lub_transition_end_mN", self.P_lub_transition_end_mN),
            ("P_lub_onset_mN", self.P_lub_onset_mN),
            ("Q_lub_transition_end_uN", self.Q_lub_transition_end_uN),
        ]
    }
}

/// One point of the MTL curves.
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct MtlCurvePoint {
    /// Mean-plane separation h, m.
    pub h_m: f64,
    /// h/σ, dimensionless.
    pub h_star: f64,
    /// Penetration ω = 3σ − h, m.
    pub penetration_m: f64,
    /// Lubricant normal force, N.
    pub P_lub_N: f64,
    /// Lubricant friction force, N.
    pub Q_lub_N: f64,
    /// Total normal force, N.
    pub P_total_N: f64,
    /// Total friction force, N.
    pub Q_total_N: f64,
    /// Total normal stiffness, N/m.
    pub k_normal_total_N_per_m: f64,
    /// Total lateral stiffness, N/m.
    pub k_lateral_total_N_per_m: f64,
    /// Adhesion force over the nominal area, N.
    pub F_s_N: f64,
}

impl MtlAnalysis {
    /// Landmarks of the reference discussion (Figs 3.19–3.22; docs/contact.md): maximum lubricant
    /// stiffnesses, the total stiffnesses at `3σ + 2κ` and the lubricant bearing force there
    /// and at `3σ`.
    pub fn landmarks(&self) -> MtlLandmarks {
        let m = self.interface.model();
        let end = m.transition_end();
        // Just outside the transition, where the dissertation quotes the stiffnesses ("the
        // lubricant dominates the normal, the solid the lateral stiffness"): k_c + k_P,max.
        let peak = self.interface.evaluate(end * (1.0 + 1e-12)).total;
        MtlLandmarks {
            lubricant: case_name(self.settings.case).into(),
            h_star_max_stiffness: end / m.film().sigma,
            k_P_max_N_per_m: m.max_normal_stiffness(),
            k_Q_max_N_per_m: m.max_shear_stiffness(),
            k_normal_total_at_peak_N_per_m: peak.normal_stiffness,
            k_lateral_total_at_peak_N_per_m: peak.friction_stiffness,
            P_lub_transition_end_mN: self.interface.lubricant(end).normal * 1e3,
            P_lub_onset_mN: self.interface.held_lubricant_forces().normal * 1e3,
            Q_lub_transition_end_uN: self.interface.lubricant(end).friction * 1e6,
        }
    }

    pub fn report(&self) -> MtlReport {
        let sigma = self.interface.model().film().sigma;
        MtlReport {
            settings: self.settings.report(),
            landmarks: self.landmarks(),
            curves: self
                .h
                .iter()
                .zip(&self.response)
                .zip(&self.adhesion)
                .map(|((h, r), fs)| MtlCurvePoint {
                    h_m: *h,
                    h_star: h / sigma,
                    penetration_m: 3.0 * sigma - h,
                    P_lub_N: r.lubricant.normal,
                    Q_lub_N: r.lubricant.friction,
                    P_total_N: r.total.normal,
                    Q_total_N: r.total.friction,
                    k_normal_total_N_per_m: r.total.normal_stiffness,
                    k_lateral_total_N_per_m: r.total.friction_stiffness,
                    F_s_N: *fs,
                })
                .collect(),
        }
    }

    pub fn write_hdf5(&self, out: &H5Out) -> Result<()> {
        let m = self.interface.model();
        let sigma = m.film().sigma;
        let g = out.group("contact/mtl", Some("NXdata"))?;
        out.attr_str(&g, "signal", "P_total")?;
        out.attr_str_list(&g, "auxiliary_signals", &["P_lub", "P_solid"])?;
        out.attr_str_list(&g, "axes", &["penetration"])?;
        out.attr_str(&g, "lubricant", case_name(self.settings.case))?;
        let h_star: Vec<f64> = self.h.iter().map(|h| h / sigma).collect();
        let penetration: Vec<f64> = self.h.iter().map(|h| 3.0 * sigma - h).collect();
        out.write_1d(&g, "h", &self.h, "m", "mean-plane separation h")?;
        out.write_1d(&g, "h_star", &h_star, "1", "h/σ")?;
        out.write_1d(
            &g,
            "penetration",
            &penetration,
            "m",
            "penetration ω = 3σ − h (> 0 solid contact, −t < ω < 0 lubricant contact)",
        )?;
        let col = |f: &dyn Fn(&InterfaceResponse) -> f64| -> Vec<f64> {
            self.response.iter().map(f).collect()
        };
        type Pick = fn(&ForceStiffness) -> f64;
        type Part = fn(&InterfaceResponse) -> ForceStiffness;
        let parts: [(&str, Part, &str); 3] = [
            ("lub", |r| r.lubricant, "lubricant"),
            ("solid", |r| r.solid, "solid (ISBL × A_n)"),
            ("total", |r| r.total, "lubricant + solid"),
        ];
        let fields: [(&str, Pick, &str, &str); 4] = [
            ("P", |f| f.normal, "N", "normal force"),
            ("Q", |f| f.friction, "N", "friction force"),
            (
                "k_normal",
                |f| f.normal_stiffness,
                "N/m",
                "normal stiffness −dP/dh",
            ),
            (
                "k_lateral",
                |f| f.friction_stiffness,
                "N/m",
                "friction (lateral) stiffness −dQ/dh",
            ),
        ];
        for (suffix, part, part_desc) in parts {
            for (name, pick, unit, desc) in fields {
                out.write_1d(
                    &g,
                    &format!("{name}_{suffix}"),
                    &col(&|r| pick(&part(r))),
                    unit,
                    &format!("{desc}, {part_desc}"),
                )?;
            }
        }
        out.write_1d(
            &g,
            "F_s",
            &self.adhesion,
            "N",
            "adhesion (ISBL × A_n), pulling the surfaces together",
        )?;
        let c = out.group("contact/mtl/cases", Some("NXdata"))?;
        out.attr_str(&c, "signal", "reference")?;
        out.attr_str_list(&c, "axes", &["penetration"])?;
        out.write_1d(&c, "penetration", &penetration, "m", "ω = 3σ − h")?;
        for (case, p) in &self.cases {
            out.write_1d(
                &c,
                case_name(*case),
                p,
                "N",
                &format!(
                    "total contact force, μ0 = {} Pa·s, κ = {} nm",
                    case.limiting_viscosity(),
                    case.kappa() * 1e9
                ),
            )?;
        }
        let a = out.group("contact/mtl/landmarks", None)?;
        for (k, x) in self.landmarks().scalars() {
            // A non-finite landmark is null in the JSON and not written here.
            if x.is_finite() {
                out.write_scalar(&a, k, x, "see name", "MTL landmark (docs/contact.md)")?;
            }
        }
        Ok(())
    }

    /// Figs 3.19–3.22.
    pub fn plots(&self, dir: &Path) -> Result<()> {
        let m = self.interface.model();
        let sigma = m.film().sigma;
        let t = m.film().film_thickness;
        let pen_nm = |h: f64| (3.0 * sigma - h) * 1e9;
        let series = |x: &dyn Fn(f64) -> f64, y: &dyn Fn(&InterfaceResponse) -> f64| {
            self.h
                .iter()
                .zip(&self.response)
                .map(|(&h, r)| (x(h), y(r)))
                .collect::<Vec<_>>()
        };
        let hs = |h: f64| h / sigma;
        figures::semilogy_png(
            &dir.join("mtl_stiffness.png"),
            &format!(
                "Normal and lateral stiffness ({}, A_n = {:.0} µm²) — Fig. 3.19",
                case_name(self.settings.case),
                self.settings.nominal_area * 1e12
            ),
            "h/σ",
            "N/m",
            &[
                (
                    "normal, lubricant",
                    series(&hs, &|r| r.lubricant.normal_stiffness),
                ),
                ("normal, solid", series(&hs, &|r| r.solid.normal_stiffness)),
                ("normal, total", series(&hs, &|r| r.total.normal_stiffness)),
                (
                    "lateral, lubricant",
                    series(&hs, &|r| r.lubricant.friction_stiffness),
                ),
                (
                    "lateral, solid",
                    series(&hs, &|r| r.solid.friction_stiffness),
                ),
                (
                    "lateral, total",
                    series(&hs, &|r| r.total.friction_stiffness),
                ),
            ],
            &[],
        )?;
        figures::semilogy_png(
            &dir.join("mtl_stiffness_penetration.png"),
            "Total stiffness vs penetration (lubricant contact at −t < ω < 0) — Fig. 3.20",
            "penetration ω (nm)",
            "N/m",
            &[
                ("normal", series(&pen_nm, &|r| r.total.normal_stiffness)),
                ("lateral", series(&pen_nm, &|r| r.total.friction_stiffness)),
            ],
            &[],
        )?;
        let fs: Vec<(f64, f64)> = self
            .h
            .iter()
            .zip(&self.adhesion)
            .map(|(&h, f)| (pen_nm(h), f * 1e3))
            .collect();
        figures::stacked_png(
            &dir.join("mtl_forces.png"),
            "Total contact, friction and adhesion forces — Fig. 3.21 (shaded: lubricant contact)",
            "penetration ω (nm)",
            &[
                ("contact P (mN)", series(&pen_nm, &|r| r.total.normal * 1e3)),
                (
                    "friction Q (mN)",
                    series(&pen_nm, &|r| r.total.friction * 1e3),
                ),
                ("adhesion F_s (mN)", fs),
            ],
            &[(-t * 1e9, 0.0)],
        )?;
        let cases: Vec<(String, Vec<(f64, f64)>)> = self
            .cases
            .iter()
            .map(|(case, p)| {
                (
                    format!(
                        "{} (μ0 {:.3} Pa·s, κ {:.2} nm)",
                        case_name(*case),
                        case.limiting_viscosity(),
                        case.kappa() * 1e9
                    ),
                    self.h
                        .iter()
                        .zip(p)
                        .map(|(&h, p)| (pen_nm(h), p * 1e3))
                        .collect(),
                )
            })
            .collect();
        let refs: Vec<(&str, Vec<(f64, f64)>)> =
            cases.iter().map(|(n, s)| (n.as_str(), s.clone())).collect();
        figures::lines_png(
            &dir.join("mtl_lubricant_cases.png"),
            "Total contact force for four lubricant conditions — Fig. 3.22",
            "penetration ω (nm)",
            "contact force (mN)",
            &refs,
        )?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::isbl::IsblModel;

    fn lookup() -> Arc<IsblLookup> {
        let model = IsblModel::new(IsblParams::mtl_table_3_2()).unwrap();
        Arc::new(IsblLookup::build_standard(model).unwrap())
    }

    #[test]
    fn reference_landmarks_match_the_spec() {
        // Figs 3.19–3.22 (docs/contact.md): k_P,max = 1.269e7 N/m at h* = 3.7317, P_lub(3σ+2κ) = 3.81 mN,
        // Q_lub(3σ+2κ) = 0.088 µN; P_lub(3σ) = 7.61 mN plus a small solid-dependent term.
        let keys = MtlKeys {
            lubricant: Some("reference".into()),
            ..MtlKeys::default()
        };
        let s = resolve(&keys, &IsblParams::mtl_table_3_2())
            .unwrap()
            .unwrap();
        let a = analyse(&s, &lookup()).unwrap();
        let l = a.landmarks();
        assert!((l.k_P_max_N_per_m / 1.2690e7 - 1.0).abs() < 1e-4);
        assert!((l.h_star_max_stiffness - 3.7317).abs() < 1e-4);
        assert!((l.P_lub_transition_end_mN - 3.807).abs() < 1e-3);
        assert!((l.Q_lub_transition_end_uN - 0.088).abs() < 1e-3);
        let onset = l.P_lub_onset_mN;
        assert!(onset > 7.614 && onset < 7.614 * 1.05, "{onset}");
        // Fig. 3.22 ordering at 3σ (penetration 0): case 2 < 1 < 4 < 3.
        let i =
            a.h.iter()
                .position(|&h| h >= a.interface.model().solid_onset())
                .unwrap();
        let at = |k: usize| a.cases[k].1[i];
        assert!(at(1) < at(0) && at(0) < at(3) && at(3) < at(2));
        assert!(a.response.iter().all(|r| r.total.normal.is_finite()));
    }

    #[test]
    fn keys_are_checked() {
        let p = IsblParams::mtl_table_3_2();
        let bad = |k: MtlKeys| resolve(&k, &p).unwrap_err().key;
        assert_eq!(
            bad(MtlKeys {
                lubricant: Some("olive_oil".into()),
                ..MtlKeys::default()
            }),
            "lubricant"
        );
        assert_eq!(
            bad(MtlKeys {
                sliding_speed: Some(Velocity(10.0)),
                ..MtlKeys::default()
            }),
            "sliding_speed"
        );
        assert_eq!(
            bad(MtlKeys {
                lubricant: Some("reference".into()),
                gyration_radius: Some(Length(1e-9)),
                ..MtlKeys::default()
            }),
            "gyration_radius"
        );
        assert_eq!(
            bad(MtlKeys {
                lubricant: Some("reference".into()),
                nominal_area: Some(Area(-1.0)),
                ..MtlKeys::default()
            }),
            "nominal_area"
        );
        assert_eq!(resolve(&MtlKeys::default(), &p).unwrap(), None);
    }
}
