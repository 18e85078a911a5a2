//! Directional mode's refinement field (`refine.rs`'s [`Field`] on SH
//! coefficients).

use super::lights::DirSource;
use super::near_gather;
use super::receive::{DirScratch, ReceivedSh};
use super::split::should_split_sh;
use super::Directional;
use crate::geometry::visibility::Occluder;
use crate::mesh::{Mesh, NewVertex};
use crate::settings::SolverSettings;
use crate::solve::refine::{Criteria, Field};
use crate::solve::state::{Materials, PatchLight, VertexField};
use glam::DVec3;
use rayon::prelude::*;

/// The solver's parts a directional shot's refinement reads beside the
/// mesh and the vertex field it changes.
pub(super) struct SolverParts<'s> {
    pub patches: &'s PatchLight,
    pub materials: &'s Materials,
    pub settings: &'s SolverSettings,
    pub occluder: &'s Occluder,
}

/// Directional mode's [`Field`] for adaptive subdivision: the same driver,
/// candidates, splits and replay of recorded (emitter) shots as the diffuse
/// solver (`refine.rs`), on SH coefficients. The diffuse proxies (c₀₀ Y₀₀,
/// ΔL, visibility) are kept in step, so L = 0 surfaces use the diffuse test
/// itself ([`Criteria::should_split_at`]) and a scene with Ks = 0 meshes, and
/// solves, as in diffuse mode. Glossy surfaces use [`should_split_sh`].
pub(super) struct DirField<'s, 'a> {
    pub(super) d: &'s mut Directional,
    pub(super) radiance: &'s mut Vec<DVec3>,
    pub(super) received: &'s mut Vec<DVec3>,
    pub(super) visible: &'s mut Vec<u32>,
    /// The diffuse solver's recorded-shot radiance: kept sized (zero) here,
    /// the directional part is `Directional::direct`.
    pub(super) direct: &'s mut Vec<DVec3>,
    pub(super) kd: &'s [DVec3],
    pub(super) shot: &'s DirSource<'a>,
    pub(super) replay: &'s [DirSource<'a>],
    /// Whether the current shot is the last of `replay`.
    pub(super) current_recorded: bool,
    /// The lights' shot: the sun's and the lamps' shadows are hard, so
    /// glossy elements across their edges split below the α floor
    /// ([`DirField::crosses_shadow`]). A patch's penumbra is as wide as the
    /// patch looks, and keeps the floor.
    pub(super) hard_shadows: bool,
    /// New glossy vertices gather their near patches' shot light.
    pub(super) near: near_gather::NearGather<'s>,
}

impl<'s, 'a> DirField<'s, 'a> {
    /// The field of one shot over the solver's vertex state `field`:
    /// `shot`, the recorded shots `replay` (ending with `shot` when it is
    /// recorded: `current_recorded`), whether its shadows are hard (the
    /// lights'), and what new glossy vertices' near gather reads.
    pub(super) fn of_shot(
        d: &'s mut Directional,
        field: &'s mut VertexField,
        solver: SolverParts<'s>,
        shot: &'s DirSource<'a>,
        replay: &'s [DirSource<'a>],
        (current_recorded, hard_shadows): (bool, bool),
    ) -> Self {
        let VertexField {
            radiance,
            received,
            visible,
            direct,
            hidden,
        } = field;
        DirField {
            d,
            radiance,
            received,
            visible,
            direct,
            kd: &solver.materials.kd,
            shot,
            replay,
            current_recorded,
            hard_shadows,
            near: near_gather::NearGather {
                patch_weights: &solver.patches.weights,
                hidden,
                emission: &solver.materials.emission,
                settings: solver.settings,
                occluder: solver.occluder,
                kd: &solver.materials.kd,
                reach: near_gather::NEAR_REACH,
            },
        }
    }

    /// Whether a hard shadow's edge crosses leaf `e`: in the lights' shot,
    /// its corners saw different shares of the lights.
    fn crosses_shadow(&self, mesh: &Mesh, e: u32) -> bool {
        if !self.hard_shadows {
            return false;
        }
        let corners = mesh.elements[e as usize].corners();
        let first = self.visible[corners[0] as usize];
        corners.iter().any(|&v| self.visible[v as usize] != first)
    }
}

impl Field for DirField<'_, '_> {
    fn changed(&self, v: u32) -> bool {
        let o = self.d.vertex_offset[v as usize];
        let end = self
            .d
            .vertex_offset
            .get(v as usize + 1)
            .copied()
            .unwrap_or(self.d.received.len());
        self.d.received[o..end].iter().any(|&x| x != 0.0)
    }

    fn should_split(&self, mesh: &Mesh, criteria: &Criteria, e: u32) -> bool {
        let surface = mesh.patches[mesh.elements[e as usize].patch as usize].surface;
        if self.d.surface_order[surface as usize] == 0 {
            // Diffuse surfaces: exactly the diffuse solver's test.
            criteria.should_split_at(
                mesh,
                Some(self.kd),
                self.radiance,
                self.received,
                self.visible,
                e,
            )
        } else {
            // A glossy surface also splits where its diffuse proxy (its
            // mean radiance, or E/π when textured) changes by the diffuse
            // test: across a hard shadow's edge below the α floor, since
            // the lobe blurs directions but not a step in visibility across
            // the surface (a sun patch's edge on a polished floor); and,
            // textured, above the floor where E/π changes.
            should_split_sh(mesh, self.d, self.visible, criteria, e)
                || ((self.crosses_shadow(mesh, e)
                    || (self.d.textured[surface as usize] && self.d.above_glossy_floor(mesh, e)))
                    && criteria.should_split_at(
                        mesh,
                        Some(self.kd),
                        self.radiance,
                        self.received,
                        self.visible,
                        e,
                    ))
        }
    }

    fn interpolate(&mut self, mesh: &Mesh, created: &[NewVertex]) {
        let d = &mut *self.d;
        d.extend_vertices(mesh);
        for nv in created {
            // As the diffuse field: the parents' radiance less the recorded
            // shots and this shot's ΔL (both recomputed exactly), averaged.
            // The whole slot: the coefficients and a textured surface's E/π.
            let range = d.vertex_slot(mesh, nv.id as usize);
            let mut earlier = vec![0.0; range.len()];
            for &p in nv.parents() {
                let o = d.vertex_offset[p as usize];
                for (k, e) in earlier.iter_mut().enumerate() {
                    let current = if self.current_recorded {
                        0.0
                    } else {
                        d.received[o + k]
                    };
                    *e += d.radiance[o + k] - d.direct[o + k] - current;
                }
            }
            for (k, e) in earlier.iter().enumerate() {
                d.radiance[range.start + k] = e / nv.parent_count as f64;
            }
            let surface = mesh.vertices[nv.id as usize].surface as usize;
            self.radiance
                .push(d.diffuse_proxy(surface, &d.radiance[range.start..]));
            self.received.push(DVec3::ZERO);
            self.visible.push(0);
            self.direct.push(DVec3::ZERO);
        }
    }

    fn receive(&mut self, mesh: &Mesh, created: &[NewVertex]) -> u64 {
        let (kd, shot, replay) = (self.kd, self.shot, self.replay);
        let current_recorded = self.current_recorded;
        // Per new vertex: (recorded shots' coefficients, this shot's, its
        // visibility, rays).
        let results: Vec<(Vec<f64>, ReceivedSh, u64)> = created
            .par_iter()
            .map_init(DirScratch::default, |scratch, nv| {
                let mut exact: Vec<f64> = Vec::new();
                let mut rays = 0u64;
                let mut current = None;
                for r in replay {
                    let got = r.receive(mesh, kd, nv.id, scratch);
                    if exact.is_empty() {
                        exact = vec![0.0; got.coefficients.len()];
                    }
                    for (e, c) in exact.iter_mut().zip(&got.coefficients) {
                        *e += c;
                    }
                    rays += got.rays as u64;
                    current = Some(got);
                }
                if !current_recorded {
                    let got = shot.receive(mesh, kd, nv.id, scratch);
                    rays += got.rays as u64;
                    current = Some(got);
                }
                let current = current.unwrap_or(ReceivedSh::nothing(Vec::new()));
                (exact, current, rays)
            })
            .collect();
        let near = self
            .near
            .corrections(mesh, self.radiance, self.d, shot.tables(), created);
        let d = &mut *self.d;
        let mut total = near.rays;
        for ((nv, (exact, current, rays)), correction) in
            created.iter().zip(results).zip(near.per_vertex)
        {
            let v = nv.id as usize;
            let o = d.vertex_offset[v];
            for (k, c) in correction.iter().flatten().enumerate() {
                d.radiance[o + k] += c;
            }
            for (k, e) in exact.iter().enumerate() {
                d.radiance[o + k] += e;
                d.direct[o + k] = *e;
            }
            for (k, c) in current.coefficients.iter().enumerate() {
                if !current_recorded {
                    d.radiance[o + k] += c;
                }
                d.received[o + k] = *c;
            }
            let surface = mesh.vertices[v].surface as usize;
            self.radiance[v] = d.diffuse_proxy(surface, &d.radiance[o..]);
            self.received[v] = if current.coefficients.is_empty() {
                DVec3::ZERO
            } else {
                d.diffuse_proxy(surface, &current.coefficients)
            };
            self.visible[v] = current.visible;
            total += rays;
        }
        total
    }
}
