//! Helpers of the end-to-end tests that drive both programs' binaries.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The path of a workspace binary. The root package cannot use
/// `CARGO_BIN_EXE_*` for other packages' binaries, so it finds them beside the
/// test executable: tests run from target/<profile>/deps/, the binaries are in
/// target/<profile>/.
pub fn binary(name: &str) -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let dir = exe.parent().and_then(Path::parent).unwrap();
    let path = dir.join(name);
    assert!(
        path.exists(),
        "{} is missing: build it first with `cargo build -p solver -p runtime`",
        path.display()
    );
    path
}

/// Points the Vulkan loader at lavapipe unless the caller chose a driver.
pub fn lavapipe(cmd: &mut Command) {
    if std::env::var_os("VK_ICD_FILENAMES").is_some()
        || std::env::var_os("VK_DRIVER_FILES").is_some()
    {
        return;
    }
    let mut found: Vec<PathBuf> = std::fs::read_dir("/usr/share/vulkan/icd.d")
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("lvp_icd"))
        })
        .collect();
    found.sort();
    assert!(
        !found.is_empty(),
        "no lavapipe ICD in /usr/share/vulkan/icd.d: install Debian's mesa-vulkan-drivers \
         (scripts/install-deps.sh does)"
    );
    cmd.env("VK_ICD_FILENAMES", &found[0]);
}

/// Runs a solve that may stop at its `--max-shots` above the threshold: it then
/// exits with status 4 (a partial file and a kept checkpoint), which is what
/// the caller asked for, not a failure.
#[allow(dead_code)] // Each test crate compiles this module; not all call this.
pub fn run_to_shot_cap(cmd: &mut Command, what: &str) {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success() || out.status.code() == Some(4),
        "{what} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

pub fn run(cmd: &mut Command, what: &str) {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{what} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The Cornell box (`config/cornell_box.toml`) solved with `solve_args` into
/// `dir/name.sol`, shown by `runtime screenshot --mono` at 512², box-filtered
/// 8 × 8 to the committed 64 × 64 truth's pixel footprints and compared with
/// it (`tests/cornell_truth.rs` says how the truth was made). Returns the
/// comparison and the truth image itself (for its own noise).
#[allow(dead_code)] // Each test crate compiles this module; not all call this.
pub fn cornell_against_truth(
    dir: &Path,
    name: &str,
    solve_args: &[&str],
) -> (
    solver::compare::metrics::Summary,
    solver::compare::image::LoadedImage,
) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let solution = dir.join(format!("{name}.sol"));
    run(
        Command::new(binary("solver"))
            .arg("solve")
            .arg(root.join("config/cornell_box.toml"))
            .args(solve_args)
            .arg("-o")
            .arg(&solution),
        "solver solve",
    );
    let prefix = dir.join(name);
    let mut screenshot = Command::new(binary("runtime"));
    lavapipe(&mut screenshot);
    run(
        screenshot
            .arg("screenshot")
            .arg(&solution)
            .args(["--mono", "--size", "512x512", "--out"])
            .arg(&prefix),
        "runtime screenshot",
    );
    let read = solver::compare::read::read_image;
    let truth = read(&root.join("tests/fixtures/cornell_truth_64.exr")).unwrap();
    let shown = read(&prefix.with_extension("exr")).unwrap();
    let factor = shown
        .image
        .supersampling_factor(truth.image.width, truth.image.height)
        .expect("the screenshot is 8× the truth's size");
    let test = shown.image.box_downsample(factor);
    (
        solver::compare::metrics::summarize(&test, &truth.image),
        truth,
    )
}
