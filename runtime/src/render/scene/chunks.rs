//! The chunk partition of a batch's triangles for culling: its index bytes
//! reordered chunk by chunk, with each chunk's bounds.

use crate::render::cull::{partition, Chunk};
use glam::DVec3;
use solution::format::layout;

/// A batch's stored index bytes (`u32` little-endian) reordered chunk by
/// chunk ([`partition`] into chunks of at most `chunk_triangles`), with the
/// chunks; `vertex_bytes` is the batch's vertex section (positions first in
/// each [`layout::VERTEX_LEN`]-byte vertex). The vertex data is only read. An
/// index without a vertex (which the file's checks exclude) makes its
/// triangle's chunk box non-finite, which culling always keeps.
pub(super) fn chunked_indices(
    vertex_bytes: &[u8],
    index_bytes: &[u8],
    chunk_triangles: u32,
) -> (Vec<u8>, Vec<Chunk>) {
    let index = |i: usize| {
        let b = &index_bytes[4 * i..4 * i + 4];
        u32::from_le_bytes([b[0], b[1], b[2], b[3]])
    };
    let position = |v: u32| {
        let start = v as usize * layout::VERTEX_LEN;
        match vertex_bytes.get(start..start + 12) {
            Some(b) => DVec3::from_array(std::array::from_fn(|a| {
                f64::from(f32::from_le_bytes([
                    b[4 * a],
                    b[4 * a + 1],
                    b[4 * a + 2],
                    b[4 * a + 3],
                ]))
            })),
            None => DVec3::NAN,
        }
    };
    let triangles = (index_bytes.len() / 12) as u32;
    let parts = partition(
        triangles,
        |t, k| position(index(3 * t as usize + k)),
        chunk_triangles,
    );
    let mut out = Vec::with_capacity(index_bytes.len());
    for &t in &parts.order {
        out.extend_from_slice(&index_bytes[12 * t as usize..12 * t as usize + 12]);
    }
    (out, parts.chunks)
}
