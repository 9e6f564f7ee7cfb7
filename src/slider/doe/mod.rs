//! The DOE's machinery below the `[doe]` stage (dissertation §2.3; docs/doe.md): its settings,
//! one design case through the 2-DOF case cache, the response surfaces per actuation level,
//! the annealing, sensitivity check and Table 2.8 comparison, and the tables and figures the
//! stage writes. The design's case list is `slider::doe_design`.
pub mod cases;
pub mod figures;
pub mod optimise;
pub mod params;
pub mod surface;
pub mod tables;
