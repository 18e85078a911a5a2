//! Directional mode's batches in the solution file: one per SH order, the
//! coefficients shown at hidden vertices filled from their neighbours, and
//! the seams of cut receivers shared.

use super::Directional;
use crate::solve::hidden::fill_hidden;
use crate::solve::seams::{share_vertices, Lone, Merge};
use crate::solve::Solver;
use glam::DVec3;
use solution::format::{Batch, Representation, ScalarType, Solution, Vertex};
use std::collections::BTreeMap;
use std::f64::consts::PI;

impl Solver {
    /// Replaces the order-0 batch of a diffuse-style solution with one batch
    /// per SH order (vertices of L = 0 materials in the order-0 batch, glossy
    /// ones in their order's), so the runtime draws per order. `ambient` is
    /// added to c₀₀ as Kd · ambient, as in the diffuse output.
    pub(in crate::solve) fn directional_batches(&self, solution: &mut Solution, ambient: DVec3) {
        let Some(d) = self.directional.as_deref() else {
            return;
        };
        solution.header.mode = solution::format::SolveMode::Directional;
        let scale = (4.0 * PI).sqrt();
        let triangles = self.mesh.triangles();
        let mut radiance = self.displayed_coefficients(d, &triangles);
        // The pieces of a receiver cut along contact lines share their seams
        // (`seams.rs`): their SH are in their polygon's frame, so vertices of
        // different polygons never merge, even on one smooth surface (see
        // "Frames on smooth surfaces"); every other vertex maps to itself.
        let shared = share_vertices(&self.mesh, &|_, _| None, Merge::WithinPolygons);
        let range = |v| d.vertex_range(&self.mesh, v);
        shared.merge_values(&self.mesh, range, &mut radiance, Lone::Kept);
        // Per order: the batch and the map from output vertex to batch vertex.
        let mut batches: BTreeMap<u32, Batch> = BTreeMap::new();
        let mut local = vec![u32::MAX; shared.representative.len()];
        for (o, &r) in shared.representative.iter().enumerate() {
            let mv = &self.mesh.vertices[r as usize];
            // The block that holds the output vertex's merged value (the
            // representative's: without UVs, lighting groups are outputs).
            let v = shared.value_vertex(o);
            // Textured surfaces (diffuse or emission textures) have batches
            // of their own (below).
            if self.directional_shown(d, mv.surface as usize).is_some() {
                continue;
            }
            let order = d.surface_order[mv.surface as usize];
            let s = &self.mesh.surfaces[mv.surface as usize];
            let batch = batches.entry(order).or_insert_with(|| Batch {
                representation: Representation::Sh { order },
                scalar: ScalarType::F32,
                vertices: Vec::new(),
                coefficients: Vec::new(),
                indices: Vec::new(),
                texturing: None,
            });
            local[o] = batch.vertices.len() as u32;
            let f = |x: DVec3| x.as_vec3().to_array();
            batch.vertices.push(Vertex {
                position: f(mv.position),
                normal: f(s.normal),
                tangent: f(s.tangent),
            });
            let start = batch.coefficients.len();
            batch.coefficients.extend(
                radiance[d.vertex_range(&self.mesh, v)]
                    .iter()
                    .map(|&c| c as f32),
            );
            let c00 = DVec3::from_slice(&radiance[d.vertex_offset[v]..d.vertex_offset[v] + 3])
                + self.materials.kd[mv.surface as usize] * ambient * scale;
            batch.coefficients[start..start + 3].copy_from_slice(&c00.as_vec3().to_array());
        }
        for t in shared.triangles(&triangles) {
            let first = shared.representative[t[0] as usize];
            let surface = self.mesh.vertices[first as usize].surface as usize;
            if self.directional_shown(d, surface).is_some() {
                continue;
            }
            let order = d.surface_order[surface];
            if let Some(batch) = batches.get_mut(&order) {
                batch.indices.extend(t.iter().map(|&v| local[v as usize]));
            }
        }
        solution.batches = batches.into_values().collect();
        self.textured_directional_batches(d, solution, ambient);
    }

    /// The radiance coefficients to display: the solver's, with each hidden
    /// vertex (`solve/hidden.rs`) shown as its visible neighbours' functions
    /// extended ring by ring along the display `triangles`
    /// ([`fill_hidden`]), as the diffuse output does.
    pub(super) fn displayed_coefficients(
        &self,
        d: &Directional,
        triangles: &[[u32; 3]],
    ) -> Vec<f64> {
        let mut values = d.radiance.clone();
        let count = self.mesh.vertices.len();
        let range = |v| d.vertex_range(&self.mesh, v);
        fill_hidden(triangles, &self.field.hidden, count, range, &mut values);
        values
    }
}
