//! The global cube on smooth surfaces: a glossy smooth sphere reflects about
//! its shading normals (as the SH mode does, `solve/smooth_tests.rs`), and flat
//! polygons keep their frames and their values bit for bit.

use super::tests::{cube_settings, material, scene, tight};
use super::*;
use crate::scene::smooth_scene;
use crate::solve::smooth_tests::facing;

/// The SH mode's smooth-sphere fixture (`solve/smooth_tests.rs`): the unit
/// sphere at the origin, 8k² outward triangles.
fn sphere(k: usize) -> Vec<Vec<DVec3>> {
    crate::solve::smooth_tests::sphere(k, DVec3::ZERO, 1.0)
}

/// The same mesh as [`solve_cube`] builds (same settings, deterministic).
fn cube_mesh_solver(scene: &Scene, settings: &SolverSettings) -> Solver {
    let mut base = settings.clone();
    base.mode = SolveMode::Diffuse;
    base.adaptive = false;
    Solver::new(scene, &base).unwrap()
}

#[test]
fn glossy_smooth_sphere_cube_reflects_about_its_shading_normals() {
    // `--directional cube` on a smooth glossy sphere (8 · 4² triangles, one
    // patch each) under a 0.2 × 0.2 source 20 above it, shadows off (the whole
    // factor from the source's centre: one incoming direction, no sampling
    // noise). A convex sphere does not see itself, so this is one bounce. At a
    // vertex with shading normal n_s, ω toward the source's centre and r the
    // mirror of ω about n_s, the small-source irradiance is
    // E = Le A cos_s (n_s · ω) / d² (relative error O((a/d)²) ≈ 1e-4), and the
    // radiance toward ω_o is E (Kd/π + Ks C(μ_i) g(ω_o · r)) with the exact lobe
    // g and normalizer C = 1/S(μ_i) ([`ExactLobe`]), μ_i = n_s · ω: the lobe
    // about the *shading* normal. Asserted toward r and 0.1 rad off it.
    //
    // Tolerance, from the cube's discretization at k = 16: the cells are at
    // most h ≈ 2/k = 0.125 rad wide; the incoming direction is splatted onto
    // four cells and the output looked up bilinearly, each interpolation of
    // g ≈ exp(−θ²/4α²) erring by at most h²/8 (|g_xx| + |g_yy|) ≤ h²/8 · 2 ·
    // 1/(2α²) = 0.022 of the lobe's peak at α = 0.3, so 0.043 for both; the
    // cell quadrature Q_i of S(μ_i) errs by under 2% at k = 16 (test
    // `cell_normalization_tends_to_the_exact_integral`). The glossy part is
    // 87% of the peak here, so 0.06 of the peak bounds the sum. The same
    // expectation about the facet normals misses by about the lobe at twice
    // the facet-to-vertex angle (~13° on this sphere): g(0.45 rad) ≈ 0.57,
    // over 0.3 of the peak: asserted above 0.15, so the test tells them apart.
    //
    // And the vertices of two polygons at one position with one shading
    // normal (a smooth seam) get one frame, so they hold the same cube up to
    // where each receives: each receiving point is 1e-3 of the way to its
    // polygon's centroid (|Δq| < 6e-4), which moves E by < 6.5e-5 of itself
    // and ω by < 3.3e-5 rad; the bilinear interpolant of the lobe changes by
    // at most 1.4 × 2 of its peak per radian (twice the lobe's steepest slope,
    // to cover the interpolant's): < 1.6e-4 of the peak, asserted below 2e-4.
    let (k, d, a) = (16, 20.0, 0.2);
    let le = d * d / (a * a);
    let (kd, ks, alpha) = (0.2, 0.5, 0.3);
    let mut polygons = vec![(crate::solve::smooth_tests::square_light(d, a), 1, 1)];
    polygons.extend(sphere(4).into_iter().map(|t| (t, 0, 1)));
    let mut scene = scene(
        polygons,
        vec![
            material("sphere", kd, ks, alpha, 0.0),
            material("light", 0.0, 0.0, 1.0, le),
        ],
    );
    smooth_scene(&mut scene, 30.0);
    let mut settings = cube_settings(k);
    settings.shadows = false;
    settings.samples = 4;
    let result = solve_cube(&scene, &settings, &tight()).unwrap();
    let mesh_solver = cube_mesh_solver(&scene, &settings);
    let mesh = mesh_solver.mesh();
    assert_eq!(mesh.vertices.len(), result.vertex_count());
    let lobe = ExactLobe::new(alpha, settings.brdf_normalization);
    let centre = DVec3::new(0.0, d, 0.0) - result.offset;
    let peak =
        le * a * a / ((d - 1.0) * (d - 1.0)) * (kd / PI + ks * lobe.brdf(DVec3::Z, DVec3::Z));
    let expected = |q: DVec3, n: DVec3, omega_o: DVec3| {
        let to_light = centre - q;
        let omega = to_light.normalize();
        let e = le * a * a * omega.y * n.dot(omega) / to_light.length_squared();
        let t = n.any_orthonormal_vector();
        let local = |x: DVec3| solution::sh::to_local(x, n, t);
        e * (kd / PI + ks * lobe.brdf(local(omega), local(omega_o)))
    };
    let (mut worst, mut worst_facet, mut tested) = (0.0f64, 0.0f64, 0);
    for (v, mv) in mesh.vertices.iter().enumerate() {
        if mv.surface == 0 {
            continue;
        }
        let q = result.receiving_points[v];
        let n_s = mv.normal;
        let omega = (centre - q).normalize();
        let mu = n_s.dot(omega);
        let facet = mesh.surfaces[mv.surface as usize].normal;
        // Away from the terminator: the source above both the shading
        // horizon and the facet's plane, and r well above both.
        if mu < 0.3 || facet.dot(omega) < 0.3 {
            continue;
        }
        assert_eq!(result.frames[v].0, n_s, "vertex {v} has its own frame");
        let r = 2.0 * mu * n_s - omega;
        let off = (r + r.any_orthonormal_vector() * 0.1).normalize();
        for omega_o in [r, off] {
            let got = result.radiance_toward(v as u32, omega_o).x;
            worst = worst.max((got - expected(q, n_s, omega_o)).abs() / peak);
            worst_facet = worst_facet.max((got - expected(q, facet, omega_o)).abs() / peak);
        }
        tested += 1;
    }
    let (pairs, seam_worst) = seam_difference(&result, mesh, peak);
    println!(
        "{tested} lit vertices: worst {worst:.2e} of the peak about the shading normals, \
         {worst_facet:.2e} about the facet normals; {pairs} seam pairs agree within \
         {seam_worst:.2e}"
    );
    assert!(tested > 40, "{tested}");
    assert!(worst < 0.06, "{worst}");
    assert!(worst_facet > 0.15, "{worst_facet}");
    assert!(pairs > 100, "{pairs}");
    assert!(seam_worst < 2e-4, "{seam_worst}");
}

/// Pairs of vertices of different polygons at one position with one shading
/// normal, and their largest difference toward 12 spread directions, relative
/// to `peak`.
fn seam_difference(result: &CubeResult, mesh: &Mesh, peak: f64) -> (usize, f64) {
    let directions: Vec<DVec3> = (0..12)
        .map(|i| {
            let z = 1.0 - (2 * i + 1) as f64 / 12.0;
            let phi = i as f64 * 2.399_963;
            let s = (1.0 - z * z).sqrt();
            DVec3::new(s * phi.cos(), z, s * phi.sin())
        })
        .collect();
    let (mut pairs, mut worst) = (0, 0.0f64);
    for (i, a) in mesh.vertices.iter().enumerate() {
        for (j, b) in mesh.vertices.iter().enumerate().skip(i + 1) {
            if a.surface == 0
                || a.surface == b.surface
                || (a.position - b.position).length() > 1e-9
                || a.normal.dot(b.normal) < 1.0 - 1e-9
            {
                continue;
            }
            pairs += 1;
            for &dir in &directions {
                let x = result.radiance_toward(i as u32, dir).x;
                let y = result.radiance_toward(j as u32, dir).x;
                worst = worst.max((x - y).abs() / peak);
            }
        }
    }
    (pairs, worst)
}

#[test]
fn coplanar_smooth_groups_keep_the_flat_frames_and_values() {
    // A glossy floor cut into 3 × 3 coplanar quads under a light in a room:
    // with smoothing on, the floor is one smooth group whose interpolated
    // shading normals equal its face normal up to rounding, so every vertex
    // keeps its polygon's frame and the solve is bit for bit the flat one
    // (`crease_angle` 0). A consistency check of the same code twice: it
    // guards the rule in `shading_frame` that keeps flat scenes unchanged.
    let mut polygons = Vec::new();
    let c = |x: f64, z: f64| DVec3::new(x, 0.0, z);
    for i in 0..3 {
        for j in 0..3 {
            let (x, z) = (i as f64 / 3.0, j as f64 / 3.0);
            let q = vec![
                c(x, z),
                c(x, z + 1.0 / 3.0),
                c(x + 1.0 / 3.0, z + 1.0 / 3.0),
                c(x + 1.0 / 3.0, z),
            ];
            polygons.push((facing(q, DVec3::Y), 0, 2));
        }
    }
    let light = vec![
        DVec3::new(0.4, 1.0, 0.4),
        DVec3::new(0.6, 1.0, 0.4),
        DVec3::new(0.6, 1.0, 0.6),
        DVec3::new(0.4, 1.0, 0.6),
    ];
    polygons.push((facing(light, -DVec3::Y), 1, 1));
    let materials = vec![
        material("floor", 0.2, 0.5, 0.3, 0.0),
        material("light", 0.0, 0.0, 1.0, 5.0),
    ];
    let flat = scene(polygons, materials);
    let mut smooth = flat.clone();
    let report = smooth_scene(&mut smooth, 30.0);
    assert!(
        smooth.polygons.iter().any(|p| p.vertex_normals.is_some()),
        "the floor forms a smooth group: {report:?}"
    );
    let settings = cube_settings(4);
    let a = solve_cube(&flat, &settings, &tight()).unwrap();
    let b = solve_cube(&smooth, &settings, &tight()).unwrap();
    assert_eq!(a.frames, b.frames);
    assert_eq!(a.values, b.values);
    assert_eq!(a.solution.batches, b.solution.batches);
}
