//! `solver solve --mode directional --method cube` end to end: flags
//! parsed, the global-cube solve run, a valid solution with a cube batch
//! written; bad resolutions and over-large cubes refused with clear messages.

use solution::format::{read_solution, Representation, SolveMode};
use std::path::PathBuf;
use std::process::{Command, Output};

fn glossy_floor() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../config/glossy_floor.toml")
}

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cube_cli");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{}-{name}", std::process::id()));
    let _ = std::fs::remove_file(&path);
    path
}

fn solve(out: &PathBuf, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_solver"))
        .args(["solve", "--preset", "draft", "--threads", "2"])
        .args(extra)
        .arg(glossy_floor())
        .arg("-o")
        .arg(out)
        .output()
        .unwrap()
}

#[test]
fn directional_cube_writes_a_cube_batch_for_the_glossy_floor() {
    // The scene config sets mode = directional; --method cube picks Immel, Cohen and Greenberg's (1986) cubes.
    let out = scratch("k4.sol");
    let run = solve(&out, &["--method", "cube", "--cube-resolution", "4"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains("global cube k = 4 (D = 96)"), "{stderr}");
    let solution = read_solution(&out).unwrap();
    assert!(!solution.header.partial);
    assert_eq!(solution.header.mode, SolveMode::Directional);
    assert!(solution
        .header
        .settings_json
        .contains("\"directional\":\"cube\""));
    let kinds: Vec<Representation> = solution.batches.iter().map(|b| b.representation).collect();
    assert_eq!(
        kinds,
        vec![
            Representation::Sh { order: 0 },
            Representation::Cube { directions: 96 }
        ]
    );
    // Only the floor is glossy: its vertices are the cube batch, lit (the
    // light is above it) and finite.
    let cube = &solution.batches[1];
    assert!(!cube.vertices.is_empty() && cube.vertices.iter().all(|v| v.normal[1] > 0.99));
    assert!(cube.coefficients.iter().all(|x| x.is_finite() && *x >= 0.0));
    assert!(cube.coefficients.iter().any(|&x| x > 0.0));
}

#[test]
fn bad_and_oversized_cubes_are_refused() {
    let out = scratch("bad.sol");
    let run = solve(&out, &["--method", "cube", "--cube-resolution", "1"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains("cube_resolution") && stderr.contains("--cube-resolution"),
        "{stderr}"
    );
    // k = 256 would need hundreds of GiB: refused before allocating.
    let run = solve(&out, &["--method", "cube", "--cube-resolution", "256"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains("k = 256") && stderr.contains("above the limit"),
        "{stderr}"
    );
    assert!(!out.exists());
}

#[test]
fn help_says_what_the_cube_resolution_trades() {
    let run = Command::new(env!("CARGO_BIN_EXE_solver"))
        .args(["solve", "--help"])
        .output()
        .unwrap();
    let help = String::from_utf8_lossy(&run.stdout);
    assert!(help.contains("--method") && help.contains("--cube-resolution"));
    assert!(
        help.contains("D = 6k²") && help.contains("highlights"),
        "{help}"
    );
}
