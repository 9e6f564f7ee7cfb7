//! Gwyddion native `.gwy` (Gwyddion 2.x, magic `GWYP`).
//!
//! The serialised object tree is walked lazily over borrowed byte slices: nothing is copied
//! except the chosen channel's data, and every size and count is checked against the bytes
//! that remain, so hostile sizes end in an error rather than a huge allocation. Nested objects
//! are skipped by their size, not by recursion.
//!
//! Masks (`/N/mask`) are noted in the header but not applied: Gwyddion masks often mark grains
//! rather than bad data.
use super::units::length_factor;
use super::{find_channel, format_error, heights_with_nan, unsupported, RawMap, ReadOptions};
use crate::surface::{HeightMap, Result, SurfaceError};
use ndarray::Array2;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// A cursor over the file bytes; positions are absolute file offsets, for error messages.
struct Cursor<'a> {
    buf: &'a [u8],
    pos: usize,
    end: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize) -> std::result::Result<&'a [u8], String> {
        match self.pos.checked_add(n) {
            Some(stop) if stop <= self.end => {
                let bytes = &self.buf[self.pos..stop];
                self.pos = stop;
                Ok(bytes)
            }
            _ => Err(format!(
                "needs {n} bytes at offset {} but only {} remain in the enclosing object",
                self.pos,
                self.end - self.pos
            )),
        }
    }

    fn array<const N: usize>(&mut self) -> std::result::Result<[u8; N], String> {
        let bytes = self.take(N)?;
        let mut out = [0u8; N];
        out.copy_from_slice(bytes);
        Ok(out)
    }

    fn count(&mut self) -> std::result::Result<usize, String> {
        Ok(u32::from_le_bytes(self.array()?) as usize)
    }

    /// A NUL-terminated string (without the NUL).
    fn cstr(&mut self) -> std::result::Result<&'a [u8], String> {
        let rest = &self.buf[self.pos..self.end];
        let len = rest
            .iter()
            .position(|&b| b == 0)
            .ok_or_else(|| format!("unterminated string at offset {}", self.pos))?;
        self.pos += len + 1;
        Ok(&rest[..len])
    }

    /// `name\0`, `u32` size, then `size` bytes of components.
    fn object(&mut self) -> std::result::Result<GwyObject<'a>, String> {
        let name = self.cstr()?;
        let size = self.count()?;
        let start = self.pos;
        self.take(size)
            .map_err(|e| format!("object `{}` of {size} bytes: {e}", lossy(name)))?;
        Ok(GwyObject {
            name,
            buf: self.buf,
            start,
            end: start + size,
        })
    }
}

fn lossy(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A serialised object whose components are parsed on demand.
#[derive(Clone, Copy)]
struct GwyObject<'a> {
    name: &'a [u8],
    buf: &'a [u8],
    start: usize,
    end: usize,
}

enum Value<'a> {
    Int(i64),
    Double(f64),
    Str(&'a [u8]),
    Object(GwyObject<'a>),
    /// Raw little-endian bytes of a `D` array.
    Doubles(&'a [u8]),
    /// Anything this reader does not use (bools, other arrays...).
    Other,
}

impl<'a> GwyObject<'a> {
    fn components(&self) -> Components<'a> {
        Components {
            cursor: Cursor {
                buf: self.buf,
                pos: self.start,
                end: self.end,
            },
            failed: false,
        }
    }
}

struct Components<'a> {
    cursor: Cursor<'a>,
    failed: bool,
}

impl<'a> Iterator for Components<'a> {
    type Item = std::result::Result<(&'a [u8], Value<'a>), String>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed || self.cursor.pos >= self.cursor.end {
            return None;
        }
        let item = self.component();
        self.failed = item.is_err();
        Some(item)
    }
}

impl<'a> Components<'a> {
    fn component(&mut self) -> std::result::Result<(&'a [u8], Value<'a>), String> {
        let c = &mut self.cursor;
        let name = c.cstr()?;
        let kind = c.take(1)?[0];
        let value = (|| -> std::result::Result<Value<'a>, String> {
            Ok(match kind {
                b'b' => {
                    c.take(1)?;
                    Value::Other
                }
                // A one-character string (the `gwyfile` package writes short titles so).
                b'c' => Value::Str(c.take(1)?),
                b'i' => Value::Int(i32::from_le_bytes(c.array()?) as i64),
                b'q' => Value::Int(i64::from_le_bytes(c.array()?)),
                b'd' => Value::Double(f64::from_le_bytes(c.array()?)),
                b's' => Value::Str(c.cstr()?),
                b'o' => Value::Object(c.object()?),
                b'C' | b'I' | b'Q' | b'D' => {
                    let width = match kind {
                        b'C' => 1,
                        b'I' => 4,
                        _ => 8,
                    };
                    let count = c.count()?;
                    let bytes = c.take(count.checked_mul(width).ok_or("array too large")?)?;
                    if kind == b'D' {
                        Value::Doubles(bytes)
                    } else {
                        Value::Other
                    }
                }
                // Each element consumes at least one byte, so these loops end with the data.
                b'S' => {
                    for _ in 0..c.count()? {
                        c.cstr()?;
                    }
                    Value::Other
                }
                b'O' => {
                    for _ in 0..c.count()? {
                        c.object()?;
                    }
                    Value::Other
                }
                other => return Err(format!("unknown component type byte 0x{other:02x}")),
            })
        })()
        .map_err(|e| format!("component `{}`: {e}", lossy(name)))?;
        Ok((name, value))
    }
}

/// One `/N/data` channel with its metadata; the data stay as borrowed bytes.
struct Channel<'a> {
    number: u32,
    title: String,
    xres: usize,
    yres: usize,
    xreal: f64,
    yreal: f64,
    xoff: f64,
    yoff: f64,
    xy_unit: String,
    z_unit: String,
    /// Metres per z unit when z is a length (an empty z unit counts as metres when xy is).
    z_factor: Option<f64>,
    data: &'a [u8],
}

/// `N` if `key` is `/N<suffix>` with N decimal digits (channel numbers can exceed 9).
fn channel_number(key: &str, suffix: &str) -> Option<u32> {
    let digits = key.strip_prefix('/')?.strip_suffix(suffix)?;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok()
}

fn unit_string(unit: GwyObject) -> std::result::Result<String, String> {
    for component in unit.components() {
        if let (b"unitstr", Value::Str(s)) = component? {
            return Ok(lossy(s));
        }
    }
    Ok(String::new())
}

fn parse_field<'a>(
    number: u32,
    title: String,
    field: GwyObject<'a>,
) -> std::result::Result<Channel<'a>, String> {
    if field.name != b"GwyDataField" {
        return Err(format!(
            "is a `{}`, expected GwyDataField",
            lossy(field.name)
        ));
    }
    let (mut xres, mut yres, mut xreal, mut yreal) = (None, None, None, None);
    let (mut xoff, mut yoff) = (0.0, 0.0);
    let (mut xy_unit, mut z_unit, mut data) = (None, None, None);
    for component in field.components() {
        match component? {
            (b"xres", Value::Int(v)) => xres = Some(v),
            (b"yres", Value::Int(v)) => yres = Some(v),
            (b"xreal", Value::Double(v)) => xreal = Some(v),
            (b"yreal", Value::Double(v)) => yreal = Some(v),
            (b"xoff", Value::Double(v)) => xoff = v,
            (b"yoff", Value::Double(v)) => yoff = v,
            (b"si_unit_xy", Value::Object(o)) => xy_unit = Some(unit_string(o)?),
            (b"si_unit_z", Value::Object(o)) => z_unit = Some(unit_string(o)?),
            (b"data", Value::Doubles(d)) => data = Some(d),
            _ => {}
        }
    }
    let positive = |name: &str, v: Option<i64>| -> std::result::Result<usize, String> {
        v.filter(|&v| v > 0)
            .and_then(|v| usize::try_from(v).ok())
            .ok_or_else(|| format!("{name} missing or not positive"))
    };
    let (xres, yres) = (positive("xres", xres)?, positive("yres", yres)?);
    let length = |name: &str, v: Option<f64>| -> std::result::Result<f64, String> {
        v.filter(|v| v.is_finite() && *v > 0.0)
            .ok_or_else(|| format!("{name} missing or not a positive number"))
    };
    let (xreal, yreal) = (length("xreal", xreal)?, length("yreal", yreal)?);
    let data = data.ok_or("no `data` array")?;
    let expected = xres.checked_mul(yres).and_then(|n| n.checked_mul(8));
    if expected != Some(data.len()) {
        return Err(format!(
            "data has {} values but xres×yres = {xres}×{yres}",
            data.len() / 8
        ));
    }
    let xy_unit = xy_unit.unwrap_or_default();
    let z_unit = z_unit.unwrap_or_default();
    let xy_is_length = length_factor(&xy_unit).is_some();
    let z_factor = match length_factor(&z_unit) {
        Some(f) => Some(f),
        None if z_unit.is_empty() && xy_is_length => Some(1.0),
        None => None,
    };
    Ok(Channel {
        number,
        title,
        xres,
        yres,
        xreal,
        yreal,
        xoff: if xoff.is_finite() { xoff } else { 0.0 },
        yoff: if yoff.is_finite() { yoff } else { 0.0 },
        xy_unit,
        z_unit,
        z_factor,
        data,
    })
}

/// One channel of a `.gwy` file as heights in metres.
pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let container = walk_container(path, bytes)?;
    let channels = parse_channels(path, container.fields, container.titles)?;
    let listing = channels
        .iter()
        .map(|c| format!("{}: {} [{}]", c.number, c.title, c.z_unit))
        .collect::<Vec<_>>()
        .join("; ");
    let channel = &channels[select_channel(path, &channels, &listing, opts)?];
    let units = length_units(path, channel)?;
    let z = decode_heights(path, channel, units.z_factor)?;

    let mut header = BTreeMap::new();
    if let Some(warning) = units.warning {
        header.insert("warning".into(), warning.into());
    }
    header.insert("channels".into(), listing);
    header.insert("channel_number".into(), channel.number.to_string());
    header.insert("xres".into(), channel.xres.to_string());
    header.insert("yres".into(), channel.yres.to_string());
    header.insert(
        "xreal".into(),
        format!("{:e} {}", channel.xreal, channel.xy_unit),
    );
    header.insert(
        "yreal".into(),
        format!("{:e} {}", channel.yreal, channel.xy_unit),
    );
    header.insert("z_unit".into(), channel.z_unit.clone());
    if container.masks.contains(&channel.number) {
        header.insert(
            "mask".into(),
            format!("/{}/mask present (not applied)", channel.number),
        );
    }
    let xy_factor = units.xy_factor;
    Ok(RawMap {
        z,
        dx: channel.xreal * xy_factor / channel.xres as f64,
        dy: channel.yreal * xy_factor / channel.yres as f64,
        x0: channel.xoff * xy_factor,
        y0: channel.yoff * xy_factor,
        channel: channel.title.clone(),
        format: "gwy",
        header,
    })
}

/// A structural error found while walking the object tree.
fn malformed(path: &Path, e: String) -> SurfaceError {
    format_error(path, format!("truncated or malformed GWY file: {e}"))
}

/// What the top-level `GwyContainer` holds, keyed by channel number.
struct Container<'a> {
    /// `/N/data` objects, not yet parsed.
    fields: BTreeMap<u32, GwyObject<'a>>,
    /// `/N/data/title` strings.
    titles: BTreeMap<u32, String>,
    /// Channels with a `/N/mask`.
    masks: BTreeSet<u32>,
}

/// The top-level container's channel entries; Gwyddion 1.x files are refused.
fn walk_container<'a>(path: &Path, bytes: &'a [u8]) -> Result<Container<'a>> {
    if bytes.starts_with(b"GWYO") {
        return Err(unsupported(
            path,
            "Gwyddion 1.x file (magic GWYO); re-save it with Gwyddion 2",
        ));
    }
    if !bytes.starts_with(b"GWYP") {
        return Err(format_error(
            path,
            "no Gwyddion 2 magic `GWYP` at the start",
        ));
    }
    let mut cursor = Cursor {
        buf: bytes,
        pos: 4,
        end: bytes.len(),
    };
    let top = cursor.object().map_err(|e| malformed(path, e))?;
    if top.name != b"GwyContainer" {
        return Err(malformed(
            path,
            format!(
                "top-level object is `{}`, expected GwyContainer",
                lossy(top.name)
            ),
        ));
    }
    let mut container = Container {
        fields: BTreeMap::new(),
        titles: BTreeMap::new(),
        masks: BTreeSet::new(),
    };
    for component in top.components() {
        let (key, value) = component.map_err(|e| malformed(path, e))?;
        let Ok(key) = std::str::from_utf8(key) else {
            continue;
        };
        match value {
            Value::Object(o) => {
                if let Some(n) = channel_number(key, "/data") {
                    container.fields.insert(n, o);
                } else if let Some(n) = channel_number(key, "/mask") {
                    container.masks.insert(n);
                }
            }
            Value::Str(s) => {
                if let Some(n) = channel_number(key, "/data/title") {
                    container.titles.insert(n, lossy(s));
                }
            }
            _ => {}
        }
    }
    Ok(container)
}

/// Every `/N/data` field parsed, in channel-number order; at least one is required.
fn parse_channels<'a>(
    path: &Path,
    fields: BTreeMap<u32, GwyObject<'a>>,
    mut titles: BTreeMap<u32, String>,
) -> Result<Vec<Channel<'a>>> {
    let mut channels = Vec::new();
    for (number, field) in fields {
        let title = titles.remove(&number).unwrap_or_default();
        let channel = parse_field(number, title, field)
            .map_err(|e| malformed(path, format!("channel /{number}/data: {e}")))?;
        channels.push(channel);
    }
    if channels.is_empty() {
        return Err(format_error(path, "GWY file has no data channel (/N/data)"));
    }
    Ok(channels)
}

/// Index of the requested channel (by number or title), else the first height-like titled
/// channel with a length z unit, else the first with a length z unit.
fn select_channel(
    path: &Path,
    channels: &[Channel],
    listing: &str,
    opts: &ReadOptions,
) -> Result<usize> {
    match &opts.channel {
        Some(wanted) => {
            let by_number = wanted
                .trim()
                .parse::<u32>()
                .ok()
                .and_then(|n| channels.iter().position(|c| c.number == n));
            let titles: Vec<Vec<String>> = channels.iter().map(|c| vec![c.title.clone()]).collect();
            by_number
                .or_else(|| find_channel(wanted, &titles))
                .ok_or_else(|| {
                    format_error(path, format!("no channel `{wanted}`; channels: {listing}"))
                })
        }
        None => {
            let is_height = |c: &Channel| {
                let t = c.title.to_lowercase();
                ["height", "topo", "zsensor"].iter().any(|k| t.contains(k))
            };
            let lengths = || {
                channels
                    .iter()
                    .enumerate()
                    .filter(|(_, c)| c.z_factor.is_some())
            };
            lengths()
                .find(|(_, c)| is_height(c))
                .or_else(|| lengths().next())
                .map(|(k, _)| k)
                .ok_or_else(|| {
                    format_error(
                        path,
                        format!("no channel with heights (a length z unit); channels: {listing}"),
                    )
                })
        }
    }
}

/// Metres per unit of the chosen channel.
struct LengthUnits {
    z_factor: f64,
    /// 1 when the lateral unit is missing (then `warning` says so).
    xy_factor: f64,
    warning: Option<&'static str>,
}

/// z must be a length; a missing lateral or z unit is taken as metres, with a warning.
fn length_units(path: &Path, channel: &Channel) -> Result<LengthUnits> {
    let z_factor = channel.z_factor.ok_or_else(|| {
        format_error(
            path,
            format!(
                "channel {} `{}` has z unit `{}`, not a length",
                channel.number, channel.title, channel.z_unit
            ),
        )
    })?;
    let xy_factor = length_factor(&channel.xy_unit);
    if xy_factor.is_none() && !channel.xy_unit.is_empty() {
        return Err(format_error(
            path,
            format!(
                "channel {} has lateral unit `{}`, not a length",
                channel.number, channel.xy_unit
            ),
        ));
    }
    let warning = if xy_factor.is_none() {
        Some("no lateral unit; xreal/yreal taken as metres")
    } else if channel.z_unit.is_empty() {
        Some("no z unit; heights taken as metres")
    } else {
        None
    };
    Ok(LengthUnits {
        z_factor,
        xy_factor: xy_factor.unwrap_or(1.0),
        warning,
    })
}

/// The channel's little-endian doubles × `z_factor`, `yres` rows of `xres`, in file order.
fn decode_heights(path: &Path, channel: &Channel, z_factor: f64) -> Result<Array2<f64>> {
    let values: Vec<f64> = channel
        .data
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]) * z_factor)
        .collect();
    Array2::from_shape_vec((channel.yres, channel.xres), values)
        .map_err(|e| format_error(path, format!("GWY data shape: {e}")))
}

/// Serialisation helpers for the writer.
fn put_component(out: &mut Vec<u8>, name: &str, kind: u8, value: &[u8]) {
    out.extend_from_slice(name.as_bytes());
    out.push(0);
    out.push(kind);
    out.extend_from_slice(value);
}

fn serialise_object(name: &str, components: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(name.len() + 5 + components.len());
    out.extend_from_slice(name.as_bytes());
    out.push(0);
    out.extend_from_slice(&(components.len() as u32).to_le_bytes());
    out.extend_from_slice(components);
    out
}

fn si_unit(unit: &str) -> Vec<u8> {
    let mut c = Vec::new();
    put_component(&mut c, "unitstr", b's', format!("{unit}\0").as_bytes());
    serialise_object("GwySIUnit", &c)
}

fn data_field(map: &HeightMap, values: impl ExactSizeIterator<Item = f64>) -> Vec<u8> {
    let (xreal, yreal) = map.size();
    let mut c = Vec::new();
    put_component(&mut c, "xres", b'i', &(map.nx() as i32).to_le_bytes());
    put_component(&mut c, "yres", b'i', &(map.ny() as i32).to_le_bytes());
    put_component(&mut c, "xreal", b'd', &xreal.to_le_bytes());
    put_component(&mut c, "yreal", b'd', &yreal.to_le_bytes());
    put_component(&mut c, "xoff", b'd', &map.x0.to_le_bytes());
    put_component(&mut c, "yoff", b'd', &map.y0.to_le_bytes());
    put_component(&mut c, "si_unit_xy", b'o', &si_unit("m"));
    put_component(&mut c, "si_unit_z", b'o', &si_unit("m"));
    let mut data = (values.len() as u32).to_le_bytes().to_vec();
    for v in values {
        data.extend_from_slice(&v.to_le_bytes());
    }
    put_component(&mut c, "data", b'D', &data);
    serialise_object("GwyDataField", &c)
}

/// Encode as Gwyddion native `.gwy` (one channel, `/0/data`, units m). Invalid pixels are
/// written as 0 and marked in `/0/mask` (Gwyddion's convention for bad data; this reader
/// notes but does not apply masks).
pub fn encode_gwy(map: &HeightMap) -> Vec<u8> {
    let mut c = Vec::new();
    let heights = heights_with_nan(map);
    put_component(
        &mut c,
        "/0/data",
        b'o',
        &data_field(
            map,
            heights.iter().map(|v| if v.is_finite() { *v } else { 0.0 }),
        ),
    );
    let title = map.channel.replace('\0', " ");
    put_component(
        &mut c,
        "/0/data/title",
        b's',
        format!("{title}\0").as_bytes(),
    );
    if heights.iter().any(|v| !v.is_finite()) {
        let marks = heights
            .iter()
            .map(|v| if v.is_finite() { 0.0 } else { 1.0 });
        put_component(&mut c, "/0/mask", b'o', &data_field(map, marks));
    }
    let mut out = b"GWYP".to_vec();
    out.extend_from_slice(&serialise_object("GwyContainer", &c));
    out
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};
    use super::encode_gwy;

    // Independent byte-level builders (not the encoder's helpers).
    fn cstr(out: &mut Vec<u8>, s: &str) {
        out.extend_from_slice(s.as_bytes());
        out.push(0);
    }
    fn object(name: &str, body: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        cstr(&mut out, name);
        out.extend_from_slice(&u32::try_from(body.len()).unwrap().to_le_bytes());
        out.extend_from_slice(body);
        out
    }
    fn unit(s: &str) -> Vec<u8> {
        let mut body = Vec::new();
        cstr(&mut body, "unitstr");
        body.push(b's');
        cstr(&mut body, s);
        object("GwySIUnit", &body)
    }
    fn field(xres: i32, yres: i32, xreal: f64, yreal: f64, z_unit: &str, data: &[f64]) -> Vec<u8> {
        let mut b = Vec::new();
        cstr(&mut b, "xres");
        b.push(b'i');
        b.extend_from_slice(&xres.to_le_bytes());
        cstr(&mut b, "yres");
        b.push(b'i');
        b.extend_from_slice(&yres.to_le_bytes());
        cstr(&mut b, "xreal");
        b.push(b'd');
        b.extend_from_slice(&xreal.to_le_bytes());
        cstr(&mut b, "yreal");
        b.push(b'd');
        b.extend_from_slice(&yreal.to_le_bytes());
        cstr(&mut b, "si_unit_xy");
        b.push(b'o');
        b.extend_from_slice(&unit("m"));
        cstr(&mut b, "si_unit_z");
        b.push(b'o');
        b.extend_from_slice(&unit(z_unit));
        cstr(&mut b, "data");
        b.push(b'D');
        b.extend_from_slice(&(data.len() as u32).to_le_bytes());
        for v in data {
            b.extend_from_slice(&v.to_le_bytes());
        }
        object("GwyDataField", &b)
    }

    /// Channel 0 "Phase" in degrees, channel 12 "Height" in nm, plus components the reader
    /// must skip (bool, char, i64, string/int/object arrays).
    fn two_channel_file() -> Vec<u8> {
        let phase: Vec<f64> = (0..20).map(|k| k as f64).collect();
        let height: Vec<f64> = (0..20).map(|k| 0.5 * k as f64 - 3.0).collect();
        let mut body = Vec::new();
        cstr(&mut body, "/0/data");
        body.push(b'o');
        body.extend_from_slice(&field(5, 4, 2e-6, 1e-6, "deg", &phase));
        cstr(&mut body, "/0/data/title");
        body.push(b's');
        cstr(&mut body, "Phase");
        cstr(&mut body, "/0/data/visible");
        body.push(b'b');
        body.push(1);
        cstr(&mut body, "/0/base/range-type");
        body.push(b'c');
        body.push(b'x');
        cstr(&mut body, "/12/data/title");
        body.push(b's');
        cstr(&mut body, "Height");
        cstr(&mut body, "/12/meta/ticks");
        body.push(b'q');
        body.extend_from_slice(&(-5i64).to_le_bytes());
        cstr(&mut body, "/12/meta/names");
        body.push(b'S');
        body.extend_from_slice(&2u32.to_le_bytes());
        cstr(&mut body, "a");
        cstr(&mut body, "bc");
        cstr(&mut body, "/12/meta/ints");
        body.push(b'I');
        body.extend_from_slice(&2u32.to_le_bytes());
        body.extend_from_slice(&[1, 0, 0, 0, 2, 0, 0, 0]);
        cstr(&mut body, "/12/select/list");
        body.push(b'O');
        body.extend_from_slice(&2u32.to_le_bytes());
        body.extend_from_slice(&unit("V"));
        body.extend_from_slice(&unit("s"));
        cstr(&mut body, "/12/data");
        body.push(b'o');
        body.extend_from_slice(&field(5, 4, 2e-6, 1e-6, "nm", &height));
        let mut file = b"GWYP".to_vec();
        file.extend_from_slice(&object("GwyContainer", &body));
        file
    }

    #[test]
    fn byte_built_file_default_and_named_channels() {
        let bytes = two_channel_file();
        let (_dir, path) = write_temp("two.gwy", &bytes);
        let map = read_height_map(&path, &ReadOptions::default()).unwrap();
        assert_eq!(map.channel, "Height");
        assert_eq!(map.source.format, "gwy");
        assert_eq!(map.source.header["channel_number"], "12");
        assert_eq!(map.z.dim(), (4, 5));
        assert!(close(map.dx, 0.4e-6, 1e-15) && close(map.dy, 0.25e-6, 1e-15));
        // Row-major, row 0 first: z[[j, i]] = (0.5 (5j + i) − 3) nm.
        for ((j, i), &z) in map.z.indexed_iter() {
            let want = (0.5 * (5 * j + i) as f64 - 3.0) * 1e-9;
            assert!(close(z, want, 1e-15), "z[[{j},{i}]] = {z}");
        }
        let by_number = ReadOptions {
            channel: Some("12".into()),
            ..Default::default()
        };
        assert_eq!(
            read_height_map(&path, &by_number).unwrap().channel,
            "Height"
        );
        let phase = ReadOptions {
            channel: Some("phase".into()),
            ..Default::default()
        };
        let msg = read_height_map(&path, &phase).unwrap_err().to_string();
        assert!(msg.contains("deg") && msg.contains("not a length"), "{msg}");
        let absent = ReadOptions {
            channel: Some("amplitude".into()),
            ..Default::default()
        };
        let msg = read_height_map(&path, &absent).unwrap_err().to_string();
        assert!(msg.contains("0: Phase [deg]; 12: Height [nm]"), "{msg}");
    }

    #[test]
    fn round_trip() {
        let mut map = sample_map(64, 48, 2.5e-9, 7.0e-9);
        map.x0 = 1e-6;
        map.y0 = 2e-6;
        let back = read_bytes("m.gwy", &encode_gwy(&map)).unwrap();
        assert_same_map(&back, &map, 1e-15, 1e-15, 0.0);
        assert_eq!(back.z, map.z);
        assert_eq!((back.x0, back.y0), (1e-6, 2e-6));
        assert_eq!(back.channel, "Height");
        assert!(!back.source.header.contains_key("mask"));

        let mut valid = ndarray::Array2::from_elem((48, 64), true);
        valid[[3, 4]] = false;
        map.valid = Some(valid);
        let back = read_bytes("m.gwy", &encode_gwy(&map)).unwrap();
        assert!(back.source.header["mask"].contains("not applied"));
    }

    /// A file written by the independent MIT `gwyfile` Python package
    /// (`testdata/make_gwyfile_fixture.py`).
    #[test]
    fn reads_file_from_independent_writer() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("src/surface/io/testdata/gwyfile_writer.gwy");
        let map = read_height_map(&path, &ReadOptions::default()).unwrap();
        assert_eq!(map.channel, "Topography");
        assert_eq!(map.source.header["channel_number"], "3");
        assert_eq!(map.z.dim(), (29, 37));
        assert!(close(map.dx, 2e-6 / 37.0, 1e-15) && close(map.dy, 1.5e-6 / 29.0, 1e-15));
        assert_eq!((map.x0, map.y0), (1e-7, -2e-7));
        for ((j, i), &z) in map.z.indexed_iter() {
            let want = (0.25 * i as f64 - 0.5 * j as f64 + ((i * j) % 7) as f64) * 1e-9;
            assert_eq!(z, want, "z[[{j}, {i}]]");
        }
    }

    #[test]
    fn hostile_files_are_errors_not_panics() {
        let bytes = two_channel_file();
        assert!(fuzz_reader("f.gwy", &bytes) > 0);
        assert!(fuzz_reader("g.gwy", &encode_gwy(&sample_map(8, 6, 1e-9, 1e-9))) > 0);
        // A data array claiming 2^32−1 doubles.
        let mut huge = bytes.clone();
        let at = huge.windows(6).rposition(|w| w == b"data\0D").unwrap() + 6;
        huge[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        let msg = read_bytes("huge.gwy", &huge).unwrap_err().to_string();
        assert!(msg.contains("malformed GWY"), "{msg}");
        let msg = read_bytes("old.gwy", b"GWYOGwyContainer\0")
            .unwrap_err()
            .to_string();
        assert!(msg.contains("Gwyddion 1.x"), "{msg}");
    }
}
