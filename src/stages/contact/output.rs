//! The contact stage's outputs: `contact.h5` (the ISBL curves, derived quantities, summit
//! origin and force table; docs/hdf5.md) and the PNGs.

use super::mtl::{MtlLandmarks, MtlReport};
use super::{ContactAnalysis, ContactParams, SummitOrigin};
use crate::artefacts::contact::{ContactInputs, SummitDistributionReport};
use crate::contact::isbl::{surface_energy_at, SurfaceEnergy};
use crate::core::store::H5Out;
use crate::error::Result;
use crate::figures;
use schemars::{json_schema, JsonSchema, Schema, SchemaGenerator};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_json::Value;
use std::borrow::Cow;
use std::path::Path;

/// ISBL contact curves of one interface and, with --lubricant, the MTL law (docs/contact.md);
/// SI units named in the keys. Schema version 1 (docs/json.md): existing keys keep their
/// name, unit and type; renaming or removing one makes version 2.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ContactReport {
    /// Dissertation parameter set the interface starts from.
    #[schemars(extend("enum" = ["initial_2dof", "improved_2dof", "three_dof", "mtl_table_3_2"]))]
    pub parameter_set: String,
    /// Upstream interface instance (pipeline only); null for `hdi contact`.
    pub interface: Option<String>,
    /// The ISBL parameters used (also `inputs` in the contact stage's result.json).
    pub inputs: ContactInputs,
    /// Derived interface quantities (docs/contact.md).
    pub derived: IsblDerived,
    /// ISBL curves on the h/σ grid.
    pub curves: Vec<IsblCurvePoint>,
    /// The verified force table the slider cases interpolate.
    pub table: ForceTableReport,
    /// The MTL lubricant law (with --lubricant).
    pub mtl: Option<MtlReport>,
    /// How a fitted (`fig_2_11`) or measured (`measured`) summit distribution was obtained;
    /// absent for `surface` and `mccool` (docs/model-form.md, "Summit heights").
    // Only a fitted or measured distribution adds the block (the default result is unchanged).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(with = "SummitDistributionReport")]
    pub summit_distribution: Option<SummitDistributionReport>,
}

/// The contact stage's `result.json`: the report and where the curves and table are.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ContactStageResult {
    #[serde(flatten)]
    pub report: ContactReport,
    /// `contact.h5` in the entry.
    pub h5: String,
}

/// Derived interface quantities (docs/contact.md).
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct IsblDerived {
    /// Composite modulus E*, Pa.
    pub E_star_Pa: f64,
    /// Hardness coefficient K, dimensionless.
    pub K: f64,
    /// Critical interference ω_c, m.
    pub omega_c_m: f64,
    /// Critical load L_c, N.
    pub L_c_N: f64,
    /// Critical contact area A_c, m².
    pub A_c_m2: f64,
    /// β = σRη, dimensionless.
    pub beta: f64,
    /// Plasticity index ψ, dimensionless.
    pub psi: f64,
    /// Plasticity index of the Kogut–Etsion model, dimensionless.
    pub psi_KE: f64,
    /// Summit-height offset y_s (McCool; 0 without), m.
    pub y_s_m: f64,
    /// Summit-height standard deviation, m.
    pub sigma_s_m: f64,
}

/// One point of the ISBL curves (per unit nominal area).
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct IsblCurvePoint {
    /// Separation h/σ, dimensionless.
    pub h_star: f64,
    /// Solid separation h, m.
    pub h_m: f64,
    /// Contact force per unit nominal area, Pa.
    pub P_Pa: f64,
    /// Contact stiffness −dP/dh per unit nominal area, Pa/m.
    pub k_c_Pa_per_m: f64,
    /// Real-to-nominal area ratio A_r/A_n, dimensionless.
    pub A_r_fraction: f64,
    /// Friction force per unit nominal area, Pa.
    pub Q_Pa: f64,
    /// Adhesion force per unit nominal area, Pa.
    pub F_s_Pa: f64,
    /// Contacting summits per unit nominal area, 1/m².
    pub n_c_per_m2: f64,
}

/// The verified force table the slider cases interpolate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ForceTableReport {
    /// Force-table range [min, max] of h/σ, dimensionless.
    pub h_star_range: (f64, f64),
    /// Force-table step in h/σ, dimensionless.
    pub h_star_step: f64,
    /// Largest relative error of the interpolated table against the direct ISBL integrals,
    /// per quantity.
    pub max_rel_error: PerChannel,
}

/// A number per force-table channel, as a JSON object in the table's channel order.
#[derive(Debug, Clone, PartialEq)]
pub struct PerChannel(pub Vec<(String, f64)>);

impl Serialize for PerChannel {
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        let mut m = serializer.serialize_map(Some(self.0.len()))?;
        for (name, v) in &self.0 {
            m.serialize_entry(name, v)?;
        }
        m.end()
    }
}

impl<'de> Deserialize<'de> for PerChannel {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        // The map in file order (serde_json keeps it).
        let map = serde_json::Map::<String, Value>::deserialize(deserializer)?;
        map.into_iter()
            .map(|(k, v)| match v.as_f64() {
                Some(x) => Ok((k, x)),
                None => Err(serde::de::Error::custom(format!("`{k}` is not a number"))),
            })
            .collect::<std::result::Result<Vec<_>, _>>()
            .map(PerChannel)
    }
}

impl JsonSchema for PerChannel {
    fn schema_name() -> Cow<'static, str> {
        "PerChannel".into()
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        json_schema!({
            "type": "object",
            "additionalProperties": {
                "type": "number",
                "description": "Relative error, dimensionless."
            },
            "propertyNames": { "enum": ["P", "k_c", "A_r", "Q", "F_s"] }
        })
    }
}

/// One row of the tidy contact table (unit suffixes in the names).
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContactRow {
    pub parameter_set: String,
    pub interface: Option<String>,
    pub sigma_nm: f64,
    pub R_um: f64,
    pub eta_per_um2: f64,
    pub beta: f64,
    pub E_star_GPa: f64,
    pub omega_c_nm: f64,
    pub psi: f64,
    pub P_at_3sigma_Pa: Option<f64>,
    pub F_s_at_3sigma_Pa: Option<f64>,
    pub table_max_rel_error: f64,
    #[serde(flatten)]
    pub lubricant: LubricantColumns,
}

/// The row's lubricant columns: the MTL landmarks, or `lubricant` null without one.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum LubricantColumns {
    Landmarks(MtlLandmarks),
    None { lubricant: Option<&'static str> },
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
    let isbl_inputs = ContactInputs::from(a.model.params()).to_json();
    out.write_string(&entry, "inputs", &isbl_inputs.to_string())?;
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
pub(super) fn write_isbl(out: &H5Out, a: &ContactAnalysis) -> Result<()> {
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
pub(super) fn write_derived(out: &H5Out, a: &ContactAnalysis) -> Result<()> {
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
pub(super) fn write_summit_origin(out: &H5Out, o: &SummitOrigin) -> Result<()> {
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
pub(super) fn write_table(out: &H5Out, a: &ContactAnalysis) -> Result<()> {
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
pub(super) fn write_figures(a: &ContactAnalysis, c: &ContactParams, dir: &Path) -> Result<()> {
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
