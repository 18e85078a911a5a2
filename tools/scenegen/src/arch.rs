//! An arch block: the solid between two column centres above their spring
//! line, with a semi-elliptical opening (the intrados) between the columns'
//! faces, extruded along z. Its flat bottom strips rest on the columns' tops,
//! its flat top carries the slab above, so the columns, the arches and the
//! slab close the arcade with no gap.
//!
//! Seen from +z the block's outline is, counter-clockwise: the left bottom
//! strip, the intrados from the left spring over the crown to the right
//! spring, the right bottom strip, the right side, the top (with a vertex
//! above the crown) and the left side. Each half of the face is fanned from
//! its top corner, which sees the whole quarter of the intrados (the corner
//! lies outside the ellipse beyond both its tangents), so no triangle
//! crosses the opening and none is a sliver: the thinnest, at the spring, has
//! area / edge² about (r/R)·(π/S)/2.

use crate::mesh::{Corner, Mesh};
use std::f64::consts::PI;

/// One arch block, millimetres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArchSpec {
    /// The two column centres it spans (x0 < x1).
    pub x: [f64; 2],
    /// The columns' half-width: the opening runs from x0 + inset to x1 − inset.
    pub inset: f64,
    /// The block's depth (z0 < z1).
    pub z: [f64; 2],
    /// The spring line (the columns' tops) and the block's top (the slab's underside).
    pub y: [f64; 2],
    /// The intrados' height above the spring line (at most the half-opening
    /// for a round arch, less for a flatter one); below the top.
    pub rise: f64,
    /// Segments of the intrados (even, at least 2).
    pub segments: u32,
}

impl ArchSpec {
    /// Two caps of S + 4 triangles (the outline has S + 6 vertices) and two
    /// per outline edge.
    pub fn triangle_count(&self) -> usize {
        let s = self.segments as usize;
        2 * (s + 4) + 2 * (s + 6)
    }

    /// The outline seen from +z, counter-clockwise.
    fn outline(&self) -> Vec<[f64; 2]> {
        let [x0, x1] = self.x;
        let [spring, top] = self.y;
        let mid = 0.5 * (x0 + x1);
        let half = mid - x0 - self.inset;
        let s = self.segments as usize;
        let mut points = vec![[x0, spring]];
        for k in 0..=s {
            let angle = PI * k as f64 / s as f64;
            // The springs and the crown exactly, not through cos/sin rounding.
            let (x, y) = match k {
                0 => (mid - half, spring),
                _ if k == s => (mid + half, spring),
                _ if 2 * k == s => (mid, spring + self.rise),
                _ => (mid - half * angle.cos(), spring + self.rise * angle.sin()),
            };
            points.push([x, y]);
        }
        points.extend([[x1, spring], [x1, top], [mid, top], [x0, top]]);
        points
    }

    /// The cap's triangles as outline indices, counter-clockwise seen from +z.
    fn cap(&self) -> Vec<[usize; 3]> {
        let s = self.segments as usize;
        let (bottom_left, bottom_right) = (0, s + 2);
        let (top_right, top_mid, top_left) = (s + 3, s + 4, s + 5);
        let arc = |k: usize| 1 + k;
        let mut triangles = vec![[top_left, bottom_left, arc(0)]];
        triangles.extend((0..s / 2).map(|k| [top_left, arc(k), arc(k + 1)]));
        triangles.push([top_left, arc(s / 2), top_mid]);
        triangles.push([top_right, top_mid, arc(s / 2)]);
        triangles.extend((s / 2..s).map(|k| [top_right, arc(k), arc(k + 1)]));
        triangles.push([top_right, arc(s), bottom_right]);
        triangles
    }
}

/// Adds the block to the current object as a closed solid facing out.
pub fn add_arch(mesh: &mut Mesh, spec: &ArchSpec) {
    add_prism_z(mesh, &spec.outline(), &spec.cap(), spec.z);
}

/// Adds the prism of a counter-clockwise outline (x, y) between z0 and z1,
/// its caps triangulated by `cap` (outline indices, counter-clockwise seen
/// from +z): closed, vertices shared, every face facing out.
pub fn add_prism_z(mesh: &mut Mesh, outline: &[[f64; 2]], cap: &[[usize; 3]], z: [f64; 2]) {
    let ring = |mesh: &mut Mesh, z: f64| -> Vec<Corner> {
        outline
            .iter()
            .map(|p| Corner::flat(mesh.add_position([p[0], p[1], z])))
            .collect()
    };
    let back = ring(mesh, z[0]);
    let front = ring(mesh, z[1]);
    for &[a, b, c] in cap {
        mesh.push_triangle([front[a], front[b], front[c]]);
        mesh.push_triangle([back[a], back[c], back[b]]);
    }
    // For an edge i → j of a counter-clockwise outline the outward normal is
    // (dy, −dx), and (b0 − a0) × (b1 − a0) = Δz · (dy, −dx, 0) for this order.
    let n = outline.len();
    for i in 0..n {
        let j = (i + 1) % n;
        mesh.quad([back[i], back[j], front[j], front[i]]);
    }
}
