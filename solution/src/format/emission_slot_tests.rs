//! The second texture slot (format 3): a textured batch's emission texture and
//! factor. Round trips, the version choice, and hostile slot fields.

use super::layout::{self, batch as bf, preamble as pf};
use super::tests::{assert_same, patch, problem};
use super::texture_tests::textured_solution;
use super::write::{encode_with, EncodeOptions};
use super::*;

/// The textured solution with the quad (batch 3) also showing texture 0 as
/// its emission, factor Ke = (2, 1, 0.5).
pub(super) fn two_slot_solution() -> Solution {
    let mut solution = textured_solution();
    solution.batches[3].texturing.as_mut().unwrap().emission = Some(TextureSlot {
        texture: 0,
        factor: [2.0, 1.0, 0.5],
    });
    solution
}

/// Offset of batch `b`'s entry in a version-3 file.
fn v3_batch_at(b: usize) -> usize {
    layout::PREAMBLE_LEN + layout::HEADER_LEN + b * layout::BATCH_ENTRY_LEN_V3
}

fn version(bytes: &[u8]) -> (u16, u16) {
    let at = |k: usize| u16::from_le_bytes([bytes[k], bytes[k + 1]]);
    (at(pf::VERSION_MAJOR), at(pf::VERSION_MINOR))
}

#[test]
fn a_batch_with_both_textures_round_trips_as_version_3() {
    let original = two_slot_solution();
    let bytes = encode(&original).unwrap();
    assert_eq!(version(&bytes), (3, 0));
    let entry_len = u32::from_le_bytes(bytes[pf::BATCH_ENTRY_LENGTH..][..4].try_into().unwrap());
    assert_eq!(entry_len as usize, layout::BATCH_ENTRY_LEN_V3);
    let decoded = decode(&bytes).unwrap();
    assert_same(&decoded, &original);
    assert_eq!(encode(&decoded).unwrap(), bytes);

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two-slot.sol");
    write_solution(&path, &original).unwrap();
    let file = MappedSolution::open(&path).unwrap();
    assert_eq!(file.version(), (3, 0));
    let quad = file.batches()[3].texture.unwrap();
    assert_eq!(
        quad.emission,
        Some(TextureSlot {
            texture: 0,
            factor: [2.0, 1.0, 0.5]
        })
    );
    // The glossy batch keeps an empty slot, the untextured ones none at all.
    assert_eq!(file.batches()[4].texture.unwrap().emission, None);
    assert_eq!(file.batches()[0].texture, None);
    let text = describe_text(&original.header, file.batches());
    assert!(
        text.contains("  emission_texture: 0\n  emission_factor: 2 1 0.5"),
        "{text}"
    );
    let json = batch_json(&file.batches()[3]);
    assert_eq!(json["texture"]["emission"]["index"], 0);
}

/// A file whose batches use one slot each is still written as 2.0 (what a
/// version-2 writer wrote, byte for byte the same layout), and 2.0 files read
/// with an empty second slot.
#[test]
fn one_slot_solutions_stay_version_2_0() {
    let bytes = encode(&textured_solution()).unwrap();
    assert_eq!(version(&bytes), (2, 0));
    let entry_len = u32::from_le_bytes(bytes[pf::BATCH_ENTRY_LENGTH..][..4].try_into().unwrap());
    assert_eq!(entry_len as usize, layout::BATCH_ENTRY_LEN_V2);
    let decoded = decode(&bytes).unwrap();
    assert!(decoded
        .batches
        .iter()
        .filter_map(|b| b.texturing.as_ref())
        .all(|t| t.emission.is_none()));
}

#[test]
fn a_bad_emission_slot_is_refused_with_a_clear_error() {
    let bytes = encode(&two_slot_solution()).unwrap();
    // An index past the file's two textures.
    let bad = patch(
        &bytes,
        v3_batch_at(3) + bf::EMISSION_TEXTURE,
        &2u32.to_le_bytes(),
    );
    let p = problem(&bad);
    assert!(
        matches!(&p, Problem::Invalid { what, reason }
            if what == "batch 3: emission texture index 2" && reason.contains("2 textures")),
        "{p}"
    );
    // A NaN or a negative factor.
    let bad = patch(
        &bytes,
        v3_batch_at(3) + bf::EMISSION_FACTOR + 4,
        &f32::NAN.to_le_bytes(),
    );
    assert!(
        matches!(problem(&bad), Problem::NonFinite { what, .. } if what.contains("emission texture factor"))
    );
    let bad = patch(
        &bytes,
        v3_batch_at(3) + bf::EMISSION_FACTOR,
        &(-1f32).to_le_bytes(),
    );
    assert!(matches!(problem(&bad), Problem::Invalid { what, .. } if what.contains("emission")));
    // An empty slot with a stray factor, and an untextured batch with a slot.
    let bad = patch(
        &bytes,
        v3_batch_at(4) + bf::EMISSION_FACTOR,
        &1f32.to_le_bytes(),
    );
    assert!(matches!(problem(&bad), Problem::Invalid { what, .. } if what.contains("emission")));
    let bad = patch(
        &bytes,
        v3_batch_at(0) + bf::EMISSION_TEXTURE,
        &0u32.to_le_bytes(),
    );
    let p = problem(&bad);
    assert!(
        matches!(&p, Problem::Invalid { reason, .. } if reason.contains("only a textured batch")),
        "{p}"
    );
    // The writer refuses the same solutions.
    let mut solution = two_slot_solution();
    let slot = solution.batches[3].texturing.as_mut().unwrap();
    slot.emission.as_mut().unwrap().texture = 2;
    assert!(encode(&solution).is_err());
    slot_factor(&mut solution, [0.0, f32::INFINITY, 0.0]);
    assert!(encode(&solution).is_err());
}

fn slot_factor(solution: &mut Solution, factor: [f32; 3]) {
    let t = solution.batches[3].texturing.as_mut().unwrap();
    t.emission = Some(TextureSlot { texture: 0, factor });
}

#[test]
fn every_truncation_and_bit_flip_of_a_version_3_file_is_refused() {
    let mut solution = two_slot_solution();
    solution.textures = vec![
        super::texture_tests::noise_texture(2, 2, 3),
        super::texture_tests::noise_texture(3, 1, 4),
    ];
    let bytes = encode(&solution).unwrap();
    for len in (0..bytes.len()).step_by(61) {
        assert!(decode(&bytes[..len]).is_err(), "length {len}");
    }
    // Every bit of the metadata (the slot lives there); the sections'
    // bits are covered by the same CRCs as in format 2.
    let metadata = u64::from_le_bytes(bytes[pf::METADATA_LENGTH..][..8].try_into().unwrap());
    for bit in 0..metadata as usize * 8 {
        let mut bad = bytes.clone();
        bad[bit / 8] ^= 1 << (bit % 8);
        assert!(decode(&bad).is_err(), "bit {bit} flip accepted");
    }
}

#[test]
fn newer_minor_version_of_3_is_read_by_skipping_what_it_adds() {
    let original = two_slot_solution();
    let future = EncodeOptions {
        minor: Some(layout::VERSION_MINOR + 1),
        header_extra: 8,
        batch_entry_extra: 16,
        section_entry_extra: 8,
        extra_sections: vec![(99, b"from a newer writer".to_vec())],
        texture_sections: None,
    };
    let bytes = encode_with(&original, &future).unwrap();
    assert_same(&decode(&bytes).unwrap(), &original);
}
