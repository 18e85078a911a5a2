//! Adaptive subdivision after a shot (Remington 1992, §3.3 and Fig. 3.6 step 5c).
//!
//! An element edge whose end vertices differ in visibility of the source is on
//! a shadow boundary. A leaf splits when the radiance difference across one of
//! its edges, less twice its sampling noise, exceeds `threshold × local
//! radiance` (`shadow_threshold` on shadow boundaries, `edge_threshold`
//! elsewhere), it is larger than the smallest element ([`Criteria::at_smallest`]:
//! its longest edge above the surface's absolute `min_element_size`, or in the
//! flat rule its area above `min_element_area × polygon area`) and its
//! depth is below `max_depth` ([`Criteria::should_split_at`]). The local
//! radiance is the level the vertices are heading for (L + Kd · ambient), never
//! less than [`DARK_FLOOR`] of the scene's level, so the test is relative
//! (design notes, "Automatic meshing"): the same mesh results whatever the
//! units or the emitters' strength.
//!
//! New vertices get the radiance of earlier shots interpolated from the corners
//! that define them (edge midpoint: the two ends; quad centre: the four
//! corners), Remington's (1992) "accumulated radiosity interpolated from the vertices on
//! either side", and are then shot to by the current source; their children are
//! tested again, recursively, until every edge passes or can split no more.
//!
//! Remington 1992 argues the interpolation is accurate because an edge with a large
//! difference would have been split when its light was shot. That holds only if
//! every shot's structure is resolved as it is shot, which a test on partial
//! sums does badly (the first of 16 light patches makes every surface look
//! like a shadow boundary; a ceiling lit by one wall patch looks like one big
//! gradient). So the solver records every shot from an emitter's patch
//! ([`super::shoot::RecordedShot`]) and keeps, per vertex, the part of its
//! radiance that came from them: a new vertex interpolates only the rest (the
//! emission and the indirect light, which is smooth) and receives every
//! recorded shot exactly. A shadow boundary can thus be refined whenever the
//! test finds it, with the direct light at new vertices computed, not guessed.
//! Emitter patches shoot few times, so this costs a few recorded shots' rays
//! per new vertex.
//!
//! Unshot radiance of earlier shots is not interpolated: it was gathered into
//! the patches after each shot (see the module documentation of
//! [`crate::solve`]), so a split neither creates nor loses unshot energy; the
//! current shot's unshot at a new vertex is its own, computed ΔL. (A new vertex
//! does receive the recorded shots' light, so its radiance is better than the
//! interpolation the patches' unshot was gathered from; the difference is
//! below the split threshold by construction and is not re-gathered.)
//!
//! Remington 1992 refines only after emitters shoot; here every shot may refine, since
//! indirect light casts shadows too, and an edge that already passed is only
//! tested again when the shot changed one of its ends.

use super::budget::SplitBudget;
use super::group_shot::{GroupShot, Shooter};
use super::lights::LightShot;
use super::shoot::{Received, SamplePool, Scratch, Shot};
use crate::mesh::{Mesh, NewVertex};
use crate::settings::SolverSettings;
use glam::DVec3;
use rayon::prelude::*;

/// The split thresholds of one solve.
#[derive(Clone, Copy, Debug)]
pub struct Criteria {
    pub edge_threshold: f64,
    pub shadow_threshold: f64,
    pub max_depth: u32,
    /// Fraction of the polygon's area: the floor of a mesh built by count
    /// alone ([`crate::mesh::Sizing::flat`], which tests use), whose surfaces
    /// have no absolute `min_element_size`
    /// ([`crate::mesh::Surface::min_element_size`]); a solve's mesh always
    /// has one.
    pub min_element_area: f64,
    /// Visibility rays per receiver (the n of the noise allowance).
    pub samples: u32,
    /// The least "local radiance" a difference is measured against (absolute,
    /// W·sr⁻¹·m⁻²); see [`DARK_FLOOR`]. 0 compares with the local radiance only.
    pub dark_floor: f64,
    /// The ambient radiance (Cohen et al. 1988) of the light not yet shot: a
    /// vertex's local radiance is taken as L + Kd · ambient, the level it is
    /// heading for, not the partial sum of the shots so far.
    pub ambient: DVec3,
}

/// Differences are judged relative to the local radiance, but never relative
/// to less than this fraction of the scene's radiance level (Cohen et al.'s
/// ambient term of the unsolved scene: emitted power over π · total area,
/// times 1 / (1 − average reflectance), i.e. the mean radiance the solution
/// will have). Weber's law, which the relative test models, fails in the dark
/// part of the range a display shows: in the dark side of a wide penumbra
/// radiance rises from zero, so relative differences between neighbours stay
/// large down to any element size and a purely relative test refines the whole
/// penumbra to the maximum depth. The floor is relative to the scene's own
/// level, so the mesh still does not depend on units or emitter strength.
pub const DARK_FLOOR: f64 = 0.1;

/// [`Criteria::min_element_area`] of a solve: Remington's (1992) flat floor,
/// which only a mesh built by count alone reaches.
pub const FLAT_MIN_ELEMENT_AREA: f64 = 5e-5;

impl Criteria {
    pub fn from_settings(s: &SolverSettings) -> Self {
        Criteria {
            edge_threshold: s.edge_threshold,
            shadow_threshold: s.shadow_threshold,
            max_depth: s.max_depth,
            min_element_area: FLAT_MIN_ELEMENT_AREA,
            samples: if s.shadows { s.samples } else { 0 },
            dark_floor: 0.0,
            ambient: DVec3::ZERO,
        }
    }

    /// Whether element `e` is as small as elements may get: its longest edge at
    /// most its surface's absolute `min_element_size` (size-driven meshing, the
    /// same floor on a small polygon as on a large one), else its area at most
    /// `min_element_area` of its polygon's (the flat rule). The longest edge,
    /// not √area, bounds the distance over which radiance is interpolated
    /// linearly, which is what meshing bias grows with; a sliver is refined
    /// until its long side is short.
    pub fn at_smallest(&self, mesh: &Mesh, e: u32) -> bool {
        let el = &mesh.elements[e as usize];
        let surface = &mesh.surfaces[mesh.patches[el.patch as usize].surface as usize];
        match surface.min_element_size {
            Some(size) => longest_edge(mesh, e) <= size,
            None => el.area <= self.min_element_area * surface.area,
        }
    }

    /// The threshold for an edge whose ends saw `visible_a` and `visible_b`
    /// of the shot's rays: the shadow threshold across a visibility change,
    /// else the edge threshold.
    pub fn threshold_between(&self, visible_a: u32, visible_b: u32) -> f64 {
        if visible_a != visible_b {
            self.shadow_threshold
        } else {
            self.edge_threshold
        }
    }

    /// The binomial relative variance (n − k)/(k n) of a visible fraction
    /// k/n, n the samples per source: σ² of a shot's ΔL over ΔL². 0 when
    /// every ray or none got through (see [`Criteria::should_split_at`]).
    pub fn visibility_variance(&self, visible: u32) -> f64 {
        let (k, n) = (visible as f64, self.samples.max(1) as f64);
        if k > 0.0 && k < n {
            (n - k) / (k * n)
        } else {
            0.0
        }
    }

    /// Whether leaf `e` must split given the vertices' radiance, this shot's
    /// ΔL and their visibility of the current source (rays that reached it).
    ///
    /// An edge a–b fails when, in some channel,
    ///
    /// |L_a − L_b| − 2 √(σ_a² + σ_b²) > threshold · max(L̂_a, L̂_b, dark floor)
    ///
    /// (the brightest channel of the brighter end), with L̂ = L + Kd · ambient
    /// the radiance the vertex is heading for. Measuring against the partial
    /// sum L alone refines every surface lit only indirectly (a ceiling) early
    /// in the solve, when a few shots make up all of its light and each
    /// varies across it by tens of percent; Remington 1992 avoided this by refining only
    /// after emitters shot (step 5c).
    ///
    ///
    /// where σ_v is the standard error of this shot's ΔL_v from its k of n
    /// visible rays, taken as binomial: ΔL = K · F · k/n, so σ_v = ΔL_v ·
    /// √((n − k)/(k n)) (0 when every ray or none got through). Without the
    /// noise term a relative test refines every penumbra to the maximum depth:
    /// neighbouring vertices that see 1 and 2 of 16 rays differ by 100%
    /// whatever their distance, so the differences never shrink with the
    /// elements. Stratified sampling is less noisy than binomial, so the
    /// allowance errs toward splitting less in deep penumbrae, never on a
    /// sharp boundary (k = n against k = 0 has no noise).
    pub fn should_split_at(
        &self,
        mesh: &Mesh,
        kd: Option<&[DVec3]>,
        radiance: &[DVec3],
        received: &[DVec3],
        visible: &[u32],
        e: u32,
    ) -> bool {
        let el = &mesh.elements[e as usize];
        if !el.is_leaf() || el.depth as u32 >= self.max_depth {
            return false;
        }
        if self.at_smallest(mesh, e) {
            return false;
        }
        let corners = el.corners();
        let count = corners.len();
        // All corners of an element share its surface, hence its reflectance.
        let reflectance = kd.map_or(DVec3::ONE, |kd| {
            kd[mesh.patches[el.patch as usize].surface as usize]
        });
        let level = |v: usize| (radiance[v] + reflectance * self.ambient).max_element();
        // Early out: no edge can differ by more than the spread of the corners,
        // and no edge's local level is below the lowest corner's (or the dark
        // floor), whatever the noise allowance (which only lowers differences).
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        let mut lowest = f64::INFINITY;
        for &c in corners {
            let l = radiance[c as usize];
            lo = lo.min(l);
            hi = hi.max(l);
            lowest = lowest.min(level(c as usize));
        }
        let least = self.edge_threshold.min(self.shadow_threshold) * lowest.max(self.dark_floor);
        if (hi - lo).max_element() <= least {
            return false;
        }
        let sigma = |v: usize| received[v].abs() * self.visibility_variance(visible[v]).sqrt();
        (0..count).any(|k| {
            let (a, b) = (corners[k] as usize, corners[(k + 1) % count] as usize);
            let threshold = self.threshold_between(visible[a], visible[b]);
            let (la, lb) = (radiance[a], radiance[b]);
            let local = level(a).max(level(b)).max(self.dark_floor);
            let (sa, sb) = (sigma(a), sigma(b));
            let noise = (sa * sa + sb * sb).powf(0.5) * 2.0;
            local > 0.0 && ((la - lb).abs() - noise).max_element() > threshold * local
        })
    }
}

/// The longest edge of element `e`: it bounds the distance over which
/// radiance is interpolated linearly (a split halves every edge).
pub fn longest_edge(mesh: &Mesh, e: u32) -> f64 {
    let corners = mesh.elements[e as usize].corners();
    let position = |k: usize| mesh.vertices[corners[k] as usize].position;
    (0..corners.len())
        .map(|k| (position((k + 1) % corners.len()) - position(k)).length())
        .fold(0.0, f64::max)
}

/// The per-vertex state refinement reads and extends.
pub struct VertexState<'a> {
    pub radiance: &'a mut Vec<DVec3>,
    pub received: &'a mut Vec<DVec3>,
    pub visible: &'a mut Vec<u32>,
    /// The part of `radiance` from recorded (emitter) shots.
    pub direct: &'a mut Vec<DVec3>,
}

/// The recorded shots, re-evaluated exactly at new vertices.
pub struct Replay<'a, 'b> {
    /// Every emitter shot so far, in order, the current one last if it is one.
    pub recorded: &'b [Shot<'a>],
    /// Their sample pools.
    pub pools: &'b [SamplePool],
    /// The emitters' first shots taken in groups, in order; replayed with
    /// `recorded` in shot order, so the current shot is the last replayed
    /// if it is recorded, alone or in a group.
    pub groups: &'b [GroupShot<'a>],
    /// The lights' shot, which every solve with lights shoots first.
    pub lights: Option<&'b LightShot<'a>>,
    /// Whether the current shot is the last of `recorded`.
    pub current_recorded: bool,
}

/// What a refinement pass did.
#[derive(Debug, Default)]
pub struct Refined {
    pub splits: usize,
    pub rays: u64,
    /// Surfaces whose mesh changed (their display triangulation and gather
    /// weights must be rebuilt).
    pub dirty_surfaces: Vec<u32>,
    /// The patches whose display triangulation changed, sorted: those of the
    /// split elements and those a new vertex lies on the edge of.
    pub dirty_patches: Vec<u32>,
}

/// A solve mode's per-vertex state as adaptive subdivision sees it: the
/// diffuse radiance ([`DiffuseField`]) or directional mode's SH coefficients
/// (`super::directional`). [`refine_field`] drives either with the same loop,
/// the same candidates, the same splitting and the same replay of recorded
/// shots, so the two modes mesh alike wherever their vertices agree.
pub trait Field: Sync {
    /// Whether the current shot changed vertex `v` (its leaves are tested).
    fn changed(&self, v: u32) -> bool;
    /// Whether leaf `e` must split.
    fn should_split(&self, mesh: &Mesh, criteria: &Criteria, e: u32) -> bool;
    /// Appends the state of the vertices `created` (ids following the last
    /// vertex): the smooth part of their radiance (emission and indirect
    /// light, less the recorded shots and this shot) averaged from their
    /// parents, and nothing received yet.
    fn interpolate(&mut self, mesh: &Mesh, created: &[NewVertex]);
    /// Shoots every recorded shot and the current one (once, if it is not
    /// recorded) to the vertices `created` and adds the light; returns the
    /// rays traced.
    fn receive(&mut self, mesh: &Mesh, created: &[NewVertex]) -> u64;
    /// The patches whose leaves may have a changed corner (the surfaces the
    /// shot touched, `super::footprint`), sorted; `None`: every leaf is a
    /// candidate, found by a scan of the whole mesh.
    fn scan(&self) -> Option<&[u32]> {
        None
    }
}

/// The leaves with a changed corner, in increasing order: those of the
/// patches `field.scan()` names, or of the whole mesh.
fn changed_leaves<F: Field>(mesh: &Mesh, field: &F) -> Vec<u32> {
    let changed = |e: u32| {
        let el = &mesh.elements[e as usize];
        el.is_leaf() && el.corners().iter().any(|&c| field.changed(c))
    };
    let Some(patches) = field.scan() else {
        return (0..mesh.elements.len() as u32)
            .into_par_iter()
            .filter(|&e| changed(e))
            .collect();
    };
    let mut leaves: Vec<u32> = patches
        .par_iter()
        .flat_map_iter(|&p| {
            let mut leaves = Vec::new();
            mesh.patch_leaves(p, &mut leaves);
            leaves.retain(|&e| changed(e));
            leaves
        })
        .collect();
    // The whole-mesh scan's order, so the splits (and the new vertices' ids)
    // come out the same.
    leaves.sort_unstable();
    leaves
}

/// Refines after a shot: tests the leaves the shot changed, splits, has the
/// field interpolate and shoot the new vertices, and repeats on the children.
///
/// Each split first takes its cost from `budget` (see [`SplitBudget`]); the
/// first that does not fit ends the refinement, and it and the splits still
/// asked for at that level are counted as refused.
pub fn refine_field<F: Field>(
    mesh: &mut Mesh,
    field: &mut F,
    criteria: &Criteria,
    budget: &mut SplitBudget,
) -> Refined {
    let mut dirty = vec![false; mesh.surfaces.len()];
    let mut out = Refined::default();
    let mut candidates: Vec<u32> = changed_leaves(mesh, field);
    let mut created = Vec::new();
    loop {
        let to_split: Vec<u32> = {
            let (mesh, field) = (&*mesh, &*field);
            candidates
                .par_iter()
                .copied()
                .filter(|&e| field.should_split(mesh, criteria, e))
                .collect()
        };
        if to_split.is_empty() {
            break;
        }
        created.clear();
        let mut children = Vec::with_capacity(4 * to_split.len());
        let mut over_budget = false;
        for (k, &e) in to_split.iter().enumerate() {
            let surface = mesh.patches[mesh.elements[e as usize].patch as usize].surface;
            if !budget.take(surface) {
                budget.refused += (to_split.len() - k) as u64;
                over_budget = true;
                break;
            }
            // Only an impossible mesh size (2^32 vertices) can fail; stop
            // refining then rather than abort the solve.
            let before = created.len();
            let Ok(first) = mesh.split(e, &mut created) else {
                break;
            };
            out.splits += 1;
            children.extend(first..first + 4);
            dirty[surface as usize] = true;
            let patch = mesh.elements[e as usize].patch;
            out.dirty_patches.push(patch);
            let piece = mesh.patches[patch as usize].piece;
            for nv in &created[before..] {
                mesh.patches_at(piece, nv.uv, &mut out.dirty_patches);
            }
        }
        field.interpolate(mesh, &created);
        out.rays += field.receive(mesh, &created);
        if over_budget {
            break;
        }
        candidates = children;
    }
    out.dirty_patches.sort_unstable();
    out.dirty_patches.dedup();
    out.dirty_surfaces = (0..dirty.len() as u32)
        .filter(|&s| dirty[s as usize])
        .collect();
    out
}

/// The diffuse solver's [`Field`]: one radiance per vertex.
pub struct DiffuseField<'s, 'a, 'b> {
    pub state: VertexState<'s>,
    pub replay: &'s Replay<'a, 'b>,
    /// The current shot: a patch or a group (`group_shot.rs`).
    pub shooter: &'s Shooter<'s, 's>,
    /// The patches to scan for candidates ([`Field::scan`]).
    pub scan: Option<&'s [u32]>,
}

impl Field for DiffuseField<'_, '_, '_> {
    fn changed(&self, v: u32) -> bool {
        self.state.received[v as usize] != DVec3::ZERO
    }

    fn scan(&self) -> Option<&[u32]> {
        self.scan
    }

    fn should_split(&self, mesh: &Mesh, criteria: &Criteria, e: u32) -> bool {
        let s = &self.state;
        criteria.should_split_at(
            mesh,
            Some(self.shooter.kd()),
            s.radiance,
            s.received,
            s.visible,
            e,
        )
    }

    fn interpolate(&mut self, _mesh: &Mesh, created: &[NewVertex]) {
        let current_recorded = self.replay.current_recorded;
        let VertexState {
            radiance,
            received,
            visible,
            direct,
        } = &mut self.state;
        for nv in created {
            debug_assert_eq!(nv.id as usize, radiance.len());
            // The smooth part of each parent's radiance, averaged: less the
            // recorded shots and this shot's ΔL, which are recomputed exactly.
            let smooth = |p: usize| {
                let current = if current_recorded {
                    DVec3::ZERO
                } else {
                    received[p]
                };
                radiance[p] - direct[p] - current
            };
            let earlier = nv
                .parents()
                .iter()
                .map(|&p| smooth(p as usize))
                .sum::<DVec3>()
                / nv.parent_count as f64;
            radiance.push(earlier);
            received.push(DVec3::ZERO);
            visible.push(0);
            direct.push(DVec3::ZERO);
        }
    }

    fn receive(&mut self, mesh: &Mesh, created: &[NewVertex]) -> u64 {
        let (replay, shooter) = (self.replay, self.shooter);
        // A new vertex's level for the ray share: its interpolated radiance.
        let prior: &[DVec3] = self.state.radiance;
        let results: Vec<(DVec3, Received, u64)> = created
            .par_iter()
            .map_init(Scratch::default, |scratch, nv| {
                let mut exact = DVec3::ZERO;
                let mut rays = 0u64;
                let mut current = Received::default();
                // The lights shoot first, so when the current shot is
                // theirs it is the last (and only) one replayed.
                if let Some(lights) = replay.lights {
                    current = lights.receive(mesh, nv.id);
                    exact += current.radiance;
                    rays += current.rays as u64;
                }
                let mut groups = replay.groups.iter().peekable();
                let mut add = |received: Received| {
                    exact += received.radiance;
                    rays += received.rays as u64;
                    received
                };
                for (r, p) in replay.recorded.iter().zip(replay.pools) {
                    while let Some(g) = groups.next_if(|g| g.index < r.index) {
                        add(g.receive(mesh, nv.id, scratch, None));
                    }
                    current = add(r.receive(mesh, nv.id, p, scratch, None));
                }
                for g in groups {
                    current = add(g.receive(mesh, nv.id, scratch, None));
                }
                if !replay.current_recorded {
                    current = shooter.receive(mesh, nv.id, scratch, Some(prior));
                    rays += current.rays as u64;
                }
                (exact, current, rays)
            })
            .collect();
        let s = &mut self.state;
        let mut total = 0;
        for (nv, (exact, current, rays)) in created.iter().zip(&results) {
            let v = nv.id as usize;
            s.radiance[v] += *exact;
            if !replay.current_recorded {
                s.radiance[v] += current.radiance;
            }
            s.direct[v] = *exact;
            s.received[v] = current.radiance;
            s.visible[v] = current.visible;
            total += rays;
        }
        total
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, Polygon, Scene, SourceRef};
    use solution::camera::UpAxis;

    /// One unit square, one patch: element 0 with corners 0..4.
    fn square_mesh() -> Mesh {
        Mesh::new(&square_mesh_scene(), DVec3::ZERO, 1).unwrap()
    }

    /// The scene of [`square_mesh`].
    fn square_mesh_scene() -> Scene {
        Scene {
            lights: Default::default(),
            polygons: vec![Polygon {
                vertices: vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
                vertex_normals: None,
                material: 0,
                patches: 1,
                sizes: Default::default(),
                source: SourceRef::default(),
                uv_map: None,
            }],
            materials: vec![Material {
                name: "grey".into(),
                kd: DVec3::splat(0.5),
                ks: DVec3::ZERO,
                alpha: 1.0,
                emission: DVec3::ZERO,
                diffuse_texture: None,
                emission_texture: None,
                folded_texture: None,
            }],
            units_per_metre: 1.0,
            up_axis: UpAxis::PosY,
            camera: None,
            recentre_offset: DVec3::ZERO,
            warnings: Vec::new(),
        }
    }

    fn criteria() -> Criteria {
        Criteria {
            edge_threshold: 0.3,
            shadow_threshold: 0.1,
            max_depth: 4,
            min_element_area: 1e-3,
            samples: 16,
            dark_floor: 0.0,
            ambient: DVec3::ZERO,
        }
    }

    /// Radiance 1 at corners 0 and 3, `right` at corners 1 and 2, all of it
    /// from this shot, with `seen` of 16 rays at the right-hand corners.
    fn split(c: &Criteria, right: f64, seen_left: u32, seen_right: u32) -> bool {
        let mesh = square_mesh();
        let l = [1.0, right, right, 1.0].map(DVec3::splat);
        let visible = [seen_left, seen_right, seen_right, seen_left];
        c.should_split_at(&mesh, None, &l, &l, &visible, 0)
    }

    #[test]
    fn split_test_follows_thresholds_noise_floor_and_limits() {
        let c = criteria();
        // An ordinary edge (same visibility) splits above 30% of the brighter end.
        assert!(!split(&c, 0.75, 16, 16));
        assert!(split(&c, 0.65, 16, 16));
        // A sharp shadow boundary (16 of 16 rays against 0) has no sampling
        // noise and splits above 10%.
        assert!(split(&c, 0.0, 16, 0));
        // Deep penumbra: 2 and 1 of 16 rays (radiance 1 and 0.5) differ by 50%
        // of the brighter end, but the binomial allowance 2 √(σ₁² + σ₂²) with
        // σ = L √((n − k)/(k n)) is 2 √(0.66² + 0.48²) ≈ 1.6: no split.
        assert!(!split(&c, 0.5, 2, 1));
        // Half-lit against fully lit: difference 0.5, allowance 2 · 0.5 · √(1/16)
        // = 0.25, so 0.25 > 0.1 · 1: split.
        assert!(split(&c, 0.5, 16, 8));
        // The dark floor: the same 35% difference at radiance 1e-3 does not count
        // against a floor of 0.01 (0.35e-3 < 0.3 · 0.01).
        let dim = |c: &Criteria| {
            let mesh = square_mesh();
            let l = [1e-3, 0.65e-3, 0.65e-3, 1e-3].map(DVec3::splat);
            c.should_split_at(&mesh, None, &l, &l, &[16; 4], 0)
        };
        assert!(dim(&c));
        assert!(!dim(&Criteria {
            dark_floor: 0.01,
            ..c
        }));
        // Light still to come raises the level: with ambient 1 (Kd = 1 here) the
        // level is ~2 and a 0.35 difference is below 0.3 · 2.
        assert!(!split(
            &Criteria {
                ambient: DVec3::ONE,
                ..c
            },
            0.65,
            16,
            16
        ));
        // Depth and area limits.
        assert!(!split(&Criteria { max_depth: 0, ..c }, 0.0, 16, 0));
        assert!(!split(
            &Criteria {
                min_element_area: 1.0,
                ..c
            },
            0.0,
            16,
            0
        ));
    }

    /// Splits every leaf that is not yet [`Criteria::at_smallest`] until none
    /// is left, and returns the longest edge of the smallest leaves of each
    /// surface.
    fn smallest_edges(mesh: &mut Mesh, c: &Criteria) -> Vec<f64> {
        let mut created = Vec::new();
        loop {
            let open: Vec<u32> = mesh
                .leaves()
                .filter(|&e| {
                    !c.at_smallest(mesh, e) && (mesh.elements[e as usize].depth as u32) < 16
                })
                .collect();
            if open.is_empty() {
                break;
            }
            for e in open {
                mesh.split(e, &mut created).unwrap();
            }
        }
        let mut smallest = vec![f64::INFINITY; mesh.surfaces.len()];
        for e in mesh.leaves() {
            let el = &mesh.elements[e as usize];
            let corners = el.corners();
            let p = |k: usize| mesh.vertices[corners[k] as usize].position;
            let longest = (0..corners.len())
                .map(|k| (p((k + 1) % corners.len()) - p(k)).length())
                .fold(0.0, f64::max);
            let s = mesh.patches[el.patch as usize].surface as usize;
            smallest[s] = smallest[s].min(longest);
        }
        smallest
    }

    #[test]
    fn the_smallest_element_is_absolute_in_size_driven_meshing() {
        use crate::mesh::Sizing;
        // Squares of side 1 and 8, one patch each. Halving from 1 reaches
        // 0.25 after 2 splits, from 8 after 5: with an absolute floor of 0.25
        // (longest edge), both stop at exactly 0.25 (a leaf of 0.5 is above it,
        // one of 0.25 is not).
        let mut scene = square_mesh_scene();
        let big: Vec<DVec3> = scene.polygons[0]
            .vertices
            .iter()
            .map(|v| *v * 8.0 + DVec3::X * 3.0)
            .collect();
        let mut second = scene.polygons[0].clone();
        second.vertices = big;
        scene.polygons.push(second);
        let absolute = Sizing {
            min_element_size: Some(0.25),
            ..Sizing::flat(1)
        };
        let c = criteria();
        let mut mesh = Mesh::with_sizing(&scene, DVec3::ZERO, &absolute).unwrap();
        let edges = smallest_edges(&mut mesh, &c);
        assert!(
            (edges[0] - 0.25).abs() < 1e-12 && (edges[1] - 0.25).abs() < 1e-12,
            "{edges:?}"
        );
        // The flat rule's floor is a fraction of each polygon's area: with
        // 1/64 of it, a leaf stops at side/8 (area side²/64), 0.125 and 1.
        let flat = Criteria {
            min_element_area: 1.0 / 64.0,
            ..c
        };
        let mut mesh = Mesh::with_sizing(&scene, DVec3::ZERO, &Sizing::flat(1)).unwrap();
        let edges = smallest_edges(&mut mesh, &flat);
        assert!(
            (edges[0] - 0.125).abs() < 1e-12 && (edges[1] - 1.0).abs() < 1e-12,
            "{edges:?}"
        );
    }
}
