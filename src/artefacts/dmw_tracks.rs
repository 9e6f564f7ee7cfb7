//! The DMW tracks a `[dmw]` or `[excitation]` instance writes (`dmw.h5`, group `dmw/tracks`)
//! and the slider cases read: `D1…D3` displacement [m], `V1…V3` velocity [m/s] (track 1 the
//! original, 2 time-flipped, 3 negated time-flipped), a `time` axis whose `sampling_rate`
//! attribute gives the rate, and `edge_transient` flagging the filter's start/end transient.

use crate::error::{Error, Result};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// File name of the tracks in the producing stage's outputs.
pub const FILE: &str = "dmw.h5";
/// HDF5 group of the tracks.
pub const GROUP: &str = "dmw/tracks";
/// Time axis (its `SAMPLING_RATE` attribute is read).
pub const TIME: &str = "time";
pub const SAMPLING_RATE: &str = "sampling_rate";
/// 1 where the sample lies inside the filter's edge transient.
pub const EDGE_TRANSIENT: &str = "edge_transient";

/// Displacement dataset of track `k` (1–3).
pub fn displacement_name(k: usize) -> String {
    format!("D{k}")
}

/// Velocity dataset of track `k` (1–3).
pub fn velocity_name(k: usize) -> String {
    format!("V{k}")
}

/// A DMW track as the simulations use it: the transient-free part of one track.
pub struct DmwTrack {
    pub displacement: Vec<f64>,
    pub velocity: Vec<f64>,
    pub sample_rate: f64,
}

/// The tracks file of the upstream DMW (or excitation) instance `dmw`.
pub fn upstream_file(upstream_dirs: &BTreeMap<String, PathBuf>, dmw: &str) -> Result<PathBuf> {
    let dir = upstream_dirs
        .get(dmw)
        .ok_or_else(|| Error::MissingUpstreamFiles {
            kind: "dmw",
            name: dmw.to_string(),
        })?;
    Ok(dir.join(FILE))
}

/// Read track 1 of a `dmw.h5`, without the filter's edge transients.
pub fn read_dmw_track(path: &Path) -> Result<DmwTrack> {
    read_track(path, 1)
}

/// Tracks 1–3 (original, flipped, negated flipped) of a `dmw.h5`, edge transients dropped.
pub fn read_dmw_tracks(path: &Path) -> Result<[DmwTrack; 3]> {
    Ok([
        read_track(path, 1)?,
        read_track(path, 2)?,
        read_track(path, 3)?,
    ])
}

/// Track `k` (1–3) of a `dmw.h5`: `D{k}`, `V{k}`, without the filter's edge transients.
fn read_track(path: &Path, k: usize) -> Result<DmwTrack> {
    let e = |what: String| {
        move |source| Error::Hdf5Read {
            path: path.to_path_buf(),
            what,
            source,
        }
    };
    let file = hdf5::File::open(path).map_err(|source| Error::Hdf5Open {
        path: path.to_path_buf(),
        source,
    })?;
    let read = |name: &str| -> Result<Vec<f64>> {
        file.dataset(&format!("{GROUP}/{name}"))
            .and_then(|d| d.read_raw::<f64>())
            .map_err(e(format!("{GROUP}/{name}")))
    };
    let (d, v) = (read(&displacement_name(k))?, read(&velocity_name(k))?);
    let edge: Vec<u8> = file
        .dataset(&format!("{GROUP}/{EDGE_TRANSIENT}"))
        .and_then(|d| d.read_raw::<u8>())
        .unwrap_or_default();
    let time = file
        .dataset(&format!("{GROUP}/{TIME}"))
        .map_err(e(format!("{GROUP}/{TIME}")))?;
    let fs = time
        .attr(SAMPLING_RATE)
        .and_then(|a| a.read_scalar::<f64>())
        .map_err(e(format!("{SAMPLING_RATE} attribute")))?;
    if d.len() != v.len() || d.len() < 2 || fs.is_nan() || fs <= 0.0 {
        return Err(crate::dmw::DmwError::Record {
            path: path.to_path_buf(),
            message: "inconsistent track datasets".into(),
        }
        .into());
    }
    // Keep the samples outside the marked edge transients.
    let first = edge.iter().position(|&b| b == 0).unwrap_or(0);
    let last = edge
        .iter()
        .rposition(|&b| b == 0)
        .map_or(d.len(), |i| i + 1);
    let (first, last) = if edge.len() == d.len() && last > first + 1 {
        (first, last)
    } else {
        (0, d.len())
    };
    Ok(DmwTrack {
        displacement: d[first..last].to_vec(),
        velocity: v[first..last].to_vec(),
        sample_rate: fs,
    })
}
