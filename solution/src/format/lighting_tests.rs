//! Minor version 1 (issue 41): the exposure key, the lights and the
//! environment, their round trips in 1.1, 2.1 and 3.1, their validation, and
//! x.0 files staying what they were.

use super::emission_slot_tests::two_slot_solution;
use super::layout::{self, header as hf, preamble as pf, section as sf};
use super::lighting::{prefix, ENVIRONMENT_PREFIX_LEN};
use super::tests::{assert_same, fix_metadata_crc, problem, sample_solution};
use super::texture_tests::textured_solution;
use super::*;

/// A small environment: 4 × 2 texels of distinct values and a 0.53° sun.
fn environment() -> Environment {
    Environment {
        width: 4,
        height: 2,
        texels: (0..8)
            .map(|k| [k as f32, 0.5 * k as f32, 1e-3 * k as f32])
            .collect(),
        sun: Some(SunDisc {
            direction: [0.6, 0.8, 0.0],
            angular_diameter_deg: 0.53,
            radiance: [2.1e6, 2.0e6, 1.9e6],
        }),
    }
}

fn lighting() -> Lighting {
    Lighting {
        exposure_key: 0.125,
        lights_json: Some(r#"[{"kind":"sun","irradiance":[146,146,146]}]"#.into()),
        environment: Some(environment()),
    }
}

fn lit(mut solution: Solution) -> Solution {
    solution.lighting = Some(lighting());
    solution
}

fn version(bytes: &[u8]) -> (u16, u16) {
    let at = |k: usize| u16::from_le_bytes([bytes[k], bytes[k + 1]]);
    (at(pf::VERSION_MAJOR), at(pf::VERSION_MINOR))
}

fn header_len(bytes: &[u8]) -> u32 {
    u32::from_le_bytes(bytes[pf::HEADER_LENGTH..][..4].try_into().unwrap())
}

#[test]
fn lit_files_round_trip_as_minor_version_1_of_each_major() {
    for (base, major) in [
        (sample_solution(), 1),
        (textured_solution(), 2),
        (two_slot_solution(), 3),
    ] {
        let original = lit(base);
        let bytes = encode(&original).unwrap();
        assert_eq!(version(&bytes), (major, 1));
        assert_eq!(header_len(&bytes) as usize, layout::HEADER_LEN_V1_1);
        let decoded = decode(&bytes).unwrap();
        assert_same(&decoded, &original);
        assert_eq!(decoded.lighting, original.lighting);
        assert_eq!(
            encode(&decoded).unwrap(),
            bytes,
            "re-encoding changed bytes"
        );
    }
}

#[test]
fn files_without_lights_stay_x_0_byte_for_byte() {
    // An empty Lighting is no lighting: the same bytes as None, version x.0,
    // the 216-byte header, no section of the new kinds.
    for base in [sample_solution(), textured_solution(), two_slot_solution()] {
        let plain = encode(&base).unwrap();
        assert_eq!(version(&plain).1, 0);
        assert_eq!(header_len(&plain) as usize, layout::HEADER_LEN);
        let mut empty = base.clone();
        empty.lighting = Some(Lighting::default());
        assert_eq!(encode(&empty).unwrap(), plain);
        assert_eq!(decode(&plain).unwrap().lighting, None);
    }
}

#[test]
fn a_key_alone_or_lights_alone_round_trip() {
    let mut key_only = sample_solution();
    key_only.lighting = Some(Lighting {
        exposure_key: 3.5,
        ..Lighting::default()
    });
    let bytes = encode(&key_only).unwrap();
    assert_eq!(version(&bytes), (1, 1));
    assert_eq!(decode(&bytes).unwrap().lighting, key_only.lighting);
    let mut sun_only = sample_solution();
    sun_only.lighting = Some(Lighting {
        environment: Some(Environment {
            width: 1,
            height: 1,
            texels: vec![[0.0; 3]],
            sun: None,
        }),
        ..Lighting::default()
    });
    let bytes = encode(&sun_only).unwrap();
    assert_eq!(decode(&bytes).unwrap().lighting, sun_only.lighting);
}

#[test]
fn mapped_open_gives_the_lighting() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lit.sol");
    let original = lit(sample_solution());
    write_solution(&path, &original).unwrap();
    let mapped = MappedSolution::open(&path).unwrap();
    assert_eq!(mapped.version(), (1, 1));
    assert_eq!(mapped.lighting(), original.lighting.as_ref());
    let deferring = MappedSolution::open_deferring_checksums(&path).unwrap();
    assert_eq!(deferring.lighting(), original.lighting.as_ref());
}

#[test]
fn every_truncation_and_bit_flip_of_a_lit_file_is_refused() {
    let bytes = encode(&lit(sample_solution())).unwrap();
    for len in 0..bytes.len() {
        assert!(
            decode(&bytes[..len]).is_err(),
            "truncation to {len} accepted"
        );
    }
    for at in 0..bytes.len() {
        for bit in 0..8 {
            let mut bad = bytes.clone();
            bad[at] ^= 1 << bit;
            assert!(
                decode(&bad).is_err(),
                "flip of byte {at} bit {bit} accepted"
            );
        }
    }
}

/// The section index of the first section of `kind`.
fn section_of_kind(bytes: &[u8], kind: u32) -> usize {
    let table = layout::PREAMBLE_LEN
        + header_len(bytes) as usize
        + u32::from_le_bytes(bytes[pf::BATCH_COUNT..][..4].try_into().unwrap()) as usize
            * layout::BATCH_ENTRY_LEN;
    let count = u32::from_le_bytes(bytes[pf::SECTION_COUNT..][..4].try_into().unwrap());
    (0..count as usize)
        .find(|&s| {
            let at = table + s * layout::SECTION_ENTRY_LEN + sf::KIND;
            u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) == kind
        })
        .expect("a section of that kind")
}

/// `(entry offset, section range)` of section `s`.
fn section_place(bytes: &[u8], s: usize) -> (usize, std::ops::Range<usize>) {
    let table = layout::PREAMBLE_LEN
        + header_len(bytes) as usize
        + u32::from_le_bytes(bytes[pf::BATCH_COUNT..][..4].try_into().unwrap()) as usize
            * layout::BATCH_ENTRY_LEN;
    let at = table + s * layout::SECTION_ENTRY_LEN;
    let read = |k: usize| u64::from_le_bytes(bytes[at + k..][..8].try_into().unwrap()) as usize;
    let offset = read(sf::OFFSET);
    (at, offset..offset + read(sf::LENGTH))
}

/// The lit sample with `edit` applied to its environment section's bytes and
/// every checksum rewritten, so that the content check under test refuses it.
fn with_environment_edit(edit: impl Fn(&mut [u8])) -> Problem {
    let mut bytes = encode(&lit(sample_solution())).unwrap();
    let s = section_of_kind(&bytes, layout::SECTION_ENVIRONMENT);
    let (entry, range) = section_place(&bytes, s);
    edit(&mut bytes[range.clone()]);
    let crc = crc32fast::hash(&bytes[range]);
    bytes[entry + sf::CRC..][..4].copy_from_slice(&crc.to_le_bytes());
    fix_metadata_crc(&mut bytes);
    problem(&bytes)
}

fn put_u32(bytes: &mut [u8], at: usize, v: u32) {
    bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
}
fn put_f32(bytes: &mut [u8], at: usize, v: f32) {
    bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

#[test]
fn hostile_environment_sizes_are_refused_before_allocating() {
    // 2¹⁶ × 2¹⁶ = 2³² texels: above the 2²⁸ cap.
    let p = with_environment_edit(|b| {
        put_u32(b, prefix::WIDTH, 1 << 16);
        put_u32(b, prefix::HEIGHT, 1 << 16);
    });
    assert!(matches!(p, Problem::TooLarge { .. }), "{p}");
    // Within the cap but far beyond the section's bytes.
    let p = with_environment_edit(|b| put_u32(b, prefix::WIDTH, 1 << 20));
    assert!(matches!(p, Problem::SizeMismatch { .. }), "{p}");
    let p = with_environment_edit(|b| put_u32(b, prefix::HEIGHT, 0));
    assert!(matches!(p, Problem::Invalid { .. }), "{p}");
}

#[test]
fn bad_environment_values_are_refused() {
    let texel = ENVIRONMENT_PREFIX_LEN + 12 * 5 + 4;
    type Edit = Box<dyn Fn(&mut [u8])>;
    let cases: Vec<(&str, Edit)> = vec![
        ("NaN texel", Box::new(move |b| put_f32(b, texel, f32::NAN))),
        ("negative texel", Box::new(move |b| put_f32(b, texel, -1.0))),
        (
            "texel format",
            Box::new(|b| put_u32(b, prefix::TEXEL_FORMAT, 2)),
        ),
        ("reserved", Box::new(|b| put_u32(b, prefix::RESERVED_1, 1))),
        (
            "sun direction",
            Box::new(|b| put_f32(b, prefix::SUN_DIRECTION, 0.9)),
        ),
        (
            "sun diameter",
            Box::new(|b| put_f32(b, prefix::SUN_DIAMETER_DEG, 91.0)),
        ),
        (
            "no disc but a radiance",
            Box::new(|b| put_f32(b, prefix::SUN_DIAMETER_DEG, 0.0)),
        ),
        (
            "sun radiance",
            Box::new(|b| put_f32(b, prefix::SUN_RADIANCE, f32::INFINITY)),
        ),
    ];
    for (name, edit) in cases {
        let p = with_environment_edit(edit);
        assert!(
            p.to_string().contains("environment"),
            "{name}: the error names the section: {p}"
        );
    }
}

#[test]
fn bad_key_lights_text_and_references_are_refused() {
    let bytes = encode(&lit(sample_solution())).unwrap();
    let key_at = layout::PREAMBLE_LEN + hf::EXPOSURE_KEY;
    for key in [f32::NAN, -1.0] {
        let mut bad = bytes.clone();
        put_f32(&mut bad, key_at, key);
        fix_metadata_crc(&mut bad);
        assert!(problem(&bad).to_string().contains("exposure_key"));
    }
    // The environment index pointing at the lights section: wrong kind.
    let mut bad = bytes.clone();
    let lights = section_of_kind(&bytes, layout::SECTION_LIGHTS) as u32;
    put_u32(
        &mut bad,
        layout::PREAMBLE_LEN + hf::ENVIRONMENT_SECTION,
        lights,
    );
    fix_metadata_crc(&mut bad);
    assert!(matches!(problem(&bad), Problem::WrongSectionKind { .. }));
    // Lights that are not UTF-8.
    let mut bad = bytes.clone();
    let (entry, range) = section_place(&bytes, lights as usize);
    bad[range.start] = 0xFF;
    let crc = crc32fast::hash(&bad[range]);
    bad[entry + sf::CRC..][..4].copy_from_slice(&crc.to_le_bytes());
    fix_metadata_crc(&mut bad);
    assert!(problem(&bad).to_string().contains("UTF-8"));
    // A 1.0 file may not hold a section of the new kinds.
    let mut old = bytes.clone();
    old[pf::VERSION_MINOR..][..2].copy_from_slice(&0u16.to_le_bytes());
    fix_metadata_crc(&mut old);
    assert!(matches!(problem(&old), Problem::BadLength { .. }));
}

#[test]
fn writer_refuses_bad_lighting() {
    type Edit = fn(&mut Lighting);
    let cases: Vec<(&str, Edit)> = vec![
        ("negative key", |l| l.exposure_key = -1.0),
        ("texel count", |l| {
            l.environment.as_mut().unwrap().texels.pop();
        }),
        ("NaN texel", |l| {
            l.environment.as_mut().unwrap().texels[3][1] = f32::NAN
        }),
        ("huge", |l| {
            let env = l.environment.as_mut().unwrap();
            env.width = 1 << 20;
            env.height = 1 << 20;
        }),
        ("sun", |l| {
            l.environment
                .as_mut()
                .unwrap()
                .sun
                .as_mut()
                .unwrap()
                .direction = [0.0; 3]
        }),
    ];
    for (name, edit) in cases {
        let mut s = lit(sample_solution());
        edit(s.lighting.as_mut().unwrap());
        assert!(encode(&s).is_err(), "{name} accepted");
    }
}

#[test]
fn equirect_orientation_is_as_documented() {
    use crate::camera::UpAxis;
    let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-12);
    // y up: u = 0 on the horizon is +x, a quarter turn is up × x = −z, v = 0
    // is the zenith.
    assert!(close(
        equirect_direction(UpAxis::PosY, 0.0, 0.5),
        [1.0, 0.0, 0.0]
    ));
    assert!(close(
        equirect_direction(UpAxis::PosY, 0.25, 0.5),
        [0.0, 0.0, -1.0]
    ));
    assert!(close(
        equirect_direction(UpAxis::PosY, 0.3, 0.0),
        [0.0, 1.0, 0.0]
    ));
    assert!(close(
        equirect_direction(UpAxis::PosZ, 0.25, 0.5),
        [0.0, 1.0, 0.0]
    ));
    assert!(close(
        equirect_direction(UpAxis::NegZ, 0.1, 1.0),
        [0.0, 0.0, 1.0]
    ));
    for up in [UpAxis::PosY, UpAxis::NegY, UpAxis::PosZ, UpAxis::NegZ] {
        for (u, v) in [(0.1, 0.2), (0.7, 0.9), (0.5, 0.5)] {
            let (u2, v2) = equirect_uv(up, equirect_direction(up, u, v));
            assert!((u2 - u).abs() < 1e-12 && (v2 - v).abs() < 1e-12, "{up}");
        }
    }
}

#[test]
fn sampling_returns_texel_centres_and_interpolates_between() {
    use crate::camera::UpAxis;
    let env = environment();
    let up = UpAxis::PosY;
    for j in 0..env.height {
        for i in 0..env.width {
            let got = env.sky(up, env.texel_direction(up, i, j));
            let want = env.texels[(j * env.width + i) as usize];
            for k in 0..3 {
                assert!((got[k] - want[k]).abs() <= 1e-5 * want[k].max(1.0));
            }
        }
    }
    // Halfway between columns 3 and 0 (u wraps): the mean of the two.
    let d = equirect_direction(up, 1.0, 0.25);
    let got = env.sky(up, d)[0];
    assert!((got - 0.5 * (3.0 + 0.0)).abs() < 1e-5, "{got}");
    // The sun's disc adds its radiance.
    let toward = [0.6, 0.8, 0.0];
    assert!(env.radiance(up, toward)[0] > 2e6);
    assert!(env.radiance(up, [0.8, 0.6, 0.0])[0] < 10.0);
}
