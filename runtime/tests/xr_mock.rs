//! `runtime xr` end to end against a scripted OpenXR runtime
//! (`examples/mock_openxr_runtime/`, loaded by Debian's OpenXR loader through
//! `XR_RUNTIME_JSON`), on lavapipe: the session lifecycle, the conformance rules
//! the mock enforces, session loss and recreation, the help overlay, and the
//! pixels the runtime receives compared with the offscreen renderer's image of
//! the same eyes.
//!
//! The mock is an example built as a shared library: `cargo test` builds it;
//! a narrower run needs `cargo build -p runtime --example mock_openxr_runtime`.

mod common;

use glam::{DQuat, DVec3};
use runtime::render::{RendererDesc, StereoRenderer};
use runtime::session::{OffscreenSwapchain, Pose, ViewState};
use runtime::xr::locomotion::{scene_yaw_deg, Locomotion, Placement};
use serde_json::Value;
use solution::camera::Fov;
use std::path::{Path, PathBuf};
use std::process::Command;

fn mock_library() -> PathBuf {
    let bin = Path::new(env!("CARGO_BIN_EXE_runtime"));
    let lib = bin
        .parent()
        .unwrap()
        .join("examples")
        .join("libmock_openxr_runtime.so");
    assert!(
        lib.is_file(),
        "{} is missing: run `cargo build -p runtime --example mock_openxr_runtime`",
        lib.display()
    );
    lib
}

struct Run {
    ok: bool,
    stdout: String,
    stderr: String,
    report: Value,
    capture: Vec<u8>,
}

fn run_xr(dir: &Path, solution: &Path, args: &[&str], env: &[(&str, &str)]) -> Run {
    common::use_lavapipe_unless_chosen();
    let manifest = dir.join("mock_runtime.json");
    let text = serde_json::json!({
        "file_format_version": "1.0.0",
        "runtime": { "name": "mock", "library_path": mock_library() }
    });
    std::fs::write(&manifest, text.to_string()).unwrap();
    let report = dir.join("report.json");
    let capture = dir.join("capture.bin");
    let _ = std::fs::remove_file(&report);
    let _ = std::fs::remove_file(&capture);
    let out = Command::new(env!("CARGO_BIN_EXE_runtime"))
        .arg("xr")
        .arg(solution)
        .args(args)
        .env("XR_RUNTIME_JSON", &manifest)
        .env("MOCK_XR_REPORT", &report)
        .env("MOCK_XR_CAPTURE", &capture)
        .envs(env.iter().copied())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let report = std::fs::read_to_string(&report)
        .unwrap_or_else(|e| panic!("no mock report ({e}); stderr:\n{stderr}"));
    Run {
        ok: out.status.success(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr,
        report: serde_json::from_str(&report).unwrap(),
        capture: std::fs::read(&capture).unwrap_or_default(),
    }
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

/// A pose from the mock's [x, y, z, qx, qy, qz, qw] (f32 values), converted as
/// `runtime xr` converts OpenXR poses (f32 → f64, quaternion normalised).
fn pose(v: &[Value]) -> Pose {
    Pose {
        position: DVec3::new(f(&v[0]), f(&v[1]), f(&v[2])),
        orientation: DQuat::from_xyzw(f(&v[3]), f(&v[4]), f(&v[5]), f(&v[6])).normalize(),
    }
}

fn check_clean(run: &Run) {
    assert!(run.ok, "runtime xr failed:\n{}", run.stderr);
    let violations = run.report["violations"].as_array().unwrap();
    assert!(violations.is_empty(), "mock runtime saw: {violations:?}");
    assert_eq!(run.report["instance_destroyed"], true);
    assert_eq!(
        run.report["sessions_created"],
        run.report["sessions_destroyed"]
    );
}

#[test]
fn headset_receives_the_renderers_image_of_the_located_eyes() {
    let dir = tempfile::tempdir().unwrap();
    // Glossy: the radiance depends on the eye position, so a misplaced eye
    // changes pixels even where the geometry would not.
    let solution = common::glossy_room(4, 4);
    let file = dir.path().join("room.sol");
    solution::format::write_solution(&file, &solution).unwrap();
    let run = run_xr(dir.path(), &file, &["--frames", "6", "--validation"], &[]);
    check_clean(&run);
    let r = &run.report;
    // Debian's loader (1.0.20) refuses 1.1; the mock accepts at most 1.0.
    assert_eq!(r["api_version"], "1.0.0");
    assert_eq!(r["frames_with_projection"], 6);
    assert_eq!(r["sessions_begun"], 1);
    assert_eq!(r["sessions_ended"], 1);
    assert_eq!(r["exit_requests"], 1);
    // The first sRGB format the mock lists (B8G8R8A8_SRGB = 50), 320×240×2.
    assert_eq!(r["capture_format"], 50);
    assert_eq!(r["swapchain_sizes"][0], serde_json::json!([320, 240, 2]));
    assert!(run.stdout.contains("frames submitted: 6"), "{}", run.stdout);

    // The eyes `runtime xr` rendered: the mock's located eyes (as submitted
    // in the last frame) placed in the scene by the same recentring.
    let header = &solution.header;
    let mut loco = Locomotion::new(header.up_axis, header.units_per_metre);
    let home = DVec3::from(header.camera.eye) - DVec3::from(header.recentre_offset);
    let yaw = scene_yaw_deg(
        DVec3::from(header.camera.target) - DVec3::from(header.camera.eye),
        header.up_axis,
    );
    let head = pose(r["first_head"].as_array().unwrap());
    loco.recentre(&head, home, yaw, Placement::Eye);
    let eyes: Vec<_> = r["last_eyes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            let e = e.as_array().unwrap();
            let view = ViewState {
                pose: pose(&e[..7]),
                fov: Fov {
                    left: f(&e[7]),
                    right: f(&e[8]),
                    up: f(&e[9]),
                    down: f(&e[10]),
                },
            };
            loco.view_to_scene(&view).eye_view(320, 240)
        })
        .collect();
    // The mock's fields of view are asymmetric and mirrored between the eyes.
    assert!(eyes[0].fov.left < -eyes[0].fov.right && eyes[1].fov.right > -eyes[1].fov.left);

    let gpu = common::gpu();
    let swapchain = OffscreenSwapchain::new(&gpu, 320, 240, 1).unwrap();
    let desc = RendererDesc {
        width: 320,
        height: 240,
        ..RendererDesc::default()
    };
    let mut renderer = StereoRenderer::new(&gpu, &solution, desc, &swapchain.desc()).unwrap();
    renderer.render(&eyes, 0).unwrap();
    let expected = renderer.read_back(&gpu, 0, 2).unwrap();

    let layer = 320 * 240 * 4;
    assert_eq!(run.capture.len(), 2 * layer);
    for (i, eye) in expected.iter().enumerate() {
        let got = &run.capture[i * layer..(i + 1) * layer];
        let mut worst = 0u8;
        let mut differing = 0usize;
        for (g, e) in got.chunks_exact(4).zip(eye.srgb.chunks_exact(4)) {
            // Captured BGRA, expected RGBA.
            let g = [g[2], g[1], g[0]];
            let d = (0..3).map(|c| g[c].abs_diff(e[c])).max().unwrap();
            worst = worst.max(d);
            differing += usize::from(d > 0);
        }
        // Same device, shaders and sample positions; only the attachment's
        // channel order differs, so the images should agree to the last
        // level (1 allowed for the sRGB encoder's rounding).
        assert!(worst <= 1, "eye {i}: worst difference {worst} levels");
        let lit = eye
            .srgb
            .chunks_exact(4)
            .filter(|p| p[..3] != [0, 0, 0])
            .count();
        assert!(lit > 320 * 240 / 2, "eye {i}: only {lit} pixels lit");
        eprintln!("eye {i}: {differing} pixels differ by one level");
    }
}

#[test]
fn lost_session_is_recreated_and_the_count_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("room.sol");
    solution::format::write_solution(&file, &common::diffuse_room(2)).unwrap();
    let run = run_xr(
        dir.path(),
        &file,
        &["--frames", "8"],
        &[("MOCK_XR_LOSS_AFTER", "4")],
    );
    check_clean(&run);
    let r = &run.report;
    assert_eq!(r["sessions_created"], 2);
    // The lost session is destroyed without xrEndSession, the second ends.
    assert_eq!(r["sessions_begun"], 2);
    assert_eq!(r["sessions_ended"], 1);
    assert_eq!(r["frames_with_projection"], 8);
    assert!(run.stderr.contains("session recreated"), "{}", run.stderr);
}

#[test]
fn menu_button_shows_the_help_panel_and_stage_falls_back_to_local() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("room.sol");
    solution::format::write_solution(&file, &common::diffuse_room(2)).unwrap();
    let config = dir.path().join("xr.toml");
    std::fs::write(&config, "reference_space = \"stage\"\n").unwrap();
    let run = run_xr(
        dir.path(),
        &file,
        &["--frames", "8", "--config", config.to_str().unwrap()],
        &[("MOCK_XR_HELP_AT", "3"), ("MOCK_XR_NO_STAGE", "1")],
    );
    check_clean(&run);
    let r = &run.report;
    // Nine frames end: the first while SYNCHRONIZED (no layers), then eight
    // with views. The button is down in the frame that starts after three
    // have ended (the 4th), so the 4th to 9th carry the panel: six.
    assert_eq!(r["frames_with_quad"], 6);
    // The panel's swapchain: one static image, one layer.
    assert_eq!(r["swapchain_sizes"][1][2], 1);
    assert!(run.stdout.contains("walkthrough controls"));
    // No STAGE offered: LOCAL (2) and VIEW (1) spaces only.
    assert_eq!(r["reference_spaces"], serde_json::json!([2, 1]));
    assert!(run.stderr.contains("no STAGE space"), "{}", run.stderr);
}
