//! Wavefront OBJ geometry, read by `tobj`, with MTL libraries read by [`super::mtl`].
//!
//! `tobj` reports neither the line nor the face of an error, mis-reads `mtllib`
//! and `usemtl` followed by a tab, and refuses some legal lines (`vt u`). So a
//! line-preserving pre-pass checks every line that matters and writes a
//! normalised copy that `tobj` then reads:
//!
//! * `v`, `vn`, `vt`, `f` are checked (numbers finite, indices in range,
//!   relative indices resolved against the counts so far) with errors naming
//!   file, line and face; a face with fewer than 3 vertices is dropped with a
//!   warning;
//! * texture coordinates (`vt u [v [w]]`, v = 0 when absent, w ignored) are
//!   kept by the pre-pass: a face whose every corner names one gets its UVs;
//! * `o`/`g`/`usemtl`/`mtllib` are recorded per face by the pre-pass itself
//!   (object names, material names, libraries relative to the OBJ file), and
//!   blanked for `tobj`, as are `vt` lines, lines, points and
//!   free-form geometry, which radiosity does not use;
//! * line numbers are kept one-to-one, so `tobj`'s k-th face is the pre-pass's
//!   k-th face line.
//!
//! `tobj` runs with `triangulate: false` (quads and polygons stay polygons) and
//! `single_index: false`, in f64 (`use_f64`), so a scene far from the origin
//! keeps its precision until re-centring.

use super::mtl::parse_mtl;
use super::raw::{RawMaterial, RawPolygon, RawScene};
use super::text::{numbered_lines, parse_real, parse_real_lazy, read_text};
use super::{SceneError, SourceRef, Warning, MAX_POLYGON_VERTICES};
use glam::{DVec2, DVec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// What the pre-pass knows about one face line.
struct FaceLine {
    line: usize,
    object: Option<String>,
    material: Option<String>,
    has_normals: bool,
    /// Texture coordinates (`vt`) of every corner, when every corner has one.
    uvs: Option<Vec<DVec2>>,
}

/// The pre-pass's result: the text for `tobj` and the per-face records.
struct Prepass {
    normalised: String,
    faces: Vec<FaceLine>,
    /// (`mtllib` argument, line) in file order.
    libraries: Vec<(String, usize)>,
    warnings: Vec<Warning>,
}

/// Parses an OBJ file and its MTL libraries.
pub(crate) fn parse_obj(path: &Path) -> Result<RawScene, SceneError> {
    let text = read_text(path)?;
    let pre = prepass(path, &text)?;
    let mut raw = RawScene {
        files: vec![path.to_path_buf()],
        warnings: pre.warnings,
        ..Default::default()
    };

    // Materials: every library, in order; later definitions of a name win.
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut seen_libraries: Vec<PathBuf> = Vec::new();
    for (argument, line) in &pre.libraries {
        for library in resolve_libraries(dir, argument) {
            if seen_libraries.contains(&library) {
                continue;
            }
            let mtl_text = read_text(&library).map_err(|e| match e {
                SceneError::Io { source, .. } => SceneError::at(
                    path,
                    Some(*line),
                    "",
                    format!(
                        "mtllib `{argument}`: cannot read {}: {source}",
                        library.display()
                    ),
                ),
                other => other,
            })?;
            raw.materials.extend(parse_mtl(&library, &mtl_text)?);
            seen_libraries.push(library);
        }
    }
    let mut by_name: HashMap<String, usize> = HashMap::new();
    for (i, m) in raw.materials.iter().enumerate() {
        by_name.insert(m.name.clone(), i);
    }

    let options = tobj::LoadOptions {
        triangulate: false,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _) = tobj::load_obj_buf(
        &mut std::io::Cursor::new(pre.normalised.as_bytes()),
        &options,
        |_| Ok((Vec::new(), Default::default())),
    )
    .map_err(|e| {
        // The pre-pass checks everything tobj checks, so this is a defect here
        // rather than in the file; still report it as the file's error.
        SceneError::at(path, None, "", format!("OBJ reader: {e}"))
    })?;

    let mut face_index = 0usize;
    for model in &models {
        let mesh = &model.mesh;
        let face_count = if mesh.face_arities.is_empty() {
            mesh.indices.len() / 3
        } else {
            mesh.face_arities.len()
        };
        let mut start = 0usize;
        for f in 0..face_count {
            let arity = mesh.face_arities.get(f).map_or(3, |&a| a as usize);
            let Some(face) = pre.faces.get(face_index) else {
                return Err(SceneError::at(
                    path,
                    None,
                    "",
                    "OBJ reader returned more faces than the file has face lines",
                ));
            };
            face_index += 1;
            let corners = start..start + arity;
            start += arity;
            let position = |k: usize| {
                let i = mesh.indices[k] as usize * 3;
                DVec3::new(
                    mesh.positions[i],
                    mesh.positions[i + 1],
                    mesh.positions[i + 2],
                )
            };
            let vertices: Vec<DVec3> = corners.clone().map(position).collect();
            let normals = (face.has_normals && !mesh.normals.is_empty()).then(|| {
                corners
                    .clone()
                    .map(|k| {
                        let i = mesh.normal_indices[k] as usize * 3;
                        DVec3::new(mesh.normals[i], mesh.normals[i + 1], mesh.normals[i + 2])
                    })
                    .collect::<Vec<_>>()
            });
            let uvs = face.uvs.clone().filter(|u| u.len() == arity);
            let source = SourceRef {
                file: path.to_path_buf(),
                line: Some(face.line),
                item: match &face.object {
                    Some(o) => format!("face {face_index} of object {o}"),
                    None => format!("face {face_index}"),
                },
            };
            let material = material_index(&mut raw.materials, &mut by_name, face, &source);
            raw.polygons.push(RawPolygon {
                vertices,
                normals,
                uvs,
                material,
                patches: None,
                sizes: Default::default(),
                object: face.object.clone(),
                source,
            });
        }
    }
    if face_index != pre.faces.len() {
        return Err(SceneError::at(
            path,
            None,
            "",
            format!(
                "OBJ reader returned {face_index} faces for {} face lines",
                pre.faces.len()
            ),
        ));
    }
    Ok(raw)
}

/// The material a face uses, creating a default one (with a pending warning) for
/// a name no library defines or for faces before any `usemtl`.
fn material_index(
    materials: &mut Vec<RawMaterial>,
    by_name: &mut HashMap<String, usize>,
    face: &FaceLine,
    source: &SourceRef,
) -> usize {
    let (name, message) = match &face.material {
        Some(name) => (
            name.as_str(),
            format!("material `{name}` is used but defined in no mtllib; it gets the default (Kd 0.8, no emission)"),
        ),
        None => (
            "default",
            "faces without `usemtl` get material `default` (Kd 0.8, no emission)".to_owned(),
        ),
    };
    if let Some(&i) = by_name.get(name) {
        return i;
    }
    materials.push(RawMaterial::undefined(name, source.clone(), message));
    by_name.insert(name.to_owned(), materials.len() - 1);
    materials.len() - 1
}

/// An `mtllib` argument is one file name (possibly with spaces) or several
/// separated by whitespace; paths are relative to the OBJ file's folder.
fn resolve_libraries(dir: &Path, argument: &str) -> Vec<PathBuf> {
    let whole = dir.join(argument);
    if whole.is_file() || !argument.contains(char::is_whitespace) {
        return vec![whole];
    }
    argument
        .split_whitespace()
        .map(|name| dir.join(name))
        .collect()
}

/// The refusal of a face with more than [`MAX_POLYGON_VERTICES`] corners.
pub(crate) fn too_many_vertices(count: usize) -> String {
    format!(
        "{count} vertices, more than the {MAX_POLYGON_VERTICES} one polygon may have (checking \
         and meshing a polygon take time quadratic in its vertex count); split the face or \
         triangulate it in the modelling tool"
    )
}

/// Parses one index of a face corner: 1-based, or negative relative to the
/// `count` elements defined so far. Returns the 0-based index.
fn resolve_index(token: &str, count: usize, what: &str) -> Result<usize, String> {
    let value: i64 = token
        .parse()
        .map_err(|_| format!("{what} index `{token}` is not an integer"))?;
    let resolved = if value > 0 {
        value - 1
    } else if value < 0 {
        count as i64 + value
    } else {
        return Err(format!(
            "{what} index 0 is invalid (OBJ indices start at 1)"
        ));
    };
    if resolved < 0 || resolved >= count as i64 {
        return Err(format!(
            "{what} index {value} is out of range: {count} {} defined before this line",
            match (what, count) {
                ("vertex", 1) => "vertex is",
                ("vertex", _) => "vertices are",
                ("texture", 1) => "texture coordinate is",
                ("texture", _) => "texture coordinates are",
                (_, 1) => "normal is",
                _ => "normals are",
            }
        ));
    }
    Ok(resolved as usize)
}

/// The line-preserving check and normalisation described in the module comment.
fn prepass(path: &Path, text: &str) -> Result<Prepass, SceneError> {
    let mut out = String::with_capacity(text.len());
    let mut faces = Vec::new();
    let mut libraries = Vec::new();
    let mut warnings = Vec::new();
    let (mut positions, mut normals) = (0usize, 0usize);
    let mut texcoords: Vec<DVec2> = Vec::new();
    let mut object: Option<String> = None;
    let mut material: Option<String> = None;
    let mut warned_freeform = false;

    // Joined continuation lines (`\` at the end) keep the first line's number;
    // the lines they swallowed become empty so that numbering stays one-to-one.
    let mut pending: Option<(usize, String, usize)> = None;
    let mut logical: Vec<(usize, String, usize)> = Vec::new();
    for (no, line) in numbered_lines(text) {
        let (start, mut content, swallowed) = match pending.take() {
            Some((start, mut content, swallowed)) => {
                content.push(' ');
                (start, content, swallowed + 1)
            }
            None => (no, String::new(), 0),
        };
        match line.strip_suffix('\\') {
            Some(head) => {
                content.push_str(head);
                pending = Some((start, content, swallowed));
            }
            None => {
                content.push_str(line);
                logical.push((start, content, swallowed));
            }
        }
    }
    if let Some(rest) = pending {
        logical.push(rest);
    }

    for (line_no, line, swallowed) in logical {
        let content = line.split('#').next().unwrap_or("");
        let tokens: Vec<&str> = content.split_whitespace().collect();
        let err =
            |item: String, message: String| SceneError::at(path, Some(line_no), item, message);
        let mut keep = String::new();
        match tokens.first().copied() {
            Some("v") => {
                let values = &tokens[1..];
                if !matches!(values.len(), 3 | 4 | 6 | 7) {
                    return Err(err(
                        format!("vertex {}", positions + 1),
                        format!(
                            "`v` needs x y z (optionally w, or r g b), found {} values",
                            values.len()
                        ),
                    ));
                }
                let mut xyz = [0.0; 3];
                for (k, slot) in xyz.iter_mut().enumerate() {
                    *slot = parse_real_lazy(values[k], || {
                        format!("vertex {} {}", positions + 1, ["x", "y", "z"][k])
                    })
                    .map_err(|m| err(String::new(), m))?;
                }
                if values.len() == 4 || values.len() == 7 {
                    // The rational weight w divides the coordinates.
                    let w = parse_real(values[3], &format!("vertex {} w", positions + 1))
                        .map_err(|m| err(String::new(), m))?;
                    if w == 0.0 {
                        return Err(err(
                            String::new(),
                            format!("vertex {} has weight w = 0", positions + 1),
                        ));
                    }
                    xyz = xyz.map(|c| c / w);
                    if !xyz.iter().all(|c| c.is_finite()) {
                        return Err(err(
                            String::new(),
                            format!("vertex {} / w is not finite", positions + 1),
                        ));
                    }
                    // `{:?}` prints the shortest string that reads back to the same f64.
                    keep = format!("v {:?} {:?} {:?}", xyz[0], xyz[1], xyz[2]);
                } else {
                    // tobj parses the same tokens to the same f64s checked above.
                    keep = ["v", values[0], values[1], values[2]].join(" ");
                }
                positions += 1;
            }
            Some("vn") => {
                if tokens.len() != 4 {
                    return Err(err(
                        format!("normal {}", normals + 1),
                        format!("`vn` needs 3 numbers, found {}", tokens.len() - 1),
                    ));
                }
                for (k, token) in tokens[1..].iter().enumerate() {
                    parse_real_lazy(token, || {
                        format!("normal {} {}", normals + 1, ["x", "y", "z"][k])
                    })
                    .map_err(|m| err(String::new(), m))?;
                }
                keep = tokens.join(" ");
                normals += 1;
            }
            Some("vt") => {
                // `vt u [v [w]]`: v defaults to 0, w (3-D textures) is ignored.
                let values = &tokens[1..];
                if values.is_empty() || values.len() > 3 {
                    return Err(err(
                        format!("texture coordinate {}", texcoords.len() + 1),
                        format!(
                            "`vt` needs u (optionally v, w), found {} values",
                            values.len()
                        ),
                    ));
                }
                let mut uv = DVec2::ZERO;
                for (k, token) in values.iter().take(2).enumerate() {
                    uv[k] = parse_real_lazy(token, || {
                        format!(
                            "texture coordinate {} {}",
                            texcoords.len() + 1,
                            ["u", "v"][k]
                        )
                    })
                    .map_err(|m| err(String::new(), m))?;
                }
                texcoords.push(uv);
            }
            Some("f") | Some("fo") => {
                let face_number = faces.len() + 1;
                let item = match &object {
                    Some(o) => format!("face {face_number} of object {o}"),
                    None => format!("face {face_number}"),
                };
                let corner_count = tokens.len() - 1;
                if corner_count > MAX_POLYGON_VERTICES {
                    return Err(err(item, too_many_vertices(corner_count)));
                }
                let mut corners = Vec::with_capacity(corner_count);
                let mut with_normals = 0usize;
                let mut uvs = Vec::new();
                for corner in &tokens[1..] {
                    let parts: Vec<&str> = corner.split('/').collect();
                    if parts.len() > 3 || parts[0].is_empty() {
                        return Err(err(
                            item,
                            format!("face corner `{corner}`: expected v, v/vt, v//vn or v/vt/vn"),
                        ));
                    }
                    let v = resolve_index(parts[0], positions, "vertex")
                        .map_err(|m| err(item.clone(), m))?;
                    if let Some(vt) = parts.get(1).filter(|s| !s.is_empty()) {
                        let t = resolve_index(vt, texcoords.len(), "texture")
                            .map_err(|m| err(item.clone(), m))?;
                        uvs.push(texcoords[t]);
                    }
                    let mut corner_text = (v + 1).to_string();
                    if let Some(vn) = parts.get(2).filter(|s| !s.is_empty()) {
                        let n = resolve_index(vn, normals, "normal")
                            .map_err(|m| err(item.clone(), m))?;
                        corner_text = format!("{}//{}", v + 1, n + 1);
                        with_normals += 1;
                    }
                    corners.push(corner_text);
                }
                if corners.len() < 3 {
                    warnings.push(Warning {
                        source: SourceRef {
                            file: path.to_path_buf(),
                            line: Some(line_no),
                            item,
                        },
                        message: format!(
                            "degenerate polygon: a face needs at least 3 vertices, this one has {}; skipped",
                            corners.len()
                        ),
                    });
                } else {
                    // A face with normals on only some corners is treated as flat.
                    let has_normals = with_normals == corners.len();
                    if !has_normals {
                        for c in &mut corners {
                            if let Some((v, _)) = c.split_once("//") {
                                *c = v.to_owned();
                            }
                        }
                    }
                    keep = format!("f {}", corners.join(" "));
                    faces.push(FaceLine {
                        line: line_no,
                        object: object.clone(),
                        material: material.clone(),
                        has_normals,
                        uvs: (uvs.len() == corners.len()).then_some(uvs),
                    });
                }
            }
            Some("o") | Some("g") => {
                let name = tokens[1..].join(" ");
                object = (!name.is_empty()).then_some(name);
                // Model boundaries for tobj; names are tracked here.
                keep = "o".to_owned();
            }
            Some("usemtl") => {
                let name = tokens[1..].join(" ");
                if name.is_empty() {
                    return Err(err(
                        String::new(),
                        "`usemtl` without a material name".to_owned(),
                    ));
                }
                material = Some(name);
            }
            Some("mtllib") => {
                let argument = tokens[1..].join(" ");
                if argument.is_empty() {
                    return Err(err(
                        String::new(),
                        "`mtllib` without a file name".to_owned(),
                    ));
                }
                libraries.push((argument, line_no));
            }
            Some("curv") | Some("curv2") | Some("surf") if !warned_freeform => {
                warned_freeform = true;
                warnings.push(Warning {
                    source: SourceRef {
                        file: path.to_path_buf(),
                        line: Some(line_no),
                        item: String::new(),
                    },
                    message: "free-form curves and surfaces are not supported; ignored".to_owned(),
                });
            }
            _ => {}
        }
        out.push_str(&keep);
        out.push('\n');
        for _ in 0..swallowed {
            out.push('\n');
        }
    }
    Ok(Prepass {
        normalised: out,
        faces,
        libraries,
        warnings,
    })
}
