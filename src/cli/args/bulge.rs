//! `hdi bulge`'s options (each has the name of its `pipeline.toml` key).

use clap::Args;
use hdi::units::{Length, Power};
use std::path::PathBuf;

/// `hdi bulge FILE…`: the options have the names of the `[bulge.NAME]` keys.
#[derive(Args, Debug)]
pub struct BulgeArgs {
    /// Height maps (one scan each).
    #[arg(required_unless_present = "lines", num_args = 1..)]
    pub files: Vec<PathBuf>,
    /// A line scan: FILE[@OFFSET[@POWER]], OFFSET the line's distance from the bulge centre
    /// across the slider (default 0), POWER its heater power (default: from the file name),
    /// e.g. "tfc_30mW_y+10um.csv@10um". Repeatable; the lines of one power are fitted together.
    #[arg(long = "line", id = "lines")]
    pub lines: Vec<hdi::stages::bulge::LineConfig>,
    /// Heater power of each file, in order (e.g. "30 mW"); default: from the file names
    /// (`…30mW…`).
    #[arg(long = "power")]
    pub powers: Vec<Power>,
    /// A rectangle left out of levelling and fitting: x0,y0,width,height with units (x along
    /// a scan line, y down from the top row), e.g. "0um,0um,10um,5um". Repeatable.
    #[arg(long)]
    pub exclude: Vec<hdi::stages::bulge::RectConfig>,
    /// Mask start before the detected trailing edge (default 2 um).
    #[arg(long)]
    pub te_margin: Option<Length>,
    /// Do not detect and mask the trailing-edge drop.
    #[arg(long)]
    pub no_auto_te: bool,
    #[arg(long)]
    pub channel: Option<String>,
    /// Also write bulge.h5, scans.csv/.parquet and the figures into this directory.
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
}
