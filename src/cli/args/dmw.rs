//! `hdi dmw`'s options (each has the name of its `pipeline.toml` key).

use clap::Args;
use hdi::units::{Frequency, Sensitivity, TimeSpan};
use std::path::PathBuf;

/// `hdi dmw FILE`: every option has the name of its `[dmw.NAME]` key.
#[derive(Args, Debug)]
pub struct DmwArgs {
    /// LDV record: CSV/TSV, Parquet, HDF5, Arrow IPC/Feather v2, UFF 58/58b, .npy/.npz or WAV
    /// (detected from the content; docs/dmw.md).
    pub file: PathBuf,
    /// Sample rate when the file has no time column, e.g. "4 MHz".
    #[arg(long)]
    pub sample_rate: Option<Frequency>,
    /// Decoder sensitivity, e.g. "25 mm/s/V" (default).
    #[arg(long)]
    pub sensitivity: Option<Sensitivity>,
    /// Spindle speed (rpm): checks the index period, or segments a record without index.
    #[arg(long)]
    pub rpm: Option<f64>,
    /// Velocity column/dataset/channel by name; in UFF, .npy and WAV also by number (from 0)
    /// or UFF node:direction.
    #[arg(long)]
    pub velocity_column: Option<String>,
    #[arg(long)]
    pub index_column: Option<String>,
    #[arg(long)]
    pub time_column: Option<String>,
    /// "V" or "m/s".
    #[arg(long)]
    pub velocity_unit: Option<String>,
    #[arg(long)]
    pub trigger_level: Option<f64>,
    /// Index edge that starts a revolution: "auto" (default), "rising" or "falling".
    #[arg(long)]
    pub trigger_polarity: Option<String>,
    /// Index pulses per revolution (default 1).
    #[arg(long)]
    pub pulses_per_revolution: Option<usize>,
    /// Averaged segment length, e.g. "2.5 ms" (default).
    #[arg(long)]
    pub segment: Option<TimeSpan>,
    #[arg(long)]
    pub max_revolutions: Option<usize>,
    /// angular (default), subsample or integer.
    #[arg(long)]
    pub averaging: Option<String>,
    /// zero_phase (default), causal or none.
    #[arg(long)]
    pub filter: Option<String>,
    /// High-pass cutoff, e.g. "10 kHz" (default).
    #[arg(long)]
    pub highpass_hz: Option<Frequency>,
    #[arg(long)]
    pub highpass_order: Option<usize>,
    #[arg(long)]
    pub lowpass_hz: Option<Frequency>,
    #[arg(long)]
    pub lowpass_order: Option<usize>,
    /// auto (3·fs/fc, default), scipy, or a number of samples.
    #[arg(long)]
    pub padlen: Option<String>,
    /// filter_then_integrate (default) or integrate_then_filter.
    #[arg(long)]
    pub chain_order: Option<String>,
    /// line (default), mean or none.
    #[arg(long)]
    pub detrend: Option<String>,
    /// Subtract the averaged velocity's mean before integrating (default true; the
    /// reference scripts use false).
    #[arg(long)]
    pub remove_offset: Option<bool>,
    /// Output sample rate, e.g. "1 GHz" (band-limited resampling).
    #[arg(long)]
    pub resample_hz: Option<Frequency>,
    #[arg(long)]
    pub peaks: Option<usize>,
    /// Also write the HDF5 output (and PNGs beside it).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
}
