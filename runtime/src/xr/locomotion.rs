//! Where the tracked space sits in the scene, and how the controls move it.
//!
//! OpenXR reports poses in a reference space (LOCAL or STAGE): metres, +y up,
//! the user initially facing −z. The scene has its own up axis (±y or ±z) and
//! units (`units_per_metre` in the solution header). The walker moves by
//! moving the reference space through the scene: [`Locomotion`] holds the
//! space's origin (in file coordinates) and its turn about the scene's up axis.
//! A pose `p` (metres) in the space maps to
//!
//! ```text
//! scene = origin + R_up(yaw) · B · (units_per_metre · p)
//! ```
//!
//! where `B` takes the space's axes to the scene's (`+x → right₀`, `+y → up`,
//! `−z → forward₀`, the same reference axes as the mock session's walk files:
//! forward₀ is −z for a ±y-up scene and +y for a ±z-up one). Positions, the
//! walking speed and the IPD are all in metres until this scale is applied.
//!
//! Controls (the `radview` keys of Remington 1992, app. C.1, translated to
//! what XR users expect): the left stick walks along the head's heading, the right stick
//! snap-turns about the head, and recentring puts the head back at the
//! solution's stored camera, looking its way (`radview`'s `r`, "reset all
//! parameters to default view").

use crate::session::{Pose, ViewState};
use glam::{DMat3, DQuat, DVec2, DVec3};
use solution::camera::UpAxis;

/// Stick deflection that triggers a snap turn, and the deflection below which
/// the stick must return before the next one (hysteresis, so one push is one
/// turn).
pub const SNAP_ENGAGE: f64 = 0.7;
pub const SNAP_RELEASE: f64 = 0.3;

/// The longest time step walking integrates over, seconds: after a stall (the
/// session was hidden, the runtime paused) the walker does not jump.
pub const MAX_STEP_S: f64 = 0.1;

/// The scene's reference axes for a head at yaw 0: (forward₀, right₀).
pub fn reference_axes(up: UpAxis) -> (DVec3, DVec3) {
    let up_v = DVec3::from(up.vector());
    let forward0 = match up {
        UpAxis::PosY | UpAxis::NegY => DVec3::NEG_Z,
        UpAxis::PosZ | UpAxis::NegZ => DVec3::Y,
    };
    (forward0, forward0.cross(up_v))
}

/// `B`: the rotation from the tracking space's axes to the scene's at yaw 0.
pub fn axes_rotation(up: UpAxis) -> DQuat {
    let up_v = DVec3::from(up.vector());
    let (forward0, right0) = reference_axes(up);
    DQuat::from_mat3(&DMat3::from_cols(right0, up_v, -forward0))
}

/// The heading of an orientation in the tracking space, degrees: the turn
/// about +y of its forward (−z) direction, counter-clockwise seen from above
/// (0 = facing −z, +90 = facing −x). Looking straight up or down, the top of
/// the head gives the heading instead.
pub fn heading_deg(orientation: DQuat) -> f64 {
    let flat = horizontal_forward(orientation);
    (-flat.x).atan2(-flat.z).to_degrees()
}

/// The forward direction flattened onto the tracking space's floor plane, unit
/// length.
fn horizontal_forward(orientation: DQuat) -> DVec3 {
    let f = orientation * DVec3::NEG_Z;
    let flat = DVec3::new(f.x, 0.0, f.z);
    if flat.length() > 1e-3 {
        return flat.normalize();
    }
    // Looking straight down, the top of the head points forward; straight up,
    // backward.
    let u = orientation * DVec3::Y;
    let flat = DVec3::new(u.x, 0.0, u.z) * -f.y.signum();
    if flat.length() > 1e-12 {
        flat.normalize()
    } else {
        DVec3::NEG_Z
    }
}

/// The yaw (degrees, [`heading_deg`]'s sense about the scene's up axis) of a
/// view direction in the scene; the pitch is ignored.
pub fn scene_yaw_deg(direction: DVec3, up: UpAxis) -> f64 {
    let (forward0, right0) = reference_axes(up);
    (-direction.dot(right0))
        .atan2(direction.dot(forward0))
        .to_degrees()
}

/// Wraps degrees into (−180, 180].
fn wrap_deg(d: f64) -> f64 {
    let w = d.rem_euclid(360.0);
    if w > 180.0 {
        w - 360.0
    } else {
        w
    }
}

/// Radial dead zone: deflections inside `deadzone` are zero, the rest is
/// rescaled to reach 1 at full deflection, and the length is capped at 1.
pub fn apply_deadzone(stick: DVec2, deadzone: f64) -> DVec2 {
    let len = stick.length();
    if !len.is_finite() || len <= deadzone {
        return DVec2::ZERO;
    }
    let scaled = ((len - deadzone) / (1.0 - deadzone).max(1e-6)).min(1.0);
    stick / len * scaled
}

/// How recentring sets the height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Placement {
    /// LOCAL space: the head goes exactly to the target eye.
    Eye,
    /// STAGE space: the play area's floor goes `eye_height_m` below the
    /// target eye, and the head only moves horizontally onto it (the user's
    /// own height is kept).
    Floor { eye_height_m: f64 },
}

/// The tracking space's place in the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Locomotion {
    /// The tracking space's origin, file coordinates.
    pub origin: DVec3,
    /// Turn of the tracking space about the scene's up axis, degrees.
    pub yaw_deg: f64,
    units_per_metre: f64,
    up: UpAxis,
    snap_armed: bool,
}

impl Locomotion {
    /// The tracking space at the scene's origin, unturned.
    pub fn new(up: UpAxis, units_per_metre: f64) -> Locomotion {
        Locomotion {
            origin: DVec3::ZERO,
            yaw_deg: 0.0,
            units_per_metre,
            up,
            snap_armed: true,
        }
    }

    pub fn units_per_metre(&self) -> f64 {
        self.units_per_metre
    }

    fn up_vector(&self) -> DVec3 {
        DVec3::from(self.up.vector())
    }

    /// `R_up(yaw) · B`.
    pub fn rotation(&self) -> DQuat {
        DQuat::from_axis_angle(self.up_vector(), self.yaw_deg.to_radians()) * axes_rotation(self.up)
    }

    /// A pose in the tracking space (metres) in file coordinates (scene units).
    pub fn to_scene(&self, pose: &Pose) -> Pose {
        let r = self.rotation();
        Pose {
            position: self.origin + r * (pose.position * self.units_per_metre),
            orientation: (r * pose.orientation).normalize(),
        }
    }

    /// A view located in the tracking space, in file coordinates (the field of
    /// view is relative to the pose and does not change).
    pub fn view_to_scene(&self, view: &ViewState) -> ViewState {
        ViewState {
            pose: self.to_scene(&view.pose),
            fov: view.fov,
        }
    }

    /// Puts the head (tracking-space pose) at `target_eye` (file coordinates)
    /// facing `target_yaw_deg` (see [`scene_yaw_deg`]).
    pub fn recentre(
        &mut self,
        head: &Pose,
        target_eye: DVec3,
        target_yaw_deg: f64,
        placement: Placement,
    ) {
        self.yaw_deg = wrap_deg(target_yaw_deg - heading_deg(head.orientation));
        let offset = self.rotation() * (head.position * self.units_per_metre);
        self.origin = match placement {
            Placement::Eye => target_eye - offset,
            Placement::Floor { eye_height_m } => {
                let up = self.up_vector();
                let horizontal = |v: DVec3| v - up * v.dot(up);
                horizontal(target_eye - offset)
                    + up * (target_eye.dot(up) - eye_height_m * self.units_per_metre)
            }
        };
    }

    /// Walks with the (dead-zoned) stick: +y forward along the head's heading,
    /// +x to the right, at `speed_m_s` at full deflection, for `dt` seconds
    /// (capped at [`MAX_STEP_S`]). Returns the displacement in scene units.
    pub fn walk(&mut self, stick: DVec2, head: &Pose, dt: f64, speed_m_s: f64) -> DVec3 {
        let dt = if dt.is_finite() {
            dt.clamp(0.0, MAX_STEP_S)
        } else {
            0.0
        };
        if stick == DVec2::ZERO || dt == 0.0 {
            return DVec3::ZERO;
        }
        let forward = horizontal_forward(head.orientation);
        let right = forward.cross(DVec3::Y);
        let step_m = (forward * stick.y + right * stick.x) * speed_m_s * dt;
        let step = self.rotation() * (step_m * self.units_per_metre);
        self.origin += step;
        step
    }

    /// Snap turn from the right stick's x: a push past [`SNAP_ENGAGE`] turns
    /// by `step_deg` (right: clockwise seen from above), once, about the head,
    /// which keeps its place in the scene; the stick must come back inside
    /// [`SNAP_RELEASE`] before the next turn. Returns the turn made, degrees
    /// (counter-clockwise positive), or 0.
    pub fn snap_turn(&mut self, stick_x: f64, head: &Pose, step_deg: f64) -> f64 {
        if !stick_x.is_finite() {
            return 0.0;
        }
        if self.snap_armed && stick_x.abs() >= SNAP_ENGAGE {
            self.snap_armed = false;
            let turn = -stick_x.signum() * step_deg;
            let pivot = self.to_scene(head).position;
            self.yaw_deg = wrap_deg(self.yaw_deg + turn);
            let r = DQuat::from_axis_angle(self.up_vector(), turn.to_radians());
            self.origin = pivot + r * (self.origin - pivot);
            return turn;
        }
        if stick_x.abs() <= SNAP_RELEASE {
            self.snap_armed = true;
        }
        0.0
    }
}

/// Overrides the distance between two eyes (metres, tracking space): both
/// move symmetrically about their midpoint along the line joining them (or
/// the left eye's +x if they coincide). Anything but two views is returned
/// unchanged.
pub fn with_ipd(views: &[ViewState], ipd_m: f64) -> Vec<ViewState> {
    let mut out = views.to_vec();
    if let [left, right] = &mut out[..] {
        let mid = 0.5 * (left.pose.position + right.pose.position);
        let mut axis = right.pose.position - left.pose.position;
        if axis.length() < 1e-9 {
            axis = left.pose.orientation * DVec3::X;
        }
        let axis = axis.normalize();
        left.pose.position = mid - axis * (0.5 * ipd_m);
        right.pose.position = mid + axis * (0.5 * ipd_m);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use solution::camera::Fov;

    const UPS: [UpAxis; 4] = [UpAxis::PosY, UpAxis::NegY, UpAxis::PosZ, UpAxis::NegZ];

    fn pose(position: DVec3, heading_deg: f64) -> Pose {
        Pose {
            position,
            orientation: DQuat::from_rotation_y(heading_deg.to_radians()),
        }
    }

    fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
        (a - b).length() <= tol
    }

    // Tolerances: every result is a handful of f64 rotations and additions of
    // O(100) values, so 1e-9 absolute is far above rounding (≈1e-13).

    #[test]
    fn axes_map_tracking_space_to_the_scene() {
        for up in UPS {
            let up_v = DVec3::from(up.vector());
            let (f0, r0) = reference_axes(up);
            let b = axes_rotation(up);
            assert!(close(b * DVec3::Y, up_v, 1e-12), "{up:?}");
            assert!(close(b * DVec3::NEG_Z, f0, 1e-12), "{up:?}");
            assert!(close(b * DVec3::X, r0, 1e-12), "{up:?}");
            // A proper rotation (no mirror): right × up = −forward.
            assert!(close(r0.cross(up_v), -f0, 1e-12), "{up:?}");
        }
    }

    #[test]
    fn poses_are_scaled_from_metres() {
        // A centimetre scene: one metre of head motion is 100 units.
        let mut loco = Locomotion::new(UpAxis::PosZ, 100.0);
        loco.origin = DVec3::new(5.0, 6.0, 7.0);
        let p = loco.to_scene(&pose(DVec3::new(1.0, 2.0, -3.0), 0.0));
        // +x → +x, +y (up) → +z, −z (forward) → +y for a +z-up scene.
        assert!(close(p.position, DVec3::new(105.0, 306.0, 207.0), 1e-9));
        // The head looks along the scene's forward₀ (+y).
        assert!(close(p.orientation * DVec3::NEG_Z, DVec3::Y, 1e-12));
    }

    #[test]
    fn heading_and_scene_yaw_agree() {
        for up in UPS {
            for yaw in [0.0, 30.0, -90.0, 135.0] {
                let mut loco = Locomotion::new(up, 1.0);
                loco.yaw_deg = yaw;
                for h in [0.0, 45.0, -170.0] {
                    let p = loco.to_scene(&pose(DVec3::ZERO, h));
                    let dir = p.orientation * DVec3::NEG_Z;
                    let got = scene_yaw_deg(dir, up);
                    assert!(
                        wrap_deg(got - (yaw + h)).abs() < 1e-9,
                        "{up:?} yaw {yaw} heading {h}: {got}"
                    );
                }
            }
        }
        // Looking straight down with the head's top toward −x: heading +90°.
        let down = DQuat::from_rotation_y(90f64.to_radians())
            * DQuat::from_rotation_x(-90f64.to_radians());
        assert!((heading_deg(down) - 90.0).abs() < 1e-9);
    }

    #[test]
    fn recentre_puts_the_head_at_the_camera() {
        for up in UPS {
            let up_v = DVec3::from(up.vector());
            let mut loco = Locomotion::new(up, 39.37);
            let head = Pose {
                position: DVec3::new(0.3, 1.7, -0.4),
                orientation: DQuat::from_rotation_y(0.7) * DQuat::from_rotation_x(0.2),
            };
            let eye = DVec3::new(10.0, -20.0, 30.0);
            loco.recentre(&head, eye, 60.0, Placement::Eye);
            let p = loco.to_scene(&head);
            assert!(close(p.position, eye, 1e-9), "{up:?}");
            let yaw = scene_yaw_deg(p.orientation * DVec3::NEG_Z, up);
            assert!((yaw - 60.0).abs() < 1e-9, "{up:?} {yaw}");

            // STAGE: horizontally at the eye, the floor 1.6 m below it, the
            // user's own 1.7 m eye height kept.
            loco.recentre(&head, eye, 60.0, Placement::Floor { eye_height_m: 1.6 });
            let p = loco.to_scene(&head);
            let horizontal = |v: DVec3| v - up_v * v.dot(up_v);
            assert!(close(horizontal(p.position), horizontal(eye), 1e-9));
            assert!((loco.origin.dot(up_v) - (eye.dot(up_v) - 1.6 * 39.37)).abs() < 1e-9);
            assert!((p.position.dot(up_v) - (eye.dot(up_v) + 0.1 * 39.37)).abs() < 1e-9);
        }
    }

    #[test]
    fn walking_follows_the_heading_at_the_scaled_speed() {
        let mut loco = Locomotion::new(UpAxis::PosY, 100.0);
        // Head turned 90° left (facing −x) and pitched down 30°: walking
        // forward still moves horizontally along −x.
        let head = Pose {
            position: DVec3::new(0.0, 1.6, 0.0),
            orientation: DQuat::from_rotation_y(90f64.to_radians())
                * DQuat::from_rotation_x(-30f64.to_radians()),
        };
        // 0.05 s at full stick and 1.4 m/s: 0.07 m = 7 units.
        let step = loco.walk(DVec2::new(0.0, 1.0), &head, 0.05, 1.4);
        assert!(close(step, DVec3::new(-7.0, 0.0, 0.0), 1e-9), "{step}");
        // Right stick-x strafes to the head's right (−z when facing −x... the
        // right of −x is −z in a +y-up right-handed space).
        let step = loco.walk(DVec2::new(1.0, 0.0), &head, 0.05, 1.4);
        assert!(close(step, DVec3::new(0.0, 0.0, -7.0), 1e-9), "{step}");
        // A stall does not teleport: the step is capped at MAX_STEP_S.
        let step = loco.walk(DVec2::new(0.0, 1.0), &head, 5.0, 1.4);
        assert!((step.length() - 1.4 * MAX_STEP_S * 100.0).abs() < 1e-9);
        // The space's own turn applies too: turned 90° more, forward is +z.
        loco.yaw_deg = 90.0;
        let step = loco.walk(DVec2::new(0.0, 1.0), &head, 0.05, 1.4);
        assert!(close(step, DVec3::new(0.0, 0.0, 7.0), 1e-9), "{step}");
    }

    #[test]
    fn deadzone_zeroes_small_deflections_and_rescales() {
        assert_eq!(apply_deadzone(DVec2::new(0.1, 0.1), 0.2), DVec2::ZERO);
        let v = apply_deadzone(DVec2::new(0.6, 0.0), 0.2);
        assert!((v.x - 0.5).abs() < 1e-12 && v.y == 0.0);
        let v = apply_deadzone(DVec2::new(1.0, 1.0), 0.2);
        assert!((v.length() - 1.0).abs() < 1e-12);
        assert_eq!(apply_deadzone(DVec2::new(f64::NAN, 0.0), 0.2), DVec2::ZERO);
    }

    #[test]
    fn snap_turn_turns_once_per_push_about_the_head() {
        for up in UPS {
            let mut loco = Locomotion::new(up, 2.5);
            loco.origin = DVec3::new(1.0, 2.0, 3.0);
            let head = pose(DVec3::new(0.4, 1.5, -0.8), 20.0);
            let before = loco.to_scene(&head);
            let yaw_before = scene_yaw_deg(before.orientation * DVec3::NEG_Z, up);
            // Push right: one clockwise 30° turn, however long it is held.
            assert_eq!(loco.snap_turn(0.9, &head, 30.0), -30.0);
            assert_eq!(loco.snap_turn(1.0, &head, 30.0), 0.0);
            assert_eq!(loco.snap_turn(0.5, &head, 30.0), 0.0);
            let after = loco.to_scene(&head);
            assert!(close(after.position, before.position, 1e-9), "{up:?}");
            let yaw_after = scene_yaw_deg(after.orientation * DVec3::NEG_Z, up);
            assert!((wrap_deg(yaw_after - yaw_before) + 30.0).abs() < 1e-9);
            // Released, then pushed left: a counter-clockwise turn.
            assert_eq!(loco.snap_turn(0.1, &head, 30.0), 0.0);
            assert_eq!(loco.snap_turn(-0.8, &head, 30.0), 30.0);
            assert!(close(loco.to_scene(&head).position, before.position, 1e-9));
        }
    }

    #[test]
    fn ipd_override_is_symmetric_and_scaled() {
        let fov = Fov::symmetric(1.5, 320, 240);
        let q = DQuat::from_rotation_y(0.3);
        let eye = |x: f64| ViewState {
            pose: Pose {
                position: q * DVec3::new(x, 0.0, 0.0) + DVec3::new(0.0, 1.6, 0.0),
                orientation: q,
            },
            fov,
        };
        let views = with_ipd(&[eye(-0.031), eye(0.033)], 0.070);
        let mid_before = DVec3::new(0.0, 1.6, 0.0) + q * DVec3::new(0.001, 0.0, 0.0);
        let mid = 0.5 * (views[0].pose.position + views[1].pose.position);
        assert!(close(mid, mid_before, 1e-12));
        let sep = views[1].pose.position - views[0].pose.position;
        assert!((sep.length() - 0.070).abs() < 1e-12);
        assert!(close(sep.normalize(), q * DVec3::X, 1e-12));
        // In a 100-units-per-metre scene the eyes are 7 units apart.
        let loco = Locomotion::new(UpAxis::PosY, 100.0);
        let a = loco.view_to_scene(&views[0]).pose.position;
        let b = loco.view_to_scene(&views[1]).pose.position;
        assert!(((b - a).length() - 7.0).abs() < 1e-9);
        // Coincident eyes separate along the left eye's +x.
        let views = with_ipd(&[eye(0.0), eye(0.0)], 0.064);
        assert!(close(
            views[1].pose.position - views[0].pose.position,
            q * DVec3::new(0.064, 0.0, 0.0),
            1e-12
        ));
    }

    /// The XR start pose of a scene without a camera: the solver stores its
    /// default view as the header camera, an eye [`EYE_HEIGHT_M`] above a
    /// floor (the chooser's own tests, in the solver, check that it stands
    /// so), and STAGE space with the default eye height puts the user's feet on
    /// the floor that a downward ray from that eye meets (through the
    /// contract crate's triangle BVH), looking where the view looks.
    ///
    /// [`EYE_HEIGHT_M`]: solution::view::EYE_HEIGHT_M
    #[test]
    fn the_default_view_start_pose_stands_on_the_floor_below_its_eye() {
        use glam::Vec3;
        use solution::view::{bvh::Bvh, fixture, EYE_HEIGHT_M};
        let solution = fixture::box_room();
        let header = &solution.header;
        let offset = DVec3::from(header.recentre_offset);
        // A view as the chooser stands one: in the room, clear of its block,
        // EYE_HEIGHT_M above the floor, looking level across the room.
        let standing = DVec3::new(
            1.2,
            f64::from(fixture::ROOM_LO.y) + EYE_HEIGHT_M * header.units_per_metre,
            -1.8,
        );
        let camera = solution::camera::Camera {
            eye: (standing + offset).to_array(),
            target: (standing + DVec3::new(-1.0, 0.0, 2.0) + offset).to_array(),
            ..solution::camera::Camera::default()
        };
        // As `XrSession` does: the home eye in file coordinates and its yaw.
        let home_eye = DVec3::from(camera.eye) - offset;
        let home_yaw = scene_yaw_deg(
            DVec3::from(camera.target) - DVec3::from(camera.eye),
            header.up_axis,
        );
        let eye_height_m = crate::xr::config::XrConfig::default().camera_eye_height_m;
        assert_eq!(eye_height_m, EYE_HEIGHT_M);
        let mut loco = Locomotion::new(header.up_axis, header.units_per_metre);
        // The user stands 0.2 m off the play area's centre, 1.75 m tall.
        let head = pose(DVec3::new(0.2, 1.75, -0.1), 25.0);
        loco.recentre(&head, home_eye, home_yaw, Placement::Floor { eye_height_m });
        let feet = loco.to_scene(&pose(DVec3::new(0.2, 0.0, -0.1), 25.0));
        let batch = &solution.batches[0];
        let triangles = batch
            .indices
            .chunks_exact(3)
            .map(|t| [0, 1, 2].map(|k| Vec3::from(batch.vertices[t[k] as usize].position)))
            .collect();
        let down = Bvh::build(triangles)
            .closest(home_eye.as_vec3(), Vec3::NEG_Y, f32::INFINITY)
            .expect("a floor below the eye");
        assert!(down.front, "the floor's upper side");
        let floor = home_eye - DVec3::Y * down.t as f64;
        // Feet on the floor straight below the eye: f32 positions of a 6 m
        // room, so within 1e-5 m.
        assert!(
            close(feet.position, floor, 1e-5),
            "{} vs {floor}",
            feet.position
        );
        // The eye stood at 1.6 m, so the user's own 1.75 m eye is 0.15 m above it.
        let eye = loco.to_scene(&head).position;
        assert!((eye.y - (home_eye.y + 0.15)).abs() < 1e-9, "{eye}");
        let yaw = scene_yaw_deg(
            loco.to_scene(&head).orientation * DVec3::NEG_Z,
            header.up_axis,
        );
        assert!(
            (wrap_deg(yaw - home_yaw)).abs() < 1e-9,
            "{yaw} vs {home_yaw}"
        );
    }
}
