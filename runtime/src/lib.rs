//! Stereo walkthrough runtime: loads a solution file and renders it per eye with
//! Vulkan, evaluating each vertex's spherical harmonics toward the eye in the
//! vertex shader (design notes, "The system in one paragraph").
//!
//! * [`gpu`]: the Vulkan context and resource wrappers (ash).
//! * [`render`]: the stereo renderer (multiview, with the per-view workaround for
//!   lavapipe's multiview clipping bug), exposure and tone mapping.
//! * [`session`]: the session trait the frame loop is written against, and the
//!   mock session (scripted head poses, offscreen swapchain).
//! * [`cli`]: `runtime screenshot` and `runtime bench`.

// Shipped code: Clippy checks clippy.toml's lists here (ARCHITECTURE.md's invariants).
#![cfg_attr(not(test), warn(clippy::disallowed_methods, clippy::disallowed_macros))]
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

pub mod cli;
pub mod gpu;
pub mod mirror;
pub mod render;
pub mod session;
pub mod xr;
