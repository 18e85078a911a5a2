//! `solver solve SCENE -o OUT …`: everything around the pure solver core — files,
//! flags, the terminal, checkpoints and Ctrl-C.
//!
//! The flow: load the scene (and display file), resolve the settings (flags > TOML
//! config > display file > preset), start or resume a [`Solver`], shoot until it is
//! done or interrupted while saving a checkpoint and a partial solution every K
//! shots, then write the solution, the stats and the preview.

mod args;
#[allow(dead_code)] // Wired in when the solver core lands.
mod checkpoint;
#[allow(dead_code)] // Wired in when the solver core lands.
mod eta;
#[allow(dead_code)] // Wired in when the solver core lands.
mod files;
#[allow(dead_code)] // Wired in when the solver core lands.
mod progress;
#[allow(dead_code)] // Wired in when the solver core lands.
mod stats;

pub use args::{SolveArgs, EXIT_INTERRUPTED};
pub use stats::RunStats;

use std::process::ExitCode;

/// Runs the command (placeholder until the importers and the solver core land).
pub fn run(args: SolveArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!(
        "`solver solve {}`: the solver is not built yet",
        args.scene.display()
    )
}
