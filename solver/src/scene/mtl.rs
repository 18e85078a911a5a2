//! MTL material libraries.
//!
//! Parsed here rather than by `tobj` because every warning and error must name
//! the `newmtl` line (design notes, "Units and conventions"), which `tobj` does not
//! record, and because `tobj` 4 panics on the legal one-value form `Kd 0.5`.
//!
//! Meaning of the keys (design notes): `Kd` diffuse reflectance, `Ks` reflectance
//! of the glossy lobe, `Ke` emitted radiance (W·sr⁻¹·m⁻², one-sided), and `Ns`
//! the Phong exponent, converted to the RMS slope of Remington 1992, eq. 4.1 by
//! α = sqrt(2 / (Ns + 2)). `map_Kd` names the diffuse texture, which
//! multiplies Kd (the MTL convention: the reflectance is Kd ⊙ texture, so
//! `Kd 0.1` with a texture is a dark surface, as the file says); its options
//! are read past, with a warning for those that change the mapping. Every
//! other key (other textures, `Ka`, `d`, `illum`, PBR extensions) is read
//! past: radiosity uses none of them.
//!
//! Statements that change how an authored surface looks but that the solver does
//! not model (other textures, bump maps, transparency, refraction, mirror and glass
//! `illum` models) give a warning, once per material and kind of statement, at the
//! first such line, saying what the solver does instead ([`unmodelled`]). Keys
//! that change nothing radiosity computes (`Ka`, which the solve replaces;
//! `illum` 0–2, the diffuse and Phong models the solver follows) stay silent, as
//! do opaque `d 1` and `Tr 0`, which say what the solver does anyway.

use super::clean::emission_problem;
use super::raw::{RawMaterial, DEFAULT_KD};
use super::text::{numbered_lines, parse_real};
use super::{SceneError, SourceRef, Warning};
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
    // The kinds the current material has already been warned about.
    let mut warned: Vec<Unmodelled> = Vec::new();
    // Per material, whether a `Ke` line gave its emission (see
    // [`emission_map_convention`]).
    let mut ke_given: Vec<bool> = Vec::new();
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
                unread_reflectance_file: None,
                unmodelled: Vec::new(),
                diffuse_map: None,
                diffuse_bytes: None,
                emission_map: None,
                emission_bytes: None,
                metal_map: None,
                unlit: false,
            });
            ke_given.push(false);
            warned.clear();
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
        if key == "map_Kd" || key == "map_Ke" {
            let source = SourceRef {
                file: path.to_path_buf(),
                line: Some(line_no),
                item: item.clone(),
            };
            match texture_argument(&tokens[1..]) {
                Ok((file, ignored)) => {
                    let dir = path.parent().unwrap_or(Path::new(""));
                    let map = Some((dir.join(file), source.clone()));
                    if key == "map_Kd" {
                        current.diffuse_map = map;
                    } else {
                        current.emission_map = map;
                    }
                    if let Some(option) = ignored {
                        current.unmodelled.push(Warning {
                            source: source.clone(),
                            message: format!(
                                "`{}`: the option `{option}` is not modelled; the texture is \
                                 used with u and v as given",
                                quoted(&tokens)
                            ),
                        });
                    }
                }
                Err(why) => current.unmodelled.push(Warning {
                    source,
                    message: format!(
                        "`{}`: {why}; the flat {} is used",
                        quoted(&tokens),
                        &key[4..]
                    ),
                }),
            }
            continue;
        }
        if let Some((kind, message)) = unmodelled(key, &tokens[1..]) {
            if !warned.contains(&kind) {
                warned.push(kind);
                current.unmodelled.push(Warning {
                    source: SourceRef {
                        file: path.to_path_buf(),
                        line: Some(line_no),
                        item: item.clone(),
                    },
                    message: format!("`{}`: {message}", quoted(&tokens)),
                });
            }
            continue;
        }
        let ke_line = set_value(current, key, &tokens[1..]).map_err(|m| err(&item, m))?;
        if ke_line {
            if let Some(given) = ke_given.last_mut() {
                *given = true;
            }
        }
    }
    for (material, &given) in materials.iter_mut().zip(&ke_given) {
        emission_map_convention(material, given);
    }
    Ok(materials)
}

/// Applies a `Kd`, `Ks`, `Ke` or `Ns` statement (arguments `args`) to the
/// current material; other keys change nothing. Returns whether it was a `Ke`
/// line, which decides what a `map_Ke` multiplies.
fn set_value(current: &mut RawMaterial, key: &str, args: &[&str]) -> Result<bool, String> {
    match key {
        "Kd" | "Ks" | "Ke" => {
            let what = match key {
                "Kd" => "Kd (diffuse reflectance)",
                "Ks" => "Ks (glossy reflectance)",
                _ => "Ke (emitted radiance)",
            };
            let value = parse_colour(args, what)?;
            if value.min_element() < 0.0 {
                return Err(format!("{what} must not be negative: {}", args.join(" ")));
            }
            if key == "Ke" {
                if let Some(problem) = emission_problem(value) {
                    return Err(format!("{what} {problem}"));
                }
            }
            match key {
                "Kd" => current.kd = value,
                "Ks" => current.ks = value,
                _ => {
                    current.emission = value;
                    return Ok(true);
                }
            }
        }
        "Ns" => {
            let [token] = args else {
                return Err(format!("Ns takes one number, found {} values", args.len()));
            };
            let ns = parse_real(token, "Ns (Phong exponent)")?;
            if ns < 0.0 {
                return Err(format!("Ns must not be negative: {token}"));
            }
            current.alpha = alpha_from_ns(ns);
        }
        _ => {}
    }
    Ok(false)
}

/// The emission a `map_Ke` multiplies (docs/textures.md, "Emissive
/// textures"). Le = Ke ⊙ texture, as `Kd` multiplies `map_Kd`; Blender
/// writes `Ke 1 1 1` beside `map_Ke`. A `map_Ke` without any `Ke` line
/// means the texture alone (Ke 1 1 1), and `Ke 0 0 0` with `map_Ke` is taken
/// at its word (the surface does not emit); both are warned, naming the
/// `map_Ke` line, since either could be an exporter's slip.
fn emission_map_convention(material: &mut RawMaterial, ke_given: bool) {
    let Some((file, at)) = &material.emission_map else {
        return;
    };
    let message = if !ke_given {
        material.emission = DVec3::ONE;
        format!(
            "map_Ke {} without a `Ke` line: Ke 1 1 1 is assumed, so the surface emits the \
             texture's radiance (W·sr⁻¹·m⁻², the texture decoded from sRGB)",
            file.display()
        )
    } else if material.emission == DVec3::ZERO {
        format!(
            "map_Ke {} with Ke 0 0 0: Ke multiplies the texture, so the surface does not emit; \
             set Ke 1 1 1 if the texture alone is meant",
            file.display()
        )
    } else {
        return;
    };
    material.unmodelled.push(Warning {
        source: at.clone(),
        message,
    });
}

/// A kind of MTL statement that the solver reads but does not model. A material
/// is warned about once per kind: two `map_Kd` lines, or `d` and `map_d`, are one
/// warning.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Unmodelled {
    Bump,
    Transparency,
    RefractiveIndex,
    IlluminationModel,
    SpecularTexture,
    ExponentTexture,
    ReflectionMap,
}

/// Whether the statement `key args` is one the solver does not model, and if so
/// its kind and what the solver does instead. `None` for the keys the solver uses
/// and for those that change nothing it computes (see the module notes).
fn unmodelled(key: &str, args: &[&str]) -> Option<(Unmodelled, String)> {
    use Unmodelled::*;
    let single = |args: &[&str]| match args {
        [value] => value.parse::<f64>().ok(),
        _ => None,
    };
    let found = match key {
        "map_Bump" | "map_bump" | "bump" => (
            Bump,
            "bump maps are not modelled; the surface's geometric (or smooth-group) \
             normal is used"
                .to_owned(),
        ),
        "d" if single(args) == Some(1.0) => return None,
        "Tr" if single(args) == Some(0.0) => return None,
        "d" | "Tr" | "map_d" => (
            Transparency,
            "transparency is not modelled; the surface is opaque (note that exporters \
             disagree on `Tr`: most write Tr = 1 − d, some write d)"
                .to_owned(),
        ),
        "Ni" => (
            RefractiveIndex,
            "the index of refraction is not modelled (no refraction, no Fresnel term); \
             reflectance is Kd and Ks at every angle"
                .to_owned(),
        ),
        "illum" => {
            let model = match args {
                [value] => value.parse::<u32>().ok(),
                _ => None,
            };
            let what = match model {
                Some(0..=2) => return None,
                Some(3) => "illumination model 3 (ray-traced mirror reflection)",
                Some(4) => "illumination model 4 (glass: ray-traced reflection and transparency)",
                Some(5) => "illumination model 5 (Fresnel mirror reflection)",
                Some(6) => "illumination model 6 (refraction)",
                Some(7) => "illumination model 7 (refraction with Fresnel reflection)",
                Some(8) => "illumination model 8 (mirror reflection without ray tracing)",
                Some(9) => "illumination model 9 (glass without ray tracing)",
                Some(10) => "illumination model 10 (shadows cast onto invisible surfaces)",
                _ => "an illumination model outside 0–10",
            };
            (
                IlluminationModel,
                format!(
                    "{what} is not modelled; the surface is opaque, reflecting Kd diffusely \
                     and, in directional mode, Ks as the glossy lobe of Ns \
                     (Remington 1992, eq. 4.1): no mirror images, no transmission"
                ),
            )
        }
        "map_Ks" => (
            SpecularTexture,
            "specular textures are not modelled; the flat Ks is used".to_owned(),
        ),
        "map_Ns" => (
            ExponentTexture,
            "exponent textures are not modelled; the flat Ns is used".to_owned(),
        ),
        "refl" => (
            ReflectionMap,
            "reflection maps are not modelled; reflections come only from the scene's \
             own surfaces"
                .to_owned(),
        ),
        _ => return None,
    };
    Some(found)
}

/// The statement as written, shortened to 80 characters so that a hostile line
/// does not flood the terminal.
fn quoted(tokens: &[&str]) -> String {
    const MAX: usize = 80;
    let text = tokens.join(" ");
    if text.chars().count() <= MAX {
        return text;
    }
    let short: String = text.chars().take(MAX).collect();
    format!("{short}…")
}

/// The file a texture statement names, after its options (Wavefront MTL:
/// `-blendu`, `-blendv`, `-cc`, `-clamp`, `-imfchan`, `-texres`, `-bm`,
/// `-boost` take one value, `-mm` two, `-o`, `-s`, `-t` one to three numbers),
/// and the first option that changes the mapping (`-o`, `-s`, `-t`,
/// `-clamp on`, `-mm`, `-cc on`), which is not modelled.
fn texture_argument(args: &[&str]) -> Result<(String, Option<String>), String> {
    let mut k = 0;
    let mut ignored = None;
    while k < args.len() && args[k].starts_with('-') {
        let option = args[k];
        let count = match option {
            "-blendu" | "-blendv" | "-cc" | "-clamp" | "-imfchan" | "-texres" | "-bm"
            | "-boost" => 1,
            "-mm" => 2,
            "-o" | "-s" | "-t" => args[k + 1..]
                .iter()
                .take(3)
                .take_while(|a| a.parse::<f64>().is_ok())
                .count(),
            _ => return Err(format!("unknown texture option `{option}`")),
        };
        let values = args.get(k + 1..k + 1 + count).unwrap_or(&[]);
        let changes = match option {
            "-o" => values.iter().any(|v| v.parse::<f64>() != Ok(0.0)),
            "-s" => values.iter().any(|v| v.parse::<f64>() != Ok(1.0)),
            "-t" | "-mm" => true,
            "-clamp" | "-cc" => values.first() == Some(&"on"),
            _ => false,
        };
        if changes && ignored.is_none() {
            ignored = Some(
                std::iter::once(option)
                    .chain(values.iter().copied())
                    .collect::<Vec<_>>()
                    .join(" "),
            );
        }
        k += 1 + count;
    }
    let file = args.get(k..).unwrap_or(&[]).join(" ");
    if file.is_empty() {
        return Err("no texture file named".to_owned());
    }
    Ok((file, ignored))
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

    /// Every unmodelled statement once, in two materials; the second material
    /// gives them in another order and on other lines.
    const EVERY_STATEMENT: &str = "newmtl first\n\
        Kd 0.5\n\
        map_Bump -bm 0.5 normal.png\n\
        d 0.5\n\
        Ni 1.45\n\
        illum 4\n\
        map_Ks spec.png\n\
        map_Ns rough.png\n\
        refl -type sphere env.png\n\
        map_Kd wall.png\n\
        map_Ke screen.png\n\
        newmtl second\n\
        map_Ke screen.png\n\
        map_Kd wall.png\n\
        refl -type sphere env.png\n\
        map_Ns rough.png\n\
        map_Ks spec.png\n\
        illum 7\n\
        Ni 1.5\n\
        Tr 0.25\n\
        bump bump.png\n";

    /// (material, kind's key as first written, line, words the message must hold).
    const EXPECTED: [(usize, &str, usize, &str); 14] = [
        (0, "map_Bump -bm 0.5 normal.png", 3, "normal is used"),
        (0, "d 0.5", 4, "opaque"),
        (0, "Ni 1.45", 5, "refraction"),
        (0, "illum 4", 6, "glass"),
        (0, "map_Ks spec.png", 7, "flat Ks"),
        (0, "map_Ns rough.png", 8, "flat Ns"),
        (0, "refl -type sphere env.png", 9, "reflection maps"),
        (1, "refl -type sphere env.png", 15, "own surfaces"),
        (1, "map_Ns rough.png", 16, "not modelled"),
        (1, "map_Ks spec.png", 17, "not modelled"),
        (1, "illum 7", 18, "refraction with Fresnel"),
        (1, "Ni 1.5", 19, "Fresnel"),
        (1, "Tr 0.25", 20, "opaque"),
        (1, "bump bump.png", 21, "bump maps"),
    ];

    #[test]
    fn every_unmodelled_statement_warns_once_per_material_naming_file_and_line() {
        let m = parse(EVERY_STATEMENT).unwrap();
        assert_eq!(m.len(), 2);
        // Seven kinds each: bump, transparency, Ni, illum, map_Ks, map_Ns,
        // refl; `map_Kd` and `map_Ke` are modelled (read as the diffuse and
        // emission textures), and the eighth warning is `map_Ke` without `Ke`.
        assert_eq!(m[0].unmodelled.len(), 8, "{:?}", m[0].unmodelled);
        assert_eq!(m[1].unmodelled.len(), 8, "{:?}", m[1].unmodelled);
        for (material, ke_line) in m.iter().zip([11, 13]) {
            let (file, at) = material.diffuse_map.as_ref().unwrap();
            assert_eq!(file, Path::new("wall.png"));
            assert!(at.line.is_some());
            let (file, at) = material.emission_map.as_ref().unwrap();
            assert_eq!(file, Path::new("screen.png"));
            assert_eq!(at.line, Some(ke_line));
            assert_eq!(material.emission, DVec3::ONE);
            let w = material.unmodelled.last().unwrap();
            assert_eq!(w.source.line, Some(ke_line));
            assert!(w.message.contains("without a `Ke` line"), "{w}");
        }
        for (material, statement, line, words) in EXPECTED {
            let hits: Vec<&Warning> = m[material]
                .unmodelled
                .iter()
                .filter(|w| w.message.starts_with(&format!("`{statement}`")))
                .collect();
            assert_eq!(hits.len(), 1, "{statement}: {:?}", m[material].unmodelled);
            let w = hits[0];
            let name = ["first", "second"][material];
            assert_eq!(
                w.to_string().split(": ").next().unwrap(),
                format!("lib.mtl:{line} (material {name})")
            );
            assert!(w.message.contains(words), "{w}");
        }
        // The flat values the warnings promise are the ones read.
        assert_eq!(m[0].kd, DVec3::splat(0.5));
    }

    #[test]
    fn a_repeated_kind_warns_once_at_its_first_line() {
        let m = parse(
            "newmtl wall\nmap_Kd a.png\nKd 0.1\nmap_Kd b.png\nd 0.5\nmap_d alpha.png\nTr 0.5\n\
             illum 3\nillum 5\nnewmtl other\nmap_Kd a.png\n",
        )
        .unwrap();
        let lines: Vec<(Option<usize>, &str)> = m[0]
            .unmodelled
            .iter()
            .map(|w| (w.source.line, w.message.split('`').nth(1).unwrap()))
            .collect();
        // `d`, `map_d` and `Tr` are one kind (transparency), as are the two `illum`s.
        assert_eq!(lines, [(Some(5), "d 0.5"), (Some(8), "illum 3")]);
        // The later `map_Kd` wins, as later `Kd` lines do.
        assert_eq!(m[0].diffuse_map.as_ref().unwrap().0, Path::new("b.png"));
        // A new material starts afresh.
        assert!(m[1].unmodelled.is_empty());
        assert_eq!(m[1].diffuse_map.as_ref().unwrap().0, Path::new("a.png"));
    }

    /// `map_Ke` multiplies Ke: a stated Ke is kept silently, `Ke 0 0 0` is
    /// kept (no emission) with a warning, a missing Ke becomes 1 1 1 with a
    /// warning; both warnings name the `map_Ke` line.
    #[test]
    fn map_ke_multiplies_ke_and_a_missing_or_zero_ke_is_warned() {
        let m = parse(
            "newmtl screen\nKe 2 2 2\nmap_Ke -o 0 0 s.png\n\
             newmtl off\nmap_Ke s.png\nKe 0 0 0\n\
             newmtl bare\nKd 0.5\nmap_Ke dir/s.png\n",
        )
        .unwrap();
        assert_eq!(m[0].emission, DVec3::splat(2.0));
        assert!(m[0].unmodelled.is_empty(), "{:?}", m[0].unmodelled);
        assert_eq!(m[0].emission_map.as_ref().unwrap().0, Path::new("s.png"));
        assert_eq!(m[1].emission, DVec3::ZERO);
        let w = &m[1].unmodelled[0];
        assert_eq!(w.source.line, Some(5));
        assert!(w.message.contains("does not emit"), "{w}");
        assert_eq!(m[2].emission, DVec3::ONE);
        let w = &m[2].unmodelled[0];
        assert_eq!(
            w.to_string().split(": ").next().unwrap(),
            "lib.mtl:9 (material bare)"
        );
        assert!(w.message.contains("Ke 1 1 1 is assumed"), "{w}");
        assert_eq!(
            m[2].emission_map.as_ref().unwrap().0,
            Path::new("dir/s.png")
        );
    }

    #[test]
    fn modelled_opaque_and_unknown_statements_stay_silent() {
        let m = parse(
            "map_Kd before_any_material.png\nnewmtl plain\nKa 1 1 1\nKd 0.5\nKs 0.1\nNs 10\n\
             illum 0\nillum 1\nillum 2\nd 1\nd 1.000000\nTr 0\nmap_Ka amb.png\nPr 0.5\n\
             Pm 0\nnorm n.png\ndisp d.png\nsharpness 60\n",
        )
        .unwrap();
        assert_eq!(m.len(), 1);
        assert!(m[0].unmodelled.is_empty(), "{:?}", m[0].unmodelled);
    }

    #[test]
    fn texture_options_are_read_past_and_mapping_changes_warned() {
        let m = parse(
            "newmtl a\nmap_Kd -blendu on -bm 1 my wall.png\nnewmtl b\nmap_Kd -s 2 2 1 -o 0 0 t.jpg\n\
             newmtl c\nmap_Kd -s 1 1 1 plain.png\nnewmtl d\nmap_Kd -nonsense x.png\n",
        )
        .unwrap();
        assert_eq!(
            m[0].diffuse_map.as_ref().unwrap().0,
            Path::new("my wall.png")
        );
        assert!(m[0].unmodelled.is_empty(), "{:?}", m[0].unmodelled);
        assert_eq!(m[1].diffuse_map.as_ref().unwrap().0, Path::new("t.jpg"));
        assert!(m[1].unmodelled[0]
            .message
            .contains("`-s 2 2 1` is not modelled"));
        assert!(m[2].unmodelled.is_empty());
        assert!(m[3].diffuse_map.is_none());
        assert!(m[3].unmodelled[0]
            .message
            .contains("unknown texture option"));
    }

    #[test]
    fn a_long_statement_is_quoted_shortened() {
        let long = format!("newmtl a\nmap_Ks {}.png\n", "x".repeat(10_000));
        let m = parse(&long).unwrap();
        let message = &m[0].unmodelled[0].message;
        assert!(message.chars().count() < 300, "{}", message.len());
        assert!(message.starts_with("`map_Ks xxx"), "{message}");
    }
}
