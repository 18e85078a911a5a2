//! Adaptive subdivision after a shot (000 §3.3 and Fig. 3.6 step 5c).
//!
//! An element edge whose end vertices differ in visibility of the source is on
//! a shadow boundary. A leaf splits when the radiance difference across one of
//! its edges exceeds `threshold × local radiance` (`shadow_threshold` on shadow
//! boundaries, `edge_threshold` elsewhere), its area is above
//! `min_element_area × polygon area` and its depth is below `max_depth`. The
//! local radiance is the brighter end's brightest channel, so the test is
//! relative (design notes, "Automatic meshing"): the same mesh results whatever
//! the units or the emitters' strength.
//!
//! New vertices get the radiance of earlier shots interpolated from the corners
//! that define them (edge midpoint: the two ends; quad centre: the four
//! corners), 000's "accumulated radiosity interpolated from the vertices on
//! either side", and are then shot to by the current source; their children are
//! tested again, recursively, until every edge passes or can split no more.
//! Unshot radiance of earlier shots is not interpolated: it was gathered into
//! the patches after each shot (see the module documentation of
//! [`crate::solve`]), so a split neither creates nor loses unshot energy; the
//! current shot's unshot at a new vertex is its own, computed ΔL.
//!
//! 000 refines only after emitters shoot; here every shot may refine, since
//! indirect light casts shadows too, and an edge that already passed is only
//! tested again when the shot changed one of its ends.

use super::shoot::{Received, Scratch, Shot};
use crate::mesh::Mesh;
use crate::settings::SolverSettings;
use glam::DVec3;
use rayon::prelude::*;

/// The split thresholds of one solve.
#[derive(Clone, Copy, Debug)]
pub struct Criteria {
    pub edge_threshold: f64,
    pub shadow_threshold: f64,
    pub max_depth: u32,
    /// Fraction of the polygon's area.
    pub min_element_area: f64,
}

impl Criteria {
    pub fn from_settings(s: &SolverSettings) -> Self {
        Criteria {
            edge_threshold: s.edge_threshold,
            shadow_threshold: s.shadow_threshold,
            max_depth: s.max_depth,
            min_element_area: s.min_element_area,
        }
    }

    /// Whether leaf `e` must split given the vertices' radiance and their
    /// visibility of the current source.
    pub fn should_split(&self, mesh: &Mesh, radiance: &[DVec3], visible: &[u32], e: u32) -> bool {
        let el = &mesh.elements[e as usize];
        if !el.is_leaf() || el.depth as u32 >= self.max_depth {
            return false;
        }
        let surface = &mesh.surfaces[mesh.patches[el.patch as usize].surface as usize];
        if el.area <= self.min_element_area * surface.area {
            return false;
        }
        let corners = el.corners();
        let n = corners.len();
        (0..n).any(|k| {
            let (a, b) = (corners[k] as usize, corners[(k + 1) % n] as usize);
            let threshold = if visible[a] != visible[b] {
                self.shadow_threshold
            } else {
                self.edge_threshold
            };
            let (la, lb) = (radiance[a], radiance[b]);
            let local = la.max(lb).max_element();
            local > 0.0 && (la - lb).abs().max_element() > threshold * local
        })
    }
}

/// The per-vertex state refinement reads and extends.
pub struct VertexState<'a> {
    pub radiance: &'a mut Vec<DVec3>,
    pub received: &'a mut Vec<DVec3>,
    pub visible: &'a mut Vec<u32>,
}

/// What a refinement pass did.
#[derive(Debug, Default)]
pub struct Refined {
    pub splits: usize,
    pub rays: u64,
    /// Surfaces whose mesh changed (their display triangulation and gather
    /// weights must be rebuilt).
    pub dirty_surfaces: Vec<u32>,
}

/// Refines after `shot`: tests the leaves the shot changed, splits, shoots the
/// new vertices, and repeats on the children.
pub fn refine(
    mesh: &mut Mesh,
    state: VertexState<'_>,
    criteria: &Criteria,
    shot: &Shot,
) -> Refined {
    let VertexState {
        radiance,
        received,
        visible,
    } = state;
    let mut dirty = vec![false; mesh.surfaces.len()];
    let mut out = Refined::default();
    let mut candidates: Vec<u32> = {
        let (mesh, received) = (&*mesh, &*received);
        (0..mesh.elements.len() as u32)
            .into_par_iter()
            .filter(|&e| {
                let el = &mesh.elements[e as usize];
                el.is_leaf()
                    && el
                        .corners()
                        .iter()
                        .any(|&c| received[c as usize] != DVec3::ZERO)
            })
            .collect()
    };
    let mut created = Vec::new();
    loop {
        let to_split: Vec<u32> = {
            let (mesh, radiance, visible) = (&*mesh, &*radiance, &*visible);
            candidates
                .par_iter()
                .copied()
                .filter(|&e| criteria.should_split(mesh, radiance, visible, e))
                .collect()
        };
        if to_split.is_empty() {
            break;
        }
        created.clear();
        let mut children = Vec::with_capacity(4 * to_split.len());
        for &e in &to_split {
            // Only an impossible mesh size (2^32 vertices) can fail; stop
            // refining then rather than abort the solve.
            let Ok(first) = mesh.split(e, &mut created) else {
                break;
            };
            out.splits += 1;
            children.extend(first..first + 4);
            let surface = mesh.patches[mesh.elements[e as usize].patch as usize].surface;
            dirty[surface as usize] = true;
        }
        for nv in &created {
            debug_assert_eq!(nv.id as usize, radiance.len());
            // Radiance of the earlier shots: each parent's radiance less this
            // shot's ΔL, averaged.
            let earlier = nv
                .parents()
                .iter()
                .map(|&p| radiance[p as usize] - received[p as usize])
                .sum::<DVec3>()
                / nv.parent_count as f64;
            radiance.push(earlier);
            received.push(DVec3::ZERO);
            visible.push(0);
        }
        let results: Vec<Received> = {
            let mesh = &*mesh;
            created
                .par_iter()
                .map_init(Scratch::default, |scratch, nv| {
                    shot.receive(mesh, nv.id, scratch)
                })
                .collect()
        };
        for (nv, r) in created.iter().zip(&results) {
            let v = nv.id as usize;
            radiance[v] += r.radiance;
            received[v] = r.radiance;
            visible[v] = r.visible;
            out.rays += r.rays as u64;
        }
        candidates = children;
    }
    out.dirty_surfaces = (0..dirty.len() as u32)
        .filter(|&s| dirty[s as usize])
        .collect();
    out
}
