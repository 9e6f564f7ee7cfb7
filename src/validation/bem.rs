//! `hdi validate` rows of the deterministic (FFT-BEM) contact solver (docs/contact.md,
//! "Deterministic contact"): closed forms (Hertz, Westergaard), the small-load κ against the
//! literature, and tamaas on the measured interface map.

use super::{Row, Tolerance};
use crate::contact::bem::reference::{hertz, kappa, westergaard};
use crate::contact::bem::{at_pressures, BemSolver, Boundary, SolverSettings};
use std::f64::consts::PI;

/// The solver's settings in these rows: the stage's default tolerance.
fn settings() -> SolverSettings {
    SolverSettings::default()
}

/// Hertz on 256² (contact radius 85 elements), Westergaard on 4096 elements per wavelength,
/// κ on a 512² self-affine surface (H = 0.8, roll-off at 4, cutoff at 64 wavelengths per side:
/// 8 elements per shortest wavelength).
pub fn rows() -> Vec<Row> {
    let mut rows = Vec::new();
    let s = settings();
    match hertz(256, 1.5, &s) {
        Ok(h) => {
            let variant = format!("non-periodic 256², {} iterations", h.iterations);
            rows.push(Row::check(
                "Hertz (1882): a = (3FR/4E*)^(1/3)",
                "Hertz contact radius a / R",
                "1",
                h.radius_exact,
                h.radius,
                Tolerance::Relative(0.01),
                &variant,
                "a from the contact area, √(A/π); R = 1, E* = 1",
            ));
            rows.push(Row::check(
                "Hertz (1882): p0 = 3F/(2πa²)",
                "Hertz peak pressure p0 / E*",
                "1",
                h.peak_exact,
                h.peak,
                Tolerance::Relative(0.01),
                &variant,
                "the largest element pressure (the element at the apex)",
            ));
        }
        Err(e) => rows.push(failed("Hertz sphere", &e.to_string())),
    }
    match westergaard(4096, &[0.05, 0.3, 0.7], &s) {
        Ok(checks) => {
            for c in checks {
                rows.push(Row::check(
                    "Westergaard (1939): 2a/λ = (2/π)·asin(√(p̄/p*)), p* = πE*Δ/λ",
                    &format!("Westergaard contact fraction at p̄/p* = {}", c.load),
                    "1",
                    c.fraction_exact,
                    c.fraction,
                    Tolerance::Relative(0.005),
                    &format!("periodic, 4096 elements per λ, {} iterations", c.iterations),
                    "",
                ));
            }
        }
        Err(e) => rows.push(failed("Westergaard sinusoid", &e.to_string())),
    }
    match kappa(512, (0.8, 4.0, 64.0, 1), &[0.01, 0.02], &s) {
        Ok(k) => {
            let persson = (8.0 / PI).sqrt();
            let bgt = (2.0 * PI).sqrt();
            let loads: Vec<String> = k
                .points
                .iter()
                .map(|(l, a, kk)| format!("p̄/(E*h′) = {l}: A_r/A_0 = {a:.4}, κ = {kk:.3}"))
                .collect();
            rows.push(
                Row::check(
                    "numerical studies: κ weakly H-dependent, slightly above 2 (van Dokkum et \
                     al. 2018, Tribol. Lett. 66:115, summarising Hyun et al. 2004, Campañá & \
                     Müser 2007, Prodanov et al. 2014); bounds: Persson √(8/π), BGT √(2π) \
                     (Paggi & Ciavarella 2010, Wear 268:1020)",
                    "κ in A_r/A_0 = κ p̄/(E* h′_rms), self-affine H = 0.8",
                    "1",
                    2.0,
                    k.kappa,
                    Tolerance::Range {
                        lo: persson,
                        hi: bgt,
                    },
                    "periodic 512², roll-off 4, cutoff 64 (8 elements per shortest λ)",
                    &format!(
                        "{}; κ/κ_Persson = {:.3}. Elements counted whole overstate A_r at \
                         light load (Yastrebov et al. 2017)",
                        loads.join("; "),
                        k.kappa / persson
                    ),
                )
                .reference("literature band: Persson √(8/π) … BGT √(2π)"),
            );
        }
        Err(e) => rows.push(failed("κ", &e.to_string())),
    }
    match compare_with_tamaas(&s) {
        Ok(cmp) => {
            for c in cmp {
                let variant = format!(
                    "periodic {}², hdi {} iterations; tamaas PolonskyKeerRey tolerance {:e}",
                    c.grid, c.iterations, c.tamaas_tolerance
                );
                let what = format!("p̄ = {:.3e} Pa", c.mean_pressure);
                for (q, unit, t, v) in [
                    ("A_r/A_0", "1", c.tamaas_fraction, c.fraction),
                    ("mean gap", "nm", c.tamaas_mean_gap * 1e9, c.mean_gap * 1e9),
                ] {
                    rows.push(Row::check(
                        "tamaas 2.9.0 on the same map (tests/data/bem/make_tamaas_reference.py)",
                        &format!("measured interface {q} at {what}"),
                        unit,
                        t,
                        v,
                        Tolerance::Relative(0.01),
                        &variant,
                        "the composite of raw/afm's disk and slider maps as the pipeline \
                         processes them",
                    ));
                }
            }
        }
        Err(e) => rows.push(failed("tamaas comparison", &e.to_string())),
    }
    super::assign_ids("bem", &mut rows);
    rows
}

/// The measured interface map the tamaas reference was computed on (the `composite.x3p` of
/// the shipped pipeline's `[contact_bem.measured]`) and tamaas's answers, written by
/// `tests/data/bem/make_tamaas_reference.py`.
const TAMAAS_MAP: &[u8] = include_bytes!("../../tests/data/bem/interface_hdi.x3p");
const TAMAAS_REFERENCE: &str = include_str!("../../tests/data/bem/tamaas_reference.json");

#[derive(serde::Deserialize)]
struct TamaasReference {
    e_star_pa: f64,
    tolerance: f64,
    loads: Vec<TamaasLoad>,
}

#[derive(serde::Deserialize)]
struct TamaasLoad {
    mean_pressure_pa: f64,
    contact_fraction: f64,
    mean_gap_m: f64,
}

/// hdi's and tamaas's answer at one load.
pub struct TamaasComparison {
    pub grid: usize,
    pub mean_pressure: f64,
    pub iterations: usize,
    pub fraction: f64,
    pub tamaas_fraction: f64,
    pub mean_gap: f64,
    pub tamaas_mean_gap: f64,
    pub tamaas_tolerance: f64,
}

/// Solve the reference map at tamaas's loads (periodic, as tamaas's model is).
pub fn compare_with_tamaas(
    settings: &SolverSettings,
) -> crate::error::Result<Vec<TamaasComparison>> {
    let reference: TamaasReference =
        serde_json::from_str(TAMAAS_REFERENCE).map_err(|e| crate::error::Error::Output {
            path: "tests/data/bem/tamaas_reference.json".into(),
            message: e.to_string(),
        })?;
    let map = crate::surface::io::read_height_map_bytes(
        std::path::Path::new("interface_hdi.x3p"),
        TAMAAS_MAP,
        &Default::default(),
    )?;
    let (ny, nx) = map.z.dim();
    let heights: Vec<f64> = map.z.iter().copied().collect();
    let solver = BemSolver::new(
        &heights,
        nx,
        ny,
        (map.dx, map.dy),
        reference.e_star_pa,
        Boundary::Periodic,
    )?;
    let pressures: Vec<f64> = reference.loads.iter().map(|l| l.mean_pressure_pa).collect();
    let solutions = at_pressures(&solver, &pressures, settings)?;
    Ok(reference
        .loads
        .iter()
        .zip(solutions)
        .map(|(l, s)| TamaasComparison {
            grid: nx,
            mean_pressure: l.mean_pressure_pa,
            iterations: s.iterations,
            fraction: s.contact_fraction,
            tamaas_fraction: l.contact_fraction,
            mean_gap: s.mean_gap,
            tamaas_mean_gap: l.mean_gap_m,
            tamaas_tolerance: reference.tolerance,
        })
        .collect())
}

/// A row that records why a check could not be computed (it fails: NaN is out of tolerance).
fn failed(what: &str, why: &str) -> Row {
    Row::check(
        "-",
        what,
        "1",
        f64::NAN,
        f64::NAN,
        Tolerance::Relative(0.0),
        "-",
        &format!("not computed: {why}"),
    )
}
