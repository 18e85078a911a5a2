//! Textured surfaces in directional mode: the diffuse solve's model
//! (`solve/textured.rs`) beside the SH of a glossy lobe.
//!
//! A textured surface (a diffuse texture and UVs) shows
//!
//!   L(x, ω) = ρ(uv) ⊙ E(x)/π + Σ c_lm Y_lm(ω),
//!
//! with ρ = Kd ⊙ texture(uv) and the SH holding only the untextured part: the
//! glossy lobe of its (untextured) Ks, and emission. So each of its vertices
//! keeps, after its `(L+1)² × 3` coefficients, three more values: E/π, the
//! incident irradiance over π, which does not depend on the texture (the
//! shot's transport gives it with reflectance 1: the solver's `kd` is 1
//! there). Those three values travel with the coefficients through every
//! per-vertex array (radiance, this shot's ΔL, the recorded shots' part),
//! so refinement's interpolation, the exact replay of recorded shots to new
//! vertices and the checkpoint treat them as three more coefficients.
//!
//! * **Shooting.** A textured patch's unshot SH gathers its vertices' glossy
//!   ΔL with the scalar area weights, as every patch does, plus its diffuse
//!   outgoing radiance as c₀₀: √(4π) · Σ_v w_v ⊙ ΔE_v/π / A_p with the RGB
//!   weights w_v = Kd ⊙ ∫ ρ λ_v of `solve/textured.rs`, which is exactly
//!   ∫ ρ ΔE/π dA / A_p for E/π interpolated linearly as displayed: the patch
//!   shoots the integral of what it shows, glossy part included.
//! * **Refinement** sees E/π (the diffuse proxy of a textured vertex, which
//!   the diffuse split test reads with reflectance 1), so a checkerboard does
//!   not force subdivision along its squares; a glossy textured surface also
//!   splits where its SH differ, as any glossy surface.
//! * **Output.** One textured SH batch per textured material, of its order:
//!   the coefficients (glossy part, emission), the texture's factor Kd, and
//!   per vertex its UV and E/π (plus the ambient term, as in diffuse mode).
//!   Solution format 2 defines this: L = Σ c Y + factor ⊙ ρ(uv) ⊙ E/π.
//! * **Emission textures** (`map_Ke`, glTF `emissiveTexture`) are the diffuse
//!   mode's (`solve/textured.rs`): each patch of the emitter starts with its
//!   texel-integrated mean Le as unshot c₀₀ = Le · √(4π), so the emitted
//!   power is π ∫ Le dA, and its vertices with the surface's mean Le. Its
//!   batch has the emission texture, factor Ke and "E/π" 1, and its SH hold
//!   the radiance less that mean Le: what it reflects, glossy lobe included.

use super::Directional;
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::solve::hidden::{fill_hidden, rgb};
use crate::solve::output_textured::TexturedBatches;
use crate::solve::textured::{SurfaceTexturing, Textured};
use crate::solve::Solver;
use glam::DVec3;
use solution::format::{Representation, Solution};
use solution::sh::{coefficient_count, Y00};
use std::f64::consts::PI;

/// Per mesh surface, whether the solve models it as textured (the same rule
/// as [`SurfaceTexturing::new`]).
pub(super) fn textured_surfaces(scene: &Scene, mesh: &Mesh) -> Vec<bool> {
    SurfaceTexturing::new(scene, mesh, DVec3::ZERO)
        .per_surface
        .iter()
        .map(Option::is_some)
        .collect()
}

impl Directional {
    /// Values per vertex of `surface`: its coefficients, and E/π when textured.
    pub(super) fn vertex_width(&self, surface: usize) -> usize {
        let sh = 3 * coefficient_count(self.surface_order[surface]);
        if self.textured[surface] {
            sh + 3
        } else {
            sh
        }
    }

    /// Vertex `v`'s whole slot in the per-vertex arrays (coefficients, then
    /// E/π on a textured surface); [`Directional::vertex_range`] is the
    /// coefficients alone.
    pub(super) fn vertex_slot(&self, mesh: &Mesh, v: usize) -> std::ops::Range<usize> {
        let o = self.vertex_offset[v];
        o..o + self.vertex_width(mesh.vertices[v].surface as usize)
    }

    /// The diffuse proxy of a vertex of `surface` whose slot starts `slot`:
    /// E/π on a textured surface, else the mean radiance c₀₀ · Y₀₀ (the value
    /// the diffuse split test and the diffuse fields read).
    pub(super) fn diffuse_proxy(&self, surface: usize, slot: &[f64]) -> DVec3 {
        if self.textured[surface] {
            let at = 3 * coefficient_count(self.surface_order[surface]);
            DVec3::from_slice(&slot[at..at + 3])
        } else {
            DVec3::from_slice(&slot[..3]) * Y00
        }
    }

    /// Whether splitting leaf `e` of a glossy surface keeps its children's
    /// edges at or above the surface's [`super::min_glossy_edge`] (the floor
    /// the SH split test applies; the E/π test of a textured glossy surface
    /// applies it too, since each new vertex carries the full SH order).
    pub(super) fn above_glossy_floor(&self, mesh: &Mesh, e: u32) -> bool {
        let el = &mesh.elements[e as usize];
        let surface = mesh.patches[el.patch as usize].surface as usize;
        let corners = el.corners();
        let shortest = (0..corners.len())
            .map(|k| {
                let (a, b) = (corners[k], corners[(k + 1) % corners.len()]);
                (mesh.vertices[a as usize].position - mesh.vertices[b as usize].position).length()
            })
            .fold(f64::INFINITY, f64::min);
        0.5 * shortest >= self.min_edge[surface]
    }

    /// E/π of vertex `v` of a textured surface, from `values` (the radiance or
    /// ΔL array).
    fn irradiance_over_pi(&self, mesh: &Mesh, values: &[f64], v: usize) -> DVec3 {
        let surface = mesh.vertices[v].surface as usize;
        let at = self.vertex_offset[v] + 3 * coefficient_count(self.surface_order[surface]);
        DVec3::from_slice(&values[at..at + 3])
    }
}

impl Solver {
    /// Adds to `sum` (patch `p`'s gathered coefficients, before the division
    /// by its area) the diffuse outgoing radiance of a textured patch as c₀₀:
    /// √(4π) · Σ_v w_v ⊙ ΔE_v/π over its visible vertices (see the module
    /// notes). Nothing for an untextured patch.
    pub(super) fn add_textured_gather(&self, d: &Directional, p: usize, sum: &mut [f64]) {
        let Some(rgb) = self.patches.rgb_weights.get(p).filter(|w| !w.is_empty()) else {
            return;
        };
        let mut reflected = DVec3::ZERO;
        for &(v, w) in rgb {
            if !self.field.hidden[v as usize] {
                reflected += w * d.irradiance_over_pi(&self.mesh, &d.received, v as usize);
            }
        }
        let c00 = reflected * (4.0 * PI).sqrt();
        sum[0] += c00.x;
        sum[1] += c00.y;
        sum[2] += c00.z;
    }

    /// The texture of `surface`'s textured batch in directional mode, and
    /// whether it is an emitter's: a diffuse-textured surface's texture
    /// (factor Kd, per-vertex E/π), else its emission texture (factor Ke,
    /// "E/π" 1, SH holding what it reflects: docs/solution-format.md,
    /// "Emission textures"); `None` for a surface of the untextured batches.
    pub(super) fn directional_shown(
        &self,
        d: &Directional,
        surface: usize,
    ) -> Option<(&Textured, bool)> {
        if d.textured[surface] {
            return self
                .materials
                .texturing
                .get(surface as u32)
                .map(|t| (t, false));
        }
        self.materials
            .texturing
            .emissive(surface as u32)
            .map(|t| (t, true))
    }

    /// Appends one textured SH batch per textured material (see the module
    /// notes) to a directional solution whose untextured batches are written,
    /// and the textures they use to its texture list. `ambient` is added to
    /// E/π, as the untextured vertices add Kd · ambient to c₀₀.
    pub(super) fn textured_directional_batches(
        &self,
        d: &Directional,
        solution: &mut Solution,
        ambient: DVec3,
    ) {
        let mesh = &self.mesh;
        if (0..mesh.surfaces.len()).all(|s| self.directional_shown(d, s).is_none()) {
            return;
        }
        let triangles = mesh.triangles();
        // E/π per vertex (zero off textured surfaces); hidden vertices show
        // their visible neighbours' light, as in diffuse mode.
        let mut irradiance: Vec<f64> = (0..mesh.vertices.len())
            .flat_map(|v| {
                if d.textured[mesh.vertices[v].surface as usize] {
                    d.irradiance_over_pi(mesh, &d.radiance, v).to_array()
                } else {
                    [0.0; 3]
                }
            })
            .collect();
        let count = mesh.vertices.len();
        fill_hidden(&triangles, &self.field.hidden, count, rgb, &mut irradiance);
        // The SH likewise.
        let coefficients = self.displayed_coefficients(d, &triangles);
        let mut textured = TexturedBatches::default();
        // Per mesh vertex, (batch, index in it).
        let mut local = vec![(usize::MAX, 0u32); mesh.vertices.len()];
        for (v, mv) in mesh.vertices.iter().enumerate() {
            let surface = mv.surface as usize;
            let Some((t, emitter)) = self.directional_shown(d, surface) else {
                continue;
            };
            let s = &mesh.surfaces[surface];
            let order = d.surface_order[surface];
            let g = textured.batch(
                s.material,
                (t, None),
                Representation::Sh { order },
                &mut solution.textures,
            );
            let mut values: Vec<f32> = coefficients[d.vertex_range(mesh, v)]
                .iter()
                .map(|&c| c as f32)
                .collect();
            let e = if emitter {
                // An emitter's SH hold what it reflects: its radiance less
                // the mean Le its vertices started with, plus Kd · ambient as
                // the untextured batches add; the texture shows Le(uv).
                let o = d.vertex_offset[v];
                let scale = (4.0 * PI).sqrt();
                let c00 = DVec3::from_slice(&coefficients[o..o + 3])
                    + (self.materials.kd[surface] * ambient - self.materials.emission[surface])
                        * scale;
                values[..3].copy_from_slice(&c00.max(DVec3::ZERO).as_vec3().to_array());
                DVec3::ONE
            } else {
                DVec3::from_slice(&irradiance[rgb(v)]) + ambient
            };
            let f = |x: DVec3| x.as_vec3().to_array();
            let vertex = solution::format::Vertex {
                position: f(mv.position),
                normal: f(s.normal),
                tangent: f(s.tangent),
            };
            let uv = self.materials.texturing.uv(t, mv.position);
            local[v] = (g, textured.push(g, vertex, values, uv, e));
        }
        let mut batches = textured.batches;
        for tri in &triangles {
            let (g, _) = local[tri[0] as usize];
            if g == usize::MAX {
                continue;
            }
            batches[g]
                .indices
                .extend(tri.iter().map(|&v| local[v as usize].1));
        }
        solution.batches.extend(batches);
    }
}

#[cfg(test)]
impl Solver {
    /// Vertex `v`'s diffuse proxy (E/π on a textured surface) and its SH
    /// coefficients, in directional mode (for the texture tests).
    pub(in crate::solve) fn directional_vertex(&self, v: usize) -> (DVec3, Vec<f64>) {
        let Some(d) = self.directional.as_deref() else {
            return (DVec3::ZERO, Vec::new());
        };
        let surface = self.mesh.vertices[v].surface as usize;
        let slot = &d.radiance[d.vertex_slot(&self.mesh, v)];
        let sh = &d.radiance[d.vertex_range(&self.mesh, v)];
        (d.diffuse_proxy(surface, slot), sh.to_vec())
    }

    /// Patch `p`'s unshot SH coefficients in directional mode (for the
    /// emission texture tests).
    pub(in crate::solve) fn directional_patch_unshot(&self, p: usize) -> Vec<f64> {
        self.directional.as_deref().map_or(Vec::new(), |d| {
            d.patch_unshot[d.patch_range(&self.mesh, p)].to_vec()
        })
    }

    /// Whether directional mode models mesh surface `s` as textured.
    pub(in crate::solve) fn directional_textured(&self, s: usize) -> bool {
        self.directional.as_deref().is_some_and(|d| d.textured[s])
    }
}
