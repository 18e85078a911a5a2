//! An emission texture (`map_Ke`, issue 15) end to end: a small open box lit
//! only by a "screen" whose emitted radiance is Ke ⊙ texture(uv), solved
//! through the library, rendered by the CPU reference rasterizer
//! (`solution::raster`, which shows Le(uv) from the textured batch) and
//! compared with the path tracer (`solver::reference`, which reads Le(uv) at
//! every hit and light sample). The files are written by the test
//! (`tests/support/emissive_box_scene.rs`, shared with the GPU test
//! `tests/emissive_gpu.rs`): an OBJ with `vt`, an MTL with `Ke 4 4 4` and
//! `map_Ke screen.png`, and a 16 × 16 PNG whose left half is white (sRGB 255,
//! linear 1) and right half dark (sRGB 50, linear 0.0319).

use glam::DVec3;
use solution::format::Solution;
use solution::raster::{self, RenderOptions};
use solver::compare::image::Image;
use solver::compare::metrics::summarize;
use solver::reference::{Accumulator, Integrator, Physics, RenderScene};
use solver::scene::{load_scene, ImportOptions, Scene};
use solver::settings::{Preset, SolverSettings};
use solver::solve::Solver;
use std::path::Path;

/// Pixels per side of the compared images.
const SIZE: u32 = 24;

mod common;
#[path = "../../tests/support/emissive_box_scene.rs"]
mod emissive_box_scene;
use emissive_box_scene::{camera, screen_camera, write_lit_screen_scene, write_scene, DARK};
use solution::camera::Camera;

fn scene(path: &Path) -> Scene {
    let options = ImportOptions {
        units_per_metre: Some(1.0),
        ..Default::default()
    };
    load_scene(path, &options).unwrap().scene
}

fn solve(scene: &Scene, settings: &SolverSettings) -> (Solution, f64) {
    let mut solver = Solver::new(scene, settings).unwrap();
    let watts = solver.progress().emitted_power;
    while solver.step().is_some() {}
    (solver.to_solution(false), watts)
}

/// The solution rendered by the CPU rasterizer at 4× the size, box-filtered
/// 4 × 4 down to the path tracer's pixels.
fn render_solution(solution: &Solution) -> Image {
    render_solution_from(solution, camera)
}

fn render_solution_from(solution: &Solution, camera: fn(u32) -> Camera) -> Image {
    let view = camera(4 * SIZE).mono_view(DVec3::from_array(solution.header.recentre_offset));
    let image = raster::render(solution, &view, &RenderOptions::default()).unwrap();
    let mut rgb = vec![0f32; (3 * SIZE * SIZE) as usize];
    for (k, pixel) in image.pixels.iter().enumerate() {
        let (x, y) = (k as u32 % (4 * SIZE), k as u32 / (4 * SIZE));
        let o = (3 * ((y / 4) * SIZE + x / 4)) as usize;
        for c in 0..3 {
            rgb[o + c] += pixel[c] / 16.0;
        }
    }
    Image {
        width: SIZE as usize,
        height: SIZE as usize,
        rgb,
    }
}

fn path_trace(scene: &Scene, spp: u32) -> Image {
    path_trace_from(scene, spp, camera)
}

fn path_trace_from(scene: &Scene, spp: u32, camera: fn(u32) -> Camera) -> Image {
    let render = RenderScene::new(scene, Physics::default());
    let integrator = Integrator {
        scene: &render,
        max_depth: None,
    };
    let view = camera(SIZE).mono_view(scene.recentre_offset);
    let mut accumulator = Accumulator::new(SIZE, SIZE);
    accumulator.render_pass(&integrator, &view, 11, spp, &|_| {});
    Image {
        width: SIZE as usize,
        height: SIZE as usize,
        rgb: accumulator
            .pixels
            .iter()
            .flat_map(|p| [0, 1, 2].map(|c| p.mean(c) as f32))
            .collect(),
    }
}

#[test]
fn a_textured_emitter_matches_the_path_tracer_reading_the_same_texture() {
    let settings = SolverSettings::preset(Preset::Draft);
    let dir = tempfile::tempdir().unwrap();
    let textured = scene(&write_scene(dir.path(), true));
    let flat_dir = tempfile::tempdir().unwrap();
    let flat = scene(&write_scene(flat_dir.path(), false));
    let screen = textured.materials.iter().find(|m| m.name == "screen");
    assert!(
        screen.unwrap().emission_texture.is_some(),
        "{:?}",
        textured.warnings
    );

    let (solution, watts) = solve(&textured, &settings);
    // The emitted power is π ∫ Le dA = π · 4 · 0.25 m² · (1 + 0.0319) / 2 per
    // channel, from the texture's integral (1e-9: exact integration, patches
    // aligned or not; the solver's own test checks the patch split).
    let dark = f64::from(solver::texture::srgb_to_linear(DARK));
    let want = 3.0 * std::f64::consts::PI * 4.0 * 0.25 * (1.0 + dark) / 2.0;
    assert!((watts - want).abs() <= 1e-9 * want, "{watts} vs {want}");
    let batch = solution
        .batches
        .iter()
        .find_map(|b| b.texturing.as_ref())
        .expect("the screen is a textured batch");
    assert_eq!(batch.factor, [4.0; 3], "the factor is Ke");
    assert!(batch
        .vertices
        .iter()
        .all(|v| v.irradiance_over_pi == [1.0; 3]));

    let truths = Truths::new(&textured, &flat);
    let flat_solution = solve(&flat, &settings).0;
    truths.assert_matched("diffuse", &solution, &flat_solution);
}

/// The path tracer's images of the textured box and of the flat-Ke box.
struct Truths {
    textured: Image,
    flat: Image,
}

impl Truths {
    /// Path-traced at 512 samples per pixel.
    fn new(textured: &Scene, flat: &Scene) -> Truths {
        Truths {
            textured: path_trace(textured, 512),
            flat: path_trace(flat, 512),
        }
    }

    /// Asserts that `solution` of the textured box matches the textured
    /// truth as well as `flat_solution` of the flat-Ke box (solved alike)
    /// matches the flat truth, with a margin, and that `flat_solution` (the
    /// texture ignored) fails against the textured truth.
    fn assert_matched(&self, mode: &str, solution: &Solution, flat_solution: &Solution) {
        let summary = summarize(&render_solution(solution), &self.textured);
        // The baseline: the flat-Ke box, solved and path-traced alike.
        let flat_solution = render_solution(flat_solution);
        let baseline = summarize(&flat_solution, &self.flat);
        // The control: the flat-Ke solution (the texture ignored) against the
        // textured truth.
        let ignored = summarize(&flat_solution, &self.textured);
        eprintln!(
            "{mode}: textured emitter vs path tracer ({SIZE}², 512 spp): MARE {:.4}, mean \
             signed {:+.4}; flat emitter: MARE {:.4}, mean signed {:+.4}; texture ignored: \
             MARE {:.4}",
            summary.mare,
            summary.mean_signed_relative_error,
            baseline.mare,
            baseline.mean_signed_relative_error,
            ignored.mare
        );
        // The bound: the flat emitter's MARE under the same solve, renderer and
        // path-tracer noise, plus 0.03, as for the textured Cornell box
        // (`textured_cornell.rs`). What the texture adds: each patch shoots its
        // mean Le uniformly (docs/textures.md, "Accuracy and patch size"), and
        // the pixels that straddle the screen's texture edge differ by the
        // reconstruction (trilinear box texels in the rasterizer, bilinear in the
        // path tracer). Measured at commit time: textured 0.0840, flat 0.0758
        // (both about −7% mean signed: the draft preset's bias); with the
        // presets of stop 18, 0.0675 and 0.0565 (−5%). Ignoring the texture
        // doubles the screen's power and shows its dark half 31× too bright:
        // it scores 1.56 (1.61), asserted to fail.
        common::assert_texture_shown(mode, summary.mare, baseline.mare, Some(ignored.mare));
    }
}

/// The same box in directional (SH) mode, which honours the emission
/// texture as the diffuse mode does: each patch emits its texels' mean Le,
/// and the emitter is shown as a textured batch (factor Ke, "E/π" 1). Every
/// surface has Ks = 0, so it solves the diffuse problem by its own
/// transport; the bound is the mode's own flat-emitter MARE + 0.03, as
/// above. Measured at commit time: SH textured 0.0609 against flat 0.0515,
/// texture ignored 1.65. Ignoring the texture is what the mode did before
/// (flat Ke, shown flat), asserted to fail. (The global cube refuses
/// textured scenes: `--method cube` is a seed baseline.)
#[test]
fn a_textured_emitter_in_directional_mode_matches_the_path_tracer() {
    let mut settings = SolverSettings::preset(Preset::Draft);
    settings.mode = solution::format::SolveMode::Directional;
    let dir = tempfile::tempdir().unwrap();
    let textured = scene(&write_scene(dir.path(), true));
    let flat_dir = tempfile::tempdir().unwrap();
    let flat = scene(&write_scene(flat_dir.path(), false));
    let truths = Truths::new(&textured, &flat);

    let (sh, watts) = solve(&textured, &settings);
    let dark = f64::from(solver::texture::srgb_to_linear(DARK));
    let want = 3.0 * std::f64::consts::PI * 4.0 * 0.25 * (1.0 + dark) / 2.0;
    assert!((watts - want).abs() <= 1e-9 * want, "{watts} vs {want}");
    truths.assert_matched("SH", &sh, &solve(&flat, &settings).0);
}

/// The textured batch of an emitter survives the file: the same texture
/// texels, factor Ke, UVs, "E/π" 1 and reflected SH, bit for bit.
#[test]
fn a_textured_emitter_round_trips_through_the_solution_file() {
    let mut settings = SolverSettings::preset(Preset::Draft);
    settings.max_shots = 30;
    let dir = tempfile::tempdir().unwrap();
    let textured = scene(&write_scene(dir.path(), true));
    let (solution, _) = solve(&textured, &settings);
    let path = dir.path().join("box.sol");
    solution::format::write_solution(&path, &solution).unwrap();
    let back = solution::format::read_solution(&path).unwrap();
    assert_eq!(back.textures, solution.textures);
    assert_eq!(back.textures.len(), 1);
    assert_eq!(back.batches.len(), solution.batches.len());
    for (a, b) in back.batches.iter().zip(&solution.batches) {
        assert_eq!(a.texturing, b.texturing);
        assert_eq!(a.coefficients, b.coefficients);
        assert_eq!(a.indices, b.indices);
    }
    // The screen reflects (Kd 0.2): some of its coefficients are positive.
    let screen = back.batches.iter().find(|b| b.texturing.is_some()).unwrap();
    assert!(screen.coefficients.iter().any(|&c| c > 0.0));
}

/// A screen with both a diffuse and an emission texture (`map_Kd` and
/// `map_Ke`, the solution file's two texture slots), lit by a flat ceiling
/// panel (`write_lit_screen_scene`), seen face-on so that the image is the
/// screen: each pixel is Kd ⊙ ρ(uv) ⊙ E/π + Ke ⊙ ρ_e(uv), against the path
/// tracer reading both textures. Dropping either texture (the MTL without
/// `map_Kd`, what the solver did before the second slot, or without `map_Ke`)
/// must fail the same bound.
#[test]
fn a_screen_with_both_textures_matches_the_path_tracer() {
    let settings = SolverSettings::preset(Preset::Draft);
    let load = |diffuse: bool, emission: bool| {
        let dir = tempfile::tempdir().unwrap();
        let path = write_lit_screen_scene(dir.path(), diffuse, emission);
        (scene(&path), dir)
    };
    let (both, _dir) = load(true, true);
    let screen = both.materials.iter().find(|m| m.name == "screen").unwrap();
    assert!(
        screen.diffuse_texture.is_some() && screen.emission_texture.is_some(),
        "{:?}",
        both.warnings
    );
    let (solution, _) = solve(&both, &settings);
    let t = solution
        .batches
        .iter()
        .find_map(|b| b.texturing.as_ref())
        .expect("the screen is a textured batch");
    assert_eq!(t.factor, [1.0; 3], "the first slot's factor is Kd");
    let slot = t
        .emission
        .expect("the second slot holds the emission texture");
    assert_eq!(slot.factor, [1.0; 3], "the second slot's factor is Ke");
    assert_ne!(slot.texture, t.texture);
    let bytes = solution::format::encode(&solution).unwrap();
    assert_eq!(&bytes[8..10], &3u16.to_le_bytes(), "written as format 3");

    let spp = 256;
    let truth = path_trace_from(&both, spp, screen_camera);
    let ours = summarize(&render_solution_from(&solution, screen_camera), &truth);
    let dropped = |diffuse: bool, emission: bool| {
        let (scene, _dir) = load(diffuse, emission);
        let image = render_solution_from(&solve(&scene, &settings).0, screen_camera);
        summarize(&image, &truth).mare
    };
    let (no_kd, no_ke) = (dropped(false, true), dropped(true, false));
    eprintln!(
        "both textures vs path tracer ({SIZE}², {spp} spp): MARE {:.4}, mean signed {:+.4}; \
         map_Kd dropped: {no_kd:.4}; map_Ke dropped: {no_ke:.4}",
        ours.mare, ours.mean_signed_relative_error
    );
    // The bound, 0.08: the draft preset's error on a direct-lit surface (the
    // Cornell box's draft MARE is about 4%, tests/cornell_truth.rs), the path
    // tracer's noise at 256 spp on the reflected term, and the pixels along
    // the two texture edges, where the rasterizer's trilinear box texels and
    // the path tracer's bilinear samples reconstruct the step differently.
    // Measured at commit time: MARE 0.0420 (mean signed −4.0%, the draft
    // preset's bias, as the one-texture emitter above shows); map_Kd dropped
    // 3.54, map_Ke dropped 3.44.
    // Dropping map_Kd shows the dark bottom half's reflection 31× too bright;
    // dropping map_Ke makes the right half emit 31× too much: each must score
    // at least three times the bound.
    const BOUND: f64 = 0.08;
    assert!(ours.mare <= BOUND, "MARE {:.4} > {BOUND}", ours.mare);
    assert!(no_kd > 3.0 * BOUND, "map_Kd dropped scores only {no_kd:.4}");
    assert!(no_ke > 3.0 * BOUND, "map_Ke dropped scores only {no_ke:.4}");
}
