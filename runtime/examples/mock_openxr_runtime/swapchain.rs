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
/// compositor would read them, and summarises them.
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
    let (family, queue) = v.queue.ok_or(vk::Result::ERROR_INITIALIZATION_FAILED)?;
    let layer_bytes = u64::from(w) * u64::from(h) * 4;
    // SAFETY: the device and image are the session's (made through this
    // runtime); the image was released, so the application is not using it,
    // and the application's queue is free during xrEndFrame; on success every
    // object made here is destroyed after the queue is idle (an error path
    // leaks them, which a test tolerates).
    unsafe {
        let buffer = device.create_buffer(
            &vk::BufferCreateInfo::default()
                .size(layer_bytes * 2)
                .usage(vk::BufferUsageFlags::TRANSFER_DST),
            None,
        )?;
        let req = device.get_buffer_memory_requirements(buffer);
        let props = instance.get_physical_device_memory_properties(v.physical);
        let wanted = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        let type_index = (0..props.memory_type_count)
            .find(|&i| {
                req.memory_type_bits & (1 << i) != 0
                    && props.memory_types[i as usize]
                        .property_flags
                        .contains(wanted)
            })
            .ok_or(vk::Result::ERROR_FEATURE_NOT_PRESENT)?;
        let memory = device.allocate_memory(
            &vk::MemoryAllocateInfo::default()
                .allocation_size(req.size)
                .memory_type_index(type_index),
            None,
        )?;
        device.bind_buffer_memory(buffer, memory, 0)?;
        let pool = device.create_command_pool(
            &vk::CommandPoolCreateInfo::default().queue_family_index(family),
            None,
        )?;
        let cmd = device.allocate_command_buffers(
            &vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .command_buffer_count(1),
        )?[0];
        device.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())?;
        let range = vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: 2,
        };
        let barrier = |from, to, src, dst| {
            vk::ImageMemoryBarrier::default()
                .old_layout(from)
                .new_layout(to)
                .src_access_mask(src)
                .dst_access_mask(dst)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(image)
                .subresource_range(range)
        };
        device.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
            vk::PipelineStageFlags::TRANSFER,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &[barrier(
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
                vk::AccessFlags::TRANSFER_READ,
            )],
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
        device.cmd_copy_image_to_buffer(
            cmd,
            image,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            buffer,
            &regions,
        );
        device.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::BOTTOM_OF_PIPE,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &[barrier(
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::AccessFlags::TRANSFER_READ,
                vk::AccessFlags::empty(),
            )],
        );
        device.end_command_buffer(cmd)?;
        let cmds = [cmd];
        device.queue_submit(
            queue,
            &[vk::SubmitInfo::default().command_buffers(&cmds)],
            vk::Fence::null(),
        )?;
        device.queue_wait_idle(queue)?;
        let ptr = device.map_memory(memory, 0, layer_bytes * 2, vk::MemoryMapFlags::empty())?
            as *const u8;
        let bytes = std::slice::from_raw_parts(ptr, (layer_bytes * 2) as usize).to_vec();
        device.unmap_memory(memory);
        device.destroy_command_pool(pool, None);
        device.destroy_buffer(buffer, None);
        device.free_memory(memory, None);

        let (left, right) = bytes.split_at(layer_bytes as usize);
        let stats = [left, right]
            .iter()
            .map(|layer| {
                let n = (w * h) as f64;
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
            })
            .collect();
        let differ = left
            .chunks_exact(4)
            .zip(right.chunks_exact(4))
            .filter(|(a, b)| a[..3] != b[..3])
            .count() as f64
            / f64::from(w * h);
        Ok((stats, differ, bytes))
    }
}
