//! A scripted OpenXR runtime for testing `runtime xr` without a headset: a
//! shared library the OpenXR loader loads through a runtime manifest
//! (`XR_RUNTIME_JSON`). It implements the calls `runtime xr` makes, enforces the
//! rules conformant runtimes enforce (requirements queried before the Vulkan
//! instance and the session; the session on exactly the Vulkan instance,
//! physical device and device made through it; begin only when READY, end only
//! when STOPPING; frames ended with the predicted time, opaque blending, and
//! projection views that match the located eyes and released images), drives
//! the session lifecycle, and writes a JSON report when the instance is
//! destroyed.
//!
//! Environment (all optional):
//! * `MOCK_XR_REPORT`: file the JSON report is written to.
//! * `MOCK_XR_API`: the highest API version accepted, `1.0` (default) or `1.1`.
//! * `MOCK_XR_LOSS_AFTER`: after this many ended frames, the first session
//!   reports LOSS_PENDING (a second session then runs normally).
//! * `MOCK_XR_HELP_AT`: the frame at which the help (left menu) button is
//!   pressed.
//! * `MOCK_XR_NO_STAGE`: offer no STAGE space.
//! * `MOCK_XR_WALK`: `x,y` deflection of both thumbsticks (default centred).
//! * `MOCK_XR_CAPTURE`: file the last projection frame's image is written to
//!   (both layers, 4 bytes per pixel, in the swapchain's format).
//!
//! **Safety.** Every entry point is an `unsafe extern "system" fn` called by
//! the OpenXR loader with the application's arguments; the invariant the
//! pointer dereferences rely on is the specification's (the loader's pointer
//! contract): every input pointer is valid for reading its structure, every
//! output pointer for writing it, and a capacity names how many elements an
//! output array holds. Each `unsafe` block's `// SAFETY:` comment names the
//! pointer it relies on; Vulkan calls additionally rely on the handles being
//! the ones this runtime created, as stated where they occur.
//!
//! Views: 320×240 recommended per eye (the smallest conformant size), an IPD
//! of 63 mm, asymmetric fields of view mirrored between the eyes, and a head
//! that sways a little with time, so poses differ per eye and per frame.
//!
//! Modules, one job each: `loader` (negotiation and the dispatch table),
//! `instance` (instance, system, events, the report), `vulkan`
//! (`XR_KHR_vulkan_enable2`), `session` (the session state machine), `frame`
//! (wait, begin and end frame with the layer checks), `spaces` (the scripted
//! head, spaces and views), `swapchain` (Vulkan images and their read-back),
//! `actions` (paths, actions and their scripted states), `script` (the
//! environment), `state` (the one global state) and `ffi` (C-side helpers).

mod actions;
mod ffi;
mod frame;
mod instance;
mod loader;
mod script;
mod session;
mod spaces;
mod state;
mod swapchain;
mod vulkan;

pub use loader::xrNegotiateLoaderRuntimeInterface;

pub(crate) use actions::*;
pub(crate) use frame::*;
pub(crate) use instance::*;
pub(crate) use session::*;
pub(crate) use spaces::*;
pub(crate) use swapchain::*;
pub(crate) use vulkan::*;

/// The predicted display period (500 Hz, so tests run quickly).
pub(crate) const FRAME_PERIOD_NS: i64 = 2_000_000;
/// The recommended per-eye image size.
pub(crate) const WIDTH: u32 = 320;
pub(crate) const HEIGHT: u32 = 240;
/// The interpupillary distance in metres.
pub(crate) const IPD_M: f32 = 0.063;
