//! The validating reader: [`decode`], [`read_solution`] and [`MappedSolution`].
//!
//! [`parse`] checks a whole file in this order, and nothing it allocates is sized
//! by an unchecked number:
//!
//! 1. length ≥ the preamble, magic, major version, the declared file length
//!    against the real one;
//! 2. the metadata length against the file, then the metadata CRC (so every count
//!    and offset read afterwards is what the writer wrote);
//! 3. block lengths and counts against the metadata length (checked arithmetic:
//!    `count × entry length ≤ metadata length ≤ file length`), header values,
//!    codes, section references;
//! 4. section alignment, bounds (in u128, so no sum can wrap), overlap, zero
//!    padding; vertex, coefficient and index counts against section lengths;
//! 5. section CRCs; then the content: UTF-8 settings, finite values, orthonormal
//!    frames, positions inside the header bounds, indices below the vertex count.
//!
//! Each stage is one function, in the submodule of its job: `metadata`
//! (`read_preamble`, `checked_metadata`, `block_layout`, `read_header`),
//! `sections` (`read_section_table`, `check_placement`, `check_section_sizes`,
//! `check_checksums`), `batch_table` (`read_batch_table`) and `content`
//! (`check_content`); `mapped` holds [`MappedSolution`]. The per-frame cost bound ([`super::check_frame_cost`]) is
//! not a reader check: the runtime applies it with the user's limit.
//!
//! The only vectors it allocates hold one element per batch or per section (each
//! ≤ the file length divided by that entry's on-disk size), and the settings text
//! (≤ its section's length). Materializing a [`Solution`] then allocates per
//! vertex, coefficient and index at most 2× the bytes those sections occupy (f16
//! coefficients widen to f32). So no allocation exceeds a small multiple of the
//! file's real length, whatever the header claims.

use super::error::{FormatError, Problem};
use super::layout;
use super::texture::{self, TextureInfo};
use super::validate;
use super::Lighting;
use super::{Batch, Header, Representation, ScalarType, Solution, Texture, TextureSlot, Texturing};
use batch_table::read_batch_table;
use content::{check_content, textured_vertex_at, vertex_at};
use lighting::{claim_lighting, read_lighting};
use metadata::{block_layout, checked_metadata, read_header, read_preamble};
use sections::{
    check_checksums, check_every_section_used, check_placement, check_section_sizes,
    check_textures, claim_textures, read_section_table, settings_text, Role,
};
use std::ops::Range;
use std::path::Path;

mod batch_table;
mod content;
mod lighting;
mod mapped;
mod metadata;
mod sections;

pub use mapped::{BatchSection, MappedSolution};

/// What a batch holds, as the runtime needs it to size buffers and pick shaders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BatchInfo {
    pub representation: Representation,
    /// For f16, the shader multiplies each stored half by `scale`.
    pub scalar: ScalarType,
    pub vertex_count: u32,
    pub index_count: u32,
    /// [`layout::FRAME_POLYGON_NTB`] in version 1.
    pub frame_convention: u32,
    /// [`layout::BASIS_SH_REAL_ORTHONORMAL`] or [`layout::BASIS_CUBE_CELL_CENTRES`].
    pub basis_convention: u32,
    /// `Some` for a textured batch (format 2): radiance is the coefficients'
    /// term plus `factor ⊙ ρ(uv) ⊙ E/π` (see [`super::Texturing`]).
    pub texture: Option<BatchTexture>,
}

/// A textured batch's texture index and factor, as the batch table stores them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BatchTexture {
    /// Index into [`MappedSolution::textures`].
    pub texture: u32,
    /// Linear RGB multiplier of the decoded texture.
    pub factor: [f32; 3],
    /// The second slot (format 3): an emission texture and its factor, added
    /// as `factor ⊙ ρ_e(uv)` (see [`super::Texturing::emission`]).
    pub emission: Option<TextureSlot>,
}

impl BatchInfo {
    pub fn coefficients_per_channel(&self) -> u64 {
        self.representation.coefficients_per_channel()
    }
    /// Coefficients in the batch: vertices × per channel × 3.
    pub fn coefficient_count(&self) -> u64 {
        u64::from(self.vertex_count) * self.coefficients_per_channel() * 3
    }
    pub fn coefficient_bytes(&self) -> u64 {
        self.coefficient_count() * layout::scalar_size(self.scalar)
    }
    pub fn vertex_bytes(&self) -> u64 {
        u64::from(self.vertex_count) * layout::VERTEX_LEN as u64
    }
    pub fn index_bytes(&self) -> u64 {
        u64::from(self.index_count) * 4
    }
    /// Bytes of the batch's UV + E/π section (0 when untextured).
    pub fn textured_vertex_bytes(&self) -> u64 {
        if self.texture.is_some() {
            u64::from(self.vertex_count) * layout::TEXTURED_VERTEX_LEN as u64
        } else {
            0
        }
    }
    pub fn triangle_count(&self) -> u32 {
        self.index_count / 3
    }
}

/// A validated file: everything but the bulk data, plus where the bulk data is.
#[derive(Clone, Debug)]
pub(crate) struct Parsed {
    pub version: (u16, u16),
    pub file_len: u64,
    pub header: Header,
    pub batches: Vec<BatchInfo>,
    /// Byte ranges of each batch's vertices, coefficients, indices and textured
    /// vertices (empty when untextured).
    pub ranges: Vec<[Range<usize>; 4]>,
    /// Section index and stored CRC of each of those (`usize::MAX` and 0 for
    /// a missing textured-vertices section).
    pub batch_sections: Vec<[(usize, u32); 4]>,
    pub textures: Vec<TextureInfo>,
    /// Byte range (the encoded image, after the prefix), section index and
    /// stored CRC of each texture section.
    pub texture_sections: Vec<(Range<usize>, usize, u32)>,
    /// Minor version 1: the exposure key, lights and environment, read and
    /// checked in full (they are small).
    pub lighting: Option<Lighting>,
}

/// Validates the bytes of a whole solution file, stage by stage (see the module
/// documentation for the order of the checks).
pub(crate) fn parse(bytes: &[u8]) -> Result<Parsed, Problem> {
    parse_checking(bytes, true)
}

/// [`parse`], optionally leaving out the CRC-32 of the batches' vertex,
/// coefficient and index sections (the settings section is always checked) and
/// the finite-value check of the coefficients, the file's bulk:
/// [`MappedSolution::open_deferring_checksums`] verifies those as the runtime
/// streams them to the GPU ([`MappedSolution::verify_section`],
/// [`MappedSolution::verify_finite_coefficients`]).
fn parse_checking(bytes: &[u8], batch_checksums: bool) -> Result<Parsed, Problem> {
    let preamble = read_preamble(bytes)?;
    let metadata = checked_metadata(bytes, &preamble)?;
    let blocks = block_layout(&preamble, metadata.len() as u64)?;
    let (mut header, settings_section) =
        read_header(&metadata[blocks.header.clone()], preamble.newer)?;
    let mut sections = read_section_table(&metadata[blocks.sections.clone()], &blocks)?;
    sections.claim(settings_section, Role::Settings, layout::SECTION_SETTINGS)?;
    let lighting_refs = claim_lighting(&metadata[blocks.header.clone()], &blocks, &mut sections)?;
    let texture_indices = claim_textures(&mut sections, blocks.major)?;
    let (batches, batch_sections) = read_batch_table(
        &metadata[blocks.batches.clone()],
        &blocks,
        &mut sections,
        texture_indices.len() as u64,
    )?;
    if !blocks.newer {
        check_every_section_used(&sections)?;
    }
    check_placement(bytes, metadata.len() as u64, &sections)?;
    check_section_sizes(&batches, &batch_sections, &sections)?;
    check_checksums(bytes, &sections, batch_checksums)?;
    header.settings_json = settings_text(bytes, &sections, settings_section as usize)?;
    let lighting = read_lighting(bytes, &sections, lighting_refs, blocks.newer)?;
    let (textures, texture_sections) = check_textures(
        bytes,
        &sections,
        &texture_indices,
        blocks.newer,
        batch_checksums,
    )?;
    let slack = validate::bounds_slack(&header);
    let mut ranges = Vec::with_capacity(batches.len());
    let mut refs_and_crcs = Vec::with_capacity(batches.len());
    for (b, (info, refs)) in batches.iter().zip(&batch_sections).enumerate() {
        let range = refs.map(|section| sections.range(section));
        check_content(b, info, bytes, &range, &header, slack, batch_checksums)?;
        ranges.push(range);
        refs_and_crcs.push(refs.map(|section| (section, sections.crc(section))));
    }
    Ok(Parsed {
        version: (preamble.major, preamble.minor),
        file_len: bytes.len() as u64,
        header,
        batches,
        ranges,
        batch_sections: refs_and_crcs,
        textures,
        texture_sections,
        lighting,
    })
}

/// Builds the in-memory solution from validated bytes. Only decoding a texture
/// can fail (the file was changed after validation, or it was opened without
/// decoding): `parse` checked every range, and slicing uses `get` so that even
/// bytes changed after validation (see [`MappedSolution`]) cannot make it panic.
pub(crate) fn materialize(bytes: &[u8], parsed: &Parsed) -> Result<Solution, Problem> {
    let section = |r: &Range<usize>| bytes.get(r.clone()).unwrap_or(&[]);
    let batches = parsed
        .batches
        .iter()
        .zip(&parsed.ranges)
        .map(|(info, [v, c, i, t])| {
            let vertices = section(v)
                .chunks_exact(layout::VERTEX_LEN)
                .map(vertex_at)
                .collect();
            let coefficients = match info.scalar {
                ScalarType::F32 => section(c)
                    .chunks_exact(4)
                    .map(|x| f32::from_le_bytes([x[0], x[1], x[2], x[3]]))
                    .collect(),
                ScalarType::F16 { scale } => section(c)
                    .chunks_exact(2)
                    .map(|x| half::f16::from_le_bytes([x[0], x[1]]).to_f32() * scale)
                    .collect(),
            };
            let indices = section(i)
                .chunks_exact(4)
                .map(|x| u32::from_le_bytes([x[0], x[1], x[2], x[3]]))
                .collect();
            let texturing = info.texture.map(|bt| Texturing {
                texture: bt.texture,
                factor: bt.factor,
                emission: bt.emission,
                vertices: section(t)
                    .chunks_exact(layout::TEXTURED_VERTEX_LEN)
                    .map(textured_vertex_at)
                    .collect(),
            });
            Batch {
                representation: info.representation,
                scalar: info.scalar,
                vertices,
                coefficients,
                indices,
                texturing,
            }
        })
        .collect();
    let textures = parsed
        .textures
        .iter()
        .zip(&parsed.texture_sections)
        .enumerate()
        .map(|(k, (info, (range, _, _)))| {
            texture::decode_png(section(range), info.width, info.height).map_err(|reason| {
                Problem::Texture {
                    texture: k as u32,
                    reason,
                }
            })
        })
        .collect::<Result<Vec<Texture>, Problem>>()?;
    Ok(Solution {
        header: parsed.header.clone(),
        batches,
        textures,
        lighting: parsed.lighting.clone(),
    })
}

/// Decodes and validates the bytes of a solution file. f16 coefficients come back
/// as `half × scale` in f32.
pub fn decode(bytes: &[u8]) -> Result<Solution, FormatError> {
    let parsed = parse(bytes)?;
    Ok(materialize(bytes, &parsed)?)
}

/// Reads and validates a solution file into memory.
pub fn read_solution(path: &Path) -> Result<Solution, FormatError> {
    let bytes = std::fs::read(path).map_err(|e| FormatError::io("read", path, e))?;
    let parsed = parse(&bytes).map_err(|p| FormatError::in_file(path, p))?;
    materialize(&bytes, &parsed).map_err(|p| FormatError::in_file(path, p))
}
