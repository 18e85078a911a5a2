//! Reference spaces and views: the scripted head (swaying with time) and the
//! two eyes located from it.

use crate::ffi::*;
use crate::state::*;
use crate::*;
use openxr::sys as xr;

/// The head at display time `t`: 1.6 m up, swaying ±5 cm sideways, turning
/// ±5° about +y.
pub(crate) fn head(t: i64) -> (xr::Vector3f, f32) {
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

pub(crate) fn yaw_quat(yaw: f32) -> xr::Quaternionf {
    xr::Quaternionf {
        x: 0.0,
        y: (0.5 * yaw).sin(),
        z: 0.0,
        w: (0.5 * yaw).cos(),
    }
}

pub(crate) fn eyes(t: i64) -> [xr::View; 2] {
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

pub(crate) unsafe extern "system" fn reference_spaces(
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
    // SAFETY: `count` is valid for writing and `out` for `cap` elements (the two-call idiom; crate notes).
    unsafe { fill(cap, count, out, &spaces) }
}

pub(crate) unsafe extern "system" fn create_reference_space(
    session: xr::Session,
    info: *const xr::ReferenceSpaceCreateInfo,
    out: *mut xr::Space,
) -> xr::Result {
    // SAFETY: `info` is valid for reading (the loader's pointer contract: crate notes).
    let kind = unsafe { (*info).reference_space_type };
    with(|s| {
        if kind == xr::ReferenceSpaceType::STAGE && s.no_stage {
            return xr::Result::ERROR_REFERENCE_SPACE_UNSUPPORTED;
        }
        let id = handle(s);
        s.spaces.insert(id, (session.into_raw(), kind.into_raw()));
        s.report.reference_spaces.push(kind.into_raw());
        // SAFETY: `out` is valid for writing (the loader's pointer contract: crate notes).
        unsafe { *out = xr::Space::from_raw(id) };
        xr::Result::SUCCESS
    })
}

pub(crate) unsafe extern "system" fn destroy_space(space: xr::Space) -> xr::Result {
    with(|s| s.spaces.remove(&space.into_raw()));
    xr::Result::SUCCESS
}

pub(crate) unsafe extern "system" fn locate_space(
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
    // SAFETY: `out` is valid for writing (the loader's pointer contract: crate notes).
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

pub(crate) unsafe extern "system" fn locate_views(
    session: xr::Session,
    info: *const xr::ViewLocateInfo,
    state: *mut xr::ViewState,
    cap: u32,
    count: *mut u32,
    out: *mut xr::View,
) -> xr::Result {
    // SAFETY: `info` is valid for reading (the loader's pointer contract: crate notes).
    let info = unsafe { &*info };
    let t = info.display_time.as_nanos();
    let views = eyes(t);
    // SAFETY: `state` and `count` are valid for writing (the loader's pointer
    // contract: crate notes).
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
        // SAFETY: `i < 2 <= cap`, and `out` holds `cap` views (the loader's pointer contract: crate notes).
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
