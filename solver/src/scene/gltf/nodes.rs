//! The scene-graph walk: node matrices composed in f64, each mesh's
//! primitives assembled into triangles and placed, the first perspective
//! camera taken, and each material converted on first use.

use super::accessors::{read_indices, read_vec2, read_vec3};
use super::container::Buffer;
use super::materials::convert_material;
use super::Context;
use crate::scene::raw::{RawMaterial, RawPolygon, RawScene, DEFAULT_KD};
use crate::scene::SceneError;
use glam::{DAffine2, DMat3, DMat4, DQuat, DVec2, DVec3};
use gltf::mesh::Mode;
use gltf::{Document, Semantic};
use solution::camera::{Camera, MAX_IMAGE_SIDE};
use std::collections::HashMap;

/// The most triangles a file may place in the scene, counting every instance
/// of a mesh. Stored triangles are bounded by the file's bytes, but nodes can
/// instance one mesh many times; each placed triangle costs about 300 bytes
/// through import (its polygon, positions and source), so this caps the
/// import near 3 GB whatever the file claims.
pub(crate) const MAX_PLACED_TRIANGLES: usize = 10_000_000;

/// Image width of the camera taken from a file; the height follows the
/// camera's aspect ratio (square when the file gives none).
const CAMERA_IMAGE_WIDTH: u32 = 512;

/// A node that carries a `KHR_lights_punctual` light, where the walk placed it.
pub(super) struct LightNode {
    /// The node's name for messages ([`node_name`]).
    pub name: String,
    /// The node's `{"light": N}` extension object.
    pub extension: serde_json::Value,
    /// The node's world matrix.
    pub world: DMat4,
}

/// Walks the scene graph ([`Builder::walk_scene`]): the file's triangles and
/// materials, in the raw form, its first perspective camera, and the nodes
/// that carry punctual lights.
pub(super) fn walk(
    ctx: &Context,
    document: &Document,
    buffers: &[Buffer],
) -> Result<(RawScene, Option<Camera>, Vec<LightNode>), SceneError> {
    let mut builder = Builder {
        ctx,
        document,
        buffers,
        raw: RawScene {
            files: vec![ctx.path.to_path_buf()],
            ..Default::default()
        },
        materials: HashMap::new(),
        placed: 0,
        camera: None,
        warned_orthographic: false,
        warned_meshes: Vec::new(),
        uv_maps: HashMap::new(),
        lights: Vec::new(),
    };
    builder.walk_scene()?;
    Ok((builder.raw, builder.camera, builder.lights))
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
    /// The nodes with a punctual light, in walk order.
    lights: Vec<LightNode>,
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
            if let Some(extension) = node.extension_value("KHR_lights_punctual") {
                self.lights.push(LightNode {
                    name: item.clone(),
                    extension: extension.clone(),
                    world,
                });
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
pub(super) fn assemble(mode: Mode, indices: &[u32]) -> Vec<u32> {
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
pub(super) fn camera_from_node(world: DMat4, yfov_rad: f64, aspect: Option<f64>) -> Camera {
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
