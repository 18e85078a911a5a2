//! Scenes as the solver sees them: planar polygons with materials, re-centred in
//! f64, with the settings that travel into the solution header.
//!
//! Importers for OBJ + MTL, the TOML scene config, the legacy geometry file
//! (Remington 1992, appendix B) and the display parameter file (Remington 1992, appendix A) all produce a
//! [`Scene`]. Units: positions in scene units, `emission` is emitted radiance
//! (W·sr⁻¹·m⁻², linear RGB), `kd`/`ks` are reflectances in [0, 1].

use crate::settings::SettingsPatch;
use glam::DVec3;
use solution::camera::{Camera, UpAxis};
use std::path::{Path, PathBuf};

mod clean;
mod config;
mod config_lights;
mod display;
mod emitter_hint;
mod envmap_file;
mod error;
mod gltf;
mod legacy;
mod light_flags;
mod metal_texture;
mod mtl;
mod obj;
mod path_case;
pub(crate) mod planar;
mod raw;
mod recentre;
mod shell;
mod skybox;
pub mod smooth;
mod text;
mod texture_file;
pub mod uv;
mod weld;

/// A hash map for integer keys derived from geometry (`weld::IntHasher`), and
/// the welder's vertex matching (for finding openings, `light::portal_detect`).
pub(crate) use weld::{IntMap, VertexIds};

#[cfg(test)]
mod hostile_tests;
#[cfg(test)]
mod lights_tests;
#[cfg(test)]
mod tests;

pub use clean::{
    COLLINEAR_TOLERANCE, MAX_EMISSION, MAX_POLYGON_VERTICES, PLANARITY_TOLERANCE,
    REPEATED_VERTEX_TOLERANCE, SMOOTH_NORMAL_DEGREES, ZERO_AREA_TOLERANCE,
};
pub use config::{Length, MeshSizes};
pub use display::{load_display_file, DisplayParams};
pub(crate) use emitter_hint::{distinct_files, no_emitter_hint};
pub use error::SceneError;
pub use light_flags::{
    LightFlags, SkyFlag, SkyFlagKind, SunFlag, DEFAULT_SKY_LUX, DEFAULT_SUN_LUX,
};
pub use mtl::alpha_from_ns;
pub use smooth::{smooth_scene, SmoothReport, DEFAULT_CREASE_ANGLE, SMOOTH_TOLERANCE};
pub use texture_file::{MAX_TEXTURE_FILE_BYTES, MAX_TEXTURE_SIZE, MAX_TEXTURE_TEXELS};
pub use uv::UvMap;
pub use weld::WELD_TOLERANCE;

/// Where a piece of input came from, for warnings and errors.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct SourceRef {
    pub file: PathBuf,
    /// 1-based line number, when the parser knows it.
    pub line: Option<usize>,
    /// A human name for the item: "face 12", "polygon 3", "material white".
    pub item: String,
}

impl std::fmt::Display for SourceRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        if !self.item.is_empty() {
            write!(f, " ({})", self.item)?;
        }
        Ok(())
    }
}

/// A surface material. Kd + Ks ≤ 1 per channel after import (design notes).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Diffuse hemispherical reflectance, linear RGB.
    pub kd: DVec3,
    /// Reflectance of the glossy lobe, linear RGB.
    pub ks: DVec3,
    /// RMS surface slope of the glossy lobe (Remington 1992, eq. 4.1).
    pub alpha: f64,
    /// Emitted radiance, linear RGB, one-sided toward the polygon normal.
    pub emission: DVec3,
    /// The diffuse texture (MTL `map_Kd`): the reflectance at a point is
    /// `kd ⊙ texture(uv)` (the MTL convention: Kd multiplies the map) where
    /// the polygon has UVs, `kd` elsewhere.
    pub diffuse_texture: Option<std::sync::Arc<SceneTexture>>,
    /// The emission texture (MTL `map_Ke`, glTF `emissiveTexture`): the
    /// emitted radiance at a point is `emission ⊙ texture(uv)` (docs/textures.md,
    /// "Emissive textures") where the polygon has UVs, `emission` elsewhere.
    pub emission_texture: Option<std::sync::Arc<SceneTexture>>,
    /// The diffuse-mode reflectance per texel where glTF's
    /// metallic-roughness texture makes the fold of Ks into Kd vary
    /// (`metal_texture.rs`): the reflectance at a point is this texture's
    /// value (factor 1) where the polygon has UVs, in diffuse mode only;
    /// directional mode keeps `kd ⊙ diffuse_texture` and the flat Ks.
    pub folded_texture: Option<std::sync::Arc<SceneTexture>>,
}

/// A decoded diffuse texture: the 8-bit sRGB texels as read (for the solution
/// file) and the linear pyramid the solve and the path tracer integrate.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneTexture {
    pub file: PathBuf,
    pub width: u32,
    pub height: u32,
    /// `width × height × 4` bytes, sRGB-encoded RGBA, rows top to bottom.
    pub rgba: Vec<u8>,
    pub texture: crate::texture::Texture,
}

impl SceneTexture {
    /// A texture from sRGB-encoded RGBA texels (`width × height × 4` bytes,
    /// rows top to bottom); `None` when the sizes do not match.
    pub fn from_rgba(
        file: PathBuf,
        width: u32,
        height: u32,
        rgba: Vec<u8>,
    ) -> Option<SceneTexture> {
        let texture =
            crate::texture::Texture::from_srgb(width as usize, height as usize, &rgba, 4)?;
        Some(SceneTexture {
            file,
            width,
            height,
            rgba,
            texture,
        })
    }

    /// Bytes held (the RGBA texels and the linear pyramid).
    pub fn bytes(&self) -> u64 {
        self.rgba.len() as u64 + self.texture.bytes()
    }
}

impl Material {
    pub fn is_emitter(&self) -> bool {
        self.emission.max_element() > 0.0
    }
    pub fn is_glossy(&self) -> bool {
        self.ks.max_element() > 0.0
    }
    /// The diffuse reflectance that stands for this material in diffuse mode:
    /// Kd plus the glossy lobe's specular albedo, per channel, capped at 1.
    /// The lobe is normalised so that its cosine-weighted hemispherical
    /// integral is Ks at every incidence (Remington 1992's `C_R`;
    /// `brdf::GlossyLobe::albedo`), so Ks is the fraction of the incident
    /// power it reflects, and a Lambertian Kd + Ks reflects the same power,
    /// only spread evenly instead of about the mirror direction. Without
    /// the fold a metal (Kd = 0) would be black in diffuse mode. The cap
    /// only matters for inputs the importer has not already scaled (it
    /// keeps Kd + Ks ≤ 1). A diffuse texture multiplies the result as it
    /// multiplies Kd, so on a textured material the texture scales Ks too:
    /// what glTF's metallic-roughness model does for a metal (its specular
    /// colour is the textured base colour), and less than an MTL's flat Ks
    /// where the texture is dark. The solver ([`crate::solve::Solver::new`])
    /// and the reference path tracer both call this, so that they agree.
    pub fn diffuse_equivalent_kd(&self) -> DVec3 {
        (self.kd + self.ks).min(DVec3::ONE)
    }
    /// The factor and texture whose product is the diffuse-mode reflectance
    /// where a polygon has UVs: the per-texel fold (factor 1) when glTF's
    /// metallic-roughness texture gave one, else
    /// [`Material::diffuse_equivalent_kd`] times the diffuse texture; `None`
    /// for an untextured material. The solver and the path tracer both call
    /// this in diffuse mode.
    pub fn diffuse_mode_texture(&self) -> Option<(DVec3, &std::sync::Arc<SceneTexture>)> {
        match &self.folded_texture {
            Some(t) => Some((DVec3::ONE, t)),
            None => self
                .diffuse_texture
                .as_ref()
                .map(|t| (self.diffuse_equivalent_kd(), t)),
        }
    }
    /// The reflectance at texture coordinate `uv` (bilinear texture sample
    /// times Kd), or the flat Kd when the material has no texture or the
    /// point no UV.
    pub fn kd_at(&self, uv: Option<glam::DVec2>) -> DVec3 {
        match (&self.diffuse_texture, uv) {
            (Some(t), Some(uv)) => self.kd * t.texture.bilinear(uv),
            _ => self.kd,
        }
    }
    /// The emitted radiance at texture coordinate `uv` (bilinear texture
    /// sample times the emission), or the flat emission when the material has
    /// no emission texture or the point no UV.
    pub fn emission_at(&self, uv: Option<glam::DVec2>) -> DVec3 {
        match (&self.emission_texture, uv) {
            (Some(t), Some(uv)) => self.emission * t.texture.bilinear(uv),
            _ => self.emission,
        }
    }
}

/// A planar, convex-or-not simple polygon after import and welding.
#[derive(Clone, Debug, PartialEq)]
pub struct Polygon {
    /// Re-centred positions, counter-clockwise seen from the front.
    pub vertices: Vec<DVec3>,
    /// Per-vertex shading normals for curved (smooth) surfaces; `None` for flat ones.
    pub vertex_normals: Option<Vec<DVec3>>,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// Texture coordinates as an affine map of position ([`uv`]), when the
    /// input gave UVs.
    pub uv_map: Option<UvMap>,
    /// User-set patch subdivision (Remington 1992, appendix B `patch N`): N × N patches.
    pub patches: u32,
    /// Per-object target patch size and smallest element (TOML config).
    pub sizes: MeshSizes,
    pub source: SourceRef,
}

impl Polygon {
    /// Newell's normal, normalised; zero for a degenerate polygon.
    pub fn normal(&self) -> DVec3 {
        let mut n = DVec3::ZERO;
        for (i, a) in self.vertices.iter().enumerate() {
            let b = self.vertices[(i + 1) % self.vertices.len()];
            n += a.cross(b);
        }
        n.normalize_or_zero()
    }

    /// Area by Newell's formula.
    pub fn area(&self) -> f64 {
        let mut n = DVec3::ZERO;
        for (i, a) in self.vertices.iter().enumerate() {
            let b = self.vertices[(i + 1) % self.vertices.len()];
            n += a.cross(b);
        }
        0.5 * n.length()
    }
}

/// A warning about the input: what was changed and where.
#[derive(Clone, Debug, PartialEq)]
pub struct Warning {
    pub source: SourceRef,
    pub message: String,
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.source, self.message)
    }
}

/// A scene ready for meshing.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub polygons: Vec<Polygon>,
    pub materials: Vec<Material>,
    pub units_per_metre: f64,
    pub up_axis: UpAxis,
    /// The initial camera in original scene coordinates, if the input names one.
    pub camera: Option<Camera>,
    /// The bounding-box centre subtracted (in f64) from every input position.
    pub recentre_offset: DVec3,
    /// The sun, sky and lamps (`crate::light`), in the polygons' re-centred
    /// frame (lamp positions less [`Scene::recentre_offset`]); empty when
    /// only emissive materials light the scene.
    pub lights: crate::light::Lights,
    pub warnings: Vec<Warning>,
}

/// `Polygon::patches` of a polygon whose input did not set a subdivision: the
/// mesh sizes it by `patch_size` (`mesh::sizing`).
pub const PATCHES_UNSET: u32 = 0;

impl Scene {
    /// Gives every polygon whose input left the patch subdivision unset
    /// ([`PATCHES_UNSET`]) `patches` × `patches` patches, as a legacy geometry
    /// file's per-polygon counts would: for tests and measurements that want
    /// a fixed count instead of sizing by `patch_size`.
    pub fn fill_default_patches(&mut self, patches: u32) {
        for polygon in &mut self.polygons {
            if polygon.patches == PATCHES_UNSET {
                polygon.patches = patches;
            }
        }
    }
}

/// Choices the caller makes about an import.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportOptions {
    /// Turn every import warning into an error ([`SceneError::Strict`]). A TOML
    /// config's `[solver] strict = true` turns it on as well.
    pub strict: bool,
    /// Patch subdivision for polygons whose input sets none; [`PATCHES_UNSET`]
    /// (the default) leaves them to be sized by `patch_size`.
    pub default_patches: u32,
    /// Scene units per metre from the command line; wins over the TOML config's.
    /// Neither given: 1.
    pub units_per_metre: Option<f64>,
    /// A sun and a sky from the command line, which replace the scene's.
    pub lights: LightFlags,
}

impl Default for ImportOptions {
    fn default() -> Self {
        ImportOptions {
            strict: false,
            default_patches: PATCHES_UNSET,
            units_per_metre: None,
            lights: LightFlags::default(),
        }
    }
}

/// A scene with the settings its input carries.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedScene {
    pub scene: Scene,
    /// Settings from the TOML config (`[solver]`, `mode`, `units_per_metre`);
    /// empty for OBJ and legacy files. Precedence: above the display file's
    /// settings, below command-line flags.
    pub settings: SettingsPatch,
    /// The display file a TOML config names (its `settings` rank below the
    /// config's). Its camera is already in [`Scene::camera`] unless the config's
    /// `[camera]` replaced it.
    pub display: Option<DisplayParams>,
}

/// Imports a scene, choosing the reader by extension (case-insensitive):
/// `.obj` (with its MTL libraries), `.toml` (a scene config naming geometry
/// files), `.gltf` / `.glb` (glTF 2.0, in metres, its first perspective camera
/// the scene's), anything else (e.g. `.geom`) the legacy geometry file of Remington 1992
/// appendix B. Positions are re-centred in f64, polygons cleaned and welded;
/// see [`Scene::warnings`] for what was changed.
pub fn load_scene(path: &Path, options: &ImportOptions) -> Result<LoadedScene, SceneError> {
    if let Some(u) = options.units_per_metre {
        if !(u.is_finite() && u > 0.0) {
            return Err(SceneError::at(
                path,
                None,
                "",
                format!("units_per_metre must be finite and > 0, is {u}"),
            ));
        }
    }
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let mut build = clean::BuildOptions {
        strict: options.strict,
        default_patches: options.default_patches,
        units_per_metre: options.units_per_metre.unwrap_or(1.0),
        up_axis: UpAxis::default(),
        camera: None,
        lights: Default::default(),
        portal_mode: Default::default(),
        from_config: false,
    };
    let mut axes = None;
    let (raw, settings, display) = match extension.as_deref() {
        Some("toml") => {
            let c = config::load_config(path, options.units_per_metre)?;
            build.lights = c.lights;
            build.portal_mode = c.portal_mode;
            build.from_config = true;
            axes = Some(c.axes);
            build.strict |= c.settings.strict == Some(true);
            build.units_per_metre = options.units_per_metre.or(c.units_per_metre).unwrap_or(1.0);
            build.up_axis = c.up_axis;
            build.camera = c.camera;
            (c.raw, c.settings, c.display)
        }
        Some("obj") => (obj::parse_obj(path)?, SettingsPatch::default(), None),
        Some("gltf") | Some("glb") => {
            let g = self::gltf::parse_gltf(path)?;
            build.units_per_metre = options
                .units_per_metre
                .unwrap_or(self::gltf::UNITS_PER_METRE);
            build.camera = g.camera;
            build.lights = g.lights;
            (g.raw, SettingsPatch::default(), None)
        }
        Some("mtl") => {
            return Err(SceneError::at(
                path,
                None,
                "",
                "an MTL file holds materials only: load the OBJ file that names it in `mtllib`",
            ))
        }
        Some("display") => {
            return Err(SceneError::at(
                path,
                None,
                "",
                "this is a display parameter file (Remington 1992, appendix A), not a scene: name it as \
                 `display = ...` in a TOML scene config, or pass it to the solver separately",
            ))
        }
        _ => (legacy::parse_legacy(path)?, SettingsPatch::default(), None),
    };
    if !options.lights.is_empty() {
        let axes = match axes {
            Some(axes) => axes,
            None => config_lights::scene_axes(build.up_axis, None)
                .map_err(|e| SceneError::at(path, None, "", e.to_string()))?,
        };
        options.lights.apply(&mut build.lights, &axes, path)?;
    }
    let scene = clean::build_scene(raw, &build)?;
    Ok(LoadedScene {
        scene,
        settings,
        display,
    })
}
