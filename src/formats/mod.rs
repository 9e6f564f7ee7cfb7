//! Container formats that several readers share (docs/formats.md): Microsoft compound files
//! (OLE2: Digital Surf Mountains `.mnt`), ZIP archives (ISO 25178-71
//! `.x3p`, NumPy `.npz`), the NumPy `.npy` header, and the XML scanner and MD5 checksum `.x3p`
//! needs; and [`isolated`], which runs a reader in a child process so that a crash in a C library
//! (libhdf5) is an error. A leaf module: it knows nothing of surfaces, records or the pipeline.
pub mod cfb;
pub mod isolated;
pub mod md5;
pub mod npy;
pub mod xml;
pub mod zip;
