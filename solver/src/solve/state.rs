//! The [`super::Solver`]'s state, split by job: each struct below is owned by
//! the solver and holds one kind of data, so a step can borrow one part
//! mutably while it reads another.

use super::{cluster, shoot, Timings};
use super::{footprint, group_shot, sites, small, textured, twins, unshot_tree};
use crate::mesh::Mesh;
use crate::scene::Scene;
use glam::DVec3;
use solution::format::SolveMode;

/// What the solution header needs of the scene, and where the solver's
/// coordinates sit in it.
pub(super) struct SceneFacts {
    /// Scene coordinates minus this are the solver's (re-centred) coordinates.
    pub offset: DVec3,
    /// From the scene, for the solution header.
    pub recentre: DVec3,
    pub camera: Option<solution::camera::Camera>,
    pub units_per_metre: f64,
    pub up_axis: solution::camera::UpAxis,
}

/// Per mesh surface, how it reflects and emits.
pub(super) struct Materials {
    /// The reflectance receivers apply to a shot (1 on textured surfaces,
    /// whose vertices hold E/π: `textured.rs`).
    pub kd: Vec<DVec3>,
    /// The mean reflectance (Kd, or Kd ⊙ the texture's mean), for the
    /// ambient term.
    pub albedo: Vec<DVec3>,
    /// The textured surfaces.
    pub texturing: textured::SurfaceTexturing,
    /// The radiance the surface's vertices start with.
    pub emission: Vec<DVec3>,
}

/// Per vertex, the light field the shots build.
pub(super) struct VertexField {
    /// Radiance L (RGB), emission included.
    pub radiance: Vec<DVec3>,
    /// ΔL of the shot in progress.
    pub received: Vec<DVec3>,
    /// Visible samples of the shot in progress.
    pub visible: Vec<u32>,
    /// The part of `radiance` that came from recorded (emitter) shots.
    pub direct: Vec<DVec3>,
    /// Whether its receiving point is enclosed by an object's inside
    /// ([`super::hidden`]); classified as vertices appear.
    pub hidden: Vec<bool>,
}

/// Per patch, the light it has yet to shoot and how it gathers it.
pub(super) struct PatchLight {
    /// Unshot radiance (RGB).
    pub unshot: Vec<DVec3>,
    /// (vertex, area) weights of the gather.
    pub weights: Vec<Vec<(u32, f64)>>,
    /// RGB gather weights if textured (empty for the others; the whole list
    /// is empty when no surface is textured, so an untextured solve holds
    /// nothing more).
    pub rgb_weights: Vec<Vec<(u32, DVec3)>>,
    /// The area its unshot radiance stands for: the gather weights of its
    /// vertices that are not hidden (its area when none is).
    pub shoot_area: Vec<f64>,
    /// Per surface, its patches (contiguous).
    pub of_surface: Vec<std::ops::Range<u32>>,
    /// The unshot power under a tree of sums and maxima, built on the first
    /// diffuse step ([`unshot_tree`]).
    pub unshot_index: Option<unshot_tree::UnshotIndex>,
}

/// The emitter shots every later vertex receives exactly (`refine.rs`).
#[derive(Default)]
pub(super) struct Recording {
    /// Every shot from an emitter's patch, in order.
    pub shots: Vec<shoot::RecordedShot>,
    /// Their sample pools (rebuilt on resume, not checkpointed).
    pub pools: Vec<shoot::SamplePool>,
    /// The emitters' first shots taken in groups, in order
    /// (`group_shot.rs`), and their members under their trees (rebuilt on
    /// resume, not checkpointed).
    pub groups: Vec<shoot::RecordedGroup>,
    pub group_sources: Vec<std::sync::Arc<group_shot::GroupSources>>,
    /// Which emitter patches have shot their emission, for grouped shooters
    /// (derived from `shots` and `groups`, so a resume rebuilds it).
    pub emitters_shot: group_shot::EmittersShot,
}

/// The receivers that share one sample among several vertices, and what
/// each shot touched.
pub(super) struct Sharing {
    /// The small flat surfaces that receive once per shot ([`small`]).
    pub small: small::SmallSurfaces,
    /// Coincident vertices of a smooth surface that take one sample per
    /// shot ([`twins`]).
    pub twins: twins::Twins,
    /// The points of finely tessellated smooth surfaces that interpolate
    /// sites instead of receiving ([`sites`]).
    pub sites: sites::Sites,
    /// What each shot touched, for the sparse passes ([`footprint`]).
    pub footprint: footprint::Footprint,
}

/// What grouped shots rank their members with.
pub(super) struct Groups {
    /// The surfaces under a bounding-volume hierarchy.
    pub receivers: cluster::ReceiverTree,
    /// The most patches a grouped shot can rank ([`super::budget::Counts`]).
    pub candidates: Option<u64>,
}

/// Counters of the solve's progress.
#[derive(Default)]
pub(super) struct Stats {
    /// Leaf elements.
    pub leaf_count: usize,
    pub shots: u64,
    pub rays: u64,
    /// Seconds spent stepping (every session of a resumed solve).
    pub seconds: f64,
    /// Total emitted power in scene units (radiance × scene area), summed
    /// over the channels; [`super::Solver::progress`] reports it in watts.
    pub emitted_power: f64,
    pub unshot_power: f64,
    /// Where step time went (this session).
    pub timings: Timings,
    /// The scene's radiance level (brightest channel of the ambient term
    /// before any shot), for the meshing's dark floor.
    pub radiance_level: f64,
}

/// The memory budget's bookkeeping ([`super::budget`]).
#[derive(Default)]
pub(super) struct MemoryGuard {
    /// The largest peak memory estimated so far.
    pub peak_estimate: u64,
    /// The scene as imported, which the caller holds during the solve
    /// ([`super::budget::scene_bytes`]).
    pub scene_bytes: u64,
    /// Whether the budget has refused a split (warned once).
    pub refinement_capped: bool,
}

/// Warnings for the caller to show.
#[derive(Default)]
pub(super) struct Warnings {
    /// The set-up's ([`super::Solver::warnings`]).
    pub setup: Vec<String>,
    /// Raised while solving, until taken ([`super::Solver::take_warnings`]).
    pub pending: Vec<String>,
}

impl Materials {
    /// Each surface's reflectance and emission. Diffuse and emission
    /// textures are modelled in both modes (diffuse: `textured.rs`;
    /// directional: `directional/textured.rs`, whose SH start from the same
    /// per-surface and per-patch emission). Also returns, per patch of an
    /// emission-textured surface, the mean Le it shoots (`textured.rs`); the
    /// surface's vertices start at its mean Le. In diffuse `mode` a glossy
    /// material reflects its diffuse equivalent
    /// ([`crate::scene::Material::diffuse_equivalent_kd`]), textured or not.
    pub fn new(
        scene: &Scene,
        mesh: &Mesh,
        mut texturing: textured::SurfaceTexturing,
        mode: SolveMode,
    ) -> (Materials, Vec<Option<DVec3>>) {
        let material_kd = |material: usize| {
            let m = &scene.materials[material];
            match mode {
                SolveMode::Diffuse => m.diffuse_equivalent_kd(),
                SolveMode::Directional => m.kd,
            }
        };
        texturing.set_mode(scene, mesh, mode);
        let albedo: Vec<DVec3> = mesh
            .surfaces
            .iter()
            .zip(&texturing.per_surface)
            .map(|(s, t)| match t {
                Some(t) => t.kd * t.texture.texture.mean(),
                None => material_kd(s.material),
            })
            .collect();
        let kd: Vec<DVec3> = (0..mesh.surfaces.len())
            .map(|s| match texturing.get(s as u32) {
                Some(_) => DVec3::ONE,
                None => albedo[s],
            })
            .collect();
        let mut emission: Vec<DVec3> = mesh
            .surfaces
            .iter()
            .map(|s| scene.materials[s.material].emission)
            .collect();
        let patch_emission = textured::patch_emission(&texturing, mesh, &mut emission);
        let materials = Materials {
            kd,
            albedo,
            texturing,
            emission,
        };
        (materials, patch_emission)
    }
}

impl VertexField {
    /// Every vertex at its surface's emission, nothing received yet.
    pub fn new(mesh: &Mesh, emission: &[DVec3]) -> VertexField {
        let count = mesh.vertices.len();
        VertexField {
            radiance: mesh
                .vertices
                .iter()
                .map(|v| emission[v.surface as usize])
                .collect(),
            received: vec![DVec3::ZERO; count],
            visible: vec![0; count],
            direct: vec![DVec3::ZERO; count],
            hidden: Vec::new(),
        }
    }

    /// The fields refinement updates, borrowed.
    pub fn state(&mut self) -> super::refine::VertexState<'_> {
        super::refine::VertexState {
            radiance: &mut self.radiance,
            received: &mut self.received,
            visible: &mut self.visible,
            direct: &mut self.direct,
        }
    }
}

impl PatchLight {
    /// Every patch about to shoot what it emits (`patch_emission` where an
    /// emission texture sets it, else its surface's emission); the gather
    /// weights are set by the solver once it exists.
    pub fn new(
        mesh: &Mesh,
        materials: &Materials,
        patch_emission: Vec<Option<DVec3>>,
    ) -> PatchLight {
        let count = mesh.patches.len();
        let mut of_surface = vec![0..0; mesh.surfaces.len()];
        for (p, patch) in mesh.patches.iter().enumerate() {
            let r: &mut std::ops::Range<u32> = &mut of_surface[patch.surface as usize];
            if r.start == r.end {
                *r = p as u32..p as u32 + 1;
            } else {
                r.end = p as u32 + 1;
            }
        }
        PatchLight {
            unshot: mesh
                .patches
                .iter()
                .zip(patch_emission)
                .map(|(p, textured)| textured.unwrap_or(materials.emission[p.surface as usize]))
                .collect(),
            weights: vec![Vec::new(); count],
            rgb_weights: if materials.texturing.any() {
                vec![Vec::new(); count]
            } else {
                Vec::new()
            },
            shoot_area: vec![0.0; count],
            of_surface,
            unshot_index: None,
        }
    }
}

impl Recording {
    /// Remembers `shot` from patch `patch`, shooting mean unshot radiance
    /// `unshot` to the `receivers` vertices there are, with the pool its
    /// replays draw from.
    pub fn push(&mut self, shot: &shoot::Shot, patch: u32, unshot: DVec3, receivers: usize) {
        self.shots.push(shoot::RecordedShot {
            index: shot.index,
            patch,
            receivers: receivers as u32,
            unshot: unshot.to_array().map(f64::to_bits),
        });
        self.pools
            .push(shoot::SamplePool::with_sets(shot, shoot::REPLAY_POOL_SETS));
    }

    /// Remembers a group of emitters' first shots, `record`, whose members
    /// shoot as `sources`.
    pub fn push_group(
        &mut self,
        record: shoot::RecordedGroup,
        sources: std::sync::Arc<group_shot::GroupSources>,
    ) {
        self.groups.push(record);
        self.group_sources.push(sources);
    }

    /// The recorded groups as shots again, for their replay to new vertices
    /// (they share the members and trees the recording keeps).
    pub fn group_replays<'a>(
        &self,
        settings: &crate::settings::SolverSettings,
        occluder: &'a crate::geometry::visibility::Occluder,
        kd: &'a [DVec3],
    ) -> Vec<group_shot::GroupShot<'a>> {
        self.groups
            .iter()
            .zip(&self.group_sources)
            .map(|(r, sources)| {
                group_shot::GroupShot::of(sources.clone(), r.index, settings, occluder, kd)
                    .recorded(settings)
            })
            .collect()
    }
}

impl Sharing {
    /// The small flat surfaces; twins and sites are found once the hidden
    /// vertices are known ([`super::Solver::new`]).
    pub fn new(mesh: &Mesh, of_surface: &[std::ops::Range<u32>]) -> Sharing {
        Sharing {
            small: small::SmallSurfaces::new(mesh, of_surface),
            twins: twins::Twins::default(),
            sites: sites::Sites::default(),
            footprint: footprint::Footprint::default(),
        }
    }
}

impl Groups {
    /// The receiver tree and the most patches a grouped shot can rank.
    pub fn new(mesh: &Mesh, of_surface: &[std::ops::Range<u32>]) -> Groups {
        let receivers = cluster::ReceiverTree::new(mesh);
        let per_surface: Vec<u64> = of_surface.iter().map(|r| r.len() as u64).collect();
        let candidates = Some(
            receivers.most_patches_near(group_shot::RADIUS * receivers.diagonal(), &per_surface),
        );
        Groups {
            receivers,
            candidates,
        }
    }
}
