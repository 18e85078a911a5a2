//! The mock session: scripted head poses, symmetric fields of view, an IPD, and
//! offscreen swapchain images.

use super::{
    walk::head_orientation, FrameTiming, HeadPath, OffscreenSwapchain, Pose, Session, SessionError,
    ViewState,
};
use crate::gpu::Gpu;
use crate::render::SwapchainDesc;
use glam::DVec3;
use solution::camera::{Fov, UpAxis};

/// Options of a mock session.
#[derive(Clone, Debug)]
pub struct MockDesc {
    /// Per-eye image size.
    pub width: u32,
    pub height: u32,
    /// Swapchain images (used round-robin).
    pub images: usize,
    /// The head path in scene coordinates.
    pub path: HeadPath,
    /// Interpupillary distance, metres.
    pub ipd_m: f64,
    /// From the solution header: scene units per metre, the up axis and the
    /// offset subtracted from scene coordinates to get file coordinates.
    pub units_per_metre: f64,
    pub up_axis: UpAxis,
    pub recentre_offset: DVec3,
    /// Vertical field of view of each eye, degrees (symmetric).
    pub fov_y_deg: f64,
    /// Simulated display rate, frames per second (the mock does not sleep).
    pub frame_rate: f64,
    /// Stop after this many frames (None: run until the caller stops).
    pub frames: Option<u64>,
}

/// A session that walks a scripted path and renders into offscreen images.
pub struct MockSession {
    swapchain: OffscreenSwapchain,
    desc: MockDesc,
    frame: u64,
    next_image: usize,
    acquired: Option<usize>,
    /// The views submitted by the last `end_frame`.
    pub last_views: Vec<ViewState>,
    /// The image the last frame was rendered into.
    pub last_image: Option<usize>,
}

impl MockSession {
    pub fn new(gpu: &Gpu, desc: MockDesc) -> Result<MockSession, SessionError> {
        if !(desc.ipd_m.is_finite() && desc.ipd_m >= 0.0) {
            return Err(SessionError::Runtime(format!(
                "interpupillary distance {} m is not a finite, non-negative length",
                desc.ipd_m
            )));
        }
        let swapchain = OffscreenSwapchain::new(gpu, desc.width, desc.height, desc.images)?;
        Ok(MockSession {
            swapchain,
            desc,
            frame: 0,
            next_image: 0,
            acquired: None,
            last_views: Vec::new(),
            last_image: None,
        })
    }

    /// The head pose at `time` in file coordinates, and its two eye views.
    pub fn views_at(&self, time: f64) -> Vec<ViewState> {
        let d = &self.desc;
        let head = d.path.sample(time);
        let orientation = head_orientation(head.yaw_deg, head.pitch_deg, d.up_axis);
        let position = head.position - d.recentre_offset;
        let right = orientation * DVec3::X;
        let half_ipd = 0.5 * d.ipd_m * d.units_per_metre;
        let fov = Fov::symmetric(d.fov_y_deg.to_radians(), d.width, d.height);
        [-half_ipd, half_ipd]
            .into_iter()
            .map(|shift| ViewState {
                pose: Pose {
                    position: position + right * shift,
                    orientation,
                },
                fov,
            })
            .collect()
    }

    pub fn frames_done(&self) -> u64 {
        self.frame
    }
}

impl Session for MockSession {
    fn swapchain(&self) -> SwapchainDesc {
        self.swapchain.desc()
    }

    fn wait_frame(&mut self) -> Result<FrameTiming, SessionError> {
        let index = self.frame;
        Ok(FrameTiming {
            index,
            predicted_display_time: self.desc.path.keys[0].time
                + index as f64 / self.desc.frame_rate.max(1e-3),
            should_render: true,
        })
    }

    fn locate_views(&mut self, timing: &FrameTiming) -> Result<Vec<ViewState>, SessionError> {
        Ok(self.views_at(timing.predicted_display_time))
    }

    fn acquire_image(&mut self) -> Result<usize, SessionError> {
        if self.acquired.is_some() {
            return Err(SessionError::Runtime(
                "acquire_image called twice without release_image".into(),
            ));
        }
        let image = self.next_image;
        self.next_image = (self.next_image + 1) % self.swapchain.images.len();
        self.acquired = Some(image);
        Ok(image)
    }

    fn release_image(&mut self) -> Result<(), SessionError> {
        self.last_image = self.acquired.take();
        if self.last_image.is_none() {
            return Err(SessionError::Runtime(
                "release_image without acquire_image".into(),
            ));
        }
        Ok(())
    }

    fn end_frame(
        &mut self,
        _timing: &FrameTiming,
        views: &[ViewState],
    ) -> Result<(), SessionError> {
        self.last_views = views.to_vec();
        self.frame += 1;
        Ok(())
    }

    fn should_exit(&self) -> bool {
        self.desc.frames.is_some_and(|n| self.frame >= n)
    }
}
