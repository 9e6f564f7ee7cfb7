//! Contact stage: an interface (from the interface stage or a dissertation parameter set) →
//! the ISBL curves per unit nominal area against the solid separation h and h/σ, and the
//! verified force table the dynamics interpolate. HDF5 + PNG + a summary row.

use super::{FromConfig, StageContext, StageKind, StageOutput};
pub mod mtl;

use self::mtl::{MtlAnalysis, MtlKeys, MtlSettings};
use crate::artefacts::contact::ContactInputs;
use crate::artefacts::interface::{upstream_summits, InterfaceSurfaces};
use crate::artefacts::surface::upstream_summit_heights;
use crate::contact::isbl::summits::{
    fit_two_point, SummitFit, TwoPointTarget, FIG_2_11_NOMINAL_AREA,
};
use crate::contact::isbl::{
    surface_energy_at, FrictionLaw, IsblModel, IsblParams, SummitDistribution, SurfaceEnergy,
};
use crate::contact::lookup::{IsblLookup, FORCE_TABLE_GRID};
use crate::contact::table::{ChannelError, ForceTable};
use crate::contact::ContactError;
use crate::core::config::{ConfigError, PipelineFile};
use crate::surface::combine::{combine_summit_heights, SummitHeights};

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

/// The interface parameters as downstream stages read them (`inputs` in the result).
fn params_json(p: &IsblParams) -> Value {
    ContactInputs::from(p).to_json()
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

/// How a fitted or measured summit distribution was obtained (the result's and contact.h5's
/// `summit_distribution`).
#[derive(Debug, Clone, PartialEq)]
pub enum SummitOrigin {
    /// Fitted to Fig. 2.11 with the force on `nominal_area` [m²].
    Fig211 { nominal_area: f64, fit: SummitFit },
    /// Measured: each surface's summits and their combination (one surface: itself).
    Measured {
        source: String,
        surfaces: Vec<(String, SummitHeights)>,
        combined: SummitHeights,
    },
}

impl SummitOrigin {
    /// The measured summits of `surfaces` (one, or an interface's two: combined as the sum
    /// surface's, `surface::combine::combine_summit_heights`).
    pub fn measured(source: &str, surfaces: Vec<(String, SummitHeights)>) -> Result<Self> {
        let combined = match surfaces.as_slice() {
            [(_, one)] => *one,
            [(_, a), (_, b)] => combine_summit_heights(a, b)?,
            _ => {
                return Err(crate::error::Error::SummitSurfaces {
                    stage: source.to_string(),
                    count: surfaces.len(),
                })
            }
        };
        Ok(SummitOrigin::Measured {
            source: source.to_string(),
            surfaces,
            combined,
        })
    }

    /// `(σ_s/σ, y_s/σ)`.
    pub fn ratios(&self) -> (f64, f64) {
        match self {
            SummitOrigin::Fig211 { fit, .. } => (fit.sigma_ratio, fit.offset_ratio),
            SummitOrigin::Measured { combined, .. } => {
                (combined.std_ratio(), combined.mean_ratio())
            }
        }
    }

    /// The result's `summit_distribution` block (SI, units in the keys).
    pub fn to_json(&self) -> Value {
        let (s, y) = self.ratios();
        let heights = |h: &SummitHeights| {
            json!({"sigma_m": h.sigma, "eta_per_m2": h.eta, "summit_mean_m": h.mean,
                   "summit_std_m": h.std, "sigma_s_over_sigma": h.std_ratio(),
                   "y_s_over_sigma": h.mean_ratio()})
        };
        match self {
            SummitOrigin::Fig211 { nominal_area, fit } => json!({
                "kind": "fig_2_11",
                "sigma_s_over_sigma": s, "y_s_over_sigma": y,
                "nominal_area_m2": nominal_area,
                "target": {"h_star": 3.0, "force_N": 7.30e-6, "h_star_ref": 2.5, "ratio": 0.03},
                "fitted": {"force_N": fit.force, "ratio": fit.ratio},
            }),
            SummitOrigin::Measured {
                source,
                surfaces,
                combined,
            } => json!({
                "kind": "measured",
                "sigma_s_over_sigma": s, "y_s_over_sigma": y,
                "source": source,
                "surfaces": surfaces.iter().map(|(n, h)| {
                    let mut v = heights(h);
                    v["surface"] = json!(n);
                    v
                }).collect::<Vec<_>>(),
                "combined": heights(combined),
                "rule": if surfaces.len() == 2 { "summit_mixture" } else { "single_surface" },
            }),
        }
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
    let mut v = json!({
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
    });
    // Only a fitted or measured distribution adds the block (the default result is unchanged).
    if let (Some(o), Value::Object(m)) = (&a.summit_origin, &mut v) {
        m.insert("summit_distribution".into(), o.to_json());
    }
    v
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
    if let Some(o) = &a.summit_origin {
        write_summit_origin(&out, o)?;
    }
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

/// `contact/summit_distribution`: a fitted or measured summit distribution and its inputs.
fn write_summit_origin(out: &H5Out, o: &SummitOrigin) -> Result<()> {
    let g = out.group("contact/summit_distribution", None)?;
    let (s, y) = o.ratios();
    out.write_scalar(&g, "sigma_s_over_sigma", s, "1", "summit height std / σ")?;
    out.write_scalar(
        &g,
        "y_s_over_sigma",
        y,
        "1",
        "summit mean plane above the surface mean plane / σ",
    )?;
    match o {
        SummitOrigin::Fig211 { nominal_area, fit } => {
            out.write_string(&g, "kind", "fig_2_11")?;
            out.write_scalar(
                &g,
                "nominal_area",
                *nominal_area,
                "m^2",
                "nominal area of Fig. 2.11's force (stated input)",
            )?;
            out.write_scalar(&g, "force_at_3sigma", fit.force, "N", "fitted P(3σ)·A_n")?;
            out.write_scalar(&g, "ratio_3_to_2_5", fit.ratio, "1", "fitted P(3σ)/P(2.5σ)")?;
        }
        SummitOrigin::Measured {
            source, combined, ..
        } => {
            out.write_string(&g, "kind", "measured")?;
            out.write_string(&g, "source", source)?;
            out.write_scalar(
                &g,
                "sigma",
                combined.sigma,
                "m",
                "σ of the measured surface(s)",
            )?;
            out.write_scalar(
                &g,
                "summit_mean",
                combined.mean,
                "m",
                "mean summit height above the mean plane",
            )?;
            out.write_scalar(&g, "summit_std", combined.std, "m", "summit height std")?;
        }
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
    fn run(&self, ctx: &StageContext) -> Result<StageOutput> {
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
        let a = analyse(&c.params, &c, None).unwrap();
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
            let result = report_json(&analyse(&p, &c, None).unwrap(), &c);
            let back = ContactInputs::from_json(&result["inputs"]).unwrap();
            assert_eq!(back.params().unwrap(), p);
        }
    }

    /// The default distribution, spelt either way, keeps the key the contact instance had
    /// before the switch existed; the others name themselves in it.
    #[test]
    fn summit_distribution_keys_and_the_default_key() {
        let with = |d: Option<&str>, o: Option<&str>| ContactConfig {
            summit_distribution: d.map(str::to_string),
            summit_offset: o.map(str::to_string),
            ..ContactConfig::defaults()
        };
        let base = check(&ContactConfig::defaults()).unwrap();
        let key = base.canonical();
        assert!(key.get("summit_distribution").is_none());
        assert_eq!(key["inputs"]["summit_offset"], "none");
        assert!(key["inputs"].get("summit_ratios").is_none());
        for (d, o) in [
            (Some("surface"), None),
            (None, Some("none")),
            (Some("surface"), Some("none")),
        ] {
            assert_eq!(check(&with(d, o)).unwrap().canonical(), key, "{d:?} {o:?}");
        }
        let mccool = check(&with(Some("mccool"), None)).unwrap();
        assert_eq!(
            mccool.canonical(),
            check(&with(None, Some("mccool"))).unwrap().canonical()
        );
        assert_eq!(mccool.params.summits, SummitDistribution::McCool);
        let fig = check(&ContactConfig {
            fig_2_11_nominal_area: Some(Area(62e-12)),
            ..with(Some("fig_2_11"), None)
        })
        .unwrap();
        assert_eq!(
            fig.summits,
            SummitSpec::Fig211 {
                nominal_area: 62e-12
            }
        );
        let k = fig.canonical();
        assert_eq!(k["inputs"]["summit_offset"], "fig_2_11");
        assert_eq!(k["summit_distribution"]["nominal_area_m2"], 62e-12);
        // The fit replaces the distribution when the curves are computed.
        let a = analyse(&fig.params, &fig, None).unwrap();
        let (s, y) = a.summit_origin.as_ref().unwrap().ratios();
        assert!(s > 0.3 && s < 0.4 && y > 2.1 && y < 2.3, "{s} {y}");
        let p3 = a.model.at(3.0 * fig.params.sigma).unwrap().contact_pressure;
        assert!((p3 * 62e-12 / 7.30e-6 - 1.0).abs() < 1e-9);
        assert_eq!(report_json(&a, &fig)["inputs"]["summit_offset"], "given");
        // Conflicts and misplaced keys name themselves; measured without a pipeline is an error.
        let key_of = |c: &ContactConfig| check(c).unwrap_err().key;
        assert_eq!(
            key_of(&with(Some("fig_2_11"), Some("mccool"))),
            "summit_offset"
        );
        assert_eq!(
            key_of(&with(Some("lognormal"), None)),
            "summit_distribution"
        );
        assert_eq!(key_of(&with(None, Some("surface"))), "summit_offset");
        assert_eq!(key_of(&with(Some("measured"), None)), "summit_distribution");
        let misplaced = ContactConfig {
            fig_2_11_nominal_area: Some(Area(62e-12)),
            ..with(Some("mccool"), None)
        };
        assert_eq!(key_of(&misplaced), "fig_2_11_nominal_area");
        let source = ContactConfig {
            summit_source: Some("disk".into()),
            ..ContactConfig::defaults()
        };
        assert_eq!(key_of(&source), "summit_source");
        let measured = check(&ContactConfig {
            summit_source: Some("disk".into()),
            ..with(Some("measured"), None)
        })
        .unwrap();
        assert!(analyse(&measured.params, &measured, None).is_err());
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
