//! Interface stage: two measured surfaces (or explicit values) → the equivalent rough surface
//! against a smooth flat (σ, R, η, β) that the contact models use (Table 2.2; docs/surfaces.md).

use super::{FromConfig, Output, StageContext, StageKind};
use crate::artefacts::interface::InterfaceRoughness;
use crate::artefacts::surface::upstream_surface_stats;
use crate::core::config::{ConfigError, PipelineFile};
use crate::core::store::H5Out;
use crate::error::Result;
use crate::surface::combine::{combine, CombineRule, SurfaceStats};
use crate::units::{Length, PerArea};
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

pub const MODEL_VERSION: &str = "interface-1";

fn default_rule() -> String {
    "sum_surface".into()
}

/// `[interface.NAME]` as written.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InterfaceConfig {
    /// The two `[surface.*]` instances to combine (not needed with rule = "explicit").
    #[serde(default)]
    pub surfaces: Vec<String>,
    /// "sum_surface" (default), "harmonic_r" or "explicit".
    #[serde(default = "default_rule")]
    pub rule: String,
    /// Explicit combined values (rule = "explicit"), e.g. the dissertation's Table 2.2.
    #[serde(default)]
    pub sigma: Option<Length>,
    #[serde(default)]
    pub r: Option<Length>,
    #[serde(default)]
    pub eta: Option<PerArea>,
}

pub struct InterfaceStage {
    pub name: String,
    pub surfaces: Vec<String>,
    pub rule: CombineRule,
}

fn rule_name(r: &CombineRule) -> &'static str {
    match r {
        CombineRule::SumSurface => "sum_surface",
        CombineRule::HarmonicR => "harmonic_r",
        CombineRule::Explicit { .. } => "explicit",
    }
}

impl FromConfig for InterfaceStage {
    type Config = InterfaceConfig;

    fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &InterfaceConfig,
    ) -> std::result::Result<Self, ConfigError> {
        let err = |k: &str, m: String| file.error("interface", name, k, m);
        let rule = match cfg.rule.as_str() {
            "sum_surface" => CombineRule::SumSurface,
            "harmonic_r" => CombineRule::HarmonicR,
            "explicit" => {
                let (Some(s), Some(r), Some(e)) = (cfg.sigma, cfg.r, cfg.eta) else {
                    return Err(err(
                        "rule",
                        "rule = \"explicit\" needs sigma, r and eta".into(),
                    ));
                };
                for (k, v) in [("sigma", s.0), ("r", r.0), ("eta", e.0)] {
                    if v <= 0.0 {
                        return Err(err(k, format!("{v} is out of range: must be > 0")));
                    }
                }
                CombineRule::Explicit {
                    sigma: s.0,
                    r: r.0,
                    eta: e.0,
                }
            }
            other => {
                return Err(err(
                    "rule",
                    format!("`{other}`: use sum_surface, harmonic_r or explicit"),
                ))
            }
        };
        if !matches!(rule, CombineRule::Explicit { .. }) {
            if cfg.surfaces.len() != 2 {
                return Err(err(
                    "surfaces",
                    format!(
                        "needs exactly two [surface.*] names, got {}",
                        cfg.surfaces.len()
                    ),
                ));
            }
            for s in &cfg.surfaces {
                if !file.has_instance("surface", s) {
                    let names: Vec<&str> = file.instance_names("surface");
                    let hint = crate::core::config::nearest(s, &names)
                        .map(|n| format!(" (did you mean `{n}`?)"))
                        .unwrap_or_default();
                    return Err(err(
                        "surfaces",
                        format!("no [surface.{s}] in this file{hint}"),
                    ));
                }
            }
        }
        Ok(Self {
            name: name.to_string(),
            surfaces: cfg.surfaces.clone(),
            rule,
        })
    }
}

/// One row of the interface summary table (table units).
#[derive(Debug, Clone, Serialize)]
pub struct InterfaceRow {
    pub rule: &'static str,
    /// The two surfaces, ` + `-joined (empty for explicit values).
    pub surfaces: String,
    pub sigma_nm: f64,
    #[serde(rename = "R_um")]
    pub r_um: f64,
    pub eta_per_um2: f64,
    pub beta: f64,
    pub alpha: f64,
}

impl StageKind for InterfaceStage {
    const KIND: &'static str = "interface";
    const MODEL_VERSION: &'static str = MODEL_VERSION;
    type Result = InterfaceRoughness;
    type Row = InterfaceRow;

    fn params(&self) -> Value {
        let explicit = match self.rule {
            CombineRule::Explicit { sigma, r, eta } => {
                json!({"sigma_m": sigma, "R_m": r, "eta_per_m2": eta})
            }
            _ => Value::Null,
        };
        json!({"rule": rule_name(&self.rule), "surfaces": self.surfaces, "explicit": explicit})
    }
    fn upstream(&self) -> Vec<String> {
        if matches!(self.rule, CombineRule::Explicit { .. }) {
            Vec::new()
        } else {
            self.surfaces.clone()
        }
    }
    fn run(&self, ctx: &StageContext) -> Result<Output<InterfaceRoughness, InterfaceRow>> {
        let (a, b) = match self.rule {
            CombineRule::Explicit { sigma, r, eta } => {
                let s = SurfaceStats {
                    sigma,
                    r,
                    eta,
                    m2: None,
                    m4: None,
                };
                (s, s)
            }
            _ => {
                let get = |n: &String| upstream_surface_stats(&ctx.upstream, n);
                (get(&self.surfaces[0])?, get(&self.surfaces[1])?)
            }
        };
        let st = combine(&a, &b, self.rule)?;
        let out = H5Out::create(&ctx.out_dir.join("interface.h5"))?;
        out.root_attributes(
            "interface",
            ctx.key,
            &self.params(),
            &Value::from(self.surfaces.clone()),
            "interface",
        )?;
        let g = out.group("interface", Some("NXentry"))?;
        out.write_string(&g, "rule", rule_name(&st.rule))?;
        out.write_scalar(&g, "sigma", st.sigma, "m", "combined RMS roughness")?;
        out.write_scalar(&g, "R", st.r, "m", "combined mean summit radius")?;
        out.write_scalar(&g, "eta", st.eta, "m^-2", "combined summit density")?;
        out.write_scalar(&g, "beta", st.beta, "1", "sigma R eta")?;
        out.write_scalar(&g, "m2", st.m2, "1", "combined second spectral moment")?;
        out.write_scalar(&g, "m4", st.m4, "m^-2", "combined fourth spectral moment")?;
        out.write_scalar(&g, "alpha", st.alpha, "1", "Nayak bandwidth parameter")?;
        out.finish()?;
        let row = InterfaceRow {
            rule: rule_name(&st.rule),
            surfaces: self.surfaces.join(" + "),
            sigma_nm: st.sigma * 1e9,
            r_um: st.r * 1e6,
            eta_per_um2: st.eta * 1e-12,
            beta: st.beta,
            alpha: st.alpha,
        };
        Ok(Output {
            result: InterfaceRoughness::new(&st, rule_name(&st.rule)),
            summary_row: Some(row),
        })
    }
}
