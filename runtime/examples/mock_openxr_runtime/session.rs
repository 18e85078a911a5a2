//! Sessions and their state machine: creation on the Vulkan objects made
//! through the runtime, begin only when READY, end only when STOPPING, exit
//! requests.

use crate::state::*;
use ash::vk::Handle;
use openxr::sys as xr;

pub(crate) unsafe extern "system" fn create_session(
    _i: xr::Instance,
    info: *const xr::SessionCreateInfo,
    out: *mut xr::Session,
) -> xr::Result {
    // SAFETY: `info` is valid for reading (the loader's pointer contract: crate notes).
    let info = unsafe { &*info };
    with(|s| {
        if !s.requirements_queried {
            return xr::Result::ERROR_GRAPHICS_REQUIREMENTS_CALL_MISSING;
        }
        let binding = info.next as *const xr::GraphicsBindingVulkanKHR;
        // SAFETY: `binding` is valid for reading (the loader's pointer contract: crate notes).
        if binding.is_null() || unsafe { (*binding).ty } != xr::GraphicsBindingVulkanKHR::TYPE {
            return violation(s, "session without a Vulkan graphics binding".into());
        }
        // SAFETY: `binding` is valid for reading (the loader's pointer contract: crate notes).
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
        // SAFETY: `out` is valid for writing (the loader's pointer contract: crate notes).
        unsafe { *out = xr::Session::from_raw(id) };
        xr::Result::SUCCESS
    })
}

pub(crate) unsafe extern "system" fn destroy_session(session: xr::Session) -> xr::Result {
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

pub(crate) fn session_mut(s: &mut State, session: xr::Session) -> Option<&mut Session> {
    s.sessions.get_mut(&session.into_raw())
}

pub(crate) unsafe extern "system" fn begin_session(
    session: xr::Session,
    info: *const xr::SessionBeginInfo,
) -> xr::Result {
    // SAFETY: `info` is valid for reading (the loader's pointer contract: crate notes).
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

pub(crate) unsafe extern "system" fn end_session(session: xr::Session) -> xr::Result {
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

pub(crate) unsafe extern "system" fn request_exit(session: xr::Session) -> xr::Result {
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
