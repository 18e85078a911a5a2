//! `solver export` on synthetic solutions of about a million triangles: the
//! child's wall time and peak resident set (wait4's ru_maxrss) against the
//! sizes of its input and output. Prints figures; asserts nothing.
//!
//! `cargo bench -p solver --bench export [-- SIDE]`: a SIDE × SIDE vertex grid
//! (default 708: 999,698 triangles), once diffuse (SH order 0, f32) and once
//! glossy (SH order 2, f16), each exported as `.glb` and as `.gltf` + `.bin`.

use bench_support::child::Measuring;
use solution::camera::{Camera, UpAxis};
use solution::format::{
    f16_scale_for, write_solution, Batch, Header, Representation, ScalarType, Solution, SolveMode,
    SolveStats, Vertex,
};
use std::path::Path;
use std::process::{Command, Stdio};

/// A flat grid of `side²` vertices one unit apart (units: centimetres, +z
/// up), two triangles per cell, with smoothly varying coefficients.
fn grid(side: u32, order: u32) -> Solution {
    let n = (order as usize + 1).pow(2);
    let mut vertices = Vec::with_capacity((side * side) as usize);
    let mut coefficients = Vec::with_capacity((side * side) as usize * n * 3);
    let half = side as f32 / 2.0;
    for j in 0..side {
        for i in 0..side {
            vertices.push(Vertex {
                position: [i as f32 - half, j as f32 - half, 0.0],
                normal: [0.0, 0.0, 1.0],
                tangent: [1.0, 0.0, 0.0],
            });
            for k in 0..n * 3 {
                let phase = (i as f32 * 0.01 + j as f32 * 0.02 + k as f32).sin();
                coefficients.push(if k < 3 { 2.0 + phase } else { 0.1 * phase });
            }
        }
    }
    let mut indices = Vec::with_capacity(((side - 1) * (side - 1) * 6) as usize);
    for j in 0..side - 1 {
        for i in 0..side - 1 {
            let a = j * side + i;
            indices.extend_from_slice(&[a, a + 1, a + side + 1, a, a + side + 1, a + side]);
        }
    }
    let scalar = if order == 0 {
        ScalarType::F32
    } else {
        ScalarType::F16 {
            scale: f16_scale_for(&coefficients),
        }
    };
    Solution {
        lighting: None,
        header: Header {
            units_per_metre: 100.0,
            up_axis: UpAxis::PosZ,
            recentre_offset: [1000.0, 2000.0, 0.0],
            camera: Camera {
                eye: [1000.0, 2000.0 - half as f64, 300.0],
                target: [1000.0, 2000.0, 0.0],
                up: [0.0, 0.0, 1.0],
                ..Camera::default()
            },
            bounds_min: [-half, -half, 0.0],
            bounds_max: [half, half, 0.0],
            partial: false,
            mode: if order == 0 {
                SolveMode::Diffuse
            } else {
                SolveMode::Directional
            },
            stats: SolveStats::default(),
            settings_json: "{}".into(),
        },
        batches: vec![Batch {
            representation: Representation::Sh { order },
            scalar,
            vertices,
            coefficients,
            indices,
            texturing: None,
        }],
        textures: Vec::new(),
    }
}

/// Runs `cmd` and reaps it with wait4(2): (seconds, peak RSS in bytes).
fn run_measured(cmd: &mut Command) -> (f64, u64) {
    let reaped = Measuring::spawn(cmd.stdout(Stdio::null()).stderr(Stdio::null()))
        .unwrap()
        .wait()
        .expect("wait4 reaps the export");
    assert!(reaped.success(), "solver export failed");
    (reaped.wall_seconds, reaped.peak_rss_bytes)
}

fn size(path: &Path) -> u64 {
    std::fs::metadata(path).map(|m| m.len()).unwrap_or(0)
}

fn main() {
    let side: u32 = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(708);
    let dir = tempfile::tempdir().unwrap();
    let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
    println!(
        "grid {side}², {} triangles per solution",
        2 * (side as u64 - 1).pow(2)
    );
    println!(
        "| solution | output | seconds | input MiB | output MiB | peak RSS MiB | peak / output |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for order in [0, 2] {
        let sol = dir.path().join(format!("grid{order}.sol"));
        write_solution(&sol, &grid(side, order)).unwrap();
        for ext in ["glb", "gltf"] {
            let out = dir.path().join(format!("grid{order}.{ext}"));
            let (seconds, peak) = run_measured(
                Command::new(env!("CARGO_BIN_EXE_solver"))
                    .arg("export")
                    .arg(&sol)
                    .arg("-o")
                    .arg(&out),
            );
            let output = size(&out) + size(&out.with_extension("bin"));
            println!(
                "| SH order {order} | .{ext} | {seconds:.2} | {:.1} | {:.1} | {:.1} | {:.2} |",
                mib(size(&sol)),
                mib(output),
                mib(peak),
                peak as f64 / output as f64
            );
        }
    }
}
