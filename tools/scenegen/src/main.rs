//! `scenegen`: writes one scale scene (OBJ + MTL + TOML scene config).

// Shipped code: Clippy checks clippy.toml's lists here (ARCHITECTURE.md's invariants).
#![cfg_attr(not(test), warn(clippy::disallowed_methods, clippy::disallowed_macros))]
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

use anyhow::Context;
use clap::Parser;
use scenegen::{generate, scene::write_scene, Family};
use std::path::PathBuf;

/// Writes a scale scene of about the requested triangle count as DIR/NAME.obj,
/// NAME.mtl and NAME.toml (millimetres, +y up; solve the .toml, which sets
/// units_per_metre = 1000 and a camera inside the scene).
#[derive(Parser)]
#[command(name = "scenegen", version)]
struct Args {
    /// Which family of scene.
    #[arg(value_enum)]
    family: Family,
    /// Triangles wanted: the family's parameter is chosen to land within ±20%
    /// of it, and the actual count is printed. More triangles make a larger
    /// OBJ (about 40 bytes a triangle) and a slower solve. Default 1000; 65000
    /// for the atrium, 300 for the window room.
    #[arg(long)]
    triangles: Option<usize>,
    /// Seed of the Cornell boxes' layout (sizes, positions, yaw); the same seed
    /// gives the same file. The other families are regular and ignore it.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output folder (created if missing).
    #[arg(long, short)]
    out: PathBuf,
    /// File stem (default: the family's name).
    #[arg(long)]
    name: Option<String>,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let triangles = args
        .triangles
        .unwrap_or_else(|| args.family.default_triangles());
    let scene = generate(args.family, triangles, args.seed)?;
    let stem = args.name.unwrap_or_else(|| args.family.name().to_owned());
    let paths = write_scene(&scene, &args.out, &stem)
        .with_context(|| format!("writing the scene into {}", args.out.display()))?;
    println!(
        "{}: {} triangles ({} requested); {}",
        args.family.name(),
        scene.mesh.triangle_count(),
        triangles,
        scene.description
    );
    println!("wrote {} (+ .mtl, .obj)", paths.toml.display());
    Ok(())
}
