//! Planar-polygon checks used while cleaning and welding: size, flatness, a 2-D
//! projection, simplicity and strict convexity. All in f64 on re-centred
//! positions. Newell's normal and ear clipping are [`crate::geometry::polygon`]'s.

use glam::{DVec2, DVec3};

/// Length of the diagonal of the vertices' bounding box: the polygon's size.
pub(crate) fn bbox_diagonal(vertices: &[DVec3]) -> f64 {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for v in vertices {
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    if vertices.is_empty() {
        0.0
    } else {
        (hi - lo).length()
    }
}

/// The largest distance of a vertex from the plane through the centroid with
/// unit normal `n` (Newell's plane, the least-squares plane's usual stand-in).
pub(crate) fn max_plane_deviation(vertices: &[DVec3], n: DVec3) -> f64 {
    let centroid = vertices.iter().copied().sum::<DVec3>() / vertices.len() as f64;
    vertices
        .iter()
        .map(|v| (*v - centroid).dot(n).abs())
        .fold(0.0, f64::max)
}

/// Projects onto the plane with unit normal `n`, in a right-handed 2-D basis so
/// that counter-clockwise about `n` stays counter-clockwise.
pub(crate) fn project(vertices: &[DVec3], n: DVec3) -> Vec<DVec2> {
    let u = n.any_orthonormal_vector();
    let w = n.cross(u);
    vertices
        .iter()
        .map(|v| DVec2::new(v.dot(u), v.dot(w)))
        .collect()
}

fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// Whether closed segments `ab` and `cd` intersect (touching counts).
fn segments_intersect(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    let on = |p: DVec2, q: DVec2, r: DVec2, o: f64| {
        o == 0.0
            && r.x >= p.x.min(q.x)
            && r.x <= p.x.max(q.x)
            && r.y >= p.y.min(q.y)
            && r.y <= p.y.max(q.y)
    };
    on(c, d, a, d1) || on(c, d, b, d2) || on(a, b, c, d3) || on(a, b, d, d4)
}

/// Whether the 2-D polygon is simple: no two non-adjacent edges meet.
pub(crate) fn is_simple(p: &[DVec2]) -> bool {
    let n = p.len();
    if n < 4 {
        return true;
    }
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue; // edges n−1 and 0 share vertex 0
            }
            if segments_intersect(a, b, p[j], p[(j + 1) % n]) {
                return false;
            }
        }
    }
    true
}

/// Whether the 3-D polygon is strictly convex and counter-clockwise about `n`:
/// every turn is to the left, and the turns add up to one full revolution (which
/// rules out star shapes whose turns all have the same sign).
pub(crate) fn is_convex(vertices: &[DVec3], n: DVec3) -> bool {
    let count = vertices.len();
    if count < 3 {
        return false;
    }
    let mut turning = 0.0;
    for i in 0..count {
        let a = vertices[(i + count - 1) % count];
        let b = vertices[i];
        let c = vertices[(i + 1) % count];
        let (e1, e2) = (b - a, c - b);
        let s = e1.cross(e2).dot(n);
        if s <= 0.0 {
            return false;
        }
        turning += s.atan2(e1.dot(e2));
    }
    (turning - std::f64::consts::TAU).abs() < 1e-6
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::polygon::newell_normal;

    #[test]
    fn newell_area_and_deviation() {
        let square = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(2.0, 2.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ];
        assert_eq!(newell_normal(&square), DVec3::new(0.0, 0.0, 8.0));
        assert_eq!(max_plane_deviation(&square, DVec3::Z), 0.0);
        let mut bent = square;
        bent[2].z = 0.4;
        // Newell's normal of a quad bent at one corner: deviations ±0.1 alternate.
        let n = newell_normal(&bent).normalize();
        assert!((max_plane_deviation(&bent, n) - 0.1 * n.z).abs() < 1e-12);
    }

    #[test]
    fn simplicity_and_convexity() {
        let bowtie = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(0.0, 1.0),
        ];
        assert!(!is_simple(&bowtie));
        let l_shape = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(1.0, 2.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ];
        assert!(is_simple(&project(&l_shape, DVec3::Z)));
        assert!(!is_convex(&l_shape, DVec3::Z));
        assert!(is_convex(&l_shape[..3], DVec3::Z));
        // A pentagram turns left at every vertex but twice around.
        let star: Vec<DVec3> = (0..5)
            .map(|k| {
                let t = (k as f64) * 4.0 * std::f64::consts::PI / 5.0;
                DVec3::new(t.cos(), t.sin(), 0.0)
            })
            .collect();
        assert!(!is_convex(&star, DVec3::Z));
    }
}
