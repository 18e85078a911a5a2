//! The headset's exposure control: the right stick's y steps the EV offset
//! by half a stop per push (up brighter, down darker), with the snap turn's
//! hysteresis, so one push is one step; the renderer adds it to the file's
//! automatic exposure and `--exposure` (`crate::render::file_tone`).

use super::locomotion::{SNAP_ENGAGE, SNAP_RELEASE};

/// Stops per push: the mirror's `[` and `]` step.
pub const EXPOSURE_STEP: f32 = 0.5;

/// The EV offset the stick has set, and whether the stick has returned.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExposureStepper {
    pub offset_stops: f32,
    armed: bool,
}

impl Default for ExposureStepper {
    fn default() -> Self {
        ExposureStepper {
            offset_stops: 0.0,
            armed: true,
        }
    }
}

impl ExposureStepper {
    /// Reads one frame's stick y: a push past [`SNAP_ENGAGE`] steps once;
    /// the stick must come back below [`SNAP_RELEASE`] before the next.
    /// Returns the step taken (0 when none). The offset stays within ±64
    /// stops, `--exposure`'s range.
    pub fn step(&mut self, stick_y: f64) -> f32 {
        if !stick_y.is_finite() {
            return 0.0;
        }
        if self.armed && stick_y.abs() >= SNAP_ENGAGE {
            self.armed = false;
            let step = EXPOSURE_STEP * stick_y.signum() as f32;
            let next = (self.offset_stops + step).clamp(-64.0, 64.0);
            let taken = next - self.offset_stops;
            self.offset_stops = next;
            return taken;
        }
        if stick_y.abs() < SNAP_RELEASE {
            self.armed = true;
        }
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_push_is_one_half_stop() {
        let mut e = ExposureStepper::default();
        assert_eq!(e.step(0.9), 0.5);
        // Held: no more steps until the stick comes back.
        assert_eq!(e.step(1.0), 0.0);
        assert_eq!(e.step(0.5), 0.0);
        assert_eq!(e.step(0.1), 0.0);
        assert_eq!(e.step(-0.8), -0.5);
        assert_eq!(e.offset_stops, 0.0);
        assert_eq!(e.step(f64::NAN), 0.0);
    }
}
