//! Segment visibility for ray-cast form factors: an any-hit BVH over the scene's
//! input polygons (Remington 1992, §3.4: rays are tested against the input polygons, never
//! against the hundreds of mesh elements each one becomes).
//!
//! **Structure.** The polygons are triangulated and put in a 4-wide BVH
//! (binned SAH, collapsed; see [`super::bvh`]). Every query is traced as a
//! *packet* of up to 64 segments that share their origin (one receiving
//! vertex's samples of a source): the packet walks the tree once, each node's
//! four child boxes are culled for the whole packet at once by interval
//! arithmetic on the rays' inverse directions plus the packet's bounding box,
//! and only at leaves are rays tested one by one, eight at a time in SIMD lanes
//! (AVX2 when the CPU has it, chosen at run time; plain code otherwise). With a
//! shared origin the Möller–Trumbore test needs three dot products per ray per
//! triangle; everything else is computed once per triangle and packet. Rays
//! leave the packet as soon as they are blocked.
//!
//! **Precision.** The occluder stores triangles in f32 relative to the centre
//! of its own bounding box (subtracted in f64), so a scene far from the origin
//! (translated by 1e6) answers exactly like the same scene at the origin. f32
//! rounding of a vertex is then ≤ 6e-8 of the scene's half-diagonal. The
//! [`Occluder::scene_epsilon`] of 1e-5 of the diagonal, node boxes padded by
//! 1e-6 of the diagonal and barycentric tests widened by [`BARY_EPSILON`] keep
//! the tests conservative: a ray that passes within rounding of an edge counts
//! as blocked, never as leaking through a closed surface.

// Lane loops index several arrays in lockstep (directions, inverses, windows);
// written as index loops they are what the compiler turns into vector code.
#![allow(clippy::needless_range_loop)]

use super::bvh::{self, Aabb, Node4, EMPTY_SLOT, LEAF_BIT};
use super::polygon::triangulate;
use glam::DVec3;
use std::mem::MaybeUninit;

pub mod closest;
pub use closest::ClosestHit;

/// Relative size of [`Occluder::scene_epsilon`]: a fraction of the scene's
/// bounding-box diagonal.
pub const SCENE_EPSILON: f64 = 1e-5;

/// Node boxes are padded by this fraction of the diagonal, far above f32
/// rounding of the relative coordinates (≈ 6e-8 of the half-diagonal) and of
/// the slab test's products, so the f32 box tests never miss a box that a
/// triangle's hit lies in.
const BOX_PADDING: f64 = 1e-6;

/// Barycentric tolerance of the f32 triangle test (a fraction of the triangle's
/// own parametrisation): hits this close outside an edge count, so edges shared
/// by two triangles never leak through f32 rounding.
pub const BARY_EPSILON: f32 = 2e-6;

/// The most segments traced together; longer target lists are split.
pub const MAX_PACKET: usize = 64;

/// Subtrees reached by at most this many of a packet's rays are traced ray by
/// ray (chosen by measurement, see docs/benchmarks.md).
const SINGLE_RAY_THRESHOLD: u32 = 4;

/// SIMD width of the per-ray tests.
const LANES: usize = 8;
const CHUNKS: usize = MAX_PACKET / LANES;

/// A triangle prepared for the shared-origin Möller–Trumbore test, in f32
/// relative to the occluder's centre: one vertex, two edges and their cross
/// product (the unnormalised geometric normal).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
struct Triangle {
    v0: [f32; 3],
    e1: [f32; 3],
    e2: [f32; 3],
    n: [f32; 3],
}

/// An any-hit occlusion structure over a scene's polygons. `Send + Sync`:
/// build once, query from every thread.
#[derive(Clone, Debug)]
pub struct Occluder {
    centre: DVec3,
    epsilon: f64,
    nodes: Vec<Node4>,
    triangles: Vec<Triangle>,
    /// For each stored triangle, the index of the input polygon it came from.
    polygon_of: Vec<u32>,
    /// Whether the AVX2 + FMA path can run on this CPU (checked once).
    avx2: bool,
}

impl Occluder {
    /// Bytes its node, triangle and polygon tables hold (by length), for the
    /// memory estimate's test (`solve/budget/tests.rs`).
    #[cfg(test)]
    pub(crate) fn allocated_bytes(&self) -> u64 {
        (std::mem::size_of_val(self.nodes.as_slice())
            + std::mem::size_of_val(self.triangles.as_slice())
            + std::mem::size_of_val(self.polygon_of.as_slice())) as u64
    }

    /// The bytes one stored triangle costs, for the memory estimate: its
    /// [`Triangle`], its polygon index and its share of the 4-wide nodes
    /// (leaves of at most [`bvh::MAX_LEAF`] triangles, so about one node per
    /// that many; 84 bytes here, against 81.4 measured on the 10k Cornell
    /// boxes, `solve/budget/tests.rs`).
    pub fn bytes_per_triangle() -> u64 {
        (std::mem::size_of::<Triangle>()
            + std::mem::size_of::<u32>()
            + std::mem::size_of::<Node4>() / bvh::MAX_LEAF) as u64
    }

    /// Builds the occluder over `polygons` (planar, simple, counter-clockwise;
    /// convex or not). Each polygon is triangulated (fan or ear clipping);
    /// degenerate polygons and polygons with non-finite vertices contribute
    /// nothing. An empty scene gives an occluder that blocks nothing.
    pub fn new<P: AsRef<[DVec3]>>(polygons: &[P]) -> Self {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for p in polygons {
            let p = p.as_ref();
            if p.iter().all(|v| v.is_finite()) {
                for &v in p {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
        }
        if lo.x.is_nan() || lo.x > hi.x {
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
        let mut boxes = Vec::new();
        let mut tris = Vec::new();
        for (index, p) in polygons.iter().enumerate() {
            let p = p.as_ref();
            if p.iter().any(|v| !v.is_finite()) {
                continue;
            }
            tris.clear();
            triangulate(p, &mut tris);
            for t in &tris {
                let v = [p[t[0]] - centre, p[t[1]] - centre, p[t[2]] - centre];
                let v32 = v.map(to_f32);
                let e1 = sub(v32[1], v32[0]);
                let e2 = sub(v32[2], v32[0]);
                triangles.push(Triangle {
                    v0: v32[0],
                    e1,
                    e2,
                    n: cross(e1, e2),
                });
                let mut b = Aabb::EMPTY;
                v32.iter().for_each(|&x| b.grow_point(x));
                boxes.push(b);
                polygon_of.push(index as u32);
            }
        }
        let padding = (BOX_PADDING * diagonal) as f32;
        let tree = bvh::build(&boxes, padding);
        let triangles = tree.order.iter().map(|&i| triangles[i as usize]).collect();
        let polygon_of = tree.order.iter().map(|&i| polygon_of[i as usize]).collect();
        Occluder {
            centre,
            epsilon,
            nodes: tree.nodes,
            triangles,
            polygon_of,
            avx2: has_avx2(),
        }
    }

    /// Builds the occluder over a scene's polygons.
    pub fn from_polygons(polygons: &[crate::scene::Polygon]) -> Self {
        let list: Vec<&[DVec3]> = polygons.iter().map(|p| p.vertices.as_slice()).collect();
        Self::new(&list)
    }

    /// A scale-aware offset: 1e-5 of the scene's bounding-box diagonal. Start
    /// rays this far off a surface (along its normal): it is far above the
    /// occluder's f32 rounding. Segment ends closer than this to a surface are
    /// not blocked by it.
    pub fn scene_epsilon(&self) -> f64 {
        self.epsilon
    }

    /// Number of triangles the input polygons became.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The plane of stored triangle `i` in scene coordinates, as a point on it and
    /// its (unnormalised) counter-clockwise normal, widened from the stored f32.
    /// A hit refined on this plane lies on the surface that was hit, which the
    /// polygon's own (Newell) plane need not be for a slightly non-planar input
    /// polygon: the Cornell box's red wall is 0.8 mm out of plane, far more than
    /// [`Occluder::scene_epsilon`].
    pub fn triangle_plane(&self, i: usize) -> Option<(DVec3, DVec3)> {
        let t = self.triangles.get(i)?;
        let widen = |v: [f32; 3]| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64);
        Some((widen(t.v0) + self.centre, widen(t.n)))
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
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is true only when the running CPU reported AVX2
            // and FMA support (has_avx2), which is all that the target-feature
            // function requires.
            return unsafe { self.visible_one_avx2(from, to) };
        }
        self.visible_one(from, to)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn visible_one_avx2(&self, from: DVec3, to: DVec3) -> bool {
        self.visible_one(from, to)
    }

    /// The single-segment path: one ray, four child boxes tested together per
    /// node. Its arithmetic (window, triangle test) is the packet path's,
    /// operation for operation, so both give identical answers.
    #[inline(always)]
    fn visible_one(&self, from: DVec3, to: DVec3) -> bool {
        if self.nodes.is_empty() {
            return true;
        }
        let d64 = to - from;
        let d = to_f32(d64);
        let o = to_f32(from - self.centre);
        let eps = self.epsilon as f32;
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if !(len > 2.0 * eps && len < f32::INFINITY) {
            return true;
        }
        let t_eps = eps / len;
        let (t_min, t_max) = (t_eps, 1.0 - t_eps);
        let inv = d.map(|x| {
            1.0 / if x.abs() < 1e-30 {
                1e-30f32.copysign(x)
            } else {
                x
            }
        });
        !self.blocked_from(0, o, d, inv, t_min, t_max)
    }

    /// Whether one ray (origin `o`, direction `d`, inverse `inv`, window
    /// (t_min, t_max)) that enters node `start`'s box is blocked inside its
    /// subtree. Four child boxes are tested together per node.
    #[inline(always)]
    fn blocked_from(
        &self,
        start: u32,
        o: [f32; 3],
        d: [f32; 3],
        inv: [f32; 3],
        t_min: f32,
        t_max: f32,
    ) -> bool {
        let mut stack = [const { MaybeUninit::<u32>::uninit() }; 256];
        let mut top = 1;
        stack[0].write(start);
        while top > 0 {
            top -= 1;
            // SAFETY: entries below `top` were all written (push writes at
            // `top` before incrementing it), so entry `top` is initialised.
            let node = &self.nodes[unsafe { stack[top].assume_init() } as usize];
            let mut t0 = [t_min; 4];
            let mut t1 = [t_max; 4];
            for a in 0..3 {
                for k in 0..4 {
                    let ta = (node.lo[a][k] - o[a]) * inv[a];
                    let tb = (node.hi[a][k] - o[a]) * inv[a];
                    t0[k] = fmax(t0[k], fmin(ta, tb));
                    t1[k] = fmin(t1[k], fmax(ta, tb));
                }
            }
            for k in 0..4 {
                if t0[k] > t1[k] || node.child[k] == EMPTY_SLOT {
                    continue;
                }
                let child = node.child[k];
                if child & LEAF_BIT == 0 {
                    // Depth bound as in `traverse`.
                    stack[top].write(child);
                    top += 1;
                    continue;
                }
                let first = (child & !LEAF_BIT) as usize;
                for tri in &self.triangles[first..first + node.count[k] as usize] {
                    let p = triangle_terms(o, tri);
                    if hits(d[0], d[1], d[2], &p, t_min, t_max) {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// How many of the segments from `origin` to each of `targets` are
    /// unobstructed; the same answers as calling [`Occluder::visible`] for each,
    /// but traced together as packets (the fast path).
    pub fn count_visible(&self, origin: DVec3, targets: &[DVec3]) -> u32 {
        // A packet this small would be traced ray by ray from its root anyway
        // (SINGLE_RAY_THRESHOLD): skip building it (the draft preset's 4
        // samples per receiver).
        if targets.len() <= SINGLE_RAY_THRESHOLD as usize {
            return self.count_visible_single(origin, targets);
        }
        targets
            .chunks(MAX_PACKET)
            .map(|chunk| self.trace(origin, chunk).count_ones())
            .sum()
    }

    /// [`Occluder::count_visible`] for a few segments: each traced alone, with
    /// the AVX2 path chosen once for all of them.
    fn count_visible_single(&self, origin: DVec3, targets: &[DVec3]) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is true only when the running CPU reported AVX2
            // and FMA support (has_avx2), which is all that the target-feature
            // function requires.
            return unsafe { self.count_visible_single_avx2(origin, targets) };
        }
        targets
            .iter()
            .filter(|&&t| self.visible_one(origin, t))
            .count() as u32
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn count_visible_single_avx2(&self, origin: DVec3, targets: &[DVec3]) -> u32 {
        targets
            .iter()
            .filter(|&&t| self.visible_one(origin, t))
            .count() as u32
    }

    /// Per-target visibility from a shared origin into `out` (cleared first),
    /// the δ_i of Remington 1992, eq. 3.1; the same answers as [`Occluder::visible`].
    pub fn visible_each(&self, origin: DVec3, targets: &[DVec3], out: &mut Vec<bool>) {
        out.clear();
        for chunk in targets.chunks(MAX_PACKET) {
            let bits = self.trace(origin, chunk);
            out.extend((0..chunk.len()).map(|i| bits >> i & 1 == 1));
        }
    }

    /// Traces up to [`MAX_PACKET`] segments from `origin`; bit i of the result
    /// is set when segment i is unobstructed. The packet is sized to the
    /// number of targets (1, 2, 4 or 8 chunks of eight lanes).
    fn trace(&self, origin: DVec3, targets: &[DVec3]) -> u64 {
        debug_assert!(targets.len() <= MAX_PACKET);
        match targets.len().div_ceil(LANES) {
            0 => 0,
            1 => self.trace_n::<1>(origin, targets),
            2 => self.trace_n::<2>(origin, targets),
            3 | 4 => self.trace_n::<4>(origin, targets),
            _ => self.trace_n::<CHUNKS>(origin, targets),
        }
    }

    fn trace_n<const C: usize>(&self, origin: DVec3, targets: &[DVec3]) -> u64 {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is true only when the running CPU reported AVX2
            // and FMA support (has_avx2), which is all that the target-feature
            // function requires.
            return unsafe { self.trace_avx2::<C>(origin, targets) };
        }
        self.trace_impl::<C>(origin, targets)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn trace_avx2<const C: usize>(&self, origin: DVec3, targets: &[DVec3]) -> u64 {
        // The same code as the portable path, compiled with AVX2 so that the
        // eight-lane loops become single instructions.
        self.trace_impl::<C>(origin, targets)
    }

    #[inline(always)]
    fn trace_impl<const C: usize>(&self, origin: DVec3, targets: &[DVec3]) -> u64 {
        let mut packet = Packet::<C>::new(self, origin, targets);
        if packet.alive != 0 && !self.nodes.is_empty() {
            self.traverse(&mut packet);
        }
        packet.visible()
    }

    /// Walks the tree once for the whole packet, clearing `packet.alive` bits
    /// of blocked rays; stops early when every ray is blocked.
    ///
    /// Each stack entry carries the rays that entered the node's box, so a
    /// subtree is only tested against the rays that can reach it; children
    /// are first culled for the whole packet at once (cheap), then per ray.
    #[inline(always)]
    fn traverse<const C: usize>(&self, packet: &mut Packet<C>) {
        // The tree is at most ~70 binary levels deep (bvh::build: median
        // splits below depth 48), and each 4-wide level pushes at most 3 more
        // entries than it pops: 256 is ample. Left uninitialised: zeroing 4 KiB
        // per query would cost more than a short query itself.
        let mut stack = [const { MaybeUninit::<(u32, u64)>::uninit() }; 256];
        let mut top = 1;
        stack[0].write((0, packet.alive));
        while top > 0 {
            top -= 1;
            // SAFETY: entries below `top` were all written (push writes at
            // `top` before incrementing it), so entry `top` is initialised.
            let (index, mask) = unsafe { stack[top].assume_init() };
            let mask = mask & packet.alive;
            if mask == 0 {
                continue;
            }
            // Few rays left in this subtree: a packet step would cost a chunk
            // per ray, so trace them one by one from here (same arithmetic,
            // same answers).
            if mask.count_ones() <= SINGLE_RAY_THRESHOLD {
                let mut m = mask;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let (c, l) = (i / LANES, i % LANES);
                    let d = [
                        packet.dir[0][c][l],
                        packet.dir[1][c][l],
                        packet.dir[2][c][l],
                    ];
                    let inv = [
                        packet.inv[0][c][l],
                        packet.inv[1][c][l],
                        packet.inv[2][c][l],
                    ];
                    if self.blocked_from(
                        index,
                        packet.origin,
                        d,
                        inv,
                        packet.t_min[c][l],
                        packet.t_max[c][l],
                    ) {
                        packet.alive &= !(1u64 << i);
                    }
                }
                if packet.alive == 0 {
                    return;
                }
                continue;
            }
            let node = &self.nodes[index as usize];
            let (hit_mask, near) = packet.cull_children(node);
            if hit_mask == 0 {
                continue;
            }
            // Visit the children nearest the origin first: a blocker there ends
            // the rays soonest. Leaves are tested near-to-far now; inner
            // children are pushed far-to-near so the nearest is popped next.
            // One surviving child (common near the leaves) needs no sorting.
            let (order, visits) = if hit_mask.count_ones() == 1 {
                ([hit_mask.trailing_zeros() as usize, 0, 0, 0], 1)
            } else {
                (sort4(near), 4)
            };
            let mut inner = [(0u32, 0u64); 4];
            let mut inner_count = 0;
            for &k in &order[..visits] {
                if hit_mask & (1 << k) == 0 {
                    continue;
                }
                let rays = packet.rays_in_box(node, k, mask & packet.alive);
                if rays == 0 {
                    continue;
                }
                let child = node.child[k];
                if child & LEAF_BIT != 0 {
                    let first = (child & !LEAF_BIT) as usize;
                    let leaf = &self.triangles[first..first + node.count[k] as usize];
                    if packet.intersect_leaf(leaf, rays) {
                        return;
                    }
                } else {
                    inner[inner_count] = (child, rays);
                    inner_count += 1;
                }
            }
            for &entry in inner[..inner_count].iter().rev() {
                stack[top].write(entry);
                top += 1;
            }
        }
    }
}

/// Whether this CPU can run the AVX2 + FMA path.
fn has_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

fn to_f32(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

#[inline(always)]
fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline(always)]
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline(always)]
fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// min(a, b) for operands that are never NaN: a single `minps` (the standard
/// `f32::min` adds NaN handling that costs two more instructions per use in
/// the slab tests). Every use here compares finite values or ±∞ (inverse
/// directions are finite, see `Packet::new`), where both give the same result.
#[inline(always)]
fn fmin(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

/// max(a, b) for operands that are never NaN (see [`fmin`]).
#[inline(always)]
fn fmax(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

/// Eight f32 lanes; plain arrays whose element-wise loops the compiler turns
/// into vector instructions.
type F8 = [f32; LANES];

/// The bits of lanes where `cond` holds.
#[inline(always)]
fn lane_mask(cond: impl Fn(usize) -> bool) -> u64 {
    // One byte (0 or 1) per lane, gathered into the low 8 bits by one
    // multiplication: byte i (bit 8i) times 2^(56 − 7i) lands on bit 56 + i,
    // and every other product falls on a distinct bit outside 56..64, so
    // nothing carries into the result.
    let mut bytes = [0u8; LANES];
    for i in 0..LANES {
        bytes[i] = cond(i) as u8;
    }
    u64::from_le_bytes(bytes).wrapping_mul(0x0102_0408_1020_4080) >> 56
}

/// Up to 8·C segments sharing an origin, structure-of-arrays in f32 relative
/// to the occluder's centre, with the packet-wide bounds used to cull nodes.
struct Packet<const C: usize> {
    origin: [f32; 3],
    /// Direction (target − origin, so t ∈ [0, 1] spans the segment) per axis
    /// and chunk of eight rays.
    dir: [[F8; C]; 3],
    inv: [[F8; C]; 3],
    t_min: [F8; C],
    t_max: [F8; C],
    /// Rays not (yet) found blocked; bit i is ray i. Rays shorter than two
    /// epsilons start visible and are never traced.
    alive: u64,
    /// Rays that exist in this packet.
    valid: u64,
    /// Bounding box of all traced segments.
    box_lo: [f32; 3],
    box_hi: [f32; 3],
    /// Per axis: the range of the traced rays' inverse directions, meaningful
    /// when all have the same sign (`same_sign`), and that sign.
    inv_lo: [f32; 3],
    inv_hi: [f32; 3],
    same_sign: [bool; 3],
    positive: [bool; 3],
    /// Union of the rays' parameter windows.
    t_lo: f32,
    t_hi: f32,
}

impl<const C: usize> Packet<C> {
    #[inline(always)]
    fn new(occ: &Occluder, origin: DVec3, targets: &[DVec3]) -> Self {
        let o = to_f32(origin - occ.centre);
        let mut dir = [[[0.0f32; LANES]; C]; 3];
        // Differences in f64 (exact enough however far the scene is from the
        // origin), then rounded once to f32.
        for (i, &target) in targets.iter().enumerate() {
            let d = target - origin;
            let (c, l) = (i / LANES, i % LANES);
            dir[0][c][l] = d.x as f32;
            dir[1][c][l] = d.y as f32;
            dir[2][c][l] = d.z as f32;
        }
        let valid = if targets.len() >= 64 {
            u64::MAX
        } else {
            (1u64 << targets.len()) - 1
        };
        let eps = occ.epsilon as f32;
        let mut p = Packet {
            origin: o,
            dir,
            inv: [[[0.0; LANES]; C]; 3],
            t_min: [[1.0; LANES]; C],
            t_max: [[0.0; LANES]; C],
            alive: 0,
            valid,
            box_lo: o,
            box_hi: o,
            inv_lo: [f32::INFINITY; 3],
            inv_hi: [f32::NEG_INFINITY; 3],
            same_sign: [true; 3],
            positive: [true; 3],
            t_lo: 1.0,
            t_hi: 0.0,
        };
        // Everything else lane by lane, so that it vectorises: per-lane flags
        // are f32-wide selects, and the packet's sign summary comes from the
        // inverse directions' range (an inverse is never zero: |d| ≥ 1e-30
        // below, and infinite segments are not traced), so no per-lane
        // boolean accumulators are needed.
        let mut inv_lo = [[f32::INFINITY; LANES]; 3];
        let mut inv_hi = [[f32::NEG_INFINITY; LANES]; 3];
        let mut box_lo = [[f32::INFINITY; LANES]; 3];
        let mut box_hi = [[f32::NEG_INFINITY; LANES]; 3];
        let mut t_lo = [1.0f32; LANES];
        let mut t_hi = [0.0f32; LANES];
        for c in 0..C {
            let (dx, dy, dz) = (&p.dir[0][c], &p.dir[1][c], &p.dir[2][c]);
            let mut len = [0.0f32; LANES];
            for l in 0..LANES {
                len[l] = (dx[l] * dx[l] + dy[l] * dy[l] + dz[l] * dz[l]).sqrt();
            }
            // Lanes past the targets (padding) have length 0 and stay out.
            let in_chunk = targets.len().saturating_sub(c * LANES).min(LANES);
            // Too short to be blocked (or not a finite segment): visible, and
            // never traced.
            let mut on = [false; LANES];
            for l in 0..LANES {
                on[l] = l < in_chunk && len[l] > 2.0 * eps && len[l] < f32::INFINITY;
            }
            let traced = lane_mask(|l| on[l]);
            p.alive |= traced << (c * LANES);
            for l in 0..LANES {
                let t_eps = eps / len[l];
                p.t_min[c][l] = if on[l] { t_eps } else { 1.0 };
                p.t_max[c][l] = if on[l] { 1.0 - t_eps } else { 0.0 };
                t_lo[l] = fmin(t_lo[l], p.t_min[c][l]);
                t_hi[l] = fmax(t_hi[l], p.t_max[c][l]);
            }
            for a in 0..3 {
                for l in 0..LANES {
                    let d = p.dir[a][c][l];
                    // A zero component would give 0 · ∞ = NaN in the slab
                    // test; a huge finite inverse of the same sign answers
                    // the same.
                    let safe = if d.abs() < 1e-30 {
                        1e-30f32.copysign(d)
                    } else {
                        d
                    };
                    let inv = 1.0 / safe;
                    p.inv[a][c][l] = inv;
                    inv_lo[a][l] = fmin(inv_lo[a][l], if on[l] { inv } else { f32::INFINITY });
                    inv_hi[a][l] = fmax(inv_hi[a][l], if on[l] { inv } else { f32::NEG_INFINITY });
                    let end = o[a] + d;
                    box_lo[a][l] = fmin(box_lo[a][l], if on[l] { end } else { f32::INFINITY });
                    box_hi[a][l] = fmax(box_hi[a][l], if on[l] { end } else { f32::NEG_INFINITY });
                }
            }
        }
        for l in 0..LANES {
            p.t_lo = fmin(p.t_lo, t_lo[l]);
            p.t_hi = fmax(p.t_hi, t_hi[l]);
        }
        for a in 0..3 {
            for l in 0..LANES {
                p.inv_lo[a] = fmin(p.inv_lo[a], inv_lo[a][l]);
                p.inv_hi[a] = fmax(p.inv_hi[a], inv_hi[a][l]);
                p.box_lo[a] = fmin(p.box_lo[a], box_lo[a][l]);
                p.box_hi[a] = fmax(p.box_hi[a], box_hi[a][l]);
            }
            // Traced rays with a negative / non-negative inverse on this axis
            // exist exactly when the range reaches below / above zero (with
            // none traced: neither, so the axis counts as positive).
            let any_neg = p.inv_lo[a] < 0.0;
            let any_pos = p.inv_hi[a] >= 0.0;
            p.same_sign[a] = !(any_neg && any_pos);
            p.positive[a] = !any_neg;
        }
        p
    }

    /// Bits of the rays found unobstructed.
    fn visible(&self) -> u64 {
        self.valid & self.alive
    }

    /// Culls a node's four children for the whole packet: a child survives when
    /// its box overlaps the packet's bounding box and, on every axis where all
    /// rays' directions share a sign, the interval-arithmetic slab test over
    /// the rays' inverse directions leaves a non-empty parameter range.
    /// Conservative: a child that any ray enters survives. Returns the mask of
    /// surviving children and a lower bound of their entry parameter.
    #[inline(always)]
    fn cull_children(&self, node: &Node4) -> (u32, [f32; 4]) {
        let mut near = [self.t_lo; 4];
        let mut far = [self.t_hi; 4];
        let mut overlap = [true; 4];
        for a in 0..3 {
            for k in 0..4 {
                overlap[k] &= node.lo[a][k] <= self.box_hi[a] && node.hi[a][k] >= self.box_lo[a];
            }
            if !self.same_sign[a] {
                continue;
            }
            let (il, ih) = (self.inv_lo[a], self.inv_hi[a]);
            for k in 0..4 {
                let lo = node.lo[a][k] - self.origin[a];
                let hi = node.hi[a][k] - self.origin[a];
                // Positive directions enter through lo and leave through hi;
                // negative ones the other way round.
                let (entry, exit) = if self.positive[a] { (lo, hi) } else { (hi, lo) };
                near[k] = fmax(near[k], fmin(entry * il, entry * ih));
                far[k] = fmin(far[k], fmax(exit * il, exit * ih));
            }
        }
        let mut mask = 0;
        for k in 0..4 {
            if overlap[k] && near[k] <= far[k] && node.child[k] != EMPTY_SLOT {
                mask |= 1 << k;
            }
        }
        (mask, near)
    }

    /// The rays of `mask` that enter child `k`'s box within their windows
    /// (exact per-ray slab test).
    #[inline(always)]
    fn rays_in_box(&self, node: &Node4, k: usize, mask: u64) -> u64 {
        let mut rays = 0;
        let lo = [
            node.lo[0][k] - self.origin[0],
            node.lo[1][k] - self.origin[1],
            node.lo[2][k] - self.origin[2],
        ];
        let hi = [
            node.hi[0][k] - self.origin[0],
            node.hi[1][k] - self.origin[1],
            node.hi[2][k] - self.origin[2],
        ];
        for c in 0..C {
            let live = (mask >> (c * LANES)) & 0xFF;
            if live == 0 {
                continue;
            }
            let mut t0 = self.t_min[c];
            let mut t1 = self.t_max[c];
            for a in 0..3 {
                let inv = &self.inv[a][c];
                for l in 0..LANES {
                    let ta = lo[a] * inv[l];
                    let tb = hi[a] * inv[l];
                    t0[l] = fmax(t0[l], fmin(ta, tb));
                    t1[l] = fmin(t1[l], fmax(ta, tb));
                }
            }
            rays |= (lane_mask(|l| t0[l] <= t1[l]) & live) << (c * LANES);
        }
        rays
    }

    /// Tests `rays` against a leaf's triangles, clearing the blocked ones from
    /// `alive`. Returns true when no ray of the packet is left alive.
    ///
    /// Shared-origin Möller–Trumbore: with s = o − v0, q = s × e1, r = e2 × s
    /// and n = e1 × e2 (all per triangle), a ray d has det = −d·n, u·det = d·r,
    /// v·det = d·q and t·det = e2·q (the last per triangle too). The per-
    /// triangle terms are computed once; then each chunk of eight rays is
    /// tested against every triangle while its directions stay in registers.
    #[inline(always)]
    fn intersect_leaf(&mut self, leaf: &[Triangle], rays: u64) -> bool {
        let mut pre = [[0.0f32; 10]; bvh::MAX_LEAF];
        for (p, tri) in pre.iter_mut().zip(leaf) {
            let s = sub(self.origin, tri.v0);
            let q = cross(s, tri.e1);
            let r = cross(tri.e2, s);
            *p = [
                -tri.n[0],
                -tri.n[1],
                -tri.n[2],
                r[0],
                r[1],
                r[2],
                q[0],
                q[1],
                q[2],
                dot(tri.e2, q),
            ];
        }
        let pre = &pre[..leaf.len()];
        for c in 0..C {
            let live = (rays >> (c * LANES)) & 0xFF;
            if live == 0 {
                continue;
            }
            let (dx, dy, dz) = (&self.dir[0][c], &self.dir[1][c], &self.dir[2][c]);
            let (t_min, t_max) = (&self.t_min[c], &self.t_max[c]);
            let mut hit = 0;
            for p in pre {
                hit |= lane_mask(|l| hits(dx[l], dy[l], dz[l], p, t_min[l], t_max[l]));
            }
            self.alive &= !((hit & live) << (c * LANES));
        }
        self.alive == 0
    }
}

/// The per-triangle terms of the shared-origin Möller–Trumbore test for rays
/// from `origin`: −n (3), r = e2 × s (3), q = s × e1 (3) and t·det = e2·q, with
/// s = origin − v0.
#[inline(always)]
fn triangle_terms(origin: [f32; 3], tri: &Triangle) -> [f32; 10] {
    let s = sub(origin, tri.v0);
    let q = cross(s, tri.e1);
    let r = cross(tri.e2, s);
    [
        -tri.n[0],
        -tri.n[1],
        -tri.n[2],
        r[0],
        r[1],
        r[2],
        q[0],
        q[1],
        q[2],
        dot(tri.e2, q),
    ]
}

/// Whether the ray with direction (dx, dy, dz) hits the triangle whose
/// [`triangle_terms`] are `p` inside the window (t_min, t_max), with the
/// barycentric bounds widened by [`BARY_EPSILON`] (conservative).
#[inline(always)]
fn hits(dx: f32, dy: f32, dz: f32, p: &[f32; 10], t_min: f32, t_max: f32) -> bool {
    let det = dx * p[0] + dy * p[1] + dz * p[2];
    let u = dx * p[3] + dy * p[4] + dz * p[5];
    let v = dx * p[6] + dy * p[7] + dz * p[8];
    // Make det positive by flipping signs with its sign bit.
    let sign = det.to_bits() & 0x8000_0000;
    let flip = |x: f32| f32::from_bits(x.to_bits() ^ sign);
    let (a, u, v, t) = (det.abs(), flip(u), flip(v), flip(p[9]));
    let tol = BARY_EPSILON * a;
    a > 0.0 && u >= -tol && v >= -tol && u + v <= a + tol && t > t_min * a && t < t_max * a
}

/// The indices 0..4 ordered by ascending `key` (a sorting network: no
/// branches, no call).
#[inline(always)]
fn sort4(key: [f32; 4]) -> [usize; 4] {
    let mut idx = [0usize, 1, 2, 3];
    let mut k = key;
    let mut swap = |a: usize, b: usize| {
        if k[b] < k[a] {
            k.swap(a, b);
            idx.swap(a, b);
        }
    };
    swap(0, 1);
    swap(2, 3);
    swap(0, 2);
    swap(1, 3);
    swap(1, 2);
    idx
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
    fn packets_and_single_rays_agree_on_a_random_triangle_soup() {
        // 3000 random triangles in a 100-unit cube: packets of every size
        // (1..=64 rays, so every chunk count and the ray-by-ray fallback of
        // small subtrees) must give exactly the single-ray answers, and both
        // must agree with the f64 brute force except for rays within f32
        // rounding of an edge.
        let mut rng = crate::geometry::sampling::Rng::new(21, 0);
        let mut point =
            |scale: f64| DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * scale;
        let polys: Vec<Vec<DVec3>> = (0..3000)
            .map(|_| {
                let c = point(100.0);
                vec![c + point(6.0), c + point(6.0), c + point(6.0)]
            })
            .collect();
        let occ = Occluder::new(&polys);
        let eps = occ.scene_epsilon();
        let mut flags = Vec::new();
        let mut blocked = 0;
        let mut rays = 0;
        let mut disagreements = 0;
        let mut total = 0;
        for k in 0..128 {
            let origin = point(100.0);
            let targets: Vec<DVec3> = (0..(k % 64) + 1).map(|_| point(100.0)).collect();
            occ.visible_each(origin, &targets, &mut flags);
            for (t, &f) in targets.iter().zip(&flags) {
                assert_eq!(f, occ.visible(origin, *t), "ray {origin} -> {t}");
                blocked += usize::from(!f);
                rays += 1;
                // The f64 brute force is slow at the tests' opt-level: check
                // every other packet against it.
                if k % 2 == 0 {
                    total += 1;
                    if f != reference_visible(&polys, origin, *t, eps) {
                        disagreements += 1;
                    }
                }
            }
            let count = flags.iter().filter(|&&f| f).count() as u32;
            assert_eq!(occ.count_visible(origin, &targets), count);
        }
        // Both outcomes occur, and the f64 reference agrees but for rare
        // edge-grazing rays (allowance 1 in 1000).
        assert!(
            blocked > rays / 10 && blocked < rays * 9 / 10,
            "{blocked} of {rays}"
        );
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
    fn occluder_is_send_and_sync() {
        // Built once, shared by every solver thread.
        fn assert_send_sync<T: Send + Sync>() {}
        assert_send_sync::<Occluder>();
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
