//! What the App. B and shock rows (`dyn-33`, `dyn-36` … `dyn-38`) read from an analysis: the
//! strongest spectral line inside a frequency band stated on physical grounds — never the line
//! nearest a target — and the time histories of a slider case (docs/analysis.md, "App. B on
//! the 3-DOF slider").

use super::pipeline::Stored;
use crate::signal::spectrum::{strongest_line, Peak};
use std::path::Path;

/// A frequency band [Hz] and why it holds what it is named for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Band {
    pub lo: f64,
    pub hi: f64,
    pub name: &'static str,
    /// The physical grounds, as the ledger shows them.
    pub why: &'static str,
}

impl Band {
    /// `3–20 kHz`.
    pub fn label(&self) -> String {
        let k = |f: f64| format!("{}", f / 1e3);
        format!("{}–{} kHz", k(self.lo), k(self.hi))
    }
}

/// The disk's motion. Its dominant line is printed as 10.7 kHz (App. B) and 12 kHz (§4.2, the
/// same line); the suspension's bending and torsional modes end at 3 kHz (App. B) and the
/// slider's lowest AB mode, roll, lies near 100 kHz: nothing the slider itself produces falls
/// between 3 and 20 kHz.
pub const DMW_BAND: Band = Band {
    lo: 3e3,
    hi: 20e3,
    name: "DMW band",
    why: "above the suspension modes (0.3–3 kHz, App. B), around the printed DMW line (10.7 kHz \
          App. B, 12 kHz §4.2), far below the lowest AB mode (roll ~100 kHz)",
};

/// The 1st pitch (~110 kHz) and roll (~100 kHz) AB modes. App. B, Fig. B.9(c): the chirp's
/// frequencies do not overlap the AB modes below 90 kHz (region I) nor between 120 and 240 kHz
/// (region II), so those two modes lie between 90 and 120 kHz.
pub const PITCH_ROLL_BAND: Band = Band {
    lo: 90e3,
    hi: 120e3,
    name: "pitch/roll band",
    why: "between region I (< 90 kHz) and region II (120–240 kHz), where App. B (Fig. B.9(c)) \
          says the excitation does not overlap the AB modes: the 1st pitch (~110 kHz) and roll \
          (~100 kHz) modes",
};

/// The normal (2nd pitch) AB mode, which "varies with FH between ~200 and ~1,000 kHz" (App. B,
/// after Fig. 4.2).
pub const NORMAL_BAND: Band = Band {
    lo: 200e3,
    hi: 1e6,
    name: "normal-mode band",
    why: "the normal (2nd pitch) AB mode varies with FH between ~200 and ~1 000 kHz (App. B, \
          Fig. 4.2)",
};

/// The lines of the shipped synthetic LDV record (raw/ldv/README.md, `hdi synth ldv`):
/// harmonics 118, 553, 1327, 3041 of 5 425 rpm and the 33.3 kHz NRRO tone [Hz].
pub const RECORD_LINES: [f64; 5] = [
    118.0 * 5425.0 / 60.0,
    553.0 * 5425.0 / 60.0,
    1327.0 * 5425.0 / 60.0,
    3041.0 * 5425.0 / 60.0,
    33.3e3,
];

/// The synthetic record's line within `tol` Hz of `f`, if any.
pub fn record_line(f: f64, tol: f64) -> Option<f64> {
    RECORD_LINES.iter().copied().find(|l| (l - f).abs() <= tol)
}

/// The amplitude spectrum an analysis stored (`analysis.h5`: `analysis/spectrum`), its bin
/// spacing, and the analysis's Hann window.
pub struct StoredSpectrum {
    pub frequency: Vec<f64>,
    pub amplitude: Vec<f64>,
    /// The red-noise amplitude level per bin (`analysis/spectrum/significance_level`; absent
    /// in analyses before issue 34 or of a constant series).
    pub level: Option<Vec<f64>>,
}

impl StoredSpectrum {
    pub fn read(a: &Stored) -> Option<StoredSpectrum> {
        let path = a.dir.join(crate::artefacts::analysis::FILE);
        Some(StoredSpectrum {
            frequency: read_1d(&path, "analysis/spectrum/frequency")?,
            amplitude: read_1d(&path, "analysis/spectrum/amplitude")?,
            level: read_1d(&path, "analysis/spectrum/significance_level"),
        })
    }

    /// A line's amplitude over the red-noise level at its frequency (linear between bins).
    pub fn level_ratio(&self, p: &Peak) -> Option<f64> {
        let level = self.level.as_ref()?;
        let df = self.resolution();
        let x = p.frequency / df;
        let (i, t) = (x.floor() as usize, x - x.floor());
        let l0 = *level.get(i)?;
        let l = level.get(i + 1).map_or(l0, |l1| l0 + t * (l1 - l0));
        (l > 0.0).then(|| p.amplitude / l)
    }

    /// What the analysis's 95 % red-noise test says of a line, for a row's note.
    pub fn significance_note(&self, p: Option<Peak>) -> String {
        match p.and_then(|p| self.level_ratio(&p)) {
            Some(r) if r > 1.0 => {
                format!(" (significant against AR(1) noise: {r:.2}× the 95 % level)")
            }
            Some(r) => format!(" (NOT significant against AR(1) noise: {r:.2}× the 95 % level)"),
            None => String::new(),
        }
    }

    /// Bin spacing [Hz].
    pub fn resolution(&self) -> f64 {
        self.frequency.get(1).copied().unwrap_or(f64::NAN)
    }

    /// The strongest line (largest local maximum, Hann-refined) inside `band`.
    pub fn strongest(&self, band: &Band) -> Option<Peak> {
        strongest_line(&self.frequency, &self.amplitude, band.lo, band.hi)
    }

    /// The strongest line of the whole spectrum above `DMW_BAND.lo` (below it: the high-pass
    /// edge and the slow settling of the start).
    pub fn strongest_overall(&self) -> Option<Peak> {
        let top = self.frequency.last().copied().unwrap_or(0.0);
        strongest_line(&self.frequency, &self.amplitude, DMW_BAND.lo, top)
    }
}

/// A 1-D f64 dataset of an HDF5 file.
pub fn read_1d(path: &Path, dataset: &str) -> Option<Vec<f64>> {
    hdf5::File::open(path)
        .and_then(|f| f.dataset(dataset)?.read_raw::<f64>())
        .ok()
}

/// A case history's series and its sample interval (`case/history/<name>`, the `time` axis's
/// `sampling_rate`).
pub fn case_series(path: &Path, name: &str) -> Option<(Vec<f64>, f64)> {
    let x = read_1d(path, &format!("case/history/{name}"))?;
    let fs = hdf5::File::open(path)
        .and_then(|f| {
            f.dataset("case/history/time")?
                .attr("sampling_rate")?
                .read_scalar::<f64>()
        })
        .ok()?;
    (fs > 0.0 && !x.is_empty()).then_some((x, 1.0 / fs))
}

/// `"107.73 kHz 1.17e-4 nm"`: a line for the notes, its amplitude in `unit` (`scale` from SI)
/// to three significant digits (`–` when absent).
pub fn describe(p: Option<Peak>, scale: f64, unit: &str) -> String {
    p.map_or("–".into(), |p| {
        let a = p.amplitude * scale;
        let amp = if a != 0.0 && !(0.01..1e4).contains(&a.abs()) {
            format!("{a:.2e}")
        } else {
            format!(
                "{:.*}",
                (2 - a.abs().log10().floor() as i32).clamp(0, 4) as usize,
                a
            )
        };
        format!("{:.2} kHz {amp} {unit}", p.frequency / 1e3)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_are_ordered_and_apart_and_the_record_lines_are_the_shipped_ones() {
        for b in [DMW_BAND, PITCH_ROLL_BAND, NORMAL_BAND] {
            assert!(b.lo < b.hi && !b.why.is_empty(), "{}", b.name);
        }
        const { assert!(DMW_BAND.hi < PITCH_ROLL_BAND.lo && PITCH_ROLL_BAND.hi < NORMAL_BAND.lo) };
        assert_eq!(PITCH_ROLL_BAND.label(), "90–120 kHz");
        // raw/ldv/README.md: 10.67, 50.0, 120.0, 275.0 kHz and the 33.3 kHz NRRO tone.
        let khz: Vec<f64> = RECORD_LINES
            .iter()
            .map(|f| (f / 10.0).round() / 100.0)
            .collect();
        assert_eq!(khz, [10.67, 50.0, 119.98, 274.96, 33.3]);
        assert_eq!(record_line(274.94e3, 1e3), Some(RECORD_LINES[3]));
        assert_eq!(record_line(262.3e3, 1.3e3), None);
    }

    #[test]
    fn a_line_reads_with_three_significant_digits() {
        let p = |a: f64| {
            Some(Peak {
                frequency: 107_732.0,
                amplitude: a,
                bin: 0,
            })
        };
        assert_eq!(describe(p(1.1669e-13), 1e9, "nm"), "107.73 kHz 1.17e-4 nm");
        assert_eq!(describe(p(0.4924e-9), 1e9, "nm"), "107.73 kHz 0.492 nm");
        assert_eq!(describe(p(2.324e-9), 1e9, "nm"), "107.73 kHz 2.32 nm");
        assert_eq!(describe(None, 1e9, "nm"), "–");
    }
}
