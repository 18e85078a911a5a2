//! The window's swapchain: made at the window's size on the first frame and
//! remade on resize (with its image views, framebuffers and per-image
//! semaphores), the acquire that begins a frame, and the submit and
//! presentation that end it.

use super::{Frame, Presenter};
use crate::gpu::{GpuError, VkContext};
use anyhow::{Context, Result};
use ash::vk;

/// Swapchain-sized state, rebuilt on resize.
pub(super) struct Chain {
    pub(super) swapchain: vk::SwapchainKHR,
    pub(super) extent: vk::Extent2D,
    pub(super) views: Vec<vk::ImageView>,
    pub(super) framebuffers: Vec<vk::Framebuffer>,
    pub(super) images: Vec<vk::Image>,
    /// Signalled by the composite of image i, waited for by its presentation.
    pub(super) rendered: Vec<vk::Semaphore>,
}

pub(super) const COLOR_RANGE: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};

impl Presenter {
    pub(super) fn destroy_chain(&mut self, keep_swapchain: bool) -> vk::SwapchainKHR {
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
    pub(super) fn rebuild(&mut self) -> Result<bool> {
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

    /// Submits the slot's recorded command buffer (waiting for the acquire,
    /// signalling the image's semaphore and the slot's fence) and presents the
    /// image; an out-of-date or suboptimal swapchain is rebuilt next frame.
    pub(super) fn submit_and_present(&mut self, frame: Frame) -> Result<()> {
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
}
