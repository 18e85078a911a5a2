//! The environment behind the geometry (solution format x.1, issue 41): a
//! full-screen triangle drawn first in the scene subpass, without depth test
//! or write, so every pixel that no triangle covers shows the sky toward its
//! view direction and the sun's disc, as `solution::raster` draws it (stage
//! 7) for the comparisons. The view directions at the triangle's corners are
//! computed in f64 here per frame, the same formula as
//! `solution::raster::pixel_direction`, and interpolated without perspective
//! (they are affine in screen space).

use super::passes::PassSet;
use super::StereoRenderer;
use crate::gpu::pipeline::{pipeline_layout, set_layout, GraphicsPipeline, ShaderModules};
use crate::gpu::{shaders, Buffer, BufferDesc, Gpu, GpuError, MemoryLocation, VkContext};
use ash::vk;
use glam::DVec3;
use solution::camera::{EyeView, UpAxis};
use solution::format::{equirect_frame, Environment};
use std::sync::Arc;

/// Bytes of the `Sky` uniform block (`shaders/sky_common.glsl`): six corner
/// directions, the frame's three axes, the sun's direction and radiance, the
/// size.
const UNIFORM_SIZE: u64 = 12 * 16;

/// The GPU side of the environment. Fields newest first.
pub struct SkyGpu {
    pipelines: Vec<vk::Pipeline>,
    layout: vk::PipelineLayout,
    set: vk::DescriptorSet,
    pool: vk::DescriptorPool,
    set_layout: vk::DescriptorSetLayout,
    uniforms: Buffer,
    _texels: Buffer,
    /// The uniform block's bytes after the corners (frame, sun, size).
    fixed: Vec<u8>,
    shared: Arc<crate::gpu::DeviceShared>,
}

impl Drop for SkyGpu {
    fn drop(&mut self) {
        // SAFETY: the renderer waits for the GPU before dropping this; null
        // handles (a failed construction) are ignored by Vulkan.
        unsafe {
            let d = &self.shared.device;
            for &p in &self.pipelines {
                d.destroy_pipeline(p, None);
            }
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_pool(self.pool, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

fn push_vec4(out: &mut Vec<u8>, v: [f32; 4]) {
    for f in v {
        out.extend_from_slice(&f.to_le_bytes());
    }
}

/// The uniform block after the corners: the equirectangular frame of `up`,
/// the sun (w = cos of its angular radius, 2 when there is none) and the size.
fn fixed_bytes(env: &Environment, up: UpAxis) -> Vec<u8> {
    let mut out = Vec::with_capacity(6 * 16);
    for axis in equirect_frame(up) {
        push_vec4(
            &mut out,
            [axis[0] as f32, axis[1] as f32, axis[2] as f32, 0.0],
        );
    }
    let (direction, radiance) = match &env.sun {
        Some(sun) => {
            let cos = (0.5 * f64::from(sun.angular_diameter_deg))
                .to_radians()
                .cos();
            let d = sun.direction;
            ([d[0], d[1], d[2], cos as f32], sun.radiance)
        }
        None => ([0.0, 0.0, 0.0, 2.0], [0.0; 3]),
    };
    push_vec4(&mut out, direction);
    push_vec4(&mut out, [radiance[0], radiance[1], radiance[2], 0.0]);
    for u in [env.width, env.height, 0, 0] {
        out.extend_from_slice(&u.to_le_bytes());
    }
    out
}

/// The view direction at NDC (`x`, `y`) (Vulkan: y = −1 is the top row):
/// `solution::raster::pixel_direction` continued over the whole plane.
fn ndc_direction(view: &EyeView, x: f64, y: f64) -> DVec3 {
    let (tl, tr, tu, td) = view.fov.tangents();
    let tx = tl + (tr - tl) * (x + 1.0) / 2.0;
    let ty = tu - (tu - td) * (y + 1.0) / 2.0;
    view.forward + tx * view.right + ty * view.up
}

impl SkyGpu {
    /// Uploads `env` and makes one pipeline per pass set.
    pub(super) fn new(
        gpu: &Gpu,
        env: &Environment,
        up: UpAxis,
        pass_sets: &[PassSet],
    ) -> Result<SkyGpu, GpuError> {
        use vk::{DescriptorType as D, ShaderStageFlags as S};
        let texel_bytes: Vec<u8> = env
            .texels
            .iter()
            .flat_map(|t| t.iter().flat_map(|c| c.to_le_bytes()))
            .collect();
        let texels = Buffer::with_data(gpu, vk::BufferUsageFlags::STORAGE_BUFFER, &texel_bytes)?;
        let uniforms = Buffer::new(
            gpu,
            BufferDesc {
                size: UNIFORM_SIZE,
                usage: vk::BufferUsageFlags::UNIFORM_BUFFER,
                location: MemoryLocation::Mapped,
            },
        )?;
        let mut sky = SkyGpu {
            pipelines: Vec::new(),
            layout: vk::PipelineLayout::null(),
            set: vk::DescriptorSet::null(),
            pool: vk::DescriptorPool::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            uniforms,
            _texels: texels,
            fixed: fixed_bytes(env, up),
            shared: gpu.shared.clone(),
        };
        // Each handle is stored at once, so Drop destroys it on a later error.
        sky.set_layout = set_layout(
            gpu,
            &[
                (D::UNIFORM_BUFFER, S::VERTEX | S::FRAGMENT),
                (D::STORAGE_BUFFER, S::FRAGMENT),
            ],
        )?;
        sky.layout = pipeline_layout(gpu, &[sky.set_layout], S::FRAGMENT, 4)?;
        sky.create_set(gpu)?;
        let mut modules = ShaderModules::new(gpu);
        let vert = modules.load(gpu, shaders::SKY_VERT)?;
        let frag = modules.load(gpu, shaders::SKY_FRAG)?;
        for set in pass_sets {
            let pipeline = GraphicsPipeline {
                samples: set.desc.samples,
                ..GraphicsPipeline::new(set.render_pass, 0, sky.layout, vert, frag)
            }
            .build(gpu)?;
            sky.pipelines.push(pipeline);
        }
        Ok(sky)
    }

    /// The descriptor pool and the one set: the uniforms and the texels.
    fn create_set(&mut self, gpu: &Gpu) -> Result<(), GpuError> {
        let device = gpu.device();
        let sizes = [
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::UNIFORM_BUFFER)
                .descriptor_count(1),
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(1),
        ];
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(1)
            .pool_sizes(&sizes);
        // SAFETY: valid device and create info; destroyed in Drop.
        self.pool =
            unsafe { device.create_descriptor_pool(&info, None) }.ctx("vkCreateDescriptorPool")?;
        let layouts = [self.set_layout];
        let alloc = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.pool)
            .set_layouts(&layouts);
        // SAFETY: the pool was sized for this one set.
        self.set =
            unsafe { device.allocate_descriptor_sets(&alloc) }.ctx("vkAllocateDescriptorSets")?[0];
        let uniform = [vk::DescriptorBufferInfo::default()
            .buffer(self.uniforms.raw)
            .range(vk::WHOLE_SIZE)];
        let storage = [vk::DescriptorBufferInfo::default()
            .buffer(self._texels.raw)
            .range(vk::WHOLE_SIZE)];
        let writes = [
            vk::WriteDescriptorSet::default()
                .dst_set(self.set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                .buffer_info(&uniform),
            vk::WriteDescriptorSet::default()
                .dst_set(self.set)
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&storage),
        ];
        // SAFETY: the set and buffers are live; no command buffer uses the set yet.
        unsafe { device.update_descriptor_sets(&writes, &[]) };
        Ok(())
    }

    /// Writes the corner directions of `views` (a mono frame repeats its
    /// view for layer 1) and the fixed part.
    ///
    /// # Safety
    ///
    /// No submitted command buffer that reads the uniforms is pending (the
    /// renderer waited for its frame fence).
    pub(super) unsafe fn write_views(&mut self, views: &[EyeView]) {
        let mut bytes = Vec::with_capacity(UNIFORM_SIZE as usize);
        for i in 0..2 {
            let view = &views[i.min(views.len().saturating_sub(1))];
            for (x, y) in [(-1.0, -1.0), (3.0, -1.0), (-1.0, 3.0)] {
                let d = ndc_direction(view, x, y).as_vec3();
                push_vec4(&mut bytes, [d.x, d.y, d.z, 0.0]);
            }
        }
        bytes.extend_from_slice(&self.fixed);
        // SAFETY: the caller guarantees no pending GPU work reads the buffer.
        unsafe { self.uniforms.write(0, &bytes) };
    }

    /// Records the background triangle into the scene subpass of pass set
    /// `set_index`.
    ///
    /// # Safety
    ///
    /// `cmd` is recording inside the scene subpass of pass set `set_index`.
    pub(super) unsafe fn record(
        &self,
        device: &ash::Device,
        cmd: vk::CommandBuffer,
        set_index: usize,
        radiance_scale: f32,
    ) {
        let Some(&pipeline) = self.pipelines.get(set_index) else {
            return;
        };
        // SAFETY: the caller guarantees the subpass this pipeline was made
        // for; the set, layout and push range are this object's.
        unsafe {
            device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline);
            device.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                self.layout,
                0,
                &[self.set],
                &[],
            );
            device.cmd_push_constants(
                cmd,
                self.layout,
                vk::ShaderStageFlags::FRAGMENT,
                0,
                &radiance_scale.to_le_bytes(),
            );
            device.cmd_draw(cmd, 3, 1, 0, 0);
        }
    }
}

impl StereoRenderer {
    /// Draws `env` behind the geometry from now on (`None`: a black
    /// background, as for every x.0 file).
    pub fn set_environment(
        &mut self,
        gpu: &Gpu,
        env: Option<&Environment>,
        up: UpAxis,
    ) -> Result<(), GpuError> {
        self.wait_idle();
        self.sky = match env {
            Some(env) => Some(SkyGpu::new(gpu, env, up, &self.pass_sets)?),
            None => None,
        };
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use solution::camera::Fov;

    #[test]
    fn corner_directions_continue_the_pixel_directions() {
        // A pixel centre's NDC is 2(i + 0.5)/w − 1; the direction there,
        // interpolated affinely from the corners, is the CPU's.
        let view = EyeView {
            position: DVec3::ZERO,
            right: DVec3::X,
            up: DVec3::Y,
            forward: DVec3::NEG_Z,
            fov: Fov::symmetric(50f64.to_radians(), 40, 30),
            width: 40,
            height: 30,
        };
        let (a, b, c) = (
            ndc_direction(&view, -1.0, -1.0),
            ndc_direction(&view, 3.0, -1.0),
            ndc_direction(&view, -1.0, 3.0),
        );
        for (i, j) in [(0, 0), (39, 29), (17, 5)] {
            let x = 2.0 * (f64::from(i) + 0.5) / 40.0 - 1.0;
            let y = 2.0 * (f64::from(j) + 0.5) / 30.0 - 1.0;
            let interpolated = a + (b - a) * (x + 1.0) / 4.0 + (c - a) * (y + 1.0) / 4.0;
            let cpu = solution::raster::pixel_direction(&view, i, j);
            assert!((interpolated - cpu).length() < 1e-12, "{i} {j}");
        }
    }
}
