//! The `[doe]` stage through the binary: the shipped design runs, is fully cached, survives a
//! kill mid-run without losing a finished case, and bad keys name the key. Its response
//! surfaces are checked against an independent least-squares solve of the design points it
//! wrote, and its annealing optimum against a brute-force scan of that surrogate.
use crate::common::*;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::{Duration, Instant};

fn stored_cases(processed: &Path) -> usize {
    std::fs::read_dir(processed.join(".hdi/store/case"))
        .map(|d| {
            d.filter_map(|e| e.ok())
                .filter(|e| e.path().is_dir())
                .count()
        })
        .unwrap_or(0)
}

#[test]
fn doe_runs_resumes_after_a_kill_and_is_fully_cached() {
    let p = Project::shipped();
    // The annealing on the surrogate (§9's "surrogate" objective): cheap evaluations, so a long
    // enough run to reach the optimum that the brute-force scan below finds.
    let cfg = p.config();
    let annealing_on_surrogate = cfg
        .replacen(
            "sa_objective = \"simulation\"",
            "sa_objective = \"surrogate\"",
            1,
        )
        .replacen("sa_max_evaluations = 12", "sa_max_evaluations = 3000", 1);
    assert_ne!(annealing_on_surrogate, cfg);
    p.set_config(&annealing_on_surrogate);
    // Upstream first, so the kill below lands inside the DOE's own cases.
    let o = p.run(&["run", "--only", "improved", "disk_md"]);
    assert_ok(&o);
    let before = stored_cases(&p.processed());
    let mut child = hdi()
        .current_dir(p.path())
        .args(["run", "--only", "bulge_design"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("spawn hdi");
    let started = Instant::now();
    while stored_cases(&p.processed()) < before + 12 && started.elapsed() < Duration::from_secs(600)
    {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    child.kill().ok();
    child.wait().unwrap();
    let finished = stored_cases(&p.processed()) - before;
    assert!(finished >= 12, "only {finished} cases before the kill");

    let o = p.run(&["run", "--only", "bulge_design"]);
    assert_ok(&o);
    let out = p.processed().join("bulge_design");
    let result: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("result.json")).unwrap()).unwrap();
    assert_eq!(result["cases"], 108);
    // Every case finished before the kill was reused (the run had not reached the annealing).
    let cached = cases_cached(&out) as usize;
    assert!(
        cached >= finished.min(108),
        "{cached} cached of {finished} finished"
    );
    for f in [
        "design.csv",
        "coefficients.parquet",
        "anova.csv",
        "predictive_equations.csv",
        "annealing.csv",
        "sensitivity.csv",
        "comparison.csv",
        "contours_9p0nm.png",
        "residuals_12p0nm.png",
        "annealing.png",
        "comparison.png",
    ] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    let design = csv_rows(&out.join("design.csv"));
    assert_eq!(design.len(), 108);
    // The 23-term quartic on 27 points leaves 4 residual df at every level.
    let anova = csv_rows(&out.join("anova.csv"));
    let residual: Vec<_> = anova.iter().filter(|r| r["source"] == "residual").collect();
    assert_eq!(residual.len(), 4);
    assert!(residual.iter().all(|r| r["df"] == "4"), "{residual:?}");
    // Table 2.7: three fixed-factor equations per level, a_tfc at 5 and 16 nm.
    let pred = csv_rows(&out.join("predictive_equations.csv"));
    assert_eq!(pred.len(), 12);
    assert_eq!(pred[0]["fixed_factor"], "a_tfc");
    assert_eq!(pred[3]["fixed_factor"], "x_tfc");
    check_surfaces_against_an_independent_fit(&out, &design, &result);
    check_annealing_against_a_brute_force_scan(&design, &result);

    // Fully cached: a rerun recomputes nothing.
    let again = p.run(&["run", "--only", "bulge_design"]);
    assert_ok(&again);
    assert!(
        stderr(&again).contains("nothing to do"),
        "{}",
        stderr(&again)
    );
}

type Row = BTreeMap<String, String>;

fn num(row: &Row, key: &str) -> f64 {
    row[key]
        .parse()
        .unwrap_or_else(|_| panic!("{key} = {:?}", row[key]))
}

/// The 23 monomials of the degree-4 model on three coded factors: each factor to at most the
/// second power, total degree at most four (dissertation §2.3; docs/doe.md). Powers per factor.
fn quartic_terms() -> Vec<[u32; 3]> {
    let mut t = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                if i + j + k <= 4 {
                    t.push([i, j, k]);
                }
            }
        }
    }
    assert_eq!(t.len(), 23);
    t
}

fn monomial(powers: &[u32; 3], c: &[f64; 3]) -> f64 {
    (0..3).map(|f| c[f].powi(powers[f] as i32)).product()
}

/// A term name of the coefficient table ("b0", "b12", "b1123") as powers per factor.
fn powers_of(term: &str) -> [u32; 3] {
    let mut p = [0; 3];
    for d in term.trim_start_matches('b').chars().filter(|&d| d != '0') {
        p[d.to_digit(10).unwrap() as usize - 1] += 1;
    }
    p
}

/// One level's least-squares fit of ξ on the 27 coded design points, by SVD (not hdi's QR).
struct IndependentFit {
    actuation_nm: f64,
    coefficients: Vec<f64>,
    rss: f64,
    r_squared: f64,
}

impl IndependentFit {
    fn predict(&self, c: &[f64; 3]) -> f64 {
        quartic_terms()
            .iter()
            .zip(&self.coefficients)
            .map(|(p, b)| b * monomial(p, c))
            .sum()
    }
}

fn coded(row: &Row) -> [f64; 3] {
    [
        num(row, "a_tfc_coded"),
        num(row, "w_tfc_coded"),
        num(row, "x_tfc_coded"),
    ]
}

fn independent_fits(design: &[Row]) -> Vec<IndependentFit> {
    let terms = quartic_terms();
    let mut levels: Vec<f64> = design.iter().map(|r| num(r, "actuation_nm")).collect();
    levels.sort_by(f64::total_cmp);
    levels.dedup();
    levels
        .into_iter()
        .map(|h| {
            let rows: Vec<&Row> = design
                .iter()
                .filter(|r| num(r, "actuation_nm") == h)
                .collect();
            assert_eq!(rows.len(), 27, "{h} nm");
            let x = nalgebra::DMatrix::from_fn(27, terms.len(), |i, j| {
                monomial(&terms[j], &coded(rows[i]))
            });
            let y = nalgebra::DVector::from_iterator(27, rows.iter().map(|r| num(r, "xi")));
            let beta = x.clone().svd(true, true).solve(&y, 1e-12).unwrap();
            let resid = &y - &x * &beta;
            let mean = y.mean();
            let tss: f64 = y.iter().map(|v| (v - mean).powi(2)).sum();
            let rss = resid.norm_squared();
            IndependentFit {
                actuation_nm: h,
                coefficients: beta.iter().copied().collect(),
                rss,
                r_squared: 1.0 - rss / tss,
            }
        })
        .collect()
}

/// The stage's response surfaces (coefficients.parquet, result.json, anova.csv) are the
/// least-squares fits of the ξ values it wrote to design.csv.
fn check_surfaces_against_an_independent_fit(
    out: &Path,
    design: &[Row],
    result: &serde_json::Value,
) {
    use polars_io::prelude::*;
    let fits = independent_fits(design);
    assert_eq!(fits.len(), 4);
    let file = std::fs::File::open(out.join("coefficients.parquet")).unwrap();
    let table = ParquetReader::new(file).finish().unwrap();
    let h_col = table.column("actuation_nm").unwrap().f64().unwrap().clone();
    let model = table.column("model").unwrap().str().unwrap().clone();
    let term = table.column("term").unwrap().str().unwrap().clone();
    let coef = table.column("coefficient").unwrap().f64().unwrap().clone();
    let anova = csv_rows(&out.join("anova.csv"));
    let terms = quartic_terms();
    for (k, fit) in fits.iter().enumerate() {
        let scale = fit.coefficients.iter().fold(0f64, |m, b| m.max(b.abs()));
        let mut seen = 0;
        for i in 0..table.height() {
            if h_col.get(i) != Some(fit.actuation_nm) || model.get(i) != Some("degree 4") {
                continue;
            }
            let powers = powers_of(term.get(i).unwrap());
            let j = terms.iter().position(|t| *t == powers).unwrap();
            let got = coef.get(i).unwrap();
            // Seven significant digits in the table, plus the conditioning of the two solves.
            assert!(
                (got - fit.coefficients[j]).abs() <= 1e-6 * scale,
                "{} nm, {}: {got} vs independent {}",
                fit.actuation_nm,
                term.get(i).unwrap(),
                fit.coefficients[j]
            );
            seen += 1;
        }
        assert_eq!(seen, 23, "{} nm", fit.actuation_nm);
        let summary = &result["fits"][k];
        assert!((summary["actuation_m"].as_f64().unwrap() * 1e9 - fit.actuation_nm).abs() < 1e-9);
        let rss = summary["degree_4"]["rss"].as_f64().unwrap();
        let r2 = summary["degree_4"]["r_squared"].as_f64().unwrap();
        let tss: f64 = fit.rss / (1.0 - fit.r_squared);
        // The design's ξ carry seven digits: the residual is known to ~1e-6 of the total.
        assert!(
            (rss - fit.rss).abs() <= 1e-6 * tss,
            "{} nm: RSS {rss} vs {}",
            fit.actuation_nm,
            fit.rss
        );
        assert!(
            (r2 - fit.r_squared).abs() <= 1e-6,
            "{} nm: R² {r2} vs {}",
            fit.actuation_nm,
            fit.r_squared
        );
        let residual = anova
            .iter()
            .find(|r| r["source"] == "residual" && num(r, "actuation_nm") == fit.actuation_nm)
            .unwrap();
        assert!(
            (num(residual, "sum_sq") - fit.rss).abs() <= 1e-6 * tss,
            "{} nm: ANOVA residual {residual:?} vs {}",
            fit.actuation_nm,
            fit.rss
        );
    }
}

/// §9's annealing objective: ξ when positive, else 1 + |ξ|.
fn objective(xi: f64) -> f64 {
    if xi > 0.0 {
        xi
    } else {
        1.0 + xi.abs()
    }
}

/// The annealing optimum on the surrogate is the minimum a brute-force scan of the same
/// surrogate (the independent fits, linear in the actuation between levels) finds on the box.
fn check_annealing_against_a_brute_force_scan(design: &[Row], result: &serde_json::Value) {
    let fits = independent_fits(design);
    let h = 9.7;
    let k = fits
        .windows(2)
        .position(|w| w[0].actuation_nm <= h && h <= w[1].actuation_nm)
        .unwrap();
    let t = (h - fits[k].actuation_nm) / (fits[k + 1].actuation_nm - fits[k].actuation_nm);
    let xi = |c: &[f64; 3]| (1.0 - t) * fits[k].predict(c) + t * fits[k + 1].predict(c);
    // Coarse grid over the coded box, then a fine one around its best node.
    let n = 40;
    let node = |i: usize, n: usize, lo: f64, hi: f64| lo + (hi - lo) * i as f64 / n as f64;
    let mut best = (f64::INFINITY, [0.0; 3]);
    for i in 0..=n {
        for j in 0..=n {
            for l in 0..=n {
                let c = [
                    node(i, n, -1.0, 1.0),
                    node(j, n, -1.0, 1.0),
                    node(l, n, -1.0, 1.0),
                ];
                let v = objective(xi(&c));
                if v < best.0 {
                    best = (v, c);
                }
            }
        }
    }
    let step = 2.0 / n as f64;
    let centre = best.1;
    let lo = centre.map(|v| (v - step).max(-1.0));
    let hi = centre.map(|v| (v + step).min(1.0));
    let m = 40;
    for i in 0..=m {
        for j in 0..=m {
            for l in 0..=m {
                let c = [
                    node(i, m, lo[0], hi[0]),
                    node(j, m, lo[1], hi[1]),
                    node(l, m, lo[2], hi[2]),
                ];
                let v = objective(xi(&c));
                if v < best.0 {
                    best = (v, c);
                }
            }
        }
    }
    let opt = &result["optimum"];
    assert_eq!(opt["objective"], "surrogate", "{opt}");
    let decode_back = |v: f64, levels: [f64; 3]| (v * 1e6 - levels[1]) / (levels[2] - levels[1]);
    let c = [
        decode_back(opt["a_m"].as_f64().unwrap(), [1.0, 3.0, 5.0]),
        decode_back(opt["w_m"].as_f64().unwrap(), [10.0, 50.0, 90.0]),
        decode_back(opt["x_m"].as_f64().unwrap(), [5.0, 8.0, 11.0]),
    ];
    assert!(c.iter().all(|v| v.abs() <= 1.0 + 1e-9), "{c:?}");
    // The ξ the stage reports at its optimum is the surrogate's value there.
    let reported = opt["xi"].as_f64().unwrap();
    let span = fits
        .iter()
        .map(|f| f.rss / (1.0 - f.r_squared))
        .fold(0.0, f64::max)
        .sqrt();
    assert!(
        (reported - xi(&c)).abs() <= 1e-6 * span.max(1e-12),
        "optimum ξ {reported} vs surrogate {} at {c:?}",
        xi(&c)
    );
    eprintln!(
        "annealing: J {} at {c:?}; brute force: J {} at {:?}",
        objective(reported),
        best.0,
        best.1
    );
    // No point of the box is better than the scan's minimum (beyond the fine grid's step)…
    assert!(
        objective(reported) >= best.0 - 1e-3 * span,
        "{} < {}",
        objective(reported),
        best.0
    );
    // …and the annealing found it.
    assert!(
        objective(reported) <= best.0 + 1e-3 * span,
        "annealing J {} at {c:?}, brute force {} at {:?}",
        objective(reported),
        best.0,
        best.1
    );
}

#[test]
fn bad_doe_keys_name_the_key() {
    let p = Project::shipped();
    let base = p.config();
    for (from, to, needle) in [
        (
            "a_tfc = [\"1 um\", \"3 um\", \"5 um\"]",
            "a_tfc = [\"5 um\", \"3 um\", \"1 um\"]",
            "doe.bulge_design.a_tfc",
        ),
        (
            "x_tfc = [\"5 um\", \"8 um\", \"11 um\"]",
            "x_tfc = [\"4 um\", \"7 um\", \"10 um\"]",
            "overhang",
        ),
        (
            "sa_objective = \"simulation\"",
            "sa_objective = \"guess\"",
            "doe.bulge_design.sa_objective",
        ),
        (
            "sa_start = [\"3 um\", \"10 um\", \"5 um\"]",
            "sa_start = [\"3 um\", \"100 um\", \"5 um\"]",
            "design box",
        ),
        (
            "actuations = [\"5 nm\", \"9 nm\", \"12 nm\", \"15 nm\"]",
            "actuations = [\"5 nm\", \"9 nm\", \"12 nm\", \"160 nm\"]",
            "doe.bulge_design.actuations",
        ),
    ] {
        let cfg = base.replacen(from, to, 1);
        assert_ne!(cfg, base, "{from}");
        p.set_config(&cfg);
        let o = p.run(&["run", "--only", "bulge_design"]);
        assert_clean_failure(&o, needle);
    }
}
