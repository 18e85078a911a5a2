//! Stages 1 to 3 of [`super::parse`] up to the tables: the preamble (is it ours,
//! which version, is it whole), the metadata checksum, the block layout and the
//! header.

use super::super::error::Problem;
use super::super::layout::{self, Fields};
use super::super::validate;
use super::super::{Header, SolveStats};
use crate::camera::{Camera, UpAxis};
use std::ops::Range;

/// The block sizes of the file's own minor version (x.0 or x.1) must match
/// exactly; a newer minor version may make them longer (appending fields this reader skips) but keeps them multiples of 8.
pub(super) fn check_block_len(
    what: &str,
    value: u32,
    v1: usize,
    newer: bool,
) -> Result<usize, Problem> {
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

pub(super) fn reserved(field: &str, value: u64, newer: bool) -> Result<(), Problem> {
    if value != 0 && !newer {
        return Err(Problem::Reserved {
            field: field.to_string(),
            value,
        });
    }
    Ok(())
}

/// The preamble's fields once stage 1 has accepted them.
pub(super) struct Preamble<'a> {
    pub(super) fields: Fields<'a>,
    /// 1 or 2.
    pub(super) major: u16,
    pub(super) minor: u16,
    /// The file's minor version is newer than this reader's.
    pub(super) newer: bool,
}

/// Stage 1: is it ours, which version, is it whole?
pub(super) fn read_preamble(bytes: &[u8]) -> Result<Preamble<'_>, Problem> {
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
pub(super) fn checked_metadata<'a>(
    bytes: &'a [u8],
    preamble: &Preamble<'_>,
) -> Result<&'a [u8], Problem> {
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
pub(super) struct Blocks {
    pub(super) header: Range<usize>,
    pub(super) batches: Range<usize>,
    pub(super) sections: Range<usize>,
    pub(super) batch_entry_len: usize,
    pub(super) section_entry_len: usize,
    pub(super) section_count: u32,
    pub(super) major: u16,
    /// The file's minor version.
    pub(super) minor: u16,
    pub(super) newer: bool,
}

/// Stage 3, first part: block lengths and counts must tile the metadata exactly
/// (summed in u128, so no hostile count can wrap), and the preamble's reserved
/// words must be zero.
pub(super) fn block_layout(preamble: &Preamble<'_>, metadata_len: u64) -> Result<Blocks, Problem> {
    use layout::preamble as pf;
    let (pre, newer) = (&preamble.fields, preamble.newer);
    let header_len = check_block_len(
        "the header length",
        pre.u32(pf::HEADER_LENGTH),
        layout::header_len(preamble.minor.min(layout::VERSION_MINOR)),
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
        minor: preamble.minor,
        newer,
    })
}

/// Stage 3, the header: codes, reserved word and every value
/// ([`validate::check_header`]). Returns the header (settings text still empty)
/// and the index of its settings section.
pub(super) fn read_header(block: &[u8], newer: bool) -> Result<(Header, u32), Problem> {
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
