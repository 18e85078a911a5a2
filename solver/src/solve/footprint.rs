//! A shot's footprint: the surfaces it changed, so that the passes of a
//! diffuse step after the shooting (refinement's candidate scan, the gather
//! into patches and the reset of the vertices' ΔL) visit those surfaces only,
//! not the whole scene (issue 13: a shot whose cost does not grow with the
//! whole scene).
//!
//! Every per-vertex quantity a shot changes lives on one surface: a vertex
//! belongs to one surface (`MeshVertex::surface`), an element's corners and
//! the T-vertices on its sides are its own surface's (the mesh's vertex keys
//! name the surface), and so are the vertices a patch's gather weights name.
//! A surface none of whose vertices received anything therefore has no leaf
//! with a changed corner and no patch whose unshot radiance changes: skipping
//! it changes no bit of the solve. The shot itself visits every vertex
//! (Remington 1992's progressive refinement); the passes after it visit the
//! surfaces *touched* by the shot (where a vertex received something), in
//! increasing order of patch and element, and add exactly what the
//! whole-scene passes added, in the same order, so they shrink where walls
//! keep a shot in one room. When a shot touched more than half of the
//! patches, one pass in order over everything is cheaper than the
//! per-surface lists and is taken instead. Either way the bits are the same
//! (test `sparse_passes_match_whole_scene`).
//!
//! The index costs 4 bytes per vertex (one `u32` in its surface's list) plus a
//! list header per surface.

use super::group_shot::Shooter;
use super::refine::VertexState;
use super::shoot::{Received, Scratch};
use super::sites::Sites;
use super::small::SmallSurfaces;
use super::twins::Twins;
use super::Solver;
use crate::mesh::Mesh;
use glam::DVec3;
use rayon::prelude::*;

/// Per surface, its vertex ids in increasing order. Vertices are only ever
/// appended to the mesh (splits, a resume's replay of them), so the index
/// catches up from the last vertex it saw.
#[derive(Default)]
pub(super) struct SurfaceVertices {
    lists: Vec<Vec<u32>>,
    indexed: usize,
}

impl SurfaceVertices {
    /// Indexes the vertices added to `mesh` since the last call.
    pub fn catch_up(&mut self, mesh: &Mesh) {
        if self.lists.len() < mesh.surfaces.len() {
            self.lists.resize_with(mesh.surfaces.len(), Vec::new);
        }
        for v in self.indexed..mesh.vertices.len() {
            self.lists[mesh.vertices[v].surface as usize].push(v as u32);
        }
        self.indexed = mesh.vertices.len();
    }

    /// Per surface of `mesh`, the length its list has once it has caught up
    /// with the mesh (for the memory estimate, `budget.rs`): O(surfaces +
    /// the vertices not yet indexed).
    pub fn lengths(&self, mesh: &Mesh) -> Vec<u64> {
        let mut lengths = vec![0u64; mesh.surfaces.len()];
        for (n, list) in lengths.iter_mut().zip(&self.lists) {
            *n = list.len() as u64;
        }
        for v in &mesh.vertices[self.indexed.min(mesh.vertices.len())..] {
            lengths[v.surface as usize] += 1;
        }
        lengths
    }

    /// The bytes the lists hold as allocated: their capacities, a heap block
    /// overhead for each non-empty one and their headers (tests of the
    /// memory estimate).
    #[cfg(test)]
    pub fn allocated_bytes(&self) -> u64 {
        let blocks = self.lists.iter().filter(|l| l.capacity() > 0).count() as u64;
        self.lists
            .iter()
            .map(|l| (l.capacity() * std::mem::size_of::<u32>()) as u64)
            .sum::<u64>()
            + blocks * super::budget::HEAP_BLOCK_OVERHEAD
            + (self.lists.capacity() * std::mem::size_of::<Vec<u32>>()) as u64
    }

    /// The vertices of surface `s`.
    pub fn of(&self, s: u32) -> &[u32] {
        self.lists.get(s as usize).map_or(&[], |l| l.as_slice())
    }
}

/// The per-shot sets, reused from shot to shot.
#[derive(Default)]
pub(super) struct Footprint {
    pub surface_vertices: SurfaceVertices,
    /// Per surface: whether this shot touched it.
    marked: Vec<bool>,
    /// The touched surfaces, in the order they were marked.
    touched: Vec<u32>,
    /// Tests only: run every pass over the whole scene, as before the
    /// footprint, to check that the sparse passes change nothing.
    #[cfg(test)]
    pub whole_scene: bool,
    /// Tests only: never fall back to whole-scene passes, however much the
    /// shot touched, so that a small scene exercises the sparse ones.
    #[cfg(test)]
    pub always_sparse: bool,
}

impl Footprint {
    fn whole_scene(&self) -> bool {
        #[cfg(test)]
        return self.whole_scene;
        #[cfg(not(test))]
        false
    }

    fn always_sparse(&self) -> bool {
        #[cfg(test)]
        return self.always_sparse;
        #[cfg(not(test))]
        false
    }

    /// The lengths of the per-surface marks and the touched list (tests of
    /// the memory estimate).
    #[cfg(test)]
    pub fn set_lengths(&self) -> (usize, usize) {
        (self.marked.len(), self.touched.len())
    }

    fn begin_shot(&mut self, surfaces: usize) {
        self.marked.clear();
        self.marked.resize(surfaces, false);
        self.touched.clear();
    }

    /// Marks surface `s` as touched. Marking a surface whose vertices all
    /// received exactly 0 costs a pass over it and changes nothing.
    fn mark(&mut self, s: u32) {
        if !self.marked[s as usize] {
            self.marked[s as usize] = true;
            self.touched.push(s);
        }
    }
}

/// Where one sample serves several vertices: a small flat surface's (`small.rs`),
/// coincident vertices of a smooth surface (`twins.rs`) and the points of a
/// finely tessellated smooth surface that interpolate sites (`sites.rs`).
#[derive(Clone, Copy)]
pub(super) struct SampleSharing<'a> {
    pub small: &'a SmallSurfaces,
    pub twins: &'a Twins,
    pub sites: &'a Sites,
}

/// Shoots `shooter` to every vertex and adds each one's ΔL to its radiance
/// (and to its recorded-shot part when `recorded`); a small surface's
/// vertices all get the one sample at its centroid (`small.rs`), a point
/// that interpolates sites takes their weighted mean (`sites.rs`) and a
/// vertex that the twins name a copy takes the sample of the vertex it
/// copies (`twins.rs`). Marks the surfaces touched; returns the rays.
/// (A free function: the shot borrows the solver's occluder and
/// reflectances.)
pub(super) fn shoot_receivers(
    mesh: &Mesh,
    footprint: &mut Footprint,
    sharing: SampleSharing<'_>,
    mut state: VertexState<'_>,
    shooter: &Shooter,
    recorded: bool,
) -> u64 {
    let SampleSharing {
        small,
        twins,
        sites,
    } = sharing;
    footprint.surface_vertices.catch_up(mesh);
    footprint.begin_shot(mesh.surfaces.len());
    // Radiance before the shot, for the ray share (`ray_share.rs`): results
    // are added only after every receiver has been shot.
    let prior: &[DVec3] = state.radiance;
    let small_results = receive_small(mesh, &footprint.surface_vertices, small, shooter, prior);
    let small_rays: u64 = small_results.iter().map(|r| r.rays as u64).sum();
    // A small surface's vertices copy its sample; its rays count once.
    let receive = |scratch: &mut Scratch, v: u32| match small.of(mesh.vertices[v as usize].surface)
    {
        Some(k) => Received {
            rays: 0,
            ..small_results[k]
        },
        None => shooter.receive(mesh, v, scratch, Some(prior)),
    };
    let mut results: Vec<Received> = (0..mesh.vertices.len() as u32)
        .into_par_iter()
        .map_init(Scratch::default, |scratch, v| {
            if twins.of(v).is_some() || sites.interpolates(v) {
                Received::default()
            } else {
                receive(scratch, v)
            }
        })
        .collect();
    interpolate_sites(&mut results, sites);
    copy_twins(&mut results, twins);
    // Flat shooting visits every vertex; the surfaces it touched are
    // those where one received something (read in vertex order, so the
    // surface ids stream from memory).
    for (vertex, r) in mesh.vertices.iter().zip(&results) {
        if r.radiance != DVec3::ZERO {
            footprint.mark(vertex.surface);
        }
    }
    add_received(&mut state, 0.., &results, recorded) + small_rays
}

/// Gives each point that interpolates sites the weighted mean of their
/// results (`sites.rs`), and the visibility of the site that weighs most
/// (sources come heaviest first); it traces no rays. `results` is indexed by
/// vertex; sites never interpolate, so their results are final.
fn interpolate_sites(results: &mut [Received], sites: &Sites) {
    for (v, sources) in sites.sources() {
        // Linear-precision weights may be slightly negative (`sites.rs`).
        let radiance = sources
            .iter()
            .map(|&(s, w)| results[s as usize].radiance * w as f64)
            .sum::<DVec3>()
            .max(DVec3::ZERO);
        results[v as usize] = Received {
            radiance,
            visible: results[sources[0].0 as usize].visible,
            rays: 0,
        };
    }
}

/// Gives each copy its twin's result (`twins.rs`); `results` is indexed by
/// vertex. The rays count once, at the twin.
fn copy_twins(results: &mut [Received], twins: &Twins) {
    for (v, twin) in twins.pairs() {
        results[v as usize] = Received {
            rays: 0,
            ..results[twin as usize]
        };
    }
}

/// One sample per small surface, at its centroid (see `small.rs`), in the
/// order of `small.points()`; a surface with no vertex gets nothing and
/// traces nothing. Its level for the ray
/// share is its vertices' mean radiance before the shot.
fn receive_small(
    mesh: &Mesh,
    index: &SurfaceVertices,
    small: &SmallSurfaces,
    shooter: &Shooter,
    prior: &[DVec3],
) -> Vec<Received> {
    small
        .points()
        .par_iter()
        .map_init(Scratch::default, |scratch, at| {
            let vertices = index.of(at.surface);
            if vertices.is_empty() {
                return Received::default();
            }
            let level =
                vertices.iter().map(|&v| prior[v as usize]).sum::<DVec3>() / vertices.len() as f64;
            shooter.receive_at(mesh, at, scratch, Some(level))
        })
        .collect()
}

/// Adds the shot's `results` at `vertices` (same order); returns the rays.
fn add_received(
    state: &mut VertexState<'_>,
    vertices: impl Iterator<Item = u32>,
    results: &[Received],
    recorded: bool,
) -> u64 {
    let mut rays = 0u64;
    for (v, r) in vertices.zip(results) {
        let v = v as usize;
        state.radiance[v] += r.radiance;
        state.received[v] = r.radiance;
        state.visible[v] = r.visible;
        if recorded {
            state.direct[v] += r.radiance;
        }
        rays += r.rays as u64;
    }
    rays
}

impl Solver {
    /// The patches of the surfaces this shot touched so far, in increasing
    /// order: refinement's candidates lie on them, and only their unshot
    /// radiance can change (see the module documentation). `None`: every
    /// patch, when the shot may have touched every surface or touched more
    /// than half of the patches, where one pass over the whole scene in
    /// order is cheaper than the lists (and gives the same bits).
    pub(super) fn touched_patches(&self) -> Option<Vec<u32>> {
        if self.sharing.footprint.whole_scene() {
            return None;
        }
        let count: usize = self
            .sharing
            .footprint
            .touched
            .iter()
            .map(|&s| self.patches.of_surface[s as usize].len())
            .sum();
        if 2 * count > self.mesh.patches.len() && !self.sharing.footprint.always_sparse() {
            return None;
        }
        let mut surfaces = self.sharing.footprint.touched.clone();
        surfaces.sort_unstable();
        Some(
            surfaces
                .iter()
                .flat_map(|&s| self.patches.of_surface[s as usize].clone())
                .collect(),
        )
    }

    /// Adds each touched patch's share of the shot's ΔL to its unshot
    /// radiance and clears the touched vertices' ΔL: U_p += Σ_v w_vp ΔL_v / A_p,
    /// so π U_p A_p grows by exactly the received power the display shows on
    /// the patch. Hidden vertices are left out and A_p is then the visible
    /// part's area (`patch_shoot_area`): U_p is the visible part's mean, and
    /// the shot's visibility rays, blocked toward the hidden part, deliver its
    /// power. Untouched patches would add exactly 0 (see the module
    /// documentation).
    pub(super) fn gather(&mut self) {
        self.sharing.footprint.surface_vertices.catch_up(&self.mesh);
        let touched = self.touched_patches();
        let patches: Vec<u32> = match &touched {
            Some(patches) => patches.clone(),
            None => (0..self.mesh.patches.len() as u32).collect(),
        };
        let (received, hidden) = (&self.field.received, &self.field.hidden);
        let (weights, rgb_weights) = (&self.patches.weights, &self.patches.rgb_weights);
        let sums: Vec<DVec3> = patches
            .par_iter()
            .map(|&p| {
                let p = p as usize;
                let visible = |v: u32| !hidden[v as usize];
                // A textured patch reflects ∫ ρ ΔE/π dA (`textured.rs`).
                match rgb_weights.get(p).filter(|w| !w.is_empty()) {
                    None => weights[p]
                        .iter()
                        .filter(|(v, _)| visible(*v))
                        .map(|&(v, w)| received[v as usize] * w)
                        .sum(),
                    Some(rgb) => rgb
                        .iter()
                        .filter(|(v, _)| visible(*v))
                        .map(|&(v, w)| received[v as usize] * w)
                        .sum(),
                }
            })
            .collect();
        for (&p, sum) in patches.iter().zip(sums) {
            let area = self.patches.shoot_area[p as usize];
            if area > 0.0 {
                self.patches.unshot[p as usize] += sum / area;
            }
        }
        self.unshot_changed(&patches);
        if touched.is_none() {
            self.field.received.fill(DVec3::ZERO);
            return;
        }
        for &s in &self.sharing.footprint.touched {
            for &v in self.sharing.footprint.surface_vertices.of(s) {
                self.field.received[v as usize] = DVec3::ZERO;
            }
        }
    }
}
