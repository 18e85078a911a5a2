//! Default views that show the scene: where to put the eye when a scene brings
//! no camera.
//!
//! The old default framed the bounding box from outside it, which shows nothing
//! of a closed room but its outer walls' backs. This module chooses an eye
//! inside the enclosed space that sees lit surfaces:
//!
//! 1. **Candidates**: a 4 × 4 × 3 grid over the bounds (two horizontal axes by
//!    the vertical one), each point jittered inside its cell by a fixed hash (so
//!    the choice is deterministic), plus the bounds' centre: 49 points.
//! 2. **Standing**: from each, a ray straight down. If it meets a front face (a
//!    floor), the eye goes [`EYE_HEIGHT_M`] × `units_per_metre` above that point,
//!    or [`EYE_HEIGHT_FRACTION`] of the way to the ceiling (the first surface
//!    straight up) when the room is lower than that; otherwise the point stays
//!    where it is.
//! 3. **Survey**: [`RAYS`] directions on a Fibonacci sphere (González 2010,
//!    "Measurement of areas on a sphere using Fibonacci and latitude–longitude
//!    lattices") from the eye. A candidate is kept when at least
//!    [`MIN_FRONT_FRACTION`] of them meet front faces, at most
//!    [`MAX_BACK_FRACTION`] meet back faces (rays from inside a closed object,
//!    or from outside a closed room, meet backs), and no surface is nearer than
//!    [`MIN_CLEARANCE_M`] (capped at 2% of the bounds' diagonal for small
//!    scenes).
//! 4. **Score**: first how the eye stands (a full eye height above a floor,
//!    then lower under a low ceiling, then no floor below), then the mean
//!    luminance the rays see (each front hit's vertex radiance interpolated,
//!    the L = 0 term only; escaped and back rays see 0). The highest wins; ties
//!    go to the earlier candidate.
//! 5. **Heading**: level, toward the one of 16 headings whose 40° cone gathers
//!    the most luminance × distance, so the view looks across the room toward
//!    the light rather than into the nearest wall.
//!
//! When no candidate is kept (an object seen from outside, an open terrain) the
//! caller keeps its framing camera. Cost: one BVH build over the triangles,
//! O(n log n), then 49 × ([`RAYS`] + 2) rays of O(log n) each; measured in
//! docs/benchmarks.md ("Default view", `solver/examples/default_view_cost.rs`).
//!
//! **Where the choice is made.** The solver makes it once, at solve time, from
//! the solution it writes, and stores it as the header camera when the scene
//! names no camera (`solver/src/solve/output.rs`). Chosen there rather than in
//! the runtime because the header always holds a camera, and telling an
//! authored one from a defaulted one would need a new header field (a minor
//! format version) that every reader must learn; and because every viewer
//! (`screenshot`, `mirror`, `xr`, `bench`, the solver's `--preview`) then shows
//! the same view with no start-up cost. The figures the runtime's help states
//! ([`EYE_HEIGHT_M`] and the others) stay in the contract crate
//! (`solution::view`), with the triangle BVH and the test room. Files solved
//! before the chooser keep the framing camera they were written with. The XR
//! start pose needs nothing more: in STAGE space the runtime puts the floor
//! `camera_eye_height_m` (default [`EYE_HEIGHT_M`]) below the header eye, which
//! is the floor found here.
//!
//! **Two BVHs.** The rays go through the contract crate's small BVH
//! (`solution::view::bvh`), not the solver's occlusion BVH
//! (`crate::geometry::visibility::Occluder`): they are cast at the solution the
//! solver writes (the mesh's f32 re-centred triangles with their vertex
//! radiance, where the occluder holds the input polygons), through the same
//! hierarchy the runtime will use for collision and teleport, so the floor
//! found here is the floor the runtime finds. The occluder's widened edges and
//! epsilon window, tuned for conservative any-hit occlusion, would also move
//! chosen eyes, so the same scene would get another header camera than before.

#[cfg(test)]
mod tests;

use glam::{DVec3, Vec3};
use solution::camera::{Camera, UpAxis};
use solution::format::{Representation, Solution};
use solution::view::bvh::{Bvh, Hit};
use solution::view::{
    EYE_HEIGHT_FRACTION, EYE_HEIGHT_M, FOV_Y_DEG, GRID, MAX_BACK_FRACTION, MIN_CLEARANCE_M,
    MIN_FRONT_FRACTION, RAYS,
};

/// Headings tried for the view direction.
const HEADINGS: usize = 16;
/// Half-angle of a heading's cone, degrees.
const HEADING_CONE_DEG: f64 = 40.0;

/// Rec. 709 luminance weights (linear RGB).
const LUMA: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// A solution's triangles with their corners' luminance, ready for rays.
pub struct ViewScene {
    bvh: Bvh,
    /// Per triangle, its three corners' luminance.
    luminance: Vec<[f32; 3]>,
    lo: Vec3,
    hi: Vec3,
}

impl ViewScene {
    /// Triangles (file coordinates) with per-corner luminance; `lo`, `hi` bound
    /// where candidates are sampled.
    pub fn new(triangles: Vec<[Vec3; 3]>, luminance: Vec<[f32; 3]>, lo: Vec3, hi: Vec3) -> Self {
        assert_eq!(triangles.len(), luminance.len());
        ViewScene {
            bvh: Bvh::build(triangles),
            luminance,
            lo,
            hi,
        }
    }

    /// Every batch's triangles, each vertex's luminance from its mean radiance:
    /// the L = 0 term of an SH batch (c₀₀ · Y₀₀), the mean of a cube batch's
    /// directions. Indices out of range (which a validated solution does not
    /// hold) drop their triangle.
    pub fn from_solution(solution: &Solution) -> Self {
        let mut triangles = Vec::new();
        let mut luminance = Vec::new();
        for batch in &solution.batches {
            let per_channel = batch.representation.coefficients_per_channel() as usize;
            let vertex_luminance: Vec<f32> = (0..batch.vertices.len())
                .map(|v| {
                    let at = |k: usize, c: usize| {
                        batch
                            .coefficients
                            .get((v * per_channel + k) * 3 + c)
                            .copied()
                            .unwrap_or(0.0)
                    };
                    let rgb = |c: usize| match batch.representation {
                        Representation::Sh { .. } => at(0, c) * solution::sh::Y00 as f32,
                        Representation::Cube { .. } => {
                            (0..per_channel).map(|k| at(k, c)).sum::<f32>()
                                / per_channel.max(1) as f32
                        }
                    };
                    (0..3).map(|c| LUMA[c] * rgb(c)).sum::<f32>().max(0.0)
                })
                .collect();
            for corners in batch.indices.chunks_exact(3) {
                let get = |i: u32| batch.vertices.get(i as usize);
                if let (Some(a), Some(b), Some(c)) =
                    (get(corners[0]), get(corners[1]), get(corners[2]))
                {
                    triangles.push([a.position, b.position, c.position].map(Vec3::from));
                    luminance.push([0, 1, 2].map(|k| vertex_luminance[corners[k] as usize]));
                }
            }
        }
        ViewScene::new(
            triangles,
            luminance,
            Vec3::from(solution.header.bounds_min),
            Vec3::from(solution.header.bounds_max),
        )
    }

    pub fn triangle_count(&self) -> usize {
        self.bvh.triangle_count()
    }

    /// The closest hit along a unit direction.
    pub fn cast(&self, origin: DVec3, direction: DVec3) -> Option<Hit> {
        self.bvh
            .closest(origin.as_vec3(), direction.as_vec3(), f32::INFINITY)
    }

    /// The luminance at a hit, interpolated from its triangle's corners.
    fn luminance_at(&self, hit: &Hit) -> f64 {
        let [a, b, c] = self.luminance[hit.triangle as usize];
        (a * (1.0 - hit.u - hit.v) + b * hit.u + c * hit.v) as f64
    }

    fn diagonal(&self) -> f64 {
        (self.hi - self.lo).as_dvec3().length()
    }
}

/// The chosen view, in file (re-centred) coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DefaultView {
    pub eye: DVec3,
    pub target: DVec3,
    /// Where the downward ray from the eye met a floor, if it did.
    pub floor: Option<DVec3>,
    /// Of the survey rays: fractions that met front faces, back faces, nothing.
    pub front_fraction: f64,
    pub back_fraction: f64,
    pub escaped_fraction: f64,
    /// Mean luminance the survey rays saw.
    pub score: f64,
    /// Candidates tried, and kept by the survey's rules.
    pub candidates: usize,
    pub kept: usize,
}

impl DefaultView {
    /// The camera in original scene coordinates (the header's convention), with
    /// [`FOV_Y_DEG`] and the given image size.
    pub fn camera(&self, recentre_offset: DVec3, up: UpAxis, width: u32, height: u32) -> Camera {
        Camera {
            eye: (self.eye + recentre_offset).to_array(),
            target: (self.target + recentre_offset).to_array(),
            up: up.vector(),
            fov_y_deg: FOV_Y_DEG,
            width,
            height,
        }
    }
}

/// The most memory [`default_camera`] holds beside the solution over
/// `triangles` triangles: the hierarchy being built
/// ([`Bvh::bytes_per_triangle`]) and each triangle's corner luminance;
/// 85 bytes a triangle. The solver's memory estimate adds it to the output's
/// peak when the scene names no camera.
pub fn transient_bytes(triangles: u64) -> u64 {
    triangles * (Bvh::bytes_per_triangle() + std::mem::size_of::<[f32; 3]>() as u64)
}

/// The camera for a solution whose scene names none: the chosen view if a
/// candidate passes, else `framing` (the solver's camera outside the bounds),
/// whose image size the chosen view keeps.
pub fn default_camera(solution: &Solution, framing: Camera) -> Camera {
    let scene = ViewScene::from_solution(solution);
    let header = &solution.header;
    match choose_view(&scene, header.up_axis, header.units_per_metre) {
        Some(view) => view.camera(
            DVec3::from(header.recentre_offset),
            header.up_axis,
            framing.width,
            framing.height,
        ),
        None => framing,
    }
}

/// What a candidate's survey saw.
struct Survey {
    front: usize,
    back: usize,
    escaped: usize,
    nearest: f64,
    luminance_sum: f64,
    /// (direction, distance, luminance) of each front hit.
    hits: Vec<(DVec3, f64, f64)>,
}

/// A candidate that passed the survey: its rank (how it stands, then the mean
/// luminance seen), where it stands, and what it saw.
struct Kept {
    rank: (Standing, f64),
    eye: DVec3,
    floor: Option<DVec3>,
    survey: Survey,
}

/// Chooses the view (module notes), or `None` when no candidate passes.
pub fn choose_view(scene: &ViewScene, up: UpAxis, units_per_metre: f64) -> Option<DefaultView> {
    if scene.triangle_count() == 0 {
        return None;
    }
    let up_vector = DVec3::from(up.vector());
    let directions = fibonacci_sphere(RAYS, up_vector);
    let clearance = (MIN_CLEARANCE_M * units_per_metre).min(0.02 * scene.diagonal());
    let candidates = candidates(scene, up);
    let mut kept = 0;
    let mut best: Option<Kept> = None;
    for point in &candidates {
        let (eye, floor, standing) = stand(scene, *point, up_vector, units_per_metre);
        let survey = survey(scene, eye, &directions);
        let n = directions.len() as f64;
        if (survey.front as f64) < MIN_FRONT_FRACTION * n
            || (survey.back as f64) > MAX_BACK_FRACTION * n
            || survey.nearest < clearance
        {
            continue;
        }
        kept += 1;
        // How the eye stands first, then light: see [`Standing`].
        let rank = (standing, survey.luminance_sum / n);
        if best.as_ref().is_none_or(|b| rank > b.rank) {
            best = Some(Kept {
                rank,
                eye,
                floor,
                survey,
            });
        }
    }
    let Kept {
        rank: (_, score),
        eye,
        floor,
        survey,
    } = best?;
    let n = directions.len() as f64;
    Some(DefaultView {
        eye,
        target: eye + heading(&survey, up_vector) * mean_distance(&survey),
        floor,
        front_fraction: survey.front as f64 / n,
        back_fraction: survey.back as f64 / n,
        escaped_fraction: survey.escaped as f64 / n,
        score,
        candidates: candidates.len(),
        kept,
    })
}

/// The jittered grid and the bounds' centre (module notes, step 1).
fn candidates(scene: &ViewScene, up: UpAxis) -> Vec<DVec3> {
    let (lo, hi) = (scene.lo.as_dvec3(), scene.hi.as_dvec3());
    let vertical = match up {
        UpAxis::PosY | UpAxis::NegY => 1,
        UpAxis::PosZ | UpAxis::NegZ => 2,
    };
    let axes: [usize; 3] = match vertical {
        1 => [0, 2, 1],
        _ => [0, 1, 2],
    };
    let mut points = Vec::with_capacity(GRID.iter().product::<usize>() + 1);
    let mut index: u64 = 0;
    for k in 0..GRID[2] {
        for j in 0..GRID[1] {
            for i in 0..GRID[0] {
                let cell = [i, j, k];
                let mut p = DVec3::ZERO;
                for (g, &axis) in axes.iter().enumerate() {
                    // Jitter within the middle half of the cell: ±0.25 of it.
                    let jitter = 0.5 * unit_hash(index * 3 + g as u64) - 0.25;
                    let f = (cell[g] as f64 + 0.5 + jitter) / GRID[g] as f64;
                    p[axis] = lo[axis] + f * (hi[axis] - lo[axis]);
                }
                points.push(p);
                index += 1;
            }
        }
    }
    points.push((lo + hi) * 0.5);
    points
}

/// A fixed hash of `n` to [0, 1): SplitMix64's finaliser (Steele, Lea and
/// Flood 2014), so candidates are the same on every machine.
fn unit_hash(n: u64) -> f64 {
    let mut z = n.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

/// How a candidate eye stands, the first key of the ranking: an eye a full
/// [`EYE_HEIGHT_M`] above a floor beats one that a low ceiling pushed lower,
/// which beats one with no floor below it, whatever they see. So wherever a
/// person fits, the view is a person's, and the XR start pose (in STAGE space
/// the runtime puts the floor `camera_eye_height_m`, default [`EYE_HEIGHT_M`],
/// below the header eye) has its feet on the floor found here.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Standing {
    Floating,
    Stooping,
    Upright,
}

/// Step 2: the eye above the floor below `point`, or `point` when no floor's
/// front is straight below it.
fn stand(
    scene: &ViewScene,
    point: DVec3,
    up: DVec3,
    units_per_metre: f64,
) -> (DVec3, Option<DVec3>, Standing) {
    let Some(down) = scene.cast(point, -up).filter(|h| h.front) else {
        return (point, None, Standing::Floating);
    };
    let floor = point - up * down.t as f64;
    // Start the upward ray a little above the floor so it does not meet it.
    let lift = 1e-5 * scene.diagonal().max(f64::MIN_POSITIVE);
    let ceiling = scene
        .cast(floor + up * lift, up)
        .map_or(f64::INFINITY, |h| h.t as f64 + lift);
    let full = EYE_HEIGHT_M * units_per_metre;
    let cap = EYE_HEIGHT_FRACTION * ceiling;
    if full <= cap {
        (floor + up * full, Some(floor), Standing::Upright)
    } else {
        (floor + up * cap, Some(floor), Standing::Stooping)
    }
}

/// Step 3: the survey rays from `eye`.
fn survey(scene: &ViewScene, eye: DVec3, directions: &[DVec3]) -> Survey {
    let mut s = Survey {
        front: 0,
        back: 0,
        escaped: 0,
        nearest: f64::INFINITY,
        luminance_sum: 0.0,
        hits: Vec::with_capacity(directions.len()),
    };
    for &d in directions {
        match scene.cast(eye, d) {
            None => s.escaped += 1,
            Some(hit) => {
                s.nearest = s.nearest.min(hit.t as f64);
                if hit.front {
                    let l = scene.luminance_at(&hit);
                    s.front += 1;
                    s.luminance_sum += l;
                    s.hits.push((d, hit.t as f64, l));
                } else {
                    s.back += 1;
                }
            }
        }
    }
    s
}

/// Step 5: the level heading whose cone gathers the most luminance × distance
/// (distance alone where nothing is lit).
fn heading(survey: &Survey, up: DVec3) -> DVec3 {
    let (a, b) = up.any_orthonormal_pair();
    let cos_cone = HEADING_CONE_DEG.to_radians().cos();
    let lit = survey.hits.iter().any(|h| h.2 > 0.0);
    let mut best = (f64::NEG_INFINITY, a);
    for k in 0..HEADINGS {
        let angle = k as f64 * std::f64::consts::TAU / HEADINGS as f64;
        let h = a * angle.cos() + b * angle.sin();
        let weight: f64 = survey
            .hits
            .iter()
            .filter(|(d, _, _)| d.dot(h) >= cos_cone)
            .map(|&(_, t, l)| if lit { l * t } else { t })
            .sum();
        if weight > best.0 {
            best = (weight, h);
        }
    }
    best.1
}

/// The mean distance of the front hits (1 when there are none), so the target
/// lies about where the view's surfaces are.
fn mean_distance(survey: &Survey) -> f64 {
    if survey.hits.is_empty() {
        return 1.0;
    }
    let d = survey.hits.iter().map(|h| h.1).sum::<f64>() / survey.hits.len() as f64;
    if d > 0.0 && d.is_finite() {
        d
    } else {
        1.0
    }
}

/// `n` unit directions on the Fibonacci sphere, poles along `axis`: point i at
/// height z = 1 − (2i + 1)/n, turned by the golden angle π(3 − √5) each step.
pub fn fibonacci_sphere(n: usize, axis: DVec3) -> Vec<DVec3> {
    let (a, b) = axis.any_orthonormal_pair();
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2 * i + 1) as f64 / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = golden * i as f64;
            a * (r * phi.cos()) + b * (r * phi.sin()) + axis * z
        })
        .collect()
}
