//! PNG plots of what the dissertation plots. plotters with an embedded DejaVu font, so no
//! system fontconfig/freetype is needed. Plots are side outputs: a failure to draw is reported
//! as an output error, never a panic.

use crate::error::{Error, Result};
use ndarray::ArrayView2;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use std::path::Path;
use std::sync::Once;

static FONT: Once = Once::new();

pub(crate) fn ensure_font() {
    FONT.call_once(|| {
        // Registration fails only for a corrupt font, which the dejavu crate does not ship.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

pub(crate) fn perr(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::output(path, format!("plot: {e}"))
}

/// Render into a PNG via a temp file + rename.
pub(crate) fn render_png(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(
        &DrawingArea<BitMapBackend, plotters::coord::Shift>,
    ) -> std::result::Result<(), String>,
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
        root.fill(&WHITE).map_err(|e| perr(path, e))?;
        draw(&root).map_err(|e| perr(path, e))?;
        root.present().map_err(|e| perr(path, e))?;
    }
    std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
}

/// Height map as a viridis heat map with a colour bar; axes in µm, colour in nm.
pub fn heatmap_png(path: &Path, z: ArrayView2<f64>, dx: f64, dy: f64, title: &str) -> Result<()> {
    let (ny, nx) = z.dim();
    if nx == 0 || ny == 0 {
        return Err(perr(path, "empty map"));
    }
    let (lo, hi) = z
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let span = if hi > lo { hi - lo } else { 1.0 };
    // Decimate to at most 512 cells per axis: enough for a PNG, fast to draw.
    let step = nx.max(ny).div_ceil(512).max(1);
    let (w_um, h_um) = (nx as f64 * dx * 1e6, ny as f64 * dy * 1e6);
    render_png(path, (790, 640), |root| {
        let (main, bar) = root.split_horizontally(630);
        let mut chart = ChartBuilder::on(&main)
            .caption(title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(0.0..w_um, 0.0..h_um)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("x (µm)")
            .y_desc("y (µm)")
            .draw()
            .map_err(|e| e.to_string())?;
        let cells = (0..ny)
            .step_by(step)
            .flat_map(|j| (0..nx).step_by(step).map(move |i| (j, i)));
        chart
            .draw_series(cells.map(|(j, i)| {
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
            }))
            .map_err(|e| e.to_string())?;
        let lo_nm = lo * 1e9;
        let hi_nm = (lo + span) * 1e9;
        let mut cb = ChartBuilder::on(&bar)
            .margin_top(40)
            .margin_bottom(50)
            .margin_left(10)
            .margin_right(60)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..1.0, lo_nm..hi_nm)
            .map_err(|e| e.to_string())?;
        cb.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_labels(6)
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 14))
            .y_desc("height (nm)")
            .draw()
            .map_err(|e| e.to_string())?;
        let n = 100;
        cb.draw_series((0..n).map(|k| {
            let a = lo_nm + (hi_nm - lo_nm) * k as f64 / n as f64;
            let b = lo_nm + (hi_nm - lo_nm) * (k + 1) as f64 / n as f64;
            Rectangle::new(
                [(0.0, a), (1.0, b)],
                ViridisRGB::get_color_normalized(a, lo_nm, hi_nm).filled(),
            )
        }))
        .map_err(|e| e.to_string())?;
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
            .caption(title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, 0.0..ymax.max(1e-30))
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(if scale == 1e9 {
                "probability density (1/nm)"
            } else {
                "probability density"
            })
            .draw()
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(density.iter().enumerate().map(|(k, d)| {
                Rectangle::new(
                    [(edges[k] * scale, 0.0), (edges[k + 1] * scale, d / scale)],
                    BLUE.mix(0.35).filled(),
                )
            }))
            .map_err(|e| e.to_string())?
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
                ))
                .map_err(|e| e.to_string())?
                .label(overlay_label)
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], RED.stroke_width(2)));
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.8))
            .draw()
            .map_err(|e| e.to_string())?;
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
    let pad = |r: (f64, f64)| {
        let d = if r.1 > r.0 {
            (r.1 - r.0) * 0.05
        } else {
            r.0.abs().max(1.0) * 0.05
        };
        (r.0 - d)..(r.1 + d)
    };
    let palette = [BLUE, RED, GREEN, MAGENTA, CYAN, BLACK];
    render_png(path, (760, 520), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(pad(xr), pad(yr))
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .draw()
            .map_err(|e| e.to_string())?;
        for (k, (label, s)) in series.iter().enumerate() {
            let c = palette[k % palette.len()];
            chart
                .draw_series(LineSeries::new(s.iter().copied(), c.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(*label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 15, y)], c.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.8))
            .draw()
            .map_err(|e| e.to_string())?;
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
    let span = |r: (f64, f64)| {
        if r.1 > r.0 {
            (r.0 / 1.3)..(r.1 * 1.3)
        } else {
            (r.0 / 2.0)..(r.0 * 2.0)
        }
    };
    let palette = [BLUE, RED, GREEN, MAGENTA, CYAN, BLACK];
    let y_floor = yr.0;
    render_png(path, (760, 520), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(span(xr).log_scale(), span(yr).log_scale())
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(|e| e.to_string())?;
        for (k, (label, s)) in series.iter().enumerate() {
            let c = palette[k % palette.len()];
            let pts: Vec<(f64, f64)> = s
                .iter()
                .filter(positive)
                .map(|&(x, y)| (x, y.max(y_floor)))
                .collect();
            chart
                .draw_series(LineSeries::new(pts, c.stroke_width(1)))
                .map_err(|e| e.to_string())?
                .label(*label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 15, y)], c.stroke_width(2))
                });
        }
        if !marks.is_empty() {
            chart
                .draw_series(
                    marks
                        .iter()
                        .filter(positive)
                        .map(|&(x, y)| Circle::new((x, y), 4, RED.stroke_width(2))),
                )
                .map_err(|e| e.to_string())?
                .label("peaks")
                .legend(|(x, y)| Circle::new((x + 7, y), 4, RED.stroke_width(2)));
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.8))
            .draw()
            .map_err(|e| e.to_string())?;
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
    let span = |r: (f64, f64)| {
        if r.1 > r.0 {
            (r.0 / 1.3)..(r.1 * 1.3)
        } else {
            (r.0 / 2.0)..(r.0 * 2.0)
        }
    };
    let palette = [BLUE, RED, GREEN, MAGENTA, CYAN, BLACK];
    let y_floor = yr.0;
    render_png(path, (760, 520), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(xr.0..xr.1, span(yr).log_scale())
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(|e| e.to_string())?;
        for (k, (label, s)) in series.iter().enumerate() {
            let c = palette[k % palette.len()];
            let pts: Vec<(f64, f64)> = s
                .iter()
                .filter(positive)
                // Below the floor a log axis shows nothing meaningful: leave those points out.
                .filter(|p| p.1 >= y_floor)
                .copied()
                .collect();
            chart
                .draw_series(LineSeries::new(pts, c.stroke_width(1)))
                .map_err(|e| e.to_string())?
                .label(*label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 15, y)], c.stroke_width(2))
                });
        }
        if !marks.is_empty() {
            chart
                .draw_series(
                    marks
                        .iter()
                        .filter(positive)
                        .map(|&(x, y)| Circle::new((x, y), 4, RED.stroke_width(2))),
                )
                .map_err(|e| e.to_string())?
                .label("peaks")
                .legend(|(x, y)| Circle::new((x + 7, y), 4, RED.stroke_width(2)));
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.8))
            .draw()
            .map_err(|e| e.to_string())?;
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
    let range = |pts: &[(f64, f64)], f: fn(&(f64, f64)) -> f64| {
        pts.iter()
            .map(f)
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            })
    };
    let all: Vec<(f64, f64)> = panels.iter().flat_map(|(_, p)| p.iter().copied()).collect();
    let xr = range(&all, |p| p.0);
    if !xr.0.is_finite() {
        return Err(perr(path, "no finite points to plot"));
    }
    let palette = [BLUE, RED, GREEN, MAGENTA, CYAN, BLACK];
    let height = 140 + 170 * panels.len() as u32;
    render_png(path, (900, height), |root| {
        let root = root
            .titled(title, ("sans-serif", 20))
            .map_err(|e| e.to_string())?;
        let areas = root.split_evenly((panels.len(), 1));
        for (k, ((label, pts), area)) in panels.iter().zip(areas.iter()).enumerate() {
            let mut yr = range(pts, |p| p.1);
            if !yr.0.is_finite() {
                yr = (-1.0, 1.0);
            }
            let pad = ((yr.1 - yr.0) * 0.05).max(1e-30);
            let mut chart = ChartBuilder::on(area)
                .margin(8)
                .x_label_area_size(if k + 1 == panels.len() { 35 } else { 20 })
                .y_label_area_size(70)
                .build_cartesian_2d(xr.0..xr.1, (yr.0 - pad)..(yr.1 + pad))
                .map_err(|e| e.to_string())?;
            let mut mesh = chart.configure_mesh();
            mesh.y_desc(*label);
            if k + 1 == panels.len() {
                mesh.x_desc(x_desc);
            }
            mesh.draw().map_err(|e| e.to_string())?;
            chart
                .draw_series(shade.iter().map(|&(a, b)| {
                    Rectangle::new([(a, yr.0 - pad), (b, yr.1 + pad)], BLACK.mix(0.08).filled())
                }))
                .map_err(|e| e.to_string())?;
            let c = palette[k % palette.len()];
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(1)))
                .map_err(|e| e.to_string())?;
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
    let palette = [BLUE, RED, GREEN, MAGENTA];
    let height = 120 + 36 * n as u32;
    render_png(path, (860, height), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(220)
            .build_cartesian_2d((lo - pad)..(hi + pad), -0.5f64..(n as f64 - 0.5))
            .map_err(|e| e.to_string())?;
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
            .draw()
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(-band, -0.5), (band, n as f64 - 0.5)],
                GREEN.mix(0.12).filled(),
            )))
            .map_err(|e| e.to_string())?;
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
                )
                .map_err(|e| e.to_string())?
                .label(*label)
                .legend(move |(x, y)| Circle::new((x + 7, y), 5, c.filled()));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .border_style(BLACK)
            .background_style(WHITE.mix(0.8))
            .draw()
            .map_err(|e| e.to_string())?;
        Ok(())
    })
}

/// Test helper: `path` holds a real PNG (signature, more than a header's worth of bytes).
#[cfg(test)]
pub(crate) fn assert_png(path: &Path) {
    const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];
    let bytes = std::fs::read(path).expect("plot written");
    assert!(
        bytes.len() > 1000,
        "{}: {} bytes",
        path.display(),
        bytes.len()
    );
    assert_eq!(bytes[..8], PNG_SIGNATURE, "{}", path.display());
}
