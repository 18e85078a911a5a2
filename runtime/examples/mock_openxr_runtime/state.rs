//! The runtime's state behind every entry point: one global, locked per call,
//! and the report written when the instance is destroyed.

use ash::vk::{self};
use openxr::sys as xr;

use std::collections::{HashMap, VecDeque};
use std::sync::Mutex;

#[derive(Default)]
pub(crate) struct Swapchain {
    pub(crate) session: u64,
    pub(crate) images: Vec<(vk::Image, vk::DeviceMemory)>,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) layers: u32,
    pub(crate) is_static: bool,
    pub(crate) next: u32,
    pub(crate) acquired: VecDeque<u32>,
    pub(crate) waited: bool,
    pub(crate) released_once: bool,
    pub(crate) last_released: Option<u32>,
}

pub(crate) struct VulkanSide {
    pub(crate) gipa: vk::PFN_vkGetInstanceProcAddr,
    pub(crate) instance: Option<ash::Instance>,
    pub(crate) physical: vk::PhysicalDevice,
    pub(crate) device: Option<ash::Device>,
    /// The session's queue (from its graphics binding), for read-back.
    pub(crate) queue: Option<(u32, vk::Queue)>,
}

#[derive(Default)]
pub(crate) struct Session {
    pub(crate) state: i32,
    pub(crate) running: bool,
    pub(crate) frame_waited: bool,
    pub(crate) frame_begun: bool,
    pub(crate) next_time: i64,
    pub(crate) last_predicted: i64,
    pub(crate) lost: bool,
    pub(crate) exit_requested: bool,
    /// Eyes returned by xrLocateViews, by display time.
    pub(crate) located: HashMap<i64, [(xr::Posef, xr::Fovf); 2]>,
    pub(crate) attached: bool,
    pub(crate) shown: bool,
}

#[derive(Default, serde::Serialize)]
pub(crate) struct Report {
    pub(crate) api_version: String,
    pub(crate) requirements_queried: bool,
    pub(crate) vulkan_instance_created: bool,
    pub(crate) vulkan_device_created: bool,
    pub(crate) sessions_created: u32,
    pub(crate) sessions_destroyed: u32,
    pub(crate) sessions_begun: u32,
    pub(crate) sessions_ended: u32,
    pub(crate) exit_requests: u32,
    pub(crate) frames_waited: u64,
    pub(crate) frames_ended: u64,
    pub(crate) frames_with_projection: u64,
    pub(crate) frames_with_quad: u64,
    pub(crate) swapchain_formats: Vec<i64>,
    pub(crate) swapchain_sizes: Vec<(u32, u32, u32)>,
    pub(crate) reference_spaces: Vec<i32>,
    pub(crate) profiles_accepted: Vec<String>,
    pub(crate) profiles_refused: Vec<String>,
    pub(crate) instance_destroyed: bool,
    /// Of the last projection frame's image, per eye: mean sRGB value of R,
    /// G and B (0–255) and the fraction of pixels that are not black.
    pub(crate) eye_stats: Vec<[f64; 4]>,
    /// Fraction of pixels that differ between the two eyes in that frame.
    pub(crate) eyes_differ: f64,
    /// The head pose of the first xrLocateSpace (where `runtime xr`
    /// recentres): position then orientation (x, y, z, w).
    pub(crate) first_head: Option<[f32; 7]>,
    /// The eyes of the last projection frame as submitted: per eye position,
    /// orientation (x, y, z, w) and field of view (left, right, up, down).
    pub(crate) last_eyes: Option<[[f32; 11]; 2]>,
    /// Vulkan format of the projection swapchain (and of `MOCK_XR_CAPTURE`).
    pub(crate) capture_format: i64,
    pub(crate) violations: Vec<String>,
}

#[derive(Default)]
pub(crate) struct State {
    pub(crate) instance: u64,
    pub(crate) next_handle: u64,
    pub(crate) max_minor: u16,
    pub(crate) loss_after: Option<u64>,
    pub(crate) help_at: Option<u64>,
    pub(crate) no_stage: bool,
    pub(crate) requirements_queried: bool,
    pub(crate) vulkan: Option<VulkanSide>,
    pub(crate) sessions: HashMap<u64, Session>,
    pub(crate) spaces: HashMap<u64, (u64, i32)>,
    pub(crate) swapchains: HashMap<u64, Swapchain>,
    pub(crate) paths: Vec<String>,
    pub(crate) actions: HashMap<u64, String>,
    pub(crate) events: VecDeque<(u64, i32)>,
    pub(crate) ended_total: u64,
    pub(crate) report: Report,
}

pub(crate) static STATE: Mutex<Option<State>> = Mutex::new(None);

pub(crate) fn with<R>(f: impl FnOnce(&mut State) -> R) -> R {
    let mut guard = STATE.lock().unwrap_or_else(|e| e.into_inner());
    let state = guard.get_or_insert_with(State::default);
    f(state)
}

pub(crate) fn violation(s: &mut State, what: String) -> xr::Result {
    s.report.violations.push(what);
    xr::Result::ERROR_VALIDATION_FAILURE
}

pub(crate) fn handle(s: &mut State) -> u64 {
    s.next_handle += 1;
    s.next_handle
}

pub(crate) fn push_state(s: &mut State, session: u64, state: xr::SessionState) {
    s.events.push_back((session, state.into_raw()));
}
