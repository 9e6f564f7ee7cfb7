//! The initial 2-DOF model's flying-height modulation at 4–7 nm (dissertation §2.1.3: mean FHM
//! 12.5 %; `hdi validate` row dyn-9) against the air-bearing damping ratio ζ (both AB springs,
//! default 0.03, §3.4 of the model's assumptions), on two DMW inputs: the shipped record (the
//! pipeline's `[dmw.disk_md]` track 1, as every `[simulate]` sees it) and the validation's
//! synthetic DMW (σ 1 nm, seed 1, the input of dyn-9). docs/model-form.md, "Miss 3".
//!
//! ```text
//! hdi run --only disk_md      # writes processed/disk_md/dmw.h5
//! cargo run --release --example initial_fhm_damping -- [record=processed/disk_md/dmw.h5]
//!     [zetas=0.005,0.01,0.02,0.03,0.05,0.1]
//! ```
//!
//! Every case is the validation's: the initial model on its own interface (Table 2.2, σ 0.87 nm,
//! 1.2σ criterion), static start, 2 ms, FHM (eq. 2.1) over 0.5–2 ms.

use hdi::artefacts::dmw_tracks::read_dmw_track;
use hdi::contact::isbl::{IsblModel, IsblParams};
use hdi::contact::lookup::IsblLookup;
use hdi::dmw::excitation_tracks::synthetic_dmw;
use hdi::dynamics::metrics::CaseParams;
use hdi::dynamics::params::initial_2dof;
use hdi::dynamics::two_dof::{DmwInput, SimOptions, TwoDofCase};
use rayon::prelude::*;
use std::path::PathBuf;

const NM: f64 = 1e-9;
const ACTUATIONS_NM: [f64; 4] = [4.0, 5.0, 6.0, 7.0];

/// A DMW input as the cases take it.
struct Input {
    label: &'static str,
    displacement: Vec<f64>,
    velocity: Vec<f64>,
    fs: f64,
}

impl Input {
    /// Standard deviation over the first 2.2 ms (what a 2 ms case with its transit sees).
    fn std_nm(&self) -> f64 {
        let n = ((2.2e-3 * self.fs) as usize).min(self.displacement.len());
        let x = &self.displacement[..n];
        let m = x.iter().sum::<f64>() / n as f64;
        (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n as f64).sqrt() / NM
    }
}

/// FHM (%) and mean clearance (nm) of one case; `None` if it fails (printed).
fn case(zeta: f64, h_nm: f64, isbl: &IsblLookup, dmw: &Input) -> Option<(f64, f64)> {
    let mut model = initial_2dof();
    model.air_bearing.front_damping_ratio = zeta;
    model.air_bearing.rear_damping_ratio = zeta;
    let options = SimOptions {
        static_init: true,
        ..SimOptions::default()
    };
    let input = DmwInput {
        displacement: &dmw.displacement,
        velocity: &dmw.velocity,
        sample_rate: dmw.fs,
    };
    let run = TwoDofCase::new(&model, h_nm * NM, isbl, Some(input), options)
        .and_then(|c| c.run())
        .map_err(|e| e.to_string())
        .and_then(|h| {
            h.metrics(&CaseParams::improved_2dof())
                .map_err(|e| e.to_string())
        });
    match run {
        Ok(m) => Some((m.vibration.percent, m.clearance_m.mean / NM)),
        Err(e) => {
            eprintln!("{} ζ = {zeta}, h = {h_nm} nm: {e}", dmw.label);
            None
        }
    }
}

fn main() {
    let mut record = PathBuf::from("processed/disk_md/dmw.h5");
    let mut zetas = vec![0.005, 0.01, 0.02, 0.03, 0.05, 0.1];
    for arg in std::env::args().skip(1) {
        match arg.split_once('=') {
            Some(("record", p)) => record = PathBuf::from(p),
            Some(("zetas", z)) => {
                zetas = z
                    .split(',')
                    .map(|s| s.trim().parse().expect("zetas=0.01,0.03"))
                    .collect()
            }
            _ => panic!("unknown argument {arg} (record=PATH, zetas=LIST)"),
        }
    }
    let track = match read_dmw_track(&record) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("{e}\nrun `hdi run --only disk_md` first, or pass record=PATH");
            std::process::exit(1);
        }
    };
    let synthetic = synthetic_dmw(2.2e-3, 4e6, 1e-9, 1).expect("synthetic DMW");
    let inputs = [
        Input {
            label: "shipped record (disk_md, track 1)",
            displacement: track.displacement,
            velocity: track.velocity,
            fs: track.sample_rate,
        },
        Input {
            label: "synthetic DMW σ 1 nm seed 1 (dyn-9)",
            displacement: synthetic.displacement,
            velocity: synthetic.velocity,
            fs: synthetic.fs,
        },
    ];
    let isbl =
        IsblLookup::build_standard(IsblModel::new(IsblParams::initial_2dof()).expect("ISBL"))
            .expect("force table");
    for dmw in &inputs {
        println!(
            "\n{} — DMW std {:.3} nm over 2.2 ms",
            dmw.label,
            dmw.std_nm()
        );
        println!("| ζ (AB) | FHM 4 / 5 / 6 / 7 nm (%) | mean (%) | c̄ 4 / 7 nm (nm) |");
        println!("|---:|---|---:|---|");
        let jobs: Vec<(f64, f64)> = zetas
            .iter()
            .flat_map(|&z| ACTUATIONS_NM.iter().map(move |&h| (z, h)))
            .collect();
        let results: Vec<Option<(f64, f64)>> = jobs
            .par_iter()
            .map(|&(z, h)| case(z, h, &isbl, dmw))
            .collect();
        for (i, z) in zetas.iter().enumerate() {
            let row = &results[i * 4..i * 4 + 4];
            let fhm: Vec<f64> = row.iter().map(|r| r.map_or(f64::NAN, |r| r.0)).collect();
            let mean = fhm.iter().sum::<f64>() / 4.0;
            let c = |k: usize| row[k].map_or(f64::NAN, |r| r.1);
            println!(
                "| {z} | {:.2} / {:.2} / {:.2} / {:.2} | {mean:.2} | {:.2} / {:.2} |",
                fhm[0],
                fhm[1],
                fhm[2],
                fhm[3],
                c(0),
                c(3)
            );
        }
    }
    println!("\npublished (§2.1.3): mean FHM 12.5 % at 4–7 nm");
}
