//! Touchdown, one convention for every area (docs/conventions.md; dissertation §2.2.1): the
//! smallest actuation whose steady window reaches solid contact (any sample with c < 0),
//! found by scanning an actuation grid upward from its start (0 nm by default) and refining
//! the first crossing by k-section to `resolution` (0.02 nm by default). Scanning from the
//! bottom is what makes it the *first* crossing: near the adhesion fold a case can touch,
//! fly and touch again as the actuation grows, and a bracket seeded elsewhere can land on a
//! later crossing.
//!
//! Pure: the caller supplies the cases through a batch predicate (so sweeps, calibration,
//! DOE and validation run their own cases, in parallel, with their own start states).

/// Where and how finely to look.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TouchdownSearch {
    /// First actuation of the scan (m); the convention is 0.
    pub start: f64,
    /// Last actuation of the scan (m).
    pub stop: f64,
    /// Scan grid step (m).
    pub step: f64,
    /// Width of the final bracket (m); the convention is 0.02 nm.
    pub resolution: f64,
    /// Cases per predicate call (scan and refinement), ≥ 1: the parallelism offered.
    pub batch: usize,
}

impl TouchdownSearch {
    /// The convention: 0 nm upward to `stop` on `step`, refined to 0.02 nm, `batch` cases at a
    /// time.
    pub fn convention(stop: f64, step: f64, batch: usize) -> Self {
        TouchdownSearch {
            start: 0.0,
            stop,
            step,
            resolution: 0.02e-9,
            batch,
        }
    }

    /// The scan grid, `start..=stop` by `step` (the end included to 1e-9 of a step).
    pub fn grid(&self) -> Vec<f64> {
        // NaN steps or ends fail these comparisons too, so they give an empty grid.
        let ordered = self.step > 0.0 && self.stop >= self.start;
        if !ordered {
            return Vec::new();
        }
        let n = ((self.stop - self.start) / self.step + 1e-9).floor() as usize;
        (0..=n).map(|i| self.start + i as f64 * self.step).collect()
    }
}

/// What the search found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Touchdown {
    /// The first actuation known to touch (upper end of the final bracket), `None` when no
    /// scanned case touches.
    pub actuation: Option<f64>,
    /// The largest actuation known to fly below it (lower end of the final bracket); `None`
    /// when the first scanned case already touches.
    pub last_flying: Option<f64>,
    /// Cases the search ran (known ones not counted).
    pub cases_run: usize,
}

/// Find touchdown. `known` are cases already run (actuation, touches) — e.g. a sweep's own
/// grid — and are not rerun; `touches(actuations)` runs the others and says, for each, whether
/// its steady window reaches solid contact.
pub fn find_touchdown<E>(
    search: &TouchdownSearch,
    known: &[(f64, bool)],
    mut touches: impl FnMut(&[f64]) -> Result<Vec<bool>, E>,
) -> Result<Touchdown, E> {
    let batch = search.batch.max(1);
    let tol = 1e-6 * search.step.abs().max(search.resolution.abs()).max(1e-15);
    let lookup = |a: f64| {
        known
            .iter()
            .find(|(k, _)| (k - a).abs() <= tol)
            .map(|(_, t)| *t)
    };
    let grid = search.grid();
    let mut cases_run = 0;
    // Scan: the first grid point that touches, in ascending order, `batch` unknowns at a time.
    let mut first_touch: Option<usize> = None;
    let mut i = 0;
    while i < grid.len() && first_touch.is_none() {
        let mut chunk: Vec<usize> = Vec::new();
        let mut j = i;
        // Walk forward: known points decide on the spot; unknown ones are gathered.
        while j < grid.len() && chunk.len() < batch {
            match lookup(grid[j]) {
                Some(true) if chunk.is_empty() => {
                    first_touch = Some(j);
                    break;
                }
                Some(true) => break, // a known touch: first run the unknowns before it
                Some(false) => {}
                None => chunk.push(j),
            }
            j += 1;
        }
        if first_touch.is_some() {
            break;
        }
        if chunk.is_empty() {
            i = j;
            continue;
        }
        let pts: Vec<f64> = chunk.iter().map(|&k| grid[k]).collect();
        let res = touches(&pts)?;
        cases_run += pts.len();
        if let Some(k) = chunk.iter().zip(&res).find(|(_, t)| **t).map(|(k, _)| *k) {
            first_touch = Some(k);
        } else {
            // Everything up to the last unknown flew; a known touch right after is next.
            i = chunk.last().map_or(j, |&k| k + 1);
        }
    }
    let Some(k) = first_touch else {
        return Ok(Touchdown {
            actuation: None,
            last_flying: grid.last().copied(),
            cases_run,
        });
    };
    if k == 0 {
        return Ok(Touchdown {
            actuation: Some(grid[0]),
            last_flying: None,
            cases_run,
        });
    }
    // Refine (lo flies, hi touches) by (batch+1)-section; known cases inside are used first.
    let (mut lo, mut hi) = (grid[k - 1], grid[k]);
    let inside = |lo: f64, hi: f64, want: bool| {
        known
            .iter()
            .filter(move |(a, t)| *t == want && *a > lo && *a < hi)
            .map(|(a, _)| *a)
    };
    if let Some(a) = inside(lo, hi, true).reduce(f64::min) {
        hi = a;
    }
    if let Some(a) = inside(lo, hi, false).reduce(f64::max) {
        lo = a;
    }
    while hi - lo > search.resolution {
        let parts = batch + 1;
        let pts: Vec<f64> = (1..parts)
            .map(|m| lo + (hi - lo) * m as f64 / parts as f64)
            .collect();
        let res = touches(&pts)?;
        cases_run += pts.len();
        match res.iter().position(|t| *t) {
            Some(0) => hi = pts[0],
            Some(m) => (lo, hi) = (pts[m - 1], pts[m]),
            None => lo = *pts.last().expect("batch ≥ 1"),
        }
    }
    Ok(Touchdown {
        actuation: Some(hi),
        last_flying: Some(lo),
        cases_run,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::convert::Infallible;

    const NM: f64 = 1e-9;

    /// A step at `td`, counting the calls.
    fn step_at(td: f64) -> impl FnMut(&[f64]) -> Result<Vec<bool>, Infallible> {
        move |a: &[f64]| Ok(a.iter().map(|&x| x >= td).collect())
    }

    #[test]
    fn finds_a_step_to_the_resolution_for_every_batch_size() {
        for batch in [1, 2, 3, 8] {
            let s = TouchdownSearch::convention(15.0 * NM, 0.2 * NM, batch);
            let td = 9.7345 * NM;
            let r = find_touchdown(&s, &[], step_at(td)).unwrap();
            let (a, lo) = (r.actuation.unwrap(), r.last_flying.unwrap());
            assert!(
                a >= td && a - td <= s.resolution + 1e-18,
                "batch {batch}: {a}"
            );
            assert!(lo < td && a - lo <= s.resolution + 1e-18);
        }
    }

    #[test]
    fn returns_the_first_crossing_not_a_later_one() {
        // Touches in 9.1–9.3 nm, flies again 9.3–10 nm, touches from 10 nm.
        let window = |x: f64| (9.1 * NM..9.3 * NM).contains(&x) || x >= 10.0 * NM;
        let s = TouchdownSearch::convention(15.0 * NM, 0.2 * NM, 4);
        let r = find_touchdown(&s, &[], |a: &[f64]| {
            Ok::<_, Infallible>(a.iter().map(|&x| window(x)).collect())
        })
        .unwrap();
        let a = r.actuation.unwrap();
        assert!((a - 9.1 * NM).abs() <= s.resolution + 1e-18, "{a}");
    }

    #[test]
    fn known_cases_are_not_rerun() {
        let s = TouchdownSearch::convention(15.0 * NM, 0.2 * NM, 2);
        let known: Vec<(f64, bool)> = s.grid().iter().map(|&a| (a, a >= 9.8 * NM)).collect();
        let mut ran = Vec::new();
        let r = find_touchdown(&s, &known, |a: &[f64]| {
            ran.extend_from_slice(a);
            Ok::<_, Infallible>(a.iter().map(|&x| x >= 9.71 * NM).collect())
        })
        .unwrap();
        assert!(ran.iter().all(|&a| a > 9.6 * NM && a < 9.8 * NM), "{ran:?}");
        assert_eq!(r.cases_run, ran.len());
        assert!((r.actuation.unwrap() - 9.71 * NM).abs() <= s.resolution + 1e-18);
    }

    #[test]
    fn no_contact_and_contact_from_the_start() {
        let s = TouchdownSearch::convention(3.0 * NM, 1.0 * NM, 2);
        let none = find_touchdown(&s, &[], step_at(10.0 * NM)).unwrap();
        assert_eq!(none.actuation, None);
        assert_eq!(none.cases_run, 4);
        let all = find_touchdown(&s, &[], step_at(-1.0)).unwrap();
        assert_eq!((all.actuation, all.last_flying), (Some(0.0), None));
    }

    #[test]
    fn errors_pass_through() {
        let s = TouchdownSearch::convention(3.0 * NM, 1.0 * NM, 2);
        let r = find_touchdown(&s, &[], |_: &[f64]| Err::<Vec<bool>, _>("case failed"));
        assert_eq!(r, Err("case failed"));
    }
}
