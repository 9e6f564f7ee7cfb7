//! A read-only Microsoft Compound File Binary (OLE2 "structured storage") reader over a byte
//! slice: what Digital Surf Mountains `.mnt` files are built on (docs/formats.md).
//!
//! Written from Microsoft's public specification [MS-CFB]: a 512-byte header (signature
//! `D0 CF 11 E0 A1 B1 1A E1`, sector shift at 0x1E, mini-sector shift at 0x20, the number of
//! FAT sectors at 0x2C, the first directory sector at 0x30, the mini-stream cutoff at 0x38,
//! the first mini-FAT sector at 0x3C, the first DIFAT sector at 0x44 and 109 DIFAT entries at
//! 0x4C), sector n at byte (n + 1) · sector size, chains of sectors through the FAT, 128-byte
//! directory entries (UTF-16 name, type, start sector at 116, size at 120), and streams shorter
//! than the cutoff stored in 64-byte mini sectors inside the root entry's stream. Every chain
//! is followed at most as many steps as the file has sectors (a cycle is an error), and no
//! stream is allocated larger than the file.

/// Why a compound file or one of its streams cannot be read.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CfbError {
    #[error("not a compound (OLE) file")]
    NotCfb,
    #[error("corrupt compound (OLE) file: {0}")]
    Corrupt(String),
    #[error("compound (OLE) file has no stream `{0}`")]
    Missing(String),
}

pub const SIGNATURE: &[u8] = b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1";
/// FAT values at or above this end a chain or mark special sectors.
const MAX_REGULAR_SECTOR: u32 = 0xFFFF_FFFA;

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}
fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}
fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}
fn corrupt(reason: impl Into<String>) -> CfbError {
    CfbError::Corrupt(reason.into())
}

/// One directory entry that is a stream.
#[derive(Debug, Clone)]
struct Entry {
    name: String,
    kind: u8,
    start: u32,
    size: u64,
}

/// The file: its bytes, FAT, mini FAT, mini stream and directory.
pub struct Cfb<'a> {
    bytes: &'a [u8],
    sector_size: usize,
    mini_sector_size: usize,
    mini_cutoff: u64,
    /// Sectors in the file: no chain without a loop is longer.
    n_sectors: usize,
    fat: Vec<u32>,
    mini_fat: Vec<u32>,
    mini_stream: Vec<u8>,
    entries: Vec<Entry>,
}

impl<'a> Cfb<'a> {
    pub fn parse(bytes: &'a [u8]) -> Result<Self, CfbError> {
        if !bytes.starts_with(SIGNATURE) {
            return Err(CfbError::NotCfb);
        }
        if bytes.len() < 512 {
            return Err(corrupt("shorter than its 512-byte header"));
        }
        let h = |at| u32_at(bytes, at).unwrap_or(0);
        let sector_shift = u16_at(bytes, 0x1E).unwrap_or(0);
        let mini_shift = u16_at(bytes, 0x20).unwrap_or(0);
        if !matches!(sector_shift, 9 | 12) || mini_shift != 6 {
            return Err(corrupt(format!(
                "sector shifts {sector_shift}/{mini_shift} (9 or 12, and 6, expected)"
            )));
        }
        let mut cfb = Cfb {
            bytes,
            sector_size: 1 << sector_shift,
            mini_sector_size: 1 << mini_shift,
            mini_cutoff: u64::from(h(0x38)),
            n_sectors: bytes.len().div_ceil(1 << sector_shift),
            fat: Vec::new(),
            mini_fat: Vec::new(),
            mini_stream: Vec::new(),
            entries: Vec::new(),
        };
        let n_sectors = cfb.n_sectors;
        // The DIFAT: 109 entries in the header, then a chain of DIFAT sectors, each holding
        // sector_size / 4 − 1 entries and the next DIFAT sector.
        let mut fat_sectors: Vec<u32> = (0..109).map(|k| h(0x4C + 4 * k)).collect();
        let (mut difat, mut steps) = (h(0x44), 0);
        while difat < MAX_REGULAR_SECTOR {
            steps += 1;
            if steps > n_sectors {
                return Err(corrupt("the DIFAT chain loops"));
            }
            let s = cfb.sector(difat)?;
            let per = cfb.sector_size / 4 - 1;
            fat_sectors.extend((0..per).map(|k| u32_at(s, 4 * k).unwrap_or(u32::MAX)));
            difat = u32_at(s, 4 * per).unwrap_or(u32::MAX);
        }
        let n_fat = h(0x2C) as usize;
        if n_fat > n_sectors {
            return Err(corrupt(format!(
                "{n_fat} FAT sectors in a file of {n_sectors} sectors"
            )));
        }
        let mut fat = Vec::with_capacity(n_fat * cfb.sector_size / 4);
        for &sector in fat_sectors
            .iter()
            .filter(|&&s| s < MAX_REGULAR_SECTOR)
            .take(n_fat)
        {
            let s = cfb.sector(sector)?;
            fat.extend(
                s.chunks_exact(4)
                    .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            );
        }
        cfb.fat = fat;
        let directory = cfb.chain(&cfb.fat, h(0x30), None)?;
        for e in directory.chunks_exact(128) {
            let name_len = (u16_at(e, 64).unwrap_or(0) as usize).min(64);
            let units: Vec<u16> = e[..name_len]
                .chunks_exact(2)
                .map(|c| u16::from_le_bytes([c[0], c[1]]))
                .take_while(|&u| u != 0)
                .collect();
            cfb.entries.push(Entry {
                name: String::from_utf16_lossy(&units),
                kind: e[66],
                start: u32_at(e, 116).unwrap_or(u32::MAX),
                size: if sector_shift == 9 {
                    // Version 3 files: the high half may be garbage (MS-CFB 2.6.3).
                    u64::from(u32_at(e, 120).unwrap_or(0))
                } else {
                    u64_at(e, 120).unwrap_or(0)
                },
            });
        }
        let root = cfb
            .entries
            .first()
            .filter(|e| e.kind == 5)
            .cloned()
            .ok_or_else(|| corrupt("the first directory entry is not the root"))?;
        if root.size > 0 {
            cfb.mini_fat = {
                let raw = cfb.chain(&cfb.fat, h(0x3C), None)?;
                raw.chunks_exact(4)
                    .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                    .collect()
            };
            cfb.mini_stream = cfb.chain(&cfb.fat, root.start, Some(root.size))?;
        }
        Ok(cfb)
    }

    fn sector(&self, n: u32) -> Result<&'a [u8], CfbError> {
        let at = (n as usize + 1) * self.sector_size;
        self.bytes
            .get(at..at + self.sector_size)
            .ok_or_else(|| corrupt(format!("sector {n} lies past the end of the file")))
    }

    /// The bytes of the chain from `start` (regular sectors), cut to `size` if given.
    fn chain(&self, fat: &[u32], start: u32, size: Option<u64>) -> Result<Vec<u8>, CfbError> {
        if size.is_some_and(|s| s > self.bytes.len() as u64) {
            return Err(corrupt(format!(
                "a stream of {} bytes in a file of {}",
                size.unwrap_or(0),
                self.bytes.len()
            )));
        }
        let mut out = Vec::with_capacity(size.unwrap_or(0) as usize);
        let mut sector = start;
        let mut steps = 0;
        while sector < MAX_REGULAR_SECTOR && size.is_none_or(|s| (out.len() as u64) < s) {
            steps += 1;
            if steps > self.n_sectors {
                return Err(corrupt("a sector chain loops"));
            }
            out.extend_from_slice(self.sector(sector)?);
            sector = *fat
                .get(sector as usize)
                .ok_or_else(|| corrupt(format!("sector {sector} is not in the FAT")))?;
        }
        if let Some(s) = size {
            if (out.len() as u64) < s {
                return Err(corrupt(format!(
                    "a stream of {s} bytes ends after {} bytes",
                    out.len()
                )));
            }
            out.truncate(s as usize);
        }
        Ok(out)
    }

    /// The bytes of the stream in the mini stream from mini sector `start`.
    fn mini_chain(&self, start: u32, size: u64) -> Result<Vec<u8>, CfbError> {
        let mut out = Vec::with_capacity(size.min(self.mini_stream.len() as u64) as usize);
        let (mut sector, mut steps) = (start, 0);
        while (out.len() as u64) < size {
            steps += 1;
            let mini_sectors = self.mini_stream.len() / self.mini_sector_size;
            if sector >= MAX_REGULAR_SECTOR || steps > mini_sectors {
                return Err(corrupt("a mini-sector chain ends early or loops"));
            }
            let at = sector as usize * self.mini_sector_size;
            let s = self
                .mini_stream
                .get(at..at + self.mini_sector_size)
                .ok_or_else(|| {
                    corrupt(format!("mini sector {sector} lies past the mini stream"))
                })?;
            out.extend_from_slice(s);
            sector = *self
                .mini_fat
                .get(sector as usize)
                .ok_or_else(|| corrupt(format!("mini sector {sector} is not in the mini FAT")))?;
        }
        out.truncate(size as usize);
        Ok(out)
    }

    /// Names of the streams (directory entries of type 2).
    pub fn stream_names(&self) -> Vec<&str> {
        self.entries
            .iter()
            .filter(|e| e.kind == 2)
            .map(|e| e.name.as_str())
            .collect()
    }

    /// The stream `name` (anywhere in the directory).
    pub fn stream(&self, name: &str) -> Result<Vec<u8>, CfbError> {
        let e = self
            .entries
            .iter()
            .find(|e| e.kind == 2 && e.name == name)
            .ok_or_else(|| CfbError::Missing(name.to_string()))?;
        if e.size < self.mini_cutoff {
            self.mini_chain(e.start, e.size)
        } else {
            self.chain(&self.fat, e.start, Some(e.size))
        }
    }
}
