//! The slider-case machinery the simulate, calibrate, DOE and 3-DOF stages and the Slurm
//! executor share: case parameters from the config tables, one 2-DOF case (run, result,
//! HDF5), a sweep of cases through the case cache with its metrics and rows, the
//! calibration's inputs, and the DOE's design cases. Below the stages: it names none of them.
pub mod calibration;
pub mod case;
pub mod doe;
pub mod doe_design;
pub mod params;
pub mod sweep;
pub mod three_dof_case;
pub mod three_dof_params;
