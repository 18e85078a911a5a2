//! Scripted head poses for the mock session.
//!
//! **Walk file format** (text, one key pose per line; `#` starts a comment; blank
//! lines are ignored):
//!
//! ```text
//! # t(seconds)  x y z (scene coordinates)  yaw pitch (degrees)
//! 0.0   278 273 -800   0  0
//! 4.0   278 273 -300  30 -5
//! ```
//!
//! Positions are in the scene's original coordinates (like every user-facing
//! position; the mock subtracts the header's `recentre_offset`). `yaw` turns
//! about the up axis, counter-clockwise seen from above (positive turns left);
//! `pitch` tilts the view up (positive) or down. At yaw = pitch = 0 the head
//! looks along −z when the up axis is ±y, and along +y when it is ±z. Times must
//! increase; poses between keys are interpolated linearly, and held before the
//! first and after the last key.

use glam::{DQuat, DVec3};
use solution::camera::UpAxis;
use std::path::Path;

#[derive(Debug, thiserror::Error)]
pub enum WalkError {
    #[error("{file}:{line}: {message}")]
    Parse {
        file: String,
        line: usize,
        message: String,
    },
    #[error("{file}: no key poses (expected lines of `t x y z yaw pitch`)")]
    Empty { file: String },
    #[error("cannot read walk file {file}: {source}")]
    Io {
        file: String,
        source: std::io::Error,
    },
}

/// One key pose (scene coordinates, degrees).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeadPose {
    pub time: f64,
    pub position: DVec3,
    pub yaw_deg: f64,
    pub pitch_deg: f64,
}

/// A head path: key poses in time order.
#[derive(Clone, Debug, PartialEq)]
pub struct HeadPath {
    pub keys: Vec<HeadPose>,
}

impl HeadPath {
    /// Reads a walk file.
    pub fn load(path: &Path) -> Result<HeadPath, WalkError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| WalkError::Io {
            file: file.clone(),
            source,
        })?;
        HeadPath::parse(&text, &file)
    }

    /// Parses walk text; `file` names the source in errors.
    pub fn parse(text: &str, file: &str) -> Result<HeadPath, WalkError> {
        let mut keys: Vec<HeadPose> = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let content = raw.split('#').next().unwrap_or("").trim();
            if content.is_empty() {
                continue;
            }
            let err = |message: String| WalkError::Parse {
                file: file.to_string(),
                line,
                message,
            };
            let fields: Vec<&str> = content.split_whitespace().collect();
            if fields.len() != 6 {
                return Err(err(format!(
                    "expected 6 numbers `t x y z yaw pitch`, found {} in {content:?}",
                    fields.len()
                )));
            }
            let mut v = [0.0f64; 6];
            for (slot, field) in v.iter_mut().zip(&fields) {
                *slot = field
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| err(format!("{field:?} is not a finite number")))?;
            }
            if let Some(last) = keys.last() {
                if v[0] <= last.time {
                    return Err(err(format!(
                        "time {} does not increase (previous key at {})",
                        v[0], last.time
                    )));
                }
            }
            keys.push(HeadPose {
                time: v[0],
                position: DVec3::new(v[1], v[2], v[3]),
                yaw_deg: v[4],
                pitch_deg: v[5],
            });
        }
        if keys.is_empty() {
            return Err(WalkError::Empty {
                file: file.to_string(),
            });
        }
        Ok(HeadPath { keys })
    }

    /// A built-in orbit: the head circles `centre` at `radius` in the plane
    /// perpendicular to `up` through `eye_height_point`'s height, one turn per
    /// `period` seconds, always facing the centre's height-adjusted point.
    pub fn orbit(
        centre: DVec3,
        eye_level: DVec3,
        radius: f64,
        period: f64,
        up: UpAxis,
    ) -> HeadPath {
        let up_v = DVec3::from(up.vector());
        let (forward0, right0) = reference_axes(up);
        // The eye level along the up axis, the centre elsewhere.
        let level = eye_level.dot(up_v);
        let centre = centre - up_v * centre.dot(up_v) + up_v * level;
        let steps = 36;
        let keys = (0..=steps)
            .map(|i| {
                let a = i as f64 / steps as f64 * std::f64::consts::TAU;
                let offset = forward0 * a.cos() + right0 * a.sin();
                let position = centre + offset * radius;
                let d = -offset;
                let yaw = (-d.dot(right0)).atan2(d.dot(forward0));
                HeadPose {
                    time: period * i as f64 / steps as f64,
                    position,
                    yaw_deg: yaw.to_degrees(),
                    pitch_deg: 0.0,
                }
            })
            .collect::<Vec<_>>();
        // Unwrap yaw so interpolation turns the short way.
        let mut keys = keys;
        for i in 1..keys.len() {
            let prev = keys[i - 1].yaw_deg;
            let mut y = keys[i].yaw_deg;
            while y - prev > 180.0 {
                y -= 360.0;
            }
            while y - prev < -180.0 {
                y += 360.0;
            }
            keys[i].yaw_deg = y;
        }
        HeadPath { keys }
    }

    /// The pose at `time` (linear between keys, held outside them).
    pub fn sample(&self, time: f64) -> HeadPose {
        let keys = &self.keys;
        let first = keys[0];
        let last = keys[keys.len() - 1];
        if time <= first.time {
            return HeadPose { time, ..first };
        }
        if time >= last.time {
            return HeadPose { time, ..last };
        }
        let i = keys.partition_point(|k| k.time <= time);
        let (a, b) = (keys[i - 1], keys[i]);
        let s = (time - a.time) / (b.time - a.time);
        HeadPose {
            time,
            position: a.position.lerp(b.position, s),
            yaw_deg: a.yaw_deg + (b.yaw_deg - a.yaw_deg) * s,
            pitch_deg: a.pitch_deg + (b.pitch_deg - a.pitch_deg) * s,
        }
    }

    /// Duration from the first to the last key.
    pub fn duration(&self) -> f64 {
        self.keys[self.keys.len() - 1].time - self.keys[0].time
    }
}

/// The head's forward and right directions at yaw = pitch = 0.
pub fn reference_axes(up: UpAxis) -> (DVec3, DVec3) {
    let up_v = DVec3::from(up.vector());
    let forward0 = match up {
        UpAxis::PosY | UpAxis::NegY => DVec3::NEG_Z,
        UpAxis::PosZ | UpAxis::NegZ => DVec3::Y,
    };
    (forward0, forward0.cross(up_v))
}

/// The head orientation (view space → world) for yaw and pitch in degrees.
pub fn head_orientation(yaw_deg: f64, pitch_deg: f64, up: UpAxis) -> DQuat {
    let up_v = DVec3::from(up.vector());
    let (forward0, right0) = reference_axes(up);
    let base = DQuat::from_mat3(&glam::DMat3::from_cols(right0, up_v, -forward0));
    DQuat::from_axis_angle(up_v, yaw_deg.to_radians())
        * base
        * DQuat::from_rotation_x(pitch_deg.to_radians())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_interpolates() {
        let text = "# walk\n0 0 1 0 0 0\n\n2 2 1 0 90 10 # turn left\n";
        let path = HeadPath::parse(text, "w.txt").unwrap();
        assert_eq!(path.keys.len(), 2);
        let mid = path.sample(1.0);
        assert!((mid.position - DVec3::new(1.0, 1.0, 0.0)).length() < 1e-12);
        assert!((mid.yaw_deg - 45.0).abs() < 1e-12 && (mid.pitch_deg - 5.0).abs() < 1e-12);
        assert_eq!(path.sample(-1.0).position, DVec3::new(0.0, 1.0, 0.0));
        assert_eq!(path.sample(9.0).yaw_deg, 90.0);
    }

    #[test]
    fn errors_name_file_line_and_value() {
        let e = HeadPath::parse("0 0 0 0 0 0\n1 2 3 x 0 0\n", "walk.txt").unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.starts_with("walk.txt:2:") && msg.contains("\"x\""),
            "{msg}"
        );
        let e = HeadPath::parse("0 0 0 0 0 0\n0 1 1 1 0 0\n", "w").unwrap_err();
        assert!(e.to_string().contains("does not increase"));
        assert!(HeadPath::parse("1 2 3\n", "w")
            .unwrap_err()
            .to_string()
            .contains("6 numbers"));
        assert!(matches!(
            HeadPath::parse("# nothing\n", "w"),
            Err(WalkError::Empty { .. })
        ));
        assert!(HeadPath::parse("0 nan 0 0 0 0", "w").is_err());
    }

    #[test]
    fn yaw_turns_left_and_pitch_looks_up() {
        for up in [UpAxis::PosY, UpAxis::NegY, UpAxis::PosZ, UpAxis::NegZ] {
            let up_v = DVec3::from(up.vector());
            let (f0, r0) = reference_axes(up);
            let q = head_orientation(0.0, 0.0, up);
            assert!((q * DVec3::NEG_Z - f0).length() < 1e-12);
            assert!((q * DVec3::Y - up_v).length() < 1e-12);
            // +90° yaw: counter-clockwise about up, so forward becomes −right0.
            let q = head_orientation(90.0, 0.0, up);
            assert!((q * DVec3::NEG_Z + r0).length() < 1e-12, "{up:?}");
            // +30° pitch: forward gains a positive up component sin 30°.
            let q = head_orientation(0.0, 30.0, up);
            assert!(((q * DVec3::NEG_Z).dot(up_v) - 0.5).abs() < 1e-12);
        }
    }

    #[test]
    fn orbit_faces_the_centre() {
        let centre = DVec3::new(1.0, 0.0, 2.0);
        let path = HeadPath::orbit(centre, DVec3::new(0.0, 1.5, 0.0), 3.0, 8.0, UpAxis::PosY);
        for t in [0.0, 1.3, 4.0, 7.9] {
            let p = path.sample(t);
            let q = head_orientation(p.yaw_deg, p.pitch_deg, UpAxis::PosY);
            let to_centre = (DVec3::new(centre.x, 1.5, centre.z) - p.position).normalize();
            // Keys every 10°: between keys the linear blend of position and yaw
            // is off the circle by at most 1 − cos 5° of the radius.
            assert!((q * DVec3::NEG_Z).dot(to_centre) > 0.995, "t = {t}");
            assert!((p.position.y - 1.5).abs() < 1e-12);
        }
    }
}
