//! Render passes and pipelines, one set per multiview view mask.
//!
//! Each pass has two subpasses: (0) the scene, Gouraud-shaded linear radiance into
//! a (multisampled) half-float colour target with depth, resolved into a
//! single-sample half-float image; (1) exposure and tone map, reading the resolved
//! image as an input attachment and writing the sRGB output image (a swapchain
//! image). With multiview both subpasses draw every view in the mask, each into
//! its own array layer.
//!
//! Layouts: every attachment's initial and final layout are the same, so a pass
//! for view mask 0b10 preserves what a pass for 0b01 wrote into layer 0 (the
//! per-view workaround, `super::multiview`). The frame starts with barriers from
//! `UNDEFINED` into those layouts.

use super::scene::CoefficientStorage;
use crate::gpu::pipeline::{pipeline_layout, set_layout, GraphicsPipeline, ShaderModules};
use crate::gpu::{shaders, Gpu, GpuError, VkContext};
use ash::vk;
use std::sync::Arc;

/// The linear colour target's format: half float with the scene's radiance
/// scale (see `GpuScene::radiance_scale`) keeps any emitter in range with 11-bit
/// precision, and every Vulkan device can render, blend and resolve it.
pub const LINEAR_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

pub const MSAA_LAYOUT: vk::ImageLayout = vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL;
pub const DEPTH_LAYOUT: vk::ImageLayout = vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
pub const LINEAR_LAYOUT: vk::ImageLayout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
pub const OUTPUT_LAYOUT: vk::ImageLayout = vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL;

/// SPIR-V of `shaders/scene_cube.vert` (compiled by `runtime/build.rs` like the
/// other scene shaders, with f32 and packed-f16 coefficients).
const SCENE_CUBE_F32_VERT: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/scene_cube_f32.vert.spv"));
const SCENE_CUBE_F16_VERT: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/scene_cube_f16.vert.spv"));

/// Push constants of the scene pipelines (`scene_common.glsl`, `Batch`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct BatchConstants {
    /// The SH order, or a cube batch's resolution k (`DrawBatch::loop_parameter`).
    pub order: u32,
    pub vertex_base: u32,
    pub coeff_base: u32,
    pub stride: u32,
    pub scale: f32,
    /// Textured batches: the texture factor times the radiance scale (the
    /// shader's `texture_scale_*`; unused by the untextured shaders).
    pub texture_scale: [f32; 3],
    /// Textured batches: the emission texture's factor (Ke, format 3's second
    /// slot) times the radiance scale; zero when the batch has none.
    pub emission_scale: [f32; 3],
}

impl BatchConstants {
    /// The push-constant range of the untextured pipelines.
    pub const SIZE: u32 = 20;
    /// The push-constant range of the textured pipeline (`texture_scale` and
    /// `emission_scale` too).
    pub const TEXTURED_SIZE: u32 = 44;

    pub fn bytes(&self) -> [u8; 44] {
        let mut out = [0u8; 44];
        out[0..4].copy_from_slice(&self.order.to_le_bytes());
        out[4..8].copy_from_slice(&self.vertex_base.to_le_bytes());
        out[8..12].copy_from_slice(&self.coeff_base.to_le_bytes());
        out[12..16].copy_from_slice(&self.stride.to_le_bytes());
        out[16..20].copy_from_slice(&self.scale.to_le_bytes());
        for (c, v) in self.texture_scale.iter().enumerate() {
            out[20 + 4 * c..24 + 4 * c].copy_from_slice(&v.to_le_bytes());
        }
        for (c, v) in self.emission_scale.iter().enumerate() {
            out[32 + 4 * c..36 + 4 * c].copy_from_slice(&v.to_le_bytes());
        }
        out
    }
}

/// Layouts shared by every pass set.
pub struct Layouts {
    // Newest first.
    /// Sets 0 (`scene_set`) and 1 (`textured_set`), 44 bytes of constants.
    pub textured_pipeline: vk::PipelineLayout,
    pub textured_set: vk::DescriptorSetLayout,
    pub tonemap_pipeline: vk::PipelineLayout,
    pub scene_pipeline: vk::PipelineLayout,
    pub tonemap_set: vk::DescriptorSetLayout,
    pub scene_set: vk::DescriptorSetLayout,
    device: Arc<crate::gpu::DeviceShared>,
}

impl Layouts {
    pub fn new(gpu: &Gpu) -> Result<Layouts, GpuError> {
        use vk::{DescriptorType as D, ShaderStageFlags as S};
        let mut layouts = Layouts {
            textured_pipeline: vk::PipelineLayout::null(),
            textured_set: vk::DescriptorSetLayout::null(),
            tonemap_pipeline: vk::PipelineLayout::null(),
            scene_pipeline: vk::PipelineLayout::null(),
            tonemap_set: vk::DescriptorSetLayout::null(),
            scene_set: vk::DescriptorSetLayout::null(),
            device: gpu.shared.clone(),
        };
        // Every handle is stored in `layouts` as soon as it exists, so its Drop
        // destroys it on any later error.
        layouts.scene_set = set_layout(
            gpu,
            &[
                (D::UNIFORM_BUFFER, S::VERTEX),
                (D::STORAGE_BUFFER, S::VERTEX),
            ],
        )?;
        layouts.tonemap_set = set_layout(gpu, &[(D::INPUT_ATTACHMENT, S::FRAGMENT)])?;
        layouts.scene_pipeline =
            pipeline_layout(gpu, &[layouts.scene_set], S::VERTEX, BatchConstants::SIZE)?;
        layouts.tonemap_pipeline = pipeline_layout(gpu, &[layouts.tonemap_set], S::FRAGMENT, 8)?;
        // Textured batches' second set: their UV + E/π, their texture and
        // their emission texture (the first texture again, with a zero
        // factor, for a batch without format 3's second slot).
        layouts.textured_set = set_layout(
            gpu,
            &[
                (D::STORAGE_BUFFER, S::VERTEX),
                (D::COMBINED_IMAGE_SAMPLER, S::FRAGMENT),
                (D::COMBINED_IMAGE_SAMPLER, S::FRAGMENT),
            ],
        )?;
        layouts.textured_pipeline = pipeline_layout(
            gpu,
            &[layouts.scene_set, layouts.textured_set],
            S::VERTEX,
            BatchConstants::TEXTURED_SIZE,
        )?;
        Ok(layouts)
    }
}

impl Drop for Layouts {
    fn drop(&mut self) {
        // SAFETY: owners wait for the device before dropping; null handles are
        // ignored by the destroy calls.
        unsafe {
            let d = &self.device.device;
            d.destroy_pipeline_layout(self.textured_pipeline, None);
            d.destroy_descriptor_set_layout(self.textured_set, None);
            d.destroy_pipeline_layout(self.tonemap_pipeline, None);
            d.destroy_pipeline_layout(self.scene_pipeline, None);
            d.destroy_descriptor_set_layout(self.tonemap_set, None);
            d.destroy_descriptor_set_layout(self.scene_set, None);
        }
    }
}

/// What a pass set is built for.
#[derive(Clone, Copy, Debug)]
pub struct PassDesc {
    pub view_mask: u32,
    pub samples: vk::SampleCountFlags,
    pub depth_format: vk::Format,
    pub output_format: vk::Format,
    pub storage: CoefficientStorage,
    /// The scene has textured batches: make the textured pipeline too (an
    /// untextured scene costs nothing more than before textures existed).
    pub textured: bool,
}

/// A render pass for one view mask with its four pipelines.
pub struct PassSet {
    // Newest first.
    pub scene_textured: vk::Pipeline,
    pub scene_cube: vk::Pipeline,
    pub tonemap: vk::Pipeline,
    pub scene_sh: vk::Pipeline,
    pub scene_l0: vk::Pipeline,
    pub render_pass: vk::RenderPass,
    pub desc: PassDesc,
    device: Arc<crate::gpu::DeviceShared>,
}

impl Drop for PassSet {
    fn drop(&mut self) {
        // SAFETY: owners wait for the device before dropping; null handles are
        // ignored.
        unsafe {
            let d = &self.device.device;
            d.destroy_pipeline(self.scene_textured, None);
            d.destroy_pipeline(self.scene_cube, None);
            d.destroy_pipeline(self.tonemap, None);
            d.destroy_pipeline(self.scene_sh, None);
            d.destroy_pipeline(self.scene_l0, None);
            d.destroy_render_pass(self.render_pass, None);
        }
    }
}

impl PassSet {
    pub fn new(gpu: &Gpu, layouts: &Layouts, desc: PassDesc) -> Result<PassSet, GpuError> {
        let mut set = PassSet {
            scene_textured: vk::Pipeline::null(),
            scene_cube: vk::Pipeline::null(),
            tonemap: vk::Pipeline::null(),
            scene_sh: vk::Pipeline::null(),
            scene_l0: vk::Pipeline::null(),
            render_pass: vk::RenderPass::null(),
            desc,
            device: gpu.shared.clone(),
        };
        set.render_pass = create_render_pass(gpu, &desc)?;
        let mut modules = ShaderModules::new(gpu);
        let (l0_spv, sh_spv, cube_spv, textured_spv) = match desc.storage {
            CoefficientStorage::F32 => (
                shaders::SCENE_L0_F32_VERT,
                shaders::SCENE_SH_F32_VERT,
                SCENE_CUBE_F32_VERT,
                shaders::SCENE_TEXTURED_F32_VERT,
            ),
            CoefficientStorage::F16 => (
                shaders::SCENE_L0_F16_VERT,
                shaders::SCENE_SH_F16_VERT,
                SCENE_CUBE_F16_VERT,
                shaders::SCENE_TEXTURED_F16_VERT,
            ),
        };
        let l0 = modules.load(gpu, l0_spv)?;
        let sh = modules.load(gpu, sh_spv)?;
        let cube = modules.load(gpu, cube_spv)?;
        let frag = modules.load(gpu, shaders::SCENE_FRAG)?;
        let tm_vert = modules.load(gpu, shaders::TONEMAP_VERT)?;
        let tm_frag = modules.load(gpu, shaders::TONEMAP_FRAG)?;
        set.scene_l0 = scene_pipeline(gpu, layouts.scene_pipeline, &set, l0, frag)?;
        set.scene_sh = scene_pipeline(gpu, layouts.scene_pipeline, &set, sh, frag)?;
        set.tonemap = tonemap_pipeline(gpu, layouts, &set, tm_vert, tm_frag)?;
        set.scene_cube = scene_pipeline(gpu, layouts.scene_pipeline, &set, cube, frag)?;
        if desc.textured {
            let textured = modules.load(gpu, textured_spv)?;
            let textured_frag = modules.load(gpu, shaders::SCENE_TEXTURED_FRAG)?;
            set.scene_textured = scene_pipeline(
                gpu,
                layouts.textured_pipeline,
                &set,
                textured,
                textured_frag,
            )?;
        }
        Ok(set)
    }
}

fn create_render_pass(gpu: &Gpu, desc: &PassDesc) -> Result<vk::RenderPass, GpuError> {
    let msaa = desc.samples != vk::SampleCountFlags::TYPE_1;
    let mut attachments = Vec::new();
    // 0: depth.
    attachments.push(
        vk::AttachmentDescription::default()
            .format(desc.depth_format)
            .samples(desc.samples)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::DONT_CARE)
            .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
            .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
            .initial_layout(DEPTH_LAYOUT)
            .final_layout(DEPTH_LAYOUT),
    );
    // 1: linear radiance, single sample (resolve target, or the colour target
    // itself without MSAA).
    attachments.push(
        vk::AttachmentDescription::default()
            .format(LINEAR_FORMAT)
            .samples(vk::SampleCountFlags::TYPE_1)
            .load_op(if msaa {
                vk::AttachmentLoadOp::DONT_CARE
            } else {
                vk::AttachmentLoadOp::CLEAR
            })
            .store_op(vk::AttachmentStoreOp::STORE)
            .initial_layout(LINEAR_LAYOUT)
            .final_layout(LINEAR_LAYOUT),
    );
    // 2: the sRGB output.
    attachments.push(
        vk::AttachmentDescription::default()
            .format(desc.output_format)
            .samples(vk::SampleCountFlags::TYPE_1)
            .load_op(vk::AttachmentLoadOp::DONT_CARE)
            .store_op(vk::AttachmentStoreOp::STORE)
            .initial_layout(OUTPUT_LAYOUT)
            .final_layout(OUTPUT_LAYOUT),
    );
    // 3: the multisampled colour target.
    if msaa {
        attachments.push(
            vk::AttachmentDescription::default()
                .format(LINEAR_FORMAT)
                .samples(desc.samples)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::DONT_CARE)
                .initial_layout(MSAA_LAYOUT)
                .final_layout(MSAA_LAYOUT),
        );
    }
    let depth_ref = vk::AttachmentReference::default()
        .attachment(0)
        .layout(DEPTH_LAYOUT);
    let scene_color = [vk::AttachmentReference::default()
        .attachment(if msaa { 3 } else { 1 })
        .layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)];
    let scene_resolve = [vk::AttachmentReference::default()
        .attachment(1)
        .layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)];
    let tonemap_input = [vk::AttachmentReference::default()
        .attachment(1)
        .layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
    let tonemap_color = [vk::AttachmentReference::default()
        .attachment(2)
        .layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)];
    let mut scene_subpass = vk::SubpassDescription::default()
        .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
        .color_attachments(&scene_color)
        .depth_stencil_attachment(&depth_ref);
    if msaa {
        scene_subpass = scene_subpass.resolve_attachments(&scene_resolve);
    }
    let subpasses = [
        scene_subpass,
        vk::SubpassDescription::default()
            .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
            .input_attachments(&tonemap_input)
            .color_attachments(&tonemap_color),
    ];
    let attachment_stages = vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
        | vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS
        | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS;
    let attachment_access = vk::AccessFlags::COLOR_ATTACHMENT_WRITE
        | vk::AccessFlags::COLOR_ATTACHMENT_READ
        | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE
        | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ;
    let dependencies = [
        // Earlier passes (the other view's, or the previous frame's tone map and
        // read-back) before this pass's attachment writes.
        vk::SubpassDependency::default()
            .src_subpass(vk::SUBPASS_EXTERNAL)
            .dst_subpass(0)
            .src_stage_mask(
                attachment_stages
                    | vk::PipelineStageFlags::FRAGMENT_SHADER
                    | vk::PipelineStageFlags::TRANSFER,
            )
            .dst_stage_mask(attachment_stages)
            .src_access_mask(attachment_access | vk::AccessFlags::TRANSFER_READ)
            .dst_access_mask(attachment_access),
        // The resolved radiance, read by the tone map in the same pixel and view.
        vk::SubpassDependency::default()
            .src_subpass(0)
            .dst_subpass(1)
            .src_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
            .dst_stage_mask(vk::PipelineStageFlags::FRAGMENT_SHADER)
            .src_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE)
            .dst_access_mask(vk::AccessFlags::INPUT_ATTACHMENT_READ)
            .dependency_flags(vk::DependencyFlags::BY_REGION | vk::DependencyFlags::VIEW_LOCAL),
        // Output and radiance before later passes, copies and presentation.
        vk::SubpassDependency::default()
            .src_subpass(1)
            .dst_subpass(vk::SUBPASS_EXTERNAL)
            .src_stage_mask(
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
                    | vk::PipelineStageFlags::FRAGMENT_SHADER,
            )
            .dst_stage_mask(
                attachment_stages
                    | vk::PipelineStageFlags::FRAGMENT_SHADER
                    | vk::PipelineStageFlags::TRANSFER,
            )
            .src_access_mask(
                vk::AccessFlags::COLOR_ATTACHMENT_WRITE | vk::AccessFlags::INPUT_ATTACHMENT_READ,
            )
            .dst_access_mask(attachment_access | vk::AccessFlags::TRANSFER_READ),
    ];
    let view_masks = [desc.view_mask, desc.view_mask];
    let correlation = [desc.view_mask];
    let mut multiview = vk::RenderPassMultiviewCreateInfo::default()
        .view_masks(&view_masks)
        .correlation_masks(&correlation);
    let info = vk::RenderPassCreateInfo::default()
        .attachments(&attachments)
        .subpasses(&subpasses)
        .dependencies(&dependencies)
        .push_next(&mut multiview);
    // SAFETY: the create info points to locals alive for the call.
    unsafe { gpu.device().create_render_pass(&info, None) }.ctx("vkCreateRenderPass")
}

fn scene_pipeline(
    gpu: &Gpu,
    layout: vk::PipelineLayout,
    set: &PassSet,
    vert: vk::ShaderModule,
    frag: vk::ShaderModule,
) -> Result<vk::Pipeline, GpuError> {
    // solution::format::Vertex: position, normal, tangent, 3 × f32 each, 36 bytes.
    let (bindings, attributes) = vertex_layout::<3>(vk::VertexInputRate::VERTEX);
    // Front faces are counter-clockwise seen from the normal's side; after the
    // projection's y flip they stay counter-clockwise in Vulkan's framebuffer
    // convention (solution/src/camera.rs), so back faces are culled as in the CPU
    // rasterizer.
    GraphicsPipeline {
        bindings: &bindings,
        attributes: &attributes,
        cull_mode: vk::CullModeFlags::BACK,
        samples: set.desc.samples,
        depth_compare: Some(vk::CompareOp::LESS),
        ..GraphicsPipeline::new(set.render_pass, 0, layout, vert, frag)
    }
    .build(gpu)
}

/// The vertex buffer of the scene subpass's pipelines: one binding of
/// [`solution::format::Vertex`] (36 bytes) at `rate`, and its first `N`
/// attributes (position at 0, normal at 12, tangent at 24), each 3 × f32.
pub(super) fn vertex_layout<const N: usize>(
    rate: vk::VertexInputRate,
) -> (
    [vk::VertexInputBindingDescription; 1],
    [vk::VertexInputAttributeDescription; N],
) {
    let bindings = [vk::VertexInputBindingDescription::default()
        .binding(0)
        .stride(std::mem::size_of::<solution::format::Vertex>() as u32)
        .input_rate(rate)];
    let attributes = std::array::from_fn(|i| {
        vk::VertexInputAttributeDescription::default()
            .location(i as u32)
            .binding(0)
            .format(vk::Format::R32G32B32_SFLOAT)
            .offset(12 * i as u32)
    });
    (bindings, attributes)
}

fn tonemap_pipeline(
    gpu: &Gpu,
    layouts: &Layouts,
    set: &PassSet,
    vert: vk::ShaderModule,
    frag: vk::ShaderModule,
) -> Result<vk::Pipeline, GpuError> {
    GraphicsPipeline::new(set.render_pass, 1, layouts.tonemap_pipeline, vert, frag).build(gpu)
}
