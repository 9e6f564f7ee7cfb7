//! Column and dataset names → roles (time, sample number, velocity, index) and units, and the
//! `key = value` metadata the text and Parquet formats carry. Shared by every reader so that a
//! CSV column and an HDF5 dataset with the same name mean the same thing.

use super::ReadOptions;

/// A unit as written in a header, `units` attribute or name suffix, with its factor to SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Unit {
    Second(f64),
    Volt(f64),
    MetrePerSecond(f64),
    /// Dimensionless sample numbers.
    Count,
}

impl Unit {
    pub(super) fn describe(self) -> String {
        match self {
            Unit::Second(f) => format!("s×{f}"),
            Unit::Volt(1.0) => "V".into(),
            Unit::Volt(f) => format!("V×{f}"),
            Unit::MetrePerSecond(1.0) => "m/s".into(),
            Unit::MetrePerSecond(f) => format!("m/s×{f}"),
            Unit::Count => "1".into(),
        }
    }
}

/// Parses a unit spelling (case-insensitive, spaces ignored); `None` if not one of ours.
pub(super) fn parse_unit(text: &str) -> Option<Unit> {
    let compact: String = text
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| !c.is_whitespace())
        .map(|c| if c == 'µ' || c == 'μ' { 'u' } else { c })
        .collect();
    let compact = compact.replace('⁻', "-").replace('¹', "1");
    Some(match compact.as_str() {
        "s" | "sec" | "second" | "seconds" => Unit::Second(1.0),
        "ms" => Unit::Second(1e-3),
        "us" => Unit::Second(1e-6),
        "ns" => Unit::Second(1e-9),
        "v" | "volt" | "volts" => Unit::Volt(1.0),
        "mv" => Unit::Volt(1e-3),
        "m/s" | "m_s" | "mps" | "ms-1" | "ms^-1" | "m*s^-1" | "m.s-1" | "m·s-1" => {
            Unit::MetrePerSecond(1.0)
        }
        "mm/s" | "mm_s" | "mms-1" | "mm·s-1" => Unit::MetrePerSecond(1e-3),
        "um/s" | "um_s" | "ums-1" | "um·s-1" => Unit::MetrePerSecond(1e-6),
        "1" | "sample" | "samples" => Unit::Count,
        _ => return None,
    })
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Role {
    Time,
    Sample,
    Velocity,
    Index,
}

const TIME: &[&str] = &["time", "t"];
const SAMPLE: &[&str] = &["sample", "n", "sample_index", "samples", "sample_number"];
const VELOCITY: &[&str] = &["velocity", "voltage", "u", "v"];
const INDEX: &[&str] = &["index", "trigger", "tacho", "once_per_rev", "trig"];

fn base_role(base: &str) -> Option<Role> {
    [
        (TIME, Role::Time),
        (SAMPLE, Role::Sample),
        (VELOCITY, Role::Velocity),
        (INDEX, Role::Index),
    ]
    .into_iter()
    .find(|(names, _)| names.contains(&base))
    .map(|(_, role)| role)
}

/// What a header name says: its role (if it is one of the known names with a compatible unit)
/// and the unit it carries (`velocity (m/s)`, `velocity [V]`, `time_ms`, `U_V`...).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Parsed {
    pub role: Option<Role>,
    pub unit: Option<Unit>,
    /// The unit text when the name has one we do not know (e.g. `velocity (in/s)`).
    pub unknown_unit: Option<String>,
}

/// Trimmed, unquoted name.
pub(super) fn clean(raw: &str) -> &str {
    raw.trim().trim_matches(|c| c == '"' || c == '\'').trim()
}

pub(super) fn classify(raw: &str) -> Parsed {
    let name = clean(raw).to_lowercase();
    let (base, unit_text) = match split_bracket(&name) {
        Some((b, u)) => (b, Some(u.to_string())),
        None => (name.clone(), None),
    };
    let base: String = base.split_whitespace().collect::<Vec<_>>().join("_");
    let (base, unit, unknown_unit) = match unit_text {
        Some(u) => match parse_unit(&u) {
            Some(unit) => (base, Some(unit), None),
            None => (base, None, Some(u)),
        },
        None => split_suffix(&base),
    };
    let role = base_role(&base).and_then(|role| match (role, unit) {
        // A velocity with a unit we do not know is still the velocity: the reader then asks
        // for `velocity_unit` instead of claiming there is no velocity column.
        (Role::Velocity, _) if unknown_unit.is_some() => Some(Role::Velocity),
        _ if unknown_unit.is_some() => None,
        (Role::Time, None | Some(Unit::Second(_))) => Some(Role::Time),
        (Role::Time | Role::Sample, Some(Unit::Count)) | (Role::Sample, None) => Some(Role::Sample),
        (Role::Velocity, None | Some(Unit::Volt(_) | Unit::MetrePerSecond(_))) => {
            Some(Role::Velocity)
        }
        (Role::Index, None | Some(Unit::Volt(_))) => Some(Role::Index),
        _ => None,
    });
    Parsed {
        role,
        unit,
        unknown_unit,
    }
}

/// `name (unit)` or `name [unit]`.
fn split_bracket(name: &str) -> Option<(String, &str)> {
    for (open, close) in [('(', ')'), ('[', ']')] {
        if let Some(stripped) = name.strip_suffix(close) {
            if let Some(k) = stripped.rfind(open) {
                let base = stripped[..k].trim().to_string();
                if !base.is_empty() {
                    return Some((base, stripped[k + 1..].trim()));
                }
            }
        }
    }
    None
}

/// `velocity_m_s` → (`velocity`, m/s): the first `_` that splits a known name from a unit.
fn split_suffix(name: &str) -> (String, Option<Unit>, Option<String>) {
    for (k, _) in name.match_indices('_') {
        let (head, tail) = (&name[..k], &name[k + 1..]);
        if base_role(head).is_some() {
            if let Some(unit) = parse_unit(tail) {
                return (head.to_string(), Some(unit), None);
            }
        }
    }
    (name.to_string(), None, None)
}

/// How the time axis is given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum TimeKind {
    /// Times; multiply by the factor to get seconds.
    Seconds(f64),
    /// Sample numbers at the stated sample rate.
    Samples,
}

/// The columns (or datasets) a reader uses, as indices into the name list.
#[derive(Debug, Clone)]
pub(super) struct Chosen {
    pub velocity: usize,
    /// Unit the velocity name carries, if any.
    pub velocity_unit: Option<Unit>,
    pub velocity_unknown_unit: Option<String>,
    pub index: Option<usize>,
    pub time: Option<(usize, TimeKind)>,
}

impl Chosen {
    /// The velocity, index and time columns, in that order (`None` for an absent one).
    pub fn slots(&self) -> [Option<usize>; 3] {
        [Some(self.velocity), self.index, self.time.map(|t| t.0)]
    }

    /// The indices of the columns used.
    pub fn used(&self) -> Vec<usize> {
        self.slots().into_iter().flatten().collect()
    }
}

fn find(names: &[String], wanted: &str) -> Option<usize> {
    let wanted = clean(wanted).to_lowercase();
    names.iter().position(|n| clean(n).to_lowercase() == wanted)
}

fn list(names: &[String]) -> String {
    let shown: Vec<&str> = names.iter().take(20).map(|n| clean(n)).collect();
    let more = if names.len() > 20 { ", …" } else { "" };
    format!("[{}{more}]", shown.join(", "))
}

/// Picks velocity, index and time among `names` (`what` = "column" or "dataset"): explicit
/// options first (case-insensitive exact names), then detection by name. Ambiguity is an error
/// rather than a guess: a wrong channel would give a plausible but wrong DMW.
pub(super) fn choose(names: &[String], opts: &ReadOptions, what: &str) -> Result<Chosen, String> {
    let parsed: Vec<Parsed> = names.iter().map(|n| classify(n)).collect();
    let explicit = |wanted: &Option<String>, option: &str| -> Result<Option<usize>, String> {
        match wanted {
            None => Ok(None),
            Some(w) => find(names, w).map(Some).ok_or_else(|| {
                format!(
                    "no {what} '{w}' ({option} option); {what}s: {}",
                    list(names)
                )
            }),
        }
    };
    let candidates = |role: Role, exclude: &[Option<usize>]| -> Vec<usize> {
        (0..names.len())
            .filter(|k| parsed[*k].role == Some(role) && !exclude.contains(&Some(*k)))
            .collect()
    };
    let ambiguous = |role: &str, found: &[usize], option: &str| {
        let found: Vec<String> = found.iter().map(|&k| names[k].clone()).collect();
        format!(
            "several {role} {what}s {}; choose one with the {option} option",
            list(&found)
        )
    };

    let ex_velocity = explicit(&opts.velocity_column, "velocity_column")?;
    let ex_index = explicit(&opts.index_column, "index_column")?;
    let ex_time = explicit(&opts.time_column, "time_column")?;
    let velocity = match ex_velocity {
        Some(k) => k,
        None => match candidates(Role::Velocity, &[ex_index, ex_time]).as_slice() {
            [k] => *k,
            [] => {
                return Err(format!(
                    "no velocity {what} among {}; name it velocity_V or velocity_m_s, or choose \
                     one with the velocity_column option",
                    list(names)
                ))
            }
            found => return Err(ambiguous("velocity", found, "velocity_column")),
        },
    };
    let time = match ex_time {
        Some(k) => Some(k),
        None => {
            let times = candidates(Role::Time, &[Some(velocity), ex_index]);
            match times.as_slice() {
                [k] => Some(*k),
                [] => match candidates(Role::Sample, &[Some(velocity), ex_index]).as_slice() {
                    [] => None,
                    [k] => Some(*k),
                    found => return Err(ambiguous("sample-number", found, "time_column")),
                },
                found => return Err(ambiguous("time", found, "time_column")),
            }
        }
    };
    let index = match ex_index {
        Some(k) => Some(k),
        None => match candidates(Role::Index, &[Some(velocity), time]).as_slice() {
            [] => None,
            [k] => Some(*k),
            found => return Err(ambiguous("index", found, "index_column")),
        },
    };
    let same = |a: Option<usize>, b: Option<usize>| a.is_some() && a == b;
    if same(Some(velocity), time) || same(Some(velocity), index) || same(time, index) {
        return Err(format!(
            "the same {what} is chosen for two of velocity, index and time; {what}s: {}",
            list(names)
        ));
    }
    let time = time.map(|k| {
        let kind = match (parsed[k].role, parsed[k].unit) {
            (Some(Role::Sample), _) => TimeKind::Samples,
            (_, Some(Unit::Second(f))) => TimeKind::Seconds(f),
            // An explicitly chosen column with an unknown name holds seconds.
            _ => TimeKind::Seconds(1.0),
        };
        (k, kind)
    });
    Ok(Chosen {
        velocity,
        velocity_unit: parsed[velocity].unit,
        velocity_unknown_unit: parsed[velocity].unknown_unit.clone(),
        index,
        time,
    })
}

/// File-level metadata (`# key = value` lines, Parquet key-value metadata, HDF5 attributes).
#[derive(Debug, Clone, Default)]
pub(super) struct Meta {
    pub sample_rate: Option<f64>,
    pub t0: Option<f64>,
    pub sensitivity: Option<f64>,
    pub rpm: Option<f64>,
    pub layout: Option<String>,
    pub velocity_unit: Option<Unit>,
    /// Keys we do not interpret, kept for provenance.
    pub other: Vec<(String, String)>,
}

/// Normalised metadata key: lower case, spaces and dashes as `_`.
pub(super) fn meta_key(key: &str) -> String {
    key.trim()
        .to_lowercase()
        .split(|c: char| c.is_whitespace() || c == '-')
        .filter(|s| !s.is_empty())
        .collect::<Vec<_>>()
        .join("_")
}

/// `4e6`, `4e6 Hz`, `4 MS/s` → (value, unit text).
fn split_number(value: &str) -> Option<(f64, String)> {
    let value = value.trim();
    if let Ok(v) = value.parse::<f64>() {
        return Some((v, String::new()));
    }
    let split = value.find(char::is_whitespace)?;
    let v = value[..split].parse::<f64>().ok()?;
    Some((v, value[split..].trim().to_lowercase().replace(' ', "")))
}

impl Meta {
    /// Takes one `key = value` pair; `Err` names the key and what is wrong with the value.
    pub(super) fn set(&mut self, key: &str, value: &str) -> Result<(), String> {
        let k = meta_key(key);
        let value = value.trim();
        let bad = |what: &str| format!("metadata '{key} = {value}' is not {what}");
        match k.as_str() {
            "sample_rate" | "sampling_rate" | "fs" | "sample_rate_hz" | "sampling_frequency" => {
                let (v, unit) = split_number(value).ok_or_else(|| bad("a number (Hz)"))?;
                let f = match unit.as_str() {
                    "" | "hz" | "s/s" | "sa/s" | "1/s" => 1.0,
                    "khz" | "ks/s" => 1e3,
                    "mhz" | "ms/s" => 1e6,
                    "ghz" | "gs/s" => 1e9,
                    _ => return Err(bad("a rate in Hz, kHz, MHz or S/s")),
                };
                self.sample_rate = Some(v * f);
            }
            "sensitivity" | "decoder" | "decoder_sensitivity" => {
                let (v, unit) = split_number(value).ok_or_else(|| bad("a number (m/s per V)"))?;
                let f = match unit.replace('µ', "u").as_str() {
                    "" | "m/s/v" | "(m/s)/v" | "ms-1v-1" => 1.0,
                    "mm/s/v" | "(mm/s)/v" | "mms-1v-1" => 1e-3,
                    "um/s/v" | "(um/s)/v" | "ums-1v-1" => 1e-6,
                    _ => return Err(bad("a sensitivity in m/s/V, mm/s/V or µm/s/V")),
                };
                self.sensitivity = Some(v * f);
            }
            "rpm" | "spindle_rpm" | "spindle_speed_rpm" => {
                let (v, unit) = split_number(value).ok_or_else(|| bad("a number (rpm)"))?;
                if !(unit.is_empty() || unit == "rpm" || unit == "1/min") {
                    return Err(bad("a speed in rpm"));
                }
                self.rpm = Some(v);
            }
            "t0" | "start_time" => {
                let (v, unit) = split_number(value).ok_or_else(|| bad("a number (s)"))?;
                let f = match parse_unit(&unit) {
                    _ if unit.is_empty() => 1.0,
                    Some(Unit::Second(f)) => f,
                    _ => return Err(bad("a time in s")),
                };
                self.t0 = Some(v * f);
            }
            "layout" => self.layout = Some(value.to_lowercase()),
            "velocity_unit" | "velocity_units" => match parse_unit(value) {
                Some(u @ (Unit::Volt(_) | Unit::MetrePerSecond(_))) => self.velocity_unit = Some(u),
                _ => return Err(bad("V, mV, m/s, mm/s or µm/s")),
            },
            _ => {
                if self.other.len() < 32 {
                    self.other.push((k, value.to_string()));
                }
            }
        }
        Ok(())
    }
}
