//! The solution's vertex, index and coefficient data on the GPU, and the draw list
//! (SH batches sorted by order, so diffuse batches share one trivial pipeline,
//! then 001's global-cube batches by resolution, drawn by `scene_cube.vert`).

use crate::gpu::{Buffer, Gpu, GpuError};
use ash::vk;
use solution::format::{Batch, Representation, Solution, Vertex};

/// How SH coefficients are stored in the GPU's storage buffer.
///
/// Measured (docs/benchmarks.md, "Runtime"): f16 halves the buffer and is within
/// a few 1e-4 relative of f32 radiance; f32 is the default because on lavapipe the
/// two cost the same per frame and f32 matches the solver's f32 evaluation to the
/// tolerance `solution::sh::f32_basis_tolerance` states.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum CoefficientStorage {
    #[default]
    F32,
    /// IEEE half, two per 32-bit word, with a per-batch scale.
    F16,
}

/// Why a solution cannot be drawn.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error(
        "batch {batch}: representation {representation:?} is not drawn by this renderer \
         (spherical harmonics and global cubes of 6·k² directions, 1 ≤ k ≤ {max}, are)",
        max = solution::cube::MAX_RESOLUTION
    )]
    Representation {
        batch: usize,
        representation: Representation,
    },
    #[error("batch {batch}: {what}")]
    Inconsistent { batch: usize, what: String },
    #[error(
        "batch {batch}: {bytes} bytes of coefficients exceed this device's storage-buffer \
         range of {limit} bytes; split the batch or lower its order (--max-order)"
    )]
    TooLarge {
        batch: usize,
        bytes: u64,
        limit: u64,
    },
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// Which vertex shader draws a batch.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum DrawKind {
    /// Spherical harmonics: `scene_l0.vert` at order 0, else `scene_sh.vert`.
    Sh,
    /// 001's global cube with `resolution` (k) cells along a face edge:
    /// `scene_cube.vert`, the bilinear lookup of `solution::cube::bilinear_f32`.
    Cube { resolution: u32 },
}

/// One batch as drawn.
#[derive(Clone, Debug)]
pub struct DrawBatch {
    /// Index of the batch in the solution file.
    pub source: usize,
    pub kind: DrawKind,
    /// The file's SH order (0 for cube batches).
    pub file_order: u32,
    /// The order evaluated: `min(file_order, max_order)` (0 for cube batches,
    /// which a cap leaves alone: a lookup reads four cells whatever D is).
    pub order: u32,
    pub first_index: u32,
    pub index_count: u32,
    /// First vertex of the batch in the shared vertex buffer.
    pub vertex_base: u32,
    pub vertex_count: u32,
    /// Byte offset and size of the batch's coefficients in the storage buffer.
    pub coeff_offset: u64,
    pub coeff_bytes: u64,
    /// Scalars per vertex, `(file_order + 1)² · 3`, or `D · 3` for a cube.
    pub stride: u32,
    /// Multiplies stored values to get radiance (the f16 scale; 1 for f32).
    pub storage_scale: f32,
}

impl DrawBatch {
    /// The push constant `order` of the batch's shader: the evaluated SH order,
    /// or for a cube its resolution k (`scene_cube.vert`).
    pub fn loop_parameter(&self) -> u32 {
        match self.kind {
            DrawKind::Sh => self.order,
            DrawKind::Cube { resolution } => resolution,
        }
    }
}

/// The GPU copy of a solution.
pub struct GpuScene {
    // Newest first.
    pub coefficients: Buffer,
    pub indices: Buffer,
    pub vertices: Buffer,
    /// Diffuse batches first, then glossy SH by increasing order, then cubes by
    /// increasing resolution.
    pub draws: Vec<DrawBatch>,
    /// Multiplies radiance before it is written to the half-float colour target,
    /// so that the brightest radiance any vertex can produce is at most 1 (see
    /// [`radiance_bound`]). The read-back and the tone map divide it out again.
    pub radiance_scale: f32,
    pub storage: CoefficientStorage,
    pub vertex_count: u64,
    pub triangle_count: u64,
}

/// An upper bound of the radiance a batch's vertices can produce in any
/// direction: for SH `max_v Σ_k |c_vk| · envelope(l_k)`, with `|Y_lm| ≤
/// envelope(l) = √((2l+1)/(4π))` (Unsöld), only the evaluated orders counting;
/// for a cube the largest |value|, since the bilinear weights are non-negative
/// and sum to 1 (`solution::cube::bilinear`).
pub fn radiance_bound(batch: &Batch, order: u32) -> f64 {
    if let Representation::Cube { .. } = batch.representation {
        return batch
            .coefficients
            .iter()
            .fold(0.0f64, |m, &c| m.max(f64::from(c).abs()));
    }
    let n = batch.representation.coefficients_per_channel() as usize;
    let count = (order as usize + 1).pow(2).min(n);
    let envelope: Vec<f64> = (0..count)
        .map(|k| solution::sh::envelope((k as f64).sqrt().floor() as u32))
        .collect();
    let mut bound = 0.0f64;
    for v in 0..batch.vertices.len() {
        for c in 0..3 {
            let mut sum = 0.0;
            for (k, e) in envelope.iter().enumerate() {
                let value = batch
                    .coefficients
                    .get((v * n + k) * 3 + c)
                    .copied()
                    .unwrap_or(0.0);
                sum += f64::from(value).abs() * e;
            }
            bound = bound.max(sum);
        }
    }
    bound
}

fn vertex_bytes(vertices: &[Vertex], out: &mut Vec<u8>) {
    for v in vertices {
        for f in v.position.iter().chain(&v.normal).chain(&v.tangent) {
            out.extend_from_slice(&f.to_le_bytes());
        }
    }
}

fn align(value: u64, alignment: u64) -> u64 {
    let a = alignment.max(4);
    value.div_ceil(a) * a
}

impl GpuScene {
    /// Uploads `solution`. `max_order` caps the evaluated SH order (bands above it
    /// are not read; see `crate::render::truncation`); cube batches ignore it.
    pub fn new(
        gpu: &Gpu,
        solution: &Solution,
        storage: CoefficientStorage,
        max_order: Option<u32>,
    ) -> Result<GpuScene, SceneError> {
        let limits = &gpu.info.limits;
        let mut order_of = Vec::new();
        for (i, batch) in solution.batches.iter().enumerate() {
            let (kind, order) = match batch.representation {
                Representation::Sh { order } => (DrawKind::Sh, order),
                Representation::Cube { directions } => {
                    match solution::cube::resolution_from_directions(directions) {
                        Some(resolution) => (DrawKind::Cube { resolution }, 0),
                        None => {
                            return Err(SceneError::Representation {
                                batch: i,
                                representation: batch.representation,
                            })
                        }
                    }
                }
            };
            let n = batch.representation.coefficients_per_channel();
            let expected = (batch.vertices.len() as u64)
                .saturating_mul(n)
                .saturating_mul(3);
            if batch.coefficients.len() as u64 != expected {
                return Err(SceneError::Inconsistent {
                    batch: i,
                    what: format!(
                        "{} coefficients for {} vertices of {:?} (expected {expected})",
                        batch.coefficients.len(),
                        batch.vertices.len(),
                        batch.representation
                    ),
                });
            }
            if !batch.indices.len().is_multiple_of(3) {
                return Err(SceneError::Inconsistent {
                    batch: i,
                    what: format!(
                        "{} indices is not a whole number of triangles",
                        batch.indices.len()
                    ),
                });
            }
            if let Some(&bad) = batch
                .indices
                .iter()
                .find(|&&ix| ix as usize >= batch.vertices.len())
            {
                return Err(SceneError::Inconsistent {
                    batch: i,
                    what: format!(
                        "index {bad} is out of range for {} vertices",
                        batch.vertices.len()
                    ),
                });
            }
            order_of.push((kind, order, i));
        }
        // Diffuse first, then SH by order, then cubes by resolution: one switch
        // per pipeline, and draws of one loop bound together.
        order_of.sort();

        let mut vertex_data = Vec::new();
        let mut index_data = Vec::new();
        let mut coeff_data: Vec<u8> = Vec::new();
        let mut draws = Vec::new();
        let mut bound = 0.0f64;
        let mut vertex_base = 0u64;
        let mut first_index = 0u64;
        for &(kind, file_order, i) in &order_of {
            let batch = &solution.batches[i];
            let order = max_order.map_or(file_order, |m| m.min(file_order));
            bound = bound.max(radiance_bound(batch, order));
            let stride = batch.representation.coefficients_per_channel() * 3;
            let offset = align(
                coeff_data.len() as u64,
                limits.min_storage_buffer_offset_alignment,
            );
            coeff_data.resize(offset as usize, 0);
            let storage_scale = match storage {
                CoefficientStorage::F32 => {
                    for c in &batch.coefficients {
                        coeff_data.extend_from_slice(&c.to_le_bytes());
                    }
                    1.0
                }
                CoefficientStorage::F16 => {
                    // Scale so the largest magnitude is 1024: far below the half
                    // maximum (65504), and values down to 6e-8 of it stay normal.
                    let max = batch
                        .coefficients
                        .iter()
                        .fold(0.0f32, |m, c| m.max(c.abs()));
                    let scale = if max > 0.0 && max.is_finite() {
                        max / 1024.0
                    } else {
                        1.0
                    };
                    for c in &batch.coefficients {
                        let h = half::f16::from_f32(c / scale);
                        coeff_data.extend_from_slice(&h.to_bits().to_le_bytes());
                    }
                    if !batch.coefficients.len().is_multiple_of(2) {
                        coeff_data.extend_from_slice(&[0, 0]);
                    }
                    scale
                }
            };
            let bytes = coeff_data.len() as u64 - offset;
            if bytes > u64::from(limits.max_storage_buffer_range) {
                return Err(SceneError::TooLarge {
                    batch: i,
                    bytes,
                    limit: u64::from(limits.max_storage_buffer_range),
                });
            }
            vertex_bytes(&batch.vertices, &mut vertex_data);
            for ix in &batch.indices {
                index_data.extend_from_slice(&ix.to_le_bytes());
            }
            let too_big = |what: &str| SceneError::Inconsistent {
                batch: i,
                what: format!("{what} exceeds the 32-bit range of a draw"),
            };
            if !batch.indices.is_empty() {
                draws.push(DrawBatch {
                    source: i,
                    kind,
                    file_order,
                    order,
                    first_index: u32::try_from(first_index).map_err(|_| too_big("index count"))?,
                    index_count: u32::try_from(batch.indices.len())
                        .map_err(|_| too_big("index count"))?,
                    vertex_base: u32::try_from(vertex_base).map_err(|_| too_big("vertex count"))?,
                    vertex_count: batch.vertices.len() as u32,
                    coeff_offset: offset,
                    coeff_bytes: bytes.max(4),
                    stride: stride as u32,
                    storage_scale,
                });
            }
            vertex_base += batch.vertices.len() as u64;
            first_index += batch.indices.len() as u64;
        }
        let radiance_scale = if bound > 0.0 && bound.is_finite() {
            (1.0 / bound) as f32
        } else {
            1.0
        };
        let vertices = Buffer::with_data(gpu, vk::BufferUsageFlags::VERTEX_BUFFER, &vertex_data)?;
        let indices = Buffer::with_data(gpu, vk::BufferUsageFlags::INDEX_BUFFER, &index_data)?;
        let coefficients =
            Buffer::with_data(gpu, vk::BufferUsageFlags::STORAGE_BUFFER, &coeff_data)?;
        Ok(GpuScene {
            coefficients,
            indices,
            vertices,
            draws,
            radiance_scale,
            storage,
            vertex_count: vertex_base,
            triangle_count: first_index / 3,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use solution::format::ScalarType;

    #[test]
    fn cube_radiance_bound_is_the_largest_value_and_bounds_every_lookup() {
        // k = 3, two vertices with values of both signs.
        let directions = 54u32;
        let coefficients: Vec<f32> = (0..2 * directions as usize * 3)
            .map(|i| ((i * 29 % 17) as f32 - 8.0) * 0.25)
            .collect();
        let largest = coefficients.iter().fold(0.0f32, |m, c| m.max(c.abs()));
        let batch = Batch {
            representation: Representation::Cube { directions },
            scalar: ScalarType::F32,
            vertices: vec![Vertex::default(); 2],
            coefficients,
            indices: vec![],
        };
        let bound = radiance_bound(&batch, 0);
        assert_eq!(bound, f64::from(largest));
        // The bilinear weights are convex, so no lookup exceeds it (checked on a
        // grid of directions over the sphere, every face and edge).
        let n = batch.representation.coefficients_per_channel() as usize * 3;
        for values in batch.coefficients.chunks_exact(n) {
            for a in 0..24 {
                for b in 0..12 {
                    let (phi, theta) = (a as f64 * 0.2618, b as f64 * 0.2618 + 0.1);
                    let dir = glam::DVec3::new(
                        theta.sin() * phi.cos(),
                        theta.sin() * phi.sin(),
                        theta.cos(),
                    );
                    for c in solution::cube::eval_rgb(3, values, dir) {
                        assert!(c.abs() <= bound * (1.0 + 1e-12), "{c} > {bound}");
                    }
                }
            }
        }
    }
}
