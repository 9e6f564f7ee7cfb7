//! Acceptance tests of the 3-DOF geometry (issue 7; §4.1, Tables 4.1–4.3). Every
//! tolerance is stated next to its target.

use nalgebra::Vector3;

use super::*;
use crate::dynamics::geometry::{
    generalised_force, AltitudeAnchor, Attitude, HalfEllipsoid, Slider2DofGeometry,
};
use crate::dynamics::{DynamicsError, NM, UM};

const UM2: f64 = 1e-12;
const SIGMA: f64 = 0.5 * NM;

#[track_caller]
fn assert_rel(what: &str, ours: f64, target: f64, tol: f64) {
    let r = (ours - target).abs() / target.abs();
    assert!(
        r <= tol,
        "{what}: ours {ours:e} vs target {target:e} (rel {r:.2e} > {tol:.1e})"
    );
}

#[track_caller]
fn assert_abs(what: &str, ours: f64, target: f64, tol: f64) {
    let d = (ours - target).abs();
    assert!(
        d <= tol,
        "{what}: ours {ours:e} vs target {target:e} (|diff| {d:.2e} > {tol:.1e})"
    );
}

fn pose(heave: f64, pitch: f64, roll: f64, actuation: f64) -> SliderPose {
    SliderPose {
        heave,
        pitch,
        roll,
        actuation,
    }
}

/// Fig. 4.8 state: h = 20 nm, θ = 100 µrad, φ = −50 µrad.
fn figure_4_8_pose() -> SliderPose {
    pose(0.0, 100e-6, -50e-6, 20.0 * NM)
}

const ATTITUDES: [(f64, f64); 6] = [
    (0.0, 0.0),
    (100e-6, 0.0),
    (100e-6, -50e-6),
    (-300e-6, 200e-6),
    (5e-3, -3e-3),
    (0.05, 0.08),
];

/// `RᵀR = I` to 1e-15 and `det R = 1` to 1e-15 at six attitudes; the fast path's lever arm
/// `r = R p` equals nalgebra's product to 1e-18 m.
#[test]
fn rotation_matrix_is_orthonormal() {
    let g = Slider3DofGeometry::dissertation();
    let mut out = FeaturePoints::new();
    for (pitch, roll) in ATTITUDES {
        let r = Attitude::new(pitch, roll).rotation();
        let err = (r.transpose() * r - nalgebra::Matrix3::identity())
            .abs()
            .max();
        assert!(err < 1e-15, "RᵀR − I = {err:e} at ({pitch}, {roll})");
        assert_abs("det R", r.determinant(), 1.0, 1e-15);
        g.evaluate_features(
            &pose(0.0, pitch, roll, 15.0 * NM),
            &PoseRates::default(),
            &mut out,
        )
        .unwrap();
        for f in out.as_slice() {
            let d = (f.lever_arm - r * f.body_point).abs().max();
            assert!(d < 1e-18, "{:?}: lever arm differs by {d:e} m", f.feature);
        }
    }
}

/// Pure pitch, base not displaced (`h_TFC = b_TFC`): the bulge POC is the 2-DOF closed form,
/// `h_s = sqrt(a² sin²θ + b² cos²θ)` with the POC `a² sinθ/h_s` toward the TE of the centre
/// (0.4975 µm at θ = 100 µrad), and body point, lever arm, spacing and spacing rate equal
/// `Slider2DofGeometry::bulge_poc` (TE anchor at 11 nm) to 1e-18 m (1e-12 relative for the
/// rate).
#[test]
fn bulge_poc_under_pure_pitch_matches_two_dof() {
    let g = Slider3DofGeometry::dissertation();
    let two = Slider2DofGeometry {
        length: g.length,
        thickness: g.thickness,
        bulge: g.bulge,
        nominal_pitch: g.nominal_pitch,
        anchor: AltitudeAnchor::TrailingEdge {
            solid_spacing: g.nominal_spacing,
        },
    };
    let (a, b) = (g.bulge.semi_width_x, g.bulge_height);
    for (heave, pitch) in [(0.0, 100e-6), (0.3 * NM, 300e-6), (-2.0 * NM, -50e-6)] {
        let p = pose(heave, pitch, 0.0, b);
        let rates = PoseRates {
            heave: 1e-3,
            pitch: 2.0,
            roll: 0.0,
            actuation: 0.0,
        };
        let ours = g.feature_point(Feature::Bulge, &p, &rates).unwrap();
        let h_s = (a * a * pitch.sin().powi(2) + b * b * pitch.cos().powi(2)).sqrt();
        let centre = g.bulge_centre(b);
        assert_abs(
            "POC x offset toward the TE",
            centre.x - ours.body_point.x,
            a * a * pitch.sin() / h_s,
            1e-17,
        );
        let reference = two.bulge_poc(heave, pitch, b).unwrap();
        assert_abs("h_s", reference.support_distance, h_s, 1e-22);
        assert!((ours.body_point - reference.body).abs().max() < 1e-18);
        assert!((ours.lever_arm - reference.lever_arm).abs().max() < 1e-18);
        assert_abs(
            "spacing vs 2-DOF",
            ours.solid_spacing,
            reference.solid_spacing,
            1e-18,
        );
        assert_rel(
            "spacing rate vs 2-DOF",
            ours.spacing_rate,
            reference.spacing_rate(pitch, rates.heave, rates.pitch, 0.0),
            1e-12,
        );
    }
    let at_nominal = g
        .feature_point(
            Feature::Bulge,
            &pose(0.0, 100e-6, 0.0, b),
            &PoseRates::default(),
        )
        .unwrap();
    assert_rel(
        "POC offset at 100 µrad (µm)",
        (g.bulge_centre(b).x - at_nominal.body_point.x) / UM,
        0.4975,
        1e-4,
    );
}

/// Lowest altitude of the lower half-ellipsoid relative to its centre, by a nested golden-section
/// search on the parametric surface (independent of the closed form).
fn brute_force_lowest_altitude(semi_axes: &Vector3<f64>, n: &Vector3<f64>) -> f64 {
    let altitude = |alpha: f64, beta: f64| {
        let (sa, ca) = alpha.sin_cos();
        let (sb, cb) = beta.sin_cos();
        n.x * semi_axes.x * ca * sb + n.y * semi_axes.y * sa * sb + n.z * semi_axes.z * cb
    };
    let golden = |f: &dyn Fn(f64) -> f64, mut lo: f64, mut hi: f64| {
        let r = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..90 {
            let (m1, m2) = (hi - r * (hi - lo), lo + r * (hi - lo));
            if f(m1) < f(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        0.5 * (lo + hi)
    };
    // The minimum lies near β = π (bottom); α free in [−π, π].
    let best_beta = |alpha: f64| golden(&|beta| altitude(alpha, beta), 0.5 * PI_, 1.5 * PI_);
    let alpha = golden(&|alpha| altitude(alpha, best_beta(alpha)), -PI_, PI_);
    altitude(alpha, best_beta(alpha))
}

const PI_: f64 = std::f64::consts::PI;

/// Chapter-4 truncation example (Fig. 4.8): a = 5 µm, b = 5 nm, h = 20 nm,
/// w = 50 µm, x_TFC = 15 µm, θ = 100 µrad, φ = −50 µrad, cut 1.5 nm → A_n = 187.9 µm² (5e-4)
/// through the feature API (both `h_T` and `s ≤ 3σ` entry points), and a grid count of the
/// horizontal cut plane inside the ellipsoid (1601² grid over the footprint, 0.5 %). Also
/// `A_n = 0` for `s ≥ 6σ` and the half-truncated value at `s = 4.5σ`.
#[test]
fn chapter_4_truncation_example() {
    let g = Slider3DofGeometry::dissertation();
    let p = figure_4_8_pose();
    let area = g
        .nominal_contact_area(Feature::Bulge, &p, 1.5 * NM)
        .unwrap();
    assert_rel("A_n (µm²)", area / UM2, 187.9, 5e-4);
    let at_spacing = g
        .nominal_contact_area_at_spacing(Feature::Bulge, &p, 1.0 * NM, SIGMA)
        .unwrap();
    assert_eq!(at_spacing, area);
    assert_eq!(
        g.nominal_contact_area_at_spacing(Feature::Bulge, &p, 3.0 * NM, SIGMA)
            .unwrap(),
        0.0
    );
    let half = g
        .nominal_contact_area_at_spacing(Feature::Bulge, &p, 2.25 * NM, SIGMA)
        .unwrap();
    assert_rel(
        "A_n(h_T = 0.75 nm)",
        half,
        g.nominal_contact_area(Feature::Bulge, &p, 0.75 * NM)
            .unwrap(),
        1e-15,
    );

    // Brute force: world-horizontal grid through the cut, mapped into the body frame.
    let att = p.attitude();
    let r = att.rotation();
    let axes = Vector3::new(5.0 * UM, 25.0 * UM, 5.0 * NM);
    let lowest = brute_force_lowest_altitude(&axes, &att.body_vertical());
    assert_abs("h_s (nm)", -lowest / NM, 5.178, 5e-4);
    let cut = lowest + 1.5 * NM; // altitude of the cut relative to the centre
    let n_grid = 1601;
    let (hx, hy) = (1.2 * axes.x, 1.2 * axes.y);
    let (dx, dy) = (2.0 * hx / n_grid as f64, 2.0 * hy / n_grid as f64);
    let mut inside = 0usize;
    for i in 0..n_grid {
        let x = -hx + (i as f64 + 0.5) * dx;
        for j in 0..n_grid {
            let y = -hy + (j as f64 + 0.5) * dy;
            let q = r.transpose() * Vector3::new(x, y, cut);
            let u = q.component_div(&axes);
            if q.z <= 0.0 && u.norm_squared() <= 1.0 {
                inside += 1;
            }
        }
    }
    let brute = inside as f64 * dx * dy;
    assert_rel("A_n vs grid count", area, brute, 5e-3);
}

/// Grid count (midpoints of an n_x × n_y grid) of the part of `rect` within `h_T` of its lowest
/// corner, the lowest corner found by comparing the four corner altitudes.
fn grid_count_area(rect: &BodyRectangle, att: &Attitude, h_t: f64, n_x: usize, n_y: usize) -> f64 {
    let r = att.rotation();
    let altitude = |x: f64, y: f64| (r * Vector3::new(x, y, rect.z)).z;
    let lowest = [
        (rect.x_min, rect.y_min),
        (rect.x_max, rect.y_min),
        (rect.x_max, rect.y_max),
        (rect.x_min, rect.y_max),
    ]
    .iter()
    .map(|&(x, y)| altitude(x, y))
    .fold(f64::INFINITY, f64::min);
    let (dx, dy) = (
        (rect.x_max - rect.x_min) / n_x as f64,
        (rect.y_max - rect.y_min) / n_y as f64,
    );
    let mut count = 0usize;
    for i in 0..n_x {
        let x = rect.x_min + (i as f64 + 0.5) * dx;
        for j in 0..n_y {
            let y = rect.y_min + (j as f64 + 0.5) * dy;
            if altitude(x, y) - lowest <= h_t {
                count += 1;
            }
        }
    }
    count as f64 * dx * dy
}

/// Flat-face truncation (§2.4) vs a 1500² grid count (1 %; the strip on a 24 200 × 10 grid, 0.1 %) for the base and TE faces at several
/// (θ, φ, h_T), plus exact targets: the zero-roll TE strip 15 µm × 680 µm = 10 200 µm² at
/// θ = 100 µrad, h_T = 1.5 nm (full recessed face, and the sum of the TE± features' halves;
/// 1e-6), a corner-only triangle `h_T²/(2 n_x n_y)` = 1.125 µm² at θ = φ = 1 mrad (1e-6), the
/// whole face when level, and zero at `h_T = 0`.
#[test]
fn flat_face_clipping_matches_grid_count() {
    let g = Slider3DofGeometry::dissertation();
    let h = 20.0 * NM;
    let base = g
        .feature_face(Feature::BaseCorner(Side::MinusY), h)
        .unwrap();
    let te = g
        .feature_face(Feature::TrailingEdgeCorner(Side::PlusY), h)
        .unwrap();
    let cases = [
        (base, 100e-6, -50e-6, 1.5 * NM),
        (base, 100e-6, 20e-6, 0.8 * NM),
        (base, -40e-6, 30e-6, 1.5 * NM),
        (te, 100e-6, -10e-6, 1.5 * NM),
        (te, 20e-6, 5e-6, 1.2 * NM),
        (te, -5e-6, -4e-6, 1.5 * NM),
    ];
    for (rect, pitch, roll, h_t) in cases {
        let att = Attitude::new(pitch, roll);
        let ours = truncated_rectangle_area(&rect, &att, h_t);
        let brute = grid_count_area(&rect, &att, h_t, 1500, 1500);
        assert!(ours > 0.0);
        assert_rel(
            &format!("clipped area at ({pitch}, {roll}, {h_t})"),
            ours,
            brute,
            1e-2,
        );
    }

    // Zero-roll strip across the whole recessed face (§2.4).
    let half_w = 0.5 * g.width - g.recess_inset;
    let full_face = BodyRectangle {
        x_min: -0.5 * g.length + g.recess_inset,
        x_max: 0.5 * g.length - g.recess_inset,
        y_min: -half_w,
        y_max: half_w,
        z: -0.5 * g.thickness + g.recess_depth,
    };
    let flying = Attitude::pitch_only(100e-6);
    let strip = truncated_rectangle_area(&full_face, &flying, 1.5 * NM);
    assert_rel("TE strip (µm²)", strip / UM2, 15.0 * 680.0, 1e-6);
    let p = pose(0.0, 100e-6, 0.0, h);
    let halves: f64 = [Side::PlusY, Side::MinusY]
        .iter()
        .map(|&s| {
            g.nominal_contact_area(Feature::TrailingEdgeCorner(s), &p, 1.5 * NM)
                .unwrap()
        })
        .sum();
    assert_rel("TE± halves (µm²)", halves / UM2, 15.0 * 680.0, 1e-6);
    assert_rel(
        "strip vs grid",
        strip,
        grid_count_area(&full_face, &flying, 1.5 * NM, 24_200, 10),
        1e-3,
    );

    // Corner-only triangle.
    let steep = Attitude::new(1e-3, 1e-3);
    let n = steep.body_vertical();
    let h_t = 1.5 * NM;
    let triangle = truncated_rectangle_area(&base, &steep, h_t);
    assert_rel(
        "corner triangle",
        triangle,
        h_t * h_t / (2.0 * n.x * n.y),
        1e-6,
    );
    assert_rel("corner triangle (µm²)", triangle / UM2, 1.125, 1e-5);
    assert_rel(
        "triangle vs grid",
        triangle,
        grid_count_area(
            &BodyRectangle {
                x_max: base.x_min + 3.0 * UM,
                y_max: base.y_min + 3.0 * UM,
                ..base
            },
            &steep,
            h_t,
            1500,
            1500,
        ),
        1e-2,
    );

    // Level face: everything; no truncation band: nothing.
    assert_rel(
        "level face",
        truncated_rectangle_area(&base, &Attitude::new(0.0, 0.0), 1e-12),
        base.area(),
        1e-12,
    );
    assert_eq!(truncated_rectangle_area(&base, &steep, 0.0), 0.0);
    assert_eq!(
        g.nominal_contact_area_at_spacing(Feature::BaseCorner(Side::PlusY), &p, 3.0 * NM, SIGMA)
            .unwrap(),
        0.0
    );
    // Pads: cap surface 2π R h_T = 9.4248 µm² at 1.5 nm.
    assert_rel(
        "pad cap (µm²)",
        g.nominal_contact_area(Feature::Pad(Side::PlusY), &p, 1.5 * NM)
            .unwrap()
            / UM2,
        2.0 * PI_ * 1e-3 * 1.5e-9 / UM2,
        1e-15,
    );
}

/// Spacing increments (§5.3) vs direct altitude differences `FH_nom + z + n·p − n0·q_TE`: at
/// large attitude changes the direct f64 difference of ~0.15 mm altitudes is itself accurate to
/// ~1e-19 m, so they must agree to 1e-18 m; the TE in the nominal state is exactly FH_nom; every
/// feature's spacing is the spacing of its lowest body point (pads: centre altitude − R_PAD) to
/// 1e-18 m, and no sampled bulge surface point is lower than the POC.
#[test]
fn spacing_increments_match_direct_altitude_differences() {
    let g = Slider3DofGeometry::dissertation();
    let te = g.trailing_edge();
    assert_eq!(
        g.spacing_of(&te, 0.0, g.nominal_pitch, 0.0),
        g.nominal_spacing
    );
    let n0 = Attitude::pitch_only(g.nominal_pitch).body_vertical();
    let mut out = FeaturePoints::new();
    for (pitch, roll) in ATTITUDES {
        for heave in [0.0, 3.0 * NM, -200.0 * NM] {
            let n = Attitude::new(pitch, roll).body_vertical();
            let p = pose(heave, pitch, roll, 12.0 * NM);
            g.evaluate_features(&p, &PoseRates::default(), &mut out)
                .unwrap();
            for f in out.as_slice() {
                let q = f.body_point;
                let direct = g.nominal_spacing + heave + n.dot(&q) - n0.dot(&te);
                let tol = if pitch.abs() > 1e-3 { 1e-18 } else { 2e-18 };
                let ours = g.spacing_of(&q, heave, pitch, roll);
                assert_abs("spacing_of vs direct", ours, direct, tol);
                assert_abs(
                    &format!("{:?} spacing vs its point", f.feature),
                    f.solid_spacing,
                    ours,
                    2e-18,
                );
            }
            let pad = out.get(Feature::Pad(Side::MinusY)).unwrap();
            let centre = Vector3::new(g.pad_x, -g.pad_y, -0.5 * g.thickness + g.pad_radius);
            let direct = g.nominal_spacing + heave + n.dot(&centre) - g.pad_radius - n0.dot(&te);
            assert_abs("pad: centre − R_PAD", pad.solid_spacing, direct, 1e-18);
            let bulge = HalfEllipsoid::new(
                g.bulge_centre(12.0 * NM),
                Vector3::new(5.0 * UM, 25.0 * UM, 5.0 * NM),
            )
            .unwrap();
            let s_poc = out.get(Feature::Bulge).unwrap().solid_spacing;
            for k in 0..50 {
                let alpha = k as f64 * 0.13;
                let beta = PI_ + 0.02 * (k as f64 - 25.0);
                let s = g.spacing_of(&bulge.surface_point(alpha, beta), heave, pitch, roll);
                assert!(s >= s_poc - 1e-18, "surface point below the POC");
            }
        }
    }
}

/// `ṡ` of every feature (§5.3, with `−n_z ḣ` for the bulge and base corners) vs a central
/// difference of the spacing along `pose + rates·t` (dt = 1 µs; 1e-9 m/s on rates of ~1e-3 m/s).
#[test]
fn spacing_rate_matches_finite_difference() {
    let g = Slider3DofGeometry::dissertation();
    let rates = PoseRates {
        heave: 2e-3,
        pitch: 3.0,
        roll: -2.0,
        actuation: 1e-3,
    };
    let dt = 1e-6;
    let at = |p: &SliderPose, t: f64| {
        pose(
            p.heave + rates.heave * t,
            p.pitch + rates.pitch * t,
            p.roll + rates.roll * t,
            p.actuation + rates.actuation * t,
        )
    };
    for base in [
        figure_4_8_pose(),
        pose(1.0 * NM, 300e-6, 100e-6, 12.0 * NM),
        pose(0.0, -200e-6, 0.0, 8.0 * NM),
    ] {
        let (mut now, mut plus, mut minus) = (
            FeaturePoints::new(),
            FeaturePoints::new(),
            FeaturePoints::new(),
        );
        g.evaluate_features(&base, &rates, &mut now).unwrap();
        g.evaluate_features(&at(&base, dt), &rates, &mut plus)
            .unwrap();
        g.evaluate_features(&at(&base, -dt), &rates, &mut minus)
            .unwrap();
        for f in now.as_slice() {
            let fd = (plus.get(f.feature).unwrap().solid_spacing
                - minus.get(f.feature).unwrap().solid_spacing)
                / (2.0 * dt);
            assert_abs(
                &format!("{:?} spacing rate", f.feature),
                f.spacing_rate,
                fd,
                1e-9,
            );
        }
    }
}

/// Lever arms (§1.1, §2.3): a vertical force N at each feature gives heave N, pitch moment
/// `r_x N` (exact) and roll moment `r_y N` (to 1e-8 relative: `cosθ r_y N`); `r = R p`; the bulge
/// sits 0.6 mm (0.1 %) behind the COM, the +y pad's
/// lowest point 0.3 mm (+ R_PAD·|φ|, 2e-4) to its side.
#[test]
fn lever_arms_give_generalised_forces() {
    let g = Slider3DofGeometry::dissertation();
    let p = figure_4_8_pose();
    let att = p.attitude();
    let mut out = FeaturePoints::new();
    g.evaluate_features(&p, &PoseRates::default(), &mut out)
        .unwrap();
    assert_eq!(out.len(), MAX_FEATURES);
    let normal = 1.7e-3;
    for f in out.as_slice() {
        let r = att.world_offset(&f.body_point);
        assert!((r - f.lever_arm).abs().max() < 1e-18);
        let gf = generalised_force(&f.lever_arm, &att, normal, 0.0);
        assert_eq!(gf.heave, normal);
        assert_eq!(gf.pitch_moment, f.lever_arm.x * normal);
        if f.lever_arm.y != 0.0 {
            assert_rel("roll moment", gf.roll_moment, f.lever_arm.y * normal, 1e-8);
        }
    }
    let bulge = out.get(Feature::Bulge).unwrap();
    // Centre 0.6 mm behind the COM; the POC a further ~0.47 µm toward the TE.
    assert_rel("bulge r_x (mm)", bulge.lever_arm.x / 1e-3, -0.6, 1e-3);
    let pad = out.get(Feature::Pad(Side::PlusY)).unwrap();
    // The cap's lowest point moves R_PAD·|φ| = 50 nm toward +y (the lower side): 0.30004 mm.
    assert_rel("pad r_y (mm)", pad.lever_arm.y / 1e-3, 0.3, 2e-4);
}

/// `FeatureSides::Lower` keeps the bulge and only the side with `sign(y) = −sign(φ)` (both at
/// φ = 0); that side is the lower one; DMW tracks are 0 (bulge), 1 (+y), 2 (−y).
#[test]
fn lower_sides_keep_only_the_lower_side() {
    let both = Slider3DofGeometry::dissertation();
    let lower = Slider3DofGeometry {
        sides: FeatureSides::Lower,
        ..both
    };
    let mut out = FeaturePoints::new();
    for (roll, kept) in [(-10e-6, Side::PlusY), (10e-6, Side::MinusY)] {
        let p = pose(0.0, 100e-6, roll, 15.0 * NM);
        lower
            .evaluate_features(&p, &PoseRates::default(), &mut out)
            .unwrap();
        assert_eq!(out.len(), 5);
        assert_eq!(out.as_slice()[0].feature, Feature::Bulge);
        for f in &out.as_slice()[1..] {
            let side = f.feature.side().unwrap();
            assert_eq!(side, kept);
            assert_eq!(side.sign(), -roll.signum());
            let mirror = match f.feature {
                Feature::BaseCorner(_) => Feature::BaseCorner(Side::MinusY),
                Feature::Pad(_) => Feature::Pad(Side::MinusY),
                Feature::TrailingEdgeCorner(_) => Feature::TrailingEdgeCorner(Side::MinusY),
                Feature::LeadingEdgeCorner(_) => Feature::LeadingEdgeCorner(Side::MinusY),
                Feature::Bulge => unreachable!(),
            };
            let mirror = match (mirror, kept) {
                (m, Side::PlusY) => m,
                (Feature::BaseCorner(_), _) => Feature::BaseCorner(Side::PlusY),
                (Feature::Pad(_), _) => Feature::Pad(Side::PlusY),
                (Feature::TrailingEdgeCorner(_), _) => Feature::TrailingEdgeCorner(Side::PlusY),
                (_, _) => Feature::LeadingEdgeCorner(Side::PlusY),
            };
            let other = both
                .feature_point(mirror, &p, &PoseRates::default())
                .unwrap();
            assert!(f.solid_spacing < other.solid_spacing, "{:?}", f.feature);
        }
        assert_eq!(lower.active_features(roll).count(), 5);
        assert_eq!(both.active_features(roll).count(), MAX_FEATURES);
    }
    assert_eq!(lower.active_features(0.0).count(), MAX_FEATURES);
    assert_eq!(Feature::Bulge.dmw_track().index(), 0);
    assert_eq!(Feature::Pad(Side::PlusY).dmw_track().index(), 1);
    assert_eq!(
        Feature::LeadingEdgeCorner(Side::MinusY).dmw_track().index(),
        2
    );
}

/// Read/write elements (§2.6, Table 4.3): β_R = 53.13°, β_W = 126.87° (0.005°), both 1.000 nm
/// above the bulge bottom in the body frame (1e-9 relative); the pole-tip FH is the read point's
/// spacing: at θ = 100 µrad it lies 1 nm + x_R sinθ + (h_s − b) = 1.325 nm above the bulge POC
/// (1e-6 nm; 1e-3 nm on the rounded value), and the write element flies lower.
#[test]
fn read_write_elements_sit_one_nanometre_above_the_bulge_bottom() {
    let g = Slider3DofGeometry::dissertation();
    let h = 20.0 * NM;
    assert_abs(
        "β_R (deg)",
        g.element_angle(g.read_offset).unwrap().to_degrees(),
        53.13,
        5e-3,
    );
    assert_abs(
        "β_W (deg)",
        g.element_angle(-g.write_offset).unwrap().to_degrees(),
        126.87,
        5e-3,
    );
    let bottom = g.bulge_centre(h).z - g.bulge_height;
    let read = g.read_element(h).unwrap();
    let write = g.write_element(h).unwrap();
    assert_rel("read above bottom (nm)", (read.z - bottom) / NM, 1.0, 1e-9);
    assert_rel(
        "write above bottom (nm)",
        (write.z - bottom) / NM,
        1.0,
        1e-9,
    );
    assert_rel("read x", read.x - g.bulge_centre(h).x, g.read_offset, 1e-9);
    let pt = g.pole_tip_spacing(0.5 * NM, 100e-6, 0.0, h).unwrap();
    assert_eq!(pt, g.spacing_of(&read, 0.5 * NM, 100e-6, 0.0));
    let poc = g
        .feature_point(
            Feature::Bulge,
            &pose(0.5 * NM, 100e-6, 0.0, h),
            &PoseRates::default(),
        )
        .unwrap();
    // 1 nm in the body frame, + x_R sinθ = 0.3 nm from the pitch, + (h_s − b) = 0.025 nm (the POC
    // lies below the centre-bottom point): 1.325 nm.
    let h_s = g
        .bulge_at(h)
        .unwrap()
        .support_distance(&Attitude::pitch_only(100e-6));
    let expected = 1.0 * NM + g.read_offset * 100e-6f64.sin() + (h_s - g.bulge_height);
    assert_abs("PT − s_POC", pt - poc.solid_spacing, expected, 1e-15);
    assert_abs(
        "PT − s_POC (nm)",
        (pt - poc.solid_spacing) / NM,
        1.325,
        1e-3,
    );
    let w = g.write_element_spacing(0.5 * NM, 100e-6, 0.0, h).unwrap();
    assert!(w < pt, "the write element (toward the TE) flies lower");
}

/// Bad parameters are `DynamicsError`s, never panics: negative `a_TFC`, `|x_R| ≥ a`, actuation
/// below `b_TFC` or NaN, negative truncation height, roll beyond 0.1 rad.
#[test]
fn bad_parameters_are_errors() {
    let g = Slider3DofGeometry::dissertation();
    g.validate().unwrap();
    let mut bad = g;
    bad.bulge.semi_width_x = -5.0 * UM;
    assert!(matches!(
        bad.validate(),
        Err(DynamicsError::Parameter { .. })
    ));
    let mut bad = g;
    bad.read_offset = 5.0 * UM;
    assert!(bad.validate().is_err());
    assert!(g.element_angle(-6.0 * UM).is_err());
    let mut bad = g;
    bad.bulge_height = 0.0;
    assert!(bad.validate().is_err());
    let below = pose(0.0, 100e-6, 0.0, 4.0 * NM);
    let mut out = FeaturePoints::new();
    assert!(g
        .evaluate_features(&below, &PoseRates::default(), &mut out)
        .is_err());
    assert!(g.bulge_at(4.0 * NM).is_err());
    assert!(g.pole_tip_spacing(0.0, 100e-6, 0.0, 4.0 * NM).is_err());
    assert!(g
        .nominal_contact_area(Feature::Bulge, &below, 1.0 * NM)
        .is_err());
    let nan = pose(0.0, 100e-6, 0.0, f64::NAN);
    assert!(g
        .feature_point(Feature::Bulge, &nan, &PoseRates::default())
        .is_err());
    let ok = pose(0.0, 100e-6, 0.0, 10.0 * NM);
    assert!(g.nominal_contact_area(Feature::Bulge, &ok, -NM).is_err());
    assert!(g
        .feature_point(
            Feature::Bulge,
            &pose(0.0, 100e-6, 0.2, 10.0 * NM),
            &PoseRates::default()
        )
        .is_err());
}

/// The fast path fills the caller's storage with exactly what the per-feature calls return,
/// and reuses it across evaluations.
#[test]
fn fast_path_equals_per_feature_calls() {
    let g = Slider3DofGeometry::dissertation();
    let rates = PoseRates {
        heave: -1e-3,
        pitch: 0.5,
        roll: 0.2,
        actuation: -2e-4,
    };
    let mut out = FeaturePoints::default();
    for p in [figure_4_8_pose(), pose(2.0 * NM, 90e-6, 10e-6, 6.0 * NM)] {
        g.evaluate_features(&p, &rates, &mut out).unwrap();
        assert_eq!(out.len(), MAX_FEATURES);
        for (f, feature) in out.as_slice().iter().zip(ALL_FEATURES) {
            assert_eq!(*f, g.feature_point(feature, &p, &rates).unwrap());
        }
    }
}
