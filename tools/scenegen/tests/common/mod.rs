//! What the end-to-end tests share: where the solver binary is.

use std::path::{Path, PathBuf};

/// The workspace's solver binary (debug, else release). Another package's
/// binary has no `CARGO_BIN_EXE_*`, so it is found in the target folder.
pub fn solver() -> PathBuf {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target"));
    ["debug", "release"]
        .iter()
        .map(|profile| target.join(profile).join("solver"))
        .find(|p| p.exists())
        .unwrap_or_else(|| {
            panic!(
                "no solver binary in {}: build it first with `cargo build -p solver`",
                target.display()
            )
        })
}
