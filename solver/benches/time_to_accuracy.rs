//! Time to accuracy on the Cornell box: how long the radiosity solver and the
//! path tracer each take to come within 5%, 3% and 2% of the ground truth.
//!
//! **Truth.** The committed 64 × 64 fixture `tests/fixtures/cornell_truth_64.exr`,
//! made by `solver reference config/cornell_box.toml --size 64x64
//! --target-error 0.005 --seed 1` (standard camera; noise 0.49%).
//!
//! **Error.** MARE, the mean over lit pixels of the relative luminance error
//! (`solver::compare::metrics::summarize`, as `solver compare` reports it).
//!
//! **Solver.** Each preset solves the box in-process as `solver solve --preset P`
//! does (scene config applied, default patches filled); its time is the solve's
//! wall seconds (meshing included) plus the first image: the CPU rasterizer
//! (`solution::raster`, what the runtime shows) from the header camera at
//! 512 × 512, box-filtered 8 × 8 to 64² so that each pixel is the mean over its
//! footprint, as the truth's are.
//!
//! **Path tracer.** The `solver::reference` core in-process (as `solver
//! reference` runs it), with another seed than the truth's so that the noise is
//! independent, at doubling sample counts (16, 32, … per pixel) until MARE ≤ 2%
//! or `PT_CAP_SECONDS` (default 120) pass; the time is cumulative, scene
//! preparation included. Its MARE against the noisy truth cannot fall below
//! about the truth's own noise (0.4%), far below 2%, so the targets measure it.
//!
//! Run: `cargo bench -p solver --bench time_to_accuracy` (env `PRESETS=draft,medium`
//! picks presets). The figures in docs/benchmarks.md, "Time to accuracy", come
//! from it.

// Only the rasterization is used here; the truth's error serves the other benches.
#[allow(dead_code)]
#[path = "common/truth.rs"]
mod truth;

use bench_support::host::cpu_seconds;
use solution::camera::Camera;
use solution::format::Solution;
use solver::compare::image::Image;
use solver::compare::metrics::summarize;
use solver::compare::read::read_image;
use solver::reference::{Accumulator, Integrator, Physics, RenderScene};
use solver::scene::{load_scene, ImportOptions, Scene};
use solver::settings::{Preset, SettingsPatch, SolverSettings};
use solver::solve::Solver;
use std::path::Path;
use std::time::Instant;
use truth::raster_at_truth;

/// The accuracy targets, as MARE fractions.
const TARGETS: [f64; 3] = [0.05, 0.03, 0.02];
/// The truth's seed is 1; any other gives independent noise.
const PATH_TRACER_SEED: u64 = 2;

/// One point of a sweep: a name, the seconds to reach it, and its MARE.
struct Point {
    name: String,
    seconds: f64,
    mare: f64,
}

/// Solves the scene to convergence (or the preset's shot cap), as `solver solve`.
fn solve(scene: &Scene, settings: &SolverSettings) -> Solution {
    let scene = scene.clone();
    let mut solver = Solver::new(&scene, settings).expect("the Cornell box solves");
    while solver.step().is_some() {}
    solver.to_solution(false)
}

/// The solution as the runtime shows it from its header camera, brought to the
/// truth's pixel footprints.
fn first_image(solution: &Solution, truth: &Image) -> Image {
    raster_at_truth(solution, &solution.header.camera, truth)
}

/// Each preset: solve, first image, MARE; prints a row per preset.
fn solver_sweep(scene: &Scene, config: &SettingsPatch, truth: &Image) -> Vec<Point> {
    let wanted = std::env::var("PRESETS").unwrap_or_else(|_| "draft,medium,final".into());
    println!("| solver preset | solve wall s | solve CPU s | first image s | total s | MARE |");
    println!("| --- | --- | --- | --- | --- | --- |");
    let mut points = Vec::new();
    for preset in [Preset::Draft, Preset::Medium, Preset::Final] {
        if !wanted.split(',').any(|w| w.trim() == preset.name()) {
            continue;
        }
        let settings = SolverSettings::resolve(preset, &[config]).expect("the preset resolves");
        let (start, cpu_start) = (Instant::now(), cpu_seconds());
        let solution = solve(scene, &settings);
        let (solve_s, solve_cpu) = (start.elapsed().as_secs_f64(), cpu_seconds() - cpu_start);
        let image_start = Instant::now();
        let image = first_image(&solution, truth);
        let image_s = image_start.elapsed().as_secs_f64();
        let mare = summarize(&image, truth).mare;
        let total = solve_s + image_s;
        println!(
            "| {} | {solve_s:.2} | {solve_cpu:.2} | {image_s:.2} | {total:.2} | {:.2}% |",
            preset.name(),
            100.0 * mare
        );
        points.push(Point {
            name: preset.name().into(),
            seconds: total,
            mare,
        });
    }
    points
}

/// The accumulated mean radiance as an image.
fn accumulated(image: &Accumulator) -> Image {
    Image {
        width: image.width as usize,
        height: image.height as usize,
        rgb: image
            .pixels
            .iter()
            .flat_map(|p| (0..3).map(|c| p.mean(c) as f32))
            .collect(),
    }
}

/// The path tracer at doubling sample counts until MARE ≤ the last target or
/// the time cap; prints a row per count.
fn path_tracer_sweep(scene: &Scene, physics: Physics, truth: &Image, cap: f64) -> Vec<Point> {
    let start = Instant::now();
    let cpu_start = cpu_seconds();
    let render = RenderScene::new(scene, physics);
    let integrator = Integrator {
        scene: &render,
        max_depth: None,
    };
    let camera = Camera {
        width: truth.width as u32,
        height: truth.height as u32,
        ..scene.camera.expect("the config names the standard camera")
    };
    let view = camera.mono_view(scene.recentre_offset);
    let mut image = Accumulator::new(camera.width, camera.height);
    println!("| path tracer spp | cumulative wall s | cumulative CPU s | MARE |");
    println!("| --- | --- | --- | --- |");
    let mut points = Vec::new();
    while points.last().is_none_or(|p: &Point| p.mare > TARGETS[2]) {
        let spp = image.samples_per_pixel().max(16) as u32;
        image.render_pass(&integrator, &view, PATH_TRACER_SEED, spp, &|_| {});
        let seconds = start.elapsed().as_secs_f64();
        let mare = summarize(&accumulated(&image), truth).mare;
        let total = image.samples_per_pixel();
        let cpu = cpu_seconds() - cpu_start;
        println!(
            "| {total} | {seconds:.2} | {cpu:.2} | {:.2}% |",
            100.0 * mare
        );
        points.push(Point {
            name: format!("{total} spp"),
            seconds,
            mare,
        });
        if seconds > cap {
            break;
        }
    }
    points
}

/// For each target, the cheapest point of a sweep that reaches it.
fn report_targets(what: &str, points: &[Point], last: &str) {
    for target in TARGETS {
        let best = points
            .iter()
            .filter(|p| p.mare <= target)
            .min_by(|a, b| a.seconds.total_cmp(&b.seconds));
        let text = best.map_or(format!("not reached by {last}"), |p| {
            format!(
                "{:.2} s ({}, MARE {:.2}%)",
                p.seconds,
                p.name,
                100.0 * p.mare
            )
        });
        println!("{what}: MARE ≤ {:.0}%: {text}", 100.0 * target);
    }
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let truth = read_image(&root.join("tests/fixtures/cornell_truth_64.exr"))
        .expect("the truth fixture reads")
        .image;
    let loaded = load_scene(
        &root.join("config/cornell_box.toml"),
        &ImportOptions::default(),
    )
    .expect("config/cornell_box.toml loads");
    let cap: f64 = std::env::var("PT_CAP_SECONDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(120.0);
    println!(
        "Cornell box, truth {}x{}, {} threads; MARE = mean relative luminance error over lit pixels",
        truth.width,
        truth.height,
        rayon::current_num_threads()
    );
    println!();
    let solver_points = solver_sweep(&loaded.scene, &loaded.settings, &truth);
    println!();
    // The same mode as `solver reference` resolves.
    let settings = SolverSettings::resolve(Preset::default(), &[&loaded.settings])
        .expect("the config resolves");
    let physics = Physics {
        mode: settings.mode,
    };
    let tracer_points = path_tracer_sweep(&loaded.scene, physics, &truth, cap);
    println!();
    report_targets("solver", &solver_points, "final");
    let last = tracer_points.last().map_or("-".into(), |p| p.name.clone());
    report_targets("path tracer", &tracer_points, &last);
}
