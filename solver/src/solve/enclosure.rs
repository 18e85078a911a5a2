//! How enclosed a receiving point is: the cosine-weighted fraction ε of its
//! hemisphere that meets a surface, for the ambient term weighted by
//! enclosure ([`super::Solver::enclosed_ambient`], `output.rs`).
//!
//! Cohen, Chen, Wallace and Greenberg's (1988) ambient term spreads the light
//! not yet shot uniformly over a closed room: every point gets ρ · R · Ū. A
//! point that looks partly out of the scene (the Cornell box's short block
//! faces the open front) receives that light only from the part of its
//! hemisphere that meets a surface: its first bounce of the uniform unshot
//! radiance Ū is the irradiance ε · π · Ū, not π · Ū. The output keeps the
//! total of Cohen's estimate over the surfaces (it is an estimate of how much
//! light is left, not of where it lands) and redistributes it by enclosure:
//! each vertex shows Cohen's term times ε_v / ε̄, with ε̄ the area-weighted
//! mean of ε over the patches' centroids. A closed room has ε = 1 everywhere
//! and keeps Cohen's term exactly.

use crate::geometry::visibility::Occluder;
use glam::DVec3;
use std::sync::Mutex;

/// ε per mesh vertex and the patches' mean ε̄, kept between the files a solve
/// writes. Vertices never move and patches never change, so each is probed
/// once: before, every partial solution probed every vertex again (64 rays
/// each), which on the large scale scenes cost as much as hundreds of shots
/// per checkpoint. Values are stored as f32, exact for ε = k / 64; NaN marks
/// a vertex not probed yet. 4 bytes a vertex (`budget.rs`, vertex state).
#[derive(Debug, Default)]
pub struct EnclosureCache {
    state: Mutex<CacheState>,
}

#[derive(Debug, Default)]
struct CacheState {
    mean: Option<f64>,
    per_vertex: Vec<f32>,
}

impl EnclosureCache {
    /// Grows the per-vertex slots to `vertices` (new ones not probed).
    pub fn catch_up(&mut self, vertices: usize) {
        let state = self.state.get_mut().unwrap_or_else(|e| e.into_inner());
        if state.per_vertex.len() < vertices {
            state.per_vertex.resize(vertices, f32::NAN);
        }
    }

    /// The per-vertex slots (tests of the memory estimate).
    #[cfg(test)]
    pub fn slots(&mut self) -> usize {
        let state = self.state.get_mut().unwrap_or_else(|e| e.into_inner());
        state.per_vertex.len()
    }

    /// ε̄, computed by `mean` on first use.
    pub fn mean(&self, mean: impl FnOnce() -> f64) -> f64 {
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        *state.mean.get_or_insert_with(mean)
    }

    /// ε at each of `vertices` (mesh vertex ids below `count`, the mesh's
    /// vertex count), probing with `probe` only those not probed before.
    pub fn at(
        &self,
        count: usize,
        vertices: &[u32],
        probe: impl Fn(u32) -> f64 + Sync,
    ) -> Vec<f64> {
        use rayon::prelude::*;
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        if state.per_vertex.len() < count {
            state.per_vertex.resize(count, f32::NAN);
        }
        let mut missing: Vec<u32> = vertices
            .iter()
            .copied()
            .filter(|&v| state.per_vertex[v as usize].is_nan())
            .collect();
        missing.sort_unstable();
        missing.dedup();
        let probed: Vec<f64> = missing.par_iter().map(|&v| probe(v)).collect();
        for (&v, &e) in missing.iter().zip(&probed) {
            state.per_vertex[v as usize] = e as f32;
        }
        vertices
            .iter()
            .map(|&v| state.per_vertex[v as usize] as f64)
            .collect()
    }
}

/// Probe rays per point. The directions are a fixed cosine-weighted
/// Hammersley set, the same at every point, so ε varies smoothly over a
/// surface (no noise between neighbouring vertices); its error against the
/// exact fraction is that of a 64-point quadrature, one or two probes (2-3%)
/// where a silhouette crosses the hemisphere.
pub const PROBES: u32 = 64;

/// ε at receiving point `q` with unit normal `n`: the share of [`PROBES`]
/// cosine-distributed rays from `q` (lifted the occluder's epsilon along
/// `n`) that meet any surface, front or back.
pub fn enclosure(occluder: &Occluder, q: DVec3, n: DVec3) -> f64 {
    let origin = q + n * occluder.scene_epsilon();
    let t = n.any_orthonormal_vector();
    let b = n.cross(t);
    let hits = (0..PROBES)
        .filter(|&k| {
            let dir = cosine_direction(k, t, b, n);
            occluder.closest_hit(origin, dir, f64::INFINITY).is_some()
        })
        .count();
    hits as f64 / PROBES as f64
}

/// The `k`-th of [`PROBES`] Hammersley points mapped to the cosine-weighted
/// hemisphere about `n` (Malley's method: uniform on the disc, projected up).
fn cosine_direction(k: u32, t: DVec3, b: DVec3, n: DVec3) -> DVec3 {
    let u = (k as f64 + 0.5) / PROBES as f64;
    let v = k.reverse_bits() as f64 / (1u64 << 32) as f64;
    let r = u.sqrt();
    let phi = std::f64::consts::TAU * v;
    (t * phi.cos() + b * phi.sin()) * r + n * (1.0 - u).max(0.0).sqrt()
}

/// Rays of the viewer's survey ([`dark_view_warning`]).
pub const VIEW_RAYS: usize = 256;
/// The view is dark when the mean luminance its survey sees is below this
/// fraction of the solution's area-weighted mean luminance. A viewer inside
/// a lit room sees about the mean (0.5 to 2 times it); a tenth of a percent
/// is a view with no light in it.
pub const DARK_VIEW_FRACTION: f64 = 1e-3;

/// Rec. 709 luminance of linear RGB.
fn luma(rgb: [f32; 3]) -> f64 {
    0.2126 * f64::from(rgb[0]) + 0.7152 * f64::from(rgb[1]) + 0.0722 * f64::from(rgb[2])
}

/// Per vertex of `batch`, the luminance it shows where its textures average
/// 1: the SH's L = 0 term (a cube's mean), plus a textured vertex's factor ⊙
/// E/π and an emission slot's factor. Textures are left out: the test below
/// asks whether light arrived at all, not how much.
fn vertex_luminance(batch: &solution::format::Batch) -> Vec<f64> {
    use solution::format::Representation;
    let per_channel = batch.representation.coefficients_per_channel() as usize;
    (0..batch.vertices.len())
        .map(|v| {
            let at = |k: usize, c: usize| {
                let i = (v * per_channel + k) * 3 + c;
                batch.coefficients.get(i).copied().unwrap_or(0.0)
            };
            let rgb = [0, 1, 2].map(|c| match batch.representation {
                Representation::Sh { .. } => at(0, c) * solution::sh::Y00 as f32,
                Representation::Cube { .. } => {
                    (0..per_channel).map(|k| at(k, c)).sum::<f32>() / per_channel.max(1) as f32
                }
            });
            let textured = batch.texturing.as_ref().map_or(0.0, |t| {
                let e = t.vertices.get(v).map_or([0.0; 3], |x| x.irradiance_over_pi);
                let reflected = luma([0, 1, 2].map(|c| t.factor[c] * e[c]));
                reflected + t.emission.as_ref().map_or(0.0, |slot| luma(slot.factor))
            });
            (luma(rgb) + textured).max(0.0)
        })
        .collect()
}

/// A warning when the light of a finished solve never reaches the viewer:
/// from the header camera's eye (the authored camera, or the default view),
/// [`VIEW_RAYS`] rays over the whole sphere see a mean luminance below
/// [`DARK_VIEW_FRACTION`] of the solution's area-weighted mean (front faces
/// only: a ray meeting a back face sees nothing, as from outside a closed
/// room), or no surface holds any light at all. Either way every emitter is
/// enclosed away from the view, or a closed shell around the scene took the
/// light of a sun, sky or lamp outside it (the importer names such a shell,
/// `scene::shell`). `None` for a view with light in it.
pub fn dark_view_warning(solution: &solution::format::Solution) -> Option<String> {
    use glam::Vec3;
    let mut triangles: Vec<[Vec3; 3]> = Vec::new();
    let mut corners: Vec<[f64; 3]> = Vec::new();
    let (mut sum, mut area) = (0.0, 0.0);
    for batch in &solution.batches {
        let luminance = vertex_luminance(batch);
        for tri in batch.indices.chunks_exact(3) {
            let get = |i: u32| {
                batch
                    .vertices
                    .get(i as usize)
                    .map(|v| Vec3::from(v.position))
            };
            let (Some(a), Some(b), Some(c)) = (get(tri[0]), get(tri[1]), get(tri[2])) else {
                continue;
            };
            let l = [0, 1, 2].map(|k| luminance.get(tri[k] as usize).copied().unwrap_or(0.0));
            let a_t = 0.5 * f64::from((b - a).cross(c - a).length());
            sum += a_t * (l[0] + l[1] + l[2]) / 3.0;
            area += a_t;
            triangles.push([a, b, c]);
            corners.push(l);
        }
    }
    let mean = if area > 0.0 { sum / area } else { 0.0 };
    let header = &solution.header;
    let eye = DVec3::from_array(header.camera.eye) - DVec3::from_array(header.recentre_offset);
    if mean <= 0.0 {
        return Some(
            "no surface of the solution holds any light, though the scene has lights: every              emitter is enclosed away from the rest, or a closed shell around the scene (a              skybox mesh?) took all the light of a sun, sky or lamp outside it; see the              import's warnings"
                .to_owned(),
        );
    }
    let bvh = solution::view::bvh::Bvh::build(triangles);
    let up = DVec3::from_array(header.up_axis.vector());
    let seen: f64 = crate::view::fibonacci_sphere(VIEW_RAYS, up)
        .iter()
        .filter_map(|d| bvh.closest(eye.as_vec3(), d.as_vec3(), f32::INFINITY))
        .filter(|hit| hit.front)
        .map(|hit| {
            let l = corners[hit.triangle as usize];
            let (u, v) = (f64::from(hit.u), f64::from(hit.v));
            l[0] * (1.0 - u - v) + l[1] * u + l[2] * v
        })
        .sum::<f64>()
        / VIEW_RAYS as f64;
    (seen < DARK_VIEW_FRACTION * mean).then(|| {
        format!(
            "the light does not reach the view: from the camera's eye ({:.3}, {:.3}, {:.3}) the \
             surroundings show a mean luminance of {seen:.3e}, against {mean:.3e} over all \
             surfaces. Every emitter is enclosed away from the view, or a closed shell around \
             the scene (a skybox mesh?) keeps the light of a sun, sky or lamp outside it from \
             reaching what is inside; see the import's warnings, or move the camera",
            header.camera.eye[0], header.camera.eye[1], header.camera.eye[2]
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vertex is probed once however many files ask for it, new vertices
    /// are probed when first asked, and the mean is computed once.
    #[test]
    fn the_cache_probes_each_vertex_once() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        let probes = AtomicUsize::new(0);
        let probe = |v: u32| {
            probes.fetch_add(1, Ordering::Relaxed);
            v as f64 / 64.0
        };
        let mut cache = EnclosureCache::default();
        cache.catch_up(4);
        assert_eq!(
            cache.at(4, &[0, 2, 2], probe),
            vec![0.0, 2.0 / 64.0, 2.0 / 64.0]
        );
        assert_eq!(probes.load(Ordering::Relaxed), 2);
        assert_eq!(
            cache.at(6, &[2, 5, 0], probe),
            vec![2.0 / 64.0, 5.0 / 64.0, 0.0]
        );
        assert_eq!(probes.load(Ordering::Relaxed), 3);
        assert_eq!(cache.slots(), 6);
        assert_eq!(cache.mean(|| 0.5), 0.5);
        assert_eq!(cache.mean(|| unreachable!("computed once")), 0.5);
    }

    fn quad(c: DVec3, e1: DVec3, e2: DVec3) -> Vec<DVec3> {
        vec![c, c + e1, c + e1 + e2, c + e2]
    }

    #[test]
    fn directions_are_unit_and_cosine_weighted() {
        // The mean of cos θ over a cosine-weighted hemisphere is 2/3; the
        // 64-point set's mean is within 1/64 of it (one ring of strata).
        let (t, b, n) = (DVec3::X, DVec3::Y, DVec3::Z);
        let mut mean = 0.0;
        for k in 0..PROBES {
            let d = cosine_direction(k, t, b, n);
            assert!((d.length() - 1.0).abs() < 1e-12, "{d}");
            assert!(d.z > 0.0);
            mean += d.z / PROBES as f64;
        }
        assert!((mean - 2.0 / 3.0).abs() < 1.0 / 64.0, "{mean}");
    }

    #[test]
    fn a_closed_box_encloses_and_a_lone_floor_does_not() {
        let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
        let o = DVec3::ZERO;
        let mut walls = vec![
            quad(o, z, x),
            quad(o + y, x, z),
            quad(o, y, z),
            quad(o + x, z, y),
            quad(o, x, y),
            quad(o + z, y, x),
        ];
        let centre_of_floor = DVec3::new(0.5, 0.0, 0.5);
        let closed = Occluder::new(&walls);
        assert_eq!(enclosure(&closed, centre_of_floor, y), 1.0);
        // Without its ceiling the box is open above: from the centre of the
        // floor the opening (a unit square one unit up) subtends the
        // point-to-parallel-rectangle factor, four corner rectangles of
        // a = b = 1/2 at height 1 (Howell's catalogue, B-3):
        // F = 4 · (1/2π) · 2 · a/√(1+a²) · atan(a/√(1+a²)) = 0.2395, so
        // ε = 1 − 0.2395, within two of the 64 probes: the opening's outline
        // cuts through about √64 = 8 of the set's strata, each of which may
        // count its point on the wrong side (measured 0.7813 against 0.7605,
        // 1.3 probes off).
        walls.remove(1);
        let open = Occluder::new(&walls);
        let a: f64 = 0.5;
        let s = (1.0 + a * a).sqrt();
        let opening = 4.0 / std::f64::consts::TAU * 2.0 * a / s * (a / s).atan();
        assert!((opening - 0.2395).abs() < 1e-4, "{opening}");
        let e = enclosure(&open, centre_of_floor, y);
        assert!((e - (1.0 - opening)).abs() < 2.0 / 64.0, "{e}");
        let lone = Occluder::new(&[quad(o, z, x)]);
        assert_eq!(enclosure(&lone, centre_of_floor, y), 0.0);
    }

    /// A unit cube room (walls Kd 0.5, the ceiling's centre patch a light),
    /// 2 × 2 patches a wall, without its z = 0 wall when `open`.
    fn cube_room(open: bool) -> crate::scene::Scene {
        use crate::solve::tests::{material, scene_of};
        let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
        let o = DVec3::ZERO;
        let mut polygons = vec![
            (quad(o, z, x), 0),
            (quad(o + y, x, z), 0),
            (quad(o, y, z), 0),
            (quad(o + x, z, y), 0),
            (quad(o + z, y, x), 0),
            (quad(DVec3::new(0.4, 0.999, 0.4), x * 0.2, z * 0.2), 1),
        ];
        if !open {
            polygons.push((quad(o, x, y), 0));
        }
        scene_of(
            polygons,
            vec![material("wall", 0.5, 0.0), material("light", 0.5, 10.0)],
            2,
        )
    }

    #[test]
    fn the_ambient_is_cohens_in_a_closed_room_and_weighted_by_enclosure_in_an_open_one() {
        use crate::settings::{Preset, SolverSettings};
        let mut settings = SolverSettings::preset(Preset::Draft);
        settings.adaptive = false;
        settings.samples = 4;
        let at = |open: bool| {
            let mut solver = crate::solve::Solver::new(&cube_room(open), &settings).unwrap();
            solver.step().unwrap();
            let ambient = solver.ambient();
            let all: Vec<u32> = (0..solver.mesh.vertices.len() as u32).collect();
            let shown = solver.enclosed_ambient(&all, ambient);
            let centre = |p: DVec3| {
                let v = solver
                    .mesh
                    .vertices
                    .iter()
                    .position(|v| (v.position + solver.scene.offset - p).length() < 1e-9)
                    .unwrap();
                shown[v].x / ambient.x
            };
            let (back, floor) = (
                centre(DVec3::new(0.5, 0.5, 1.0)),
                centre(DVec3::new(0.5, 0.0, 0.5)),
            );
            (ambient, shown, back, floor)
        };
        // Closed: every probe meets a wall, so every vertex shows Cohen's term
        // exactly.
        let (ambient, shown, _, _) = at(false);
        assert!(ambient.x > 0.0);
        assert!(shown.iter().all(|&a| a == ambient), "{shown:?}");
        // Open at z = 0: the back wall's centre faces the opening, a parallel
        // unit square one unit away (ε = 1 − 0.2395, as above); the floor's
        // centre sees it edge-on at half a unit, a larger share. Both are
        // shown ε / ε̄ of Cohen's term, so their ratio is the ratio of their
        // enclosures (each within two probes).
        let (_, _, back, floor) = at(true);
        let ratio = back / floor;
        // The floor centre's view of the opening: the exact point-to-polygon
        // factor (Lambert's formula, `geometry::formfactor`).
        let opening = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        let floor_open = crate::geometry::formfactor::point_to_polygon(
            DVec3::new(0.5, 0.0, 0.5),
            DVec3::Y,
            &opening,
        );
        let expected = (1.0 - 0.2395) / (1.0 - floor_open);
        assert!(
            (ratio - expected).abs() < 0.05,
            "{ratio} against {expected}"
        );
        assert!(back < 1.0 && floor < 1.2, "back {back}, floor {floor}");
    }

    /// A solve of `scene` at draft, to its end or 200 shots, as a solution.
    fn solved(scene: &crate::scene::Scene) -> solution::format::Solution {
        let mut settings = crate::settings::SolverSettings::preset(crate::settings::Preset::Draft);
        settings.max_shots = 200;
        let mut solver = crate::solve::Solver::new(scene, &settings).unwrap();
        while solver.step().is_some() {}
        solver.to_solution(false)
    }

    #[test]
    fn a_room_lit_only_by_a_sun_outside_its_closed_walls_warns_of_a_dark_view() {
        // The closed cube's walls face in: the sun outside meets only their
        // backs, so nothing inside receives any light.
        let mut scene = crate::solve::tests::scene_of(
            crate::solve::physics_tests::cube(4.0, DVec3::ZERO),
            vec![crate::solve::tests::material("wall", 0.5, 0.0)],
            2,
        );
        scene.lights = crate::solve::lights_tests::sun_lights(40.0, 100.0);
        let warning = dark_view_warning(&solved(&scene)).expect("a dark view warns");
        assert!(
            warning.contains("closed shell") && warning.contains("sun"),
            "{warning}"
        );
    }

    #[test]
    fn the_cornell_box_does_not_warn_of_a_dark_view() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/cornell_box.obj");
        let mut scene = crate::scene::load_scene(&path, &Default::default())
            .unwrap()
            .scene;
        scene.fill_default_patches(2);
        let solution = solved(&scene);
        assert_eq!(dark_view_warning(&solution), None);
        // The same solution seen from outside its back wall (facing away
        // from the box, every ray meets a back face or nothing) is dark.
        let mut outside = solution.clone();
        let (lo, hi) = (outside.header.bounds_min, outside.header.bounds_max);
        let offset = outside.header.recentre_offset;
        outside.header.camera.eye = [
            0.5 * (lo[0] + hi[0]) as f64 + offset[0],
            0.5 * (lo[1] + hi[1]) as f64 + offset[1],
            hi[2] as f64 + 10.0 * (hi[2] - lo[2]) as f64 + offset[2],
        ];
        assert!(dark_view_warning(&outside).is_some());
    }
}
