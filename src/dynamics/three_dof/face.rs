//! Flat faces of the 3-DOF slider (docs/dynamics-3dof-geometry.md, "Truncation"): the part
//! of a body-plane rectangle whose world altitude lies within the truncation height of its
//! lowest corner, by one Sutherland–Hodgman clip against a line and the shoelace formula.

use nalgebra::Vector3;

use crate::dynamics::geometry::Attitude;

/// An axis-aligned rectangle in the body plane `z = const` (m, relative to the COM).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyRectangle {
    pub x_min: f64,
    pub x_max: f64,
    pub y_min: f64,
    pub y_max: f64,
    pub z: f64,
}

impl BodyRectangle {
    pub fn area(&self) -> f64 {
        (self.x_max - self.x_min) * (self.y_max - self.y_min)
    }

    /// The corner with the lowest world altitude at `attitude` (ties → smaller x / y).
    pub fn lowest_corner(&self, attitude: &Attitude) -> Vector3<f64> {
        let n = attitude.body_vertical();
        let x = if n.x < 0.0 { self.x_max } else { self.x_min };
        let y = if n.y < 0.0 { self.y_max } else { self.y_min };
        Vector3::new(x, y, self.z)
    }
}

/// Area of the part of `rect` whose world altitude lies within `truncation_height` above its
/// lowest corner (§2.4 "truncation of cuboids"): the rectangle clipped by the half-plane
/// `n_x (x − x_c) + n_y (y − y_c) ≤ h_T` (Sutherland–Hodgman against one line), measured by the
/// shoelace formula in body coordinates (projection factor `cosθ cosφ` ignored). Zero for
/// `h_T ≤ 0`; the whole rectangle when the face is level.
pub fn truncated_rectangle_area(
    rect: &BodyRectangle,
    attitude: &Attitude,
    truncation_height: f64,
) -> f64 {
    if truncation_height.is_nan() || truncation_height <= 0.0 {
        return 0.0;
    }
    let n = attitude.body_vertical();
    let c = rect.lowest_corner(attitude);
    // Local coordinates from (x_min, y_min) keep the µm-scale geometry exact.
    let (wx, wy) = (rect.x_max - rect.x_min, rect.y_max - rect.y_min);
    let (cx, cy) = (c.x - rect.x_min, c.y - rect.y_min);
    let height = |x: f64, y: f64| n.x * (x - cx) + n.y * (y - cy);
    let corners = [(0.0, 0.0), (wx, 0.0), (wx, wy), (0.0, wy)];
    let mut clipped = [(0.0_f64, 0.0_f64); 8];
    let mut len = 0;
    for i in 0..4 {
        let (x0, y0) = corners[i];
        let (x1, y1) = corners[(i + 1) % 4];
        let (g0, g1) = (height(x0, y0), height(x1, y1));
        let (in0, in1) = (g0 <= truncation_height, g1 <= truncation_height);
        if in0 {
            clipped[len] = (x0, y0);
            len += 1;
        }
        if in0 != in1 {
            let t = (truncation_height - g0) / (g1 - g0);
            clipped[len] = (x0 + t * (x1 - x0), y0 + t * (y1 - y0));
            len += 1;
        }
    }
    shoelace_area(&clipped[..len])
}

/// Area of a simple polygon (any orientation).
fn shoelace_area(vertices: &[(f64, f64)]) -> f64 {
    let k = vertices.len();
    if k < 3 {
        return 0.0;
    }
    let twice: f64 = (0..k)
        .map(|i| {
            let (x0, y0) = vertices[i];
            let (x1, y1) = vertices[(i + 1) % k];
            x0 * y1 - x1 * y0
        })
        .sum();
    0.5 * twice.abs()
}
