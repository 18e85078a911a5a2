//! `solver info`: a solution written by the library is described as text and as
//! JSON by the binary, and a corrupted or missing file is refused with its name.

use solution::camera::{Camera, UpAxis};
use solution::format::{
    write_solution, Batch, Header, Representation, ScalarType, Solution, SolveMode, SolveStats,
    Vertex,
};
use std::path::Path;
use std::process::{Command, Output};

fn vertex(x: f32, z: f32) -> Vertex {
    Vertex {
        position: [x, 0.0, z],
        normal: [0.0, 1.0, 0.0],
        tangent: [1.0, 0.0, 0.0],
    }
}

fn solution() -> Solution {
    let quad = vec![
        vertex(0.0, 0.0),
        vertex(1.0, 0.0),
        vertex(1.0, 1.0),
        vertex(0.0, 1.0),
    ];
    Solution {
        lighting: None,
        header: Header {
            units_per_metre: 1000.0,
            up_axis: UpAxis::NegZ,
            recentre_offset: [278.0, 274.4, -279.6],
            camera: Camera {
                eye: [278.0, 273.0, -800.0],
                target: [278.0, 273.0, 0.0],
                up: [0.0, 1.0, 0.0],
                fov_y_deg: 39.3,
                width: 320,
                height: 240,
            },
            bounds_min: [0.0, 0.0, 0.0],
            bounds_max: [1.0, 0.0, 1.0],
            partial: true,
            mode: SolveMode::Directional,
            stats: SolveStats {
                shots: 17,
                rays: 4096,
                seconds: 1.5,
                unshot_fraction: 0.25,
                emitted_power: 100.0,
                ambient: [0.5, 0.25, 0.125],
            },
            settings_json: r#"{"preset":"draft","rays_per_shot":16}"#.into(),
        },
        batches: vec![
            Batch {
                representation: Representation::Sh { order: 0 },
                scalar: ScalarType::F32,
                vertices: quad.clone(),
                coefficients: vec![1.0; 4 * 3],
                indices: vec![0, 2, 1, 0, 3, 2],
                texturing: None,
            },
            Batch {
                representation: Representation::Sh { order: 2 },
                scalar: ScalarType::F16 { scale: 0.5 },
                vertices: quad,
                coefficients: (0..4 * 9 * 3).map(|k| k as f32 / 8.0).collect(),
                indices: vec![0, 2, 1],
                texturing: None,
            },
        ],
        textures: Vec::new(),
    }
}

fn info(args: &[&str], file: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_solver"))
        .arg("info")
        .args(args)
        .arg(file)
        .output()
        .expect("run solver")
}

#[test]
fn info_prints_text_one_field_per_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("box.sol");
    write_solution(&path, &solution()).unwrap();
    let out = info(&[], &path);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let size = std::fs::metadata(&path).unwrap().len();
    for line in [
        "format_version: 1.0".to_string(),
        format!("file_bytes: {size}"),
        "units_per_metre: 1000".into(),
        "up_axis: -z".into(),
        "recentre_offset: 278 274.4 -279.6".into(),
        "camera.image: 320x240".into(),
        "partial: true".into(),
        "mode: directional".into(),
        "stats.shots: 17".into(),
        "stats.ambient_radiance: 0.5 0.25 0.125".into(),
        "batches: 2".into(),
        "total_vertices: 8".into(),
        "total_triangles: 3".into(),
        "batch 1:".into(),
        "  representation: sh L=2 (9 coefficients per channel)".into(),
        "  scalar: f16 (scale 0.5)".into(),
        // 4 vertices × 9 × 3 channels × 2 bytes.
        "  coefficient_bytes: 216".into(),
        "  vertices: 4".into(),
    ] {
        assert!(
            text.lines().any(|l| l == line),
            "missing {line:?} in:\n{text}"
        );
    }
}

#[test]
fn info_json_is_one_valid_object() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("box.sol");
    write_solution(&path, &solution()).unwrap();
    let out = info(&["--json"], &path);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["format_version"], "1.0");
    assert_eq!(json["file_bytes"], std::fs::metadata(&path).unwrap().len());
    assert_eq!(json["units_per_metre"], 1000.0);
    assert_eq!(json["up_axis"], "-z");
    assert_eq!(json["camera"]["fov_y_deg"], 39.3);
    assert_eq!(json["stats"]["unshot_fraction"], 0.25);
    assert_eq!(json["settings"]["rays_per_shot"], 16);
    let batches = json["batches"].as_array().unwrap();
    assert_eq!(batches.len(), 2);
    assert_eq!(batches[0]["representation"]["kind"], "sh");
    assert_eq!(batches[0]["representation"]["order"], 0);
    assert_eq!(batches[0]["coefficient_bytes"], 4 * 3 * 4);
    assert_eq!(batches[1]["scalar"]["kind"], "f16");
    assert_eq!(batches[1]["scalar"]["scale"], 0.5);
    assert_eq!(batches[1]["vertex_count"], 4);
    assert_eq!(batches[1]["triangle_count"], 1);
}

#[test]
fn info_refuses_corrupt_and_missing_files_naming_them() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("box.sol");
    write_solution(&path, &solution()).unwrap();
    let mut bytes = std::fs::read(&path).unwrap();
    // The last byte is in batch 1's index section.
    *bytes.last_mut().unwrap() ^= 0x01;
    std::fs::write(&path, &bytes).unwrap();
    let out = info(&[], &path);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains(&path.display().to_string()), "{stderr}");
    assert!(
        stderr.contains("section 6 (indices of batch 1)") && stderr.contains("CRC-32"),
        "{stderr}"
    );
    assert!(out.stdout.is_empty());

    let missing = dir.path().join("missing.sol");
    let out = info(&["--json"], &missing);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("cannot open") && stderr.contains("missing.sol"),
        "{stderr}"
    );
}

#[test]
fn info_prints_the_lights_of_a_lit_file() {
    // A file with lights (format 1.1): the exposure key, one line per light
    // and the environment in text; a `lighting` object in JSON. A file
    // without lights has neither (the test above).
    let mut lit = solution();
    lit.lighting = Some(solution::format::Lighting {
        exposure_key: 0.25,
        lights_json: Some(
            r#"{"lights":[{"kind":"sun","irradiance_w_m2":[146,146,146]},{"kind":"point","name":"bulb"}],"power_into_scene":3.5}"#
                .into(),
        ),
        environment: Some(solution::format::Environment {
            width: 2,
            height: 1,
            texels: vec![[1.0, 2.0, 3.0], [0.5, 0.5, 0.5]],
            sun: None,
        }),
    });
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lit.sol");
    write_solution(&path, &lit).unwrap();
    let out = info(&[], &path);
    let text = String::from_utf8(out.stdout).unwrap();
    for line in [
        "format_version: 1.1",
        "exposure_key: 0.25",
        "lights: 2",
        "lights.power_into_scene: 3.5",
        "environment: 2x1 RGB f32",
    ] {
        assert!(
            text.lines().any(|l| l == line),
            "no line {line:?} in:\n{text}"
        );
    }
    assert!(
        text.contains(r#"  {"irradiance_w_m2":[146,146,146],"kind":"sun"}"#),
        "{text}"
    );
    let out = info(&["--json"], &path);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["lighting"]["exposure_key"], 0.25);
    assert_eq!(v["lighting"]["lights"]["lights"][1]["name"], "bulb");
    assert_eq!(v["lighting"]["environment"]["width"], 2);
    let plain = dir.path().join("plain.sol");
    write_solution(&plain, &solution()).unwrap();
    let out = info(&["--json"], &plain);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v.get("lighting").is_none());
}
