//! The default-view chooser's cost (docs/benchmarks.md, "Default view"): the
//! closed box room of `solution::view::fixture` at growing triangle counts, or
//! the solution files named on the command line.
//!
//! Usage: `cargo run --release -p solver --example default_view_cost [FILE.sol ...]`

use solution::format::{MappedSolution, Solution};
use solution::view::fixture;
use solver::view::{choose_view, ViewScene};
use std::time::Instant;

fn measure(name: &str, solution: &Solution) {
    let start = Instant::now();
    let scene = ViewScene::from_solution(solution);
    let built = start.elapsed();
    let start = Instant::now();
    let view = choose_view(
        &scene,
        solution.header.up_axis,
        solution.header.units_per_metre,
    );
    let chosen = start.elapsed();
    println!(
        "{name}: {} triangles, gather + BVH {:.3} s, 49 candidates × 130 rays {:.3} s, {}",
        scene.triangle_count(),
        built.as_secs_f64(),
        chosen.as_secs_f64(),
        match view {
            Some(v) => format!(
                "eye {:.3?}, {:.0}% front, {} of {} kept",
                v.eye.to_array(),
                100.0 * v.front_fraction,
                v.kept,
                v.candidates
            ),
            None => "no candidate kept (framing camera)".to_owned(),
        }
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let files: Vec<String> = std::env::args().skip(1).collect();
    if files.is_empty() {
        // 24·cells² + 2 triangles: 100k at 65 cells, 1M at 205.
        for cells in [4, 65, 205] {
            measure(
                &format!("box room, {cells} cells a face"),
                &fixture::box_room_with(cells),
            );
        }
    }
    for file in files {
        let solution = MappedSolution::open(&file)?.to_solution()?;
        measure(&file, &solution);
    }
    Ok(())
}
