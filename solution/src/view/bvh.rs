//! A small bounding-volume hierarchy over a solution's triangles, for the few
//! thousand closest-hit rays of the default-view chooser (in the solver,
//! `solver/src/view/`) and, later, the runtime's collision and teleport.
//!
//! Binary, median split on the longest axis of the centroids' box, at most
//! [`LEAF_SIZE`] triangles a leaf, nodes in depth-first order (the left child
//! follows its parent). Building costs O(n log n) (one `select_nth_unstable` per
//! node, n per level); a ray visits O(log n) nodes in a scene of separated
//! surfaces. The solver's packet BVH is not reused: the runtime may not depend
//! on the solver, and this one needs only single closest-hit rays, in the f32
//! re-centred positions the file stores.

use glam::Vec3;

/// Triangles per leaf: small, since a ray pays each triangle it meets.
const LEAF_SIZE: usize = 4;

/// The closest hit of a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) direction.
    pub t: f32,
    /// Index of the triangle, in the order given to [`Bvh::build`].
    pub triangle: u32,
    /// Barycentric weights of the triangle's second and third corners.
    pub u: f32,
    pub v: f32,
    /// Whether the ray met the side the normal points to: triangles are
    /// counter-clockwise seen from their front (the solution format's rule).
    pub front: bool,
}

#[derive(Clone, Copy, Debug)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    /// Leaf: first index into `order`; inner node: the right child's index.
    start_or_right: u32,
    /// Leaf: its triangle count (≥ 1); inner node: 0.
    count: u32,
}

/// Triangles and the hierarchy over them.
pub struct Bvh {
    triangles: Vec<[Vec3; 3]>,
    /// Triangle indices, grouped by leaf.
    order: Vec<u32>,
    nodes: Vec<Node>,
}

impl Bvh {
    /// The bytes one triangle costs while the hierarchy is built: its
    /// positions, its slot in the order, its centroid (freed after the
    /// build) and its share of the nodes. Median splits leave leaves of 2 to
    /// [`LEAF_SIZE`] triangles, about `LEAF_SIZE − 1` on average, and a
    /// binary tree has two nodes a leaf: 2 / (LEAF_SIZE − 1) nodes a
    /// triangle (measured 0.51–0.77, test `bytes_per_triangle_matches_a_build`).
    pub fn bytes_per_triangle() -> u64 {
        (std::mem::size_of::<[Vec3; 3]>()
            + std::mem::size_of::<u32>()
            + std::mem::size_of::<Vec3>()
            + 2 * std::mem::size_of::<Node>() / (LEAF_SIZE - 1)) as u64
    }

    /// Builds the hierarchy. Degenerate triangles are kept (a ray never hits
    /// them); non-finite positions do not occur in a validated solution.
    pub fn build(triangles: Vec<[Vec3; 3]>) -> Bvh {
        let n = triangles.len();
        let mut order: Vec<u32> = (0..n as u32).collect();
        let centroids: Vec<Vec3> = triangles
            .iter()
            .map(|t| (t[0] + t[1] + t[2]) / 3.0)
            .collect();
        let mut nodes = Vec::with_capacity(2 * n / LEAF_SIZE + 1);
        if n > 0 {
            build_node(&triangles, &centroids, &mut order, 0, &mut nodes);
        }
        Bvh {
            triangles,
            order,
            nodes,
        }
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The closest hit of the ray `origin + t · direction`, 0 < t < `t_max`,
    /// on either side of a triangle. `direction` must be a unit vector.
    pub fn closest(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<Hit> {
        if self.nodes.is_empty() {
            return None;
        }
        // A zero component would give 0 · ∞ = NaN for an origin on a slab's
        // plane; a tiny one gives a finite (if huge) inverse instead.
        let inverse = Vec3::from_array(direction.to_array().map(|c| {
            if c.abs() < 1e-20 {
                1e20_f32.copysign(c)
            } else {
                1.0 / c
            }
        }));
        let mut best: Option<Hit> = None;
        let mut limit = t_max;
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        stack.push(0);
        while let Some(index) = stack.pop() {
            let node = self.nodes[index as usize];
            if !slab_hit(node.lo, node.hi, origin, inverse, limit) {
                continue;
            }
            if node.count > 0 {
                let start = node.start_or_right as usize;
                for &triangle in &self.order[start..start + node.count as usize] {
                    if let Some(hit) =
                        intersect(&self.triangles[triangle as usize], origin, direction, limit)
                    {
                        limit = hit.t;
                        best = Some(Hit { triangle, ..hit });
                    }
                }
            } else {
                stack.push(node.start_or_right);
                stack.push(index + 1);
            }
        }
        best
    }
}

/// Builds the node for `order[first..first + slice.len()]` and its subtree,
/// appending in depth-first order; returns nothing, the node is at the index
/// `nodes.len()` had on entry.
fn build_node(
    triangles: &[[Vec3; 3]],
    centroids: &[Vec3],
    slice: &mut [u32],
    first: usize,
    nodes: &mut Vec<Node>,
) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    let (mut c_lo, mut c_hi) = (lo, hi);
    for &t in slice.iter() {
        for p in triangles[t as usize] {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        let c = centroids[t as usize];
        c_lo = c_lo.min(c);
        c_hi = c_hi.max(c);
    }
    let me = nodes.len();
    nodes.push(Node {
        lo,
        hi,
        start_or_right: first as u32,
        count: slice.len() as u32,
    });
    if slice.len() <= LEAF_SIZE {
        return;
    }
    let extent = c_hi - c_lo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = slice.len() / 2;
    slice.select_nth_unstable_by(mid, |a, b| {
        centroids[*a as usize][axis].total_cmp(&centroids[*b as usize][axis])
    });
    let (left, right) = slice.split_at_mut(mid);
    build_node(triangles, centroids, left, first, nodes);
    let right_index = nodes.len() as u32;
    build_node(triangles, centroids, right, first + mid, nodes);
    nodes[me].start_or_right = right_index;
    nodes[me].count = 0;
}

/// Whether the ray meets the box before `limit` (the slab test, with `inverse`
/// finite so that no product is NaN).
fn slab_hit(lo: Vec3, hi: Vec3, origin: Vec3, inverse: Vec3, limit: f32) -> bool {
    let a = (lo - origin) * inverse;
    let b = (hi - origin) * inverse;
    let near = a.min(b).max_element().max(0.0);
    let far = a.max(b).min_element().min(limit);
    near <= far
}

/// Möller and Trumbore (1997), "Fast, minimum storage ray-triangle
/// intersection", both sides. det = e₁ · (d × e₂) = −d · (e₁ × e₂), so det > 0
/// is a ray against the normal: the front face.
fn intersect(triangle: &[Vec3; 3], origin: Vec3, direction: Vec3, limit: f32) -> Option<Hit> {
    let e1 = triangle[1] - triangle[0];
    let e2 = triangle[2] - triangle[0];
    let p = direction.cross(e2);
    let det = e1.dot(p);
    let scale = e1.length_squared().max(e2.length_squared());
    if det.abs() <= 1e-12 * scale || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - triangle[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = direction.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0 && t < limit).then_some(Hit {
        t,
        triangle: 0,
        u,
        v,
        front: det > 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A brute-force closest hit, the reference for the hierarchy.
    fn brute(triangles: &[[Vec3; 3]], o: Vec3, d: Vec3) -> Option<(u32, f32)> {
        let mut best: Option<(u32, f32)> = None;
        for (i, t) in triangles.iter().enumerate() {
            if let Some(h) = intersect(t, o, d, best.map_or(f32::INFINITY, |b| b.1)) {
                best = Some((i as u32, h.t));
            }
        }
        best
    }

    #[test]
    fn closest_hits_match_brute_force_on_a_grid_of_facing_squares() {
        // 20 × 20 unit squares (two triangles each) on z = k for k = 0..4,
        // facing +z, shifted so that rays meet every layer at varied places.
        let mut triangles = Vec::new();
        for k in 0..5 {
            for i in 0..20 {
                for j in 0..20 {
                    let z = k as f32;
                    let (x, y) = (i as f32 + 0.1 * k as f32, j as f32);
                    let a = Vec3::new(x, y, z);
                    let b = Vec3::new(x + 1.0, y, z);
                    let c = Vec3::new(x + 1.0, y + 1.0, z);
                    let d = Vec3::new(x, y + 1.0, z);
                    triangles.push([a, b, c]);
                    triangles.push([a, c, d]);
                }
            }
        }
        let bvh = Bvh::build(triangles.clone());
        let mut checked = 0;
        for i in 0..37 {
            for j in 0..37 {
                let o = Vec3::new(0.3 + 0.55 * i as f32, 0.2 + 0.55 * j as f32, 10.0);
                let d = Vec3::new(0.05 * (i % 5) as f32, -0.03 * (j % 7) as f32, -1.0).normalize();
                let got = bvh.closest(o, d, f32::INFINITY);
                let want = brute(&triangles, o, d);
                assert_eq!(got.map(|h| (h.triangle, h.t)), want, "ray {i},{j}");
                if let Some(h) = got {
                    // Coming down onto faces whose normal is +z: the front.
                    assert!(h.front);
                    checked += 1;
                }
            }
        }
        assert!(checked > 1000, "{checked}");
    }

    #[test]
    fn the_back_of_a_triangle_is_reported_as_such() {
        let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let bvh = Bvh::build(vec![t]);
        let front = bvh
            .closest(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z, 10.0)
            .unwrap();
        let back = bvh
            .closest(Vec3::new(0.2, 0.2, -1.0), Vec3::Z, 10.0)
            .unwrap();
        assert!(front.front && !back.front);
        assert!((front.t - 1.0).abs() < 1e-6 && (back.t - 1.0).abs() < 1e-6);
        assert!((front.u - 0.2).abs() < 1e-6 && (front.v - 0.2).abs() < 1e-6);
        assert!(bvh
            .closest(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z, 0.5)
            .is_none());
        assert!(Bvh::build(Vec::new())
            .closest(Vec3::ZERO, Vec3::X, 1.0)
            .is_none());
    }

    /// The memory estimate's per-triangle figure against a real build: the
    /// positions, order and centroids by length, the nodes as `build` left
    /// them. The node share varies with the triangle count (median splits
    /// leave leaves of 2 to 4 triangles: measured 68.4–76.7 bytes a triangle
    /// at these counts), so the model, an average leaf of 3, must be within
    /// 10% of each.
    #[test]
    fn bytes_per_triangle_matches_a_build() {
        for n in [1_000usize, 10_000, 77_777] {
            let triangles: Vec<[Vec3; 3]> = (0..n)
                .map(|i| {
                    let a = Vec3::new((i % 100) as f32, (i / 100) as f32, (i % 7) as f32);
                    [a, a + Vec3::X, a + Vec3::Y]
                })
                .collect();
            let bvh = Bvh::build(triangles);
            let measured = std::mem::size_of_val(bvh.triangles.as_slice())
                + std::mem::size_of_val(bvh.order.as_slice())
                + n * std::mem::size_of::<Vec3>()
                + std::mem::size_of_val(bvh.nodes.as_slice());
            let per = measured as f64 / n as f64;
            let model = Bvh::bytes_per_triangle() as f64;
            assert!(
                (model - per).abs() < 0.10 * per,
                "n {n}: {per:.1} measured, {model} modelled"
            );
        }
    }
}
