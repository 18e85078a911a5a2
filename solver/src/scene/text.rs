//! Small text helpers shared by the line-oriented parsers: reading a file,
//! numbering lines and parsing numbers with messages that say what was expected.

use super::SceneError;
use std::path::Path;

/// Reads a whole input file. Invalid UTF-8 (Latin-1 comments from old exporters)
/// is replaced rather than refused: every keyword and number is ASCII.
pub(crate) fn read_text(path: &Path) -> Result<String, SceneError> {
    #[allow(clippy::disallowed_methods)] // An edge: an importer reads its scene file.
    let bytes = std::fs::read(path).map_err(|e| SceneError::io(path, e))?;
    let mut text = String::from_utf8_lossy(&bytes).into_owned();
    if text.starts_with('\u{feff}') {
        // A byte-order mark is not part of the first keyword.
        text.replace_range(..'\u{feff}'.len_utf8(), "");
    }
    Ok(text)
}

/// The lines of `text` with 1-based numbers; `\r` of CRLF files is dropped.
pub(crate) fn numbered_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.split('\n')
        .enumerate()
        .map(|(i, line)| (i + 1, line.strip_suffix('\r').unwrap_or(line)))
}

/// The 1-based line that byte `offset` of `text` lies on.
pub(crate) fn line_of_offset(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// Parses a finite real number; the message names what the number was for.
pub(crate) fn parse_real(token: &str, what: &str) -> Result<f64, String> {
    match token.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(v) => Err(format!("{what} is not a finite number: `{token}` ({v})")),
        Err(_) => Err(format!("{what}: expected a number, found `{token}`")),
    }
}

/// As [`parse_real`], building the description only when there is an error (the
/// OBJ reader parses millions of numbers).
pub(crate) fn parse_real_lazy(token: &str, what: impl FnOnce() -> String) -> Result<f64, String> {
    match token.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => parse_real(token, &what()),
    }
}

/// Parses a non-negative integer that fits `u32`.
pub(crate) fn parse_count(token: &str, what: &str) -> Result<u64, String> {
    token
        .parse::<u64>()
        .map_err(|_| format!("{what}: expected a non-negative integer, found `{token}`"))
}

/// Parses three finite reals from `tokens`, naming the component on error.
pub(crate) fn parse_vec3(tokens: &[&str], what: &str) -> Result<[f64; 3], String> {
    if tokens.len() < 3 {
        return Err(format!(
            "{what}: expected 3 numbers, found {}",
            tokens.len()
        ));
    }
    let mut out = [0.0; 3];
    for (k, (slot, token)) in out.iter_mut().zip(tokens).enumerate() {
        *slot = parse_real(token, &format!("{what} component {}", ["x", "y", "z"][k]))?;
    }
    Ok(out)
}

/// Formats an RGB triple compactly for messages.
pub(crate) fn rgb(v: glam::DVec3) -> String {
    format!("({}, {}, {})", short(v.x), short(v.y), short(v.z))
}

/// A number with at most 4 significant decimals, for messages.
pub(crate) fn short(x: f64) -> String {
    let s = format!("{x:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.is_empty() || s == "-" {
        "0".to_owned()
    } else {
        s.to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_map_to_lines() {
        let text = "a\nbb\n\nccc";
        assert_eq!(line_of_offset(text, 0), 1);
        assert_eq!(line_of_offset(text, 2), 2);
        assert_eq!(line_of_offset(text, 5), 3);
        assert_eq!(line_of_offset(text, 6), 4);
        assert_eq!(line_of_offset(text, 1000), 4);
    }

    #[test]
    fn numbers_are_checked() {
        assert_eq!(parse_real("1.5", "x"), Ok(1.5));
        assert!(parse_real("nan", "x").unwrap_err().contains("not a finite"));
        assert!(parse_real("inf", "x").unwrap_err().contains("not a finite"));
        assert!(parse_real("1e999", "x")
            .unwrap_err()
            .contains("not a finite"));
        assert!(parse_real("abc", "x")
            .unwrap_err()
            .contains("expected a number"));
        assert_eq!(short(0.5), "0.5");
        assert_eq!(short(1.0), "1");
        assert_eq!(short(0.76923), "0.7692");
    }
}
