//! The one plotting kit every figure uses: the error type, the embedded font and text styles,
//! rendering into a PNG through a temp file, colours, axis extents and padding, finite runs and
//! decimation of long series, number and tick formatting (linear and log axes), legends,
//! boxed labels, and (in [`contour`]) marching squares on a grid.
//!
//! Where two figure families had grown slightly different versions of one helper, both
//! behaviours are kept and named here (a parameter or a second function), so that moving the
//! figures onto the kit changed no pixel.

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Once;

pub mod contour;

/// A figure could not be drawn or written. Figures are side outputs: degenerate data gives a
/// "no data" figure or this error, never a panic.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// The input cannot be drawn, or drawing or encoding the image failed.
    #[error("writing {}: {message}", path.display())]
    Draw { path: PathBuf, message: String },
    /// Plotters failed to draw or encode the image.
    #[error("writing {}: plot", path.display())]
    Plot {
        path: PathBuf,
        #[source]
        source: PlotError,
    },
    /// Moving the finished image into place failed.
    #[error("{}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

pub type Result<T> = std::result::Result<T, FigureError>;

/// A plotters drawing error, whatever the backend: the drawing closures return it with `?`
/// and [`render_png`] wraps it with the figure's path.
#[derive(Debug, thiserror::Error)]
#[error(transparent)]
pub struct PlotError(Box<dyn std::error::Error + Send + Sync>);

impl<E: std::error::Error + Send + Sync + 'static> From<DrawingAreaErrorKind<E>> for PlotError {
    fn from(e: DrawingAreaErrorKind<E>) -> Self {
        PlotError(Box::new(e))
    }
}

/// What the drawing closures return.
pub(crate) type DrawResult<T> = std::result::Result<T, PlotError>;

/// The error for figure `path`: "plot: " and the reason.
pub(crate) fn perr(path: &Path, e: impl std::fmt::Display) -> FigureError {
    FigureError::Draw {
        path: path.to_path_buf(),
        message: format!("plot: {e}"),
    }
}

// ---------------------------------------------------------------------------------------------
// Font and text

/// The family every figure names; [`ensure_font`] backs it with the embedded DejaVu Sans, so
/// no system fontconfig/freetype is needed.
pub(crate) const FAMILY: &str = "sans-serif";

static FONT: Once = Once::new();

pub(crate) fn ensure_font() {
    FONT.call_once(|| {
        // Registration fails only for a corrupt font, which the dejavu crate does not ship.
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, dejavu::sans::regular());
    });
}

/// The figure font at `size` pixels (captions, tick labels, axis descriptions).
pub(crate) fn font(size: u32) -> (&'static str, u32) {
    (FAMILY, size)
}

/// The font of a figure's title.
pub(crate) fn title_font() -> (&'static str, u32) {
    font(20)
}

/// Black text at `size` anchored by `pos`.
pub(crate) fn text_style(size: u32, pos: Pos) -> TextStyle<'static> {
    font(size).into_font().color(&BLACK).pos(pos)
}

// ---------------------------------------------------------------------------------------------
// Rendering

/// A drawing area in pixels.
pub(crate) type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// A chart on linear f64 axes.
pub(crate) type Chart<'a, 'b> =
    ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Render into a PNG on a white background via a temp file + rename.
pub(crate) fn render_png(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&Area) -> DrawResult<()>,
) -> Result<()> {
    ensure_font();
    // The bitmap backend picks the image format from the extension: keep ".png" last.
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{file_name}.tmp-{}.png", std::process::id()));
    {
        let root = BitMapBackend::new(&tmp, size).into_drawing_area();
        let plot = |source: PlotError| FigureError::Plot {
            path: path.to_path_buf(),
            source,
        };
        root.fill(&WHITE).map_err(|e| plot(e.into()))?;
        draw(&root).map_err(plot)?;
        root.present().map_err(|e| plot(e.into()))?;
    }
    std::fs::rename(&tmp, path).map_err(|source| FigureError::Io {
        path: path.to_path_buf(),
        source,
    })
}

// ---------------------------------------------------------------------------------------------
// Colours

/// The basic figures' series colours (plotters' primaries, then black).
pub(crate) const BASIC_PALETTE: [RGBColor; 6] = [BLUE, RED, GREEN, MAGENTA, CYAN, BLACK];

/// Line colours of the sweep, DOE and time-history figures (Okabe–Ito, distinguishable for
/// colour-blind readers), then black.
pub(crate) const PALETTE: [RGBColor; 7] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
];

/// Light fills for shaded x intervals (regime bands): blue, green, yellow, red, lavender, grey.
pub(crate) const BAND_FILLS: [RGBColor; 6] = [
    RGBColor(214, 230, 246),
    RGBColor(214, 239, 208),
    RGBColor(253, 240, 196),
    RGBColor(252, 213, 200),
    RGBColor(226, 222, 240),
    RGBColor(228, 228, 228),
];

/// The single trace colour of the analysis figures (return map, phase portrait, spectrum).
pub(crate) const TRACE_BLUE: RGBColor = RGBColor(0, 90, 170);

/// A marker that must stand out on every viridis colour (the DOE optimum).
pub(crate) const MARKER_RED: RGBColor = RGBColor(220, 20, 20);

// ---------------------------------------------------------------------------------------------
// Extents and padding

/// A value that can be placed on a plotters axis (finite and far from overflow).
pub(crate) fn usable(v: f64) -> bool {
    v.is_finite() && v.abs() < 1e300
}

/// Running min/max of usable values.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Extent {
    pub(crate) lo: f64,
    pub(crate) hi: f64,
}

impl Extent {
    pub(crate) fn new() -> Self {
        Extent {
            lo: f64::INFINITY,
            hi: f64::NEG_INFINITY,
        }
    }

    pub(crate) fn add(&mut self, v: f64) {
        if usable(v) {
            self.lo = self.lo.min(v);
            self.hi = self.hi.max(v);
        }
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.lo > self.hi
    }

    /// The range padded by `frac` of its span below and `frac + top_extra` above; a
    /// constant (or relatively tiny) span is padded by 5 % of its magnitude (±1 around 0);
    /// an empty extent gives `fallback`.
    pub(crate) fn range(&self, frac: f64, top_extra: f64, fallback: Range<f64>) -> Range<f64> {
        if self.is_empty() {
            return fallback;
        }
        let (lo, hi) = (self.lo, self.hi);
        let span = hi - lo;
        let scale = lo.abs().max(hi.abs());
        if span.is_finite() && span > scale * 1e-9 && span > 0.0 {
            (lo - frac * span)..(hi + (frac + top_extra) * span)
        } else {
            let d = if scale > 0.0 { 0.05 * scale } else { 1.0 };
            (lo - d)..(hi + d + top_extra * 2.0 * d)
        }
    }
}

/// Min and max of the finite values; `(∞, −∞)` when there is none.
pub(crate) fn finite_min_max(values: impl IntoIterator<Item = f64>) -> (f64, f64) {
    values
        .into_iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        })
}

/// `lo..=hi` (usable, `lo ≤ hi`) padded by 5 % of the span; a constant (or relatively tiny)
/// span gets ±5 % of its magnitude (±1 around zero): [`Extent::range`] without headroom.
pub(crate) fn padded(lo: f64, hi: f64) -> (f64, f64) {
    let r = Extent { lo, hi }.range(0.05, 0.0, lo..hi);
    (r.start, r.end)
}

/// The basic line plots' padding: 5 % of the span, or 5 % of `max(|lo|, 1)` when `lo == hi`.
/// Unlike [`Extent::range`] a relatively tiny span is not treated as constant; the two rules
/// stay apart so that neither family's figures change.
pub(crate) fn padded_abs((lo, hi): (f64, f64)) -> Range<f64> {
    let d = if hi > lo {
        (hi - lo) * 0.05
    } else {
        lo.abs().max(1.0) * 0.05
    };
    (lo - d)..(hi + d)
}

/// A log-axis range around positive `lo..=hi`: `factor` beyond each end, or a factor of two
/// around a single value.
pub(crate) fn log_padded(lo: f64, hi: f64, factor: f64) -> Range<f64> {
    if hi > lo {
        (lo / factor)..(hi * factor)
    } else {
        (lo / 2.0)..(lo * 2.0)
    }
}

/// Usable `(x, y)` points, in order.
pub(crate) fn finite_xy(pts: &[(f64, f64)]) -> impl Iterator<Item = (f64, f64)> + '_ {
    pts.iter().copied().filter(|&(x, y)| usable(x) && usable(y))
}

/// The maximal runs of usable points, split at every non-finite one.
pub(crate) fn finite_runs(pts: &[(f64, f64)]) -> impl Iterator<Item = &[(f64, f64)]> + '_ {
    pts.split(|&(x, y)| !(usable(x) && usable(y)))
        .filter(|run| !run.is_empty())
}

// ---------------------------------------------------------------------------------------------
// Decimation of long series

/// M4 decimation for drawing: the points falling in each of `columns` equal x bins keep only
/// their first, last, minimum and maximum (in their original order), so the drawn envelope
/// is exactly that of the full series. Non-finite points are dropped; series of at most
/// `4·columns` points are returned as they are (filtered).
pub(crate) fn decimate_minmax(
    pts: &[(f64, f64)],
    x0: f64,
    x1: f64,
    columns: usize,
) -> Vec<(f64, f64)> {
    let columns = columns.max(1);
    if pts.len() <= 4 * columns || !(usable(x0) && usable(x1) && x1 > x0) {
        return finite_xy(pts).collect();
    }
    let scale = columns as f64 / (x1 - x0);
    let bin = |x: f64| (((x - x0) * scale).floor().max(0.0) as usize).min(columns - 1);
    let mut out = Vec::with_capacity(4 * columns + 4);
    // (bin, first, min, max, last) as indices into pts.
    let mut cur: Option<(usize, usize, usize, usize, usize)> = None;
    let flush = |c: (usize, usize, usize, usize, usize), out: &mut Vec<(f64, f64)>| {
        let mut idx = [c.1, c.2, c.3, c.4];
        idx.sort_unstable();
        let mut last = usize::MAX;
        for i in idx {
            if i != last {
                out.push(pts[i]);
                last = i;
            }
        }
    };
    for (i, &(x, y)) in pts.iter().enumerate() {
        if !(usable(x) && usable(y)) {
            continue;
        }
        let b = bin(x);
        match cur.as_mut() {
            Some(c) if c.0 == b => {
                if y < pts[c.2].1 {
                    c.2 = i;
                }
                if y > pts[c.3].1 {
                    c.3 = i;
                }
                c.4 = i;
            }
            _ => {
                if let Some(c) = cur {
                    flush(c, &mut out);
                }
                cur = Some((b, i, i, i, i));
            }
        }
    }
    if let Some(c) = cur {
        flush(c, &mut out);
    }
    out
}

/// The lowest and the highest `(x, y)` point of a bin.
type MinMaxPoints = ((f64, f64), (f64, f64));

/// Min/max decimation on a log x axis: positive points (x in `x0..=x1`, `0 < x0 < x1`) are
/// binned on `bins` log-spaced x bins, each keeping its lowest and highest point in x order
/// (a spectrum's envelope).
pub(crate) fn decimate_log_minmax(
    pts: &[(f64, f64)],
    x0: f64,
    x1: f64,
    bins: usize,
) -> Vec<(f64, f64)> {
    let (l0, l1) = (x0.ln(), x1.ln());
    let scale = (bins as f64 - 1e-9) / (l1 - l0);
    let mut slots: Vec<Option<MinMaxPoints>> = vec![None; bins];
    for &(f, a) in pts {
        let k = (((f.ln() - l0) * scale) as usize).min(bins - 1);
        let bin = slots[k].get_or_insert(((f, a), (f, a)));
        if a < bin.0 .1 {
            bin.0 = (f, a);
        }
        if a > bin.1 .1 {
            bin.1 = (f, a);
        }
    }
    slots
        .into_iter()
        .flatten()
        .flat_map(|(mn, mx)| if mn.0 <= mx.0 { [mn, mx] } else { [mx, mn] })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Numbers and ticks

/// Three significant digits, without exponent for the usual kHz values.
pub(crate) fn fmt_sig3(v: f64) -> String {
    let a = v.abs();
    if a >= 1e5 || (a < 1e-3 && a > 0.0) {
        format!("{v:.2e}")
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}

/// A linear-axis tick label with as many decimals as the tick spacing (≈ span/10) needs,
/// trailing zeros trimmed.
pub(crate) fn lin_tick_label(v: f64, span: f64) -> String {
    let step = (span / 10.0).abs();
    let decimals = if step > 0.0 && step.is_finite() {
        (-(step.log10().floor()) as i32 + 1).clamp(0, 12) as usize
    } else {
        3
    };
    let mut s = format!("{v:.decimals$}");
    if s.contains('.') {
        s = s.trim_end_matches('0').trim_end_matches('.').to_string();
    }
    if s == "-0" {
        s = "0".to_string();
    }
    s
}

/// A log-axis tick label as a one-digit power of ten ("1e-6", "3e2"): the basic figures'
/// log axes, whose ticks plotters places.
pub(crate) fn sci_tick_label(v: &f64) -> String {
    format!("{v:.0e}")
}

/// A log-axis tick label: decades always, also 2 and 5 (and 3 on short axes) when the axis
/// spans few decades; other ticks are unlabelled minor ticks. Goes with [`log_key_points`].
pub(crate) fn log_tick_label(v: f64, decades: f64) -> String {
    if !v.is_finite() || v <= 0.0 {
        return String::new();
    }
    let e = (v.log10() + 1e-9).floor();
    let m = v / 10f64.powf(e);
    let mr = m.round();
    if (m - mr).abs() > 1e-6 * m {
        return String::new();
    }
    let allowed: &[f64] = if decades <= 1.3 {
        &[1.0, 2.0, 3.0, 5.0]
    } else if decades <= 3.5 {
        &[1.0, 2.0, 5.0]
    } else {
        &[1.0]
    };
    if !allowed.contains(&mr) {
        return String::new();
    }
    let (m, e) = (mr as i64, e as i32);
    if !(-3..=5).contains(&e) {
        format!("{m}e{e}")
    } else if e >= 0 {
        format!("{}", m * 10i64.pow(e as u32))
    } else {
        format!("0.{}{m}", "0".repeat((-e - 1) as usize))
    }
}

/// Tick positions of a log axis over `lo..hi`: every `m·10^e` (m = 1…9) when the axis spans
/// at most four decades, only the decades otherwise (labelled by [`log_tick_label`]).
pub(crate) fn log_key_points(lo: f64, hi: f64) -> Vec<f64> {
    let decades = (hi / lo).log10();
    let mantissas: &[f64] = if decades <= 4.0 {
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]
    } else {
        &[1.0]
    };
    let (e0, e1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    (e0..=e1)
        .flat_map(|e| mantissas.iter().map(move |m| m * 10f64.powi(e)))
        .filter(|v| *v >= lo * (1.0 - 1e-12) && *v <= hi * (1.0 + 1e-12))
        .collect()
}

/// `name (unit)`, or `name` alone for an empty unit.
pub(crate) fn with_unit(name: &str, unit: &str) -> String {
    if unit.trim().is_empty() {
        name.to_string()
    } else {
        format!("{name} ({unit})")
    }
}

// ---------------------------------------------------------------------------------------------
// Lines, legends and labels

/// A legend key: a horizontal line `len` pixels long in `style`.
pub(crate) fn line_key(
    len: i32,
    style: ShapeStyle,
) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new(vec![(x, y), (x + len, y)], style)
}

/// A dashed grey reference line through `pts` (8 px dashes, 5 px gaps).
pub(crate) fn dashed_line(
    pts: Vec<(f64, f64)>,
) -> DashedLineSeries<std::vec::IntoIter<(f64, f64)>, i32> {
    DashedLineSeries::new(pts, 8, 5, BLACK.mix(0.6).stroke_width(1))
}

/// A polyline as plotters elements: one path for thin lines, one path per segment for wide
/// ones — plotters joins wide paths with unlimited inner miters, which at sharp turns (a
/// contour through a saddle, a reannealing jump) spike far across the plot.
pub(crate) fn polyline_elements(
    pts: &[(f64, f64)],
    style: ShapeStyle,
) -> Vec<PathElement<(f64, f64)>> {
    if style.stroke_width <= 1 || pts.len() < 3 {
        vec![PathElement::new(pts.to_vec(), style)]
    } else {
        pts.windows(2)
            .map(|w| PathElement::new(w.to_vec(), style))
            .collect()
    }
}

pub(crate) fn draw_polyline(
    chart: &mut Chart,
    pts: &[(f64, f64)],
    style: ShapeStyle,
) -> DrawResult<()> {
    chart.draw_series(polyline_elements(pts, style))?;
    Ok(())
}

/// How a legend box looks: black border on a translucent white background.
#[derive(Debug, Clone)]
pub(crate) struct Legend {
    /// Corner of the plot; `None` keeps plotters' default (middle right).
    pub(crate) position: Option<SeriesLabelPosition>,
    /// Label font size; `None` keeps plotters' default (12 px).
    pub(crate) font_size: Option<u32>,
    /// Opacity of the white background.
    pub(crate) background: f64,
}

impl Legend {
    /// The basic figures' legend: plotters' default place and font, background 0.8 opaque.
    pub(crate) const BASIC: Legend = Legend {
        position: None,
        font_size: None,
        background: 0.8,
    };

    /// A legend in `position` with labels of `font_size` px, background 0.85 opaque (sweep,
    /// DOE and analysis figures).
    pub(crate) fn at(position: SeriesLabelPosition, font_size: u32) -> Legend {
        Legend {
            position: Some(position),
            font_size: Some(font_size),
            background: 0.85,
        }
    }
}

/// The legend of the series labelled so far.
pub(crate) fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    legend: Legend,
) -> DrawResult<()>
where
    DB::ErrorType: 'static,
{
    let mut labels = chart.configure_series_labels();
    if let Some(position) = legend.position {
        labels.position(position);
    }
    if let Some(size) = legend.font_size {
        labels.label_font(font(size));
    }
    labels
        .border_style(BLACK)
        .background_style(WHITE.mix(legend.background))
        .draw()?;
    Ok(())
}

/// "no data" in the middle of an empty chart.
pub(crate) fn draw_no_data<'a, 'b: 'a>(chart: &mut Chart<'a, 'b>) -> DrawResult<()> {
    let (xr, yr) = (chart.x_range(), chart.y_range());
    let centre = (0.5 * (xr.start + xr.end), 0.5 * (yr.start + yr.end));
    chart.draw_series(std::iter::once(Text::new(
        "no data",
        centre,
        text_style(18, Pos::new(HPos::Center, VPos::Center)),
    )))?;
    Ok(())
}

/// A pixel rectangle `(left, top, right, bottom)`.
pub(crate) type PixelRect = (i32, i32, i32, i32);

/// Top-left corner of a `w × h` pixel box anchored at `at` by `pos`.
pub(crate) fn anchor_box(at: (i32, i32), (w, h): (i32, i32), pos: Pos) -> (i32, i32) {
    let left = match pos.h_pos {
        HPos::Left => at.0,
        HPos::Center => at.0 - w / 2,
        HPos::Right => at.0 - w,
    };
    let top = match pos.v_pos {
        VPos::Top => at.1,
        VPos::Center => at.1 - h / 2,
        VPos::Bottom => at.1 - h,
    };
    (left, top)
}

/// A one-line `label` (size 13) at pixel offset `offset` from the data point `at`, anchored
/// by `pos`, on a translucent white box (0.8, 2 px margin) so that it stays legible over
/// lines and bands. The sweep figures' labels; [`boxed_text`] is the multi-line one.
pub(crate) fn boxed_label<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    at: (f64, f64),
    label: &str,
    offset: (i32, i32),
    pos: Pos,
) -> DrawResult<()> {
    if label.is_empty() {
        return Ok(());
    }
    let style = text_style(13, pos);
    let (w, h) = chart.plotting_area().estimate_text_size(label, &style)?;
    let (w, h) = (w as i32, h as i32);
    let (left, top) = anchor_box(offset, (w, h), pos);
    chart.draw_series(std::iter::once(
        EmptyElement::at(at)
            + Rectangle::new(
                [(left - 2, top - 1), (left + w + 2, top + h + 1)],
                WHITE.mix(0.8).filled(),
            )
            + Text::new(label.to_string(), offset, style),
    ))?;
    Ok(())
}

/// `text` (possibly several lines) on a translucent white box (0.85, 4 px margin), anchored
/// at pixel `at` of `area` by `pos`. Returns the box in `area` pixels. The analysis figures'
/// annotations and peak labels.
pub(crate) fn boxed_text(
    area: &Area,
    at: (i32, i32),
    text: &str,
    pos: Pos,
    size: u32,
) -> DrawResult<PixelRect> {
    let (w, h, lines) = measure_text(area, text, size)?;
    let (left, top) = anchor_box(at, (w, h), pos);
    let rect = (left - 4, top - 3, left + w + 4, top + h + 3);
    area.draw(&Rectangle::new(
        [(rect.0, rect.1), (rect.2, rect.3)],
        WHITE.mix(0.85).filled(),
    ))?;
    let line_h = if lines.is_empty() {
        0
    } else {
        h / lines.len() as i32
    };
    for (k, line) in lines.iter().enumerate() {
        area.draw(&Text::new(
            line.to_string(),
            (left, top + k as i32 * line_h),
            text_style(size, Pos::new(HPos::Left, VPos::Top)),
        ))?;
    }
    Ok(rect)
}

/// Width, height (pixels) and lines of a possibly multi-line text.
pub(crate) fn measure_text<'t>(
    area: &Area,
    text: &'t str,
    size: u32,
) -> DrawResult<(i32, i32, Vec<&'t str>)> {
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    let style = text_style(size, Pos::new(HPos::Left, VPos::Top));
    let (mut w, mut h) = (0i32, 0i32);
    for line in &lines {
        let (lw, _) = area.estimate_text_size(line, &style)?;
        w = w.max(lw as i32);
        // A fixed line height: the estimate of a line without descenders is shorter.
        h += (size as f64 * 1.25).round() as i32;
    }
    Ok((w, h, lines))
}

pub(crate) fn overlaps(a: PixelRect, b: PixelRect) -> bool {
    a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3
}

// ---------------------------------------------------------------------------------------------
// Layout: where a chart puts its data, so that tests can map data to image pixels

#[cfg(test)]
/// One axis of a drawn chart: its data range and the image pixel of each end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct AxisMap {
    pub(crate) lo: f64,
    pub(crate) hi: f64,
    pub(crate) px_lo: f64,
    pub(crate) px_hi: f64,
    pub(crate) log: bool,
}

#[cfg(test)]
impl AxisMap {
    /// The image pixel coordinate of the data value `v` (fractional; beyond the ends for
    /// values off the axis).
    pub(crate) fn pixel(&self, v: f64) -> f64 {
        let f = if self.log {
            (v.ln() - self.lo.ln()) / (self.hi.ln() - self.lo.ln())
        } else {
            (v - self.lo) / (self.hi - self.lo)
        };
        self.px_lo + f * (self.px_hi - self.px_lo)
    }
}

#[cfg(test)]
/// A chart's plot area in image pixels and the mapping of its two axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ChartLayout {
    /// `(left, top, right, bottom)`, right and bottom exclusive.
    pub(crate) plot: PixelRect,
    pub(crate) x: AxisMap,
    pub(crate) y: AxisMap,
}

#[cfg(test)]
impl ChartLayout {
    /// The image pixel of the data point `(x, y)`, rounded.
    pub(crate) fn pixel(&self, (x, y): (f64, f64)) -> (i32, i32) {
        (
            self.x.pixel(x).round() as i32,
            self.y.pixel(y).round() as i32,
        )
    }
}

#[cfg(test)]
thread_local! {
    static LAYOUTS: std::cell::RefCell<Vec<ChartLayout>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Records where `chart` draws — its plot area and the pixels of the ends of its axes `x` and
/// `y` (`log` per axis) — for the tests of this thread to read with [`take_layouts`]. Costs
/// nothing outside tests.
pub(crate) fn note_layout<DB: DrawingBackend, CT: CoordTranslate<From = (f64, f64)>>(
    chart: &ChartContext<DB, CT>,
    x: Range<f64>,
    y: Range<f64>,
    log: (bool, bool),
) {
    #[cfg(test)]
    {
        let (xs, ys) = chart.plotting_area().get_pixel_range();
        let a = chart.as_coord_spec().translate(&(x.start, y.start));
        let b = chart.as_coord_spec().translate(&(x.end, y.end));
        let layout = ChartLayout {
            plot: (xs.start, ys.start, xs.end, ys.end),
            x: AxisMap {
                lo: x.start,
                hi: x.end,
                px_lo: a.0 as f64,
                px_hi: b.0 as f64,
                log: log.0,
            },
            y: AxisMap {
                lo: y.start,
                hi: y.end,
                px_lo: a.1 as f64,
                px_hi: b.1 as f64,
                log: log.1,
            },
        };
        LAYOUTS.with(|l| l.borrow_mut().push(layout));
    }
    #[cfg(not(test))]
    let _ = (chart, x, y, log);
}

/// The layouts noted on this thread since the last call, in drawing order.
#[cfg(test)]
pub(crate) fn take_layouts() -> Vec<ChartLayout> {
    LAYOUTS.with(|l| std::mem::take(&mut *l.borrow_mut()))
}

/// Test helpers: decode a written figure and ask what colour its pixels have.
#[cfg(test)]
pub(crate) mod testing {
    use super::{take_layouts, ChartLayout, PixelRect, Result};
    use plotters::style::RGBColor;
    use std::path::Path;

    /// A decoded PNG, 8-bit RGB.
    pub(crate) struct Image {
        pub(crate) width: i32,
        pub(crate) height: i32,
        rgb: Vec<[u8; 3]>,
    }

    /// Decodes the figure at `path` (the `png` crate: an independent decoder of what
    /// plotters encoded).
    pub(crate) fn read_png(path: &Path) -> Image {
        let file = std::fs::File::open(path).expect("figure written");
        let mut reader = png::Decoder::new(std::io::BufReader::new(file))
            .read_info()
            .expect("a PNG");
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).expect("PNG data");
        assert_eq!(info.bit_depth, png::BitDepth::Eight, "{}", path.display());
        let channels = match info.color_type {
            png::ColorType::Rgb => 3,
            png::ColorType::Rgba => 4,
            other => panic!("{}: colour type {other:?}", path.display()),
        };
        let rgb = buf[..info.buffer_size()]
            .chunks_exact(channels)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        Image {
            width: info.width as i32,
            height: info.height as i32,
            rgb,
        }
    }

    /// Draws a figure with `draw` and returns its image and the layouts of its charts.
    pub(crate) fn drawn(
        path: &Path,
        draw: impl FnOnce() -> Result<()>,
    ) -> (Image, Vec<ChartLayout>) {
        take_layouts();
        draw().expect("figure drawn");
        // To look at what a test drew: HDI_KEEP_FIGURES=<dir>.
        if let Some(dir) = std::env::var_os("HDI_KEEP_FIGURES") {
            let name = path.file_name().expect("a file name");
            std::fs::copy(path, Path::new(&dir).join(name)).expect("figure kept");
        }
        (read_png(path), take_layouts())
    }

    /// Where on the viridis scale (0…1) the colour `p` lies, if it is a viridis colour
    /// (within `tol` per channel of plotters' map).
    pub(crate) fn viridis_value(p: [u8; 3], tol: u8) -> Option<f64> {
        use plotters::style::colors::colormaps::ViridisRGB;
        let dist = |c: RGBColor| {
            (0..3)
                .map(|i| [c.0, c.1, c.2][i].abs_diff(p[i]))
                .max()
                .unwrap_or(0)
        };
        (0..=1000)
            .map(|k| {
                let t = k as f64 / 1000.0;
                (t, dist(ViridisRGB::get_color_normalized(t, 0.0, 1.0)))
            })
            .min_by_key(|&(_, d)| d)
            .filter(|&(_, d)| d <= tol)
            .map(|(t, _)| t)
    }

    /// `colour` drawn with opacity `alpha` over white, as the bitmap backend blends it.
    pub(crate) fn over_white(colour: RGBColor, alpha: f64) -> RGBColor {
        let mix = |c: u8| (f64::from(c) * alpha + 255.0 * (1.0 - alpha)).round() as u8;
        RGBColor(mix(colour.0), mix(colour.1), mix(colour.2))
    }

    /// Every channel within `tol` of `colour`.
    pub(crate) fn near(p: [u8; 3], colour: RGBColor, tol: u8) -> bool {
        p[0].abs_diff(colour.0) <= tol
            && p[1].abs_diff(colour.1) <= tol
            && p[2].abs_diff(colour.2) <= tol
    }

    /// `colour` over white with some opacity of at least `min_alpha` (lines drawn at an angle
    /// are blended into the background along their edges).
    pub(crate) fn tinted(p: [u8; 3], colour: RGBColor, min_alpha: f64) -> bool {
        let c = [colour.0, colour.1, colour.2].map(f64::from);
        let q = p.map(f64::from);
        let k = (0..3).min_by(|&a, &b| c[a].total_cmp(&c[b])).unwrap_or(0);
        if c[k] >= 250.0 {
            return false;
        }
        let alpha = (255.0 - q[k]) / (255.0 - c[k]);
        alpha >= min_alpha
            && alpha <= 1.05
            && (0..3).all(|i| (alpha * c[i] + (1.0 - alpha) * 255.0 - q[i]).abs() <= 25.0)
    }

    pub(crate) const WHITE_PX: [u8; 3] = [255, 255, 255];

    impl Image {
        /// The pixel at `(x, y)`, `None` outside the image.
        pub(crate) fn at(&self, x: i32, y: i32) -> Option<[u8; 3]> {
            (x >= 0 && y >= 0 && x < self.width && y < self.height)
                .then(|| self.rgb[(y * self.width + x) as usize])
        }

        /// How many pixels of `rect` (right, bottom exclusive) satisfy `pred`.
        pub(crate) fn count(&self, rect: PixelRect, pred: impl Fn([u8; 3]) -> bool) -> usize {
            let mut n = 0;
            for y in rect.1.max(0)..rect.3.min(self.height) {
                for x in rect.0.max(0)..rect.2.min(self.width) {
                    if pred(self.rgb[(y * self.width + x) as usize]) {
                        n += 1;
                    }
                }
            }
            n
        }

        /// Whether a pixel within `radius` (a square) of `(x, y)` satisfies `pred`.
        pub(crate) fn any_near(
            &self,
            (x, y): (i32, i32),
            radius: i32,
            pred: impl Fn([u8; 3]) -> bool,
        ) -> bool {
            self.count(
                (x - radius, y - radius, x + radius + 1, y + radius + 1),
                pred,
            ) > 0
        }

        /// How many pixels differ from `other`'s (every pixel when the sizes differ).
        pub(crate) fn differing_pixels(&self, other: &Image) -> usize {
            if (self.width, self.height) != (other.width, other.height) {
                return self.rgb.len().max(other.rgb.len());
            }
            self.rgb
                .iter()
                .zip(&other.rgb)
                .filter(|(a, b)| a != b)
                .count()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_keeps_envelope_and_order() {
        let pts: Vec<(f64, f64)> = (0..8000)
            .map(|i| {
                let x = i as f64;
                let spike = if i == 4321 {
                    50.0
                } else if i == 777 {
                    -40.0
                } else {
                    0.0
                };
                (x, (x * 0.37).sin() + spike)
            })
            .collect();
        let d = decimate_minmax(&pts, 0.0, 7999.0, 500);
        assert!(d.len() <= 4 * 500, "{}", d.len());
        assert!(d.len() >= 2 * 500);
        assert!(d.contains(&pts[4321]) && d.contains(&pts[777]));
        assert_eq!(d[0], pts[0]);
        assert_eq!(*d.last().unwrap(), pts[7999]);
        assert!(d.windows(2).all(|w| w[0].0 < w[1].0));
        // Short, NaN-laden and degenerate-range inputs pass through filtered.
        let short = [(0.0, 1.0), (f64::NAN, 2.0), (2.0, 3.0)];
        assert_eq!(
            decimate_minmax(&short, 0.0, 2.0, 500),
            vec![(0.0, 1.0), (2.0, 3.0)]
        );
        assert_eq!(decimate_minmax(&pts, 1.0, 1.0, 10).len(), 8000);
        assert!(decimate_minmax(&[(f64::NAN, 0.0); 100], 0.0, 1.0, 10).is_empty());
    }

    #[test]
    fn log_decimation_keeps_extrema_in_x_order() {
        // 10 000 points over four decades, two spikes.
        let pts: Vec<(f64, f64)> = (0..10_000)
            .map(|k| {
                let f = 10f64.powf(4.0 * k as f64 / 9999.0);
                let a = match k {
                    5000 => 1e3,
                    8000 => 1e-6,
                    _ => 1.0 + 0.1 * (k as f64 * 0.3).sin(),
                };
                (f, a)
            })
            .collect();
        let d = decimate_log_minmax(&pts, 1.0, 1e4, 200);
        assert!(d.len() <= 2 * 200, "{}", d.len());
        assert!(d.contains(&pts[5000]) && d.contains(&pts[8000]));
        // Every bin is occupied: both ends of the axis are kept.
        assert!(d[0].0 < 1.05 && d[d.len() - 1].0 > 1e4 / 1.05);
        assert!(d.windows(2).all(|w| w[0].0 <= w[1].0));
    }

    #[test]
    fn log_tick_labels() {
        assert_eq!(log_tick_label(10.0, 2.0), "10");
        assert_eq!(log_tick_label(20.0, 2.0), "20");
        assert_eq!(log_tick_label(30.0, 2.0), "");
        assert_eq!(log_tick_label(30.0, 1.0), "30");
        assert_eq!(log_tick_label(0.05, 2.0), "0.05");
        assert_eq!(log_tick_label(200.0, 5.0), "");
        assert_eq!(log_tick_label(1e-6, 8.0), "1e-6");
        assert_eq!(log_tick_label(0.0, 2.0), "");
    }

    #[test]
    fn numbers_and_ticks() {
        assert_eq!(lin_tick_label(0.25, 1.0), "0.25");
        assert_eq!(lin_tick_label(2.0, 10.0), "2");
        assert_eq!(lin_tick_label(-0.0001, 1.0), "0");
        assert_eq!(lin_tick_label(1.5, 0.0), "1.5");
        assert_eq!(fmt_sig3(48.0), "48.0");
        assert_eq!(fmt_sig3(101.4), "101");
        assert_eq!(fmt_sig3(2.5e5), "2.50e5");
        assert_eq!(fmt_sig3(0.5), "0.500");
        assert_eq!(sci_tick_label(&1e-6), "1e-6");
        assert_eq!(sci_tick_label(&300.0), "3e2");
        assert_eq!(with_unit("x", "nm"), "x (nm)");
        assert_eq!(with_unit("x", " "), "x");
        let ticks = log_key_points(1.0, 100.0);
        assert_eq!(ticks.len(), 19);
        assert_eq!((ticks[0], ticks[18]), (1.0, 100.0));
        assert_eq!(
            log_key_points(1.0, 1e6),
            vec![1.0, 10.0, 100.0, 1e3, 1e4, 1e5, 1e6]
        );
    }

    #[test]
    fn extents_and_padding() {
        let mut e = Extent::new();
        assert!(e.is_empty());
        assert_eq!(e.range(0.05, 0.0, -1.0..1.0), -1.0..1.0);
        for v in [2.0, f64::NAN, 1e301, 4.0] {
            e.add(v);
        }
        assert_eq!((e.lo, e.hi), (2.0, 4.0));
        assert_eq!(e.range(0.5, 0.5, 0.0..1.0), 1.0..6.0);
        // Constant: ±5 % of the magnitude, ±1 around zero.
        assert_eq!(padded(2.0, 2.0), (1.9, 2.1));
        assert_eq!(padded(0.0, 0.0), (-1.0, 1.0));
        assert_eq!(padded(0.0, 10.0), (-0.5, 10.5));
        // The basic rule pads a relatively tiny span by its own size.
        let r = padded_abs((1.0, 1.0 + 1e-12));
        assert!(r.end - r.start < 1e-11);
        assert_eq!(padded_abs((0.0, 0.0)), -0.05..0.05);
        assert_eq!(log_padded(1.0, 10.0, 2.0), 0.5..20.0);
        assert_eq!(log_padded(4.0, 4.0, 1.3), 2.0..8.0);
        assert_eq!(
            finite_min_max([3.0, f64::NAN, -1.0, f64::INFINITY]),
            (-1.0, 3.0)
        );
        let nan = f64::NAN;
        let runs: Vec<usize> = finite_runs(&[(0.0, 1.0), (nan, 1.0), (1.0, 2.0), (2.0, 3.0)])
            .map(<[_]>::len)
            .collect();
        assert_eq!(runs, vec![1, 2]);
    }

    #[test]
    fn errors_name_the_figure() {
        let e = perr(Path::new("out/a.png"), "empty map");
        assert_eq!(e.to_string(), "writing out/a.png: plot: empty map");
        // A plotters error reads as before (path, "plot", plotters' text) through the chain.
        let e = FigureError::Plot {
            path: PathBuf::from("out/a.png"),
            source: DrawingAreaErrorKind::<std::io::Error>::LayoutError.into(),
        };
        let source = std::error::Error::source(&e).map(|s| s.to_string());
        assert_eq!(
            (e.to_string(), source.as_deref()),
            ("writing out/a.png: plot".to_string(), Some("Bad layout"))
        );
    }

    #[test]
    fn boxes_anchor_and_overlap() {
        let c = Pos::new(HPos::Center, VPos::Bottom);
        assert_eq!(anchor_box((100, 50), (20, 10), c), (90, 40));
        let r = Pos::new(HPos::Right, VPos::Top);
        assert_eq!(anchor_box((100, 50), (20, 10), r), (80, 50));
        assert!(overlaps((0, 0, 10, 10), (5, 5, 15, 15)));
        assert!(!overlaps((0, 0, 10, 10), (10, 0, 20, 10)));
    }
}
