//! Bounded shooting (`--shooting bounded`): a shot visits ray by ray only the
//! receivers it can still change visibly.
//!
//! Receiver clusters are the surfaces (input polygons) under a bounding-volume
//! hierarchy built once per mesh. A surface's box is its polygon's, so it
//! bounds every vertex refinement will ever add to it and never needs a refit,
//! and its normal is exact (one facet normal per surface). For each shot the
//! tree is walked from the root:
//!
//! * a node entirely behind the source's plane receives exactly nothing (the
//!   margin is the shooter's own cull, so the shooter would give every vertex
//!   0 too);
//! * a surface that faces away from every source corner, or is the source's own
//!   surface, or is black, receives exactly nothing;
//! * a node whose bound ΔL_max = F_max · max_c(Kd_c · U_c) is below the shot's
//!   tolerance τ is *bounded*: none of its vertices is visited. Each of its
//!   surfaces gets one estimate, the exact unoccluded factor at the surface's
//!   centroid times the visible fraction of the shot's pooled rays from there,
//!   and every vertex of the surface receives that ΔL, uniform, with no rays;
//! * every other surface is visited vertex by vertex, exactly as the flat
//!   shooter does.
//!
//! ## Why a uniform deposit (option (a) of issue 13), and what it costs
//!
//! A bounded surface's energy is not dropped: its vertices get the ΔL above,
//! which enters their radiance and, by the ordinary gather, their patches'
//! unshot radiance, so the power is reshot and the energy bookkeeping is the
//! flat solver's (test `bounded_shooting_loses_no_energy`). Any value in
//! [0, ΔL_max] would keep each vertex within τ of its flat value for this
//! shot; the centroid's visible factor is the one-point estimate of the
//! surface's mean. Deferring the deposit at tree nodes (option (b)) would make
//! the shot O(visited nodes); it is not done because a per-vertex add of a
//! known ΔL (a few nanoseconds, and only over the bounded surfaces' own
//! vertices, `footprint.rs`) is not what limits the slope, while the form
//! factor and rays per visited vertex (microseconds) are. The step's other
//! passes (the gather into patches, the ambient term, the source choice,
//! refinement's candidate scan) visit only the surfaces the shot touched or
//! the patches it changed (`footprint.rs`, `unshot_tree.rs`);
//! docs/lab/bounded-shooting.md, "Bounded shooting", has the measured split.
//!
//! The deposit goes in after refinement has run on the visited surfaces, so a
//! bounded surface is not scanned for splits by a shot that changed it by a
//! uniform amount below τ.

use super::shoot::{SamplePool, Shot};
use crate::geometry::polygon::bounding_sphere;
use crate::mesh::Mesh;
use crate::settings::FormFactorMethod;
use glam::DVec3;
use std::f64::consts::PI;

/// The receiver tree: surfaces under a binary bounding-volume hierarchy.
pub struct ReceiverTree {
    nodes: Vec<Node>,
    /// Surfaces in tree order: node `n` covers `order[n.start..n.end]`.
    order: Vec<u32>,
    /// Per surface: its polygon's box, normal and centroid.
    surfaces: Vec<SurfaceBounds>,
}

struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Brightest reflectance channel of any surface below.
    kd_max: f64,
    start: u32,
    end: u32,
    /// Children (`left`, `left + 1`), or `u32::MAX` for a leaf.
    left: u32,
}

struct SurfaceBounds {
    lo: DVec3,
    hi: DVec3,
    normal: DVec3,
    centroid: DVec3,
}

/// What one surface gets from one shot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Receipt {
    /// Exactly nothing (behind the source, facing away, the source's own
    /// surface, or black).
    Nothing,
    /// Every vertex is visited with the flat shooter's form factor and rays.
    Visit,
    /// Every vertex receives this ΔL (RGB radiance) without being visited.
    Uniform(DVec3),
}

/// One shot's receipts per surface, and what the plan cost.
pub struct Plan {
    pub receipts: Vec<Receipt>,
    /// Rays traced for the bounded surfaces' centroid estimates.
    pub rays: u64,
}

/// What the tree needs of the source: its corners, plane, box and bounding sphere.
pub struct SourceBounds<'a> {
    pub corners: &'a [DVec3],
    pub normal: DVec3,
    /// Vertex average: the shooter's plane test is taken from here.
    pub centre: DVec3,
    pub area: f64,
    pub diameter: f64,
    lo: DVec3,
    hi: DVec3,
    radius: f64,
}

impl<'a> SourceBounds<'a> {
    pub fn new(corners: &'a [DVec3], normal: DVec3, area: f64) -> SourceBounds<'a> {
        let (centre, radius) = bounding_sphere(corners);
        let lo = corners.iter().copied().fold(DVec3::INFINITY, DVec3::min);
        let hi = corners
            .iter()
            .copied()
            .fold(DVec3::NEG_INFINITY, DVec3::max);
        let diameter = corners
            .iter()
            .flat_map(|a| corners.iter().map(move |b| (*a - *b).length()))
            .fold(0.0, f64::max);
        SourceBounds {
            corners,
            normal,
            centre,
            area,
            diameter,
            lo,
            hi,
            radius,
        }
    }

    fn of_shot(shot: &'a Shot) -> SourceBounds<'a> {
        let mut s = SourceBounds::new(shot.polygon(), shot.normal, shot.area);
        // The shooter's own plane test uses the shot's centre and diameter;
        // take them from the shot so the culls agree to the bit.
        s.centre = shot.centre;
        s.diameter = shot.diameter;
        s
    }

    /// H: the greatest height n_s · (x − c_s) of a point x of the box [lo, hi]
    /// above the source's plane.
    fn max_height(&self, lo: DVec3, hi: DVec3) -> f64 {
        max_over_box(self.normal, lo, hi) - self.normal.dot(self.centre)
    }

    /// Whether every point of the box is behind the source by more than the
    /// shooter's margin (1e-6 of the source's diameter), where the shooter
    /// returns 0 for every receiving point.
    fn box_behind(&self, lo: DVec3, hi: DVec3) -> bool {
        self.max_height(lo, hi) < -1e-6 * self.diameter
    }
}

/// max over the box [lo, hi] of n · x (a linear function peaks at a corner,
/// taken per axis).
fn max_over_box(n: DVec3, lo: DVec3, hi: DVec3) -> f64 {
    (n * lo).max(n * hi).element_sum()
}

/// The most cells a side of [`ReceiverTree::most_patches_near`]'s grid: a
/// cubic room at a quarter of the group radius (0.2 of the diagonal) needs 12.
const CANDIDATE_GRID: usize = 16;

/// The distance from the box [lo, hi] to the point p (0 inside).
fn box_point_distance(lo: DVec3, hi: DVec3, p: DVec3) -> f64 {
    (lo - p).max(p - hi).max(DVec3::ZERO).length()
}

/// The distance between two boxes (0 when they overlap).
fn box_box_distance(lo: DVec3, hi: DVec3, lo2: DVec3, hi2: DVec3) -> f64 {
    (lo - hi2).max(lo2 - hi).max(DVec3::ZERO).length()
}

/// A conservative upper bound on the unoccluded point-to-polygon form factor
/// F(x, n) (the exact factor of `geometry::formfactor::point_to_polygon`) over
/// every point x of the box [lo, hi], for any receiver normal n, or for the
/// one normal `receiver_normal` when it is given.
///
/// Proof. F(x, n) = (1/π) ∫_P cos θ_x cos θ_y / r² dA_y over the part of the
/// source P in front of x's tangent plane, with r = |y − x| (Lambert; Cohen
/// and Wallace 1993, §4.3). For y on the source's plane, cos θ_y = h(x)/r with
/// h(x) = n_s · (x − c_s) the height of x above the plane, the same for every
/// y; F = 0 for h < 0. Let d ≤ r for every x in the box and y in P (a lower
/// bound on their distance), H ≥ h(x) the greatest height over the box, and,
/// for a known n, G ≥ n · (y − x) the greatest over corners y and box points x
/// (linear in both, so its maximum is at a source corner and a box corner),
/// so cos θ_x ≤ min(1, G/r). Then, for h(x) ≥ 0, each of
///
///   cos θ_x cos θ_y / r² ≤ 1/d², H/d³, G/d³, G·H/d⁴
///
/// holds pointwise, and integrating over P (area A) bounds F by A/π times the
/// smallest; F ≤ 1 for any point. The distance bound d is the largest of three
/// lower bounds of r: the distance between the box and the source's box (P
/// lies in it), the distance from the box to the source's vertex average less
/// the source's radius about it, and the box's least height above the plane
/// (r ≥ h(x) for y on the plane). Near the plane the exact factor returns the
/// limit from the front, which is 0 for a point off the polygon (d > 0) and
/// covered by F ≤ 1 on it (d = 0). Checked against the exact factor at random
/// points by `bound_holds_at_random_points`.
pub fn form_factor_bound(
    source: &SourceBounds,
    lo: DVec3,
    hi: DVec3,
    receiver_normal: Option<DVec3>,
) -> f64 {
    if source.box_behind(lo, hi) {
        return 0.0;
    }
    // Points behind the plane receive 0; those within the margin are bounded
    // with their height taken as 0 (the limit from the front, see above).
    let height = source.max_height(lo, hi).max(0.0);
    let least_height = -max_over_box(-source.normal, lo, hi) - source.normal.dot(source.centre);
    let d = box_box_distance(lo, hi, source.lo, source.hi)
        .max(box_point_distance(lo, hi, source.centre) - source.radius)
        .max(least_height);
    if d.is_nan() || d <= 0.0 {
        return 1.0;
    }
    let mut per_area = (1.0 / (d * d)).min(height / (d * d * d));
    if let Some(n) = receiver_normal {
        let reach = source
            .corners
            .iter()
            .map(|&c| n.dot(c))
            .fold(f64::NEG_INFINITY, f64::max)
            + max_over_box(-n, lo, hi);
        if reach <= 0.0 {
            return 0.0;
        }
        per_area = per_area
            .min(reach / (d * d * d))
            .min(reach * height / (d * d * d * d));
    }
    (source.area * per_area / PI).min(1.0)
}

impl ReceiverTree {
    /// The bytes one surface costs, for the memory estimate: its bounds, its
    /// slot in the order and two nodes (a binary tree over n leaves has
    /// 2n − 1).
    pub fn bytes_per_surface() -> u64 {
        (std::mem::size_of::<SurfaceBounds>()
            + std::mem::size_of::<u32>()
            + 2 * std::mem::size_of::<Node>()) as u64
    }

    /// Bytes its node, order and surface tables hold (by length), for the
    /// memory estimate's test (`budget/tests.rs`).
    #[cfg(test)]
    pub(crate) fn allocated_bytes(&self) -> u64 {
        (std::mem::size_of_val(self.nodes.as_slice())
            + std::mem::size_of_val(self.order.as_slice())
            + std::mem::size_of_val(self.surfaces.as_slice())) as u64
    }

    /// The tree over the surfaces of `mesh`, with reflectances `kd`.
    pub fn new(mesh: &Mesh, kd: &[DVec3]) -> ReceiverTree {
        let surfaces: Vec<SurfaceBounds> = mesh
            .surfaces
            .iter()
            .map(|s| SurfaceBounds {
                lo: s.vertices.iter().copied().fold(DVec3::INFINITY, DVec3::min),
                hi: s
                    .vertices
                    .iter()
                    .copied()
                    .fold(DVec3::NEG_INFINITY, DVec3::max),
                normal: s.normal,
                centroid: polygon_centroid(&s.vertices, s.normal),
            })
            .collect();
        let mut tree = ReceiverTree {
            nodes: Vec::with_capacity(2 * surfaces.len()),
            order: (0..surfaces.len() as u32).collect(),
            surfaces,
        };
        if !tree.order.is_empty() {
            tree.nodes
                .push(tree.make_node(0, tree.order.len() as u32, kd));
            tree.split(0, kd);
        }
        tree
    }

    fn make_node(&self, start: u32, end: u32, kd: &[DVec3]) -> Node {
        let mut node = Node {
            lo: DVec3::INFINITY,
            hi: DVec3::NEG_INFINITY,
            kd_max: 0.0,
            start,
            end,
            left: u32::MAX,
        };
        for &s in &self.order[start as usize..end as usize] {
            let b = &self.surfaces[s as usize];
            node.lo = node.lo.min(b.lo);
            node.hi = node.hi.max(b.hi);
            node.kd_max = node.kd_max.max(kd[s as usize].max_element());
        }
        node
    }

    /// Splits node `n` (and its children) at the median centroid along the
    /// longest axis of its box, down to one surface per leaf. Iterative, so a
    /// degenerate scene cannot overflow the stack.
    fn split(&mut self, root: u32, kd: &[DVec3]) {
        let mut stack = vec![root];
        while let Some(n) = stack.pop() {
            let (start, end, lo, hi) = {
                let node = &self.nodes[n as usize];
                (node.start, node.end, node.lo, node.hi)
            };
            if end - start <= 1 {
                continue;
            }
            let extent = hi - lo;
            let axis = if extent.x >= extent.y && extent.x >= extent.z {
                0
            } else if extent.y >= extent.z {
                1
            } else {
                2
            };
            let mid = (start + end) / 2;
            let surfaces = &self.surfaces;
            self.order[start as usize..end as usize].select_nth_unstable_by(
                (mid - start) as usize,
                |&a, &b| {
                    let (ca, cb) = (
                        surfaces[a as usize].centroid[axis],
                        surfaces[b as usize].centroid[axis],
                    );
                    ca.total_cmp(&cb).then(a.cmp(&b))
                },
            );
            let left = self.nodes.len() as u32;
            let (l, r) = (self.make_node(start, mid, kd), self.make_node(mid, end, kd));
            self.nodes.push(l);
            self.nodes.push(r);
            self.nodes[n as usize].left = left;
            stack.push(left);
            stack.push(left + 1);
        }
    }

    /// The surfaces whose polygon's box comes within `radius` of `centre`,
    /// appended to `out` in tree order (grouped shooters, `group_shot.rs`).
    pub(super) fn surfaces_near(&self, centre: DVec3, radius: f64, out: &mut Vec<u32>) {
        let mut stack = if self.nodes.is_empty() {
            vec![]
        } else {
            vec![0u32]
        };
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            if box_point_distance(node.lo, node.hi, centre) > radius {
                continue;
            }
            if node.left != u32::MAX {
                stack.push(node.left + 1);
                stack.push(node.left);
                continue;
            }
            for &s in &self.order[node.start as usize..node.end as usize] {
                let b = &self.surfaces[s as usize];
                if box_point_distance(b.lo, b.hi, centre) <= radius {
                    out.push(s);
                }
            }
        }
    }

    /// An upper bound on the patches one grouped shot can rank: the most
    /// patches (`patches`, per surface) on surfaces whose box comes within
    /// `radius` of any one point, as [`ReceiverTree::surfaces_near`] tests.
    /// Counted on a grid of cells a quarter of `radius` wide (at most
    /// [`CANDIDATE_GRID`] a side): each surface is charged to every cell whose
    /// box comes within `radius` of its box, so every candidate of a seed is
    /// charged to the cell holding the seed's centre, and the fullest cell
    /// bounds them all. The grid's cells make it loose by about a cell's width
    /// on the radius. Every patch when `radius` is not positive.
    pub(super) fn most_patches_near(&self, radius: f64, patches: &[u64]) -> u64 {
        let total: u64 = patches.iter().sum();
        let Some(root) = self.nodes.first() else {
            return total;
        };
        if !(radius > 0.0 && radius.is_finite()) {
            return total;
        }
        let extent = root.hi - root.lo;
        let dims = extent
            .to_array()
            .map(|e| ((4.0 * e / radius).ceil() as usize).clamp(1, CANDIDATE_GRID));
        let size = DVec3::from_array(std::array::from_fn(|a| extent[a] / dims[a] as f64));
        let cell = |axis: usize, x: f64| {
            let k = if size[axis] > 0.0 {
                ((x - root.lo[axis]) / size[axis]).floor()
            } else {
                0.0
            };
            (k.max(0.0) as usize).min(dims[axis] - 1)
        };
        let mut counts = vec![0u64; dims[0] * dims[1] * dims[2]];
        for (s, b) in self.surfaces.iter().enumerate() {
            let n = patches.get(s).copied().unwrap_or(0);
            if n == 0 {
                continue;
            }
            let (lo, hi) = (b.lo - DVec3::splat(radius), b.hi + DVec3::splat(radius));
            for i in cell(0, lo.x)..=cell(0, hi.x) {
                for j in cell(1, lo.y)..=cell(1, hi.y) {
                    for k in cell(2, lo.z)..=cell(2, hi.z) {
                        let low = root.lo + size * DVec3::new(i as f64, j as f64, k as f64);
                        if box_box_distance(low, low + size, b.lo, b.hi) <= radius {
                            counts[(i * dims[1] + j) * dims[2] + k] += n;
                        }
                    }
                }
            }
        }
        counts.into_iter().max().unwrap_or(0).min(total)
    }

    /// The scene's diagonal: the length of the root's box (0 when empty).
    pub(super) fn diagonal(&self) -> f64 {
        self.nodes.first().map_or(0.0, |n| (n.hi - n.lo).length())
    }

    /// The receipts of every surface from `shot`, whose bounded receivers get
    /// less than `tolerance` (radiance, brightest channel) each.
    pub fn plan(&self, shot: &Shot, pool: &SamplePool, tolerance: f64) -> Plan {
        let mut plan = Plan {
            receipts: vec![Receipt::Nothing; self.surfaces.len()],
            rays: 0,
        };
        if self.nodes.is_empty() {
            return plan;
        }
        let source = SourceBounds::of_shot(shot);
        let brightest = shot.unshot.max_element();
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            if source.box_behind(node.lo, node.hi) {
                continue;
            }
            let bounded =
                form_factor_bound(&source, node.lo, node.hi, None) * brightest * node.kd_max
                    < tolerance;
            if node.left != u32::MAX && !bounded {
                stack.push(node.left);
                stack.push(node.left + 1);
                continue;
            }
            for &s in &self.order[node.start as usize..node.end as usize] {
                let receipt = self.receipt(shot, pool, &source, s, tolerance, bounded);
                if let Receipt::Uniform(_) = receipt {
                    plan.rays += shot.samples as u64 * shot.shadows as u64;
                }
                plan.receipts[s as usize] = receipt;
            }
        }
        plan
    }

    /// One surface's receipt (see the module documentation); `bounded` when
    /// its node's bound is already below the tolerance.
    fn receipt(
        &self,
        shot: &Shot,
        pool: &SamplePool,
        source: &SourceBounds,
        s: u32,
        tolerance: f64,
        bounded: bool,
    ) -> Receipt {
        let b = &self.surfaces[s as usize];
        let kd = shot.kd[s as usize];
        if s == shot.source_surface || kd == DVec3::ZERO || source.box_behind(b.lo, b.hi) {
            return Receipt::Nothing;
        }
        // The shooter gives every receiving point of a surface facing away
        // from every source corner exactly 0 (`Shot::form_factor`'s cull).
        let facing = source
            .corners
            .iter()
            .map(|&c| b.normal.dot(c))
            .fold(f64::NEG_INFINITY, f64::max)
            + max_over_box(-b.normal, b.lo, b.hi);
        if facing <= 0.0 {
            return Receipt::Nothing;
        }
        let bound = form_factor_bound(source, b.lo, b.hi, Some(b.normal));
        let bounded = bounded || bound * (kd * shot.unshot).max_element() < tolerance;
        // The centroid estimate takes the pooled set, so the whole source must
        // be above the centroid's horizon; the shooter's other methods have
        // their own visibility, so they are visited as the flat shooter does.
        let q = b.centroid;
        if !bounded
            || shot.method != FormFactorMethod::Analytic
            || !shot.source_above_horizon(q, b.normal)
        {
            return Receipt::Visit;
        }
        let unoccluded = shot.source.form_factor(q, b.normal);
        if unoccluded.is_nan() || unoccluded <= 0.0 {
            return Receipt::Nothing;
        }
        let fraction = if shot.shadows {
            let origin = q + b.normal * shot.occluder.scene_epsilon();
            // A stream id above every vertex id's use in practice; which of
            // the pool's sets it names depends only on (seed, shot, surface).
            let (_, targets) = pool.set_for(shot, u32::MAX - s);
            shot.occluder.count_visible(origin, targets) as f64 / shot.samples.max(1) as f64
        } else {
            1.0
        };
        Receipt::Uniform(kd * shot.unshot * (unoccluded * fraction))
    }
}

impl super::Solver {
    /// This shot's plan under bounded shooting (`None` when flat): the
    /// tolerance is `shooting_tolerance` × the scene's radiance level (the
    /// brightest channel of the ambient term before any shot), so it scales
    /// with the scene's light, not with the shot.
    pub(super) fn plan_receivers(&self, shot: &Shot, pool: &SamplePool) -> Option<Plan> {
        if self.settings.shooting != crate::settings::Shooting::Bounded {
            return None;
        }
        let tolerance = self.settings.shooting_tolerance * self.radiance_level;
        Some(self.receivers.plan(shot, pool, tolerance))
    }
}

/// The area centroid of a planar convex polygon (its fan's triangle centroids
/// weighted by area); the vertex average when the area vanishes.
pub(super) fn polygon_centroid(vertices: &[DVec3], normal: DVec3) -> DVec3 {
    let average = vertices.iter().copied().sum::<DVec3>() / vertices.len().max(1) as f64;
    let mut sum = DVec3::ZERO;
    let mut area = 0.0;
    for k in 1..vertices.len().saturating_sub(1) {
        let (a, b, c) = (vertices[0], vertices[k], vertices[k + 1]);
        let w = (b - a).cross(c - a).dot(normal) * 0.5;
        sum += (a + b + c) / 3.0 * w;
        area += w;
    }
    if area > 0.0 && sum.is_finite() {
        sum / area
    } else {
        average
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::formfactor::point_to_polygon;
    use crate::geometry::sampling::Rng;

    fn uniform(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * rng.next_f64()
    }

    fn unit(rng: &mut Rng) -> DVec3 {
        loop {
            let v = DVec3::new(
                uniform(rng, -1.0, 1.0),
                uniform(rng, -1.0, 1.0),
                uniform(rng, -1.0, 1.0),
            );
            let l = v.length();
            if l > 1e-3 && l <= 1.0 {
                return v / l;
            }
        }
    }

    /// A random convex source: a rectangle or a triangle of random size,
    /// placement and orientation, counter-clockwise about its normal.
    fn random_source(rng: &mut Rng) -> (Vec<DVec3>, DVec3) {
        let n = unit(rng);
        let t = n.any_orthonormal_vector();
        let b = n.cross(t);
        let centre = DVec3::new(
            uniform(rng, -2.0, 2.0),
            uniform(rng, -2.0, 2.0),
            uniform(rng, -2.0, 2.0),
        );
        let (w, h) = (uniform(rng, 0.05, 2.0), uniform(rng, 0.05, 2.0));
        let corners = if rng.next_u32().is_multiple_of(2) {
            vec![
                centre - t * w - b * h,
                centre + t * w - b * h,
                centre + t * w + b * h,
                centre - t * w + b * h,
            ]
        } else {
            vec![
                centre - t * w - b * h,
                centre + t * w - b * h,
                centre + b * h,
            ]
        };
        (corners, n)
    }

    fn area(corners: &[DVec3], n: DVec3) -> f64 {
        (1..corners.len() - 1)
            .map(|k| {
                (corners[k] - corners[0])
                    .cross(corners[k + 1] - corners[0])
                    .dot(n)
                    * 0.5
            })
            .sum()
    }

    /// The bound is an upper bound: at 2,000 random (source, box) pairs and 64
    /// random points and normals in each box (a quarter of the boxes touching
    /// or straddling the source, so the F ≤ 1 and on-plane cases are met), the
    /// exact factor never exceeds it. The slack, 1e-12, is the exact factor's
    /// own rounding (formfactor.rs: about 1e-12 absolute in general position).
    /// A second pass with the box's one normal checks the bound with the
    /// receiver's cosine.
    #[test]
    fn bound_holds_at_random_points() {
        let mut rng = Rng::new(7, 13);
        let mut tight = 0usize;
        for case in 0..2000 {
            let (corners, n_s) = random_source(&mut rng);
            let source = SourceBounds::new(&corners, n_s, area(&corners, n_s));
            let reach = if case % 4 == 0 { 1.0 } else { 6.0 };
            let centre = source.centre
                + unit(&mut rng) * uniform(&mut rng, 0.0, reach)
                + n_s * uniform(&mut rng, -0.5, 2.0);
            let half = DVec3::new(
                uniform(&mut rng, 0.0, 1.0),
                uniform(&mut rng, 0.0, 1.0),
                uniform(&mut rng, 0.0, 1.0),
            );
            let (lo, hi) = (centre - half, centre + half);
            let fixed = unit(&mut rng);
            let any = form_factor_bound(&source, lo, hi, None);
            let with_normal = form_factor_bound(&source, lo, hi, Some(fixed));
            assert!(with_normal <= any + 1e-15);
            let mut worst: f64 = 0.0;
            for _ in 0..64 {
                let p = DVec3::new(
                    uniform(&mut rng, lo.x, hi.x),
                    uniform(&mut rng, lo.y, hi.y),
                    uniform(&mut rng, lo.z, hi.z),
                );
                let f = point_to_polygon(p, unit(&mut rng), &corners);
                assert!(
                    f <= any + 1e-12,
                    "case {case}: F = {f} > bound {any} at {p}"
                );
                let f = point_to_polygon(p, fixed, &corners);
                assert!(
                    f <= with_normal + 1e-12,
                    "case {case}: F = {f} > bound {with_normal} at {p} (normal {fixed})"
                );
                worst = worst.max(f);
            }
            if any < 1.0 && worst > 0.1 * any {
                tight += 1;
            }
        }
        // Not vacuous: in many cases some sampled point comes within a factor
        // of ten of the bound (a bound of 1 everywhere would pass the asserts).
        assert!(tight > 200, "only {tight} cases came near their bound");
    }

    /// A box wholly behind a source's plane gets an exact zero; one in front
    /// whose one normal faces away from every corner gets zero too; and the
    /// bound falls like A/(π d²) far away.
    #[test]
    fn culls_and_far_field() {
        let corners = vec![
            DVec3::new(-0.5, 0.0, -0.5),
            DVec3::new(-0.5, 0.0, 0.5),
            DVec3::new(0.5, 0.0, 0.5),
            DVec3::new(0.5, 0.0, -0.5),
        ];
        let n = DVec3::Y;
        let source = SourceBounds::new(&corners, n, 1.0);
        let below = (DVec3::new(-1.0, -3.0, -1.0), DVec3::new(1.0, -1.0, 1.0));
        assert_eq!(form_factor_bound(&source, below.0, below.1, None), 0.0);
        assert!(source.box_behind(below.0, below.1));
        let above = (DVec3::new(-0.1, 2.0, -0.1), DVec3::new(0.1, 2.2, 0.1));
        assert_eq!(
            form_factor_bound(&source, above.0, above.1, Some(DVec3::Y)),
            0.0
        );
        let far = (DVec3::new(-0.1, 100.0, -0.1), DVec3::new(0.1, 100.2, 0.1));
        let bound = form_factor_bound(&source, far.0, far.1, None);
        let exact = point_to_polygon(DVec3::new(0.0, 100.0, 0.0), -DVec3::Y, &corners);
        // Within 0.5% of the on-axis factor at distance 100 (the box's 0.1
        // half-width and the bound's 1/d² against the exact 1/(d² + a²)).
        assert!(
            bound >= exact && bound < exact * 1.005,
            "{bound} vs {exact}"
        );
    }

    #[test]
    fn centroid_of_a_square_is_its_centre() {
        let v = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, -2.0),
            DVec3::new(0.0, 0.0, -2.0),
        ];
        let c = polygon_centroid(&v, DVec3::Y);
        assert!((c - DVec3::new(1.0, 0.0, -1.0)).length() < 1e-12);
    }
}
