//! `hdi surface`'s options (each has the name of its `pipeline.toml` key).

use clap::Args;
use hdi::stages::surfaces;
use hdi::units::Length;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct SurfaceArgs {
    pub file: PathBuf,
    #[arg(long)]
    pub channel: Option<String>,
    /// Lateral size along x for files without one (e.g. "1 um").
    #[arg(long)]
    pub size_x: Option<Length>,
    #[arg(long)]
    pub size_y: Option<Length>,
    /// Height unit for files without one (m, um, nm, ...).
    #[arg(long)]
    pub z_unit: Option<String>,
    /// Analyse only a rectangle: x0,y0,width,height with units (y down from the top row),
    /// e.g. "0um,0um,1um,1um".
    #[arg(long)]
    pub crop: Option<surfaces::CropConfig>,
    /// Levelling recipe, comma-separated (default rows:median,plane,mean).
    #[arg(long, value_delimiter = ',')]
    pub level: Option<Vec<String>>,
    /// S-filter cutoff (Gaussian low-pass), e.g. "20 nm".
    #[arg(long)]
    pub filter_s: Option<Length>,
    /// L-filter cutoff (Gaussian high-pass), e.g. "5 um".
    #[arg(long)]
    pub filter_l: Option<Length>,
    /// Summit definition: 9 or 5.
    #[arg(long, default_value_t = 9)]
    pub summits: u8,
    #[arg(long, default_value = "inverse_mean_curvature")]
    pub radius: String,
    #[arg(long)]
    pub birmingham: bool,
    #[arg(long, default_value = "finite_difference")]
    pub moments: String,
    #[arg(long)]
    pub periodic: bool,
    #[arg(long, default_value_t = 64)]
    pub histogram_bins: usize,
    /// Scanning-probe tip radius (e.g. 40nm): report the tip reliability cutoff and σ, R, η, β
    /// above it (docs/surfaces.md, "Surface analyses").
    #[arg(long)]
    pub tip_radius: Option<Length>,
    /// Also write the full HDF5 output (and PNGs beside it).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Also write the analysed (levelled, filtered) map as ISO 25178-71 X3P to this file.
    #[arg(long, value_name = "FILE")]
    pub x3p_out: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
    /// Only show what the file holds — format, grid, spacing, the channel read and every
    /// channel, the instrument's metadata — without analysing it (with --json: as JSON).
    #[arg(long)]
    pub info: bool,
}
