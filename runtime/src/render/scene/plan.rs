//! The batch description of an upload: where each batch goes in the scene's
//! GPU buffers, in draw order, and the scene's one coefficient storage type.

use super::{CoefficientStorage, DrawBatch, DrawKind, SceneError, TexturedDraw};
use ash::vk;
use solution::format::{layout, BatchTexture, Representation, ScalarType};

pub(super) fn align(value: u64, alignment: u64) -> u64 {
    let a = alignment.max(4);
    value.div_ceil(a) * a
}

/// What the upload needs to know of a batch, from the file's tables or from an
/// in-memory batch.
#[derive(Clone, Copy, Debug)]
pub(super) struct BatchShape {
    pub(super) representation: Representation,
    pub(super) scalar: ScalarType,
    pub(super) vertex_count: u64,
    pub(super) index_count: u64,
    pub(super) texture: Option<BatchTexture>,
}

impl BatchShape {
    pub(super) fn coefficient_bytes(&self) -> u64 {
        let size = match self.scalar {
            ScalarType::F32 => 4,
            ScalarType::F16 { .. } => 2,
        };
        self.vertex_count * self.representation.coefficients_per_channel() * 3 * size
    }
}

/// Where each batch goes in the three GPU buffers, in draw order.
pub(super) struct Plan {
    /// `(batch index, draw)`, draw order; the draw's `index_count` is 0 for a
    /// batch without triangles (its data is still uploaded).
    pub(super) batches: Vec<(usize, DrawBatch)>,
    pub(super) storage: CoefficientStorage,
    pub(super) vertex_total: u64,
    pub(super) index_total: u64,
    pub(super) coefficient_total: u64,
    /// Bytes of the textured-vertex buffer.
    pub(super) textured_total: u64,
}

impl Plan {
    /// The scene this plan describes, once its buffers and textures are
    /// uploaded: the one place both uploads (in memory and streamed from a
    /// mapped file) assemble a [`super::GpuScene`]. `bound` is the brightest
    /// radiance any vertex can produce.
    pub(super) fn into_scene(
        self,
        buffers: super::SceneBuffers,
        textures: super::SceneTextures,
        bound: f64,
    ) -> super::GpuScene {
        super::GpuScene {
            coefficients: buffers.coefficients,
            indices: buffers.indices,
            vertices: buffers.vertices,
            draws: self.draws(),
            radiance_scale: super::radiance_scale(bound),
            storage: self.storage,
            vertex_count: self.vertex_total,
            triangle_count: self.index_total / 3,
            textured: buffers.textured,
            textures,
        }
    }

    pub(super) fn new(
        shapes: &[BatchShape],
        max_order: Option<u32>,
        limits: &vk::PhysicalDeviceLimits,
    ) -> Result<Plan, SceneError> {
        let storage = scene_storage(shapes)?;
        let mut order_of = Vec::with_capacity(shapes.len());
        for (i, shape) in shapes.iter().enumerate() {
            let (kind, order) = match shape.representation {
                Representation::Sh { order } => (DrawKind::Sh, order),
                Representation::Cube { directions } => {
                    match solution::cube::resolution_from_directions(directions) {
                        Some(resolution) => (DrawKind::Cube { resolution }, 0),
                        None => {
                            return Err(SceneError::Representation {
                                batch: i,
                                representation: shape.representation,
                            })
                        }
                    }
                }
            };
            order_of.push((kind, shape.texture.is_some(), order, i));
        }
        // Diffuse first, then SH by order, then textured SH, then cubes by
        // resolution: one switch per pipeline, and draws of one loop bound
        // together.
        order_of.sort();
        let mut batches = Vec::with_capacity(shapes.len());
        let (mut vertex_base, mut first_index, mut coefficient_end) = (0u64, 0u64, 0u64);
        let mut textured_end = 0u64;
        for (kind, _, file_order, i) in order_of {
            let shape = &shapes[i];
            let offset = align(coefficient_end, limits.min_storage_buffer_offset_alignment);
            let bytes = shape.coefficient_bytes();
            if bytes > u64::from(limits.max_storage_buffer_range) {
                return Err(SceneError::TooLarge {
                    batch: i,
                    bytes,
                    limit: u64::from(limits.max_storage_buffer_range),
                });
            }
            let too_big = |what: &str| SceneError::Inconsistent {
                batch: i,
                what: format!("{what} exceeds the 32-bit range of a draw"),
            };
            let u32_of = |value: u64, what: &str| u32::try_from(value).map_err(|_| too_big(what));
            let draw = DrawBatch {
                source: i,
                kind,
                file_order,
                order: max_order.map_or(file_order, |m| m.min(file_order)),
                first_index: u32_of(first_index, "index count")?,
                index_count: u32_of(shape.index_count, "index count")?,
                vertex_base: u32_of(vertex_base, "vertex count")?,
                vertex_count: u32_of(shape.vertex_count, "vertex count")?,
                coeff_offset: offset,
                // f16 is read in 32-bit words: round up to whole words.
                coeff_bytes: align(bytes, 4).max(4),
                stride: u32_of(
                    shape.representation.coefficients_per_channel() * 3,
                    "stride",
                )?,
                storage_scale: match shape.scalar {
                    ScalarType::F32 => 1.0,
                    ScalarType::F16 { scale } => scale,
                },
                chunks: Vec::new(),
                texture: shape.texture.map(|t| {
                    let offset = align(textured_end, limits.min_storage_buffer_offset_alignment);
                    let bytes = shape.vertex_count * layout::TEXTURED_VERTEX_LEN as u64;
                    textured_end = offset + bytes;
                    TexturedDraw {
                        texture: t.texture,
                        factor: t.factor,
                        emission: t.emission,
                        offset,
                        bytes: bytes.max(4),
                    }
                }),
            };
            coefficient_end = offset + bytes;
            vertex_base += shape.vertex_count;
            first_index += shape.index_count;
            batches.push((i, draw));
        }
        Ok(Plan {
            batches,
            storage,
            vertex_total: vertex_base,
            index_total: first_index,
            coefficient_total: align(coefficient_end, 4),
            textured_total: align(textured_end, 4),
        })
    }

    pub(super) fn draws(&self) -> Vec<DrawBatch> {
        self.batches
            .iter()
            .filter(|(_, d)| d.index_count > 0)
            .map(|(_, d)| d.clone())
            .collect()
    }
}

/// The one storage type of a scene's batches.
pub(super) fn scene_storage(shapes: &[BatchShape]) -> Result<CoefficientStorage, SceneError> {
    let find = |storage| {
        shapes
            .iter()
            .position(|s| CoefficientStorage::of(s.scalar) == storage)
    };
    match (find(CoefficientStorage::F32), find(CoefficientStorage::F16)) {
        (Some(f32_batch), Some(f16_batch)) => Err(SceneError::MixedStorage {
            f32_batch,
            f16_batch,
        }),
        (None, Some(_)) => Ok(CoefficientStorage::F16),
        _ => Ok(CoefficientStorage::F32),
    }
}
