//! Stage 5, the content of each batch: finite values, orthonormal frames,
//! positions inside the header bounds and indices below the vertex count; and the
//! decoding of one vertex, shared with [`super::materialize`].

use super::super::error::Problem;
use super::super::layout::{self, Fields};
use super::super::validate;
use super::super::{Header, ScalarType, TexturedVertex, Vertex};
use super::BatchInfo;
use std::ops::Range;

pub(super) fn vertex_at(chunk: &[u8]) -> Vertex {
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

pub(super) fn textured_vertex_at(chunk: &[u8]) -> TexturedVertex {
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
pub(super) fn check_content(
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
pub(super) fn check_finite_coefficients(
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
