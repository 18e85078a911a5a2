//! SPIR-V of `shaders/`, compiled by `runtime/build.rs` and embedded here.

use super::{Gpu, GpuError, VkContext};
use ash::vk;

macro_rules! spirv {
    ($name:literal) => {
        include_bytes!(concat!(env!("OUT_DIR"), "/", $name))
    };
}

pub const SCENE_L0_F32_VERT: &[u8] = spirv!("scene_l0_f32.vert.spv");
pub const SCENE_L0_F16_VERT: &[u8] = spirv!("scene_l0_f16.vert.spv");
pub const SCENE_SH_F32_VERT: &[u8] = spirv!("scene_sh_f32.vert.spv");
pub const SCENE_SH_F16_VERT: &[u8] = spirv!("scene_sh_f16.vert.spv");
pub const SCENE_FRAG: &[u8] = spirv!("scene.frag.spv");
/// Textured batches (solution format 2): `scene_sh.vert` with `-DTEXTURED`.
pub const SCENE_TEXTURED_F32_VERT: &[u8] = spirv!("scene_textured_f32.vert.spv");
pub const SCENE_TEXTURED_F16_VERT: &[u8] = spirv!("scene_textured_f16.vert.spv");
pub const SCENE_TEXTURED_FRAG: &[u8] = spirv!("scene_textured.frag.spv");
pub const TONEMAP_VERT: &[u8] = spirv!("tonemap.vert.spv");
pub const TONEMAP_FRAG: &[u8] = spirv!("tonemap.frag.spv");
pub const INSPECT_VERT: &[u8] = spirv!("inspect.vert.spv");
pub const INSPECT_FRAG: &[u8] = spirv!("inspect.frag.spv");
/// The mirror window's composite pass (its vertex shader is `TONEMAP_VERT`,
/// the full-screen triangle).
pub const COMPOSITE_FRAG: &[u8] = spirv!("composite.frag.spv");
/// The environment behind the geometry (solution format x.1).
pub const SKY_VERT: &[u8] = spirv!("sky.vert.spv");
pub const SKY_FRAG: &[u8] = spirv!("sky.frag.spv");
/// The mirror's text overlay over copied eye images.
pub const OVERLAY_FRAG: &[u8] = spirv!("overlay.frag.spv");

/// A shader module (destroyed by its owner, see `render::pipelines`).
pub fn create_module(gpu: &Gpu, spirv: &[u8]) -> Result<vk::ShaderModule, GpuError> {
    // include_bytes! data is not necessarily 4-byte aligned: copy into words.
    let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
        .map_err(|e| GpuError::Unsupported(format!("embedded SPIR-V is malformed: {e}")))?;
    let info = vk::ShaderModuleCreateInfo::default().code(&words);
    // SAFETY: `words` is SPIR-V produced by glslangValidator at build time.
    unsafe { gpu.device().create_shader_module(&info, None) }.ctx("vkCreateShaderModule")
}
