//! The Vulkan instance and device, created through the OpenXR runtime
//! (`XR_KHR_vulkan_enable2`): the runtime adds the instance and device
//! extensions its compositor needs, and names the one physical device it can
//! share images with.
//!
//! The three steps, in the order the extension requires (after
//! `xrGetVulkanGraphicsRequirements2KHR`, which [`super::XrSystem::new`] calls):
//! 1. [`XrVulkanFactory::create_instance`]: `xrCreateVulkanInstanceKHR` with the
//!    renderer's `VkInstanceCreateInfo` (API version 1.1, validation layer when
//!    asked);
//! 2. [`XrVulkanFactory::physical_device`]: `xrGetVulkanGraphicsDevice2KHR` —
//!    exactly this device must be used;
//! 3. [`XrVulkanFactory::create_device`]: `xrCreateVulkanDeviceKHR` on it with
//!    the renderer's `VkDeviceCreateInfo` (one graphics queue, multiview on).
//!
//! The GPU context ([`crate::gpu::Gpu`]) owns the results. It creates its
//! instance and device itself today (`Gpu::new`); [`create_gpu`] needs a way to
//! hand it these three steps instead, which the GPU module does not offer yet
//! (see its notes).

use super::{system::XrSystem, XrError, XrResult};
use crate::gpu::Gpu;
use ash::vk::{self, Handle};
use openxr as xr;

/// Creates the renderer's Vulkan objects through the OpenXR runtime.
pub struct XrVulkanFactory {
    instance: xr::Instance,
    system: xr::SystemId,
    runtime: String,
}

fn vk_call(
    call: &'static str,
    result: Result<Result<usize, i32>, xr::sys::Result>,
) -> Result<usize, XrError> {
    match result {
        Err(result) => Err(XrError::Call {
            call,
            result: XrResult(result),
        }),
        Ok(Err(code)) => Err(XrError::Vulkan {
            call,
            result: vk::Result::from_raw(code),
        }),
        Ok(Ok(handle)) => Ok(handle),
    }
}

impl XrVulkanFactory {
    pub fn new(system: &XrSystem) -> XrVulkanFactory {
        XrVulkanFactory {
            instance: system.instance.clone(),
            system: system.system,
            runtime: system.runtime.clone(),
        }
    }

    /// `vkGetInstanceProcAddr` of `entry` in the type OpenXR expects.
    fn get_instance_proc_addr(entry: &ash::Entry) -> xr::sys::platform::VkGetInstanceProcAddr {
        let f: vk::PFN_vkGetInstanceProcAddr = entry.static_fn().get_instance_proc_addr;
        // SAFETY: both types are `extern "system"` functions of a dispatchable
        // handle (a pointer-sized value in both bindings) and a C string,
        // returning an optional function pointer: the same ABI.
        unsafe {
            std::mem::transmute::<
                vk::PFN_vkGetInstanceProcAddr,
                xr::sys::platform::VkGetInstanceProcAddr,
            >(f)
        }
    }

    /// `xrCreateVulkanInstanceKHR`.
    ///
    /// # Safety
    ///
    /// `info` and everything it points to are valid for the call, and
    /// `xrGetVulkanGraphicsRequirements2KHR` was called (by [`XrSystem::new`]).
    pub unsafe fn create_instance(
        &self,
        entry: &ash::Entry,
        info: &vk::InstanceCreateInfo<'_>,
    ) -> Result<vk::Instance, XrError> {
        // SAFETY: the caller guarantees `info`; the proc-address function comes
        // from a loaded Vulkan loader.
        let made = unsafe {
            self.instance.create_vulkan_instance(
                self.system,
                Self::get_instance_proc_addr(entry),
                info as *const vk::InstanceCreateInfo<'_> as *const _,
            )
        };
        let raw = vk_call(
            "xrCreateVulkanInstanceKHR",
            made.map(|r| r.map(|h| h as usize)),
        )?;
        Ok(vk::Instance::from_raw(raw as u64))
    }

    /// `xrGetVulkanGraphicsDevice2KHR`: the physical device the runtime
    /// requires.
    ///
    /// # Safety
    ///
    /// `instance` was made by [`XrVulkanFactory::create_instance`] and is alive.
    pub unsafe fn physical_device(
        &self,
        instance: vk::Instance,
    ) -> Result<vk::PhysicalDevice, XrError> {
        // SAFETY: the caller guarantees the instance came from
        // xrCreateVulkanInstanceKHR on this OpenXR instance and system.
        let made = unsafe {
            self.instance
                .vulkan_graphics_device(self.system, instance.as_raw() as usize as _)
        };
        let raw = made.map_err(|result| XrError::Call {
            call: "xrGetVulkanGraphicsDevice2KHR",
            result: XrResult(result),
        })?;
        if raw.is_null() {
            return Err(XrError::Unsupported {
                runtime: self.runtime.clone(),
                reason: "it named no Vulkan physical device".into(),
            });
        }
        Ok(vk::PhysicalDevice::from_raw(raw as usize as u64))
    }

    /// `xrCreateVulkanDeviceKHR` on `physical`.
    ///
    /// # Safety
    ///
    /// `physical` came from [`XrVulkanFactory::physical_device`], and `info` and
    /// everything it points to are valid for the call.
    pub unsafe fn create_device(
        &self,
        entry: &ash::Entry,
        physical: vk::PhysicalDevice,
        info: &vk::DeviceCreateInfo<'_>,
    ) -> Result<vk::Device, XrError> {
        // SAFETY: the caller guarantees `physical` and `info`.
        let made = unsafe {
            self.instance.create_vulkan_device(
                self.system,
                Self::get_instance_proc_addr(entry),
                physical.as_raw() as usize as _,
                info as *const vk::DeviceCreateInfo<'_> as *const _,
            )
        };
        let raw = vk_call(
            "xrCreateVulkanDeviceKHR",
            made.map(|r| r.map(|h| h as usize)),
        )?;
        Ok(vk::Device::from_raw(raw as u64))
    }
}

/// The GPU context for a headset session: Vulkan created through the runtime.
///
/// Not available yet: [`Gpu`] creates its instance and device itself
/// (`vkCreateInstance`, its own device choice, `vkCreateDevice`), and has no
/// way to let [`XrVulkanFactory`] do those three steps. A GPU context made by
/// `Gpu::new` would lack the runtime's required extensions and may sit on
/// another device, which conformant runtimes refuse, so this reports the gap
/// instead of pretending.
pub fn create_gpu(system: &XrSystem, validation: bool) -> Result<Gpu, XrError> {
    let _ = (XrVulkanFactory::new(system), validation);
    Err(XrError::Unsupported {
        runtime: system.runtime.clone(),
        reason: "this build cannot yet create its Vulkan device through OpenXR \
                 (xrCreateVulkanInstanceKHR/xrCreateVulkanDeviceKHR need a hook in gpu::Gpu)"
            .into(),
    })
}
