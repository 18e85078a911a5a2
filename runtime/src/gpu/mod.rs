//! The Vulkan context: instance, optional validation, physical-device selection,
//! logical device and queue, through `ash`.
//!
//! Ownership (kajiya style): every Vulkan object is held by a small wrapper with a
//! `raw` handle, built from a `*Desc`. Wrappers keep an `Arc<DeviceShared>`, so the
//! device and instance are destroyed only after the last resource made from them
//! (see [`DeviceShared`]'s `Drop`). Structs that own several wrappers declare their
//! fields newest-first, so Rust's in-order field drop tears them down in reverse
//! order of creation, and they wait on their fences before that.
//!
//! Any Vulkan 1.1 device is accepted (multiview is core in 1.1), including
//! lavapipe, Mesa's CPU device. With `validation` set, `VK_LAYER_KHRONOS_validation`
//! is enabled and every message it sends is logged to stderr and counted
//! ([`ValidationLog`]); the tests assert that the count stays zero.

pub mod barrier;
pub mod pipeline;
mod resources;
pub mod shaders;

pub use resources::{Buffer, BufferDesc, Image, ImageDesc, MemoryLocation};

use ash::vk;
use std::ffi::{c_void, CStr};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// The Debian packages that provide a Vulkan loader and a CPU device; named in
/// every "no Vulkan" error.
pub const VULKAN_PACKAGES: &str = "libvulkan1 mesa-vulkan-drivers";

/// The environment variable that turns validation on (`1`, `true` or `yes`).
pub const VALIDATION_ENV: &str = "RUNTIME_VALIDATION";

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Why the GPU context could not be created.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "cannot load the Vulkan loader (libvulkan.so.1): {0}; install the Debian packages \
         `{VULKAN_PACKAGES}`"
    )]
    NoLoader(String),
    #[error(
        "no Vulkan 1.1 device found ({0}); install the Debian packages `{VULKAN_PACKAGES}` \
         (lavapipe, a CPU device, is enough), and check VK_ICD_FILENAMES"
    )]
    NoDevice(String),
    #[error(
        "validation was requested but the layer VK_LAYER_KHRONOS_validation is not installed; \
         install the Debian package `vulkan-validationlayers`"
    )]
    NoValidationLayer,
    #[error("Vulkan call {call} failed: {result}")]
    Vulkan {
        call: &'static str,
        result: vk::Result,
    },
    #[error("{0}")]
    Unsupported(String),
}

/// Shorthand for mapping a `vk::Result` into [`GpuError::Vulkan`].
pub(crate) trait VkContext<T> {
    fn ctx(self, call: &'static str) -> Result<T, GpuError>;
}

impl<T> VkContext<T> for Result<T, vk::Result> {
    fn ctx(self, call: &'static str) -> Result<T, GpuError> {
        self.map_err(|result| GpuError::Vulkan { call, result })
    }
}

/// Options for [`Gpu::new`].
#[derive(Clone, Debug, Default)]
pub struct GpuDesc {
    /// Enable `VK_LAYER_KHRONOS_validation` and count its messages. Also turned on
    /// by the environment variable [`VALIDATION_ENV`].
    pub validation: bool,
}

/// Extra Vulkan extensions to enable (the mirror window's surface and
/// swapchain; see [`Gpu::with_extensions`]).
#[derive(Clone, Debug, Default)]
pub struct GpuExtensions {
    /// Instance extensions (e.g. `VK_KHR_surface` and the platform's surface).
    pub instance: Vec<&'static CStr>,
    /// Device extensions (e.g. `VK_KHR_swapchain`); devices without all of them
    /// are not chosen.
    pub device: Vec<&'static CStr>,
}

/// Creates the Vulkan instance and device for [`Gpu::with_factory`]. The
/// direct way is `vkCreateInstance`, the ranked device choice and
/// `vkCreateDevice`; OpenXR's `XR_KHR_vulkan_enable2` instead creates both
/// itself (adding the extensions its compositor needs) and names the one
/// physical device it can share images with (`runtime::xr::vulkan`).
pub trait VulkanFactory {
    /// Creates the instance from the renderer's create info.
    ///
    /// # Safety
    ///
    /// `info` and everything it points to are valid for the call.
    unsafe fn create_instance(
        &mut self,
        entry: &ash::Entry,
        info: &vk::InstanceCreateInfo<'_>,
    ) -> Result<vk::Instance, GpuError>;

    /// The physical device that must be used, or `None` to let the GPU
    /// context choose (see [`Gpu::new`]).
    ///
    /// # Safety
    ///
    /// `instance` was made by [`VulkanFactory::create_instance`] and is alive.
    unsafe fn physical_device(
        &mut self,
        instance: &ash::Instance,
    ) -> Result<Option<vk::PhysicalDevice>, GpuError>;

    /// Creates the device on `physical` from the renderer's create info.
    ///
    /// # Safety
    ///
    /// `physical` belongs to `instance`; `info` and everything it points to
    /// are valid for the call.
    unsafe fn create_device(
        &mut self,
        instance: &ash::Instance,
        physical: vk::PhysicalDevice,
        info: &vk::DeviceCreateInfo<'_>,
    ) -> Result<vk::Device, GpuError>;
}

/// `vkCreateInstance` and `vkCreateDevice` through the loader.
struct DirectFactory;

impl VulkanFactory for DirectFactory {
    unsafe fn create_instance(
        &mut self,
        entry: &ash::Entry,
        info: &vk::InstanceCreateInfo<'_>,
    ) -> Result<vk::Instance, GpuError> {
        // SAFETY: the caller guarantees the create info.
        let instance = unsafe { entry.create_instance(info, None) }.map_err(|e| {
            if e == vk::Result::ERROR_INCOMPATIBLE_DRIVER {
                GpuError::NoDevice("no installable client driver accepted the instance".into())
            } else {
                GpuError::Vulkan {
                    call: "vkCreateInstance",
                    result: e,
                }
            }
        })?;
        Ok(instance.handle())
    }

    unsafe fn physical_device(
        &mut self,
        _instance: &ash::Instance,
    ) -> Result<Option<vk::PhysicalDevice>, GpuError> {
        Ok(None)
    }

    unsafe fn create_device(
        &mut self,
        instance: &ash::Instance,
        physical: vk::PhysicalDevice,
        info: &vk::DeviceCreateInfo<'_>,
    ) -> Result<vk::Device, GpuError> {
        // SAFETY: the caller guarantees `physical` and the create info.
        let device =
            unsafe { instance.create_device(physical, info, None) }.ctx("vkCreateDevice")?;
        Ok(device.handle())
    }
}

/// Validation messages received so far (warnings and errors; info and verbose
/// messages are not counted).
#[derive(Debug, Default)]
pub struct ValidationLog {
    count: AtomicUsize,
    messages: Mutex<Vec<String>>,
}

impl ValidationLog {
    /// How many warning or error messages the layer has sent.
    pub fn count(&self) -> usize {
        self.count.load(Ordering::SeqCst)
    }

    /// The messages' text, oldest first.
    pub fn messages(&self) -> Vec<String> {
        self.messages.lock().map(|m| m.clone()).unwrap_or_default()
    }

    fn push(&self, text: String) {
        self.count.fetch_add(1, Ordering::SeqCst);
        if let Ok(mut m) = self.messages.lock() {
            m.push(text);
        }
    }
}

/// What the renderer needs to know about the chosen device.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub name: String,
    /// `driverID` (Vulkan 1.2 / VK_KHR_driver_properties) when the device reports it.
    pub driver_id: Option<vk::DriverId>,
    pub api_version: u32,
    pub device_type: vk::PhysicalDeviceType,
    pub limits: vk::PhysicalDeviceLimits,
    pub memory: vk::PhysicalDeviceMemoryProperties,
}

impl DeviceInfo {
    /// Mesa's lavapipe (llvmpipe) CPU device, which has the multiview clipping bug
    /// described in `render::multiview`.
    pub fn is_llvmpipe(&self) -> bool {
        self.driver_id == Some(vk::DriverId::MESA_LLVMPIPE) || self.name.contains("llvmpipe")
    }

    /// "name (Vulkan x.y.z)" for reports.
    pub fn describe(&self) -> String {
        format!(
            "{} (Vulkan {}.{}.{})",
            self.name,
            vk::api_version_major(self.api_version),
            vk::api_version_minor(self.api_version),
            vk::api_version_patch(self.api_version)
        )
    }
}

/// The instance and device, shared by every resource made from them.
pub struct DeviceShared {
    pub device: ash::Device,
    pub instance: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Shared so that its address, handed to the messenger as user data, is stable.
    log: Arc<ValidationLog>,
    _entry: ash::Entry,
}

impl Drop for DeviceShared {
    fn drop(&mut self) {
        // SAFETY: this is the last reference to the device and instance (every
        // resource holds an Arc to this struct), so no object made from them is
        // alive; waiting for idle first lets in-flight work finish. The messenger
        // is destroyed before its instance.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_device(None);
            if let Some((loader, messenger)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

/// The GPU context: device, one graphics queue, a command pool for one-shot work.
pub struct Gpu {
    // Fields newest-first (see the module notes).
    command_pool: vk::CommandPool,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub physical: vk::PhysicalDevice,
    pub info: DeviceInfo,
    pub shared: Arc<DeviceShared>,
}

impl Drop for Gpu {
    fn drop(&mut self) {
        // SAFETY: the pool belongs to this device; waiting for idle guarantees none
        // of its command buffers is pending.
        unsafe {
            let _ = self.shared.device.device_wait_idle();
            self.shared
                .device
                .destroy_command_pool(self.command_pool, None);
        }
    }
}

fn validation_from_env() -> bool {
    std::env::var(VALIDATION_ENV)
        .map(|v| matches!(v.to_ascii_lowercase().as_str(), "1" | "true" | "yes"))
        .unwrap_or(false)
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the loader passes a valid callback-data pointer for the duration of
    // the call, and `user` is the `ValidationLog` that `DeviceShared` keeps alive
    // (through its Arc) for as long as the messenger exists.
    let (text, log) = unsafe {
        let text = if data.is_null() || (*data).p_message.is_null() {
            String::from("(no message)")
        } else {
            CStr::from_ptr((*data).p_message)
                .to_string_lossy()
                .into_owned()
        };
        (text, &*(user as *const ValidationLog))
    };
    let line = format!("vulkan validation [{severity:?}]: {text}");
    eprintln!("{line}");
    log.push(line);
    vk::FALSE
}

fn c_name(raw: &[std::ffi::c_char]) -> String {
    // The name arrays are NUL-terminated within their fixed size.
    let bytes: Vec<u8> = raw
        .iter()
        .take_while(|&&c| c != 0)
        .map(|&c| c as u8)
        .collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

impl Gpu {
    /// Loads Vulkan, creates an instance (with validation when asked or when
    /// [`VALIDATION_ENV`] is set), picks a device and creates it.
    ///
    /// Device choice: Vulkan ≥ 1.1 with a graphics queue; discrete before
    /// integrated before virtual before CPU, first listed among equals.
    pub fn new(desc: &GpuDesc) -> Result<Gpu, GpuError> {
        Gpu::with_extensions(desc, &GpuExtensions::default())
    }

    /// As [`Gpu::new`], also enabling `extensions` (a device that lacks one of the
    /// device extensions is passed over, and named in the error if none is left).
    pub fn with_extensions(desc: &GpuDesc, wanted: &GpuExtensions) -> Result<Gpu, GpuError> {
        Gpu::with_factory(desc, wanted, &mut DirectFactory)
    }

    /// As [`Gpu::with_extensions`], with the instance and device made by
    /// `factory` (and on the physical device it names, if it names one, which
    /// must meet the same requirements as a chosen one).
    pub fn with_factory(
        desc: &GpuDesc,
        wanted: &GpuExtensions,
        factory: &mut dyn VulkanFactory,
    ) -> Result<Gpu, GpuError> {
        let validation = desc.validation || validation_from_env();
        // SAFETY: loading the Vulkan loader runs its initialisers; ash requires the
        // library to be a conforming Vulkan loader, which libvulkan.so.1 is.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| GpuError::NoLoader(e.to_string()))?;

        // SAFETY: plain query on a loaded entry.
        let version = unsafe { entry.try_enumerate_instance_version() }
            .ctx("vkEnumerateInstanceVersion")?
            .unwrap_or(vk::API_VERSION_1_0);
        if version < vk::API_VERSION_1_1 {
            return Err(GpuError::NoDevice(format!(
                "the Vulkan loader supports only {}.{}",
                vk::api_version_major(version),
                vk::api_version_minor(version)
            )));
        }

        let mut layers = Vec::new();
        let mut extensions: Vec<*const std::ffi::c_char> =
            wanted.instance.iter().map(|e| e.as_ptr()).collect();
        if validation {
            // SAFETY: plain query on a loaded entry.
            let available = unsafe { entry.enumerate_instance_layer_properties() }
                .ctx("vkEnumerateInstanceLayerProperties")?;
            let found = available
                .iter()
                .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER));
            if !found {
                return Err(GpuError::NoValidationLayer);
            }
            layers.push(VALIDATION_LAYER.as_ptr());
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }

        let app = vk::ApplicationInfo::default()
            .application_name(c"radiosity walkthrough runtime")
            .engine_name(c"runtime")
            .api_version(vk::API_VERSION_1_1);
        let log = Arc::new(ValidationLog::default());
        let mut messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(
                vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                    | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
            )
            .message_type(
                vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                    | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                    | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
            )
            .pfn_user_callback(Some(debug_callback))
            .user_data(Arc::as_ptr(&log) as *mut c_void);
        let mut instance_info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if validation {
            // Also catches messages from vkCreateInstance / vkDestroyInstance.
            instance_info = instance_info.push_next(&mut messenger_info);
        }
        // SAFETY: every pointer in the create info refers to locals alive here;
        // the handle is a live instance of this loader, whose functions `load`
        // fetches through the entry's vkGetInstanceProcAddr.
        let instance = unsafe {
            let raw = factory.create_instance(&entry, &instance_info)?;
            ash::Instance::load(entry.static_fn(), raw)
        };
        // From here on, an early return must destroy the instance: wrap it.
        let guard = InstanceGuard {
            instance: Some(instance),
            debug: None,
        };
        let mut guard = guard;
        if validation {
            let loader = ash::ext::debug_utils::Instance::new(&entry, guard.instance());
            // SAFETY: the create info's user data points into `log`, which the
            // returned DeviceShared keeps alive until the messenger is destroyed.
            let messenger = unsafe { loader.create_debug_utils_messenger(&messenger_info, None) }
                .ctx("vkCreateDebugUtilsMessengerEXT")?;
            guard.debug = Some((loader, messenger));
        }

        // SAFETY: the instance came from the factory and is alive.
        let named = unsafe { factory.physical_device(guard.instance()) }?;
        let (physical, queue_family, info) = match named {
            None => pick_device(guard.instance(), &wanted.device)?,
            Some(physical) => {
                let (_, family, info) = examine_device(guard.instance(), physical, &wanted.device)
                    .map_err(|why| {
                        GpuError::NoDevice(format!("the device named for this session: {why}"))
                    })?;
                (physical, family, info)
            }
        };
        let device_extensions: Vec<*const std::ffi::c_char> =
            wanted.device.iter().map(|e| e.as_ptr()).collect();

        let priorities = [1.0f32];
        let queue_info = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        let mut multiview = vk::PhysicalDeviceMultiviewFeatures::default().multiview(true);
        let device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_extension_names(&device_extensions)
            .push_next(&mut multiview);
        // SAFETY: `physical` came from this instance; the create info points to
        // locals alive for the call; the handle is a live device of this
        // instance, whose functions `load` fetches through vkGetDeviceProcAddr.
        let device = unsafe {
            let raw = factory.create_device(guard.instance(), physical, &device_info)?;
            ash::Device::load(guard.instance().fp_v1_0(), raw)
        };
        // SAFETY: the queue family and index were requested at device creation.
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        let (instance, debug) = guard.release();
        let shared = Arc::new(DeviceShared {
            device,
            instance,
            debug,
            log,
            _entry: entry,
        });
        // SAFETY: valid device; the pool is destroyed in Gpu::drop.
        let command_pool = unsafe { shared.device.create_command_pool(&pool_info, None) }
            .ctx("vkCreateCommandPool")?;
        Ok(Gpu {
            command_pool,
            queue,
            queue_family,
            physical,
            info,
            shared,
        })
    }

    pub fn device(&self) -> &ash::Device {
        &self.shared.device
    }

    pub fn instance(&self) -> &ash::Instance {
        &self.shared.instance
    }

    /// The loaded Vulkan entry points (for extension loaders such as surfaces).
    pub fn entry(&self) -> &ash::Entry {
        &self.shared._entry
    }

    /// Validation messages received (empty, with count 0, when validation is off).
    pub fn validation_log(&self) -> &ValidationLog {
        &self.shared.log
    }

    /// A handle on the validation log that outlives the device: messages sent
    /// while the device and instance are destroyed (leaked objects) land here too.
    pub fn validation_log_handle(&self) -> Arc<ValidationLog> {
        self.shared.log.clone()
    }

    /// Whether the validation layer is active.
    pub fn validation_enabled(&self) -> bool {
        self.shared.debug.is_some()
    }

    pub fn command_pool(&self) -> vk::CommandPool {
        self.command_pool
    }

    /// Records commands with `record`, submits them and waits for completion.
    pub fn one_shot<T>(
        &self,
        record: impl FnOnce(&ash::Device, vk::CommandBuffer) -> T,
    ) -> Result<T, GpuError> {
        let device = self.device();
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool belongs to this device and is used from this thread only
        // (Gpu is not Sync-shared across recording threads).
        let cmd =
            unsafe { device.allocate_command_buffers(&alloc) }.ctx("vkAllocateCommandBuffers")?[0];
        let fence = Fence::new(self, false)?;
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: freshly allocated command buffer in the initial state.
        unsafe { device.begin_command_buffer(cmd, &begin) }.ctx("vkBeginCommandBuffer")?;
        let value = record(device, cmd);
        let result = (|| {
            // SAFETY: `cmd` is recording; the submit info points to locals; the
            // fence is unsignalled and waited for before the buffer is freed.
            unsafe {
                device.end_command_buffer(cmd).ctx("vkEndCommandBuffer")?;
                let cmds = [cmd];
                let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
                device
                    .queue_submit(self.queue, &submit, fence.raw)
                    .ctx("vkQueueSubmit")?;
            }
            fence.wait()
        })();
        // SAFETY: the fence wait above finished (or the submit never happened), so
        // the command buffer is not pending.
        unsafe { device.free_command_buffers(self.command_pool, &[cmd]) };
        result.map(|()| value)
    }

    /// Index of a memory type with `flags` allowed by `type_bits`.
    pub fn memory_type(&self, type_bits: u32, flags: vk::MemoryPropertyFlags) -> Option<u32> {
        let mem = &self.info.memory;
        (0..mem.memory_type_count).find(|&i| {
            type_bits & (1 << i) != 0 && mem.memory_types[i as usize].property_flags.contains(flags)
        })
    }
}

/// Destroys the instance (and messenger) on an early return from [`Gpu::new`].
struct InstanceGuard {
    instance: Option<ash::Instance>,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
}

impl InstanceGuard {
    fn instance(&self) -> &ash::Instance {
        self.instance
            .as_ref()
            .expect("instance present until released")
    }

    #[allow(clippy::type_complexity)]
    fn release(
        mut self,
    ) -> (
        ash::Instance,
        Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    ) {
        let instance = self.instance.take().expect("released once");
        (instance, self.debug.take())
    }
}

impl Drop for InstanceGuard {
    fn drop(&mut self) {
        // SAFETY: only reached on an error path, where no device was created from
        // the instance; the messenger goes before its instance.
        unsafe {
            if let Some((loader, messenger)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            if let Some(instance) = self.instance.take() {
                instance.destroy_instance(None);
            }
        }
    }
}

fn pick_device(
    instance: &ash::Instance,
    device_extensions: &[&CStr],
) -> Result<(vk::PhysicalDevice, u32, DeviceInfo), GpuError> {
    // SAFETY: plain query on a valid instance.
    let devices =
        unsafe { instance.enumerate_physical_devices() }.ctx("vkEnumeratePhysicalDevices")?;
    let mut best: Option<(u32, vk::PhysicalDevice, u32, DeviceInfo)> = None;
    let mut rejected = Vec::new();
    for physical in devices {
        match examine_device(instance, physical, device_extensions) {
            Err(why) => rejected.push(why),
            Ok((rank, family, info)) => {
                if best.as_ref().is_none_or(|b| rank < b.0) {
                    best = Some((rank, physical, family, info));
                }
            }
        }
    }
    match best {
        Some((_, physical, family, info)) => Ok((physical, family, info)),
        None if rejected.is_empty() => Err(GpuError::NoDevice("the loader lists no device".into())),
        None => Err(GpuError::NoDevice(rejected.join("; "))),
    }
}

/// Checks one device (Vulkan 1.1, a graphics queue, multiview, the wanted
/// extensions): its rank (lower is preferred), graphics queue family and
/// description, or why it cannot be used.
fn examine_device(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    device_extensions: &[&CStr],
) -> Result<(u32, u32, DeviceInfo), String> {
    // SAFETY: `physical` belongs to this instance.
    let props = unsafe { instance.get_physical_device_properties(physical) };
    let name = c_name(&props.device_name);
    if props.api_version < vk::API_VERSION_1_1 {
        return Err(format!("{name}: Vulkan 1.0 only"));
    }
    // SAFETY: as above.
    let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
    let Some(family) = families
        .iter()
        .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS))
    else {
        return Err(format!("{name}: no graphics queue"));
    };
    let mut multiview = vk::PhysicalDeviceMultiviewFeatures::default();
    let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut multiview);
    // SAFETY: `physical` belongs to this instance; the features chain is locals.
    unsafe { instance.get_physical_device_features2(physical, &mut features) };
    if multiview.multiview == vk::FALSE {
        return Err(format!("{name}: no multiview"));
    }
    if !device_extensions.is_empty() {
        // SAFETY: plain query on a physical device of this instance.
        let available =
            unsafe { instance.enumerate_device_extension_properties(physical) }.unwrap_or_default();
        let missing: Vec<String> = device_extensions
            .iter()
            .filter(|want| {
                !available
                    .iter()
                    .any(|e| e.extension_name_as_c_str() == Ok(**want))
            })
            .map(|want| want.to_string_lossy().into_owned())
            .collect();
        if !missing.is_empty() {
            return Err(format!("{name}: no {}", missing.join(", ")));
        }
    }
    let driver_id = if props.api_version >= vk::API_VERSION_1_2 {
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
        // SAFETY: a 1.2 device supports the driver-properties query; locals only.
        unsafe { instance.get_physical_device_properties2(physical, &mut props2) };
        Some(driver.driver_id)
    } else {
        None
    };
    // SAFETY: plain query.
    let memory = unsafe { instance.get_physical_device_memory_properties(physical) };
    let rank = match props.device_type {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    };
    let info = DeviceInfo {
        name,
        driver_id,
        api_version: props.api_version,
        device_type: props.device_type,
        limits: props.limits,
        memory,
    };
    Ok((rank, family as u32, info))
}

/// A fence wrapper.
pub struct Fence {
    pub raw: vk::Fence,
    shared: Arc<DeviceShared>,
}

impl Fence {
    pub fn new(gpu: &Gpu, signaled: bool) -> Result<Fence, GpuError> {
        let flags = if signaled {
            vk::FenceCreateFlags::SIGNALED
        } else {
            vk::FenceCreateFlags::empty()
        };
        // SAFETY: valid device; destroyed in Drop.
        let raw = unsafe {
            gpu.device()
                .create_fence(&vk::FenceCreateInfo::default().flags(flags), None)
        }
        .ctx("vkCreateFence")?;
        Ok(Fence {
            raw,
            shared: gpu.shared.clone(),
        })
    }

    /// Waits (without a time limit) until the fence is signalled.
    pub fn wait(&self) -> Result<(), GpuError> {
        // SAFETY: the fence belongs to this device.
        unsafe {
            self.shared
                .device
                .wait_for_fences(&[self.raw], true, u64::MAX)
        }
        .ctx("vkWaitForFences")
    }

    pub fn reset(&self) -> Result<(), GpuError> {
        // SAFETY: callers reset only after waiting, so the fence is not pending.
        unsafe { self.shared.device.reset_fences(&[self.raw]) }.ctx("vkResetFences")
    }
}

impl Drop for Fence {
    fn drop(&mut self) {
        // SAFETY: owners wait for their fences (or for device idle) before dropping
        // them, so no queue operation still refers to this one.
        unsafe { self.shared.device.destroy_fence(self.raw, None) };
    }
}
