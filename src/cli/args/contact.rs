//! `hdi contact`'s options (each has the name of its `pipeline.toml` key).

use clap::Args;
use hdi::units::{Area, Length, PerArea, Pressure, Velocity, Viscosity};
use std::path::PathBuf;

/// `hdi contact`: every option has the name of its `[contact.NAME]` key.
#[derive(Args, Debug)]
pub struct ContactArgs {
    /// initial_2dof, improved_2dof (default), three_dof or mtl_table_3_2.
    #[arg(long)]
    pub parameter_set: Option<String>,
    /// Combined RMS roughness, e.g. "0.5 nm".
    #[arg(long, allow_hyphen_values = true)]
    pub sigma: Option<Length>,
    /// Mean summit radius, e.g. "0.43 um".
    #[arg(long, allow_hyphen_values = true)]
    pub r: Option<Length>,
    /// Summit density, e.g. "124 um^-2".
    #[arg(long, allow_hyphen_values = true)]
    pub eta: Option<PerArea>,
    /// Hardness of the yielding body, e.g. "13 GPa".
    #[arg(long, allow_hyphen_values = true)]
    pub hardness: Option<Pressure>,
    /// Young's modulus of both bodies, e.g. "280 GPa".
    #[arg(long, allow_hyphen_values = true)]
    pub modulus: Option<Pressure>,
    #[arg(long, allow_hyphen_values = true)]
    pub poisson: Option<f64>,
    /// Lennard-Jones equilibrium spacing ε, e.g. "0.3 nm".
    #[arg(long, allow_hyphen_values = true)]
    pub lj_spacing: Option<Length>,
    /// Total lubricant thickness t, e.g. "1.5 nm".
    #[arg(long, allow_hyphen_values = true)]
    pub lubricant_thickness: Option<Length>,
    /// Constant Δγ ("60 mN/m") or "variable".
    #[arg(long)]
    pub surface_energy: Option<String>,
    /// Older name of --summit-distribution: none (= surface) or mccool.
    #[arg(long)]
    pub summit_offset: Option<String>,
    /// surface (default), mccool or fig_2_11 (σ_s, y_s fitted to Fig. 2.11's two numbers).
    #[arg(long)]
    pub summit_distribution: Option<String>,
    /// fig_2_11: the nominal area of Fig. 2.11's 7.30 µN, e.g. "55 um^2" (the default).
    #[arg(long, allow_hyphen_values = true)]
    pub fig_2_11_nominal_area: Option<Area>,
    /// junction_shear (default), seed_power_elastic or ke_static (docs/contact.md, "Friction").
    #[arg(long)]
    pub friction_law: Option<String>,
    #[arg(long, allow_hyphen_values = true)]
    pub h_star_min: Option<f64>,
    #[arg(long, allow_hyphen_values = true)]
    pub h_star_max: Option<f64>,
    /// Grid step in h/σ (also the force table's).
    #[arg(long)]
    pub step: Option<f64>,
    /// Add the MTL law: reference, humidity_temperature, more_bonding, larger_gyration_radius.
    #[arg(long)]
    pub lubricant: Option<String>,
    /// Nominal area for the MTL curves, e.g. "2500 um^2" (default).
    #[arg(long, allow_hyphen_values = true)]
    pub nominal_area: Option<Area>,
    /// Sliding speed of the MTL law, e.g. "30 m/s" (default).
    #[arg(long, allow_hyphen_values = true)]
    pub sliding_speed: Option<Velocity>,
    /// Limiting viscosity μ0, e.g. "0.31 Pa s".
    #[arg(long, allow_hyphen_values = true)]
    pub lubricant_viscosity: Option<Viscosity>,
    /// Minimum liquid gap κ (radius of gyration), e.g. "0.3 nm".
    #[arg(long, allow_hyphen_values = true)]
    pub gyration_radius: Option<Length>,
    /// Deterministic contact instead of ISBL: the FFT-BEM on one height map, or on the sum
    /// of two (each levelled rows:median, plane, mean), against a rigid flat
    /// (docs/contact.md, "Deterministic contact"; `[contact_bem.NAME] files`).
    #[arg(long, num_args = 1..=2, value_name = "FILE")]
    pub bem: Vec<PathBuf>,
    /// --bem: periodic (default) or non_periodic.
    #[arg(long)]
    pub boundary: Option<String>,
    /// --bem: h/σ of the pressure map and gap histogram (default 1.5).
    #[arg(long)]
    pub map_at: Option<f64>,
    /// --bem: convergence tolerance (default 1e-10).
    #[arg(long)]
    pub tolerance: Option<f64>,
    /// Also write the HDF5 output (and PNGs beside it).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
}
