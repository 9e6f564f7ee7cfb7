//! PNG plots of the design-of-experiments stage, the analogues of the dissertation's
//! Figs 2.26–2.30: response-surface contour maps side by side (one panel per level of a third
//! factor, Figs 2.26–2.28), the residual diagnostics of the fitted surface (Fig. 2.29) and the
//! simulated-annealing history of the optimisation (Fig. 2.30).
//!
//! Drawn with the plotting kit (iso-lines by [`crate::figures::marching_squares`]) and the
//! conventions of the sweep figures: plots are side outputs, so degenerate data — NaN cells, a
//! constant or all-NaN surface, empty series — still gives a valid PNG, with "no data" where
//! nothing can be drawn. Only a broken contract (mismatched shapes or lengths, an unsorted
//! grid) or a failure to draw or write is an error.

use super::kit::contour::{bilinear, contour_levels, locate, marching_squares, refine};
use super::kit::{
    dashed_line, decimate_minmax, draw_legend, draw_no_data, draw_polyline, finite_runs, fmt_sig3,
    font, lin_tick_label, line_key, log_padded, note_layout, perr, polyline_elements, render_png,
    sci_tick_label, text_style, title_font, usable, Area, Chart, DrawResult, Extent, Legend,
    Result, MARKER_RED, PALETTE,
};
use ndarray::Array2;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::ops::Range;
use std::path::Path;

/// One panel of [`contour_panels_png`]: a surface sampled on a rectangular grid.
#[derive(Debug, Clone, PartialEq)]
pub struct ContourPanel<'a> {
    /// Panel caption, e.g. "a_TFC = 3 µm".
    pub title: &'a str,
    /// Axis descriptions, e.g. "w_TFC (µm)".
    pub x_desc: &'a str,
    pub y_desc: &'a str,
    /// Grid x values, strictly increasing, length nx.
    pub x: Vec<f64>,
    /// Grid y values, strictly increasing, length ny.
    pub y: Vec<f64>,
    /// Values, shape (ny, nx): `z[[j, i]]` belongs to `(x[i], y[j])`. NaN = no value.
    pub z: Array2<f64>,
    /// Design points, drawn as small black dots.
    pub points: Vec<(f64, f64)>,
    /// An optimum, drawn as a red star.
    pub marker: Option<(f64, f64)>,
}

/// Coarse grids are refined bilinearly to about this many nodes per axis before marching
/// squares, so that the iso-lines follow the bilinear surface the colour fill shows.
const REFINE_NODES: usize = 121;
/// Pixel size of one contour panel, and the width of the colour-bar column.
const PANEL_SIZE: (u32, u32) = (400, 370);
const BAR_WIDTH: u32 = 130;
const MAX_PANEL_COLUMNS: usize = 3;
/// Long annealing histories (the current J is noisy) are drawn as min/max envelopes.
const ANNEALING_COLUMNS: usize = 1000;

/// The shared colour scale: bands between consecutive levels, each in the viridis colour of
/// its middle, so that the fill changes colour exactly at the drawn iso-lines (as MATLAB's
/// contourf).
struct ColourScale {
    lo: f64,
    hi: f64,
    levels: Vec<f64>,
    colours: Vec<RGBColor>,
}

impl ColourScale {
    fn new(lo: f64, hi: f64) -> Self {
        let levels = contour_levels(lo, hi);
        let edges: Vec<f64> = std::iter::once(lo)
            .chain(levels.iter().copied())
            .chain(std::iter::once(hi))
            .collect();
        let colours = edges
            .windows(2)
            .map(|w| {
                let f = if hi > lo {
                    (0.5 * (w[0] + w[1]) - lo) / (hi - lo)
                } else {
                    0.5
                };
                ViridisRGB::get_color_normalized(f, 0.0, 1.0)
            })
            .collect();
        ColourScale {
            lo,
            hi,
            levels,
            colours,
        }
    }

    /// Colour of the band holding `v` (a value equal to a level belongs to the band above,
    /// as a node equal to the level is inside in [`marching_squares`]).
    fn colour(&self, v: f64) -> RGBColor {
        self.colours[self.levels.partition_point(|&l| l <= v)]
    }

    /// `(from, to, colour)` of every band.
    fn bands(&self) -> Vec<(f64, f64, RGBColor)> {
        let edges: Vec<f64> = std::iter::once(self.lo)
            .chain(self.levels.iter().copied())
            .chain(std::iter::once(self.hi))
            .collect();
        edges
            .windows(2)
            .zip(&self.colours)
            .map(|(w, &c)| (w[0], w[1], c))
            .collect()
    }
}

/// Axis range of grid values: the grid itself, or padded around a single value.
fn grid_range(g: &[f64]) -> Range<f64> {
    match g {
        [] => 0.0..1.0,
        [a, .., b] if b > a => *a..*b,
        _ => {
            let mut e = Extent::new();
            g.iter().for_each(|&v| e.add(v));
            e.range(0.0, 0.0, 0.0..1.0)
        }
    }
}

/// Whether `p` lies in the plotted rectangle (with a little slack for points on its edge).
fn in_view(p: (f64, f64), xr: &Range<f64>, yr: &Range<f64>) -> bool {
    let (sx, sy) = (1e-9 * (xr.end - xr.start), 1e-9 * (yr.end - yr.start));
    usable(p.0)
        && usable(p.1)
        && p.0 >= xr.start - sx
        && p.0 <= xr.end + sx
        && p.1 >= yr.start - sy
        && p.1 <= yr.end + sy
}

/// Outline of a five-pointed star of outer radius `r` pixels, centred on the origin.
fn star(r: f64) -> Vec<(i32, i32)> {
    (0..10)
        .map(|k| {
            let a = -std::f64::consts::FRAC_PI_2 + k as f64 * std::f64::consts::PI / 5.0;
            let rr = if k % 2 == 0 { r } else { 0.45 * r };
            ((rr * a.cos()).round() as i32, (rr * a.sin()).round() as i32)
        })
        .collect()
}

/// A design point: a black dot on a white ring, visible on dark and light colours alike.
fn draw_design_dot<CT: CoordTranslate>(
    area: &DrawingArea<BitMapBackend<'_>, CT>,
    at: CT::From,
) -> DrawResult<()> {
    area.draw(
        &(EmptyElement::at(at)
            + Circle::new((0, 0), 4, WHITE.filled())
            + Circle::new((0, 0), 3, BLACK.filled())),
    )?;
    Ok(())
}

/// The optimum: a red star with a black outline.
fn draw_optimum_star<CT: CoordTranslate>(
    area: &DrawingArea<BitMapBackend<'_>, CT>,
    at: CT::From,
) -> DrawResult<()> {
    let outline = star(9.0);
    let mut closed = outline.clone();
    closed.push(outline[0]);
    area.draw(
        &(EmptyElement::at(at)
            + Polygon::new(outline, MARKER_RED.filled())
            + PathElement::new(closed, BLACK.stroke_width(1))),
    )?;
    Ok(())
}

/// The chart of one contour panel, captioned, on the grid's extent (mesh drawn later, over
/// the fill).
fn contour_chart<'a, 'b: 'a>(
    area: &'a Area<'b>,
    panel: &ContourPanel,
    xr: Range<f64>,
    yr: Range<f64>,
) -> DrawResult<Chart<'a, 'b>> {
    let chart = ChartBuilder::on(area)
        .caption(panel.title, font(16))
        .margin(8)
        .margin_right(16)
        .x_label_area_size(42)
        .y_label_area_size(58)
        .build_cartesian_2d(xr.clone(), yr.clone())?;
    note_layout(&chart, xr, yr, (false, false));
    Ok(chart)
}

/// Axes and tick labels without grid lines (they would clutter the colour map).
fn draw_mesh(chart: &mut Chart, x_desc: &str, y_desc: &str) -> DrawResult<()> {
    let (xr, yr) = (chart.x_range(), chart.y_range());
    let (xs, ys) = (xr.end - xr.start, yr.end - yr.start);
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(6)
        .y_labels(6)
        .x_label_formatter(&|v| lin_tick_label(*v, xs))
        .y_label_formatter(&|v| lin_tick_label(*v, ys))
        .x_desc(x_desc)
        .y_desc(y_desc)
        .label_style(font(13))
        .axis_desc_style(font(14))
        .draw()?;
    Ok(())
}

/// One contour panel: the banded fill pixel by pixel (bilinear between grid nodes), the
/// iso-lines (zero bold), then the design points and the optimum on top.
fn draw_contour_panel(
    area: &Area,
    panel: &ContourPanel,
    scale: Option<&ColourScale>,
) -> DrawResult<()> {
    let (xr, yr) = (grid_range(&panel.x), grid_range(&panel.y));
    let mut chart = contour_chart(area, panel, xr.clone(), yr.clone())?;
    let z = panel.z.view();
    let has_data = z.iter().any(|&v| usable(v));
    if let (Some(scale), true) = (scale, has_data) {
        let plot = chart.plotting_area().strip_coord_spec();
        let (w, h) = plot.dim_in_pixel();
        let cols: Vec<_> = (0..w)
            .map(|px| {
                let v = xr.start + (px as f64 + 0.5) / w as f64 * (xr.end - xr.start);
                locate(&panel.x, v)
            })
            .collect();
        for py in 0..h {
            let v = yr.end - (py as f64 + 0.5) / h as f64 * (yr.end - yr.start);
            let row = locate(&panel.y, v);
            for (px, &col) in cols.iter().enumerate() {
                let value = bilinear(&z, col, row);
                if value.is_finite() {
                    plot.draw_pixel((px as i32, py as i32), &scale.colour(value))?;
                }
            }
        }
        // Iso-lines on a bilinearly refined grid: they then bound the fill's bands exactly.
        let (rx, ry) = (
            refine(&panel.x, REFINE_NODES),
            refine(&panel.y, REFINE_NODES),
        );
        let (lx, ly): (Vec<_>, Vec<_>) = (
            rx.iter().map(|&v| locate(&panel.x, v)).collect(),
            ry.iter().map(|&v| locate(&panel.y, v)).collect(),
        );
        let rz = Array2::from_shape_fn((ry.len(), rx.len()), |(j, i)| bilinear(&z, lx[i], ly[j]));
        // Zero last, so that the bold line lies on top.
        let mut levels = scale.levels.clone();
        levels.sort_by_key(|&l| l == 0.0);
        for level in levels {
            let style = if level == 0.0 {
                BLACK.stroke_width(3)
            } else {
                BLACK.mix(0.55).stroke_width(1)
            };
            for line in marching_squares(&rx, &ry, rz.view(), level) {
                draw_polyline(&mut chart, &line, style)?;
            }
        }
    }
    draw_mesh(&mut chart, panel.x_desc, panel.y_desc)?;
    for &p in panel.points.iter().filter(|&&p| in_view(p, &xr, &yr)) {
        draw_design_dot(chart.plotting_area(), p)?;
    }
    if let Some(m) = panel.marker.filter(|&m| in_view(m, &xr, &yr)) {
        draw_optimum_star(chart.plotting_area(), m)?;
    }
    if !has_data {
        draw_no_data(&mut chart)?;
    }
    Ok(())
}

/// The colour bar: the bands of the shared scale, thin lines at the levels, a bold one at 0.
fn draw_colour_bar(area: &Area, z_desc: &str, scale: &ColourScale) -> DrawResult<()> {
    let mut e = Extent::new();
    e.add(scale.lo);
    e.add(scale.hi);
    let yr = e.range(0.0, 0.0, 0.0..1.0);
    let span = yr.end - yr.start;
    let mut cb = ChartBuilder::on(area)
        .margin_top(45)
        .margin_bottom(55)
        .margin_left(4)
        .margin_right(40)
        .y_label_area_size(62)
        .build_cartesian_2d(0.0..1.0, yr.clone())?;
    let bands = scale.bands();
    // A constant surface is one band over the padded range.
    let rects: Vec<(f64, f64, RGBColor)> = if scale.hi > scale.lo {
        bands
    } else {
        vec![(yr.start, yr.end, scale.colours[0])]
    };
    cb.draw_series(
        rects
            .into_iter()
            .map(|(a, b, c)| Rectangle::new([(0.0, a), (1.0, b)], c.filled())),
    )?;
    cb.draw_series(scale.levels.iter().map(|&l| {
        let style = if l == 0.0 {
            BLACK.stroke_width(3)
        } else {
            BLACK.mix(0.55).stroke_width(1)
        };
        PathElement::new(vec![(0.0, l), (1.0, l)], style)
    }))?;
    cb.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_labels(8)
        .y_label_formatter(&|v| lin_tick_label(*v, span))
        .label_style(font(13))
        .axis_desc_style(font(15))
        .y_desc(z_desc)
        .draw()?;
    Ok(())
}

/// Legend for the markers, under the colour bar (the panels stay uncovered).
fn draw_marker_legend(area: &Area, points: bool, marker: bool) -> DrawResult<()> {
    let (_, h) = area.dim_in_pixel();
    let style = text_style(13, Pos::new(HPos::Left, VPos::Center));
    let mut y = h as i32 - 45;
    if points {
        draw_design_dot(area, (14, y))?;
        area.draw(&Text::new("design points", (28, y), style.clone()))?;
        y += 22;
    }
    if marker {
        draw_optimum_star(area, (14, y))?;
        area.draw(&Text::new("optimum", (28, y), style))?;
    }
    Ok(())
}

/// Contour maps side by side (up to three per row, more rows as needed), Figs 2.26–2.28:
/// each panel's surface as a filled colour map on ONE colour scale shared by all panels (so
/// colours compare across panels), with a colour bar labelled `z_desc` (e.g. "ξ"); iso-lines
/// at about ten nice levels, twice as dense below zero, and the zero level bold black; the
/// design points as black dots and the optimum, if any, as a red star. The fill is the
/// bilinear interpolant of the grid, banded between the levels; cells with a NaN corner stay
/// white. A panel without finite values says "no data".
///
/// Errors: `z` not of shape `(y.len(), x.len())`, or grid values not finite and strictly
/// increasing.
pub fn contour_panels_png(
    path: &Path,
    title: &str,
    z_desc: &str,
    panels: &[ContourPanel],
) -> Result<()> {
    for (k, p) in panels.iter().enumerate() {
        if p.z.dim() != (p.y.len(), p.x.len()) {
            return Err(perr(
                path,
                format!(
                    "contour panel {k}: z has shape {:?}, the grid is {} × {} (y × x)",
                    p.z.dim(),
                    p.y.len(),
                    p.x.len()
                ),
            ));
        }
        let sorted = |g: &[f64]| g.iter().all(|&v| usable(v)) && g.windows(2).all(|w| w[1] > w[0]);
        if !(sorted(&p.x) && sorted(&p.y)) {
            return Err(perr(
                path,
                format!("contour panel {k}: grid values must be finite and increasing"),
            ));
        }
    }
    let mut e = Extent::new();
    panels
        .iter()
        .flat_map(|p| p.z.iter())
        .for_each(|&v| e.add(v));
    let scale = (!e.is_empty()).then(|| ColourScale::new(e.lo, e.hi));
    let n = panels.len().max(1);
    let ncol = n.min(MAX_PANEL_COLUMNS);
    let nrow = n.div_ceil(ncol);
    let size = (
        ncol as u32 * PANEL_SIZE.0 + BAR_WIDTH,
        45 + nrow as u32 * PANEL_SIZE.1,
    );
    let points = panels.iter().any(|p| !p.points.is_empty());
    let marker = panels.iter().any(|p| p.marker.is_some());
    render_png(path, size, |root| {
        let root = root.titled(title, title_font())?;
        let (grid, bar) = root.split_horizontally(ncol as u32 * PANEL_SIZE.0);
        let areas = grid.split_evenly((nrow, ncol));
        if panels.is_empty() {
            let empty = ContourPanel {
                title: "",
                x_desc: "",
                y_desc: "",
                x: Vec::new(),
                y: Vec::new(),
                z: Array2::zeros((0, 0)),
                points: Vec::new(),
                marker: None,
            };
            draw_contour_panel(&areas[0], &empty, None)?;
        }
        for (panel, area) in panels.iter().zip(&areas) {
            draw_contour_panel(area, panel, scale.as_ref())?;
        }
        let legend_h = 22 * (points as u32 + marker as u32) + if points || marker { 20 } else { 0 };
        let (_, bar_h) = bar.dim_in_pixel();
        let (bar_top, legend) = bar.split_vertically(bar_h.saturating_sub(legend_h));
        if let Some(scale) = &scale {
            draw_colour_bar(&bar_top, z_desc, scale)?;
        }
        if points || marker {
            draw_marker_legend(&legend, points, marker)?;
        }
        Ok(())
    })
}

/// Scatter of points in PALETTE blue; nothing for an empty slice.
fn draw_scatter(chart: &mut Chart, pts: &[(f64, f64)]) -> DrawResult<()> {
    let c = PALETTE[0];
    chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, c.mix(0.85).filled())))?;
    Ok(())
}

/// A chart on linear axes with a light grid and its mesh drawn; no caption when `caption` is
/// empty (so that it takes no room).
fn linear_chart<'a, 'b: 'a>(
    area: &'a Area<'b>,
    caption: &str,
    xr: Range<f64>,
    yr: Range<f64>,
    x_desc: &str,
    y_desc: &str,
) -> DrawResult<Chart<'a, 'b>> {
    let mut builder = ChartBuilder::on(area);
    if !caption.is_empty() {
        builder.caption(caption, font(16));
    }
    let mut chart = builder
        .margin(10)
        .margin_right(18)
        .x_label_area_size(45)
        .y_label_area_size(62)
        .build_cartesian_2d(xr.clone(), yr.clone())?;
    note_layout(&chart, xr.clone(), yr.clone(), (false, false));
    let (xs, ys) = (xr.end - xr.start, yr.end - yr.start);
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_label_formatter(&|v| lin_tick_label(*v, xs))
        .y_label_formatter(&|v| lin_tick_label(*v, ys))
        .light_line_style(BLACK.mix(0.05))
        .bold_line_style(BLACK.mix(0.12))
        .label_style(font(13))
        .axis_desc_style(font(14))
        .draw()?;
    Ok(chart)
}

/// Residual diagnostics of a fitted response surface, Fig. 2.29, two panels: residual
/// against fitted value with a dashed zero line (a pattern means the model misses a term),
/// and a normal probability plot — theoretical normal quantile (x) against standardized
/// residual (y) with the reference line y = x on equal axes (departures mean non-normal
/// residuals, so the fit's confidence statements are doubtful). Non-finite points are
/// skipped; an empty panel says "no data".
pub fn residual_panels_png(
    path: &Path,
    title: &str,
    fitted_residual: &[(f64, f64)],
    normal_quantiles: &[(f64, f64)],
) -> Result<()> {
    let clean = |pts: &[(f64, f64)]| -> Vec<(f64, f64)> {
        pts.iter()
            .copied()
            .filter(|&(a, b)| usable(a) && usable(b))
            .collect()
    };
    let (fr, nq) = (clean(fitted_residual), clean(normal_quantiles));
    // Residuals: symmetric about zero, so that a bias shows.
    let (mut xe, mut ye) = (Extent::new(), Extent::new());
    ye.add(0.0);
    for &(f, r) in &fr {
        xe.add(f);
        ye.add(r);
        ye.add(-r);
    }
    let (xr1, yr1) = (
        xe.range(0.05, 0.0, 0.0..1.0),
        ye.range(0.08, 0.0, -1.0..1.0),
    );
    // Probability plot: one range for both axes, so that y = x is the diagonal.
    let mut qe = Extent::new();
    for &(a, b) in &nq {
        qe.add(a);
        qe.add(b);
    }
    let qr = qe.range(0.05, 0.0, -3.0..3.0);
    render_png(path, (1100, 520), |root| {
        let root = root.titled(title, title_font())?;
        let (left, right) = root.split_horizontally(550);
        let mut chart = linear_chart(
            &left,
            "residuals vs fitted",
            xr1.clone(),
            yr1,
            "fitted value",
            "residual",
        )?;
        chart.draw_series(dashed_line(vec![(xr1.start, 0.0), (xr1.end, 0.0)]))?;
        draw_scatter(&mut chart, &fr)?;
        if fr.is_empty() {
            draw_no_data(&mut chart)?;
        }
        let mut chart = linear_chart(
            &right,
            "normal probability plot",
            qr.clone(),
            qr.clone(),
            "theoretical normal quantile",
            "standardized residual",
        )?;
        let c = PALETTE[1];
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(qr.start, qr.start), (qr.end, qr.end)],
                c.stroke_width(2),
            )))?
            .label("y = x")
            .legend(line_key(20, c.stroke_width(2)));
        draw_scatter(&mut chart, &nq)?;
        if nq.is_empty() {
            draw_no_data(&mut chart)?;
        }
        draw_legend(&mut chart, Legend::at(SeriesLabelPosition::UpperLeft, 14))?;
        Ok(())
    })
}

/// The objective panel of [`annealing_png`].
fn draw_objective(
    area: &Area,
    iterations: &[(f64, f64, f64)],
    xr: Range<f64>,
    x_desc: &str,
) -> DrawResult<()> {
    let current: Vec<(f64, f64)> = iterations.iter().map(|&(i, c, _)| (i, c)).collect();
    let best: Vec<(f64, f64)> = iterations.iter().map(|&(i, _, b)| (i, b)).collect();
    let mut ye = Extent::new();
    for &(i, c, b) in iterations {
        if usable(i) {
            ye.add(c);
            ye.add(b);
        }
    }
    let yr = ye.range(0.05, 0.0, 0.0..1.0);
    let mut chart = linear_chart(area, "", xr.clone(), yr, x_desc, "objective J")?;
    let best_value = best
        .iter()
        .filter(|&&(i, b)| usable(i) && usable(b))
        .map(|p| p.1)
        .fold(f64::INFINITY, f64::min);
    /// Points, colour, line width, legend label.
    type Styled<'a> = (&'a [(f64, f64)], RGBColor, u32, String);
    let series: [Styled; 2] = [
        (&current, PALETTE[0], 1, "current J".to_string()),
        (
            &best,
            PALETTE[1],
            2,
            format!("best J (lowest {})", fmt_sig3(best_value)),
        ),
    ];
    for (pts, c, width, label) in series {
        let mut labelled = false;
        for run in finite_runs(pts) {
            let line = decimate_minmax(run, xr.start, xr.end, ANNEALING_COLUMNS);
            let drawn = chart.draw_series(polyline_elements(&line, c.stroke_width(width)))?;
            if !labelled {
                labelled = true;
                drawn
                    .label(label.as_str())
                    .legend(line_key(20, c.stroke_width(2)));
            }
        }
    }
    if ye.is_empty() {
        draw_no_data(&mut chart)?;
    } else {
        draw_legend(&mut chart, Legend::at(SeriesLabelPosition::UpperRight, 14))?;
    }
    Ok(())
}

/// The temperature panel of [`annealing_png`], on a log axis (the cooling schedule is
/// geometric, and reannealing shows as jumps).
fn draw_temperature(
    area: &Area,
    iterations: &[(f64, f64, f64)],
    temperature: &[f64],
    xr: Range<f64>,
) -> DrawResult<()> {
    let positive = |(i, t): (f64, f64)| usable(i) && usable(t) && t > 0.0;
    let pts: Vec<(f64, f64)> = iterations
        .iter()
        .zip(temperature)
        .map(|(&(i, _, _), &t)| (i, t))
        .collect();
    let mut te = Extent::new();
    pts.iter()
        .filter(|&&p| positive(p))
        .for_each(|p| te.add(p.1));
    if te.is_empty() {
        let mut chart = linear_chart(area, "", xr, 0.0..1.0, "iteration", "temperature")?;
        return draw_no_data(&mut chart);
    }
    let yr = log_padded(te.lo, te.hi, 1.3);
    let mut chart = ChartBuilder::on(area)
        .margin(10)
        .margin_right(18)
        .x_label_area_size(45)
        .y_label_area_size(62)
        .build_cartesian_2d(xr.clone(), yr.clone().log_scale())?;
    note_layout(&chart, xr.clone(), yr, (false, true));
    let xs = xr.end - xr.start;
    chart
        .configure_mesh()
        .x_desc("iteration")
        .y_desc("temperature")
        .x_label_formatter(&|v| lin_tick_label(*v, xs))
        .y_label_formatter(&sci_tick_label)
        .light_line_style(BLACK.mix(0.05))
        .bold_line_style(BLACK.mix(0.12))
        .label_style(font(13))
        .axis_desc_style(font(14))
        .draw()?;
    let c = PALETTE[2];
    for run in pts.split(|&p| !positive(p)).filter(|r| !r.is_empty()) {
        let line = decimate_minmax(run, xr.start, xr.end, ANNEALING_COLUMNS);
        chart.draw_series(LineSeries::new(line, c.stroke_width(1)))?;
    }
    Ok(())
}

/// Simulated-annealing history, Fig. 2.30 (as MATLAB's simulannealbnd plots it): the
/// current and the best objective J against the iteration, `iterations` holding
/// `(iteration, current J, best J)`. The legend gives the lowest best J. With `temperature`
/// (one value per iteration; the cooling schedule, which explains when the current J stops
/// wandering) a second panel below shows it on a log axis; non-positive temperatures are
/// skipped there. Non-finite values break the lines; long histories are drawn as min/max
/// envelopes. Errors: a temperature slice of another length than `iterations`.
pub fn annealing_png(
    path: &Path,
    title: &str,
    iterations: &[(f64, f64, f64)],
    temperature: Option<&[f64]>,
) -> Result<()> {
    if let Some(t) = temperature {
        if t.len() != iterations.len() {
            return Err(perr(
                path,
                format!(
                    "annealing: {} temperatures for {} iterations",
                    t.len(),
                    iterations.len()
                ),
            ));
        }
    }
    let mut xe = Extent::new();
    for &(i, c, b) in iterations {
        if usable(c) || usable(b) || temperature.is_some() {
            xe.add(i);
        }
    }
    let xr = xe.range(0.02, 0.0, 0.0..1.0);
    let height = if temperature.is_some() { 760 } else { 540 };
    render_png(path, (900, height), |root| {
        let root = root.titled(title, title_font())?;
        match temperature {
            None => draw_objective(&root, iterations, xr.clone(), "iteration"),
            Some(t) => {
                let (_, h) = root.dim_in_pixel();
                let (top, bottom) = root.split_vertically((h as f64 * 0.6) as u32);
                draw_objective(&top, iterations, xr.clone(), "iteration")?;
                draw_temperature(&bottom, iterations, t, xr.clone())
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::figures::kit::contour::tests::{grid, surface};
    use crate::figures::kit::testing::{
        drawn, near, over_white, tinted, viridis_value, Image, WHITE_PX,
    };
    use crate::figures::kit::ChartLayout;

    /// The fill's colours follow the values: on the one shared scale, wherever `z` is higher
    /// by more than a band, the fill is higher on the viridis map — across panels too.
    /// `samples` are `(layout, (x, y), z)`; pixels on iso-lines (not viridis) are skipped.
    fn assert_fill_follows(img: &Image, samples: &[(ChartLayout, (f64, f64), f64)], band: f64) {
        let seen: Vec<(f64, f64)> = samples
            .iter()
            .filter_map(|(l, at, z)| {
                let p = img.at(l.pixel(*at).0, l.pixel(*at).1).unwrap();
                Some((*z, viridis_value(p, 3)?))
            })
            .collect();
        assert!(
            seen.len() * 10 >= samples.len() * 8,
            "{} of {}",
            seen.len(),
            samples.len()
        );
        for &(za, la) in &seen {
            for &(zb, lb) in &seen {
                if za > zb + band {
                    assert!(la > lb, "z {za} (viridis {la}) vs z {zb} ({lb})");
                }
            }
        }
    }

    /// The degree to which pixels near `at` are of colour `c` (any within `r` px).
    fn has(img: &Image, l: &ChartLayout, at: (f64, f64), r: i32, c: RGBColor) -> bool {
        img.any_near(l.pixel(at), r, |p| near(p, c, 30))
    }

    fn saddle_panels(n: usize) -> Vec<ContourPanel<'static>> {
        let x = grid(-1.0, 1.0, n);
        let y = grid(-1.0, 1.0, n);
        let titles = ["a_TFC = 2 µm", "a_TFC = 3 µm", "a_TFC = 4 µm"];
        titles
            .iter()
            .enumerate()
            .map(|(k, &title)| {
                let shift = 0.3 * (k as f64 - 1.0);
                ContourPanel {
                    title,
                    x_desc: "w_TFC (µm)",
                    y_desc: "h_TFC (nm)",
                    x: x.clone(),
                    y: y.clone(),
                    z: surface(&x, &y, |a, b| a * a - b * b + shift),
                    points: [-1.0, 0.0, 1.0]
                        .iter()
                        .flat_map(|&a| [-1.0, 0.0, 1.0].map(|b| (a, b)))
                        .collect(),
                    marker: (k == 1).then_some((0.0, 0.8)),
                }
            })
            .collect()
    }

    #[test]
    fn contour_panels_normal_and_degenerate() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("saddle.png");
        let panels = saddle_panels(41);
        let (img, l) = drawn(&p, || {
            contour_panels_png(&p, "ξ over the design space", "ξ", &panels)
        });
        assert_eq!(l.len(), 3);
        let mut samples = Vec::new();
        for (k, layout) in l.iter().enumerate() {
            let shift = 0.3 * (k as f64 - 1.0);
            for i in 0..9 {
                for j in 0..9 {
                    let (a, b) = (-0.84 + 0.21 * i as f64, -0.84 + 0.21 * j as f64);
                    samples.push((*layout, (a, b), a * a - b * b + shift));
                }
            }
            // The design point in the middle is a black dot.
            assert!(has(&img, layout, (0.0, 0.0), 1, BLACK), "panel {k}");
            // The bold zero iso-line: x² − y² = −shift.
            let zero = (0.49 - shift).sqrt();
            assert!(
                has(&img, layout, (zero, 0.7), 2, BLACK),
                "panel {k}: zero line"
            );
            assert!(
                !has(&img, layout, (zero, 0.3), 2, BLACK),
                "panel {k}: zero line"
            );
            // The optimum's red star only where the panel has one.
            assert_eq!(
                has(&img, layout, (0.0, 0.8), 3, MARKER_RED),
                k == 1,
                "panel {k}: optimum"
            );
        }
        // Values span −1.3…1.3 on about ten levels.
        assert_fill_follows(&img, &samples, 0.35);

        let nan = f64::NAN;
        let base = |z: Array2<f64>| ContourPanel {
            title: "t",
            x_desc: "x",
            y_desc: "y",
            x: grid(0.0, 1.0, z.ncols().max(1)),
            y: grid(0.0, 1.0, z.nrows().max(1)),
            z,
            points: vec![(0.5, 0.5), (nan, 0.0), (7.0, 7.0)],
            marker: Some((1.0, 1.0)),
        };
        let mut holed = surface(&grid(0.0, 1.0, 9), &grid(0.0, 1.0, 9), |a, b| a - b);
        holed.slice_mut(ndarray::s![2..5, 3..7]).fill(nan);
        let mut single = base(Array2::from_elem((1, 1), 2.0));
        single.x = vec![0.5];
        single.y = vec![3.0];
        let cases: Vec<(&str, Vec<ContourPanel>)> = vec![
            ("no-panels", vec![]),
            (
                "tiny",
                vec![base(
                    Array2::from_shape_vec((2, 2), vec![-1.0, 0.5, 0.2, 1.0]).unwrap(),
                )],
            ),
            ("holed", vec![base(holed.clone())]),
            ("constant", vec![base(Array2::from_elem((5, 4), 3.0))]),
            (
                "all-nan",
                vec![
                    base(Array2::from_elem((5, 4), nan)),
                    base(Array2::from_elem((2, 2), nan)),
                ],
            ),
            (
                "some-nan-panels",
                vec![base(Array2::from_elem((5, 4), nan)), base(holed), single],
            ),
        ];
        for (name, panels) in &cases {
            let p = dir.path().join(format!("contour-{name}.png"));
            let (img, l) = drawn(&p, || contour_panels_png(&p, name, "ξ", panels));
            assert_eq!(l.len(), panels.len().max(1), "{name}");
            let colour_at = |k: usize, at: (f64, f64)| {
                let (x, y) = l[k].pixel(at);
                img.at(x, y).unwrap()
            };
            match *name {
                // Cells with a NaN corner stay white, the others are filled.
                "holed" => {
                    assert_eq!(colour_at(0, (0.6, 0.3)), WHITE_PX);
                    assert_ne!(colour_at(0, (0.1, 0.9)), WHITE_PX);
                }
                // One band: one colour everywhere.
                "constant" => {
                    let c = colour_at(0, (0.2, 0.2));
                    assert_ne!(c, WHITE_PX);
                    for at in [(0.8, 0.2), (0.2, 0.8), (0.7, 0.7)] {
                        assert_eq!(colour_at(0, at), c, "{at:?}");
                    }
                }
                "all-nan" => {
                    for k in 0..2 {
                        assert_eq!(colour_at(k, (0.2, 0.8)), WHITE_PX);
                    }
                }
                "some-nan-panels" => {
                    assert_eq!(colour_at(0, (0.2, 0.8)), WHITE_PX);
                    assert_ne!(colour_at(1, (0.1, 0.9)), WHITE_PX);
                    // The single node (0.5, 3) fills its small padded extent.
                    assert_ne!(colour_at(2, (0.5, 3.0)), WHITE_PX);
                }
                _ => {}
            }
        }
        // Seven panels: three rows of up to three.
        let mut many = saddle_panels(5);
        many.extend(saddle_panels(3));
        many.push(saddle_panels(2).remove(0));
        let p = dir.path().join("contour-many.png");
        let (_, l) = drawn(&p, || contour_panels_png(&p, "many", "ξ", &many));
        assert_eq!(l.len(), 7);
        let row_of = |k: usize| l[k].plot.1;
        assert!(row_of(0) == row_of(2) && row_of(2) < row_of(3));
        assert!(row_of(3) == row_of(5) && row_of(5) < row_of(6));
        assert!(l[0].plot.0 < l[1].plot.0 && l[1].plot.0 < l[2].plot.0);
    }

    #[test]
    fn contour_panels_reject_broken_grids() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.png");
        let mut panels = saddle_panels(5);
        panels[1].x.pop();
        assert!(contour_panels_png(&p, "t", "ξ", &panels).is_err());
        let mut panels = saddle_panels(5);
        panels[0].y.reverse();
        assert!(contour_panels_png(&p, "t", "ξ", &panels).is_err());
        assert!(!p.exists());
    }

    #[test]
    fn residual_panels_normal_and_degenerate() {
        let dir = tempfile::tempdir().unwrap();
        let fr: Vec<(f64, f64)> = (0..30)
            .map(|k| {
                let f = -1.0 + 0.07 * k as f64;
                (f, 0.05 * (1.7 * k as f64).sin())
            })
            .collect();
        let nq: Vec<(f64, f64)> = (0..30)
            .map(|k| {
                let q = -2.0 + 4.0 * (k as f64 + 0.5) / 30.0;
                (q, q * 1.1 + 0.1 * (3.0 * q).sin())
            })
            .collect();
        let p = dir.path().join("residuals.png");
        let (img, l) = drawn(&p, || {
            residual_panels_png(&p, "residuals of the ξ model", &fr, &nq)
        });
        assert_eq!(l.len(), 2);
        // Residuals symmetric about zero; the probability plot on equal axes.
        assert!((l[0].y.lo + l[0].y.hi).abs() < 1e-12, "{:?}", l[0].y);
        assert_eq!((l[1].x.lo, l[1].x.hi), (l[1].y.lo, l[1].y.hi));
        let dot = over_white(PALETTE[0], 0.85);
        for &pt in &fr {
            assert!(has(&img, &l[0], pt, 1, dot), "residual {pt:?}");
        }
        for &pt in &nq {
            assert!(has(&img, &l[1], pt, 1, dot), "quantile {pt:?}");
        }
        // The reference line y = x (orange) on the right, none on the left.
        for q in [-1.5, 0.3, 1.7] {
            assert!(has(&img, &l[1], (q, q), 1, PALETTE[1]), "y = x at {q}");
        }
        assert_eq!(img.count(l[0].plot, |p| near(p, PALETTE[1], 30)), 0);
        let nan = f64::NAN;
        type Xy = Vec<(f64, f64)>;
        let cases: [(&str, Xy, Xy); 3] = [
            ("empty", vec![], vec![]),
            ("nan", vec![(nan, 1.0), (1.0, nan)], vec![(nan, nan)]),
            ("constant", vec![(2.0, 0.0); 4], vec![(0.0, 0.0); 4]),
        ];
        for (name, a, b) in &cases {
            let p = dir.path().join(format!("residuals-{name}.png"));
            let (img, l) = drawn(&p, || residual_panels_png(&p, name, a, b));
            let dots =
                |k: usize| img.count(l[k].plot, |p| near(p, over_white(PALETTE[0], 0.85), 30));
            if *name == "constant" {
                // Four dots on one another: nearly opaque.
                assert!(has(&img, &l[0], (2.0, 0.0), 1, PALETTE[0]));
                assert!(has(&img, &l[1], (0.0, 0.0), 1, PALETTE[0]));
            } else {
                // Nothing finite: no dot.
                assert_eq!((dots(0), dots(1)), (0, 0), "{name}");
            }
        }
    }

    fn annealing_history(n: usize) -> (Vec<(f64, f64, f64)>, Vec<f64>) {
        let mut best = f64::INFINITY;
        let mut its = Vec::with_capacity(n);
        let mut temps = Vec::with_capacity(n);
        for k in 0..n {
            let t = 100.0 * 0.95f64.powi((k % 300) as i32);
            let cur =
                -1.0 + 0.02 * t * (0.37 * k as f64).sin().abs() + (k as f64 * 0.91).cos() * 0.01;
            best = best.min(cur);
            its.push((k as f64 + 1.0, cur, best));
            temps.push(t);
        }
        (its, temps)
    }

    #[test]
    fn annealing_normal_and_degenerate() {
        let dir = tempfile::tempdir().unwrap();
        let (its, temps) = annealing_history(1200);
        let p = dir.path().join("annealing.png");
        let (img, l) = drawn(&p, || annealing_png(&p, "simulated annealing", &its, None));
        assert_eq!(l.len(), 1);
        assert_follows(&img, &l[0], &its, None);
        let p = dir.path().join("annealing-t.png");
        let (img, l) = drawn(&p, || {
            annealing_png(&p, "simulated annealing", &its, Some(&temps))
        });
        assert_eq!(l.len(), 2);
        assert_follows(&img, &l[0], &its, None);
        assert_follows(&img, &l[1], &its, Some(&temps));
        // Long history: decimated, still fast, still on the data.
        let (its, temps) = annealing_history(50_000);
        let p = dir.path().join("annealing-long.png");
        let start = std::time::Instant::now();
        let (img, l) = drawn(&p, || annealing_png(&p, "long", &its, Some(&temps)));
        assert!(start.elapsed().as_secs_f64() < 20.0);
        assert_follows(&img, &l[0], &its, None);
        assert_follows(&img, &l[1], &its, Some(&temps));

        let nan = f64::NAN;
        type History = Vec<(f64, f64, f64)>;
        let cases: [(&str, History, Vec<f64>); 4] = [
            ("empty", vec![], vec![]),
            (
                "nan",
                vec![(nan, 1.0, 1.0), (1.0, nan, nan)],
                vec![nan, -1.0],
            ),
            ("one", vec![(1.0, 2.0, 2.0)], vec![0.0]),
            (
                "gappy",
                vec![
                    (1.0, 2.0, 2.0),
                    (2.0, nan, 2.0),
                    (3.0, 1.0, 1.0),
                    (4.0, 3.0, 1.0),
                ],
                vec![1.0, 0.5, nan, 0.25],
            ),
        ];
        for (name, its, t) in &cases {
            for temperature in [None, Some(t.as_slice())] {
                let p = dir
                    .path()
                    .join(format!("annealing-{name}-{}.png", temperature.is_some()));
                let (img, l) = drawn(&p, || annealing_png(&p, name, its, temperature));
                assert_eq!(l.len(), 1 + temperature.is_some() as usize, "{name}");
                if *name != "gappy" {
                    continue;
                }
                // The best J line is drawn through its finite points…
                let line = |k: usize, at: (f64, f64), c: RGBColor| {
                    img.any_near(l[k].pixel(at), 1, |p| tinted(p, c, 0.35))
                };
                assert!(line(0, (1.5, 2.0), PALETTE[1]));
                assert!(line(0, (3.5, 1.0), PALETTE[1]));
                // …the current J's gap (iteration 2) is not bridged, its last run is drawn.
                assert!(line(0, (3.5, 2.0), PALETTE[0]));
                assert!(!line(0, (2.0, 1.5), PALETTE[0]));
                if temperature.is_some() {
                    // Temperature 1 → 0.5 drawn (log axis), the NaN at 3 breaks the line.
                    assert!(line(1, (1.5, 0.5f64.sqrt()), PALETTE[2]));
                    assert!(!line(1, (3.0, 0.125f64.sqrt()), PALETTE[2]));
                }
            }
        }
        let p = dir.path().join("annealing-bad.png");
        assert!(annealing_png(&p, "t", &[(1.0, 1.0, 1.0)], Some(&[1.0, 2.0])).is_err());
    }

    /// The best J line (or, with `temperature`, the temperature line) passes through the
    /// history's values.
    fn assert_follows(
        img: &Image,
        l: &ChartLayout,
        its: &[(f64, f64, f64)],
        temperature: Option<&[f64]>,
    ) {
        let step = (its.len() / 97).max(1);
        let picks: Vec<usize> = (step / 2..its.len()).step_by(step).collect();
        let on = picks
            .iter()
            .filter(|&&k| {
                let (at, c) = match temperature {
                    None => ((its[k].0, its[k].2), PALETTE[1]),
                    Some(t) => ((its[k].0, t[k]), PALETTE[2]),
                };
                img.any_near(l.pixel(at), 1, |p| tinted(p, c, 0.35))
            })
            .count();
        assert!(
            on * 100 >= picks.len() * 95,
            "{on} of {} on the line",
            picks.len()
        );
    }

    /// Renders the examples to /tmp/plots_doe_examples for a visual check:
    /// `cargo test --lib figures::doe -- --ignored`.
    #[test]
    #[ignore]
    fn write_examples() {
        let dir = Path::new("/tmp/plots_doe_examples");
        std::fs::create_dir_all(dir).unwrap();
        contour_panels_png(
            &dir.join("contour_saddle.png"),
            "Saddle z = x² − y² (+ shift per panel)",
            "ξ",
            &saddle_panels(41),
        )
        .unwrap();
        contour_panels_png(
            &dir.join("contour_saddle_coarse.png"),
            "Saddle on a 5 × 5 grid",
            "ξ",
            &saddle_panels(5),
        )
        .unwrap();
        let mut holed = saddle_panels(41);
        for p in &mut holed {
            p.z.slice_mut(ndarray::s![25..35, 5..15]).fill(f64::NAN);
        }
        contour_panels_png(
            &dir.join("contour_holed.png"),
            "With a NaN hole",
            "ξ",
            &holed,
        )
        .unwrap();
        // Degenerate panels: all NaN, a 2 × 2 grid, a constant, a single node.
        let nan = f64::NAN;
        let mut odd = saddle_panels(2);
        odd[0].z.fill(nan);
        odd[2].z.fill(0.25);
        let mut single = saddle_panels(2).remove(1);
        single.x = vec![0.5];
        single.y = vec![3.0];
        single.z = Array2::from_elem((1, 1), -0.5);
        odd.push(single);
        contour_panels_png(&dir.join("contour_degenerate.png"), "Degenerate", "ξ", &odd).unwrap();
        let fr: Vec<(f64, f64)> = (0..30)
            .map(|k| (-1.0 + 0.07 * k as f64, 0.05 * (1.7 * k as f64).sin()))
            .collect();
        let nq: Vec<(f64, f64)> = (0..30)
            .map(|k| {
                let q = -2.0 + 4.0 * (k as f64 + 0.5) / 30.0;
                (q, q * 1.1 + 0.1 * (3.0 * q).sin())
            })
            .collect();
        residual_panels_png(
            &dir.join("residuals.png"),
            "Residuals of the ξ model",
            &fr,
            &nq,
        )
        .unwrap();
        let (its, temps) = annealing_history(1500);
        annealing_png(
            &dir.join("annealing.png"),
            "Simulated annealing",
            &its,
            Some(&temps),
        )
        .unwrap();
        annealing_png(
            &dir.join("annealing_no_t.png"),
            "Simulated annealing",
            &its,
            None,
        )
        .unwrap();
    }
}
