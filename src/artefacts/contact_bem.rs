//! What a `[contact_bem.*]` instance hands on: its `result.json` ([`BemResult`]: the
//! deterministic force–separation curve of the measured composite map beside the ISBL curve at
//! the same h/σ) and its `contact.h5` (`/bem`; docs/hdf5.md). `[simulate] contact_law = "bem"`
//! reads the curve back through the same type.

use crate::contact::bem::law::ContactCurve;
use crate::contact::bem::CurvePoint;
use crate::contact::ContactError;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// HDF5 file of the stage.
pub const BEM_FILE: &str = "contact.h5";

/// One separation: BEM and (with a `contact` overlay) ISBL, SI units named in the keys.
/// Schema version 1 (docs/json.md).
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct BemCurvePoint {
    /// Separation over the composite map's RMS height, h/σ.
    pub h_star: f64,
    /// Mean gap [m] (the separation, in a periodic domain).
    pub mean_gap_m: f64,
    /// Mean contact pressure over the nominal area [Pa].
    pub pressure_Pa: f64,
    /// Real over nominal contact area.
    pub contact_fraction: f64,
    /// The solve's iterations and final error.
    pub iterations: usize,
    pub error: f64,
    /// ISBL at the same h/σ: pressure [Pa] and A_r/A_n; null without an overlay.
    pub isbl_pressure_Pa: Option<f64>,
    pub isbl_contact_fraction: Option<f64>,
}

impl BemCurvePoint {
    pub fn new(h_star: f64, c: &CurvePoint, isbl: Option<(f64, f64)>) -> Self {
        BemCurvePoint {
            h_star,
            mean_gap_m: c.mean_gap,
            pressure_Pa: c.mean_pressure,
            contact_fraction: c.contact_fraction,
            iterations: c.iterations,
            error: c.error,
            isbl_pressure_Pa: isbl.map(|v| v.0),
            isbl_contact_fraction: isbl.map(|v| v.1),
        }
    }
}

/// A ratio under each model; null where a curve is zero or absent.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ModelRatio {
    pub bem: Option<f64>,
    pub isbl: Option<f64>,
}

/// The `[contact_bem.*]` result.json. Schema version 1 (docs/json.md).
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct BemResult {
    /// Elements along x and y.
    pub grid: [usize; 2],
    /// Element size [m].
    pub spacing_m: [f64; 2],
    /// RMS height of the composite map [m] (h/σ uses it).
    pub sigma_m: f64,
    /// σ of the overlaid ISBL interface [m]; null without an overlay.
    pub isbl_sigma_m: Option<f64>,
    /// Reduced modulus [Pa].
    pub e_star_Pa: f64,
    /// "periodic" or "non_periodic".
    pub boundary: String,
    /// Convergence tolerance of every solve (docs/contact.md, "Deterministic contact").
    pub tolerance: f64,
    /// Most iterations any separation took.
    pub iterations_max: usize,
    /// Memory the solver held [bytes].
    pub memory_bytes: usize,
    /// P(3σ)/P(2.5σ): the steepness of the light-load curve (Fig. 2.11).
    pub ratio_3_over_2_5: ModelRatio,
    /// The curve, from the largest separation down.
    pub curve: Vec<BemCurvePoint>,
    /// The curve's table beside the result (`bem_vs_isbl.{parquet,csv,arrow}`).
    pub table: String,
}

/// One row of `bem_vs_isbl`: table units.
#[allow(non_snake_case)]
#[derive(Debug, Clone, Serialize)]
pub struct BemTableRow {
    pub h_star: f64,
    pub mean_gap_nm: f64,
    pub p_bem_MPa: f64,
    pub p_isbl_MPa: Option<f64>,
    /// BEM over ISBL; null where ISBL is zero or absent.
    pub p_ratio: Option<f64>,
    pub ar_bem: f64,
    pub ar_isbl: Option<f64>,
    pub ar_ratio: Option<f64>,
    pub iterations: usize,
}

fn ratio(a: f64, b: Option<f64>) -> Option<f64> {
    b.filter(|b| *b > 0.0).map(|b| a / b)
}

impl BemResult {
    #[allow(clippy::too_many_arguments)] // the result's fields, in order
    pub fn new(
        grid: (usize, usize),
        spacing: (f64, f64),
        sigma: f64,
        e_star: f64,
        boundary: &str,
        tolerance: f64,
        isbl_sigma: Option<f64>,
        curve: Vec<BemCurvePoint>,
        memory_bytes: usize,
    ) -> Self {
        let at = |h: f64| curve.iter().find(|p| (p.h_star - h).abs() < 1e-9);
        let ratio_3_over_2_5 = match (at(3.0), at(2.5)) {
            (Some(a), Some(b)) => ModelRatio {
                bem: ratio(a.pressure_Pa, Some(b.pressure_Pa)),
                isbl: a
                    .isbl_pressure_Pa
                    .and_then(|pa| ratio(pa, b.isbl_pressure_Pa)),
            },
            _ => ModelRatio {
                bem: None,
                isbl: None,
            },
        };
        BemResult {
            grid: [grid.0, grid.1],
            spacing_m: [spacing.0, spacing.1],
            sigma_m: sigma,
            isbl_sigma_m: isbl_sigma,
            e_star_Pa: e_star,
            boundary: boundary.into(),
            tolerance,
            iterations_max: curve.iter().map(|p| p.iterations).max().unwrap_or(0),
            memory_bytes,
            ratio_3_over_2_5,
            curve,
            table: "bem_vs_isbl".into(),
        }
    }

    /// The curve as the dynamics' contact law (`[simulate] contact_law = "bem"`): mean gap,
    /// pressure and real area of every solved separation.
    pub fn contact_law(&self) -> Result<ContactCurve, ContactError> {
        let points: Vec<(f64, f64, f64)> = self
            .curve
            .iter()
            .map(|p| (p.mean_gap_m, p.pressure_Pa, p.contact_fraction))
            .collect();
        ContactCurve::new(&points)
    }

    /// A_r/A_0 at h/σ = `h_star`, when the curve holds it.
    pub fn contact_fraction_at(&self, h_star: f64) -> Option<f64> {
        self.curve
            .iter()
            .find(|p| (p.h_star - h_star).abs() < 1e-9)
            .map(|p| p.contact_fraction)
    }

    pub fn table_rows(&self) -> Vec<BemTableRow> {
        use crate::core::store::round_significant as r;
        self.curve
            .iter()
            .map(|p| BemTableRow {
                h_star: p.h_star,
                mean_gap_nm: r(p.mean_gap_m * 1e9, 9),
                p_bem_MPa: r(p.pressure_Pa * 1e-6, 9),
                p_isbl_MPa: p.isbl_pressure_Pa.map(|v| r(v * 1e-6, 9)),
                p_ratio: ratio(p.pressure_Pa, p.isbl_pressure_Pa).map(|v| r(v, 6)),
                ar_bem: r(p.contact_fraction, 9),
                ar_isbl: p.isbl_contact_fraction.map(|v| r(v, 9)),
                ar_ratio: ratio(p.contact_fraction, p.isbl_contact_fraction).map(|v| r(v, 6)),
                iterations: p.iterations,
            })
            .collect()
    }
}
