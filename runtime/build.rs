//! Compiles `shaders/*.vert|*.frag` (GLSL) to SPIR-V in `OUT_DIR` with
//! `glslangValidator` (Debian package `glslang-tools`). The runtime embeds the
//! results with `include_bytes!` (see `src/gpu/shaders.rs`).
//!
//! Each scene vertex shader is compiled twice: as is (f32 coefficients) and with
//! `-DCOEFF_F16` (coefficients packed as two halves per word).

use std::path::{Path, PathBuf};
use std::process::Command;

/// (source file, output name, extra defines)
const SHADERS: &[(&str, &str, &[&str])] = &[
    ("scene_l0.vert", "scene_l0_f32.vert.spv", &[]),
    ("scene_l0.vert", "scene_l0_f16.vert.spv", &["-DCOEFF_F16"]),
    ("scene_sh.vert", "scene_sh_f32.vert.spv", &[]),
    ("scene_sh.vert", "scene_sh_f16.vert.spv", &["-DCOEFF_F16"]),
    ("scene_cube.vert", "scene_cube_f32.vert.spv", &[]),
    (
        "scene_cube.vert",
        "scene_cube_f16.vert.spv",
        &["-DCOEFF_F16"],
    ),
    (
        "scene_sh.vert",
        "scene_textured_f32.vert.spv",
        &["-DTEXTURED"],
    ),
    (
        "scene_sh.vert",
        "scene_textured_f16.vert.spv",
        &["-DTEXTURED", "-DCOEFF_F16"],
    ),
    ("scene.frag", "scene.frag.spv", &[]),
    ("scene_textured.frag", "scene_textured.frag.spv", &[]),
    ("tonemap.vert", "tonemap.vert.spv", &[]),
    ("tonemap.frag", "tonemap.frag.spv", &[]),
    ("inspect.vert", "inspect.vert.spv", &[]),
    ("inspect.frag", "inspect.frag.spv", &[]),
    ("composite.frag", "composite.frag.spv", &[]),
    ("overlay.frag", "overlay.frag.spv", &[]),
    ("sky.vert", "sky.vert.spv", &[]),
    ("sky.frag", "sky.frag.spv", &[]),
];

fn main() {
    let manifest =
        PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let shader_dir = manifest.join("..").join("shaders");
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    println!("cargo:rerun-if-changed={}", shader_dir.display());
    println!("cargo:rerun-if-env-changed=GLSLANG_VALIDATOR");
    if let Ok(entries) = std::fs::read_dir(&shader_dir) {
        for entry in entries.flatten() {
            println!("cargo:rerun-if-changed={}", entry.path().display());
        }
    }
    let tool = std::env::var("GLSLANG_VALIDATOR").unwrap_or_else(|_| "glslangValidator".into());
    for (source, output, defines) in SHADERS {
        compile(
            &tool,
            &shader_dir.join(source),
            &out_dir.join(output),
            defines,
        );
    }
}

fn compile(tool: &str, source: &Path, output: &Path, defines: &[&str]) {
    let result = Command::new(tool)
        .arg("-V")
        .arg("--target-env")
        .arg("vulkan1.1")
        .args(defines)
        .arg("-o")
        .arg(output)
        .arg(source)
        .output();
    match result {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => panic!(
            "runtime/build.rs: `{tool}` was not found, so the shaders in shaders/ cannot be \
             compiled to SPIR-V. Install the Debian package `glslang-tools` \
             (scripts/install-deps.sh does), or set GLSLANG_VALIDATOR to the compiler's path."
        ),
        Err(e) => panic!("runtime/build.rs: cannot run `{tool}`: {e}"),
        Ok(out) if !out.status.success() => panic!(
            "runtime/build.rs: `{tool}` failed on {}:\n{}{}",
            source.display(),
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        ),
        Ok(_) => {}
    }
}
