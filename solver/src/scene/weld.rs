//! Welding (design notes, "Local frames and SH"): adjacent coplanar polygons of
//! the same material that share an edge become one polygon when their union is
//! a convex polygon, so a floor exported as two triangles is meshed as the quad
//! and a wall split into strips as one wall: one frame, no seam.
//!
//! Tolerance: vertices closer than [`WELD_TOLERANCE`] × the scene's bounding-box
//! diagonal are the same vertex, and two polygons are coplanar when every vertex
//! of their union lies within that distance of the union's Newell plane (and
//! their normals point the same way). For the Cornell box (diagonal 961 mm) that
//! is 0.0096 mm: far below modelling precision, far above the rounding of
//! coordinates written with 6 or more significant digits.
//!
//! Not welded: different materials or patch settings, curved polygons (with
//! vertex normals), unions that are not convex, or polygons that share more than
//! one edge. Collinear vertices left on the union's boundary (where two strips
//! met) are removed, as in cleaning; a neighbour that still has such a vertex on
//! its edge meets the welded polygon in a T-vertex, which the mesher must handle
//! anyway (Remington 1992, §3.4).

use super::clean::COLLINEAR_TOLERANCE;
use super::planar::is_convex;
use super::Polygon;
use crate::geometry::polygon::newell_normal;
use glam::DVec3;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Coincidence and coplanarity tolerance, relative to the scene's bounding-box
/// diagonal.
pub const WELD_TOLERANCE: f64 = 1e-5;

/// A small multiplicative hasher (FxHash's constant) for the integer keys here:
/// SipHash's DoS resistance buys nothing for keys derived from geometry, and it
/// made vertex sharing the slowest step of importing a large mesh.
#[derive(Default)]
pub(crate) struct IntHasher(u64);

impl Hasher for IntHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u32(&mut self, v: u32) {
        self.write_u64(u64::from(v));
    }
    fn write_i64(&mut self, v: i64) {
        self.write_u64(v as u64);
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

pub(crate) type IntMap<K, V> = HashMap<K, V, BuildHasherDefault<IntHasher>>;

/// Shared vertex ids: positions within `tol` of one another get one id. Cells
/// are 2·tol wide, so every position within `tol` of a point lies in the 2 × 2 × 2
/// block of cells nearest to it.
pub(crate) struct VertexIds {
    tol: f64,
    pub(crate) positions: Vec<DVec3>,
    grid: IntMap<(i64, i64, i64), Vec<u32>>,
}

impl VertexIds {
    pub(crate) fn new(tol: f64) -> Self {
        VertexIds {
            tol,
            positions: Vec::new(),
            grid: IntMap::default(),
        }
    }

    pub(crate) fn id(&mut self, p: DVec3) -> u32 {
        let scaled = p / (2.0 * self.tol);
        let cell = scaled.floor();
        // Toward the nearer neighbour along each axis.
        let step = (scaled - cell).cmplt(DVec3::splat(0.5));
        let near = |axis: usize| -> [i64; 2] {
            let c = cell[axis] as i64;
            [c, if step.test(axis) { c - 1 } else { c + 1 }]
        };
        let (xs, ys, zs) = (near(0), near(1), near(2));
        for x in xs {
            for y in ys {
                for z in zs {
                    if let Some(ids) = self.grid.get(&(x, y, z)) {
                        for &id in ids {
                            if (self.positions[id as usize] - p).length() <= self.tol {
                                return id;
                            }
                        }
                    }
                }
            }
        }
        let id = self.positions.len() as u32;
        self.positions.push(p);
        self.grid.entry((xs[0], ys[0], zs[0])).or_default().push(id);
        id
    }
}

/// Welds `polygons` in place (see the module comment).
pub(crate) fn weld(polygons: &mut Vec<Polygon>, scene_diagonal: f64) {
    let tol = WELD_TOLERANCE * scene_diagonal;
    if tol.is_nan() || tol <= 0.0 || polygons.len() < 2 {
        return;
    }
    let mut ids = VertexIds {
        tol,
        positions: Vec::new(),
        grid: IntMap::default(),
    };
    let mut index: Vec<Vec<u32>> = polygons
        .iter()
        .map(|p| p.vertices.iter().map(|&v| ids.id(v)).collect())
        .collect();
    let mut edges: IntMap<(u32, u32), usize> = IntMap::default();
    for (p, ring) in index.iter().enumerate() {
        for k in 0..ring.len() {
            edges.insert((ring[k], ring[(k + 1) % ring.len()]), p);
        }
    }
    let mut alive = vec![true; polygons.len()];
    let mut welded = vec![0usize; polygons.len()];
    let mut changed = true;
    while changed {
        changed = false;
        for p in 0..polygons.len() {
            'edges: loop {
                if !alive[p] || polygons[p].vertex_normals.is_some() {
                    break;
                }
                let ring = &index[p];
                for k in 0..ring.len() {
                    let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
                    let Some(&q) = edges.get(&(b, a)) else {
                        continue;
                    };
                    if q == p || !alive[q] || !compatible(&polygons[p], &polygons[q]) {
                        continue;
                    }
                    let Some((merged_ids, merged)) = merge(
                        &index[p],
                        &polygons[p].vertices,
                        k,
                        &index[q],
                        &polygons[q].vertices,
                        tol,
                    ) else {
                        continue;
                    };
                    for (r, ring) in [(p, &index[p]), (q, &index[q])] {
                        for i in 0..ring.len() {
                            let e = (ring[i], ring[(i + 1) % ring.len()]);
                            if edges.get(&e) == Some(&r) {
                                edges.remove(&e);
                            }
                        }
                    }
                    for i in 0..merged_ids.len() {
                        edges.insert((merged_ids[i], merged_ids[(i + 1) % merged_ids.len()]), p);
                    }
                    polygons[p].vertices = merged;
                    index[p] = merged_ids;
                    alive[q] = false;
                    welded[p] += 1 + welded[q];
                    changed = true;
                    continue 'edges;
                }
                break;
            }
        }
    }
    let mut k = 0;
    polygons.retain_mut(|polygon| {
        let keep = alive[k];
        if keep && welded[k] > 0 {
            polygon.source.item = format!("{} + {} welded", polygon.source.item, welded[k]);
        }
        k += 1;
        keep
    });
}

fn compatible(p: &Polygon, q: &Polygon) -> bool {
    p.material == q.material
        && p.patches == q.patches
        && p.sizes == q.sizes
        && p.vertex_normals.is_none()
        && q.vertex_normals.is_none()
        // Textured polygons keep their own UV maps (two triangles' fitted
        // maps agree only to rounding, and welding is an optimisation).
        && p.uv_map.is_none()
        && q.uv_map.is_none()
        && newell_normal(&p.vertices).dot(newell_normal(&q.vertices)) > 0.0
}

/// The union of P and Q across P's edge `k` (a → b), which Q has as b → a;
/// `None` unless it is planar within `tol`, simple and convex.
fn merge(
    p_ids: &[u32],
    p: &[DVec3],
    k: usize,
    q_ids: &[u32],
    q: &[DVec3],
    tol: f64,
) -> Option<(Vec<u32>, Vec<DVec3>)> {
    let (np, nq) = (p_ids.len(), q_ids.len());
    let (a, b) = (p_ids[k], p_ids[(k + 1) % np]);
    let j = (0..nq).find(|&j| q_ids[j] == b && q_ids[(j + 1) % nq] == a)?;
    // P from b round to a, then Q's vertices strictly after a and before b.
    let mut ids = Vec::with_capacity(np + nq - 2);
    let mut vertices = Vec::with_capacity(np + nq - 2);
    for t in 0..np {
        let i = (k + 1 + t) % np;
        ids.push(p_ids[i]);
        vertices.push(p[i]);
    }
    for t in 2..nq {
        let i = (j + t) % nq;
        ids.push(q_ids[i]);
        vertices.push(q[i]);
    }
    // Sharing two or more edges would make a vertex appear twice.
    if (1..ids.len()).any(|i| ids[..i].contains(&ids[i])) {
        return None;
    }
    let normal = newell_normal(&vertices).normalize_or_zero();
    if normal == DVec3::ZERO {
        return None;
    }
    let centroid = vertices.iter().copied().sum::<DVec3>() / vertices.len() as f64;
    if vertices
        .iter()
        .any(|v| (*v - centroid).dot(normal).abs() > tol)
    {
        return None;
    }
    // Drop vertices left in the middle of a straight edge.
    let mut i = 0;
    while i < vertices.len() && vertices.len() > 3 {
        let n = vertices.len();
        let (prev, cur, next) = (
            vertices[(i + n - 1) % n],
            vertices[i],
            vertices[(i + 1) % n],
        );
        let chord = next - prev;
        let length = chord.length();
        if length > 0.0
            && (cur - prev).cross(chord).length() / length <= COLLINEAR_TOLERANCE * length
        {
            vertices.remove(i);
            ids.remove(i);
            i = i.saturating_sub(1);
        } else {
            i += 1;
        }
    }
    is_convex(&vertices, normal).then_some((ids, vertices))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SourceRef;

    fn polygon(vertices: &[[f64; 3]], material: usize) -> Polygon {
        Polygon {
            vertices: vertices.iter().map(|&v| DVec3::from(v)).collect(),
            vertex_normals: None,
            uv_map: None,
            material,
            patches: 4,
            sizes: Default::default(),
            source: SourceRef {
                item: "face".to_owned(),
                ..Default::default()
            },
        }
    }

    #[test]
    fn two_triangles_become_the_quad() {
        let mut polygons = vec![
            polygon(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, -1.0]], 0),
            polygon(&[[0.0, 0.0, 0.0], [1.0, 0.0, -1.0], [0.0, 0.0, -1.0]], 0),
        ];
        weld(&mut polygons, 2.0f64.sqrt());
        assert_eq!(polygons.len(), 1);
        assert_eq!(polygons[0].vertices.len(), 4);
        assert!((polygons[0].area() - 1.0).abs() < 1e-15);
        assert_eq!(polygons[0].source.item, "face + 1 welded");
    }

    #[test]
    fn strips_become_one_wall_but_not_across_materials_or_into_an_l() {
        // Four 1 × 0.25 strips of a wall in the z = 0 plane, facing +z.
        let strip = |y0: f64, material| {
            polygon(
                &[
                    [0.0, y0, 0.0],
                    [1.0, y0, 0.0],
                    [1.0, y0 + 0.25, 0.0],
                    [0.0, y0 + 0.25, 0.0],
                ],
                material,
            )
        };
        let mut polygons = vec![strip(0.0, 0), strip(0.5, 0), strip(0.25, 0), strip(0.75, 0)];
        weld(&mut polygons, 2.0f64.sqrt());
        assert_eq!(polygons.len(), 1);
        let mut corners: Vec<[i64; 2]> = polygons[0]
            .vertices
            .iter()
            .map(|v| [(v.x * 4.0).round() as i64, (v.y * 4.0).round() as i64])
            .collect();
        corners.sort();
        assert_eq!(corners, vec![[0, 0], [0, 4], [4, 0], [4, 4]]);

        let mut mixed = vec![strip(0.0, 0), strip(0.25, 1)];
        weld(&mut mixed, 2.0f64.sqrt());
        assert_eq!(mixed.len(), 2, "different materials must not weld");

        // Two unit squares meeting along half an edge of a 2 × 1 rectangle: the
        // union would be an L (non-convex), so they stay apart.
        let mut l_shape = vec![
            polygon(
                &[
                    [0.0, 0.0, 0.0],
                    [2.0, 0.0, 0.0],
                    [2.0, 1.0, 0.0],
                    [1.0, 1.0, 0.0],
                    [0.0, 1.0, 0.0],
                ],
                0,
            ),
            polygon(
                &[
                    [0.0, 1.0, 0.0],
                    [1.0, 1.0, 0.0],
                    [1.0, 2.0, 0.0],
                    [0.0, 2.0, 0.0],
                ],
                0,
            ),
        ];
        weld(&mut l_shape, 3.0);
        assert_eq!(l_shape.len(), 2, "a non-convex union must not weld");
    }

    #[test]
    fn a_fold_is_not_welded() {
        // Two triangles sharing an edge, bent by 1e-3 of their size: beyond the
        // 1e-5 coplanarity tolerance.
        let mut polygons = vec![
            polygon(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 1e-3]], 0),
            polygon(&[[0.0, 0.0, 0.0], [1.0, 1.0, 1e-3], [0.0, 1.0, 0.0]], 0),
        ];
        weld(&mut polygons, 2.0f64.sqrt());
        assert_eq!(polygons.len(), 2);
    }
}
