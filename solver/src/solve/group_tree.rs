//! The far field of a grouped shot: its members under a bounding hierarchy,
//! so that a receiver pays for the members near it and one item per far
//! cluster of them. This is the shooter half of Smits, Arvo and Greenberg's
//! (1994) clustering with a hierarchy of clusters; the sampled clusters below
//! follow the stochastic light cuts of Yuksel (2019, "Stochastic
//! Lightcuts"): a cluster is represented by one member drawn in proportion to
//! its power, which keeps the estimate unbiased whatever the cut.
//!
//! ## Why
//!
//! A receiver computed an unoccluded factor to every member of a group, so a
//! grouped shot cost members × receivers and a group could not grow past a
//! few dozen patches without its shot growing as much (a 10k boxes draft
//! solve: 85% of its time in the per-member factors, 7% in rays). Larger
//! groups mean fewer shots only if a receiver's cost grows more slowly than
//! the group.
//!
//! ## The cut
//!
//! Each receiver q (normal n) walks the tree from the root. A node wholly on
//! or below q's horizon gives nothing, as each of its members would. A single
//! member is itself: its exact factor (`Member::factor`). Otherwise, with c
//! the members' centres weighted by A_p |U_p| (A_p its area, U_p its unshot
//! radiance, |U_p| its channels summed), R the radius about c that holds
//! every member's corners, d = q − c and r = |d|:
//!
//! * **Far** (r > [`CLUSTER_FAR`] · 2R, the node's box wholly above q's
//!   horizon, every member facing q): the cluster kernel, deterministic.
//! * **Sampled** (r > [`SAMPLED_FAR`] · 2R, members of one orientation, say
//!   box faces that straddle q's plane or horizon, so that the cluster
//!   kernel does not apply): an upper bound on the members' kernels as the
//!   node's importance, and each ray's own point kernel.
//! * Otherwise the node opens.
//!
//! Members facing apart are parted by normal near the root
//! ([`NORMAL_SPLIT`]), so a node of mixed orientation opens rather than
//! being sampled.
//!
//! ## The cluster kernel (far nodes)
//!
//! Member p (normal n_p, centre c_p) far from q gives, by the differential
//! kernel at its centre, w_p = A_p |U_p| (n_p · d_p)(−n · d_p) / (π r_p⁴),
//! d_p = q − c_p. The node takes its members at c:
//! w_P = Σ_p A_p |U_p| (n_p · d)(−n · d) / (π r⁴) = (N · d)(−n · d) / (π r⁴),
//! N = Σ_p A_p |U_p| n_p, and its colour sum
//! g_P = (M d)(−n · d) / (π r⁴), with (M d)_c = Σ_p A_p U_p,c (n_p · d).
//! Both are linear in the members' normals, so they are exact in the
//! orientations; only the positions are approximated. Expanding each
//! member's kernel about c, the first-order terms cancel (c is the weighted
//! centre), so the relative error is O((R/r)²) ≤ O(1/(2 · CLUSTER_FAR)²);
//! test `cluster_kernel_matches_its_members` measures it at the threshold.
//! A ray sent to the node picks member p with probability A_p |U_p| / S
//! (S = Σ A_p |U_p|) and a uniform point on it; one that arrives carries
//! U_p / |U_p| · (n_p · d) / (n̄ · d), n̄ = N / S, so the expectation is
//! Σ_p w_p f_p U_p / |U_p| (f_p p's visible fraction), as for members.
//!
//! ## Sampled nodes
//!
//! The node's importance is w_P = S cos_q cos_p / (π (r − R)²), cos_q and
//! cos_p upper bounds on the receiving and sending cosines over the node's
//! sphere and normal cone, so w_P ≥ S max K (K(q, y) = cos cos / (π |y − q|²)
//! per unit area). A ray sent to it picks member p as above and a uniform
//! point y on it; one that arrives carries U_p / |U_p| · S K(q, y) / w_P.
//! The expectation is Σ_p U_p ∫_p K V dA, the members' shots exactly (no
//! kernel approximation), and no ray carries more than a member's colour
//! (w_P bounds S K), so the estimate has no outliers; its cost is noise where
//! K varies across the node, which is why such nodes must be farther than
//! their own diameter and only single-orientation nodes are sampled. The
//! bound also serves the ray share and the no-shadow case is never sampled:
//! without shadows every node opens to its members (exact factors).

use super::group_shot::Member;
use crate::geometry::sampling::Rng;
use glam::DVec3;
use std::f64::consts::PI;

/// The deepest a tree over [`super::group_shot::MAX_MEMBERS`] pieces can
/// be (median splits halve each node), with room to spare: the traversal's
/// stack.
const STACK: usize = 64;

/// A receiver takes a node by the cluster kernel beyond this many of its
/// diameters (see the module documentation). At 3 the furnace's worst vertex
/// moved from 0.38% to 0.39% off the exact value (2: 0.41%).
pub const CLUSTER_FAR: f64 = 3.0;

/// A receiver samples a single-orientation node that the cluster kernel
/// cannot take beyond this many of its diameters: the kernel over the node
/// then varies by at most ((r + R) / (r − R))² = 9 in distance.
pub const SAMPLED_FAR: f64 = 1.0;

/// A node whose members' normals spread wider than this (radians, 30°) is
/// split by normal rather than by position.
const NORMAL_SPLIT: f64 = std::f64::consts::FRAC_PI_6;

/// Members in tree order under a binary hierarchy of clusters.
pub struct MemberTree {
    nodes: Vec<Node>,
    /// Σ A_p |U_p| over the members before each, in tree order (one more
    /// entry than members): a ray's member inside a node.
    cumulative: Vec<f64>,
}

struct Node {
    /// Members' centres weighted by A_p |U_p|.
    centre: DVec3,
    /// The sphere about `centre` that holds every member's corners, and the
    /// box that does (its middle and half extent).
    radius: f64,
    middle: DVec3,
    half: DVec3,
    /// N / |N|, and the half-angle of the cone about it that holds every
    /// member's normal.
    axis: DVec3,
    cone: f64,
    cone_sin: f64,
    cone_cos: f64,
    /// S = Σ A_p |U_p|.
    strength: f64,
    /// Σ A_p U_p / S: the colour of the node's unshot power.
    colour: DVec3,
    /// N = Σ A_p |U_p| n_p, and M's rows Σ A_p U_p,c n_p.
    normal_sum: DVec3,
    colour_normal: [DVec3; 3],
    /// Per channel c, the members' centres weighted by A_p U_p,c: each
    /// channel's own expansion point (see `Node::channel_gain`).
    channel_centres: [DVec3; 3],
    start: u32,
    end: u32,
    /// Children (`left`, `left + 1`), or `u32::MAX` for a single member.
    left: u32,
}

/// A receiving point: q, its normal n, its surface (which its own members
/// cannot light) and the scene epsilon.
#[derive(Clone, Copy, Debug)]
pub struct Receiver {
    pub q: DVec3,
    pub n: DVec3,
    pub surface: u32,
    pub epsilon: f64,
}

/// What a receiver sees of the group: single members (index in tree order)
/// and clusters taken whole.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Item {
    Member(u32),
    Cluster(Cluster),
}

/// A node taken whole: by the cluster kernel (far) or `sampled`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cluster {
    pub node: u32,
    pub sampled: bool,
}

/// The bytes a grouped shot holds per piece: the piece, its member, two tree
/// nodes (a binary tree over n leaves has 2n − 1) and a cumulative weight
/// (`budget.rs` counts them).
pub fn bytes_per_piece() -> u64 {
    (size_of::<super::group_shot::Piece>()
        + size_of::<Member>()
        + 2 * size_of::<Node>()
        + size_of::<f64>()) as u64
}

impl MemberTree {
    /// The tree over `members`, which it reorders into tree order.
    pub fn build(members: &mut [Member]) -> MemberTree {
        let mut tree = MemberTree {
            nodes: Vec::with_capacity(2 * members.len()),
            cumulative: Vec::with_capacity(members.len() + 1),
        };
        if members.is_empty() {
            return tree;
        }
        tree.nodes.push(Node::over(members, 0, members.len()));
        tree.split(members, 0);
        tree.cumulative.push(0.0);
        let mut sum = 0.0;
        for m in members.iter() {
            sum += m.strength();
            tree.cumulative.push(sum);
        }
        tree
    }

    /// Splits node `k` at the median of its members' centres along their
    /// longest extent, children appended, until each holds one member.
    fn split(&mut self, members: &mut [Member], k: usize) {
        let (start, end) = (self.nodes[k].start as usize, self.nodes[k].end as usize);
        if end - start < 2 {
            return;
        }
        let part = &mut members[start..end];
        let middle = part.len() / 2;
        // A cluster is taken whole only when all its members face the
        // receiver, so members facing apart are parted first: by the normal
        // component that varies most, then by position.
        let key: fn(&Member, usize) -> f64 = if self.nodes[k].cone > NORMAL_SPLIT {
            |m, axis| m.normal()[axis]
        } else {
            |m, axis| m.centre()[axis]
        };
        let (lo, hi) = part.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), m| {
                let p = DVec3::new(key(m, 0), key(m, 1), key(m, 2));
                (lo.min(p), hi.max(p))
            },
        );
        // Extents equal to a millionth of the largest count as equal (a
        // square's two sides), so that rounding does not pick the axis.
        let longest = (hi - lo).max_element();
        let extent = if longest > 0.0 {
            ((hi - lo) / longest * 1e6).round()
        } else {
            DVec3::ZERO
        };
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        // The median on keys quantized to a millionth of the node's extent,
        // ties broken by surface and then by the quantized centre: members
        // whose keys tie (box faces in a row) must part the same way when
        // the scene is moved and its coordinates round differently, or the
        // cut, and with it the mesh, changes with the scene's position.
        let (low, span) = (lo[axis], hi[axis] - lo[axis]);
        let quantize = |x: f64| {
            if span > 0.0 {
                ((x - low) / span * 1e6).round() as i64
            } else {
                0
            }
        };
        let rank = |m: &Member| {
            let c = m.centre();
            (
                quantize(key(m, axis)),
                m.surface(),
                [quantize(c.x), quantize(c.y), quantize(c.z)],
            )
        };
        part.select_nth_unstable_by_key(middle, rank);
        let left = self.nodes.len();
        self.nodes[k].left = left as u32;
        self.nodes.push(Node::over(members, start, start + middle));
        self.nodes.push(Node::over(members, start + middle, end));
        self.split(members, left);
        self.split(members, left + 1);
    }

    /// The items `receiver` sees, appended to
    /// `items` with their weights w (the estimate's importance) in
    /// `weights`; returns Σ of their unoccluded colour sums. Members get
    /// their exact factor (`Member::factor`), far clusters the cluster
    /// kernel (see the module documentation).
    pub fn items(
        &self,
        members: &[Member],
        receiver: &Receiver,
        clusters: bool,
        sample: bool,
        items: &mut Vec<Item>,
        weights: &mut Vec<f64>,
    ) -> DVec3 {
        let Receiver {
            q,
            n,
            surface,
            epsilon,
        } = *receiver;
        let mut gain = DVec3::ZERO;
        if self.nodes.is_empty() {
            return gain;
        }
        let mut stack = [0u32; STACK];
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            let node = &self.nodes[stack[depth] as usize];
            // Wholly on or below q's horizon (behind the sphere, or the box's
            // highest corner along n in q's plane): no member can light q.
            let height = n.dot(node.middle - q);
            if n.dot(node.centre - q) < -node.radius
                || height + n.abs().dot(node.half) <= 1e-6 * epsilon
            {
                continue;
            }
            if node.left == u32::MAX {
                let m = &members[node.start as usize];
                // A planar polygon cannot light its own surface.
                if m.surface() != surface {
                    let w = m.factor(q, n, epsilon) * m.unshot.element_sum();
                    if w > 0.0 {
                        gain += m.colour() * w;
                        items.push(Item::Member(node.start));
                        weights.push(w);
                    }
                }
                continue;
            }
            if !clusters {
                stack[depth] = node.left;
                stack[depth + 1] = node.left + 1;
                depth += 2;
                continue;
            }
            let taken = match node.far(q, n, epsilon) {
                Far::Taken(weight, g) => Some((far(stack[depth]), weight, g)),
                Far::Near => None,
                // Members facing apart are parted near the root, so such a
                // node opens; one of a single orientation that straddles
                // q's horizon or its plane is sampled when far enough.
                Far::Mixed if node.cone > NORMAL_SPLIT || !sample => None,
                Far::Mixed => node
                    .bound(q, n)
                    .map(|weight| (sampled(stack[depth]), weight, node.colour * weight)),
            };
            match taken {
                Some((item, weight, g)) => {
                    if weight > 0.0 && weight.is_finite() {
                        gain += g;
                        items.push(item);
                        weights.push(weight);
                    }
                }
                None => {
                    stack[depth] = node.left;
                    stack[depth + 1] = node.left + 1;
                    depth += 2;
                }
            }
        }
        gain
    }

    /// For a ray sent to node `cluster` that it takes whole, with uniform
    /// `u` in [0, 1): the member it goes to (tree order), chosen in
    /// proportion to A_p |U_p|, and the node's strength S.
    fn pick(&self, cluster: u32, u: f64) -> (u32, f64) {
        let node = &self.nodes[cluster as usize];
        let (start, end) = (node.start as usize, node.end as usize);
        let target = self.cumulative[start] + u * node.strength;
        // The first member whose cumulative end passes the target.
        let k = start
            + self.cumulative[start + 1..=end]
                .partition_point(|&c| c <= target)
                .min(end - start - 1);
        (k as u32, node.strength)
    }
}

impl MemberTree {
    /// One ray of receiver `q` (normal `n`) to `cluster` with importance
    /// `weight`: a member in proportion
    /// to A_p |U_p|, a uniform point y on it, and what the ray carries if it
    /// arrives (see the module documentation): (y, the member's normal, the
    /// colour, the member in tree order), or `None` when y cannot light q
    /// (a sampled node's member point behind q's horizon or facing away; it
    /// carries nothing).
    pub fn ray(
        &self,
        members: &[Member],
        cluster: Cluster,
        weight: f64,
        q: DVec3,
        n: DVec3,
        rng: &mut Rng,
    ) -> Option<(DVec3, DVec3, DVec3, u32)> {
        let Cluster {
            node: cluster,
            sampled,
        } = cluster;
        let (member, strength) = self.pick(cluster, rng.next_f64());
        let m = &members[member as usize];
        let y = m.uniform_point(rng);
        let carried = if sampled {
            let kernel = point_kernel(q, n, y, m.normal());
            if kernel <= 0.0 {
                return None;
            }
            m.colour() * (strength * kernel / weight)
        } else {
            // The pick averages to the common-centre colour; each channel is
            // rescaled to its own centre's (both ≥ 0 for a far node).
            let node = &self.nodes[cluster as usize];
            let d = q - node.centre;
            let (own, common) = (node.channel_gain(q, n), node.common_gain(q, n));
            let rescale = DVec3::from_array(std::array::from_fn(|c| {
                if common[c] > 0.0 {
                    own[c] / common[c]
                } else {
                    1.0
                }
            }));
            m.colour() * rescale * (m.normal().dot(d) * node.strength / node.normal_sum.dot(d))
        };
        Some((y, m.normal(), carried, member))
    }
}

impl Node {
    /// The node over `members[start..end]`, a leaf until split.
    fn over(members: &[Member], start: usize, end: usize) -> Node {
        let part = &members[start..end];
        let mut strength = 0.0;
        let mut weighted = DVec3::ZERO;
        let mut normal_sum = DVec3::ZERO;
        let mut power = DVec3::ZERO;
        let mut colour_normal = [DVec3::ZERO; 3];
        let mut channel_weighted = [DVec3::ZERO; 3];
        for m in part {
            let s = m.strength();
            strength += s;
            weighted += m.centre() * s;
            normal_sum += m.normal() * s;
            let a = m.unshot * m.area();
            power += a;
            for (c, sum) in channel_weighted.iter_mut().enumerate() {
                *sum += m.centre() * a[c];
            }
            for (c, row) in colour_normal.iter_mut().enumerate() {
                *row += m.normal() * a[c];
            }
        }
        let centre = if strength > 0.0 {
            weighted / strength
        } else {
            part.iter().map(|m| m.centre()).sum::<DVec3>() / part.len() as f64
        };
        let corners = || part.iter().flat_map(|m| m.polygon().iter().copied());
        let radius = corners().map(|c| (c - centre).length()).fold(0.0, f64::max);
        let (lo, hi) = corners().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), c| (lo.min(c), hi.max(c)),
        );
        let channel_centres = std::array::from_fn(|c| {
            if power[c] > 0.0 {
                channel_weighted[c] / power[c]
            } else {
                centre
            }
        });
        let axis = normal_sum.normalize_or_zero();
        let cone = part
            .iter()
            .map(|m| angle_between(m.normal(), axis))
            .fold(0.0, f64::max);
        Node {
            centre,
            radius,
            middle: (lo + hi) * 0.5,
            half: (hi - lo) * 0.5,
            axis,
            cone,
            cone_sin: cone.sin(),
            cone_cos: cone.cos(),
            strength,
            colour: if strength > 0.0 {
                power / strength
            } else {
                DVec3::ZERO
            },
            normal_sum,
            colour_normal,
            channel_centres,
            start: start as u32,
            end: end as u32,
            left: u32::MAX,
        }
    }

    /// Receiver `q` (normal `n`) takes this node whole by the cluster
    /// kernel when it is far, wholly above q's horizon and every member
    /// faces q: (w_P, g_P). `Near` when only the distance fails (its
    /// children may pass), `Mixed` when the orientations do.
    fn far(&self, q: DVec3, n: DVec3, epsilon: f64) -> Far {
        if self.axis == DVec3::ZERO {
            return Far::Mixed;
        }
        // Every corner on or above q's horizon: the box's lowest corner
        // along n (the member's own test, `Member::above_horizon`).
        if n.dot(self.middle - q) - n.abs().dot(self.half) < -1e-6 * epsilon {
            return Far::Mixed;
        }
        let d = q - self.centre;
        let r2 = d.length_squared();
        let r = r2.sqrt();
        if self.cone_cos >= 1.0 - 1e-12 {
            // One normal: q in front of the box's farthest corner along it.
            if self.axis.dot(q - self.middle) - self.axis.abs().dot(self.half) <= 0.0 {
                return Far::Mixed;
            }
        } else {
            // Every member faces q when the angle off the axis plus the cone
            // and the sphere's half-angle seen from q stays under 90°:
            // cos(off axis) > sin(cone + spread), sin(spread) = R / r, with
            // cone + spread < 90° (sin(spread) < cos(cone)).
            let spread_sin = (self.radius / r).min(1.0);
            let spread_cos = (1.0 - spread_sin * spread_sin).sqrt();
            let bound = self.cone_sin * spread_cos + self.cone_cos * spread_sin;
            if spread_sin >= self.cone_cos || self.axis.dot(d) <= r * bound {
                return Far::Mixed;
            }
        }
        if r2 <= (CLUSTER_FAR * 2.0 * self.radius).powi(2) {
            return Far::Near;
        }
        let k = -n.dot(d) / (PI * r2 * r2);
        Far::Taken(self.normal_sum.dot(d) * k, self.channel_gain(q, n))
    }

    /// g_P, each channel c expanded about its own centre c_c (members
    /// weighted by A_p U_p,c), so that each is second order in R / r: about
    /// the common centre c a channel whose members differ in colour keeps a
    /// first-order error (test `cluster_kernel_matches_its_members`).
    fn channel_gain(&self, q: DVec3, n: DVec3) -> DVec3 {
        DVec3::from_array(std::array::from_fn(|c| {
            let d = q - self.channel_centres[c];
            let r2 = d.length_squared();
            self.colour_normal[c].dot(d) * -n.dot(d) / (PI * r2 * r2)
        }))
    }

    /// g_P with every channel about the common centre c: the colour the
    /// rays' picks (by A_p |U_p|) average to.
    fn common_gain(&self, q: DVec3, n: DVec3) -> DVec3 {
        let d = q - self.centre;
        let r2 = d.length_squared();
        let k = -n.dot(d) / (PI * r2 * r2);
        DVec3::from_array(std::array::from_fn(|c| self.colour_normal[c].dot(d) * k))
    }

    /// The importance w_P of this node taken as one item by receiver `q`
    /// (normal `n`): an upper bound on the members' summed kernel times
    /// their strength (see the module documentation); `Some(0)` when no
    /// member can light q, `None` when q is too near and the node opens.
    fn bound(&self, q: DVec3, n: DVec3) -> Option<f64> {
        let d = q - self.centre;
        let r2 = d.length_squared();
        if r2 <= (SAMPLED_FAR * 2.0 * self.radius).powi(2) {
            return None;
        }
        let r = r2.sqrt();
        // Seen from q the sphere spans at most `spread` either side of d.
        let spread_sin = self.radius / r;
        let spread_cos = (1.0 - spread_sin * spread_sin).sqrt();
        // The receiving cosine is at most cos(θ − spread), θ the angle
        // between n and the direction to the centre.
        let receiving = cos_within(-n.dot(d) / r, spread_sin, spread_cos);
        // A member's cosine is at most cos(φ − cone − spread), φ the angle
        // between the axis and d.
        let (a_sin, a_cos) = (
            self.cone_sin * spread_cos + self.cone_cos * spread_sin,
            self.cone_cos * spread_cos - self.cone_sin * spread_sin,
        );
        let sending = if self.cone + spread_sin.asin() >= std::f64::consts::PI {
            1.0
        } else {
            cos_within(self.axis.dot(d) / r, a_sin, a_cos)
        };
        if receiving <= 0.0 || sending <= 0.0 {
            return Some(0.0);
        }
        let nearest = r - self.radius;
        Some(self.strength * receiving * sending / (PI * nearest * nearest))
    }
}

/// The angle between unit vectors `a` and `b`, as atan2(|a × b|, a · b): well
/// conditioned near 0, where acos(a · b) turns a rounding of 1e-16 in the dot
/// product into an angle of 1.5e-8 (√(2 · 1e-16)). A cone of 1.5e-8 in place
/// of 0 moved every bound of a flat cluster by that much, so a scene's
/// radiance depended on its emission's scale to 1e-8 (test
/// `radiance_scales_linearly_with_emission_from_1e_minus_6_to_1e6`).
fn angle_between(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// K(q, y) = cos θ_y cos θ_q / (π |y − q|²): the differential factor from
/// receiver q (normal `n`) to the point y (normal `m`) of a source, per unit
/// of its area; 0 when either faces away.
fn point_kernel(q: DVec3, n: DVec3, y: DVec3, m: DVec3) -> f64 {
    let d = y - q;
    let r2 = d.length_squared();
    let (cq, cy) = (n.dot(d), -m.dot(d));
    if cq <= 0.0 || cy <= 0.0 || r2 <= 0.0 {
        return 0.0;
    }
    cq * cy / (PI * r2 * r2)
}

fn far(node: u32) -> Item {
    Item::Cluster(Cluster {
        node,
        sampled: false,
    })
}

fn sampled(node: u32) -> Item {
    Item::Cluster(Cluster {
        node,
        sampled: true,
    })
}

/// How a receiver may take a node by the cluster kernel.
enum Far {
    Taken(f64, DVec3),
    Near,
    Mixed,
}

/// The largest cos(θ − δ) for θ ∈ [0, π] with cos θ = `cos`, δ ≥ 0 given
/// by its sine and cosine: 1 when δ ≥ θ.
fn cos_within(cos: f64, delta_sin: f64, delta_cos: f64) -> f64 {
    let cos = cos.clamp(-1.0, 1.0);
    if cos >= delta_cos {
        return 1.0;
    }
    let sin = (1.0 - cos * cos).sqrt();
    (cos * delta_cos + sin * delta_sin).min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::formfactor::SourcePolygon;
    use crate::solve::group_shot::Piece;

    /// A unit square piece with corners `corners` (counter-clockwise about
    /// `normal`), on its own surface, with unshot radiance `unshot`.
    fn member(corners: [DVec3; 4], normal: DVec3, unshot: DVec3, surface: u32) -> Member {
        let piece = Piece {
            patch: surface,
            surface,
            corners,
            corner_count: 4,
            area: (corners[1] - corners[0])
                .cross(corners[3] - corners[0])
                .length(),
            unshot,
            by_solid_angle: false,
        };
        Member::of(&piece, normal)
    }

    fn colour(k: usize) -> DVec3 {
        DVec3::new(1.0 + (k % 3) as f64, 0.5 + (k % 2) as f64, 1.0)
    }

    /// 16 unit squares tiling [0, 4]² in the plane z = 0, facing +z.
    fn floor_grid() -> Vec<Member> {
        (0..16)
            .map(|k| {
                let (x, y) = ((k % 4) as f64, (k / 4) as f64);
                let c = [
                    DVec3::new(x, y, 0.0),
                    DVec3::new(x + 1.0, y, 0.0),
                    DVec3::new(x + 1.0, y + 1.0, 0.0),
                    DVec3::new(x, y + 1.0, 0.0),
                ];
                member(c, DVec3::Z, colour(k), k as u32)
            })
            .collect()
    }

    fn cluster_of(item: Item) -> Cluster {
        match item {
            Item::Cluster(c) => c,
            Item::Member(m) => panic!("member {m} where a cluster was expected"),
        }
    }

    /// The cut receiver `q` (normal `n`, on no member's surface) sees: its
    /// items, their weights and its unoccluded gain.
    fn cut(
        tree: &MemberTree,
        members: &[Member],
        q: DVec3,
        n: DVec3,
    ) -> (Vec<Item>, Vec<f64>, DVec3) {
        let receiver = Receiver {
            q,
            n,
            surface: u32::MAX,
            epsilon: 1e-6,
        };
        let (mut items, mut weights) = (Vec::new(), Vec::new());
        let gain = tree.items(members, &receiver, true, true, &mut items, &mut weights);
        (items, weights, gain)
    }

    /// Σ_p U_p F(q←p) with the exact point-to-polygon factor.
    fn exact(members: &[Member], q: DVec3, n: DVec3) -> DVec3 {
        members
            .iter()
            .map(|m| m.unshot * SourcePolygon::new(m.polygon()).form_factor(q, n))
            .sum()
    }

    /// The cluster kernel against the members' exact factors, from an oblique
    /// receiver at r = 6.05 R (just past the threshold) and at twice that.
    /// Expanding each member's kernel about the weighted centre, the error is
    /// second order: ½ Σ w_p δ_pᵀ H δ_p with |δ_p| ≤ R, and for the
    /// cos · cos / ρ² kernel |H| / K ≲ 6 / r² (3 from 1/ρ², ½ from each cosine,
    /// and their cross terms), so the bound is 3 (R/r)² ≈ 8% here; the 4 × 4
    /// grid's spread, Σ w |δ|² / S = R² / 3, makes it about 1 (R/r)² = 2.7%,
    /// the tolerance. Halving R/r must quarter the error (second order: a
    /// centre weighted wrongly would leave a first-order error that halves).
    #[test]
    fn cluster_kernel_matches_its_members() {
        let mut members = floor_grid();
        let tree = MemberTree::build(&mut members);
        let root = &tree.nodes[0];
        let direction = DVec3::new(0.5, 0.3, 1.0).normalize();
        let n = (-direction + DVec3::new(0.3, 0.0, 0.0)).normalize();
        let mut errors = Vec::new();
        for scale in [1.0, 2.0] {
            let r = scale * (CLUSTER_FAR * 2.0 + 0.05) * root.radius;
            let q = root.centre + direction * r;
            let (items, weights, gain) = cut(&tree, &members, q, n);
            assert_eq!(items, [far(0)]);
            let truth = exact(&members, q, n);
            let error = ((gain - truth) / truth).abs().max_element();
            let weight_error = (weights[0] / truth.element_sum() - 1.0).abs();
            let tolerance = (root.radius / r).powi(2);
            eprintln!("r = {:.2} R: colour error {error:.2e}, weight error {weight_error:.2e}, tolerance {tolerance:.2e}", r / root.radius);
            assert!(
                error < tolerance && weight_error < tolerance,
                "{error} {weight_error}"
            );
            errors.push(error);
            // The rays' expectation (every ray arrives) is that same gain:
            // a ray carries its member's colour, which varies about 3× over
            // the grid, so 20,000 draws have a relative standard error near
            // 0.4%; 2% is five of them.
            let mut rng = Rng::new(3, 0);
            let draws = 20_000;
            let mean = (0..draws)
                .map(|_| {
                    tree.ray(&members, cluster_of(items[0]), weights[0], q, n, &mut rng)
                        .unwrap()
                        .2
                })
                .sum::<DVec3>()
                * (weights[0] / draws as f64);
            let ray_error = ((mean - gain) / gain).abs().max_element();
            assert!(ray_error < 0.02, "rays {mean} against {gain}");
        }
        assert!(errors[1] < errors[0] / 3.0, "{errors:?}");
    }

    /// A node that straddles the receiver's horizon is sampled, and its rays
    /// are unbiased for the members' exact factors (the part of each member
    /// above the horizon, as `SourcePolygon` clips it): 200,000 draws, within
    /// 4 standard errors of their mean. No ray carries more than its member's
    /// colour, since the node's importance bounds S K.
    #[test]
    fn a_straddling_node_is_sampled_without_bias() {
        // Eight unit squares in the plane x = 0 facing +x, from z = −0.5 to
        // 0.5: half of each is below the receiver's horizon.
        let mut members: Vec<Member> = (0..8)
            .map(|k| {
                let y = k as f64;
                let c = [
                    DVec3::new(0.0, y, -0.5),
                    DVec3::new(0.0, y + 1.0, -0.5),
                    DVec3::new(0.0, y + 1.0, 0.5),
                    DVec3::new(0.0, y, 0.5),
                ];
                member(c, DVec3::X, colour(k), k as u32)
            })
            .collect();
        let tree = MemberTree::build(&mut members);
        let (q, n) = (DVec3::new(10.0, 4.0, 0.0), DVec3::Z);
        let (items, weights, _) = cut(&tree, &members, q, n);
        assert_eq!(items, [sampled(0)]);
        let draws = 200_000;
        let mut rng = Rng::new(7, 0);
        let (mut sum, mut squares) = (DVec3::ZERO, DVec3::ZERO);
        for _ in 0..draws {
            let estimate =
                match tree.ray(&members, cluster_of(items[0]), weights[0], q, n, &mut rng) {
                    Some((_, _, carried, _)) => {
                        let limit = members
                            .iter()
                            .map(|m| m.colour().max_element())
                            .fold(0.0, f64::max);
                        assert!(carried.max_element() <= limit * (1.0 + 1e-12), "{carried}");
                        carried * weights[0]
                    }
                    None => DVec3::ZERO,
                };
            sum += estimate;
            squares += estimate * estimate;
        }
        let mean = sum / draws as f64;
        let standard_error = ((squares / draws as f64 - mean * mean) / draws as f64).powf(0.5);
        let truth = exact(&members, q, n);
        eprintln!("sampled {mean} ± {standard_error}, exact {truth}");
        assert!(((mean - truth).abs() - standard_error * 4.0).max_element() < 0.0);
    }

    /// A 6 × 6 grid of members 0.3 apart, its centres tied in rows and
    /// columns, and the same grid moved 1e6 away and back (the rounding a
    /// solve of a translated scene sees after re-centring): the tree puts the
    /// members in the same order, so the cuts, and the mesh, do not depend on
    /// where the scene lies (test `translating_the_scene_by_1e6_gives_the_same_answer`
    /// holds this for the patch shooter). With the median taken on the raw
    /// keys the rounding broke the ties differently.
    #[test]
    fn the_tree_does_not_depend_on_rounding_of_tied_centres() {
        let grid = |shift: f64| -> Vec<Member> {
            (0..36)
                .map(|k| {
                    let (x, y) = (0.3 * (k % 6) as f64, 0.3 * (k / 6) as f64);
                    let moved = |v: DVec3| (v + DVec3::splat(shift)) - DVec3::splat(shift);
                    let c = [
                        DVec3::new(x, y, 0.0),
                        DVec3::new(x + 0.3, y, 0.0),
                        DVec3::new(x + 0.3, y + 0.3, 0.0),
                        DVec3::new(x, y + 0.3, 0.0),
                    ]
                    .map(moved);
                    member(c, DVec3::Z, colour(k), k as u32)
                })
                .collect()
        };
        let (mut near, mut far) = (grid(0.0), grid(1e6));
        let rounded = near.iter().zip(&far).any(|(a, b)| a.centre() != b.centre());
        assert!(rounded, "the round trip must change some coordinates");
        MemberTree::build(&mut near);
        MemberTree::build(&mut far);
        let order = |m: &[Member]| m.iter().map(|m| m.surface()).collect::<Vec<_>>();
        assert_eq!(order(&near), order(&far));
    }
}
