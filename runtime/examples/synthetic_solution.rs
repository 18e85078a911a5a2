//! Writes the synthetic test rooms (`runtime/tests/common`) as solution files,
//! for `runtime bench` and `runtime screenshot` before real solver output exists.
//!
//! Usage: `cargo run -p runtime --example synthetic_solution -- OUT.sol KIND N [P] [f16]`
//! with KIND one of
//! - `diffuse`, `glossy`, `cube`: N = subdivisions per room face; P = the glossy
//!   floor's SH order, default 8, or for `cube` its global-cube resolution k,
//!   D = 6k², default 12;
//! - `sized`: the glossy room with N chosen so that the file is about N MiB
//!   (P = the floor's SH order, default 16), for the upload benchmark of
//!   docs/benchmarks.md ("Opening a solution");
//! - `city`: N × N box buildings with faces of P × P cells (default 10) on a
//!   glossy ground (`common::city`): 10·N²·P² + 32·N² triangles, for the
//!   runtime at scale (docs/benchmarks.md, "Runtime at scale"; N = 32 gives
//!   1.06M triangles).
//!
//! A last argument `f16` stores the directional batch (the floor) as IEEE half
//! with the writer's per-batch scale.

#[path = "../tests/common/mod.rs"]
mod common;

use solution::format::{layout, Batch, Representation, ScalarType, Solution};

/// The largest coefficient section of a `sized` batch: devices bound a storage
/// buffer range (lavapipe: 128 MiB), so the floor is split into strips of rows
/// of at most this many coefficient bytes.
const MAX_BATCH_COEFFICIENT_BYTES: usize = 96 << 20;

/// Subdivisions of the glossy room whose file is about `mib` MiB at SH order
/// `order`: the floor's vertices carry `(order + 1)² · 3` coefficients, the three
/// walls' vertices three, and each of the four faces has `(n + 1)²` vertices and
/// `6n²` indices.
fn subdivisions_for_size(mib: u64, order: u32, scalar_bytes: u64) -> usize {
    let floor = layout::VERTEX_LEN as f64
        + (Representation::Sh { order }.coefficients_per_channel() * 3 * scalar_bytes) as f64;
    let walls = 3.0 * (layout::VERTEX_LEN as f64 + 12.0);
    let indices = 4.0 * 6.0 * 4.0;
    let per_n2 = floor + walls + indices;
    let target = (mib as f64) * 1024.0 * 1024.0;
    ((target / per_n2).sqrt() - 1.0).round().max(1.0) as usize
}

/// Splits a `Quad` grid batch of `n` × `n` cells (rows of `n + 1` vertices,
/// `6n` indices per strip of cells) into strips of whole rows whose
/// coefficients take at most `max_bytes` each; the rows between strips are
/// duplicated (each strip has its own vertices).
fn split_into_strips(batch: Batch, n: usize, scalar_bytes: usize, max_bytes: usize) -> Vec<Batch> {
    let row = n + 1;
    let stride = batch.representation.coefficients_per_channel() as usize * 3;
    let row_bytes = row * stride * scalar_bytes;
    // A strip of s cells high has s + 1 rows.
    let cells = (max_bytes / row_bytes).saturating_sub(1).max(1);
    let mut strips = Vec::new();
    let mut first = 0;
    while first < n {
        let last = (first + cells).min(n);
        let (v0, v1) = (first * row, (last + 1) * row);
        strips.push(Batch {
            representation: batch.representation,
            scalar: batch.scalar,
            vertices: batch.vertices[v0..v1].to_vec(),
            coefficients: batch.coefficients[v0 * stride..v1 * stride].to_vec(),
            indices: batch.indices[first * 6 * n..last * 6 * n]
                .iter()
                .map(|i| i - v0 as u32)
                .collect(),
            texturing: None,
        });
        first = last;
    }
    strips
}

fn to_f16(solution: &mut Solution) {
    for batch in &mut solution.batches {
        if batch.representation != (Representation::Sh { order: 0 }) {
            let scale = solution::format::f16_scale_for(&batch.coefficients);
            batch.scalar = ScalarType::F16 { scale };
        }
    }
}

fn main() -> anyhow::Result<()> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let f16 = args.last().is_some_and(|a| a == "f16");
    if f16 {
        args.pop();
    }
    anyhow::ensure!(
        args.len() >= 3,
        "usage: synthetic_solution OUT.sol diffuse|glossy|cube|sized|city N [P] [f16]"
    );
    let n: usize = args[2].parse()?;
    let param = |default: u32| -> anyhow::Result<u32> {
        Ok(args
            .get(3)
            .map(|s| s.parse())
            .transpose()?
            .unwrap_or(default))
    };
    let mut solution = match args[1].as_str() {
        "diffuse" | "glossy" | "cube" => {
            anyhow::ensure!((1..=1000).contains(&n), "N must be in 1..=1000");
            match args[1].as_str() {
                "diffuse" => common::diffuse_room(n),
                "glossy" => common::glossy_room(n, param(8)?),
                _ => {
                    let k = param(12)?;
                    anyhow::ensure!((1..=64).contains(&k), "cube resolution k must be in 1..=64");
                    common::cube_room(n, k)
                }
            }
        }
        "sized" => {
            anyhow::ensure!((1..=8192).contains(&n), "the size must be 1..=8192 MiB");
            let order = param(16)?;
            anyhow::ensure!((1..=64).contains(&order), "the SH order must be in 1..=64");
            let scalar_bytes = if f16 { 2 } else { 4 };
            let subdivisions = subdivisions_for_size(n as u64, order, scalar_bytes as u64);
            let mut room = common::glossy_room(subdivisions, order);
            // glossy_room: batch 0 the walls, batch 1 the floor grid.
            let floor = room.batches.pop().expect("the glossy floor");
            room.batches.extend(split_into_strips(
                floor,
                subdivisions,
                scalar_bytes,
                MAX_BATCH_COEFFICIENT_BYTES,
            ));
            eprintln!(
                "sized: order {order}, {subdivisions} subdivisions per face, floor in {} batches",
                room.batches.len() - 1
            );
            room
        }
        "city" => {
            anyhow::ensure!(
                (1..=200).contains(&n),
                "N must be in 1..=200 buildings per side"
            );
            let cells = param(10)?;
            anyhow::ensure!(
                (1..=100).contains(&cells),
                "P must be in 1..=100 cells per face side"
            );
            common::city(n, cells as usize)
        }
        other => anyhow::bail!("unknown kind {other:?} (diffuse, glossy, cube, sized or city)"),
    };
    if f16 {
        to_f16(&mut solution);
    }
    solution::format::write_solution(std::path::Path::new(&args[0]), &solution)?;
    let vertices: usize = solution.batches.iter().map(|b| b.vertices.len()).sum();
    let triangles: usize = solution.batches.iter().map(|b| b.indices.len() / 3).sum();
    // Read back through the validating reader, as the runtime opens it.
    let written = solution::format::MappedSolution::open(std::path::Path::new(&args[0]))?;
    println!(
        "wrote {} ({vertices} vertices, {triangles} triangles, {} batches; per-frame cost {} basis terms per view, limit {})",
        args[0],
        solution.batches.len(),
        solution::format::frame_cost(written.batches()),
        solution::format::DEFAULT_MAX_FRAME_COST
    );
    Ok(())
}
