//! The surface stage's outputs: `surface.h5` (maps, summits, parameters, scale sweep;
//! docs/hdf5.md) and the PNGs.

use super::{SurfaceAnalysis, SurfaceParams, AREA_QUANTITIES};
use crate::core::store::H5Out;
use crate::error::Result;
use crate::figures;
use crate::numerics::bootstrap::Summary;
use crate::surface::roughness::{RoughnessReport, SweepRow};
use crate::surface::spectra::{Curve, TipCutoff, TIP_SAFETY_FACTOR};
use crate::surface::HeightMap;
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::path::Path;

pub(super) fn axis(n: usize, d: f64, off: f64) -> Vec<f64> {
    (0..n).map(|i| off + i as f64 * d).collect()
}

pub(super) fn write_map(out: &H5Out, path: &str, m: &HeightMap, long_name: &str) -> Result<()> {
    let g = out.group(path, Some("NXdata"))?;
    out.attr_str(&g, "signal", "height")?;
    out.attr_str_list(&g, "axes", &["y", "x"])?;
    out.attr_f64(&g, "y_indices", 0.0)?;
    out.attr_f64(&g, "x_indices", 1.0)?;
    out.write_array(&g, "height", m.z.view(), "m", long_name)?;
    out.write_1d(
        &g,
        "x",
        &axis(m.nx(), m.dx, m.x0),
        "m",
        "fast-scan position",
    )?;
    out.write_1d(
        &g,
        "y",
        &axis(m.ny(), m.dy, m.y0),
        "m",
        "slow-scan position (row 0 = top)",
    )?;
    Ok(())
}

/// The analysed map as ISO 25178-71 X3P (float64 metres, docs/surfaces.md "X3P out"), with the
/// source file's name and the processing in a comment of its `main.xml`. The file name only,
/// not its path: the same input gives the same bytes wherever the project lies.
pub(super) fn write_x3p(a: &SurfaceAnalysis, p: &SurfaceParams, path: &Path) -> Result<()> {
    let map = a.final_map();
    let steps: Vec<String> = map
        .history
        .iter()
        .map(|s| {
            let args: Vec<String> = s.params.iter().map(|(k, v)| format!("{k}={v}")).collect();
            format!("{}({})", s.name, args.join(", "))
        })
        .collect();
    let note = format!(
        "written by hdi {} from {} ({}, channel {}); processing: {}",
        env!("CARGO_PKG_VERSION"),
        p.file
            .file_name()
            .map_or_else(String::new, |f| f.to_string_lossy().into_owned()),
        map.source.format,
        map.channel,
        if steps.is_empty() {
            "none".to_string()
        } else {
            steps.join("; ")
        }
    );
    let bytes = crate::surface::io::encode_x3p(map, &note)?;
    std::fs::write(path, bytes).map_err(|e| crate::error::Error::io(path, e))
}

/// HDF5 (layout in docs/hdf5.md) and PNGs into `dir`.
pub fn write_outputs(
    a: &SurfaceAnalysis,
    p: &SurfaceParams,
    h5_path: &Path,
    plot_dir: Option<&Path>,
    cache_key: &str,
    inputs: &Value,
) -> Result<()> {
    let out = H5Out::create(h5_path)?;
    out.root_attributes("surface", cache_key, &p.canonical(), inputs, "surface")?;
    write_h5_body(&out, a)?;
    out.finish()?;

    if let Some(dir) = plot_dir {
        write_figures(a, dir)?;
    }
    Ok(())
}

/// Everything in `surface.h5` below the root attributes, for one analysed map.
pub(super) fn write_h5_body(out: &H5Out, a: &SurfaceAnalysis) -> Result<()> {
    let entry = out.group("surface", Some("NXentry"))?;
    let default = if a.filtered.is_some() {
        "filtered"
    } else {
        "levelled"
    };
    out.attr_str(&entry, "default", default)?;
    write_maps(out, &entry, a)?;
    write_summits(out, &a.report)?;
    write_parameters(out, &a.report, a.final_map())?;
    if !a.sweep.is_empty() {
        write_sweeps(out, &a.sweep)?;
    }
    write_spectra(out, "surface", a)?;
    let fm = a.final_map();
    let history: Vec<Value> = fm
        .history
        .iter()
        .map(|s| json!({"name": s.name, "params": s.params}))
        .collect();
    out.write_string(&entry, "history", &Value::Array(history).to_string())?;
    out.write_string(&entry, "warnings", &a.report.warnings.join("\n"))?;
    Ok(())
}

/// `surface/{raw,levelled,filtered}` and the invalid-pixel mask of the final map.
pub(super) fn write_maps(out: &H5Out, entry: &hdf5::Group, a: &SurfaceAnalysis) -> Result<()> {
    write_map(out, "surface/raw", &a.raw, "height as read")?;
    write_map(
        out,
        "surface/levelled",
        &a.levelled,
        "height after levelling",
    )?;
    if let Some(f) = &a.filtered {
        write_map(
            out,
            "surface/filtered",
            f,
            "height after levelling and filtering",
        )?;
    }
    let fm = a.final_map();
    if let Some(valid) = &fm.valid {
        let mask = valid.mapv(|ok| u8::from(!ok));
        out.write_array(
            entry,
            "mask",
            mask.view(),
            "1",
            "1 = invalid pixel (NaN, saturated, masked)",
        )?;
    }
    Ok(())
}

/// `surface/summits` and the height and summit-height histograms.
pub(super) fn write_summits(out: &H5Out, r: &RoughnessReport) -> Result<()> {
    let g = out.group("surface/summits", None)?;
    let col = |f: fn(&crate::surface::roughness::Summit) -> f64| -> Vec<f64> {
        r.summits.iter().map(f).collect()
    };
    out.write_1d(&g, "x", &col(|s| s.x), "m", "summit x")?;
    out.write_1d(&g, "y", &col(|s| s.y), "m", "summit y")?;
    out.write_1d(
        &g,
        "height",
        &col(|s| s.height),
        "m",
        "summit height above the mean plane",
    )?;
    out.write_1d(
        &g,
        "curvature",
        &col(|s| s.curvature),
        "1/m",
        "summit curvature",
    )?;
    out.write_string(&g, "scheme", &r.summit_scheme.to_string())?;
    for (name, h, what) in [
        ("height_histogram", &r.height_histogram, "height"),
        ("summit_histogram", &r.summit_histogram, "summit height"),
    ] {
        let g = out.group(&format!("surface/{name}"), None)?;
        out.write_1d(&g, "edges", &h.edges, "m", &format!("{what} bin edges"))?;
        let counts: Vec<f64> = h.counts.iter().map(|&c| c as f64).collect();
        out.write_1d(&g, "counts", &counts, "1", &format!("{what} counts"))?;
        out.write_1d(
            &g,
            "density",
            &h.density,
            "1/m",
            &format!("{what} probability density"),
        )?;
        out.write_1d(
            &g,
            "gaussian",
            &h.gaussian,
            "1/m",
            "Gaussian density, same mean and sigma",
        )?;
    }
    Ok(())
}

/// `surface/parameters` (roughness and summit statistics) and `surface/nayak` (the same from
/// the spectral moments).
pub(super) fn write_parameters(out: &H5Out, r: &RoughnessReport, fm: &HeightMap) -> Result<()> {
    let g = out.group("surface/parameters", None)?;
    for (name, v, u, ln) in [
        ("sigma", r.sigma, "m", "RMS roughness Sq"),
        ("Sa", r.sa, "m", "arithmetic mean roughness"),
        ("Ssk", r.ssk, "1", "skewness"),
        ("Sku", r.sku, "1", "kurtosis (not excess)"),
        (
            "m2",
            r.m2,
            "1",
            "second spectral moment (mean square slope / 2)",
        ),
        ("m4", r.m4, "m^-2", "fourth spectral moment"),
        ("alpha", r.alpha, "1", "Nayak bandwidth parameter"),
        ("eta", r.eta, "m^-2", "summit density"),
        ("R", r.r, "m", "mean summit radius"),
        (
            "R_mean_of_inverse",
            r.r_mean_of_inverse,
            "m",
            "mean of 1/curvature",
        ),
        (
            "R_median_of_inverse",
            r.r_median_of_inverse,
            "m",
            "median of 1/curvature",
        ),
        ("beta", r.beta, "1", "sigma R eta"),
        ("sigma_s", r.sigma_s, "m", "std of summit heights"),
        (
            "mean_summit_height",
            r.mean_summit_height,
            "m",
            "mean summit height above mean plane",
        ),
        (
            "sampling_interval",
            r.sampling_interval,
            "m",
            "pixel spacing the summits were found at",
        ),
        (
            "masked_fraction",
            fm.masked_fraction(),
            "1",
            "fraction of invalid pixels",
        ),
    ] {
        out.write_scalar(&g, name, v, u, ln)?;
    }
    out.write_count(&g, "n_summits", r.n_summits as u64, "number of summits")?;
    out.write_string(&g, "R_definition", &r.r_definition.to_string())?;
    out.write_string(&g, "moments_method", &r.moments_method.to_string())?;
    let g = out.group("surface/nayak", None)?;
    out.write_scalar(
        &g,
        "eta",
        r.nayak.eta,
        "m^-2",
        "summit density from spectral moments",
    )?;
    out.write_scalar(
        &g,
        "R",
        r.nayak.r,
        "m",
        "mean summit radius from spectral moments",
    )?;
    out.write_scalar(&g, "beta", r.nayak.beta, "1", "beta from spectral moments")?;
    out.write_scalar(
        &g,
        "sigma_s",
        r.nayak.sigma_s,
        "m",
        "summit height std (Nayak)",
    )?;
    Ok(())
}

/// `surface/sweeps`: the sub-sampling and S-filter rows.
pub(super) fn write_sweeps(out: &H5Out, sweep: &[SweepRow]) -> Result<()> {
    let g = out.group("surface/sweeps", None)?;
    let kinds: Vec<&str> = sweep.iter().map(|s| s.kind.as_str()).collect();
    out.attr_str_list(&g, "kind", &kinds)?;
    let c = |f: fn(&SweepRow) -> f64| -> Vec<f64> { sweep.iter().map(f).collect() };
    out.write_1d(
        &g,
        "value",
        &c(|s| s.value),
        "1",
        "sub-sampling factor or S-filter cutoff in pixels",
    )?;
    out.write_1d(
        &g,
        "sampling_interval",
        &c(|s| s.sampling_interval),
        "m",
        "pixel spacing",
    )?;
    out.write_1d(&g, "sigma", &c(|s| s.sigma), "m", "RMS roughness")?;
    out.write_1d(&g, "eta", &c(|s| s.eta), "m^-2", "summit density")?;
    out.write_1d(&g, "R", &c(|s| s.r), "m", "mean summit radius")?;
    out.write_1d(&g, "beta", &c(|s| s.beta), "1", "sigma R eta")?;
    Ok(())
}

/// `{at}/analyses` (PSD, ACF, scale-dependent slope and curvature of the analysed map) and,
/// with a tip radius, `{at}/tip_reliability` (docs/surfaces.md).
pub(super) fn write_spectra(out: &H5Out, at: &str, a: &SurfaceAnalysis) -> Result<()> {
    let g = out.group(&format!("{at}/analyses"), None)?;
    match &a.spectra {
        Err(why) => out.write_string(&g, "not_computed", why)?,
        Ok(s) => {
            type Entry<'a> = (&'a str, &'a Curve, [(&'a str, &'a str, &'a str); 2]);
            let entries: [Entry; 8] = [
                (
                    "psd_profile",
                    &s.psd_profile,
                    [
                        ("q", "1/m", "wavevector 2π/λ along x"),
                        ("C", "m^3", "1-D PSD along x, averaged over the rows"),
                    ],
                ),
                (
                    "psd_area",
                    &s.psd_area,
                    [
                        ("q", "1/m", "wavevector magnitude 2π/λ"),
                        ("C", "m^4", "radially averaged 2-D PSD"),
                    ],
                ),
                (
                    "acf_profile",
                    &s.acf_profile,
                    [
                        ("r", "m", "distance along x"),
                        (
                            "A",
                            "m^2",
                            "height-difference ACF ½⟨(h(x+r)−h(x))²⟩ along x, averaged over the rows",
                        ),
                    ],
                ),
                (
                    "acf_area",
                    &s.acf_area,
                    [
                        ("r", "m", "distance"),
                        ("A", "m^2", "radially averaged height-difference ACF"),
                    ],
                ),
                (
                    "slope_profile",
                    &s.slope_profile,
                    [
                        ("scale", "m", "distance λ of the two-point difference"),
                        ("slope", "1", "RMS slope along x at scale λ"),
                    ],
                ),
                (
                    "slope_area",
                    &s.slope_area,
                    [
                        ("scale", "m", "distance λ of the two-point difference"),
                        ("slope", "1", "RMS slope at scale λ from the radial ACF"),
                    ],
                ),
                (
                    "curvature_profile",
                    &s.curvature_profile,
                    [
                        ("scale", "m", "total length λ of the three-point stencil"),
                        ("curvature", "1/m", "RMS curvature along x at scale λ"),
                    ],
                ),
                (
                    "curvature_area",
                    &s.curvature_area,
                    [
                        ("scale", "m", "total length λ of the three-point stencil"),
                        (
                            "curvature",
                            "1/m",
                            "RMS curvature at scale λ from the radial ACF",
                        ),
                    ],
                ),
            ];
            for (name, curve, [(xn, xu, xl), (yn, yu, yl)]) in entries {
                let c = out.group(&format!("{at}/analyses/{name}"), None)?;
                out.write_1d(&c, xn, &curve.x, xu, xl)?;
                out.write_1d(&c, yn, &curve.y, yu, yl)?;
            }
        }
    }
    let Some(t) = &a.tip else {
        return Ok(());
    };
    let g = out.group(&format!("{at}/tip_reliability"), None)?;
    out.write_scalar(&g, "tip_radius", t.tip_radius, "m", "tip radius given")?;
    out.write_scalar(
        &g,
        "safety_factor",
        TIP_SAFETY_FACTOR,
        "1",
        "f in the criterion min h''(λ) = −f/R",
    )?;
    let (status, cutoff) = match &t.cutoff {
        Ok(TipCutoff::At(l)) => ("cutoff", *l),
        Ok(TipCutoff::NoArtefacts) => ("no_artefacts", f64::NAN),
        Ok(TipCutoff::NoReliableData(l)) => ("no_reliable_data", *l),
        Err(_) => ("not_computed", f64::NAN),
    };
    out.write_string(&g, "status", status)?;
    if let Err(why) = &t.cutoff {
        out.write_string(&g, "not_computed", why)?;
    }
    out.write_scalar(
        &g,
        "cutoff",
        cutoff,
        "m",
        "stencil length below which the tip distorts the map (NaN: none)",
    )?;
    if let Some(r) = &t.above {
        for (name, v, u, ln) in [
            ("sigma", r.sigma, "m", "RMS roughness above the cutoff"),
            ("eta", r.eta, "m^-2", "summit density above the cutoff"),
            ("R", r.r, "m", "mean summit radius above the cutoff"),
            ("beta", r.beta, "1", "sigma R eta above the cutoff"),
        ] {
            out.write_scalar(&g, name, v, u, ln)?;
        }
        out.write_count(
            &g,
            "n_summits",
            r.n_summits as u64,
            "summits above the cutoff",
        )?;
    }
    Ok(())
}

/// PSD, ACF, slope and curvature against scale, log–log (`psd_profile.png`, `psd_area.png`,
/// `acf.png`, `slope.png`, `curvature.png`); nothing when the analyses were not computed.
fn write_spectra_figures(a: &SurfaceAnalysis, dir: &Path) -> Result<()> {
    let Ok(s) = &a.spectra else {
        return Ok(());
    };
    let pts = |c: &Curve, kx: f64, ky: f64| -> Vec<(f64, f64)> {
        c.x.iter()
            .zip(&c.y)
            .map(|(x, y)| (x * kx, y * ky))
            .collect()
    };
    let cutoff = a
        .tip
        .as_ref()
        .and_then(|t| t.cutoff.as_ref().ok())
        .and_then(|c| match c {
            TipCutoff::At(l) => Some(*l),
            _ => None,
        });
    let title = |what: &str| match cutoff {
        Some(l) => format!("{what} (tip cutoff λc = {:.1} nm)", l * 1e9),
        None => what.to_string(),
    };
    // The cutoff as a vertical line across the plotted values (at q = 2π/λc on a spectrum,
    // r = λc/2 on the ACF: the ACF's distance is half the curvature stencil).
    let plot = |file: &str,
                what: &str,
                x_desc: &str,
                y_desc: &str,
                series: Vec<(&str, Vec<(f64, f64)>)>,
                x_of_cutoff: Option<f64>|
     -> Result<()> {
        let mut series = series;
        if let Some(xc) = x_of_cutoff {
            let (lo, hi) = series
                .iter()
                .flat_map(|(_, s)| s.iter().map(|p| p.1))
                .filter(|y| *y > 0.0 && y.is_finite())
                .fold((f64::INFINITY, 0.0f64), |(a, b), y| (a.min(y), b.max(y)));
            if lo.is_finite() {
                series.push((
                    "tip reliability cutoff",
                    vec![(xc, lo.max(hi * 1e-10)), (xc, hi)],
                ));
            }
        }
        figures::loglog_png(&dir.join(file), &title(what), x_desc, y_desc, &series, &[])?;
        Ok(())
    };
    plot(
        "psd_profile.png",
        "1-D power spectral density along x",
        "wavevector q = 2π/λ (1/µm)",
        "C¹ᴰ (nm³)",
        vec![("averaged over the rows", pts(&s.psd_profile, 1e-6, 1e27))],
        cutoff.map(|l| 2.0 * PI / l * 1e-6),
    )?;
    plot(
        "psd_area.png",
        "Radially averaged 2-D power spectral density",
        "wavevector |q| = 2π/λ (1/µm)",
        "C²ᴰ (nm⁴)",
        vec![("radial average", pts(&s.psd_area, 1e-6, 1e36))],
        cutoff.map(|l| 2.0 * PI / l * 1e-6),
    )?;
    plot(
        "acf.png",
        "Height-difference autocorrelation ½⟨(h(x+r) − h(x))²⟩",
        "distance r (nm)",
        "A (nm²)",
        vec![
            ("along x (profiles)", pts(&s.acf_profile, 1e9, 1e18)),
            ("radial average (map)", pts(&s.acf_area, 1e9, 1e18)),
        ],
        cutoff.map(|l| l / 2.0 * 1e9),
    )?;
    plot(
        "slope.png",
        "RMS slope against scale",
        "scale λ (nm)",
        "RMS slope (1)",
        vec![
            ("along x (profiles)", pts(&s.slope_profile, 1e9, 1.0)),
            ("radial average (map)", pts(&s.slope_area, 1e9, 1.0)),
        ],
        cutoff.map(|l| l / 2.0 * 1e9),
    )?;
    plot(
        "curvature.png",
        "RMS curvature against scale",
        "scale λ = stencil length (nm)",
        "RMS curvature (1/µm)",
        vec![
            ("along x (profiles)", pts(&s.curvature_profile, 1e9, 1e-6)),
            ("radial average (map)", pts(&s.curvature_area, 1e9, 1e-6)),
        ],
        cutoff.map(|l| l * 1e9),
    )?;
    Ok(())
}

/// Height map, height and summit-height histograms, and the β scale sweep.
pub(super) fn write_figures(a: &SurfaceAnalysis, dir: &Path) -> Result<()> {
    let fm = a.final_map();
    let r = &a.report;
    let z = &fm.z;
    figures::heatmap_png(
        &dir.join("height_map.png"),
        z.view(),
        fm.dx,
        fm.dy,
        &format!("{} — σ = {:.3} nm", fm.channel, r.sigma * 1e9),
    )?;
    let h = &r.height_histogram;
    figures::histogram_png(
        &dir.join("height_histogram.png"),
        &h.edges,
        &h.density,
        &h.gaussian,
        1e9,
        "Height distribution",
        "height (nm)",
        "Gaussian, same σ",
    )?;
    let s = &r.summit_histogram;
    if r.n_summits > 0 && s.density.iter().any(|d| *d > 0.0) {
        figures::histogram_png(
            &dir.join("summit_height_histogram.png"),
            &s.edges,
            &s.density,
            &s.gaussian,
            1e9,
            &format!(
                "Summit heights ({} summits, {})",
                r.n_summits, r.summit_scheme
            ),
            "summit height (nm)",
            "Gaussian, same mean and σ_s",
        )?;
    }
    write_sweep_plot(&dir.join("scale_sweep.png"), &a.sweep, fm.dx.max(fm.dy))?;
    write_spectra_figures(a, dir)
}

/// β against the lateral scale it was measured at: the sampling interval (sub-sampling) or the
/// S-filter cutoff, with McCool's lower bound for a Gaussian surface (App. C's discussion).
pub(super) fn write_sweep_plot(path: &Path, sweep: &[SweepRow], pixel: f64) -> Result<()> {
    let series = |kind: &str, scale: f64| -> Vec<(f64, f64)> {
        sweep
            .iter()
            .filter(|r| r.kind == kind && r.beta > 0.0)
            .map(|r| {
                let x = if kind == "subsample" {
                    r.sampling_interval
                } else {
                    r.value * pixel
                };
                (x * scale, r.beta)
            })
            .collect()
    };
    let sub = series("subsample", 1e9);
    let filt = series("s_filter", 1e9);
    if sub.is_empty() && filt.is_empty() {
        return Ok(());
    }
    let xs = sub.iter().chain(&filt).map(|p| p.0);
    let (lo, hi) = xs.fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
    figures::lines_png(
        path,
        "β = σRη against lateral scale",
        "sampling interval or S-filter cutoff (nm)",
        "β",
        &[
            ("sub-sampling (x = sampling interval)", sub),
            ("S-filter (x = cutoff)", filt),
            ("McCool bound 0.0193", vec![(lo, 0.0193), (hi, 0.0193)]),
        ],
    )?;
    Ok(())
}

/// Per-area σ, R, η, β relative to their mean over areas, with ± one std and the 95 %
/// bootstrap interval of the mean.
pub(super) fn write_areas_plot(
    path: &Path,
    reports: &[&RoughnessReport],
    summaries: &[(&'static str, &'static str, Summary)],
) -> Result<()> {
    let names = ["σ", "R", "η", "β"];
    let rel = |k: usize, v: f64| v / summaries[k].2.mean - 1.0;
    let mut series: Vec<(String, Vec<f64>)> = reports
        .iter()
        .enumerate()
        .map(|(a, r)| {
            (
                format!("area {a}"),
                (0..4).map(|k| rel(k, (AREA_QUANTITIES[k].3)(r))).collect(),
            )
        })
        .collect();
    series.push((
        "95 % CI of the mean, low".into(),
        (0..4).map(|k| rel(k, summaries[k].2.ci_low)).collect(),
    ));
    series.push((
        "95 % CI of the mean, high".into(),
        (0..4).map(|k| rel(k, summaries[k].2.ci_high)).collect(),
    ));
    // The shaded band: ± the largest relative std of the four.
    let band = (0..4)
        .map(|k| (summaries[k].2.std / summaries[k].2.mean).abs())
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let refs: Vec<(&str, Vec<f64>)> = series
        .iter()
        .map(|(l, v)| (l.as_str(), v.clone()))
        .collect();
    figures::category_dots_png(
        path,
        "areas: value / mean − 1 (band: ± largest relative std)",
        "relative to the mean over areas",
        &names.iter().map(|s| s.to_string()).collect::<Vec<_>>(),
        &refs,
        band,
    )?;
    Ok(())
}
