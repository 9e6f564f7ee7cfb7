//! Bulge stage: profilometer scans of the TFC bulge at several heater powers → fitted bulge
//! geometry (a, w, x_TFC) and efficiency (m/W) for the slider stages (App. C.2; docs/bulge.md).
//! The same analysis backs `hdi bulge FILE…`.

use super::{FromConfig, Output, StageContext, StageKind};
use crate::artefacts::bulge::{BulgeReport, BulgeScan, FittedBulge};
use crate::artefacts::finite;
use crate::core::config::{ConfigError, PipelineFile};
use crate::core::store::{write_table, H5Out};
use crate::error::Result;
use crate::surface::bulge::{
    fit_bulge, fit_bulge_lines, fit_efficiency, power_from_name, BulgeFit, BulgeOptions,
    EfficiencyFit, OffsetLine, Rect,
};
use crate::surface::io::profile::read_line_profile;
use crate::surface::io::{read_height_map, ReadOptions};
use crate::surface::SurfaceError;
use crate::units::{Length, Power};
use serde::{Deserialize, Serialize};
use serde_json::{json, Map, Value};
use std::path::{Path, PathBuf};

pub const MODEL_VERSION: &str = "bulge-1";

fn default_true() -> bool {
    true
}

/// `[bulge.NAME]` as written.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BulgeConfig {
    /// Profilometer scans (any height-map format hdi reads).
    #[serde(default)]
    pub files: Vec<PathBuf>,
    /// Line scans (any line-profile format hdi reads), each at a stated offset from the bulge
    /// centre; the lines of one heater power are fitted together (docs/bulge.md "Line scans").
    #[serde(default)]
    pub lines: Vec<LineConfig>,
    /// Heater power of each scan (e.g. "30 mW"); default: from the file names (`…30mW…`).
    #[serde(default)]
    pub powers: Option<Vec<Power>>,
    /// Rectangles left out of levelling and fitting (x along a scan line, y down the rows).
    #[serde(default)]
    pub exclude: Vec<RectConfig>,
    /// Detect and mask the trailing-edge drop and its pull-up.
    #[serde(default = "default_true")]
    pub auto_te: bool,
    /// Mask start before the detected edge (default 2 µm).
    #[serde(default)]
    pub te_margin: Option<Length>,
    /// Channel for multi-channel formats.
    #[serde(default)]
    pub channel: Option<String>,
}

/// One line scan, `{ file = "tfc_30mW_y+10um.csv", offset = "10 um", power = "30 mW" }`
/// or on the command line `FILE@OFFSET[@POWER]`: `offset` (default 0) is the line's distance
/// from the bulge centre across the slider, `power` (default: from the file name) its heater
/// power.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LineConfig {
    pub file: PathBuf,
    #[serde(default)]
    pub offset: Option<Length>,
    #[serde(default)]
    pub power: Option<Power>,
}

impl std::str::FromStr for LineConfig {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let mut parts = s.split('@');
        let file = parts.next().unwrap_or_default();
        if file.is_empty() {
            return Err(format!(
                "`{s}`: expected FILE[@OFFSET[@POWER]] (e.g. scan.csv@10um)"
            ));
        }
        let offset = parts.next().map(str::parse::<Length>).transpose()?;
        let power = parts.next().map(str::parse::<Power>).transpose()?;
        if parts.next().is_some() {
            return Err(format!("`{s}`: expected FILE[@OFFSET[@POWER]]"));
        }
        Ok(Self {
            file: PathBuf::from(file),
            offset,
            power,
        })
    }
}

/// A line scan, validated: file, offset (m), heater power (W, `None`: unknown).
#[derive(Debug, Clone, PartialEq)]
pub struct LineSpec {
    pub file: PathBuf,
    pub offset: f64,
    pub power: Option<f64>,
}

/// Checks a line's offset and power (given, else from the file name).
pub fn line_spec(file: PathBuf, c: &LineConfig) -> std::result::Result<LineSpec, String> {
    let offset = c.offset.map(|l| l.0).unwrap_or(0.0);
    if !offset.is_finite() {
        return Err(format!(
            "{}: offset {offset} m is not finite",
            file.display()
        ));
    }
    let power = match c.power {
        Some(p) if !(p.0.is_finite() && p.0 >= 0.0) => {
            return Err(format!("{}: power {} W must be ≥ 0", file.display(), p.0))
        }
        Some(p) => Some(p.0),
        None => file
            .file_name()
            .and_then(|n| n.to_str())
            .and_then(power_from_name),
    };
    Ok(LineSpec {
        file,
        offset,
        power,
    })
}

/// An excluded rectangle, `{ x0 = "0 um", y0 = "0 um", width = "10 um", height = "5 um" }`
/// or on the command line `"0um,0um,10um,5um"`: x along a scan line, y down the rows, from
/// the first pixel (the same convention as the surfaces stage's `crop`).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RectConfig {
    pub x0: Length,
    pub y0: Length,
    pub width: Length,
    pub height: Length,
}

impl std::str::FromStr for RectConfig {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let parts: Vec<&str> = s.split(',').collect();
        let [x0, y0, width, height] = parts.as_slice() else {
            return Err(format!(
                "`{s}`: expected x0,y0,width,height (e.g. 0um,0um,10um,5um)"
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
#[derive(Debug, Clone)]
pub struct BulgeParams {
    pub files: Vec<PathBuf>,
    /// Heater power per file, W (`None`: unknown).
    pub powers: Vec<Option<f64>>,
    /// Line scans; those of one power (or all of unknown power) make one scan.
    pub lines: Vec<LineSpec>,
    pub options: BulgeOptions,
    pub channel: Option<String>,
}

/// The heater power of each file: as given (one per file), else from the file names.
pub fn resolve_powers(
    files: &[PathBuf],
    given: Option<&[f64]>,
) -> std::result::Result<Vec<Option<f64>>, String> {
    match given {
        Some(p) if p.len() != files.len() => Err(format!(
            "{} powers for {} files (give one per file, or none to read them from the file names)",
            p.len(),
            files.len()
        )),
        Some(p) => {
            if let Some(bad) = p.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
                return Err(format!("power {bad} W must be ≥ 0"));
            }
            Ok(p.iter().map(|v| Some(*v)).collect())
        }
        None => Ok(files
            .iter()
            .map(|f| {
                f.file_name()
                    .and_then(|n| n.to_str())
                    .and_then(power_from_name)
            })
            .collect()),
    }
}

/// Exclusion rectangles from their config form.
pub fn rects(exclude: &[RectConfig]) -> Vec<Rect> {
    exclude
        .iter()
        .map(|c| Rect {
            x0: c.x0.0,
            y0: c.y0.0,
            width: c.width.0,
            height: c.height.0,
        })
        .collect()
}

/// One fitted scan: a map, or the line scans of one heater power.
pub struct ScanResult {
    pub file: PathBuf,
    /// The line scans fitted together (empty for a map).
    pub line_files: Vec<PathBuf>,
    pub power: Option<f64>,
    pub fit: BulgeFit,
}

pub struct BulgeAnalysis {
    pub scans: Vec<ScanResult>,
    pub efficiency: Option<EfficiencyFit>,
    pub tfc: FittedBulge,
}

/// Inverse-variance weighted mean (plain mean if a standard error is zero or not finite).
fn weighted_mean(values: &[(f64, f64)]) -> f64 {
    let ok = values.iter().all(|(_, se)| se.is_finite() && *se > 0.0);
    if ok {
        let (s, w) = values.iter().fold((0.0, 0.0), |(s, w), (v, se)| {
            (s + v / (se * se), w + 1.0 / (se * se))
        });
        s / w
    } else {
        values.iter().map(|(v, _)| v).sum::<f64>() / values.len() as f64
    }
}

/// Fit every scan, then the efficiency line over the scans with a power. The geometry handed
/// on (a, w, x_TFC) is the inverse-variance weighted mean over the scans: the shape is
/// expected not to change with power (docs/bulge.md), and the weights favour the tall,
/// well-determined bulges of the higher powers.
pub fn analyse(params: &BulgeParams) -> Result<BulgeAnalysis> {
    let opts = ReadOptions {
        channel: params.channel.clone(),
        ..Default::default()
    };
    let mut scans = Vec::new();
    for (file, power) in params.files.iter().zip(&params.powers) {
        let map = read_height_map(file, &opts)?;
        let fit = fit_bulge(&map, &params.options).map_err(|e| SurfaceError::Format {
            path: file.clone(),
            reason: e.to_string(),
        })?;
        scans.push(ScanResult {
            file: file.clone(),
            line_files: Vec::new(),
            power: *power,
            fit,
        });
    }
    for group in line_groups(&params.lines) {
        let mut lines = Vec::with_capacity(group.len());
        for l in &group {
            lines.push(OffsetLine {
                profile: read_line_profile(&l.file)?,
                offset: l.offset,
            });
        }
        let names: Vec<String> = group.iter().map(|l| l.file.display().to_string()).collect();
        let fit = fit_bulge_lines(&lines, &params.options).map_err(|e| SurfaceError::Format {
            path: PathBuf::from(names.join(" + ")),
            reason: e.to_string(),
        })?;
        scans.push(ScanResult {
            file: group[0].file.clone(),
            line_files: group.iter().map(|l| l.file.clone()).collect(),
            power: group[0].power,
            fit,
        });
    }
    let with_power: Vec<(f64, f64)> = scans
        .iter()
        .filter_map(|s| s.power.map(|p| (p, s.fit.height)))
        .collect();
    let distinct = with_power
        .iter()
        .any(|(p, _)| (p - with_power[0].0).abs() > 0.0);
    let efficiency = if with_power.len() >= 2 && distinct {
        let (p, h): (Vec<f64>, Vec<f64>) = with_power.into_iter().unzip();
        Some(fit_efficiency(&p, &h)?)
    } else {
        None
    };
    let pick = |f: &dyn Fn(&BulgeFit) -> (f64, f64)| {
        weighted_mean(&scans.iter().map(|s| f(&s.fit)).collect::<Vec<_>>())
    };
    // Centre lines alone do not give w: the mean is over the scans that do.
    let widths: Vec<(f64, f64)> = scans
        .iter()
        .filter(|s| s.fit.w.is_finite())
        .map(|s| (s.fit.w, s.fit.w_se))
        .collect();
    if widths.is_empty() {
        return Err(SurfaceError::InvalidData(
            "no scan gives the bulge width w (line scans through the centre alone do not): \
             add a line at an offset from the centre"
                .into(),
        )
        .into());
    }
    let x_tfc = scans
        .iter()
        .all(|s| s.fit.x_tfc.is_some())
        .then(|| pick(&|f| (f.x_tfc.unwrap_or(f64::NAN), f.xc_se)));
    let tfc = FittedBulge {
        a_tfc_m: pick(&|f| (f.a, f.a_se)),
        w_tfc_m: weighted_mean(&widths),
        x_tfc_m: x_tfc,
        efficiency_m_per_w: efficiency.map(|e| e.efficiency),
        intercept_m: efficiency.map(|e| e.intercept),
    };
    Ok(BulgeAnalysis {
        scans,
        efficiency,
        tfc,
    })
}

/// The line scans grouped into scans: one per heater power (lines of unknown power together),
/// in order of first appearance.
fn line_groups(lines: &[LineSpec]) -> Vec<Vec<LineSpec>> {
    let mut groups: Vec<Vec<LineSpec>> = Vec::new();
    for l in lines {
        let key = l.power.map(f64::to_bits);
        match groups
            .iter_mut()
            .find(|g| g[0].power.map(f64::to_bits) == key)
        {
            Some(g) => g.push(l.clone()),
            None => groups.push(vec![l.clone()]),
        }
    }
    groups
}

/// The name a scan is reported under: the file name, or the line scans' names joined by ` + `.
fn scan_label(s: &ScanResult) -> String {
    let name = |p: &Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    if s.line_files.is_empty() {
        name(&s.file)
    } else {
        s.line_files
            .iter()
            .map(|p| name(p))
            .collect::<Vec<_>>()
            .join(" + ")
    }
}

/// One scan as the `hdi bulge --json` and `scans.csv` keys have it (SI units named in the
/// keys). x_TFC's standard error is that of the centre: the edge position is taken as exact
/// (it is known to ±dx/2).
pub fn scan(s: &ScanResult) -> BulgeScan {
    let f = &s.fit;
    let lines = !s.line_files.is_empty();
    BulgeScan {
        file: scan_label(s),
        heater_power_mw: s.power.map(|p| p * 1e3),
        height_m: finite(f.height),
        height_se_m: finite(f.height_se),
        a_tfc_m: finite(f.a),
        a_tfc_se_m: finite(f.a_se),
        w_tfc_m: finite(f.w),
        w_tfc_se_m: finite(f.w_se),
        x_tfc_m: f.x_tfc.and_then(finite),
        x_tfc_se_m: f.x_tfc.and_then(|_| finite(f.xc_se)),
        x_c_m: finite(f.xc),
        // Line offsets are from the centre: y_c is not fitted.
        y_c_m: if lines { None } else { finite(f.yc) },
        y_c_se_m: finite(f.yc_se),
        trailing_edge_x_m: f.trailing_edge.and_then(|t| finite(t.x)),
        residual_rms_m: finite(f.residual_rms),
        n_pixels: f.n_pixels,
    }
}

/// The full report: scans, efficiency fit and the geometry handed on.
pub fn report(a: &BulgeAnalysis) -> BulgeReport {
    let e = a.efficiency;
    BulgeReport {
        scans: a.scans.iter().map(scan).collect(),
        efficiency_m_per_w: e.and_then(|e| finite(e.efficiency)),
        efficiency_se_m_per_w: e.and_then(|e| finite(e.efficiency_se)),
        intercept_m: e.and_then(|e| finite(e.intercept)),
        intercept_se_m: e.and_then(|e| finite(e.intercept_se)),
        tfc: a.tfc,
    }
}

/// One row of the bulge summary table (table units, 6 significant digits).
#[derive(Debug, Clone, Serialize)]
pub struct BulgeRow {
    pub scans: usize,
    pub a_tfc_um: f64,
    pub w_tfc_um: f64,
    pub x_tfc_um: Option<f64>,
    #[serde(rename = "efficiency_nm_per_mW")]
    pub efficiency_nm_per_mw: Option<f64>,
    pub intercept_nm: Option<f64>,
}

fn encode(message: String) -> crate::error::Error {
    crate::error::Error::Encode {
        kind: "bulge",
        what: "scan row".into(),
        message,
    }
}

/// `bulge.h5` (per-scan values with units as attributes, the levelled maps) and the tidy
/// `scans.csv`/`scans.parquet` in `dir`.
pub fn write_outputs(a: &BulgeAnalysis, params: &Value, key: &str, dir: &Path) -> Result<()> {
    let out = H5Out::create(&dir.join("bulge.h5"))?;
    let files: Vec<String> = a
        .scans
        .iter()
        .map(|s| {
            if s.line_files.is_empty() {
                s.file.to_string_lossy().into_owned()
            } else {
                let f: Vec<String> = s
                    .line_files
                    .iter()
                    .map(|p| p.to_string_lossy().into_owned())
                    .collect();
                f.join(" + ")
            }
        })
        .collect();
    out.root_attributes("bulge", key, params, &Value::from(files.clone()), "bulge")?;
    let g = out.group("bulge", Some("NXentry"))?;
    let col = |f: &dyn Fn(&ScanResult) -> f64| a.scans.iter().map(f).collect::<Vec<f64>>();
    let nan = f64::NAN;
    out.write_1d(
        &g,
        "heater_power",
        &col(&|s| s.power.unwrap_or(nan)),
        "W",
        "heater power (NaN: unknown)",
    )?;
    out.write_1d(&g, "height", &col(&|s| s.fit.height), "m", "bulge height")?;
    out.write_1d(
        &g,
        "height_se",
        &col(&|s| s.fit.height_se),
        "m",
        "standard error of the height",
    )?;
    out.write_1d(
        &g,
        "a_tfc",
        &col(&|s| s.fit.a),
        "m",
        "half-length along the slider",
    )?;
    out.write_1d(
        &g,
        "a_tfc_se",
        &col(&|s| s.fit.a_se),
        "m",
        "standard error of a",
    )?;
    out.write_1d(
        &g,
        "w_tfc",
        &col(&|s| s.fit.w),
        "m",
        "full width across the slider",
    )?;
    out.write_1d(
        &g,
        "w_tfc_se",
        &col(&|s| s.fit.w_se),
        "m",
        "standard error of w",
    )?;
    out.write_1d(
        &g,
        "x_tfc",
        &col(&|s| s.fit.x_tfc.unwrap_or(nan)),
        "m",
        "centre distance from the trailing edge",
    )?;
    out.write_1d(
        &g,
        "x_tfc_se",
        &col(&|s| s.fit.xc_se),
        "m",
        "standard error of x_TFC",
    )?;
    out.write_1d(
        &g,
        "residual_rms",
        &col(&|s| s.fit.residual_rms),
        "m",
        "RMS of the fit residuals",
    )?;
    if let Some(e) = a.efficiency {
        out.write_scalar(
            &g,
            "efficiency",
            e.efficiency,
            "m/W",
            "bulge height per heater power",
        )?;
        out.write_scalar(
            &g,
            "efficiency_se",
            e.efficiency_se,
            "m/W",
            "standard error",
        )?;
        out.write_scalar(
            &g,
            "intercept",
            e.intercept,
            "m",
            "bulge height at zero power",
        )?;
        out.write_scalar(&g, "intercept_se", e.intercept_se, "m", "standard error")?;
    }
    for (k, s) in a.scans.iter().enumerate() {
        let sg = out.group(&format!("bulge/scan_{k}"), Some("NXdata"))?;
        out.write_string(&sg, "file", &files[k])?;
        if let Some(lev) = &s.fit.levelled {
            out.write_array(&sg, "levelled", lev.z.view(), "m", "levelled height")?;
            out.write_scalar(&sg, "dx", lev.dx, "m", "pixel spacing along x")?;
            out.write_scalar(&sg, "dy", lev.dy, "m", "pixel spacing along y")?;
        }
        for (l, line) in s.fit.lines.iter().enumerate() {
            out.write_scalar(
                &sg,
                &format!("line_{l}_offset"),
                line.offset,
                "m",
                "offset of the line from the bulge centre",
            )?;
            out.write_1d(
                &sg,
                &format!("line_{l}_x"),
                &line.x,
                "m",
                "position along the line",
            )?;
            out.write_1d(
                &sg,
                &format!("line_{l}_levelled"),
                &line.z,
                "m",
                "levelled height (NaN: not fitted)",
            )?;
        }
    }
    out.finish()?;
    let rows = a
        .scans
        .iter()
        .map(|s| match serde_json::to_value(scan(s)) {
            Ok(Value::Object(m)) => Ok(m),
            Ok(other) => Err(encode(format!("not a JSON object: {other}"))),
            Err(e) => Err(encode(e.to_string())),
        })
        .collect::<Result<Vec<Map<String, Value>>>>()?;
    write_table(&rows, &dir.join("scans"))?;
    Ok(())
}

/// Figures (docs/bulge.md, `figures::bulge`): per scan the levelled map (masked pixels blank)
/// with the fitted outline and the regions left out, and three scan lines through the fitted
/// centre and ±6 µm across it with the fitted cap (Fig. C.5 style); height against heater
/// power with the efficiency line.
pub fn write_figures(a: &BulgeAnalysis, options: &BulgeOptions, dir: &Path) -> Result<()> {
    use crate::figures::bulge as fig;
    for (k, s) in a.scans.iter().enumerate() {
        let f = &s.fit;
        let label = match s.power {
            Some(p) => format!("{:.0} mW", p * 1e3),
            None => s.file.display().to_string(),
        };
        let Some(lev) = &f.levelled else {
            fig::scan_lines_png(
                &dir.join(format!("scan_{k}_lines.png")),
                &fig::offset_lines(f),
                &format!("Line scans across the bulge, {label}"),
            )?;
            continue;
        };
        let shown = ndarray::Array2::from_shape_fn(lev.z.dim(), |(j, i)| {
            if lev.is_valid(j, i) {
                lev.z[[j, i]]
            } else {
                f64::NAN
            }
        });
        fig::levelled_map_png(
            &dir.join(format!("scan_{k}_levelled.png")),
            f,
            shown.view(),
            &options.exclude,
            options.te_margin,
            &format!("Levelled profilometer scan, {label}"),
        )?;
        let lines = fig::scan_lines(shown.view(), lev.dx, lev.dy, &fig::Cap::from(f));
        fig::scan_lines_png(
            &dir.join(format!("scan_{k}_lines.png")),
            &lines,
            &format!("Scan lines across the bulge, {label} — Fig. C.5"),
        )?;
    }
    if let Some(e) = a.efficiency {
        let pts: Vec<(f64, f64)> = a
            .scans
            .iter()
            .filter_map(|s| s.power.map(|p| (p, s.fit.height)))
            .collect();
        fig::height_vs_power_png(
            &dir.join("height_vs_power.png"),
            &pts,
            e.efficiency,
            e.intercept,
        )?;
    }
    Ok(())
}

pub struct BulgeStage {
    pub params: BulgeParams,
}

impl FromConfig for BulgeStage {
    type Config = BulgeConfig;

    fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &BulgeConfig,
    ) -> std::result::Result<Self, ConfigError> {
        let err = |k: &str, m: String| file.error("bulge", name, k, m);
        if cfg.files.is_empty() && cfg.lines.is_empty() {
            return Err(err(
                "files",
                "needs at least one scan (`files` or `lines`)".into(),
            ));
        }
        let lines = cfg
            .lines
            .iter()
            .map(|l| {
                let f = file.input_file("bulge", name, "lines", &l.file, "line scan")?;
                line_spec(f, l).map_err(|m| err("lines", m))
            })
            .collect::<std::result::Result<Vec<_>, _>>()?;
        let files = cfg
            .files
            .iter()
            .map(|f| file.input_file("bulge", name, "files", f, "profilometer scan"))
            .collect::<std::result::Result<Vec<_>, _>>()?;
        let given: Option<Vec<f64>> = cfg.powers.as_ref().map(|p| p.iter().map(|v| v.0).collect());
        let powers = resolve_powers(&files, given.as_deref()).map_err(|m| err("powers", m))?;
        let te_margin = cfg.te_margin.map(|l| l.0).unwrap_or(2e-6);
        if te_margin.is_nan() || te_margin < 0.0 {
            return Err(err("te_margin", format!("{te_margin} m must be ≥ 0")));
        }
        Ok(Self {
            params: BulgeParams {
                files,
                powers,
                lines,
                options: BulgeOptions {
                    exclude: rects(&cfg.exclude),
                    auto_te: cfg.auto_te,
                    te_margin,
                },
                channel: cfg.channel.clone(),
            },
        })
    }
}

impl StageKind for BulgeStage {
    const KIND: &'static str = "bulge";
    const MODEL_VERSION: &'static str = MODEL_VERSION;
    type Result = BulgeReport;
    type Row = BulgeRow;

    fn params(&self) -> Value {
        let p = &self.params;
        let mut v = json!({
            "powers_W": p.powers,
            "exclude_m": p.options.exclude.iter().map(|r| [r.x0, r.y0, r.width, r.height]).collect::<Vec<_>>(),
            "auto_te": p.options.auto_te,
            "te_margin_m": p.options.te_margin,
            "channel": p.channel,
        });
        // Only when given, so map-only instances keep their cache key.
        if !p.lines.is_empty() {
            v["lines"] = p
                .lines
                .iter()
                .map(|l| json!({ "offset_m": l.offset, "power_W": l.power }))
                .collect();
        }
        v
    }
    fn inputs(&self) -> Vec<(String, PathBuf)> {
        let p = &self.params;
        let files = p
            .files
            .iter()
            .enumerate()
            .map(|(k, f)| (format!("files[{k}]"), f.clone()));
        let lines = p
            .lines
            .iter()
            .enumerate()
            .map(|(k, l)| (format!("lines[{k}]"), l.file.clone()));
        files.chain(lines).collect()
    }
    fn run(&self, ctx: &StageContext) -> Result<Output<BulgeReport, BulgeRow>> {
        let a = analyse(&self.params)?;
        write_outputs(&a, &self.params(), ctx.key, ctx.out_dir)?;
        write_figures(&a, &self.params.options, ctx.out_dir)?;
        let r = |v: f64| crate::core::store::round_significant(v, 6);
        let row = BulgeRow {
            scans: a.scans.len(),
            a_tfc_um: r(a.tfc.a_tfc_m * 1e6),
            w_tfc_um: r(a.tfc.w_tfc_m * 1e6),
            x_tfc_um: a.tfc.x_tfc_m.map(|x| r(x * 1e6)),
            efficiency_nm_per_mw: a.tfc.efficiency_m_per_w.map(|e| r(e * 1e6)),
            intercept_nm: a.tfc.intercept_m.map(|h| r(h * 1e9)),
        };
        Ok(Output {
            result: report(&a),
            summary_row: Some(row),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn powers_from_names_or_given() {
        let files = vec![PathBuf::from("a/tfc_30mW.gsf"), PathBuf::from("b.gsf")];
        assert_eq!(
            resolve_powers(&files, None).unwrap(),
            vec![Some(0.03), None]
        );
        assert_eq!(
            resolve_powers(&files, Some(&[0.0, 0.09])).unwrap(),
            vec![Some(0.0), Some(0.09)]
        );
        assert!(resolve_powers(&files, Some(&[0.0])).is_err());
        assert!(resolve_powers(&files, Some(&[0.0, -1.0])).is_err());
    }
}
