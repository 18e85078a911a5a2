//! Writes the synthetic test rooms (`runtime/tests/common`) as solution files,
//! for `runtime bench` and `runtime screenshot` before real solver output exists.
//!
//! Usage: `cargo run -p runtime --example synthetic_solution -- OUT.sol diffuse|glossy|cube N [P]`
//! (N = subdivisions per room face; P = the glossy floor's SH order, default 8, or
//! for `cube` its global-cube resolution k, D = 6k², default 12).

#[path = "../tests/common/mod.rs"]
mod common;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    anyhow::ensure!(
        args.len() >= 3,
        "usage: synthetic_solution OUT.sol diffuse|glossy|cube N [P]"
    );
    let n: usize = args[2].parse()?;
    anyhow::ensure!((1..=1000).contains(&n), "N must be in 1..=1000");
    let solution = match args[1].as_str() {
        "diffuse" => common::diffuse_room(n),
        "glossy" => {
            let order: u32 = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(8);
            common::glossy_room(n, order)
        }
        "cube" => {
            let k: u32 = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(12);
            anyhow::ensure!((1..=64).contains(&k), "cube resolution k must be in 1..=64");
            common::cube_room(n, k)
        }
        other => anyhow::bail!("unknown kind {other:?} (diffuse, glossy or cube)"),
    };
    solution::format::write_solution(std::path::Path::new(&args[0]), &solution)?;
    let vertices: usize = solution.batches.iter().map(|b| b.vertices.len()).sum();
    println!("wrote {} ({vertices} vertices)", args[0]);
    Ok(())
}
