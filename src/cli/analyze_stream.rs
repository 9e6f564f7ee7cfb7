//! `hdi analyze FILE --stream`: the band CWT of a long 1-D float `.npy` series in bounded
//! memory (`hdi::analysis::streaming`; docs/analysis.md, "Streaming band CWT"). The file is
//! memory-mapped and read block by block in two passes (the mean and the finite check, then
//! the transform); pages already consumed are dropped from the mapping so the resident memory
//! stays that of the transform, not of the file.

use anyhow::{bail, Context, Result};
use hdi::analysis::cwt::{FrequencyGrid, Normalization, Wavelet};
use hdi::analysis::streaming::{band_cwt, series_mean, BandOptions, BandPlan, BandScalogram};
use hdi::core::store::H5Out;
use hdi::formats::npy::{self, Dtype, NpyError};
use schemars::JsonSchema;
use serde::Serialize;
use serde_json::json;
use std::convert::Infallible;
use std::path::Path;
use std::time::Instant;

use super::args::AnalyzeArgs;

/// `hdi analyze FILE --stream --json`: a band CWT of a long series, reduced to bins of
/// `decimate` samples (docs/analysis.md, "Streaming band CWT"). `.npy` carries no unit: |W| is
/// in the file's units, powers in their square.
#[derive(Debug, Serialize, JsonSchema)]
pub(super) struct StreamOutput {
    /// the file as given on the command line
    file: String,
    /// element type of the array
    #[schemars(extend("enum" = ["float64", "float32"]))]
    dtype: String,
    /// samples in the record
    #[schemars(range(min = 4))]
    samples: usize,
    /// sample rate (--sample-rate), Hz
    #[serde(rename = "sample_rate_Hz")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    sample_rate_hz: f64,
    /// lowest and highest analysed frequency, Hz
    #[serde(rename = "band_Hz")]
    band_hz: [f64; 2],
    /// samples per output bin
    #[schemars(range(min = 1))]
    decimate: usize,
    /// output bins, ⌈samples/decimate⌉
    #[schemars(range(min = 1))]
    bins: usize,
    /// the mother wavelet (`morlet6`: Morlet ω0 = 6)
    wavelet: String,
    /// `L1`: a tone of amplitude A reads |W| = A
    normalization: String,
    /// the series mean, removed before the transform (file units)
    mean: f64,
    /// median ridge frequency over the bins inside the cone of influence, Hz; null when no
    /// bin is
    #[serde(rename = "ridge_median_Hz")]
    ridge_median_hz: Option<f64>,
    /// per analysed frequency, increasing
    frequencies: Vec<FrequencyPower>,
    /// the overlap-save blocks
    blocks: Blocks,
    /// memory: the transform's own allocations and the process's peak resident set
    memory: Memory,
    /// wall time of the two passes, s
    seconds: Seconds,
}

/// One analysed frequency.
#[derive(Debug, Serialize, JsonSchema)]
struct FrequencyPower {
    #[serde(rename = "frequency_Hz")]
    frequency_hz: f64,
    /// mean |W|² over the whole record (the L1 global wavelet spectrum), file units²
    mean_power: f64,
    /// the largest |W| anywhere in the record, file units
    max_magnitude: f64,
}

#[derive(Debug, Serialize, JsonSchema)]
struct Blocks {
    /// number of blocks
    count: usize,
    /// output samples per block
    samples: usize,
    /// input samples read beyond each side of a block (the wavelet's support at the lowest
    /// frequency)
    overlap_samples: usize,
    /// FFT length per block
    fft_length: usize,
}

#[derive(Debug, Serialize, JsonSchema)]
struct Memory {
    /// the transform's allocations at their peak (block, spectra, buffers, bins), bytes
    transform_bytes: usize,
    /// peak resident set of the process (Linux VmHWM), bytes; null where unknown
    peak_rss_bytes: Option<u64>,
}

#[derive(Debug, Serialize, JsonSchema)]
struct Seconds {
    /// first pass: mean and finite check
    mean_pass: f64,
    /// second pass: the transform
    transform: f64,
}

/// A 1-D float `.npy` array, memory-mapped read-only.
struct NpySeries {
    map: memmap2::Mmap,
    data_offset: usize,
    samples: usize,
    /// 8 (float64) or 4 (float32).
    size: usize,
    big_endian: bool,
    /// Bytes of the map before this offset were released from the process (a multiple of
    /// [`RELEASE_STEP`], so page-aligned).
    released: usize,
}

/// Consumed pages are dropped from the mapping in steps of this many bytes.
const RELEASE_STEP: usize = 1 << 20;

impl NpySeries {
    fn open(path: &Path) -> Result<Self> {
        let file = std::fs::File::open(path)?;
        // SAFETY: a read-only map of a file hdi does not modify while reading it (as the
        // other .npy readers, src/dmw/io/npy.rs).
        let map = unsafe { memmap2::Mmap::map(&file) }?;
        let h = match npy::parse(&map, map.len()) {
            Ok(h) => h,
            Err(NpyError::NotNpy) => {
                bail!("not a .npy file (--stream reads a 1-D float64 or float32 .npy array)")
            }
            Err(e) => return Err(e.into()),
        };
        let s = match h.dtype {
            Dtype::Scalar(s) if s.kind == 'f' && (s.size == 8 || s.size == 4) => s,
            Dtype::Scalar(s) => bail!(
                "element type {}{}; --stream reads float64 or float32",
                s.kind,
                s.size
            ),
            Dtype::Structured { .. } => {
                bail!("a structured array; --stream reads a plain 1-D float64 or float32 array")
            }
        };
        let [samples] = h.shape[..] else {
            bail!("array of shape {:?}; --stream reads a 1-D series", h.shape);
        };
        if map.len() < h.data_offset + h.data_len() {
            bail!("the data is shorter than its header says");
        }
        #[cfg(unix)]
        map.advise(memmap2::Advice::Sequential)?;
        Ok(NpySeries {
            map,
            data_offset: h.data_offset,
            samples,
            size: s.size,
            big_endian: s.big_endian,
            released: 0,
        })
    }

    fn dtype(&self) -> &'static str {
        if self.size == 8 {
            "float64"
        } else {
            "float32"
        }
    }

    /// Samples `start…start + buf.len()` as f64. Reads go forward, so the pages below the
    /// byte `start` is on are released first.
    fn read(&mut self, start: usize, buf: &mut [f64]) -> Result<(), Infallible> {
        let begin = self.data_offset + start * self.size;
        self.release_below(begin);
        let bytes = &self.map[begin..begin + buf.len() * self.size];
        match (self.size, self.big_endian) {
            (8, false) => fill(buf, bytes, |b| {
                f64::from_le_bytes(b.try_into().unwrap_or([0; 8]))
            }),
            (8, true) => fill(buf, bytes, |b| {
                f64::from_be_bytes(b.try_into().unwrap_or([0; 8]))
            }),
            (_, false) => fill(buf, bytes, |b| {
                f32::from_le_bytes(b.try_into().unwrap_or([0; 4])) as f64
            }),
            (_, true) => fill(buf, bytes, |b| {
                f32::from_be_bytes(b.try_into().unwrap_or([0; 4])) as f64
            }),
        }
        Ok(())
    }

    /// Drops the mapped pages below `byte` (rounded down to [`RELEASE_STEP`], never past the
    /// map) from this process: a file-backed map counts in the resident set until then, and a
    /// 10⁸-sample record would otherwise grow it by the whole file.
    fn release_below(&mut self, byte: usize) {
        // madvise acts on whatever is mapped in the range: it must not reach past this map.
        let end = byte.min(self.map.len()) / RELEASE_STEP * RELEASE_STEP;
        if end <= self.released {
            return;
        }
        #[cfg(unix)]
        {
            // SAFETY: [released, end) lies inside this read-only map (the map starts on a page
            // boundary and RELEASE_STEP is a multiple of the page size) and nothing borrows
            // it: dropping its pages only makes a later access fault them in from the file.
            let _ = unsafe {
                self.map.unchecked_advise_range(
                    memmap2::UncheckedAdvice::DontNeed,
                    self.released,
                    end - self.released,
                )
            };
        }
        self.released = end;
    }

    /// Starts the next pass from the beginning of the file.
    fn rewind(&mut self) {
        self.release_below(self.map.len());
        self.released = 0;
    }
}

fn fill(buf: &mut [f64], bytes: &[u8], decode: impl Fn(&[u8]) -> f64) {
    let size = bytes.len() / buf.len().max(1);
    for (v, b) in buf.iter_mut().zip(bytes.chunks_exact(size)) {
        *v = decode(b);
    }
}

pub(super) fn cmd_analyze_stream(a: &AnalyzeArgs) -> Result<()> {
    let file = a.file.display().to_string();
    if !a.file.is_file() {
        bail!("{file}: no such file");
    }
    let mut series = NpySeries::open(&a.file).with_context(|| file.clone())?;
    let Some(fs) = a.sample_rate.map(|f| f.0) else {
        bail!("{file}: a .npy array has no time axis: give --sample-rate");
    };
    // A band is what streaming is for: it is not guessed from the record.
    let (Some(f_min), Some(f_max)) = (a.f_min, a.f_max) else {
        bail!("{file}: --stream analyses a band: give --f-min and --f-max");
    };
    let opts = BandOptions {
        wavelet: Wavelet::default(),
        frequencies: FrequencyGrid::Log {
            f_min_hz: f_min.0,
            f_max_hz: f_max.0,
            count: a.frequencies.unwrap_or(10),
        },
        decimate: a.decimate.unwrap_or(0),
        block: None,
    };
    let plan = BandPlan::new(series.samples, fs, &opts).with_context(|| file.clone())?;
    let started = Instant::now();
    let mean = series_mean(plan.samples, plan.fft_len, |s, b| series.read(s, b))
        .with_context(|| file.clone())?;
    let mean_pass = started.elapsed().as_secs_f64();
    series.rewind();
    let started = Instant::now();
    let r = band_cwt(&plan, mean, |s, b| series.read(s, b)).with_context(|| file.clone())?;
    let transform = started.elapsed().as_secs_f64();
    let dtype = series.dtype().to_string();
    drop(series);
    if let Some(dir) = &a.out {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        write_h5(dir, &file, &r)?;
    }
    let out = StreamOutput {
        file: file.clone(),
        dtype,
        samples: plan.samples,
        sample_rate_hz: fs,
        band_hz: [
            plan.frequencies_hz[0],
            plan.frequencies_hz[plan.frequencies_hz.len() - 1],
        ],
        decimate: plan.decimate,
        bins: plan.bins,
        wavelet: plan.wavelet.to_string(),
        normalization: Normalization::Amplitude.to_string(),
        mean,
        ridge_median_hz: r.median_trusted_ridge_hz(),
        frequencies: (0..plan.frequencies_hz.len())
            .map(|j| FrequencyPower {
                frequency_hz: plan.frequencies_hz[j],
                mean_power: r.global_power[j],
                max_magnitude: r.max_magnitude_row(j).iter().fold(0f32, |m, &v| m.max(v)) as f64,
            })
            .collect(),
        blocks: Blocks {
            count: plan.blocks(),
            samples: plan.block,
            overlap_samples: plan.overlap,
            fft_length: plan.fft_len,
        },
        memory: Memory {
            transform_bytes: r.working_bytes,
            peak_rss_bytes: hdi::bench::readers::peak_rss_bytes(),
        },
        seconds: Seconds {
            mean_pass,
            transform,
        },
    };
    if a.json {
        println!("{}", serde_json::to_string(&out)?);
        return Ok(());
    }
    print_text(&out);
    if let Some(dir) = &a.out {
        println!("  wrote {}/analysis.h5", dir.display());
    }
    Ok(())
}

fn print_text(o: &StreamOutput) {
    let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
    println!(
        "{}: {} samples at {} MHz, band {:.3}–{:.3} kHz ({} frequencies, {}), {} bins of {} \
         samples ({:.2} s + {:.2} s)",
        o.file,
        o.samples,
        o.sample_rate_hz / 1e6,
        o.band_hz[0] / 1e3,
        o.band_hz[1] / 1e3,
        o.frequencies.len(),
        o.wavelet,
        o.bins,
        o.decimate,
        o.seconds.mean_pass,
        o.seconds.transform
    );
    println!("  {:>14} {:>14} {:>14}", "f (kHz)", "mean |W|²", "max |W|");
    for f in &o.frequencies {
        println!(
            "  {:>14.4} {:>14.6e} {:>14.6e}",
            f.frequency_hz / 1e3,
            f.mean_power,
            f.max_magnitude
        );
    }
    if let Some(f) = o.ridge_median_hz {
        println!(
            "  ridge (median, inside the cone of influence): {:.3} kHz",
            f / 1e3
        );
    }
    let rss = o.memory.peak_rss_bytes.map_or(String::new(), |b| {
        format!(", peak resident {:.1} MiB", mib(b))
    });
    println!(
        "  {} blocks of {} samples (overlap {}, FFT {}); transform memory {:.1} MiB{rss}",
        o.blocks.count,
        o.blocks.samples,
        o.blocks.overlap_samples,
        o.blocks.fft_length,
        mib(o.memory.transform_bytes as u64)
    );
}

/// `analysis.h5` with `analysis/band_scalogram` (the layout of `src/stages/analysis.rs`: an
/// NXdata group, units and long names on every dataset).
fn write_h5(dir: &Path, file: &str, r: &BandScalogram) -> Result<()> {
    let p = &r.plan;
    let out = H5Out::create(&dir.join("analysis.h5"))?;
    out.root_attributes(
        "analysis",
        "",
        &json!({ "file": file, "series": "values" }),
        &json!({}),
        "analysis",
    )?;
    let entry = out.group("analysis", Some("NXentry"))?;
    out.attr_str(&entry, "default", "band_scalogram")?;
    let g = out.group("analysis/band_scalogram", Some("NXdata"))?;
    out.attr_str(&g, "signal", "mean_power")?;
    out.attr_str_list(&g, "axes", &["frequency", "time"])?;
    out.attr_str(&g, "wavelet", &p.wavelet.to_string())?;
    out.attr_str(&g, "normalization", &Normalization::Amplitude.to_string())?;
    out.write_count(&g, "samples", p.samples as u64, "samples in the record")?;
    out.write_count(&g, "decimate", p.decimate as u64, "samples per bin")?;
    out.write_scalar(
        &g,
        "mean",
        r.mean,
        "1",
        "series mean removed before the transform",
    )?;
    let shape = (p.frequencies_hz.len(), p.bins);
    let power = ndarray::ArrayView2::from_shape(shape, &r.mean_power)?;
    out.write_array(
        &g,
        "mean_power",
        power,
        "1",
        "mean |W|² per bin (series units squared)",
    )?;
    let max = ndarray::ArrayView2::from_shape(shape, &r.max_magnitude)?;
    out.write_array(
        &g,
        "max_magnitude",
        max,
        "1",
        "max |W| per bin (L1: a tone of amplitude A reads A)",
    )?;
    out.write_1d(&g, "frequency", &p.frequencies_hz, "Hz", "frequency")?;
    out.write_1d(&g, "time", &r.time_s, "s", "bin centre time")?;
    out.write_1d(
        &g,
        "ridge_frequency",
        &r.ridge.frequency_hz,
        "Hz",
        "ridge: frequency of the largest mean power (parabola-refined)",
    )?;
    out.write_1d(
        &g,
        "coi_frequency",
        &r.coi_hz,
        "Hz",
        "cone of influence: lowest frequency trusted throughout the bin",
    )?;
    out.write_1d(
        &g,
        "global_power",
        &r.global_power,
        "1",
        "mean |W|² over the record",
    )?;
    out.finish()?;
    Ok(())
}
