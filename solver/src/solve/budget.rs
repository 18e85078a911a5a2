//! Memory known before it is allocated: the progressive solve's peak memory,
//! estimated from the sizes of the structures it will hold, and the budget it
//! is planned against.
//!
//! ## The estimate
//!
//! [`estimate`] turns [`Counts`] (vertices, elements, patches, SH coefficients,
//! recorded shots) into bytes, term by term, each from the `size_of` of the
//! structure that holds it (see the functions below for the exact list):
//!
//! * **fixed**: the process before any solve state ([`FIXED_BYTES`], measured:
//!   the executable, the allocator, the worker threads) and the scene as
//!   imported ([`scene_bytes`]: per input polygon its [`Polygon`], corners,
//!   shading normals and source reference, which the command line keeps for
//!   the whole solve), or the resident set measured before meshing where the
//!   command line could read it and it is larger (import's freed pages that
//!   the allocator keeps), and per mesh surface its tables, occlusion BVH share and
//!   receiver-tree share ([`surface_bytes`]);
//! * **mesh**: per vertex a [`MeshVertex`] and its slot in the vertex table (a
//!   hashbrown map: a power-of-two bucket count at most 7/8 full, each bucket
//!   one `(VertexKey, u32)` and one control byte), per element an [`Element`],
//!   per split a split-log entry;
//! * **vertex state**: the solver's per-vertex radiance, ΔL and recorded-shot
//!   radiance (three `DVec3`), visibility (`u32`) and hidden flag (`bool`);
//! * **SH**: directional mode's radiance, ΔL and recorded-shot coefficients,
//!   `3 (L+1)²` f64 per vertex each at its surface's order L (three more, E/π,
//!   on a textured surface: `directional/textured.rs`), an offset per vertex,
//!   and the patches' unshot coefficients;
//! * **patches**: per patch a [`Patch`], its unshot radiance, its shooting
//!   area and its gather weights (`(u32, f64)` per vertex of the patch, in a
//!   heap block of its own);
//! * **indexes** (diffuse mode, which alone uses them): the footprint's
//!   per-surface vertex lists (`footprint.rs`: a `u32` per vertex in a list
//!   per surface, each list's capacity as `Vec::push` grows it, see
//!   [`list_slots`]) and its per-surface marks; the small
//!   surfaces' index (`u32` per surface) and receiving points (`small.rs`);
//!   the table of coincident smooth vertices (`u32` per vertex of the
//!   unrefined mesh, `twins.rs`); the sites' tables (a `bool` per vertex
//!   of the unrefined mesh, two `u32` per interpolating point and a
//!   `(u32, f32)` per source, `sites.rs`);
//!   and the unshot tree (`unshot_tree.rs`: two nodes per leaf, the leaves
//!   the patch count rounded up to a power of two);
//! * **recorded shots**: what refinement replays, per emitter shot its
//!   [`RecordedShot`], its replay sample pool (points on and lifted off the
//!   source) and the rebuilt [`Shot`], and in directional mode its unshot SH.
//!
//! and four transient peaks, of which only the largest counts (they never
//! overlap: each is freed before the next begins):
//!
//! * **shot**: one shot's per-vertex and per-small-surface results
//!   (directional: a heap vector of
//!   coefficients per vertex) and its sample pool, and a grouped shot's
//!   members and their tree ([`group_shot_bytes`]), for as many patches as
//!   lie within the group radius of one point (`Counts::group_candidates`;
//!   every patch before the solver is built);
//! * **checkpoint**: the writer's buffers. Checkpoints stream section by
//!   section from the solver's own arrays through a 1 MiB buffer
//!   ([`Solver::write_checkpoint`]), their f64 arrays packed a 256 KiB chunk
//!   at a time, so the state is never copied; only the directional recorded
//!   shots' length table (4 bytes a shot) and per-patch mask flags (4 bytes a
//!   patch) are built;
//! * **output**: the solution ([`Solver::to_solution`]): per vertex a stored
//!   vertex and its f32 coefficients, per display triangle its indices, and in
//!   directional mode the diffuse-style batch that the per-order batches
//!   replace, alive while they are built, and the f64 coefficients shown
//!   (hidden vertices filled, contact cuts averaged), and when the scene names
//!   no camera the default view's hierarchy over the solution's triangles
//!   (`crate::view::transient_bytes`, about 85 bytes a triangle);
//! * **gather** (diffuse mode): the touched patches' list and its copy, and
//!   the larger of the per-patch sums and the unshot tree rebuilt beside the
//!   old one (`UnshotTree::update_many` when a shot changed more than 1/8 of
//!   the patches).
//!
//! Large vectors are counted by length, not capacity: they live in their own
//! memory mappings, and the unused part of a capacity that doubled is never
//! touched, so it is not resident.
//!
//! ## The budget
//!
//! `SolverSettings::memory_budget` (bytes; `None` plans nothing). The solver
//! plans against [`PLANNING_FRACTION`] of it, the rest being the margin for the
//! estimate's error. A directional solve first caps SH orders until the
//! unrefined mesh fits in [`ORDER_SHARE`] of the plan (leaving the rest to
//! refinement), then refinement splits only what fits
//! ([`SplitBudget`]); a scene whose unrefined mesh at SH order 0 does not fit
//! is refused before its state is allocated.

use super::shoot::{Received, RecordedShot, Shot, POOL_POINTS, POOL_SETS, REPLAY_POOL_SETS};
use super::unshot_tree::NODE_BYTES;
use super::{Directional, Solver};
use crate::mesh::{Element, Mesh, MeshVertex, Patch, Surface, VertexKey};
use crate::scene::{Polygon, Scene};
use crate::settings::SolverSettings;
use glam::DVec3;
use std::mem::size_of;

/// The solver plans against this fraction of the budget; the other 10% is the
/// margin for the estimate's error (measured within it: docs/benchmarks.md,
/// "Memory: estimate against measured peak").
pub const PLANNING_FRACTION: f64 = 0.9;

/// A directional solve caps SH orders until its unrefined state fits in this
/// share of the plan, so that refinement has the other half: a mesh that
/// cannot refine at all shows shadows as coarsely as its patches.
pub const ORDER_SHARE: f64 = 0.5;

/// The process before any solve state: the executable and its libraries, the
/// allocator's arenas, the scene as imported and the command line's buffers,
/// measured as 6.2 MiB peak RSS of a `solver solve` of the Cornell box refused
/// before meshing (release build, this machine), plus 0.8 MiB for the worker
/// threads' touched stacks and buffers (the Cornell box's measured peak at
/// `--preset medium` less its estimated solve state).
pub const FIXED_BYTES: u64 = 7 << 20;

/// The bytes each surface costs wherever it is held, from the structures'
/// sizes (a quad surface: four corners, two triangles; the test
/// `surface_term_matches_the_allocated_per_surface_structures` sums the real
/// tables): the mesh's [`Surface`], its heap block of corners, its piece and
/// the piece's patch range; the occlusion BVH's two triangles
/// ([`crate::geometry::visibility::Occluder::bytes_per_triangle`]); the
/// receiver tree's share ([`super::cluster::ReceiverTree::bytes_per_surface`]);
/// and the solver's per-surface reflectance, albedo, emission, patch range
/// and texturing slot. (The input polygons are [`scene_bytes`]: a surface may
/// weld many of them.) It was a rounded guess of 664 bytes, which left out
/// the receiver tree, until the 1M Cornell boxes measured a peak 28% above
/// the estimate; it is 944 bytes now.
pub fn surface_bytes() -> u64 {
    let range = size_of::<std::ops::Range<u32>>();
    let mesh = size_of::<Surface>()
        + heap_chunk(4 * size_of::<DVec3>()) as usize
        + size_of::<crate::mesh::Piece>()
        + range;
    let solver = 3 * size_of::<DVec3>() + range + size_of::<Option<super::textured::Textured>>();
    (mesh + solver) as u64
        + 2 * crate::geometry::visibility::Occluder::bytes_per_triangle()
        + super::cluster::ReceiverTree::bytes_per_surface()
}

/// The scene as imported, per input polygon: its [`Polygon`] (held inline in
/// the scene's vector), the heap blocks of its corners and of its shading
/// normals, and its source reference's file path and item name. The scene
/// lives for the whole solve (the command line holds it), and on a
/// tessellated model it is one of the largest terms: the 99,628 triangles of
/// the floor-plan scale scene take 26 MB.
pub fn scene_bytes(scene: &Scene) -> u64 {
    scene.polygons.iter().map(polygon_bytes).sum()
}

/// The bytes glibc's malloc takes for a block of `bytes`: an 8-byte header,
/// rounded up to 16, at least 32 (its smallest chunk); none for an empty
/// vector or string, which allocates nothing.
pub(super) fn heap_chunk(bytes: usize) -> u64 {
    if bytes == 0 {
        return 0;
    }
    ((bytes as u64 + 8).div_ceil(16) * 16).max(32)
}

fn polygon_bytes(p: &Polygon) -> u64 {
    let block = heap_chunk;
    let normals = p
        .vertex_normals
        .as_ref()
        .map_or(0, |n| block(n.len() * size_of::<DVec3>()));
    size_of::<Polygon>() as u64
        + block(p.vertices.len() * size_of::<DVec3>())
        + normals
        + block(p.source.file.as_os_str().len())
        // The item name ("face 12 (line 40)") is built piece by piece, so
        // its capacity doubled to the power of two above its length.
        + block(p.source.item.len().next_power_of_two())
}

/// The buffer a checkpoint streams through (`solution::atomic::write_atomically_buffered`).
const CHECKPOINT_BUFFER_BYTES: u64 = 1 << 20;

/// miniz_oxide's deflate state: its 32 KiB window, two tables of 32 Ki u16
/// (hash heads and chains), the 64 KiB LZ code buffer and the Huffman tables,
/// about 240 KiB; rounded up.
const PACKER_STATE_BYTES: u64 = 320 << 10;

/// glibc's per-allocation overhead on a small heap block: an 8-byte header,
/// rounded up to 16.
pub(super) const HEAP_BLOCK_OVERHEAD: u64 = 16;

/// A 1 MiB buffered writer per output file written.
const WRITER_BUFFER: u64 = 1 << 20;

/// What the estimate needs to know about a solve.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Counts {
    pub surfaces: u64,
    pub patches: u64,
    pub elements: u64,
    pub vertices: u64,
    /// Splits done (the split log's length).
    pub splits: u64,
    /// Σ over patches of the vertices in its gather weights.
    pub weight_entries: u64,
    pub recorded_shots: u64,
    /// Members of the recorded groups of emitters' first shots, each kept
    /// with its piece, tree share and record for the whole solve.
    pub recorded_members: u64,
    /// Visibility rays per receiver (the pools' points per set).
    pub samples: u64,
    pub directional: bool,
    /// Σ over vertices of `3 (L+1)²` at its surface's order.
    pub vertex_coefficients: u64,
    /// Σ over patches of the same.
    pub patch_coefficients: u64,
    /// Σ over recorded shots of their source's `3 (L+1)²`.
    pub recorded_coefficients: u64,
    /// Decoded diffuse textures (RGBA texels and linear pyramids) and the
    /// textured patches' RGB gather weights, in bytes (`textured.rs`).
    pub texture_bytes: u64,
    /// The scene as imported ([`scene_bytes`]).
    pub scene_bytes: u64,
    /// The process's resident bytes measured before meshing (0: not
    /// measured), which the fixed term is at least
    /// (`SolverSettings::resident_before_meshing`).
    pub resident_before_meshing: u64,
    /// Σ over surfaces of [`list_slots`] of its vertex count: the entries
    /// the footprint's per-surface vertex lists hold room for.
    pub index_slots: u64,
    /// Surfaces with at least one vertex (one heap block each in the index).
    pub index_lists: u64,
    /// Grouped shooters (`--shooters grouped`), whose shot holds its members
    /// and their tree ([`group_shot_bytes`]).
    pub grouped: bool,
    /// The most patches one grouped shot can rank as candidates (its
    /// members among them): `cluster::ReceiverTree::most_patches_near` once
    /// the solver has its receivers; `None`, every patch, before.
    pub group_candidates: Option<u64>,
    /// The small flat surfaces that receive once per shot (`small.rs`);
    /// `None`, every surface, before the solver has meshed.
    pub small_surfaces: Option<u64>,
    /// The vertices the table of coincident smooth vertices covers
    /// (`twins.rs`: the unrefined mesh's, none when no vertex copies
    /// another); `None`, every vertex, before the solver has built it.
    pub twin_table: Option<u64>,
    /// The sites' tables (`sites.rs`): (vertices covered, interpolating
    /// points, sources); `None` before the solver has built them, counted as
    /// none (at most 45 bytes per interpolating point, a few percent of a
    /// vertex's own bytes even where every point of a scene interpolates).
    pub site_tables: Option<(u64, u64, u64)>,
    /// The scene names no camera, so the output chooses a view over the
    /// solution's triangles ([`crate::view::transient_bytes`]).
    pub chooses_view: bool,
}

/// The estimate in bytes, per term (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MemoryEstimate {
    pub fixed: u64,
    pub mesh: u64,
    pub vertex_state: u64,
    pub sh: u64,
    pub patches: u64,
    pub recorded: u64,
    pub shot: u64,
    pub checkpoint: u64,
    pub output: u64,
    /// The footprint index and the unshot tree (diffuse mode).
    pub index: u64,
    /// The gather's transient (diffuse mode).
    pub gather: u64,
}

impl MemoryEstimate {
    /// What the solve holds between shots.
    pub fn persistent(&self) -> u64 {
        self.fixed
            + self.mesh
            + self.vertex_state
            + self.sh
            + self.patches
            + self.recorded
            + self.index
    }

    /// The largest of the transient peaks (they do not overlap).
    pub fn transient(&self) -> u64 {
        self.shot
            .max(self.checkpoint)
            .max(self.output)
            .max(self.gather)
    }

    /// The peak: what is held plus the largest transient.
    pub fn peak(&self) -> u64 {
        self.persistent() + self.transient()
    }

    /// The terms, for messages.
    pub fn breakdown(&self) -> String {
        let h = |b: u64| human_bytes(b as u128);
        format!(
            "fixed {}, mesh {}, vertex state {}, SH coefficients {}, patches {}, recorded shots \
             {}, indexes {}, and the largest of shot {} / checkpoint {} / output {} / gather {}",
            h(self.fixed),
            h(self.mesh),
            h(self.vertex_state),
            h(self.sh),
            h(self.patches),
            h(self.recorded),
            h(self.index),
            h(self.shot),
            h(self.checkpoint),
            h(self.output),
            h(self.gather)
        )
    }
}

/// `bytes` as GiB/MiB/KiB with one decimal.
pub fn human_bytes(bytes: u128) -> String {
    super::human_bytes(bytes)
}

/// Buckets of a hashbrown table holding `n` entries: the next power of two
/// with `n ≤ 7/8 · buckets` (at least 4 when not empty).
fn table_buckets(n: u64) -> u64 {
    if n == 0 {
        return 0;
    }
    if n < 4 {
        return 4;
    }
    (n * 8).div_ceil(7).next_power_of_two()
}

/// Bytes of the vertex table at `n` entries.
fn table_bytes(n: u64) -> u64 {
    let buckets = table_buckets(n);
    buckets * (size_of::<(VertexKey, u32)>() as u64 + 1)
}

/// The capacity, in entries, of a `Vec<u32>` grown by `n` pushes from
/// empty: `RawVec` doubles, from at least 4 entries for elements of 4 bytes
/// (its `MIN_NON_ZERO_CAP`), so 0 for none and max(4, n rounded up to a
/// power of two) otherwise. The footprint's per-surface lists grow this way
/// (`SurfaceVertices::catch_up`). Unlike the solver's large vectors, these
/// are many small heap blocks, so their unused capacity is resident.
pub fn list_slots(n: u64) -> u64 {
    match n {
        0 => 0,
        _ => n.next_power_of_two().max(4),
    }
}

/// The unshot tree's bytes over `patches` patches: two nodes per leaf, the
/// leaves a power of two ≥ the patch count (`UnshotTree::new`).
pub fn unshot_tree_bytes(patches: u64) -> u64 {
    2 * patches.max(1).next_power_of_two() * NODE_BYTES
}

/// The indexes of a diffuse solve (see the module documentation): the
/// footprint's lists (their slots, a heap block and a header each) and its
/// per-surface mark (`bool`) and touched list (`u32`, by length), and the
/// unshot tree.
fn index_bytes(c: &Counts) -> u64 {
    if c.directional {
        return 0;
    }
    let lists = c.index_slots * size_of::<u32>() as u64
        + c.index_lists * HEAP_BLOCK_OVERHEAD
        + c.surfaces * (size_of::<Vec<u32>>() + size_of::<bool>() + size_of::<u32>()) as u64;
    let small = super::small::SmallSurfaces::bytes(c.surfaces, small_surfaces(c));
    let twins = super::twins::Twins::bytes(c.twin_table.unwrap_or(c.vertices));
    let (covered, targets, sources) = c.site_tables.unwrap_or_default();
    let sites = super::sites::Sites::bytes(covered, targets, sources);
    lists + small + twins + sites + unshot_tree_bytes(c.patches)
}

/// The surfaces that receive once per shot, at most every surface.
fn small_surfaces(c: &Counts) -> u64 {
    c.small_surfaces.unwrap_or(c.surfaces).min(c.surfaces)
}

/// The gather's transient (diffuse mode): the touched patches and their copy
/// (`u32` each, at most every patch), then the larger of the per-patch sums
/// (`DVec3`) and the rebuilt unshot tree, which exists beside the old one
/// while it replaces it.
fn gather_bytes(c: &Counts) -> u64 {
    if c.directional {
        return 0;
    }
    2 * c.patches * size_of::<u32>() as u64
        + (c.patches * size_of::<DVec3>() as u64).max(unshot_tree_bytes(c.patches))
}

/// Points of a sample pool of `sets` sets of `samples` (as `SamplePool::with_sets`).
fn pool_points(samples: u64, sets: u32) -> u64 {
    let sets = (sets as u64).min((POOL_POINTS as u64 / samples.max(1)).max(8));
    sets * samples
}

/// A pool's bytes: points on the source and the same lifted off it.
fn pool_bytes(samples: u64, sets: u32) -> u64 {
    2 * pool_points(samples, sets) * size_of::<DVec3>() as u64
}

/// The estimate for `c` (see the module documentation).
pub fn estimate(c: &Counts) -> MemoryEstimate {
    let dvec3 = size_of::<DVec3>() as u64;
    let f64_ = size_of::<f64>() as u64;
    // The measured resident set before meshing holds the process and the
    // scene, and also what import freed but the allocator kept: on the 1M
    // floor plan 254 MiB where these terms give 68 MiB, the estimate's whole
    // shortfall (docs/lab/small-surfaces.md, "What import leaves resident").
    let before_meshing = (FIXED_BYTES + c.scene_bytes).max(c.resident_before_meshing);
    let fixed = before_meshing + c.surfaces * surface_bytes() + c.texture_bytes;
    let mesh = c.vertices * size_of::<MeshVertex>() as u64
        + table_bytes(c.vertices)
        + c.elements * size_of::<Element>() as u64
        + c.splits * size_of::<u32>() as u64;
    // Radiance, ΔL and recorded-shot radiance, the visible count, the hidden
    // flag and the enclosure cache's f32.
    let vertex_state = c.vertices
        * (3 * dvec3
            + size_of::<u32>() as u64
            + size_of::<bool>() as u64
            + size_of::<f32>() as u64);
    // Radiance, ΔL and recorded-shot radiance per vertex coefficient; an
    // offset per vertex and per patch; the patches' unshot coefficients and
    // the sums they have shot (`directional/near_gather.rs`).
    let sh = if c.directional {
        3 * c.vertex_coefficients * f64_
            + (c.vertices + c.patches) * size_of::<usize>() as u64
            + 2 * c.patch_coefficients * f64_
    } else {
        0
    };
    let weight_entry = size_of::<(u32, f64)>() as u64;
    let patches = c.patches
        * (size_of::<Patch>() as u64 + dvec3 + f64_ + size_of::<Vec<(u32, f64)>>() as u64)
        + c.weight_entries * weight_entry
        + c.patches * HEAP_BLOCK_OVERHEAD;
    let recorded = c.recorded_shots
        * (size_of::<RecordedShot>() as u64
            + pool_bytes(c.samples, REPLAY_POOL_SETS)
            + size_of::<Shot>() as u64
            + if c.directional {
                size_of::<Vec<f64>>() as u64 + HEAP_BLOCK_OVERHEAD
            } else {
                0
            })
        + c.recorded_coefficients * f64_
        + c.recorded_members
            * (super::group_tree::bytes_per_piece() + size_of::<(u32, [u64; 3])>() as u64);
    // One shot: its pool and a result per vertex (directional: the result
    // struct and its heap block of coefficients).
    let shot = pool_bytes(c.samples, POOL_SETS)
        + if c.directional {
            c.vertices * (size_of::<Vec<f64>>() as u64 + 8 + HEAP_BLOCK_OVERHEAD)
                + c.vertex_coefficients * f64_
        } else {
            (c.vertices + small_surfaces(c)) * size_of::<Received>() as u64
        }
        + if c.grouped {
            group_shot_bytes(c.group_candidates.unwrap_or(c.patches).min(c.patches))
        } else {
            0
        };
    let checkpoint = checkpoint_bytes(c);
    let output = output_bytes(c);
    MemoryEstimate {
        fixed,
        mesh,
        vertex_state,
        sh,
        patches,
        recorded,
        shot,
        checkpoint,
        output,
        index: index_bytes(c),
        gather: gather_bytes(c),
    }
}

/// The checkpoint's transient: the stream's buffer, the packer's (a chunk's
/// byte planes and its deflated bytes, 256 KiB each, and the deflate state,
/// [`PACKER_STATE_BYTES`]), the per-patch mask flags (4 bytes a patch) and
/// the recorded shots' length table; the state itself is written from where
/// it lives.
fn checkpoint_bytes(c: &Counts) -> u64 {
    let chunk = (8 * super::checkpoint::CHUNK_VALUES) as u64;
    CHECKPOINT_BUFFER_BYTES
        + 2 * chunk
        + PACKER_STATE_BYTES
        + if c.directional { 4 * c.patches } else { 0 }
        + 4 * c.recorded_shots
}

/// The output's transient: the solution and the writer's buffer.
fn output_bytes(c: &Counts) -> u64 {
    // Display triangles: at most two per vertex (a planar triangulation of a
    // disc has fewer than 2V triangles).
    let triangles = 2 * c.vertices;
    let stored_vertex = size_of::<solution::format::Vertex>() as u64;
    let f32_ = size_of::<f32>() as u64;
    let index_triple = 3 * size_of::<u32>() as u64;
    // The diffuse-style batch: vertices, 3 coefficients, indices, and the
    // triangle list its indices are flattened from.
    let diffuse = c.vertices * (stored_vertex + 3 * f32_) + triangles * 2 * index_triple;
    let directional = if c.directional {
        // The per-order batches, the vertex map and a second triangle list,
        // and the f64 coefficients shown (`Solver::displayed_coefficients`:
        // the solver's with hidden vertices filled, then averaged across
        // contact cuts in place by `seams.rs`).
        c.vertices * (stored_vertex + size_of::<u32>() as u64)
            + c.vertex_coefficients * (f32_ + size_of::<f64>() as u64)
            + triangles * 2 * index_triple
    } else {
        0
    };
    let view = if c.chooses_view {
        crate::view::transient_bytes(triangles)
    } else {
        0
    };
    diffuse + directional + view + WRITER_BUFFER
}

/// Whether a solve with `settings` makes grouped shots (a directional
/// solve groups its order-0 sources, `directional/group.rs`).
fn groups_shots(settings: &SolverSettings) -> bool {
    settings.shooters == crate::settings::Shooters::Grouped
}

/// The counts of a mesh not yet built: N patches per side (the solve's
/// [`crate::mesh::Sizing`] rule for each polygon) gives N² elements
/// per triangle or quad piece and at most (N+1)² vertices (a polygon of k > 4
/// vertices is counted as k − 2 triangles), at SH order 0, with E/π on the
/// vertices of a directional solve's textured surfaces (a diffuse texture
/// and UVs, as `SurfaceTexturing::new` decides). `parts` are the polygons'
/// cuts (`mesh::contact::conform`), counted part by part.
pub fn counts_before_meshing(
    scene: &Scene,
    settings: &SolverSettings,
    parts: &[Option<Vec<crate::mesh::contact::Part>>],
) -> Counts {
    let mut c = Counts {
        samples: settings.samples as u64,
        directional: settings.mode == solution::format::SolveMode::Directional,
        grouped: groups_shots(settings),
        scene_bytes: scene_bytes(scene),
        chooses_view: scene.camera.is_none(),
        resident_before_meshing: settings.resident_before_meshing.unwrap_or(0),
        ..Counts::default()
    };
    let sizing = crate::mesh::Sizing::from_settings(settings, scene);
    let mut textured_vertices = 0;
    let mut count = |corners: usize, n: u64, textured: bool| {
        let pieces = if corners <= 4 { 1 } else { corners as u64 - 2 };
        let vertices = pieces * (n + 1) * (n + 1);
        c.surfaces += 1;
        c.patches += pieces * n * n;
        c.elements += pieces * n * n;
        c.vertices += vertices;
        c.index_slots += list_slots(vertices);
        c.index_lists += 1;
        if textured {
            textured_vertices += vertices;
        }
    };
    // The receivers the mesh cuts along contact lines (`mesh::contact`),
    // part by part, as `Solver::new` decides.
    for (p, parts) in scene.polygons.iter().zip(parts) {
        let textured = p.uv_map.is_some() && {
            let m = &scene.materials[p.material];
            m.diffuse_texture.is_some() || m.folded_texture.is_some()
        };
        match parts {
            None => count(
                p.vertices.len(),
                sizing.patches_per_side(p) as u64,
                textured,
            ),
            Some(parts) => {
                for part in parts {
                    let n = sizing.patches_per_side_of_part(p, &part.vertices);
                    count(part.vertices.len(), n as u64, textured);
                }
            }
        }
    }
    c.weight_entries = c.vertices + 3 * c.patches;
    let mut textures: Vec<*const crate::scene::SceneTexture> = Vec::new();
    for t in scene.materials.iter().flat_map(|m| {
        m.diffuse_texture
            .iter()
            .chain(&m.emission_texture)
            .chain(&m.folded_texture)
    }) {
        if !textures.contains(&std::sync::Arc::as_ptr(t)) {
            textures.push(std::sync::Arc::as_ptr(t));
            c.texture_bytes += t.bytes();
        }
    }
    if c.directional {
        c.vertex_coefficients = 3 * c.vertices + 3 * textured_vertices;
        c.patch_coefficients = 3 * c.patches;
    }
    c
}

/// The cuts [`counts_before_meshing`] takes, as `Solver::new` makes them.
#[cfg(test)]
pub fn cuts_of(
    scene: &Scene,
    settings: &SolverSettings,
) -> Vec<Option<Vec<crate::mesh::contact::Part>>> {
    crate::mesh::contact::conform(scene, crate::mesh::contact::Cuts::for_settings(settings))
}

/// The counts of a built mesh, its surfaces at SH orders `order_of(surface)`
/// (with E/π on the vertices of the surfaces `textured` marks, in a
/// directional solve; an empty slice marks none),
/// with `recorded_shots` (of order-0 sources) and the weights as a fresh
/// mesh has them (each vertex once per patch it is a corner of, bounded by
/// vertices + 3 per patch).
pub fn counts_for_mesh(
    mesh: &Mesh,
    settings: &SolverSettings,
    order_of: impl Fn(usize) -> u32,
    textured: &[bool],
    recorded_shots: u64,
) -> Counts {
    let directional = settings.mode == solution::format::SolveMode::Directional;
    let mut per_surface_vertices = vec![0u64; mesh.surfaces.len()];
    for v in &mesh.vertices {
        per_surface_vertices[v.surface as usize] += 1;
    }
    let mut per_surface_patches = vec![0u64; mesh.surfaces.len()];
    for p in &mesh.patches {
        per_surface_patches[p.surface as usize] += 1;
    }
    let mut c = Counts {
        surfaces: mesh.surfaces.len() as u64,
        patches: mesh.patches.len() as u64,
        elements: mesh.elements.len() as u64,
        vertices: mesh.vertices.len() as u64,
        splits: mesh.split_log.len() as u64,
        weight_entries: (mesh.vertices.len() + 3 * mesh.patches.len()) as u64,
        recorded_shots,
        samples: settings.samples as u64,
        directional,
        index_slots: per_surface_vertices.iter().map(|&n| list_slots(n)).sum(),
        index_lists: per_surface_vertices.iter().filter(|&&n| n > 0).count() as u64,
        grouped: groups_shots(settings),
        resident_before_meshing: settings.resident_before_meshing.unwrap_or(0),
        ..Counts::default()
    };
    if directional {
        c.recorded_coefficients = 3 * recorded_shots;
        for s in 0..mesh.surfaces.len() {
            let e_over_pi = if textured.get(s) == Some(&true) { 3 } else { 0 };
            let k = coefficients(order_of(s));
            c.vertex_coefficients += per_surface_vertices[s] * (k + e_over_pi);
            c.patch_coefficients += per_surface_patches[s] * k;
        }
    }
    c
}

/// Patches of emitting surfaces: each shoots, and is recorded, at least once.
pub fn emitter_patches(scene: &Scene, mesh: &Mesh) -> u64 {
    mesh.patches
        .iter()
        .filter(|p| {
            scene.materials[mesh.surfaces[p.surface as usize].material].emission != DVec3::ZERO
        })
        .count() as u64
}

/// The SH order to keep per material so that the unrefined mesh's estimated
/// peak fits in `target` bytes: while it does not, the highest order (the
/// first such material on ties) drops by one, since the coefficients of one
/// vertex grow as (L+1)² and the highest order costs the most per band. Orders
/// stop at 0; the caller refuses what still does not fit. `textured` marks
/// the surfaces whose vertices also hold E/π ([`counts_for_mesh`]); the
/// scene itself takes `scene_bytes` ([`scene_bytes`]).
pub fn orders_within(
    mesh: &Mesh,
    settings: &SolverSettings,
    material_orders: &[u32],
    textured: &[bool],
    (recorded_shots, scene_bytes, chooses_view): (u64, u64, bool),
    target: u64,
) -> Vec<u32> {
    let mut orders = material_orders.to_vec();
    loop {
        let counts = Counts {
            scene_bytes,
            chooses_view,
            ..counts_for_mesh(
                mesh,
                settings,
                |s| orders[mesh.surfaces[s].material],
                textured,
                recorded_shots,
            )
        };
        if estimate(&counts).peak() <= target {
            return orders;
        }
        let Some((highest, _)) = orders
            .iter()
            .enumerate()
            .filter(|(_, &o)| o > 0)
            .max_by_key(|&(i, &o)| (o, std::cmp::Reverse(i)))
        else {
            return orders;
        };
        orders[highest] -= 1;
    }
}

/// The warning for a material whose SH order the budget capped: the order
/// kept and what it costs. By Parseval the lobe's energy (its squared L2 norm
/// over μ0 ∈ [−1, 1], Σ a_l² · 2/(2l+1)) splits band by band, so the fraction
/// in the dropped bands l > L is the squared relative L2 error of the
/// truncated Legendre series ([`crate::brdf::LegendreFit::error`]).
pub fn order_cap_warning(
    material: &str,
    alpha: f64,
    wanted: u32,
    kept: u32,
    budget: u64,
) -> String {
    let fit = crate::brdf::LegendreFit::new(alpha, kept);
    let error = fit.error(kept, crate::brdf::Window::None);
    // An order-L expansion resolves angular detail down to about 180°/L.
    let detail = if kept == 0 {
        "every direction alike (a diffuse-looking sheen)".to_string()
    } else {
        format!("nothing narrower than about {:.0}°", 180.0 / kept as f64)
    };
    format!(
        "memory budget {}: material `{}` (α = {:.4}) needs SH order L = {} but keeps L = {} \
         (Hann-windowed): the dropped bands hold {:.1}% of the lobe's energy (Parseval; relative \
         L2 error {:.3}). Its reflections render blurred, showing {}. Raise --memory-budget to \
         keep more bands",
        human_bytes(budget as u128),
        material,
        alpha,
        wanted,
        kept,
        100.0 * error * error,
        error,
        detail
    )
}

/// `3 (L+1)²`: the values per vertex at order L.
pub fn coefficients(order: u32) -> u64 {
    3 * solution::sh::coefficient_count(order) as u64
}

/// A grouped shot's own bytes (`group_shot.rs`, `group_tree.rs`) when it
/// may rank up to `candidates` patches: an `(f64, u32)` each, and up to
/// [`MAX_MEMBERS`](super::group_shot::MAX_MEMBERS) of them as members of
/// four quadrant pieces each, every piece with its
/// [`Piece`](super::group_shot::Piece), its member, two tree nodes and a
/// cumulative weight.
pub fn group_shot_bytes(candidates: u64) -> u64 {
    let members = candidates.min(super::group_shot::MAX_MEMBERS as u64);
    candidates * size_of::<(f64, u32)>() as u64 + members * 4 * super::group_tree::bytes_per_piece()
}

/// The bytes one split may add on a surface of `coefficients` values per
/// vertex (its SH, and E/π on a textured surface): four elements, at most
/// five vertices (four edge midpoints and a centre) with their gather-weight
/// entries (two each: a vertex on a patch edge is in both patches) and their
/// SH, charged at their persistent size plus their share of the largest
/// transient, a doubling vertex table and, in diffuse mode, a doubling
/// footprint list (two `u32` slots a vertex).
pub fn split_cost(coefficients: u64, directional: bool) -> u64 {
    let delta = Counts {
        elements: 4,
        vertices: 5,
        splits: 1,
        weight_entries: 10,
        directional,
        vertex_coefficients: if directional { 5 * coefficients } else { 0 },
        ..Counts::default()
    };
    let e = estimate(&delta);
    // Without the constants that `estimate` adds whatever the counts (the
    // fixed bytes, the pool, the writer buffer, the table of 5 entries, the
    // one-leaf unshot tree and its gather).
    let empty = Counts {
        directional,
        ..Counts::default()
    };
    let persistent = e.persistent() - FIXED_BYTES - table_bytes(5) - index_bytes(&empty);
    let transient = (e.shot - pool_bytes(0, POOL_SETS))
        .max(e.checkpoint)
        .max(e.output - WRITER_BUFFER);
    // A doubling table holds up to two buckets per entry (8/7 · 2).
    let table = 5 * 16 * (size_of::<(VertexKey, u32)>() as u64 + 1) / 7;
    let lists = if directional {
        0
    } else {
        5 * 2 * size_of::<u32>() as u64
    };
    persistent + transient + table + lists
}

/// How much refinement may still add this shot: bytes left under the plan and
/// the cost of a split per surface. [`super::refine::refine_field`] splits
/// while a split's cost fits and counts what it refused.
#[derive(Clone, Debug)]
pub struct SplitBudget {
    pub left: u64,
    /// Per surface, [`split_cost`] at its order (empty: splits are free).
    pub cost: Vec<u64>,
    /// Splits the test asked for that did not fit.
    pub refused: u64,
    /// The estimated peak when the budget was drawn up.
    pub peak_before: u64,
}

impl SplitBudget {
    /// No limit.
    pub fn unlimited() -> SplitBudget {
        SplitBudget {
            left: u64::MAX,
            cost: Vec::new(),
            refused: 0,
            peak_before: 0,
        }
    }

    /// Takes the cost of one split on `surface`; `false` when it does not fit.
    pub fn take(&mut self, surface: u32) -> bool {
        let cost = self.cost.get(surface as usize).copied().unwrap_or(0);
        if cost > self.left {
            return false;
        }
        self.left -= cost;
        true
    }
}

/// The bytes a solve plans against: [`PLANNING_FRACTION`] of the budget.
pub fn plan(budget: u64) -> u64 {
    (budget as f64 * PLANNING_FRACTION) as u64
}

impl Solver {
    /// The counts of the solve as it stands.
    pub fn memory_counts(&self) -> Counts {
        self.memory_counts_with(self.directional.as_deref())
    }

    /// [`Solver::memory_counts`] with the directional state `d` (taken out of
    /// the solver during a directional shot).
    fn memory_counts_with(&self, d: Option<&Directional>) -> Counts {
        let mut c = Counts {
            surfaces: self.mesh.surfaces.len() as u64,
            patches: self.mesh.patches.len() as u64,
            elements: self.mesh.elements.len() as u64,
            vertices: self.mesh.vertices.len() as u64,
            splits: self.mesh.split_log.len() as u64,
            weight_entries: self.patches.weights.iter().map(|w| w.len() as u64).sum(),
            recorded_shots: self.record.shots.len() as u64,
            recorded_members: self
                .record
                .groups
                .iter()
                .map(|g| g.members.len() as u64)
                .sum(),
            samples: self.settings.samples as u64,
            directional: false,
            texture_bytes: self.texture_bytes(),
            scene_bytes: self.memory.scene_bytes,
            grouped: groups_shots(&self.settings),
            group_candidates: self.groups.candidates,
            small_surfaces: Some(self.sharing.small.len() as u64),
            twin_table: Some(self.sharing.twins.table_len() as u64),
            site_tables: Some(self.sharing.sites.counts()),
            resident_before_meshing: self.settings.resident_before_meshing.unwrap_or(0),
            chooses_view: self.scene.camera.is_none(),
            ..Counts::default()
        };
        if let Some(d) = d {
            c.directional = true;
            (
                c.vertex_coefficients,
                c.patch_coefficients,
                c.recorded_coefficients,
            ) = d.coefficient_totals();
        } else {
            // The footprint's lists as they are once they have caught up with
            // the mesh (they do at the next shot or gather).
            for n in self.sharing.footprint.surface_vertices.lengths(&self.mesh) {
                c.index_slots += list_slots(n);
                c.index_lists += u64::from(n > 0);
            }
        }
        c
    }

    /// The estimated peak memory of the solve as it stands (see the module
    /// documentation).
    pub fn memory_estimate(&self) -> MemoryEstimate {
        estimate(&self.memory_counts())
    }

    /// The largest peak estimated so far (at set-up and before each
    /// refinement), for the closing summary.
    pub fn peak_memory_estimate(&self) -> u64 {
        self.memory.peak_estimate
    }

    /// What refinement may add this shot under the budget (`directional`: the
    /// directional state, taken out of the solver during its shot).
    pub(super) fn split_budget(&self, directional: Option<&Directional>) -> SplitBudget {
        let counts = self.memory_counts_with(directional);
        let now = estimate(&counts).peak();
        let Some(budget) = self.settings.memory_budget else {
            return SplitBudget {
                peak_before: now,
                ..SplitBudget::unlimited()
            };
        };
        let cost = (0..self.mesh.surfaces.len())
            .map(|s| {
                let values = directional.map_or(0, |d| d.vertex_values(s));
                split_cost(values, directional.is_some())
            })
            .collect();
        // The vertex table grows by doubling, all at once: plan as if this
        // refinement's vertices make it double (its new half, on top of the
        // per-vertex share each split is charged).
        let doubled = table_bytes(counts.vertices).max(table_bytes(4));
        SplitBudget {
            left: plan(budget).saturating_sub(now + doubled),
            cost,
            refused: 0,
            peak_before: now,
        }
    }

    /// After a refinement under `budget`: the warning, the first time splits
    /// were refused, and the peak estimate.
    pub(super) fn after_refinement(
        &mut self,
        budget: &SplitBudget,
        directional: Option<&Directional>,
    ) {
        let now = estimate(&self.memory_counts_with(directional)).peak();
        self.memory.peak_estimate = self.memory.peak_estimate.max(now).max(budget.peak_before);
        if budget.refused == 0 || self.memory.refinement_capped {
            return;
        }
        self.memory.refinement_capped = true;
        let warning = self.refinement_stop_warning(now);
        self.warnings.pending.push(warning);
    }

    /// When recording one more emitter shot (of `source_coefficients` SH
    /// values) would take the estimate past the plan: the warning that
    /// refinement stops. Recorded shots only serve refinement (their replay
    /// to new vertices), so a solve that can no longer refine stops recording
    /// and its state stops growing. `None` when it fits or has no budget.
    pub(super) fn recording_overflows(
        &self,
        directional: Option<&Directional>,
        source_coefficients: u64,
    ) -> Option<String> {
        let budget = self.settings.memory_budget?;
        let mut c = self.memory_counts_with(directional);
        c.recorded_shots += 1;
        if c.directional {
            c.recorded_coefficients += source_coefficients;
        }
        let peak = estimate(&c).peak();
        (peak > plan(budget)).then(|| self.refinement_stop_warning(peak))
    }

    /// The warning that the budget stopped refinement, at estimated peak `now`.
    fn refinement_stop_warning(&self, now: u64) -> String {
        let limit = self.settings.memory_budget.unwrap_or(0);
        format!(
            "memory budget {}: refinement stopped at {} elements and {} vertices (estimated \
             peak {}, planned against {:.0}% of the budget); further subdivision is refused, so \
             shadows and highlights finer than the current elements stay coarse. Raise \
             --memory-budget or use a coarser preset to refine further",
            human_bytes(limit as u128),
            self.stats.leaf_count,
            self.mesh.vertices.len(),
            human_bytes(now as u128),
            100.0 * PLANNING_FRACTION
        )
    }

    /// Warnings raised while solving (refinement stopped by the memory
    /// budget), each returned once; the command line prints them.
    pub fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings.pending)
    }
}

#[cfg(test)]
mod tests;
