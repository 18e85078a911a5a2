//! Swapchains: Vulkan images made by the runtime, the acquire/wait/release
//! cycle, and the read-back of a released image as a compositor would read it.

use crate::ffi::*;
use crate::state::*;
use ash::vk::{self, Handle};
use openxr::sys as xr;
use std::ffi::c_void;

pub(crate) unsafe extern "system" fn swapchain_formats(
    _session: xr::Session,
    cap: u32,
    count: *mut u32,
    out: *mut i64,
) -> xr::Result {
    // A float format first, then two sRGB formats: the application should
    // take the first sRGB one.
    let formats = [
        vk::Format::R16G16B16A16_SFLOAT.as_raw() as i64,
        vk::Format::B8G8R8A8_SRGB.as_raw() as i64,
        vk::Format::R8G8B8A8_SRGB.as_raw() as i64,
    ];
    // SAFETY: `count` is valid for writing and `out` for `cap` elements (the two-call idiom; crate notes).
    unsafe { fill(cap, count, out, &formats) }
}

pub(crate) unsafe extern "system" fn create_swapchain(
    session: xr::Session,
    info: *const xr::SwapchainCreateInfo,
    out: *mut xr::Swapchain,
) -> xr::Result {
    // SAFETY: `info` is valid for reading (the loader's pointer contract: crate notes).
    let info = unsafe { &*info };
    with(|s| {
        s.report.swapchain_formats.push(info.format);
        if info.array_size == 2 {
            s.report.capture_format = info.format;
        }
        s.report
            .swapchain_sizes
            .push((info.width, info.height, info.array_size));
        let Some(device) = s.vulkan.as_ref().and_then(|v| v.device.clone()) else {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        };
        let instance = s.vulkan.as_ref().and_then(|v| v.instance.clone());
        let physical = s.vulkan.as_ref().map(|v| v.physical).unwrap_or_default();
        let is_static = info
            .create_flags
            .contains(xr::SwapchainCreateFlags::STATIC_IMAGE);
        let mut usage = vk::ImageUsageFlags::empty();
        if info
            .usage_flags
            .contains(xr::SwapchainUsageFlags::COLOR_ATTACHMENT)
        {
            usage |= vk::ImageUsageFlags::COLOR_ATTACHMENT;
        }
        if info
            .usage_flags
            .contains(xr::SwapchainUsageFlags::TRANSFER_DST)
        {
            usage |= vk::ImageUsageFlags::TRANSFER_DST;
        }
        // The runtime samples what it composites.
        usage |= vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        let count = if is_static { 1 } else { 3 };
        let mut images = Vec::new();
        for _ in 0..count {
            let create = vk::ImageCreateInfo::default()
                .image_type(vk::ImageType::TYPE_2D)
                .format(vk::Format::from_raw(info.format as i32))
                .extent(vk::Extent3D {
                    width: info.width,
                    height: info.height,
                    depth: 1,
                })
                .mip_levels(1)
                .array_layers(info.array_size)
                .samples(vk::SampleCountFlags::TYPE_1)
                .tiling(vk::ImageTiling::OPTIMAL)
                .usage(usage)
                .initial_layout(vk::ImageLayout::UNDEFINED);
            // SAFETY: the application's device (created through this runtime);
            // the create info is local. Images are destroyed with the swapchain.
            let Ok(image) = (unsafe { device.create_image(&create, None) }) else {
                return xr::Result::ERROR_RUNTIME_FAILURE;
            };
            // SAFETY: `image` was just made on this device.
            let req = unsafe { device.get_image_memory_requirements(image) };
            let memory_types = instance
                .as_ref()
                // SAFETY: `physical` is the device this instance named for the session.
                .map(|i| unsafe { i.get_physical_device_memory_properties(physical) })
                .unwrap_or_default();
            let type_index = (0..memory_types.memory_type_count)
                .find(|i| req.memory_type_bits & (1 << i) != 0)
                .unwrap_or(0);
            let alloc = vk::MemoryAllocateInfo::default()
                .allocation_size(req.size)
                .memory_type_index(type_index);
            // SAFETY: the allocate info is local; the memory is freed with the
            // swapchain.
            let Ok(memory) = (unsafe { device.allocate_memory(&alloc, None) }) else {
                return xr::Result::ERROR_RUNTIME_FAILURE;
            };
            // SAFETY: the memory was allocated for this image's requirements and
            // is bound once.
            if unsafe { device.bind_image_memory(image, memory, 0) }.is_err() {
                return xr::Result::ERROR_RUNTIME_FAILURE;
            }
            images.push((image, memory));
        }
        let id = handle(s);
        s.swapchains.insert(
            id,
            Swapchain {
                session: session.into_raw(),
                images,
                width: info.width,
                height: info.height,
                layers: info.array_size,
                is_static,
                ..Swapchain::default()
            },
        );
        // SAFETY: `out` is valid for writing (the loader's pointer contract: crate notes).
        unsafe { *out = xr::Swapchain::from_raw(id) };
        xr::Result::SUCCESS
    })
}

pub(crate) unsafe extern "system" fn destroy_swapchain(swapchain: xr::Swapchain) -> xr::Result {
    with(|s| {
        let device = s.vulkan.as_ref().and_then(|v| v.device.clone());
        if let (Some(chain), Some(device)) = (s.swapchains.remove(&swapchain.into_raw()), device) {
            // SAFETY: the images belong to this swapchain and device; waiting
            // for idle ends any use of them.
            unsafe {
                let _ = device.device_wait_idle();
                for (image, memory) in chain.images {
                    device.destroy_image(image, None);
                    device.free_memory(memory, None);
                }
            }
        }
    });
    xr::Result::SUCCESS
}

pub(crate) unsafe extern "system" fn swapchain_images(
    swapchain: xr::Swapchain,
    cap: u32,
    count: *mut u32,
    out: *mut xr::SwapchainImageBaseHeader,
) -> xr::Result {
    let images: Vec<u64> = with(|s| {
        s.swapchains
            .get(&swapchain.into_raw())
            .map(|c| c.images.iter().map(|(i, _)| i.as_raw()).collect())
            .unwrap_or_default()
    });
    // SAFETY: `count` is valid for writing (the loader's pointer contract: crate notes).
    unsafe { *count = images.len() as u32 };
    if cap == 0 {
        return xr::Result::SUCCESS;
    }
    if (cap as usize) < images.len() {
        return xr::Result::ERROR_SIZE_INSUFFICIENT;
    }
    let out = out as *mut xr::SwapchainImageVulkanKHR;
    for (i, image) in images.iter().enumerate() {
        // SAFETY: `i < images.len() <= cap`, and `out` holds `cap` Vulkan image
        // structures, valid for writing (the loader's pointer contract: crate notes).
        unsafe { (*out.add(i)).image = *image };
    }
    xr::Result::SUCCESS
}

pub(crate) unsafe extern "system" fn acquire_image(
    swapchain: xr::Swapchain,
    _info: *const c_void,
    index: *mut u32,
) -> xr::Result {
    with(|s| {
        let Some(c) = s.swapchains.get_mut(&swapchain.into_raw()) else {
            return xr::Result::ERROR_HANDLE_INVALID;
        };
        if c.is_static && c.released_once {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        }
        if c.acquired.len() >= c.images.len() {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        }
        let i = c.next;
        c.next = (c.next + 1) % c.images.len() as u32;
        c.acquired.push_back(i);
        c.waited = false;
        // SAFETY: `index` is valid for writing (the loader's pointer contract: crate notes).
        unsafe { *index = i };
        xr::Result::SUCCESS
    })
}

pub(crate) unsafe extern "system" fn wait_image(
    swapchain: xr::Swapchain,
    _info: *const c_void,
) -> xr::Result {
    with(|s| {
        let Some(c) = s.swapchains.get_mut(&swapchain.into_raw()) else {
            return xr::Result::ERROR_HANDLE_INVALID;
        };
        if c.acquired.is_empty() {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        }
        c.waited = true;
        xr::Result::SUCCESS
    })
}

pub(crate) unsafe extern "system" fn release_image(
    swapchain: xr::Swapchain,
    _info: *const c_void,
) -> xr::Result {
    with(|s| {
        let Some(c) = s.swapchains.get_mut(&swapchain.into_raw()) else {
            return xr::Result::ERROR_HANDLE_INVALID;
        };
        if !c.waited {
            return xr::Result::ERROR_CALL_ORDER_INVALID;
        }
        c.waited = false;
        c.last_released = c.acquired.pop_front();
        c.released_once = true;
        xr::Result::SUCCESS
    })
}

/// Copies both layers of a released swapchain image (8-bit, 4 channels, in
/// COLOR_ATTACHMENT_OPTIMAL as OpenXR requires) to host memory, as a
/// compositor would read them, and summarises them: per eye the mean of R, G
/// and B and the lit fraction, the fraction of pixels that differ between the
/// eyes, and the bytes themselves.
#[allow(clippy::type_complexity)]
pub(crate) fn read_back(
    s: &State,
    image: vk::Image,
    w: u32,
    h: u32,
) -> Result<(Vec<[f64; 4]>, f64, Vec<u8>), vk::Result> {
    let v = s
        .vulkan
        .as_ref()
        .ok_or(vk::Result::ERROR_INITIALIZATION_FAILED)?;
    let (device, instance) = match (&v.device, &v.instance) {
        (Some(d), Some(i)) => (d, i),
        _ => return Err(vk::Result::ERROR_INITIALIZATION_FAILED),
    };
    let queue = v.queue.ok_or(vk::Result::ERROR_INITIALIZATION_FAILED)?;
    let target = Target {
        device,
        instance,
        physical: v.physical,
        queue,
    };
    // SAFETY: the device and image are the session's (made through this
    // runtime, on `physical` of `instance`); the image was released, so the
    // application is not using it, and the application's queue is free during
    // xrEndFrame.
    let bytes = unsafe { copy_layers(&target, image, w, h) }?;
    let (left, right) = bytes.split_at(bytes.len() / 2);
    let stats = [left, right]
        .iter()
        .map(|layer| layer_stats(layer, w * h))
        .collect();
    let differ = left
        .chunks_exact(4)
        .zip(right.chunks_exact(4))
        .filter(|(a, b)| a[..3] != b[..3])
        .count() as f64
        / f64::from(w * h);
    Ok((stats, differ, bytes))
}

/// The mean of R, G and B (0–255) and the fraction of pixels that are not
/// black, of one layer of `pixels` 4-byte pixels.
fn layer_stats(layer: &[u8], pixels: u32) -> [f64; 4] {
    let n = f64::from(pixels);
    let mut sum = [0.0f64; 3];
    let mut lit = 0usize;
    for px in layer.chunks_exact(4) {
        for c in 0..3 {
            sum[c] += f64::from(px[c]);
        }
        if px[..3].iter().any(|&b| b > 0) {
            lit += 1;
        }
    }
    [sum[0] / n, sum[1] / n, sum[2] / n, lit as f64 / n]
}

/// The session's Vulkan objects a read-back uses.
struct Target<'a> {
    device: &'a ash::Device,
    instance: &'a ash::Instance,
    physical: vk::PhysicalDevice,
    /// Queue family and queue of the session's graphics binding.
    queue: (u32, vk::Queue),
}

/// Copies both layers of `image` to host memory and returns their bytes, layer
/// 0 first. On success every object made here is destroyed after the queue is
/// idle; an error path leaks them, which a test tolerates.
///
/// # Safety
///
/// `target.device` was made on `target.physical` of `target.instance`, and
/// `target.queue` is one of its queues, not in use by the application during
/// the call; `image` is a live two-layer `w` × `h` 4-byte image of the device in
/// COLOR_ATTACHMENT_OPTIMAL that nothing else uses meanwhile.
unsafe fn copy_layers(
    target: &Target<'_>,
    image: vk::Image,
    w: u32,
    h: u32,
) -> Result<Vec<u8>, vk::Result> {
    let device = target.device;
    let (family, queue) = target.queue;
    let layer_bytes = u64::from(w) * u64::from(h) * 4;
    // SAFETY: the caller guarantees the device, instance and physical device.
    let (buffer, memory) = unsafe { host_buffer(target, layer_bytes * 2) }?;
    let pool_info = vk::CommandPoolCreateInfo::default().queue_family_index(family);
    // SAFETY: the family is the session's queue family on this device.
    let pool = unsafe { device.create_command_pool(&pool_info, None) }?;
    let alloc = vk::CommandBufferAllocateInfo::default()
        .command_pool(pool)
        .command_buffer_count(1);
    // SAFETY: the pool was just made on this device.
    let cmd = unsafe { device.allocate_command_buffers(&alloc) }?[0];
    // SAFETY: a fresh command buffer; the caller guarantees the image, and the
    // buffer holds both layers.
    unsafe { record_layer_copy(device, cmd, image, buffer, w, h) }?;
    let cmds = [cmd];
    let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
    // SAFETY: the command buffer was recorded and ended; the caller guarantees
    // that the queue is free; waiting for idle ends the copy.
    unsafe {
        device.queue_submit(queue, &submit, vk::Fence::null())?;
        device.queue_wait_idle(queue)?;
    }
    let size = layer_bytes * 2;
    // SAFETY: the memory is host-visible and coherent, not mapped yet, and the
    // copy that wrote it has finished (queue idle).
    let ptr = unsafe { device.map_memory(memory, 0, size, vk::MemoryMapFlags::empty()) }?;
    // SAFETY: the mapping covers `size` bytes and nothing writes them now.
    let bytes = unsafe { std::slice::from_raw_parts(ptr as *const u8, size as usize) }.to_vec();
    // SAFETY: the queue is idle, so nothing uses these objects; the memory is
    // unmapped before it is freed.
    unsafe {
        device.unmap_memory(memory);
        device.destroy_command_pool(pool, None);
        device.destroy_buffer(buffer, None);
        device.free_memory(memory, None);
    }
    Ok(bytes)
}

/// A host-visible, coherent transfer-destination buffer of `size` bytes and
/// its bound memory.
///
/// # Safety
///
/// `target.device` was made on `target.physical` of `target.instance`.
unsafe fn host_buffer(
    target: &Target<'_>,
    size: u64,
) -> Result<(vk::Buffer, vk::DeviceMemory), vk::Result> {
    let device = target.device;
    let info = vk::BufferCreateInfo::default()
        .size(size)
        .usage(vk::BufferUsageFlags::TRANSFER_DST);
    // SAFETY: the create info is local; the buffer is the caller's to destroy.
    let buffer = unsafe { device.create_buffer(&info, None) }?;
    // SAFETY: `buffer` was just made on this device, and the caller
    // guarantees that `physical` is the device's.
    let (req, props) = unsafe {
        (
            device.get_buffer_memory_requirements(buffer),
            target
                .instance
                .get_physical_device_memory_properties(target.physical),
        )
    };
    let wanted = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
    let type_index = (0..props.memory_type_count)
        .find(|&i| {
            req.memory_type_bits & (1 << i) != 0
                && props.memory_types[i as usize]
                    .property_flags
                    .contains(wanted)
        })
        .ok_or(vk::Result::ERROR_FEATURE_NOT_PRESENT)?;
    let alloc = vk::MemoryAllocateInfo::default()
        .allocation_size(req.size)
        .memory_type_index(type_index);
    // SAFETY: the allocate info is local; the memory is the caller's to free.
    let memory = unsafe { device.allocate_memory(&alloc, None) }?;
    // SAFETY: the memory was allocated for this buffer's requirements.
    unsafe { device.bind_buffer_memory(buffer, memory, 0) }?;
    Ok((buffer, memory))
}

/// Records, into a fresh `cmd`, the copy of both layers of `image` into
/// `buffer` (layer 0 first), with the image moved to TRANSFER_SRC and back.
///
/// # Safety
///
/// `cmd` is a fresh command buffer of `device`; `image` is a live two-layer
/// `w` × `h` image in COLOR_ATTACHMENT_OPTIMAL, and `buffer` holds
/// `2 × w × h × 4` bytes.
unsafe fn record_layer_copy(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    buffer: vk::Buffer,
    w: u32,
    h: u32,
) -> Result<(), vk::Result> {
    use vk::{AccessFlags as A, ImageLayout as L, PipelineStageFlags as S};
    let layer_bytes = u64::from(w) * u64::from(h) * 4;
    let range = vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 2,
    };
    let barrier = |(from, src), (to, dst)| {
        [vk::ImageMemoryBarrier::default()
            .old_layout(from)
            .new_layout(to)
            .src_access_mask(src)
            .dst_access_mask(dst)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image)
            .subresource_range(range)]
    };
    let to_src = barrier(
        (L::COLOR_ATTACHMENT_OPTIMAL, A::COLOR_ATTACHMENT_WRITE),
        (L::TRANSFER_SRC_OPTIMAL, A::TRANSFER_READ),
    );
    let back = barrier(
        (L::TRANSFER_SRC_OPTIMAL, A::TRANSFER_READ),
        (L::COLOR_ATTACHMENT_OPTIMAL, A::empty()),
    );
    let regions: Vec<vk::BufferImageCopy> = (0..2u32)
        .map(|layer| {
            vk::BufferImageCopy::default()
                .buffer_offset(u64::from(layer) * layer_bytes)
                .image_subresource(vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    mip_level: 0,
                    base_array_layer: layer,
                    layer_count: 1,
                })
                .image_extent(vk::Extent3D {
                    width: w,
                    height: h,
                    depth: 1,
                })
        })
        .collect();
    let none = vk::DependencyFlags::empty();
    // SAFETY: the caller guarantees the command buffer, the image's layout and
    // the buffer's size; the first barrier puts the image in the copy's layout
    // and the second returns it to the one OpenXR expects.
    unsafe {
        device.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())?;
        let (src, dst) = (S::COLOR_ATTACHMENT_OUTPUT, S::TRANSFER);
        device.cmd_pipeline_barrier(cmd, src, dst, none, &[], &[], &to_src);
        device.cmd_copy_image_to_buffer(cmd, image, L::TRANSFER_SRC_OPTIMAL, buffer, &regions);
        let (src, dst) = (S::TRANSFER, S::BOTTOM_OF_PIPE);
        device.cmd_pipeline_barrier(cmd, src, dst, none, &[], &[], &back);
        device.end_command_buffer(cmd)
    }
}
