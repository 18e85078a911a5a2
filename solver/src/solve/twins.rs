//! Coincident vertices of a smooth surface receive once per shot (issue 13:
//! a scene's cost follows what it needs to show, not how many polygons it
//! was exported with).
//!
//! The mesh keeps each polygon's vertices apart (`mesh::Surface`), so a
//! point that six triangles of a smooth sphere share is six vertices, and a
//! shot used to receive at each of them: six samples of one radiance, at
//! receiving points a step apart inside the six triangles, with one shading
//! normal (`mesh::MeshVertex::normal`: both polygons interpolate the same
//! corner normals). On the 100k spheres room 240,670 of its 325,881
//! vertices are such copies. They now take the sample of
//! the first of them (the lowest vertex id), its rays counted once; the
//! output, which already merged them into one display vertex
//! (`seams.rs`), shows the same expected radiance.
//!
//! What it costs: the display vertex's shot noise is one receiver's, where
//! it was the mean of its copies' independent samples (up to six on a
//! triangle mesh). Copies are joined only when they agree exactly in
//! position, shading normal, material and hiddenness, so nothing is joined
//! that could receive differently; vertices that refinement adds later
//! receive on their own. The pieces of a polygon cut along contact lines
//! (`mesh::contact`), which share their seams as a smooth surface does, are
//! left alone: their seam points come from separate clipping arithmetic, so
//! which of them agree to the bit is an accident of rounding (the Cornell
//! box's solves are unchanged, and stay the same when the scene is moved).
//!
//! Directional mode builds none: its coefficients live in each polygon's
//! frame (`directional.rs`).

use crate::mesh::Mesh;

/// A vertex's entry in [`Twins::of`] when it receives on its own.
const OWN: u32 = u32::MAX;

/// Per vertex of the unrefined mesh, the vertex whose sample it copies.
#[derive(Default)]
pub struct Twins {
    /// Per vertex: the coincident vertex it copies, or [`OWN`]; empty when no
    /// vertex copies another.
    of: Vec<u32>,
    /// How many vertices copy another.
    copies: usize,
}

impl Twins {
    /// The copies among `mesh`'s vertices (see the module documentation);
    /// `hidden[v]` is vertex `v`'s hiddenness.
    pub fn new(mesh: &Mesh, hidden: &[bool]) -> Twins {
        let key = |v: u32| {
            let vertex = &mesh.vertices[v as usize];
            let surface = &mesh.surfaces[vertex.surface as usize];
            (
                surface.material,
                vertex.position.to_array().map(f64::to_bits),
                vertex.normal.to_array().map(f64::to_bits),
                hidden.get(v as usize).copied().unwrap_or(false),
            )
        };
        // Per input polygon, how many surfaces it became: more than one are
        // the pieces of a contact cut.
        let mut pieces: std::collections::HashMap<usize, u32> = Default::default();
        for surface in &mesh.surfaces {
            *pieces.entry(surface.polygon).or_default() += 1;
        }
        let mut smooth: Vec<u32> = (0..mesh.vertices.len() as u32)
            .filter(|&v| {
                let surface = &mesh.surfaces[mesh.vertices[v as usize].surface as usize];
                surface.corner_normals.is_some() && pieces[&surface.polygon] == 1
            })
            .collect();
        // Ties by id, so each run starts at its lowest vertex.
        smooth.sort_unstable_by_key(|&v| (key(v), v));
        let mut twins = Twins {
            of: vec![OWN; mesh.vertices.len()],
            copies: 0,
        };
        for run in smooth.chunk_by(|&a, &b| key(a) == key(b)) {
            for &v in &run[1..] {
                twins.of[v as usize] = run[0];
                twins.copies += 1;
            }
        }
        if twins.copies == 0 {
            twins.of = Vec::new();
        }
        twins
    }

    /// The vertex whose sample `v` copies, if it copies one.
    pub fn of(&self, v: u32) -> Option<u32> {
        match self.of.get(v as usize) {
            Some(&t) if t != OWN => Some(t),
            _ => None,
        }
    }

    /// The vertices the table covers: the unrefined mesh's, or none when no
    /// vertex copies another (the memory estimate).
    pub fn table_len(&self) -> usize {
        self.of.len()
    }

    /// How many vertices copy another's sample.
    pub fn copies(&self) -> usize {
        self.copies
    }

    /// The copies and the vertex each copies, in increasing vertex order.
    pub fn pairs(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.of
            .iter()
            .enumerate()
            .filter(|(_, &t)| t != OWN)
            .map(|(v, &t)| (v as u32, t))
    }

    /// The bytes the table holds as allocated (tests of the memory
    /// estimate).
    #[cfg(test)]
    pub fn allocated_bytes(&self) -> u64 {
        (self.of.capacity() * std::mem::size_of::<u32>()) as u64
    }

    /// The bytes the table holds for `vertices` vertices of the unrefined
    /// mesh (the memory estimate, `budget.rs`; none when no vertex copies).
    pub fn bytes(vertices: u64) -> u64 {
        vertices * std::mem::size_of::<u32>() as u64
    }
}

#[cfg(test)]
mod tests {
    use super::super::physics_tests::lit_room_with;
    use super::super::smooth_tests::facing;
    use super::super::Solver;
    use crate::scene::{smooth_scene, Scene};
    use crate::settings::{Preset, SolverSettings};
    use glam::DVec3;

    /// A 1 m room lit from a ceiling quad, with a gentle bump of `m` × `m`
    /// cells (two triangles each, facing up, at most 12° from level) above
    /// its floor: each grid point is computed once, so the triangles that
    /// share it share its bits, as an exported indexed mesh does.
    fn room_with_a_bump(m: usize) -> Scene {
        let h = 400.0 / m as f64;
        let at = |i: usize, j: usize| {
            let (x, z) = (300.0 + i as f64 * h, 300.0 + j as f64 * h);
            let r2 = ((x - 500.0).powi(2) + (z - 500.0).powi(2)) / (200.0 * 200.0);
            DVec3::new(x, 100.0 + 50.0 * (-r2).exp(), z)
        };
        let mut facets = Vec::new();
        for i in 0..m {
            for j in 0..m {
                let cell = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
                for t in [[0, 1, 2], [0, 2, 3]] {
                    facets.push(facing(t.map(|k| cell[k]).to_vec(), DVec3::Y));
                }
            }
        }
        let mut scene = lit_room_with(facets, "bump");
        smooth_scene(&mut scene, 30.0);
        scene
    }

    fn settings() -> SolverSettings {
        let mut s = SolverSettings::preset(Preset::Draft);
        s.adaptive = false;
        s.ambient = false;
        s.max_shots = 20;
        s
    }

    #[test]
    fn a_smooth_meshs_shared_points_receive_once() {
        // 2m² triangles, each one patch of one element at draft (their 71 mm
        // against a 260 mm patch), have 6m² corners at (m + 1)² points: all
        // but one vertex per point copies. The walls are flat and copy none.
        let m = 8;
        let scene = room_with_a_bump(m);
        let solver = Solver::new(&scene, &settings()).unwrap();
        let on_bump =
            |v: &crate::mesh::MeshVertex| solver.materials.kd[v.surface as usize].x == 0.7;
        assert_eq!(
            solver.mesh.vertices.iter().filter(|v| on_bump(v)).count(),
            6 * m * m
        );
        assert_eq!(solver.twin_copy_count(), 6 * m * m - (m + 1) * (m + 1));
        for (v, twin) in solver.sharing.twins.pairs() {
            let (a, b) = (
                &solver.mesh.vertices[v as usize],
                &solver.mesh.vertices[twin as usize],
            );
            assert!(twin < v && on_bump(a) && a.position == b.position && a.normal == b.normal);
        }
    }

    #[test]
    fn copies_carry_their_twins_radiance_and_trace_no_rays() {
        // After 20 shots every copy holds its twin's radiance to the bit (it
        // takes each ΔL whole).
        let scene = room_with_a_bump(8);
        let mut solver = Solver::new(&scene, &settings()).unwrap();
        while solver.step().is_some() {}
        let radiance = solver.vertex_radiance();
        for (v, twin) in solver.sharing.twins.pairs() {
            assert_eq!(radiance[v as usize], radiance[twin as usize], "vertex {v}");
        }
    }
}
