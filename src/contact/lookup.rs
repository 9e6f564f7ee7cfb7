//! What the dynamics call in their inner loop: the ISBL curves per unit nominal area,
//! tabulated once per interface and looked up in O(1) with the out-of-range rules of
//! docs/contact.md, and the same table as the solid of the MTL law.

use super::bem::law::ContactCurve;
use super::isbl::{IsblModel, IsblPoint};
use super::mtl::rough::{SolidContact, SolidResponse};
use super::table::{ChannelError, ForceTable, Interp, Sample, TablePoint};
use super::ContactError;
use std::sync::Arc;

/// ISBL table channels (per unit nominal area, abscissa h* = h/σ) and how each is
/// interpolated. `k_fr` and `dF_s/dh` are the slopes of `Q` and `F_s`.
pub const ISBL_CHANNELS: [(&str, Interp); 5] = [
    ("P", Interp::Log),
    ("k_c", Interp::Log),
    ("A_r", Interp::Log),
    ("Q", Interp::Log),
    ("F_s", Interp::Log),
];
const P: usize = 0;
const KC: usize = 1;
const AR: usize = 2;
const Q: usize = 3;
const FS: usize = 4;

/// Node step and h* = h/σ range of a force table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForceTableGrid {
    pub step: f64,
    pub h_star_min: f64,
    pub h_star_max: f64,
}

/// The grid every slider model's ISBL table uses (2-DOF and 3-DOF cases, the DOE, the MTL
/// solid, benches and checks): one definition, so they all tabulate the same curves.
pub const FORCE_TABLE_GRID: ForceTableGrid = ForceTableGrid {
    step: 0.05,
    h_star_min: -2.0,
    h_star_max: 10.0,
};

/// Where a lookup was answered from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LookupRange {
    /// Interpolated in the table.
    Table,
    /// Above the table: the contact terms are zero and `F_s` follows the far-tail formula.
    AboveTable,
    /// Below the table (deeper than h* = −4): evaluated directly. The dissertation never
    /// simulates this deep an interference, so callers should flag the state.
    BelowTable,
}

/// ISBL forces per unit nominal area at one separation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IsblForces {
    /// Contact pressure `P` [Pa].
    pub pressure: f64,
    /// Contact stiffness `k_c = −dP/dh` [Pa/m].
    pub stiffness: f64,
    /// Real area over nominal area `A_r/A_n` [1].
    pub real_area_fraction: f64,
    /// Static friction per unit area `Q` [Pa].
    pub friction: f64,
    /// `k_fr = −dQ/dh` [Pa/m].
    pub friction_stiffness: f64,
    /// Adhesion per unit area `F_s` (magnitude, pulling the surfaces together) [Pa].
    pub adhesion: f64,
    /// `dF_s/dh` [Pa/m] (negative).
    pub adhesion_gradient: f64,
    pub range: LookupRange,
}

/// Value and exact h*-derivative of every ISBL channel at h* = x; `dk_c/dh*` is a
/// fourth-order central difference of the exact `k_c` (the model has no second derivative).
fn isbl_sample(model: &IsblModel, x: f64) -> Result<Sample, ContactError> {
    let sigma = model.params().sigma;
    let p = model.at(x * sigma)?;
    let delta = 1e-3;
    let kc = |dx: f64| model.at((x + dx) * sigma).map(|q| q.contact_stiffness);
    let dkc = (-kc(2.0 * delta)? + 8.0 * kc(delta)? - 8.0 * kc(-delta)? + kc(-2.0 * delta)?)
        / (12.0 * delta);
    let mut value = isbl_values(&p);
    let mut derivative = vec![
        -p.contact_stiffness * sigma,
        dkc,
        -p.real_area_gradient * sigma,
        -p.friction_stiffness * sigma,
        p.adhesion_gradient * sigma,
    ];
    // A narrow summit distribution (the Fig. 2.11 fit: σ_s = 0.35σ) takes the contact
    // channels below the smallest f64 inside the table (P(15.5σ) = 0). Below the floor they
    // are zero for any use; the log-interpolated channel then holds the floor, flat.
    for c in [P, KC, AR, Q] {
        if value[c] < CONTACT_FLOOR {
            value[c] = CONTACT_FLOOR;
            derivative[c] = 0.0;
        }
    }
    Ok(Sample { value, derivative })
}

/// [`isbl_sample`] with the contact channels (P, k_c, A_r, Q) from a measured contact law:
/// friction is the junction-shear stress on the law's real area (`Q = τ·A_r`), adhesion stays
/// ISBL's.
fn law_sample(model: &IsblModel, law: &ContactCurve, x: f64) -> Result<Sample, ContactError> {
    let mut s = isbl_sample(model, x)?;
    let sigma = model.params().sigma;
    let tau = model.derived().junction_shear_strength;
    let h = x * sigma;
    let q = law.at(h);
    let delta = 1e-3 * sigma;
    let kc = |dh: f64| -law.at(h + dh).pressure_slope;
    let dkc = (-kc(2.0 * delta) + 8.0 * kc(delta) - 8.0 * kc(-delta) + kc(-2.0 * delta))
        / (12.0 * delta)
        * sigma;
    let values = [
        (P, q.pressure, q.pressure_slope * sigma),
        (KC, -q.pressure_slope, dkc),
        (AR, q.real_area_fraction, q.real_area_slope * sigma),
        (
            Q,
            tau * q.real_area_fraction,
            tau * q.real_area_slope * sigma,
        ),
    ];
    for (c, v, d) in values {
        s.value[c] = v.max(CONTACT_FLOOR);
        s.derivative[c] = if v < CONTACT_FLOOR { 0.0 } else { d };
    }
    Ok(s)
}

/// Smallest tabulated contact value (Pa, Pa/m or 1): below it the quadrature's own absolute
/// floor (1e-280) makes the value noise. Never reached by the dissertation's parameter sets
/// with `surface` or `mccool` summits (P(16σ) ≥ 1e-93 Pa), whose tables are unchanged by it.
const CONTACT_FLOOR: f64 = 1e-250;

fn isbl_values(p: &IsblPoint) -> Vec<f64> {
    vec![
        p.contact_pressure,
        p.contact_stiffness,
        p.real_area_fraction,
        p.friction_stress,
        p.adhesion,
    ]
}

/// The ISBL model of one interface, tabulated on h* ∈ [−4, 3 + t/σ + 10] (or wider).
#[derive(Debug, Clone)]
pub struct IsblLookup {
    model: IsblModel,
    table: ForceTable,
    error: Vec<ChannelError>,
    inv_sigma: f64,
    /// Far-tail adhesion `F_s ≈ a·(ε/D)²·(1 + 3σ_s²/D²)`, `D = h − y_s − t + ε`
    /// (docs/contact.md), scaled so it meets the table at its last node.
    tail_scale: f64,
    /// `contact_law = "bem"`: the measured contact law replacing ISBL's contact channels.
    law: Option<std::sync::Arc<ContactCurve>>,
}

impl IsblLookup {
    /// Tabulate `model` with node step `step` (in h*) over the spec's range widened to
    /// `[h_star_min, h_star_max]`, and verify the table against direct evaluation at the
    /// midpoints and quarter points (values above 10⁻¹² of each channel's peak).
    /// [`IsblLookup::build`] on [`FORCE_TABLE_GRID`].
    pub fn build_standard(model: IsblModel) -> Result<Self, ContactError> {
        let g = FORCE_TABLE_GRID;
        Self::build(model, g.step, g.h_star_min, g.h_star_max)
    }

    pub fn build(
        model: IsblModel,
        step: f64,
        h_star_min: f64,
        h_star_max: f64,
    ) -> Result<Self, ContactError> {
        let mut lookup = Self::build_unverified(model, step, h_star_min, h_star_max)?;
        let (model, sigma) = (&lookup.model, lookup.model.params().sigma);
        let values_only = |x: f64| -> Result<Sample, ContactError> {
            Ok(Sample {
                value: isbl_values(&model.at(x * sigma)?),
                derivative: vec![0.0; ISBL_CHANNELS.len()],
            })
        };
        lookup.error = lookup.table.verify(values_only, 1, 1e-12)?;
        Ok(lookup)
    }

    /// [`IsblLookup::build_standard`] without the verification against direct evaluation
    /// (its `verified_error` is empty): the same table, bit for bit, with 5 instead of 7 ISBL evaluations per node. For
    /// tables whose error nobody reads — one per calibration evaluation, per sweep, per
    /// validation case set; the `[contact]` stage, which reports the error, verifies the
    /// interface's table (docs/contact.md).
    pub fn build_standard_unverified(model: IsblModel) -> Result<Self, ContactError> {
        let g = FORCE_TABLE_GRID;
        Self::build_unverified(model, g.step, g.h_star_min, g.h_star_max)
    }

    /// The standard table with the contact channels (P, k_c, A_r and the junction-shear
    /// friction on A_r) from the measured contact law `law` instead of ISBL; adhesion stays
    /// ISBL's (`[simulate] contact_law = "bem"`, docs/model-form.md "Contact law").
    pub fn build_with_contact_law(
        model: IsblModel,
        law: std::sync::Arc<ContactCurve>,
    ) -> Result<Self, ContactError> {
        let g = FORCE_TABLE_GRID;
        Self::build_table(model, g.step, g.h_star_min, g.h_star_max, Some(law))
    }

    fn build_unverified(
        model: IsblModel,
        step: f64,
        h_star_min: f64,
        h_star_max: f64,
    ) -> Result<Self, ContactError> {
        Self::build_table(model, step, h_star_min, h_star_max, None)
    }

    fn build_table(
        model: IsblModel,
        step: f64,
        h_star_min: f64,
        h_star_max: f64,
        law: Option<std::sync::Arc<ContactCurve>>,
    ) -> Result<Self, ContactError> {
        let p = *model.params();
        let top = (3.0 + p.lubricant_thickness / p.sigma + 10.0).max(h_star_max);
        let lo = h_star_min.min(-4.0);
        let table = ForceTable::build(&ISBL_CHANNELS, lo, top, step, |x| match &law {
            Some(l) => law_sample(&model, l, x),
            None => isbl_sample(&model, x),
        })?;
        let error = Vec::new();
        let (_, last) = table.range();
        let at_last = table.eval(FS, last).unwrap_or(0.0);
        let shape = Self::tail_shape(&model, last * p.sigma).0;
        let tail_scale = if shape > 0.0 { at_last / shape } else { 0.0 };
        Ok(Self {
            inv_sigma: 1.0 / p.sigma,
            model,
            table,
            error,
            tail_scale,
            law,
        })
    }

    /// `(ε/D)²(1 + 3σ_s²/D²)` and its h-derivative.
    fn tail_shape(model: &IsblModel, h: f64) -> (f64, f64) {
        let (p, dv) = (model.params(), model.derived());
        let eps = p.lj_spacing;
        let d = h - dv.summit_offset - p.lubricant_thickness + eps;
        if d <= 0.0 {
            return (0.0, 0.0);
        }
        let s2 = dv.summit_sigma * dv.summit_sigma;
        let r = eps / d;
        let value = r * r * (1.0 + 3.0 * s2 / (d * d));
        let slope = -2.0 * r * r / d - 12.0 * r * r * s2 / (d * d * d);
        (value, slope)
    }

    /// Forces per unit nominal area at solid separation `h` [m].
    pub fn at(&self, h: f64) -> Result<IsblForces, ContactError> {
        if !h.is_finite() {
            return Err(ContactError::Numerical(format!(
                "ISBL lookup at a non-finite separation {h}"
            )));
        }
        let x = h * self.inv_sigma;
        let (lo, hi) = self.table.range();
        if x > hi {
            let (shape, slope) = Self::tail_shape(&self.model, h);
            return Ok(IsblForces {
                pressure: 0.0,
                stiffness: 0.0,
                real_area_fraction: 0.0,
                friction: 0.0,
                friction_stiffness: 0.0,
                adhesion: self.tail_scale * shape,
                adhesion_gradient: self.tail_scale * slope,
                range: LookupRange::AboveTable,
            });
        }
        if x < lo {
            let p = self.model.at(h)?;
            if let Some(law) = &self.law {
                let q = law.at(h);
                let tau = self.model.derived().junction_shear_strength;
                return Ok(IsblForces {
                    pressure: q.pressure,
                    stiffness: -q.pressure_slope,
                    real_area_fraction: q.real_area_fraction,
                    friction: tau * q.real_area_fraction,
                    friction_stiffness: -tau * q.real_area_slope,
                    adhesion: p.adhesion,
                    adhesion_gradient: p.adhesion_gradient,
                    range: LookupRange::BelowTable,
                });
            }
            return Ok(IsblForces {
                pressure: p.contact_pressure,
                stiffness: p.contact_stiffness,
                real_area_fraction: p.real_area_fraction,
                friction: p.friction_stress,
                friction_stiffness: p.friction_stiffness,
                adhesion: p.adhesion,
                adhesion_gradient: p.adhesion_gradient,
                range: LookupRange::BelowTable,
            });
        }
        let t = &self.table;
        // In range by the checks above, so every channel answers.
        let get = |c| t.eval_with_slope(c, x).unwrap_or((0.0, 0.0));
        let (pressure, _) = get(P);
        let (stiffness, _) = get(KC);
        let (real_area_fraction, _) = get(AR);
        let (friction, dq) = get(Q);
        let (adhesion, dfs) = get(FS);
        Ok(IsblForces {
            pressure,
            stiffness,
            real_area_fraction,
            friction,
            friction_stiffness: -dq * self.inv_sigma,
            adhesion,
            adhesion_gradient: dfs * self.inv_sigma,
            range: LookupRange::Table,
        })
    }

    /// [`IsblLookup::at`] evaluating only the channels asked for: inside the table each
    /// accessor interpolates its one channel (one `exp` instead of five); outside it, the
    /// full [`IsblForces`] of `at`. Same values, bit for bit, as the fields of `at(h)`. The
    /// dynamics' right-hand sides need one or two channels per call (docs/performance.md).
    #[inline]
    pub fn at_lazy(&self, h: f64) -> Result<IsblAt<'_>, ContactError> {
        if h.is_finite() {
            let x = h * self.inv_sigma;
            let (lo, hi) = self.table.range();
            if (lo..=hi).contains(&x) {
                // The cell and its Hermite weights once for every channel read here.
                return Ok(match self.table.locate(x) {
                    Some(point) => IsblAt::Table {
                        table: &self.table,
                        point,
                    },
                    // Only where rounding puts x a hair outside the last node: every channel
                    // of `eval_with_slope` answers None there, which `at` reads as 0.
                    None => IsblAt::Forces(IsblForces {
                        pressure: 0.0,
                        stiffness: 0.0,
                        real_area_fraction: 0.0,
                        friction: 0.0,
                        friction_stiffness: 0.0,
                        adhesion: 0.0,
                        adhesion_gradient: 0.0,
                        range: LookupRange::Table,
                    }),
                });
            }
        }
        self.at(h).map(IsblAt::Forces)
    }

    /// The separation `h` [m] at which the contact pressure equals `pressure` [Pa]
    /// (`P⁻¹`, monotone inversion of the table; eq. 2.16): `None` for `pressure ≤ 0`
    /// or NaN; a pressure above the table's largest is clamped to its deepest node.
    pub fn separation_for_pressure(&self, pressure: f64) -> Option<f64> {
        if pressure.is_nan() || pressure <= 0.0 {
            return None;
        }
        let (lo, hi) = self.table.range();
        let x = match self.table.invert_decreasing(P, pressure) {
            Some(x) => x,
            None if pressure >= self.table.eval(P, lo)? => lo,
            None => hi,
        };
        Some(x / self.inv_sigma)
    }

    pub fn model(&self) -> &IsblModel {
        &self.model
    }

    pub fn table(&self) -> &ForceTable {
        &self.table
    }

    /// Worst interpolation error per channel against direct evaluation.
    pub fn verified_error(&self) -> &[ChannelError] {
        &self.error
    }

    /// The ISBL model as the MTL law's solid, scaled to a nominal area `A_n` [m²]: forces in N,
    /// stiffnesses in N/m, evaluated from the table (direct below it).
    pub fn as_solid(self: &Arc<Self>, nominal_area: f64) -> ScaledIsbl {
        ScaledIsbl {
            lookup: Arc::clone(self),
            nominal_area,
        }
    }
}

/// A lookup whose channels are interpolated on demand ([`IsblLookup::at_lazy`]).
#[derive(Debug, Clone, Copy)]
pub enum IsblAt<'a> {
    /// Inside the table, at a located point.
    Table {
        table: &'a ForceTable,
        point: TablePoint,
    },
    /// Outside the table: every channel already evaluated.
    Forces(IsblForces),
}

impl IsblAt<'_> {
    #[inline]
    fn channel(&self, c: usize) -> f64 {
        match self {
            // In range by construction, so every channel answers.
            IsblAt::Table { table, point } => table.value_at(c, point).unwrap_or(0.0),
            IsblAt::Forces(f) => match c {
                P => f.pressure,
                KC => f.stiffness,
                AR => f.real_area_fraction,
                Q => f.friction,
                _ => f.adhesion,
            },
        }
    }

    /// [`IsblForces::pressure`].
    #[inline]
    pub fn pressure(&self) -> f64 {
        self.channel(P)
    }

    /// [`IsblForces::stiffness`].
    #[inline]
    pub fn stiffness(&self) -> f64 {
        self.channel(KC)
    }

    /// [`IsblForces::real_area_fraction`].
    #[inline]
    pub fn real_area_fraction(&self) -> f64 {
        self.channel(AR)
    }

    /// [`IsblForces::friction`].
    #[inline]
    pub fn friction(&self) -> f64 {
        self.channel(Q)
    }

    /// [`IsblForces::adhesion`].
    #[inline]
    pub fn adhesion(&self) -> f64 {
        self.channel(FS)
    }
}

/// [`IsblLookup`] times a nominal area, as a [`SolidContact`] for the MTL law.
///
/// `MtlInterface<ScaledIsbl>` is the fast path of the combined lubricant + solid model: the
/// MTL law is closed-form per `h` once its anchors are computed (docs/contact.md), so only
/// the solid needs a table; no cubic straddles the stiffness jumps at `3σ + 2κ` and `3σ + t`.
#[derive(Debug, Clone)]
pub struct ScaledIsbl {
    lookup: Arc<IsblLookup>,
    nominal_area: f64,
}

impl SolidContact for ScaledIsbl {
    fn response(&self, separation: f64) -> SolidResponse {
        // Separations come from the MTL law's own grid (finite), so a failure here means a
        // broken model; zero keeps the MTL arithmetic finite and the table verification
        // reports the mismatch.
        let f = self.lookup.at(separation).ok();
        let a = self.nominal_area;
        f.map(|f| SolidResponse {
            normal: f.pressure * a,
            friction: f.friction * a,
            normal_stiffness: f.stiffness * a,
            friction_stiffness: f.friction_stiffness * a,
        })
        .unwrap_or_default()
    }
}

#[cfg(test)]
mod tests;
