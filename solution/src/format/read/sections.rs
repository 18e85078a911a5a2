//! The section table (stage 3) and the checks on the sections themselves: which
//! batch or texture claims each one, their placement and sizes (stage 4), their
//! checksums, the settings text and the texture images (stage 5).

use super::super::error::Problem;
use super::super::layout::{self, Fields};
use super::super::texture::{self, TextureInfo};
use super::super::validate;
use super::metadata::{reserved, Blocks};
use super::BatchInfo;
use std::ops::Range;

#[derive(Clone, Copy, Debug)]
pub(super) struct SectionEntry {
    kind: u32,
    crc: u32,
    offset: u64,
    length: u64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Role {
    Unused,
    Settings,
    Vertices(usize),
    Coefficients(usize),
    Indices(usize),
    TexturedVertices(usize),
    Texture(usize),
    Lights,
    Environment,
}

pub(super) fn role_name(role: Role) -> String {
    match role {
        Role::Unused => "unused".into(),
        Role::Settings => "settings".into(),
        Role::Vertices(b) => format!("vertices of batch {b}"),
        Role::Coefficients(b) => format!("coefficients of batch {b}"),
        Role::Indices(b) => format!("indices of batch {b}"),
        Role::TexturedVertices(b) => format!("textured vertices of batch {b}"),
        Role::Texture(k) => format!("texture {k}"),
        Role::Lights => "lights".into(),
        Role::Environment => "environment".into(),
    }
}

pub(super) struct Sections {
    pub(super) entries: Vec<SectionEntry>,
    pub(super) roles: Vec<Role>,
}

impl Sections {
    /// "section 3 (coefficients of batch 1)".
    pub(super) fn name(&self, index: usize) -> String {
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
    pub(super) fn claim(&mut self, index: u32, role: Role, kind: u32) -> Result<(), Problem> {
        let what = match role {
            Role::Settings => "header: settings section".to_string(),
            Role::Vertices(b) => format!("batch {b}: vertices section"),
            Role::Coefficients(b) => format!("batch {b}: coefficients section"),
            Role::Indices(b) => format!("batch {b}: indices section"),
            Role::TexturedVertices(b) => format!("batch {b}: textured vertices section"),
            Role::Texture(k) => format!("texture {k}"),
            Role::Lights => "header: lights section".to_string(),
            Role::Environment => "header: environment section".to_string(),
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
    pub(super) fn crc(&self, index: usize) -> u32 {
        self.entries.get(index).map_or(0, |e| e.crc)
    }

    /// The byte range of a section whose bounds `parse` has checked (empty for
    /// a missing one, `usize::MAX`).
    pub(super) fn range(&self, index: usize) -> Range<usize> {
        self.entries.get(index).map_or(0..0, |e| {
            // Bounds were checked against the in-memory file, so both fit usize.
            e.offset as usize..(e.offset + e.length) as usize
        })
    }
}

/// Stage 3, the section table: known kinds, zero reserved fields. Every section
/// starts unused; the header and batches claim theirs.
pub(super) fn read_section_table(table: &[u8], blocks: &Blocks) -> Result<Sections, Problem> {
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
        if !layout::section_kind_known(blocks.major, blocks.minor, kind) && !blocks.newer {
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

/// Stage 3, textures (format 2): every section of the texture kind is a
/// texture, numbered in section-table order; returns their section indices.
pub(super) fn claim_textures(sections: &mut Sections, major: u16) -> Result<Vec<usize>, Problem> {
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
pub(super) fn check_textures(
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

/// A version-1.0 file uses every section it lists.
pub(super) fn check_every_section_used(sections: &Sections) -> Result<(), Problem> {
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
pub(super) fn check_placement(
    bytes: &[u8],
    metadata_len: u64,
    sections: &Sections,
) -> Result<(), Problem> {
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
pub(super) fn check_section_sizes(
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
/// `batch_checksums`; see [`super::parse_checking`]).
pub(super) fn check_checksums(
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
pub(super) fn settings_text(
    bytes: &[u8],
    sections: &Sections,
    index: usize,
) -> Result<String, Problem> {
    std::str::from_utf8(&bytes[sections.range(index)])
        .map(str::to_string)
        .map_err(|e| Problem::Invalid {
            what: sections.name(index),
            reason: format!("the settings are not UTF-8 text: {e}"),
        })
}

pub(super) fn check_zero(bytes: &[u8], from: u64, to: u64) -> Result<(), Problem> {
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
