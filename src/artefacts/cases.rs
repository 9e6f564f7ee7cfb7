//! The case files a `[simulate]` or `[three_dof]` instance exposes in its outputs (hard links
//! to its cached cases), by the names a downstream stage (`[analysis]`) addresses them with.

/// Directory of the case files inside the instance's outputs.
pub const DIR: &str = "cases";

/// File name (inside `DIR`) of the 2-DOF sweep case at `actuation` [m]: `h_008.60nm.h5`.
pub fn sweep_case_name(actuation: f64) -> String {
    format!("h_{:06.2}nm.h5", actuation * 1e9)
}

/// Path of the 2-DOF sweep case at `actuation` [m] inside the instance's outputs.
pub fn sweep_case_file(actuation: f64) -> String {
    format!("{DIR}/{}", sweep_case_name(actuation))
}

/// Path of the 3-DOF case with interface label `label` (`isbl`, `mtl_reference`, …).
pub fn three_dof_case_file(label: &str) -> String {
    format!("{DIR}/{label}.h5")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_the_published_ones() {
        assert_eq!(sweep_case_file(8.6e-9), "cases/h_008.60nm.h5");
        assert_eq!(sweep_case_file(12e-9), "cases/h_012.00nm.h5");
        assert_eq!(three_dof_case_file("isbl"), "cases/isbl.h5");
    }
}
