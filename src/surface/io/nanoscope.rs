//! Bruker / Veeco / Digital Instruments NanoScope binary files, version ≥ 0x04300000.
//!
//! Header: latin-1 `\key: value` lines ending `\r\n`, sections `\*Name`, up to `\*File list end`.
//! Each `\*Ciao image list` is one channel of little-endian int16/int32 samples stored bottom
//! line first. Heights: `raw × hard_value / 2^(8·bpp) × soft_value × unit(soft)`, the soft scale
//! being looked up by the name the `Z scale` line gives it.
use super::units::{decode_text, length_factor};
use super::{find_channel, format_error, heights_with_nan, unsupported, RawMap, ReadOptions};
use crate::surface::{HeightMap, Result, SurfaceError};
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

const HEADER_END: &[u8] = b"\\*File list end";
/// Oldest version with the CIAO soft/hard scale scheme (as SurfaceTopography requires).
const MIN_VERSION: u32 = 0x0430_0000;

/// One `\*Section` with its `\key: value` lines; keys lower-cased.
struct Section {
    name: String,
    entries: Vec<(String, String)>,
}

impl Section {
    /// Value of `key` (lower case); CIAO keys also match without their `@<group>:` prefix.
    fn get(&self, key: &str) -> Option<&str> {
        self.entries
            .iter()
            .find(|(k, _)| k == key || strip_group(k) == key)
            .map(|(_, v)| v.as_str())
    }
}

/// `@2:z scale` → `z scale`.
fn strip_group(key: &str) -> &str {
    key.strip_prefix('@')
        .and_then(|rest| rest.split_once(':'))
        .filter(|(group, _)| !group.is_empty() && group.bytes().all(|b| b.is_ascii_digit()))
        .map_or(key, |(_, name)| name)
}

fn parse_header(text: &str) -> Vec<Section> {
    let mut sections: Vec<Section> = Vec::new();
    for line in text.lines() {
        let line = line.trim_end_matches('\r');
        if let Some(name) = line.strip_prefix("\\*") {
            let name = name.trim().to_lowercase();
            if name == "file list end" {
                break;
            }
            sections.push(Section {
                name,
                entries: vec![],
            });
        } else if let (Some(body), Some(section)) = (line.strip_prefix('\\'), sections.last_mut()) {
            // The key ends at the first ':' followed by a space or the line end
            // (`@2:Image Data: S ...` has a ':' inside the key).
            let bytes = body.as_bytes();
            let split = (0..bytes.len())
                .find(|&k| bytes[k] == b':' && bytes.get(k + 1).is_none_or(|&b| b == b' '));
            if let Some(k) = split {
                section.entries.push((
                    body[..k].trim().to_lowercase(),
                    body[k + 1..].trim().to_string(),
                ));
            }
        }
    }
    sections
}

/// The text between the first `open` and the next `close`.
fn between(text: &str, open: char, close: char) -> Option<&str> {
    let start = text.find(open)? + open.len_utf8();
    let len = text[start..].find(close)?;
    Some(&text[start..start + len])
}

fn first_number(text: &str) -> Option<f64> {
    text.split_whitespace().next()?.parse().ok()
}

/// `V 57.39005 nm/V` → metres per volt.
fn parse_soft_scale(value: &str) -> Option<f64> {
    let mut tokens = value
        .split_whitespace()
        .skip_while(|t| t.parse::<f64>().is_err());
    let number: f64 = tokens.next()?.parse().ok()?;
    let unit = tokens.next()?.strip_suffix("/V")?;
    Some(number * length_factor(unit)?)
}

/// `<sx> <sy> <unit>` or `<s> <unit>` (square) → metres.
fn parse_scan_size(value: &str) -> Option<(f64, f64)> {
    let tokens: Vec<&str> = value.split_whitespace().collect();
    let numbers: Vec<f64> = tokens.iter().map_while(|t| t.parse().ok()).collect();
    let factor = length_factor(tokens.get(numbers.len())?)?;
    match numbers[..] {
        [s] => Some((s * factor, s * factor)),
        [sx, sy] => Some((sx * factor, sy * factor)),
        _ => None,
    }
}

/// One channel of a NanoScope file as heights in metres (layout and scaling in the module docs).
pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let sections = read_header(path, bytes)?;
    let version_text = check_version(path, &sections)?;
    let channel = select_channel(path, &sections, opts)?;
    let layout = data_layout(path, &channel, bytes.len())?;
    let scan = scan_size(path, &channel)?;
    let scale = z_scale(path, &sections, &channel, layout.bpp)?;
    let z = decode_heights(path, bytes, &layout, scale.metres_per_lsb)?;

    let mut header = BTreeMap::new();
    if let Some(soft) = scale.soft_scale {
        header.insert("soft_scale".into(), soft);
    }
    if let Some(warning) = scale.warning {
        header.insert("warning".into(), warning);
    }
    header.insert("version".into(), version_text.to_string());
    header.insert("channels".into(), channel.listing);
    header.insert("channel_internal".into(), channel.internal.clone());
    header.insert("scan_size".into(), scan.text.to_string());
    header.insert("z_scale".into(), scale.text.to_string());
    header.insert("bytes_per_pixel".into(), layout.bpp.to_string());
    header.insert("data_offset".into(), layout.offset.to_string());
    header.insert(
        "metres_per_lsb".into(),
        format!("{:e}", scale.metres_per_lsb),
    );
    let name = if channel.display.is_empty() {
        channel.internal
    } else {
        channel.display
    };
    Ok(RawMap {
        z,
        dx: scan.x / layout.nx as f64,
        dy: scan.y / layout.ny as f64,
        x0: 0.0,
        y0: 0.0,
        channel: name,
        format: "nanoscope",
        header,
    })
}

/// A required header entry is absent.
fn missing(path: &Path, what: &str) -> SurfaceError {
    format_error(path, format!("NanoScope header lacks {what}"))
}

/// The first section called `name` (lower case).
fn section<'a>(sections: &'a [Section], name: &str) -> Option<&'a Section> {
    sections.iter().find(|s| s.name == name)
}

/// The header's sections; ASCII-data files and a missing `\*File list end` are refused.
fn read_header(path: &Path, bytes: &[u8]) -> Result<Vec<Section>> {
    if bytes.starts_with(b"?*File list") {
        return Err(unsupported(
            path,
            "NanoScope file with ASCII data (`?*File list`); export it as binary",
        ));
    }
    let header_end = bytes
        .windows(HEADER_END.len())
        .position(|w| w == HEADER_END)
        .ok_or_else(|| {
            format_error(
                path,
                "NanoScope header has no `\\*File list end` (truncated?)",
            )
        })?;
    Ok(parse_header(&decode_text(&bytes[..header_end])))
}

/// The `\Version` text of the File list, if at least [`MIN_VERSION`].
fn check_version<'a>(path: &Path, sections: &'a [Section]) -> Result<&'a str> {
    let file_list =
        section(sections, "file list").ok_or_else(|| missing(path, "`\\*File list`"))?;
    let version_text = file_list
        .get("version")
        .ok_or_else(|| missing(path, "`\\Version` in File list"))?;
    let version =
        u32::from_str_radix(version_text.trim().trim_start_matches("0x"), 16).map_err(|_| {
            format_error(
                path,
                format!("NanoScope `\\Version: {version_text}` is not hex"),
            )
        })?;
    if version < MIN_VERSION {
        return Err(unsupported(
            path,
            format!("NanoScope version {version_text} is older than 0x04300000 (not read)"),
        ));
    }
    Ok(version_text)
}

/// The chosen `\*Ciao image list` and the scan list its keys fall back to.
struct Channel<'a> {
    image: &'a Section,
    scan_list: Option<&'a Section>,
    /// `[internal]` name from `\@2:Image Data`.
    internal: String,
    /// `"display"` name (may be empty).
    display: String,
    /// Every channel as `[internal] "display"`, for messages and the header.
    listing: String,
}

impl<'a> Channel<'a> {
    /// Per-image keys, falling back to the scan list where older versions keep them.
    fn get(&self, key: &str) -> Option<&'a str> {
        self.image
            .get(key)
            .or_else(|| self.scan_list.and_then(|s| s.get(key)))
    }

    /// A count (first token); data location keys (`image_only`) belong to the image itself.
    fn count(
        &self,
        path: &Path,
        key: &str,
        default: Option<usize>,
        image_only: bool,
    ) -> Result<usize> {
        let value = if image_only {
            self.image.get(key)
        } else {
            self.get(key)
        };
        match value {
            None => default.ok_or_else(|| {
                missing(path, &format!("`\\{key}` for channel [{}]", self.internal))
            }),
            Some(text) => text
                .split_whitespace()
                .next()
                .and_then(|t| t.parse::<usize>().ok())
                .ok_or_else(|| {
                    format_error(path, format!("NanoScope `\\{key}: {text}` is not a count"))
                }),
        }
    }
}

/// The requested channel, else ZSensor ("Height Sensor"), else Height.
fn select_channel<'a>(
    path: &Path,
    sections: &'a [Section],
    opts: &ReadOptions,
) -> Result<Channel<'a>> {
    let images: Vec<&Section> = sections
        .iter()
        .filter(|s| s.name == "ciao image list")
        .collect();
    let names: Vec<Vec<String>> = images
        .iter()
        .map(|image| {
            let data = image.get("image data").unwrap_or("");
            let internal = between(data, '[', ']').unwrap_or("").to_string();
            let display = between(data, '"', '"').unwrap_or("").to_string();
            vec![internal, display]
        })
        .collect();
    let listing = names
        .iter()
        .map(|n| format!("[{}] \"{}\"", n[0], n[1]))
        .collect::<Vec<_>>()
        .join("; ");
    let chosen = match &opts.channel {
        Some(wanted) => find_channel(wanted, &names).ok_or_else(|| {
            format_error(path, format!("no channel `{wanted}`; channels: {listing}"))
        })?,
        None => names
            .iter()
            .position(|n| {
                n[0].eq_ignore_ascii_case("zsensor") || n[1].eq_ignore_ascii_case("height sensor")
            })
            .or_else(|| {
                names
                    .iter()
                    .position(|n| n[0].eq_ignore_ascii_case("height"))
            })
            .ok_or_else(|| {
                format_error(
                    path,
                    format!("no [ZSensor] or [Height] channel; channels: {listing}; choose one"),
                )
            })?,
    };
    Ok(Channel {
        image: images[chosen],
        scan_list: section(sections, "ciao scan list"),
        internal: names[chosen][0].clone(),
        display: names[chosen][1].clone(),
        listing,
    })
}

/// Where the chosen image's samples sit and how they are stored.
struct DataLayout {
    /// Byte offset of the first sample.
    offset: usize,
    /// Bytes per sample: 2 or 4.
    bpp: usize,
    nx: usize,
    ny: usize,
    /// Bytes of image data, `nx·ny·bpp`, all inside the file.
    needed: usize,
}

/// The image's location and size, checked against the file length and `\Data length`.
fn data_layout(path: &Path, channel: &Channel, file_len: usize) -> Result<DataLayout> {
    let offset = channel.count(path, "data offset", None, true)?;
    let data_length = channel.count(path, "data length", None, true)?;
    let bpp = channel.count(path, "bytes/pixel", Some(2), false)?;
    let nx = channel.count(path, "samps/line", None, false)?;
    let ny = channel.count(path, "number of lines", None, false)?;
    if bpp != 2 && bpp != 4 {
        return Err(format_error(
            path,
            format!("NanoScope `\\Bytes/pixel: {bpp}`; expected 2 or 4"),
        ));
    }
    if nx == 0 || ny == 0 {
        return Err(format_error(
            path,
            format!("NanoScope image is {nx}×{ny} pixels"),
        ));
    }
    let needed = nx.checked_mul(ny).and_then(|n| n.checked_mul(bpp));
    let fits = needed
        .and_then(|n| n.checked_add(offset))
        .is_some_and(|end| end <= file_len);
    let Some(needed) = needed.filter(|_| fits) else {
        return Err(format_error(
            path,
            format!(
                "truncated NanoScope file: image data needs {} bytes at offset {offset} but the file has {}",
                needed.map_or(format!("{nx}×{ny}×{bpp}"), |n| n.to_string()),
                file_len
            ),
        ));
    };
    if data_length < needed {
        return Err(format_error(
            path,
            format!(
                "truncated NanoScope image: `\\Data length: {data_length}` but {nx}×{ny} samples \
                 of {bpp} bytes need {needed}"
            ),
        ));
    }
    Ok(DataLayout {
        offset,
        bpp,
        nx,
        ny,
        needed,
    })
}

/// Lateral size of the scan, metres, with the header text it came from.
struct ScanSize<'a> {
    x: f64,
    y: f64,
    text: &'a str,
}

/// `\Scan Size` of the image, or of the scan list, in metres.
fn scan_size<'a>(path: &Path, channel: &Channel<'a>) -> Result<ScanSize<'a>> {
    let text = channel
        .get("scan size")
        .ok_or_else(|| missing(path, "`\\Scan Size`"))?;
    let (x, y) = parse_scan_size(text).ok_or_else(|| {
        format_error(
            path,
            format!("NanoScope `\\Scan Size: {text}`; expected `<sx> <sy> nm|~m`"),
        )
    })?;
    Ok(ScanSize { x, y, text })
}

/// The chosen image's height scale and what the header should record about it.
struct ZScale<'a> {
    /// The `\@2:Z scale` text.
    text: &'a str,
    metres_per_lsb: f64,
    /// `name: value` of the soft scale used, if any.
    soft_scale: Option<String>,
    /// Set when the bracketed per-LSB figure disagrees with the hard value.
    warning: Option<String>,
}

/// Metres per LSB: `hard_value / 2^(8·bpp) × soft_value × unit(soft)`; without a soft scale
/// the hard value is itself a length (older CIAO files).
fn z_scale<'a>(
    path: &Path,
    sections: &'a [Section],
    channel: &Channel<'a>,
    bpp: usize,
) -> Result<ZScale<'a>> {
    let z_scale = channel
        .image
        .get("z scale")
        .ok_or_else(|| missing(path, "`\\@2:Z scale` in the image list"))?;
    let lsb_per_range = 2f64.powi(8 * bpp as i32);
    // The hard value follows the bracketed parts: `V [soft] (x V/LSB) <value> V`.
    let tail = z_scale
        .rsplit_once(')')
        .or_else(|| z_scale.rsplit_once(']'))
        .map_or(z_scale, |(_, after)| after);
    let mut tail_tokens = tail
        .split_whitespace()
        .skip_while(|t| t.parse::<f64>().is_err());
    let hard_value = tail_tokens.next().and_then(|t| t.parse::<f64>().ok());
    let hard_unit = tail_tokens.next();
    let Some(hard_value) = hard_value.filter(|v| v.is_finite() && *v != 0.0) else {
        return Err(format_error(
            path,
            format!("NanoScope `Z scale: {z_scale}`; expected `V [soft] (x V/LSB) <value> V`"),
        ));
    };
    let (metres_per_volt, soft_scale) = match between(z_scale, '[', ']') {
        Some(soft_name) => {
            let soft = soft_scale(path, sections, soft_name)?;
            (soft.metres_per_volt, Some(soft.header))
        }
        None => (
            hard_unit.and_then(length_factor).ok_or_else(|| {
                format_error(
                    path,
                    format!("NanoScope `Z scale: {z_scale}` has no soft scale"),
                )
            })?,
            None,
        ),
    };
    // The bracketed per-LSB figure should agree with hard_value / 2^(8·bpp).
    let mut warning = None;
    if let Some(per_lsb) = between(z_scale, '(', ')').and_then(first_number) {
        let derived = hard_value / lsb_per_range;
        if ((per_lsb - derived) / derived).abs() >= 1e-3 {
            warning = Some(format!(
                "Z scale: bracketed {per_lsb} per LSB disagrees with hard value / 2^{} = {derived}",
                8 * bpp
            ));
        }
    }
    Ok(ZScale {
        text: z_scale,
        metres_per_lsb: hard_value / lsb_per_range * metres_per_volt,
        soft_scale,
        warning,
    })
}

/// A soft scale looked up by name.
struct SoftScale {
    metres_per_volt: f64,
    /// `name: value`, as the header records it.
    header: String,
}

/// The soft scale `\@<name>` from the Scanner list or the Ciao scan list.
fn soft_scale(path: &Path, sections: &[Section], soft_name: &str) -> Result<SoftScale> {
    let key = format!("@{}", soft_name.trim().to_lowercase());
    let soft_text = ["scanner list", "ciao scan list"]
        .iter()
        .filter_map(|name| section(sections, name))
        .find_map(|s| s.get(&key))
        .ok_or_else(|| {
            missing(
                path,
                &format!("soft scale `\\@{soft_name}` in Scanner list or Ciao scan list"),
            )
        })?;
    let header = format!("{soft_name}: {soft_text}");
    let metres_per_volt = parse_soft_scale(soft_text).ok_or_else(|| {
        format_error(
            path,
            format!("soft scale `\\@{soft_name}: {soft_text}`; expected `V <value> nm/V`"),
        )
    })?;
    Ok(SoftScale {
        metres_per_volt,
        header,
    })
}

/// Samples → metres (saturated codes → NaN), rows flipped from bottom-first to top-first.
fn decode_heights(
    path: &Path,
    bytes: &[u8],
    layout: &DataLayout,
    metres_per_lsb: f64,
) -> Result<Array2<f64>> {
    let data = &bytes[layout.offset..layout.offset + layout.needed];
    let samples: Vec<f64> = if layout.bpp == 2 {
        data.chunks_exact(2)
            .map(|c| match i16::from_le_bytes([c[0], c[1]]) {
                i16::MAX | i16::MIN | -32767 => f64::NAN, // saturated
                raw => raw as f64 * metres_per_lsb,
            })
            .collect()
    } else {
        data.chunks_exact(4)
            .map(|c| match i32::from_le_bytes([c[0], c[1], c[2], c[3]]) {
                i32::MAX | i32::MIN | -2147483647 => f64::NAN,
                raw => raw as f64 * metres_per_lsb,
            })
            .collect()
    };
    let bottom_first = Array2::from_shape_vec((layout.ny, layout.nx), samples)
        .map_err(|e| format_error(path, format!("NanoScope data shape: {e}")))?;
    Ok(bottom_first.slice(ndarray::s![..;-1, ..]).to_owned())
}

/// Soft scale the writer declares (name and value as a real Multimode/Icon file would).
const SOFT_SCALE_NAME: &str = "Sens. ZsensSens";
const SOFT_SCALE_NM_PER_V: f64 = 57.39005;
const HEADER_BLOCK: usize = 8192;

/// What the encoder's header states.
struct EncoderHeader {
    nx: usize,
    ny: usize,
    bpp: usize,
    /// Scan size, nm.
    sx_nm: f64,
    sy_nm: f64,
    /// Volts spanning the integer range.
    hard_value: f64,
    lsb_per_range: f64,
}

impl EncoderHeader {
    /// Header text for image data at `offset` (the File list's `\Data length` is that offset).
    fn text(&self, offset: usize) -> String {
        let EncoderHeader {
            nx,
            ny,
            bpp,
            sx_nm,
            sy_nm,
            hard_value,
            lsb_per_range,
        } = *self;
        let data_length = nx * ny * bpp;
        let mut h = String::new();
        let mut line = |s: &str| {
            h.push_str(s);
            h.push_str("\r\n");
        };
        line("\\*File list");
        line("\\Version: 0x09200000");
        line("\\Date: 12:00:00 PM Mon Jan 01 2024");
        line("\\Start context: OL2");
        line(&format!("\\Data length: {offset}"));
        line("\\Text: ");
        line("\\*Scanner list");
        line("\\Scanner type: Multimode");
        line("\\Serial Number: hdi-synthetic");
        line(&format!(
            "\\@{SOFT_SCALE_NAME}: V {SOFT_SCALE_NM_PER_V} nm/V"
        ));
        line("\\*Ciao scan list");
        line(&format!("\\Scan Size: {sx_nm} {sy_nm} nm"));
        line(&format!("\\Samps/line: {nx}"));
        line(&format!("\\Lines: {ny}"));
        line("\\@Sens. Zsens: V 1 V/V");
        line("\\*Ciao image list");
        line(&format!("\\Data offset: {offset}"));
        line(&format!("\\Data length: {data_length}"));
        line(&format!("\\Bytes/pixel: {bpp}"));
        line("\\Data type: AFM");
        line(&format!("\\Samps/line: {nx}"));
        line(&format!("\\Number of lines: {ny}"));
        line(&format!("\\Scan Size: {sx_nm} {sy_nm} nm"));
        line("\\@2:Image Data: S [ZSensor] \"Height Sensor\"");
        let per_lsb = hard_value / lsb_per_range;
        line(&format!(
            "\\@2:Z scale: V [{SOFT_SCALE_NAME}] ({per_lsb:e} V/LSB) {hard_value} V"
        ));
        line(&format!(
            "\\@2:Z offset: V [{SOFT_SCALE_NAME}] ({per_lsb:e} V/LSB) 0 V"
        ));
        line("\\*File list end");
        h
    }
}

/// Encode as a Bruker NanoScope v5+ file with int16 or int32 data (`bytes_per_pixel` 2 or 4).
///
/// The hard value is chosen so that the integer range spans 1.05 × max|z|, so the quantisation
/// step is 2.1·max|z| / 2^(8·bpp). Invalid pixels are written as the most negative integer
/// (saturated), which the reader marks invalid. Lateral offsets are not stored.
///
/// # Panics
/// If `bytes_per_pixel` is not 2 or 4 (a programming error, not a data error).
pub fn encode_nanoscope(map: &HeightMap, bytes_per_pixel: usize) -> Vec<u8> {
    assert!(
        bytes_per_pixel == 2 || bytes_per_pixel == 4,
        "NanoScope bytes/pixel must be 2 or 4, got {bytes_per_pixel}"
    );
    let bpp = bytes_per_pixel;
    let (nx, ny) = (map.nx(), map.ny());
    let heights = heights_with_nan(map);
    let max_abs = heights
        .iter()
        .filter(|v| v.is_finite())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let max_abs = if max_abs > 0.0 { max_abs } else { 1e-9 };
    let metres_per_volt = SOFT_SCALE_NM_PER_V * 1e-9;
    let hard_value = 2.1 * max_abs / metres_per_volt;
    let lsb_per_range = 2f64.powi(8 * bpp as i32);
    let metres_per_lsb = hard_value / lsb_per_range * metres_per_volt;
    let (size_x, size_y) = map.size();
    let header = EncoderHeader {
        nx,
        ny,
        bpp,
        sx_nm: size_x * 1e9,
        sy_nm: size_y * 1e9,
        hard_value,
        lsb_per_range,
    };
    let mut offset = HEADER_BLOCK;
    while header.text(offset).len() > offset {
        offset += HEADER_BLOCK;
    }
    let mut out = header.text(offset).into_bytes();
    out.resize(offset, 0);
    let limit = lsb_per_range / 2.0 - 2.0; // stay clear of the saturation codes
    for row in heights.rows().into_iter().rev() {
        for &v in row {
            let raw = if v.is_finite() {
                (v / metres_per_lsb).round().clamp(-limit, limit)
            } else {
                -lsb_per_range / 2.0
            };
            if bpp == 2 {
                out.extend_from_slice(&(raw as i16).to_le_bytes());
            } else {
                out.extend_from_slice(&(raw as i32).to_le_bytes());
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};
    use super::encode_nanoscope;
    use crate::surface::SurfaceError;

    const NX: usize = 4;
    const NY: usize = 3;
    const OFFSET: usize = 4096;

    /// Raw samples of the two channels in FILE order (row 0 = bottom line), scaled to use the
    /// integer width; the first Height sample is saturated.
    fn raw_samples(bpp: usize) -> (Vec<i64>, Vec<i64>) {
        let widen = if bpp == 2 { 1 } else { 65536 + 7 };
        let n = (NX * NY) as i64;
        let mut height: Vec<i64> = (0..n).map(|k| (k * 1000 - 5000) * widen).collect();
        height[0] = if bpp == 2 { 32767 } else { i32::MAX as i64 };
        let zsensor = (0..n).map(|k| (3000 - k * 700) * widen).collect();
        (height, zsensor)
    }

    /// A two-channel NanoScope file written line by line from the documented layout, with soft
    /// scale names the encoder does not use, one in each of the two sections they may live in.
    fn byte_built_file(bpp: usize, data_length_override: Option<usize>) -> Vec<u8> {
        let length = NX * NY * bpp;
        let range = 2f64.powi(8 * bpp as i32);
        let mut lines = vec![
            "\\*File list".to_string(),
            "\\Version: 0x05300001".into(),
            format!("\\Data length: {OFFSET}"),
            "\\*Equipment list".into(),
            "\\Description: D3100".into(),
            "\\*Scanner list".into(),
            "\\@Sens. Zscan: V 0.0123 ~m/V".into(),
            "\\*Ciao scan list".into(),
            "\\Scan size: 2 2 ~m".into(),
            "\\@Sens. ZSensor: V 9.5 nm/V".into(),
            // Channel 1: [Height], Scan Size from the scan list, bracketed V/LSB 1 % off.
            "\\*Ciao image list".into(),
            format!("\\Data offset: {OFFSET}"),
            format!("\\Data length: {}", data_length_override.unwrap_or(length)),
            format!("\\Samps/line: {NX}"),
            format!("\\Number of lines: {NY}"),
            "\\@2:Image Data: S [Height] \"Height\"".into(),
            format!(
                "\\@2:Z scale: V [Sens. Zscan] ({:e} V/LSB) 440 V",
                1.01 * 440.0 / range
            ),
            // Channel 2: [ZSensor].
            "\\*Ciao image list".into(),
            format!("\\Data offset: {}", OFFSET + length),
            format!("\\Data length: {length}"),
            format!("\\Samps/line: {NX}"),
            format!("\\Number of lines: {NY}"),
            "\\Scan Size: 2 2 ~m".into(),
            "\\@2:Image Data: S [ZSensor] \"Height Sensor\"".into(),
            format!(
                "\\@2:Z scale: V [Sens. ZSensor] ({:e} V/LSB) 3.5 V",
                3.5 / range
            ),
            "\\*File list end".into(),
        ];
        // Bytes/pixel is 2 by default: state it only for int32 files.
        if bpp == 4 {
            lines.insert(13, "\\Bytes/pixel: 4".into());
            lines.insert(21, "\\Bytes/pixel: 4".into());
        }
        let mut file = Vec::new();
        for line in lines {
            file.extend_from_slice(line.as_bytes());
            file.extend_from_slice(b"\r\n");
        }
        assert!(file.len() < OFFSET);
        file.resize(OFFSET, 0);
        let (height, zsensor) = raw_samples(bpp);
        for raw in height.iter().chain(&zsensor) {
            if bpp == 2 {
                file.extend_from_slice(&(*raw as i16).to_le_bytes());
            } else {
                file.extend_from_slice(&(*raw as i32).to_le_bytes());
            }
        }
        file
    }

    #[test]
    fn byte_built_file_int16_and_int32() {
        for bpp in [2, 4] {
            let (_dir, path) = write_temp("scan.spm", &byte_built_file(bpp, None));
            let range = 2f64.powi(8 * bpp as i32);
            let (height_raw, zsensor_raw) = raw_samples(bpp);

            // Default: the ZSensor channel, listed second.
            let map = read_height_map(&path, &ReadOptions::default()).unwrap();
            assert_eq!(map.channel, "Height Sensor");
            assert_eq!(map.source.format, "nanoscope");
            assert_eq!(map.z.dim(), (NY, NX));
            assert!(close(map.dx, 2e-6 / 4.0, 1e-15) && close(map.dy, 2e-6 / 3.0, 1e-15));
            assert!(map.valid.is_none());
            assert!(!map.source.header.contains_key("warning"));
            for r in 0..NY {
                for c in 0..NX {
                    // File row r (bottom first) is map row NY−1−r.
                    let want = zsensor_raw[r * NX + c] as f64 * 3.5 / range * 9.5e-9;
                    let got = map.z[[NY - 1 - r, c]];
                    assert!(
                        close(got, want, 1e-14),
                        "bpp {bpp} z[{r},{c}] {got} vs {want}"
                    );
                }
            }

            let opts = ReadOptions {
                channel: Some("height".into()),
                ..Default::default()
            };
            let map = read_height_map(&path, &opts).unwrap();
            assert_eq!(map.channel, "Height");
            assert!(map.source.header["warning"].contains("disagrees"));
            assert!(close(map.dx, 0.5e-6, 1e-15));
            // The saturated first sample (bottom-left) is invalid.
            assert!(!map.is_valid(NY - 1, 0) && map.z[[NY - 1, 0]] == 0.0);
            assert_eq!(map.masked_fraction(), 1.0 / 12.0);
            for r in 0..NY {
                for c in 0..NX {
                    if r == 0 && c == 0 {
                        continue;
                    }
                    let want = height_raw[r * NX + c] as f64 * 440.0 / range * 0.0123e-6;
                    let got = map.z[[NY - 1 - r, c]];
                    assert!(
                        close(got, want, 1e-14),
                        "bpp {bpp} z[{r},{c}] {got} vs {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn round_trip_int16_and_int32() {
        for bpp in [2, 4] {
            let mut map = sample_map(64, 48, 2.5e-9, 7.0e-9);
            let mut valid = ndarray::Array2::from_elem((48, 64), true);
            valid[[40, 3]] = false;
            map.z[[40, 3]] = 0.0;
            map.valid = Some(valid);
            let bytes = encode_nanoscope(&map, bpp);
            assert!(bytes.starts_with(b"\\*File list\r\n\\Version: 0x09200000\r\n"));
            assert_eq!(bytes.len(), 8192 + 64 * 48 * bpp);
            let back = read_bytes("m.spm", &bytes).unwrap();
            let max_abs = map.z.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let step = 2.1 * max_abs / 2f64.powi(8 * bpp as i32);
            assert_same_map(&back, &map, 1e-14, 0.0, 0.5 * step * (1.0 + 1e-9));
            assert_eq!(back.channel, "Height Sensor");
            assert!(!back.is_valid(40, 3) && back.is_valid(40, 4));
            assert!(!back.source.header.contains_key("warning"));
        }
    }

    #[test]
    fn bad_files_give_clear_errors() {
        let good = byte_built_file(2, None);
        let msg = read_bytes("cut.spm", &good[..good.len() - 10])
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("cut.spm: truncated NanoScope file") && msg.contains("needs"),
            "{msg}"
        );

        let short = byte_built_file(2, Some(10));
        let opts = ReadOptions {
            channel: Some("Height".into()),
            ..Default::default()
        };
        let (_dir, path) = write_temp("short.spm", &short);
        let msg = read_height_map(&path, &opts).unwrap_err().to_string();
        assert!(msg.contains("Data length: 10"), "{msg}");

        let mut old = good.clone();
        old[..35].copy_from_slice(b"\\*File list\r\n\\Version: 0x04220000\r\n");
        let err = read_bytes("old.spm", &old).unwrap_err();
        assert!(
            matches!(err, SurfaceError::Unsupported { .. })
                && err.to_string().contains("0x04220000"),
            "{err}"
        );

        let mut ascii = good.clone();
        ascii[0] = b'?';
        let err = read_bytes("ascii.spm", &ascii).unwrap_err();
        assert!(matches!(err, SurfaceError::Unsupported { .. }), "{err}");
    }

    #[test]
    fn hostile_files_are_errors_not_panics() {
        assert!(fuzz_reader("f.spm", &byte_built_file(4, None)) > 0);
        assert!(
            fuzz_reader(
                "g.spm",
                &encode_nanoscope(&sample_map(16, 12, 1e-9, 2e-9), 2)
            ) > 0
        );
    }
}
