//! The textured Cornell box of issue 15, written by the tests that use it
//! (`solver/tests/textured_cornell.rs` against the path tracer,
//! `tests/textured_cornell_gpu.rs` on the GPU), so that no binary is committed.
//!
//! The box of `config/cornell_box.obj` whose back wall uses material
//! `checker`, `Kd 1 1 1` and `map_Kd checker.png`, a 64 × 64 PNG of 8 × 8
//! squares, sRGB codes 255 and 50 (linear 1 and 0.0319), mapped once onto the
//! wall by `vt` UVs. Square (i, j), counted from the image's top-left, is
//! light when i + j is even.

use std::path::{Path, PathBuf};

/// The box's standard camera (the `config/cornell_box.toml` view), square
/// images of `size` pixels.
pub fn standard_camera(size: u32) -> solution::camera::Camera {
    solution::camera::Camera {
        eye: [278.0, 273.0, -800.0],
        target: [278.0, 273.0, 0.0],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 39.3077,
        width: size,
        height: size,
    }
}

/// The checkerboard's two sRGB codes and its size.
pub const LIGHT: u8 = 255;
pub const DARK: u8 = 50;
pub const TEXELS: u32 = 64;
pub const SQUARES: u32 = 8;

/// Writes the box into `dir` (`cornell_box.obj`, `.mtl`, `checker.png`),
/// reading the plain box from `repo`'s `config/`; returns the OBJ's path.
/// `textured` false writes the plain box (white back wall) for baselines.
pub fn write_scene(repo: &Path, dir: &Path, textured: bool) -> PathBuf {
    let obj = std::fs::read_to_string(repo.join("config/cornell_box.obj")).unwrap();
    let mut mtl = std::fs::read_to_string(repo.join("config/cornell_box.mtl")).unwrap();
    let mut out = String::new();
    let mut in_back_wall = false;
    for line in obj.lines() {
        if line == "o back_wall" && textured {
            // u runs right as the camera sees it (−x), v up: the wall's
            // corners (549.6, 0), (0, 0), (0, 548.8), (556, 548.8) in (x, y)
            // get u = (556 − x) / 556, v = y / 548.8, an affine image of the
            // (planar) wall, so the importer's fit is exact.
            out.push_str("vt 0.011510791 0\nvt 1 0\nvt 1 1\nvt 0 1\n");
            in_back_wall = true;
        } else if line.starts_with("o ") {
            in_back_wall = false;
        }
        if in_back_wall && line.starts_with("usemtl") {
            out.push_str("usemtl checker\n");
        } else if in_back_wall && line.starts_with("f ") {
            out.push_str("f 9/1/3 10/2/3 11/3/3 12/4/3\n");
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    mtl.push_str("\nnewmtl checker\nKd 1 1 1\nmap_Kd checker.png\n");
    let image = image::RgbImage::from_fn(TEXELS, TEXELS, |x, y| {
        let per = TEXELS / SQUARES;
        image::Rgb(
            [if (x / per + y / per).is_multiple_of(2) {
                LIGHT
            } else {
                DARK
            }; 3],
        )
    });
    image.save(dir.join("checker.png")).unwrap();
    std::fs::write(dir.join("cornell_box.mtl"), mtl).unwrap();
    let path = dir.join("cornell_box.obj");
    std::fs::write(&path, out).unwrap();
    path
}
