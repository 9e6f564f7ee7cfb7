//! Helpers shared by the reader tests.
use super::{read_height_map, ReadOptions};
use crate::surface::{HeightMap, SourceInfo};
use ndarray::Array2;
use std::path::PathBuf;

/// Writes `bytes` to `name` in a fresh temporary directory (kept alive by the returned guard).
pub fn write_temp(name: &str, bytes: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    (dir, path)
}

/// A plane plus two sinusoids (heights of a few nm), `nx` × `ny` pixels.
pub fn sample_map(nx: usize, ny: usize, dx: f64, dy: f64) -> HeightMap {
    let z = Array2::from_shape_fn((ny, nx), |(j, i)| {
        let (x, y) = (i as f64, j as f64);
        1e-10 * x - 0.5e-10 * y
            + 3e-9 * (0.37 * x).sin() * (0.21 * y).cos()
            + 0.7e-9 * (1.3 * x + 0.4 * y).sin()
    });
    HeightMap {
        z,
        dx,
        dy,
        x0: 0.0,
        y0: 0.0,
        channel: "Height".to_string(),
        valid: None,
        periodic: false,
        source: SourceInfo::default(),
        history: vec![],
    }
}

/// Writes `bytes` and reads them back with default options.
pub fn read_bytes(name: &str, bytes: &[u8]) -> crate::surface::Result<HeightMap> {
    let (_dir, path) = write_temp(name, bytes);
    read_height_map(&path, &ReadOptions::default())
}

/// Deterministic pseudo-random numbers (Knuth's MMIX LCG), so the fuzz cases are reproducible.
pub struct Lcg(pub u64);
impl Lcg {
    pub fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        self.0 >> 33
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Reads `valid` truncated at ~40 lengths and with bytes flipped at ~200 positions; every read
/// must return (Ok or an error naming the file), never panic. Returns how many reads failed, to show both paths ran.
pub fn fuzz_reader(name: &str, valid: &[u8]) -> usize {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    let mut failures = 0;
    let mut check = |bytes: &[u8], what: String| {
        std::fs::write(&path, bytes).unwrap();
        let outcome = std::panic::catch_unwind(|| read_height_map(&path, &ReadOptions::default()));
        match outcome {
            Ok(Ok(_)) => {}
            Ok(Err(e)) => {
                // One clear error that names the file.
                let message = e.to_string();
                assert!(
                    message.contains(name),
                    "the error on {what} does not name the file: {message}"
                );
                failures += 1
            }
            Err(_) => panic!("reader panicked on {what}"),
        }
    };
    let mut rng = Lcg(0x5EED_1234);
    for k in 0..40 {
        // Spread over the whole file, with extra cuts in the first few hundred (header) bytes.
        let cut = if k < 20 {
            rng.below(valid.len().min(600))
        } else {
            rng.below(valid.len())
        };
        check(&valid[..cut], format!("truncation at {cut}"));
    }
    for _ in 0..200 {
        let mut mutated = valid.to_vec();
        // Mostly hit the header/structure, where a flip changes sizes and counts.
        let at = if rng.below(4) < 3 {
            rng.below(valid.len().min(1024))
        } else {
            rng.below(valid.len())
        };
        let mask = 1u8 << rng.below(8);
        mutated[at] ^= mask;
        if rng.below(3) == 0 {
            mutated[at] = 0xFF;
        }
        check(&mutated, format!("byte {at} changed"));
    }
    failures
}

/// Relative closeness of two numbers.
pub fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

/// Asserts two maps have the same dimensions, spacing (to `rel_spacing`) and heights to
/// `abs_z` + `rel_z`·|z|.
pub fn assert_same_map(
    got: &HeightMap,
    want: &HeightMap,
    rel_spacing: f64,
    rel_z: f64,
    abs_z: f64,
) {
    assert_eq!(got.z.dim(), want.z.dim(), "dimensions");
    assert!(
        close(got.dx, want.dx, rel_spacing),
        "dx {} vs {}",
        got.dx,
        want.dx
    );
    assert!(
        close(got.dy, want.dy, rel_spacing),
        "dy {} vs {}",
        got.dy,
        want.dy
    );
    for ((j, i), &w) in want.z.indexed_iter() {
        let g = got.z[[j, i]];
        assert!(
            (g - w).abs() <= abs_z + rel_z * w.abs(),
            "z[[{j}, {i}]] = {g} vs {w}"
        );
    }
}

/// A file of `tests/data/surfaces/` (the reader samples and their fixtures).
pub fn surface_sample(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/surfaces")).join(name)
}

/// Mean and population standard deviation of the valid pixels (numpy's `mean`/`std` of the
/// reference scripts), and the number of invalid ones.
pub fn valid_stats(map: &HeightMap) -> (f64, f64, usize) {
    let vals: Vec<f64> = map
        .z
        .indexed_iter()
        .filter(|(ij, _)| map.valid.as_ref().is_none_or(|v| v[*ij]))
        .map(|(_, &z)| z)
        .collect();
    let n = vals.len() as f64;
    let mean = vals.iter().sum::<f64>() / n;
    let var = vals.iter().map(|z| (z - mean).powi(2)).sum::<f64>() / n;
    (mean, var.sqrt(), map.z.len() - vals.len())
}
