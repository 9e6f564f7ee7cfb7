//! `hdi simulate`'s options (each has the name of its `pipeline.toml` key).

use clap::Args;
use hdi::units::{Length, PerArea, Pressure, TimeSpan};
use std::path::PathBuf;

/// `hdi simulate`: every option has the name of its `[simulate.NAME]` key; the interface is a
/// dissertation parameter set (`--contact-set`) instead of a `[contact.*]` instance.
#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// improved_2dof (default) or initial_2dof.
    #[arg(long, default_value = "improved_2dof")]
    pub model: String,
    /// ISBL parameter set of the interface (default: the model's).
    #[arg(long)]
    pub contact_set: Option<String>,
    /// A DMW stage output (`dmw.h5`, track 1); none by default.
    #[arg(long)]
    pub dmw: Option<PathBuf>,
    /// Interface overrides on top of `--contact-set` (the `[contact]` keys): Δγ ("60 mN/m" or
    /// "variable"), ε, R, η, H.
    #[arg(long)]
    pub surface_energy: Option<String>,
    #[arg(long, allow_hyphen_values = true)]
    pub lj_spacing: Option<Length>,
    #[arg(long, allow_hyphen_values = true)]
    pub r: Option<Length>,
    #[arg(long, allow_hyphen_values = true)]
    pub eta: Option<PerArea>,
    #[arg(long, allow_hyphen_values = true)]
    pub hardness: Option<Pressure>,
    /// Static friction law of the interface: junction_shear (default), seed_power_elastic or
    /// ke_static (the `[contact] friction_law` key; docs/contact.md, "Friction").
    #[arg(long)]
    pub friction_law: Option<String>,
    /// One or more actuations, e.g. "8.5 nm" "12 nm"; otherwise the sweep below.
    #[arg(long, num_args = 1..)]
    pub actuation: Vec<Length>,
    #[arg(long)]
    pub actuation_start: Option<Length>,
    #[arg(long)]
    pub actuation_stop: Option<Length>,
    #[arg(long)]
    pub actuation_step: Option<Length>,
    #[arg(long)]
    pub duration: Option<TimeSpan>,
    #[arg(long)]
    pub steady_start: Option<TimeSpan>,
    #[arg(long)]
    pub output_step: Option<TimeSpan>,
    /// interference_tangent (default), static_curve or integrated_stiffness
    /// (docs/model-form.md).
    #[arg(long)]
    pub contact_force: Option<String>,
    /// Lubricant force: none (default) or mtl (Chapter 3's law; docs/model-form.md).
    #[arg(long)]
    pub lubricant: Option<String>,
    /// dopri5 (default) or rk5_fixed.
    #[arg(long)]
    pub integrator: Option<String>,
    #[arg(long, allow_hyphen_values = true)]
    pub rtol: Option<f64>,
    #[arg(long)]
    pub contact_max_step: Option<TimeSpan>,
    #[arg(long)]
    pub max_step: Option<TimeSpan>,
    #[arg(long)]
    pub fixed_step: Option<TimeSpan>,
    /// All points see the same DMW (no transit delay).
    #[arg(long)]
    pub no_transit_delay: bool,
    #[arg(long)]
    pub dmw_wrap: bool,
    #[arg(long, allow_hyphen_values = true)]
    pub kr_stiffening_beta: Option<f64>,
    /// dissertation (default) or optimised.
    #[arg(long)]
    pub geometry: Option<String>,
    #[arg(long)]
    pub bulge_width: Option<Length>,
    /// Plot the time histories of these actuations.
    #[arg(long, num_args = 1..)]
    pub histories: Vec<Length>,
    /// nominal (default) or static (start from the static equilibrium).
    #[arg(long)]
    pub init: Option<String>,
    /// Write case HDF5s, the sweep table and plots into this directory.
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
}
