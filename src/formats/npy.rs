//! The NumPy `.npy` header (format versions 1.0, 2.0 and 3.0, as described in numpy's
//! `numpy/lib/format.py` documentation; docs/formats.md): magic `\x93NUMPY`, major and minor
//! version bytes, a little-endian header length (u16 in 1.0, u32 in 2.0/3.0), then a Python
//! dict literal `{'descr': …, 'fortran_order': …, 'shape': (…), }` padded with spaces and a
//! newline; the array data follows. Only the header is parsed here: callers map or read the
//! data themselves. Nothing is sized from the header without checking it against the bytes
//! that follow it.

/// The first six bytes of every `.npy` file.
pub const MAGIC: &[u8] = b"\x93NUMPY";

/// Why a header cannot be used.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum NpyError {
    #[error("not a .npy file (no \\x93NUMPY magic)")]
    NotNpy,
    #[error("corrupt .npy header: {0}")]
    Header(String),
    #[error("unsupported .npy array: {0}")]
    Unsupported(String),
    #[error(".npy data: {0}")]
    Data(String),
}

/// A scalar element type: `kind` is numpy's type character (`f` float, `i` signed, `u`
/// unsigned, `b` bool, `V` raw bytes, used for padding).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Scalar {
    pub kind: char,
    pub size: usize,
    pub big_endian: bool,
}

/// A named field of a structured dtype, at `offset` bytes into each element.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    pub name: String,
    pub scalar: Scalar,
    pub offset: usize,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Dtype {
    Scalar(Scalar),
    /// List-form structured dtype `[('name', '<f8'), …]`; `itemsize` is the element size.
    Structured {
        fields: Vec<Field>,
        itemsize: usize,
    },
}

impl Dtype {
    pub fn itemsize(&self) -> usize {
        match self {
            Dtype::Scalar(s) => s.size,
            Dtype::Structured { itemsize, .. } => *itemsize,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Header {
    pub version: (u8, u8),
    pub dtype: Dtype,
    pub fortran_order: bool,
    pub shape: Vec<usize>,
    /// Offset of the array data from the start of the file.
    pub data_offset: usize,
}

impl Header {
    /// Number of elements (product of the shape; 1 for a 0-d array).
    pub fn count(&self) -> usize {
        self.shape.iter().product()
    }

    /// Size of the data in bytes.
    pub fn data_len(&self) -> usize {
        self.count() * self.dtype.itemsize()
    }
}

fn header_err(m: impl Into<String>) -> NpyError {
    NpyError::Header(m.into())
}

/// Parses the header at the start of `bytes` (the whole file, or at least its header) and
/// checks that the data it announces fits in `file_len` bytes.
pub fn parse(bytes: &[u8], file_len: usize) -> Result<Header, NpyError> {
    if !bytes.starts_with(MAGIC) {
        return Err(NpyError::NotNpy);
    }
    let (major, minor) = match bytes.get(6..8) {
        Some(v) => (v[0], v[1]),
        None => return Err(header_err("cut before the version")),
    };
    let (len, start): (Option<usize>, usize) = match major {
        1 => (
            bytes
                .get(8..10)
                .map(|b| u16::from_le_bytes([b[0], b[1]]) as usize),
            10,
        ),
        2 | 3 => (
            bytes
                .get(8..12)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize),
            12,
        ),
        _ => {
            return Err(NpyError::Unsupported(format!(
                "format version {major}.{minor} (1.0, 2.0 and 3.0 are read)"
            )))
        }
    };
    let len = len.ok_or_else(|| header_err("cut before the header length"))?;
    let text = bytes
        .get(start..start.saturating_add(len))
        .ok_or_else(|| header_err(format!("header of {len} bytes runs past the end")))?;
    // Versions 1 and 2 are latin-1; a valid header is ASCII anyway except for field names.
    let text: String = if major == 3 {
        std::str::from_utf8(text)
            .map_err(|_| header_err("header is not UTF-8"))?
            .to_string()
    } else {
        text.iter().map(|&b| b as char).collect()
    };
    let lit = Parser {
        s: text.as_bytes(),
        at: 0,
        depth: 0,
    }
    .whole()?;
    let Lit::Dict(items) = lit else {
        return Err(header_err("header is not a dict"));
    };
    let get = |key: &str| {
        items
            .iter()
            .find(|(k, _)| matches!(k, Lit::Str(s) if s == key))
            .map(|(_, v)| v)
    };
    let dtype = dtype(get("descr").ok_or_else(|| header_err("no 'descr'"))?)?;
    let fortran_order = match get("fortran_order") {
        Some(Lit::Bool(b)) => *b,
        _ => return Err(header_err("no boolean 'fortran_order'")),
    };
    let shape = match get("shape") {
        Some(Lit::List(dims)) => dims
            .iter()
            .map(|d| match d {
                Lit::Int(n) => Ok(*n),
                _ => Err(header_err("'shape' holds a non-integer")),
            })
            .collect::<Result<Vec<_>, _>>()?,
        _ => return Err(header_err("no 'shape' tuple")),
    };
    let data_offset = start + len;
    let data_len = shape
        .iter()
        .try_fold(dtype.itemsize(), |acc, &d| acc.checked_mul(d))
        .ok_or_else(|| header_err(format!("shape {shape:?} overflows")))?;
    if data_offset
        .checked_add(data_len)
        .is_none_or(|end| end > file_len)
    {
        return Err(NpyError::Data(format!(
            "shape {shape:?} of {}-byte elements needs {data_len} bytes after the header, the \
             file has {}; is it cut?",
            dtype.itemsize(),
            file_len.saturating_sub(data_offset)
        )));
    }
    Ok(Header {
        version: (major, minor),
        dtype,
        fortran_order,
        shape,
        data_offset,
    })
}

fn scalar(descr: &str) -> Result<Scalar, NpyError> {
    let bad = || NpyError::Unsupported(format!("dtype '{descr}'"));
    let mut chars = descr.chars();
    let order = chars.next().ok_or_else(bad)?;
    let big_endian = match order {
        '<' | '|' | '=' => false,
        '>' => true,
        _ => return Err(bad()),
    };
    let kind = chars.next().ok_or_else(bad)?;
    let size: usize = chars.as_str().parse().map_err(|_| bad())?;
    let ok = match kind {
        'f' => matches!(size, 4 | 8),
        'i' | 'u' => matches!(size, 1 | 2 | 4 | 8),
        'b' => size == 1,
        'V' => size > 0 && size < 1 << 20,
        _ => false,
    };
    if !ok {
        return Err(bad());
    }
    Ok(Scalar {
        kind,
        size,
        big_endian,
    })
}

fn dtype(lit: &Lit) -> Result<Dtype, NpyError> {
    match lit {
        Lit::Str(s) => {
            let sc = scalar(s)?;
            if sc.kind == 'V' {
                return Err(NpyError::Unsupported(format!("dtype '{s}'")));
            }
            Ok(Dtype::Scalar(sc))
        }
        Lit::List(items) => {
            let mut fields = Vec::new();
            let mut offset = 0usize;
            for item in items {
                let (name, ty) = match item {
                    Lit::List(pair) if pair.len() == 2 => match (&pair[0], &pair[1]) {
                        (Lit::Str(n), Lit::Str(t)) => (n.clone(), t.as_str()),
                        _ => return Err(header_err("a structured field is not ('name', 'type')")),
                    },
                    Lit::List(_) => {
                        return Err(NpyError::Unsupported(
                            "structured fields with a sub-array shape".into(),
                        ))
                    }
                    _ => return Err(header_err("a structured field is not a tuple")),
                };
                let sc = scalar(ty)?;
                fields.push(Field {
                    name,
                    scalar: sc,
                    offset,
                });
                offset += sc.size;
            }
            if fields.is_empty() {
                return Err(header_err("structured dtype without fields"));
            }
            Ok(Dtype::Structured {
                fields,
                itemsize: offset,
            })
        }
        _ => Err(NpyError::Unsupported(
            "'descr' is neither a type string nor a list of fields".into(),
        )),
    }
}

/// The subset of Python literals a `.npy` header uses; tuples parse as lists.
#[derive(Debug, Clone, PartialEq)]
enum Lit {
    Str(String),
    Int(usize),
    Bool(bool),
    None,
    List(Vec<Lit>),
    Dict(Vec<(Lit, Lit)>),
}

struct Parser<'a> {
    s: &'a [u8],
    at: usize,
    depth: usize,
}

impl Parser<'_> {
    fn whole(mut self) -> Result<Lit, NpyError> {
        let v = self.value()?;
        self.ws();
        if self.at != self.s.len() {
            return Err(header_err(format!("unexpected text at byte {}", self.at)));
        }
        Ok(v)
    }

    fn ws(&mut self) {
        while self.at < self.s.len() && self.s[self.at].is_ascii_whitespace() {
            self.at += 1;
        }
    }

    fn peek(&mut self) -> Option<u8> {
        self.ws();
        self.s.get(self.at).copied()
    }

    fn value(&mut self) -> Result<Lit, NpyError> {
        self.depth += 1;
        if self.depth > 16 {
            return Err(header_err("nested too deeply"));
        }
        let v = match self.peek() {
            Some(b'{') => self.seq(b'}', true)?,
            Some(b'(') => self.seq(b')', false)?,
            Some(b'[') => self.seq(b']', false)?,
            Some(q @ (b'\'' | b'"')) => {
                self.at += 1;
                let start = self.at;
                while self.at < self.s.len() && self.s[self.at] != q {
                    self.at += 1;
                }
                if self.at >= self.s.len() {
                    return Err(header_err("unterminated string"));
                }
                let text = String::from_utf8_lossy(&self.s[start..self.at]).into_owned();
                self.at += 1;
                Lit::Str(text)
            }
            Some(c) if c.is_ascii_alphanumeric() => {
                let start = self.at;
                while self.at < self.s.len()
                    && (self.s[self.at].is_ascii_alphanumeric() || self.s[self.at] == b'_')
                {
                    self.at += 1;
                }
                let word = String::from_utf8_lossy(&self.s[start..self.at]).into_owned();
                // Python 2 headers may write longs as `100L`.
                let digits = word.trim_end_matches('L');
                match word.as_str() {
                    "True" => Lit::Bool(true),
                    "False" => Lit::Bool(false),
                    "None" => Lit::None,
                    _ => Lit::Int(
                        digits
                            .parse()
                            .map_err(|_| header_err(format!("unexpected '{word}'")))?,
                    ),
                }
            }
            _ => return Err(header_err(format!("unexpected text at byte {}", self.at))),
        };
        self.depth -= 1;
        Ok(v)
    }

    fn seq(&mut self, close: u8, dict: bool) -> Result<Lit, NpyError> {
        self.at += 1;
        let mut items = Vec::new();
        let mut pairs = Vec::new();
        loop {
            if self.peek() == Some(close) {
                self.at += 1;
                break;
            }
            let v = self.value()?;
            if dict {
                if self.peek() != Some(b':') {
                    return Err(header_err("dict key without ':'"));
                }
                self.at += 1;
                pairs.push((v, self.value()?));
            } else {
                items.push(v);
            }
            match self.peek() {
                Some(b',') => self.at += 1,
                Some(c) if c == close => {}
                _ => return Err(header_err(format!("expected ',' at byte {}", self.at))),
            }
        }
        Ok(if dict {
            Lit::Dict(pairs)
        } else {
            Lit::List(items)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn npy(version: u8, dict: &str, data: &[u8]) -> Vec<u8> {
        let mut out = MAGIC.to_vec();
        out.extend([version, 0]);
        let mut h = dict.to_string();
        let pre = if version == 1 { 10 } else { 12 };
        while !(pre + h.len() + 1).is_multiple_of(64) {
            h.push(' ');
        }
        h.push('\n');
        if version == 1 {
            out.extend((h.len() as u16).to_le_bytes());
        } else {
            out.extend((h.len() as u32).to_le_bytes());
        }
        out.extend(h.as_bytes());
        out.extend(data);
        out
    }

    #[test]
    fn headers() {
        let b = npy(
            1,
            "{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }",
            &[0; 24],
        );
        let h = parse(&b, b.len()).unwrap();
        assert_eq!(h.shape, vec![3]);
        // numpy pads the header so that the data starts on a 64-byte boundary.
        assert_eq!(h.data_offset % 64, 0);
        assert_eq!(
            h.dtype,
            Dtype::Scalar(Scalar {
                kind: 'f',
                size: 8,
                big_endian: false
            })
        );
        let b = npy(
            3,
            "{'descr': [('time', '<f8'), ('velocity', '>f4')], 'fortran_order': True, \
             'shape': (2, 1), }",
            &[0; 24],
        );
        let h = parse(&b, b.len()).unwrap();
        assert!(h.fortran_order);
        let Dtype::Structured { fields, itemsize } = &h.dtype else {
            panic!()
        };
        assert_eq!(*itemsize, 12);
        assert_eq!(fields[1].offset, 8);
        assert!(fields[1].scalar.big_endian);
        // 0-d scalar.
        let b = npy(
            1,
            "{'descr': '<i8', 'fortran_order': False, 'shape': (), }",
            &[0; 8],
        );
        assert_eq!(parse(&b, b.len()).unwrap().count(), 1);
    }

    #[test]
    fn bad_headers() {
        let ok = npy(
            1,
            "{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }",
            &[0; 24],
        );
        assert_eq!(parse(b"PK\x03\x04", 4), Err(NpyError::NotNpy));
        // Cut data, cut header, absurd shape, unknown dtype, garbage.
        assert!(matches!(parse(&ok, ok.len() - 1), Err(NpyError::Data(_))));
        assert!(matches!(parse(&ok[..30], 30), Err(NpyError::Header(_))));
        let huge = npy(
            1,
            "{'descr': '<f8', 'fortran_order': False, 'shape': (4611686018427387904, 8), }",
            &[],
        );
        assert!(parse(&huge, huge.len()).is_err());
        let c16 = npy(
            1,
            "{'descr': '<c16', 'fortran_order': False, 'shape': (1,), }",
            &[0; 16],
        );
        assert!(matches!(
            parse(&c16, c16.len()),
            Err(NpyError::Unsupported(_))
        ));
        let junk = npy(1, "{'descr': '<f8', 'fortran_order': Fals", &[]);
        assert!(parse(&junk, junk.len()).is_err());
        let deep = npy(1, &"[".repeat(100), &[]);
        assert!(parse(&deep, deep.len()).is_err());
    }
}
