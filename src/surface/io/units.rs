//! Length units as AFM software writes them, and small text helpers shared by the readers.

/// Metres per unit for the length units AFM software writes; `None` if not a length.
/// `~m` is NanoScope's spelling of µm; both the micro sign (U+00B5) and Greek mu are accepted.
pub(crate) fn length_factor(unit: &str) -> Option<f64> {
    crate::units::length_factor(unit)
}

/// Parses `"<number> <unit>"` (e.g. `12.34 µm`) into metres.
pub(crate) fn parse_length(text: &str) -> Option<f64> {
    let text = text.trim();
    let split = text.find(|c: char| c.is_whitespace()).unwrap_or(text.len());
    let value: f64 = text[..split].parse().ok()?;
    let metres = value * length_factor(&text[split..])?;
    metres.is_finite().then_some(metres)
}

/// Text of a file: UTF-8 if it is valid UTF-8 (BOM stripped), else latin-1 (old instrument
/// software writes `µ` as the single byte 0xB5).
pub(crate) fn decode_text(bytes: &[u8]) -> String {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match std::str::from_utf8(bytes) {
        Ok(text) => text.to_string(),
        Err(_) => bytes.iter().map(|&b| b as char).collect(),
    }
}

/// The text of a fixed-size, NUL-padded binary field, trimmed (latin-1 for non-ASCII bytes).
pub(crate) fn nul_terminated(field: &[u8]) -> String {
    let end = field.iter().position(|&c| c == 0).unwrap_or(field.len());
    field[..end]
        .iter()
        .map(|&c| c as char)
        .collect::<String>()
        .trim()
        .to_string()
}

/// Parses a numeric token; `NaN`/`nan` (and infinities) become NaN = invalid pixel.
pub(crate) fn parse_value(token: &str) -> Option<f64> {
    let value: f64 = token.parse().ok()?;
    Some(if value.is_finite() { value } else { f64::NAN })
}

/// Splits a data line on whitespace, commas and semicolons.
pub(crate) fn tokens(line: &str) -> impl Iterator<Item = &str> {
    line.split(|c: char| c.is_whitespace() || c == ',' || c == ';')
        .filter(|t| !t.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(got: Option<f64>, want: f64) -> bool {
        got.is_some_and(|g| (g - want).abs() <= 1e-15 * want.abs())
    }

    #[test]
    fn lengths() {
        assert!(close(parse_length("12.5 µm"), 12.5e-6));
        assert!(close(parse_length("2 ~m"), 2e-6));
        assert!(close(parse_length("5678.9 nm"), 5678.9e-9));
        assert!(close(parse_length("3 Å"), 3e-10));
        assert_eq!(parse_length("3 V"), None);
        assert_eq!(parse_length("abc m"), None);
        assert_eq!(parse_length(""), None);
        assert_eq!(decode_text(b"1 \xB5m"), "1 µm");
    }
}
