//! The glossy split test: when an element of a glossy surface must split, from
//! its corner vertices' SH coefficients (the diffuse test, `refine.rs`, reads
//! one radiance per vertex; a glossy vertex holds a function of direction).

use super::Directional;
use crate::mesh::Mesh;
use crate::solve::refine::Criteria;
use glam::DVec3;
use std::f64::consts::PI;

/// Whether leaf `e` of a glossy surface must split: an edge fails when the
/// L2 norm of its ends' coefficient difference (by Parseval, the L2
/// difference of their radiance over the sphere) exceeds the threshold times
/// the larger end's norm, per channel, after the diffuse test's allowance for
/// sampling noise; elements whose children's longest edge would be shorter
/// than the surface's [`super::min_glossy_edge`] do not split.
pub(super) fn should_split_sh(
    mesh: &Mesh,
    d: &Directional,
    visible: &[u32],
    criteria: &Criteria,
    e: u32,
) -> bool {
    let el = &mesh.elements[e as usize];
    if !el.is_leaf() || el.depth as u32 >= criteria.max_depth {
        return false;
    }
    let surface_index = mesh.patches[el.patch as usize].surface as usize;
    if criteria.at_smallest(mesh, e) {
        return false;
    }
    let corners = el.corners();
    // The α floor, on the longest edge (a split halves every edge): as the
    // diffuse floor (`Criteria::at_smallest`), since the longest edge bounds
    // the distance over which the lobe is interpolated linearly. A sliver
    // (the thin pieces a contact cut leaves along its lines) is refined
    // until its long side is short; tested on its shortest edge, it never
    // split, and its long elements spread the light's reflection on the
    // glossy Cornell box's floor (docs/accuracy.md, "Glossy: contact cuts in
    // directional mode").
    let longest = (0..corners.len())
        .map(|k| {
            let (a, b) = (corners[k], corners[(k + 1) % corners.len()]);
            (mesh.vertices[a as usize].position - mesh.vertices[b as usize].position).length()
        })
        .fold(0.0, f64::max);
    if 0.5 * longest < d.min_edge[surface_index] {
        return false;
    }
    let n = corners.len();
    // Per channel Σ_k c_k², the squared L2 norm over the sphere (Parseval).
    let norms = |a: &[f64]| {
        let mut s = DVec3::ZERO;
        for c in a.chunks_exact(3) {
            s += DVec3::from_slice(c) * DVec3::from_slice(c);
        }
        s
    };
    // The diffuse test's allowance for sampling noise (see
    // `Criteria::should_split`), on this shot's ΔL norm: σ_v = |ΔL_v| ·
    // √((n − k)/(k n)) for k of n visible rays.
    let samples = criteria.samples.max(1) as f64;
    let sigma2 = |v: usize| {
        let k = visible[v] as f64;
        if k > 0.0 && k < samples {
            norms(&d.received[d.vertex_range(mesh, v)]) * ((samples - k) / (k * samples))
        } else {
            DVec3::ZERO
        }
    };
    (0..n).any(|k| {
        let (a, b) = (corners[k] as usize, corners[(k + 1) % n] as usize);
        let threshold = if visible[a] != visible[b] {
            criteria.shadow_threshold
        } else {
            criteria.edge_threshold
        };
        let noise = (sigma2(a) + sigma2(b)).max_element().sqrt();
        let (ca, cb) = (
            &d.radiance[d.vertex_range(mesh, a)],
            &d.radiance[d.vertex_range(mesh, b)],
        );
        // The dark floor and the ambient level are radiances; an isotropic
        // radiance L has norm L √(4π).
        let local = norms(ca)
            .max(norms(cb))
            .max_element()
            .sqrt()
            .max((criteria.dark_floor + criteria.ambient.max_element()) * (4.0 * PI).sqrt());
        let mut diff = DVec3::ZERO;
        for (x, y) in ca.chunks_exact(3).zip(cb.chunks_exact(3)) {
            let t = DVec3::from_slice(x) - DVec3::from_slice(y);
            diff += t * t;
        }
        local > 0.0 && diff.max_element().sqrt() - 2.0 * noise > threshold * local
    })
}
