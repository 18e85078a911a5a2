//! Mesh inspection (Remington 1992, app. D: prorad's `-w` wireframe and `-n` vertex
//! normals), drawn by the stereo renderer in its scene subpass when asked
//! ([`super::StereoRenderer::set_inspect`]): element edges as lines over the
//! shading or alone, and a short line along each vertex normal.
//!
//! Edges come from the triangles: each triangle's three edges, with the ones
//! two triangles share drawn once (an index list of `LINE_LIST` pairs per
//! batch, local to the batch like its triangle indices). The pipelines are made
//! the first time inspection is turned on, so a renderer that never inspects
//! (screenshots, XR) pays nothing.

use super::passes::{self, Layouts, PassSet};
use crate::gpu::pipeline::{pipeline_layout, GraphicsPipeline};
use crate::gpu::{shaders, Buffer, Gpu, GpuError};
use crate::render::ToneSettings;
use ash::vk;
use solution::format::MappedSolution;
use std::sync::Arc;

/// What to draw besides (or instead of) the shading.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Edges {
    #[default]
    Off,
    /// Element edges over the shaded image.
    Overlay,
    /// Element edges alone, on black (prorad's `-w`).
    Only,
}

/// The inspection state of a renderer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Inspect {
    pub edges: Edges,
    /// A line along each vertex normal (prorad's `-n`).
    pub normals: bool,
}

impl Inspect {
    pub fn draws_lines(&self) -> bool {
        self.edges != Edges::Off || self.normals
    }
}

/// Display colours (0..1, before sRGB encoding) of the lines.
pub const EDGE_COLOR: [f32; 3] = [0.1, 0.9, 0.3];
pub const NORMAL_COLOR: [f32; 3] = [1.0, 0.75, 0.1];
/// Normal lines are this fraction of the scene's bounding-box diagonal long.
pub const NORMAL_LENGTH_FRACTION: f32 = 0.02;
/// Each line end is moved this fraction of its distance toward the eye (see
/// `shaders/inspect.vert`).
pub const PULL: f32 = 1e-3;

/// Every edge of a triangle list once, as index pairs (smaller index first),
/// sorted.
pub fn unique_edges(indices: &[u32]) -> Vec<[u32; 2]> {
    let mut edges: Vec<[u32; 2]> = indices
        .chunks_exact(3)
        .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
        .filter(|[a, b]| a != b)
        .map(|[a, b]| [a.min(b), a.max(b)])
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// The value to write into the linear target so that the tone map shows
/// `display` (0..1): the inverse of exposure and curve, found by bisection (the
/// curves are monotone), times the scene's radiance scale.
pub fn linear_for_display(display: [f32; 3], tone: ToneSettings, radiance_scale: f32) -> [f32; 4] {
    let unexposed = ToneSettings {
        exposure_stops: 0.0,
        curve: tone.curve,
    };
    let invert = |target: f32| -> f32 {
        // Reinhard never reaches 1: ask for at most 0.98.
        let target = target.clamp(0.0, 0.98);
        let (mut lo, mut hi) = (0.0f32, 1.0f32);
        while unexposed.display_value(hi) < target && hi < 1e6 {
            hi *= 2.0;
        }
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if unexposed.display_value(mid) < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    };
    let gain = tone.gain();
    // Linear target = radiance × radiance scale; radiance = x / 2^stops. Half
    // floats end at 65504: keep the value finite at extreme exposures.
    let v = |c: f32| (invert(c) / gain * radiance_scale).min(60000.0);
    [v(display[0]), v(display[1]), v(display[2]), 1.0]
}

/// Push constants of `inspect.vert` / `inspect.frag` (24 bytes).
fn push_bytes(color: [f32; 4], normal_length: f32) -> [u8; 24] {
    let mut out = [0u8; 24];
    for (i, f) in color.iter().chain(&[normal_length, PULL]).enumerate() {
        out[4 * i..4 * i + 4].copy_from_slice(&f.to_le_bytes());
    }
    out
}

/// Edge index range of one draw batch.
#[derive(Clone, Copy, Debug)]
struct EdgeRange {
    first: u32,
    count: u32,
    vertex_base: u32,
}

/// Pipelines of one pass set.
struct Pipelines {
    edges: vk::Pipeline,
    normals: vk::Pipeline,
}

/// The GPU side of inspection: edge indices and the line pipelines.
pub struct InspectGpu {
    // Newest first.
    pipelines: Vec<Pipelines>,
    layout: vk::PipelineLayout,
    edge_indices: Option<Buffer>,
    ranges: Vec<EdgeRange>,
    normal_length: f32,
    shared: Arc<crate::gpu::DeviceShared>,
}

impl Drop for InspectGpu {
    fn drop(&mut self) {
        // SAFETY: the renderer waits for the GPU before dropping this; null
        // handles (a failed construction) are ignored.
        unsafe {
            let d = &self.shared.device;
            for p in &self.pipelines {
                d.destroy_pipeline(p.edges, None);
                d.destroy_pipeline(p.normals, None);
            }
            d.destroy_pipeline_layout(self.layout, None);
        }
    }
}

impl InspectGpu {
    /// Builds the edge lists of `file` (which must be the one the scene was
    /// uploaded from: `draws` name its batches) and one pair of pipelines per
    /// pass set. Only the index sections are read (and decoded), not the whole
    /// file.
    pub(super) fn new(
        gpu: &Gpu,
        file: &MappedSolution,
        draws: &[super::scene::DrawBatch],
        layouts: &Layouts,
        pass_sets: &[PassSet],
        diagonal: f32,
    ) -> Result<InspectGpu, super::RenderError> {
        let mut index_data: Vec<u8> = Vec::new();
        let mut ranges = Vec::new();
        let mut first = 0u64;
        for draw in draws {
            let batch = file.batches().get(draw.source).ok_or_else(|| {
                super::RenderError::Usage(format!(
                    "inspection was given a solution without batch {} of the uploaded one",
                    draw.source
                ))
            })?;
            if batch.index_count != draw.index_count {
                return Err(super::RenderError::Usage(format!(
                    "inspection was given a different solution (batch {} has {} indices, \
                     {} were uploaded)",
                    draw.source, batch.index_count, draw.index_count
                )));
            }
            let indices: Vec<u32> = file
                .index_bytes(draw.source)
                .chunks_exact(4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
            let edges = unique_edges(&indices);
            for [a, b] in &edges {
                index_data.extend_from_slice(&a.to_le_bytes());
                index_data.extend_from_slice(&b.to_le_bytes());
            }
            let count = edges.len() as u64 * 2;
            ranges.push(EdgeRange {
                first: u32::try_from(first).map_err(|_| {
                    super::RenderError::Usage("edge list exceeds 2^32 indices".into())
                })?,
                count: count as u32,
                vertex_base: draw.vertex_base,
            });
            first += count;
        }
        let edge_indices = if index_data.is_empty() {
            None
        } else {
            Some(Buffer::with_data(
                gpu,
                vk::BufferUsageFlags::INDEX_BUFFER,
                &index_data,
            )?)
        };
        let mut inspect = InspectGpu {
            pipelines: Vec::new(),
            layout: vk::PipelineLayout::null(),
            edge_indices,
            ranges,
            normal_length: NORMAL_LENGTH_FRACTION * diagonal,
            shared: gpu.shared.clone(),
        };
        // Stored at once, so Drop destroys it on a later error.
        inspect.layout = pipeline_layout(
            gpu,
            &[layouts.scene_set],
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            24,
        )?;
        let vert = shaders::create_module(gpu, shaders::INSPECT_VERT)?;
        let frag = match shaders::create_module(gpu, shaders::INSPECT_FRAG) {
            Ok(f) => f,
            Err(e) => {
                // SAFETY: unused module of this device.
                unsafe { gpu.device().destroy_shader_module(vert, None) };
                return Err(e.into());
            }
        };
        let mut result = Ok(());
        for set in pass_sets {
            let pair = line_pipeline(gpu, inspect.layout, set, vert, frag, false).and_then(|e| {
                match line_pipeline(gpu, inspect.layout, set, vert, frag, true) {
                    Ok(n) => Ok(Pipelines {
                        edges: e,
                        normals: n,
                    }),
                    Err(err) => {
                        // SAFETY: just created, never used.
                        unsafe { gpu.device().destroy_pipeline(e, None) };
                        Err(err)
                    }
                }
            });
            match pair {
                Ok(p) => inspect.pipelines.push(p),
                Err(e) => {
                    result = Err(e);
                    break;
                }
            }
        }
        // SAFETY: the pipelines that use the modules exist (or failed); modules
        // may be destroyed after pipeline creation.
        unsafe {
            gpu.device().destroy_shader_module(vert, None);
            gpu.device().destroy_shader_module(frag, None);
        }
        result?;
        Ok(inspect)
    }

    /// Records the inspection lines into the scene subpass of pass set
    /// `set_index` (the scene's vertex buffer is bound; `frame_set` holds the
    /// per-frame uniforms).
    ///
    /// # Safety
    ///
    /// `cmd` is recording inside the scene subpass of pass set `set_index`,
    /// and `vertices` is the scene's vertex buffer with its vertex count (the
    /// buffer the edge indices were built against).
    #[allow(clippy::too_many_arguments)]
    pub(super) unsafe fn record(
        &self,
        device: &ash::Device,
        cmd: vk::CommandBuffer,
        set_index: usize,
        frame_set: vk::DescriptorSet,
        mode: Inspect,
        tone: ToneSettings,
        radiance_scale: f32,
        vertices: (&Buffer, u64),
    ) {
        let Some(pipelines) = self.pipelines.get(set_index) else {
            return;
        };
        if mode.edges != Edges::Off {
            if let Some(indices) = &self.edge_indices {
                let color = linear_for_display(EDGE_COLOR, tone, radiance_scale);
                // SAFETY: the caller guarantees the subpass these pipelines were
                // made for; every handle is live.
                unsafe {
                    self.bind_lines(
                        device,
                        cmd,
                        pipelines.edges,
                        frame_set,
                        &push_bytes(color, 0.0),
                    );
                    device.cmd_bind_vertex_buffers(cmd, 0, &[vertices.0.raw], &[0]);
                    device.cmd_bind_index_buffer(cmd, indices.raw, 0, vk::IndexType::UINT32);
                }
                for r in self.ranges.iter().filter(|r| r.count > 0) {
                    // SAFETY: the edge indices and their ranges were built from
                    // the uploaded batches' own indices, so every index names a
                    // vertex of the buffer the caller bound.
                    unsafe {
                        device.cmd_draw_indexed(cmd, r.count, 1, r.first, r.vertex_base as i32, 0)
                    };
                }
            }
        }
        let vertex_count = u32::try_from(vertices.1).unwrap_or(u32::MAX);
        if mode.normals && vertex_count > 0 {
            let color = linear_for_display(NORMAL_COLOR, tone, radiance_scale);
            let push = push_bytes(color, self.normal_length.max(f32::MIN_POSITIVE));
            // SAFETY: as above; one instance per vertex of the buffer the caller
            // names with its vertex count.
            unsafe {
                self.bind_lines(device, cmd, pipelines.normals, frame_set, &push);
                device.cmd_bind_vertex_buffers(cmd, 0, &[vertices.0.raw], &[0]);
                device.cmd_draw(cmd, 2, vertex_count, 0, 0);
            }
        }
    }

    /// Binds a line pipeline with the frame's uniforms and its push constants.
    ///
    /// # Safety
    ///
    /// `cmd` is recording inside the subpass `pipeline` was made for, and
    /// `frame_set` is live.
    unsafe fn bind_lines(
        &self,
        device: &ash::Device,
        cmd: vk::CommandBuffer,
        pipeline: vk::Pipeline,
        frame_set: vk::DescriptorSet,
        push: &[u8],
    ) {
        // SAFETY: the caller guarantees the subpass and the set; the layout is
        // this object's and the push constants match its range.
        unsafe {
            device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline);
            device.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                self.layout,
                0,
                &[frame_set],
                &[],
            );
            device.cmd_push_constants(
                cmd,
                self.layout,
                vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
                0,
                push,
            );
        }
    }
}

/// A `LINE_LIST` pipeline in the scene subpass of `set`: per-vertex attributes
/// for edges, per-instance for normals (two vertices per mesh vertex).
fn line_pipeline(
    gpu: &Gpu,
    layout: vk::PipelineLayout,
    set: &PassSet,
    vert: vk::ShaderModule,
    frag: vk::ShaderModule,
    per_instance: bool,
) -> Result<vk::Pipeline, GpuError> {
    // solution::format::Vertex: position at 0, normal at 12.
    let (bindings, attributes) = passes::vertex_layout::<2>(if per_instance {
        vk::VertexInputRate::INSTANCE
    } else {
        vk::VertexInputRate::VERTEX
    });
    GraphicsPipeline {
        bindings: &bindings,
        attributes: &attributes,
        topology: vk::PrimitiveTopology::LINE_LIST,
        samples: set.desc.samples,
        depth_compare: Some(vk::CompareOp::LESS_OR_EQUAL),
        ..GraphicsPipeline::new(set.render_pass, 0, layout, vert, frag)
    }
    .build(gpu)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::ToneCurve;

    #[test]
    fn shared_edges_are_drawn_once() {
        // Two triangles of a quad share the diagonal 0–2: 5 edges, not 6.
        let edges = unique_edges(&[0, 1, 2, 0, 2, 3]);
        assert_eq!(edges, vec![[0, 1], [0, 2], [0, 3], [1, 2], [2, 3]]);
        // A degenerate triangle's zero-length edge is dropped.
        assert_eq!(unique_edges(&[4, 4, 5]), vec![[4, 5]]);
        assert!(unique_edges(&[1, 2]).is_empty());
    }

    #[test]
    fn line_colours_tone_map_back_to_their_display_values() {
        for curve in [ToneCurve::Clamp, ToneCurve::Reinhard, ToneCurve::Aces] {
            for stops in [-3.0f32, 0.0, 2.5] {
                let tone = ToneSettings {
                    exposure_stops: stops,
                    curve,
                };
                let scale = 0.25;
                let v = linear_for_display([0.1, 0.5, 0.9], tone, scale);
                for (c, want) in [0.1f32, 0.5, 0.9].iter().enumerate() {
                    // What tonemap.frag does: curve(value × 2^stops / scale).
                    let shown = tone.display_value(v[c] / scale);
                    // 40 bisection steps: far below the 8-bit step of 1/255.
                    assert!((shown - want).abs() < 1e-4, "{curve:?} {stops}: {shown}");
                }
            }
        }
    }
}
