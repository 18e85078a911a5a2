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
//!   `emissiveTexture`, decoded from sRGB, where there is one). The
//!   `metallicRoughnessTexture` is folded per texel in diffuse mode and by its
//!   means in directional mode (`scene::metal_texture`). glTF gives
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
//! per material or feature: normal maps, textures on another set than
//! `TEXCOORD_0` (flat factors are used), alpha modes,
//! transmission, clearcoat and the other material extensions, normal maps,
//! double-sided materials, skins, morph targets and animations.
//!
//! * **Lights** (`KHR_lights_punctual`): point and spot lights become lamps
//!   and the brightest directional light the sun ([`lights`]).
//!
//! The jobs are split by module: [`container`] reads the `.gltf`/`.glb`
//! container and the buffers (files, the GLB BIN chunk, data URIs);
//! [`nodes`] walks the scene graph, placing each mesh's triangles and taking
//! the camera; [`lights`] converts punctual lights; [`materials`] converts
//! materials and locates their textures;
//! [`accessors`] reads typed vertex and index data out of the buffers.

use super::raw::RawScene;
use super::{SceneError, SourceRef, Warning};
use crate::light::Lights;
use container::{check_views, load_buffers, split_glb};
use gltf::{Document, Gltf};
use solution::camera::Camera;
use std::path::Path;

mod accessors;
mod container;
mod lights;
mod materials;
mod nodes;

pub(crate) use materials::{metallic_roughness, DIELECTRIC_SPECULAR};

#[cfg(test)]
mod lights_tests;
#[cfg(test)]
mod metal_tests;
#[cfg(test)]
mod skybox_tests;
#[cfg(test)]
mod tests;

/// glTF's unit of length is the metre (glTF 2.0 specification, §3.4).
pub(crate) const UNITS_PER_METRE: f64 = 1.0;

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

/// What a glTF file contributes: geometry and materials, a camera, and its
/// punctual lights.
pub(crate) struct GltfScene {
    pub raw: RawScene,
    pub camera: Option<Camera>,
    pub lights: Lights,
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
    #[allow(clippy::disallowed_methods)] // An edge: an importer reads its scene file.
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

    let (mut raw, camera, light_nodes) = nodes::walk(&ctx, &document, &buffers)?;
    warnings.append(&mut raw.warnings);
    let lights = lights::read_lights(&ctx, &document, &light_nodes, &mut warnings)?;
    raw.warnings = warnings;
    Ok(GltfScene {
        raw,
        camera,
        lights,
    })
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

/// Warnings about features of the file as a whole.
fn document_warnings(ctx: &Context, document: &Document, warnings: &mut Vec<Warning>) {
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
