//! The thin command-line layer: parse arguments, call the library, print. `anyhow` only here.

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::core::cache::Store;
use crate::core::config::PipelineFile;
use crate::core::executor::ExecutorKind;
use crate::core::units::{
    Area, Frequency, Length, PerArea, Pressure, Sensitivity, TimeSpan, Velocity, Viscosity,
};
use crate::engine::{self, Outcome, RunOptions, State};
use crate::stages;
use crate::stages::contact::{self, ContactConfig, SurfaceEnergyConfig};
use crate::stages::dmw::{self, DmwConfig};
use crate::stages::surfaces::{self, SurfaceConfig};

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
    executor: String,
    /// Slurm partition.
    #[arg(long)]
    partition: Option<String>,
    /// Cases per array task (amortises start-up).
    #[arg(long, default_value_t = 4)]
    cases_per_task: usize,
    /// Tasks per array at most (the site's MaxArraySize); more cases make more arrays.
    #[arg(long, default_value_t = 1000)]
    max_array: usize,
    /// Submit and return; a later `hdi run --executor slurm` collects and resubmits only
    /// what is still missing.
    #[arg(long)]
    no_wait: bool,
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
    /// One LDV record → DMW tracks and their statistics.
    Dmw(Box<DmwArgs>),
    /// ISBL contact curves (and the MTL lubricant law with --lubricant) for one interface.
    Contact(Box<ContactArgs>),
    /// 2-DOF slider cases: one actuation or a sweep, with metrics, tables and plots.
    Simulate(Box<SimulateArgs>),
    /// Spectrum, wavelet transform, Poincaré section and phase space of one series of an
    /// HDF5 file (a slider case, a DMW or excitation track, …): dominant frequencies and class.
    Analyze(Box<AnalyzeArgs>),
    /// Every reproducible number of the specs: target, hdi's value, tolerance, pass. Exit 1 if
    /// a reproducible target fails.
    Validate {
        #[arg(long)]
        json: bool,
        /// Only these areas (e.g. dmw).
        #[arg(long, num_args = 1..)]
        only: Vec<String>,
        /// Pipeline whose finished `[calibrate.*]` fits are re-evaluated (area `calibration`;
        /// skipped when the file does not exist).
        #[arg(long, default_value = "pipeline.toml")]
        config: PathBuf,
    },
    /// Generate the shipped synthetic sample data (deterministic).
    Synth {
        /// What to generate: `afm` (height maps) or `ldv` (an LDV record).
        what: String,
        /// Output directory (default raw/afm or raw/ldv).
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
    /// Print benchmark figures (surfaces stage on a 1024² map; no-op cached rerun).
    Bench {
        #[arg(long, default_value = "pipeline.toml")]
        config: PathBuf,
        #[arg(long, default_value_t = 1024)]
        size: usize,
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

/// `hdi dmw FILE`: every option has the name of its `[dmw.NAME]` key.
#[derive(Args, Debug)]
pub struct DmwArgs {
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
    /// none (default) or mccool.
    #[arg(long)]
    pub summit_offset: Option<String>,
    /// junction_shear (default) or seed_power_elastic.
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
    /// interference_tangent (default) or static_curve.
    #[arg(long)]
    pub contact_force: Option<String>,
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

pub fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Run {
            config,
            only,
            force,
            dry_run,
            jobs,
            slurm,
        } => {
            if slurm.executor.parse::<ExecutorKind>()? == ExecutorKind::Slurm && !dry_run {
                let submitted = run_cases_on_slurm(&config, &slurm, jobs)?;
                if !submitted {
                    return Ok(());
                }
            }
            cmd_run(&config, only, force, dry_run, jobs)
        }
        Command::ExecCases {
            manifest,
            task,
            offset,
        } => cmd_exec_cases(&manifest, task + offset),
        Command::Status { config, json } => cmd_status(&config, json),
        Command::Gc { config, dry_run } => cmd_gc(&config, dry_run),
        Command::Surface(args) => cmd_surface(*args),
        Command::Dmw(args) => cmd_dmw(*args),
        Command::Contact(args) => cmd_contact(*args),
        Command::Simulate(args) => cmd_simulate(*args),
        Command::Analyze(args) => cmd_analyze(*args),
        Command::Validate { json, only, config } => cmd_validate(json, &only, &config),
        Command::Synth {
            what,
            out_dir,
            format,
            revolutions,
            seed,
            no_index,
        } => match what.as_str() {
            "ldv" => {
                let dir = out_dir.unwrap_or_else(|| PathBuf::from("raw/ldv"));
                let files =
                    crate::samples::write_ldv_sample(&dir, &format, revolutions, seed, !no_index)?;
                for f in files {
                    println!("{}", f.display());
                }
                Ok(())
            }
            "afm" => {
                let dir = out_dir.unwrap_or_else(|| PathBuf::from("raw/afm"));
                crate::samples::write_afm_samples(&dir)
                    .map(|_| ())
                    .with_context(|| format!("writing samples to {}", dir.display()))
            }
            other => bail!("unknown synth target `{other}` (available: afm, ldv)"),
        },
        Command::Bench { config, size } => crate::samples::bench(&config, size),
    }
}

fn load(config: &Path) -> Result<(PipelineFile, Vec<Box<dyn crate::stages::Stage>>)> {
    let file = stages::load(config)?;
    let stages = stages::build(&file)?;
    Ok((file, stages))
}

/// Exit status for "something is stale" in `hdi status`.
pub struct Stale;
impl std::fmt::Debug for Stale {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "stale")
    }
}
impl std::fmt::Display for Stale {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "some stage instances are stale")
    }
}
impl std::error::Error for Stale {}

fn cmd_run(
    config: &Path,
    only: Vec<String>,
    force: bool,
    dry_run: bool,
    jobs: Option<usize>,
) -> Result<()> {
    let started = Instant::now();
    let (file, stages) = load(config)?;
    let processed = file.processed_dir();
    let store =
        Store::open(&processed).with_context(|| format!("opening {}", processed.display()))?;
    let jobs = jobs.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    });
    let opts = RunOptions {
        only,
        force,
        dry_run,
        jobs,
    };
    let report = engine::run(stages, &store, &opts)?;
    if dry_run {
        for (name, o) in &report.outcomes {
            match o {
                Outcome::WouldRun(why) => println!("would run  {name}: {}", why.join("; ")),
                _ => println!("fresh      {name}"),
            }
        }
        return Ok(());
    }
    let ran = report.count(|o| matches!(o, Outcome::Ran { .. }));
    let cached = report.count(|o| matches!(o, Outcome::Cached));
    let n_failed = report.count(|o| matches!(o, Outcome::Failed(_)));
    let mut first_failure = None;
    for (name, o) in &report.outcomes {
        match o {
            Outcome::Ran { seconds } => eprintln!("ran     {name} ({seconds:.2} s)"),
            Outcome::Failed(e) => {
                // The first failure becomes the error line; list the others here.
                if first_failure.is_none() {
                    first_failure = Some(format!("stage `{name}` failed: {e}"));
                } else {
                    eprintln!("FAILED  {name}: {e}");
                }
            }
            Outcome::Skipped(e) => eprintln!("skipped {name}: {e}"),
            _ => {}
        }
    }
    // Tidy tables from the current entries: rewritten when something ran and nothing failed
    // (a failed instance keeps its earlier row), or when a table is missing.
    let tables_dir = processed.join("tables");
    let failed = report.failed();
    for (kind, rows) in engine::summary_rows(&store, &report.current) {
        let stem = tables_dir.join(table_name(&kind));
        if (ran > 0 && failed == 0)
            || !stem.with_extension("parquet").exists()
            || !stem.with_extension("csv").exists()
        {
            crate::core::store::write_table(&rows, &stem)?;
        }
    }
    let total = report.outcomes.len();
    if ran == 0 && failed == 0 {
        eprintln!(
            "nothing to do: all {total} stage instances fresh ({:.2} s)",
            started.elapsed().as_secs_f64()
        );
    } else {
        eprintln!(
            "ran {ran}, cached {cached}, failed {n_failed}, skipped {} of {total} ({:.2} s); \
             outputs in {}",
            failed - n_failed,
            started.elapsed().as_secs_f64(),
            processed.display()
        );
    }
    if let Some(first) = first_failure {
        if n_failed > 1 {
            bail!("{first} (and {} more failed)", n_failed - 1);
        }
        bail!("{first}");
    }
    if failed > 0 {
        bail!("{failed} stage instance(s) did not run");
    }
    Ok(())
}

/// Summary table per stage kind: `surfaces`, `interfaces`, `dmw` (a mass noun), `analyses`.
fn table_name(kind: &str) -> String {
    match kind {
        "dmw" => "dmw".into(),
        "analysis" => "analyses".into(),
        "three_dof" => "three_dof".into(),
        "doe" => "doe".into(),
        k => format!("{k}s"),
    }
}

/// `--executor slurm`: bring the `[simulate]` instances' upstream up to date, list their stale
/// cases into a manifest, submit it as array jobs and wait for them. Returns `false` for
/// `--no-wait` (submitted; nothing more to do now), `true` when the local run should follow
/// (every case is then cached).
fn run_cases_on_slurm(config: &Path, args: &SlurmArgs, jobs: Option<usize>) -> Result<bool> {
    use crate::core::executor::slurm::{submit_manifest, ScriptOptions, SlurmClient};
    use crate::core::executor::{manifest_path, CaseManifest};
    use crate::stages::distributed;
    let (file, _) = load(config)?;
    let processed = file.processed_dir();
    let store =
        Store::open(&processed).with_context(|| format!("opening {}", processed.display()))?;
    let upstream = distributed::case_upstream(&file, &store)?;
    if !upstream.is_empty() {
        let report = engine::run(
            crate::stages::build(&file)?,
            &store,
            &RunOptions {
                only: upstream,
                force: false,
                dry_run: false,
                jobs: jobs
                    .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
            },
        )?;
        if report.failed() > 0 {
            bail!(
                "the upstream of the [simulate]/[doe] instances failed: run `hdi run` to see why"
            );
        }
    }
    let config_abs =
        std::fs::canonicalize(config).with_context(|| format!("resolving {}", config.display()))?;
    let specs = distributed::stale_cases(&file, &config_abs, &store)?;
    if specs.is_empty() {
        eprintln!("slurm: no stale [simulate] or [doe] case to submit");
        return Ok(true);
    }
    let manifest = CaseManifest::new(specs, args.cases_per_task)?;
    let path = manifest_path(&processed, &manifest.id());
    manifest.write(&path)?;
    let client = SlurmClient::from_path();
    let workdir = config_abs
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    let opts = ScriptOptions {
        hdi: std::env::current_exe().context("locating the hdi binary")?,
        workdir,
        processed: std::fs::canonicalize(&processed)?,
        job_name: "hdi-cases".into(),
        partition: args.partition.clone(),
        max_running: None,
        extra_directives: Vec::new(),
    };
    let records = submit_manifest(&client, &opts, &path, &manifest, args.max_array)?;
    let ids: Vec<String> = records.iter().map(|r| r.job_id.to_string()).collect();
    eprintln!(
        "slurm: {} cases in {} tasks submitted as job(s) {} (manifest {})",
        manifest.cases.len(),
        manifest.task_count(),
        ids.join(", "),
        path.display()
    );
    if args.no_wait {
        eprintln!("slurm: --no-wait: `hdi run --executor slurm` later collects the results");
        return Ok(false);
    }
    let poll = std::env::var("HDI_SLURM_POLL_MS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5_000u64);
    let bar = indicatif::ProgressBar::new(manifest.task_count() as u64);
    let statuses = loop {
        let (total, each) = client.status_all(&records)?;
        bar.set_position(total.finished as u64);
        bar.set_message(format!(
            "{} running, {} pending",
            total.running, total.pending
        ));
        if total.is_finished() {
            break each;
        }
        std::thread::sleep(std::time::Duration::from_millis(poll));
    };
    bar.finish_and_clear();
    let mut done = CaseManifest::read(&path)?;
    done.merge_outcomes(&path)?;
    for (record, status) in records.iter().zip(&statuses) {
        done.mark_unreported(&processed, record, &status.failed);
    }
    done.write(&path)?;
    let failed = report_failed_cases(&done);
    if failed > 0 {
        bail!(
            "{failed} case(s) failed on Slurm (listed above; `hdi status` lists them too); \
             `hdi run --executor slurm` resubmits only what is missing"
        );
    }
    Ok(true)
}

/// Print the failed cases of a manifest (key, error, job/task, log); returns how many.
fn report_failed_cases(m: &crate::core::executor::CaseManifest) -> usize {
    use crate::core::executor::CaseStatus;
    let mut n = 0;
    for (i, e) in m.failed() {
        if let CaseStatus::Failed {
            error,
            job_id,
            task_id,
            log,
        } = &e.status
        {
            n += 1;
            let at = match (job_id, task_id) {
                (Some(j), Some(t)) => format!(" (job {j}, task {t})"),
                _ => String::new(),
            };
            let log = log
                .as_ref()
                .map_or(String::new(), |l| format!(", log {}", l.display()));
            eprintln!(
                "FAILED  case {i} {} {}{at}{log}: {error}",
                e.spec.kind, e.spec.key
            );
        }
    }
    n
}

fn cmd_exec_cases(manifest: &Path, task: usize) -> Result<()> {
    use crate::core::executor::{exec_task, TaskIdentity};
    // Manifests live in `processed/.hdi/slurm/manifests/`: the store is four levels up.
    let processed = manifest
        .ancestors()
        .nth(4)
        .filter(|p| p.join(".hdi").is_dir())
        .with_context(|| {
            format!(
                "{}: not a manifest under processed/.hdi/slurm/manifests/",
                manifest.display()
            )
        })?
        .to_path_buf();
    let store = Store::open(&processed)?;
    let report = exec_task(
        &store,
        manifest,
        task,
        &crate::stages::distributed::registry(),
        &TaskIdentity::from_env(&processed),
    )?;
    eprintln!(
        "task {task}: {} computed, {} cached, {} failed",
        report.computed, report.cached, report.failed
    );
    if report.failed > 0 {
        bail!("{} case(s) of task {task} failed", report.failed);
    }
    Ok(())
}

fn cmd_status(config: &Path, as_json: bool) -> Result<()> {
    let (file, stages) = load(config)?;
    let store = Store::open_existing(&file.processed_dir());
    let plan = engine::plan(stages, &store, &Default::default())?;
    let mut stale = 0;
    let mut rows = Vec::new();
    for p in &plan.planned {
        let (state, why) = match &p.state {
            State::Fresh => ("fresh", Vec::new()),
            State::Stale(why) if why.iter().any(|w| w == "never run") => ("missing", why.clone()),
            State::Stale(why) => ("stale", why.clone()),
        };
        if state != "fresh" {
            stale += 1;
        }
        if !as_json {
            if why.is_empty() {
                println!("{state:<8} {}", p.name);
            } else {
                println!("{state:<8} {}: {}", p.name, why.join("; "));
            }
        }
        rows.push(
            json!({"name": p.name, "kind": p.kind, "state": state, "why": why, "key": p.key}),
        );
    }
    if as_json {
        println!("{}", Value::Array(rows));
    } else {
        // Cases that failed on Slurm and are still missing from the cache.
        use crate::core::executor::{list_manifests, CaseManifest};
        for path in list_manifests(&file.processed_dir()).unwrap_or_default() {
            let Ok(mut m) = CaseManifest::read(&path) else {
                continue;
            };
            let _ = m.merge_outcomes(&path);
            let missing: std::collections::BTreeSet<String> =
                m.still_missing(&store).into_iter().map(|s| s.key).collect();
            m.cases.retain(|e| missing.contains(&e.spec.key));
            if m.failed().next().is_some() {
                println!("failed cases in {}:", path.display());
                report_failed_cases(&m);
            }
        }
    }
    if stale > 0 {
        return Err(Stale.into());
    }
    Ok(())
}

fn cmd_gc(config: &Path, dry_run: bool) -> Result<()> {
    let (file, stages) = load(config)?;
    let store = Store::open(&file.processed_dir())?;
    let plan = engine::plan(stages, &store, &Default::default())?;
    let removed = engine::gc(&plan, &store, dry_run)?;
    let verb = if dry_run { "would remove" } else { "removed" };
    for r in &removed {
        println!("{verb} {}", r.display());
    }
    eprintln!("{verb} {} item(s)", removed.len());
    Ok(())
}

fn cmd_surface(a: SurfaceArgs) -> Result<()> {
    let cfg = SurfaceConfig {
        file: a.file.clone(),
        channel: a.channel,
        size_x: a.size_x,
        size_y: a.size_y,
        z_unit: a.z_unit,
        crop: a.crop,
        level: a.level.unwrap_or_else(surfaces::default_level),
        filter_s: a.filter_s,
        filter_l: a.filter_l,
        summits: a.summits,
        radius: a.radius,
        birmingham: a.birmingham,
        moments: a.moments,
        periodic: a.periodic,
        histogram_bins: a.histogram_bins,
        scale_sweep: a.out.is_some(),
    };
    let params = surfaces::validate(&cfg, a.file.clone())
        .map_err(|(k, m)| anyhow::anyhow!("--{}: {m}", k.replace('_', "-")))?;
    let analysis = surfaces::analyse(&params)?;
    if let Some(out) = &a.out {
        let dir = out
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        surfaces::write_outputs(
            &analysis,
            &params,
            out,
            Some(dir),
            "",
            &json!([a.file.to_string_lossy()]),
        )?;
    }
    let report = surfaces::report_json(&analysis, &params);
    if a.json {
        println!("{report}");
    } else {
        let r = &analysis.report;
        println!(
            "{} ({}, channel {}), {} × {} px, dx = {:.3} nm",
            a.file.display(),
            analysis.raw.source.format,
            analysis.raw.channel,
            analysis.final_map().nx(),
            analysis.final_map().ny(),
            analysis.final_map().dx * 1e9
        );
        println!("  levelling  {}", report["levelling"]);
        println!("  filter     {}", report["filter"]);
        println!(
            "  σ          {:.4} nm   (Sa {:.4} nm, Ssk {:.3}, Sku {:.3})",
            r.sigma * 1e9,
            r.sa * 1e9,
            r.ssk,
            r.sku
        );
        println!(
            "  η          {:.2} µm⁻²  ({} summits, {})",
            r.eta * 1e-12,
            r.n_summits,
            r.summit_scheme
        );
        println!("  R          {:.4} µm   ({})", r.r * 1e6, r.r_definition);
        println!("  β = σRη    {:.5}", r.beta);
        println!(
            "  Nayak      η {:.2} µm⁻², R {:.4} µm, β {:.5} (α = {:.3})",
            r.nayak.eta * 1e-12,
            r.nayak.r * 1e6,
            r.nayak.beta,
            r.alpha
        );
        for w in &r.warnings {
            println!("  warning: {w}");
        }
    }
    Ok(())
}

fn cmd_dmw(a: DmwArgs) -> Result<()> {
    let mut cfg = DmwConfig::for_file(a.file.clone());
    cfg.sample_rate = a.sample_rate;
    if let Some(s) = a.sensitivity {
        cfg.sensitivity = s;
    }
    cfg.rpm = a.rpm;
    cfg.velocity_column = a.velocity_column;
    cfg.index_column = a.index_column;
    cfg.time_column = a.time_column;
    cfg.velocity_unit = a.velocity_unit;
    cfg.trigger_level = a.trigger_level;
    if let Some(s) = a.segment {
        cfg.segment = s;
    }
    cfg.max_revolutions = a.max_revolutions;
    if let Some(v) = a.averaging {
        cfg.averaging = v;
    }
    if let Some(v) = a.filter {
        cfg.filter = v;
    }
    if let Some(v) = a.highpass_hz {
        cfg.highpass_hz = v;
    }
    if let Some(v) = a.highpass_order {
        cfg.highpass_order = v;
    }
    cfg.lowpass_hz = a.lowpass_hz;
    if let Some(v) = a.lowpass_order {
        cfg.lowpass_order = v;
    }
    if let Some(v) = a.padlen {
        cfg.padlen = match v.parse::<i64>() {
            Ok(n) => dmw::PadlenConfig::Samples(n),
            Err(_) => dmw::PadlenConfig::Text(v),
        };
    }
    if let Some(v) = a.chain_order {
        cfg.chain_order = v;
    }
    if let Some(v) = a.detrend {
        cfg.detrend = v;
    }
    if let Some(v) = a.remove_offset {
        cfg.remove_offset = v;
    }
    cfg.resample_hz = a.resample_hz;
    if let Some(v) = a.peaks {
        cfg.peaks = v;
    }
    let params = dmw::validate(&cfg, a.file.clone())
        .map_err(|(k, m)| anyhow::anyhow!("--{}: {m}", k.replace('_', "-")))?;
    let (rec, res) = dmw::analyse(&params)?;
    if let Some(out) = &a.out {
        let dir = out
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        dmw::write_outputs(
            &rec,
            &res,
            &params,
            out,
            Some(dir),
            "",
            &json!([a.file.to_string_lossy()]),
        )?;
    }
    let report = dmw::report_json(&rec, &res, &params);
    if a.json {
        println!("{report}");
        return Ok(());
    }
    let q = &res.qa;
    let s = &res.stats;
    println!(
        "{} ({}, {}), {} samples at {} MS/s",
        a.file.display(),
        rec.format,
        q.layout,
        rec.velocity.len(),
        rec.sample_rate / 1e6
    );
    println!(
        "  revolutions  {} averaged of {} triggers ({}; {} averaging)",
        q.n_avg, q.n_triggers, q.segmentation, params.chain.averaging
    );
    if q.period_mean.is_finite() {
        println!(
            "  period       {:.6} ms ({:.1} rpm), relative std {:.2e}",
            q.period_mean * 1e3,
            60.0 / q.period_mean,
            q.period_relstd
        );
    }
    println!(
        "  noise floor  {:.3} µm/s in the average (residual {:.3} µm/s per revolution)",
        q.noise_floor * 1e6,
        q.residual_std * 1e6
    );
    println!(
        "  DMW          std {:.4} nm, peak-to-peak {:.4} nm ({} samples at {} MS/s, {} edge samples excluded each end)",
        s.std * 1e9,
        s.peak_to_peak * 1e9,
        res.tracks.d[0].len(),
        res.sample_rate / 1e6,
        q.edge_samples
    );
    for p in s.peaks.iter().take(5) {
        println!(
            "  line         {:9.3} kHz  {:.4} nm",
            p.frequency / 1e3,
            p.amplitude * 1e9
        );
    }
    for w in &q.warnings {
        println!("  warning: {w}");
    }
    Ok(())
}

fn cmd_contact(a: ContactArgs) -> Result<()> {
    let mut cfg = ContactConfig::defaults();
    if let Some(v) = a.parameter_set {
        cfg.parameter_set = v;
    }
    cfg.sigma = a.sigma;
    cfg.r = a.r;
    cfg.eta = a.eta;
    cfg.hardness = a.hardness;
    cfg.modulus = a.modulus;
    cfg.poisson = a.poisson;
    cfg.lj_spacing = a.lj_spacing;
    cfg.lubricant_thickness = a.lubricant_thickness;
    cfg.surface_energy = a.surface_energy.map(SurfaceEnergyConfig::Text);
    if let Some(v) = a.summit_offset {
        cfg.summit_offset = v;
    }
    if let Some(v) = a.friction_law {
        cfg.friction_law = v;
    }
    if let Some(v) = a.h_star_min {
        cfg.h_star_min = v;
    }
    if let Some(v) = a.h_star_max {
        cfg.h_star_max = v;
    }
    if let Some(v) = a.step {
        cfg.step = v;
    }
    cfg.lubricant = a.lubricant;
    cfg.nominal_area = a.nominal_area;
    cfg.sliding_speed = a.sliding_speed;
    cfg.lubricant_viscosity = a.lubricant_viscosity;
    cfg.gyration_radius = a.gyration_radius;
    let params = contact::validate(&cfg)
        .map_err(|(k, m)| anyhow::anyhow!("--{}: {m}", k.replace('_', "-")))?;
    let analysis = contact::analyse(&params.params, &params)?;
    if let Some(out) = &a.out {
        let dir = out
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        contact::write_outputs(&analysis, &params, out, Some(dir), "", &json!([]))?;
    }
    if a.json {
        println!("{}", contact::report_json(&analysis, &params));
        return Ok(());
    }
    let p = analysis.model.params();
    let d = analysis.model.derived();
    println!(
        "ISBL interface ({}): σ = {:.3} nm, R = {:.3} µm, η = {:.1} µm⁻², β = {:.4}",
        params.parameter_set,
        p.sigma * 1e9,
        p.summit_radius * 1e6,
        p.summit_density * 1e-12,
        d.beta
    );
    println!(
        "  E* = {:.1} GPa, ω_c = {:.4} nm, ψ = {:.3}, t = {:.2} nm, ε = {:.2} nm",
        d.composite_modulus / 1e9,
        d.critical_interference * 1e9,
        d.plasticity_index,
        p.lubricant_thickness * 1e9,
        p.lj_spacing * 1e9
    );
    println!(
        "  {:>6} {:>12} {:>12} {:>12} {:>12} {:>12}",
        "h/σ", "P (Pa)", "k_c (Pa/nm)", "A_r/A_n", "Q (Pa)", "F_s (Pa)"
    );
    for x in [0.0, 1.0, 2.0, 3.0, 4.0, 6.0] {
        if x < params.h_star_min || x > params.h_star_max {
            continue;
        }
        let q = analysis.lookup.at(x * p.sigma)?;
        println!(
            "  {:>6.2} {:>12.4e} {:>12.4e} {:>12.4e} {:>12.4e} {:>12.4e}",
            x,
            q.pressure,
            q.stiffness * 1e-9,
            q.real_area_fraction,
            q.friction,
            q.adhesion
        );
    }
    let worst = analysis
        .table_error()
        .iter()
        .map(|e| e.max_rel)
        .fold(0.0, f64::max);
    let (lo, hi) = analysis.table().range();
    println!(
        "  force table: h/σ {lo} … {hi} step {}, max relative error vs direct {worst:.1e}",
        analysis.table().step()
    );
    if let Some(m) = &analysis.mtl {
        let l = m.landmarks();
        let g = |k: &str| l[k].as_f64().unwrap_or(f64::NAN);
        println!(
            "MTL lubricant ({}): μ0 = {} Pa·s, κ = {} nm, U = {} m/s, A_n = {} µm²",
            l["lubricant"].as_str().unwrap_or("?"),
            m.settings.limiting_viscosity,
            m.settings.kappa * 1e9,
            m.settings.speed,
            m.settings.nominal_area * 1e12
        );
        println!(
            "  k_P,max = {:.4e} N/m at h/σ = {:.4}; k_Q,max = {:.2} N/m",
            g("k_P_max_N_per_m"),
            g("h_star_max_stiffness"),
            g("k_Q_max_N_per_m")
        );
        println!(
            "  total stiffness there: normal {:.4e} N/m, lateral {:.4e} N/m",
            g("k_normal_total_at_peak_N_per_m"),
            g("k_lateral_total_at_peak_N_per_m")
        );
        println!(
            "  lubricant bearing force: {:.4} mN at 3σ + 2κ, {:.4} mN at 3σ; Q_lub {:.4} µN",
            g("P_lub_transition_end_mN"),
            g("P_lub_onset_mN"),
            g("Q_lub_transition_end_uN")
        );
    }
    Ok(())
}

/// `hdi analyze`.
#[derive(Args, Debug)]
pub struct AnalyzeArgs {
    /// An HDF5 file (a case `h_XXX.XXnm.h5`, a `dmw.h5`, or any file with a 1-D series and a
    /// `time` dataset with a `sampling_rate` attribute beside it).
    pub file: PathBuf,
    /// Series to analyse (default: `case/history/heave` or `dmw/tracks/D1`).
    #[arg(long)]
    pub dataset: Option<String>,
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

fn cmd_analyze(a: AnalyzeArgs) -> Result<()> {
    use crate::stages::analysis::{read_series, summary, write_outputs, AnalysisSettings};
    let settings = AnalysisSettings {
        window: match a.window.as_slice() {
            [t0, t1] => (Some(t0.0), Some(t1.0)),
            _ => (None, None),
        },
        f_min: a.f_min.0,
        f_max: a.f_max.0,
        frequencies: a.frequencies,
        peaks: a.peaks,
        min_peak_frequency: a.min_peak_frequency.map_or(0.0, |f| f.0),
    };
    if let Err((k, m)) = settings.check() {
        bail!("--{}: {m}", k.replace('_', "-"));
    }
    if !a.file.is_file() {
        bail!("{}: no such file", a.file.display());
    }
    let s = read_series(&a.file, a.dataset.as_deref(), a.velocity.as_deref())?;
    let started = Instant::now();
    let r = crate::analysis::report::analyze(
        &s.x,
        s.v.as_deref(),
        s.sample_rate,
        s.t0,
        &settings.options(),
    )
    .with_context(|| format!("{}", a.file.display()))?;
    let seconds = started.elapsed().as_secs_f64();
    let sum = summary(&r, &s.unit);
    if let Some(dir) = &a.out {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let label = a
            .file
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        write_outputs(
            dir,
            "",
            &label,
            &json!({"file": a.file.display().to_string(), "dataset": a.dataset}),
            &r,
            &s,
        )?;
    }
    if a.json {
        println!("{sum}");
        return Ok(());
    }
    let (du, k) = match s.unit.as_str() {
        "m" => ("nm", 1e9),
        "N" => ("mN", 1e3),
        u => (u, 1.0),
    };
    println!(
        "{}: {} samples at {} MHz from {:.4} ms ({seconds:.2} s)",
        a.file.display(),
        r.samples,
        r.sample_rate_hz / 1e6,
        r.t0_s * 1e3
    );
    println!("  {:>12} {:>14}", "peak (kHz)", format!("amplitude ({du})"));
    for p in &r.peaks {
        println!("  {:>12.3} {:>14.5}", p.frequency / 1e3, p.amplitude * k);
    }
    if let Some(f) = r.median_trusted_ridge_hz() {
        println!(
            "  wavelet ridge (median, inside the cone of influence): {:.3} kHz",
            f / 1e3
        );
    }
    println!(
        "  Poincaré section: {} maxima → {}",
        r.section.maxima.len(),
        r.class_label()
    );
    if let Some(dir) = &a.out {
        println!("  wrote {}/analysis.h5 and 4 PNGs", dir.display());
    }
    Ok(())
}

fn cmd_simulate(a: SimulateArgs) -> Result<()> {
    use crate::stages::simulate::{self as sim, SimulateConfig};
    let mut cfg: SimulateConfig =
        toml::from_str("contact = \"adhoc\"").context("default simulate settings")?;
    cfg.model = a.model.clone();
    if !a.actuation.is_empty() {
        cfg.actuations = Some(a.actuation.clone());
    }
    macro_rules! set {
        ($($f:ident),*) => { $( if let Some(v) = a.$f.clone() { cfg.$f = v; } )* };
    }
    set!(
        actuation_start,
        actuation_stop,
        actuation_step,
        duration,
        steady_start,
        output_step,
        contact_force,
        integrator,
        rtol,
        contact_max_step,
        max_step,
        fixed_step,
        geometry,
        init
    );
    cfg.transit_delay = !a.no_transit_delay;
    cfg.dmw_wrap = a.dmw_wrap;
    cfg.kr_stiffening_beta = a.kr_stiffening_beta;
    cfg.bulge_width = a.bulge_width;
    cfg.histories = a.histories.clone();
    let params = sim::validate(&cfg).map_err(|(k, m)| {
        // The list key is `actuations` in pipeline.toml, `--actuation` on the command line.
        let flag = if k == "actuations" {
            "actuation".to_string()
        } else {
            k.replace('_', "-")
        };
        anyhow::anyhow!("--{flag}: {m}")
    })?;
    let mut interface = ContactConfig::defaults();
    interface.parameter_set = a.contact_set.clone().unwrap_or_else(|| a.model.clone());
    interface.surface_energy = a.surface_energy.clone().map(SurfaceEnergyConfig::Text);
    interface.lj_spacing = a.lj_spacing;
    interface.r = a.r;
    interface.eta = a.eta;
    interface.hardness = a.hardness;
    let isbl_params = contact::validate(&interface)
        .map_err(|(k, m)| {
            let flag = if k == "parameter_set" {
                "contact-set".to_string()
            } else {
                k.replace('_', "-")
            };
            anyhow::anyhow!("--{flag}: {m}")
        })?
        .params;
    let isbl = crate::contact::lookup::IsblLookup::build_standard(
        crate::contact::isbl::IsblModel::new(isbl_params)?,
    )?;
    let dmw = match &a.dmw {
        Some(p) => Some(sim::read_dmw_track(p)?),
        None => None,
    };
    let (root, temporary) = match &a.out {
        Some(o) => (o.clone(), false),
        None => (
            std::env::temp_dir().join(format!("hdi-simulate-{}", std::process::id())),
            true,
        ),
    };
    std::fs::create_dir_all(root.join("cases"))
        .with_context(|| format!("creating {}", root.display()))?;
    let bar = indicatif::ProgressBar::new(params.actuations.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} cases {elapsed} (eta {eta})")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let started = Instant::now();
    use rayon::prelude::*;
    let results: Vec<Result<sim::CaseOutcome>> = params
        .actuations
        .par_iter()
        .map(|&h| {
            let dir = root.join("cases").join(format!("h_{:06.2}nm", h * 1e9));
            std::fs::create_dir_all(&dir)?;
            let r = sim::simulate_case(&params, h, &isbl, dmw.as_ref(), &dir)
                .with_context(|| format!("case h_TFC = {:.3} nm", h * 1e9));
            bar.inc(1);
            let result = r?;
            Ok(sim::CaseOutcome {
                actuation: h,
                metrics: result.clone(),
                entry: crate::core::cases::CaseEntry {
                    key: String::new(),
                    dir,
                    result,
                    cached: false,
                },
            })
        })
        .collect();
    bar.finish_and_clear();
    let mut cases = Vec::new();
    for r in results {
        cases.push(r?);
    }
    cases.sort_by(|x, y| x.actuation.total_cmp(&y.actuation));
    let wall = started.elapsed().as_secs_f64();
    let sweep = sim::sweep_analysis(&params, &cases)?;
    let rows = sim::case_rows(&cases, &sweep);
    if a.out.is_some() {
        crate::core::store::write_table(&rows, &root.join("sweep"))?;
        sim::plots(&root, &params, &cases, &sweep, &a.model)?;
    }
    if temporary {
        let _ = std::fs::remove_dir_all(&root);
    }
    if a.json {
        println!("{}", json!({"cases": rows, "wall_time_s": wall}));
        return Ok(());
    }
    println!(
        "{} ({}), {} case(s) in {:.2} s",
        a.model,
        params.geometry,
        cases.len(),
        wall
    );
    println!(
        "  {:>8} {:>10} {:>9} {:>9} {:>8} {:>17} {:>10} {:>6} {:>8}",
        "h (nm)", "c̄ (nm)", "std (nm)", "FHM/BV %", "solid %", "regime", "F_c (mN)", "μ", "steps"
    );
    for r in &rows {
        let g = |k: &str| r.get(k).and_then(|v| v.as_f64());
        let s = |k: &str| g(k).map_or("-".to_string(), |x| format!("{x:.3}"));
        println!(
            "  {:>8.2} {:>10.4} {:>9.4} {:>9.2} {:>8.2} {:>17} {:>10} {:>6} {:>8}",
            g("actuation_nm").unwrap_or(f64::NAN),
            g("clearance_mean_nm").unwrap_or(f64::NAN),
            g("clearance_std_nm").unwrap_or(f64::NAN),
            g("vibration_percent").unwrap_or(f64::NAN),
            g("solid_contact_percent").unwrap_or(f64::NAN),
            r.get("regime").and_then(|v| v.as_str()).unwrap_or("-"),
            s("contact_force_mean_mN"),
            s("friction_coefficient"),
            g("steps").unwrap_or(f64::NAN)
        );
    }
    if cases.len() > 1 {
        let nm = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{:.2} nm", x * 1e9));
        println!("  touchdown {}", nm(sweep.touchdown_actuation_m));
        if let Some(cp) = &sweep.slopes.critical_point {
            println!(
                "  critical point {:.2} nm at clearance {:.3} nm",
                cp.actuation_m * 1e9,
                cp.clearance_m * 1e9
            );
        }
        for (k, l) in [
            ("A", &sweep.slopes.a),
            ("B", &sweep.slopes.b),
            ("C", &sweep.slopes.c),
            ("D", &sweep.slopes.d),
        ] {
            if let Some(l) = l {
                println!("  slope {k} {:.3}", l.slope);
            }
        }
    }
    Ok(())
}

/// Six significant digits, scientific for very small or large magnitudes.
fn fmt_number(x: f64) -> String {
    let a = x.abs();
    if x != 0.0 && !(1e-3..1e7).contains(&a) {
        format!("{x:.5e}")
    } else {
        format!("{x:.6}")
    }
}

fn cmd_validate(as_json: bool, only: &[String], config: &Path) -> Result<()> {
    let mut known: Vec<&str> = crate::validate::AREAS.iter().map(|(a, _)| *a).collect();
    known.push("calibration");
    known.push("optimisation");
    for o in only {
        if !known.contains(&o.as_str()) {
            bail!(
                "--only: unknown area `{o}` (available: {})",
                known.join(", ")
            );
        }
    }
    let wants = |a: &str| only.is_empty() || only.iter().any(|o| o == a);
    let mut areas: Vec<(&'static str, Vec<crate::validate::Row>)> = crate::validate::AREAS
        .iter()
        .filter(|(a, _)| wants(a))
        .map(|(a, rows)| (*a, rows()))
        .collect();
    // The fits of the pipeline in the working directory, when there is one (or when asked).
    if wants("calibration") && (config.exists() || !only.is_empty()) {
        let rows = crate::stages::calibrate::validation_rows(config)
            .with_context(|| format!("calibration rows from {}", config.display()))?;
        areas.push(("calibration", rows));
    }
    if wants("optimisation") && (config.exists() || !only.is_empty()) {
        let rows = crate::stages::doe::validation_rows(config)
            .with_context(|| format!("optimisation rows from {}", config.display()))?;
        areas.push(("optimisation", rows));
    }
    let failed = crate::validate::failures(&areas);
    let total: usize = areas.iter().map(|(_, r)| r.len()).sum();
    if as_json {
        let out: serde_json::Map<String, Value> = areas
            .iter()
            .map(|(a, rows)| {
                (
                    a.to_string(),
                    Value::Array(rows.iter().map(|r| r.to_json()).collect()),
                )
            })
            .collect();
        println!("{}", json!({"areas": out, "rows": total, "failed": failed}));
    } else {
        for (area, rows) in &areas {
            println!("── {area} ──");
            println!(
                "{:<6} {:<58} {:>12} {:>12} {:>10}  variant / note",
                "", "quantity", "target", "hdi", "tolerance"
            );
            for r in rows {
                let status = match (r.pass(), r.reproducible) {
                    (true, _) => "pass",
                    (false, true) => "FAIL",
                    (false, false) => "differs",
                };
                // Tolerances span 1e-12 … 50 %: short forms, scientific when tiny.
                let short = |x: f64| {
                    if x != 0.0 && x.abs() < 1e-3 {
                        format!("{x:.0e}")
                    } else {
                        format!("{}", (x * 1e4).round() / 1e4)
                    }
                };
                let tol = match r.tolerance {
                    crate::validate::Tolerance::Relative(t) => format!("±{}%", short(t * 100.0)),
                    crate::validate::Tolerance::Absolute(t) => format!("±{}", short(t)),
                };
                let unit = if r.unit == "1" {
                    String::new()
                } else {
                    format!(" {}", r.unit)
                };
                println!(
                    "{:<6} {:<58} {:>12} {:>12} {:>10}  {}{}",
                    status,
                    format!("{}{}", r.quantity, unit),
                    fmt_number(r.target),
                    fmt_number(r.ours),
                    tol,
                    r.variant,
                    if r.note.is_empty() {
                        String::new()
                    } else {
                        format!(" — {}", r.note)
                    }
                );
            }
        }
        eprintln!("{} rows, {} reproducible failed", total, failed);
    }
    if failed > 0 {
        std::process::exit(1);
    }
    Ok(())
}
