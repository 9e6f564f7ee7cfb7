//! Zygo `.datx` (Mx export, HDF5) height maps (docs/surfaces.md), following the layout the
//! public readers describe (SurfaceTopography's `IO/DATX.py`, prysm's `read_zygo_datx`):
//!
//! * `/MetaData`: a compound dataset of (`Source`, `Link`, `Destination`) strings, read as a
//!   table `Source → Link → Destination`; a destination `{…}` names a further node. From
//!   `Root` → `Measurement` → `Surface` → `Path` comes the HDF5 path of the height dataset
//!   (typically `/Data/Surface/{GUID}`), likewise `Intensity` → `Path`.
//! * The dataset: 2-D numbers, rows = y, with the attributes `No Data` (pixels equal to it are
//!   invalid), `Unit` (height unit, e.g. `nm`) and `X/Y/Z Converter`: one-element compounds
//!   (`Category`, `BaseUnit`, `HWUnit`, `Parameters`) where `Parameters[1]` of the
//!   `LateralCat` X/Y converters is the pixel spacing in metres and the `HeightCat` Z
//!   converter's `BaseUnit` names the height unit (`NanoMeters`, …).
//! * Instrument serial number and type in attributes whose names end with
//!   `System Serial Number` / `System Type` (under `/Attributes`).
//!
//! Strings may be variable-length or fixed-length (ASCII or UTF-8) and `Parameters` a
//! variable-length or fixed-size float64 array: compound fields are read by name (HDF5
//! converts a compound to a subset of its fields), trying each string encoding in turn.
use super::{find_channel, format_error, units, unsupported, RawMap, ReadOptions};
use crate::formats::isolated;
use crate::surface::{Result, SurfaceError};
use hdf5::types::{
    FixedAscii, FixedUnicode, TypeDescriptor, VarLenArray, VarLenAscii, VarLenUnicode,
};
use hdf5::H5Type;
use ndarray::Array2;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// The HDF5 superblock signature at offset 0.
pub(crate) const MAGIC: &[u8; 8] = b"\x89HDF\r\n\x1a\n";
/// Deflate compresses at most ~1032:1, so more stored values than this many per byte of file
/// cannot be real data: refuse before allocating (a tiny file may declare a huge dataset).
const MAX_VALUES_PER_FILE_BYTE: usize = 1100;
/// Attributes read here hold one element; a corrupt element count must not size an allocation.
const MAX_ATTRIBUTE_ELEMENTS: usize = 64;
/// Bytes one `/MetaData` row takes in the file at least (three 16-byte vlen references, or
/// three fixed strings of at least 1 byte each; 3 is the safe bound).
const MIN_META_ROW_BYTES: usize = 3;
/// Objects visited under `/Attributes` when looking for the instrument attributes.
const MAX_ATTRIBUTE_OBJECTS: usize = 2000;

#[derive(H5Type)]
#[repr(C)]
struct MetaRow<S: H5Type> {
    #[hdf5(rename = "Source")]
    source: S,
    #[hdf5(rename = "Link")]
    link: S,
    #[hdf5(rename = "Destination")]
    destination: S,
}

#[derive(H5Type)]
#[repr(C)]
struct ConvNames<S: H5Type> {
    #[hdf5(rename = "Category")]
    category: S,
    #[hdf5(rename = "BaseUnit")]
    base_unit: S,
}

#[derive(H5Type)]
#[repr(C)]
struct ConvParams<P: H5Type> {
    #[hdf5(rename = "Parameters")]
    parameters: P,
}

/// The string types HDF5 files use, as text.
trait Text: H5Type {
    fn text(&self) -> String;
}
impl Text for VarLenUnicode {
    fn text(&self) -> String {
        self.as_str().to_string()
    }
}
impl Text for VarLenAscii {
    fn text(&self) -> String {
        self.as_str().to_string()
    }
}
impl Text for FixedAscii<1024> {
    fn text(&self) -> String {
        self.as_str().to_string()
    }
}
impl Text for FixedUnicode<1024> {
    fn text(&self) -> String {
        self.as_str().to_string()
    }
}

/// Tries `f` with each string encoding until one reads.
fn with_strings<T>(f: impl Fn(Encoding) -> Option<T>) -> Option<T> {
    [
        Encoding::VarUnicode,
        Encoding::VarAscii,
        Encoding::FixedAscii,
        Encoding::FixedUnicode,
    ]
    .into_iter()
    .find_map(f)
}

#[derive(Clone, Copy)]
enum Encoding {
    VarUnicode,
    VarAscii,
    FixedAscii,
    FixedUnicode,
}

/// Whether a compound type has string fields of all these names. HDF5 leaves a memory field
/// without a same-named file field untouched, so reading a subset whose names are missing
/// (a corrupt or foreign file) would hand back uninitialised strings: check first.
fn has_string_fields(td: &TypeDescriptor, names: &[&str]) -> bool {
    let TypeDescriptor::Compound(c) = td else {
        return false;
    };
    // A corrupt datatype message can place a member outside its compound; libhdf5 would then
    // copy out of bounds during conversion.
    if c.fields
        .iter()
        .any(|f| f.offset.saturating_add(f.ty.size()) > c.size)
    {
        return false;
    }
    names.iter().all(|n| {
        c.fields.iter().any(|f| {
            f.name == *n
                && matches!(
                    f.ty,
                    TypeDescriptor::VarLenAscii
                        | TypeDescriptor::VarLenUnicode
                        | TypeDescriptor::FixedAscii(_)
                        | TypeDescriptor::FixedUnicode(_)
                )
        })
    })
}

fn meta_rows(ds: &hdf5::Dataset) -> Option<Vec<[String; 3]>> {
    let td = ds.dtype().and_then(|t| t.to_descriptor()).ok()?;
    if !has_string_fields(&td, &["Source", "Link", "Destination"]) {
        return None;
    }
    fn rows<S: Text>(ds: &hdf5::Dataset) -> Option<Vec<[String; 3]>> {
        let raw = ds.read_raw::<MetaRow<S>>().ok()?;
        Some(
            raw.iter()
                .map(|r| [r.source.text(), r.link.text(), r.destination.text()])
                .collect(),
        )
    }
    with_strings(|e| match e {
        Encoding::VarUnicode => rows::<VarLenUnicode>(ds),
        Encoding::VarAscii => rows::<VarLenAscii>(ds),
        Encoding::FixedAscii => rows::<FixedAscii<1024>>(ds),
        Encoding::FixedUnicode => rows::<FixedUnicode<1024>>(ds),
    })
}

/// First element of a string attribute (scalar or array), in any encoding.
fn attr_string(a: &hdf5::Attribute) -> Option<String> {
    if a.size() > MAX_ATTRIBUTE_ELEMENTS {
        return None;
    }
    fn first<S: Text>(a: &hdf5::Attribute) -> Option<String> {
        a.read_raw::<S>().ok()?.first().map(Text::text)
    }
    with_strings(|e| match e {
        Encoding::VarUnicode => first::<VarLenUnicode>(a),
        Encoding::VarAscii => first::<VarLenAscii>(a),
        Encoding::FixedAscii => first::<FixedAscii<1024>>(a),
        Encoding::FixedUnicode => first::<FixedUnicode<1024>>(a),
    })
}

/// First element of a numeric attribute (scalar or array).
fn attr_number(a: &hdf5::Attribute) -> Option<f64> {
    if a.size() > MAX_ATTRIBUTE_ELEMENTS {
        return None;
    }
    match a.dtype().and_then(|t| t.to_descriptor()).ok()? {
        TypeDescriptor::Float(_) | TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_) => {
            a.read_raw::<f64>().ok()?.first().copied()
        }
        _ => None,
    }
}

/// An attribute as text: a string, or a number in round-trip form.
fn attr_text(a: &hdf5::Attribute) -> Option<String> {
    attr_number(a)
        .map(|x| x.to_string())
        .or_else(|| attr_string(a))
}

/// One `X/Y/Z Converter` attribute.
struct Converter {
    category: String,
    base_unit: String,
    parameters: Vec<f64>,
}

fn converter(ds: &hdf5::Dataset, name: &str) -> std::result::Result<Converter, String> {
    let a = ds
        .attr(name)
        .map_err(|_| format!("no `{name}` attribute"))?;
    let bad = |what: &str| format!("`{name}` attribute: {what}");
    if a.size() > MAX_ATTRIBUTE_ELEMENTS {
        return Err(bad(&format!("{} elements, expected 1", a.size())));
    }
    let fields = match a.dtype().and_then(|t| t.to_descriptor()) {
        Ok(td @ TypeDescriptor::Compound(_))
            if !has_string_fields(&td, &["Category", "BaseUnit"]) =>
        {
            return Err(bad("no `Category` and `BaseUnit` string fields"))
        }
        Ok(TypeDescriptor::Compound(c)) => c.fields,
        Ok(other) => return Err(bad(&format!("holds {other}, not a compound"))),
        Err(e) => return Err(bad(&one_line(&e.to_string()))),
    };
    fn names<S: Text>(a: &hdf5::Attribute) -> Option<(String, String)> {
        let v = a.read_raw::<ConvNames<S>>().ok()?;
        v.first().map(|c| (c.category.text(), c.base_unit.text()))
    }
    let (category, base_unit) = with_strings(|e| match e {
        Encoding::VarUnicode => names::<VarLenUnicode>(&a),
        Encoding::VarAscii => names::<VarLenAscii>(&a),
        Encoding::FixedAscii => names::<FixedAscii<1024>>(&a),
        Encoding::FixedUnicode => names::<FixedUnicode<1024>>(&a),
    })
    .ok_or_else(|| bad("no readable `Category` and `BaseUnit` strings"))?;
    let ty = fields
        .iter()
        .find(|f| f.name == "Parameters")
        .map(|f| f.ty.clone())
        .ok_or_else(|| bad("no `Parameters` field"))?;
    fn fixed<const N: usize>(a: &hdf5::Attribute) -> Option<Vec<f64>> {
        let v = a.read_raw::<ConvParams<[f64; N]>>().ok()?;
        v.first().map(|p| p.parameters.to_vec())
    }
    let numeric = |t: &TypeDescriptor| {
        matches!(
            t,
            TypeDescriptor::Float(_) | TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_)
        )
    };
    let parameters = match &ty {
        TypeDescriptor::VarLenArray(el) if numeric(el) => a
            .read_raw::<ConvParams<VarLenArray<f64>>>()
            .ok()
            .and_then(|v| v.first().map(|p| p.parameters.as_slice().to_vec())),
        TypeDescriptor::FixedArray(el, n) if numeric(el) => match n {
            1 => fixed::<1>(&a),
            2 => fixed::<2>(&a),
            3 => fixed::<3>(&a),
            4 => fixed::<4>(&a),
            5 => fixed::<5>(&a),
            6 => fixed::<6>(&a),
            7 => fixed::<7>(&a),
            8 => fixed::<8>(&a),
            _ => None,
        },
        _ => None,
    }
    .ok_or_else(|| bad(&format!("`Parameters` is {ty}, not a float64 array")))?;
    Ok(Converter {
        category,
        base_unit,
        parameters,
    })
}

/// Metres per `BaseUnit` of a Z converter.
fn base_unit_factor(unit: &str) -> Option<f64> {
    Some(match unit {
        "Meters" => 1.0,
        "MilliMeters" => 1e-3,
        "MicroMeters" => 1e-6,
        "NanoMeters" => 1e-9,
        "PicoMeters" => 1e-12,
        "Angstroms" => 1e-10,
        _ => return None,
    })
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Reads in a child process (`formats::isolated`): libhdf5 1.10 crashes or spins on some
/// corrupt files, and that must be an error naming the file, not the end of hdi.
pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let reply = isolated::read_hdf5(
        path,
        || read_in_process(path, bytes.len(), opts),
        send,
        |r| receive(path, r),
    );
    reply.unwrap_or_else(|failure| {
        Err(format_error(
            path,
            format!("{failure} on this .datx (HDF5) file; is it corrupt?"),
        ))
    })
}

fn read_in_process(path: &Path, file_len: usize, opts: &ReadOptions) -> Result<RawMap> {
    // The HDF5 bindings must not take the reader down on a hostile file either.
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        read_inner(path, file_len, opts)
    })) {
        Ok(r) => r,
        Err(_) => Err(format_error(
            path,
            "the .datx (HDF5) reader failed on this file",
        )),
    }
}

/// The child's reply: tag 0 and the map, or an error's kind and text (the path is the
/// parent's own).
fn send(reply: Result<RawMap>, w: &mut isolated::Writer) -> std::io::Result<()> {
    let map = match reply {
        Ok(map) => map,
        Err(e) => {
            let (tag, text) = match e {
                SurfaceError::Format { reason, .. } => (1, reason),
                SurfaceError::Unsupported { reason, .. } => (2, reason),
                SurfaceError::InvalidData(m) => (3, m),
                other => (1, other.to_string()),
            };
            w.u64(tag)?;
            return w.str(&text);
        }
    };
    w.u64(0)?;
    let (ny, nx) = map.z.dim();
    w.u64(ny as u64)?;
    w.u64(nx as u64)?;
    let z = map.z.as_standard_layout();
    let values = z.as_slice().ok_or(std::io::ErrorKind::InvalidData)?;
    w.f64s(values)?;
    drop(z);
    for x in [map.dx, map.dy, map.x0, map.y0] {
        w.f64(x)?;
    }
    w.str(&map.channel)?;
    w.u64(map.header.len() as u64)?;
    for (k, v) in &map.header {
        w.str(k)?;
        w.str(v)?;
    }
    Ok(())
}

fn receive(path: &Path, r: &mut isolated::Reader) -> std::io::Result<Result<RawMap>> {
    let bad = || std::io::Error::from(std::io::ErrorKind::InvalidData);
    match r.u64()? {
        0 => {}
        1 => return Ok(Err(format_error(path, r.str()?))),
        2 => return Ok(Err(unsupported(path, r.str()?))),
        3 => return Ok(Err(SurfaceError::InvalidData(r.str()?))),
        _ => return Err(bad()),
    }
    let ny = r.usize()?;
    let nx = r.usize()?;
    let z = Array2::from_shape_vec((ny, nx), r.f64s()?).map_err(|_| bad())?;
    let [dx, dy, x0, y0] = [r.f64()?, r.f64()?, r.f64()?, r.f64()?];
    let channel = r.str()?;
    let mut header = BTreeMap::new();
    for _ in 0..r.u64()? {
        let k = r.str()?;
        header.insert(k, r.str()?);
    }
    Ok(Ok(RawMap {
        z,
        dx,
        dy,
        x0,
        y0,
        channel,
        format: "datx",
        header,
    }))
}

fn read_inner(path: &Path, file_len: usize, opts: &ReadOptions) -> Result<RawMap> {
    let file = hdf5::File::open(path).map_err(|e| h5_error(path, e))?;
    let (surface_path, intensity_path) = measurement_paths(path, &file, file_len)?;
    let channel = choose_channel(path, opts, intensity_path.is_some())?;
    let open = |p: &str, what: &str| {
        file.dataset(p).map_err(|_| {
            format_error(
                path,
                format!(".datx /MetaData gives the {what} path `{p}`, which names no dataset"),
            )
        })
    };
    let surface = open(&surface_path, "surface")?;
    let ds = match (&intensity_path, channel) {
        (Some(p), 1) => open(p, "intensity")?,
        _ => surface.clone(),
    };
    let ds_path = if channel == 0 {
        surface_path.clone()
    } else {
        intensity_path.clone().unwrap_or_default()
    };
    let dataset = Dataset {
        path,
        ds: &ds,
        ds_path: &ds_path,
    };

    // Lateral spacing: the dataset's own converters, for intensity falling back to the surface's.
    let dx = dataset.lateral_spacing(&surface, channel, "X Converter")?;
    let dy = dataset.lateral_spacing(&surface, channel, "Y Converter")?;

    let unit_attr = ds.attr("Unit").ok().and_then(|a| attr_string(&a));
    let mut header = BTreeMap::new();
    let scale = if channel == 0 {
        dataset.height_scale(unit_attr.as_deref(), &mut header)?
    } else {
        1.0 // intensities are counts, not lengths
    };
    if let Some(u) = &unit_attr {
        header.insert("unit".to_string(), u.clone());
    }
    header.insert("path".to_string(), ds_path.clone());
    let channels = if intensity_path.is_some() {
        "height, intensity"
    } else {
        "height"
    };
    header.insert("channels".to_string(), channels.to_string());

    let (z, no_data) = dataset.read_values(file_len, scale)?;
    if let Some(nd) = no_data {
        header.insert("no_data".to_string(), nd.to_string());
    }
    find_instrument(&file, &surface_path, &mut header);
    Ok(RawMap {
        z,
        dx,
        dy,
        x0: 0.0,
        y0: 0.0,
        channel: if channel == 0 { "height" } else { "intensity" }.to_string(),
        format: "datx",
        header,
    })
}

fn h5_error(path: &Path, e: hdf5::Error) -> SurfaceError {
    format_error(path, format!("HDF5: {}", one_line(&e.to_string())))
}

/// The surface dataset's path and, if the file has one, the intensity dataset's, from the
/// /MetaData table: Root → Measurement → <channel> → Path.
fn measurement_paths(
    path: &Path,
    file: &hdf5::File,
    file_len: usize,
) -> Result<(String, Option<String>)> {
    let meta = match file.dataset("MetaData") {
        Ok(ds) => ds,
        Err(_) => {
            return Err(unsupported(
                path,
                "HDF5 but not Zygo .datx: no /MetaData dataset; \
                 hdi reads height maps from HDF5 only in Zygo's .datx layout",
            ))
        }
    };
    if meta.size() > file_len / MIN_META_ROW_BYTES {
        return Err(format_error(
            path,
            format!(
                ".datx /MetaData claims {} rows, more than a file of {file_len} bytes can hold",
                meta.size()
            ),
        ));
    }
    let rows = meta_rows(&meta).ok_or_else(|| {
        format_error(
            path,
            ".datx /MetaData is not a table of (Source, Link, Destination) strings",
        )
    })?;
    let mut table: HashMap<&str, HashMap<&str, &str>> = HashMap::new();
    for [s, l, d] in &rows {
        table.entry(s.as_str()).or_default().insert(l, d);
    }
    let lookup = |what: &str| -> std::result::Result<String, String> {
        let mut node = "Root";
        for key in ["Measurement", what] {
            let next = table
                .get(node)
                .and_then(|m| m.get(key))
                .ok_or_else(|| format!("/MetaData has no `{key}` entry under `{node}`"))?;
            if !(next.starts_with('{') && next.ends_with('}')) {
                return Err(format!(
                    "/MetaData `{node}` → `{key}` is `{next}`, not a {{…}} node"
                ));
            }
            node = next;
        }
        table
            .get(node)
            .and_then(|m| m.get("Path"))
            .map(|p| p.to_string())
            .ok_or_else(|| format!("/MetaData has no `Path` for the {what}"))
    };
    let surface_path = lookup("Surface").map_err(|m| format_error(path, format!(".datx {m}")))?;
    Ok((surface_path, lookup("Intensity").ok()))
}

/// 0 = height (the default), 1 = intensity (only when the file has one).
fn choose_channel(path: &Path, opts: &ReadOptions, has_intensity: bool) -> Result<usize> {
    let names = vec![
        vec!["height".to_string(), "surface".to_string()],
        vec!["intensity".to_string()],
    ];
    Ok(match opts.channel.as_deref() {
        None => 0,
        Some(req) => find_channel(req, &names)
            .filter(|&k| k == 0 || has_intensity)
            .ok_or_else(|| {
                let list = if has_intensity {
                    "height (surface), intensity"
                } else {
                    "height (surface)"
                };
                unsupported(
                    path,
                    format!(".datx file has no channel `{req}`; channels: {list}"),
                )
            })?,
    })
}

/// The dataset being read, with what its errors name.
struct Dataset<'a> {
    path: &'a Path,
    ds: &'a hdf5::Dataset,
    ds_path: &'a str,
}

impl Dataset<'_> {
    fn error(&self, m: String) -> SurfaceError {
        format_error(self.path, format!(".datx dataset `{}`: {m}", self.ds_path))
    }

    /// Pixel spacing (m) from converter `name`; for intensity (channel 1) the surface's
    /// converter stands in for a missing one.
    fn lateral_spacing(&self, surface: &hdf5::Dataset, channel: usize, name: &str) -> Result<f64> {
        let conv = match converter(self.ds, name) {
            Err(_) if channel == 1 => converter(surface, name),
            r => r,
        }
        .map_err(|m| self.error(m.clone()))?;
        if conv.category != "LateralCat" {
            return Err(self.error(format!(
                "`{name}` has category `{}`, expected `LateralCat`",
                conv.category
            )));
        }
        match conv.parameters.get(1) {
            Some(&d) if d.is_finite() && d > 0.0 => Ok(d),
            Some(d) => Err(self.error(format!(
                "`{name}` pixel spacing Parameters[1] = {d} m is not a positive length"
            ))),
            None => Err(self.error(format!("`{name}` Parameters has no element [1] (spacing)"))),
        }
    }

    /// Metres per stored height value: the `Unit` attribute and the Z converter's base unit
    /// must agree where both are lengths.
    fn height_scale(
        &self,
        unit_attr: Option<&str>,
        header: &mut BTreeMap<String, String>,
    ) -> Result<f64> {
        let z = converter(self.ds, "Z Converter").map_err(|m| self.error(m))?;
        if z.category != "HeightCat" {
            return Err(self.error(format!(
                "`Z Converter` has category `{}`, expected `HeightCat`",
                z.category
            )));
        }
        let from_attr = unit_attr.and_then(units::length_factor);
        let from_conv = base_unit_factor(&z.base_unit);
        header.insert("z_base_unit".to_string(), z.base_unit.clone());
        match (from_attr, from_conv) {
            (Some(a), Some(c)) if (a / c - 1.0).abs() > 1e-9 => Err(self.error(format!(
                "conflicting height units: `Unit` = `{}`, `Z Converter` BaseUnit = `{}`",
                unit_attr.unwrap_or_default(),
                z.base_unit
            ))),
            (Some(f), _) | (None, Some(f)) => Ok(f),
            (None, None) => Err(unsupported(
                self.path,
                format!(
                    ".datx height unit `{}` (Z Converter BaseUnit `{}`) is not a length \
                     hdi can convert",
                    unit_attr.unwrap_or_default(),
                    z.base_unit
                ),
            )),
        }
    }

    /// The 2-D values times `scale`, no-data and non-finite values as NaN; and the no-data
    /// value, if the dataset declares one.
    fn read_values(&self, file_len: usize, scale: f64) -> Result<(Array2<f64>, Option<f64>)> {
        let ds = self.ds;
        let shape = ds.shape();
        let (ny, nx) = match shape.as_slice() {
            [ny, nx] => (*ny, *nx),
            _ => return Err(self.error(format!("shape {shape:?} is not 2-D"))),
        };
        let is_f32 = match ds
            .dtype()
            .and_then(|t| t.to_descriptor())
            .map_err(|e| h5_error(self.path, e))?
        {
            TypeDescriptor::Float(s) => s == hdf5::types::FloatSize::U4,
            TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_) => false,
            other => return Err(self.error(format!("holds {other}, not numbers"))),
        };
        let n = ny.saturating_mul(nx);
        if n > file_len.saturating_mul(MAX_VALUES_PER_FILE_BYTE) {
            return Err(self.error(format!(
                "{nx}×{ny} pixels is too large for a file of {file_len} bytes"
            )));
        }
        let no_data = ds.attr("No Data").ok().and_then(|a| attr_number(&a));
        let raw: Array2<f64> = ds.read_2d::<f64>().map_err(|e| h5_error(self.path, e))?;
        let is_no_data = |v: f64| match no_data {
            Some(nd) => v == nd || (is_f32 && (v as f32) == (nd as f32)),
            None => false,
        };
        let z = raw.mapv(|v| {
            if is_no_data(v) || !v.is_finite() {
                f64::NAN
            } else {
                v * scale
            }
        });
        Ok((z, no_data))
    }
}

/// `System Serial Number` / `System Type` from the surface dataset, its parent groups, then
/// anything under `/Attributes` (where Mx writes them, with a dotted context prefix).
fn find_instrument(file: &hdf5::File, surface_path: &str, header: &mut BTreeMap<String, String>) {
    let wanted = [
        ("System Serial Number", "system_serial_number"),
        ("System Type", "system_type"),
    ];
    let scan = |loc: &hdf5::Location, header: &mut BTreeMap<String, String>| {
        let Ok(names) = loc.attr_names() else { return };
        for (suffix, key) in wanted {
            if header.contains_key(key) {
                continue;
            }
            if let Some(v) = names
                .iter()
                .filter(|n| n.ends_with(suffix))
                .find_map(|n| loc.attr(n).ok().and_then(|a| attr_text(&a)))
            {
                header.insert(key.to_string(), v);
            }
        }
    };
    if let Ok(ds) = file.dataset(surface_path) {
        scan(&ds, header);
    }
    let mut p = surface_path;
    while let Some(k) = p.rfind('/') {
        p = &p[..k];
        if p.is_empty() {
            break;
        }
        if let Ok(g) = file.group(p) {
            scan(&g, header);
        }
    }
    let Ok(root) = file.group("Attributes") else {
        return;
    };
    let mut stack = vec![root];
    let mut visited = 0;
    while let Some(g) = stack.pop() {
        visited += 1;
        if visited > MAX_ATTRIBUTE_OBJECTS || wanted.iter().all(|(_, k)| header.contains_key(*k)) {
            break;
        }
        scan(&g, header);
        for name in g.member_names().unwrap_or_default() {
            if let Ok(child) = g.group(&name) {
                stack.push(child);
            } else if let Ok(ds) = g.dataset(&name) {
                scan(&ds, header);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};
    use crate::surface::{HeightMap, SurfaceError};
    use std::path::PathBuf;

    const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/surfaces/readers_b");

    fn sample(name: &str) -> PathBuf {
        PathBuf::from(DIR).join(name)
    }

    fn read_with(name: &str, channel: Option<&str>) -> crate::surface::Result<HeightMap> {
        let opts = ReadOptions {
            channel: channel.map(str::to_string),
            ..Default::default()
        };
        read_height_map(&sample(name), &opts)
    }

    #[test]
    fn h5py_written_files_match_numpy() {
        // Files and numbers from tests/data/surfaces/readers_b/make_datx.py (h5py + numpy):
        // vlen strings + vlen Parameters (float64 nm data), fixed strings + fixed [4]
        // Parameters (float32 µm data with a NaN).
        let text = std::fs::read_to_string(sample("datx_expected.json")).unwrap();
        let expected: serde_json::Value = serde_json::from_str(&text).unwrap();
        let mut seen = 0;
        for (name, want) in expected.as_object().unwrap() {
            seen += 1;
            let map = read_with(name, None).unwrap();
            let f = |k: &str| want[k].as_f64().unwrap();
            assert_eq!(map.source.format, "datx");
            assert_eq!(map.channel, "height");
            assert_eq!(
                (map.nx() as f64, map.ny() as f64),
                (f("nx"), f("ny")),
                "{name}"
            );
            assert!(close(map.dx, f("dx"), 1e-15), "{name} dx {}", map.dx);
            assert!(close(map.dy, f("dy"), 1e-15), "{name} dy {}", map.dy);
            let (ny, nx) = map.z.dim();
            for (got, k) in [
                (map.z[[0, 0]], "z_0_0"),
                (map.z[[1, 2]], "z_1_2"),
                (map.z[[ny - 1, nx - 1]], "z_last"),
            ] {
                assert!(close(got, f(k), 1e-14), "{name} {k}: {got} vs {}", f(k));
            }
            let (mean, std, invalid) = valid_stats(&map);
            assert_eq!(invalid as f64, f("n_invalid"), "{name}");
            assert!(
                close(std, f("std"), 1e-12),
                "{name} σ {std} vs {}",
                f("std")
            );
            assert!((mean - f("mean")).abs() <= 1e-12 * f("std"), "{name} mean");
            let h = &map.source.header;
            assert_eq!(h["system_serial_number"], want["serial"].as_str().unwrap());
            assert_eq!(h["system_type"], want["system_type"].as_str().unwrap());
        }
        assert_eq!(seen, 2);
    }

    #[test]
    fn intensity_channel_and_unknown_channel() {
        let text = std::fs::read_to_string(sample("datx_expected.json")).unwrap();
        let want: serde_json::Value = serde_json::from_str(&text).unwrap();
        let want = &want["datx_vlen.datx"];
        let map = read_with("datx_vlen.datx", Some("intensity")).unwrap();
        assert_eq!(
            (map.nx(), map.ny(), map.channel.as_str()),
            (40, 30, "intensity")
        );
        assert!(close(map.dx, 0.8e-6, 1e-15) && close(map.dy, 1.2e-6, 1e-15));
        let (mean, _, invalid) = valid_stats(&map);
        assert_eq!(
            invalid as f64,
            want["intensity_n_invalid"].as_f64().unwrap()
        );
        assert!(close(mean, want["intensity_mean"].as_f64().unwrap(), 1e-12));
        // "surface" is the height channel's other name.
        let map = read_with("datx_vlen.datx", Some("Surface")).unwrap();
        assert_eq!(map.channel, "height");
        // The fixed-string file has no intensity dataset.
        for (name, req) in [
            ("datx_fixed.datx", "intensity"),
            ("datx_vlen.datx", "phase"),
        ] {
            let err = read_with(name, Some(req)).unwrap_err();
            assert!(matches!(err, SurfaceError::Unsupported { .. }), "{err}");
            let msg = err.to_string();
            assert!(
                msg.contains(name) && msg.contains("channels: height"),
                "{msg}"
            );
        }
    }

    #[test]
    fn wrong_content_is_one_clear_error() {
        for (name, needle) in [
            ("bad_no_metadata.datx", "HDF5 but not Zygo .datx"),
            ("bad_path.datx", "names no dataset"),
            (
                "bad_category.datx",
                "`X Converter` has category `HeightCat`",
            ),
            ("bad_units.datx", "conflicting height units"),
        ] {
            let msg = read_with(name, None).unwrap_err().to_string();
            assert!(msg.contains(name) && msg.contains(needle), "{name}: {msg}");
            assert!(!msg.contains('\n'), "{msg}");
        }
    }

    #[test]
    fn truncated_and_garbled_files_are_errors() {
        let bytes = std::fs::read(sample("datx_vlen.datx")).unwrap();
        for cut in [8, 100, 2000, bytes.len() / 2, bytes.len() - 1] {
            let msg = read_bytes("t.datx", &bytes[..cut]).unwrap_err().to_string();
            assert!(
                msg.contains("t.datx") && !msg.contains('\n'),
                "{cut}: {msg}"
            );
        }
        // Flipped bytes in the datatype messages once made libhdf5 copy out of bounds and
        // left uninitialised strings behind (missing compound members): both files are registry
        // samples, whose corrupt copies registry.rs reads
        // (`every_sample_survives_truncation_and_flipped_bytes`).
    }
}
