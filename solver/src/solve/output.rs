//! The solution the solver hands to the file writer (Remington 1992, Fig. 3.6 steps 5d and
//! 6), and the ambient term of the light not yet shot.

use super::hidden::{fill_hidden, rgb};
use super::seams::{share_vertices, Lone, Merge, SharedVertices};
use super::{enclosure, Solver};
use glam::DVec3;
use rayon::prelude::*;
use solution::camera::{Camera, UpAxis};
use solution::format::{
    Batch, Header, Representation, ScalarType, Solution, SolveMode, SolveStats, Vertex,
};
use std::f64::consts::PI;

/// Patches above which ε̄ is estimated from this many centroids instead of
/// all of them.
const MEAN_PROBES: usize = 1 << 16;

/// ε̄, the area-weighted mean of ε over the patches at their centroids
/// ([`enclosure`]). Up to [`MEAN_PROBES`] patches every one is probed; above,
/// [`MEAN_PROBES`] centroids are drawn by systematic sampling in proportion
/// to area (evenly spaced along the patches' cumulative area, a patch
/// larger than the spacing drawn as often as it spans it), whose plain mean
/// is an unbiased estimate of the area-weighted one, with a standard error
/// below 0.5 / √65,536 = 0.002 (ε lies in [0, 1]): a 1M-triangle scene
/// probed a million centroids, 64 rays each, for one factor of the ambient
/// term.
fn enclosure_mean(solver: &Solver) -> f64 {
    let mesh = &solver.mesh;
    let occluder = &solver.occluder;
    let at_centroid = |p: &crate::mesh::Patch| {
        let corners = p.polygon();
        let centroid = corners.iter().sum::<DVec3>() / corners.len() as f64;
        let normal = mesh.surfaces[p.surface as usize].normal;
        enclosure::enclosure(occluder, centroid, normal)
    };
    if mesh.patches.len() <= MEAN_PROBES {
        // Probed in parallel, summed in patch order: a parallel reduce would
        // add in an order set by work stealing, and the bits would depend on
        // the threads.
        let probes: Vec<f64> = mesh
            .patches
            .par_iter()
            .map(|p| at_centroid(p) * p.area)
            .collect();
        let area: f64 = mesh.patches.iter().map(|p| p.area).sum();
        let weighted: f64 = probes.iter().sum();
        return weighted / area;
    }
    let draws = systematic_draws(
        &mesh.patches.iter().map(|p| p.area).collect::<Vec<_>>(),
        MEAN_PROBES,
    );
    let drawn: u32 = draws.iter().map(|d| d.1).sum();
    // Summed in patch order, so the bits do not depend on the threads.
    let probes: Vec<f64> = draws
        .par_iter()
        .map(|&(k, count)| at_centroid(&mesh.patches[k]) * count as f64)
        .collect();
    let sum: f64 = probes.iter().sum();
    sum / drawn.max(1) as f64
}

/// `n` draws spaced evenly along the cumulative sum of `areas`, at
/// (j + ½) · Σ areas / n: per item drawn, (index, draws), in order.
fn systematic_draws(areas: &[f64], n: usize) -> Vec<(usize, u32)> {
    let step = areas.iter().sum::<f64>() / n as f64;
    let mut draws = Vec::new();
    let (mut start, mut next, mut drawn) = (0.0, 0.5 * step, 0usize);
    for (k, area) in areas.iter().enumerate() {
        let end = start + area;
        let mut count = 0;
        while next < end && drawn < n {
            count += 1;
            drawn += 1;
            next += step;
        }
        if count > 0 {
            draws.push((k, count));
        }
        start = end;
    }
    draws
}

impl Solver {
    /// The ambient radiance of Cohen, Chen, Wallace and Greenberg (1988), the
    /// term Remington's (1992) display file switches on (appendix A, line 8): the light not
    /// yet shot, spread uniformly and reflected by an average surface forever.
    ///
    /// With A_j the patch areas, U_j their unshot radiance and ρ_j their
    /// reflectance, per channel:
    ///
    /// ρ_avg = Σ ρ_j A_j / Σ A_j,  R = 1 / (1 − ρ_avg) = 1 + ρ_avg + ρ_avg² + …,
    /// ambient = R · Σ U_j A_j / Σ A_j   (= R · Σ unshot power / (π Σ A_j)),
    ///
    /// and a vertex of reflectance ρ_i is displayed as L_i + ρ_i · ambient. The
    /// term goes to zero as the unshot power does. R is capped at 1e6 (ρ_avg
    /// within 1e-6 of 1), where the true sum diverges.
    pub fn ambient(&self) -> DVec3 {
        let mut area = 0.0;
        let mut reflect = DVec3::ZERO;
        let mut unshot = DVec3::ZERO;
        for ((p, u), a) in self
            .mesh
            .patches
            .iter()
            .zip(&self.patches.unshot)
            .zip(&self.patches.shoot_area)
        {
            area += p.area;
            reflect += self.materials.albedo[p.surface as usize] * p.area;
            unshot += *u * *a;
        }
        if area.is_nan() || area <= 0.0 {
            return DVec3::ZERO;
        }
        let rho = reflect / area;
        let r = (DVec3::ONE - rho).max(DVec3::splat(1e-6)).recip();
        r * unshot / area
    }

    /// The ambient term a written file displays: Cohen et al.'s (1988)
    /// estimate of the light still unshot, in partial files and also in a
    /// file that stopped at its threshold. A converged progressive solve still
    /// has `threshold` of its emitted power unshot, and without the term that
    /// light is simply missing: measured against the path-traced truth the
    /// Cornell box's ceiling, lit only by interreflection, was too dark by
    /// about the unshot share (docs/lab/ambient-term.md, "The ambient term at
    /// convergence"). A solver that has not shot (the Gauss–Seidel and cube
    /// gathers use it for their mesh and write their own radiance) has all of
    /// its emission unshot, so its final file gets none.
    pub fn display_ambient(&self, partial: bool) -> DVec3 {
        if self.settings.ambient && (partial || self.stats.shots > 0) {
            self.ambient()
        } else {
            DVec3::ZERO
        }
    }

    /// Per mesh vertex of `representative`, the ambient radiance it shows
    /// before its reflectance: Cohen et al.'s (1988) `ambient` weighted by
    /// the vertex's enclosure over the scene's mean, ε_v / ε̄ ([`enclosure`]),
    /// so that a point looking partly out of the scene gets less of it and
    /// the term's total over the surfaces (Σ A · ambient) stays Cohen's. A
    /// closed scene (ε = 1) gets `ambient` at every vertex. Hidden vertices
    /// keep `ambient` (they show their neighbours' radiance anyway). No
    /// probes are cast when `ambient` is zero or in directional mode, whose
    /// batches carry Cohen's term unweighted.
    pub(super) fn enclosed_ambient(&self, representative: &[u32], ambient: DVec3) -> Vec<DVec3> {
        if ambient == DVec3::ZERO || self.directional.is_some() {
            return vec![ambient; representative.len()];
        }
        let mesh = &self.mesh;
        let occluder = &self.occluder;
        let epsilon = occluder.scene_epsilon();
        // ε̄: the area-weighted mean over the patches, probed at their
        // centroids; both it and each vertex's ε are probed once per solve
        // (`EnclosureCache`).
        let mean = self.enclosure.mean(|| enclosure_mean(self));
        if !(mean.is_finite() && mean > 0.0) {
            return vec![ambient; representative.len()];
        }
        let hidden = |r: u32| self.field.hidden.get(r as usize).copied().unwrap_or(false);
        // A point that interpolates sites (`sites.rs`) takes their weighted
        // ε, as it takes their radiance: only the sites are probed.
        let shown: Vec<u32> = representative
            .iter()
            .copied()
            .filter(|&r| !hidden(r))
            .collect();
        let mut probed = Vec::with_capacity(shown.len());
        for &r in &shown {
            match self.sharing.sites.sources_of(r) {
                Some(sources) => probed.extend(sources.iter().map(|s| s.0)),
                None => probed.push(r),
            }
        }
        let epsilons = self.enclosure.at(mesh.vertices.len(), &probed, |r| {
            let (q, n) = super::shoot::receiving_point(mesh, r, epsilon);
            enclosure::enclosure(occluder, q, n)
        });
        let mut probed_epsilons = epsilons.into_iter();
        representative
            .iter()
            .map(|&r| {
                if hidden(r) {
                    return ambient;
                }
                let e = match self.sharing.sites.sources_of(r) {
                    Some(sources) => sources
                        .iter()
                        .map(|s| s.1 as f64 * probed_epsilons.next().unwrap_or(mean))
                        .sum::<f64>()
                        .clamp(0.0, 1.0),
                    None => probed_epsilons.next().unwrap_or(mean),
                };
                ambient * (e / mean)
            })
            .collect()
    }

    /// The output vertices (`seams.rs`) and, per output vertex, the radiance
    /// to display: hidden vertices filled from their visible neighbours
    /// (`hidden.rs`), then the area-weighted mean over the vertices at its
    /// position. Textured smooth surfaces keep their UV seams.
    fn shared_radiance(&self, triangles: &[[u32; 3]]) -> (SharedVertices, Vec<DVec3>) {
        let mut radiance: Vec<f64> = self
            .field
            .radiance
            .iter()
            .flat_map(|l| l.to_array())
            .collect();
        let count = self.field.radiance.len();
        fill_hidden(triangles, &self.field.hidden, count, rgb, &mut radiance);
        let texturing = &self.materials.texturing;
        let uv = |s, p| texturing.shown(s).map(|t| texturing.uv(t, p));
        let shared = share_vertices(&self.mesh, &uv, Merge::AcrossPolygons);
        shared.merge_values(&self.mesh, rgb, &mut radiance, Lone::Reweighted);
        let shown = (0..shared.representative.len())
            .map(|o| DVec3::from_slice(&radiance[rgb(shared.value_vertex(o))]))
            .collect();
        (shared, shown)
    }

    /// The solution: one batch of order-0 SH (the diffuse mode), one vertex per
    /// mesh vertex of a flat facet and one per position of a smooth surface,
    /// with its shading normal; the display triangles with T-vertices resolved,
    /// within a polygon and across the polygons of a smooth surface. c₀₀ = L ·
    /// √(4π) per channel, since Y₀₀ = 1/(2√π) and L = c₀₀ · Y₀₀.
    ///
    /// `partial` marks a file written mid-solve. With `settings.ambient` the
    /// displayed radiance carries the ambient term ρ · ambient (never the
    /// solver's own radiance), see [`Solver::display_ambient`].
    pub fn to_solution(&self, partial: bool) -> Solution {
        let ambient = self.display_ambient(partial);
        let scale = (4.0 * PI).sqrt();
        // One output vertex per position of a smooth surface, and its seams
        // free of T-junctions (`seams.rs`); flat facets map one to one.
        // Hidden vertices show their visible neighbours' radiance, so no
        // visible element interpolates toward the dark inside of an object.
        let triangles = self.mesh.triangles();
        let (shared, radiance) = self.shared_radiance(&triangles);
        let ambient_at = self.enclosed_ambient(&shared.representative, ambient);
        let mut vertices = Vec::with_capacity(shared.representative.len());
        let mut coefficients = Vec::with_capacity(3 * shared.representative.len());
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for ((&r, l), a) in shared.representative.iter().zip(&radiance).zip(&ambient_at) {
            let v = &self.mesh.vertices[r as usize];
            let s = &self.mesh.surfaces[v.surface as usize];
            let shown = *l + self.materials.kd[v.surface as usize] * *a;
            let f = |d: DVec3| d.as_vec3().to_array();
            // A shading normal is not the polygon's: its frame's tangent is
            // the polygon's made orthogonal to it (the format wants an
            // orthonormal frame). Flat facets keep theirs bit for bit.
            let tangent = if v.normal == s.normal {
                s.tangent
            } else {
                (s.tangent - v.normal * v.normal.dot(s.tangent))
                    .try_normalize()
                    .unwrap_or_else(|| v.normal.any_orthonormal_vector())
            };
            vertices.push(Vertex {
                position: f(v.position),
                normal: f(v.normal),
                tangent: f(tangent),
            });
            coefficients.extend((shown * scale).as_vec3().to_array());
            let stored = v.position.as_vec3().as_dvec3();
            lo = lo.min(stored);
            hi = hi.max(stored);
        }
        if lo.x > hi.x {
            lo = DVec3::ZERO;
            hi = DVec3::ZERO;
        }
        let indices: Vec<u32> = shared.triangles(&triangles).into_iter().flatten().collect();
        let scene_offset = self.scene.recentre + self.scene.offset;
        let camera = self.scene.camera.unwrap_or_else(|| {
            default_camera(lo + scene_offset, hi + scene_offset, self.scene.up_axis)
        });
        let units_per_metre = self.units_per_metre();
        let mut solution = Solution {
            lighting: None,
            header: Header {
                units_per_metre,
                up_axis: self.scene.up_axis,
                recentre_offset: scene_offset.to_array(),
                camera,
                bounds_min: lo.as_vec3().to_array(),
                bounds_max: hi.as_vec3().to_array(),
                partial,
                mode: SolveMode::Diffuse,
                stats: SolveStats {
                    shots: self.stats.shots,
                    rays: self.stats.rays,
                    seconds: self.stats.seconds,
                    unshot_fraction: self.unshot_fraction(),
                    emitted_power: self.emitted_watts(),
                    ambient: ambient.as_vec3().to_array(),
                },
                settings_json: serde_json::to_string(&self.settings).unwrap_or_default(),
            },
            batches: vec![Batch {
                representation: Representation::Sh { order: 0 },
                scalar: ScalarType::F32,
                vertices,
                coefficients,
                indices,
                texturing: None,
            }],
            textures: Vec::new(),
        };
        // Textured surfaces: batches of UV and E/π (`output_textured.rs`).
        self.split_textured(&shared, &radiance, &mut solution, &ambient_at);
        // Directional mode: one batch per SH order instead.
        self.directional_batches(&mut solution, ambient);
        if self.scene.camera.is_none() {
            // No authored camera: an eye inside the enclosed space that sees lit
            // surfaces, standing on the floor (`crate::view`, whose notes say
            // why the choice is made here, at solve time); the framing camera
            // when no candidate passes.
            let framing = solution.header.camera;
            solution.header.camera = crate::view::default_camera(&solution, framing);
        }
        // The exposure key, the lights and the visible sky (`output_lights.rs`).
        solution.lighting = self.lighting(&solution);
        solution
    }
}

/// A camera that frames the scene's bounds (scene coordinates) from outside
/// them: the fallback when the scene names no camera and
/// `crate::view::default_camera` finds no eye inside it, and the default of
/// `solver reference`. 45° vertical field of view, looking horizontally along the axis
/// perpendicular to `up` that OpenGL would use (−z for a y-up scene, +y for a
/// z-up one), from far enough that the bounding sphere fits.
pub(crate) fn default_camera(lo: DVec3, hi: DVec3, up: UpAxis) -> Camera {
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-9);
    let fov_y_deg: f64 = 45.0;
    let distance = radius / (0.5 * fov_y_deg.to_radians()).sin();
    let up_vector = DVec3::from_array(up.vector());
    let back = match up {
        UpAxis::PosY | UpAxis::NegY => DVec3::Z,
        UpAxis::PosZ | UpAxis::NegZ => -DVec3::Y,
    };
    Camera {
        eye: (centre + back * distance).to_array(),
        target: centre.to_array(),
        up: up_vector.to_array(),
        fov_y_deg,
        width: 512,
        height: 512,
    }
}

#[cfg(test)]
mod tests {
    use crate::solve::tests::{closed_room, settings};
    use crate::solve::Solver;

    #[test]
    fn enclosure_mean_has_the_same_bits_on_any_number_of_threads() {
        // ε̄ feeds the ambient term of every vertex, so solution files are
        // reproducible only if its sum does not depend on how rayon splits
        // the work. Each patch's probe is deterministic; the sum must be too.
        // The room without its ceiling, so that ε varies from patch to patch
        // and the order of the sum shows in its last bits.
        let mut room = closed_room(None);
        room.polygons.remove(1);
        for polygon in &mut room.polygons {
            polygon.patches = 7;
        }
        let solver = Solver::new(&room, &settings()).unwrap();
        let mean_on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| super::enclosure_mean(&solver)).to_bits()
        };
        let one = mean_on(1);
        for threads in [2, 3, 4, 7] {
            assert_eq!(mean_on(threads), one, "{threads} threads");
        }
        // Open above, every patch sees some sky and the floor sees walls: ε̄
        // lies strictly between 0 and 1.
        let mean = f64::from_bits(one);
        assert!(mean > 0.0 && mean < 1.0, "{mean}");
    }

    #[test]
    fn systematic_draws_follow_area() {
        // Areas 1, 2, 3, 4 and ten draws one unit apart: each item is drawn
        // as often as its area, so the plain mean over the draws is the
        // area-weighted mean exactly.
        let draws = super::systematic_draws(&[1.0, 2.0, 3.0, 4.0], 10);
        assert_eq!(draws, vec![(0, 1), (1, 2), (2, 3), (3, 4)]);
        // Items far smaller than the spacing: every hundredth is drawn, once
        // (give or take one where the running sum rounds across a draw).
        let small = super::systematic_draws(&vec![1e-3; 1000], 10);
        assert_eq!(small.len(), 10);
        assert!(small.iter().all(|d| d.1 == 1));
        assert!(small
            .windows(2)
            .all(|w| (99..=101).contains(&(w[1].0 - w[0].0))));
    }
}
