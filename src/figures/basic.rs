//! The basic figures of the surface, DMW, contact, excitation and calibration stages: heat
//! map, histogram, named lines on linear, log–log and semi-log axes, stacked panels and
//! category dots. Degenerate input (no finite point, mismatched lengths) is an error, never a
//! panic.

use super::kit::{
    draw_legend, finite_min_max, font, line_key, log_padded, padded_abs, perr, render_png,
    sci_tick_label, title_font, Chart, DrawResult, Legend, Result, BASIC_PALETTE,
};
use ndarray::ArrayView2;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use std::path::Path;

/// Height map as a viridis heat map with a colour bar; axes in µm, colour in nm.
pub fn heatmap_png(path: &Path, z: ArrayView2<f64>, dx: f64, dy: f64, title: &str) -> Result<()> {
    heatmap_overlay_png(path, z, dx, dy, title, HEIGHT_NM, |_| Ok(()))
}

/// How a heat map's colour bar shows values: the factor from SI and the axis label.
#[derive(Debug, Clone, Copy)]
pub struct ColourScale {
    pub factor: f64,
    pub label: &'static str,
}

/// Heights in nm.
pub const HEIGHT_NM: ColourScale = ColourScale {
    factor: 1e9,
    label: "height (nm)",
};

/// A field (pressure, gap, …) as a viridis heat map, colour bar per `colour`; axes in µm.
pub fn field_png(
    path: &Path,
    z: ArrayView2<f64>,
    (dx, dy): (f64, f64),
    title: &str,
    colour: ColourScale,
) -> Result<()> {
    heatmap_overlay_png(path, z, dx, dy, title, colour, |_| Ok(()))
}

/// [`heatmap_png`] with `overlay` drawn on top, in the map's plot coordinates (µm; row 0 at
/// the top, so a row's plot y is the map height minus its y).
pub(crate) fn heatmap_overlay_png(
    path: &Path,
    z: ArrayView2<f64>,
    dx: f64,
    dy: f64,
    title: &str,
    colour: ColourScale,
    overlay: impl FnOnce(&mut Chart) -> DrawResult<()>,
) -> Result<()> {
    let (ny, nx) = z.dim();
    if nx == 0 || ny == 0 {
        return Err(perr(path, "empty map"));
    }
    let (lo, hi) = finite_min_max(z.iter().copied());
    let span = if hi > lo { hi - lo } else { 1.0 };
    // Decimate to at most 512 cells per axis: enough for a PNG, fast to draw.
    let step = nx.max(ny).div_ceil(512).max(1);
    let (w_um, h_um) = (nx as f64 * dx * 1e6, ny as f64 * dy * 1e6);
    render_png(path, (790, 640), |root| {
        let (main, bar) = root.split_horizontally(630);
        let mut chart = ChartBuilder::on(&main)
            .caption(title, title_font())
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(0.0..w_um, 0.0..h_um)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("x (µm)")
            .y_desc("y (µm)")
            .draw()?;
        let cells = (0..ny)
            .step_by(step)
            .flat_map(|j| (0..nx).step_by(step).map(move |i| (j, i)));
        chart.draw_series(cells.map(|(j, i)| {
            let v = z[[j, i]];
            let c = if v.is_finite() {
                ViridisRGB::get_color_normalized(v, lo, lo + span)
            } else {
                RGBColor(255, 255, 255)
            };
            // Row 0 is the top of the image.
            let x0 = i as f64 * dx * 1e6;
            let y1 = h_um - j as f64 * dy * 1e6;
            Rectangle::new(
                [
                    (x0, y1),
                    (x0 + step as f64 * dx * 1e6, y1 - step as f64 * dy * 1e6),
                ],
                c.filled(),
            )
        }))?;
        overlay(&mut chart)?;
        let lo_shown = lo * colour.factor;
        let hi_shown = (lo + span) * colour.factor;
        let mut cb = ChartBuilder::on(&bar)
            .margin_top(40)
            .margin_bottom(50)
            .margin_left(10)
            .margin_right(60)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..1.0, lo_shown..hi_shown)?;
        cb.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_labels(6)
            .label_style(font(14))
            .axis_desc_style(font(14))
            .y_desc(colour.label)
            .draw()?;
        let n = 100;
        cb.draw_series((0..n).map(|k| {
            let a = lo_shown + (hi_shown - lo_shown) * k as f64 / n as f64;
            let b = lo_shown + (hi_shown - lo_shown) * (k + 1) as f64 / n as f64;
            Rectangle::new(
                [(0.0, a), (1.0, b)],
                ViridisRGB::get_color_normalized(a, lo_shown, hi_shown).filled(),
            )
        }))?;
        Ok(())
    })
}

/// A histogram (bars of probability density) with an overlaid curve, e.g. the Gaussian of the
/// same mean and σ. `scale` converts x values for display (e.g. 1e9 for nm).
#[allow(clippy::too_many_arguments)]
pub fn histogram_png(
    path: &Path,
    edges: &[f64],
    density: &[f64],
    overlay: &[f64],
    scale: f64,
    title: &str,
    x_desc: &str,
    overlay_label: &str,
) -> Result<()> {
    if edges.len() != density.len() + 1 || density.is_empty() {
        return Err(perr(path, "histogram edges and densities do not match"));
    }
    let x0 = edges[0] * scale;
    let x1 = edges[edges.len() - 1] * scale;
    let ymax = density
        .iter()
        .chain(overlay)
        .map(|v| v / scale)
        .fold(0.0f64, f64::max)
        * 1.1;
    render_png(path, (760, 520), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, title_font())
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, 0.0..ymax.max(1e-30))?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(if scale == 1e9 {
                "probability density (1/nm)"
            } else {
                "probability density"
            })
            .draw()?;
        chart
            .draw_series(density.iter().enumerate().map(|(k, d)| {
                Rectangle::new(
                    [(edges[k] * scale, 0.0), (edges[k + 1] * scale, d / scale)],
                    BLUE.mix(0.35).filled(),
                )
            }))?
            .label("measured")
            .legend(|(x, y)| {
                Rectangle::new([(x, y - 5), (x + 15, y + 5)], BLUE.mix(0.35).filled())
            });
        if overlay.len() == density.len() {
            chart
                .draw_series(LineSeries::new(
                    overlay
                        .iter()
                        .enumerate()
                        .map(|(k, g)| (0.5 * (edges[k] + edges[k + 1]) * scale, g / scale)),
                    RED.stroke_width(2),
                ))?
                .label(overlay_label)
                .legend(line_key(15, RED.stroke_width(2)));
        }
        draw_legend(&mut chart, Legend::BASIC)?;
        Ok(())
    })
}

/// Several named (x, y) series on linear axes.
pub fn lines_png(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[(&str, Vec<(f64, f64)>)],
) -> Result<()> {
    let pts = series
        .iter()
        .flat_map(|(_, s)| s.iter())
        .filter(|(x, y)| x.is_finite() && y.is_finite());
    let (mut xr, mut yr) = (
        (f64::INFINITY, f64::NEG_INFINITY),
        (f64::INFINITY, f64::NEG_INFINITY),
    );
    for (x, y) in pts {
        xr = (xr.0.min(*x), xr.1.max(*x));
        yr = (yr.0.min(*y), yr.1.max(*y));
    }
    if !xr.0.is_finite() {
        return Err(perr(path, "no finite points to plot"));
    }
    render_png(path, (760, 520), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, title_font())
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(padded_abs(xr), padded_abs(yr))?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .draw()?;
        for (k, (label, s)) in series.iter().enumerate() {
            let c = BASIC_PALETTE[k % BASIC_PALETTE.len()];
            chart
                .draw_series(LineSeries::new(s.iter().copied(), c.stroke_width(2)))?
                .label(*label)
                .legend(line_key(15, c.stroke_width(2)));
        }
        draw_legend(&mut chart, Legend::BASIC)?;
        Ok(())
    })
}

/// Named (x, y) series on log–log axes (spectra), with optional marked points (peaks).
/// Non-positive values are dropped (they have no place on a log axis).
pub fn loglog_png(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[(&str, Vec<(f64, f64)>)],
    marks: &[(f64, f64)],
) -> Result<()> {
    let positive = |p: &&(f64, f64)| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite();
    let (mut xr, mut yr) = ((f64::INFINITY, 0.0f64), (f64::INFINITY, 0.0f64));
    for (x, y) in series.iter().flat_map(|(_, s)| s.iter()).filter(positive) {
        xr = (xr.0.min(*x), xr.1.max(*x));
        yr = (yr.0.min(*y), yr.1.max(*y));
    }
    if !xr.0.is_finite() {
        return Err(perr(path, "no positive points to plot"));
    }
    // Keep ten decades below the top at most: FFT leakage floors are not information.
    yr.0 = yr.0.max(yr.1 * 1e-10);
    let y_floor = yr.0;
    render_png(path, (760, 520), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, title_font())
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(
                log_padded(xr.0, xr.1, 1.3).log_scale(),
                log_padded(yr.0, yr.1, 1.3).log_scale(),
            )?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .y_label_formatter(&sci_tick_label)
            .draw()?;
        for (k, (label, s)) in series.iter().enumerate() {
            let c = BASIC_PALETTE[k % BASIC_PALETTE.len()];
            let pts: Vec<(f64, f64)> = s
                .iter()
                .filter(positive)
                .map(|&(x, y)| (x, y.max(y_floor)))
                .collect();
            chart
                .draw_series(LineSeries::new(pts, c.stroke_width(1)))?
                .label(*label)
                .legend(line_key(15, c.stroke_width(2)));
        }
        if !marks.is_empty() {
            chart
                .draw_series(
                    marks
                        .iter()
                        .filter(positive)
                        .map(|&(x, y)| Circle::new((x, y), 4, RED.stroke_width(2))),
                )?
                .label("peaks")
                .legend(|(x, y)| Circle::new((x + 7, y), 4, RED.stroke_width(2)));
        }
        draw_legend(&mut chart, Legend::BASIC)?;
        Ok(())
    })
}

/// Named (x, y) series on a linear x and a log y axis (contact curves against h/σ).
/// Non-positive y values are dropped.
pub fn semilogy_png(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[(&str, Vec<(f64, f64)>)],
    marks: &[(f64, f64)],
) -> Result<()> {
    let positive = |p: &&(f64, f64)| p.1 > 0.0 && p.0.is_finite() && p.1.is_finite();
    let (mut xr, mut yr) = ((f64::INFINITY, f64::NEG_INFINITY), (f64::INFINITY, 0.0f64));
    for (x, y) in series.iter().flat_map(|(_, s)| s.iter()).filter(positive) {
        xr = (xr.0.min(*x), xr.1.max(*x));
        yr = (yr.0.min(*y), yr.1.max(*y));
    }
    if !xr.0.is_finite() {
        return Err(perr(path, "no positive points to plot"));
    }
    // Keep twenty decades below the top at most: far tails are not information.
    yr.0 = yr.0.max(yr.1 * 1e-20);
    let y_floor = yr.0;
    render_png(path, (760, 520), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, title_font())
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(xr.0..xr.1, log_padded(yr.0, yr.1, 1.3).log_scale())?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .y_label_formatter(&sci_tick_label)
            .draw()?;
        for (k, (label, s)) in series.iter().enumerate() {
            let c = BASIC_PALETTE[k % BASIC_PALETTE.len()];
            let pts: Vec<(f64, f64)> = s
                .iter()
                .filter(positive)
                // Below the floor a log axis shows nothing meaningful: leave those points out.
                .filter(|p| p.1 >= y_floor)
                .copied()
                .collect();
            chart
                .draw_series(LineSeries::new(pts, c.stroke_width(1)))?
                .label(*label)
                .legend(line_key(15, c.stroke_width(2)));
        }
        if !marks.is_empty() {
            chart
                .draw_series(
                    marks
                        .iter()
                        .filter(positive)
                        .map(|&(x, y)| Circle::new((x, y), 4, RED.stroke_width(2))),
                )?
                .label("peaks")
                .legend(|(x, y)| Circle::new((x + 7, y), 4, RED.stroke_width(2)));
        }
        draw_legend(&mut chart, Legend::BASIC)?;
        Ok(())
    })
}

/// Series stacked in panels that share the x axis (time histories of several tracks), each
/// with its own y range; `shade` marks x intervals (e.g. filter edge transients) in grey.
pub fn stacked_png(
    path: &Path,
    title: &str,
    x_desc: &str,
    panels: &[(&str, Vec<(f64, f64)>)],
    shade: &[(f64, f64)],
) -> Result<()> {
    if panels.is_empty() {
        return Err(perr(path, "no panels to plot"));
    }
    let all: Vec<(f64, f64)> = panels.iter().flat_map(|(_, p)| p.iter().copied()).collect();
    let xr = finite_min_max(all.iter().map(|p| p.0));
    if !xr.0.is_finite() {
        return Err(perr(path, "no finite points to plot"));
    }
    let height = 140 + 170 * panels.len() as u32;
    render_png(path, (900, height), |root| {
        let root = root.titled(title, title_font())?;
        let areas = root.split_evenly((panels.len(), 1));
        for (k, ((label, pts), area)) in panels.iter().zip(areas.iter()).enumerate() {
            let mut yr = finite_min_max(pts.iter().map(|p| p.1));
            if !yr.0.is_finite() {
                yr = (-1.0, 1.0);
            }
            let pad = ((yr.1 - yr.0) * 0.05).max(1e-30);
            let mut chart = ChartBuilder::on(area)
                .margin(8)
                .x_label_area_size(if k + 1 == panels.len() { 35 } else { 20 })
                .y_label_area_size(70)
                .build_cartesian_2d(xr.0..xr.1, (yr.0 - pad)..(yr.1 + pad))?;
            let mut mesh = chart.configure_mesh();
            mesh.y_desc(*label);
            if k + 1 == panels.len() {
                mesh.x_desc(x_desc);
            }
            mesh.draw()?;
            chart.draw_series(shade.iter().map(|&(a, b)| {
                Rectangle::new([(a, yr.0 - pad), (b, yr.1 + pad)], BLACK.mix(0.08).filled())
            }))?;
            let c = BASIC_PALETTE[k % BASIC_PALETTE.len()];
            chart.draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(1)))?;
        }
        Ok(())
    })
}

/// One row per category (labels on the y axis), one marker per series on a shared x axis, with
/// a shaded band `[−band, band]` (normalised residuals against their tolerance band).
pub fn category_dots_png(
    path: &Path,
    title: &str,
    x_desc: &str,
    categories: &[String],
    series: &[(&str, Vec<f64>)],
    band: f64,
) -> Result<()> {
    let n = categories.len();
    if n == 0 {
        return Err(perr(path, "no categories to plot"));
    }
    let finite = series
        .iter()
        .flat_map(|(_, v)| v.iter())
        .filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((-band, band), |(a, b), v| (a.min(*v), b.max(*v)));
    let pad = 0.08 * (hi - lo).max(1e-12);
    // The first four colours of the basic palette, cycled.
    let palette = &BASIC_PALETTE[..4];
    let height = 120 + 36 * n as u32;
    render_png(path, (860, height), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, title_font())
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(220)
            .build_cartesian_2d((lo - pad)..(hi + pad), -0.5f64..(n as f64 - 0.5))?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_labels(n)
            .y_label_formatter(&|y| {
                let i = y.round();
                if (y - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < n {
                    categories[n - 1 - i as usize].clone()
                } else {
                    String::new()
                }
            })
            .disable_y_mesh()
            .draw()?;
        chart.draw_series(std::iter::once(Rectangle::new(
            [(-band, -0.5), (band, n as f64 - 0.5)],
            GREEN.mix(0.12).filled(),
        )))?;
        for (k, (label, values)) in series.iter().enumerate() {
            let c = palette[k % palette.len()];
            // Rows top-down in category order; series offset a little so markers do not hide.
            let dy = (k as f64 - 0.5 * (series.len() as f64 - 1.0)) * 0.18;
            chart
                .draw_series(
                    values
                        .iter()
                        .enumerate()
                        .filter(|(_, v)| v.is_finite())
                        .map(|(i, v)| Circle::new((*v, (n - 1 - i) as f64 + dy), 6, c.filled())),
                )?
                .label(*label)
                .legend(move |(x, y)| Circle::new((x + 7, y), 5, c.filled()));
        }
        let legend = Legend {
            position: Some(SeriesLabelPosition::LowerRight),
            ..Legend::BASIC
        };
        draw_legend(&mut chart, legend)?;
        Ok(())
    })
}
