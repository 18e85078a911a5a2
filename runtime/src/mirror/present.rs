//! The mirror window's Vulkan side: the surface and swapchain of a winit
//! window, the renderer's own eye images, and the composite pass that copies
//! them (side by side, one eye, or anaglyph) with the text overlay into the
//! swapchain image.
//!
//! The stereo renderer draws into [`Presenter::eye_targets`] (two images of two
//! layers, one per frame in flight), never into the swapchain, so the window's
//! pace cannot hold up the renderer: presentation uses MAILBOX or IMMEDIATE and
//! a non-blocking acquire (a frame with no free swapchain image is simply not
//! shown), or FIFO when vsync is asked for (or nothing else is offered).
//!
//! Synchronisation per frame slot: a fence (the slot's composite has finished,
//! so its eye image and acquire semaphore are free), an acquire semaphore, and
//! per swapchain image a semaphore that the composite signals and the
//! presentation waits for.

use crate::gpu::barrier::{cmd_image_barriers, image_barrier};
use crate::gpu::{Buffer, BufferDesc, Gpu, GpuError, Image, ImageDesc, MemoryLocation, VkContext};
use crate::render::SwapchainDesc;
use anyhow::{bail, Context, Result};
use ash::vk;
use std::sync::Arc;
use winit::window::Window;

use super::font::{self, TextGrid};

/// Frames in flight (eye images, command buffers, fences).
pub const SLOTS: usize = 2;
/// The eye images' format when the window's cannot be used (the renderer's
/// output: sRGB, sampled as linear by the composite shader).
pub const DEFAULT_EYE_FORMAT: vk::Format = vk::Format::R8G8B8A8_SRGB;
/// The most text the overlay holds.
pub const MAX_TEXT_COLS: u32 = 100;
pub const MAX_TEXT_ROWS: u32 = 40;

/// How the composite pass combines the eye images.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// Layer 0 left half, layer 1 right half.
    SideBySide,
    /// One layer, full window.
    Single { layer: u32 },
    /// Red of layer 0, green and blue of layer 1.
    Anaglyph,
}

/// The overlay text and where it goes.
#[derive(Clone, Debug, Default)]
pub struct Overlay {
    pub grid: TextGrid,
    pub origin: (i32, i32),
    pub scale: u32,
}

/// The window's last image as shown, for `--dump-last-frame`.
#[derive(Clone, Debug)]
pub struct Dump {
    pub width: u32,
    pub height: u32,
    /// sRGB RGBA8, row 0 at the top.
    pub rgba: Vec<u8>,
}

/// An acquired frame.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// The frame slot: the eye image to render into.
    pub slot: usize,
    image: u32,
}

struct Slot {
    command_buffer: vk::CommandBuffer,
    fence: vk::Fence,
    acquired: vk::Semaphore,
    overlay: Buffer,
    descriptor_set: vk::DescriptorSet,
}

/// Swapchain-sized state, rebuilt on resize.
struct Chain {
    swapchain: vk::SwapchainKHR,
    extent: vk::Extent2D,
    views: Vec<vk::ImageView>,
    framebuffers: Vec<vk::Framebuffer>,
    images: Vec<vk::Image>,
    /// Signalled by the composite of image i, waited for by its presentation.
    rendered: Vec<vk::Semaphore>,
}

pub struct Presenter {
    // Destroyed explicitly in Drop (after waiting for the device), in this
    // order: chain, slots, pipeline objects, eye images, surface.
    chain: Option<Chain>,
    slots: Vec<Slot>,
    eyes: Vec<Image>,
    eye_size: (u32, u32),
    descriptor_pool: vk::DescriptorPool,
    pipeline: vk::Pipeline,
    pipeline_layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    render_pass: vk::RenderPass,
    overlay_pipeline: vk::Pipeline,
    overlay_pass: vk::RenderPass,
    sampler: vk::Sampler,
    format: vk::SurfaceFormatKHR,
    encode_srgb: bool,
    /// The eye images' format: the window's when it is 8-bit sRGB (then they
    /// are copied into it), else R8G8B8A8_SRGB through the composite shader.
    eye_format: vk::Format,
    copy_path: bool,
    present_mode: vk::PresentModeKHR,
    can_dump: bool,
    next_slot: usize,
    needs_rebuild: bool,
    swapchain_loader: ash::khr::swapchain::Device,
    surface_loader: ash::khr::surface::Instance,
    surface: vk::SurfaceKHR,
    queue: vk::Queue,
    command_pool: vk::CommandPool,
    physical: vk::PhysicalDevice,
    shared: Arc<crate::gpu::DeviceShared>,
    window: Arc<Window>,
}

/// The instance and device extensions a window on `window`'s display needs.
pub fn required_extensions(window: &Window) -> Result<crate::gpu::GpuExtensions> {
    use raw_window_handle::HasDisplayHandle;
    let display = window
        .display_handle()
        .context("the window has no display handle")?
        .as_raw();
    let names = ash_window::enumerate_required_extensions(display)
        .context("this display system has no Vulkan surface extension")?;
    let instance = names
        .iter()
        // SAFETY: ash-window returns pointers to static, NUL-terminated
        // extension names.
        .map(|&p| unsafe { std::ffi::CStr::from_ptr(p) })
        .collect();
    Ok(crate::gpu::GpuExtensions {
        instance,
        device: vec![ash::khr::swapchain::NAME],
    })
}

fn srgb_format(format: vk::Format) -> bool {
    matches!(
        format,
        vk::Format::B8G8R8A8_SRGB | vk::Format::R8G8B8A8_SRGB | vk::Format::A8B8G8R8_SRGB_PACK32
    )
}

/// The present mode: FIFO with vsync; else MAILBOX, then IMMEDIATE, then FIFO
/// (always supported).
pub fn choose_present_mode(available: &[vk::PresentModeKHR], vsync: bool) -> vk::PresentModeKHR {
    if vsync {
        return vk::PresentModeKHR::FIFO;
    }
    [vk::PresentModeKHR::MAILBOX, vk::PresentModeKHR::IMMEDIATE]
        .into_iter()
        .find(|m| available.contains(m))
        .unwrap_or(vk::PresentModeKHR::FIFO)
}

/// The surface format: 8-bit sRGB if offered, else the first (the shader then
/// applies the sRGB curve itself).
pub fn choose_format(available: &[vk::SurfaceFormatKHR]) -> Option<vk::SurfaceFormatKHR> {
    available
        .iter()
        .find(|f| srgb_format(f.format) && f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR)
        .or_else(|| available.first())
        .copied()
}

impl Presenter {
    /// Creates the surface of `window` (on a `gpu` made with
    /// [`required_extensions`]) and the composite pipeline; the swapchain is made
    /// on the first frame.
    pub fn new(gpu: &Gpu, window: Arc<Window>, vsync: bool) -> Result<Presenter> {
        use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
        let display = window
            .display_handle()
            .context("the window has no display handle")?
            .as_raw();
        let handle = window
            .window_handle()
            .context("the window has no window handle")?
            .as_raw();
        // SAFETY: the handles belong to `window`, which the presenter keeps
        // alive (Arc) until the surface is destroyed in Drop; the instance was
        // made with the extensions `required_extensions` named.
        let surface = unsafe {
            ash_window::create_surface(gpu.entry(), gpu.instance(), display, handle, None)
        }
        .context("cannot create a Vulkan surface for the window")?;
        let surface_loader = ash::khr::surface::Instance::new(gpu.entry(), gpu.instance());
        let swapchain_loader = ash::khr::swapchain::Device::new(gpu.instance(), gpu.device());
        let mut presenter = Presenter {
            chain: None,
            slots: Vec::new(),
            eyes: Vec::new(),
            eye_size: (0, 0),
            descriptor_pool: vk::DescriptorPool::null(),
            pipeline: vk::Pipeline::null(),
            pipeline_layout: vk::PipelineLayout::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            render_pass: vk::RenderPass::null(),
            overlay_pipeline: vk::Pipeline::null(),
            overlay_pass: vk::RenderPass::null(),
            sampler: vk::Sampler::null(),
            format: vk::SurfaceFormatKHR::default(),
            encode_srgb: false,
            eye_format: DEFAULT_EYE_FORMAT,
            copy_path: false,
            present_mode: vk::PresentModeKHR::FIFO,
            can_dump: false,
            next_slot: 0,
            needs_rebuild: true,
            swapchain_loader,
            surface_loader,
            surface,
            queue: gpu.queue,
            command_pool: gpu.command_pool(),
            physical: gpu.physical,
            shared: gpu.shared.clone(),
            window,
        };
        // From here on, Drop cleans up whatever exists.
        // SAFETY: plain queries on this instance's physical device and surface.
        let (supported, formats, modes) = unsafe {
            (
                presenter
                    .surface_loader
                    .get_physical_device_surface_support(gpu.physical, gpu.queue_family, surface)
                    .ctx("vkGetPhysicalDeviceSurfaceSupportKHR")?,
                presenter
                    .surface_loader
                    .get_physical_device_surface_formats(gpu.physical, surface)
                    .ctx("vkGetPhysicalDeviceSurfaceFormatsKHR")?,
                presenter
                    .surface_loader
                    .get_physical_device_surface_present_modes(gpu.physical, surface)
                    .ctx("vkGetPhysicalDeviceSurfacePresentModesKHR")?,
            )
        };
        if !supported {
            bail!(
                "the Vulkan device {} cannot present to this window (queue family {})",
                gpu.info.name,
                gpu.queue_family
            );
        }
        presenter.format = choose_format(&formats).context("the surface offers no format")?;
        presenter.encode_srgb = !srgb_format(presenter.format.format);
        // SAFETY: plain query.
        let caps = unsafe {
            presenter
                .surface_loader
                .get_physical_device_surface_capabilities(gpu.physical, surface)
        }
        .ctx("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?;
        let copyable = matches!(
            presenter.format.format,
            vk::Format::B8G8R8A8_SRGB | vk::Format::R8G8B8A8_SRGB
        ) && caps
            .supported_usage_flags
            .contains(vk::ImageUsageFlags::TRANSFER_DST);
        // RUNTIME_MIRROR_COMPOSITE=1 forces the composite shader (to measure
        // or test it against the copies).
        presenter.copy_path = copyable && std::env::var_os("RUNTIME_MIRROR_COMPOSITE").is_none();
        presenter.eye_format = if presenter.copy_path {
            presenter.format.format
        } else {
            DEFAULT_EYE_FORMAT
        };
        presenter.present_mode = choose_present_mode(&modes, vsync);
        presenter.create_pipeline(gpu)?;
        presenter.create_slots(gpu)?;
        Ok(presenter)
    }

    pub fn present_mode(&self) -> vk::PresentModeKHR {
        self.present_mode
    }

    pub fn surface_format(&self) -> vk::Format {
        self.format.format
    }

    /// Whether side-by-side and single-eye frames are copied into the window
    /// (else drawn by the composite shader).
    pub fn copies_eyes(&self) -> bool {
        self.copy_path
    }

    /// The window's drawable size now (the swapchain follows it).
    pub fn window_size(&self) -> (u32, u32) {
        let size = self.window.inner_size();
        (size.width, size.height)
    }

    /// Asks for a new swapchain before the next frame (the window was resized).
    pub fn resized(&mut self) {
        self.needs_rebuild = true;
    }

    /// The renderer's targets: two images of two layers at `eye_size`.
    pub fn eye_targets(&self) -> SwapchainDesc {
        SwapchainDesc {
            images: self.eyes.iter().map(|i| i.raw).collect(),
            format: self.eye_format,
            width: self.eye_size.0,
            height: self.eye_size.1,
            layers: 2,
        }
    }

    /// Makes the eye images `width × height` if they are not. When they were
    /// remade, the old ones are returned: a renderer drawing into them must be
    /// pointed at the new ones ([`Presenter::eye_targets`]) before they are
    /// dropped.
    pub fn ensure_eye_size(
        &mut self,
        gpu: &Gpu,
        width: u32,
        height: u32,
    ) -> Result<Option<Vec<Image>>> {
        if self.eye_size == (width, height) && !self.eyes.is_empty() {
            return Ok(None);
        }
        self.wait_idle();
        let mut eyes = Vec::new();
        for _ in 0..SLOTS {
            eyes.push(Image::new(
                gpu,
                ImageDesc {
                    width,
                    height,
                    layers: 2,
                    format: self.eye_format,
                    samples: vk::SampleCountFlags::TYPE_1,
                    usage: vk::ImageUsageFlags::COLOR_ATTACHMENT
                        | vk::ImageUsageFlags::SAMPLED
                        | vk::ImageUsageFlags::TRANSFER_SRC,
                    aspect: vk::ImageAspectFlags::COLOR,
                },
            )?);
        }
        let retired = std::mem::replace(&mut self.eyes, eyes);
        self.eye_size = (width, height);
        for (slot, eye) in self.slots.iter().zip(&self.eyes) {
            let image_info = [vk::DescriptorImageInfo::default()
                .sampler(self.sampler)
                .image_view(eye.view)
                .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
            let buffer_info = [vk::DescriptorBufferInfo::default()
                .buffer(slot.overlay.raw)
                .range(vk::WHOLE_SIZE)];
            let writes = [
                vk::WriteDescriptorSet::default()
                    .dst_set(slot.descriptor_set)
                    .dst_binding(0)
                    .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                    .image_info(&image_info),
                vk::WriteDescriptorSet::default()
                    .dst_set(slot.descriptor_set)
                    .dst_binding(1)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(&buffer_info),
            ];
            // SAFETY: the device is idle (no pending use of the sets); every
            // handle is live.
            unsafe { self.shared.device.update_descriptor_sets(&writes, &[]) };
        }
        Ok(Some(retired))
    }

    fn wait_idle(&self) {
        // SAFETY: waiting has no preconditions.
        let _ = unsafe { self.shared.device.device_wait_idle() };
    }

    /// A render pass on the swapchain image: the full composite (its contents
    /// discarded first) or the overlay over copied eye images (loaded from the
    /// copy's TRANSFER_DST layout). The two are compatible (one attachment of
    /// one format), so the framebuffers serve both.
    fn create_render_pass(
        &self,
        device: &ash::Device,
        overlay: bool,
    ) -> Result<vk::RenderPass, GpuError> {
        let attachment = [vk::AttachmentDescription::default()
            .format(self.format.format)
            .samples(vk::SampleCountFlags::TYPE_1)
            .load_op(if overlay {
                vk::AttachmentLoadOp::LOAD
            } else {
                vk::AttachmentLoadOp::DONT_CARE
            })
            .store_op(vk::AttachmentStoreOp::STORE)
            .initial_layout(if overlay {
                vk::ImageLayout::TRANSFER_DST_OPTIMAL
            } else {
                vk::ImageLayout::UNDEFINED
            })
            .final_layout(vk::ImageLayout::PRESENT_SRC_KHR)];
        let color = [vk::AttachmentReference::default()
            .attachment(0)
            .layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)];
        let subpass = [vk::SubpassDescription::default()
            .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
            .color_attachments(&color)];
        // Before: the acquire semaphore (waited for at COLOR_ATTACHMENT_OUTPUT
        // and TRANSFER) and, for the overlay, the copies into the image. After:
        // the dump's copy, if any.
        let dependencies = [
            vk::SubpassDependency::default()
                .src_subpass(vk::SUBPASS_EXTERNAL)
                .dst_subpass(0)
                .src_stage_mask(
                    vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
                        | vk::PipelineStageFlags::TRANSFER,
                )
                .dst_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(
                    vk::AccessFlags::COLOR_ATTACHMENT_READ
                        | vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
                ),
            vk::SubpassDependency::default()
                .src_subpass(0)
                .dst_subpass(vk::SUBPASS_EXTERNAL)
                .src_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
                .dst_stage_mask(vk::PipelineStageFlags::TRANSFER)
                .src_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE)
                .dst_access_mask(vk::AccessFlags::TRANSFER_READ),
        ];
        // SAFETY: the create info points to locals.
        unsafe {
            device.create_render_pass(
                &vk::RenderPassCreateInfo::default()
                    .attachments(&attachment)
                    .subpasses(&subpass)
                    .dependencies(&dependencies),
                None,
            )
        }
        .ctx("vkCreateRenderPass")
    }

    fn create_pipeline(&mut self, gpu: &Gpu) -> Result<(), GpuError> {
        let device = gpu.device();
        let bindings = [
            vk::DescriptorSetLayoutBinding::default()
                .binding(0)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .descriptor_count(1)
                .stage_flags(vk::ShaderStageFlags::FRAGMENT),
            vk::DescriptorSetLayoutBinding::default()
                .binding(1)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(1)
                .stage_flags(vk::ShaderStageFlags::FRAGMENT),
        ];
        let push = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::FRAGMENT)
            .size(PUSH_SIZE)];
        self.render_pass = self.create_render_pass(device, false)?;
        self.overlay_pass = self.create_render_pass(device, true)?;
        // Every handle is stored in self at once, so Drop destroys it if a
        // later step fails.
        let set_info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
        // SAFETY: the create info points to locals alive for the call.
        self.set_layout = unsafe { device.create_descriptor_set_layout(&set_info, None) }
            .ctx("vkCreateDescriptorSetLayout")?;
        let sets = [self.set_layout];
        let layout_info = vk::PipelineLayoutCreateInfo::default()
            .set_layouts(&sets)
            .push_constant_ranges(&push);
        // SAFETY: the create info points to locals and to the live set layout.
        self.pipeline_layout = unsafe { device.create_pipeline_layout(&layout_info, None) }
            .ctx("vkCreatePipelineLayout")?;
        let sampler_info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::NEAREST)
            .min_filter(vk::Filter::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE);
        // SAFETY: a plain create info.
        self.sampler =
            unsafe { device.create_sampler(&sampler_info, None) }.ctx("vkCreateSampler")?;
        use crate::gpu::shaders::{create_module, COMPOSITE_FRAG, OVERLAY_FRAG, TONEMAP_VERT};
        let mut modules = Vec::new();
        let made = [TONEMAP_VERT, COMPOSITE_FRAG, OVERLAY_FRAG]
            .into_iter()
            .try_for_each(|spirv| create_module(gpu, spirv).map(|m| modules.push(m)));
        if let Err(e) = made {
            for m in modules {
                // SAFETY: unused modules.
                unsafe { device.destroy_shader_module(m, None) };
            }
            return Err(e);
        }
        let stage = |kind, module| {
            vk::PipelineShaderStageCreateInfo::default()
                .stage(kind)
                .module(module)
                .name(c"main")
        };
        let composite_stages = [
            stage(vk::ShaderStageFlags::VERTEX, modules[0]),
            stage(vk::ShaderStageFlags::FRAGMENT, modules[1]),
        ];
        let overlay_stages = [
            stage(vk::ShaderStageFlags::VERTEX, modules[0]),
            stage(vk::ShaderStageFlags::FRAGMENT, modules[2]),
        ];
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
        let assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
            .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .line_width(1.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let opaque = [vk::PipelineColorBlendAttachmentState::default()
            .color_write_mask(vk::ColorComponentFlags::RGBA)];
        // The overlay over copied eye images: text opaque, the block's
        // background darkening what is below (alpha = 1 - TEXT_BACKGROUND);
        // blending on an sRGB attachment happens on linear values.
        let over = [vk::PipelineColorBlendAttachmentState::default()
            .blend_enable(true)
            .src_color_blend_factor(vk::BlendFactor::SRC_ALPHA)
            .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .color_blend_op(vk::BlendOp::ADD)
            .src_alpha_blend_factor(vk::BlendFactor::ONE)
            .dst_alpha_blend_factor(vk::BlendFactor::ZERO)
            .alpha_blend_op(vk::BlendOp::ADD)
            .color_write_mask(vk::ColorComponentFlags::RGBA)];
        let blend_opaque = vk::PipelineColorBlendStateCreateInfo::default().attachments(&opaque);
        let blend_over = vk::PipelineColorBlendStateCreateInfo::default().attachments(&over);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default();
        let info = [
            (self.render_pass, &blend_opaque, &composite_stages),
            (self.overlay_pass, &blend_over, &overlay_stages),
        ]
        .map(|(pass, blend, stages)| {
            vk::GraphicsPipelineCreateInfo::default()
                .stages(stages)
                .vertex_input_state(&vertex_input)
                .input_assembly_state(&assembly)
                .viewport_state(&viewport)
                .rasterization_state(&raster)
                .multisample_state(&multisample)
                .depth_stencil_state(&depth)
                .color_blend_state(blend)
                .dynamic_state(&dynamic)
                .layout(self.pipeline_layout)
                .render_pass(pass)
                .subpass(0)
        });
        // SAFETY: the create infos point to locals and live handles.
        let result =
            unsafe { device.create_graphics_pipelines(vk::PipelineCache::null(), &info, None) };
        for m in modules {
            // SAFETY: modules may go once the pipelines exist (or failed).
            unsafe { device.destroy_shader_module(m, None) };
        }
        let pipelines = result.map_err(|(_, result)| GpuError::Vulkan {
            call: "vkCreateGraphicsPipelines",
            result,
        })?;
        self.pipeline = pipelines[0];
        self.overlay_pipeline = pipelines[1];
        Ok(())
    }

    fn create_slots(&mut self, gpu: &Gpu) -> Result<(), GpuError> {
        let device = gpu.device();
        let sizes = [
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .descriptor_count(SLOTS as u32),
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(SLOTS as u32),
        ];
        // SAFETY: create infos point to locals; handles are stored at once.
        unsafe {
            self.descriptor_pool = device
                .create_descriptor_pool(
                    &vk::DescriptorPoolCreateInfo::default()
                        .max_sets(SLOTS as u32)
                        .pool_sizes(&sizes),
                    None,
                )
                .ctx("vkCreateDescriptorPool")?;
        }
        let overlay_bytes = u64::from(95 * 7 + MAX_TEXT_COLS * MAX_TEXT_ROWS) * 4;
        for _ in 0..SLOTS {
            let overlay = Buffer::new(
                gpu,
                BufferDesc {
                    size: overlay_bytes,
                    usage: vk::BufferUsageFlags::STORAGE_BUFFER,
                    location: MemoryLocation::Mapped,
                },
            )?;
            let layouts = [self.set_layout];
            let set_info = vk::DescriptorSetAllocateInfo::default()
                .descriptor_pool(self.descriptor_pool)
                .set_layouts(&layouts);
            // SAFETY: the pool was sized for SLOTS sets and the pool and the
            // layout are live; the set is freed with the pool.
            let descriptor_set = unsafe { device.allocate_descriptor_sets(&set_info) }
                .ctx("vkAllocateDescriptorSets")?[0];
            let command_info = vk::CommandBufferAllocateInfo::default()
                .command_pool(self.command_pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1);
            // SAFETY: the command pool is live and used from this thread only;
            // the buffer is freed with the pool.
            let command_buffer = unsafe { device.allocate_command_buffers(&command_info) }
                .ctx("vkAllocateCommandBuffers")?[0];
            let fence_info = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
            // SAFETY: a plain create info; the fence is destroyed in Drop.
            let fence = unsafe { device.create_fence(&fence_info, None) }.ctx("vkCreateFence")?;
            // SAFETY: a plain create info; the semaphore is destroyed in Drop.
            let acquired =
                unsafe { device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
                    .ctx("vkCreateSemaphore")?;
            let slot = Slot {
                command_buffer,
                fence,
                acquired,
                overlay,
                descriptor_set,
            };
            self.slots.push(slot);
        }
        Ok(())
    }

    fn destroy_chain(&mut self, keep_swapchain: bool) -> vk::SwapchainKHR {
        let Some(chain) = self.chain.take() else {
            return vk::SwapchainKHR::null();
        };
        let device = &self.shared.device;
        // SAFETY: callers waited for the device to be idle, so nothing uses
        // these objects.
        unsafe {
            for &fb in &chain.framebuffers {
                device.destroy_framebuffer(fb, None);
            }
            for &view in &chain.views {
                device.destroy_image_view(view, None);
            }
            for &s in &chain.rendered {
                device.destroy_semaphore(s, None);
            }
            if keep_swapchain {
                return chain.swapchain;
            }
            self.swapchain_loader
                .destroy_swapchain(chain.swapchain, None);
        }
        vk::SwapchainKHR::null()
    }

    /// (Re)creates the swapchain at the window's size; false while the window
    /// has no area (minimised).
    fn rebuild(&mut self) -> Result<bool> {
        self.wait_idle();
        let old = self.destroy_chain(true);
        let device = &self.shared.device;
        // SAFETY: plain query.
        let caps = unsafe {
            self.surface_loader
                .get_physical_device_surface_capabilities(self.physical, self.surface)
        };
        let caps = match caps {
            Ok(c) => c,
            Err(e) => {
                // SAFETY: the old swapchain is retired and unused (device idle).
                unsafe { self.swapchain_loader.destroy_swapchain(old, None) };
                return Err(GpuError::Vulkan {
                    call: "vkGetPhysicalDeviceSurfaceCapabilitiesKHR",
                    result: e,
                }
                .into());
            }
        };
        let (w, h) = self.window_size();
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: w.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: h.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        if extent.width == 0 || extent.height == 0 {
            // SAFETY: as above.
            unsafe { self.swapchain_loader.destroy_swapchain(old, None) };
            return Ok(false);
        }
        let mut count = caps.min_image_count.max(3);
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        self.can_dump = caps
            .supported_usage_flags
            .contains(vk::ImageUsageFlags::TRANSFER_SRC);
        let mut usage = vk::ImageUsageFlags::COLOR_ATTACHMENT;
        if self.copy_path {
            usage |= vk::ImageUsageFlags::TRANSFER_DST;
        }
        if self.can_dump {
            usage |= vk::ImageUsageFlags::TRANSFER_SRC;
        }
        let alpha = [
            vk::CompositeAlphaFlagsKHR::OPAQUE,
            vk::CompositeAlphaFlagsKHR::INHERIT,
            vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
            vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
        ]
        .into_iter()
        .find(|a| caps.supported_composite_alpha.contains(*a))
        .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE);
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface)
            .min_image_count(count)
            .image_format(self.format.format)
            .image_color_space(self.format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(alpha)
            .present_mode(self.present_mode)
            .clipped(true)
            .old_swapchain(old);
        // SAFETY: the create info points to locals and live handles; the old
        // swapchain is retired by this call and destroyed right after.
        let created = unsafe { self.swapchain_loader.create_swapchain(&info, None) };
        // SAFETY: retired and unused (device idle).
        unsafe { self.swapchain_loader.destroy_swapchain(old, None) };
        let swapchain = created.ctx("vkCreateSwapchainKHR")?;
        let mut chain = Chain {
            swapchain,
            extent,
            views: Vec::new(),
            framebuffers: Vec::new(),
            images: Vec::new(),
            rendered: Vec::new(),
        };
        // Stored before the fallible steps so that Drop cleans up.
        let result = (|| -> Result<(), GpuError> {
            // SAFETY: the swapchain is live.
            chain.images = unsafe { self.swapchain_loader.get_swapchain_images(swapchain) }
                .ctx("vkGetSwapchainImagesKHR")?;
            for &image in &chain.images {
                let view_info = vk::ImageViewCreateInfo::default()
                    .image(image)
                    .view_type(vk::ImageViewType::TYPE_2D)
                    .format(self.format.format)
                    .subresource_range(COLOR_RANGE);
                // SAFETY: a swapchain image of this device; destroyed in
                // destroy_chain.
                let view = unsafe { device.create_image_view(&view_info, None) }
                    .ctx("vkCreateImageView")?;
                chain.views.push(view);
                let attachments = [view];
                let fb_info = vk::FramebufferCreateInfo::default()
                    .render_pass(self.render_pass)
                    .attachments(&attachments)
                    .width(extent.width)
                    .height(extent.height)
                    .layers(1);
                // SAFETY: as above.
                let fb = unsafe { device.create_framebuffer(&fb_info, None) }
                    .ctx("vkCreateFramebuffer")?;
                chain.framebuffers.push(fb);
                // SAFETY: as above.
                let s =
                    unsafe { device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
                        .ctx("vkCreateSemaphore")?;
                chain.rendered.push(s);
            }
            Ok(())
        })();
        self.chain = Some(chain);
        result?;
        // Acquire semaphores may hold a signal from an acquire whose frame was
        // abandoned: make them fresh too.
        for slot in &mut self.slots {
            // SAFETY: the device is idle; a fresh semaphore replaces the old.
            unsafe {
                device.destroy_semaphore(slot.acquired, None);
                slot.acquired = device
                    .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
                    .ctx("vkCreateSemaphore")?;
            }
        }
        self.needs_rebuild = false;
        Ok(true)
    }

    /// The swapchain's size (the window's drawable area), once there is one.
    pub fn extent(&self) -> Option<(u32, u32)> {
        self.chain
            .as_ref()
            .map(|c| (c.extent.width, c.extent.height))
    }

    /// Waits for the next slot and acquires a swapchain image: None when none
    /// is free now (the frame is skipped, never waited for unless vsync is on)
    /// or the window has no area.
    pub fn begin_frame(&mut self) -> Result<Option<Frame>> {
        let (w, h) = self.window_size();
        if w == 0 || h == 0 {
            return Ok(None);
        }
        let size_changed = self.extent().is_some_and(|(cw, ch)| (cw, ch) != (w, h));
        if (self.needs_rebuild || self.chain.is_none() || size_changed) && !self.rebuild()? {
            return Ok(None);
        }
        let slot = self.next_slot;
        let device = &self.shared.device;
        let fence = self.slots[slot].fence;
        // SAFETY: the fence belongs to this device.
        unsafe { device.wait_for_fences(&[fence], true, u64::MAX) }.ctx("vkWaitForFences")?;
        let chain = self.chain.as_ref().context("no swapchain")?;
        let timeout = if self.present_mode == vk::PresentModeKHR::FIFO {
            u64::MAX
        } else {
            0
        };
        // SAFETY: the slot's semaphore is unsignalled (its last acquire was
        // waited for by the slot's composite, which the fence says finished).
        let acquired = unsafe {
            self.swapchain_loader.acquire_next_image(
                chain.swapchain,
                timeout,
                self.slots[slot].acquired,
                vk::Fence::null(),
            )
        };
        match acquired {
            Ok((image, suboptimal)) => {
                if suboptimal {
                    self.needs_rebuild = true;
                }
                Ok(Some(Frame { slot, image }))
            }
            Err(vk::Result::NOT_READY) | Err(vk::Result::TIMEOUT) => Ok(None),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.needs_rebuild = true;
                Ok(None)
            }
            Err(e) => Err(GpuError::Vulkan {
                call: "vkAcquireNextImageKHR",
                result: e,
            }
            .into()),
        }
    }

    /// Records and submits the composite of the frame's eye image into the
    /// acquired swapchain image, presents it, and (with `dump`) reads it back.
    pub fn finish_frame(
        &mut self,
        gpu: &Gpu,
        frame: Frame,
        layout: Layout,
        overlay: &Overlay,
        dump: bool,
    ) -> Result<Option<Dump>> {
        let extent = self.chain.as_ref().context("no swapchain")?.extent;
        self.write_overlay(frame.slot, overlay);
        let dump_buffer = if dump {
            Some(self.dump_buffer(gpu, extent)?)
        } else {
            None
        };
        self.record_frame(frame, layout, overlay, dump_buffer.as_ref())?;
        self.submit_and_present(frame)?;
        self.next_slot = (frame.slot + 1) % SLOTS;
        match dump_buffer {
            None => Ok(None),
            Some(buffer) => self.read_dump(frame.slot, &buffer, extent).map(Some),
        }
    }

    /// Uploads the overlay's text grid into the slot's overlay buffer.
    fn write_overlay(&mut self, slot: usize, overlay: &Overlay) {
        let words = font::shader_words(&overlay.grid);
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        // SAFETY: the slot's fence was waited for in begin_frame and its command
        // buffer is not resubmitted before this frame's submit, so the GPU does
        // not read this buffer now.
        unsafe { self.slots[slot].overlay.write(0, &bytes) };
    }

    /// A host-visible buffer for one window image, after checking that the
    /// swapchain images can be copied and are 8-bit RGBA or BGRA.
    fn dump_buffer(&self, gpu: &Gpu, extent: vk::Extent2D) -> Result<Buffer> {
        if !self.can_dump {
            bail!("this window's swapchain images cannot be copied (no TRANSFER_SRC usage)");
        }
        if !matches!(
            self.format.format,
            vk::Format::B8G8R8A8_SRGB
                | vk::Format::B8G8R8A8_UNORM
                | vk::Format::R8G8B8A8_SRGB
                | vk::Format::R8G8B8A8_UNORM
        ) {
            bail!(
                "cannot dump a window image of format {:?} (8-bit RGBA or BGRA only)",
                self.format.format
            );
        }
        Ok(Buffer::new(
            gpu,
            BufferDesc {
                size: u64::from(extent.width) * u64::from(extent.height) * 4,
                usage: vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::Mapped,
            },
        )?)
    }

    /// Records the slot's command buffer: the eye image copied (or composited)
    /// into the swapchain image, the overlay over it, and the copy to `dump`.
    fn record_frame(
        &self,
        frame: Frame,
        layout: Layout,
        overlay: &Overlay,
        dump: Option<&Buffer>,
    ) -> Result<()> {
        let chain = self.chain.as_ref().context("no swapchain")?;
        let slot = &self.slots[frame.slot];
        let device = &self.shared.device;
        let cmd = slot.command_buffer;
        let eye = &self.eyes[frame.slot];
        let image = chain.images[frame.image as usize];
        let extent = chain.extent;
        // Copy path: the eye images are already in the window's format, so
        // side by side and single eyes are plain image copies (a memcpy on a CPU
        // device), with the overlay blended over its own rectangle. Anaglyph
        // (and windows of other formats) take the full-screen composite.
        let copies = copy_regions(layout, self.eye_size, (extent.width, extent.height));
        let copy = self.copy_path && copies.is_some();
        let (mode, layer) = match layout {
            Layout::SideBySide => (0u32, 0u32),
            Layout::Single { layer } => (1, layer),
            Layout::Anaglyph => (2, 0),
        };
        let push = push_bytes(
            self.eye_size,
            if copy { 3 } else { mode },
            layer,
            self.encode_srgb,
            overlay,
        );
        let overlay_area = overlay_rect(overlay, extent);
        // SAFETY: begin_frame waited for this slot's fence and nothing has
        // submitted the slot since.
        unsafe { begin_commands(device, cmd, slot.fence) }?;
        // SAFETY (for the recordings below): `cmd` is recording, outside a render
        // pass; the eye image and the swapchain image are live, and the eye image
        // was last written by the renderer's pass (layout COLOR_ATTACHMENT_OPTIMAL),
        // an earlier submission on this queue.
        let target = match (copy, &copies) {
            (true, Some((regions, covers))) => {
                // SAFETY: as above.
                let area =
                    unsafe { record_copy(device, cmd, eye, image, regions, *covers, overlay_area) };
                area.map(|area| (self.overlay_pass, self.overlay_pipeline, area))
            }
            _ => {
                // SAFETY: as above.
                unsafe { record_to_sampled(device, cmd, eye) };
                let full = vk::Rect2D {
                    offset: vk::Offset2D { x: 0, y: 0 },
                    extent,
                };
                Some((self.render_pass, self.pipeline, full))
            }
        };
        if let Some((pass, pipeline, area)) = target {
            let pass = Composite {
                pass,
                pipeline,
                framebuffer: chain.framebuffers[frame.image as usize],
                descriptor_set: slot.descriptor_set,
                area,
                extent,
            };
            // SAFETY: as above; the framebuffer is the swapchain image's and the
            // descriptor set (eye image, overlay buffer) is the slot's.
            unsafe { self.record_composite(cmd, &pass, &push) };
        }
        if let Some(buffer) = dump {
            // SAFETY: as above; the buffer holds one 4-byte texel per pixel.
            unsafe { record_dump_copy(device, cmd, image, buffer, extent) };
        }
        // SAFETY: `cmd` is recording, outside a render pass.
        unsafe { device.end_command_buffer(cmd) }.ctx("vkEndCommandBuffer")?;
        Ok(())
    }

    /// Draws the full-screen triangle of `pass` (the composite, or the overlay
    /// blended over the copied eyes) into `pass.area`.
    ///
    /// # Safety
    ///
    /// `cmd` is recording, outside a render pass; the framebuffer and the
    /// descriptor set are live and the images they name are in the layouts the
    /// render pass and the shader expect.
    unsafe fn record_composite(&self, cmd: vk::CommandBuffer, pass: &Composite, push: &[u8]) {
        let device = &self.shared.device;
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: pass.extent.width as f32,
            height: pass.extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        let begin = vk::RenderPassBeginInfo::default()
            .render_pass(pass.pass)
            .framebuffer(pass.framebuffer)
            .render_area(pass.area);
        // SAFETY: the caller guarantees the command buffer and the objects; the
        // pipeline was made for this render pass and this layout, and the push
        // constants match the layout's fragment range.
        unsafe {
            device.cmd_begin_render_pass(cmd, &begin, vk::SubpassContents::INLINE);
            device.cmd_set_viewport(cmd, 0, &[viewport]);
            device.cmd_set_scissor(cmd, 0, &[pass.area]);
            device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pass.pipeline);
            device.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                self.pipeline_layout,
                0,
                &[pass.descriptor_set],
                &[],
            );
            device.cmd_push_constants(
                cmd,
                self.pipeline_layout,
                vk::ShaderStageFlags::FRAGMENT,
                0,
                push,
            );
            device.cmd_draw(cmd, 3, 1, 0, 0);
            device.cmd_end_render_pass(cmd);
        }
    }

    /// Submits the slot's recorded command buffer (waiting for the acquire,
    /// signalling the image's semaphore and the slot's fence) and presents the
    /// image; an out-of-date or suboptimal swapchain is rebuilt next frame.
    fn submit_and_present(&mut self, frame: Frame) -> Result<()> {
        let chain = self.chain.as_ref().context("no swapchain")?;
        let slot = &self.slots[frame.slot];
        let waits = [slot.acquired];
        let stages =
            [vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT | vk::PipelineStageFlags::TRANSFER];
        let signals = [chain.rendered[frame.image as usize]];
        let cmds = [slot.command_buffer];
        let submit = [vk::SubmitInfo::default()
            .wait_semaphores(&waits)
            .wait_dst_stage_mask(&stages)
            .command_buffers(&cmds)
            .signal_semaphores(&signals)];
        // SAFETY: record_frame ended the command buffer; its fence was reset
        // there; the acquire semaphore is signalled by this frame's acquire, and
        // the image's semaphore was waited for by its last presentation.
        unsafe {
            self.shared
                .device
                .queue_submit(self.queue, &submit, slot.fence)
        }
        .ctx("vkQueueSubmit")?;
        let swapchains = [chain.swapchain];
        let indices = [frame.image];
        let present = vk::PresentInfoKHR::default()
            .wait_semaphores(&signals)
            .swapchains(&swapchains)
            .image_indices(&indices);
        // SAFETY: the image was acquired in begin_frame and the submission above
        // signals the semaphore the presentation waits for.
        let presented = unsafe { self.swapchain_loader.queue_present(self.queue, &present) };
        match presented {
            Ok(false) => {}
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => self.needs_rebuild = true,
            Err(e) => {
                return Err(GpuError::Vulkan {
                    call: "vkQueuePresentKHR",
                    result: e,
                }
                .into())
            }
        }
        Ok(())
    }

    /// Waits for the slot's submission and returns the dumped window image as
    /// RGBA (swapping BGRA windows' channels).
    fn read_dump(&self, slot: usize, buffer: &Buffer, extent: vk::Extent2D) -> Result<Dump> {
        let device = &self.shared.device;
        let fence = self.slots[slot].fence;
        // SAFETY: the fence belongs to this device.
        unsafe { device.wait_for_fences(&[fence], true, u64::MAX) }.ctx("vkWaitForFences")?;
        // SAFETY: the fence just waited for covers the only submission that
        // writes `buffer`, which was made for this dump and is used by no other.
        let data = unsafe { buffer.read() };
        let bgra = matches!(
            self.format.format,
            vk::Format::B8G8R8A8_SRGB | vk::Format::B8G8R8A8_UNORM
        );
        let mut rgba = data.to_vec();
        if bgra {
            for px in rgba.chunks_exact_mut(4) {
                px.swap(0, 2);
            }
        }
        Ok(Dump {
            width: extent.width,
            height: extent.height,
            rgba,
        })
    }
}

/// One full-screen draw of the composite or overlay pipeline.
struct Composite {
    pass: vk::RenderPass,
    pipeline: vk::Pipeline,
    framebuffer: vk::Framebuffer,
    descriptor_set: vk::DescriptorSet,
    area: vk::Rect2D,
    extent: vk::Extent2D,
}

/// Resets the slot's fence and command buffer and begins recording.
///
/// # Safety
///
/// The slot's fence was waited for since its last submission, so neither the
/// fence nor the command buffer is in use by the queue.
unsafe fn begin_commands(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
) -> Result<(), GpuError> {
    let begin =
        vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
    // SAFETY: the caller guarantees that neither object is pending; the
    // command pool was made with RESET_COMMAND_BUFFER.
    unsafe {
        device.reset_fences(&[fence]).ctx("vkResetFences")?;
        device
            .reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())
            .ctx("vkResetCommandBuffer")?;
        device
            .begin_command_buffer(cmd, &begin)
            .ctx("vkBeginCommandBuffer")
    }
}

/// The copy path: the eye layers copied into the swapchain image (cleared
/// first when they do not cover it). Returns the overlay's rectangle, to be
/// drawn next in the overlay pass; without an overlay, the image is moved to
/// PRESENT_SRC here and None is returned.
///
/// # Safety
///
/// `cmd` is recording, outside a render pass; `eye` is in
/// COLOR_ATTACHMENT_OPTIMAL after the renderer's pass; both images are live.
unsafe fn record_copy(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    eye: &Image,
    image: vk::Image,
    regions: &[vk::ImageCopy],
    covers: bool,
    overlay_area: Option<vk::Rect2D>,
) -> Option<vk::Rect2D> {
    use vk::{AccessFlags as A, ImageLayout as L, PipelineStageFlags as S};
    let to_copy = [
        image_barrier(
            eye.raw,
            eye.range(),
            (L::COLOR_ATTACHMENT_OPTIMAL, A::COLOR_ATTACHMENT_WRITE),
            (L::TRANSFER_SRC_OPTIMAL, A::TRANSFER_READ),
        ),
        image_barrier(
            image,
            COLOR_RANGE,
            (L::UNDEFINED, A::empty()),
            (L::TRANSFER_DST_OPTIMAL, A::TRANSFER_WRITE),
        ),
    ];
    let write = (L::TRANSFER_DST_OPTIMAL, A::TRANSFER_WRITE);
    // SAFETY: the caller guarantees the command buffer and the images; the
    // barriers above put both images in the layouts the clear and the copy name.
    unsafe {
        cmd_image_barriers(
            device,
            cmd,
            S::COLOR_ATTACHMENT_OUTPUT | S::TRANSFER,
            S::TRANSFER,
            &to_copy,
        );
        if !covers {
            // An odd window width leaves a column no eye covers.
            device.cmd_clear_color_image(
                cmd,
                image,
                L::TRANSFER_DST_OPTIMAL,
                &vk::ClearColorValue {
                    float32: [0.0, 0.0, 0.0, 1.0],
                },
                &[COLOR_RANGE],
            );
            let after_clear = [image_barrier(image, COLOR_RANGE, write, write)];
            cmd_image_barriers(device, cmd, S::TRANSFER, S::TRANSFER, &after_clear);
        }
        device.cmd_copy_image(
            cmd,
            eye.raw,
            L::TRANSFER_SRC_OPTIMAL,
            image,
            L::TRANSFER_DST_OPTIMAL,
            regions,
        );
    }
    if overlay_area.is_none() {
        let to_present = [image_barrier(
            image,
            COLOR_RANGE,
            write,
            (L::PRESENT_SRC_KHR, A::empty()),
        )];
        // SAFETY: as above; the copy left the image in TRANSFER_DST_OPTIMAL.
        unsafe { cmd_image_barriers(device, cmd, S::TRANSFER, S::BOTTOM_OF_PIPE, &to_present) };
    }
    overlay_area
}

/// The composite path: the eye image made readable by the fragment shader.
///
/// # Safety
///
/// `cmd` is recording, outside a render pass; `eye` is live and in
/// COLOR_ATTACHMENT_OPTIMAL after the renderer's pass.
unsafe fn record_to_sampled(device: &ash::Device, cmd: vk::CommandBuffer, eye: &Image) {
    use vk::{AccessFlags as A, ImageLayout as L, PipelineStageFlags as S};
    let to_sampled = [image_barrier(
        eye.raw,
        eye.range(),
        (L::COLOR_ATTACHMENT_OPTIMAL, A::COLOR_ATTACHMENT_WRITE),
        (L::SHADER_READ_ONLY_OPTIMAL, A::SHADER_READ),
    )];
    // SAFETY: the caller guarantees the command buffer, the image and its layout.
    unsafe {
        cmd_image_barriers(
            device,
            cmd,
            S::COLOR_ATTACHMENT_OUTPUT,
            S::FRAGMENT_SHADER,
            &to_sampled,
        )
    };
}

/// Copies the presented swapchain image into `buffer` (and back to
/// PRESENT_SRC), for `--dump-last-frame`.
///
/// # Safety
///
/// `cmd` is recording, outside a render pass; `image` is live and in
/// PRESENT_SRC_KHR (left there by the composite or overlay pass); `buffer`
/// holds `extent` texels of 4 bytes.
unsafe fn record_dump_copy(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    buffer: &Buffer,
    extent: vk::Extent2D,
) {
    use vk::{AccessFlags as A, ImageLayout as L, PipelineStageFlags as S};
    let to_src = [image_barrier(
        image,
        COLOR_RANGE,
        (L::PRESENT_SRC_KHR, A::COLOR_ATTACHMENT_WRITE),
        (L::TRANSFER_SRC_OPTIMAL, A::TRANSFER_READ),
    )];
    let back = [image_barrier(
        image,
        COLOR_RANGE,
        (L::TRANSFER_SRC_OPTIMAL, A::TRANSFER_READ),
        (L::PRESENT_SRC_KHR, A::empty()),
    )];
    let region = [vk::BufferImageCopy::default()
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        })
        .image_extent(vk::Extent3D {
            width: extent.width,
            height: extent.height,
            depth: 1,
        })];
    // SAFETY: the caller guarantees the command buffer, the image's layout and
    // the buffer's size; the first barrier puts the image in the copy's layout.
    unsafe {
        cmd_image_barriers(
            device,
            cmd,
            S::COLOR_ATTACHMENT_OUTPUT,
            S::TRANSFER,
            &to_src,
        );
        device.cmd_copy_image_to_buffer(cmd, image, L::TRANSFER_SRC_OPTIMAL, buffer.raw, &region);
        cmd_image_barriers(device, cmd, S::TRANSFER, S::BOTTOM_OF_PIPE, &back);
    }
}

const COLOR_RANGE: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};

/// The copies that place the eye layers in the window for `layout` (None:
/// the layout needs the composite shader), and whether they cover the whole
/// window.
fn copy_regions(
    layout: Layout,
    eye: (u32, u32),
    window: (u32, u32),
) -> Option<(Vec<vk::ImageCopy>, bool)> {
    let region = |layer: u32, x: u32| {
        let sub = |layer| vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: layer,
            layer_count: 1,
        };
        vk::ImageCopy::default()
            .src_subresource(sub(layer))
            .dst_subresource(sub(0))
            .dst_offset(vk::Offset3D {
                x: x as i32,
                y: 0,
                z: 0,
            })
            .extent(vk::Extent3D {
                width: eye.0.min(window.0.saturating_sub(x)),
                height: eye.1.min(window.1),
                depth: 1,
            })
    };
    let (regions, covered) = match layout {
        Layout::SideBySide => (vec![region(0, 0), region(1, eye.0)], (2 * eye.0, eye.1)),
        Layout::Single { layer } => (vec![region(layer, 0)], eye),
        Layout::Anaglyph => return None,
    };
    if regions
        .iter()
        .any(|r| r.extent.width == 0 || r.extent.height == 0)
    {
        return None;
    }
    let covers = covered.0 >= window.0 && covered.1 >= window.1;
    Some((regions, covers))
}

/// The overlay's text block clipped to the window (None when empty).
fn overlay_rect(overlay: &Overlay, extent: vk::Extent2D) -> Option<vk::Rect2D> {
    let (w, h) = overlay.grid.size(overlay.scale.max(1));
    let x0 = overlay.origin.0.max(0) as u32;
    let y0 = overlay.origin.1.max(0) as u32;
    let x1 = (x0 + w).min(extent.width);
    let y1 = (y0 + h).min(extent.height);
    (x1 > x0 && y1 > y0).then(|| vk::Rect2D {
        offset: vk::Offset2D {
            x: x0 as i32,
            y: y0 as i32,
        },
        extent: vk::Extent2D {
            width: x1 - x0,
            height: y1 - y0,
        },
    })
}

/// Push constants of `composite.frag`, 40 bytes.
const PUSH_SIZE: u32 = 40;

fn push_bytes(
    eye_size: (u32, u32),
    mode: u32,
    layer: u32,
    encode_srgb: bool,
    overlay: &Overlay,
) -> [u8; PUSH_SIZE as usize] {
    let words: [u32; 10] = [
        eye_size.0,
        eye_size.1,
        mode,
        u32::from(encode_srgb),
        overlay.origin.0 as u32,
        overlay.origin.1 as u32,
        overlay.grid.cols,
        overlay.grid.rows,
        overlay.scale.max(1),
        layer,
    ];
    let mut out = [0u8; PUSH_SIZE as usize];
    for (i, w) in words.iter().enumerate() {
        out[4 * i..4 * i + 4].copy_from_slice(&w.to_le_bytes());
    }
    out
}

impl Drop for Presenter {
    fn drop(&mut self) {
        self.wait_idle();
        self.destroy_chain(false);
        let device = &self.shared.device;
        // SAFETY: the device is idle; every handle below was made from it (null
        // handles are ignored); the surface goes before the instance, which the
        // Arc keeps alive until after this, and before the window (dropped
        // after this body).
        unsafe {
            for slot in self.slots.drain(..) {
                device.destroy_fence(slot.fence, None);
                device.destroy_semaphore(slot.acquired, None);
                device.free_command_buffers(self.command_pool, &[slot.command_buffer]);
            }
            self.eyes.clear();
            device.destroy_descriptor_pool(self.descriptor_pool, None);
            device.destroy_pipeline(self.pipeline, None);
            device.destroy_pipeline_layout(self.pipeline_layout, None);
            device.destroy_descriptor_set_layout(self.set_layout, None);
            device.destroy_render_pass(self.render_pass, None);
            device.destroy_pipeline(self.overlay_pipeline, None);
            device.destroy_render_pass(self.overlay_pass, None);
            device.destroy_sampler(self.sampler, None);
            self.surface_loader.destroy_surface(self.surface, None);
        }
    }
}
