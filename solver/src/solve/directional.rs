//! Directional (glossy) shooting: radiance and unshot radiance as spherical
//! harmonics per vertex and per patch (Remington 1992, ch. 4, Fig. 4.7; design notes,
//! "Directional mode").
//!
//! ## State
//!
//! * Per surface, an SH order L: 0 for a diffuse material (Ks = 0), otherwise
//!   the smallest order whose Legendre fit of the lobe meets
//!   `sh_error_target`, capped at `max_sh_order` (with a warning stating the
//!   error left). All vertices and patches of a surface share its order and its
//!   frame (n, t), so a patch's coefficients are the area-weighted average of
//!   its vertices' and evaluating them toward a receiver is meaningful (a
//!   source never mixes frames: patches do not cross surfaces).
//!
//! ## Frames on smooth surfaces
//!
//! The SH frame of every vertex is its polygon's (n = the polygon's normal,
//! t = its first edge), on a smooth surface too; the shading normal enters
//! only the physics: the receiving cosine and horizon (the diffuse path's
//! samples), and the glossy lobe's incidence cosine μ_i and mirror direction,
//! taken about the vertex's shading normal and then written in the polygon's
//! frame ([`GlossyLobe::add_lobe_sh_about`]: each SH band is closed under
//! rotation, so that is the same function exactly, not an approximation). So
//! the rule for a patch whose vertices have different shading normals is: its
//! unshot SH is the area-weighted average of its vertices' ΔL, all written in
//! the one frame of its polygon, which is the average of their radiance
//! functions; no coefficients of two different frames are ever added, averaged
//! or compared (gathering, refinement's interpolation and split test, and the
//! output all stay within a polygon). Two polygons meeting at a smooth seam
//! each keep a vertex there, with the same position and shading normal, so
//! they receive the same radiance function, each in its own polygon's frame,
//! and the runtime (which evaluates every vertex's SH in the frame written
//! with it) shows the same radiance from both sides. No tangent field has to
//! be continuous across polygons: none could be on a closed surface (the
//! hairy-ball theorem; see docs/smooth-surfaces.md).
//! * Per vertex: radiance coefficients (emission included) and the ΔL of the
//!   shot in progress, `(L+1)² × 3` f64 each, in flat vectors with an offset
//!   per vertex, laid out coefficient-major then RGB as in the solution file.
//! * Per patch: unshot coefficients, gathered from the vertices after each
//!   shot exactly as the diffuse solver gathers ΔL (see [`crate::solve`]).
//!
//! The diffuse fields of [`Solver`] stay meaningful: `radiance` holds each
//! vertex's c₀₀·Y₀₀ (its mean radiance over the sphere) and `patch_unshot` the
//! diffuse-equivalent unshot radiance, hemispherical unshot power / (π A), so
//! the convergence test, the ambient term and the hemisphere source choice are
//! the diffuse code's, unchanged.
//!
//! ## Transport (design notes, "Directional mode")
//!
//! For every visible source sample i with form-factor share F_i (analytic
//! method, where the receiver is glossy or the source's radiance depends on
//! direction: samples uniform in the solid angle of the source's part in
//! front of the receiver, sharing the exact unoccluded factor by the
//! receiver's cosine, `shoot::SampleBy::SolidAngle`; between two
//! diffuse ends: the exact factor divided evenly over area samples; the
//! visible ones kept; Wallace: Remington 1992, eq. 3.1's per-sample term), with ω_i the
//! direction from the receiver to the sample:
//!
//! * ΔE_i = U_s(−ω_i) · π · F_i, U_s evaluated from the source's SH in the
//!   source's frame (clamped at 0: ringing of a truncated lobe is not light);
//!   a quad source lit unevenly (`regions.rs`, as in the diffuse solve)
//!   scales U_s at each sample by its quadrant's s_q (Σ_q s_q A_q = A_p, so
//!   the shot's power is unchanged), times the ratio that makes the
//!   unoccluded sum the quadrants' exact factors
//!   ([`super::regions::QuadrantScale`]); such a shot samples by solid angle
//!   even between two diffuse ends, since equal area shares would average
//!   the quadrants out. Emitters' recorded shots stay uniform;
//! * diffuse: c₀₀ += Kd · ΔE_i / π · √(4π);
//! * glossy: c_lm += ΔE_i · Ks · C_R(μ_i) · a_l · 4π/(2l+1) · Y_lm(r_i)
//!   ([`GlossyLobe::add_lobe_sh`], built with Ks = 1 and scaled per channel,
//!   since C_R is linear in Ks); C_R is the thesis's.
//!
//! ## Refinement
//!
//! Adaptive subdivision is the diffuse solver's (`refine::refine_field` with
//! this module's `DirField`): the same candidates, splits, interpolation
//! of the smooth part and exact replay of every recorded emitter shot to new
//! vertices, per SH coefficient (the recorded shots' unshot SH are kept, and
//! checkpointed, beside the diffuse solver's list). A new vertex on a glossy
//! surface also gathers what the patches near it have shot so far, instead of
//! taking that part from its parents' average (`directional/near_gather.rs`:
//! the average of two reflected images is not the image between them; each
//! patch's shot SH are summed, and checkpointed). L = 0 surfaces use the
//! diffuse split test on the c₀₀ proxies, so with Ks = 0 the two modes mesh
//! and solve alike; glossy surfaces split on the Parseval L2 norm of the
//! coefficient difference across an edge, down to [`min_glossy_edge`].

use super::budget;
use super::checkpoint::precision::round_to_kept;
use super::fine_shape::FineShape;
use super::regions::{self, QuadrantScale};
use super::shoot::Shot;
use super::{ShapeView, SolveError, Solver};
use crate::brdf::normalization::funk_hecke_d;
use crate::brdf::GlossyLobe;
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::settings::SolverSettings;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use solution::sh::coefficient_count;
use std::f64::consts::PI;
use std::sync::Arc;

mod field;
mod group;
#[cfg(test)]
mod group_tests;
mod lights;
mod near_gather;
mod output;
mod receive;
mod shot;
mod split;
mod state;
mod textured;

pub(super) use lights::DirLightsShot;
pub(super) use shot::ShShot;

/// How the next source patch is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SourceChoice {
    /// Most unshot power over the upper hemisphere, A · Σ_l c_l0 ∫ Y_l0 cosθ dω
    /// (design notes, "Progressive refinement"): the default.
    #[default]
    Hemisphere,
    /// Remington's (1992) choice by the [0,0] term alone, A · c₀₀ (kept to measure against).
    ZerothTerm,
}

/// The directional state of a [`Solver`] in `SolveMode::Directional`.
#[derive(Clone, Debug)]
pub struct Directional {
    /// Per surface: SH order, glossy reflectance and lobe (None when Ks = 0).
    surface_order: Vec<u32>,
    ks: Vec<DVec3>,
    lobes: Vec<Option<Arc<GlossyLobe>>>,
    /// Per vertex: start of its coefficients in `radiance`/`received`.
    vertex_offset: Vec<usize>,
    radiance: Vec<f64>,
    received: Vec<f64>,
    /// Per patch: start of its coefficients in `patch_unshot`.
    patch_offset: Vec<usize>,
    patch_unshot: Vec<f64>,
    /// `hemisphere[l] = ∫_{upper} Y_l0 cosθ dω = 2π √((2l+1)/4π) D_l`.
    hemisphere: Vec<f64>,
    choice: SourceChoice,
    /// Per vertex, per coefficient: the part of `radiance` from recorded
    /// (emitter) shots, which a new vertex receives exactly instead of by
    /// interpolation (as the diffuse solver's `direct`; see `refine.rs`).
    direct: Vec<f64>,
    /// The unshot SH of each of the solver's recorded shots, in order.
    recorded_unshot: Vec<Vec<f64>>,
    /// Per patch (laid out as `patch_unshot`): the sum of the unshot SH it
    /// has shot in unrecorded shots, which a split's new glossy vertex
    /// gathers from the patches near it (`directional/near_gather.rs`).
    shot_sum: Vec<f64>,
    /// Per surface: the smallest element edge glossy refinement may create
    /// (see [`min_glossy_edge`]); 0 for L = 0 surfaces.
    min_edge: Vec<f64>,
    /// The scene's viewing distance scale D (half its bounds' diagonal, as in
    /// [`min_glossy_edge`]): the split test's view term turns the direction
    /// to an eye by an edge's length over D (`directional/split.rs`).
    view_distance: f64,
    /// Per surface: whether it is textured. A textured surface's vertex
    /// slot holds its SH coefficients (glossy lobe and emission only) and
    /// then E/π, three more values (`directional/textured.rs`).
    textured: Vec<bool>,
}

/// The smallest element edge refinement may create on a glossy surface of
/// glossiness α in a scene whose viewing distance scale is `view_distance`
/// (half the diagonal of the scene's bounds: a walkthrough's eye is inside
/// the scene, so that is the distance its surfaces are typically seen from).
///
/// Rule: `h_min = k · α · D`, k the setting `glossy_edge` (0.5 unless a
/// preset or the user says otherwise). Why: the runtime evaluates each
/// vertex's SH toward the eye and interpolates between vertices, so what the
/// mesh must resolve is the radiance toward one eye as it varies across the
/// surface. A step Δx on the surface turns the direction to an eye at
/// distance d_e by about Δx / d_e and the mirror direction of a source at
/// d_s by about Δx / d_s, the other way, so the angle between them changes
/// by Δx / d with 1/d = 1/d_e + 1/d_s. The lobe g = exp(−tan²(θ0/2)/α²)
/// falls to 1/e at θ0 ≈ 2α, so a highlight's 1/e half-width on the surface
/// is w ≈ 2αd: 2αD for a far source, αD when eye and source are both D
/// away. Vertices every w/4 interpolate that Gaussian profile to within
/// h²/8 · max|g''| = (w/4)²/8 · 2/w² = 1/64 ≈ 1.6% of its peak: k = 0.5
/// for a far source, 0.25 for a near one (measured on the glossy room: k =
/// 0.25 with the smallest element halved too takes its MARE from 6.1% to
/// 4.3%, docs/accuracy.md). Finer
/// elements cannot show the eye more (the lobe itself blurs anything
/// smaller), only cost coefficients, (L+1)² per vertex. The floor scales
/// with α: a narrow lobe (more bands) may be meshed finer.
pub fn min_glossy_edge(alpha: f64, view_distance: f64, factor: f64) -> f64 {
    factor * alpha * view_distance
}

/// The directional part of a [`super::Checkpoint`] as read back: coefficients
/// as f64 bit patterns, and the orders they were computed with. `direct` is
/// empty in checkpoints of this version: it is recomputed on resume (see
/// `directional/state.rs`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DirectionalCheckpoint {
    pub surface_order: Vec<u32>,
    pub radiance: Vec<u64>,
    pub patch_unshot: Vec<u64>,
    /// Per coefficient: the part of `radiance` from recorded shots.
    #[serde(default)]
    pub direct: Vec<u64>,
    /// The unshot SH of each recorded shot.
    #[serde(default)]
    pub recorded_unshot: Vec<Vec<u64>>,
    /// Per patch coefficient: the SH it has shot in unrecorded shots.
    #[serde(default)]
    pub shot_sum: Vec<u64>,
}

/// The warnings for a diffuse solve of a scene with glossy materials (design
/// notes, "Directional mode"), one per used material with Ks > 0: its
/// specular albedo was folded into its diffuse reflectance
/// ([`crate::scene::Material::diffuse_equivalent_kd`]), and `--mode
/// directional` shows its glossy lobe properly. Empty when no used material
/// is glossy.
pub fn diffuse_mode_warning(scene: &Scene, mesh: &Mesh) -> Vec<String> {
    let mut used = vec![false; scene.materials.len()];
    for s in &mesh.surfaces {
        used[s.material] = true;
    }
    let rgb = |v: glam::DVec3| format!("({:.3}, {:.3}, {:.3})", v.x, v.y, v.z);
    let glossy = scene
        .materials
        .iter()
        .zip(&used)
        .filter(|(m, &u)| u && m.is_glossy())
        .map(|(m, _)| m);
    // A dielectric's faint specular (glTF gives every non-metal Ks = 0.04)
    // is folded without a warning each: one line counts them.
    let (faint, strong): (Vec<_>, Vec<_>) =
        glossy.partition(|m| m.ks.max_element() <= DIELECTRIC_KS);
    let mut warnings: Vec<String> = strong
        .iter()
        .map(|m| {
            format!(
                "diffuse mode: material `{}` is glossy (Ks {}); its specular albedo was folded \
                 into its diffuse reflectance (Kd {} became {}, per channel, capped at 1), so \
                 it reflects as much light but spreads it evenly; solve with `--mode \
                 directional` (or `mode = \"directional\"` in the scene config) to show its \
                 glossy reflection properly",
                m.name,
                rgb(m.ks),
                rgb(m.kd),
                rgb(m.diffuse_equivalent_kd())
            )
        })
        .collect();
    if let Some(first) = faint.first() {
        warnings.push(format!(
            "diffuse mode: {} material(s) with a dielectric's specular albedo (Ks at most \
             {DIELECTRIC_KS}, `{}` among them) had it folded into their diffuse reflectance",
            faint.len(),
            first.name
        ));
    }
    warnings
}

/// The specular albedo of a dielectric (glTF's F0 = 0.04 for every
/// non-metal): at or below it, a material's fold is counted, not warned.
pub const DIELECTRIC_KS: f64 = 0.04;

impl Directional {
    /// Chooses each material's order, builds its lobe, and sets vertex radiance
    /// and patch unshot to the emission (c₀₀ = Le · √(4π), the SH of the
    /// isotropic radiance Le). `emission` is per mesh surface what its
    /// vertices start with and `patch_emission` per patch what it shoots,
    /// as the diffuse solver sets them up ([`Solver::new`]): the material's
    /// Ke, or on an emission-textured surface its mean Le and each patch's
    /// texel-integrated mean Le (`solve/textured.rs`), so the emitted power
    /// is π ∫ Le dA in both modes. Returns the state and its warnings (orders
    /// capped at `max_sh_order`).
    pub fn new(
        scene: &Scene,
        settings: &SolverSettings,
        mesh: &Mesh,
        emission: &[DVec3],
        patch_emission: &[DVec3],
    ) -> Result<(Directional, Vec<String>), SolveError> {
        let mut warnings = Vec::new();
        let mut material_lobe: Vec<Option<Arc<GlossyLobe>>> = Vec::new();
        for m in &scene.materials {
            let ok = m.ks.is_finite() && m.ks.min_element() >= 0.0 && m.ks.max_element() <= 1.0;
            if !ok {
                return Err(SolveError::BadMaterial {
                    name: m.name.clone(),
                    problem: format!("Ks {:?} must be in [0, 1]", m.ks.to_array()),
                });
            }
            if !m.is_glossy() {
                material_lobe.push(None);
                continue;
            }
            let lobe = GlossyLobe::with_default_window(
                m.alpha,
                1.0,
                settings.sh_error_target,
                settings.max_sh_order,
            )
            .map_err(|e| SolveError::BadMaterial {
                name: m.name.clone(),
                problem: e.to_string(),
            })?;
            if lobe.choice.capped {
                warnings.push(format!(
                    "material `{}`: α = {} needs more than max_sh_order = {} SH bands for the \
                     error target {:e}; capped at L = {} with a {} window, leaving a relative \
                     L2 lobe error of {:.3e} (unwindowed fit)",
                    m.name,
                    m.alpha,
                    settings.max_sh_order,
                    settings.sh_error_target,
                    lobe.order(),
                    lobe.window.name(),
                    lobe.choice.error
                ));
            }
            material_lobe.push(Some(Arc::new(lobe)));
        }
        if let Some(limit) = settings.memory_budget {
            cap_orders(
                scene,
                settings,
                mesh,
                limit,
                &mut material_lobe,
                &mut warnings,
            )?;
        }
        let lobes: Vec<Option<Arc<GlossyLobe>>> = mesh
            .surfaces
            .iter()
            .map(|s| material_lobe[s.material].clone())
            .collect();
        let surface_order: Vec<u32> = lobes
            .iter()
            .map(|l| l.as_ref().map_or(0, |l| l.order()))
            .collect();
        let ks = mesh
            .surfaces
            .iter()
            .map(|s| scene.materials[s.material].ks)
            .collect();
        let max_order = surface_order.iter().copied().max().unwrap_or(0);
        let hemisphere = (0..=max_order)
            .map(|l| 2.0 * PI * ((2.0 * l as f64 + 1.0) / (4.0 * PI)).sqrt() * funk_hecke_d(l))
            .collect();
        let mut d = Directional {
            surface_order,
            ks,
            lobes,
            vertex_offset: Vec::new(),
            radiance: Vec::new(),
            received: Vec::new(),
            patch_offset: Vec::new(),
            patch_unshot: Vec::new(),
            hemisphere,
            choice: SourceChoice::default(),
            direct: Vec::new(),
            recorded_unshot: Vec::new(),
            shot_sum: Vec::new(),
            min_edge: Vec::new(),
            view_distance: 0.0,
            textured: textured::textured_surfaces(scene, mesh),
        };
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for v in &mesh.vertices {
            lo = lo.min(v.position);
            hi = hi.max(v.position);
        }
        let view_distance = if lo.x <= hi.x {
            0.5 * (hi - lo).length()
        } else {
            0.0
        };
        d.view_distance = view_distance;
        d.min_edge = d
            .lobes
            .iter()
            .map(|l| {
                l.as_ref().map_or(0.0, |l| {
                    min_glossy_edge(l.alpha, view_distance, settings.glossy_edge)
                })
            })
            .collect();
        d.extend_vertices(mesh);
        let mut at = 0;
        for p in &mesh.patches {
            d.patch_offset.push(at);
            at += 3 * coefficient_count(d.surface_order[p.surface as usize]);
        }
        d.patch_unshot = vec![0.0; at];
        d.shot_sum = vec![0.0; at];
        let scale = (4.0 * PI).sqrt();
        for (v, mv) in mesh.vertices.iter().enumerate() {
            let e = emission[mv.surface as usize];
            let o = d.vertex_offset[v];
            // The state keeps 40 mantissa bits from the start
            // (`checkpoint/precision.rs`).
            d.radiance[o..o + 3].copy_from_slice(&(e * scale).to_array().map(round_to_kept));
        }
        for (p, &e) in patch_emission.iter().enumerate() {
            let o = d.patch_offset[p];
            d.patch_unshot[o..o + 3].copy_from_slice(&(e * scale).to_array().map(round_to_kept));
        }
        Ok((d, warnings))
    }

    /// Adds zeroed coefficient slots for mesh vertices created since the last
    /// call.
    fn extend_vertices(&mut self, mesh: &Mesh) {
        let mut at = self.radiance.len();
        for v in &mesh.vertices[self.vertex_offset.len()..] {
            self.vertex_offset.push(at);
            at += self.vertex_width(v.surface as usize);
        }
        self.radiance.resize(at, 0.0);
        self.received.resize(at, 0.0);
        self.direct.resize(at, 0.0);
    }

    /// Values held per vertex coefficient array, in the patches' unshot and in
    /// the recorded shots' unshot SH, for the memory estimate.
    pub(super) fn coefficient_totals(&self) -> (u64, u64, u64) {
        (
            self.radiance.len() as u64,
            self.patch_unshot.len() as u64,
            self.recorded_unshot.iter().map(|u| u.len() as u64).sum(),
        )
    }

    /// The SH order of each mesh surface.
    pub fn surface_orders(&self) -> &[u32] {
        &self.surface_order
    }

    /// The smallest element edge glossy refinement may create on each mesh
    /// surface ([`min_glossy_edge`]; 0 for L = 0 surfaces).
    pub fn min_glossy_edges(&self) -> &[f64] {
        &self.min_edge
    }

    /// Values held per vertex of mesh surface `s` in each per-vertex array:
    /// its coefficients, and E/π when it is textured (for the memory budget).
    pub(super) fn vertex_values(&self, s: usize) -> u64 {
        self.vertex_width(s) as u64
    }

    fn vertex_range(&self, mesh: &Mesh, v: usize) -> std::ops::Range<usize> {
        let o = self.vertex_offset[v];
        o..o + 3 * coefficient_count(self.surface_order[mesh.vertices[v].surface as usize])
    }

    fn patch_range(&self, mesh: &Mesh, p: usize) -> std::ops::Range<usize> {
        let o = self.patch_offset[p];
        o..o + 3 * coefficient_count(self.surface_order[mesh.patches[p].surface as usize])
    }

    /// The unshot SH patch `p` has shot in unrecorded shots so far.
    fn shot_sum(&self, mesh: &Mesh, p: usize) -> &[f64] {
        &self.shot_sum[self.patch_range(mesh, p)]
    }

    /// Whether patch `p` has shot light in an unrecorded shot.
    fn has_shot(&self, mesh: &Mesh, p: usize) -> bool {
        self.shot_sum(mesh, p).iter().any(|&c| c != 0.0)
    }

    /// The radiance a source of order `order` with unshot SH `coefficients`
    /// shoots as, for its weight in a group: c₀₀ · Y₀₀ at order 0, else
    /// [`Self::hemisphere_equivalent`].
    fn source_radiance(&self, order: u32, coefficients: &[f64]) -> DVec3 {
        if order == 0 {
            DVec3::from_slice(&coefficients[..3]) * solution::sh::Y00
        } else {
            self.hemisphere_equivalent(order, coefficients)
        }
    }

    /// Unshot radiance equivalent to the upper-hemisphere power of
    /// `coefficients` (order `order`), per channel:
    /// Σ_l c_l0 ∫_{upper} Y_l0 cosθ dω / π (design notes, "Progressive
    /// refinement"); for L = 0 this is c₀₀ · Y₀₀, the diffuse unshot radiance.
    fn hemisphere_equivalent(&self, order: u32, coefficients: &[f64]) -> DVec3 {
        let mut sum = DVec3::ZERO;
        for l in 0..=order as usize {
            let k = l * l + l; // index(l, 0)
            let c = DVec3::from_slice(&coefficients[3 * k..3 * k + 3]);
            sum += c * self.hemisphere[l];
        }
        sum / PI
    }
}

/// Caps SH orders so that the unrefined mesh fits in [`budget::ORDER_SHARE`]
/// of the planned budget ([`budget::orders_within`]), before any coefficient
/// is allocated: each capped material's lobe is rebuilt at the order kept
/// (Hann-windowed, as any capped lobe) and warned about.
fn cap_orders(
    scene: &Scene,
    settings: &SolverSettings,
    mesh: &Mesh,
    limit: u64,
    material_lobe: &mut [Option<Arc<GlossyLobe>>],
    warnings: &mut Vec<String>,
) -> Result<(), SolveError> {
    let wanted: Vec<u32> = material_lobe
        .iter()
        .map(|l| l.as_ref().map_or(0, |l| l.order()))
        .collect();
    let target = (budget::plan(limit) as f64 * budget::ORDER_SHARE) as u64;
    let recorded = budget::emitter_patches(scene, mesh);
    let textured = textured::textured_surfaces(scene, mesh);
    let scene_bytes = budget::scene_bytes(scene);
    let kept = budget::orders_within(
        mesh,
        settings,
        &wanted,
        &textured,
        (recorded, scene_bytes, scene.camera.is_none()),
        target,
    );
    for (m, (&want, &keep)) in wanted.iter().zip(&kept).enumerate() {
        if keep == want {
            continue;
        }
        let material = &scene.materials[m];
        let lobe =
            GlossyLobe::with_default_window(material.alpha, 1.0, settings.sh_error_target, keep)
                .map_err(|e| SolveError::BadMaterial {
                    name: material.name.clone(),
                    problem: e.to_string(),
                })?;
        warnings.push(budget::order_cap_warning(
            &material.name,
            material.alpha,
            want,
            keep,
            limit,
        ));
        material_lobe[m] = Some(Arc::new(lobe));
    }
    Ok(())
}

impl Solver {
    /// The directional state, when the solve is in directional mode.
    pub fn directional(&self) -> Option<&Directional> {
        self.directional.as_deref()
    }

    /// Radiance coefficients of vertex `v` (`(L+1)² × 3`, coefficient-major
    /// then RGB) and their order, in directional mode.
    pub fn vertex_sh(&self, v: u32) -> Option<(u32, &[f64])> {
        let d = self.directional.as_deref()?;
        let surface = self.mesh.vertices.get(v as usize)?.surface as usize;
        Some((
            d.surface_order[surface],
            &d.radiance[d.vertex_range(&self.mesh, v as usize)],
        ))
    }

    /// Selects how directional sources are chosen (for measurements).
    pub fn set_source_choice(&mut self, choice: SourceChoice) {
        if let Some(d) = self.directional.as_deref_mut() {
            d.choice = choice;
        }
    }

    /// Warnings of the set-up: glossy materials folded into diffuse, SH orders
    /// capped. The command line prints them.
    pub fn warnings(&self) -> &[String] {
        &self.warnings.setup
    }

    /// Sets up directional mode (called by [`Solver::new`]) or, in diffuse mode,
    /// records a warning per glossy material folded into diffuse.
    pub(super) fn init_directional(&mut self, scene: &Scene) -> Result<(), SolveError> {
        if self.settings.mode != solution::format::SolveMode::Directional {
            self.warnings
                .setup
                .extend(diffuse_mode_warning(scene, &self.mesh));
            return Ok(());
        }
        // Before any shot the diffuse fields hold the emission: per vertex its
        // surface's, per patch what it shoots.
        let (d, warnings) = Directional::new(
            scene,
            &self.settings,
            &self.mesh,
            &self.materials.emission,
            &self.patches.unshot,
        )?;
        self.warnings.setup.extend(warnings);
        self.directional = Some(Box::new(d));
        Ok(())
    }
}

/// The quadrant scales of quad patch `source` lit unevenly
/// ([`ShapeView::source_regions`] with a unit mean), each shaped inside by
/// [`FineShape`] where subdivision split it; `None` for a triangle, or a
/// patch lit evenly and not split inside a quadrant.
fn quadrant_scale(view: ShapeView, source: u32, shot: &Shot) -> Option<QuadrantScale> {
    let patch = &view.mesh.patches[source as usize];
    if patch.corner_count != 4 {
        return None;
    }
    let fine = FineShape::new(&patch.corners, view.shape_samples(source));
    // A patch lit evenly quadrant by quadrant may still hold a step
    // inside one (a shadow's edge): its quadrants shoot at their mean,
    // each shaped inside.
    let regions = view
        .source_regions(source, DVec3::ONE)
        .or_else(|| fine.as_ref().map(|_| regions::uniform(&patch.corners)))?;
    Some(QuadrantScale {
        corners: patch.corners,
        normal: shot.normal,
        centre: shot.centre,
        diameter: shot.diameter,
        regions,
        fine,
    })
}
