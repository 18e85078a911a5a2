//! The `runtime` binary: screenshots, bench, and refusal of bad solution files.

mod common;

use std::path::Path;
use std::process::Command;

fn runtime() -> Command {
    common::use_lavapipe_unless_chosen();
    Command::new(env!("CARGO_BIN_EXE_runtime"))
}

fn write_room(dir: &Path, name: &str, solution: &solution::format::Solution) -> std::path::PathBuf {
    let path = dir.join(name);
    solution::format::write_solution(&path, solution).unwrap();
    path
}

#[test]
fn screenshot_writes_stereo_and_mono_png_and_exr() {
    let dir = tempfile::tempdir().unwrap();
    let file = write_room(dir.path(), "room.sol", &common::diffuse_room(4));
    let prefix = dir.path().join("shot");
    let out = runtime()
        .args(["screenshot"])
        .arg(&file)
        .args([
            "--eye", "0.3", "1.2", "2.5", "--target", "-0.4", "0.6", "-2", "--size", "48x32",
        ])
        .args(["--fov-y", "70", "--validation", "--out"])
        .arg(&prefix)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "screenshot failed: {stderr}");
    for eye in ["left", "right"] {
        let png = image::open(dir.path().join(format!("shot-{eye}.png"))).unwrap();
        assert_eq!((png.width(), png.height()), (48, 32));
        let exr = exr::prelude::read_first_rgba_layer_from_file(
            dir.path().join(format!("shot-{eye}.exr")),
            |res, _| vec![0f32; res.width() * res.height() * 3],
            |buf: &mut Vec<f32>, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                let i = (pos.y() * 48 + pos.x()) * 3;
                buf[i] = r;
                buf[i + 1] = g;
                buf[i + 2] = b;
            },
        )
        .unwrap();
        let pixels = &exr.layer_data.channel_data.pixels;
        // The room's radiance lies in 0.2..0.9 per channel (common::diffuse_radiance);
        // the EXR is linear radiance, not exposed or tone-mapped.
        let max = pixels.iter().cloned().fold(0.0f32, f32::max);
        assert!(max > 0.4 && max < 0.95, "max radiance {max}");
    }
    // Mono: one image from the eye itself.
    let out = runtime()
        .args(["screenshot"])
        .arg(&file)
        .args(["--mono", "--size", "16x16", "--out"])
        .arg(dir.path().join("mono"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.path().join("mono.png").exists() && dir.path().join("mono.exr").exists());
    assert!(!dir.path().join("mono-left.png").exists());
}

#[test]
fn bench_prints_one_json_object_with_the_documented_keys() {
    let dir = tempfile::tempdir().unwrap();
    let file = write_room(dir.path(), "glossy.sol", &common::glossy_room(4, 4));
    let out = runtime()
        .args(["bench"])
        .arg(&file)
        .args([
            "--frames",
            "3",
            "--warmup",
            "1",
            "--size",
            "32x32",
            "--json",
            "--validation",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    let v: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    for key in [
        "median_ms",
        "p99_ms",
        "frames",
        "width",
        "height",
        "vertices",
        "sh_evals_per_second",
        "device",
    ] {
        assert!(v.get(key).is_some(), "missing {key} in {stdout}");
    }
    assert_eq!(v["frames"], 3);
    assert_eq!(v["vertices"], 4 * 25);
    assert!(v["median_ms"].as_f64().unwrap() > 0.0);
    assert!(v["p99_ms"].as_f64().unwrap() >= v["median_ms"].as_f64().unwrap());
}

#[test]
fn bad_solution_files_are_refused_with_one_clear_line() {
    let dir = tempfile::tempdir().unwrap();
    let good = write_room(dir.path(), "good.sol", &common::diffuse_room(2));
    let bytes = std::fs::read(&good).unwrap();
    let truncated = dir.path().join("truncated.sol");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let corrupt = dir.path().join("corrupt.sol");
    let mut flipped = bytes.clone();
    let at = bytes.len() - 40;
    flipped[at] ^= 0x5a;
    std::fs::write(&corrupt, &flipped).unwrap();
    let garbage = dir.path().join("garbage.sol");
    std::fs::write(&garbage, b"not a solution file at all").unwrap();
    let missing = dir.path().join("missing.sol");
    for file in [&truncated, &corrupt, &garbage, &missing] {
        for command in ["screenshot", "bench"] {
            let mut cmd = runtime();
            cmd.arg(command).arg(file);
            if command == "screenshot" {
                cmd.arg("--out").arg(dir.path().join("x"));
            }
            let out = cmd.output().unwrap();
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert!(
                !out.status.success(),
                "{command} accepted {}",
                file.display()
            );
            assert!(!stderr.contains("panicked"), "{stderr}");
            let lines: Vec<&str> = stderr.lines().collect();
            assert_eq!(lines.len(), 1, "expected one line, got: {stderr}");
            assert!(
                lines[0].contains(&*file.file_name().unwrap().to_string_lossy()),
                "error does not name the file: {stderr}"
            );
        }
    }
    assert!(!dir.path().join("x-left.png").exists());
}

#[test]
fn a_file_above_the_frame_cost_bound_is_refused_naming_the_flag() {
    // The glossy room at N = 4, L = 8: 25 floor vertices × 81 terms plus 75
    // wall vertices × 1 term = 2100 basis terms per view
    // (solution::format::frame_cost), so a bound of 2099 refuses it and 2100
    // lets it through.
    let dir = tempfile::tempdir().unwrap();
    let file = write_room(dir.path(), "glossy.sol", &common::glossy_room(4, 8));
    let shot = |bound: &str| {
        runtime()
            .args(["screenshot"])
            .arg(&file)
            .args(["--size", "16x16", "--max-frame-cost", bound, "--out"])
            .arg(dir.path().join("shot"))
            .output()
            .unwrap()
    };
    let out = shot("2099");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "a file above the bound was drawn");
    for part in ["glossy.sol", "2100", "2099", "--max-frame-cost"] {
        assert!(stderr.contains(part), "{stderr:?} lacks {part:?}");
    }
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    let out = shot("2100");
    assert!(
        out.status.success(),
        "at the bound: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn no_vulkan_device_fails_with_the_package_names() {
    let dir = tempfile::tempdir().unwrap();
    let file = write_room(dir.path(), "room.sol", &common::diffuse_room(2));
    // An ICD list naming no real driver: the loader finds no device.
    let out = Command::new(env!("CARGO_BIN_EXE_runtime"))
        .env("VK_ICD_FILENAMES", dir.path().join("no-such-icd.json"))
        .env_remove("VK_DRIVER_FILES")
        .arg("screenshot")
        .arg(&file)
        .arg("--out")
        .arg(dir.path().join("x"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("libvulkan1 mesa-vulkan-drivers"),
        "error does not name the packages: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}
