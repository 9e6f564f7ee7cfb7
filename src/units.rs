//! Physical quantities in configuration and on the command line.
//!
//! Inside hdi everything is SI. Users may write a plain number (taken as SI) or a string with a
//! unit: `"5 um"`, `"0.34nm"`, `"220 um^-2"`. Parsing normalises to SI so that the cache key
//! does not change when a user rewrites `"5 um"` as `5e-6`.

use serde::{Deserialize, Deserializer};

/// What kind of quantity a value is; decides which unit suffixes are accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dimension {
    Length,
    /// Areal density, m^-2.
    PerArea,
    /// Frequency or sample rate, Hz.
    Frequency,
    /// Duration, s.
    Time,
    /// Velocity-decoder sensitivity, m/s per V.
    Sensitivity,
    /// Pressure, modulus, hardness, Pa.
    Pressure,
    /// Surface energy (N/m = J/m²).
    SurfaceEnergy,
    /// Area, m².
    Area,
    /// Speed, m/s.
    Velocity,
    /// Dynamic viscosity, Pa·s.
    Viscosity,
    /// Electrical (heater) power, W.
    Power,
}

impl Dimension {
    fn si_unit(self) -> &'static str {
        match self {
            Dimension::Length => "m",
            Dimension::PerArea => "m^-2",
            Dimension::Frequency => "Hz",
            Dimension::Time => "s",
            Dimension::Sensitivity => "m/s/V",
            Dimension::Pressure => "Pa",
            Dimension::SurfaceEnergy => "N/m",
            Dimension::Area => "m^2",
            Dimension::Velocity => "m/s",
            Dimension::Viscosity => "Pa s",
            Dimension::Power => "W",
        }
    }
}

fn pressure_exponent(unit: &str) -> Option<i32> {
    Some(match unit {
        "Pa" => 0,
        "kPa" => 3,
        "MPa" => 6,
        "GPa" => 9,
        _ => return None,
    })
}

fn surface_energy_exponent(unit: &str) -> Option<i32> {
    Some(match unit {
        "N/m" | "J/m^2" | "J/m²" => 0,
        "mN/m" | "mJ/m^2" | "mJ/m²" => -3,
        _ => return None,
    })
}

fn viscosity_exponent(unit: &str) -> Option<i32> {
    Some(match unit {
        "Pa s" | "Pa·s" | "Pa*s" => 0,
        "mPa s" | "mPa·s" | "mPa*s" | "cP" => -3,
        _ => return None,
    })
}

fn power_exponent(unit: &str) -> Option<i32> {
    Some(match unit {
        "W" => 0,
        "mW" => -3,
        "uW" | "µW" | "μW" => -6,
        _ => return None,
    })
}

/// Frequency unit as a power of ten of hertz (sample rates may be written as S/s).
fn frequency_exponent(unit: &str) -> Option<i32> {
    Some(match unit {
        "Hz" | "S/s" | "Sa/s" => 0,
        "kHz" | "kS/s" => 3,
        "MHz" | "MS/s" => 6,
        "GHz" | "GS/s" => 9,
        _ => return None,
    })
}

/// Time unit as a power of ten of seconds.
fn time_exponent(unit: &str) -> Option<i32> {
    Some(match unit {
        "s" => 0,
        "ms" => -3,
        "us" | "µs" | "μs" => -6,
        "ns" => -9,
        "ps" => -12,
        _ => return None,
    })
}

/// Length unit as a power of ten of metres (all supported units are decimal).
pub fn length_exponent(unit: &str) -> Option<i32> {
    Some(match unit.trim() {
        "m" => 0,
        "cm" => -2,
        "mm" => -3,
        "um" | "µm" | "μm" | "~m" | "micron" | "microns" => -6,
        "nm" => -9,
        "pm" => -12,
        "fm" => -15,
        "A" | "Å" | "Ang" | "angstrom" | "Angstrom" => -10,
        _ => return None,
    })
}

/// Length unit factor to metres.
pub fn length_factor(unit: &str) -> Option<f64> {
    // 1/10^k is the correctly rounded 10^-k, the same bits as the literal (1e-9 etc.).
    length_exponent(unit).map(|e| 1.0 / 10f64.powi(-e))
}

/// Parse `"<number> <unit>"` (or a bare number, taken as SI) into SI.
///
/// The unit is applied by shifting the decimal exponent of the text before one correctly
/// rounded parse, so `"5 um"` and `5e-6` give the same bits and the same cache key.
pub fn parse_quantity(text: &str, dim: Dimension) -> Result<f64, String> {
    let t = text.trim();
    let split = t
        .char_indices()
        .find(|(_, c)| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E')))
        .map(|(i, _)| i)
        .unwrap_or(t.len());
    // "1e-9m" would be cut wrongly only if a unit started with e/E; none does.
    let (num, unit) = t.split_at(split);
    let num = num.trim();
    let not_number = || format!("`{text}` is not a number with a unit (e.g. \"5 um\")");
    let (mantissa, exp) = match num.find(['e', 'E']) {
        Some(i) => (
            &num[..i],
            num[i + 1..].parse::<i32>().map_err(|_| not_number())?,
        ),
        None => (num, 0),
    };
    mantissa.parse::<f64>().map_err(|_| not_number())?;
    let unit = unit.trim();
    let shift = if unit.is_empty() {
        0
    } else {
        match dim {
            Dimension::Length => length_exponent(unit),
            Dimension::PerArea => unit
                .strip_suffix("^-2")
                .or_else(|| unit.strip_suffix("⁻²"))
                .and_then(length_exponent)
                .map(|e| -2 * e),
            Dimension::Frequency => frequency_exponent(unit),
            Dimension::Time => time_exponent(unit),
            Dimension::Sensitivity => unit
                .strip_suffix("/s/V")
                .or_else(|| unit.strip_suffix("s^-1 V^-1"))
                .map(str::trim)
                .and_then(length_exponent),
            Dimension::Pressure => pressure_exponent(unit),
            Dimension::SurfaceEnergy => surface_energy_exponent(unit),
            Dimension::Area => unit
                .strip_suffix("^2")
                .or_else(|| unit.strip_suffix('²'))
                .and_then(length_exponent)
                .map(|e| 2 * e),
            Dimension::Velocity => unit.strip_suffix("/s").and_then(length_exponent),
            Dimension::Viscosity => viscosity_exponent(unit),
            Dimension::Power => power_exponent(unit),
        }
        .ok_or_else(|| {
            format!(
                "unknown unit `{unit}` in `{text}` (expected a {} unit such as {})",
                match dim {
                    Dimension::Length => "length",
                    Dimension::PerArea => "per-area",
                    Dimension::Frequency => "frequency",
                    Dimension::Time => "time",
                    Dimension::Sensitivity => "sensitivity",
                    Dimension::Pressure => "pressure",
                    Dimension::SurfaceEnergy => "surface-energy",
                    Dimension::Area => "area",
                    Dimension::Velocity => "speed",
                    Dimension::Viscosity => "viscosity",
                    Dimension::Power => "power",
                },
                match dim {
                    Dimension::Length => "m, mm, um, nm, pm, A",
                    Dimension::PerArea => "m^-2, um^-2",
                    Dimension::Frequency => "Hz, kHz, MHz, MS/s",
                    Dimension::Time => "s, ms, us, ns",
                    Dimension::Sensitivity => "m/s/V, mm/s/V, um/s/V",
                    Dimension::Pressure => "Pa, kPa, MPa, GPa",
                    Dimension::SurfaceEnergy => "N/m, mN/m, J/m^2, mJ/m^2",
                    Dimension::Area => "m^2, mm^2, um^2",
                    Dimension::Velocity => "m/s, mm/s, um/s",
                    Dimension::Viscosity => "Pa s, mPa s",
                    Dimension::Power => "W, mW, uW",
                }
            )
        })?
    };
    let si: f64 = format!("{mantissa}e{}", exp + shift)
        .parse()
        .map_err(|_| not_number())?;
    if !si.is_finite() {
        return Err(format!("`{text}` is not finite"));
    }
    Ok(si)
}

/// A length in metres, written in config as a number (m) or a string with a unit.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct Length(pub f64);

/// An areal density in m^-2, written as a number or e.g. `"220 um^-2"`.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct PerArea(pub f64);

/// A frequency or sample rate in Hz, written as a number or e.g. `"10 kHz"`, `"4 MS/s"`.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct Frequency(pub f64);

/// A duration in seconds, written as a number or e.g. `"2.5 ms"`.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct TimeSpan(pub f64);

/// A velocity-decoder sensitivity in m/s per V, written as a number or e.g. `"25 mm/s/V"`.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct Sensitivity(pub f64);

macro_rules! quantity_impls {
    ($t:ident, $dim:expr) => {
        impl<'de> Deserialize<'de> for $t {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                deserialize_quantity(d, $dim).map($t)
            }
        }
        impl std::str::FromStr for $t {
            type Err = String;
            fn from_str(s: &str) -> Result<Self, String> {
                parse_quantity(s, $dim).map($t)
            }
        }
    };
}
quantity_impls!(Frequency, Dimension::Frequency);
quantity_impls!(TimeSpan, Dimension::Time);
quantity_impls!(Sensitivity, Dimension::Sensitivity);

/// A pressure, modulus or hardness in Pa, written as a number or e.g. `"13 GPa"`.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct Pressure(pub f64);
quantity_impls!(Pressure, Dimension::Pressure);

/// A surface energy in N/m, written as a number or e.g. `"60 mN/m"`.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct SurfaceEnergy(pub f64);
quantity_impls!(SurfaceEnergy, Dimension::SurfaceEnergy);

/// An area in m², written as a number or e.g. `"2500 um^2"`.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct Area(pub f64);
quantity_impls!(Area, Dimension::Area);

/// A speed in m/s, written as a number or e.g. `"200 um/s"`.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct Velocity(pub f64);
quantity_impls!(Velocity, Dimension::Velocity);

/// A dynamic viscosity in Pa·s, written as a number or e.g. `"310 mPa s"`.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct Viscosity(pub f64);
quantity_impls!(Viscosity, Dimension::Viscosity);

/// A heater power in W, written as a number or e.g. `"30 mW"`.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct Power(pub f64);
quantity_impls!(Power, Dimension::Power);

fn deserialize_quantity<'de, D: Deserializer<'de>>(d: D, dim: Dimension) -> Result<f64, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum NumOrText {
        Num(f64),
        Text(String),
    }
    match NumOrText::deserialize(d).map_err(|_| {
        serde::de::Error::custom(format!(
            "expected a number in {} or a string with a unit",
            dim.si_unit()
        ))
    })? {
        NumOrText::Num(v) if v.is_finite() => Ok(v),
        NumOrText::Num(v) => Err(serde::de::Error::custom(format!("{v} is not finite"))),
        NumOrText::Text(s) => parse_quantity(&s, dim).map_err(serde::de::Error::custom),
    }
}

impl<'de> Deserialize<'de> for Length {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        deserialize_quantity(d, Dimension::Length).map(Length)
    }
}

impl<'de> Deserialize<'de> for PerArea {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        deserialize_quantity(d, Dimension::PerArea).map(PerArea)
    }
}

impl std::str::FromStr for Length {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        parse_quantity(s, Dimension::Length).map(Length)
    }
}

impl std::str::FromStr for PerArea {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        parse_quantity(s, Dimension::PerArea).map(PerArea)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_normalise_to_metres() {
        assert_eq!(parse_quantity("5 um", Dimension::Length).unwrap(), 5e-6);
        assert_eq!(
            parse_quantity("0.34nm", Dimension::Length).unwrap(),
            0.34e-9
        );
        assert_eq!(parse_quantity("2e-6", Dimension::Length).unwrap(), 2e-6);
        assert_eq!(parse_quantity("3 Å", Dimension::Length).unwrap(), 3e-10);
        assert!(parse_quantity("5 parsecs", Dimension::Length).is_err());
        assert!(parse_quantity("five um", Dimension::Length).is_err());
    }

    #[test]
    fn signal_quantities_normalise_to_si() {
        assert_eq!(
            parse_quantity("10 kHz", Dimension::Frequency).unwrap(),
            10e3
        );
        assert_eq!(parse_quantity("4 MS/s", Dimension::Frequency).unwrap(), 4e6);
        assert_eq!(parse_quantity("2.5 ms", Dimension::Time).unwrap(), 2.5e-3);
        assert_eq!(
            parse_quantity("25 mm/s/V", Dimension::Sensitivity).unwrap(),
            0.025
        );
        assert_eq!(
            parse_quantity("0.025", Dimension::Sensitivity).unwrap(),
            0.025
        );
        assert!(parse_quantity("10 kg", Dimension::Frequency).is_err());
        assert!(parse_quantity("25 mm/s", Dimension::Sensitivity).is_err());
        assert_eq!(parse_quantity("13 GPa", Dimension::Pressure).unwrap(), 13e9);
        assert_eq!(
            parse_quantity("60 mN/m", Dimension::SurfaceEnergy).unwrap(),
            0.06
        );
    }

    #[test]
    fn areal_density_normalises_to_per_square_metre() {
        assert_eq!(
            parse_quantity("220 um^-2", Dimension::PerArea).unwrap(),
            220e12
        );
        assert_eq!(
            parse_quantity("1.5e-3 mm", Dimension::Length).unwrap(),
            1.5e-6
        );
    }

    #[test]
    fn area_speed_viscosity_normalise_to_si() {
        assert_eq!(
            parse_quantity("2500 um^2", Dimension::Area).unwrap(),
            2500e-12
        );
        assert_eq!(
            parse_quantity("2500 µm²", Dimension::Area).unwrap(),
            2500e-12
        );
        assert_eq!(
            parse_quantity("200 um/s", Dimension::Velocity).unwrap(),
            200e-6
        );
        assert_eq!(parse_quantity("30 m/s", Dimension::Velocity).unwrap(), 30.0);
        assert_eq!(
            parse_quantity("310 mPa s", Dimension::Viscosity).unwrap(),
            0.31
        );
        assert_eq!(
            parse_quantity("0.31 Pa·s", Dimension::Viscosity).unwrap(),
            0.31
        );
        assert!(parse_quantity("2500 um", Dimension::Area).is_err());
        assert!(parse_quantity("3 m", Dimension::Velocity).is_err());
    }
}
