//! `solver compare` end to end: EXR and .npy inputs through the binary, with known
//! answers for the metrics, the per-material table, the reference noise, the JSON
//! report, the heatmap and FLIP-map PNGs and the size-mismatch error; and HDR-FLIP through the
//! binary against flip-evaluator's number for a committed fixture pair.

use exr::prelude::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn solver(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_solver"))
        .arg("compare")
        .args(args)
        .output()
        .expect("run solver")
}

fn json(output: &Output) -> serde_json::Value {
    assert!(
        output.status.success(),
        "solver compare failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).expect("JSON report")
}

/// A test image written as `runtime screenshot` writes one (runtime/src/cli/output.rs).
fn write_screenshot(path: &Path, width: usize, height: usize, rgb: &[f32]) {
    write_rgb_file(path, width, height, |x, y| {
        let i = (y * width + x) * 3;
        (rgb[i], rgb[i + 1], rgb[i + 2])
    })
    .unwrap();
}

/// A reference written in `solver reference`'s EXR contract.
fn write_reference(
    path: &Path,
    width: usize,
    height: usize,
    channels: Vec<(&str, Vec<f32>)>,
    attributes: &[(&str, &str)],
) {
    let list = channels
        .into_iter()
        .map(|(name, values)| AnyChannel::new(name, FlatSamples::F32(values)))
        .collect();
    let mut layer_attributes = LayerAttributes::default();
    for (name, text) in attributes {
        layer_attributes
            .other
            .insert(Text::from(*name), AttributeValue::Text(Text::from(*text)));
    }
    let layer = Layer::new(
        (width, height),
        layer_attributes,
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list),
    );
    Image::from_layer(layer).write().to_file(path).unwrap();
}

const W: usize = 8;
const H: usize = 4;

/// Reference: uniform white (Y = 1) with se = 0.02 in every channel; materials
/// "floor" (left half) and "lamp" (right half), one object "room". Test: the left
/// half exact, the right half 1.5× too bright.
fn scene(dir: &Path) -> (PathBuf, PathBuf) {
    let n = W * H;
    let right = |i: usize| i % W >= W / 2;
    let material: Vec<f32> = (0..n).map(|i| if right(i) { 1.0 } else { 0.0 }).collect();
    let reference = dir.join("truth.exr");
    write_reference(
        &reference,
        W,
        H,
        vec![
            ("R", vec![1.0; n]),
            ("G", vec![1.0; n]),
            ("B", vec![1.0; n]),
            ("se.R", vec![0.02; n]),
            ("se.G", vec![0.02; n]),
            ("se.B", vec![0.02; n]),
            ("material_id", material),
            ("object_id", vec![0.0; n]),
        ],
        &[
            ("materials", r#"["floor", "lamp"]"#),
            ("objects", r#"["room"]"#),
        ],
    );
    let rgb: Vec<f32> = (0..n * 3)
        .map(|i| if right(i / 3) { 1.5 } else { 1.0 })
        .collect();
    let test = dir.join("shot.exr");
    write_screenshot(&test, W, H, &rgb);
    (test, reference)
}

#[test]
fn json_report_and_heatmap_have_the_known_answers() {
    let dir = tempfile::tempdir().unwrap();
    let (test, reference) = scene(dir.path());
    let heatmap = dir.path().join("maps/err.png");
    std::fs::create_dir_all(heatmap.parent().unwrap()).unwrap();
    let report = json(&solver(&[
        test.as_os_str(),
        reference.as_os_str(),
        "--json".as_ref(),
        "--heatmap".as_ref(),
        heatmap.as_os_str(),
        "--heatmap-range".as_ref(),
        "0.25".as_ref(),
    ]));
    let num = |key: &str| {
        report[key]
            .as_f64()
            .unwrap_or_else(|| panic!("{key} in {report}"))
    };
    // Half the pixels are off by +0.5 in every channel (Y_ref = 1): MARE and the
    // signed error are 0.5 × ½ = 0.25, RMSE = sqrt(½ · 0.25) = 0.353553 over a mean
    // of 1, the largest error 0.5. Tolerances 1e-6: sums of 32 exact f32 values.
    assert!((num("mare") - 0.25).abs() < 1e-6);
    assert!((num("mean_signed_relative_error") - 0.25).abs() < 1e-6);
    assert!((num("relative_rmse") - 0.125f64.sqrt()).abs() < 1e-6);
    assert!((num("max_abs_error") - 0.5).abs() < 1e-6);
    assert!((num("reference_mean") - 1.0).abs() < 1e-6);
    assert!((num("test_mean") - 1.25).abs() < 1e-6);
    assert_eq!(report["lit_pixels"], 32);
    // se = 0.02 in each channel of Y = 1: a relative standard error of 0.02.
    assert!((num("reference_noise") - 0.02).abs() < 1e-6);

    let materials = report["by_material"].as_array().unwrap();
    assert_eq!(materials[0]["name"], "lamp");
    assert_eq!(materials[0]["pixels"], 16);
    assert!((materials[0]["mare"].as_f64().unwrap() - 0.5).abs() < 1e-6);
    assert!((materials[0]["share_of_abs_error"].as_f64().unwrap() - 1.0).abs() < 1e-12);
    assert_eq!(materials[1]["name"], "floor");
    assert_eq!(materials[1]["mare"], 0.0);
    assert_eq!(report["by_object"][0]["name"], "room");

    let flip = &report["flip"];
    assert_eq!(flip["variant"], "hdr");
    let mean = flip["mean"].as_f64().unwrap();
    assert!(mean > 0.0 && mean < 1.0, "{flip}");

    // The heatmap: white where exact, the saturated "too bright" red on the right.
    let png = image::open(&heatmap).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (W as u32, H as u32));
    assert_eq!(png.get_pixel(0, 0).0, [255, 255, 255]);
    let red = png.get_pixel(W as u32 - 1, H as u32 - 1).0;
    assert!(red[0] > 150 && red[1] < 60 && red[2] < 60, "{red:?}");
    // Written atomically: no temporary file is left beside it.
    let names: Vec<_> = std::fs::read_dir(heatmap.parent().unwrap())
        .unwrap()
        .collect();
    assert_eq!(names.len(), 1);
}

#[test]
fn flip_map_is_black_where_the_images_agree_and_brighter_where_they_differ() {
    let dir = tempfile::tempdir().unwrap();
    let (test, reference) = scene(dir.path());
    let map_of = |a: &Path, b: &Path, name: &str| {
        let map = dir.path().join(name);
        let report = json(&solver(&[
            a.as_os_str(),
            b.as_os_str(),
            "--json".as_ref(),
            "--flip-map".as_ref(),
            map.as_os_str(),
        ]));
        (report, image::open(&map).unwrap().to_rgb8())
    };
    // An image against itself: FLIP is exactly 0 at every pixel (every
    // difference FLIP filters is 0), drawn as magma's black.
    let (same, png) = map_of(&reference, &reference, "same.png");
    assert_eq!(same["flip"]["mean"].as_f64(), Some(0.0));
    assert_eq!(png.dimensions(), (W as u32, H as u32));
    assert!(png.pixels().all(|p| p.0 == [0, 0, 4]), "{png:?}");
    // The scene's pair: the map is named in the report, brighter where the test
    // is off (the right half) than where it is exact (the left edge), and
    // somewhere not black.
    let (report, png) = map_of(&test, &reference, "flip.png");
    assert!(report["flip"]["map"]
        .as_str()
        .unwrap()
        .ends_with("flip.png"));
    let sum = |x: u32, y: u32| {
        png.get_pixel(x, y)
            .0
            .iter()
            .map(|&v| u32::from(v))
            .sum::<u32>()
    };
    assert!(sum(W as u32 - 1, 1) > sum(0, 1), "{png:?}");
    assert!(png.pixels().any(|p| p.0 != [0, 0, 4]));
}

#[test]
fn flip_map_without_a_flip_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (test, reference) = scene(dir.path());
    let map = dir.path().join("flip.png");
    let output = solver(&[
        test.as_os_str(),
        reference.as_os_str(),
        "--flip".as_ref(),
        "none".as_ref(),
        "--flip-map".as_ref(),
        map.as_os_str(),
    ]);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("--flip-map"), "{stderr}");
    assert!(!map.exists());
}

#[test]
fn text_report_names_each_metric() {
    let dir = tempfile::tempdir().unwrap();
    let (test, reference) = scene(dir.path());
    let output = solver(&[
        test.as_os_str(),
        reference.as_os_str(),
        "--flip".as_ref(),
        "ldr".as_ref(),
    ]);
    assert!(output.status.success());
    let text = String::from_utf8(output.stdout).unwrap();
    for needle in [
        "relative RMSE",
        "MARE",
        "max absolute error",
        "reference noise",
        "mean LDR-FLIP",
        "error by material",
        "lamp",
    ] {
        assert!(text.contains(needle), "missing {needle:?} in\n{text}");
    }
}

#[test]
fn hdr_flip_through_the_binary_matches_flip_evaluator() {
    // The fixture pair and flip-evaluator's mean come from
    // tests/fixtures/flip/generate.py (see tests/flip_reference.rs); 1e-5 as there.
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/flip");
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixtures.join("expected.json")).unwrap())
            .unwrap();
    let report = json(&solver(&[
        fixtures.join("hdr_scene.test.npy").as_os_str(),
        fixtures.join("hdr_scene.ref.npy").as_os_str(),
        "--json".as_ref(),
    ]));
    let ours = report["flip"]["mean"].as_f64().unwrap();
    let theirs = expected["cases"]["hdr_scene"]["mean"].as_f64().unwrap();
    assert!((ours - theirs).abs() < 1e-5, "{ours} vs {theirs}");
    assert_eq!(report["flip"]["exposures"]["count"], 8);
}

#[test]
fn different_sizes_are_refused_naming_both_files() {
    let dir = tempfile::tempdir().unwrap();
    let (_, reference) = scene(dir.path());
    let small = dir.path().join("small.exr");
    write_screenshot(&small, 3, 2, &[0.5; 18]);
    let output = solver(&[small.as_os_str(), reference.as_os_str()]);
    assert!(!output.status.success());
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(err.contains("small.exr") && err.contains("3×2"), "{err}");
    assert!(err.contains("truth.exr") && err.contains("8×4"), "{err}");
}

#[test]
fn non_finite_pixels_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (_, reference) = scene(dir.path());
    let mut rgb = vec![1.0; W * H * 3];
    rgb[3 * (W + 2) + 1] = f32::NAN;
    let bad = dir.path().join("nan.exr");
    write_screenshot(&bad, W, H, &rgb);
    let output = solver(&[bad.as_os_str(), reference.as_os_str()]);
    assert!(!output.status.success());
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(
        err.contains("nan.exr") && err.contains("(2, 1)") && err.contains("channel G"),
        "{err}"
    );
}
