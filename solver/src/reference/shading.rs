//! Shading normals of smooth surfaces at a hit point: the polygon's corner
//! normals (`scene::smooth`) interpolated exactly as the solver's mesh
//! interpolates them to its vertices (`mesh::MeshVertex::normal`), so that the
//! truth and the solver agree on what a smooth surface is.
//!
//! * A strictly convex quad: bilinear in the (s, t) whose bilinear map gives
//!   the point (Newton's method on the inverse map, from the centre).
//! * Any other polygon: barycentric on the triangle of its triangulation
//!   ([`crate::geometry::polygon::triangulate`], the mesh's pieces) that holds the
//!   point.
//!
//! Either way the result is normalised. The integrator uses it for the BSDF's
//! cosines and its sampling frame; the geometric normal still decides which
//! side is the front and whether a direction leaves the surface.

use crate::geometry::polygon::{bilinear, inverse_bilinear, triangulate};
use crate::mesh::strictly_convex;
use glam::DVec3;

/// Corner normals and the parameterisation that interpolates them.
#[derive(Clone, Debug)]
pub struct CornerNormals {
    normals: Vec<DVec3>,
    /// The triangulation's corners (empty for a bilinear quad).
    triangles: Vec<[usize; 3]>,
}

impl CornerNormals {
    /// `None` unless `normals` has one finite normal per vertex.
    pub fn new(vertices: &[DVec3], normal: DVec3, normals: &[DVec3]) -> Option<CornerNormals> {
        if normals.len() != vertices.len() || !normals.iter().all(|n| n.is_finite()) {
            return None;
        }
        let mut triangles = Vec::new();
        if !(vertices.len() == 4 && strictly_convex(vertices, normal)) {
            triangulate(vertices, &mut triangles);
        }
        Some(CornerNormals {
            normals: normals.to_vec(),
            triangles,
        })
    }

    /// The unit shading normal at `point` (on the polygon `vertices`), or
    /// `fallback` where the interpolation degenerates.
    pub fn at(&self, vertices: &[DVec3], point: DVec3, fallback: DVec3) -> DVec3 {
        let n = &self.normals;
        let interpolated = if self.triangles.is_empty() {
            let (s, t) = inverse_bilinear(vertices, point);
            bilinear(n, s, t)
        } else {
            // The triangle whose smallest barycentric weight is largest: the
            // one that holds the point (or the nearest, for a point on an edge
            // rounded just outside).
            let mut best = (f64::NEG_INFINITY, DVec3::ZERO);
            for t in &self.triangles {
                let w = barycentric([vertices[t[0]], vertices[t[1]], vertices[t[2]]], point);
                let worst = w.min_element();
                if worst > best.0 {
                    best = (worst, n[t[0]] * w.x + n[t[1]] * w.y + n[t[2]] * w.z);
                }
            }
            best.1
        };
        interpolated.try_normalize().unwrap_or(fallback)
    }
}

/// Barycentric weights of `p` (projected onto the triangle's plane).
fn barycentric(t: [DVec3; 3], p: DVec3) -> DVec3 {
    let (e1, e2, d) = (t[1] - t[0], t[2] - t[0], p - t[0]);
    let (a, b, c) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (u, v) = (d.dot(e1), d.dot(e2));
    let det = a * c - b * b;
    if det.is_nan() || det <= 0.0 {
        return DVec3::new(1.0, 0.0, 0.0);
    }
    let w1 = (c * u - b * v) / det;
    let w2 = (a * v - b * u) / det;
    DVec3::new(1.0 - w1 - w2, w1, w2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangles_interpolate_barycentrically_and_quads_bilinearly() {
        // The solver's mesh interpolates corner normals by the same weights
        // as positions (mesh::param::VertexKey::position), so at a point built
        // from known weights the path tracer must find those weights again.
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let tn = [
            DVec3::Z,
            DVec3::new(0.3, 0.0, 1.0).normalize(),
            DVec3::new(0.0, 0.4, 1.0).normalize(),
        ];
        let c = CornerNormals::new(&tri, DVec3::Z, &tn).unwrap();
        let w = DVec3::new(0.2, 0.5, 0.3);
        let p = tri[0] * w.x + tri[1] * w.y + tri[2] * w.z;
        let expected = (tn[0] * w.x + tn[1] * w.y + tn[2] * w.z).normalize();
        assert!(c.at(&tri, p, DVec3::Z).distance(expected) < 1e-12);
        assert!(c.at(&tri, tri[1], DVec3::Z).distance(tn[1]) < 1e-12);

        // A convex quad that is not a parallelogram: the bilinear map is not
        // affine, so (s, t) must come from its inverse.
        let quad = [
            DVec3::ZERO,
            DVec3::new(4.0, 0.0, 0.0),
            DVec3::new(3.0, 2.0, 0.0),
            DVec3::new(0.5, 3.0, 0.0),
        ];
        let qn = [
            DVec3::Z,
            DVec3::new(0.2, 0.0, 1.0).normalize(),
            DVec3::new(0.2, 0.2, 1.0).normalize(),
            DVec3::new(0.0, 0.3, 1.0).normalize(),
        ];
        let c = CornerNormals::new(&quad, DVec3::Z, &qn).unwrap();
        let bilinear = |v: &[DVec3], s: f64, t: f64| {
            (v[0] * (1.0 - s) + v[1] * s) * (1.0 - t) + (v[3] * (1.0 - s) + v[2] * s) * t
        };
        for (s, t) in [(0.3, 0.7), (0.9, 0.1), (0.5, 0.5), (0.0, 1.0)] {
            let p = bilinear(&quad, s, t);
            let expected = bilinear(&qn, s, t).normalize();
            let got = c.at(&quad, p, DVec3::Z);
            assert!(
                got.distance(expected) < 1e-12,
                "({s}, {t}): {got} against {expected}"
            );
        }
    }
}
