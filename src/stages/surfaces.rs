//! Surfaces stage: one height map → levelled/filtered field → σ, R, η, β (+ Nayak estimates,
//! summit list, histograms, scale sweep), as HDF5 + PNG + a summary row. The same function
//! serves the pipeline and `hdi surface FILE`.

use super::{FromConfig, Output, StageContext, StageKind};
use crate::artefacts::finite;
use crate::artefacts::surface::{
    AreaQuantities, AreasSummary, BootstrapSettings, NayakReport, Spread, SummitStats,
    SurfaceReport, SurfaceResult, TipReliabilityReport,
};
use crate::core::config::{ConfigError, PipelineFile};
use crate::core::store::H5Out;
use crate::error::Result;
use crate::numerics::bootstrap::{self, Summary};
use crate::surface::crop::{crop, CropRect};
use crate::surface::filter::apply_filters;
use crate::surface::io::{read_height_map, ReadOptions};
use crate::surface::level::{level, LevelOp};
use crate::surface::roughness::{
    roughness, scale_sweep_with, MomentsMethod, RadiusDefinition, RoughnessOptions,
    RoughnessReport, SummitScheme, SweepRow,
};
use crate::surface::spectra::{
    surface_analyses, tip_reliability_cutoff, SurfaceAnalyses, TipCutoff, TIP_SAFETY_FACTOR,
};
use crate::surface::{HeightMap, SurfaceError};
use crate::units::Length;
use serde::Deserialize;
use serde_json::{json, Map, Value};
use std::path::PathBuf;

mod output;
mod rows;
pub use output::write_outputs;
use output::{write_areas_plot, write_figures, write_h5_body, write_spectra, write_x3p};
pub use rows::{AreaColumns, AreaRow, SurfaceRow, SurfaceSummaryRow};

/// Bump when the numbers or files this stage produces change. surface-2: `surface.h5` holds
/// the PSD/ACF/slope/curvature curves and the stage draws their figures (issue 32).
pub const MODEL_VERSION: &str = "surface-2";

/// The default levelling recipe (docs/surfaces.md).
pub fn default_level() -> Vec<String> {
    crate::surface::level::DEFAULT_RECIPE
        .iter()
        .map(ToString::to_string)
        .collect()
}
fn default_summits() -> u8 {
    9
}
fn default_bins() -> usize {
    64
}
fn default_true() -> bool {
    true
}
fn default_radius() -> String {
    "inverse_mean_curvature".into()
}
fn default_moments() -> String {
    "finite_difference".into()
}

/// `[surface.NAME]` as written in `pipeline.toml`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SurfaceConfig {
    /// Height map file (any supported format, detected from content).
    #[serde(default)]
    pub file: PathBuf,
    /// Several scans of the same surface instead of `file` (App. C.1: several scans per
    /// surface, reported as mean ± spread).
    #[serde(default)]
    pub files: Option<Vec<PathBuf>>,
    /// Channel name (default: the format's height channel).
    #[serde(default)]
    pub channel: Option<String>,
    /// Lateral size for formats that do not carry it (plain ASCII without header).
    #[serde(default)]
    pub size_x: Option<Length>,
    #[serde(default)]
    pub size_y: Option<Length>,
    /// Height unit for formats that do not carry it.
    #[serde(default)]
    pub z_unit: Option<String>,
    /// Analyse only this rectangle of the scan (e.g. a 1 × 1 µm sub-area free of artefacts).
    #[serde(default)]
    pub crop: Option<CropConfig>,
    /// Several rectangles instead of `crop`; each is analysed in each file.
    #[serde(default)]
    pub crops: Option<Vec<CropConfig>>,
    /// Levelling recipe, applied in order.
    #[serde(default = "default_level")]
    pub level: Vec<String>,
    /// S-filter (Gaussian low-pass) cutoff wavelength: removes noise shorter than it.
    #[serde(default)]
    pub filter_s: Option<Length>,
    /// L-filter (Gaussian high-pass) cutoff wavelength: removes waviness longer than it.
    #[serde(default)]
    pub filter_l: Option<Length>,
    /// Summit definition: 9 (8 neighbours) or 5 (4 neighbours).
    #[serde(default = "default_summits")]
    pub summits: u8,
    /// Which mean summit radius is reported as R.
    #[serde(default = "default_radius")]
    pub radius: String,
    /// Birmingham-14 summit filtering (5 % of Sz, 1 % merge distance).
    #[serde(default)]
    pub birmingham: bool,
    /// Spectral moments estimator: "finite_difference" or "spectral" (periodic maps only).
    #[serde(default = "default_moments")]
    pub moments: String,
    /// Treat the map as periodic (synthetic surfaces).
    #[serde(default)]
    pub periodic: bool,
    #[serde(default = "default_bins")]
    pub histogram_bins: usize,
    /// Also compute the sub-sampling / S-filter scale sweep.
    #[serde(default = "default_true")]
    pub scale_sweep: bool,
    /// Also write the analysed map (levelled, and filtered when a filter is set) as ISO
    /// 25178-71 X3P: `surface.x3p`, or `area_K.x3p` per area.
    #[serde(default)]
    pub x3p: bool,
    /// Scanning-probe tip radius (e.g. "40 nm"): computes the tip reliability cutoff and σ, R,
    /// η, β above it (docs/surfaces.md, "Surface analyses"). Absent: no cutoff.
    #[serde(default)]
    pub tip_radius: Option<Length>,
}

/// `crop = { x0 = "0 um", y0 = "0 um", width = "1 um", height = "1 um" }`: x along a scan
/// line, y down from the top row, both from the first pixel.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CropConfig {
    pub x0: Length,
    pub y0: Length,
    pub width: Length,
    pub height: Length,
}

impl std::str::FromStr for CropConfig {
    type Err = String;
    /// `"x0,y0,width,height"`, each a length with a unit, e.g. `"0um,0um,1um,1um"`.
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let parts: Vec<&str> = s.split(',').collect();
        let [x0, y0, width, height] = parts.as_slice() else {
            return Err(format!(
                "`{s}`: expected x0,y0,width,height (e.g. 0um,0um,1um,1um)"
            ));
        };
        Ok(Self {
            x0: x0.parse()?,
            y0: y0.parse()?,
            width: width.parse()?,
            height: height.parse()?,
        })
    }
}

/// Validated parameters, SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceParams {
    pub file: PathBuf,
    pub read: ReadOptions,
    pub crop: Option<CropRect>,
    /// Every (file × crop) area analysed; the first is `file` with `crop`. One area = the
    /// single-scan behaviour, unchanged.
    pub areas: Vec<Area>,
    pub level: Vec<LevelOp>,
    pub filter_s: Option<f64>,
    pub filter_l: Option<f64>,
    pub roughness: RoughnessOptions,
    pub periodic: bool,
    pub scale_sweep: bool,
    /// Write the analysed map as X3P too.
    pub x3p: bool,
    /// Tip radius for the reliability cutoff, m.
    pub tip_radius: Option<f64>,
    /// Compute the PSD/ACF/slope/curvature curves (`surface/analyses`). Always in a pipeline;
    /// `hdi surface` without `--out` has nowhere to put them and skips their cost.
    pub analyses: bool,
}

/// One analysed area: a file and an optional rectangle of it.
#[derive(Debug, Clone, PartialEq)]
pub struct Area {
    pub file: PathBuf,
    pub crop: Option<CropRect>,
}

fn crop_rect(
    key: &str,
    c: CropConfig,
) -> std::result::Result<CropRect, crate::core::config::KeyError> {
    if c.x0.0 < 0.0 || c.y0.0 < 0.0 || c.width.0 <= 0.0 || c.height.0 <= 0.0 {
        return Err(crate::core::config::KeyError::new(
            key,
            "x0 and y0 must be ≥ 0, width and height > 0",
        ));
    }
    Ok(CropRect {
        x0: c.x0.0,
        y0: c.y0.0,
        width: c.width.0,
        height: c.height.0,
    })
}

/// [`check`] for several files (`files = [..]`, already resolved): every file × every crop.
pub fn check_files(
    cfg: &SurfaceConfig,
    files: Vec<PathBuf>,
) -> std::result::Result<SurfaceParams, crate::core::config::KeyError> {
    let Some(first) = files.first().cloned() else {
        return Err(crate::core::config::KeyError::new(
            "files",
            "the list is empty: give at least one height map",
        ));
    };
    let mut p = check(cfg, first)?;
    let crops: Vec<Option<CropRect>> = {
        let mut seen = Vec::new();
        for a in &p.areas {
            if !seen.contains(&a.crop) {
                seen.push(a.crop);
            }
        }
        seen
    };
    p.areas = files
        .iter()
        .flat_map(|f| {
            crops.iter().map(|c| Area {
                file: f.clone(),
                crop: *c,
            })
        })
        .collect();
    Ok(p)
}

/// Check a `[surface]` table (or `hdi surface`'s options) key by key.
pub fn check(
    cfg: &SurfaceConfig,
    file: PathBuf,
) -> std::result::Result<SurfaceParams, crate::core::config::KeyError> {
    let bad = |k: &str, m: String| Err(crate::core::config::KeyError::new(k, m));
    let level = cfg
        .level
        .iter()
        .map(|s| s.parse::<LevelOp>())
        .collect::<std::result::Result<Vec<_>, _>>();
    let level = match level {
        Ok(l) => l,
        Err(e) => return bad("level", e),
    };
    for (k, v) in [("filter_s", cfg.filter_s), ("filter_l", cfg.filter_l)] {
        if let Some(Length(x)) = v {
            if x <= 0.0 {
                return bad(
                    k,
                    format!("{x:e} m is out of range: a cutoff wavelength must be > 0"),
                );
            }
        }
    }
    if let (Some(s), Some(l)) = (cfg.filter_s, cfg.filter_l) {
        if s.0 >= l.0 {
            return bad(
                "filter_s",
                format!(
                    "S-filter cutoff {:e} m must be shorter than the L-filter cutoff {:e} m",
                    s.0, l.0
                ),
            );
        }
    }
    for (k, v) in [
        ("size_x", cfg.size_x),
        ("size_y", cfg.size_y),
        ("tip_radius", cfg.tip_radius),
    ] {
        if let Some(Length(x)) = v {
            if x <= 0.0 {
                return bad(k, format!("{x:e} m is out of range: must be > 0"));
            }
        }
    }
    let summits: SummitScheme = match cfg.summits.to_string().parse() {
        Ok(s) => s,
        Err(_) => {
            return bad(
                "summits",
                format!("{} is not a summit definition: use 9 or 5", cfg.summits),
            )
        }
    };
    let radius: RadiusDefinition = match cfg.radius.parse() {
        Ok(r) => r,
        Err(e) => return bad("radius", e),
    };
    let moments: MomentsMethod = match cfg.moments.parse() {
        Ok(m) => m,
        Err(e) => return bad("moments", e),
    };
    if moments == MomentsMethod::Spectral && !cfg.periodic {
        return bad(
            "moments",
            "spectral moments need a periodic map (set periodic = true)".into(),
        );
    }
    if !(4..=4096).contains(&cfg.histogram_bins) {
        return bad(
            "histogram_bins",
            format!("{} is out of range 4..=4096", cfg.histogram_bins),
        );
    }
    let crops: Vec<Option<CropRect>> = match (cfg.crop, &cfg.crops) {
        (Some(_), Some(_)) => {
            return bad(
                "crops",
                "give either `crop` (one rectangle) or `crops` (a list), not both".into(),
            )
        }
        (_, Some(list)) if list.is_empty() => {
            return bad(
                "crops",
                "the list is empty: give at least one rectangle".into(),
            )
        }
        (_, Some(list)) => list
            .iter()
            .map(|c| crop_rect("crops", *c).map(Some))
            .collect::<std::result::Result<_, _>>()?,
        (Some(c), None) => vec![Some(crop_rect("crop", c)?)],
        (None, None) => vec![None],
    };
    let crop = crops[0];
    let areas = crops
        .iter()
        .map(|c| Area {
            file: file.clone(),
            crop: *c,
        })
        .collect();
    Ok(SurfaceParams {
        file,
        crop,
        areas,
        read: ReadOptions {
            channel: cfg.channel.clone(),
            size_x: cfg.size_x.map(|l| l.0),
            size_y: cfg.size_y.map(|l| l.0),
            z_unit: cfg.z_unit.clone(),
        },
        level,
        filter_s: cfg.filter_s.map(|l| l.0),
        filter_l: cfg.filter_l.map(|l| l.0),
        roughness: RoughnessOptions {
            summits,
            radius,
            birmingham: cfg.birmingham,
            moments,
            histogram_bins: cfg.histogram_bins,
        },
        periodic: cfg.periodic,
        scale_sweep: cfg.scale_sweep,
        x3p: cfg.x3p,
        tip_radius: cfg.tip_radius.map(|l| l.0),
        analyses: true,
    })
}

impl SurfaceParams {
    /// Canonical parameters for the cache key (the file enters by content, not by path).
    pub fn canonical(&self) -> Value {
        let mut v = self.canonical_one();
        if self.areas.len() > 1 {
            // Files enter the key by content (`inputs`); here their order and the crops.
            let files = self.distinct_files();
            let areas: Vec<Value> = self
                .areas
                .iter()
                .map(|a| {
                    json!({
                        "file_index": files.iter().position(|f| *f == a.file),
                        "crop_m": a.crop.map(|c| [c.x0, c.y0, c.width, c.height]),
                    })
                })
                .collect();
            if let Value::Object(m) = &mut v {
                m.insert("areas".into(), Value::Array(areas));
            }
        }
        v
    }

    /// The files of the areas, each once, in order.
    pub fn distinct_files(&self) -> Vec<PathBuf> {
        let mut files: Vec<PathBuf> = Vec::new();
        for a in &self.areas {
            if !files.contains(&a.file) {
                files.push(a.file.clone());
            }
        }
        files
    }

    /// The parameters of area `k` alone.
    pub fn area(&self, k: usize) -> SurfaceParams {
        let a = &self.areas[k];
        SurfaceParams {
            file: a.file.clone(),
            crop: a.crop,
            areas: vec![a.clone()],
            ..self.clone()
        }
    }

    fn canonical_one(&self) -> Value {
        let mut v = json!({
            "channel": self.read.channel,
            "size_x_m": self.read.size_x,
            "size_y_m": self.read.size_y,
            "z_unit": self.read.z_unit,
            "crop_m": self.crop.map(|c| [c.x0, c.y0, c.width, c.height]),
            "level": self.level.iter().map(|l| l.to_string()).collect::<Vec<_>>(),
            "filter_s_m": self.filter_s,
            "filter_l_m": self.filter_l,
            "summits": self.roughness.summits.to_string(),
            "radius": self.roughness.radius.to_string(),
            "birmingham": self.roughness.birmingham,
            "moments": self.roughness.moments.to_string(),
            "periodic": self.periodic,
            "histogram_bins": self.roughness.histogram_bins,
            "scale_sweep": self.scale_sweep,
        });
        // Only when asked for: the instances written before the option keep their keys.
        if let (true, Value::Object(m)) = (self.x3p, &mut v) {
            m.insert("x3p".into(), Value::Bool(true));
        }
        // Only when given: without it the key is what it was before the option existed.
        if let (Some(r), Value::Object(m)) = (self.tip_radius, &mut v) {
            m.insert("tip_radius_m".into(), json!(r));
        }
        if let (false, Value::Object(m)) = (self.analyses, &mut v) {
            m.insert("analyses".into(), json!(false));
        }
        v
    }
}

/// Everything computed for one surface.
pub struct SurfaceAnalysis {
    pub raw: HeightMap,
    pub levelled: HeightMap,
    /// After the S/L filters, when any was set.
    pub filtered: Option<HeightMap>,
    pub report: RoughnessReport,
    pub sweep: Vec<SweepRow>,
    /// PSD, ACF, scale-dependent slope and curvature of the analysed map, or why not (a map
    /// with invalid pixels).
    pub spectra: std::result::Result<SurfaceAnalyses, String>,
    /// The tip reliability cutoff, when a tip radius is given.
    pub tip: Option<TipReliability>,
}

/// The tip-radius reliability cutoff of the analysed map and the roughness above it.
pub struct TipReliability {
    pub tip_radius: f64,
    /// `Err`: not computed (why).
    pub cutoff: std::result::Result<TipCutoff, String>,
    /// σ, R, η, β of the analysed map S-filtered at λs = the cutoff (`cutoff` = `At`), of the
    /// map itself (`None`: no artefacts); absent when no data are reliable or not computed.
    pub above: Option<RoughnessReport>,
}

/// The cutoff for `tip_radius` and the roughness above it (docs/surfaces.md).
fn tip_reliability(
    map: &HeightMap,
    tip_radius: f64,
    raw: &RoughnessReport,
    opts: &RoughnessOptions,
) -> Result<TipReliability> {
    let cutoff = match tip_reliability_cutoff(map, tip_radius) {
        Ok(c) => Ok(c),
        Err(SurfaceError::InvalidData(why)) => Err(why),
        Err(e) => return Err(e.into()),
    };
    let above = match &cutoff {
        Ok(TipCutoff::At(lambda)) => {
            let mut filtered = map.clone();
            apply_filters(&mut filtered, Some(*lambda), None)?;
            Some(roughness(&filtered, opts)?)
        }
        Ok(TipCutoff::NoArtefacts) => Some(raw.clone()),
        Ok(TipCutoff::NoReliableData(_)) | Err(_) => None,
    };
    Ok(TipReliability {
        tip_radius,
        cutoff,
        above,
    })
}

impl SurfaceAnalysis {
    pub fn final_map(&self) -> &HeightMap {
        self.filtered.as_ref().unwrap_or(&self.levelled)
    }
}

/// Read, level, filter, and measure one height map.
pub fn analyse(params: &SurfaceParams) -> Result<SurfaceAnalysis> {
    let mut raw = read_height_map(&params.file, &params.read)?;
    if params.periodic {
        raw.periodic = true;
    }
    // `raw` stays the whole scan (so the output shows where the crop lies).
    let mut levelled = match &params.crop {
        Some(rect) => crop(&raw, rect)?,
        None => raw.clone(),
    };
    level(&mut levelled, &params.level)?;
    let filtered = if params.filter_s.is_some() || params.filter_l.is_some() {
        let mut f = levelled.clone();
        apply_filters(&mut f, params.filter_s, params.filter_l)?;
        Some(f)
    } else {
        None
    };
    let target = filtered.as_ref().unwrap_or(&levelled);
    let report = roughness(target, &params.roughness)?;
    let sweep = if params.scale_sweep {
        scale_sweep_with(target, &params.roughness, Some(&report))?
    } else {
        Vec::new()
    };
    let spectra = if !params.analyses {
        Err("not requested (`hdi surface` without --out)".to_string())
    } else {
        match surface_analyses(target) {
            Ok(s) => Ok(s),
            Err(SurfaceError::InvalidData(why)) => Err(why),
            Err(e) => return Err(e.into()),
        }
    };
    let tip = match params.tip_radius {
        Some(radius) => Some(tip_reliability(target, radius, &report, &params.roughness)?),
        None => None,
    };
    Ok(SurfaceAnalysis {
        raw,
        levelled,
        filtered,
        report,
        sweep,
        spectra,
        tip,
    })
}

/// The S/L filters in words (`none`, `S 0.02 um, L 5 um`), for the text report.
pub fn filter_text(p: &SurfaceParams) -> String {
    match (p.filter_s, p.filter_l) {
        (None, None) => "none".into(),
        (s, l) => {
            let mut parts = Vec::new();
            if let Some(s) = s {
                parts.push(format!("S {} um", s * 1e6));
            }
            if let Some(l) = l {
                parts.push(format!("L {} um", l * 1e6));
            }
            parts.join(", ")
        }
    }
}

/// The `--json` object of `hdi surface` (docs/surfaces.md, docs/schemas/surface.json), SI units
/// named in the keys; a statistic the map does not define (no summits, a flat map) is `null`.
pub fn report(a: &SurfaceAnalysis, p: &SurfaceParams) -> SurfaceReport {
    let r = &a.report;
    let m = a.final_map();
    SurfaceReport {
        file: p.file.to_string_lossy().into_owned(),
        format: a.raw.source.format.clone(),
        channel: a.raw.channel.clone(),
        nx: m.nx(),
        ny: m.ny(),
        dx_m: m.dx,
        dy_m: m.dy,
        sigma_m: r.sigma,
        sa_m: r.sa,
        ssk: finite(r.ssk),
        sku: finite(r.sku),
        m2: finite(r.m2),
        m4_per_m2: finite(r.m4),
        alpha: finite(r.alpha),
        moments_method: r.moments_method.to_string(),
        eta_per_m2: finite(r.eta),
        r_m: finite(r.r),
        r_definition: r.r_definition.to_string(),
        r_mean_of_inverse_m: finite(r.r_mean_of_inverse),
        r_median_of_inverse_m: finite(r.r_median_of_inverse),
        beta: finite(r.beta),
        sigma_s_m: finite(r.sigma_s),
        mean_summit_height_m: finite(r.mean_summit_height),
        n_summits: r.n_summits,
        summit_scheme: r.summit_scheme.to_string(),
        sampling_interval_m: r.sampling_interval,
        nayak: NayakReport {
            eta_per_m2: finite(r.nayak.eta),
            r_m: finite(r.nayak.r),
            beta: finite(r.nayak.beta),
            sigma_s_m: finite(r.nayak.sigma_s),
        },
        levelling: p.level.iter().map(|l| l.to_string()).collect(),
        crop_m: p.crop.map(|c| [c.x0, c.y0, c.width, c.height]),
        // The S/L-filter cutoffs as numbers (null: that filter is off), not a text with units.
        filter_s_m: p.filter_s,
        filter_l_m: p.filter_l,
        masked_fraction: m.masked_fraction(),
        warnings: r.warnings.clone(),
        tip_reliability: a.tip.as_ref().map(tip_report),
    }
}

/// `tip_reliability` of the `--json` report.
fn tip_report(t: &TipReliability) -> TipReliabilityReport {
    let (status, cutoff_m) = match &t.cutoff {
        Ok(TipCutoff::At(l)) => ("cutoff", Some(*l)),
        Ok(TipCutoff::NoArtefacts) => ("no_artefacts", None),
        Ok(TipCutoff::NoReliableData(l)) => ("no_reliable_data", Some(*l)),
        Err(_) => ("not_computed", None),
    };
    let above = t.above.as_ref();
    TipReliabilityReport {
        tip_radius_m: t.tip_radius,
        safety_factor: TIP_SAFETY_FACTOR,
        status: status.into(),
        cutoff_m,
        sigma_m: above.and_then(|r| finite(r.sigma)),
        eta_per_m2: above.and_then(|r| finite(r.eta)),
        r_m: above.and_then(|r| finite(r.r)),
        beta: above.and_then(|r| finite(r.beta)),
        n_summits: above.map(|r| r.n_summits),
    }
}

/// A `[surface.NAME]` instance.
pub struct SurfaceStage {
    pub name: String,
    pub params: SurfaceParams,
}

impl FromConfig for SurfaceStage {
    type Config = SurfaceConfig;

    fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &SurfaceConfig,
    ) -> std::result::Result<Self, ConfigError> {
        let params = match &cfg.files {
            Some(_) if !cfg.file.as_os_str().is_empty() => {
                return Err(crate::core::config::KeyError::new(
                    "files",
                    "give either `file` (one scan) or `files` (several), not both",
                )
                .locate(file, "surface", name))
            }
            Some(list) => {
                let paths = list
                    .iter()
                    .map(|f| file.input_file("surface", name, "files", f, "height map"))
                    .collect::<std::result::Result<Vec<_>, _>>()?;
                check_files(cfg, paths).map_err(|e| e.locate(file, "surface", name))?
            }
            None => {
                let path = file.input_file("surface", name, "file", &cfg.file, "height map")?;
                check(cfg, path).map_err(|e| e.locate(file, "surface", name))?
            }
        };
        Ok(Self {
            name: name.to_string(),
            params,
        })
    }
}

impl StageKind for SurfaceStage {
    const KIND: &'static str = "surface";
    const MODEL_VERSION: &'static str = MODEL_VERSION;
    type Result = SurfaceResult;
    type Row = SurfaceSummaryRow;

    fn params(&self) -> Value {
        self.params.canonical()
    }
    fn inputs(&self) -> Vec<(String, PathBuf)> {
        self.params
            .distinct_files()
            .into_iter()
            .enumerate()
            .map(|(k, f)| {
                let key = if k == 0 {
                    "file".to_string()
                } else {
                    format!("file_{k}")
                };
                (key, f)
            })
            .collect()
    }
    fn run(&self, ctx: &StageContext) -> Result<Output<SurfaceResult, SurfaceSummaryRow>> {
        if self.params.areas.len() > 1 {
            return run_areas(&self.params, ctx);
        }
        ctx.progress.set_message("reading and levelling");
        let a = analyse(&self.params)?;
        ctx.progress.set_message("writing HDF5 and plots");
        let inputs = serde_json::to_value(&ctx.fingerprint.inputs).unwrap_or(Value::Null);
        write_outputs(
            &a,
            &self.params,
            &ctx.out_dir.join("surface.h5"),
            Some(ctx.out_dir),
            ctx.key,
            &inputs,
        )?;
        if self.params.x3p {
            write_x3p(&a, &self.params, &ctx.out_dir.join("surface.x3p"))?;
        }
        let r = &a.report;
        // What the interface stage combines.
        let stats = SummitStats {
            sigma: finite(r.sigma),
            r: finite(r.r),
            eta: finite(r.eta),
            m2: finite(r.m2),
            m4: finite(r.m4),
        };
        Ok(Output {
            result: SurfaceResult {
                report: report(&a, &self.params),
                stats,
                areas: None,
            },
            summary_row: Some(SurfaceSummaryRow {
                row: SurfaceRow::new(&a, &self.params),
                areas: None,
            }),
        })
    }
}

/// The per-area quantities summarised over areas: name, unit, SI → table-unit factor, and
/// the value of one report.
type Quantity = (&'static str, &'static str, f64, fn(&RoughnessReport) -> f64);
const AREA_QUANTITIES: [Quantity; 6] = [
    ("sigma", "m", 1e9, |r| r.sigma),
    ("R", "m", 1e6, |r| r.r),
    ("eta", "1/m^2", 1e-12, |r| r.eta),
    ("beta", "1", 1.0, |r| r.beta),
    ("m2", "1", 1.0, |r| r.m2),
    ("m4", "1/m^2", 1.0, |r| r.m4),
];

/// Mean, sample std and 95 % percentile-bootstrap interval of each quantity over the areas
/// (`numerics::bootstrap`, 2000 resamples, fixed seed; docs/surfaces.md).
pub fn area_summaries(reports: &[&RoughnessReport]) -> Vec<(&'static str, &'static str, Summary)> {
    AREA_QUANTITIES
        .iter()
        .map(|(name, unit, _, get)| {
            let x: Vec<f64> = reports.iter().map(|r| get(r)).collect();
            (*name, *unit, bootstrap::summarise(&x))
        })
        .collect()
}

/// One quantity's spread as the result writes it (non-finite values as `null`).
fn spread(s: &Summary) -> Spread {
    Spread {
        mean: finite(s.mean),
        std: finite(s.std),
        ci95: [finite(s.ci_low), finite(s.ci_high)],
        n: s.n,
    }
}

/// Several (file × crop) areas: each analysed as a single scan; `surface.h5` holds the first
/// area's maps as today plus `/surface/areas` (per-area values, mean, std, bootstrap CI);
/// `areas.{csv,parquet}` one row per area; `areas.png`; the interface gets the means.
fn run_areas(
    p: &SurfaceParams,
    ctx: &StageContext,
) -> Result<Output<SurfaceResult, SurfaceSummaryRow>> {
    let n = p.areas.len();
    let mut analyses = Vec::with_capacity(n);
    for k in 0..n {
        ctx.progress
            .set_message(format!("reading and levelling area {}/{n}", k + 1));
        analyses.push(analyse(&p.area(k))?);
    }
    let reports: Vec<&RoughnessReport> = analyses.iter().map(|a| &a.report).collect();
    let summaries = area_summaries(&reports);
    ctx.progress.set_message("writing HDF5, tables and plots");
    let first = p.area(0);
    let inputs = serde_json::to_value(&ctx.fingerprint.inputs).unwrap_or(Value::Null);
    let out = H5Out::create(&ctx.out_dir.join("surface.h5"))?;
    out.root_attributes("surface", ctx.key, &p.canonical(), &inputs, "surface")?;
    write_h5_body(&out, &analyses[0])?;
    let g = out.group("surface/areas", None)?;
    for (k, (name, unit, _, get)) in AREA_QUANTITIES.iter().enumerate() {
        let v: Vec<f64> = reports.iter().map(|r| get(r)).collect();
        out.write_1d(&g, name, &v, unit, &format!("{name} of each area"))?;
        let s = &summaries[k].2;
        for (suffix, val, what) in [
            ("mean", s.mean, "mean over areas"),
            ("std", s.std, "sample standard deviation over areas"),
            (
                "ci95_low",
                s.ci_low,
                "95 % percentile-bootstrap interval of the mean, low",
            ),
            (
                "ci95_high",
                s.ci_high,
                "95 % percentile-bootstrap interval of the mean, high",
            ),
        ] {
            out.write_scalar(&g, &format!("{name}_{suffix}"), val, unit, what)?;
        }
    }
    out.write_count(&g, "n_areas", n as u64, "areas analysed")?;
    // Each area's curves and tip cutoff (area 0's are also those under /surface).
    for (k, a) in analyses.iter().enumerate() {
        write_spectra(&out, &format!("surface/areas/area_{k}"), a)?;
    }
    out.write_count(
        &g,
        "bootstrap_resamples",
        bootstrap::RESAMPLES as u64,
        "percentile-bootstrap resamples",
    )?;
    out.finish()?;
    write_figures(&analyses[0], ctx.out_dir)?;
    if p.x3p {
        for (k, a) in analyses.iter().enumerate() {
            write_x3p(a, &p.area(k), &ctx.out_dir.join(format!("area_{k}.x3p")))?;
        }
    }

    let rows: Vec<AreaRow> = analyses
        .iter()
        .enumerate()
        .map(|(k, a)| AreaRow {
            area: k as i64,
            row: SurfaceRow::new(a, &p.area(k)),
        })
        .collect();
    crate::core::store::write_table(&table_rows(&rows)?, &ctx.out_dir.join("areas"))?;
    write_areas_plot(&ctx.out_dir.join("areas.png"), &reports, &summaries)?;

    // AREA_QUANTITIES order: sigma, R, eta, beta, m2, m4.
    let s: Vec<Summary> = summaries.iter().map(|s| s.2).collect();
    let scaled = |k: usize| (s[k], AREA_QUANTITIES[k].2);
    let row = SurfaceSummaryRow {
        row: SurfaceRow::new(&analyses[0], &first),
        areas: Some(AreaColumns::new(
            n,
            [scaled(0), scaled(1), scaled(2), scaled(3)],
        )),
    };
    // The interface combines the means over areas; the spread travels beside them.
    let stats = SummitStats {
        sigma: finite(s[0].mean),
        r: finite(s[1].mean),
        eta: finite(s[2].mean),
        m2: finite(s[4].mean),
        m4: finite(s[5].mean),
    };
    let areas = AreasSummary {
        n,
        summary: AreaQuantities {
            sigma: spread(&s[0]),
            r: spread(&s[1]),
            eta: spread(&s[2]),
            beta: spread(&s[3]),
            m2: spread(&s[4]),
            m4: spread(&s[5]),
        },
        bootstrap: BootstrapSettings {
            resamples: bootstrap::RESAMPLES,
            level: 0.95,
            seed: bootstrap::SEED,
        },
        table: "areas.csv".into(),
    };
    Ok(Output {
        result: SurfaceResult {
            report: report(&analyses[0], &first),
            stats,
            areas: Some(areas),
        },
        summary_row: Some(row),
    })
}

/// Typed rows as the table writer takes them (one JSON object each).
fn table_rows<T: serde::Serialize>(rows: &[T]) -> Result<Vec<Map<String, Value>>> {
    rows.iter()
        .map(|r| match serde_json::to_value(r) {
            Ok(Value::Object(m)) => Ok(m),
            Ok(other) => Err(crate::error::Error::Encode {
                kind: "surface",
                what: "area row".into(),
                message: format!("not a JSON object: {other}"),
            }),
            Err(e) => Err(crate::error::Error::Encode {
                kind: "surface",
                what: "area row".into(),
                message: e.to_string(),
            }),
        })
        .collect()
}

#[cfg(test)]
mod tests;
