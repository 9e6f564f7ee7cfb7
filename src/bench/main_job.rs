//! The pipeline figures: the no-op cached rerun and the main job run cold in a temp dir.

use super::{
    time_best, BenchError, Details, Figure, Figures, Group, Result, StageWalls, Statistic, Unit,
};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The no-op cached rerun of `config` (the first run may do real work and is the warm-up).
pub(super) fn noop(out: &mut Figures, config: &Path, repeats: usize) -> Result<()> {
    let (times, _) = time_best(repeats, || out.host.run_pipeline(config).map(|_| ()))?;
    out.push(Figure::best(
        Group::Noop,
        "noop_cached_rerun",
        format!("no-op cached rerun of {}", config.display()),
        times,
        Unit::Seconds,
        repeats,
        Details::default(),
    ));
    Ok(())
}

/// The main job measured, not estimated: `CONFIG` and the `raw/` beside it copied into a temp
/// dir, the pipeline run there from scratch (one cold run; the per-stage wall times are the
/// ones `hdi run` logs as `ran NAME (S s)`), then its no-op rerun.
pub(super) fn cold(out: &mut Figures, config: &Path, repeats: usize) -> Result<()> {
    if !config.is_file() {
        return Err(BenchError::NoPipeline(config.to_path_buf()));
    }
    let from = config.parent().unwrap_or(Path::new("."));
    let from = if from.as_os_str().is_empty() {
        Path::new(".")
    } else {
        from
    };
    let tmp = ScratchDir::new("main-job")?;
    let raw = from.join("raw");
    if raw.is_dir() {
        copy_dir(&raw, &tmp.path().join("raw"))?;
    }
    let cfg = tmp.path().join("pipeline.toml");
    std::fs::copy(config, &cfg).map_err(BenchError::io("copying", config))?;
    out.host.main_job_starting(config);
    let t = Instant::now();
    let log = out.host.run_pipeline(&cfg)?;
    let secs = t.elapsed().as_secs_f64();
    let stages = stage_walls(&log);
    out.push(Figure {
        group: Group::MainJob,
        name: "main_job_cold".into(),
        label: format!("main job cold ({}, fresh temp dir)", config.display()),
        value: secs,
        unit: Unit::Seconds,
        statistic: Statistic::Single,
        repeats: 1,
        median: None,
        details: Details {
            stages_ran: Some(stages.len()),
            stage_wall_s: Some(StageWalls(stages.clone())),
            ..Details::default()
        },
    });
    let mut sorted = stages;
    sorted.sort_by(|a, b| b.1.total_cmp(&a.1));
    for (name, t) in sorted {
        out.push(Figure {
            group: Group::MainJob,
            name: format!("main_job_stage_{name}"),
            label: format!("  stage {name}"),
            value: t,
            unit: Unit::Seconds,
            statistic: Statistic::Single,
            repeats: 1,
            median: None,
            details: Details::default(),
        });
    }
    let (times, _) = time_best(repeats, || out.host.run_pipeline(&cfg).map(|_| ()))?;
    out.push(Figure::best(
        Group::MainJob,
        "main_job_noop_rerun",
        "main job, no-op cached rerun",
        times,
        Unit::Seconds,
        repeats,
        Details::default(),
    ));
    Ok(())
}

/// The `ran     NAME (S s)` lines of an `hdi run` log: (name, seconds) in log order.
fn stage_walls(log: &str) -> Vec<(String, f64)> {
    log.lines()
        .filter_map(|l| {
            let rest = l.strip_prefix("ran     ")?;
            let (name, t) = rest.rsplit_once(" (")?;
            let t = t.strip_suffix(" s)")?.parse::<f64>().ok()?;
            Some((name.to_string(), t))
        })
        .collect()
}

fn copy_dir(from: &Path, to: &Path) -> Result<()> {
    std::fs::create_dir_all(to).map_err(BenchError::io("creating", to))?;
    for e in std::fs::read_dir(from).map_err(BenchError::io("reading", from))? {
        let e = e.map_err(BenchError::io("reading", from))?;
        let p = e.path();
        if e.file_type()
            .map_err(BenchError::io("reading", &p))?
            .is_dir()
        {
            copy_dir(&p, &to.join(e.file_name()))?;
        } else {
            std::fs::copy(&p, to.join(e.file_name())).map_err(BenchError::io("copying", &p))?;
        }
    }
    Ok(())
}

/// A scratch directory under the system temp dir, removed when dropped (`tempfile` is a
/// dev-dependency only).
pub(super) struct ScratchDir(PathBuf);

impl ScratchDir {
    pub(super) fn new(tag: &str) -> Result<Self> {
        let p = std::env::temp_dir().join(format!("hdi-bench-{}-{tag}", std::process::id()));
        std::fs::create_dir_all(&p).map_err(BenchError::io("creating", &p))?;
        Ok(Self(p))
    }
    pub(super) fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn stage_walls_from_the_run_log() {
        let log = "ran     surface.a (1.5 s)\nskipped x\nran     dmw.b (0.25 s)\n";
        assert_eq!(
            super::stage_walls(log),
            [("surface.a".to_string(), 1.5), ("dmw.b".to_string(), 0.25)]
        );
    }
}
