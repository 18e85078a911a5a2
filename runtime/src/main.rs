//! `runtime`: renders radiosity solution files in stereo (see `runtime --help`).

// Shipped code: Clippy checks clippy.toml's lists here (ARCHITECTURE.md's invariants).
#![cfg_attr(not(test), warn(clippy::disallowed_methods, clippy::disallowed_macros))]
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

use clap::Parser;

fn main() {
    let cli = runtime::cli::Cli::parse();
    if let Err(e) = runtime::cli::run(cli) {
        // One line: the error and its causes.
        eprintln!("runtime: error: {e:#}");
        // `runtime mirror` without a usable display has its own status, so
        // scripts can fall back to screenshots.
        if e.downcast_ref::<runtime::mirror::NoDisplay>().is_some() {
            std::process::exit(runtime::mirror::NO_DISPLAY_EXIT_CODE);
        }
        std::process::exit(1);
    }
}
