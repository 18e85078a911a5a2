//! `solver solve SCENE -o OUT …`.

use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args, Debug)]
pub struct SolveArgs {
    /// The scene: `.obj`, `.toml` or a legacy geometry file.
    pub scene: PathBuf,
    /// Where to write the solution file.
    #[arg(short, long)]
    pub out: PathBuf,
}

pub fn run(args: SolveArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!(
        "`solver solve {}`: the solver is not built yet",
        args.scene.display()
    )
}
