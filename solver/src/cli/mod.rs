//! The `solver` command line: argument parsing and dispatch. Files, terminals and
//! flags live here and in the files beside it, never in the solver core.

// An edge: the command line prints (solver/clippy.toml).
#![allow(clippy::disallowed_macros)]

use clap::{Parser, Subcommand};
use std::process::ExitCode;

pub mod compare;
pub mod export;
pub mod info;
pub mod reference;
pub mod solve;

/// Progressive-refinement radiosity solver: a scene in, a view-independent
/// solution file out.
#[derive(Parser, Debug)]
#[command(name = "solver", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

// Parsed once per run: the size of the `Solve` variant costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Solve a scene (.obj, .toml or legacy geometry file) into a solution file.
    Solve(solve::SolveArgs),
    /// Print a solution file's header (text, or JSON with --json).
    Info(info::InfoArgs),
    /// Compare a test image with a reference: relative RMSE, MARE, FLIP, per-material errors.
    #[command(long_about = compare::LONG_ABOUT)]
    Compare(compare::CompareArgs),
    /// Path-trace an unbiased reference image (EXR with standard errors) of a scene.
    Reference(reference::ReferenceArgs),
    /// Export a solution file as glTF 2.0 (.glb, or .gltf + .bin): tone-mapped
    /// COLOR_0 (unlit) for viewing, linear radiance as _RADIANCE for round trips.
    #[command(long_about = export::LONG_ABOUT)]
    Export(export::ExportArgs),
}

/// Runs the command line; errors are printed with their context chain.
pub fn main() -> ExitCode {
    #[allow(clippy::disallowed_methods)] // An edge: flags are parsed here.
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Solve(args) => solve::run(args),
        Command::Info(args) => info::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Reference(args) => reference::run(args),
        Command::Export(args) => export::run(args),
    };
    match result {
        Ok(code) => code,
        Err(err) => {
            eprintln!("solver: error: {err:#}");
            ExitCode::FAILURE
        }
    }
}
