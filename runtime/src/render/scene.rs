//! The solution's vertex, index and coefficient data on the GPU, and the draw list
//! (SH batches sorted by order, so diffuse batches share one trivial pipeline,
//! then 001's global-cube batches by resolution, drawn by `scene_cube.vert`).

use super::cull::{partition, Chunk, DEFAULT_CHUNK_TRIANGLES};
use super::textures::SceneTextures;
use crate::gpu::{Buffer, BufferDesc, Fence, Gpu, GpuError, MemoryLocation, VkContext};
use ash::vk;
use glam::DVec3;
use solution::format::{
    layout, Batch, BatchSection, BatchTexture, FormatError, MappedSolution, Representation,
    ScalarType, Solution, Vertex,
};

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

/// The piece of a section that the upload checksums, bounds and copies before
/// moving on: small enough to stay in the L2 cache between the three.
const PASS_BYTES: u64 = 256 << 10;

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

/// The largest of `factor_c · E_c / π` over a textured batch's stored vertices
/// (20-byte u, v, E/π records): with ρ ≤ 1 the most its textured term can add
/// to a pixel.
fn textured_bound(bytes: &[u8], factor: [f32; 3]) -> f64 {
    bytes
        .chunks_exact(layout::TEXTURED_VERTEX_LEN)
        .flat_map(|v| {
            (0..3).map(move |c| {
                let at = 8 + 4 * c;
                f64::from(f32::from_le_bytes([v[at], v[at + 1], v[at + 2], v[at + 3]]))
                    * f64::from(factor[c])
            })
        })
        .fold(0.0f64, f64::max)
}

/// `|Y_lm| ≤ envelope(l) = √((2l+1)/(4π))` (Unsöld) for the first `count`
/// coefficients, index `l² + l + m`.
fn envelopes(count: usize) -> Vec<f64> {
    (0..count)
        .map(|k| solution::sh::envelope((k as f64).sqrt().floor() as u32))
        .collect()
}

/// The SH bound of [`radiance_bound`] over vertices whose `n · 3` coefficients
/// `value(v, i)` returns, only the first `envelope.len()` per channel counting.
fn sh_bound(vertex_count: usize, n: usize, envelope: &[f64], value: impl Fn(usize) -> f32) -> f64 {
    let mut bound = 0.0f64;
    for v in 0..vertex_count {
        let mut sum = [0.0f64; 3];
        for (k, e) in envelope.iter().enumerate() {
            for (c, s) in sum.iter_mut().enumerate() {
                *s += f64::from(value((v * n + k) * 3 + c)).abs() * e;
            }
        }
        bound = sum.into_iter().fold(bound, f64::max);
    }
    bound
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
    sh_bound(batch.vertices.len(), n, &envelopes(count), |i| {
        batch.coefficients.get(i).copied().unwrap_or(0.0)
    })
}

/// [`radiance_bound`] of stored coefficient bytes (a whole number of vertices
/// for SH): f32, or f16 times `scale`. Reads the bytes; converts nothing that
/// is uploaded.
fn stored_radiance_bound(
    bytes: &[u8],
    representation: Representation,
    scalar: ScalarType,
    envelope: &[f64],
    half_table: &[f32],
) -> f64 {
    let f32_at = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]).abs();
    // Magnitude only: the sign bit is masked off (the bound sums |c|).
    let f16_at = |b: &[u8]| half_table[usize::from(u16::from_le_bytes([b[0], b[1]]) & 0x7FFF)];
    match (representation, scalar) {
        (Representation::Cube { .. }, ScalarType::F32) => bytes
            .chunks_exact(4)
            .fold(0.0f32, |m, b| m.max(f32_at(b)))
            .into(),
        // Finite halves without their sign order as their bit patterns do, so
        // the largest magnitude is the largest masked pattern.
        (Representation::Cube { .. }, ScalarType::F16 { scale }) => {
            let top = bytes
                .chunks_exact(2)
                .map(|b| u16::from_le_bytes([b[0], b[1]]) & 0x7FFF)
                .max()
                .unwrap_or(0);
            f64::from(half_table[usize::from(top)]) * f64::from(scale)
        }
        (Representation::Sh { .. }, ScalarType::F32) => {
            sh_bound_f32(bytes, representation, envelope)
        }
        (Representation::Sh { .. }, ScalarType::F16 { scale }) => {
            sh_bound_stored(bytes, representation, envelope, 2, f16_at) * f64::from(scale)
        }
    }
}

/// The SH bound of [`radiance_bound`] over stored f32 vertices, summed in f32
/// over twelve lanes (four RGB triples, which the compiler vectorizes) so that
/// it keeps pace with the copy. A sum of m non-negative f32 products is within
/// (m + 1)·2⁻²⁴ relative of the exact one (Higham 2002, §4.2), so scaling it up
/// by that keeps it an upper bound.
fn sh_bound_f32(bytes: &[u8], representation: Representation, envelope: &[f64]) -> f64 {
    let n = representation.coefficients_per_channel() as usize;
    let lanes: Vec<f32> = (0..envelope.len() * 3)
        .map(|i| envelope[i / 3] as f32)
        .collect();
    let slack = 1.0 + (envelope.len() as f64 + 1.0) * 2f64.powi(-24);
    let mut bound = 0.0f64;
    for vertex in bytes.chunks_exact(n * 3 * 4) {
        let used = &vertex[..lanes.len() * 4];
        let mut acc = [0.0f32; 12];
        let mut values = used.chunks_exact(48);
        let mut weights = lanes.chunks_exact(12);
        for (v, e) in (&mut values).zip(&mut weights) {
            for j in 0..12 {
                let x = f32::from_le_bytes([v[4 * j], v[4 * j + 1], v[4 * j + 2], v[4 * j + 3]]);
                acc[j] += x.abs() * e[j];
            }
        }
        // The rest starts at a whole RGB triple, so lane j is still channel j % 3.
        for (j, (v, e)) in values
            .remainder()
            .chunks_exact(4)
            .zip(weights.remainder())
            .enumerate()
        {
            acc[j] += f32::from_le_bytes([v[0], v[1], v[2], v[3]]).abs() * e;
        }
        for c in 0..3 {
            let sum = acc[c] + acc[c + 3] + acc[c + 6] + acc[c + 9];
            bound = bound.max(f64::from(sum) * slack);
        }
    }
    bound
}

/// The SH bound of [`radiance_bound`] over stored vertices of `size`-byte
/// scalars that `magnitude` reads.
fn sh_bound_stored(
    bytes: &[u8],
    representation: Representation,
    envelope: &[f64],
    size: usize,
    magnitude: impl Fn(&[u8]) -> f32,
) -> f64 {
    let n = representation.coefficients_per_channel() as usize;
    let mut bound = 0.0f64;
    for vertex in bytes.chunks_exact(n * 3 * size) {
        let mut sum = [0.0f64; 3];
        for (rgb, e) in vertex.chunks_exact(3 * size).zip(envelope) {
            for (c, s) in sum.iter_mut().enumerate() {
                *s += f64::from(magnitude(&rgb[c * size..(c + 1) * size])) * e;
            }
        }
        bound = sum.into_iter().fold(bound, f64::max);
    }
    bound
}

/// Every half's magnitude as f32, indexed by its bits without the sign: the
/// bound reads f16 coefficients through it (32 K entries, built once per upload).
fn half_magnitudes() -> Vec<f32> {
    (0..0x8000u16)
        .map(|bits| half::f16::from_bits(bits).to_f32())
        .collect()
}

fn vertex_bytes(vertices: &[Vertex], out: &mut Vec<u8>) {
    for v in vertices {
        for f in v.position.iter().chain(&v.normal).chain(&v.tangent) {
            out.extend_from_slice(&f.to_le_bytes());
        }
    }
}

/// A batch's stored index bytes (`u32` little-endian) reordered chunk by
/// chunk ([`partition`] into chunks of at most `chunk_triangles`), with the
/// chunks; `vertex_bytes` is the batch's vertex section (positions first in
/// each [`layout::VERTEX_LEN`]-byte vertex). The vertex data is only read. An
/// index without a vertex (which the file's checks exclude) makes its
/// triangle's chunk box non-finite, which culling always keeps.
fn chunked_indices(
    vertex_bytes: &[u8],
    index_bytes: &[u8],
    chunk_triangles: u32,
) -> (Vec<u8>, Vec<Chunk>) {
    let index = |i: usize| {
        let b = &index_bytes[4 * i..4 * i + 4];
        u32::from_le_bytes([b[0], b[1], b[2], b[3]])
    };
    let position = |v: u32| {
        let start = v as usize * layout::VERTEX_LEN;
        match vertex_bytes.get(start..start + 12) {
            Some(b) => DVec3::from_array(std::array::from_fn(|a| {
                f64::from(f32::from_le_bytes([
                    b[4 * a],
                    b[4 * a + 1],
                    b[4 * a + 2],
                    b[4 * a + 3],
                ]))
            })),
            None => DVec3::NAN,
        }
    };
    let triangles = (index_bytes.len() / 12) as u32;
    let parts = partition(
        triangles,
        |t, k| position(index(3 * t as usize + k)),
        chunk_triangles,
    );
    let mut out = Vec::with_capacity(index_bytes.len());
    for &t in &parts.order {
        out.extend_from_slice(&index_bytes[12 * t as usize..12 * t as usize + 12]);
    }
    (out, parts.chunks)
}

fn align(value: u64, alignment: u64) -> u64 {
    let a = alignment.max(4);
    value.div_ceil(a) * a
}

/// What the upload needs to know of a batch, from the file's tables or from an
/// in-memory batch.
#[derive(Clone, Copy, Debug)]
struct BatchShape {
    representation: Representation,
    scalar: ScalarType,
    vertex_count: u64,
    index_count: u64,
    texture: Option<BatchTexture>,
}

impl BatchShape {
    fn coefficient_bytes(&self) -> u64 {
        let size = match self.scalar {
            ScalarType::F32 => 4,
            ScalarType::F16 { .. } => 2,
        };
        self.vertex_count * self.representation.coefficients_per_channel() * 3 * size
    }
}

/// Where each batch goes in the three GPU buffers, in draw order.
struct Plan {
    /// `(batch index, draw)`, draw order; the draw's `index_count` is 0 for a
    /// batch without triangles (its data is still uploaded).
    batches: Vec<(usize, DrawBatch)>,
    storage: CoefficientStorage,
    vertex_total: u64,
    index_total: u64,
    coefficient_total: u64,
    /// Bytes of the textured-vertex buffer.
    textured_total: u64,
}

impl Plan {
    fn new(
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

    fn draws(&self) -> Vec<DrawBatch> {
        self.batches
            .iter()
            .filter(|(_, d)| d.index_count > 0)
            .map(|(_, d)| d.clone())
            .collect()
    }
}

/// The one storage type of a scene's batches.
fn scene_storage(shapes: &[BatchShape]) -> Result<CoefficientStorage, SceneError> {
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

fn radiance_scale(bound: f64) -> f32 {
    if bound > 0.0 && bound.is_finite() {
        (1.0 / bound) as f32
    } else {
        1.0
    }
}

fn device_buffer(gpu: &Gpu, usage: vk::BufferUsageFlags, size: u64) -> Result<Buffer, GpuError> {
    Buffer::new(
        gpu,
        BufferDesc {
            size: size.max(4),
            usage: usage | vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuOnly,
        },
    )
}

/// Which of the three scene buffers a copy fills.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Target {
    Vertices,
    Indices,
    Coefficients,
}

/// One half of the staging buffer: its own pending copies, command buffer and
/// fence, so the host fills one half while the device copies out of the other.
struct StagingHalf {
    /// Where the half starts in the staging buffer, and its size.
    offset: u64,
    size: u64,
    fill: u64,
    regions: Vec<(Target, vk::BufferCopy)>,
    cmd: vk::CommandBuffer,
    fence: Fence,
    /// Submitted and not yet waited for.
    pending: bool,
}

/// Streams byte ranges into the scene buffers through one reused staging
/// buffer in two halves: [`Uploader::push`] copies into the current half; a
/// full half is submitted without waiting and filling goes on in the other,
/// once the device has finished copying out of it.
struct Uploader<'a> {
    gpu: &'a Gpu,
    // Declared before `staging`: dropped (and waited for) first.
    halves: [StagingHalf; 2],
    current: usize,
    staging: Buffer,
    targets: [vk::Buffer; 3],
    /// Submits so far (one per filled half) and the time spent waiting for
    /// them, for `--timings`.
    submits: u32,
    transfer: std::time::Duration,
}

impl<'a> Uploader<'a> {
    /// A staging buffer of two halves of `half` bytes each.
    fn new(gpu: &'a Gpu, half: u64, targets: [vk::Buffer; 3]) -> Result<Self, GpuError> {
        let half = half.max(4).div_ceil(4) * 4;
        let staging = Buffer::new(
            gpu,
            BufferDesc {
                size: 2 * half,
                usage: vk::BufferUsageFlags::TRANSFER_SRC,
                location: MemoryLocation::Mapped,
            },
        )?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(gpu.command_pool())
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(2);
        // SAFETY: the pool belongs to this device and is used from this thread;
        // the buffers are freed in Drop after their fences are waited for.
        let cmds = unsafe { gpu.device().allocate_command_buffers(&alloc) }
            .ctx("vkAllocateCommandBuffers")?;
        let half_at = |k: usize, fence: Fence| StagingHalf {
            offset: k as u64 * half,
            size: half,
            fill: 0,
            regions: Vec::new(),
            cmd: cmds[k],
            fence,
            pending: false,
        };
        Ok(Uploader {
            gpu,
            halves: [
                half_at(0, Fence::new(gpu, false)?),
                half_at(1, Fence::new(gpu, false)?),
            ],
            current: 0,
            staging,
            targets,
            submits: 0,
            transfer: std::time::Duration::ZERO,
        })
    }

    fn room(&self) -> u64 {
        let half = &self.halves[self.current];
        half.size - half.fill
    }

    /// Copies `bytes` (at most a half's size) to staging, bound for `target`
    /// at `dst_offset`.
    fn push(&mut self, target: Target, dst_offset: u64, bytes: &[u8]) -> Result<(), GpuError> {
        if bytes.is_empty() {
            return Ok(());
        }
        if bytes.len() as u64 > self.room() {
            self.flush()?;
        }
        let size = bytes.len() as u64;
        let half = &mut self.halves[self.current];
        let src_offset = half.offset + half.fill;
        // SAFETY: the half is not pending (flush waited for its fence before
        // making it current), so no device work reads this range of staging.
        unsafe { self.staging.write(src_offset, bytes) };
        // Consecutive pieces of one section continue the previous region.
        match half.regions.last_mut() {
            Some((t, r))
                if *t == target
                    && r.src_offset + r.size == src_offset
                    && r.dst_offset + r.size == dst_offset =>
            {
                r.size += size;
            }
            _ => half.regions.push((
                target,
                vk::BufferCopy {
                    src_offset,
                    dst_offset,
                    size,
                },
            )),
        }
        half.fill += size;
        Ok(())
    }

    /// Submits the current half's copies without waiting, then makes the other
    /// half current once the device has finished with it.
    fn flush(&mut self) -> Result<(), GpuError> {
        if !self.halves[self.current].regions.is_empty() {
            self.submit(self.current)?;
        }
        self.current ^= 1;
        self.wait(self.current)
    }

    fn submit(&mut self, k: usize) -> Result<(), GpuError> {
        let device = self.gpu.device();
        let half = &mut self.halves[k];
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the half is not pending (waited for before it was filled), so
        // its command buffer may be re-recorded (the pool allows resets); every
        // region lies inside the staging buffer (push kept `fill` ≤ the half)
        // and inside its target, which `Plan` sized for every batch at its
        // offset; the fence is unsignalled (reset after its last wait).
        unsafe {
            device
                .begin_command_buffer(half.cmd, &begin)
                .ctx("vkBeginCommandBuffer")?;
            for (t, target) in [Target::Vertices, Target::Indices, Target::Coefficients]
                .into_iter()
                .enumerate()
            {
                let list: Vec<vk::BufferCopy> = half
                    .regions
                    .iter()
                    .filter(|(r, _)| *r == target)
                    .map(|(_, r)| *r)
                    .collect();
                if !list.is_empty() {
                    device.cmd_copy_buffer(half.cmd, self.staging.raw, self.targets[t], &list);
                }
            }
            device
                .end_command_buffer(half.cmd)
                .ctx("vkEndCommandBuffer")?;
            let cmds = [half.cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            device
                .queue_submit(self.gpu.queue, &submit, half.fence.raw)
                .ctx("vkQueueSubmit")?;
        }
        half.pending = true;
        half.regions.clear();
        self.submits += 1;
        Ok(())
    }

    /// Waits for half `k`'s copies, leaving it empty and its fence reset.
    fn wait(&mut self, k: usize) -> Result<(), GpuError> {
        let half = &mut self.halves[k];
        if half.pending {
            let start = std::time::Instant::now();
            half.fence.wait()?;
            half.fence.reset()?;
            half.pending = false;
            self.transfer += start.elapsed();
        }
        half.fill = 0;
        Ok(())
    }

    fn finish(mut self) -> Result<(u32, std::time::Duration), GpuError> {
        self.flush()?;
        self.wait(self.current ^ 1)?;
        self.wait(self.current)?;
        Ok((self.submits, self.transfer))
    }
}

impl Drop for Uploader<'_> {
    fn drop(&mut self) {
        for half in &self.halves {
            if half.pending {
                // An upload abandoned mid-way (a checksum mismatch): the device
                // must stop reading staging memory before it is freed.
                let _ = half.fence.wait();
            }
        }
        let cmds = [self.halves[0].cmd, self.halves[1].cmd];
        // SAFETY: no submission of these command buffers is pending (waited for
        // above or in `finish`), and they came from this pool.
        unsafe {
            self.gpu
                .device()
                .free_command_buffers(self.gpu.command_pool(), &cmds)
        };
    }
}

/// Figures of one mapped upload (`--timings`).
#[derive(Clone, Copy, Debug, Default)]
pub struct UploadStats {
    /// Bytes copied from the file to the GPU.
    pub bytes: u64,
    /// Staging fills submitted.
    pub submits: u32,
    /// Host time computing the sections' CRC-32.
    pub checksum: std::time::Duration,
    /// Host time computing the radiance bound of the coefficients.
    pub bound: std::time::Duration,
    /// Host time copying from the map into staging memory.
    pub staging: std::time::Duration,
    /// Time waiting for the device's staging-to-buffer copies.
    pub transfer: std::time::Duration,
    /// Host time partitioning the batches into spatial chunks.
    pub partition: std::time::Duration,
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
        Ok(GpuScene {
            coefficients,
            indices,
            vertices,
            draws: plan.draws(),
            radiance_scale: radiance_scale(bound),
            storage: plan.storage,
            vertex_count: plan.vertex_total,
            triangle_count: plan.index_total / 3,
            textured,
            textures,
        })
    }

    /// Uploads a mapped file as stored: vertices, indices and coefficients (f32,
    /// or f16 whose scale the shader applies) are copied from the map to staging
    /// memory in chunks of at most [`STAGING_BYTES`] and from there to device
    /// buffers. Each section's CRC-32 is computed as its chunks pass and checked
    /// against the file's ([`MappedSolution::verify_section`]), so `file` may be
    /// opened with [`MappedSolution::open_deferring_checksums`]; a mismatch
    /// refuses the file with the error naming file, batch and section.
    ///
    /// Each batch's triangles are partitioned into spatial chunks of at most
    /// [`DEFAULT_CHUNK_TRIANGLES`] for culling ([`super::cull`]); its index
    /// section goes to the GPU in chunk order (checksummed as stored).
    pub fn from_mapped(
        gpu: &Gpu,
        file: &MappedSolution,
        max_order: Option<u32>,
    ) -> Result<(GpuScene, UploadStats), SceneError> {
        Self::from_mapped_with(gpu, file, max_order, DEFAULT_CHUNK_TRIANGLES, STAGING_BYTES)
    }

    /// [`GpuScene::from_mapped`] through a staging buffer of `staging_bytes`
    /// in two halves (the host fills one while the device copies out of the
    /// other); a half is raised to one SH vertex's coefficients if that is
    /// larger, and lowered to the file's bulk if that is smaller. The tests
    /// stream through a tiny one so that every section is split across chunks.
    pub fn from_mapped_in_chunks(
        gpu: &Gpu,
        file: &MappedSolution,
        max_order: Option<u32>,
        staging_bytes: u64,
    ) -> Result<(GpuScene, UploadStats), SceneError> {
        Self::from_mapped_with(gpu, file, max_order, DEFAULT_CHUNK_TRIANGLES, staging_bytes)
    }

    /// [`GpuScene::from_mapped_in_chunks`] with chunks of at most
    /// `chunk_triangles` triangles for culling.
    pub fn from_mapped_with(
        gpu: &Gpu,
        file: &MappedSolution,
        max_order: Option<u32>,
        chunk_triangles: u32,
        staging_bytes: u64,
    ) -> Result<(GpuScene, UploadStats), SceneError> {
        let shapes: Vec<BatchShape> = file
            .batches()
            .iter()
            .map(|info| BatchShape {
                representation: info.representation,
                scalar: info.scalar,
                vertex_count: u64::from(info.vertex_count),
                index_count: u64::from(info.index_count),
                texture: info.texture,
            })
            .collect();
        let mut plan = Plan::new(&shapes, max_order, &gpu.info.limits)?;
        let vertices = device_buffer(
            gpu,
            vk::BufferUsageFlags::VERTEX_BUFFER,
            plan.vertex_total * layout::VERTEX_LEN as u64,
        )?;
        let indices = device_buffer(
            gpu,
            vk::BufferUsageFlags::INDEX_BUFFER,
            plan.index_total * 4,
        )?;
        let coefficients = device_buffer(
            gpu,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            plan.coefficient_total,
        )?;
        let total: u64 = (0..shapes.len())
            .map(|b| {
                [
                    BatchSection::Vertices,
                    BatchSection::Coefficients,
                    BatchSection::Indices,
                ]
                .iter()
                .map(|&s| file.section_bytes(b, s).len() as u64)
                .sum::<u64>()
            })
            .sum();
        // SH bounds sum per vertex, so SH coefficient chunks hold whole vertices
        // (one vertex is at most (1024 + 1)² · 3 · 4 ≈ 12.6 MB, under the
        // default staging size); other sections split anywhere.
        let unit = |shape: &BatchShape| match shape.representation {
            Representation::Sh { .. } => {
                shape.representation.coefficients_per_channel()
                    * 3
                    * layout::scalar_size(shape.scalar)
            }
            Representation::Cube { .. } => 1,
        };
        // Two halves, each at least one unit, together at most `staging_bytes`
        // (unless one unit is larger) and no larger than needed.
        let largest_unit = shapes.iter().map(unit).max().unwrap_or(1);
        let half = (staging_bytes / 2).max(largest_unit).min(total);
        let mut uploader = Uploader::new(gpu, half, [vertices.raw, indices.raw, coefficients.raw])?;
        let half_table = match plan.storage {
            CoefficientStorage::F16 => half_magnitudes(),
            CoefficientStorage::F32 => Vec::new(),
        };
        let mut bound = 0.0f64;
        let mut textured_data: Vec<u8> = Vec::new();
        let mut textured_bounds = vec![0.0f64; shapes.len()];
        let mut stats = UploadStats {
            bytes: total,
            ..UploadStats::default()
        };
        for (b, draw) in &mut plan.batches {
            let b = *b;
            let shape = shapes[b];
            // The batch's chunks and its indices in chunk order, read from the
            // map before its sections stream (the vertices are still resident).
            let partition_start = std::time::Instant::now();
            let (reordered, chunks) = chunked_indices(
                file.section_bytes(b, BatchSection::Vertices),
                file.section_bytes(b, BatchSection::Indices),
                chunk_triangles,
            );
            draw.chunks = chunks;
            stats.partition += partition_start.elapsed();
            let envelope = match shape.representation {
                Representation::Sh { .. } => envelopes(
                    (draw.order as usize + 1)
                        .pow(2)
                        .min(shape.representation.coefficients_per_channel() as usize),
                ),
                Representation::Cube { .. } => Vec::new(),
            };
            let sections = [
                (
                    BatchSection::Vertices,
                    Target::Vertices,
                    u64::from(draw.vertex_base) * layout::VERTEX_LEN as u64,
                ),
                (
                    BatchSection::Coefficients,
                    Target::Coefficients,
                    draw.coeff_offset,
                ),
                (
                    BatchSection::Indices,
                    Target::Indices,
                    u64::from(draw.first_index) * 4,
                ),
            ];
            for (section, target, dst) in sections {
                let bytes = file.section_bytes(b, section);
                // The checksum covers the stored bytes; the GPU gets the
                // indices in chunk order (the same length).
                let source = match section {
                    BatchSection::Indices => &reordered[..],
                    _ => bytes,
                };
                let unit = match section {
                    BatchSection::Coefficients => unit(&shape).max(1),
                    _ => 1,
                };
                let mut hasher = crc32fast::Hasher::new();
                let mut done = 0u64;
                while done < bytes.len() as u64 {
                    // Sections are whole units long, and staging holds at least
                    // one unit, so after a flush `take` is positive.
                    // Pieces of about PASS_BYTES stay in the cache between the
                    // checksum, the bound and the copy, so the map is read from
                    // memory once.
                    let remaining =
                        (bytes.len() as u64 - done).min((PASS_BYTES / unit).max(1) * unit);
                    let mut take = (uploader.room() / unit * unit).min(remaining);
                    if take == 0 {
                        uploader.flush()?;
                        take = (uploader.room() / unit * unit).min(remaining);
                    }
                    if take == 0 {
                        return Err(SceneError::Inconsistent {
                            batch: b,
                            what: format!(
                                "{section:?} of {remaining} bytes do not fit staging chunks of {unit}"
                            ),
                        });
                    }
                    let chunk = &bytes[done as usize..(done + take) as usize];
                    let start = std::time::Instant::now();
                    hasher.update(chunk);
                    let hashed = std::time::Instant::now();
                    stats.checksum += hashed - start;
                    if section == BatchSection::Coefficients {
                        // The finite check the mapped open left to this pass,
                        // while the piece is in the cache.
                        let first = done / layout::scalar_size(shape.scalar);
                        file.verify_finite_coefficients(b, first, chunk)?;
                        bound = bound.max(stored_radiance_bound(
                            chunk,
                            shape.representation,
                            shape.scalar,
                            &envelope,
                            &half_table,
                        ));
                    }
                    let bounded = std::time::Instant::now();
                    stats.bound += bounded - hashed;
                    let transfer_before = uploader.transfer;
                    uploader.push(
                        target,
                        dst + done,
                        &source[done as usize..(done + take) as usize],
                    )?;
                    // A push that flushed spent part of its time waiting.
                    stats.staging += bounded
                        .elapsed()
                        .saturating_sub(uploader.transfer - transfer_before);
                    done += take;
                }
                file.verify_section(b, section, hasher.finalize())?;
                // The bytes are in staging or on the device: the map's pages
                // need not stay resident beside the device copy.
                file.release_section(b, section);
            }
            if let Some(t) = &draw.texture {
                // Textured vertices (20 bytes each, a small part of the file)
                // are gathered in memory and copied in one go below.
                let bytes = file.section_bytes(b, BatchSection::TexturedVertices);
                file.verify_section(b, BatchSection::TexturedVertices, crc32fast::hash(bytes))?;
                textured_data.resize(t.offset as usize, 0);
                textured_data.extend_from_slice(bytes);
                textured_bounds[b] = textured_bound(bytes, t.factor);
            }
        }
        (stats.submits, stats.transfer) = uploader.finish()?;
        // SH and textured terms add in a pixel: bound each batch by the sum of
        // its two bounds (the SH bound was folded per chunk into `bound`, so
        // add the largest textured bound to it: still an upper bound).
        bound += textured_bounds.iter().copied().fold(0.0f64, f64::max);
        textured_data.resize(plan.textured_total.max(4) as usize, 0);
        let textured =
            Buffer::with_data(gpu, vk::BufferUsageFlags::STORAGE_BUFFER, &textured_data)?;
        let textures = SceneTextures::new(gpu, file.textures().len(), |k| {
            file.decode_texture(k).map_err(SceneError::from)
        })?;
        Ok((
            GpuScene {
                coefficients,
                indices,
                vertices,
                draws: plan.draws(),
                radiance_scale: radiance_scale(bound),
                storage: plan.storage,
                vertex_count: plan.vertex_total,
                triangle_count: plan.index_total / 3,
                textured,
                textures,
            },
            stats,
        ))
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

#[cfg(test)]
mod tests {
    use super::*;
    use solution::format::ScalarType;

    /// The bound the mapped upload computes from stored bytes is the bound of
    /// the in-memory batch: for f32 an upper bound within the f32 summation's
    /// rounding (the f32 envelope rounds too, by 2⁻²⁴ per term), and for
    /// f16 the bound of the rounded values, within 2⁻¹¹ relative of the f32
    /// one (each |c| rounds by at most that, and the sum has positive terms).
    #[test]
    fn stored_bound_matches_the_in_memory_bound() {
        let order = 3u32;
        let n = (order as usize + 1).pow(2);
        let vertices = 5;
        let coefficients: Vec<f32> = (0..vertices * n * 3)
            .map(|i| ((i * 37 % 23) as f32 - 11.0) * 0.37)
            .collect();
        let batch = Batch {
            representation: Representation::Sh { order },
            scalar: ScalarType::F32,
            vertices: vec![Vertex::default(); vertices],
            coefficients: coefficients.clone(),
            indices: vec![],
            texturing: None,
        };
        let f32_bytes: Vec<u8> = coefficients.iter().flat_map(|c| c.to_le_bytes()).collect();
        let scale = solution::format::f16_scale_for(&coefficients);
        let f16_bytes: Vec<u8> = coefficients
            .iter()
            .flat_map(|c| half::f16::from_f32(c / scale).to_bits().to_le_bytes())
            .collect();
        let table = half_magnitudes();
        for cap in [order, 1] {
            let expected = radiance_bound(&batch, cap);
            let envelope = envelopes((cap as usize + 1).pow(2));
            let from_f32 = stored_radiance_bound(
                &f32_bytes,
                batch.representation,
                ScalarType::F32,
                &envelope,
                &table,
            );
            // Summed in f32 and scaled up by its rounding bound (sh_bound_f32):
            // never below the f64 bound, at most 2·(16 + 1)·2⁻²⁴ above it.
            assert!(
                from_f32 >= expected * (1.0 - 1e-15)
                    && from_f32 <= expected * (1.0 + 34.0 * 2f64.powi(-24)),
                "{from_f32} vs {expected}"
            );
            let from_f16 = stored_radiance_bound(
                &f16_bytes,
                batch.representation,
                ScalarType::F16 { scale },
                &envelope,
                &table,
            );
            assert!(
                (from_f16 - expected).abs() <= 2f64.powi(-11) * expected,
                "{from_f16} vs {expected}"
            );
        }
        // A cube: the largest magnitude, through the bit patterns for f16.
        let cube = Representation::Cube { directions: 6 };
        let largest = coefficients
            .iter()
            .fold(0.0f64, |m, c| m.max(f64::from(c.abs())));
        let from_f32 = stored_radiance_bound(&f32_bytes, cube, ScalarType::F32, &[], &table);
        assert_eq!(from_f32, largest);
        let from_f16 =
            stored_radiance_bound(&f16_bytes, cube, ScalarType::F16 { scale }, &[], &table);
        assert!((from_f16 - largest).abs() <= 2f64.powi(-11) * largest);
    }

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
            texturing: None,
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
