//! The emissive box of issue 15, written by the tests that use it
//! (`solver/tests/emissive_texture.rs` against the path tracer,
//! `tests/emissive_gpu.rs` on the GPU), so that no binary is committed.

use glam::DVec3;
use std::path::{Path, PathBuf};

/// The texture's size and its two sRGB codes (left half, right half).
pub const TEXELS: u32 = 16;
pub const WHITE: u8 = 255;
pub const DARK: u8 = 50;

/// A face: (corner, e1, e2, material), e1 × e2 its inward normal.
type Face = ([f64; 3], [f64; 3], [f64; 3], &'static str);

/// The box: a unit cube open toward −z (floor, ceiling, left, right and back
/// walls facing in, Kd 0.6) and a 0.5 × 0.5 screen 1 cm in front of the back
/// wall facing the opening, Kd 0.2, mapped once onto the texture (u along
/// +x, v along +y). `textured` false writes the same screen with the flat
/// `Ke` alone (what a solver ignoring `map_Ke` would use).
pub fn write_scene(dir: &Path, textured: bool) -> PathBuf {
    let faces: [Face; 6] = [
        ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], "wall"),
        ([0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], "wall"),
        ([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], "wall"),
        ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0], "wall"),
        ([0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], "wall"),
        (
            [0.25, 0.3, 0.99],
            [0.0, 0.5, 0.0],
            [0.5, 0.0, 0.0],
            "screen",
        ),
    ];
    let mut obj = String::from("mtllib box.mtl\nvt 0 0\nvt 0 1\nvt 1 1\nvt 1 0\n");
    for (k, (c, e1, e2, material)) in faces.iter().enumerate() {
        let (c, e1, e2) = (DVec3::from(*c), DVec3::from(*e1), DVec3::from(*e2));
        for p in [c, c + e1, c + e1 + e2, c + e2] {
            obj.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
        }
        let v = 4 * k + 1;
        obj.push_str(&format!("o face{k}\nusemtl {material}\n"));
        if *material == "screen" {
            obj.push_str(&format!("f {}/1 {}/2 {}/3 {}/4\n", v, v + 1, v + 2, v + 3));
        } else {
            obj.push_str(&format!("f {} {} {} {}\n", v, v + 1, v + 2, v + 3));
        }
    }
    let map = if textured { "map_Ke screen.png\n" } else { "" };
    std::fs::write(
        dir.join("box.mtl"),
        format!("newmtl wall\nKd 0.6 0.6 0.6\nnewmtl screen\nKd 0.2 0.2 0.2\nKe 4 4 4\n{map}"),
    )
    .unwrap();
    image::RgbImage::from_fn(TEXELS, TEXELS, |x, _| {
        image::Rgb([if x < TEXELS / 2 { WHITE } else { DARK }; 3])
    })
    .save(dir.join("screen.png"))
    .unwrap();
    let path = dir.join("box.obj");
    std::fs::write(&path, obj).unwrap();
    path
}

pub fn camera(size: u32) -> solution::camera::Camera {
    solution::camera::Camera {
        eye: [0.5, 0.5, -1.2],
        target: [0.5, 0.5, 0.5],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 45.0,
        width: size,
        height: size,
    }
}
