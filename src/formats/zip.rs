//! A ZIP archive reader over a byte slice, and a small deterministic writer: what `.x3p`
//! (ISO 25178-71) and NumPy `.npz` files are built on (docs/formats.md).
//!
//! Written from PKWARE's APPNOTE (sections 4.3.7 local header, 4.3.12 central directory,
//! 4.3.14–4.3.16 ZIP64 end records, 4.5.3 ZIP64 extra field). Entries are listed from the
//! central directory, which is authoritative for sizes (a local header may carry zeros and a
//! data descriptor instead); methods 0 (stored) and 8 (deflate) are read; every entry's CRC-32
//! is checked. Nothing is allocated from a size field before it is checked against the archive
//! length: a stored entry must lie inside the archive, and a deflated one cannot expand more than
//! deflate's maximum ratio (1032:1).

/// Why an archive or one of its entries cannot be read.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ZipError {
    #[error("not a ZIP archive: {0}")]
    NotZip(&'static str),
    #[error("corrupt ZIP archive: {0}")]
    Corrupt(String),
    #[error("ZIP entry `{name}`: {reason}")]
    Entry { name: String, reason: String },
}

/// One member of the archive, as the central directory lists it.
#[derive(Debug, Clone, PartialEq)]
pub struct ZipEntry {
    pub name: String,
    /// 0 = stored, 8 = deflate (others are refused on read).
    pub method: u16,
    pub compressed_size: u64,
    pub size: u64,
    pub crc32: u32,
    local_header_offset: u64,
}

/// The archive: the bytes and the entries of its central directory.
#[derive(Debug)]
pub struct ZipArchive<'a> {
    bytes: &'a [u8],
    entries: Vec<ZipEntry>,
}

const EOCD_SIG: u32 = 0x0605_4b50;
const ZIP64_LOCATOR_SIG: u32 = 0x0706_4b50;
const ZIP64_EOCD_SIG: u32 = 0x0606_4b50;
const CENTRAL_SIG: u32 = 0x0201_4b50;
const LOCAL_SIG: u32 = 0x0403_4b50;
/// Deflate cannot expand input by more than this factor (a 258-byte match per 2 bits, RFC 1951).
const MAX_DEFLATE_RATIO: u64 = 1032;

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}
fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}
fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

fn corrupt(reason: impl Into<String>) -> ZipError {
    ZipError::Corrupt(reason.into())
}

/// Whether `bytes` starts like a ZIP archive (a local header or an empty archive's end record).
pub fn is_zip(bytes: &[u8]) -> bool {
    bytes.starts_with(b"PK\x03\x04") || bytes.starts_with(b"PK\x05\x06")
}

impl<'a> ZipArchive<'a> {
    /// Reads the central directory of `bytes`.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, ZipError> {
        if !is_zip(bytes) {
            return Err(ZipError::NotZip("no `PK` signature at the start"));
        }
        let eocd = find_end_record(bytes)?;
        let mut count = u64::from(u16_at(bytes, eocd + 10).ok_or_else(|| corrupt("end record"))?);
        let mut cd_size = u64::from(u32_at(bytes, eocd + 12).ok_or_else(|| corrupt("end record"))?);
        let mut cd_offset =
            u64::from(u32_at(bytes, eocd + 16).ok_or_else(|| corrupt("end record"))?);
        // ZIP64: the locator sits right before the end record and points at the ZIP64 record.
        if eocd >= 20 && u32_at(bytes, eocd - 20) == Some(ZIP64_LOCATOR_SIG) {
            let at = u64_at(bytes, eocd - 12).ok_or_else(|| corrupt("ZIP64 locator"))?;
            let at = usize::try_from(at).map_err(|_| corrupt("ZIP64 record offset"))?;
            if u32_at(bytes, at) != Some(ZIP64_EOCD_SIG) {
                return Err(corrupt("ZIP64 end record missing where its locator points"));
            }
            let field = |off| u64_at(bytes, at + off).ok_or_else(|| corrupt("ZIP64 end record"));
            count = field(32)?;
            cd_size = field(40)?;
            cd_offset = field(48)?;
        }
        let start = usize::try_from(cd_offset).map_err(|_| corrupt("directory offset"))?;
        let end = start
            .checked_add(usize::try_from(cd_size).map_err(|_| corrupt("directory size"))?)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| {
                corrupt(format!(
                    "central directory ({cd_size} bytes at {cd_offset}) runs past the end of the \
                     {}-byte archive (truncated?)",
                    bytes.len()
                ))
            })?;
        // Each directory record takes at least 46 bytes: the count cannot exceed that bound.
        if count > (end - start) as u64 / 46 + 1 {
            return Err(corrupt(format!(
                "{count} entries cannot fit in a {cd_size}-byte directory"
            )));
        }
        let mut entries = Vec::with_capacity(count as usize);
        let mut at = start;
        for k in 0..count {
            let entry = parse_central_record(&bytes[..end], at).ok_or_else(|| {
                corrupt(format!("central directory record {k} is cut or garbled"))
            })?;
            at = entry.1;
            entries.push(entry.0);
        }
        Ok(ZipArchive { bytes, entries })
    }

    pub fn entries(&self) -> &[ZipEntry] {
        &self.entries
    }

    /// The entry called `name` (exact match).
    pub fn find(&self, name: &str) -> Option<&ZipEntry> {
        self.entries.iter().find(|e| e.name == name)
    }

    /// The raw (still compressed, for method 8) data of `entry`, located through its local
    /// header.
    fn raw_data(&self, entry: &ZipEntry) -> Result<&'a [u8], ZipError> {
        let bad = |reason: &str| ZipError::Entry {
            name: entry.name.clone(),
            reason: reason.to_string(),
        };
        let at = usize::try_from(entry.local_header_offset).map_err(|_| bad("offset"))?;
        if u32_at(self.bytes, at) != Some(LOCAL_SIG) {
            return Err(bad("no local header where the directory points"));
        }
        let name_len = u16_at(self.bytes, at + 26).ok_or_else(|| bad("local header cut"))?;
        let extra_len = u16_at(self.bytes, at + 28).ok_or_else(|| bad("local header cut"))?;
        let data = at + 30 + usize::from(name_len) + usize::from(extra_len);
        let len = usize::try_from(entry.compressed_size).map_err(|_| bad("size"))?;
        data.checked_add(len)
            .and_then(|end| self.bytes.get(data..end))
            .ok_or_else(|| bad("data runs past the end of the archive (truncated?)"))
    }

    /// The bytes of a stored (uncompressed) entry without copying, or `None` if it is
    /// compressed; for zero-copy access to memory-mapped archives. The CRC is not checked.
    pub fn stored_slice(&self, entry: &ZipEntry) -> Result<Option<&'a [u8]>, ZipError> {
        if entry.method != 0 {
            return Ok(None);
        }
        self.raw_data(entry).map(Some)
    }

    /// The decompressed bytes of `entry`, CRC-checked. `max_size` caps what the caller is
    /// willing to hold (the entry's declared size must not exceed it).
    pub fn read(&self, entry: &ZipEntry, max_size: u64) -> Result<Vec<u8>, ZipError> {
        let bad = |reason: String| ZipError::Entry {
            name: entry.name.clone(),
            reason,
        };
        if entry.size > max_size {
            return Err(bad(format!(
                "declares {} bytes, more than the {max_size} allowed",
                entry.size
            )));
        }
        let raw = self.raw_data(entry)?;
        let data = match entry.method {
            0 => {
                if entry.size != entry.compressed_size {
                    return Err(bad("stored entry with differing sizes".into()));
                }
                raw.to_vec()
            }
            8 => {
                if entry.size > MAX_DEFLATE_RATIO * (entry.compressed_size + 1) {
                    return Err(bad(format!(
                        "declares {} bytes from {} deflated bytes, beyond deflate's ratio",
                        entry.size, entry.compressed_size
                    )));
                }
                // One byte more than declared: an entry that inflates past its size is caught.
                let limit = usize::try_from(entry.size + 1).map_err(|_| bad("size".into()))?;
                miniz_oxide::inflate::decompress_to_vec_with_limit(raw, limit)
                    .map_err(|e| bad(format!("deflate stream is corrupt ({e})")))?
            }
            m => return Err(bad(format!("compression method {m} is not supported"))),
        };
        if data.len() as u64 != entry.size {
            return Err(bad(format!(
                "inflates to {} bytes, the directory says {}",
                data.len(),
                entry.size
            )));
        }
        let crc = crc32fast::hash(&data);
        if crc != entry.crc32 {
            return Err(bad(format!(
                "CRC-32 mismatch ({crc:08x}, expected {:08x}): the data is corrupt",
                entry.crc32
            )));
        }
        Ok(data)
    }
}

/// Offset of the end-of-central-directory record: searched backwards over the last
/// 22 + 65 535 bytes (the record plus the longest comment).
fn find_end_record(bytes: &[u8]) -> Result<usize, ZipError> {
    if bytes.len() < 22 {
        return Err(corrupt("shorter than an end record (truncated?)"));
    }
    let lowest = bytes.len().saturating_sub(22 + 65_535);
    (lowest..=bytes.len() - 22)
        .rev()
        .find(|&at| u32_at(bytes, at) == Some(EOCD_SIG))
        .ok_or_else(|| corrupt("no end-of-central-directory record (truncated?)"))
}

/// One central-directory record at `at`: the entry and the offset of the next record.
fn parse_central_record(b: &[u8], at: usize) -> Option<(ZipEntry, usize)> {
    if u32_at(b, at)? != CENTRAL_SIG {
        return None;
    }
    let flags = u16_at(b, at + 8)?;
    let method = u16_at(b, at + 10)?;
    let crc32 = u32_at(b, at + 16)?;
    let mut compressed_size = u64::from(u32_at(b, at + 20)?);
    let mut size = u64::from(u32_at(b, at + 24)?);
    let name_len = usize::from(u16_at(b, at + 28)?);
    let extra_len = usize::from(u16_at(b, at + 30)?);
    let comment_len = usize::from(u16_at(b, at + 32)?);
    let mut local_header_offset = u64::from(u32_at(b, at + 42)?);
    let name_bytes = b.get(at + 46..at + 46 + name_len)?;
    // Bit 11: UTF-8 names; otherwise CP437, whose ASCII part is what these formats use.
    let name = if flags & 0x800 != 0 {
        std::str::from_utf8(name_bytes).ok()?.to_string()
    } else {
        name_bytes.iter().map(|&c| c as char).collect()
    };
    let extra = b.get(at + 46 + name_len..at + 46 + name_len + extra_len)?;
    // ZIP64 extra field: the 64-bit values of the fields that read 0xFFFFFFFF, in order.
    let mut k = 0;
    while k + 4 <= extra.len() {
        let id = u16_at(extra, k)?;
        let len = usize::from(u16_at(extra, k + 2)?);
        let body = extra.get(k + 4..k + 4 + len)?;
        if id == 0x0001 {
            let mut p = 0;
            for field in [&mut size, &mut compressed_size, &mut local_header_offset] {
                if *field == u64::from(u32::MAX) {
                    *field = u64_at(body, p)?;
                    p += 8;
                }
            }
        }
        k += 4 + len;
    }
    let next = at + 46 + name_len + extra_len + comment_len;
    Some((
        ZipEntry {
            name,
            method,
            compressed_size,
            size,
            crc32,
            local_header_offset,
        },
        next,
    ))
}

/// Bytes a classic (non-ZIP64) archive can address: sizes and offsets are 32-bit.
const MAX_CLASSIC: u64 = u32::MAX as u64;

/// A deflated archive of `members` (name, content), in the given order. Deterministic: every
/// entry is dated 1980-01-01 00:00 (the DOS epoch), so the same members give the same bytes.
/// Archives beyond 4 GiB would need ZIP64 and are refused.
pub fn write_deflated(members: &[(&str, &[u8])]) -> Result<Vec<u8>, ZipError> {
    // DOS time 00:00:00, date 1980-01-01 (day 1, month 1, year 0).
    const DOS_TIME: u16 = 0;
    const DOS_DATE: u16 = (1 << 5) | 1;
    let too_big = |what: &str| corrupt(format!("{what} exceeds 4 GiB; ZIP64 is not written"));
    let mut out = Vec::new();
    let mut central = Vec::new();
    for (name, data) in members {
        let packed = miniz_oxide::deflate::compress_to_vec(data, 1);
        let offset = u32::try_from(out.len()).map_err(|_| too_big("archive"))?;
        let size = u32::try_from(data.len()).map_err(|_| too_big(name))?;
        let csize = u32::try_from(packed.len()).map_err(|_| too_big(name))?;
        let name_len = u16::try_from(name.len()).map_err(|_| corrupt("member name too long"))?;
        let crc = crc32fast::hash(data);
        // The fields the local header and the directory record share (APPNOTE 4.3.7, 4.3.12).
        let mut common = Vec::with_capacity(26);
        for v in [20u16, 0, 8, DOS_TIME, DOS_DATE] {
            common.extend_from_slice(&v.to_le_bytes());
        }
        for v in [crc, csize, size] {
            common.extend_from_slice(&v.to_le_bytes());
        }
        common.extend_from_slice(&name_len.to_le_bytes());
        common.extend_from_slice(&0u16.to_le_bytes());

        out.extend_from_slice(&LOCAL_SIG.to_le_bytes());
        out.extend_from_slice(&common);
        out.extend_from_slice(name.as_bytes());
        out.extend_from_slice(&packed);

        central.extend_from_slice(&CENTRAL_SIG.to_le_bytes());
        central.extend_from_slice(&20u16.to_le_bytes()); // version made by: 2.0, MS-DOS
        central.extend_from_slice(&common);
        for v in [0u16, 0, 0] {
            central.extend_from_slice(&v.to_le_bytes()); // comment, disk, internal attributes
        }
        central.extend_from_slice(&0u32.to_le_bytes()); // external attributes
        central.extend_from_slice(&offset.to_le_bytes());
        central.extend_from_slice(name.as_bytes());
    }
    let count = u16::try_from(members.len()).map_err(|_| corrupt("more than 65535 members"))?;
    let cd_offset = out.len() as u64;
    let cd_size = central.len() as u64;
    if cd_offset + cd_size > MAX_CLASSIC {
        return Err(too_big("archive"));
    }
    out.extend_from_slice(&central);
    out.extend_from_slice(&EOCD_SIG.to_le_bytes());
    for v in [0u16, 0, count, count] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&(cd_size as u32).to_le_bytes());
    out.extend_from_slice(&(cd_offset as u32).to_le_bytes());
    out.extend_from_slice(&0u16.to_le_bytes());
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `zipfile.ZipFile('t.zip','w').writestr('a.txt','hello\n'*3)` plus a deflated member
    /// `b.bin` = bytes(range(256))*4, written by CPython 3.11's zipfile (an independent writer).
    fn python_zip() -> Vec<u8> {
        include_bytes!("../../tests/data/formats/python-zipfile.zip").to_vec()
    }

    #[test]
    fn reads_stored_and_deflated_members_written_by_python() {
        let bytes = python_zip();
        let zip = ZipArchive::parse(&bytes).unwrap();
        let names: Vec<&str> = zip.entries().iter().map(|e| e.name.as_str()).collect();
        assert_eq!(names, ["a.txt", "b.bin", "dir/c64.bin"]);
        let a = zip.find("a.txt").unwrap();
        assert_eq!(a.method, 0);
        assert_eq!(zip.read(a, 1 << 20).unwrap(), b"hello\nhello\nhello\n");
        assert_eq!(
            zip.stored_slice(a).unwrap().unwrap(),
            b"hello\nhello\nhello\n"
        );
        let b = zip.find("b.bin").unwrap();
        assert_eq!(b.method, 8);
        let want: Vec<u8> = (0..4).flat_map(|_| 0..=255u8).collect();
        assert_eq!(zip.read(b, 1 << 20).unwrap(), want);
        assert_eq!(zip.stored_slice(b).unwrap(), None);
        // Written with force_zip64=True (as numpy's savez does): ZIP64 extra fields.
        let c = zip.find("dir/c64.bin").unwrap();
        assert_eq!(zip.read(c, 1 << 20).unwrap(), vec![7u8; 1000]);
    }

    #[test]
    fn written_archives_read_back_and_are_deterministic() {
        let big: Vec<u8> = (0..100_000u32)
            .flat_map(|k| (k % 251).to_le_bytes())
            .collect();
        let members: [(&str, &[u8]); 3] =
            [("main.xml", b"<a/>"), ("bin/data.bin", &big), ("e", b"")];
        let bytes = write_deflated(&members).unwrap();
        assert_eq!(bytes, write_deflated(&members).unwrap());
        let zip = ZipArchive::parse(&bytes).unwrap();
        let names: Vec<&str> = zip.entries().iter().map(|e| e.name.as_str()).collect();
        assert_eq!(names, ["main.xml", "bin/data.bin", "e"]);
        for (name, data) in members {
            let e = zip.find(name).unwrap();
            assert_eq!(e.method, 8);
            assert_eq!(zip.read(e, 1 << 30).unwrap(), data);
        }
    }

    #[test]
    fn caps_and_corruption_are_errors_not_panics() {
        let bytes = python_zip();
        let zip = ZipArchive::parse(&bytes).unwrap();
        let b = zip.find("b.bin").unwrap();
        assert!(matches!(zip.read(b, 10), Err(ZipError::Entry { .. })));
        // Every truncation fails cleanly (or, cut inside the trailing comment, still parses).
        for cut in 0..bytes.len() {
            let _ = ZipArchive::parse(&bytes[..cut]).map(|z| {
                for e in z.entries() {
                    let _ = z.read(e, 1 << 20);
                }
            });
        }
        // A flipped bit in the deflated data: CRC or inflate error, never wrong data.
        let data_at = bytes.windows(4).rposition(|w| w == b"PK\x03\x04").unwrap();
        let mut garbled = bytes.clone();
        for k in 0..bytes.len() {
            garbled[k] ^= 0x10;
            if let Ok(z) = ZipArchive::parse(&garbled) {
                if let Some(e) = z.find("b.bin") {
                    if let Ok(d) = z.read(e, 1 << 20) {
                        // Only header bytes outside the checked data may change harmlessly.
                        let want: Vec<u8> = (0..4).flat_map(|_| 0..=255u8).collect();
                        assert_eq!(d, want, "byte {k} flipped, data_at {data_at}");
                    }
                }
            }
            garbled[k] ^= 0x10;
        }
        assert_eq!(
            ZipArchive::parse(b"not a zip").unwrap_err(),
            ZipError::NotZip("no `PK` signature at the start")
        );
    }
}
