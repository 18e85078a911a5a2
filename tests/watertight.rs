//! No cracks in the rendered mesh: a watertight closed scene seen from inside
//! shows no background pixel (issue 13, "No cracks").
//!
//! The scene is a closed room of tessellated walls (each wall a grid of
//! triangles, 90° creases between walls) around a tessellated smooth sphere,
//! lit by an emissive ceiling whose light the sphere shadows, so that adaptive
//! subdivision refines the floor and the walls unevenly and T-junctions appear
//! both inside a smooth surface and across the creases. Every surface has
//! Kd > 0 and the ambient term is on, so every surface pixel has radiance > 0;
//! the renderer clears to exactly 0. A pixel whose three channels are exactly
//! 0 is therefore one no triangle covered: a crack (or a hole in the scene).
//! MSAA is off (`--samples 1`), so a crack one sample wide leaves a whole
//! zero pixel rather than a dimmed one.
//!
//! The tolerance is zero pixels: a watertight mesh rendered with shared
//! vertices covers every pixel centre exactly once (Vulkan's rasterization
//! rules), and a T-junction left unfanned shows as isolated zero pixels along
//! the edge, which is what this test exists to catch.

use solver::compare::read::read_image;
use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

mod common;
use common::{binary, lavapipe, run, run_to_shot_cap};

/// Cells per side of each wall's triangle grid.
const WALL_CELLS: usize = 4;
/// The sphere's rings and segments.
const RINGS: usize = 12;
const SEGMENTS: usize = 24;

/// A wall: its material, an origin corner and two edge vectors whose cross
/// product points into the room.
type Wall = (&'static str, [f64; 3], [f64; 3], [f64; 3]);

/// Writes the room (unit cube, walls facing inward) and the sphere as OBJ + MTL.
fn write_scene(dir: &Path) -> std::path::PathBuf {
    let mut obj = String::from("mtllib room.mtl\n");
    let mut next = 1usize;
    let walls: [Wall; 6] = [
        ("wall", [0., 0., 0.], [0., 0., 1.], [1., 0., 0.]), // floor, normal +y
        ("light", [0., 1., 0.], [1., 0., 0.], [0., 0., 1.]), // ceiling, normal −y
        ("wall", [0., 0., 0.], [1., 0., 0.], [0., 1., 0.]), // z = 0, normal +z
        ("wall", [0., 0., 1.], [0., 1., 0.], [1., 0., 0.]), // z = 1, normal −z
        ("wall", [0., 0., 0.], [0., 1., 0.], [0., 0., 1.]), // x = 0, normal +x
        ("wall", [1., 0., 0.], [0., 0., 1.], [0., 1., 0.]), // x = 1, normal −x
    ];
    for (material, o, u, v) in walls {
        writeln!(obj, "usemtl {material}").unwrap();
        let n = WALL_CELLS;
        for j in 0..=n {
            for i in 0..=n {
                let (s, t) = (i as f64 / n as f64, j as f64 / n as f64);
                let p: Vec<f64> = (0..3).map(|k| o[k] + s * u[k] + t * v[k]).collect();
                writeln!(obj, "v {} {} {}", p[0], p[1], p[2]).unwrap();
            }
        }
        let at = |i: usize, j: usize| next + j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                writeln!(obj, "f {a} {b} {c}\nf {a} {c} {d}").unwrap();
            }
        }
        next += (n + 1) * (n + 1);
    }
    // The sphere, centre (0.5, 0.4, 0.5), radius 0.22, outward faces.
    writeln!(obj, "usemtl ball").unwrap();
    let (centre, radius) = ([0.5, 0.4, 0.5], 0.22);
    let pole_top = next;
    writeln!(obj, "v {} {} {}", centre[0], centre[1] + radius, centre[2]).unwrap();
    next += 1;
    for ring in 1..RINGS {
        let theta = std::f64::consts::PI * ring as f64 / RINGS as f64;
        for seg in 0..SEGMENTS {
            let phi = 2.0 * std::f64::consts::PI * seg as f64 / SEGMENTS as f64;
            let (x, y, z) = (
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            let p = [
                centre[0] + radius * x,
                centre[1] + radius * y,
                centre[2] + radius * z,
            ];
            writeln!(obj, "v {} {} {}", p[0], p[1], p[2]).unwrap();
        }
    }
    let ring_at = |ring: usize, seg: usize| next + (ring - 1) * SEGMENTS + seg % SEGMENTS;
    let pole_bottom = next + (RINGS - 1) * SEGMENTS;
    writeln!(obj, "v {} {} {}", centre[0], centre[1] - radius, centre[2]).unwrap();
    for seg in 0..SEGMENTS {
        // Counter-clockwise seen from outside: the normal points away from the centre.
        writeln!(
            obj,
            "f {pole_top} {} {}",
            ring_at(1, seg + 1),
            ring_at(1, seg)
        )
        .unwrap();
        for ring in 1..RINGS - 1 {
            let (a, b) = (ring_at(ring, seg), ring_at(ring, seg + 1));
            let (c, d) = (ring_at(ring + 1, seg + 1), ring_at(ring + 1, seg));
            writeln!(obj, "f {a} {b} {c}\nf {a} {c} {d}").unwrap();
        }
        writeln!(
            obj,
            "f {pole_bottom} {} {}",
            ring_at(RINGS - 1, seg),
            ring_at(RINGS - 1, seg + 1)
        )
        .unwrap();
    }
    let mtl = "newmtl wall\nKd 0.6 0.6 0.6\n\
               newmtl light\nKd 0.5 0.5 0.5\nKe 1 1 1\n\
               newmtl ball\nKd 0.7 0.5 0.3\n";
    std::fs::write(dir.join("room.mtl"), mtl).unwrap();
    let path = dir.join("room.obj");
    std::fs::write(&path, obj).unwrap();
    path
}

/// Zero pixels of a screenshot, and their positions (the first few).
fn background_pixels(exr: &Path) -> (usize, Vec<(usize, usize)>) {
    let image = read_image(exr).unwrap().image;
    let mut found = Vec::new();
    let mut count = 0;
    for (index, rgb) in image.pixels().enumerate() {
        if rgb.iter().all(|&c| c == 0.0) {
            count += 1;
            if found.len() < 8 {
                found.push((index % image.width, index / image.width));
            }
        }
    }
    (count, found)
}

#[test]
fn a_closed_tessellated_room_shows_no_background_pixel_from_inside() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let solution = dir.path().join("room.sol");
    // Medium refines shadow boundaries on the floor and walls; 150 shots are
    // enough for every surface to have been refined and lit.
    run_to_shot_cap(
        Command::new(binary("solver"))
            .arg("solve")
            .arg(&scene)
            .args(["--preset", "medium", "--max-shots", "150", "-o"])
            .arg(&solution),
        "solver solve",
    );
    let eye = ["0.2", "0.75", "0.2"];
    // Six axis views cover the whole sphere of directions; the two diagonal
    // views look straight into a three-wall corner and along the floor's
    // creases, where T-junctions across polygons meet.
    let views: [([&str; 3], [&str; 3]); 8] = [
        (["1.2", "0.75", "0.2"], ["0", "1", "0"]),
        (["-0.8", "0.75", "0.2"], ["0", "1", "0"]),
        (["0.2", "0.75", "1.2"], ["0", "1", "0"]),
        (["0.2", "0.75", "-0.8"], ["0", "1", "0"]),
        (["0.2", "1.75", "0.2"], ["0", "0", "1"]),
        (["0.2", "-0.25", "0.2"], ["0", "0", "1"]),
        (["1.0", "0.0", "1.0"], ["0", "1", "0"]),
        (["1.0", "1.0", "1.0"], ["0", "1", "0"]),
    ];
    let mut failures = Vec::new();
    for (view, (target, up)) in views.iter().enumerate() {
        let prefix = dir.path().join(format!("view{view}"));
        let mut screenshot = Command::new(binary("runtime"));
        lavapipe(&mut screenshot);
        run(
            screenshot
                .arg("screenshot")
                .arg(&solution)
                .args(["--mono", "--size", "256x256", "--samples", "1"])
                .args(["--fov-y", "100", "--up"])
                .args(up)
                .arg("--eye")
                .args(eye)
                .arg("--target")
                .args(target)
                .arg("--out")
                .arg(&prefix),
            "runtime screenshot",
        );
        let (count, first) = background_pixels(&prefix.with_extension("exr"));
        if count > 0 {
            failures.push(format!(
                "view {view} (towards {target:?}): {count} background pixels, first at {first:?}; image {}",
                prefix.with_extension("png").display()
            ));
        }
    }
    if !failures.is_empty() {
        // Keep the images for inspection.
        let kept = dir.keep();
        panic!(
            "cracks (images kept in {}):\n{}",
            kept.display(),
            failures.join("\n")
        );
    }
}
