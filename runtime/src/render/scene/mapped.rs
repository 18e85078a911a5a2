//! The mapped upload: a [`MappedSolution`]'s sections streamed as stored
//! through the staging halves into the scene's buffers, each section
//! checksummed, its coefficients checked finite and bounded, as it passes.

use super::bound::{envelopes, half_magnitudes, stored_radiance_bound, textured_bound};
use super::chunks::chunked_indices;
use super::plan::{BatchShape, Plan};
use super::staging::{device_buffer, Target, Uploader};
use super::{CoefficientStorage, DrawBatch, GpuScene, SceneError, STAGING_BYTES};
use crate::gpu::{Buffer, Gpu};
use crate::render::cull::DEFAULT_CHUNK_TRIANGLES;
use ash::vk;
use solution::format::{layout, BatchSection, MappedSolution, Representation};

/// The piece of a section that the upload checksums, bounds and copies before
/// moving on: small enough to stay in the L2 cache between the three.
const PASS_BYTES: u64 = 256 << 10;

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
    /// Uploads a mapped file as stored: vertices, indices and coefficients (f32,
    /// or f16 whose scale the shader applies) are copied from the map to staging
    /// memory in chunks of at most [`STAGING_BYTES`] and from there to device
    /// buffers. Each section's CRC-32 is computed as its chunks pass and checked
    /// against the file's ([`MappedSolution::verify_section`]), so `file` may be
    /// opened with [`MappedSolution::open_deferring_checksums`]; a mismatch
    /// refuses the file with the error naming file, batch and section.
    ///
    /// Each batch's triangles are partitioned into spatial chunks of at most
    /// [`DEFAULT_CHUNK_TRIANGLES`] for culling ([`crate::render::cull`]); its index
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
        let total = bulk_bytes(file);
        let half = staging_half(&shapes, total, staging_bytes);
        let mut upload = MappedUpload {
            file,
            uploader: Uploader::new(gpu, half, [vertices.raw, indices.raw, coefficients.raw])?,
            half_table: match plan.storage {
                CoefficientStorage::F16 => half_magnitudes(),
                CoefficientStorage::F32 => Vec::new(),
            },
            bound: 0.0,
            textured_data: Vec::new(),
            textured_bounds: vec![0.0f64; shapes.len()],
            stats: UploadStats {
                bytes: total,
                ..UploadStats::default()
            },
        };
        for (b, draw) in &mut plan.batches {
            upload.batch(*b, &shapes[*b], draw, chunk_triangles)?;
        }
        let MappedUpload {
            uploader,
            mut bound,
            mut textured_data,
            textured_bounds,
            mut stats,
            ..
        } = upload;
        (stats.submits, stats.transfer) = uploader.finish()?;
        // SH and textured terms add in a pixel: bound each batch by the sum of
        // its two bounds (the SH bound was folded per chunk into `bound`, so
        // add the largest textured bound to it: still an upper bound).
        bound += textured_bounds.iter().copied().fold(0.0f64, f64::max);
        textured_data.resize(plan.textured_total.max(4) as usize, 0);
        let textured =
            Buffer::with_data(gpu, vk::BufferUsageFlags::STORAGE_BUFFER, &textured_data)?;
        let textures = super::SceneTextures::new(gpu, file.textures().len(), |k| {
            file.decode_texture(k).map_err(SceneError::from)
        })?;
        let buffers = super::SceneBuffers {
            coefficients,
            indices,
            vertices,
            textured,
        };
        Ok((plan.into_scene(buffers, textures, bound), stats))
    }
}

/// The bytes the upload streams: every batch's vertices, coefficients and
/// indices.
fn bulk_bytes(file: &MappedSolution) -> u64 {
    (0..file.batches().len())
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
        .sum()
}

/// The smallest piece of a batch's coefficients that streams whole. SH bounds
/// sum per vertex, so SH coefficient chunks hold whole vertices (one vertex is
/// at most (1024 + 1)² · 3 · 4 ≈ 12.6 MB, under the default staging size);
/// other sections split anywhere.
fn stream_unit(shape: &BatchShape) -> u64 {
    match shape.representation {
        Representation::Sh { .. } => {
            shape.representation.coefficients_per_channel() * 3 * layout::scalar_size(shape.scalar)
        }
        Representation::Cube { .. } => 1,
    }
}

/// The size of each staging half: at least one unit, the two together at most
/// `staging_bytes` (unless one unit is larger) and no larger than needed.
fn staging_half(shapes: &[BatchShape], total: u64, staging_bytes: u64) -> u64 {
    let largest_unit = shapes.iter().map(stream_unit).max().unwrap_or(1);
    (staging_bytes / 2).max(largest_unit).min(total)
}

/// One mapped upload in progress: the staging uploader, and what the batches
/// streamed so far have added to the bound, the textured vertices and the
/// figures.
struct MappedUpload<'f, 'g> {
    file: &'f MappedSolution,
    uploader: Uploader<'g>,
    /// [`half_magnitudes`] for an f16 scene, else empty.
    half_table: Vec<f32>,
    /// The largest SH (or cube) bound of the coefficients streamed so far.
    bound: f64,
    /// The textured vertices, gathered in memory and copied in one go at the
    /// end (20 bytes a vertex, a small part of the file).
    textured_data: Vec<u8>,
    /// Each batch's textured bound ([`textured_bound`]; 0 when untextured).
    textured_bounds: Vec<f64>,
    stats: UploadStats,
}

impl MappedUpload<'_, '_> {
    /// Streams batch `b`: partitions its triangles into chunks (filling
    /// `draw.chunks`), streams its three bulk sections, then gathers its
    /// textured vertices.
    fn batch(
        &mut self,
        b: usize,
        shape: &BatchShape,
        draw: &mut DrawBatch,
        chunk_triangles: u32,
    ) -> Result<(), SceneError> {
        let file = self.file;
        // The batch's chunks and its indices in chunk order, read from the
        // map before its sections stream (the vertices are still resident).
        let partition_start = std::time::Instant::now();
        let (reordered, chunks) = chunked_indices(
            file.section_bytes(b, BatchSection::Vertices),
            file.section_bytes(b, BatchSection::Indices),
            chunk_triangles,
        );
        draw.chunks = chunks;
        self.stats.partition += partition_start.elapsed();
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
            self.section(b, shape, section, (target, dst), source, &envelope)?;
        }
        if let Some(t) = &draw.texture {
            // Textured vertices (20 bytes each, a small part of the file)
            // are gathered in memory and copied in one go at the end.
            let bytes = file.section_bytes(b, BatchSection::TexturedVertices);
            file.verify_section(b, BatchSection::TexturedVertices, crc32fast::hash(bytes))?;
            self.textured_data.resize(t.offset as usize, 0);
            self.textured_data.extend_from_slice(bytes);
            self.textured_bounds[b] = textured_bound(bytes, t.factor);
        }
        Ok(())
    }

    /// Streams batch `b`'s `section` into `target` at byte `dst`, piece by
    /// piece: the stored bytes are checksummed (and coefficients checked finite
    /// and bounded), `source` (the stored bytes, or the indices in chunk order)
    /// is copied; then the checksum is verified and the map's pages released.
    fn section(
        &mut self,
        b: usize,
        shape: &BatchShape,
        section: BatchSection,
        (target, dst): (Target, u64),
        source: &[u8],
        envelope: &[f64],
    ) -> Result<(), SceneError> {
        let file = self.file;
        let bytes = file.section_bytes(b, section);
        let unit = match section {
            BatchSection::Coefficients => stream_unit(shape).max(1),
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
            let remaining = (bytes.len() as u64 - done).min((PASS_BYTES / unit).max(1) * unit);
            let mut take = (self.uploader.room() / unit * unit).min(remaining);
            if take == 0 {
                self.uploader.flush()?;
                take = (self.uploader.room() / unit * unit).min(remaining);
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
            self.stats.checksum += hashed - start;
            if section == BatchSection::Coefficients {
                // The finite check the mapped open left to this pass,
                // while the piece is in the cache.
                let first = done / layout::scalar_size(shape.scalar);
                file.verify_finite_coefficients(b, first, chunk)?;
                self.bound = self.bound.max(stored_radiance_bound(
                    chunk,
                    shape.representation,
                    shape.scalar,
                    envelope,
                    &self.half_table,
                ));
            }
            let bounded = std::time::Instant::now();
            self.stats.bound += bounded - hashed;
            let transfer_before = self.uploader.transfer;
            self.uploader.push(
                target,
                dst + done,
                &source[done as usize..(done + take) as usize],
            )?;
            // A push that flushed spent part of its time waiting.
            self.stats.staging += bounded
                .elapsed()
                .saturating_sub(self.uploader.transfer - transfer_before);
            done += take;
        }
        file.verify_section(b, section, hasher.finalize())?;
        // The bytes are in staging or on the device: the map's pages
        // need not stay resident beside the device copy.
        file.release_section(b, section);
        Ok(())
    }
}
