//! The textured batches of a diffuse solution (`textured.rs`): the output
//! vertices of textured surfaces move out of the untextured batch into one
//! batch per textured material, with per vertex its UV and E/π, the
//! material's Kd as the texture's factor, and SH coefficients holding the
//! untextured term: its emission, zero for a plain diffuse textured surface. The textures go to the
//! solution's texture list once each, as their 8-bit sRGB texels.
//!
//! An emission-textured surface (`textured.rs`) without a diffuse texture
//! fits the same batch (docs/solution-format.md, "Emission textures"): its
//! texture is the emission texture, the factor Ke, the per-vertex "E/π" 1,
//! so the textured term is Le(uv) = Ke ⊙ texture(uv); its SH coefficients
//! hold the light it reflects with its flat Kd (its radiance less its mean
//! emission). A surface with both textures is a diffuse-textured batch (E/π,
//! Kd, no SH term) whose second slot (format 3) holds the emission texture
//! and Ke, so it shows Kd ⊙ ρ(uv) ⊙ E/π + Ke ⊙ ρ_e(uv).

use super::seams::SharedVertices;
use super::textured::Textured;
use super::Solver;
use crate::scene::SceneTexture;
use glam::DVec3;
use solution::format::{Batch, Solution, Texture, TextureSlot, TexturedVertex, Texturing};
use std::sync::Arc;

impl Solver {
    /// Splits `solution.batches[0]` (every output vertex of `shared`, in
    /// order) into the untextured batch and the textured ones; `radiance`
    /// is, per output vertex, its displayed radiance, and `ambient_at` the
    /// ambient term added to E/π, as the
    /// untextured vertices add Kd · ambient. Nothing changes when no surface is textured.
    pub(super) fn split_textured(
        &self,
        shared: &SharedVertices,
        radiance: &[DVec3],
        solution: &mut Solution,
        ambient_at: &[DVec3],
    ) {
        // Directional mode writes its textured batches itself
        // (`directional/textured.rs`).
        if !self.materials.texturing.any_display()
            || solution.batches.is_empty()
            || self.directional.is_some()
        {
            return;
        }
        let whole = solution.batches.remove(0);
        let empty = |texturing: Option<Texturing>| Batch {
            representation: whole.representation,
            scalar: whole.scalar,
            vertices: Vec::new(),
            coefficients: Vec::new(),
            indices: Vec::new(),
            texturing,
        };
        let mut batches = vec![empty(None)];
        // Per textured batch, its material; per texture index, its source.
        let mut materials: Vec<usize> = Vec::new();
        let mut sources = Vec::new();
        let mut slot: Vec<(usize, u32)> = Vec::with_capacity(whole.vertices.len());
        for (o, &r) in shared.representative.iter().enumerate() {
            let v = &self.mesh.vertices[r as usize];
            let ambient = ambient_at[o];
            let Some(t) = self.materials.texturing.shown(v.surface) else {
                let b = &mut batches[0];
                slot.push((0, b.vertices.len() as u32));
                b.vertices.push(whole.vertices[o]);
                b.coefficients
                    .extend_from_slice(&whole.coefficients[3 * o..3 * o + 3]);
                continue;
            };
            let material = self.mesh.surfaces[v.surface as usize].material;
            let g = match materials.iter().position(|&m| m == material) {
                Some(k) => k + 1,
                None => {
                    let texture = texture_index(&mut sources, &mut solution.textures, t);
                    let emission = self.second_slot(v.surface).map(|e| TextureSlot {
                        texture: texture_index(&mut sources, &mut solution.textures, e),
                        factor: e.kd.as_vec3().to_array(),
                    });
                    materials.push(material);
                    batches.push(empty(Some(Texturing {
                        texture,
                        factor: t.kd.as_vec3().to_array(),
                        emission,
                        vertices: Vec::new(),
                    })));
                    materials.len()
                }
            };
            let b = &mut batches[g];
            slot.push((g, b.vertices.len() as u32));
            b.vertices.push(whole.vertices[o]);
            // E/π for a diffuse-textured vertex; for an emitter's, 1, with
            // its reflected light in the coefficients.
            let e = if self.materials.texturing.get(v.surface).is_some() {
                // The vertex holds E/π plus its surface's emission (from the
                // start of the solve; the mean Le of an emission texture).
                // A flat emission is the untextured term; an emission
                // texture is shown by the second slot instead.
                let emission = self.materials.emission[v.surface as usize];
                let untextured = match self.second_slot(v.surface) {
                    Some(_) => DVec3::ZERO,
                    None => emission,
                };
                let c00 = untextured * (4.0 * std::f64::consts::PI).sqrt();
                b.coefficients.extend(c00.as_vec3().to_array());
                (radiance[o] - emission + ambient).max(DVec3::ZERO)
            } else {
                // As `to_solution` computes the coefficients, less Le.
                let s = v.surface as usize;
                let reflected =
                    radiance[o] - self.materials.emission[s] + self.materials.kd[s] * ambient;
                let scale = (4.0 * std::f64::consts::PI).sqrt();
                let c = reflected.max(DVec3::ZERO) * scale;
                b.coefficients.extend(c.as_vec3().to_array());
                DVec3::ONE
            };
            if let Some(texturing) = &mut b.texturing {
                texturing.vertices.push(TexturedVertex {
                    uv: self
                        .materials
                        .texturing
                        .uv(t, v.position)
                        .as_vec2()
                        .to_array(),
                    irradiance_over_pi: e.as_vec3().to_array(),
                });
            }
        }
        place_triangles_and_prepend(solution, batches, &slot, &whole.indices);
    }
}

impl Solver {
    /// The emission texture shown in the second slot of `surface`'s batch:
    /// its emission texture when it also has a diffuse one (the first slot).
    fn second_slot(&self, surface: u32) -> Option<&Textured> {
        self.materials.texturing.get(surface)?;
        self.materials.texturing.emissive(surface)
    }
}

/// Gives each display triangle of `indices` (output vertex ids) to the batch
/// its corners were placed in (`slot[o]` = (batch, index in it)), drops the
/// first batch (the untextured one) if it is empty, and puts the batches in
/// front of `solution`'s. Shared by the diffuse output and the cube method's
/// textured batches (`cube_textured.rs`).
pub(super) fn place_triangles_and_prepend(
    solution: &mut Solution,
    mut batches: Vec<Batch>,
    slot: &[(usize, u32)],
    indices: &[u32],
) {
    for tri in indices.chunks_exact(3) {
        let (g, _) = slot[tri[0] as usize];
        // A display triangle lies on one surface, so its corners are in
        // one batch (the seams keep textured and untextured apart).
        if tri.iter().any(|&o| slot[o as usize].0 != g) {
            debug_assert!(false, "a triangle spans two batches: {tri:?}");
            continue;
        }
        batches[g]
            .indices
            .extend(tri.iter().map(|&o| slot[o as usize].1));
    }
    if batches.first().is_some_and(|b| b.vertices.is_empty()) {
        batches.remove(0);
    }
    solution.batches.splice(0..0, batches);
}

/// The index in `textures` of `t`'s texture, added (its 8-bit sRGB texels)
/// the first time; `sources` records which scene texture each index holds.
pub(super) fn texture_index(
    sources: &mut Vec<*const SceneTexture>,
    textures: &mut Vec<Texture>,
    t: &Textured,
) -> u32 {
    let source = Arc::as_ptr(&t.texture);
    let index = match sources.iter().position(|&s| s == source) {
        Some(i) => i,
        None => {
            sources.push(source);
            textures.push(Texture {
                width: t.texture.width,
                height: t.texture.height,
                rgba: t.texture.rgba.clone(),
            });
            sources.len() - 1
        }
    };
    index as u32
}
