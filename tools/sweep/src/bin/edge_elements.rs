//! `edge_elements SOLUTION --axis 1 --at 0 --threshold Y`: how wide a solution
//! draws the shadow edges on one plane (see `sweep::edge_elements`). Prints the
//! number of triangles on the plane, of those that straddle the lit/unlit
//! boundary, and their sizes in scene units, as JSON.

// Shipped code: Clippy checks clippy.toml's lists here (ARCHITECTURE.md's invariants).
#![cfg_attr(not(test), warn(clippy::disallowed_methods, clippy::disallowed_macros))]
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

use anyhow::{bail, Context};
use clap::Parser;
use glam::DVec3;
use std::path::PathBuf;
use sweep::edge_elements::straddling_triangles;

#[derive(Parser, Debug)]
#[command(about = "Sizes of the triangles that straddle a shadow edge on one plane of a solution")]
struct Args {
    /// The solution file.
    solution: PathBuf,
    /// The plane's normal axis: 0 (x), 1 (y) or 2 (z).
    #[arg(long, default_value_t = 1)]
    axis: usize,
    /// The plane's coordinate on that axis, in the scene's (not re-centred) units.
    #[arg(long, default_value_t = 0.0)]
    at: f64,
    /// How far from the plane a vertex may be and still be on it (scene units).
    #[arg(long, default_value_t = 1e-2)]
    tolerance: f64,
    /// A vertex is lit when its radiance's luminance (Rec. 709) exceeds this:
    /// choose it between the lit and the shaded level (e.g. half the direct
    /// sun's ρE/π), so that the boundary is the middle of the edge's ramp.
    #[arg(long)]
    threshold: f64,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    if args.axis > 2 {
        bail!("--axis must be 0, 1 or 2, not {}", args.axis);
    }
    let solution = solution::format::read_solution(&args.solution)
        .with_context(|| format!("reading {}", args.solution.display()))?;
    let offset = solution.header.recentre_offset;
    let (mut positions, mut luminance, mut indices) = (Vec::new(), Vec::new(), Vec::new());
    for batch in &solution.batches {
        // Diffuse radiance does not depend on the eye; a glossy batch is shaded
        // toward the point above the plane's origin, which is as good as any.
        let radiance = solution::raster::shade_vertices(batch, u32::MAX, DVec3::Y * 1e6, true)
            .with_context(|| format!("shading {}", args.solution.display()))?;
        let base = positions.len() as u32;
        for (v, rgb) in batch.vertices.iter().zip(&radiance) {
            positions.push([0, 1, 2].map(|k| v.position[k] as f64 + offset[k]));
            luminance
                .push(0.2126 * rgb[0] as f64 + 0.7152 * rgb[1] as f64 + 0.0722 * rgb[2] as f64);
        }
        indices.extend(batch.indices.iter().map(|&i| i + base));
    }
    let on_plane = |p: [f64; 3]| (p[args.axis] - args.at).abs() <= args.tolerance;
    match straddling_triangles(&positions, &luminance, &indices, on_plane, args.threshold) {
        Some(found) => println!("{}", serde_json::to_string_pretty(&found)?),
        None => bail!(
            "no triangle on the plane straddles luminance {}",
            args.threshold
        ),
    }
    Ok(())
}
