//! `hdi analyze FILE`: spectrum, wavelet ridge and Poincaré class of one series.

use anyhow::{bail, Context, Result};
use hdi::artefacts::analysis::AnalysisSummary;
use schemars::JsonSchema;
use serde::Serialize;
use std::time::Instant;

use super::args::AnalyzeArgs;

/// One series' spectrum peaks, wavelet ridge and periodicity class with its evidence
/// (docs/analysis.md). Units are in the key names.
#[derive(Debug, Serialize, JsonSchema)]
pub(super) struct AnalyzeOutput {
    input: AnalyzedInput,
    summary: AnalysisSummary,
}

/// The file and the series read from it.
#[derive(Debug, Serialize, JsonSchema)]
struct AnalyzedInput {
    /// the file as given on the command line
    file: String,
    /// format detected from the content
    #[schemars(extend("enum" = ["hdf5", "csv", "parquet", "arrow-file", "arrow-stream", "npy"]))]
    format: String,
    /// the column or dataset analysed
    series: String,
    /// SI unit of the series after conversion
    unit: String,
    /// where the sample rate came from (time column/dataset, attribute, metadata or
    /// --sample-rate)
    sample_rate_source: String,
}

/// The `source` attribute of the `analysis.h5` that `--out` writes.
#[derive(Serialize)]
struct AnalysedFile<'a> {
    file: String,
    series: &'a str,
}

pub(super) fn cmd_analyze(a: AnalyzeArgs) -> Result<()> {
    if a.stream {
        return super::analyze_stream::cmd_analyze_stream(&a);
    }
    use hdi::stages::analysis::{read_any_series, summary, write_outputs, AnalysisSettings};
    let settings = AnalysisSettings {
        window: match a.window.as_slice() {
            [t0, t1] => (Some(t0.0), Some(t1.0)),
            _ => (None, None),
        },
        f_min: a.f_min.map(|f| f.0),
        f_max: a.f_max.map(|f| f.0),
        frequencies: a.frequencies,
        peaks: a.peaks,
        min_peak_frequency: a.min_peak_frequency.map_or(0.0, |f| f.0),
    };
    if let Err(e) = settings.check() {
        bail!("--{}: {}", e.key.replace('_', "-"), e.message);
    }
    if !a.file.is_file() {
        bail!("{}: no such file", a.file.display());
    }
    if a.column.is_some() && a.dataset.is_some() {
        bail!("--column is for tables, --dataset for HDF5: give one");
    }
    let s = read_any_series(
        &a.file,
        a.column.as_deref().or(a.dataset.as_deref()),
        a.velocity.as_deref(),
        a.sample_rate.map(|f| f.0),
    )?;
    let started = Instant::now();
    let r = hdi::analysis::report::analyze(
        &s.x,
        s.v.as_deref(),
        s.sample_rate,
        s.t0,
        &settings.options(),
    )
    .map_err(|e| match e {
        // The range the options and the record gave: name the options.
        hdi::analysis::AnalysisError::FrequencyRange { .. } => {
            anyhow::anyhow!("{}: --f-min/--f-max: {e}", a.file.display())
        }
        e => anyhow::Error::new(e).context(format!("{}", a.file.display())),
    })?;
    let coherence = match &a.against {
        None => None,
        Some(path) => {
            if !path.is_file() {
                bail!("{}: no such file", path.display());
            }
            let y = read_any_series(path, a.against_series.as_deref(), Some("none"), None)?;
            let mc = hdi::analysis::coherence::MonteCarlo {
                surrogates: a.surrogates,
                seed: a.seed,
                ..Default::default()
            };
            let c = hdi::analysis::report::coherence_against(
                &s.x,
                s.t0,
                &r,
                &y.x,
                y.sample_rate,
                y.t0,
                &mc,
            )
            .with_context(|| format!("{} against {}", a.file.display(), path.display()))?;
            Some((c, format!("{} `{}`", path.display(), y.name)))
        }
    };
    let seconds = started.elapsed().as_secs_f64();
    let mut sum = summary(&r, &s.unit);
    sum.coherence = coherence
        .as_ref()
        .map(|(c, l)| hdi::stages::analysis::coherence_summary(c, l));
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
            &serde_json::to_value(AnalysedFile {
                file: a.file.display().to_string(),
                series: &s.name,
            })?,
            &r,
            &s,
            coherence.as_ref().map(|(c, l)| (c, l.as_str())),
        )?;
    }
    if a.json {
        let out = AnalyzeOutput {
            input: AnalyzedInput {
                file: a.file.display().to_string(),
                format: s.format.clone(),
                series: s.name.clone(),
                unit: s.unit.clone(),
                sample_rate_source: s.rate_source.clone(),
            },
            summary: sum,
        };
        println!("{}", serde_json::to_string(&out)?);
        return Ok(());
    }
    let (du, k) = match s.unit.as_str() {
        "m" => ("nm", 1e9),
        "N" => ("mN", 1e3),
        u => (u, 1.0),
    };
    println!(
        "{} `{}` ({}, {}): {} samples at {} MHz ({}) from {:.4} ms ({seconds:.2} s)",
        a.file.display(),
        s.name,
        s.format,
        s.unit,
        r.samples,
        r.sample_rate_hz / 1e6,
        s.rate_source,
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
    if let Ok(c) = &r.classification {
        let d = &c.diagnostics;
        if let Some(p) = d.period_s {
            println!("  period {:.6} ms (decided by {})", p * 1e3, d.decided_by);
        }
        if let Some(e) = &d.lines {
            if let Some(f0) = e.fundamental_hz {
                println!(
                    "  spectral lines: fundamental {:.4} kHz, lowest line its harmonic {}",
                    f0 / 1e3,
                    e.lowest_harmonic.unwrap_or(0)
                );
            }
            let ratios: Vec<String> = e
                .lines
                .iter()
                .map(|l| format!("{:.5} ≈ {}/{}", l.ratio, l.numerator, l.denominator))
                .collect();
            println!(
                "  line ratios to the lowest: {} (lines carry {:.1} % of the variance)",
                ratios.join(", "),
                e.line_power_fraction * 100.0
            );
        }
    }
    if let Ok(sig) = &r.significance {
        println!(
            "  red noise: lag-1 autocorrelation {:.4}; {:.1} % of the scalogram outside the cone \
             is significant at {:.0} %",
            sig.background.alpha,
            sig.wavelet.significant_fraction * 100.0,
            sig.wavelet.level * 100.0
        );
        for (p, l) in r.peaks.iter().zip(&sig.peak_levels) {
            println!(
                "    {:>10.3} kHz: {} ({:.2}× the level)",
                p.frequency / 1e3,
                if p.amplitude > *l {
                    "significant"
                } else {
                    "not significant"
                },
                p.amplitude / l
            );
        }
    }
    if let Some(c) = &sum.coherence {
        println!(
            "  coherence against {} ({} surrogates, seed {}):",
            c.against, c.surrogates, c.seed
        );
        for b in &c.bands {
            println!(
                "    {:<11} {:>8.1}–{:<8.1} kHz: mean R² {}, {} above the {:.0} % level",
                b.name,
                b.band_hz[0] / 1e3,
                b.band_hz[1] / 1e3,
                b.mean_coherence.map_or("–".into(), |m| format!("{m:.3}")),
                b.significant_fraction
                    .map_or("–".into(), |m| format!("{:.1} %", m * 100.0)),
                c.level * 100.0
            );
        }
    }
    if let Some(dir) = &a.out {
        println!(
            "  wrote {}/analysis.h5 and {} PNGs",
            dir.display(),
            if coherence.is_some() { 5 } else { 4 }
        );
    }
    Ok(())
}
