//! Directional mode's [`Transport`]: SH coefficients per vertex and per
//! patch (module documentation of [`super`], "Transport"). The diffuse
//! fields of the solver carry each vertex's and patch's diffuse proxy, so
//! the pipeline's source choice, convergence test and L = 0 refinement are
//! the diffuse solve's.

use super::field::{DirField, SolverParts};
use super::group::{self, DirGroup};
use super::lights::{DirLights, DirSource};
use super::receive::{DirScratch, DirShot, Receiving, Reflector, Tables};
use super::{quadrant_scale, Directional, SourceChoice};
use crate::mesh::Mesh;
use crate::solve::checkpoint::precision::round_to_kept;
use crate::solve::group_shot::GroupShot;
use crate::solve::lights::LightShot;
use crate::solve::pipeline::{Shooting, Source, Transport};
use crate::solve::refine::{self, Refined};
use crate::solve::shoot::{RecordedShot, SamplePool, Shot};
use crate::solve::small::SmallSurfaces;
use crate::solve::state::VertexField;
use crate::solve::Solver;
use glam::DVec3;
use rayon::prelude::*;
use std::time::Instant;

/// One directional shot's state between the pipeline's steps.
pub(in crate::solve) struct ShShot<'d> {
    d: &'d mut Directional,
    /// The source patch, chosen by `take_source`.
    patch: u32,
    /// The source's unshot SH, taken out of its patch.
    unshot: Vec<f64>,
    /// Whether the shot is recorded (an emitter's: replayed, not summed).
    recorded: bool,
    /// The partners a grouped shot took along, with their unshot SH
    /// (`group.rs`); empty when the patch shoots alone.
    taken: group::Taken,
    /// Where the coefficients of the vertices refinement creates begin;
    /// they are rounded to the kept bits once gathered.
    created_from: usize,
}

impl<'d> ShShot<'d> {
    pub(in crate::solve) fn new(d: &'d mut Directional) -> ShShot<'d> {
        ShShot {
            d,
            patch: 0,
            unshot: Vec::new(),
            recorded: false,
            taken: Vec::new(),
            created_from: 0,
        }
    }
}

impl Transport for ShShot<'_> {
    fn take_source(&mut self, s: &mut Solver) -> Source {
        let d = &mut *self.d;
        let patch = choose_source(s, d);
        self.patch = patch;
        // The light not yet shot, this shot's included.
        let ambient = s.ambient();
        let range = d.patch_range(&s.mesh, patch as usize);
        self.unshot = d.patch_unshot[range.clone()].to_vec();
        d.patch_unshot[range].fill(0.0);
        let unshot = std::mem::replace(&mut s.patches.unshot[patch as usize], DVec3::ZERO);
        Source {
            patch: Some(patch),
            ambient,
            unshot,
        }
    }

    fn shoot(&mut self, s: &mut Solver, source: &Source) -> Shooting {
        let d = &mut *self.d;
        let patch = self.patch;
        // With grouped shooters a source may take its neighbours along
        // (`group.rs`); such a shot is not recorded.
        let (sources, group_sh) = match group::take(s, d, patch, &self.unshot) {
            Some((sources, sh, taken)) => {
                self.taken = taken;
                (Some(sources), sh)
            }
            None => {
                self.taken = Vec::new();
                (None, group::GroupSh::default())
            }
        };
        let alone = sources.is_none();
        let recorded = alone && s.records(patch, true, Some((d, self.unshot.len() as u64)));
        let shot = Shot::for_patch(
            &s.mesh,
            patch,
            s.stats.shots,
            source.unshot,
            &s.settings,
            &s.occluder,
            &s.materials.kd,
        );
        if recorded {
            s.record
                .push(&shot, patch, source.unshot, s.mesh.vertices.len());
            d.recorded_unshot.push(self.unshot.clone());
        }
        self.recorded = recorded;
        // A group draws its own rays: the seed's shot keeps no sample sets.
        let pool = if alone {
            SamplePool::new(&shot)
        } else {
            SamplePool::with_sets(&shot, 0)
        };
        let source_surface = shot.source_surface as usize;
        let tables = Tables::new(d, &s.mesh);
        // Recorded (emitter) shots stay uniform: refinement replays them from
        // the patch's mean alone.
        let quadrants = if recorded || !alone || s.settings.shoots_uniformly() {
            None
        } else {
            quadrant_scale(s.shape_view(), patch, &shot)
        };
        let group_shot = sources.map(|sources| {
            GroupShot::of(
                sources,
                s.stats.shots,
                &s.settings,
                &s.occluder,
                &s.materials.kd,
            )
        });
        let dir_shot = match &group_shot {
            Some(group) => DirSource::Group(DirGroup {
                group,
                sh: &group_sh,
                tables: &tables,
                glossy_rays: group::glossy_rays(group, &s.settings),
            }),
            None => DirSource::Patch(DirShot {
                shot: &shot,
                pool: &pool,
                unshot: &self.unshot,
                source_order: d.surface_order[source_surface],
                source_tangent: tables.tangent[source_surface],
                tables: &tables,
                quadrants: quadrants.as_ref(),
            }),
        };
        let rays = receive_all(
            &s.mesh,
            &s.materials.kd,
            (&mut s.field, &s.sharing.small),
            d,
            &dir_shot,
            recorded,
        );
        let shot_done = Instant::now();
        self.created_from = d.radiance.len();
        if !s.refines() {
            return Shooting {
                rays,
                refined: Refined::default(),
                shot_done,
            };
        }
        // Adaptive subdivision, the diffuse solve's driver on SH
        // (`field.rs`), replaying the recorded shots with their unshot SH.
        let mut split_budget = s.split_budget(Some(d));
        let replay_shots = RecordedShot::rebuild_all(
            &s.record.shots,
            &s.mesh,
            &s.settings,
            &s.occluder,
            &s.materials.kd,
        );
        let recorded_unshot = std::mem::take(&mut d.recorded_unshot);
        // The lights shot first: they replay first (`directional/lights.rs`).
        let upm = s.units_per_metre();
        let (kd, settings) = (&s.materials.kd, &s.settings);
        let lights = LightShot::replay(&s.lights, &s.occluder, kd, settings, upm);
        let replay: Vec<DirSource> = lights
            .iter()
            .map(|lights| {
                DirSource::Lights(DirLights {
                    lights,
                    tables: &tables,
                })
            })
            .chain(
                replay_shots
                    .iter()
                    .zip(&s.record.pools)
                    .zip(&recorded_unshot)
                    .map(|((shot, pool), unshot)| {
                        DirSource::Patch(DirShot::replay(shot, pool, unshot, &tables))
                    }),
            )
            .collect();
        let criteria = s.refine_criteria(source.ambient);
        let refined = refine::refine_field(
            &mut s.mesh,
            &mut DirField::of_shot(
                d,
                &mut s.field,
                SolverParts {
                    patches: &s.patches,
                    materials: &s.materials,
                    settings: &s.settings,
                    occluder: &s.occluder,
                },
                &dir_shot,
                &replay,
                (recorded, false),
            ),
            &criteria,
            &mut split_budget,
        );
        drop(replay);
        d.recorded_unshot = recorded_unshot;
        s.after_refinement(&split_budget, Some(d));
        Shooting {
            rays: rays + refined.rays,
            refined,
            shot_done,
        }
    }

    fn gather(&mut self, s: &mut Solver, _source: &Source, _dirty: &[u32]) {
        let d = &mut *self.d;
        // This shot's light joins its patch's sum for the gathers of later
        // splits (`directional/near_gather.rs`); recorded shots replay.
        if !self.recorded {
            let patch = self.patch;
            let range = d.patch_range(&s.mesh, patch as usize);
            for (sum, u) in d.shot_sum[range].iter_mut().zip(&self.unshot) {
                *sum = round_to_kept(*sum + u);
            }
            group::add_shot_sums(&s.mesh, d, &self.taken);
        }
        finish_shot(s, d, self.created_from);
    }

    fn unshot_power(&mut self, s: &mut Solver) -> f64 {
        s.total_unshot_power()
    }
}

/// The end of every directional shot: its ΔL gathered into the patches,
/// the received coefficients cleared, the new vertices' coefficients rounded
/// to the kept bits, and every vertex's diffuse proxy taken.
pub(super) fn finish_shot(s: &mut Solver, d: &mut Directional, created_from: usize) {
    gather_patches(s, d);
    d.received.fill(0.0);
    s.field.received.fill(DVec3::ZERO);
    // The new vertices' coefficients, before the proxies are taken from
    // them (`checkpoint/precision.rs`; the others were rounded as they
    // received).
    d.radiance[created_from..]
        .iter_mut()
        .for_each(|x| *x = round_to_kept(*x));
    for v in 0..s.mesh.vertices.len() {
        let o = d.vertex_offset[v];
        let surface = s.mesh.vertices[v].surface as usize;
        s.field.radiance[v] = d.diffuse_proxy(surface, &d.radiance[o..]);
    }
}

/// The next source: by hemispherical unshot power, the diffuse solve's
/// choice on the proxies (the default), or by the [0,0] term alone.
fn choose_source(s: &Solver, d: &Directional) -> u32 {
    match d.choice {
        SourceChoice::Hemisphere => s.choose_source(),
        SourceChoice::ZerothTerm => {
            let mut best = (0u32, f64::NEG_INFINITY);
            for (i, p) in s.mesh.patches.iter().enumerate() {
                let o = d.patch_offset[i];
                let power = p.area * d.patch_unshot[o..o + 3].iter().sum::<f64>();
                if power > best.1 {
                    best = (i as u32, power);
                }
            }
            best.0
        }
    }
}

/// Every vertex receives `shot`; returns the rays traced. A recorded shot's
/// coefficients also join each vertex's recorded part. A small flat
/// surface's vertices (`small`) all take the one sample at its centroid, as
/// in a diffuse solve (`solve/small.rs`), its rays counted once.
pub(super) fn receive_all(
    mesh: &Mesh,
    kd: &[DVec3],
    (field, small): (&mut VertexField, &SmallSurfaces),
    d: &mut Directional,
    shot: &DirSource,
    recorded: bool,
) -> u64 {
    let (at_small, small_rays) = receive_small(mesh, kd, small, shot);
    // Each vertex receives straight into its slot of `received`: a buffer
    // a receiver was 16 KB at order 25, allocated and freed every shot
    // (docs/lab/glossy-profile.md: 14.5% of a glossy solve in allocation
    // and page faults).
    let count = mesh.vertices.len();
    let mut slots: Vec<&mut [f64]> = Vec::with_capacity(count);
    let mut rest = d.received.as_mut_slice();
    for v in 0..count {
        let end = d
            .vertex_offset
            .get(v + 1)
            .copied()
            .unwrap_or(d.vertex_offset[v] + rest.len());
        let (slot, tail) = rest.split_at_mut(end - d.vertex_offset[v]);
        slots.push(slot);
        rest = tail;
    }
    let results: Vec<(u32, u32)> = slots
        .into_par_iter()
        .enumerate()
        .map_init(DirScratch::default, |scratch, (v, slot)| {
            match small.of(mesh.vertices[v].surface) {
                Some(k) => {
                    let (coefficients, visible) = &at_small[k];
                    slot.copy_from_slice(coefficients);
                    (*visible, 0)
                }
                None => shot.receive_into(mesh, kd, v as u32, scratch, slot),
            }
        })
        .collect();
    let mut rays = small_rays;
    for (v, (visible, traced)) in results.into_iter().enumerate() {
        let range = d.vertex_slot(mesh, v);
        for k in range.clone() {
            let c = d.received[k];
            // The state keeps 40 mantissa bits (`checkpoint/precision.rs`).
            d.radiance[k] = round_to_kept(d.radiance[k] + c);
            if recorded {
                d.direct[k] += c;
            }
        }
        field.visible[v] = visible;
        rays += traced as u64;
        // The diffuse proxies (mean radiance c₀₀ Y₀₀, or E/π on a textured
        // surface) the L = 0 refinement test reads.
        let surface = mesh.vertices[v].surface as usize;
        let o = range.start;
        field.radiance[v] = d.diffuse_proxy(surface, &d.radiance[o..]);
        field.received[v] = d.diffuse_proxy(surface, &d.received[range]);
    }
    rays
}

/// What each small surface receives of `shot` at its one point (`small.rs`),
/// in the order of `small.points()`: its slot's coefficients and visible
/// count (nothing, and no ray, for a surface with no vertex); and the rays.
fn receive_small(
    mesh: &Mesh,
    kd: &[DVec3],
    small: &SmallSurfaces,
    shot: &DirSource,
) -> (Vec<(Vec<f64>, u32)>, u64) {
    let mut has_vertex = vec![false; small.points().len()];
    for vertex in &mesh.vertices {
        if let Some(k) = small.of(vertex.surface) {
            has_vertex[k] = true;
        }
    }
    let received: Vec<(Vec<f64>, u32, u32)> = small
        .points()
        .par_iter()
        .zip(&has_vertex)
        .map_init(DirScratch::default, |scratch, (at, &has)| {
            let who = Receiving::Small(at);
            let mut out = Reflector::of(mesh, shot.tables(), kd, who).zeroed();
            if !has {
                return (out, 0, 0);
            }
            let (visible, rays) = shot.receive_as(mesh, kd, who, scratch, &mut out);
            (out, visible, rays)
        })
        .collect();
    let rays = received.iter().map(|r| r.2 as u64).sum();
    (received.into_iter().map(|(c, v, _)| (c, v)).collect(), rays)
}

/// The shot's ΔL gathered into every patch's unshot SH, as the diffuse
/// solve gathers ΔL (`Solver::gather`): U_p += Σ_v w_vp ΔL_v / A_p per
/// coefficient, hidden vertices left out; then each patch's diffuse proxy.
fn gather_patches(s: &mut Solver, d: &mut Directional) {
    for p in 0..s.mesh.patches.len() {
        let range = d.patch_range(&s.mesh, p);
        let area = s.patches.shoot_area[p];
        let mut sum = vec![0.0; range.len()];
        for &(v, w) in &s.patches.weights[p] {
            if s.field.hidden[v as usize] {
                continue;
            }
            let o = d.vertex_offset[v as usize];
            for (total, r) in sum.iter_mut().zip(&d.received[o..o + range.len()]) {
                *total += r * w;
            }
        }
        // A textured patch reflects ∫ ρ ΔE/π dA (`directional/textured.rs`).
        s.add_textured_gather(d, p, &mut sum);
        for (u, total) in d.patch_unshot[range.clone()].iter_mut().zip(&sum) {
            if area > 0.0 {
                *u += total / area;
            }
            // The state keeps 40 mantissa bits (`checkpoint/precision.rs`).
            *u = round_to_kept(*u);
        }
        let order = d.surface_order[s.mesh.patches[p].surface as usize];
        s.patches.unshot[p] = d.hemisphere_equivalent(order, &d.patch_unshot[range]);
    }
}
