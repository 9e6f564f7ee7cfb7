//! The command line: every command, subcommand and flag (clap). Each option of an ad-hoc
//! command has the name of its `pipeline.toml` key.

use clap::{Args, Parser, Subcommand};
use hdi::stages::surfaces;
use hdi::units::{
    Area, Frequency, Length, PerArea, Power, Pressure, Sensitivity, TimeSpan, Velocity, Viscosity,
};
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(
    name = "hdi",
    version,
    about = "Head-disk interface pipeline: AFM surfaces → contact → slider dynamics → signal analysis, cached by content hash"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// Where the independent cases run (docs/slurm.md).
#[derive(Args, Debug, Clone)]
pub struct SlurmArgs {
    /// `local` (the thread pool) or `slurm` (one `sbatch --array` job for the stale cases of
    /// the `[simulate]` instances; the rest of the pipeline then runs locally).
    #[arg(long, default_value = "local")]
    pub executor: String,
    /// Slurm partition.
    #[arg(long)]
    pub partition: Option<String>,
    /// Cases per array task (amortises start-up).
    #[arg(long, default_value_t = 4)]
    pub cases_per_task: usize,
    /// Tasks per array at most (the site's MaxArraySize); more cases make more arrays.
    #[arg(long, default_value_t = 1000)]
    pub max_array: usize,
    /// Submit and return; a later `hdi run --executor slurm` collects and resubmits only
    /// what is still missing.
    #[arg(long)]
    pub no_wait: bool,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Run the pipeline: recompute exactly the stale stage instances.
    Run {
        #[arg(long, default_value = "pipeline.toml")]
        config: PathBuf,
        /// Run only these instances (and what they consume).
        #[arg(long, num_args = 1..)]
        only: Vec<String>,
        /// Recompute even if cached (the --only instances, or all).
        #[arg(long)]
        force: bool,
        /// List what would run and why; change nothing.
        #[arg(long)]
        dry_run: bool,
        /// Parallel jobs (default: number of cores).
        #[arg(short = 'j', long)]
        jobs: Option<usize>,
        #[command(flatten)]
        slurm: SlurmArgs,
    },
    /// Compute one Slurm array task's cases of a case manifest into the cache (what the
    /// `hdi run --executor slurm` job script runs on the nodes).
    ExecCases {
        manifest: PathBuf,
        /// `$SLURM_ARRAY_TASK_ID`.
        #[arg(long)]
        task: usize,
        /// The array's first global task (several arrays cover one manifest).
        #[arg(long, default_value_t = 0)]
        offset: usize,
    },
    /// Fresh / stale (and why) per stage instance. Exit 1 if anything is stale.
    Status {
        #[arg(long, default_value = "pipeline.toml")]
        config: PathBuf,
        #[arg(long)]
        json: bool,
    },
    /// Remove cache entries the current pipeline does not reference, and leftover temp dirs.
    Gc {
        #[arg(long, default_value = "pipeline.toml")]
        config: PathBuf,
        #[arg(long)]
        dry_run: bool,
    },
    /// One height map → σ, R, η, β, summit count, levelling used.
    Surface(Box<SurfaceArgs>),
    /// Profilometer scans of the TFC bulge → a, w, x_TFC, height (± SE) per scan and the
    /// efficiency (height per heater power) over the scans (docs/bulge.md).
    Bulge(Box<BulgeArgs>),
    /// One LDV record → DMW tracks and their statistics.
    Dmw(Box<DmwArgs>),
    /// ISBL contact curves (and the MTL lubricant law with --lubricant) for one interface.
    Contact(Box<ContactArgs>),
    /// 2-DOF slider cases: one actuation or a sweep, with metrics, tables and plots.
    Simulate(Box<SimulateArgs>),
    /// Spectrum, wavelet transform, Poincaré section and phase space of one series of an
    /// HDF5 file (a slider case, a DMW or excitation track, …): dominant frequencies and class.
    Analyze(Box<AnalyzeArgs>),
    /// The published targets hdi is checked against, one typed row each (class G, K, D, Q or
    /// C): target, hdi's value, tolerance, pass (docs/validation.md). Exit 1 if a G, K or C row
    /// fails (or a Q row, when `--class` names Q); D rows never fail the command.
    Validate {
        #[arg(long)]
        json: bool,
        /// Only these areas (e.g. dmw).
        #[arg(long, num_args = 1..)]
        only: Vec<String>,
        /// Only rows of these classes, comma-separated (e.g. `G,K`): the gate then checks them.
        #[arg(long, value_delimiter = ',')]
        class: Vec<String>,
        /// Pipeline whose finished `[calibrate.*]` fits are re-evaluated (area `calibration`;
        /// skipped when the file does not exist).
        #[arg(long, default_value = "pipeline.toml")]
        config: PathBuf,
    },
    /// Generate the shipped synthetic sample data (deterministic).
    Synth {
        /// What to generate: `afm` (height maps), `ldv` (an LDV record) or `profilometer`
        /// (TFC-bulge scans at several heater powers).
        what: String,
        /// Output directory (default raw/afm, raw/ldv or raw/bulge).
        #[arg(long)]
        out_dir: Option<PathBuf>,
        /// ldv: file format, h5 (int16 counts, the shipped sample), csv or parquet.
        #[arg(long, default_value = "h5")]
        format: String,
        /// ldv: number of revolutions.
        #[arg(long)]
        revolutions: Option<usize>,
        /// ldv: random seed.
        #[arg(long)]
        seed: Option<u64>,
        /// ldv: leave out the index channel.
        #[arg(long)]
        no_index: bool,
    },
    /// Print benchmark figures with units, repeats and statistic: surfaces stage, 2-DOF µs per
    /// step, 76-case sweep, one 3-DOF case, CWT, Hann spectrum, roughness, no-op rerun and
    /// (`--main-job`) the shipped pipeline cold (docs/performance.md, bench/README.md).
    Bench {
        #[arg(long, default_value = "pipeline.toml")]
        config: PathBuf,
        /// Side of the synthetic square map (surfaces, roughness), pixels.
        #[arg(long, default_value_t = 1024)]
        size: usize,
        /// Print one JSON document (docs/schemas/bench.json) instead of the table.
        #[arg(long)]
        json: bool,
        /// Run only these groups: surfaces, two-dof, sweep, three-dof, cwt, fft, roughness,
        /// noop, main-job (comma-separated).
        #[arg(long, value_delimiter = ',')]
        only: Vec<String>,
        /// Also run CONFIG (and the raw/ beside it) cold in a temp dir and print its per-stage
        /// wall times (takes as long as the main job).
        #[arg(long)]
        main_job: bool,
        /// Time the one kernel of `--only cwt|fft|roughness` on this float `.npy` array (1-D
        /// signal at 4 MS/s, or 2-D map over 4 µm) instead of the built-in input.
        #[arg(long)]
        input: Option<PathBuf>,
        /// Timed repeats per figure after the warm-up (default 3–5 by figure).
        #[arg(long)]
        repeat: Option<usize>,
        /// Instead: time every binary height-map and LDV reader on the files under these
        /// directories (MB/s, peak memory), e.g. `--readers tests/data`.
        #[arg(long, num_args = 1..)]
        readers: Vec<PathBuf>,
        /// One timed read of FILE in this process (what `--readers` runs per file).
        #[arg(long, hide = true)]
        read_one: Option<PathBuf>,
    },
    /// Write the static HTML report of the pipeline (summary, per-instance numbers, figures
    /// and files, the validation table, provenance, status) into processed/report/
    /// (docs/report.md). `hdi run` writes it at its end too.
    Report {
        #[arg(long, default_value = "pipeline.toml")]
        config: PathBuf,
        /// Report directory (default: processed/report).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Leave the `hdi validate` table out (default: `[report] validation`).
        #[arg(long, conflicts_with = "validation")]
        no_validation: bool,
        /// Include the `hdi validate` table even when `[report] validation = false`.
        #[arg(long)]
        validation: bool,
        /// Rebuild even when the report of the same results exists.
        #[arg(long)]
        force: bool,
    },
    /// Compare two processed directories or two pipeline files: instances added, removed or
    /// changed (cache key), the parameters that changed, and the metric deltas of the summary
    /// tables and result.json (docs/diff.md). Exit 0 identical, 1 different, 2 error.
    Diff(Box<DiffArgs>),
    /// Re-hash the store entries the pipeline references (`--all`: every entry) against their
    /// manifests: damaged entries (a file edited, missing or extra) and orphans (docs/reliability.md).
    /// Exit 0 clean, 1 damaged, 2 error.
    Verify {
        #[arg(long, default_value = "pipeline.toml")]
        config: PathBuf,
        /// Check every entry in the store, not only those the pipeline references.
        #[arg(long)]
        all: bool,
        /// Move damaged entries aside and re-run the instances that made them, then verify again.
        #[arg(long)]
        repair: bool,
        #[arg(long)]
        json: bool,
        /// Parallel jobs for `--repair` (default: number of cores).
        #[arg(short = 'j', long)]
        jobs: Option<usize>,
    },
}

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
    /// Also write the full HDF5 output (and PNGs beside it).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
}

/// `hdi bulge FILE…`: the options have the names of the `[bulge.NAME]` keys.
#[derive(Args, Debug)]
pub struct BulgeArgs {
    #[arg(required = true, num_args = 1..)]
    pub files: Vec<PathBuf>,
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
    /// Also write the HDF5 output (and PNGs beside it).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
}

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
    #[arg(long, default_value = "5 kHz")]
    pub f_min: Frequency,
    #[arg(long, default_value = "1 MHz")]
    pub f_max: Frequency,
    /// Log-spaced CWT frequencies.
    #[arg(long, default_value_t = 100)]
    pub frequencies: usize,
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
}

/// `hdi diff`.
#[derive(Args, Debug)]
pub struct DiffArgs {
    /// The old side: a processed directory (with `.hdi/`) or a pipeline file.
    pub a: PathBuf,
    /// The new side: a processed directory or a pipeline file.
    pub b: PathBuf,
    /// Machine-readable output (docs/schemas/diff.json).
    #[arg(long)]
    pub json: bool,
    /// Also list unchanged instances and metrics.
    #[arg(long)]
    pub all: bool,
    /// Numbers within rtol·max(|old|, |new|) count as equal (default: exact; results are
    /// byte-deterministic).
    #[arg(long, default_value_t = 0.0)]
    pub rtol: f64,
}
