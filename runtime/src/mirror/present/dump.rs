//! Frame dumps (`--dump-last-frame`): the presented window image copied into a
//! host-visible buffer and read back as RGBA.

use super::swapchain::COLOR_RANGE;
use super::Presenter;
use crate::gpu::barrier::{cmd_image_barriers, image_barrier};
use crate::gpu::{Buffer, BufferDesc, Gpu, MemoryLocation, VkContext};
use anyhow::{bail, Result};
use ash::vk;

/// The window's last image as shown, for `--dump-last-frame`.
#[derive(Clone, Debug)]
pub struct Dump {
    pub width: u32,
    pub height: u32,
    /// sRGB RGBA8, row 0 at the top.
    pub rgba: Vec<u8>,
}

impl Presenter {
    /// A host-visible buffer for one window image, after checking that the
    /// swapchain images can be copied and are 8-bit RGBA or BGRA.
    pub(super) fn dump_buffer(&self, gpu: &Gpu, extent: vk::Extent2D) -> Result<Buffer> {
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

    /// Waits for the slot's submission and returns the dumped window image as
    /// RGBA (swapping BGRA windows' channels).
    pub(super) fn read_dump(
        &self,
        slot: usize,
        buffer: &Buffer,
        extent: vk::Extent2D,
    ) -> Result<Dump> {
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

/// Copies the presented swapchain image into `buffer` (and back to
/// PRESENT_SRC), for `--dump-last-frame`.
///
/// # Safety
///
/// `cmd` is recording, outside a render pass; `image` is live and in
/// PRESENT_SRC_KHR (left there by the composite or overlay pass); `buffer`
/// holds `extent` texels of 4 bytes.
pub(super) unsafe fn record_dump_copy(
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
