//! Height-map readers (detect by magic bytes, never by extension) and writers.
//! CONTRACT STUB — replaced by the readers implementation.
use super::{HeightMap, Result};
use std::path::Path;

/// Options a reader may need. Lengths in metres.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReadOptions {
    /// Channel to read (matched case-insensitively against the file's channel names);
    /// `None` = the format's default height channel.
    pub channel: Option<String>,
    /// Lateral size along x / y for formats that do not carry it (plain ASCII without header).
    pub size_x: Option<f64>,
    pub size_y: Option<f64>,
    /// Height unit for formats that do not carry it ("m", "mm", "um", "µm", "nm", "pm", "A").
    pub z_unit: Option<String>,
}

/// Short format id of a file's content, from its first bytes; `None` if not recognised.
pub fn detect_format(_head: &[u8]) -> Option<&'static str> {
    unimplemented!()
}

/// Read one height map in SI units from any supported format.
pub fn read_height_map(_path: &Path, _opts: &ReadOptions) -> Result<HeightMap> {
    unimplemented!()
}

/// Encode as Gwyddion native `.gwy` (one channel).
pub fn encode_gwy(_map: &HeightMap) -> Vec<u8> {
    unimplemented!()
}

/// Encode as a Bruker NanoScope v5+ file with int16 or int32 data (`bytes_per_pixel` 2 or 4).
pub fn encode_nanoscope(_map: &HeightMap, _bytes_per_pixel: usize) -> Vec<u8> {
    unimplemented!()
}

/// Encode as a Gwyddion-style ASCII matrix with `# Width/Height/Value units` header.
pub fn encode_ascii_matrix(_map: &HeightMap) -> Vec<u8> {
    unimplemented!()
}
