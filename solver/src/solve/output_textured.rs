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
use solution::format::{
    Batch, Representation, ScalarType, Solution, Texture, TextureSlot, TexturedVertex, Texturing,
    Vertex,
};
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
        let mut untextured = Batch {
            representation: whole.representation,
            scalar: whole.scalar,
            vertices: Vec::new(),
            coefficients: Vec::new(),
            indices: Vec::new(),
            texturing: None,
        };
        let mut textured = TexturedBatches::default();
        // Per output vertex, (batch, index in it): batch 0 is the untextured.
        let mut slot: Vec<(usize, u32)> = Vec::with_capacity(whole.vertices.len());
        for (o, &r) in shared.representative.iter().enumerate() {
            let v = &self.mesh.vertices[r as usize];
            let Some(t) = self.materials.texturing.shown(v.surface) else {
                slot.push((0, untextured.vertices.len() as u32));
                untextured.vertices.push(whole.vertices[o]);
                untextured
                    .coefficients
                    .extend_from_slice(&whole.coefficients[3 * o..3 * o + 3]);
                continue;
            };
            let g = textured.batch(
                self.mesh.surfaces[v.surface as usize].material,
                (t, self.second_slot(v.surface)),
                whole.representation,
                &mut solution.textures,
            );
            let (c00, e) = self.textured_values(v.surface, radiance[o], ambient_at[o]);
            let uv = self.materials.texturing.uv(t, v.position);
            let index = textured.push(g, whole.vertices[o], c00.as_vec3().to_array(), uv, e);
            slot.push((g + 1, index));
        }
        let mut batches = vec![untextured];
        batches.extend(textured.batches);
        place_triangles_and_prepend(solution, batches, &slot, &whole.indices);
    }
}

impl Solver {
    /// A textured output vertex's untextured term (c₀₀) and the per-vertex
    /// factor of its texture, from its displayed `radiance` and `ambient`
    /// term. A diffuse-textured vertex: E/π, its radiance less its surface's
    /// emission (from the start of the solve; the mean Le of an emission
    /// texture), plus the ambient term; a flat emission is the untextured
    /// term, an emission texture is shown by the second slot instead. An
    /// emitter's (emission texture alone): 1, with the light it reflects as
    /// the untextured term (as `to_solution` computes the coefficients, less
    /// Le).
    fn textured_values(&self, surface: u32, radiance: DVec3, ambient: DVec3) -> (DVec3, DVec3) {
        let scale = (4.0 * std::f64::consts::PI).sqrt();
        let s = surface as usize;
        let emission = self.materials.emission[s];
        if self.materials.texturing.get(surface).is_some() {
            let untextured = match self.second_slot(surface) {
                Some(_) => DVec3::ZERO,
                None => emission,
            };
            let e = (radiance - emission + ambient).max(DVec3::ZERO);
            (untextured * scale, e)
        } else {
            let reflected = radiance - emission + self.materials.kd[s] * ambient;
            (reflected.max(DVec3::ZERO) * scale, DVec3::ONE)
        }
    }
}

/// The textured batches of a solution being written, one per textured
/// material in the order of their first vertex, and the textures they use,
/// each added to the solution's list once. Both modes' outputs build theirs
/// with it (diffuse: [`Solver::split_textured`]; directional:
/// `directional/textured.rs`).
#[derive(Default)]
pub(super) struct TexturedBatches {
    /// Per batch, its material.
    materials: Vec<usize>,
    /// Per index of the solution's texture list, its scene texture.
    sources: Vec<*const SceneTexture>,
    pub batches: Vec<Batch>,
}

impl TexturedBatches {
    /// The index of `material`'s batch, made on its first vertex with
    /// `representation` and `shown` (the texture of the first slot, and of
    /// the second where there is one), their textures added to `textures`.
    pub fn batch(
        &mut self,
        material: usize,
        shown: (&Textured, Option<&Textured>),
        representation: Representation,
        textures: &mut Vec<Texture>,
    ) -> usize {
        if let Some(g) = self.materials.iter().position(|&m| m == material) {
            return g;
        }
        let (first, second) = shown;
        let texture = texture_index(&mut self.sources, textures, first);
        let emission = second.map(|e| TextureSlot {
            texture: texture_index(&mut self.sources, textures, e),
            factor: e.kd.as_vec3().to_array(),
        });
        self.materials.push(material);
        self.batches.push(Batch {
            representation,
            scalar: ScalarType::F32,
            vertices: Vec::new(),
            coefficients: Vec::new(),
            indices: Vec::new(),
            texturing: Some(Texturing {
                texture,
                factor: first.kd.as_vec3().to_array(),
                emission,
                vertices: Vec::new(),
            }),
        });
        self.batches.len() - 1
    }

    /// Adds a vertex to batch `g` with its coefficients, texture coordinates
    /// and per-vertex texture factor (E/π); returns its index in the batch.
    pub fn push(
        &mut self,
        g: usize,
        vertex: Vertex,
        coefficients: impl IntoIterator<Item = f32>,
        uv: glam::DVec2,
        irradiance_over_pi: DVec3,
    ) -> u32 {
        let batch = &mut self.batches[g];
        let index = batch.vertices.len() as u32;
        batch.vertices.push(vertex);
        batch.coefficients.extend(coefficients);
        if let Some(texturing) = &mut batch.texturing {
            texturing.vertices.push(TexturedVertex {
                uv: uv.as_vec2().to_array(),
                irradiance_over_pi: irradiance_over_pi.as_vec3().to_array(),
            });
        }
        index
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
fn texture_index(
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
