//! One shot, whatever light it carries (Remington 1992, Fig. 3.6 steps
//! 5a–5c; Fig. 4.7 for directional shooting): take the source's unshot
//! light, record the shot when an emitter shoots, shoot to every receiver,
//! refine the mesh where the result varies, and gather the shot's ΔL into
//! the patches.
//!
//! What the light is (RGB radiance per vertex, [`super::scalar`], or SH
//! coefficients per vertex, [`super::directional`]) is a [`Transport`]'s:
//! the order of the steps, the recording of emitter shots, the refinement
//! criteria and the bookkeeping are written here once. A transport with K
//! colours per source group (light groups) is one more implementation.

use super::refine::{Criteria, Refined, DARK_FLOOR};
use super::{Directional, ShotReport, Solver};
use glam::DVec3;
use std::f64::consts::PI;
use std::time::Instant;

/// The source of the shot in progress.
pub(super) struct Source {
    /// The patch that shoots; `None` for the lights' shot (`lights.rs`).
    pub patch: Option<u32>,
    /// The light not yet shot, this shot's included, for the meshing's
    /// local radiance level.
    pub ambient: DVec3,
    /// Its unshot radiance (RGB), taken out of the patch; a directional
    /// source's is the radiance of equal upper-hemisphere power.
    pub unshot: DVec3,
}

/// What shooting and refining did.
pub(super) struct Shooting {
    /// Rays traced, refinement's included.
    pub rays: u64,
    pub refined: Refined,
    /// When the shot was done and refinement began, for [`super::Timings`].
    pub shot_done: Instant,
}

/// The light a shot carries, from the source's patch to the receivers and
/// back into the patches.
pub(super) trait Transport {
    /// Chooses the source (the patch with the most unshot power) and takes
    /// its unshot light out of it.
    fn take_source(&mut self, solver: &mut Solver) -> Source;
    /// Shoots the source's light to every receiving vertex, then refines the
    /// mesh where the result varies, new vertices receiving exactly.
    fn shoot(&mut self, solver: &mut Solver, source: &Source) -> Shooting;
    /// Gathers the shot's ΔL from `source` into the patches; the gather
    /// weights of the patches refinement changed (`dirty`) are already up to
    /// date.
    fn gather(&mut self, solver: &mut Solver, source: &Source, dirty: &[u32]);
    /// The total unshot power once gathered.
    fn unshot_power(&mut self, solver: &mut Solver) -> f64;
}

impl Solver {
    /// One shot with `transport` (see the module documentation).
    pub(super) fn shoot_with(&mut self, transport: &mut impl Transport) -> ShotReport {
        let start = Instant::now();
        let source = transport.take_source(self);
        if let Some(patch) = source.patch {
            self.stats.timings.shot_power +=
                PI * self.patches.shoot_area[patch as usize] * source.unshot.element_sum();
        }
        let shooting = transport.shoot(self, &source);
        let refine_done = Instant::now();
        let splits = shooting.refined.splits;
        self.stats.leaf_count += 3 * splits;
        self.update_patch_weights(&shooting.refined.dirty_patches);
        transport.gather(self, &source, &shooting.refined.dirty_patches);
        let timings = &mut self.stats.timings;
        timings.shoot += (shooting.shot_done - start).as_secs_f64();
        timings.shoot_rays += shooting.rays - shooting.refined.rays;
        timings.refine += (refine_done - shooting.shot_done).as_secs_f64();
        timings.gather += refine_done.elapsed().as_secs_f64();
        self.stats.shots += 1;
        self.stats.rays += shooting.rays;
        self.stats.unshot_power = transport.unshot_power(self);
        self.stats.seconds += start.elapsed().as_secs_f64();
        ShotReport {
            shot: self.stats.shots,
            source: source.patch,
            rays: shooting.rays,
            unshot_fraction: self.unshot_fraction(),
            elements: self.stats.leaf_count,
            vertices: self.mesh.vertices.len(),
            splits,
        }
    }

    /// Whether a shot from patch `source` is recorded: when it is an
    /// emitter's patch shooting `alone`, so that vertices later splits
    /// create receive it exactly (`refine.rs`; [`super::state::Recording`]).
    /// Not when the memory budget has stopped refinement, or cannot hold one
    /// more recorded shot with `directional`'s coefficients (which stops
    /// refinement, with a warning).
    pub(super) fn records(
        &mut self,
        source: u32,
        alone: bool,
        directional: Option<(&Directional, u64)>,
    ) -> bool {
        let surface = self.mesh.patches[source as usize].surface;
        let emitter = self.materials.emission[surface as usize] != DVec3::ZERO;
        if !emitter || self.memory.refinement_capped || !alone {
            return false;
        }
        let (d, coefficients) = directional.map_or((None, 0), |(d, n)| (Some(d), n));
        if let Some(warning) = self.recording_overflows(d, coefficients) {
            self.memory.refinement_capped = true;
            self.warnings.pending.push(warning);
            return false;
        }
        true
    }

    /// Whether this shot refines: adaptive subdivision is on and the memory
    /// budget has not stopped it (a solve it stopped stays unrefined).
    pub(super) fn refines(&self) -> bool {
        self.settings.adaptive && !self.memory.refinement_capped
    }

    /// The split criteria of a shot whose source saw `ambient` unshot light.
    pub(super) fn refine_criteria(&self, ambient: DVec3) -> Criteria {
        Criteria {
            dark_floor: DARK_FLOOR * self.stats.radiance_level,
            ambient,
            ..Criteria::from_settings(&self.settings)
        }
    }
}
