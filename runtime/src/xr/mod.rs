//! The OpenXR backend: a headset session that implements [`crate::session::Session`],
//! so the frame loop is the same [`crate::session::run_frame`] the mock session
//! drives, and `runtime xr`.
//!
//! * [`system`]: the loader, the instance (with `XR_KHR_vulkan_enable2`, asking
//!   for the newest API version the loader accepts), the HMD system, and the
//!   checks on what it offers (primary stereo views, opaque blending, sRGB
//!   swapchain formats, Vulkan 1.1 within the runtime's range).
//! * [`vulkan`]: the Vulkan instance and device created through the runtime
//!   (`xrCreateVulkanInstanceKHR`, `xrGetVulkanGraphicsDevice2KHR`,
//!   `xrCreateVulkanDeviceKHR`).
//! * [`lifecycle`]: the session lifecycle as a pure state machine (events in,
//!   actions out), unit-tested against scripted event sequences.
//! * [`session`]: [`XrSession`], the single flow of OpenXR calls that carries the
//!   lifecycle's actions out and paces frames (wait, begin, locate views at the
//!   predicted display time, acquire, release, end).
//! * [`input`]: the action set (walk, snap turn, recentre, help) and its
//!   suggested bindings for common controllers.
//! * [`overlay`]: the help panel the menu button toggles (a quad layer).
//! * [`locomotion`]: the tracking space's place in the scene (units, up axis,
//!   walking, snap turns, recentring, IPD override), pure and unit-tested.
//! * [`config`]: comfort settings from `config/xr.toml`.
//! * [`cli`]: `runtime xr SOLUTION [--frames N]`.
//!
//! **Teardown order.** OpenXR handles go first (swapchain, spaces, actions,
//! session), then the renderer (which waits on its fence before destroying its
//! Vulkan objects, newest first), then the Vulkan device and instance, and the
//! OpenXR instance last: see [`cli::XrApp`]'s field order.

pub mod cli;
pub mod config;
pub mod exposure;
pub mod input;
pub mod lifecycle;
pub mod locomotion;
pub mod overlay;
pub mod session;
pub mod system;
pub mod vulkan;

pub use config::{ReferenceSpace, XrConfig};
pub use session::XrSession;
pub use system::XrSystem;

use openxr as xr;

/// The command to suggest when no headset can be used.
pub const MIRROR_HINT: &str = "use `runtime mirror` for the desktop stereo window";

/// Why the OpenXR backend stopped.
#[derive(Debug, thiserror::Error)]
pub enum XrError {
    #[error(
        "cannot load the OpenXR loader ({0}); install the Debian package `libopenxr-loader1` \
         and an OpenXR runtime, or {MIRROR_HINT}"
    )]
    NoLoader(String),
    #[error(
        "no OpenXR runtime is installed or none answers ({call}: {result}); install and start \
         one (e.g. Monado) and check XR_RUNTIME_JSON, or {MIRROR_HINT}"
    )]
    NoRuntime {
        call: &'static str,
        result: XrResult,
    },
    #[error("the OpenXR runtime {runtime} has no headset available ({result}); connect one, or {MIRROR_HINT}")]
    NoHeadset { runtime: String, result: XrResult },
    #[error("the OpenXR runtime {runtime} cannot be used: {reason}; {MIRROR_HINT}")]
    Unsupported { runtime: String, reason: String },
    #[error("OpenXR call {call} failed: {result}")]
    Call {
        call: &'static str,
        result: XrResult,
    },
    #[error("Vulkan call {call} (through OpenXR) failed: {result}")]
    Vulkan {
        call: &'static str,
        result: ash::vk::Result,
    },
    #[error(transparent)]
    Gpu(#[from] crate::gpu::GpuError),
    #[error(transparent)]
    Config(#[from] config::ConfigError),
}

/// An `XrResult` shown with its name and meaning, e.g.
/// `XR_ERROR_RUNTIME_UNAVAILABLE (the loader was unable to find or load a runtime)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct XrResult(pub xr::sys::Result);

impl std::fmt::Display for XrResult {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "XR_{:?} ({})", self.0, self.0)
    }
}

/// Shorthand for mapping an OpenXR result into [`XrError::Call`].
pub(crate) trait XrContext<T> {
    fn xr(self, call: &'static str) -> Result<T, XrError>;
}

impl<T> XrContext<T> for Result<T, xr::sys::Result> {
    fn xr(self, call: &'static str) -> Result<T, XrError> {
        self.map_err(|result| XrError::Call {
            call,
            result: XrResult(result),
        })
    }
}

impl XrError {
    /// The raw result of a failed OpenXR call, if this is one.
    pub fn xr_result(&self) -> Option<xr::sys::Result> {
        match self {
            XrError::Call { result, .. }
            | XrError::NoRuntime { result, .. }
            | XrError::NoHeadset { result, .. } => Some(result.0),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_read_with_name_and_meaning() {
        let e = XrError::NoRuntime {
            call: "xrEnumerateInstanceExtensionProperties",
            result: XrResult(xr::sys::Result::ERROR_RUNTIME_UNAVAILABLE),
        };
        let text = e.to_string();
        assert!(
            text.contains("XR_ERROR_RUNTIME_UNAVAILABLE (the loader was unable")
                && text.contains("runtime mirror")
                && !text.contains('\n'),
            "{text}"
        );
    }
}
