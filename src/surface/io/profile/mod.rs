//! Line-profile (1-D) readers: stylus-profilometer line scans for the TFC bulge fit
//! (docs/bulge.md, docs/surfaces.md "Line profiles"). Pure functions of the file's bytes, with
//! their own small registry in the style of `registry::READERS`: detection by content, x
//! positions (uniform or not) and heights in metres, a validity flag per point.
//!
//! Formats: Bruker Dektak CSV export (`dektak`), `.hfm` (`X;Y;valid` text, `hfm`), Bruker
//! Vision64 `.opdx` profiles (`opdx`) and plain two-column x–z text (`xz`).

use crate::surface::{Result, SurfaceError};
use std::collections::BTreeMap;
use std::path::Path;

mod dektak;
mod hfm;
mod opdx;
mod xz;

/// One line profile: positions along the scan and heights, metres; `valid[k]` false where the
/// instrument marked the point invalid or wrote NaN (then `z[k]` is 0).
#[derive(Debug, Clone, PartialEq)]
pub struct LineProfile {
    pub x: Vec<f64>,
    pub z: Vec<f64>,
    pub valid: Vec<bool>,
    /// The reader's id (`ProfileReader::id`).
    pub format: &'static str,
    /// The file's metadata (units, instrument settings) as key/value text.
    pub header: BTreeMap<String, String>,
}

impl LineProfile {
    pub fn len(&self) -> usize {
        self.x.len()
    }
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }
    /// The sample spacing if every step equals it to 1 % (positions are often printed with few
    /// digits: xy-4.txt's 1e-4 steps with 6 decimals), else `None`. Informative: the bulge fit
    /// uses the positions as they are.
    pub fn uniform_spacing(&self) -> Option<f64> {
        let n = self.x.len();
        if n < 2 {
            return None;
        }
        let d = (self.x[n - 1] - self.x[0]) / (n - 1) as f64;
        let tol = 1e-2 * d.abs();
        self.x
            .windows(2)
            .all(|w| ((w[1] - w[0]) - d).abs() <= tol)
            .then_some(d)
    }
}

/// What a reader produces: heights in metres with NaN marking invalid points.
pub(crate) struct RawProfile {
    pub x: Vec<f64>,
    pub z: Vec<f64>,
    pub header: BTreeMap<String, String>,
}

/// One line-profile format.
pub struct ProfileReader {
    pub id: &'static str,
    pub name: &'static str,
    /// The extensions its files usually have (informative: detection is by content).
    pub extensions: &'static [&'static str],
    /// How the sniffer recognises it, for the docs.
    pub detected_by: &'static str,
    pub(crate) sniff: fn(&[u8]) -> bool,
    pub(crate) read: fn(&Path, &[u8]) -> Result<RawProfile>,
    /// Files the tests read it on, from the repository root (provenance in tests/data/README.md).
    pub samples: &'static [&'static str],
}

/// Every line-profile reader, in detection order: magic first, then the text headers, then
/// plain two-column text.
pub const PROFILE_READERS: &[ProfileReader] = &[
    ProfileReader {
        id: "opdx",
        name: "Bruker Vision64 OPDx profile",
        extensions: &["opdx"],
        detected_by: "`VCA DATA\\x01\\x00\\x00\\x55`",
        sniff: |h| h.starts_with(opdx::MAGIC),
        read: opdx::read,
        samples: &["tests/data/surfaces/opdx-3.opdx"],
    },
    ProfileReader {
        id: "dektak",
        name: "Bruker Dektak CSV export",
        extensions: &["csv"],
        detected_by: "`Scan Parameters`",
        sniff: |h| h.starts_with(dektak::MAGIC),
        read: dektak::read,
        samples: &["tests/data/surfaces/dektak-1.csv"],
    },
    ProfileReader {
        id: "hfm",
        name: "HFM profile text (`X;Y;valid`)",
        extensions: &["hfm"],
        detected_by: "`X;Y;valid`",
        sniff: |h| h.starts_with(hfm::MAGIC),
        read: hfm::read,
        samples: &["tests/data/surfaces/hfm-1.hfm"],
    },
    ProfileReader {
        id: "xz",
        name: "Plain x–z text (two columns)",
        extensions: &["txt", "csv", "xz"],
        detected_by: "text: two numeric columns, optional `# x_unit:`/`# z_unit:` or unit line",
        sniff: xz::looks_like,
        read: xz::read,
        samples: &[
            "tests/data/surfaces/xy-1.txt",
            "tests/data/surfaces/xy-4.txt",
            "tests/data/surfaces/opdx-3.txt",
        ],
    },
];

/// The reader whose sniffer claims `head` first.
pub fn detect(head: &[u8]) -> Option<&'static ProfileReader> {
    PROFILE_READERS.iter().find(|r| (r.sniff)(head))
}

/// The formats, for the "supported:" list of the error.
pub fn supported() -> String {
    super::registry::supported_list(PROFILE_READERS.iter().map(|r| (r.name, r.extensions)))
}

/// The line-profile table of docs/surfaces.md, between its `profiles:begin`/`profiles:end`
/// markers.
pub fn markdown_table() -> String {
    super::registry::markdown_table_of(
        PROFILE_READERS
            .iter()
            .map(|r| (r.name, r.id, r.extensions, r.detected_by, r.samples)),
    )
}

/// How many leading bytes the sniffers see.
const SNIFF_BYTES: usize = 64 * 1024;

/// Read one line profile in SI units from any supported profile format.
pub fn read_line_profile(path: &Path) -> Result<LineProfile> {
    let bytes = std::fs::read(path).map_err(|source| SurfaceError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    read_profile_bytes(path, &bytes)
}

/// As [`read_line_profile`], on bytes already read (`path` names the file in errors).
pub fn read_profile_bytes(path: &Path, bytes: &[u8]) -> Result<LineProfile> {
    let head = &bytes[..bytes.len().min(SNIFF_BYTES)];
    let Some(reader) = detect(head) else {
        let what = if bytes.is_empty() {
            "empty file"
        } else {
            "not a line profile"
        };
        return Err(format_error(
            path,
            format!("{what}; supported line-profile formats: {}", supported()),
        ));
    };
    let raw = (reader.read)(path, bytes)?;
    finish(path, reader.id, raw)
}

/// Checks what every reader must guarantee and turns NaN heights into the validity flags.
fn finish(path: &Path, format: &'static str, raw: RawProfile) -> Result<LineProfile> {
    let RawProfile { x, mut z, header } = raw;
    if x.len() != z.len() {
        return Err(format_error(
            path,
            format!("{} positions for {} heights", x.len(), z.len()),
        ));
    }
    if let Some(k) = x.iter().position(|v| !v.is_finite()) {
        return Err(format_error(
            path,
            format!("position of point {k} is not a finite number"),
        ));
    }
    let valid: Vec<bool> = z.iter().map(|v| v.is_finite()).collect();
    let n_valid = valid.iter().filter(|v| **v).count();
    if n_valid < 3 {
        return Err(format_error(
            path,
            format!(
                "line profile has {n_valid} valid points of {}; at least 3 are needed",
                x.len()
            ),
        ));
    }
    for (v, ok) in z.iter_mut().zip(&valid) {
        if !ok {
            *v = 0.0;
        }
    }
    Ok(LineProfile {
        x,
        z,
        valid,
        format,
        header,
    })
}

pub(crate) fn format_error(path: &Path, reason: impl Into<String>) -> SurfaceError {
    SurfaceError::Format {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Metres per unit of a unit as profilometer software spells it in a column header or header
/// line: the symbols of `units::length_factor`, bracketed (`[mm]`), or spelled out
/// (`Micrometer`, Dektak's "Raw Micrometer").
pub(crate) fn unit_factor(word: &str) -> Option<f64> {
    let w = word
        .trim()
        .trim_start_matches(['[', '('])
        .trim_end_matches([']', ')']);
    if let Some(f) = super::units::length_factor(w) {
        return Some(f);
    }
    let lower = w.to_lowercase();
    let lower = lower.trim_end_matches('s');
    Some(match lower {
        "meter" | "metre" => 1.0,
        "millimeter" | "millimetre" => 1e-3,
        "micrometer" | "micrometre" | "mikrometer" => 1e-6,
        "nanometer" | "nanometre" => 1e-9,
        "angstrom" | "ångström" => 1e-10,
        _ => return None,
    })
}

/// Parses one number of a data line, naming the line in the error.
pub(crate) fn number(path: &Path, line_no: usize, token: &str) -> Result<f64> {
    super::units::parse_value(token.trim())
        .ok_or_else(|| format_error(path, format!("line {line_no}: `{token}` is not a number")))
}

#[cfg(test)]
mod tests;
