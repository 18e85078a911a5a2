//! The glTF JSON document of an export: one mesh and node per exported batch,
//! one unlit material, the header's camera, one buffer (glTF 2.0
//! specification, §3.6–§3.10; `KHR_materials_unlit`).

use super::{ExportOptions, RADIANCE_ATTRIBUTE};
use serde_json::{json, Value};

/// `bufferView.target` values (§5.11): vertex attributes and indices.
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
/// `accessor.componentType` values (§3.6.2.2).
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
/// `primitive.mode`: triangles.
const TRIANGLES: u32 = 4;
/// Sampler values (§5.26).
const LINEAR: u32 = 9729;
const LINEAR_MIPMAP_LINEAR: u32 = 9987;
const REPEAT: u32 = 10497;

/// Where one exported batch lies in the binary buffer: its attributes one
/// after the other (positions, normals, COLOR_0, the radiance attribute, each
/// `12 × vertices` bytes), then its indices.
#[derive(Clone, Debug)]
pub(crate) struct Placed {
    pub batch: usize,
    pub name: String,
    pub offset: u64,
    pub vertices: u64,
    pub indices: u64,
    /// A textured batch's texture index and linear factor: `TEXCOORD_0`
    /// follows the four attributes, and the batch has its own material.
    pub texture: Option<(u32, [f32; 3])>,
    /// A textured batch's emission texture and its factor Ke (solution format
    /// 3's second slot): the material's `emissiveTexture` and factor.
    pub emission: Option<(u32, [f32; 3])>,
    /// The smallest and largest exported position per axis (the spec requires
    /// them on `POSITION`, §3.7.2.1).
    pub min: [f32; 3],
    pub max: [f32; 3],
}

/// The header camera as glTF wants it.
pub(crate) struct CameraJson {
    pub translation: [f64; 3],
    pub rotation: [f64; 4],
    pub yfov_rad: f64,
    pub aspect: f64,
    pub znear_m: f64,
    pub zfar_m: Option<f64>,
}

/// The material every primitive uses: unlit, white, so that a viewer shows
/// COLOR_0 as it is (the extension's colour is baseColorFactor × COLOR_0).
/// Metallic 0 and roughness 1 are the fallback the extension recommends for
/// viewers without it (a white diffuse surface lit by the viewer's lights).
pub(crate) const MATERIAL_NAME: &str = "solution radiance (unlit)";

/// The whole document. `bin_uri` is the `.bin` file's URI for a `.gltf`,
/// `None` for a `.glb` (the buffer is the BIN chunk, §4.4.3.3).
pub(crate) fn document(
    placed: &[Placed],
    images: &[(u64, u64)],
    bin_length: u64,
    bin_uri: Option<&str>,
    camera: &CameraJson,
    options: &ExportOptions,
    glossy_eye: [f64; 3],
) -> Value {
    let mut parts = Parts::new();
    for p in placed {
        parts.add_batch(p, f64::from(options.exposure_stops));
    }
    parts.nodes.push(json!({
        "name": "camera (solution header)",
        "camera": 0,
        "translation": camera.translation,
        "rotation": camera.rotation,
    }));
    let mut buffer = json!({"byteLength": bin_length});
    if let Some(uri) = bin_uri {
        buffer["uri"] = json!(uri);
    }
    let mut doc = json!({
        "asset": {
            "version": "2.0",
            "generator": concat!("solver export ", env!("CARGO_PKG_VERSION")),
            "extras": asset_extras(options, glossy_eye),
        },
        "extensionsUsed": if parts.emissive_strength {
            json!(["KHR_materials_unlit", "KHR_materials_emissive_strength"])
        } else {
            json!(["KHR_materials_unlit"])
        },
        "scene": 0,
        "scenes": [{"name": "solution", "nodes": (0..parts.nodes.len()).collect::<Vec<_>>()}],
        "nodes": parts.nodes,
        "materials": parts.materials,
        "cameras": [{"name": "solution header", "type": "perspective", "perspective": perspective(camera)}],
    });
    if !images.is_empty() {
        add_images(&mut doc, images, &mut parts.views);
    }
    if !parts.meshes.is_empty() {
        doc["meshes"] = json!(parts.meshes);
        doc["accessors"] = json!(parts.accessors);
    }
    if !parts.views.is_empty() {
        doc["bufferViews"] = json!(parts.views);
        doc["buffers"] = json!([buffer]);
    }
    doc
}

/// The document's arrays as the batches fill them, in glTF index order.
struct Parts {
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    materials: Vec<Value>,
    /// Whether some material needed `KHR_materials_emissive_strength`.
    emissive_strength: bool,
}

impl Parts {
    fn new() -> Self {
        Parts {
            views: Vec::new(),
            accessors: Vec::new(),
            meshes: Vec::new(),
            nodes: Vec::new(),
            materials: vec![unlit_material(MATERIAL_NAME, [1.0; 3], None)],
            emissive_strength: false,
        }
    }

    /// A buffer view of `length` bytes at `offset` and an accessor over it;
    /// the accessor's index.
    fn view_and_accessor(
        &mut self,
        offset: u64,
        length: u64,
        target: u32,
        accessor: Value,
    ) -> usize {
        let mut accessor = accessor;
        accessor["bufferView"] = json!(self.views.len());
        self.views.push(json!({
            "buffer": 0,
            "byteOffset": offset,
            "byteLength": length,
            "target": target,
        }));
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// One exported batch: its four VEC3 attributes, a textured batch's UVs
    /// and material, its indices, and its mesh and node.
    fn add_batch(&mut self, p: &Placed, exposure_stops: f64) {
        let mut base = None;
        for k in 0..4u64 {
            let mut accessor = json!({"componentType": FLOAT, "count": p.vertices, "type": "VEC3"});
            if k == 0 {
                accessor["min"] = json!(p.min);
                accessor["max"] = json!(p.max);
            }
            let offset = p.offset + k * 12 * p.vertices;
            let index = self.view_and_accessor(offset, 12 * p.vertices, ARRAY_BUFFER, accessor);
            base.get_or_insert(index);
        }
        let base = base.unwrap_or_default();
        let mut attributes = json!({
            "POSITION": base,
            "NORMAL": base + 1,
            "COLOR_0": base + 2,
            RADIANCE_ATTRIBUTE: base + 3,
        });
        let mut end = p.offset + 48 * p.vertices;
        let mut material = 0;
        if let Some((texture, factor)) = p.texture {
            let accessor = json!({"componentType": FLOAT, "count": p.vertices, "type": "VEC2"});
            attributes["TEXCOORD_0"] =
                json!(self.view_and_accessor(end, 8 * p.vertices, ARRAY_BUFFER, accessor));
            end += 8 * p.vertices;
            material = self.materials.len();
            self.add_textured_material(p, texture, factor, exposure_stops);
        }
        let accessor = json!({"componentType": UNSIGNED_INT, "count": p.indices, "type": "SCALAR"});
        let indices = self.view_and_accessor(end, 4 * p.indices, ELEMENT_ARRAY_BUFFER, accessor);
        self.nodes
            .push(json!({"name": p.name, "mesh": self.meshes.len()}));
        self.meshes.push(json!({
            "name": p.name,
            "primitives": [{
                "attributes": attributes,
                "indices": indices,
                "material": material,
                "mode": TRIANGLES,
                "extras": {"solution_batch": p.batch},
            }],
        }));
    }

    /// A textured batch's own material, with its emission texture if any.
    fn add_textured_material(&mut self, p: &Placed, texture: u32, factor: [f32; 3], stops: f64) {
        let name = format!("{} (textured)", p.name);
        let mut material = unlit_material(&name, factor, Some(texture));
        if let Some((emission, ke)) = p.emission {
            add_emission(&mut material, emission, ke, stops);
            self.emissive_strength |= material["extensions"]
                .get("KHR_materials_emissive_strength")
                .is_some();
        }
        self.materials.push(material);
    }
}

/// The header camera's perspective projection (§5.13).
fn perspective(camera: &CameraJson) -> Value {
    let mut perspective = json!({
        "yfov": camera.yfov_rad,
        "aspectRatio": camera.aspect,
        "znear": camera.znear_m,
    });
    if let Some(zfar) = camera.zfar_m {
        perspective["zfar"] = json!(zfar);
    }
    perspective
}

/// The PNG images (a buffer view each), their textures and the one sampler.
fn add_images(doc: &mut Value, images: &[(u64, u64)], views: &mut Vec<Value>) {
    let mut image_list = Vec::new();
    for &(offset, length) in images {
        image_list.push(json!({"bufferView": views.len(), "mimeType": "image/png"}));
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": length}));
    }
    doc["images"] = json!(image_list);
    doc["textures"] = json!((0..images.len())
        .map(|k| json!({"sampler": 0, "source": k}))
        .collect::<Vec<_>>());
    // Trilinear and repeating, as the runtime samples (docs/solution-format.md).
    doc["samplers"] = json!([{
        "magFilter": LINEAR,
        "minFilter": LINEAR_MIPMAP_LINEAR,
        "wrapS": REPEAT,
        "wrapT": REPEAT,
    }]);
}

/// An unlit material: `factor` (linear) as the base colour, times the
/// sRGB-encoded `texture` if any (glTF 2.0 §3.9.2, `KHR_materials_unlit`).
fn unlit_material(name: &str, factor: [f32; 3], texture: Option<u32>) -> Value {
    let mut pbr = json!({
        "baseColorFactor": [factor[0], factor[1], factor[2], 1.0],
        "metallicFactor": 0.0,
        "roughnessFactor": 1.0,
    });
    if let Some(index) = texture {
        pbr["baseColorTexture"] = json!({"index": index});
    }
    json!({
        "name": name,
        "pbrMetallicRoughness": pbr,
        "extensions": {"KHR_materials_unlit": {}},
    })
}

/// Adds a textured batch's emission (the solution's second texture slot) to
/// its unlit material: `emissiveTexture` the emission texture, and the factor
/// Ke × 2^exposure, the display value the runtime's clamp tone map gives the
/// emission below saturation (COLOR_0 holds the curve of E/π × 2^exposure the
/// same way). glTF caps `emissiveFactor` at 1 (§5.19), so a larger factor is
/// divided by its largest channel, which becomes
/// `KHR_materials_emissive_strength`.
fn add_emission(material: &mut Value, texture: u32, ke: [f32; 3], exposure_stops: f64) {
    let scaled = ke.map(|k| f64::from(k) * exposure_stops.exp2());
    let strength = scaled.iter().fold(1.0f64, |m, &x| m.max(x));
    material["emissiveTexture"] = json!({"index": texture});
    material["emissiveFactor"] = json!(scaled.map(|x| x / strength));
    if strength > 1.0 {
        material["extensions"]["KHR_materials_emissive_strength"] =
            json!({"emissiveStrength": strength});
    }
}

/// What the attributes hold, in the file itself, for whoever reads it back.
fn asset_extras(options: &ExportOptions, glossy_eye: [f64; 3]) -> Value {
    json!({
        "COLOR_0": "linear display value y = curve(radiance × 2^exposure_stops) in 0..1: \
                    a viewer that writes y through an sRGB framebuffer without a tone map of \
                    its own shows the runtime's PNG pixel",
        "tone_curve": super::curve_name(options.curve),
        "exposure_stops": options.exposure_stops,
        RADIANCE_ATTRIBUTE: "linear radiance, W·sr⁻¹·m⁻² per RGB channel, negative values clamped to 0",
        "glossy_eye_scene_units": glossy_eye,
        "units": "metres, +y up (positions baked from the solution's units and up axis)",
    })
}
