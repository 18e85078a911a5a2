//! Diffuse progressive-refinement radiosity (Remington 1992, §3.7, Fig. 3.6) with ray-cast
//! vertex form factors (§3.6) and adaptive meshing (§3.3, step 5c).
//!
//! The [`Solver`] is the pure core: no files, terminals or flags. The command
//! line drives it shot by shot (`step`), saves [`Checkpoint`]s and writes
//! [`Solver::to_solution`].
//!
//! ## State and units
//!
//! * Per vertex: radiance L (RGB, W·sr⁻¹·m⁻²), including the emission of its
//!   surface, and ΔL of the shot in progress.
//! * Per patch: unshot radiance U_p. After each shot the ΔL of every vertex is
//!   gathered into the patches it belongs to, each patch receiving the part of
//!   the vertex's ΔL that its area there represents (design notes,
//!   "Progressive refinement"). The weights are exact integrals of the displayed
//!   (Gouraud) field: a vertex gets a third of the area of every display
//!   triangle it is a corner of ([`Mesh::patch_triangles`]), so a patch's unshot
//!   power π · U_p · A_p is the integral of the displayed ΔL over the patch, and
//!   a vertex shared by four patches gives each its share instead of all to the
//!   first. Remington 1992 (step 5a) gathers the same area-weighted average into the patch
//!   and zeroes the vertices; doing it right after the shot means vertex unshot
//!   never outlives its shot, so a split never has to interpolate unshot
//!   radiance of earlier shots: that energy is already held by the patch,
//!   exactly, and new vertices only receive the current shot's ΔL.
//! * Per vertex also the part of L that came from emitter shots, and the list
//!   of those shots: a vertex created by a later split receives them again,
//!   exactly, and interpolates only the rest (see `refine.rs`).
//! * Power = π · U · A per channel for a diffuse emitter; totals sum the three
//!   channels. The source each step is the patch with the most unshot power
//!   (Remington 1992 shoots patches, not elements: the source count stays fixed as
//!   elements refine). An unevenly lit quad patch shoots from its four
//!   quadrants, each with its own unshot radiance ([`regions`]), so the patch
//!   grid no longer bounds the error of treating a source as uniform alone.
//!
//! ## Determinism
//!
//! Receivers are shot in parallel with rayon, on the caller's pool (the command
//! line builds one of `settings.threads`; tests use `ThreadPool::install`).
//! Each receiver's random choices come from its own stream (seed, shot index,
//! vertex id): which of the shot's pooled sample sets it uses
//! ([`shoot::SamplePool`]), or its own set where the source is clipped by its
//! horizon. Its result goes to its own slot; sums over vertices (the gather
//! into patches, the ray count) are done in a fixed order. A solve therefore
//! gives bit-identical radiance for any thread count, and a resumed solve
//! continues bit-identically.
//!
//! ## Limits
//!
//! Form factors and frames use the facet normal of each polygon; per-vertex
//! normals of curved input are not used by the diffuse solve. Radiance a new
//! vertex receives from recorded shots (better than the interpolation the
//! patches' unshot was gathered from) is not re-gathered.

pub mod budget;
mod checkpoint;
pub mod cluster;
pub mod cube_gather;
pub mod directional;
pub mod enclosure;
pub mod gauss_seidel;
pub mod hidden;
mod output;
mod output_lights;
mod output_textured;
pub(crate) use output::default_camera;
pub mod fine_shape;
mod footprint;
mod group_shot;
mod group_tree;
mod lights;
mod pipeline;
pub mod ray_share;
mod refine;
pub mod regions;
mod scalar;
mod seams;
pub mod shoot;
mod sites;
mod small;
mod state;
mod textured;
mod twins;
mod unshot_tree;

pub use checkpoint::Checkpoint;
pub use directional::{Directional, DirectionalCheckpoint, SourceChoice};
pub use output_lights::{environment, exposure_key, lighting_record, lights_json};

use crate::geometry::visibility::Occluder;
use crate::mesh::{Mesh, MeshError};
use crate::scene::Scene;
use crate::settings::{SettingsError, SolverSettings};
use glam::DVec3;
use rayon::prelude::*;
use shoot::{SamplePool, Scratch, Shot};
use solution::format::SolveMode;
use std::f64::consts::PI;

/// Why a solve cannot start or resume.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    #[error("the scene has no polygons with non-zero area: nothing to solve")]
    EmptyScene,
    #[error(
        "the scene has a single polygon: a planar polygon cannot light itself, so there is \
         nothing to solve (add the surfaces it should light)"
    )]
    SinglePolygon,
    /// `hint` says the fix in the formats of the scene's files
    /// ([`crate::scene::no_emitter_hint`]).
    #[error(
        "the scene has no emitter and no light: no polygon of non-zero area emits light (an \
         emission above zero, not blacked out by its emission texture), and the scene has no \
         sun, sky or lamp. {hint}"
    )]
    NoEmitter { hint: String },
    #[error("material `{name}`: {problem}")]
    BadMaterial { name: String, problem: String },
    #[error(transparent)]
    Mesh(#[from] MeshError),
    #[error(transparent)]
    Settings(#[from] SettingsError),
    #[error("mode `{0:?}` is not implemented by this solver yet; use `diffuse`")]
    UnsupportedMode(SolveMode),
    /// A one-call gather (Gauss–Seidel, global cube) of a scene with lights:
    /// only progressive refinement shoots the sun, the sky and the lamps.
    #[error(
        "`--method {0}` gathers the light of emissive polygons only, and this scene is lit \
         by a sun, a sky or lamps: solve it with `--method progressive` (the default)"
    )]
    LightsNeedProgressive(&'static str),
    #[error("the checkpoint does not belong to this scene and these settings: {0}")]
    CheckpointMismatch(String),
    /// The memory budget cannot hold even the coarsest solve: the message
    /// gives the estimate, the budget and what to change (see `check_coarsest`).
    #[error("{0}")]
    OverBudget(String),
}

impl SolveError {
    /// [`SolveError::NoEmitter`] with the fix in the formats of the files the
    /// scene's polygons came from. A TOML config is not among them (the scene
    /// does not keep its name), so its `emission` is not offered: the import's
    /// own check ([`crate::scene::SceneError::NoEmitter`]) offers it.
    fn no_emitter(scene: &Scene) -> Self {
        let files =
            crate::scene::distinct_files(scene.polygons.iter().map(|p| p.source.file.as_path()));
        SolveError::NoEmitter {
            hint: crate::scene::no_emitter_hint(&files, false),
        }
    }
}

/// What one shot did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShotReport {
    /// Shots done so far, this one included (1 for the first).
    pub shot: u64,
    /// The patch that shot; `None` for the lights' shot.
    pub source: Option<u32>,
    /// Visibility rays traced by this shot (refinement included).
    pub rays: u64,
    /// Total unshot power / total emitted power after the shot.
    pub unshot_fraction: f64,
    /// Leaf elements after the shot.
    pub elements: usize,
    pub vertices: usize,
    /// Elements split by this shot's adaptive subdivision.
    pub splits: usize,
}

/// Wall seconds spent in the parts of [`Solver::step`] since the solver was
/// built or resumed, for benchmarks: shooting (source choice, form factors and
/// visibility to every vertex), refinement (split tests, splits, shooting new
/// vertices) and bookkeeping (display triangulation of the changed patches,
/// gather into patches).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timings {
    pub shoot: f64,
    pub refine: f64,
    pub gather: f64,
    /// Rays traced by the shooting part (the rest were traced by refinement).
    pub shoot_rays: u64,
    /// Patches shot by grouped shots, summed over them (`group_shot.rs`;
    /// 0 with `--shooters patch`).
    pub grouped_patches: u64,
    /// Grouped shots (of two patches or more).
    pub group_shots: u64,
    /// Power shot (π U A over the shots' patches, scene units, summed over
    /// the channels), for the energy bookkeeping of grouped shots.
    pub shot_power: f64,
}

/// Where the solve stands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    pub shots: u64,
    pub rays: u64,
    pub unshot_fraction: f64,
    /// Leaf elements.
    pub elements: usize,
    pub vertices: usize,
    /// Total emitted power, W (areas converted to m² by the units per
    /// metre), summed over the three channels.
    pub emitted_power: f64,
}

/// The progressive-refinement solver. See the module documentation.
pub struct Solver {
    settings: SolverSettings,
    mesh: Mesh,
    occluder: Occluder,
    scene: state::SceneFacts,
    materials: state::Materials,
    field: state::VertexField,
    patches: state::PatchLight,
    record: state::Recording,
    sharing: state::Sharing,
    groups: state::Groups,
    stats: state::Stats,
    memory: state::MemoryGuard,
    warnings: state::Warnings,
    /// Directional mode's SH state (`None` in diffuse mode); see [`directional`].
    directional: Option<Box<Directional>>,
    /// Each vertex's enclosure, probed once for all the files the solve
    /// writes (`enclosure.rs`).
    enclosure: enclosure::EnclosureCache,
    /// The sun, the sky and the lamps, in the solver's frame (`lights.rs`).
    lights: lights::LightsState,
    /// The polygons the set-up cut along contact lines and their parts, kept
    /// for checkpoints (its `hidden` stays empty: `field.hidden` is written).
    setup_cuts: checkpoint::SetupResult,
}

impl Solver {
    /// Meshes the scene into patches and sets every emitter's patches to shoot.
    ///
    /// Errors: settings out of range, directional mode, an empty scene, a single
    /// polygon, no emitter, a material with negative or non-finite values, too
    /// many patches.
    pub fn new(scene: &Scene, settings: &SolverSettings) -> Result<Solver, SolveError> {
        Self::new_observed(scene, settings, &mut crate::progress::Quiet)
    }

    /// [`Solver::new`], reporting each pass of the set-up to `observer`.
    pub fn new_observed(
        scene: &Scene,
        settings: &SolverSettings,
        observer: &mut dyn crate::progress::Observer,
    ) -> Result<Solver, SolveError> {
        Self::set_up(scene, settings, None, observer)
    }

    /// The set-up, searching the scene, or taking what a checkpoint stored of
    /// an earlier search (`found`: a resume).
    fn set_up(
        scene: &Scene,
        settings: &SolverSettings,
        found: Option<checkpoint::SetupResult>,
        observer: &mut dyn crate::progress::Observer,
    ) -> Result<Solver, SolveError> {
        settings.validate()?;
        check_materials(scene)?;
        // The receivers' cuts, once: the estimate below counts their parts
        // and the mesh is built from them.
        let (parts, mut hidden) = match found {
            Some(found) => (
                checkpoint::SetupResult::parts_for(found.polygons_hash, found.cuts, scene)?,
                found.hidden,
            ),
            None => {
                let cuts = crate::mesh::contact::Cuts::for_settings(settings);
                let parts = crate::mesh::contact::conform_observed(scene, cuts, observer);
                (parts, Vec::new())
            }
        };
        // Refuse before meshing when even the unrefined mesh at SH order 0
        // cannot fit (its counts are known from the polygons' parts alone).
        check_coarsest(
            &budget::counts_before_meshing(scene, settings, &parts),
            settings,
            "before meshing",
        )?;
        let offset = scene_centre(scene);
        let mesh = mesh_scene(scene, settings, offset, &parts, observer)?;
        let setup_cuts = checkpoint::SetupResult {
            polygons_hash: checkpoint::polygons_hash(scene),
            cuts: parts
                .into_iter()
                .enumerate()
                .filter_map(|(i, p)| p.map(|p| (i as u32, p)))
                .collect(),
            hidden: Vec::new(),
        };
        observer.advance(crate::progress::Pass::SolverState, 0, 1);
        let texturing = textured::SurfaceTexturing::new(scene, &mesh, offset);
        let scene_bytes = budget::scene_bytes(scene);
        check_unrefined(scene, settings, &mesh, &texturing, scene_bytes)?;
        let (materials, patch_emission) =
            state::Materials::new(scene, &mesh, texturing, settings.mode);
        let patches = state::PatchLight::new(&mesh, &materials, patch_emission);
        let emitted_power: f64 = mesh
            .patches
            .iter()
            .zip(&patches.unshot)
            .map(|(p, u)| PI * p.area * u.element_sum())
            .sum();
        let has_emitter = emitted_power.is_finite() && emitted_power > 0.0;
        if !has_emitter && scene.lights.is_empty() {
            return Err(SolveError::no_emitter(scene));
        }
        observer.advance(crate::progress::Pass::SolverState, 1, 1);
        observer.advance(crate::progress::Pass::Occluder, 0, 1);
        let occluder = Occluder::new(
            &mesh
                .surfaces
                .iter()
                .map(|s| s.vertices.as_slice())
                .collect::<Vec<_>>(),
        );
        observer.advance(crate::progress::Pass::Occluder, 1, 1);
        let mut solver = Solver {
            settings: settings.clone(),
            scene: state::SceneFacts {
                offset,
                recentre: scene.recentre_offset,
                camera: scene.camera,
                units_per_metre: scene.units_per_metre,
                up_axis: scene.up_axis,
            },
            field: state::VertexField::new(&mesh, &materials.emission),
            groups: state::Groups::new(&mesh, &patches.of_surface),
            sharing: state::Sharing::new(&mesh, &patches.of_surface),
            stats: state::Stats {
                leaf_count: mesh.leaf_count(),
                emitted_power,
                ..state::Stats::default()
            },
            memory: state::MemoryGuard {
                scene_bytes,
                ..state::MemoryGuard::default()
            },
            mesh,
            occluder,
            materials,
            patches,
            record: state::Recording::default(),
            warnings: state::Warnings::default(),
            directional: None,
            enclosure: enclosure::EnclosureCache::default(),
            lights: lights::LightsState::new(scene.lights.recentred(offset)),
            setup_cuts,
        };
        // The flags a checkpoint stored for the unrefined mesh's vertices.
        hidden.truncate(solver.mesh.vertices.len());
        solver.field.hidden = hidden;
        solver.finish_setup(scene, observer)?;
        Ok(solver)
    }

    /// The set-up that needs the whole solver: directional mode, the gather
    /// weights and hidden vertices, the receivers that share samples, and
    /// the first totals.
    fn finish_setup(
        &mut self,
        scene: &Scene,
        observer: &mut dyn crate::progress::Observer,
    ) -> Result<(), SolveError> {
        self.enclosure.catch_up(self.mesh.vertices.len());
        let enclosed = self.enclosed_lamp_warnings();
        self.warnings.setup.extend(enclosed);
        self.init_directional(scene)?;
        self.classify_vertices_observed(observer);
        observer.advance(crate::progress::Pass::SharedSamples, 0, 1);
        let all: Vec<u32> = (0..self.mesh.surfaces.len() as u32).collect();
        self.update_weights(&all);
        // After `update_weights`, which classifies the vertices as hidden;
        // diffuse mode only (directional coefficients live in each polygon's
        // frame).
        if self.directional.is_none() {
            self.sharing.twins = twins::Twins::new(&self.mesh, &self.field.hidden);
            self.sharing.sites = sites::Sites::new(
                &self.mesh,
                &self.field.hidden,
                &self.sharing.twins,
                &self.small_patch_surfaces(),
                self.settings.site_angle,
            );
        }
        self.stats.unshot_power = self.total_unshot_power();
        self.stats.radiance_level = self.ambient().max_element();
        self.memory.peak_estimate = self.memory_estimate().peak();
        observer.advance(crate::progress::Pass::SharedSamples, 1, 1);
        Ok(())
    }

    /// Whether the solve has converged (total unshot power below `threshold` ×
    /// emitted power) or used its shot budget.
    pub fn is_done(&self) -> bool {
        if self.lights.pending() {
            return self.stats.shots >= self.settings.max_shots;
        }
        self.stats.shots >= self.settings.max_shots
            || self.stats.unshot_power < self.settings.threshold * self.stats.emitted_power
            || self.stats.unshot_power.is_nan()
            || self.stats.unshot_power <= 0.0
    }

    /// One shot (Remington 1992, Fig. 3.6 steps 5a–5c): the patch with the most unshot power
    /// shoots to every vertex, the mesh is refined where the result varies too
    /// much, and the shot's ΔL is gathered into the patches. `None` when done.
    pub fn step(&mut self) -> Option<ShotReport> {
        if self.is_done() {
            return None;
        }
        let report = match self.directional.take() {
            None if self.lights.pending() => self.shoot_with(&mut lights::LightsTransport),
            Some(mut d) if self.lights.pending() => {
                let report = self.shoot_with(&mut directional::DirLightsShot::new(&mut d));
                self.directional = Some(d);
                report
            }
            Some(mut d) => {
                let report = self.shoot_with(&mut directional::ShShot::new(&mut d));
                self.directional = Some(d);
                report
            }
            None => self.shoot_with(&mut scalar::ScalarShot::default()),
        };
        self.enclosure.catch_up(self.mesh.vertices.len());
        Some(report)
    }

    /// Where step time went since the solver was built or resumed.
    pub fn timings(&self) -> Timings {
        self.stats.timings
    }

    /// Where the solve stands.
    pub fn progress(&self) -> Progress {
        Progress {
            shots: self.stats.shots,
            rays: self.stats.rays,
            unshot_fraction: self.unshot_fraction(),
            elements: self.stats.leaf_count,
            vertices: self.mesh.vertices.len(),
            emitted_power: self.emitted_watts(),
        }
    }

    /// Radiance per mesh vertex (RGB, W·sr⁻¹·m⁻²), emission included, without
    /// the ambient term.
    pub fn vertex_radiance(&self) -> &[DVec3] {
        &self.field.radiance
    }

    /// The mesh, for inspection (element sizes, vertices, display triangles).
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// Unshot radiance per patch (RGB).
    pub fn patch_unshot(&self) -> &[DVec3] {
        &self.patches.unshot
    }

    /// The gather weights of `patch`: (vertex, area of the patch the vertex
    /// represents), summing to the patch's area.
    pub fn patch_weights(&self, patch: u32) -> &[(u32, f64)] {
        &self.patches.weights[patch as usize]
    }

    /// The offset subtracted from scene coordinates to get the solver's (and the
    /// solution's) positions.
    pub fn offset(&self) -> DVec3 {
        self.scene.offset
    }

    pub fn settings(&self) -> &SolverSettings {
        &self.settings
    }

    /// Seconds spent in [`Solver::step`] (this session and, after a resume, the
    /// sessions before).
    pub fn seconds(&self) -> f64 {
        self.stats.seconds
    }

    /// F(v←s) for every vertex from patch `source` as the next shot would
    /// compute it (same samples and visibility), for tests and measurements.
    pub fn vertex_form_factors(&self, source: u32) -> Vec<f64> {
        let shot = Shot::for_patch(
            &self.mesh,
            source,
            self.stats.shots,
            DVec3::ONE,
            &self.settings,
            &self.occluder,
            &self.materials.kd,
        );
        let mut scratch = Scratch::default();
        let pool = SamplePool::new(&shot);
        (0..self.mesh.vertices.len() as u32)
            .map(|v| {
                if self.mesh.vertices[v as usize].surface == shot.source_surface {
                    0.0
                } else {
                    shot.form_factor(&self.mesh, v, &pool, &mut scratch).0
                }
            })
            .collect()
    }

    /// Scene units per metre: the settings' when set (a flag or the scene
    /// config), else the scene's.
    fn units_per_metre(&self) -> f64 {
        if self.settings.units_per_metre != 1.0 {
            self.settings.units_per_metre
        } else {
            self.scene.units_per_metre
        }
    }

    /// The emitted power in watts: areas in scene units² over units_per_metre².
    fn emitted_watts(&self) -> f64 {
        self.stats.emitted_power / (self.units_per_metre() * self.units_per_metre())
    }

    fn unshot_fraction(&self) -> f64 {
        // Before the lights of a scene without emitters shoot, nothing has
        // been emitted yet and all of it is to come: 1, not 0 / 0.
        if self.lights.pending() && self.stats.emitted_power <= 0.0 {
            return 1.0;
        }
        self.stats.unshot_power / self.stats.emitted_power
    }

    fn total_unshot_power(&self) -> f64 {
        // Summed pairwise, as the diffuse step's tree sums it
        // (`unshot_tree.rs`), so a resumed solve reports the same bits.
        PI * unshot_tree::pairwise_unshot_area_sum(&self.patches.unshot, &self.patches.shoot_area)
            .element_sum()
    }

    /// The patch with the most unshot power (Remington 1992 step 5a); ties go to the
    /// lowest index. The diffuse step takes the same patch from its tree
    /// (`unshot_tree.rs`); directional mode scans.
    fn choose_source(&self) -> u32 {
        let mut best = (0u32, f64::NEG_INFINITY);
        for (i, (a, u)) in self
            .patches
            .shoot_area
            .iter()
            .zip(&self.patches.unshot)
            .enumerate()
        {
            let power = a * u.element_sum();
            if power > best.1 {
                best = (i as u32, power);
            }
        }
        best.0
    }

    /// Recomputes the gather weights of the patches of `surfaces` from their
    /// display triangulation.
    fn update_weights(&mut self, surfaces: &[u32]) {
        let patches: Vec<u32> = surfaces
            .iter()
            .flat_map(|&s| self.patches.of_surface[s as usize].clone())
            .collect();
        self.update_patch_weights(&patches);
    }

    /// Recomputes the gather weights of `patches` from their display
    /// triangulation.
    fn update_patch_weights(&mut self, patches: &[u32]) {
        self.classify_new_vertices();
        let mesh = &self.mesh;
        let weights: Vec<Vec<(u32, f64)>> = patches
            .par_iter()
            .map(|&p| {
                let mut tris = Vec::new();
                mesh.patch_triangles(p, &mut tris);
                let mut entries: Vec<(u32, f64)> = Vec::with_capacity(tris.len() * 3);
                for t in &tris {
                    let [a, b, c] = t.map(|i| mesh.vertices[i as usize].position);
                    let third = (b - a).cross(c - a).length() / 6.0;
                    entries.extend(t.iter().map(|&v| (v, third)));
                }
                // Merge per vertex in a fixed order.
                entries.sort_unstable_by_key(|e| e.0);
                let mut merged: Vec<(u32, f64)> = Vec::with_capacity(entries.len() / 2);
                for (v, w) in entries {
                    match merged.last_mut() {
                        Some(last) if last.0 == v => last.1 += w,
                        _ => merged.push((v, w)),
                    }
                }
                merged
            })
            .collect();
        for (&p, w) in patches.iter().zip(weights) {
            let area = self.mesh.patches[p as usize].area;
            let hidden: f64 = w
                .iter()
                .filter(|(v, _)| self.field.hidden[*v as usize])
                .map(|(_, a)| a)
                .sum();
            self.patches.shoot_area[p as usize] = if hidden > 0.0 {
                w.iter()
                    .filter(|(v, _)| !self.field.hidden[*v as usize])
                    .map(|(_, a)| a)
                    .sum()
            } else {
                area
            };
            self.patches.weights[p as usize] = w;
        }
        if self.materials.texturing.any() {
            self.update_rgb_weights(patches);
        }
    }

    /// Bytes of the textures the solve holds and of the RGB gather weights.
    fn texture_bytes(&self) -> u64 {
        let entry = std::mem::size_of::<(u32, DVec3)>() as u64;
        let entries: u64 = self
            .patches
            .rgb_weights
            .iter()
            .map(|w| w.len() as u64)
            .sum();
        let headers =
            (self.patches.rgb_weights.len() * std::mem::size_of::<Vec<(u32, DVec3)>>()) as u64;
        self.materials.texturing.texture_bytes() + entries * entry + headers
    }

    /// Recomputes the RGB gather weights of the textured ones of `patches`
    /// (`textured.rs`).
    fn update_rgb_weights(&mut self, patches: &[u32]) {
        let (mesh, texturing) = (&self.mesh, &self.materials.texturing);
        let weights: Vec<(u32, Vec<(u32, DVec3)>)> = patches
            .par_iter()
            .filter_map(|&p| {
                let t = texturing.get(mesh.patches[p as usize].surface)?;
                let mut tris = Vec::new();
                mesh.patch_triangles(p, &mut tris);
                Some((p, texturing.weights(mesh, t, &tris)))
            })
            .collect();
        for (p, w) in weights {
            self.patches.rgb_weights[p as usize] = w;
        }
    }

    /// Classifies the vertices created since the last call as hidden or not
    /// ([`hidden::is_hidden`] at their receiving points).
    fn classify_new_vertices(&mut self) {
        self.classify_vertices_observed(&mut crate::progress::Quiet);
    }

    /// [`Self::classify_new_vertices`] in chunks, reporting to `observer`.
    fn classify_vertices_observed(&mut self, observer: &mut dyn crate::progress::Observer) {
        let end = self.mesh.vertices.len() as u32;
        let pass = crate::progress::Pass::HiddenVertices;
        while (self.field.hidden.len() as u32) < end {
            let start = self.field.hidden.len() as u32;
            observer.advance(pass, start as u64, end as u64);
            let stop = end.min(start + crate::progress::CHUNK as u32);
            let mesh = &self.mesh;
            let occluder = &self.occluder;
            let epsilon = occluder.scene_epsilon();
            let new: Vec<bool> = (start..stop)
                .into_par_iter()
                .map(|v| {
                    let (q, n) = shoot::receiving_point(mesh, v, epsilon);
                    hidden::is_hidden(occluder, q, n)
                })
                .collect();
            self.field.hidden.extend(new);
            if stop == end {
                observer.advance(pass, end as u64, end as u64);
            }
        }
    }

    /// The quadrants of quad patch `source` with unshot `unshot`, shaped by its
    /// visible vertices' received radiance ([`regions`]); `None` for a
    /// triangle or a patch lit evenly.
    fn source_regions(&self, source: u32, unshot: DVec3) -> Option<regions::Regions> {
        self.shape_view().source_regions(source, unshot)
    }

    /// The fields a patch's light shape is read from, borrowed.
    fn shape_view(&self) -> ShapeView<'_> {
        ShapeView {
            mesh: &self.mesh,
            patch_weights: &self.patches.weights,
            hidden: &self.field.hidden,
            radiance: &self.field.radiance,
            emission: &self.materials.emission,
        }
    }

    /// How many small flat surfaces receive once per shot ([`small`]).
    pub fn small_surface_count(&self) -> usize {
        self.sharing.small.len()
    }

    /// How many vertices copy a coincident vertex's sample ([`twins`]).
    pub fn twin_copy_count(&self) -> usize {
        self.sharing.twins.copies()
    }

    /// How many points of finely tessellated smooth surfaces interpolate
    /// sites, and how many of those surfaces' points receive as sites
    /// ([`sites`]).
    pub fn site_counts(&self) -> (usize, usize) {
        (
            self.sharing.sites.interpolated_count(),
            self.sharing.sites.site_count(),
        )
    }

    /// Per surface, whether it is one patch that refinement never splits
    /// ([`small::one_small_patch`]).
    fn small_patch_surfaces(&self) -> Vec<bool> {
        self.patches
            .of_surface
            .iter()
            .map(|patches| small::one_small_patch(&self.mesh, patches))
            .collect()
    }

    /// Per vertex, whether it is hidden ([`hidden`]).
    pub fn hidden_vertices(&self) -> &[bool] {
        &self.field.hidden
    }
}

/// The solver's fields that give the shape of a patch's light, borrowed apart
/// from the rest, so that refinement, which holds the others mutably, can
/// read it too (`directional/near_gather.rs`).
#[derive(Clone, Copy)]
pub(crate) struct ShapeView<'a> {
    mesh: &'a Mesh,
    patch_weights: &'a [Vec<(u32, f64)>],
    hidden: &'a [bool],
    radiance: &'a [DVec3],
    emission: &'a [DVec3],
}

impl<'a> ShapeView<'a> {
    /// The quadrants of quad patch `source` with unshot `unshot`, shaped by
    /// its visible vertices' received radiance ([`regions`]); `None` for a
    /// triangle or a patch lit evenly.
    fn source_regions(self, source: u32, unshot: DVec3) -> Option<regions::Regions> {
        let patch = &self.mesh.patches[source as usize];
        if patch.corner_count != 4 || unshot == DVec3::ZERO {
            return None;
        }
        let normal = self.mesh.surfaces[patch.surface as usize].normal;
        regions::regions(&patch.corners, normal, unshot, self.shape_samples(source))
    }

    /// The shape of patch `source`'s light: each visible vertex's position,
    /// gather weight and displayed received radiance (L − emission). A vertex
    /// created since the weights were last updated is not among them.
    fn shape_samples(self, source: u32) -> impl Iterator<Item = (DVec3, f64, DVec3)> + 'a {
        let patch = &self.mesh.patches[source as usize];
        let emission = self.emission[patch.surface as usize];
        self.patch_weights[source as usize]
            .iter()
            .filter(move |(v, _)| !self.hidden[*v as usize])
            .map(move |&(v, w)| {
                let position = self.mesh.vertices[v as usize].position;
                let received = (self.radiance[v as usize] - emission).max(DVec3::ZERO);
                (position, w, received)
            })
    }
}

/// The centre of the scene's bounding box: the solver works relative to it so a
/// scene far from the origin loses no precision in the f32 occluder or the
/// solution file (design notes, "Units and conventions").
pub(crate) fn scene_centre(scene: &Scene) -> DVec3 {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for p in &scene.polygons {
        for &v in &p.vertices {
            if v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    if lo.x <= hi.x {
        (lo + hi) * 0.5
    } else {
        DVec3::ZERO
    }
}

/// Refuses a material with negative or non-finite values, or Kd above 1.
fn check_materials(scene: &Scene) -> Result<(), SolveError> {
    for m in &scene.materials {
        let ok = |v: DVec3| v.is_finite() && v.min_element() >= 0.0;
        if !ok(m.kd) || !ok(m.emission) || m.kd.max_element() > 1.0 {
            return Err(SolveError::BadMaterial {
                name: m.name.clone(),
                problem: format!(
                    "Kd {:?} must be in [0, 1] and emission {:?} finite and >= 0",
                    m.kd.to_array(),
                    m.emission.to_array()
                ),
            });
        }
    }
    Ok(())
}

/// The scene meshed into patches, re-centred by `offset`. Receivers are cut
/// along contact lines (`mesh::contact`) in both modes, and along shadow
/// lines in directional mode; each output shares the cuts' seams
/// (`seams.rs`; directional output only within each cut polygon).
fn mesh_scene(
    scene: &Scene,
    settings: &SolverSettings,
    offset: DVec3,
    parts: &[Option<Vec<crate::mesh::contact::Part>>],
    observer: &mut dyn crate::progress::Observer,
) -> Result<Mesh, SolveError> {
    let sizing = crate::mesh::Sizing::from_settings(settings, scene);
    let mesh = Mesh::with_contacts(scene, offset, &sizing, parts, observer)?;
    match mesh.surfaces.len() {
        0 => Err(SolveError::EmptyScene),
        1 => Err(SolveError::SinglePolygon),
        _ => Ok(mesh),
    }
}

/// [`check_coarsest`] with the mesh's exact counts, before the solve's state
/// (each emitter patch shoots, and is recorded, at least once; a
/// directional solve's textured vertices also hold E/π).
fn check_unrefined(
    scene: &Scene,
    settings: &SolverSettings,
    mesh: &Mesh,
    texturing: &textured::SurfaceTexturing,
    scene_bytes: u64,
) -> Result<(), SolveError> {
    let emitter_patches = budget::emitter_patches(scene, mesh);
    let textured: Vec<bool> = texturing.per_surface.iter().map(Option::is_some).collect();
    check_coarsest(
        &budget::Counts {
            scene_bytes,
            chooses_view: scene.camera.is_none(),
            ..budget::counts_for_mesh(mesh, settings, |_| 0, &textured, emitter_patches)
        },
        settings,
        "the unrefined mesh",
    )
}

/// Refuses a solve whose coarsest state (`counts`, no subdivision, SH order 0)
/// does not fit in the planned share of the memory budget; `what` names the
/// counts' origin for the message.
fn check_coarsest(
    counts: &budget::Counts,
    settings: &SolverSettings,
    what: &str,
) -> Result<(), SolveError> {
    let Some(limit) = settings.memory_budget else {
        return Ok(());
    };
    let estimate = budget::estimate(counts);
    let peak = estimate.peak();
    if peak <= budget::plan(limit) {
        return Ok(());
    }
    let needed = (peak as f64 / budget::PLANNING_FRACTION).ceil() as u128;
    Err(SolveError::OverBudget(format!(
        "the estimated peak memory {} exceeds the memory budget {} (the solve plans against \
         {:.0}% of it) even with the coarsest mesh ({what}: {} patches, {} vertices: no \
         subdivision, every material at SH order 0): {}. Raise --memory-budget to at least {}, \
         or use fewer patches per polygon (`patches` in the scene config or the preset), or a \
         smaller scene",
        human_bytes(peak as u128),
        human_bytes(limit as u128),
        100.0 * budget::PLANNING_FRACTION,
        counts.patches,
        counts.vertices,
        estimate.breakdown(),
        human_bytes(needed),
    )))
}

/// `bytes` as GiB/MiB/KiB with one decimal, for the memory-bound refusals of
/// the Gauss–Seidel and global-cube solves.
pub(crate) fn human_bytes(bytes: u128) -> String {
    let b = bytes as f64;
    if b >= (1u64 << 30) as f64 {
        format!("{:.1} GiB", b / (1u64 << 30) as f64)
    } else if b >= (1u64 << 20) as f64 {
        format!("{:.1} MiB", b / (1u64 << 20) as f64)
    } else {
        format!("{:.1} KiB", b / 1024.0)
    }
}

#[cfg(test)]
mod directional_lights_tests;
#[cfg(test)]
mod directional_tests;
#[cfg(test)]
mod emissive_tests;
#[cfg(test)]
mod folded_texture_tests;
#[cfg(test)]
mod footprint_tests;
#[cfg(test)]
mod gltf_lights_tests;
#[cfg(test)]
mod group_shot_tests;
#[cfg(test)]
mod hidden_tests;
#[cfg(test)]
mod lights_tests;
#[cfg(test)]
mod metal_tests;
#[cfg(test)]
mod physics_tests;
#[cfg(test)]
mod portal_detect_tests;
#[cfg(test)]
mod ray_share_tests;
#[cfg(test)]
mod smooth_tests;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod texture_tests;
#[cfg(test)]
mod two_slot_tests;
