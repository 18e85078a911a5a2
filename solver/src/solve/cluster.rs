//! The receiver tree: the surfaces (input polygons) under a bounding-volume
//! hierarchy built once per mesh, which grouped shots (`group_shot.rs`) ask
//! for the surfaces near a seed and the memory estimate (`budget.rs`) asks
//! for the most patches one group can rank. A surface's box is its
//! polygon's, so it bounds every vertex refinement will ever add to it and
//! never needs a refit.

use crate::mesh::Mesh;
use glam::DVec3;

/// The receiver tree: surfaces under a binary bounding-volume hierarchy.
pub struct ReceiverTree {
    nodes: Vec<Node>,
    /// Surfaces in tree order: node `n` covers `order[n.start..n.end]`.
    order: Vec<u32>,
    /// Per surface: its polygon's box and centroid.
    surfaces: Vec<SurfaceBounds>,
}

struct Node {
    lo: DVec3,
    hi: DVec3,
    start: u32,
    end: u32,
    /// Children (`left`, `left + 1`), or `u32::MAX` for a leaf.
    left: u32,
}

struct SurfaceBounds {
    lo: DVec3,
    hi: DVec3,
    centroid: DVec3,
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

    /// The tree over the surfaces of `mesh`.
    pub fn new(mesh: &Mesh) -> ReceiverTree {
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
                centroid: polygon_centroid(&s.vertices, s.normal),
            })
            .collect();
        let mut tree = ReceiverTree {
            nodes: Vec::with_capacity(2 * surfaces.len()),
            order: (0..surfaces.len() as u32).collect(),
            surfaces,
        };
        if !tree.order.is_empty() {
            tree.nodes.push(tree.make_node(0, tree.order.len() as u32));
            tree.split(0);
        }
        tree
    }

    fn make_node(&self, start: u32, end: u32) -> Node {
        let mut node = Node {
            lo: DVec3::INFINITY,
            hi: DVec3::NEG_INFINITY,
            start,
            end,
            left: u32::MAX,
        };
        for &s in &self.order[start as usize..end as usize] {
            let b = &self.surfaces[s as usize];
            node.lo = node.lo.min(b.lo);
            node.hi = node.hi.max(b.hi);
        }
        node
    }

    /// Splits node `n` (and its children) at the median centroid along the
    /// longest axis of its box, down to one surface per leaf. Iterative, so a
    /// degenerate scene cannot overflow the stack.
    fn split(&mut self, root: u32) {
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
            let (l, r) = (self.make_node(start, mid), self.make_node(mid, end));
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
