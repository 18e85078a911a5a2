//! The mirror window's controls: input events → camera and display state. Pure
//! (no window, no GPU), so every key's effect is unit-tested here, and the
//! hidden `--script` option drives the window through this same code.
//!
//! The keys are radview's (Remington 1992, app. C.1), plus a walk mode as
//! walkthrough users expect, plus the inspection toggles of prorad's `-w` and
//! `-n` (Remington 1992, app. D):
//!
//! * Left mouse drag: in orbit mode (the default) the viewpoint's azimuth and
//!   elevation about the reference point change, [`DEG_PER_PIXEL`] per pixel,
//!   in the same sense as the arrow keys (drag right = azimuth right, drag up =
//!   elevation up); in walk mode the view turns about the eye (mouse look: drag
//!   right looks right, drag up looks up).
//! * Arrow keys: elevation (up/down) and azimuth (left/right) of the viewpoint
//!   about the reference point, one degree per press (radview).
//! * `z` / `x`: zoom in / out with a constant reference point: the eye's
//!   distance to it is divided / multiplied by [`ZOOM_FACTOR`].
//! * `a` / `s` (orbit mode): move the viewpoint and the reference point together
//!   along / against the line of sight by [`MOVE_FRACTION`] of the scene's
//!   diagonal.
//! * `Tab`: walk mode on / off. In walk mode `w`/`s` walk forward / back along
//!   the view direction projected on the horizontal plane, `a`/`d` step left /
//!   right, `q`/`e` go down / up the up axis, at [`WALK_SPEED_M_S`] (times
//!   [`RUN_FACTOR`] with Shift), scaled by the header's `units_per_metre`.
//! * `r`: reset the view to the initial camera (display toggles are kept).
//! * `F1` / `F2`: help overlay on / off; `F3`: frame-time overlay on / off.
//! * `1` `2` `3` `4`: both eyes side by side, left eye, right eye, red–cyan
//!   anaglyph. `m`: wireframe off / over the shading / alone. `n`: vertex
//!   normals. `[` / `]`: exposure −/+ half a stop.
//! * `F12`: stereo screenshot; `Esc`: exit.
//!
//! Angles: the viewpoint's azimuth turns counter-clockwise about the up axis
//! (seen from above) as it increases; "azimuth right" is the direction that
//! moves the eye toward the camera's right. Elevation is the angle of the
//! vector from the reference point to the eye above the horizontal plane, kept
//! within ±[`MAX_ELEVATION_DEG`] by the keys and the mouse so the view never
//! flips over the pole.

use glam::DVec3;
use solution::camera::{Camera, UpAxis};

/// Degrees per arrow-key press (Remington 1992, app. C.1).
pub const ARROW_STEP_DEG: f64 = 1.0;
/// Degrees of azimuth / elevation (or of mouse look) per pixel of mouse drag.
pub const DEG_PER_PIXEL: f64 = 0.2;
/// `z` divides the eye's distance to the reference point by this, `x`
/// multiplies it.
pub const ZOOM_FACTOR: f64 = 1.1;
/// `a` / `s` move by this fraction of the scene's bounding-box diagonal.
pub const MOVE_FRACTION: f64 = 0.02;
/// Walking speed, metres per second (a brisk walk), scaled by `units_per_metre`.
pub const WALK_SPEED_M_S: f64 = 1.4;
/// Shift multiplies the walking speed by this.
pub const RUN_FACTOR: f64 = 4.0;
/// The elevation the keys and the mouse stop at, degrees.
pub const MAX_ELEVATION_DEG: f64 = 89.0;
/// Exposure change per `[` / `]` press, stops.
pub const EXPOSURE_STEP: f32 = 0.5;
/// The eye never gets closer to the reference point than this fraction of the
/// scene's diagonal (zooming in stops there).
pub const MIN_DISTANCE_FRACTION: f64 = 1e-4;

/// The keys the controls know. Window events and `--script` files are
/// translated into these.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Key {
    Left,
    Right,
    Up,
    Down,
    /// A letter, digit or bracket, lower case (`'z'`, `'1'`, `'['`).
    Char(char),
    Tab,
    Shift,
    F1,
    F2,
    F3,
    F12,
    Escape,
}

impl Key {
    /// Parses a key name as `--script` files write it: `Left`, `Right`, `Up`,
    /// `Down`, `Tab`, `Shift`, `F1`, `F2`, `F3`, `F12`, `Escape` (or `Esc`), or a
    /// single character (`z`, `1`, `[`). Case-insensitive.
    pub fn parse(name: &str) -> Option<Key> {
        let lower = name.to_ascii_lowercase();
        Some(match lower.as_str() {
            "left" => Key::Left,
            "right" => Key::Right,
            "up" => Key::Up,
            "down" => Key::Down,
            "tab" => Key::Tab,
            "shift" => Key::Shift,
            "f1" => Key::F1,
            "f2" => Key::F2,
            "f3" => Key::F3,
            "f12" => Key::F12,
            "escape" | "esc" => Key::Escape,
            _ => {
                let mut chars = lower.chars();
                match (chars.next(), chars.next()) {
                    (Some(c), None) if c.is_ascii_graphic() => Key::Char(c),
                    _ => return None,
                }
            }
        })
    }
}

/// One input event.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Input {
    /// A key went down (`repeat`: the keyboard's auto-repeat while held; the
    /// step keys act on each repeat, the held walking keys ignore them).
    KeyDown {
        key: Key,
        repeat: bool,
    },
    KeyUp(Key),
    /// The left mouse button.
    ButtonDown,
    ButtonUp,
    /// The pointer moved by `(dx, dy)` pixels (x right, y down); it counts only
    /// while the left button is down.
    PointerMoved {
        dx: f64,
        dy: f64,
    },
    /// The window lost the keyboard focus: every held key is released.
    FocusLost,
}

/// What the window should do besides moving the camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Command {
    Exit,
    Screenshot,
}

/// Orbit about the reference point (radview) or walk with the eye.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Mode {
    #[default]
    Orbit,
    Walk,
}

/// How the two eyes are shown in the window.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Display {
    /// Left eye in the left half, right eye in the right half.
    #[default]
    SideBySide,
    /// The left eye alone, full window.
    Left,
    /// The right eye alone, full window.
    Right,
    /// Red from the left eye, green and blue from the right (red–cyan glasses).
    Anaglyph,
}

/// Wireframe drawing (Remington 1992, app. D, `-w`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Wireframe {
    #[default]
    Off,
    /// Element edges over the shaded image.
    Overlay,
    /// Element edges alone, as prorad's `-w`.
    Only,
}

/// Display state the keys toggle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewOptions {
    pub display: Display,
    pub wireframe: Wireframe,
    /// Vertex normals (Remington 1992, app. D, `-n`).
    pub normals: bool,
    pub help: bool,
    /// The frame-time line.
    pub hud: bool,
    pub exposure_stops: f32,
}

impl Default for ViewOptions {
    fn default() -> Self {
        ViewOptions {
            display: Display::SideBySide,
            wireframe: Wireframe::Off,
            normals: false,
            help: false,
            hud: true,
            exposure_stops: 0.0,
        }
    }
}

/// What the controls need to know about the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneFrame {
    pub up_axis: UpAxis,
    pub units_per_metre: f64,
    /// The scene's bounding-box diagonal, scene units (step sizes are relative
    /// to it, so they do not depend on the units).
    pub diagonal: f64,
}

/// Held walking keys.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Held {
    forward: bool,
    back: bool,
    left: bool,
    right: bool,
    down: bool,
    up: bool,
    run: bool,
}

/// The camera and display state.
#[derive(Clone, Debug, PartialEq)]
pub struct Controls {
    /// The viewpoint (eye) and the reference point, scene coordinates.
    pub eye: DVec3,
    pub target: DVec3,
    pub mode: Mode,
    pub view: ViewOptions,
    initial: Camera,
    scene: SceneFrame,
    held: Held,
    dragging: bool,
}

/// Unit vectors `(h1, h2)` spanning the plane perpendicular to `up` with
/// `h2 = up × h1`, so increasing azimuth turns counter-clockwise seen from
/// above (from +up).
fn horizontal_axes(up: DVec3) -> (DVec3, DVec3) {
    let h1 = if up.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let h1 = (h1 - up * h1.dot(up)).normalize();
    (h1, up.cross(h1))
}

impl Controls {
    /// Controls starting at `camera` (scene coordinates: the header's camera or
    /// the command line's `--eye`/`--target`).
    pub fn new(camera: Camera, scene: SceneFrame) -> Controls {
        Controls {
            eye: DVec3::from(camera.eye),
            target: DVec3::from(camera.target),
            mode: Mode::Orbit,
            view: ViewOptions::default(),
            initial: camera,
            scene,
            held: Held::default(),
            dragging: false,
        }
    }

    /// Updates the scene figures (after a reload) without moving the camera.
    pub fn set_scene(&mut self, scene: SceneFrame) {
        self.scene = scene;
    }

    pub fn scene(&self) -> SceneFrame {
        self.scene
    }

    fn up(&self) -> DVec3 {
        DVec3::from(self.scene.up_axis.vector())
    }

    /// The camera for an image of `width × height` per eye. Its `up` is the
    /// initial camera's, unless the view direction has come within about 2.6°
    /// of it, where the up axis is used instead.
    pub fn camera(&self, width: u32, height: u32) -> Camera {
        let forward = (self.target - self.eye).normalize_or_zero();
        let initial_up = DVec3::from(self.initial.up).normalize_or_zero();
        let up = if forward.dot(initial_up).abs() < 0.999 {
            self.initial.up
        } else {
            self.scene.up_axis.vector()
        };
        Camera {
            eye: self.eye.to_array(),
            target: self.target.to_array(),
            up,
            fov_y_deg: self.initial.fov_y_deg,
            width,
            height,
        }
    }

    /// The eye's distance to the reference point.
    pub fn distance(&self) -> f64 {
        (self.eye - self.target).length()
    }

    /// Azimuth and elevation (degrees) of the eye seen from the reference point.
    pub fn angles_deg(&self) -> (f64, f64) {
        let up = self.up();
        let (h1, h2) = horizontal_axes(up);
        let d = (self.eye - self.target).normalize_or_zero();
        let elevation = d.dot(up).clamp(-1.0, 1.0).asin();
        let azimuth = d.dot(h2).atan2(d.dot(h1));
        (azimuth.to_degrees(), elevation.to_degrees())
    }

    /// The unit vector from the reference point toward the eye at the given
    /// angles (degrees).
    fn direction(&self, azimuth_deg: f64, elevation_deg: f64) -> DVec3 {
        let up = self.up();
        let (h1, h2) = horizontal_axes(up);
        let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
        el.cos() * (az.cos() * h1 + az.sin() * h2) + el.sin() * up
    }

    fn clamp_elevation(elevation: f64) -> f64 {
        elevation.clamp(-MAX_ELEVATION_DEG, MAX_ELEVATION_DEG)
    }

    /// Orbits the eye about the reference point by the given changes of
    /// azimuth and elevation (degrees); the distance is kept.
    pub fn orbit(&mut self, d_azimuth: f64, d_elevation: f64) {
        let (az, el) = self.angles_deg();
        let el = Self::clamp_elevation(el + d_elevation);
        let dist = self.distance();
        self.eye = self.target + self.direction(az + d_azimuth, el) * dist;
    }

    /// Turns the view about the eye (mouse look): `d_yaw` > 0 looks right,
    /// `d_pitch` > 0 looks up; the reference point moves, the eye stays.
    pub fn look(&mut self, d_yaw: f64, d_pitch: f64) {
        // The view direction is minus the eye's direction from the target, so
        // looking right (clockwise from above) is an azimuth change of −d_yaw,
        // and looking up lowers the eye's elevation seen from the target.
        let (az, el) = self.angles_deg();
        let el = Self::clamp_elevation(el - d_pitch);
        let dist = self.distance();
        self.target = self.eye - self.direction(az - d_yaw, el) * dist;
    }

    /// Zoom with a constant reference point: the distance is divided by
    /// `factor` (> 1 zooms in).
    pub fn zoom(&mut self, factor: f64) {
        let min = MIN_DISTANCE_FRACTION * self.scene.diagonal.max(f64::MIN_POSITIVE);
        let offset = self.eye - self.target;
        let dist = offset.length();
        let new = (dist / factor).max(min);
        if dist > 0.0 {
            self.eye = self.target + offset * (new / dist);
        }
    }

    /// Moves the eye and the reference point together by `distance` along the
    /// line of sight (negative: against it).
    pub fn advance(&mut self, distance: f64) {
        let forward = (self.target - self.eye).normalize_or_zero();
        self.eye += forward * distance;
        self.target += forward * distance;
    }

    /// The `a` / `s` step, scene units.
    pub fn move_step(&self) -> f64 {
        MOVE_FRACTION * self.scene.diagonal
    }

    /// Back to the initial camera.
    pub fn reset(&mut self) {
        self.eye = DVec3::from(self.initial.eye);
        self.target = DVec3::from(self.initial.target);
    }

    /// Applies one input event; returns what the window must do, if anything.
    pub fn apply(&mut self, input: Input) -> Option<Command> {
        match input {
            Input::KeyDown { key, repeat } => return self.key_down(key, repeat),
            Input::KeyUp(key) => {
                self.set_held(key, false);
            }
            Input::ButtonDown => self.dragging = true,
            Input::ButtonUp => self.dragging = false,
            Input::PointerMoved { dx, dy } => {
                if self.dragging {
                    match self.mode {
                        // Drag right = azimuth right; drag up (dy < 0) = elevation up.
                        Mode::Orbit => self.orbit(dx * DEG_PER_PIXEL, -dy * DEG_PER_PIXEL),
                        // Drag right looks right; drag up looks up.
                        Mode::Walk => self.look(dx * DEG_PER_PIXEL, -dy * DEG_PER_PIXEL),
                    }
                }
            }
            Input::FocusLost => {
                self.held = Held::default();
                self.dragging = false;
            }
        }
        None
    }

    /// Marks a walking key held or released; false when `key` is not one.
    fn set_held(&mut self, key: Key, down: bool) -> bool {
        let walk = self.mode == Mode::Walk;
        let slot = match key {
            Key::Char('w') if walk => &mut self.held.forward,
            Key::Char('s') if walk => &mut self.held.back,
            Key::Char('a') if walk => &mut self.held.left,
            Key::Char('d') if walk => &mut self.held.right,
            Key::Char('q') if walk => &mut self.held.down,
            Key::Char('e') if walk => &mut self.held.up,
            Key::Shift => &mut self.held.run,
            _ => return false,
        };
        *slot = down;
        true
    }

    fn key_down(&mut self, key: Key, repeat: bool) -> Option<Command> {
        if self.set_held(key, true) {
            return None;
        }
        let view = &mut self.view;
        match key {
            Key::Up => self.orbit(0.0, ARROW_STEP_DEG),
            Key::Down => self.orbit(0.0, -ARROW_STEP_DEG),
            Key::Right => self.orbit(ARROW_STEP_DEG, 0.0),
            Key::Left => self.orbit(-ARROW_STEP_DEG, 0.0),
            Key::Char('z') => self.zoom(ZOOM_FACTOR),
            Key::Char('x') => self.zoom(1.0 / ZOOM_FACTOR),
            Key::Char('a') => self.advance(self.move_step()),
            Key::Char('s') => self.advance(-self.move_step()),
            Key::Char('r') => self.reset(),
            Key::Tab if !repeat => {
                self.mode = match self.mode {
                    Mode::Orbit => Mode::Walk,
                    Mode::Walk => Mode::Orbit,
                };
                self.held = Held {
                    run: self.held.run,
                    ..Held::default()
                };
            }
            Key::F1 => view.help = true,
            Key::F2 => view.help = false,
            Key::F3 if !repeat => view.hud = !view.hud,
            Key::Char('1') => view.display = Display::SideBySide,
            Key::Char('2') => view.display = Display::Left,
            Key::Char('3') => view.display = Display::Right,
            Key::Char('4') => view.display = Display::Anaglyph,
            Key::Char('m') if !repeat => {
                view.wireframe = match view.wireframe {
                    Wireframe::Off => Wireframe::Overlay,
                    Wireframe::Overlay => Wireframe::Only,
                    Wireframe::Only => Wireframe::Off,
                }
            }
            Key::Char('n') if !repeat => view.normals = !view.normals,
            Key::Char('[') => view.exposure_stops -= EXPOSURE_STEP,
            Key::Char(']') => view.exposure_stops += EXPOSURE_STEP,
            Key::F12 if !repeat => return Some(Command::Screenshot),
            Key::Escape => return Some(Command::Exit),
            _ => {}
        }
        None
    }

    /// Moves the eye (and the reference point with it) for `dt` seconds of the
    /// held walking keys.
    pub fn update(&mut self, dt: f64) {
        if self.mode != Mode::Walk || dt.is_nan() || dt <= 0.0 {
            return;
        }
        let h = self.held;
        let axis = |plus: bool, minus: bool| f64::from(u8::from(plus)) - f64::from(u8::from(minus));
        let (fwd, side, vertical) = (
            axis(h.forward, h.back),
            axis(h.right, h.left),
            axis(h.up, h.down),
        );
        if fwd == 0.0 && side == 0.0 && vertical == 0.0 {
            return;
        }
        let up = self.up();
        let view = (self.target - self.eye).normalize_or_zero();
        // Walking keeps the eye height: forward is the view direction projected
        // on the horizontal plane (looking straight up or down: no forward).
        let forward = (view - up * view.dot(up)).normalize_or_zero();
        let right = forward.cross(up).normalize_or_zero();
        let speed =
            WALK_SPEED_M_S * self.scene.units_per_metre * if h.run { RUN_FACTOR } else { 1.0 };
        let step = (forward * fwd + right * side + up * vertical) * (speed * dt);
        self.eye += step;
        self.target += step;
    }

    /// The key list the help overlay shows (ASCII, for the bitmap font).
    pub fn help_lines() -> &'static [&'static str] {
        &[
            "runtime mirror - keys (F2 closes this help)",
            "left drag   orbit: azimuth/elevation; walk: look",
            "arrows      elevation / azimuth, 1 degree",
            "z / x       zoom in / out (reference point fixed)",
            "a / s       move along / against the line of sight",
            "Tab         walk mode: W A S D, Q E down/up, Shift runs",
            "r           reset the view",
            "1 2 3 4     both eyes / left / right / anaglyph",
            "m           wireframe: off / over shading / alone",
            "n           vertex normals",
            "[ ]         exposure -/+ half a stop",
            "F1 F2       help on / off      F3 frame time",
            "F12         stereo screenshot (PNG + EXR)",
            "Esc         exit",
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL_UP: [UpAxis; 4] = [UpAxis::PosY, UpAxis::NegY, UpAxis::PosZ, UpAxis::NegZ];

    /// A camera 10 units from the origin, level, looking at it, for each up axis.
    fn controls(up: UpAxis) -> Controls {
        let u = DVec3::from(up.vector());
        let (h1, _) = horizontal_axes(u);
        let camera = Camera {
            eye: (h1 * 10.0 + u * 0.0).to_array(),
            target: [0.0; 3],
            up: up.vector(),
            fov_y_deg: 60.0,
            width: 64,
            height: 64,
        };
        Controls::new(
            camera,
            SceneFrame {
                up_axis: up,
                units_per_metre: 1000.0,
                diagonal: 500.0,
            },
        )
    }

    fn press(c: &mut Controls, key: Key) -> Option<Command> {
        let cmd = c.apply(Input::KeyDown { key, repeat: false });
        c.apply(Input::KeyUp(key));
        cmd
    }

    /// Angle in degrees between two vectors.
    fn angle_deg(a: DVec3, b: DVec3) -> f64 {
        a.normalize()
            .dot(b.normalize())
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees()
    }

    // Tolerances: every operation is a few f64 trig calls on values of order
    // 10; 1e-9 leaves six orders of magnitude over their rounding error.
    const EPS: f64 = 1e-9;

    #[test]
    fn arrows_turn_the_viewpoint_one_degree_about_the_reference_point() {
        for up in ALL_UP {
            let u = DVec3::from(up.vector());
            let mut c = controls(up);
            let eye0 = c.eye;
            let camera0 = c.camera(64, 64);
            let right0 = (DVec3::from(camera0.target) - eye0).cross(u).normalize();
            press(&mut c, Key::Right);
            // One degree of azimuth, distance kept, toward the camera's right,
            // level (the rotation is about the up axis).
            assert!((angle_deg(eye0, c.eye) - 1.0).abs() < EPS, "{up:?}");
            assert!((c.distance() - 10.0).abs() < EPS);
            assert!(
                (c.eye - eye0).dot(right0) > 0.0,
                "{up:?}: right moves right"
            );
            assert!(c.eye.dot(u).abs() < EPS);
            press(&mut c, Key::Left);
            assert!((c.eye - eye0).length() < EPS, "{up:?}: left undoes right");
            // Up: the eye rises one degree above the horizontal plane.
            press(&mut c, Key::Up);
            let elevation = c.eye.normalize().dot(u).asin().to_degrees();
            assert!((elevation - 1.0).abs() < EPS, "{up:?}: {elevation}");
            press(&mut c, Key::Down);
            press(&mut c, Key::Down);
            let elevation = c.eye.normalize().dot(u).asin().to_degrees();
            assert!((elevation + 1.0).abs() < EPS, "{up:?}: {elevation}");
            assert_eq!(c.target, DVec3::ZERO, "the reference point stays");
        }
    }

    #[test]
    fn ninety_right_presses_are_a_quarter_turn_and_auto_repeat_counts() {
        let mut c = controls(UpAxis::PosY);
        for i in 0..90 {
            c.apply(Input::KeyDown {
                key: Key::Right,
                repeat: i > 0,
            });
        }
        // From +x (h1 for +y up), a quarter turn counter-clockwise seen from +y
        // ends at h2 = y × x = −z.
        assert!((c.eye - DVec3::new(0.0, 0.0, -10.0)).length() < 1e-9);
    }

    #[test]
    fn elevation_stops_short_of_the_pole() {
        let mut c = controls(UpAxis::PosZ);
        for _ in 0..200 {
            press(&mut c, Key::Up);
        }
        let (_, el) = c.angles_deg();
        assert!((el - MAX_ELEVATION_DEG).abs() < EPS, "{el}");
        // The camera stays usable: a valid up vector, not parallel to the view.
        let cam = c.camera(8, 8);
        assert!(cam.validate().is_ok());
    }

    #[test]
    fn zoom_keeps_the_reference_point_and_scales_the_distance() {
        let mut c = controls(UpAxis::NegY);
        let dir0 = (c.eye - c.target).normalize();
        press(&mut c, Key::Char('z'));
        assert!((c.distance() - 10.0 / ZOOM_FACTOR).abs() < EPS);
        press(&mut c, Key::Char('z'));
        assert!((c.distance() - 10.0 / ZOOM_FACTOR.powi(2)).abs() < EPS);
        press(&mut c, Key::Char('x'));
        press(&mut c, Key::Char('x'));
        press(&mut c, Key::Char('x'));
        assert!((c.distance() - 10.0 * ZOOM_FACTOR).abs() < EPS);
        assert_eq!(c.target, DVec3::ZERO);
        assert!(((c.eye - c.target).normalize() - dir0).length() < EPS);
        // Zooming in stops at the minimum distance instead of reaching the target.
        for _ in 0..1000 {
            press(&mut c, Key::Char('z'));
        }
        assert!((c.distance() - MIN_DISTANCE_FRACTION * 500.0).abs() < EPS);
    }

    #[test]
    fn a_and_s_move_both_points_along_the_line_of_sight() {
        let mut c = controls(UpAxis::PosY);
        let (eye0, target0) = (c.eye, c.target);
        let forward = (target0 - eye0).normalize();
        press(&mut c, Key::Char('a'));
        let step = MOVE_FRACTION * 500.0;
        assert!((c.eye - (eye0 + forward * step)).length() < EPS);
        assert!((c.target - (target0 + forward * step)).length() < EPS);
        press(&mut c, Key::Char('s'));
        press(&mut c, Key::Char('s'));
        assert!((c.eye - (eye0 - forward * step)).length() < EPS);
        assert!((c.distance() - 10.0).abs() < EPS);
    }

    #[test]
    fn reset_returns_to_the_initial_camera_exactly() {
        let mut c = controls(UpAxis::PosZ);
        let camera0 = c.camera(64, 64);
        for key in [Key::Right, Key::Up, Key::Char('z'), Key::Char('a')] {
            press(&mut c, key);
        }
        c.apply(Input::ButtonDown);
        c.apply(Input::PointerMoved { dx: 30.0, dy: 7.0 });
        assert_ne!(c.camera(64, 64), camera0);
        press(&mut c, Key::Char('r'));
        assert_eq!(c.camera(64, 64), camera0);
    }

    #[test]
    fn dragging_orbits_like_the_arrows_and_only_while_the_button_is_down() {
        let mut a = controls(UpAxis::PosY);
        let mut b = a.clone();
        // Without the button, moving the pointer does nothing.
        a.apply(Input::PointerMoved { dx: 50.0, dy: 0.0 });
        assert_eq!(a, b);
        a.apply(Input::ButtonDown);
        // 5 px right = 1 degree of azimuth right; 10 px up = 2 degrees up.
        a.apply(Input::PointerMoved { dx: 5.0, dy: 0.0 });
        a.apply(Input::PointerMoved { dx: 0.0, dy: -10.0 });
        a.apply(Input::ButtonUp);
        a.apply(Input::PointerMoved { dx: 99.0, dy: 99.0 });
        press(&mut b, Key::Right);
        press(&mut b, Key::Up);
        press(&mut b, Key::Up);
        assert!((a.eye - b.eye).length() < EPS);
    }

    #[test]
    fn walk_mode_walks_level_at_the_walking_speed_and_looks_with_the_mouse() {
        for up in ALL_UP {
            let u = DVec3::from(up.vector());
            let mut c = controls(up);
            press(&mut c, Key::Up); // look slightly down: walking stays level
            press(&mut c, Key::Tab);
            assert_eq!(c.mode, Mode::Walk);
            let eye0 = c.eye;
            let view = (c.target - c.eye).normalize();
            let level = (view - u * view.dot(u)).normalize();
            c.apply(Input::KeyDown {
                key: Key::Char('w'),
                repeat: false,
            });
            c.update(0.5);
            // 1.4 m/s × 1000 units/m × 0.5 s = 700 units, horizontally forward.
            let moved = c.eye - eye0;
            assert!((moved - level * 700.0).length() < 1e-6, "{up:?}: {moved}");
            c.apply(Input::KeyUp(Key::Char('w')));
            c.update(0.5);
            assert!((c.eye - eye0 - level * 700.0).length() < 1e-6);
            // d steps right, e goes up, Shift runs.
            c.apply(Input::KeyDown {
                key: Key::Shift,
                repeat: false,
            });
            let eye1 = c.eye;
            c.apply(Input::KeyDown {
                key: Key::Char('e'),
                repeat: false,
            });
            c.update(0.25);
            assert!((c.eye - eye1 - u * (1400.0 * RUN_FACTOR * 0.25)).length() < 1e-6);
            c.apply(Input::FocusLost);
            let eye2 = c.eye;
            c.update(1.0);
            assert_eq!(c.eye, eye2, "focus loss releases the keys");
            // Mouse look: the eye stays, the view turns right.
            let view0 = (c.target - c.eye).normalize();
            let right0 = view0.cross(u).normalize();
            c.apply(Input::ButtonDown);
            c.apply(Input::PointerMoved { dx: 50.0, dy: 0.0 });
            let view1 = (c.target - c.eye).normalize();
            assert_eq!(c.eye, eye2);
            assert!(view1.dot(right0) > 0.0, "{up:?}: looks right");
            // 50 px = 10 degrees of yaw about the up axis.
            let flat = |v: DVec3| (v - u * v.dot(u)).normalize();
            assert!((angle_deg(flat(view0), flat(view1)) - 10.0).abs() < 1e-6);
            c.apply(Input::PointerMoved { dx: 0.0, dy: -25.0 });
            let view2 = (c.target - c.eye).normalize();
            assert!(view2.dot(u) > view1.dot(u), "{up:?}: drag up looks up");
            // In walk mode a and s walk (s back), they do not move along the
            // line of sight in steps.
            press(&mut c, Key::Tab);
            assert_eq!(c.mode, Mode::Orbit);
        }
    }

    #[test]
    fn toggles_and_commands() {
        let mut c = controls(UpAxis::PosY);
        assert!(!c.view.help && c.view.hud);
        press(&mut c, Key::F1);
        assert!(c.view.help);
        press(&mut c, Key::F1);
        assert!(c.view.help, "F1 opens (radview): it does not toggle");
        press(&mut c, Key::F2);
        assert!(!c.view.help);
        press(&mut c, Key::F3);
        assert!(!c.view.hud);
        for (key, display) in [
            ('4', Display::Anaglyph),
            ('2', Display::Left),
            ('3', Display::Right),
            ('1', Display::SideBySide),
        ] {
            press(&mut c, Key::Char(key));
            assert_eq!(c.view.display, display);
        }
        press(&mut c, Key::Char('m'));
        assert_eq!(c.view.wireframe, Wireframe::Overlay);
        press(&mut c, Key::Char('m'));
        assert_eq!(c.view.wireframe, Wireframe::Only);
        press(&mut c, Key::Char('m'));
        assert_eq!(c.view.wireframe, Wireframe::Off);
        press(&mut c, Key::Char('n'));
        assert!(c.view.normals);
        press(&mut c, Key::Char(']'));
        press(&mut c, Key::Char(']'));
        press(&mut c, Key::Char('['));
        assert_eq!(c.view.exposure_stops, EXPOSURE_STEP);
        assert_eq!(press(&mut c, Key::F12), Some(Command::Screenshot));
        assert_eq!(press(&mut c, Key::Escape), Some(Command::Exit));
        // A toggle held down (auto-repeat) does not flicker.
        c.apply(Input::KeyDown {
            key: Key::Char('n'),
            repeat: true,
        });
        assert!(c.view.normals);
    }

    #[test]
    fn key_names_parse() {
        assert_eq!(Key::parse("Right"), Some(Key::Right));
        assert_eq!(Key::parse("esc"), Some(Key::Escape));
        assert_eq!(Key::parse("F12"), Some(Key::F12));
        assert_eq!(Key::parse("Z"), Some(Key::Char('z')));
        assert_eq!(Key::parse("["), Some(Key::Char('[')));
        assert_eq!(Key::parse("zz"), None);
        assert_eq!(Key::parse(""), None);
    }

    #[test]
    fn initial_camera_is_reproduced_exactly() {
        // The window's first frame must be the header's camera bit for bit, so
        // that it matches `runtime screenshot` of the same camera.
        let camera = Camera {
            eye: [278.0, 273.0, -800.0],
            target: [278.0, 273.0, 0.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 39.3,
            width: 10,
            height: 20,
        };
        let c = Controls::new(
            camera,
            SceneFrame {
                up_axis: UpAxis::PosY,
                units_per_metre: 1000.0,
                diagonal: 960.0,
            },
        );
        assert_eq!(c.camera(10, 20), camera);
    }
}
