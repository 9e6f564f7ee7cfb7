//! Little-endian numbers at a byte offset, shared by the binary readers (`sur`, `opd`, `tmd`,
//! `plu`, `frt`, `nms`, `park`).
//! The caller has checked that the bytes are there.

pub(crate) fn le_u16(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}
pub(crate) fn le_i32(b: &[u8], at: usize) -> i32 {
    i32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}
pub(crate) fn le_u32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}
/// A float32, widened.
pub(crate) fn le_f32(b: &[u8], at: usize) -> f64 {
    f32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]) as f64
}
pub(crate) fn le_f64(b: &[u8], at: usize) -> f64 {
    let mut v = [0u8; 8];
    v.copy_from_slice(&b[at..at + 8]);
    f64::from_le_bytes(v)
}
