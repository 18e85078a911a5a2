//! Emission textures in the global-cube method (`map_Ke`, glTF
//! `emissiveTexture`; docs/textures.md, "Emissive textures").
//!
//! The progressive solves shoot each patch of an emission-textured surface
//! with its texel-integrated mean Le, m_p = Ke ⊙ ∫_P texture dA / A_P
//! ([`crate::solve::textured::SurfaceTexturing::emitted_radiance`]), so the
//! emitted power is π ∫ Le dA. The cube gather's unknowns are per vertex and
//! a source patch's radiance is the weighted average of its vertices' (the
//! module notes, "Discretization"), and vertices are shared by patches with
//! different means, so no per-vertex Le can make every patch emit its own
//! m_p. Instead, as in the progressive solve, the surface's vertices hold its
//! area-weighted mean Le, m̄ (plus what they reflect), and each of its patches
//! adds to its source radiance the offset δ_p = m_p − m̄. The patch's gather
//! weights sum to 1, so its source radiance is m_p + Σ_v w_v R_v, R_v the
//! light its vertices reflect: it emits its own texels' mean, uniformly, and
//! all sources together emit π ∫ Le dA ([`emitted_power`]).
//!
//! Surfaces without an emission texture get no offset (the list is empty
//! when no surface has one), so their solves are unchanged bit for bit. One
//! approximation is left: a glossy emitter's vertex whose own cube frame
//! (a smooth surface's) puts a receiver below its shading horizon gives that
//! receiver none of its value, its emission included, while the offset is
//! still added: a few degrees at grazing, as the module notes say for the
//! reflected light.

use super::SurfaceData;
use crate::mesh::Mesh;
use crate::solve::Solver;
use glam::DVec3;
use std::f64::consts::PI;

/// Sets each emission-textured surface's vertex emission to its mean Le m̄
/// (the progressive solver's per-surface emission) and returns per patch the
/// offset δ_p = m_p − m̄ its source radiance adds; empty when no surface has
/// an emission texture. `solver` is the cube solve's base solver, before any
/// shot, so its unshot radiance per patch is what the patch emits.
pub(super) fn patch_offsets(solver: &Solver, surfaces: &mut [SurfaceData]) -> Vec<DVec3> {
    if solver.texturing.emissive.is_empty() {
        return Vec::new();
    }
    for (s, data) in surfaces.iter_mut().enumerate() {
        if solver.texturing.emissive(s as u32).is_some() {
            data.emission = solver.emission[s];
        }
    }
    solver
        .mesh
        .patches
        .iter()
        .zip(solver.patch_unshot())
        .map(|(p, &m)| m - surfaces[p.surface as usize].emission)
        .collect()
}

/// The power the sources emit, W: Σ_p π A_p Σ_rgb (m̄ + δ_p), the emission
/// each patch's source radiance carries. With no offsets it is
/// Σ_p π A_p Σ_rgb Le, as before emission textures.
pub(super) fn emitted_power(mesh: &Mesh, surfaces: &[SurfaceData], offsets: &[DVec3]) -> f64 {
    mesh.patches
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let offset = offsets.get(i).copied().unwrap_or(DVec3::ZERO);
            PI * p.area * (surfaces[p.surface as usize].emission + offset).element_sum()
        })
        .sum()
}
