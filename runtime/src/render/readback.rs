//! Reading a drawn frame back to the CPU: the sRGB output and the linear
//! radiance of each view, for screenshots, EXR dumps and the tests.

use super::passes;
use super::record::transition;
use super::{RenderError, StereoRenderer};
use crate::gpu::barrier::cmd_image_barriers;
use crate::gpu::{Buffer, BufferDesc, Gpu, MemoryLocation};
use ash::vk;

/// One eye's read-back images.
#[derive(Clone, Debug)]
pub struct EyeImage {
    pub width: u32,
    pub height: u32,
    /// Exposed, tone-mapped, sRGB-encoded RGBA8, row 0 at the top.
    pub srgb: Vec<u8>,
    /// Linear radiance RGB (W·sr⁻¹·m⁻²), row-major, row 0 at the top.
    pub radiance: Vec<f32>,
}

impl StereoRenderer {
    /// Reads back the last frame drawn into swapchain image `image`: `views`
    /// layers (1 or 2) of the sRGB output and of the linear radiance.
    pub fn read_back(
        &self,
        gpu: &Gpu,
        image: usize,
        views: usize,
    ) -> Result<Vec<EyeImage>, RenderError> {
        let target = self
            .targets
            .get(image)
            .ok_or_else(|| RenderError::Usage(format!("swapchain image {image} does not exist")))?;
        let views = views.clamp(1, 2) as u32;
        let (w, h) = (self.desc.width, self.desc.height);
        let pixels = u64::from(w) * u64::from(h);
        let srgb_bytes = pixels * 4;
        let linear_bytes = pixels * 8;
        let per_layer = srgb_bytes + linear_bytes;
        let buffer = Buffer::new(
            gpu,
            BufferDesc {
                size: per_layer * u64::from(views),
                usage: vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::Mapped,
            },
        )?;
        gpu.one_shot(|device, cmd| {
            let to_src = [
                transition(
                    &target.output,
                    passes::OUTPUT_LAYOUT,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                ),
                transition(
                    &self.linear,
                    passes::LINEAR_LAYOUT,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                ),
            ];
            let back = [
                transition(
                    &target.output,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    passes::OUTPUT_LAYOUT,
                ),
                transition(
                    &self.linear,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    passes::LINEAR_LAYOUT,
                ),
            ];
            let mut regions_out = Vec::new();
            let mut regions_lin = Vec::new();
            for layer in 0..views {
                let base = u64::from(layer) * per_layer;
                let region = |offset| {
                    vk::BufferImageCopy::default()
                        .buffer_offset(offset)
                        .image_subresource(vk::ImageSubresourceLayers {
                            aspect_mask: vk::ImageAspectFlags::COLOR,
                            mip_level: 0,
                            base_array_layer: layer,
                            layer_count: 1,
                        })
                        .image_extent(vk::Extent3D {
                            width: w,
                            height: h,
                            depth: 1,
                        })
                };
                regions_out.push(region(base));
                regions_lin.push(region(base + srgb_bytes));
            }
            // SAFETY: recording; images are live, the buffer holds every region,
            // and the frame's fence was waited for in `render`.
            unsafe {
                cmd_image_barriers(
                    device,
                    cmd,
                    vk::PipelineStageFlags::ALL_COMMANDS,
                    vk::PipelineStageFlags::TRANSFER,
                    &to_src,
                );
                device.cmd_copy_image_to_buffer(
                    cmd,
                    target.output.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    buffer.raw,
                    &regions_out,
                );
                device.cmd_copy_image_to_buffer(
                    cmd,
                    self.linear.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    buffer.raw,
                    &regions_lin,
                );
                cmd_image_barriers(
                    device,
                    cmd,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::PipelineStageFlags::ALL_COMMANDS,
                    &back,
                );
            }
        })?;
        // SAFETY: `one_shot` waited for the only submission that writes
        // `buffer`, a buffer made for this read-back and used by nothing else.
        let data = unsafe { buffer.read() };
        let bgra = matches!(
            self.swapchain.format,
            vk::Format::B8G8R8A8_SRGB | vk::Format::B8G8R8A8_UNORM
        );
        Ok(eye_images(
            data,
            views,
            (w, h),
            bgra,
            1.0 / self.scene.radiance_scale,
        ))
    }
}

/// Splits the read-back buffer into `views` eyes: each layer's sRGB output
/// (BGRA swapped to RGBA) and its half-float linear radiance, divided by the
/// scene's radiance scale (`unscale` is its inverse) back to W·sr⁻¹·m⁻².
fn eye_images(
    data: &[u8],
    views: u32,
    (w, h): (u32, u32),
    bgra: bool,
    unscale: f32,
) -> Vec<EyeImage> {
    let pixels = u64::from(w) * u64::from(h);
    let srgb_bytes = pixels * 4;
    let linear_bytes = pixels * 8;
    let per_layer = srgb_bytes + linear_bytes;
    let mut eyes = Vec::new();
    for layer in 0..views as u64 {
        let base = (layer * per_layer) as usize;
        let mut srgb = data[base..base + srgb_bytes as usize].to_vec();
        // BGRA outputs (window and XR swapchains often are) read back as RGBA.
        if bgra {
            for px in srgb.chunks_exact_mut(4) {
                px.swap(0, 2);
            }
        }
        let lin = &data[base + srgb_bytes as usize..base + per_layer as usize];
        let mut radiance = Vec::with_capacity(pixels as usize * 3);
        for px in lin.chunks_exact(8) {
            for c in 0..3 {
                let h = half::f16::from_bits(u16::from_le_bytes([px[2 * c], px[2 * c + 1]]));
                radiance.push(h.to_f32() * unscale);
            }
        }
        eyes.push(EyeImage {
            width: w,
            height: h,
            srgb,
            radiance,
        });
    }
    eyes
}
