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
//! The GPU context ([`crate::gpu::Gpu`]) owns the results: [`create_gpu`]
//! hands it these three steps through its `VulkanFactory` hook.

use super::{system::XrSystem, XrError, XrResult};
use crate::gpu::{Gpu, GpuDesc, GpuError, GpuExtensions, VulkanFactory};
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

/// [`XrVulkanFactory`] as the GPU context's [`VulkanFactory`]: OpenXR failures
/// become [`GpuError::Unsupported`] carrying the OpenXR message.
struct GpuHook {
    factory: XrVulkanFactory,
    /// The Vulkan loader the instance was made with (its
    /// `vkGetInstanceProcAddr` is handed to OpenXR again for the device).
    entry: Option<ash::Entry>,
}

fn hook_error(e: XrError) -> GpuError {
    GpuError::Unsupported(e.to_string())
}

impl VulkanFactory for GpuHook {
    unsafe fn create_instance(
        &mut self,
        entry: &ash::Entry,
        info: &vk::InstanceCreateInfo<'_>,
    ) -> Result<vk::Instance, GpuError> {
        self.entry = Some(entry.clone());
        // SAFETY: the GPU context passes a valid create info (the trait's
        // contract), and XrSystem::new called xrGetVulkanGraphicsRequirements2KHR.
        unsafe { self.factory.create_instance(entry, info) }.map_err(hook_error)
    }

    unsafe fn physical_device(
        &mut self,
        instance: &ash::Instance,
    ) -> Result<Option<vk::PhysicalDevice>, GpuError> {
        // SAFETY: the instance came from `create_instance` above.
        unsafe { self.factory.physical_device(instance.handle()) }
            .map(Some)
            .map_err(hook_error)
    }

    unsafe fn create_device(
        &mut self,
        _instance: &ash::Instance,
        physical: vk::PhysicalDevice,
        info: &vk::DeviceCreateInfo<'_>,
    ) -> Result<vk::Device, GpuError> {
        let entry = self
            .entry
            .as_ref()
            .ok_or_else(|| GpuError::Unsupported("device requested before the instance".into()))?;
        // SAFETY: `physical` is the device `physical_device` named (the GPU
        // context passes it back), and the create info is valid (the trait's
        // contract).
        unsafe { self.factory.create_device(entry, physical, info) }.map_err(hook_error)
    }
}

/// The GPU context for a headset session: Vulkan 1.1 instance and device
/// created through the runtime, on the physical device it names.
pub fn create_gpu(system: &XrSystem, validation: bool) -> Result<Gpu, XrError> {
    let mut hook = GpuHook {
        factory: XrVulkanFactory::new(system),
        entry: None,
    };
    Ok(Gpu::with_factory(
        &GpuDesc { validation },
        &GpuExtensions::default(),
        &mut hook,
    )?)
}
