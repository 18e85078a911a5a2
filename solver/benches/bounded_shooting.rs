//! Flat against bounded shooting (`solve/cluster.rs`, docs/benchmarks.md,
//! "Bounded shooting"): per scene, preset and shooting method, the solve's wall
//! and CPU seconds, shots, vertices, rays, receivers visited ray by ray per
//! shot, and the seconds per shot, with where the step time went.
//!
//! Run: `cargo bench -p solver --bench bounded_shooting` with env
//! `SCENES=a.toml,b.obj` (default the Cornell box config), `PRESETS=draft,medium`
//! (default draft), `SHOOTING=flat,bounded` (default both), `TOLERANCE=x`
//! (bounded shooting's tolerance, default the setting's), `SHOTS=N` (cap,
//! default the preset's) and `THREADS=N` (default 2). CPU seconds are the
//! steadier figure on a shared machine; wall seconds include waiting for a core.

use solver::scene::{load_scene, ImportOptions};
use solver::settings::{Preset, Shooting, SolverSettings};
use solver::solve::Solver;
use std::path::PathBuf;
use std::time::Instant;

fn env_list(name: &str, default: &str) -> Vec<String> {
    std::env::var(name)
        .unwrap_or_else(|_| default.into())
        .split(',')
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .collect()
}

fn main() {
    let default_scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../config/cornell_box.toml");
    let scenes = env_list("SCENES", default_scene);
    let presets = env_list("PRESETS", "draft");
    let methods = env_list("SHOOTING", "flat,bounded");
    let tolerance: Option<f64> = std::env::var("TOLERANCE").ok().and_then(|s| s.parse().ok());
    let shots: Option<u64> = std::env::var("SHOTS").ok().and_then(|s| s.parse().ok());
    let threads: usize = std::env::var("THREADS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("worker threads");
    println!(
        "| scene | preset | shooting | triangles | shots | vertices | rays | visited/shot | \
         bounded/shot | wall s | cpu s | ms/shot (cpu) | shoot s | refine s | gather s | unshot |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for scene_path in &scenes {
        let path = PathBuf::from(scene_path);
        let loaded = match load_scene(&path, &ImportOptions::default()) {
            Ok(l) => l,
            Err(e) => {
                eprintln!("{scene_path}: {e}");
                continue;
            }
        };
        let triangles: usize = loaded
            .scene
            .polygons
            .iter()
            .map(|p| p.vertices.len().saturating_sub(2))
            .sum();
        let name = path
            .parent()
            .and_then(|p| p.file_name())
            .map_or_else(|| scene_path.clone(), |n| n.to_string_lossy().into_owned());
        for preset_name in &presets {
            let preset = match preset_name.as_str() {
                "draft" => Preset::Draft,
                "medium" => Preset::Medium,
                "final" => Preset::Final,
                other => {
                    eprintln!("unknown preset {other}");
                    continue;
                }
            };
            for method in &methods {
                let mut settings = SolverSettings::resolve(preset, &[&loaded.settings])
                    .expect("the scene's settings are valid");
                settings.shooting = match method.as_str() {
                    "flat" => Shooting::Flat,
                    _ => Shooting::Bounded,
                };
                if let Some(t) = tolerance {
                    settings.shooting_tolerance = t;
                }
                if let Some(s) = shots {
                    settings.max_shots = s;
                }
                let mut scene = loaded.scene.clone();
                scene.fill_default_patches(settings.patches);
                let cpu_start = process_cpu_seconds();
                let start = Instant::now();
                let solver = pool.install(|| {
                    let mut solver = Solver::new(&scene, &settings).expect("the scene solves");
                    while solver.step().is_some() {}
                    solver
                });
                let wall = start.elapsed().as_secs_f64();
                let cpu = match (cpu_start, process_cpu_seconds()) {
                    (Some(a), Some(b)) => b - a,
                    _ => f64::NAN,
                };
                let p = solver.progress();
                let t = solver.timings();
                let per_shot = |n: u64| n as f64 / p.shots.max(1) as f64;
                let visited = if settings.shooting == Shooting::Flat {
                    // Flat shooting visits every vertex: the mean over shots
                    // is close to the final count once refinement settles.
                    p.vertices as f64
                } else {
                    per_shot(t.visited_receivers)
                };
                println!(
                    "| {name} | {preset_name} | {method} | {triangles} | {} | {} | {} | {:.0} | {:.0} | \
                     {wall:.2} | {cpu:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.4} |",
                    p.shots,
                    p.vertices,
                    p.rays,
                    visited,
                    per_shot(t.bounded_receivers),
                    1e3 * cpu / p.shots.max(1) as f64,
                    t.shoot,
                    t.refine,
                    t.gather,
                    p.unshot_fraction,
                );
            }
        }
    }
}

/// User + system CPU seconds of this process (Linux `/proc/self/stat`).
fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let after = stat.rsplit_once(')')?.1;
    let fields: Vec<&str> = after.split_whitespace().collect();
    let ticks = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}
