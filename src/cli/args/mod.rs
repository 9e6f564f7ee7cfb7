//! The command line: every command, subcommand and flag (clap). The options of the one-off
//! commands live beside this file, one file per command; each has the name of its
//! `pipeline.toml` key.

mod analyze;
mod bulge;
mod contact;
mod diff;
mod dmw;
mod simulate;
mod surface;

pub use analyze::AnalyzeArgs;
pub use bulge::BulgeArgs;
pub use contact::ContactArgs;
pub use diff::DiffArgs;
pub use dmw::DmwArgs;
pub use simulate::SimulateArgs;
pub use surface::SurfaceArgs;

use clap::{Args, Parser, Subcommand};
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
    /// The JSON Schema of a command's JSON output, generated from the type it prints
    /// (docs/json.md); without NAME, the list.
    Schema {
        name: Option<String>,
        /// Write every schema into DIR (`docs/schemas`).
        #[arg(long, conflicts_with_all = ["name", "check"])]
        write: Option<PathBuf>,
        /// Exit 1 unless every schema in DIR is what the types give, and every file there
        /// is generated.
        #[arg(long, conflicts_with = "name")]
        check: Option<PathBuf>,
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
        /// bem and stream (only when named), noop, main-job (comma-separated).
        #[arg(long, value_delimiter = ',')]
        only: Vec<String>,
        /// Also run CONFIG (and the raw/ beside it) cold in a temp dir and print its per-stage
        /// wall times (takes as long as the main job).
        #[arg(long)]
        main_job: bool,
        /// Time the one kernel of `--only cwt|fft|roughness|bem` on this float `.npy` array (1-D
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
