//! Scene import speed: parsing (OBJ via tobj, MTL, TOML), cleaning, welding and
//! re-centring, on the bundled Cornell box and on two large generated OBJ files:
//! a flat floor exported as a triangulated grid (every pair welds) and a smooth
//! sphere with vertex normals (nothing welds, every facet keeps its normals).
//!
//! `cargo bench -p solver --bench import` (figures in docs/benchmarks.md).

use solver::scene::{load_scene, ImportOptions};
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// Best of `runs` wall-clock times, seconds, and the polygon count imported.
fn time(path: &Path, runs: usize) -> (f64, usize) {
    let mut best = f64::INFINITY;
    let mut polygons = 0;
    for _ in 0..runs {
        let start = Instant::now();
        let loaded = load_scene(path, &ImportOptions::default()).expect("bench scene imports");
        best = best.min(start.elapsed().as_secs_f64());
        polygons = loaded.scene.polygons.len();
    }
    (best, polygons)
}

const LAMP: &str = "usemtl lamp\nv 0 5 0\nv 1 5 0\nv 1 5 -1\nv 0 5 -1\nf -1 -2 -3 -4\n";
const MTL: &str = "newmtl grey\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0.5 0.5 0.5\nKe 10 10 10\n";

/// An n × n grid of unit squares on y = 0, each written as two triangles.
fn grid_obj(n: usize) -> String {
    let mut s = String::from("mtllib m.mtl\nusemtl grey\n");
    for i in 0..=n {
        for j in 0..=n {
            writeln!(s, "v {} 0 {}", i, -(j as f64)).unwrap();
        }
    }
    let id = |i: usize, j: usize| i * (n + 1) + j + 1;
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            writeln!(s, "f {a} {b} {c}\nf {a} {c} {d}").unwrap();
        }
    }
    s + LAMP
}

/// A UV sphere with `rings` × `segments` facets and per-vertex normals.
fn sphere_obj(rings: usize, segments: usize) -> String {
    use std::f64::consts::{PI, TAU};
    let mut s = String::from("mtllib m.mtl\nusemtl grey\n");
    for i in 1..rings {
        for j in 0..segments {
            let (t, p) = (
                PI * i as f64 / rings as f64,
                TAU * j as f64 / segments as f64,
            );
            let n = [t.sin() * p.cos(), t.cos(), -t.sin() * p.sin()];
            writeln!(
                s,
                "v {} {} {}\nvn {} {} {}",
                n[0], n[1], n[2], n[0], n[1], n[2]
            )
            .unwrap();
        }
    }
    let id = |i: usize, j: usize| (i - 1) * segments + (j % segments) + 1;
    for i in 1..rings - 1 {
        for j in 0..segments {
            let c = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
            writeln!(
                s,
                "f {}//{} {}//{} {}//{} {}//{}",
                c[0], c[0], c[1], c[1], c[2], c[2], c[3], c[3]
            )
            .unwrap();
        }
    }
    s + LAMP
}

fn main() {
    let config = Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/cornell_box.toml");
    let (t, polygons) = time(&config, 20);
    println!(
        "cornell_box.toml        {polygons:>7} polygons  {:>9.3} ms",
        t * 1e3
    );

    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("m.mtl"), MTL).expect("write mtl");
    for (name, text, faces) in [
        ("grid 200x200 triangles", grid_obj(200), 2 * 200 * 200 + 1),
        ("sphere 200x400 smooth", sphere_obj(200, 400), 198 * 400 + 1),
    ] {
        let path = dir.path().join("bench.obj");
        std::fs::write(&path, &text).expect("write obj");
        let (t, polygons) = time(&path, 3);
        println!(
            "{name:<22} {faces:>7} faces -> {polygons:>6} polygons  {:>9.1} ms  {:>6.2} M faces/s  ({:.1} MB)",
            t * 1e3,
            faces as f64 / t / 1e6,
            text.len() as f64 / 1e6
        );
    }
}
