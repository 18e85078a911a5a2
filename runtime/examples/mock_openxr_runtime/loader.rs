//! Loader negotiation and the dispatch table: the runtime's one exported
//! symbol, and `xrGetInstanceProcAddr` naming every function it implements.

use crate::ffi::*;
use crate::*;
use openxr::sys as xr;
use std::ffi::c_char;

/// The loader's entry point into the runtime.
///
/// # Safety
///
/// Both pointers are valid, as the loader guarantees.
#[no_mangle]
pub unsafe extern "system" fn xrNegotiateLoaderRuntimeInterface(
    loader: *const openxr::sys::loader::XrNegotiateLoaderInfo,
    request: *mut openxr::sys::loader::XrNegotiateRuntimeRequest,
) -> xr::Result {
    // SAFETY: the loader passes valid negotiation structures (see `# Safety`).
    let (loader, request) = unsafe { (&*loader, &mut *request) };
    request.runtime_interface_version = 1;
    request.runtime_api_version = loader.max_api_version;
    request.get_instance_proc_addr = Some(get_instance_proc_addr);
    xr::Result::SUCCESS
}

macro_rules! table {
    ($name:expr, $( $s:literal => $f:ident ),* $(,)?) => {
        match $name {
            // SAFETY: a function pointer cast to the generic type the loader
            // expects; it casts it back to the named function's type.
            $( $s => Some(unsafe { std::mem::transmute::<*const (), xr::pfn::VoidFunction>($f as *const ()) }), )*
            _ => None,
        }
    };
}

unsafe extern "system" fn get_instance_proc_addr(
    _instance: xr::Instance,
    name: *const c_char,
    function: *mut Option<xr::pfn::VoidFunction>,
) -> xr::Result {
    // SAFETY: the name is a NUL-terminated string (the loader's pointer contract: crate notes).
    let name = unsafe { cstr(name) };
    let f = table!(name,
        "xrGetInstanceProcAddr" => get_instance_proc_addr,
        "xrEnumerateInstanceExtensionProperties" => enumerate_extensions,
        "xrCreateInstance" => create_instance,
        "xrDestroyInstance" => destroy_instance,
        "xrGetInstanceProperties" => instance_properties,
        "xrPollEvent" => poll_event,
        "xrGetSystem" => get_system,
        "xrEnumerateViewConfigurations" => view_configurations,
        "xrEnumerateEnvironmentBlendModes" => blend_modes,
        "xrEnumerateViewConfigurationViews" => view_configuration_views,
        "xrGetVulkanGraphicsRequirements2KHR" => graphics_requirements,
        "xrCreateVulkanInstanceKHR" => create_vulkan_instance,
        "xrGetVulkanGraphicsDevice2KHR" => graphics_device,
        "xrCreateVulkanDeviceKHR" => create_vulkan_device,
        "xrCreateSession" => create_session,
        "xrDestroySession" => destroy_session,
        "xrBeginSession" => begin_session,
        "xrEndSession" => end_session,
        "xrRequestExitSession" => request_exit,
        "xrEnumerateReferenceSpaces" => reference_spaces,
        "xrCreateReferenceSpace" => create_reference_space,
        "xrDestroySpace" => destroy_space,
        "xrLocateSpace" => locate_space,
        "xrLocateViews" => locate_views,
        "xrEnumerateSwapchainFormats" => swapchain_formats,
        "xrCreateSwapchain" => create_swapchain,
        "xrDestroySwapchain" => destroy_swapchain,
        "xrEnumerateSwapchainImages" => swapchain_images,
        "xrAcquireSwapchainImage" => acquire_image,
        "xrWaitSwapchainImage" => wait_image,
        "xrReleaseSwapchainImage" => release_image,
        "xrWaitFrame" => wait_frame,
        "xrBeginFrame" => begin_frame,
        "xrEndFrame" => end_frame,
        "xrStringToPath" => string_to_path,
        "xrCreateActionSet" => create_action_set,
        "xrDestroyActionSet" => destroy_nothing,
        "xrCreateAction" => create_action,
        "xrDestroyAction" => destroy_nothing,
        "xrSuggestInteractionProfileBindings" => suggest_bindings,
        "xrAttachSessionActionSets" => attach_action_sets,
        "xrSyncActions" => sync_actions,
        "xrGetActionStateBoolean" => action_boolean,
        "xrGetActionStateVector2f" => action_vector2,
        // Core functions `runtime xr` never calls: present (the loader and the
        // bindings fetch every core function), but unsupported.
        "xrEnumerateApiLayerProperties" => unsupported,
        "xrResultToString" => unsupported,
        "xrStructureTypeToString" => unsupported,
        "xrGetSystemProperties" => unsupported,
        "xrGetViewConfigurationProperties" => unsupported,
        "xrGetReferenceSpaceBoundsRect" => unsupported,
        "xrCreateActionSpace" => unsupported,
        "xrGetActionStateFloat" => unsupported,
        "xrGetActionStatePose" => unsupported,
        "xrEnumerateBoundSourcesForAction" => unsupported,
        "xrGetInputSourceLocalizedName" => unsupported,
        "xrApplyHapticFeedback" => unsupported,
        "xrStopHapticFeedback" => unsupported,
        "xrGetCurrentInteractionProfile" => unsupported,
        "xrPathToString" => unsupported,
    );
    // SAFETY: `function` is valid for writing (the loader's pointer contract: crate notes).
    unsafe { *function = f };
    if f.is_some() {
        xr::Result::SUCCESS
    } else {
        xr::Result::ERROR_FUNCTION_UNSUPPORTED
    }
}
