//! `runtime xr` where no OpenXR runtime answers: one line that says so and
//! suggests `runtime mirror`, a non-zero exit, no panic; and its refusals of bad
//! arguments and config files (checked before OpenXR is touched).
//!
//! The loader is Debian's libopenxr-loader1 (installed by scripts/install-deps.sh);
//! `XR_RUNTIME_JSON` points it at a file that does not exist, and the XDG
//! config folders at an empty one, so no installed runtime can answer.

mod common;

use std::path::Path;
use std::process::{Command, Output};

fn runtime_xr(dir: &Path, args: &[&str]) -> Output {
    common::use_lavapipe_unless_chosen();
    let empty = dir.join("no-xdg");
    std::fs::create_dir_all(&empty).unwrap();
    Command::new(env!("CARGO_BIN_EXE_runtime"))
        .arg("xr")
        .args(args)
        .env("XR_RUNTIME_JSON", dir.join("nonexistent_runtime.json"))
        .env("XDG_CONFIG_HOME", &empty)
        .env("XDG_CONFIG_DIRS", &empty)
        // The command silences the loader's own log unless this is set.
        .env_remove("XR_LOADER_DEBUG")
        .output()
        .unwrap()
}

fn one_line(out: &Output) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(
        lines.len(),
        1,
        "expected one line on stderr, got:\n{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    lines[0].to_string()
}

#[test]
fn without_a_runtime_says_so_in_one_line_and_suggests_the_mirror() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("room.sol");
    solution::format::write_solution(&file, &common::diffuse_room(2)).unwrap();
    let out = runtime_xr(dir.path(), &[file.to_str().unwrap(), "--frames", "5"]);
    assert!(!out.status.success());
    assert_eq!(out.status.code(), Some(1), "exit status {:?}", out.status);
    let line = one_line(&out);
    assert!(
        line.contains("no OpenXR runtime") && line.contains("runtime mirror"),
        "{line}"
    );
    // The loader's answer is named, so a user can tell "none installed" from
    // other failures.
    assert!(line.contains("XR_ERROR_RUNTIME_UNAVAILABLE"), "{line}");
    assert!(
        out.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
}

#[test]
fn bad_config_is_refused_with_file_and_line_before_openxr() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("room.sol");
    solution::format::write_solution(&file, &common::diffuse_room(2)).unwrap();
    let config = dir.path().join("xr.toml");
    std::fs::write(&config, "snap_turn_deg = 45\nwalk_speed_m_s = 99\n").unwrap();
    let out = runtime_xr(
        dir.path(),
        &[file.to_str().unwrap(), "--config", config.to_str().unwrap()],
    );
    assert!(!out.status.success());
    let line = one_line(&out);
    assert!(
        line.contains("xr.toml:2:") && line.contains("walk_speed_m_s = 99"),
        "{line}"
    );
}

#[test]
fn bad_arguments_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("room.sol");
    solution::format::write_solution(&file, &common::diffuse_room(2)).unwrap();
    let out = runtime_xr(dir.path(), &[file.to_str().unwrap(), "--frames", "0"]);
    assert!(!out.status.success());
    assert!(one_line(&out).contains("--frames must be at least 1"));
    // A missing solution is named.
    let missing = dir.path().join("missing.sol");
    let out = runtime_xr(dir.path(), &[missing.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(one_line(&out).contains("missing.sol"));
}

#[test]
fn a_file_above_the_frame_cost_bound_is_refused_before_openxr() {
    // The glossy room at N = 4, L = 8 costs 2100 basis terms per view
    // (25 floor vertices × 81 terms plus 75 wall vertices × 1 term,
    // solution::format::frame_cost; as in tests/cli.rs), so a bound of 2099
    // refuses it with the format's one-line message, and 2100 lets it through
    // to OpenXR, which is absent here.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("glossy.sol");
    solution::format::write_solution(&file, &common::glossy_room(4, 8)).unwrap();
    let xr = |bound: &str| {
        runtime_xr(
            dir.path(),
            &[file.to_str().unwrap(), "--max-frame-cost", bound],
        )
    };
    let out = xr("2099");
    assert!(!out.status.success(), "a file above the bound was opened");
    let line = one_line(&out);
    for part in ["glossy.sol", "2100", "2099", "--max-frame-cost"] {
        assert!(line.contains(part), "{line:?} lacks {part:?}");
    }
    assert!(!line.contains("OpenXR"), "refused after OpenXR: {line}");
    let out = xr("2100");
    let line = one_line(&out);
    assert!(
        line.contains("no OpenXR runtime"),
        "at the bound the file is not refused: {line}"
    );
}
