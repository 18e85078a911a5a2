//! Smooth surfaces: which polygons of a scene are facets of one curved surface,
//! and the shading normal at each of their corners.
//!
//! Two polygons belong to one smooth surface (a *smooth group*, the transitive
//! closure of the test below) when they
//!
//! * have the same material,
//! * share an edge by position: both end points within [`SMOOTH_TOLERANCE`] ×
//!   the scene's bounding-box diagonal (the welding tolerance: 0.0096 mm on the
//!   Cornell box's 961 mm diagonal), traversed in opposite directions (the
//!   same front side),
//! * meet at a dihedral angle below the crease angle (the `crease_angle`
//!   setting, [`DEFAULT_CREASE_ANGLE`] degrees): their face normals differ by
//!   less than it,
//! * and are not separated by a UV seam. The scene carries no texture
//!   coordinates yet, so [`uv_seam`] is always false; when UVs arrive it is the
//!   one place that splits a group along a seam.
//!
//! Each polygon of a group of two or more gets a shading normal per corner
//! ([`super::Polygon::vertex_normals`]): the OBJ's `vn` when the polygon has
//! them and they are consistent (every corner within the crease angle of the
//! face normal; else they are ignored, with one warning per object), otherwise
//! the angle-weighted mean of the face normals of the group's polygons at that
//! position (Thürmer and Wüthrich 1998, "Computing vertex normals from polygonal
//! meshes"). Angle weights rather than area weights because they do not depend on
//! how a region is cut into polygons: a flat face split into a fan of thin
//! triangles and one split into two halves give the same normal at a corner,
//! while area weights would lean toward whichever neighbour happened to be cut
//! coarser. The mean runs over the polygon's *fan* at that position: the
//! polygons reached from it across smooth edges that end there. All of a fan
//! share one normal (so the output merges their vertices), and a crease that
//! runs into a vertex keeps the fans on its two sides apart.
//!
//! Shared corners are snapped to one position (the first polygon's), so the
//! mesher, the output and the path tracer see bit-identical positions on both
//! sides of an edge. The mesh interpolates these corner normals to every
//! vertex (`mesh::MeshVertex::normal`), the solver receives with them, the
//! output merges coincident vertices of equal shading normal into one
//! (`solve/output.rs`), and the path tracer interpolates the same corner normals
//! over the hit triangle (`reference/scene.rs`).
//!
//! A crease angle of 0 is the flat-facet mode: every polygon shades with its
//! own face normal, the OBJ's `vn` are dropped, and nothing is shared.

use super::weld::{IntMap, VertexIds, WELD_TOLERANCE};
use super::{Polygon, Scene, SourceRef, Warning};
use crate::geometry::polygon::newell_normal;
use glam::DVec3;
use std::collections::BTreeSet;

/// The default crease angle, degrees: the usual default of modelling tools
/// (Blender's auto smooth, Maya's soften edge). A tessellated sphere or
/// cylinder needs fewer than 12 segments around before its facets meet at more
/// than 30°, and the right angles of rooms and boxes stay sharp.
pub const DEFAULT_CREASE_ANGLE: f64 = 30.0;

/// Coincidence tolerance of shared corners, relative to the scene's
/// bounding-box diagonal: the welding tolerance (see [`WELD_TOLERANCE`]).
pub const SMOOTH_TOLERANCE: f64 = WELD_TOLERANCE;

/// What [`smooth_scene`] found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SmoothReport {
    /// Smooth groups of two or more polygons.
    pub groups: usize,
    /// Polygons in those groups.
    pub polygons: usize,
    /// Polygons that shade with their OBJ `vn`.
    pub with_input_normals: usize,
    /// One per object whose `vn` were ignored.
    pub warnings: Vec<Warning>,
}

/// Finds the smooth groups of `scene` at `crease_angle` degrees and gives their
/// polygons corner shading normals (see the module comment); 0 (or less)
/// makes every polygon flat.
pub fn smooth_scene(scene: &mut Scene, crease_angle: f64) -> SmoothReport {
    let mut report = SmoothReport::default();
    let polygons = &mut scene.polygons;
    if crease_angle.is_nan() || crease_angle <= 0.0 {
        for p in polygons.iter_mut() {
            p.vertex_normals = None;
        }
        return report;
    }
    let tol = SMOOTH_TOLERANCE * scene_diagonal(polygons);
    let cos_crease = crease_angle.min(90.0).to_radians().cos();
    let mut ids = VertexIds::new(tol.max(f64::MIN_POSITIVE));
    let rings: Vec<Vec<u32>> = polygons
        .iter()
        .map(|p| p.vertices.iter().map(|&v| ids.id(v)).collect())
        .collect();
    let face_normals: Vec<DVec3> = polygons
        .iter()
        .map(|p| newell_normal(&p.vertices).normalize_or_zero())
        .collect();
    // A polygon with two corners within the tolerance (a sliver) has a
    // degenerate edge in this welding: it stays out of every group.
    let usable: Vec<bool> = rings
        .iter()
        .zip(&face_normals)
        .map(|(ring, n)| {
            *n != DVec3::ZERO && (1..ring.len()).all(|i| !ring[..i].contains(&ring[i]))
        })
        .collect();
    let mut groups = UnionFind::new(polygons.len());
    let mut edges: IntMap<(u32, u32), Vec<usize>> = IntMap::default();
    // Per undirected edge, the polygon pairs joined across it.
    let mut smooth_edges: IntMap<(u32, u32), Vec<(usize, usize)>> = IntMap::default();
    for (p, ring) in rings.iter().enumerate().filter(|(p, _)| usable[*p]) {
        for k in 0..ring.len() {
            edges
                .entry((ring[k], ring[(k + 1) % ring.len()]))
                .or_default()
                .push(p);
        }
    }
    for (p, ring) in rings.iter().enumerate().filter(|(p, _)| usable[*p]) {
        for k in 0..ring.len() {
            let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
            for &q in edges.get(&(b, a)).into_iter().flatten() {
                if q != p
                    && polygons[p].material == polygons[q].material
                    && face_normals[p].dot(face_normals[q]) >= cos_crease
                    && !uv_seam(&polygons[p], &polygons[q])
                {
                    groups.union(p, q);
                    smooth_edges
                        .entry((a.min(b), a.max(b)))
                        .or_default()
                        .push((p, q));
                }
            }
        }
    }
    let mut size = vec![0usize; polygons.len()];
    for p in 0..polygons.len() {
        size[groups.find(p)] += 1;
    }
    let mut incident: IntMap<u32, Vec<(usize, usize)>> = IntMap::default();
    for (p, ring) in rings.iter().enumerate().filter(|(p, _)| usable[*p]) {
        for (k, &id) in ring.iter().enumerate() {
            incident.entry(id).or_default().push((p, k));
        }
    }
    let mut warned: BTreeSet<String> = BTreeSet::new();
    for p in 0..polygons.len() {
        let root = groups.find(p);
        let grouped = usable[p] && size[root] >= 2;
        if grouped && p == root {
            report.groups += 1;
        }
        let input = polygons[p].vertex_normals.take();
        let consistent = input
            .as_ref()
            .is_some_and(|n| n.iter().all(|n| n.dot(face_normals[p]) >= cos_crease));
        if input.is_some() && !consistent {
            let object = object_of(&polygons[p].source);
            if warned.insert(object.clone()) {
                report.warnings.push(Warning {
                    source: polygons[p].source.clone(),
                    message: format!(
                        "vertex normals: some `vn` of {object} differ from their face's normal by \
                         more than the crease angle ({crease_angle}°); its `vn` are ignored and \
                         shading normals are computed from the faces"
                    ),
                });
            }
        }
        if consistent {
            report.with_input_normals += 1;
            polygons[p].vertex_normals = input;
        } else if grouped {
            let normals = (0..rings[p].len())
                .map(|k| {
                    let id = rings[p][k];
                    let fan = fan_of(&rings, &incident[&id], &smooth_edges, id, p);
                    corner_normal(polygons, &face_normals, &fan, p)
                })
                .collect();
            polygons[p].vertex_normals = Some(normals);
        }
        if grouped {
            report.polygons += 1;
            for (v, &id) in polygons[p].vertices.iter_mut().zip(&rings[p]) {
                *v = ids.positions[id as usize];
            }
        }
    }
    report
}

/// Whether a UV seam runs between `p` and `q`: polygons carry no texture
/// coordinates yet, so never. Where they do, a shared edge whose two sides
/// have different UVs splits the group here.
fn uv_seam(_p: &Polygon, _q: &Polygon) -> bool {
    false
}

/// The corners at one position (`at`, all the polygons with a corner at
/// vertex `id`) that lie in `p`'s fan there: those reached from `p` by crossing
/// smooth edges that end at `id`. Every polygon of a fan gets the same normal
/// there, so the output can merge the fan's vertices; two fans at one position
/// (a cone's tip where a crease runs in, a group that bends further than the
/// crease angle around a vertex) keep different normals.
fn fan_of(
    rings: &[Vec<u32>],
    at: &[(usize, usize)],
    smooth_edges: &IntMap<(u32, u32), Vec<(usize, usize)>>,
    id: u32,
    p: usize,
) -> Vec<(usize, usize)> {
    let index_of = |q: usize| at.iter().position(|&(r, _)| r == q);
    let mut fan = UnionFind::new(at.len());
    for &(q, k) in at {
        let ring = &rings[q];
        let n = ring.len();
        for other in [ring[(k + n - 1) % n], ring[(k + 1) % n]] {
            for &(a, b) in smooth_edges
                .get(&(id.min(other), id.max(other)))
                .into_iter()
                .flatten()
            {
                if let (Some(i), Some(j)) = (index_of(a), index_of(b)) {
                    fan.union(i, j);
                }
            }
        }
    }
    let own = index_of(p).map(|i| fan.find_const(i));
    at.iter()
        .enumerate()
        .filter(|(i, _)| Some(fan.find_const(*i)) == own)
        .map(|(_, c)| *c)
        .collect()
}

/// The angle-weighted mean of the face normals of the corners `fan` (`p`'s
/// fan at one position), or `p`'s own normal if it degenerates.
fn corner_normal(
    polygons: &[Polygon],
    face_normals: &[DVec3],
    fan: &[(usize, usize)],
    p: usize,
) -> DVec3 {
    let mut sum = DVec3::ZERO;
    for &(q, c) in fan {
        sum += corner_angle(&polygons[q].vertices, c) * face_normals[q];
    }
    sum.try_normalize().unwrap_or(face_normals[p])
}

/// The interior angle of a polygon at corner `k`, radians.
fn corner_angle(vertices: &[DVec3], k: usize) -> f64 {
    let n = vertices.len();
    let a = (vertices[(k + n - 1) % n] - vertices[k]).normalize_or_zero();
    let b = (vertices[(k + 1) % n] - vertices[k]).normalize_or_zero();
    a.dot(b).clamp(-1.0, 1.0).acos()
}

fn scene_diagonal(polygons: &[Polygon]) -> f64 {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for v in polygons.iter().flat_map(|p| &p.vertices) {
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    if lo.x > hi.x {
        0.0
    } else {
        (hi - lo).length()
    }
}

/// The object a polygon came from, for one warning per object: the OBJ object
/// or group its face came from (the importer names faces "face N of object
/// NAME"), else its file.
fn object_of(source: &SourceRef) -> String {
    match source.item.split_once(" of object ") {
        Some((_, name)) => format!("object {name}"),
        None => source.file.display().to_string(),
    }
}

/// Disjoint sets of indices (polygons here, surfaces in `solve::sites`), by
/// parent pointers with path halving.
pub(crate) struct UnionFind {
    parent: Vec<usize>,
}

impl UnionFind {
    pub(crate) fn new(n: usize) -> Self {
        UnionFind {
            parent: (0..n).collect(),
        }
    }

    pub(crate) fn find(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }

    /// [`UnionFind::find`] without path halving, for shared borrows.
    fn find_const(&self, mut i: usize) -> usize {
        while self.parent[i] != i {
            i = self.parent[i];
        }
        i
    }

    /// Joins the sets of `a` and `b`; the smaller index becomes the root, so
    /// roots (and the group count) do not depend on the order of unions.
    pub(crate) fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = (ra.min(rb), ra.max(rb));
            self.parent[hi] = lo;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use solution::camera::UpAxis;

    fn polygon(vertices: Vec<DVec3>, normals: Option<Vec<DVec3>>, item: &str) -> Polygon {
        Polygon {
            vertices,
            vertex_normals: normals,
            uv_map: None,
            material: 0,
            patches: 1,
            sizes: Default::default(),
            source: SourceRef {
                item: item.to_owned(),
                ..Default::default()
            },
        }
    }

    fn scene(polygons: Vec<Polygon>) -> Scene {
        Scene {
            lights: Default::default(),
            polygons,
            materials: Vec::new(),
            units_per_metre: 1.0,
            up_axis: UpAxis::PosY,
            camera: None,
            recentre_offset: DVec3::ZERO,
            warnings: Vec::new(),
        }
    }

    /// Two unit squares sharing the edge x = 0, z ∈ [0, 1], folded by
    /// `degrees` about it; both face +y (before the fold).
    fn fold(degrees: f64) -> Vec<Polygon> {
        let (c, s) = (degrees.to_radians().cos(), degrees.to_radians().sin());
        let a = vec![
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(-1.0, 0.0, 1.0),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(0.0, 0.0, 0.0),
        ];
        let b = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(c, s, 1.0),
            DVec3::new(c, s, 0.0),
        ];
        vec![polygon(a, None, "a"), polygon(b, None, "b")]
    }

    #[test]
    fn folds_below_the_crease_angle_are_smooth_and_above_are_sharp() {
        for (degrees, smooth) in [(10.0, true), (29.0, true), (31.0, false), (90.0, false)] {
            let mut s = scene(fold(degrees));
            let report = smooth_scene(&mut s, 30.0);
            assert_eq!(report.groups, usize::from(smooth), "{degrees}°");
            assert_eq!(s.polygons[0].vertex_normals.is_some(), smooth);
            if smooth {
                // On the shared edge both sides get the bisector (two right
                // angles, equal weights); at the far edges their own normal.
                let n = s.polygons[0].vertex_normals.as_ref().unwrap();
                let m = s.polygons[1].vertex_normals.as_ref().unwrap();
                let half = (degrees / 2.0f64).to_radians();
                let bisector = DVec3::new(-half.sin(), half.cos(), 0.0);
                assert!(n[2].angle_between(bisector) < 1e-12, "{:?}", n[2]);
                assert!(m[1].angle_between(bisector) < 1e-12, "{:?}", m[1]);
                assert!(n[0].angle_between(DVec3::Y) < 1e-12);
            }
        }
        // Different materials never join, and crease 0 is flat.
        let mut s = scene(fold(10.0));
        s.polygons[1].material = 1;
        assert_eq!(smooth_scene(&mut s, 30.0).groups, 0);
        let mut s = scene(fold(10.0));
        assert_eq!(smooth_scene(&mut s, 0.0).groups, 0);
        assert!(s.polygons.iter().all(|p| p.vertex_normals.is_none()));
    }

    #[test]
    fn inconsistent_input_normals_are_ignored_with_one_warning_per_object() {
        // Both faces of object "o" carry `vn` 60° off their faces (beyond the
        // 30° crease): ignored, one warning, computed normals instead. A third
        // face of object "p" carries consistent ones (10° off): kept.
        let mut polygons = fold(10.0);
        let off = DVec3::new(60f64.to_radians().sin(), 60f64.to_radians().cos(), 0.0);
        for (p, item) in polygons
            .iter_mut()
            .zip(["face 1 of object o", "face 2 of object o"])
        {
            p.vertex_normals = Some(vec![off; 4]);
            p.source.item = item.to_owned();
        }
        let tilted = DVec3::new(10f64.to_radians().sin(), 10f64.to_radians().cos(), 0.0);
        let far = vec![
            DVec3::new(5.0, 0.0, 0.0),
            DVec3::new(5.0, 0.0, 1.0),
            DVec3::new(6.0, 0.0, 1.0),
            DVec3::new(6.0, 0.0, 0.0),
        ];
        polygons.push(polygon(far, Some(vec![tilted; 4]), "face 3 of object p"));
        let mut s = scene(polygons);
        let report = smooth_scene(&mut s, 30.0);
        assert_eq!(report.warnings.len(), 1, "{:?}", report.warnings);
        assert!(report.warnings[0].message.contains("object o"));
        assert_eq!(report.with_input_normals, 1);
        assert_eq!(s.polygons[2].vertex_normals, Some(vec![tilted; 4]));
        let n = s.polygons[0].vertex_normals.as_ref().unwrap();
        assert!(n[0].angle_between(DVec3::Y) < 1e-12);
    }

    #[test]
    fn corners_within_the_tolerance_are_shared_and_snapped() {
        // The second square's shared corners are 1e-7 off (the tolerance is
        // 1e-5 of the ≈ 2.3 diagonal): joined, and moved onto the first's.
        let mut polygons = fold(10.0);
        for v in polygons[1].vertices.iter_mut().filter(|v| v.x == 0.0) {
            v.x += 1e-7;
        }
        let mut s = scene(polygons);
        assert_eq!(smooth_scene(&mut s, 30.0).groups, 1);
        assert_eq!(s.polygons[1].vertices[0], s.polygons[0].vertices[3]);
        assert_eq!(s.polygons[1].vertices[1], s.polygons[0].vertices[2]);
    }
}
