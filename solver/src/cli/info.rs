//! `solver info FILE [--json]`.

use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args, Debug)]
pub struct InfoArgs {
    /// The solution file to describe.
    pub file: PathBuf,
    /// Print the header as one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: InfoArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!(
        "`solver info {}`: the solution reader is not built yet",
        args.file.display()
    )
}
