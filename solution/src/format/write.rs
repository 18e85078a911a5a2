//! The writer: validates a [`Solution`], lays it out and streams it out.
//!
//! The layout is planned from the counts alone, so sections are streamed in
//! chunks (no second copy of the coefficients in memory) and the metadata, whose
//! section checksums are only known at the end, is written last over a zeroed
//! placeholder. [`write_solution`] does this through the atomic writer
//! ([`crate::atomic`]).

use super::error::{FormatError, Problem};
use super::layout::{self, FieldsMut};
use super::validate::{self, F16_MAX};
use super::{Batch, ScalarType, Solution};
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// The smallest magnitude that rounds to infinity in IEEE half (round to nearest
/// even): halfway between 65504 and the next step, 65536. Comparing against it is
/// the same test as converting and checking for infinity, at a fraction of the
/// cost (the conversion is done in software unless F16C is enabled).
const F16_OVERFLOW: f32 = 65520.0;

/// Knobs that only tests turn: they let a test write what a newer minor version
/// would (longer blocks, sections of kinds this version does not know), to check
/// that this reader skips them.
#[derive(Clone, Debug, Default)]
pub(crate) struct EncodeOptions {
    /// The minor version to claim; `None` picks it from the solution (1 with
    /// lighting, else 0).
    pub minor: Option<u16>,
    pub header_extra: usize,
    pub batch_entry_extra: usize,
    pub section_entry_extra: usize,
    pub extra_sections: Vec<(u32, Vec<u8>)>,
    /// Written instead of the encoded textures' sections (prefix and image),
    /// so a test can store a hostile image under correct checksums.
    pub texture_sections: Option<Vec<Vec<u8>>>,
}

#[derive(Clone, Copy, Debug)]
struct SectionPlan {
    kind: u32,
    offset: u64,
    length: u64,
}

#[derive(Debug)]
struct Plan {
    /// 1 without textures (the version-1 layout, byte for byte), 2 with
    /// textures but no emission slot (the version-2 layout), else 3.
    major: u16,
    /// 0, or [`layout::LIGHTING_VERSION_MINOR`] for a solution with lighting.
    minor: u16,
    /// The lights and environment sections' indices, or
    /// [`layout::NO_SECTION`].
    lights_section: u32,
    environment_section: u32,
    /// Per batch, the section indices of its vertices, coefficients, indices
    /// and (textured batches) textured vertices.
    batch_sections: Vec<[u32; 4]>,
    /// Each texture's section bytes (prefix and PNG), encoded once.
    texture_sections: Vec<Vec<u8>>,
    header_len: usize,
    batch_entry_len: usize,
    section_entry_len: usize,
    metadata_len: usize,
    sections: Vec<SectionPlan>,
    file_len: u64,
}

/// Encodes a solution into the bytes of a solution file, after checking it (see
/// [`check_solution`]).
pub fn encode(solution: &Solution) -> Result<Vec<u8>, FormatError> {
    encode_with(solution, &EncodeOptions::default())
}

pub(crate) fn encode_with(
    solution: &Solution,
    options: &EncodeOptions,
) -> Result<Vec<u8>, FormatError> {
    check_solution(solution)?;
    let plan = plan(solution, options)?;
    let capacity = usize::try_from(plan.file_len).map_err(|_| Problem::TooLarge {
        what: "the encoded file's length".into(),
        value: plan.file_len,
        limit: usize::MAX as u64,
        reason: "it does not fit in this machine's address space",
    })?;
    let mut out = std::io::Cursor::new(Vec::with_capacity(capacity));
    write_planned(&mut out, solution, &plan, options).map_err(|source| FormatError::Io {
        action: "encode into memory",
        path: PathBuf::from("<memory>"),
        source,
    })?;
    Ok(out.into_inner())
}

/// Writes `solution` to `path` atomically ([`crate::atomic::write_atomically`]: a
/// temporary file in the same directory, fsync, rename, directory fsync), so a
/// crash or a full disk never leaves a partial file under the final name, and a
/// reader that has the old file mapped keeps its (unchanged) inode. An invalid
/// solution is refused before any file is created.
pub fn write_solution(path: &Path, solution: &Solution) -> Result<(), FormatError> {
    write_solution_with(path, solution, &EncodeOptions::default())
}

pub(crate) fn write_solution_with(
    path: &Path,
    solution: &Solution,
    options: &EncodeOptions,
) -> Result<(), FormatError> {
    check_solution(solution).map_err(|p| FormatError::in_file(path, p))?;
    let plan = plan(solution, options).map_err(|p| FormatError::in_file(path, p))?;
    crate::atomic::write_atomically(path, |file| {
        let mut writer = std::io::BufWriter::with_capacity(1 << 20, file);
        write_planned(&mut writer, solution, &plan, options)?;
        writer.flush()
    })
    .map_err(|e| FormatError::io(e.action, &e.path, e.source))
}

/// The power-of-two f16 scale that maps the largest magnitude in `values` to at
/// most 65504 (the largest half), keeping as much of the half range as possible
/// for small values. A power of two makes `value / scale` and `half × scale` exact
/// in f32, so the only error is the rounding to half: relative 2⁻¹¹ for stored
/// magnitudes ≥ 2⁻¹⁴·scale, absolute 2⁻²⁵·scale below. Non-finite values are
/// ignored (the writer refuses them anyway); all-zero input gives 1.
pub fn f16_scale_for(values: &[f32]) -> f32 {
    let max = values
        .iter()
        .filter(|v| v.is_finite())
        .fold(0.0f32, |m, v| m.max(v.abs()));
    if max == 0.0 {
        return 1.0;
    }
    let mut scale = 2f32.powi((max / F16_MAX).log2().ceil() as i32);
    while max / scale > F16_MAX {
        scale *= 2.0;
    }
    scale.max(f32::MIN_POSITIVE)
}

/// Checks everything the format requires of a solution: valid header values,
/// counts that fit version 1, `coefficients.len() == vertices × coefficients per
/// channel × 3`, whole triangles with indices below the vertex count, finite
/// values, orthonormal frames, every vertex inside the header bounds, and f16
/// coefficients inside the half range.
pub fn check_solution(solution: &Solution) -> Result<(), Problem> {
    let header = &solution.header;
    validate::check_header(header)?;
    let slack = validate::bounds_slack(header);
    for (b, batch) in solution.batches.iter().enumerate() {
        check_batch(b, batch)?;
        for (v, vertex) in batch.vertices.iter().enumerate() {
            validate::check_in_bounds(b, v as u64, vertex.position, header, slack)?;
        }
        if let Some(t) = &batch.texturing {
            check_texturing(b, batch, t, solution.textures.len())?;
        }
    }
    if let Some(lighting) = &solution.lighting {
        super::lighting::check_lighting(lighting)?;
    }
    let mut decoded = 0u64;
    for (k, texture) in solution.textures.iter().enumerate() {
        super::texture::check_texture(k as u32, texture)?;
        decoded += texture.rgba.len() as u64;
        validate::check_decoded_texture_bytes(decoded)?;
    }
    Ok(())
}

fn check_texturing(
    b: usize,
    batch: &Batch,
    t: &super::Texturing,
    texture_count: usize,
) -> Result<(), Problem> {
    validate::check_batch_texture(
        b,
        batch.representation,
        t.texture,
        texture_count as u64,
        t.factor,
    )?;
    if let Some(slot) = &t.emission {
        validate::check_emission_slot(b, slot, texture_count as u64)?;
    }
    if t.vertices.len() != batch.vertices.len() {
        return Err(Problem::Invalid {
            what: format!(
                "batch {b}: {} textured vertices for {} vertices",
                t.vertices.len(),
                batch.vertices.len()
            ),
            reason: "a textured batch has one UV and E/π per vertex".into(),
        });
    }
    for (v, tv) in t.vertices.iter().enumerate() {
        validate::check_textured_vertex(b, v as u64, tv)?;
    }
    Ok(())
}

fn check_batch(b: usize, batch: &Batch) -> Result<(), Problem> {
    validate::check_representation(b, batch.representation)?;
    validate::check_scalar(b, batch.scalar)?;
    let vertex_count = batch.vertices.len() as u64;
    let index_count = batch.indices.len() as u64;
    validate::check_counts(b, vertex_count, index_count)?;
    let per_channel = batch.representation.coefficients_per_channel();
    let expected = u128::from(vertex_count) * u128::from(per_channel) * 3;
    if expected != batch.coefficients.len() as u128 {
        return Err(Problem::CoefficientCount {
            batch: b,
            found: batch.coefficients.len() as u64,
            vertices: vertex_count,
            per_channel,
            expected,
        });
    }
    for (v, vertex) in batch.vertices.iter().enumerate() {
        validate::check_vertex(b, v as u64, vertex)?;
    }
    if let Some((position, &index)) = batch
        .indices
        .iter()
        .enumerate()
        .find(|(_, &i)| u64::from(i) >= vertex_count)
    {
        return Err(Problem::IndexOutOfRange {
            batch: b,
            position: position as u64,
            index,
            vertex_count,
        });
    }
    let per_vertex = (per_channel * 3).max(1) as usize;
    for (position, &value) in batch.coefficients.iter().enumerate() {
        if !value.is_finite() {
            return Err(Problem::NonFinite {
                what: format!(
                    "batch {b}: coefficient {position} (vertex {}, coefficient {}, channel {})",
                    position / per_vertex,
                    position % per_vertex / 3,
                    position % 3
                ),
                value: value.to_string(),
            });
        }
        if let ScalarType::F16 { scale } = batch.scalar {
            if (value / scale).abs() >= F16_OVERFLOW {
                return Err(Problem::F16Overflow {
                    batch: b,
                    position: position as u64,
                    value,
                    scale,
                });
            }
        }
    }
    Ok(())
}

fn section_len(what: &str, count: u64, size: u64) -> Result<u64, Problem> {
    count.checked_mul(size).ok_or_else(|| Problem::TooLarge {
        what: what.to_string(),
        value: count,
        limit: u64::MAX / size,
        reason: "its byte length overflows 64 bits",
    })
}

/// The lowest version that holds the solution: major 1 without textures, 2
/// with textures but no second slot, else 3 ([`layout::VERSION_MAJOR`]);
/// minor 1 with lighting, else 0 (unless a test forces another).
fn pick_version(solution: &Solution, options: &EncodeOptions) -> (u16, u16) {
    let textured =
        !solution.textures.is_empty() || solution.batches.iter().any(|b| b.texturing.is_some());
    let second_slot = solution
        .batches
        .iter()
        .any(|b| b.texturing.as_ref().is_some_and(|t| t.emission.is_some()));
    let major = if second_slot {
        layout::VERSION_MAJOR
    } else if textured {
        layout::TEXTURED_VERSION_MAJOR
    } else {
        layout::UNTEXTURED_VERSION_MAJOR
    };
    let lit = solution.lighting.as_ref().is_some_and(|l| !l.is_empty());
    let minor = options.minor.unwrap_or(if lit {
        layout::LIGHTING_VERSION_MINOR
    } else {
        0
    });
    (major, minor)
}

fn plan(solution: &Solution, options: &EncodeOptions) -> Result<Plan, Problem> {
    let (major, minor) = pick_version(solution, options);
    let lighting = solution.lighting.as_ref().filter(|l| !l.is_empty());
    let header_len = layout::header_len(minor.min(layout::VERSION_MINOR)) + options.header_extra;
    let batch_entry_len = layout::batch_entry_len(major) + options.batch_entry_extra;
    let section_entry_len = layout::SECTION_ENTRY_LEN + options.section_entry_extra;
    let mut sections = vec![SectionPlan {
        kind: layout::SECTION_SETTINGS,
        offset: 0,
        length: solution.header.settings_json.len() as u64,
    }];
    let mut batch_sections = Vec::with_capacity(solution.batches.len());
    for (b, batch) in solution.batches.iter().enumerate() {
        let vertex_count = batch.vertices.len() as u64;
        let first = sections.len() as u32;
        batch_sections.push([
            first,
            first + 1,
            first + 2,
            if batch.texturing.is_some() {
                first + 3
            } else {
                layout::NO_TEXTURE
            },
        ]);
        sections.push(SectionPlan {
            kind: layout::SECTION_VERTICES,
            offset: 0,
            length: section_len(
                &format!("batch {b}: vertices"),
                vertex_count,
                layout::VERTEX_LEN as u64,
            )?,
        });
        sections.push(SectionPlan {
            kind: layout::SECTION_COEFFICIENTS,
            offset: 0,
            length: section_len(
                &format!("batch {b}: coefficients"),
                batch.coefficients.len() as u64,
                layout::scalar_size(batch.scalar),
            )?,
        });
        sections.push(SectionPlan {
            kind: layout::SECTION_INDICES,
            offset: 0,
            length: section_len(
                &format!("batch {b}: indices"),
                batch.indices.len() as u64,
                4,
            )?,
        });
        if batch.texturing.is_some() {
            sections.push(SectionPlan {
                kind: layout::SECTION_TEXTURED_VERTICES,
                offset: 0,
                length: section_len(
                    &format!("batch {b}: textured vertices"),
                    vertex_count,
                    layout::TEXTURED_VERTEX_LEN as u64,
                )?,
            });
        }
    }
    let mut texture_sections = Vec::with_capacity(solution.textures.len());
    for (k, texture) in solution.textures.iter().enumerate() {
        let bytes = match options.texture_sections.as_ref().and_then(|t| t.get(k)) {
            Some(raw) => raw.clone(),
            None => {
                let png =
                    super::texture::encode_png(texture).map_err(|reason| Problem::Texture {
                        texture: k as u32,
                        reason: format!("cannot encode it as PNG: {reason}"),
                    })?;
                super::texture::section_bytes(texture, &png)
            }
        };
        sections.push(SectionPlan {
            kind: layout::SECTION_TEXTURE,
            offset: 0,
            length: bytes.len() as u64,
        });
        texture_sections.push(bytes);
    }
    let (lights_section, environment_section) = plan_lighting(lighting, &mut sections);
    for (kind, bytes) in &options.extra_sections {
        sections.push(SectionPlan {
            kind: *kind,
            offset: 0,
            length: bytes.len() as u64,
        });
    }
    let too_many = |what: &str, n: usize| Problem::TooLarge {
        what: what.to_string(),
        value: n as u64,
        limit: u32::MAX.into(),
        reason: "the count is a u32 in the preamble",
    };
    if u32::try_from(solution.batches.len()).is_err() {
        return Err(too_many("the number of batches", solution.batches.len()));
    }
    if u32::try_from(sections.len()).is_err() {
        return Err(too_many("the number of sections", sections.len()));
    }
    let metadata_len = layout::PREAMBLE_LEN
        + header_len
        + batch_entry_len * solution.batches.len()
        + section_entry_len * sections.len();
    let overflow = || Problem::TooLarge {
        what: "the file length".into(),
        value: u64::MAX,
        limit: u64::MAX,
        reason: "its sections do not fit in 64-bit offsets",
    };
    let mut end = metadata_len as u64;
    for section in &mut sections {
        section.offset = layout::align_up(end).ok_or_else(overflow)?;
        end = section
            .offset
            .checked_add(section.length)
            .ok_or_else(overflow)?;
    }
    Ok(Plan {
        major,
        minor,
        lights_section,
        environment_section,
        batch_sections,
        texture_sections,
        header_len,
        batch_entry_len,
        section_entry_len,
        metadata_len,
        sections,
        file_len: end,
    })
}

/// Appends the lights and environment sections (minor version 1) and returns
/// their indices, [`layout::NO_SECTION`] for each one absent.
fn plan_lighting(
    lighting: Option<&super::Lighting>,
    sections: &mut Vec<SectionPlan>,
) -> (u32, u32) {
    let mut indices = (layout::NO_SECTION, layout::NO_SECTION);
    let Some(l) = lighting else {
        return indices;
    };
    if let Some(json) = &l.lights_json {
        indices.0 = sections.len() as u32;
        sections.push(SectionPlan {
            kind: layout::SECTION_LIGHTS,
            offset: 0,
            length: json.len() as u64,
        });
    }
    if let Some(env) = &l.environment {
        indices.1 = sections.len() as u32;
        sections.push(SectionPlan {
            kind: layout::SECTION_ENVIRONMENT,
            offset: 0,
            length: super::lighting::environment_section_len(env),
        });
    }
    indices
}

/// Streams sections through a fixed-size buffer, hashing what it writes and
/// tracking the position so padding can be inserted without seeking.
struct SectionStream<'w, W: Write> {
    out: &'w mut W,
    position: u64,
    buffer: Vec<u8>,
    hasher: crc32fast::Hasher,
}

const CHUNK: usize = 1 << 16;

impl<W: Write> SectionStream<'_, W> {
    fn pad_to(&mut self, offset: u64) -> std::io::Result<()> {
        let zeros = [0u8; layout::SECTION_ALIGN as usize];
        while self.position < offset {
            let n = (offset - self.position).min(zeros.len() as u64) as usize;
            self.out.write_all(&zeros[..n])?;
            self.position += n as u64;
        }
        Ok(())
    }

    fn push(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.buffer.extend_from_slice(bytes);
        if self.buffer.len() >= CHUNK {
            self.flush_buffer()?;
        }
        Ok(())
    }

    /// Appends the little-endian bytes of each item, a chunk at a time (one
    /// capacity check and one flush test per chunk rather than per value).
    fn push_each<T: Copy, const N: usize>(
        &mut self,
        items: &[T],
        to_bytes: impl Fn(T) -> [u8; N],
    ) -> std::io::Result<()> {
        for chunk in items.chunks(CHUNK / N) {
            self.buffer
                .extend(chunk.iter().flat_map(|&item| to_bytes(item)));
            if self.buffer.len() >= CHUNK {
                self.flush_buffer()?;
            }
        }
        Ok(())
    }

    fn flush_buffer(&mut self) -> std::io::Result<()> {
        self.hasher.update(&self.buffer);
        self.out.write_all(&self.buffer)?;
        self.position += self.buffer.len() as u64;
        self.buffer.clear();
        Ok(())
    }

    /// Ends the current section and returns its CRC-32.
    fn finish_section(&mut self) -> std::io::Result<u32> {
        self.flush_buffer()?;
        Ok(std::mem::take(&mut self.hasher).finalize())
    }
}

fn write_planned<W: Write + Seek>(
    out: &mut W,
    solution: &Solution,
    plan: &Plan,
    options: &EncodeOptions,
) -> std::io::Result<()> {
    // A zeroed placeholder for the metadata; it is written for real at the end,
    // once the section checksums are known.
    out.write_all(&vec![0u8; plan.metadata_len])?;
    let mut stream = SectionStream {
        out,
        position: plan.metadata_len as u64,
        buffer: Vec::with_capacity(CHUNK + 64),
        hasher: crc32fast::Hasher::new(),
    };
    let mut crcs = Vec::with_capacity(plan.sections.len());
    let mut sections = plan.sections.iter();
    let mut next_offset = || sections.next().map_or(0, |s| s.offset);

    stream.pad_to(next_offset())?;
    stream.push(solution.header.settings_json.as_bytes())?;
    crcs.push(stream.finish_section()?);
    for batch in &solution.batches {
        stream.pad_to(next_offset())?;
        stream.push_each(&batch.vertices, |v| {
            let mut bytes = [0u8; layout::VERTEX_LEN];
            let mut f = FieldsMut::new(&mut bytes);
            f.f32x3(0, v.position);
            f.f32x3(12, v.normal);
            f.f32x3(24, v.tangent);
            bytes
        })?;
        crcs.push(stream.finish_section()?);

        stream.pad_to(next_offset())?;
        match batch.scalar {
            ScalarType::F32 => stream.push_each(&batch.coefficients, f32::to_le_bytes)?,
            ScalarType::F16 { scale } => stream.push_each(&batch.coefficients, |c| {
                half::f16::from_f32(c / scale).to_le_bytes()
            })?,
        }
        crcs.push(stream.finish_section()?);

        stream.pad_to(next_offset())?;
        stream.push_each(&batch.indices, u32::to_le_bytes)?;
        crcs.push(stream.finish_section()?);

        if let Some(t) = &batch.texturing {
            stream.pad_to(next_offset())?;
            stream.push_each(&t.vertices, |tv| {
                let mut bytes = [0u8; layout::TEXTURED_VERTEX_LEN];
                let mut f = FieldsMut::new(&mut bytes);
                f.f32(0, tv.uv[0]);
                f.f32(4, tv.uv[1]);
                f.f32x3(8, tv.irradiance_over_pi);
                bytes
            })?;
            crcs.push(stream.finish_section()?);
        }
    }
    for bytes in &plan.texture_sections {
        stream.pad_to(next_offset())?;
        stream.push(bytes)?;
        crcs.push(stream.finish_section()?);
    }
    if let Some(l) = solution.lighting.as_ref().filter(|l| !l.is_empty()) {
        if let Some(json) = &l.lights_json {
            stream.pad_to(next_offset())?;
            stream.push(json.as_bytes())?;
            crcs.push(stream.finish_section()?);
        }
        if let Some(env) = &l.environment {
            stream.pad_to(next_offset())?;
            stream.push(&super::lighting::environment_section_bytes(env))?;
            crcs.push(stream.finish_section()?);
        }
    }
    for (_, bytes) in &options.extra_sections {
        stream.pad_to(next_offset())?;
        stream.push(bytes)?;
        crcs.push(stream.finish_section()?);
    }
    debug_assert_eq!(stream.position, plan.file_len);

    let metadata = metadata_bytes(solution, plan, &crcs);
    out.seek(SeekFrom::Start(0))?;
    out.write_all(&metadata)?;
    out.flush()
}

fn metadata_bytes(solution: &Solution, plan: &Plan, crcs: &[u32]) -> Vec<u8> {
    use layout::{batch as bf, header as hf, preamble as pf, section as sf};
    let mut metadata = vec![0u8; plan.metadata_len];

    let (pre, rest) = metadata.split_at_mut(layout::PREAMBLE_LEN);
    let mut p = FieldsMut::new(pre);
    p.u16(pf::VERSION_MAJOR, plan.major);
    p.u16(pf::VERSION_MINOR, plan.minor);
    p.u64(pf::FILE_LENGTH, plan.file_len);
    p.u64(pf::METADATA_LENGTH, plan.metadata_len as u64);
    p.u32(pf::HEADER_LENGTH, plan.header_len as u32);
    p.u32(pf::BATCH_COUNT, solution.batches.len() as u32);
    p.u32(pf::BATCH_ENTRY_LENGTH, plan.batch_entry_len as u32);
    p.u32(pf::SECTION_COUNT, plan.sections.len() as u32);
    p.u32(pf::SECTION_ENTRY_LENGTH, plan.section_entry_len as u32);
    pre[pf::MAGIC..pf::MAGIC + 8].copy_from_slice(&layout::MAGIC);

    let (head, rest) = rest.split_at_mut(plan.header_len);
    let h = &solution.header;
    let mut f = FieldsMut::new(head);
    f.f64(hf::UNITS_PER_METRE, h.units_per_metre);
    f.f64x3(hf::RECENTRE_OFFSET, h.recentre_offset);
    f.f64x3(hf::CAMERA_EYE, h.camera.eye);
    f.f64x3(hf::CAMERA_TARGET, h.camera.target);
    f.f64x3(hf::CAMERA_UP, h.camera.up);
    f.f64(hf::CAMERA_FOV_Y_DEG, h.camera.fov_y_deg);
    f.u32(hf::CAMERA_WIDTH, h.camera.width);
    f.u32(hf::CAMERA_HEIGHT, h.camera.height);
    f.f32x3(hf::BOUNDS_MIN, h.bounds_min);
    f.f32x3(hf::BOUNDS_MAX, h.bounds_max);
    f.u32(hf::UP_AXIS, h.up_axis.code());
    f.u32(hf::MODE, layout::mode_code(h.mode));
    f.u32(hf::PARTIAL, u32::from(h.partial));
    f.u32(hf::SETTINGS_SECTION, 0);
    f.u64(hf::SHOTS, h.stats.shots);
    f.u64(hf::RAYS, h.stats.rays);
    f.f64(hf::SECONDS, h.stats.seconds);
    f.f64(hf::UNSHOT_FRACTION, h.stats.unshot_fraction);
    f.f64(hf::EMITTED_POWER, h.stats.emitted_power);
    f.f32x3(hf::AMBIENT, h.stats.ambient);
    if plan.minor >= layout::LIGHTING_VERSION_MINOR {
        let key = solution.lighting.as_ref().map_or(0.0, |l| l.exposure_key);
        f.f32(hf::EXPOSURE_KEY, key);
        f.u32(hf::LIGHTS_SECTION, plan.lights_section);
        f.u32(hf::ENVIRONMENT_SECTION, plan.environment_section);
    }

    let (batch_table, section_table) =
        rest.split_at_mut(plan.batch_entry_len * solution.batches.len());
    for ((batch, entry), refs) in solution
        .batches
        .iter()
        .zip(batch_table.chunks_exact_mut(plan.batch_entry_len))
        .zip(&plan.batch_sections)
    {
        let (repr, parameter) = layout::representation_code(batch.representation);
        let (scalar, scale) = layout::scalar_code(batch.scalar);
        let mut f = FieldsMut::new(entry);
        f.u32(bf::REPRESENTATION, repr);
        f.u32(bf::REPRESENTATION_PARAMETER, parameter);
        f.u32(bf::SCALAR, scalar);
        f.f32(bf::SCALE, scale);
        f.u32(bf::FRAME_CONVENTION, layout::FRAME_POLYGON_NTB);
        f.u32(
            bf::BASIS_CONVENTION,
            layout::basis_convention(batch.representation),
        );
        f.u64(bf::VERTEX_COUNT, batch.vertices.len() as u64);
        f.u64(bf::INDEX_COUNT, batch.indices.len() as u64);
        f.u32(bf::VERTICES_SECTION, refs[0]);
        f.u32(bf::COEFFICIENTS_SECTION, refs[1]);
        f.u32(bf::INDICES_SECTION, refs[2]);
        if plan.major >= 2 {
            let texture = batch.texturing.as_ref();
            f.u32(
                bf::TEXTURE,
                texture.map_or(layout::NO_TEXTURE, |t| t.texture),
            );
            f.u32(bf::TEXTURED_VERTICES_SECTION, refs[3]);
            f.f32x3(bf::TEXTURE_FACTOR, texture.map_or([0.0; 3], |t| t.factor));
        }
        if plan.major >= 3 {
            let slot = batch.texturing.as_ref().and_then(|t| t.emission);
            f.u32(
                bf::EMISSION_TEXTURE,
                slot.map_or(layout::NO_TEXTURE, |s| s.texture),
            );
            f.f32x3(bf::EMISSION_FACTOR, slot.map_or([0.0; 3], |s| s.factor));
        }
    }
    for ((section, crc), entry) in plan
        .sections
        .iter()
        .zip(crcs)
        .zip(section_table.chunks_exact_mut(plan.section_entry_len))
    {
        let mut f = FieldsMut::new(entry);
        f.u32(sf::KIND, section.kind);
        f.u32(sf::CRC, *crc);
        f.u64(sf::OFFSET, section.offset);
        f.u64(sf::LENGTH, section.length);
    }

    let crc = layout::metadata_crc(&metadata);
    FieldsMut::new(&mut metadata).u32(pf::METADATA_CRC, crc);
    metadata
}
