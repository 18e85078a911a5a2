//! The session the frame loop is written against, and its mock.
//!
//! A frame is: [`Session::wait_frame`] (pace and begin the frame) →
//! [`Session::locate_views`] (per-view pose and field of view for the predicted
//! display time) → [`Session::acquire_image`] → render → [`Session::release_image`]
//! → [`Session::end_frame`] (submit the views for display). This is OpenXR's
//! order (xrWaitFrame/xrBeginFrame, xrLocateViews, xrAcquire/WaitSwapchainImage,
//! xrReleaseSwapchainImage, xrEndFrame), so an OpenXR backend implements the
//! trait directly; [`MockSession`] scripts head poses and renders offscreen.

mod mock;
mod walk;

pub use mock::{MockDesc, MockSession};
pub use walk::{HeadPath, HeadPose, WalkError};

use crate::gpu::{Gpu, GpuError, Image, ImageDesc};
use crate::render::{RenderError, StereoRenderer, SwapchainDesc};
use ash::vk;
use glam::{DQuat, DVec3};
use solution::camera::{EyeView, Fov};

/// A pose in the solution's file (re-centred) coordinates, scene units:
/// `orientation` rotates view space (+x right, +y up, looking down −z) into the
/// world, as an OpenXR pose does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub position: DVec3,
    pub orientation: DQuat,
}

/// One view of a frame: where the eye is and what it sees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewState {
    pub pose: Pose,
    /// Four angles, OpenXR's signs (left and down negative); may be asymmetric.
    pub fov: Fov,
}

impl ViewState {
    /// The renderer's view for an image of `width × height`.
    pub fn eye_view(&self, width: u32, height: u32) -> EyeView {
        EyeView::from_pose(
            self.pose.position,
            self.pose.orientation,
            self.fov,
            width,
            height,
        )
    }
}

/// What `wait_frame` returns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameTiming {
    /// Counts frames from 0.
    pub index: u64,
    /// When the frame will be shown, seconds since the session began.
    pub predicted_display_time: f64,
    /// False when the runtime wants the frame skipped (headset not visible).
    pub should_render: bool,
}

#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error("{0}")]
    Runtime(String),
}

/// A display session: a swapchain of two-layer images (one layer per view) and
/// the frame protocol described in the module notes.
pub trait Session {
    /// The images frames are rendered into.
    fn swapchain(&self) -> SwapchainDesc;
    /// Paces the loop and begins a frame.
    fn wait_frame(&mut self) -> Result<FrameTiming, SessionError>;
    /// Per-view pose and field of view at the frame's display time; left first.
    fn locate_views(&mut self, timing: &FrameTiming) -> Result<Vec<ViewState>, SessionError>;
    /// The swapchain image to render into (acquired and waited for).
    fn acquire_image(&mut self) -> Result<usize, SessionError>;
    /// Gives the image back (after the rendering commands were submitted).
    fn release_image(&mut self) -> Result<(), SessionError>;
    /// Ends the frame, submitting the rendered views for display.
    fn end_frame(&mut self, timing: &FrameTiming, views: &[ViewState]) -> Result<(), SessionError>;
    /// True when the session wants the loop to stop.
    fn should_exit(&self) -> bool;
}

/// What one pass of [`run_frame`] did.
#[derive(Clone, Debug)]
pub struct FrameReport {
    pub timing: FrameTiming,
    pub image: Option<usize>,
    pub views: Vec<ViewState>,
}

#[derive(Debug, thiserror::Error)]
pub enum FrameError {
    #[error(transparent)]
    Session(#[from] SessionError),
    #[error(transparent)]
    Render(#[from] RenderError),
}

/// One frame of the loop: wait frame → views → acquire → render → release →
/// submit.
pub fn run_frame(
    session: &mut dyn Session,
    renderer: &mut StereoRenderer,
) -> Result<FrameReport, FrameError> {
    let timing = session.wait_frame()?;
    if !timing.should_render {
        session.end_frame(&timing, &[])?;
        return Ok(FrameReport {
            timing,
            image: None,
            views: Vec::new(),
        });
    }
    let views = session.locate_views(&timing)?;
    let swapchain = session.swapchain();
    let eye_views: Vec<EyeView> = views
        .iter()
        .map(|v| v.eye_view(swapchain.width, swapchain.height))
        .collect();
    let image = session.acquire_image()?;
    let rendered = renderer.render(&eye_views, image);
    // Release even when rendering failed, so the session stays consistent.
    session.release_image()?;
    rendered?;
    session.end_frame(&timing, &views)?;
    Ok(FrameReport {
        timing,
        image: Some(image),
        views,
    })
}

/// Offscreen swapchain images: sRGB RGBA8, two layers, usable as colour
/// attachments and as copy sources (for screenshots and tests).
pub struct OffscreenSwapchain {
    pub images: Vec<Image>,
    pub width: u32,
    pub height: u32,
}

/// The offscreen swapchain's format.
pub const OFFSCREEN_FORMAT: vk::Format = vk::Format::R8G8B8A8_SRGB;

impl OffscreenSwapchain {
    pub fn new(
        gpu: &Gpu,
        width: u32,
        height: u32,
        count: usize,
    ) -> Result<OffscreenSwapchain, GpuError> {
        let images = (0..count.max(1))
            .map(|_| {
                Image::new(
                    gpu,
                    ImageDesc {
                        width,
                        height,
                        layers: 2,
                        format: OFFSCREEN_FORMAT,
                        samples: vk::SampleCountFlags::TYPE_1,
                        usage: vk::ImageUsageFlags::COLOR_ATTACHMENT
                            | vk::ImageUsageFlags::TRANSFER_SRC,
                        aspect: vk::ImageAspectFlags::COLOR,
                    },
                )
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(OffscreenSwapchain {
            images,
            width,
            height,
        })
    }

    pub fn desc(&self) -> SwapchainDesc {
        SwapchainDesc {
            images: self.images.iter().map(|i| i.raw).collect(),
            format: OFFSCREEN_FORMAT,
            width: self.width,
            height: self.height,
            layers: 2,
        }
    }
}
