//! `hdi analyze`'s options.

use clap::Args;
use hdi::units::{Frequency, TimeSpan};
use std::path::PathBuf;

/// `hdi analyze`.
#[derive(Args, Debug)]
pub struct AnalyzeArgs {
    /// A series file: CSV/TSV, Parquet, Arrow IPC (Feather v2), `.npy`, or HDF5 (an hdi case
    /// or `dmw.h5`, or any file with a 1-D dataset). The format is detected from the content.
    pub file: PathBuf,
    /// HDF5: the dataset to analyse (default: `case/history/heave`, `dmw/tracks/D1`, or the
    /// file's only 1-D dataset).
    #[arg(long)]
    pub dataset: Option<String>,
    /// Tables: the column to analyse (default: the only numeric column besides time).
    #[arg(long)]
    pub column: Option<String>,
    /// Sample rate, e.g. `--sample-rate "500 kHz"`, when the file has no time axis (must agree
    /// with one if it has).
    #[arg(long)]
    pub sample_rate: Option<Frequency>,
    /// Its velocity (default: the file's own; `none`: central differences).
    #[arg(long)]
    pub velocity: Option<String>,
    /// Time window, e.g. `--window "0.7 ms" "1.3 ms"`.
    #[arg(long, num_args = 2)]
    pub window: Vec<TimeSpan>,
    /// Lowest CWT frequency (default: 5 kHz, raised to the cone of influence at mid-record
    /// for a short record, lowered with f_max for a slow one; the JSON says which).
    #[arg(long)]
    pub f_min: Option<Frequency>,
    /// Highest CWT frequency (default: 1 MHz, or fs/3 when that is lower).
    #[arg(long)]
    pub f_max: Option<Frequency>,
    /// Log-spaced CWT frequencies (default: 13.1 per octave, 100 over 5 kHz–1 MHz).
    #[arg(long)]
    pub frequencies: Option<usize>,
    #[arg(long, default_value_t = 5)]
    pub peaks: usize,
    #[arg(long)]
    pub min_peak_frequency: Option<Frequency>,
    /// Write `analysis.h5` and the PNGs (spectrum, scalogram, Poincaré map, phase portrait)
    /// into this directory.
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
    /// A second series file on the same time axis: wavelet coherence of FILE against it, with
    /// Monte Carlo levels from AR(1) surrogates.
    #[arg(long)]
    pub against: Option<PathBuf>,
    /// The against-series' column (tables) or dataset (HDF5).
    #[arg(long)]
    pub against_series: Option<String>,
    /// AR(1) surrogate pairs of the coherence Monte Carlo.
    #[arg(long, default_value_t = 300)]
    pub surrogates: usize,
    /// Seed of the surrogates.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Band CWT of a long 1-D float `.npy` series in bounded memory, read block by block: mean
    /// |W|² and max |W| per `--decimate` samples at the `--frequencies` log-spaced frequencies
    /// from --f-min to --f-max (docs/analysis.md, "Streaming band CWT").
    #[arg(long, requires = "decimate", conflicts_with_all = ["dataset", "column", "velocity", "window"])]
    pub stream: bool,
    /// With --stream: samples per output bin.
    #[arg(long, requires = "stream")]
    pub decimate: Option<usize>,
}
