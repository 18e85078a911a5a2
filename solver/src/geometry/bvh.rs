//! Bounding volume hierarchy construction for the occluder: a binned-SAH
//! binary tree over primitive boxes, collapsed into a 4-wide tree whose child
//! boxes are stored structure-of-arrays in f32, so one node's four children
//! are tested together.

// Per-axis and per-child loops index several arrays in lockstep; written as
// index loops they stay readable and vectorise.
#![allow(clippy::needless_range_loop)]

/// Axis-aligned box in f32.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Aabb {
    pub lo: [f32; 3],
    pub hi: [f32; 3],
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        lo: [f32::INFINITY; 3],
        hi: [f32::NEG_INFINITY; 3],
    };

    pub fn grow_point(&mut self, p: [f32; 3]) {
        for a in 0..3 {
            self.lo[a] = self.lo[a].min(p[a]);
            self.hi[a] = self.hi[a].max(p[a]);
        }
    }

    pub fn grow(&mut self, b: &Aabb) {
        for a in 0..3 {
            self.lo[a] = self.lo[a].min(b.lo[a]);
            self.hi[a] = self.hi[a].max(b.hi[a]);
        }
    }

    /// Half the surface area (the SAH's cost measure); 0 for an empty box.
    pub fn half_area(&self) -> f32 {
        let d = [
            self.hi[0] - self.lo[0],
            self.hi[1] - self.lo[1],
            self.hi[2] - self.lo[2],
        ];
        if d[0].is_nan() || d[0] < 0.0 {
            return 0.0;
        }
        d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
    }

    fn centroid(&self) -> [f32; 3] {
        [
            0.5 * (self.lo[0] + self.hi[0]),
            0.5 * (self.lo[1] + self.hi[1]),
            0.5 * (self.lo[2] + self.hi[2]),
        ]
    }
}

/// Leaves of the binary tree (and so of the 4-wide one) hold at most this many
/// primitives.
pub(crate) const MAX_LEAF: usize = 4;

/// SAH cost of visiting one more node, relative to one primitive test.
const TRAVERSAL_COST: f32 = 1.0;

/// A node of the binary tree: inner nodes (`count == 0`) have their children
/// at `first` and `first + 1`; leaves hold `count` primitives from `first` in
/// the build order.
#[derive(Clone, Copy, Debug)]
struct BinaryNode {
    bounds: Aabb,
    first: u32,
    count: u32,
}

/// Child slot marker: the slot is a leaf; the low bits are its first primitive.
pub(crate) const LEAF_BIT: u32 = 1 << 31;
/// Child slot marker: the slot is unused (its box is empty and never hit).
pub(crate) const EMPTY_SLOT: u32 = u32::MAX;

/// A 4-wide node: child boxes structure-of-arrays (`lo[axis][child]`), padded
/// outward by the builder's padding; `child[i]` is an inner node index, or
/// `LEAF_BIT | first primitive` with `count[i]` primitives, or [`EMPTY_SLOT`].
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct Node4 {
    pub lo: [[f32; 4]; 3],
    pub hi: [[f32; 4]; 3],
    pub child: [u32; 4],
    pub count: [u32; 4],
}

impl Node4 {
    const EMPTY: Node4 = Node4 {
        lo: [[f32::INFINITY; 4]; 3],
        hi: [[f32::NEG_INFINITY; 4]; 3],
        child: [EMPTY_SLOT; 4],
        count: [0; 4],
    };
}

/// A 4-wide BVH: `nodes[0]` is the root; `order[k]` is the input primitive
/// stored at position k (leaves refer to positions).
pub(crate) struct Bvh4 {
    pub nodes: Vec<Node4>,
    pub order: Vec<u32>,
}

/// Builds the 4-wide tree over primitive `boxes`, padding every stored box by
/// `padding` on each side so that f32 rounding in the ray/box tests can never
/// reject a ray that touches a primitive.
pub(crate) fn build(boxes: &[Aabb], padding: f32) -> Bvh4 {
    let (binary, order) = build_binary(boxes);
    if binary.is_empty() {
        return Bvh4 {
            nodes: Vec::new(),
            order,
        };
    }
    let mut nodes = vec![Node4::EMPTY];
    // The root's slots: a root that is itself a leaf becomes one leaf slot.
    let mut work = vec![(0usize, 0usize)]; // (binary node, Node4 index)
    while let Some((b, n)) = work.pop() {
        let mut slots: Vec<usize> = if binary[b].count > 0 {
            vec![b]
        } else {
            let f = binary[b].first as usize;
            vec![f, f + 1]
        };
        // Open the largest inner child until there are four slots.
        while slots.len() < 4 {
            let pick = slots
                .iter()
                .enumerate()
                .filter(|(_, &s)| binary[s].count == 0)
                .max_by(|(_, &x), (_, &y)| {
                    binary[x]
                        .bounds
                        .half_area()
                        .total_cmp(&binary[y].bounds.half_area())
                })
                .map(|(i, _)| i);
            let Some(i) = pick else { break };
            let s = slots.swap_remove(i);
            let f = binary[s].first as usize;
            slots.push(f);
            slots.push(f + 1);
        }
        for (k, &s) in slots.iter().enumerate() {
            let node = &binary[s];
            for a in 0..3 {
                nodes[n].lo[a][k] = node.bounds.lo[a] - padding;
                nodes[n].hi[a][k] = node.bounds.hi[a] + padding;
            }
            if node.count > 0 {
                nodes[n].child[k] = LEAF_BIT | node.first;
                nodes[n].count[k] = node.count;
            } else {
                let index = nodes.len();
                nodes.push(Node4::EMPTY);
                nodes[n].child[k] = index as u32;
                work.push((s, index));
            }
        }
    }
    Bvh4 { nodes, order }
}

/// Binned-SAH build (16 bins on centroids) of a binary tree. Returns the nodes
/// (root first) and the primitive order of the leaves. Splits fall back to the
/// median of the widest centroid axis when binning cannot separate centroids,
/// and are forced to the median below depth 48, so the depth stays bounded
/// (the traversal stacks hold 64 entries per level of 4-wide nodes and more).
fn build_binary(boxes: &[Aabb]) -> (Vec<BinaryNode>, Vec<u32>) {
    let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
    if boxes.is_empty() {
        return (Vec::new(), order);
    }
    let centroids: Vec<[f32; 3]> = boxes.iter().map(Aabb::centroid).collect();
    let mut nodes = Vec::with_capacity(2 * boxes.len() / MAX_LEAF + 1);
    nodes.push(BinaryNode {
        bounds: Aabb::EMPTY,
        first: 0,
        count: 0,
    });
    // (node index, start, end, depth)
    let mut work = vec![(0usize, 0usize, boxes.len(), 0u32)];
    while let Some((node_index, start, end, depth)) = work.pop() {
        let mut bounds = Aabb::EMPTY;
        let mut cbounds = Aabb::EMPTY;
        for &i in &order[start..end] {
            bounds.grow(&boxes[i as usize]);
            cbounds.grow_point(centroids[i as usize]);
        }
        nodes[node_index].bounds = bounds;
        let count = end - start;
        // Small nodes stay leaves unless the SAH says splitting them pays.
        let leaf_cost = (count <= MAX_LEAF).then(|| count as f32 * bounds.half_area());
        let split_at = if count < 2 {
            None
        } else {
            split(
                &mut order[start..end],
                boxes,
                &centroids,
                &cbounds,
                depth >= 48,
                leaf_cost,
            )
        };
        let Some(offset) = split_at else {
            nodes[node_index].first = start as u32;
            nodes[node_index].count = count as u32;
            continue;
        };
        let mid = start + offset;
        let left = nodes.len();
        nodes[node_index].first = left as u32;
        nodes[node_index].count = 0;
        nodes.push(BinaryNode {
            bounds: Aabb::EMPTY,
            first: 0,
            count: 0,
        });
        nodes.push(BinaryNode {
            bounds: Aabb::EMPTY,
            first: 0,
            count: 0,
        });
        work.push((left, start, mid, depth + 1));
        work.push((left + 1, mid, end, depth + 1));
    }
    (nodes, order)
}

/// Partitions `order` (at least 2 entries) by the best binned-SAH plane and
/// returns the split position in 1..len, or partitions at the median of the
/// widest centroid axis when binning fails or `median` is forced.
///
/// With `leaf_cost` (the SAH cost of keeping the node a leaf: primitives ×
/// area, one unit per primitive test), returns `None` without partitioning
/// when no split beats it; a split costs [`TRAVERSAL_COST`] × area for the
/// extra node visit plus its children's costs.
fn split(
    order: &mut [u32],
    boxes: &[Aabb],
    centroids: &[[f32; 3]],
    cbounds: &Aabb,
    median: bool,
    leaf_cost: Option<f32>,
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
    let bin_of = |axis: usize, c: f32| {
        let scale = BINS as f32 / extent[axis];
        (((c - cbounds.lo[axis]) * scale) as usize).min(BINS - 1)
    };
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, first bin on the right)
    if !median {
        for axis in 0..3 {
            if extent[axis].is_nan() || extent[axis] <= 0.0 {
                continue;
            }
            let mut bin_box = [Aabb::EMPTY; BINS];
            let mut bin_count = [0usize; BINS];
            for &i in order.iter() {
                let b = bin_of(axis, centroids[i as usize][axis]);
                bin_box[b].grow(&boxes[i as usize]);
                bin_count[b] += 1;
            }
            let mut right_area = [0.0f32; BINS];
            let mut right_count = [0usize; BINS];
            let mut acc = Aabb::EMPTY;
            let mut acc_count = 0;
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
    if let (Some(leaf), Some((cost, _, _))) = (leaf_cost, best) {
        let mut bounds = Aabb::EMPTY;
        order.iter().for_each(|&i| bounds.grow(&boxes[i as usize]));
        if cost + TRAVERSAL_COST * bounds.half_area() >= leaf {
            return None;
        }
    } else if leaf_cost.is_some() {
        return None; // binning cannot separate them: keep the small leaf
    }
    if let Some((_, axis, boundary)) = best {
        let mut left = 0;
        for k in 0..order.len() {
            if bin_of(axis, centroids[order[k] as usize][axis]) < boundary {
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

    /// Every primitive appears in exactly one leaf, and every leaf's slot box
    /// contains its primitives' boxes.
    #[test]
    fn four_wide_tree_covers_every_primitive_once() {
        let mut boxes = Vec::new();
        for i in 0..1000 {
            let x = (i % 10) as f32;
            let y = ((i / 10) % 10) as f32;
            let z = (i / 100) as f32 * 0.37;
            boxes.push(Aabb {
                lo: [x, y, z],
                hi: [x + 0.5, y + 0.9, z + 0.1],
            });
        }
        let bvh = build(&boxes, 0.0);
        let mut seen = vec![0u32; boxes.len()];
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &bvh.nodes[n];
            for k in 0..4 {
                let c = node.child[k];
                if c == EMPTY_SLOT {
                    continue;
                }
                if c & LEAF_BIT != 0 {
                    let first = (c & !LEAF_BIT) as usize;
                    assert!(node.count[k] as usize <= MAX_LEAF);
                    for pos in first..first + node.count[k] as usize {
                        let b = boxes[bvh.order[pos] as usize];
                        for a in 0..3 {
                            assert!(node.lo[a][k] <= b.lo[a] && b.hi[a] <= node.hi[a][k]);
                        }
                        seen[bvh.order[pos] as usize] += 1;
                    }
                } else {
                    stack.push(c as usize);
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
    }
}
