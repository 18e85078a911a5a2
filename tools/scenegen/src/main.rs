//! `scenegen`: writes one scale scene (OBJ + MTL + TOML scene config), with
//! the materials `--glossy` names made glossy (scenegen::glossy).

// Shipped code: Clippy checks clippy.toml's lists here (ARCHITECTURE.md's invariants).
#![cfg_attr(not(test), warn(clippy::disallowed_methods, clippy::disallowed_macros))]
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

use anyhow::Context;
use clap::Parser;
use scenegen::glossy::{self, GlossyRequest};
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
    /// Makes a material glossy: NAME, NAME=KS,NS or NAME=R,G,B,NS; repeatable.
    ///
    /// KS is the glossy reflectance (grey, or R,G,B, each in [0, 1]) and NS
    /// the MTL's Phong exponent (lobe RMS slope √(2 / (NS + 2)): 10 is broad,
    /// 100 polished, 1000 and above near-mirror). `--glossy NAME` alone is
    /// 0.5,100. NAME is one of the family's materials (an unknown name is an
    /// error that lists them), or an object's name, such as the Cornell box's
    /// `floor`, which then gets a material of its own named after it. Where
    /// Kd + Ks would exceed 1 in a channel, Kd is scaled down, its colour kept,
    /// and the change is printed. The config then sets mode = "directional"
    /// (pass `--mode diffuse` to the solver to fold Ks into Kd instead): a
    /// directional solve shows the reflections but is far slower than a
    /// diffuse one (the glossy Cornell box at medium: 310 s against about 2 s
    /// diffuse on two cores, docs/benchmarks.md).
    #[arg(long, value_name = "NAME[=KS,NS]")]
    glossy: Vec<GlossyRequest>,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let triangles = args
        .triangles
        .unwrap_or_else(|| args.family.default_triangles());
    let mut scene = generate(args.family, triangles, args.seed)?;
    for note in glossy::apply(&mut scene, args.family.name(), &args.glossy)? {
        println!("{note}");
    }
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
