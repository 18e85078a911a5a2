//! Enclosing shells: a connected, closed surface, facing inward, whose
//! bounding box holds the rest of the scene's geometry (a skybox mesh, or an
//! ordinary closed room).
//!
//! Finding one is geometry alone ([`find_enclosing_shell`]); whether it is
//! worth a warning is the lights' business ([`ShellVerdict`]). A closed room
//! lit from inside (the Cornell box closed, an office with its lamps) is an
//! inward-facing shell around everything, and nothing is wrong with it. A
//! shell matters when
//!
//! * the scene is lit by a sun or a sky (or a lamp placed outside the shell):
//!   that light arrives from outside, and a closed shell stops every ray of
//!   it, so the scene inside stays black (VirtualCity.glb's skybox with a sun
//!   outside it); or
//! * its material is a skybox's: glTF `KHR_materials_unlit`, or an emission
//!   texture; a picture of a sky is then part of the geometry.
//!
//! The tests: the component's bounding box contains every other polygon's
//! within [`CONTAIN_TOLERANCE`] of the scene's diagonal; it is closed: the
//! edges whose reverse no polygon of it has (a hole's rim, a window's) make
//! at most [`CLOSED_TOLERANCE`] of its edges' length (a box without one face
//! scores 1/6, a 4 × 3 × 5 m room with a 0.5 m square window 2%); and it faces
//! inward, its signed volume (1/3) Σ A n · c below −[`INWARD_FILL`] times its
//! bounding box's volume (a cube's is −1 of it, a sphere's −0.52). A room
//! with an opening is not a shell: light comes in through it. T-junctions
//! (an edge met by two shorter ones) count as open, so a room modelled with
//! them is not reported: the test errs toward silence.

use super::Polygon;
use glam::DVec3;
use std::collections::HashMap;

/// How far, as a fraction of the scene's diagonal, the rest of the geometry
/// may reach out of a shell's bounding box.
pub const CONTAIN_TOLERANCE: f64 = 1e-3;
/// The largest length of unmatched edges, as a fraction of all edges' length,
/// of a closed surface (a few missing slivers of a "nearly" closed one).
pub const CLOSED_TOLERANCE: f64 = 0.005;
/// The least (negative) signed volume, as a fraction of the bounding box's,
/// of an inward-facing shell.
pub const INWARD_FILL: f64 = 0.25;

/// A shell found: its polygons (indices into the scene's) and bounds.
#[derive(Clone, Debug, PartialEq)]
pub struct Shell {
    pub polygons: Vec<usize>,
    pub lo: DVec3,
    pub hi: DVec3,
}

impl Shell {
    pub fn centre(&self) -> DVec3 {
        0.5 * (self.lo + self.hi)
    }
    /// Whether `point` lies inside the shell's bounding box.
    pub fn contains(&self, point: DVec3) -> bool {
        point.cmpge(self.lo).all() && point.cmple(self.hi).all()
    }
}

/// The polygons that share a vertex (to `diagonal` × 1e-7), as connected
/// components: each a list of polygon indices, in order.
fn components(polygons: &[Polygon], diagonal: f64) -> Vec<Vec<usize>> {
    let quantum = (diagonal * 1e-7).max(f64::MIN_POSITIVE);
    let mut parent: Vec<usize> = (0..polygons.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut first: HashMap<[i64; 3], usize> = HashMap::new();
    for (i, p) in polygons.iter().enumerate() {
        for v in &p.vertices {
            let key = (*v / quantum).round().to_array().map(|c| c as i64);
            let j = *first.entry(key).or_insert(i);
            let (a, b) = (root(&mut parent, i), root(&mut parent, j));
            if a != b {
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    let mut groups: HashMap<usize, Vec<usize>> = HashMap::new();
    for i in 0..polygons.len() {
        let r = root(&mut parent, i);
        groups.entry(r).or_default().push(i);
    }
    let mut out: Vec<Vec<usize>> = groups.into_values().collect();
    out.sort_unstable_by_key(|g| g[0]);
    out
}

/// The share of the edges' length of `group` whose reverse edge no polygon
/// of the group has (a consistently wound closed surface has none).
fn open_fraction(polygons: &[Polygon], group: &[usize], diagonal: f64) -> f64 {
    let quantum = (diagonal * 1e-7).max(f64::MIN_POSITIVE);
    let key = |v: DVec3| (v / quantum).round().to_array().map(|c| c as i64);
    let mut edges: HashMap<([i64; 3], [i64; 3]), f64> = HashMap::new();
    for &i in group {
        let v = &polygons[i].vertices;
        for k in 0..v.len() {
            let (a, b) = (v[k], v[(k + 1) % v.len()]);
            *edges.entry((key(a), key(b))).or_default() += (b - a).length();
        }
    }
    let total: f64 = edges.values().sum();
    let open: f64 = edges
        .iter()
        .filter(|((a, b), _)| !edges.contains_key(&(*b, *a)))
        .map(|(_, l)| l)
        .sum();
    if total > 0.0 {
        open / total
    } else {
        1.0
    }
}

fn bounds<'a>(polygons: impl Iterator<Item = &'a Polygon>) -> (DVec3, DVec3) {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for v in polygons.flat_map(|p| &p.vertices) {
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    (lo, hi)
}

/// The enclosing shell of `polygons` (see the module notes), if there is one
/// and something else for it to enclose.
pub fn find_enclosing_shell(polygons: &[Polygon], diagonal: f64) -> Option<Shell> {
    let tolerance = CONTAIN_TOLERANCE * diagonal;
    let (all_lo, all_hi) = bounds(polygons.iter());
    components(polygons, diagonal)
        .into_iter()
        .filter(|group| group.len() < polygons.len())
        .find_map(|group| {
            let (lo, hi) = bounds(group.iter().map(|&i| &polygons[i]));
            // Its box must reach the scene's box on every side.
            if (lo - all_lo).max_element() > tolerance || (all_hi - hi).max_element() > tolerance {
                return None;
            }
            let (mut area, mut volume) = (0.0, 0.0);
            let centre = 0.5 * (lo + hi);
            for &i in &group {
                let p = &polygons[i];
                let a = p.area();
                let c = p.vertices.iter().sum::<DVec3>() / p.vertices.len() as f64;
                area += a;
                volume += a * p.normal().dot(c - centre) / 3.0;
            }
            let size = hi - lo;
            let closed = open_fraction(polygons, &group, diagonal) <= CLOSED_TOLERANCE;
            let inward = volume < -INWARD_FILL * size.x * size.y * size.z;
            (area > 0.0 && closed && inward).then_some(Shell {
                polygons: group,
                lo,
                hi,
            })
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{MeshSizes, SourceRef};

    fn polygon(vertices: Vec<DVec3>) -> Polygon {
        Polygon {
            vertices,
            vertex_normals: None,
            material: 0,
            uv_map: None,
            patches: 1,
            sizes: MeshSizes::default(),
            source: SourceRef {
                file: "t".into(),
                line: None,
                item: String::new(),
            },
        }
    }

    /// The six faces of the box `lo`..`hi`, facing in (`inward`) or out.
    pub(crate) fn box_faces(lo: DVec3, hi: DVec3, inward: bool) -> Vec<Vec<DVec3>> {
        let s = hi - lo;
        let (x, y, z) = (DVec3::X * s.x, DVec3::Y * s.y, DVec3::Z * s.z);
        let face = |c: DVec3, a: DVec3, b: DVec3| vec![c, c + a, c + a + b, c + b];
        // Each facing in (counter-clockwise seen from inside).
        let faces = vec![
            face(lo, z, x),
            face(lo + y, x, z),
            face(lo, y, z),
            face(lo + x, z, y),
            face(lo, x, y),
            face(lo + z, y, x),
        ];
        if inward {
            faces
        } else {
            faces
                .into_iter()
                .map(|mut f| {
                    f.reverse();
                    f
                })
                .collect()
        }
    }

    fn scene(room: Vec<Vec<DVec3>>, block: Vec<Vec<DVec3>>) -> Vec<Polygon> {
        room.into_iter().chain(block).map(polygon).collect()
    }

    #[test]
    fn an_inward_closed_box_around_a_block_is_a_shell() {
        let polygons = scene(
            box_faces(DVec3::splat(-5.0), DVec3::splat(5.0), true),
            box_faces(DVec3::ZERO, DVec3::ONE, false),
        );
        let shell = find_enclosing_shell(&polygons, 17.3).expect("a shell");
        assert_eq!(shell.polygons, vec![0, 1, 2, 3, 4, 5]);
        assert!(shell.contains(DVec3::splat(0.5)));
    }

    #[test]
    fn open_outward_or_not_enclosing_boxes_are_not_shells() {
        let block = || box_faces(DVec3::ZERO, DVec3::ONE, false);
        let big = |inward| box_faces(DVec3::splat(-5.0), DVec3::splat(5.0), inward);
        // Outward-facing: a big block beside a small one.
        assert_eq!(
            find_enclosing_shell(&scene(big(false), block()), 17.3),
            None
        );
        // Open: one face missing (1/6 of the edges unmatched).
        let mut open = big(true);
        open.remove(1);
        assert_eq!(find_enclosing_shell(&scene(open, block()), 17.3), None);
        // The block reaches out of the box.
        let far = box_faces(DVec3::splat(4.0), DVec3::splat(6.0), false);
        assert_eq!(find_enclosing_shell(&scene(big(true), far), 17.3), None);
        // Two equal windows in opposite walls (their vector areas cancel):
        // open.
        // Each window's wall is a frame of four pieces around the hole.
        let mut windows = big(true);
        for wall in [3, 2] {
            let outer = windows.remove(wall);
            let c = outer.iter().sum::<DVec3>() / 4.0;
            let inner: Vec<DVec3> = outer.iter().map(|&v| c + (v - c) * 0.2).collect();
            for k in 0..4 {
                let next = (k + 1) % 4;
                windows.push(vec![outer[k], outer[next], inner[next], inner[k]]);
            }
        }
        assert_eq!(find_enclosing_shell(&scene(windows, block()), 17.3), None);
        // Nothing else in the scene: an empty room encloses nothing.
        assert_eq!(
            find_enclosing_shell(&scene(big(true), Vec::new()), 17.3),
            None
        );
    }
}
