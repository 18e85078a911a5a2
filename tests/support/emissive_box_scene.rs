//! The emissive box of issue 15, written by the tests that use it
//! (`solver/tests/emissive_texture.rs` against the path tracer,
//! `tests/emissive_gpu.rs` on the GPU), so that no binary is committed.

// Shared by several test crates, each using a part of it.
#![allow(dead_code)]

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
    let map = if textured { "map_Ke screen.png\n" } else { "" };
    let screen = format!("newmtl screen\nKd 0.2 0.2 0.2\nKe 4 4 4\n{map}");
    write_box(dir, &[], &screen)
}

/// The same box lit by a second, flat emitter, a 0.4 × 0.4 ceiling panel
/// (Ke 20) 2 cm under the ceiling, so the screen reflects about as much as it
/// emits, and the screen a white reflector (Kd 1) emitting Ke 1: with
/// `diffuse`, `map_Kd kd.png` (the top half white, the bottom half sRGB
/// [`DARK`]: [`write_textures`]); with `emission`, `map_Ke screen.png` (the
/// left half white, the right half dark). Both maps share the face's `vt`,
/// so the four quadrants show the four combinations.
pub fn write_lit_screen_scene(dir: &Path, diffuse: bool, emission: bool) -> PathBuf {
    let light: Face = ([0.3, 0.98, 0.1], [0.4, 0.0, 0.0], [0.0, 0.0, 0.4], "light");
    let kd = if diffuse { "map_Kd kd.png\n" } else { "" };
    let ke = if emission { "map_Ke screen.png\n" } else { "" };
    let materials =
        format!("newmtl light\nKd 0 0 0\nKe 20 20 20\nnewmtl screen\nKd 1 1 1\nKe 1 1 1\n{kd}{ke}");
    write_box(dir, &[light], &materials)
}

/// The lit screen seen face-on from 0.69 in front (30° field of view): the
/// image shows only the screen, u and v from 0.13 to 0.87.
pub fn screen_camera(size: u32) -> solution::camera::Camera {
    solution::camera::Camera {
        eye: [0.5, 0.55, 0.3],
        target: [0.5, 0.55, 0.99],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 30.0,
        width: size,
        height: size,
    }
}

/// Writes the box with `extra` faces and the screen's (and any extra
/// material's) MTL text, and the two textures.
fn write_box(dir: &Path, extra: &[Face], screen_materials: &str) -> PathBuf {
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
    for (k, (c, e1, e2, material)) in faces.iter().chain(extra).enumerate() {
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
    std::fs::write(
        dir.join("box.mtl"),
        format!("newmtl wall\nKd 0.6 0.6 0.6\n{screen_materials}"),
    )
    .unwrap();
    write_textures(dir);
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

/// `screen.png`: the left half white, the right half [`DARK`]; `kd.png`: the
/// top half white, the bottom half dark (PNG rows run from the top).
pub fn write_textures(dir: &Path) {
    let half = |t: u32| if t < TEXELS / 2 { WHITE } else { DARK };
    image::RgbImage::from_fn(TEXELS, TEXELS, |x, _| image::Rgb([half(x); 3]))
        .save(dir.join("screen.png"))
        .unwrap();
    image::RgbImage::from_fn(TEXELS, TEXELS, |_, y| image::Rgb([half(y); 3]))
        .save(dir.join("kd.png"))
        .unwrap();
}
