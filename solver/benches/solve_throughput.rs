//! Effective visibility throughput of the whole solve: rays traced divided by
//! the wall time of the entire solve (meshing, BVH, shooting, refinement,
//! gather), on ONE thread, for the Cornell box with each preset's settings,
//! with where the time went.
//!
//! This is the figure of merit for the solver core: it is the packet
//! speed of the occluder (`--bench visibility`) less everything the solver does
//! around the rays. Run: `cargo bench -p solver --bench solve_throughput`
//! (env `PRESETS=draft,medium`, `SHOTS=N` caps the shots, default 200; `SAMPLES=N`
//! overrides every preset's rays per receiver, e.g. 64 for the reference
//! workload now that the presets use fewer). The CPU-time
//! column divides by the solve's CPU time instead: on a shared machine it is the
//! steadier figure (wall time includes waiting for a core).

use bench_support::host::live_threads_cpu_seconds;
use solver::scene::{load_scene, ImportOptions};
use solver::settings::{Preset, SolverSettings};
use solver::solve::Solver;
use std::path::Path;
use std::time::Instant;

fn main() {
    let presets: Vec<Preset> = std::env::var("PRESETS")
        .unwrap_or_else(|_| "draft,medium,final".into())
        .split(',')
        .filter_map(|p| match p.trim() {
            "draft" => Some(Preset::Draft),
            "medium" => Some(Preset::Medium),
            "final" => Some(Preset::Final),
            _ => None,
        })
        .collect();
    let shots: u64 = std::env::var("SHOTS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(200);
    let samples: Option<u32> = std::env::var("SAMPLES").ok().and_then(|s| s.parse().ok());
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/cornell_box.obj");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("one worker thread");
    println!(
        "| preset | samples | shots | elements | vertices | rays | wall s | M rays/s (1 thread) | \
         cpu s | M rays/s by CPU | setup s | shoot s | shoot M rays/s | refine s | refine M rays/s | gather s |"
    );
    println!(
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    );
    for preset in presets {
        let scene = load_scene(&path, &ImportOptions::default())
            .expect("config/cornell_box.obj imports")
            .scene;
        let mut settings = SolverSettings::preset(preset);
        settings.max_shots = shots;
        if let Some(samples) = samples {
            settings.samples = samples;
        }
        // The solve runs on one rayon worker while the main thread sleeps, so
        // the live threads' CPU time is the solve's own: unlike the wall time
        // it leaves out time spent waiting for a core on a shared machine.
        let cpu_start = live_threads_cpu_seconds();
        let start = Instant::now();
        let solver = pool.install(|| {
            let mut solver = Solver::new(&scene, &settings).expect("the Cornell box solves");
            while solver.step().is_some() {}
            solver
        });
        let wall = start.elapsed().as_secs_f64();
        let cpu = match (cpu_start, live_threads_cpu_seconds()) {
            (Some(a), Some(b)) => b - a,
            _ => f64::NAN,
        };
        let p = solver.progress();
        let t = solver.timings();
        let setup = wall - t.shoot - t.refine - t.gather;
        println!(
            "| {} | {} | {} | {} | {} | {:.3e} | {:.2} | {:.1} | {:.2} | {:.1} | {:.3} | {:.2} | {:.1} | {:.2} | {:.1} | {:.2} |",
            preset.name(),
            settings.samples,
            p.shots,
            p.elements,
            p.vertices,
            p.rays as f64,
            wall,
            p.rays as f64 / wall / 1e6,
            cpu,
            p.rays as f64 / cpu / 1e6,
            setup,
            t.shoot,
            t.shoot_rays as f64 / t.shoot / 1e6,
            t.refine,
            (p.rays - t.shoot_rays) as f64 / t.refine / 1e6,
            t.gather
        );
    }
}
