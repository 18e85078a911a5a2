//! `floor_probe SOLUTION --at Y (--ring X Z R | --line X0 Z0 X1 Z1 N)`: a
//! solution's luminance on the horizontal plane y = Y (scene units) as it is
//! drawn: on a contact ring (the visible side's vertices, by angle), or at
//! N + 1 points along a segment. See `sweep::floor_probe`.

// Shipped code: Clippy checks clippy.toml's lists here (ARCHITECTURE.md's invariants).
#![cfg_attr(not(test), warn(clippy::disallowed_methods, clippy::disallowed_macros))]
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

use anyhow::{bail, Context};
use clap::Parser;
use glam::DVec3;
use std::path::PathBuf;
use sweep::floor_probe::Plane;

#[derive(Parser, Debug)]
#[command(about = "A solution's luminance on a horizontal plane, as drawn: on a ring or a line")]
struct Args {
    /// The solution file.
    solution: PathBuf,
    /// The plane's height, scene units (not re-centred).
    #[arg(long, default_value_t = 0.0)]
    at: f64,
    /// The visible vertices on the circle of radius R about (X, Z), within 0.5 units.
    #[arg(long, num_args = 3, value_names = ["X", "Z", "R"])]
    ring: Option<Vec<f64>>,
    /// N + 1 points from (X0, Z0) to (X1, Z1).
    #[arg(long, num_args = 5, value_names = ["X0", "Z0", "X1", "Z1", "N"])]
    line: Option<Vec<f64>>,
}

fn plane(args: &Args) -> anyhow::Result<Plane> {
    let solution = solution::format::read_solution(&args.solution)
        .with_context(|| format!("reading {}", args.solution.display()))?;
    let offset = solution.header.recentre_offset;
    let mut plane = Plane::default();
    for batch in &solution.batches {
        // Seen from far above: a diffuse vertex's radiance does not depend on it.
        let eye = DVec3::new(0.0, 1e9, 0.0);
        let radiance = solution::raster::shade_vertices(batch, u32::MAX, eye, true)
            .with_context(|| format!("shading {}", args.solution.display()))?;
        let lum = |i: u32| {
            let c = radiance[i as usize];
            0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
        };
        for t in batch.indices.chunks_exact(3) {
            let vertex = |k: usize| &batch.vertices[t[k] as usize];
            let on = (0..3).all(|k| {
                (vertex(k).position[1] as f64 + offset[1] - args.at).abs() < 0.5
                    && vertex(k).normal[1] > 0.9
            });
            if on {
                let xz = [0, 1, 2].map(|k| {
                    let p = vertex(k).position;
                    [p[0] as f64 + offset[0], p[2] as f64 + offset[2]]
                });
                plane
                    .triangles
                    .push((xz, [lum(t[0]), lum(t[1]), lum(t[2])]));
            }
        }
    }
    Ok(plane)
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let plane = plane(&args)?;
    match (&args.ring, &args.line) {
        (Some(r), None) => {
            for (angle, value) in plane.ring([r[0], r[1]], r[2], 0.5) {
                println!("{angle:8.2}  {value:.4}");
            }
        }
        (None, Some(l)) => {
            let n = l[4].max(1.0) as usize;
            for k in 0..=n {
                let s = k as f64 / n as f64;
                let (x, z) = (l[0] + s * (l[2] - l[0]), l[1] + s * (l[3] - l[1]));
                match plane.drawn_at(x, z) {
                    Some(value) => println!("{x:10.1} {z:10.1}  {value:.4}"),
                    None => println!("{x:10.1} {z:10.1}  -"),
                }
            }
        }
        _ => bail!("give one of --ring X Z R or --line X0 Z0 X1 Z1 N"),
    }
    Ok(())
}
