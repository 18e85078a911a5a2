//! The diffuse solve's [`Transport`]: RGB radiance per vertex and per patch
//! (module documentation of [`super`], "State and units"). A reflecting
//! source may shoot with its bright neighbours (`group_shot.rs`), and only
//! the receivers a shot touched are revisited (`footprint.rs`).

use super::group_shot::{GroupShot, GroupSources, Shooter};
use super::lights::LightShot;
use super::pipeline::{Shooting, Source, Transport};
use super::ray_share::RayShare;
use super::refine::{self, Refined};
use super::shoot::{RecordedGroup, RecordedShot, SamplePool, Shot};
use super::{footprint, Solver};
use crate::settings::Shooters;
use glam::DVec3;
use std::sync::Arc;
use std::time::Instant;

/// Diffuse shots; between the steps of one shot they keep only the source
/// patch `take_source` chose.
#[derive(Default)]
pub(super) struct ScalarShot {
    patch: u32,
}

impl Transport for ScalarShot {
    fn take_source(&mut self, s: &mut Solver) -> Source {
        let patch = s.brightest_patch();
        self.patch = patch;
        let ambient = s.ambient_from_index();
        let unshot = std::mem::replace(&mut s.patches.unshot[patch as usize], DVec3::ZERO);
        s.unshot_changed(&[patch]);
        Source {
            patch: Some(patch),
            ambient,
            unshot,
        }
    }

    fn shoot(&mut self, s: &mut Solver, source: &Source) -> Shooting {
        let patch = self.patch;
        let unshot = source.unshot;
        // With grouped shooters the source may take its bright neighbours
        // along (`group_shot.rs`); an emitter's first shot, alone or with
        // other emitters' first shots, is recorded.
        let grouped = s.settings.shooters == Shooters::Grouped;
        let first = s.first_shot(patch);
        let members = if grouped {
            s.take_group(patch, unshot)
        } else {
            None
        };
        let recorded = s.records(patch, members.is_none() || first, None);
        // A recorded group is its members whole (emitters' patches shoot
        // uniformly), built from its record so that a resume rebuilds the
        // same tree.
        let sources = match &members {
            Some(m) if recorded => {
                let record = RecordedGroup::new(s.stats.shots, s.mesh.vertices.len(), m);
                let sources = Arc::new(record.sources(&s.mesh));
                s.record.push_group(record, sources.clone());
                Some(sources)
            }
            Some(m) => Some(Arc::new(GroupSources::new(&s.mesh, &s.group_pieces(m)))),
            None => None,
        };
        let mut shot = Shot::for_patch(
            &s.mesh,
            patch,
            s.stats.shots,
            unshot,
            &s.settings,
            &s.occluder,
            &s.materials.kd,
        );
        if recorded && members.is_none() {
            s.record.push(&shot, patch, unshot, s.mesh.vertices.len());
        }
        // Recorded (emitter) shots stay uniform: their replay to new vertices
        // rebuilds them from the patch and its mean unshot alone.
        if !recorded && !s.settings.shoots_uniformly() && members.is_none() {
            shot.regions = s.source_regions(patch, unshot).map(Box::new);
        }
        // Recorded shots keep every ray: later splits replay them exactly.
        let share = RayShare::new(s.settings.full_rays_above, source.ambient);
        if !recorded {
            shot.ray_share = share;
        }
        let group = sources.map(|sources| {
            let mut group = GroupShot::of(
                sources,
                s.stats.shots,
                &s.settings,
                &s.occluder,
                &s.materials.kd,
            );
            // A recorded group keeps every ray, as its replays do.
            if recorded {
                group.recorded(&s.settings)
            } else {
                group.ray_share = share;
                group
            }
        });
        let pool = match group {
            Some(_) => SamplePool::with_sets(&shot, 0),
            None => SamplePool::new(&shot),
        };
        let shooter = match &group {
            Some(g) => Shooter::Group(g),
            None => Shooter::Patch {
                shot: &shot,
                pool: &pool,
            },
        };
        let rays = footprint::shoot_receivers(
            &s.mesh,
            &mut s.sharing.footprint,
            footprint::SampleSharing {
                small: &s.sharing.small,
                twins: &s.sharing.twins,
                sites: &s.sharing.sites,
            },
            s.field.state(),
            &shooter,
            recorded,
        );
        let shot_done = Instant::now();
        if !s.refines() {
            return Shooting {
                rays,
                refined: Refined::default(),
                shot_done,
            };
        }
        // Adaptive subdivision (`refine.rs`): new vertices receive every
        // recorded shot exactly, and this one unless it is recorded (then it
        // is the last of the replayed).
        let mut split_budget = s.split_budget(None);
        let replay_shots = RecordedShot::rebuild_all(
            &s.record.shots,
            &s.mesh,
            &s.settings,
            &s.occluder,
            &s.materials.kd,
        );
        // Only the touched surfaces' leaves can have a changed corner.
        let scan = s.touched_patches();
        let upm = s.units_per_metre();
        let lights = LightShot::replay(&s.lights, &s.occluder, &s.materials.kd, &s.settings, upm);
        let replay_groups = s
            .record
            .group_replays(&s.settings, &s.occluder, &s.materials.kd);
        let replay = refine::Replay {
            recorded: &replay_shots,
            pools: &s.record.pools,
            groups: &replay_groups,
            lights: lights.as_ref(),
            current_recorded: recorded,
        };
        // A grouped shot's visible counts are out of `group_samples` rays
        // but are judged against `samples`: a group's count also drops for
        // rays that carry nothing (a sampled member's point behind the
        // receiver's horizon), so it is not binomial, and judging it out of
        // `group_samples` gave partly seen receivers a noise allowance that
        // stopped their refinement (Cornell box, medium: 1.78% / 1.70% MARE
        // → 2.21% / 1.81%; docs/lab/grouped-shooters.md, "Grouped shooters
        // by default").
        let criteria = s.refine_criteria(source.ambient);
        let refined = refine::refine_field(
            &mut s.mesh,
            &mut refine::DiffuseField {
                state: s.field.state(),
                replay: &replay,
                shooter: &shooter,
                scan: scan.as_deref(),
            },
            &criteria,
            &mut split_budget,
        );
        drop(replay_shots);
        s.after_refinement(&split_budget, None);
        Shooting {
            rays: rays + refined.rays,
            refined,
            shot_done,
        }
    }

    fn gather(&mut self, s: &mut Solver, _source: &Source, dirty: &[u32]) {
        s.unshot_changed(dirty);
        s.gather();
    }

    fn unshot_power(&mut self, s: &mut Solver) -> f64 {
        s.unshot_power_from_index()
    }
}
