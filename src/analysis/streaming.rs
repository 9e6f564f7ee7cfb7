//! Band CWT of a long record in bounded memory (docs/analysis.md, "Streaming band CWT"): the
//! transform of [`cwt::cwt_morlet`] (same wavelet, L1 normalisation, series mean removed, zero
//! outside the record) at a few frequencies, computed block by block by overlap-save and
//! reduced on the fly to bins of `decimate` samples.
//!
//! Samples arrive through a caller-supplied reader `read(start, buf)` that fills `buf` with
//! samples `start…start + buf.len()` (always inside the record); the series mean comes from
//! the caller ([`series_mean`] is the first pass). No I/O here.
//!
//! Overlap-save: the output samples `[a, a + B)` of a block need the input `[a − L, a + B + L)`
//! with `L = ⌈CUTOFF·s_max·fs/σ⌉`, the wavelet's one-sided support at the lowest frequency
//! ([`Wavelet::support_samples`], where its envelope is below e^{−36}); outside the record the
//! input is zero, as in the in-memory transform's zero padding. Each block is one real FFT of
//! `M` ≥ B + 2L points (a fast length), then per frequency the product with `Ψ̂(sω_k)` on the
//! M-point grid ([`cwt::ScaleFilter`], the in-memory code's filter) and one inverse FFT in
//! f32, as `cwt_morlet` does. Because `M ≥ B + 2L` the circular convolution does not wrap into
//! the kept outputs; the kernels differ from the in-memory ones only by the wavelet's tail
//! beyond L (< e^{−36}) and the negligible `G(0)` step of the analytic filter, aliased with
//! period M instead of N_pad. So the streamed |W| equals `cwt_morlet`'s to the rounding of the
//! f32 inverse transforms (tests: ≤ 1e-5 of the largest |W|, at and across block boundaries).
//!
//! Output, per frequency and bin of `decimate` samples (the last bin may be shorter): the mean
//! |W|² (summed in f64, stored f32) and the max |W| (f32). Per bin: its centre time, the cone
//! of influence (the highest per-sample value in the bin, i.e. the lowest frequency trusted
//! throughout it) and the ridge — [`cwt::ridge`] of the bins' RMS |W| = √(mean |W|²): the grid
//! frequency of the largest mean power, refined by the parabola in ln|W| against ln f.
//!
//! Memory: O(M + n_freq·n/decimate) — the block (M f64), its spectrum (M/2 + 1 complex f64)
//! and FFT scratch, one M-point complex f32 buffer and scratch per worker (at most one per
//! thread), the filter gains (≤ M/2 f64 per frequency); per frequency and bin 12 bytes of sums
//! and maxima (f64, f32) and 12 of outputs (f32 mean |W|², max |W| and the ridge's RMS), per bin
//! about 50 (time, COI, ridge). [`BandScalogram::working_bytes`] adds up the actual allocations.
//! Only the bins grow with the record.
//!
//! Determinism: the block loop is sequential and each frequency's row is transformed and
//! accumulated by one worker in sample order, so the results are bit-identical for any
//! number of threads (test).

use super::cwt::{
    self, coi_at_edge, fast_len, normalization_terms, FrequencyGrid, Normalization, Ridge,
    ScaleFilter, Scalogram, Wavelet, MAX_LEN,
};
use super::{check_rate, AnalysisError};
use crate::signal::rfft::RealFft;
use rayon::prelude::*;
use rustfft::num_complex::{Complex32, Complex64};
use rustfft::{Fft, FftPlanner};

/// Default FFT length floor: below it the per-block overhead (planning, the forward FFT, the
/// overlap) dominates; 2¹⁶ complex f32 (512 KiB) still fits a core's L2 cache.
const MIN_FFT_LEN: usize = 1 << 16;

/// What the band transform computes.
#[derive(Debug, Clone, PartialEq)]
pub struct BandOptions {
    pub wavelet: Wavelet,
    /// The band, typically 1–20 frequencies.
    pub frequencies: FrequencyGrid,
    /// Samples per output bin (≥ 1).
    pub decimate: usize,
    /// Output samples per block; `None`: `M = max(2¹⁶, fast length ≥ 16·L)` and `B = M − 2L`
    /// (the overlap costs at most 1/8 of each transform).
    pub block: Option<usize>,
}

/// The checked sizes of a band transform of `samples` samples.
#[derive(Debug, Clone, PartialEq)]
pub struct BandPlan {
    pub samples: usize,
    pub sample_rate_hz: f64,
    /// Analysed frequencies, Hz, increasing.
    pub frequencies_hz: Vec<f64>,
    /// Wavelet scale of each frequency, s.
    pub scales_s: Vec<f64>,
    pub wavelet: Wavelet,
    /// Samples per output bin.
    pub decimate: usize,
    /// Output bins, ⌈samples/decimate⌉.
    pub bins: usize,
    /// L: input samples read beyond each side of a block.
    pub overlap: usize,
    /// B: output samples per block.
    pub block: usize,
    /// M: FFT length per block (≥ B + 2L).
    pub fft_len: usize,
}

impl BandPlan {
    /// Checks the options against the record: sample rate, ≥ 4 samples, the band below Nyquist,
    /// decimate and block ≥ 1, sizes that fit.
    pub fn new(samples: usize, fs: f64, opts: &BandOptions) -> Result<Self, AnalysisError> {
        check_rate(fs)?;
        if samples < 4 {
            return Err(AnalysisError::TooShort {
                what: "band CWT",
                len: samples,
                min: 4,
                unit: "samples",
            });
        }
        opts.wavelet.validate()?;
        if opts.decimate == 0 {
            return Err(AnalysisError::parameter(
                "decimate",
                0,
                "must be ≥ 1 sample per output bin",
            ));
        }
        if opts.block == Some(0) {
            return Err(AnalysisError::parameter("block", 0, "must be ≥ 1 sample"));
        }
        let frequencies = opts.frequencies.frequencies(fs)?;
        let scales: Vec<f64> = frequencies
            .iter()
            .map(|&f| opts.wavelet.scale_of_frequency(f))
            .collect();
        let s_max = scales.iter().cloned().fold(0.0, f64::max);
        let support = opts.wavelet.support_samples(s_max, fs).ceil();
        // A block needs M ≥ B + 2L points: refuse a wavelet longer than the FFT limit allows.
        if 4.0 * support + 1.0 > MAX_LEN as f64 {
            return Err(AnalysisError::FrequencyRange {
                low_hz: frequencies[0],
                high_hz: frequencies[frequencies.len() - 1],
                reason: format!(
                    "the lowest frequency needs a wavelet of {support:.3e} samples (limit {})",
                    MAX_LEN / 4
                ),
            });
        }
        let overlap = support as usize;
        let (block, fft_len) = match opts.block {
            Some(b) => {
                let b = b.min(samples);
                if b > MAX_LEN - 2 * overlap {
                    return Err(AnalysisError::parameter(
                        "block",
                        b,
                        format!("block + 2 × overlap ({overlap}) exceeds {MAX_LEN} samples"),
                    ));
                }
                (b, fast_len(b + 2 * overlap))
            }
            None => {
                let m = fast_len(MIN_FFT_LEN.max(16 * overlap));
                if samples + 2 * overlap <= m {
                    (samples, fast_len(samples + 2 * overlap))
                } else {
                    (m - 2 * overlap, m)
                }
            }
        };
        let bins = samples.div_ceil(opts.decimate);
        if bins
            .checked_mul(frequencies.len())
            .is_none_or(|v| v > MAX_LEN)
        {
            return Err(AnalysisError::parameter(
                "band scalogram size",
                format!("{} frequencies × {bins} bins", frequencies.len()),
                format!("more than {MAX_LEN} values; decimate more or ask fewer frequencies"),
            ));
        }
        Ok(BandPlan {
            samples,
            sample_rate_hz: fs,
            frequencies_hz: frequencies,
            scales_s: scales,
            wavelet: opts.wavelet,
            decimate: opts.decimate,
            bins,
            overlap,
            block,
            fft_len,
        })
    }

    /// Number of blocks, ⌈samples/B⌉.
    pub fn blocks(&self) -> usize {
        self.samples.div_ceil(self.block)
    }

    /// Samples `[start, end)` of bin `b`.
    pub fn bin_range(&self, b: usize) -> (usize, usize) {
        let start = b * self.decimate;
        (start, (start + self.decimate).min(self.samples))
    }
}

/// Why a streamed transform stopped: the reader's own error, or the input or options.
#[derive(Debug)]
pub enum StreamError<E> {
    /// The reader failed on samples `start…start + len`.
    Read { start: usize, len: usize, error: E },
    /// Bad options or a non-finite sample (its index in the whole record).
    Analysis(AnalysisError),
}

impl<E> From<AnalysisError> for StreamError<E> {
    fn from(e: AnalysisError) -> Self {
        StreamError::Analysis(e)
    }
}

impl<E: std::fmt::Display> std::fmt::Display for StreamError<E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StreamError::Read { start, len, error } => {
                write!(f, "reading samples {start}…{}: {error}", start + len)
            }
            StreamError::Analysis(e) => e.fmt(f),
        }
    }
}

impl<E: std::error::Error + 'static> std::error::Error for StreamError<E> {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            StreamError::Read { error, .. } => Some(error),
            StreamError::Analysis(e) => e.source(),
        }
    }
}

/// Calls `read` for samples `[start, start + buf.len())` and checks them (index in the record).
fn read_checked<E>(
    read: &mut impl FnMut(usize, &mut [f64]) -> Result<(), E>,
    start: usize,
    buf: &mut [f64],
) -> Result<(), StreamError<E>> {
    read(start, buf).map_err(|error| StreamError::Read {
        start,
        len: buf.len(),
        error,
    })?;
    match buf.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(AnalysisError::NonFinite {
            what: "band CWT",
            index: start + i,
            value: buf[i],
        }
        .into()),
        None => Ok(()),
    }
}

/// First pass: the mean of `samples` samples read `block` at a time (summed in order, as
/// `cwt_morlet` sums the in-memory series), and the check that every sample is finite.
pub fn series_mean<E>(
    samples: usize,
    block: usize,
    mut read: impl FnMut(usize, &mut [f64]) -> Result<(), E>,
) -> Result<f64, StreamError<E>> {
    if samples == 0 {
        return Err(AnalysisError::TooShort {
            what: "band CWT",
            len: 0,
            min: 1,
            unit: "samples",
        }
        .into());
    }
    if block == 0 {
        return Err(AnalysisError::parameter("block", 0, "must be ≥ 1 sample").into());
    }
    let mut buf = vec![0.0; block.min(samples)];
    let mut sum = 0.0;
    let mut start = 0;
    while start < samples {
        let len = block.min(samples - start);
        read_checked(&mut read, start, &mut buf[..len])?;
        for v in &buf[..len] {
            sum += v;
        }
        start += len;
    }
    Ok(sum / samples as f64)
}

/// The decimated band scalogram (row-major `[frequency][bin]`).
#[derive(Debug, Clone)]
pub struct BandScalogram {
    pub plan: BandPlan,
    /// The mean removed from the series.
    pub mean: f64,
    /// Bin centres, s from the first sample: `(first + (len − 1)/2)/fs`.
    pub time_s: Vec<f64>,
    /// Mean |W|² per bin, (signal units)².
    pub mean_power: Vec<f32>,
    /// Max |W| per bin, signal units.
    pub max_magnitude: Vec<f32>,
    /// Mean |W|² over the whole record per frequency (the L1 global wavelet spectrum).
    pub global_power: Vec<f64>,
    /// Cone of influence per bin, Hz (the highest per-sample value in the bin).
    pub coi_hz: Vec<f64>,
    /// Ridge per bin, of the RMS |W| (its `magnitude` is an RMS |W|).
    pub ridge: Ridge,
    /// Bytes the transform held at its peak (block, spectra, buffers, gains, accumulators,
    /// outputs), from the actual allocation sizes.
    pub working_bytes: usize,
}

impl BandScalogram {
    pub fn mean_power_row(&self, j: usize) -> &[f32] {
        &self.mean_power[j * self.plan.bins..(j + 1) * self.plan.bins]
    }

    pub fn max_magnitude_row(&self, j: usize) -> &[f32] {
        &self.max_magnitude[j * self.plan.bins..(j + 1) * self.plan.bins]
    }

    /// Median ridge frequency over the bins inside the cone of influence.
    pub fn median_trusted_ridge_hz(&self) -> Option<f64> {
        super::cwt::median_trusted(&self.ridge.frequency_hz, &self.ridge.trusted)
    }
}

/// One frequency: its filter gains on the M-point grid and its bins' accumulators.
struct Row {
    /// First positive bin of the filter (analytic: ≥ 1).
    k_lo: usize,
    gains: Vec<f64>,
    power: Vec<f64>,
    max: Vec<f32>,
}

impl Row {
    /// Filters `spectrum` (one block), inverse transforms it and folds the block's outputs
    /// `[a, b)` (buffer positions `overlap…`) into the bins.
    #[allow(clippy::too_many_arguments)]
    fn accumulate(
        &mut self,
        spectrum: &[Complex64],
        ifft: &dyn Fft<f32>,
        buf: &mut [Complex32],
        scratch: &mut [Complex32],
        overlap: usize,
        (a, b): (usize, usize),
        decimate: usize,
    ) {
        buf.fill(Complex32::default());
        for (i, g) in self.gains.iter().enumerate() {
            let k = self.k_lo + i;
            // As `cwt_morlet`: the product in f64, stored in f32.
            let c = spectrum[k] * *g;
            buf[k] = Complex32::new(c.re as f32, c.im as f32);
        }
        ifft.process_with_scratch(buf, scratch);
        let mut t = a;
        while t < b {
            let bin = t / decimate;
            let end = b.min((bin + 1) * decimate);
            let (mut sum, mut max) = (0.0, self.max[bin]);
            for c in &buf[overlap + t - a..overlap + end - a] {
                // |W| from the f32 parts in f64, as `cwt_morlet`.
                let p = f64::from(c.re).powi(2) + f64::from(c.im).powi(2);
                sum += p;
                max = max.max(p.sqrt() as f32);
            }
            self.power[bin] += sum;
            self.max[bin] = max;
            t = end;
        }
    }
}

/// Second pass: the band scalogram of the record `plan` describes, the caller's `mean` removed,
/// read block by block through `read` (each call one contiguous range inside the record, in
/// increasing order; neighbouring ranges overlap by 2L).
pub fn band_cwt<E>(
    plan: &BandPlan,
    mean: f64,
    mut read: impl FnMut(usize, &mut [f64]) -> Result<(), E>,
) -> Result<BandScalogram, StreamError<E>> {
    if !mean.is_finite() {
        return Err(AnalysisError::parameter("series mean", mean, "must be finite").into());
    }
    let (n, fs, m, l) = (
        plan.samples,
        plan.sample_rate_hz,
        plan.fft_len,
        plan.overlap,
    );
    let nf = plan.frequencies_hz.len();
    // L1's gain does not depend on the scale.
    let (peak, analytic, _) = normalization_terms(Normalization::Amplitude, &plan.wavelet, 1.0, fs);
    let mut rows: Vec<Row> = plan
        .scales_s
        .iter()
        .map(|&s| {
            let f = ScaleFilter::new(&plan.wavelet, s, fs, m, peak, analytic);
            // Analytic: k_lo ≥ 1 and k_hi ≤ M/2, so the one-sided spectrum covers the filter.
            let (lo, hi) = (f.k_lo.max(1), f.k_hi);
            Row {
                k_lo: lo as usize,
                gains: (lo..=hi).map(|k| f.gain(k)).collect(),
                power: vec![0.0; plan.bins],
                max: vec![0.0; plan.bins],
            }
        })
        .collect();
    let rfft = RealFft::<f64>::new(&mut FftPlanner::new(), m);
    let ifft = FftPlanner::<f32>::new().plan_fft_inverse(m);
    let mut input = vec![0.0; m];
    let mut spectrum = vec![Complex64::default(); rfft.spectrum_len()];
    let mut forward_scratch = rfft.make_scratch();
    // One buffer per worker; each worker takes a fixed run of rows.
    let per_worker = nf.div_ceil(rayon::current_num_threads().clamp(1, nf));
    let mut pool: Vec<(Vec<Complex32>, Vec<Complex32>)> = (0..nf.div_ceil(per_worker))
        .map(|_| {
            (
                vec![Complex32::default(); m],
                vec![Complex32::default(); ifft.get_inplace_scratch_len()],
            )
        })
        .collect();
    for q in 0..plan.blocks() {
        let a = q * plan.block;
        let b = n.min(a + plan.block);
        // Buffer index i holds sample a − L + i; zero outside the record.
        let (lo, hi) = (a.saturating_sub(l), n.min(b + l));
        let off = lo + l - a;
        input.fill(0.0);
        let samples = &mut input[off..off + hi - lo];
        read_checked(&mut read, lo, samples)?;
        for v in samples.iter_mut() {
            *v -= mean;
        }
        rfft.forward_with_scratch(&input, &mut spectrum, &mut forward_scratch);
        rows.par_chunks_mut(per_worker)
            .zip(pool.par_iter_mut())
            .for_each(|(rows, (buf, scratch))| {
                for row in rows {
                    row.accumulate(&spectrum, &*ifft, buf, scratch, l, (a, b), plan.decimate);
                }
            });
    }
    let accumulator_bytes: usize = rows.iter().map(|r| 12 * r.power.len()).sum();
    let running_bytes = 8 * input.len()
        + 16 * (spectrum.len() + forward_scratch.len())
        + pool
            .iter()
            .map(|(b, s)| 8 * (b.len() + s.len()))
            .sum::<usize>()
        + rows.iter().map(|r| 8 * r.gains.len()).sum::<usize>()
        + accumulator_bytes;
    drop((input, spectrum, forward_scratch, pool));

    let bins = plan.bins;
    let mut mean_power = Vec::with_capacity(nf * bins);
    let mut max_magnitude = Vec::with_capacity(nf * bins);
    let mut global_power = Vec::with_capacity(nf);
    for row in rows {
        for (b, p) in row.power.iter().enumerate() {
            let (s, e) = plan.bin_range(b);
            mean_power.push((p / (e - s) as f64) as f32);
        }
        global_power.push(row.power.iter().sum::<f64>() / n as f64);
        max_magnitude.extend_from_slice(&row.max);
    }
    let (mut time_s, mut coi_hz) = (Vec::with_capacity(bins), Vec::with_capacity(bins));
    for b in 0..bins {
        let (s, e) = plan.bin_range(b);
        time_s.push((s as f64 + (e - s - 1) as f64 / 2.0) / fs);
        // min over i in [s, e) of min(i, n − 1 − i) is at an end of the bin.
        coi_hz.push(coi_at_edge(&plan.wavelet, s.min(n - e), fs));
    }
    let rms = Scalogram {
        frequencies_hz: plan.frequencies_hz.clone(),
        scales_s: plan.scales_s.clone(),
        sample_rate_hz: fs / plan.decimate as f64,
        n_time: bins,
        magnitude: mean_power.iter().map(|p| p.sqrt()).collect(),
        coi_hz: coi_hz.clone(),
        wavelet: plan.wavelet,
        normalization: Normalization::Amplitude,
    };
    let ridge = cwt::ridge(&rms);
    // The accumulators are consumed row by row while the outputs grow: counting both is an
    // upper bound of the second phase.
    let output_bytes = 4 * (mean_power.len() + max_magnitude.len() + rms.magnitude.len())
        + 8 * (time_s.len() + 2 * coi_hz.len() + 3 * ridge.index.len())
        + ridge.trusted.len();
    Ok(BandScalogram {
        plan: plan.clone(),
        mean,
        time_s,
        mean_power,
        max_magnitude,
        global_power,
        coi_hz,
        ridge,
        working_bytes: running_bytes.max(accumulator_bytes + output_bytes),
    })
}

#[cfg(test)]
mod tests;
