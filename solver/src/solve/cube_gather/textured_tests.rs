//! Tests of textured surfaces in the global-cube gather ([`super::textured`]).

use super::tests::{cube_settings, material, scene, tight};
use super::*;
use crate::scene::{SceneTexture, UvMap};
use glam::DVec2;
use std::sync::Arc;

/// sRGB codes of the two-tone texture's halves.
const LIGHT: u8 = 255;
const DARK: u8 = 50;

/// An 8 × 8 texture whose left half (u < 0.5) is sRGB `LIGHT` (linear 1) and
/// right half `DARK` (linear 0.0319).
fn two_tone() -> Arc<SceneTexture> {
    let mut rgba = Vec::new();
    for _ in 0..8 {
        for x in 0..8 {
            let c = if x < 4 { LIGHT } else { DARK };
            rgba.extend([c, c, c, 255]);
        }
    }
    Arc::new(SceneTexture::from_rgba("two-tone.png".into(), 8, 8, rgba).unwrap())
}

/// The unit cube's six faces facing in, each cut in two halves along its
/// first edge: (half, which half: 0 or 1) with the half's UV map onto that
/// half of the texture (u in [0.02, 0.48] or [0.52, 0.98], v in [0.02,
/// 0.98]: inside the half, so no element reads the other tone).
fn split_room() -> Vec<(Vec<DVec3>, usize, UvMap)> {
    let c = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let faces = [
        (c(0., 0., 0.), DVec3::X, DVec3::Y),
        (c(0., 0., 1.), DVec3::X, DVec3::Y),
        (c(0., 0., 0.), DVec3::Y, DVec3::Z),
        (c(1., 0., 0.), DVec3::Y, DVec3::Z),
        (c(0., 0., 0.), DVec3::Z, DVec3::X),
        (c(0., 1., 0.), DVec3::Z, DVec3::X),
    ];
    let centre = DVec3::splat(0.5);
    let mut halves = Vec::new();
    for (corner, e1, e2) in faces {
        for half in 0..2 {
            let origin = corner + e1 * (0.5 * half as f64);
            let mut polygon = vec![
                origin,
                origin + e1 * 0.5,
                origin + e1 * 0.5 + e2,
                origin + e2,
            ];
            let normal = crate::geometry::polygon::newell_normal(&polygon);
            if normal.dot(centre - origin) < 0.0 {
                polygon.reverse();
            }
            let map = UvMap {
                origin,
                du: e1 * (0.46 / 0.5),
                dv: e2 * 0.96,
                base: DVec2::new(0.02 + 0.5 * half as f64, 0.02),
            };
            halves.push((polygon, half, map));
        }
    }
    halves
}

/// The split room with materials 0 (light halves) and 1 (dark halves), both
/// Kd `kd` × the two-tone texture (one texture, shared), emitting `le[half]`.
fn textured_furnace(kd: f64, le: [f64; 2]) -> Scene {
    let texture = two_tone();
    let materials = (0..2)
        .map(|half| {
            let mut m = material(["light", "dark"][half], kd, 0.0, 1.0, le[half]);
            m.diffuse_texture = Some(texture.clone());
            m
        })
        .collect();
    let room = split_room();
    let mut scene = scene(
        room.iter()
            .map(|(p, half, _)| (p.clone(), *half, 2))
            .collect(),
        materials,
    );
    for (polygon, (_, _, map)) in scene.polygons.iter_mut().zip(&room) {
        polygon.uv_map = Some(*map);
    }
    scene
}

#[test]
fn two_tone_furnace_reflects_each_half_with_its_own_texels() {
    // The closed unit cube, each face cut into a half mapped onto the
    // texture's light half (ρ_a = Kd · 1) and a half mapped onto its dark
    // half (ρ_b = Kd · 0.0319), Kd = 0.9, one material per half sharing the
    // texture. Each half emits Le = (1 − ρ) · L₀ with L₀ = 1, so L = L₀
    // everywhere solves L = Le + ρ E/π with E/π = L₀ (every vertex sees the
    // rest of the closed room, whose factors sum to 1): the exact solution
    // is E/π = 1 at every vertex, radiance 1, and total exitance π · 6 m²,
    // of which each half reflects π · 3 m² · ρ. It holds only if each patch
    // reflects its own texels' ρ: the texture's mean (Kd · 0.516 = 0.464,
    // the transport this mode used before) gives about 0.56 on the light
    // halves and 1.44 on the dark ones (worst vertex error measured 0.64). Tolerance 1e-6, as the untextured
    // furnace: the vertices' factor sums are 1 to ~1e-12 and the sweeps stop
    // at a change of 1e-10, leaving γ/(1 − γ) · 1e-10 = 9e-10.
    let kd = 0.9;
    let rho = [1.0, f64::from(crate::texture::srgb_to_linear(DARK))].map(|t| kd * t);
    let scene = textured_furnace(kd, rho.map(|r| 1.0 - r));
    let result = solve_cube(&scene, &cube_settings(2), &tight()).unwrap();
    let mut worst_e: f64 = 0.0;
    let mut worst_l: f64 = 0.0;
    let mut reflected = [0.0; 2];
    for v in 0..result.vertex_count() as u32 {
        let e = result
            .irradiance_over_pi(v)
            .expect("every vertex is textured");
        worst_e = worst_e.max((e - DVec3::ONE).abs().max_element());
        let (n, _) = result.frames[v as usize];
        let l = result.radiance_toward(v, n);
        worst_l = worst_l.max((l - DVec3::ONE).abs().max_element());
        // The halves differ in emission: 0.1 on the light ones.
        let t = result.texturing.vertex(v).unwrap();
        let half = usize::from(t.emission.x > 0.5);
        reflected[half] += PI * result.vertex_areas[v as usize] * (t.reflectance * e).x;
    }
    let exact = rho.map(|r| PI * 3.0 * r);
    let power_error = (0..2)
        .map(|h| (reflected[h] - exact[h]).abs() / exact[h])
        .fold(0.0, f64::max);
    println!(
        "two-tone furnace: {} sweeps, γ = {:.6}, bound {:.1e}; worst E/π error {worst_e:.1e}, \
         radiance {worst_l:.1e}; reflected power {:.6} / {:.6} W (exact {:.6} / {:.6}), \
         worst {power_error:.1e}",
        result.sweeps,
        result.gamma,
        result.error_bound,
        reflected[0],
        reflected[1],
        exact[0],
        exact[1]
    );
    assert!(result.converged);
    assert!(worst_e < 1e-6 && worst_l < 1e-6, "{worst_e} {worst_l}");
    assert!(power_error < 1e-6, "{power_error}");
    // The weighted norm (module notes of `textured.rs`): a light half's
    // row is c_v Σ F · gain = 0.9 · 1 · 1.
    assert!((result.gamma - kd).abs() < 1e-9, "γ = {}", result.gamma);
    assert!(result.error_bound < 1e-8);

    // The mean-colour transport (Kd ⊙ the texture's mean, untextured) on
    // the same room misses by far more than the tolerance.
    let mut mean = scene.clone();
    for m in &mut mean.materials {
        let t = m.diffuse_texture.take().unwrap();
        m.kd *= t.texture.mean();
    }
    let old = solve_cube(&mean, &cube_settings(2), &tight()).unwrap();
    let worst_old = (0..old.vertex_count() as u32)
        .map(|v| {
            let (n, _) = old.frames[v as usize];
            (old.radiance_toward(v, n) - DVec3::ONE).abs().max_element()
        })
        .fold(0.0, f64::max);
    println!("mean-colour transport: worst radiance error {worst_old:.3}");
    assert!(worst_old > 0.1, "{worst_old}");
}
