//! The one graphics-pipeline builder of the runtime: the renderer's scene,
//! tone-map and inspection pipelines and the mirror window's composite and
//! overlay pipelines are all made here, each stating only where it differs
//! from the defaults that every one of them shares.

use super::{shaders, Gpu, GpuError, VkContext};
use ash::vk;

/// A graphics pipeline of one vertex and one fragment stage (entry point
/// `main`), polygons filled, lines one pixel wide, front faces
/// counter-clockwise, one colour attachment, and dynamic viewport and scissor
/// (one pipeline serves every image size). [`GraphicsPipeline::new`] gives the
/// full-screen defaults; a caller changes the fields it needs.
#[derive(Clone, Copy)]
pub struct GraphicsPipeline<'a> {
    pub render_pass: vk::RenderPass,
    pub subpass: u32,
    pub layout: vk::PipelineLayout,
    pub vert: vk::ShaderModule,
    pub frag: vk::ShaderModule,
    /// The vertex buffers' layout (none for a full-screen triangle).
    pub bindings: &'a [vk::VertexInputBindingDescription],
    pub attributes: &'a [vk::VertexInputAttributeDescription],
    pub topology: vk::PrimitiveTopology,
    pub cull_mode: vk::CullModeFlags,
    pub samples: vk::SampleCountFlags,
    /// The depth test's comparison, with depth writes; `None`: no depth test.
    pub depth_compare: Option<vk::CompareOp>,
    /// How the fragment's colour meets the attachment's.
    pub blend: vk::PipelineColorBlendAttachmentState,
}

impl<'a> GraphicsPipeline<'a> {
    /// A full-screen pass's pipeline: no vertex input, a triangle list, no
    /// culling, one sample, no depth test, colour written opaque.
    pub fn new(
        render_pass: vk::RenderPass,
        subpass: u32,
        layout: vk::PipelineLayout,
        vert: vk::ShaderModule,
        frag: vk::ShaderModule,
    ) -> Self {
        GraphicsPipeline {
            render_pass,
            subpass,
            layout,
            vert,
            frag,
            bindings: &[],
            attributes: &[],
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            cull_mode: vk::CullModeFlags::NONE,
            samples: vk::SampleCountFlags::TYPE_1,
            depth_compare: None,
            blend: vk::PipelineColorBlendAttachmentState::default()
                .color_write_mask(vk::ColorComponentFlags::RGBA),
        }
    }

    /// Creates the pipeline; its owner destroys it.
    pub fn build(&self, gpu: &Gpu) -> Result<vk::Pipeline, GpuError> {
        let stages = [
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::VERTEX)
                .module(self.vert)
                .name(c"main"),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(self.frag)
                .name(c"main"),
        ];
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(self.bindings)
            .vertex_attribute_descriptions(self.attributes);
        let assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(self.topology);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(self.cull_mode)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample =
            vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(self.samples);
        let depth = match self.depth_compare {
            Some(compare) => vk::PipelineDepthStencilStateCreateInfo::default()
                .depth_test_enable(true)
                .depth_write_enable(true)
                .depth_compare_op(compare),
            None => vk::PipelineDepthStencilStateCreateInfo::default(),
        };
        let blend_attachments = [self.blend];
        let blend =
            vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
        // Viewport and scissor are dynamic: one pipeline serves every image size.
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let info = [vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(self.layout)
            .render_pass(self.render_pass)
            .subpass(self.subpass)];
        // SAFETY: every state struct points to locals alive for the call; the
        // render pass, layout and shader modules are live handles of this device.
        let pipelines = unsafe {
            gpu.device()
                .create_graphics_pipelines(vk::PipelineCache::null(), &info, None)
        }
        .map_err(|(_, result)| GpuError::Vulkan {
            call: "vkCreateGraphicsPipelines",
            result,
        })?;
        Ok(pipelines[0])
    }
}

/// Shader modules, destroyed once the pipelines made from them exist (or
/// failed): on every return path, by `Drop`.
pub struct ShaderModules<'a> {
    device: &'a ash::Device,
    handles: Vec<vk::ShaderModule>,
}

impl<'a> ShaderModules<'a> {
    pub fn new(gpu: &'a Gpu) -> Self {
        ShaderModules {
            device: gpu.device(),
            handles: Vec::new(),
        }
    }

    /// A module of embedded SPIR-V ([`shaders`]), kept until `self` drops.
    pub fn load(&mut self, gpu: &Gpu, spirv: &[u8]) -> Result<vk::ShaderModule, GpuError> {
        let m = shaders::create_module(gpu, spirv)?;
        self.handles.push(m);
        Ok(m)
    }
}

impl Drop for ShaderModules<'_> {
    fn drop(&mut self) {
        for &m in &self.handles {
            // SAFETY: modules may be destroyed once pipelines using them exist.
            unsafe { self.device.destroy_shader_module(m, None) };
        }
    }
}

/// A descriptor set layout of one descriptor per binding, numbered from 0:
/// each binding's type and the stages that read it. Its owner destroys it.
pub fn set_layout(
    gpu: &Gpu,
    bindings: &[(vk::DescriptorType, vk::ShaderStageFlags)],
) -> Result<vk::DescriptorSetLayout, GpuError> {
    let bindings: Vec<_> = bindings
        .iter()
        .enumerate()
        .map(|(i, &(kind, stages))| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(i as u32)
                .descriptor_type(kind)
                .descriptor_count(1)
                .stage_flags(stages)
        })
        .collect();
    let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
    // SAFETY: the create info points to locals alive for the call.
    unsafe { gpu.device().create_descriptor_set_layout(&info, None) }
        .ctx("vkCreateDescriptorSetLayout")
}

/// A pipeline layout of `sets` and one push-constant range of `push_bytes`
/// bytes, read by `push_stages`. Its owner destroys it.
pub fn pipeline_layout(
    gpu: &Gpu,
    sets: &[vk::DescriptorSetLayout],
    push_stages: vk::ShaderStageFlags,
    push_bytes: u32,
) -> Result<vk::PipelineLayout, GpuError> {
    let push = [vk::PushConstantRange::default()
        .stage_flags(push_stages)
        .size(push_bytes)];
    let info = vk::PipelineLayoutCreateInfo::default()
        .set_layouts(sets)
        .push_constant_ranges(&push);
    // SAFETY: the create info points to locals and to live set layouts.
    unsafe { gpu.device().create_pipeline_layout(&info, None) }.ctx("vkCreatePipelineLayout")
}
