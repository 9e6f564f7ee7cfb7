//! `[three_dof]` settings: the raw `pipeline.toml` table (`ThreeDofConfig`), its check into
//! `ThreeDofParams` (scenario, interfaces and lubricant cases of Table 4.4, options) and the
//! canonical parameters that key the instance. The 3-DOF stage runs them; `[analysis]`
//! resolves a 3-DOF source's case files through here.

use crate::contact::mtl::LubricantCase;
use crate::core::config::KeyError;
use crate::dynamics::geometry::BulgeDesign;
use crate::dynamics::three_dof::air_bearing::{
    NominalForce, PushbackCurve, RollSpring, SpringLaw, StiffnessArgument,
};
use crate::dynamics::three_dof::case::{Init3Dof, Model3Dof, Options3Dof, TrackAssignment};
use crate::dynamics::three_dof::inputs::{ActuationProfile, ShockPulse};
use crate::dynamics::two_dof::ContactForceForm;
use crate::slider::params::GeometryConfig;
use crate::units::{Length, TimeSpan};
use serde::Deserialize;
use serde_json::{json, Value};

fn default_none() -> String {
    "none".into()
}
fn default_scenario() -> String {
    "constant".into()
}
fn default_interfaces() -> Vec<String> {
    vec!["isbl".into()]
}
fn default_lubricants() -> Vec<String> {
    vec!["reference".into()]
}
fn default_duration() -> TimeSpan {
    TimeSpan(2e-3)
}
fn default_steady() -> TimeSpan {
    TimeSpan(0.5e-3)
}
fn default_output_step() -> TimeSpan {
    TimeSpan(0.25e-6)
}
fn default_shock_start() -> TimeSpan {
    TimeSpan(0.6e-3)
}
fn default_shock_duration() -> TimeSpan {
    TimeSpan(5e-6)
}
fn default_shock_impulse() -> f64 {
    0.25e-6
}
fn default_true() -> bool {
    true
}
fn default_word(w: &str) -> String {
    w.to_string()
}
fn default_tracks() -> String {
    default_word("three")
}
fn default_pushback() -> String {
    default_word("linear")
}
fn default_contact_force() -> String {
    default_word("interference_tangent")
}

/// `[three_dof.NAME]` as written in `pipeline.toml`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ThreeDofConfig {
    /// The `[contact.*]` instance whose ISBL interface the features use (σ, R, η, H, t).
    pub contact: String,
    /// A `[dmw.*]` or `[excitation.*]` instance (tracks D1–D3) or `none`.
    #[serde(default = "default_none")]
    pub dmw: String,
    /// `constant` (S3), `shock` (S4) or `variable` (S5/S6).
    #[serde(default = "default_scenario")]
    pub scenario: String,
    /// Constant / shock actuation (default 12 nm constant, 5 nm shock).
    #[serde(default)]
    pub actuation: Option<Length>,
    /// Variable scenario: `[["0 ms", "5 nm"], ["0.2 ms", "5 nm"], …]` (default the S5 profile).
    #[serde(default)]
    pub profile: Option<Vec<(TimeSpan, Length)>>,
    /// Any of `isbl`, `mtl`: one case each (MTL once per lubricant).
    #[serde(default = "default_interfaces")]
    pub interfaces: Vec<String>,
    /// Table 4.4 cases for the MTL runs: `reference`, `humidity_temperature`, `more_bonding`,
    /// `larger_gyration_radius`.
    #[serde(default = "default_lubricants")]
    pub lubricants: Vec<String>,
    #[serde(default = "default_duration")]
    pub duration: TimeSpan,
    #[serde(default = "default_steady")]
    pub steady_start: TimeSpan,
    #[serde(default = "default_output_step")]
    pub output_step: TimeSpan,
    #[serde(default = "default_shock_start")]
    pub shock_start: TimeSpan,
    #[serde(default = "default_shock_duration")]
    pub shock_duration: TimeSpan,
    /// Impulse of the shock [N·s] (0.25 µN·s).
    #[serde(default = "default_shock_impulse")]
    pub shock_impulse: f64,
    /// The air bearing's reading of eqs. 4.8–4.14 as a whole: `hdi` (default: the four
    /// `ab_*` readings below at their defaults) or `faithful` (all four as printed, and the
    /// run starting from the nominal state as §4.1.1 prints it). Each `ab_*` key and `init`
    /// written in the table override the preset.
    #[serde(default)]
    pub air_bearing: Option<String>,
    /// `integrated` (default, stable) or `linear` (eqs. 4.11–4.14 as printed).
    #[serde(default)]
    pub ab_spring_law: Option<String>,
    /// `balanced` (default: F_f,0 + F_r,0 = F with the moment balanced) or `as_printed`
    /// (eqs. 4.11–4.12: `k_j,nom·FH_nom`).
    #[serde(default)]
    pub ab_nominal_force: Option<String>,
    /// The PT that sets `k(PT)`: `rear_spring_disk` (default: the read element over the disk
    /// under the rear spring), `pole_tip` (over its own disk, as printed) or `static_pole_tip`
    /// (the push-back calibration's static PT at the current actuation).
    #[serde(default)]
    pub ab_stiffness_argument: Option<String>,
    /// What the roll spring acts on: `disk_relative` (default: φ − φ_d) or `absolute` (φ, as
    /// printed).
    #[serde(default)]
    pub ab_roll_spring: Option<String>,
    /// Contact damping ratio ζ_c of every feature (Table 4.1, value not printed; default 0.05).
    #[serde(default)]
    pub contact_damping_ratio: Option<f64>,
    /// `linear` (ΔFH = 0.5·h) or `flattened` (above 12 nm, docs/dynamics-3dof-air-bearing.md).
    #[serde(default = "default_pushback")]
    pub pushback_curve: String,
    /// Reading of eq. 2.16 on every feature: `interference_tangent` (default), `static_curve`
    /// or `integrated_stiffness` (docs/model-form.md).
    #[serde(default = "default_contact_force")]
    pub contact_force: String,
    /// `static` (the push-back already in place; the default) or `nominal` (the nominal state,
    /// as printed in §4.1.1; the default under `air_bearing = "faithful"`).
    #[serde(default)]
    pub init: Option<String>,
    /// Heave offset of the start state, e.g. `"1 nm"` (|z0| ≤ 5 nm; default none): a kick whose
    /// free decay shows the heave/pitch AB modes (App. B's zero excitation; the Table 4.1
    /// initial roll of −10 µrad only rings the roll mode).
    #[serde(default)]
    pub initial_heave: Option<Length>,
    /// `three` (D1 centre, D2 +y, D3 −y) or `one` (D1 everywhere).
    #[serde(default = "default_tracks")]
    pub tracks: String,
    #[serde(default = "default_true")]
    pub transit_delay: bool,
    #[serde(default)]
    pub dmw_wrap: bool,
    /// `"dissertation"` (Table 4.3, default) or `{ bulge = "NAME" }`: a_TFC, w_TFC and x_TFC
    /// from a `[bulge.NAME]` fit (docs/bulge.md); b_TFC stays 5 nm.
    #[serde(default)]
    pub geometry: Option<GeometryConfig>,
}

/// One case of an instance: the interface law and its lubricant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CaseInterface {
    Isbl,
    Mtl(LubricantCase),
}

impl CaseInterface {
    pub fn label(&self) -> String {
        match self {
            CaseInterface::Isbl => "isbl".into(),
            CaseInterface::Mtl(l) => format!("mtl_{}", lubricant_name(*l)),
        }
    }
}

fn lubricant_name(l: LubricantCase) -> &'static str {
    match l {
        LubricantCase::Reference => "reference",
        LubricantCase::HumidityTemperature => "humidity_temperature",
        LubricantCase::MoreBonding => "more_bonding",
        LubricantCase::LargerGyrationRadius => "larger_gyration_radius",
    }
}

/// Validated parameters (SI).
#[derive(Debug, Clone, PartialEq)]
pub struct ThreeDofParams {
    pub contact: String,
    pub dmw: Option<String>,
    pub scenario: String,
    pub profile: ActuationProfile,
    pub shock: Option<ShockPulse>,
    pub cases: Vec<CaseInterface>,
    pub options: Options3Dof,
    pub steady_start: f64,
    /// The air bearing's readings (`air_bearing` preset and the `ab_*` keys).
    pub readings: AbReadings,
    pub pushback: String,
    /// ζ_c of every feature's contact damper.
    pub contact_damping_ratio: f64,
    /// Reading of eq. 2.16 on the features (docs/model-form.md).
    pub contact_force: ContactForceForm,
    /// The `[bulge.*]` instance whose fitted a, w, x_TFC replace Table 4.3's at run time.
    pub bulge: Option<String>,
    /// That fit, once read from the upstream result (not part of the key: the bulge
    /// instance's key is).
    pub fitted: Option<BulgeDesign>,
}

/// The contact damping ratio ζ_c the stage has always used (Table 4.1's value is not printed).
pub const DEFAULT_CONTACT_DAMPING_RATIO: f64 = 0.05;

/// The four readings of eqs. 4.8–4.14 where hdi departs from the printed text
/// (docs/model-form.md, "Misses 4 and 5").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct AbReadings {
    pub spring_law: SpringLaw,
    pub nominal_force: NominalForce,
    pub stiffness_argument: StiffnessArgument,
    pub roll_spring: RollSpring,
}

impl AbReadings {
    /// `air_bearing = "faithful"`: all four as printed.
    pub fn faithful() -> Self {
        AbReadings {
            spring_law: SpringLaw::Linear,
            nominal_force: NominalForce::AsPrinted,
            stiffness_argument: StiffnessArgument::PoleTip,
            roll_spring: RollSpring::Absolute,
        }
    }

    /// Put the readings into the air bearing's parameters.
    pub fn apply(&self, ab: &mut crate::dynamics::three_dof::air_bearing::ThreeDofAbParams) {
        ab.spring_law = self.spring_law;
        ab.nominal_force = self.nominal_force;
        ab.stiffness_argument = self.stiffness_argument;
        ab.roll_spring = self.roll_spring;
    }
}

/// One `ab_*` key: its value (or the preset's) parsed through `words`.
fn reading<T: Copy>(
    key: &str,
    value: &Option<String>,
    preset: T,
    words: &[(&str, T)],
) -> std::result::Result<T, KeyError> {
    let Some(v) = value else {
        return Ok(preset);
    };
    words
        .iter()
        .find(|(w, _)| w == v)
        .map(|(_, t)| *t)
        .ok_or_else(|| {
            let list: Vec<&str> = words.iter().map(|(w, _)| *w).collect();
            KeyError::new(key, format!("unknown `{v}` ({})", list.join(", ")))
        })
}

/// `air_bearing` (the preset), then each `ab_*` key over it.
fn check_readings(cfg: &ThreeDofConfig) -> std::result::Result<AbReadings, KeyError> {
    let preset = match cfg.air_bearing.as_deref() {
        None | Some("hdi") => AbReadings::default(),
        Some("faithful") => AbReadings::faithful(),
        Some(o) => return bad("air_bearing", format!("unknown `{o}` (hdi, faithful)")),
    };
    Ok(AbReadings {
        spring_law: reading(
            "ab_spring_law",
            &cfg.ab_spring_law,
            preset.spring_law,
            &[
                ("integrated", SpringLaw::Integrated),
                ("linear", SpringLaw::Linear),
            ],
        )?,
        nominal_force: reading(
            "ab_nominal_force",
            &cfg.ab_nominal_force,
            preset.nominal_force,
            &[
                ("balanced", NominalForce::Balanced),
                ("as_printed", NominalForce::AsPrinted),
            ],
        )?,
        stiffness_argument: reading(
            "ab_stiffness_argument",
            &cfg.ab_stiffness_argument,
            preset.stiffness_argument,
            &[
                ("rear_spring_disk", StiffnessArgument::RearSpringDisk),
                ("pole_tip", StiffnessArgument::PoleTip),
                ("static_pole_tip", StiffnessArgument::StaticPoleTip),
            ],
        )?,
        roll_spring: reading(
            "ab_roll_spring",
            &cfg.ab_roll_spring,
            preset.roll_spring,
            &[
                ("disk_relative", RollSpring::DiskRelative),
                ("absolute", RollSpring::Absolute),
            ],
        )?,
    })
}

/// A failed `[three_dof]` check at `key`.
fn bad<T>(key: &str, m: impl Into<String>) -> std::result::Result<T, KeyError> {
    Err(KeyError::new(key, m))
}

/// `scenario` with its `actuation` or `profile` and shock pulse; the actuation must reach
/// the bulge bottom.
fn check_actuation(
    cfg: &ThreeDofConfig,
) -> std::result::Result<(ActuationProfile, Option<ShockPulse>), KeyError> {
    let nm = 1e-9;
    let (profile, shock) = match cfg.scenario.as_str() {
        "constant" | "shock" => {
            if cfg.profile.is_some() {
                return bad("profile", "only the `variable` scenario takes a profile");
            }
            let default = if cfg.scenario == "shock" { 5.0 } else { 12.0 };
            let h = cfg.actuation.map_or(default * nm, |l| l.0);
            let p = ActuationProfile::constant(h)
                .map_err(|e| KeyError::new("actuation", e.to_string()))?;
            let shock = if cfg.scenario == "shock" {
                Some(
                    ShockPulse::from_impulse(
                        cfg.shock_start.0,
                        cfg.shock_duration.0,
                        cfg.shock_impulse,
                    )
                    .map_err(|e| KeyError::new("shock_impulse", e.to_string()))?,
                )
            } else {
                None
            };
            (p, shock)
        }
        "variable" => {
            if cfg.actuation.is_some() {
                return bad(
                    "actuation",
                    "the `variable` scenario takes a `profile` instead",
                );
            }
            let p = match &cfg.profile {
                None => ActuationProfile::variable_default(),
                Some(points) => {
                    ActuationProfile::table(points.iter().map(|(t, h)| (t.0, h.0)).collect())
                        .map_err(|e| KeyError::new("profile", e.to_string()))?
                }
            };
            (p, None)
        }
        o => {
            return bad(
                "scenario",
                format!("unknown `{o}` (constant, shock, variable)"),
            )
        }
    };
    let b = Model3Dof::dissertation().geometry.bulge_height;
    if profile.range().0 < b {
        let key = if cfg.scenario == "variable" {
            "profile"
        } else {
            "actuation"
        };
        return bad(
            key,
            format!(
                "{:.2} nm is below the bulge height b_TFC = {:.0} nm (the 3-DOF actuation is the \
                 bulge bottom's total protrusion)",
                profile.range().0 * 1e9,
                b * 1e9
            ),
        );
    }
    Ok((profile, shock))
}

/// `interfaces` and, for the MTL runs, `lubricants`: the cases, each once.
fn check_cases(cfg: &ThreeDofConfig) -> std::result::Result<Vec<CaseInterface>, KeyError> {
    let mut cases = Vec::new();
    if cfg.interfaces.is_empty() {
        return bad("interfaces", "name at least one of isbl, mtl");
    }
    for i in &cfg.interfaces {
        match i.as_str() {
            "isbl" => cases.push(CaseInterface::Isbl),
            "mtl" => {
                if cfg.lubricants.is_empty() {
                    return bad(
                        "lubricants",
                        "the MTL runs need at least one lubricant case",
                    );
                }
                for l in &cfg.lubricants {
                    let case = LubricantCase::ALL
                        .into_iter()
                        .find(|c| lubricant_name(*c) == l)
                        .ok_or_else(|| {
                            KeyError::new(
                                "lubricants",
                                format!(
                                    "unknown `{l}` (reference, humidity_temperature, more_bonding, \
                                     larger_gyration_radius)"
                                ),
                            )
                        })?;
                    cases.push(CaseInterface::Mtl(case));
                }
            }
            o => return bad("interfaces", format!("unknown `{o}` (isbl, mtl)")),
        }
    }
    let mut seen = Vec::new();
    for c in &cases {
        if seen.contains(c) {
            return bad("interfaces", format!("`{}` listed twice", c.label()));
        }
        seen.push(*c);
    }
    Ok(cases)
}

/// `pushback_curve`, then the integrator options (`init`, `tracks`, `duration`, steps),
/// `steady_start` and the shock pulse's end within `duration`.
fn check_options(
    cfg: &ThreeDofConfig,
    shock: Option<&ShockPulse>,
) -> std::result::Result<Options3Dof, KeyError> {
    if !matches!(cfg.pushback_curve.as_str(), "linear" | "flattened") {
        return bad(
            "pushback_curve",
            format!("unknown `{}` (linear, flattened)", cfg.pushback_curve),
        );
    }
    // The printed initial state is the nominal one ("the initial front and rear AB spring FH
    // are equal to the nominal value", §4.1.1): the faithful preset's default.
    let preset_init = match cfg.air_bearing.as_deref() {
        Some("faithful") => "nominal",
        _ => "static",
    };
    let init = match cfg.init.as_deref().unwrap_or(preset_init) {
        "static" => Init3Dof::AirBearingStatic,
        "nominal" => Init3Dof::Nominal,
        o => return bad("init", format!("unknown `{o}` (static, nominal)")),
    };
    let tracks = match cfg.tracks.as_str() {
        "three" => TrackAssignment::Three,
        "one" => TrackAssignment::One,
        o => return bad("tracks", format!("unknown `{o}` (three, one)")),
    };
    let initial_heave = cfg.initial_heave.map_or(0.0, |l| l.0);
    if !(initial_heave.is_finite() && initial_heave.abs() <= 5e-9) {
        return bad(
            "initial_heave",
            format!("{initial_heave} m is out of range: |z0| ≤ 5 nm"),
        );
    }
    let options = Options3Dof {
        duration: cfg.duration.0,
        output_step: cfg.output_step.0,
        transit_delay: cfg.transit_delay,
        wrap_dmw: cfg.dmw_wrap,
        tracks,
        init,
        initial_heave,
        ..Options3Dof::default()
    };
    options
        .validate()
        .map_err(|e| KeyError::new("duration", e.to_string()))?;
    if !(cfg.steady_start.0 >= 0.0 && cfg.steady_start.0 < cfg.duration.0) {
        return bad("steady_start", "must lie in [0, duration)");
    }
    if let Some(s) = shock {
        if s.start + s.duration > cfg.duration.0 {
            return bad("shock_start", "the pulse must end before `duration`");
        }
    }
    Ok(options)
}

/// `contact_force`: the reading of eq. 2.16 on the features.
fn check_contact_force(cfg: &ThreeDofConfig) -> std::result::Result<ContactForceForm, KeyError> {
    match cfg.contact_force.as_str() {
        "interference_tangent" => Ok(ContactForceForm::InterferenceTangent),
        "static_curve" => Ok(ContactForceForm::StaticCurve),
        "integrated_stiffness" => Ok(ContactForceForm::IntegratedStiffness),
        o => bad(
            "contact_force",
            format!("unknown `{o}` (interference_tangent, static_curve, integrated_stiffness)"),
        ),
    }
}

impl ThreeDofParams {
    /// Check a `[three_dof]` table key by key (no cross-references to other instances): the
    /// actuation scenario, the interface cases, then the options.
    pub fn check(cfg: &ThreeDofConfig) -> std::result::Result<ThreeDofParams, KeyError> {
        let dmw = (cfg.dmw != "none").then(|| cfg.dmw.clone());
        let (profile, shock) = check_actuation(cfg)?;
        let cases = check_cases(cfg)?;
        let readings = check_readings(cfg)?;
        let options = check_options(cfg, shock.as_ref())?;
        let contact_force = check_contact_force(cfg)?;
        let contact_damping_ratio = cfg
            .contact_damping_ratio
            .unwrap_or(DEFAULT_CONTACT_DAMPING_RATIO);
        if !(0.0..=10.0).contains(&contact_damping_ratio) {
            return bad("contact_damping_ratio", "must lie in [0, 10]");
        }
        let bulge = match &cfg.geometry {
            None => None,
            Some(GeometryConfig::Named(n)) if n == "dissertation" => None,
            Some(GeometryConfig::Named(n)) => {
                return bad(
                    "geometry",
                    format!("unknown geometry `{n}` (dissertation, or {{ bulge = \"NAME\" }})"),
                )
            }
            Some(GeometryConfig::Bulge { bulge }) => Some(bulge.clone()),
        };
        Ok(ThreeDofParams {
            contact: cfg.contact.clone(),
            dmw,
            scenario: cfg.scenario.clone(),
            profile,
            shock,
            cases,
            options,
            steady_start: cfg.steady_start.0,
            readings,
            pushback: cfg.pushback_curve.clone(),
            contact_damping_ratio,
            contact_force,
            bulge,
            fitted: None,
        })
    }
    /// Canonical parameters (part of the instance key).
    pub fn canonical(&self) -> Value {
        let o = &self.options;
        let mut v = json!({
            "contact": self.contact,
            "dmw": self.dmw,
            "scenario": self.scenario,
            "profile_s_m": self.profile.points(),
            "shock": self.shock.map(|s| json!({"start_s": s.start, "duration_s": s.duration, "peak_N": s.peak})),
            "cases": self.cases.iter().map(|c| c.label()).collect::<Vec<_>>(),
            "duration_s": o.duration,
            "output_step_s": o.output_step,
            "steady_start_s": self.steady_start,
            "transit_delay": o.transit_delay,
            "dmw_wrap": o.wrap_dmw,
            "tracks": o.tracks,
            "init": o.init,
            "ab_spring_law": self.readings.spring_law,
            "pushback_curve": self.pushback,
        });
        // Only instances with a fitted bulge carry the key: the others keep theirs.
        if let (Some(b), Some(obj)) = (&self.bulge, v.as_object_mut()) {
            obj.insert("bulge".into(), json!(b));
        }
        // Likewise a heave kick at the start (App. B's zero excitation).
        if let (true, Some(obj)) = (o.initial_heave != 0.0, v.as_object_mut()) {
            obj.insert("initial_heave_m".into(), json!(o.initial_heave));
        }
        // Likewise a non-default contact-force reading.
        if let (ContactForceForm::StaticCurve | ContactForceForm::IntegratedStiffness, Some(obj)) =
            (self.contact_force, v.as_object_mut())
        {
            obj.insert("contact_force".into(), json!(self.contact_force));
        }
        // Likewise the other readings of eqs. 4.8–4.14 and ζ_c, each only off its default.
        let r = &self.readings;
        let d = AbReadings::default();
        if let Some(obj) = v.as_object_mut() {
            if r.nominal_force != d.nominal_force {
                obj.insert("ab_nominal_force".into(), json!(r.nominal_force));
            }
            if r.stiffness_argument != d.stiffness_argument {
                obj.insert("ab_stiffness_argument".into(), json!(r.stiffness_argument));
            }
            if r.roll_spring != d.roll_spring {
                obj.insert("ab_roll_spring".into(), json!(r.roll_spring));
            }
            if self.contact_damping_ratio != DEFAULT_CONTACT_DAMPING_RATIO {
                obj.insert(
                    "contact_damping_ratio".into(),
                    json!(self.contact_damping_ratio),
                );
            }
        }
        v
    }

    /// The dissertation's 3-DOF model with this instance's air-bearing readings and push-back
    /// curve.
    pub fn model(&self) -> Model3Dof {
        let mut m = Model3Dof::dissertation();
        self.readings.apply(&mut m.air_bearing);
        if self.pushback == "flattened" {
            m.pushback = PushbackCurve::flattened();
        }
        // A fitted bulge replaces a_TFC, w_TFC, x_TFC in the geometry and the air bearing's
        // copies (the stiffening point and read element sit at the TFC centre, Table 4.3).
        if let Some(d) = self.fitted {
            m.geometry.bulge = d;
            m.air_bearing.tfc_offset_from_te = d.offset_from_te;
            m.air_bearing.bulge_semi_width_x = d.semi_width_x;
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(toml_text: &str) -> ThreeDofParams {
        let cfg: ThreeDofConfig = toml::from_str(toml_text).unwrap();
        ThreeDofParams::check(&cfg).unwrap()
    }

    #[test]
    fn dissertation_geometry_keeps_its_canonical_parameters() {
        // The canonical parameters an instance was keyed by before `geometry` existed: with no
        // geometry or "dissertation" they must be exactly these (cached outputs stay valid).
        let before = json!({
            "contact": "c", "dmw": null, "scenario": "constant",
            "profile_s_m": [[0.0, 12e-9]], "shock": null, "cases": ["isbl"],
            "duration_s": 0.5e-3, "output_step_s": 1e-6, "steady_start_s": 0.2e-3,
            "transit_delay": true, "dmw_wrap": false,
            "tracks": "three", "init": "air_bearing_static",
            "ab_spring_law": "integrated", "pushback_curve": "linear",
        });
        let base = "contact = \"c\"\nactuation = \"12 nm\"\ninterfaces = [\"isbl\"]\nduration = \"0.5 ms\"\nsteady_start = \"0.2 ms\"\noutput_step = \"1 us\"";
        let plain = params(base);
        let named = params(&format!("{base}\ngeometry = \"dissertation\""));
        let keys = |v: &Value| -> Vec<String> { v.as_object().unwrap().keys().cloned().collect() };
        assert_eq!(keys(&plain.canonical()), keys(&before));
        // The enums as their snake_case names (plain data, docs/architecture.md).
        for k in ["tracks", "init", "ab_spring_law"] {
            assert_eq!(plain.canonical()[k], before[k], "{k}");
        }
        assert_eq!(plain.canonical(), named.canonical());
        assert_eq!(plain.model(), Model3Dof::dissertation());
        // The fitted bulge: its instance joins the key, and its a, w, x replace Table 4.3's.
        let mut fitted = params(&format!("{base}\ngeometry = {{ bulge = \"tfc\" }}"));
        assert_eq!(fitted.canonical()["bulge"], "tfc");
        let d = BulgeDesign {
            semi_width_x: 4.86e-6,
            full_width_y: 50e-6,
            offset_from_te: 6.35e-6,
        };
        fitted.fitted = Some(d);
        let m = fitted.model();
        assert_eq!(m.geometry.bulge, d);
        assert_eq!(m.air_bearing.tfc_offset_from_te, 6.35e-6);
        assert_eq!(m.air_bearing.bulge_semi_width_x, 4.86e-6);
        assert_eq!(m.geometry.bulge_height, 5e-9);
        let cfg: ThreeDofConfig =
            toml::from_str(&format!("{base}\ngeometry = \"optimised\"")).unwrap();
        assert_eq!(ThreeDofParams::check(&cfg).unwrap_err().key, "geometry");
    }

    #[test]
    fn contact_force_reading_parses_and_keys_only_when_not_the_default() {
        let base = "contact = \"c\"\nscenario = \"shock\"\nduration = \"1.5 ms\"";
        let plain = params(base);
        assert_eq!(plain.contact_force, ContactForceForm::InterferenceTangent);
        // The default leaves the instance key as it was (cached outputs stay valid).
        assert!(plain.canonical().get("contact_force").is_none());
        let soft = params(&format!("{base}\ncontact_force = \"integrated_stiffness\""));
        assert_eq!(soft.contact_force, ContactForceForm::IntegratedStiffness);
        assert_eq!(soft.canonical()["contact_force"], "integrated_stiffness");
        assert_ne!(soft.canonical(), plain.canonical());
        let cfg: ThreeDofConfig =
            toml::from_str(&format!("{base}\ncontact_force = \"hertz\"")).unwrap();
        let e = ThreeDofParams::check(&cfg).unwrap_err();
        assert_eq!(e.key, "contact_force");
        assert!(e.message.contains("hertz") && e.message.contains("static_curve"));
    }

    #[test]
    fn initial_heave_kicks_the_start_and_keys_only_when_set() {
        let base = "contact = \"c\"\ndmw = \"still\"";
        let plain = params(base);
        assert_eq!(plain.options.initial_heave, 0.0);
        // Unset leaves the instance key as it was (cached outputs stay valid).
        assert!(plain.canonical().get("initial_heave_m").is_none());
        let kicked = params(&format!("{base}\ninitial_heave = \"1 nm\""));
        assert_eq!(kicked.options.initial_heave, 1e-9);
        assert_eq!(kicked.canonical()["initial_heave_m"], 1e-9);
        let cfg: ThreeDofConfig =
            toml::from_str(&format!("{base}\ninitial_heave = \"6 nm\"")).unwrap();
        let e = ThreeDofParams::check(&cfg).unwrap_err();
        assert_eq!(e.key, "initial_heave");
        assert!(e.message.contains("5 nm"), "{}", e.message);
    }

    #[test]
    fn air_bearing_readings_preset_overrides_and_keys() {
        let base = "contact = \"c\"\nscenario = \"shock\"\nduration = \"1.5 ms\"";
        let plain = params(base);
        assert_eq!(plain.readings, AbReadings::default());
        assert_eq!(plain.options.init, Init3Dof::AirBearingStatic);
        assert_eq!(plain.contact_damping_ratio, DEFAULT_CONTACT_DAMPING_RATIO);
        // `hdi` and the defaults written out leave the instance key as it was.
        let written = params(&format!(
            "{base}\nair_bearing = \"hdi\"\nab_spring_law = \"integrated\"\n\
             ab_nominal_force = \"balanced\"\nab_stiffness_argument = \"rear_spring_disk\"\n\
             ab_roll_spring = \"disk_relative\"\ncontact_damping_ratio = 0.05\ninit = \"static\""
        ));
        assert_eq!(written.canonical(), plain.canonical());
        // The preset: all four as printed, started from the nominal state.
        let faithful = params(&format!("{base}\nair_bearing = \"faithful\""));
        assert_eq!(faithful.readings, AbReadings::faithful());
        assert_eq!(faithful.options.init, Init3Dof::Nominal);
        let m = faithful.model();
        assert_eq!(m.air_bearing.spring_law, SpringLaw::Linear);
        assert_eq!(m.air_bearing.nominal_force, NominalForce::AsPrinted);
        assert_eq!(m.air_bearing.stiffness_argument, StiffnessArgument::PoleTip);
        assert_eq!(m.air_bearing.roll_spring, RollSpring::Absolute);
        let c = faithful.canonical();
        assert_eq!(c["ab_spring_law"], "linear");
        assert_eq!(c["ab_nominal_force"], "as_printed");
        assert_eq!(c["ab_stiffness_argument"], "pole_tip");
        assert_eq!(c["ab_roll_spring"], "absolute");
        assert_eq!(c["init"], "nominal");
        // A key written in the table overrides the preset.
        let mixed = params(&format!(
            "{base}\nair_bearing = \"faithful\"\nab_spring_law = \"integrated\"\ninit = \"static\""
        ));
        assert_eq!(mixed.readings.spring_law, SpringLaw::Integrated);
        assert_eq!(mixed.readings.nominal_force, NominalForce::AsPrinted);
        assert_eq!(mixed.options.init, Init3Dof::AirBearingStatic);
        // One switch alone keys only itself.
        let one = params(&format!("{base}\nab_roll_spring = \"absolute\""));
        let keys = |v: &Value| -> Vec<String> { v.as_object().unwrap().keys().cloned().collect() };
        let mut expected = keys(&plain.canonical());
        expected.push("ab_roll_spring".into());
        assert_eq!(keys(&one.canonical()), expected);
        let zeta = params(&format!("{base}\ncontact_damping_ratio = 0.3"));
        assert_eq!(zeta.canonical()["contact_damping_ratio"], 0.3);
        // Unknown values are refused at their key, naming the choices.
        for (key, bad_value) in [
            ("air_bearing", "\"printed\""),
            ("ab_spring_law", "\"cubic\""),
            ("ab_nominal_force", "\"faithful\""),
            ("ab_stiffness_argument", "\"read_element\""),
            ("ab_roll_spring", "\"relative\""),
            ("contact_damping_ratio", "-0.1"),
        ] {
            let cfg: ThreeDofConfig =
                toml::from_str(&format!("{base}\n{key} = {bad_value}")).unwrap();
            let e = ThreeDofParams::check(&cfg).unwrap_err();
            assert_eq!(e.key, key, "{key}");
        }
        let cfg: ThreeDofConfig =
            toml::from_str(&format!("{base}\nab_roll_spring = \"relative\"")).unwrap();
        let e = ThreeDofParams::check(&cfg).unwrap_err();
        assert!(
            e.message.contains("disk_relative, absolute"),
            "{}",
            e.message
        );
    }
}
