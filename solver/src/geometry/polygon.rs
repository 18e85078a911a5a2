//! Planar polygon helpers in f64: Newell's normal, clipping against a plane,
//! triangulation (fan for convex polygons, ear clipping otherwise) and a
//! ray/triangle test.
//!
//! Polygons are slices of vertices, counter-clockwise seen from their front
//! (design notes, "Units and conventions"), implicitly closed.

use glam::{DVec2, DVec3};

/// Newell's normal, not normalised: its length is twice the polygon's area, so
/// a degenerate polygon gives (near) zero. Robust for slightly non-planar input.
pub fn newell_normal(polygon: &[DVec3]) -> DVec3 {
    let mut n = DVec3::ZERO;
    let count = polygon.len();
    for (i, a) in polygon.iter().enumerate() {
        let b = polygon[(i + 1) % count];
        n += a.cross(b);
    }
    n
}

/// Area of a planar polygon by Newell's formula.
pub fn area(polygon: &[DVec3]) -> f64 {
    0.5 * newell_normal(polygon).length()
}

/// A sphere holding every corner: the corners' mean and the largest distance
/// from it to a corner. Not the smallest such sphere; exact for regular
/// polygons and within 2× of the smallest for any. An empty polygon gives
/// the origin and 0.
pub fn bounding_sphere(polygon: &[DVec3]) -> (DVec3, f64) {
    let centre = polygon.iter().copied().sum::<DVec3>() / polygon.len().max(1) as f64;
    let radius = polygon
        .iter()
        .map(|&c| (c - centre).length())
        .fold(0.0, f64::max);
    (centre, radius)
}

/// Clips `polygon` to the closed half-space `normal · (x − origin) ≥ 0`
/// (Sutherland–Hodgman against one plane) and writes the result into `out`
/// (cleared first). `normal` need not be unit length.
///
/// For a non-convex polygon the result may contain edges that run back and forth
/// along the clipping line; they cancel in contour integrals and in signed
/// areas, which is all the form-factor code needs. Output may have fewer than 3
/// vertices when nothing (or only a point/segment) is in front.
pub fn clip_to_halfspace(polygon: &[DVec3], origin: DVec3, normal: DVec3, out: &mut Vec<DVec3>) {
    out.clear();
    let count = polygon.len();
    if count == 0 {
        return;
    }
    let mut prev = polygon[count - 1];
    let mut prev_d = normal.dot(prev - origin);
    for &cur in polygon {
        let cur_d = normal.dot(cur - origin);
        if (prev_d > 0.0 && cur_d < 0.0) || (prev_d < 0.0 && cur_d > 0.0) {
            // The edge crosses the plane strictly: add the crossing point. The
            // parameter is in (0, 1) because the distances have opposite signs.
            let t = prev_d / (prev_d - cur_d);
            out.push(prev + (cur - prev) * t);
        }
        if cur_d >= 0.0 {
            out.push(cur);
        }
        prev = cur;
        prev_d = cur_d;
    }
}

/// Whether a planar polygon is convex (all turns the same way around its
/// Newell normal; collinear vertices allowed).
pub fn is_convex(polygon: &[DVec3]) -> bool {
    let count = polygon.len();
    if count < 4 {
        return true;
    }
    let n = newell_normal(polygon);
    let scale = n.length();
    for i in 0..count {
        let a = polygon[i];
        let b = polygon[(i + 1) % count];
        let c = polygon[(i + 2) % count];
        // A reflex turn has a cross product against the normal; allow rounding
        // relative to the polygon's own size.
        if (b - a).cross(c - b).dot(n) < -1e-12 * scale * scale {
            return false;
        }
    }
    true
}

/// Triangulates a simple planar polygon into `out` (appended) as index triples
/// into `polygon`, each counter-clockwise like the polygon. Convex polygons get a
/// fan from vertex 0; others are ear-clipped in the plane of their dominant
/// normal axis (O(n²), fine for input polygons). Degenerate (zero-area) polygons
/// produce nothing.
pub fn triangulate(polygon: &[DVec3], out: &mut Vec<[usize; 3]>) {
    let count = polygon.len();
    if count < 3 {
        return;
    }
    let n = newell_normal(polygon);
    if n.length_squared() == 0.0 {
        return;
    }
    if is_convex(polygon) {
        for i in 1..count - 1 {
            out.push([0, i, i + 1]);
        }
        return;
    }
    // Project onto the plane that drops the normal's dominant axis, keeping the
    // orientation counter-clockwise.
    let abs = n.abs();
    let project = |v: DVec3| -> DVec2 {
        if abs.x >= abs.y && abs.x >= abs.z {
            if n.x > 0.0 {
                DVec2::new(v.y, v.z)
            } else {
                DVec2::new(v.z, v.y)
            }
        } else if abs.y >= abs.z {
            if n.y > 0.0 {
                DVec2::new(v.z, v.x)
            } else {
                DVec2::new(v.x, v.z)
            }
        } else if n.z > 0.0 {
            DVec2::new(v.x, v.y)
        } else {
            DVec2::new(v.y, v.x)
        }
    };
    let points: Vec<DVec2> = polygon.iter().map(|&v| project(v)).collect();
    out.extend(ear_clip(&points));
}

/// Ear clipping of a simple 2-D polygon, counter-clockwise or not: index triples
/// in the input's orientation, O(n²) (fine for input polygons). A polygon on which
/// no ear can be found (not simple, or numerically degenerate) is finished as a
/// fan rather than looping forever. Shared by [`triangulate`] and the importers'
/// cleaning of non-convex polygons.
pub fn ear_clip(p: &[DVec2]) -> Vec<[usize; 3]> {
    let n = p.len();
    if n < 3 {
        return Vec::new();
    }
    let signed_area: f64 = (0..n).map(|i| p[i].perp_dot(p[(i + 1) % n])).sum();
    let ccw = signed_area >= 0.0;
    let turn = |a: usize, b: usize, c: usize| {
        let o = (p[b] - p[a]).perp_dot(p[c] - p[a]);
        if ccw {
            o
        } else {
            -o
        }
    };
    let mut remaining: Vec<usize> = (0..n).collect();
    let mut triangles = Vec::with_capacity(n - 2);
    while remaining.len() > 3 {
        let m = remaining.len();
        let corner = |k: usize| {
            (
                remaining[(k + m - 1) % m],
                remaining[k],
                remaining[(k + 1) % m],
            )
        };
        let ear = (0..m).find(|&k| {
            let (a, b, c) = corner(k);
            // A reflex or collinear corner is not an ear.
            if turn(a, b, c) <= 0.0 {
                return false;
            }
            // No other remaining vertex may lie inside or on the ear.
            remaining.iter().all(|&q| {
                q == a
                    || q == b
                    || q == c
                    || !(turn(a, b, q) >= 0.0 && turn(b, c, q) >= 0.0 && turn(c, a, q) >= 0.0)
            })
        });
        let Some(k) = ear else {
            // Not simple (or numerically degenerate): a fan over what is left.
            for i in 1..m - 1 {
                triangles.push([remaining[0], remaining[i], remaining[i + 1]]);
            }
            return triangles;
        };
        let (a, b, c) = corner(k);
        triangles.push([a, b, c]);
        remaining.remove(k);
    }
    triangles.push([remaining[0], remaining[1], remaining[2]]);
    triangles
}

/// Ray/triangle intersection (Möller–Trumbore) in f64: the parameter `t` of
/// `origin + t · dir` where the ray meets the triangle, if it does (either side;
/// edges and vertices count as hits). Returns `None` for rays parallel to the
/// triangle's plane.
pub fn ray_triangle(origin: DVec3, dir: DVec3, v0: DVec3, v1: DVec3, v2: DVec3) -> Option<f64> {
    let e1 = v1 - v0;
    let e2 = v2 - v0;
    let pvec = dir.cross(e2);
    let det = e1.dot(pvec);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let tvec = origin - v0;
    let u = tvec.dot(pvec) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qvec = tvec.cross(e1);
    let v = dir.dot(qvec) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(qvec) * inv)
}

/// The bilinear map of quad `q` at (s, t): q₀ at (0, 0), q₁ at (1, 0), q₂ at
/// (1, 1), q₃ at (0, 1). Linear along every edge and iso-line, exact at the
/// corners. Also interpolates per-corner values (shading normals).
#[inline]
pub fn bilinear(q: &[DVec3], s: f64, t: f64) -> DVec3 {
    let bottom = q[0] * (1.0 - s) + q[1] * s;
    let top = q[3] * (1.0 - s) + q[2] * s;
    bottom * (1.0 - t) + top * t
}

/// (s, t) in [0, 1]² with [`bilinear`]`(q, s, t)` = `p` (projected onto the quad's
/// plane; corners q₀ at (0, 0), q₁ at (1, 0), q₂ at (1, 1), q₃ at (0, 1), the
/// order of `mesh::param::VertexKey::position`), by Newton's method: the map is smooth and a
/// convex quad's inverse is unique, so a few steps from the centre reach f64
/// rounding.
pub fn inverse_bilinear(q: &[DVec3], p: DVec3) -> (f64, f64) {
    let (mut s, mut t) = (0.5, 0.5);
    for _ in 0..12 {
        let bottom = q[0] * (1.0 - s) + q[1] * s;
        let top = q[3] * (1.0 - s) + q[2] * s;
        let r = bottom * (1.0 - t) + top * t - p;
        let ds = (q[1] - q[0]) * (1.0 - t) + (q[2] - q[3]) * t;
        let dt = top - bottom;
        // Solve [ds dt] (δs, δt) = −r in the plane, by the normal equations.
        let (a, b, c) = (ds.dot(ds), ds.dot(dt), dt.dot(dt));
        let det = a * c - b * b;
        if det.is_nan() || det <= 0.0 {
            break;
        }
        let (u, v) = (-r.dot(ds), -r.dot(dt));
        let (step_s, step_t) = ((c * u - b * v) / det, (a * v - b * u) / det);
        s = (s + step_s).clamp(0.0, 1.0);
        t = (t + step_t).clamp(0.0, 1.0);
        if step_s.abs() + step_t.abs() < 1e-14 {
            break;
        }
    }
    (s, t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounding_sphere_of_a_square_and_a_triangle() {
        // A 2 × 2 square about (1, 1, 0): its half-diagonal, √2.
        let (c, r) = bounding_sphere(&[
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(2.0, 2.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ]);
        assert!((c - DVec3::new(1.0, 1.0, 0.0)).length() < 1e-15);
        assert!((r - 2f64.sqrt()).abs() < 1e-15);
        // A right triangle: centroid (1/3, 1/3), farthest corner (1, 0) or
        // (0, 1), at √(4/9 + 1/9) = √5 / 3.
        let (c, r) = bounding_sphere(&[DVec3::ZERO, DVec3::X, DVec3::Y]);
        assert!((c - DVec3::new(1.0 / 3.0, 1.0 / 3.0, 0.0)).length() < 1e-15);
        assert!((r - 5f64.sqrt() / 3.0).abs() < 1e-15);
        assert_eq!(bounding_sphere(&[]), (DVec3::ZERO, 0.0));
    }

    fn square() -> Vec<DVec3> {
        vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ]
    }

    #[test]
    fn clipping_a_square_in_half_keeps_half_its_area() {
        let mut out = Vec::new();
        clip_to_halfspace(&square(), DVec3::new(0.5, 0.0, 0.0), DVec3::X, &mut out);
        assert!((area(&out) - 0.5).abs() < 1e-15, "area {}", area(&out));
        clip_to_halfspace(&square(), DVec3::new(2.0, 0.0, 0.0), DVec3::X, &mut out);
        assert!(out.len() < 3);
    }

    #[test]
    fn ear_clipping_an_l_shape_preserves_area_and_orientation() {
        // An L of area 3 (three unit squares), counter-clockwise about +z.
        let l = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(1.0, 2.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ];
        assert!(!is_convex(&l));
        let mut tris = Vec::new();
        triangulate(&l, &mut tris);
        assert_eq!(tris.len(), 4);
        let mut total = 0.0;
        for t in &tris {
            let n = newell_normal(&[l[t[0]], l[t[1]], l[t[2]]]);
            assert!(n.z > 0.0, "triangle {t:?} is clockwise");
            total += 0.5 * n.length();
        }
        assert!((total - 3.0).abs() < 1e-12, "area {total}");
    }

    #[test]
    fn ear_clipping_a_clockwise_l_keeps_its_orientation_and_area() {
        // The L above projected to 2-D and reversed: clockwise, area 3.
        let l: Vec<DVec2> = [
            (0.0, 2.0),
            (1.0, 2.0),
            (1.0, 1.0),
            (2.0, 1.0),
            (2.0, 0.0),
            (0.0, 0.0),
        ]
        .iter()
        .map(|&(x, y)| DVec2::new(x, y))
        .collect();
        let tris = ear_clip(&l);
        assert_eq!(tris.len(), 4);
        let signed = |t: &[usize; 3]| 0.5 * (l[t[1]] - l[t[0]]).perp_dot(l[t[2]] - l[t[0]]);
        assert!(tris.iter().all(|t| signed(t) < 0.0), "{tris:?}");
        let total: f64 = tris.iter().map(signed).sum();
        assert!((total + 3.0).abs() < 1e-12, "area {total}");
    }

    #[test]
    fn ray_hits_square_triangle() {
        let s = square();
        let t = ray_triangle(DVec3::new(0.2, 0.2, 1.0), -DVec3::Z, s[0], s[1], s[2]);
        assert_eq!(t, Some(1.0));
        let miss = ray_triangle(DVec3::new(0.2, 0.8, 1.0), -DVec3::Z, s[0], s[1], s[2]);
        assert_eq!(miss, None);
    }

    #[test]
    fn inverse_bilinear_recovers_the_coordinates_on_a_trapezoid() {
        // A convex non-parallelogram, the point lifted off its plane: Newton's
        // iterations recover (s, t) to 1e-9 (they stop at 1e-14 steps; the
        // quad is of size 3).
        let c = [
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(3.0, 0.0, 1.0),
            DVec3::new(2.0, 2.0, 1.0),
            DVec3::new(0.5, 1.5, 1.0),
        ];
        for &(s, t) in &[(0.1, 0.2), (0.5, 0.5), (0.9, 0.7), (0.0, 1.0), (0.3, 0.95)] {
            let (gs, gt) = inverse_bilinear(&c, bilinear(&c, s, t) + DVec3::Z * 0.25);
            assert!(
                (gs - s).abs() < 1e-9 && (gt - t).abs() < 1e-9,
                "({s}, {t}) → ({gs}, {gt})"
            );
        }
    }
}
