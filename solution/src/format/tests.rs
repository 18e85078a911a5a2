//! Round trips and bad-input tests of the solution-file codec.

use super::layout::{self, batch as bf, header as hf, preamble as pf, section as sf};
use super::*;
use crate::camera::{Camera, UpAxis};

fn vertex(position: [f32; 3]) -> Vertex {
    Vertex {
        position,
        normal: [0.0, 1.0, 0.0],
        tangent: [1.0, 0.0, 0.0],
    }
}

/// A small solution exercising every header field and all representations and
/// scalar types: an L = 0 f32 quad, an L = 2 f16 triangle and a 6-direction cube
/// triangle.
pub(crate) fn sample_solution() -> Solution {
    let header = Header {
        units_per_metre: 1000.0,
        up_axis: UpAxis::PosZ,
        recentre_offset: [278.0, 274.4, -279.6],
        camera: Camera {
            eye: [278.0, 273.0, -800.0],
            target: [278.0, 273.0, 0.0],
            up: [0.0, 0.0, 1.0],
            fov_y_deg: 39.3,
            width: 640,
            height: 480,
        },
        bounds_min: [-278.0, -274.4, -279.6],
        bounds_max: [278.0, 274.4, 279.6],
        partial: true,
        mode: SolveMode::Directional,
        stats: SolveStats {
            shots: 1234,
            rays: 987_654_321,
            seconds: 12.5,
            unshot_fraction: 0.0042,
            emitted_power: 3.75e3,
            ambient: [0.01, 0.02, 0.03],
        },
        settings_json: r#"{"preset":"draft","threshold":0.001,"note":"é ü"}"#.into(),
    };
    let quad = Batch {
        representation: Representation::Sh { order: 0 },
        scalar: ScalarType::F32,
        vertices: vec![
            vertex([-1.0, 0.0, -1.0]),
            vertex([1.0, 0.0, -1.0]),
            vertex([1.0, 0.0, 1.0]),
            vertex([-1.0, 0.0, 1.0]),
        ],
        coefficients: (0..12).map(|k| 0.1 * k as f32 + 1e-7).collect(),
        indices: vec![0, 2, 1, 0, 3, 2],
        texturing: None,
    };
    let glossy = Batch {
        representation: Representation::Sh { order: 2 },
        scalar: ScalarType::F16 { scale: 0.25 },
        vertices: vec![
            vertex([0.0, 1.0, 0.0]),
            vertex([1.0, 1.0, 0.0]),
            vertex([0.0, 1.0, 1.0]),
        ],
        // Spans several binades, signs, and the half subnormal range (1e-7/0.25).
        coefficients: (0..3 * 9 * 3)
            .map(|k| {
                if k % 7 == 0 {
                    1e-7 * (k + 1) as f32
                } else {
                    (k as f32 - 40.0) * 3.7
                }
            })
            .collect(),
        indices: vec![0, 1, 2],
        texturing: None,
    };
    let cube = Batch {
        representation: Representation::Cube { directions: 6 },
        scalar: ScalarType::F32,
        vertices: vec![
            vertex([2.0, 0.0, 0.0]),
            vertex([3.0, 0.0, 0.0]),
            vertex([2.0, 0.0, 1.0]),
        ],
        coefficients: (0..3 * 6 * 3).map(|k| k as f32 * 0.5).collect(),
        indices: vec![0, 2, 1],
        texturing: None,
    };
    Solution {
        lighting: None,
        header,
        batches: vec![quad, glossy, cube],
        textures: Vec::new(),
    }
}

/// The bound on f16 storage error stated in `docs/solution-format.md`: rounding
/// `v / scale` to half is within 2⁻¹¹ relative for normal halves and 2⁻²⁵ absolute
/// (half the subnormal spacing 2⁻²⁴) below 2⁻¹⁴, times the scale; the factor
/// 1.001 covers the two f32 roundings (2⁻²⁴ each) of a scale that is not a power
/// of two.
fn f16_tolerance(value: f32, scale: f32) -> f32 {
    2f32.powi(-11) * value.abs() * 1.001 + 2f32.powi(-25) * scale
}

pub(super) fn assert_same(decoded: &Solution, original: &Solution) {
    assert_eq!(decoded.header, original.header);
    assert_eq!(decoded.batches.len(), original.batches.len());
    for (d, o) in decoded.batches.iter().zip(&original.batches) {
        assert_eq!(d.representation, o.representation);
        assert_eq!(d.scalar, o.scalar);
        assert_eq!(d.vertices, o.vertices);
        assert_eq!(d.indices, o.indices);
        assert_eq!(d.texturing, o.texturing);
        match o.scalar {
            ScalarType::F32 => assert_eq!(d.coefficients, o.coefficients),
            ScalarType::F16 { scale } => {
                assert_eq!(d.coefficients.len(), o.coefficients.len());
                for (k, (x, y)) in d.coefficients.iter().zip(&o.coefficients).enumerate() {
                    let tol = f16_tolerance(*y, scale);
                    assert!(
                        (x - y).abs() <= tol,
                        "coefficient {k}: {x} vs {y} (tol {tol})"
                    );
                }
            }
        }
    }
    assert_eq!(decoded.textures, original.textures);
}

/// Rewrites the metadata checksum after a test patched the header or tables, so
/// that the check under test (not the checksum) is what refuses the file.
pub(super) fn fix_metadata_crc(bytes: &mut [u8]) {
    let len = u64::from_le_bytes(bytes[pf::METADATA_LENGTH..][..8].try_into().unwrap());
    let len = len.min(bytes.len() as u64) as usize;
    let crc = layout::metadata_crc(&bytes[..len]);
    bytes[pf::METADATA_CRC..][..4].copy_from_slice(&crc.to_le_bytes());
}

pub(super) fn patch(bytes: &[u8], at: usize, value: &[u8]) -> Vec<u8> {
    let mut out = bytes.to_vec();
    out[at..at + value.len()].copy_from_slice(value);
    fix_metadata_crc(&mut out);
    out
}

pub(super) fn problem(bytes: &[u8]) -> Problem {
    match decode(bytes) {
        Ok(_) => panic!("decode accepted invalid bytes"),
        Err(e) => e.problem().cloned().expect("a data problem, not I/O"),
    }
}

const HEADER_AT: usize = layout::PREAMBLE_LEN;
fn batch_at(b: usize) -> usize {
    HEADER_AT + layout::HEADER_LEN + b * layout::BATCH_ENTRY_LEN
}
fn section_at(bytes: &[u8], s: usize) -> usize {
    let batches = u32::from_le_bytes(bytes[pf::BATCH_COUNT..][..4].try_into().unwrap()) as usize;
    batch_at(batches) + s * layout::SECTION_ENTRY_LEN
}
fn section_range(bytes: &[u8], s: usize) -> std::ops::Range<usize> {
    let at = section_at(bytes, s);
    let offset = u64::from_le_bytes(bytes[at + sf::OFFSET..][..8].try_into().unwrap()) as usize;
    let length = u64::from_le_bytes(bytes[at + sf::LENGTH..][..8].try_into().unwrap()) as usize;
    offset..offset + length
}

#[test]
fn encode_decode_round_trip() {
    let original = sample_solution();
    let bytes = encode(&original).unwrap();
    assert_same(&decode(&bytes).unwrap(), &original);
    // f32 batches and the header come back bit for bit.
    let decoded = decode(&bytes).unwrap();
    assert_eq!(decoded.batches[0], original.batches[0]);
    assert_eq!(decoded.batches[2], original.batches[2]);
}

#[test]
fn reencoding_a_decoded_file_is_byte_identical() {
    // Holds for f16 too: decoding gives half × scale, and re-encoding divides by
    // the same scale and rounds to the same half.
    for scale in [0.25f32, 0.3] {
        let mut solution = sample_solution();
        solution.batches[1].scalar = ScalarType::F16 { scale };
        let bytes = encode(&solution).unwrap();
        let again = encode(&decode(&bytes).unwrap()).unwrap();
        assert_eq!(bytes, again, "scale {scale}");
    }
}

#[test]
fn empty_solution_round_trips() {
    let mut solution = sample_solution();
    solution.batches.clear();
    solution.header.settings_json.clear();
    let bytes = encode(&solution).unwrap();
    assert_eq!(decode(&bytes).unwrap(), solution);
}

#[test]
fn sections_are_aligned_and_sized_as_documented() {
    let solution = sample_solution();
    let bytes = encode(&solution).unwrap();
    assert_eq!(&bytes[..8], &layout::MAGIC);
    let sections = 1 + 3 * solution.batches.len();
    for s in 0..sections {
        assert_eq!(section_range(&bytes, s).start % 64, 0, "section {s}");
    }
    // Batch 1: 3 vertices × 9 coefficients × 3 channels × 2 bytes.
    assert_eq!(section_range(&bytes, 5).len(), 3 * 9 * 3 * 2);
    assert_eq!(section_range(&bytes, 4).len(), 3 * 36);
    assert_eq!(section_range(&bytes, 6).len(), 3 * 4);
    // Vertex 0 of batch 0 is its position, normal, tangent as little-endian f32.
    let v = section_range(&bytes, 1).start;
    assert_eq!(&bytes[v..v + 4], &(-1.0f32).to_le_bytes());
    assert_eq!(&bytes[v + 16..v + 20], &1.0f32.to_le_bytes());
}

#[test]
fn every_truncation_is_refused() {
    let bytes = encode(&sample_solution()).unwrap();
    for len in 0..bytes.len() {
        let err = decode(&bytes[..len]).expect_err("truncated file accepted");
        let p = err.problem().expect("data problem");
        assert!(
            matches!(p, Problem::TooShort { .. } | Problem::LengthMismatch { .. }),
            "length {len}: {p}"
        );
    }
    // Appended bytes are refused too.
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(matches!(problem(&longer), Problem::LengthMismatch { .. }));
}

#[test]
fn every_single_bit_flip_is_refused() {
    // Each bit of the file is covered by the magic, version or length checks, the
    // metadata CRC, a section CRC, or the zero-padding check, so no flip anywhere
    // (header, tables, any section, padding) goes unnoticed.
    let bytes = encode(&sample_solution()).unwrap();
    let sections = 1 + 3 * 3;
    let ranges: Vec<_> = (0..sections).map(|s| section_range(&bytes, s)).collect();
    let mut flipped_in_section = vec![0usize; sections];
    for at in 0..bytes.len() {
        for bit in 0..8 {
            let mut bad = bytes.clone();
            bad[at] ^= 1 << bit;
            let p = problem(&bad);
            if let Some(s) = ranges.iter().position(|r| r.contains(&at)) {
                match &p {
                    Problem::Checksum { what, .. } => {
                        assert!(what.starts_with(&format!("section {s} ")), "{p}")
                    }
                    // A flip that breaks UTF-8 in the settings would also be
                    // refused, but the checksum is checked first.
                    other => panic!("byte {at} in section {s}: unexpected {other}"),
                }
                flipped_in_section[s] += 1;
            }
        }
    }
    // Every section was hit (the empty ones have no bytes to flip).
    for (s, n) in flipped_in_section.iter().enumerate() {
        assert_eq!(*n, ranges[s].len() * 8, "section {s}");
        assert!(*n > 0, "section {s} is empty in the sample");
    }
}

#[test]
fn header_flip_is_a_checksum_error() {
    let bytes = encode(&sample_solution()).unwrap();
    let mut bad = bytes.clone();
    bad[HEADER_AT + hf::UNITS_PER_METRE] ^= 0x10;
    assert!(matches!(problem(&bad), Problem::Checksum { .. }));
}

#[test]
fn counts_near_2_pow_40_are_refused_before_allocating() {
    // Allocation cannot follow these counts: every count is checked against the
    // section it describes, whose bounds were checked against the real file length,
    // before anything is sized by it (see `read.rs`). tests/solution_file.rs
    // measures the largest allocation of such a decode.
    let bytes = encode(&sample_solution()).unwrap();
    let big = 1u64 << 40;
    for (field, value) in [
        (batch_at(0) + bf::VERTEX_COUNT, big),
        (batch_at(0) + bf::INDEX_COUNT, big + 2),
        (batch_at(1) + bf::VERTEX_COUNT, u64::MAX),
    ] {
        let p = problem(&patch(&bytes, field, &value.to_le_bytes()));
        assert!(matches!(p, Problem::TooLarge { .. }), "{p}");
    }
    // Below the u32 limit, the count must still match its section's length.
    let p = problem(&patch(
        &bytes,
        batch_at(0) + bf::VERTEX_COUNT,
        &u64::from(u32::MAX).to_le_bytes(),
    ));
    assert!(matches!(p, Problem::SizeMismatch { .. }), "{p}");
    // An index count claiming 2^32 - 1 ≈ 4e9 indices (a multiple of 3).
    let p = problem(&patch(
        &bytes,
        batch_at(0) + bf::INDEX_COUNT,
        &(u64::from(u32::MAX)).to_le_bytes(),
    ));
    assert!(matches!(p, Problem::SizeMismatch { .. }), "{p}");
    // Section lengths and offsets near 2^40 and 2^64 point past the file.
    let s3 = section_at(&bytes, 3);
    let p = problem(&patch(&bytes, s3 + sf::LENGTH, &big.to_le_bytes()));
    assert!(matches!(p, Problem::OutOfBounds { .. }), "{p}");
    let p = problem(&patch(
        &bytes,
        s3 + sf::OFFSET,
        &(u64::MAX - 63).to_le_bytes(),
    ));
    assert!(matches!(p, Problem::OutOfBounds { .. }), "{p}");
    // offset + length would wrap a u64; the reader sums in u128.
    let p = problem(&patch(&bytes, s3 + sf::LENGTH, &u64::MAX.to_le_bytes()));
    assert!(
        matches!(p, Problem::OutOfBounds { end, .. } if end > u128::from(u64::MAX)),
        "{p}"
    );
    // Table counts: the metadata length no longer matches.
    for field in [pf::BATCH_COUNT, pf::SECTION_COUNT] {
        let p = problem(&patch(&bytes, field, &u32::MAX.to_le_bytes()));
        assert!(matches!(p, Problem::BadLength { .. }), "{p}");
    }
    let p = problem(&patch(&bytes, pf::METADATA_LENGTH, &big.to_le_bytes()));
    assert!(matches!(p, Problem::OutOfBounds { .. }), "{p}");
    // An absurd SH order with the vertex count unchanged, and the first order
    // above the one limit that settings, writer and reader share.
    for order in [u32::MAX, MAX_SH_ORDER + 1] {
        let p = problem(&patch(
            &bytes,
            batch_at(1) + bf::REPRESENTATION_PARAMETER,
            &order.to_le_bytes(),
        ));
        assert!(
            matches!(p, Problem::TooLarge { limit, .. } if limit == u64::from(MAX_SH_ORDER)),
            "{p}"
        );
    }
}

#[test]
fn out_of_bounds_message_names_section_and_sizes() {
    let bytes = encode(&sample_solution()).unwrap();
    let s3 = section_at(&bytes, 3);
    let range = section_range(&bytes, 3);
    let bad = patch(&bytes, s3 + sf::LENGTH, &10_000u64.to_le_bytes());
    let message = decode(&bad).unwrap_err().to_string();
    assert_eq!(
        message,
        format!(
            "section 3 (indices of batch 0) ends at byte {} but the file has {} bytes",
            range.start + 10_000,
            bytes.len()
        )
    );
}

#[test]
fn unknown_major_version_is_refused() {
    let bytes = encode(&sample_solution()).unwrap();
    for major in [0u16, layout::VERSION_MAJOR + 1, u16::MAX] {
        let bad = patch(&bytes, pf::VERSION_MAJOR, &major.to_le_bytes());
        let p = problem(&bad);
        assert!(
            matches!(p, Problem::UnsupportedVersion { major: m, .. } if m == major),
            "{p}"
        );
    }
}

#[test]
fn wrong_magic_is_refused() {
    let bytes = encode(&sample_solution()).unwrap();
    let mut bad = bytes.clone();
    bad[..8].copy_from_slice(b"RIFF\0\0\0\0");
    assert!(matches!(problem(&bad), Problem::BadMagic { .. }));
    // A text file that merely starts like one.
    let mut text = b"\x89RAD\n\n\x1a\n".to_vec();
    text.resize(200, b' ');
    assert!(matches!(problem(&text), Problem::BadMagic { .. }));
    assert!(matches!(problem(&[]), Problem::TooShort { len: 0, .. }));
}

#[test]
fn unknown_codes_are_refused() {
    let bytes = encode(&sample_solution()).unwrap();
    let cases: Vec<(usize, u32, &str)> = vec![
        (batch_at(0) + bf::REPRESENTATION, 0, "representation"),
        (batch_at(0) + bf::REPRESENTATION, 3, "representation"),
        (batch_at(0) + bf::SCALAR, 0, "scalar type"),
        (batch_at(0) + bf::SCALAR, 3, "scalar type"),
        (batch_at(0) + bf::FRAME_CONVENTION, 0, "frame convention"),
        (batch_at(0) + bf::FRAME_CONVENTION, 2, "frame convention"),
        (batch_at(0) + bf::BASIS_CONVENTION, 0, "basis convention"),
        // The cube's basis code on an SH batch, and the other way round.
        (
            batch_at(0) + bf::BASIS_CONVENTION,
            layout::BASIS_CUBE_CELL_CENTRES,
            "basis convention",
        ),
        (
            batch_at(2) + bf::BASIS_CONVENTION,
            layout::BASIS_SH_REAL_ORTHONORMAL,
            "basis convention",
        ),
        (HEADER_AT + hf::UP_AXIS, 4, "up axis"),
        (HEADER_AT + hf::MODE, 0, "solve mode"),
        (HEADER_AT + hf::PARTIAL, 2, "partial"),
        (section_at(&bytes, 0) + sf::KIND, 9, "kind"),
    ];
    for (at, code, field) in cases {
        let p = problem(&patch(&bytes, at, &code.to_le_bytes()));
        match &p {
            Problem::UnknownCode { field: f, code: c } => {
                assert!(f.contains(field), "{p}");
                assert_eq!(*c, code);
            }
            other => panic!("code {code} at {at}: {other}"),
        }
    }
}

#[test]
fn reserved_fields_must_be_zero() {
    let bytes = encode(&sample_solution()).unwrap();
    for at in [
        pf::RESERVED_0,
        pf::RESERVED_1,
        HEADER_AT + hf::RESERVED,
        batch_at(1) + bf::RESERVED,
        section_at(&bytes, 2) + sf::RESERVED,
    ] {
        let p = problem(&patch(&bytes, at, &[1]));
        assert!(matches!(p, Problem::Reserved { .. }), "byte {at}: {p}");
    }
}

#[test]
fn bad_section_references_and_placement_are_refused() {
    let bytes = encode(&sample_solution()).unwrap();
    let p = problem(&patch(
        &bytes,
        batch_at(0) + bf::VERTICES_SECTION,
        &99u32.to_le_bytes(),
    ));
    assert!(
        matches!(p, Problem::MissingSection { index: 99, .. }),
        "{p}"
    );
    // Batch 0's vertices pointing at its coefficients.
    let p = problem(&patch(
        &bytes,
        batch_at(0) + bf::VERTICES_SECTION,
        &2u32.to_le_bytes(),
    ));
    assert!(matches!(p, Problem::WrongSectionKind { .. }), "{p}");
    // Batch 1's vertices pointing at batch 0's.
    let p = problem(&patch(
        &bytes,
        batch_at(1) + bf::VERTICES_SECTION,
        &1u32.to_le_bytes(),
    ));
    assert!(matches!(p, Problem::SectionReused { index: 1, .. }), "{p}");
    // A section moved off the 64-byte grid.
    let s1 = section_at(&bytes, 1);
    let start = section_range(&bytes, 1).start as u64;
    let p = problem(&patch(&bytes, s1 + sf::OFFSET, &(start + 4).to_le_bytes()));
    assert!(matches!(p, Problem::Misaligned { .. }), "{p}");
    // Two sections at the same place.
    let s2 = section_at(&bytes, 2);
    let p = problem(&patch(&bytes, s2 + sf::OFFSET, &start.to_le_bytes()));
    assert!(matches!(p, Problem::Overlap { .. }), "{p}");
    // A section over the metadata.
    let p = problem(&patch(&bytes, s2 + sf::OFFSET, &0u64.to_le_bytes()));
    assert!(matches!(p, Problem::Overlap { .. }), "{p}");
}

#[test]
fn bad_values_inside_checksummed_sections_are_refused() {
    // A writer that checksums garbage: the content checks still refuse it.
    let bytes = encode(&sample_solution()).unwrap();
    let rewrite = |s: usize, offset: usize, value: &[u8]| {
        let mut bad = bytes.clone();
        let r = section_range(&bad, s);
        bad[r.start + offset..r.start + offset + value.len()].copy_from_slice(value);
        let crc = crc32fast::hash(&bad[r.clone()]);
        let at = section_at(&bad, s) + sf::CRC;
        bad[at..at + 4].copy_from_slice(&crc.to_le_bytes());
        fix_metadata_crc(&mut bad);
        problem(&bad)
    };
    let p = rewrite(6, 4, &7u32.to_le_bytes());
    assert!(
        matches!(
            p,
            Problem::IndexOutOfRange {
                batch: 1,
                position: 1,
                index: 7,
                ..
            }
        ),
        "{p}"
    );
    let p = rewrite(1, 0, &f32::NAN.to_le_bytes());
    assert!(matches!(p, Problem::NonFinite { .. }), "{p}");
    let p = rewrite(1, 12, &0.5f32.to_le_bytes());
    assert!(matches!(p, Problem::Invalid { .. }), "non-unit normal: {p}");
    let p = rewrite(2, 8, &f32::INFINITY.to_le_bytes());
    assert!(matches!(p, Problem::NonFinite { .. }), "{p}");
    let p = rewrite(5, 2, &half::f16::NAN.to_le_bytes());
    assert!(matches!(p, Problem::NonFinite { .. }), "{p}");
    let p = rewrite(0, 0, &[0xFF]);
    assert!(
        matches!(p, Problem::Invalid { .. }),
        "non-UTF-8 settings: {p}"
    );
}

#[test]
fn newer_minor_version_is_read_by_skipping_what_it_adds() {
    use super::write::{encode_with, EncodeOptions};
    let original = sample_solution();
    let future = EncodeOptions {
        minor: Some(layout::VERSION_MINOR + 1),
        header_extra: 16,
        batch_entry_extra: 8,
        section_entry_extra: 24,
        extra_sections: vec![(77, b"a section a newer writer added".to_vec())],
        texture_sections: None,
    };
    let bytes = encode_with(&original, &future).unwrap();
    assert_same(&decode(&bytes).unwrap(), &original);
    // The same file claiming the current minor version is refused: it has longer
    // blocks and a section kind this version does not define.
    let current = patch(
        &bytes,
        pf::VERSION_MINOR,
        &layout::VERSION_MINOR.to_le_bytes(),
    );
    assert!(matches!(problem(&current), Problem::BadLength { .. }));
    let only_section = EncodeOptions {
        minor: Some(layout::VERSION_MINOR),
        extra_sections: vec![(77, vec![1, 2, 3])],
        ..EncodeOptions::default()
    };
    let bytes = encode_with(&original, &only_section).unwrap();
    assert!(matches!(
        problem(&bytes),
        Problem::UnknownCode { code: 77, .. }
    ));
}

#[test]
fn writer_refuses_invalid_solutions() {
    type Edit = fn(&mut Solution);
    let cases: Vec<(&str, Edit)> = vec![
        ("coefficient count", |s| {
            s.batches[0].coefficients.pop();
        }),
        ("index out of range", |s| s.batches[0].indices[4] = 4),
        ("not triangles", |s| {
            s.batches[0].indices.pop();
        }),
        ("NaN position", |s| {
            s.batches[1].vertices[2].position[1] = f32::NAN
        }),
        ("Inf coefficient", |s| {
            s.batches[2].coefficients[5] = f32::INFINITY
        }),
        ("f16 overflow", |s| s.batches[1].coefficients[3] = 1e6),
        ("zero normal", |s| {
            s.batches[0].vertices[1].normal = [0.0; 3]
        }),
        ("units", |s| s.header.units_per_metre = 0.0),
        ("fov", |s| s.header.camera.fov_y_deg = 180.0),
        ("bounds", |s| s.header.bounds_min[0] = 1e9),
        ("vertex outside the bounds", |s| {
            s.header.bounds_max[0] = 2.5
        }),
        ("camera image size", |s| s.header.camera.width = 100_000),
        ("camera field of view", |s| {
            s.header.camera.fov_y_deg = 179.5
        }),
        ("unshot NaN", |s| s.header.stats.unshot_fraction = f64::NAN),
        ("cube directions", |s| {
            s.batches[2].representation = Representation::Cube { directions: 7 }
        }),
        ("f16 scale", |s| {
            s.batches[1].scalar = ScalarType::F16 { scale: 0.0 }
        }),
        ("SH order", |s| {
            s.batches[0].representation = Representation::Sh {
                order: MAX_SH_ORDER + 1,
            }
        }),
    ];
    for (name, edit) in cases {
        let mut s = sample_solution();
        edit(&mut s);
        let err = encode(&s).expect_err(name);
        assert!(err.problem().is_some(), "{name}: {err}");
    }
    let mut s = sample_solution();
    s.batches[0].indices[4] = 4;
    assert_eq!(
        encode(&s).unwrap_err().to_string(),
        "batch 0: index 4 is 4 but the batch has 4 vertices"
    );
}

#[test]
fn f16_overflow_threshold_matches_the_conversion() {
    // The writer compares |value / scale| with 65520 instead of converting.
    let below = f32::from_bits(65520f32.to_bits() - 1);
    assert_eq!(half::f16::from_f32(below).to_f32(), F16_MAX);
    assert!(half::f16::from_f32(65520.0).is_infinite());
    let mut s = sample_solution();
    s.batches[1].coefficients[0] = below * 0.25;
    assert!(encode(&s).is_ok());
    s.batches[1].coefficients[0] = -65520.0 * 0.25;
    assert!(matches!(
        encode(&s).unwrap_err().problem(),
        Some(Problem::F16Overflow { position: 0, .. })
    ));
}

#[test]
fn f16_scale_is_a_power_of_two_that_fits() {
    assert_eq!(f16_scale_for(&[]), 1.0);
    assert_eq!(f16_scale_for(&[0.0, -0.0]), 1.0);
    for max in [1e-30f32, 1e-3, 1.0, 65504.0, 65505.0, 1e6, 3.4e38] {
        let scale = f16_scale_for(&[0.5 * max, -max, f32::NAN]);
        assert_eq!(
            scale.to_bits() & 0x007F_FFFF,
            0,
            "{scale} is a power of two"
        );
        assert!(max / scale <= F16_MAX, "{max} / {scale}");
        assert!(half::f16::from_f32(-max / scale).is_finite());
        // And it is the smallest such power (unless clamped to the least normal).
        if scale > f32::MIN_POSITIVE {
            assert!(max / (scale / 2.0) > F16_MAX, "{max}: {scale} not minimal");
        }
    }
}

#[test]
fn mapped_file_matches_and_is_aligned() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("room.sol");
    let original = sample_solution();
    write_solution(&path, &original).unwrap();
    let mapped = MappedSolution::open(&path).unwrap();
    assert_eq!(mapped.version(), (layout::UNTEXTURED_VERSION_MAJOR, 0));
    assert_eq!(mapped.header(), &original.header);
    assert_eq!(mapped.batches().len(), 3);
    assert_eq!(
        mapped.batches()[1],
        BatchInfo {
            representation: Representation::Sh { order: 2 },
            scalar: ScalarType::F16 { scale: 0.25 },
            vertex_count: 3,
            index_count: 3,
            frame_convention: layout::FRAME_POLYGON_NTB,
            basis_convention: layout::BASIS_SH_REAL_ORTHONORMAL,
            texture: None,
        }
    );
    for b in 0..3 {
        let info = mapped.batches()[b];
        for (bytes, len) in [
            (mapped.vertex_bytes(b), info.vertex_bytes()),
            (mapped.coefficient_bytes(b), info.coefficient_bytes()),
            (mapped.index_bytes(b), info.index_bytes()),
        ] {
            assert_eq!(bytes.len() as u64, len);
            assert_eq!(bytes.as_ptr() as usize % 64, 0, "batch {b} not 64-aligned");
        }
    }
    assert_eq!(
        mapped.index_bytes(0),
        &[0, 0, 0, 0, 2, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 3, 0, 0, 0, 2, 0, 0, 0]
    );
    assert_same(&mapped.to_solution().unwrap(), &original);
    assert_same(&read_solution(&path).unwrap(), &original);
    assert_eq!(std::fs::read(&path).unwrap(), encode(&original).unwrap());
}

#[test]
fn atomic_write_leaves_no_temporary_and_keeps_old_file_on_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.sol");
    let original = sample_solution();
    write_solution(&path, &original).unwrap();
    let old = MappedSolution::open(&path).unwrap();

    // Replacing the file leaves an existing map reading the old inode's bytes.
    let mut newer = sample_solution();
    newer.header.partial = false;
    write_solution(&path, &newer).unwrap();
    assert!(old.header().partial);
    assert_same(&old.to_solution().unwrap(), &original);
    assert!(!read_solution(&path).unwrap().header.partial);

    // An invalid solution is refused before anything is written.
    let mut invalid = sample_solution();
    invalid.batches[0].coefficients.clear();
    let err = write_solution(&path, &invalid).unwrap_err();
    assert_eq!(err.path(), Some(path.as_path()));
    assert!(!read_solution(&path).unwrap().header.partial);

    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("out.sol")]);

    // A missing directory is an I/O error naming the temporary file's directory.
    let err = write_solution(&dir.path().join("missing/out.sol"), &original).unwrap_err();
    assert!(matches!(err, FormatError::Io { .. }), "{err}");
}

#[test]
fn open_errors_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("short.sol");
    std::fs::write(&path, b"hello").unwrap();
    let err = MappedSolution::open(&path).unwrap_err();
    assert!(matches!(
        err.problem(),
        Some(Problem::TooShort { len: 5, .. })
    ));
    assert!(err.to_string().starts_with(&path.display().to_string()));
    let err = MappedSolution::open(dir.path().join("absent.sol")).unwrap_err();
    assert!(matches!(err, FormatError::Io { .. }));
    assert!(read_solution(&path).is_err());
}

#[test]
fn describe_lists_fields_and_batches() {
    let s = sample_solution();
    let bytes = encode(&s).unwrap();
    let parsed = super::read::parse(&bytes).unwrap();
    let text = describe_text(&parsed.header, &parsed.batches);
    for line in [
        "units_per_metre: 1000",
        "up_axis: +z",
        "partial: true",
        "mode: directional",
        "batches: 3",
        "  representation: sh L=2 (9 coefficients per channel)",
        "  scalar: f16 (scale 0.25)",
        "  coefficient_bytes: 162",
        "  representation: cube D=6 directions",
    ] {
        assert!(
            text.lines().any(|l| l == line),
            "missing {line:?} in\n{text}"
        );
    }
    let json = describe_json(&parsed.header, &parsed.batches);
    assert_eq!(json["units_per_metre"], 1000.0);
    assert_eq!(json["settings"]["preset"], "draft");
    assert_eq!(json["batches"][1]["representation"]["order"], 2);
    assert_eq!(json["batches"][1]["coefficient_bytes"], 162);
    assert_eq!(json["batches"][0]["triangle_count"], 2);
}
