//! Instance and system: extensions, creation and destruction (which writes
//! the report), properties, the one HMD system, its view configuration and
//! blend modes, and the event queue.

use crate::ffi::*;
use crate::state::*;
use crate::*;
use openxr::sys as xr;
use std::ffi::c_char;

pub(crate) unsafe extern "system" fn enumerate_extensions(
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
        // SAFETY: `out` is valid for writing (the loader's pointer contract: crate notes).
        let slot = unsafe { &mut *out };
        slot.extension_name = ext.extension_name;
        slot.extension_version = ext.extension_version;
        // SAFETY: `count` is valid for writing (the loader's pointer contract: crate notes).
        unsafe { *count = 1 };
        return xr::Result::SUCCESS;
    }
    // SAFETY: `count` is valid for writing (the loader's pointer contract: crate notes).
    unsafe { *count = 1 };
    xr::Result::SUCCESS
}

pub(crate) unsafe extern "system" fn create_instance(
    info: *const xr::InstanceCreateInfo,
    instance: *mut xr::Instance,
) -> xr::Result {
    // SAFETY: `info` is valid for reading (the loader's pointer contract: crate notes).
    let info = unsafe { &*info };
    let version = info.application_info.api_version;
    with(|s| {
        *s = State::default();
        script::configure(s);
        if version.major() != 1 || version.minor() > s.max_minor {
            return xr::Result::ERROR_API_VERSION_UNSUPPORTED;
        }
        let names: Vec<&str> = (0..info.enabled_extension_count as usize)
            // SAFETY: `info` names `enabled_extension_count` NUL-terminated strings (the loader's pointer contract: crate notes).
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
        // SAFETY: `instance` is valid for writing (the loader's pointer contract: crate notes).
        unsafe { *instance = xr::Instance::from_raw(s.instance) };
        xr::Result::SUCCESS
    })
}

pub(crate) unsafe extern "system" fn destroy_instance(_instance: xr::Instance) -> xr::Result {
    with(|s| {
        if !s.sessions.is_empty() {
            violation(s, "instance destroyed before its session".into());
        }
        s.report.instance_destroyed = true;
        if let Some(path) = script::report_path() {
            if let Ok(text) = serde_json::to_string_pretty(&s.report) {
                let _ = std::fs::write(path, text);
            }
        }
    });
    xr::Result::SUCCESS
}

pub(crate) unsafe extern "system" fn instance_properties(
    _instance: xr::Instance,
    props: *mut xr::InstanceProperties,
) -> xr::Result {
    // SAFETY: `props` is valid for writing (the loader's pointer contract: crate notes).
    let props = unsafe { &mut *props };
    props.runtime_version = xr::Version::new(0, 1, 0);
    fixed(&mut props.runtime_name, "mock runtime");
    xr::Result::SUCCESS
}

pub(crate) unsafe extern "system" fn get_system(
    _instance: xr::Instance,
    info: *const xr::SystemGetInfo,
    system: *mut xr::SystemId,
) -> xr::Result {
    // SAFETY: `info` is valid for reading (the loader's pointer contract: crate notes).
    if unsafe { (*info).form_factor } != xr::FormFactor::HEAD_MOUNTED_DISPLAY {
        return xr::Result::ERROR_FORM_FACTOR_UNSUPPORTED;
    }
    // SAFETY: `system` is valid for writing (the loader's pointer contract: crate notes).
    unsafe { *system = xr::SystemId::from_raw(1) };
    xr::Result::SUCCESS
}

pub(crate) unsafe extern "system" fn view_configurations(
    _i: xr::Instance,
    _s: xr::SystemId,
    cap: u32,
    count: *mut u32,
    out: *mut xr::ViewConfigurationType,
) -> xr::Result {
    // SAFETY: `count` is valid for writing and `out` for `cap` elements (the two-call idiom; crate notes).
    unsafe {
        fill(
            cap,
            count,
            out,
            &[xr::ViewConfigurationType::PRIMARY_STEREO],
        )
    }
}

pub(crate) unsafe extern "system" fn blend_modes(
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
    // SAFETY: `count` is valid for writing and `out` for `cap` elements (the two-call idiom; crate notes).
    unsafe { fill(cap, count, out, &[xr::EnvironmentBlendMode::OPAQUE]) }
}

pub(crate) unsafe extern "system" fn view_configuration_views(
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
    // SAFETY: `count` is valid for writing and `out` for `cap` elements (the two-call idiom; crate notes).
    unsafe { fill(cap, count, out, &[v, v]) }
}

pub(crate) unsafe extern "system" fn poll_event(
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
            // SAFETY: `buffer` is an XrEventDataBuffer, large enough for any event and valid for writing (the loader's pointer contract: crate notes).
            unsafe { std::ptr::write(buffer as *mut xr::EventDataSessionStateChanged, event) };
            xr::Result::SUCCESS
        }
    })
}
