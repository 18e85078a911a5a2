//! [`XrSession`]: an OpenXR session that implements [`Session`], so the frame
//! loop is [`crate::session::run_frame`], the code the mock session drives.
//!
//! One frame: [`Session::wait_frame`] polls events (the lifecycle decides, this
//! module carries its actions out), then `xrWaitFrame` and `xrBeginFrame`,
//! reads the controllers and locates the eyes at the predicted display time;
//! [`Session::locate_views`] hands the eyes over in scene coordinates;
//! [`Session::acquire_image`] and [`Session::release_image`] bracket the
//! rendering into the swapchain; [`Session::end_frame`] submits one projection
//! layer with the poses the eyes were rendered from (in the tracking space,
//! metres), or no layer when nothing was rendered. While the session is not
//! running there is no frame: `wait_frame` sleeps briefly and says not to
//! render, and `end_frame` does nothing.

use super::config::{ReferenceSpace, XrConfig};
use super::input::{XrInput, HELP};
use super::lifecycle::{Action, Event, ExitReason, Lifecycle, XrState};
use super::locomotion::{apply_deadzone, scene_yaw_deg, with_ipd, Locomotion, Placement};
use super::overlay::{panel_pose, HelpOverlay};
use super::system::{choose_swapchain_format, XrSystem, BLEND_MODE, VIEW_TYPE};
use super::{XrContext, XrError, XrResult};
use crate::gpu::{DeviceShared, Gpu};
use crate::render::SwapchainDesc;
use crate::session::{FrameTiming, Pose, Session, SessionError, ViewState};
use ash::vk::{self, Handle};
use glam::{DQuat, DVec3};
use openxr as xr;
use solution::camera::Fov;
use solution::format::Header;
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Duration;

/// How long `wait_frame` sleeps while the session is not running (the runtime
/// paces nothing then; this keeps the idle loop off the CPU).
const IDLE_POLL: Duration = Duration::from_millis(50);

/// The pause before trying to create a lost session again.
const RECREATE_PAUSE: Duration = Duration::from_secs(1);

/// `XrSessionState` → [`XrState`].
pub fn state_from_xr(state: xr::SessionState) -> XrState {
    match state {
        xr::SessionState::IDLE => XrState::Idle,
        xr::SessionState::READY => XrState::Ready,
        xr::SessionState::SYNCHRONIZED => XrState::Synchronized,
        xr::SessionState::VISIBLE => XrState::Visible,
        xr::SessionState::FOCUSED => XrState::Focused,
        xr::SessionState::STOPPING => XrState::Stopping,
        xr::SessionState::LOSS_PENDING => XrState::LossPending,
        xr::SessionState::EXITING => XrState::Exiting,
        _ => XrState::Unknown,
    }
}

/// An OpenXR pose (f32, metres) as a [`Pose`]; a zero quaternion (the runtime
/// did not know the orientation) becomes the identity.
pub fn pose_from_xr(pose: &xr::Posef) -> Pose {
    let o = pose.orientation;
    let q = DQuat::from_xyzw(o.x.into(), o.y.into(), o.z.into(), o.w.into());
    let orientation = if q.length_squared() > 1e-12 && q.is_finite() {
        q.normalize()
    } else {
        DQuat::IDENTITY
    };
    let p = pose.position;
    Pose {
        position: DVec3::new(p.x.into(), p.y.into(), p.z.into()),
        orientation,
    }
}

/// A [`Pose`] in the tracking space as an OpenXR pose.
pub fn pose_to_xr(pose: &Pose) -> xr::Posef {
    let (q, p) = (pose.orientation, pose.position);
    xr::Posef {
        orientation: xr::Quaternionf {
            x: q.x as f32,
            y: q.y as f32,
            z: q.z as f32,
            w: q.w as f32,
        },
        position: xr::Vector3f {
            x: p.x as f32,
            y: p.y as f32,
            z: p.z as f32,
        },
    }
}

/// OpenXR's field of view (radians; left and down negative) — the same
/// convention as [`Fov`], which allows asymmetric angles.
pub fn fov_from_xr(fov: &xr::Fovf) -> Fov {
    Fov {
        left: fov.angle_left.into(),
        right: fov.angle_right.into(),
        up: fov.angle_up.into(),
        down: fov.angle_down.into(),
    }
}

pub fn fov_to_xr(fov: &Fov) -> xr::Fovf {
    xr::Fovf {
        angle_left: fov.left as f32,
        angle_right: fov.right as f32,
        angle_up: fov.up as f32,
        angle_down: fov.down as f32,
    }
}

/// The handles one session owns. Fields are dropped in declaration order:
/// the swapchain and spaces before the frame stream, waiter and session.
struct SessionObjects {
    overlay: Option<HelpOverlay>,
    swapchain: xr::Swapchain<xr::Vulkan>,
    images: Vec<vk::Image>,
    format: vk::Format,
    view_space: xr::Space,
    space: xr::Space,
    stream: xr::FrameStream<xr::Vulkan>,
    waiter: xr::FrameWaiter,
    session: xr::Session<xr::Vulkan>,
}

/// What [`XrSession`] needs to (re)create a session.
struct SessionRecipe {
    instance: xr::Instance,
    system: xr::SystemId,
    binding: xr::vulkan::SessionCreateInfo,
    width: u32,
    height: u32,
    wanted_space: ReferenceSpace,
}

impl SessionRecipe {
    fn create(&self, input: &XrInput) -> Result<(SessionObjects, ReferenceSpace), XrError> {
        // SAFETY: `binding` holds the Vulkan instance, physical device and
        // device of the GPU context made through this OpenXR instance and
        // system (`vulkan::create_gpu`), with its graphics queue family and
        // queue 0; the XrSession keeps that context's `DeviceShared` alive
        // until after the session and everything made from it are destroyed
        // (field order), and it uses the queue only from this thread.
        let (session, waiter, stream) = unsafe {
            self.instance
                .create_session::<xr::Vulkan>(self.system, &self.binding)
        }
        .xr("xrCreateSession")?;
        input.attach(&session)?;

        let offered = session
            .enumerate_reference_spaces()
            .xr("xrEnumerateReferenceSpaces")?;
        let space_kind = match self.wanted_space {
            ReferenceSpace::Stage if offered.contains(&xr::ReferenceSpaceType::STAGE) => {
                ReferenceSpace::Stage
            }
            ReferenceSpace::Stage => {
                eprintln!("runtime xr: the runtime has no STAGE space; using LOCAL");
                ReferenceSpace::Local
            }
            ReferenceSpace::Local => ReferenceSpace::Local,
        };
        let space_type = match space_kind {
            ReferenceSpace::Stage => xr::ReferenceSpaceType::STAGE,
            ReferenceSpace::Local => xr::ReferenceSpaceType::LOCAL,
        };
        let space = session
            .create_reference_space(space_type, xr::Posef::IDENTITY)
            .xr("xrCreateReferenceSpace")?;
        let view_space = session
            .create_reference_space(xr::ReferenceSpaceType::VIEW, xr::Posef::IDENTITY)
            .xr("xrCreateReferenceSpace")?;

        let formats: Vec<vk::Format> = session
            .enumerate_swapchain_formats()
            .xr("xrEnumerateSwapchainFormats")?
            .into_iter()
            .map(|f| vk::Format::from_raw(f as i32))
            .collect();
        let format = choose_swapchain_format(&formats).ok_or_else(|| XrError::Unsupported {
            runtime: "the runtime".into(),
            reason: format!("it offers no 8-bit sRGB swapchain format (offered: {formats:?})"),
        })?;
        // One image array with a layer per eye, as multiview renders it; the
        // renderer resolves its own MSAA, so one sample.
        let swapchain = session
            .create_swapchain(&xr::SwapchainCreateInfo {
                create_flags: xr::SwapchainCreateFlags::EMPTY,
                usage_flags: xr::SwapchainUsageFlags::COLOR_ATTACHMENT,
                format: format.as_raw() as u32,
                sample_count: 1,
                width: self.width,
                height: self.height,
                face_count: 1,
                array_size: 2,
                mip_count: 1,
            })
            .xr("xrCreateSwapchain")?;
        let images = swapchain
            .enumerate_images()
            .xr("xrEnumerateSwapchainImages")?
            .into_iter()
            .map(vk::Image::from_raw)
            .collect();
        Ok((
            SessionObjects {
                overlay: None,
                swapchain,
                images,
                format,
                view_space,
                space,
                stream,
                waiter,
                session,
            },
            space_kind,
        ))
    }
}

/// Counts and timings of the frames submitted so far.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SubmitCounts {
    /// Frames ended with a rendered projection layer.
    pub with_layers: u64,
    /// Frames ended without layers (not visible, or winding down).
    pub empty: u64,
}

/// A headset session.
pub struct XrSession {
    // Dropped first: the session's handles (see the module notes of `xr`).
    objects: Option<SessionObjects>,
    input: XrInput,
    recipe: SessionRecipe,
    lifecycle: Lifecycle,
    locomotion: Locomotion,
    config: XrConfig,
    placement: Placement,
    /// The solution's stored camera (file coordinates) and its heading.
    home_eye: DVec3,
    home_yaw_deg: f64,
    events: xr::EventDataBuffer,
    /// The frame begun by `wait_frame` and not yet ended.
    frame: Option<xr::FrameState>,
    /// This frame's eyes in the tracking space (metres), IPD override applied:
    /// rendered from, and reported in the projection layer.
    eyes: Vec<ViewState>,
    acquired: bool,
    released: bool,
    frame_index: u64,
    first_time: Option<xr::Time>,
    last_time: Option<xr::Time>,
    counts: SubmitCounts,
    generation: u64,
    need_recentre: bool,
    help_visible: bool,
    /// The EV offset the right stick's y has set.
    exposure: super::exposure::ExposureStepper,
    /// Keeps the Vulkan device and instance alive until the session is gone.
    _vulkan: Arc<DeviceShared>,
}

impl XrSession {
    /// Creates the session on `gpu` (which must have been made through this
    /// system's runtime, see `vulkan::create_gpu`), its reference space and
    /// swapchain, and attaches the actions. The walker starts at the
    /// solution's stored camera.
    pub fn new(
        system: &XrSystem,
        gpu: &Gpu,
        header: &Header,
        config: XrConfig,
    ) -> Result<XrSession, XrError> {
        let (input, refused) = XrInput::new(&system.instance)?;
        for profile in refused {
            eprintln!("runtime xr: no bindings for {profile}");
        }
        let recipe = SessionRecipe {
            instance: system.instance.clone(),
            system: system.system,
            binding: xr::vulkan::SessionCreateInfo {
                instance: gpu.instance().handle().as_raw() as usize as _,
                physical_device: gpu.physical.as_raw() as usize as _,
                device: gpu.device().handle().as_raw() as usize as _,
                queue_family_index: gpu.queue_family,
                queue_index: 0,
            },
            width: system.width,
            height: system.height,
            wanted_space: config.reference_space,
        };
        let (objects, space) = recipe.create(&input)?;
        let placement = match space {
            ReferenceSpace::Local => Placement::Eye,
            ReferenceSpace::Stage => Placement::Floor {
                eye_height_m: config.camera_eye_height_m,
            },
        };
        let offset = DVec3::from(header.recentre_offset);
        let camera = &header.camera;
        let home_eye = DVec3::from(camera.eye) - offset;
        let home_yaw_deg = scene_yaw_deg(
            DVec3::from(camera.target) - DVec3::from(camera.eye),
            header.up_axis,
        );
        let mut locomotion = Locomotion::new(header.up_axis, header.units_per_metre);
        locomotion.origin = home_eye;
        Ok(XrSession {
            objects: Some(objects),
            input,
            recipe,
            lifecycle: Lifecycle::default(),
            locomotion,
            config,
            placement,
            home_eye,
            home_yaw_deg,
            events: xr::EventDataBuffer::new(),
            frame: None,
            eyes: Vec::new(),
            acquired: false,
            released: false,
            frame_index: 0,
            first_time: None,
            last_time: None,
            counts: SubmitCounts::default(),
            generation: 0,
            need_recentre: true,
            help_visible: false,
            exposure: Default::default(),
            _vulkan: gpu.shared.clone(),
        })
    }

    /// Frames submitted so far.
    pub fn counts(&self) -> SubmitCounts {
        self.counts
    }

    /// Changes whenever the swapchain is replaced (a lost session was
    /// recreated): the renderer must then be rebuilt on the new images.
    pub fn swapchain_generation(&self) -> u64 {
        self.generation
    }

    /// Why the session ended, once it has.
    pub fn exit_reason(&self) -> Option<ExitReason> {
        self.lifecycle.exit_reason()
    }

    /// Whether the help overlay is toggled on.
    pub fn help_visible(&self) -> bool {
        self.help_visible
    }

    /// Creates the help overlay's swapchain and writes the help text into it
    /// (after the session is created, and again after it is recreated). Without
    /// it the help goes to standard output only.
    pub fn prepare_overlay(&mut self, gpu: &Gpu) {
        let Some(o) = self.objects.as_mut() else {
            return;
        };
        if o.overlay.is_some() {
            return;
        }
        match HelpOverlay::new(&o.session, gpu, o.format) {
            Ok(overlay) => o.overlay = Some(overlay),
            Err(e) => eprintln!("runtime xr: no help overlay in the headset: {e}"),
        }
    }

    /// Asks the runtime to end the session; frames go on (without layers)
    /// until it agrees, and [`Session::should_exit`] turns true.
    pub fn request_exit(&mut self) -> Result<(), XrError> {
        self.dispatch(Event::ExitRequested)
    }

    /// Handles a failed frame call: a lost session or instance is a lifecycle
    /// event, anything else an error.
    fn on_frame_error(
        &mut self,
        call: &'static str,
        result: xr::sys::Result,
    ) -> Result<(), XrError> {
        self.frame = None;
        match result {
            xr::sys::Result::ERROR_SESSION_LOST => {
                self.dispatch(Event::StateChanged(XrState::LossPending))
            }
            xr::sys::Result::ERROR_INSTANCE_LOST => self.dispatch(Event::InstanceLossPending),
            _ => Err(XrError::Call {
                call,
                result: XrResult(result),
            }),
        }
    }

    /// Reads every pending event and acts on it.
    fn poll_events(&mut self) -> Result<(), XrError> {
        loop {
            let current = self.objects.as_ref().map(|o| o.session.as_raw());
            let event = match self.recipe.instance.poll_event(&mut self.events) {
                Ok(Some(event)) => match event {
                    xr::Event::SessionStateChanged(e) if Some(e.session()) == current => {
                        Some(Event::StateChanged(state_from_xr(e.state())))
                    }
                    xr::Event::InstanceLossPending(_) => Some(Event::InstanceLossPending),
                    xr::Event::EventsLost(e) => {
                        eprintln!(
                            "runtime xr: the runtime dropped {} events",
                            e.lost_event_count()
                        );
                        None
                    }
                    // Events of a destroyed session, recentring by the
                    // runtime (its space moves, the walker stays), profile
                    // changes and extensions need nothing.
                    _ => None,
                },
                Ok(None) => return Ok(()),
                Err(xr::sys::Result::ERROR_INSTANCE_LOST) => Some(Event::InstanceLossPending),
                Err(result) => {
                    return Err(XrError::Call {
                        call: "xrPollEvent",
                        result: XrResult(result),
                    })
                }
            };
            if let Some(event) = event {
                self.dispatch(event)?;
            }
            if self.lifecycle.is_done() {
                return Ok(());
            }
        }
    }

    /// Feeds an event to the lifecycle and carries out its actions (which may
    /// produce further events: a recreated session, or a failed attempt).
    fn dispatch(&mut self, event: Event) -> Result<(), XrError> {
        let mut queue = VecDeque::from([event]);
        while let Some(event) = queue.pop_front() {
            for action in self.lifecycle.handle(event) {
                if let Some(next) = self.perform(action)? {
                    queue.push_back(next);
                }
            }
        }
        Ok(())
    }

    fn perform(&mut self, action: Action) -> Result<Option<Event>, XrError> {
        match action {
            Action::BeginSession => {
                if let Some(o) = &self.objects {
                    o.session.begin(VIEW_TYPE).xr("xrBeginSession")?;
                }
            }
            Action::EndSession => {
                if let Some(o) = &self.objects {
                    o.session.end().xr("xrEndSession")?;
                }
            }
            Action::RequestExit => {
                if let Some(o) = &self.objects {
                    match o.session.request_exit() {
                        // Already winding down: the runtime's STOPPING is on its way.
                        Ok(()) | Err(xr::sys::Result::ERROR_SESSION_NOT_RUNNING) => {}
                        Err(result) => {
                            return Err(XrError::Call {
                                call: "xrRequestExitSession",
                                result: XrResult(result),
                            })
                        }
                    }
                }
            }
            Action::StartRendering | Action::StopRendering => {
                // `Lifecycle::should_render` is read each frame.
            }
            Action::DestroySession => {
                self.frame = None;
                self.acquired = false;
                self.objects = None;
            }
            Action::RecreateSession => {
                std::thread::sleep(RECREATE_PAUSE);
                return Ok(Some(match self.recipe.create(&self.input) {
                    Ok((objects, _)) => {
                        eprintln!("runtime xr: session recreated after a loss");
                        self.objects = Some(objects);
                        self.generation += 1;
                        Event::SessionRecreated
                    }
                    Err(e) => {
                        eprintln!("runtime xr: cannot recreate the session yet: {e}");
                        Event::RecreateFailed
                    }
                }));
            }
            Action::Exit(_) => {}
        }
        Ok(None)
    }

    /// Locates the head and eyes at `time`, and applies the controls.
    /// Returns whether the eyes' orientations are known (frames are only
    /// rendered then).
    fn track(&mut self, time: xr::Time) -> Result<bool, XrError> {
        let Some(o) = &self.objects else {
            return Ok(false);
        };
        let (flags, views) = o
            .session
            .locate_views(VIEW_TYPE, time, &o.space)
            .xr("xrLocateViews")?;
        let head = o.view_space.locate(&o.space, time).xr("xrLocateSpace")?;
        let controls = if self.lifecycle.input_focused() {
            Some(self.input.read(&o.session)?)
        } else {
            None
        };

        let dt = self
            .last_time
            .map(|t| (time.as_nanos() - t.as_nanos()) as f64 * 1e-9)
            .unwrap_or(0.0);
        self.last_time = Some(time);
        self.first_time.get_or_insert(time);

        let head_known = head.location_flags.contains(
            xr::SpaceLocationFlags::ORIENTATION_VALID | xr::SpaceLocationFlags::POSITION_VALID,
        );
        if head_known {
            let head = pose_from_xr(&head.pose);
            if let Some(c) = controls {
                if c.recentre_pressed {
                    self.need_recentre = true;
                }
                if c.help_pressed {
                    self.help_visible = !self.help_visible;
                    if self.help_visible {
                        println!("{HELP}");
                    }
                    if let Some(overlay) = self.objects.as_mut().and_then(|o| o.overlay.as_mut()) {
                        overlay.pose = self.help_visible.then(|| panel_pose(&head));
                    }
                }
            }
            if self.need_recentre {
                self.locomotion
                    .recentre(&head, self.home_eye, self.home_yaw_deg, self.placement);
                self.need_recentre = false;
            }
            if let Some(c) = controls {
                let walk = apply_deadzone(c.walk, self.config.thumbstick_deadzone);
                self.locomotion
                    .walk(walk, &head, dt, self.config.walk_speed_m_s);
                self.locomotion
                    .snap_turn(c.turn_x, &head, self.config.snap_turn_deg);
                self.exposure.step(c.turn_y);
            }
        }

        let eyes: Vec<ViewState> = views
            .iter()
            .map(|v| ViewState {
                pose: pose_from_xr(&v.pose),
                fov: fov_from_xr(&v.fov),
            })
            .collect();
        self.eyes = match self.config.ipd_m {
            Some(ipd) => with_ipd(&eyes, ipd),
            None => eyes,
        };
        Ok(self.eyes.len() == 2 && flags.contains(xr::ViewStateFlags::ORIENTATION_VALID))
    }

    /// The EV offset (stops) the controller has set, added to `--exposure`.
    pub fn exposure_offset_stops(&self) -> f32 {
        self.exposure.offset_stops
    }

    fn seconds(&self, time: xr::Time) -> f64 {
        self.first_time
            .map(|t0| (time.as_nanos() - t0.as_nanos()) as f64 * 1e-9)
            .unwrap_or(0.0)
    }
}

fn session_error(e: XrError) -> SessionError {
    SessionError::Runtime(e.to_string())
}

impl Session for XrSession {
    fn swapchain(&self) -> SwapchainDesc {
        let (images, format) = match &self.objects {
            Some(o) => (o.images.clone(), o.format),
            None => (Vec::new(), vk::Format::UNDEFINED),
        };
        SwapchainDesc {
            images,
            format,
            width: self.recipe.width,
            height: self.recipe.height,
            layers: 2,
        }
    }

    fn wait_frame(&mut self) -> Result<FrameTiming, SessionError> {
        self.poll_events().map_err(session_error)?;
        let skipped = FrameTiming {
            index: self.frame_index,
            predicted_display_time: self.last_time.map(|t| self.seconds(t)).unwrap_or(0.0),
            should_render: false,
        };
        if self.lifecycle.is_done() {
            return Ok(skipped);
        }
        if !self.lifecycle.is_running() || self.objects.is_none() {
            std::thread::sleep(IDLE_POLL);
            return Ok(skipped);
        }
        let waited = match self.objects.as_mut() {
            Some(o) => o.waiter.wait(),
            None => return Ok(skipped),
        };
        let state = match waited {
            Ok(state) => state,
            Err(result) => {
                self.on_frame_error("xrWaitFrame", result)
                    .map_err(session_error)?;
                return Ok(skipped);
            }
        };
        let begun = match self.objects.as_mut() {
            Some(o) => o.stream.begin(),
            None => return Ok(skipped),
        };
        if let Err(result) = begun {
            self.on_frame_error("xrBeginFrame", result)
                .map_err(session_error)?;
            return Ok(skipped);
        }
        self.frame = Some(state);
        self.released = false;
        let tracked = self
            .track(state.predicted_display_time)
            .map_err(session_error)?;
        let index = self.frame_index;
        self.frame_index += 1;
        Ok(FrameTiming {
            index,
            predicted_display_time: self.seconds(state.predicted_display_time),
            should_render: state.should_render && self.lifecycle.should_render() && tracked,
        })
    }

    fn locate_views(&mut self, _timing: &FrameTiming) -> Result<Vec<ViewState>, SessionError> {
        if self.frame.is_none() || self.eyes.len() != 2 {
            return Err(SessionError::Runtime(
                "locate_views outside a frame with two located eyes".into(),
            ));
        }
        Ok(self
            .eyes
            .iter()
            .map(|v| self.locomotion.view_to_scene(v))
            .collect())
    }

    fn acquire_image(&mut self) -> Result<usize, SessionError> {
        if self.acquired {
            return Err(SessionError::Runtime(
                "acquire_image called twice without release_image".into(),
            ));
        }
        let o = match self.objects.as_mut() {
            Some(o) => o,
            None => return Err(SessionError::Runtime("the OpenXR session is gone".into())),
        };
        let index = o
            .swapchain
            .acquire_image()
            .xr("xrAcquireSwapchainImage")
            .map_err(session_error)?;
        o.swapchain
            .wait_image(xr::Duration::INFINITE)
            .xr("xrWaitSwapchainImage")
            .map_err(session_error)?;
        self.acquired = true;
        Ok(index as usize)
    }

    fn release_image(&mut self) -> Result<(), SessionError> {
        if !self.acquired {
            return Err(SessionError::Runtime(
                "release_image without acquire_image".into(),
            ));
        }
        self.acquired = false;
        let o = match self.objects.as_mut() {
            Some(o) => o,
            None => return Err(SessionError::Runtime("the OpenXR session is gone".into())),
        };
        o.swapchain
            .release_image()
            .xr("xrReleaseSwapchainImage")
            .map_err(session_error)?;
        self.released = true;
        Ok(())
    }

    fn end_frame(
        &mut self,
        _timing: &FrameTiming,
        views: &[ViewState],
    ) -> Result<(), SessionError> {
        // No frame was begun (not running, or the session was lost meanwhile).
        let Some(state) = self.frame.take() else {
            return Ok(());
        };
        let with_layer = !views.is_empty() && self.released && self.eyes.len() == 2;
        self.released = false;
        let Some(o) = self.objects.as_mut() else {
            return Err(SessionError::Runtime("the OpenXR session is gone".into()));
        };
        // Disjoint borrows: the layer refers to the swapchain and space while
        // the stream ends the frame.
        let SessionObjects {
            swapchain,
            space,
            stream,
            overlay,
            ..
        } = o;
        let time = state.predicted_display_time;
        let result = if with_layer {
            let rect = xr::Rect2Di {
                offset: xr::Offset2Di { x: 0, y: 0 },
                extent: xr::Extent2Di {
                    width: self.recipe.width as i32,
                    height: self.recipe.height as i32,
                },
            };
            let projection_views: Vec<xr::CompositionLayerProjectionView<xr::Vulkan>> = self
                .eyes
                .iter()
                .enumerate()
                .map(|(layer, eye)| {
                    xr::CompositionLayerProjectionView::new()
                        .pose(pose_to_xr(&eye.pose))
                        .fov(fov_to_xr(&eye.fov))
                        .sub_image(
                            xr::SwapchainSubImage::new()
                                .swapchain(swapchain)
                                .image_array_index(layer as u32)
                                .image_rect(rect),
                        )
                })
                .collect();
            let projection = xr::CompositionLayerProjection::new()
                .space(space)
                .views(&projection_views);
            let quad = overlay.as_ref().and_then(|h| h.layer(space));
            let mut layers: Vec<&xr::CompositionLayerBase<xr::Vulkan>> = vec![&projection];
            if let Some(quad) = &quad {
                layers.push(quad);
            }
            stream.end(time, BLEND_MODE, &layers)
        } else {
            stream.end(time, BLEND_MODE, &[])
        };
        match result {
            Ok(()) => {
                if with_layer {
                    self.counts.with_layers += 1;
                } else {
                    self.counts.empty += 1;
                }
                Ok(())
            }
            Err(result) => self
                .on_frame_error("xrEndFrame", result)
                .map_err(session_error),
        }
    }

    fn should_exit(&self) -> bool {
        self.lifecycle.is_done()
    }
}
