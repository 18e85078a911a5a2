//! Textured surfaces in the diffuse solve.
//!
//! A surface whose material has a diffuse texture and whose polygon has UVs
//! stores per vertex the incident light E/π (irradiance over π), which does
//! not depend on the texture: it receives shots with reflectance 1 (the
//! solver's per-surface `kd` is 1 there). What it reflects is the integral of
//! ρ · E over each patch, with ρ = Kd ⊙ texture(uv): the gather weights of a
//! textured patch are RGB, per vertex v
//!
//!   w_v = Σ over display triangles T with corner v of A_T · Kd ⊙ ∫_T ρ λ_v / A_T,
//!
//! where λ_v is v's barycentric weight, integrated over T's UV triangle by
//! [`crate::texture::Texture::integrate`] (exact for the box-filtered texels
//! at the mip level it picks). With E interpolated linearly over T, as the
//! display does, Σ_v w_v ⊙ ΔE_v/π is exactly ∫ ρ ΔE/π dA over the patch: the
//! energy a textured patch shoots is the integral of what it shows.
//!
//! Refinement sees E/π on textured surfaces (their vertex values), not the
//! reflected radiance, so a checkerboard does not force subdivision to its
//! edges: light variation does. Untextured surfaces keep scalar weights and
//! their radiance representation unchanged.
//!
//! Emission textures (`map_Ke`, glTF `emissiveTexture`; docs/textures.md,
//! "Emissive textures"): Le(uv) = Ke ⊙ texture(uv). A patch of an emitter
//! shoots its mean Le, the integral of Le over the patch by the same texel
//! integration divided by its area ([`SurfaceTexturing::emitted_radiance`]),
//! uniformly, so the total emitted power is π ∫ Le dA exactly. The surface
//! reflects with its flat Kd, untextured; its output vertices carry the
//! texture for display (`output_textured.rs`). Directional mode starts its
//! SH from the same per-patch means (`directional.rs`, `Directional::new`),
//! and the global-cube method adds each patch's mean to its source radiance
//! (`cube_gather`, `cube_emission.rs`).
//!
//! Directional mode keeps the same E/π beside its SH
//! (`directional/textured.rs`), the Gauss–Seidel method gathers it per patch
//! (`gauss_seidel.rs`), and the global-cube method reflects the texture's
//! mean and shows the texture (`cube_textured.rs`); docs/textures.md, "Modes
//! and methods".

use crate::mesh::Mesh;
use crate::scene::{Scene, SceneTexture, UvMap};
use glam::{DVec2, DVec3};
use solution::format::SolveMode;
use std::sync::Arc;

/// Per patch, its mean emitted radiance when its surface has an emission
/// texture ([`SurfaceTexturing::emitted_radiance`]); and each such surface's
/// entry of `emission` set to its mean Le, area-weighted over its patches,
/// which its vertices start with (reflected light is added to it, and the
/// display subtracts it again: `output_textured.rs`).
pub(crate) fn patch_emission(
    texturing: &SurfaceTexturing,
    mesh: &Mesh,
    emission: &mut [DVec3],
) -> Vec<Option<DVec3>> {
    if texturing.emissive.is_empty() {
        return vec![None; mesh.patches.len()];
    }
    let per_patch: Vec<Option<DVec3>> = mesh
        .patches
        .iter()
        .map(|p| texturing.emitted_radiance(p))
        .collect();
    let mut sums = vec![(DVec3::ZERO, 0.0); emission.len()];
    for (p, le) in mesh.patches.iter().zip(&per_patch) {
        if let Some(le) = le {
            let sum = &mut sums[p.surface as usize];
            sum.0 += *le * p.area;
            sum.1 += p.area;
        }
    }
    for (e, (sum, area)) in emission.iter_mut().zip(sums) {
        if area > 0.0 {
            *e = sum / area;
        }
    }
    per_patch
}

/// One textured surface's texture, Kd and UV map. For an emission texture
/// (`SurfaceTexturing::emissive`), `kd` holds the texture's factor Ke.
#[derive(Clone, Debug)]
pub(crate) struct Textured {
    pub texture: Arc<SceneTexture>,
    pub kd: DVec3,
    pub map: UvMap,
}

/// Per mesh surface, its texturing (`None`: untextured).
#[derive(Clone, Debug, Default)]
pub(crate) struct SurfaceTexturing {
    pub per_surface: Vec<Option<Textured>>,
    /// Per mesh surface, its emission texture (`kd` = Ke); empty when no
    /// surface has one.
    pub emissive: Vec<Option<Textured>>,
    /// Solver coordinates plus this are the scene's (re-centred) ones, in
    /// which the UV maps are written.
    offset: DVec3,
}

impl SurfaceTexturing {
    /// The textured surfaces of `mesh` (from `scene`, meshed relative to
    /// `offset`).
    pub fn new(scene: &Scene, mesh: &Mesh, offset: DVec3) -> SurfaceTexturing {
        let per_surface = mesh
            .surfaces
            .iter()
            .map(|s| {
                let material = &scene.materials[s.material];
                let texture = material.diffuse_texture.clone()?;
                let map = scene.polygons.get(s.polygon)?.uv_map?;
                Some(Textured {
                    texture,
                    kd: material.kd,
                    map,
                })
            })
            .collect();
        let mut emissive: Vec<Option<Textured>> = mesh
            .surfaces
            .iter()
            .map(|s| {
                let material = &scene.materials[s.material];
                let texture = material.emission_texture.clone()?;
                let map = scene.polygons.get(s.polygon)?.uv_map?;
                Some(Textured {
                    texture,
                    kd: material.emission,
                    map,
                })
            })
            .collect();
        if emissive.iter().all(Option::is_none) {
            emissive = Vec::new();
        }
        SurfaceTexturing {
            per_surface,
            emissive,
            offset,
        }
    }

    /// Sets each surface's texture and factor for `mode`. Directional mode
    /// reflects Kd ⊙ the diffuse texture (its lobe apart). Diffuse mode
    /// reflects the material's [`crate::scene::Material::diffuse_mode_texture`]:
    /// the diffuse texture times Kd with Ks folded in, or where glTF's
    /// metallic-roughness texture makes the fold vary per texel, that fold
    /// (factor 1), which also textures a surface without a base-colour
    /// texture.
    pub fn set_mode(&mut self, scene: &Scene, mesh: &Mesh, mode: SolveMode) {
        for (s, t) in mesh.surfaces.iter().zip(&mut self.per_surface) {
            let material = &scene.materials[s.material];
            match mode {
                SolveMode::Directional => {
                    if let Some(t) = t {
                        t.kd = material.kd;
                    }
                }
                SolveMode::Diffuse => {
                    let map = scene.polygons.get(s.polygon).and_then(|p| p.uv_map);
                    *t = match (material.diffuse_mode_texture(), map) {
                        (Some((kd, texture)), Some(map)) => Some(Textured {
                            texture: texture.clone(),
                            kd,
                            map,
                        }),
                        _ => None,
                    };
                }
            }
        }
    }

    /// Whether any surface has a diffuse texture.
    pub fn any(&self) -> bool {
        self.per_surface.iter().any(Option::is_some)
    }

    /// Whether any surface has a diffuse or an emission texture.
    pub fn any_display(&self) -> bool {
        self.any() || !self.emissive.is_empty()
    }

    pub fn get(&self, surface: u32) -> Option<&Textured> {
        self.per_surface.get(surface as usize)?.as_ref()
    }

    /// The emission texture of `surface`, if any.
    pub fn emissive(&self, surface: u32) -> Option<&Textured> {
        self.emissive.get(surface as usize)?.as_ref()
    }

    /// The texture `surface` shows (diffuse or emission), if any.
    pub fn shown(&self, surface: u32) -> Option<&Textured> {
        self.get(surface).or_else(|| self.emissive(surface))
    }

    /// The mean emitted radiance of `patch` of an emission-textured surface,
    /// Ke ⊙ ∫ texture dA / A over the patch (triangles fanned from its
    /// first corner, each integrated exactly by
    /// [`crate::texture::Texture::integrate`]); `None` for other surfaces.
    /// Times π and the patch's area, summed over the patches that tile a
    /// surface, it is the surface's π ∫ Le dA.
    pub fn emitted_radiance(&self, patch: &crate::mesh::Patch) -> Option<DVec3> {
        let t = self.emissive(patch.surface)?;
        let corners = patch.polygon();
        let mut integral = DVec3::ZERO;
        let mut area = 0.0;
        for k in 1..corners.len().saturating_sub(1) {
            let p = [corners[0], corners[k], corners[k + 1]];
            let a = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
            if a > 0.0 {
                integral += a * t.texture.texture.integrate(p.map(|q| self.uv(t, q))).mean;
                area += a;
            }
        }
        if area > 0.0 {
            Some(t.kd * integral / area)
        } else {
            Some(t.kd * t.texture.texture.mean())
        }
    }

    /// The UV of a point (solver coordinates) on a textured surface.
    pub fn uv(&self, t: &Textured, position: DVec3) -> DVec2 {
        t.map.at(position + self.offset)
    }

    /// Bytes of the distinct textures held.
    pub fn texture_bytes(&self) -> u64 {
        let mut seen: Vec<*const SceneTexture> = Vec::new();
        let mut bytes = 0;
        for t in self.per_surface.iter().chain(&self.emissive).flatten() {
            let p = Arc::as_ptr(&t.texture);
            if !seen.contains(&p) {
                seen.push(p);
                bytes += t.texture.bytes();
            }
        }
        bytes
    }

    /// The RGB gather weights of a textured patch from its display triangles
    /// (see the module notes), merged per vertex in vertex order.
    pub fn weights(&self, mesh: &Mesh, t: &Textured, triangles: &[[u32; 3]]) -> Vec<(u32, DVec3)> {
        let mut entries: Vec<(u32, DVec3)> = Vec::with_capacity(triangles.len() * 3);
        for tri in triangles {
            let p = tri.map(|i| mesh.vertices[i as usize].position);
            let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
            let integral = t.texture.texture.integrate(p.map(|q| self.uv(t, q)));
            for (&v, corner) in tri.iter().zip(integral.corner) {
                entries.push((v, t.kd * corner * area));
            }
        }
        entries.sort_unstable_by_key(|e| e.0);
        let mut merged: Vec<(u32, DVec3)> = Vec::with_capacity(entries.len() / 2);
        for (v, w) in entries {
            match merged.last_mut() {
                Some(last) if last.0 == v => last.1 += w,
                _ => merged.push((v, w)),
            }
        }
        merged
    }
}
