//! The 3-DOF stage's results (`[three_dof.NAME]`; docs/three-dof.md): one case's
//! `result.json` (also a row of the instance's `cases` table) and the instance's
//! `result.json`. Field order is the file's key order.

use super::cases::f64_or_nan;
use serde::{Deserialize, Serialize};

/// One 3-DOF case: steady-window statistics (nm, %, mN), the features that touched, each
/// feature's closest approach, contact severity and, for a variable actuation profile, the
/// Table 4.4 windows.
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThreeDofCaseResult {
    #[serde(deserialize_with = "f64_or_nan")]
    pub pole_tip_mean_nm: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub pole_tip_std_nm: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub bulge_spacing_mean_nm: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub bulge_spacing_std_nm: f64,
    pub bulge_vibration_percent: Option<f64>,
    #[serde(deserialize_with = "f64_or_nan")]
    pub roll_std_urad: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub solid_contact_percent: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub lubricant_contact_percent: f64,
    /// Over the integrator's steps, not only the output samples.
    #[serde(deserialize_with = "f64_or_nan")]
    pub peak_contact_force_mN: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub peak_lubricant_force_mN: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub mean_contact_force_mN: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub mean_friction_mN: f64,
    /// Space-separated names of the features that went below the solid level.
    pub features_in_solid_contact: String,
    pub ab_lost_samples: usize,
    /// `min_spacing_<feature>_nm`: each feature's closest approach over the whole run
    /// (null when never finite), in feature order.
    #[serde(flatten)]
    pub min_spacing_nm: MinSpacings,
    /// Contact severity over the steady window (docs/conventions.md); each present only when
    /// defined and finite.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_coefficient: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_coefficient_mean_inst: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_pressure_GPa: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_pressure_GPa_mean_inst: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_traction_GPa: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_traction_GPa_mean_inst: Option<f64>,
    /// The Table 4.4 windows of a variable actuation profile (all four or none).
    #[serde(flatten, default, skip_serializing_if = "Option::is_none")]
    pub table_4_4: Option<Table44Columns>,
    /// Interface label (`isbl`, `mtl_…`).
    pub case: String,
    pub steps: u64,
}

/// Table 4.4 of one case: first lubricant contact (ms) and the bulge vibration of each
/// window, %. Each key is required when reading (null is a value), so a case without the
/// keys reads as no Table 4.4.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Table44Columns {
    #[serde(deserialize_with = "required")]
    pub first_lubricant_contact_ms: Option<f64>,
    #[serde(deserialize_with = "required")]
    pub flying_fhm_percent: Option<f64>,
    #[serde(deserialize_with = "required")]
    pub jump_to_contact_bv_percent: Option<f64>,
    #[serde(deserialize_with = "required")]
    pub steady_contact_bv_percent: Option<f64>,
}

/// A key that must be present, its value a number or null (serde's derive treats a missing
/// `Option` as `None` unless the field has its own deserializer).
fn required<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    Option::<f64>::deserialize(d)
}

/// The result of one `[three_dof]` instance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThreeDofResult {
    /// Every case, in the instance's case order (the `cases` table's rows).
    pub cases: Vec<ThreeDofCaseResult>,
    pub case_keys: Vec<String>,
    pub table: String,
    /// The bulge the cases ran with, when it came from a fit (docs/bulge.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fitted_bulge: Option<FittedBulge>,
}

/// A fitted bulge design, m.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FittedBulge {
    pub a_tfc_m: f64,
    pub w_tfc_m: f64,
    pub x_tfc_m: f64,
}

/// Each feature's closest approach, nm, by its column name (`pad_plus_y`), written as
/// `min_spacing_<feature>_nm` keys in feature order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MinSpacings(pub Vec<(String, Option<f64>)>);

const MIN_SPACING: (&str, &str) = ("min_spacing_", "_nm");

impl MinSpacings {
    /// The closest approach of the feature with column name `feature`.
    pub fn get(&self, feature: &str) -> Option<Option<f64>> {
        self.0.iter().find(|(f, _)| f == feature).map(|(_, v)| *v)
    }
}

impl Serialize for MinSpacings {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (f, v) in &self.0 {
            m.serialize_entry(&format!("{}{f}{}", MIN_SPACING.0, MIN_SPACING.1), v)?;
        }
        m.end()
    }
}

impl<'de> Deserialize<'de> for MinSpacings {
    /// Takes the `min_spacing_…_nm` keys of the object (the other flattened keys belong to
    /// other fields).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = MinSpacings;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("min_spacing_<feature>_nm keys")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut a: A,
            ) -> Result<MinSpacings, A::Error> {
                let mut out = Vec::new();
                while let Some(k) = a.next_key::<String>()? {
                    let feature = k
                        .strip_prefix(MIN_SPACING.0)
                        .and_then(|r| r.strip_suffix(MIN_SPACING.1));
                    match feature {
                        Some(f) => out.push((f.to_string(), a.next_value::<Option<f64>>()?)),
                        None => {
                            a.next_value::<serde::de::IgnoredAny>()?;
                        }
                    }
                }
                Ok(MinSpacings(out))
            }
        }
        d.deserialize_map(Visit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A case result reads back and writes the same bytes, with and without the Table 4.4
    /// and severity keys.
    #[test]
    fn a_case_result_round_trips_byte_for_byte() {
        let base = r#"{"pole_tip_mean_nm":1.5,"pole_tip_std_nm":0.1,"bulge_spacing_mean_nm":2.0,"bulge_spacing_std_nm":0.2,"bulge_vibration_percent":null,"roll_std_urad":0.3,"solid_contact_percent":0.0,"lubricant_contact_percent":0.0,"peak_contact_force_mN":0.0,"peak_lubricant_force_mN":0.0,"mean_contact_force_mN":0.0,"mean_friction_mN":0.0,"features_in_solid_contact":"","ab_lost_samples":0,"min_spacing_bulge_nm":3.5,"min_spacing_pad_plus_y_nm":null"#;
        let variants = [
            format!(r#"{base},"case":"isbl","steps":12}}"#),
            format!(
                r#"{base},"friction_coefficient":0.2,"first_lubricant_contact_ms":null,"flying_fhm_percent":1.0,"jump_to_contact_bv_percent":null,"steady_contact_bv_percent":2.0,"case":"mtl_reference","steps":7}}"#
            ),
        ];
        for text in variants {
            let r: ThreeDofCaseResult = serde_json::from_str(&text).unwrap();
            assert_eq!(serde_json::to_string(&r).unwrap(), text);
        }
    }
}
