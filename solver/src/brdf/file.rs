//! Reflectance files (Remington 1992, App. F): the Legendre coefficients of one material's lobe.
//!
//! ```text
//! lval <L> Ks <Ks> Kd <Kd>
//! <a_0>
//! <a_1>
//! …
//! <a_L>
//! ```
//!
//! Line 1 is the header, then exactly L + 1 lines with one number each. Blank lines
//! and lines starting with `#` are ignored (an extension: Remington's (1992) files have none), so
//! that a file can carry the α it was made from. Every error names the file, the
//! line and the offending text.

use super::BrdfError;
use std::path::Path;

/// Largest `lval` accepted: checked before anything sized by it is allocated.
/// (L = 4096 is already a lobe of α ≈ 0.002; see `brdf::MIN_ALPHA`.)
pub const MAX_FILE_ORDER: u32 = 4096;

/// The contents of a reflectance file.
#[derive(Clone, Debug, PartialEq)]
pub struct ReflectanceFile {
    /// L: the file holds `a_0 … a_L`.
    pub order: u32,
    pub ks: f64,
    pub kd: f64,
    /// `a_0 … a_L` (Remington 1992, eq. 4.4).
    pub coefficients: Vec<f64>,
}

fn parse_err(path: &Path, line: usize, message: String) -> BrdfError {
    BrdfError::Parse {
        path: path.to_path_buf(),
        line,
        message,
    }
}

fn parse_number(path: &Path, line: usize, what: &str, text: &str) -> Result<f64, BrdfError> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(v) => Err(parse_err(path, line, format!("{what} = {v} is not finite"))),
        Err(_) => Err(parse_err(
            path,
            line,
            format!("{what}: expected a number, found `{text}`"),
        )),
    }
}

/// Parses reflectance-file text; `path` is used in error messages only.
pub fn parse_reflectance(path: &Path, text: &str) -> Result<ReflectanceFile, BrdfError> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let (line, header) = lines.next().ok_or_else(|| {
        parse_err(
            path,
            1,
            "empty file: expected `lval <L> Ks <Ks> Kd <Kd>`".into(),
        )
    })?;
    let tokens: Vec<&str> = header.split_whitespace().collect();
    let expect = "expected `lval <L> Ks <Ks> Kd <Kd>`";
    if tokens.len() != 6
        || !tokens[0].eq_ignore_ascii_case("lval")
        || !tokens[2].eq_ignore_ascii_case("ks")
        || !tokens[4].eq_ignore_ascii_case("kd")
    {
        return Err(parse_err(path, line, format!("{expect}, found `{header}`")));
    }
    let order: u32 = tokens[1].parse().map_err(|_| {
        parse_err(
            path,
            line,
            format!("lval: expected a whole number, found `{}`", tokens[1]),
        )
    })?;
    if order > MAX_FILE_ORDER {
        return Err(parse_err(
            path,
            line,
            format!("lval = {order} exceeds the maximum {MAX_FILE_ORDER}"),
        ));
    }
    let ks = parse_number(path, line, "Ks", tokens[3])?;
    let kd = parse_number(path, line, "Kd", tokens[5])?;
    for (name, v) in [("Ks", ks), ("Kd", kd)] {
        if v < 0.0 {
            return Err(parse_err(path, line, format!("{name} = {v} is negative")));
        }
    }
    let mut coefficients = Vec::with_capacity(order as usize + 1);
    let mut last_line = line;
    for l in 0..=order {
        let (line, text) = lines.next().ok_or_else(|| {
            parse_err(
                path,
                last_line + 1,
                format!(
                    "file ends after a_{}: lval {order} needs {} coefficients",
                    l as i64 - 1,
                    order + 1
                ),
            )
        })?;
        let mut parts = text.split_whitespace();
        let value = parts.next().unwrap_or("");
        if let Some(extra) = parts.next() {
            return Err(parse_err(
                path,
                line,
                format!("a_{l}: one number per line, found also `{extra}`"),
            ));
        }
        coefficients.push(parse_number(path, line, &format!("a_{l}"), value)?);
        last_line = line;
    }
    if let Some((line, text)) = lines.next() {
        return Err(parse_err(
            path,
            line,
            format!(
                "unexpected `{text}` after a_{order} (lval {order} means {} coefficients)",
                order + 1
            ),
        ));
    }
    Ok(ReflectanceFile {
        order,
        ks,
        kd,
        coefficients,
    })
}

/// Reads and parses a reflectance file.
pub fn read_reflectance_file(path: &Path) -> Result<ReflectanceFile, BrdfError> {
    let text = std::fs::read_to_string(path).map_err(|source| BrdfError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_reflectance(path, &text)
}

/// The file's text: numbers in Rust's shortest round-trip form, so reading it back
/// gives the same f64 bits.
pub fn format_reflectance(file: &ReflectanceFile) -> String {
    let mut s = format!("lval {} Ks {:e} Kd {:e}\n", file.order, file.ks, file.kd);
    for a in &file.coefficients {
        s.push_str(&format!("{a:e}\n"));
    }
    s
}

/// Writes a reflectance file atomically ([`solution::atomic::write_atomically`]),
/// so a crash never leaves a half file.
/// `file.coefficients.len()` must be `order + 1` (checked).
pub fn write_reflectance_file(path: &Path, file: &ReflectanceFile) -> Result<(), BrdfError> {
    let io = |source| BrdfError::Io {
        path: path.to_path_buf(),
        source,
    };
    if file.coefficients.len() != file.order as usize + 1 {
        return Err(io(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "lval {} needs {} coefficients, got {}",
                file.order,
                file.order + 1,
                file.coefficients.len()
            ),
        )));
    }
    solution::atomic::write_bytes_atomically(path, format_reflectance(file).as_bytes())
        .map_err(|e| io(e.source))
}
