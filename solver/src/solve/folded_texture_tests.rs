//! A material whose diffuse-mode reflectance is a per-texel fold (glTF's
//! metallic-roughness texture, `scene::metal_texture`) in the diffuse
//! progressive solve and the path tracer: both reflect the fold, not the
//! material's flat Kd + Ks.

use super::physics_tests::cube;
use super::tests::{material, scene_of};
use super::two_slot_tests::{checker, map_each_face_once};
use super::*;
use crate::reference::{Physics, RenderScene};

/// The closed unit cube, every face a metal (Kd 0, Ks 0.9: its flat fold is
/// 0.9) emitting Le = 1, whose per-texel fold is a checkerboard of mean m;
/// each face mapped once, 2 × 2 patches of 2 × 2 squares each.
fn furnace() -> (Scene, f64) {
    let mut metal = material("metal", 0.0, 1.0);
    metal.ks = DVec3::splat(0.9);
    metal.folded_texture = Some(checker(255, 50));
    let m = metal.folded_texture.as_ref().unwrap().texture.mean().x;
    let mut scene = scene_of(cube(1.0, DVec3::ZERO), vec![metal], 2);
    map_each_face_once(&mut scene);
    (scene, m)
}

#[test]
fn a_furnace_of_folded_metal_reflects_the_folds_mean() {
    // Every patch reflects ∫ρ/A = m exactly (it covers whole squares), so the
    // furnace's E/π is Le/(1 − m) = 2.07 everywhere; the flat fold (0.9)
    // would give 10. Tolerance as the two-slot furnace's (1%, threshold
    // 0.002). Measured at commit time: see the printed line.
    let (scene, m) = furnace();
    let settings = super::physics_tests::furnace_settings(0.002);
    let mut solver = Solver::new(&scene, &settings).unwrap();
    while solver.step().is_some() {}
    let exact = 1.0 / (1.0 - m);
    let solution = solver.to_solution(false);
    assert_eq!(solution.batches.len(), 1, "one textured batch");
    let t = solution.batches[0].texturing.as_ref().unwrap();
    assert_eq!(t.factor, [1.0; 3], "the fold is stored with factor 1");
    let worst = t
        .vertices
        .iter()
        .map(|v| ((f64::from(v.irradiance_over_pi[0]) - exact) / exact).abs())
        .fold(0.0, f64::max);
    println!("folded furnace: m {m:.4}, E/π {exact:.4}, worst {worst:.2e}");
    assert!(worst < 0.01, "{worst}");
}

#[test]
fn the_path_tracer_reads_the_fold_in_diffuse_mode_and_kd_in_directional() {
    let (scene, _) = furnace();
    let point = scene.polygons[0].vertices[0] + DVec3::splat(1e-3);
    let point = point
        - scene.polygons[0].normal()
            * scene.polygons[0]
                .normal()
                .dot(point - scene.polygons[0].vertices[0]);
    let texel = scene.materials[0]
        .folded_texture
        .as_ref()
        .unwrap()
        .texture
        .bilinear(scene.polygons[0].uv_map.unwrap().at(point));
    let diffuse = RenderScene::new(
        &scene,
        Physics {
            mode: SolveMode::Diffuse,
        },
    );
    let kd = diffuse.bsdf_at(0, point).kd;
    assert!((kd - texel).abs().max_element() < 1e-12, "{kd} vs {texel}");
    let directional = RenderScene::new(
        &scene,
        Physics {
            mode: SolveMode::Directional,
        },
    );
    // No diffuse texture: directional mode reflects the flat Kd and its lobe.
    assert_eq!(directional.bsdf_at(0, point).kd, DVec3::ZERO);
}
