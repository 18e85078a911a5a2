//! `solver reference` end to end: the EXR contract that `solver compare` reads,
//! the camera conventions (edges land where `EyeView::project_to_pixel`, which
//! `runtime screenshot` also uses, puts them), and thread-count independence.

use exr::prelude::*;
use glam::DVec3;
use solution::camera::Camera;
use std::path::{Path, PathBuf};
use std::process::Command;

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("reference_cli")
        .join(format!("{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A one-sided emitting rectangle (Le = 1, Kd = 0) in the plane z = 0 facing
/// +z, spanning x ∈ [−0.7, 0.9], y ∈ [−0.5, 0.6], alone in the scene.
fn write_panel(dir: &Path) -> PathBuf {
    std::fs::write(dir.join("panel.mtl"), "newmtl light\nKd 0 0 0\nKe 1 1 1\n").unwrap();
    std::fs::write(
        dir.join("panel.obj"),
        "mtllib panel.mtl\no panel\nusemtl light\n\
         v -0.7 -0.5 0\nv 0.9 -0.5 0\nv 0.9 0.6 0\nv -0.7 0.6 0\nf 1 2 3 4\n",
    )
    .unwrap();
    dir.join("panel.obj")
}

const EYE: [f64; 3] = [0.1, 0.05, 4.0];
const FOV: f64 = 40.0;
const SIZE: (u32, u32) = (32, 24);

fn reference(scene: &Path, out: &Path, extra: &[&str]) {
    let output = Command::new(env!("CARGO_BIN_EXE_solver"))
        .arg("reference")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args([
            "--eye", "0.1", "0.05", "4.0", "--target", "0.1", "0.05", "0",
        ])
        .args(["--up", "0", "1", "0", "--fov-y", "40", "--size", "32x24"])
        .args(extra)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "solver reference failed: {stderr}");
}

struct ExrImage {
    channels: Vec<(String, Vec<f32>)>,
    attributes: Vec<(String, String)>,
}

impl ExrImage {
    fn read(path: &Path) -> ExrImage {
        let image = read_all_flat_layers_from_file(path).unwrap();
        assert_eq!(image.layer_data.len(), 1, "one layer");
        let layer = &image.layer_data[0];
        assert_eq!(layer.size, Vec2(SIZE.0 as usize, SIZE.1 as usize));
        let channels = layer
            .channel_data
            .list
            .iter()
            .map(|c| {
                let values = match &c.sample_data {
                    FlatSamples::F32(v) => v.clone(),
                    other => panic!("{} is not f32: {other:?}", c.name),
                };
                (c.name.to_string(), values)
            })
            .collect();
        let attributes = layer
            .attributes
            .other
            .iter()
            .filter_map(|(k, v)| match v {
                AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
                _ => None,
            })
            .collect();
        ExrImage {
            channels,
            attributes,
        }
    }

    fn channel(&self, name: &str) -> &[f32] {
        &self
            .channels
            .iter()
            .find(|(n, _)| n == name)
            .unwrap_or_else(|| panic!("no channel {name}"))
            .1
    }

    fn attribute(&self, name: &str) -> serde_json::Value {
        let text = &self
            .attributes
            .iter()
            .find(|(n, _)| n == name)
            .unwrap_or_else(|| panic!("no attribute {name}"))
            .1;
        serde_json::from_str(text).unwrap()
    }
}

/// The contract, and the camera: each pixel is the mean of the radiance over its
/// square, so a pixel that an edge of the Le = 1 panel crosses holds the covered
/// fraction of its square. The edge's sub-pixel position follows, and must match
/// the projection of the panel's corners by the shared camera code within 0.1
/// pixel. Noise: 512 samples give a coverage standard error ≤ 0.5/√512 = 0.022
/// pixel per pixel, averaged over several rows or columns.
#[test]
fn reference_exr_contract_and_edge_positions() {
    let dir = scratch("edges");
    let scene = write_panel(&dir);
    let out = dir.join("panel.exr");
    reference(&scene, &out, &["--spp", "512", "--seed", "3"]);
    let image = ExrImage::read(&out);
    let mut names: Vec<&str> = image.channels.iter().map(|(n, _)| n.as_str()).collect();
    names.sort_unstable();
    assert_eq!(
        names,
        [
            "B",
            "G",
            "R",
            "material_id",
            "object_id",
            "se.B",
            "se.G",
            "se.R"
        ]
    );
    assert_eq!(image.attribute("materials"), serde_json::json!(["light"]));
    assert_eq!(image.attribute("objects"), serde_json::json!(["panel"]));
    assert_eq!(image.attribute("reference")["spp"], 512);

    let camera = Camera {
        eye: EYE,
        target: [0.1, 0.05, 0.0],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: FOV,
        width: SIZE.0,
        height: SIZE.1,
    };
    let view = camera.mono_view(DVec3::ZERO);
    let corner = |x: f64, y: f64| view.project_to_pixel(DVec3::new(x, y, 0.0)).unwrap();
    let (top_left, bottom_right) = (corner(-0.7, 0.6), corner(0.9, -0.5));
    // Image orientation: +x right, +y up (row 0 at the top).
    assert!(top_left.x < bottom_right.x && top_left.y < bottom_right.y);
    let (w, h) = (SIZE.0 as usize, SIZE.1 as usize);
    let r = image.channel("R");
    let ids = image.channel("material_id");
    let at = |i: usize, j: usize| r[j * w + i] as f64;
    let (i_left, i_right) = (top_left.x.floor() as usize, bottom_right.x.floor() as usize);
    let (j_top, j_bottom) = (top_left.y.floor() as usize, bottom_right.y.floor() as usize);
    // Rows and columns well inside the panel's span.
    let (mut left, mut right, mut top, mut bottom) = (0.0, 0.0, 0.0, 0.0);
    let rows: Vec<usize> = (j_top + 2..j_bottom - 1).collect();
    let cols: Vec<usize> = (i_left + 2..i_right - 1).collect();
    for &j in &rows {
        left += i_left as f64 + 1.0 - at(i_left, j);
        right += i_right as f64 + at(i_right, j);
    }
    for &i in &cols {
        top += j_top as f64 + 1.0 - at(i, j_top);
        bottom += j_bottom as f64 + at(i, j_bottom);
    }
    let (nr, nc) = (rows.len() as f64, cols.len() as f64);
    for (name, measured, expected) in [
        ("left", left / nr, top_left.x),
        ("right", right / nr, bottom_right.x),
        ("top", top / nc, top_left.y),
        ("bottom", bottom / nc, bottom_right.y),
    ] {
        assert!(
            (measured - expected).abs() < 0.1,
            "{name} edge at {measured:.3} px, projection says {expected:.3}"
        );
    }
    // Fully covered pixels see exactly Le = 1 (no noise: every sample hits);
    // the ids follow the ray through each pixel's centre.
    assert_eq!(at(i_left + 2, j_top + 2), 1.0);
    assert_eq!(image.channel("se.R")[(j_top + 2) * w + i_left + 2], 0.0);
    assert_eq!(ids[(j_top + 2) * w + i_left + 2], 0.0);
    assert_eq!(ids[0], -1.0);
    assert_eq!(image.channel("object_id")[h / 2 * w + w / 2], 0.0);
}

/// Bit-identical images with 1 and 2 threads (the seed alone decides).
#[test]
fn reference_output_does_not_depend_on_threads() {
    let dir = scratch("threads");
    let scene = write_panel(&dir);
    let (a, b) = (dir.join("one.exr"), dir.join("two.exr"));
    reference(&scene, &a, &["--spp", "8", "--threads", "1"]);
    reference(&scene, &b, &["--spp", "8", "--threads", "2"]);
    // The decoded channels, bit for bit (the files' bytes may differ: the
    // attributes are stored from a hash map, in no fixed order).
    let (one, two) = (ExrImage::read(&a), ExrImage::read(&b));
    let bits = |image: &ExrImage| {
        let mut c: Vec<(String, Vec<u32>)> = image
            .channels
            .iter()
            .map(|(n, v)| (n.clone(), v.iter().map(|x| x.to_bits()).collect()))
            .collect();
        c.sort();
        c
    };
    let same = bits(&one) == bits(&two);
    assert!(same, "1 and 2 threads gave different images");
    // No temporary file is left beside the outputs.
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp"))
        .collect();
    assert!(left.is_empty());
}

/// `--target-error` stops once the measured noise is at most the target, and
/// bad flags are refused with one line.
#[test]
fn target_error_stops_at_the_target_and_bad_flags_are_refused() {
    let dir = scratch("target");
    let scene = write_panel(&dir);
    let out = dir.join("t.exr");
    reference(&scene, &out, &["--target-error", "0.05", "--pass-spp", "8"]);
    let image = ExrImage::read(&out);
    let info = image.attribute("reference");
    assert!(info["mean_relative_error"].as_f64().unwrap() <= 0.05);
    for bad in [["--target-error", "0"], ["--spp", "1"]] {
        let output = Command::new(env!("CARGO_BIN_EXE_solver"))
            .arg("reference")
            .arg(&scene)
            .args(["-o", "x.exr"])
            .args(bad)
            .output()
            .unwrap();
        assert!(!output.status.success());
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.contains(bad[0]), "{stderr}");
    }
}
