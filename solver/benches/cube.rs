//! The global-cube representation (Immel, Cohen and Greenberg 1986; `solve --method cube`) on the
//! bundled glossy scene, `config/glossy_floor.toml` with the `medium` preset's
//! patches and samples: for k = 2, 4, 8, 16, 32 (D = 6k²), the transport and
//! sweep seconds on every core, the solve's memory estimate (what it refuses
//! on), the solution file's size, and how far the floor's radiance toward the
//! config camera's eye is from the k = 32 solve (relative L2 over the floor's
//! vertices: a self-convergence figure; the issue-7 convergence test compares
//! against an independent reference).
//!
//! Run: `cargo bench -p solver --bench cube`. The figures in docs/benchmarks.md,
//! "Global cube", come from it.

use bench_support::metrics::relative_l2;
use glam::DVec3;
use solver::scene::load_scene;
use solver::settings::{DirectionalRepresentation, Preset, SolverSettings};
use solver::solve::cube_gather::{solve_cube, CubeLimits, CubeResult};
use std::path::Path;
use std::time::Instant;

fn main() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/glossy_floor.toml");
    let loaded = load_scene(&path, &Default::default()).expect("config/glossy_floor.toml loads");
    let mut settings = SolverSettings::preset(Preset::Medium);
    settings.apply(&loaded.settings);
    settings.directional = DirectionalRepresentation::Cube;
    let scene = loaded.scene;
    let eye = DVec3::from_array(scene.camera.expect("the config names a camera").eye);
    let limits = CubeLimits::default();
    let threads = rayon::current_num_threads();
    println!(
        "## Global cube: glossy_floor.toml, medium preset (patch size {} of the diagonal, {} samples), {threads} threads",
        settings.patch_size, settings.samples
    );
    let mut runs: Vec<(u32, CubeResult, f64, usize)> = Vec::new();
    for k in [2u32, 4, 8, 16, 32] {
        settings.cube_resolution = k;
        let start = Instant::now();
        let result = solve_cube(&scene, &settings, &limits).expect("the solve fits");
        let wall = start.elapsed().as_secs_f64();
        let bytes = solution::format::encode(&result.solution)
            .expect("the solution encodes")
            .len();
        runs.push((k, result, wall, bytes));
    }
    let toward_eye = |r: &CubeResult| -> Vec<f64> {
        (0..r.vertex_count() as u32)
            .filter(|&v| r.is_glossy(v))
            .map(|v| {
                let q = r.receiving_points[v as usize];
                r.radiance_toward(v, (eye - r.offset) - q).element_sum()
            })
            .collect()
    };
    let finest = toward_eye(&runs.last().expect("five runs").1);
    println!("| k | D | transport s | sweeps | sweep s | wall s | memory estimate MiB | file KiB | L2 vs k = 32 |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for (k, r, wall, bytes) in &runs {
        let values = toward_eye(r);
        println!(
            "| {k} | {} | {:.3} | {} | {:.3} | {:.3} | {:.1} | {:.1} | {:.3} |",
            6 * k * k,
            r.form_factor_seconds,
            r.sweeps,
            r.solve_seconds,
            wall,
            r.memory_bytes as f64 / (1u64 << 20) as f64,
            *bytes as f64 / 1024.0,
            relative_l2(values.iter().copied().zip(finest.iter().copied()))
        );
    }
}
