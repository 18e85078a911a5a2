//! The scene as the reference path tracer sees it: the imported polygons with
//! their planes, one [`Bsdf`] per material, the closest-hit BVH, the emitter
//! distribution and the lights that are not polygons; plus the material and object names the image's id channels
//! index.

use super::bsdf::Bsdf;
use super::emitters::Emitters;
use super::lights::SceneLights;
use super::lobe::ExactLobe;
use crate::geometry::visibility::Occluder;
use crate::scene::Scene;
use glam::DVec3;
use rayon::prelude::*;
use solution::format::SolveMode;
use std::collections::BTreeMap;
use std::sync::Arc;

/// One polygon: vertices (re-centred scene coordinates), unit normal (Newell),
/// material and object indices.
#[derive(Clone, Debug)]
pub struct Surface {
    pub vertices: Vec<DVec3>,
    pub normal: DVec3,
    pub material: usize,
    pub object: usize,
    /// Corner shading normals of a smooth surface (`scene::smooth`); `None` for
    /// a flat facet.
    pub shading: Option<super::shading::CornerNormals>,
    /// Texture coordinates as a function of position, when the polygon has
    /// them and its material a diffuse or an emission texture.
    pub uv_map: Option<crate::scene::UvMap>,
}

impl Surface {
    /// The unit shading normal at `point` on this polygon: the interpolated
    /// corner normals on a smooth surface, else the polygon's normal.
    pub fn shading_normal(&self, point: DVec3) -> DVec3 {
        match &self.shading {
            Some(c) => c.at(&self.vertices, point, self.normal),
            None => self.normal,
        }
    }
}

/// How the scene's materials are reflected: `solver solve`'s `--mode`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Physics {
    pub mode: SolveMode,
}

/// Everything the integrator reads; `Send + Sync`, built once.
pub struct RenderScene {
    pub surfaces: Vec<Surface>,
    pub bsdfs: Vec<Bsdf>,
    pub occluder: Occluder,
    pub emitters: Emitters,
    /// The sun, the sky and the lamps, re-centred as the surfaces.
    pub lights: SceneLights,
    pub material_names: Vec<String>,
    pub object_names: Vec<String>,
    /// Largest reflectance `max(Kd + Ks)` over the channels of the used materials:
    /// the bound on what each bounce keeps of the light's power.
    pub max_albedo: f64,
    /// Glossy lobes built, by α: their tables' sizes and measured errors.
    pub lobes: Vec<Arc<ExactLobe>>,
    /// Per material, the factor and texture whose product is its diffuse
    /// reflectance where a surface has UVs: Kd (diffuse mode: Ks folded in)
    /// and the diffuse texture, or in diffuse mode the per-texel fold of a
    /// glTF metallic-roughness texture with factor 1.
    pub textures: Vec<Option<(DVec3, Arc<crate::scene::SceneTexture>)>>,
    /// Per material, its emission texture (`map_Ke`), read the same way.
    pub emission_textures: Vec<Option<Arc<crate::scene::SceneTexture>>>,
}

/// The object a polygon belongs to: the OBJ object or group its face came from
/// (the importer names faces "face N of object NAME"), else its source file.
fn object_name(source: &crate::scene::SourceRef) -> String {
    match source.item.split_once(" of object ") {
        Some((_, name)) => name.to_string(),
        None => source
            .file
            .file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_default(),
    }
}

impl RenderScene {
    /// Prepares `scene` (as `scene::load_scene` returns it) for rendering with
    /// `physics`. Glossy lobes (directional mode only) are tabulated once per
    /// distinct α, in parallel.
    pub fn new(scene: &Scene, physics: Physics) -> RenderScene {
        let glossy = physics.mode == SolveMode::Directional;
        let mut alphas: Vec<u64> = scene
            .materials
            .iter()
            .filter(|m| glossy && m.is_glossy())
            .map(|m| m.alpha.to_bits())
            .collect();
        alphas.sort_unstable();
        alphas.dedup();
        let lobes: BTreeMap<u64, Arc<ExactLobe>> = alphas
            .par_iter()
            .map(|&a| {
                let lobe = ExactLobe::new(f64::from_bits(a));
                (a, Arc::new(lobe))
            })
            .collect();
        let bsdfs: Vec<Bsdf> = scene
            .materials
            .iter()
            .map(|m| {
                if !glossy {
                    // Diffuse mode: the solver's fold of the specular albedo
                    // into Kd, so that the truth agrees with what it solves.
                    return Bsdf::new(m.diffuse_equivalent_kd(), DVec3::ZERO, None, m.emission);
                }
                let lobe = if m.is_glossy() {
                    lobes.get(&m.alpha.to_bits()).cloned()
                } else {
                    None
                };
                Bsdf::new(m.kd, m.ks, lobe, m.emission)
            })
            .collect();
        let mut object_names: Vec<String> = Vec::new();
        let mut object_index = BTreeMap::new();
        let surfaces: Vec<Surface> = scene
            .polygons
            .iter()
            .map(|p| {
                let name = object_name(&p.source);
                let next = object_index.len();
                let object = *object_index.entry(name.clone()).or_insert_with(|| {
                    object_names.push(name);
                    next
                });
                let normal = p.normal();
                Surface {
                    shading: p
                        .vertex_normals
                        .as_ref()
                        .and_then(|c| super::shading::CornerNormals::new(&p.vertices, normal, c)),
                    vertices: p.vertices.clone(),
                    normal,
                    material: p.material,
                    object,
                    uv_map: p.uv_map.filter(|_| {
                        let m = &scene.materials[p.material];
                        m.diffuse_texture.is_some()
                            || m.emission_texture.is_some()
                            || m.folded_texture.is_some()
                    }),
                }
            })
            .collect();
        let occluder = Occluder::from_polygons(&scene.polygons);
        let list: Vec<&[DVec3]> = surfaces.iter().map(|s| s.vertices.as_slice()).collect();
        // Emitters are picked by power: an emission-textured one's is its Ke
        // times the texture's mean (a proposal only: the estimate reads
        // Le(uv) at the sampled point, `emission_at`).
        let emission: Vec<DVec3> = surfaces
            .iter()
            .map(|s| {
                let m = &scene.materials[s.material];
                match (&s.uv_map, &m.emission_texture) {
                    (Some(_), Some(t)) => m.emission * t.texture.mean(),
                    _ => bsdfs[s.material].emission,
                }
            })
            .collect();
        let emitters = Emitters::new(&list, &emission);
        let max_albedo = surfaces
            .iter()
            .map(|s| (bsdfs[s.material].kd + bsdfs[s.material].ks).max_element())
            .fold(0.0, f64::max);
        let lights = SceneLights::new(&scene.lights, scene.units_per_metre, bounds_of(&surfaces));
        RenderScene {
            surfaces,
            bsdfs,
            occluder,
            emitters,
            lights,
            material_names: scene.materials.iter().map(|m| m.name.clone()).collect(),
            object_names,
            max_albedo,
            lobes: lobes.into_values().collect(),
            // Diffuse mode reads the per-texel fold where glTF's
            // metallic-roughness texture gave one (`Material::diffuse_mode_texture`).
            textures: scene
                .materials
                .iter()
                .map(|m| match (glossy, m.diffuse_mode_texture()) {
                    (false, Some((kd, t))) => Some((kd, t.clone())),
                    (false, None) => None,
                    (true, _) => m.diffuse_texture.clone().map(|t| (m.kd, t)),
                })
                .collect(),
            emission_textures: scene
                .materials
                .iter()
                .map(|m| m.emission_texture.clone())
                .collect(),
        }
    }

    /// Whether anything lights the scene: an emitting polygon, the sun, the
    /// sky or a lamp.
    pub fn is_lit(&self) -> bool {
        !self.emitters.is_empty() || !self.lights.is_empty()
    }

    /// The BSDF at `point` on surface `polygon`: its material's, with Kd
    /// times the texture's bilinear sample at the point's UV (level 0, repeat
    /// wrap: `Texture::bilinear`) where the surface is textured, and its
    /// emission [`RenderScene::emission_at`] the point. Bilinear rather than
    /// the box texels the solve integrates: the two agree in every integral
    /// over more than a texel, which is all an image pixel or a solver
    /// element sees.
    pub fn bsdf_at(&self, polygon: usize, point: DVec3) -> std::borrow::Cow<'_, Bsdf> {
        let surface = &self.surfaces[polygon];
        let bsdf = &self.bsdfs[surface.material];
        let Some(map) = &surface.uv_map else {
            return std::borrow::Cow::Borrowed(bsdf);
        };
        let kd = match &self.textures[surface.material] {
            Some((kd, texture)) => *kd * texture.texture.bilinear(map.at(point)),
            None => bsdf.kd,
        };
        let emission = self.emission_at(polygon, point);
        std::borrow::Cow::Owned(Bsdf::new(kd, bsdf.ks, bsdf.lobe.clone(), emission))
    }

    /// The radiance emitted at `point` on surface `polygon`: Ke ⊙ the
    /// emission texture's bilinear sample at its UV where it has one (as
    /// [`RenderScene::bsdf_at`] reads Kd), else the flat Ke.
    pub fn emission_at(&self, polygon: usize, point: DVec3) -> DVec3 {
        let surface = &self.surfaces[polygon];
        let le = self.bsdfs[surface.material].emission;
        match (&surface.uv_map, &self.emission_textures[surface.material]) {
            (Some(map), Some(texture)) => le * texture.texture.bilinear(map.at(point)),
            _ => le,
        }
    }

    /// The scene's bounds (re-centred coordinates).
    pub fn bounds(&self) -> (DVec3, DVec3) {
        bounds_of(&self.surfaces)
    }
}

/// The bounding box of `surfaces`' vertices; zero when there are none.
fn bounds_of(surfaces: &[Surface]) -> (DVec3, DVec3) {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for v in surfaces.iter().flat_map(|s| &s.vertices) {
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    if lo.x > hi.x {
        (DVec3::ZERO, DVec3::ZERO)
    } else {
        (lo, hi)
    }
}
