//! The frame loop: wait (paced at the frame period), begin, and end, which
//! checks the submitted layers against the located eyes and released images.

use crate::state::*;
use crate::*;
use ash::vk;
use openxr::sys as xr;
use std::ffi::c_void;

pub(crate) unsafe extern "system" fn wait_frame(
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
        // SAFETY: `out` is valid for writing (the loader's pointer contract: crate notes).
        let out = unsafe { &mut *out };
        out.predicted_display_time = xr::Time::from_nanos(sess.next_time);
        out.predicted_display_period = xr::Duration::from_nanos(FRAME_PERIOD_NS);
        out.should_render = visible.into();
        s.report.frames_waited += 1;
        xr::Result::SUCCESS
    })
}

pub(crate) unsafe extern "system" fn begin_frame(
    session: xr::Session,
    _info: *const c_void,
) -> xr::Result {
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

pub(crate) fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= 1e-6
}

pub(crate) fn same_pose(a: &xr::Posef, b: &xr::Posef) -> bool {
    close(a.position.x, b.position.x)
        && close(a.position.y, b.position.y)
        && close(a.position.z, b.position.z)
        && close(a.orientation.x, b.orientation.x)
        && close(a.orientation.y, b.orientation.y)
        && close(a.orientation.z, b.orientation.z)
        && close(a.orientation.w, b.orientation.w)
}

pub(crate) unsafe extern "system" fn end_frame(
    session: xr::Session,
    info: *const xr::FrameEndInfo,
) -> xr::Result {
    // SAFETY: `info` is valid for reading (the loader's pointer contract: crate notes).
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
            // SAFETY: `i < layer_count`, and `layers` holds that many valid layer pointers (the loader's pointer contract: crate notes).
            let header = unsafe { &**info.layers.add(i) };
            if header.ty == xr::CompositionLayerProjection::TYPE {
                projection = true;
                let layer =
                    // SAFETY: the header's `ty`, checked above, says which layer structure it begins; `layers[i]` is valid for reading (crate notes).
                    unsafe { &*(header as *const _ as *const xr::CompositionLayerProjection) };
                // SAFETY: `layer` came through the loader's pointer contract (crate notes).
                unsafe {
                    check_projection(
                        s,
                        layer,
                        located.as_ref(),
                        &mut problems,
                        &mut shown_image,
                        &mut submitted_eyes,
                    )
                };
            } else if header.ty == xr::CompositionLayerQuad::TYPE {
                quad = true;
                // SAFETY: the header's `ty`, checked above, says which layer structure it begins; `layers[i]` is valid for reading (crate notes).
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
                    if let Some(path) = script::capture_path() {
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

/// Checks a projection layer's two views against their swapchains (an image
/// released, the view's own array layer, the whole image) and against the eyes
/// located for the frame's time, pushing what is wrong to `problems`; notes the
/// image shown and the submitted poses and fields of view.
///
/// # Safety
///
/// `layer.views` holds `layer.view_count` valid views (the loader's pointer
/// contract: crate notes).
unsafe fn check_projection(
    s: &State,
    layer: &xr::CompositionLayerProjection,
    located: Option<&[(xr::Posef, xr::Fovf); 2]>,
    problems: &mut Vec<String>,
    shown_image: &mut Option<(vk::Image, u32, u32)>,
    submitted_eyes: &mut [[f32; 11]; 2],
) {
    if layer.view_count != 2 {
        problems.push(format!("{} projection views", layer.view_count));
        return;
    }
    for v in 0..2usize {
        // SAFETY: `v < view_count`, and `views` holds that many views (the loader's pointer contract: crate notes).
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
                    Some(i) => *shown_image = Some((c.images[i as usize].0, c.width, c.height)),
                }
                if sub.image_array_index != v as u32 || sub.image_array_index >= c.layers {
                    problems.push(format!("view {v} in layer {}", sub.image_array_index));
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
        match located {
            None => problems.push("projection for a time no views were located at".into()),
            Some(eyes) => {
                let (pose, fov) = &eyes[v];
                let f = (view.fov, *fov);
                if !same_pose(&view.pose, pose)
                    || !close(f.0.angle_left, f.1.angle_left)
                    || !close(f.0.angle_right, f.1.angle_right)
                    || !close(f.0.angle_up, f.1.angle_up)
                    || !close(f.0.angle_down, f.1.angle_down)
                {
                    problems.push(format!("view {v} pose/fov differ from the located eye"));
                }
            }
        }
    }
}
