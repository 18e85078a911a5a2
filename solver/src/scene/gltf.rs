//! glTF 2.0 scenes (`.gltf` with `.bin` files or data-URI buffers, and `.glb`),
//! read through the `gltf` crate for the JSON document and its validation, with
//! the bytes read here.
//!
//! The `gltf` crate's own file and accessor readers are not used: its GLB
//! splitter subtracts before it checks a header length, and its accessor
//! iterators assert on strides, so hostile input could panic. Here every
//! length is checked in `u64` before a slice is taken, every allocation is
//! bounded by bytes that exist (a file's size, a decoded data URI, a buffer's
//! bytes), and every error names the file and the glTF item (buffer, view,
//! accessor, mesh, primitive, index).
//!
//! What the scene becomes (docs/gltf.md has the full table):
//!
//! * **Geometry**: every triangle of every mesh instanced by a node of the
//!   default scene (else scene 0), in world coordinates: the node matrices
//!   composed along the scene graph in f64 (glTF 2.0 specification, §3.5.3
//!   "Transformations"). A node whose world matrix has a negative determinant
//!   mirrors, so its triangles are turned round to keep their front faces
//!   (§3.7.3). `TRIANGLE_STRIP` and `TRIANGLE_FAN` primitives are converted
//!   by the specification's formulas (§3.7.3); points and lines are skipped
//!   with a warning. `NORMAL`s, transformed by the inverse transpose, become
//!   the polygons' vertex normals, as OBJ `vn` do.
//! * **Materials** (metallic-roughness, §3.9.2): Kd = baseColor·(1 − metallic),
//!   Ks = lerp(0.04, baseColor, metallic) (used only in directional mode, as an
//!   MTL `Ks` is), α = roughness² (glTF roughness is perceptual; α is clamped
//!   to [`crate::brdf::MIN_ALPHA`]), and emitted radiance
//!   Le = emissiveFactor × `KHR_materials_emissive_strength` (× the
//!   `emissiveTexture`, decoded from sRGB, where there is one). glTF gives
//!   emission no absolute unit; it is taken as W·sr⁻¹·m⁻², one-sided toward
//!   the front face, as an MTL `Ke` is.
//! * **Units**: metres, +y up, right-handed (§3.4): the scene's
//!   `units_per_metre` is [`UNITS_PER_METRE`] unless the command line says
//!   otherwise.
//! * **Camera**: the first perspective camera in scene-graph order (depth
//!   first, children in order) becomes the scene's camera: the eye at the
//!   node's world origin, looking down its −z with its +y up, `yfov` as the
//!   vertical field of view (§3.10).
//!
//! Everything else is either refused (compressed meshes and textures that a
//! file requires, since then the mesh cannot be read) or warned about once
//! per material or feature: textures other than the base colour's, or on
//! another set than `TEXCOORD_0` (flat factors are used), alpha modes,
//! transmission, clearcoat and the other material extensions, normal maps,
//! double-sided materials, punctual lights (not turned
//! into emitters: radiosity needs area emitters), skins, morph targets and
//! animations.

use super::raw::{RawMaterial, RawPolygon, RawScene, DEFAULT_KD};
use super::{SceneError, SourceRef, Warning};
use crate::brdf::MIN_ALPHA;
use base64::Engine as _;
use glam::{DAffine2, DMat3, DMat4, DQuat, DVec2, DVec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use gltf::{Document, Gltf, Semantic};
use solution::camera::{Camera, MAX_IMAGE_SIDE};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

#[cfg(test)]
#[path = "gltf_tests.rs"]
mod tests;

/// glTF's unit of length is the metre (glTF 2.0 specification, §3.4).
pub(crate) const UNITS_PER_METRE: f64 = 1.0;

/// The most triangles a file may place in the scene, counting every instance
/// of a mesh. Stored triangles are bounded by the file's bytes, but nodes can
/// instance one mesh many times; each placed triangle costs about 300 bytes
/// through import (its polygon, positions and source), so this caps the
/// import near 3 GB whatever the file claims.
pub(crate) const MAX_PLACED_TRIANGLES: usize = 10_000_000;

/// The reflectance of a dielectric at normal incidence that the
/// metallic-roughness model assumes (glTF 2.0 specification, appendix B):
/// Ks = lerp(0.04, baseColor, metallic).
pub(crate) const DIELECTRIC_SPECULAR: f64 = 0.04;

/// Image width of the camera taken from a file; the height follows the
/// camera's aspect ratio (square when the file gives none).
const CAMERA_IMAGE_WIDTH: u32 = 512;

/// Required extensions that this importer reads past: their effect is on
/// appearance, and each is warned about where it is used.
const TOLERATED_REQUIRED: &[&str] = &[
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
    "KHR_lights_punctual",
    "KHR_materials_unlit",
    "KHR_materials_transmission",
    "KHR_materials_clearcoat",
    "KHR_materials_volume",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_sheen",
    "KHR_materials_iridescence",
    "KHR_materials_anisotropy",
    "KHR_materials_dispersion",
    "KHR_materials_variants",
    "KHR_materials_pbrSpecularGlossiness",
];

/// Material extensions that change appearance and that the solver does not
/// model (warned once per material). `KHR_materials_emissive_strength` is
/// modelled and absent here.
const UNMODELLED_MATERIAL_EXTENSIONS: &[(&str, &str)] = &[
    (
        "KHR_materials_transmission",
        "transmission (the surface is taken as opaque)",
    ),
    (
        "KHR_materials_volume",
        "volume (the surface is taken as opaque)",
    ),
    ("KHR_materials_clearcoat", "clearcoat (no coat layer)"),
    ("KHR_materials_sheen", "sheen"),
    ("KHR_materials_specular", "specular strength and colour"),
    ("KHR_materials_ior", "index of refraction (0.04 at normal incidence is used)"),
    ("KHR_materials_iridescence", "iridescence"),
    ("KHR_materials_anisotropy", "anisotropy"),
    ("KHR_materials_dispersion", "dispersion"),
    (
        "KHR_materials_unlit",
        "unlit shading (the surface is lit like any other)",
    ),
    (
        "KHR_materials_pbrSpecularGlossiness",
        "the specular-glossiness model (the metallic-roughness factors, or their defaults, are used)",
    ),
];

/// What a glTF file contributes: geometry and materials, and a camera.
pub(crate) struct GltfScene {
    pub raw: RawScene,
    pub camera: Option<Camera>,
}

/// Where errors and warnings point: the file, and the glTF item.
struct Context<'a> {
    path: &'a Path,
}

impl Context<'_> {
    fn err(&self, item: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::at(self.path, None, item, message)
    }

    fn source(&self, item: impl Into<String>) -> SourceRef {
        SourceRef {
            file: self.path.to_path_buf(),
            line: None,
            item: item.into(),
        }
    }

    fn warning(&self, item: impl Into<String>, message: impl Into<String>) -> Warning {
        Warning {
            source: self.source(item),
            message: message.into(),
        }
    }
}

/// Reads a `.gltf` or `.glb` file and the buffers it names.
pub(crate) fn parse_gltf(path: &Path) -> Result<GltfScene, SceneError> {
    let ctx = Context { path };
    let bytes = std::fs::read(path).map_err(|e| SceneError::io(path, e))?;
    let (json, blob) = if bytes.starts_with(b"glTF") {
        split_glb(&ctx, &bytes)?
    } else {
        (&bytes[..], None)
    };
    let gltf = Gltf::from_slice_without_validation(json).map_err(|e| {
        let line = match &e {
            gltf::Error::Deserialize(d) => Some(d.line()),
            _ => None,
        };
        SceneError::at(path, line, "", format!("not a glTF 2.0 document: {e}"))
    })?;
    let mut warnings = Vec::new();
    check_required_extensions(&ctx, &gltf.document)?;
    let document = validate(&ctx, gltf.document)?;
    let buffers = load_buffers(&ctx, &document, blob)?;
    check_views(&ctx, &document, &buffers)?;
    document_warnings(&ctx, &document, &mut warnings);

    let mut builder = Builder {
        ctx: &ctx,
        document: &document,
        buffers: &buffers,
        raw: RawScene {
            files: vec![path.to_path_buf()],
            ..Default::default()
        },
        materials: HashMap::new(),
        placed: 0,
        camera: None,
        warned_orthographic: false,
        warned_meshes: Vec::new(),
        uv_maps: HashMap::new(),
    };
    builder.walk_scene()?;
    let Builder {
        mut raw, camera, ..
    } = builder;
    warnings.append(&mut raw.warnings);
    raw.warnings = warnings;
    Ok(GltfScene { raw, camera })
}

/// Splits a binary glTF file (glTF 2.0 specification, chapter 4) into its JSON
/// chunk and its optional BIN chunk, checking every length against the bytes
/// that are there.
fn split_glb<'a>(
    ctx: &Context,
    bytes: &'a [u8],
) -> Result<(&'a [u8], Option<&'a [u8]>), SceneError> {
    let word = |at: usize| -> Option<u32> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let truncated = |what: &str| {
        ctx.err(
            "GLB",
            format!(
                "truncated binary glTF: the file ends inside {what} ({} bytes)",
                bytes.len()
            ),
        )
    };
    let version = word(4).ok_or_else(|| truncated("the 12-byte header"))?;
    let length = word(8).ok_or_else(|| truncated("the 12-byte header"))? as usize;
    if version != 2 {
        return Err(ctx.err(
            "GLB",
            format!("binary glTF version {version}: only version 2 is read"),
        ));
    }
    if length > bytes.len() {
        return Err(ctx.err(
            "GLB",
            format!(
                "truncated binary glTF: the header says {length} bytes, the file has {}",
                bytes.len()
            ),
        ));
    }
    let data = &bytes[..length];
    let chunk = |at: usize, what: &str| -> Result<(u32, &'a [u8], usize), SceneError> {
        let data: &'a [u8] = &bytes[..length];
        let (Some(len), Some(kind)) = (word(at), word(at + 4)) else {
            return Err(truncated(&format!("the {what} chunk header")));
        };
        let start = at + 8;
        let end = start as u64 + u64::from(len);
        if end > data.len() as u64 {
            return Err(ctx.err(
                "GLB",
                format!(
                    "truncated binary glTF: the {what} chunk claims {len} bytes from byte {start}, \
                     the file has {} in all",
                    data.len()
                ),
            ));
        }
        let end = end as usize;
        Ok((kind, &data[start..end], end))
    };
    if data.len() < 20 {
        return Err(truncated("the JSON chunk header"));
    }
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    let (kind, json, mut next) = chunk(12, "JSON")?;
    if kind != JSON {
        return Err(ctx.err("GLB", "the first chunk of a binary glTF must be JSON"));
    }
    let mut bin = None;
    // Chunks are 4-byte aligned; the BIN chunk, if any, is the second, and
    // chunks of other types are ignored (chapter 4).
    next = next.div_ceil(4) * 4;
    if next + 8 <= data.len() {
        let (kind, body, _) = chunk(next, "BIN")?;
        if kind == BIN {
            bin = Some(body);
        }
    }
    Ok((json, bin))
}

/// Refuses files that require what this importer cannot read, by name and
/// with what to do about it. A required extension must be understood to read
/// the file at all (glTF 2.0 specification, §3.12).
fn check_required_extensions(ctx: &Context, document: &Document) -> Result<(), SceneError> {
    for name in document.extensions_required() {
        let why = match name {
            "KHR_draco_mesh_compression" => {
                "its meshes are Draco-compressed, and this importer cannot decode Draco: \
                 export again without mesh compression"
            }
            "EXT_meshopt_compression" | "KHR_meshopt_compression" => {
                "its buffers are meshopt-compressed, and this importer cannot decode them: \
                 export again without mesh compression"
            }
            "KHR_mesh_quantization" => {
                "its vertex attributes are quantized integers; this importer reads float \
                 positions and normals only: export again without quantization"
            }
            "KHR_texture_basisu" | "EXT_texture_webp" | "EXT_texture_avif" => {
                "its textures cannot be read in that format (base-colour textures are read as \
                 PNG or JPEG only): export again with PNG or JPEG textures"
            }
            known if TOLERATED_REQUIRED.contains(&known) => continue,
            _ => "this importer does not know that extension",
        };
        return Err(ctx.err(
            "extensionsRequired",
            format!("the file requires the extension {name}, but {why}"),
        ));
    }
    Ok(())
}

/// The `gltf` crate's validation (every index in range, required fields
/// present), after the required extensions that [`check_required_extensions`]
/// let through are taken off its list (it refuses those it has no types for).
fn validate(ctx: &Context, document: Document) -> Result<Document, SceneError> {
    let mut json = document.into_json();
    json.extensions_required
        .retain(|e| !TOLERATED_REQUIRED.contains(&e.as_str()));
    Document::from_json(json).map_err(|e| match e {
        gltf::Error::Validation(list) => {
            let shown: Vec<String> = list
                .iter()
                .take(5)
                .map(|(path, error)| format!("{path}: {error}"))
                .collect();
            let more = list.len().saturating_sub(shown.len());
            ctx.err(
                "",
                format!(
                    "invalid glTF: {}{}",
                    shown.join("; "),
                    if more > 0 {
                        format!(" (and {more} more)")
                    } else {
                        String::new()
                    }
                ),
            )
        }
        other => ctx.err("", format!("invalid glTF: {other}")),
    })
}

/// One buffer: its first `length` bytes of `bytes`, which several buffers
/// may share (one file named twice is read once).
struct Buffer {
    bytes: Rc<[u8]>,
    length: usize,
}

impl Buffer {
    /// The buffer's `byteLength` bytes.
    fn data(&self) -> &[u8] {
        &self.bytes[..self.length]
    }
}

/// Each buffer's bytes: the GLB BIN chunk, a data URI decoded, or a file
/// relative to the glTF file, each at least the buffer's `byteLength`. Every
/// source is held once however many buffers name it, so what is allocated is
/// at most the files' sizes and the decoded data URIs (which are smaller than
/// the JSON that holds them).
fn load_buffers(
    ctx: &Context,
    document: &Document,
    blob: Option<&[u8]>,
) -> Result<Vec<Buffer>, SceneError> {
    let dir = ctx.path.parent().unwrap_or(Path::new(""));
    let mut files: HashMap<PathBuf, Rc<[u8]>> = HashMap::new();
    let mut bin: Option<Rc<[u8]>> = None;
    let mut out = Vec::new();
    for buffer in document.buffers() {
        let item = format!("buffer {}", buffer.index());
        let length = buffer.length();
        let bytes: Rc<[u8]> = match buffer.source() {
            gltf::buffer::Source::Bin => {
                let Some(blob) = blob else {
                    return Err(ctx.err(
                        item,
                        "the buffer refers to the GLB BIN chunk, and the file has none",
                    ));
                };
                bin.get_or_insert_with(|| Rc::from(blob)).clone()
            }
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                Rc::from(decode_data_uri(uri).map_err(|m| ctx.err(item.clone(), m))?)
            }
            gltf::buffer::Source::Uri(uri) => {
                let file = relative_file(dir, uri).map_err(|m| ctx.err(item.clone(), m))?;
                match files.get(&file) {
                    Some(bytes) => bytes.clone(),
                    None => {
                        let bytes: Rc<[u8]> = Rc::from(std::fs::read(&file).map_err(|e| {
                            ctx.err(
                                item.clone(),
                                format!("uri `{uri}`: cannot read {}: {e}", file.display()),
                            )
                        })?);
                        files.insert(file, bytes.clone());
                        bytes
                    }
                }
            }
        };
        if bytes.len() < length {
            let what = match buffer.source() {
                gltf::buffer::Source::Bin => "the GLB BIN chunk".to_owned(),
                gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                    "the data URI".to_owned()
                }
                gltf::buffer::Source::Uri(uri) => format!("`{uri}`"),
            };
            return Err(ctx.err(
                item,
                format!(
                    "{what} is {} bytes, shorter than the buffer's byteLength {length}",
                    bytes.len()
                ),
            ));
        }
        out.push(Buffer { bytes, length });
    }
    Ok(out)
}

/// The bytes of a base64 data URI (`data:[<type>];base64,<data>`); its size
/// is bounded by the URI's, which is part of the file.
fn decode_data_uri(uri: &str) -> Result<Vec<u8>, String> {
    let Some((head, data)) = uri.split_once(',') else {
        return Err("a data URI without a `,` before its data".to_owned());
    };
    if !head.ends_with(";base64") {
        return Err(format!(
            "the data URI `{}` is not base64-encoded: only `;base64,` data URIs are read",
            short_text(head)
        ));
    }
    base64::engine::general_purpose::STANDARD
        .decode(data.trim())
        .map_err(|e| format!("the data URI's base64 does not decode: {e}"))
}

/// A buffer URI as a file beside the glTF file: percent-decoded (RFC 3986,
/// §2.1) and relative; URIs with a scheme name nothing that can be read here.
fn relative_file(dir: &Path, uri: &str) -> Result<PathBuf, String> {
    let scheme = uri.split_once(':').map(|(s, _)| s).filter(|s| {
        s.len() > 1
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    });
    if let Some(scheme) = scheme {
        return Err(format!(
            "uri `{}`: only relative file names and data URIs are read, not `{scheme}:` URIs",
            short_text(uri)
        ));
    }
    let mut bytes = Vec::with_capacity(uri.len());
    let raw = uri.as_bytes();
    let mut i = 0;
    while i < raw.len() {
        if raw[i] == b'%' {
            let hex = raw
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok());
            let Some(byte) = hex else {
                return Err(format!(
                    "uri `{}`: a `%` not followed by two hex digits",
                    short_text(uri)
                ));
            };
            bytes.push(byte);
            i += 3;
        } else {
            bytes.push(raw[i]);
            i += 1;
        }
    }
    let name = String::from_utf8(bytes)
        .map_err(|_| format!("uri `{}` does not decode to UTF-8", short_text(uri)))?;
    Ok(dir.join(name))
}

/// The first 60 characters of a text, for messages about long URIs.
fn short_text(text: &str) -> String {
    match text.char_indices().nth(60) {
        Some((at, _)) => format!("{}…", &text[..at]),
        None => text.to_owned(),
    }
}

/// Every buffer view lies inside its buffer.
fn check_views(ctx: &Context, document: &Document, buffers: &[Buffer]) -> Result<(), SceneError> {
    for view in document.views() {
        let buffer = view.buffer().index();
        let end = view.offset() as u64 + view.length() as u64;
        let have = buffers[buffer].data().len() as u64;
        if end > have {
            return Err(ctx.err(
                format!("bufferView {}", view.index()),
                format!(
                    "the view spans bytes {}..{end} of buffer {buffer}, which has {have}: \
                     the buffer is shorter than its views",
                    view.offset()
                ),
            ));
        }
        if let Some(stride) = view.stride() {
            if !(4..=252).contains(&stride) || !stride.is_multiple_of(4) {
                return Err(ctx.err(
                    format!("bufferView {}", view.index()),
                    format!("byteStride {stride} is not a multiple of 4 in 4..=252"),
                ));
            }
        }
    }
    Ok(())
}

/// Warnings about features of the file as a whole.
fn document_warnings(ctx: &Context, document: &Document, warnings: &mut Vec<Warning>) {
    let lights = document
        .nodes()
        .filter(|n| n.extension_value("KHR_lights_punctual").is_some())
        .count();
    if lights > 0 {
        warnings.push(ctx.warning(
            "KHR_lights_punctual",
            format!(
                "{lights} punctual light(s) ignored: point, spot and directional lights are not \
                 turned into emitters, because radiosity needs area emitters; give the light \
                 fixtures an emissive material instead"
            ),
        ));
    }
    let skins = document.skins().count();
    if skins > 0 {
        warnings.push(ctx.warning(
            "skins",
            format!(
                "{skins} skin(s) ignored: skinned meshes are placed by their nodes' transforms, \
                 in their bind pose"
            ),
        ));
    }
    let animations = document.animations().count();
    if animations > 0 {
        warnings.push(ctx.warning(
            "animations",
            format!("{animations} animation(s) ignored: the scene is solved as it stands"),
        ));
    }
}

/// The state of the scene-graph walk.
struct Builder<'a> {
    ctx: &'a Context<'a>,
    document: &'a Document,
    buffers: &'a [Buffer],
    raw: RawScene,
    /// glTF material index (`None`: the primitive names none) → raw material.
    materials: HashMap<Option<usize>, usize>,
    placed: usize,
    camera: Option<Camera>,
    warned_orthographic: bool,
    /// Meshes already warned about (morph targets, points and lines).
    warned_meshes: Vec<usize>,
    /// For each raw material with a base-colour texture, the map from the
    /// primitive's `TEXCOORD_0` to the solver's UVs ([`uv_map`]).
    uv_maps: HashMap<usize, DAffine2>,
}

impl Builder<'_> {
    /// Walks the default scene (else the first) depth first, children in order,
    /// composing the node matrices.
    fn walk_scene(&mut self) -> Result<(), SceneError> {
        let Some(scene) = self
            .document
            .default_scene()
            .or_else(|| self.document.scenes().next())
        else {
            return Err(self
                .ctx
                .err("scenes", "the file has no scene, so nothing to solve"));
        };
        let mut visited = vec![false; self.document.nodes().count()];
        let mut stack: Vec<(gltf::Node, DMat4)> =
            scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
        stack.reverse();
        while let Some((node, parent)) = stack.pop() {
            let item = node_name(&node);
            if std::mem::replace(&mut visited[node.index()], true) {
                return Err(self.ctx.err(
                    item,
                    "the node appears twice in the scene graph (glTF 2.0 §3.5.2 requires a \
                     forest: each node has at most one parent)",
                ));
            }
            let world = parent * local_matrix(&node).map_err(|m| self.ctx.err(item.clone(), m))?;
            if let Some(camera) = node.camera() {
                self.take_camera(&node, &camera, world);
            }
            if let Some(mesh) = node.mesh() {
                self.add_mesh(&node, &mesh, world)?;
            }
            for child in node.children().collect::<Vec<_>>().into_iter().rev() {
                stack.push((child, world));
            }
        }
        Ok(())
    }

    /// The first perspective camera becomes the scene's camera.
    fn take_camera(&mut self, node: &gltf::Node, camera: &gltf::Camera, world: DMat4) {
        if self.camera.is_some() {
            return;
        }
        match camera.projection() {
            gltf::camera::Projection::Perspective(p) => {
                let camera =
                    camera_from_node(world, f64::from(p.yfov()), p.aspect_ratio().map(f64::from));
                match camera.validate() {
                    Ok(()) => self.camera = Some(camera),
                    Err(e) => self.raw.warnings.push(
                        self.ctx
                            .warning(node_name(node), format!("perspective camera ignored: {e}")),
                    ),
                }
            }
            gltf::camera::Projection::Orthographic(_) if !self.warned_orthographic => {
                self.warned_orthographic = true;
                self.raw.warnings.push(self.ctx.warning(
                    node_name(node),
                    "orthographic cameras are ignored: the scene's camera is the first \
                     perspective one",
                ));
            }
            gltf::camera::Projection::Orthographic(_) => {}
        }
    }

    /// Every triangle of `mesh`'s primitives, placed by `world`.
    fn add_mesh(
        &mut self,
        node: &gltf::Node,
        mesh: &gltf::Mesh,
        world: DMat4,
    ) -> Result<(), SceneError> {
        let mesh_item = mesh_name(mesh);
        let first_visit = !self.warned_meshes.contains(&mesh.index());
        if first_visit {
            self.warned_meshes.push(mesh.index());
            let morphs = mesh
                .primitives()
                .any(|p| p.morph_targets().next().is_some());
            if morphs {
                self.raw.warnings.push(self.ctx.warning(
                    mesh_item.clone(),
                    "morph targets ignored: the base shape is used",
                ));
            }
        }
        let linear = DMat3::from_mat4(world);
        let determinant = linear.determinant();
        let normal_matrix = (determinant != 0.0).then(|| linear.inverse().transpose());
        let mirrored = determinant < 0.0;
        let object = node
            .name()
            .map(str::to_owned)
            .or_else(|| mesh.name().map(str::to_owned));
        for primitive in mesh.primitives() {
            let item = format!("{mesh_item}, primitive {}", primitive.index());
            let triangles = match primitive.mode() {
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => {
                    self.primitive_triangles(&primitive, &item)?
                }
                other => {
                    if first_visit {
                        self.raw.warnings.push(self.ctx.warning(
                            item,
                            format!(
                                "{other:?} primitive skipped: radiosity needs surfaces, and points \
                                 and lines have no area"
                            ),
                        ));
                    }
                    continue;
                }
            };
            self.placed = self.placed.saturating_add(triangles.corners.len() / 3);
            if self.placed > MAX_PLACED_TRIANGLES {
                return Err(self.ctx.err(
                    item,
                    format!(
                        "the scene places more than {MAX_PLACED_TRIANGLES} triangles (counting \
                         every instance of a mesh), the importer's cap"
                    ),
                ));
            }
            let material = self.material_for(&primitive);
            let uvs = match self.uv_maps.get(&material) {
                Some(&map) => {
                    self.primitive_uvs(&primitive, &item, triangles.positions.len(), map)?
                }
                None => None,
            };
            let source_item = match node.name() {
                Some(name) => format!("node `{name}`, {item}"),
                None => format!("node {}, {item}", node.index()),
            };
            for (t, corners) in triangles.corners.chunks_exact(3).enumerate() {
                let mut order = [corners[0], corners[1], corners[2]];
                if mirrored {
                    order.swap(1, 2);
                }
                let vertices: Vec<DVec3> = order
                    .iter()
                    .map(|&i| world.transform_point3(triangles.positions[i as usize]))
                    .collect();
                let normals = match (&triangles.normals, normal_matrix) {
                    (Some(n), Some(m)) => Some(order.iter().map(|&i| m * n[i as usize]).collect()),
                    _ => None,
                };
                self.raw.polygons.push(RawPolygon {
                    vertices,
                    normals,
                    material,
                    patches: None,
                    sizes: Default::default(),
                    object: object.clone(),
                    source: self.ctx.source(format!("{source_item}, triangle {t}")),
                    uvs: uvs
                        .as_ref()
                        .map(|uv| order.iter().map(|&i| uv[i as usize]).collect()),
                });
            }
        }
        Ok(())
    }

    /// Positions, normals and triangle corners of one primitive, every index
    /// checked against the `POSITION` accessor's count.
    fn primitive_triangles(
        &mut self,
        primitive: &gltf::Primitive,
        item: &str,
    ) -> Result<Triangles, SceneError> {
        let Some(positions) = primitive.get(&Semantic::Positions) else {
            return Err(self
                .ctx
                .err(item, "the primitive has no POSITION attribute"));
        };
        let positions = read_vec3(self.ctx, self.buffers, &positions, "POSITION", item)?;
        let normals = match primitive.get(&Semantic::Normals) {
            Some(accessor) => {
                let normals = read_vec3(self.ctx, self.buffers, &accessor, "NORMAL", item)?;
                if normals.len() != positions.len() {
                    return Err(self.ctx.err(
                        item,
                        format!(
                            "NORMAL has {} elements for {} positions",
                            normals.len(),
                            positions.len()
                        ),
                    ));
                }
                Some(normals)
            }
            None => None,
        };
        let indices: Vec<u32> = match primitive.indices() {
            Some(accessor) => {
                let indices = read_indices(self.ctx, self.buffers, &accessor, item)?;
                if let Some((k, &i)) = indices
                    .iter()
                    .enumerate()
                    .find(|(_, &i)| i as usize >= positions.len())
                {
                    return Err(self.ctx.err(
                        item,
                        format!(
                            "index {i} (element {k} of accessor {}) is out of range: the POSITION \
                             accessor has {} vertices",
                            accessor.index(),
                            positions.len()
                        ),
                    ));
                }
                indices
            }
            None => (0..positions.len() as u32).collect(),
        };
        let corners = assemble(primitive.mode(), &indices);
        let leftover = match primitive.mode() {
            Mode::Triangles => indices.len() % 3,
            _ => 0,
        };
        if leftover != 0 {
            self.raw.warnings.push(self.ctx.warning(
                item,
                format!(
                    "{} indices do not make whole triangles: the last {leftover} are ignored",
                    indices.len()
                ),
            ));
        }
        Ok(Triangles {
            positions,
            normals,
            corners,
        })
    }

    /// A primitive's `TEXCOORD_0` through `map` (the texture transform and
    /// glTF's downward v turned into the solver's upward v), one per
    /// position; `None` when the primitive has none (the material's texture
    /// is then unused there, which the cleaning step warns about).
    fn primitive_uvs(
        &self,
        primitive: &gltf::Primitive,
        item: &str,
        positions: usize,
        map: DAffine2,
    ) -> Result<Option<Vec<DVec2>>, SceneError> {
        let Some(accessor) = primitive.get(&Semantic::TexCoords(0)) else {
            return Ok(None);
        };
        let uvs = read_vec2(self.ctx, self.buffers, &accessor, "TEXCOORD_0", item)?;
        if uvs.len() != positions {
            return Err(self.ctx.err(
                item,
                format!(
                    "TEXCOORD_0 has {} elements for {positions} positions",
                    uvs.len()
                ),
            ));
        }
        Ok(Some(
            uvs.into_iter().map(|uv| map.transform_point2(uv)).collect(),
        ))
    }

    /// The raw material of a primitive, made (with its warnings) on first use.
    fn material_for(&mut self, primitive: &gltf::Primitive) -> usize {
        let material = primitive.material();
        if let Some(&i) = self.materials.get(&material.index()) {
            return i;
        }
        let (raw, warnings) = match material.index() {
            Some(_) => {
                let (raw, warnings, uv_map) = convert_material(self.ctx, self.buffers, &material);
                if let Some(map) = uv_map {
                    self.uv_maps.insert(self.raw.materials.len(), map);
                }
                (raw, warnings)
            }
            None => (
                RawMaterial {
                    undefined: None,
                    ..RawMaterial::undefined(
                        "default",
                        self.ctx.source("default material"),
                        String::new(),
                    )
                },
                vec![self.ctx.warning(
                    "default material",
                    format!(
                        "primitives without a material get `default` (Kd {DEFAULT_KD}, no \
                         emission), as OBJ faces without `usemtl` do; glTF's own default, a rough \
                         white metal, would reflect nothing diffusely"
                    ),
                )],
            ),
        };
        self.raw.warnings.extend(warnings);
        self.raw.materials.push(raw);
        let index = self.raw.materials.len() - 1;
        self.materials.insert(material.index(), index);
        index
    }
}

/// One primitive's vertex data and its triangles as corner indices.
struct Triangles {
    positions: Vec<DVec3>,
    normals: Option<Vec<DVec3>>,
    /// Three corners per triangle, indices into `positions`.
    corners: Vec<u32>,
}

/// Triangle corners from a primitive's index list (glTF 2.0 specification,
/// §3.7.3): triangles take the indices in threes; strip triangle i is
/// (v_i, v_{i+1+i%2}, v_{i+2−i%2}), keeping every triangle's winding; fan
/// triangle i is (v_{i+1}, v_{i+2}, v_0). Strip and fan triangles that repeat
/// an index are the degenerate joins that strips use and are left out.
pub(crate) fn assemble(mode: Mode, indices: &[u32]) -> Vec<u32> {
    let n = indices.len();
    let mut corners = Vec::new();
    match mode {
        Mode::Triangles => corners.extend_from_slice(&indices[..n - n % 3]),
        Mode::TriangleStrip => {
            for i in 0..n.saturating_sub(2) {
                let t = [indices[i], indices[i + 1 + i % 2], indices[i + 2 - i % 2]];
                if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                    corners.extend_from_slice(&t);
                }
            }
        }
        Mode::TriangleFan => {
            for i in 0..n.saturating_sub(2) {
                let t = [indices[i + 1], indices[i + 2], indices[0]];
                if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                    corners.extend_from_slice(&t);
                }
            }
        }
        _ => {}
    }
    corners
}

/// A node's local matrix in f64: its `matrix`, or T · R · S (glTF 2.0
/// specification, §3.5.3), the rotation quaternion normalised.
fn local_matrix(node: &gltf::Node) -> Result<DMat4, String> {
    let f = |v: &[f32]| v.iter().all(|x| x.is_finite());
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            let flat: Vec<f64> = matrix.iter().flatten().map(|&x| f64::from(x)).collect();
            if !flat.iter().all(|x| x.is_finite()) {
                return Err("the node's matrix is not finite".to_owned());
            }
            let mut cols = [0.0; 16];
            cols.copy_from_slice(&flat);
            Ok(DMat4::from_cols_array(&cols))
        }
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            if !(f(&translation) && f(&rotation) && f(&scale)) {
                return Err("the node's translation, rotation or scale is not finite".to_owned());
            }
            let d = |v: [f32; 3]| DVec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]));
            let q = DQuat::from_xyzw(
                f64::from(rotation[0]),
                f64::from(rotation[1]),
                f64::from(rotation[2]),
                f64::from(rotation[3]),
            );
            if q.length() == 0.0 {
                return Err("the node's rotation quaternion is zero".to_owned());
            }
            Ok(DMat4::from_scale_rotation_translation(
                d(scale),
                q.normalize(),
                d(translation),
            ))
        }
    }
}

/// The solver's camera for a glTF camera node with world matrix `world`: the
/// eye at the node's origin, looking down its −z, its +y up (glTF 2.0
/// specification, §3.10). The target is one scene unit ahead.
pub(crate) fn camera_from_node(world: DMat4, yfov_rad: f64, aspect: Option<f64>) -> Camera {
    let eye = world.transform_point3(DVec3::ZERO);
    let forward = world.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
    let up = world.transform_vector3(DVec3::Y).normalize_or_zero();
    let height = match aspect {
        Some(a) if a.is_finite() && a > 0.0 => (f64::from(CAMERA_IMAGE_WIDTH) / a)
            .round()
            .clamp(1.0, f64::from(MAX_IMAGE_SIDE))
            as u32,
        _ => CAMERA_IMAGE_WIDTH,
    };
    Camera {
        eye: eye.to_array(),
        target: (eye + forward).to_array(),
        up: up.to_array(),
        fov_y_deg: yfov_rad.to_degrees(),
        width: CAMERA_IMAGE_WIDTH,
        height,
    }
}

/// Kd, Ks and α of the metallic-roughness model (glTF 2.0 specification,
/// appendix B): Kd = baseColor·(1 − metallic), Ks = lerp(0.04, baseColor,
/// metallic), α = roughness² clamped below at [`MIN_ALPHA`]. The last value
/// says whether α was clamped.
pub(crate) fn metallic_roughness(
    base: DVec3,
    metallic: f64,
    roughness: f64,
) -> (DVec3, DVec3, f64, bool) {
    let kd = base * (1.0 - metallic);
    let ks =
        DVec3::splat(DIELECTRIC_SPECULAR) + metallic * (base - DVec3::splat(DIELECTRIC_SPECULAR));
    let alpha = roughness * roughness;
    (kd, ks, alpha.max(MIN_ALPHA), alpha < MIN_ALPHA)
}

/// A glTF material as the solver's, with a warning for each feature of it
/// that is not modelled.
/// The third value, for a material with a usable base-colour texture, maps
/// its `TEXCOORD_0` to the solver's UVs.
fn convert_material(
    ctx: &Context,
    buffers: &[Buffer],
    material: &gltf::Material,
) -> (RawMaterial, Vec<Warning>, Option<DAffine2>) {
    let index = material.index().unwrap_or(0);
    let name = material
        .name()
        .map(str::to_owned)
        .unwrap_or_else(|| format!("material {index}"));
    let item = format!("material `{name}` (materials[{index}])");
    let mut warnings = Vec::new();
    let mut warn = |message: String| warnings.push(ctx.warning(item.clone(), message));

    let pbr = material.pbr_metallic_roughness();
    let [r, g, b, _] = pbr.base_color_factor().map(f64::from);
    let metallic = f64::from(pbr.metallic_factor());
    let roughness = f64::from(pbr.roughness_factor());
    // Out-of-range factors are the file's error, but the cleaning step refuses
    // negative or non-finite reflectances with the material's name, so they
    // are clamped to glTF's [0, 1] here only where the model needs it.
    let (kd, ks, alpha, clamped) = metallic_roughness(
        DVec3::new(r, g, b),
        metallic.clamp(0.0, 1.0),
        roughness.clamp(0.0, 1.0),
    );
    if clamped {
        warn(format!(
            "roughness {roughness} gives α = roughness² = {:.3e}, below the solver's smallest \
             glossy lobe; α = {MIN_ALPHA} is used",
            roughness * roughness
        ));
    }
    if !(0.0..=1.0).contains(&metallic) || !(0.0..=1.0).contains(&roughness) {
        warn(format!(
            "metallicFactor {metallic} and roughnessFactor {roughness} must lie in [0, 1]; \
             clamped"
        ));
    }
    let strength = f64::from(material.emissive_strength().unwrap_or(1.0));
    let emission = DVec3::from_array(material.emissive_factor().map(f64::from)) * strength;

    let base_colour = match pbr.base_color_texture() {
        Some(info) => material_texture(ctx, buffers, &info, BASE_COLOUR, &mut warn),
        None => None,
    };
    // Le = emissiveFactor × strength × emissiveTexture (§3.9.3, sRGB like the
    // base colour), honouring its texCoord and `KHR_texture_transform`.
    let emissive = match material.emissive_texture() {
        Some(_) if emission == DVec3::ZERO => {
            warn(
                "emissiveTexture with emissiveFactor (0, 0, 0): the factor multiplies the \
                 texture, so the surface does not emit"
                    .to_owned(),
            );
            None
        }
        Some(info) => material_texture(ctx, buffers, &info, EMISSIVE, &mut warn),
        None => None,
    };
    // Both textures of a surface are sampled at its one UV set (the solution
    // file's two slots share the textured vertices' UVs), so an emitter's
    // base-colour texture is modelled when it maps like its emissive texture.
    let base_colour = match (base_colour, &emissive) {
        (Some(b), Some(e)) if b.uv_map != e.uv_map => {
            warn(
                "baseColorTexture and emissiveTexture map differently (texCoord or \
                 KHR_texture_transform) and a surface has one UV set: the emissive texture is \
                 used and the flat base colour reflects"
                    .to_owned(),
            );
            None
        }
        (b, _) => b,
    };
    if pbr.metallic_roughness_texture().is_some() {
        warn(format!(
            "metallicRoughnessTexture ignored, the flat factors used (metallic {metallic}, \
             roughness {roughness}): only base-colour and emissive textures are modelled"
        ));
    }
    if material.normal_texture().is_some() {
        warn("normal map ignored: surfaces are shaded with their geometric normals".to_owned());
    }
    match material.alpha_mode() {
        gltf::material::AlphaMode::Opaque => {}
        gltf::material::AlphaMode::Mask => warn(format!(
            "alpha mode MASK ignored: the surface is opaque everywhere (cutoff {})",
            material.alpha_cutoff().unwrap_or(0.5)
        )),
        gltf::material::AlphaMode::Blend => {
            warn("alpha mode BLEND ignored: the surface is opaque".to_owned())
        }
    }
    if material.double_sided() {
        warn(
            "doubleSided: the solver's surfaces are one-sided; each triangle receives, reflects \
             and emits on its front (counter-clockwise) side only"
                .to_owned(),
        );
    }
    for (extension, what) in UNMODELLED_MATERIAL_EXTENSIONS {
        if material.extension_value(extension).is_some() {
            warn(format!("{extension} ignored: {what} is not modelled"));
        }
    }
    let raw = RawMaterial {
        name,
        aliases: Vec::new(),
        kd,
        ks,
        alpha,
        emission,
        source: ctx.source(item.clone()),
        overridden_at: None,
        undefined: None,
        unread_reflectance_file: None,
        // This importer's warnings about unmodelled features are returned
        // beside the material (the MTL reader's per-statement list is not used).
        unmodelled: Vec::new(),
        diffuse_map: base_colour
            .as_ref()
            .map(|t| (t.name.clone(), ctx.source(item.clone()))),
        diffuse_bytes: base_colour.as_ref().and_then(|t| t.bytes.clone()),
        emission_map: emissive
            .as_ref()
            .map(|t| (t.name.clone(), ctx.source(item.clone()))),
        emission_bytes: emissive.as_ref().and_then(|t| t.bytes.clone()),
    };
    // A polygon has one UV set: the two textures' maps are equal when both
    // are kept (above).
    let uv_map = emissive.or(base_colour).map(|t| t.uv_map);
    (raw, warnings, uv_map)
}

/// Which texture of a material [`material_texture`] reads, for its messages.
struct Slot {
    name: &'static str,
    flat: &'static str,
}

const BASE_COLOUR: Slot = Slot {
    name: "baseColorTexture",
    flat: "the flat base colour",
};
const EMISSIVE: Slot = Slot {
    name: "emissiveTexture",
    flat: "the flat emissive factor",
};

/// A base-colour or emissive texture as the importer hands it on: decoded
/// later by `texture_file` (like an MTL `map_Kd` or `map_Ke`) only if a
/// polygon uses it.
struct MaterialTexture {
    /// The image file, or the glTF file and image index naming embedded bytes.
    name: PathBuf,
    /// The encoded image when it is not a file of its own.
    bytes: Option<std::sync::Arc<[u8]>>,
    uv_map: DAffine2,
}

/// The base-colour or emissive texture of a material (glTF 2.0
/// specification, §3.9.2 and §3.9.3: sRGB, multiplied by `baseColorFactor`
/// or `emissiveFactor`, which is the MTL convention the solver follows: the
/// base factor · (1 − metallic) is Kd, the emissive factor × strength is Ke).
/// `None`, with a warning, when it uses another set of texture coordinates
/// than `TEXCOORD_0` or its image cannot be located.
fn material_texture(
    ctx: &Context,
    buffers: &[Buffer],
    info: &gltf::texture::Info,
    slot: Slot,
    warn: &mut impl FnMut(String),
) -> Option<MaterialTexture> {
    let transform = info.extension_value("KHR_texture_transform");
    let set = transform
        .and_then(|t| t.get("texCoord"))
        .and_then(|t| t.as_u64())
        .unwrap_or(u64::from(info.tex_coord()));
    if set != 0 {
        warn(format!(
            "{} uses TEXCOORD_{set}; only TEXCOORD_0 is read, so {} is used",
            slot.name, slot.flat
        ));
        return None;
    }
    let image = info.texture().source();
    let label = |how: &str| {
        PathBuf::from(format!(
            "{} images[{}] ({how})",
            ctx.path.display(),
            image.index()
        ))
    };
    let (name, bytes) = match image.source() {
        gltf::image::Source::View { view, .. } => {
            // `check_views` has checked every view against its buffer.
            let data = buffers[view.buffer().index()].data();
            let bytes = data.get(view.offset()..view.offset() + view.length())?;
            (
                label(&format!("bufferView {}", view.index())),
                Some(bytes.into()),
            )
        }
        gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => {
            match decode_data_uri(uri) {
                Ok(bytes) => (label("data URI"), Some(bytes.into())),
                Err(why) => {
                    warn(format!("{}: {why}; {} is used", slot.name, slot.flat));
                    return None;
                }
            }
        }
        gltf::image::Source::Uri { uri, .. } => {
            let dir = ctx.path.parent().unwrap_or(Path::new(""));
            match relative_file(dir, uri) {
                Ok(file) => (file, None),
                Err(why) => {
                    warn(format!("{}: {why}; {} is used", slot.name, slot.flat));
                    return None;
                }
            }
        }
    };
    Some(MaterialTexture {
        name,
        bytes,
        uv_map: uv_map(transform),
    })
}

/// glTF UVs to the solver's: `KHR_texture_transform` first (its README's
/// T(offset) · R(rotation) · S(scale), applied to glTF's (u, v)), then glTF's v, which runs down
/// from the image's top row, turned into the OBJ convention the solver and
/// the solution file use (v up from the bottom row): v ↦ 1 − v.
fn uv_map(transform: Option<&serde_json::Value>) -> DAffine2 {
    let pair = |key: &str, default: f64| {
        let value = transform.and_then(|t| t.get(key));
        let at = |k: usize| {
            value
                .and_then(|v| v.get(k))
                .and_then(|x| x.as_f64())
                .filter(|x| x.is_finite())
                .unwrap_or(default)
        };
        DVec2::new(at(0), at(1))
    };
    let rotation = transform
        .and_then(|t| t.get("rotation"))
        .and_then(|x| x.as_f64())
        .filter(|x| x.is_finite())
        .unwrap_or(0.0);
    // R = [[cos, sin], [−sin, cos]] in row form: u' = cos·u + sin·v,
    // v' = −sin·u + cos·v, counter-clockwise in glTF's v-down UV space. The
    // README's GLSL listing, read as GLSL (column-major), gives the transpose;
    // KhronosGroup/glTF issue #1563 records that the listing is wrong and that
    // Blender, Babylon.js, three.js and the TextureTransformTest sample model
    // all turn this way, as does the README's own example (rotation π/2,
    // offset (0, 1), scale ½ selects the image's lower-left quadrant), which
    // `texture_transform_rotation_turns_as_the_extensions_example_says` checks.
    let (sin, cos) = rotation.sin_cos();
    let gltf = DAffine2::from_translation(pair("offset", 0.0))
        * DAffine2::from_mat2(glam::DMat2::from_cols(
            DVec2::new(cos, -sin),
            DVec2::new(sin, cos),
        ))
        * DAffine2::from_scale(pair("scale", 1.0));
    let flip = DAffine2::from_cols(DVec2::X, DVec2::NEG_Y, DVec2::Y);
    flip * gltf
}

/// The bytes an accessor's elements occupy, with their stride: the accessor
/// must have a view (sparse and zero-filled accessors carry no geometry
/// here), and its last element must end inside the view.
fn accessor_span<'b>(
    ctx: &Context,
    buffers: &'b [Buffer],
    accessor: &gltf::Accessor,
    element: usize,
    what: &str,
    item: &str,
) -> Result<(&'b [u8], usize, usize), SceneError> {
    let name = format!("{what} accessor {}", accessor.index());
    if accessor.sparse().is_some() {
        return Err(ctx.err(
            item,
            format!("{name} is sparse; sparse accessors are not read for mesh geometry"),
        ));
    }
    let Some(view) = accessor.view() else {
        return Err(ctx.err(
            item,
            format!("{name} has no bufferView (all zeros), which makes no surface"),
        ));
    };
    let count = accessor.count();
    if count == 0 {
        return Err(ctx.err(item, format!("{name} has no elements")));
    }
    let stride = view.stride().unwrap_or(element);
    if stride < element {
        return Err(ctx.err(
            item,
            format!("{name}: byteStride {stride} of bufferView {} is less than its {element}-byte elements", view.index()),
        ));
    }
    let end = accessor.offset() as u64 + (count as u64 - 1) * stride as u64 + element as u64;
    if end > view.length() as u64 {
        return Err(ctx.err(
            item,
            format!(
                "{name}: {count} elements of {element} bytes at stride {stride} from byte {} \
                 need {end} bytes, but bufferView {} has {}",
                accessor.offset(),
                view.index(),
                view.length()
            ),
        ));
    }
    let buffer = buffers[view.buffer().index()].data();
    let start = view.offset() + accessor.offset();
    Ok((&buffer[start..view.offset() + end as usize], stride, count))
}

/// A `VEC3` `FLOAT` accessor (positions, normals) in f64, every value finite.
fn read_vec3(
    ctx: &Context,
    buffers: &[Buffer],
    accessor: &gltf::Accessor,
    what: &str,
    item: &str,
) -> Result<Vec<DVec3>, SceneError> {
    if accessor.data_type() != DataType::F32
        || accessor.dimensions() != Dimensions::Vec3
        || accessor.normalized()
    {
        return Err(ctx.err(
            item,
            format!(
                "{what} accessor {} is {:?} {:?}{}; expected VEC3 of FLOAT",
                accessor.index(),
                accessor.dimensions(),
                accessor.data_type(),
                if accessor.normalized() {
                    " normalized"
                } else {
                    ""
                }
            ),
        ));
    }
    let (bytes, stride, count) = accessor_span(ctx, buffers, accessor, 12, what, item)?;
    let mut out = Vec::with_capacity(count);
    for k in 0..count {
        let e = &bytes[k * stride..k * stride + 12];
        let c = |j: usize| {
            f64::from(f32::from_le_bytes([
                e[4 * j],
                e[4 * j + 1],
                e[4 * j + 2],
                e[4 * j + 3],
            ]))
        };
        let v = DVec3::new(c(0), c(1), c(2));
        if !v.is_finite() {
            return Err(ctx.err(
                item,
                format!(
                    "{what} accessor {}: element {k} is not finite",
                    accessor.index()
                ),
            ));
        }
        out.push(v);
    }
    Ok(out)
}

/// A `VEC2` texture-coordinate accessor in f64: `FLOAT`, or normalized
/// `UNSIGNED_BYTE` or `UNSIGNED_SHORT` (glTF 2.0 specification, §3.7.2.1),
/// every value finite.
fn read_vec2(
    ctx: &Context,
    buffers: &[Buffer],
    accessor: &gltf::Accessor,
    what: &str,
    item: &str,
) -> Result<Vec<DVec2>, SceneError> {
    let size = match (accessor.data_type(), accessor.normalized()) {
        (DataType::F32, false) => 4,
        (DataType::U16, true) => 2,
        (DataType::U8, true) => 1,
        _ => 0,
    };
    if size == 0 || accessor.dimensions() != Dimensions::Vec2 {
        return Err(ctx.err(
            item,
            format!(
                "{what} accessor {} is {:?} {:?}{}; expected VEC2 of FLOAT, or of normalized \
                 UNSIGNED_BYTE or UNSIGNED_SHORT",
                accessor.index(),
                accessor.dimensions(),
                accessor.data_type(),
                if accessor.normalized() {
                    " normalized"
                } else {
                    ""
                }
            ),
        ));
    }
    let (bytes, stride, count) = accessor_span(ctx, buffers, accessor, 2 * size, what, item)?;
    let mut out = Vec::with_capacity(count);
    for k in 0..count {
        let e = &bytes[k * stride..k * stride + 2 * size];
        let c = |j: usize| -> f64 {
            let b = &e[j * size..(j + 1) * size];
            match size {
                4 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                2 => f64::from(u16::from_le_bytes([b[0], b[1]])) / 65535.0,
                _ => f64::from(b[0]) / 255.0,
            }
        };
        let v = DVec2::new(c(0), c(1));
        if !v.is_finite() {
            return Err(ctx.err(
                item,
                format!(
                    "{what} accessor {}: element {k} is not finite",
                    accessor.index()
                ),
            ));
        }
        out.push(v);
    }
    Ok(out)
}

/// A `SCALAR` index accessor of unsigned bytes, shorts or ints (glTF 2.0
/// specification, §3.7.3).
fn read_indices(
    ctx: &Context,
    buffers: &[Buffer],
    accessor: &gltf::Accessor,
    item: &str,
) -> Result<Vec<u32>, SceneError> {
    let size = match accessor.data_type() {
        DataType::U8 => 1,
        DataType::U16 => 2,
        DataType::U32 => 4,
        other => {
            return Err(ctx.err(
                item,
                format!(
                    "index accessor {} has component type {other:?}; indices are \
                     UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT",
                    accessor.index()
                ),
            ))
        }
    };
    if accessor.dimensions() != Dimensions::Scalar {
        return Err(ctx.err(
            item,
            format!(
                "index accessor {} is {:?}, not SCALAR",
                accessor.index(),
                accessor.dimensions()
            ),
        ));
    }
    let (bytes, stride, count) = accessor_span(ctx, buffers, accessor, size, "index", item)?;
    Ok((0..count)
        .map(|k| {
            let e = &bytes[k * stride..k * stride + size];
            match size {
                1 => u32::from(e[0]),
                2 => u32::from(u16::from_le_bytes([e[0], e[1]])),
                _ => u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
            }
        })
        .collect())
}

fn node_name(node: &gltf::Node) -> String {
    match node.name() {
        Some(name) => format!("node `{name}` (nodes[{}])", node.index()),
        None => format!("nodes[{}]", node.index()),
    }
}

fn mesh_name(mesh: &gltf::Mesh) -> String {
    match mesh.name() {
        Some(name) => format!("mesh `{name}` (meshes[{}])", mesh.index()),
        None => format!("meshes[{}]", mesh.index()),
    }
}
