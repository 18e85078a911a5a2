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
    let mut pass = Pass {
        path,
        result: Prepass {
            normalised: String::with_capacity(text.len()),
            faces: Vec::new(),
            libraries: Vec::new(),
            warnings: Vec::new(),
        },
        positions: 0,
        normals: 0,
        texcoords: Vec::new(),
        object: None,
        material: None,
        warned_freeform: false,
    };
    for (line_no, line, swallowed) in logical_lines(text) {
        let content = line.split('#').next().unwrap_or("");
        let tokens: Vec<&str> = content.split_whitespace().collect();
        let keep = pass.line(line_no, &tokens)?;
        let out = &mut pass.result.normalised;
        out.push_str(&keep);
        out.push('\n');
        for _ in 0..swallowed {
            out.push('\n');
        }
    }
    Ok(pass.result)
}

/// The file's logical lines as (first line's number, text, lines swallowed):
/// continuation lines (`\` at the end) are joined and keep the first line's
/// number; the lines they swallowed become empty in the normalised text, so
/// that numbering stays one-to-one.
fn logical_lines(text: &str) -> Vec<(usize, String, usize)> {
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
    logical
}

/// The pre-pass's state between lines: what it has produced, the counts of
/// elements defined so far (for index checks), and the current object and
/// material.
struct Pass<'a> {
    path: &'a Path,
    result: Prepass,
    positions: usize,
    normals: usize,
    texcoords: Vec<DVec2>,
    object: Option<String>,
    material: Option<String>,
    warned_freeform: bool,
}

impl Pass<'_> {
    fn err(&self, line_no: usize, item: String, message: String) -> SceneError {
        SceneError::at(self.path, Some(line_no), item, message)
    }

    fn warn(&mut self, line_no: usize, item: String, message: String) {
        self.result.warnings.push(Warning {
            source: SourceRef {
                file: self.path.to_path_buf(),
                line: Some(line_no),
                item,
            },
            message,
        });
    }

    /// Checks and records one logical line; returns what `tobj` reads in its
    /// place (empty for the lines it must not see).
    fn line(&mut self, line_no: usize, tokens: &[&str]) -> Result<String, SceneError> {
        let mut keep = String::new();
        match tokens.first().copied() {
            Some("v") => keep = self.vertex(line_no, &tokens[1..])?,
            Some("vn") => keep = self.normal(line_no, tokens)?,
            Some("vt") => self.texcoord(line_no, &tokens[1..])?,
            Some("f") | Some("fo") => keep = self.face(line_no, &tokens[1..])?,
            Some("o") | Some("g") => {
                let name = tokens[1..].join(" ");
                self.object = (!name.is_empty()).then_some(name);
                // Model boundaries for tobj; names are tracked here.
                keep = "o".to_owned();
            }
            Some("usemtl") => {
                let name = tokens[1..].join(" ");
                if name.is_empty() {
                    return Err(self.err(
                        line_no,
                        String::new(),
                        "`usemtl` without a material name".to_owned(),
                    ));
                }
                self.material = Some(name);
            }
            Some("mtllib") => {
                let argument = tokens[1..].join(" ");
                if argument.is_empty() {
                    return Err(self.err(
                        line_no,
                        String::new(),
                        "`mtllib` without a file name".to_owned(),
                    ));
                }
                self.result.libraries.push((argument, line_no));
            }
            Some("curv") | Some("curv2") | Some("surf") if !self.warned_freeform => {
                self.warned_freeform = true;
                self.warn(
                    line_no,
                    String::new(),
                    "free-form curves and surfaces are not supported; ignored".to_owned(),
                );
            }
            _ => {}
        }
        Ok(keep)
    }

    /// `v x y z [w]` or `v x y z r g b`: the position, divided by a rational
    /// weight w when there is one.
    fn vertex(&mut self, line_no: usize, values: &[&str]) -> Result<String, SceneError> {
        let number = self.positions + 1;
        let err = |message: String| self.err(line_no, String::new(), message);
        if !matches!(values.len(), 3 | 4 | 6 | 7) {
            return Err(self.err(
                line_no,
                format!("vertex {number}"),
                format!(
                    "`v` needs x y z (optionally w, or r g b), found {} values",
                    values.len()
                ),
            ));
        }
        let mut xyz = [0.0; 3];
        for (k, slot) in xyz.iter_mut().enumerate() {
            *slot = parse_real_lazy(values[k], || {
                format!("vertex {number} {}", ["x", "y", "z"][k])
            })
            .map_err(err)?;
        }
        let keep = if values.len() == 4 || values.len() == 7 {
            // The rational weight w divides the coordinates.
            let w = parse_real(values[3], &format!("vertex {number} w")).map_err(err)?;
            if w == 0.0 {
                return Err(err(format!("vertex {number} has weight w = 0")));
            }
            xyz = xyz.map(|c| c / w);
            if !xyz.iter().all(|c| c.is_finite()) {
                return Err(err(format!("vertex {number} / w is not finite")));
            }
            // `{:?}` prints the shortest string that reads back to the same f64.
            format!("v {:?} {:?} {:?}", xyz[0], xyz[1], xyz[2])
        } else {
            // tobj parses the same tokens to the same f64s checked above.
            ["v", values[0], values[1], values[2]].join(" ")
        };
        self.positions += 1;
        Ok(keep)
    }

    /// `vn x y z`, checked and passed on as it is.
    fn normal(&mut self, line_no: usize, tokens: &[&str]) -> Result<String, SceneError> {
        let number = self.normals + 1;
        if tokens.len() != 4 {
            return Err(self.err(
                line_no,
                format!("normal {number}"),
                format!("`vn` needs 3 numbers, found {}", tokens.len() - 1),
            ));
        }
        for (k, token) in tokens[1..].iter().enumerate() {
            parse_real_lazy(token, || format!("normal {number} {}", ["x", "y", "z"][k]))
                .map_err(|m| self.err(line_no, String::new(), m))?;
        }
        self.normals += 1;
        Ok(tokens.join(" "))
    }

    /// `vt u [v [w]]`: v defaults to 0, w (3-D textures) is ignored. Kept
    /// here, not passed to `tobj`.
    fn texcoord(&mut self, line_no: usize, values: &[&str]) -> Result<(), SceneError> {
        let number = self.texcoords.len() + 1;
        if values.is_empty() || values.len() > 3 {
            return Err(self.err(
                line_no,
                format!("texture coordinate {number}"),
                format!(
                    "`vt` needs u (optionally v, w), found {} values",
                    values.len()
                ),
            ));
        }
        let mut uv = DVec2::ZERO;
        for (k, token) in values.iter().take(2).enumerate() {
            uv[k] = parse_real_lazy(token, || {
                format!("texture coordinate {number} {}", ["u", "v"][k])
            })
            .map_err(|m| self.err(line_no, String::new(), m))?;
        }
        self.texcoords.push(uv);
        Ok(())
    }

    /// `f` (or `fo`) with corners `v`, `v/vt`, `v//vn` or `v/vt/vn`: indices
    /// checked and resolved, the face recorded with its object, material,
    /// normals and UVs, and written for `tobj` with absolute indices. A face
    /// of fewer than 3 corners is dropped with a warning.
    fn face(&mut self, line_no: usize, corners_text: &[&str]) -> Result<String, SceneError> {
        let face_number = self.result.faces.len() + 1;
        let item = match &self.object {
            Some(o) => format!("face {face_number} of object {o}"),
            None => format!("face {face_number}"),
        };
        if corners_text.len() > MAX_POLYGON_VERTICES {
            return Err(self.err(line_no, item, too_many_vertices(corners_text.len())));
        }
        let err = |m: String| self.err(line_no, item.clone(), m);
        let mut corners = Vec::with_capacity(corners_text.len());
        let mut with_normals = 0usize;
        let mut uvs = Vec::new();
        for corner in corners_text {
            let parts: Vec<&str> = corner.split('/').collect();
            if parts.len() > 3 || parts[0].is_empty() {
                return Err(err(format!(
                    "face corner `{corner}`: expected v, v/vt, v//vn or v/vt/vn"
                )));
            }
            let v = resolve_index(parts[0], self.positions, "vertex").map_err(err)?;
            if let Some(vt) = parts.get(1).filter(|s| !s.is_empty()) {
                let t = resolve_index(vt, self.texcoords.len(), "texture").map_err(err)?;
                uvs.push(self.texcoords[t]);
            }
            let mut corner_text = (v + 1).to_string();
            if let Some(vn) = parts.get(2).filter(|s| !s.is_empty()) {
                let n = resolve_index(vn, self.normals, "normal").map_err(err)?;
                corner_text = format!("{}//{}", v + 1, n + 1);
                with_normals += 1;
            }
            corners.push(corner_text);
        }
        if corners.len() < 3 {
            let message = format!(
                "degenerate polygon: a face needs at least 3 vertices, this one has {}; skipped",
                corners.len()
            );
            self.warn(line_no, item, message);
            return Ok(String::new());
        }
        // A face with normals on only some corners is treated as flat.
        let has_normals = with_normals == corners.len();
        if !has_normals {
            for c in &mut corners {
                if let Some((v, _)) = c.split_once("//") {
                    *c = v.to_owned();
                }
            }
        }
        self.result.faces.push(FaceLine {
            line: line_no,
            object: self.object.clone(),
            material: self.material.clone(),
            has_normals,
            uvs: (uvs.len() == corners.len()).then_some(uvs),
        });
        Ok(format!("f {}", corners.join(" ")))
    }
}
