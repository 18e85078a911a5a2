//! Stage 3, the batch table: each entry's representation, scalar type,
//! conventions, counts, texture slots, and the sections it claims.

use super::super::error::Problem;
use super::super::layout::{self, Fields};
use super::super::validate;
use super::super::{Representation, ScalarType, TextureSlot};
use super::metadata::{reserved, Blocks};
use super::sections::{Role, Sections};
use super::{BatchInfo, BatchTexture};

/// Stage 3, the batch table: each entry ([`read_batch_entry`]) with the indices of
/// its vertices, coefficients and indices sections.
pub(super) fn read_batch_table(
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
pub(super) fn read_batch_entry(
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
pub(super) fn batch_texture(
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
pub(super) fn emission_slot(
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
pub(super) fn check_empty_emission_slot(
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

pub(super) fn batch_representation(b: usize, f: &Fields<'_>) -> Result<Representation, Problem> {
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

pub(super) fn batch_scalar(b: usize, f: &Fields<'_>) -> Result<ScalarType, Problem> {
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
pub(super) fn batch_conventions(
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
pub(super) fn batch_counts(b: usize, f: &Fields<'_>) -> Result<(u32, u32), Problem> {
    use layout::batch as bf;
    let vertex_count = f.u64(bf::VERTEX_COUNT);
    let index_count = f.u64(bf::INDEX_COUNT);
    validate::check_counts(b, vertex_count, index_count)?;
    // Both fit: checked against MAX_COUNT = u32::MAX above.
    Ok((vertex_count as u32, index_count as u32))
}
