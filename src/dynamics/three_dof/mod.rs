//! The 3-DOF slider model (dissertation chapter 4; docs/three-dof.md):
//! heave `z`, pitch `θ` and roll `φ` of a slider carrying a constant TFC bulge on an actuated
//! base, contact pads and recessed TE/LE corners. Pure physics, no I/O, SI units.
//!
//! * [`geometry`] — the Table 4.3 slider geometry, its possible points of contact (bulge, base
//!   corners, pads, TE/LE corners; §2.5) with their DMW tracks (§6), lever arms, solid spacings
//!   anchored at the nominal state (§5.2) and spacing rates (§5.3), nominal contact areas by
//!   truncation (§2.4; ellipsoid section, spherical cap, clipped rectangle), the read/write
//!   elements and the pole-tip spacing (§2.6), and an allocation-free per-evaluation fast path.
//! * [`face`] — truncated area of a tilted flat face (rectangle ∩ half-plane, shoelace).
//! * [`inputs`] — actuation profile (S3/S5), impulse shock (S4), the Table 4.4 windows.
//! * [`case`] — one case: equations of motion (z, θ, φ), DMW tracks, shock, histories.
//! * [`air_bearing`] — the AB springs k(PT) by modal inversion, damping, ΔF_AB push-back
//!   calibration (`docs/dynamics-3dof-air-bearing.md`).
//! * [`interface`] — ISBL / MTL forces on one feature from its spacing, rate and area.

pub mod air_bearing;
pub mod case;
pub mod face;
pub mod geometry;
pub mod inputs;
pub mod interface;
