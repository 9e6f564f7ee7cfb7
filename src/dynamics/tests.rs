//! Tests of the dynamics building blocks against the dissertation's numbers (§2.1.1, §2.2, §4.1;
//! docs/dynamics-geometry.md, docs/validation.md). Every tolerance is stated next to its target.

use nalgebra::Vector3;

use super::air_bearing::{
    heave_pitch_modes, springs_from_frequencies, DmwAtSprings, HeavePitchState, RearStiffening,
    RootAssignment,
};
use super::geometry::{
    generalised_force, hertz_contact_radius, spacing_truncation_height, Attitude, BulgeDesign,
    ContactCriterion, HalfEllipsoid,
};
use super::params::{improved_2dof, initial_2dof, optimised_bulge};
use super::{DynamicsError, NM, UM};

const UM2: f64 = 1e-12;

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[track_caller]
fn assert_rel(what: &str, ours: f64, target: f64, tol: f64) {
    let r = rel(ours, target);
    assert!(
        r <= tol,
        "{what}: ours {ours:e} vs target {target:e} (rel {r:.2e} > {tol:.1e})"
    );
}

// ---------------------------------------------------------------------------------------------
// Geometry: nominal areas and curvatures (§2.7, §12.2 rows 1–5)

/// Initial model (σ = 0.87 nm, truncation 1.8σ = 1.566 nm, θ0 = 100 µrad): A_n and protrusion
/// curvature at 5/10/15 nm. Published 124/68/47 µm² and 1506/827/567 µm (tolerance 2 %, and the
/// spec's class G ±1 % holds too); ours 124.07/67.96/46.61 µm² and 1510.5/828.4/568.3 µm, pinned
/// to 0.05 %. The quoted "curvature" is the radius of the circle through the section chord and
/// the lowest point, `d1²/(2h_T)`; the apex radius `a²/h` (1800/900/600 µm) does not match.
#[test]
fn initial_areas_and_curvatures_match_dissertation() {
    let model = initial_2dof();
    assert!((model.interface.truncation_height() - 1.566 * NM).abs() < 1e-15);
    let cases = [
        (5.0, 124.0, 1506.0, 124.07, 1510.5),
        (10.0, 68.0, 827.0, 67.96, 828.4),
        (15.0, 47.0, 567.0, 46.61, 568.3),
    ];
    for (h, area_pub, curv_pub, area_ref, curv_ref) in cases {
        let sec = model.nominal_contact_area(h * NM).unwrap();
        let area = sec.area / UM2;
        let curv = sec.chord_radius_x() / UM;
        assert_rel(
            &format!("A_n({h} nm) vs dissertation"),
            area,
            area_pub,
            0.01,
        );
        assert_rel(
            &format!("curvature({h} nm) vs dissertation"),
            curv,
            curv_pub,
            0.01,
        );
        assert_rel(&format!("A_n({h} nm) vs spec"), area, area_ref, 5e-4);
        assert_rel(&format!("curvature({h} nm) vs spec"), curv, curv_ref, 5e-4);
        // π d1 d2 is the area.
        assert_rel(
            "π d1 d2",
            std::f64::consts::PI * sec.semi_axis_x * sec.semi_axis_y,
            sec.area,
            1e-12,
        );
    }
    // Zero pitch: 124.48 / 68.02 / 46.63 µm² (§2.1.1).
    let geo = model.geometry();
    for (h, want) in [(5.0, 124.48), (10.0, 68.02), (15.0, 46.63)] {
        let a = geo
            .nominal_contact_area(h * NM, 1.566 * NM, 0.0)
            .unwrap()
            .area
            / UM2;
        assert_rel("zero-pitch A_n", a, want, 5e-4);
    }
    // Initial model at 11 nm: 62 µm² [seed §2.1.3]; ours 62.27.
    let a11 = model.nominal_contact_area(11.0 * NM).unwrap().area / UM2;
    assert_rel("A_n(11 nm)", a11, 62.0, 0.01);
    assert_rel("A_n(11 nm) vs spec", a11, 62.27, 5e-4);
}

/// Improved model (σ = 0.5 nm, 3σ rule → h_T = 1.5 nm) at 12 nm: 55 µm² published (2 %), ours
/// 55.19 µm² with d1 = 1.452 µm, d2 = 12.10 µm. Composite radius of the two chord radii
/// 1.385 mm vs published 1.37 mm (1.1 %, within the class-G ±2 %); the Hertz semi-width with
/// R = 1.37 mm, F_c = 1.63 mN, E = 280 GPa, ν = 0.20 is 2.256 µm (published 2.26 µm) and the
/// quoted range π a² … π (3a)² = 16 … 144 µm² brackets our nominal area.
#[test]
fn improved_area_composite_radius_and_hertz_match_dissertation() {
    let model = improved_2dof();
    assert!((model.interface.truncation_height() - 1.5 * NM).abs() < 1e-15);
    let sec = model.nominal_contact_area(12.0 * NM).unwrap();
    assert_rel("A_n(12 nm)", sec.area / UM2, 55.0, 0.01);
    assert_rel("A_n(12 nm) vs spec", sec.area / UM2, 55.19, 5e-4);
    assert_rel("d1", sec.semi_axis_x / UM, 1.452, 1e-3);
    assert_rel("d2", sec.semi_axis_y / UM, 12.10, 1e-3);
    let composite = sec.composite_radius();
    assert_rel("composite radius", composite / 1e-3, 1.37, 0.02);
    assert_rel("composite radius vs spec", composite / 1e-3, 1.385, 1e-3);

    let e = 280e9;
    let nu: f64 = 0.20;
    let e_star = 1.0 / (2.0 * (1.0 - nu * nu) / e);
    let a_pub = hertz_contact_radius(1.63e-3, 1.37e-3, e_star).unwrap();
    assert_rel("Hertz semi-width (R = 1.37 mm)", a_pub / UM, 2.26, 0.005);
    let a_ours = hertz_contact_radius(1.63e-3, composite, e_star).unwrap();
    assert_rel("Hertz semi-width (our R)", a_ours / UM, 2.26, 0.02);
    let pi = std::f64::consts::PI;
    assert_rel("π a²", pi * a_pub * a_pub / UM2, 16.0, 0.02);
    assert_rel("π (3a)²", pi * 9.0 * a_pub * a_pub / UM2, 144.0, 0.02);
    assert!(sec.area > pi * a_pub * a_pub && sec.area < 9.0 * pi * a_pub * a_pub);
}

/// Truncation heights of both rules and the per-feature clamp of §2.4.
#[test]
fn truncation_rules() {
    let sigma_i = 0.87 * NM;
    let init = ContactCriterion::NSigma { n: 1.2 };
    assert!((init.truncation_height(sigma_i) - 1.566 * NM).abs() < 1e-18);
    assert!((init.contact_threshold(sigma_i) - 1.044 * NM).abs() < 1e-18);
    let sigma = 0.5 * NM;
    let impr = ContactCriterion::ThreeSigma;
    assert!((impr.truncation_height(sigma) - 1.5 * NM).abs() < 1e-18);
    assert!((impr.clearance(4.0 * NM, sigma) - 2.5 * NM).abs() < 1e-18);
    assert_eq!(spacing_truncation_height(3.5 * NM, sigma), 0.0);
    assert!((spacing_truncation_height(2.0 * NM, sigma) - 1.0 * NM).abs() < 1e-18);
    assert!((spacing_truncation_height(-NM, sigma) - 1.5 * NM).abs() < 1e-18);
}

/// Optimised design (a = 4.86 µm, x = 6.35 µm; w dropped): A_n at 9.7 / 12 nm for
/// w = 10, 20, 30, 50 µm, §2.1.1 (0.3 %: one decimal printed).
#[test]
fn optimised_design_areas() {
    let model = improved_2dof();
    for (w, a97, a12) in [
        (10.0, 21.7, 17.9),
        (20.0, 43.5, 35.7),
        (30.0, 65.2, 53.6),
        (50.0, 108.7, 89.3),
    ] {
        let m = model.with_bulge(optimised_bulge(w * UM).unwrap());
        assert_rel(
            "A_n(9.7)",
            m.nominal_contact_area(9.7 * NM).unwrap().area / UM2,
            a97,
            3e-3,
        );
        assert_rel(
            "A_n(12)",
            m.nominal_contact_area(12.0 * NM).unwrap().area / UM2,
            a12,
            3e-3,
        );
    }
}

/// 3-DOF example of Fig. 4.8 (a = 5 µm, b = 5 nm, h = 20 nm, w = 50 µm, x = 15 µm,
/// θ = 100 µrad, φ = −50 µrad, cut 1.5 nm): A_n = 187.9 µm² (dissertation value dropped; spec
/// §2.7 derived), semi-axes 3.50 × 17.08 µm, h_s = 5.178 nm, zero attitude 200.3 µm²; POC 6.0 µm
/// toward +y.
#[test]
fn tilted_bulge_section_of_figure_4_8() {
    let (l, lt) = (1.23e-3, 0.30e-3);
    let bulge = HalfEllipsoid::new(
        Vector3::new(-l / 2.0 + 15.0 * UM, 0.0, -lt / 2.0 - 15.0 * NM),
        Vector3::new(5.0 * UM, 25.0 * UM, 5.0 * NM),
    )
    .unwrap();
    let att = Attitude::new(100e-6, -50e-6);
    assert_rel("h_s", bulge.support_distance(&att) / NM, 5.178, 2e-4);
    let sec = bulge.section(&att, 1.5 * NM).unwrap();
    assert_rel("A_n", sec.area / UM2, 187.9, 5e-4);
    assert_rel("d_x", sec.semi_axis_x / UM, 3.50, 2e-3);
    assert_rel("d_y", sec.semi_axis_y / UM, 17.08, 2e-3);
    let flat = bulge.section(&Attitude::new(0.0, 0.0), 1.5 * NM).unwrap();
    assert_rel("zero-attitude A_n", flat.area / UM2, 200.3, 5e-4);
    let poc = bulge.lowest_point(&att);
    // Ours 6.035 µm; the spec quotes two digits.
    assert_rel(
        "POC y offset",
        (poc.body.y - bulge.centre.y) / UM,
        6.0,
        0.01,
    );
}

/// Brute force: the closed-form POC is the minimum of the parametric surface (eq. 2.2/2.4)
/// to < 1e-13 m in altitude, and the section area equals a grid count of the points of the cut
/// plane inside the ellipsoid (801² grid, 0.5 %; spec: < 0.5 %).
#[test]
fn closed_forms_match_brute_force() {
    let (l, lt) = (1.23e-3, 0.30e-3);
    let cases = [
        (
            3.0 * UM,
            25.0 * UM,
            5.0 * NM,
            8.0 * UM,
            Attitude::pitch_only(100e-6),
            1.566 * NM,
        ),
        (
            3.0 * UM,
            25.0 * UM,
            15.0 * NM,
            8.0 * UM,
            Attitude::pitch_only(100e-6),
            1.566 * NM,
        ),
        (
            5.0 * UM,
            25.0 * UM,
            5.0 * NM,
            15.0 * UM,
            Attitude::new(100e-6, -50e-6),
            1.5 * NM,
        ),
        (
            4.86 * UM,
            5.0 * UM,
            12.0 * NM,
            6.35 * UM,
            Attitude::new(-200e-6, 300e-6),
            1.5 * NM,
        ),
    ];
    for (a, b, c, x, att, h_t) in cases {
        let bulge = HalfEllipsoid::new(
            Vector3::new(-l / 2.0 + x, 0.0, -lt / 2.0),
            Vector3::new(a, b, c),
        )
        .unwrap();
        let n = att.body_vertical();
        let alt = |p: Vector3<f64>| n.dot(&(p - bulge.centre));
        // Zooming grid search over (α, β) of the lower half.
        let (mut a0, mut a1) = (0.0, std::f64::consts::TAU);
        let (mut b0, mut b1) = (std::f64::consts::FRAC_PI_2, 1.5 * std::f64::consts::PI);
        let mut best = (f64::INFINITY, 0.0, 0.0);
        for _ in 0..40 {
            let k = 40;
            for i in 0..=k {
                for j in 0..=k {
                    let al = a0 + (a1 - a0) * i as f64 / k as f64;
                    let be = b0 + (b1 - b0) * j as f64 / k as f64;
                    let z = alt(bulge.surface_point(al, be));
                    if z < best.0 {
                        best = (z, al, be);
                    }
                }
            }
            let (da, db) = ((a1 - a0) / 8.0, (b1 - b0) / 8.0);
            a0 = best.1 - da;
            a1 = best.1 + da;
            b0 = best.2 - db;
            b1 = best.2 + db;
        }
        let low = bulge.lowest_point(&att);
        let z_closed = alt(low.body);
        assert!((z_closed + low.support_distance).abs() < 1e-17);
        assert!(
            (best.0 - z_closed).abs() < 1e-13,
            "POC altitude: brute {:e} vs closed {:e}",
            best.0,
            z_closed
        );
        // Nothing on the surface is lower (to the ~1e-19 m resolution of body coordinates).
        assert!(best.0 >= z_closed - 1e-17);

        // Grid count of the cut plane inside the ellipsoid.
        let sec = bulge.section(&att, h_t).unwrap();
        let e1 = (Vector3::x() - n * n.x).normalize();
        let e2 = n.cross(&e1);
        let (hx, hy) = (1.2 * sec.semi_axis_x, 1.2 * sec.semi_axis_y);
        let k = 801;
        // Centre of the section: the POC scaled toward the ellipsoid centre by ρ = 1 − h_T/h_s
        // (§2.4 derivation); scan a window 1.2× the semi-axes around it.
        let rho = 1.0 - h_t / low.support_distance;
        let centre_sec = bulge.centre + (low.body - bulge.centre) * rho;
        let mut inside = 0usize;
        for i in 0..k {
            for j in 0..k {
                let s = -hx + 2.0 * hx * (i as f64 + 0.5) / k as f64;
                let t = -hy + 2.0 * hy * (j as f64 + 0.5) / k as f64;
                let p = centre_sec + e1 * s + e2 * t;
                let q = (p - bulge.centre).component_div(&bulge.semi_axes);
                if q.norm_squared() <= 1.0 {
                    inside += 1;
                }
            }
        }
        // Planar altitude of the cut: every counted point is at low + h_T.
        assert!((alt(centre_sec) - (z_closed + h_t)).abs() < 1e-20);
        let area_grid = inside as f64 * (2.0 * hx) * (2.0 * hy) / (k * k) as f64;
        assert_rel("grid area", area_grid, sec.area, 5e-3);
    }
}

/// §2.2: for h = 5 nm, a = 3 µm, θ = 100 µrad the POC sits 0.18 µm toward the TE from the
/// ellipsoid centre and `h_s − h` is < 0.01 nm. Lever arms ≈ (−(l/2 − x_TFC), 0, −l_t/2 − h).
#[test]
fn poc_offset_and_lever_arm() {
    let model = improved_2dof();
    let geo = model.geometry();
    let poc = geo.bulge_poc(0.0, model.nominal_pitch, 5.0 * NM).unwrap();
    let dx = poc.body.x - geo.bulge_centre().x;
    assert_rel("POC x offset", -dx / UM, 0.18, 0.01);
    assert!(poc.support_distance - 5.0 * NM < 0.01 * NM);
    let r = poc.lever_arm;
    // r_x differs from −(l/2 − x_TFC) by the 0.18 µm POC offset.
    assert!((r.x + (0.615e-3 - 8e-6)).abs() < 0.3 * UM, "r_x = {}", r.x);
    assert!((r.z + (0.15e-3 + 5e-9)).abs() < 0.1 * UM, "r_z = {}", r.z);
    assert!(r.y.abs() < 1e-18);
}

/// Actuation 0 (no bulge) is valid input: finite POC on the TE-side rim, zero area, no panic.
#[test]
fn zero_actuation_is_finite() {
    let model = improved_2dof();
    let geo = model.geometry();
    let poc = geo.bulge_poc(0.0, model.nominal_pitch, 0.0).unwrap();
    assert!((poc.body.x - (geo.bulge_centre().x - 3.0 * UM)).abs() < 1e-15);
    assert!(poc.solid_spacing.is_finite());
    let sec = model.nominal_contact_area(0.0).unwrap();
    assert_eq!(sec.area, 0.0);
    // Flat and level: the whole footprint.
    let flat = geo.nominal_contact_area(0.0, 1.5 * NM, 0.0).unwrap();
    assert_rel(
        "flat footprint",
        flat.area,
        std::f64::consts::PI * 3.0 * UM * 25.0 * UM,
        1e-12,
    );
}

/// `ṡ` of the POC equals a finite difference of `s_POC(z, θ, h)`.
#[test]
fn spacing_rate_matches_finite_difference() {
    let model = improved_2dof();
    let geo = model.geometry();
    let (z, th, h) = (0.3 * NM, 103e-6, 9.0 * NM);
    let (vz, vth, vh) = (1e-3, 2.0, 5e-6);
    let dt = 1e-9;
    let s = |t: f64| {
        geo.bulge_poc(z + vz * t, th + vth * t, h + vh * t)
            .unwrap()
            .solid_spacing
    };
    let fd = (s(dt) - s(-dt)) / (2.0 * dt);
    let poc = geo.bulge_poc(z, th, h).unwrap();
    let rate = poc.spacing_rate(th, vz, vth, vh);
    assert_rel("ṡ", rate, fd, 1e-6);
}

/// Interfacial moments (§1.1): friction at the ABS gives a nose-down moment; adhesion (N < 0)
/// near the TE a nose-up moment.
#[test]
fn generalised_force_signs() {
    let att = Attitude::pitch_only(100e-6);
    let r = Vector3::new(-0.607e-3, 0.0, -0.15e-3);
    let friction = generalised_force(&r, &att, 0.0, 1e-3);
    assert!(friction.pitch_moment < 0.0);
    let adhesion = generalised_force(&r, &att, -1e-3, 0.0);
    assert!(adhesion.pitch_moment > 0.0);
    assert_eq!(adhesion.heave, -1e-3);
    let side = generalised_force(&Vector3::new(0.0, 1e-4, 0.0), &att, 1e-3, 0.0);
    assert!(side.roll_moment > 0.0);
}

// ---------------------------------------------------------------------------------------------
// Cross-checks of §12.1 that concern geometry and the AB

/// C1 (improved model): steady flying clearance `c = FH_nom + x_TFC θ0 + T0 − 3σ − h =
/// 11.05 − h`: 2.55 nm at 8.5 nm vs published 2.54 (class K ±0.05 nm); C3: HMS = c − t ≈ 1 nm;
/// optimised design (x = 6.35 µm) 2.285 nm at 8.6 nm (published 2.23 includes adhesion pull,
/// not checked here). Flying slope A = −1.00.
#[test]
fn c1_c3_improved_clearance_line() {
    let model = improved_2dof();
    let geo = model.geometry();
    let sigma = model.interface.sigma;
    let clearance = |g: &super::geometry::Slider2DofGeometry, h: f64| {
        let poc = g.bulge_poc(0.0, model.nominal_pitch, h).unwrap();
        model
            .interface
            .criterion
            .clearance(poc.solid_spacing, sigma)
    };
    // The exact POC lies a²θ0²/(2h) = 0.0053 nm below `centre − h`, so ours is 2.5447 nm
    // against the spec's line value 2.55 nm.
    let c85 = clearance(&geo, 8.5 * NM);
    assert!((c85 - 2.5447 * NM).abs() < 0.001 * NM, "c(8.5) = {c85:e}");
    assert!((c85 - 2.54 * NM).abs() < 0.05 * NM);
    let hms = c85 - model.interface.lubricant_thickness;
    assert!((hms - 1.0 * NM).abs() < 0.1 * NM, "HMS = {hms:e}");
    let slope = (clearance(&geo, 8.0 * NM) - clearance(&geo, 5.0 * NM)) / (3.0 * NM);
    assert!((slope + 1.0).abs() < 0.02, "slope {slope}");
    let opt = model
        .with_bulge(optimised_bulge(50.0 * UM).unwrap())
        .geometry();
    let c86 = clearance(&opt, 8.6 * NM);
    // Line value 2.285 nm; the exact POC is 0.0137 nm lower (a = 4.86 µm).
    assert!(
        (c86 - 2.2713 * NM).abs() < 0.001 * NM,
        "c_opt(8.6) = {c86:e}"
    );
}

/// C2 (initial model): published clearance 5.8 → 2.8 nm for 4 → 7 nm actuation (`9.8 − h`).
/// With the spec's reproduction anchor (ABS under the bulge centre at h = FH_nom) the geometry
/// gives `11 − 1.2σ − h = 9.956 − h` less the 0.01 nm exact-POC correction (pinned to 0.001 nm); the remaining 0.16 nm is the
/// adhesion pull of the dynamic model (not part of the geometry), within the class-K ±0.2 nm.
#[test]
fn c2_initial_clearance_line() {
    let model = initial_2dof();
    let geo = model.geometry();
    for (h, published) in [(4.0, 5.8), (7.0, 2.8)] {
        let poc = geo.bulge_poc(0.0, model.nominal_pitch, h * NM).unwrap();
        let c = model
            .interface
            .criterion
            .clearance(poc.solid_spacing, model.interface.sigma);
        // Line 9.956 − h less the exact-POC correction a²θ0²/(2h) (0.011 nm at 4 nm).
        let line = (9.956 - h) * NM - (3.0 * UM * 100e-6f64).powi(2) / (2.0 * h * NM);
        assert!((c - line).abs() < 0.001 * NM, "c({h}) = {c:e}");
        assert!((c - published * NM).abs() < 0.2 * NM);
    }
}

/// C5: `(k_f + k_r)·FH_nom = 12.7 mN < 14.7 mN` preload.
#[test]
fn c5_ab_force_budget() {
    let model = initial_2dof();
    let ab = model.air_bearing_model().unwrap();
    let budget = (ab.front_stiffness + ab.rear_stiffness_nominal) * model.nominal_flying_height;
    assert_rel("AB force budget", budget / 1e-3, 12.7, 0.005);
    assert!(budget < model.suspension.preload);
}

// ---------------------------------------------------------------------------------------------
// Air bearing

/// Modal inversion (110 / 300 kHz, stiff rear): k_f = 1.865e5, k_r = 9.683e5 N/m
/// (docs/dynamics-geometry.md, 0.1 %); the nalgebra eigen-solve of the assembled 2×2 system
/// (suspension included) reproduces both frequencies to 1e-9 (brief: 0.5 %;
/// docs/dynamics-geometry.md: 1e-9); the other root pair gives the same frequencies with the
/// springs swapped.
#[test]
fn modal_inversion_round_trip() {
    let model = initial_2dof();
    let body = model.heave_pitch_body();
    let springs = springs_from_frequencies(&body, 110e3, 300e3, RootAssignment::StiffRear).unwrap();
    assert_rel("k_f", springs.front, 1.865e5, 1e-3);
    assert_rel("k_r", springs.rear, 9.683e5, 1e-3);
    let modes = heave_pitch_modes(&body.mass_matrix(), &body.stiffness_matrix(&springs)).unwrap();
    assert_rel("f1", modes[0].frequency_hz, 110e3, 1e-9);
    assert_rel("f2", modes[1].frequency_hz, 300e3, 1e-9);

    let swapped =
        springs_from_frequencies(&body, 110e3, 300e3, RootAssignment::StiffFront).unwrap();
    assert!(swapped.front > swapped.rear);
    let modes = heave_pitch_modes(&body.mass_matrix(), &body.stiffness_matrix(&swapped)).unwrap();
    assert_rel("f1 swapped", modes[0].frequency_hz, 110e3, 1e-9);
    assert_rel("f2 swapped", modes[1].frequency_hz, 300e3, 1e-9);

    // Other frequency pairs and unequal arms round-trip as well.
    let mut skew = body;
    skew.front_arm = 0.5e-3;
    for (f1, f2) in [(90e3, 250e3), (110e3, 539e3), (120e3, 1001e3)] {
        for assign in [RootAssignment::StiffRear, RootAssignment::StiffFront] {
            let s = springs_from_frequencies(&skew, f1, f2, assign).unwrap();
            let m = heave_pitch_modes(&skew.mass_matrix(), &skew.stiffness_matrix(&s)).unwrap();
            assert_rel("f1 (skew)", m[0].frequency_hz, f1, 1e-9);
            assert_rel("f2 (skew)", m[1].frequency_hz, f2, 1e-9);
        }
    }
    // The pair the model hands to the equations of motion.
    let ab = model.air_bearing_model().unwrap();
    let sus = model.suspension_coefficients().unwrap();
    let m = ab
        .modes(model.slider.mass, model.slider.pitch_inertia, &sus, 0.0)
        .unwrap();
    assert_rel("model f1", m[0].frequency_hz, 110e3, 1e-9);
    assert_rel("model f2", m[1].frequency_hz, 300e3, 1e-9);
}

/// Mode shapes with the stiff-rear assignment (docs/dynamics-geometry.md, derived): the 1st mode's
/// TE/LE amplitude ratio is 0.11 and the 2nd mode's node lies 175 µm toward the LE (5 %).
#[test]
fn mode_shapes_stiff_rear() {
    let model = initial_2dof();
    let ab = model.air_bearing_model().unwrap();
    let sus = model.suspension_coefficients().unwrap();
    let m = ab
        .modes(model.slider.mass, model.slider.pitch_inertia, &sus, 0.0)
        .unwrap();
    let half = 0.5 * model.slider.length;
    let ratio = (m[0].amplitude_at(-half) / m[0].amplitude_at(half)).abs();
    assert_rel("TE/LE ratio of mode 1", ratio, 0.11, 0.05);
    assert_rel("node of mode 2", m[1].node_x() / UM, 175.0, 0.05);
    // Mode 1 rotates about a point behind the TE.
    assert!(m[0].node_x() < -half);
}

/// A frequency ratio below 1.683 has no real spring pair; f2 ≤ f1 is a parameter error.
#[test]
fn modal_inversion_rejects_impossible_frequencies() {
    let body = initial_2dof().heave_pitch_body();
    let err = springs_from_frequencies(&body, 110e3, 150e3, RootAssignment::StiffRear);
    assert!(matches!(err, Err(DynamicsError::Numerical(_))), "{err:?}");
    assert!(springs_from_frequencies(&body, 110e3, 186e3, RootAssignment::StiffRear).is_ok());
    let err = springs_from_frequencies(&body, 300e3, 110e3, RootAssignment::StiffRear);
    assert!(
        matches!(err, Err(DynamicsError::Parameter { .. })),
        "{err:?}"
    );
}

/// Damping coefficients of Tables 2.1, 2.2 (c_f, c_r, c: N·s/m; c_θ: N·m·s/rad), 0.1 %, and the
/// resulting modal damping ≈ 4.9 % (110 kHz) and 6.5 % (300 kHz) (docs/dynamics-geometry.md, ±0.2
/// points).
#[test]
fn damping_coefficients_and_modal_damping() {
    let model = initial_2dof();
    let ab = model.air_bearing_model().unwrap();
    let sus = model.suspension_coefficients().unwrap();
    assert_rel("c_f", ab.front_damping, 2.715e-2, 1e-3);
    assert_rel("c_r", ab.rear_damping, 6.186e-2, 1e-3);
    assert_rel("c", sus.heave_damping, 1.325e-4, 1e-3);
    assert_rel("c_θ", sus.pitch_damping, 1.083e-10, 1e-3);
    let m = model.slider.mass;
    let j = model.slider.pitch_inertia;
    let mats = ab.eom_matrices(m, j, &sus);
    let modes = ab.modes(m, j, &sus, 0.0).unwrap();
    let z1 = modes[0].damping_ratio(&mats.damping, &mats.mass);
    let z2 = modes[1].damping_ratio(&mats.damping, &mats.mass);
    assert!((z1 - 0.049).abs() < 0.002, "ζ1 = {z1}");
    assert!((z2 - 0.065).abs() < 0.002, "ζ2 = {z2}");
}

/// Rear stiffening (§3.2): constant in the initial model; `k_r,nom (1 + β (h/15 nm)²)` in the
/// improved one (doubles at 15 nm for β = 1).
#[test]
fn rear_stiffening() {
    let init = initial_2dof().air_bearing_model().unwrap();
    assert_eq!(init.rear_stiffness(12.0 * NM), init.rear_stiffness_nominal);
    let impr = improved_2dof().air_bearing_model().unwrap();
    let k0 = impr.rear_stiffness_nominal;
    assert_eq!(impr.rear_stiffness(0.0), k0);
    assert_rel(
        "k_r(15 nm)",
        impr.rear_stiffness(15.0 * NM),
        2.0 * k0,
        1e-12,
    );
    assert_rel(
        "k_r(7.5 nm)",
        impr.rear_stiffness(7.5 * NM),
        1.25 * k0,
        1e-12,
    );
    assert!(RearStiffening::Quadratic { beta: 3.5 }.validate().is_err());
}

/// The §5.1 split (front spring in K and C, rear spring force on the right) gives the same
/// acceleration as the total AB forces with only the suspension on the left.
#[test]
fn eom_split_equals_total_forces() {
    let model = improved_2dof();
    let ab = model.air_bearing_model().unwrap();
    let sus = model.suspension_coefficients().unwrap();
    let (m, j) = (model.slider.mass, model.slider.pitch_inertia);
    let mats = ab.eom_matrices(m, j, &sus);
    let state = HeavePitchState {
        heave: 0.7 * NM,
        pitch_offset: -3e-6,
        heave_rate: 2e-4,
        pitch_rate: 0.4,
    };
    let dmw = DmwAtSprings {
        front: 1.1 * NM,
        front_rate: -3e-4,
        rear: -0.4 * NM,
        rear_rate: 5e-4,
    };
    let h = 11.0 * NM;
    let q = nalgebra::Vector2::new(state.heave, state.pitch_offset);
    let qd = nalgebra::Vector2::new(state.heave_rate, state.pitch_rate);
    let split = ab.eom_forcing(&state, &dmw, h) - mats.damping * qd - mats.stiffness * q;
    let f = ab.forces(&state, &dmw, h);
    let c_sus = nalgebra::Matrix2::new(sus.heave_damping, 0.0, 0.0, sus.pitch_damping);
    let k_sus = nalgebra::Matrix2::new(sus.heave_stiffness, 0.0, 0.0, sus.pitch_stiffness);
    let total = nalgebra::Vector2::new(f.heave, f.pitch_moment) - c_sus * qd - k_sus * q;
    assert_rel("heave force", split.x, total.x, 1e-12);
    assert_rel("pitch moment", split.y, total.y, 1e-12);
    // Nominal state with no DMW: no AB force.
    let zero = ab.forces(&HeavePitchState::default(), &DmwAtSprings::default(), h);
    assert_eq!((zero.heave, zero.pitch_moment), (0.0, 0.0));
}

// ---------------------------------------------------------------------------------------------
// Parameter validation

#[test]
fn parameter_sets_validate() {
    initial_2dof().validate().unwrap();
    improved_2dof().validate().unwrap();
    let m = initial_2dof();
    assert_rel("m", m.slider.mass / 1e-6, 1.098, 1e-3);
    assert_rel("J", m.slider.pitch_inertia, 1.466e-13, 1e-3);
}

fn param_name(err: DynamicsError) -> String {
    match err {
        DynamicsError::Parameter { name, .. } => name,
        other => panic!("expected a parameter error, got {other:?}"),
    }
}

#[test]
fn validation_names_the_offending_parameter() {
    let mut m = initial_2dof();
    m.slider.mass = -1e-6;
    assert!(param_name(m.validate().unwrap_err()).contains("mass"));

    let mut m = improved_2dof();
    m.interface.sigma = 0.0;
    assert!(param_name(m.validate().unwrap_err()).contains("σ"));

    let mut m = improved_2dof();
    m.air_bearing.stiffening = RearStiffening::Quadratic { beta: -0.5 };
    assert!(param_name(m.validate().unwrap_err()).contains("beta"));

    let mut m = initial_2dof();
    m.interface.poisson_ratio = 0.5;
    assert!(param_name(m.validate().unwrap_err()).contains("Poisson"));

    let mut m = initial_2dof();
    m.interface.criterion = ContactCriterion::NSigma { n: 3.0 };
    assert!(param_name(m.validate().unwrap_err()).contains("criterion"));

    let mut m = initial_2dof();
    m.suspension.heave_damping_ratio = f64::NAN;
    assert!(param_name(m.validate().unwrap_err()).contains("ζ"));

    let mut m = initial_2dof();
    m.air_bearing.second_frequency_hz = 150e3;
    assert!(matches!(m.validate(), Err(DynamicsError::Numerical(_))));

    // Bulge overhanging the TE.
    let err = BulgeDesign {
        semi_width_x: 9.0 * UM,
        full_width_y: 50.0 * UM,
        offset_from_te: 8.0 * UM,
    }
    .validate()
    .unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("a_TFC") && msg.contains("x_TFC"), "{msg}");
    assert!(optimised_bulge(-1.0).is_err());

    // Run-time inputs.
    let geo = initial_2dof().geometry();
    assert!(param_name(geo.bulge_poc(0.0, 100e-6, -NM).unwrap_err()).contains("h_TFC"));
    assert!(geo.bulge_poc(f64::NAN, 100e-6, 1.0 * NM).is_err());
    assert!(geo.nominal_contact_area(5.0 * NM, -NM, 100e-6).is_err());
}

/// Roll AB stiffness (§3.1, §11.3): `k_l = J_φ (2π·100 kHz)² − k_φ = 2.090e-2 N·m/rad` with
/// `J_φ = m (l_w² + l_t²)/12 = 5.306e-14 kg·m²` and `k_φ = 5e-5 N·m/rad` (0.1 %).
#[test]
fn roll_stiffness() {
    use super::air_bearing::roll_stiffness_from_frequency;
    let s = initial_2dof().slider;
    let j_roll = s.mass * (s.width * s.width + s.thickness * s.thickness) / 12.0;
    assert_rel("J_φ", j_roll, 5.306e-14, 1e-3);
    let k_l = roll_stiffness_from_frequency(j_roll, 100e3, 5e-5).unwrap();
    assert_rel("k_l", k_l, 2.090e-2, 1e-3);
    assert!(roll_stiffness_from_frequency(j_roll, 1.0, 5e-5).is_err());
}

/// The 2-DOF right-hand side's precomputed POC frame gives exactly (bit for bit) what the
/// general `bulge_poc`/`spacing_of`/`spacing_rate` give, over the states a run visits and
/// beyond (docs/performance.md: the speed-up must not move the histories).
#[test]
fn poc_frame_is_bit_identical_to_the_general_geometry() {
    for model in [improved_2dof(), initial_2dof()] {
        let g = model.geometry();
        for actuation in [0.0, 3.3 * NM, 8.5 * NM, 12.0 * NM, 15.0 * NM] {
            let frame = g.poc_frame(actuation).unwrap();
            let mut seed = 0x9e37_79b9_7f4a_7c15u64;
            let mut uniform = || {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
            };
            for _ in 0..2000 {
                let heave = uniform() * 20.0 * NM;
                let pitch = g.nominal_pitch + uniform() * 1e-4;
                let (z_rate, pitch_rate) = (uniform() * 1e-3, uniform() * 10.0);
                let tr = frame.pitch_terms(pitch);
                let fast = frame.poc(heave, &tr).unwrap();
                let slow = g.bulge_poc(heave, pitch, actuation).unwrap();
                assert_eq!(fast.solid_spacing.to_bits(), slow.solid_spacing.to_bits());
                assert_eq!(fast.lever_arm.x.to_bits(), slow.lever_arm.x.to_bits());
                assert_eq!(fast.lever_arm.z.to_bits(), slow.lever_arm.z.to_bits());
                assert_eq!(fast.body, slow.body);
                assert_eq!(
                    frame.spacing_rate(&fast, &tr, z_rate, pitch_rate).to_bits(),
                    slow.spacing_rate(pitch, z_rate, pitch_rate, 0.0).to_bits()
                );
                let te = g.trailing_edge();
                assert_eq!(
                    frame.spacing_of(&te, heave, &tr).to_bits(),
                    g.spacing_of(&te, heave, pitch).to_bits()
                );
            }
            // Same domain errors as the general form.
            let tr = frame.pitch_terms(0.2);
            assert!(frame.poc(0.0, &tr).is_err() && g.bulge_poc(0.0, 0.2, actuation).is_err());
            let tr = frame.pitch_terms(g.nominal_pitch);
            assert!(frame.poc(f64::NAN, &tr).is_err());
        }
    }
}
