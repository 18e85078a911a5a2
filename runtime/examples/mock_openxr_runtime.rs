//! A scripted OpenXR runtime for testing `runtime xr` without a headset: a
//! shared library the OpenXR loader loads through a runtime manifest
//! (`XR_RUNTIME_JSON`). It implements the calls `runtime xr` makes, enforces the
//! rules conformant runtimes enforce (requirements queried before the Vulkan
//! instance and the session; the session on exactly the Vulkan instance,
//! physical device and device made through it; begin only when READY, end only
//! when STOPPING; frames ended with the predicted time, opaque blending, and
//! projection views that match the located eyes and released images), drives
//! the session lifecycle, and writes a JSON report when the instance is
//! destroyed.
//!
//! Environment (all optional):
//! * `MOCK_XR_REPORT`: file the JSON report is written to.
//! * `MOCK_XR_API`: the highest API version accepted, `1.0` (default) or `1.1`.
//! * `MOCK_XR_LOSS_AFTER`: after this many ended frames, the first session
//!   reports LOSS_PENDING (a second session then runs normally).
//! * `MOCK_XR_HELP_AT`: the frame at which the help (left menu) button is
//!   pressed.
//! * `MOCK_XR_NO_STAGE`: offer no STAGE space.
//! * `MOCK_XR_WALK`: `x,y` deflection of both thumbsticks (default centred).
//! * `MOCK_XR_CAPTURE`: file the last projection frame's image is written to
//!   (both layers, 4 bytes per pixel, in the swapchain's format).
//!
//! **Safety.** Every entry point is an `unsafe extern "system" fn` called by
//! the OpenXR loader with the application's arguments; the one invariant the
//! pointer dereferences below rely on (and which is not repeated at each of
//! them) is the specification's: every input pointer is valid for reading its
//! structure, every output pointer for writing it, and a capacity names how
//! many elements an output array holds. Vulkan calls additionally rely on the
//! handles being the ones this runtime created, as stated where they occur.
//!
//! Views: 320×240 recommended per eye (the smallest conformant size), an IPD
//! of 63 mm, asymmetric fields of view mirrored between the eyes, and a head
//! that sways a little with time, so poses differ per eye and per frame.

use ash::vk::{self, Handle};
use openxr::sys as xr;
use std::collections::{HashMap, VecDeque};
use std::ffi::{c_char, c_void, CStr};
use std::sync::Mutex;

const FRAME_PERIOD_NS: i64 = 2_000_000;
const WIDTH: u32 = 320;
const HEIGHT: u32 = 240;
const IPD_M: f32 = 0.063;

#[derive(Default)]
struct Swapchain {
    session: u64,
    images: Vec<(vk::Image, vk::DeviceMemory)>,
    width: u32,
    height: u32,
    layers: u32,
    is_static: bool,
    next: u32,
    acquired: VecDeque<u32>,
    waited: bool,
    released_once: bool,
    last_released: Option<u32>,
}

struct VulkanSide {
    gipa: vk::PFN_vkGetInstanceProcAddr,
    instance: Option<ash::Instance>,
    physical: vk::PhysicalDevice,
    device: Option<ash::Device>,
    /// The session's queue (from its graphics binding), for read-back.
    queue: Option<(u32, vk::Queue)>,
}

#[derive(Default)]
struct Session {
    state: i32,
    running: bool,
    frame_waited: bool,
    frame_begun: bool,
    next_time: i64,
    last_predicted: i64,
    lost: bool,
    exit_requested: bool,
    /// Eyes returned by xrLocateViews, by display time.
    located: HashMap<i64, [(xr::Posef, xr::Fovf); 2]>,
    attached: bool,
    shown: bool,
}

#[derive(Default, serde::Serialize)]
struct Report {
    api_version: String,
    requirements_queried: bool,
    vulkan_instance_created: bool,
    vulkan_device_created: bool,
    sessions_created: u32,
    sessions_destroyed: u32,
    sessions_begun: u32,
    sessions_ended: u32,
    exit_requests: u32,
    frames_waited: u64,
    frames_ended: u64,
    frames_with_projection: u64,
    frames_with_quad: u64,
    swapchain_formats: Vec<i64>,
    swapchain_sizes: Vec<(u32, u32, u32)>,
    reference_spaces: Vec<i32>,
    profiles_accepted: Vec<String>,
    profiles_refused: Vec<String>,
    instance_destroyed: bool,
    /// Of the last projection frame's image, per eye: mean sRGB value of R,
    /// G and B (0–255) and the fraction of pixels that are not black.
    eye_stats: Vec<[f64; 4]>,
    /// Fraction of pixels that differ between the two eyes in that frame.
    eyes_differ: f64,
    /// The head pose of the first xrLocateSpace (where `runtime xr`
    /// recentres): position then orientation (x, y, z, w).
    first_head: Option<[f32; 7]>,
    /// The eyes of the last projection frame as submitted: per eye position,
    /// orientation (x, y, z, w) and field of view (left, right, up, down).
    last_eyes: Option<[[f32; 11]; 2]>,
    /// Vulkan format of the projection swapchain (and of `MOCK_XR_CAPTURE`).
    capture_format: i64,
    violations: Vec<String>,
}

#[derive(Default)]
struct State {
    instance: u64,
    next_handle: u64,
    max_minor: u16,
    loss_after: Option<u64>,
    help_at: Option<u64>,
    no_stage: bool,
    requirements_queried: bool,
    vulkan: Option<VulkanSide>,
    sessions: HashMap<u64, Session>,
    spaces: HashMap<u64, (u64, i32)>,
    swapchains: HashMap<u64, Swapchain>,
    paths: Vec<String>,
    actions: HashMap<u64, String>,
    events: VecDeque<(u64, i32)>,
    ended_total: u64,
    report: Report,
}

static STATE: Mutex<Option<State>> = Mutex::new(None);

fn with<R>(f: impl FnOnce(&mut State) -> R) -> R {
    let mut guard = STATE.lock().unwrap_or_else(|e| e.into_inner());
    let state = guard.get_or_insert_with(State::default);
    f(state)
}

fn violation(s: &mut State, what: String) -> xr::Result {
    s.report.violations.push(what);
    xr::Result::ERROR_VALIDATION_FAILURE
}

fn handle(s: &mut State) -> u64 {
    s.next_handle += 1;
    s.next_handle
}

fn push_state(s: &mut State, session: u64, state: xr::SessionState) {
    s.events.push_back((session, state.into_raw()));
}

/// The head at display time `t`: 1.6 m up, swaying ±5 cm sideways, turning
/// ±5° about +y.
fn head(t: i64) -> (xr::Vector3f, f32) {
    let s = (t as f64 * 1e-9 * 2.0).sin() as f32;
    (
        xr::Vector3f {
            x: 0.05 * s,
            y: 1.6,
            z: 0.0,
        },
        0.087 * s,
    )
}

fn yaw_quat(yaw: f32) -> xr::Quaternionf {
    xr::Quaternionf {
        x: 0.0,
        y: (0.5 * yaw).sin(),
        z: 0.0,
        w: (0.5 * yaw).cos(),
    }
}

fn eyes(t: i64) -> [xr::View; 2] {
    let (p, yaw) = head(t);
    let (c, sn) = (yaw.cos(), yaw.sin());
    let eye = |side: f32, fov: xr::Fovf| xr::View {
        ty: xr::View::TYPE,
        next: std::ptr::null_mut(),
        pose: xr::Posef {
            orientation: yaw_quat(yaw),
            // The head's +x after the yaw is (cos, 0, −sin).
            position: xr::Vector3f {
                x: p.x + side * 0.5 * IPD_M * c,
                y: p.y,
                z: p.z - side * 0.5 * IPD_M * sn,
            },
        },
        fov,
    };
    [
        eye(
            -1.0,
            xr::Fovf {
                angle_left: -0.95,
                angle_right: 0.75,
                angle_up: 0.80,
                angle_down: -0.90,
            },
        ),
        eye(
            1.0,
            xr::Fovf {
                angle_left: -0.75,
                angle_right: 0.95,
                angle_up: 0.80,
                angle_down: -0.90,
            },
        ),
    ]
}

fn env_u64(name: &str) -> Option<u64> {
    std::env::var(name).ok().and_then(|v| v.parse().ok())
}

unsafe fn cstr<'a>(p: *const c_char) -> &'a str {
    if p.is_null() {
        ""
    } else {
        unsafe { CStr::from_ptr(p) }.to_str().unwrap_or("")
    }
}

fn fixed(out: &mut [c_char], text: &str) {
    for (o, b) in out.iter_mut().zip(text.bytes().chain(std::iter::once(0))) {
        *o = b as c_char;
    }
}

/// The two-call idiom: writes `items` if there is room, always the count.
unsafe fn fill<T: Copy>(cap: u32, count: *mut u32, out: *mut T, items: &[T]) -> xr::Result {
    unsafe { *count = items.len() as u32 };
    if cap == 0 {
        return xr::Result::SUCCESS;
    }
    if (cap as usize) < items.len() {
        return xr::Result::ERROR_SIZE_INSUFFICIENT;
    }
    for (i, item) in items.iter().enumerate() {
        unsafe { *out.add(i) = *item };
    }
    xr::Result::SUCCESS
}

// ---- negotiation and dispatch ----

/// The loader's entry point into the runtime.
///
/// # Safety
///
/// Both pointers are valid, as the loader guarantees.
#[no_mangle]
pub unsafe extern "system" fn xrNegotiateLoaderRuntimeInterface(
    loader: *const openxr::sys::loader::XrNegotiateLoaderInfo,
    request: *mut openxr::sys::loader::XrNegotiateRuntimeRequest,
) -> xr::Result {
    let (loader, request) = unsafe { (&*loader, &mut *request) };
    request.runtime_interface_version = 1;
    request.runtime_api_version = loader.max_api_version;
    request.get_instance_proc_addr = Some(get_instance_proc_addr);
    xr::Result::SUCCESS
}

macro_rules! table {
    ($name:expr, $( $s:literal => $f:ident ),* $(,)?) => {
        match $name {
            // SAFETY: a function pointer cast to the generic type the loader
            // expects; it casts it back to the named function's type.
            $( $s => Some(unsafe { std::mem::transmute::<*const (), xr::pfn::VoidFunction>($f as *const ()) }), )*
            _ => None,
        }
    };
}

unsafe extern "system" fn get_instance_proc_addr(
    _instance: xr::Instance,
    name: *const c_char,
    function: *mut Option<xr::pfn::VoidFunction>,
) -> xr::Result {
    let name = unsafe { cstr(name) };
    let f = table!(name,
        "xrGetInstanceProcAddr" => get_instance_proc_addr,
        "xrEnumerateInstanceExtensionProperties" => enumerate_extensions,
        "xrCreateInstance" => create_instance,
        "xrDestroyInstance" => destroy_instance,
        "xrGetInstanceProperties" => instance_properties,
        "xrPollEvent" => poll_event,
        "xrGetSystem" => get_system,
        "xrEnumerateViewConfigurations" => view_configurations,
        "xrEnumerateEnvironmentBlendModes" => blend_modes,
        "xrEnumerateViewConfigurationViews" => view_configuration_views,
        "xrGetVulkanGraphicsRequirements2KHR" => graphics_requirements,
        "xrCreateVulkanInstanceKHR" => create_vulkan_instance,
        "xrGetVulkanGraphicsDevice2KHR" => graphics_device,
        "xrCreateVulkanDeviceKHR" => create_vulkan_device,
        "xrCreateSession" => create_session,
        "xrDestroySession" => destroy_session,
        "xrBeginSession" => begin_session,
        "xrEndSession" => end_session,
        "xrRequestExitSession" => request_exit,
        "xrEnumerateReferenceSpaces" => reference_spaces,
        "xrCreateReferenceSpace" => create_reference_space,
        "xrDestroySpace" => destroy_space,
        "xrLocateSpace" => locate_space,
        "xrLocateViews" => locate_views,
        "xrEnumerateSwapchainFormats" => swapchain_formats,
        "xrCreateSwapchain" => create_swapchain,
        "xrDestroySwapchain" => destroy_swapchain,
        "xrEnumerateSwapchainImages" => swapchain_images,
        "xrAcquireSwapchainImage" => acquire_image,
        "xrWaitSwapchainImage" => wait_image,
        "xrReleaseSwapchainImage" => release_image,
        "xrWaitFrame" => wait_frame,
        "xrBeginFrame" => begin_frame,
        "xrEndFrame" => end_frame,
        "xrStringToPath" => string_to_path,
        "xrCreateActionSet" => create_action_set,
        "xrDestroyActionSet" => destroy_nothing,
        "xrCreateAction" => create_action,
        "xrDestroyAction" => destroy_nothing,
        "xrSuggestInteractionProfileBindings" => suggest_bindings,
        "xrAttachSessionActionSets" => attach_action_sets,
        "xrSyncActions" => sync_actions,
        "xrGetActionStateBoolean" => action_boolean,
        "xrGetActionStateVector2f" => action_vector2,
        // Core functions `runtime xr` never calls: present (the loader and the
        // bindings fetch every core function), but unsupported.
        "xrEnumerateApiLayerProperties" => unsupported,
        "xrResultToString" => unsupported,
        "xrStructureTypeToString" => unsupported,
        "xrGetSystemProperties" => unsupported,
        "xrGetViewConfigurationProperties" => unsupported,
        "xrGetReferenceSpaceBoundsRect" => unsupported,
        "xrCreateActionSpace" => unsupported,
        "xrGetActionStateFloat" => unsupported,
        "xrGetActionStatePose" => unsupported,
        "xrEnumerateBoundSourcesForAction" => unsupported,
        "xrGetInputSourceLocalizedName" => unsupported,
        "xrApplyHapticFeedback" => unsupported,
        "xrStopHapticFeedback" => unsupported,
        "xrGetCurrentInteractionProfile" => unsupported,
        "xrPathToString" => unsupported,
    );
    unsafe { *function = f };
    if f.is_some() {
        xr::Result::SUCCESS
    } else {
        xr::Result::ERROR_FUNCTION_UNSUPPORTED
    }
}

// ---- instance and system ----

unsafe extern "system" fn enumerate_extensions(
    _layer: *const c_char,
    cap: u32,
    count: *mut u32,
    out: *mut xr::ExtensionProperties,
) -> xr::Result {
    let mut ext = xr::ExtensionProperties {
        ty: xr::ExtensionProperties::TYPE,
        next: std::ptr::null_mut(),
        extension_name: [0; xr::MAX_EXTENSION_NAME_SIZE],
        extension_version: 2,
    };
    fixed(&mut ext.extension_name, "XR_KHR_vulkan_enable2");
    if cap > 0 && !out.is_null() {
        // Keep the caller's type/next as the spec asks; write the rest.
        let slot = unsafe { &mut *out };
        slot.extension_name = ext.extension_name;
        slot.extension_version = ext.extension_version;
        unsafe { *count = 1 };
        return xr::Result::SUCCESS;
    }
    unsafe { *count = 1 };
    xr::Result::SUCCESS
}

unsafe extern "system" fn create_instance(
    info: *const xr::InstanceCreateInfo,
    instance: *mut xr::Instance,
) -> xr::Result {
    let info = unsafe { &*info };
    let version = info.application_info.api_version;
    with(|s| {
        *s = State::default();
        s.max_minor = match std::env::var("MOCK_XR_API").as_deref() {
            Ok("1.1") => 1,
            _ => 0,
        };
        s.loss_after = env_u64("MOCK_XR_LOSS_AFTER");
        s.help_at = env_u64("MOCK_XR_HELP_AT");
        s.no_stage = std::env::var_os("MOCK_XR_NO_STAGE").is_some();
        if version.major() != 1 || version.minor() > s.max_minor {
            return xr::Result::ERROR_API_VERSION_UNSUPPORTED;
        }
        let names: Vec<&str> = (0..info.enabled_extension_count as usize)
            .map(|i| unsafe { cstr(*info.enabled_extension_names.add(i)) })
            .collect();
        if !names.contains(&"XR_KHR_vulkan_enable2") {
            return violation(
                s,
                format!("instance without XR_KHR_vulkan_enable2: {names:?}"),
            );
        }
        s.report.api_version = format!("{version}");
        s.instance = handle(s);
        unsafe { *instance = xr::Instance::from_raw(s.instance) };
        xr::Result::SUCCESS
    })
}

unsafe extern "system" fn destroy_instance(_instance: xr::Instance) -> xr::Result {
    with(|s| {
        if !s.sessions.is_empty() {
            violation(s, "instance destroyed before its session".into());
        }
        s.report.instance_destroyed = true;
        if let Ok(path) = std::env::var("MOCK_XR_REPORT") {
            if let Ok(text) = serde_json::to_string_pretty(&s.report) {
                let _ = std::fs::write(path, text);
            }
        }
    });
    xr::Result::SUCCESS
}

unsafe extern "system" fn instance_properties(
    _instance: xr::Instance,
    props: *mut xr::InstanceProperties,
) -> xr::Result {
    let props = unsafe { &mut *props };
    props.runtime_version = xr::Version::new(0, 1, 0);
    fixed(&mut props.runtime_name, "mock runtime");
    xr::Result::SUCCESS
}

unsafe extern "system" fn get_system(
    _instance: xr::Instance,
    info: *const xr::SystemGetInfo,
    system: *mut xr::SystemId,
) -> xr::Result {
    if unsafe { (*info).form_factor } != xr::FormFactor::HEAD_MOUNTED_DISPLAY {
        return xr::Result::ERROR_FORM_FACTOR_UNSUPPORTED;
    }
    unsafe { *system = xr::SystemId::from_raw(1) };
    xr::Result::SUCCESS
}

unsafe extern "system" fn view_configurations(
    _i: xr::Instance,
    _s: xr::SystemId,
    cap: u32,
    count: *mut u32,
    out: *mut xr::ViewConfigurationType,
) -> xr::Result {
    unsafe {
        fill(
            cap,
            count,
            out,
            &[xr::ViewConfigurationType::PRIMARY_STEREO],
        )
    }
}

unsafe extern "system" fn blend_modes(
    _i: xr::Instance,
    _s: xr::SystemId,
    view: xr::ViewConfigurationType,
    cap: u32,
    count: *mut u32,
    out: *mut xr::EnvironmentBlendMode,
) -> xr::Result {
    if view != xr::ViewConfigurationType::PRIMARY_STEREO {
        return xr::Result::ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
    }
    unsafe { fill(cap, count, out, &[xr::EnvironmentBlendMode::OPAQUE]) }
}

unsafe extern "system" fn view_configuration_views(
    _i: xr::Instance,
    _s: xr::SystemId,
    _view: xr::ViewConfigurationType,
    cap: u32,
    count: *mut u32,
    out: *mut xr::ViewConfigurationView,
) -> xr::Result {
    let v = xr::ViewConfigurationView {
        ty: xr::ViewConfigurationView::TYPE,
        next: std::ptr::null_mut(),
        recommended_image_rect_width: WIDTH,
        max_image_rect_width: 2048,
        recommended_image_rect_height: HEIGHT,
        max_image_rect_height: 2048,
        recommended_swapchain_sample_count: 1,
        max_swapchain_sample_count: 1,
    };
    unsafe { fill(cap, count, out, &[v, v]) }
}

unsafe extern "system" fn poll_event(
    _instance: xr::Instance,
    buffer: *mut xr::EventDataBuffer,
) -> xr::Result {
    with(|s| match s.events.pop_front() {
        None => xr::Result::EVENT_UNAVAILABLE,
        Some((session, state)) => {
            let event = xr::EventDataSessionStateChanged {
                ty: xr::EventDataSessionStateChanged::TYPE,
                next: std::ptr::null(),
                session: xr::Session::from_raw(session),
                state: xr::SessionState::from_raw(state),
                time: xr::Time::from_nanos(0),
            };
            if let Some(sess) = s.sessions.get_mut(&session) {
                sess.state = state;
            }
            unsafe { std::ptr::write(buffer as *mut xr::EventDataSessionStateChanged, event) };
            xr::Result::SUCCESS
        }
    })
}

// ---- Vulkan ----

unsafe extern "system" fn graphics_requirements(
    _i: xr::Instance,
    _s: xr::SystemId,
    out: *mut xr::GraphicsRequirementsVulkanKHR,
) -> xr::Result {
    let out = unsafe { &mut *out };
    out.min_api_version_supported = xr::Version::new(1, 0, 0);
    out.max_api_version_supported = xr::Version::new(1, 3, 0);
    with(|s| {
        s.requirements_queried = true;
        s.report.requirements_queried = true;
    });
    xr::Result::SUCCESS
}

unsafe extern "system" fn create_vulkan_instance(
    _i: xr::Instance,
    info: *const xr::VulkanInstanceCreateInfoKHR,
    out: *mut xr::platform::VkInstance,
    vk_result: *mut xr::platform::VkResult,
) -> xr::Result {
    let info = unsafe { &*info };
    with(|s| {
        if !s.requirements_queried {
            return xr::Result::ERROR_GRAPHICS_REQUIREMENTS_CALL_MISSING;
        }
        let Some(gipa) = info.pfn_get_instance_proc_addr else {
            return violation(s, "no pfnGetInstanceProcAddr".into());
        };
        // SAFETY: both are the Vulkan loader's vkGetInstanceProcAddr type.
        let gipa: vk::PFN_vkGetInstanceProcAddr = unsafe { std::mem::transmute(gipa) };
        // SAFETY: `gipa` is the application's Vulkan loader entry point.
        let entry = unsafe {
            ash::Entry::from_static_fn(ash::StaticFn {
                get_instance_proc_addr: gipa,
            })
        };
        let create = unsafe { &*(info.vulkan_create_info as *const vk::InstanceCreateInfo) };
        let version = unsafe { create.p_application_info.as_ref() }
            .map(|a| a.api_version)
            .unwrap_or(0);
        if version < vk::API_VERSION_1_1 {
            violation(s, format!("Vulkan instance asks for {version:#x} < 1.1"));
        }
        // SAFETY: the application's create info, valid for the call (module notes).
        match unsafe { entry.create_instance(create, None) } {
            Ok(instance) => {
                unsafe { *out = instance.handle().as_raw() as usize as _ };
                unsafe { *vk_result = 0 };
                s.vulkan = Some(VulkanSide {
                    gipa,
                    instance: Some(instance),
                    physical: vk::PhysicalDevice::null(),
                    device: None,
                    queue: None,
                });
                s.report.vulkan_instance_created = true;
            }
            Err(e) => unsafe { *vk_result = e.as_raw() },
        }
        xr::Result::SUCCESS
    })
}

unsafe extern "system" fn graphics_device(
    _i: xr::Instance,
    info: *const xr::VulkanGraphicsDeviceGetInfoKHR,
    out: *mut xr::platform::VkPhysicalDevice,
) -> xr::Result {
    let info = unsafe { &*info };
    with(|s| {
        let Some(v) = s.vulkan.as_mut() else {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        };
        let Some(instance) = &v.instance else {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        };
        if instance.handle().as_raw() as usize != info.vulkan_instance as usize {
            return violation(
                s,
                "device asked for an instance not made by xrCreateVulkanInstanceKHR".into(),
            );
        }
        // SAFETY: the instance this runtime created.
        let devices = unsafe { instance.enumerate_physical_devices() }.unwrap_or_default();
        let Some(&physical) = devices.first() else {
            return xr::Result::ERROR_RUNTIME_FAILURE;
        };
        v.physical = physical;
        unsafe { *out = physical.as_raw() as usize as _ };
        xr::Result::SUCCESS
    })
}

unsafe extern "system" fn create_vulkan_device(
    _i: xr::Instance,
    info: *const xr::VulkanDeviceCreateInfoKHR,
    out: *mut xr::platform::VkDevice,
    vk_result: *mut xr::platform::VkResult,
) -> xr::Result {
    let info = unsafe { &*info };
    with(|s| {
        let Some(v) = s.vulkan.as_mut() else {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        };
        let physical = vk::PhysicalDevice::from_raw(info.vulkan_physical_device as usize as u64);
        if physical != v.physical || physical == vk::PhysicalDevice::null() {
            return xr::Result::ERROR_HANDLE_INVALID;
        }
        let Some(instance) = &v.instance else {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        };
        let create = unsafe { &*(info.vulkan_create_info as *const vk::DeviceCreateInfo) };
        // SAFETY: `physical` was checked to be the device named above; the
        // create info is the application's.
        match unsafe { instance.create_device(physical, create, None) } {
            Ok(device) => {
                unsafe { *out = device.handle().as_raw() as usize as _ };
                unsafe { *vk_result = 0 };
                v.device = Some(device);
                s.report.vulkan_device_created = true;
            }
            Err(e) => unsafe { *vk_result = e.as_raw() },
        }
        let _ = v.gipa;
        xr::Result::SUCCESS
    })
}

// ---- session ----

unsafe extern "system" fn create_session(
    _i: xr::Instance,
    info: *const xr::SessionCreateInfo,
    out: *mut xr::Session,
) -> xr::Result {
    let info = unsafe { &*info };
    with(|s| {
        if !s.requirements_queried {
            return xr::Result::ERROR_GRAPHICS_REQUIREMENTS_CALL_MISSING;
        }
        let binding = info.next as *const xr::GraphicsBindingVulkanKHR;
        if binding.is_null() || unsafe { (*binding).ty } != xr::GraphicsBindingVulkanKHR::TYPE {
            return violation(s, "session without a Vulkan graphics binding".into());
        }
        let b = unsafe { &*binding };
        let Some(v) = &s.vulkan else {
            return xr::Result::ERROR_GRAPHICS_DEVICE_INVALID;
        };
        let same = v.instance.as_ref().map(|i| i.handle().as_raw() as usize)
            == Some(b.instance as usize)
            && v.physical.as_raw() as usize == b.physical_device as usize
            && v.device.as_ref().map(|d| d.handle().as_raw() as usize) == Some(b.device as usize);
        if !same {
            return violation(
                s,
                "session binding is not the Vulkan objects made through the runtime".into(),
            );
        }
        if let Some(v) = s.vulkan.as_mut() {
            if let Some(device) = &v.device {
                // SAFETY: the binding names a queue of the device created above
                // (checked: same handles).
                let queue = unsafe { device.get_device_queue(b.queue_family_index, b.queue_index) };
                v.queue = Some((b.queue_family_index, queue));
            }
        }
        let id = handle(s);
        s.sessions.insert(id, Session::default());
        s.report.sessions_created += 1;
        push_state(s, id, xr::SessionState::IDLE);
        push_state(s, id, xr::SessionState::READY);
        unsafe { *out = xr::Session::from_raw(id) };
        xr::Result::SUCCESS
    })
}

unsafe extern "system" fn destroy_session(session: xr::Session) -> xr::Result {
    with(|s| {
        let id = session.into_raw();
        if s.swapchains.values().any(|c| c.session == id) {
            violation(s, "session destroyed before its swapchains".into());
        }
        if s.spaces.values().any(|(sess, _)| *sess == id) {
            violation(s, "session destroyed before its spaces".into());
        }
        if let Some(sess) = s.sessions.remove(&id) {
            if sess.running && !sess.lost {
                violation(s, "running session destroyed without xrEndSession".into());
            }
        }
        s.report.sessions_destroyed += 1;
        xr::Result::SUCCESS
    })
}

fn session_mut(s: &mut State, session: xr::Session) -> Option<&mut Session> {
    s.sessions.get_mut(&session.into_raw())
}

unsafe extern "system" fn begin_session(
    session: xr::Session,
    info: *const xr::SessionBeginInfo,
) -> xr::Result {
    let view = unsafe { (*info).primary_view_configuration_type };
    with(|s| {
        let id = session.into_raw();
        let Some(sess) = session_mut(s, session) else {
            return xr::Result::ERROR_HANDLE_INVALID;
        };
        if sess.state != xr::SessionState::READY.into_raw() {
            return xr::Result::ERROR_SESSION_NOT_READY;
        }
        if view != xr::ViewConfigurationType::PRIMARY_STEREO {
            return xr::Result::ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
        }
        sess.running = true;
        s.report.sessions_begun += 1;
        push_state(s, id, xr::SessionState::SYNCHRONIZED);
        xr::Result::SUCCESS
    })
}

unsafe extern "system" fn end_session(session: xr::Session) -> xr::Result {
    with(|s| {
        let id = session.into_raw();
        let Some(sess) = session_mut(s, session) else {
            return xr::Result::ERROR_HANDLE_INVALID;
        };
        if sess.state != xr::SessionState::STOPPING.into_raw() {
            return xr::Result::ERROR_SESSION_NOT_STOPPING;
        }
        sess.running = false;
        s.report.sessions_ended += 1;
        push_state(s, id, xr::SessionState::IDLE);
        push_state(s, id, xr::SessionState::EXITING);
        xr::Result::SUCCESS
    })
}

unsafe extern "system" fn request_exit(session: xr::Session) -> xr::Result {
    with(|s| {
        let id = session.into_raw();
        let Some(sess) = session_mut(s, session) else {
            return xr::Result::ERROR_HANDLE_INVALID;
        };
        if !sess.running {
            return xr::Result::ERROR_SESSION_NOT_RUNNING;
        }
        sess.exit_requested = true;
        let from = sess.state;
        s.report.exit_requests += 1;
        if from == xr::SessionState::FOCUSED.into_raw() {
            push_state(s, id, xr::SessionState::VISIBLE);
        }
        if from >= xr::SessionState::VISIBLE.into_raw() {
            push_state(s, id, xr::SessionState::SYNCHRONIZED);
        }
        push_state(s, id, xr::SessionState::STOPPING);
        xr::Result::SUCCESS
    })
}

// ---- spaces and views ----

unsafe extern "system" fn reference_spaces(
    _session: xr::Session,
    cap: u32,
    count: *mut u32,
    out: *mut xr::ReferenceSpaceType,
) -> xr::Result {
    let no_stage = with(|s| s.no_stage);
    let mut spaces = vec![xr::ReferenceSpaceType::VIEW, xr::ReferenceSpaceType::LOCAL];
    if !no_stage {
        spaces.push(xr::ReferenceSpaceType::STAGE);
    }
    unsafe { fill(cap, count, out, &spaces) }
}

unsafe extern "system" fn create_reference_space(
    session: xr::Session,
    info: *const xr::ReferenceSpaceCreateInfo,
    out: *mut xr::Space,
) -> xr::Result {
    let kind = unsafe { (*info).reference_space_type };
    with(|s| {
        if kind == xr::ReferenceSpaceType::STAGE && s.no_stage {
            return xr::Result::ERROR_REFERENCE_SPACE_UNSUPPORTED;
        }
        let id = handle(s);
        s.spaces.insert(id, (session.into_raw(), kind.into_raw()));
        s.report.reference_spaces.push(kind.into_raw());
        unsafe { *out = xr::Space::from_raw(id) };
        xr::Result::SUCCESS
    })
}

unsafe extern "system" fn destroy_space(space: xr::Space) -> xr::Result {
    with(|s| s.spaces.remove(&space.into_raw()));
    xr::Result::SUCCESS
}

unsafe extern "system" fn locate_space(
    space: xr::Space,
    base: xr::Space,
    time: xr::Time,
    out: *mut xr::SpaceLocation,
) -> xr::Result {
    let kinds = with(|s| {
        (
            s.spaces.get(&space.into_raw()).map(|k| k.1),
            s.spaces.get(&base.into_raw()).map(|k| k.1),
        )
    });
    if kinds.0 != Some(xr::ReferenceSpaceType::VIEW.into_raw()) || kinds.1.is_none() {
        return xr::Result::ERROR_HANDLE_INVALID;
    }
    let (p, yaw) = head(time.as_nanos());
    let q = yaw_quat(yaw);
    with(|s| {
        s.report
            .first_head
            .get_or_insert([p.x, p.y, p.z, q.x, q.y, q.z, q.w]);
    });
    let out = unsafe { &mut *out };
    out.location_flags = xr::SpaceLocationFlags::ORIENTATION_VALID
        | xr::SpaceLocationFlags::POSITION_VALID
        | xr::SpaceLocationFlags::ORIENTATION_TRACKED
        | xr::SpaceLocationFlags::POSITION_TRACKED;
    out.pose = xr::Posef {
        orientation: yaw_quat(yaw),
        position: p,
    };
    xr::Result::SUCCESS
}

unsafe extern "system" fn locate_views(
    session: xr::Session,
    info: *const xr::ViewLocateInfo,
    state: *mut xr::ViewState,
    cap: u32,
    count: *mut u32,
    out: *mut xr::View,
) -> xr::Result {
    let info = unsafe { &*info };
    let t = info.display_time.as_nanos();
    let views = eyes(t);
    unsafe {
        (*state).view_state_flags = xr::ViewStateFlags::ORIENTATION_VALID
            | xr::ViewStateFlags::POSITION_VALID
            | xr::ViewStateFlags::ORIENTATION_TRACKED
            | xr::ViewStateFlags::POSITION_TRACKED;
        *count = 2;
    }
    if cap == 0 {
        return xr::Result::SUCCESS;
    }
    if cap < 2 {
        return xr::Result::ERROR_SIZE_INSUFFICIENT;
    }
    for (i, v) in views.iter().enumerate() {
        let slot = unsafe { &mut *out.add(i) };
        slot.pose = v.pose;
        slot.fov = v.fov;
    }
    with(|s| {
        if let Some(sess) = session_mut(s, session) {
            sess.located.insert(
                t,
                [(views[0].pose, views[0].fov), (views[1].pose, views[1].fov)],
            );
        }
    });
    xr::Result::SUCCESS
}

// ---- swapchains ----

unsafe extern "system" fn swapchain_formats(
    _session: xr::Session,
    cap: u32,
    count: *mut u32,
    out: *mut i64,
) -> xr::Result {
    // A float format first, then two sRGB formats: the application should
    // take the first sRGB one.
    let formats = [
        vk::Format::R16G16B16A16_SFLOAT.as_raw() as i64,
        vk::Format::B8G8R8A8_SRGB.as_raw() as i64,
        vk::Format::R8G8B8A8_SRGB.as_raw() as i64,
    ];
    unsafe { fill(cap, count, out, &formats) }
}

unsafe extern "system" fn create_swapchain(
    session: xr::Session,
    info: *const xr::SwapchainCreateInfo,
    out: *mut xr::Swapchain,
) -> xr::Result {
    let info = unsafe { &*info };
    with(|s| {
        s.report.swapchain_formats.push(info.format);
        if info.array_size == 2 {
            s.report.capture_format = info.format;
        }
        s.report
            .swapchain_sizes
            .push((info.width, info.height, info.array_size));
        let Some(device) = s.vulkan.as_ref().and_then(|v| v.device.clone()) else {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        };
        let instance = s.vulkan.as_ref().and_then(|v| v.instance.clone());
        let physical = s.vulkan.as_ref().map(|v| v.physical).unwrap_or_default();
        let is_static = info
            .create_flags
            .contains(xr::SwapchainCreateFlags::STATIC_IMAGE);
        let mut usage = vk::ImageUsageFlags::empty();
        if info
            .usage_flags
            .contains(xr::SwapchainUsageFlags::COLOR_ATTACHMENT)
        {
            usage |= vk::ImageUsageFlags::COLOR_ATTACHMENT;
        }
        if info
            .usage_flags
            .contains(xr::SwapchainUsageFlags::TRANSFER_DST)
        {
            usage |= vk::ImageUsageFlags::TRANSFER_DST;
        }
        // The runtime samples what it composites.
        usage |= vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        let count = if is_static { 1 } else { 3 };
        let mut images = Vec::new();
        for _ in 0..count {
            let create = vk::ImageCreateInfo::default()
                .image_type(vk::ImageType::TYPE_2D)
                .format(vk::Format::from_raw(info.format as i32))
                .extent(vk::Extent3D {
                    width: info.width,
                    height: info.height,
                    depth: 1,
                })
                .mip_levels(1)
                .array_layers(info.array_size)
                .samples(vk::SampleCountFlags::TYPE_1)
                .tiling(vk::ImageTiling::OPTIMAL)
                .usage(usage)
                .initial_layout(vk::ImageLayout::UNDEFINED);
            // SAFETY: the application's device (created through this runtime);
            // the create info is local. Images are destroyed with the swapchain.
            let Ok(image) = (unsafe { device.create_image(&create, None) }) else {
                return xr::Result::ERROR_RUNTIME_FAILURE;
            };
            let req = unsafe { device.get_image_memory_requirements(image) };
            let memory_types = instance
                .as_ref()
                .map(|i| unsafe { i.get_physical_device_memory_properties(physical) })
                .unwrap_or_default();
            let type_index = (0..memory_types.memory_type_count)
                .find(|i| req.memory_type_bits & (1 << i) != 0)
                .unwrap_or(0);
            let alloc = vk::MemoryAllocateInfo::default()
                .allocation_size(req.size)
                .memory_type_index(type_index);
            let Ok(memory) = (unsafe { device.allocate_memory(&alloc, None) }) else {
                return xr::Result::ERROR_RUNTIME_FAILURE;
            };
            if unsafe { device.bind_image_memory(image, memory, 0) }.is_err() {
                return xr::Result::ERROR_RUNTIME_FAILURE;
            }
            images.push((image, memory));
        }
        let id = handle(s);
        s.swapchains.insert(
            id,
            Swapchain {
                session: session.into_raw(),
                images,
                width: info.width,
                height: info.height,
                layers: info.array_size,
                is_static,
                ..Swapchain::default()
            },
        );
        unsafe { *out = xr::Swapchain::from_raw(id) };
        xr::Result::SUCCESS
    })
}

unsafe extern "system" fn destroy_swapchain(swapchain: xr::Swapchain) -> xr::Result {
    with(|s| {
        let device = s.vulkan.as_ref().and_then(|v| v.device.clone());
        if let (Some(chain), Some(device)) = (s.swapchains.remove(&swapchain.into_raw()), device) {
            // SAFETY: the images belong to this swapchain and device; waiting
            // for idle ends any use of them.
            unsafe {
                let _ = device.device_wait_idle();
                for (image, memory) in chain.images {
                    device.destroy_image(image, None);
                    device.free_memory(memory, None);
                }
            }
        }
    });
    xr::Result::SUCCESS
}

unsafe extern "system" fn swapchain_images(
    swapchain: xr::Swapchain,
    cap: u32,
    count: *mut u32,
    out: *mut xr::SwapchainImageBaseHeader,
) -> xr::Result {
    let images: Vec<u64> = with(|s| {
        s.swapchains
            .get(&swapchain.into_raw())
            .map(|c| c.images.iter().map(|(i, _)| i.as_raw()).collect())
            .unwrap_or_default()
    });
    unsafe { *count = images.len() as u32 };
    if cap == 0 {
        return xr::Result::SUCCESS;
    }
    if (cap as usize) < images.len() {
        return xr::Result::ERROR_SIZE_INSUFFICIENT;
    }
    let out = out as *mut xr::SwapchainImageVulkanKHR;
    for (i, image) in images.iter().enumerate() {
        unsafe { (*out.add(i)).image = *image };
    }
    xr::Result::SUCCESS
}

unsafe extern "system" fn acquire_image(
    swapchain: xr::Swapchain,
    _info: *const c_void,
    index: *mut u32,
) -> xr::Result {
    with(|s| {
        let Some(c) = s.swapchains.get_mut(&swapchain.into_raw()) else {
            return xr::Result::ERROR_HANDLE_INVALID;
        };
        if c.is_static && c.released_once {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        }
        if c.acquired.len() >= c.images.len() {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        }
        let i = c.next;
        c.next = (c.next + 1) % c.images.len() as u32;
        c.acquired.push_back(i);
        c.waited = false;
        unsafe { *index = i };
        xr::Result::SUCCESS
    })
}

unsafe extern "system" fn wait_image(swapchain: xr::Swapchain, _info: *const c_void) -> xr::Result {
    with(|s| {
        let Some(c) = s.swapchains.get_mut(&swapchain.into_raw()) else {
            return xr::Result::ERROR_HANDLE_INVALID;
        };
        if c.acquired.is_empty() {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        }
        c.waited = true;
        xr::Result::SUCCESS
    })
}

unsafe extern "system" fn release_image(
    swapchain: xr::Swapchain,
    _info: *const c_void,
) -> xr::Result {
    with(|s| {
        let Some(c) = s.swapchains.get_mut(&swapchain.into_raw()) else {
            return xr::Result::ERROR_HANDLE_INVALID;
        };
        if !c.waited {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        }
        c.waited = false;
        c.last_released = c.acquired.pop_front();
        c.released_once = true;
        xr::Result::SUCCESS
    })
}

// ---- frames ----

unsafe extern "system" fn wait_frame(
    session: xr::Session,
    _info: *const c_void,
    out: *mut xr::FrameState,
) -> xr::Result {
    std::thread::sleep(std::time::Duration::from_nanos(FRAME_PERIOD_NS as u64));
    with(|s| {
        let Some(sess) = session_mut(s, session) else {
            return xr::Result::ERROR_HANDLE_INVALID;
        };
        if sess.lost {
            return xr::Result::ERROR_SESSION_LOST;
        }
        if !sess.running {
            return xr::Result::ERROR_SESSION_NOT_RUNNING;
        }
        sess.next_time += FRAME_PERIOD_NS;
        sess.last_predicted = sess.next_time;
        sess.frame_waited = true;
        let visible = sess.state == xr::SessionState::VISIBLE.into_raw()
            || sess.state == xr::SessionState::FOCUSED.into_raw();
        let out = unsafe { &mut *out };
        out.predicted_display_time = xr::Time::from_nanos(sess.next_time);
        out.predicted_display_period = xr::Duration::from_nanos(FRAME_PERIOD_NS);
        out.should_render = visible.into();
        s.report.frames_waited += 1;
        xr::Result::SUCCESS
    })
}

unsafe extern "system" fn begin_frame(session: xr::Session, _info: *const c_void) -> xr::Result {
    with(|s| {
        let Some(sess) = session_mut(s, session) else {
            return xr::Result::ERROR_HANDLE_INVALID;
        };
        if sess.lost {
            return xr::Result::ERROR_SESSION_LOST;
        }
        if !sess.frame_waited {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        }
        sess.frame_waited = false;
        sess.frame_begun = true;
        xr::Result::SUCCESS
    })
}

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= 1e-6
}

fn same_pose(a: &xr::Posef, b: &xr::Posef) -> bool {
    close(a.position.x, b.position.x)
        && close(a.position.y, b.position.y)
        && close(a.position.z, b.position.z)
        && close(a.orientation.x, b.orientation.x)
        && close(a.orientation.y, b.orientation.y)
        && close(a.orientation.z, b.orientation.z)
        && close(a.orientation.w, b.orientation.w)
}

unsafe extern "system" fn end_frame(
    session: xr::Session,
    info: *const xr::FrameEndInfo,
) -> xr::Result {
    let info = unsafe { &*info };
    with(|s| {
        let id = session.into_raw();
        let Some(sess) = s.sessions.get_mut(&id) else {
            return xr::Result::ERROR_HANDLE_INVALID;
        };
        if sess.lost {
            return xr::Result::ERROR_SESSION_LOST;
        }
        if !sess.frame_begun {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        }
        sess.frame_begun = false;
        let time = info.display_time.as_nanos();
        let located = sess.located.remove(&time);
        sess.located.retain(|&t, _| t > time);
        let expected_time = sess.last_predicted;
        let state = sess.state;
        let mut problems = Vec::new();
        if time != expected_time {
            problems.push(format!("xrEndFrame at {time}, predicted {expected_time}"));
        }
        if info.environment_blend_mode != xr::EnvironmentBlendMode::OPAQUE {
            problems.push("blend mode is not OPAQUE".into());
        }
        let mut projection = false;
        let mut quad = false;
        let mut shown_image: Option<(vk::Image, u32, u32)> = None;
        let mut submitted_eyes = [[0f32; 11]; 2];
        for i in 0..info.layer_count as usize {
            let header = unsafe { &**info.layers.add(i) };
            if header.ty == xr::CompositionLayerProjection::TYPE {
                projection = true;
                let layer =
                    unsafe { &*(header as *const _ as *const xr::CompositionLayerProjection) };
                if layer.view_count != 2 {
                    problems.push(format!("{} projection views", layer.view_count));
                    continue;
                }
                for v in 0..2usize {
                    let view = unsafe { &*layer.views.add(v) };
                    let (p, o, f) = (view.pose.position, view.pose.orientation, view.fov);
                    submitted_eyes[v] = [
                        p.x,
                        p.y,
                        p.z,
                        o.x,
                        o.y,
                        o.z,
                        o.w,
                        f.angle_left,
                        f.angle_right,
                        f.angle_up,
                        f.angle_down,
                    ];
                    let sub = &view.sub_image;
                    match s.swapchains.get(&sub.swapchain.into_raw()) {
                        None => problems.push("projection view without a swapchain".into()),
                        Some(c) => {
                            match c.last_released {
                                None => problems.push("projection image never released".into()),
                                Some(i) => {
                                    shown_image = Some((c.images[i as usize].0, c.width, c.height))
                                }
                            }
                            if sub.image_array_index != v as u32
                                || sub.image_array_index >= c.layers
                            {
                                problems
                                    .push(format!("view {v} in layer {}", sub.image_array_index));
                            }
                            let r = sub.image_rect;
                            if r.offset.x != 0
                                || r.offset.y != 0
                                || r.extent.width != c.width as i32
                                || r.extent.height != c.height as i32
                            {
                                problems.push(format!("view {v} rect {r:?}"));
                            }
                        }
                    }
                    match &located {
                        None => {
                            problems.push("projection for a time no views were located at".into())
                        }
                        Some(eyes) => {
                            let (pose, fov) = &eyes[v];
                            let f = (view.fov, *fov);
                            if !same_pose(&view.pose, pose)
                                || !close(f.0.angle_left, f.1.angle_left)
                                || !close(f.0.angle_right, f.1.angle_right)
                                || !close(f.0.angle_up, f.1.angle_up)
                                || !close(f.0.angle_down, f.1.angle_down)
                            {
                                problems
                                    .push(format!("view {v} pose/fov differ from the located eye"));
                            }
                        }
                    }
                }
            } else if header.ty == xr::CompositionLayerQuad::TYPE {
                quad = true;
                let layer = unsafe { &*(header as *const _ as *const xr::CompositionLayerQuad) };
                match s.swapchains.get(&layer.sub_image.swapchain.into_raw()) {
                    Some(c) if c.released_once => {}
                    _ => problems.push("quad without a released swapchain image".into()),
                }
            } else {
                problems.push(format!("unexpected layer type {:?}", header.ty));
            }
        }
        let visible = state == xr::SessionState::VISIBLE.into_raw()
            || state == xr::SessionState::FOCUSED.into_raw();
        if projection && !visible {
            // Allowed by the specification, but a waste; `runtime xr` should
            // not render then.
            problems.push("projection submitted while not visible".into());
        }
        if let Some((image, w, h)) = shown_image {
            s.report.last_eyes = Some(submitted_eyes);
            match read_back(s, image, w, h) {
                Ok((stats, differ, bytes)) => {
                    s.report.eye_stats = stats;
                    s.report.eyes_differ = differ;
                    if let Ok(path) = std::env::var("MOCK_XR_CAPTURE") {
                        let _ = std::fs::write(path, &bytes);
                    }
                }
                Err(e) => problems.push(format!("read-back failed: {e:?}")),
            }
        }
        s.report.frames_ended += 1;
        s.ended_total += 1;
        if projection {
            s.report.frames_with_projection += 1;
        }
        if quad {
            s.report.frames_with_quad += 1;
        }
        let ended = s.ended_total;
        // The first frame ended after SYNCHRONIZED makes the session visible
        // and focused.
        let show = s
            .sessions
            .get_mut(&id)
            .map(|x| {
                let show = !x.shown
                    && !x.exit_requested
                    && state == xr::SessionState::SYNCHRONIZED.into_raw();
                x.shown |= show;
                show
            })
            .unwrap_or(false);
        if show {
            push_state(s, id, xr::SessionState::VISIBLE);
            push_state(s, id, xr::SessionState::FOCUSED);
        }
        if s.loss_after == Some(ended) && s.report.sessions_created == 1 {
            if let Some(sess) = s.sessions.get_mut(&id) {
                sess.lost = true;
            }
            push_state(s, id, xr::SessionState::LOSS_PENDING);
        }
        for p in problems {
            violation(s, p);
        }
        xr::Result::SUCCESS
    })
}

// ---- actions ----

unsafe extern "system" fn string_to_path(
    _i: xr::Instance,
    text: *const c_char,
    out: *mut xr::Path,
) -> xr::Result {
    let text = unsafe { cstr(text) }.to_owned();
    if !text.starts_with('/') {
        return xr::Result::ERROR_PATH_FORMAT_INVALID;
    }
    with(|s| {
        let index = match s.paths.iter().position(|p| *p == text) {
            Some(i) => i,
            None => {
                s.paths.push(text);
                s.paths.len() - 1
            }
        };
        unsafe { *out = xr::Path::from_raw(index as u64 + 1) };
        xr::Result::SUCCESS
    })
}

unsafe extern "system" fn create_action_set(
    _i: xr::Instance,
    _info: *const xr::ActionSetCreateInfo,
    out: *mut xr::ActionSet,
) -> xr::Result {
    with(|s| {
        let id = handle(s);
        unsafe { *out = xr::ActionSet::from_raw(id) };
        xr::Result::SUCCESS
    })
}

unsafe extern "system" fn create_action(
    _set: xr::ActionSet,
    info: *const xr::ActionCreateInfo,
    out: *mut xr::Action,
) -> xr::Result {
    let name = unsafe { cstr((*info).action_name.as_ptr()) }.to_owned();
    with(|s| {
        let id = handle(s);
        s.actions.insert(id, name);
        unsafe { *out = xr::Action::from_raw(id) };
        xr::Result::SUCCESS
    })
}

/// Stands in for functions that are never called; every argument is ignored
/// (under the C calling convention a callee may ignore its arguments).
unsafe extern "system" fn unsupported() -> xr::Result {
    xr::Result::ERROR_FUNCTION_UNSUPPORTED
}

unsafe extern "system" fn destroy_nothing(_handle: u64) -> xr::Result {
    xr::Result::SUCCESS
}

unsafe extern "system" fn suggest_bindings(
    _i: xr::Instance,
    info: *const xr::InteractionProfileSuggestedBinding,
) -> xr::Result {
    let info = unsafe { &*info };
    with(|s| {
        let profile = s
            .paths
            .get(info.interaction_profile.into_raw() as usize - 1)
            .cloned()
            .unwrap_or_default();
        // Like a runtime that knows only two profiles.
        if profile.ends_with("khr/simple_controller")
            || profile.ends_with("oculus/touch_controller")
        {
            s.report.profiles_accepted.push(profile);
            xr::Result::SUCCESS
        } else {
            s.report.profiles_refused.push(profile);
            xr::Result::ERROR_PATH_UNSUPPORTED
        }
    })
}

unsafe extern "system" fn attach_action_sets(
    session: xr::Session,
    _info: *const xr::SessionActionSetsAttachInfo,
) -> xr::Result {
    with(|s| match session_mut(s, session) {
        Some(sess) if sess.attached => xr::Result::ERROR_ACTIONSETS_ALREADY_ATTACHED,
        Some(sess) => {
            sess.attached = true;
            xr::Result::SUCCESS
        }
        None => xr::Result::ERROR_HANDLE_INVALID,
    })
}

unsafe extern "system" fn sync_actions(session: xr::Session, _info: *const c_void) -> xr::Result {
    with(|s| match session_mut(s, session) {
        Some(sess) if sess.state == xr::SessionState::FOCUSED.into_raw() => xr::Result::SUCCESS,
        Some(_) => xr::Result::SESSION_NOT_FOCUSED,
        None => xr::Result::ERROR_HANDLE_INVALID,
    })
}

unsafe extern "system" fn action_boolean(
    _session: xr::Session,
    info: *const xr::ActionStateGetInfo,
    out: *mut xr::ActionStateBoolean,
) -> xr::Result {
    let action = unsafe { (*info).action.into_raw() };
    let pressed = with(|s| {
        let help = s.actions.get(&action).is_some_and(|n| n == "help");
        help && s.help_at == Some(s.ended_total)
    });
    let out = unsafe { &mut *out };
    out.current_state = pressed.into();
    out.changed_since_last_sync = pressed.into();
    out.last_change_time = xr::Time::from_nanos(0);
    out.is_active = true.into();
    xr::Result::SUCCESS
}

unsafe extern "system" fn action_vector2(
    _session: xr::Session,
    _info: *const xr::ActionStateGetInfo,
    out: *mut xr::ActionStateVector2f,
) -> xr::Result {
    // `MOCK_XR_WALK=x,y` holds both sticks there (default: centred).
    let (x, y) = std::env::var("MOCK_XR_WALK")
        .ok()
        .and_then(|v| {
            let (a, b) = v.split_once(',')?;
            Some((a.parse().ok()?, b.parse().ok()?))
        })
        .unwrap_or((0.0, 0.0));
    let out = unsafe { &mut *out };
    out.current_state = xr::Vector2f { x, y };
    out.changed_since_last_sync = false.into();
    out.last_change_time = xr::Time::from_nanos(0);
    out.is_active = true.into();
    xr::Result::SUCCESS
}

/// Copies both layers of a released swapchain image (8-bit, 4 channels, in
/// COLOR_ATTACHMENT_OPTIMAL as OpenXR requires) to host memory, as a
/// compositor would read them, and summarises them.
#[allow(clippy::type_complexity)]
fn read_back(
    s: &State,
    image: vk::Image,
    w: u32,
    h: u32,
) -> Result<(Vec<[f64; 4]>, f64, Vec<u8>), vk::Result> {
    let v = s
        .vulkan
        .as_ref()
        .ok_or(vk::Result::ERROR_INITIALIZATION_FAILED)?;
    let (device, instance) = match (&v.device, &v.instance) {
        (Some(d), Some(i)) => (d, i),
        _ => return Err(vk::Result::ERROR_INITIALIZATION_FAILED),
    };
    let (family, queue) = v.queue.ok_or(vk::Result::ERROR_INITIALIZATION_FAILED)?;
    let layer_bytes = u64::from(w) * u64::from(h) * 4;
    // SAFETY: the device and image are the session's (made through this
    // runtime); the image was released, so the application is not using it,
    // and the application's queue is free during xrEndFrame; on success every
    // object made here is destroyed after the queue is idle (an error path
    // leaks them, which a test tolerates).
    unsafe {
        let buffer = device.create_buffer(
            &vk::BufferCreateInfo::default()
                .size(layer_bytes * 2)
                .usage(vk::BufferUsageFlags::TRANSFER_DST),
            None,
        )?;
        let req = device.get_buffer_memory_requirements(buffer);
        let props = instance.get_physical_device_memory_properties(v.physical);
        let wanted = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        let type_index = (0..props.memory_type_count)
            .find(|&i| {
                req.memory_type_bits & (1 << i) != 0
                    && props.memory_types[i as usize]
                        .property_flags
                        .contains(wanted)
            })
            .ok_or(vk::Result::ERROR_FEATURE_NOT_PRESENT)?;
        let memory = device.allocate_memory(
            &vk::MemoryAllocateInfo::default()
                .allocation_size(req.size)
                .memory_type_index(type_index),
            None,
        )?;
        device.bind_buffer_memory(buffer, memory, 0)?;
        let pool = device.create_command_pool(
            &vk::CommandPoolCreateInfo::default().queue_family_index(family),
            None,
        )?;
        let cmd = device.allocate_command_buffers(
            &vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .command_buffer_count(1),
        )?[0];
        device.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())?;
        let range = vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: 2,
        };
        let barrier = |from, to, src, dst| {
            vk::ImageMemoryBarrier::default()
                .old_layout(from)
                .new_layout(to)
                .src_access_mask(src)
                .dst_access_mask(dst)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(image)
                .subresource_range(range)
        };
        device.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
            vk::PipelineStageFlags::TRANSFER,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &[barrier(
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
                vk::AccessFlags::TRANSFER_READ,
            )],
        );
        let regions: Vec<vk::BufferImageCopy> = (0..2u32)
            .map(|layer| {
                vk::BufferImageCopy::default()
                    .buffer_offset(u64::from(layer) * layer_bytes)
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
            })
            .collect();
        device.cmd_copy_image_to_buffer(
            cmd,
            image,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            buffer,
            &regions,
        );
        device.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::BOTTOM_OF_PIPE,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &[barrier(
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::AccessFlags::TRANSFER_READ,
                vk::AccessFlags::empty(),
            )],
        );
        device.end_command_buffer(cmd)?;
        let cmds = [cmd];
        device.queue_submit(
            queue,
            &[vk::SubmitInfo::default().command_buffers(&cmds)],
            vk::Fence::null(),
        )?;
        device.queue_wait_idle(queue)?;
        let ptr = device.map_memory(memory, 0, layer_bytes * 2, vk::MemoryMapFlags::empty())?
            as *const u8;
        let bytes = std::slice::from_raw_parts(ptr, (layer_bytes * 2) as usize).to_vec();
        device.unmap_memory(memory);
        device.destroy_command_pool(pool, None);
        device.destroy_buffer(buffer, None);
        device.free_memory(memory, None);

        let (left, right) = bytes.split_at(layer_bytes as usize);
        let stats = [left, right]
            .iter()
            .map(|layer| {
                let n = (w * h) as f64;
                let mut sum = [0.0f64; 3];
                let mut lit = 0usize;
                for px in layer.chunks_exact(4) {
                    for c in 0..3 {
                        sum[c] += f64::from(px[c]);
                    }
                    if px[..3].iter().any(|&b| b > 0) {
                        lit += 1;
                    }
                }
                [sum[0] / n, sum[1] / n, sum[2] / n, lit as f64 / n]
            })
            .collect();
        let differ = left
            .chunks_exact(4)
            .zip(right.chunks_exact(4))
            .filter(|(a, b)| a[..3] != b[..3])
            .count() as f64
            / f64::from(w * h);
        Ok((stats, differ, bytes))
    }
}
