//! `--input FILE.npy`: the array a kernel times instead of its synthetic input, so that
//! `bench/compare.sh` gives hdi and the Python anchors identical data (bench/README.md).

use super::{BenchError, Result};
use crate::surface::HeightMap;
use std::path::Path;

fn invalid(path: &Path, message: String) -> BenchError {
    BenchError::Input {
        path: path.to_path_buf(),
        message,
    }
}

/// A float `.npy` array (f8 or f4, either byte order, C or Fortran order): its shape and
/// values in C order.
fn read(path: &Path) -> Result<(Vec<usize>, Vec<f64>)> {
    use crate::formats::npy::{parse, Dtype};
    let bytes = std::fs::read(path).map_err(BenchError::io("reading", path))?;
    let h = parse(&bytes, bytes.len()).map_err(|source| BenchError::Npy {
        path: path.to_path_buf(),
        source,
    })?;
    let s = match h.dtype {
        Dtype::Scalar(s) if s.kind == 'f' && (s.size == 8 || s.size == 4) => s,
        _ => {
            return Err(invalid(
                path,
                "the array must hold float64 or float32 values".into(),
            ))
        }
    };
    let data = bytes
        .get(h.data_offset..h.data_offset + h.data_len())
        .ok_or_else(|| invalid(path, "the data is shorter than its header says".into()))?;
    let values: Vec<f64> = data
        .chunks_exact(s.size)
        .map(|c| match (s.size, s.big_endian) {
            (8, false) => f64::from_le_bytes(c.try_into().unwrap_or([0; 8])),
            (8, true) => f64::from_be_bytes(c.try_into().unwrap_or([0; 8])),
            (_, false) => f32::from_le_bytes(c.try_into().unwrap_or([0; 4])) as f64,
            (_, true) => f32::from_be_bytes(c.try_into().unwrap_or([0; 4])) as f64,
        })
        .collect();
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(invalid(path, format!("value {i} is not finite")));
    }
    let values = if h.fortran_order && h.shape.len() == 2 {
        let (a, b) = (h.shape[0], h.shape[1]);
        let mut c = vec![0.0; values.len()];
        for i in 0..a {
            for j in 0..b {
                c[i * b + j] = values[i + j * a];
            }
        }
        c
    } else {
        values
    };
    Ok((h.shape, values))
}

/// A 1-D signal of at least 16 samples.
pub(super) fn read_signal(path: &Path) -> Result<Vec<f64>> {
    let (shape, values) = read(path)?;
    if shape.len() != 1 || shape[0] < 16 {
        return Err(invalid(
            path,
            format!("a 1-D signal of at least 16 samples is needed, the array has shape {shape:?}"),
        ));
    }
    Ok(values)
}

/// A 2-D array as a height map in metres over `size_m` along x (square pixels).
pub(super) fn read_map(path: &Path, size_m: f64) -> Result<HeightMap> {
    let (shape, values) = read(path)?;
    if shape.len() != 2 || shape[0] < 8 || shape[1] < 8 {
        return Err(invalid(
            path,
            format!("a 2-D map of at least 8 × 8 pixels is needed, the array has shape {shape:?}"),
        ));
    }
    let z = ndarray::Array2::from_shape_vec((shape[0], shape[1]), values)
        .map_err(|e| invalid(path, format!("shape: {e}")))?;
    let dx = size_m / shape[1] as f64;
    Ok(HeightMap {
        z,
        dx,
        dy: dx,
        x0: 0.0,
        y0: 0.0,
        channel: "height".into(),
        valid: None,
        periodic: false,
        source: crate::surface::SourceInfo {
            format: "npy".into(),
            header: Default::default(),
        },
        history: Vec::new(),
    })
}
