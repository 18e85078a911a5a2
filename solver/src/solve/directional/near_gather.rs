//! A split's new glossy vertex gathers the light of nearby patches again,
//! instead of taking it from its parents' average.
//!
//! Refinement gives a new vertex the light of earlier, unrecorded shots as
//! the mean of its parents' (Remington 1992, §3.3: "accumulated radiosity
//! interpolated from the vertices on either side"; `refine.rs`). For a diffuse
//! receiver that is irradiance, smooth away from shadow lines. For a glossy
//! receiver it is the mean of two reflected images. A source at distance r
//! seen from two parents a span h apart turns by about h / r, and the lobe,
//! of angular width about 2α, reflects that turn: where h / r is not small
//! against α the mean of the two images puts a sharp reflected edge on the
//! dark side of the new vertex. (Measured on the glossy Cornell box: the
//! short block's face, reflecting the floor's penumbra 50 mm in front of it,
//! 1.3–1.8× the truth from the floor camera, `docs/lab/glossy-final-floor.md`, "Glossy:
//! the short block's face".)
//!
//! So each patch keeps the sum of the unshot SH it has shot so far
//! (`Directional::shot_sum`; recorded emitter shots are replayed exactly
//! and are not in it). A new vertex on a glossy surface gathers that sum
//! from every patch within reach, `NEAR_REACH · h / α` of it, shaped by the
//! patch's current light ([`super::quadrant_scale`]), and its parents
//! gather the same patches the same way. The vertex keeps the parents'
//! average less their near part, plus its own near part:
//!
//!   L_new = mean_parents(L − L_recorded − ΔL − N) + N_new
//!
//! with N the gather of the near patches. The far part, whose images the
//! parents see alike, is still interpolated; the near part is computed.
//! Subtracting the parents' own gather, rather than zeroing their near
//! part, cancels the difference between what they received shot by shot and
//! what one gather of the sum delivers (the patches' shapes changed between
//! shots), so the correction is unbiased where nothing is near.
//!
//! Why `NEAR_REACH` = 2.5: linear interpolation of a Gaussian lobe of 1/e
//! half-width w = 2α across a turn s = h / r errs by s² / 8 · max|g''| =
//! s² / (4 w²) = (h / r)² / (16 α²) of its peak; below 1% that asks
//! r ≥ 2.5 h / α.
//!
//! Cost: three gathers (the vertex and two parents; five for a quad's
//! centre) of the near patches per new glossy vertex, each a shot's receive
//! with `samples` rays. The reach shrinks with the span, so the fine splits,
//! which are most of them, see few patches.

use super::receive::{DirScratch, DirShot, Receiving, Tables};
use super::{quadrant_scale, Directional};
use crate::geometry::polygon::bounding_sphere;
use crate::geometry::visibility::Occluder;
use crate::mesh::{Mesh, NewVertex};
use crate::settings::SolverSettings;
use crate::solve::regions::QuadrantScale;
use crate::solve::shoot::{SamplePool, Shot};
use crate::solve::ShapeView;
use glam::DVec3;
use rayon::prelude::*;

/// The reach of a new vertex's gather in spans over α (module documentation).
pub const NEAR_REACH: f64 = 2.5;

/// Gathers shoot as shot number `GATHER_INDEX + patch`: RNG streams apart from
/// every real shot's (a solve shoots far fewer than 2^48 times).
const GATHER_INDEX: u64 = 1 << 48;

/// Sample sets per gather pool: the fewest a pool holds (a gather is
/// rebuilt for each refinement level, so a small pool is drawn often).
const GATHER_POOL_SETS: u32 = 8;

/// What a gather reads besides the directional state and the mesh.
pub(super) struct NearGather<'a> {
    /// The solver's fields a patch's shape is read from, with the mesh and
    /// the radiance, which refinement holds mutably ([`ShapeView`]).
    pub patch_weights: &'a [Vec<(u32, f64)>],
    pub hidden: &'a [bool],
    pub emission: &'a [DVec3],
    pub settings: &'a SolverSettings,
    pub occluder: &'a Occluder,
    pub kd: &'a [DVec3],
    /// The reach in spans over α ([`NEAR_REACH`]); 0 turns gathers off.
    pub reach: f64,
}

/// Per new vertex, its correction N_new − mean_parents(N) (the whole slot),
/// or `None` where nothing is near; and the rays traced.
pub(super) struct Corrections {
    pub per_vertex: Vec<Option<Vec<f64>>>,
    pub rays: u64,
}

/// One near patch made ready to gather: its shot, pool and shape.
struct Source<'a> {
    shot: Shot<'a>,
    pool: SamplePool,
    quadrants: Option<QuadrantScale>,
}

impl<'a> NearGather<'a> {
    /// The corrections of the vertices `created` (see [`Corrections`]).
    pub fn corrections(
        &self,
        mesh: &Mesh,
        radiance: &[DVec3],
        d: &Directional,
        tables: &Tables,
        created: &[NewVertex],
    ) -> Corrections {
        let glossy =
            |nv: &NewVertex| d.lobes[mesh.vertices[nv.id as usize].surface as usize].is_some();
        if self.reach <= 0.0 || !created.iter().any(glossy) {
            return Corrections {
                per_vertex: vec![None; created.len()],
                rays: 0,
            };
        }
        let candidates = candidates(mesh, d);
        let near: Vec<Vec<u32>> = created
            .iter()
            .map(|nv| self.near_patches(mesh, d, &candidates, nv))
            .collect();
        let mut wanted: Vec<u32> = near.iter().flatten().copied().collect();
        wanted.sort_unstable();
        wanted.dedup();
        if wanted.is_empty() {
            return Corrections {
                per_vertex: vec![None; created.len()],
                rays: 0,
            };
        }
        let sources: Vec<Source> = wanted
            .par_iter()
            .map(|&p| self.source(mesh, radiance, d, p))
            .collect();
        let at = |p: u32| wanted.binary_search(&p).ok();
        let results: Vec<(Option<Vec<f64>>, u64)> = created
            .par_iter()
            .zip(&near)
            .map_init(DirScratch::default, |scratch, (nv, patches)| {
                if patches.is_empty() {
                    return (None, 0);
                }
                let shots: Vec<DirShot> = patches
                    .iter()
                    .filter_map(|&p| at(p))
                    .map(|i| dir_shot(&sources[i], d, tables, wanted[i] as usize, mesh))
                    .collect();
                let mut rays = 0;
                let mut got = Vec::new();
                let mut gather = |v: u32, scale: f64, out: &mut Vec<f64>| {
                    for s in &shots {
                        got.resize(d.vertex_slot(mesh, v as usize).len(), 0.0);
                        let who = Receiving::Vertex(v);
                        let (_, traced) = s.receive_into(mesh, self.kd, who, scratch, &mut got);
                        out.resize(got.len(), 0.0);
                        for (o, c) in out.iter_mut().zip(&got) {
                            *o += scale * c;
                        }
                        rays += traced as u64;
                    }
                };
                let mut correction = Vec::new();
                gather(nv.id, 1.0, &mut correction);
                let share = -1.0 / nv.parent_count as f64;
                for &parent in nv.parents() {
                    gather(parent, share, &mut correction);
                }
                (Some(correction), rays)
            })
            .collect();
        let rays = results.iter().map(|r| r.1).sum();
        Corrections {
            per_vertex: results.into_iter().map(|r| r.0).collect(),
            rays,
        }
    }

    /// The patches new vertex `nv` gathers: those of `candidates` (holding
    /// shot light) on another surface and nearer than the reach; none unless
    /// its surface is glossy. In ascending patch order.
    fn near_patches(
        &self,
        mesh: &Mesh,
        d: &Directional,
        candidates: &[Candidate],
        nv: &NewVertex,
    ) -> Vec<u32> {
        let x = mesh.vertices[nv.id as usize].position;
        let surface = mesh.vertices[nv.id as usize].surface;
        let Some(lobe) = d.lobes[surface as usize].as_deref() else {
            return Vec::new();
        };
        if self.reach <= 0.0 {
            return Vec::new();
        }
        let span = 2.0
            * nv.parents()
                .iter()
                .map(|&p| (mesh.vertices[p as usize].position - x).length())
                .fold(0.0, f64::max);
        let reach = self.reach * span / lobe.alpha;
        candidates
            .iter()
            .filter(|c| c.surface != surface && (c.centre - x).length() - c.radius < reach)
            .map(|c| c.patch)
            .collect()
    }

    /// Patch `p` as a gather source: the sum it has shot, from a pool of its
    /// own, shaped by its light now.
    fn source(&self, mesh: &Mesh, radiance: &[DVec3], d: &Directional, p: u32) -> Source<'a> {
        let order = d.surface_order[mesh.patches[p as usize].surface as usize];
        let equivalent = d.hemisphere_equivalent(order, d.shot_sum(mesh, p as usize));
        let shot = Shot::for_patch(
            mesh,
            p,
            GATHER_INDEX + p as u64,
            equivalent,
            self.settings,
            self.occluder,
            self.kd,
        );
        let pool = SamplePool::with_sets(&shot, GATHER_POOL_SETS);
        let quadrants = if self.settings.shoots_uniformly() {
            None
        } else {
            let view = ShapeView {
                mesh,
                patch_weights: self.patch_weights,
                hidden: self.hidden,
                radiance,
                emission: self.emission,
            };
            quadrant_scale(view, p, &shot)
        };
        Source {
            shot,
            pool,
            quadrants,
        }
    }
}

/// A patch that has shot light in an unrecorded shot, with the bounds the
/// reach test reads (found once per refinement level, not per vertex).
struct Candidate {
    patch: u32,
    surface: u32,
    centre: DVec3,
    /// The largest distance from the centre to a corner.
    radius: f64,
}

fn candidates(mesh: &Mesh, d: &Directional) -> Vec<Candidate> {
    (0..mesh.patches.len())
        .filter(|&p| d.has_shot(mesh, p))
        .map(|p| {
            let patch = &mesh.patches[p];
            let (centre, radius) = bounding_sphere(patch.polygon());
            Candidate {
                patch: p as u32,
                surface: patch.surface,
                centre,
                radius,
            }
        })
        .collect()
}

fn dir_shot<'s>(
    source: &'s Source,
    d: &'s Directional,
    tables: &'s Tables,
    p: usize,
    mesh: &Mesh,
) -> DirShot<'s> {
    let surface = source.shot.source_surface as usize;
    DirShot {
        shot: &source.shot,
        pool: &source.pool,
        unshot: d.shot_sum(mesh, p),
        source_order: tables.surface_order[surface],
        source_tangent: tables.tangent[surface],
        tables,
        quadrants: source.quadrants.as_ref(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::Preset;
    use crate::solve::Solver;

    /// The glossy floor room (`config/glossy_floor.toml`: a glossy floor, a
    /// small light under the ceiling near the back wall) on a 16 × 16 patch
    /// grid, solved for `shots` shots without refinement, so that every
    /// vertex received every shot itself. Uniform shooters, so a shot and a
    /// gather of the same patch spread its light alike. The preset's grouped
    /// shooters (the walls' patches shoot in groups, `directional/group.rs`)
    /// with 2,048 rays a receiver: at the preset's 16 the vertex's own light
    /// from the groups, the truth here, was 17% off its gather by the
    /// groups' noise alone.
    fn solved_room(shots: u64) -> Solver {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/glossy_floor.toml");
        let loaded = crate::scene::load_scene(&path, &Default::default()).unwrap();
        let mut settings = SolverSettings::preset(Preset::Draft);
        settings.apply(&loaded.settings);
        settings.samples = 64;
        settings.adaptive = false;
        settings.uniform_shooters = true;
        settings.full_rays_above = 0.0;
        settings.max_shots = shots;
        settings.group_samples = 2048;
        let mut scene = loaded.scene;
        scene.fill_default_patches(16);
        let mut solver = Solver::new(&scene, &settings).unwrap();
        while solver.step().is_some() {}
        solver
    }

    fn gather_of(solver: &Solver, reach: f64) -> NearGather<'_> {
        NearGather {
            patch_weights: &solver.patches.weights,
            hidden: &solver.field.hidden,
            emission: &solver.materials.emission,
            settings: &solver.settings,
            occluder: &solver.occluder,
            kd: &solver.materials.kd,
            reach,
        }
    }

    /// The floor vertex nearest (x, 0, z) (scene coordinates).
    fn floor_vertex(solver: &Solver, d: &Directional, x: f64, z: f64) -> u32 {
        let at = DVec3::new(x, 0.0, z) - solver.scene.offset;
        let (v, _) = (solver.mesh.vertices.iter().enumerate())
            .filter(|(_, mv)| d.lobes[mv.surface as usize].is_some())
            .map(|(v, mv)| (v, (mv.position - at).length()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        v as u32
    }

    /// Three floor vertices in a line toward the back wall, 0.25 m apart, as
    /// if a split had created the middle one between the other two.
    fn midpoint_toward_back_wall(solver: &Solver, d: &Directional) -> NewVertex {
        let [a, m, b] = [-1.75, -1.5, -1.25].map(|z| floor_vertex(solver, d, 0.0, z));
        NewVertex {
            id: m,
            parents: [a, b, 0, 0],
            parent_count: 2,
            uv: [0, 0],
        }
    }

    /// Vertex `v`'s light from unrecorded shots: its radiance less the
    /// recorded (emitter) shots' part (the floor emits nothing, and between
    /// shots nothing is received).
    fn unrecorded(d: &Directional, mesh: &Mesh, v: u32) -> Vec<f64> {
        let slot = d.vertex_slot(mesh, v as usize);
        slot.map(|k| d.radiance[k] - d.direct[k]).collect()
    }

    fn distance(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    #[test]
    fn a_gathered_midpoint_matches_a_vertex_that_received_every_shot() {
        // Three floor vertices in a line toward the back wall, 0.25 m apart:
        // the middle one is treated as if a split had created it between the
        // other two. It received every shot itself, so its unrecorded light
        // is the truth the new vertex should get. By linearity a gather of
        // each patch's shot sum delivers what its shots delivered, in
        // expectation; the room is convex, so the only noise is the jitter of
        // 64 stratified directions per source, each shot's and the gather's.
        let solver = solved_room(40);
        let d = solver.directional.as_deref().unwrap();
        let mesh = &solver.mesh;
        let nv = midpoint_toward_back_wall(&solver, d);
        let (m, [a, b]) = (nv.id, [nv.parents[0], nv.parents[1]]);
        let tables = Tables::new(d, mesh);
        // A reach past the room: every patch that has shot is near.
        let got =
            gather_of(&solver, 1e3).corrections(mesh, &solver.field.radiance, d, &tables, &[nv]);
        let correction = got.per_vertex[0].clone().expect("the floor vertex gathers");
        assert!(got.rays > 0);
        let truth = unrecorded(d, mesh, m);
        let (ua, ub) = (unrecorded(d, mesh, a), unrecorded(d, mesh, b));
        let interpolated: Vec<f64> = ua.iter().zip(&ub).map(|(x, y)| 0.5 * (x + y)).collect();
        let gathered: Vec<f64> = interpolated
            .iter()
            .zip(&correction)
            .map(|(x, c)| x + c)
            .collect();
        // Relative L2 errors over the sphere (Parseval: the coefficients'
        // Euclidean distance), all channels together.
        let norm = distance(&truth, &vec![0.0; truth.len()]);
        let interpolation_error = distance(&interpolated, &truth) / norm;
        let gather_error = distance(&gathered, &truth) / norm;
        eprintln!("interpolated {interpolation_error:.4}, gathered {gather_error:.4}");
        // The two parents see the back wall's lit band under different
        // angles, so their average is a different reflection.
        assert!(interpolation_error > 0.05, "{interpolation_error}");
        // Tolerance: 2%, seven times the directions' jitter measured with
        // one patch a shot (0.12-0.28% over seeds 1-4), far below the
        // interpolation's error (31% for every seed); with the groups'
        // rays, glossy floor patches among them, 0.94% (interpolation 6.5%).
        assert!(gather_error < 0.02, "{gather_error}");
    }

    #[test]
    fn only_glossy_vertices_gather_and_only_from_near_patches_of_other_surfaces() {
        let solver = solved_room(40);
        let d = solver.directional.as_deref().unwrap();
        let mesh = &solver.mesh;
        let nv = midpoint_toward_back_wall(&solver, d);
        let m = nv.id;
        // Reach 0.3 spans of 0.5 m over α = 0.1: 1.5 m.
        let near = gather_of(&solver, 0.3).near_patches(mesh, d, &candidates(mesh, d), &nv);
        let shot = (0..mesh.patches.len())
            .filter(|&p| d.has_shot(mesh, p))
            .count();
        assert!(
            !near.is_empty() && near.len() < shot,
            "{} of {shot}",
            near.len()
        );
        let x = mesh.vertices[m as usize].position;
        let floor = mesh.vertices[m as usize].surface;
        for &p in &near {
            let patch = &mesh.patches[p as usize];
            assert_ne!(patch.surface, floor);
            assert!(d.has_shot(mesh, p as usize));
            // Its centre within the reach plus its circumradius.
            let (centre, radius) = bounding_sphere(patch.polygon());
            let from = (centre - x).length();
            assert!(from < 1.5 + radius, "patch {p}: centre {from} m away");
        }
        // And every other patch of another surface that has shot is out of
        // reach: the near set is exactly the rule's.
        for p in (0..mesh.patches.len()).filter(|&p| d.has_shot(mesh, p)) {
            let patch = &mesh.patches[p];
            if patch.surface == floor || near.contains(&(p as u32)) {
                continue;
            }
            let (centre, radius) = bounding_sphere(patch.polygon());
            let from = (centre - x).length();
            assert!(from >= 1.5 + radius, "patch {p} left out at {from} m");
        }
        // Switched off, or on a diffuse wall, nothing gathers.
        assert!(gather_of(&solver, 0.0)
            .near_patches(mesh, d, &candidates(mesh, d), &nv)
            .is_empty());
        let wall = (0..mesh.vertices.len() as u32)
            .find(|&v| d.lobes[mesh.vertices[v as usize].surface as usize].is_none())
            .unwrap();
        let on_wall = NewVertex { id: wall, ..nv };
        assert!(gather_of(&solver, 1e3)
            .near_patches(mesh, d, &candidates(mesh, d), &on_wall)
            .is_empty());
    }
}
