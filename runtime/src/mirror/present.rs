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
//!
//! By job: `swapchain` (the chain, acquire, submit and present), `composite`
//! (render passes, pipelines and a frame's recording) and `dump` (the
//! window image read back for `--dump-last-frame`); this module holds the
//! presenter, its frame slots and the eye images.

use crate::gpu::{Buffer, BufferDesc, Gpu, GpuError, Image, ImageDesc, MemoryLocation, VkContext};
use crate::render::SwapchainDesc;
use anyhow::{bail, Context, Result};
use ash::vk;
use std::sync::Arc;
use winit::window::Window;

use super::font::{self, TextGrid};

mod composite;
mod dump;
mod swapchain;

pub use dump::Dump;
use swapchain::Chain;

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
