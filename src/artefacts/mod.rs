//! What one stage hands another, defined once: each file here is the typed form of an
//! artefact a producing stage writes (its `result.json` or an HDF5 file in its outputs) and a
//! consuming stage reads from its upstream results. Producer and consumer share the struct,
//! the dataset names and the file names, so neither imports the other's stage file.
pub mod bulge;
pub mod calibration;
pub mod cases;
pub mod contact;
pub mod dmw_tracks;
pub mod interface;
pub mod ldv;
pub mod series;
pub mod surface;
