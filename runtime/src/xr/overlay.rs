//! The in-headset help overlay (`radview`'s F1 help window, Remington 1992,
//! app. C.1): the controls as white text on a dark panel, in a static
//! one-image swapchain shown as a quad layer over the scene while the menu
//! button has it toggled on.
//!
//! The panel is world-locked: when it is toggled on it is placed
//! [`PANEL_DISTANCE_M`] ahead of the head at eye height, facing it, and stays
//! there (head-locked text is uncomfortable). The text uses the mirror
//! window's 5×7 bitmap font ([`crate::mirror::font`]).

use super::input::HELP;
use super::locomotion::heading_deg;
use super::session::pose_to_xr;
use super::{XrContext, XrError};
use crate::gpu::barrier::{cmd_image_barriers, image_barrier};
use crate::gpu::{Buffer, BufferDesc, Gpu, MemoryLocation};
use crate::mirror::font::TextGrid;
use crate::session::Pose;
use ash::vk::{self, Handle};
use glam::{DQuat, DVec3};
use openxr as xr;

/// How far ahead of the head the panel appears, metres.
pub const PANEL_DISTANCE_M: f64 = 1.2;
/// The panel's width, metres (its height follows the text's aspect).
pub const PANEL_WIDTH_M: f64 = 0.9;
/// Font scale (pixels per font pixel) and margin around the text, pixels.
const SCALE: u32 = 3;
const MARGIN: u32 = 12;
/// Grey levels (equal in R, G and B, so RGBA and BGRA formats read alike).
const TEXT: u8 = 240;
const PANEL: u8 = 28;

/// The help text drawn as RGBA8 pixels (sRGB-encoded grey levels, opaque),
/// row 0 at the top: (width, height, pixels).
pub fn help_pixels(text: &str) -> (u32, u32, Vec<u8>) {
    let lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let grid = TextGrid::new(&lines, 80, 24);
    let (tw, th, lit) = grid.rasterize(SCALE);
    let (w, h) = (tw + 2 * MARGIN, th + 2 * MARGIN);
    let mut pixels = Vec::with_capacity((w * h * 4) as usize);
    for y in 0..h {
        for x in 0..w {
            let inside = x >= MARGIN && y >= MARGIN && x < MARGIN + tw && y < MARGIN + th;
            let on = inside && lit[((y - MARGIN) * tw + (x - MARGIN)) as usize];
            let grey = if on { TEXT } else { PANEL };
            pixels.extend_from_slice(&[grey, grey, grey, 255]);
        }
    }
    (w, h, pixels)
}

/// The panel's pose in the tracking space for a head pose: ahead along the
/// head's heading at eye height, turned to face the head (a quad faces +z).
pub fn panel_pose(head: &Pose) -> Pose {
    let heading = DQuat::from_rotation_y(heading_deg(head.orientation).to_radians());
    Pose {
        position: head.position + heading * DVec3::new(0.0, 0.0, -PANEL_DISTANCE_M),
        orientation: heading,
    }
}

/// The help panel's swapchain (one static image, written once).
pub struct HelpOverlay {
    swapchain: xr::Swapchain<xr::Vulkan>,
    width: u32,
    height: u32,
    /// Where the panel is, in the tracking space, while it is shown.
    pub pose: Option<Pose>,
}

impl HelpOverlay {
    /// Creates the swapchain on `session` in `format` (an 8-bit sRGB format the
    /// runtime offered) and uploads the help text into its image.
    pub fn new(
        session: &xr::Session<xr::Vulkan>,
        gpu: &Gpu,
        format: vk::Format,
    ) -> Result<HelpOverlay, XrError> {
        let (width, height, pixels) = help_pixels(HELP);
        let mut swapchain = session
            .create_swapchain(&xr::SwapchainCreateInfo {
                create_flags: xr::SwapchainCreateFlags::STATIC_IMAGE,
                usage_flags: xr::SwapchainUsageFlags::TRANSFER_DST
                    | xr::SwapchainUsageFlags::COLOR_ATTACHMENT,
                format: format.as_raw() as u32,
                sample_count: 1,
                width,
                height,
                face_count: 1,
                array_size: 1,
                mip_count: 1,
            })
            .xr("xrCreateSwapchain")?;
        let images = swapchain
            .enumerate_images()
            .xr("xrEnumerateSwapchainImages")?;
        let index = swapchain.acquire_image().xr("xrAcquireSwapchainImage")?;
        swapchain
            .wait_image(xr::Duration::INFINITE)
            .xr("xrWaitSwapchainImage")?;
        let image = images
            .get(index as usize)
            .map(|&raw| vk::Image::from_raw(raw))
            .ok_or(XrError::Call {
                call: "xrAcquireSwapchainImage",
                result: super::XrResult(xr::sys::Result::ERROR_INDEX_OUT_OF_RANGE),
            })?;
        let upload = upload(gpu, image, width, height, &pixels);
        // Released whether or not the upload worked, so the swapchain stays
        // consistent; a failed upload is reported after.
        swapchain.release_image().xr("xrReleaseSwapchainImage")?;
        upload?;
        Ok(HelpOverlay {
            swapchain,
            width,
            height,
            pose: None,
        })
    }

    /// The quad layer, while shown.
    pub fn layer<'a>(
        &'a self,
        space: &'a xr::Space,
    ) -> Option<xr::CompositionLayerQuad<'a, xr::Vulkan>> {
        let pose = self.pose?;
        let aspect = f64::from(self.height) / f64::from(self.width.max(1));
        Some(
            xr::CompositionLayerQuad::new()
                .space(space)
                .eye_visibility(xr::EyeVisibility::BOTH)
                .sub_image(
                    xr::SwapchainSubImage::new()
                        .swapchain(&self.swapchain)
                        .image_array_index(0)
                        .image_rect(xr::Rect2Di {
                            offset: xr::Offset2Di { x: 0, y: 0 },
                            extent: xr::Extent2Di {
                                width: self.width as i32,
                                height: self.height as i32,
                            },
                        }),
                )
                .pose(pose_to_xr(&pose))
                .size(xr::Extent2Df {
                    width: PANEL_WIDTH_M as f32,
                    height: (PANEL_WIDTH_M * aspect) as f32,
                }),
        )
    }
}

/// Copies RGBA8 `pixels` into `image` (left in COLOR_ATTACHMENT_OPTIMAL, the
/// layout OpenXR expects of a released colour image).
fn upload(
    gpu: &Gpu,
    image: vk::Image,
    width: u32,
    height: u32,
    pixels: &[u8],
) -> Result<(), XrError> {
    let mut staging = Buffer::new(
        gpu,
        BufferDesc {
            size: pixels.len() as u64,
            usage: vk::BufferUsageFlags::TRANSFER_SRC,
            location: MemoryLocation::Mapped,
        },
    )?;
    // SAFETY: the staging buffer was just created; no command buffer refers to
    // it yet.
    unsafe { staging.write(0, pixels) };
    let range = vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
    };
    use vk::{AccessFlags as A, ImageLayout as L, PipelineStageFlags as S};
    let to_dst = [image_barrier(
        image,
        range,
        (L::UNDEFINED, A::empty()),
        (L::TRANSFER_DST_OPTIMAL, A::TRANSFER_WRITE),
    )];
    let to_attachment = [image_barrier(
        image,
        range,
        (L::TRANSFER_DST_OPTIMAL, A::TRANSFER_WRITE),
        (L::COLOR_ATTACHMENT_OPTIMAL, A::empty()),
    )];
    let region = vk::BufferImageCopy::default()
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        })
        .image_extent(vk::Extent3D {
            width,
            height,
            depth: 1,
        });
    gpu.one_shot(|device, cmd| {
        // SAFETY: `cmd` is recording (one_shot's contract); the image is the
        // acquired, waited-for swapchain image of this device, and the
        // staging buffer holds width × height × 4 bytes.
        unsafe {
            cmd_image_barriers(device, cmd, S::TOP_OF_PIPE, S::TRANSFER, &to_dst);
            device.cmd_copy_buffer_to_image(
                cmd,
                staging.raw,
                image,
                L::TRANSFER_DST_OPTIMAL,
                &[region],
            );
            cmd_image_barriers(device, cmd, S::TRANSFER, S::BOTTOM_OF_PIPE, &to_attachment);
        }
    })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn help_text_is_drawn_on_an_opaque_panel() {
        let (w, h, px) = help_pixels("AB\nC");
        // Two columns and two rows of 6×9 cells at scale 3, plus margins.
        assert_eq!((w, h), (2 * 6 * 3 + 2 * MARGIN, 2 * 9 * 3 + 2 * MARGIN));
        assert_eq!(px.len(), (w * h * 4) as usize);
        let lit = px.chunks_exact(4).filter(|p| p[0] == TEXT).count();
        let dark = px.chunks_exact(4).filter(|p| p[0] == PANEL).count();
        assert_eq!(lit + dark, (w * h) as usize);
        assert!(px
            .chunks_exact(4)
            .all(|p| p[3] == 255 && p[0] == p[1] && p[1] == p[2]));
        // 'A' (0x0e,0x11,0x11,0x11,0x1f,0x11,0x11) has 3+2+2+2+5+2+2 = 18 lit
        // font pixels, 'B' 4+2+2+4+2+2+4 = 20, 'C' 3+2+1+1+1+2+3 = 13: each
        // is SCALE² screen pixels.
        assert_eq!(lit as u32, (18 + 20 + 13) * SCALE * SCALE);
        // The margin is dark.
        assert!(px[..(MARGIN * w * 4) as usize]
            .chunks_exact(4)
            .all(|p| p[0] == PANEL));
        // The shipped help fits the grid (80 × 24).
        let (w, h, _) = help_pixels(HELP);
        assert!(w > 0 && h > 0 && w <= 80 * 6 * SCALE + 2 * MARGIN);
    }

    #[test]
    fn panel_sits_ahead_at_eye_height_facing_the_head() {
        // Head at 1.7 m, turned 90° left and looking down 40°.
        let head = Pose {
            position: DVec3::new(0.5, 1.7, -0.2),
            orientation: DQuat::from_rotation_y(90f64.to_radians())
                * DQuat::from_rotation_x(-40f64.to_radians()),
        };
        let p = panel_pose(&head);
        // 1.2 m toward −x, same height.
        assert!((p.position - DVec3::new(0.5 - 1.2, 1.7, -0.2)).length() < 1e-12);
        // The quad's front (+z) points back at the head, level.
        let normal = p.orientation * DVec3::Z;
        assert!((normal - DVec3::X).length() < 1e-12, "{normal}");
    }
}
