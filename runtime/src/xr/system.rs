//! The OpenXR loader, instance and head-mounted system, and the checks on what
//! the runtime offers.
//!
//! What conformant runtimes enforce, and how this module meets it:
//! * The instance enables `XR_KHR_vulkan_enable2` and asks for the newest API
//!   version the loader accepts: 1.1, then 1.0 (Debian 12's loader 1.0.20
//!   refuses 1.1 with `XR_ERROR_API_VERSION_UNSUPPORTED`).
//! * Only the primary stereo view configuration and the opaque blend mode are
//!   used; a runtime that offers neither is refused with a clear message.
//! * `xrGetVulkanGraphicsRequirements2KHR` is called here, before any session
//!   exists (runtimes fail `xrCreateSession` otherwise), and Vulkan 1.1 must lie
//!   within the range it reports.
//! * The per-eye image size is the runtime's recommendation (as small as
//!   320×240 on some), and the swapchain format is the runtime's first sRGB
//!   colour format (the renderer's tone map relies on the sRGB encoding).

use super::{XrContext, XrError, XrResult};
use ash::vk;
use openxr as xr;
use std::path::Path;

/// The loader's file names, tried in order: Debian's `libopenxr-loader1` ships
/// only the versioned name (the unversioned link is in the -dev package).
pub const LOADER_NAMES: &[&str] = &["libopenxr_loader.so.1", "libopenxr_loader.so"];

/// API versions asked for, newest first.
pub const API_VERSIONS: [xr::Version; 2] = [xr::Version::new(1, 1, 0), xr::Version::new(1, 0, 0)];

/// The Vulkan version the renderer needs (multiview is core in 1.1).
pub const VULKAN_VERSION: xr::Version = xr::Version::new(1, 1, 0);

/// The only view configuration and blend mode used.
pub const VIEW_TYPE: xr::ViewConfigurationType = xr::ViewConfigurationType::PRIMARY_STEREO;
pub const BLEND_MODE: xr::EnvironmentBlendMode = xr::EnvironmentBlendMode::OPAQUE;

/// The OpenXR instance and the headset it drives.
pub struct XrSystem {
    pub instance: xr::Instance,
    pub system: xr::SystemId,
    /// "name version" of the runtime, for messages.
    pub runtime: String,
    /// The API version the instance was created with.
    pub api_version: xr::Version,
    /// Per-eye image size of the swapchain (the runtime's recommendation).
    pub width: u32,
    pub height: u32,
    pub requirements: xr::vulkan::Requirements,
}

/// Silences the loader's own stderr log (several lines per failure), unless the
/// user set `XR_LOADER_DEBUG`: our errors carry the result code in one line.
///
/// Call before any other thread starts (it changes the environment).
pub fn quiet_loader_log() {
    if std::env::var_os("XR_LOADER_DEBUG").is_none() {
        std::env::set_var("XR_LOADER_DEBUG", "none");
    }
}

/// Loads the OpenXR loader library.
pub fn load_entry() -> Result<xr::Entry, XrError> {
    let mut failures = Vec::new();
    for name in LOADER_NAMES {
        // SAFETY: these names are the Khronos OpenXR loader's, which provides
        // every core entry point with the specification's semantics — the
        // contract `load_from` asks for.
        match unsafe { xr::Entry::load_from(Path::new(name)) } {
            Ok(entry) => return Ok(entry),
            Err(e) => failures.push(format!("{name}: {e}")),
        }
    }
    Err(XrError::NoLoader(failures.join("; ")))
}

/// Tries `create` with each version in turn, moving on only when the version
/// is refused; returns what it made and the version that worked.
pub fn with_version_fallback<T>(
    versions: &[xr::Version],
    mut create: impl FnMut(xr::Version) -> Result<T, xr::sys::Result>,
) -> Result<(T, xr::Version), xr::sys::Result> {
    let mut last = xr::sys::Result::ERROR_API_VERSION_UNSUPPORTED;
    for &version in versions {
        match create(version) {
            Ok(made) => return Ok((made, version)),
            Err(xr::sys::Result::ERROR_API_VERSION_UNSUPPORTED) => {
                last = xr::sys::Result::ERROR_API_VERSION_UNSUPPORTED
            }
            Err(e) => return Err(e),
        }
    }
    Err(last)
}

/// Whether Vulkan `wanted` lies in the runtime's range (any minor version of
/// the highest major it supports is accepted, as the extension specifies).
pub fn vulkan_version_ok(requirements: &xr::vulkan::Requirements, wanted: xr::Version) -> bool {
    wanted >= requirements.min_api_version_supported
        && wanted.major() <= requirements.max_api_version_supported.major()
}

/// The runtime's first sRGB 8-bit colour format (it lists formats in its order
/// of preference).
pub fn choose_swapchain_format(offered: &[vk::Format]) -> Option<vk::Format> {
    offered.iter().copied().find(|f| {
        matches!(
            *f,
            vk::Format::R8G8B8A8_SRGB
                | vk::Format::B8G8R8A8_SRGB
                | vk::Format::A8B8G8R8_SRGB_PACK32
        )
    })
}

/// One image size for both eyes (the swapchain is one two-layer array, as
/// multiview needs): the larger recommendation in each dimension, within the
/// smaller maximum.
pub fn choose_image_size(views: &[xr::ViewConfigurationView]) -> Result<(u32, u32), String> {
    if views.len() != 2 {
        return Err(format!(
            "the primary stereo configuration has {} views, not 2",
            views.len()
        ));
    }
    let width = views.iter().map(|v| v.recommended_image_rect_width).max();
    let height = views.iter().map(|v| v.recommended_image_rect_height).max();
    let max_w = views.iter().map(|v| v.max_image_rect_width).min();
    let max_h = views.iter().map(|v| v.max_image_rect_height).min();
    let (w, h) = match (width, height, max_w, max_h) {
        (Some(w), Some(h), Some(mw), Some(mh)) => (w.min(mw), h.min(mh)),
        _ => return Err("no view sizes".into()),
    };
    let max_side = solution::camera::MAX_IMAGE_SIDE;
    if w == 0 || h == 0 || w > max_side || h > max_side {
        return Err(format!(
            "recommended image size {w}x{h} is outside 1..={max_side} pixels"
        ));
    }
    Ok((w, h))
}

impl XrSystem {
    /// Loads OpenXR, creates the instance and finds the headset; every check
    /// that needs no session happens here.
    pub fn new() -> Result<XrSystem, XrError> {
        let entry = load_entry()?;
        let available = entry
            .enumerate_extensions()
            .map_err(|result| XrError::NoRuntime {
                call: "xrEnumerateInstanceExtensionProperties",
                result: XrResult(result),
            })?;
        if !available.khr_vulkan_enable2 {
            return Err(XrError::Unsupported {
                runtime: "(active runtime)".into(),
                reason: "it does not offer XR_KHR_vulkan_enable2".into(),
            });
        }
        let mut extensions = xr::ExtensionSet::default();
        extensions.khr_vulkan_enable2 = true;
        let (instance, api_version) = with_version_fallback(&API_VERSIONS, |api_version| {
            entry.create_instance(
                &xr::ApplicationInfo {
                    application_name: "radiosity walkthrough",
                    application_version: 1,
                    engine_name: "runtime",
                    engine_version: 1,
                    api_version,
                },
                &extensions,
                &[],
            )
        })
        .map_err(|result| match result {
            xr::sys::Result::ERROR_RUNTIME_UNAVAILABLE
            | xr::sys::Result::ERROR_RUNTIME_FAILURE
            | xr::sys::Result::ERROR_INSTANCE_LOST => XrError::NoRuntime {
                call: "xrCreateInstance",
                result: XrResult(result),
            },
            _ => XrError::Call {
                call: "xrCreateInstance",
                result: XrResult(result),
            },
        })?;
        let runtime = instance
            .properties()
            .map(|p| format!("{} {}", p.runtime_name, p.runtime_version))
            .unwrap_or_else(|_| "(unnamed)".into());
        let unsupported = |reason: String| XrError::Unsupported {
            runtime: runtime.clone(),
            reason,
        };

        let system = instance
            .system(xr::FormFactor::HEAD_MOUNTED_DISPLAY)
            .map_err(|result| match result {
                xr::sys::Result::ERROR_FORM_FACTOR_UNAVAILABLE
                | xr::sys::Result::ERROR_FORM_FACTOR_UNSUPPORTED => XrError::NoHeadset {
                    runtime: runtime.clone(),
                    result: XrResult(result),
                },
                _ => XrError::Call {
                    call: "xrGetSystem",
                    result: XrResult(result),
                },
            })?;

        let configurations = instance
            .enumerate_view_configurations(system)
            .xr("xrEnumerateViewConfigurations")?;
        if !configurations.contains(&VIEW_TYPE) {
            return Err(unsupported(format!(
                "it offers no primary stereo view configuration (offered: {configurations:?})"
            )));
        }
        let blend_modes = instance
            .enumerate_environment_blend_modes(system, VIEW_TYPE)
            .xr("xrEnumerateEnvironmentBlendModes")?;
        if !blend_modes.contains(&BLEND_MODE) {
            return Err(unsupported(format!(
                "it offers no opaque blend mode (offered: {blend_modes:?})"
            )));
        }
        let views = instance
            .enumerate_view_configuration_views(system, VIEW_TYPE)
            .xr("xrEnumerateViewConfigurationViews")?;
        let (width, height) = choose_image_size(&views).map_err(unsupported)?;

        // Must precede xrCreateSession (and xrCreateVulkanInstanceKHR).
        let requirements = instance
            .graphics_requirements::<xr::Vulkan>(system)
            .xr("xrGetVulkanGraphicsRequirements2KHR")?;
        if !vulkan_version_ok(&requirements, VULKAN_VERSION) {
            return Err(unsupported(format!(
                "it needs Vulkan {} to {}.x, and the renderer uses {}",
                requirements.min_api_version_supported,
                requirements.max_api_version_supported.major(),
                VULKAN_VERSION
            )));
        }
        Ok(XrSystem {
            instance,
            system,
            runtime,
            api_version,
            width,
            height,
            requirements,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view(w: u32, h: u32, mw: u32, mh: u32) -> xr::ViewConfigurationView {
        xr::ViewConfigurationView {
            recommended_image_rect_width: w,
            max_image_rect_width: mw,
            recommended_image_rect_height: h,
            max_image_rect_height: mh,
            recommended_swapchain_sample_count: 1,
            max_swapchain_sample_count: 4,
        }
    }

    #[test]
    fn version_fallback_moves_on_only_when_refused() {
        let mut asked = Vec::new();
        // A 1.0-only loader (Debian 12's 1.0.20): 1.1 is refused, 1.0 works.
        let got = with_version_fallback(&API_VERSIONS, |v| {
            asked.push(v);
            if v.minor() >= 1 {
                Err(xr::sys::Result::ERROR_API_VERSION_UNSUPPORTED)
            } else {
                Ok("instance")
            }
        });
        assert_eq!(got, Ok(("instance", xr::Version::new(1, 0, 0))));
        assert_eq!(asked, API_VERSIONS.to_vec());
        // Any other failure (no runtime) is reported at once.
        let mut calls = 0;
        let got: Result<((), _), _> = with_version_fallback(&API_VERSIONS, |_| {
            calls += 1;
            Err(xr::sys::Result::ERROR_RUNTIME_UNAVAILABLE)
        });
        assert_eq!(got, Err(xr::sys::Result::ERROR_RUNTIME_UNAVAILABLE));
        assert_eq!(calls, 1);
        // Every version refused.
        let got: Result<((), _), _> = with_version_fallback(&API_VERSIONS, |_| {
            Err(xr::sys::Result::ERROR_API_VERSION_UNSUPPORTED)
        });
        assert_eq!(got, Err(xr::sys::Result::ERROR_API_VERSION_UNSUPPORTED));
    }

    #[test]
    fn vulkan_range_check() {
        let req = |min: (u16, u16), max: (u16, u16)| xr::vulkan::Requirements {
            min_api_version_supported: xr::Version::new(min.0, min.1, 0),
            max_api_version_supported: xr::Version::new(max.0, max.1, 0),
        };
        assert!(vulkan_version_ok(&req((1, 0), (1, 3)), VULKAN_VERSION));
        // "1.0 to 1.0" still accepts 1.1: the maximum bounds the major only.
        assert!(vulkan_version_ok(&req((1, 0), (1, 0)), VULKAN_VERSION));
        assert!(!vulkan_version_ok(&req((1, 2), (1, 3)), VULKAN_VERSION));
        assert!(!vulkan_version_ok(&req((2, 0), (2, 1)), VULKAN_VERSION));
    }

    #[test]
    fn format_is_the_first_srgb_in_the_runtimes_order() {
        let offered = [
            vk::Format::R16G16B16A16_SFLOAT,
            vk::Format::B8G8R8A8_SRGB,
            vk::Format::R8G8B8A8_SRGB,
        ];
        assert_eq!(
            choose_swapchain_format(&offered),
            Some(vk::Format::B8G8R8A8_SRGB)
        );
        assert_eq!(choose_swapchain_format(&[vk::Format::R8G8B8A8_UNORM]), None);
    }

    #[test]
    fn image_size_covers_both_eyes_within_limits() {
        // The smallest conformant recommendation.
        assert_eq!(
            choose_image_size(&[view(320, 240, 4096, 4096), view(320, 240, 4096, 4096)]),
            Ok((320, 240))
        );
        // Differing eyes: the larger recommendation, within the smaller maximum.
        assert_eq!(
            choose_image_size(&[view(1000, 1100, 1200, 2000), view(1050, 1080, 2000, 1090)]),
            Ok((1050, 1090))
        );
        assert!(choose_image_size(&[view(320, 240, 320, 240)]).is_err());
        assert!(choose_image_size(&[view(0, 240, 320, 240), view(0, 240, 320, 240)]).is_err());
    }
}
