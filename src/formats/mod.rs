//! Container formats that several readers share (docs/formats.md): ZIP archives (ISO 25178-71
//! `.x3p`, NumPy `.npz`) and the NumPy `.npy` header. A leaf module: it knows nothing of
//! surfaces, records or the pipeline.
pub mod npy;
pub mod zip;
