//! The composite: the render passes and pipelines on the swapchain image, and
//! the recording of a frame: the eye layers copied into the window (or drawn by
//! the full-screen composite shader for anaglyph and other formats), the text
//! overlay over them, and the dump's copy.

use super::dump::record_dump_copy;
use super::swapchain::COLOR_RANGE;
use super::{Frame, Layout, Overlay, Presenter};
use crate::gpu::barrier::{cmd_image_barriers, image_barrier};
use crate::gpu::pipeline::{pipeline_layout, set_layout, GraphicsPipeline, ShaderModules};
use crate::gpu::{shaders, Buffer, Gpu, GpuError, Image, VkContext};
use anyhow::{Context, Result};
use ash::vk;

impl Presenter {
    /// A render pass on the swapchain image: the full composite (its contents
    /// discarded first) or the overlay over copied eye images (loaded from the
    /// copy's TRANSFER_DST layout). The two are compatible (one attachment of
    /// one format), so the framebuffers serve both.
    pub(super) fn create_render_pass(
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

    pub(super) fn create_pipeline(&mut self, gpu: &Gpu) -> Result<(), GpuError> {
        let device = gpu.device();
        self.render_pass = self.create_render_pass(device, false)?;
        self.overlay_pass = self.create_render_pass(device, true)?;
        // Every handle is stored in self at once, so Drop destroys it if a
        // later step fails.
        self.set_layout = set_layout(
            gpu,
            &[
                (
                    vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                    vk::ShaderStageFlags::FRAGMENT,
                ),
                (
                    vk::DescriptorType::STORAGE_BUFFER,
                    vk::ShaderStageFlags::FRAGMENT,
                ),
            ],
        )?;
        self.pipeline_layout = pipeline_layout(
            gpu,
            &[self.set_layout],
            vk::ShaderStageFlags::FRAGMENT,
            PUSH_SIZE,
        )?;
        let sampler_info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::NEAREST)
            .min_filter(vk::Filter::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE);
        // SAFETY: a plain create info.
        self.sampler =
            unsafe { device.create_sampler(&sampler_info, None) }.ctx("vkCreateSampler")?;
        let mut modules = ShaderModules::new(gpu);
        let vert = modules.load(gpu, shaders::TONEMAP_VERT)?;
        let composite = modules.load(gpu, shaders::COMPOSITE_FRAG)?;
        let overlay = modules.load(gpu, shaders::OVERLAY_FRAG)?;
        self.pipeline =
            GraphicsPipeline::new(self.render_pass, 0, self.pipeline_layout, vert, composite)
                .build(gpu)?;
        // The overlay over copied eye images: text opaque, the block's
        // background darkening what is below (alpha = 1 - TEXT_BACKGROUND);
        // blending on an sRGB attachment happens on linear values.
        let over = vk::PipelineColorBlendAttachmentState::default()
            .blend_enable(true)
            .src_color_blend_factor(vk::BlendFactor::SRC_ALPHA)
            .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .color_blend_op(vk::BlendOp::ADD)
            .src_alpha_blend_factor(vk::BlendFactor::ONE)
            .dst_alpha_blend_factor(vk::BlendFactor::ZERO)
            .alpha_blend_op(vk::BlendOp::ADD)
            .color_write_mask(vk::ColorComponentFlags::RGBA);
        self.overlay_pipeline = GraphicsPipeline {
            blend: over,
            ..GraphicsPipeline::new(self.overlay_pass, 0, self.pipeline_layout, vert, overlay)
        }
        .build(gpu)?;
        Ok(())
    }

    /// Records the slot's command buffer: the eye image copied (or composited)
    /// into the swapchain image, the overlay over it, and the copy to `dump`.
    pub(super) fn record_frame(
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
    pub(super) unsafe fn record_composite(
        &self,
        cmd: vk::CommandBuffer,
        pass: &Composite,
        push: &[u8],
    ) {
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
}

/// One full-screen draw of the composite or overlay pipeline.
pub(super) struct Composite {
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
pub(super) unsafe fn begin_commands(
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
pub(super) unsafe fn record_copy(
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
pub(super) unsafe fn record_to_sampled(device: &ash::Device, cmd: vk::CommandBuffer, eye: &Image) {
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

/// The copies that place the eye layers in the window for `layout` (None:
/// the layout needs the composite shader), and whether they cover the whole
/// window.
pub(super) fn copy_regions(
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
pub(super) fn overlay_rect(overlay: &Overlay, extent: vk::Extent2D) -> Option<vk::Rect2D> {
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
pub(super) const PUSH_SIZE: u32 = 40;

pub(super) fn push_bytes(
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
