//! Every figure the pipeline draws, and the one plotting kit they share. The only module that
//! uses plotters; it depends on nothing above it (no stage, engine or CLI), takes plain slices
//! and ndarray views, and returns its own [`FigureError`].
//!
//! - `kit` (private): embedded DejaVu font, colours, text styles, legends, boxed
//!   labels, axis extents and padding, decimation of long series, tick and number formatting,
//!   temp-file rendering, and [`marching_squares`] for contours.
//! - [`basic`]: heat map, histogram, lines on linear, log–log and semi-log axes, stacked
//!   panels, category dots (surface, DMW, contact, excitation, calibration stages).
//! - [`bulge`]: the TFC-bulge fit (levelled map with the fitted outline, Fig. C.5 scan lines,
//!   height vs heater power).
//! - [`sweep`]: actuation sweeps and time histories (Figs 2.13–2.22).
//! - [`analysis`]: scalogram, Poincaré return map, phase portrait, amplitude spectrum.
//! - [`doe`]: response-surface contour panels, residual diagnostics, annealing history
//!   (Figs 2.26–2.30).
//!
//! Figures are side outputs: each is written through a temp file and renamed into place, and a
//! failure is an error, never a panic. Adding a figure: a function in the family's file that
//! builds its chart from the kit's pieces (so fonts, colours, legends and tick labels match the
//! others), re-exported here.

mod kit;

pub mod analysis;
pub mod basic;
pub mod bulge;
pub mod contact_bem;
pub mod doe;
pub mod sweep;

pub use analysis::{
    phase_portrait_png, poincare_png, scalogram_png, scalogram_significance_png, spectrum_png,
    SignificanceOverlay,
};
pub use basic::{
    category_dots_png, heatmap_png, histogram_png, lines_png, loglog_png, semilogy_png, stacked_png,
};
pub use doe::{annealing_png, contour_panels_png, residual_panels_png, ContourPanel};
pub use kit::contour::{marching_squares, Polyline};
pub use kit::{FigureError, PlotError, Result};
pub use sweep::{
    clearance_sweep_png, metric_sweep_png, time_histories_banded_png, time_histories_png, Panel,
    RegimeBand, SweepSeries,
};
