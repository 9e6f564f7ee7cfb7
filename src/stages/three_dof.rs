//! 3-DOF slider stage `[three_dof.NAME]` (dissertation Chapter 4; docs/three-dof.md): one scenario —
//! constant actuation, impulse shock or a variable actuation profile — run for each requested
//! interface (ISBL, MTL with each lubricant case of Table 4.4), one cached case each, in
//! parallel. Outputs per case an HDF5 of the time histories and a PNG of them; per instance a
//! table with one row per case (PT, bulge spacing, BV/FHM overall and per Table 4.4 window,
//! contact shares, peak forces, the features that touched).

use super::case_engine::{
    case_value, typed_case, CaseEngine, ListedCase, PreparedCases, UpstreamEntries,
};
use super::{FromConfig, StageContext, StageKind, StageOutput};
use crate::artefacts::cases::{self as case_files};
use crate::artefacts::contact::upstream_isbl_params;
use crate::artefacts::dmw_tracks::{self, read_dmw_tracks, DmwTrack};
use crate::contact::isbl::{IsblModel, SurfaceEnergy};
use crate::contact::lookup::IsblLookup;
use crate::contact::mtl::{FwmExperiment, LubricantCase, RoughFilm, RoughMtl};
use crate::core::cases;
use crate::core::config::{ConfigError, PipelineFile};
use crate::core::store::H5Out;
use crate::dynamics::three_dof::case::{History3Dof, ThreeDofCase};
use crate::dynamics::three_dof::inputs::ActuationProfile;
use crate::dynamics::three_dof::interface::{FeatureInterface, InterfaceLaw};
use crate::dynamics::two_dof::DmwInput;
use crate::error::{Error, Result};
use crate::slider::three_dof_params::{CaseInterface, ThreeDofParams};
use serde_json::{json, Map, Value};
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

/// The MTL law of a Table 4.4 case on the interface's film (σ, t) at the disk speed.
fn mtl_law(case: LubricantCase, sigma: f64, thickness: f64, speed: f64) -> Result<RoughMtl> {
    let film = RoughFilm::new(sigma, case.kappa(), thickness, speed)?;
    let exp = FwmExperiment::fukuzawa_z03().with_limiting_viscosity(case.limiting_viscosity())?;
    Ok(RoughMtl::from_experiment(film, &exp)?)
}

/// Simulate one case into `dir` (`case.h5`); returns its metrics.
fn run_case(
    p: &ThreeDofParams,
    which: CaseInterface,
    isbl: &IsblLookup,
    tracks: Option<&[DmwTrack; 3]>,
    dir: &Path,
) -> Result<Value> {
    let model = p.model();
    let ip = isbl.model().params();
    let law = match which {
        CaseInterface::Isbl => InterfaceLaw::Isbl,
        CaseInterface::Mtl(l) => InterfaceLaw::Mtl(mtl_law(
            l,
            ip.sigma,
            ip.lubricant_thickness,
            model.disk_speed,
        )?),
    };
    let interface = FeatureInterface::new(
        isbl,
        law,
        p.contact_force,
        p.contact_damping_ratio,
        model.air_bearing.slider.mass,
    )?;
    let inputs = tracks.map(|t| {
        let one = |k: usize| DmwInput {
            displacement: &t[k].displacement,
            velocity: &t[k].velocity,
            sample_rate: t[k].sample_rate,
        };
        [one(0), one(1), one(2)]
    });
    let case = ThreeDofCase::new(
        &model,
        interface,
        p.profile.clone(),
        p.shock,
        inputs,
        p.options,
    )?;
    let h = case.run()?;
    let sigma = ip.sigma;
    let metrics = case_metrics(p, &h, 3.0 * sigma, 3.0 * sigma + ip.lubricant_thickness)?;
    write_case_h5(&dir.join("case.h5"), &h)?;
    history_png(&dir.join("history.png"), &h, &which.label())?;
    if !p.profile.is_constant() {
        let levels = (3.0 * sigma, 3.0 * sigma + ip.lubricant_thickness);
        variable_actuation_pngs(dir, &h, &p.profile, levels, &which.label())?;
    }
    let mut m = metrics;
    m.insert("case".into(), json!(which.label()));
    m.insert("steps".into(), json!(h.stats.accepted_steps));
    Ok(Value::Object(m))
}

fn window(x: &[f64], dt: f64, (a, b): (f64, f64)) -> &[f64] {
    let n = x.len();
    let i0 = ((a / dt).round() as usize).min(n);
    let i1 = ((b / dt).round() as usize).clamp(i0, n);
    &x[i0..i1]
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

fn std(x: &[f64]) -> f64 {
    let m = mean(x);
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

fn case_metrics(
    p: &ThreeDofParams,
    h: &History3Dof,
    solid: f64,
    lubricant: f64,
) -> Result<Map<String, Value>> {
    let dt = h.dt;
    let end = (h.len() - 1) as f64 * dt;
    let steady = (p.steady_start, end + dt);
    let mut m = Map::new();
    let nm = |x: f64| x * 1e9;
    let pt = window(&h.pole_tip, dt, steady);
    let bulge = window(&h.bulge_spacing, dt, steady);
    m.insert("pole_tip_mean_nm".into(), json!(nm(mean(pt))));
    m.insert("pole_tip_std_nm".into(), json!(nm(std(pt))));
    m.insert("bulge_spacing_mean_nm".into(), json!(nm(mean(bulge))));
    m.insert("bulge_spacing_std_nm".into(), json!(nm(std(bulge))));
    m.insert(
        "bulge_vibration_percent".into(),
        json!(h.bulge_vibration(steady)),
    );
    let roll = window(&h.roll, dt, steady);
    m.insert("roll_std_urad".into(), json!(std(roll) * 1e6));
    let n = bulge.len().max(1) as f64;
    let i0 = ((steady.0 / dt).round() as usize).min(h.len());
    let any_below = |k: usize, level: f64| h.feature_spacing.iter().any(|s| s[k] < level);
    let solid_share = (i0..h.len()).filter(|&k| any_below(k, solid)).count() as f64 / n;
    let lube_share = (i0..h.len()).filter(|&k| any_below(k, lubricant)).count() as f64 / n;
    m.insert("solid_contact_percent".into(), json!(100.0 * solid_share));
    m.insert(
        "lubricant_contact_percent".into(),
        json!(100.0 * lube_share),
    );
    // Over the integrator's steps, not only the samples (an impact can fall between them).
    m.insert(
        "peak_contact_force_mN".into(),
        json!(h.peak_contact_force * 1e3),
    );
    m.insert(
        "peak_lubricant_force_mN".into(),
        json!(h.peak_lubricant_force * 1e3),
    );
    m.insert(
        "mean_contact_force_mN".into(),
        json!(mean(window(&h.contact_force, dt, steady)) * 1e3),
    );
    m.insert(
        "mean_friction_mN".into(),
        json!(mean(window(&h.friction, dt, steady)) * 1e3),
    );
    let touched: Vec<String> = h
        .features
        .iter()
        .zip(&h.feature_spacing)
        .filter(|(_, s)| s.iter().any(|v| *v < solid))
        .map(|(f, _)| format!("{f:?}"))
        .collect();
    m.insert("features_in_solid_contact".into(), json!(touched.join(" ")));
    m.insert("ab_lost_samples".into(), json!(h.ab_lost_samples));
    // Closest approach of every feature over the whole run (which ones came near the disk).
    for (f, sp) in h.features.iter().zip(&h.feature_spacing) {
        let min = sp
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(f64::INFINITY, f64::min);
        m.insert(
            format!("min_spacing_{}_nm", feature_column(f)),
            json!(min.is_finite().then(|| nm(min))),
        );
    }
    // Contact severity over the steady window, one definition for every area
    // (docs/conventions.md): headline ratio of means μ = Q̄/F̄_c, P_m = F̄_c/Ā_r, τ = Q̄/Ā_r,
    // the mean of the instantaneous ratio (samples with F_c > 1 µN) beside it.
    let severity = crate::dynamics::metrics::contact_severity(
        &crate::dynamics::metrics::ContactSeries {
            contact_force_n: &h.contact_force[i0..],
            friction_n: &h.friction[i0..],
            real_area_m2: &h.real_area[i0..],
            adhesion_n: None,
        },
        crate::dynamics::metrics::FORCE_THRESHOLD_N,
    );
    if let Ok(c) = severity {
        let put = |m: &mut Map<String, Value>, k: &str, v: Option<f64>| {
            if let Some(v) = v.filter(|v| v.is_finite()) {
                m.insert(k.into(), json!(v));
            }
        };
        let gpa = |v: Option<f64>| v.map(|x| x * 1e-9);
        put(
            &mut m,
            "friction_coefficient",
            c.friction_coefficient_ratio_of_means,
        );
        put(
            &mut m,
            "friction_coefficient_mean_inst",
            c.friction_coefficient.map(|s| s.mean),
        );
        put(
            &mut m,
            "mean_pressure_GPa",
            gpa(c.mean_pressure_pa_ratio_of_means),
        );
        put(
            &mut m,
            "mean_pressure_GPa_mean_inst",
            gpa(c.mean_pressure_pa.map(|s| s.mean)),
        );
        put(
            &mut m,
            "shear_traction_GPa",
            gpa(c.shear_traction_pa_ratio_of_means),
        );
        put(
            &mut m,
            "shear_traction_GPa_mean_inst",
            gpa(c.shear_traction_pa.map(|s| s.mean)),
        );
    }
    // Table 4.4 windows of a variable profile.
    if !p.profile.is_constant() {
        let t = h.table_4_4(&p.profile, lubricant);
        m.insert(
            "first_lubricant_contact_ms".into(),
            json!(t.first_lubricant_contact.map(|t| t * 1e3)),
        );
        m.insert("flying_fhm_percent".into(), json!(t.flying_fhm));
        m.insert(
            "jump_to_contact_bv_percent".into(),
            json!(t.jump_to_contact_bv),
        );
        m.insert(
            "steady_contact_bv_percent".into(),
            json!(t.steady_contact_bv),
        );
    }
    Ok(m)
}

/// `Pad(PlusY)` → `pad_plus_y`: a column-friendly feature name.
fn feature_column(f: &crate::dynamics::three_dof::geometry::Feature) -> String {
    let mut out = String::new();
    for (i, c) in format!("{f:?}").replace(['(', ')'], "").chars().enumerate() {
        if c.is_uppercase() && i > 0 {
            out.push('_');
        }
        out.push(c.to_ascii_lowercase());
    }
    out
}

fn write_case_h5(path: &Path, h: &History3Dof) -> Result<()> {
    let out = H5Out::create(path)?;
    let entry = out.group("case", Some("NXentry"))?;
    out.attr_str(&entry, "default", "history")?;
    let g = out.history_group("case/history", "pole_tip", h.dt, h.len())?;
    for (name, data, unit, what) in [
        ("heave", &h.heave, "m", "COM heave from the nominal state"),
        ("heave_rate", &h.heave_rate, "m/s", "dz/dt"),
        ("pitch", &h.pitch, "rad", "pitch θ"),
        ("pitch_rate", &h.pitch_rate, "rad/s", "dθ/dt"),
        ("roll", &h.roll, "rad", "roll φ"),
        ("roll_rate", &h.roll_rate, "rad/s", "dφ/dt"),
        ("actuation", &h.actuation, "m", "TFC actuation h_TFC"),
        ("pole_tip", &h.pole_tip, "m", "pole-tip flying height PT"),
        (
            "bulge_spacing",
            &h.bulge_spacing,
            "m",
            "solid spacing of the bulge",
        ),
        (
            "contact_force",
            &h.contact_force,
            "N",
            "solid contact force, all features",
        ),
        (
            "lubricant_force",
            &h.lubricant_force,
            "N",
            "lubricant force, all features",
        ),
        ("adhesion", &h.adhesion, "N", "adhesion, all features"),
        ("friction", &h.friction, "N", "friction, all features"),
        (
            "real_area",
            &h.real_area,
            "m^2",
            "real contact area, all features",
        ),
        ("front_force", &h.front_force, "N", "front AB spring force"),
        ("rear_force", &h.rear_force, "N", "rear AB spring force"),
        (
            "shock_force",
            &h.shock_force,
            "N",
            "shock force toward the disk",
        ),
    ] {
        out.write_1d(&g, name, data, unit, what)?;
    }
    let fg = out.group("case/features", None)?;
    for (i, f) in h.features.iter().enumerate() {
        let name = format!("{f:?}")
            .replace(['(', ')'], "_")
            .trim_end_matches('_')
            .to_string();
        out.write_1d(
            &fg,
            &format!("{name}_spacing"),
            &h.feature_spacing[i],
            "m",
            "solid spacing",
        )?;
        out.write_1d(
            &fg,
            &format!("{name}_normal"),
            &h.feature_normal[i],
            "N",
            "normal force F_c + P_lub − F_s",
        )?;
    }
    Ok(out.finish()?)
}

/// `(time in ms, value · scale)` of a series sampled every `dt` seconds (the plots' x axis).
fn ms_series(dt: f64, x: &[f64], scale: f64) -> Vec<(f64, f64)> {
    x.iter()
        .enumerate()
        .map(|(k, v)| (k as f64 * dt * 1e3, v * scale))
        .collect()
}

fn history_png(path: &Path, h: &History3Dof, label: &str) -> Result<()> {
    use crate::figures::{time_histories_png, Panel};
    let pair = |x: &[f64], scale: f64| ms_series(h.dt, x, scale);
    // Every feature that comes within 50 nm of the disk (the bulge always).
    let names: Vec<String> = h.features.iter().map(|f| format!("{f:?}")).collect();
    let near: Vec<(&str, Vec<(f64, f64)>)> = names
        .iter()
        .zip(&h.feature_spacing)
        .filter(|(n, s)| *n == "Bulge" || s.iter().any(|v| *v < 50e-9))
        .map(|(n, s)| (n.as_str(), pair(s, 1e9)))
        .collect();
    time_histories_png(
        path,
        &format!("3-DOF slider, {label} (Figs 4.9–4.11, 4.14–4.16)"),
        &[
            Panel {
                y_desc: "spacing (nm)",
                series: vec![
                    ("pole tip PT", pair(&h.pole_tip, 1e9)),
                    ("bulge", pair(&h.bulge_spacing, 1e9)),
                    ("actuation", pair(&h.actuation, 1e9)),
                ],
            },
            Panel {
                y_desc: "force (mN)",
                series: vec![
                    ("contact", pair(&h.contact_force, 1e3)),
                    ("lubricant", pair(&h.lubricant_force, 1e3)),
                    ("adhesion", pair(&h.adhesion, 1e3)),
                    ("friction", pair(&h.friction, 1e3)),
                ],
            },
            Panel {
                y_desc: "feature spacing (nm)",
                series: near,
            },
            Panel {
                y_desc: "roll (µrad)",
                series: vec![("roll φ", pair(&h.roll, 1e6))],
            },
        ],
    )?;
    Ok(())
}

/// The variable-actuation figures: bulge and pole-tip spacing against the solid and lubricant
/// surfaces with the Table 4.4 regimes shaded (`regimes.png`, Figs 4.14 and 4.16), and the
/// interface forces with μ (`forces.png`, Fig. 4.15).
fn variable_actuation_pngs(
    dir: &Path,
    h: &History3Dof,
    profile: &ActuationProfile,
    (solid, lubricant): (f64, f64),
    label: &str,
) -> Result<()> {
    use crate::figures::{time_histories_banded_png, time_histories_png, Panel, RegimeBand};
    let t_ms = |k: usize| k as f64 * h.dt * 1e3;
    let pair = |x: &[f64], scale: f64| ms_series(h.dt, x, scale);
    let level = |v: f64| vec![(0.0, v * 1e9), (t_ms(h.len().saturating_sub(1)), v * 1e9)];
    let mut bands = Vec::new();
    if let Some(w) = h.regime_windows(profile, lubricant) {
        let ms = |(a, b): (f64, f64)| (a * 1e3, b * 1e3);
        let mut push = |win: (f64, f64), label: &'static str| {
            let (x0, x1) = ms(win);
            bands.push(RegimeBand { x0, x1, label });
        };
        push(w.flying, "flying (FHM)");
        if let Some(j) = w.jump_to_contact {
            push(j, "jump to contact (BV)");
        }
        if let Some(sc) = w.steady_contact {
            push(sc, "steady contact (BV)");
            // Retraction: from the plateau's end to the next kink (or the run's end).
            let end = (h.len().saturating_sub(1)) as f64 * h.dt;
            let next = profile
                .breakpoints()
                .into_iter()
                .find(|&b| b > sc.1 + 1e-12)
                .unwrap_or(end);
            push((sc.1, next), "snap-off");
        }
    }
    time_histories_banded_png(
        &dir.join("regimes.png"),
        &format!("3-DOF slider, variable actuation, {label} (Figs 4.14, 4.16)"),
        &[
            Panel {
                y_desc: "bulge spacing (nm)",
                series: vec![
                    ("bulge", pair(&h.bulge_spacing, 1e9)),
                    ("solid surface 3σ", level(solid)),
                    ("lubricant surface 3σ + t", level(lubricant)),
                ],
            },
            Panel {
                y_desc: "clearance (nm)",
                series: vec![
                    ("pole tip PT", pair(&h.pole_tip, 1e9)),
                    ("actuation h_TFC", pair(&h.actuation, 1e9)),
                ],
            },
        ],
        &bands,
    )?;
    // μ only where the interface carries load (> 1 µN): a gap elsewhere, not a zero.
    let mu: Vec<(f64, f64)> = (0..h.len())
        .map(|k| {
            let normal = h.contact_force[k] + h.lubricant_force[k];
            let v = if normal > 1e-6 {
                h.friction[k] / normal
            } else {
                f64::NAN
            };
            (t_ms(k), v)
        })
        .collect();
    time_histories_png(
        &dir.join("forces.png"),
        &format!("3-DOF slider, variable actuation, {label}: interface (Fig. 4.15)"),
        &[
            Panel {
                y_desc: "adhesion (mN)",
                series: vec![("F_s", pair(&h.adhesion, 1e3))],
            },
            Panel {
                y_desc: "contact (mN)",
                series: vec![
                    ("solid F_c", pair(&h.contact_force, 1e3)),
                    ("lubricant P_lub", pair(&h.lubricant_force, 1e3)),
                ],
            },
            Panel {
                y_desc: "friction (mN)",
                series: vec![("Q", pair(&h.friction, 1e3))],
            },
            Panel {
                y_desc: "friction coefficient",
                series: vec![("μ = Q / (F_c + P_lub)", mu)],
            },
        ],
    )?;
    Ok(())
}

/// The parameters with the upstream bulge fit in place (docs/bulge.md): a_TFC, w_TFC and
/// x_TFC from `[bulge.NAME]`'s `tfc`, checked against the 3-DOF slider (read and write
/// elements on the bulge, bulge inside the slider).
fn fitted_params(
    p: &ThreeDofParams,
    upstream: &std::collections::BTreeMap<String, Value>,
) -> Result<ThreeDofParams> {
    let mut p = p.clone();
    if let Some(b) = &p.bulge {
        let fitted = crate::artefacts::bulge::upstream_bulge(upstream, b)?;
        let x = fitted.x_tfc_m.ok_or_else(|| Error::UpstreamField {
            kind: "bulge",
            name: b.clone(),
            what: "x_TFC (no trailing edge detected)".into(),
        })?;
        p.fitted = Some(crate::dynamics::geometry::BulgeDesign {
            semi_width_x: fitted.a_tfc_m,
            full_width_y: fitted.w_tfc_m,
            offset_from_te: x,
        });
        let m = p.model();
        m.geometry.validate()?;
        m.air_bearing.validate()?;
    }
    Ok(p)
}

/// A `[three_dof.NAME]` instance with its upstream in place (fitted bulge, contact
/// parameters, DMW file, upstream keys): what both the stage and a Slurm worker
/// (`engine::distributed`, docs/slurm.md) key and compute its cases from, so a case
/// computed on a node has the key and bytes of a local run.
pub struct PreparedThreeDof {
    /// The instance's parameters with the upstream bulge fit in place.
    pub params: ThreeDofParams,
    isbl_params: crate::contact::isbl::IsblParams,
    dmw_file: Option<std::path::PathBuf>,
    contact_key: String,
    dmw_key: Option<String>,
    bulge_key: Option<String>,
}

impl PreparedThreeDof {
    /// From the consumed instances' results, entry directories and cache keys.
    pub fn prepare(
        params: &ThreeDofParams,
        upstream: &std::collections::BTreeMap<String, Value>,
        upstream_dirs: &std::collections::BTreeMap<String, std::path::PathBuf>,
        key_of: impl Fn(&str) -> String,
    ) -> Result<Self> {
        let p = fitted_params(params, upstream)?;
        let isbl_params = upstream_isbl_params(upstream, &p.contact)?;
        let dmw_file = match &p.dmw {
            Some(d) => Some(dmw_tracks::upstream_file(upstream_dirs, d)?),
            None => None,
        };
        Ok(Self {
            contact_key: key_of(&p.contact),
            dmw_key: p.dmw.as_deref().map(&key_of),
            bulge_key: p.bulge.as_deref().map(&key_of),
            params: p,
            isbl_params,
            dmw_file,
        })
    }

    /// The case's key parameters (what `cases::get_or_compute` hashes).
    pub fn case_params(&self, which: CaseInterface) -> Value {
        let mut params = json!({"instance": self.params.canonical(), "case": which.label(), "contact_key": self.contact_key, "dmw_key": self.dmw_key});
        // A fitted bulge keys the case by its instance's key (other cases keep theirs).
        if let (Some(k), Some(obj)) = (&self.bulge_key, params.as_object_mut()) {
            obj.insert("bulge_key".into(), json!(k));
        }
        params
    }

    /// The interface lookup tables and DMW tracks the cases share (built once per process).
    pub fn solver(&self) -> Result<ThreeDofSolver> {
        let tracks = match &self.dmw_file {
            Some(f) => Some(read_dmw_tracks(f)?),
            None => None,
        };
        // The MTL runs use the variable surface energy of Chapter 3 (contact-isbl §10).
        let build = |variable: bool| -> Result<IsblLookup> {
            let mut ip = self.isbl_params;
            if variable {
                ip.surface_energy = SurfaceEnergy::seed_variable();
            }
            Ok(IsblLookup::build_standard_unverified(IsblModel::new(ip)?)?)
        };
        let isbl_solid = build(false)?;
        let isbl_mtl = if self
            .params
            .cases
            .iter()
            .any(|c| matches!(c, CaseInterface::Mtl(_)))
        {
            Some(build(true)?)
        } else {
            None
        };
        Ok(ThreeDofSolver {
            isbl_solid,
            isbl_mtl,
            tracks,
        })
    }
}

/// What the cases of one prepared instance share: see [`PreparedThreeDof::solver`].
pub struct ThreeDofSolver {
    isbl_solid: IsblLookup,
    isbl_mtl: Option<IsblLookup>,
    tracks: Option<[DmwTrack; 3]>,
}

impl ThreeDofSolver {
    /// Simulate case `which` of `prepared` into `dir`; returns its metrics.
    pub fn compute_case(
        &self,
        prepared: &PreparedThreeDof,
        which: CaseInterface,
        dir: &Path,
    ) -> Result<Value> {
        let isbl = match which {
            CaseInterface::Isbl => &self.isbl_solid,
            CaseInterface::Mtl(_) => self.isbl_mtl.as_ref().unwrap_or(&self.isbl_solid),
        };
        run_case(&prepared.params, which, isbl, self.tracks.as_ref(), dir)
    }
}

impl StageKind for ThreeDofStage {
    const KIND: &'static str = "three_dof";
    const MODEL_VERSION: &'static str = MODEL_VERSION;

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
    fn run(&self, ctx: &StageContext) -> Result<StageOutput> {
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
            json!(done.iter().filter(|(_, e)| e.cached).count()),
        );
        let dir = ctx.out_dir.join(case_files::DIR);
        std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
        let mut rows = Vec::new();
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
            if let Value::Object(m) = &entry.result {
                rows.push(m.clone());
            }
        }
        crate::core::store::write_table(&rows, &ctx.out_dir.join("cases"))?;
        let mut row = Map::new();
        row.insert("scenario".into(), json!(p.scenario));
        row.insert("cases".into(), json!(done.len()));
        if let Some(first) = rows.first() {
            for k in [
                "pole_tip_mean_nm",
                "bulge_vibration_percent",
                "peak_contact_force_mN",
            ] {
                row.insert(
                    format!("{}_{k}", first["case"].as_str().unwrap_or("case")),
                    first[k].clone(),
                );
            }
        }
        Ok(StageOutput {
            result: {
                let mut r = json!({
                    "cases": rows,
                    "case_keys": done.iter().map(|(_, e)| e.key.clone()).collect::<Vec<_>>(),
                    "table": "cases.parquet",
                });
                // The bulge the cases ran with, when it came from a fit (docs/bulge.md).
                if let (Some(d), Some(obj)) = (p.fitted, r.as_object_mut()) {
                    obj.insert(
                        "fitted_bulge".into(),
                        json!({"a_tfc_m": d.semi_width_x, "w_tfc_m": d.full_width_y, "x_tfc_m": d.offset_from_te}),
                    );
                }
                r
            },
            summary_row: Some(row),
        })
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
