//! The solution's vertex, index and coefficient data on the GPU, and the draw list
//! (SH batches sorted by order, so diffuse batches share one trivial pipeline,
//! then 001's global-cube batches by resolution, drawn by `scene_cube.vert`).

use super::cull::Chunk;
use super::textures::SceneTextures;
use crate::gpu::{Buffer, Gpu, GpuError};
use ash::vk;
use solution::format::{
    layout, Batch, BatchTexture, FormatError, Representation, ScalarType, Solution, Vertex,
};

mod bound;
mod chunks;
mod mapped;
mod plan;
mod staging;

pub use bound::radiance_bound;
pub use mapped::UploadStats;

use bound::textured_bound;
use chunks::chunked_indices;
use plan::{BatchShape, Plan};

/// How a scene's coefficients are stored in the GPU's storage buffer: as the
/// file stores them (the shaders read either; f16 with the batch's scale as a
/// push constant). In-memory solutions use their batches' [`ScalarType`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum CoefficientStorage {
    #[default]
    F32,
    /// IEEE half, two per 32-bit word, with a per-batch scale.
    F16,
}

impl CoefficientStorage {
    pub fn of(scalar: ScalarType) -> CoefficientStorage {
        match scalar {
            ScalarType::F32 => CoefficientStorage::F32,
            ScalarType::F16 { .. } => CoefficientStorage::F16,
        }
    }
}

/// The staging buffer of the mapped upload: sections pass through it in chunks
/// of at most half this many bytes (two halves, so that filling one overlaps
/// the device's copy out of the other), so the upload's host memory is bounded
/// whatever the file's size (a larger buffer saves little: one submit per
/// 32 MiB).
pub const STAGING_BYTES: u64 = 64 << 20;

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
    #[error(
        "batch {f16_batch} stores f16 coefficients and batch {f32_batch} f32; this renderer \
         draws one storage type per scene (write the file with one scalar type)"
    )]
    MixedStorage { f32_batch: usize, f16_batch: usize },
    /// A section's checksum failed while it was streamed to the GPU.
    #[error(transparent)]
    File(#[from] FormatError),
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
    /// The batch's spatial chunks ([`super::cull`]), covering its triangles in
    /// the order of the uploaded (reordered) index buffer; triangle numbers
    /// count from `first_index / 3`.
    pub chunks: Vec<Chunk>,
    /// A textured batch's texture, factor and UV + E/π range.
    pub texture: Option<TexturedDraw>,
}

/// How a textured batch (solution format 2) is drawn: `scene_textured.frag`
/// adds `factor ⊙ ρ(uv) ⊙ E/π` to the SH term, and `Ke ⊙ ρ_e(uv)` when the
/// batch has format 3's emission slot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexturedDraw {
    /// Index into the scene's textures.
    pub texture: u32,
    /// Linear RGB multiplier of the texture (MTL's Kd).
    pub factor: [f32; 3],
    /// The emission texture and its factor Ke (format 3), if any.
    pub emission: Option<solution::format::TextureSlot>,
    /// Byte offset and size of the batch's UV + E/π in [`GpuScene::textured`].
    pub offset: u64,
    pub bytes: u64,
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

/// The four buffers an upload fills, before they become a [`GpuScene`].
struct SceneBuffers {
    coefficients: Buffer,
    indices: Buffer,
    vertices: Buffer,
    textured: Buffer,
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
    /// The file's storage type (every batch has the same).
    pub storage: CoefficientStorage,
    pub vertex_count: u64,
    pub triangle_count: u64,
    /// Per vertex of the textured batches, u, v and E/π (20 bytes, as stored).
    pub textured: Buffer,
    /// Their textures, decoded and with their mip chains.
    pub textures: SceneTextures,
}

impl GpuScene {
    /// Whether any batch is drawn textured (the renderer then makes the
    /// textured pipeline).
    pub fn is_textured(&self) -> bool {
        self.draws.iter().any(|d| d.texture.is_some())
    }
}

fn vertex_bytes(vertices: &[Vertex], out: &mut Vec<u8>) {
    for v in vertices {
        for f in v.position.iter().chain(&v.normal).chain(&v.tangent) {
            out.extend_from_slice(&f.to_le_bytes());
        }
    }
}

fn radiance_scale(bound: f64) -> f32 {
    if bound > 0.0 && bound.is_finite() {
        (1.0 / bound) as f32
    } else {
        1.0
    }
}

impl GpuScene {
    /// Uploads an in-memory `solution`, storing coefficients as its batches'
    /// scalar types say (f16 batches are rounded to half here, divided by their
    /// scale). `max_order` caps the evaluated SH order (bands above it are not
    /// read; see `crate::render::truncation`); cube batches ignore it.
    ///
    /// Batches are partitioned into chunks of at most `chunk_triangles` for
    /// culling, as [`GpuScene::from_mapped_with`] does.
    pub fn new(
        gpu: &Gpu,
        solution: &Solution,
        max_order: Option<u32>,
        chunk_triangles: u32,
    ) -> Result<GpuScene, SceneError> {
        let mut shapes = Vec::with_capacity(solution.batches.len());
        for (i, batch) in solution.batches.iter().enumerate() {
            check_in_memory(i, batch)?;
            shapes.push(BatchShape {
                representation: batch.representation,
                scalar: batch.scalar,
                vertex_count: batch.vertices.len() as u64,
                index_count: batch.indices.len() as u64,
                texture: batch.texturing.as_ref().map(|t| BatchTexture {
                    texture: t.texture,
                    factor: t.factor,
                    emission: t.emission,
                }),
            });
        }
        for (i, batch) in solution.batches.iter().enumerate() {
            if let Some(t) = &batch.texturing {
                check_texturing(i, batch, t, solution.textures.len())?;
            }
        }
        let mut plan = Plan::new(&shapes, max_order, &gpu.info.limits)?;
        let mut vertex_data = Vec::new();
        let mut index_data = Vec::new();
        let mut coeff_data: Vec<u8> = Vec::new();
        let mut textured_data: Vec<u8> = Vec::new();
        let mut bound = 0.0f64;
        for (i, draw) in &mut plan.batches {
            let batch = &solution.batches[*i];
            let mut batch_bound = radiance_bound(batch, draw.order);
            if let (Some(t), Some(texturing)) = (&draw.texture, &batch.texturing) {
                textured_data.resize(t.offset as usize, 0);
                for v in &texturing.vertices {
                    for x in v.uv.iter().chain(&v.irradiance_over_pi) {
                        textured_data.extend_from_slice(&x.to_le_bytes());
                    }
                }
                batch_bound += textured_bound(&textured_data[t.offset as usize..], t.factor);
            }
            bound = bound.max(batch_bound);
            coeff_data.resize(draw.coeff_offset as usize, 0);
            match batch.scalar {
                ScalarType::F32 => {
                    for c in &batch.coefficients {
                        coeff_data.extend_from_slice(&c.to_le_bytes());
                    }
                }
                ScalarType::F16 { scale } => {
                    for c in &batch.coefficients {
                        let h = half::f16::from_f32(c / scale);
                        coeff_data.extend_from_slice(&h.to_bits().to_le_bytes());
                    }
                }
            }
            let mut stored_vertices = Vec::with_capacity(batch.vertices.len() * layout::VERTEX_LEN);
            vertex_bytes(&batch.vertices, &mut stored_vertices);
            let stored_indices: Vec<u8> = batch
                .indices
                .iter()
                .flat_map(|ix| ix.to_le_bytes())
                .collect();
            let (reordered, chunks) =
                chunked_indices(&stored_vertices, &stored_indices, chunk_triangles);
            draw.chunks = chunks;
            vertex_data.extend_from_slice(&stored_vertices);
            index_data.extend_from_slice(&reordered);
        }
        coeff_data.resize(plan.coefficient_total.max(4) as usize, 0);
        let vertices = Buffer::with_data(gpu, vk::BufferUsageFlags::VERTEX_BUFFER, &vertex_data)?;
        let indices = Buffer::with_data(gpu, vk::BufferUsageFlags::INDEX_BUFFER, &index_data)?;
        let coefficients =
            Buffer::with_data(gpu, vk::BufferUsageFlags::STORAGE_BUFFER, &coeff_data)?;
        textured_data.resize(plan.textured_total.max(4) as usize, 0);
        let textured =
            Buffer::with_data(gpu, vk::BufferUsageFlags::STORAGE_BUFFER, &textured_data)?;
        let textures = SceneTextures::new(gpu, solution.textures.len(), |k| {
            Ok::<_, SceneError>(solution.textures[k].clone())
        })?;
        let buffers = SceneBuffers {
            coefficients,
            indices,
            vertices,
            textured,
        };
        Ok(plan.into_scene(buffers, textures, bound))
    }
}

/// What `MappedSolution` checks of a textured batch at open, for a solution
/// built in memory: a texture that exists, one UV + E/π per vertex, and an SH
/// representation (the textured pipeline evaluates SH).
fn check_texturing(
    i: usize,
    batch: &Batch,
    t: &solution::format::Texturing,
    textures: usize,
) -> Result<(), SceneError> {
    let emission = t.emission.map(|e| e.texture);
    let what = if t.texture as usize >= textures {
        format!("texture {} but the solution has {textures}", t.texture)
    } else if let Some(e) = emission.filter(|&e| e as usize >= textures) {
        format!("emission texture {e} but the solution has {textures}")
    } else if t.vertices.len() != batch.vertices.len() {
        format!(
            "{} textured vertices for {} vertices",
            t.vertices.len(),
            batch.vertices.len()
        )
    } else if !matches!(batch.representation, Representation::Sh { .. }) {
        "a textured batch must store spherical harmonics".to_string()
    } else {
        return Ok(());
    };
    Err(SceneError::Inconsistent { batch: i, what })
}

/// The checks `MappedSolution` makes at open, for a solution built in memory:
/// coefficient counts, whole triangles, indices in range.
fn check_in_memory(i: usize, batch: &Batch) -> Result<(), SceneError> {
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
    Ok(())
}
