//! Directional (glossy) radiosity on Immel, Cohen and Greenberg's (1986) global cubes
//! (`shared/seeds/001`): each glossy vertex stores its outgoing
//! radiance on the D = 6k² cell directions of a cube in its frame
//! ([`solution::cube`]), and the whole system is gathered by Gauss–Seidel sweeps
//! in light-propagation order — the documents' alternative to the thesis's
//! spherical harmonics shot progressively (design notes, "The other methods in
//! the documents").
//!
//! ## Discretization
//!
//! * The mesh is the progressive solver's patch mesh ([`Solver::new`], the
//!   `patches` setting), fixed: no adaptive subdivision. Unknowns are per mesh
//!   vertex: a diffuse surface's vertex (Ks = 0) has one RGB radiance (the
//!   scene needs no more), a glossy one H × 3 values, H the cube cells above its
//!   surface (local z > 0; the cells below stay 0 in the file).
//! * Sources are the patches. A patch's radiance toward a receiver is the
//!   area-weighted average of its vertices' radiance (the progressive solver's
//!   gather weights, [`Solver::patch_weights`]), each glossy vertex looked up
//!   bilinearly in its cube toward the direction from the patch's centre to the
//!   receiver (in the polygon's frame).
//! * Transport ([`transport`]): for receiver v and source s, the factor
//!   F(v←s) of the progressive solver (exact point-to-polygon factor × visible
//!   fraction of `samples` rays); a glossy receiver splats each visible
//!   sample's share onto the incoming cells of its own cube.
//! * Reflection (Immel, Cohen and Greenberg 1986, eq. 10's gather, with the thesis's BRDF, design notes
//!   "Directional mode"): with E_i = π Σ_s w_{v,s,i} L_s the irradiance
//!   arriving through incoming cell i,
//!
//!   L_v(ω_o) = Le_v + Kd/π · Σ_i E_i + Ks · Σ_i C(μ_i) g(ω_o · r_i) E_i,
//!
//!   for every upper cell o, the lobe g evaluated exactly at the cell
//!   directions ([`lobe`]; no Legendre truncation). A diffuse receiver gets
//!   L_v = Le_v + Kd · Σ_s F(v←s) L_s, the diffuse solvers' equation.
//!
//! ## Scope: untextured flat facets
//!
//! The global cube is a seed baseline, kept at the scope Immel, Cohen and
//! Greenberg (1986) measured: it refuses, before any work, a scene with a
//! texture (diffuse or emission) or a smooth surface whose shading normals
//! turn ([`check_scene`]); the progressive method solves both, in both modes.
//! Each cube is written in its polygon's frame ([`vertex_frame`]).
//!
//! ## Solution: Gauss–Seidel in light-propagation order
//!
//! Vertices are ordered as light spreads (Immel, Cohen and Greenberg 1986, Fig. 10): emitters' vertices,
//! then the vertices that gather from a patch of an already placed vertex, and
//! so on; vertices no light reaches come last. A sweep updates the vertices in
//! that order, in blocks of [`BLOCK`]: the vertices of a block are updated in
//! parallel (rayon) from the values of every earlier block of the sweep, then
//! written in order, so the result does not depend on the thread count.
//!
//! Convergence, two bounds, both reported:
//!
//! * ∞-norm: the update is linear in the values and every source lookup is a
//!   convex combination of them, so a sweep contracts the largest error by γ,
//!   the largest row sum of the reflection operator over all vertices,
//!   outgoing cells and channels — Kd · Σ_s F + Ks · Σ_i C_i g(ω_o·r_i) π
//!   Σ_s w_{v,s,i} — computed from the actual factors and cells before the
//!   first sweep ([`CubeResult::gamma`]). After a sweep that changed the values
//!   by Δ (∞-norm) the error is at most γ/(1 − γ) · Δ
//!   ([`CubeResult::error_bound`]). The thesis's normalization is not
//!   reciprocal, so a row (fixed outgoing cell, all incoming ones) can sum to
//!   more than Ks toward grazing; γ ≥ 1 is then reported with an infinite
//!   bound.
//! * power: each incident beam reflects at most Kd + Ks of its power
//!   ([`lobe`]'s normalization, in the cube's quadrature), so the power a sweep
//!   adds shrinks by ρ_max = the largest Kd + Ks (on a textured surface, Ks +
//!   the largest texel reflectance next to a vertex), and the power still missing
//!   after a sweep that added P is about ρ_max/(1 − ρ_max) · P
//!   ([`CubeResult::power_bound`], relative to the emitted power; "about"
//!   because the lookups' and the splats' discretization conserve power only
//!   to the cells' accuracy).
//!
//! The solve stops when a sweep changes no value by more than `tolerance` × the
//! largest value, or at `max_sweeps` (then the file is marked partial).
//!
//! ## Memory
//!
//! [`memory_estimate`] bounds the bytes before anything of that size is
//! allocated: values (f64: glossy vertices × H × 3 × 8, which is about
//! D × 3 × 4), each glossy material's H × H matrix (f64), and the transport
//! (every vertex × patch pair, plus for glossy receivers up to
//! min(4 × samples, H) incoming cells per pair); the solve is refused above
//! [`CubeLimits::max_bytes`] (default 2 GiB).

mod lobe;
mod transport;

pub use lobe::{CellBrdf, ExactLobe};

use super::{human_bytes, SolveError, Solver};
use crate::geometry::visibility::Occluder;
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::settings::SolverSettings;
use crate::solve::shoot::{SamplePool, Shot};
use glam::DVec3;
use rayon::prelude::*;
use solution::cube;
use solution::format::{Batch, Representation, ScalarType, Solution, SolveMode, Vertex};
use std::f64::consts::PI;
use std::time::Instant;
use transport::{PairInput, Receiver};

/// Vertices updated together (in parallel) within a Gauss–Seidel sweep.
pub const BLOCK: usize = 64;

/// Default memory bound: 2 GiB.
pub const DEFAULT_MAX_BYTES: u64 = 2 << 30;

/// Bounds on a global-cube solve.
#[derive(Clone, Debug, PartialEq)]
pub struct CubeLimits {
    /// Refuse a solve whose [`memory_estimate`] exceeds this.
    pub max_bytes: u64,
    pub max_sweeps: u32,
    /// Converged when a sweep changes no value by more than this fraction of
    /// the largest value.
    pub tolerance: f64,
}

impl Default for CubeLimits {
    fn default() -> Self {
        CubeLimits {
            max_bytes: DEFAULT_MAX_BYTES,
            max_sweeps: 1000,
            tolerance: 1e-6,
        }
    }
}

/// Why a global-cube solve cannot run.
#[derive(Debug, thiserror::Error)]
pub enum CubeError {
    #[error(transparent)]
    Solve(#[from] SolveError),
    #[error(
        "the global-cube solve needs `mode = directional` (it models glossy surfaces); \
         this solve is `{0:?}`"
    )]
    NotDirectional(SolveMode),
    #[error(
        "the global cube at k = {k} (D = {directions} directions) needs about {bytes} bytes \
         ({}) for {vertices} vertices ({glossy} glossy) and {patches} patches, above the limit \
         of {limit} bytes ({}); use a smaller --cube-resolution, a larger --patch-size, fewer --samples, \
         or --method progressive",
        human_bytes(*bytes),
        human_bytes(*limit as u128)
    )]
    TooLarge {
        k: u32,
        directions: u64,
        vertices: u64,
        glossy: u64,
        patches: u64,
        bytes: u128,
        limit: u64,
    },
    #[error("could not allocate {bytes} bytes for the global-cube solve: out of memory")]
    OutOfMemory { bytes: u128 },
    #[error("tolerance {0} is out of range: 0 < tolerance < 1")]
    BadTolerance(f64),
    #[error(
        "--method cube solves untextured scenes, the scope of Immel, Cohen and Greenberg \
         (1986): material `{material}` has {what} on {item}; use --method progressive"
    )]
    Textured {
        material: String,
        what: &'static str,
        item: String,
    },
    #[error(
        "--method cube solves flat facets, the scope of Immel, Cohen and Greenberg (1986): \
         {item} is part of a smooth surface (its shading normals turn across it); use \
         --method progressive, or --crease-angle 0 to keep every polygon a flat facet"
    )]
    Smooth { item: String },
}

/// The cells of a cube of resolution k above a surface (local z > 0), with
/// their directions and the map from cell index to slot.
#[derive(Clone, Debug)]
pub struct UpperCells {
    pub k: u32,
    /// Cell index of each slot.
    pub cells: Vec<u32>,
    /// Unit local direction of each slot.
    pub directions: Vec<DVec3>,
    /// Exact solid angle of each slot's cell (sr).
    pub solid_angles: Vec<f64>,
    /// Slot of each cell (`u32::MAX` below the horizon).
    slot: Vec<u32>,
}

impl UpperCells {
    pub fn new(k: u32) -> UpperCells {
        let d = cube::direction_count(k) as u32;
        let mut cells = Vec::new();
        let mut directions = Vec::new();
        let mut solid_angles = Vec::new();
        let mut slot = vec![u32::MAX; d as usize];
        for i in 0..d {
            let dir = cube::cell_direction(k, i);
            if dir.z > 0.0 {
                slot[i as usize] = cells.len() as u32;
                cells.push(i);
                directions.push(dir);
                solid_angles.push(cube::cell_solid_angle(k, i));
            }
        }
        UpperCells {
            k,
            cells,
            directions,
            solid_angles,
            slot,
        }
    }

    /// H, the number of upper cells: 3k² for even k (the +z face and half of
    /// each side face), 3k² − 2k for odd k (the side faces' middle rows lie on
    /// the horizon).
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// The bilinear taps of [`cube::bilinear`] toward `dir` as (slot, weight),
    /// restricted to upper cells and renormalized to sum to 1; `None` when no
    /// upper cell has weight (a direction on or below the horizon). Moving a
    /// near-horizon tap's weight up is a direction error below one cell.
    pub fn taps(&self, dir: DVec3) -> Option<[(u32, f64); 4]> {
        let mut out = [(0u32, 0.0); 4];
        let mut total = 0.0;
        for (o, (cell, w)) in out.iter_mut().zip(cube::bilinear(self.k, dir)) {
            let s = self.slot[cell as usize];
            if s != u32::MAX && w > 0.0 {
                *o = (s, w);
                total += w;
            }
        }
        if total > 0.0 {
            for o in &mut out {
                o.1 /= total;
            }
            Some(out)
        } else {
            None
        }
    }
}

/// The bytes a solve of these counts needs (see the module documentation).
pub fn memory_estimate(
    k: u32,
    vertices: u64,
    glossy_vertices: u64,
    patches: u64,
    glossy_materials: u64,
    samples: u32,
) -> u128 {
    let h = UpperCells::new(k.clamp(1, 256)).len() as u128;
    let values = glossy_vertices as u128 * h * 24 + (vertices - glossy_vertices) as u128 * 24;
    let matrices = glossy_materials as u128 * h * h * 8;
    let pair = std::mem::size_of::<transport::Pair>() as u128;
    let pairs = vertices as u128 * patches as u128 * pair;
    let per_pair = (4 * samples as u128).min(h);
    let entries = glossy_vertices as u128 * patches as u128 * per_pair * 16;
    values + matrices + pairs + entries
}

/// A finished global-cube solve.
#[derive(Clone, Debug)]
pub struct CubeResult {
    /// Diffuse vertices as an order-0 SH batch, glossy ones as a
    /// `Cube { directions: 6k² }` batch; header as [`Solver::to_solution`]'s
    /// with `mode` directional, `stats.shots` = sweeps, and the cube's figures
    /// in `settings_json` under `"cube"`.
    pub solution: Solution,
    pub k: u32,
    /// Patches of the (fixed) mesh: the sources.
    pub patches: usize,
    /// Per mesh vertex: its values (H × 3 for glossy vertices, slot-major then
    /// RGB; 3 for diffuse ones).
    values: Vec<Vec<f64>>,
    /// Per mesh vertex: its frame (n, t).
    frames: Vec<(DVec3, DVec3)>,
    cells: UpperCells,
    /// Per mesh vertex: the receiving point the factors were computed at
    /// (re-centred coordinates) — the solver's `offset` was subtracted.
    pub receiving_points: Vec<DVec3>,
    /// The offset subtracted from scene coordinates.
    pub offset: DVec3,
    /// Per mesh vertex: the area it represents (a third of each display
    /// triangle it is a corner of), for power sums.
    pub vertex_areas: Vec<f64>,
    pub sweeps: u32,
    pub change: f64,
    pub gamma: f64,
    pub error_bound: f64,
    /// ρ_max/(1 − ρ_max) × (power the last sweep added / emitted power).
    pub power_bound: f64,
    /// The power the sources emit, W: Σ_p π A_p Σ_rgb Le_p.
    pub emitted_power: f64,
    pub converged: bool,
    pub rays: u64,
    pub form_factor_seconds: f64,
    pub solve_seconds: f64,
    /// [`memory_estimate`] of this solve.
    pub memory_bytes: u64,
}

impl CubeResult {
    /// Outgoing radiance (RGB) of mesh vertex `v` toward the world direction
    /// `dir`: bilinear in its cube for a glossy vertex (0 below its surface),
    /// its one value for a diffuse vertex.
    pub fn radiance_toward(&self, v: u32, dir: DVec3) -> DVec3 {
        let values = &self.values[v as usize];
        if values.len() == 3 {
            return DVec3::from_slice(values);
        }
        let (n, t) = self.frames[v as usize];
        let local = solution::sh::to_local(dir.normalize_or_zero(), n, t);
        let mut sum = DVec3::ZERO;
        for (cell, w) in cube::bilinear(self.k, local) {
            let s = self.cells.slot[cell as usize];
            if s != u32::MAX {
                sum += DVec3::from_slice(&values[3 * s as usize..3 * s as usize + 3]) * w;
            }
        }
        sum
    }

    /// Whether mesh vertex `v` is stored as a cube (its surface is glossy).
    pub fn is_glossy(&self, v: u32) -> bool {
        self.values[v as usize].len() != 3
    }

    /// Vertices in mesh order.
    pub fn vertex_count(&self) -> usize {
        self.values.len()
    }
}

/// Per surface: diffuse reflectance, glossy reflectance, emission and the
/// index of its material's cell BRDF (None for Ks = 0).
struct SurfaceData {
    kd: DVec3,
    ks: DVec3,
    emission: DVec3,
    brdf: Option<usize>,
}

/// Solves `scene` on global cubes of `settings.cube_resolution` (see the module
/// documentation). Uses `patches`, `samples`, `seed`, `form_factors`,
/// and `shadows`; `mode` must be directional.
///
/// Stages: check the inputs; mesh the scene (the progressive solver's mesh,
/// gather weights and scene checks; its diffuse state is not used); per-surface
/// materials; the memory check; cell BRDFs; transport (every source's pairs);
/// Gauss–Seidel sweeps; error bounds; the solution file's batches and header.
pub fn solve_cube(
    scene: &Scene,
    settings: &SolverSettings,
    limits: &CubeLimits,
) -> Result<CubeResult, CubeError> {
    check_inputs(settings, limits)?;
    check_scene(scene)?;
    let k = settings.cube_resolution;
    // The patches and the diffuse transport are the progressive solver's.
    let mut base = settings.clone();
    base.mode = SolveMode::Diffuse;
    base.method = crate::method::Method::Progressive;
    base.adaptive = false;
    let solver = Solver::new(scene, &base)?;
    let mesh = solver.mesh();
    let (surfaces, glossy_alphas) = surface_materials(scene, mesh)?;
    let materials = (&surfaces[..], glossy_alphas.len());
    let bytes = check_memory(k, mesh, materials, settings, limits)?;
    let cells = UpperCells::new(k);
    let brdfs = cell_brdfs(&glossy_alphas, &cells, bytes)?;
    let start = Instant::now();
    let occluder = mesh_occluder(mesh);
    let kd: Vec<DVec3> = surfaces.iter().map(|s| s.kd).collect();
    let frames = vertex_frames(mesh);
    let transport = transport_pairs(mesh, settings, &surfaces, &cells, &occluder, &kd, &frames);
    let receivers = transport.receivers;
    let form_factor_seconds = start.elapsed().as_secs_f64();
    let receiving_points = receiving_points(mesh, settings, &occluder, &kd);

    let start = Instant::now();
    let state = State {
        surfaces: &surfaces,
        brdfs: &brdfs,
        receivers: &receivers,
        solver: &solver,
        cells: &cells,
        weights: normalized_patch_weights(&solver),
    };
    let sweep = run_sweeps(&state, mesh, limits);
    let bounds = Bounds::new(&state, &sweep);
    let solve_seconds = start.elapsed().as_secs_f64();
    let rays: u64 = receivers.iter().map(|r| r.rays).sum();

    let mut solution = solver.to_solution(false);
    let layout = BatchLayout {
        frames: &frames,
        cells: &cells,
        k,
    };
    fill_batches(&solver, &sweep.values, &layout, &mut solution);
    let report = CubeReport {
        settings,
        limits,
        k,
        upper_cells: cells.len(),
        bytes,
        sweep: &sweep,
        bounds: &bounds,
        rays,
        seconds: form_factor_seconds + solve_seconds,
    };
    report.write_header(&mut solution);
    let converged = sweep.converged(limits);
    Ok(CubeResult {
        solution,
        k,
        patches: mesh.patches.len(),
        values: sweep.values,
        frames,
        cells,
        receiving_points,
        offset: solver.offset(),
        vertex_areas: sweep.area,
        sweeps: sweep.sweeps,
        change: sweep.change,
        gamma: bounds.gamma,
        error_bound: bounds.error_bound,
        power_bound: bounds.power_bound,
        emitted_power: sweep.emitted,
        converged,
        rays,
        form_factor_seconds,
        solve_seconds,
        memory_bytes: bytes.min(u64::MAX as u128) as u64,
    })
}

/// The occluder of the mesh's surfaces (the input polygons).
fn mesh_occluder(mesh: &Mesh) -> Occluder {
    Occluder::new(
        &mesh
            .surfaces
            .iter()
            .map(|s| s.vertices.as_slice())
            .collect::<Vec<_>>(),
    )
}

/// Each vertex's cube frame (n, t): [`vertex_frame`].
fn vertex_frames(mesh: &Mesh) -> Vec<(DVec3, DVec3)> {
    (0..mesh.vertices.len())
        .map(|v| vertex_frame(mesh, v))
        .collect()
}

/// The frame vertex `v`'s cube is written in: its polygon's (n, t) (the
/// method refuses smooth surfaces, [`check_scene`]).
pub(super) fn vertex_frame(mesh: &Mesh, v: usize) -> (DVec3, DVec3) {
    let s = &mesh.surfaces[mesh.vertices[v].surface as usize];
    (s.normal, s.tangent)
}

/// Each vertex's receiving point, which depends only on the vertex and the
/// occluder's ε (so any shot gives it).
fn receiving_points(
    mesh: &Mesh,
    settings: &SolverSettings,
    occluder: &Occluder,
    kd: &[DVec3],
) -> Vec<DVec3> {
    let any_shot = Shot::for_patch(mesh, 0, 0, DVec3::ONE, settings, occluder, kd);
    (0..mesh.vertices.len() as u32)
        .map(|v| any_shot.receiving_point(mesh, v).0)
        .collect()
}

/// Settings in range, directional mode, a usable tolerance.
/// Refuses what the global cube does not model, before any work: a texture
/// (diffuse or emission) on a polygon with UVs, and a smooth surface whose
/// shading normals turn (more than 1.4e-6 rad from the facet's normal: a
/// coplanar smooth group's interpolated normals are the facet's to rounding).
/// The progressive method solves both.
fn check_scene(scene: &Scene) -> Result<(), CubeError> {
    if !scene.lights.is_empty() {
        return Err(SolveError::LightsNeedProgressive("cube").into());
    }
    for p in &scene.polygons {
        let m = &scene.materials[p.material];
        if p.uv_map.is_some() {
            let what = if m.diffuse_texture.is_some() {
                Some("a diffuse texture")
            } else if m.emission_texture.is_some() {
                Some("an emission texture")
            } else {
                None
            };
            if let Some(what) = what {
                return Err(CubeError::Textured {
                    material: m.name.clone(),
                    what,
                    item: p.source.to_string(),
                });
            }
        }
        if let Some(normals) = &p.vertex_normals {
            let facet = crate::geometry::polygon::newell_normal(&p.vertices).normalize_or_zero();
            if normals
                .iter()
                .any(|n| n.normalize_or_zero().angle_between(facet) > 1.4e-6)
            {
                return Err(CubeError::Smooth {
                    item: p.source.to_string(),
                });
            }
        }
    }
    Ok(())
}

fn check_inputs(settings: &SolverSettings, limits: &CubeLimits) -> Result<(), CubeError> {
    settings.validate().map_err(SolveError::from)?;
    if settings.mode != SolveMode::Directional {
        return Err(CubeError::NotDirectional(settings.mode));
    }
    if !(limits.tolerance > 0.0 && limits.tolerance < 1.0) {
        return Err(CubeError::BadTolerance(limits.tolerance));
    }
    Ok(())
}

/// Per surface its material's reflectances and emission; glossy materials that
/// a surface uses get an index into the returned α list (their cell BRDFs are
/// built after the memory check).
fn surface_materials(
    scene: &Scene,
    mesh: &Mesh,
) -> Result<(Vec<SurfaceData>, Vec<f64>), CubeError> {
    let mut material_brdf: Vec<Option<usize>> = vec![None; scene.materials.len()];
    let mut glossy_alphas: Vec<f64> = Vec::new();
    let mut used = vec![false; scene.materials.len()];
    for s in &mesh.surfaces {
        used[s.material] = true;
    }
    for (i, m) in scene.materials.iter().enumerate() {
        let ok = m.ks.is_finite() && m.ks.min_element() >= 0.0 && m.ks.max_element() <= 1.0;
        if !ok {
            return Err(SolveError::BadMaterial {
                name: m.name.clone(),
                problem: format!("Ks {:?} must be in [0, 1]", m.ks.to_array()),
            }
            .into());
        }
        if used[i] && m.is_glossy() {
            let alpha =
                crate::brdf::validate_alpha(m.alpha).map_err(|e| SolveError::BadMaterial {
                    name: m.name.clone(),
                    problem: e.to_string(),
                })?;
            material_brdf[i] = Some(glossy_alphas.len());
            glossy_alphas.push(alpha);
        }
    }
    let surfaces = mesh
        .surfaces
        .iter()
        .map(|s| {
            let m = &scene.materials[s.material];
            SurfaceData {
                kd: m.kd,
                ks: m.ks,
                emission: m.emission,
                brdf: material_brdf[s.material],
            }
        })
        .collect();
    Ok((surfaces, glossy_alphas))
}

/// Whether vertex `v` lies on a glossy surface (and so stores a cube).
fn is_glossy(mesh: &Mesh, surfaces: &[SurfaceData], v: usize) -> bool {
    surfaces[mesh.vertices[v].surface as usize].brdf.is_some()
}

/// The [`memory_estimate`] of this solve, refused above `limits.max_bytes`
/// before anything of that size is allocated.
/// `textured_bytes` is what the textured surfaces add
/// ([`CubeTexturing::bytes`]).
fn check_memory(
    k: u32,
    mesh: &Mesh,
    (surfaces, glossy_materials): (&[SurfaceData], usize),
    settings: &SolverSettings,
    limits: &CubeLimits,
) -> Result<u128, CubeError> {
    let n = mesh.vertices.len();
    let glossy_count = (0..n).filter(|&v| is_glossy(mesh, surfaces, v)).count();
    let bytes = memory_estimate(
        k,
        n as u64,
        glossy_count as u64,
        mesh.patches.len() as u64,
        glossy_materials as u64,
        settings.samples,
    );
    if bytes > limits.max_bytes as u128 {
        return Err(CubeError::TooLarge {
            k,
            directions: cube::direction_count(k),
            vertices: n as u64,
            glossy: glossy_count as u64,
            patches: mesh.patches.len() as u64,
            bytes,
            limit: limits.max_bytes,
        });
    }
    Ok(bytes)
}

/// One cell BRDF per glossy material, built in parallel.
fn cell_brdfs(
    glossy_alphas: &[f64],
    cells: &UpperCells,
    bytes: u128,
) -> Result<Vec<CellBrdf>, CubeError> {
    let mut brdfs: Vec<CellBrdf> = Vec::new();
    brdfs
        .try_reserve_exact(glossy_alphas.len())
        .map_err(|_| CubeError::OutOfMemory { bytes })?;
    brdfs.extend(
        glossy_alphas
            .par_iter()
            .map(|&a| CellBrdf::new(a, &cells.directions, &cells.solid_angles))
            .collect::<Vec<_>>(),
    );
    Ok(brdfs)
}

/// What the transport leaves: every receiver's pairs.
struct Transport {
    receivers: Vec<Receiver>,
}

/// Transport, source by source (one sample pool alive at a time), each source's
/// receivers in parallel; pairs are appended in source order. `frames` are
/// the receivers' cube frames ([`vertex_frame`]).
fn transport_pairs(
    mesh: &Mesh,
    settings: &SolverSettings,
    surfaces: &[SurfaceData],
    cells: &UpperCells,
    occluder: &Occluder,
    kd: &[DVec3],
    frames: &[(DVec3, DVec3)],
) -> Transport {
    let n = mesh.vertices.len();
    let mut receivers: Vec<Receiver> = vec![Receiver::default(); n];
    for source in 0..mesh.patches.len() as u32 {
        let shot = Shot::for_patch(
            mesh,
            source,
            source as u64,
            DVec3::ONE,
            settings,
            occluder,
            kd,
        );
        let pool = SamplePool::new(&shot);
        let source_glossy = surfaces[shot.source_surface as usize].brdf.is_some();
        let results: Vec<_> = (0..n as u32)
            .into_par_iter()
            .map_init(transport::Scratch::default, |scratch, v| {
                PairInput {
                    mesh,
                    shot: &shot,
                    pool: &pool,
                    receiver_cells: is_glossy(mesh, surfaces, v as usize).then_some(cells),
                    receiver_frame: frames[v as usize],
                    source_cells: source_glossy.then_some(cells),
                }
                .pair(v, source, scratch)
            })
            .collect();
        for (receiver, result) in receivers.iter_mut().zip(results) {
            if let Some((mut pair, entries, rays)) = result {
                receiver.entries.extend(entries);
                pair.entries_end = receiver.entries.len() as u32;
                receiver.pairs.push(pair);
                receiver.rays += rays as u64;
            }
        }
    }
    Transport { receivers }
}

/// Each patch's gather weights, normalized to sum to 1 (empty for a patch with
/// no weight).
fn normalized_patch_weights(solver: &Solver) -> Vec<Vec<(u32, f64)>> {
    (0..solver.mesh().patches.len() as u32)
        .map(|p| {
            let w = solver.patch_weights(p);
            let total: f64 = w.iter().map(|e| e.1).sum();
            if total > 0.0 {
                w.iter().map(|&(v, a)| (v, a / total)).collect()
            } else {
                Vec::new()
            }
        })
        .collect()
}

/// What the Gauss–Seidel sweeps leave.
struct SweepOutcome {
    /// Per vertex: RGB (diffuse) or RGB per upper cell (glossy).
    values: Vec<Vec<f64>>,
    /// Per vertex: the area it represents (its gather weights summed over its
    /// patches).
    area: Vec<f64>,
    sweeps: u32,
    /// The last sweep's largest change relative to the largest value.
    change: f64,
    /// The power the last sweep added, W.
    added_power: f64,
    /// Total emitted power, W.
    emitted: f64,
}

impl SweepOutcome {
    fn converged(&self, limits: &CubeLimits) -> bool {
        self.change < limits.tolerance
    }
}

/// Sweeps in light-propagation order, blocks of vertices in parallel, until the
/// largest relative change is below the tolerance or the sweep limit is reached.
fn run_sweeps(state: &State<'_>, mesh: &Mesh, limits: &CubeLimits) -> SweepOutcome {
    let n = mesh.vertices.len();
    let h = state.cells.len();
    let surfaces = state.surfaces;
    // Emitted radiance.
    let mut values: Vec<Vec<f64>> = (0..n)
        .map(|v| {
            let e = surfaces[mesh.vertices[v].surface as usize].emission;
            if is_glossy(mesh, surfaces, v) {
                e.to_array().repeat(h)
            } else {
                e.to_array().to_vec()
            }
        })
        .collect();
    let order = state.propagation_order();
    // Per value, the weight that turns radiance into exitance (π for a diffuse
    // vertex; cosθ_o × the cell's solid angle in a cube).
    let mut area = vec![0.0; n];
    for p in 0..mesh.patches.len() as u32 {
        for &(v, w) in state.solver.patch_weights(p) {
            area[v as usize] += w;
        }
    }
    let exitance_weight: Vec<f64> = state
        .cells
        .solid_angles
        .iter()
        .zip(&state.cells.directions)
        .map(|(&solid, d)| d.z * solid)
        .collect();
    let emitted: f64 = mesh
        .patches
        .iter()
        .map(|p| PI * p.area * surfaces[p.surface as usize].emission.element_sum())
        .sum();
    let mut sweeps = 0;
    let mut change = f64::INFINITY;
    let mut added_power = 0.0;
    while sweeps < limits.max_sweeps {
        sweeps += 1;
        let mut largest: f64 = 0.0;
        added_power = 0.0;
        for block in order.chunks(BLOCK) {
            let updated: Vec<Vec<f64>> = block
                .par_iter()
                .map_init(Vec::new, |scratch, &v| state.update(v, &values, scratch))
                .collect();
            for (&v, new) in block.iter().zip(updated) {
                let old = &values[v as usize];
                let mut power = 0.0;
                for (c, (a, b)) in new.iter().zip(old).enumerate() {
                    let d = (a - b).abs();
                    largest = largest.max(d);
                    power += d * if new.len() == 3 {
                        PI
                    } else {
                        exitance_weight[c / 3]
                    };
                }
                added_power += power * area[v as usize];
                values[v as usize] = new;
            }
        }
        let scale = values
            .iter()
            .map(|x| x.iter().fold(0.0f64, |m, &x| m.max(x.abs())))
            .fold(0.0f64, f64::max);
        change = if scale > 0.0 { largest / scale } else { 0.0 };
        if change < limits.tolerance {
            break;
        }
    }
    SweepOutcome {
        values,
        area,
        sweeps,
        change,
        added_power,
        emitted,
    }
}

/// Error bounds of the result (see the module documentation).
struct Bounds {
    /// The largest row sum of the iteration (a contraction factor when < 1).
    gamma: f64,
    /// γ / (1 − γ) × the last change, relative to the largest value.
    error_bound: f64,
    /// ρ_max / (1 − ρ_max) × the last sweep's added power over the emitted power.
    power_bound: f64,
}

impl Bounds {
    fn new(state: &State<'_>, sweep: &SweepOutcome) -> Bounds {
        let n = sweep.values.len();
        let gamma = (0..n)
            .into_par_iter()
            .map(|v| state.row_sum(v as u32))
            .reduce(|| 0.0, f64::max);
        let error_bound = if gamma < 1.0 {
            gamma / (1.0 - gamma) * sweep.change
        } else {
            f64::INFINITY
        };
        // The largest reflectance of any beam: Kd + Ks.
        let rho_max = (0..n as u32)
            .map(|v| {
                let s = state.surface_of(v);
                (s.kd + s.ks).max_element()
            })
            .fold(0.0, f64::max);
        let power_bound = if rho_max < 1.0 && sweep.emitted > 0.0 {
            rho_max / (1.0 - rho_max) * sweep.added_power / sweep.emitted
        } else {
            f64::INFINITY
        };
        Bounds {
            gamma,
            error_bound,
            power_bound,
        }
    }
}

/// What the solution header records about a cube solve.
struct CubeReport<'a> {
    settings: &'a SolverSettings,
    limits: &'a CubeLimits,
    k: u32,
    upper_cells: usize,
    bytes: u128,
    sweep: &'a SweepOutcome,
    bounds: &'a Bounds,
    rays: u64,
    seconds: f64,
}

impl CubeReport<'_> {
    /// Mode, partial flag, statistics and the settings JSON with the cube's
    /// figures.
    fn write_header(&self, solution: &mut Solution) {
        let (sweep, bounds) = (self.sweep, self.bounds);
        let header = &mut solution.header;
        header.mode = SolveMode::Directional;
        header.partial = !sweep.converged(self.limits);
        header.stats.shots = sweep.sweeps as u64;
        header.stats.rays = self.rays;
        header.stats.seconds = self.seconds;
        // As the Gauss–Seidel solver reports it: the power the last sweep still
        // added, over the emitted power.
        header.stats.unshot_fraction = if sweep.emitted > 0.0 {
            sweep.added_power / sweep.emitted
        } else {
            0.0
        };
        header.stats.ambient = [0.0; 3];
        if let Ok(serde_json::Value::Object(mut map)) = serde_json::to_value(self.settings) {
            map.insert("solver".into(), "gauss-seidel".into());
            map.insert(
                "cube".into(),
                serde_json::json!({
                    "k": self.k,
                    "directions": cube::direction_count(self.k),
                    "upper_cells": self.upper_cells,
                    "max_bytes": self.limits.max_bytes,
                    "memory_estimate": self.bytes as u64,
                    "max_sweeps": self.limits.max_sweeps,
                    "tolerance": self.limits.tolerance,
                    "sweeps": sweep.sweeps,
                    "change": sweep.change,
                    "gamma": bounds.gamma,
                    "error_bound": bounds.error_bound,
                    "power_bound": bounds.power_bound,
                }),
            );
            header.settings_json = serde_json::Value::Object(map).to_string();
        }
    }
}

/// What a sweep reads.
struct State<'a> {
    surfaces: &'a [SurfaceData],
    brdfs: &'a [CellBrdf],
    receivers: &'a [Receiver],
    solver: &'a Solver,
    cells: &'a UpperCells,
    /// Per patch: (vertex, weight) with weights summing to 1.
    weights: Vec<Vec<(u32, f64)>>,
}

impl State<'_> {
    fn surface_of(&self, v: u32) -> &SurfaceData {
        &self.surfaces[self.solver.mesh().vertices[v as usize].surface as usize]
    }

    /// Radiance of source patch `p` toward the receiver of `pair`: the
    /// weighted average of its vertices', each glossy one looked up at the
    /// pair's taps.
    fn source_radiance(&self, values: &[Vec<f64>], pair: &transport::Pair) -> DVec3 {
        let mut sum = DVec3::ZERO;
        for &(u, w) in &self.weights[pair.source as usize] {
            let x = &values[u as usize];
            if x.len() == 3 {
                sum += DVec3::from_slice(x) * w;
            } else {
                for &(slot, t) in &pair.taps {
                    if t > 0.0 {
                        let o = 3 * slot as usize;
                        sum += DVec3::from_slice(&x[o..o + 3]) * (w * t as f64);
                    }
                }
            }
        }
        sum
    }

    /// The new values of vertex `v` from the current `values`.
    fn update(&self, v: u32, values: &[Vec<f64>], incoming: &mut Vec<f64>) -> Vec<f64> {
        let s = self.surface_of(v);
        let receiver = &self.receivers[v as usize];
        let Some(b) = s.brdf else {
            // Diffuse: L = Le + Kd Σ_s F(v←s) L_s (the diffuse solvers' equation).
            let mut gathered = DVec3::ZERO;
            for pair in &receiver.pairs {
                gathered += self.source_radiance(values, pair) * pair.factor;
            }
            return (s.emission + s.kd * gathered).to_array().to_vec();
        };
        let h = self.cells.len();
        incoming.clear();
        incoming.resize(3 * h, 0.0);
        let mut irradiance = DVec3::ZERO;
        let mut start = 0;
        for pair in &receiver.pairs {
            let e = self.source_radiance(values, pair) * PI;
            irradiance += e * pair.factor;
            for &(slot, w) in &receiver.entries[start..pair.entries_end as usize] {
                let o = 3 * slot as usize;
                incoming[o] += e.x * w;
                incoming[o + 1] += e.y * w;
                incoming[o + 2] += e.z * w;
            }
            start = pair.entries_end as usize;
        }
        // Emission and the diffuse part are the same in every upper cell.
        let base = s.emission + s.kd * irradiance / PI;
        let mut out = base.to_array().repeat(h);
        let matrix = &self.brdfs[b].matrix;
        for (i, e) in incoming.chunks_exact(3).enumerate() {
            if e[0] == 0.0 && e[1] == 0.0 && e[2] == 0.0 {
                continue;
            }
            let e = DVec3::from_slice(e) * s.ks;
            for (o, &f) in out.chunks_exact_mut(3).zip(&matrix[i * h..(i + 1) * h]) {
                o[0] += f * e.x;
                o[1] += f * e.y;
                o[2] += f * e.z;
            }
        }
        out
    }

    /// The largest row sum of vertex `v`'s reflection operator (see the module
    /// documentation's convergence paragraph).
    fn row_sum(&self, v: u32) -> f64 {
        let s = self.surface_of(v);
        let receiver = &self.receivers[v as usize];
        let total: f64 = receiver.pairs.iter().map(|p| p.factor).sum();
        let diffuse = s.kd * total;
        let Some(b) = s.brdf else {
            return diffuse.max_element().max(0.0);
        };
        let h = self.cells.len();
        let mut weight = vec![0.0; h];
        let mut start = 0;
        for pair in &receiver.pairs {
            let end = pair.entries_end as usize;
            for &(slot, w) in &receiver.entries[start..end] {
                weight[slot as usize] += PI * w;
            }
            start = end;
        }
        let matrix = &self.brdfs[b].matrix;
        let mut rows = vec![0.0; h];
        for (i, &w) in weight.iter().enumerate() {
            if w > 0.0 {
                for (r, &f) in rows.iter_mut().zip(&matrix[i * h..(i + 1) * h]) {
                    *r += f * w;
                }
            }
        }
        let glossy = rows.iter().copied().fold(0.0, f64::max);
        (diffuse + s.ks * glossy).max_element().max(0.0)
    }

    /// Immel, Cohen and Greenberg 1986, Fig. 10: emitters' vertices first, then the vertices that gather
    /// from a patch holding an already placed vertex, and so on; vertices no
    /// light reaches last, each group in index order.
    fn propagation_order(&self) -> Vec<u32> {
        let mesh = self.solver.mesh();
        let n = mesh.vertices.len();
        let p = mesh.patches.len();
        // Patches of each vertex, and receivers of each patch.
        let mut vertex_patches: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (patch, w) in self.weights.iter().enumerate() {
            for &(v, _) in w {
                vertex_patches[v as usize].push(patch as u32);
            }
        }
        let mut patch_receivers: Vec<Vec<u32>> = vec![Vec::new(); p];
        for (v, r) in self.receivers.iter().enumerate() {
            for pair in &r.pairs {
                patch_receivers[pair.source as usize].push(v as u32);
            }
        }
        let mut placed = vec![false; n];
        let mut lit = vec![false; p];
        let mut order: Vec<u32> = Vec::with_capacity(n);
        for v in 0..n as u32 {
            if self.surface_of(v).emission.max_element() > 0.0 {
                placed[v as usize] = true;
                order.push(v);
            }
        }
        let mut next = 0;
        while next < order.len() {
            let u = order[next];
            next += 1;
            for &patch in &vertex_patches[u as usize] {
                if std::mem::replace(&mut lit[patch as usize], true) {
                    continue;
                }
                for &v in &patch_receivers[patch as usize] {
                    if !std::mem::replace(&mut placed[v as usize], true) {
                        order.push(v);
                    }
                }
            }
        }
        order.extend((0..n as u32).filter(|&v| !placed[v as usize]));
        order
    }
}

/// What [`fill_batches`] writes the values with.
struct BatchLayout<'a> {
    /// Per vertex, its cube's frame.
    frames: &'a [(DVec3, DVec3)],
    cells: &'a UpperCells,
    k: u32,
}

/// Replaces `solution`'s order-0 batch by a diffuse batch (order-0 SH,
/// c₀₀ = L·√(4π)) and a cube batch of the glossy vertices (D × 3 values, 0
/// below the surface), each with the display triangles of its vertices, and
/// no textures.
fn fill_batches(
    solver: &Solver,
    values: &[Vec<f64>],
    layout: &BatchLayout<'_>,
    solution: &mut Solution,
) {
    let BatchLayout { frames, cells, k } = *layout;
    let mesh = solver.mesh();
    let d = cube::direction_count(k) as usize;
    let scale = (4.0 * PI).sqrt();
    let mut diffuse = Batch {
        representation: Representation::Sh { order: 0 },
        scalar: ScalarType::F32,
        vertices: Vec::new(),
        coefficients: Vec::new(),
        indices: Vec::new(),
        texturing: None,
    };
    let mut glossy = Batch {
        representation: Representation::Cube {
            directions: d as u32,
        },
        ..diffuse.clone()
    };
    let mut local = vec![(false, 0u32); mesh.vertices.len()];
    for (v, mv) in mesh.vertices.iter().enumerate() {
        let x = &values[v];
        // A cube is read in its own frame; a diffuse vertex keeps its polygon's.
        let (normal, tangent) = if x.len() == 3 {
            let s = &mesh.surfaces[mv.surface as usize];
            (s.normal, s.tangent)
        } else {
            frames[v]
        };
        let f = |x: DVec3| x.as_vec3().to_array();
        let vertex = Vertex {
            position: f(mv.position),
            normal: f(normal),
            tangent: f(tangent),
        };
        if x.len() == 3 {
            local[v] = (false, diffuse.vertices.len() as u32);
            diffuse.vertices.push(vertex);
            let l = DVec3::from_slice(x);
            diffuse
                .coefficients
                .extend(l.to_array().map(|l| (l * scale) as f32));
        } else {
            local[v] = (true, glossy.vertices.len() as u32);
            glossy.vertices.push(vertex);
            let start = glossy.coefficients.len();
            glossy.coefficients.resize(start + 3 * d, 0.0);
            for (slot, &cell) in cells.cells.iter().enumerate() {
                for c in 0..3 {
                    glossy.coefficients[start + 3 * cell as usize + c] = x[3 * slot + c] as f32;
                }
            }
        }
    }
    for t in mesh.triangles() {
        let (is_glossy, _) = local[t[0] as usize];
        let batch = if is_glossy { &mut glossy } else { &mut diffuse };
        batch.indices.extend(t.iter().map(|&v| local[v as usize].1));
    }
    solution.batches = [diffuse, glossy]
        .into_iter()
        .filter(|b| !b.vertices.is_empty())
        .collect();
    // No batch here is textured (the method refuses textured scenes).
    solution.textures.clear();
}

#[cfg(test)]
mod tests;
