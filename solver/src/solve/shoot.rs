//! One shot's transport from the source patch to receiving vertices (Remington 1992, Fig. 3.6,
//! `Shoot(SP)`, and §3.6 for the form factor).
//!
//! Everything that depends only on the source is prepared once per shot
//! ([`Shot`]); the per-receiver work is one analytic form factor and one packet
//! of `samples` visibility rays from a shared origin, with no allocation per ray
//! (the sample buffer lives in per-worker [`Scratch`]).

use super::regions::Regions;
use crate::geometry::formfactor::{wallace, SourcePolygon};
use crate::geometry::hemicube::{self, ItemBuffer};
use crate::geometry::polygon::clip_to_halfspace;
use crate::geometry::sampling::{stratified_points, stream_id, Rng};
use crate::geometry::solid_angle::stratified_solid_angle_points;
use crate::geometry::visibility::Occluder;
use crate::mesh::Mesh;
use crate::settings::FormFactorMethod;
use glam::DVec3;
use std::sync::OnceLock;

/// Receiving points on element boundaries are evaluated this fraction of the
/// way toward the centroid of an element they belong to (design notes, "Form
/// factors"). A vertex on the edge the receiver shares with the source (a
/// room's corner) then sits just off the source's plane instead of on its edge,
/// where r → 0; the bias is O(fraction) relative, 1e-3 at worst for such
/// vertices, and zero where the form factor is flat.
pub const INWARD_STEP: f64 = 1e-3;

/// What one receiving vertex gets from one shot.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Received {
    /// ΔL, radiance added by this shot (W·sr⁻¹·m⁻², RGB).
    pub radiance: DVec3,
    /// How many of the visibility rays reached the source (all of them when
    /// shadows are off and the source is in front); 0 when the source cannot
    /// be seen at all. Edges whose ends differ here are shadow boundaries.
    pub visible: u32,
    /// Rays traced for this receiver.
    pub rays: u32,
}

/// Where a receiver samples a shot: its point, its unit normal, its surface
/// and the RNG stream its rays draw from. A vertex receives at its receiving
/// point ([`receiving_point`]) on stream `v`; a small flat surface that takes
/// one sample for all its vertices (`footprint.rs`) at its centroid on a
/// stream above every vertex id.
#[derive(Clone, Copy, Debug)]
pub struct ReceivingPoint {
    pub q: DVec3,
    pub n: DVec3,
    pub surface: u32,
    pub stream: u32,
}

impl ReceivingPoint {
    /// Vertex `v`'s receiving point, for an occluder of scene epsilon
    /// `epsilon`.
    pub fn of_vertex(mesh: &Mesh, v: u32, epsilon: f64) -> ReceivingPoint {
        let (q, n) = receiving_point(mesh, v, epsilon);
        ReceivingPoint {
            q,
            n,
            surface: mesh.vertices[v as usize].surface,
            stream: v,
        }
    }
}

/// Per-worker buffers: the source samples and their visibility flags.
#[derive(Default)]
pub struct Scratch {
    pub(super) points: Vec<DVec3>,
    pub(super) clipped: Vec<DVec3>,
    pub(super) flags: Vec<bool>,
    /// Grouped shots (`group_shot.rs`): the members and far clusters a
    /// receiver sees with their shares of its estimate, and per ray the
    /// colour it carries if it arrives.
    pub(super) weights: Vec<f64>,
    pub(super) items: Vec<super::group_tree::Item>,
    pub(super) carried: Vec<DVec3>,
    /// Per ray, the member (tree order) it ends on.
    pub(super) ends: Vec<u32>,
    /// A point drawn by solid angle (`Member::solid_angle_point`).
    pub(super) solid: Vec<DVec3>,
}

/// How many jittered sample sets a shot draws on its source ([`SamplePool`]).
pub const POOL_SETS: u32 = 256;

/// The most points a pool holds (3 MB): with thousands of samples per
/// receiver a pool has fewer sets rather than grow without bound.
pub const POOL_POINTS: u32 = 1 << 16;

/// Sets kept for each recorded (emitter) shot, re-evaluated at vertices that
/// later splits create: smaller, since such a pool lives for the whole solve.
pub const REPLAY_POOL_SETS: u32 = 32;

/// Stream ids of the pool's sets, apart from the vertex ids (< 2^32) that name
/// the receivers' streams.
const POOL_STREAM: u64 = 1 << 62;

/// A patch shot's unoccluded factor at or below this counts as none: the
/// receiver gets nothing and traces no ray. A receiver in the source's plane
/// (a floor vertex on a block's contact line, with the block's face
/// shooting) has a factor of 0 that rounding makes ±1e-17 or so; without
/// the floor its visible count went 0 or all rays with that rounding, and
/// the split test, which tightens its threshold where neighbours' counts
/// differ, split by it: the Cornell box moved by 1e6 refined one element
/// more (test `translating_the_scene_by_1e6_gives_the_same_answer`). 1e-12
/// of a unit factor delivers nothing visible.
pub const NEGLIGIBLE_FACTOR: f64 = 1e-12;

/// Stratified, jittered sample sets over one shot's source, drawn once per
/// shot: [`POOL_SETS`] sets of `samples` points, set k from the RNG stream
/// (seed, shot, 2^62 + k). A receiver whose view of the source is not clipped
/// by its horizon uses the set named by the first draw of its own stream
/// (seed, shot, vertex id), so results still depend only on the seed, the
/// shot and the vertex, never on threads or order.
///
/// Drawing a fresh set per receiver cost as much as tracing its rays (stratified
/// sampling maps every point through the source's fan with a square root and
/// two 53-bit draws): a pool moves that out of the inner loop. Each receiver's
/// estimate is as unbiased as before (a random, independently jittered set);
/// receivers that draw the same set (1 in 256 pairs) have correlated noise,
/// which at 256 sets is far below what a viewer or the refinement test could
/// see.
pub struct SamplePool {
    samples: usize,
    sets: u32,
    /// On the source's surface (the points Remington 1992, eq. 3.1 evaluates).
    on_source: Vec<DVec3>,
    /// The same lifted `scene_epsilon` off the source: the rays' targets.
    lifted: Vec<DVec3>,
}

impl SamplePool {
    /// The pool of `shot`; empty when its method and settings trace no rays
    /// and need no samples.
    pub fn new(shot: &Shot) -> SamplePool {
        Self::with_sets(shot, POOL_SETS)
    }

    /// A pool of `sets` sets (the first `sets` of the full pool's), fewer when
    /// that would exceed [`POOL_POINTS`] points (at least 8 sets).
    pub fn with_sets(shot: &Shot, sets: u32) -> SamplePool {
        let sets = sets.min((POOL_POINTS / shot.samples.max(1)).max(8));
        let needed = match shot.method {
            FormFactorMethod::Analytic => shot.shadows,
            FormFactorMethod::Wallace => true,
            FormFactorMethod::Hemicube => false,
        };
        let samples = shot.samples as usize;
        let sets = sets.max(1);
        let mut pool = SamplePool {
            samples,
            sets,
            on_source: Vec::new(),
            lifted: Vec::new(),
        };
        if !needed || samples == 0 {
            return pool;
        }
        pool.on_source.reserve(sets as usize * samples);
        let mut set = Vec::with_capacity(samples);
        for k in 0..sets {
            let mut rng = Rng::new(shot.seed, stream_id(shot.index, POOL_STREAM + k as u64));
            stratified_points(shot.polygon(), shot.samples, &mut rng, &mut set);
            pool.on_source.extend_from_slice(&set);
        }
        let lift = shot.normal * shot.occluder.scene_epsilon();
        pool.lifted = pool.on_source.iter().map(|&p| p + lift).collect();
        pool
    }

    /// The set receiver `v` of `shot` uses: (points on the source, lifted).
    pub fn set_for(&self, shot: &Shot, v: u32) -> (&[DVec3], &[DVec3]) {
        self.set_and_offset(shot, v).0
    }

    /// [`SamplePool::set_for`], and the offset of a strided subset of it
    /// ([`super::ray_share::strided`]): the receiver stream's second draw.
    fn set_and_offset(&self, shot: &Shot, v: u32) -> ((&[DVec3], &[DVec3]), u32) {
        if self.on_source.is_empty() {
            return ((&[], &[]), 0);
        }
        let mut rng = Rng::new(shot.seed, stream_id(shot.index, v as u64));
        let k = rng.next_u32() % self.sets;
        let range = k as usize * self.samples..(k as usize + 1) * self.samples;
        let offset = rng.next_u32();
        (
            (&self.on_source[range.clone()], &self.lifted[range]),
            offset,
        )
    }
}

/// The `Hemicube` method gathers candidate occluders from this many cells each
/// side of the receiver's cell: a 3 × 3 block, so that an occluder covering
/// the receiver's direction but not its cell's centre is still found.
const HEMICUBE_SEARCH_RADIUS: usize = 1;

/// The source patch of one shot, with everything the receivers share.
pub struct Shot<'a> {
    /// 0-based shot number: with the seed and the vertex id it names the RNG
    /// stream, so a receiver's samples do not depend on the thread count.
    pub index: u64,
    pub seed: u64,
    pub source_surface: u32,
    pub polygon: [DVec3; 4],
    pub corner_count: usize,
    /// The source polygon prepared for the exact form factor (its unit normal
    /// and vertex average computed once per shot, not per receiver).
    pub source: SourcePolygon,
    pub normal: DVec3,
    pub centre: DVec3,
    pub area: f64,
    /// Size of the source, for the scale of plane tests.
    pub diameter: f64,
    /// U_s: unshot radiance of the source patch (RGB).
    pub unshot: DVec3,
    pub samples: u32,
    pub method: FormFactorMethod,
    /// Cells per side of the `Hemicube` method's top face.
    pub hemicube_resolution: u32,
    /// The `Hemicube` method's item buffer on the source's centre, rendered on
    /// first use ([`Shot::hemicube_visible`]).
    pub hemicube: OnceLock<ItemBuffer>,
    pub shadows: bool,
    pub occluder: &'a Occluder,
    /// Diffuse reflectance per surface.
    pub kd: &'a [DVec3],
    /// The source's quadrants with their own unshot radiance, where it is lit
    /// unevenly ([`super::regions`]); `None` shoots U_s uniformly.
    pub regions: Option<Box<Regions>>,
    /// Fewer rays where the shot adds little ([`super::ray_share`]); `None`
    /// traces every ray to every receiver.
    pub ray_share: Option<super::ray_share::RayShare>,
}

/// A shot the solver remembers: every shot from an emitter's patch, so that a
/// vertex created by a later split can receive it exactly instead of by
/// interpolation (see `solve/refine.rs`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RecordedShot {
    /// The shot's 0-based index (its RNG streams).
    pub index: u64,
    pub patch: u32,
    /// The vertex count when it was shot: vertices below it received the shot
    /// itself, later ones its replay when a split created them (so a resume can
    /// recompute every vertex's recorded-shot part instead of storing it; see
    /// `solve/checkpoint.rs`).
    pub receivers: u32,
    /// U_s as f64 bit patterns (RGB), exact through any serde format.
    pub unshot: [u64; 3],
}

/// A recorded group: the first shots of emitters' patches, shot together
/// (`group_shot.rs`, "Emitters' first shots"). Its members are the patches
/// whole with their unshot radiance, so the group rebuilds from them alone
/// and its replay at a new vertex is the shot itself there: the same
/// members, tree, RNG stream and rays.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordedGroup {
    /// The shot's 0-based index (its RNG streams).
    pub index: u64,
    /// The vertex count when it was shot, as [`RecordedShot::receivers`].
    pub receivers: u32,
    /// (patch, U_p as f64 bit patterns), the seed first.
    pub members: Vec<(u32, [u64; 3])>,
}

impl RecordedGroup {
    /// The group of `members` (patch, unshot) shot as shot `index` to the
    /// `receivers` vertices there are.
    pub fn new(index: u64, receivers: usize, members: &[(u32, DVec3)]) -> RecordedGroup {
        RecordedGroup {
            index,
            receivers: receivers as u32,
            members: members
                .iter()
                .map(|&(p, u)| (p, u.to_array().map(f64::to_bits)))
                .collect(),
        }
    }

    /// The members' pieces, each patch whole, and their tree.
    pub fn sources(&self, mesh: &Mesh) -> super::group_shot::GroupSources {
        let pieces: Vec<super::group_shot::Piece> = self
            .members
            .iter()
            .map(|&(p, u)| {
                super::group_shot::Piece::whole(mesh, p, DVec3::from_array(u.map(f64::from_bits)))
            })
            .collect();
        super::group_shot::GroupSources::new(mesh, &pieces)
    }
}

impl RecordedShot {
    pub fn unshot(&self) -> DVec3 {
        DVec3::from_array(self.unshot.map(f64::from_bits))
    }

    /// The recorded shots rebuilt against the current mesh, for the replay to
    /// new vertices after a split (Remington 1992, §3.3, step 5c); the diffuse and the SH
    /// refinements replay exactly these. The shots borrow the occluder and the
    /// reflectances, not the mesh, so the mesh can be split while they live.
    pub fn rebuild_all<'a>(
        recorded: &[RecordedShot],
        mesh: &Mesh,
        settings: &crate::settings::SolverSettings,
        occluder: &'a Occluder,
        kd: &'a [DVec3],
    ) -> Vec<Shot<'a>> {
        recorded
            .iter()
            .map(|r| Shot::for_patch(mesh, r.patch, r.index, r.unshot(), settings, occluder, kd))
            .collect()
    }
}

impl<'a> Shot<'a> {
    /// The shot of `patch` with unshot radiance `unshot` as shot number `index`.
    pub fn for_patch(
        mesh: &Mesh,
        patch: u32,
        index: u64,
        unshot: DVec3,
        settings: &crate::settings::SolverSettings,
        occluder: &'a Occluder,
        kd: &'a [DVec3],
    ) -> Shot<'a> {
        let patch = &mesh.patches[patch as usize];
        let polygon = patch.polygon();
        let centre = polygon.iter().copied().sum::<DVec3>() / polygon.len() as f64;
        let diameter = polygon
            .iter()
            .flat_map(|a| polygon.iter().map(move |b| (*a - *b).length()))
            .fold(0.0, f64::max);
        Shot {
            index,
            seed: settings.seed,
            source_surface: patch.surface,
            polygon: patch.corners,
            corner_count: patch.corner_count as usize,
            source: SourcePolygon::new(polygon),
            normal: mesh.surfaces[patch.surface as usize].normal,
            centre,
            area: patch.area,
            diameter,
            unshot,
            samples: settings.samples,
            method: settings.form_factors,
            hemicube_resolution: settings.hemicube_resolution,
            hemicube: OnceLock::new(),
            shadows: settings.shadows,
            occluder,
            kd,
            regions: None,
            ray_share: None,
        }
    }
}

impl Shot<'_> {
    pub fn polygon(&self) -> &[DVec3] {
        &self.polygon[..self.corner_count]
    }

    /// The receiving point of vertex `v` (a small step inside an element it
    /// belongs to) and its shading normal ([`crate::mesh::MeshVertex::normal`]:
    /// the polygon's normal on a flat facet, the interpolated corner normals on
    /// a smooth surface). The receiving cosine of every form factor, the
    /// horizon clip of the source and the ray origin's lift use it; the
    /// source's own cosine stays its plane's, since emission and shooting are
    /// one-sided about the polygon that emits.
    pub fn receiving_point(&self, mesh: &Mesh, v: u32) -> (DVec3, DVec3) {
        receiving_point(mesh, v, self.occluder.scene_epsilon())
    }

    /// F(v←s): the form factor from vertex `v`'s receiving point to the source,
    /// with visibility, and the number of rays that reached the source.
    ///
    /// * `Analytic` (default): the exact unoccluded point-to-polygon factor
    ///   times the visible fraction of `samples` stratified, jittered rays to
    ///   the part of the source above the receiver's horizon (design notes,
    ///   "Form factors"): a pooled set ([`SamplePool`]) when the whole source is
    ///   above it, else a set drawn on the clipped part
    ///   ([`Shot::draw_part_samples`]).
    /// * `Wallace`: Remington 1992, eq. 3.1 over a pooled set on the whole source.
    /// * `Hemicube`: the exact unoccluded factor when the source's centre is
    ///   visible by a hemicube item buffer on it (radiosity lecture notes, "on the shooting patch
    ///   when shooting"; see [`Shot::hemicube_visible`]), else 0. No rays are
    ///   traced.
    ///
    /// Rays run between points lifted `scene_epsilon` off both surfaces along
    /// their normals: from the receiving point, and to each sample on the
    /// source. Lifting only the origin is not enough: a ray from a receiver
    /// next to the source's edge (a room's corner) runs at a grazing angle to
    /// the source's plane, and the f32 occluder then finds the source itself
    /// a little before the segment's end, blocking half of the rays.
    pub fn form_factor(
        &self,
        mesh: &Mesh,
        v: u32,
        pool: &SamplePool,
        scratch: &mut Scratch,
    ) -> (f64, u32, u32) {
        let at = ReceivingPoint::of_vertex(mesh, v, self.occluder.scene_epsilon());
        self.form_factor_sharing(mesh, &at, pool, scratch, 0.0)
    }

    /// [`Shot::form_factor`], with the `Analytic` method's rays cut in
    /// proportion below the unoccluded factor `full_factor`
    /// ([`super::ray_share`]; 0 traces every ray). The visible count is
    /// returned scaled to `samples` rays (k of n as k · samples / n), the
    /// rays as traced.
    pub fn form_factor_sharing(
        &self,
        mesh: &Mesh,
        at: &ReceivingPoint,
        pool: &SamplePool,
        scratch: &mut Scratch,
        full_factor: f64,
    ) -> (f64, u32, u32) {
        let ReceivingPoint {
            q,
            n,
            surface,
            stream: v,
        } = *at;
        // Cheap culls before the contour integral: a receiver clearly behind the
        // one-sided source, or one that faces away from every source corner,
        // gets nothing. The margin leaves points near the source's plane to
        // the exact factor, which returns the limit from the front there.
        if self.normal.dot(q - self.centre) < -1e-6 * self.diameter {
            return (0.0, 0, 0);
        }
        if self.polygon().iter().all(|&c| n.dot(c - q) <= 0.0) {
            return (0.0, 0, 0);
        }
        let origin = q + n * self.occluder.scene_epsilon();
        match self.method {
            FormFactorMethod::Analytic => {
                let unoccluded = self.source.form_factor(q, n);
                if unoccluded.is_nan() || unoccluded <= NEGLIGIBLE_FACTOR {
                    return (0.0, 0, 0);
                }
                if !self.shadows {
                    return (unoccluded, self.samples, 0);
                }
                // A source entirely in the receiver's closed upper half-space
                // (corners on the tangent plane allowed, as where a wall meets
                // the floor) uses a pooled set: a ray from the lifted origin to
                // a target at height ≥ 0 reaches the receiving plane at most at
                // its end, which the occluder excludes. The tolerance, 1e-6 ε,
                // absorbs rounding of corners on the plane and moves such a
                // crossing no further than 1e-6 of the segment from its end.
                let rays = super::ray_share::rays_for(self.samples, unoccluded, full_factor);
                let visible = if self.source_above_horizon(q, n) {
                    let ((_, lifted), offset) = pool.set_and_offset(self, v);
                    if rays == self.samples {
                        self.occluder.count_visible(origin, lifted)
                    } else {
                        super::ray_share::strided(lifted, rays, offset, &mut scratch.points);
                        self.occluder.count_visible(origin, &scratch.points)
                    }
                } else {
                    self.draw_part_samples(
                        q,
                        n,
                        v,
                        rays,
                        &mut scratch.clipped,
                        &mut scratch.points,
                    );
                    let lift = self.normal * self.occluder.scene_epsilon();
                    scratch.points.iter_mut().for_each(|p| *p += lift);
                    self.occluder.count_visible(origin, &scratch.points)
                };
                let fraction = visible as f64 / rays as f64;
                let scaled = visible * (self.samples / rays);
                (unoccluded * fraction, scaled, rays)
            }
            FormFactorMethod::Wallace => {
                let (points, targets) = pool.set_for(self, v);
                let rays = if self.shadows {
                    self.occluder
                        .visible_each(origin, targets, &mut scratch.flags);
                    self.samples
                } else {
                    scratch.flags.clear();
                    scratch.flags.resize(points.len(), true);
                    0
                };
                let factor = wallace(q, n, points, self.normal, self.area, &scratch.flags);
                let visible = scratch.flags.iter().filter(|&&f| f).count() as u32;
                let visible = if factor > 0.0 { visible } else { 0 };
                (factor, visible, rays)
            }
            FormFactorMethod::Hemicube => {
                let unoccluded = self.source.form_factor(q, n);
                if unoccluded.is_nan() || unoccluded <= NEGLIGIBLE_FACTOR {
                    return (0.0, 0, 0);
                }
                if !self.shadows {
                    return (unoccluded, 1, 0);
                }
                if self.hemicube_visible(mesh, q, surface) {
                    (unoccluded, 1, 0)
                } else {
                    (0.0, 0, 0)
                }
            }
        }
    }

    /// Whether receiving point `q` on `surface` sees the source's centre, by
    /// the hemicube method ([`ItemBuffer::segment_visible`] over the 3 × 3
    /// block of cells around `q`'s direction).
    ///
    /// The item buffer is a hemicube of `hemicube_resolution` on the source
    /// patch's centre over every input surface (item k = surface k), rotated
    /// about the normal by the golden angle times the shot index so that the
    /// cell grid's aliasing does not line up from shot to shot. It is rendered
    /// once per shot, on the first query (a shot that never asks, such as a
    /// replayed shot no new vertex needs, renders nothing). It is a one-point
    /// view of the source, like Remington's (1992) single sample: hard shadows as seen from
    /// the source's centre. The buffer finds the candidate occluders and each
    /// is tested exactly against the segment, so walls meeting at a room's
    /// corner or a box's edges cast no false shadows.
    pub fn hemicube_visible(&self, mesh: &Mesh, q: DVec3, surface: u32) -> bool {
        let buffer = self.hemicube.get_or_init(|| {
            let mut buffer = ItemBuffer::with_resolution(self.hemicube_resolution);
            let source = &mesh.surfaces[self.source_surface as usize];
            let angle = hemicube::GOLDEN_ANGLE * self.index as f64;
            let hint = source.tangent * angle.cos() + source.bitangent * angle.sin();
            // A degenerate normal leaves the buffer unrendered: nothing can be
            // looked up, so nothing is seen.
            if let Some(frame) = hemicube::Frame::new(self.centre, self.normal, hint) {
                let targets: Vec<&[DVec3]> = mesh
                    .surfaces
                    .iter()
                    .map(|s| s.vertices.as_slice())
                    .collect();
                buffer.render(&frame, &targets);
            }
            buffer
        });
        buffer
            .segment_visible(
                q,
                surface,
                HEMICUBE_SEARCH_RADIUS,
                self.occluder.scene_epsilon(),
            )
            .unwrap_or(false)
    }

    /// Whether the whole source lies in the receiver's closed upper half-space
    /// (corners on its tangent plane allowed, within 1e-6 ε), so that the
    /// shot's pooled sample sets serve it (see [`Shot::form_factor`]).
    #[inline]
    pub fn source_above_horizon(&self, q: DVec3, n: DVec3) -> bool {
        let floor = -1e-6 * self.occluder.scene_epsilon();
        self.polygon().iter().all(|&c| n.dot(c - q) >= floor)
    }

    /// The (unlifted) sample points on the source that receiver `v` at `q`, with
    /// normal `n`, traces to, written into `points`: the shot's pooled set when
    /// the source is above the receiver's horizon, else a set over the part in
    /// front of it ([`Shot::draw_part_samples`]). The directional
    /// transports (SH and global cube) draw their samples here, so they are
    /// exactly the diffuse path's.
    pub fn receiver_samples(
        &self,
        pool: &SamplePool,
        q: DVec3,
        n: DVec3,
        v: u32,
        clipped: &mut Vec<DVec3>,
        points: &mut Vec<DVec3>,
    ) {
        if self.source_above_horizon(q, n) {
            points.clear();
            points.extend_from_slice(pool.set_for(self, v).0);
        } else {
            self.draw_part_samples(q, n, v, self.samples, clipped, points);
        }
    }

    /// Writes `samples` points of the part of the source in front of the
    /// receiver (ray origin `origin`, normal `n`) into `scratch.points`,
    /// stratified uniformly in the solid angle it subtends (RNG stream
    /// (seed, shot, vertex), as [`Shot::draw_part_samples`]); `false`, with
    /// nothing drawn, when that part subtends no solid angle.
    fn solid_angle_samples(
        &self,
        origin: DVec3,
        n: DVec3,
        v: u32,
        scratch: &mut SampleScratch,
    ) -> bool {
        clip_to_halfspace(self.polygon(), origin, n, &mut scratch.clipped);
        let mut rng = Rng::new(self.seed, stream_id(self.index, v as u64));
        let solid_angle = stratified_solid_angle_points(
            origin,
            &scratch.clipped,
            self.samples,
            &mut rng,
            &mut scratch.points,
        );
        solid_angle > 0.0 && !scratch.points.is_empty()
    }

    /// Draws `count` stratified, jittered points (RNG stream (seed, shot,
    /// vertex)) into `points` over the part of the source in front of
    /// the receiver: the source clipped to the half-space n · (x − o) ≥ 0 with o
    /// the ray origin, ε above the receiving point.
    ///
    /// The analytic factor already leaves out the part of the source behind the
    /// receiver's tangent plane, so the visible fraction must be estimated over
    /// the rest only: sampling the whole source would multiply the factor by
    /// the fraction of the source above the horizon a second time (and blocked
    /// rays through the receiver's own surface would make it noisy). Clipping
    /// at the origin's height rather than the point's keeps every ray above
    /// the receiving plane, at the cost of an ε-thin band of the source. `count` is `samples`, or
    /// fewer under the ray share ([`super::ray_share`]).
    fn draw_part_samples(
        &self,
        q: DVec3,
        n: DVec3,
        v: u32,
        count: u32,
        clipped: &mut Vec<DVec3>,
        points: &mut Vec<DVec3>,
    ) {
        let origin = q + n * self.occluder.scene_epsilon();
        clip_to_halfspace(self.polygon(), origin, n, clipped);
        let part: &[DVec3] = if clipped.len() >= 3 {
            clipped
        } else {
            // Only a sliver (numerically nothing) is in front: its factor is
            // negligible; sample the whole source rather than nothing.
            self.polygon()
        };
        let mut rng = Rng::new(self.seed, stream_id(self.index, v as u64));
        stratified_points(part, count, &mut rng, points);
    }

    /// ΔL_v = Kd · U_s · F(v←s) (Remington 1992, Fig. 3.6: ΔRad = SP.unshotRad ·
    /// V.reflectance · F, in radiance: L = B/π on both sides).
    ///
    /// `prior`: every vertex's radiance before this shot, for the ray share
    /// ([`super::ray_share`]); `None`, or a shot without a share, traces
    /// every ray.
    pub fn receive(
        &self,
        mesh: &Mesh,
        v: u32,
        pool: &SamplePool,
        scratch: &mut Scratch,
        prior: Option<&[DVec3]>,
    ) -> Received {
        let at = ReceivingPoint::of_vertex(mesh, v, self.occluder.scene_epsilon());
        self.receive_at(mesh, &at, pool, scratch, prior.map(|p| p[v as usize]))
    }

    /// [`Shot::receive`] at a receiving point; `prior`: its radiance before
    /// this shot, for the ray share.
    pub fn receive_at(
        &self,
        mesh: &Mesh,
        at: &ReceivingPoint,
        pool: &SamplePool,
        scratch: &mut Scratch,
        prior: Option<DVec3>,
    ) -> Received {
        // A planar polygon cannot light itself; a black one reflects nothing.
        let kd = self.kd[at.surface as usize];
        if at.surface == self.source_surface || kd == DVec3::ZERO {
            return Received::default();
        }
        let full_factor = match (&self.ray_share, prior) {
            (Some(share), Some(prior)) => share.full_factor(prior, kd, self.unshot),
            _ => 0.0,
        };
        let (factor, visible, rays) =
            self.form_factor_sharing(mesh, at, pool, scratch, full_factor);
        let radiance = match &self.regions {
            Some(regions) if factor > 0.0 && self.method == FormFactorMethod::Analytic => {
                kd * self.region_radiance(at.q, at.n, regions, factor)
            }
            _ => kd * self.unshot * factor,
        };
        Received {
            radiance,
            visible,
            rays,
        }
    }
}

impl Shot<'_> {
    /// Σ_q U_q F(v←q) · f: the factors of the source's quadrants, each
    /// weighted by its own unshot radiance, times the visible fraction f of
    /// the whole source (`factor` / F(v←s), with F(v←s) = Σ_q F(v←q)). The
    /// fraction is the whole source's: per quadrant, the few visibility rays
    /// (2 to 16 in all) would add more noise than the split removes bias.
    ///
    /// Near the source (within [`regions::FAR`] diameters of its centre) the
    /// quadrants' factors are the exact point-to-polygon ones; farther away
    /// only their ratios matter, and the differential kernel at each
    /// quadrant's centroid gives those to O((D / 2d)²) of the correction,
    /// without four contour integrals per receiver.
    fn region_radiance(&self, q: DVec3, n: DVec3, regions: &Regions, factor: f64) -> DVec3 {
        let (weighted, whole) =
            regions.factor_weights(self.centre, self.diameter, self.normal, q, n);
        if whole > 0.0 {
            weighted * (factor / whole)
        } else {
            self.unshot * factor
        }
    }
}

/// The receiving point of vertex `v` and its shading normal (see
/// [`Shot::receiving_point`]), for an occluder of scene epsilon `epsilon`.
pub fn receiving_point(mesh: &Mesh, v: u32, epsilon: f64) -> (DVec3, DVec3) {
    let vertex = &mesh.vertices[v as usize];
    let to_inside = vertex.inward - vertex.position;
    let distance = to_inside.length();
    let q = if distance > 0.0 {
        let step = (INWARD_STEP * distance)
            .max(2.0 * epsilon)
            .min(0.5 * distance);
        vertex.position + to_inside * (step / distance)
    } else {
        vertex.position
    };
    (q, vertex.normal)
}

/// How [`visible_samples`] spreads its samples over a source.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleBy {
    /// Uniform in area, equal shares: the diffuse path's samples, enough
    /// where only the visible fraction matters (both ends diffuse).
    Area,
    /// Uniform in solid angle, shares by the receiver's cosine: where the
    /// incoming direction matters (a glossy receiver or source).
    SolidAngle,
}

/// Per-worker buffers of [`visible_samples`]; `samples` holds its answer.
#[derive(Default)]
pub struct SampleScratch {
    points: Vec<DVec3>,
    clipped: Vec<DVec3>,
    targets: Vec<DVec3>,
    flags: Vec<bool>,
    /// Visible samples: (point on the source, share of the factor).
    pub samples: Vec<(DVec3, f64)>,
    /// The occluded samples, likewise (the Analytic factor's): with the
    /// visible ones their shares sum to the unoccluded factor.
    pub occluded: Vec<(DVec3, f64)>,
}

/// The visible samples of `shot`'s source seen from vertex `v`'s receiving
/// point, with their shares of F(v←s), into `scratch.samples`: the samples,
/// culls and visibility of [`Shot::form_factor`], so the shares sum to its
/// factor (tests `pair_factors_equal_the_shooters` in `solve/cube_gather`, and the
/// Ks = 0 ≡ diffuse tests of directional mode). Returns the receiving
/// point, the visible sample count and the rays traced. The directional
/// transports (SH shooting and the global-cube gather) read their incoming
/// directions from here.
///
/// `by`: [`SampleBy::Area`] takes the diffuse path's samples, uniform in
/// area with equal shares. [`SampleBy::SolidAngle`] (Analytic factor with
/// shadows only; otherwise as `Area`) spreads them uniformly in the solid
/// angle the part of the source in front of the receiver subtends
/// (`geometry/solid_angle.rs`), and each visible one carries F · cos θ_i /
/// Σ_j cos θ_j of the exact unoccluded factor F (θ the angle at the
/// receiver, the sum over every sample, visible or not). Equal area shares
/// estimate F times the source's mean over its *area*, so near a source they
/// send a glossy receiver's light from the wrong directions, a bias no
/// sample count removes; shares by solid angle follow dF
/// (docs/lab/glossy-solid-angle-samples.md, "Glossy: samples by solid angle").
pub fn visible_samples(
    s: &Shot,
    mesh: &Mesh,
    v: u32,
    pool: &SamplePool,
    scratch: &mut SampleScratch,
    by: SampleBy,
) -> (DVec3, u32, u32) {
    let at = ReceivingPoint::of_vertex(mesh, v, s.occluder.scene_epsilon());
    visible_samples_at(s, &at, pool, scratch, by)
}

/// [`visible_samples`] at a receiving point, its random numbers from the
/// point's stream (a vertex's id, or a small surface's, `small.rs`).
pub fn visible_samples_at(
    s: &Shot,
    at: &ReceivingPoint,
    pool: &SamplePool,
    scratch: &mut SampleScratch,
    by: SampleBy,
) -> (DVec3, u32, u32) {
    scratch.samples.clear();
    scratch.occluded.clear();
    let (q, n, v) = (at.q, at.n, at.stream);
    if s.normal.dot(q - s.centre) < -1e-6 * s.diameter {
        return (q, 0, 0);
    }
    if s.polygon().iter().all(|&c| n.dot(c - q) <= 0.0) {
        return (q, 0, 0);
    }
    let origin = q + n * s.occluder.scene_epsilon();
    let lift = s.normal * s.occluder.scene_epsilon();
    match s.method {
        FormFactorMethod::Analytic | FormFactorMethod::Hemicube => {
            let unoccluded = s.source.form_factor(q, n);
            if unoccluded.is_nan() || unoccluded <= 0.0 {
                return (q, 0, 0);
            }
            if !s.shadows {
                // No rays: the whole factor comes from the source's centre.
                scratch.samples.push((s.centre, unoccluded));
                return (q, s.samples, 0);
            }
            let solid_angle = by == SampleBy::SolidAngle
                && matches!(s.method, FormFactorMethod::Analytic)
                && s.solid_angle_samples(origin, n, v, scratch);
            if !solid_angle {
                s.receiver_samples(pool, q, n, v, &mut scratch.clipped, &mut scratch.points);
            }
            scratch.targets.clear();
            scratch
                .targets
                .extend(scratch.points.iter().map(|&p| p + lift));
            s.occluder
                .visible_each(origin, &scratch.targets, &mut scratch.flags);
            // Equal shares: the samples are uniform in area, so the incoming
            // directions of a source much larger than its distance are spread
            // by area rather than by differential factor. That is harmless
            // between two diffuse ends (only the visible fraction matters);
            // where direction matters the SH shooter samples by solid angle
            // instead ([`SampleBy::SolidAngle`]). (Weighting area
            // samples by Remington 1992, eq. 3.1's term was tried: with 16
            // samples it concentrates a corner's light on a few cells and
            // raised the largest row sum γ of a glossy furnace from 0.87 to
            // 0.999.)
            let cosine = |p: DVec3| (p - origin).normalize_or_zero().dot(n).max(0.0);
            let total: f64 = if solid_angle {
                scratch.points.iter().map(|&p| cosine(p)).sum()
            } else {
                0.0
            };
            let share = |p: DVec3| {
                if total > 0.0 {
                    unoccluded * cosine(p) / total
                } else {
                    unoccluded / s.samples as f64
                }
            };
            let mut visible = 0;
            for (p, &f) in scratch.points.iter().zip(&scratch.flags) {
                if f {
                    visible += 1;
                    scratch.samples.push((*p, share(*p)));
                } else {
                    scratch.occluded.push((*p, share(*p)));
                }
            }
            (q, visible, s.samples)
        }
        FormFactorMethod::Wallace => {
            let (points, _) = pool.set_for(s, v);
            scratch.points.clear();
            scratch.points.extend_from_slice(points);
            let rays = if s.shadows {
                scratch.targets.clear();
                scratch
                    .targets
                    .extend(scratch.points.iter().map(|&p| p + lift));
                s.occluder
                    .visible_each(origin, &scratch.targets, &mut scratch.flags);
                s.samples
            } else {
                scratch.flags.clear();
                scratch.flags.resize(scratch.points.len(), true);
                0
            };
            // Remington 1992, eq. 3.1 term by term: each sample's disc is A/n.
            let disc = s.area / scratch.points.len().max(1) as f64;
            let mut visible = 0;
            for (p, &f) in scratch.points.iter().zip(&scratch.flags) {
                let term = wallace(q, n, std::slice::from_ref(p), s.normal, disc, &[f]);
                if term > 0.0 {
                    visible += 1;
                    scratch.samples.push((*p, term));
                }
            }
            (q, visible, rays)
        }
    }
}
