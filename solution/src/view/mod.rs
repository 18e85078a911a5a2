//! What the default-view chooser and the runtime share. The chooser itself (an
//! eye inside the enclosed space that sees lit surfaces, standing on the floor,
//! for a scene that names no camera) lives in the solver (`solver/src/view/`),
//! which runs it at solve time and stores the view as the header camera. This
//! module keeps what the runtime needs too:
//!
//! * the standing eye height [`EYE_HEIGHT_M`] (the runtime's default
//!   `camera_eye_height_m`, so the XR start pose stands on the floor the
//!   chooser found) and the chooser's figures that the runtime's help states;
//! * [`bvh`]: the triangle BVH the chooser casts its rays through, which the
//!   runtime will use for collision and teleport;
//! * [`fixture`]: the closed box room that the chooser's, the solver's and the
//!   runtime's tests share.

pub mod bvh;
pub mod fixture;

/// Standing eye height above a floor, metres (scaled by the header's
/// `units_per_metre`); also the runtime's default `camera_eye_height_m`.
pub const EYE_HEIGHT_M: f64 = 1.6;
/// The largest fraction of the floor-to-ceiling clearance the eye may stand at,
/// for rooms (or models) lower than [`EYE_HEIGHT_M`] / 0.7.
pub const EYE_HEIGHT_FRACTION: f64 = 0.7;
/// Survey rays per candidate.
pub const RAYS: usize = 128;
/// Candidate grid: two horizontal axes, then the vertical one.
pub const GRID: [usize; 3] = [4, 4, 3];
/// Fraction of survey rays that must meet front faces.
pub const MIN_FRONT_FRACTION: f64 = 0.75;
/// Fraction of survey rays that may meet back faces.
pub const MAX_BACK_FRACTION: f64 = 0.1;
/// Nearest surface allowed around the eye, metres.
pub const MIN_CLEARANCE_M: f64 = 0.3;
/// Vertical field of view of a chosen view, degrees: wider than the framing
/// camera's 45°, since the eye is inside the scene.
pub const FOV_Y_DEG: f64 = 60.0;
