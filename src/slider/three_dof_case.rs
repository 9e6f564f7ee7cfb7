//! One `[three_dof]` case (dissertation Chapter 4; docs/three-dof.md): the instance with its
//! upstream in place, the interface tables and DMW tracks its cases share, one case run into
//! its HDF5, figures and table row. The stage and a Slurm worker compute every case through
//! here (`stages::three_dof`'s case capability), so a case has the same bytes wherever it ran.

use crate::artefacts::contact::upstream_isbl_params;
use crate::artefacts::dmw_tracks::{self, read_dmw_tracks, DmwTrack};
use crate::artefacts::three_dof::{MinSpacings, Table44Columns, ThreeDofCaseResult};
use crate::contact::isbl::{IsblModel, SurfaceEnergy};
use crate::contact::lookup::IsblLookup;
use crate::contact::mtl::{FwmExperiment, LubricantCase, RoughFilm, RoughMtl};
use crate::core::store::H5Out;
use crate::dynamics::three_dof::case::{History3Dof, ThreeDofCase};
use crate::dynamics::three_dof::inputs::ActuationProfile;
use crate::dynamics::three_dof::interface::{FeatureInterface, InterfaceLaw};
use crate::dynamics::two_dof::DmwInput;
use crate::error::{Error, Result};
use crate::slider::three_dof_params::{CaseInterface, ThreeDofParams};
use serde_json::{json, Value};
use std::path::Path;

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
    let levels = (3.0 * sigma, 3.0 * sigma + ip.lubricant_thickness);
    let result = case_result(p, &h, levels, which.label());
    write_case_h5(&dir.join("case.h5"), &h)?;
    history_png(&dir.join("history.png"), &h, &which.label())?;
    if !p.profile.is_constant() {
        variable_actuation_pngs(dir, &h, &p.profile, levels, &which.label())?;
    }
    serde_json::to_value(&result).map_err(|e| Error::Encode {
        kind: "three_dof",
        what: "case result".into(),
        message: e.to_string(),
    })
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

/// The case's result: its steady-window statistics, features in contact, closest approaches,
/// contact severity and (variable profile) Table 4.4; `levels` are the solid and lubricant
/// contact spacings.
fn case_result(
    p: &ThreeDofParams,
    h: &History3Dof,
    (solid, lubricant): (f64, f64),
    case: String,
) -> ThreeDofCaseResult {
    let dt = h.dt;
    let end = (h.len() - 1) as f64 * dt;
    let steady = (p.steady_start, end + dt);
    let nm = |x: f64| x * 1e9;
    let pt = window(&h.pole_tip, dt, steady);
    let bulge = window(&h.bulge_spacing, dt, steady);
    let roll = window(&h.roll, dt, steady);
    let n = bulge.len().max(1) as f64;
    let i0 = ((steady.0 / dt).round() as usize).min(h.len());
    let any_below = |k: usize, level: f64| h.feature_spacing.iter().any(|s| s[k] < level);
    let solid_share = (i0..h.len()).filter(|&k| any_below(k, solid)).count() as f64 / n;
    let lube_share = (i0..h.len()).filter(|&k| any_below(k, lubricant)).count() as f64 / n;
    let touched: Vec<String> = h
        .features
        .iter()
        .zip(&h.feature_spacing)
        .filter(|(_, s)| s.iter().any(|v| *v < solid))
        .map(|(f, _)| format!("{f:?}"))
        .collect();
    // Closest approach of every feature over the whole run (which ones came near the disk).
    let min_spacing = h
        .features
        .iter()
        .zip(&h.feature_spacing)
        .map(|(f, sp)| {
            let min = sp
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .fold(f64::INFINITY, f64::min);
            (feature_column(f), min.is_finite().then(|| nm(min)))
        })
        .collect();
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
    )
    .ok();
    let finite = |v: Option<f64>| v.filter(|v| v.is_finite());
    let gpa = |v: Option<f64>| finite(v.map(|x| x * 1e-9));
    let c = severity.as_ref();
    // Table 4.4 windows of a variable profile.
    let table_4_4 = (!p.profile.is_constant()).then(|| {
        let t = h.table_4_4(&p.profile, lubricant);
        Table44Columns {
            first_lubricant_contact_ms: t.first_lubricant_contact.map(|t| t * 1e3),
            flying_fhm_percent: t.flying_fhm,
            jump_to_contact_bv_percent: t.jump_to_contact_bv,
            steady_contact_bv_percent: t.steady_contact_bv,
        }
    });
    ThreeDofCaseResult {
        pole_tip_mean_nm: nm(mean(pt)),
        pole_tip_std_nm: nm(std(pt)),
        bulge_spacing_mean_nm: nm(mean(bulge)),
        bulge_spacing_std_nm: nm(std(bulge)),
        bulge_vibration_percent: h.bulge_vibration(steady),
        roll_std_urad: std(roll) * 1e6,
        solid_contact_percent: 100.0 * solid_share,
        lubricant_contact_percent: 100.0 * lube_share,
        // Over the integrator's steps, not only the samples (an impact can fall between them).
        peak_contact_force_mN: h.peak_contact_force * 1e3,
        peak_lubricant_force_mN: h.peak_lubricant_force * 1e3,
        mean_contact_force_mN: mean(window(&h.contact_force, dt, steady)) * 1e3,
        mean_friction_mN: mean(window(&h.friction, dt, steady)) * 1e3,
        features_in_solid_contact: touched.join(" "),
        ab_lost_samples: h.ab_lost_samples,
        min_spacing_nm: MinSpacings(min_spacing),
        friction_coefficient: c.and_then(|c| finite(c.friction_coefficient_ratio_of_means)),
        friction_coefficient_mean_inst: c
            .and_then(|c| finite(c.friction_coefficient.as_ref().map(|s| s.mean))),
        mean_pressure_GPa: c.and_then(|c| gpa(c.mean_pressure_pa_ratio_of_means)),
        mean_pressure_GPa_mean_inst: c
            .and_then(|c| gpa(c.mean_pressure_pa.as_ref().map(|s| s.mean))),
        shear_traction_GPa: c.and_then(|c| gpa(c.shear_traction_pa_ratio_of_means)),
        shear_traction_GPa_mean_inst: c
            .and_then(|c| gpa(c.shear_traction_pa.as_ref().map(|s| s.mean))),
        table_4_4,
        case,
        steps: h.stats.accepted_steps,
    }
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
