//! Deterministic contact stage (`[contact_bem.NAME]`): the FFT-BEM solution on the measured
//! composite map of an interface — the same two maps whose statistics the ISBL model uses —
//! over the ISBL curves' separations, overlaid on those curves (docs/contact.md,
//! "Deterministic contact").

use super::{FromConfig, Output, StageContext, StageKind};
use crate::artefacts::contact::upstream_isbl_params;
use crate::artefacts::contact_bem::{BemCurvePoint, BemResult, BEM_FILE};
use crate::artefacts::interface::InterfaceSurfaces;
use crate::artefacts::surface::upstream_final_map;
use crate::contact::bem::{force_separation, BemSolver, Boundary, SolverSettings, Target};
use crate::contact::bem::{BemSolution, GapHistogram};
use crate::contact::isbl::IsblModel;
use crate::contact::reduced_modulus;
use crate::core::config::{ConfigError, PipelineFile};
use crate::core::store::{round_significant, rows_of, write_table, H5Out};
use crate::error::Result;
use crate::figures;
use crate::figures::contact_bem::OverlayPoint;
use crate::surface::io::{read_height_map, ReadOptions};
use crate::surface::level::{level, DEFAULT_RECIPE};
use crate::surface::SurfaceError;
use crate::units::Pressure;
use ndarray::Array2;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};
use std::path::PathBuf;

pub const MODEL_VERSION: &str = "bem-1";

/// The DLC/DLC pair of every dissertation parameter set (docs/contact.md).
const DEFAULT_MODULUS: f64 = 280e9;
const DEFAULT_POISSON: f64 = 0.25;

/// `[contact_bem.NAME]` as written.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct ContactBemConfig {
    /// The `[interface.*]` whose two surfaces' analysed maps are summed.
    #[serde(default)]
    pub interface: Option<String>,
    /// Or one or two height-map files, levelled with the surface stage's default recipe.
    #[serde(default)]
    pub files: Vec<PathBuf>,
    /// The `[contact.*]` whose ISBL curves are overlaid; its E1, ν1, E2, ν2 give E*.
    #[serde(default)]
    pub contact: Option<String>,
    /// Without `contact`: both bodies' modulus and Poisson ratio (default DLC, 280 GPa, 0.25).
    #[serde(default)]
    pub modulus: Option<Pressure>,
    #[serde(default)]
    pub poisson: Option<f64>,
    /// "periodic" (default) or "non_periodic".
    #[serde(default)]
    pub boundary: Option<String>,
    /// Separations h/σ (σ of the composite map): from `h_star_max` down to `h_star_min`.
    #[serde(default)]
    pub h_star_min: Option<f64>,
    #[serde(default)]
    pub h_star_max: Option<f64>,
    #[serde(default)]
    pub step: Option<f64>,
    /// h/σ of the pressure map and gap histogram.
    #[serde(default)]
    pub map_at: Option<f64>,
    #[serde(default)]
    pub tolerance: Option<f64>,
    #[serde(default)]
    pub max_iterations: Option<usize>,
}

/// Where the map comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum MapSource {
    /// The interface and its two surface instances.
    Interface {
        name: String,
        surfaces: [String; 2],
    },
    Files(Vec<PathBuf>),
}

/// Checked settings.
#[derive(Debug, Clone, PartialEq)]
pub struct BemParams {
    pub source: MapSource,
    pub contact: Option<String>,
    pub modulus: f64,
    pub poisson: f64,
    pub boundary: Boundary,
    pub h_star_min: f64,
    pub h_star_max: f64,
    pub step: f64,
    pub map_at: f64,
    pub settings: SolverSettings,
}

pub struct ContactBemStage {
    pub name: String,
    pub params: BemParams,
}

fn boundary_name(b: Boundary) -> &'static str {
    match b {
        Boundary::Periodic => "periodic",
        Boundary::NonPeriodic => "non_periodic",
    }
}

/// A rejected key and why (the CLI names it as a flag, the pipeline at its line).
#[derive(Debug, Clone, PartialEq)]
pub struct KeyError {
    pub key: &'static str,
    pub message: String,
}

/// The settings of `cfg` apart from the map's source (shared by the pipeline and the CLI).
pub fn check(
    cfg: &ContactBemConfig,
    source: MapSource,
) -> std::result::Result<BemParams, KeyError> {
    let err = |key: &'static str, message: String| KeyError { key, message };
    if cfg.contact.is_some() && (cfg.modulus.is_some() || cfg.poisson.is_some()) {
        let key = if cfg.modulus.is_some() {
            "modulus"
        } else {
            "poisson"
        };
        return Err(err(
            key,
            "E* comes from the `contact` instance: drop this key or `contact`".into(),
        ));
    }
    let modulus = cfg.modulus.map_or(DEFAULT_MODULUS, |m| m.0);
    let poisson = cfg.poisson.unwrap_or(DEFAULT_POISSON);
    if !(modulus > 0.0 && modulus.is_finite()) {
        return Err(err(
            "modulus",
            format!("{modulus} Pa is out of range: must be > 0"),
        ));
    }
    if !(-1.0..0.5).contains(&poisson) {
        return Err(err(
            "poisson",
            format!("{poisson} is out of range: −1 ≤ ν < 0.5"),
        ));
    }
    let boundary = match cfg.boundary.as_deref().unwrap_or("periodic") {
        "periodic" => Boundary::Periodic,
        "non_periodic" => Boundary::NonPeriodic,
        other => {
            return Err(err(
                "boundary",
                format!("`{other}`: use periodic or non_periodic"),
            ))
        }
    };
    let h_star_min = cfg.h_star_min.unwrap_or(0.25);
    let h_star_max = cfg.h_star_max.unwrap_or(4.0);
    let step = cfg.step.unwrap_or(0.05);
    if !(h_star_min > 0.0 && h_star_min.is_finite()) {
        return Err(err(
            "h_star_min",
            format!("{h_star_min} is out of range: the mean gap is > 0 (full contact at 0)"),
        ));
    }
    if !(h_star_max > h_star_min && h_star_max <= 50.0) {
        return Err(err(
            "h_star_max",
            format!("{h_star_max} is out of range: must lie in (h_star_min, 50]"),
        ));
    }
    if !(step > 0.0 && (h_star_max - h_star_min) / step <= 2000.0) {
        return Err(err(
            "step",
            format!("{step} is out of range: > 0 and at most 2000 separations"),
        ));
    }
    let map_at = cfg.map_at.unwrap_or(1.5);
    if !(h_star_min..=h_star_max).contains(&map_at) {
        return Err(err(
            "map_at",
            format!("{map_at} is out of range: within [h_star_min, h_star_max]"),
        ));
    }
    let defaults = SolverSettings::default();
    let settings = SolverSettings {
        tolerance: cfg.tolerance.unwrap_or(defaults.tolerance),
        max_iterations: cfg.max_iterations.unwrap_or(defaults.max_iterations),
    };
    if !(settings.tolerance > 0.0 && settings.tolerance < 1e-2) {
        return Err(err(
            "tolerance",
            format!("{} is out of range: (0, 0.01)", settings.tolerance),
        ));
    }
    if settings.max_iterations == 0 {
        return Err(err("max_iterations", "must be ≥ 1".into()));
    }
    Ok(BemParams {
        source,
        contact: cfg.contact.clone(),
        modulus,
        poisson,
        boundary,
        h_star_min,
        h_star_max,
        step,
        map_at,
        settings,
    })
}

impl FromConfig for ContactBemStage {
    type Config = ContactBemConfig;

    fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &ContactBemConfig,
    ) -> std::result::Result<Self, ConfigError> {
        let err = |k: &str, m: String| file.error("contact_bem", name, k, m);
        let source = match (&cfg.interface, cfg.files.is_empty()) {
            (Some(i), true) => {
                let surfaces = InterfaceSurfaces::of(file, i)?
                    .filter(InterfaceSurfaces::has_two_surfaces)
                    .ok_or_else(|| {
                        err(
                            "interface",
                            format!(
                                "no [interface.{i}] of two measured surfaces in this file (an \
                                 explicit interface has no map)"
                            ),
                        )
                    })?
                    .surfaces;
                MapSource::Interface {
                    name: i.clone(),
                    surfaces: [surfaces[0].clone(), surfaces[1].clone()],
                }
            }
            (None, false) if cfg.files.len() <= 2 => {
                let files = cfg
                    .files
                    .iter()
                    .map(|f| file.input_file("contact_bem", name, "files", f, "height map"))
                    .collect::<std::result::Result<Vec<_>, _>>()?;
                MapSource::Files(files)
            }
            (None, false) => return Err(err("files", "one or two height maps".into())),
            (Some(_), false) => {
                return Err(err("files", "give `interface` or `files`, not both".into()))
            }
            (None, true) => {
                return Err(err(
                    "interface",
                    "needs an `interface` (or one or two `files`)".into(),
                ))
            }
        };
        if let Some(c) = &cfg.contact {
            if !file.has_instance("contact", c) {
                return Err(err("contact", format!("no [contact.{c}] in this file")));
            }
        }
        let params = check(cfg, source).map_err(|e| err(e.key, e.message))?;
        Ok(ContactBemStage {
            name: name.to_string(),
            params,
        })
    }
}

/// One row of the contact_bem summary table.
#[derive(Debug, Clone, Serialize)]
pub struct BemRow {
    pub grid: String,
    pub sigma_nm: f64,
    #[serde(rename = "E_star_GPa")]
    pub e_star_gpa: f64,
    pub boundary: &'static str,
    /// P(3σ)/P(2.5σ) under the BEM and, with an ISBL overlay, under ISBL.
    pub p_ratio_3_over_2_5_bem: Option<f64>,
    pub p_ratio_3_over_2_5_isbl: Option<f64>,
    pub contact_fraction_at_2sigma: Option<f64>,
    pub iterations_max: usize,
}

impl StageKind for ContactBemStage {
    const KIND: &'static str = "contact_bem";
    const MODEL_VERSION: &'static str = MODEL_VERSION;
    type Result = BemResult;
    type Row = BemRow;

    fn params(&self) -> Value {
        let p = &self.params;
        let source = match &p.source {
            MapSource::Interface { name, surfaces } => {
                json!({"interface": name, "surfaces": surfaces})
            }
            MapSource::Files(_) => json!({"files": "see inputs"}),
        };
        json!({
            "source": source,
            "contact": p.contact,
            "modulus_Pa": p.modulus,
            "poisson": p.poisson,
            "boundary": boundary_name(p.boundary),
            "h_star_min": p.h_star_min,
            "h_star_max": p.h_star_max,
            "step": p.step,
            "map_at": p.map_at,
            "tolerance": p.settings.tolerance,
            "max_iterations": p.settings.max_iterations,
        })
    }
    fn inputs(&self) -> Vec<(String, PathBuf)> {
        match &self.params.source {
            MapSource::Files(f) => f
                .iter()
                .enumerate()
                .map(|(k, p)| (format!("files[{k}]"), p.clone()))
                .collect(),
            MapSource::Interface { .. } => Vec::new(),
        }
    }
    fn upstream(&self) -> Vec<String> {
        let mut up = match &self.params.source {
            MapSource::Interface { name, surfaces } => {
                vec![name.clone(), surfaces[0].clone(), surfaces[1].clone()]
            }
            MapSource::Files(_) => Vec::new(),
        };
        up.extend(self.params.contact.clone());
        up
    }
    fn run(&self, ctx: &StageContext) -> Result<Output<BemResult, BemRow>> {
        let p = &self.params;
        let map = composite_map(p, ctx)?;
        let isbl = match &p.contact {
            Some(c) => Some(IsblModel::new(upstream_isbl_params(&ctx.upstream, c)?)?),
            None => None,
        };
        let e_star = match &isbl {
            Some(m) => m.params().composite_modulus(),
            None => reduced_modulus(p.modulus, p.poisson, p.modulus, p.poisson),
        };
        let (ny, nx) = map.z.dim();
        let heights: Vec<f64> = map.z.iter().copied().collect();
        let solver = BemSolver::new(&heights, nx, ny, (map.dx, map.dy), e_star, p.boundary)?;
        let sigma = solver.sigma();
        let n_steps = ((p.h_star_max - p.h_star_min) / p.step + 1e-9).floor() as usize;
        let h_stars: Vec<f64> = (0..=n_steps)
            .map(|k| round_significant(p.h_star_max - k as f64 * p.step, 12))
            .collect();
        ctx.progress.set_message(format!(
            "BEM {nx}×{ny}: {} separations (h/σ {} → {})",
            h_stars.len(),
            p.h_star_max,
            p.h_star_min
        ));
        let separations: Vec<f64> = h_stars.iter().map(|h| h * sigma).collect();
        let curve = force_separation(&solver, &separations, &p.settings)?;
        // The ISBL curves at the same h/σ (its own σ: the interface's combined statistics).
        let isbl_at = |h_star: f64| -> Result<Option<(f64, f64)>> {
            match &isbl {
                Some(m) => {
                    let pt = m.at(h_star * m.params().sigma)?;
                    Ok(Some((pt.contact_pressure, pt.real_area_fraction)))
                }
                None => Ok(None),
            }
        };
        let mut points = Vec::with_capacity(curve.len());
        for (c, &h_star) in curve.iter().zip(&h_stars) {
            let isbl = isbl_at(h_star)?;
            points.push(BemCurvePoint::new(h_star, c, isbl));
        }
        let at_map = solver.solve(Target::Separation(p.map_at * sigma), &p.settings, None)?;
        let result = BemResult::new(
            (nx, ny),
            (map.dx, map.dy),
            sigma,
            e_star,
            boundary_name(p.boundary),
            p.settings.tolerance,
            isbl.as_ref().map(|m| m.params().sigma),
            points,
            solver.memory_bytes(),
        );
        let histogram = GapHistogram::of(&at_map, sigma);
        write_h5(
            ctx,
            &self.params(),
            &map,
            &result,
            &at_map,
            &histogram,
            p.map_at,
        )?;
        let overlay: Vec<OverlayPoint> = result
            .curve
            .iter()
            .map(|c| OverlayPoint {
                h_star: c.h_star,
                bem: (c.pressure_Pa, c.contact_fraction),
                isbl: c.isbl_pressure_Pa.zip(c.isbl_contact_fraction),
            })
            .collect();
        figures::contact_bem::write_all(
            ctx.out_dir,
            &overlay,
            &at_map.pressure,
            ((nx, ny), (map.dx, map.dy)),
            &histogram,
            p.map_at,
        )?;
        write_table(
            &rows_of(&result.table_rows()),
            &ctx.out_dir.join("bem_vs_isbl"),
        )?;
        write_composite_x3p(&ctx.out_dir.join(COMPOSITE_X3P), &map, &p.source)?;
        let row = BemRow {
            grid: format!("{nx}x{ny}"),
            sigma_nm: round_significant(sigma * 1e9, 6),
            e_star_gpa: round_significant(e_star * 1e-9, 6),
            boundary: boundary_name(p.boundary),
            p_ratio_3_over_2_5_bem: result.ratio_3_over_2_5.bem,
            p_ratio_3_over_2_5_isbl: result.ratio_3_over_2_5.isbl,
            contact_fraction_at_2sigma: result.contact_fraction_at(2.0),
            iterations_max: result.iterations_max,
        };
        Ok(Output {
            result,
            summary_row: Some(row),
        })
    }
}

/// The composite map as ISO 25178-71 X3P: what another solver (tamaas, ContactMechanics)
/// needs to check this one on the same map.
pub const COMPOSITE_X3P: &str = "composite.x3p";

fn write_composite_x3p(path: &std::path::Path, map: &Map, source: &MapSource) -> Result<()> {
    let what = match source {
        MapSource::Interface { name, surfaces } => format!(
            "interface {name}: the sum of the analysed maps of surfaces {} and {}",
            surfaces[0], surfaces[1]
        ),
        MapSource::Files(files) => {
            let names: Vec<String> = files
                .iter()
                .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
                .collect();
            format!(
                "the sum of {} levelled (rows:median, plane, mean)",
                names.join(" and ")
            )
        }
    };
    let height_map = crate::surface::HeightMap {
        z: map.z.clone(),
        dx: map.dx,
        dy: map.dy,
        x0: 0.0,
        y0: 0.0,
        channel: "composite height".into(),
        valid: None,
        periodic: false,
        source: Default::default(),
        history: Vec::new(),
    };
    let bytes = crate::surface::io::encode_x3p(&height_map, &format!("hdi contact_bem: {what}"))?;
    std::fs::write(path, bytes).map_err(|e| crate::error::Error::io(path, e))
}

/// A height map in metres and its spacing.
pub struct Map {
    pub z: Array2<f64>,
    pub dx: f64,
    pub dy: f64,
}

/// The map the BEM solves: the sum of the interface's two analysed maps (the composite the
/// ISBL interface's statistics describe), or of the given files levelled by the surface
/// stage's default recipe.
fn composite_map(p: &BemParams, ctx: &StageContext) -> Result<Map> {
    let maps: Vec<Map> = match &p.source {
        MapSource::Interface { surfaces, .. } => surfaces
            .iter()
            .map(|s| {
                upstream_final_map(&ctx.upstream_dirs, s).map(|m| Map {
                    z: m.z,
                    dx: m.dx,
                    dy: m.dy,
                })
            })
            .collect::<Result<_>>()?,
        MapSource::Files(files) => files
            .iter()
            .map(|f| read_levelled(f))
            .collect::<Result<_>>()?,
    };
    sum_maps(maps)
}

/// A height map read and levelled with the surface stage's default recipe; invalid pixels
/// are an error (the BEM needs every element).
pub fn read_levelled(path: &std::path::Path) -> Result<Map> {
    let mut m = read_height_map(path, &ReadOptions::default())?;
    level(&mut m, &DEFAULT_RECIPE)?;
    if m.valid.as_ref().is_some_and(|v| v.iter().any(|ok| !ok)) {
        return Err(SurfaceError::InvalidData(format!(
            "{}: {:.2} % of the pixels are invalid; the BEM needs a complete map (crop it)",
            path.display(),
            100.0 * m.masked_fraction()
        ))
        .into());
    }
    Ok(Map {
        z: m.z,
        dx: m.dx,
        dy: m.dy,
    })
}

/// The sum of one or two maps on the same grid (spacings within 0.1 %).
pub fn sum_maps(mut maps: Vec<Map>) -> Result<Map> {
    let mut first = maps.remove(0);
    if let Some(second) = maps.pop() {
        let same_spacing = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-3;
        if first.z.dim() != second.z.dim()
            || !same_spacing(first.dx, second.dx)
            || !same_spacing(first.dy, second.dy)
        {
            return Err(SurfaceError::InvalidData(format!(
                "the two maps differ in grid: {:?} at {:.4e} × {:.4e} m against {:?} at \
                 {:.4e} × {:.4e} m (resample one onto the other's grid)",
                first.z.dim(),
                first.dx,
                first.dy,
                second.z.dim(),
                second.dx,
                second.dy
            ))
            .into());
        }
        first.z += &second.z;
    }
    Ok(first)
}

/// `contact.h5`: `/bem` (the curve, the composite map, the pressure and gap at `map_at`, the
/// gap histogram) with units as attributes (docs/hdf5.md).
fn write_h5(
    ctx: &StageContext,
    params: &Value,
    map: &Map,
    r: &BemResult,
    at: &BemSolution,
    histogram: &GapHistogram,
    map_at: f64,
) -> Result<()> {
    let out = H5Out::create(&ctx.out_dir.join(BEM_FILE))?;
    out.root_attributes("contact_bem", ctx.key, params, &Value::Null, "bem")?;
    let g = out.group("bem", Some("NXentry"))?;
    out.write_scalar(
        &g,
        "sigma",
        r.sigma_m,
        "m",
        "RMS height of the composite map",
    )?;
    out.write_scalar(&g, "E_star", r.e_star_Pa, "Pa", "reduced modulus")?;
    out.write_string(&g, "boundary", &r.boundary)?;
    out.write_scalar(
        &g,
        "tolerance",
        r.tolerance,
        "1",
        "convergence tolerance (docs/contact.md)",
    )?;
    let c = out.group("bem/curve", Some("NXdata"))?;
    out.attr_str(&c, "signal", "pressure")?;
    out.attr_str_list(&c, "axes", &["h_star"])?;
    let col = |f: &dyn Fn(&BemCurvePoint) -> f64| -> Vec<f64> { r.curve.iter().map(f).collect() };
    out.write_1d(&c, "h_star", &col(&|p| p.h_star), "1", "separation / sigma")?;
    out.write_1d(&c, "mean_gap", &col(&|p| p.mean_gap_m), "m", "mean gap")?;
    out.write_1d(
        &c,
        "pressure",
        &col(&|p| p.pressure_Pa),
        "Pa",
        "BEM mean contact pressure",
    )?;
    out.write_1d(
        &c,
        "contact_fraction",
        &col(&|p| p.contact_fraction),
        "1",
        "BEM A_r/A_0",
    )?;
    out.write_1d(
        &c,
        "iterations",
        &col(&|p| p.iterations as f64),
        "1",
        "CG iterations",
    )?;
    out.write_1d(&c, "error", &col(&|p| p.error), "1", "final error")?;
    if r.isbl_sigma_m.is_some() {
        let nan = f64::NAN;
        out.write_1d(
            &c,
            "isbl_pressure",
            &col(&|p| p.isbl_pressure_Pa.unwrap_or(nan)),
            "Pa",
            "ISBL contact pressure at the same h/sigma",
        )?;
        out.write_1d(
            &c,
            "isbl_contact_fraction",
            &col(&|p| p.isbl_contact_fraction.unwrap_or(nan)),
            "1",
            "ISBL A_r/A_n at the same h/sigma",
        )?;
    }
    let m = out.group("bem/map", Some("NXdata"))?;
    out.attr_str(&m, "signal", "height")?;
    out.attr_str_list(&m, "axes", &["y", "x"])?;
    let (ny, nx) = map.z.dim();
    out.write_array(
        &m,
        "height",
        map.z.view(),
        "m",
        "composite height (sum of the two maps)",
    )?;
    let axis = |n: usize, d: f64| -> Vec<f64> { (0..n).map(|k| k as f64 * d).collect() };
    out.write_1d(&m, "x", &axis(nx, map.dx), "m", "x")?;
    out.write_1d(&m, "y", &axis(ny, map.dy), "m", "y")?;
    let field = |v: &[f64]| Array2::from_shape_vec((ny, nx), v.to_vec()).expect("ny × nx field");
    let l = out.group("bem/at_load", Some("NXdata"))?;
    out.attr_str(&l, "signal", "pressure")?;
    out.attr_f64(&l, "h_star", map_at)?;
    out.write_array(
        &l,
        "pressure",
        field(&at.pressure).view(),
        "Pa",
        "contact pressure",
    )?;
    out.write_array(&l, "gap", field(&at.gap).view(), "m", "gap")?;
    out.write_scalar(&l, "mean_pressure", at.mean_pressure, "Pa", "mean pressure")?;
    out.write_scalar(&l, "contact_fraction", at.contact_fraction, "1", "A_r/A_0")?;
    let hg = out.group("bem/gap_histogram", Some("NXdata"))?;
    out.write_1d(
        &hg,
        "edges",
        &histogram.edges,
        "1",
        "gap / sigma bin edges (elements out of contact)",
    )?;
    let counts: Vec<f64> = histogram.counts.iter().map(|&c| c as f64).collect();
    out.write_1d(&hg, "counts", &counts, "1", "elements per bin")?;
    out.write_count(
        &hg,
        "in_contact",
        histogram.in_contact,
        "elements in contact (gap 0)",
    )?;
    Ok(out.finish()?)
}
