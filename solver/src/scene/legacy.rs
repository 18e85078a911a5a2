//! The legacy geometry file of Remington 1992, appendix B (the "AFIT geom" format with
//! Remington's (1992) additions), also accepted with the extension `.geom`.
//!
//! ```text
//! line 1   title (free text)
//! line 2   [ccw] [cw] [purge] [nopurge]           (may be empty or left out)
//! line 3   points N patches M attributes K        (`polygons` is accepted for `patches`)
//! N lines  x y z [normal nx ny nz]
//! M lines  n i1 … in attribute a [patch p]        (Remington 1992 writes n = 4; 3 or more accepted)
//! K lines  color r g b [emit r g b] [material m]
//! ```
//!
//! Conventions chosen where appendix B is silent, stated here so that files can be
//! written for it: point, polygon and attribute indices are 1-based; `patch p`
//! asks for p × p patches (left out: the solver's default); `color` is the
//! diffuse reflectance Kd and `emit` the emitted radiance (design notes); `cw`
//! means polygons are listed clockwise seen from their front, and they are
//! reversed on import; `purge`/`nopurge` are accepted and have no effect (import
//! merges coincident vertices when welding anyway). An attribute line becomes the
//! material `attribute K`. Appendix B's `material m` names reflectance file m
//! (appendix F: Ks, Kd and a Legendre series of the glossy lobe), which is not
//! read, since the path-traced reference evaluates only the analytic lobe and
//! could not check a solve that used the file. An attribute with `material m`
//! that a polygon uses is therefore refused, naming the file, the line and m,
//! unless a TOML scene config overrides it under `[materials."material m"]`
//! (where kd, ks and α are given instead). Blank lines and lines starting with `#` after
//! the title are skipped. Every malformed line is an error naming the file, the
//! line and what is wrong.

use super::clean::emission_problem;
use super::obj::too_many_vertices;
use super::raw::{RawMaterial, RawPolygon, RawScene};
use super::text::{numbered_lines, parse_count, parse_real, parse_vec3, read_text};
use super::{SceneError, SourceRef, MAX_POLYGON_VERTICES};
use glam::DVec3;
use std::path::Path;

/// The largest `patch p` accepted (as the solver's `patches` setting).
pub(crate) const MAX_PATCHES: u32 = 256;

/// Why a used attribute's `material m` is refused: the reflectance file it
/// names is not read (see the module comment).
fn unread_reflectance_file(m: u64) -> String {
    format!(
        "`material {m}` names reflectance file {m} (Remington 1992, appendix F), which is not \
         read: the path-traced reference that checks a solve evaluates the analytic lobe, not \
         a file's Legendre series. Remove `material {m}` to make the attribute diffuse with its \
         `color`, or give its kd, ks and alpha under [materials.\"material {m}\"] in a TOML \
         scene config that names this file"
    )
}

/// Parses a legacy geometry file.
pub(crate) fn parse_legacy(path: &Path) -> Result<RawScene, SceneError> {
    let text = read_text(path)?;
    parse_legacy_text(path, &text)
}

struct Point {
    position: DVec3,
    normal: Option<DVec3>,
}

struct PolygonLine {
    line: usize,
    indices: Vec<usize>,
    attribute: usize,
    patches: Option<u32>,
}

/// The counts line (`points N patches M attributes K`) and the winding that
/// the optional line before it chose.
struct Header {
    clockwise: bool,
    points: u64,
    polygons: u64,
    attributes: u64,
}

/// The lines after the title, less blank and comment lines, as tokens with
/// their 1-based numbers.
struct Content<'a> {
    path: &'a Path,
    lines: Box<dyn Iterator<Item = (usize, Vec<&'a str>)> + 'a>,
}

impl<'a> Content<'a> {
    fn new(path: &'a Path, text: &'a str) -> Self {
        let mut lines = numbered_lines(text);
        lines.next(); // the title
        let lines = lines.filter_map(|(no, line)| {
            let tokens: Vec<&str> = line.split_whitespace().collect();
            match tokens.first() {
                None => None,
                Some(t) if t.starts_with('#') => None,
                Some(_) => Some((no, tokens)),
            }
        });
        Content {
            path,
            lines: Box::new(lines),
        }
    }

    /// The next line, or an error saying what the file ends before.
    fn next_before(
        &mut self,
        what: impl FnOnce() -> String,
    ) -> Result<(usize, Vec<&'a str>), SceneError> {
        self.lines.next().ok_or_else(|| {
            SceneError::at(
                self.path,
                None,
                "",
                format!("the file ends before {}", what()),
            )
        })
    }

    fn err(&self, line: usize, item: String, message: String) -> SceneError {
        SceneError::at(self.path, Some(line), item, message)
    }
}

pub(crate) fn parse_legacy_text(path: &Path, text: &str) -> Result<RawScene, SceneError> {
    if text.trim().is_empty() {
        return Err(SceneError::Empty(format!("{} is empty", path.display())));
    }
    let mut content = Content::new(path, text);
    let header = read_header(&mut content)?;
    // Counts come from the file: nothing is allocated from them up front; the
    // vectors grow only as lines are actually read.
    let mut points = Vec::new();
    for k in 0..header.points {
        let (no, tokens) =
            content.next_before(|| format!("point {} of {}", k + 1, header.points))?;
        points.push(read_point(&content, no, &tokens, k)?);
    }
    let mut polygon_lines = Vec::new();
    for k in 0..header.polygons {
        let (no, tokens) =
            content.next_before(|| format!("polygon {} of {}", k + 1, header.polygons))?;
        polygon_lines.push(read_polygon_line(&content, no, &tokens, k, &header)?);
    }
    let mut materials = Vec::new();
    for k in 0..header.attributes {
        let (no, tokens) =
            content.next_before(|| format!("attribute {} of {}", k + 1, header.attributes))?;
        materials.push(read_attribute(&content, no, &tokens, k)?);
    }
    if let Some((no, tokens)) = content.lines.next() {
        return Err(content.err(
            no,
            String::new(),
            format!(
                "unexpected `{}` after the last attribute line (the header declares {} points, {} polygons, {} attributes)",
                tokens.join(" "),
                header.points,
                header.polygons,
                header.attributes
            ),
        ));
    }
    let polygons = polygon_lines
        .into_iter()
        .enumerate()
        .map(|(k, p)| polygon(path, &points, p, k, header.clockwise))
        .collect();
    Ok(RawScene {
        polygons,
        materials,
        warnings: Vec::new(),
        files: vec![path.to_path_buf()],
    })
}

/// Line 2 (optional: `ccw`, `cw`, `purge`, `nopurge`) and line 3, the counts.
fn read_header(content: &mut Content) -> Result<Header, SceneError> {
    let counts_line = || "the `points N patches M attributes K` line".to_owned();
    let (mut no, mut tokens) = content.next_before(counts_line)?;
    let mut clockwise = false;
    if tokens[0] != "points" {
        let (mut ccw, mut cw) = (false, false);
        for t in &tokens {
            match *t {
                "ccw" => ccw = true,
                "cw" => cw = true,
                "purge" | "nopurge" => {}
                other => {
                    return Err(content.err(
                        no,
                        String::new(),
                        format!("attribute selection line: unknown word `{other}` (expected ccw, cw, purge or nopurge)"),
                    ))
                }
            }
        }
        if ccw && cw {
            return Err(content.err(
                no,
                String::new(),
                "attribute selection line: both `ccw` and `cw`".to_owned(),
            ));
        }
        clockwise = cw;
        (no, tokens) = content.next_before(counts_line)?;
    }
    if tokens.len() != 6
        || tokens[0] != "points"
        || !matches!(tokens[2], "patches" | "polygons")
        || tokens[4] != "attributes"
    {
        return Err(content.err(
            no,
            String::new(),
            format!(
                "expected `points N patches M attributes K`, found `{}`",
                tokens.join(" ")
            ),
        ));
    }
    let count =
        |t: &str, what: &str| parse_count(t, what).map_err(|m| content.err(no, String::new(), m));
    Ok(Header {
        clockwise,
        points: count(tokens[1], "number of points")?,
        polygons: count(tokens[3], "number of polygons")?,
        attributes: count(tokens[5], "number of attributes")?,
    })
}

/// Point `k`: `x y z [normal nx ny nz]`.
fn read_point(content: &Content, no: usize, tokens: &[&str], k: u64) -> Result<Point, SceneError> {
    let item = format!("point {}", k + 1);
    let position = parse_vec3(tokens, "position").map_err(|m| content.err(no, item.clone(), m))?;
    let normal = match tokens.len() {
        3 => None,
        7 if tokens[3] == "normal" => {
            let n =
                parse_vec3(&tokens[4..], "normal").map_err(|m| content.err(no, item.clone(), m))?;
            Some(DVec3::from(n))
        }
        _ => {
            return Err(content.err(
                no,
                item,
                format!(
                    "expected `x y z` or `x y z normal nx ny nz`, found `{}`",
                    tokens.join(" ")
                ),
            ))
        }
    };
    Ok(Point {
        position: DVec3::from(position),
        normal,
    })
}

/// Polygon line `k`: `n i1 … in attribute a [patch p]`.
fn read_polygon_line(
    content: &Content,
    no: usize,
    tokens: &[&str],
    k: u64,
    header: &Header,
) -> Result<PolygonLine, SceneError> {
    let item = format!("polygon {}", k + 1);
    let e = |m: String| content.err(no, item.clone(), m);
    let n = parse_count(tokens[0], "vertex count").map_err(&e)?;
    if n < 3 {
        return Err(e(format!(
            "vertex count {n} is out of range (at least 3; Remington 1992 writes 4)"
        )));
    }
    if n > MAX_POLYGON_VERTICES as u64 {
        return Err(e(too_many_vertices(
            usize::try_from(n).unwrap_or(usize::MAX),
        )));
    }
    let n = n as usize;
    if tokens.len() < 1 + n {
        return Err(e(format!(
            "vertex count {n} but only {} point indices follow",
            tokens.len() - 1
        )));
    }
    let mut indices = Vec::with_capacity(n);
    for t in &tokens[1..=n] {
        let i = parse_count(t, "point index").map_err(&e)?;
        if i == 0 || i > header.points {
            return Err(e(format!(
                "point index {i} is out of range: points are numbered 1 to {}",
                header.points
            )));
        }
        indices.push(i as usize - 1);
    }
    let (mut attribute, mut patches) = (None, None);
    let mut rest = tokens[1 + n..].iter();
    while let Some(&key) = rest.next() {
        let value = rest
            .next()
            .ok_or_else(|| e(format!("`{key}` without a value")))?;
        match key {
            "attribute" => {
                let a = parse_count(value, "attribute").map_err(&e)?;
                if a == 0 || a > header.attributes {
                    return Err(e(format!(
                        "attribute {a} is out of range: attributes are numbered 1 to {}",
                        header.attributes
                    )));
                }
                attribute = Some(a as usize - 1);
            }
            "patch" => {
                let p = parse_count(value, "patch").map_err(&e)?;
                if p == 0 || p > u64::from(MAX_PATCHES) {
                    return Err(e(format!("patch {p} is out of range (1 to {MAX_PATCHES})")));
                }
                patches = Some(p as u32);
            }
            other => {
                if other.parse::<f64>().is_ok() {
                    return Err(e(format!(
                        "vertex count {n} but more point indices follow (`{other}`)"
                    )));
                }
                return Err(e(format!(
                    "unknown word `{other}` (expected `attribute a` or `patch p`)"
                )));
            }
        }
    }
    let attribute = attribute.ok_or_else(|| e("missing `attribute a`".to_owned()))?;
    Ok(PolygonLine {
        line: no,
        indices,
        attribute,
        patches,
    })
}

/// Attribute line `k`: `color r g b [emit r g b] [material m]`, as the
/// material `attribute K`.
fn read_attribute(
    content: &Content,
    no: usize,
    tokens: &[&str],
    k: u64,
) -> Result<RawMaterial, SceneError> {
    let item = format!("attribute {}", k + 1);
    let e = |m: String| content.err(no, item.clone(), m);
    let (mut colour, mut emit, mut number) = (None, DVec3::ZERO, None);
    let mut i = 0;
    while i < tokens.len() {
        match tokens[i] {
            "color" | "colour" | "emit" => {
                let emits = tokens[i] == "emit";
                let v = read_rgb(tokens.get(i + 1..i + 4), emits).map_err(&e)?;
                if emits {
                    emit = v;
                } else {
                    colour = Some(v);
                }
                i += 4;
            }
            "material" => {
                let m = tokens
                    .get(i + 1)
                    .ok_or_else(|| e("`material` without a number".to_owned()))?;
                number = Some(parse_count(m, "material").map_err(&e)?);
                i += 2;
            }
            other => {
                return Err(e(format!(
                    "unknown word `{other}` (expected `color r g b`, `emit r g b` or `material m`)"
                )))
            }
        }
    }
    let kd = colour.ok_or_else(|| e("missing `color r g b`".to_owned()))?;
    let name = format!("attribute {}", k + 1);
    let unread_reflectance_file = number.map(|m| {
        let at = SourceRef {
            file: content.path.to_path_buf(),
            line: Some(no),
            item: item.clone(),
        };
        (at, unread_reflectance_file(m))
    });
    Ok(RawMaterial {
        name: name.clone(),
        aliases: number
            .map(|m| format!("material {m}"))
            .into_iter()
            .collect(),
        kd,
        ks: DVec3::ZERO,
        alpha: 1.0,
        emission: emit,
        source: SourceRef {
            file: content.path.to_path_buf(),
            line: Some(no),
            item: format!("material {name}"),
        },
        overridden_at: None,
        undefined: None,
        unread_reflectance_file,
        unmodelled: Vec::new(),
        diffuse_map: None,
        diffuse_bytes: None,
        emission_map: None,
        emission_bytes: None,
        metal_map: None,
        unlit: false,
    })
}

/// The three numbers after `color` (the diffuse reflectance) or `emit` (the
/// emitted radiance, bounded by [`super::MAX_EMISSION`]).
fn read_rgb(tokens: Option<&[&str]>, emits: bool) -> Result<DVec3, String> {
    let what = if emits {
        "emit (emitted radiance)"
    } else {
        "color (diffuse reflectance)"
    };
    let tokens = tokens.ok_or_else(|| format!("{what}: expected 3 numbers"))?;
    let mut v = [0.0; 3];
    for (c, (slot, token)) in v.iter_mut().zip(tokens).enumerate() {
        *slot = parse_real(token, &format!("{what} {}", ["red", "green", "blue"][c]))?;
    }
    let v = DVec3::from(v);
    if v.min_element() < 0.0 {
        return Err(format!("{what} must not be negative"));
    }
    if emits {
        if let Some(problem) = emission_problem(v) {
            return Err(format!("{what} {problem}"));
        }
    }
    Ok(v)
}

/// Polygon line `k` as a raw polygon, reversed when the file is clockwise.
fn polygon(path: &Path, points: &[Point], p: PolygonLine, k: usize, clockwise: bool) -> RawPolygon {
    let mut order = p.indices;
    if clockwise {
        order.reverse();
    }
    let vertices = order.iter().map(|&i| points[i].position).collect();
    let normals = order
        .iter()
        .map(|&i| points[i].normal)
        .collect::<Option<Vec<_>>>();
    RawPolygon {
        vertices,
        normals,
        material: p.attribute,
        patches: p.patches,
        sizes: Default::default(),
        object: None,
        source: SourceRef {
            file: path.to_path_buf(),
            line: Some(p.line),
            item: format!("polygon {}", k + 1),
        },
        uvs: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "title\nccw\npoints 4 patches 1 attributes 1\n";
    const POINTS: &str = "0 0 0 normal 0 0 1\n1 0 0 normal 0 0 1\n1 1 0 normal 0 0 1\n0 1 0\n";

    fn parse(text: &str) -> Result<RawScene, SceneError> {
        parse_legacy_text(Path::new("room.geom"), text)
    }

    #[test]
    fn reads_points_polygons_and_attributes() {
        let text = format!(
            "{HEADER}{POINTS}4 1 2 3 4 attribute 1 patch 3\ncolor 0.5 0.25 0.125 emit 1 2 3 material 7\n"
        );
        let raw = parse(&text).unwrap();
        assert_eq!(raw.polygons.len(), 1);
        let p = &raw.polygons[0];
        assert_eq!(p.vertices[2], DVec3::new(1.0, 1.0, 0.0));
        assert_eq!(p.patches, Some(3));
        assert_eq!(p.source.line, Some(8));
        // Point 4 has no normal, so the polygon has no vertex normals.
        assert!(p.normals.is_none());
        let m = &raw.materials[0];
        assert_eq!(m.kd, DVec3::new(0.5, 0.25, 0.125));
        assert_eq!(m.emission, DVec3::new(1.0, 2.0, 3.0));
        assert!(m.answers_to("attribute 1") && m.answers_to("material 7"));
    }

    #[test]
    fn cw_reverses_and_attribute_line_may_be_left_out() {
        let cw = format!(
            "title\ncw purge\npoints 4 patches 1 attributes 1\n{POINTS}4 1 2 3 4 attribute 1\ncolor 1 1 1\n"
        );
        let raw = parse(&cw).unwrap();
        assert_eq!(raw.polygons[0].vertices[0], DVec3::new(0.0, 1.0, 0.0));
        let bare = format!("title\npoints 4 polygons 1 attributes 1\n\n# comment\n{POINTS}3 1 2 3 attribute 1\ncolor 1 1 1\n");
        let raw = parse(&bare).unwrap();
        assert_eq!(raw.polygons[0].vertices.len(), 3);
        assert_eq!(raw.polygons[0].patches, None);
    }

    #[test]
    fn every_malformed_line_names_file_line_and_what() {
        let poly = "4 1 2 3 4 attribute 1 patch 2\n";
        let attr = "color 1 1 1\n";
        let cases: Vec<(String, Option<usize>, &str)> = vec![
            (
                "title\nccw sideways\n".into(),
                Some(2),
                "unknown word `sideways`",
            ),
            ("title\nccw cw\n".into(), Some(2), "both `ccw` and `cw`"),
            (
                "title\nccw\npoints 4 patches\n".into(),
                Some(3),
                "expected `points N patches M attributes K`",
            ),
            (
                "title\nccw\npoints -4 patches 1 attributes 1\n".into(),
                Some(3),
                "number of points",
            ),
            (
                format!("{HEADER}0 0 0\n1 0\n"),
                Some(5),
                "expected 3 numbers",
            ),
            (
                format!("{HEADER}0 0 0\n1 0 x\n"),
                Some(5),
                "position component z",
            ),
            (
                format!("{HEADER}0 0 0\n1 0 inf\n"),
                Some(5),
                "not a finite number",
            ),
            (
                format!("{HEADER}0 0 0\n1 0 0 normal 1 0\n"),
                Some(5),
                "expected `x y z` or `x y z normal nx ny nz`",
            ),
            (
                format!("{HEADER}0 0 0\n1 0 0 normal 1 nan 0\n"),
                Some(5),
                "not a finite",
            ),
            (
                format!("{HEADER}{POINTS}4 1 2 3\n{attr}"),
                Some(8),
                "only 3 point indices follow",
            ),
            (
                format!("{HEADER}{POINTS}2 1 2 attribute 1\n{attr}"),
                Some(8),
                "vertex count 2 is out of range",
            ),
            (
                format!("{HEADER}{POINTS}4 1 2 3 5 attribute 1\n{attr}"),
                Some(8),
                "point index 5 is out of range",
            ),
            (
                format!("{HEADER}{POINTS}4 0 1 2 3 attribute 1\n{attr}"),
                Some(8),
                "point index 0 is out of range",
            ),
            (
                format!("{HEADER}{POINTS}4 1 2 3 4 attribute 2\n{attr}"),
                Some(8),
                "attribute 2 is out of range",
            ),
            (
                format!("{HEADER}{POINTS}4 1 2 3 4 patch 2\n{attr}"),
                Some(8),
                "missing `attribute a`",
            ),
            (
                format!("{HEADER}{POINTS}4 1 2 3 4 attribute 1 patch 0\n{attr}"),
                Some(8),
                "patch 0 is out of range",
            ),
            (
                format!("{HEADER}{POINTS}4 1 2 3 4 attribute 1 patch\n{attr}"),
                Some(8),
                "`patch` without a value",
            ),
            (
                format!("{HEADER}{POINTS}4 1 2 3 4 attribute 1 colour 2\n{attr}"),
                Some(8),
                "unknown word `colour`",
            ),
            (
                format!("{HEADER}{POINTS}4 1 2 3 4 4 attribute 1\n{attr}"),
                Some(8),
                "more point indices follow",
            ),
            (
                format!("{HEADER}{POINTS}{poly}emit 1 1 1\n"),
                Some(9),
                "missing `color r g b`",
            ),
            (
                format!("{HEADER}{POINTS}{poly}color 1 1\n"),
                Some(9),
                "expected 3 numbers",
            ),
            (
                format!("{HEADER}{POINTS}{poly}color 1 1 -1\n"),
                Some(9),
                "must not be negative",
            ),
            (
                format!("{HEADER}{POINTS}{poly}color 1 1 1 emit 1 x 1\n"),
                Some(9),
                "emit (emitted radiance) green",
            ),
            (
                format!("{HEADER}{POINTS}{poly}color 1 1 1 material\n"),
                Some(9),
                "`material` without a number",
            ),
            (
                format!("{HEADER}{POINTS}{poly}color 1 1 1 shiny 3\n"),
                Some(9),
                "unknown word `shiny`",
            ),
            (
                format!("{HEADER}{POINTS}{poly}{attr}extra line\n"),
                Some(10),
                "after the last attribute line",
            ),
            (
                format!("{HEADER}{POINTS}{poly}"),
                None,
                "before attribute 1 of 1",
            ),
            (format!("{HEADER}0 0 0\n"), None, "before point 2 of 4"),
        ];
        for (text, line, fragment) in cases {
            let message = parse(&text).unwrap_err().to_string();
            let prefix = match line {
                Some(l) => format!("room.geom:{l}"),
                None => "room.geom".to_owned(),
            };
            assert!(
                message.starts_with(&prefix),
                "{message:?} should start with {prefix:?}"
            );
            assert!(
                message.contains(fragment),
                "{message:?} should say {fragment:?}"
            );
        }
    }
}
