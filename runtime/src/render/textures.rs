//! Textures of a format-2 solution on the GPU: each decoded once at load (the
//! one section not uploaded as stored, docs/solution-format.md), its whole mip
//! chain built on the CPU by [`solution::texture::MipChain`] (the levels the
//! reference renderer samples, byte for byte) and copied into an
//! `R8G8B8A8_SRGB` image, so the sampler decodes sRGB to linear per texel before
//! filtering, as the reference does. One sampler serves them all: trilinear
//! (`LINEAR`, `LINEAR`, mipmap `LINEAR`), `REPEAT`, no anisotropy.

use crate::gpu::{Buffer, BufferDesc, Gpu, GpuError, MemoryLocation, VkContext};
use ash::vk;
use solution::format::Texture;
use solution::texture::MipChain;

/// One texture: image, memory and a view of all its levels.
pub struct GpuTexture {
    pub view: vk::ImageView,
    raw: vk::Image,
    memory: vk::DeviceMemory,
    device: ash::Device,
    pub width: u32,
    pub height: u32,
    pub levels: u32,
}

impl Drop for GpuTexture {
    fn drop(&mut self) {
        // SAFETY: owners drop a texture only after waiting for the work that
        // uses it; null handles (failed construction) are ignored by Vulkan.
        unsafe {
            self.device.destroy_image_view(self.view, None);
            self.device.destroy_image(self.raw, None);
            self.device.free_memory(self.memory, None);
        }
    }
}

/// The sampler every textured draw uses (destroyed by its owner).
pub fn create_sampler(gpu: &Gpu) -> Result<vk::Sampler, GpuError> {
    let info = vk::SamplerCreateInfo::default()
        .mag_filter(vk::Filter::LINEAR)
        .min_filter(vk::Filter::LINEAR)
        .mipmap_mode(vk::SamplerMipmapMode::LINEAR)
        .address_mode_u(vk::SamplerAddressMode::REPEAT)
        .address_mode_v(vk::SamplerAddressMode::REPEAT)
        .address_mode_w(vk::SamplerAddressMode::REPEAT)
        .min_lod(0.0)
        .max_lod(vk::LOD_CLAMP_NONE);
    // SAFETY: valid create info.
    unsafe { gpu.device().create_sampler(&info, None) }.ctx("vkCreateSampler")
}

/// Uploads `texture` and its mip chain.
pub fn upload(gpu: &Gpu, texture: &Texture) -> Result<GpuTexture, GpuError> {
    let chain = MipChain::new(texture);
    let levels = chain.levels();
    let device = gpu.device();
    let format = vk::Format::R8G8B8A8_SRGB;
    let info = vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(format)
        .extent(vk::Extent3D {
            width: levels[0].width,
            height: levels[0].height,
            depth: 1,
        })
        .mip_levels(levels.len() as u32)
        .array_layers(1)
        .samples(vk::SampleCountFlags::TYPE_1)
        .tiling(vk::ImageTiling::OPTIMAL)
        .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST)
        .sharing_mode(vk::SharingMode::EXCLUSIVE)
        .initial_layout(vk::ImageLayout::UNDEFINED);
    let mut out = GpuTexture {
        view: vk::ImageView::null(),
        // SAFETY: valid create info; destroyed by the GpuTexture's Drop.
        raw: unsafe { device.create_image(&info, None) }.ctx("vkCreateImage")?,
        memory: vk::DeviceMemory::null(),
        device: device.clone(),
        width: levels[0].width,
        height: levels[0].height,
        levels: levels.len() as u32,
    };
    // SAFETY: `out.raw` belongs to this device.
    let req = unsafe { device.get_image_memory_requirements(out.raw) };
    let type_index = gpu
        .memory_type(req.memory_type_bits, vk::MemoryPropertyFlags::DEVICE_LOCAL)
        .or_else(|| gpu.memory_type(req.memory_type_bits, vk::MemoryPropertyFlags::empty()))
        .ok_or_else(|| GpuError::Unsupported("no memory type for a texture".into()))?;
    let alloc = vk::MemoryAllocateInfo::default()
        .allocation_size(req.size)
        .memory_type_index(type_index);
    // SAFETY: valid allocate info; freed by Drop.
    out.memory = unsafe { device.allocate_memory(&alloc, None) }.ctx("vkAllocateMemory")?;
    // SAFETY: memory allocated for this image's requirements.
    unsafe { device.bind_image_memory(out.raw, out.memory, 0) }.ctx("vkBindImageMemory")?;
    copy_levels(gpu, out.raw, levels)?;
    let range = vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: 0,
        level_count: out.levels,
        base_array_layer: 0,
        layer_count: 1,
    };
    let view = vk::ImageViewCreateInfo::default()
        .image(out.raw)
        .view_type(vk::ImageViewType::TYPE_2D)
        .format(format)
        .subresource_range(range);
    // SAFETY: the image was created with this format and these levels.
    out.view = unsafe { device.create_image_view(&view, None) }.ctx("vkCreateImageView")?;
    Ok(out)
}

/// Copies every level through one staging buffer and leaves the image in
/// `SHADER_READ_ONLY_OPTIMAL`.
fn copy_levels(
    gpu: &Gpu,
    image: vk::Image,
    levels: &[solution::texture::Level],
) -> Result<(), GpuError> {
    let total: u64 = levels.iter().map(|l| l.rgba.len() as u64).sum();
    let mut staging = Buffer::new(
        gpu,
        BufferDesc {
            size: total.max(4),
            usage: vk::BufferUsageFlags::TRANSFER_SRC,
            location: MemoryLocation::Mapped,
        },
    )?;
    let mut regions = Vec::with_capacity(levels.len());
    let mut offset = 0u64;
    for (k, level) in levels.iter().enumerate() {
        // SAFETY: the staging buffer is new and holds `total` bytes.
        unsafe { staging.write(offset, &level.rgba) };
        regions.push(
            vk::BufferImageCopy::default()
                .buffer_offset(offset)
                .image_subresource(vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    mip_level: k as u32,
                    base_array_layer: 0,
                    layer_count: 1,
                })
                .image_extent(vk::Extent3D {
                    width: level.width,
                    height: level.height,
                    depth: 1,
                }),
        );
        offset += level.rgba.len() as u64;
    }
    let range = vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: 0,
        level_count: levels.len() as u32,
        base_array_layer: 0,
        layer_count: 1,
    };
    gpu.one_shot(|device, cmd| {
        let to_dst = crate::gpu::barrier::image_barrier(
            image,
            range,
            (vk::ImageLayout::UNDEFINED, vk::AccessFlags::empty()),
            (
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                vk::AccessFlags::TRANSFER_WRITE,
            ),
        );
        let to_read = crate::gpu::barrier::image_barrier(
            image,
            range,
            (
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                vk::AccessFlags::TRANSFER_WRITE,
            ),
            (
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                vk::AccessFlags::SHADER_READ,
            ),
        );
        // SAFETY: `cmd` is recording outside a render pass; the image and the
        // staging buffer are live until the one-shot submit has finished.
        unsafe {
            crate::gpu::barrier::cmd_image_barriers(
                device,
                cmd,
                vk::PipelineStageFlags::TOP_OF_PIPE,
                vk::PipelineStageFlags::TRANSFER,
                &[to_dst],
            );
            device.cmd_copy_buffer_to_image(
                cmd,
                staging.raw,
                image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &regions,
            );
            crate::gpu::barrier::cmd_image_barriers(
                device,
                cmd,
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::FRAGMENT_SHADER,
                &[to_read],
            );
        }
    })
}

/// A scene's textures and the one sampler they share (none for an
/// untextured scene).
pub struct SceneTextures {
    pub sampler: vk::Sampler,
    textures: Vec<GpuTexture>,
    device: ash::Device,
}

impl SceneTextures {
    /// Uploads each texture `decode(k)` returns for k in `0..count`, decoding
    /// one at a time (only one decoded image is in host memory at once).
    pub fn new<E: From<GpuError>>(
        gpu: &Gpu,
        count: usize,
        mut decode: impl FnMut(usize) -> Result<Texture, E>,
    ) -> Result<SceneTextures, E> {
        let mut out = SceneTextures {
            sampler: vk::Sampler::null(),
            textures: Vec::with_capacity(count),
            device: gpu.device().clone(),
        };
        if count == 0 {
            return Ok(out);
        }
        out.sampler = create_sampler(gpu)?;
        for k in 0..count {
            let texture = decode(k)?;
            out.textures.push(upload(gpu, &texture)?);
        }
        Ok(out)
    }

    /// The view of texture `k`, if it exists.
    pub fn view(&self, k: u32) -> Option<vk::ImageView> {
        self.textures.get(k as usize).map(|t| t.view)
    }

    pub fn len(&self) -> usize {
        self.textures.len()
    }

    pub fn is_empty(&self) -> bool {
        self.textures.is_empty()
    }
}

impl Drop for SceneTextures {
    fn drop(&mut self) {
        // SAFETY: owners drop the scene only after waiting for the device; a
        // null sampler is ignored.
        unsafe { self.device.destroy_sampler(self.sampler, None) };
    }
}
