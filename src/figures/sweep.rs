//! PNG plots of slider-dynamics actuation sweeps (docs/simulation.md, docs/dynamics-metrics.md),
//! the analogues of the dissertation's figures: clearance against TFC actuation with the contact
//! regimes shaded (Figs 2.16/2.18), FHM/BV and % solid contact against actuation with marked
//! landmarks (Figs 2.19/2.22), and stacked time histories at chosen actuations (Figs 2.13–2.14).
//!
//! Drawn with the plotting kit: plots are side outputs, so degenerate input — no
//! series, no finite point, constant data — still gives a valid (possibly empty, "no data")
//! PNG; only a failure to draw or write is an error. NaN and infinite points are skipped.

use super::kit::{
    boxed_label, dashed_line, decimate_minmax, draw_legend, draw_no_data, finite_runs, finite_xy,
    line_key, perr, render_png, text_style, title_font, usable, Chart, DrawResult, Extent, Legend,
    Result, BAND_FILLS, PALETTE,
};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// A swept quantity: its mean with a ±1 std band, one point per actuation.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepSeries<'a> {
    pub label: &'a str,
    /// `(x, mean, std)`, e.g. (h_TFC in nm, steady mean clearance in nm, its std in nm).
    /// A non-finite std draws no band at that point.
    pub points: Vec<(f64, f64, f64)>,
}

/// A shaded interval of the x axis with its label at the top (a contact regime).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RegimeBand<'a> {
    pub x0: f64,
    pub x1: f64,
    pub label: &'a str,
}

/// One panel of [`time_histories_png`]: several named `(time, value)` series.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel<'a> {
    pub y_desc: &'a str,
    pub series: Vec<(&'a str, Vec<(f64, f64)>)>,
}

/// Columns per panel for min/max decimation of time histories (≥ the plot width in pixels).
const DECIMATION_COLUMNS: usize = 1000;

/// Shade the bands (x intervals clipped to the chart) over the full y range, under what is
/// drawn next, labelled at the top when `label_size` is given (one word per line when the
/// label, ≈ 7 px per character, is wider than its band).
fn draw_bands<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    bands: &[RegimeBand],
    label_size: Option<u32>,
) -> DrawResult<()> {
    let (xr, yr) = (chart.x_range(), chart.y_range());
    let plot_w = chart.plotting_area().dim_in_pixel().0.max(1) as f64;
    for (k, b) in bands.iter().enumerate() {
        if !(usable(b.x0) && usable(b.x1)) {
            continue;
        }
        let a = b.x0.min(b.x1).max(xr.start);
        let c = b.x0.max(b.x1).min(xr.end);
        if c <= a {
            continue;
        }
        let fill = BAND_FILLS[k % BAND_FILLS.len()];
        chart.draw_series(std::iter::once(Rectangle::new(
            [(a, yr.start), (c, yr.end)],
            fill.filled(),
        )))?;
        let Some(size) = label_size else { continue };
        let width_px = (c - a) / (xr.end - xr.start) * plot_w;
        let lines: Vec<&str> = if (b.label.chars().count() as f64) * 7.0 > width_px {
            b.label.split_whitespace().collect()
        } else {
            vec![b.label]
        };
        let step = size as i32 + 2;
        chart.draw_series(lines.into_iter().enumerate().map(|(i, line)| {
            EmptyElement::at((0.5 * (a + c), yr.end))
                + Text::new(
                    line.to_string(),
                    (0, 4 + step * i as i32),
                    text_style(size, Pos::new(HPos::Center, VPos::Top)),
                )
        }))?;
    }
    Ok(())
}

/// Outline of marker `shape` (0 circle, 1 triangle, 2 square) centred 10 px right of the
/// legend entry's origin, as one polygon type for all shapes.
fn marker_outline(shape: usize) -> Vec<(i32, i32)> {
    match shape {
        0 => (0..12)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / 12.0;
                (
                    10 + (3.5 * a.cos()).round() as i32,
                    (3.5 * a.sin()).round() as i32,
                )
            })
            .collect(),
        1 => vec![(10, -4), (14, 3), (6, 3)],
        _ => vec![(7, -3), (13, -3), (13, 3), (7, 3)],
    }
}

/// Draw a line with markers for series `k` (marker shape cycles: circle, triangle, square),
/// labelled in the legend when `label` is not empty. Returns whether a legend entry was made.
fn draw_line_with_markers<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    k: usize,
    label: &str,
    pts: &[(f64, f64)],
) -> DrawResult<bool> {
    let c = PALETTE[k % PALETTE.len()];
    let line = chart.draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(2)))?;
    let shape = k % 3;
    if !label.is_empty() {
        line.label(label).legend(move |(x, y)| {
            EmptyElement::at((x, y))
                + PathElement::new(vec![(0, 0), (20, 0)], c.stroke_width(2))
                + Polygon::new(marker_outline(shape), c.filled())
        });
    }
    match shape {
        0 => chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 3, c.filled())))
            .map(|_| ()),
        1 => chart
            .draw_series(pts.iter().map(|&p| TriangleMarker::new(p, 4, c.filled())))
            .map(|_| ()),
        _ => chart
            .draw_series(
                pts.iter()
                    .map(|&p| EmptyElement::at(p) + Rectangle::new([(-3, -3), (3, 3)], c.filled())),
            )
            .map(|_| ()),
    }?;
    Ok(!label.is_empty())
}

/// Clearance (or any swept mean ± std) against actuation: each series' mean as a line with
/// markers over a translucent ±1 std band; `bands` shade x intervals in light colours with
/// their label at the top (flying / mobile lubricant / bonded lubricant / solid contact);
/// `hlines` are dashed horizontal references with a label at the right end (clearance 0, T0,
/// 2T0). The y range includes every reference line. Figs 2.16/2.18.
pub fn clearance_sweep_png(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[SweepSeries],
    bands: &[RegimeBand],
    hlines: &[(f64, &str)],
) -> Result<()> {
    // Sanitised, x-sorted points per series; a non-finite std counts as no band.
    let clean: Vec<Vec<(f64, f64, f64)>> = series
        .iter()
        .map(|s| {
            let mut p: Vec<(f64, f64, f64)> = s
                .points
                .iter()
                .filter(|p| usable(p.0) && usable(p.1))
                .map(|&(x, m, sd)| (x, m, if usable(sd) { sd.abs() } else { 0.0 }))
                .collect();
            p.sort_by(|a, b| a.0.total_cmp(&b.0));
            p
        })
        .collect();
    let (mut xe, mut ye) = (Extent::new(), Extent::new());
    for &(x, m, sd) in clean.iter().flatten() {
        xe.add(x);
        ye.add(m - sd);
        ye.add(m + sd);
    }
    let has_data = !xe.is_empty();
    if xe.is_empty() {
        for b in bands {
            xe.add(b.x0);
            xe.add(b.x1);
        }
    }
    for &(y, _) in hlines {
        ye.add(y);
    }
    let xr = xe.range(0.03, 0.0, 0.0..1.0);
    // Headroom for the band labels.
    let top = if bands.is_empty() { 0.0 } else { 0.12 };
    let yr = ye.range(0.05, top, -1.0..1.0);
    render_png(path, (900, 600), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, title_font())
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(65)
            .build_cartesian_2d(xr.clone(), yr.clone())?;
        super::kit::note_layout(&chart, xr.clone(), yr.clone(), (false, false));
        // Bands first, under the mesh lines and the data.
        draw_bands(&mut chart, bands, Some(13))?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .light_line_style(BLACK.mix(0.05))
            .bold_line_style(BLACK.mix(0.12))
            .draw()?;
        for &(y, label) in hlines {
            if !usable(y) {
                continue;
            }
            chart.draw_series(dashed_line(vec![(xr.start, y), (xr.end, y)]))?;
            boxed_label(
                &mut chart,
                (xr.end, y),
                label,
                (-5, -3),
                Pos::new(HPos::Right, VPos::Bottom),
            )?;
        }
        let mut legend = false;
        for (k, (s, pts)) in series.iter().zip(&clean).enumerate() {
            if pts.is_empty() {
                continue;
            }
            let c = PALETTE[k % PALETTE.len()];
            if pts.len() >= 2 && pts.iter().any(|p| p.2 > 0.0) {
                let poly: Vec<(f64, f64)> = pts
                    .iter()
                    .map(|p| (p.0, p.1 + p.2))
                    .chain(pts.iter().rev().map(|p| (p.0, p.1 - p.2)))
                    .collect();
                chart.draw_series(std::iter::once(Polygon::new(poly, c.mix(0.2).filled())))?;
            } else {
                // A lone point: its ±std as an error bar.
                chart.draw_series(pts.iter().filter(|p| p.2 > 0.0).map(|p| {
                    PathElement::new(vec![(p.0, p.1 - p.2), (p.0, p.1 + p.2)], c.mix(0.5))
                }))?;
            }
            let xy: Vec<(f64, f64)> = pts.iter().map(|p| (p.0, p.1)).collect();
            legend |= draw_line_with_markers(&mut chart, k, s.label, &xy)?;
        }
        if !has_data {
            draw_no_data(&mut chart)?;
        }
        if legend {
            draw_legend(&mut chart, Legend::at(SeriesLabelPosition::LowerLeft, 14))?;
        }
        Ok(())
    })
}

/// Metrics against actuation (FHM/BV, % solid contact): lines with markers, and vertical
/// dashed marker lines labelled at the top (touchdown, critical point). The x range includes
/// every mark. Figs 2.19/2.22.
pub fn metric_sweep_png(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[(&str, Vec<(f64, f64)>)],
    marks: &[(f64, &str)],
) -> Result<()> {
    let clean: Vec<Vec<(f64, f64)>> = series
        .iter()
        .map(|(_, s)| {
            let mut p: Vec<(f64, f64)> = finite_xy(s).collect();
            p.sort_by(|a, b| a.0.total_cmp(&b.0));
            p
        })
        .collect();
    let (mut xe, mut ye) = (Extent::new(), Extent::new());
    for &(x, y) in clean.iter().flatten() {
        xe.add(x);
        ye.add(y);
    }
    let has_data = !xe.is_empty();
    for &(x, _) in marks {
        xe.add(x);
    }
    let xr = xe.range(0.03, 0.0, 0.0..1.0);
    let top = if marks.is_empty() {
        0.0
    } else {
        0.04 * marks.len().min(4) as f64
    };
    let yr = ye.range(0.05, top, 0.0..1.0);
    render_png(path, (900, 600), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, title_font())
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(65)
            .build_cartesian_2d(xr.clone(), yr.clone())?;
        super::kit::note_layout(&chart, xr.clone(), yr.clone(), (false, false));
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .light_line_style(BLACK.mix(0.05))
            .bold_line_style(BLACK.mix(0.12))
            .draw()?;
        let mut usable_marks: Vec<(f64, &str)> =
            marks.iter().copied().filter(|m| usable(m.0)).collect();
        usable_marks.sort_by(|a, b| a.0.total_cmp(&b.0));
        for &(x, _) in &usable_marks {
            chart.draw_series(dashed_line(vec![(x, yr.start), (x, yr.end)]))?;
        }
        // Labels after all lines, on a light box, staggered in x order so that close marks do
        // not print over each other.
        for (k, &(x, label)) in usable_marks.iter().enumerate() {
            boxed_label(
                &mut chart,
                (x, yr.end),
                label,
                (4, 4 + 17 * (k % 4) as i32),
                Pos::new(HPos::Left, VPos::Top),
            )?;
        }
        let mut legend = false;
        for (k, ((label, _), pts)) in series.iter().zip(&clean).enumerate() {
            if !pts.is_empty() {
                legend |= draw_line_with_markers(&mut chart, k, label, pts)?;
            }
        }
        if !has_data {
            draw_no_data(&mut chart)?;
        }
        if legend {
            draw_legend(&mut chart, Legend::at(SeriesLabelPosition::UpperLeft, 14))?;
        }
        Ok(())
    })
}

/// Time histories in stacked panels sharing the time axis, several series per panel with a
/// legend (clearance, forces, μ, P_m, τ at chosen actuations; Figs 2.13–2.14). The x values
/// are times in milliseconds (the axis is labelled "time (ms)"). Long series are decimated
/// per pixel column (min/max), so an 8000-sample history draws as fast as a short one.
/// A non-finite value breaks a line (μ where nothing is loaded draws as a gap, not a bridge).
pub fn time_histories_png(path: &Path, title: &str, panels: &[Panel]) -> Result<()> {
    time_histories_banded_png(path, title, panels, &[])
}

/// [`time_histories_png`] with shaded time intervals behind every panel, labelled in the
/// first one (the regimes of a variable-actuation run, Fig. 4.16). Band x values in ms.
pub fn time_histories_banded_png(
    path: &Path,
    title: &str,
    panels: &[Panel],
    bands: &[RegimeBand],
) -> Result<()> {
    let mut xe = Extent::new();
    for (x, _) in panels
        .iter()
        .flat_map(|p| p.series.iter())
        .flat_map(|(_, s)| finite_xy(s))
    {
        xe.add(x);
    }
    let xr = xe.range(0.0, 0.0, 0.0..1.0);
    let n_panels = panels.len().max(1);
    let height = u32::try_from(60 + 210 * n_panels)
        .map_err(|_| perr(path, "too many panels"))?
        .min(16_000);
    render_png(path, (1000, height), |root| {
        let root = root.titled(title, title_font())?;
        let areas = root.split_evenly((n_panels, 1));
        let empty = Panel {
            y_desc: "",
            series: Vec::new(),
        };
        let panel_list: Vec<&Panel> = if panels.is_empty() {
            vec![&empty]
        } else {
            panels.iter().collect()
        };
        for (k, (panel, area)) in panel_list.iter().zip(areas.iter()).enumerate() {
            let last = k + 1 == n_panels;
            // Each series as its finite runs, each run decimated on its own.
            let drawn: Vec<Vec<Vec<(f64, f64)>>> = panel
                .series
                .iter()
                .map(|(_, s)| {
                    finite_runs(s)
                        .map(|run| decimate_minmax(run, xr.start, xr.end, DECIMATION_COLUMNS))
                        .collect()
                })
                .collect();
            let mut ye = Extent::new();
            for &(_, y) in drawn.iter().flatten().flatten() {
                ye.add(y);
            }
            let top = if k == 0 && !bands.is_empty() {
                0.15
            } else {
                0.0
            };
            let yr = ye.range(0.05, top, -1.0..1.0);
            let mut chart = ChartBuilder::on(area)
                .margin(8)
                .margin_right(16)
                .x_label_area_size(if last { 40 } else { 22 })
                .y_label_area_size(75)
                .build_cartesian_2d(xr.clone(), yr.clone())?;
            super::kit::note_layout(&chart, xr.clone(), yr.clone(), (false, false));
            draw_bands(&mut chart, bands, (k == 0).then_some(12))?;
            let mut mesh = chart.configure_mesh();
            mesh.y_desc(panel.y_desc)
                .light_line_style(BLACK.mix(0.05))
                .bold_line_style(BLACK.mix(0.12));
            if last {
                mesh.x_desc("time (ms)");
            }
            mesh.draw()?;
            let mut legend = false;
            for (j, ((label, _), runs)) in panel.series.iter().zip(&drawn).enumerate() {
                let c = PALETTE[j % PALETTE.len()];
                let mut labelled = false;
                for pts in runs.iter().filter(|r| !r.is_empty()) {
                    let line = chart
                        .draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(1)))?;
                    if label.is_empty() || labelled {
                        continue;
                    }
                    labelled = true;
                    legend = true;
                    line.label(*label).legend(line_key(20, c.stroke_width(2)));
                }
            }
            if ye.is_empty() {
                draw_no_data(&mut chart)?;
            }
            if legend {
                // With bands the top is taken by their labels.
                let corner = if bands.is_empty() {
                    SeriesLabelPosition::UpperRight
                } else {
                    SeriesLabelPosition::LowerRight
                };
                draw_legend(&mut chart, Legend::at(corner, 14))?;
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::figures::kit::testing::{drawn, near, tinted, Image};
    use crate::figures::kit::ChartLayout;

    fn has(img: &Image, l: &ChartLayout, at: (f64, f64), r: i32, c: RGBColor) -> bool {
        img.any_near(l.pixel(at), r, |p| near(p, c, 30))
    }

    /// How many of `pts` have colour `c` drawn within 2 px (blended along a steep line's
    /// edges, at least half opaque).
    fn drawn_at(img: &Image, l: &ChartLayout, pts: &[(f64, f64)], c: RGBColor) -> usize {
        pts.iter()
            .filter(|&&p| img.any_near(l.pixel(p), 2, |px| tinted(px, c, 0.5)))
            .count()
    }

    /// The dashed reference lines' grey (also over a band), or black.
    fn dark(p: [u8; 3]) -> bool {
        p.iter().all(|&c| c < 140)
    }

    fn colour_count(img: &Image, l: &ChartLayout, c: RGBColor) -> usize {
        img.count(l.plot, |p| near(p, c, 30))
    }

    fn regimes() -> Vec<RegimeBand<'static>> {
        vec![
            RegimeBand {
                x0: 0.0,
                x1: 8.6,
                label: "flying",
            },
            RegimeBand {
                x0: 8.6,
                x1: 9.9,
                label: "mobile lubricant",
            },
            RegimeBand {
                x0: 9.9,
                x1: 11.4,
                label: "bonded lubricant",
            },
            RegimeBand {
                x0: 11.4,
                x1: 15.0,
                label: "solid contact",
            },
        ]
    }

    #[test]
    fn clearance_sweep_normal_and_degenerate() {
        let dir = tempfile::tempdir().unwrap();
        let t0 = 1.2;
        let clearance: Vec<(f64, f64, f64)> = (0..=75)
            .map(|i| {
                let h = 0.2 * i as f64;
                let c = if h < 8.6 {
                    11.0 - h
                } else {
                    (2.4 - 0.4 * (h - 8.6)).max(-0.6)
                };
                (h, c, 0.05 + 0.02 * (h - 7.0).abs().min(3.0))
            })
            .collect();
        let fh: Vec<(f64, f64, f64)> = clearance.iter().map(|&(h, c, s)| (h, c + t0, s)).collect();
        let series = [
            SweepSeries {
                label: "clearance",
                points: clearance,
            },
            SweepSeries {
                label: "FH",
                points: fh,
            },
        ];
        let hlines = [(0.0, "c = 0"), (t0, "T0"), (2.0 * t0, "2T0")];
        let p = dir.path().join("clearance.png");
        let (img, l) = drawn(&p, || {
            clearance_sweep_png(
                &p,
                "clearance vs actuation",
                "h_TFC (nm)",
                "clearance (nm)",
                &series,
                &regimes(),
                &hlines,
            )
        });
        let l = l[0];
        // Every mean is on its series' line (the legend may hide a few).
        for (k, s) in series.iter().enumerate() {
            let pts: Vec<(f64, f64)> = s.points.iter().map(|p| (p.0, p.1)).collect();
            let on = drawn_at(&img, &l, &pts, PALETTE[k]);
            assert!(
                on * 10 >= pts.len() * 9,
                "{}: {on} of {}",
                s.label,
                pts.len()
            );
        }
        // The clearance line crosses the zero line where the data say (2.4 nm at 8.6 nm,
        // falling 0.4 nm per nm: 14.6 nm), and not before.
        assert!(has(&img, &l, (14.6, 0.0), 1, PALETTE[0]));
        let (x0, y0) = l.pixel((14.0, 0.0));
        assert!(!img.any_near((x0, y0), 1, |p| near(p, PALETTE[0], 30)));
        // The dashed references at T0 and 2T0, clear of the data at 2–4 nm.
        for y in [t0, 2.0 * t0] {
            let (xa, ya) = l.pixel((2.0, y));
            let (xb, _) = l.pixel((4.0, y));
            let dashes = img.count((xa, ya - 1, xb, ya + 2), dark);
            assert!(dashes > 10, "T line at {y}: {dashes}");
        }
        // The regime bands shade their x intervals (above the data, below the labels).
        for (k, x) in [4.1, 9.25, 10.65, 13.1].into_iter().enumerate() {
            assert!(has(&img, &l, (x, 7.3), 0, BAND_FILLS[k]), "band {k} at {x}");
        }

        let nan = f64::NAN;
        let degenerate: [(&str, Vec<SweepSeries>); 4] = [
            ("empty", vec![]),
            (
                "empty-series",
                vec![SweepSeries {
                    label: "none",
                    points: vec![],
                }],
            ),
            (
                "all-nan",
                vec![SweepSeries {
                    label: "nan",
                    points: vec![(nan, nan, nan), (1.0, nan, 0.1), (nan, 2.0, 0.1)],
                }],
            ),
            (
                "constant",
                vec![SweepSeries {
                    label: "const",
                    points: vec![
                        (3.0, 1e-9, 0.0),
                        (3.0, 1e-9, nan),
                        (3.0, 1e-9, f64::INFINITY),
                    ],
                }],
            ),
        ];
        for (name, s) in &degenerate {
            for (bands, lines) in [(vec![], vec![]), (regimes(), hlines.to_vec())] {
                let p = dir
                    .path()
                    .join(format!("clearance-{name}-{}.png", bands.len()));
                let (img, l) = drawn(&p, || {
                    clearance_sweep_png(&p, name, "x", "y", s, &bands, &lines)
                });
                let l = l[0];
                if *name == "constant" {
                    // One usable point: a marker, where it is.
                    assert!(has(&img, &l, (3.0, 1e-9), 1, PALETTE[0]));
                } else {
                    assert_eq!(colour_count(&img, &l, PALETTE[0]), 0, "{name}");
                }
            }
        }
        // Bands and lines that are themselves degenerate.
        let p = dir.path().join("clearance-bad-bands.png");
        let bad = [
            RegimeBand {
                x0: nan,
                x1: 1.0,
                label: "nan",
            },
            RegimeBand {
                x0: 5.0,
                x1: 5.0,
                label: "",
            },
            RegimeBand {
                x0: 1e9,
                x1: 2e9,
                label: "outside",
            },
        ];
        let (img, l) = drawn(&p, || {
            clearance_sweep_png(
                &p,
                "t",
                "x",
                "y",
                &series,
                &bad,
                &[(nan, "nan"), (1e308, "huge")],
            )
        });
        // The bad bands and lines leave the data where it was.
        let l = l[0];
        let pts: Vec<(f64, f64)> = series[0].points.iter().map(|p| (p.0, p.1)).collect();
        assert!(drawn_at(&img, &l, &pts, PALETTE[0]) * 10 >= pts.len() * 9);
        assert!(l.y.hi < 100.0, "{:?}", l.y);
    }

    #[test]
    fn metric_sweep_normal_and_degenerate() {
        let dir = tempfile::tempdir().unwrap();
        let fhm: Vec<(f64, f64)> = (0..=75)
            .map(|i| {
                let h = 0.2 * i as f64;
                (
                    h,
                    if h < 9.7 {
                        4.0 + 0.1 * h
                    } else {
                        40.0 * (h - 9.0)
                    },
                )
            })
            .collect();
        let solid: Vec<(f64, f64)> = fhm
            .iter()
            .map(|&(h, _)| (h, (h - 9.7).max(0.0) * 12.0))
            .collect();
        let p = dir.path().join("metric.png");
        let series = [("FHM/BV", fhm), ("% solid contact", solid)];
        let (img, l) = drawn(&p, || {
            metric_sweep_png(
                &p,
                "FHM/BV vs actuation",
                "h_TFC (nm)",
                "FHM / BV (%)",
                &series,
                &[(9.7, "touchdown"), (8.5, "critical point"), (9.8, "close")],
            )
        });
        let l = l[0];
        for (k, (label, pts)) in series.iter().enumerate() {
            let on = drawn_at(&img, &l, pts, PALETTE[k]);
            assert!(on * 10 >= pts.len() * 9, "{label}: {on} of {}", pts.len());
        }
        // The touchdown mark's dashed line stands at 9.7 nm, the critical point's at 8.5 nm.
        for x in [8.5, 9.7] {
            let (px, _) = l.pixel((x, 0.0));
            let (_, mid) = l.pixel((x, 120.0));
            let dashes = img.count((px - 1, mid - 60, px + 2, mid + 60), dark);
            assert!(dashes > 30, "mark at {x}: {dashes}");
        }
        let (px, _) = l.pixel((7.0, 0.0));
        let (_, mid) = l.pixel((7.0, 120.0));
        assert_eq!(img.count((px - 1, mid - 60, px + 2, mid + 60), dark), 0);

        let nan = f64::NAN;
        type Named = Vec<(&'static str, Vec<(f64, f64)>)>;
        let cases: [(&str, Named); 4] = [
            ("empty", vec![]),
            ("empty-series", vec![("none", vec![])]),
            (
                "all-nan",
                vec![("nan", vec![(nan, 1.0), (2.0, nan), (nan, nan)])],
            ),
            (
                "constant",
                vec![("const", vec![(1.0, 0.0), (1.0, 0.0), (1.0, 0.0)])],
            ),
        ];
        for (name, s) in &cases {
            for marks in [vec![], vec![(nan, "nan"), (4.0, "td")]] {
                let p = dir
                    .path()
                    .join(format!("metric-{name}-{}.png", marks.len()));
                let (img, l) = drawn(&p, || metric_sweep_png(&p, name, "x", "y", s, &marks));
                let l = l[0];
                if *name == "constant" {
                    assert!(has(&img, &l, (1.0, 0.0), 1, PALETTE[0]));
                } else {
                    assert_eq!(colour_count(&img, &l, PALETTE[0]), 0, "{name}");
                }
                // The x range takes in the usable mark.
                if !marks.is_empty() {
                    assert!(l.x.lo < 4.0 && 4.0 < l.x.hi, "{name}: {:?}", l.x);
                }
            }
        }
    }

    #[test]
    fn time_histories_normal_and_degenerate() {
        let dir = tempfile::tempdir().unwrap();
        // 8000 samples at 0.25 µs: a 2 ms history, times in ms.
        let t: Vec<f64> = (0..8000).map(|i| i as f64 * 0.25e-3).collect();
        let wave = |f: f64, a: f64, off: f64| -> Vec<(f64, f64)> {
            t.iter()
                .map(|&ti| (ti, off + a * (2.0 * std::f64::consts::PI * f * ti).sin()))
                .collect()
        };
        let panels = vec![
            Panel {
                y_desc: "clearance (nm)",
                series: vec![
                    ("9.7 nm", wave(110.0, 0.3, 1.0)),
                    ("12 nm", wave(110.0, 0.2, -0.3)),
                ],
            },
            Panel {
                y_desc: "force (mN)",
                series: vec![("F_c", wave(10.7, 1.0, 2.0)), ("Q", wave(10.7, 0.3, 0.6))],
            },
            Panel {
                y_desc: "μ",
                series: vec![("μ", wave(50.0, 0.05, 0.3))],
            },
        ];
        let p = dir.path().join("histories.png");
        let start = std::time::Instant::now();
        let (img, l) = drawn(&p, || time_histories_png(&p, "time histories", &panels));
        // Generous: the point is that 8000-point series do not draw point by point.
        assert!(start.elapsed().as_secs_f64() < 20.0);
        // Stacked panels on one time axis, each series on its data (decimated or not).
        assert_eq!(l.len(), 3);
        for (panel, layout) in panels.iter().zip(&l) {
            assert_eq!((layout.x.lo, layout.x.hi), (l[0].x.lo, l[0].x.hi));
            for (k, (label, pts)) in panel.series.iter().enumerate() {
                let picks: Vec<(f64, f64)> = pts.iter().step_by(83).copied().collect();
                let on = drawn_at(&img, layout, &picks, PALETTE[k]);
                assert!(
                    on * 10 >= picks.len() * 9,
                    "{label}: {on} of {}",
                    picks.len()
                );
            }
        }
        assert!(l[0].plot.3 <= l[1].plot.1 && l[1].plot.3 <= l[2].plot.1);

        let nan = f64::NAN;
        let cases: Vec<(&str, Vec<Panel>)> = vec![
            ("no-panels", vec![]),
            (
                "empty-series",
                vec![
                    Panel {
                        y_desc: "a",
                        series: vec![],
                    },
                    Panel {
                        y_desc: "b",
                        series: vec![("none", vec![])],
                    },
                ],
            ),
            (
                "all-nan",
                vec![Panel {
                    y_desc: "nan",
                    series: vec![("nan", vec![(nan, nan); 10_000])],
                }],
            ),
            (
                "constant",
                vec![
                    Panel {
                        y_desc: "const",
                        series: vec![("c", t.iter().map(|&x| (x, 5e-9)).collect())],
                    },
                    Panel {
                        y_desc: "same t",
                        series: vec![("c", vec![(1.0, 0.0); 5000])],
                    },
                ],
            ),
        ];
        for (name, panels) in &cases {
            let p = dir.path().join(format!("hist-{name}.png"));
            let (img, l) = drawn(&p, || time_histories_png(&p, name, panels));
            assert_eq!(l.len(), panels.len().max(1), "{name}");
            if *name == "constant" {
                // 5 nm-ish constant over 2 ms: a flat line at its value.
                assert!(has(&img, &l[0], (1.0, 5e-9), 1, PALETTE[0]));
            } else {
                for layout in &l {
                    assert_eq!(colour_count(&img, layout, PALETTE[0]), 0, "{name}");
                }
            }
        }
    }

    #[test]
    fn runs_split_at_gaps_and_bands_draw() {
        let nan = f64::NAN;
        let pts = [
            (0.0, 1.0),
            (1.0, nan),
            (2.0, 2.0),
            (3.0, 3.0),
            (nan, 0.0),
            (5.0, 5.0),
        ];
        let runs: Vec<usize> = finite_runs(&pts).map(<[_]>::len).collect();
        assert_eq!(runs, vec![1, 2, 1]);
        assert_eq!(finite_runs(&[(nan, nan)]).count(), 0);

        let dir = tempfile::tempdir().unwrap();
        let t: Vec<f64> = (0..4000).map(|i| i as f64 * 0.5e-3).collect();
        // μ defined only while loaded: a gappy series must draw (as separate runs).
        let mu: Vec<(f64, f64)> = t
            .iter()
            .map(|&x| (x, if (0.6..1.4).contains(&x) { 1.2 } else { nan }))
            .collect();
        let panels = vec![
            Panel {
                y_desc: "spacing (nm)",
                series: vec![("bulge", t.iter().map(|&x| (x, (5.0 * x).sin())).collect())],
            },
            Panel {
                y_desc: "μ",
                series: vec![("μ", mu)],
            },
        ];
        let bands = [
            RegimeBand {
                x0: 0.0,
                x1: 0.45,
                label: "flying",
            },
            RegimeBand {
                x0: 0.45,
                x1: 0.6,
                label: "jump to contact",
            },
            RegimeBand {
                x0: nan,
                x1: 1.0,
                label: "skipped",
            },
            RegimeBand {
                x0: 0.6,
                x1: 1.4,
                label: "steady contact",
            },
        ];
        let p = dir.path().join("banded.png");
        let (img, l) = drawn(&p, || {
            time_histories_banded_png(&p, "banded", &panels, &bands)
        });
        // μ drawn while loaded, a gap (band colour) elsewhere: not bridged across 0–0.6 ms.
        let mu = &l[1];
        assert!(has(&img, mu, (1.0, 1.2), 1, PALETTE[0]));
        assert!(!has(&img, mu, (0.3, 1.2), 2, PALETTE[0]));
        // The bands behind both panels; the NaN one skipped (its index keeps its colour).
        for layout in &l {
            let (_, y) = layout.pixel((0.0, layout.y.lo));
            let row = y - 3;
            let at = |t: f64| img.at(layout.pixel((t, 0.0)).0, row).unwrap();
            // (A light grid line may cross: 15 levels of tolerance.)
            assert!(near(at(0.23), BAND_FILLS[0], 15), "{:?}", at(0.23));
            assert!(near(at(0.53), BAND_FILLS[1], 15), "{:?}", at(0.53));
            assert!(
                near(at(1.87), RGBColor(255, 255, 255), 15),
                "{:?}",
                at(1.87)
            );
        }
    }
}
