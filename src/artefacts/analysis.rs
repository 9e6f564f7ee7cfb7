//! The analysis stage's `result.json` and summary-table row (docs/analysis.md), and the
//! summary `hdi analyze --json` prints: typed once, written by the stage and the command, read
//! by validation. Keys carry their units; the field order is the key order of the JSON.

use schemars::{json_schema, JsonSchema, Schema, SchemaGenerator};
use serde::de::{Deserializer, IgnoredAny, MapAccess, Visitor};
use serde::ser::{SerializeMap, Serializer};
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

/// The HDF5 file the stage writes into its outputs.
pub const FILE: &str = "analysis.h5";

/// Display unit and factor for a stored unit (m → nm, N → mN, m/s → mm/s).
pub fn display_unit(unit: &str) -> (&str, f64) {
    match unit {
        "m" => ("nm", 1e9),
        "N" => ("mN", 1e3),
        "m/s" => ("mm/s", 1e3),
        u => (u, 1.0),
    }
}

/// The unit as a key suffix: `amplitude_m`, `amplitude_nm`, `amplitude_m_s` (m/s); a
/// dimensionless series ("1") has plain `amplitude`.
pub fn amplitude_key(unit: &str) -> String {
    let u: String = unit
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    match u.as_str() {
        "1" | "" => "amplitude".into(),
        _ => format!("amplitude_{u}"),
    }
}

/// result.json of an [analysis.NAME] stage instance: where the series came from and the same
/// summary as `hdi analyze --json` (docs/analysis.md).
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct StoredAnalysisResult {
    #[serde(flatten)]
    pub result: AnalysisResult,
    /// the instance's row of processed/tables/analyses.* (six significant digits)
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(with = "AnalysisRow")]
    pub summary_row: Option<AnalysisRow>,
}

/// What the analysis stage returns: where the series came from and its summary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct AnalysisResult {
    pub series: AnalysedSeries,
    pub summary: AnalysisSummary,
    /// the stage's HDF5 output
    #[schemars(extend("const" = FILE))]
    pub file: String,
}

/// Where the analysed series is (also the `source` attribute of `analysis.h5`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct AnalysedSeries {
    /// the upstream stage instance
    pub source: String,
    /// file inside the source's outputs
    pub file: String,
    /// HDF5 dataset of the series
    pub dataset: String,
    /// velocity dataset; null: central differences
    pub velocity: Option<String>,
}

/// The summary of one analysed series (`summary` of `result.json` and of
/// `hdi analyze --json`); keys carry their units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct AnalysisSummary {
    /// [start, end) of the analysed window on the series' time axis, s
    pub window_s: [f64; 2],
    /// samples in the window
    #[schemars(range(min = 16))]
    pub samples: usize,
    /// sample rate, Hz
    #[serde(rename = "sample_rate_Hz")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub sample_rate_hz: f64,
    /// SI unit of the series (m, N, V, m/s, …; 1 if the file does not say)
    pub unit: String,
    /// the largest spectral lines (Hann-refined), largest first
    pub peaks: Vec<SpectralPeak>,
    /// median CWT ridge frequency inside the cone of influence, Hz
    #[serde(rename = "ridge_median_Hz")]
    pub ridge_median_hz: Option<f64>,
    /// periodicity class (docs/analysis.md)
    pub class: PeriodicityClass,
    /// periodic: section maxima per period (period-n: n)
    #[schemars(range(min = 1))]
    pub period_sections: Option<usize>,
    /// periodic: the period, s
    pub period_s: Option<f64>,
    /// why there is no class (too few section maxima)
    pub unclassified_reason: Option<String>,
    /// number of Poincaré-section maxima
    pub poincare_maxima: usize,
    /// the evidence behind `class`; null when unclassified
    pub evidence: Option<Evidence>,
    /// fraction of the trusted ridge samples where the wavelet power is significant
    #[serde(default)]
    pub ridge_significant_fraction: Option<f64>,
    /// the CWT frequency grid used and why
    #[serde(default)]
    pub frequency_grid: Option<FrequencyGridUsed>,
    /// red-noise significance of the spectrum and the scalogram (docs/analysis.md,
    /// "Significance"); null when the window has no background (a constant series)
    #[serde(default)]
    pub significance: Option<SignificanceSummary>,
    /// why there is no significance test
    #[serde(default)]
    pub significance_unavailable: Option<String>,
    /// wavelet coherence with a second series (`--against`, `against = …`)
    #[serde(default)]
    pub coherence: Option<CoherenceSummary>,
}

/// Wavelet coherence of the series against a second one (Grinsted et al. 2004), with Monte
/// Carlo levels from AR(1) surrogates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct CoherenceSummary {
    /// the against-series (file or instance, and dataset/column)
    pub against: String,
    /// AR(1) surrogate pairs of the Monte Carlo
    pub surrogates: usize,
    /// seed of the surrogates
    pub seed: u64,
    /// confidence level of the coherence levels
    pub level: f64,
    /// lag-1 autocorrelations of the series and of the against-series
    pub lag1_autocorrelation: [f64; 2],
    /// the stated bands the grid covers
    pub bands: Vec<BandCoherence>,
}

/// Coherence inside one band, over the samples outside the cone of influence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct BandCoherence {
    pub name: String,
    #[serde(rename = "band_Hz")]
    pub band_hz: [f64; 2],
    /// mean squared coherence R²
    pub mean_coherence: Option<f64>,
    /// fraction of the cells above the Monte Carlo level
    pub significant_fraction: Option<f64>,
    /// circular mean of the phase arg S(W_x W_y*), rad (negative: the series lags)
    #[serde(rename = "phase_rad")]
    pub phase_rad: Option<f64>,
}

/// The CWT grid: log-spaced frequencies from `f_min` to `f_max`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct FrequencyGridUsed {
    #[serde(rename = "f_min_Hz")]
    pub f_min_hz: f64,
    #[serde(rename = "f_max_Hz")]
    pub f_max_hz: f64,
    pub count: usize,
    /// given, the HDI band's default, or what the record changed (fs/3, cone of influence)
    pub reason: String,
}

/// Torrence & Compo (1998) red-noise significance of one analysed window.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SignificanceSummary {
    /// confidence level of every test
    #[schemars(range(min = 0, max = 1))]
    pub level: f64,
    /// background model: AR(1) with the window's lag-1 autocorrelation and variance
    pub background: String,
    /// the window's lag-1 autocorrelation α (biased sample ACF)
    pub lag1_autocorrelation: f64,
    /// fraction of the time–frequency cells outside the cone of influence whose wavelet
    /// power exceeds the local level (≈ 1 − level for noise)
    #[schemars(range(min = 0, max = 1))]
    pub significant_area_fraction: f64,
    /// frequencies where the global wavelet spectrum has a local maximum above its level, Hz
    #[serde(rename = "global_significant_peaks_Hz")]
    pub global_significant_peaks_hz: Vec<f64>,
    /// scale-averaged power of the stated bands that the grid covers
    pub bands: Vec<BandSignificance>,
}

/// Scale-averaged power of one band against its level (T&C eqs. 24–28).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct BandSignificance {
    pub name: String,
    /// the band asked for, Hz
    #[serde(rename = "band_Hz")]
    pub band_hz: [f64; 2],
    /// analysed frequencies inside it
    pub frequencies: usize,
    /// mean band power over the samples outside the cone of influence, over its level
    pub mean_power_to_level: Option<f64>,
    /// fraction of those samples above the level
    pub significant_fraction: Option<f64>,
    /// degrees of freedom of the level
    pub dof: f64,
}

/// The periodicity class as a stable word (the period is a separate key).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub enum PeriodicityClass {
    #[serde(rename = "fixed point")]
    FixedPoint,
    #[serde(rename = "periodic")]
    Periodic,
    #[serde(rename = "quasi-periodic")]
    QuasiPeriodic,
    #[serde(rename = "irregular")]
    Irregular,
    #[serde(rename = "unclassified")]
    Unclassified,
}

impl PeriodicityClass {
    /// The word written to the JSON.
    pub fn word(self) -> &'static str {
        match self {
            PeriodicityClass::FixedPoint => "fixed point",
            PeriodicityClass::Periodic => "periodic",
            PeriodicityClass::QuasiPeriodic => "quasi-periodic",
            PeriodicityClass::Irregular => "irregular",
            PeriodicityClass::Unclassified => "unclassified",
        }
    }
}

/// One spectral line: its amplitude under unit-named keys, then its frequency.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(extend("minProperties" = 2))]
pub struct SpectralPeak {
    // Not a doc comment: a flattened field's description would become the object's.
    #[serde(flatten)]
    pub amplitude: Amplitudes,
    /// refined line frequency, Hz
    #[serde(rename = "frequency_Hz")]
    pub frequency_hz: f64,
    /// above the red-noise level (`significance.level`) at its frequency; null when untested
    #[serde(default)]
    pub significant: Option<bool>,
    /// amplitude over that level
    #[serde(default)]
    pub amplitude_to_level: Option<f64>,
}

/// The evidence behind the class (docs/analysis.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Evidence {
    /// the test that decided (none: irregular)
    #[schemars(extend("enum" = ["decay", "section recurrence", "spectral lines", "return-map ring", "none"]))]
    pub decided_by: String,
    /// Poincaré-section statistics (maxima and minima at v = 0)
    pub section: SectionStatistics,
    /// the spectral-line test (docs/analysis.md); null when only the section was used
    pub spectral_lines: Option<SpectralLines>,
}

/// Poincaré-section statistics; a ratio that could not be computed is null.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SectionStatistics {
    // A = (max maxima − min minima)/2 under unit-named keys.
    #[serde(flatten)]
    #[schemars(schema_with = "section_amplitude_schema")]
    pub amplitude: Amplitudes,
    /// number of section maxima
    pub maxima: usize,
    /// (max − min) of the maxima / A (1); A is the amplitude_* key
    pub spread: Option<f64>,
    /// largest half-cycle swing of the last quarter / of the first quarter (1)
    pub final_to_initial: Option<f64>,
    /// median per-period swing ratio h_{i+2}/h_i (1)
    pub decay_ratio: Option<f64>,
    /// fraction of per-period swing ratios below 1
    pub decreasing_fraction: Option<f64>,
    /// k ≤ 16 with the smallest recurrence residual of the section points (0: not reached)
    pub best_period_sections: usize,
    /// max |x_{n+k} − x_n| / A at that k (1); null if not computed
    pub period_residual: Option<f64>,
    /// maxima distinct at 1e-4·A
    pub distinct_values: usize,
    /// their fraction of all maxima
    pub distinct_fraction: Option<f64>,
    /// occupied fraction of 36 angular sectors of the return map around its centroid
    pub ring_coverage: Option<f64>,
    /// r_min / r_max of the return map around its centroid (1)
    pub ring_hole: Option<f64>,
    /// median cosine of the angle between a return-map point's two nearest neighbours (−1:
    /// on a curve)
    pub neighbour_cosine: Option<f64>,
}

/// The spectral-line test (docs/analysis.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SpectralLines {
    /// Σ A²/2 over the lines / variance of the series (1)
    pub line_power_fraction: Option<f64>,
    /// common fundamental of the lines, Hz (least squares over the harmonic numbers); null if
    /// they are not commensurate
    #[serde(rename = "fundamental_Hz")]
    pub fundamental_hz: Option<f64>,
    /// harmonic number of the lowest line over the fundamental (q)
    #[schemars(range(min = 1))]
    pub lowest_harmonic: Option<u64>,
    /// largest q tried: 16, lowered so that the period q/f_low fits 3 times into the record
    pub max_denominator: u64,
    /// rms(x(t+P) − x(t)) / (√2·rms x) at the fundamental period P (0: exact recurrence; 1:
    /// unrelated); null without a fundamental
    pub recurrence_residual: Option<f64>,
    /// spectral resolution fs/N, Hz
    #[serde(rename = "resolution_Hz")]
    pub resolution_hz: f64,
    /// lines ≥ 5 % of the largest, lowest frequency first
    pub lines: Vec<SpectralLine>,
}

/// One line of the spectral-line test and its place in the harmonic series.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SpectralLine {
    #[serde(flatten)]
    pub amplitude: Amplitudes,
    /// refined line frequency, Hz
    #[serde(rename = "frequency_Hz")]
    pub frequency_hz: f64,
    /// frequency over the lowest line's frequency (1)
    pub ratio: f64,
    /// p of the rational approximation p/q of `ratio` (q ≤ max_denominator): of the accepted
    /// fundamental when the lines are commensurate, else the closest
    pub numerator: u64,
    /// q of that approximation
    pub denominator: u64,
    /// |f − n·f0| for this line's harmonic number n, Hz
    #[serde(rename = "mismatch_Hz")]
    pub mismatch_hz: f64,
    /// the tolerance the mismatch is held to: line_tolerance_bins·Δf·(1 + n/q), Hz
    #[serde(rename = "tolerance_Hz")]
    pub tolerance_hz: f64,
}

/// An amplitude under keys that name its unit, in order: `amplitude_<SI unit>` and
/// `amplitude_<display unit>` (one key when they coincide; plain `amplitude` when
/// dimensionless). A value that is not finite is written as null.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Amplitudes(pub Vec<(String, f64)>);

impl Amplitudes {
    /// `a` in `unit` and in its display unit.
    pub fn new(unit: &str, a: f64) -> Amplitudes {
        let (display, k) = display_unit(unit);
        let si = amplitude_key(unit);
        let shown = amplitude_key(display);
        if shown == si {
            Amplitudes(vec![(si, a * k)])
        } else {
            Amplitudes(vec![(si, a), (shown, a * k)])
        }
    }

    /// The value under `key` (NaN when absent or null).
    pub fn get(&self, key: &str) -> f64 {
        self.0
            .iter()
            .find(|(k, _)| k == key)
            .map_or(f64::NAN, |(_, a)| *a)
    }
}

impl Serialize for Amplitudes {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (k, a) in &self.0 {
            map.serialize_entry(k, a)?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for Amplitudes {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Keys;
        impl<'de> Visitor<'de> for Keys {
            type Value = Amplitudes;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("amplitude_<unit> keys")
            }
            fn visit_map<M: MapAccess<'de>>(self, mut map: M) -> Result<Amplitudes, M::Error> {
                let mut keyed = Vec::new();
                while let Some(k) = map.next_key::<String>()? {
                    if k.starts_with("amplitude") {
                        let a: Option<f64> = map.next_value()?;
                        keyed.push((k, a.unwrap_or(f64::NAN)));
                    } else {
                        map.next_value::<IgnoredAny>()?;
                    }
                }
                Ok(Amplitudes(keyed))
            }
        }
        deserializer.deserialize_map(Keys)
    }
}

/// The unit-named amplitude keys of an object.
fn amplitude_schema(description: &str) -> Schema {
    json_schema!({
        "type": "object",
        "patternProperties": {
            "^amplitude(_[A-Za-z0-9_]+)?$": {
                "type": ["number", "null"],
                "description": description,
            }
        }
    })
}

impl JsonSchema for Amplitudes {
    fn schema_name() -> Cow<'static, str> {
        "Amplitudes".into()
    }
    fn inline_schema() -> bool {
        true
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        amplitude_schema(
            "amplitude in the unit the key names: amplitude_<SI unit of the series> (e.g. \
             amplitude_m) and amplitude_<display unit> (e.g. amplitude_nm); plain `amplitude` \
             for a dimensionless series; `/` in a unit is `_` (amplitude_m_s is m/s)",
        )
    }
}

fn section_amplitude_schema(_: &mut SchemaGenerator) -> Schema {
    amplitude_schema("A = (max maxima − min minima)/2 in the unit the key names")
}

/// The instance's row of `processed/tables/analyses.*`, six significant digits.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct AnalysisRow {
    /// the upstream stage instance
    pub source: String,
    /// HDF5 dataset of the series
    pub dataset: String,
    /// window start, ms
    pub window_start_ms: f64,
    /// window end, ms
    pub window_end_ms: f64,
    #[serde(flatten)]
    pub peaks: PeakColumns,
    /// median trusted CWT ridge frequency, kHz
    #[serde(rename = "ridge_median_kHz")]
    pub ridge_median_khz: Option<f64>,
    /// class with its period in section points, e.g. `periodic (period 1)`, or `unclassified
    /// (reason)`
    pub class: String,
    /// number of Poincaré-section maxima
    pub poincare_maxima: usize,
}

/// The strongest lines as row columns: `peak<n>_kHz` and `peak<n>_<display unit>`, n = 1, 2, …
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PeakColumns {
    /// The unit of the amplitudes (the series' display unit).
    pub unit: String,
    /// (frequency in kHz, amplitude in `unit`), strongest first.
    pub peaks: Vec<(f64, f64)>,
}

impl Serialize for PeakColumns {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(2 * self.peaks.len()))?;
        for (i, (f, a)) in self.peaks.iter().enumerate() {
            map.serialize_entry(&format!("peak{}_kHz", i + 1), f)?;
            map.serialize_entry(&format!("peak{}_{}", i + 1, self.unit), a)?;
        }
        map.end()
    }
}

impl JsonSchema for PeakColumns {
    fn schema_name() -> Cow<'static, str> {
        "PeakColumns".into()
    }
    fn inline_schema() -> bool {
        true
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        json_schema!({
            "type": "object",
            "patternProperties": {
                "^peak[1-3]_kHz$": {
                    "type": "number",
                    "description": "n-th strongest spectral line, kHz"
                },
                "^peak[1-3]_(?!kHz$)[A-Za-z0-9_]+$": {
                    "type": "number",
                    "description": "its amplitude in the display unit the key names (nm for a displacement in m)"
                }
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn amplitudes_keep_their_key_order_and_read_back() {
        let peak = SpectralPeak {
            amplitude: Amplitudes::new("m/s", 2e-3),
            frequency_hz: 1e4,
            significant: Some(true),
            amplitude_to_level: Some(2.5),
        };
        let text = serde_json::to_string(&peak).unwrap();
        assert_eq!(
            text,
            r#"{"amplitude_m_s":0.002,"amplitude_mm_s":2.0,"frequency_Hz":10000.0,"significant":true,"amplitude_to_level":2.5}"#
        );
        assert_eq!(serde_json::from_str::<SpectralPeak>(&text).unwrap(), peak);
        // Dimensionless: one key; a value that is not finite is null and reads back as NaN.
        let one = Amplitudes::new("1", f64::NAN);
        let text = serde_json::to_string(&one).unwrap();
        assert_eq!(text, r#"{"amplitude":null}"#);
        assert!(serde_json::from_str::<Amplitudes>(&text)
            .unwrap()
            .get("amplitude")
            .is_nan());
    }

    #[test]
    fn the_row_interleaves_each_line_and_its_amplitude() {
        let row = AnalysisRow {
            source: "s".into(),
            dataset: "d".into(),
            window_start_ms: 0.5,
            window_end_ms: 2.0,
            peaks: PeakColumns {
                unit: "nm".into(),
                peaks: vec![(10.7, 0.75), (21.4, 0.01)],
            },
            ridge_median_khz: None,
            class: "periodic (period 1)".into(),
            poincare_maxima: 16,
        };
        assert_eq!(
            serde_json::to_string(&row).unwrap(),
            r#"{"source":"s","dataset":"d","window_start_ms":0.5,"window_end_ms":2.0,"peak1_kHz":10.7,"peak1_nm":0.75,"peak2_kHz":21.4,"peak2_nm":0.01,"ridge_median_kHz":null,"class":"periodic (period 1)","poincare_maxima":16}"#
        );
    }
}
