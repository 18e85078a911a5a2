//! Buffers and images: wrappers that own a `raw` handle and its memory, built from
//! a small description, destroyed on drop.
//!
//! # GPU lifetimes
//!
//! The GPU runs behind the host: memory the host touches may still be read or
//! written by a submitted command buffer. Two rules keep that sound, and this
//! module chooses to state them as contracts rather than to track submissions:
//!
//! - **Host access is `unsafe`.** [`Buffer::write`] and [`Buffer::read`] are
//!   `unsafe fn`s whose `# Safety` sections say what the GPU must not be doing
//!   with the memory; every caller names, in a `// SAFETY:` comment, the fence
//!   wait or `vkDeviceWaitIdle` that makes it so. The runtime's frame loops are
//!   synchronous (each frame's fence is waited for before its resources are
//!   touched again), so the proof is always a local one.
//! - **Drop is immediate.** A wrapper destroys its handle when dropped, so its
//!   owner must drop it only after waiting for the work that uses it (owners
//!   wait on their fences, or for device idle, in their own `Drop`, and declare
//!   fields newest-first: see the `gpu` module notes). Deferring destruction
//!   to fences, as wgpu and kajiya do, would make drop safe in every order, but
//!   needs every `vkQueueSubmit` to go through one tracker; with three
//!   submitters (renderer, one-shot uploads, mirror) that each already wait,
//!   the contract is the smaller, checkable design.

use super::{DeviceShared, Gpu, GpuError, VkContext};
use ash::vk;
use std::sync::Arc;

/// Where a buffer's memory lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MemoryLocation {
    /// Device-local, filled through a staging copy.
    GpuOnly,
    /// Host-visible and coherent, persistently mapped (uniforms, staging,
    /// read-back).
    Mapped,
}

#[derive(Clone, Debug)]
pub struct BufferDesc {
    pub size: u64,
    pub usage: vk::BufferUsageFlags,
    pub location: MemoryLocation,
}

pub struct Buffer {
    pub raw: vk::Buffer,
    pub desc: BufferDesc,
    memory: vk::DeviceMemory,
    /// Host address of the whole buffer for [`MemoryLocation::Mapped`].
    mapped: Option<std::ptr::NonNull<u8>>,
    shared: Arc<DeviceShared>,
}

// SAFETY: the mapped pointer refers to memory owned by this buffer, and access to
// it goes through `&self`/`&mut self` methods; Vulkan handles are plain values.
unsafe impl Send for Buffer {}

impl Buffer {
    pub fn new(gpu: &Gpu, desc: BufferDesc) -> Result<Buffer, GpuError> {
        if desc.size == 0 {
            return Err(GpuError::Unsupported("zero-sized buffer".into()));
        }
        let device = gpu.device();
        let info = vk::BufferCreateInfo::default()
            .size(desc.size)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid device and create info; destroyed in Drop (or below on error).
        let raw = unsafe { device.create_buffer(&info, None) }.ctx("vkCreateBuffer")?;
        // SAFETY: `raw` is a buffer of this device.
        let req = unsafe { device.get_buffer_memory_requirements(raw) };
        let flags = match desc.location {
            MemoryLocation::GpuOnly => vk::MemoryPropertyFlags::DEVICE_LOCAL,
            MemoryLocation::Mapped => {
                vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT
            }
        };
        let memory = gpu
            .memory_type(req.memory_type_bits, flags)
            .or_else(|| {
                // Device-local is a preference: any allowed type works for GpuOnly.
                (desc.location == MemoryLocation::GpuOnly)
                    .then(|| {
                        gpu.memory_type(req.memory_type_bits, vk::MemoryPropertyFlags::empty())
                    })
                    .flatten()
            })
            .ok_or_else(|| GpuError::Unsupported(format!("no memory type for {desc:?}")))
            .and_then(|type_index| {
                let alloc = vk::MemoryAllocateInfo::default()
                    .allocation_size(req.size)
                    .memory_type_index(type_index);
                // SAFETY: valid allocate info; freed in Drop.
                unsafe { device.allocate_memory(&alloc, None) }.ctx("vkAllocateMemory")
            });
        let memory = match memory {
            Ok(m) => m,
            Err(e) => {
                // SAFETY: `raw` is unused and owned here.
                unsafe { device.destroy_buffer(raw, None) };
                return Err(e);
            }
        };
        let mut buffer = Buffer {
            raw,
            desc,
            memory,
            mapped: None,
            shared: gpu.shared.clone(),
        };
        // SAFETY: the memory was allocated for this buffer's requirements.
        unsafe { device.bind_buffer_memory(raw, memory, 0) }.ctx("vkBindBufferMemory")?;
        if buffer.desc.location == MemoryLocation::Mapped {
            // SAFETY: host-visible memory, mapped once for the buffer's lifetime.
            let ptr = unsafe {
                device.map_memory(memory, 0, vk::WHOLE_SIZE, vk::MemoryMapFlags::empty())
            }
            .ctx("vkMapMemory")?;
            buffer.mapped = std::ptr::NonNull::new(ptr.cast());
        }
        Ok(buffer)
    }

    /// Copies `bytes` to `offset` of a mapped buffer.
    ///
    /// # Safety
    ///
    /// No command buffer that reads or writes this buffer may be pending on the
    /// GPU (its fence was waited for, or the device is idle, or it was never
    /// submitted), so the host write races with no device access.
    ///
    /// # Panics
    /// If the buffer is not mapped or the range is out of bounds (programming
    /// errors: sizes come from the renderer, not from input).
    pub unsafe fn write(&mut self, offset: u64, bytes: &[u8]) {
        let ptr = self.mapped.expect("Buffer::write on an unmapped buffer");
        assert!(
            offset + bytes.len() as u64 <= self.desc.size,
            "Buffer::write out of range"
        );
        // SAFETY: the mapping covers `desc.size` bytes, checked above, and the
        // source is a separate host slice; the memory is coherent, and the caller
        // guarantees that no pending GPU work uses it.
        unsafe {
            std::ptr::copy_nonoverlapping(
                bytes.as_ptr(),
                ptr.as_ptr().add(offset as usize),
                bytes.len(),
            )
        };
    }

    /// The mapped contents.
    ///
    /// # Safety
    ///
    /// The GPU writes the caller wants to see have completed (their fence was
    /// waited for, or they were a [`Gpu::one_shot`], which waits), and no command
    /// buffer that writes this buffer is pending or is submitted while the
    /// returned slice is alive.
    ///
    /// # Panics
    /// If the buffer is not mapped.
    pub unsafe fn read(&self) -> &[u8] {
        let ptr = self.mapped.expect("Buffer::read on an unmapped buffer");
        // SAFETY: the mapping covers `desc.size` bytes and lives as long as self;
        // the caller guarantees that the GPU does not write it meanwhile.
        unsafe { std::slice::from_raw_parts(ptr.as_ptr(), self.desc.size as usize) }
    }

    /// A device-local buffer filled with `bytes` through a staging copy.
    pub fn with_data(
        gpu: &Gpu,
        usage: vk::BufferUsageFlags,
        bytes: &[u8],
    ) -> Result<Buffer, GpuError> {
        let size = (bytes.len() as u64).max(4);
        let mut staging = Buffer::new(
            gpu,
            BufferDesc {
                size,
                usage: vk::BufferUsageFlags::TRANSFER_SRC,
                location: MemoryLocation::Mapped,
            },
        )?;
        // SAFETY: the staging buffer was just created and no command buffer
        // refers to it yet.
        unsafe { staging.write(0, bytes) };
        let buffer = Buffer::new(
            gpu,
            BufferDesc {
                size,
                usage: usage | vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuOnly,
            },
        )?;
        gpu.one_shot(|device, cmd| {
            let region = [vk::BufferCopy::default().size(size)];
            // SAFETY: both buffers are at least `size` bytes; `cmd` is recording.
            unsafe { device.cmd_copy_buffer(cmd, staging.raw, buffer.raw, &region) };
        })?;
        Ok(buffer)
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: owners drop a buffer only after waiting for the work that uses
        // it (the module's lifetime rules); the memory is unmapped implicitly
        // when freed.
        unsafe {
            self.shared.device.destroy_buffer(self.raw, None);
            self.shared.device.free_memory(self.memory, None);
        }
    }
}

/// A 2-D image with `layers` array layers (one per view) and one view of all of
/// them (`TYPE_2D_ARRAY`).
#[derive(Clone, Debug)]
pub struct ImageDesc {
    pub width: u32,
    pub height: u32,
    pub layers: u32,
    pub format: vk::Format,
    pub samples: vk::SampleCountFlags,
    pub usage: vk::ImageUsageFlags,
    pub aspect: vk::ImageAspectFlags,
}

pub struct Image {
    pub view: vk::ImageView,
    pub raw: vk::Image,
    pub desc: ImageDesc,
    /// None for an image owned by someone else (a swapchain's).
    memory: Option<vk::DeviceMemory>,
    shared: Arc<DeviceShared>,
}

impl Image {
    pub fn new(gpu: &Gpu, desc: ImageDesc) -> Result<Image, GpuError> {
        let device = gpu.device();
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D {
                width: desc.width,
                height: desc.height,
                depth: 1,
            })
            .mip_levels(1)
            .array_layers(desc.layers)
            .samples(desc.samples)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid create info; destroyed in Drop or below on error.
        let raw = unsafe { device.create_image(&info, None) }.ctx("vkCreateImage")?;
        // SAFETY: `raw` belongs to this device.
        let req = unsafe { device.get_image_memory_requirements(raw) };
        let type_index = gpu
            .memory_type(req.memory_type_bits, vk::MemoryPropertyFlags::DEVICE_LOCAL)
            .or_else(|| gpu.memory_type(req.memory_type_bits, vk::MemoryPropertyFlags::empty()));
        let Some(type_index) = type_index else {
            // SAFETY: unused image owned here.
            unsafe { device.destroy_image(raw, None) };
            return Err(GpuError::Unsupported(format!(
                "no memory type for image {desc:?}"
            )));
        };
        let alloc = vk::MemoryAllocateInfo::default()
            .allocation_size(req.size)
            .memory_type_index(type_index);
        // SAFETY: valid allocate info.
        let memory = match unsafe { device.allocate_memory(&alloc, None) } {
            Ok(m) => m,
            Err(result) => {
                // SAFETY: unused image owned here.
                unsafe { device.destroy_image(raw, None) };
                return Err(GpuError::Vulkan {
                    call: "vkAllocateMemory",
                    result,
                });
            }
        };
        let mut image = Image {
            view: vk::ImageView::null(),
            raw,
            desc,
            memory: Some(memory),
            shared: gpu.shared.clone(),
        };
        // SAFETY: memory allocated for this image's requirements.
        unsafe { device.bind_image_memory(raw, memory, 0) }.ctx("vkBindImageMemory")?;
        image.view = create_view(gpu, raw, &image.desc)?;
        Ok(image)
    }

    /// Wraps an image owned elsewhere (an OpenXR swapchain's): only the view is
    /// created and destroyed here.
    pub fn borrowed(gpu: &Gpu, raw: vk::Image, desc: ImageDesc) -> Result<Image, GpuError> {
        let view = create_view(gpu, raw, &desc)?;
        Ok(Image {
            view,
            raw,
            desc,
            memory: None,
            shared: gpu.shared.clone(),
        })
    }

    /// The subresource range of every layer.
    pub fn range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            aspect_mask: self.desc.aspect,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: self.desc.layers,
        }
    }
}

fn create_view(gpu: &Gpu, raw: vk::Image, desc: &ImageDesc) -> Result<vk::ImageView, GpuError> {
    let info = vk::ImageViewCreateInfo::default()
        .image(raw)
        .view_type(vk::ImageViewType::TYPE_2D_ARRAY)
        .format(desc.format)
        .subresource_range(vk::ImageSubresourceRange {
            aspect_mask: desc.aspect,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: desc.layers,
        });
    // SAFETY: `raw` is an image of this device created with `desc`.
    unsafe { gpu.device().create_image_view(&info, None) }.ctx("vkCreateImageView")
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: owners drop an image only after waiting for the work that uses
        // it (the module's lifetime rules); a null view (failed
        // construction) is ignored by vkDestroyImageView; a borrowed image is not
        // destroyed here.
        unsafe {
            self.shared.device.destroy_image_view(self.view, None);
            if let Some(memory) = self.memory {
                self.shared.device.destroy_image(self.raw, None);
                self.shared.device.free_memory(memory, None);
            }
        }
    }
}
