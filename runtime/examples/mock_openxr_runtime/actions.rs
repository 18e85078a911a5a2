//! Actions: paths, action sets and actions, suggested bindings, attachment,
//! and the scripted button and thumbstick states.

use crate::ffi::*;
use crate::state::*;
use crate::*;
use openxr::sys as xr;
use std::ffi::{c_char, c_void};

pub(crate) unsafe extern "system" fn string_to_path(
    _i: xr::Instance,
    text: *const c_char,
    out: *mut xr::Path,
) -> xr::Result {
    // SAFETY: the name is a NUL-terminated string (the loader's pointer contract: crate notes).
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
        // SAFETY: `out` is valid for writing (the loader's pointer contract: crate notes).
        unsafe { *out = xr::Path::from_raw(index as u64 + 1) };
        xr::Result::SUCCESS
    })
}

pub(crate) unsafe extern "system" fn create_action_set(
    _i: xr::Instance,
    _info: *const xr::ActionSetCreateInfo,
    out: *mut xr::ActionSet,
) -> xr::Result {
    with(|s| {
        let id = handle(s);
        // SAFETY: `out` is valid for writing (the loader's pointer contract: crate notes).
        unsafe { *out = xr::ActionSet::from_raw(id) };
        xr::Result::SUCCESS
    })
}

pub(crate) unsafe extern "system" fn create_action(
    _set: xr::ActionSet,
    info: *const xr::ActionCreateInfo,
    out: *mut xr::Action,
) -> xr::Result {
    // SAFETY: `info` is valid for reading and its name is NUL-terminated (the loader's pointer contract: crate notes).
    let name = unsafe { cstr((*info).action_name.as_ptr()) }.to_owned();
    with(|s| {
        let id = handle(s);
        s.actions.insert(id, name);
        // SAFETY: `out` is valid for writing (the loader's pointer contract: crate notes).
        unsafe { *out = xr::Action::from_raw(id) };
        xr::Result::SUCCESS
    })
}

/// Stands in for functions that are never called; every argument is ignored
/// (under the C calling convention a callee may ignore its arguments).
pub(crate) unsafe extern "system" fn unsupported() -> xr::Result {
    xr::Result::ERROR_FUNCTION_UNSUPPORTED
}

pub(crate) unsafe extern "system" fn destroy_nothing(_handle: u64) -> xr::Result {
    xr::Result::SUCCESS
}

pub(crate) unsafe extern "system" fn suggest_bindings(
    _i: xr::Instance,
    info: *const xr::InteractionProfileSuggestedBinding,
) -> xr::Result {
    // SAFETY: `info` is valid for reading (the loader's pointer contract: crate notes).
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

pub(crate) unsafe extern "system" fn attach_action_sets(
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

pub(crate) unsafe extern "system" fn sync_actions(
    session: xr::Session,
    _info: *const c_void,
) -> xr::Result {
    with(|s| match session_mut(s, session) {
        Some(sess) if sess.state == xr::SessionState::FOCUSED.into_raw() => xr::Result::SUCCESS,
        Some(_) => xr::Result::SESSION_NOT_FOCUSED,
        None => xr::Result::ERROR_HANDLE_INVALID,
    })
}

pub(crate) unsafe extern "system" fn action_boolean(
    _session: xr::Session,
    info: *const xr::ActionStateGetInfo,
    out: *mut xr::ActionStateBoolean,
) -> xr::Result {
    // SAFETY: `info` is valid for reading (the loader's pointer contract: crate notes).
    let action = unsafe { (*info).action.into_raw() };
    let pressed = with(|s| {
        let help = s.actions.get(&action).is_some_and(|n| n == "help");
        help && s.help_at == Some(s.ended_total)
    });
    // SAFETY: `out` is valid for writing (the loader's pointer contract: crate notes).
    let out = unsafe { &mut *out };
    out.current_state = pressed.into();
    out.changed_since_last_sync = pressed.into();
    out.last_change_time = xr::Time::from_nanos(0);
    out.is_active = true.into();
    xr::Result::SUCCESS
}

pub(crate) unsafe extern "system" fn action_vector2(
    _session: xr::Session,
    _info: *const xr::ActionStateGetInfo,
    out: *mut xr::ActionStateVector2f,
) -> xr::Result {
    let (x, y) = script::walk();
    // SAFETY: `out` is valid for writing (the loader's pointer contract: crate notes).
    let out = unsafe { &mut *out };
    out.current_state = xr::Vector2f { x, y };
    out.changed_since_last_sync = false.into();
    out.last_change_time = xr::Time::from_nanos(0);
    out.is_active = true.into();
    xr::Result::SUCCESS
}
