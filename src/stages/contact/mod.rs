//! Contact stage: an interface (from the interface stage or a dissertation parameter set) →
//! the ISBL curves per unit nominal area against the solid separation h and h/σ, and the
//! verified force table the dynamics interpolate. HDF5 + PNG + a summary row.

use super::{FromConfig, StageContext, StageKind, StageOutput};
pub mod mtl;

use self::mtl::{MtlAnalysis, MtlKeys, MtlSettings};
use crate::artefacts::contact::ContactInputs;
use crate::artefacts::interface::upstream_summits;
use crate::contact::isbl::{
    surface_energy_at, FrictionLaw, IsblModel, IsblParams, SummitOffset, SurfaceEnergy,
};
use crate::contact::lookup::{IsblLookup, FORCE_TABLE_GRID};
use crate::contact::table::{ChannelError, ForceTable};
use crate::contact::ContactError;
use crate::core::config::{ConfigError, PipelineFile};

use crate::core::store::H5Out;
use crate::error::Result;
use crate::figures;
use crate::units::{
    parse_quantity, Area, Dimension, Length, PerArea, Pressure, Velocity, Viscosity,
};
use serde::Deserialize;
use serde_json::{json, Map, Value};
use std::path::Path;
use std::sync::Arc;

/// Bump when the numbers this stage produces change. contact-3: the key's `inputs` name the
/// summit offset and friction law as in the results (`none`, `junction_shear`), not in their
/// Rust Debug form (plain key params, docs/architecture.md).
pub const MODEL_VERSION: &str = "contact-3";

fn default_set() -> String {
    "improved_2dof".into()
}
fn default_offset() -> String {
    "none".into()
}
fn default_friction() -> String {
    "junction_shear".into()
}
fn default_h_min() -> f64 {
    FORCE_TABLE_GRID.h_star_min
}
fn default_h_max() -> f64 {
    FORCE_TABLE_GRID.h_star_max
}
fn default_step() -> f64 {
    FORCE_TABLE_GRID.step
}

/// A number (N/m), a string with a unit (`"60 mN/m"`) or `"variable"`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum SurfaceEnergyConfig {
    Number(f64),
    Text(String),
}

/// `[contact.NAME]` as written in `pipeline.toml` (every key is also a `hdi contact` option).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ContactConfig {
    /// Take σ, R, η from this `[interface.*]` instance.
    #[serde(default)]
    pub interface: Option<String>,
    /// The dissertation parameter set the other inputs start from: `initial_2dof`,
    /// `improved_2dof`, `three_dof`, `mtl_table_3_2`.
    #[serde(default = "default_set")]
    pub parameter_set: String,
    #[serde(default)]
    pub sigma: Option<Length>,
    #[serde(default)]
    pub r: Option<Length>,
    #[serde(default)]
    pub eta: Option<PerArea>,
    /// Hardness of the yielding body.
    #[serde(default)]
    pub hardness: Option<Pressure>,
    /// Young's modulus of both bodies.
    #[serde(default)]
    pub modulus: Option<Pressure>,
    /// Poisson ratio of both bodies.
    #[serde(default)]
    pub poisson: Option<f64>,
    /// Lennard-Jones equilibrium spacing ε.
    #[serde(default)]
    pub lj_spacing: Option<Length>,
    /// Total lubricant thickness t.
    #[serde(default)]
    pub lubricant_thickness: Option<Length>,
    /// Constant Δγ or `"variable"` (Δγ(s) = c1·exp(−c2·s) + c3).
    #[serde(default)]
    pub surface_energy: Option<SurfaceEnergyConfig>,
    /// `none` (d = h, σ_s = σ: the dissertation) or `mccool`.
    #[serde(default = "default_offset")]
    pub summit_offset: String,
    /// `junction_shear` (default), `seed_power_elastic` or `ke_static` (docs/contact.md,
    /// "Friction").
    #[serde(default = "default_friction")]
    pub friction_law: String,
    /// Output curves from h* = h_star_min to h_star_max in steps of `step` (also the table's
    /// grid step).
    #[serde(default = "default_h_min")]
    pub h_star_min: f64,
    #[serde(default = "default_h_max")]
    pub h_star_max: f64,
    #[serde(default = "default_step")]
    pub step: f64,
    /// Add the molecularly-thin-lubricant law on top of the ISBL solid: `reference`,
    /// `humidity_temperature`, `more_bonding`, `larger_gyration_radius` (Fig. 3.22 cases).
    #[serde(default)]
    pub lubricant: Option<String>,
    /// Nominal area the solid forces are scaled to for the MTL curves (default 2500 µm²).
    #[serde(default)]
    pub nominal_area: Option<Area>,
    /// Sliding speed U of the MTL law (default 30 m/s).
    #[serde(default)]
    pub sliding_speed: Option<Velocity>,
    /// Limiting viscosity μ0 (default: the lubricant case's).
    #[serde(default)]
    pub lubricant_viscosity: Option<Viscosity>,
    /// Minimum liquid gap κ = radius of gyration (default: the lubricant case's).
    #[serde(default)]
    pub gyration_radius: Option<Length>,
}

impl ContactConfig {
    /// Every key at its default (what `hdi contact` and the tests start from).
    pub fn defaults() -> Self {
        // Every field has a serde default, so the empty table always parses (not user input).
        toml::from_str("").expect("every [contact] key has a default")
    }
}

/// Validated parameters: the model inputs (σ, R, η possibly still to come from upstream).
#[derive(Debug, Clone, PartialEq)]
pub struct ContactParams {
    pub interface: Option<String>,
    pub parameter_set: String,
    pub params: IsblParams,
    pub h_star_min: f64,
    pub h_star_max: f64,
    pub step: f64,
    /// The lubricant model, when `lubricant` is set.
    pub mtl: Option<MtlSettings>,
}

/// A dissertation parameter set by name.
pub fn parameter_set(name: &str) -> Option<IsblParams> {
    Some(match name {
        "initial_2dof" => IsblParams::initial_2dof(),
        "improved_2dof" => IsblParams::improved_2dof(),
        "three_dof" => IsblParams::three_dof(),
        "mtl_table_3_2" => IsblParams::mtl_table_3_2(),
        _ => return None,
    })
}

/// Check a `[contact]` table (or `hdi contact`'s options) key by key.
pub fn check(
    cfg: &ContactConfig,
) -> std::result::Result<ContactParams, crate::core::config::KeyError> {
    let bad = |k: &str, m: String| Err(crate::core::config::KeyError::new(k, m));
    let Some(mut p) = parameter_set(&cfg.parameter_set) else {
        return bad(
            "parameter_set",
            format!(
                "unknown set `{}` (initial_2dof, improved_2dof, three_dof, mtl_table_3_2)",
                cfg.parameter_set
            ),
        );
    };
    if cfg.interface.is_some() && (cfg.sigma.is_some() || cfg.r.is_some() || cfg.eta.is_some()) {
        return bad(
            "interface",
            "σ, R, η come from the interface: drop `sigma`/`r`/`eta` or the `interface` key".into(),
        );
    }
    if let Some(Length(v)) = cfg.sigma {
        p.sigma = v;
    }
    if let Some(Length(v)) = cfg.r {
        p.summit_radius = v;
    }
    if let Some(PerArea(v)) = cfg.eta {
        p.summit_density = v;
    }
    if let Some(Pressure(v)) = cfg.hardness {
        p.hardness = v;
    }
    if let Some(Pressure(v)) = cfg.modulus {
        p.slider_modulus = v;
        p.disk_modulus = v;
    }
    if let Some(v) = cfg.poisson {
        p.slider_poisson = v;
        p.disk_poisson = v;
        p.yielding_poisson = v;
    }
    if let Some(Length(v)) = cfg.lj_spacing {
        p.lj_spacing = v;
    }
    if let Some(Length(v)) = cfg.lubricant_thickness {
        p.lubricant_thickness = v;
    }
    match &cfg.surface_energy {
        None => {}
        Some(SurfaceEnergyConfig::Number(v)) => {
            p.surface_energy = SurfaceEnergy::Constant { delta_gamma: *v }
        }
        Some(SurfaceEnergyConfig::Text(t)) if t == "variable" => {
            p.surface_energy = SurfaceEnergy::seed_variable()
        }
        Some(SurfaceEnergyConfig::Text(t)) => match parse_quantity(t, Dimension::SurfaceEnergy) {
            Ok(v) => p.surface_energy = SurfaceEnergy::Constant { delta_gamma: v },
            Err(e) => return bad("surface_energy", format!("{e}, or \"variable\"")),
        },
    }
    p.summit_offset = match cfg.summit_offset.as_str() {
        "none" => SummitOffset::None,
        "mccool" => SummitOffset::McCool,
        o => return bad("summit_offset", format!("unknown `{o}` (none, mccool)")),
    };
    p.friction_law = match cfg.friction_law.as_str() {
        "junction_shear" => FrictionLaw::JunctionShear,
        "seed_power_elastic" => FrictionLaw::SeedPowerElastic,
        "ke_static" => FrictionLaw::KeStatic,
        o => {
            return bad(
                "friction_law",
                format!("unknown `{o}` (junction_shear, seed_power_elastic, ke_static)"),
            )
        }
    };
    if !(cfg.h_star_min.is_finite() && cfg.h_star_max.is_finite())
        || cfg.h_star_min < -4.0
        || cfg.h_star_max > 20.0
        || cfg.h_star_max <= cfg.h_star_min
    {
        return bad(
            "h_star_max",
            format!(
                "range [{}, {}] is out of range: need −4 ≤ h_star_min < h_star_max ≤ 20",
                cfg.h_star_min, cfg.h_star_max
            ),
        );
    }
    if !(cfg.step.is_finite() && cfg.step >= 0.005 && cfg.step <= 0.5) {
        return bad(
            "step",
            format!("{} is out of range: 0.005 ≤ step ≤ 0.5 (in h/σ)", cfg.step),
        );
    }
    if cfg.interface.is_none() {
        p.validate().map_err(|e| match e {
            ContactError::Parameter { name, .. } => {
                crate::core::config::KeyError::new(name, e.to_string())
            }
            other => crate::core::config::KeyError::new("parameter_set", other.to_string()),
        })?;
    }
    let mtl = mtl::resolve(
        &MtlKeys {
            lubricant: cfg.lubricant.clone(),
            nominal_area: cfg.nominal_area,
            sliding_speed: cfg.sliding_speed,
            lubricant_viscosity: cfg.lubricant_viscosity,
            gyration_radius: cfg.gyration_radius,
        },
        &p,
    )?;
    Ok(ContactParams {
        interface: cfg.interface.clone(),
        parameter_set: cfg.parameter_set.clone(),
        params: p,
        h_star_min: cfg.h_star_min,
        h_star_max: cfg.h_star_max,
        step: cfg.step,
        mtl,
    })
}

/// The interface parameters as downstream stages read them (`inputs` in the result).
fn params_json(p: &IsblParams) -> Value {
    ContactInputs::from(p).to_json()
}

impl ContactParams {
    pub fn canonical(&self) -> Value {
        json!({
            "interface": self.interface,
            "parameter_set": self.parameter_set,
            // With an interface, σ/R/η come from upstream (its key is in the fingerprint).
            "inputs": ContactInputs::from(&self.params).to_json(),
            "h_star_min": self.h_star_min,
            "h_star_max": self.h_star_max,
            "step": self.step,
            "lubricant": self.mtl.map(|m| m.canonical()),
        })
    }
}

/// The computed stage: model, curves on the output grid, the verified table, and the
/// lubricant curves when a lubricant is configured.
pub struct ContactAnalysis {
    pub model: IsblModel,
    pub h_star: Vec<f64>,
    pub points: Vec<crate::contact::isbl::IsblPoint>,
    pub lookup: Arc<IsblLookup>,
    pub mtl: Option<MtlAnalysis>,
}

impl ContactAnalysis {
    pub fn table(&self) -> &ForceTable {
        self.lookup.table()
    }
    pub fn table_error(&self) -> &[ChannelError] {
        self.lookup.verified_error()
    }
}

/// Build the model, the curves and the table (the table covers the range docs/contact.md states
/// h* ∈ [−4, 3 + t/σ + 10] or the output range, whichever is wider).
pub fn analyse(params: &IsblParams, c: &ContactParams) -> Result<ContactAnalysis> {
    let model = IsblModel::new(*params)?;
    let n = ((c.h_star_max - c.h_star_min) / c.step).round() as usize + 1;
    let h_star: Vec<f64> = (0..n).map(|i| c.h_star_min + i as f64 * c.step).collect();
    use rayon::prelude::*;
    let points = h_star
        .par_iter()
        .map(|&x| model.at(x * params.sigma))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let lookup = Arc::new(IsblLookup::build(
        model,
        c.step,
        c.h_star_min,
        c.h_star_max,
    )?);
    let mtl = match &c.mtl {
        Some(settings) => Some(mtl::analyse(settings, &lookup)?),
        None => None,
    };
    Ok(ContactAnalysis {
        model,
        h_star,
        points,
        lookup,
        mtl,
    })
}

pub fn summary_row(a: &ContactAnalysis, c: &ContactParams) -> Map<String, Value> {
    let p = a.model.params();
    let d = a.model.derived();
    let at3 = a.model.at(3.0 * p.sigma).ok();
    let mut m = Map::new();
    m.insert("parameter_set".into(), json!(c.parameter_set));
    m.insert("interface".into(), json!(c.interface));
    m.insert("sigma_nm".into(), json!(p.sigma * 1e9));
    m.insert("R_um".into(), json!(p.summit_radius * 1e6));
    m.insert("eta_per_um2".into(), json!(p.summit_density * 1e-12));
    m.insert("beta".into(), json!(d.beta));
    m.insert("E_star_GPa".into(), json!(d.composite_modulus / 1e9));
    m.insert("omega_c_nm".into(), json!(d.critical_interference * 1e9));
    m.insert("psi".into(), json!(d.plasticity_index));
    m.insert(
        "P_at_3sigma_Pa".into(),
        json!(at3.map(|q| q.contact_pressure)),
    );
    m.insert("F_s_at_3sigma_Pa".into(), json!(at3.map(|q| q.adhesion)));
    let worst = a
        .table_error()
        .iter()
        .map(|e| e.max_rel)
        .fold(0.0, f64::max);
    m.insert("table_max_rel_error".into(), json!(worst));
    match &a.mtl {
        Some(mtl) => m.extend(mtl.landmarks()),
        None => {
            m.insert("lubricant".into(), Value::Null);
        }
    }
    m
}

pub fn report_json(a: &ContactAnalysis, c: &ContactParams) -> Value {
    let d = a.model.derived();
    json!({
        "parameter_set": c.parameter_set,
        "interface": c.interface,
        "inputs": params_json(a.model.params()),
        // Units in the key names (docs/json.md); the curves are per unit nominal area.
        "derived": {
            "E_star_Pa": d.composite_modulus, "K": d.k_factor,
            "omega_c_m": d.critical_interference, "L_c_N": d.critical_load,
            "A_c_m2": d.critical_area, "beta": d.beta,
            "psi": d.plasticity_index, "psi_KE": d.plasticity_index_ke,
            "y_s_m": d.summit_offset, "sigma_s_m": d.summit_sigma,
        },
        "curves": a.h_star.iter().zip(&a.points).map(|(x, p)| json!({
            "h_star": x, "h_m": p.separation, "P_Pa": p.contact_pressure,
            "k_c_Pa_per_m": p.contact_stiffness, "A_r_fraction": p.real_area_fraction,
            "Q_Pa": p.friction_stress, "F_s_Pa": p.adhesion, "n_c_per_m2": p.contacts_per_area,
        })).collect::<Vec<_>>(),
        "table": {
            "h_star_range": a.table().range(), "h_star_step": a.table().step(),
            "max_rel_error": a.table_error().iter().map(|e| (e.name.clone(), json!(e.max_rel))).collect::<Map<_, _>>(),
        },
        "mtl": a.mtl.as_ref().map(|m| m.report()),
    })
}

pub fn write_outputs(
    a: &ContactAnalysis,
    c: &ContactParams,
    h5_path: &Path,
    plot_dir: Option<&Path>,
    cache_key: &str,
    inputs: &Value,
) -> Result<()> {
    let out = H5Out::create(h5_path)?;
    out.root_attributes("contact", cache_key, &c.canonical(), inputs, "contact")?;
    let entry = out.group("contact", Some("NXentry"))?;
    out.attr_str(&entry, "default", "isbl")?;
    write_isbl(&out, a)?;
    write_derived(&out, a)?;
    write_table(&out, a)?;
    out.write_string(&entry, "inputs", &params_json(a.model.params()).to_string())?;
    if let Some(mtl) = &a.mtl {
        mtl.write_hdf5(&out)?;
    }
    out.finish()?;

    if let Some(dir) = plot_dir {
        write_figures(a, c, dir)?;
    }
    Ok(())
}

/// `contact/isbl`: the ISBL curves per unit nominal area against h/σ and h.
fn write_isbl(out: &H5Out, a: &ContactAnalysis) -> Result<()> {
    let g = out.group("contact/isbl", Some("NXdata"))?;
    out.attr_str(&g, "signal", "P")?;
    out.attr_str_list(&g, "auxiliary_signals", &["Q", "F_s"])?;
    out.attr_str_list(&g, "axes", &["h_star"])?;
    let col = |f: fn(&crate::contact::isbl::IsblPoint) -> f64| -> Vec<f64> {
        a.points.iter().map(f).collect()
    };
    out.write_1d(&g, "h_star", &a.h_star, "1", "separation h/σ")?;
    out.write_1d(
        &g,
        "h",
        &col(|p| p.separation),
        "m",
        "solid separation h (mean plane of surface heights)",
    )?;
    for (name, f, unit, ln) in [
        (
            "P",
            (|p| p.contact_pressure) as fn(&crate::contact::isbl::IsblPoint) -> f64,
            "Pa",
            "contact force per unit nominal area",
        ),
        (
            "k_c",
            |p| p.contact_stiffness,
            "Pa/m",
            "contact stiffness −dP/dh per unit nominal area",
        ),
        (
            "A_r_fraction",
            |p| p.real_area_fraction,
            "1",
            "real contact area / nominal area",
        ),
        (
            "Q",
            |p| p.friction_stress,
            "Pa",
            "static friction per unit nominal area",
        ),
        (
            "k_fr",
            |p| p.friction_stiffness,
            "Pa/m",
            "−dQ/dh per unit nominal area",
        ),
        (
            "F_s",
            |p| p.adhesion,
            "Pa",
            "adhesion per unit nominal area",
        ),
        (
            "F_nc",
            |p| p.adhesion_non_contacting,
            "Pa",
            "adhesion of non-contacting summits",
        ),
        (
            "F_lc",
            |p| p.adhesion_lubricant,
            "Pa",
            "adhesion of lubricant-contacting summits",
        ),
        (
            "F_sc",
            |p| p.adhesion_solid,
            "Pa",
            "adhesion of solid-contacting summits",
        ),
        ("dF_s_dh", |p| p.adhesion_gradient, "Pa/m", "dF_s/dh"),
        (
            "n_c",
            |p| p.contacts_per_area,
            "m^-2",
            "contacting summits per unit nominal area",
        ),
    ] {
        out.write_1d(&g, name, &col(f), unit, ln)?;
    }
    Ok(())
}

/// `contact/derived`: the interface's derived constants.
fn write_derived(out: &H5Out, a: &ContactAnalysis) -> Result<()> {
    let d = a.model.derived();
    let g = out.group("contact/derived", None)?;
    for (name, v, u, ln) in [
        ("E_star", d.composite_modulus, "Pa", "composite modulus"),
        (
            "K",
            d.k_factor,
            "1",
            "Kogut–Etsion hardness factor 0.454 + 0.41ν",
        ),
        (
            "omega_c",
            d.critical_interference,
            "m",
            "critical interference",
        ),
        ("L_c", d.critical_load, "N", "critical load"),
        ("A_c", d.critical_area, "m^2", "critical area"),
        ("beta", d.beta, "1", "σRη"),
        (
            "psi",
            d.plasticity_index,
            "1",
            "plasticity index (E*/H)√(σ/R)",
        ),
        (
            "psi_KE",
            d.plasticity_index_ke,
            "1",
            "KE plasticity index √(σ/ω_c)",
        ),
        (
            "y_s",
            d.summit_offset,
            "m",
            "summit mean plane above the surface mean plane",
        ),
        (
            "sigma_s",
            d.summit_sigma,
            "m",
            "summit height standard deviation",
        ),
    ] {
        out.write_scalar(&g, name, v, u, ln)?;
    }
    Ok(())
}

/// `contact/table`: the force table's range, spacing and interpolation error per channel.
fn write_table(out: &H5Out, a: &ContactAnalysis) -> Result<()> {
    let g = out.group("contact/table", None)?;
    let (lo, hi) = a.table().range();
    out.write_scalar(&g, "h_star_min", lo, "1", "first node")?;
    out.write_scalar(&g, "h_star_max", hi, "1", "last node")?;
    out.write_scalar(&g, "step", a.table().step(), "1", "node spacing in h/σ")?;
    let names: Vec<&str> = a.table_error().iter().map(|e| e.name.as_str()).collect();
    out.attr_str_list(&g, "channels", &names)?;
    let errs: Vec<f64> = a.table_error().iter().map(|e| e.max_rel).collect();
    out.write_1d(
        &g,
        "max_rel_error",
        &errs,
        "1",
        "interpolation error vs direct evaluation (midpoints and quarter points), per channel",
    )?;
    Ok(())
}

/// ISBL forces, real area and stiffness, variable surface energy (Fig. 3.18), and the MTL
/// figures when that analysis ran.
fn write_figures(a: &ContactAnalysis, c: &ContactParams, dir: &Path) -> Result<()> {
    let series = |f: fn(&crate::contact::isbl::IsblPoint) -> f64| -> Vec<(f64, f64)> {
        a.h_star
            .iter()
            .zip(&a.points)
            .map(|(x, p)| (*x, f(p)))
            .collect()
    };
    figures::semilogy_png(
        &dir.join("isbl_forces.png"),
        &format!(
            "ISBL per unit nominal area ({}, σ = {:.2} nm)",
            c.parameter_set,
            a.model.params().sigma * 1e9
        ),
        "h/σ",
        "Pa",
        &[
            ("contact P", series(|p| p.contact_pressure)),
            ("static friction Q", series(|p| p.friction_stress)),
            ("adhesion F_s", series(|p| p.adhesion)),
        ],
        &[],
    )?;
    figures::semilogy_png(
        &dir.join("isbl_area_stiffness.png"),
        "Real area fraction and contact stiffness",
        "h/σ",
        "A_r/A_n (1), k_c (Pa/nm)",
        &[
            ("A_r/A_n", series(|p| p.real_area_fraction)),
            ("k_c (Pa/nm)", series(|p| p.contact_stiffness * 1e-9)),
        ],
        &[],
    )?;
    let params = a.model.params();
    if matches!(params.surface_energy, SurfaceEnergy::Variable { .. }) {
        // Fig. 3.18: Δγ against the (dimensionless) lubricant gap, held at its maximum
        // below ε, and the total adhesion it produces.
        let energy: Vec<(f64, f64)> = a
            .h_star
            .iter()
            .filter(|x| **x >= 0.0)
            .map(|x| (*x, surface_energy_at(params, x * params.sigma) * 1e3))
            .collect();
        figures::stacked_png(
            &dir.join("surface_energy.png"),
            "Variable surface energy and total adhesion — Fig. 3.18 (shaded: gap < ε)",
            "h/σ",
            &[
                ("Δγ (mN/m) vs gap/σ", energy),
                ("adhesion F_s (Pa)", series(|p| p.adhesion)),
            ],
            &[(0.0, params.lj_spacing / params.sigma)],
        )?;
    }
    if let Some(mtl) = &a.mtl {
        mtl.plots(dir)?;
    }
    Ok(())
}

/// A `[contact.NAME]` instance.
pub struct ContactStage {
    pub name: String,
    pub params: ContactParams,
}

impl FromConfig for ContactStage {
    type Config = ContactConfig;

    fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &ContactConfig,
    ) -> std::result::Result<Self, ConfigError> {
        let params = check(cfg).map_err(|e| e.locate(file, "contact", name))?;
        if let Some(i) = &cfg.interface {
            if !file.has_instance("interface", i) {
                return Err(file.error(
                    "contact",
                    name,
                    "interface",
                    format!("no [interface.{i}] in this file"),
                ));
            }
        }
        Ok(Self {
            name: name.to_string(),
            params,
        })
    }
}

impl StageKind for ContactStage {
    const KIND: &'static str = "contact";
    const MODEL_VERSION: &'static str = MODEL_VERSION;

    fn params(&self) -> Value {
        self.params.canonical()
    }
    fn upstream(&self) -> Vec<String> {
        self.params.interface.iter().cloned().collect()
    }
    fn run(&self, ctx: &StageContext) -> Result<StageOutput> {
        let mut p = self.params.params;
        if let Some(i) = &self.params.interface {
            [p.sigma, p.summit_radius, p.summit_density] = upstream_summits(&ctx.upstream, i)?;
        }
        ctx.progress.set_message("ISBL curves and force table");
        let a = analyse(&p, &self.params)?;
        let inputs = serde_json::to_value(&ctx.fingerprint.inputs).unwrap_or(Value::Null);
        write_outputs(
            &a,
            &self.params,
            &ctx.out_dir.join("contact.h5"),
            Some(ctx.out_dir),
            ctx.key,
            &inputs,
        )?;
        let mut result = report_json(&a, &self.params);
        if let Value::Object(m) = &mut result {
            m.insert("h5".into(), json!("contact.h5"));
        }
        Ok(StageOutput {
            result,
            summary_row: Some(summary_row(&a, &self.params)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn force_table_matches_direct_evaluation_across_the_regime_boundaries() {
        // Acceptance: ≤ 1e-4 relative everywhere the curves matter, no NaN or jump at 3σ,
        // 3σ + t and the table's ends (measured: ≤ 1.1e-8, F_s the worst).
        let cfg = ContactConfig::defaults();
        let c = check(&cfg).unwrap();
        let a = analyse(&c.params, &c).unwrap();
        for e in a.table_error() {
            assert!(e.max_rel < 1e-4, "{e:?}");
        }
        let sigma = c.params.sigma;
        let t = c.params.lubricant_thickness / sigma;
        for x in [3.0, 3.0 + t, 0.0, -3.5, 10.0] {
            for ch in 0..5 {
                let below = a.table().eval(ch, x - 1e-7).unwrap();
                let above = a.table().eval(ch, x + 1e-7).unwrap();
                assert!(below.is_finite() && above.is_finite());
                assert!(((below - above) / below).abs() < 1e-5, "{ch} at {x}");
            }
        }
        // P, A_r, Q fall and F_s falls with separation.
        for ch in [0, 2, 3, 4] {
            let mut prev = f64::INFINITY;
            for k in 0..2000 {
                let y = a.table().eval(ch, -3.9 + k as f64 * 0.0087).unwrap();
                assert!(y <= prev, "channel {ch} at step {k}");
                prev = y;
            }
        }
    }

    #[test]
    fn isbl_params_round_trip_through_the_result_json() {
        for p in [IsblParams::improved_2dof(), IsblParams::mtl_table_3_2()] {
            let c = ContactParams {
                params: p,
                ..check(&ContactConfig::defaults()).unwrap()
            };
            let result = report_json(&analyse(&p, &c).unwrap(), &c);
            let back = ContactInputs::from_json(&result["inputs"]).unwrap();
            assert_eq!(back.params().unwrap(), p);
        }
    }

    #[test]
    fn bad_keys_name_themselves() {
        let mut cfg = ContactConfig::defaults();
        cfg.parameter_set = "nope".into();
        assert_eq!(check(&cfg).unwrap_err().key, "parameter_set");
        let mut cfg = ContactConfig::defaults();
        cfg.hardness = Some(Pressure(-1.0));
        assert_eq!(check(&cfg).unwrap_err().key, "hardness");
        let mut cfg = ContactConfig::defaults();
        cfg.step = 0.0;
        assert_eq!(check(&cfg).unwrap_err().key, "step");
        let mut cfg = ContactConfig::defaults();
        cfg.surface_energy = Some(SurfaceEnergyConfig::Text("lots".into()));
        assert_eq!(check(&cfg).unwrap_err().key, "surface_energy");
    }
}
