//! Full-matrix gathering radiosity solved by Gauss–Seidel (radiosity lecture notes, "Radiosity"
//! and "The Hemicube method"; Immel, Cohen and Greenberg 1986, "Global solution"): the seeds' own
//! alternative to progressive refinement, kept as a baseline to measure it
//! against (design notes, "The other methods in the documents").
//!
//! ## Method
//!
//! 1. The scene is meshed into patches exactly as the progressive solver does
//!    (it *is* the progressive solver's mesh: [`Solver::new`] validates the
//!    scene and settings and builds it), without adaptive subdivision.
//! 2. Row i of the form-factor matrix comes from a hemicube on the *receiving*
//!    patch i (radiosity lecture notes: gathering), at its centre, over every patch as a target:
//!    F_ij = Σ of the delta form factors of the cells where patch j is the
//!    nearest surface ([`crate::geometry::hemicube`]). Each hemicube is rotated
//!    about its normal by the golden angle times the patch index, so the O(h)
//!    bias of cell edges lined up with a box room's walls becomes noise that
//!    averages out over patches (see the hemicube module's accuracy notes).
//!    This is the centre-point approximation of the radiosity lecture notes ("we can consider the terms
//!    in the integral to be constant over A_i"); Immel, Cohen and Greenberg's (1986) averaging over several
//!    points of the patch is not done.
//! 3. The matrix equation B_i = E_i + ρ_i Σ_j F_ij B_j (radiosity lecture notes) is solved by
//!    Gauss–Seidel (Immel, Cohen and Greenberg 1986): start from B = E, update each patch in turn with the
//!    newest values of the others, in light-propagation order (Immel, Cohen and Greenberg 1986, Fig. 10:
//!    emitters first, then the patches that see them, and so on). In radiance
//!    units throughout (B = πL on both sides, so the π cancels): L_i = Le_i +
//!    ρ_i Σ_j F_ij L_j, per RGB channel.
//! 4. Vertex radiance is the average of the adjacent patches' radiance weighted
//!    by the area of each patch the vertex represents (radiosity lecture notes, step 4, "average
//!    the radiosity values at the corners of each patch"; the weights are the
//!    progressive solver's gather weights, [`Solver::patch_weights`]).
//!
//! ## Textured surfaces
//!
//! As in the progressive solve (`solve/textured.rs`), a textured surface
//! stores the incident light E/π, not its radiance: a textured patch's
//! gathered G_i = Σ_j F_ij L_j is its E/π (constant over the patch, the
//! centre-point approximation above), it reflects ∫ ρ E/π dA / A_i = ρ̄_i ⊙
//! G_i with ρ̄_i = Σ_v w_v / A_i from its RGB gather weights (Kd ⊙ the exact
//! integral of the texture over the patch), so L_i = Le_i + ρ̄_i ⊙ G_i; its
//! vertices get the area-weighted average of their patches' G, and the
//! solution shows ρ(uv) ⊙ E/π through textured batches, written by
//! [`Solver::to_solution`] as for the progressive solve. A patch of an
//! emission-textured surface emits its texels' mean Le, as in the progressive
//! solve (its initial unshot radiance), and is shown with the texture.
//!
//! ## Convergence
//!
//! Every row sums to at most 1 (a hemicube's delta factors sum to 1) and
//! ρ_max = the largest reflectance < 1, so the Gauss–Seidel iteration matrix has
//! ∞-norm γ ≤ ρ_max and the error after a sweep that changed the solution by Δ
//! (∞-norm) is at most γ/(1 − γ) · Δ. The solve stops when Δ falls below
//! `tolerance` × the largest patch radiance, or after `max_sweeps`;
//! [`GaussSeidelResult::error_bound`] reports the bound.
//!
//! ## Memory
//!
//! The matrix has n² entries, stored as f32 (4n² bytes; the solve sums in
//! f64). It is refused above [`GaussSeidelLimits::max_matrix_bytes`] (default
//! 2 GiB, n ≈ 23 000) *before* anything of size n² is allocated: first from a
//! lower bound on n counted from the scene's polygons before meshing, then from
//! the mesh's exact count.

use super::{human_bytes, SolveError, Solver};
use crate::geometry::hemicube::{Frame, Hemicube, HemicubeError, ItemBuffer, GOLDEN_ANGLE};
use crate::scene::Scene;
use crate::settings::SolverSettings;
use glam::DVec3;
use rayon::prelude::*;
use solution::format::{Solution, SolveMode};
use std::time::Instant;

/// Bytes per stored form factor (f32).
pub const BYTES_PER_FACTOR: u64 = 4;

/// Default bound on the form-factor matrix: 2 GiB.
pub const DEFAULT_MAX_MATRIX_BYTES: u64 = 2 << 30;

/// Bounds on a Gauss–Seidel solve.
#[derive(Clone, Debug, PartialEq)]
pub struct GaussSeidelLimits {
    /// Refuse scenes whose n × n f32 form-factor matrix needs more bytes.
    pub max_matrix_bytes: u64,
    /// Stop after this many sweeps even if not converged.
    pub max_sweeps: u32,
    /// Converged when a sweep changes no patch's radiance by more than this
    /// fraction of the largest patch radiance (any channel).
    pub tolerance: f64,
}

impl Default for GaussSeidelLimits {
    fn default() -> Self {
        GaussSeidelLimits {
            max_matrix_bytes: DEFAULT_MAX_MATRIX_BYTES,
            max_sweeps: 1000,
            tolerance: 1e-6,
        }
    }
}

/// Why a Gauss–Seidel solve cannot run.
#[derive(Debug, thiserror::Error)]
pub enum GaussSeidelError {
    #[error(transparent)]
    Solve(#[from] SolveError),
    #[error(transparent)]
    Hemicube(#[from] HemicubeError),
    #[error(
        "the Gauss-Seidel solver stores the full n x n form-factor matrix: {patches} patches \
         need {patches}² × {BYTES_PER_FACTOR} = {bytes} bytes ({}), above the limit of {limit} \
         bytes ({}); use larger patches (--patch-size) or --method progressive",
        human_bytes(*bytes),
        human_bytes(*limit as u128)
    )]
    MatrixTooLarge {
        patches: u64,
        bytes: u128,
        limit: u64,
    },
    #[error(
        "could not allocate the {bytes}-byte form-factor matrix ({patches} patches): out of memory"
    )]
    OutOfMemory { patches: u64, bytes: u128 },
    #[error("tolerance {0} is out of range: 0 < tolerance < 1")]
    BadTolerance(f64),
}

/// Bytes of the form-factor matrix of `patches` patches (u128, saturating).
pub fn matrix_bytes(patches: u64) -> u128 {
    (patches as u128)
        .saturating_mul(patches as u128)
        .saturating_mul(BYTES_PER_FACTOR as u128)
}

/// Refuses a matrix above the limit; returns its size in bytes otherwise.
pub fn check_matrix_size(
    patches: u64,
    limits: &GaussSeidelLimits,
) -> Result<u64, GaussSeidelError> {
    let bytes = matrix_bytes(patches);
    if bytes > limits.max_matrix_bytes as u128 {
        return Err(GaussSeidelError::MatrixTooLarge {
            patches,
            bytes,
            limit: limits.max_matrix_bytes,
        });
    }
    Ok(bytes as u64)
}

/// A lower bound on the number of patches [`crate::mesh::Mesh::with_sizing`] will make,
/// counted without meshing: N² per polygon of non-zero area (N its own patch
/// count, else the size-driven or flat setting's, [`crate::mesh::sizing`]), times its triangle count for polygons other than
/// quads (a non-convex quad, meshed as two triangles, is counted once).
pub fn patch_count_lower_bound(scene: &Scene, settings: &SolverSettings) -> u64 {
    let sizing = crate::mesh::Sizing::from_settings(settings, scene);
    scene
        .polygons
        .iter()
        .filter(|p| p.vertices.len() >= 3 && p.area().is_finite() && p.area() > 0.0)
        .map(|p| {
            let n = sizing.patches_per_side(p) as u64;
            let pieces = if p.vertices.len() == 4 {
                1
            } else {
                p.vertices.len() as u64 - 2
            };
            pieces.saturating_mul(n.saturating_mul(n))
        })
        .fold(0u64, u64::saturating_add)
}

/// A finished Gauss–Seidel solve.
#[derive(Clone, Debug)]
pub struct GaussSeidelResult {
    /// The solution file's contents, with the same header conventions as
    /// [`Solver::to_solution`]; `stats.shots` holds the sweeps, `stats.rays`
    /// 0 (no rays are traced), `stats.unshot_fraction` the power the last
    /// sweep still added divided by the emitted power, and `partial` is set
    /// when the solve stopped at `max_sweeps` unconverged.
    pub solution: Solution,
    /// Per patch (mesh order): radiance, RGB, W·sr⁻¹·m⁻².
    pub patch_radiance: Vec<DVec3>,
    /// Per mesh vertex: the area-weighted average of its patches' radiance.
    pub vertex_radiance: Vec<DVec3>,
    /// Per patch: the gathered Σ_j F_ij L_j, its incident E/π.
    pub patch_irradiance_over_pi: Vec<DVec3>,
    /// Per mesh vertex: the area-weighted average of its patches' E/π (what
    /// a textured vertex stores and the file shows times ρ(uv)).
    pub vertex_irradiance_over_pi: Vec<DVec3>,
    /// Per patch: Σ_j F_ij, summed in f64 before storage as f32 (1 in a
    /// closed scene, within 1e-10).
    pub row_sums: Vec<f64>,
    pub sweeps: u32,
    /// Largest change of the last sweep / largest patch radiance.
    pub change: f64,
    /// γ/(1 − γ) · change with γ the largest reflectance: a bound on the
    /// remaining error relative to the largest patch radiance (infinite when
    /// a reflectance is 1).
    pub error_bound: f64,
    pub converged: bool,
    pub form_factor_seconds: f64,
    pub solve_seconds: f64,
    pub matrix_bytes: u64,
}

/// Solves `scene` by Gauss–Seidel on the full form-factor matrix from
/// hemicubes of `settings.hemicube_resolution` on the receiving patches (see
/// the module documentation). Uses `settings.patch_size`, `mode` (diffuse only),
/// the material checks and the scene checks of [`Solver::new`]; the
/// progressive settings (samples, threshold, adaptive meshing, …) play no
/// part.
pub fn solve_gauss_seidel(
    scene: &Scene,
    settings: &SolverSettings,
    limits: &GaussSeidelLimits,
) -> Result<GaussSeidelResult, GaussSeidelError> {
    settings.validate().map_err(SolveError::from)?;
    if settings.mode != SolveMode::Diffuse {
        return Err(SolveError::UnsupportedMode(settings.mode).into());
    }
    if !scene.lights.is_empty() {
        return Err(SolveError::LightsNeedProgressive("gauss-seidel").into());
    }
    if !(limits.tolerance > 0.0 && limits.tolerance < 1.0) {
        return Err(GaussSeidelError::BadTolerance(limits.tolerance));
    }
    // Refuse a hopeless scene before meshing it: meshing is O(n), the matrix
    // O(n²), and this bound never exceeds the mesh's patch count.
    check_matrix_size(patch_count_lower_bound(scene, settings), limits)?;
    let hemicube = Hemicube::new(settings.hemicube_resolution)?;
    // Receivers whole (`mesh::contact` off), as this method was measured
    // and tested: the Gauss–Seidel tests compare it with a whole-receiver
    // progressive solve.
    let whole = SolverSettings {
        whole_receivers: true,
        ..settings.clone()
    };
    let mut solver = Solver::new(scene, &whole)?;
    let mesh = solver.mesh();
    let n = mesh.patches.len();
    let bytes = check_matrix_size(n as u64, limits)?;

    let start = Instant::now();
    let (factors, row_sums) = form_factor_matrix(&solver, &hemicube, bytes)?;
    let form_factor_seconds = start.elapsed().as_secs_f64();

    let start = Instant::now();
    let kd = patch_reflectance(&solver, scene);
    // Each patch's emitted radiance as the progressive solve starts it: Ke,
    // or on an emission-textured surface the texels' mean over the patch
    // (`textured.rs`); before any shot that is its unshot radiance.
    let emission: Vec<DVec3> = solver.patch_unshot().to_vec();
    let swept = sweep(&solver, &factors, &kd, &emission, limits);
    let converged = swept.change < limits.tolerance;
    let gamma = kd.iter().map(|k| k.max_element()).fold(0.0, f64::max);
    let error_bound = if gamma < 1.0 {
        gamma / (1.0 - gamma) * swept.change
    } else {
        f64::INFINITY
    };

    // The radiosity lecture notes step 4: vertex radiance from the adjacent patches, area-weighted.
    let vertex_radiance = vertex_average(&solver, &swept.radiance);
    let vertex_irradiance_over_pi = vertex_average(&solver, &swept.gathered_light);
    let solve_seconds = start.elapsed().as_secs_f64();

    let emitted = solver.progress().emitted_power;
    set_vertex_values(
        &mut solver,
        &swept,
        &emission,
        &vertex_radiance,
        &vertex_irradiance_over_pi,
    );
    let mut solution = solver.to_solution(false);
    let header = &mut solution.header;
    header.partial = !converged;
    header.stats.shots = swept.sweeps as u64;
    header.stats.rays = 0;
    header.stats.seconds = form_factor_seconds + solve_seconds;
    header.stats.unshot_fraction = if emitted > 0.0 {
        swept.added_power / emitted
    } else {
        0.0
    };
    header.stats.ambient = [0.0; 3];
    let record = serde_json::json!({
        "max_matrix_bytes": limits.max_matrix_bytes,
        "max_sweeps": limits.max_sweeps,
        "tolerance": limits.tolerance,
        "sweeps": swept.sweeps,
        "change": swept.change,
        "error_bound": error_bound,
    });
    record_in_settings(&mut header.settings_json, record);
    Ok(GaussSeidelResult {
        solution,
        patch_radiance: swept.radiance,
        vertex_radiance,
        patch_irradiance_over_pi: swept.gathered_light,
        vertex_irradiance_over_pi,
        row_sums,
        sweeps: swept.sweeps,
        change: swept.change,
        error_bound,
        converged,
        form_factor_seconds,
        solve_seconds,
        matrix_bytes: bytes,
    })
}

/// The n × n form factors F_ij (f32, row i from a hemicube on patch i) and
/// each row's sum in f64; `bytes` is the matrix's size, for the refusal when
/// it cannot be allocated.
fn form_factor_matrix(
    solver: &Solver,
    hemicube: &Hemicube,
    bytes: u64,
) -> Result<(Vec<f32>, Vec<f64>), GaussSeidelError> {
    let mesh = solver.mesh();
    let n = mesh.patches.len();
    let mut factors: Vec<f32> = Vec::new();
    factors
        .try_reserve_exact(n * n)
        .map_err(|_| GaussSeidelError::OutOfMemory {
            patches: n as u64,
            bytes: bytes as u128,
        })?;
    factors.resize(n * n, 0.0);
    let targets: Vec<&[DVec3]> = mesh.patches.iter().map(|p| p.polygon()).collect();
    let row_sums: Vec<f64> = factors
        .par_chunks_mut(n.max(1))
        .enumerate()
        .map_init(
            || (hemicube.buffer(), vec![0.0f64; n]),
            |(buffer, row64), (i, row)| {
                gather_row(hemicube, buffer, row64, solver, &targets, i);
                for (dst, &f) in row.iter_mut().zip(row64.iter()) {
                    *dst = f as f32;
                }
                row64.iter().sum()
            },
        )
        .collect();
    Ok((factors, row_sums))
}

/// What the Gauss–Seidel sweeps leave: per patch its radiance and the
/// light it gathered (Σ_j F_ij L_j, its E/π), the sweeps done, the last
/// sweep's largest change relative to the brightest patch, and the power
/// that sweep added.
struct Swept {
    radiance: Vec<DVec3>,
    gathered_light: Vec<DVec3>,
    sweeps: u32,
    change: f64,
    added_power: f64,
}

/// Gauss–Seidel sweeps in light-propagation order until the relative change
/// falls below the tolerance or the sweep limit is reached.
fn sweep(
    solver: &Solver,
    factors: &[f32],
    kd: &[DVec3],
    emission: &[DVec3],
    limits: &GaussSeidelLimits,
) -> Swept {
    let mesh = solver.mesh();
    let n = mesh.patches.len();
    let order = propagation_order(factors, emission, n);
    let mut radiance = emission.to_vec();
    let mut gathered_light = vec![DVec3::ZERO; n];
    let mut sweeps = 0;
    let mut change = f64::INFINITY;
    let mut added_power = 0.0;
    while sweeps < limits.max_sweeps {
        sweeps += 1;
        let mut largest_change: f64 = 0.0;
        added_power = 0.0;
        for &i in &order {
            let row = &factors[i * n..(i + 1) * n];
            let mut gathered = DVec3::ZERO;
            for (&f, &l) in row.iter().zip(&radiance) {
                gathered += l * f as f64;
            }
            // The radiosity lecture notes: B_i = E_i + ρ_i Σ_j F_ij B_j, in radiance.
            let updated = emission[i] + kd[i] * gathered;
            gathered_light[i] = gathered;
            let delta = (updated - radiance[i]).abs();
            largest_change = largest_change.max(delta.max_element());
            added_power += std::f64::consts::PI * mesh.patches[i].area * delta.element_sum();
            radiance[i] = updated;
        }
        let scale = radiance.iter().map(|l| l.max_element()).fold(0.0, f64::max);
        change = if scale > 0.0 {
            largest_change / scale
        } else {
            0.0
        };
        if change < limits.tolerance {
            break;
        }
    }
    Swept {
        radiance,
        gathered_light,
        sweeps,
        change,
        added_power,
    }
}

/// The solver's per-vertex values as the progressive output reads them
/// (smooth surfaces' shared vertices, hidden vertices, textured batches):
/// radiance, or on a textured surface E/π plus its emission, and on an
/// emission-textured one its surface's mean Le plus the light it reflects,
/// which the output splits into the texture and the SH.
fn set_vertex_values(
    solver: &mut Solver,
    swept: &Swept,
    emission: &[DVec3],
    vertex_radiance: &[DVec3],
    vertex_irradiance_over_pi: &[DVec3],
) {
    let reflected: Vec<DVec3> = swept
        .radiance
        .iter()
        .zip(emission)
        .map(|(l, e)| *l - *e)
        .collect();
    let vertex_reflected = vertex_average(solver, &reflected);
    solver.field.radiance = solver
        .mesh
        .vertices
        .iter()
        .enumerate()
        .map(|(v, mv)| {
            let own = solver.materials.emission[mv.surface as usize];
            if solver.materials.texturing.get(mv.surface).is_some() {
                own + vertex_irradiance_over_pi[v]
            } else if solver.materials.texturing.emissive(mv.surface).is_some() {
                own + vertex_reflected[v]
            } else {
                vertex_radiance[v]
            }
        })
        .collect();
}

/// Records the method and its sweep figures in the settings JSON.
fn record_in_settings(settings_json: &mut String, record: serde_json::Value) {
    if let Ok(serde_json::Value::Object(mut map)) =
        serde_json::from_str::<serde_json::Value>(settings_json)
    {
        map.insert("solver".into(), "gauss-seidel".into());
        map.insert("gauss_seidel".into(), record);
        *settings_json = serde_json::Value::Object(map).to_string();
    }
}

/// Per patch its reflectance: the material's Kd (with its specular albedo
/// folded in, [`crate::scene::Material::diffuse_equivalent_kd`]), or on a textured surface
/// the mean of ρ = Kd ⊙ texture over the patch, Σ_v w_v / A from its RGB
/// gather weights (exact integrals of the texture, `solve/textured.rs`).
fn patch_reflectance(solver: &Solver, scene: &Scene) -> Vec<DVec3> {
    let mesh = solver.mesh();
    mesh.patches
        .iter()
        .enumerate()
        .map(|(p, patch)| match solver.patches.rgb_weights.get(p) {
            Some(w) if !w.is_empty() && patch.area > 0.0 => {
                w.iter().map(|e| e.1).sum::<DVec3>() / patch.area
            }
            // Diffuse mode only, as the solver's own reflectance.
            _ => scene.materials[mesh.surfaces[patch.surface as usize].material]
                .diffuse_equivalent_kd(),
        })
        .collect()
}

/// Per mesh vertex, the average of `per_patch` over its patches weighted by
/// the area of each the vertex represents (its gather weights).
fn vertex_average(solver: &Solver, per_patch: &[DVec3]) -> Vec<DVec3> {
    let vertices = solver.mesh().vertices.len();
    let mut sums = vec![DVec3::ZERO; vertices];
    let mut weights = vec![0.0; vertices];
    for (p, l) in per_patch.iter().enumerate() {
        for &(v, w) in solver.patch_weights(p as u32) {
            sums[v as usize] += *l * w;
            weights[v as usize] += w;
        }
    }
    sums.iter()
        .zip(&weights)
        .map(|(s, &w)| if w > 0.0 { *s / w } else { DVec3::ZERO })
        .collect()
}

/// Row i of the matrix: the hemicube on patch i's centre over every patch.
fn gather_row(
    hemicube: &Hemicube,
    buffer: &mut ItemBuffer,
    row: &mut [f64],
    solver: &Solver,
    targets: &[&[DVec3]],
    i: usize,
) {
    row.fill(0.0);
    let mesh = solver.mesh();
    let patch = &mesh.patches[i];
    let surface = &mesh.surfaces[patch.surface as usize];
    let polygon = patch.polygon();
    let centre = polygon.iter().copied().sum::<DVec3>() / polygon.len() as f64;
    let angle = GOLDEN_ANGLE * i as f64;
    let hint = surface.tangent * angle.cos() + surface.bitangent * angle.sin();
    if let Some(frame) = Frame::new(centre, surface.normal, hint) {
        buffer.render(&frame, targets);
        hemicube.accumulate(buffer, row);
    }
}

/// Immel, Cohen and Greenberg 1986, Fig. 10: emitters first, then the patches that gather from them, then
/// those that gather from these, …; patches no light reaches come last, each
/// group in index order.
fn propagation_order(factors: &[f32], emission: &[DVec3], n: usize) -> Vec<usize> {
    let mut placed = vec![false; n];
    let mut order: Vec<usize> = Vec::with_capacity(n);
    for (i, e) in emission.iter().enumerate() {
        if e.max_element() > 0.0 {
            placed[i] = true;
            order.push(i);
        }
    }
    let mut next = 0;
    while next < order.len() {
        let j = order[next];
        next += 1;
        for i in 0..n {
            if !placed[i] && factors[i * n + j] > 0.0 {
                placed[i] = true;
                order.push(i);
            }
        }
    }
    order.extend((0..n).filter(|&i| !placed[i]));
    order
}

#[cfg(test)]
mod tests;
