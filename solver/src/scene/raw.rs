//! The parsers' common output before cleaning: polygons in the input's original
//! f64 coordinates, materials as written, and where each came from. The TOML
//! config edits this form (overrides) before [`super::clean`] turns it into a
//! [`super::Scene`].

use super::{SourceRef, Warning};
use glam::{DVec2, DVec3};
use std::path::PathBuf;

/// Diffuse reflectance given to a material that the input uses but never defines
/// (MTL's customary default, and what modelling tools show for such faces).
pub(crate) const DEFAULT_KD: f64 = 0.8;

/// A material as the input file wrote it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RawMaterial {
    pub name: String,
    /// Other names a TOML override may use (a legacy attribute's `material N`).
    pub aliases: Vec<String>,
    pub kd: DVec3,
    pub ks: DVec3,
    pub alpha: f64,
    pub emission: DVec3,
    /// Where it was defined (MTL `newmtl` line, legacy attribute line).
    pub source: SourceRef,
    /// Where a TOML override last changed it.
    pub overridden_at: Option<SourceRef>,
    /// A warning to give if nothing defines this material (a `usemtl` name missing
    /// from every MTL file, or faces with no `usemtl`); a TOML override clears it.
    pub undefined: Option<Warning>,
    /// An error to give if a polygon uses this material and no TOML override
    /// replaces it: a legacy attribute's `material m` names a reflectance file
    /// (Remington 1992, appendix F) that is not read ([`super::legacy`]).
    pub unread_reflectance_file: Option<(SourceRef, String)>,
    /// Warnings for statements the input gives but the solver does not model
    /// (MTL textures, transparency, `illum` 3–9, ...), one per statement kind,
    /// given by [`super::clean`] only if a polygon uses the material.
    pub unmodelled: Vec<Warning>,
    /// The diffuse texture (MTL `map_Kd`), resolved against the MTL file's
    /// folder, and where it was named. Read by [`super::clean`] only if a
    /// polygon uses the material.
    pub diffuse_map: Option<(PathBuf, SourceRef)>,
    /// The diffuse texture's encoded bytes when they are not a file of their
    /// own (a glTF image in a buffer view or a data URI); `diffuse_map`'s
    /// path then only names them in messages.
    pub diffuse_bytes: Option<std::sync::Arc<[u8]>>,
    /// The emission texture (MTL `map_Ke`, glTF `emissiveTexture`), as
    /// `diffuse_map`; it multiplies `emission`.
    pub emission_map: Option<(PathBuf, SourceRef)>,
    /// Its encoded bytes when they are not a file of their own.
    pub emission_bytes: Option<std::sync::Arc<[u8]>>,
    /// glTF's metallic-roughness texture with the factors it multiplies,
    /// read by [`super::clean`] only if a polygon uses the material
    /// ([`super::metal_texture`]).
    pub metal_map: Option<MetalMap>,
    /// glTF `KHR_materials_unlit`: a picture shown as is, which on an
    /// enclosing shell marks a skybox ([`super::skybox`]).
    pub unlit: bool,
}

/// A glTF `metallicRoughnessTexture` (B: metalness, G: roughness, linear)
/// and the material's factors, from which [`super::metal_texture`] derives
/// Kd, Ks, α and the diffuse-mode reflectance texture.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct MetalMap {
    /// The image file, or the glTF file and image index naming its bytes.
    pub file: PathBuf,
    /// The encoded image when it is not a file of its own.
    pub bytes: Option<std::sync::Arc<[u8]>>,
    /// The material, for warnings.
    pub source: SourceRef,
    /// `baseColorFactor` (rgb), `metallicFactor` and `roughnessFactor`,
    /// clamped to [0, 1].
    pub base_colour: DVec3,
    pub metallic: f64,
    pub roughness: f64,
}

impl RawMaterial {
    /// A material that the input uses but does not define.
    pub fn undefined(name: &str, source: SourceRef, message: String) -> Self {
        RawMaterial {
            name: name.to_owned(),
            aliases: Vec::new(),
            kd: DVec3::splat(DEFAULT_KD),
            ks: DVec3::ZERO,
            alpha: 1.0,
            emission: DVec3::ZERO,
            source: source.clone(),
            overridden_at: None,
            undefined: Some(Warning { source, message }),
            unread_reflectance_file: None,
            unmodelled: Vec::new(),
            diffuse_map: None,
            diffuse_bytes: None,
            emission_map: None,
            emission_bytes: None,
            metal_map: None,
            unlit: false,
        }
    }

    /// Whether a TOML override key addresses this material.
    pub fn answers_to(&self, key: &str) -> bool {
        self.name == key || self.aliases.iter().any(|a| a == key)
    }
}

/// A polygon as the input file wrote it, in original coordinates.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RawPolygon {
    pub vertices: Vec<DVec3>,
    /// One shading normal per vertex when the input gave them (OBJ `vn`, legacy
    /// `normal`), not yet normalised or compared with the facet.
    pub normals: Option<Vec<DVec3>>,
    /// One texture coordinate per vertex when the input gave them (OBJ `vt`,
    /// OBJ orientation: v grows upwards).
    pub uvs: Option<Vec<DVec2>>,
    /// Index into [`RawScene::materials`].
    pub material: usize,
    /// Patch subdivision the input asked for (legacy `patch N`, TOML overrides).
    pub patches: Option<u32>,
    /// Per-object patch and element sizes (TOML overrides).
    pub sizes: super::MeshSizes,
    /// OBJ object or group name, for TOML `[objects.NAME]` overrides.
    pub object: Option<String>,
    pub source: SourceRef,
}

/// Everything parsed from one or more files.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct RawScene {
    pub polygons: Vec<RawPolygon>,
    pub materials: Vec<RawMaterial>,
    pub warnings: Vec<Warning>,
    /// The geometry files read, for messages about the scene as a whole.
    pub files: Vec<PathBuf>,
}

impl RawScene {
    /// Appends `other`, re-indexing its polygons' materials.
    pub fn append(&mut self, other: RawScene) {
        let offset = self.materials.len();
        self.materials.extend(other.materials);
        self.polygons
            .extend(other.polygons.into_iter().map(|mut p| {
                p.material += offset;
                p
            }));
        self.warnings.extend(other.warnings);
        self.files.extend(other.files);
    }
}
