//! The quality presets on the Cornell box: what each costs and how accurate it is.
//!
//! For `draft`, `medium` and `final` (config/presets.toml, with the scene config
//! config/cornell_box.toml applied as the CLI applies it) this solves the box on
//! every core and prints elements, vertices, shots, rays, wall seconds (meshing
//! included), rays per second per core, and the error against a reference.
//!
//! **Reference.** The meshing of preset `REFERENCE_PRESET` (default `final`) with
//! `REFERENCE_SAMPLES` visibility rays (default 256) and a threshold of
//! `REFERENCE_THRESHOLD` (default 1e-4) and another seed than the presets',
//! cached in `target/bench-cache/` because it is by far the slowest part (delete
//! the file to recompute it).
//!
//! **Error.** Each solution and the reference are drawn by the CPU rasterizer
//! (`solution::raster`, linear radiance, what the runtime shows) from two fixed
//! cameras at 256 × 256: the standard Cornell camera, and a view from a high front
//! corner toward the blocks. The error is the relative RMS radiance difference
//!
//!     e = sqrt( Σ_pixels Σ_rgb (I − R)² / Σ_pixels Σ_rgb R² )
//!
//! over both images, where R is the reference and I the preset's image. It measures
//! what a viewer sees — noise in penumbrae, missing interreflection (threshold),
//! Gouraud interpolation over coarse elements — in one number; a pixel that one
//! image covers and the other does not counts in full. Being against a converged
//! solution, it measures convergence, not accuracy.
//!
//! **Against the truth.** Beside it, each preset's (and the reference's) MARE and
//! HDR-FLIP against the committed 64 × 64 path-traced truth of the standard camera
//! (`tests/fixtures/cornell_truth_64.exr`, `common/truth.rs`): bias plus the
//! truth's 0.5% noise.
//!
//! Run: `cargo bench -p solver --bench presets` (env `PRESETS=draft,medium` picks
//! presets). The figures in docs/benchmarks.md, "Solver presets", come from it.

#[path = "common/truth.rs"]
mod truth;

use bench_support::host::{cpu_model, cpu_seconds};
use bench_support::metrics::relative_l2;
use solution::camera::Camera;
use solution::format::Solution;
use solution::raster::{render, RenderOptions};
use solver::scene::{load_scene, ImportOptions, Scene};
use solver::settings::{Preset, SettingsPatch, SolverSettings};
use solver::solve::Solver;
use std::path::{Path, PathBuf};
use std::time::Instant;

struct Run {
    solution: Solution,
    elements: usize,
    vertices: usize,
    shots: u64,
    rays: u64,
    seconds: f64,
    /// User + system CPU seconds of the process during the solve (all threads).
    cpu_seconds: f64,
    unshot_fraction: f64,
}

fn solve(scene: &Scene, settings: &SolverSettings) -> Run {
    let start = Instant::now();
    let cpu_start = cpu_seconds();
    let mut solver = Solver::new(scene, settings).expect("the Cornell box solves");
    while solver.step().is_some() {}
    let seconds = start.elapsed().as_secs_f64();
    let cpu_seconds = cpu_seconds() - cpu_start;
    let p = solver.progress();
    Run {
        solution: solver.to_solution(false),
        elements: p.elements,
        vertices: p.vertices,
        shots: p.shots,
        rays: p.rays,
        seconds,
        cpu_seconds,
        unshot_fraction: p.unshot_fraction,
    }
}

/// The two views of the error measure, in original scene coordinates (mm).
fn cameras(standard: Camera) -> [Camera; 2] {
    let side = 256;
    [
        Camera {
            width: side,
            height: side,
            ..standard
        },
        Camera {
            eye: [500.0, 500.0, 40.0],
            target: [250.0, 120.0, 300.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 60.0,
            width: side,
            height: side,
        },
    ]
}

fn images(solution: &Solution, cameras: &[Camera]) -> Vec<solution::raster::Image> {
    let offset = glam::DVec3::from_array(solution.header.recentre_offset);
    cameras
        .iter()
        .map(|c| render(solution, &c.mono_view(offset), &RenderOptions::default()).unwrap())
        .collect()
}

/// Relative RMS radiance difference over all pixels and channels of all views
/// (the L2 norm of the difference over the reference's).
fn relative_rms(test: &[solution::raster::Image], reference: &[solution::raster::Image]) -> f64 {
    relative_l2(test.iter().zip(reference).flat_map(|(t, r)| {
        t.pixels
            .iter()
            .zip(&r.pixels)
            .flat_map(|(a, b)| (0..3).map(move |c| (a[c] as f64, b[c] as f64)))
    }))
}

fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let scene_path = root.join("config/cornell_box.toml");
    let loaded =
        load_scene(&scene_path, &ImportOptions::default()).expect("config/cornell_box.toml loads");
    let config: SettingsPatch = loaded.settings.clone();
    let scene = loaded.scene;
    let standard = scene.camera.expect("the config names the standard camera");
    let views = cameras(standard);
    let threads = rayon::current_num_threads();

    // The reference, cached.
    let ref_samples: u32 = env_or("REFERENCE_SAMPLES", 256);
    let ref_threshold: f64 = env_or("REFERENCE_THRESHOLD", 1e-4);
    let ref_preset = match std::env::var("REFERENCE_PRESET").as_deref() {
        Ok("draft") => Preset::Draft,
        Ok("medium") => Preset::Medium,
        _ => Preset::Final,
    };
    let mut reference_settings = SolverSettings::resolve(ref_preset, &[&config]).unwrap();
    reference_settings.samples = ref_samples;
    reference_settings.threshold = ref_threshold;
    reference_settings.max_shots = u64::MAX / 2;
    // Other jitter than the presets', so that the reference's noise is independent
    // of theirs (with the same seed a preset would share the reference's samples).
    reference_settings.seed = reference_settings.seed.wrapping_add(1000);
    let cache_dir = root.join("target/bench-cache");
    let cache: PathBuf = cache_dir.join(format!(
        "cornell-reference-{}-s{ref_samples}-t{ref_threshold:e}-seed+1000.sol",
        ref_preset.name()
    ));
    let reference = match solution::format::read_solution(&cache) {
        Ok(solution) => {
            eprintln!("presets: reference from {}", cache.display());
            solution
        }
        Err(_) => {
            eprintln!(
                "presets: computing the reference ({ref_samples} samples, threshold \
                 {ref_threshold:e}); cached in {}",
                cache.display()
            );
            let run = solve(&scene, &reference_settings);
            eprintln!(
                "presets: reference: {} elements, {} vertices, {} shots, {:.1} s",
                run.elements, run.vertices, run.shots, run.seconds
            );
            std::fs::create_dir_all(&cache_dir).unwrap();
            solution::format::write_solution(&cache, &run.solution).unwrap();
            run.solution
        }
    };
    let reference_images = images(&reference, &views);
    let truth = truth::CornellTruth::load(&root);
    let reference_truth = truth.error(&reference);

    let wanted = std::env::var("PRESETS").unwrap_or_else(|_| "draft,medium,final".into());
    println!("CPU: {} ({threads} threads)", cpu_model());
    println!(
        "reference: {} meshing, {ref_samples} samples, threshold {ref_threshold:e}; \
         error = relative RMS radiance difference over 2 views at 256x256",
        ref_preset.name()
    );
    println!("{}", truth.describe());
    println!(
        "the reference itself vs truth: MARE {:.2}%, HDR-FLIP {:.3}",
        100.0 * reference_truth.mare,
        reference_truth.flip
    );
    println!();
    println!(
        "| preset | samples | threshold | elements | vertices | shots | rays | wall s | CPU s | \
         rays/s per core (wall) | rays per CPU s | unshot | error vs reference | MARE vs truth | \
         HDR-FLIP vs truth |"
    );
    println!(
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    );
    for preset in [Preset::Draft, Preset::Medium, Preset::Final] {
        if !wanted.split(',').any(|w| w.trim() == preset.name()) {
            continue;
        }
        let settings = SolverSettings::resolve(preset, &[&config]).unwrap();
        let run = solve(&scene, &settings);
        let error = relative_rms(&images(&run.solution, &views), &reference_images);
        let against_truth = truth.error(&run.solution);
        println!(
            "| {} | {} | {} | {} | {} | {} | {:.3e} | {:.2} | {:.2} | {:.3e} | {:.3e} | {:.2e} | {:.4} | {:.2}% | {:.3} |",
            preset.name(),
            settings.samples,
            settings.threshold,
            run.elements,
            run.vertices,
            run.shots,
            run.rays as f64,
            run.seconds,
            run.cpu_seconds,
            run.rays as f64 / run.seconds / threads as f64,
            run.rays as f64 / run.cpu_seconds,
            run.unshot_fraction,
            error,
            100.0 * against_truth.mare,
            against_truth.flip
        );
    }
}
