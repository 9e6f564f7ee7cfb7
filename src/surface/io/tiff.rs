//! A small, bounded reader of classic TIFF structure (TIFF 6.0 Specification, Part 1: the
//! 8-byte header `II*\0` / `MM\0*` with the first IFD's offset; each IFD a u16 entry count,
//! 12-byte entries (tag u16, type u16, count u32, value or its offset u32) and the next IFD's
//! offset), both byte orders. The instrument formats built on TIFF (Park Systems; JPK and Olympus
//! LEXT have no permissively licensed sample, docs/surfaces.md) keep their heights and scales in private tags or in plain
//! uncompressed strips, so this is all they need: no decompression, no BigTIFF.
//!
//! Every value's bytes are checked against the file when the directory is read, the IFD chain
//! is followed at most [`MAX_IFDS`] steps and never back to an IFD already read, so a corrupt
//! header gives an error, not a panic, a loop or a large allocation.
// The strip-image reader and the typed tag accessors served the JPK reader too, left out for
// want of a permissively licensed sample (docs/surfaces.md); Park uses a part of them. They stay,
// tested here, for the next TIFF-based format (LEXT, JPK).
#![allow(dead_code)]
use std::collections::BTreeSet;

/// Little-endian TIFF header.
pub(crate) const MAGIC_LE: &[u8] = b"II*\0";
/// Big-endian TIFF header.
pub(crate) const MAGIC_BE: &[u8] = b"MM\0*";
/// How many IFDs (pages) a file may chain.
pub(crate) const MAX_IFDS: usize = 1024;

/// TIFF field types (TIFF 6.0, section 2), by their code.
pub(crate) const BYTE: u16 = 1;
pub(crate) const ASCII: u16 = 2;
pub(crate) const SHORT: u16 = 3;
pub(crate) const LONG: u16 = 4;
pub(crate) const RATIONAL: u16 = 5;
pub(crate) const SBYTE: u16 = 6;
#[cfg(test)]
pub(crate) const UNDEFINED: u16 = 7;
pub(crate) const SSHORT: u16 = 8;
pub(crate) const SLONG: u16 = 9;
pub(crate) const FLOAT: u16 = 11;
pub(crate) const DOUBLE: u16 = 12;

/// Baseline tags the strip reader uses (TIFF 6.0, section 8).
pub(crate) const IMAGE_WIDTH: u16 = 256;
pub(crate) const IMAGE_LENGTH: u16 = 257;
pub(crate) const BITS_PER_SAMPLE: u16 = 258;
pub(crate) const COMPRESSION: u16 = 259;
pub(crate) const STRIP_OFFSETS: u16 = 273;
pub(crate) const SAMPLES_PER_PIXEL: u16 = 277;
pub(crate) const ROWS_PER_STRIP: u16 = 278;
pub(crate) const STRIP_BYTE_COUNTS: u16 = 279;
pub(crate) const SAMPLE_FORMAT: u16 = 339;

/// Bytes per value of a field type; `None` for types this reader skips (TIFF 6.0 asks readers
/// to ignore unknown types).
fn type_size(kind: u16) -> Option<usize> {
    match kind {
        1 | 2 | 6 | 7 => Some(1),
        3 | 8 => Some(2),
        4 | 9 | 11 | 13 => Some(4),
        5 | 10 | 12 => Some(8),
        _ => None,
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Order {
    Little,
    Big,
}

impl Order {
    pub(crate) fn u16(self, b: &[u8], at: usize) -> u16 {
        let v = [b[at], b[at + 1]];
        match self {
            Order::Little => u16::from_le_bytes(v),
            Order::Big => u16::from_be_bytes(v),
        }
    }
    pub(crate) fn u32(self, b: &[u8], at: usize) -> u32 {
        let v = [b[at], b[at + 1], b[at + 2], b[at + 3]];
        match self {
            Order::Little => u32::from_le_bytes(v),
            Order::Big => u32::from_be_bytes(v),
        }
    }
    pub(crate) fn u64(self, b: &[u8], at: usize) -> u64 {
        let mut v = [0u8; 8];
        v.copy_from_slice(&b[at..at + 8]);
        match self {
            Order::Little => u64::from_le_bytes(v),
            Order::Big => u64::from_be_bytes(v),
        }
    }
    pub(crate) fn f32(self, b: &[u8], at: usize) -> f64 {
        f64::from(f32::from_bits(self.u32(b, at)))
    }
    pub(crate) fn f64(self, b: &[u8], at: usize) -> f64 {
        f64::from_bits(self.u64(b, at))
    }
}

/// One IFD entry, its value's bytes located and checked against the file.
#[derive(Clone, Debug)]
pub(crate) struct Entry {
    pub tag: u16,
    pub kind: u16,
    pub count: usize,
    /// Where the value's bytes start (inside the entry when they fit in 4 bytes).
    value_at: usize,
    /// How many bytes the value has (`count` × the type's size).
    len: usize,
}

/// A parsed TIFF file: its byte order and the entries of each IFD, in file order.
#[derive(Debug)]
pub(crate) struct Tiff<'a> {
    bytes: &'a [u8],
    pub order: Order,
    pub ifds: Vec<Vec<Entry>>,
}

/// The byte order of a classic TIFF header, `None` if `head` does not start with one.
pub(crate) fn order_of(head: &[u8]) -> Option<Order> {
    if head.starts_with(MAGIC_LE) {
        Some(Order::Little)
    } else if head.starts_with(MAGIC_BE) {
        Some(Order::Big)
    } else {
        None
    }
}

/// The type, count and 4-byte value field of `tag` in the first IFD, if the header and that
/// IFD lie inside `head` (the sniffers' look at the first bytes of a file).
pub(crate) fn first_ifd_entry(head: &[u8], tag: u16) -> Option<(u16, u32, [u8; 4])> {
    let order = order_of(head)?;
    let ifd = usize::try_from(order.u32(head.get(..8)?, 4)).ok()?;
    let n = usize::from(order.u16(head.get(ifd..ifd + 2)?, 0));
    (0..n).find_map(|k| {
        let at = ifd + 2 + 12 * k;
        let entry = head.get(at..at + 12)?;
        (order.u16(entry, 0) == tag).then(|| {
            let value = [entry[8], entry[9], entry[10], entry[11]];
            (order.u16(entry, 2), order.u32(entry, 4), value)
        })
    })
}

/// The value of a scalar SHORT or LONG `tag` in the first IFD inside `head`.
pub(crate) fn first_ifd_scalar(head: &[u8], tag: u16) -> Option<u32> {
    let order = order_of(head)?;
    match first_ifd_entry(head, tag)? {
        (SHORT, 1, v) => Some(u32::from(order.u16(&v, 0))),
        (LONG, 1, v) => Some(order.u32(&v, 0)),
        _ => None,
    }
}

impl<'a> Tiff<'a> {
    /// Reads the header and follows the IFD chain. Errors say what is wrong, without the file
    /// name (the readers add it).
    pub(crate) fn parse(bytes: &'a [u8]) -> Result<Self, String> {
        let order = order_of(bytes).ok_or_else(|| "not a TIFF file".to_string())?;
        if bytes.len() < 8 {
            return Err(format!("truncated TIFF header: {} of 8 bytes", bytes.len()));
        }
        let mut ifds = Vec::new();
        let mut seen = BTreeSet::new();
        let mut next = order.u32(bytes, 4) as usize;
        while next != 0 {
            if ifds.len() == MAX_IFDS {
                return Err(format!("TIFF file chains more than {MAX_IFDS} IFDs"));
            }
            if !seen.insert(next) {
                return Err(format!("TIFF IFD chain loops back to offset {next}"));
            }
            let (entries, after) = Self::read_ifd(bytes, order, next)?;
            ifds.push(entries);
            next = after;
        }
        if ifds.is_empty() {
            return Err("TIFF file has no IFD".into());
        }
        Ok(Tiff { bytes, order, ifds })
    }

    /// The entries of the IFD at `at` and the next IFD's offset.
    fn read_ifd(bytes: &[u8], order: Order, at: usize) -> Result<(Vec<Entry>, usize), String> {
        let past_end = || {
            format!(
                "TIFF IFD at offset {at} runs past the end of the file ({} bytes)",
                bytes.len()
            )
        };
        if at.checked_add(2).is_none_or(|e| e > bytes.len()) {
            return Err(past_end());
        }
        let n = usize::from(order.u16(bytes, at));
        let end = at + 2 + 12 * n + 4;
        if end > bytes.len() {
            return Err(past_end());
        }
        let mut entries = Vec::with_capacity(n);
        for k in 0..n {
            let e = at + 2 + 12 * k;
            let (tag, kind) = (order.u16(bytes, e), order.u16(bytes, e + 2));
            let count = order.u32(bytes, e + 4) as usize;
            let Some(size) = type_size(kind) else {
                continue;
            };
            let len = count.checked_mul(size).ok_or_else(|| {
                format!("TIFF tag {tag}: {count} values overflow the address space")
            })?;
            let value_at = if len <= 4 {
                e + 8
            } else {
                order.u32(bytes, e + 8) as usize
            };
            if value_at.checked_add(len).is_none_or(|v| v > bytes.len()) {
                return Err(format!(
                    "TIFF tag {tag}: its {len} bytes at offset {value_at} run past the end of \
                     the file ({} bytes)",
                    bytes.len()
                ));
            }
            entries.push(Entry {
                tag,
                kind,
                count,
                value_at,
                len,
            });
        }
        Ok((entries, order.u32(bytes, end - 4) as usize))
    }

    /// The entry of `tag` in IFD `ifd`.
    pub(crate) fn find(&self, ifd: usize, tag: u16) -> Option<&Entry> {
        self.ifds.get(ifd)?.iter().find(|e| e.tag == tag)
    }

    /// The raw bytes of an entry's value (in the file's byte order).
    pub(crate) fn data(&self, e: &Entry) -> &'a [u8] {
        &self.bytes[e.value_at..e.value_at + e.len]
    }

    /// The values of an integer entry (BYTE, SHORT, LONG and their signed kinds), `None` for
    /// other types.
    pub(crate) fn ints(&self, e: &Entry) -> Option<Vec<i64>> {
        let d = self.data(e);
        let o = self.order;
        let n = e.count;
        match e.kind {
            BYTE => Some(d.iter().map(|&b| i64::from(b)).collect()),
            SBYTE => Some(d.iter().map(|&b| i64::from(b as i8)).collect()),
            SHORT => Some((0..n).map(|k| i64::from(o.u16(d, 2 * k))).collect()),
            SSHORT => Some((0..n).map(|k| i64::from(o.u16(d, 2 * k) as i16)).collect()),
            LONG => Some((0..n).map(|k| i64::from(o.u32(d, 4 * k))).collect()),
            SLONG => Some((0..n).map(|k| i64::from(o.u32(d, 4 * k) as i32)).collect()),
            _ => None,
        }
    }

    /// The values of a non-negative integer entry (offsets, counts, sizes).
    pub(crate) fn uints(&self, e: &Entry) -> Option<Vec<u64>> {
        self.ints(e)?
            .into_iter()
            .map(|v| u64::try_from(v).ok())
            .collect()
    }

    /// The single value of a scalar integer `tag` in IFD `ifd`.
    pub(crate) fn int(&self, ifd: usize, tag: u16) -> Option<i64> {
        let e = self.find(ifd, tag)?;
        match self.ints(e)?.as_slice() {
            [v] => Some(*v),
            _ => None,
        }
    }

    /// The single value of a scalar non-negative integer `tag` in IFD `ifd`.
    pub(crate) fn uint(&self, ifd: usize, tag: u16) -> Option<u64> {
        self.int(ifd, tag).and_then(|v| u64::try_from(v).ok())
    }

    /// The first value of a numeric entry as f64 (integers, RATIONAL, FLOAT, DOUBLE).
    pub(crate) fn number(&self, e: &Entry) -> Option<f64> {
        let (d, o) = (self.data(e), self.order);
        if e.count == 0 {
            return None;
        }
        match e.kind {
            BYTE | SBYTE | SHORT | SSHORT | LONG | SLONG => self.ints(e).map(|v| v[0] as f64),
            RATIONAL => Some(f64::from(o.u32(d, 0)) / f64::from(o.u32(d, 4))),
            FLOAT => Some(o.f32(d, 0)),
            DOUBLE => Some(o.f64(d, 0)),
            _ => None,
        }
    }

    /// The first value of numeric `tag` in IFD `ifd`.
    pub(crate) fn float(&self, ifd: usize, tag: u16) -> Option<f64> {
        self.number(self.find(ifd, tag)?)
    }

    /// The text of ASCII `tag` in IFD `ifd`.
    pub(crate) fn text(&self, ifd: usize, tag: u16) -> Option<String> {
        let e = self.find(ifd, tag)?;
        (e.kind == ASCII).then(|| self.ascii(e))
    }

    /// An ASCII entry's text up to its first NUL (latin-1 for bytes beyond ASCII).
    pub(crate) fn ascii(&self, e: &Entry) -> String {
        let d = self.data(e);
        let end = d.iter().position(|&b| b == 0).unwrap_or(d.len());
        d[..end].iter().map(|&b| b as char).collect()
    }

    /// The uncompressed single-sample image of IFD `ifd`, row 0 first as stored, each sample
    /// widened to f64 (SampleFormat 1 unsigned, 2 signed, 3 IEEE float; 8 to 64 bits).
    pub(crate) fn strip_image(&self, ifd: usize) -> Result<StripImage, String> {
        let need = |tag: u16, name: &str| {
            self.uint(ifd, tag)
                .ok_or_else(|| format!("TIFF IFD {ifd} has no {name} (tag {tag})"))
        };
        let width = need(IMAGE_WIDTH, "ImageWidth")? as usize;
        let height = need(IMAGE_LENGTH, "ImageLength")? as usize;
        let bits = self.uint(ifd, BITS_PER_SAMPLE).unwrap_or(1);
        let compression = self.uint(ifd, COMPRESSION).unwrap_or(1);
        let samples = self.uint(ifd, SAMPLES_PER_PIXEL).unwrap_or(1);
        let format = self.uint(ifd, SAMPLE_FORMAT).unwrap_or(1);
        if compression != 1 {
            return Err(format!(
                "TIFF IFD {ifd} is compressed (Compression {compression}); only uncompressed \
                 images are read"
            ));
        }
        if samples != 1 {
            return Err(format!(
                "TIFF IFD {ifd} has {samples} samples per pixel; one is expected"
            ));
        }
        let size = match (format, bits) {
            (1 | 2, 8 | 16 | 32 | 64) | (3, 32 | 64) => bits as usize / 8,
            _ => {
                return Err(format!(
                    "TIFF IFD {ifd}: {bits}-bit samples of SampleFormat {format} are not read"
                ))
            }
        };
        let row_bytes = width
            .checked_mul(size)
            .ok_or_else(|| format!("TIFF IFD {ifd}: width {width} overflows"))?;
        let total = row_bytes
            .checked_mul(height)
            .filter(|&t| t > 0 && t <= self.bytes.len())
            .ok_or_else(|| {
                format!(
                    "TIFF IFD {ifd}: a {width} × {height} image of {bits}-bit samples does not \
                     fit the file ({} bytes)",
                    self.bytes.len()
                )
            })?;
        let offsets = self
            .find(ifd, STRIP_OFFSETS)
            .and_then(|e| self.uints(e))
            .ok_or_else(|| format!("TIFF IFD {ifd} has no StripOffsets"))?;
        let counts = self
            .find(ifd, STRIP_BYTE_COUNTS)
            .and_then(|e| self.uints(e))
            .ok_or_else(|| format!("TIFF IFD {ifd} has no StripByteCounts"))?;
        let rows_per_strip = self
            .uint(ifd, ROWS_PER_STRIP)
            .map_or(height, |r| (r as usize).clamp(1, height.max(1)));
        let strips = height.div_ceil(rows_per_strip);
        if offsets.len() < strips || counts.len() < strips {
            return Err(format!(
                "TIFF IFD {ifd}: {} strip offsets and {} byte counts for {strips} strips",
                offsets.len(),
                counts.len()
            ));
        }
        let mut raw = Vec::with_capacity(total);
        for s in 0..strips {
            let rows = rows_per_strip.min(height - s * rows_per_strip);
            let want = rows * row_bytes;
            let at = offsets[s] as usize;
            if (counts[s] as usize) < want
                || at.checked_add(want).is_none_or(|e| e > self.bytes.len())
            {
                return Err(format!(
                    "TIFF IFD {ifd}: strip {s} ({want} bytes at offset {at}) is short or runs \
                     past the end of the file ({} bytes)",
                    self.bytes.len()
                ));
            }
            raw.extend_from_slice(&self.bytes[at..at + want]);
        }
        let o = self.order;
        let value = |k: usize| -> f64 {
            let at = k * size;
            match (format, size) {
                (1, 1) => f64::from(raw[at]),
                (2, 1) => f64::from(raw[at] as i8),
                (1, 2) => f64::from(o.u16(&raw, at)),
                (2, 2) => f64::from(o.u16(&raw, at) as i16),
                (1, 4) => f64::from(o.u32(&raw, at)),
                (2, 4) => f64::from(o.u32(&raw, at) as i32),
                (3, 4) => o.f32(&raw, at),
                (1, 8) => o.u64(&raw, at) as f64,
                (2, 8) => o.u64(&raw, at) as i64 as f64,
                _ => o.f64(&raw, at),
            }
        };
        Ok(StripImage {
            width,
            height,
            values: (0..width * height).map(value).collect(),
        })
    }
}

/// An image read from strips: `values[row * width + column]`, row 0 first in the file.
pub(crate) struct StripImage {
    pub width: usize,
    pub height: usize,
    pub values: Vec<f64>,
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    const SOFTWARE: u16 = 305;

    /// One IFD entry for the test writer: tag, type, count, value bytes (in the file's order).
    pub(crate) type TestEntry = (u16, u16, u32, Vec<u8>);

    /// A one-IFD TIFF in byte order `order` with `entries`; values longer than 4 bytes go
    /// after the IFD.
    pub(crate) fn tiff(order: Order, entries: &[TestEntry]) -> Vec<u8> {
        tiff_pages(order, &[(entries.to_vec(), None)])
    }

    /// A TIFF of chained IFDs, each followed by its long values and, if given, its raster in
    /// one strip (StripOffsets and StripByteCounts are added to point at it).
    pub(crate) fn tiff_pages(order: Order, pages: &[(Vec<TestEntry>, Option<Vec<u8>>)]) -> Vec<u8> {
        let u16b = |v: u16| match order {
            Order::Little => v.to_le_bytes(),
            Order::Big => v.to_be_bytes(),
        };
        let u32b = |v: u32| match order {
            Order::Little => v.to_le_bytes(),
            Order::Big => v.to_be_bytes(),
        };
        let mut out = match order {
            Order::Little => MAGIC_LE.to_vec(),
            Order::Big => MAGIC_BE.to_vec(),
        };
        out.extend(u32b(8));
        for (k, (entries, raster)) in pages.iter().enumerate() {
            let mut sorted = entries.clone();
            if let Some(r) = raster {
                // Placeholders: the offset is known once the IFD's size is.
                sorted.push((STRIP_OFFSETS, LONG, 1, vec![0; 4]));
                sorted.push((STRIP_BYTE_COUNTS, LONG, 1, u32b(r.len() as u32).to_vec()));
            }
            sorted.sort_by_key(|e| e.0);
            let ifd_at = out.len();
            let long_values: usize = sorted.iter().map(|e| e.3.len()).filter(|&n| n > 4).sum();
            let values_at = ifd_at + 2 + 12 * sorted.len() + 4;
            let raster_at = values_at + long_values;
            let page_end = raster_at + raster.as_ref().map_or(0, Vec::len);
            out.extend(u16b(sorted.len() as u16));
            let mut extra: Vec<u8> = Vec::new();
            for (tag, kind, count, value) in &sorted {
                out.extend(u16b(*tag));
                out.extend(u16b(*kind));
                out.extend(u32b(*count));
                if *tag == STRIP_OFFSETS && raster.is_some() {
                    out.extend(u32b(raster_at as u32));
                } else if value.len() <= 4 {
                    let mut v = value.clone();
                    v.resize(4, 0);
                    out.extend(v);
                } else {
                    out.extend(u32b((values_at + extra.len()) as u32));
                    extra.extend(value);
                }
            }
            let next = if k + 1 < pages.len() { page_end } else { 0 };
            out.extend(u32b(next as u32));
            out.extend(extra);
            if let Some(r) = raster {
                out.extend(r);
            }
        }
        out
    }

    fn short(order: Order, v: u16) -> Vec<u8> {
        match order {
            Order::Little => v.to_le_bytes().to_vec(),
            Order::Big => v.to_be_bytes().to_vec(),
        }
    }

    fn long(order: Order, v: u32) -> Vec<u8> {
        match order {
            Order::Little => v.to_le_bytes().to_vec(),
            Order::Big => v.to_be_bytes().to_vec(),
        }
    }

    /// A 3 × 2 image of int16 samples in one strip; sample k = 100·k − 250.
    fn int16_image(order: Order) -> Vec<u8> {
        let data: Vec<u8> = (0..6i16)
            .flat_map(|k| short(order, (100 * k - 250) as u16))
            .collect();
        let mut t = tiff(
            order,
            &[
                (IMAGE_WIDTH, SHORT, 1, short(order, 3)),
                (IMAGE_LENGTH, SHORT, 1, short(order, 2)),
                (BITS_PER_SAMPLE, SHORT, 1, short(order, 16)),
                (SAMPLE_FORMAT, SHORT, 1, short(order, 2)),
                (ROWS_PER_STRIP, LONG, 1, long(order, 1)),
                (STRIP_OFFSETS, LONG, 2, vec![0; 8]),
                (
                    STRIP_BYTE_COUNTS,
                    LONG,
                    2,
                    [long(order, 6), long(order, 6)].concat(),
                ),
                (SOFTWARE, ASCII, 6, b"hello\0".to_vec()),
            ],
        );
        // The strips follow the IFD and its values; point the offsets at them.
        let at = t.len() as u32;
        let parsed = Tiff::parse(&t).unwrap();
        let offsets_at = parsed.find(0, STRIP_OFFSETS).unwrap().value_at;
        t[offsets_at..offsets_at + 4].copy_from_slice(&long(order, at));
        t[offsets_at + 4..offsets_at + 8].copy_from_slice(&long(order, at + 6));
        t.extend(data);
        t
    }

    #[test]
    fn both_byte_orders_read_the_same_image_and_tags() {
        for order in [Order::Little, Order::Big] {
            let bytes = int16_image(order);
            let t = Tiff::parse(&bytes).unwrap();
            assert_eq!(t.order, order);
            assert_eq!(t.ifds.len(), 1);
            assert_eq!(t.uint(0, IMAGE_WIDTH), Some(3));
            assert_eq!(t.ascii(t.find(0, SOFTWARE).unwrap()), "hello");
            assert_eq!(first_ifd_scalar(&bytes, IMAGE_LENGTH), Some(2));
            assert_eq!(first_ifd_scalar(&bytes, 999), None);
            let img = t.strip_image(0).unwrap();
            assert_eq!((img.width, img.height), (3, 2));
            let want: Vec<f64> = (0..6).map(|k| f64::from(100 * k - 250)).collect();
            assert_eq!(img.values, want);
        }
    }

    #[test]
    fn corrupt_structure_is_an_error() {
        let bytes = int16_image(Order::Little);
        // An IFD offset past the end, a loop back to the first IFD, a value past the end.
        let mut far = bytes.clone();
        far[4..8].copy_from_slice(&1_000_000u32.to_le_bytes());
        assert!(Tiff::parse(&far).unwrap_err().contains("past the end"));
        let mut looped = bytes.clone();
        let next_at = 8 + 2 + 12 * 8;
        looped[next_at..next_at + 4].copy_from_slice(&8u32.to_le_bytes());
        assert!(Tiff::parse(&looped).unwrap_err().contains("loops"));
        let mut long_value = bytes.clone();
        // The Software entry (the seventh after sorting by tag) claims 1 GB.
        let count_at = 8 + 2 + 12 * 6 + 4;
        long_value[count_at..count_at + 4].copy_from_slice(&(1u32 << 30).to_le_bytes());
        assert!(Tiff::parse(&long_value).unwrap_err().contains("tag 305"));
        assert!(Tiff::parse(&bytes[..5]).is_err());
        assert!(Tiff::parse(b"PK\x03\x04").is_err());
        for cut in 0..bytes.len() {
            if let Ok(t) = Tiff::parse(&bytes[..cut]) {
                assert!(t.strip_image(0).is_err(), "cut at {cut}");
            }
        }
    }
}
