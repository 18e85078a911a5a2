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
//! Each stage is one function below (`read_preamble`, `checked_metadata`,
//! `block_layout`, `read_header`, `read_section_table`, `read_batch_table`,
//! `check_placement`, `check_section_sizes`, `check_checksums`,
//! `check_content`). The per-frame cost bound ([`super::check_frame_cost`]) is
//! not a reader check: the runtime applies it with the user's limit.
//!
//! The only vectors it allocates hold one element per batch or per section (each
//! ≤ the file length divided by that entry's on-disk size), and the settings text
//! (≤ its section's length). Materializing a [`Solution`] then allocates per
//! vertex, coefficient and index at most 2× the bytes those sections occupy (f16
//! coefficients widen to f32). So no allocation exceeds a small multiple of the
//! file's real length, whatever the header claims.

use super::error::{FormatError, Problem};
use super::layout::{self, Fields};
use super::texture::{self, TextureInfo};
use super::validate;
use super::{
    Batch, Header, Representation, ScalarType, Solution, SolveStats, Texture, TextureSlot,
    TexturedVertex, Texturing, Vertex,
};
use crate::camera::{Camera, UpAxis};
use std::ops::Range;
use std::path::{Path, PathBuf};

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
}

#[derive(Clone, Copy, Debug)]
struct SectionEntry {
    kind: u32,
    crc: u32,
    offset: u64,
    length: u64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Role {
    Unused,
    Settings,
    Vertices(usize),
    Coefficients(usize),
    Indices(usize),
    TexturedVertices(usize),
    Texture(usize),
}

fn role_name(role: Role) -> String {
    match role {
        Role::Unused => "unused".into(),
        Role::Settings => "settings".into(),
        Role::Vertices(b) => format!("vertices of batch {b}"),
        Role::Coefficients(b) => format!("coefficients of batch {b}"),
        Role::Indices(b) => format!("indices of batch {b}"),
        Role::TexturedVertices(b) => format!("textured vertices of batch {b}"),
        Role::Texture(k) => format!("texture {k}"),
    }
}

struct Sections {
    entries: Vec<SectionEntry>,
    roles: Vec<Role>,
}

impl Sections {
    /// "section 3 (coefficients of batch 1)".
    fn name(&self, index: usize) -> String {
        match (self.roles.get(index), self.entries.get(index)) {
            (Some(Role::Unused) | None, Some(e)) => format!(
                "section {index} (kind {} {}, unused)",
                e.kind,
                layout::section_kind_name(e.kind)
            ),
            (Some(role), _) => format!("section {index} ({})", role_name(*role)),
            (None, None) => format!("section {index}"),
        }
    }

    /// Assigns `role` to section `index`, checking that the section exists, has
    /// the expected kind and has no other role.
    fn claim(&mut self, index: u32, role: Role, kind: u32) -> Result<(), Problem> {
        let what = match role {
            Role::Settings => "header: settings section".to_string(),
            Role::Vertices(b) => format!("batch {b}: vertices section"),
            Role::Coefficients(b) => format!("batch {b}: coefficients section"),
            Role::Indices(b) => format!("batch {b}: indices section"),
            Role::TexturedVertices(b) => format!("batch {b}: textured vertices section"),
            Role::Texture(k) => format!("texture {k}"),
            Role::Unused => "a section reference".to_string(),
        };
        let i = index as usize;
        let Some(entry) = self.entries.get(i) else {
            return Err(Problem::MissingSection {
                what,
                index,
                count: self.entries.len() as u32,
            });
        };
        if entry.kind != kind {
            return Err(Problem::WrongSectionKind {
                what,
                index,
                kind: entry.kind,
                expected: kind,
                expected_name: layout::section_kind_name(kind),
            });
        }
        if self.roles[i] != Role::Unused {
            return Err(Problem::SectionReused {
                index,
                first: role_name(self.roles[i]),
                second: role_name(role),
            });
        }
        self.roles[i] = role;
        Ok(())
    }

    /// The stored CRC of a section (0 for a missing one).
    fn crc(&self, index: usize) -> u32 {
        self.entries.get(index).map_or(0, |e| e.crc)
    }

    /// The byte range of a section whose bounds `parse` has checked (empty for
    /// a missing one, `usize::MAX`).
    fn range(&self, index: usize) -> Range<usize> {
        self.entries.get(index).map_or(0..0, |e| {
            // Bounds were checked against the in-memory file, so both fit usize.
            e.offset as usize..(e.offset + e.length) as usize
        })
    }
}

/// Version-1.0 block sizes must match exactly; a newer minor version may make
/// them longer (appending fields this reader skips) but keeps them multiples of 8.
fn check_block_len(what: &str, value: u32, v1: usize, newer: bool) -> Result<usize, Problem> {
    let value_usize = value as usize;
    let ok = if newer {
        value_usize >= v1 && value_usize.is_multiple_of(8)
    } else {
        value_usize == v1
    };
    if ok {
        Ok(value_usize)
    } else {
        Err(Problem::BadLength {
            what: what.to_string(),
            value: value.into(),
            reason: if newer {
                format!("a newer minor version may only extend it from {v1} in steps of 8")
            } else {
                format!("it is {v1} in this format version")
            },
        })
    }
}

fn reserved(field: &str, value: u64, newer: bool) -> Result<(), Problem> {
    if value != 0 && !newer {
        return Err(Problem::Reserved {
            field: field.to_string(),
            value,
        });
    }
    Ok(())
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
    })
}

/// Stage 3, textures (format 2): every section of the texture kind is a
/// texture, numbered in section-table order; returns their section indices.
fn claim_textures(sections: &mut Sections, major: u16) -> Result<Vec<usize>, Problem> {
    if major < 2 {
        return Ok(Vec::new());
    }
    let indices: Vec<usize> = (0..sections.entries.len())
        .filter(|&i| sections.entries[i].kind == layout::SECTION_TEXTURE)
        .collect();
    for (k, &i) in indices.iter().enumerate() {
        sections.claim(i as u32, Role::Texture(k), layout::SECTION_TEXTURE)?;
    }
    Ok(indices)
}

/// Stage 5, textures: each section's prefix and PNG header
/// ([`texture::check_section`]), the decoded total against
/// [`layout::MAX_DECODED_TEXTURE_BYTES`], and, when `decode` (every check, not the
/// deferring open), a full decode of each image.
#[allow(clippy::type_complexity)]
fn check_textures(
    bytes: &[u8],
    sections: &Sections,
    indices: &[usize],
    newer: bool,
    decode: bool,
) -> Result<(Vec<TextureInfo>, Vec<(Range<usize>, usize, u32)>), Problem> {
    let mut infos = Vec::with_capacity(indices.len());
    let mut ranges = Vec::with_capacity(indices.len());
    let mut decoded = 0u64;
    for (k, &i) in indices.iter().enumerate() {
        let range = sections.range(i);
        let info = texture::check_section(k as u32, &bytes[range.clone()], newer)?;
        decoded = decoded.saturating_add(info.decoded_bytes());
        validate::check_decoded_texture_bytes(decoded)?;
        let png = range.start + layout::TEXTURE_PREFIX_LEN..range.end;
        if decode {
            texture::decode_png(&bytes[png.clone()], info.width, info.height).map_err(
                |reason| Problem::Texture {
                    texture: k as u32,
                    reason,
                },
            )?;
        }
        infos.push(info);
        ranges.push((png, i, sections.crc(i)));
    }
    Ok((infos, ranges))
}

/// The preamble's fields once stage 1 has accepted them.
struct Preamble<'a> {
    fields: Fields<'a>,
    /// 1 or 2.
    major: u16,
    minor: u16,
    /// The file's minor version is newer than this reader's.
    newer: bool,
}

/// Stage 1: is it ours, which version, is it whole?
fn read_preamble(bytes: &[u8]) -> Result<Preamble<'_>, Problem> {
    use layout::preamble as pf;
    let len = bytes.len() as u64;
    let Some(fields) = bytes
        .get(..layout::PREAMBLE_LEN)
        .and_then(|b| Fields::new(b, layout::PREAMBLE_LEN))
    else {
        return Err(Problem::TooShort {
            len,
            min: layout::PREAMBLE_LEN as u64,
        });
    };
    let mut magic = [0u8; 8];
    magic.copy_from_slice(&bytes[pf::MAGIC..pf::MAGIC + 8]);
    if magic != layout::MAGIC {
        return Err(Problem::BadMagic {
            found: magic,
            expected: layout::MAGIC,
        });
    }
    let major = fields.u16(pf::VERSION_MAJOR);
    let minor = fields.u16(pf::VERSION_MINOR);
    if !(layout::UNTEXTURED_VERSION_MAJOR..=layout::VERSION_MAJOR).contains(&major) {
        return Err(Problem::UnsupportedVersion {
            major,
            minor,
            known_major: layout::VERSION_MAJOR,
            known_minor: layout::VERSION_MINOR,
        });
    }
    let declared = fields.u64(pf::FILE_LENGTH);
    if declared != len {
        return Err(Problem::LengthMismatch {
            declared,
            actual: len,
        });
    }
    Ok(Preamble {
        fields,
        major,
        minor,
        newer: minor > layout::VERSION_MINOR,
    })
}

/// Stage 2: the metadata region (preamble, header, tables) lies inside the file
/// and its checksum matches, so every count and offset read from it afterwards is
/// what the writer wrote.
fn checked_metadata<'a>(bytes: &'a [u8], preamble: &Preamble<'_>) -> Result<&'a [u8], Problem> {
    use layout::preamble as pf;
    let len = bytes.len() as u64;
    let metadata_len = preamble.fields.u64(pf::METADATA_LENGTH);
    if metadata_len < layout::PREAMBLE_LEN as u64 {
        return Err(Problem::BadLength {
            what: "the metadata length".into(),
            value: metadata_len,
            reason: format!("it includes the {}-byte preamble", layout::PREAMBLE_LEN),
        });
    }
    if metadata_len > len {
        return Err(Problem::OutOfBounds {
            what: "the header and tables".into(),
            end: metadata_len.into(),
            len,
        });
    }
    let metadata = &bytes[..metadata_len as usize];
    let stored = preamble.fields.u32(pf::METADATA_CRC);
    let computed = layout::metadata_crc(metadata);
    if stored != computed {
        return Err(Problem::Checksum {
            what: format!("the header and tables (bytes 0..{metadata_len})"),
            stored,
            computed,
        });
    }
    Ok(metadata)
}

/// Where the header and the two tables lie inside the metadata, and their entry
/// sizes.
struct Blocks {
    header: Range<usize>,
    batches: Range<usize>,
    sections: Range<usize>,
    batch_entry_len: usize,
    section_entry_len: usize,
    section_count: u32,
    major: u16,
    newer: bool,
}

/// Stage 3, first part: block lengths and counts must tile the metadata exactly
/// (summed in u128, so no hostile count can wrap), and the preamble's reserved
/// words must be zero.
fn block_layout(preamble: &Preamble<'_>, metadata_len: u64) -> Result<Blocks, Problem> {
    use layout::preamble as pf;
    let (pre, newer) = (&preamble.fields, preamble.newer);
    let header_len = check_block_len(
        "the header length",
        pre.u32(pf::HEADER_LENGTH),
        layout::HEADER_LEN,
        newer,
    )?;
    let batch_entry_len = check_block_len(
        "the batch entry length",
        pre.u32(pf::BATCH_ENTRY_LENGTH),
        layout::batch_entry_len(preamble.major),
        newer,
    )?;
    let section_entry_len = check_block_len(
        "the section entry length",
        pre.u32(pf::SECTION_ENTRY_LENGTH),
        layout::SECTION_ENTRY_LEN,
        newer,
    )?;
    let batch_count = pre.u32(pf::BATCH_COUNT);
    let section_count = pre.u32(pf::SECTION_COUNT);
    let expected_metadata = layout::PREAMBLE_LEN as u128
        + header_len as u128
        + u128::from(batch_count) * batch_entry_len as u128
        + u128::from(section_count) * section_entry_len as u128;
    if expected_metadata != u128::from(metadata_len) {
        return Err(Problem::BadLength {
            what: "the metadata length".into(),
            value: metadata_len,
            reason: format!(
                "a {header_len}-byte header, {batch_count} batch entries of {batch_entry_len} bytes and {section_count} section entries of {section_entry_len} bytes take {expected_metadata}"
            ),
        });
    }
    reserved(
        "the preamble's reserved word at byte 52",
        pre.u32(pf::RESERVED_0).into(),
        newer,
    )?;
    reserved(
        "the preamble's reserved word at byte 56",
        pre.u64(pf::RESERVED_1),
        newer,
    )?;
    // Every block lies inside the metadata because the sum above matched.
    let header_start = layout::PREAMBLE_LEN;
    let batches_start = header_start + header_len;
    let sections_start = batches_start + batch_count as usize * batch_entry_len;
    Ok(Blocks {
        header: header_start..batches_start,
        batches: batches_start..sections_start,
        sections: sections_start..metadata_len as usize,
        batch_entry_len,
        section_entry_len,
        section_count,
        major: preamble.major,
        newer,
    })
}

/// Stage 3, the header: codes, reserved word and every value
/// ([`validate::check_header`]). Returns the header (settings text still empty)
/// and the index of its settings section.
fn read_header(block: &[u8], newer: bool) -> Result<(Header, u32), Problem> {
    use layout::header as hf;
    let hb = Fields::new(block, layout::HEADER_LEN).ok_or_else(|| Problem::BadLength {
        what: "the header length".into(),
        value: block.len() as u64,
        reason: "shorter than version 1.0's header".into(),
    })?;
    let up_code = hb.u32(hf::UP_AXIS);
    let up_axis = UpAxis::from_code(up_code).ok_or_else(|| Problem::UnknownCode {
        field: "header: up axis".into(),
        code: up_code,
    })?;
    let mode_code = hb.u32(hf::MODE);
    let mode = layout::mode_from_code(mode_code).ok_or_else(|| Problem::UnknownCode {
        field: "header: solve mode".into(),
        code: mode_code,
    })?;
    let partial = match hb.u32(hf::PARTIAL) {
        0 => false,
        1 => true,
        code => {
            return Err(Problem::UnknownCode {
                field: "header: partial flag (0 or 1)".into(),
                code,
            })
        }
    };
    reserved("header: reserved word", hb.u32(hf::RESERVED).into(), newer)?;
    let header = Header {
        units_per_metre: hb.f64(hf::UNITS_PER_METRE),
        up_axis,
        recentre_offset: hb.f64x3(hf::RECENTRE_OFFSET),
        camera: Camera {
            eye: hb.f64x3(hf::CAMERA_EYE),
            target: hb.f64x3(hf::CAMERA_TARGET),
            up: hb.f64x3(hf::CAMERA_UP),
            fov_y_deg: hb.f64(hf::CAMERA_FOV_Y_DEG),
            width: hb.u32(hf::CAMERA_WIDTH),
            height: hb.u32(hf::CAMERA_HEIGHT),
        },
        bounds_min: hb.f32x3(hf::BOUNDS_MIN),
        bounds_max: hb.f32x3(hf::BOUNDS_MAX),
        partial,
        mode,
        stats: SolveStats {
            shots: hb.u64(hf::SHOTS),
            rays: hb.u64(hf::RAYS),
            seconds: hb.f64(hf::SECONDS),
            unshot_fraction: hb.f64(hf::UNSHOT_FRACTION),
            emitted_power: hb.f64(hf::EMITTED_POWER),
            ambient: hb.f32x3(hf::AMBIENT),
        },
        settings_json: String::new(),
    };
    validate::check_header(&header)?;
    Ok((header, hb.u32(hf::SETTINGS_SECTION)))
}

/// Stage 3, the section table: known kinds, zero reserved fields. Every section
/// starts unused; the header and batches claim theirs.
fn read_section_table(table: &[u8], blocks: &Blocks) -> Result<Sections, Problem> {
    use layout::section as sf;
    // The table's length was checked against the metadata: section_count entries.
    let mut entries = Vec::with_capacity(blocks.section_count as usize);
    for (i, raw) in table.chunks_exact(blocks.section_entry_len).enumerate() {
        let f = Fields::new(raw, layout::SECTION_ENTRY_LEN).ok_or_else(|| Problem::BadLength {
            what: "the section entry length".into(),
            value: blocks.section_entry_len as u64,
            reason: "shorter than version 1.0's entry".into(),
        })?;
        let kind = f.u32(sf::KIND);
        let known = layout::SECTION_SETTINGS..=layout::last_section_kind(blocks.major);
        if !known.contains(&kind) && !blocks.newer {
            return Err(Problem::UnknownCode {
                field: format!("section {i}: kind"),
                code: kind,
            });
        }
        reserved(
            &format!("section {i}: reserved field"),
            f.u64(sf::RESERVED),
            blocks.newer,
        )?;
        entries.push(SectionEntry {
            kind,
            crc: f.u32(sf::CRC),
            offset: f.u64(sf::OFFSET),
            length: f.u64(sf::LENGTH),
        });
    }
    Ok(Sections {
        roles: vec![Role::Unused; entries.len()],
        entries,
    })
}

/// Stage 3, the batch table: each entry ([`read_batch_entry`]) with the indices of
/// its vertices, coefficients and indices sections.
fn read_batch_table(
    table: &[u8],
    blocks: &Blocks,
    sections: &mut Sections,
    texture_count: u64,
) -> Result<(Vec<BatchInfo>, Vec<[usize; 4]>), Problem> {
    let count = table.len() / blocks.batch_entry_len.max(1);
    let mut batches = Vec::with_capacity(count);
    let mut batch_sections = Vec::with_capacity(count);
    for (b, raw) in table.chunks_exact(blocks.batch_entry_len).enumerate() {
        let f = Fields::new(raw, layout::BATCH_ENTRY_LEN).ok_or_else(|| Problem::BadLength {
            what: "the batch entry length".into(),
            value: blocks.batch_entry_len as u64,
            reason: "shorter than version 1.0's entry".into(),
        })?;
        let (info, refs) = read_batch_entry(b, &f, blocks, sections, texture_count)?;
        batches.push(info);
        batch_sections.push(refs);
    }
    Ok((batches, batch_sections))
}

/// One batch-table entry: representation, scalar type, conventions, counts, and
/// the sections it claims.
fn read_batch_entry(
    b: usize,
    f: &Fields<'_>,
    blocks: &Blocks,
    sections: &mut Sections,
    texture_count: u64,
) -> Result<(BatchInfo, [usize; 4]), Problem> {
    use layout::batch as bf;
    let representation = batch_representation(b, f)?;
    let scalar = batch_scalar(b, f)?;
    let (frame_convention, basis_convention) = batch_conventions(b, f, representation)?;
    let (texture, textured_vertices) = if blocks.major >= 2 {
        batch_texture(b, f, representation, texture_count, sections, blocks.major)?
    } else {
        reserved(
            &format!("batch {b}: reserved field"),
            f.u32(bf::RESERVED).into(),
            blocks.newer,
        )?;
        (None, usize::MAX)
    };
    let (vertex_count, index_count) = batch_counts(b, f)?;
    let refs = [
        (
            bf::VERTICES_SECTION,
            Role::Vertices(b),
            layout::SECTION_VERTICES,
        ),
        (
            bf::COEFFICIENTS_SECTION,
            Role::Coefficients(b),
            layout::SECTION_COEFFICIENTS,
        ),
        (
            bf::INDICES_SECTION,
            Role::Indices(b),
            layout::SECTION_INDICES,
        ),
    ];
    let mut indices = [0, 0, 0, textured_vertices];
    for (k, (at, role, kind)) in refs.into_iter().enumerate() {
        let index = f.u32(at);
        sections.claim(index, role, kind)?;
        indices[k] = index as usize;
    }
    let info = BatchInfo {
        representation,
        scalar,
        vertex_count,
        index_count,
        frame_convention,
        basis_convention,
        texture,
    };
    Ok((info, indices))
}

/// A format-2 batch entry's texture fields: [`layout::NO_TEXTURE`] twice and a
/// zero factor for an untextured batch; else a texture index below the file's
/// texture count ([`validate::check_batch_texture`]) and the claimed index of
/// its textured-vertices section (`usize::MAX` when untextured).
fn batch_texture(
    b: usize,
    f: &Fields<'_>,
    representation: Representation,
    texture_count: u64,
    sections: &mut Sections,
    major: u16,
) -> Result<(Option<BatchTexture>, usize), Problem> {
    use layout::batch as bf;
    let texture = f.u32(bf::TEXTURE);
    let section = f.u32(bf::TEXTURED_VERTICES_SECTION);
    let factor = f.f32x3(bf::TEXTURE_FACTOR);
    if texture == layout::NO_TEXTURE {
        if major >= 3 {
            check_empty_emission_slot(
                b,
                f.u32(bf::EMISSION_TEXTURE),
                f.f32x3(bf::EMISSION_FACTOR),
                "an untextured batch",
            )?;
        }
        if section != layout::NO_TEXTURE || factor.iter().any(|x| x.to_bits() != 0) {
            return Err(Problem::Invalid {
                what: format!(
                    "batch {b}: untextured, with textured-vertices section {section} and factor {factor:?}"
                ),
                reason: format!(
                    "an untextured batch stores {} and a zero factor",
                    layout::NO_TEXTURE
                ),
            });
        }
        return Ok((None, usize::MAX));
    }
    validate::check_batch_texture(b, representation, texture, texture_count, factor)?;
    let emission = if major >= 3 {
        emission_slot(b, f, texture_count)?
    } else {
        None
    };
    sections.claim(
        section,
        Role::TexturedVertices(b),
        layout::SECTION_TEXTURED_VERTICES,
    )?;
    Ok((
        Some(BatchTexture {
            texture,
            factor,
            emission,
        }),
        section as usize,
    ))
}

/// A format-3 batch entry's second slot: [`layout::NO_TEXTURE`] and a zero
/// factor when empty, else an emission texture index below the file's texture
/// count and a finite, non-negative factor ([`validate::check_emission_slot`]).
fn emission_slot(
    b: usize,
    f: &Fields<'_>,
    texture_count: u64,
) -> Result<Option<TextureSlot>, Problem> {
    use layout::batch as bf;
    let texture = f.u32(bf::EMISSION_TEXTURE);
    let factor = f.f32x3(bf::EMISSION_FACTOR);
    if texture == layout::NO_TEXTURE {
        return check_empty_emission_slot(b, texture, factor, "an empty emission slot");
    }
    let slot = TextureSlot { texture, factor };
    validate::check_emission_slot(b, &slot, texture_count)?;
    Ok(Some(slot))
}

/// An emission slot that must be empty (an untextured batch's, or one stored
/// as empty): [`layout::NO_TEXTURE`] and a zero factor.
fn check_empty_emission_slot(
    b: usize,
    texture: u32,
    factor: [f32; 3],
    what: &str,
) -> Result<Option<TextureSlot>, Problem> {
    if texture != layout::NO_TEXTURE || factor.iter().any(|x| x.to_bits() != 0) {
        return Err(Problem::Invalid {
            what: format!("batch {b}: emission texture {texture} with factor {factor:?}"),
            reason: format!(
                "{what} stores {} and a zero factor, and only a textured batch may have an emission texture",
                layout::NO_TEXTURE
            ),
        });
    }
    Ok(None)
}

fn batch_representation(b: usize, f: &Fields<'_>) -> Result<Representation, Problem> {
    use layout::batch as bf;
    let parameter = f.u32(bf::REPRESENTATION_PARAMETER);
    let representation = match f.u32(bf::REPRESENTATION) {
        layout::REPRESENTATION_SH => Representation::Sh { order: parameter },
        layout::REPRESENTATION_CUBE => Representation::Cube {
            directions: parameter,
        },
        code => {
            return Err(Problem::UnknownCode {
                field: format!("batch {b}: representation"),
                code,
            })
        }
    };
    validate::check_representation(b, representation)?;
    Ok(representation)
}

fn batch_scalar(b: usize, f: &Fields<'_>) -> Result<ScalarType, Problem> {
    use layout::batch as bf;
    let scale = f.f32(bf::SCALE);
    let scalar = match f.u32(bf::SCALAR) {
        layout::SCALAR_F32 => {
            if scale != 1.0 {
                return Err(Problem::Invalid {
                    what: format!("batch {b}: f32 batch with scale {scale}"),
                    reason: "f32 batches store scale 1".into(),
                });
            }
            ScalarType::F32
        }
        layout::SCALAR_F16 => ScalarType::F16 { scale },
        code => {
            return Err(Problem::UnknownCode {
                field: format!("batch {b}: scalar type"),
                code,
            })
        }
    };
    validate::check_scalar(b, scalar)?;
    Ok(scalar)
}

/// `(frame_convention, basis_convention)`: the only ones version 1 defines.
fn batch_conventions(
    b: usize,
    f: &Fields<'_>,
    representation: Representation,
) -> Result<(u32, u32), Problem> {
    use layout::batch as bf;
    let frame_convention = f.u32(bf::FRAME_CONVENTION);
    if frame_convention != layout::FRAME_POLYGON_NTB {
        return Err(Problem::UnknownCode {
            field: format!("batch {b}: frame convention"),
            code: frame_convention,
        });
    }
    let basis_convention = f.u32(bf::BASIS_CONVENTION);
    if basis_convention != layout::basis_convention(representation) {
        return Err(Problem::UnknownCode {
            field: format!(
                "batch {b}: basis convention for {}",
                match representation {
                    Representation::Sh { .. } => "spherical harmonics",
                    Representation::Cube { .. } => "a global cube",
                }
            ),
            code: basis_convention,
        });
    }
    Ok((frame_convention, basis_convention))
}

/// `(vertex_count, index_count)`, u64 on disk, at most [`layout::MAX_COUNT`], and
/// the indices a whole number of triangles.
fn batch_counts(b: usize, f: &Fields<'_>) -> Result<(u32, u32), Problem> {
    use layout::batch as bf;
    let vertex_count = f.u64(bf::VERTEX_COUNT);
    let index_count = f.u64(bf::INDEX_COUNT);
    validate::check_counts(b, vertex_count, index_count)?;
    // Both fit: checked against MAX_COUNT = u32::MAX above.
    Ok((vertex_count as u32, index_count as u32))
}

/// A version-1.0 file uses every section it lists.
fn check_every_section_used(sections: &Sections) -> Result<(), Problem> {
    match sections.roles.iter().position(|r| *r == Role::Unused) {
        Some(i) => Err(Problem::UnusedSection {
            index: i as u32,
            kind_name: layout::section_kind_name(sections.entries[i].kind),
        }),
        None => Ok(()),
    }
}

/// Stage 4, placement: every section aligned, inside the file (summed in u128),
/// after the metadata, disjoint from the others, with zero padding between.
fn check_placement(bytes: &[u8], metadata_len: u64, sections: &Sections) -> Result<(), Problem> {
    let len = bytes.len() as u64;
    for (i, e) in sections.entries.iter().enumerate() {
        if e.offset % layout::SECTION_ALIGN != 0 {
            return Err(Problem::Misaligned {
                what: sections.name(i),
                offset: e.offset,
                align: layout::SECTION_ALIGN,
            });
        }
        let end = u128::from(e.offset) + u128::from(e.length);
        if end > u128::from(len) {
            return Err(Problem::OutOfBounds {
                what: sections.name(i),
                end,
                len,
            });
        }
        if e.offset < metadata_len {
            return Err(Problem::Overlap {
                first: format!("the header and tables (bytes 0..{metadata_len})"),
                second: sections.name(i),
            });
        }
    }
    let mut order: Vec<usize> = (0..sections.entries.len()).collect();
    order.sort_by_key(|&i| (sections.entries[i].offset, sections.entries[i].length));
    let mut cursor = metadata_len;
    let mut previous: Option<usize> = None;
    for &i in &order {
        let e = sections.entries[i];
        if e.offset < cursor {
            return Err(Problem::Overlap {
                first: previous
                    .map_or_else(|| "the header and tables".into(), |p| sections.name(p)),
                second: sections.name(i),
            });
        }
        check_zero(bytes, cursor, e.offset)?;
        cursor = e.offset + e.length;
        previous = Some(i);
    }
    check_zero(bytes, cursor, len)
}

/// Stage 4, sizes: each batch's vertex, coefficient and index counts against the
/// lengths of the sections it claims (in u128).
fn check_section_sizes(
    batches: &[BatchInfo],
    batch_sections: &[[usize; 4]],
    sections: &Sections,
) -> Result<(), Problem> {
    for (b, (info, refs)) in batches.iter().zip(batch_sections).enumerate() {
        let vertex_count = u64::from(info.vertex_count);
        let per_channel = info.coefficients_per_channel();
        let expectations = [
            (
                refs[0],
                vertex_count,
                "vertices",
                layout::VERTEX_LEN as u128,
            ),
            (
                refs[1],
                vertex_count,
                "vertices' coefficients",
                u128::from(per_channel) * 3 * u128::from(layout::scalar_size(info.scalar)),
            ),
            (refs[2], u64::from(info.index_count), "indices", 4),
            (
                refs[3],
                vertex_count,
                "textured vertices",
                layout::TEXTURED_VERTEX_LEN as u128,
            ),
        ];
        for (section, count, unit, size) in expectations {
            if section == usize::MAX {
                continue;
            }
            let expected = u128::from(count) * size;
            let actual = sections.entries[section].length;
            if expected != u128::from(actual) {
                return Err(Problem::SizeMismatch {
                    what: format!("batch {b}"),
                    count,
                    unit,
                    expected,
                    section: sections.name(section),
                    actual,
                });
            }
        }
    }
    Ok(())
}

/// Stage 5, first part: every section's CRC (the batches' sections only if
/// `batch_checksums`; see [`parse_checking`]).
fn check_checksums(
    bytes: &[u8],
    sections: &Sections,
    batch_checksums: bool,
) -> Result<(), Problem> {
    for (i, e) in sections.entries.iter().enumerate() {
        let deferred = matches!(
            sections.roles[i],
            Role::Vertices(_)
                | Role::Coefficients(_)
                | Role::Indices(_)
                | Role::TexturedVertices(_)
                | Role::Texture(_)
        );
        if deferred && !batch_checksums {
            continue;
        }
        let computed = crc32fast::hash(&bytes[sections.range(i)]);
        if computed != e.crc {
            return Err(Problem::Checksum {
                what: sections.name(i),
                stored: e.crc,
                computed,
            });
        }
    }
    Ok(())
}

/// Stage 5, the settings section's text (it must be UTF-8).
fn settings_text(bytes: &[u8], sections: &Sections, index: usize) -> Result<String, Problem> {
    std::str::from_utf8(&bytes[sections.range(index)])
        .map(str::to_string)
        .map_err(|e| Problem::Invalid {
            what: sections.name(index),
            reason: format!("the settings are not UTF-8 text: {e}"),
        })
}

fn check_zero(bytes: &[u8], from: u64, to: u64) -> Result<(), Problem> {
    let Some(gap) = bytes.get(from as usize..to as usize) else {
        return Ok(());
    };
    match gap.iter().position(|&x| x != 0) {
        Some(k) => Err(Problem::NonZeroPadding {
            at: from + k as u64,
            value: gap[k],
        }),
        None => Ok(()),
    }
}

fn vertex_at(chunk: &[u8]) -> Vertex {
    // `chunk` is one of `chunks_exact(VERTEX_LEN)`.
    match Fields::new(chunk, layout::VERTEX_LEN) {
        Some(f) => Vertex {
            position: f.f32x3(0),
            normal: f.f32x3(12),
            tangent: f.f32x3(24),
        },
        None => Vertex::default(),
    }
}

fn textured_vertex_at(chunk: &[u8]) -> TexturedVertex {
    // `chunk` is one of `chunks_exact(TEXTURED_VERTEX_LEN)`.
    match Fields::new(chunk, layout::TEXTURED_VERTEX_LEN) {
        Some(f) => TexturedVertex {
            uv: [f.f32(0), f.f32(4)],
            irradiance_over_pi: f.f32x3(8),
        },
        None => TexturedVertex::default(),
    }
}

/// Stage 5, content of one batch: finite values, orthonormal frames, positions
/// inside the header bounds (within `slack`), indices below the vertex count.
/// Without `coefficients`, the coefficients' finite check is left to the caller
/// (the streaming upload), which reads them anyway.
fn check_content(
    b: usize,
    info: &BatchInfo,
    bytes: &[u8],
    ranges: &[Range<usize>; 4],
    header: &Header,
    slack: f32,
    coefficients: bool,
) -> Result<(), Problem> {
    let [vertices, coefficients_range, indices, textured] = ranges;
    for (v, chunk) in bytes[textured.clone()]
        .chunks_exact(layout::TEXTURED_VERTEX_LEN)
        .enumerate()
    {
        validate::check_textured_vertex(b, v as u64, &textured_vertex_at(chunk))?;
    }
    for (v, chunk) in bytes[vertices.clone()]
        .chunks_exact(layout::VERTEX_LEN)
        .enumerate()
    {
        let vertex = vertex_at(chunk);
        validate::check_vertex(b, v as u64, &vertex)?;
        validate::check_in_bounds(b, v as u64, vertex.position, header, slack)?;
    }
    if coefficients {
        check_finite_coefficients(b, info.scalar, 0, &bytes[coefficients_range.clone()])?;
    }
    let vertex_count = u64::from(info.vertex_count);
    if let Some((position, index)) = bytes[indices.clone()]
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .enumerate()
        .find(|(_, i)| u64::from(*i) >= vertex_count)
    {
        return Err(Problem::IndexOutOfRange {
            batch: b,
            position: position as u64,
            index,
            vertex_count,
        });
    }
    Ok(())
}

/// Refuses the first Inf or NaN among coefficient bytes that start at
/// coefficient `first` of batch `b`'s section.
fn check_finite_coefficients(
    b: usize,
    scalar: ScalarType,
    first: u64,
    bytes: &[u8],
) -> Result<(), Problem> {
    let bad = match scalar {
        // An f32 is Inf or NaN when its exponent bits are all ones; testing the
        // bits (rather than `is_finite`) lets the loop vectorize.
        ScalarType::F32 => bytes
            .chunks_exact(4)
            .position(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]) & 0x7F80_0000 == 0x7F80_0000)
            .map(|k| (k, "f32")),
        // A half is Inf or NaN when its exponent bits are all ones.
        ScalarType::F16 { .. } => bytes
            .chunks_exact(2)
            .position(|c| u16::from_le_bytes([c[0], c[1]]) & 0x7C00 == 0x7C00)
            .map(|k| (k, "f16")),
    };
    match bad {
        Some((k, kind)) => Err(Problem::NonFinite {
            what: format!("batch {b}: coefficient {} ({kind})", first + k as u64),
            value: "Inf or NaN".into(),
        }),
        None => Ok(()),
    }
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

/// A validated solution file mapped into memory: the runtime uploads
/// [`vertex_bytes`](Self::vertex_bytes), [`coefficient_bytes`](Self::coefficient_bytes)
/// and [`index_bytes`](Self::index_bytes) to GPU buffers as they are (little-endian,
/// each slice starting 64-byte aligned in memory).
pub struct MappedSolution {
    path: PathBuf,
    map: memmap2::Mmap,
    parsed: Parsed,
}

impl std::fmt::Debug for MappedSolution {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MappedSolution")
            .field("path", &self.path)
            .field("file_len", &self.parsed.file_len)
            .field("batches", &self.parsed.batches)
            .finish_non_exhaustive()
    }
}

impl MappedSolution {
    /// Maps and validates a solution file (every check of [`decode`], including all
    /// checksums) before returning; only per-batch and per-section tables (bounded
    /// by the file's length) are allocated.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, FormatError> {
        Self::map_and_parse(path.as_ref(), true)
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// `(major, minor)` format version of the file.
    pub fn version(&self) -> (u16, u16) {
        self.parsed.version
    }

    pub fn file_len(&self) -> u64 {
        self.parsed.file_len
    }

    pub fn header(&self) -> &Header {
        &self.parsed.header
    }

    pub fn batches(&self) -> &[BatchInfo] {
        &self.parsed.batches
    }

    fn section(&self, batch: usize, which: usize) -> &[u8] {
        let range = &self.parsed.ranges[batch][which];
        self.map.get(range.clone()).unwrap_or(&[])
    }

    /// Batch `batch`'s vertices: `vertex_count × 36` bytes, each vertex 9
    /// little-endian f32 (position, normal, tangent), the layout of [`Vertex`].
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn vertex_bytes(&self, batch: usize) -> &[u8] {
        self.section(batch, 0)
    }

    /// Batch `batch`'s coefficients, vertex-major, then coefficient, then RGB:
    /// little-endian f32, or f16 (multiply by the batch's scale).
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn coefficient_bytes(&self, batch: usize) -> &[u8] {
        self.section(batch, 1)
    }

    /// Batch `batch`'s triangle list: `index_count` little-endian u32.
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn index_bytes(&self, batch: usize) -> &[u8] {
        self.section(batch, 2)
    }

    /// Copies the file into an in-memory [`Solution`] (f16 coefficients widened to
    /// f32 and multiplied by their scale, textures decoded). Fails only if a
    /// texture does not decode: possible after
    /// [`open_deferring_checksums`](Self::open_deferring_checksums), which does
    /// not decode textures, or if the file was changed in place.
    pub fn to_solution(&self) -> Result<Solution, FormatError> {
        materialize(&self.map, &self.parsed).map_err(|p| FormatError::in_file(&self.path, p))
    }

    /// The file's textures (format 2; empty for 1.x), as their sections declare
    /// them.
    pub fn textures(&self) -> &[TextureInfo] {
        &self.parsed.textures
    }

    /// Texture `k`'s encoded image (the PNG stream, after the section's prefix).
    ///
    /// # Panics
    /// If `k >= self.textures().len()`.
    pub fn texture_bytes(&self, k: usize) -> &[u8] {
        let (range, _, _) = &self.parsed.texture_sections[k];
        self.map.get(range.clone()).unwrap_or(&[])
    }

    /// Texture `k`, its section's CRC-32 verified (also after
    /// [`open_deferring_checksums`](Self::open_deferring_checksums), which
    /// leaves it) and decoded to 8-bit sRGB RGBA. Allocates at most the decoded
    /// image (width × height × 4, within the caps `open` checked) plus 1 MiB.
    ///
    /// # Panics
    /// If `k >= self.textures().len()`.
    pub fn decode_texture(&self, k: usize) -> Result<Texture, FormatError> {
        let (range, index, stored) = &self.parsed.texture_sections[k];
        let start = range.start - layout::TEXTURE_PREFIX_LEN;
        let section = self.map.get(start..range.end).unwrap_or(&[]);
        let computed = crc32fast::hash(section);
        if computed != *stored {
            return Err(FormatError::in_file(
                &self.path,
                Problem::Checksum {
                    what: format!("section {index} (texture {k})"),
                    stored: *stored,
                    computed,
                },
            ));
        }
        let info = self.parsed.textures[k];
        texture::decode_png(self.texture_bytes(k), info.width, info.height).map_err(|reason| {
            FormatError::in_file(
                &self.path,
                Problem::Texture {
                    texture: k as u32,
                    reason,
                },
            )
        })
    }

    /// Batch `batch`'s UV + E/π section: `vertex_count × 20` bytes, each vertex
    /// 5 little-endian f32 (u, v, E/π RGB), the layout of [`TexturedVertex`];
    /// empty for an untextured batch.
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn textured_vertex_bytes(&self, batch: usize) -> &[u8] {
        self.section(batch, 3)
    }

    /// Maps and validates a solution file like [`open`](Self::open), except
    /// that the CRC-32 of each batch's vertex, coefficient and index sections is
    /// not computed: the caller checks each one with
    /// [`verify_section`](Self::verify_section) as it copies the section, so
    /// the file's bulk is read once for checksum and copy together. Every other
    /// check runs (the metadata and settings checksums, bounds, counts, finite
    /// vertices, frames, indices below the vertex count) except the coefficients'
    /// finite check, which the caller makes as it streams them
    /// ([`verify_finite_coefficients`](Self::verify_finite_coefficients)); nothing
    /// the deferred checks guard is needed for memory safety, so a caller that
    /// never verifies only loses the detection of corrupted or non-finite values.
    pub fn open_deferring_checksums(path: impl AsRef<Path>) -> Result<Self, FormatError> {
        Self::map_and_parse(path.as_ref(), false)
    }

    fn map_and_parse(path: &Path, batch_checksums: bool) -> Result<Self, FormatError> {
        let file = std::fs::File::open(path).map_err(|e| FormatError::io("open", path, e))?;
        let len = file
            .metadata()
            .map_err(|e| FormatError::io("inspect", path, e))?
            .len();
        if len < layout::PREAMBLE_LEN as u64 {
            // Also avoids mapping an empty file, which some platforms refuse.
            return Err(FormatError::in_file(
                path,
                Problem::TooShort {
                    len,
                    min: layout::PREAMBLE_LEN as u64,
                },
            ));
        }
        // SAFETY: `Mmap` hands out `&[u8]` that Rust assumes immutable for the
        // map's lifetime. That holds as long as no process modifies or truncates
        // the file while it is mapped. The solver never writes a solution file in
        // place: `write_solution` writes a new temporary file and renames it over
        // the old name, which leaves the inode we mapped untouched (readers of the
        // old file keep the old bytes). Another tool truncating the file in place
        // would make later accesses fault (SIGBUS) and in-place edits would change
        // bytes after validation; the reader never trusts validated values for
        // memory safety (all later slicing is bounds-checked), so such edits can
        // only yield wrong pixels, not out-of-bounds access.
        let map = unsafe { memmap2::Mmap::map(&file) }
            .map_err(|e| FormatError::io("memory-map", path, e))?;
        let parsed =
            parse_checking(&map, batch_checksums).map_err(|p| FormatError::in_file(path, p))?;
        Ok(MappedSolution {
            path: path.to_path_buf(),
            map,
            parsed,
        })
    }

    fn slot(section: BatchSection) -> usize {
        match section {
            BatchSection::Vertices => 0,
            BatchSection::Coefficients => 1,
            BatchSection::Indices => 2,
            BatchSection::TexturedVertices => 3,
        }
    }

    /// Index in the section table of batch `batch`'s `section`, as the batch
    /// table (whose checksum `open` verified) gave it; `usize::MAX` for the
    /// textured vertices of an untextured batch.
    fn section_index(&self, batch: usize, section: BatchSection) -> usize {
        self.parsed.batch_sections[batch][Self::slot(section)].0
    }

    /// The CRC-32 (IEEE) the file stores for batch `batch`'s `section`: what
    /// `crc32fast::hash` of [`vertex_bytes`](Self::vertex_bytes) (or the
    /// coefficient, index or textured-vertex bytes) must equal (0 for the
    /// textured vertices of an untextured batch, the CRC of no bytes).
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn section_crc(&self, batch: usize, section: BatchSection) -> u32 {
        self.parsed.batch_sections[batch][Self::slot(section)].1
    }

    /// Checks that `bytes`, batch `batch`'s coefficients from coefficient
    /// `first` on, hold no Inf or NaN: the check that
    /// [`open_deferring_checksums`](Self::open_deferring_checksums) leaves to the
    /// streaming upload (which reads every coefficient anyway). On failure, the
    /// error `open` gives for the same value (file, batch, coefficient index).
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn verify_finite_coefficients(
        &self,
        batch: usize,
        first: u64,
        bytes: &[u8],
    ) -> Result<(), FormatError> {
        check_finite_coefficients(batch, self.parsed.batches[batch].scalar, first, bytes)
            .map_err(|p| FormatError::in_file(&self.path, p))
    }

    /// Checks `computed`, the CRC-32 of batch `batch`'s `section` as the caller
    /// read it, against the stored one: on mismatch, the same error `open`
    /// gives (naming the file, the section and its batch).
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn verify_section(
        &self,
        batch: usize,
        section: BatchSection,
        computed: u32,
    ) -> Result<(), FormatError> {
        let stored = self.section_crc(batch, section);
        if stored == computed {
            return Ok(());
        }
        let index = self.section_index(batch, section);
        let what = match section {
            BatchSection::Vertices => "vertices",
            BatchSection::Coefficients => "coefficients",
            BatchSection::Indices => "indices",
            BatchSection::TexturedVertices => "textured vertices",
        };
        Err(FormatError::in_file(
            &self.path,
            Problem::Checksum {
                what: format!("section {index} ({what} of batch {batch})"),
                stored,
                computed,
            },
        ))
    }

    /// The bytes of batch `batch`'s `section`.
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn section_bytes(&self, batch: usize, section: BatchSection) -> &[u8] {
        match section {
            BatchSection::Vertices => self.vertex_bytes(batch),
            BatchSection::Coefficients => self.coefficient_bytes(batch),
            BatchSection::Indices => self.index_bytes(batch),
            BatchSection::TexturedVertices => self.textured_vertex_bytes(batch),
        }
    }

    /// Tells the kernel that this process is done with batch `batch`'s
    /// `section` for now (`madvise(MADV_DONTNEED)`, rounded out to whole pages):
    /// its pages leave the process's resident set but stay in the page cache,
    /// and a later read maps them again. The runtime calls it once a section is
    /// on the GPU, so the map and the GPU copy are not both resident. Advisory:
    /// failure (or a platform without `madvise`) changes nothing.
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn release_section(&self, batch: usize, section: BatchSection) {
        let bytes = self.section_bytes(batch, section);
        if bytes.is_empty() {
            return;
        }
        #[cfg(unix)]
        {
            let offset = bytes.as_ptr() as usize - self.map.as_ptr() as usize;
            // SAFETY: the map is a read-only shared mapping of a file, so
            // MADV_DONTNEED only drops page-table entries: a later access faults
            // the same file bytes back in from the page cache (nothing was
            // written through the map, so nothing is lost), and `&[u8]` borrows
            // of the map keep seeing the same contents under the invariant of
            // `open` (the file is replaced by rename, never edited in place).
            let _ = unsafe {
                self.map.unchecked_advise_range(
                    memmap2::UncheckedAdvice::DontNeed,
                    offset,
                    bytes.len(),
                )
            };
        }
    }
}

/// One of a batch's bulk sections.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BatchSection {
    Vertices,
    Coefficients,
    Indices,
    /// Format 2, textured batches: per-vertex u, v, E/π (empty otherwise).
    TexturedVertices,
}

#[cfg(test)]
mod deferred_checksum_tests {
    use super::super::tests::sample_solution;
    use super::super::write_solution;
    use super::*;

    fn written() -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sample.sol");
        write_solution(&path, &sample_solution()).unwrap();
        (dir, path)
    }

    const SECTIONS: [BatchSection; 3] = [
        BatchSection::Vertices,
        BatchSection::Coefficients,
        BatchSection::Indices,
    ];

    /// Every stored CRC is the CRC-32 of the section's bytes, and verifying it
    /// passes: the getter reads the same table entry `parse` checks.
    #[test]
    fn stored_crcs_match_the_sections_and_verify() {
        let (_dir, path) = written();
        let file = MappedSolution::open_deferring_checksums(&path).unwrap();
        for b in 0..file.batches().len() {
            for section in SECTIONS {
                let bytes = file.section_bytes(b, section);
                let crc = crc32fast::hash(bytes);
                assert_eq!(file.section_crc(b, section), crc, "batch {b} {section:?}");
                file.verify_section(b, section, crc).unwrap();
            }
        }
    }

    /// A NaN coefficient: `open` refuses the file (at its checksum, which the
    /// edit breaks, before the content check); the deferring constructor leaves
    /// the coefficients' finite check to the stream, where
    /// `verify_finite_coefficients` names the coefficient by its index in the
    /// section, also when the piece checked starts past the section's start.
    #[test]
    fn a_nan_coefficient_is_refused_by_the_streaming_finite_check() {
        let (_dir, path) = written();
        let (offset, scalar) = {
            let file = MappedSolution::open(&path).unwrap();
            let base = file.map.as_ptr() as usize;
            (
                file.coefficient_bytes(0).as_ptr() as usize - base,
                file.batches()[0].scalar,
            )
        };
        assert_eq!(scalar, ScalarType::F32, "batch 0 of the sample stores f32");
        let mut bytes = std::fs::read(&path).unwrap();
        // Coefficient 2 of batch 0 becomes a quiet NaN.
        bytes[offset + 8..offset + 12].copy_from_slice(&f32::NAN.to_le_bytes());
        std::fs::write(&path, &bytes).unwrap();

        assert!(MappedSolution::open(&path).is_err());
        let file = MappedSolution::open_deferring_checksums(&path).unwrap();
        let coefficients = file.coefficient_bytes(0);
        let whole = file
            .verify_finite_coefficients(0, 0, coefficients)
            .unwrap_err()
            .to_string();
        assert!(whole.contains("batch 0: coefficient 2 (f32)"), "{whole}");
        assert!(whole.contains("sample.sol"), "{whole}");
        let piece = file
            .verify_finite_coefficients(0, 1, &coefficients[4..])
            .unwrap_err()
            .to_string();
        assert_eq!(piece, whole);
        file.verify_finite_coefficients(0, 3, &coefficients[12..])
            .unwrap();
    }

    /// One flipped coefficient byte: `open` refuses the file; the deferring
    /// constructor accepts it (the byte stays a finite half), and verifying the
    /// section gives the very error `open` gave.
    #[test]
    fn a_flipped_coefficient_byte_is_refused_by_both_paths_with_one_error() {
        let (_dir, path) = written();
        let (batch, offset) = {
            let file = MappedSolution::open(&path).unwrap();
            // Batch 1 is the f16 glossy triangle; flip the low byte of its first
            // half, which changes the mantissa only (still finite).
            let base = file.map.as_ptr() as usize;
            (1, file.coefficient_bytes(1).as_ptr() as usize - base)
        };
        let mut bytes = std::fs::read(&path).unwrap();
        bytes[offset] ^= 0x01;
        std::fs::write(&path, &bytes).unwrap();

        let refused = MappedSolution::open(&path).unwrap_err().to_string();
        assert!(refused.contains("CRC-32"), "{refused}");
        assert!(refused.contains("coefficients of batch 1"), "{refused}");
        assert!(refused.contains("sample.sol"), "{refused}");

        let file = MappedSolution::open_deferring_checksums(&path).unwrap();
        let computed = crc32fast::hash(file.coefficient_bytes(batch));
        let streamed = file
            .verify_section(batch, BatchSection::Coefficients, computed)
            .unwrap_err()
            .to_string();
        assert_eq!(streamed, refused);
        // The untouched sections still verify.
        for section in [BatchSection::Vertices, BatchSection::Indices] {
            let crc = crc32fast::hash(file.section_bytes(batch, section));
            file.verify_section(batch, section, crc).unwrap();
        }
    }

    /// The deferring constructor still refuses what the checksums do not guard:
    /// a corrupted settings section (its CRC is always checked) and a bad
    /// metadata checksum.
    #[test]
    fn deferring_still_checks_metadata_and_settings() {
        let (_dir, path) = written();
        let clean = std::fs::read(&path).unwrap();
        let settings_at = {
            let file = MappedSolution::open(&path).unwrap();
            let text = &file.header().settings_json;
            let at = clean
                .windows(text.len())
                .position(|w| w == text.as_bytes())
                .unwrap();
            at
        };
        let mut bytes = clean.clone();
        bytes[settings_at] ^= 0x01;
        std::fs::write(&path, &bytes).unwrap();
        let error = MappedSolution::open_deferring_checksums(&path)
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("CRC-32") && error.contains("settings"),
            "{error}"
        );
        let mut bytes = clean;
        bytes[layout::PREAMBLE_LEN] ^= 0x01;
        std::fs::write(&path, &bytes).unwrap();
        let error = MappedSolution::open_deferring_checksums(&path)
            .unwrap_err()
            .to_string();
        assert!(error.contains("header and tables"), "{error}");
    }
}
