//! MTL material libraries.
//!
//! Parsed here rather than by `tobj` because every warning and error must name
//! the `newmtl` line (design notes, "Units and conventions"), which `tobj` does not
//! record, and because `tobj` 4 panics on the legal one-value form `Kd 0.5`.
//!
//! Meaning of the keys (design notes): `Kd` diffuse reflectance, `Ks` reflectance
//! of the glossy lobe, `Ke` emitted radiance (W·sr⁻¹·m⁻², one-sided), and `Ns`
//! the Phong exponent, converted to the RMS slope of Remington 1992, eq. 4.1 by
//! α = sqrt(2 / (Ns + 2)). Every other key (textures, `Ka`, `d`, `illum`, PBR
//! extensions) is read past: radiosity uses none of them.

use super::raw::{RawMaterial, DEFAULT_KD};
use super::text::{numbered_lines, parse_real};
use super::{SceneError, SourceRef};
use glam::DVec3;
use std::path::Path;

/// α from a Phong exponent: α = sqrt(2 / (Ns + 2)) (design notes). Ns = 0 gives
/// α = 1, the broadest lobe; Ns = 198 gives α = 0.1.
pub fn alpha_from_ns(ns: f64) -> f64 {
    (2.0 / (ns + 2.0)).sqrt()
}

/// Parses an MTL file's text. Materials come back in file order; a name defined
/// twice keeps both entries and the later one wins lookups (as in `tobj`).
pub(crate) fn parse_mtl(path: &Path, text: &str) -> Result<Vec<RawMaterial>, SceneError> {
    let mut materials: Vec<RawMaterial> = Vec::new();
    for (line_no, line) in numbered_lines(text) {
        let content = line.split('#').next().unwrap_or("");
        let tokens: Vec<&str> = content.split_whitespace().collect();
        let Some(&key) = tokens.first() else {
            continue;
        };
        let err = |item: &str, message: String| {
            SceneError::at(path, Some(line_no), item.to_owned(), message)
        };
        if key == "newmtl" {
            let name = tokens[1..].join(" ");
            if name.is_empty() {
                return Err(err("", "`newmtl` without a material name".to_owned()));
            }
            materials.push(RawMaterial {
                name: name.clone(),
                aliases: Vec::new(),
                kd: DVec3::splat(DEFAULT_KD),
                ks: DVec3::ZERO,
                alpha: 1.0,
                emission: DVec3::ZERO,
                source: SourceRef {
                    file: path.to_path_buf(),
                    line: Some(line_no),
                    item: format!("material {name}"),
                },
                overridden_at: None,
                undefined: None,
            });
            continue;
        }
        let is_used_key = matches!(key, "Kd" | "Ks" | "Ke" | "Ns");
        let Some(current) = materials.last_mut() else {
            if is_used_key {
                return Err(err(
                    "",
                    format!("`{key}` before any `newmtl`: it belongs to no material"),
                ));
            }
            continue;
        };
        let item = format!("material {}", current.name);
        match key {
            "Kd" | "Ks" | "Ke" => {
                let what = match key {
                    "Kd" => "Kd (diffuse reflectance)",
                    "Ks" => "Ks (glossy reflectance)",
                    _ => "Ke (emitted radiance)",
                };
                let value = parse_colour(&tokens[1..], what).map_err(|m| err(&item, m))?;
                if value.min_element() < 0.0 {
                    return Err(err(
                        &item,
                        format!("{what} must not be negative: {}", tokens[1..].join(" ")),
                    ));
                }
                match key {
                    "Kd" => current.kd = value,
                    "Ks" => current.ks = value,
                    _ => current.emission = value,
                }
            }
            "Ns" => {
                let [token] = tokens[1..] else {
                    return Err(err(
                        &item,
                        format!("Ns takes one number, found {} values", tokens.len() - 1),
                    ));
                };
                let ns = parse_real(token, "Ns (Phong exponent)").map_err(|m| err(&item, m))?;
                if ns < 0.0 {
                    return Err(err(&item, format!("Ns must not be negative: {token}")));
                }
                current.alpha = alpha_from_ns(ns);
            }
            _ => {}
        }
    }
    Ok(materials)
}

/// `r g b` or the one-value grey form `r`. The CIE `xyz` and `spectral` forms
/// are refused by name rather than misread as numbers.
fn parse_colour(tokens: &[&str], what: &str) -> Result<DVec3, String> {
    match tokens {
        [first, ..] if *first == "spectral" || *first == "xyz" => Err(format!(
            "{what}: the `{first}` colour form is not supported; give linear RGB `r g b`"
        )),
        [grey] => Ok(DVec3::splat(parse_real(grey, what)?)),
        [r, g, b] => Ok(DVec3::new(
            parse_real(r, &format!("{what} red"))?,
            parse_real(g, &format!("{what} green"))?,
            parse_real(b, &format!("{what} blue"))?,
        )),
        _ => Err(format!(
            "{what}: expected `r g b` or one grey value, found {} values",
            tokens.len()
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Vec<RawMaterial>, SceneError> {
        parse_mtl(Path::new("lib.mtl"), text)
    }

    #[test]
    fn reads_the_radiometric_keys_and_records_the_newmtl_line() {
        let m = parse(
            "# comment\n\nnewmtl white\nKd 0.725 0.71 0.68\nKs 0 0 0\n\
             map_Kd tex.png\nnewmtl glossy\n\tKd 0.2\n\tKs 0.5 0.5 0.5\n\tNs 198\nillum 2\n\
             newmtl lamp\nKe 17 12 4\n",
        )
        .unwrap();
        assert_eq!(m.len(), 3);
        assert_eq!(m[0].name, "white");
        assert_eq!(m[0].kd, DVec3::new(0.725, 0.71, 0.68));
        assert_eq!(m[0].source.line, Some(3));
        assert_eq!(m[1].kd, DVec3::splat(0.2));
        assert_eq!(m[1].source.line, Some(7));
        // α = sqrt(2 / (198 + 2)) = 0.1 exactly in decimal; f64 rounding only.
        assert!((m[1].alpha - 0.1).abs() < 1e-15);
        assert_eq!(m[2].emission, DVec3::new(17.0, 12.0, 4.0));
        assert_eq!(m[2].kd, DVec3::splat(DEFAULT_KD));
    }

    #[test]
    fn alpha_from_ns_matches_the_formula_at_its_ends() {
        assert_eq!(alpha_from_ns(0.0), 1.0);
        // Ns → ∞ is a mirror: α → 0 as sqrt(2 / Ns).
        let a = alpha_from_ns(2.0e6);
        assert!((a - (2.0f64 / 2.000002e6).sqrt()).abs() < 1e-18);
    }

    #[test]
    fn malformed_lines_name_file_line_and_material() {
        let cases = [
            ("newmtl a\nKd 0.5 0.5\n", 2, "expected `r g b`"),
            ("newmtl a\nKd 0.5 x 0.5\n", 2, "green"),
            ("newmtl a\nKs -0.1 0 0\n", 2, "must not be negative"),
            ("newmtl a\nKe nan 1 1\n", 2, "not a finite"),
            ("newmtl a\nNs\n", 2, "Ns takes one number"),
            ("newmtl a\nNs -3\n", 2, "Ns must not be negative"),
            ("Kd 1 1 1\nnewmtl a\n", 1, "before any `newmtl`"),
            ("newmtl a\nKd spectral file.spd\n", 2, "not supported"),
            ("newmtl\n", 1, "without a material name"),
        ];
        for (text, line, fragment) in cases {
            let err = parse(text).unwrap_err();
            let message = err.to_string();
            assert!(message.starts_with(&format!("lib.mtl:{line}")), "{message}");
            assert!(message.contains(fragment), "{message}");
            if line == 2 {
                assert!(message.contains("(material a)"), "{message}");
            }
        }
    }
}
