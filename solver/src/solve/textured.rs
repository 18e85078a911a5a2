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
//! Directional mode keeps the same E/π beside its SH
//! (`directional/textured.rs`), the Gauss–Seidel method gathers it per patch
//! (`gauss_seidel.rs`), and the global-cube method reflects the texture's
//! mean and shows the texture (`cube_textured.rs`); docs/textures.md, "Modes
//! and methods".

use crate::mesh::Mesh;
use crate::scene::{Scene, SceneTexture, UvMap};
use glam::{DVec2, DVec3};
use std::sync::Arc;

/// One textured surface's texture, Kd and UV map.
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
        SurfaceTexturing {
            per_surface,
            offset,
        }
    }

    pub fn any(&self) -> bool {
        self.per_surface.iter().any(Option::is_some)
    }

    pub fn get(&self, surface: u32) -> Option<&Textured> {
        self.per_surface.get(surface as usize)?.as_ref()
    }

    /// The UV of a point (solver coordinates) on a textured surface.
    pub fn uv(&self, t: &Textured, position: DVec3) -> DVec2 {
        t.map.at(position + self.offset)
    }

    /// Bytes of the distinct textures held.
    pub fn texture_bytes(&self) -> u64 {
        let mut seen: Vec<*const SceneTexture> = Vec::new();
        let mut bytes = 0;
        for t in self.per_surface.iter().flatten() {
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
