//! Spatial chunks of a batch and their frustum culling.
//!
//! A batch of a large scene spans the whole scene (the solver groups triangles
//! by SH order, not by place), so a test per batch culls nothing. At upload the
//! runtime therefore partitions each batch's triangles into chunks of at most
//! [`Culling::chunk_triangles`] triangles by recursive median splits of their
//! centroids along the longest axis (a kd-tree whose leaves are stored in
//! depth-first order, so neighbouring chunks are neighbours in space and in the
//! index buffer), and reorders the batch's index buffer chunk by chunk; the
//! vertex data stays as stored. Each chunk keeps the axis-aligned box of its
//! triangles' corners.
//!
//! Each frame, every chunk is tested against the frusta of the views a pass
//! draws (one per view on the per-view path, both eyes for a multiview pass):
//! it is drawn if its box may intersect any of them. The test is conservative:
//! a box is culled only when all eight corners lie outside one clip plane
//! (beyond a margin that covers the f32 arithmetic of the GPU's clipper), and
//! then every triangle inside it lies outside that plane and is clipped away
//! whole, so no visible pixel is lost. Visible chunks that follow each other in
//! the index buffer are merged into one draw.

use glam::{DMat4, DVec3, DVec4};

/// How the renderer culls: on or off, and the chunk size it partitions
/// batches into at upload.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Culling {
    /// Test chunks against the views' frusta each frame (`--no-cull` turns it
    /// off: every chunk is drawn, which the image test compares against).
    pub enabled: bool,
    /// The most triangles per chunk (`--chunk-triangles`).
    pub chunk_triangles: u32,
}

/// The default chunk size. Measured on lavapipe (docs/benchmarks.md, "Runtime
/// at scale"): smaller chunks cull closer to the frustum but cost a draw and a
/// box test each; at 4096 a 1M-triangle batch has 256 chunks, whose test takes
/// microseconds and whose draws cost little beside the triangles they hold.
pub const DEFAULT_CHUNK_TRIANGLES: u32 = 4096;

impl Default for Culling {
    fn default() -> Self {
        Culling {
            enabled: true,
            chunk_triangles: DEFAULT_CHUNK_TRIANGLES,
        }
    }
}

/// An axis-aligned box in file coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    /// The empty box: growing it by a point gives that point.
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    pub fn grow(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
}

/// A run of whole triangles of one batch's (reordered) index buffer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chunk {
    /// First triangle of the chunk, counted from the batch's first index / 3.
    pub first_triangle: u32,
    pub triangle_count: u32,
    pub bounds: Aabb,
}

/// A batch's triangles in chunk order: `order[k]` is the stored triangle drawn
/// k-th, and the chunks cover `order` in sequence.
#[derive(Clone, Debug, Default)]
pub struct Partition {
    pub order: Vec<u32>,
    pub chunks: Vec<Chunk>,
}

/// Partitions `triangle_count` triangles, whose corner `k` (0..3) of triangle
/// `t` is `corner(t, k)`, into chunks of at most `max_triangles` (at least 1).
/// Host memory: 28 bytes per triangle while it runs (centroids and the order).
pub fn partition(
    triangle_count: u32,
    corner: impl Fn(u32, usize) -> DVec3,
    max_triangles: u32,
) -> Partition {
    let max = max_triangles.max(1) as usize;
    let centroids: Vec<[f32; 3]> = (0..triangle_count)
        .map(|t| {
            let c = (corner(t, 0) + corner(t, 1) + corner(t, 2)) / 3.0;
            c.as_vec3().to_array()
        })
        .collect();
    let mut order: Vec<u32> = (0..triangle_count).collect();
    let mut leaves = Vec::new();
    split(&mut order, 0, &centroids, max, &mut leaves);
    let chunks = leaves
        .into_iter()
        .map(|(first, count)| {
            let mut bounds = Aabb::EMPTY;
            for &t in &order[first..first + count] {
                for k in 0..3 {
                    bounds.grow(corner(t, k));
                }
            }
            Chunk {
                first_triangle: first as u32,
                triangle_count: count as u32,
                bounds,
            }
        })
        .collect();
    Partition { order, chunks }
}

/// Splits `tris` (which start at `offset` in the whole order) at the median
/// centroid along their centroids' longest axis until each part holds at most
/// `max`; pushes `(offset, len)` of each leaf in depth-first order. Each split
/// halves the count, so the depth is log₂(n / max) whatever the geometry.
fn split(
    tris: &mut [u32],
    offset: usize,
    centroids: &[[f32; 3]],
    max: usize,
    leaves: &mut Vec<(usize, usize)>,
) {
    if tris.len() <= max {
        if !tris.is_empty() {
            leaves.push((offset, tris.len()));
        }
        return;
    }
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for &t in tris.iter() {
        for a in 0..3 {
            lo[a] = lo[a].min(centroids[t as usize][a]);
            hi[a] = hi[a].max(centroids[t as usize][a]);
        }
    }
    let axis = (0..3)
        .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
        .unwrap_or(0);
    let mid = tris.len() / 2;
    tris.select_nth_unstable_by(mid, |&a, &b| {
        centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
    });
    let (left, right) = tris.split_at_mut(mid);
    split(left, offset, centroids, max, leaves);
    split(right, offset + mid, centroids, max, leaves);
}

/// The six clip planes of a Vulkan view-projection matrix (clip space
/// −w ≤ x, y ≤ w, 0 ≤ z ≤ w; `solution::camera::EyeView::projection`), as
/// world-space half-spaces `n · p + d ≥ 0` (Gribb & Hartmann 2001, "Fast
/// extraction of viewing frustum planes from the world-view-projection
/// matrix").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    planes: [DVec4; 6],
}

/// The GPU clips f32 positions transformed by an f32 matrix; each clip
/// coordinate is then within a few units of 2⁻²⁴ of the sum of its terms'
/// magnitudes. A box is culled only when it lies outside a plane by more than
/// this fraction of that sum (about 170 such units), so rounding never culls
/// a triangle the GPU would have kept.
const CLIP_MARGIN: f64 = 1e-5;

impl Frustum {
    pub fn from_view_projection(m: DMat4) -> Frustum {
        let row = |i: usize| m.row(i);
        let (r0, r1, r2, r3) = (row(0), row(1), row(2), row(3));
        Frustum {
            planes: [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2],
        }
    }

    /// Whether `bounds` may intersect the frustum: false only when the box's
    /// corner farthest inside some plane is still outside it (beyond
    /// [`CLIP_MARGIN`]). Empty or non-finite boxes are kept.
    pub fn may_intersect(&self, bounds: &Aabb) -> bool {
        if !(bounds.min.is_finite() && bounds.max.is_finite()) {
            return true;
        }
        self.planes.iter().all(|plane| {
            let n = plane.truncate();
            // The corner farthest along the plane's normal.
            let p = DVec3::select(n.cmpge(DVec3::ZERO), bounds.max, bounds.min);
            let distance = n.dot(p) + plane.w;
            let magnitude = (n * p).abs().element_sum() + plane.w.abs();
            distance >= -CLIP_MARGIN * magnitude
        })
    }
}

/// Whether a chunk may be seen by any of `frusta` (a pass draws all its views).
pub fn visible(bounds: &Aabb, frusta: &[Frustum]) -> bool {
    frusta.iter().any(|f| f.may_intersect(bounds))
}

/// What culling kept in one frame, summed over its passes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CullStats {
    pub chunks: u64,
    pub chunks_drawn: u64,
    pub triangles: u64,
    pub triangles_drawn: u64,
    /// Draw calls recorded (after merging neighbouring visible chunks).
    pub draws: u64,
}

/// Appends the triangle ranges `(first_triangle, count)` of `chunks` to draw
/// for `frusta` (all of them when `enabled` is false), merging neighbours, and
/// counts them in `stats`.
pub fn visible_ranges(
    chunks: &[Chunk],
    frusta: &[Frustum],
    enabled: bool,
    stats: &mut CullStats,
    out: &mut Vec<(u32, u32)>,
) {
    let start = out.len();
    for chunk in chunks {
        stats.chunks += 1;
        stats.triangles += u64::from(chunk.triangle_count);
        if enabled && !visible(&chunk.bounds, frusta) {
            continue;
        }
        stats.chunks_drawn += 1;
        stats.triangles_drawn += u64::from(chunk.triangle_count);
        // Ranges before `start` belong to another draw: never merged into.
        let len = out.len();
        match out.last_mut() {
            Some((first, count)) if len > start && *first + *count == chunk.first_triangle => {
                *count += chunk.triangle_count;
            }
            _ => out.push((chunk.first_triangle, chunk.triangle_count)),
        }
    }
    stats.draws += (out.len() - start) as u64;
}

#[cfg(test)]
mod tests {
    use super::*;
    use solution::camera::{clip_planes_for, Camera};

    /// A camera at the origin looking down −z with a 60° vertical field of view,
    /// square images.
    fn camera() -> Camera {
        Camera {
            eye: [0.0, 0.0, 0.0],
            target: [0.0, 0.0, -1.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 60.0,
            width: 64,
            height: 64,
        }
    }

    /// The frustum of `view` with the clip planes both renderers use for a scene
    /// of bounds ±10.
    fn frustum(view: &solution::camera::EyeView) -> Frustum {
        let (near, far) = clip_planes_for(view.position, DVec3::splat(-10.0), DVec3::splat(10.0));
        Frustum::from_view_projection(view.view_projection(near, far))
    }

    fn cube(centre: DVec3, half: f64) -> Aabb {
        Aabb {
            min: centre - DVec3::splat(half),
            max: centre + DVec3::splat(half),
        }
    }

    #[test]
    fn boxes_in_front_are_kept_and_boxes_beside_or_behind_are_culled() {
        let f = frustum(&camera().mono_view(DVec3::ZERO));
        assert!(f.may_intersect(&cube(DVec3::new(0.0, 0.0, -5.0), 0.5)));
        // Behind the eye.
        assert!(!f.may_intersect(&cube(DVec3::new(0.0, 0.0, 5.0), 0.5)));
        // Far to the side: at distance 5 the half-width is 5·tan 30° ≈ 2.89.
        assert!(!f.may_intersect(&cube(DVec3::new(4.0, 0.0, -5.0), 0.5)));
        assert!(!f.may_intersect(&cube(DVec3::new(0.0, -4.0, -5.0), 0.5)));
        // Poking into the frustum past its side: 2.5 + 0.5 > 2.89.
        assert!(f.may_intersect(&cube(DVec3::new(3.3, 0.0, -5.0), 0.5)));
        // Beyond the far plane (the far distance is about 1.01 · √300 + near).
        assert!(!f.may_intersect(&cube(DVec3::new(0.0, 0.0, -40.0), 0.5)));
    }

    #[test]
    fn a_box_straddling_the_near_plane_or_around_the_eye_is_kept() {
        let view = camera().mono_view(DVec3::ZERO);
        let f = frustum(&view);
        let (near, _) = clip_planes_for(view.position, DVec3::splat(-10.0), DVec3::splat(10.0));
        // From behind the eye to just past the near plane.
        let straddling = Aabb {
            min: DVec3::new(-0.01, -0.01, -1.5 * near),
            max: DVec3::new(0.01, 0.01, 1.0),
        };
        assert!(f.may_intersect(&straddling));
        // A wall the eye stands inside of.
        assert!(f.may_intersect(&cube(DVec3::ZERO, 0.2)));
        // Wholly between the eye and the near plane: nothing of it is drawn.
        let before_near = Aabb {
            min: DVec3::new(-0.01, -0.01, -0.5 * near),
            max: DVec3::new(0.01, 0.01, -0.25 * near),
        };
        assert!(!f.may_intersect(&before_near));
    }

    /// Every point the projection maps inside clip space lies in a kept box:
    /// points sampled over the frustum (and just outside it) are each wrapped in
    /// a tiny box, and a box is culled only if the point's clip coordinates are
    /// outside the clip volume.
    #[test]
    fn culling_agrees_with_the_projection_point_by_point() {
        let view = camera().mono_view(DVec3::ZERO);
        let (near, far) = clip_planes_for(view.position, DVec3::splat(-10.0), DVec3::splat(10.0));
        let m = view.view_projection(near, far);
        let f = Frustum::from_view_projection(m);
        for i in 0..21 {
            for j in 0..21 {
                for k in 0..12 {
                    let p = DVec3::new(
                        (i as f64 - 10.0) * 0.9,
                        (j as f64 - 10.0) * 0.9,
                        -(k as f64) * 3.0 + 1.0,
                    );
                    let clip = m * p.extend(1.0);
                    let inside = clip.x.abs() <= clip.w
                        && clip.y.abs() <= clip.w
                        && clip.z >= 0.0
                        && clip.z <= clip.w;
                    let kept = f.may_intersect(&cube(p, 1e-9));
                    if inside {
                        assert!(kept, "{p} is inside the frustum but was culled");
                    }
                    // Points clearly outside (beyond 1% of w) are culled.
                    let margin = 0.01 * clip.w.abs();
                    if clip.x.abs() > clip.w + margin || clip.z < -margin || clip.w < 0.0 {
                        assert!(!kept, "{p} is outside the frustum but was kept");
                    }
                }
            }
        }
    }

    /// A box seen by the right eye only: a multiview pass (both frusta) draws
    /// it, the left eye's own pass culls it.
    #[test]
    fn the_stereo_pair_keeps_what_either_eye_sees() {
        let ipd = 1.0;
        let [left, right] = camera().stereo_views(ipd, DVec3::ZERO);
        let (fl, fr) = (frustum(&left), frustum(&right));
        // At distance 1 the right eye (x = 0.5) sees x up to 0.5 + tan 30° ≈
        // 1.077, the left eye up to 0.077.
        let b = cube(DVec3::new(0.8, 0.0, -1.0), 0.1);
        assert!(!fl.may_intersect(&b));
        assert!(fr.may_intersect(&b));
        assert!(visible(&b, &[fl, fr]));
        assert!(!visible(&b, &[fl]));
    }

    #[test]
    fn empty_or_non_finite_boxes_are_kept() {
        let f = frustum(&camera().mono_view(DVec3::ZERO));
        assert!(f.may_intersect(&Aabb::EMPTY));
        let nan = Aabb {
            min: DVec3::splat(f64::NAN),
            max: DVec3::ZERO,
        };
        assert!(f.may_intersect(&nan));
    }

    /// A grid of n × n unit squares (two triangles each) in the z = 0 plane.
    fn grid(n: u32) -> impl Fn(u32, usize) -> DVec3 {
        move |t, k| {
            let (cell, upper) = (t / 2, t % 2 == 1);
            let (x, y) = (f64::from(cell % n), f64::from(cell / n));
            let corners = if upper {
                [(0.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            } else {
                [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0)]
            };
            DVec3::new(x + corners[k].0, y + corners[k].1, 0.0)
        }
    }

    #[test]
    fn the_partition_covers_every_triangle_once_in_bounded_chunks() {
        let n = 37;
        let corner = grid(n);
        let count = 2 * n * n;
        let p = partition(count, &corner, 100);
        let mut seen = vec![false; count as usize];
        for &t in &p.order {
            assert!(!std::mem::replace(&mut seen[t as usize], true), "{t} twice");
        }
        assert!(seen.iter().all(|&s| s));
        let mut next = 0;
        for chunk in &p.chunks {
            assert_eq!(chunk.first_triangle, next);
            assert!(chunk.triangle_count >= 1 && chunk.triangle_count <= 100);
            next += chunk.triangle_count;
            // Every corner of every triangle of the chunk lies in its box.
            for &t in &p.order[chunk.first_triangle as usize..next as usize] {
                for k in 0..3 {
                    let c = corner(t, k);
                    assert!(c.cmpge(chunk.bounds.min).all() && c.cmple(chunk.bounds.max).all());
                }
            }
        }
        assert_eq!(next, count);
        // Median splits of 2738 triangles down to ≤ 100: 2⁵ = 32 leaves.
        assert_eq!(p.chunks.len(), 32);
        // Chunks are compact: each box is far smaller than the grid.
        for chunk in &p.chunks {
            let size = chunk.bounds.max - chunk.bounds.min;
            assert!(size.x * size.y < 0.1 * f64::from(n * n), "{size}");
        }
    }

    #[test]
    fn visible_neighbours_merge_into_one_draw() {
        let chunk = |first, count, x: f64| Chunk {
            first_triangle: first,
            triangle_count: count,
            bounds: cube(DVec3::new(x, 0.0, -5.0), 0.5),
        };
        // Visible, visible, culled (beside the frustum), visible.
        let chunks = [
            chunk(0, 10, 0.0),
            chunk(10, 5, 1.0),
            chunk(15, 7, 50.0),
            chunk(22, 3, -1.0),
        ];
        let f = frustum(&camera().mono_view(DVec3::ZERO));
        let mut stats = CullStats::default();
        let mut out = Vec::new();
        visible_ranges(&chunks, &[f], true, &mut stats, &mut out);
        assert_eq!(out, vec![(0, 15), (22, 3)]);
        assert_eq!(stats.triangles_drawn, 18);
        assert_eq!(stats.chunks_drawn, 3);
        assert_eq!(stats.draws, 2);
        out.clear();
        visible_ranges(&chunks, &[f], false, &mut stats, &mut out);
        assert_eq!(out, vec![(0, 25)]);
    }
}
