//! The stereo renderer: draws a solution for one or two views into an sRGB
//! output image (a swapchain image) with exposure and tone mapping, keeping the
//! linear radiance in a half-float image that screenshots read back as EXR.
//!
//! Per frame ([`StereoRenderer::render`]): wait for the previous frame's fence,
//! write the views' view-projection matrices and eye positions into the uniform
//! buffer, then one multiview render pass draws both eyes (view mask 0b11) —
//! or, where the driver has the multiview clipping bug (`multiview`), one pass
//! per view (masks 0b01 then 0b10) with the same shaders. Batches are drawn by
//! increasing SH order: order 0 with the trivial `scene_l0.vert`, the rest with
//! `scene_sh.vert` whose loop bound is the batch's order (push constant); then
//! the global-cube batches (Immel, Cohen & Greenberg 1986, "The global cube")
//! with `scene_cube.vert` (four cells per channel, the resolution k in the same
//! push constant).
//!
//! Conventions: positions are in file (re-centred) coordinates; views are
//! `solution::camera::EyeView`s, projected with `EyeView::view_projection` and the
//! clip planes of `solution::camera::clip_planes_for`, exactly as the CPU
//! reference rasterizer does.

pub mod cull;
pub mod inspect;
pub mod multiview;
mod passes;
mod readback;
mod record;
pub mod scene;
pub mod sky;
pub mod textures;
pub mod tonemap;
pub mod truncation;

pub use cull::{CullStats, Culling};
pub use inspect::{Edges, Inspect};
pub use multiview::MultiviewMode;
pub use readback::EyeImage;
pub use scene::{CoefficientStorage, DrawKind, GpuScene, SceneError, UploadStats};
pub use tonemap::{file_tone, ToneCurve, ToneSettings};

use crate::gpu::{
    Buffer, BufferDesc, Fence, Gpu, GpuError, Image, ImageDesc, MemoryLocation, VkContext,
};
use ash::vk;
use glam::DVec3;
use passes::{Layouts, PassDesc, PassSet};
use solution::camera::{clip_planes_for, EyeView};
use solution::format::{Header, MappedSolution, Solution};
use std::sync::Arc;

/// Options of the renderer.
#[derive(Clone, Debug)]
pub struct RendererDesc {
    /// Image size per eye.
    pub width: u32,
    pub height: u32,
    /// The most samples per pixel to use; the device's limit lowers it, and 1
    /// turns MSAA off.
    pub max_samples: u32,
    pub multiview: MultiviewMode,
    /// Cap on the evaluated SH order (`--max-order`).
    pub max_order: Option<u32>,
    pub tone: ToneSettings,
    /// Chunk size and per-chunk frustum culling ([`cull`]).
    pub culling: Culling,
}

impl Default for RendererDesc {
    fn default() -> Self {
        RendererDesc {
            width: 512,
            height: 512,
            max_samples: 4,
            multiview: MultiviewMode::Auto,
            max_order: None,
            tone: ToneSettings::default(),
            culling: Culling::default(),
        }
    }
}

/// The images a renderer draws into: one per swapchain image, each with one
/// array layer per view (layer 0 = left, 1 = right).
#[derive(Clone, Debug)]
pub struct SwapchainDesc {
    pub images: Vec<vk::Image>,
    /// An sRGB format (the tone map writes display values and relies on the
    /// attachment's sRGB encoding).
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    pub layers: u32,
}

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error("{0}")]
    Usage(String),
}

#[derive(Clone, Debug, Default)]
struct PassRanges {
    view_mask: u32,
    /// `(first triangle, count)` per draw, counted from the draw's first index.
    ranges: Vec<(u32, u32)>,
    /// Which of `ranges` belong to each of the scene's draws.
    per_draw: Vec<std::ops::Range<usize>>,
}

/// Per-swapchain-image state: the output view and one framebuffer per pass set.
struct Target {
    framebuffers: Vec<vk::Framebuffer>,
    output: Image,
}

/// The stereo renderer. Fields are declared newest-first; `Drop` waits for the
/// device before they are destroyed.
pub struct StereoRenderer {
    /// The environment behind the geometry (format x.1 files with one).
    sky: Option<sky::SkyGpu>,
    /// Made on the first [`StereoRenderer::set_inspect`] that draws lines.
    inspect_gpu: Option<inspect::InspectGpu>,
    inspect: Inspect,
    targets: Vec<Target>,
    tonemap_set: vk::DescriptorSet,
    batch_sets: Vec<vk::DescriptorSet>,
    /// Per draw, the textured batches' second set (UV + E/π, texture).
    texture_sets: Vec<Option<vk::DescriptorSet>>,
    descriptor_pool: vk::DescriptorPool,
    command_buffer: vk::CommandBuffer,
    fence: Fence,
    uniforms: Buffer,
    msaa: Option<Image>,
    linear: Image,
    depth: Image,
    /// One per pass of a stereo frame, then (if not among them) the mono pass.
    pass_sets: Vec<PassSet>,
    layouts: Layouts,
    scene: GpuScene,
    desc: RendererDesc,
    samples: vk::SampleCountFlags,
    path: multiview::MultiviewPath,
    bounds: (DVec3, DVec3),
    swapchain: SwapchainDesc,
    gpu_shared: Arc<crate::gpu::DeviceShared>,
    queue: vk::Queue,
    command_pool: vk::CommandPool,
    /// How long the scene upload took in [`StereoRenderer::new`] (`--timings`).
    upload_time: std::time::Duration,
    /// When the first frame's commands were submitted (`--timings`).
    first_submit: Option<std::time::Instant>,
    /// Bytes and submits of a mapped upload (zero for in-memory solutions).
    upload_stats: UploadStats,
    /// The frusta of the views of the frame being drawn (layer 0, layer 1).
    frusta: [cull::Frustum; 2],
    /// What each pass of the frame being drawn draws.
    pass_ranges: Vec<PassRanges>,
    /// What culling kept in the last frame.
    cull_stats: CullStats,
}

const UNIFORM_SIZE: u64 = 2 * 64 + 2 * 16;

fn check_swapchain(desc: &RendererDesc, swapchain: &SwapchainDesc) -> Result<(), RenderError> {
    if swapchain.width != desc.width || swapchain.height != desc.height {
        return Err(RenderError::Usage(format!(
            "swapchain images are {}x{} but the renderer was asked for {}x{}",
            swapchain.width, swapchain.height, desc.width, desc.height
        )));
    }
    if swapchain.layers < 2 || swapchain.images.is_empty() {
        return Err(RenderError::Usage(
            "the swapchain needs at least one image with two layers".into(),
        ));
    }
    Ok(())
}

fn sample_count(gpu: &Gpu, max: u32) -> vk::SampleCountFlags {
    let limits = &gpu.info.limits;
    let supported = limits.framebuffer_color_sample_counts & limits.framebuffer_depth_sample_counts;
    for (n, flag) in [
        (8, vk::SampleCountFlags::TYPE_8),
        (4, vk::SampleCountFlags::TYPE_4),
        (2, vk::SampleCountFlags::TYPE_2),
    ] {
        if n <= max && supported.contains(flag) {
            return flag;
        }
    }
    vk::SampleCountFlags::TYPE_1
}

fn depth_format(gpu: &Gpu) -> Result<vk::Format, GpuError> {
    for format in [
        vk::Format::D32_SFLOAT,
        vk::Format::X8_D24_UNORM_PACK32,
        vk::Format::D16_UNORM,
    ] {
        // SAFETY: plain query of a physical device of this instance.
        let props = unsafe {
            gpu.instance()
                .get_physical_device_format_properties(gpu.physical, format)
        };
        if props
            .optimal_tiling_features
            .contains(vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT)
        {
            return Ok(format);
        }
    }
    Err(GpuError::Unsupported("no depth format".into()))
}

fn header_bounds(header: &Header) -> (DVec3, DVec3) {
    (
        DVec3::from(header.bounds_min.map(f64::from)),
        DVec3::from(header.bounds_max.map(f64::from)),
    )
}

/// The pass sets of a renderer drawing coefficients stored as `storage`: one
/// per pass of a stereo frame, then (if not among them) the mono pass.
fn pass_sets(
    gpu: &Gpu,
    layouts: &Layouts,
    path: multiview::MultiviewPath,
    template: PassDesc,
) -> Result<Vec<PassSet>, GpuError> {
    let mut masks: Vec<u32> = path.stereo_masks().to_vec();
    if !masks.contains(&0b01) {
        masks.push(0b01);
    }
    masks
        .into_iter()
        .map(|view_mask| {
            PassSet::new(
                gpu,
                layouts,
                PassDesc {
                    view_mask,
                    ..template
                },
            )
        })
        .collect()
}

impl StereoRenderer {
    /// Uploads an in-memory `solution` (coefficients stored as its batches'
    /// scalar types say) and prepares to draw into `swapchain`'s images.
    pub fn new(
        gpu: &Gpu,
        solution: &Solution,
        desc: RendererDesc,
        swapchain: &SwapchainDesc,
    ) -> Result<StereoRenderer, RenderError> {
        check_swapchain(&desc, swapchain)?;
        let upload_start = std::time::Instant::now();
        let scene = GpuScene::new(gpu, solution, desc.max_order, desc.culling.chunk_triangles)?;
        let upload_time = upload_start.elapsed();
        let mut renderer = Self::from_scene(gpu, scene, &solution.header, desc, swapchain)?;
        renderer.upload_time = upload_time;
        let env = solution
            .lighting
            .as_ref()
            .and_then(|l| l.environment.as_ref());
        renderer.set_environment(gpu, env, solution.header.up_axis)?;
        Ok(renderer)
    }

    /// Uploads a mapped solution file as stored ([`GpuScene::from_mapped`]: in
    /// bounded chunks, each section's checksum verified on the way) and prepares
    /// to draw into `swapchain`'s images.
    pub fn from_mapped(
        gpu: &Gpu,
        file: &MappedSolution,
        desc: RendererDesc,
        swapchain: &SwapchainDesc,
    ) -> Result<StereoRenderer, RenderError> {
        check_swapchain(&desc, swapchain)?;
        let upload_start = std::time::Instant::now();
        let (scene, stats) = GpuScene::from_mapped_with(
            gpu,
            file,
            desc.max_order,
            desc.culling.chunk_triangles,
            scene::STAGING_BYTES,
        )?;
        let upload_time = upload_start.elapsed();
        let mut renderer = Self::from_scene(gpu, scene, file.header(), desc, swapchain)?;
        renderer.upload_time = upload_time;
        renderer.upload_stats = stats;
        let env = file.lighting().and_then(|l| l.environment.as_ref());
        renderer.set_environment(gpu, env, file.header().up_axis)?;
        Ok(renderer)
    }

    /// Bytes and staging submits of the upload ([`StereoRenderer::from_mapped`]).
    pub fn upload_stats(&self) -> UploadStats {
        self.upload_stats
    }

    /// Prepares to draw an uploaded `scene` (whose file's header is `header`)
    /// into `swapchain`'s images.
    pub fn from_scene(
        gpu: &Gpu,
        scene: GpuScene,
        header: &Header,
        desc: RendererDesc,
        swapchain: &SwapchainDesc,
    ) -> Result<StereoRenderer, RenderError> {
        check_swapchain(&desc, swapchain)?;
        let bounds = header_bounds(header);
        let path = multiview::resolve(gpu, desc.multiview);
        let samples = sample_count(gpu, desc.max_samples);
        let depth_format = depth_format(gpu)?;
        let layouts = Layouts::new(gpu)?;
        let pass_sets = pass_sets(
            gpu,
            &layouts,
            path,
            PassDesc {
                view_mask: 0b01,
                samples,
                depth_format,
                output_format: swapchain.format,
                storage: scene.storage,
                textured: scene.is_textured(),
            },
        )?;
        let (depth, linear, msaa) =
            frame_images(gpu, desc.width, desc.height, samples, depth_format)?;
        let uniforms = Buffer::new(
            gpu,
            BufferDesc {
                size: UNIFORM_SIZE,
                usage: vk::BufferUsageFlags::UNIFORM_BUFFER,
                location: MemoryLocation::Mapped,
            },
        )?;
        let fence = Fence::new(gpu, true)?;
        let device = gpu.device();
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(gpu.command_pool())
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool belongs to this device; freed in Drop.
        let command_buffer =
            unsafe { device.allocate_command_buffers(&alloc) }.ctx("vkAllocateCommandBuffers")?[0];

        let mut renderer = StereoRenderer {
            sky: None,
            inspect_gpu: None,
            inspect: Inspect::default(),
            targets: Vec::new(),
            tonemap_set: vk::DescriptorSet::null(),
            batch_sets: Vec::new(),
            texture_sets: Vec::new(),
            descriptor_pool: vk::DescriptorPool::null(),
            command_buffer,
            fence,
            uniforms,
            msaa,
            linear,
            depth,
            pass_sets,
            layouts,
            scene,
            desc,
            samples,
            path,
            bounds,
            swapchain: swapchain.clone(),
            gpu_shared: gpu.shared.clone(),
            queue: gpu.queue,
            command_pool: gpu.command_pool(),
            upload_time: std::time::Duration::ZERO,
            first_submit: None,
            upload_stats: UploadStats::default(),
            frusta: [cull::Frustum::from_view_projection(glam::DMat4::IDENTITY); 2],
            pass_ranges: Vec::new(),
            cull_stats: CullStats::default(),
        };
        renderer.create_descriptors()?;
        for &raw in &swapchain.images {
            renderer.add_target(gpu, raw)?;
        }
        Ok(renderer)
    }

    /// Draws into `swapchain`'s images from now on, at their size (a resized
    /// window): the size-dependent images and framebuffers are remade, the
    /// scene and pipelines kept (viewport and scissor are dynamic).
    pub fn resize(&mut self, gpu: &Gpu, swapchain: &SwapchainDesc) -> Result<(), RenderError> {
        if swapchain.layers < 2 || swapchain.images.is_empty() {
            return Err(RenderError::Usage(
                "the swapchain needs at least one image with two layers".into(),
            ));
        }
        if swapchain.format != self.swapchain.format {
            return Err(RenderError::Usage(format!(
                "resize cannot change the output format ({:?} to {:?})",
                self.swapchain.format, swapchain.format
            )));
        }
        let depth_format = self
            .pass_sets
            .first()
            .map(|s| s.desc.depth_format)
            .ok_or_else(|| RenderError::Usage("renderer without passes".into()))?;
        let (depth, linear, msaa) = frame_images(
            gpu,
            swapchain.width,
            swapchain.height,
            self.samples,
            depth_format,
        )?;
        self.wait_idle();
        for target in std::mem::take(&mut self.targets) {
            self.destroy_target(target);
        }
        self.depth = depth;
        self.linear = linear;
        self.msaa = msaa;
        self.desc.width = swapchain.width;
        self.desc.height = swapchain.height;
        self.swapchain = swapchain.clone();
        let image_info = [vk::DescriptorImageInfo::default()
            .image_view(self.linear.view)
            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
        let write = [vk::WriteDescriptorSet::default()
            .dst_set(self.tonemap_set)
            .dst_binding(0)
            .descriptor_type(vk::DescriptorType::INPUT_ATTACHMENT)
            .image_info(&image_info)];
        // SAFETY: the device is idle, so the set is not in use; the view is live.
        unsafe { self.gpu_shared.device.update_descriptor_sets(&write, &[]) };
        for &raw in &swapchain.images {
            self.add_target(gpu, raw)?;
        }
        Ok(())
    }

    /// Replaces the drawn solution with a reloaded, mapped `file` (uploaded as
    /// [`StereoRenderer::from_mapped`] does), keeping the images and, unless its
    /// storage type differs, the pipelines. On error the previous solution
    /// stays.
    pub fn set_mapped(&mut self, gpu: &Gpu, file: &MappedSolution) -> Result<(), RenderError> {
        let upload_start = std::time::Instant::now();
        let (scene, stats) = GpuScene::from_mapped_with(
            gpu,
            file,
            self.desc.max_order,
            self.desc.culling.chunk_triangles,
            scene::STAGING_BYTES,
        )?;
        let upload_time = upload_start.elapsed();
        let bounds = header_bounds(file.header());
        // A file of the other storage type needs the other shaders, and a
        // textured one the textured pipeline.
        let new_passes = match self.pass_sets.first() {
            Some(first)
                if first.desc.storage != scene.storage
                    || first.desc.textured != scene.is_textured() =>
            {
                Some(pass_sets(
                    gpu,
                    &self.layouts,
                    self.path,
                    PassDesc {
                        storage: scene.storage,
                        textured: scene.is_textured(),
                        ..first.desc
                    },
                )?)
            }
            _ => None,
        };
        let inspect_gpu = if self.inspect.draws_lines() {
            let diagonal = (bounds.1 - bounds.0).length() as f32;
            Some(inspect::InspectGpu::new(
                gpu,
                file,
                &scene.draws,
                &self.layouts,
                new_passes.as_ref().unwrap_or(&self.pass_sets),
                diagonal,
            )?)
        } else {
            None
        };
        self.wait_idle();
        if let Some(passes) = new_passes {
            // The framebuffers belong to the old passes' render passes: remade
            // for the new ones, as on a resize.
            for target in std::mem::take(&mut self.targets) {
                self.destroy_target(target);
            }
            self.pass_sets = passes;
            for raw in self.swapchain.images.clone() {
                self.add_target(gpu, raw)?;
            }
        }
        // SAFETY: the device is idle; the pool's sets are used by no pending
        // command buffer, and new ones are made right after.
        unsafe {
            self.gpu_shared
                .device
                .destroy_descriptor_pool(self.descriptor_pool, None)
        };
        self.descriptor_pool = vk::DescriptorPool::null();
        self.batch_sets.clear();
        self.texture_sets.clear();
        self.scene = scene;
        self.bounds = bounds;
        self.inspect_gpu = inspect_gpu;
        self.upload_time = upload_time;
        self.upload_stats = stats;
        self.create_descriptors()?;
        // The new file's sky (or none), on the current pass sets.
        let env = file.lighting().and_then(|l| l.environment.as_ref());
        self.set_environment(gpu, env, file.header().up_axis)?;
        Ok(())
    }

    fn wait_idle(&self) {
        // SAFETY: waiting has no preconditions.
        unsafe {
            let _ = self.fence.wait();
            let _ = self.gpu_shared.device.queue_wait_idle(self.queue);
        }
    }

    fn create_descriptors(&mut self) -> Result<(), GpuError> {
        let device = &self.gpu_shared.device;
        let batches = self.scene.draws.len() as u32;
        // Textured batches have a second set: a storage buffer and a sampler.
        let textured = self
            .scene
            .draws
            .iter()
            .filter(|d| d.texture.is_some())
            .count() as u32;
        let sizes = [
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::UNIFORM_BUFFER)
                .descriptor_count(batches.max(1)),
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count((batches + textured).max(1)),
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .descriptor_count((2 * textured).max(1)),
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::INPUT_ATTACHMENT)
                .descriptor_count(1),
        ];
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(batches + 1 + textured)
            .pool_sizes(&sizes);
        // SAFETY: valid device and create info; destroyed in Drop.
        self.descriptor_pool =
            unsafe { device.create_descriptor_pool(&info, None) }.ctx("vkCreateDescriptorPool")?;
        let mut layouts = vec![self.layouts.scene_set; batches as usize];
        layouts.push(self.layouts.tonemap_set);
        layouts.extend(std::iter::repeat_n(
            self.layouts.textured_set,
            textured as usize,
        ));
        let alloc = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.descriptor_pool)
            .set_layouts(&layouts);
        // SAFETY: the pool was sized for exactly these sets.
        let mut sets =
            unsafe { device.allocate_descriptor_sets(&alloc) }.ctx("vkAllocateDescriptorSets")?;
        let mut textured_sets = sets.split_off(batches as usize + 1).into_iter();
        self.tonemap_set = sets.pop().unwrap_or_default();
        self.batch_sets = sets;
        self.texture_sets = self
            .scene
            .draws
            .iter()
            .map(|d| d.texture.and_then(|_| textured_sets.next()))
            .collect();
        let uniform_info = [vk::DescriptorBufferInfo::default()
            .buffer(self.uniforms.raw)
            .range(UNIFORM_SIZE)];
        let storage_infos: Vec<[vk::DescriptorBufferInfo; 1]> = self
            .scene
            .draws
            .iter()
            .map(|d| {
                [vk::DescriptorBufferInfo::default()
                    .buffer(self.scene.coefficients.raw)
                    .offset(d.coeff_offset)
                    .range(d.coeff_bytes)]
            })
            .collect();
        let image_info = [vk::DescriptorImageInfo::default()
            .image_view(self.linear.view)
            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
        // Textured batches: their UV + E/π range, their texture and their
        // emission texture (the texture again when they have none: its
        // factor is then zero).
        type TexturedInfo = (
            [vk::DescriptorBufferInfo; 1],
            [vk::DescriptorImageInfo; 1],
            [vk::DescriptorImageInfo; 1],
        );
        let sampled = |view| {
            [vk::DescriptorImageInfo::default()
                .sampler(self.scene.textures.sampler)
                .image_view(view)
                .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)]
        };
        let textured_infos: Vec<Option<TexturedInfo>> = self
            .scene
            .draws
            .iter()
            .map(|d| {
                let t = d.texture.as_ref()?;
                let view = self.scene.textures.view(t.texture)?;
                let emission = match t.emission {
                    Some(e) => self.scene.textures.view(e.texture)?,
                    None => view,
                };
                Some((
                    [vk::DescriptorBufferInfo::default()
                        .buffer(self.scene.textured.raw)
                        .offset(t.offset)
                        .range(t.bytes)],
                    sampled(view),
                    sampled(emission),
                ))
            })
            .collect();
        let mut writes = Vec::new();
        for (set, textured) in self.texture_sets.iter().zip(&textured_infos) {
            if let (Some(set), Some((buffer, image, emission))) = (set, textured) {
                writes.push(
                    vk::WriteDescriptorSet::default()
                        .dst_set(*set)
                        .dst_binding(0)
                        .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                        .buffer_info(buffer),
                );
                writes.push(
                    vk::WriteDescriptorSet::default()
                        .dst_set(*set)
                        .dst_binding(1)
                        .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                        .image_info(image),
                );
                writes.push(
                    vk::WriteDescriptorSet::default()
                        .dst_set(*set)
                        .dst_binding(2)
                        .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                        .image_info(emission),
                );
            }
        }
        for (set, storage) in self.batch_sets.iter().zip(&storage_infos) {
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(*set)
                    .dst_binding(0)
                    .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                    .buffer_info(&uniform_info),
            );
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(*set)
                    .dst_binding(1)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(storage),
            );
        }
        writes.push(
            vk::WriteDescriptorSet::default()
                .dst_set(self.tonemap_set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::INPUT_ATTACHMENT)
                .image_info(&image_info),
        );
        // SAFETY: every write refers to live sets, buffers and views; no set is in
        // use by a pending command buffer yet.
        unsafe { device.update_descriptor_sets(&writes, &[]) };
        Ok(())
    }

    fn add_target(&mut self, gpu: &Gpu, raw: vk::Image) -> Result<(), GpuError> {
        let output = Image::borrowed(
            gpu,
            raw,
            ImageDesc {
                width: self.desc.width,
                height: self.desc.height,
                layers: 2,
                format: self.swapchain.format,
                samples: vk::SampleCountFlags::TYPE_1,
                usage: vk::ImageUsageFlags::COLOR_ATTACHMENT,
                aspect: vk::ImageAspectFlags::COLOR,
            },
        )?;
        let mut target = Target {
            framebuffers: Vec::new(),
            output,
        };
        for set in &self.pass_sets {
            let mut views = vec![self.depth.view, self.linear.view, target.output.view];
            if let Some(msaa) = &self.msaa {
                views.push(msaa.view);
            }
            let info = vk::FramebufferCreateInfo::default()
                .render_pass(set.render_pass)
                .attachments(&views)
                .width(self.desc.width)
                .height(self.desc.height)
                .layers(1);
            // SAFETY: views and render pass are live; with multiview the
            // framebuffer has one layer and the views carry the array layers.
            let fb = unsafe { gpu.device().create_framebuffer(&info, None) };
            match fb {
                Ok(fb) => target.framebuffers.push(fb),
                Err(result) => {
                    self.destroy_target(target);
                    return Err(GpuError::Vulkan {
                        call: "vkCreateFramebuffer",
                        result,
                    });
                }
            }
        }
        self.targets.push(target);
        Ok(())
    }

    fn destroy_target(&self, target: Target) {
        for fb in target.framebuffers {
            // SAFETY: callers ensured the GPU no longer uses the framebuffer.
            unsafe { self.gpu_shared.device.destroy_framebuffer(fb, None) };
        }
    }

    /// The multiview path in use (single pass or one pass per view).
    pub fn multiview_path(&self) -> multiview::MultiviewPath {
        self.path
    }

    /// Samples per pixel in use.
    pub fn samples(&self) -> u32 {
        self.samples.as_raw()
    }

    pub fn scene(&self) -> &GpuScene {
        &self.scene
    }

    pub fn desc(&self) -> &RendererDesc {
        &self.desc
    }

    /// Mesh inspection for the next frames (Remington 1992, app. D: `-w`, `-n`): element
    /// edges and vertex normals as lines. `file` must be the one this
    /// renderer was made from (its triangles give the edges); the line
    /// pipelines are made on the first call that needs them.
    pub fn set_inspect(
        &mut self,
        gpu: &Gpu,
        file: &MappedSolution,
        mode: Inspect,
    ) -> Result<(), RenderError> {
        if mode.draws_lines() && self.inspect_gpu.is_none() {
            let diagonal = (self.bounds.1 - self.bounds.0).length() as f32;
            self.inspect_gpu = Some(inspect::InspectGpu::new(
                gpu,
                file,
                &self.scene.draws,
                &self.layouts,
                &self.pass_sets,
                diagonal,
            )?);
        }
        self.inspect = mode;
        Ok(())
    }

    /// The inspection mode in use.
    pub fn inspect(&self) -> Inspect {
        self.inspect
    }

    /// Changes exposure and curve for the next frames.
    pub fn set_tone(&mut self, tone: ToneSettings) {
        self.desc.tone = tone;
    }

    /// Near and far planes for an eye, shared with the CPU reference
    /// (`solution::camera::clip_planes_for` over the header's bounds).
    pub fn clip_planes(&self, view: &EyeView) -> (f64, f64) {
        clip_planes_for(view.position, self.bounds.0, self.bounds.1)
    }

    /// Draws `views` (one: mono into layer 0; two: left into layer 0, right into
    /// layer 1) into swapchain image `image`, submits, and waits until the GPU has
    /// finished (so the next call may rewrite the uniforms, and read-back may
    /// follow).
    pub fn render(&mut self, views: &[EyeView], image: usize) -> Result<(), RenderError> {
        if views.is_empty() || views.len() > 2 {
            return Err(RenderError::Usage(format!(
                "render takes one or two views, got {}",
                views.len()
            )));
        }
        if image >= self.targets.len() {
            return Err(RenderError::Usage(format!(
                "swapchain image {image} does not exist ({} images)",
                self.targets.len()
            )));
        }
        for v in views {
            if v.width != self.desc.width || v.height != self.desc.height {
                return Err(RenderError::Usage(format!(
                    "view is {}x{} but the renderer draws {}x{}",
                    v.width, v.height, self.desc.width, self.desc.height
                )));
            }
        }
        self.fence.wait()?;
        self.fence.reset()?;
        self.write_uniforms(views);
        if let Some(sky) = self.sky.as_mut() {
            // SAFETY: the frame fence was waited for above, so no submitted
            // work reads the sky's uniforms.
            unsafe { sky.write_views(views) };
        }
        self.cull(views.len());
        self.record(views.len(), image)?;
        let cmds = [self.command_buffer];
        let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
        // SAFETY: the command buffer was just recorded; the fence was reset and is
        // not in use by another submission.
        unsafe {
            self.gpu_shared
                .device
                .queue_submit(self.queue, &submit, self.fence.raw)
        }
        .ctx("vkQueueSubmit")?;
        self.first_submit
            .get_or_insert_with(std::time::Instant::now);
        self.fence.wait()?;
        Ok(())
    }

    /// How long [`StereoRenderer::new`] spent uploading the scene.
    pub fn upload_time(&self) -> std::time::Duration {
        self.upload_time
    }

    /// When [`StereoRenderer::render`] first submitted a frame.
    pub fn first_submit(&self) -> Option<std::time::Instant> {
        self.first_submit
    }

    /// What culling kept in the last frame drawn, summed over its passes.
    pub fn cull_stats(&self) -> CullStats {
        self.cull_stats
    }

    /// The view masks of a frame's passes: mono draws layer 0 alone.
    fn frame_masks(&self, view_count: usize) -> Vec<u32> {
        if view_count == 1 {
            vec![0b01]
        } else {
            self.path.stereo_masks().to_vec()
        }
    }

    /// Chooses, for each pass of the frame, the chunks of each draw that the
    /// pass's views may see ([`cull::visible_ranges`] against the frusta that
    /// `write_uniforms` set: one eye's on the per-view path, both eyes' for a
    /// multiview pass). The one culling path of every command: screenshot,
    /// bench, mirror and xr all draw through [`StereoRenderer::render`].
    fn cull(&mut self, view_count: usize) {
        let mut stats = CullStats::default();
        let mut passes = std::mem::take(&mut self.pass_ranges);
        passes.clear();
        for view_mask in self.frame_masks(view_count) {
            let frusta: Vec<cull::Frustum> = (0..2)
                .filter(|v| view_mask & (1 << v) != 0)
                .map(|v| self.frusta[v])
                .collect();
            let mut pass = PassRanges {
                view_mask,
                ..PassRanges::default()
            };
            for draw in &self.scene.draws {
                let start = pass.ranges.len();
                cull::visible_ranges(
                    &draw.chunks,
                    &frusta,
                    self.desc.culling.enabled,
                    &mut stats,
                    &mut pass.ranges,
                );
                pass.per_draw.push(start..pass.ranges.len());
            }
            passes.push(pass);
        }
        self.pass_ranges = passes;
        self.cull_stats = stats;
    }

    fn write_uniforms(&mut self, views: &[EyeView]) {
        let mut bytes = Vec::with_capacity(UNIFORM_SIZE as usize);
        let mut eyes = Vec::new();
        for i in 0..2 {
            // Mono: layer 1 is not drawn; repeat the view so the data is defined.
            let view = &views[i.min(views.len() - 1)];
            let (near, far) = self.clip_planes(view);
            let projection = view.view_projection(near, far);
            self.frusta[i] = cull::Frustum::from_view_projection(projection);
            let m = projection.as_mat4();
            for f in m.to_cols_array() {
                bytes.extend_from_slice(&f.to_le_bytes());
            }
            eyes.push(view.position.as_vec3());
        }
        for e in eyes {
            for f in [e.x, e.y, e.z, 1.0] {
                bytes.extend_from_slice(&f.to_le_bytes());
            }
        }
        // SAFETY: `render` waited for the frame fence before calling this, and
        // the uniform buffer is used only by this renderer's command buffer, so
        // no GPU work reads it now.
        unsafe { self.uniforms.write(0, &bytes) };
    }
}

/// Depth, resolved linear radiance and (with MSAA) the multisampled colour
/// target, two layers each.
fn frame_images(
    gpu: &Gpu,
    width: u32,
    height: u32,
    samples: vk::SampleCountFlags,
    depth_format: vk::Format,
) -> Result<(Image, Image, Option<Image>), GpuError> {
    let image = |format, samples, usage, aspect| {
        Image::new(
            gpu,
            ImageDesc {
                width,
                height,
                layers: 2,
                format,
                samples,
                usage,
                aspect,
            },
        )
    };
    let depth = image(
        depth_format,
        samples,
        vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        vk::ImageAspectFlags::DEPTH,
    )?;
    let linear = image(
        passes::LINEAR_FORMAT,
        vk::SampleCountFlags::TYPE_1,
        vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::INPUT_ATTACHMENT
            | vk::ImageUsageFlags::TRANSFER_SRC,
        vk::ImageAspectFlags::COLOR,
    )?;
    let msaa = if samples == vk::SampleCountFlags::TYPE_1 {
        None
    } else {
        Some(image(
            passes::LINEAR_FORMAT,
            samples,
            vk::ImageUsageFlags::COLOR_ATTACHMENT,
            vk::ImageAspectFlags::COLOR,
        )?)
    };
    Ok((depth, linear, msaa))
}

impl Drop for StereoRenderer {
    fn drop(&mut self) {
        let device = &self.gpu_shared.device;
        // SAFETY: wait for the queue, then destroy what this struct created
        // directly (framebuffers, pool, command buffer); the wrapper fields are
        // destroyed after this, newest first, in declaration order.
        unsafe {
            let _ = self.fence.wait();
            let _ = device.queue_wait_idle(self.queue);
            for target in &self.targets {
                for &fb in &target.framebuffers {
                    device.destroy_framebuffer(fb, None);
                }
            }
            device.destroy_descriptor_pool(self.descriptor_pool, None);
            device.free_command_buffers(self.command_pool, &[self.command_buffer]);
        }
    }
}
