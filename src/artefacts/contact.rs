//! The contact stage's interface parameters (`inputs` in its `result.json`, and the `inputs`
//! string of `contact.h5`): everything a downstream stage needs to rebuild the ISBL model and
//! its force table (the 2-DOF and 3-DOF cases, the calibration).

use crate::contact::isbl::summits::SummitFit;
use crate::contact::isbl::{FrictionLaw, IsblParams, SummitDistribution, SurfaceEnergy};
use crate::error::{Error, Result};
use crate::surface::combine::{combine_summit_heights, SummitHeights};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;

/// The ISBL parameters as the contact stage writes them (SI, unit suffixes in the keys). The
/// field order is the key order of the written JSON, which is also part of the contact
/// instance's cache key: do not reorder.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ContactInputs {
    /// Combined RMS roughness σ, m.
    #[serde(rename = "sigma_m")]
    pub sigma: f64,
    /// Mean summit radius R, m.
    #[serde(rename = "R_m")]
    pub summit_radius: f64,
    /// Summit density η, 1/m².
    #[serde(rename = "eta_per_m2")]
    pub summit_density: f64,
    /// Slider Young's modulus, Pa.
    #[serde(rename = "E1_Pa")]
    pub slider_modulus: f64,
    /// Slider Poisson ratio.
    #[serde(rename = "nu1")]
    pub slider_poisson: f64,
    /// Disk Young's modulus, Pa.
    #[serde(rename = "E2_Pa")]
    pub disk_modulus: f64,
    /// Disk Poisson ratio.
    #[serde(rename = "nu2")]
    pub disk_poisson: f64,
    /// Poisson ratio of the yielding body.
    #[serde(rename = "nu_yielding")]
    pub yielding_poisson: f64,
    /// Hardness of the yielding body, Pa.
    #[serde(rename = "H_Pa")]
    pub hardness: f64,
    /// Lennard-Jones equilibrium spacing ε, m.
    #[serde(rename = "epsilon_m")]
    pub lj_spacing: f64,
    /// Total lubricant thickness t, m.
    #[serde(rename = "t_m")]
    pub lubricant_thickness: f64,
    /// Surface energy Δγ: constant or the variable law.
    pub surface_energy: SurfaceEnergyInput,
    /// Summit distribution as the model uses it: `none` (the surface heights' statistics;
    /// `[contact] summit_distribution = "surface"`), `mccool`, or `given` with
    /// `summit_ratios` (fitted to Fig. 2.11 or measured; the top-level `summit_distribution`
    /// says how).
    // The legacy `None`/`McCool` of results written before docs/json.md are still read. The
    // key keeps its old name so that results and cache keys of the default are unchanged.
    #[schemars(extend("enum" = ["none", "mccool", "given"]))]
    pub summit_offset: String,
    /// Friction law (the `[contact] friction_law` values).
    // Legacy `JunctionShear`/`SeedPowerElastic` are still read.
    #[schemars(extend("enum" = ["junction_shear", "seed_power_elastic", "ke_static"]))]
    pub friction_law: String,
    /// Only with summit_offset = given.
    // Absent (not written) otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schemars(with = "SummitRatios")]
    pub summit_ratios: Option<SummitRatios>,
}

/// A given summit distribution in units of σ.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SummitRatios {
    /// σ_s/σ: standard deviation of the summit heights over σ.
    pub sigma_s_over_sigma: f64,
    /// y_s/σ: mean plane of the summits above the surface mean plane, over σ.
    pub y_s_over_sigma: f64,
}

/// The `inputs.summit_offset` name of a summit distribution.
pub fn summit_offset_name(o: SummitDistribution) -> &'static str {
    match o {
        SummitDistribution::Surface => "none",
        SummitDistribution::McCool => "mccool",
        SummitDistribution::Given { .. } => "given",
    }
}

/// The `[contact] friction_law` name of a law.
pub fn friction_law_name(f: FrictionLaw) -> &'static str {
    match f {
        FrictionLaw::JunctionShear => "junction_shear",
        FrictionLaw::SeedPowerElastic => "seed_power_elastic",
        FrictionLaw::KeStatic => "ke_static",
    }
}

/// Δγ: `{"constant_N_per_m": …}` or `{"variable": {"c1_N_per_m", "c2_per_m", "c3_N_per_m"}}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum SurfaceEnergyInput {
    Constant {
        /// Constant Δγ, N/m.
        #[serde(rename = "constant_N_per_m")]
        delta_gamma: f64,
    },
    Variable {
        /// Δγ(s) = c1·exp(−c2·s) + c3.
        variable: VariableSurfaceEnergy,
    },
}

/// The coefficients of `Δγ(s) = c1·exp(−c2·s) + c3`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct VariableSurfaceEnergy {
    /// c1, N/m.
    #[serde(rename = "c1_N_per_m")]
    pub c1: f64,
    /// c2, 1/m.
    #[serde(rename = "c2_per_m")]
    pub c2: f64,
    /// c3, N/m.
    #[serde(rename = "c3_N_per_m")]
    pub c3: f64,
}

impl From<&IsblParams> for ContactInputs {
    fn from(p: &IsblParams) -> Self {
        ContactInputs {
            sigma: p.sigma,
            summit_radius: p.summit_radius,
            summit_density: p.summit_density,
            slider_modulus: p.slider_modulus,
            slider_poisson: p.slider_poisson,
            disk_modulus: p.disk_modulus,
            disk_poisson: p.disk_poisson,
            yielding_poisson: p.yielding_poisson,
            hardness: p.hardness,
            lj_spacing: p.lj_spacing,
            lubricant_thickness: p.lubricant_thickness,
            surface_energy: match p.surface_energy {
                SurfaceEnergy::Constant { delta_gamma } => {
                    SurfaceEnergyInput::Constant { delta_gamma }
                }
                SurfaceEnergy::Variable { c1, c2, c3 } => SurfaceEnergyInput::Variable {
                    variable: VariableSurfaceEnergy { c1, c2, c3 },
                },
            },
            summit_offset: summit_offset_name(p.summits).to_string(),
            friction_law: friction_law_name(p.friction_law).to_string(),
            summit_ratios: match p.summits {
                SummitDistribution::Given {
                    sigma_ratio,
                    offset_ratio,
                } => Some(SummitRatios {
                    sigma_s_over_sigma: sigma_ratio,
                    y_s_over_sigma: offset_ratio,
                }),
                _ => None,
            },
        }
    }
}

impl ContactInputs {
    /// The JSON the contact stage writes (`inputs`).
    pub fn to_json(&self) -> Value {
        serde_json::to_value(self).unwrap_or(Value::Null)
    }

    /// The `inputs` block of a contact result; `None` if it is missing or malformed.
    pub fn from_json(v: &Value) -> Option<Self> {
        Self::deserialize(v).ok()
    }

    /// The ISBL parameters; `None` for an unknown summit offset or friction law (or a `given`
    /// one without its ratios).
    pub fn params(&self) -> Option<IsblParams> {
        Some(IsblParams {
            sigma: self.sigma,
            summit_radius: self.summit_radius,
            summit_density: self.summit_density,
            slider_modulus: self.slider_modulus,
            slider_poisson: self.slider_poisson,
            disk_modulus: self.disk_modulus,
            disk_poisson: self.disk_poisson,
            yielding_poisson: self.yielding_poisson,
            hardness: self.hardness,
            lj_spacing: self.lj_spacing,
            lubricant_thickness: self.lubricant_thickness,
            surface_energy: match self.surface_energy {
                SurfaceEnergyInput::Constant { delta_gamma } => {
                    SurfaceEnergy::Constant { delta_gamma }
                }
                SurfaceEnergyInput::Variable {
                    variable: VariableSurfaceEnergy { c1, c2, c3 },
                } => SurfaceEnergy::Variable { c1, c2, c3 },
            },
            summits: match (self.summit_offset.as_str(), self.summit_ratios) {
                ("none" | "None", None) => SummitDistribution::Surface,
                ("mccool" | "McCool", None) => SummitDistribution::McCool,
                ("given", Some(r)) => SummitDistribution::Given {
                    sigma_ratio: r.sigma_s_over_sigma,
                    offset_ratio: r.y_s_over_sigma,
                },
                _ => return None,
            },
            friction_law: match self.friction_law.as_str() {
                "junction_shear" | "JunctionShear" => FrictionLaw::JunctionShear,
                "seed_power_elastic" | "SeedPowerElastic" => FrictionLaw::SeedPowerElastic,
                "ke_static" => FrictionLaw::KeStatic,
                _ => return None,
            },
        })
    }
}

/// What downstream stages read of a contact instance's `result.json` (the stage writes more,
/// `stages::contact::ContactReport`; serde skips the rest): the interface parameters.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct ContactResult {
    pub inputs: ContactInputs,
}

/// The ISBL parameters of the contact instance `contact` from the upstream results.
pub fn upstream_isbl_params(
    upstream: &BTreeMap<String, Value>,
    contact: &str,
) -> Result<IsblParams> {
    let unusable = || Error::UpstreamField {
        kind: "contact",
        name: contact.to_string(),
        what: "usable `inputs`".into(),
    };
    let result: ContactResult = crate::artefacts::upstream_result(upstream, "contact", contact)
        .map_err(|e| match e {
            Error::UpstreamField { .. } => unusable(),
            other => other,
        })?;
    result.inputs.params().ok_or_else(unusable)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// The `inputs` block as the contact stage wrote it before the struct existed, with the
    /// enums in their Rust Debug form: results written in this form must still read back.
    fn written_before(p: &IsblParams) -> Value {
        let surface_energy = match p.surface_energy {
            SurfaceEnergy::Constant { delta_gamma } => json!({"constant_N_per_m": delta_gamma}),
            SurfaceEnergy::Variable { c1, c2, c3 } => {
                json!({"variable": {"c1_N_per_m": c1, "c2_per_m": c2, "c3_N_per_m": c3}})
            }
        };
        json!({
            "sigma_m": p.sigma, "R_m": p.summit_radius, "eta_per_m2": p.summit_density,
            "E1_Pa": p.slider_modulus, "nu1": p.slider_poisson,
            "E2_Pa": p.disk_modulus, "nu2": p.disk_poisson, "nu_yielding": p.yielding_poisson,
            "H_Pa": p.hardness, "epsilon_m": p.lj_spacing, "t_m": p.lubricant_thickness,
            "surface_energy": surface_energy,
            "summit_offset": match p.summits {
                SummitDistribution::Surface => "None",
                _ => "McCool",
            },
            "friction_law": format!("{:?}", p.friction_law),
        })
    }

    #[test]
    fn written_json_is_unchanged_and_reads_back() {
        let mut mccool = IsblParams::improved_2dof();
        mccool.summits = SummitDistribution::McCool;
        mccool.friction_law = FrictionLaw::SeedPowerElastic;
        let ke_static = IsblParams {
            friction_law: FrictionLaw::KeStatic,
            ..IsblParams::improved_2dof()
        };
        for p in [
            IsblParams::improved_2dof(),
            IsblParams::mtl_table_3_2(),
            mccool,
            ke_static,
        ] {
            let inputs = ContactInputs::from(&p);
            // `ke_static` is newer than the Debug form: results never named it that way.
            if p.friction_law != FrictionLaw::KeStatic {
                let old = ContactInputs::from_json(&written_before(&p)).unwrap();
                assert_eq!(old.params().unwrap(), p);
            }
            // The results name the enums explicitly (docs/json.md), no Rust debug form.
            let v = inputs.to_json();
            assert_eq!(v["summit_offset"], summit_offset_name(p.summits));
            assert!(v.get("summit_ratios").is_none());
            assert_eq!(v["friction_law"], friction_law_name(p.friction_law));
            let back = ContactInputs::from_json(&v).unwrap().params().unwrap();
            assert_eq!(back, p);
        }
    }

    /// A given distribution writes its ratios and reads back; without them it is unusable.
    #[test]
    fn a_given_summit_distribution_round_trips_with_its_ratios() {
        let p = IsblParams {
            summits: SummitDistribution::Given {
                sigma_ratio: 0.42,
                offset_ratio: 1.9,
            },
            ..IsblParams::improved_2dof()
        };
        let v = ContactInputs::from(&p).to_json();
        assert_eq!(v["summit_offset"], "given");
        assert_eq!(v["summit_ratios"]["sigma_s_over_sigma"], 0.42);
        assert_eq!(v["summit_ratios"]["y_s_over_sigma"], 1.9);
        assert_eq!(ContactInputs::from_json(&v).unwrap().params().unwrap(), p);
        let mut bare = v.clone();
        bare.as_object_mut().unwrap().remove("summit_ratios");
        assert!(ContactInputs::from_json(&bare).unwrap().params().is_none());
    }

    #[test]
    fn a_missing_field_or_unknown_law_is_unusable() {
        let p = IsblParams::improved_2dof();
        let mut v = ContactInputs::from(&p).to_json();
        v.as_object_mut().unwrap().remove("H_Pa");
        assert!(ContactInputs::from_json(&v).is_none());
        let mut v = ContactInputs::from(&p).to_json();
        v["friction_law"] = json!("Coulomb");
        assert!(ContactInputs::from_json(&v).unwrap().params().is_none());
        let up = BTreeMap::from([("c".to_string(), json!({"inputs": {}}))]);
        let e = upstream_isbl_params(&up, "c").unwrap_err().to_string();
        assert!(
            e.contains("contact `c` result has no usable `inputs`"),
            "{e}"
        );
        let e = upstream_isbl_params(&up, "d").unwrap_err().to_string();
        assert!(e.contains("no result from contact `d`"), "{e}");
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
    pub fn report(&self) -> SummitDistributionReport {
        let (sigma_s_over_sigma, y_s_over_sigma) = self.ratios();
        match self {
            SummitOrigin::Fig211 { nominal_area, fit } => SummitDistributionReport::Fig211 {
                sigma_s_over_sigma,
                y_s_over_sigma,
                nominal_area_m2: *nominal_area,
                target: Fig211Target {
                    h_star: 3.0,
                    force_N: 7.30e-6,
                    h_star_ref: 2.5,
                    ratio: 0.03,
                },
                fitted: Fig211Fitted {
                    force_N: fit.force,
                    ratio: fit.ratio,
                },
            },
            SummitOrigin::Measured {
                source,
                surfaces,
                combined,
            } => SummitDistributionReport::Measured {
                sigma_s_over_sigma,
                y_s_over_sigma,
                source: source.clone(),
                surfaces: surfaces
                    .iter()
                    .map(|(n, h)| SummitHeightsReport::of(h, Some(n.clone())))
                    .collect(),
                combined: SummitHeightsReport::of(combined, None),
                rule: if surfaces.len() == 2 {
                    "summit_mixture"
                } else {
                    "single_surface"
                }
                .into(),
            },
        }
    }
}

/// How a fitted (`fig_2_11`) or measured (`measured`) summit distribution was obtained; absent
/// for `surface` and `mccool` (docs/model-form.md, "Summit heights").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "kind")]
pub enum SummitDistributionReport {
    /// Fitted to Fig. 2.11's two numbers.
    #[serde(rename = "fig_2_11")]
    Fig211 {
        /// σ_s/σ the model uses.
        sigma_s_over_sigma: f64,
        /// y_s/σ the model uses.
        y_s_over_sigma: f64,
        /// The nominal area of Fig. 2.11's force (a stated input), m².
        nominal_area_m2: f64,
        /// The two numbers fitted (h* = 3: 7.30 µN; P(3)/P(2.5) = 0.03).
        target: Fig211Target,
        /// What the fitted model gives at the two points.
        fitted: Fig211Fitted,
    },
    /// Measured on a surface, or on an interface's two surfaces.
    #[serde(rename = "measured")]
    Measured {
        /// σ_s/σ the model uses.
        sigma_s_over_sigma: f64,
        /// y_s/σ the model uses.
        y_s_over_sigma: f64,
        /// The [surface.*] or [interface.*] instance.
        source: String,
        /// Each surface's summits.
        surfaces: Vec<SummitHeightsReport>,
        /// The summits the model uses (one surface: itself).
        combined: SummitHeightsReport,
        /// How two surfaces' summits combine (surface::combine::combine_summit_heights).
        #[schemars(extend("enum" = ["summit_mixture", "single_surface"]))]
        rule: String,
    },
}

/// The two numbers of Fig. 2.11 a `fig_2_11` distribution is fitted to.
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Fig211Target {
    /// h/σ of the force, dimensionless.
    pub h_star: f64,
    /// P(h_star)·A_n, N.
    pub force_N: f64,
    /// h/σ of the ratio's denominator, dimensionless.
    pub h_star_ref: f64,
    /// P(h_star)/P(h_star_ref), dimensionless.
    pub ratio: f64,
}

/// What the fitted model gives at Fig. 2.11's two points.
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Fig211Fitted {
    /// P(3σ)·A_n, N.
    pub force_N: f64,
    /// P(3σ)/P(2.5σ), dimensionless.
    pub ratio: f64,
}

/// A surface's (or the combined) summit heights.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SummitHeightsReport {
    /// RMS of the surface heights, m (combined: in quadrature).
    pub sigma_m: f64,
    /// Summit density, 1/m² (combined: η1 + η2, the mixture's weights).
    pub eta_per_m2: f64,
    /// Mean summit height above the mean plane, m.
    pub summit_mean_m: f64,
    /// Standard deviation of the summit heights, m.
    pub summit_std_m: f64,
    /// σ_s/σ, dimensionless.
    pub sigma_s_over_sigma: f64,
    /// y_s/σ, dimensionless.
    pub y_s_over_sigma: f64,
    /// The [surface.*] instance (per-surface entries only).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(with = "String")]
    pub surface: Option<String>,
}

impl SummitHeightsReport {
    fn of(h: &SummitHeights, surface: Option<String>) -> Self {
        SummitHeightsReport {
            sigma_m: h.sigma,
            eta_per_m2: h.eta,
            summit_mean_m: h.mean,
            summit_std_m: h.std,
            sigma_s_over_sigma: h.std_ratio(),
            y_s_over_sigma: h.mean_ratio(),
            surface,
        }
    }
}
