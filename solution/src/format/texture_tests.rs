//! Textured solutions (format 2): round trips, the version choice, and hostile
//! texture sections and batch fields.

use super::layout::{self, batch as bf, preamble as pf};
use super::tests::{assert_same, patch, problem, sample_solution};
use super::write::{encode_with, EncodeOptions};
use super::*;

/// A `width × height` texture whose bytes come from a small LCG, so that PNG
/// cannot compress it much (the deflate-ratio check must not be what refuses
/// a truncated one).
pub(super) fn noise_texture(width: u32, height: u32, seed: u32) -> Texture {
    let mut state = seed.wrapping_mul(2_654_435_761).wrapping_add(1);
    let rgba = (0..width * height * 4)
        .map(|_| {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 24) as u8
        })
        .collect();
    Texture {
        width,
        height,
        rgba,
    }
}

/// The sample solution plus a textured quad (texture 1, factor 0.5, 0.25, 1)
/// and a textured L = 2 glossy triangle (texture 0).
pub(super) fn textured_solution() -> Solution {
    let mut solution = sample_solution();
    let mut quad = solution.batches[0].clone();
    quad.texturing = Some(Texturing {
        texture: 1,
        factor: [0.5, 0.25, 1.0],
        emission: None,
        vertices: (0..4)
            .map(|k| TexturedVertex {
                uv: [(k % 2) as f32 * 2.0, (k / 2) as f32 - 0.5],
                irradiance_over_pi: [0.1 * k as f32, 1.5, 1e-9],
            })
            .collect(),
    });
    let mut glossy = solution.batches[1].clone();
    glossy.texturing = Some(Texturing {
        texture: 0,
        factor: [1.0; 3],
        emission: None,
        vertices: vec![TexturedVertex::default(); 3],
    });
    solution.batches.push(quad);
    solution.batches.push(glossy);
    solution.textures = vec![noise_texture(7, 5, 1), noise_texture(64, 64, 2)];
    solution
}

#[test]
fn textured_solution_round_trips_as_version_2() {
    let original = textured_solution();
    let bytes = encode(&original).unwrap();
    assert_eq!(
        u16::from_le_bytes([bytes[pf::VERSION_MAJOR], bytes[pf::VERSION_MAJOR + 1]]),
        2
    );
    let decoded = decode(&bytes).unwrap();
    assert_same(&decoded, &original);
    // PNG is lossless: the texels come back exactly.
    assert_eq!(decoded.textures, original.textures);
    // And encoding the decoded file again gives the same bytes.
    assert_eq!(encode(&decoded).unwrap(), bytes);
}

#[test]
fn untextured_solutions_stay_version_1_0_byte_for_byte() {
    // The version-1 layout: 56-byte batch entries and no texture fields.
    let bytes = encode(&sample_solution()).unwrap();
    assert_eq!(
        &bytes[pf::VERSION_MAJOR..pf::VERSION_MAJOR + 4],
        &[1, 0, 0, 0]
    );
    let entry_len = u32::from_le_bytes(bytes[pf::BATCH_ENTRY_LENGTH..][..4].try_into().unwrap());
    assert_eq!(entry_len as usize, layout::BATCH_ENTRY_LEN);
}

#[test]
fn mapped_textured_file_exposes_textures_and_uv_sections() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("textured.sol");
    let original = textured_solution();
    write_solution(&path, &original).unwrap();
    for file in [
        MappedSolution::open(&path).unwrap(),
        MappedSolution::open_deferring_checksums(&path).unwrap(),
    ] {
        assert_eq!(file.version(), (2, 0));
        let infos = file.textures();
        assert_eq!(infos.len(), 2);
        assert_eq!((infos[0].width, infos[0].height), (7, 5));
        assert_eq!(infos[1].decoded_bytes(), 64 * 64 * 4);
        for (k, texture) in original.textures.iter().enumerate() {
            assert_eq!(&file.decode_texture(k).unwrap(), texture);
        }
        let quad = file.batches()[3];
        assert_eq!(
            quad.texture,
            Some(BatchTexture {
                texture: 1,
                factor: [0.5, 0.25, 1.0],
                emission: None,
            })
        );
        assert_eq!(file.batches()[0].texture, None);
        assert!(file.textured_vertex_bytes(0).is_empty());
        let uv = file.textured_vertex_bytes(3);
        assert_eq!(uv.len() as u64, quad.textured_vertex_bytes());
        assert_eq!(uv.len(), 4 * layout::TEXTURED_VERTEX_LEN);
        assert_eq!(uv.as_ptr() as usize % 64, 0);
        let crc = crc32fast::hash(uv);
        file.verify_section(3, BatchSection::TexturedVertices, crc)
            .unwrap();
        assert_same(&file.to_solution().unwrap(), &original);
    }
    let text = describe_textures_text(MappedSolution::open(&path).unwrap().textures());
    assert!(text.contains("texture 1:\n  size: 64x64"), "{text}");
    let batches = describe_text(
        &original.header,
        MappedSolution::open(&path).unwrap().batches(),
    );
    assert!(
        batches.contains("  texture: 1\n  texture_factor: 0.5 0.25 1"),
        "{batches}"
    );
}

/// Bytes of the textured solution with texture 1's section replaced.
fn with_texture_section(section: Vec<u8>) -> Vec<u8> {
    let original = textured_solution();
    let good = super::texture::section_bytes(
        &original.textures[0],
        &encode_png(&original.textures[0]).unwrap(),
    );
    let options = EncodeOptions {
        minor: None,
        texture_sections: Some(vec![good, section]),
        ..EncodeOptions::default()
    };
    encode_with(&original, &options).unwrap()
}

fn prefix(width: u32, height: u32) -> Vec<u8> {
    let mut p = Vec::new();
    for v in [width, height, layout::ENCODING_PNG_SRGB8, 0] {
        p.extend_from_slice(&v.to_le_bytes());
    }
    p
}

/// A PNG stream of just the signature and an IHDR chunk (8-bit RGBA); no image
/// data, so any decoder must fail, and only the checks before decoding can
/// refuse it cheaply.
fn ihdr_only(width: u32, height: u32) -> Vec<u8> {
    let mut png = vec![0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1A, b'\n'];
    let mut chunk = b"IHDR".to_vec();
    chunk.extend_from_slice(&width.to_be_bytes());
    chunk.extend_from_slice(&height.to_be_bytes());
    chunk.extend_from_slice(&[8, 6, 0, 0, 0]);
    png.extend_from_slice(&13u32.to_be_bytes());
    png.extend_from_slice(&chunk);
    png.extend_from_slice(&crc32fast::hash(&chunk).to_be_bytes());
    png
}

#[test]
fn a_truncated_png_is_refused_by_open_and_by_decode_texture() {
    let texture = noise_texture(64, 64, 2);
    let png = encode_png(&texture).unwrap();
    let mut section = prefix(64, 64);
    section.extend_from_slice(&png[..png.len() / 2]);
    let bytes = with_texture_section(section);
    let p = problem(&bytes);
    assert!(
        matches!(&p, Problem::Texture { texture: 1, reason } if reason.contains("PNG")),
        "{p}"
    );
    // The deferring open (the runtime's) does not decode; decoding refuses it.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("truncated.sol");
    std::fs::write(&path, &bytes).unwrap();
    let file = MappedSolution::open_deferring_checksums(&path).unwrap();
    let error = file.decode_texture(1).unwrap_err().to_string();
    assert!(error.contains("truncated.sol: texture 1: PNG"), "{error}");
    assert!(file.decode_texture(0).is_ok());
}

#[test]
fn absurd_dimensions_are_refused_before_decoding() {
    // 65535² declared by both the prefix and the IHDR: above the cap.
    let mut section = prefix(65535, 65535);
    section.extend_from_slice(&ihdr_only(65535, 65535));
    let p = problem(&with_texture_section(section));
    assert!(
        matches!(
            &p,
            Problem::TooLarge {
                value: 65535,
                limit: 16384,
                ..
            }
        ),
        "{p}"
    );
    // At the cap, but a 33-byte stream cannot deflate to 16384 × 65537 bytes.
    let mut section = prefix(16384, 16384);
    section.extend_from_slice(&ihdr_only(16384, 16384));
    let p = problem(&with_texture_section(section));
    assert!(
        matches!(&p, Problem::Texture { texture: 1, reason } if reason.contains("deflate")),
        "{p}"
    );
    // The prefix and the PNG disagree.
    let mut section = prefix(64, 64);
    section.extend_from_slice(&ihdr_only(64, 65));
    let p = problem(&with_texture_section(section));
    assert!(
        matches!(&p, Problem::Texture { reason, .. } if reason.contains("64×65")),
        "{p}"
    );
    // Not a PNG at all, and a section shorter than its prefix.
    let mut section = prefix(64, 64);
    section.extend_from_slice(b"GIF89a................................");
    assert!(matches!(
        problem(&with_texture_section(section)),
        Problem::Texture { .. }
    ));
    assert!(matches!(
        problem(&with_texture_section(vec![1, 2, 3])),
        Problem::Texture { .. }
    ));
}

#[test]
fn decoded_texture_bytes_are_capped_in_total() {
    assert!(validate::check_decoded_texture_bytes(layout::MAX_DECODED_TEXTURE_BYTES).is_ok());
    assert!(matches!(
        validate::check_decoded_texture_bytes(layout::MAX_DECODED_TEXTURE_BYTES + 1),
        Err(Problem::TooLarge { .. })
    ));
}

/// Offset of batch `b`'s entry in a version-2 file.
pub(super) fn v2_batch_at(b: usize) -> usize {
    layout::PREAMBLE_LEN + layout::HEADER_LEN + b * layout::BATCH_ENTRY_LEN_V2
}

#[test]
fn a_texture_index_out_of_range_is_refused() {
    let bytes = encode(&textured_solution()).unwrap();
    let bad = patch(&bytes, v2_batch_at(3) + bf::TEXTURE, &2u32.to_le_bytes());
    let p = problem(&bad);
    assert!(
        matches!(&p, Problem::Invalid { what, reason } if what.contains("texture index 2") && reason.contains("2 textures")),
        "{p}"
    );
    // The writer refuses the same solution.
    let mut solution = textured_solution();
    solution.batches[3].texturing.as_mut().unwrap().texture = 2;
    assert!(encode(&solution).is_err());
    // An untextured entry with a stray section or factor.
    let bad = patch(
        &bytes,
        v2_batch_at(0) + bf::TEXTURE_FACTOR,
        &1f32.to_le_bytes(),
    );
    assert!(matches!(problem(&bad), Problem::Invalid { .. }));
    // A textured batch pointing at a section of another kind.
    let bad = patch(
        &bytes,
        v2_batch_at(3) + bf::TEXTURED_VERTICES_SECTION,
        &1u32.to_le_bytes(),
    );
    assert!(matches!(
        problem(&bad),
        Problem::WrongSectionKind { .. } | Problem::SectionReused { .. }
    ));
}

#[test]
fn writer_refuses_invalid_texturing() {
    type Edit = fn(&mut Solution);
    let cases: Vec<(&str, Edit)> = vec![
        ("uv count", |s| {
            s.batches[3].texturing.as_mut().unwrap().vertices.pop();
        }),
        ("negative E/π", |s| {
            s.batches[3].texturing.as_mut().unwrap().vertices[0].irradiance_over_pi[1] = -1.0;
        }),
        ("NaN uv", |s| {
            s.batches[3].texturing.as_mut().unwrap().vertices[0].uv[0] = f32::NAN;
        }),
        ("negative factor", |s| {
            s.batches[3].texturing.as_mut().unwrap().factor[0] = -0.5;
        }),
        ("texel count", |s| {
            s.textures[0].rgba.pop();
        }),
        ("zero width", |s| {
            s.textures[0] = Texture {
                width: 0,
                height: 5,
                rgba: Vec::new(),
            };
        }),
        ("textured cube", |s| {
            let mut cube = s.batches[2].clone();
            cube.texturing = s.batches[3].texturing.clone();
            cube.texturing.as_mut().unwrap().vertices.pop();
            s.batches.push(cube);
        }),
    ];
    for (name, edit) in cases {
        let mut solution = textured_solution();
        edit(&mut solution);
        assert!(encode(&solution).is_err(), "{name} accepted");
    }
}

#[test]
fn every_truncation_of_a_textured_file_is_refused() {
    let bytes = encode(&textured_solution()).unwrap();
    for len in (0..bytes.len()).step_by(61) {
        assert!(decode(&bytes[..len]).is_err(), "length {len}");
    }
}

#[test]
fn every_single_bit_flip_of_a_textured_file_is_refused() {
    // A smaller file (one 2×2 texture) keeps this at a few thousand decodes.
    let mut solution = textured_solution();
    solution.textures = vec![noise_texture(2, 2, 3), noise_texture(3, 1, 4)];
    let bytes = encode(&solution).unwrap();
    for bit in 0..bytes.len() * 8 {
        let mut bad = bytes.clone();
        bad[bit / 8] ^= 1 << (bit % 8);
        assert!(decode(&bad).is_err(), "bit {bit} flip accepted");
    }
}

#[test]
fn newer_minor_version_of_2_is_read_by_skipping_what_it_adds() {
    let original = textured_solution();
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
