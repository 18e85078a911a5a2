//! Grouped shooters in directional mode (`--shooters grouped`; the diffuse
//! solve's `group_shot.rs`): a reflecting patch whose outgoing radiance is
//! the same toward every receiver (SH order 0) shoots with its bright
//! neighbours of order 0 in one pass, through the same selection, member
//! tree and rays as a diffuse grouped shot.
//!
//! ## What a receiver gets
//!
//! Each of a receiver's `group_samples` rays ends on one member (a member
//! of its cut, or one a far cluster picked), so its direction is known, and
//! it carries ΔE = π · colour · W / R ([`GroupShot::visit_at`]): the diffuse
//! estimate ray by ray, unbiased for the members' summed irradiance. The
//! receiver reflects each arriving ray's ΔE from its direction as it
//! reflects a patch shot's sample (`Reflector::add`): its diffuse part
//! Kd · ΔE / π as c₀₀, its glossy lobe by the ray's incidence. So the
//! reflected power is Ks × the incident power ray by ray, as in a patch
//! shot, and the group's irradiance is the diffuse group's estimate.
//!
//! A glossy receiver traces [`GLOSSY_RAYS`] times as many rays, since its
//! lobe is built from their directions one by one.
//!
//! A ray's point is uniform on its member's area, not uniform in the solid
//! angle it subtends: the directions of a near, large member are spread by
//! area rather than by the receiver's cosine weighting, a change in the
//! lobe's shape within one member's solid angle, not in energy.
//!
//! ## What is not grouped
//!
//! * A glossy source (order > 0): its radiance toward each receiver is its
//!   SH evaluated in that direction, which the cluster tree's colours
//!   (one RGB per member and per cluster) cannot carry; it shoots alone, as
//!   before, and a group admits no glossy patch.
//! * An emitter's first shot: it is recorded with its unshot SH and
//!   replayed to the vertices later splits create; it shoots alone, as
//!   before (a recorded group's replay would need its members' SH kept).
//!   An emitter's later shots, of reflected light, group as a reflector's.

use super::receive::{receive_arrivals, DirScratch, Tables};
use super::Directional;
use crate::mesh::Mesh;
use crate::settings::Shooters;
use crate::solve::checkpoint::precision::round_to_kept;
use crate::solve::group_shot::{GroupShot, GroupSources};
use crate::solve::Solver;
use glam::DVec3;
use solution::sh::Y00;
use std::sync::Arc;

/// A grouped shot as a directional source: the diffuse group's rays, each
/// reflected by the receiver from its direction.
pub(super) struct DirGroup<'a> {
    pub(super) group: &'a GroupShot<'a>,
    pub(super) tables: &'a Tables,
    /// Rays per glossy receiver ([`glossy_rays`]); a diffuse one takes the
    /// group's `group_samples`.
    pub(super) glossy_rays: u32,
}

/// A glossy receiver traces this many times `group_samples` rays of a
/// grouped shot, but never more than the members would alone (`samples`
/// each; [`GroupShot::more_rays`]): its lobe is built from the rays'
/// directions, one per ray, where a diffuse receiver needs only their sum,
/// and a patch shot gives it `samples` directions per member. The glossy
/// room (`config/glossy_floor.toml`, draft) against its truth from the
/// front camera: 10.77% MARE at 16 rays a glossy receiver (1×), 6.73% at
/// 256 (16×), 6.62% patch by patch (docs/lab/glossy-grouped-shooters.md).
pub const GLOSSY_RAYS: u32 = 16;

/// The rays a glossy receiver traces of `group` (see [`GLOSSY_RAYS`]).
pub(super) fn glossy_rays(group: &GroupShot, settings: &crate::settings::SolverSettings) -> u32 {
    group.more_rays(GLOSSY_RAYS, settings)
}

impl DirGroup<'_> {
    /// ΔL of vertex `v` as SH coefficients of its surface's order, into
    /// `out`, the vertex's slot, which it overwrites; the visible count
    /// (out of `group_samples`) and the rays traced.
    pub(super) fn receive_into(
        &self,
        mesh: &Mesh,
        kd: &[DVec3],
        v: u32,
        scratch: &mut DirScratch,
        out: &mut [f64],
    ) -> (u32, u32) {
        let epsilon = self.group.occluder.scene_epsilon();
        let DirScratch { group, lobe, .. } = scratch;
        receive_arrivals(
            mesh,
            self.tables,
            kd,
            v,
            epsilon,
            out,
            lobe,
            |at, reflector, sink| {
                let rays = if reflector.glossy() {
                    self.glossy_rays
                } else {
                    self.group.samples
                };
                self.group.visit_at(at, group, rays, sink)
            },
        )
    }
}

/// The members of a directional grouped shot beside its seed: each
/// patch and the unshot SH (c₀₀, order 0) taken out of it.
pub(super) type Taken = Vec<(u32, [f64; 3])>;

/// The group that shoots with `seed` (order 0, its unshot SH `unshot`
/// already taken), when the solve groups shooters and a partner of order 0
/// qualifies: the members under their tree and the partners' unshot SH,
/// taken out of their patches. `None` (nothing taken) otherwise (see the
/// module documentation).
pub(super) fn take(
    s: &mut Solver,
    d: &mut Directional,
    seed: u32,
    unshot: &[f64],
) -> Option<(Arc<GroupSources>, Taken)> {
    let seed_surface = s.mesh.patches[seed as usize].surface as usize;
    if s.settings.shooters != Shooters::Grouped
        || d.surface_order[seed_surface] != 0
        || s.first_shot(seed)
    {
        return None;
    }
    let seed_unshot = DVec3::from_slice(&unshot[..3]) * Y00;
    let orders = &d.surface_order;
    let members = s.take_group_where(seed, seed_unshot, |surface| orders[surface as usize] == 0)?;
    // Each member shoots its unshot SH, whose c₀₀ · Y₀₀ is its radiance
    // toward every receiver, as a patch shot evaluates an order-0 source.
    let mut taken = Vec::with_capacity(members.len() - 1);
    let mut pieces = Vec::with_capacity(members.len());
    pieces.push((seed, seed_unshot));
    for &(p, _) in &members[1..] {
        let range = d.patch_range(&s.mesh, p as usize);
        let c = [
            d.patch_unshot[range.start],
            d.patch_unshot[range.start + 1],
            d.patch_unshot[range.start + 2],
        ];
        d.patch_unshot[range].fill(0.0);
        taken.push((p, c));
        pieces.push((p, DVec3::from_array(c) * Y00));
    }
    let sources = Arc::new(GroupSources::new(&s.mesh, &s.group_pieces(&pieces)));
    Some((sources, taken))
}

/// After a grouped shot: each partner's shot light joins its patch's sum
/// for the near gathers of later splits (`near_gather.rs`), as the seed's
/// does.
pub(super) fn add_shot_sums(mesh: &Mesh, d: &mut Directional, taken: &Taken) {
    for (p, c) in taken {
        let range = d.patch_range(mesh, *p as usize);
        for (sum, u) in d.shot_sum[range].iter_mut().zip(c) {
            *sum = round_to_kept(*sum + u);
        }
    }
}
