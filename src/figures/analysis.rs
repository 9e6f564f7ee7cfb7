//! PNG plots of the analysis stage: the wavelet scalogram with its cone of influence and
//! ridge, the Poincaré return map, the phase portrait and the amplitude spectrum.
//!
//! Drawn with the plotting kit: the plot functions take plain slices (no dependency on
//! the analysis types), skip non-finite values (and non-positive ones on log axes), and report
//! empty or degenerate input as an error, never a panic.

use super::kit::{
    boxed_text, decimate_log_minmax, draw_legend, finite_min_max, fmt_sig3, font, lin_tick_label,
    line_key, log_key_points, log_padded, log_tick_label, measure_text, note_layout, overlaps,
    padded, perr, render_png, title_font, usable, with_unit, Area, DrawResult, Legend, PixelRect,
    Result, TRACE_BLUE,
};
use plotters::coord::combinators::BindKeyPoints;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// At most this many time columns in a scalogram (the plot is ~750 px wide).
const MAX_SCALOGRAM_COLUMNS: usize = 800;
/// At most this many frequency rows in a scalogram (the plot is ~450 px high).
const MAX_SCALOGRAM_ROWS: usize = 400;
/// At most this many rectangles in a scalogram: bounds the drawing time.
const MAX_SCALOGRAM_CELLS: usize = 160_000;
/// At most this many points of a ridge line.
const MAX_RIDGE_POINTS: usize = 4000;
/// Above this many points a spectrum is reduced to a min/max envelope on log-spaced bins.
const SPECTRUM_DECIMATE_ABOVE: usize = 6000;
const SPECTRUM_BINS: usize = 1500;
/// Labelled peaks in a spectrum.
const MAX_PEAK_LABELS: usize = 5;
/// Phase portraits keep a point only when it moves by 1/PHASE_GRID of the axis span.
const PHASE_GRID: f64 = 3000.0;

/// Lower/upper cell edges of sorted log-spaced frequencies: geometric midpoints between
/// neighbours, and the outer edges half a step beyond the ends.
fn log_edges(f: &[f64]) -> Vec<f64> {
    let n = f.len();
    let mut e = Vec::with_capacity(n + 1);
    if n == 1 {
        e.push(f[0] / 1.1);
        e.push(f[0] * 1.1);
        return e;
    }
    e.push(f[0] * (f[0] / f[1]).sqrt());
    for k in 1..n {
        e.push(f[k - 1].sqrt() * f[k].sqrt());
    }
    e.push(f[n - 1] * (f[n - 1] / f[n - 2]).sqrt());
    e
}

/// `n` items split into `parts` contiguous blocks of near-equal size: block `b` is
/// `start(b)..start(b + 1)`.
fn block_start(n: usize, parts: usize, b: usize) -> usize {
    b * n / parts
}

/// Scalogram `|W|` as a viridis heat map: time in ms (x), frequency in kHz on a log axis
/// (y), a colour bar in `magnitude_unit`, the cone of influence as a black-edged white line
/// with the region below it (where edge effects matter) dimmed, and the ridge, if given, as
/// a red line.
///
/// `magnitude` is row-major `[frequency][time]` (as in the analysis `Scalogram`);
/// `frequencies_hz` must be positive and strictly monotonic (increasing, or decreasing),
/// `time_s` strictly increasing; `coi_hz` has one value per time sample or is empty (no
/// cone drawn); `ridge_hz` has one value per time sample (non-finite values break the
/// line). Time is reduced to at most 800 columns by the maximum over each block, so that
/// peaks survive.
#[allow(clippy::too_many_arguments)]
pub fn scalogram_png(
    path: &Path,
    title: &str,
    time_s: &[f64],
    frequencies_hz: &[f64],
    magnitude: &[f32],
    coi_hz: &[f64],
    ridge_hz: Option<&[f64]>,
    magnitude_unit: &str,
) -> Result<()> {
    scalogram_figure(
        path,
        title,
        time_s,
        frequencies_hz,
        magnitude,
        coi_hz,
        ridge_hz,
        magnitude_unit,
        None,
    )
}

/// The significance drawn over a scalogram: the mask (row-major like the magnitude) is
/// outlined outside the cone of influence, and the global wavelet spectrum with its level
/// is plotted beside the scalogram against the same frequency axis.
pub struct SignificanceOverlay<'a> {
    pub mask: &'a [bool],
    /// Global spectrum and its level per frequency row, in `power_unit` (NaN: not formed).
    pub global: &'a [f64],
    pub global_level: &'a [f64],
    pub power_unit: &'a str,
    /// Confidence level, e.g. 0.95.
    pub level: f64,
}

/// [`scalogram_png`] with the significance contours and the global spectrum panel.
#[allow(clippy::too_many_arguments)]
pub fn scalogram_significance_png(
    path: &Path,
    title: &str,
    time_s: &[f64],
    frequencies_hz: &[f64],
    magnitude: &[f32],
    coi_hz: &[f64],
    ridge_hz: Option<&[f64]>,
    magnitude_unit: &str,
    overlay: &SignificanceOverlay,
) -> Result<()> {
    let nf = frequencies_hz.len();
    if overlay.mask.len() != magnitude.len()
        || overlay.global.len() != nf
        || overlay.global_level.len() != nf
    {
        return Err(perr(
            path,
            "significance overlay does not match the scalogram",
        ));
    }
    scalogram_figure(
        path,
        title,
        time_s,
        frequencies_hz,
        magnitude,
        coi_hz,
        ridge_hz,
        magnitude_unit,
        Some(overlay),
    )
}

#[allow(clippy::too_many_arguments)]
fn scalogram_figure(
    path: &Path,
    title: &str,
    time_s: &[f64],
    frequencies_hz: &[f64],
    magnitude: &[f32],
    coi_hz: &[f64],
    ridge_hz: Option<&[f64]>,
    magnitude_unit: &str,
    overlay: Option<&SignificanceOverlay>,
) -> Result<()> {
    let order = scalogram_row_order(path, time_s, frequencies_hz, magnitude, coi_hz, ridge_hz)?;
    let (nt, nf) = (time_s.len(), frequencies_hz.len());
    let f_khz: Vec<f64> = order.iter().map(|&j| frequencies_hz[j] * 1e-3).collect();
    let edges = log_edges(&f_khz);
    let grid = decimate_scalogram(path, magnitude, &order, nt)?;
    let (rows, cols) = (grid.rows, grid.cols);

    let t_ms = |i: usize| {
        if i < nt {
            time_s[i] * 1e3
        } else {
            (2.0 * time_s[nt - 1] - time_s[nt - 2]) * 1e3
        }
    };
    let (x0, x1) = (t_ms(0), t_ms(nt));
    let (y0, y1) = (edges[0], edges[nf]);
    if !x1.is_finite() || y0 <= 0.0 || !y1.is_finite() {
        return Err(perr(path, "scalogram axes out of range"));
    }
    let layout = ScalogramLayout {
        col_x: (0..=cols).map(|b| t_ms(block_start(nt, cols, b))).collect(),
        row_y: (0..=rows)
            .map(|g| edges[block_start(nf, rows, g)])
            .collect(),
        x: (x0, x1),
        y: (y0, y1),
        coi: cone_per_column(coi_hz, nt, cols, y0, y1),
        ridge_segments: ridge_segments(ridge_hz, time_s, y0, y1),
        contours: Vec::new(),
    };
    let Some(overlay) = overlay else {
        return render_png(path, (940, 580), |root| {
            let (main, bar) = root.split_horizontally(800);
            draw_scalogram_chart(&main, title, &grid, &layout)?;
            draw_colour_bar(&bar, grid.lo, grid.hi, magnitude_unit)
        });
    };
    let mut layout = layout;
    layout.contours = contour_segments(overlay.mask, &order, nt, rows, cols, &layout);
    let global: Vec<(f64, f64, f64)> = order
        .iter()
        .map(|&j| {
            (
                frequencies_hz[j] * 1e-3,
                overlay.global[j],
                overlay.global_level[j],
            )
        })
        .filter(|(_, g, l)| g.is_finite() && l.is_finite() && *g > 0.0 && *l > 0.0)
        .collect();
    render_png(path, (1180, 580), |root| {
        let (main, rest) = root.split_horizontally(800);
        let (side, bar) = rest.split_horizontally(240);
        draw_scalogram_chart(&main, title, &grid, &layout)?;
        draw_global_spectrum(&side, &global, (y0, y1), overlay)?;
        draw_colour_bar(&bar, grid.lo, grid.hi, magnitude_unit)
    })
}

/// Cell edges between significant and non-significant cells (a cell is significant when
/// most of its samples are), where both cells lie outside the cone of influence.
fn contour_segments(
    mask: &[bool],
    order: &[usize],
    nt: usize,
    rows: usize,
    cols: usize,
    layout: &ScalogramLayout,
) -> Vec<[(f64, f64); 2]> {
    let nf = order.len();
    let mut flag = vec![false; rows * cols];
    for g in 0..rows {
        for b in 0..cols {
            let (mut hit, mut all) = (0usize, 0usize);
            for &j in &order[block_start(nf, rows, g)..block_start(nf, rows, g + 1)] {
                let row = &mask[j * nt..(j + 1) * nt];
                for &m in &row[block_start(nt, cols, b)..block_start(nt, cols, b + 1)] {
                    all += 1;
                    hit += usize::from(m);
                }
            }
            flag[g * cols + b] = 2 * hit > all;
        }
    }
    let (cx, ry) = (&layout.col_x, &layout.row_y);
    let outside =
        |g: usize, b: usize| layout.coi.is_empty() || (ry[g] * ry[g + 1]).sqrt() >= layout.coi[b];
    let mut segs = Vec::new();
    for g in 0..rows {
        for b in 0..cols {
            let here = flag[g * cols + b];
            if b + 1 < cols && here != flag[g * cols + b + 1] && outside(g, b) && outside(g, b + 1)
            {
                segs.push([(cx[b + 1], ry[g]), (cx[b + 1], ry[g + 1])]);
            }
            if g + 1 < rows
                && here != flag[(g + 1) * cols + b]
                && outside(g, b)
                && outside(g + 1, b)
            {
                segs.push([(cx[b], ry[g + 1]), (cx[b + 1], ry[g + 1])]);
            }
        }
    }
    segs
}

/// The global wavelet spectrum (black) and its level (red) against frequency (kHz, log).
fn draw_global_spectrum(
    area: &Area,
    global: &[(f64, f64, f64)],
    (y0, y1): (f64, f64),
    overlay: &SignificanceOverlay,
) -> DrawResult<()> {
    let (lo, hi) = finite_min_max(global.iter().flat_map(|(_, g, l)| [*g, *l]));
    let (lo, hi) = if lo > 0.0 && hi > lo {
        (lo / 1.5, hi * 1.5)
    } else {
        (1e-30, 1.0)
    };
    let mut chart = ChartBuilder::on(area)
        .caption("global spectrum", font(15))
        .margin(10)
        .margin_top(30)
        .x_label_area_size(45)
        .y_label_area_size(8)
        .build_cartesian_2d((lo..hi).log_scale(), (y0..y1).log_scale())?;
    chart
        .configure_mesh()
        .disable_mesh()
        .disable_y_axis()
        .x_labels(3)
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .x_desc(with_unit("mean |W|²", overlay.power_unit))
        .label_style(font(12))
        .axis_desc_style(font(13))
        .draw()?;
    chart
        .draw_series(std::iter::once(PathElement::new(
            global.iter().map(|(f, g, _)| (*g, *f)).collect::<Vec<_>>(),
            BLACK.stroke_width(2),
        )))?
        .label("global")
        .legend(line_key(16, BLACK.stroke_width(2)));
    chart
        .draw_series(std::iter::once(PathElement::new(
            global.iter().map(|(f, _, l)| (*l, *f)).collect::<Vec<_>>(),
            RED.stroke_width(2),
        )))?
        .label(format!("{:.0} % AR(1)", overlay.level * 100.0))
        .legend(line_key(16, RED.stroke_width(2)));
    draw_legend(&mut chart, Legend::at(SeriesLabelPosition::UpperRight, 12))?;
    Ok(())
}

/// Checks the scalogram's inputs; the order of the frequency rows that makes them increase.
fn scalogram_row_order(
    path: &Path,
    time_s: &[f64],
    frequencies_hz: &[f64],
    magnitude: &[f32],
    coi_hz: &[f64],
    ridge_hz: Option<&[f64]>,
) -> Result<Vec<usize>> {
    let (nt, nf) = (time_s.len(), frequencies_hz.len());
    if nt < 2 || nf == 0 {
        return Err(perr(
            path,
            format!("scalogram needs ≥ 2 times and ≥ 1 frequency, got {nt} × {nf}"),
        ));
    }
    if nt.checked_mul(nf) != Some(magnitude.len()) {
        return Err(perr(
            path,
            format!(
                "scalogram magnitude has {} values, expected {nf} × {nt}",
                magnitude.len()
            ),
        ));
    }
    if !coi_hz.is_empty() && coi_hz.len() != nt {
        return Err(perr(
            path,
            format!(
                "cone of influence has {} values for {nt} times",
                coi_hz.len()
            ),
        ));
    }
    if let Some(r) = ridge_hz {
        if r.len() != nt {
            return Err(perr(
                path,
                format!("ridge has {} values for {nt} times", r.len()),
            ));
        }
    }
    let time_ok = time_s.iter().all(|t| t.is_finite()) && time_s.windows(2).all(|w| w[1] > w[0]);
    if !time_ok {
        return Err(perr(path, "scalogram times must be finite and increasing"));
    }
    if frequencies_hz
        .iter()
        .any(|f| !f.is_finite() || *f <= 0.0 || *f > 1e300)
    {
        return Err(perr(
            path,
            "scalogram frequencies must be finite and positive",
        ));
    }
    // Rows in increasing frequency.
    if frequencies_hz.windows(2).all(|w| w[1] > w[0]) {
        Ok((0..nf).collect())
    } else if frequencies_hz.windows(2).all(|w| w[1] < w[0]) {
        Ok((0..nf).rev().collect())
    } else {
        Err(perr(
            path,
            "scalogram frequencies must be strictly monotonic",
        ))
    }
}

/// The decimated scalogram: `rows × cols` cells (row-major), each the maximum of its block,
/// and the colour scale `lo..hi`.
struct ScalogramGrid {
    rows: usize,
    cols: usize,
    cells: Vec<f64>,
    lo: f64,
    hi: f64,
}

/// Decimation: groups of rows, blocks of time samples; each cell is the max of its block.
fn decimate_scalogram(
    path: &Path,
    magnitude: &[f32],
    order: &[usize],
    nt: usize,
) -> Result<ScalogramGrid> {
    let nf = order.len();
    let rows = nf.min(MAX_SCALOGRAM_ROWS);
    let cols = nt
        .min(MAX_SCALOGRAM_COLUMNS)
        .min((MAX_SCALOGRAM_CELLS / rows).max(1));
    let mut cells = vec![f64::NAN; rows * cols];
    for g in 0..rows {
        for &j in &order[block_start(nf, rows, g)..block_start(nf, rows, g + 1)] {
            let row = &magnitude[j * nt..(j + 1) * nt];
            for b in 0..cols {
                let cell = &mut cells[g * cols + b];
                for &v in &row[block_start(nt, cols, b)..block_start(nt, cols, b + 1)] {
                    let v = f64::from(v);
                    if v.is_finite() && (cell.is_nan() || v > *cell) {
                        *cell = v;
                    }
                }
            }
        }
    }
    let (lo, hi) = finite_min_max(cells.iter().copied());
    if lo > hi {
        return Err(perr(path, "scalogram has no finite magnitude"));
    }
    let hi = if hi > lo {
        hi
    } else if lo != 0.0 {
        lo + lo.abs()
    } else {
        1.0
    };
    Ok(ScalogramGrid {
        rows,
        cols,
        cells,
        lo,
        hi,
    })
}

/// Where the scalogram's cells, axes and overlays go, in data coordinates (ms, kHz).
struct ScalogramLayout {
    /// Left edges of the columns, then the right edge of the last.
    col_x: Vec<f64>,
    /// Lower edges of the row groups, then the upper edge of the last.
    row_y: Vec<f64>,
    x: (f64, f64),
    y: (f64, f64),
    /// Cone of influence per column (empty: no cone).
    coi: Vec<f64>,
    /// Outline of the significant region (segments in plot coordinates).
    contours: Vec<[(f64, f64); 2]>,
    ridge_segments: Vec<Vec<(f64, f64)>>,
}

/// Cone of influence per column (the highest value in the block), clamped to the axis.
fn cone_per_column(coi_hz: &[f64], nt: usize, cols: usize, y0: f64, y1: f64) -> Vec<f64> {
    if coi_hz.is_empty() {
        return Vec::new();
    }
    (0..cols)
        .map(|b| {
            let c = coi_hz[block_start(nt, cols, b)..block_start(nt, cols, b + 1)]
                .iter()
                .filter(|c| !c.is_nan())
                .fold(f64::NEG_INFINITY, |a, &c| a.max(c * 1e-3));
            c.clamp(y0, y1)
        })
        .collect()
}

/// Ridge as line segments, broken at non-finite or off-axis values.
fn ridge_segments(
    ridge_hz: Option<&[f64]>,
    time_s: &[f64],
    y0: f64,
    y1: f64,
) -> Vec<Vec<(f64, f64)>> {
    let Some(r) = ridge_hz else {
        return Vec::new();
    };
    let nt = time_s.len();
    let stride = nt.div_ceil(MAX_RIDGE_POINTS).max(1);
    let mut segs = vec![Vec::new()];
    for i in (0..nt).step_by(stride) {
        let f = r[i] * 1e-3;
        if f.is_finite() && f >= y0 && f <= y1 {
            segs.last_mut().unwrap().push((time_s[i] * 1e3, f));
        } else if !segs.last().unwrap().is_empty() {
            segs.push(Vec::new());
        }
    }
    segs.retain(|s| !s.is_empty());
    segs
}

/// The heat map with its axes, the cone of influence, the ridge and their legend.
fn draw_scalogram_chart(
    main: &Area,
    title: &str,
    grid: &ScalogramGrid,
    layout: &ScalogramLayout,
) -> DrawResult<()> {
    let ((x0, x1), (y0, y1)) = (layout.x, layout.y);
    let (rows, cols, lo, hi) = (grid.rows, grid.cols, grid.lo, grid.hi);
    let (col_x, row_y) = (&layout.col_x, &layout.row_y);
    let (coi, ridge_segments) = (&layout.coi, &layout.ridge_segments);
    let decades = (y1 / y0).log10();
    let y_ticks = log_key_points(y0, y1);
    let mut chart = ChartBuilder::on(main)
        .caption(title, title_font())
        .margin(10)
        .margin_right(15)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d(x0..x1, (y0..y1).log_scale().with_key_points(y_ticks))?;
    note_layout(&chart, x0..x1, y0..y1, (false, true));
    chart
        .configure_mesh()
        .disable_mesh()
        .x_label_formatter(&|t| lin_tick_label(*t, x1 - x0))
        .x_desc("time (ms)")
        .y_desc("frequency (kHz)")
        .y_label_formatter(&|v| log_tick_label(*v, decades))
        .label_style(font(14))
        .axis_desc_style(font(15))
        .draw()?;
    let cell_rects = (0..rows).flat_map(|g| (0..cols).map(move |b| (g, b)));
    chart.draw_series(cell_rects.filter_map(|(g, b)| {
        let v = grid.cells[g * cols + b];
        v.is_finite().then(|| {
            Rectangle::new(
                [(col_x[b], row_y[g]), (col_x[b + 1], row_y[g + 1])],
                ViridisRGB::get_color_normalized(v, lo, hi).filled(),
            )
        })
    }))?;
    if !coi.is_empty() {
        // The cone through the block centres, extended to the plot edges.
        let mut line = Vec::with_capacity(cols + 2);
        line.push((x0, coi[0]));
        for (b, &c) in coi.iter().enumerate() {
            line.push((0.5 * (col_x[b] + col_x[b + 1]), c));
        }
        line.push((x1, coi[cols - 1]));
        let mut region = line.clone();
        region.push((x1, y0));
        region.push((x0, y0));
        chart.draw_series(std::iter::once(Polygon::new(region, WHITE.mix(0.45))))?;
        chart.draw_series(std::iter::once(PathElement::new(
            line.clone(),
            BLACK.stroke_width(4),
        )))?;
        chart
            .draw_series(std::iter::once(PathElement::new(
                line,
                WHITE.stroke_width(2),
            )))?
            .label("cone of influence")
            .legend(|(x, y)| {
                EmptyElement::at((x, y))
                    + Rectangle::new([(0, -5), (16, 5)], RGBColor(200, 200, 200).filled())
                    + PathElement::new(vec![(0, -5), (16, -5)], BLACK.stroke_width(2))
            });
    }
    for (k, seg) in layout.contours.iter().enumerate() {
        let drawn = chart.draw_series(std::iter::once(PathElement::new(
            seg.to_vec(),
            BLACK.stroke_width(2),
        )))?;
        if k == 0 {
            drawn
                .label("significant (outlined)")
                .legend(line_key(16, BLACK.stroke_width(2)));
        }
    }
    for (k, seg) in ridge_segments.iter().enumerate() {
        let drawn = chart.draw_series(std::iter::once(PathElement::new(
            seg.clone(),
            RED.stroke_width(2),
        )))?;
        if k == 0 {
            drawn
                .label("ridge")
                .legend(line_key(16, RED.stroke_width(2)));
        }
    }
    if !coi.is_empty() || !ridge_segments.is_empty() || !layout.contours.is_empty() {
        // Low frequencies at late times: usually inside the cone, the least trusted part.
        draw_legend(&mut chart, Legend::at(SeriesLabelPosition::LowerRight, 13))?;
    }
    Ok(())
}

/// The colour bar: 128 viridis bands over `lo..hi`, labelled `|W|` in `magnitude_unit`.
fn draw_colour_bar(bar: &Area, lo: f64, hi: f64, magnitude_unit: &str) -> DrawResult<()> {
    let bar_span = hi - lo;
    let mut cb = ChartBuilder::on(bar)
        .margin_top(40)
        .margin_bottom(55)
        .margin_left(4)
        .margin_right(45)
        .y_label_area_size(58)
        .build_cartesian_2d(0.0..1.0, lo..hi)?;
    cb.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_labels(8)
        .y_label_formatter(&|v| lin_tick_label(*v, bar_span))
        .label_style(font(13))
        .axis_desc_style(font(14))
        .y_desc(with_unit("|W|", magnitude_unit))
        .draw()?;
    let n = 128;
    cb.draw_series((0..n).map(|k| {
        let a = lo + (hi - lo) * k as f64 / n as f64;
        let b = lo + (hi - lo) * (k + 1) as f64 / n as f64;
        Rectangle::new(
            [(0.0, a), (1.0, b)],
            ViridisRGB::get_color_normalized(0.5 * (a + b), lo, hi).filled(),
        )
    }))?;
    Ok(())
}

/// Poincaré return map: points `(x_n, x_{n+1})` on equal, square axes with the diagonal
/// `x_{n+1} = x_n` as a thin grey line and `annotation` (e.g. the classification, several
/// lines allowed) in the upper-left corner. Values are in `unit`.
pub fn poincare_png(
    path: &Path,
    title: &str,
    return_map: &[(f64, f64)],
    unit: &str,
    annotation: &str,
) -> Result<()> {
    let pts: Vec<(f64, f64)> = return_map
        .iter()
        .copied()
        .filter(|&(a, b)| usable(a) && usable(b))
        .collect();
    if pts.is_empty() {
        return Err(perr(path, "return map has no finite point"));
    }
    let (lo, hi) = finite_min_max(pts.iter().flat_map(|&(a, b)| [a, b]));
    let (lo, hi) = padded(lo, hi);
    let n = pts.len();
    let radius = if n > 2000 { 2 } else { 3 };
    let span = hi - lo;
    // The annotation goes into the corner with the fewest points nearby.
    let corner_count = |right: bool, top: bool| {
        pts.iter()
            .filter(|&&(a, b)| {
                let (u, w) = ((a - lo) / span, (b - lo) / span);
                let in_x = if right { u > 0.6 } else { u < 0.4 };
                let in_y = if top { w > 0.8 } else { w < 0.2 };
                in_x && in_y
            })
            .count()
    };
    let corners = [(false, true), (true, false), (true, true), (false, false)];
    let (right, top) = corners
        .iter()
        .copied()
        .min_by_key(|&(r, t)| corner_count(r, t))
        .unwrap_or((false, true));
    // Square plot area (≈ 560 px): equal axes look equal.
    render_png(path, (680, 676), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, title_font())
            .margin(15)
            .margin_right(25)
            .x_label_area_size(50)
            .y_label_area_size(75)
            .build_cartesian_2d(lo..hi, lo..hi)?;
        note_layout(&chart, lo..hi, lo..hi, (false, false));
        chart
            .configure_mesh()
            .light_line_style(BLACK.mix(0.04))
            .bold_line_style(BLACK.mix(0.12))
            .x_label_formatter(&|v| lin_tick_label(*v, span))
            .y_label_formatter(&|v| lin_tick_label(*v, span))
            .x_desc(with_unit("xₙ", unit))
            .y_desc(with_unit("xₙ₊₁", unit))
            .label_style(font(14))
            .axis_desc_style(font(15))
            .draw()?;
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(lo, lo), (hi, hi)],
            RGBColor(150, 150, 150).stroke_width(1),
        )))?;
        chart.draw_series(
            pts.iter()
                .map(|&p| Circle::new(p, radius, TRACE_BLUE.mix(0.75).filled())),
        )?;
        let area = chart.plotting_area().strip_coord_spec();
        let (w, h) = area.dim_in_pixel();
        let text = if annotation.trim().is_empty() {
            format!("{n} points")
        } else {
            format!("{annotation}\n{n} points")
        };
        let at = (
            if right { w as i32 - 10 } else { 10 },
            if top { 8 } else { h as i32 - 8 },
        );
        let pos = Pos::new(
            if right { HPos::Right } else { HPos::Left },
            if top { VPos::Top } else { VPos::Bottom },
        );
        boxed_text(&area, at, &text, pos, 15)?;
        Ok(())
    })
}

/// Phase portrait: the trajectory `(x, v)` as a thin line, x horizontal and v vertical,
/// with the start (green circle) and end (red square) marked. Non-finite samples break the
/// line; samples that would not move the line by a visible amount are dropped.
pub fn phase_portrait_png(
    path: &Path,
    title: &str,
    x: &[f64],
    v: &[f64],
    x_unit: &str,
    v_unit: &str,
) -> Result<()> {
    if x.len() != v.len() {
        return Err(perr(
            path,
            format!("phase portrait: {} x values, {} v values", x.len(), v.len()),
        ));
    }
    let ok = |a: f64, b: f64| usable(a) && usable(b);
    let mut xr = (f64::INFINITY, f64::NEG_INFINITY);
    let mut vr = xr;
    let mut n_ok = 0usize;
    for (&a, &b) in x.iter().zip(v) {
        if ok(a, b) {
            xr = (xr.0.min(a), xr.1.max(a));
            vr = (vr.0.min(b), vr.1.max(b));
            n_ok += 1;
        }
    }
    if n_ok < 2 {
        return Err(perr(
            path,
            "phase portrait needs at least two finite points",
        ));
    }
    let (xr, vr) = (padded(xr.0, xr.1), padded(vr.0, vr.1));
    // Segments broken at non-finite samples, thinned to a fine grid.
    let (qx, qv) = (PHASE_GRID / (xr.1 - xr.0), PHASE_GRID / (vr.1 - vr.0));
    let mut segments: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    let mut last_cell = (i64::MIN, i64::MIN);
    for (&a, &b) in x.iter().zip(v) {
        if ok(a, b) {
            let cell = (
                ((a - xr.0) * qx).floor() as i64,
                ((b - vr.0) * qv).floor() as i64,
            );
            let seg = segments.last_mut().unwrap();
            if cell != last_cell || seg.is_empty() {
                seg.push((a, b));
                last_cell = cell;
            }
        } else if !segments.last().unwrap().is_empty() {
            segments.push(Vec::new());
            last_cell = (i64::MIN, i64::MIN);
        }
    }
    segments.retain(|s| !s.is_empty());
    let start = segments[0][0];
    // The true last finite sample (thinning may have dropped it).
    let end = x
        .iter()
        .zip(v)
        .rev()
        .find(|(&a, &b)| ok(a, b))
        .map(|(&a, &b)| (a, b))
        .unwrap_or(start);
    render_png(path, (760, 600), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, title_font())
            .margin(15)
            .margin_right(25)
            .x_label_area_size(50)
            .y_label_area_size(75)
            .build_cartesian_2d(xr.0..xr.1, vr.0..vr.1)?;
        note_layout(&chart, xr.0..xr.1, vr.0..vr.1, (false, false));
        chart
            .configure_mesh()
            .light_line_style(BLACK.mix(0.04))
            .bold_line_style(BLACK.mix(0.12))
            .x_label_formatter(&|t| lin_tick_label(*t, xr.1 - xr.0))
            .y_label_formatter(&|t| lin_tick_label(*t, vr.1 - vr.0))
            .x_desc(with_unit("x", x_unit))
            .y_desc(with_unit("v", v_unit))
            .label_style(font(14))
            .axis_desc_style(font(15))
            .draw()?;
        let line = TRACE_BLUE.mix(0.6).stroke_width(1);
        for seg in &segments {
            chart.draw_series(std::iter::once(PathElement::new(seg.clone(), line)))?;
        }
        chart
            .draw_series(std::iter::once(Circle::new(
                start,
                6,
                RGBColor(0, 158, 115).filled(),
            )))?
            .label("start")
            .legend(|(x, y)| Circle::new((x + 8, y), 5, RGBColor(0, 158, 115).filled()));
        chart
            .draw_series(std::iter::once(
                EmptyElement::at(end)
                    + Rectangle::new([(-5, -5), (5, 5)], RGBColor(213, 30, 0).filled()),
            ))?
            .label("end")
            .legend(|(x, y)| {
                Rectangle::new(
                    [(x + 3, y - 5), (x + 13, y + 5)],
                    RGBColor(213, 30, 0).filled(),
                )
            });
        draw_legend(&mut chart, Legend::at(SeriesLabelPosition::UpperRight, 13))?;
        Ok(())
    })
}

/// One-sided amplitude spectrum on log–log axes, frequency in kHz (x) and amplitude in
/// `unit` (y), restricted to `f_range_hz` if given; `peaks` `(frequency Hz, amplitude)` are
/// circled and the largest few labelled with their frequency in kHz. Non-positive and
/// non-finite values are skipped; the amplitude axis shows at most eight decades below the
/// top.
pub fn spectrum_png(
    path: &Path,
    title: &str,
    frequency_hz: &[f64],
    amplitude: &[f64],
    peaks: &[(f64, f64)],
    unit: &str,
    f_range_hz: Option<(f64, f64)>,
) -> Result<()> {
    let plot = spectrum_plot(path, frequency_hz, amplitude, peaks, f_range_hz)?;
    render_png(path, (820, 560), |root| {
        draw_spectrum(root, title, unit, &plot)
    })
}

/// The spectrum's points and axes in kHz, ready to draw.
struct SpectrumPlot {
    /// The trace (decimated if long), raised to the floor.
    pts: Vec<(f64, f64)>,
    /// Peaks in range, largest first.
    marks: Vec<(f64, f64)>,
    /// The largest few peaks, which get labels.
    labelled: Vec<(f64, f64)>,
    /// The lowest amplitude shown.
    floor: f64,
    x_axis: (f64, f64),
    y_axis: (f64, f64),
}

/// The spectrum's points in range, its axes, the floor and the peaks to circle and label.
fn spectrum_plot(
    path: &Path,
    frequency_hz: &[f64],
    amplitude: &[f64],
    peaks: &[(f64, f64)],
    f_range_hz: Option<(f64, f64)>,
) -> Result<SpectrumPlot> {
    if frequency_hz.len() != amplitude.len() {
        return Err(perr(
            path,
            format!(
                "spectrum: {} frequencies, {} amplitudes",
                frequency_hz.len(),
                amplitude.len()
            ),
        ));
    }
    let positive = |a: f64| usable(a) && a > 0.0;
    let (fa, fb) = match f_range_hz {
        Some((a, b)) => {
            if a.is_nan() || b.is_nan() || b <= a.max(0.0) {
                return Err(perr(
                    path,
                    format!("spectrum: bad frequency range {a}..{b} Hz"),
                ));
            }
            (a, b)
        }
        None => (0.0, f64::INFINITY),
    };
    let in_range = |f: f64| positive(f) && f >= fa && f <= fb;
    let mut pts: Vec<(f64, f64)> = frequency_hz
        .iter()
        .zip(amplitude)
        .filter(|(&f, &a)| in_range(f) && positive(a))
        .map(|(&f, &a)| (f * 1e-3, a))
        .collect();
    if pts.is_empty() {
        return Err(perr(path, "spectrum has no positive point in range"));
    }
    let mut marks: Vec<(f64, f64)> = peaks
        .iter()
        .filter(|&&(f, a)| in_range(f) && positive(a))
        .map(|&(f, a)| (f * 1e-3, a))
        .collect();
    let (mut xr, mut yr) = ((f64::INFINITY, 0.0f64), (f64::INFINITY, 0.0f64));
    for &(f, a) in pts.iter().chain(&marks) {
        xr = (xr.0.min(f), xr.1.max(f));
        yr = (yr.0.min(a), yr.1.max(a));
    }
    let x_axis = match f_range_hz {
        Some(_) => {
            let a = if fa > 0.0 { fa * 1e-3 } else { xr.0 };
            let b = if fb.is_finite() { fb * 1e-3 } else { xr.1 };
            if b > a {
                (a, b)
            } else {
                (a / 1.2, a * 1.2)
            }
        }
        None => {
            let r = log_padded(xr.0, xr.1, 1.1);
            (r.start, r.end)
        }
    };
    let floor = yr.0.max(yr.1 * 1e-8);
    // Room above the top for the peak labels.
    let y_axis = if yr.1 > floor {
        (floor / 1.5, yr.1 * 4.0)
    } else {
        (floor / 3.0, floor * 6.0)
    };
    // Long spectra: min and max of each log-spaced bin, in frequency order.
    if pts.len() > SPECTRUM_DECIMATE_ABOVE && xr.1 > xr.0 {
        pts = decimate_log_minmax(&pts, xr.0, xr.1, SPECTRUM_BINS);
    }
    for p in &mut pts {
        p.1 = p.1.max(floor);
    }
    // The largest few peaks get labels.
    marks.sort_by(|a, b| b.1.total_cmp(&a.1));
    let labelled: Vec<(f64, f64)> = marks.iter().copied().take(MAX_PEAK_LABELS).collect();
    Ok(SpectrumPlot {
        pts,
        marks,
        labelled,
        floor,
        x_axis,
        y_axis,
    })
}

/// The log–log axes, the trace, the circled peaks and their labels.
fn draw_spectrum(root: &Area, title: &str, unit: &str, plot: &SpectrumPlot) -> DrawResult<()> {
    let (x_axis, y_axis, floor) = (plot.x_axis, plot.y_axis, plot.floor);
    let x_decades = (x_axis.1 / x_axis.0).log10();
    let y_decades = (y_axis.1 / y_axis.0).log10();
    let (x_ticks, y_ticks) = (
        log_key_points(x_axis.0, x_axis.1),
        log_key_points(y_axis.0, y_axis.1),
    );
    let mut chart = ChartBuilder::on(root)
        .caption(title, title_font())
        .margin(15)
        .margin_right(25)
        .x_label_area_size(45)
        .y_label_area_size(75)
        .build_cartesian_2d(
            (x_axis.0..x_axis.1).log_scale().with_key_points(x_ticks),
            (y_axis.0..y_axis.1).log_scale().with_key_points(y_ticks),
        )?;
    note_layout(&chart, x_axis.0..x_axis.1, y_axis.0..y_axis.1, (true, true));
    chart
        .configure_mesh()
        .bold_line_style(BLACK.mix(0.07))
        .x_label_formatter(&|v| log_tick_label(*v, x_decades))
        .y_label_formatter(&|v| log_tick_label(*v, y_decades))
        .x_desc("frequency (kHz)")
        .y_desc(with_unit("amplitude", unit))
        .label_style(font(14))
        .axis_desc_style(font(15))
        .draw()?;
    chart.draw_series(std::iter::once(PathElement::new(
        plot.pts.clone(),
        TRACE_BLUE.stroke_width(1),
    )))?;
    if !plot.marks.is_empty() {
        chart.draw_series(
            plot.marks
                .iter()
                .map(|&(f, a)| Circle::new((f, a.max(floor)), 5, RED.stroke_width(2))),
        )?;
    }
    let area = chart.plotting_area().strip_coord_spec();
    let base = chart.plotting_area().get_base_pixel();
    let by_x: Vec<(i32, i32, f64)> = plot
        .labelled
        .iter()
        .map(|&(f, a)| {
            let (px, py) = chart.backend_coord(&(f, a.max(floor)));
            (px - base.0, py - base.1, f)
        })
        .collect();
    label_peaks(&area, by_x)
}

/// Labels above their peaks (pixel `(x, y, frequency kHz)`), left to right, each moved up
/// until it overlaps no other.
fn label_peaks(area: &Area, mut by_x: Vec<(i32, i32, f64)>) -> DrawResult<()> {
    by_x.sort_by_key(|p| p.0);
    let mut placed: Vec<PixelRect> = Vec::new();
    for (px, py, f) in by_x {
        let text = format!("{} kHz", fmt_sig3(f));
        let (w, h, _) = measure_text(area, &text, 13)?;
        let mut top = py - 9 - h;
        let left = px - w / 2;
        let clash = |top: i32, placed: &[PixelRect]| {
            let r = (left - 4, top - 3, left + w + 4, top + h + 3);
            placed.iter().any(|&p| overlaps(r, p))
        };
        while clash(top, &placed) && top > 0 {
            top -= 2;
        }
        let top = top.max(2);
        let rect = boxed_text(
            area,
            (px, top),
            &text,
            Pos::new(HPos::Center, VPos::Top),
            13,
        )?;
        placed.push(rect);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::figures::kit::testing::{drawn, near, over_white, viridis_value, Image, WHITE_PX};
    use crate::figures::kit::ChartLayout;

    /// The ridge's (and the peak circles') red.
    fn red(p: [u8; 3]) -> bool {
        near(p, RED, 60)
    }

    /// The analysis trace blue, drawn opaque or translucent over white.
    fn bluish(p: [u8; 3]) -> bool {
        let [r, g, b] = p.map(i32::from);
        b > r + 50 && b > g + 25
    }

    /// The middle of the rows of column `x` inside the plot whose colour is the highest on
    /// the viridis scale.
    fn brightest_row(img: &Image, l: &ChartLayout, x: i32) -> f64 {
        let rows: Vec<(i32, f64)> = (l.plot.1 + 1..l.plot.3 - 1)
            .filter_map(|y| Some((y, viridis_value(img.at(x, y).unwrap(), 3)?)))
            .collect();
        let top = rows.iter().map(|r| r.1).fold(f64::MIN, f64::max);
        let at_top: Vec<i32> = rows
            .iter()
            .filter(|r| r.1 >= top - 1e-9)
            .map(|r| r.0)
            .collect();
        at_top.iter().sum::<i32>() as f64 / at_top.len() as f64
    }

    /// A hand-made scalogram of a log chirp 20 → 300 kHz: times, frequencies, |W|, coi, ridge.
    type Chirp = (Vec<f64>, Vec<f64>, Vec<f32>, Vec<f64>, Vec<f64>);

    fn chirp(nt: usize, nf: usize) -> Chirp {
        let fs = 1e6;
        let duration = nt as f64 / fs;
        let t: Vec<f64> = (0..nt).map(|n| n as f64 / fs).collect();
        let f: Vec<f64> = (0..nf)
            .map(|j| 5e3 * 100f64.powf(j as f64 / (nf - 1).max(1) as f64))
            .collect();
        let f_inst: Vec<f64> = t.iter().map(|&t| 20e3 * 15f64.powf(t / duration)).collect();
        let mut m = vec![0f32; nt * nf];
        for (j, &fj) in f.iter().enumerate() {
            for (n, &fi) in f_inst.iter().enumerate() {
                let a = 2.5 * (1.0 + 0.3 * (t[n] * 2e3).sin());
                m[j * nt + n] = (a * (-((fj.ln() - fi.ln()) / 0.1).powi(2)).exp()) as f32;
            }
        }
        // Morlet (ω₀ = 6): f_coi ≈ 1.35 / distance to the nearer edge.
        let coi: Vec<f64> = t
            .iter()
            .map(|&t| 1.35 / (t.min(duration - t) + 1.0 / fs))
            .collect();
        (t, f, m, coi, f_inst)
    }

    #[test]
    fn scalogram_of_chirp_shows_the_chirp_where_it_is() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("scalogram.png");
        let (t, f, m, coi, ridge) = chirp(2000, 40);
        let (img, l) = drawn(&p, || {
            scalogram_png(&p, "chirp", &t, &f, &m, &coi, Some(&ridge), "nm")
        });
        assert_eq!(l.len(), 1);
        let l = l[0];
        // Axes: time in ms over the record, frequency in kHz over the cells' edges.
        assert!(
            (l.x.lo - 0.0).abs() < 1e-12 && (l.x.hi - 2.0).abs() < 1e-9,
            "{l:?}"
        );
        assert!(l.y.log && l.y.lo < 5.0 && l.y.hi > 500.0, "{l:?}");
        // The red ridge runs along the chirp's instantaneous frequency.
        for n in (100..1900).step_by(150) {
            let at = l.pixel((t[n] * 1e3, ridge[n] * 1e-3));
            assert!(
                img.any_near(at, 2, red),
                "no ridge at {at:?}, t = {} s",
                t[n]
            );
        }
        // No cone, no ridge, no unit: the brightest cell of every column is the chirp's.
        let p2 = dir.path().join("bare.png");
        let (img, l) = drawn(&p2, || {
            scalogram_png(&p2, "bare", &t, &f, &m, &[], None, "")
        });
        let l = l[0];
        assert_eq!(img.count(l.plot, red), 0, "a ridge without a ridge");
        // One cell is a factor 100^(1/39) in frequency.
        let cell = l.y.pixel(10.0) - l.y.pixel(10.0 * 100f64.powf(1.0 / 39.0));
        for n in (50..2000).step_by(97) {
            let (x, y) = l.pixel((t[n] * 1e3, ridge[n] * 1e-3));
            let bright = brightest_row(&img, &l, x);
            assert!(
                (bright - f64::from(y)).abs() <= 0.5 * cell + 2.0,
                "t = {} s: brightest row {bright}, chirp at {y} (cell {cell} px)",
                t[n]
            );
        }
    }

    #[test]
    fn scalogram_accepts_decreasing_frequencies_and_clamps_the_cone() {
        let dir = tempfile::tempdir().unwrap();
        let (t, mut f, m, _, _) = chirp(500, 20);
        // Rows reversed: the same picture with decreasing frequencies.
        f.reverse();
        let nt = t.len();
        let m_rev: Vec<f32> = (0..f.len())
            .rev()
            .flat_map(|j| m[j * nt..(j + 1) * nt].to_vec())
            .collect();
        // Cone far above the top, far below the bottom, NaN and infinite.
        let coi: Vec<f64> = (0..nt)
            .map(|n| match n % 4 {
                0 => 1e12,
                1 => 1e-3,
                2 => f64::NAN,
                _ => f64::INFINITY,
            })
            .collect();
        let ridge = vec![f64::NAN; nt];
        let p = dir.path().join("clamped.png");
        let (img, l) = drawn(&p, || {
            scalogram_png(&p, "clamped", &t, &f, &m_rev, &coi, Some(&ridge), "nm")
        });
        // An all-NaN ridge draws nothing.
        assert_eq!(img.count(l[0].plot, red), 0);
        // Increasing frequencies with the same cone: the same picture, pixel for pixel.
        f.reverse();
        let p2 = dir.path().join("increasing.png");
        let (same, _) = drawn(&p2, || {
            scalogram_png(&p2, "clamped", &t, &f, &m, &coi, Some(&ridge), "nm")
        });
        assert_eq!(img.differing_pixels(&same), 0);
    }

    #[test]
    fn scalogram_skips_non_finite_cells_and_handles_one_frequency() {
        let dir = tempfile::tempdir().unwrap();
        // Few enough cells (60 × 10) that each is many pixels.
        let (t, f, mut m, coi, _) = chirp(60, 10);
        for k in (0..m.len()).step_by(7) {
            m[k] = if k % 2 == 0 { f32::NAN } else { f32::INFINITY };
        }
        let p = dir.path().join("holes.png");
        let (img, l) = drawn(&p, || {
            scalogram_png(&p, "holes", &t, &f, &m, &coi, None, "nm")
        });
        let l = l[0];
        let nt = t.len();
        let step = f[1] / f[0];
        let (mut holes, mut cells) = (0, 0);
        for (j, &fj) in f.iter().enumerate() {
            for n in 0..nt - 1 {
                let (x, y) = l.pixel(((t[n] + 0.5e-6) * 1e3, fj * 1e-3));
                // Away from the cone's line and the cell's edges.
                let cone = l.y.pixel((coi[n] * 1e-3).clamp(l.y.lo, l.y.hi));
                let edge = l.y.pixel(fj * 1e-3 * step.sqrt());
                if (f64::from(y) - cone).abs() < 6.0 || (f64::from(y) - edge).abs() < 3.0 {
                    continue;
                }
                let px = img.at(x, y).unwrap();
                if (j * nt + n) % 7 == 0 {
                    assert_eq!(px, WHITE_PX, "non-finite cell ({j}, {n}) drawn");
                    holes += 1;
                } else {
                    assert_ne!(px, WHITE_PX, "cell ({j}, {n}) missing");
                    cells += 1;
                }
            }
        }
        assert!(
            holes > 40 && cells > 300,
            "{holes} holes, {cells} cells checked"
        );
        // One frequency, constant magnitude: the lowest viridis colour everywhere, dimmed
        // (the cone lies above this low frequency at every time).
        let p1 = dir.path().join("one.png");
        let (img, l) = drawn(&p1, || {
            scalogram_png(
                &p1,
                "one",
                &t,
                &f[..1],
                &vec![1.0; t.len()],
                &coi,
                None,
                "nm",
            )
        });
        let l = l[0];
        let low = ViridisRGB::get_color_normalized(0.0, 0.0, 1.0);
        let dimmed = over_white(low, 0.55);
        let area = (l.plot.2 - l.plot.0) * (l.plot.3 - l.plot.1);
        let n = img.count(l.plot, |p| near(p, dimmed, 3));
        assert!(
            n as f64 > 0.8 * area as f64,
            "{n} of {area} pixels {dimmed:?}"
        );
    }

    #[test]
    fn scalogram_8000_by_67_renders() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("large.png");
        let (t, f, m, coi, ridge) = chirp(8000, 67);
        let (img, l) = drawn(&p, || {
            scalogram_png(&p, "8000 × 67", &t, &f, &m, &coi, Some(&ridge), "nm")
        });
        // Decimated to 800 columns (each the maximum of its block): the ridge still sits on
        // the chirp, and the heat map is brightest there.
        let l = l[0];
        for n in (400..7600).step_by(600) {
            let at = l.pixel((t[n] * 1e3, ridge[n] * 1e-3));
            assert!(img.any_near(at, 2, red), "no ridge at {at:?}");
        }
    }

    #[test]
    fn scalogram_degenerate_inputs_are_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.png");
        let (t, f, m, coi, ridge) = chirp(100, 8);
        let run = |t: &[f64], f: &[f64], m: &[f32], coi: &[f64], r: Option<&[f64]>| {
            scalogram_png(&p, "bad", t, f, m, coi, r, "nm")
        };
        assert!(run(&[], &[], &[], &[], None).is_err());
        assert!(run(&t[..1], &f, &m[..8], &[], None).is_err());
        assert!(run(&t, &[], &[], &[], None).is_err());
        assert!(run(&t, &f, &m[1..], &coi, None).is_err());
        assert!(run(&t, &f, &m, &coi[1..], None).is_err());
        assert!(run(&t, &f, &m, &coi, Some(&ridge[1..])).is_err());
        let mut bad_t = t.clone();
        bad_t[5] = bad_t[4];
        assert!(run(&bad_t, &f, &m, &coi, None).is_err());
        bad_t[5] = f64::NAN;
        assert!(run(&bad_t, &f, &m, &coi, None).is_err());
        let mut bad_f = f.clone();
        bad_f[0] = 0.0;
        assert!(run(&t, &bad_f, &m, &coi, None).is_err());
        bad_f[0] = f64::NAN;
        assert!(run(&t, &bad_f, &m, &coi, None).is_err());
        let mut bad_f = f.clone();
        bad_f.swap(2, 3);
        assert!(run(&t, &bad_f, &m, &coi, None).is_err());
        assert!(run(&t, &f, &vec![f32::NAN; m.len()], &coi, None).is_err());
        assert!(!p.exists());
    }

    fn quasi_periodic_return_map(n: usize) -> Vec<(f64, f64)> {
        let rho = (5f64.sqrt() - 1.0) / 2.0;
        let x: Vec<f64> = (0..=n)
            .map(|k| 12.0 + 0.8 * (std::f64::consts::TAU * rho * k as f64).cos())
            .collect();
        x.windows(2).map(|w| (w[0], w[1])).collect()
    }

    #[test]
    fn poincare_writes_png() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("poincare.png");
        let mut map = quasi_periodic_return_map(300);
        map.push((f64::NAN, 1.0));
        map.push((1.0, f64::INFINITY));
        let (img, l) = drawn(&p, || {
            poincare_png(&p, "return map", &map, "nm", "quasi-periodic")
        });
        let l = l[0];
        // Equal axes padded around 12 ± 0.8.
        assert_eq!((l.x.lo, l.x.hi), (l.y.lo, l.y.hi));
        assert!(l.x.lo < 11.2 && l.x.hi > 12.8, "{l:?}");
        // Every finite point is a blue dot (a few may sit under the annotation's box).
        let finite: Vec<(f64, f64)> = map
            .iter()
            .copied()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect();
        let dots = finite
            .iter()
            .filter(|&&pt| img.any_near(l.pixel(pt), 1, bluish))
            .count();
        assert!(
            dots as f64 >= 0.9 * finite.len() as f64,
            "{dots} of {}",
            finite.len()
        );
        // The points lie on an ellipse around (12, 12): its centre is empty.
        assert!(!img.any_near(l.pixel((12.0, 12.0)), 6, bluish));
        // A short map, sparse enough to tell (xₙ, xₙ₊₁) from (xₙ₊₁, xₙ): the dots are at
        // the former, not at the mirror images (the ellipse itself is symmetric).
        let short = quasi_periodic_return_map(12);
        let p1 = dir.path().join("short.png");
        let (img, l) = drawn(&p1, || poincare_png(&p1, "short", &short, "nm", ""));
        let l = l[0];
        let far_from_all = |q: (i32, i32)| {
            short.iter().all(|&pt| {
                let d = l.pixel(pt);
                (d.0 - q.0).abs().max((d.1 - q.1).abs()) > 10
            })
        };
        let mut mirrors = 0;
        for &(a, b) in &short {
            assert!(img.any_near(l.pixel((a, b)), 1, bluish), "({a}, {b})");
            let q = l.pixel((b, a));
            if far_from_all(q) {
                assert!(
                    !img.any_near(q, 2, bluish),
                    "a dot at the mirror of ({a}, {b})"
                );
                mirrors += 1;
            }
        }
        assert!(mirrors >= 6, "{mirrors}");
        // One point (a fixed point), no annotation, no unit: a dot in the middle.
        let p1 = dir.path().join("fixed.png");
        let (img, l) = drawn(&p1, || {
            poincare_png(&p1, "fixed point", &[(3.0, 3.0)], "", "")
        });
        let l = l[0];
        let (cx, cy) = l.pixel((3.0, 3.0));
        assert_eq!(
            (cx, cy),
            ((l.plot.0 + l.plot.2) / 2, (l.plot.1 + l.plot.3) / 2),
            "{l:?}"
        );
        assert!(img.any_near((cx, cy), 1, bluish));
        assert!(!img.any_near((cx + 25, cy - 25), 5, bluish));
    }

    #[test]
    fn poincare_degenerate_inputs_are_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.png");
        assert!(poincare_png(&p, "t", &[], "nm", "").is_err());
        assert!(poincare_png(
            &p,
            "t",
            &[(f64::NAN, 1.0), (1.0, f64::NEG_INFINITY)],
            "nm",
            ""
        )
        .is_err());
        assert!(!p.exists());
    }

    fn quasi_periodic_trajectory(n: usize) -> (Vec<f64>, Vec<f64>) {
        let fs = 2e6;
        let (f1, f2) = (50e3, 50e3 * 0.618_034);
        let w = std::f64::consts::TAU;
        let t: Vec<f64> = (0..n).map(|k| k as f64 / fs).collect();
        let x = t
            .iter()
            .map(|&t| 2.0 * (w * f1 * t).sin() + 0.6 * (w * f2 * t).sin())
            .collect();
        // dx/dt in nm/ms = µm/s.
        let v = t
            .iter()
            .map(|&t| {
                (2.0 * w * f1 * (w * f1 * t).cos() + 0.6 * w * f2 * (w * f2 * t).cos()) * 1e-3
            })
            .collect();
        (x, v)
    }

    #[test]
    fn phase_portrait_writes_png() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("phase.png");
        let (mut x, v) = quasi_periodic_trajectory(20_000);
        x[100] = f64::NAN;
        let (img, l) = drawn(&p, || {
            phase_portrait_png(&p, "phase portrait", &x, &v, "nm", "µm/s")
        });
        let l = l[0];
        let green = |p: [u8; 3]| near(p, RGBColor(0, 158, 115), 40);
        let end_red = |p: [u8; 3]| near(p, RGBColor(213, 30, 0), 40);
        assert!(
            img.any_near(l.pixel((x[0], v[0])), 1, green),
            "start marker"
        );
        let last = x.len() - 1;
        assert!(
            img.any_near(l.pixel((x[last], v[last])), 1, end_red),
            "end marker"
        );
        // The line passes through the trajectory's samples.
        let samples: Vec<usize> = (150..x.len()).step_by(97).collect();
        let on_line = samples
            .iter()
            .filter(|&&k| img.any_near(l.pixel((x[k], v[k])), 1, bluish))
            .count();
        assert!(
            on_line as f64 >= 0.95 * samples.len() as f64,
            "{on_line} of {}",
            samples.len()
        );
        // Two points on a constant velocity: start and end at their places, a line between.
        let p2 = dir.path().join("two.png");
        let (img, l) = drawn(&p2, || {
            phase_portrait_png(&p2, "two", &[0.0, 1.0], &[2.0, 2.0], "", "")
        });
        let l = l[0];
        assert!(img.any_near(l.pixel((0.0, 2.0)), 1, green));
        assert!(img.any_near(l.pixel((1.0, 2.0)), 1, end_red));
        assert!(img.any_near(l.pixel((0.5, 2.0)), 1, bluish));
        assert!(!img.any_near(l.pixel((0.5, 2.04)), 2, bluish));
    }

    #[test]
    fn phase_portrait_degenerate_inputs_are_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.png");
        assert!(phase_portrait_png(&p, "t", &[], &[], "nm", "µm/s").is_err());
        assert!(phase_portrait_png(&p, "t", &[1.0], &[1.0], "nm", "µm/s").is_err());
        assert!(phase_portrait_png(&p, "t", &[1.0, 2.0], &[1.0], "nm", "µm/s").is_err());
        assert!(phase_portrait_png(&p, "t", &[1.0, f64::NAN], &[1.0, 2.0], "nm", "µm/s").is_err());
        assert!(!p.exists());
    }

    type Spectrum = (Vec<f64>, Vec<f64>, Vec<(f64, f64)>);

    fn synthetic_spectrum(n: usize, df: f64) -> Spectrum {
        let lines = [
            (48e3, 1.0),
            (96e3, 0.3),
            (101e3, 0.12),
            (144e3, 0.08),
            (230e3, 0.02),
        ];
        let f: Vec<f64> = (0..n).map(|k| k as f64 * df).collect();
        let a = f
            .iter()
            .enumerate()
            .map(|(k, &f)| {
                let floor = 2e-4 * (1.0 + 0.5 * (k as f64 * 0.37).sin().abs());
                let peaks: f64 = lines
                    .iter()
                    .map(|&(f0, a0)| a0 / (1.0 + ((f - f0) / 600.0).powi(2)))
                    .sum();
                floor + peaks
            })
            .collect();
        // Include the unlabelled small ones.
        (f, a, lines.to_vec())
    }

    #[test]
    fn spectrum_writes_png_with_peaks() {
        let dir = tempfile::tempdir().unwrap();
        let (f, mut a, peaks) = synthetic_spectrum(4000, 125.0);
        a[10] = f64::NAN;
        a[11] = -1.0;
        let p = dir.path().join("spectrum.png");
        let (img, l) = drawn(&p, || {
            spectrum_png(&p, "spectrum", &f, &a, &peaks, "nm", None)
        });
        assert_circled_exactly(&img, &l[0], &peaks, &a, &f);
        let p2 = dir.path().join("range.png");
        let (img, l) = drawn(&p2, || {
            spectrum_png(&p2, "range", &f, &a, &peaks, "nm", Some((20e3, 200e3)))
        });
        assert_eq!((l[0].x.lo, l[0].x.hi), (20.0, 200.0));
        // The 230 kHz peak is out of range.
        assert_circled_exactly(&img, &l[0], &peaks[..4], &a, &f);
        // Long spectrum (envelope decimation), no peaks, range starting at 0: no circle, and
        // the envelope still reaches every line's top.
        let (f, a, lines) = synthetic_spectrum(200_000, 2.5);
        let p3 = dir.path().join("long.png");
        let (img, l) = drawn(&p3, || {
            spectrum_png(&p3, "long", &f, &a, &[], "", Some((0.0, 400e3)))
        });
        let l = l[0];
        assert_eq!(img.count((0, 0, img.width, img.height), red), 0);
        for &(f0, _) in &lines {
            let k = (f0 / 2.5).round() as usize;
            let at = l.pixel((f[k] * 1e-3, a[k]));
            assert!(
                img.any_near(at, 2, |p| near(p, TRACE_BLUE, 30)),
                "trace misses the {f0} Hz line's top at {at:?}"
            );
        }
    }

    /// The red circles are exactly the `peaks`' (at their frequency and amplitude), and the
    /// trace reaches each peak's top, where the spectrum `(f, a)` has it.
    fn assert_circled_exactly(
        img: &Image,
        l: &ChartLayout,
        peaks: &[(f64, f64)],
        a: &[f64],
        f: &[f64],
    ) {
        let centres: Vec<(i32, i32)> = peaks
            .iter()
            .map(|&(f0, a0)| l.pixel((f0 * 1e-3, a0)))
            .collect();
        for (&(f0, _), &(x, y)) in peaks.iter().zip(&centres) {
            // A ring of radius 5: red around the centre, not on it.
            let ring = img.count((x - 7, y - 7, x + 8, y + 8), red);
            assert!(ring >= 12, "{f0} Hz at ({x}, {y}): {ring} red pixels");
            let k = f.iter().position(|&fk| fk >= f0).unwrap();
            let top = l.pixel((f[k] * 1e-3, a[k]));
            assert!(
                img.any_near(top, 2, |p| near(p, TRACE_BLUE, 30)),
                "trace misses the {f0} Hz peak at {top:?}"
            );
        }
        let mut stray = 0;
        for y in l.plot.1..l.plot.3 {
            for x in l.plot.0..l.plot.2 {
                let by_a_peak = centres
                    .iter()
                    .any(|&(cx, cy)| (x - cx).abs() <= 8 && (y - cy).abs() <= 8);
                if !by_a_peak && red(img.at(x, y).unwrap()) {
                    stray += 1;
                }
            }
        }
        assert_eq!(stray, 0, "red pixels away from the peaks");
    }

    #[test]
    fn spectrum_degenerate_inputs_are_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.png");
        let (f, a, peaks) = synthetic_spectrum(100, 1000.0);
        assert!(spectrum_png(&p, "t", &[], &[], &[], "nm", None).is_err());
        assert!(spectrum_png(&p, "t", &f, &a[1..], &peaks, "nm", None).is_err());
        assert!(spectrum_png(&p, "t", &f, &vec![0.0; f.len()], &peaks, "nm", None).is_err());
        assert!(spectrum_png(&p, "t", &f, &a, &peaks, "nm", Some((2e6, 3e6))).is_err());
        assert!(spectrum_png(&p, "t", &f, &a, &peaks, "nm", Some((5e4, 1e4))).is_err());
        assert!(spectrum_png(&p, "t", &f, &a, &peaks, "nm", Some((f64::NAN, 1e4))).is_err());
        assert!(!p.exists());
    }

    /// Renders the examples to /tmp/plots_examples for a visual check:
    /// `cargo test --release --lib figures::analysis -- --ignored`.
    #[test]
    #[ignore]
    fn write_examples() {
        let dir = Path::new("/tmp/plots_examples");
        std::fs::create_dir_all(dir).unwrap();
        let (t, f, m, coi, ridge) = chirp(8000, 67);
        let t0 = std::time::Instant::now();
        scalogram_png(
            &dir.join("scalogram.png"),
            "Scalogram of a 20 → 300 kHz chirp",
            &t,
            &f,
            &m,
            &coi,
            Some(&ridge),
            "nm",
        )
        .unwrap();
        eprintln!("scalogram 8000 × 67: {:?}", t0.elapsed());
        // A cone 20× wider than Morlet's (as for a short record), to see the dimmed region.
        let wide: Vec<f64> = coi.iter().map(|c| 20.0 * c).collect();
        scalogram_png(
            &dir.join("scalogram_wide_coi.png"),
            "Scalogram, wide cone of influence",
            &t,
            &f,
            &m,
            &wide,
            Some(&ridge),
            "nm",
        )
        .unwrap();
        // Decreasing frequencies, cone alternating above the top and below the bottom.
        let (t, mut f, m, _, ridge) = chirp(2000, 30);
        f.reverse();
        let m_rev: Vec<f32> = (0..f.len())
            .rev()
            .flat_map(|j| m[j * 2000..(j + 1) * 2000].to_vec())
            .collect();
        let coi: Vec<f64> = (0..2000)
            .map(|n| if (n / 250) % 2 == 0 { 1e9 } else { 1.0 })
            .collect();
        scalogram_png(
            &dir.join("scalogram_clamped.png"),
            "Decreasing frequencies, clamped cone",
            &t,
            &f,
            &m_rev,
            &coi,
            Some(&ridge),
            "",
        )
        .unwrap();
        poincare_png(
            &dir.join("poincare.png"),
            "Poincaré return map (maxima)",
            &quasi_periodic_return_map(400),
            "nm",
            "quasi-periodic",
        )
        .unwrap();
        let (x, v) = quasi_periodic_trajectory(4000);
        phase_portrait_png(
            &dir.join("phase.png"),
            "Phase portrait",
            &x,
            &v,
            "nm",
            "µm/s",
        )
        .unwrap();
        let (f, a, _) = synthetic_spectrum(200_000, 2.5);
        spectrum_png(
            &dir.join("spectrum_long.png"),
            "200 000 bins (min/max envelope), no peaks",
            &f,
            &a,
            &[],
            "",
            None,
        )
        .unwrap();
        poincare_png(
            &dir.join("poincare_fixed.png"),
            "Fixed point",
            &[(3.0, 3.0); 20],
            "nm",
            "periodic (period 1)",
        )
        .unwrap();
        let (f, a, peaks) = synthetic_spectrum(4000, 125.0);
        spectrum_png(
            &dir.join("spectrum.png"),
            "Amplitude spectrum",
            &f,
            &a,
            &peaks,
            "nm",
            Some((5e3, 500e3)),
        )
        .unwrap();
    }
}
