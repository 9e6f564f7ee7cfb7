//! Contact stage: an interface (from the interface stage or a dissertation parameter set) →
//! the ISBL curves per unit nominal area against the solid separation h and h/σ, and the
//! verified force table the dynamics interpolate. HDF5 + PNG + a summary row.

use super::{FromConfig, Output, StageContext, StageKind};
pub mod mtl;

use self::mtl::{MtlAnalysis, MtlKeys, MtlSettings};
use crate::artefacts::contact::ContactInputs;
use crate::artefacts::interface::{upstream_summits, InterfaceSurfaces};
use crate::artefacts::surface::upstream_summit_heights;
use crate::contact::isbl::summits::{fit_two_point, TwoPointTarget, FIG_2_11_NOMINAL_AREA};
use crate::contact::isbl::{FrictionLaw, IsblModel, IsblParams, SummitDistribution, SurfaceEnergy};
use crate::contact::lookup::{IsblLookup, FORCE_TABLE_GRID};
use crate::contact::table::{ChannelError, ForceTable};
use crate::contact::ContactError;
use crate::core::config::{ConfigError, PipelineFile};

use crate::error::Result;
use crate::units::{
    parse_quantity, Area, Dimension, Length, PerArea, Pressure, Velocity, Viscosity,
};
use serde::Deserialize;
use serde_json::{json, Value};
use std::sync::Arc;

mod output;
pub use crate::artefacts::contact::SummitOrigin;
pub use output::{
    write_outputs, ContactReport, ContactRow, ContactStageResult, ForceTableReport, IsblCurvePoint,
    IsblDerived, LubricantColumns, PerChannel,
};

/// Bump when the numbers this stage produces change. contact-3: the key's `inputs` name the
/// summit offset and friction law as in the results (`none`, `junction_shear`), not in their
/// Rust Debug form (plain key params, docs/architecture.md).
pub const MODEL_VERSION: &str = "contact-3";

fn default_set() -> String {
    "improved_2dof".into()
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
    /// The older name of `summit_distribution`: `none` (= `surface`) or `mccool`.
    #[serde(default)]
    pub summit_offset: Option<String>,
    /// The Gaussian summit-height distribution (docs/model-form.md, "Summit heights"):
    /// `surface` (σ_s = σ, y_s = 0: the dissertation; default), `mccool`, `fig_2_11` (σ_s and
    /// y_s fitted to Fig. 2.11's two numbers) or `measured` (the surfaces' summits).
    #[serde(default)]
    pub summit_distribution: Option<String>,
    /// `fig_2_11`: the nominal area of Fig. 2.11's 7.30 µN (not stated; default 55 µm²).
    #[serde(default)]
    pub fig_2_11_nominal_area: Option<Area>,
    /// `measured`: the `[surface.*]` or `[interface.*]` instance whose summits are taken
    /// (default: this contact's `interface`).
    #[serde(default)]
    pub summit_source: Option<String>,
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
    /// How the summit distribution is obtained when it is not one of `params.summits`' fixed
    /// forms.
    pub summits: SummitSpec,
}

/// A summit distribution that needs more than the parameters: a fit or a measurement.
#[derive(Debug, Clone, PartialEq)]
pub enum SummitSpec {
    /// `surface` or `mccool`: `params.summits` is the distribution.
    Fixed,
    /// Fitted to Fig. 2.11's two numbers with the force on `nominal_area` [m²].
    Fig211 { nominal_area: f64 },
    /// The summits measured on a surface, or on an interface's two surfaces.
    Measured(SummitSource),
}

/// Where `measured` summits come from.
#[derive(Debug, Clone, PartialEq)]
pub enum SummitSource {
    /// Named in `summit_source`; its kind is known once the pipeline file is read.
    Unresolved(String),
    Surface(String),
    /// An interface instance and its two surfaces.
    Interface {
        name: String,
        surfaces: Vec<String>,
    },
}

impl SummitSource {
    fn name(&self) -> &str {
        match self {
            SummitSource::Unresolved(n) | SummitSource::Surface(n) => n,
            SummitSource::Interface { name, .. } => name,
        }
    }

    /// The surface instances whose results hold the summits.
    fn surfaces(&self) -> Vec<String> {
        match self {
            SummitSource::Unresolved(_) => Vec::new(),
            SummitSource::Surface(n) => vec![n.clone()],
            SummitSource::Interface { surfaces, .. } => surfaces.clone(),
        }
    }
}

impl SummitSpec {
    /// The `[contact] summit_distribution` name.
    pub fn name(&self, fixed: SummitDistribution) -> &'static str {
        match (self, fixed) {
            (SummitSpec::Fig211 { .. }, _) => "fig_2_11",
            (SummitSpec::Measured(_), _) => "measured",
            (SummitSpec::Fixed, SummitDistribution::McCool) => "mccool",
            (SummitSpec::Fixed, _) => "surface",
        }
    }

    /// Its part of the cache key (`None` for a fixed distribution, which the `inputs` name).
    fn canonical(&self) -> Option<Value> {
        match self {
            SummitSpec::Fixed => None,
            SummitSpec::Fig211 { nominal_area } => Some(json!({
                "kind": "fig_2_11", "nominal_area_m2": nominal_area,
                "h_star": 3.0, "force_N": 7.30e-6, "h_star_ref": 2.5, "ratio": 0.03,
            })),
            SummitSpec::Measured(src) => Some(json!({
                "kind": "measured", "source": src.name(), "surfaces": src.surfaces(),
            })),
        }
    }
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
    let (summits, spec) = summit_keys(cfg)?;
    p.summits = summits;
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
        summits: spec,
    })
}

/// `summit_distribution` (or its older name `summit_offset`) with `fig_2_11_nominal_area` and
/// `summit_source`: the fixed distribution (`Surface` for a fit or a measurement, which replace
/// it when the stage runs) and how the others are obtained.
fn summit_keys(
    cfg: &ContactConfig,
) -> std::result::Result<(SummitDistribution, SummitSpec), crate::core::config::KeyError> {
    let bad = |k: &str, m: String| Err(crate::core::config::KeyError::new(k, m));
    let legacy = match cfg.summit_offset.as_deref() {
        None => None,
        Some("none") => Some("surface"),
        Some("mccool") => Some("mccool"),
        Some(o) => return bad("summit_offset", format!("unknown `{o}` (none, mccool)")),
    };
    let name = match (cfg.summit_distribution.as_deref(), legacy) {
        (Some(d), Some(l)) if d != l => {
            return bad(
                "summit_offset",
                format!(
                    "`summit_offset` is the older name of `summit_distribution` and says `{l}` \
                     where `summit_distribution` says `{d}`: keep one"
                ),
            )
        }
        (Some(d), _) => d,
        (None, Some(l)) => l,
        (None, None) => "surface",
    };
    if cfg.fig_2_11_nominal_area.is_some() && name != "fig_2_11" {
        return bad(
            "fig_2_11_nominal_area",
            format!("only for summit_distribution = \"fig_2_11\" (here `{name}`)"),
        );
    }
    if cfg.summit_source.is_some() && name != "measured" {
        return bad(
            "summit_source",
            format!("only for summit_distribution = \"measured\" (here `{name}`)"),
        );
    }
    Ok(match name {
        "surface" => (SummitDistribution::Surface, SummitSpec::Fixed),
        "mccool" => (SummitDistribution::McCool, SummitSpec::Fixed),
        "fig_2_11" => {
            let nominal_area = cfg
                .fig_2_11_nominal_area
                .map_or(FIG_2_11_NOMINAL_AREA, |Area(a)| a);
            if !(nominal_area.is_finite() && nominal_area > 0.0) {
                return bad(
                    "fig_2_11_nominal_area",
                    format!("{nominal_area} m² is out of range: must be > 0"),
                );
            }
            (
                SummitDistribution::Surface,
                SummitSpec::Fig211 { nominal_area },
            )
        }
        "measured" => match cfg.summit_source.as_ref().or(cfg.interface.as_ref()) {
            Some(src) => (
                SummitDistribution::Surface,
                SummitSpec::Measured(SummitSource::Unresolved(src.clone())),
            ),
            None => {
                return bad(
                    "summit_distribution",
                    "\"measured\" needs the [surface.*] or [interface.*] instance whose \
                     summits it takes (summit_source, or this contact's interface; a pipeline, \
                     not `hdi contact`)"
                        .into(),
                )
            }
        },
        o => {
            return bad(
                "summit_distribution",
                format!("unknown `{o}` (surface, mccool, fig_2_11, measured)"),
            )
        }
    })
}

impl ContactParams {
    pub fn canonical(&self) -> Value {
        let mut inputs = ContactInputs::from(&self.params).to_json();
        let mut v = json!({
            "interface": self.interface,
            "parameter_set": self.parameter_set,
            // With an interface, σ/R/η come from upstream (its key is in the fingerprint).
            "inputs": inputs,
            "h_star_min": self.h_star_min,
            "h_star_max": self.h_star_max,
            "step": self.step,
            "lubricant": self.mtl.map(|m| m.canonical()),
        });
        // A fitted or measured distribution: named in the inputs and stated beside them (with
        // the fixed ones the key is as it was before the switch existed).
        if let (Some(spec), Value::Object(m)) = (self.summits.canonical(), &mut v) {
            inputs["summit_offset"] = json!(self.summits.name(self.params.summits));
            m.insert("inputs".into(), inputs);
            m.insert("summit_distribution".into(), spec);
        }
        v
    }
}

/// The summit distribution the model uses: `params.summits` for a fixed one, the fit for
/// `fig_2_11`, the measured one (`measured`, from the stage's upstream) for `measured`.
pub fn resolve_summits(
    params: &IsblParams,
    c: &ContactParams,
    measured: Option<SummitOrigin>,
) -> Result<(IsblParams, Option<SummitOrigin>)> {
    let origin = match (&c.summits, measured) {
        (SummitSpec::Fixed, _) => return Ok((*params, None)),
        (SummitSpec::Fig211 { nominal_area }, _) => SummitOrigin::Fig211 {
            nominal_area: *nominal_area,
            fit: fit_two_point(params, &TwoPointTarget::fig_2_11(*nominal_area))?,
        },
        (SummitSpec::Measured(_), Some(m @ SummitOrigin::Measured { .. })) => m,
        (SummitSpec::Measured(src), _) => {
            return Err(crate::error::Error::MeasuredSummitsOutsidePipeline {
                surface: src.name().to_string(),
            })
        }
    };
    let (sigma_ratio, offset_ratio) = origin.ratios();
    let resolved = IsblParams {
        summits: SummitDistribution::Given {
            sigma_ratio,
            offset_ratio,
        },
        ..*params
    };
    Ok((resolved, Some(origin)))
}

/// The computed stage: model, curves on the output grid, the verified table, and the
/// lubricant curves when a lubricant is configured.
pub struct ContactAnalysis {
    pub model: IsblModel,
    /// How a fitted or measured summit distribution was obtained.
    pub summit_origin: Option<SummitOrigin>,
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
/// `measured`: the upstream summits of a `measured` distribution.
pub fn analyse(
    params: &IsblParams,
    c: &ContactParams,
    measured: Option<SummitOrigin>,
) -> Result<ContactAnalysis> {
    let (resolved, summit_origin) = resolve_summits(params, c, measured)?;
    let params = &resolved;
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
        summit_origin,
        h_star,
        points,
        lookup,
        mtl,
    })
}

/// One row of the tidy contact table (unit suffixes in the names).
pub fn summary_row(a: &ContactAnalysis, c: &ContactParams) -> ContactRow {
    let p = a.model.params();
    let d = a.model.derived();
    let at3 = a.model.at(3.0 * p.sigma).ok();
    let worst = a
        .table_error()
        .iter()
        .map(|e| e.max_rel)
        .fold(0.0, f64::max);
    ContactRow {
        parameter_set: c.parameter_set.clone(),
        interface: c.interface.clone(),
        sigma_nm: p.sigma * 1e9,
        R_um: p.summit_radius * 1e6,
        eta_per_um2: p.summit_density * 1e-12,
        beta: d.beta,
        E_star_GPa: d.composite_modulus / 1e9,
        omega_c_nm: d.critical_interference * 1e9,
        psi: d.plasticity_index,
        P_at_3sigma_Pa: at3.map(|q| q.contact_pressure),
        F_s_at_3sigma_Pa: at3.map(|q| q.adhesion),
        table_max_rel_error: worst,
        lubricant: match &a.mtl {
            Some(mtl) => LubricantColumns::Landmarks(mtl.landmarks()),
            None => LubricantColumns::None { lubricant: None },
        },
    }
}

/// What `hdi contact --json` prints and the stage's `result.json` holds (without its `h5`).
pub fn report_json(a: &ContactAnalysis, c: &ContactParams) -> ContactReport {
    let d = a.model.derived();
    ContactReport {
        parameter_set: c.parameter_set.clone(),
        interface: c.interface.clone(),
        inputs: ContactInputs::from(a.model.params()),
        derived: IsblDerived {
            E_star_Pa: d.composite_modulus,
            K: d.k_factor,
            omega_c_m: d.critical_interference,
            L_c_N: d.critical_load,
            A_c_m2: d.critical_area,
            beta: d.beta,
            psi: d.plasticity_index,
            psi_KE: d.plasticity_index_ke,
            y_s_m: d.summit_offset,
            sigma_s_m: d.summit_sigma,
        },
        curves: a
            .h_star
            .iter()
            .zip(&a.points)
            .map(|(x, p)| IsblCurvePoint {
                h_star: *x,
                h_m: p.separation,
                P_Pa: p.contact_pressure,
                k_c_Pa_per_m: p.contact_stiffness,
                A_r_fraction: p.real_area_fraction,
                Q_Pa: p.friction_stress,
                F_s_Pa: p.adhesion,
                n_c_per_m2: p.contacts_per_area,
            })
            .collect(),
        table: ForceTableReport {
            h_star_range: a.table().range(),
            h_star_step: a.table().step(),
            max_rel_error: PerChannel(
                a.table_error()
                    .iter()
                    .map(|e| (e.name.clone(), e.max_rel))
                    .collect(),
            ),
        },
        mtl: a.mtl.as_ref().map(|m| m.report()),
        summit_distribution: a.summit_origin.as_ref().map(SummitOrigin::report),
    }
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
        let mut params = check(cfg).map_err(|e| e.locate(file, "contact", name))?;
        if let SummitSpec::Measured(SummitSource::Unresolved(src)) = &params.summits {
            let key = if cfg.summit_source.is_some() {
                "summit_source"
            } else {
                "interface"
            };
            let err = |m: String| file.error("contact", name, key, m);
            let source = if file.has_instance("surface", src) {
                SummitSource::Surface(src.clone())
            } else if let Some(i) = InterfaceSurfaces::of(file, src)? {
                if !i.has_two_surfaces() {
                    return Err(err(format!(
                        "[interface.{src}] has no two measured surfaces (rule = \"{}\"): \
                         measured summits need a [surface.*] or an interface of two",
                        i.rule
                    )));
                }
                SummitSource::Interface {
                    name: src.clone(),
                    surfaces: i.surfaces,
                }
            } else {
                return Err(err(format!(
                    "no [surface.{src}] or [interface.{src}] in this file for the measured summits"
                )));
            };
            params.summits = SummitSpec::Measured(source);
        }
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
    type Result = ContactStageResult;
    type Row = ContactRow;

    fn params(&self) -> Value {
        self.params.canonical()
    }
    fn upstream(&self) -> Vec<String> {
        let mut up: Vec<String> = self.params.interface.iter().cloned().collect();
        if let SummitSpec::Measured(src) = &self.params.summits {
            for s in src.surfaces() {
                if !up.contains(&s) {
                    up.push(s);
                }
            }
        }
        up
    }
    fn run(&self, ctx: &StageContext) -> Result<Output<ContactStageResult, ContactRow>> {
        let mut p = self.params.params;
        if let Some(i) = &self.params.interface {
            [p.sigma, p.summit_radius, p.summit_density] = upstream_summits(&ctx.upstream, i)?;
        }
        let measured = match &self.params.summits {
            SummitSpec::Measured(src) => {
                let surfaces = src
                    .surfaces()
                    .into_iter()
                    .map(|s| {
                        let h = upstream_summit_heights(&ctx.upstream, &s)?;
                        Ok((s, h))
                    })
                    .collect::<Result<Vec<_>>>()?;
                Some(SummitOrigin::measured(src.name(), surfaces)?)
            }
            _ => None,
        };
        ctx.progress.set_message("ISBL curves and force table");
        let a = analyse(&p, &self.params, measured)?;
        let inputs = serde_json::to_value(&ctx.fingerprint.inputs).unwrap_or(Value::Null);
        write_outputs(
            &a,
            &self.params,
            &ctx.out_dir.join("contact.h5"),
            Some(ctx.out_dir),
            ctx.key,
            &inputs,
        )?;
        Ok(Output {
            result: ContactStageResult {
                report: report_json(&a, &self.params),
                h5: "contact.h5".into(),
            },
            summary_row: Some(summary_row(&a, &self.params)),
        })
    }
}

#[cfg(test)]
mod tests;
