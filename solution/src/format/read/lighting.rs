//! Minor version 1 (issue 41): the header's exposure key and the lights and
//! environment sections it refers to.

use super::super::error::Problem;
use super::super::layout::{self, Fields};
use super::super::lighting::{check_exposure_key, read_environment_section, Lighting};
use super::metadata::{reserved, Blocks};
use super::sections::{Role, Sections};

/// The header's minor-version-1 fields.
#[derive(Clone, Copy, Debug)]
pub(super) struct LightingRefs {
    exposure_key: f32,
    lights: u32,
    environment: u32,
}

/// Stage 3: the exposure key and the two section indices of a file of minor
/// version ≥ 1 (`None` for x.0), claiming the sections they refer to.
pub(super) fn claim_lighting(
    header: &[u8],
    blocks: &Blocks,
    sections: &mut Sections,
) -> Result<Option<LightingRefs>, Problem> {
    use layout::header as hf;
    if blocks.minor < layout::LIGHTING_VERSION_MINOR {
        return Ok(None);
    }
    // block_layout checked the header's length against the 1.1 header.
    let Some(f) = Fields::new(header, layout::HEADER_LEN_V1_1) else {
        return Err(Problem::BadLength {
            what: "the header length".into(),
            value: header.len() as u64,
            reason: "shorter than version x.1's header".into(),
        });
    };
    reserved(
        "header: reserved word at byte 228",
        f.u32(hf::RESERVED_V1_1).into(),
        blocks.newer,
    )?;
    let refs = LightingRefs {
        exposure_key: f.f32(hf::EXPOSURE_KEY),
        lights: f.u32(hf::LIGHTS_SECTION),
        environment: f.u32(hf::ENVIRONMENT_SECTION),
    };
    check_exposure_key(refs.exposure_key)?;
    if refs.lights != layout::NO_SECTION {
        sections.claim(refs.lights, Role::Lights, layout::SECTION_LIGHTS)?;
    }
    if refs.environment != layout::NO_SECTION {
        sections.claim(
            refs.environment,
            Role::Environment,
            layout::SECTION_ENVIRONMENT,
        )?;
    }
    Ok(Some(refs))
}

/// Stage 5 (after the checksums): the lights' text, which must be UTF-8, and
/// the environment ([`read_environment_section`]). `None` when the file
/// stores nothing ([`Lighting::is_empty`]).
pub(super) fn read_lighting(
    bytes: &[u8],
    sections: &Sections,
    refs: Option<LightingRefs>,
    newer: bool,
) -> Result<Option<Lighting>, Problem> {
    let Some(refs) = refs else {
        return Ok(None);
    };
    let lights_json = if refs.lights == layout::NO_SECTION {
        None
    } else {
        let index = refs.lights as usize;
        let text =
            std::str::from_utf8(&bytes[sections.range(index)]).map_err(|e| Problem::Invalid {
                what: sections.name(index),
                reason: format!("the lights are not UTF-8 text: {e}"),
            })?;
        Some(text.to_string())
    };
    let environment = if refs.environment == layout::NO_SECTION {
        None
    } else {
        let index = refs.environment as usize;
        let what = sections.name(index);
        Some(read_environment_section(
            &what,
            &bytes[sections.range(index)],
            newer,
        )?)
    };
    let lighting = Lighting {
        exposure_key: refs.exposure_key,
        lights_json,
        environment,
    };
    Ok((!lighting.is_empty()).then_some(lighting))
}
