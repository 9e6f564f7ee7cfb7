//! Container formats that several readers share (docs/formats.md): ZIP archives (ISO 25178-71
//! `.x3p`, NumPy `.npz`), the NumPy `.npy` header, and the XML scanner and MD5 checksum `.x3p`
//! needs. A leaf module: it knows nothing of surfaces, records or the pipeline.
pub mod md5;
pub mod npy;
pub mod xml;
pub mod zip;
