//! Surfaces stage physics and I/O: AFM height maps → levelled field → σ, R, η, β.
//!
//! Everything in here is pure (no pipeline, no cache); the `surfaces` stage wires it into
//! the pipeline. Conventions (docs/surfaces.md): `z[[j, i]]`, row `j` = slow-scan
//! axis y (one scan line per row), column `i` = fast-scan axis x; row 0 is the top of the image
//! as the instrument software displays it; heights and lengths in metres.

pub mod bulge;
pub mod combine;
pub mod crop;
pub mod filter;
pub mod io;
pub mod level;
pub mod roughness;
pub mod spectra;
pub mod synth;

use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// A height map in SI units with its provenance.
#[derive(Debug, Clone)]
pub struct HeightMap {
    /// Heights in metres, shape `[ny, nx]`.
    pub z: Array2<f64>,
    /// Pixel spacing along x (columns), metres.
    pub dx: f64,
    /// Pixel spacing along y (rows), metres.
    pub dy: f64,
    /// Lateral offsets of pixel (0, 0), metres.
    pub x0: f64,
    pub y0: f64,
    /// Channel name as the file calls it (e.g. "Height Sensor", "ZSensor").
    pub channel: String,
    /// `false` marks invalid pixels (NaN, saturated, masked); `None` = all valid.
    pub valid: Option<Array2<bool>>,
    /// Whether the field is periodic (synthetic surfaces); enables spectral moments and
    /// wrap-around summit detection.
    pub periodic: bool,
    /// Format name and header key/values, for provenance.
    pub source: SourceInfo,
    /// Operations applied since reading, in order.
    pub history: Vec<Step>,
}

#[derive(Debug, Clone, Default)]
pub struct SourceInfo {
    /// Short format id: "ascii", "xyz", "gwy", "nanoscope", "gsf", "ibw", "sur", "sdf",
    /// "metropro", "x3p".
    pub format: String,
    pub header: BTreeMap<String, String>,
}

/// One processing step, recorded in the output and the cache key.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    pub name: String,
    pub params: BTreeMap<String, String>,
}

impl HeightMap {
    pub fn nx(&self) -> usize {
        self.z.ncols()
    }
    pub fn ny(&self) -> usize {
        self.z.nrows()
    }
    /// Physical size along x and y (pixel count × spacing), metres.
    pub fn size(&self) -> (f64, f64) {
        (self.nx() as f64 * self.dx, self.ny() as f64 * self.dy)
    }
    pub fn is_valid(&self, j: usize, i: usize) -> bool {
        self.valid.as_ref().is_none_or(|v| v[[j, i]])
    }
    /// Fraction of pixels marked invalid.
    pub fn masked_fraction(&self) -> f64 {
        match &self.valid {
            None => 0.0,
            Some(v) => v.iter().filter(|ok| !**ok).count() as f64 / v.len() as f64,
        }
    }
    pub fn push_step(&mut self, name: &str, params: &[(&str, String)]) {
        self.history.push(Step {
            name: name.to_string(),
            params: params
                .iter()
                .map(|(k, v)| (k.to_string(), v.clone()))
                .collect(),
        });
    }
}

/// Errors of the surfaces domain. Each names the file (where there is one) and what was wrong.
#[derive(Debug, thiserror::Error)]
pub enum SurfaceError {
    #[error("cannot read {path}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file is of a known format but its content is wrong (truncated, bad header, ...).
    #[error("{path}: {reason}")]
    Format { path: PathBuf, reason: String },
    /// The file is not one of the formats hdi reads.
    #[error("{path}: unsupported height-map format ({reason})")]
    Unsupported { path: PathBuf, reason: String },
    /// The data are unusable for the requested operation (all NaN, too small, ...).
    #[error("{0}")]
    InvalidData(String),
    /// A parameter outside its valid range.
    #[error("parameter `{name}` = {value} is out of range: {expected}")]
    Parameter {
        name: String,
        value: String,
        expected: String,
    },
}

pub type Result<T> = std::result::Result<T, SurfaceError>;
