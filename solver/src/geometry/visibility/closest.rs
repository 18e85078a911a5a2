//! Closest-hit queries on the [`Occluder`]'s BVH, for the reference path tracer
//! (`crate::reference`): the nearest triangle a ray meets, with its input polygon,
//! parameter and barycentrics.
//!
//! The occluder's traversal answers "is anything in the way" and stops at the
//! first hit; a closest-hit query must instead shrink the ray's window to the
//! nearest hit found so far and visit children front to back, so that boxes
//! behind that hit are skipped. It reuses the occluder's f32 triangles, padded
//! boxes and Möller–Trumbore terms, so it has the same conservative edge
//! tolerance ([`super::BARY_EPSILON`]): a ray through an edge shared by two
//! triangles always hits one of them.
//!
//! Precision: `t` is computed in f32 relative to the occluder's centre, so it
//! carries an absolute error of about 1e-7 of the scene's size. Callers that need
//! the hit point in f64 (the path tracer does) re-intersect the ray with the hit
//! polygon's plane.

use super::{fmax, fmin, sort4, to_f32, triangle_terms, Occluder, BARY_EPSILON};
use super::{EMPTY_SLOT, LEAF_BIT};
use glam::DVec3;

/// The nearest surface a ray meets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosestHit {
    /// Index of the input polygon (as passed to [`Occluder::new`]).
    pub polygon: usize,
    /// Index of the stored triangle (see [`Occluder::polygon_of_triangle`]).
    pub triangle: usize,
    /// Ray parameter: the hit is at `origin + t · dir` (`dir` as given, not
    /// normalised).
    pub t: f64,
    /// Barycentric coordinates of the hit in the stored triangle `(v0, v1, v2)`:
    /// the hit is `(1 − u − v) v0 + u v1 + v v2`.
    pub u: f64,
    pub v: f64,
    /// Whether the ray meets the triangle's front (counter-clockwise) side, i.e.
    /// travels against the polygon's normal.
    pub front: bool,
}

impl Occluder {
    /// The nearest polygon that the ray `origin + t · dir` meets with
    /// `t_min < t < t_max`, where `t_min` is [`Occluder::scene_epsilon`] along
    /// the ray (so a ray leaving a surface does not hit that surface). Either side
    /// of a polygon counts ([`ClosestHit::front`] says which). `None` when the ray
    /// meets nothing, `dir` is zero or not finite, or the window is empty.
    pub fn closest_hit(&self, origin: DVec3, dir: DVec3, t_max: f64) -> Option<ClosestHit> {
        if self.nodes.is_empty() || !origin.is_finite() || !dir.is_finite() {
            return None;
        }
        let len = dir.length();
        if len.is_nan() || len <= 0.0 {
            return None;
        }
        let d = to_f32(dir);
        let o = to_f32(origin - self.centre);
        let t_min = (self.epsilon / len) as f32;
        let mut best_t = if t_max.is_finite() {
            t_max as f32
        } else {
            f32::INFINITY
        };
        if best_t.is_nan() || best_t <= t_min {
            return None;
        }
        let inv = d.map(|x| {
            1.0 / if x.abs() < 1e-30 {
                1e-30f32.copysign(x)
            } else {
                x
            }
        });
        let mut best: Option<(usize, f32, f32, f32, bool)> = None;
        let mut stack = [0u32; 256];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            let mut t0 = [t_min; 4];
            let mut t1 = [best_t; 4];
            for a in 0..3 {
                for k in 0..4 {
                    let ta = (node.lo[a][k] - o[a]) * inv[a];
                    let tb = (node.hi[a][k] - o[a]) * inv[a];
                    t0[k] = fmax(t0[k], fmin(ta, tb));
                    t1[k] = fmin(t1[k], fmax(ta, tb));
                }
            }
            // Push the farthest child first so that the nearest is popped first.
            let order = sort4(t0);
            for &k in order.iter().rev() {
                if t0[k] > t1[k] || node.child[k] == EMPTY_SLOT {
                    continue;
                }
                let child = node.child[k];
                if child & LEAF_BIT == 0 {
                    // The tree's depth is far below 256 / 4 levels (the builder
                    // splits by SAH into 4-wide nodes), so the stack cannot overflow.
                    stack[top] = child;
                    top += 1;
                    continue;
                }
                let first = (child & !LEAF_BIT) as usize;
                for (i, tri) in self.triangles[first..first + node.count[k] as usize]
                    .iter()
                    .enumerate()
                {
                    let p = triangle_terms(o, tri);
                    if let Some((t, u, v, front)) = nearer_hit(d, &p, t_min, best_t) {
                        best_t = t;
                        best = Some((first + i, t, u, v, front));
                    }
                }
            }
        }
        best.map(|(triangle, t, u, v, front)| ClosestHit {
            polygon: self.polygon_of[triangle] as usize,
            triangle,
            t: t as f64,
            u: u as f64,
            v: v as f64,
            front,
        })
    }
}

/// The hit `(t, u, v, front)` of direction `d` with the triangle whose
/// [`triangle_terms`] are `p`, when it lies in `(t_min, t_best)`; barycentric
/// bounds widened by [`BARY_EPSILON`] as in the occlusion test.
#[inline(always)]
fn nearer_hit(
    d: [f32; 3],
    p: &[f32; 10],
    t_min: f32,
    t_best: f32,
) -> Option<(f32, f32, f32, bool)> {
    let det = d[0] * p[0] + d[1] * p[1] + d[2] * p[2];
    if !(det != 0.0) {
        return None;
    }
    let inv = 1.0 / det;
    let u = (d[0] * p[3] + d[1] * p[4] + d[2] * p[5]) * inv;
    let v = (d[0] * p[6] + d[1] * p[7] + d[2] * p[8]) * inv;
    let t = p[9] * inv;
    let tol = BARY_EPSILON;
    let inside = u >= -tol && v >= -tol && u + v <= 1.0 + tol;
    // det = −d·n: positive when the ray travels against the normal (front side).
    (inside && t > t_min && t < t_best).then_some((t, u, v, det > 0.0))
}

#[cfg(test)]
mod tests {
    use super::super::tests::cornell_box;
    use super::*;
    use crate::geometry::polygon::{ray_triangle, triangulate};
    use crate::geometry::sampling::Rng;

    /// Brute force in f64 over every triangle of every polygon: the nearest
    /// parameter and its polygon.
    fn brute_force(
        polygons: &[Vec<DVec3>],
        o: DVec3,
        d: DVec3,
        t_min: f64,
    ) -> Option<(usize, f64)> {
        let mut best: Option<(usize, f64)> = None;
        let mut tris = Vec::new();
        for (i, p) in polygons.iter().enumerate() {
            tris.clear();
            triangulate(p, &mut tris);
            for t in &tris {
                if let Some(t) = ray_triangle(o, d, p[t[0]], p[t[1]], p[t[2]]) {
                    if t > t_min && best.is_none_or(|(_, b)| t < b) {
                        best = Some((i, t));
                    }
                }
            }
        }
        best
    }

    fn random_in_box(rng: &mut Rng, lo: DVec3, hi: DVec3) -> DVec3 {
        lo + (hi - lo) * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64())
    }

    #[test]
    fn closest_hit_matches_brute_force_in_the_cornell_box() {
        let polygons = cornell_box();
        let occluder = Occluder::new(&polygons);
        let mut rng = Rng::new(7, 1);
        let (lo, hi) = (
            DVec3::new(10.0, 10.0, 10.0),
            DVec3::new(540.0, 540.0, 550.0),
        );
        let mut checked = 0;
        for _ in 0..4000 {
            let o = random_in_box(&mut rng, lo, hi);
            let d = random_in_box(&mut rng, -DVec3::ONE, DVec3::ONE);
            let hit = occluder.closest_hit(o, d, f64::INFINITY);
            let expected = brute_force(&polygons, o, d, 1e-9);
            match (hit, expected) {
                (Some(h), Some((p, t))) => {
                    // The f32 parameter: relative error ~1e-6 of the box's size
                    // (~1e3 units) over |d| ≤ √3, i.e. ~1e-3 in t at worst.
                    assert!(
                        (h.t - t).abs() <= 1e-5 * 1000.0 / d.length() + 1e-6 * t,
                        "t {} vs {t}",
                        h.t
                    );
                    if h.polygon != p {
                        // Only a tie (two polygons at the same t, e.g. a corner)
                        // may choose differently.
                        let other = brute_force(&[polygons[h.polygon].clone()], o, d, 1e-9);
                        let t_other = other.map(|(_, t)| t).unwrap_or(f64::INFINITY);
                        assert!((t_other - t).abs() < 1e-3, "polygon {} vs {p}", h.polygon);
                    }
                    // The barycentrics put the hit where t does.
                    let hit_point = o + d * h.t;
                    let tri = &occluder.triangles[h.triangle];
                    let w = |a: [f32; 3]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
                    let bary = occluder.centre + w(tri.v0) + w(tri.e1) * h.u + w(tri.e2) * h.v;
                    assert!((bary - hit_point).length() < 1e-2, "{bary} vs {hit_point}");
                    checked += 1;
                }
                // The box is open at its front (z = 0): rays leaving through it
                // miss in both.
                (None, None) => {}
                (h, e) => panic!("closest {h:?} vs brute force {e:?} for {o} {d}"),
            }
        }
        // Most rays hit a wall or a block (the open side is one of six).
        assert!(checked > 2500, "{checked}");
    }

    #[test]
    fn front_flag_and_window() {
        let square = vec![vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ]];
        let occluder = Occluder::new(&square);
        let down = occluder
            .closest_hit(
                DVec3::new(0.3, 0.4, 2.0),
                DVec3::new(0.0, 0.0, -1.0),
                f64::INFINITY,
            )
            .unwrap();
        assert!(down.front && down.polygon == 0);
        assert!((down.t - 2.0).abs() < 1e-6);
        let up = occluder
            .closest_hit(
                DVec3::new(0.3, 0.4, -2.0),
                DVec3::new(0.0, 0.0, 2.0),
                f64::INFINITY,
            )
            .unwrap();
        assert!(!up.front && (up.t - 1.0).abs() < 1e-6);
        // The window excludes hits beyond t_max, and rays that miss.
        assert!(occluder
            .closest_hit(DVec3::new(0.3, 0.4, 2.0), DVec3::new(0.0, 0.0, -1.0), 1.5)
            .is_none());
        assert!(occluder
            .closest_hit(
                DVec3::new(3.0, 0.4, 2.0),
                DVec3::new(0.0, 0.0, -1.0),
                f64::INFINITY
            )
            .is_none());
        assert!(occluder
            .closest_hit(DVec3::ZERO, DVec3::ZERO, f64::INFINITY)
            .is_none());
    }
}
