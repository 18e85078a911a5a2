//! Sky portals found in the geometry (issue 41): the openings of a closed
//! room, such as a window cut in a wall or an open roof, become portals
//! (`portal.rs`) when a scene has a sky and declares none.
//!
//! An opening is a loop of boundary edges: edges that one polygon uses and
//! no other. Vertices are matched as the welder matches them (within
//! `WELD_TOLERANCE` of the scene's diagonal), and an edge that another
//! polygon's vertex splits (a T-vertex, which welding leaves behind) is
//! split there first, so that a long edge matches the short ones along it.
//! A loop is kept when:
//! - it is planar, within [`PLANARITY_TOLERANCE`] of its size;
//! - its area is at least [`MIN_OPENING_AREA`] of the scene's diagonal
//!   squared (a crack lets in too little sky to be worth half of a
//!   receiver's sky rays);
//! - it is a hole, not an outer rim: the surface that meets it in its own
//!   plane lies outside the loop (a wall around a window), not inside it (a
//!   ground plane's outer edge), by edge length; surface across its plane
//!   (the walls under an open roof) counts for neither;
//! - nothing covers it: no polygon in its plane holds a point inside it (the
//!   open bottom of a column that stands on a floor).
//!
//! Each kept loop becomes the smallest rectangle around it in its plane (the
//! loop itself when it is a rectangle), whose normal points into the room:
//! the side the surface beside it faces, or, for surface across its plane,
//! the side that surface lies on. Only the [`MAX_DETECTED_PORTALS`] largest
//! are kept.
//!
//! Work, for E edges: matching vertices is linear (the welder's grid);
//! matching edges sorts them, O(E log E); splitting the open edges visits
//! grid cells of about their mean length along each, within a budget
//! proportional to their count that stops the search (with a note) on
//! pathological input; a loop of k vertices gets its rectangle in
//! O(k log k); the cover test is linear in the polygons for each of at most
//! [`MAX_COVER_CHECKS`] loops. The 56,000-polygon `atrium` scene takes 0.07 s.

use super::portal::Portal;
use crate::geometry::polygon::newell_normal;
use crate::mesh::contact::convex_hull;
use crate::scene::planar::bbox_diagonal;
use crate::scene::{IntMap, VertexIds, WELD_TOLERANCE};
use glam::{DVec2, DVec3};

/// The most portals detected in one scene: each portal a receiver faces
/// takes a share of its sky rays, and a few dozen openings (the windows of
/// a facade) are covered well enough by their largest.
pub const MAX_DETECTED_PORTALS: usize = 16;

/// A loop is planar when no vertex is farther from its plane than this
/// fraction of its size: exporters' rounding (1e-7 of a coordinate in f32)
/// passes by far, a boundary that bends around a corner (a tenth of its
/// size or more) does not.
pub const PLANARITY_TOLERANCE: f64 = 1e-3;

/// The smallest opening made a portal, as a fraction of the scene's
/// bounding-box diagonal squared: a 10 cm square in a 10 m scene.
pub const MIN_OPENING_AREA: f64 = 1e-4;

/// The surface beside a loop is "in its plane" when its direction away from
/// the edge leaves the plane by less than 30° (sine 0.5).
const IN_PLANE_SINE: f64 = 0.5;

/// How many of the largest loops are tested for a cover.
pub const MAX_COVER_CHECKS: usize = 64;

/// Grid cells looked up per open edge, on average, before splitting at
/// T-vertices gives up.
const CELLS_PER_OPEN_EDGE: usize = 1024;

/// `[sky] portals = "auto" | "none"` in a scene config.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PortalMode {
    /// Detect portals when the scene has a sky and declares none.
    #[default]
    Auto,
    /// Never detect portals.
    Off,
}

impl PortalMode {
    pub fn parse(value: &str) -> Option<PortalMode> {
        match value {
            "auto" => Some(PortalMode::Auto),
            "none" => Some(PortalMode::Off),
            _ => None,
        }
    }
}

/// What detection found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Detection {
    /// The portals, largest first, each marked detected.
    pub portals: Vec<Portal>,
    /// Something the user should know: openings left out, or a search that
    /// gave up.
    pub note: Option<String>,
}

/// The portals of the openings of `polygons` (each counter-clockwise seen
/// from its front, in one frame), in a scene whose bounding-box diagonal is
/// `diagonal` (see the module comment).
pub fn detect_portals(polygons: &[&[DVec3]], diagonal: f64) -> Detection {
    let tol = WELD_TOLERANCE * diagonal;
    if !(tol.is_finite() && tol > 0.0) {
        return Detection::default();
    }
    let mut ids = VertexIds::new(tol);
    let mut sides = Vec::new();
    for (p, polygon) in polygons.iter().enumerate() {
        let ring: Vec<u32> = polygon.iter().map(|&v| ids.id(v)).collect();
        for k in 0..ring.len() {
            let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
            if a != b {
                sides.push(Side {
                    a,
                    b,
                    polygon: p as u32,
                });
            }
        }
    }
    let positions = std::mem::take(&mut ids.positions);
    // The grid of every vertex is not needed past here.
    drop(ids);
    let open = unmatched(sides);
    let Some(pieces) = split_at_t_junctions(&open, &positions, tol) else {
        return Detection {
            portals: Vec::new(),
            note: Some(format!(
                "{} open edges are too many to search for openings; no portals detected \
                 (declare them as [[portals]])",
                open.len()
            )),
        };
    };
    let boundary = unmatched(pieces);
    let normals: Vec<DVec3> = polygons
        .iter()
        .map(|p| newell_normal(p).normalize_or_zero())
        .collect();
    let geometry = Geometry {
        positions: &positions,
        normals: &normals,
        boundary: &boundary,
        diagonal,
    };
    let mut openings: Vec<Opening> = loops(&boundary)
        .iter()
        .filter_map(|walk| geometry.opening(walk))
        .collect();
    openings.sort_by(|a, b| b.area.total_cmp(&a.area));
    select(&openings, polygons, &normals, tol)
}

/// An edge of a polygon, from vertex id `a` to `b` in the polygon's order.
#[derive(Clone, Copy, Debug)]
struct Side {
    a: u32,
    b: u32,
    polygon: u32,
}

/// The sides no other side matches (the same two vertices, either way), in
/// the order of their vertex ids: sorting keeps the peak memory at the
/// sides themselves, where a hash map of counts would double it.
fn unmatched(mut sides: Vec<Side>) -> Vec<Side> {
    let key = |s: &Side| (s.a.min(s.b), s.a.max(s.b));
    sides.sort_unstable_by_key(key);
    let mut out = Vec::new();
    let mut i = 0;
    while i < sides.len() {
        let run = sides[i..]
            .iter()
            .take_while(|s| key(s) == key(&sides[i]))
            .count();
        if run == 1 {
            out.push(sides[i]);
        }
        i += run;
    }
    out
}

/// Each open side cut at the open sides' ends that lie on it (within `tol`
/// of the segment, strictly between its ends). `None` when the search runs
/// past its budget.
fn split_at_t_junctions(open: &[Side], positions: &[DVec3], tol: f64) -> Option<Vec<Side>> {
    if open.is_empty() {
        return Some(Vec::new());
    }
    let length = |s: &Side| (positions[s.b as usize] - positions[s.a as usize]).length();
    let cell_size = (open.iter().map(length).sum::<f64>() / open.len() as f64).max(4.0 * tol);
    let cell = |p: DVec3| {
        let c = (p / cell_size).floor();
        (c.x as i64, c.y as i64, c.z as i64)
    };
    let mut ends: Vec<u32> = open.iter().flat_map(|s| [s.a, s.b]).collect();
    ends.sort_unstable();
    ends.dedup();
    let mut grid: IntMap<(i64, i64, i64), Vec<u32>> = IntMap::default();
    for &id in &ends {
        grid.entry(cell(positions[id as usize]))
            .or_default()
            .push(id);
    }
    let mut budget = CELLS_PER_OPEN_EDGE.saturating_mul(open.len());
    let mut spend = |n: usize| -> Option<()> {
        budget = budget.checked_sub(n)?;
        Some(())
    };
    let (mut out, mut cells, mut cuts) = (Vec::with_capacity(open.len()), Vec::new(), Vec::new());
    for side in open {
        let a = positions[side.a as usize];
        let d = positions[side.b as usize] - a;
        // Every point of the segment is within half a step of a sample, so
        // its cell is next to the sample's: the 27 cells about each sample
        // hold every end within `tol` of the segment.
        let steps = (d.length() / cell_size).ceil().max(1.0);
        spend((27.0 * (steps + 1.0)).min(usize::MAX as f64) as usize)?;
        cells.clear();
        for k in 0..=steps as usize {
            let (x, y, z) = cell(a + d * (k as f64 / steps));
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        cells.push((x + dx, y + dy, z + dz));
                    }
                }
            }
        }
        cells.sort_unstable();
        cells.dedup();
        cuts.clear();
        for c in &cells {
            let Some(list) = grid.get(c) else { continue };
            spend(list.len())?;
            for &id in list {
                let p = positions[id as usize];
                let t = (p - a).dot(d) / d.length_squared();
                let on = t > 0.0 && t < 1.0 && (a + d * t - p).length() <= tol;
                if on && id != side.a && id != side.b {
                    cuts.push((t, id));
                }
            }
        }
        cuts.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut from = side.a;
        for &(_, id) in cuts.iter().chain([(1.0, side.b)].iter()) {
            if id != from {
                out.push(Side {
                    b: id,
                    a: from,
                    ..*side
                });
                from = id;
            }
        }
    }
    Some(out)
}

/// The closed loops the boundary sides make, each as (side index, whether
/// it is walked from `a` to `b`) in order. A walk continues with a side
/// that starts where it stands when there is one (a consistently oriented
/// surface), else with any unused side there; walks that end open are
/// dropped.
fn loops(boundary: &[Side]) -> Vec<Vec<(usize, bool)>> {
    let mut at: IntMap<u32, Vec<usize>> = IntMap::default();
    for (i, s) in boundary.iter().enumerate() {
        at.entry(s.a).or_default().push(i);
        at.entry(s.b).or_default().push(i);
    }
    let mut used = vec![false; boundary.len()];
    let mut loops = Vec::new();
    for start in 0..boundary.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        let first = boundary[start].a;
        let mut here = boundary[start].b;
        let mut walk = vec![(start, true)];
        while here != first {
            let free = at.get(&here).map_or(&[][..], |v| v.as_slice());
            let next = free
                .iter()
                .copied()
                .find(|&j| !used[j] && boundary[j].a == here)
                .or_else(|| free.iter().copied().find(|&j| !used[j]));
            let Some(j) = next else { break };
            used[j] = true;
            let forward = boundary[j].a == here;
            here = if forward {
                boundary[j].b
            } else {
                boundary[j].a
            };
            walk.push((j, forward));
        }
        if here == first && walk.len() >= 3 {
            loops.push(walk);
        }
    }
    loops
}

/// A loop that passed the tests of its own shape: its portal, its area,
/// its plane's normal, and a point inside it (for the cover test) when one
/// was found.
struct Opening {
    portal: Portal,
    area: f64,
    normal: DVec3,
    probe: Option<DVec3>,
}

/// What the loop tests read.
struct Geometry<'a> {
    positions: &'a [DVec3],
    normals: &'a [DVec3],
    boundary: &'a [Side],
    diagonal: f64,
}

impl Geometry<'_> {
    /// The opening `walk` makes, if it is a large enough planar hole.
    fn opening(&self, walk: &[(usize, bool)]) -> Option<Opening> {
        let points: Vec<DVec3> = walk
            .iter()
            .map(|&(j, forward)| {
                let s = self.boundary[j];
                self.positions[if forward { s.a } else { s.b } as usize]
            })
            .collect();
        let centre = points.iter().copied().sum::<DVec3>() / points.len() as f64;
        let rel: Vec<DVec3> = points.iter().map(|p| *p - centre).collect();
        let twice = newell_normal(&rel);
        let area = 0.5 * twice.length();
        // A NaN area (non-finite input) is refused too.
        if area.is_nan() || area < MIN_OPENING_AREA * self.diagonal * self.diagonal {
            return None;
        }
        let n = twice / (2.0 * area);
        let size = bbox_diagonal(&rel);
        if rel
            .iter()
            .any(|p| p.dot(n).abs() > PLANARITY_TOLERANCE * size)
        {
            return None;
        }
        let inward = self.inward_side(walk, &rel, n)?;
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        let flat: Vec<DVec2> = rel.iter().map(|p| DVec2::new(p.dot(u), p.dot(v))).collect();
        let rectangle = min_area_rectangle(&convex_hull(&flat))?;
        let mut corners: Vec<DVec3> = rectangle
            .iter()
            .map(|c| centre + u * c.x + v * c.y)
            .collect();
        // The rectangle is counter-clockwise about n; Portal's normal
        // follows its corners' order.
        if inward < 0.0 {
            corners.reverse();
        }
        let portal = Portal::new(&corners).ok()?.into_detected();
        let probe = point_inside(&flat, size).map(|p| centre + u * p.x + v * p.y);
        Some(Opening {
            portal,
            area,
            normal: n,
            probe,
        })
    }

    /// Whether the loop is a hole, and if so the side of its plane (about
    /// `n`, its counter-clockwise normal) the room is on, as a signed
    /// weight; `None` for an outer rim. See the module comment.
    fn inward_side(&self, walk: &[(usize, bool)], rel: &[DVec3], n: DVec3) -> Option<f64> {
        let (mut hole, mut rim, mut side) = (0.0, 0.0, 0.0);
        for (k, &(j, _)) in walk.iter().enumerate() {
            let e = rel[(k + 1) % rel.len()] - rel[k];
            let length = e.length();
            let s = self.boundary[j];
            let front = self.normals[s.polygon as usize];
            let own = self.positions[s.b as usize] - self.positions[s.a as usize];
            // Into the polygon from its edge: left of the edge about its
            // front, for a counter-clockwise polygon.
            let into = front.cross(own).normalize_or_zero();
            let lift = into.dot(n);
            if lift.abs() < IN_PLANE_SINE {
                let out_of_loop = e.cross(n);
                if into.dot(out_of_loop) > 0.0 {
                    hole += length;
                } else {
                    rim += length;
                }
                side += length * front.dot(n);
            } else {
                side += length * lift;
            }
        }
        (hole >= rim).then_some(if side < 0.0 { -1.0 } else { 1.0 })
    }
}

/// The smallest-area rectangle around the convex, counter-clockwise `hull`,
/// counter-clockwise: one of its sides lies on a side of the hull (Freeman
/// and Shapira 1975), found by rotating calipers (Toussaint 1983) in O(k).
pub(super) fn min_area_rectangle(hull: &[DVec2]) -> Option<[DVec2; 4]> {
    let n = hull.len();
    if n < 3 {
        return None;
    }
    // Moves `index` on while the next point scores higher: each score is
    // unimodal along a convex hull, and its maximum turns with the edge.
    let climb = |index: &mut usize, score: &dyn Fn(DVec2) -> f64| {
        for _ in 0..n {
            let next = (*index + 1) % n;
            if score(hull[next]) > score(hull[*index]) {
                *index = next;
            } else {
                break;
            }
        }
    };
    let (mut far, mut top, mut near) = (1, 1, 1);
    let mut best: Option<(f64, [DVec2; 4])> = None;
    for i in 0..n {
        let a = hull[i];
        let d = (hull[(i + 1) % n] - a).normalize_or_zero();
        if d == DVec2::ZERO {
            continue;
        }
        let m = d.perp();
        climb(&mut far, &|p| (p - a).dot(d));
        if i == 0 {
            top = far;
        }
        climb(&mut top, &|p| (p - a).dot(m));
        if i == 0 {
            near = top;
        }
        climb(&mut near, &|p| -(p - a).dot(d));
        let (lo, hi) = ((hull[near] - a).dot(d), (hull[far] - a).dot(d));
        let height = (hull[top] - a).dot(m);
        let area = (hi - lo) * height;
        if best.as_ref().is_none_or(|(b, _)| area < *b) {
            let base = [a + d * lo, a + d * hi];
            best = Some((
                area,
                [base[0], base[1], base[1] + m * height, base[0] + m * height],
            ));
        }
    }
    best.map(|(_, r)| r)
}

/// Whether `q` is inside the simple polygon `ring` (even-odd rule).
fn contains(ring: &[DVec2], q: DVec2) -> bool {
    let mut inside = false;
    for i in 0..ring.len() {
        let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
        if (a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
    }
    inside
}

/// A point inside the counter-clockwise `ring` of size `size`: its area
/// centroid when that is inside, else its longest side's midpoint moved in
/// by 1e-3 of the size; `None` when neither is.
fn point_inside(ring: &[DVec2], size: f64) -> Option<DVec2> {
    let n = ring.len();
    let (mut twice, mut moment) = (0.0, DVec2::ZERO);
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        let cross = a.perp_dot(b);
        twice += cross;
        moment += (a + b) * cross;
    }
    let centroid = moment / (3.0 * twice);
    if centroid.is_finite() && contains(ring, centroid) {
        return Some(centroid);
    }
    let i = (0..n).max_by(|&i, &j| {
        let len = |k: usize| (ring[(k + 1) % n] - ring[k]).length_squared();
        len(i).total_cmp(&len(j))
    })?;
    let (a, b) = (ring[i], ring[(i + 1) % n]);
    let nudged = (a + b) * 0.5 + (b - a).normalize_or_zero().perp() * (1e-3 * size);
    contains(ring, nudged).then_some(nudged)
}

/// Whether a polygon in the opening's plane (normal within 1e-6 in cosine,
/// within 10 `tol` of the probe) holds the probe.
fn covered(probe: DVec3, n: DVec3, polygons: &[&[DVec3]], normals: &[DVec3], tol: f64) -> bool {
    polygons.iter().zip(normals).any(|(polygon, front)| {
        if front.dot(n).abs() < 1.0 - 1e-6 || (polygon[0] - probe).dot(n).abs() > 10.0 * tol {
            return false;
        }
        let u = front.any_orthonormal_vector();
        let v = front.cross(u);
        let flat = |p: DVec3| DVec2::new((p - probe).dot(u), (p - probe).dot(v));
        let ring: Vec<DVec2> = polygon.iter().map(|&p| flat(p)).collect();
        contains(&ring, DVec2::ZERO)
    })
}

/// The portals of the largest uncovered openings (`openings` sorted by
/// area, largest first), with a note when some were left out.
fn select(openings: &[Opening], polygons: &[&[DVec3]], normals: &[DVec3], tol: f64) -> Detection {
    let mut portals = Vec::new();
    let mut checked = 0;
    for o in openings {
        if portals.len() == MAX_DETECTED_PORTALS || checked == MAX_COVER_CHECKS {
            break;
        }
        checked += 1;
        if o.probe
            .is_some_and(|p| covered(p, o.normal, polygons, normals, tol))
        {
            continue;
        }
        portals.push(o.portal.clone());
    }
    let left = openings.len() - checked;
    let note = (left > 0).then(|| {
        format!(
            "{} openings found in the geometry; the {} largest open ones are sky portals, \
             the {left} smaller ones are not (declare [[portals]] to choose)",
            openings.len(),
            portals.len()
        )
    });
    Detection { portals, note }
}
