//! Textured surfaces in the diffuse solve (`textured.rs`).

use super::tests::{material, scene_of};
use super::*;
use crate::scene::{Material, SceneTexture, UvMap};
use crate::settings::Preset;
use glam::DVec2;
use std::sync::Arc;

fn settings() -> SolverSettings {
    let mut s = SolverSettings::preset(Preset::Draft);
    s.adaptive = false;
    s.samples = 4;
    s
}

/// A `size` × `size` RGBA texture, texel (x, y) of sRGB code `code(x, y)`.
fn texture(size: u32, code: impl Fn(u32, u32) -> u8) -> Arc<SceneTexture> {
    let mut rgba = Vec::new();
    for y in 0..size {
        for x in 0..size {
            let c = code(x, y);
            rgba.extend([c, c, c, 255]);
        }
    }
    Arc::new(SceneTexture::from_rgba("t.png".into(), size, size, rgba).unwrap())
}

/// A closed 4 × 2.5 × 6 room with a 1 m² ceiling light, every wall of material
/// 0, each mapped once onto the texture.
fn room(wall: Material) -> Scene {
    let face = |c: DVec3, e1: DVec3, e2: DVec3| vec![c, c + e1, c + e1 + e2, c + e2];
    let lo = DVec3::new(-2.0, 0.0, -3.0);
    let (x, y, z) = (DVec3::X * 4.0, DVec3::Y * 2.5, DVec3::Z * 6.0);
    let walls = [
        (lo, z, x),
        (lo + y, x, z),
        (lo, y, z),
        (lo + x, z, y),
        (lo, x, y),
        (lo + z, y, x),
    ];
    let mut polygons: Vec<(Vec<DVec3>, usize)> =
        walls.iter().map(|&(c, a, b)| (face(c, a, b), 0)).collect();
    polygons.push((face(DVec3::new(0.5, 2.49, 1.0), DVec3::X, DVec3::Z), 1));
    let mut scene = scene_of(polygons, vec![wall, material("light", 0.5, 10.0)], 2);
    for (p, &(c, a, b)) in scene.polygons.iter_mut().zip(&walls) {
        // u along the first edge, v along the second, each 0..1.
        p.uv_map = Some(UvMap {
            origin: c,
            du: a / a.length_squared(),
            dv: b / b.length_squared(),
            base: DVec2::ZERO,
        });
    }
    scene
}

fn solve(scene: &Scene, shots: usize) -> Solver {
    let mut solver = Solver::new(scene, &settings()).unwrap();
    for _ in 0..shots {
        solver.step();
    }
    solver
}

#[test]
fn a_uniform_texture_solves_as_its_flat_reflectance() {
    // Kd 1 × a uniform texture of sRGB 180 (linear 0.4564) must give the same
    // light as Kd 0.4564 untextured: textured vertices hold E/π, so E/π ·
    // 0.4564 must equal the untextured radiance, shot for shot. The two
    // differ only by the order of rounding in the gather (ρ applied before
    // or after the weights), 1e-12 relative per shot; 1e-9 is asserted
    // after 20 shots.
    let rho = f64::from(crate::texture::srgb_to_linear(180));
    let mut textured_wall = material("wall", 1.0, 0.0);
    textured_wall.diffuse_texture = Some(texture(8, |_, _| 180));
    let textured = solve(&room(textured_wall), 20);
    let flat = solve(&room(material("wall", rho, 0.0)), 20);
    assert!(textured.texturing.any());
    for (v, (e, l)) in textured
        .vertex_radiance()
        .iter()
        .zip(flat.vertex_radiance())
        .enumerate()
    {
        let surface = textured.mesh.vertices[v].surface;
        let shown = if textured.texturing.get(surface).is_some() {
            *e * rho
        } else {
            *e
        };
        assert!(
            (shown - *l).abs().max_element() <= 1e-9 * l.max_element().max(1e-3),
            "vertex {v}: {shown} vs {l}"
        );
    }
    let (a, b) = (textured.progress(), flat.progress());
    assert!((a.unshot_fraction - b.unshot_fraction).abs() < 1e-9);
}

#[test]
fn a_textured_patch_shoots_the_integral_of_its_albedo() {
    // Left half of the texture grey 128 (0.2159), right half white: the RGB
    // weights of each patch sum to Kd · ∫ρ dA over it. With 2 × 2 patches
    // per wall, every patch lies in one half: Σ w = A_p · 0.2159 or A_p.
    let mut wall = material("wall", 0.5, 0.0);
    wall.diffuse_texture = Some(texture(16, |x, _| if x < 8 { 128 } else { 255 }));
    let solver = Solver::new(&room(wall), &settings()).unwrap();
    let grey = f64::from(crate::texture::srgb_to_linear(128));
    let mut halves = [0, 0];
    for (p, patch) in solver.mesh.patches.iter().enumerate() {
        if solver.texturing.get(patch.surface).is_none() {
            assert!(solver.patch_rgb_weights[p].is_empty());
            continue;
        }
        let sum: DVec3 = solver.patch_rgb_weights[p].iter().map(|e| e.1).sum();
        let albedo = sum.x / patch.area;
        // Exact integration: only rounding (1e-12) separates the sums.
        let is_grey = (albedo - 0.5 * grey).abs() < 1e-9;
        let is_white = (albedo - 0.5).abs() < 1e-9;
        assert!(is_grey || is_white, "patch {p}: albedo {albedo}");
        halves[usize::from(is_white)] += 1;
    }
    assert_eq!(halves, [12, 12], "six walls × two patches per half");
}

#[test]
fn a_checkerboard_does_not_refine_where_the_light_is_smooth() {
    // Refinement looks at E/π on textured surfaces, so a room whose walls are
    // a fine checkerboard (8 × 8 squares per wall, codes 255 and 30, Kd 1)
    // refines like the same room with the checkerboard's mean as a flat Kd:
    // the light differs only through where the reflected light comes from.
    // Refining on the reflected radiance would split along all 2 × 7 × 8 × 6
    // square edges, several times the elements. Bound: 25% more elements
    // than the flat room (measured: 280 elements for both).
    let mut s = settings();
    s.adaptive = true;
    let run = |wall: Material| {
        let mut solver = Solver::new(&room(wall), &s).unwrap();
        for _ in 0..8 {
            solver.step();
        }
        solver.progress().elements
    };
    let squares = texture(64, |x, y| if (x / 8 + y / 8) % 2 == 0 { 255 } else { 30 });
    let mean = squares.texture.mean();
    let mut checker = material("wall", 1.0, 0.0);
    checker.diffuse_texture = Some(squares);
    let textured = run(checker);
    let flat = run(material("wall", mean.x, 0.0));
    eprintln!("elements after 8 shots: checkerboard {textured}, flat mean {flat}");
    assert!(flat > 28, "the solve refines somewhere: {flat} elements");
    assert!(
        textured as f64 <= 1.25 * flat as f64,
        "checkerboard {textured} elements, flat {flat}"
    );
}

#[test]
fn the_solution_has_a_textured_batch_of_uv_and_e_over_pi_that_round_trips() {
    // The room with textured walls: the walls' output vertices form one
    // textured batch (one material) whose E/π are the solver's vertex values
    // and whose UVs are the walls' maps; the light stays untextured. The file
    // encodes and decodes to the same solution (the format's validation).
    let mut wall = material("wall", 0.8, 0.0);
    wall.diffuse_texture = Some(texture(16, |x, y| ((x * 16 + y) % 256) as u8));
    let mut solver = solve(&room(wall), 5);
    // Without the ambient term (which a file now carries while light is
    // unshot), E/π is exactly the solver's vertex value.
    solver.settings.ambient = false;
    let solution = solver.to_solution(false);
    assert_eq!(
        solution.batches.len(),
        2,
        "untextured light + textured walls"
    );
    assert_eq!(solution.textures.len(), 1);
    assert_eq!(
        (solution.textures[0].width, solution.textures[0].rgba.len()),
        (16, 16 * 16 * 4)
    );
    let light = &solution.batches[0];
    let walls = &solution.batches[1];
    assert!(light.texturing.is_none());
    let texturing = walls.texturing.as_ref().unwrap();
    assert_eq!(texturing.factor, [0.8; 3]);
    assert_eq!(texturing.vertices.len(), walls.vertices.len());
    let textured_radiance: Vec<DVec3> = solver
        .mesh
        .vertices
        .iter()
        .zip(solver.vertex_radiance())
        .filter(|(v, _)| solver.texturing.get(v.surface).is_some())
        .map(|(_, l)| *l)
        .collect();
    // Flat walls: one output vertex per mesh vertex, in mesh order, whose
    // E/π is the solver's vertex value (no ambient term, above) rounded to
    // f32.
    assert_eq!(walls.vertices.len(), textured_radiance.len());
    for (tv, l) in texturing.vertices.iter().zip(&textured_radiance) {
        assert_eq!(tv.irradiance_over_pi, l.as_vec3().to_array());
    }
    assert!(walls.coefficients.iter().all(|&c| c == 0.0));
    let mut e_sum = 0.0;
    for tv in &texturing.vertices {
        assert!(
            tv.uv.iter().all(|u| (-1e-5..=1.0 + 1e-5).contains(u)),
            "{tv:?}"
        );
        assert!(tv
            .irradiance_over_pi
            .iter()
            .all(|e| e.is_finite() && *e >= 0.0));
        e_sum += f64::from(tv.irradiance_over_pi[0]);
    }
    assert!(e_sum > 0.0, "the walls are lit");
    let max_index = walls.indices.iter().max().copied().unwrap();
    assert!((max_index as usize) < walls.vertices.len());
    let bytes = solution::format::encode(&solution).unwrap();
    assert_eq!(solution::format::decode(&bytes).unwrap(), solution);
}

#[test]
fn textures_are_counted_in_the_memory_budget() {
    // One 64² texture shared by the walls: RGBA8 (16 KiB) plus the linear
    // pyramid (12 bytes a texel over 64² + 32² + … + 1², 65 532 bytes),
    // counted once before meshing; the solver adds its RGB gather weights
    // (32 bytes an entry) and nothing for an untextured scene.
    let shared = texture(64, |x, _| x as u8);
    let expected = 64 * 64 * 4 + 12 * (4096 + 1024 + 256 + 64 + 16 + 4 + 1);
    assert_eq!(shared.bytes(), expected);
    let mut wall = material("wall", 1.0, 0.0);
    wall.diffuse_texture = Some(shared);
    let scene = room(wall);
    let before = budget::counts_before_meshing(&scene, &settings());
    assert_eq!(before.texture_bytes, expected);
    let solver = Solver::new(&scene, &settings()).unwrap();
    let entries: u64 = solver
        .patch_rgb_weights
        .iter()
        .map(|w| w.len() as u64)
        .sum();
    assert!(entries > 0);
    assert!(solver.memory_counts().texture_bytes >= expected + 32 * entries);
    let plain = Solver::new(&room(material("wall", 0.5, 0.0)), &settings()).unwrap();
    assert_eq!(plain.memory_counts().texture_bytes, 0);
}

#[test]
fn a_checkpoint_refuses_a_changed_texture_and_resumes_the_same_one() {
    // Textured vertices hold E/π and their patches shoot through the
    // texture, so the unshot light of a checkpoint belongs to one texture: a
    // resume on another (one texel changed) must be refused, and one on the
    // same texels (a new, equal decode) accepted.
    let wall = |t: Arc<SceneTexture>| {
        let mut m = material("wall", 1.0, 0.0);
        m.diffuse_texture = Some(t);
        m
    };
    let checker = |x: u32, y: u32| if (x + y).is_multiple_of(2) { 200 } else { 60 };
    let solver = solve(&room(wall(texture(8, checker))), 5);
    let checkpoint = checkpoint::Checkpoint::round_trip(&solver);
    let same = room(wall(texture(8, checker)));
    assert!(Solver::resume(&same, &settings(), checkpoint.clone()).is_ok());
    let changed = room(wall(texture(8, |x, y| {
        if (x, y) == (3, 5) {
            61
        } else {
            checker(x, y)
        }
    })));
    let err = Solver::resume(&changed, &settings(), checkpoint)
        .err()
        .unwrap();
    assert!(err.to_string().contains("fingerprint"), "{err}");
}
