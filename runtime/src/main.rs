//! `runtime`: renders radiosity solution files in stereo (see `runtime --help`).

use clap::Parser;

fn main() {
    let cli = runtime::cli::Cli::parse();
    if let Err(e) = runtime::cli::run(cli) {
        // One line: the error and its causes.
        eprintln!("runtime: error: {e:#}");
        std::process::exit(1);
    }
}
