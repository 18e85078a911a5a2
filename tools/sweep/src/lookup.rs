//! Per-vertex error: the reference solution sampled at each test vertex.
//!
//! A test solution's mesh differs from the reference's (other thresholds, other
//! noise), so vertices cannot be paired by index. Instead each test vertex is
//! located on the reference mesh (the triangle that contains it, same side, same
//! plane) and the reference's radiance toward a fixed eye is interpolated
//! barycentrically there, which is exactly what the renderers draw between
//! vertices (Gouraud). Radiance toward the fixed eye makes the error
//! view-dependent for glossy (SH) vertices; for diffuse vertices it is just the
//! vertex radiance. Each vertex is weighted by the area it stands for
//! ([`vertex_areas`]), so the figure is a surface average.

use crate::metrics::{relative_error_weighted, ErrorStats, MetricError};
use glam::DVec3;
use solution::format::Solution;
use solution::raster::shade_vertices;

/// A reference triangle, ready for point location.
struct Triangle {
    a: DVec3,
    /// Edges `b − a` and `c − a`.
    e1: DVec3,
    e2: DVec3,
    /// Unit face normal.
    normal: DVec3,
    radiance: [[f64; 3]; 3],
}

/// The reference mesh in a uniform grid, with its radiance toward one eye.
pub struct ReferenceLookup {
    triangles: Vec<Triangle>,
    origin: DVec3,
    cell: f64,
    dims: [usize; 3],
    /// Triangle indices per cell, `cells[(z * ny + y) * nx + x]`.
    cells: Vec<Vec<u32>>,
    /// Distance from a triangle's plane still counted as on it: 1e-5 of the
    /// scene's diagonal, well above f32 position rounding (~1e-7 relative) and
    /// well below the gap between any two distinct surfaces of the scenes.
    plane_tolerance: f64,
}

/// Per-vertex comparison result.
#[derive(Clone, Copy, Debug)]
pub struct VertexError {
    pub stats: ErrorStats,
    /// Test vertices that lie on no reference triangle (not compared).
    pub unmatched: usize,
    pub vertices: usize,
}

/// The most cells per axis: 64³ cells bound the grid's memory.
const MAX_CELLS_PER_AXIS: usize = 64;

impl ReferenceLookup {
    /// Builds the lookup; `eye` is in file (re-centred) coordinates.
    pub fn new(reference: &Solution, eye: DVec3) -> anyhow::Result<Self> {
        let mut triangles = Vec::new();
        for (index, batch) in reference.batches.iter().enumerate() {
            let radiance = shade_vertices(batch, u32::MAX, eye, true)
                .map_err(|e| anyhow::anyhow!("reference batch {index}: {e}"))?;
            let position = |i: u32| DVec3::from(batch.vertices[i as usize].position.map(f64::from));
            for t in batch.indices.chunks_exact(3) {
                if t.iter().any(|&i| i as usize >= batch.vertices.len()) {
                    anyhow::bail!("reference batch {index}: index out of range");
                }
                let a = position(t[0]);
                let e1 = position(t[1]) - a;
                let e2 = position(t[2]) - a;
                let cross = e1.cross(e2);
                if cross.length() == 0.0 {
                    continue; // Degenerate: covers no point.
                }
                triangles.push(Triangle {
                    a,
                    e1,
                    e2,
                    normal: cross.normalize(),
                    radiance: [0, 1, 2].map(|k| radiance[t[k] as usize].map(f64::from)),
                });
            }
        }
        let lo = DVec3::from(reference.header.bounds_min.map(f64::from));
        let hi = DVec3::from(reference.header.bounds_max.map(f64::from));
        let diagonal = (hi - lo).length().max(1e-30);
        let plane_tolerance = 1e-5 * diagonal;
        let pad = DVec3::splat(2.0 * plane_tolerance);
        let origin = lo - pad;
        let extent = hi - lo + 2.0 * pad;
        let cell = extent.max_element() / MAX_CELLS_PER_AXIS as f64;
        let dims = [extent.x, extent.y, extent.z]
            .map(|e| ((e / cell).ceil() as usize).clamp(1, MAX_CELLS_PER_AXIS));
        let mut cells = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        let mut lookup = ReferenceLookup {
            triangles: Vec::new(),
            origin,
            cell,
            dims,
            cells: Vec::new(),
            plane_tolerance,
        };
        for (k, t) in triangles.iter().enumerate() {
            let corners = [t.a, t.a + t.e1, t.a + t.e2];
            let tmin = corners[0].min(corners[1]).min(corners[2]) - pad;
            let tmax = corners[0].max(corners[1]).max(corners[2]) + pad;
            let (c0, c1) = (lookup.cell_of(tmin), lookup.cell_of(tmax));
            for z in c0[2]..=c1[2] {
                for y in c0[1]..=c1[1] {
                    for x in c0[0]..=c1[0] {
                        cells[(z * dims[1] + y) * dims[0] + x].push(k as u32);
                    }
                }
            }
        }
        lookup.triangles = triangles;
        lookup.cells = cells;
        Ok(lookup)
    }

    fn cell_of(&self, p: DVec3) -> [usize; 3] {
        let q = (p - self.origin) / self.cell;
        [q.x, q.y, q.z]
            .iter()
            .zip(self.dims)
            .map(|(&v, d)| (v.max(0.0) as usize).min(d - 1))
            .collect::<Vec<_>>()
            .try_into()
            .unwrap_or([0, 0, 0])
    }

    /// The reference radiance at point `p` on a surface facing `normal`, or
    /// `None` when no reference triangle holds it.
    pub fn radiance_at(&self, p: DVec3, normal: DVec3) -> Option<[f64; 3]> {
        let c = self.cell_of(p);
        let cell = &self.cells[(c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]];
        let mut best: Option<(f64, [f64; 3])> = None;
        for &k in cell {
            let t = &self.triangles[k as usize];
            // Same side of the same plane: a wall's two faces, or a block's
            // face touching the floor, must not borrow each other's light.
            if t.normal.dot(normal) < 0.9 {
                continue;
            }
            let d = p - t.a;
            if t.normal.dot(d).abs() > self.plane_tolerance {
                continue;
            }
            // Barycentric coordinates of p's projection (Ericson, Real-Time
            // Collision Detection §3.4).
            let (d00, d01, d11) = (t.e1.dot(t.e1), t.e1.dot(t.e2), t.e2.dot(t.e2));
            let (d20, d21) = (d.dot(t.e1), d.dot(t.e2));
            let denom = d00 * d11 - d01 * d01;
            if denom <= 0.0 {
                continue;
            }
            let v = (d11 * d20 - d01 * d21) / denom;
            let w = (d00 * d21 - d01 * d20) / denom;
            let u = 1.0 - v - w;
            let inside = u.min(v).min(w);
            // 1e-6 admits vertices on shared edges despite f32 rounding.
            if inside < -1e-6 {
                continue;
            }
            if best.is_none_or(|(b, _)| inside > b) {
                let r = t.radiance;
                let value = [0, 1, 2].map(|ch| u * r[0][ch] + v * r[1][ch] + w * r[2][ch]);
                best = Some((inside, value));
            }
        }
        best.map(|(_, v)| v)
    }

    /// Compares every vertex of `test` (radiance toward `eye`, file
    /// coordinates, the same eye as the lookup's) with the reference there.
    pub fn vertex_error(&self, test: &Solution, eye: DVec3) -> anyhow::Result<VertexError> {
        self.vertex_error_capped(test, eye, u32::MAX)
    }

    /// [`Self::vertex_error`] with the test's SH expansion cut at `max_order`
    /// (plain truncation, as `runtime screenshot --max-order` draws it).
    pub fn vertex_error_capped(
        &self,
        test: &Solution,
        eye: DVec3,
        max_order: u32,
    ) -> anyhow::Result<VertexError> {
        let mut reference = Vec::new();
        let mut values = Vec::new();
        let mut weights = Vec::new();
        let mut unmatched = 0;
        let mut vertices = 0;
        for (index, batch) in test.batches.iter().enumerate() {
            let radiance = shade_vertices(batch, max_order, eye, true)
                .map_err(|e| anyhow::anyhow!("test batch {index}: {e}"))?;
            let area = vertex_areas(batch);
            for ((vertex, rgb), &a) in batch.vertices.iter().zip(&radiance).zip(&area) {
                vertices += 1;
                let p = DVec3::from(vertex.position.map(f64::from));
                let n = DVec3::from(vertex.normal.map(f64::from));
                match self.radiance_at(p, n) {
                    Some(r) => {
                        reference.extend(r);
                        values.extend(rgb.map(f64::from));
                        weights.extend([a; 3]);
                    }
                    None => unmatched += 1,
                }
            }
        }
        let stats = relative_error_weighted(&reference, &values, Some(&weights)).map_err(
            |e: MetricError| anyhow::anyhow!("per-vertex comparison ({vertices} vertices): {e}"),
        )?;
        Ok(VertexError {
            stats,
            unmatched,
            vertices,
        })
    }
}

/// The surface area each vertex stands for: a third of each triangle it is a
/// corner of. Weighing the per-vertex error by it makes the figure a surface
/// average, not an average over wherever the adaptive mesher put vertices
/// (which is densest exactly where the radiance is hardest: penumbrae and
/// highlights).
fn vertex_areas(batch: &solution::format::Batch) -> Vec<f64> {
    let mut area = vec![0.0; batch.vertices.len()];
    let p = |i: u32| {
        batch
            .vertices
            .get(i as usize)
            .map(|v| DVec3::from(v.position.map(f64::from)))
    };
    for t in batch.indices.chunks_exact(3) {
        if let (Some(a), Some(b), Some(c)) = (p(t[0]), p(t[1]), p(t[2])) {
            let third = (b - a).cross(c - a).length() / 6.0;
            for &i in t {
                area[i as usize] += third;
            }
        }
    }
    area
}

#[cfg(test)]
mod tests {
    use super::*;
    use solution::format::{Batch, Header, Representation, ScalarType, SolveMode, Vertex};

    /// A unit square in z = 0 facing +z as two triangles, diffuse (order 0),
    /// with vertex radiance `corner(x, y)` (stored as the Y00 coefficient).
    fn square(corner: impl Fn(f64, f64) -> f64, subdivisions: u32) -> Solution {
        let n = subdivisions + 1;
        let mut vertices = Vec::new();
        let mut coefficients = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let (x, y) = (
                    i as f64 / subdivisions as f64,
                    j as f64 / subdivisions as f64,
                );
                vertices.push(Vertex {
                    position: [x as f32, y as f32, 0.0],
                    normal: [0.0, 0.0, 1.0],
                    tangent: [1.0, 0.0, 0.0],
                });
                let c = (corner(x, y) / solution::sh::Y00) as f32;
                coefficients.extend([c, c, c]);
            }
        }
        let mut indices = Vec::new();
        for j in 0..subdivisions {
            for i in 0..subdivisions {
                let v = j * n + i;
                indices.extend([v, v + 1, v + n + 1, v, v + n + 1, v + n]);
            }
        }
        Solution {
            lighting: None,
            header: Header {
                units_per_metre: 1.0,
                up_axis: Default::default(),
                recentre_offset: [0.0; 3],
                camera: Default::default(),
                bounds_min: [0.0, 0.0, 0.0],
                bounds_max: [1.0, 1.0, 0.0],
                partial: false,
                mode: SolveMode::Diffuse,
                stats: Default::default(),
                settings_json: String::new(),
            },
            batches: vec![Batch {
                representation: Representation::Sh { order: 0 },
                scalar: ScalarType::F32,
                vertices,
                coefficients,
                indices,
                texturing: None,
            }],
            textures: Vec::new(),
        }
    }

    #[test]
    fn linear_field_is_interpolated_exactly() {
        // Barycentric interpolation reproduces a linear field exactly, so a fine
        // test mesh of the same field has zero error against a coarse
        // reference (up to f32 storage: 1e-6 relative).
        let field = |x: f64, y: f64| 1.0 + 2.0 * x + 0.5 * y;
        let reference = square(field, 1);
        let test = square(field, 7);
        let eye = DVec3::new(0.5, 0.5, 2.0);
        let lookup = ReferenceLookup::new(&reference, eye).unwrap();
        let e = lookup.vertex_error(&test, eye).unwrap();
        assert_eq!(e.unmatched, 0);
        assert_eq!(e.vertices, 64);
        assert!(e.stats.rel_l1 < 1e-6, "{e:?}");
    }

    #[test]
    fn scaled_solution_has_the_scale_as_error() {
        // Every test vertex 1.2× the reference: rel_l1 = 0.2 (f32 storage:
        // 1e-6).
        let reference = square(|x, y| 1.0 + x + y, 4);
        let test = square(|x, y| 1.2 * (1.0 + x + y), 3);
        let eye = DVec3::new(0.5, 0.5, 2.0);
        let lookup = ReferenceLookup::new(&reference, eye).unwrap();
        let e = lookup.vertex_error(&test, eye).unwrap();
        assert!((e.stats.rel_l1 - 0.2).abs() < 1e-6, "{e:?}");
    }

    #[test]
    fn points_off_the_surface_or_facing_away_are_unmatched() {
        let reference = square(|_, _| 1.0, 2);
        let lookup = ReferenceLookup::new(&reference, DVec3::new(0.5, 0.5, 2.0)).unwrap();
        let up = DVec3::Z;
        assert!(lookup.radiance_at(DVec3::new(0.3, 0.3, 0.0), up).is_some());
        assert!(lookup.radiance_at(DVec3::new(0.3, 0.3, 0.01), up).is_none());
        assert!(lookup.radiance_at(DVec3::new(0.3, 0.3, 0.0), -up).is_none());
        assert!(lookup.radiance_at(DVec3::new(1.3, 0.3, 0.0), up).is_none());
    }
}
