//! `solver info FILE [--json]`: validates a solution file (all checksums) and
//! prints its header and batches.

use solution::format::{
    describe_json, describe_lighting_text, describe_text, describe_textures_text, lighting_json,
    textures_json, MappedSolution,
};
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
    // The error names the file and what is wrong with it.
    #[allow(clippy::disallowed_methods)] // An edge: `solver info` reads the file it is given.
    let solution = MappedSolution::open(&args.file)?;
    let (major, minor) = solution.version();
    if args.json {
        let mut value = describe_json(solution.header(), solution.batches());
        if let Some(object) = value.as_object_mut() {
            object.insert("file".into(), args.file.display().to_string().into());
            object.insert("format_version".into(), format!("{major}.{minor}").into());
            object.insert("file_bytes".into(), solution.file_len().into());
            object.insert("textures".into(), textures_json(solution.textures()));
            if solution.lighting().is_some() {
                object.insert("lighting".into(), lighting_json(solution.lighting()));
            }
        }
        println!("{}", serde_json::to_string_pretty(&value)?);
    } else {
        println!("file: {}", args.file.display());
        println!("format_version: {major}.{minor}");
        println!("file_bytes: {}", solution.file_len());
        print!("{}", describe_text(solution.header(), solution.batches()));
        print!("{}", describe_textures_text(solution.textures()));
        print!("{}", describe_lighting_text(solution.lighting()));
    }
    Ok(ExitCode::SUCCESS)
}
