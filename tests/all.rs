//! One integration-test binary (one link step on 2 cores), one module per concern.
mod analysis_cli;
mod architecture;
mod bad_input;
mod bulge_cli;
mod calibrate_cli;
mod common;
mod diff_cli;
mod dmw_cli;
mod doe_cli;
mod pipeline_cache;
mod simulate_cli;
mod slurm_cli;
mod standalone;
mod surface_cli;
mod three_dof_cli;
mod validate_cli;
