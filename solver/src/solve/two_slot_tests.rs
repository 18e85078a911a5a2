//! An emitter with both a diffuse and an emission texture in the diffuse
//! progressive solve: it reflects through its texture like any
//! diffuse-textured surface (`textured.rs`), emits its texels' mean Le, and
//! its output batch uses both texture slots of the solution file
//! (`output_textured.rs`).

use super::physics_tests::cube;
use super::tests::{material, scene_of};
use super::*;
use crate::scene::{SceneTexture, UvMap};
use crate::settings::Preset;
use glam::DVec2;
use std::sync::Arc;

/// A 16 × 16 checkerboard of 4-texel squares, sRGB `a` where the square's
/// (column + row) is even, `b` elsewhere.
pub(super) fn checker(a: u8, b: u8) -> Arc<SceneTexture> {
    let rgba = (0..16 * 16)
        .flat_map(|k| {
            let (x, y) = (k % 16 / 4, k / 16 / 4);
            let c = if (x + y) % 2 == 0 { a } else { b };
            [c, c, c, 255]
        })
        .collect();
    Arc::new(SceneTexture::from_rgba("checker.png".into(), 16, 16, rgba).unwrap())
}

#[test]
fn a_furnace_of_emitters_with_both_textures_reflects_the_diffuse_textures_mean() {
    // The closed unit cube, every face Kd 1 × a checkerboard (codes 255 and
    // 50: mean m = 0.516) and Ke 2 × another (255 and 128: mean m_e = 0.608),
    // each face mapped once, 2 × 2 patches of 2 × 2 squares each, so every
    // patch reflects ∫ρ/A = m and emits Le = 2 m_e exactly. Then E/π is the
    // mean outgoing radiance everywhere: E/π = Le + m E/π, E/π = Le/(1 − m)
    // = 2.51. The furnace test's tolerance for ρ = 0.5 at threshold 0.002
    // (physics_tests.rs: 1%, the unshot light ρ u/(1 − ρ) about 0.1%) holds.
    // A solve reflecting the flat Kd 1 instead would diverge (1/(1 − 1)).
    // Measured at commit time: worst vertex 2.5e-3.
    let (scene, m, m_e) = furnace();
    let settings = super::physics_tests::furnace_settings(0.002);
    let mut solver = Solver::new(&scene, &settings).unwrap();
    while solver.step().is_some() {}
    let exact = 2.0 * m_e / (1.0 - m);
    let worst = check_two_slots(&solver.to_solution(false), exact);
    println!("two-slot furnace: m {m:.4}, m_e {m_e:.4}, E/π {exact:.4}, worst {worst:.2e}");
    assert!(worst < 0.01, "{worst}");
}

/// The same furnace gathered by the Gauss–Seidel method, whose output goes
/// through the same writer: the tolerance of its textured furnace
/// (gauss_seidel/tests.rs: 1e-5, the iteration and f32 factors). Measured
/// at commit time: 4.5e-8.
#[test]
fn the_gauss_seidel_method_writes_the_same_two_slot_furnace() {
    use super::gauss_seidel::{solve_gauss_seidel, GaussSeidelLimits};
    let (scene, m, m_e) = furnace();
    let mut settings = SolverSettings::preset(Preset::Draft);
    settings.hemicube_resolution = 16;
    let limits = GaussSeidelLimits {
        tolerance: 1e-9,
        max_sweeps: 20_000,
        ..Default::default()
    };
    let result = solve_gauss_seidel(&scene, &settings, &limits).unwrap();
    assert!(result.converged);
    let worst = check_two_slots(&result.solution, 2.0 * m_e / (1.0 - m));
    println!("two-slot Gauss–Seidel furnace: worst {worst:.2e}");
    assert!(worst < 1e-5, "{worst}");
}

/// The closed unit cube of emitters with both textures (see the first test),
/// each face mapped once, 2 × 2 patches a face; and the two textures' means.
fn furnace() -> (Scene, f64, f64) {
    let mut furnace = material("furnace", 1.0, 2.0);
    furnace.diffuse_texture = Some(checker(255, 50));
    furnace.emission_texture = Some(checker(255, 128));
    let m = furnace.diffuse_texture.as_ref().unwrap().texture.mean().x;
    let m_e = furnace.emission_texture.as_ref().unwrap().texture.mean().x;
    let mut scene = scene_of(cube(1.0, DVec3::ZERO), vec![furnace], 2);
    map_each_face_once(&mut scene);
    (scene, m, m_e)
}

/// Maps each (rectangular) face onto the unit UV square once, u along its
/// first edge and v along its last.
pub(super) fn map_each_face_once(scene: &mut Scene) {
    for p in &mut scene.polygons {
        let o = p.vertices[0];
        let (a, b) = (p.vertices[1] - o, p.vertices[3] - o);
        p.uv_map = Some(UvMap {
            origin: o,
            du: a / a.length_squared(),
            dv: b / b.length_squared(),
            base: DVec2::ZERO,
        });
    }
}

/// Checks the furnace's output batch (both slots, factors Kd and Ke, no SH
/// term) and returns its largest relative E/π error against `exact`.
fn check_two_slots(solution: &solution::format::Solution, exact: f64) -> f64 {
    assert_eq!(solution.batches.len(), 1, "one textured batch");
    let batch = &solution.batches[0];
    let t = batch.texturing.as_ref().unwrap();
    assert_eq!(t.factor, [1.0; 3], "the first slot: map_Kd × Kd");
    let slot = t.emission.expect("the second slot: map_Ke × Ke");
    assert_eq!(slot.factor, [2.0; 3]);
    assert_eq!(solution.textures.len(), 2);
    assert_ne!(slot.texture, t.texture);
    assert!(batch.coefficients.iter().all(|&c| c == 0.0), "no SH term");
    t.vertices
        .iter()
        .map(|v| ((f64::from(v.irradiance_over_pi[0]) - exact) / exact).abs())
        .fold(0.0, f64::max)
}
