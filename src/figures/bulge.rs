//! The TFC-bulge figures (App. C.2; docs/bulge.md): the levelled profilometer map with the
//! fitted ellipse outline and the regions left out, the three scan lines across the bulge with
//! the fitted cap (Fig. C.5 style), and the bulge height against heater power with the
//! efficiency line.

use super::basic::{heatmap_overlay_png, lines_png, HEIGHT_NM};
use super::kit::{dashed_line, draw_polyline, Result};
use crate::surface::bulge::{BulgeFit, Rect};
use ndarray::ArrayView2;
use plotters::prelude::*;
use std::path::Path;

/// The fitted ellipsoidal cap (metres): z = offset + h·√(1 − u² − v²), u = (x − x_c)/a,
/// v = (y − y_c)/(w/2) (docs/bulge.md), 0 outside the outline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cap {
    pub height: f64,
    pub a: f64,
    pub w: f64,
    pub xc: f64,
    pub yc: f64,
    pub offset: f64,
}

impl From<&BulgeFit> for Cap {
    fn from(f: &BulgeFit) -> Self {
        Cap {
            height: f.height,
            a: f.a,
            w: f.w,
            xc: f.xc,
            yc: f.yc,
            offset: f.offset,
        }
    }
}

impl Cap {
    pub fn at(&self, x: f64, y: f64) -> f64 {
        let u = (x - self.xc) / self.a;
        let v = 2.0 * (y - self.yc) / self.w;
        self.offset + self.height * (1.0 - u * u - v * v).max(0.0).sqrt()
    }

    /// `n` points of the outline x_c + a·cos t, y_c + (w/2)·sin t (closed: the last repeats
    /// the first), metres.
    pub fn outline(&self, n: usize) -> Vec<(f64, f64)> {
        let n = n.max(3);
        (0..=n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                (self.xc + self.a * t.cos(), self.yc + 0.5 * self.w * t.sin())
            })
            .collect()
    }
}

/// Map coordinates (metres from the first pixel) → heat-map plot coordinates (µm): pixel
/// (j, i) is drawn as the cell whose top-left corner is (i·dx, H − j·dy), so its centre — where
/// the fit put it — sits half a cell right of and below that corner.
pub fn plot_xy(x: f64, y: f64, dx: f64, dy: f64, ny: usize) -> (f64, f64) {
    let h_um = ny as f64 * dy * 1e6;
    ((x + 0.5 * dx) * 1e6, h_um - (y + 0.5 * dy) * 1e6)
}

/// The trailing-edge mask as a rectangle (metres): from `te_margin` before the detected edge
/// to the map border on the far side (docs/bulge.md step 1).
pub fn te_mask(fit: &BulgeFit, te_margin: f64) -> Option<Rect> {
    let te = fit.trailing_edge?;
    let lev = fit.levelled.as_ref()?;
    let (w, h) = (lev.nx() as f64 * lev.dx, lev.ny() as f64 * lev.dy);
    let (x0, x1) = if te.slider_below {
        ((te.x - te_margin).max(0.0), w)
    } else {
        (0.0, (te.x + te_margin).min(w))
    };
    Some(Rect {
        x0,
        y0: 0.0,
        width: x1 - x0,
        height: h,
    })
}

/// One scan line across the bulge: the row nearest `y_c + offset`, its analysed pixels and
/// the fitted cap on them (x, z in metres).
#[derive(Debug, Clone, PartialEq)]
pub struct ScanLine {
    pub offset: f64,
    pub row: usize,
    pub measured: Vec<(f64, f64)>,
    pub fitted: Vec<(f64, f64)>,
}

/// The rows through the fitted centre and ±6 µm across it (Fig. C.5); `shown` is the levelled
/// map with masked pixels NaN. Rows outside the map are skipped.
pub fn scan_lines(shown: ArrayView2<f64>, dx: f64, dy: f64, cap: &Cap) -> Vec<ScanLine> {
    let (ny, nx) = shown.dim();
    let mut out = Vec::new();
    for offset in [-6e-6, 0.0, 6e-6] {
        let j = ((cap.yc + offset) / dy).round();
        if !(j >= 0.0 && (j as usize) < ny) {
            continue;
        }
        let row = j as usize;
        let y = row as f64 * dy;
        let cols: Vec<usize> = (0..nx).filter(|&i| shown[[row, i]].is_finite()).collect();
        out.push(ScanLine {
            offset,
            row,
            measured: cols
                .iter()
                .map(|&i| (i as f64 * dx, shown[[row, i]]))
                .collect(),
            fitted: cols
                .iter()
                .map(|&i| {
                    let x = i as f64 * dx;
                    (x, cap.at(x, y))
                })
                .collect(),
        });
    }
    out
}

/// The levelled line scans of a line-scan fit (`row` = the line's index) and the fitted cap
/// along each at its offset.
pub fn offset_lines(fit: &BulgeFit) -> Vec<ScanLine> {
    let cap = Cap::from(fit);
    fit.lines
        .iter()
        .enumerate()
        .map(|(row, l)| {
            let pts: Vec<(f64, f64)> =
                l.x.iter()
                    .zip(&l.z)
                    .filter(|(_, z)| z.is_finite())
                    .map(|(x, z)| (*x, *z))
                    .collect();
            // Without a fitted width only the centre line is defined (v = 0 there).
            let y = if cap.w.is_finite() { l.offset } else { 0.0 };
            ScanLine {
                offset: l.offset,
                row,
                fitted: pts.iter().map(|&(x, _)| (x, cap.at(x, y))).collect(),
                measured: pts,
            }
        })
        .collect()
}

fn rect_path(r: &Rect, dx: f64, dy: f64, ny: usize) -> Vec<(f64, f64)> {
    // Rectangles bound pixel centres: draw them through the same mapping as the pixels.
    let c = |x: f64, y: f64| plot_xy(x, y, dx, dy, ny);
    let (x1, y1) = (r.x0 + r.width, r.y0 + r.height);
    vec![
        c(r.x0, r.y0),
        c(x1, r.y0),
        c(x1, y1),
        c(r.x0, y1),
        c(r.x0, r.y0),
    ]
}

/// The levelled map (masked pixels blank) with the fitted outline (red), the exclusion
/// rectangles (black) and the trailing-edge mask (dashed) drawn over it; the title says so
/// (a legend box would hide part of the map).
pub fn levelled_map_png(
    path: &Path,
    fit: &BulgeFit,
    shown: ArrayView2<f64>,
    exclude: &[Rect],
    te_margin: f64,
    title: &str,
) -> Result<()> {
    // A line-scan fit has no map to draw (its lines are `offset_lines`).
    let Some(lev) = fit.levelled.as_ref() else {
        return Ok(());
    };
    let (dx, dy, ny) = (lev.dx, lev.dy, lev.ny());
    let cap = Cap::from(fit);
    let outline: Vec<(f64, f64)> = cap
        .outline(180)
        .into_iter()
        .map(|(x, y)| plot_xy(x, y, dx, dy, ny))
        .collect();
    let te = te_mask(fit, te_margin).map(|r| rect_path(&r, dx, dy, ny));
    let rects: Vec<Vec<(f64, f64)>> = exclude.iter().map(|r| rect_path(r, dx, dy, ny)).collect();
    let title = format!("{title} — red: fit, dashed: TE mask");
    heatmap_overlay_png(path, shown, dx, dy, &title, HEIGHT_NM, |chart| {
        draw_polyline(chart, &outline, RED.stroke_width(2))?;
        for r in &rects {
            draw_polyline(chart, r, BLACK.stroke_width(2))?;
        }
        if let Some(t) = te {
            chart.draw_series(dashed_line(t))?;
        }
        Ok(())
    })
}

/// The three scan lines (Fig. C.5): measured points and the fitted cap on each, x in µm,
/// heights in nm.
pub fn scan_lines_png(path: &Path, lines: &[ScanLine], title: &str) -> Result<()> {
    let scaled = |v: &[(f64, f64)]| -> Vec<(f64, f64)> {
        v.iter().map(|(x, z)| (x * 1e6, z * 1e9)).collect()
    };
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for l in lines {
        let d = l.offset * 1e6;
        series.push((format!("scan y_c {d:+.0} µm"), scaled(&l.measured)));
        series.push((format!("fit y_c {d:+.0} µm"), scaled(&l.fitted)));
    }
    let refs: Vec<(&str, Vec<(f64, f64)>)> = series
        .iter()
        .map(|(n, v)| (n.as_str(), v.clone()))
        .collect();
    lines_png(path, title, "x along the slider (µm)", "height (nm)", &refs)
}

/// Bulge height against heater power (W, m) with the efficiency line from zero power; the
/// legend names the efficiency and the intercept (the unpowered bulge).
pub fn height_vs_power_png(
    path: &Path,
    points: &[(f64, f64)],
    efficiency: f64,
    intercept: f64,
) -> Result<()> {
    let pts: Vec<(f64, f64)> = points.iter().map(|(p, h)| (p * 1e3, h * 1e9)).collect();
    let pmax = pts.iter().map(|p| p.0).fold(0.0, f64::max);
    let line = vec![
        (0.0, intercept * 1e9),
        (pmax, (intercept + efficiency * pmax * 1e-3) * 1e9),
    ];
    let name = format!(
        "fit: {:.3} nm/mW, intercept {:.2} nm",
        efficiency * 1e6,
        intercept * 1e9
    );
    // Lines with markers, the fitted heights drawn last so the efficiency line cannot hide them.
    super::sweep::metric_sweep_png(
        path,
        "Bulge height against heater power",
        "heater power (mW)",
        "bulge height (nm)",
        &[(name.as_str(), line), ("fitted heights", pts)],
        &[],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outline_lies_on_the_ellipse_and_on_the_right_pixels() {
        let cap = Cap {
            height: 20e-9,
            a: 4.86e-6,
            w: 50e-6,
            xc: 30e-6,
            yc: 40e-6,
            offset: 1e-9,
        };
        for (x, y) in cap.outline(64) {
            let u = (x - cap.xc) / cap.a;
            let v = (y - cap.yc) / (0.5 * cap.w);
            assert!((u * u + v * v - 1.0).abs() < 1e-12);
            // On the outline the cap is down to its offset.
            assert!((cap.at(x, y) - cap.offset).abs() < 1e-3 * cap.height);
        }
        // The extreme points are x_c ± a and y_c ± w/2.
        let o = cap.outline(4);
        assert!((o[0].0 - (cap.xc + cap.a)).abs() < 1e-18);
        assert!((o[1].1 - (cap.yc + 0.5 * cap.w)).abs() < 1e-18);
        // Pixel (j, i) = (2, 3) of a 10-row map, dx = 0.5 µm, dy = 1 µm: drawn as the cell
        // with top-left corner (1.5 µm, 8 µm), centre (1.75 µm, 7.5 µm).
        let (px, py) = plot_xy(3.0 * 0.5e-6, 2.0 * 1e-6, 0.5e-6, 1e-6, 10);
        assert!((px - 1.75).abs() < 1e-12 && (py - 7.5).abs() < 1e-12);
    }

    #[test]
    fn scan_lines_are_the_map_rows_and_the_cap_on_them() {
        // A map that is exactly the cap, with one masked pixel on the centre row.
        let (dx, dy) = (0.5e-6, 1e-6);
        let cap = Cap {
            height: 12e-9,
            a: 5e-6,
            w: 30e-6,
            xc: 10e-6,
            yc: 20e-6,
            offset: 0.0,
        };
        let mut z =
            ndarray::Array2::from_shape_fn((40, 40), |(j, i)| cap.at(i as f64 * dx, j as f64 * dy));
        z[[20, 5]] = f64::NAN;
        let lines = scan_lines(z.view(), dx, dy, &cap);
        assert_eq!(
            lines.iter().map(|l| l.row).collect::<Vec<_>>(),
            vec![14, 20, 26]
        );
        assert_eq!(lines[1].measured.len(), 39);
        for l in &lines {
            assert_eq!(l.measured, l.fitted);
        }
        // The centre row peaks at the apex (x_c = 10 µm is column 20); the ±6 µm rows at
        // h·√(1 − (6/15)²) (independent of the code: the ellipse equation by hand).
        let peak = |l: &ScanLine| l.fitted.iter().map(|p| p.1).fold(f64::MIN, f64::max);
        assert!((peak(&lines[1]) - 12e-9).abs() < 1e-18);
        let side = 12e-9 * (1.0f64 - 0.16).sqrt();
        assert!((peak(&lines[0]) - side).abs() < 1e-15);
        assert!((peak(&lines[2]) - side).abs() < 1e-15);
    }
}
