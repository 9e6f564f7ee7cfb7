//! One 2-DOF slider case (dissertation §2.2, Figs 2.13–2.14): run it, summarise it as the
//! case's `result.json` (its metrics) and write its time histories as `case.h5`; read them
//! back for the plots. The simulate and DOE stages, the Slurm worker and `hdi simulate` run
//! cases through here, under one case-cache model version.

pub use crate::artefacts::cases::{Stats, SweepCaseResult};
use crate::artefacts::dmw_tracks::DmwTrack;
use crate::contact::lookup::IsblLookup;
use crate::core::store::H5Out;
use crate::dynamics::metrics::{CaseMetrics, Regime, VibrationKind};
use crate::dynamics::two_dof::{CaseHistory, DmwInput, TwoDofCase};
use crate::error::{Error, Result};
use crate::slider::params::SimulateParams;
use serde_json::Value;
use std::path::Path;

/// Bump when the numbers a case produces change (it keys every 2-DOF case and is the
/// simulate stage's model version).
/// simulate-4: the case and instance keys hold the model and options as plain JSON fields
/// instead of Rust Debug strings (same numbers; docs/architecture.md).
pub const MODEL_VERSION: &str = "simulate-4";

/// A case's time histories inside its case-cache entry.
pub const CASE_FILE: &str = "case.h5";

/// Simulate one case and write its HDF5 (time histories) into `dir`; returns its result.
pub fn simulate_case(
    p: &SimulateParams,
    actuation: f64,
    isbl: &IsblLookup,
    dmw: Option<&DmwTrack>,
    dir: &Path,
) -> Result<Value> {
    let input = dmw.map(|t| DmwInput {
        displacement: &t.displacement,
        velocity: &t.velocity,
        sample_rate: t.sample_rate,
    });
    let case = TwoDofCase::new(&p.model, actuation, isbl, input, p.options)?;
    let h = case.run()?;
    let m = h.metrics(&p.case_metric_params())?;
    write_case_h5(&dir.join(CASE_FILE), &h, actuation, &m)?;
    Ok(SweepCaseResult::new(actuation, &h, &m, case.contact_damping()).to_json())
}

impl From<&crate::dynamics::metrics::SeriesStats> for Stats {
    fn from(s: &crate::dynamics::metrics::SeriesStats) -> Self {
        Stats {
            mean: s.mean,
            std: s.std,
            min: s.min,
            max: s.max,
        }
    }
}

impl SweepCaseResult {
    pub fn new(actuation: f64, h: &CaseHistory, m: &CaseMetrics, c_c: f64) -> Self {
        let c = m.contact.as_ref();
        let opt = |v: Option<f64>| v.filter(|x| x.is_finite());
        SweepCaseResult {
            actuation_m: actuation,
            nominal_area_m2: h.nominal_area,
            contact_damping_N_s_per_m: c_c,
            clearance_m: (&m.clearance_m).into(),
            fh_m: (&m.fh_m).into(),
            hms_mean_m: m.hms_mean_m,
            vibration_percent: m.vibration.percent,
            vibration_extrema_percent: m.vibration_extrema.as_ref().map(|v| v.percent),
            vibration_kind: vibration_kind_name(m.vibration_kind).to_string(),
            percent_solid_contact: m.percent_solid_contact,
            regime: regime_name(m.regime).to_string(),
            contact_force_N: c.map(|c| (&c.contact_force_n).into()),
            friction_N: c.map(|c| (&c.friction_n).into()),
            real_area_m2: c.map(|c| (&c.real_area_m2).into()),
            adhesion_N: c.and_then(|c| c.adhesion_n.as_ref().map(Stats::from)),
            friction_coefficient: c.and_then(|c| opt(c.friction_coefficient_ratio_of_means)),
            friction_coefficient_ratio_of_means: c
                .and_then(|c| opt(c.friction_coefficient_ratio_of_means)),
            friction_coefficient_mean_inst: c
                .and_then(|c| c.friction_coefficient.as_ref().map(|s| s.mean)),
            mean_pressure_Pa: c.and_then(|c| opt(c.mean_pressure_pa_ratio_of_means)),
            mean_pressure_Pa_mean_inst: c.and_then(|c| c.mean_pressure_pa.as_ref().map(|s| s.mean)),
            shear_traction_Pa: c.and_then(|c| opt(c.shear_traction_pa_ratio_of_means)),
            shear_traction_Pa_mean_inst: c
                .and_then(|c| c.shear_traction_pa.as_ref().map(|s| s.mean)),
            clipped_samples: h.clipped_samples as u64,
            steps: h.stats.accepted_steps,
            rejected_steps: h.stats.rejected_steps,
            rhs_evaluations: h.stats.rhs_evaluations,
        }
    }

    /// A case entry's `result.json` as this type.
    pub fn from_json(v: &Value) -> Result<Self> {
        serde_json::from_value(v.clone()).map_err(|source| Error::CaseResult { source })
    }

    /// Whether the steady window saw solid contact.
    pub fn touches(&self) -> bool {
        self.percent_solid_contact > 0.0
    }

    /// The result as written (`result.json`).
    pub fn to_json(&self) -> Value {
        serde_json::to_value(self).unwrap_or(Value::Null)
    }
}

pub fn write_case_h5(path: &Path, h: &CaseHistory, actuation: f64, m: &CaseMetrics) -> Result<()> {
    let out = H5Out::create(path)?;
    let entry = out.group("case", Some("NXentry"))?;
    out.attr_str(&entry, "default", "history")?;
    out.write_scalar(&entry, "actuation", actuation, "m", "TFC actuation h_TFC")?;
    out.write_scalar(
        &entry,
        "nominal_area",
        h.nominal_area,
        "m^2",
        "bulge nominal contact area",
    )?;
    out.write_scalar(
        &entry,
        "clearance_mean",
        m.clearance_m.mean,
        "m",
        "steady mean clearance",
    )?;
    out.write_scalar(
        &entry,
        "vibration",
        m.vibration.percent,
        "%",
        "FHM/BV (eq. 2.1) over the steady window",
    )?;
    let g = out.history_group("case/history", "clearance", h.dt, h.len())?;
    for (name, data, unit, what) in [
        ("heave", &h.heave, "m", "COM heave from the nominal state"),
        ("pitch_offset", &h.pitch_offset, "rad", "pitch θ − θ0"),
        ("heave_rate", &h.heave_rate, "m/s", "dz/dt"),
        ("pitch_rate", &h.pitch_rate, "rad/s", "dθ/dt"),
        (
            "spacing",
            &h.spacing,
            "m",
            "solid spacing s of the bulge POC",
        ),
        (
            "clearance",
            &h.clearance,
            "m",
            "clearance (negative: solid contact)",
        ),
        (
            "flying_height",
            &h.flying_height,
            "m",
            "flying height of the POC",
        ),
        (
            "contact_force",
            &h.contact_force,
            "N",
            "dynamic contact force F_c",
        ),
        ("friction", &h.friction, "N", "friction Q"),
        ("adhesion", &h.adhesion, "N", "adhesion F_s"),
        ("real_area", &h.real_area, "m^2", "real contact area A_r"),
        (
            "disk_displacement",
            &h.disk_displacement,
            "m",
            "DMW under the POC",
        ),
        (
            "trailing_edge_spacing",
            &h.trailing_edge_spacing,
            "m",
            "solid spacing of the TE",
        ),
    ] {
        out.write_1d(&g, name, data, unit, what)?;
    }
    Ok(out.finish()?)
}

/// Named series of a case file.
pub type NamedSeries = Vec<(String, Vec<f64>)>;

/// Read a case's histories back (for plots of chosen actuations): time and named series.
pub fn read_case_history(path: &Path) -> Result<(Vec<f64>, NamedSeries)> {
    let file = hdf5::File::open(path).map_err(|source| Error::Hdf5Open {
        path: path.to_path_buf(),
        source,
    })?;
    let read = |name: &str| -> Result<Vec<f64>> {
        file.dataset(&format!("case/history/{name}"))
            .and_then(|d| d.read_raw::<f64>())
            .map_err(|source| Error::Hdf5Read {
                path: path.to_path_buf(),
                what: name.to_string(),
                source,
            })
    };
    let time = read("time")?;
    let mut out = Vec::new();
    for n in [
        "clearance",
        "contact_force",
        "friction",
        "adhesion",
        "real_area",
    ] {
        out.push((n.to_string(), read(n)?));
    }
    Ok((time, out))
}
/// `FHM` (flying-height modulation) or `BV` (bouncing vibration), the labels of eq. 2.1.
pub fn vibration_kind_name(k: VibrationKind) -> &'static str {
    match k {
        VibrationKind::Fhm => "FHM",
        VibrationKind::Bv => "BV",
    }
}

/// The regime of eq. 2.1's classification as named in the tables.
pub fn regime_name(r: Regime) -> &'static str {
    match r {
        Regime::Flying => "flying",
        Regime::MobileLubricantContact => "mobile lubricant",
        Regime::BondedLubricantContact => "bonded lubricant",
        Regime::SolidContact => "solid contact",
    }
}
