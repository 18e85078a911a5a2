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
    assert_textured_solves_as_flat(&textured, &flat, rho);
}

/// Asserts that `textured` (whose textured vertices hold E/π) shows the
/// light of `flat` once its textured vertices are scaled by `reflectance`,
/// to 1e-9 relative (see above), and has the same unshot fraction.
fn assert_textured_solves_as_flat(textured: &Solver, flat: &Solver, reflectance: f64) {
    assert!(textured.materials.texturing.any());
    for (v, (e, l)) in textured
        .vertex_radiance()
        .iter()
        .zip(flat.vertex_radiance())
        .enumerate()
    {
        let surface = textured.mesh.vertices[v].surface;
        let shown = if textured.materials.texturing.get(surface).is_some() {
            *e * reflectance
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
fn a_textured_glossy_wall_in_diffuse_mode_folds_ks_into_the_textured_factor() {
    // Kd 0.25 and Ks 0.5 times a uniform texture of linear ρ (sRGB 180):
    // diffuse mode folds Ks into the factor the texture multiplies
    // (`Material::diffuse_equivalent_kd`), so the wall reflects 0.75 ρ, the
    // light of that flat Kd untextured, to the same 1e-9 as above.
    let rho = f64::from(crate::texture::srgb_to_linear(180));
    let mut glossy_wall = material("wall", 0.25, 0.0);
    glossy_wall.ks = DVec3::splat(0.5);
    glossy_wall.alpha = 0.3;
    glossy_wall.diffuse_texture = Some(texture(8, |_, _| 180));
    let textured = solve(&room(glossy_wall), 20);
    let flat = solve(&room(material("wall", 0.75 * rho, 0.0)), 20);
    assert_textured_solves_as_flat(&textured, &flat, 0.75 * rho);
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
        if solver.materials.texturing.get(patch.surface).is_none() {
            assert!(solver.patches.rgb_weights[p].is_empty());
            continue;
        }
        let sum: DVec3 = solver.patches.rgb_weights[p].iter().map(|e| e.1).sum();
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
        .filter(|(v, _)| solver.materials.texturing.get(v.surface).is_some())
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
    let before =
        budget::counts_before_meshing(&scene, &settings(), &budget::cuts_of(&scene, &settings()));
    assert_eq!(before.texture_bytes, expected);
    let solver = Solver::new(&scene, &settings()).unwrap();
    let entries: u64 = solver
        .patches
        .rgb_weights
        .iter()
        .map(|w| w.len() as u64)
        .sum();
    assert!(entries > 0);
    assert!(solver.memory_counts().texture_bytes >= expected + 32 * entries);
    let plain = Solver::new(&room(material("wall", 0.5, 0.0)), &settings()).unwrap();
    assert_eq!(plain.memory_counts().texture_bytes, 0);
}

/// A directional solve's textured vertices hold E/π (three values after
/// their coefficients in each per-vertex array): the estimates before the
/// state is allocated count them, exactly for the built mesh and as the
/// usual (N+1)² upper bound before meshing, and the split cost charges them.
#[test]
fn directional_e_over_pi_is_counted_in_the_memory_budget() {
    let mut wall = material("wall", 1.0, 0.0);
    wall.diffuse_texture = Some(texture(8, |x, y| if (x + y) % 2 == 0 { 40 } else { 220 }));
    let scene = room(wall);
    let settings = directional_settings();
    let solver = Solver::new(&scene, &settings).unwrap();
    let d = solver.directional().unwrap();
    // The allocated per-vertex values, summed from the arrays themselves.
    let (allocated, _, _) = d.coefficient_totals();
    let textured: Vec<bool> = solver
        .materials
        .texturing
        .per_surface
        .iter()
        .map(Option::is_some)
        .collect();
    let textured_vertices = solver
        .mesh
        .vertices
        .iter()
        .filter(|v| textured[v.surface as usize])
        .count() as u64;
    assert!(textured_vertices > 0);
    let orders = d.surface_orders().to_vec();
    let recorded = budget::emitter_patches(&scene, &solver.mesh);
    let model =
        budget::counts_for_mesh(&solver.mesh, &settings, |s| orders[s], &textured, recorded);
    assert_eq!(model.vertex_coefficients, allocated);
    // Without E/π it would be three values short per textured vertex
    // (half of an order-0 textured vertex's six).
    let plain = budget::counts_for_mesh(&solver.mesh, &settings, |s| orders[s], &[], recorded);
    assert_eq!(plain.vertex_coefficients + 3 * textured_vertices, allocated);
    // Before meshing: N² patches and (N+1)² vertices a quad, six values per
    // textured vertex at order 0: an upper bound (the walls' patch corners
    // are shared along their edges only within a wall, as counted).
    let before =
        budget::counts_before_meshing(&scene, &settings, &budget::cuts_of(&scene, &settings));
    assert!(before.vertex_coefficients >= allocated);
    let before_plain_walls = 3 * before.vertices;
    assert!(before.vertex_coefficients > before_plain_walls);
    // A split on a textured surface charges its five new vertices' E/π too.
    let s = textured.iter().position(|&t| t).unwrap();
    assert_eq!(d.vertex_values(s), 6);
    // Five vertices × three more values in the radiance, ΔL and recorded
    // arrays (f64) at least.
    assert!(budget::split_cost(6, true) >= budget::split_cost(3, true) + 5 * 3 * 3 * 8);
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

// Directional mode (`directional/textured.rs`).

/// The room's settings in directional mode.
fn directional_settings() -> SolverSettings {
    let mut s = settings();
    s.mode = SolveMode::Directional;
    s
}

fn solve_with(scene: &Scene, settings: &SolverSettings, shots: usize) -> Solver {
    let mut solver = Solver::new(scene, settings).unwrap();
    for _ in 0..shots {
        solver.step();
    }
    solver
}

/// A glossy wall: Kd `kd`, Ks 0.3 grey, α 0.25 (an SH order above 0).
fn glossy_wall(kd: f64) -> Material {
    let mut m = material("wall", kd, 0.0);
    m.ks = DVec3::splat(0.3);
    m.alpha = 0.25;
    m
}

/// E/π of a textured vertex in directional mode, and its coefficients.
fn directional_vertex(solver: &Solver, v: usize) -> (DVec3, Vec<f64>) {
    solver.directional_vertex(v)
}

#[test]
fn directional_a_uniform_texture_solves_as_its_flat_reflectance() {
    // Glossy walls (Ks 0.3, α 0.25) with Kd 1 × a uniform texture of sRGB
    // 180 (linear 0.4564) against the same walls with a flat Kd 0.4564: the
    // textured vertex's ρ · E/π · √(4π) added to its c₀₀, and its glossy
    // coefficients, must equal the flat vertex's coefficients shot for shot
    // (the same sources: the patches' hemisphere power is the same). The two
    // differ only in where ρ is applied (before or after the gather
    // weights), 1e-12 relative per shot; 1e-9 of the peak coefficient is
    // asserted after 20 shots.
    let rho = f64::from(crate::texture::srgb_to_linear(180));
    let mut textured_wall = glossy_wall(1.0);
    textured_wall.diffuse_texture = Some(texture(8, |_, _| 180));
    let mut s = directional_settings();
    // A patch lit unevenly takes its quadrants' shape from its vertices'
    // proxies (`regions.rs`): E/π on a textured surface, the mean radiance
    // c₀₀ Y₀₀ (the glossy part included) on a flat one, so the two would
    // shoot slightly different shapes; this test is about where ρ applies.
    s.uniform_shooters = true;
    let textured = solve_with(&room(textured_wall), &s, 20);
    let flat = solve_with(&room(glossy_wall(rho)), &s, 20);
    assert!(textured.directional_textured(0));
    let orders = flat.directional().unwrap().surface_orders();
    assert!(orders.iter().any(|&o| o > 0), "the walls are glossy");
    let peak = (0..flat.mesh.vertices.len())
        .flat_map(|v| flat.vertex_sh(v as u32).unwrap().1.to_vec())
        .fold(0.0f64, |m, c| m.max(c.abs()));
    let scale = (4.0 * PI).sqrt();
    for v in 0..flat.mesh.vertices.len() {
        let expected = flat.vertex_sh(v as u32).unwrap().1;
        let (e, mut sh) = directional_vertex(&textured, v);
        if textured.directional_textured(textured.mesh.vertices[v].surface as usize) {
            for c in 0..3 {
                sh[c] += rho * e[c] * scale;
            }
        }
        assert_eq!(sh.len(), expected.len());
        for (k, (a, b)) in sh.iter().zip(expected).enumerate() {
            assert!(
                (a - b).abs() <= 1e-9 * peak,
                "vertex {v} coefficient {k}: {a} vs {b}"
            );
        }
    }
    let (a, b) = (textured.progress(), flat.progress());
    assert!((a.unshot_fraction - b.unshot_fraction).abs() < 1e-9);
}

#[test]
fn directional_with_ks_zero_a_checkerboard_solves_as_in_diffuse_mode() {
    // A consistency check of two implementations of one model (the diffuse
    // solve's `textured.rs` and directional mode's `directional/textured.rs`):
    // with Ks = 0 the directional solve of a checkerboard room (8 × 8 squares
    // per wall, codes 255 and 30, Kd 0.9) must shoot the same sources,
    // split the same elements (refinement on E/π in both) and give every
    // vertex the same E/π. Directional mode shoots each patch's mean
    // uniformly, one patch a shot, and visits every receiver, so the diffuse
    // solve is set to do the same. They differ in rounding only (c₀₀ = L √(4π) and back), so
    // 1e-9 of the peak E/π is asserted, with adaptive meshing off and on.
    let squares = texture(64, |x, y| if (x / 8 + y / 8) % 2 == 0 { 255 } else { 30 });
    let mut wall = material("wall", 0.9, 0.0);
    wall.diffuse_texture = Some(squares);
    let scene = room(wall);
    for adaptive in [false, true] {
        let mut diffuse = settings();
        diffuse.adaptive = adaptive;
        diffuse.uniform_shooters = true;
        diffuse.full_rays_above = 0.0;
        diffuse.shooters = crate::settings::Shooters::Patch;
        let mut directional = diffuse.clone();
        directional.mode = SolveMode::Directional;
        let mut a = Solver::new(&scene, &diffuse).unwrap();
        let mut b = Solver::new(&scene, &directional).unwrap();
        for _ in 0..12 {
            let (ra, rb) = (a.step().unwrap(), b.step().unwrap());
            assert_eq!((ra.source, ra.splits), (rb.source, rb.splits));
        }
        assert_eq!(a.mesh.split_log, b.mesh.split_log);
        assert_eq!(a.mesh.split_log.is_empty(), !adaptive);
        let peak = a
            .vertex_radiance()
            .iter()
            .fold(0.0f64, |m, l| m.max(l.max_element()));
        for v in 0..a.mesh.vertices.len() {
            let (e, sh) = directional_vertex(&b, v);
            let diffuse_value = a.vertex_radiance()[v];
            if b.materials
                .texturing
                .get(a.mesh.vertices[v].surface)
                .is_some()
            {
                // Textured: E/π in both, and no untextured term.
                assert!(sh.iter().all(|&c| c == 0.0), "vertex {v}: {sh:?}");
            }
            assert!(
                (e - diffuse_value).abs().max_element() <= 1e-9 * peak,
                "vertex {v}: {e} vs {diffuse_value}"
            );
        }
    }
}

/// The room's far wall (z = +3) seen from inside, `size`² pixels.
fn far_wall_view(solution: &solution::format::Solution, size: u32) -> solution::camera::EyeView {
    let camera = solution::camera::Camera {
        eye: [0.0, 1.25, -2.0],
        target: [0.0, 1.25, 3.0],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 20.0,
        width: size,
        height: size,
    };
    camera.mono_view(DVec3::from_array(solution.header.recentre_offset))
}

#[test]
fn directional_textured_sh_batches_round_trip_and_render_the_checkerboard() {
    // Glossy checkerboard walls (Ks 0.3, α 0.25; Kd 0.9 × squares of codes
    // 255 and 30, linear 1 and 0.0130). The directional file holds the walls
    // as a textured SH batch of their order: coefficients = the solver's
    // glossy SH, E/π = its vertex values, factor Kd; it encodes and decodes
    // to the same solution. The CPU reference renderer shows the squares:
    // with the same solution rendered once more with the texture white (ρ =
    // 1) and once black (ρ = 0, the SH term alone), (T − B)/(W − B) at each
    // pixel of the far wall is the texture's ρ there; the squares' mean
    // ratio of light to dark pixels (the half above and below the median)
    // must be at least 80% of the texture's 1/0.0130 contrast, in Michelson
    // terms (an untextured display would give 0).
    let squares = texture(64, |x, y| if (x / 8 + y / 8) % 2 == 0 { 255 } else { 30 });
    let mut wall = glossy_wall(0.9);
    wall.diffuse_texture = Some(squares);
    let solver = solve_with(&room(wall), &directional_settings(), 12);
    let solution = solver.to_solution(false);
    let d = solver.directional().unwrap();
    let wall_order = d.surface_orders()[0];
    assert!(wall_order > 0);
    let textured: Vec<_> = solution
        .batches
        .iter()
        .filter(|b| b.texturing.is_some())
        .collect();
    assert_eq!(textured.len(), 1, "one textured material");
    let walls = textured[0];
    assert_eq!(
        walls.representation,
        solution::format::Representation::Sh { order: wall_order }
    );
    assert_eq!(solution.textures.len(), 1);
    let texturing = walls.texturing.as_ref().unwrap();
    assert_eq!(texturing.factor, [0.9; 3]);
    // Flat walls: one output vertex per mesh vertex, in mesh order; E/π is
    // the solver's plus the ambient term.
    let wall_vertices: Vec<usize> = (0..solver.mesh.vertices.len())
        .filter(|&v| solver.directional_textured(solver.mesh.vertices[v].surface as usize))
        .collect();
    assert_eq!(walls.vertices.len(), wall_vertices.len());
    let count = 3 * solution::sh::coefficient_count(wall_order);
    for (k, &v) in wall_vertices.iter().enumerate() {
        // Hidden vertices (the ceiling above the light) show their visible
        // neighbours' light (`solve/hidden.rs`).
        if solver.hidden_vertices()[v] {
            continue;
        }
        let (e, sh) = directional_vertex(&solver, v);
        // Plus the ambient term the file shows (`Solver::display_ambient`).
        let shown = e + solver.display_ambient(false);
        assert_eq!(
            texturing.vertices[k].irradiance_over_pi,
            shown.as_vec3().to_array()
        );
        let stored = &walls.coefficients[k * count..(k + 1) * count];
        assert!(stored.iter().zip(&sh).all(|(a, b)| *a == *b as f32));
    }
    assert!(
        walls.coefficients.iter().any(|&c| c != 0.0),
        "a glossy term"
    );
    let bytes = solution::format::encode(&solution).unwrap();
    assert_eq!(solution::format::decode(&bytes).unwrap(), solution);

    let render = |code: u8| {
        let mut s = solution.clone();
        for texel in s.textures[0].rgba.chunks_exact_mut(4) {
            texel[..3].fill(code);
        }
        let view = far_wall_view(&s, 48);
        solution::raster::render(&s, &view, &Default::default()).unwrap()
    };
    let (t, w, b) = (
        solution::raster::render(
            &solution,
            &far_wall_view(&solution, 48),
            &Default::default(),
        )
        .unwrap(),
        render(255),
        render(0),
    );
    let mut ratios: Vec<f64> = Vec::new();
    for k in 0..t.pixels.len() {
        let (tp, wp, bp) = (
            t.pixels[k][1] as f64,
            w.pixels[k][1] as f64,
            b.pixels[k][1] as f64,
        );
        if wp - bp > 1e-6 {
            ratios.push((tp - bp) / (wp - bp));
        }
    }
    assert!(ratios.len() > 48 * 48 / 2, "the wall fills the view");
    ratios.sort_by(f64::total_cmp);
    let half = ratios.len() / 2;
    let dark = ratios[..half].iter().sum::<f64>() / half as f64;
    let light = ratios[half..].iter().sum::<f64>() / (ratios.len() - half) as f64;
    let shown = (light - dark) / (light + dark);
    let (hi, lo) = (1.0, f64::from(crate::texture::srgb_to_linear(30)));
    let ideal = (hi - lo) / (hi + lo);
    eprintln!("checkerboard contrast shown {shown:.4}, texture {ideal:.4}");
    assert!(shown >= 0.8 * ideal, "contrast {shown} vs {ideal}");
}

// Global cubes: a seed baseline, refused on textured scenes.

#[test]
fn cube_mode_refuses_a_textured_scene_naming_the_method_and_the_material() {
    // Immel, Cohen and Greenberg (1986) solved untextured scenes; the
    // progressive method solves textures, so the cube refuses them before any
    // work rather than keep a third copy of the texture transport.
    let s = directional_settings();
    let limits = cube_gather::CubeLimits::default();
    let mut wall = material("wall", 0.8, 0.0);
    wall.diffuse_texture = Some(texture(8, |_, _| 180));
    let err = match cube_gather::solve_cube(&room(wall), &s, &limits) {
        Err(err) => err.to_string(),
        Ok(_) => panic!("a textured scene must be refused"),
    };
    assert!(
        err.contains("--method cube") && err.contains("`wall`") && err.contains("diffuse texture"),
        "{err}"
    );
    // Untextured, the same room solves.
    assert!(cube_gather::solve_cube(&room(material("wall", 0.8, 0.0)), &s, &limits).is_ok());
}

#[test]
fn directional_textured_resume_continues_bit_for_bit() {
    // A textured vertex's E/π lives in the coefficient arrays (three values
    // after its SH), so a checkpoint stores it, the recorded shots' part is
    // recomputed into it, and refinement replays into it: a solve of glossy
    // checkerboard walls with adaptive meshing, checkpointed after 5 shots
    // and resumed, must give the same bits after 10 as one never stopped.
    let squares = texture(64, |x, y| if (x / 8 + y / 8) % 2 == 0 { 255 } else { 30 });
    let mut wall = glossy_wall(0.9);
    wall.diffuse_texture = Some(squares);
    let scene = room(wall);
    let mut s = directional_settings();
    s.adaptive = true;
    let straight = solve_with(&scene, &s, 10);
    let first = solve_with(&scene, &s, 5);
    let mut resumed =
        Solver::resume(&scene, &s, checkpoint::Checkpoint::round_trip(&first)).unwrap();
    for _ in 0..5 {
        resumed.step();
    }
    assert!(!straight.mesh.split_log.is_empty(), "the walls refined");
    assert_eq!(straight.mesh.split_log, resumed.mesh.split_log);
    crate::solve::tests::assert_same_directional_bits(&straight, &resumed);
}
