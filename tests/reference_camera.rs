//! Camera conventions across the two programs: `solver reference` (path traced,
//! box filter over each pixel) and `runtime screenshot --mono` (rasterized with
//! MSAA) image the same slanted edge of an emitting panel from the same camera
//! flags; the edge's sub-pixel position agrees row by row within 0.1 pixel.
//!
//! Both binaries must be built first (`cargo build -p solver -p runtime`, which
//! `cargo test --workspace` does); the test says so if they are missing. The
//! runtime renders on lavapipe unless a Vulkan driver is chosen.

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::{binary, lavapipe, run};

/// The R channel of an EXR, row-major, and its width.
fn red(path: &Path) -> (Vec<f32>, usize) {
    use exr::prelude::*;
    let image = read_all_flat_layers_from_file(path).unwrap();
    let layer = &image.layer_data[0];
    let channel = layer
        .channel_data
        .list
        .iter()
        .find(|c| c.name.to_string() == "R")
        .expect("an R channel");
    let values = match &channel.sample_data {
        FlatSamples::F32(v) => v.clone(),
        FlatSamples::F16(v) => v.iter().map(|x| x.to_f32()).collect(),
        FlatSamples::U32(v) => v.iter().map(|&x| x as f32).collect(),
    };
    (values, layer.size.0)
}

/// Per row, the left edge's position: over a window [a, b) with 0 left of it and
/// full coverage right of it, Σ coverage = b − x_edge.
fn left_edges(
    values: &[f32],
    width: usize,
    rows: std::ops::Range<usize>,
    a: usize,
    b: usize,
) -> Vec<f64> {
    let full = values[rows.start * width + b + 2] as f64;
    rows.map(|j| {
        let covered: f64 = (a..b).map(|i| values[j * width + i] as f64 / full).sum();
        b as f64 - covered
    })
    .collect()
}

#[test]
fn reference_and_screenshot_put_a_slanted_edge_at_the_same_place() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("reference_camera-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // An emitting quad (Le = 1, Kd = 0) facing +z whose left edge leans by 0.15
    // in x over its height of 1.2, so that the edge crosses every sub-pixel phase;
    // behind it a black backdrop (the solver refuses a scene of one polygon).
    std::fs::write(
        dir.join("panel.mtl"),
        "newmtl light\nKd 0 0 0\nKe 1 1 1\nnewmtl black\nKd 0 0 0\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("panel.obj"),
        "mtllib panel.mtl\no panel\nusemtl light\n\
         v -0.6 -0.6 0\nv 0.8 -0.6 0\nv 0.8 0.6 0\nv -0.45 0.6 0\nf 1 2 3 4\n\
         o backdrop\nusemtl black\n\
         v -9 -9 -1\nv 9 -9 -1\nv 9 9 -1\nv -9 9 -1\nf 5 6 7 8\n",
    )
    .unwrap();
    let camera = [
        "--eye", "0.1", "0.0", "3.0", "--target", "0.1", "0.0", "0", "--up", "0", "1", "0",
        "--fov-y", "45", "--size", "48x40",
    ];
    let scene = dir.join("panel.obj");
    let solution = dir.join("panel.sol");
    run(
        Command::new(binary("solver"))
            .args(["solve", "--preset", "draft", "-o"])
            .arg(&solution)
            .arg(&scene),
        "solver solve",
    );
    let traced = dir.join("traced.exr");
    run(
        Command::new(binary("solver"))
            .arg("reference")
            .arg(&scene)
            .arg("-o")
            .arg(&traced)
            .args(camera)
            .args(["--spp", "256"]),
        "solver reference",
    );
    let shot = dir.join("shot");
    let mut screenshot = Command::new(binary("runtime"));
    screenshot
        .arg("screenshot")
        .arg(&solution)
        .args(camera)
        .args(["--mono", "--samples", "8", "--out"])
        .arg(&shot);
    lavapipe(&mut screenshot);
    run(&mut screenshot, "runtime screenshot");

    let (t, w) = red(&traced);
    let (s, w2) = red(&dir.join("shot.exr"));
    assert_eq!(w, w2);
    // Rows inside the panel (well away from its top and bottom edges), and a
    // window that holds the left edge for every such row (from the projection:
    // x ≈ 12.8 … 15.6 px here).
    let rows = 12..28;
    let (a, b) = (8, 20);
    let (lt, ls) = (
        left_edges(&t, w, rows.clone(), a, b),
        left_edges(&s, w, rows, a, b),
    );
    let mean_gap = lt.iter().zip(&ls).map(|(x, y)| x - y).sum::<f64>() / lt.len() as f64;
    eprintln!("mean edge offset {mean_gap:.4} px; traced {lt:.2?}; raster {ls:.2?}");
    // The path tracer's per-row noise is ≤ 0.5/√256 = 0.03 px; MSAA (8 asked; lavapipe
    // gives 4) quantizes coverage to 1/4 per pixel, which averages out over rows
    // whose edge phase varies. The mean offset must be under 0.1 px.
    assert!(
        mean_gap.abs() < 0.1,
        "edges differ by {mean_gap:.3} px on average: {lt:?} vs {ls:?}"
    );
    // The edge leans the same way in both (the image is not flipped).
    let slope = |v: &[f64]| v[v.len() - 1] - v[0];
    assert!(slope(&lt) < -1.0 && slope(&ls) < -1.0, "{lt:?} {ls:?}");
}
