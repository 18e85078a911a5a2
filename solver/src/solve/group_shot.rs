//! Grouped shooters (`--shooters grouped`): the patch with the most unshot
//! power and its bright neighbours shoot in one pass over the receivers, the
//! shooter side of Smits, Arvo and Greenberg's (1994) clustering.
//!
//! ## Why
//!
//! On a scene of many small lit patches (thousands of boxes on a floor) every
//! lit patch must shoot once, so the shots grow with the scene, and each early
//! shot visits most receivers: a solve costs shots × receivers. A group of g
//! patches shot together costs one pass and the same R rays per receiver,
//! instead of g passes of R rays. Each receiver sees the group through a cut
//! of a tree over its members (`group_tree.rs`): the members near it with
//! their exact factors, far clusters of them as one item each, so a
//! receiver's cost grows with the log of the group, not with g, and groups
//! can hold thousands of patches.
//!
//! ## The estimate (unbiased for the sum of the members' shots)
//!
//! Each member p (unshot radiance U_p, polygon A_p) would give receiver v
//! ΔL_v,p = Kd U_p F(v←p) with F(v←p) = F̂_p · f_p: the unoccluded factor F̂_p
//! (exact point-to-polygon, as the patch shooter computes it) times the
//! visible fraction f_p of the part of A_p in front of v, estimated by rays to
//! uniform points on it. Here each receiver computes every member's F̂_p and
//! weight w_p = |U_p| F̂_p (|·| summing the channels), W = Σ w_p, and sends
//! its R rays to members chosen in proportion to w_p (systematic sampling of
//! the cumulative weights: ray i at (i + ξ)/R · W, one ξ per receiver), each
//! to a uniform point of the chosen member's front part. A ray to p that
//! arrives contributes W · U_p / |U_p| / R, so the expectation of the sum is
//! Σ_p w_p f_p U_p / |U_p| = Σ_p U_p F̂_p f_p, the members' shots summed.
//! What changes against shooting them one by one is the noise: a member
//! gets R w_p / W rays instead of R. The refinement test reads the k of R
//! visible rays as the patch shooter's k of n.
//!
//! Far members (beyond [`FAR`] of their own diameters, wholly above the
//! receiver's horizon) use the differential kernel at their centroid
//! instead of the contour integral: relative error O((D/d)²) ≤ 1/FAR² = 1%
//! of that member's factor, a small, smooth bias on light from far patches,
//! which saves the contour integral for most of a group's members. Clusters
//! of members far from the receiver enter its weights as one item each
//! (`group_tree.rs`), by the cluster kernel (the same centroid expansion
//! over the cluster) or, where members straddle its horizon, sampled
//! without bias; a ray to a cluster goes to one of its members.
//!
//! ## What is grouped
//!
//! The seed is the patch with the most unshot power. It takes the patches
//! on surfaces within [`RADIUS`] of the scene diagonal of its centre with at
//! least [`FRACTION`] of its unshot power, the brightest first, up to
//! [`MAX_MEMBERS`] in all. A small patch, one element that refinement never
//! splits (a small flat surface of `small.rs`, or a facet of a finely
//! tessellated sphere), joins with [`FRACTION`] of the seed's unshot
//! *radiance* instead: on a floor of 83,000 small boxes each face holds a
//! thousandth of a wall patch's power, so by power alone no face ever joined
//! a wall's seed, the walls kept seeding groups of a few dozen patches, and
//! each shot took 0.02% of the power while the faces held most of it
//! (docs/lab/small-surfaces.md, "Small surfaces receive once"; the spheres' facets, "Small
//! patches join by radiance"). Other patches keep the power rule: admitting every patch by
//! radiance took the Cornell box at draft from 3.19% / 3.25% MARE to 3.76% /
//! 3.54% against the truth (wider groups, docs/lab/small-surfaces.md). Nearby members share most of their occluders, so a
//! receiver's rays to the group see one visibility, and the mixed estimate is
//! little noisier than the seed's own. A group shot of reflected light is not
//! recorded, like a reflector's shot under the patch shooter: a new vertex
//! made by the group shot's own refinement receives it (through
//! [`Shooter`]), and a later one interpolates it. (The patch shooter records
//! an emitter patch's later shots of reflected light too; grouped, those are
//! interpolated like any reflector's.) A seed with no partner shoots alone,
//! exactly as the patch shooter would, quadrants and recording included.
//!
//! ## Emitters' first shots
//!
//! An emitter patch's first shot carries its emission, and is recorded:
//! every vertex that a later split creates receives it again instead of
//! interpolating it, so that direct light stays resolved (`refine.rs`). Such
//! a first shot groups only with other first shots (and a later shot only
//! with reflectors and emitters that have had theirs), by the same rules of
//! radius and power, and the group is recorded whole
//! ([`super::shoot::RecordedGroup`]: its shot number, and each member's patch
//! and unshot radiance). Its members shoot whole and uniformly, as a
//! recorded single shot does, so the group rebuilds from its record alone
//! (a resume rebuilds it from the checkpoint's), and its replay at a new
//! vertex is the group shot itself there: the same members and tree, the
//! vertex's own RNG stream, the same rays. Replays run in shot order with
//! the recorded single shots.
//!
//! Before, every emitter patch shot alone first: a body of 100k emitting
//! facets (Khronos's ToyCar, an emissive texture over the whole car) took
//! 100k single shots before any grouping, each traced to every receiver and
//! replayed at every new vertex, and stopped at the 20,000-shot cap with
//! 27.4% of its power unshot (issue 42). Grouped, its first shots are a few
//! dozen groups (docs/lab/emitter-groups.md).
//!
//! The direct light must stay as accurate as the single shots made it, so a
//! recorded group differs from a reflectors' group in two ways
//! ([`GroupShot::recorded`]). It samples no cluster that straddles a
//! receiver's horizon: such a cluster's rays carry unequal shares of an
//! upper bound, which on a curved emitter (a car body, a sphere) left the
//! worst vertex's direct light −2.8% / +2.5% off the members' exact shots
//! where the node opened to members gives −0.10% / +0.33% (test
//! `grouped_emitters_give_the_members_exact_direct_light`). And it traces
//! [`EMITTER_RAYS`] times `group_samples` rays per receiver (never more than
//! its members alone would), since rays to far clusters of curved members
//! still carry unequal shares: at 16 rays instead of 256 the worst vertex
//! was −0.62% / +1.02% off. A group is shot once, so these rays cost little
//! beside the members' single shots they replace. A scene whose emitter is
//! one patch (the Cornell box's light) has no partner for it and shoots it
//! alone, exactly as before; so does every emitter under the seed papers'
//! form factors (`--form-factors wallace` or `hemicube`, baselines that a
//! group, which computes exact factors, would bypass).
//!
//! ## Bookkeeping
//!
//! Every member's unshot radiance is zeroed before the shot and its power is
//! the shot's, π U_p A_p each; what receivers get is gathered into patches as
//! after any shot, so shot = received + absorbed + escaped holds exactly as
//! for single shots (test `grouped_shooting_loses_no_energy`). An unevenly
//! lit quad member shoots as its four quadrants, each its own piece with its
//! own unshot radiance (`regions.rs`, Σ_q U_q A_q = U_p A_p), as it would
//! alone: shooting members uniformly cost 1.3 MARE points on the Cornell box
//! at draft (docs/lab/grouped-shooters.md, "Grouped shooters"). An emitter's patch
//! shoots uniformly, as alone its shots are recorded and so uniform: shaped
//! by its vertices it took a furnace of emitting faces 2.2% off at ρ = 0.95.
//!
//! ## Directional mode
//!
//! A directional solve groups its sources of SH order 0 through the same
//! selection, tree and rays (`directional/group.rs`): [`GroupShot::visit_at`]
//! hands each arriving ray's direction and ΔE to the receiver, which
//! reflects it by its lobe. Glossy sources and emitters' first shots shoot
//! alone there.
//!
//! ## Rays
//!
//! A receiver's `group_samples` rays are shared among the members, so a
//! member gets fewer than a patch shot's `samples`; on the Cornell box
//! against the truth a group needs about twice to eight times as many for
//! the same accuracy (docs/lab/grouped-shooters.md, "Grouped shooters against the
//! truth").

use super::group_tree::{Item, MemberTree, Receiver};
use super::lights::LightShot;
use super::shoot::{Received, ReceivingPoint, SamplePool, Scratch, Shot};
use super::Solver;
use crate::geometry::formfactor::SourcePolygon;
use crate::geometry::polygon::clip_to_halfspace;
use crate::geometry::sampling::{stream_id, Rng};
use crate::geometry::solid_angle::stratified_solid_angle_points;
use crate::geometry::visibility::Occluder;
use crate::mesh::Mesh;
use glam::DVec3;
use std::f64::consts::PI;
use std::sync::Arc;

/// A member's unshot power must be at least this fraction of the seed's (a
/// small surface's, its unshot radiance): a weaker patch adds little to the
/// group's shot and would get few rays.
pub const FRACTION: f64 = 0.1;

/// Members lie on surfaces within this fraction of the scene's diagonal of
/// the seed's centre, so that the group is local and its members share
/// occluders. On the Cornell box at draft against the truth, 0.1 and 0.2
/// measure 3.69% / 3.70% MARE, 0.3 and the whole scene 4.33% / 4.89%
/// (docs/lab/grouped-shooters.md, "Clustered group shots").
pub const RADIUS: f64 = 0.2;

/// The most patches one grouped shot carries. Receivers see the group
/// through the cluster tree (`group_tree.rs`), so a receiver's cost grows
/// with the log of the members; what the cap bounds is the shot's memory
/// (`budget.rs`, `group_shot_bytes`: about 72 MiB at this cap, 4.4 KiB a
/// member of four quadrant pieces). At 4,096 the 100k boxes took 202 s at
/// medium and the 1M boxes stopped at 6.2% unshot at draft; at this cap
/// 167 s and 5.6% in less time (docs/lab/grouped-shooters.md, "Clustered group shots").
pub const MAX_MEMBERS: usize = 16384;

/// A recorded group of emitters' first shots traces this many times
/// `group_samples` rays per receiver ([`GroupShot::recorded`]): it carries
/// the direct light, which the patch shooter resolves with `samples` rays
/// per member, and its far clusters' rays carry unequal shares where the
/// members curve (a car body). In a closed sphere of 512 emitting facets
/// (test `grouped_emitters_give_the_members_exact_direct_light`) the worst
/// vertex's direct light was −0.62% / +1.02% off the members' exact shots
/// at 16 rays, −0.10% / +0.33% at 256; a group is shot once and replayed
/// to new vertices, so the rays cost little beside the members' single
/// shots they replace (docs/lab/emitter-groups.md).
pub const EMITTER_RAYS: u32 = 16;

/// Members farther than this many of their own diameters use the
/// differential kernel at their centroid (see the module documentation).
pub const FAR: f64 = 10.0;

/// One patch of a group.
pub struct Member {
    /// The patch it is (or is a quadrant of).
    patch: u32,
    surface: u32,
    corners: [DVec3; 4],
    corner_count: usize,
    source: SourcePolygon,
    normal: DVec3,
    centre: DVec3,
    diameter: f64,
    area: f64,
    /// The doubled areas of the fan triangles (corner 0, 1, 2) and (0, 2,
    /// 3) and their sum, as `uniform_point` computes them: kept so that a
    /// ray's point costs no square roots beyond the warp's (a third of a
    /// `final` Cornell solve was spent recomputing them, ray by ray).
    fan: [f64; 2],
    fan_total: f64,
    /// U_p, RGB.
    pub unshot: DVec3,
    /// U_p / |U_p|: what one ray that reaches the member carries, per unit
    /// of the receiver's total weight.
    colour: DVec3,
    /// See [`Piece::by_solid_angle`].
    by_solid_angle: bool,
}

/// A polygon that shoots in a group: a whole patch, or one quadrant of an
/// unevenly lit one (`regions.rs`), with its own unshot radiance.
#[derive(Clone, Copy, Debug)]
pub struct Piece {
    /// The patch it is (or is a quadrant of).
    pub patch: u32,
    pub surface: u32,
    pub corners: [DVec3; 4],
    pub corner_count: usize,
    pub area: f64,
    pub unshot: DVec3,
    /// Whether its rays go to points uniform in the solid angle it subtends
    /// rather than in its area: a source whose radiance depends on direction
    /// (`directional/group.rs`), where the kernel's weighting within it
    /// matters.
    pub by_solid_angle: bool,
}

impl Piece {
    /// Patch `patch` whole, shooting `unshot` uniformly.
    pub fn whole(mesh: &Mesh, patch: u32, unshot: DVec3) -> Piece {
        let p = &mesh.patches[patch as usize];
        Piece {
            patch,
            surface: p.surface,
            corners: p.corners,
            corner_count: p.corner_count as usize,
            area: p.area,
            unshot,
            by_solid_angle: false,
        }
    }
}

impl Member {
    fn new(mesh: &Mesh, piece: &Piece) -> Member {
        Member::of(piece, mesh.surfaces[piece.surface as usize].normal)
    }

    /// The member for `piece`, whose plane has unit normal `normal`.
    pub(super) fn of(piece: &Piece, normal: DVec3) -> Member {
        let polygon = &piece.corners[..piece.corner_count];
        let centre = polygon.iter().copied().sum::<DVec3>() / polygon.len() as f64;
        let diameter = polygon
            .iter()
            .flat_map(|a| polygon.iter().map(move |b| (*a - *b).length()))
            .fold(0.0, f64::max);
        let unshot = piece.unshot;
        let sum = unshot.element_sum();
        let fan_area = |i: usize| fan_triangle_area(polygon, i);
        let fan = [
            fan_area(1),
            if polygon.len() > 3 { fan_area(2) } else { 0.0 },
        ];
        Member {
            patch: piece.patch,
            surface: piece.surface,
            corners: piece.corners,
            corner_count: piece.corner_count,
            source: SourcePolygon::new(polygon),
            normal,
            centre,
            diameter,
            area: piece.area,
            fan,
            fan_total: (1..polygon.len() - 1).map(fan_area).sum(),
            unshot,
            colour: if sum > 0.0 { unshot / sum } else { DVec3::ZERO },
            by_solid_angle: piece.by_solid_angle,
        }
    }

    pub(super) fn polygon(&self) -> &[DVec3] {
        &self.corners[..self.corner_count]
    }

    pub(super) fn centre(&self) -> DVec3 {
        self.centre
    }

    pub(super) fn normal(&self) -> DVec3 {
        self.normal
    }

    pub(super) fn surface(&self) -> u32 {
        self.surface
    }

    /// The patch it is (or is a quadrant of).
    pub(super) fn patch(&self) -> u32 {
        self.patch
    }

    pub(super) fn area(&self) -> f64 {
        self.area
    }

    /// U_p / |U_p|.
    pub(super) fn colour(&self) -> DVec3 {
        self.colour
    }

    /// A_p |U_p|: the member's share of a far cluster (`group_tree.rs`).
    pub(super) fn strength(&self) -> f64 {
        self.area * self.unshot.element_sum()
    }

    /// A uniform point on the member: `uniform_point` of its polygon, the
    /// same bits from the same draws, with the fan's areas computed once.
    pub(super) fn uniform_point(&self, rng: &mut Rng) -> DVec3 {
        let u = rng.next_f64() * self.fan_total;
        let c = &self.corners;
        if self.corner_count > 3 && u >= self.fan[0] {
            triangle_point(c[0], c[2], c[3], rng)
        } else {
            triangle_point(c[0], c[1], c[2], rng)
        }
    }

    /// Whether the whole member lies in the closed upper half-space of the
    /// receiver at `q` with normal `n` (the patch shooter's test).
    fn above_horizon(&self, q: DVec3, n: DVec3, epsilon: f64) -> bool {
        let floor = -1e-6 * epsilon;
        self.polygon().iter().all(|&c| n.dot(c - q) >= floor)
    }

    /// F̂(q←p): the unoccluded factor, with the patch shooter's culls; the
    /// centroid kernel when far (see the module documentation).
    pub(super) fn factor(&self, q: DVec3, n: DVec3, epsilon: f64) -> f64 {
        if self.normal.dot(q - self.centre) < -1e-6 * self.diameter {
            return 0.0;
        }
        if self.polygon().iter().all(|&c| n.dot(c - q) <= 0.0) {
            return 0.0;
        }
        let d = q - self.centre;
        let r2 = d.length_squared();
        let far = r2 > (FAR * self.diameter).powi(2) && self.above_horizon(q, n, epsilon);
        let f = if far {
            let (cs, cr) = (self.normal.dot(d), -n.dot(d));
            if cs <= 0.0 || cr <= 0.0 {
                0.0
            } else {
                self.area * cs * cr / (PI * r2 * r2)
            }
        } else {
            self.source.form_factor(q, n)
        };
        // The patch shooter's floor: a member in the receiver's plane has a
        // factor of 0 up to rounding.
        if f.is_finite() && f > super::shoot::NEGLIGIBLE_FACTOR {
            f
        } else {
            0.0
        }
    }

    /// A point of the part of the member in front of the ray origin's
    /// tangent plane (`origin`, ε above the receiving point, normal `n`),
    /// uniform in the solid angle it subtends from the origin
    /// (one stratum of `stratified_solid_angle_points`), and the ray's
    /// factor cos θ · Ω / (π F̂) against the member's unoccluded factor
    /// `factor` F̂ (its weight's): its mean over such points is 1, since
    /// ∫ cos θ dω = π F̂, so a ray weighted by it and by the source's
    /// radiance toward it estimates the kernel-weighted mean of that
    /// radiance without bias. `None` when the part subtends no solid angle.
    fn solid_angle_point(
        &self,
        origin: DVec3,
        n: DVec3,
        factor: f64,
        rng: &mut Rng,
        clipped: &mut Vec<DVec3>,
        point: &mut Vec<DVec3>,
    ) -> Option<(DVec3, f64)> {
        clip_to_halfspace(self.polygon(), origin, n, clipped);
        if clipped.len() < 3 {
            clipped.clear();
            clipped.extend_from_slice(self.polygon());
        }
        let omega = stratified_solid_angle_points(origin, clipped, 1, rng, point);
        let y = *point.first()?;
        let cos = (y - origin).normalize_or_zero().dot(n).max(0.0);
        let weight = cos * omega / (PI * factor);
        weight.is_finite().then_some((y, weight))
    }

    /// A uniform point on the part of the member in front of the ray origin's
    /// tangent plane (the whole member when it is above the horizon), as the
    /// patch shooter samples its source.
    fn sample_point(
        &self,
        q: DVec3,
        n: DVec3,
        epsilon: f64,
        rng: &mut Rng,
        clipped: &mut Vec<DVec3>,
    ) -> DVec3 {
        if self.above_horizon(q, n, epsilon) {
            return self.uniform_point(rng);
        }
        clip_to_halfspace(self.polygon(), q + n * epsilon, n, clipped);
        if clipped.len() >= 3 {
            uniform_point(clipped, rng)
        } else {
            self.uniform_point(rng)
        }
    }
}

/// A uniform point on convex polygon `polygon`: a fan triangle chosen by
/// area, then a uniform point in it (Turk 1990, square-root warp).
pub(super) fn uniform_point(polygon: &[DVec3], rng: &mut Rng) -> DVec3 {
    let area = |i: usize| fan_triangle_area(polygon, i);
    let total: f64 = (1..polygon.len() - 1).map(area).sum();
    let mut u = rng.next_f64() * total;
    let mut i = 1;
    while i + 2 < polygon.len() && u >= area(i) {
        u -= area(i);
        i += 1;
    }
    triangle_point(polygon[0], polygon[i], polygon[i + 1], rng)
}

/// Twice the area of fan triangle (corner 0, `i`, `i` + 1) of `polygon`.
fn fan_triangle_area(polygon: &[DVec3], i: usize) -> f64 {
    let a = polygon[0];
    (polygon[i] - a).cross(polygon[i + 1] - a).length()
}

/// A uniform point in triangle (a, b, c): Turk's (1990) square-root warp
/// of two draws.
fn triangle_point(a: DVec3, b: DVec3, c: DVec3, rng: &mut Rng) -> DVec3 {
    let r = rng.next_f64().sqrt();
    let s = rng.next_f64();
    a * (1.0 - r) + b * (r * (1.0 - s)) + c * (r * s)
}

/// One grouped shot: its members and what its receivers share.
pub struct GroupShot<'a> {
    /// Shot number: with the seed and the vertex id it names the RNG stream.
    pub index: u64,
    pub seed: u64,
    /// Rays per receiver, shared among the members (`group_samples`; more
    /// for a recorded group, [`GroupShot::recorded`]).
    pub samples: u32,
    /// What a receiver's visible count is out of, for the refinement test:
    /// `group_samples`, whatever `samples` is.
    counted: u32,
    /// Whether far clusters that straddle a receiver's horizon may be
    /// sampled (`group_tree.rs`): not in a recorded group.
    sampled: bool,
    pub shadows: bool,
    pub occluder: &'a Occluder,
    pub kd: &'a [DVec3],
    /// The members under their tree, shared with the recording when the
    /// shot is an emitters' first (see the module documentation).
    sources: Arc<GroupSources>,
    /// Fewer rays where the group adds little (`ray_share.rs`).
    pub ray_share: Option<super::ray_share::RayShare>,
}

/// A group's members in tree order under their tree (`group_tree.rs`):
/// built once per shot, and kept for the whole solve by a recorded group,
/// whose replays to new vertices share it.
pub struct GroupSources {
    members: Vec<Member>,
    tree: MemberTree,
}

impl GroupSources {
    /// The members of `pieces` under their tree.
    pub fn new(mesh: &Mesh, pieces: &[Piece]) -> GroupSources {
        let mut members: Vec<Member> = pieces.iter().map(|p| Member::new(mesh, p)).collect();
        let tree = MemberTree::build(&mut members);
        GroupSources { members, tree }
    }

    /// How many pieces shoot.
    pub fn len(&self) -> usize {
        self.members.len()
    }

    /// The members in tree order.
    pub(super) fn members(&self) -> &[Member] {
        &self.members
    }
}

impl<'a> GroupShot<'a> {
    /// The shot of `pieces` (the seed's first).
    #[cfg(test)]
    pub fn new(
        mesh: &Mesh,
        pieces: &[Piece],
        index: u64,
        settings: &crate::settings::SolverSettings,
        occluder: &'a Occluder,
        kd: &'a [DVec3],
    ) -> GroupShot<'a> {
        let sources = Arc::new(GroupSources::new(mesh, pieces));
        GroupShot::of(sources, index, settings, occluder, kd)
    }

    /// The shot of `sources` as shot number `index` (a recorded group's
    /// replay is the same shot: the same members, streams and rays).
    pub fn of(
        sources: Arc<GroupSources>,
        index: u64,
        settings: &crate::settings::SolverSettings,
        occluder: &'a Occluder,
        kd: &'a [DVec3],
    ) -> GroupShot<'a> {
        GroupShot {
            index,
            seed: settings.seed,
            samples: settings.group_samples.max(1),
            counted: settings.group_samples.max(1),
            sampled: true,
            shadows: settings.shadows,
            occluder,
            kd,
            sources,
            ray_share: None,
        }
    }

    /// This group as a recorded one, emitters' first shots: [`EMITTER_RAYS`]
    /// times `group_samples` rays per receiver, but never more than its
    /// members would trace alone (`samples` each), nor fewer than a group's;
    /// and no sampled clusters, whose rays carry unequal shares (see the
    /// module documentation, "Emitters' first shots"). Its visible counts
    /// stay out of `group_samples`, as any group's.
    pub fn recorded(mut self, settings: &crate::settings::SolverSettings) -> GroupShot<'a> {
        self.sampled = false;
        self.samples = self.more_rays(EMITTER_RAYS, settings);
        self
    }

    /// `factor` times the group's rays per receiver, but never more than
    /// its members would trace alone (`samples` each), nor fewer than a
    /// group's.
    pub fn more_rays(&self, factor: u32, settings: &crate::settings::SolverSettings) -> u32 {
        let alone = (self.sources.len() as u64 * settings.samples as u64).min(u32::MAX as u64);
        (self.samples.saturating_mul(factor))
            .min(alone as u32)
            .max(self.samples)
    }

    /// ΔL_v: the importance-sampled sum of the members' shots, far clusters
    /// of members taken whole (`group_tree.rs`; see the module
    /// documentation).
    /// `prior`: every vertex's radiance before this shot, for the ray share.
    pub fn receive(
        &self,
        mesh: &Mesh,
        v: u32,
        scratch: &mut Scratch,
        prior: Option<&[DVec3]>,
    ) -> Received {
        let at = ReceivingPoint::of_vertex(mesh, v, self.occluder.scene_epsilon());
        self.receive_at(&at, scratch, prior.map(|p| p[v as usize]))
    }

    /// [`GroupShot::receive`] at a receiving point; `prior`: its radiance
    /// before this shot, for the ray share.
    pub fn receive_at(
        &self,
        at: &ReceivingPoint,
        scratch: &mut Scratch,
        prior: Option<DVec3>,
    ) -> Received {
        let kd = self.kd[at.surface as usize];
        if kd == DVec3::ZERO {
            return Received::default();
        }
        let Some((total, unoccluded)) = self.cut(at, scratch) else {
            return Received::default();
        };
        if !self.shadows {
            return Received {
                radiance: kd * unoccluded,
                visible: self.counted,
                rays: 0,
            };
        }
        // The ray share compares the members' summed unoccluded gain with
        // the receiver's level (`ray_share.rs`): ΔL̂ = Kd ⊙ Σ colour_p w_p,
        // against a unit source of that colour at factor W.
        let rays = match (&self.ray_share, prior) {
            (Some(share), Some(prior)) => {
                let full = share.full_factor(prior, kd, unoccluded / total);
                super::ray_share::rays_for(self.samples, total, full)
            }
            _ => self.samples,
        };
        self.draw(at, scratch, total, rays, false);
        let mut sum = DVec3::ZERO;
        let mut visible = 0;
        for (&c, &f) in scratch.carried.iter().zip(scratch.flags.iter()) {
            if f {
                visible += 1;
                sum += c;
            }
        }
        Received {
            radiance: kd * sum * (total / rays as f64),
            visible: self.visible_count(visible, rays),
            rays,
        }
    }

    /// The incident light of the group at a receiving point ray by ray, for
    /// a receiver that reflects by direction (`directional/group.rs`):
    /// `visit(toward, irradiance, member)` for each of `rays` rays that
    /// arrives, with the unit direction from the point to the ray's end on a
    /// member, the ΔE it carries, RGB, π · colour · W / R, and that member
    /// (tree order, [`GroupSources::members`]). With `rays` the
    /// group's `samples` and not `by_solid_angle`, their sum is π times
    /// [`GroupShot::receive_at`]'s estimate before Kd (the same rays, no ray
    /// share); with shadows off every ray arrives. With `by_solid_angle`
    /// (a glossy receiver) every member's rays go by solid angle, so that the
    /// directions within a near member are weighted by the receiver's cosine
    /// as a patch shot's are. Returns the visible count (out of
    /// `group_samples`, as [`GroupShot::receive_at`]'s) and the rays traced.
    pub fn visit_at(
        &self,
        at: &ReceivingPoint,
        scratch: &mut Scratch,
        rays: u32,
        by_solid_angle: bool,
        visit: &mut dyn FnMut(DVec3, DVec3, u32),
    ) -> (u32, u32) {
        let Some((total, _)) = self.cut(at, scratch) else {
            return (0, 0);
        };
        self.draw(at, scratch, total, rays, by_solid_angle);
        let scale = PI * total / rays as f64;
        let (members, epsilon) = (&self.sources.members, self.occluder.scene_epsilon());
        let mut visible = 0;
        for (((&y, &c), &f), &member) in scratch
            .points
            .iter()
            .zip(&scratch.carried)
            .zip(&scratch.flags)
            .zip(&scratch.ends)
        {
            if !f {
                continue;
            }
            visible += 1;
            // The direction to the point on the member, not to the ray's end
            // lifted ε off it for the visibility test: near a corner, where
            // points by solid angle lie within a few ε of the receiving
            // point, the lift would tilt it toward grazing (a patch shot's
            // directions are the samples' own too).
            let on_member = y - members[member as usize].normal * epsilon;
            if let Some(toward) = (on_member - at.q).try_normalize() {
                visit(toward, c * scale, member);
            }
        }
        let traced = if self.shadows { rays } else { 0 };
        (self.visible_count(visible, rays), traced)
    }

    /// A visible count of `rays` rays out of `group_samples`, for the
    /// refinement test.
    fn visible_count(&self, visible: u32, rays: u32) -> u32 {
        if self.counted == self.samples && rays <= self.samples {
            visible * (self.samples / rays)
        } else {
            (visible as u64 * self.counted as u64 / rays as u64) as u32
        }
    }

    /// The receiver's cut of the member tree into `scratch`'s items and
    /// weights: their total W and the members' unoccluded shots summed,
    /// Σ_p U_p F̂_p; `None` when the group gives the point nothing.
    fn cut(&self, at: &ReceivingPoint, scratch: &mut Scratch) -> Option<(f64, DVec3)> {
        let Scratch { weights, items, .. } = scratch;
        weights.clear();
        items.clear();
        let GroupSources { members, tree } = &*self.sources;
        let unoccluded = tree.items(
            members,
            &Receiver {
                q: at.q,
                n: at.n,
                surface: at.surface,
                epsilon: self.occluder.scene_epsilon(),
            },
            self.shadows,
            self.sampled,
            items,
            weights,
        );
        let total: f64 = weights.iter().sum();
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        Some((total, unoccluded))
    }

    /// Draws `rays` rays over the cut (systematic sampling of its weights,
    /// total `total`) into `scratch`: each ray's end point and the colour it
    /// carries if it arrives, and whether it does (every ray, shadows off).
    /// With `by_solid_angle`, every member item's rays go by solid angle
    /// (`Member::solid_angle_point`), not only those of members that ask for
    /// it.
    fn draw(
        &self,
        at: &ReceivingPoint,
        scratch: &mut Scratch,
        total: f64,
        rays: u32,
        by_solid_angle: bool,
    ) {
        let ReceivingPoint { q, n, stream, .. } = *at;
        let epsilon = self.occluder.scene_epsilon();
        let Scratch {
            points,
            clipped,
            flags,
            weights,
            items,
            carried,
            ends,
            solid,
        } = scratch;
        let GroupSources { members, tree } = &*self.sources;
        let mut rng = Rng::new(self.seed, stream_id(self.index, stream as u64));
        let offset = rng.next_f64();
        points.clear();
        carried.clear();
        ends.clear();
        let last = weights.len() - 1;
        let (mut k, mut cumulative) = (0, weights[0]);
        for i in 0..rays {
            let u = (i as f64 + offset) / rays as f64 * total;
            while u >= cumulative && k < last {
                k += 1;
                cumulative += weights[k];
            }
            match items[k] {
                Item::Member(member) => {
                    let m = &members[member as usize];
                    let factor = weights[k] / m.unshot.element_sum();
                    let by_solid_angle = if m.by_solid_angle || by_solid_angle {
                        let origin = q + n * epsilon;
                        m.solid_angle_point(origin, n, factor, &mut rng, clipped, solid)
                    } else {
                        None
                    };
                    let (y, weight) = by_solid_angle
                        .unwrap_or_else(|| (m.sample_point(q, n, epsilon, &mut rng, clipped), 1.0));
                    points.push(y + m.normal * epsilon);
                    carried.push(m.colour * weight);
                    ends.push(member);
                }
                Item::Cluster(cluster) => {
                    let ray = tree.ray(members, cluster, weights[k], q, n, &mut rng);
                    if let Some((y, normal, colour, member)) = ray {
                        points.push(y + normal * epsilon);
                        carried.push(colour);
                        ends.push(member);
                    }
                }
            }
        }
        if self.shadows {
            self.occluder.visible_each(q + n * epsilon, points, flags);
        } else {
            flags.clear();
            flags.resize(points.len(), true);
        }
    }
}

#[cfg(test)]
impl GroupShot<'_> {
    /// How receiver `v` sees the group: the weights of the single members,
    /// the far clusters and the sampled clusters in its cut.
    pub fn cut_weights(&self, mesh: &Mesh, v: u32) -> [f64; 3] {
        let surface = mesh.vertices[v as usize].surface;
        let epsilon = self.occluder.scene_epsilon();
        let (q, n) = super::shoot::receiving_point(mesh, v, epsilon);
        let (mut items, mut weights) = (Vec::new(), Vec::new());
        self.sources.tree.items(
            &self.sources.members,
            &Receiver {
                q,
                n,
                surface,
                epsilon,
            },
            true,
            self.sampled,
            &mut items,
            &mut weights,
        );
        let mut sums = [0.0; 3];
        for (item, w) in items.iter().zip(&weights) {
            let k = match item {
                Item::Member(_) => 0,
                Item::Cluster(c) if !c.sampled => 1,
                Item::Cluster(_) => 2,
            };
            sums[k] += w;
        }
        sums
    }
}

/// What shoots this step: one patch (with its sample pool), or a group.
pub enum Shooter<'s, 'a> {
    Patch {
        shot: &'s Shot<'a>,
        pool: &'s SamplePool,
    },
    Group(&'s GroupShot<'a>),
    /// The sun, the sky and the lamps (`lights.rs`).
    Lights(&'s LightShot<'a>),
}

impl Shooter<'_, '_> {
    /// ΔL_v from this shooter.
    /// `prior`: every vertex's radiance before this shot (the ray share's
    /// level, `ray_share.rs`); `None` traces every ray.
    pub fn receive(
        &self,
        mesh: &Mesh,
        v: u32,
        scratch: &mut Scratch,
        prior: Option<&[DVec3]>,
    ) -> Received {
        match self {
            Shooter::Patch { shot, pool } => shot.receive(mesh, v, pool, scratch, prior),
            Shooter::Group(group) => group.receive(mesh, v, scratch, prior),
            Shooter::Lights(lights) => lights.receive(mesh, v),
        }
    }

    /// ΔL at a receiving point; `prior`: its radiance before this shot.
    pub fn receive_at(
        &self,
        mesh: &Mesh,
        at: &ReceivingPoint,
        scratch: &mut Scratch,
        prior: Option<DVec3>,
    ) -> Received {
        match self {
            Shooter::Patch { shot, pool } => shot.receive_at(mesh, at, pool, scratch, prior),
            Shooter::Group(group) => group.receive_at(at, scratch, prior),
            Shooter::Lights(lights) => lights.receive_at(at),
        }
    }

    /// Diffuse reflectance per surface.
    pub fn kd(&self) -> &[DVec3] {
        match self {
            Shooter::Patch { shot, .. } => shot.kd,
            Shooter::Group(group) => group.kd,
            Shooter::Lights(lights) => lights.kd,
        }
    }
}

impl Solver {
    /// The group that shoots with `seed`, whose unshot radiance `unshot` the
    /// step has already taken: (patch, unshot) with the seed first, each
    /// other member's unshot taken from the patches too. `None` (nothing
    /// taken) when no other patch qualifies (see the module documentation).
    pub(super) fn take_group(&mut self, seed: u32, unshot: DVec3) -> Option<Vec<(u32, DVec3)>> {
        self.take_group_where(seed, unshot, |_| true)
    }

    /// [`Solver::take_group`] of the patches on surfaces `admit` accepts
    /// alone: a directional solve groups only patches whose outgoing
    /// radiance is the same toward every receiver (`directional/group.rs`).
    pub(super) fn take_group_where(
        &mut self,
        seed: u32,
        unshot: DVec3,
        admit: impl Fn(u32) -> bool,
    ) -> Option<Vec<(u32, DVec3)>> {
        self.catch_up_emitters();
        // An emitter's first shot groups only with other first shots, and a
        // later shot only with reflectors and emitters that have had theirs:
        // a recorded group is the emitters' direct light and nothing else.
        let first = self.first_shot(seed);
        // The seed papers' form factors (`--form-factors wallace` or
        // `hemicube`), kept as measured baselines, reach the receivers
        // only through single shots: their emitters shoot alone, as before.
        if first && self.settings.form_factors != crate::settings::FormFactorMethod::Analytic {
            return None;
        }
        let patch = &self.mesh.patches[seed as usize];
        let power = |p: u32| {
            self.patches.shoot_area[p as usize] * self.patches.unshot[p as usize].element_sum()
        };
        let least = FRACTION * self.patches.shoot_area[seed as usize] * unshot.element_sum();
        if least.is_nan() || least <= 0.0 {
            return None;
        }
        let centre = patch.polygon().iter().copied().sum::<DVec3>() / patch.corner_count as f64;
        let mut surfaces = Vec::new();
        self.groups.receivers.surfaces_near(
            centre,
            RADIUS * self.groups.receivers.diagonal(),
            &mut surfaces,
        );
        let mut candidates: Vec<(f64, u32)> = surfaces
            .iter()
            .flat_map(|&s| self.patches.of_surface[s as usize].clone())
            .filter(|&p| p != seed && self.is_first_shot(p) == first)
            .filter(|&p| admit(self.mesh.patches[p as usize].surface))
            .map(|p| (power(p), p))
            .filter(|&(w, p)| w >= least || self.bright_small(p, unshot))
            .collect();
        if candidates.is_empty() {
            return None;
        }
        // Brightest first, ties to the lower patch: the same group for any
        // tree order.
        candidates.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        candidates.truncate(MAX_MEMBERS - 1);
        let mut members = vec![(seed, unshot)];
        for &(_, p) in &candidates {
            let u = std::mem::replace(&mut self.patches.unshot[p as usize], DVec3::ZERO);
            members.push((p, u));
        }
        let taken: Vec<u32> = candidates.iter().map(|c| c.1).collect();
        self.unshot_changed(&taken);
        self.stats.timings.grouped_patches += members.len() as u64;
        self.stats.timings.group_shots += 1;
        let shot_power: f64 = members[1..]
            .iter()
            .map(|&(p, u)| PI * self.patches.shoot_area[p as usize] * u.element_sum())
            .sum();
        self.stats.timings.shot_power += shot_power;
        Some(members)
    }

    /// Whether patch `p` is small, one element that refinement never splits
    /// (its longest edge within its surface's smallest element size, the
    /// test of `refine::Criteria::at_smallest`), and its unshot radiance is
    /// at least [`FRACTION`] of the seed's `unshot`: such a patch is weak in
    /// power because it is small, not because it is dim, and joins by its
    /// brightness (see the module documentation). A small flat surface
    /// (`small.rs`) is one such patch; a finely tessellated sphere is many.
    fn bright_small(&self, p: u32, unshot: DVec3) -> bool {
        let patch = &self.mesh.patches[p as usize];
        let Some(size) = self.mesh.surfaces[patch.surface as usize].min_element_size else {
            return false;
        };
        self.patches.unshot[p as usize].element_sum() >= FRACTION * unshot.element_sum()
            && super::refine::longest_edge(&self.mesh, patch.root) <= size
    }

    /// The pieces `members` (patch, unshot) shoot as: each unevenly lit quad
    /// patch as its four quadrants with their own unshot radiance, as the
    /// patch shooter shoots it alone (`regions.rs`; Σ_q U_q A_q = U_p A_p, so
    /// the power is the same), the others whole; an emitter's patch whole,
    /// as the patch shooter's recorded shots are.
    pub(super) fn group_pieces(&self, members: &[(u32, DVec3)]) -> Vec<Piece> {
        let mut pieces = Vec::with_capacity(members.len());
        for &(p, u) in members {
            let whole = Piece::whole(&self.mesh, p, u);
            // An emitter's patch shoots uniformly, as the patch shooter's
            // recorded emitter shots do: its vertices' radiance (less the
            // emission) is no measure of how its unshot light lies. In a
            // furnace where every face emits, quadrants shaped by it put the
            // vertices at 1.987-2.005 against the exact 2 at ρ = 0.5, and
            // 2.2% off at ρ = 0.95 (test
            // `grouped_furnace_converges_to_le_over_one_minus_rho`).
            let emits = self.materials.emission[whole.surface as usize] != DVec3::ZERO;
            let regions = if self.settings.shoots_uniformly() || emits {
                None
            } else {
                self.source_regions(p, u)
            };
            match regions {
                Some(r) => {
                    let quadrants = super::regions::quadrants(&whole.corners);
                    for (k, corners) in quadrants.into_iter().enumerate() {
                        pieces.push(Piece {
                            corners,
                            corner_count: 4,
                            area: r.areas[k],
                            unshot: r.unshot[k],
                            ..whole
                        });
                    }
                }
                None => pieces.push(whole),
            }
        }
        pieces
    }

    /// How the emitters' patches shot their emission so far: (alone, in
    /// recorded groups), each patch counted once.
    pub fn emitter_first_shots(&self) -> (u64, u64) {
        let mut alone: Vec<u32> = self.record.shots.iter().map(|r| r.patch).collect();
        alone.sort_unstable();
        alone.dedup();
        let grouped: usize = self.record.groups.iter().map(|g| g.members.len()).sum();
        (alone.len() as u64, grouped as u64)
    }

    /// Whether patch `p`'s next shot is its emitter's first, its emission
    /// not yet shot in a recorded shot or group: such shots group only with
    /// each other, and the group is recorded (see the module documentation).
    pub(super) fn first_shot(&mut self, p: u32) -> bool {
        self.catch_up_emitters();
        self.is_first_shot(p)
    }

    /// [`Solver::first_shot`] with the emitters' record caught up.
    fn is_first_shot(&self, p: u32) -> bool {
        let surface = self.mesh.patches[p as usize].surface;
        self.materials.emission[surface as usize] != DVec3::ZERO
            && !self.record.emitters_shot.shot[p as usize]
    }

    fn catch_up_emitters(&mut self) {
        let record = &mut self.record;
        record
            .emitters_shot
            .catch_up(&record.shots, &record.groups, self.mesh.patches.len());
    }
}

/// Per patch, whether it has a recorded shot, alone or in a group; caught up
/// from the recorded lists (append-only), so a resumed solve rebuilds it
/// from its checkpoint.
#[derive(Default)]
pub(super) struct EmittersShot {
    shot: Vec<bool>,
    seen: usize,
    seen_groups: usize,
}

impl EmittersShot {
    fn catch_up(
        &mut self,
        recorded: &[super::shoot::RecordedShot],
        groups: &[super::shoot::RecordedGroup],
        patches: usize,
    ) {
        self.shot.resize(patches, false);
        for r in &recorded[self.seen.min(recorded.len())..] {
            self.shot[r.patch as usize] = true;
        }
        self.seen = recorded.len();
        for g in &groups[self.seen_groups.min(groups.len())..] {
            for &(p, _) in &g.members {
                self.shot[p as usize] = true;
            }
        }
        self.seen_groups = groups.len();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trapezoid: its centroid is not its vertex average, and its two fan
    /// triangles differ in area.
    const TRAPEZOID: [DVec3; 4] = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(1.5, 1.0, 0.0),
        DVec3::new(0.5, 1.0, 0.0),
    ];

    #[test]
    fn a_members_points_are_uniform_points_of_its_polygon() {
        // The member keeps its fan's areas; the points must be the bits
        // `uniform_point` gives from the same draws, for a triangle and for
        // a quad whose two fan triangles differ in area.
        let quad = TRAPEZOID;
        for corner_count in [3, 4] {
            let polygon = &quad[..corner_count];
            let mut corners = quad;
            if corner_count == 3 {
                corners[3] = DVec3::ZERO;
            }
            let piece = Piece {
                patch: 0,
                surface: 0,
                corners,
                corner_count,
                area: 1.0,
                unshot: DVec3::ONE,
                by_solid_angle: false,
            };
            let member = Member::of(&piece, DVec3::Z);
            let (mut a, mut b) = (Rng::new(3, 9), Rng::new(3, 9));
            for _ in 0..1000 {
                let p = member.uniform_point(&mut a);
                assert_eq!(p, uniform_point(polygon, &mut b), "{corner_count} corners");
            }
        }
    }

    /// Points drawn on a quad land inside it, and their mean is the quad's
    /// area centroid within the Monte Carlo error (σ of the mean ≈ 0.3/√n
    /// per axis for this quad: 4,000 points give 0.005; allowed 0.02).
    #[test]
    fn uniform_points_cover_a_quad_evenly() {
        let quad = TRAPEZOID;
        let mut rng = Rng::new(7, 1);
        let n = 4000;
        let mut mean = DVec3::ZERO;
        for _ in 0..n {
            let p = uniform_point(&quad, &mut rng);
            assert!(
                p.y >= 0.0
                    && p.y <= 1.0
                    && p.x >= 0.5 * p.y - 1e-12
                    && p.x <= 2.0 - 0.5 * p.y + 1e-12
            );
            mean += p / n as f64;
        }
        // Trapezoid with parallel sides 2 (y = 0) and 1 (y = 1): centroid
        // y = (1/3)(2·1 + 2)/(2 + 1) = 4/9, x = 1 by symmetry.
        assert!(
            (mean - DVec3::new(1.0, 4.0 / 9.0, 0.0)).length() < 0.02,
            "{mean}"
        );
    }
}
