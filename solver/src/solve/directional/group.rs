//! Grouped shooters in directional mode (`--shooters grouped`; the diffuse
//! solve's `group_shot.rs`): a reflecting patch shoots with its bright
//! neighbours in one pass, through the same selection, member tree and rays
//! as a diffuse grouped shot, whatever the members' SH orders.
//!
//! ## What a receiver gets
//!
//! Each of a receiver's `group_samples` rays ends on one member (a member
//! of its cut, or one a far cluster picked), so its direction is known, and
//! it carries ΔE = π · colour · W / R ([`GroupShot::visit_at`]): the diffuse
//! estimate ray by ray, unbiased for the members' summed irradiance were
//! each to shoot its hemisphere-equivalent radiance U_p uniformly. A glossy
//! member's radiance depends on direction, so its rays carry ΔE times
//! L_p(ω)/U_p per channel ([`GroupSh::scale`]), with L_p(ω) its unshot SH
//! evaluated toward the receiver (clamped at zero, as a patch shot clamps
//! ringing): each ray's estimate is f/pdf with f the member's directional
//! contribution, so the sum stays unbiased for the members' shots whatever
//! the weights that drew the rays. An order-0 member's factor is 1.
//!
//! The receiver reflects each arriving ray's ΔE from its direction as it
//! reflects a patch shot's sample (`Reflector::add`): its diffuse part
//! Kd · ΔE / π as c₀₀, its glossy lobe by the ray's incidence. So the
//! reflected power is Ks × the incident power ray by ray, as in a patch
//! shot.
//!
//! A glossy receiver traces [`GLOSSY_RAYS`] times as many rays, since its
//! lobe is built from their directions one by one.
//!
//! Where direction matters (a glossy member, or a glossy receiver), a ray's
//! point on a member is uniform in the solid angle the member subtends, and
//! the ray carries cos θ · Ω / (π F̂) of its share (`group_shot.rs`,
//! `Member::solid_angle_point`), so that within a near member the directions
//! are weighted by the receiver's cosine, as a patch shot's samples are.
//! Points uniform in area would weight them by area instead: on the glossy
//! Cornell box at draft that put the standard camera's MARE at 5.9% where
//! the patch shooter gives 4.7% (5.1% with glossy members alone by solid
//! angle). Between diffuse ends a point stays uniform in area: only the
//! visible fraction matters there.
//!
//! ## What is not grouped
//!
//! An emitter's first shot: it is recorded with its unshot SH and replayed
//! to the vertices later splits create; it shoots alone, as before (a
//! recorded group's replay would need its members' SH kept). An emitter's
//! later shots, of reflected light, group as a reflector's.

use super::receive::{receive_arrivals, sh_toward, DirScratch, Receiving, Tables};
use super::Directional;
use crate::mesh::Mesh;
use crate::settings::Shooters;
use crate::solve::checkpoint::precision::round_to_kept;
use crate::solve::group_shot::{GroupShot, GroupSources};
use crate::solve::Solver;
use glam::DVec3;
use solution::sh::{self, coefficient_count};
use std::sync::Arc;

/// A grouped shot as a directional source: the diffuse group's rays, each
/// scaled by its member's direction and reflected by the receiver from its
/// direction.
pub(super) struct DirGroup<'a> {
    pub(super) group: &'a GroupShot<'a>,
    pub(super) sh: &'a GroupSh,
    pub(super) tables: &'a Tables,
    /// Rays per glossy receiver ([`glossy_rays`]); a diffuse one takes the
    /// group's `group_samples`.
    pub(super) glossy_rays: u32,
}

/// A glossy receiver traces this many times `group_samples` rays of a
/// grouped shot, but never more than the members would alone (`samples`
/// each; [`GroupShot::more_rays`]): its lobe is built from the rays'
/// directions, one per ray, where a diffuse receiver needs only their sum.
/// The glossy Cornell box at medium against its truths (standard and floor
/// cameras, MARE): 3.68% and 6.53% at 8×, 3.65% and 6.48% at 12×, 3.62% and
/// 6.00% at 16×, in 38, 56 and 69 s (docs/lab/glossy-grouped-shooters.md).
pub const GLOSSY_RAYS: u32 = 8;

/// The rays a glossy receiver traces of `group` (see [`GLOSSY_RAYS`]).
pub(super) fn glossy_rays(group: &GroupShot, settings: &crate::settings::SolverSettings) -> u32 {
    group.more_rays(GLOSSY_RAYS, settings)
}

impl DirGroup<'_> {
    /// ΔL of `who` as SH coefficients of its surface's order, into `out`,
    /// its slot, which it overwrites; the visible count (out of
    /// `group_samples`) and the rays traced.
    pub(super) fn receive_into(
        &self,
        mesh: &Mesh,
        kd: &[DVec3],
        who: Receiving,
        scratch: &mut DirScratch,
        out: &mut [f64],
    ) -> (u32, u32) {
        let epsilon = self.group.occluder.scene_epsilon();
        let DirScratch {
            group, lobe, basis, ..
        } = scratch;
        receive_arrivals(
            mesh,
            self.tables,
            kd,
            who,
            epsilon,
            out,
            lobe,
            |at, reflector, sink| {
                let glossy = reflector.glossy();
                let rays = if glossy {
                    self.glossy_rays
                } else {
                    self.group.samples
                };
                let mut arrive = |toward, irradiance, member| {
                    let scale = self.sh.scale(member, toward, basis);
                    sink(toward, irradiance * scale);
                };
                self.group.visit_at(at, group, rays, glossy, &mut arrive)
            },
        )
    }
}

/// The unshot SH of a group's glossy members, by member in tree order: what
/// [`GroupSh::scale`] evaluates toward a receiver.
#[derive(Default)]
pub(super) struct GroupSh {
    /// Per member (tree order), its index in `sources`, or [`ORDER_ZERO`].
    by_member: Vec<u32>,
    sources: Vec<SourceSh>,
    /// The sources' coefficients, one after another.
    coefficients: Vec<f64>,
}

/// A member of order 0: its rays carry what the diffuse group gives them.
const ORDER_ZERO: u32 = u32::MAX;

/// One glossy patch of a group: its SH frame, order, where its unshot SH
/// lies in [`GroupSh::coefficients`], and 1/U per channel (0 where U is 0).
struct SourceSh {
    order: u32,
    normal: DVec3,
    tangent: DVec3,
    start: usize,
    inverse: DVec3,
}

impl GroupSh {
    /// Source `s`'s unshot radiance toward a receiver that sees it along
    /// `toward`, RGB, clamped at zero: ringing of a truncated lobe below zero
    /// is not light to shoot.
    fn radiance(&self, s: &SourceSh, toward: DVec3, basis: &mut Vec<f64>) -> DVec3 {
        let count = 3 * coefficient_count(s.order);
        let local = sh::to_local(-toward, s.normal, s.tangent);
        let coefficients = &self.coefficients[s.start..s.start + count];
        sh_toward(s.order, local, coefficients, basis).max(DVec3::ZERO)
    }

    /// The factor L_p(ω)/U_p per channel of a ray that arrives from member
    /// `member` (tree order) along `toward` (from the receiver to the
    /// member): 1 for an order-0 member.
    fn scale(&self, member: u32, toward: DVec3, basis: &mut Vec<f64>) -> DVec3 {
        let k = self.by_member[member as usize];
        if k == ORDER_ZERO {
            return DVec3::ONE;
        }
        let s = &self.sources[k as usize];
        self.radiance(s, toward, basis) * s.inverse
    }
}

/// The members of a directional grouped shot beside its seed: each
/// patch and the unshot SH taken out of it.
pub(super) type Taken = Vec<(u32, Vec<f64>)>;

/// The group that shoots with `seed` (its unshot SH `unshot` already taken),
/// when the solve groups shooters and a partner qualifies: the members under
/// their tree, their glossy members' SH, and the partners' unshot SH, taken
/// out of their patches. `None` (nothing taken) otherwise (see the module
/// documentation).
pub(super) fn take(
    s: &mut Solver,
    d: &mut Directional,
    seed: u32,
    unshot: &[f64],
) -> Option<(Arc<GroupSources>, GroupSh, Taken)> {
    if s.settings.shooters != Shooters::Grouped || s.first_shot(seed) {
        return None;
    }
    let seed_surface = s.mesh.patches[seed as usize].surface as usize;
    let seed_unshot = d.source_radiance(d.surface_order[seed_surface], unshot);
    let members = s.take_group_where(seed, seed_unshot, |_| true)?;
    // Each member shoots its unshot SH: U_p, its hemisphere-equivalent
    // radiance, weighs it in the tree, and a glossy member's rays are
    // scaled by direction ([`GroupSh::scale`]).
    let mut taken = Vec::with_capacity(members.len() - 1);
    let mut pieces = Vec::with_capacity(members.len());
    let mut sh = Vec::with_capacity(members.len());
    pieces.push((seed, seed_unshot));
    sh.push((seed, unshot.to_vec()));
    for &(p, _) in &members[1..] {
        let range = d.patch_range(&s.mesh, p as usize);
        let c = d.patch_unshot[range.clone()].to_vec();
        d.patch_unshot[range].fill(0.0);
        let order = d.surface_order[s.mesh.patches[p as usize].surface as usize];
        pieces.push((p, d.source_radiance(order, &c)));
        taken.push((p, c.clone()));
        sh.push((p, c));
    }
    // A glossy member's rays go by solid angle, so that within it the
    // directions are weighted by the receiver's kernel as its radiance's are.
    let mut group_pieces = s.group_pieces(&pieces);
    for piece in &mut group_pieces {
        piece.by_solid_angle = d.surface_order[piece.surface as usize] > 0;
    }
    let sources = Arc::new(GroupSources::new(&s.mesh, &group_pieces));
    let group_sh = group_sh(s, d, &sources, &sh, &pieces);
    Some((sources, group_sh, taken))
}

/// The [`GroupSh`] of `sources`, whose patches shot `sh` with the
/// hemisphere-equivalent radiance `pieces` gives each.
fn group_sh(
    s: &Solver,
    d: &Directional,
    sources: &GroupSources,
    sh: &[(u32, Vec<f64>)],
    pieces: &[(u32, DVec3)],
) -> GroupSh {
    let mut out = GroupSh::default();
    // Patches in ascending order, each with its index in `sh`.
    let mut index: Vec<(u32, usize)> = sh.iter().enumerate().map(|(i, c)| (c.0, i)).collect();
    index.sort_unstable();
    let mut source_of = vec![ORDER_ZERO; sh.len()];
    for member in sources.members() {
        let found = index.binary_search_by_key(&member.patch(), |e| e.0);
        let Ok(at) = found else {
            out.by_member.push(ORDER_ZERO);
            continue;
        };
        let i = index[at].1;
        let surface = &s.mesh.surfaces[member.surface() as usize];
        let order = d.surface_order[member.surface() as usize];
        if order == 0 {
            out.by_member.push(ORDER_ZERO);
            continue;
        }
        if source_of[i] == ORDER_ZERO {
            source_of[i] = out.sources.len() as u32;
            let u = pieces[i].1;
            let inverse =
                DVec3::from_array(u.to_array().map(|c| if c > 0.0 { 1.0 / c } else { 0.0 }));
            out.sources.push(SourceSh {
                order,
                normal: surface.normal,
                tangent: surface.tangent,
                start: out.coefficients.len(),
                inverse,
            });
            out.coefficients.extend_from_slice(&sh[i].1);
        }
        out.by_member.push(source_of[i]);
    }
    out
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
