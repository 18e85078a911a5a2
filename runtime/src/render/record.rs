//! Recording a frame's command buffer: the attachments' layout barriers, then
//! for each pass of the frame the scene subpass (batches by pipeline, then the
//! inspection lines) and the tone-map subpass.

use super::passes::{self, BatchConstants, PassSet};
use super::{DrawKind, Edges, StereoRenderer};
use crate::gpu::barrier::{cmd_image_barriers, image_barrier};
use crate::gpu::{GpuError, Image, VkContext};
use ash::vk;

impl StereoRenderer {
    /// Records the frame's command buffer for swapchain image `image`: the
    /// attachments' layout barriers, then one render pass per view mask.
    pub(super) fn record(&self, view_count: usize, image: usize) -> Result<(), GpuError> {
        let device = &self.gpu_shared.device;
        let cmd = self.command_buffer;
        let target = &self.targets[image];
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the fence wait in `render` guarantees the buffer is not pending;
        // the pool was created with RESET_COMMAND_BUFFER.
        unsafe {
            device
                .reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())
                .ctx("vkResetCommandBuffer")?;
            device
                .begin_command_buffer(cmd, &begin)
                .ctx("vkBeginCommandBuffer")?;
        }
        // Discard last frame's contents: UNDEFINED → each attachment's layout.
        let mut barriers = vec![
            layout_barrier(&self.depth, passes::DEPTH_LAYOUT),
            layout_barrier(&self.linear, passes::LINEAR_LAYOUT),
            layout_barrier(&target.output, passes::OUTPUT_LAYOUT),
        ];
        if let Some(msaa) = &self.msaa {
            barriers.push(layout_barrier(msaa, passes::MSAA_LAYOUT));
        }
        // SAFETY: recording; the barriers name live images of this device.
        unsafe {
            cmd_image_barriers(
                device,
                cmd,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::PipelineStageFlags::ALL_COMMANDS,
                &barriers,
            )
        };
        for mask in self.frame_masks(view_count) {
            let (index, set) = self
                .pass_sets
                .iter()
                .enumerate()
                .find(|(_, s)| s.desc.view_mask == mask)
                .ok_or_else(|| GpuError::Unsupported(format!("no pass for view mask {mask:#b}")))?;
            // SAFETY: `cmd` was begun above and no render pass is open; the
            // framebuffer is the target's for this pass set.
            unsafe { self.record_pass(cmd, index, set, target.framebuffers[index]) };
        }
        // SAFETY: recording.
        unsafe { device.end_command_buffer(cmd) }.ctx("vkEndCommandBuffer")
    }

    /// Records one pass set's render pass: the scene subpass (batches, then
    /// the inspection lines) and the tone-map subpass.
    ///
    /// # Safety
    ///
    /// `cmd` is recording, outside a render pass, and `framebuffer` is this
    /// renderer's framebuffer for `set` (index `set_index`).
    unsafe fn record_pass(
        &self,
        cmd: vk::CommandBuffer,
        set_index: usize,
        set: &PassSet,
        framebuffer: vk::Framebuffer,
    ) {
        let device = &self.gpu_shared.device;
        let (w, h) = (self.desc.width, self.desc.height);
        let black = vk::ClearValue {
            color: vk::ClearColorValue {
                float32: [0.0, 0.0, 0.0, 1.0],
            },
        };
        let mut clear = vec![
            vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: 1.0,
                    stencil: 0,
                },
            },
            black,
            black,
        ];
        if self.msaa.is_some() {
            clear.push(black);
        }
        let area = vk::Rect2D {
            offset: vk::Offset2D { x: 0, y: 0 },
            extent: vk::Extent2D {
                width: w,
                height: h,
            },
        };
        let begin = vk::RenderPassBeginInfo::default()
            .render_pass(set.render_pass)
            .framebuffer(framebuffer)
            .render_area(area)
            .clear_values(&clear);
        let viewport = [vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: w as f32,
            height: h as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        }];
        let tone_gain = self.desc.tone.gain() / self.scene.radiance_scale;
        let mut tone_push = [0u8; 8];
        tone_push[0..4].copy_from_slice(&tone_gain.to_le_bytes());
        tone_push[4..8].copy_from_slice(&self.desc.tone.curve.code().to_le_bytes());
        // SAFETY: the caller guarantees that `cmd` is recording outside a
        // render pass; the render pass, framebuffer and scene buffers are live
        // and this renderer's, the framebuffer made for this pass set.
        unsafe {
            device.cmd_begin_render_pass(cmd, &begin, vk::SubpassContents::INLINE);
            device.cmd_set_viewport(cmd, 0, &viewport);
            device.cmd_set_scissor(cmd, 0, &[area]);
            device.cmd_bind_vertex_buffers(cmd, 0, &[self.scene.vertices.raw], &[0]);
            device.cmd_bind_index_buffer(cmd, self.scene.indices.raw, 0, vk::IndexType::UINT32);
        }
        if let Some(sky) = &self.sky {
            // SAFETY: inside the scene subpass of pass set `set_index`; the
            // background goes first, so the geometry covers it.
            unsafe { sky.record(device, cmd, set_index, self.scene.radiance_scale) };
        }
        // SAFETY: inside the scene subpass of `set`, the scene's buffers bound.
        unsafe { self.record_batches(cmd, set) };
        if let (Some(lines), Some(&frame_set)) = (&self.inspect_gpu, self.batch_sets.first()) {
            if self.inspect.draws_lines() {
                // SAFETY: inside the scene subpass of pass set `set_index`; the
                // lines index the scene's own vertex buffer.
                unsafe {
                    lines.record(
                        device,
                        cmd,
                        set_index,
                        frame_set,
                        self.inspect,
                        self.desc.tone,
                        self.scene.radiance_scale,
                        (&self.scene.vertices, self.scene.vertex_count),
                    )
                };
            }
        }
        // SAFETY: inside the scene subpass of `set`; the tone-map pipeline and
        // its descriptor set (the linear attachment as input) are this
        // renderer's, and the push constants match its fragment range.
        unsafe {
            device.cmd_next_subpass(cmd, vk::SubpassContents::INLINE);
            device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, set.tonemap);
            device.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                self.layouts.tonemap_pipeline,
                0,
                &[self.tonemap_set],
                &[],
            );
            device.cmd_push_constants(
                cmd,
                self.layouts.tonemap_pipeline,
                vk::ShaderStageFlags::FRAGMENT,
                0,
                &tone_push,
            );
            device.cmd_draw(cmd, 3, 1, 0, 0);
            device.cmd_end_render_pass(cmd);
        }
    }

    /// Draws the scene's batches (none when the wireframe is shown alone),
    /// binding each batch's pipeline, descriptor set and push constants.
    ///
    /// # Safety
    ///
    /// `cmd` is recording inside the scene subpass of `set`, with the scene's
    /// vertex and index buffers bound.
    unsafe fn record_batches(&self, cmd: vk::CommandBuffer, set: &PassSet) {
        let device = &self.gpu_shared.device;
        // Wireframe alone (prorad's -w) leaves the shading out.
        let shaded = if self.inspect.edges == Edges::Only {
            0
        } else {
            self.scene.draws.len()
        };
        let Some(pass) = self
            .pass_ranges
            .iter()
            .find(|p| p.view_mask == set.desc.view_mask)
        else {
            return;
        };
        let mut bound = None;
        for (((draw, &ds), drawn), texture_set) in self
            .scene
            .draws
            .iter()
            .zip(&self.batch_sets)
            .zip(&pass.per_draw)
            .zip(&self.texture_sets)
            .take(shaded)
        {
            let ranges = &pass.ranges[drawn.clone()];
            if ranges.is_empty() {
                continue;
            }
            let pipeline = match draw.kind {
                _ if draw.texture.is_some() => set.scene_textured,
                DrawKind::Sh if draw.order == 0 => set.scene_l0,
                DrawKind::Sh => set.scene_sh,
                DrawKind::Cube { .. } => set.scene_cube,
            };
            if bound != Some(pipeline) {
                // SAFETY: the caller guarantees the subpass; the pipeline was
                // made for it.
                unsafe { device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline) };
                bound = Some(pipeline);
            }
            let constants = BatchConstants {
                order: draw.loop_parameter(),
                vertex_base: draw.vertex_base,
                coeff_base: 0,
                stride: draw.stride,
                scale: draw.storage_scale * self.scene.radiance_scale,
                texture_scale: draw.texture.as_ref().map_or([0.0; 3], |t| {
                    t.factor.map(|f| f * self.scene.radiance_scale)
                }),
                emission_scale: draw
                    .texture
                    .as_ref()
                    .and_then(|t| t.emission)
                    .map_or([0.0; 3], |e| {
                        e.factor.map(|f| f * self.scene.radiance_scale)
                    }),
            };
            // Textured batches bind their second set and push 44 bytes with
            // the textured layout; the others exactly what they did before.
            let bytes = constants.bytes();
            let all_sets = [ds, texture_set.unwrap_or_default()];
            let (layout, sets, push) = match texture_set {
                Some(_) => (self.layouts.textured_pipeline, &all_sets[..], &bytes[..]),
                None => (
                    self.layouts.scene_pipeline,
                    &all_sets[..1],
                    &bytes[..BatchConstants::SIZE as usize],
                ),
            };
            // SAFETY: the caller guarantees the subpass and the bound buffers;
            // the batch's descriptor sets are live (a textured batch's second
            // set holds its UV + E/π range and its texture, both alive with the
            // scene); each draw stays within the buffers (indices were checked
            // against their batch's vertex count at upload, and the chunks
            // cover the batch's triangles).
            unsafe {
                device.cmd_bind_descriptor_sets(
                    cmd,
                    vk::PipelineBindPoint::GRAPHICS,
                    layout,
                    0,
                    sets,
                    &[],
                );
                device.cmd_push_constants(cmd, layout, vk::ShaderStageFlags::VERTEX, 0, push);
                for &(first_triangle, triangles) in ranges {
                    device.cmd_draw_indexed(
                        cmd,
                        3 * triangles,
                        1,
                        draw.first_index + 3 * first_triangle,
                        draw.vertex_base as i32,
                        0,
                    );
                }
            }
        }
    }
}

fn layout_barrier(image: &Image, layout: vk::ImageLayout) -> vk::ImageMemoryBarrier<'static> {
    transition(image, vk::ImageLayout::UNDEFINED, layout)
}

/// A full-memory barrier moving every layer of `image` from `from` to `to`.
pub(super) fn transition(
    image: &Image,
    from: vk::ImageLayout,
    to: vk::ImageLayout,
) -> vk::ImageMemoryBarrier<'static> {
    image_barrier(
        image.raw,
        image.range(),
        (from, vk::AccessFlags::MEMORY_WRITE),
        (
            to,
            vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE,
        ),
    )
}
