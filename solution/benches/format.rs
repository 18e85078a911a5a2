//! Throughput of the solution-file codec: encode, write (atomic, with fsync),
//! validating map, decode, and materializing from the map.
//!
//! `cargo bench -p solution --bench format` (figures in docs/benchmarks.md).
//! The workload is a scene-sized file: 300,000 diffuse vertices (L = 0, f32) and
//! 30,000 glossy vertices (L = 6, 49 coefficients per channel, f16).

use solution::camera::{Camera, UpAxis};
use solution::format::{
    decode, encode, f16_scale_for, write_solution, Batch, Header, MappedSolution, Representation,
    ScalarType, Solution, SolveMode, SolveStats, Vertex,
};
use std::hint::black_box;
use std::time::Instant;

fn batch(vertex_count: u32, order: u32, f16: bool) -> Batch {
    let vertices: Vec<Vertex> = (0..vertex_count)
        .map(|i| Vertex {
            position: [(i % 1000) as f32, (i / 1000) as f32, 0.5],
            normal: [0.0, 0.0, 1.0],
            tangent: [1.0, 0.0, 0.0],
        })
        .collect();
    let per_vertex = ((order + 1) * (order + 1) * 3) as usize;
    let coefficients: Vec<f32> = (0..vertices.len() * per_vertex)
        .map(|k| ((k * 2_654_435_761) % 10_007) as f32 * 1e-3)
        .collect();
    // Two triangles per vertex, as a grid mesh has.
    let n = vertex_count.saturating_sub(2).max(1);
    let indices: Vec<u32> = (0..2 * vertex_count)
        .flat_map(|t| {
            let v = t % n;
            [v, v + 1, v + 2]
        })
        .collect();
    let scalar = if f16 {
        ScalarType::F16 {
            scale: f16_scale_for(&coefficients),
        }
    } else {
        ScalarType::F32
    };
    Batch {
        representation: Representation::Sh { order },
        scalar,
        vertices,
        coefficients,
        indices,
        texturing: None,
    }
}

fn time<T>(label: &str, bytes: u64, repeats: u32, mut f: impl FnMut() -> T) {
    // One warm-up run, then the best of `repeats` (least disturbed by the other
    // processes on a shared machine).
    black_box(f());
    let mut best = f64::INFINITY;
    for _ in 0..repeats {
        let start = Instant::now();
        black_box(f());
        best = best.min(start.elapsed().as_secs_f64());
    }
    println!(
        "{label:<34} {:>8.2} ms  {:>7.0} MB/s",
        best * 1e3,
        bytes as f64 / best / 1e6
    );
}

fn main() {
    let solution = Solution {
        lighting: None,
        header: Header {
            units_per_metre: 1000.0,
            up_axis: UpAxis::PosY,
            recentre_offset: [0.0; 3],
            camera: Camera::default(),
            bounds_min: [0.0; 3],
            bounds_max: [1000.0, 1000.0, 1.0],
            partial: false,
            mode: SolveMode::Directional,
            stats: SolveStats::default(),
            settings_json: "{}".into(),
        },
        batches: vec![batch(300_000, 0, false), batch(30_000, 6, true)],
        textures: Vec::new(),
    };
    let bytes = encode(&solution).expect("encode");
    let len = bytes.len() as u64;
    println!(
        "file: {:.1} MB, {} vertices",
        len as f64 / 1e6,
        solution
            .batches
            .iter()
            .map(|b| b.vertices.len())
            .sum::<usize>()
    );
    let dir = std::env::temp_dir().join(format!("solver-format-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("bench.sol");

    time("encode (validate + serialize)", len, 5, || {
        encode(&solution).expect("encode")
    });
    time("decode (validate + materialize)", len, 5, || {
        decode(&bytes).expect("decode")
    });
    time("write_solution (temp, fsync, rename)", len, 3, || {
        write_solution(&path, &solution).expect("write")
    });
    time("MappedSolution::open (all checks)", len, 5, || {
        MappedSolution::open(&path).expect("open")
    });
    let mapped = MappedSolution::open(&path).expect("open");
    time("MappedSolution::to_solution", len, 5, || {
        mapped.to_solution().unwrap()
    });
    let _ = std::fs::remove_dir_all(&dir);
}
