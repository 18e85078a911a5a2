//! The vertex attributes of an exported batch, written straight into their
//! views of the output buffer: positions and normals in glTF's frame,
//! radiance and its tone map (through the CPU reference renderer's vertex
//! stage, chunk by chunk), and for textured batches E/π and the UVs.

use super::{BatchBytes, ExportOptions, GltfFrame, CHUNK_SCALARS};
use glam::DVec3;
use solution::format::{Batch, BatchInfo, ScalarType, Vertex};
use solution::raster::{shade_vertices, tone_map};

/// The stored vertex at `bytes` (36 bytes: position, normal, tangent as
/// little-endian f32).
pub(super) fn vertex_at(bytes: &[u8]) -> Vertex {
    let f = |k: usize| {
        f32::from_le_bytes([
            bytes[4 * k],
            bytes[4 * k + 1],
            bytes[4 * k + 2],
            bytes[4 * k + 3],
        ])
    };
    Vertex {
        position: [f(0), f(1), f(2)],
        normal: [f(3), f(4), f(5)],
        tangent: [f(6), f(7), f(8)],
    }
}

pub(super) fn put_vec3(out: &mut [u8], v: [f32; 3]) {
    for (slot, value) in out.chunks_exact_mut(4).zip(v) {
        slot.copy_from_slice(&value.to_le_bytes());
    }
}

/// Positions (in metres, +y up) and normals (rotated) into their views;
/// returns the positions' per-axis minimum and maximum.
pub(super) fn write_geometry(
    frame: &GltfFrame,
    vertices: &[u8],
    positions: &mut [u8],
    normals: &mut [u8],
) -> ([f32; 3], [f32; 3]) {
    let (mut min, mut max) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    let stored = vertices.chunks_exact(36);
    for ((v, p_out), n_out) in stored
        .zip(positions.chunks_exact_mut(12))
        .zip(normals.chunks_exact_mut(12))
    {
        let vertex = vertex_at(v);
        let p = frame.file_position(vertex.position);
        for axis in 0..3 {
            min[axis] = min[axis].min(p[axis]);
            max[axis] = max[axis].max(p[axis]);
        }
        put_vec3(p_out, p);
        put_vec3(n_out, frame.direction(vertex.normal));
    }
    (min, max)
}

/// COLOR_0 and `_RADIANCE` for a batch, shading at most [`CHUNK_SCALARS`]
/// coefficients at a time through the CPU reference renderer's vertex stage.
pub(super) fn shade_into(
    info: &BatchInfo,
    bytes: &BatchBytes,
    eye_file: DVec3,
    options: &ExportOptions,
    colors: &mut [u8],
    radiance: &mut [u8],
) -> Result<(), String> {
    let per_vertex = info.coefficients_per_channel() as usize * 3;
    let scalar_bytes = match info.scalar {
        ScalarType::F32 => 4,
        ScalarType::F16 { .. } => 2,
    };
    let chunk = (CHUNK_SCALARS / per_vertex.max(1)).max(1);
    // The same f32 product as the runtime's PNG path (`tonemap_srgb8`).
    let exposure = options.exposure_stops.exp2();
    let vertex_chunks = bytes.vertices.chunks(36 * chunk);
    let coefficient_chunks = bytes.coefficients.chunks(scalar_bytes * per_vertex * chunk);
    let out = colors
        .chunks_mut(12 * chunk)
        .zip(radiance.chunks_mut(12 * chunk));
    for ((v, c), (color_out, radiance_out)) in vertex_chunks.zip(coefficient_chunks).zip(out) {
        let batch = Batch {
            representation: info.representation,
            scalar: ScalarType::F32,
            vertices: v.chunks_exact(36).map(vertex_at).collect(),
            coefficients: widen(info.scalar, c),
            indices: Vec::new(),
            texturing: None,
        };
        // u32::MAX: no order cap; negative radiance clamped as renderers do.
        let shaded = shade_vertices(&batch, u32::MAX, eye_file, true).map_err(|e| e.to_string())?;
        for ((rgb, c_out), r_out) in shaded
            .iter()
            .zip(color_out.chunks_exact_mut(12))
            .zip(radiance_out.chunks_exact_mut(12))
        {
            put_vec3(r_out, *rgb);
            put_vec3(c_out, rgb.map(|x| tone_map(x * exposure, options.curve)));
        }
    }
    Ok(())
}

/// Stored coefficients as f32 values, exactly as the format's reader widens
/// them (`half × scale` for f16).
pub(super) fn widen(scalar: ScalarType, bytes: &[u8]) -> Vec<f32> {
    match scalar {
        ScalarType::F32 => bytes
            .chunks_exact(4)
            .map(|x| f32::from_le_bytes([x[0], x[1], x[2], x[3]]))
            .collect(),
        ScalarType::F16 { scale } => bytes
            .chunks_exact(2)
            .map(|x| half::f16::from_le_bytes([x[0], x[1]]).to_f32() * scale)
            .collect(),
    }
}

/// A textured batch's attributes from its textured-vertex section (per vertex
/// u, v, E/π RGB as little-endian f32): `_RADIANCE` = E/π, COLOR_0 its tone
/// map, `TEXCOORD_0` = (u, 1 − v), since glTF's v runs down from the image's
/// top row (glTF 2.0 §3.8.4.4) and the format's (OBJ's) up from its bottom.
pub(super) fn textured_into(
    textured: &[u8],
    options: &ExportOptions,
    colors: &mut [u8],
    radiance: &mut [u8],
    texcoords: &mut [u8],
) {
    let exposure = options.exposure_stops.exp2();
    let out = colors
        .chunks_exact_mut(12)
        .zip(radiance.chunks_exact_mut(12))
        .zip(texcoords.chunks_exact_mut(8));
    for (t, ((c_out, r_out), uv_out)) in textured.chunks_exact(20).zip(out) {
        let f = |k: usize| f32::from_le_bytes([t[4 * k], t[4 * k + 1], t[4 * k + 2], t[4 * k + 3]]);
        let e = [f(2), f(3), f(4)];
        put_vec3(r_out, e);
        put_vec3(c_out, e.map(|x| tone_map(x * exposure, options.curve)));
        uv_out[..4].copy_from_slice(&f(0).to_le_bytes());
        uv_out[4..].copy_from_slice(&(1.0 - f(1)).to_le_bytes());
    }
}

/// Whether stored coefficients hold any non-zero value.
pub(super) fn has_nonzero(scalar: ScalarType, bytes: &[u8]) -> bool {
    match scalar {
        ScalarType::F32 => bytes
            .chunks_exact(4)
            .any(|x| f32::from_le_bytes([x[0], x[1], x[2], x[3]]) != 0.0),
        ScalarType::F16 { .. } => bytes
            .chunks_exact(2)
            .any(|x| half::f16::from_le_bytes([x[0], x[1]]).to_f32() != 0.0),
    }
}
