//! The path tracer against closed forms (never against the solver): furnaces,
//! a point-to-polygon form factor, a grazing glossy bounce; and determinism.
//!
//! Statistics: each check pools many independent estimates `x_k ± se_k` of known
//! values `μ_k` into `z_k = (x_k − μ_k)/se_k`. If the estimator is unbiased and
//! its standard errors honest, the mean of N z-scores is ~N(0, 1/N) and the mean
//! of z² is ≈ 1. We assert |mean z|·√N < 4 (a false alarm 6e-5 of the time; the
//! seeds are fixed, so a test cannot flake) and 0.5 < mean z² < 2 (the errors are
//! neither hidden by inflated standard errors nor understated).

use super::*;
use crate::geometry::formfactor::point_to_polygon;
use crate::geometry::sampling::{stream_id, Rng};
use crate::scene::{Material, Polygon, Scene, SourceRef};
use glam::DVec3;
use solution::camera::{Camera, UpAxis};
use solution::format::SolveMode;
use std::f64::consts::PI;

pub(super) fn material(name: &str, kd: f64, ks: f64, alpha: f64, le: DVec3) -> Material {
    Material {
        name: name.into(),
        kd: DVec3::splat(kd),
        ks: DVec3::splat(ks),
        alpha,
        emission: le,
        diffuse_texture: None,
        emission_texture: None,
        folded_texture: None,
    }
}

pub(super) fn polygon(vertices: Vec<DVec3>, material: usize) -> Polygon {
    Polygon {
        vertices,
        vertex_normals: None,
        material,
        patches: 1,
        sizes: Default::default(),
        source: SourceRef::default(),
        uv_map: None,
    }
}

pub(super) fn scene(polygons: Vec<Polygon>, materials: Vec<Material>) -> Scene {
    Scene {
        lights: Default::default(),
        polygons,
        materials,
        units_per_metre: 1.0,
        up_axis: UpAxis::PosY,
        camera: None,
        recentre_offset: DVec3::ZERO,
        warnings: vec![],
    }
}

/// The six inward-facing faces of the cube [−1, 1]³, all of material 0.
fn closed_box() -> Vec<Polygon> {
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    // Each face listed counter-clockwise as seen from outside, then reversed so
    // that it is counter-clockwise from inside (normal pointing inward).
    [
        [
            v(-1., -1., -1.),
            v(1., -1., -1.),
            v(1., -1., 1.),
            v(-1., -1., 1.),
        ], // floor
        [
            v(-1., 1., -1.),
            v(-1., 1., 1.),
            v(1., 1., 1.),
            v(1., 1., -1.),
        ], // ceiling
        [
            v(-1., -1., -1.),
            v(-1., 1., -1.),
            v(1., 1., -1.),
            v(1., -1., -1.),
        ], // back
        [
            v(-1., -1., 1.),
            v(1., -1., 1.),
            v(1., 1., 1.),
            v(-1., 1., 1.),
        ], // front
        [
            v(-1., -1., -1.),
            v(-1., -1., 1.),
            v(-1., 1., 1.),
            v(-1., 1., -1.),
        ], // left
        [
            v(1., -1., -1.),
            v(1., 1., -1.),
            v(1., 1., 1.),
            v(1., -1., 1.),
        ], // right
    ]
    .map(|mut q| {
        q.reverse();
        q
    })
    .into_iter()
    .map(|q| polygon(q.to_vec(), 0))
    .collect()
}

/// Pooled z-scores: (mean z · √N, mean z²).
fn z_stats(z: &[f64]) -> (f64, f64) {
    let n = z.len() as f64;
    let mean = z.iter().sum::<f64>() / n;
    let mean_sq = z.iter().map(|z| z * z).sum::<f64>() / n;
    (mean * n.sqrt(), mean_sq)
}

pub(super) fn assert_unbiased(name: &str, z: &[f64]) {
    let (scaled_mean, mean_sq) = z_stats(z);
    assert!(
        scaled_mean.abs() < 4.0 && mean_sq > 0.5 && mean_sq < 2.0,
        "{name}: mean z · √N = {scaled_mean:.3}, mean z² = {mean_sq:.3} over {} points",
        z.len()
    );
}

/// Mean and standard error of `count` samples of `f`.
pub(super) fn estimate(count: usize, mut f: impl FnMut(usize) -> f64) -> (f64, f64) {
    let (mut s, mut s2) = (0.0, 0.0);
    for k in 0..count {
        let x = f(k);
        s += x;
        s2 += x * x;
    }
    let n = count as f64;
    let mean = s / n;
    (mean, ((s2 / n - mean * mean) / (n - 1.0)).max(0.0).sqrt())
}

/// Diffuse furnace: every wall emits Le and reflects ρ, so L = Le/(1 − ρ)
/// everywhere. Checked per pixel of an image from the box's centre (each
/// pixel's mean and standard error from its own samples), per channel.
#[test]
fn diffuse_furnace_radiance_is_le_over_one_minus_rho() {
    let le = DVec3::new(1.0, 0.5, 0.25);
    let rho = 0.6;
    let s = scene(closed_box(), vec![material("wall", rho, 0.0, 1.0, le)]);
    let render = RenderScene::new(&s, Physics::default());
    for q in &render.surfaces {
        assert!(q.normal.dot(q.vertices[0]) < 0.0, "walls face inward");
    }
    let integrator = Integrator {
        scene: &render,
        max_depth: None,
    };
    let camera = Camera {
        eye: [0.1, 0.2, 0.3],
        target: [0.5, -0.3, -1.0],
        fov_y_deg: 120.0,
        width: 8,
        height: 8,
        ..Camera::default()
    };
    let view = camera.mono_view(DVec3::ZERO);
    let mut image = Accumulator::new(8, 8);
    image.render_pass(&integrator, &view, 1, 64, &|_| {});
    let exact = le / (1.0 - rho);
    let mut z = Vec::new();
    for p in &image.pixels {
        for c in 0..3 {
            z.push((p.mean(c) - exact[c]) / p.standard_error(c));
        }
    }
    assert_unbiased("diffuse furnace", &z);
}

/// Glossy furnace, thesis normalization: with C_R(μ_i) = Ks / S(μ_i) every
/// incident beam reflects exactly Ks, so the total reflected power is Ks times
/// the total incident power, which in a closed box equals the total leaving
/// power: Φ = π Le A + Ks Φ, and the area-mean exitance is π Le / (1 − Ks).
/// (Radiance itself is not uniform: the lobe is not reciprocal.) Estimated as
/// π · L_o(x, ω) with x uniform on the walls by area and ω cosine-distributed.
#[test]
fn glossy_furnace_mean_exitance_is_pi_le_over_one_minus_ks() {
    let (le, ks) = (1.0, 0.5);
    let s = scene(
        closed_box(),
        vec![material("gloss", 0.0, ks, 0.3, DVec3::splat(le))],
    );
    let physics = Physics {
        mode: SolveMode::Directional,
    };
    let render = RenderScene::new(&s, physics);
    let integrator = Integrator {
        scene: &render,
        max_depth: None,
    };
    // 40 batches of 500 samples each give 40 z-scores.
    let mut z = Vec::new();
    for batch in 0..40u64 {
        let mut rng = Rng::new(11, batch);
        let (mean, se) = estimate(500, |_| {
            let face = ((rng.next_f64() * 6.0) as usize).min(5);
            let q = &render.surfaces[face];
            let (a, b, d) = (q.vertices[0], q.vertices[1], q.vertices[3]);
            let x = a + (b - a) * rng.next_f64() + (d - a) * rng.next_f64();
            let (u1, u2) = (rng.next_f64(), rng.next_f64());
            let wo = bsdf::cosine_hemisphere(q.normal, u1, u2);
            PI * integrator.outgoing(face, x, wo, &mut rng).x
        });
        z.push((mean - PI * le / (1.0 - ks)) / se);
    }
    assert_unbiased("glossy furnace", &z);
}

pub(super) fn square_at(centre: DVec3, half: f64, facing_down: bool) -> Vec<DVec3> {
    let c = centre;
    let v = |x: f64, y: f64| c + DVec3::new(x * half, y * half, 0.0);
    if facing_down {
        vec![v(-1., -1.), v(-1., 1.), v(1., 1.), v(1., -1.)]
    } else {
        vec![v(-1., -1.), v(1., -1.), v(1., 1.), v(-1., 1.)]
    }
}

/// A one-sided square light over a diffuse floor, single bounce (the light
/// reflects nothing and its back is black, so the floor's reflected light never
/// returns): L = ρ · Le · F, F the exact unoccluded point-to-polygon form
/// factor (Lambert's contour formula), at 48 floor points inside and outside
/// the light's footprint.
#[test]
fn light_over_a_plane_gives_rho_le_form_factor() {
    let (rho, le) = (0.7, 3.0);
    let light = square_at(DVec3::new(0.3, 0.1, 1.0), 0.5, true);
    let floor = square_at(DVec3::ZERO, 3.0, false);
    let s = scene(
        vec![polygon(floor, 0), polygon(light.clone(), 1)],
        vec![
            material("floor", rho, 0.0, 1.0, DVec3::ZERO),
            material("light", 0.0, 0.0, 1.0, DVec3::splat(le)),
        ],
    );
    let render = RenderScene::new(&s, Physics::default());
    let integrator = Integrator {
        scene: &render,
        max_depth: None,
    };
    let mut z = Vec::new();
    for k in 0..48u64 {
        let x = DVec3::new((k % 8) as f64 * 0.4 - 1.3, (k / 8) as f64 * 0.45 - 1.1, 0.0);
        let mut rng = Rng::new(5, k);
        let wo = DVec3::new(0.3, -0.2, 1.0).normalize();
        let (mean, se) = estimate(256, |_| integrator.outgoing(0, x, wo, &mut rng).y);
        let exact = rho * le * point_to_polygon(x, DVec3::Z, &light);
        z.push((mean - exact) / se);
    }
    assert_unbiased("light over a plane", &z);
}

/// The same with a reflecting light and `max_depth = 1`: light that bounces
/// back off the light's underside is cut, so L = ρ · Le · F still.
#[test]
fn max_depth_one_is_single_bounce() {
    let (rho, le) = (0.7, 3.0);
    let light = square_at(DVec3::new(0.0, 0.0, 0.5), 0.5, true);
    let floor = square_at(DVec3::ZERO, 3.0, false);
    let s = scene(
        vec![polygon(floor, 0), polygon(light.clone(), 1)],
        vec![
            material("floor", rho, 0.0, 1.0, DVec3::ZERO),
            material("light", 0.9, 0.0, 1.0, DVec3::splat(le)),
        ],
    );
    let render = RenderScene::new(&s, Physics::default());
    let integrator = Integrator {
        scene: &render,
        max_depth: Some(1),
    };
    let mut z = Vec::new();
    for k in 0..24u64 {
        let x = DVec3::new((k % 6) as f64 * 0.3 - 0.8, (k / 6) as f64 * 0.35 - 0.5, 0.0);
        let mut rng = Rng::new(6, k);
        let (mean, se) = estimate(256, |_| integrator.outgoing(0, x, DVec3::Z, &mut rng).z);
        let exact = rho * le * point_to_polygon(x, DVec3::Z, &light);
        z.push((mean - exact) / se);
    }
    assert_unbiased("max depth 1", &z);
}

/// Single-bounce radiance off a glossy floor (thesis normalization) from a small
/// light at grazing incidence (80° from the normal), seen at 70°: the closed form
/// `L = ∫_light Ks C_R(μ_i) g(ω_o·r_i) Le cos θ_i cos θ_l / r² dA` with
/// `C_R = 1 / S(μ_i)` from `brdf::exact_hemisphere_integral` (independent of the
/// tracer's table), by an 8 × 8 Gauss–Legendre rule over the light (smooth
/// integrand on a 0.2-wide square at distance 3: converged to ~1e-8). With the
/// arguments of f swapped (C_R(μ_o)) the value differs by many standard errors,
/// which the test also checks, so it does catch a swap.
#[test]
fn grazing_glossy_bounce_matches_its_closed_form() {
    let (ks, alpha, le) = (0.8, 0.2, 5.0);
    let theta_l = 80f64.to_radians();
    let centre = DVec3::new(3.0 * theta_l.sin(), 0.0, 3.0 * theta_l.cos());
    let normal = -centre.normalize();
    let (t, b) = normal.any_orthonormal_pair();
    let half = 0.1;
    // Counter-clockwise about `normal` (t × b = normal).
    let light: Vec<DVec3> = [(-1., -1.), (1., -1.), (1., 1.), (-1., 1.)]
        .iter()
        .map(|&(x, y)| centre + t * (x * half) + b * (y * half))
        .collect();
    let floor = square_at(DVec3::ZERO, 1.0, false);
    let s = scene(
        vec![polygon(floor, 0), polygon(light.clone(), 1)],
        vec![
            material("gloss", 0.0, ks, alpha, DVec3::ZERO),
            material("light", 0.0, 0.0, 1.0, DVec3::splat(le)),
        ],
    );
    let physics = Physics {
        mode: SolveMode::Directional,
    };
    let render = RenderScene::new(&s, physics);
    let integrator = Integrator {
        scene: &render,
        max_depth: None,
    };
    let theta_o = 70f64.to_radians();
    let wo = DVec3::new(-theta_o.sin(), 0.0, theta_o.cos());
    let (nodes, weights) = solution::sh::gauss_legendre(8);
    let closed_form = |x: DVec3, swapped: bool| {
        let mut sum = 0.0;
        for (xa, wa) in nodes.iter().zip(&weights) {
            for (xb, wb) in nodes.iter().zip(&weights) {
                let y = centre + t * (xa * half) + b * (xb * half);
                let d = y - x;
                let r2 = d.length_squared();
                let wi = d / r2.sqrt();
                let (mu_i, cos_l) = (wi.z, -wi.dot(normal));
                let r = 2.0 * mu_i * DVec3::Z - wi;
                let mu0 = wo.dot(r);
                let g = crate::brdf::lobe(alpha, mu0);
                let mu = if swapped { wo.z } else { mu_i };
                let c_r = ks / crate::brdf::exact_hemisphere_integral(alpha, mu);
                // dA = half² · wa · wb for the map [−1, 1]² → the square.
                sum += wa * wb * half * half * c_r * g * le * mu_i * cos_l / r2;
            }
        }
        sum
    };
    let mut z = Vec::new();
    let mut z_swapped = Vec::new();
    for k in 0..12u64 {
        let x = DVec3::new((k % 4) as f64 * 0.1 - 0.15, (k / 4) as f64 * 0.1 - 0.1, 0.0);
        let mut rng = Rng::new(8, stream_id(k, 1));
        let (mean, se) = estimate(3000, |_| integrator.outgoing(0, x, wo, &mut rng).x);
        z.push((mean - closed_form(x, false)) / se);
        z_swapped.push((mean - closed_form(x, true)) / se);
    }
    assert_unbiased("grazing glossy", &z);
    let (swapped_mean, _) = z_stats(&z_swapped);
    assert!(
        swapped_mean.abs() > 20.0,
        "swap not detectable: {swapped_mean}"
    );
}

/// The image depends on the seed only, not on the thread count: bit-identical
/// sums with 1 and 2 worker threads.
#[test]
fn images_are_bit_identical_across_thread_counts() {
    let light = square_at(DVec3::new(0.0, 0.0, 1.0), 0.4, true);
    let floor = square_at(DVec3::ZERO, 2.0, false);
    let s = scene(
        vec![polygon(floor, 0), polygon(light, 1)],
        vec![
            material("floor", 0.5, 0.3, 0.3, DVec3::ZERO),
            material("light", 0.2, 0.0, 1.0, DVec3::splat(2.0)),
        ],
    );
    let physics = Physics {
        mode: SolveMode::Directional,
    };
    let render = RenderScene::new(&s, physics);
    let integrator = Integrator {
        scene: &render,
        max_depth: None,
    };
    let camera = Camera {
        eye: [0.0, -2.0, 2.0],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 0.0, 1.0],
        width: 12,
        height: 9,
        ..Camera::default()
    };
    let view = camera.mono_view(DVec3::ZERO);
    let render_with = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut image = Accumulator::new(12, 9);
            for _ in 0..2 {
                image.render_pass(&integrator, &view, 42, 8, &|_| {});
            }
            image
        })
    };
    let (one, two) = (render_with(1), render_with(2));
    assert!(
        one.pixels.iter().any(|p| p.sum[3] > 0.0),
        "the image is lit"
    );
    assert_eq!(one, two);
}
