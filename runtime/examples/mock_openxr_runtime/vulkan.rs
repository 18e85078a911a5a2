//! `XR_KHR_vulkan_enable2`: the graphics requirements, and the Vulkan instance
//! and device made through the runtime (so the session can check it gets them).

use crate::state::*;
use ash::vk::{self, Handle};
use openxr::sys as xr;

pub(crate) unsafe extern "system" fn graphics_requirements(
    _i: xr::Instance,
    _s: xr::SystemId,
    out: *mut xr::GraphicsRequirementsVulkanKHR,
) -> xr::Result {
    // SAFETY: `out` is valid for writing (the loader's pointer contract: crate notes).
    let out = unsafe { &mut *out };
    out.min_api_version_supported = xr::Version::new(1, 0, 0);
    out.max_api_version_supported = xr::Version::new(1, 3, 0);
    with(|s| {
        s.requirements_queried = true;
        s.report.requirements_queried = true;
    });
    xr::Result::SUCCESS
}

pub(crate) unsafe extern "system" fn create_vulkan_instance(
    _i: xr::Instance,
    info: *const xr::VulkanInstanceCreateInfoKHR,
    out: *mut xr::platform::VkInstance,
    vk_result: *mut xr::platform::VkResult,
) -> xr::Result {
    // SAFETY: `info` is valid for reading (the loader's pointer contract: crate notes).
    let info = unsafe { &*info };
    with(|s| {
        if !s.requirements_queried {
            return xr::Result::ERROR_GRAPHICS_REQUIREMENTS_CALL_MISSING;
        }
        let Some(gipa) = info.pfn_get_instance_proc_addr else {
            return violation(s, "no pfnGetInstanceProcAddr".into());
        };
        // SAFETY: both are the Vulkan loader's vkGetInstanceProcAddr type.
        let gipa: vk::PFN_vkGetInstanceProcAddr = unsafe { std::mem::transmute(gipa) };
        // SAFETY: `gipa` is the application's Vulkan loader entry point.
        let entry = unsafe {
            ash::Entry::from_static_fn(ash::StaticFn {
                get_instance_proc_addr: gipa,
            })
        };
        // SAFETY: `vulkanCreateInfo` points to the application's valid Vulkan create info (the loader's pointer contract: crate notes).
        let create = unsafe { &*(info.vulkan_create_info as *const vk::InstanceCreateInfo) };
        // SAFETY: a Vulkan create info's application info is null or valid for reading.
        let version = unsafe { create.p_application_info.as_ref() }
            .map(|a| a.api_version)
            .unwrap_or(0);
        if version < vk::API_VERSION_1_1 {
            violation(s, format!("Vulkan instance asks for {version:#x} < 1.1"));
        }
        // SAFETY: the application's create info, valid for the call (module notes).
        match unsafe { entry.create_instance(create, None) } {
            Ok(instance) => {
                // SAFETY: `out` is valid for writing (the loader's pointer contract: crate notes).
                unsafe { *out = instance.handle().as_raw() as usize as _ };
                // SAFETY: `vk_result` is valid for writing (the loader's pointer contract: crate notes).
                unsafe { *vk_result = 0 };
                s.vulkan = Some(VulkanSide {
                    gipa,
                    instance: Some(instance),
                    physical: vk::PhysicalDevice::null(),
                    device: None,
                    queue: None,
                });
                s.report.vulkan_instance_created = true;
            }
            // SAFETY: `vk_result` is valid for writing (the loader's pointer contract: crate notes).
            Err(e) => unsafe { *vk_result = e.as_raw() },
        }
        xr::Result::SUCCESS
    })
}

pub(crate) unsafe extern "system" fn graphics_device(
    _i: xr::Instance,
    info: *const xr::VulkanGraphicsDeviceGetInfoKHR,
    out: *mut xr::platform::VkPhysicalDevice,
) -> xr::Result {
    // SAFETY: `info` is valid for reading (the loader's pointer contract: crate notes).
    let info = unsafe { &*info };
    with(|s| {
        let Some(v) = s.vulkan.as_mut() else {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        };
        let Some(instance) = &v.instance else {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        };
        if instance.handle().as_raw() as usize != info.vulkan_instance as usize {
            return violation(
                s,
                "device asked for an instance not made by xrCreateVulkanInstanceKHR".into(),
            );
        }
        // SAFETY: the instance this runtime created.
        let devices = unsafe { instance.enumerate_physical_devices() }.unwrap_or_default();
        let Some(&physical) = devices.first() else {
            return xr::Result::ERROR_RUNTIME_FAILURE;
        };
        v.physical = physical;
        // SAFETY: `out` is valid for writing (the loader's pointer contract: crate notes).
        unsafe { *out = physical.as_raw() as usize as _ };
        xr::Result::SUCCESS
    })
}

pub(crate) unsafe extern "system" fn create_vulkan_device(
    _i: xr::Instance,
    info: *const xr::VulkanDeviceCreateInfoKHR,
    out: *mut xr::platform::VkDevice,
    vk_result: *mut xr::platform::VkResult,
) -> xr::Result {
    // SAFETY: `info` is valid for reading (the loader's pointer contract: crate notes).
    let info = unsafe { &*info };
    with(|s| {
        let Some(v) = s.vulkan.as_mut() else {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        };
        let physical = vk::PhysicalDevice::from_raw(info.vulkan_physical_device as usize as u64);
        if physical != v.physical || physical == vk::PhysicalDevice::null() {
            return xr::Result::ERROR_HANDLE_INVALID;
        }
        let Some(instance) = &v.instance else {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        };
        // SAFETY: `vulkanCreateInfo` points to the application's valid Vulkan create info (the loader's pointer contract: crate notes).
        let create = unsafe { &*(info.vulkan_create_info as *const vk::DeviceCreateInfo) };
        // SAFETY: `physical` was checked to be the device named above; the
        // create info is the application's.
        match unsafe { instance.create_device(physical, create, None) } {
            Ok(device) => {
                // SAFETY: `out` is valid for writing (the loader's pointer contract: crate notes).
                unsafe { *out = device.handle().as_raw() as usize as _ };
                // SAFETY: `vk_result` is valid for writing (the loader's pointer contract: crate notes).
                unsafe { *vk_result = 0 };
                v.device = Some(device);
                s.report.vulkan_device_created = true;
            }
            // SAFETY: `vk_result` is valid for writing (the loader's pointer contract: crate notes).
            Err(e) => unsafe { *vk_result = e.as_raw() },
        }
        let _ = v.gipa;
        xr::Result::SUCCESS
    })
}
