//! Segment visibility for ray-cast form factors: an any-hit BVH over the scene's
//! input polygons (000 §3.4: rays are tested against the input polygons, never
//! against the hundreds of mesh elements each one becomes).
//!
//! Precision: the occluder stores triangles in f32 relative to the centre of
//! its own bounding box (subtracted in f64), so a scene far from the origin
//! (translated by 1e6) answers exactly like the same scene at the origin. f32
//! rounding of a vertex is then ≤ 6e-8 of the scene's half-diagonal; the
//! [`Occluder::scene_epsilon`] of 1e-5 of the diagonal, node boxes padded by
//! 1e-6 of the diagonal and barycentric tests widened by 1e-5 keep the tests
//! conservative: a ray that passes within rounding of an edge counts as
//! blocked, never as leaking through a closed surface.

use super::polygon::triangulate;
use glam::DVec3;

/// Relative size of [`Occluder::scene_epsilon`]: a fraction of the scene's
/// bounding-box diagonal.
pub const SCENE_EPSILON: f64 = 1e-5;

/// Node boxes are padded by this fraction of the diagonal, far above f32
/// rounding of the relative coordinates (≈ 6e-8 of the half-diagonal), so the
/// f32 slab test never misses a box that a triangle's hit lies in.
const BOX_PADDING: f64 = 1e-6;

/// Barycentric tolerance of the f32 triangle test: hits within this fraction of
/// a triangle's extent outside its edges count, so shared edges never leak.
const BARY_EPSILON: f32 = 1e-5;

/// Leaves hold at most this many triangles.
const MAX_LEAF: usize = 4;

/// A triangle prepared for the Möller–Trumbore test: one vertex and two edges,
/// in f32, relative to the occluder's centre.
#[derive(Clone, Copy, Debug)]
struct Triangle {
    v0: [f32; 3],
    e1: [f32; 3],
    e2: [f32; 3],
}

/// A binary BVH node. Inner nodes (`count == 0`) have their children at
/// `first` and `first + 1`; leaves hold `count` triangles from `first`.
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: [f32; 3],
    first: u32,
    hi: [f32; 3],
    count: u32,
}

/// An any-hit occlusion structure over a scene's polygons. `Send + Sync`:
/// build once, query from every thread.
#[derive(Clone, Debug)]
pub struct Occluder {
    centre: DVec3,
    epsilon: f64,
    nodes: Vec<Node>,
    triangles: Vec<Triangle>,
    /// For each stored triangle, the index of the input polygon it came from.
    polygon_of: Vec<u32>,
}

impl Occluder {
    /// Builds the occluder over `polygons` (planar, simple, counter-clockwise;
    /// convex or not). Each polygon is triangulated (fan or ear clipping);
    /// degenerate polygons contribute nothing. An empty scene gives an occluder
    /// that blocks nothing.
    pub fn new<P: AsRef<[DVec3]>>(polygons: &[P]) -> Self {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for p in polygons {
            for &v in p.as_ref() {
                if v.is_finite() {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
        }
        if !(lo.x <= hi.x) {
            lo = DVec3::ZERO;
            hi = DVec3::ZERO;
        }
        let centre = (lo + hi) * 0.5;
        let diagonal = (hi - lo).length();
        let epsilon = if diagonal > 0.0 {
            SCENE_EPSILON * diagonal
        } else {
            SCENE_EPSILON
        };

        let mut triangles = Vec::new();
        let mut polygon_of = Vec::new();
        let mut tris = Vec::new();
        for (index, p) in polygons.iter().enumerate() {
            let p = p.as_ref();
            if p.iter().any(|v| !v.is_finite()) {
                continue;
            }
            tris.clear();
            triangulate(p, &mut tris);
            for t in &tris {
                let v0 = p[t[0]] - centre;
                let v1 = p[t[1]] - centre;
                let v2 = p[t[2]] - centre;
                triangles.push(Triangle {
                    v0: to_f32(v0),
                    e1: to_f32(v1 - v0),
                    e2: to_f32(v2 - v0),
                });
                polygon_of.push(index as u32);
            }
        }
        let padding = (BOX_PADDING * diagonal) as f32;
        let (nodes, order) = build_bvh(&triangles, padding);
        let triangles = order.iter().map(|&i| triangles[i as usize]).collect();
        let polygon_of = order.iter().map(|&i| polygon_of[i as usize]).collect();
        Occluder {
            centre,
            epsilon,
            nodes,
            triangles,
            polygon_of,
        }
    }

    /// Builds the occluder over a scene's polygons.
    pub fn from_polygons(polygons: &[crate::scene::Polygon]) -> Self {
        let list: Vec<&[DVec3]> = polygons.iter().map(|p| p.vertices.as_slice()).collect();
        Self::new(&list)
    }

    /// A scale-aware offset: 1e-5 of the scene's bounding-box diagonal. Start
    /// rays this far off a surface (along its normal) and it is far above the
    /// occluder's f32 rounding; segment ends closer than this to a surface are
    /// not blocked by it.
    pub fn scene_epsilon(&self) -> f64 {
        self.epsilon
    }

    /// Number of triangles the input polygons became.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The input polygon that stored triangle `i` came from (for diagnostics).
    pub fn polygon_of_triangle(&self, i: usize) -> Option<usize> {
        self.polygon_of.get(i).map(|&p| p as usize)
    }

    /// Whether the open segment from `from` to `to` is unobstructed. The ends
    /// are excluded by [`Occluder::scene_epsilon`] each (a relative epsilon in
    /// the segment's parameter), so a segment between two points on surfaces is
    /// not blocked by those surfaces. Segments shorter than two epsilons are
    /// visible.
    pub fn visible(&self, from: DVec3, to: DVec3) -> bool {
        match SegmentRay::new(self, from, to) {
            Some(ray) => !self.any_hit(&ray),
            None => true,
        }
    }

    /// How many of the segments from `origin` to each of `targets` are
    /// unobstructed; the same answers as calling [`Occluder::visible`] for each.
    /// One receiver's samples of a source share their origin, which this path
    /// exploits.
    pub fn count_visible(&self, origin: DVec3, targets: &[DVec3]) -> u32 {
        targets.iter().filter(|&&t| self.visible(origin, t)).count() as u32
    }

    /// Per-target visibility from a shared origin into `out` (cleared first),
    /// the δ_i of 000 eq. 3.1; the same answers as [`Occluder::visible`].
    pub fn visible_each(&self, origin: DVec3, targets: &[DVec3], out: &mut Vec<bool>) {
        out.clear();
        out.extend(targets.iter().map(|&t| self.visible(origin, t)));
    }

    fn any_hit(&self, ray: &SegmentRay) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let mut stack = [0u32; 64];
        let mut top = 1;
        stack[0] = 0;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if !ray.hits_box(node) {
                continue;
            }
            if node.count > 0 {
                let first = node.first as usize;
                for tri in &self.triangles[first..first + node.count as usize] {
                    if ray.hits_triangle(tri) {
                        return true;
                    }
                }
            } else {
                // Depth is bounded by the builder (≤ 60 levels), see build_bvh.
                stack[top] = node.first;
                stack[top + 1] = node.first + 1;
                top += 2;
            }
        }
        false
    }
}

fn to_f32(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

/// A segment as an f32 ray relative to the occluder's centre, with its
/// parameter window [t_min, t_max] excluding the ends.
struct SegmentRay {
    origin: [f32; 3],
    dir: [f32; 3],
    inv_dir: [f32; 3],
    t_min: f32,
    t_max: f32,
}

impl SegmentRay {
    fn new(occ: &Occluder, from: DVec3, to: DVec3) -> Option<Self> {
        let d = to - from;
        let len = d.length();
        if !(len > 2.0 * occ.epsilon) || !len.is_finite() {
            return None;
        }
        let t_eps = occ.epsilon / len;
        let origin = to_f32(from - occ.centre);
        let dir = to_f32(d);
        let inv = |c: f32| {
            // A zero component would make 0 · ∞ = NaN in the slab test; a huge
            // finite inverse gives the same answer without NaN.
            let c = if c.abs() < 1e-30 {
                1e-30f32.copysign(c)
            } else {
                c
            };
            1.0 / c
        };
        Some(SegmentRay {
            origin,
            dir,
            inv_dir: [inv(dir[0]), inv(dir[1]), inv(dir[2])],
            t_min: t_eps as f32,
            t_max: (1.0 - t_eps) as f32,
        })
    }

    #[inline]
    fn hits_box(&self, node: &Node) -> bool {
        let mut t0 = self.t_min;
        let mut t1 = self.t_max;
        for a in 0..3 {
            let ta = (node.lo[a] - self.origin[a]) * self.inv_dir[a];
            let tb = (node.hi[a] - self.origin[a]) * self.inv_dir[a];
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        t0 <= t1
    }

    /// Möller–Trumbore in f32 with widened barycentric bounds.
    #[inline]
    fn hits_triangle(&self, tri: &Triangle) -> bool {
        let d = self.dir;
        let (e1, e2) = (tri.e1, tri.e2);
        let p = cross(d, e2);
        let det = dot(e1, p);
        if det == 0.0 {
            return false;
        }
        let inv = 1.0 / det;
        let s = sub(self.origin, tri.v0);
        let u = dot(s, p) * inv;
        if !(-BARY_EPSILON..=1.0 + BARY_EPSILON).contains(&u) {
            return false;
        }
        let q = cross(s, e1);
        let v = dot(d, q) * inv;
        if v < -BARY_EPSILON || u + v > 1.0 + BARY_EPSILON {
            return false;
        }
        let t = dot(e2, q) * inv;
        t > self.t_min && t < self.t_max
    }
}

#[inline]
fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline]
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline]
fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Axis-aligned box in f32 used by the builder.
#[derive(Clone, Copy, Debug)]
struct Aabb {
    lo: [f32; 3],
    hi: [f32; 3],
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        lo: [f32::INFINITY; 3],
        hi: [f32::NEG_INFINITY; 3],
    };
    fn grow_point(&mut self, p: [f32; 3]) {
        for a in 0..3 {
            self.lo[a] = self.lo[a].min(p[a]);
            self.hi[a] = self.hi[a].max(p[a]);
        }
    }
    fn grow(&mut self, b: &Aabb) {
        for a in 0..3 {
            self.lo[a] = self.lo[a].min(b.lo[a]);
            self.hi[a] = self.hi[a].max(b.hi[a]);
        }
    }
    fn half_area(&self) -> f32 {
        let d = [
            self.hi[0] - self.lo[0],
            self.hi[1] - self.lo[1],
            self.hi[2] - self.lo[2],
        ];
        if d[0] < 0.0 {
            return 0.0;
        }
        d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
    }
    fn of_triangle(t: &Triangle) -> Aabb {
        let mut b = Aabb::EMPTY;
        b.grow_point(t.v0);
        b.grow_point([t.v0[0] + t.e1[0], t.v0[1] + t.e1[1], t.v0[2] + t.e1[2]]);
        b.grow_point([t.v0[0] + t.e2[0], t.v0[1] + t.e2[1], t.v0[2] + t.e2[2]]);
        b
    }
}

/// Binned-SAH build (16 bins on centroids). Returns the nodes (root first) and
/// the triangle order of the leaves. Depth stays far below the traversal
/// stack: each split leaves at least one triangle on each side, and splits
/// fall back to the median when binning cannot separate centroids, so the
/// depth is ≤ log2(n) + O(1) for median splits; SAH splits of pathological
/// inputs are capped at depth 48 by forcing median splits there.
fn build_bvh(triangles: &[Triangle], padding: f32) -> (Vec<Node>, Vec<u32>) {
    let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
    if triangles.is_empty() {
        return (Vec::new(), order);
    }
    let boxes: Vec<Aabb> = triangles.iter().map(Aabb::of_triangle).collect();
    let centroids: Vec<[f32; 3]> = boxes
        .iter()
        .map(|b| {
            [
                0.5 * (b.lo[0] + b.hi[0]),
                0.5 * (b.lo[1] + b.hi[1]),
                0.5 * (b.lo[2] + b.hi[2]),
            ]
        })
        .collect();
    let mut nodes = Vec::with_capacity(2 * triangles.len() / MAX_LEAF + 1);
    nodes.push(Node {
        lo: [0.0; 3],
        first: 0,
        hi: [0.0; 3],
        count: 0,
    });
    // (node index, start, end, depth)
    let mut work = vec![(0usize, 0usize, triangles.len(), 0u32)];
    while let Some((node_index, start, end, depth)) = work.pop() {
        let mut bounds = Aabb::EMPTY;
        let mut cbounds = Aabb::EMPTY;
        for &i in &order[start..end] {
            bounds.grow(&boxes[i as usize]);
            cbounds.grow_point(centroids[i as usize]);
        }
        let node = &mut nodes[node_index];
        for a in 0..3 {
            node.lo[a] = bounds.lo[a] - padding;
            node.hi[a] = bounds.hi[a] + padding;
        }
        let count = end - start;
        if count <= MAX_LEAF {
            node.first = start as u32;
            node.count = count as u32;
            continue;
        }
        let mid = split(
            &mut order[start..end],
            &boxes,
            &centroids,
            &cbounds,
            depth >= 48,
        )
        .map(|m| start + m)
        .unwrap_or(start + count / 2);
        let left = nodes.len();
        nodes[node_index].first = left as u32;
        nodes[node_index].count = 0;
        nodes.push(Node {
            lo: [0.0; 3],
            first: 0,
            hi: [0.0; 3],
            count: 0,
        });
        nodes.push(Node {
            lo: [0.0; 3],
            first: 0,
            hi: [0.0; 3],
            count: 0,
        });
        work.push((left, start, mid, depth + 1));
        work.push((left + 1, mid, end, depth + 1));
    }
    (nodes, order)
}

/// Partitions `order` by the best binned-SAH plane and returns the split
/// position (1..len-1), or sorts by the widest centroid axis and returns the
/// median when binning fails or `median` is forced.
fn split(
    order: &mut [u32],
    boxes: &[Aabb],
    centroids: &[[f32; 3]],
    cbounds: &Aabb,
    median: bool,
) -> Option<usize> {
    const BINS: usize = 16;
    let extent = [
        cbounds.hi[0] - cbounds.lo[0],
        cbounds.hi[1] - cbounds.lo[1],
        cbounds.hi[2] - cbounds.lo[2],
    ];
    let widest = if extent[0] >= extent[1] && extent[0] >= extent[2] {
        0
    } else if extent[1] >= extent[2] {
        1
    } else {
        2
    };
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bin boundary)
    if !median {
        for axis in 0..3 {
            if !(extent[axis] > 0.0) {
                continue;
            }
            let scale = BINS as f32 / extent[axis];
            let bin_of = |c: f32| (((c - cbounds.lo[axis]) * scale) as usize).min(BINS - 1);
            let mut bin_box = [Aabb::EMPTY; BINS];
            let mut bin_count = [0usize; BINS];
            for &i in order.iter() {
                let b = bin_of(centroids[i as usize][axis]);
                bin_box[b].grow(&boxes[i as usize]);
                bin_count[b] += 1;
            }
            let mut right_area = [0.0f32; BINS];
            let mut acc = Aabb::EMPTY;
            let mut acc_count = 0;
            let mut right_count = [0usize; BINS];
            for b in (1..BINS).rev() {
                acc.grow(&bin_box[b]);
                acc_count += bin_count[b];
                right_area[b] = acc.half_area();
                right_count[b] = acc_count;
            }
            let mut acc = Aabb::EMPTY;
            let mut acc_count = 0;
            for b in 1..BINS {
                acc.grow(&bin_box[b - 1]);
                acc_count += bin_count[b - 1];
                if acc_count == 0 || right_count[b] == 0 {
                    continue;
                }
                let cost =
                    acc.half_area() * acc_count as f32 + right_area[b] * right_count[b] as f32;
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, b));
                }
            }
        }
    }
    if let Some((_, axis, boundary)) = best {
        let scale = BINS as f32 / extent[axis];
        let lo = cbounds.lo[axis];
        let goes_left = |i: u32| {
            ((((centroids[i as usize][axis] - lo) * scale) as usize).min(BINS - 1)) < boundary
        };
        let mut left = 0;
        for k in 0..order.len() {
            if goes_left(order[k]) {
                order.swap(left, k);
                left += 1;
            }
        }
        if left > 0 && left < order.len() {
            return Some(left);
        }
    }
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |&a, &b| {
        centroids[a as usize][widest].total_cmp(&centroids[b as usize][widest])
    });
    Some(mid)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Cornell box blocks' and room's quads (from the published data, as in
    /// shared/scenes/cornell_box.obj), wound to face the room's interior.
    pub(crate) fn cornell_box() -> Vec<Vec<DVec3>> {
        let q = |v: [[f64; 3]; 4]| v.iter().map(|p| DVec3::from_array(*p)).collect::<Vec<_>>();
        vec![
            // floor, ceiling, back wall, right wall (green, x = 0), left wall (red)
            q([
                [552.8, 0.0, 0.0],
                [0.0, 0.0, 0.0],
                [0.0, 0.0, 559.2],
                [549.6, 0.0, 559.2],
            ]),
            q([
                [556.0, 548.8, 0.0],
                [556.0, 548.8, 559.2],
                [0.0, 548.8, 559.2],
                [0.0, 548.8, 0.0],
            ]),
            q([
                [549.6, 0.0, 559.2],
                [0.0, 0.0, 559.2],
                [0.0, 548.8, 559.2],
                [556.0, 548.8, 559.2],
            ]),
            q([
                [0.0, 0.0, 559.2],
                [0.0, 0.0, 0.0],
                [0.0, 548.8, 0.0],
                [0.0, 548.8, 559.2],
            ]),
            q([
                [552.8, 0.0, 0.0],
                [549.6, 0.0, 559.2],
                [556.0, 548.8, 559.2],
                [556.0, 548.8, 0.0],
            ]),
            // light
            q([
                [343.0, 548.7, 227.0],
                [343.0, 548.7, 332.0],
                [213.0, 548.7, 332.0],
                [213.0, 548.7, 227.0],
            ]),
            // short block
            q([
                [130.0, 165.0, 65.0],
                [82.0, 165.0, 225.0],
                [240.0, 165.0, 272.0],
                [290.0, 165.0, 114.0],
            ]),
            q([
                [290.0, 0.0, 114.0],
                [290.0, 165.0, 114.0],
                [240.0, 165.0, 272.0],
                [240.0, 0.0, 272.0],
            ]),
            q([
                [130.0, 0.0, 65.0],
                [130.0, 165.0, 65.0],
                [290.0, 165.0, 114.0],
                [290.0, 0.0, 114.0],
            ]),
            q([
                [82.0, 0.0, 225.0],
                [82.0, 165.0, 225.0],
                [130.0, 165.0, 65.0],
                [130.0, 0.0, 65.0],
            ]),
            q([
                [240.0, 0.0, 272.0],
                [240.0, 165.0, 272.0],
                [82.0, 165.0, 225.0],
                [82.0, 0.0, 225.0],
            ]),
            // tall block
            q([
                [423.0, 330.0, 247.0],
                [265.0, 330.0, 296.0],
                [314.0, 330.0, 456.0],
                [472.0, 330.0, 406.0],
            ]),
            q([
                [423.0, 0.0, 247.0],
                [423.0, 330.0, 247.0],
                [472.0, 330.0, 406.0],
                [472.0, 0.0, 406.0],
            ]),
            q([
                [472.0, 0.0, 406.0],
                [472.0, 330.0, 406.0],
                [314.0, 330.0, 456.0],
                [314.0, 0.0, 456.0],
            ]),
            q([
                [314.0, 0.0, 456.0],
                [314.0, 330.0, 456.0],
                [265.0, 330.0, 296.0],
                [265.0, 0.0, 296.0],
            ]),
            q([
                [265.0, 0.0, 296.0],
                [265.0, 330.0, 296.0],
                [423.0, 330.0, 247.0],
                [423.0, 0.0, 247.0],
            ]),
        ]
    }

    /// Brute-force reference in f64: does any polygon's triangle cross the open
    /// segment strictly inside the window (eps, 1 − eps)?
    fn reference_visible(polys: &[Vec<DVec3>], from: DVec3, to: DVec3, eps: f64) -> bool {
        let d = to - from;
        let t_eps = eps / d.length();
        let mut tris = Vec::new();
        for p in polys {
            tris.clear();
            triangulate(p, &mut tris);
            for t in &tris {
                if let Some(t) =
                    super::super::polygon::ray_triangle(from, d, p[t[0]], p[t[1]], p[t[2]])
                {
                    if t > t_eps && t < 1.0 - t_eps {
                        return false;
                    }
                }
            }
        }
        true
    }

    #[test]
    fn cornell_box_blocks_cast_shadows() {
        let polys = cornell_box();
        let occ = Occluder::new(&polys);
        assert_eq!(occ.triangle_count(), 32);
        let light = DVec3::new(278.0, 548.7, 279.5);
        // Under the short block's top (165 high, around (186, ·, 168)): blocked.
        assert!(!occ.visible(DVec3::new(186.0, 0.0, 168.0), light));
        // On top of the short block, offset off the surface: visible.
        let eps = occ.scene_epsilon();
        assert!(occ.visible(DVec3::new(186.0, 165.0 + eps, 168.0), light));
        // Behind the tall block seen from the light: blocked.
        assert!(!occ.visible(
            DVec3::new(400.0, 0.0, 500.0),
            DVec3::new(300.0, 548.7, 240.0)
        ));
        // The open floor in front of both blocks: visible.
        assert!(occ.visible(DVec3::new(450.0, 0.0, 60.0), light));
        // Through a wall: blocked (from inside the room to outside).
        assert!(!occ.visible(
            DVec3::new(278.0, 274.0, 279.0),
            DVec3::new(-100.0, 274.0, 279.0)
        ));
    }

    #[test]
    fn segment_ends_on_surfaces_are_not_self_occluded() {
        let polys = cornell_box();
        let occ = Occluder::new(&polys);
        // Exactly on the floor to exactly on the light, no offset: the floor and
        // the light are outside the parameter window.
        let light_pt = DVec3::new(250.0, 548.7, 300.0);
        assert!(occ.visible(DVec3::new(450.0, 0.0, 60.0), light_pt));
        // Exactly on the back wall to exactly on the floor, grazing-ish.
        assert!(occ.visible(
            DVec3::new(500.0, 300.0, 559.2),
            DVec3::new(540.0, 0.0, 10.0)
        ));
        // A vertex in the room's corner (on three walls) to the light.
        assert!(occ.visible(
            DVec3::new(556.0 - 0.01, 548.8 - 0.01, 559.2 - 0.01),
            light_pt
        ));
        // Floor point at the foot of the short block's side (x = 290 face), to
        // the light, away from the block: the block does not touch the ray.
        assert!(occ.visible(DVec3::new(292.0, 0.0, 140.0), light_pt));
        // The same point to a target behind the block: blocked.
        assert!(!occ.visible(
            DVec3::new(292.0, 0.0, 140.0),
            DVec3::new(100.0, 100.0, 150.0)
        ));
    }

    #[test]
    fn agrees_with_brute_force_and_count_visible_matches_visible() {
        let polys = cornell_box();
        let occ = Occluder::new(&polys);
        let eps = occ.scene_epsilon();
        let mut rng = crate::geometry::sampling::Rng::new(11, 0);
        let mut samples = Vec::new();
        let light = polys[5].clone();
        let mut disagreements = 0;
        let mut total = 0;
        for k in 0..300 {
            // A random floor point, offset off the floor.
            let from = DVec3::new(rng.next_f64() * 550.0, eps, rng.next_f64() * 559.0);
            crate::geometry::sampling::stratified_points(&light, 16, &mut rng, &mut samples);
            let mut flags = Vec::new();
            occ.visible_each(from, &samples, &mut flags);
            let loop_count = samples.iter().filter(|&&s| occ.visible(from, s)).count() as u32;
            assert_eq!(occ.count_visible(from, &samples), loop_count, "point {k}");
            assert_eq!(flags.iter().filter(|&&f| f).count() as u32, loop_count);
            for (s, f) in samples.iter().zip(&flags) {
                total += 1;
                if *f != reference_visible(&polys, from, *s, eps) {
                    disagreements += 1;
                }
            }
        }
        // Only rays passing within f32 rounding of a block's edge may differ from
        // the f64 reference (the conservative side); with random points that is
        // vanishingly rare: allow 1 in 1000.
        assert!(disagreements * 1000 <= total, "{disagreements} of {total}");
    }

    #[test]
    fn translated_scene_gives_the_same_answers() {
        let polys = cornell_box();
        let shift = DVec3::new(1e6, -1e6, 1e6);
        let moved: Vec<Vec<DVec3>> = polys
            .iter()
            .map(|p| p.iter().map(|&v| v + shift).collect())
            .collect();
        let a = Occluder::new(&polys);
        let b = Occluder::new(&moved);
        assert!((a.scene_epsilon() - b.scene_epsilon()).abs() < 1e-9 * a.scene_epsilon());
        let eps = a.scene_epsilon();
        let mut rng = crate::geometry::sampling::Rng::new(5, 5);
        let mut blocked = 0;
        for _ in 0..2000 {
            // Offset-corrected rays: from just above the floor to just below the
            // light, at random.
            let from = DVec3::new(rng.next_f64() * 550.0, eps, rng.next_f64() * 559.0);
            let to = DVec3::new(
                213.0 + rng.next_f64() * 130.0,
                548.7 - eps,
                227.0 + rng.next_f64() * 105.0,
            );
            let va = a.visible(from, to);
            assert_eq!(va, b.visible(from + shift, to + shift), "{from} -> {to}");
            blocked += usize::from(!va);
        }
        // The blocks shadow part of the floor: both outcomes were exercised.
        assert!(blocked > 100 && blocked < 1900, "blocked {blocked}");
    }

    #[test]
    fn empty_and_degenerate_scenes_block_nothing() {
        let empty: Vec<Vec<DVec3>> = Vec::new();
        let occ = Occluder::new(&empty);
        assert!(occ.visible(DVec3::ZERO, DVec3::ONE));
        assert_eq!(occ.count_visible(DVec3::ZERO, &[DVec3::ONE, DVec3::X]), 2);
        let line = vec![vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0]];
        let occ = Occluder::new(&line);
        assert_eq!(occ.triangle_count(), 0);
        assert!(occ.visible(DVec3::new(1.0, -1.0, 0.0), DVec3::new(1.0, 1.0, 0.0)));
    }

    #[test]
    fn many_triangles_build_a_valid_tree() {
        // A tessellated grid of small quads between two points: every ray
        // through it is blocked, rays beside it are not.
        let mut polys = Vec::new();
        for i in 0..40 {
            for j in 0..40 {
                let (x, y) = (i as f64, j as f64);
                polys.push(vec![
                    DVec3::new(x, y, 0.0),
                    DVec3::new(x + 1.0, y, 0.0),
                    DVec3::new(x + 1.0, y + 1.0, 0.0),
                    DVec3::new(x, y + 1.0, 0.0),
                ]);
            }
        }
        let occ = Occluder::new(&polys);
        assert_eq!(occ.triangle_count(), 3200);
        let mut rng = crate::geometry::sampling::Rng::new(2, 2);
        for _ in 0..500 {
            let x = rng.next_f64() * 40.0;
            let y = rng.next_f64() * 40.0;
            assert!(!occ.visible(DVec3::new(x, y, -1.0), DVec3::new(x, y, 1.0)));
            assert!(occ.visible(DVec3::new(x + 41.0, y, -1.0), DVec3::new(x + 41.0, y, 1.0)));
        }
        // Rays across shared edges and vertices never leak.
        for i in 1..40 {
            let p = DVec3::new(i as f64, 20.0, 0.0);
            assert!(!occ.visible(p - DVec3::new(0.3, 0.2, 1.0), p + DVec3::new(0.3, 0.2, 1.0)));
            let v = DVec3::new(i as f64, i as f64, 0.0);
            assert!(!occ.visible(v - DVec3::Z, v + DVec3::Z));
        }
    }
}
