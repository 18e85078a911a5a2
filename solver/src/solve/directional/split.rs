//! The glossy split test: when an element of a glossy surface must split, from
//! its corner vertices' SH coefficients (the diffuse test, `refine.rs`, reads
//! one radiance per vertex; a glossy vertex holds a function of direction).

use super::Directional;
use crate::mesh::Mesh;
use crate::solve::refine::{longest_edge, Criteria};
use glam::DVec3;
use std::f64::consts::PI;

/// Whether leaf `e` of a glossy surface must split: an edge fails when the
/// L2 norm of its ends' coefficient difference (by Parseval, the L2
/// difference of their radiance over the sphere) exceeds the threshold times
/// the larger end's norm, per channel, after the diffuse test's allowance for
/// sampling noise, plus the edge's [`view_turn`]; elements whose children's
/// longest edge would be shorter than the surface's
/// [`super::min_glossy_edge`] do not split.
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
    // glossy Cornell box's floor (docs/lab/contact-cuts.md, "Glossy: contact cuts in
    // directional mode").
    if 0.5 * longest_edge(mesh, e) < d.min_edge[surface_index] {
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
    // `Criteria::should_split_at`), on this shot's ΔL norm: σ_v² = |ΔL_v|² ·
    // (n − k)/(k n) for k of n visible rays.
    let sigma2 = |v: usize| {
        norms(&d.received[d.vertex_range(mesh, v)]) * criteria.visibility_variance(visible[v])
    };
    (0..n).any(|k| {
        let (a, b) = (corners[k] as usize, corners[(k + 1) % n] as usize);
        let threshold = criteria.threshold_between(visible[a], visible[b]);
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
        let view = view_turn(mesh, d, (a, b), (ca, cb));
        local > 0.0 && diff.max_element().sqrt() + view - 2.0 * noise > threshold * local
    })
}

/// The view term of the glossy split test: how much the radiance an eye sees
/// can change across edge (a, b) because the direction to the eye turns.
///
/// The runtime shows L_a(ω_a) at one end and L_b(ω_b) at the other, ω the
/// directions to the eye, and interpolates between them. By the triangle
/// inequality |L_a(ω_a) − L_b(ω_b)| ≤ |L_a(ω_a) − L_b(ω_a)| + |L_b(ω_a) −
/// L_b(ω_b)|. The L2 test bounds the first term (the two functions' difference
/// at one direction, in the mean square over the sphere). The second is at
/// most the angle between ω_a and ω_b, which for an eye at distance D is at
/// most |a − b| / D, times the gradient of L_b; in the same mean square its
/// norm is [`angular_gradient_norm`]. D is the scene's viewing distance scale
/// (half its bounds' diagonal, as in [`super::min_glossy_edge`]).
///
/// Without it an edge whose ends hold the same lobe never splits, though an
/// eye sees the highlight cross it: the L2 test sees a lobe move by the edge's
/// angle to its source, not by its angle to the eye (docs/lab/glossy-view-term.md,
/// "Glossy: the view term").
fn view_turn(
    mesh: &Mesh,
    d: &Directional,
    (a, b): (usize, usize),
    (ca, cb): (&[f64], &[f64]),
) -> f64 {
    if d.view_distance <= 0.0 {
        return 0.0;
    }
    let h = (mesh.vertices[a].position - mesh.vertices[b].position).length();
    h / d.view_distance * angular_gradient_norm(ca).max(angular_gradient_norm(cb))
}

/// The L2 norm over the unit sphere of the angular gradient of the function
/// whose real SH coefficients (RGB interleaved, index l² + l + m) are
/// `coefficients`, per channel, the largest: ‖∇L‖₂ = √(Σ_lm l(l+1) c_lm²).
/// It follows from Green's identity on the sphere, ∫|∇f|² = −∫ f Δf, and
/// −Δ Y_lm = l(l+1) Y_lm with the Y_lm orthonormal. An isotropic radiance
/// (l = 0, a diffuse surface) has none.
fn angular_gradient_norm(coefficients: &[f64]) -> f64 {
    let mut sum = DVec3::ZERO;
    // Degree l holds the 2l + 1 coefficients (RGB each) from index l² on.
    let mut start = 0;
    for l in 0.. {
        let end = (3 * (l + 1) * (l + 1)).min(coefficients.len());
        if start >= end {
            break;
        }
        let weight = (l * (l + 1)) as f64;
        for c in coefficients[start..end].chunks_exact(3) {
            let c = DVec3::from_slice(c);
            sum += c * c * weight;
        }
        start = end;
    }
    sum.max_element().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use solution::sh::{coefficient_count, eval_basis};

    /// ‖∇f‖₂ from the coefficients against a quadrature of |∇f|² =
    /// f_θ² + f_φ² / sin²θ, the derivatives by central differences, for a
    /// function with every coefficient up to order 6 set (a different one
    /// per channel: the largest channel is reported). The φ rule (uniform,
    /// 96 points) is exact for these trigonometric polynomials; the θ rule
    /// (midpoint, 400 points) and the differences (step 1e-5) are each
    /// accurate to far below the 1e-4 relative tolerance asserted.
    #[test]
    fn angular_gradient_norm_matches_a_quadrature_of_the_gradient() {
        let order = 6;
        let n = coefficient_count(order);
        let coefficients: Vec<f64> = (0..3 * n)
            .map(|i| ((i as f64 * 0.737).sin() + 0.3) * if i % 3 == 1 { 2.0 } else { 1.0 })
            .collect();
        let value = |channel: usize, theta: f64, phi: f64| {
            let dir = DVec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            let mut basis = vec![0.0; n];
            eval_basis(order, dir, &mut basis);
            (0..n)
                .map(|k| basis[k] * coefficients[3 * k + channel])
                .sum::<f64>()
        };
        let (nt, np, step) = (400, 96, 1e-5);
        let mut best: f64 = 0.0;
        for channel in 0..3 {
            let mut integral = 0.0;
            for i in 0..nt {
                let theta = PI * (i as f64 + 0.5) / nt as f64;
                for j in 0..np {
                    let phi = 2.0 * PI * j as f64 / np as f64;
                    let f_theta = (value(channel, theta + step, phi)
                        - value(channel, theta - step, phi))
                        / (2.0 * step);
                    let f_phi = (value(channel, theta, phi + step)
                        - value(channel, theta, phi - step))
                        / (2.0 * step);
                    let gradient2 = f_theta * f_theta + f_phi * f_phi / (theta.sin() * theta.sin());
                    integral += gradient2 * theta.sin() * (PI / nt as f64) * (2.0 * PI / np as f64);
                }
            }
            best = best.max(integral.sqrt());
        }
        let formula = angular_gradient_norm(&coefficients);
        assert!(
            (formula / best - 1.0).abs() < 1e-4,
            "formula {formula}, quadrature {best}"
        );
        // A constant (diffuse) radiance has no gradient.
        assert_eq!(angular_gradient_norm(&[1.0, 2.0, 3.0]), 0.0);
    }
}
