//! The DOE's design cases (dissertation §2.3): the 3³ full factorial in the bulge geometry
//! (`a_TFC`, `w_TFC`, `x_TFC`) crossed with the actuation levels, and the 2-DOF parameters of
//! one design point. The DOE stage runs them; the Slurm executor lists and computes the same
//! cases, so both build identical case keys from here.

use crate::dynamics::geometry::BulgeDesign;
use crate::error::Result;
use crate::numerics::regression::{decoded, full_factorial};
use crate::slider::params::SimulateParams;

/// Physical design `[a, w, x]` [m] of a coded point, `levels[f]` the −1/0/+1 values of factor
/// `f`.
pub fn decode(levels: &[[f64; 3]; 3], c: &[f64]) -> [f64; 3] {
    // The design levels exactly (not to an ulp), so a level shared by two factors compares
    // equal (a_TFC = x_TFC = 5 µm is allowed).
    std::array::from_fn(|f| match c[f] {
        -1.0 => levels[f][0],
        0.0 => levels[f][1],
        1.0 => levels[f][2],
        v => decoded(v, levels[f][0], levels[f][2]),
    })
}

/// The 27 designs `[a, w, x]` [m] of the 3³ factorial, in `full_factorial` order.
pub fn design_points(levels: &[[f64; 3]; 3]) -> Vec<[f64; 3]> {
    full_factorial(&[3, 3, 3])
        .iter()
        .map(|c| decode(levels, c))
        .collect()
}

/// The design points `[a, w, x]` [m] crossed with the actuation levels, in run order (level
/// by level).
pub fn design_cases(levels: &[[f64; 3]; 3], actuations: &[f64]) -> Vec<([f64; 3], f64)> {
    let designs = design_points(levels);
    actuations
        .iter()
        .flat_map(|&h| designs.iter().map(move |d| (*d, h)))
        .collect()
}

/// The base instance's parameters with the bulge `[a, w, x]`, for a case at `actuation` (the
/// local runner and the Slurm worker build the same key from this).
pub fn design_params(
    base: &SimulateParams,
    design: &[f64; 3],
    actuation: f64,
) -> Result<SimulateParams> {
    // An annealing point on the a = x edge may miss it by rounding only.
    let a = if design[0] > design[2] && design[0] - design[2] < 1e-9 * design[2] {
        design[2]
    } else {
        design[0]
    };
    let bulge = BulgeDesign {
        semi_width_x: a,
        full_width_y: design[1],
        offset_from_te: design[2],
    };
    bulge.validate()?;
    let mut p = base.clone();
    p.model = p.model.with_bulge(bulge);
    // Only beyond the model's range is the range widened, so every case inside it keeps the
    // `[simulate]` stage's cache key (Table 2.8's initial design reuses its sweep).
    if actuation > p.model.max_actuation {
        p.model.max_actuation = actuation;
    }
    Ok(p)
}
