//! The 3-DOF air bearing as printed against hdi's readings (docs/model-form.md, "Misses 4 and
//! 5"): Table 4.4 and the shock's peak contact force under each reading of eqs. 4.8–4.14, the
//! shock's peak force split into its parts, a sweep of the contact damping ratio ζ_c, the
//! Table 4.4 BVs under other jump-to-contact windows, and the static stability of the spring
//! laws along the push-back calibration.
//!
//! ```text
//! cargo run --release --example three_dof_readings -- [pipeline=pipeline.toml]
//!     [record=processed/disk_md/dmw.h5] [parts=table44,shock,zeta,window,stability,steps]
//!     [variants=hdi,ab_spring_law=linear,…,air_bearing=faithful]
//! ```
//!
//! Every case is the shipped `[three_dof.lubricant_cases]` (its four MTL lubricant cases) or
//! `[three_dof.shock]` instance of `pipeline` with one key added, checked by the stage's own
//! `ThreeDofParams::check`. The DMW is the validation's synthetic one (σ 1 nm, seed 1: D1,
//! D2 flipped, D3 negated flipped; what `hdi validate --only three_dof` uses), and, with
//! `record=`, the shipped record as the stage reads it (`processed/disk_md/dmw.h5` after
//! `hdi run`).

use hdi::artefacts::dmw_tracks::read_dmw_tracks;
use hdi::contact::isbl::{IsblModel, IsblParams, SurfaceEnergy};
use hdi::contact::lookup::IsblLookup;
use hdi::contact::mtl::{FwmExperiment, LubricantCase, RoughFilm, RoughMtl};
use hdi::dmw::excitation_tracks::synthetic_dmw;
use hdi::dynamics::three_dof::air_bearing::ThreeDofAirBearing;
use hdi::dynamics::three_dof::case::{delta_force_table, static_start, History3Dof, ThreeDofCase};
use hdi::dynamics::three_dof::interface::{FeatureInterface, InterfaceLaw};
use hdi::dynamics::two_dof::DmwInput;
use hdi::slider::three_dof_params::{CaseInterface, ThreeDofConfig, ThreeDofParams};
use rayon::prelude::*;

const NM: f64 = 1e-9;
const MN: f64 = 1e-3;

/// The variants: the default, each reading alone, and the preset.
const VARIANTS: [&str; 6] = [
    "hdi",
    "ab_spring_law=linear",
    "ab_nominal_force=as_printed",
    "ab_stiffness_argument=pole_tip",
    "ab_roll_spring=absolute",
    "air_bearing=faithful",
];

const PUBLISHED: [(f64, f64, f64); 4] = [
    (61.7, 5.7, 7.8),
    (623.9, 19.4, 5.9),
    (61.8, 1.7, 6.4),
    (900.0, 23.6, 6.0),
];

struct Tracks {
    name: &'static str,
    d: [(Vec<f64>, Vec<f64>); 3],
    fs: f64,
}

impl Tracks {
    fn inputs(&self) -> [DmwInput<'_>; 3] {
        let one = |k: usize| DmwInput {
            displacement: &self.d[k].0,
            velocity: &self.d[k].1,
            sample_rate: self.fs,
        };
        [one(0), one(1), one(2)]
    }
}

fn synthetic() -> Tracks {
    let d = synthetic_dmw(2.2e-3, 4e6, 1e-9, 1).expect("synthetic DMW");
    let flip = |x: &[f64], sign: f64| x.iter().rev().map(|v| sign * v).collect::<Vec<_>>();
    Tracks {
        name: "synthetic DMW (σ 1 nm, seed 1)",
        d: [
            (d.displacement.clone(), d.velocity.clone()),
            (flip(&d.displacement, 1.0), flip(&d.velocity, -1.0)),
            (flip(&d.displacement, -1.0), flip(&d.velocity, 1.0)),
        ],
        fs: d.fs,
    }
}

fn record(path: &str) -> Tracks {
    let t = read_dmw_tracks(std::path::Path::new(path)).expect("DMW record");
    let fs = t[0].sample_rate;
    let [a, b, c] = t;
    Tracks {
        name: "shipped record (disk_md)",
        d: [
            (a.displacement, a.velocity),
            (b.displacement, b.velocity),
            (c.displacement, c.velocity),
        ],
        fs,
    }
}

/// `[three_dof.instance]` of the pipeline with `extra` keys (`key=value`, TOML values) added.
fn params(
    pipeline: &toml::Value,
    instance: &str,
    extra: &[(String, toml::Value)],
) -> ThreeDofParams {
    let mut t = pipeline["three_dof"][instance].clone();
    let table = t.as_table_mut().expect("instance table");
    for (k, v) in extra {
        table.insert(k.clone(), v.clone());
    }
    let cfg: ThreeDofConfig = t.try_into().expect("[three_dof] table");
    ThreeDofParams::check(&cfg).unwrap_or_else(|e| panic!("{instance} + {extra:?}: {e:?}"))
}

/// The experiment `pressure_cap=PA` of a variant (not a pipeline key).
fn variant_cap(v: &str) -> Option<f64> {
    v.split('+')
        .find_map(|s| s.strip_prefix("pressure_cap="))
        .map(|c| c.parse().expect("pressure_cap in Pa"))
}

/// `key=value` (string value unless it parses as a number); `hdi` is no key.
fn variant_keys(v: &str) -> Vec<(String, toml::Value)> {
    v.split('+')
        .filter(|s| *s != "hdi" && !s.starts_with("pressure_cap="))
        .map(|kv| {
            let (k, val) = kv.split_once('=').expect("key=value");
            let val = val
                .parse::<f64>()
                .map(toml::Value::Float)
                .unwrap_or_else(|_| toml::Value::String(val.into()));
            (k.to_string(), val)
        })
        .collect()
}

struct Lookups {
    solid: IsblLookup,
    mtl: IsblLookup,
}

fn lookups() -> Lookups {
    let build = |variable: bool| {
        let mut ip = IsblParams::three_dof();
        if variable {
            ip.surface_energy = SurfaceEnergy::seed_variable();
        }
        IsblLookup::build_standard_unverified(IsblModel::new(ip).unwrap()).unwrap()
    };
    Lookups {
        solid: build(false),
        mtl: build(true),
    }
}

/// One case as the stage runs it (`stages::three_dof::run_case`), without the files.
fn run(
    p: &ThreeDofParams,
    which: CaseInterface,
    l: &Lookups,
    tracks: &Tracks,
    cap: Option<f64>,
    tweak: impl Fn(&mut hdi::dynamics::three_dof::case::Options3Dof),
) -> Result<History3Dof, String> {
    let model = p.model();
    let (isbl, law) = match which {
        CaseInterface::Isbl => (&l.solid, InterfaceLaw::Isbl),
        CaseInterface::Mtl(c) => {
            let ip = l.mtl.model().params();
            let film = RoughFilm::new(
                ip.sigma,
                c.kappa(),
                ip.lubricant_thickness,
                model.disk_speed,
            )
            .map_err(|e| e.to_string())?;
            let exp = FwmExperiment::fukuzawa_z03()
                .with_limiting_viscosity(c.limiting_viscosity())
                .map_err(|e| e.to_string())?;
            let law = RoughMtl::from_experiment(film, &exp).map_err(|e| e.to_string())?;
            (&l.mtl, InterfaceLaw::Mtl(law))
        }
    };
    let mut interface = FeatureInterface::new(
        isbl,
        law,
        p.contact_force,
        p.contact_damping_ratio,
        model.air_bearing.slider.mass,
    )
    .map_err(|e| e.to_string())?;
    if let Some(cap) = cap {
        interface = interface
            .with_pressure_cap(cap)
            .map_err(|e| e.to_string())?;
    }
    let mut options = p.options;
    tweak(&mut options);
    ThreeDofCase::new(
        &model,
        interface,
        p.profile.clone(),
        p.shock,
        Some(tracks.inputs()),
        options,
    )
    .and_then(|c| c.run())
    .map_err(|e| e.to_string())
}

fn lubricant_surface(l: &Lookups) -> f64 {
    let ip = l.mtl.model().params();
    3.0 * ip.sigma + ip.lubricant_thickness
}

fn pct(x: Option<f64>) -> String {
    x.map_or("—".into(), |v| format!("{v:.2}"))
}

/// What a case did beyond the BVs: AB-lost samples, PT range, bulge range.
fn behaviour(h: &History3Dof) -> String {
    let range = |x: &[f64]| {
        x.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(*v), b.max(*v))
            })
    };
    let (b0, b1) = range(&h.bulge_spacing);
    let (p0, p1) = range(&h.pole_tip);
    let lost = (0..h.len())
        .find(|&k| h.front_force[k] == 0.0 || h.rear_force[k] == 0.0)
        .map_or(String::new(), |k| {
            format!(
                " (first at {:.3} ms, h_TFC {:.2} nm, {} spring)",
                k as f64 * h.dt * 1e3,
                h.actuation[k] / NM,
                if h.rear_force[k] == 0.0 {
                    "rear"
                } else {
                    "front"
                }
            )
        });
    format!(
        "bulge {:.2}…{:.2} nm, PT {:.2}…{:.2} nm, AB lost {} samples{lost}, steps {}",
        b0 / NM,
        b1 / NM,
        p0 / NM,
        p1 / NM,
        h.ab_lost_samples,
        h.stats.accepted_steps
    )
}

type Table44Runs = Vec<(String, Vec<Result<History3Dof, String>>)>;

fn table44_runs(
    pipeline: &toml::Value,
    variants: &[String],
    l: &Lookups,
    tracks: &Tracks,
) -> (ThreeDofParams, Table44Runs) {
    let base = params(pipeline, "lubricant_cases", &[]);
    let jobs: Vec<(usize, LubricantCase)> = (0..variants.len())
        .flat_map(|v| LubricantCase::ALL.into_iter().map(move |c| (v, c)))
        .collect();
    let done: Vec<Result<History3Dof, String>> = jobs
        .par_iter()
        .map(|(v, c)| {
            let p = params(pipeline, "lubricant_cases", &variant_keys(&variants[*v]));
            run(
                &p,
                CaseInterface::Mtl(*c),
                l,
                tracks,
                variant_cap(&variants[*v]),
                |_| {},
            )
        })
        .collect();
    let mut it = done.into_iter();
    let runs = variants
        .iter()
        .map(|v| (v.clone(), (0..4).map(|_| it.next().unwrap()).collect()))
        .collect();
    (base, runs)
}

fn table44(base: &ThreeDofParams, runs: &Table44Runs, l: &Lookups, tracks: &Tracks) {
    println!("\n### Table 4.4 on the {}\n", tracks.name);
    println!("JTC / steady / flying BV-FHM (%); orderings: steady 2 < 0 < 1 < 3; JTC min(1,3) ≥ 3·max(0,2); flying 4–10 %\n");
    println!("| variant | case 0 | case 1 | case 2 | case 3 | steady order | JTC ratio | flying in 4–10 % |");
    println!("|---|---|---|---|---|---|---|---|");
    let cells: Vec<String> = PUBLISHED
        .iter()
        .map(|(j, s, f)| format!("{j} / {s} / {f}"))
        .collect();
    println!(
        "| published | {} | 2 < 0 < 1 < 3 | 10.1 | yes |",
        cells.join(" | ")
    );
    let lube = lubricant_surface(l);
    for (name, hs) in runs {
        let t: Vec<Option<_>> = hs
            .iter()
            .map(|h| h.as_ref().ok().map(|h| h.table_4_4(&base.profile, lube)))
            .collect();
        let cells: Vec<String> = t
            .iter()
            .zip(hs)
            .map(|(t, h)| match (t, h) {
                (Some(t), _) => format!(
                    "{} / {} / {}",
                    pct(t.jump_to_contact_bv),
                    pct(t.steady_contact_bv),
                    pct(t.flying_fhm)
                ),
                (None, Err(e)) => format!("failed: {e}"),
                _ => "—".into(),
            })
            .collect();
        let get = |k: usize, f: fn(&hdi::dynamics::three_dof::case::Table44) -> Option<f64>| {
            t[k].as_ref().and_then(f).unwrap_or(f64::NAN)
        };
        let st = |k| get(k, |t| t.steady_contact_bv);
        let jt = |k| get(k, |t| t.jump_to_contact_bv);
        let fl = |k| get(k, |t| t.flying_fhm);
        let steady_order = st(2) < st(0) && st(0) < st(1) && st(1) < st(3);
        let mut order: Vec<usize> = (0..4).collect();
        order.sort_by(|a, b| st(*a).total_cmp(&st(*b)));
        let ratio = jt(1).min(jt(3)) / jt(0).max(jt(2));
        let flying = (0..4).all(|k| (4.0..=10.0).contains(&fl(k)));
        println!(
            "| `{name}` | {} | {} ({}) | {:.2} | {} |",
            cells.join(" | "),
            order
                .iter()
                .map(|k| k.to_string())
                .collect::<Vec<_>>()
                .join(" < "),
            if steady_order { "holds" } else { "no" },
            ratio,
            if flying { "yes" } else { "no" }
        );
    }
    println!();
    for (name, hs) in runs {
        for (k, h) in hs.iter().enumerate() {
            if let Ok(h) = h {
                println!("- `{name}` case {k}: {}", behaviour(h));
            }
        }
    }
}

/// A window `[start, end)` from the lubricant entry time and the plateau `(start, end)` (s).
type Window = fn(f64, (f64, f64)) -> (f64, f64);

/// The Table 4.4 BVs under other jump-to-contact windows.
fn windows(base: &ThreeDofParams, runs: &Table44Runs, l: &Lookups, tracks: &Tracks) {
    println!(
        "\n### Table 4.4 BVs against the jump-to-contact window ({})\n",
        tracks.name
    );
    println!("Entry = first lubricant contact of any feature; plateau 0.6–1.4 ms; ramp down 1.4–1.8 ms. JTC BV (%) of cases 0 / 1 / 2 / 3, and the ratio min(1,3)/max(0,2).\n");
    let lube = lubricant_surface(l);
    // The S5 ramp up runs 0.2 → 0.6 ms (plateau start − 0.4 ms).
    let defs: [(&str, Window); 11] = [
        ("entry → plateau + 0.1 ms (hdi)", |e, p| (e, p.0 + 0.1e-3)),
        (
            "ramp start → plateau + 0.1 ms (the whole approach)",
            |_, p| (p.0 - 0.4e-3, p.0 + 0.1e-3),
        ),
        ("ramp start + 0.1 ms → plateau + 0.1 ms", |_, p| {
            (p.0 - 0.3e-3, p.0 + 0.1e-3)
        }),
        ("ramp start + 0.2 ms → plateau + 0.1 ms", |_, p| {
            (p.0 - 0.2e-3, p.0 + 0.1e-3)
        }),
        ("entry → plateau + 0.05 ms", |e, p| (e, p.0 + 0.05e-3)),
        ("entry → plateau + 0.2 ms", |e, p| (e, p.0 + 0.2e-3)),
        ("entry → plateau + 0.3 ms", |e, p| (e, p.0 + 0.3e-3)),
        ("entry − 0.05 ms → plateau + 0.1 ms", |e, p| {
            (e - 0.05e-3, p.0 + 0.1e-3)
        }),
        ("entry → entry + 0.05 ms", |e, _| (e, e + 0.05e-3)),
        ("entry → plateau end (whole contact)", |e, p| (e, p.1)),
        ("snap-off: plateau end → 1.8 ms", |_, p| {
            (p.1, p.1 + 0.4e-3)
        }),
    ];
    print!("| window |");
    for (name, _) in runs {
        print!(" `{name}` |");
    }
    println!();
    print!("|---|");
    for _ in runs {
        print!("---|");
    }
    println!();
    let plateau = base.profile.plateau().expect("variable profile");
    for (label, w) in defs {
        print!("| {label} |");
        for (_, hs) in runs {
            let v: Vec<f64> = hs
                .iter()
                .map(|h| {
                    h.as_ref()
                        .ok()
                        .and_then(|h| {
                            let e = h.first_time_below(lube)?;
                            h.bulge_vibration(w(e, plateau))
                        })
                        .unwrap_or(f64::NAN)
                })
                .collect();
            let ratio = v[1].min(v[3]) / v[0].max(v[2]);
            print!(
                " {:.1} / {:.1} / {:.1} / {:.1} ({:.2}) |",
                v[0], v[1], v[2], v[3], ratio
            );
        }
        println!();
    }
    // The entry times themselves.
    for (name, hs) in runs {
        let e: Vec<String> = hs
            .iter()
            .map(|h| {
                h.as_ref()
                    .ok()
                    .and_then(|h| h.first_time_below(lube))
                    .map_or("—".into(), |t| format!("{:.4}", t * 1e3))
            })
            .collect();
        println!("- `{name}`: lubricant entry (ms) {}", e.join(" / "));
    }
}

/// The shock's peak contact force split at the peak, and the peak of each part.
fn shock_breakdown(name: &str, h: &History3Dof, p: &ThreeDofParams) {
    let model = p.model();
    let m = model.air_bearing.slider.mass;
    let u = &model.air_bearing.suspension;
    let ab = ThreeDofAirBearing::new(&model.air_bearing).unwrap();
    let c_heave = ab.damping().heave;
    let (k, peak) =
        h.contact_force.iter().enumerate().fold(
            (0, 0.0),
            |(i, v), (j, x)| if *x > v { (j, *x) } else { (i, v) },
        );
    let t = k as f64 * h.dt;
    let max = |x: &[f64]| x.iter().cloned().fold(0.0, f64::max);
    println!(
        "\n#### `{name}`: peak contact force {:.1} mN at t = {:.4} ms ({})\n",
        peak / MN,
        t * 1e3,
        behaviour(h)
    );
    println!("| part | at the peak (mN) | its own peak (mN) |");
    println!("|---|---:|---:|");
    let mut elastic_sum = 0.0;
    let mut damper_sum = 0.0;
    for (i, f) in h.features.iter().enumerate() {
        let fc = &h.feature_contact[i];
        let fd = &h.feature_contact_damping[i];
        if max(fc) <= 0.0 {
            continue;
        }
        let el: Vec<f64> = fc.iter().zip(fd).map(|(a, b)| a - b).collect();
        elastic_sum += el[k];
        damper_sum += fd[k];
        println!(
            "| {f:?}: elastic | {:.2} | {:.2} |",
            el[k] / MN,
            max(&el) / MN
        );
        println!(
            "| {f:?}: contact damper −c_c ṡ | {:.2} | {:.2} |",
            fd[k] / MN,
            max(fd) / MN
        );
    }
    println!(
        "| all features: elastic / damper | {:.2} / {:.2} | |",
        elastic_sum / MN,
        damper_sum / MN
    );
    println!(
        "| adhesion (all features) | {:.3} | {:.3} |",
        h.adhesion[k] / MN,
        max(&h.adhesion) / MN
    );
    println!(
        "| AB springs front / rear | {:.2} / {:.2} | {:.2} / {:.2} |",
        h.front_force[k] / MN,
        h.rear_force[k] / MN,
        max(&h.front_force) / MN,
        max(&h.rear_force) / MN
    );
    println!(
        "| shock force | {:.2} | {:.2} |",
        h.shock_force[k] / MN,
        max(&h.shock_force) / MN
    );
    // Heave balance: m z̈ = ΣN + F_f + F_r − F − k z − c ż − shock (friction's heave part is
    // second order in the angles).
    let normal: f64 = h.feature_normal.iter().map(|n| n[k]).sum();
    let suspension = u.heave_stiffness * h.heave[k] + c_heave * h.heave_rate[k];
    let inertia =
        normal + h.front_force[k] + h.rear_force[k] - u.preload - suspension - h.shock_force[k];
    println!(
        "| preload / suspension | {:.2} / {:.4} | |",
        u.preload / MN,
        suspension / MN
    );
    println!("| heave inertia m z̈ (balance) | {:.2} | |", inertia / MN);
    println!("| z̈ at the peak (m/s²) | {:.3e} | |", inertia / m);
    // The pads' first solid contact: when, how fast they closed, the slider's heave rate.
    let pad_idx: Vec<usize> = (0..h.features.len())
        .filter(|&i| format!("{:?}", h.features[i]).starts_with("Pad"))
        .collect();
    if let Some(k0) =
        (1..h.len()).find(|&k| pad_idx.iter().any(|&i| h.feature_spacing[i][k] < 1.5 * NM))
    {
        let rate = pad_idx
            .iter()
            .map(|&i| (h.feature_spacing[i][k0] - h.feature_spacing[i][k0 - 1]) / h.dt)
            .fold(f64::INFINITY, f64::min);
        println!(
            "| first pad contact: t (ms), pad closing speed −ṡ (m/s), heave rate ż (m/s) | {:.5} | {:.4} / {:.4} |",
            k0 as f64 * h.dt * 1e3,
            -rate,
            h.heave_rate[k0]
        );
    }
}

fn shock(pipeline: &toml::Value, variants: &[String], l: &Lookups, tracks: &Tracks) {
    println!("\n### Shock on the {}\n", tracks.name);
    let runs: Vec<(String, ThreeDofParams, Result<History3Dof, String>)> = variants
        .par_iter()
        .map(|v| {
            let p = params(pipeline, "shock", &variant_keys(v));
            let h = run(&p, CaseInterface::Isbl, l, tracks, variant_cap(v), |_| {});
            (v.clone(), p, h)
        })
        .collect();
    println!("| variant | peak F_c (mN) | features in solid contact | deepest pad (nm) | bulge closest (nm) |");
    println!("|---|---:|---|---:|---:|");
    for (name, _, h) in &runs {
        match h {
            Ok(h) => {
                let min = |i: usize| {
                    h.feature_spacing[i]
                        .iter()
                        .cloned()
                        .fold(f64::INFINITY, f64::min)
                };
                let touched: Vec<String> = h
                    .features
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| min(*i) < 1.5 * NM)
                    .map(|(_, f)| format!("{f:?}"))
                    .collect();
                let pad = h
                    .features
                    .iter()
                    .enumerate()
                    .filter(|(_, f)| format!("{f:?}").starts_with("Pad"))
                    .map(|(i, _)| min(i))
                    .fold(f64::INFINITY, f64::min);
                let bulge = h
                    .bulge_spacing
                    .iter()
                    .cloned()
                    .fold(f64::INFINITY, f64::min);
                println!(
                    "| `{name}` | {:.1} | {} | {:.2} | {:.2} |",
                    h.contact_force.iter().cloned().fold(0.0, f64::max) / MN,
                    touched.join(", "),
                    pad / NM,
                    bulge / NM
                );
            }
            Err(e) => println!("| `{name}` | failed: {e} | | | |"),
        }
    }
    for (name, p, h) in &runs {
        if let Ok(h) = h {
            shock_breakdown(name, h, p);
        }
    }
}

fn zeta(pipeline: &toml::Value, variants: &[String], l: &Lookups, tracks: &Tracks) {
    println!(
        "\n### Shock peak contact force (mN) against the contact damping ratio ζ_c ({})\n",
        tracks.name
    );
    let zetas = [0.0, 0.05, 0.1, 0.3, 0.5, 1.0];
    let jobs: Vec<(usize, f64)> = (0..variants.len())
        .flat_map(|v| zetas.iter().map(move |z| (v, *z)))
        .collect();
    let out: Vec<String> = jobs
        .par_iter()
        .map(|(v, z)| {
            let mut keys = variant_keys(&variants[*v]);
            keys.push(("contact_damping_ratio".into(), toml::Value::Float(*z)));
            let p = params(pipeline, "shock", &keys);
            match run(
                &p,
                CaseInterface::Isbl,
                l,
                tracks,
                variant_cap(&variants[*v]),
                |_| {},
            ) {
                Ok(h) => {
                    let k = h
                        .contact_force
                        .iter()
                        .enumerate()
                        .fold(
                            (0, 0.0),
                            |(i, v), (j, x)| if *x > v { (j, *x) } else { (i, v) },
                        )
                        .0;
                    let damper: f64 = h.feature_contact_damping.iter().map(|d| d[k]).sum();
                    format!("{:.1} ({:.1})", h.contact_force[k] / MN, damper / MN)
                }
                Err(e) => format!("failed: {e}"),
            }
        })
        .collect();
    print!("| variant |");
    for z in zetas {
        print!(" ζ_c = {z} |");
    }
    println!();
    print!("|---|");
    for _ in zetas {
        print!("---:|");
    }
    println!();
    for (v, name) in variants.iter().enumerate() {
        print!("| `{name}` |");
        for j in 0..zetas.len() {
            print!(" {} |", out[v * zetas.len() + j]);
        }
        println!();
    }
    println!("\n(in brackets: the damper's part at the peak, mN)");
}

/// Static stability of the AB along the push-back calibration of both shipped curves.
fn stability(pipeline: &toml::Value) {
    println!("\n### Static stability of the air bearing along the push-back calibration\n");
    println!("Heave stiffness of the AB springs −∂(F_f + F_r)/∂z (N/m) and the heave–pitch eigenvalues λ of M⁻¹K_t (λ < 0: divergence, growth time 1/√−λ) at the calibrated static states (no DMW, no contact).\n");
    for (instance, hs) in [("shock", [5.0, 12.0]), ("lubricant_cases", [5.0, 18.0])] {
        for v in [
            "hdi",
            "ab_spring_law=linear",
            "ab_spring_law=linear+ab_stiffness_argument=static_pole_tip",
            "ab_nominal_force=as_printed",
            "air_bearing=faithful",
        ] {
            let p = params(pipeline, instance, &variant_keys(v));
            let model = p.model();
            let ab = ThreeDofAirBearing::new(&model.air_bearing).unwrap();
            let table = match delta_force_table(&model) {
                Ok(t) => t,
                Err(e) => {
                    println!("- `{instance}` `{v}`: calibration failed: {e}");
                    continue;
                }
            };
            println!(
                "\n`[three_dof.{instance}]` + `{v}` ({} push-back, ΔF_AB table to {:.1} nm):\n",
                p.pushback,
                table.max_actuation() / NM
            );
            println!("| h_TFC (nm) | ΔF_AB (mN) | PT (nm) | TE rise (nm) | K_zz springs (N/m) | λ₁ | λ₂ | state |");
            println!("|---:|---:|---:|---:|---:|---:|---:|---|");
            let grid: Vec<f64> = (0..=((hs[1] - hs[0]) as usize))
                .map(|i| hs[0] + i as f64)
                .collect();
            for h in grid {
                let s = match static_start(&model, &ab, &table, h * NM) {
                    Ok(s) => s,
                    Err(_) => {
                        // Continuation in ΔF_AB from the unactuated balance at this h: the largest
                        // ΔF_AB that still has an equilibrium on that branch.
                        let target = table.delta_force_at(h * NM);
                        let mut last = None;
                        let mut f = 0.0;
                        while f <= target {
                            match ab.solve_static(
                                h * NM,
                                hdi::dynamics::three_dof::air_bearing::StaticCondition::GivenForce(
                                    f,
                                ),
                                last.as_ref(),
                                false,
                            ) {
                                Ok(s) => last = Some(s),
                                Err(_) => break,
                            }
                            f += 0.01 * MN;
                        }
                        let fold = last.map_or("none at ΔF_AB = 0".into(), |s| {
                            format!(
                                "up to ΔF_AB = {:.2} mN (PT {:.2} nm, TE rise {:.2} nm)",
                                s.delta_force / MN,
                                s.pole_tip / NM,
                                s.te_rise / NM
                            )
                        });
                        println!(
                            "| {h:.0} | {:.2} | — | — | — | — | — | no equilibrium on the unactuated branch: it exists {fold} |",
                            target / MN
                        );
                        continue;
                    }
                };
                let s = &s;
                let k = ab.tangent_stiffness(s);
                let eig = ab.heave_pitch_eigenvalues(s);
                let fmt = |c: nalgebra::Complex<f64>| {
                    if c.im.abs() > 1e-9 * c.re.abs() {
                        format!("{:.3e} {:+.2e}i", c.re, c.im)
                    } else {
                        format!("{:.3e}", c.re)
                    }
                };
                let state = if eig[0].re < 0.0 {
                    format!("diverges, 1/√−λ = {:.2} µs", 1e6 / (-eig[0].re).sqrt())
                } else if eig[0].im.abs() > 0.0 {
                    "flutter".into()
                } else {
                    format!(
                        "stable, {:.0} / {:.0} kHz",
                        eig[0].re.sqrt() / std::f64::consts::TAU / 1e3,
                        eig[1].re.sqrt() / std::f64::consts::TAU / 1e3
                    )
                };
                println!(
                    "| {h:.0} | {:.2} | {:.2} | {:.2} | {:.3e} | {} | {} | {} |",
                    s.delta_force / MN,
                    s.pole_tip / NM,
                    s.te_rise / NM,
                    k[(0, 0)] - model.air_bearing.suspension.heave_stiffness,
                    fmt(eig[0]),
                    fmt(eig[1]),
                    state
                );
            }
        }
    }
}

/// Step convergence of the cases a variant reaches a band with: the same case with rtol and
/// the contact step cap tightened tenfold.
fn steps(pipeline: &toml::Value, variants: &[String], l: &Lookups, tracks: &Tracks) {
    println!(
        "\n### Step convergence ({}): rtol 1e-8 → 1e-9, contact step cap 10 ns → 1 ns\n",
        tracks.name
    );
    println!("| variant | case | JTC / steady / flying (%) or shock peak (mN), default steps | tightened |");
    println!("|---|---|---|---|");
    let lube = lubricant_surface(l);
    let jobs: Vec<(String, Option<LubricantCase>)> = variants
        .iter()
        .flat_map(|v| {
            [
                (v.clone(), Some(LubricantCase::Reference)),
                (v.clone(), Some(LubricantCase::HumidityTemperature)),
                (v.clone(), None),
            ]
        })
        .collect();
    let out: Vec<String> = jobs
        .par_iter()
        .map(|(v, c)| {
            let describe = |tight: bool| -> String {
                let tweak = |o: &mut hdi::dynamics::three_dof::case::Options3Dof| {
                    if tight {
                        o.rtol = 1e-9;
                        o.contact_max_step = 1e-9;
                    }
                };
                match c {
                    Some(c) => {
                        let p = params(pipeline, "lubricant_cases", &variant_keys(v));
                        match run(&p, CaseInterface::Mtl(*c), l, tracks, variant_cap(v), tweak) {
                            Ok(h) => {
                                let t = h.table_4_4(&p.profile, lube);
                                format!(
                                    "{} / {} / {} ({} steps)",
                                    pct(t.jump_to_contact_bv),
                                    pct(t.steady_contact_bv),
                                    pct(t.flying_fhm),
                                    h.stats.accepted_steps
                                )
                            }
                            Err(e) => format!("failed: {e}"),
                        }
                    }
                    None => {
                        let p = params(pipeline, "shock", &variant_keys(v));
                        match run(&p, CaseInterface::Isbl, l, tracks, variant_cap(v), tweak) {
                            Ok(h) => format!(
                                "{:.1} mN ({} steps)",
                                h.contact_force.iter().cloned().fold(0.0, f64::max) / MN,
                                h.stats.accepted_steps
                            ),
                            Err(e) => format!("failed: {e}"),
                        }
                    }
                }
            };
            let case = c.map_or("shock".to_string(), |c| format!("{c:?}"));
            format!(
                "| `{v}` | {case} | {} | {} |",
                describe(false),
                describe(true)
            )
        })
        .collect();
    for line in out {
        println!("{line}");
    }
}

/// The pad's contact law at deep penetration: what one pad carries at solid spacing s.
fn pads(l: &Lookups) {
    println!(
        "\n### One pad's ISBL contact (nominal area 2π R_PAD·3σ = {:.2} µm², hardness 13 GPa)\n",
        2.0 * std::f64::consts::PI * 1e-3 * 1.5e-9 * 1e12
    );
    println!("| s (nm) | h* | P (GPa) | k_c (GPa/nm) | A_r/A_n | tangent F_c = A_n k_c (3σ − s) (mN) | static A_n P (mN) | mean pressure F_c/A_n (GPa) |");
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|");
    let sigma = l.solid.model().params().sigma;
    let area = 2.0 * std::f64::consts::PI * 1e-3 * 3.0 * sigma;
    for s_nm in [1.0, 0.0, -1.0, -2.0, -4.0, -6.0, -8.0, -10.0] {
        let s = s_nm * NM;
        let at = l.solid.at(s).unwrap();
        let tangent = area * at.stiffness * (3.0 * sigma - s);
        println!(
            "| {s_nm:.0} | {:.0} | {:.3} | {:.3} | {:.3} | {:.1} | {:.1} | {:.2} |",
            s / sigma,
            at.pressure * 1e-9,
            at.stiffness * 1e-18,
            at.real_area_fraction,
            tangent / MN,
            area * at.pressure / MN,
            tangent / area * 1e-9
        );
    }
}

fn main() {
    let mut pipeline_path = "pipeline.toml".to_string();
    let mut record_path: Option<String> = None;
    let mut parts = vec![
        "table44".to_string(),
        "shock".into(),
        "zeta".into(),
        "window".into(),
        "stability".into(),
    ];
    let mut variants: Vec<String> = VARIANTS.iter().map(|s| s.to_string()).collect();
    for a in std::env::args().skip(1) {
        match a.split_once('=') {
            Some(("pipeline", v)) => pipeline_path = v.into(),
            Some(("record", v)) => record_path = Some(v.into()),
            Some(("parts", v)) => parts = v.split(',').map(str::to_string).collect(),
            Some(("variants", v)) => variants = v.split(',').map(str::to_string).collect(),
            _ => panic!("unknown argument {a}"),
        }
    }
    let text = std::fs::read_to_string(&pipeline_path).expect("pipeline.toml");
    let pipeline: toml::Value = toml::from_str(&text).expect("pipeline.toml parses");
    let l = lookups();
    let mut inputs = vec![synthetic()];
    if let Some(r) = &record_path {
        inputs.push(record(r));
    }
    let has = |p: &str| parts.iter().any(|x| x == p);
    if has("stability") {
        stability(&pipeline);
    }
    if has("pads") {
        pads(&l);
    }
    for tracks in &inputs {
        if has("table44") || has("window") {
            let (base, runs) = table44_runs(&pipeline, &variants, &l, tracks);
            if has("table44") {
                table44(&base, &runs, &l, tracks);
            }
            if has("window") {
                windows(&base, &runs, &l, tracks);
            }
        }
        if has("shock") {
            shock(&pipeline, &variants, &l, tracks);
        }
        if has("zeta") {
            let zv: Vec<String> = variants
                .iter()
                .filter(|v| {
                    let head = v.split('+').next().unwrap_or("");
                    head == "hdi" || head == "air_bearing=faithful"
                })
                .cloned()
                .collect();
            zeta(&pipeline, &zv, &l, tracks);
        }
        if has("steps") {
            steps(&pipeline, &variants, &l, tracks);
        }
    }
}
