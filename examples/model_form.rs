//! The model-form experiments of docs/model-form.md: one variant of the 2-DOF improved model's
//! interface (contact-force reading, lubricant force, ISBL summit offset, surface energy,
//! static friction law) →
//! the structural misses it attacks and the held-out set it is judged on.
//!
//! ```text
//! cargo run --release --example model_form -- [contact_force=interference_tangent|static_curve|integrated_stiffness]
//!     [lubricant=none|mtl] [summit_distribution=surface|mccool|fig_2_11|given]
//!     [fig_2_11_area=55] [summits=S,Y] [surface_energy=constant|variable]
//!     [friction_law=junction_shear|seed_power_elastic|ke_static] [dmw_seed=1]
//!     [model=initial_2dof] [contact_law=bem bem_result=processed/bem_measured/result.json]
//! ```
//!
//! `contact_law=bem` takes the contact pressure, real area and junction-shear friction from
//! the BEM curve in a `[contact_bem]` instance's `result.json` (`hdi run` writes it), adhesion
//! from the variant's ISBL interface.
//!
//! `summit_offset=none|mccool` is still read (the older name). `fig_2_11` fits σ_s and y_s to
//! Fig. 2.11 on the variant's interface with the force on `fig_2_11_area` µm² (default 55);
//! `given` takes `summits=σ_s/σ,y_s/σ` (e.g. the measured ones a `[contact]` stage with
//! `summit_distribution = "measured"` writes in its result).
//!
//! Every case starts from its static equilibrium (`init = "static"`) and sees the validation's
//! synthetic DMW (σ 1 nm, seed 1) unless stated; the no-DMW numbers are the steady states the
//! calibration notes quote (docs/calibration.md).

use hdi::contact::isbl::summits::{fit_two_point, TwoPointTarget};
use hdi::contact::isbl::{FrictionLaw, IsblModel, IsblParams, SummitDistribution, SurfaceEnergy};
use hdi::contact::lookup::IsblLookup;
use hdi::dmw::excitation_tracks::{synthetic_dmw, Excitation};
use hdi::dynamics::metrics::{slopes, CaseParams, SlopeParams, SweepPoint};
use hdi::dynamics::params::{improved_2dof, initial_2dof, optimised_bulge, Model2Dof};
use hdi::dynamics::touchdown::{find_touchdown, TouchdownSearch};
use hdi::dynamics::two_dof::{ContactForceForm, DmwInput, LubricantForce, SimOptions, TwoDofCase};
use rayon::prelude::*;

const NM: f64 = 1e-9;

/// The `summit_distribution` flag.
#[derive(Clone, Copy)]
enum Summits {
    Surface,
    McCool,
    Fig211,
    Given,
}

#[derive(Clone, Copy)]
struct Outcome {
    clearance: f64,
    solid: bool,
    vibration: f64,
    contact_force: f64,
    lubricant_force: f64,
    adhesion: f64,
    friction: f64,
    real_area: f64,
    nominal_area: f64,
}

impl Outcome {
    /// `Q̄/F̄_c` and `Q̄/Ā_r` (GPa), the ratios of means of `hdi validate`.
    fn mu_tau(&self) -> (f64, f64) {
        let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { f64::NAN };
        (
            ratio(self.friction, self.contact_force),
            ratio(self.friction, self.real_area) * 1e-9,
        )
    }
}

fn run(
    model: &Model2Dof,
    isbl: &IsblLookup,
    options: SimOptions,
    h: f64,
    dmw: Option<&Excitation>,
) -> Option<Outcome> {
    let input = dmw.map(|t| DmwInput {
        displacement: &t.displacement,
        velocity: &t.velocity,
        sample_rate: t.fs,
    });
    let case = match TwoDofCase::new(model, h, isbl, input, options) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("h = {:.2} nm: {e}", h / NM);
            return None;
        }
    };
    let hist = match case.run() {
        Ok(x) => x,
        Err(e) => {
            eprintln!("h = {:.2} nm: {e}", h / NM);
            return None;
        }
    };
    let m = hist.metrics(&CaseParams::improved_2dof()).ok()?;
    let n0 = (0.5e-3 / hist.dt).round() as usize;
    let mean = |v: &[f64]| {
        let w = &v[n0.min(v.len())..];
        w.iter().sum::<f64>() / w.len().max(1) as f64
    };
    Some(Outcome {
        clearance: m.clearance_m.mean,
        solid: m.percent_solid_contact > 0.0,
        vibration: m.vibration.percent,
        contact_force: mean(&hist.contact_force),
        lubricant_force: mean(&hist.lubricant_force),
        adhesion: mean(&hist.adhesion),
        friction: mean(&hist.friction),
        real_area: mean(&hist.real_area),
        nominal_area: hist.nominal_area,
    })
}

/// Actuation where the c̄(h) sweep first falls below `level` (linear interpolation).
fn crossing(sweep: &[(f64, Outcome)], level: f64) -> f64 {
    for w in sweep.windows(2) {
        let (a, b) = (w[0], w[1]);
        if a.1.clearance >= level && b.1.clearance < level {
            let f = (a.1.clearance - level) / (a.1.clearance - b.1.clearance);
            return a.0 + f * (b.0 - a.0);
        }
    }
    f64::NAN
}

fn sweep(
    model: &Model2Dof,
    isbl: &IsblLookup,
    o: SimOptions,
    dmw: Option<&Excitation>,
    grid: &[f64],
) -> Vec<(f64, Outcome)> {
    let mut v: Vec<(f64, Outcome)> = grid
        .par_iter()
        .filter_map(|&h| run(model, isbl, o, h, dmw).map(|m| (h, m)))
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

fn touchdown(
    model: &Model2Dof,
    isbl: &IsblLookup,
    o: SimOptions,
    dmw: &Excitation,
    known: &[(f64, Outcome)],
) -> f64 {
    let known: Vec<(f64, bool)> = known.iter().map(|(h, m)| (*h, m.solid)).collect();
    let search = TouchdownSearch::convention(13e-9, 0.2e-9, 4);
    let td = find_touchdown::<()>(&search, &known, |hs| {
        Ok(hs
            .par_iter()
            .map(|&h| run(model, isbl, o, h, Some(dmw)).is_some_and(|m| m.solid))
            .collect())
    });
    td.ok()
        .and_then(|t| t.actuation)
        .map_or(f64::NAN, |h| h / NM)
}

/// The friction the table gives at the slider's mean adhesion-augmented load `F̄_c + F̄_s`
/// (Ch. 4: "the net vertical force … determines the value of the maximum friction force"),
/// evaluated once at the steady state (the dynamics read Q at `F_c` alone): `(Q, μ = Q/F̄_c,
/// τ = Q/Ā_r in GPa)`. A reading of the text, not a switch of the dynamics.
fn slider_level_augmented(isbl: &IsblLookup, m: &Outcome) -> (f64, f64, f64) {
    let a = m.nominal_area;
    let q = isbl
        .separation_for_pressure((m.contact_force + m.adhesion) / a)
        .and_then(|h| isbl.at(h).ok())
        .map_or(f64::NAN, |f| f.friction * a);
    (q, q / m.contact_force, q / m.real_area * 1e-9)
}

fn band(name: &str, value: f64, target: f64, lo: f64, hi: f64) -> bool {
    let ok = value >= lo && value <= hi;
    println!(
        "  {name:<38} {value:>9.3}   published {target:>6.2}  band [{lo:.2}, {hi:.2}]  {}",
        if ok { "in" } else { "OUT" }
    );
    ok
}

fn main() {
    let mut options = SimOptions {
        static_init: true,
        ..SimOptions::default()
    };
    let mut ip = IsblParams::improved_2dof();
    let mut label = Vec::new();
    let mut seed = 1;
    let mut initial = false;
    let mut summits = Summits::Surface;
    let mut fig_area = 55e-12;
    let mut given = (f64::NAN, f64::NAN);
    let mut bem_law = false;
    let mut bem_result = std::path::PathBuf::from("processed/bem_measured/result.json");
    for arg in std::env::args().skip(1) {
        let (k, v) = arg.split_once('=').expect("key=value");
        label.push(arg.clone());
        match (k, v) {
            ("contact_force", "interference_tangent") => {
                options.contact_force = ContactForceForm::InterferenceTangent
            }
            ("contact_force", "static_curve") => {
                options.contact_force = ContactForceForm::StaticCurve
            }
            ("contact_force", "integrated_stiffness") => {
                options.contact_force = ContactForceForm::IntegratedStiffness
            }
            ("lubricant", "none") => options.lubricant = LubricantForce::None,
            ("lubricant", "mtl") => options.lubricant = LubricantForce::Mtl,
            ("summit_offset", "none") | ("summit_distribution", "surface") => {
                summits = Summits::Surface
            }
            ("summit_offset", "mccool") | ("summit_distribution", "mccool") => {
                summits = Summits::McCool
            }
            ("summit_distribution", "fig_2_11") => summits = Summits::Fig211,
            ("summit_distribution", "given") => summits = Summits::Given,
            ("fig_2_11_area", a) => fig_area = a.parse::<f64>().expect("fig_2_11_area=µm²") * 1e-12,
            ("summits", r) => {
                let (a, b) = r.split_once(',').expect("summits=S,Y");
                given = (a.parse().expect("σ_s/σ"), b.parse().expect("y_s/σ"));
            }
            ("surface_energy", "constant") => {}
            ("surface_energy", "variable") => ip.surface_energy = SurfaceEnergy::seed_variable(),
            ("friction_law", "junction_shear") => ip.friction_law = FrictionLaw::JunctionShear,
            ("friction_law", "seed_power_elastic") => {
                ip.friction_law = FrictionLaw::SeedPowerElastic
            }
            ("friction_law", "ke_static") => ip.friction_law = FrictionLaw::KeStatic,
            ("dmw_seed", s) => seed = s.parse().expect("dmw_seed=N"),
            ("model", "initial_2dof") => initial = true,
            ("contact_law", "isbl") => bem_law = false,
            ("contact_law", "bem") => bem_law = true,
            ("bem_result", path) => bem_result = path.into(),
            _ => panic!("unknown {arg}"),
        }
    }
    println!("variant: {}", label.join(" "));
    // The summit distribution on the variant's interface (as a [contact] stage would resolve it).
    let distribution = |p: &IsblParams| match summits {
        Summits::Surface => SummitDistribution::Surface,
        Summits::McCool => SummitDistribution::McCool,
        Summits::Given => SummitDistribution::Given {
            sigma_ratio: given.0,
            offset_ratio: given.1,
        },
        Summits::Fig211 => {
            let fit = fit_two_point(p, &TwoPointTarget::fig_2_11(fig_area)).expect("Fig. 2.11 fit");
            println!(
                "  Fig. 2.11 fit on A_n = {:.1} µm²: σ_s/σ = {:.4}, y_s/σ = {:.4} (P(3σ)·A_n = {:.3} µN, \
                 P(3σ)/P(2.5σ) = {:.4})",
                fig_area * 1e12,
                fit.sigma_ratio,
                fit.offset_ratio,
                fit.force * 1e6,
                fit.ratio
            );
            fit.distribution()
        }
    };
    if initial {
        // §12.2 #9: the initial model's mean FHM at 4–7 nm (its own interface, 1.2σ criterion).
        let mut ip0 = IsblParams::initial_2dof();
        ip0.friction_law = ip.friction_law;
        ip0.surface_energy = match ip.surface_energy {
            SurfaceEnergy::Variable { .. } => ip.surface_energy,
            SurfaceEnergy::Constant { .. } => ip0.surface_energy,
        };
        ip0.summits = distribution(&ip0);
        let isbl0 = IsblLookup::build_standard(IsblModel::new(ip0).expect("ISBL")).expect("table");
        let dmw = synthetic_dmw(2.2e-3, 4e6, 1e-9, seed).expect("DMW");
        let model = initial_2dof();
        let mut sum = 0.0;
        for h in [4.0, 5.0, 6.0, 7.0] {
            let m = run(&model, &isbl0, options, h * NM, Some(&dmw)).expect("case");
            println!(
                "  initial model {h} nm: c̄ {:.3} nm, FHM {:.2} %",
                m.clearance / NM,
                m.vibration
            );
            sum += m.vibration;
        }
        println!(
            "  initial model mean FHM 4–7 nm: {:.2} % (published 12.5)",
            sum / 4.0
        );
        if let Some(m) = run(&model, &isbl0, options, 11.0 * NM, Some(&dmw)) {
            let (mu, tau) = m.mu_tau();
            println!(
                "  initial model 11 nm: F_c {:.3} mN, Q {:.3} mN, μ {mu:.3} (published 1.2), \
                 τ {:.0} MPa (published 438), A_r {:.3} μm²",
                m.contact_force * 1e3,
                m.friction * 1e3,
                tau * 1e3,
                m.real_area * 1e12
            );
            let (q, mu, tau) = slider_level_augmented(&isbl0, &m);
            println!(
                "    Q read at F̄_c + F̄_s (slider level, static): Q {:.3} mN, μ {mu:.3}, \
                 τ {:.0} MPa",
                q * 1e3,
                tau * 1e3
            );
        }
        // §12.2 #10 (a Q ordering): the BV peaks above 20 % between touchdown (the first grid
        // case whose steady window reaches c < 0, the touchdown convention, on the 0.2 nm grid
        // of `hdi validate`'s sweep, not refined) and 11 nm.
        let grid: Vec<f64> = (0..=15).map(|i| 8.0 + 0.2 * i as f64).collect();
        let sweep: Vec<(f64, Option<Outcome>)> = grid
            .par_iter()
            .map(|&h| (h, run(&model, &isbl0, options, h * NM, Some(&dmw))))
            .collect();
        let td = sweep
            .iter()
            .find(|(_, o)| o.is_some_and(|o| o.solid))
            .map(|(h, _)| *h);
        let peak = sweep
            .iter()
            .filter(|(h, _)| td.is_some_and(|t| *h >= t - 1e-9) && *h <= 11.0 + 1e-9)
            .filter_map(|(_, o)| o.map(|o| o.vibration))
            .fold(f64::NAN, f64::max);
        println!(
            "  initial model BV peak between the grid touchdown {} nm and 11 nm: {peak:.2} % \
             (published > 20 %)",
            td.map_or("–".into(), |t| format!("{t:.1}"))
        );
        return;
    }
    ip.summits = distribution(&ip);
    let isbl = if bem_law {
        let text =
            std::fs::read_to_string(&bem_result).expect("bem_result: a [contact_bem] result.json");
        let r: hdi::artefacts::contact_bem::BemResult =
            serde_json::from_str(&text).expect("BEM result");
        let law = r.contact_law().expect("BEM curve");
        let (lo, hi) = law.measured_range();
        println!(
            "  BEM law from {} (mean gap {:.3}–{:.3} nm solved)",
            bem_result.display(),
            lo / NM,
            hi / NM
        );
        IsblLookup::build_with_contact_law(
            IsblModel::new(ip).expect("ISBL"),
            std::sync::Arc::new(law),
        )
        .expect("table")
    } else {
        IsblLookup::build_standard(IsblModel::new(ip).expect("ISBL")).expect("table")
    };
    let model = improved_2dof();
    let dmw = synthetic_dmw(2.2e-3, 4e6, 1e-9, seed).expect("DMW");

    println!("structural misses (no DMW, static init):");
    let none = |h: f64| run(&model, &isbl, options, h * NM, None);
    if let Some(m) = none(12.0) {
        let (mu, tau) = m.mu_tau();
        println!(
            "  12 nm: interference {:.3} nm, F_c {:.3} mN, P_lub {:.3} mN, F_s {:.3} mN, \
             Q {:.3} mN, μ {mu:.3}, τ {tau:.3} GPa",
            -m.clearance / NM,
            m.contact_force * 1e3,
            m.lubricant_force * 1e3,
            m.adhesion * 1e3,
            m.friction * 1e3
        );
        let (q, mu, tau) = slider_level_augmented(&isbl, &m);
        println!(
            "    Q read at F̄_c + F̄_s (slider level, static): Q {:.3} mN, μ {mu:.3}, τ {tau:.3} GPa",
            q * 1e3
        );
    }
    if let Some(m) = none(9.5) {
        println!(
            "  9.5 nm: c̄ {:.3} nm, P_lub {:.4} mN",
            m.clearance / NM,
            m.lubricant_force * 1e3
        );
    }
    println!("structural misses (synthetic DMW σ 1 nm, static init):");
    for h in [9.5, 12.0] {
        if let Some(m) = run(&model, &isbl, options, h * NM, Some(&dmw)) {
            let (mu, tau) = m.mu_tau();
            println!(
                "  {h} nm: c̄ {:.3} nm, FHM/BV {:.2} %, F_c {:.3} mN, P_lub {:.3} mN, \
                 Q {:.3} mN, μ {mu:.3}, τ {tau:.3} GPa, A_r {:.3} μm²",
                m.clearance / NM,
                m.vibration,
                m.contact_force * 1e3,
                m.lubricant_force * 1e3,
                m.friction * 1e3,
                m.real_area * 1e12
            );
        }
    }

    // Held-out set: the dissertation-geometry sweep 7–12.5 nm on a 0.1 nm grid.
    let grid: Vec<f64> = (0..=55).map(|i| (7.0 + 0.1 * i as f64) * NM).collect();
    let s = sweep(&model, &isbl, options, Some(&dmw), &grid);
    let points: Vec<SweepPoint> = s
        .iter()
        .map(|(h, m)| SweepPoint {
            actuation_m: *h,
            mean_clearance_m: m.clearance,
            any_solid_contact: m.solid,
            vibration_percent: m.vibration,
        })
        .collect();
    let an = slopes(&points, &SlopeParams::new(0.75e-9)).ok();
    let slope = |f: Option<f64>| f.unwrap_or(f64::NAN);
    let td = touchdown(&model, &isbl, options, &dmw, &s);
    println!("fitted-class target (for reference): touchdown {td:.2} nm (published 9.7)");
    println!(
        "  c̄(9.5 nm) with DMW {:.3} nm (published 0.67)",
        s.iter()
            .find(|(h, _)| (h / NM - 9.5).abs() < 1e-6)
            .map_or(f64::NAN, |(_, m)| m.clearance / NM)
    );
    println!("held-out set:");
    let mut n_in = 0;
    let mut n = 0;
    let mut count = |ok: bool| {
        n += 1;
        n_in += usize::from(ok);
    };
    let cp = an.as_ref().and_then(|a| a.critical_point);
    count(band(
        "#17 critical point h_cr (nm)",
        cp.map_or(f64::NAN, |c| c.actuation_m / NM),
        8.6,
        8.4,
        8.8,
    ));
    count(band(
        "#17 critical point c_cr (nm)",
        cp.map_or(f64::NAN, |c| c.clearance_m / NM),
        2.39,
        2.24,
        2.54,
    ));
    let sl = |f: fn(&hdi::dynamics::metrics::SlopeAnalysis) -> Option<f64>| {
        slope(an.as_ref().and_then(f))
    };
    count(band(
        "#21 slope B",
        sl(|a| a.b.as_ref().map(|l| l.slope)),
        -4.4,
        -5.72,
        -3.08,
    ));
    count(band(
        "#21 slope C",
        sl(|a| a.c.as_ref().map(|l| l.slope)),
        -1.0,
        -1.3,
        -0.7,
    ));
    count(band(
        "#21 slope D",
        sl(|a| a.d.as_ref().map(|l| l.slope)),
        -0.2,
        -0.26,
        -0.14,
    ));
    count(band(
        "#20 flying → mobile (c̄ = 2T0) (nm)",
        crossing(&s, 1.5e-9) / NM,
        8.8,
        8.5,
        9.1,
    ));
    count(band(
        "#20 mobile → bonded (c̄ = T0) (nm)",
        crossing(&s, 0.75e-9) / NM,
        9.5,
        9.2,
        9.8,
    ));
    count(band(
        "#20 bonded → solid (c̄ = 0) (nm)",
        crossing(&s, 0.0) / NM,
        10.4,
        10.1,
        10.7,
    ));
    // Optimised geometry (§2.3, w = 50 µm assumed).
    let opt = improved_2dof().with_bulge(optimised_bulge(50e-6).expect("bulge"));
    let og: Vec<f64> = (0..=30).map(|i| (8.0 + 0.1 * i as f64) * NM).collect();
    let so = sweep(&opt, &isbl, options, Some(&dmw), &og);
    let c86 = so
        .iter()
        .find(|(h, _)| (h / NM - 8.6).abs() < 1e-6)
        .map_or(f64::NAN, |(_, m)| m.clearance / NM);
    count(band("#26 optimised c̄(8.6 nm) (nm)", c86, 2.23, 2.08, 2.38));
    count(band(
        "#26 optimised lube onset (c̄ = 2T0) (nm)",
        crossing(&so, 1.5e-9) / NM,
        9.0,
        8.8,
        9.2,
    ));
    let tdo = touchdown(&opt, &isbl, options, &dmw, &so);
    count(band("#26 optimised touchdown (nm)", tdo, 9.9, 9.7, 10.1));
    println!("held-out in band: {n_in} of {n}");
}
