//! RIFF/WAVE records (memory-mapped): PCM 8/16/24/32-bit integers and IEEE float 32/64, plain
//! or WAVE_FORMAT_EXTENSIBLE. Channel 0 is the velocity and channel 1 the index unless the
//! options choose others by number; the sample rate comes from the `fmt ` chunk. Integer PCM
//! is read as a fraction of full scale (±1 V for the most negative code, so 16-bit code k is
//! k/32768 V; 8-bit is unsigned around 128), which the `sensitivity` then turns into m/s like
//! any decoder voltage; set the velocity_unit option if the channel holds m/s.

use super::columns::{self, Column, Num, Seg, Table};
use super::names::Meta;
use super::{read_err, record_err, ReadOptions};
use crate::dmw::{DmwError, LdvRecord};
use std::path::Path;

const PCM: u16 = 1;
const IEEE_FLOAT: u16 = 3;
const EXTENSIBLE: u16 = 0xfffe;

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}
fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

struct Fmt {
    code: u16,
    channels: usize,
    rate: u32,
    block: usize,
    bits: u16,
}

pub(super) fn read(path: &Path, opts: &ReadOptions) -> Result<LdvRecord, DmwError> {
    let file = std::fs::File::open(path).map_err(|e| read_err(path, e))?;
    // SAFETY: read-only map; hdi does not modify the file while reading it.
    let b = unsafe { memmap2::Mmap::map(&file) }.map_err(|e| read_err(path, e))?;
    let bad = |m: String| record_err(path, format!("WAV: {m}"));
    if b.len() < 12 || &b[..4] != b"RIFF" || &b[8..12] != b"WAVE" {
        return Err(bad("no RIFF/WAVE header".into()));
    }
    let mut fmt = None;
    let mut data = None;
    let mut at = 12usize;
    while at + 8 <= b.len() {
        let id = &b[at..at + 4];
        let size = u32_at(&b, at + 4).unwrap_or(0) as usize;
        let body = at + 8;
        if id == b"data" {
            // Streaming writers leave the size 0 or 0xFFFFFFFF; a size past the end is a cut
            // file either way.
            if size > b.len() - body {
                return Err(bad(format!(
                    "the data chunk declares {size} bytes, the file has {} after it; is it cut?",
                    b.len() - body
                )));
            }
            data = Some((body, size));
            break;
        }
        if size > b.len() - body {
            return Err(bad(format!(
                "chunk '{}' at byte {at} runs past the end of the file; is it cut?",
                String::from_utf8_lossy(id)
            )));
        }
        if id == b"fmt " {
            let c = &b[body..body + size];
            let mut code = u16_at(c, 0).ok_or_else(|| bad("fmt chunk too short".into()))?;
            if code == EXTENSIBLE {
                // cbSize, valid bits, channel mask, then the sub-format GUID whose first two
                // bytes are the format code.
                code = u16_at(c, 24)
                    .ok_or_else(|| bad("WAVE_FORMAT_EXTENSIBLE fmt chunk too short".into()))?;
            }
            match (u16_at(c, 2), u32_at(c, 4), u16_at(c, 12), u16_at(c, 14)) {
                (Some(ch), Some(rate), Some(block), Some(bits)) => {
                    fmt = Some(Fmt {
                        code,
                        channels: ch as usize,
                        rate,
                        block: block as usize,
                        bits,
                    })
                }
                _ => return Err(bad("fmt chunk too short".into())),
            }
        }
        at = body + size + (size & 1);
    }
    let fmt = fmt.ok_or_else(|| bad("no fmt chunk before the data".into()))?;
    let (body, size) = data.ok_or_else(|| bad("no data chunk".into()))?;
    let num = match (fmt.code, fmt.bits) {
        (PCM, 8) => Num::U8,
        (PCM, 16) => Num::I16,
        (PCM, 24) => Num::I24,
        (PCM, 32) => Num::I32,
        (IEEE_FLOAT, 32) => Num::F32,
        (IEEE_FLOAT, 64) => Num::F64,
        (code, bits) => {
            return Err(bad(format!(
                "format code {code} with {bits} bits per sample; PCM 8/16/24/32-bit and IEEE \
                 float 32/64 are read"
            )))
        }
    };
    if fmt.channels == 0 || fmt.block != fmt.channels * num.size() {
        return Err(bad(format!(
            "{} channels of {} bits in blocks of {} bytes do not add up",
            fmt.channels, fmt.bits, fmt.block
        )));
    }
    if fmt.rate == 0 {
        return Err(bad("sample rate 0".into()));
    }
    let frames = size / fmt.block;
    // Full scale ±1: code k of an n-bit channel is k / 2^(n−1).
    let (scale, offset) = match num {
        Num::U8 => (1.0 / 128.0, -1.0),
        Num::I16 => (1.0 / 32768.0, 0.0),
        Num::I24 => (1.0 / 8_388_608.0, 0.0),
        Num::I32 => (1.0 / 2_147_483_648.0, 0.0),
        _ => (1.0, 0.0),
    };
    let mut columns = Vec::new();
    for j in 0..fmt.channels {
        let name = match j {
            0 => "velocity".to_string(),
            1 => "index".to_string(),
            _ => format!("channel{j}"),
        };
        let seg = Seg::Bytes {
            bytes: &b[body..body + frames * fmt.block],
            offset: j * num.size(),
            stride: fmt.block,
            len: frames,
            num,
            big_endian: false,
            valid: None,
        };
        let mut col = Column::new(name, vec![seg]);
        col.scale = scale;
        col.offset = offset;
        columns.push(col);
    }
    let meta = Meta {
        sample_rate: Some(fmt.rate as f64),
        ..Meta::default()
    };
    let table = Table {
        format: "wav",
        columns,
        meta,
        meta_hint: "a sample rate in the fmt chunk",
        what: "channel",
        positional: true,
        provenance: vec![(
            "wav_encoding".to_string(),
            format!(
                "{} {}-bit{}",
                if fmt.code == PCM { "PCM" } else { "float" },
                fmt.bits,
                if fmt.code == PCM {
                    " (full scale = 1 V)"
                } else {
                    ""
                }
            ),
        )],
    };
    columns::read(path, table, opts)
}
