//! Cameras and the up axis, shared by the solver (`--preview`), the solution file
//! and the runtime.
//!
//! Conventions (design notes, "Units and conventions"): right-handed coordinates,
//! a camera is `eye`, `target`, `up` and a vertical field of view in degrees. User
//! facing positions (scene files, command-line flags, the camera stored in a
//! solution header) are in the scene's original coordinates; the solution's vertex
//! positions are re-centred, and `position_file = position_scene - recentre_offset`.

use serde::{Deserialize, Serialize};

/// The world axis that points up for the viewer (000 appendix C allows y, -y, z, -z).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum UpAxis {
    /// +y (the default, and the Cornell box's).
    #[default]
    #[serde(rename = "y", alias = "+y")]
    PosY,
    #[serde(rename = "-y")]
    NegY,
    #[serde(rename = "z", alias = "+z")]
    PosZ,
    #[serde(rename = "-z")]
    NegZ,
}

impl UpAxis {
    /// The unit vector of this axis.
    pub fn vector(self) -> [f64; 3] {
        match self {
            UpAxis::PosY => [0.0, 1.0, 0.0],
            UpAxis::NegY => [0.0, -1.0, 0.0],
            UpAxis::PosZ => [0.0, 0.0, 1.0],
            UpAxis::NegZ => [0.0, 0.0, -1.0],
        }
    }

    /// The code stored in the solution file.
    pub fn code(self) -> u32 {
        match self {
            UpAxis::PosY => 0,
            UpAxis::NegY => 1,
            UpAxis::PosZ => 2,
            UpAxis::NegZ => 3,
        }
    }

    /// Inverse of [`UpAxis::code`]; `None` for an unknown code.
    pub fn from_code(code: u32) -> Option<Self> {
        Some(match code {
            0 => UpAxis::PosY,
            1 => UpAxis::NegY,
            2 => UpAxis::PosZ,
            3 => UpAxis::NegZ,
            _ => return None,
        })
    }

    /// Parses `y`, `+y`, `-y`, `z`, `+z`, `-z` (case-insensitive).
    pub fn parse(text: &str) -> Option<Self> {
        Some(match text.trim().to_ascii_lowercase().as_str() {
            "y" | "+y" => UpAxis::PosY,
            "-y" => UpAxis::NegY,
            "z" | "+z" => UpAxis::PosZ,
            "-z" => UpAxis::NegZ,
            _ => return None,
        })
    }
}

impl std::fmt::Display for UpAxis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            UpAxis::PosY => "+y",
            UpAxis::NegY => "-y",
            UpAxis::PosZ => "+z",
            UpAxis::NegZ => "-z",
        })
    }
}

/// A pinhole camera in scene units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    pub eye: [f64; 3],
    pub target: [f64; 3],
    pub up: [f64; 3],
    /// Vertical field of view in degrees.
    pub fov_y_deg: f64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Default for Camera {
    /// Looks down -z from +z, as OpenGL does; scenes should name their own camera.
    fn default() -> Self {
        Camera {
            eye: [0.0, 0.0, 1.0],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 45.0,
            width: 512,
            height: 512,
        }
    }
}
