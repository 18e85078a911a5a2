//! Batches cut to fit a storage buffer every Vulkan device can bind.
//!
//! The runtime binds each batch's coefficients as one storage-buffer range, and
//! a device refuses a range above its `maxStorageBufferRange`. Vulkan guarantees
//! only 2²⁷ bytes (Vulkan 1.3 specification, §"Limit Requirements", table
//! "Required Limits"): lavapipe and many mobile GPUs, headsets among them, stop
//! there. A glossy solve on a fine mesh can exceed it in one SH batch (46,899
//! display vertices at L = 29 held 310 MiB; docs/lab/glossy-final-floor.md), so the solver
//! cuts such a batch into batches of whole triangles that each fit, before it
//! writes the file.

use super::{layout, Batch};

/// The largest storage-buffer range every Vulkan device binds (2²⁷ bytes = 128 MiB).
pub const PORTABLE_STORAGE_RANGE: u64 = 1 << 27;

/// Every batch of `batches` whose coefficients, as stored (the batch's
/// `scalar`, as the runtime counts them), exceed `max_bytes`, replaced in place by batches of
/// consecutive whole triangles whose vertices' coefficients each fit. A
/// vertex that triangles of two pieces share is copied into both, with the
/// same position, frame, coefficients and texturing, so the pieces draw
/// exactly what the batch drew; vertices that no triangle uses are dropped
/// from a cut batch. A batch that fits, or whose single triangle would not
/// fit either, is kept as it is (the runtime then names the limit).
pub fn split_to_storage_range(batches: Vec<Batch>, max_bytes: u64) -> Vec<Batch> {
    let mut out = Vec::with_capacity(batches.len());
    for batch in batches {
        let per_vertex =
            layout::scalar_size(batch.scalar) * batch.representation.coefficients_per_channel() * 3;
        let capacity = max_bytes.checked_div(per_vertex).unwrap_or(u64::MAX);
        let bytes = per_vertex.saturating_mul(batch.vertices.len() as u64);
        if bytes <= max_bytes || capacity < 3 {
            out.push(batch);
            continue;
        }
        out.extend(cut(&batch, capacity as usize));
    }
    out
}

/// `batch` as pieces of consecutive triangles, each with at most `capacity`
/// vertices (`capacity` ≥ 3, so every triangle fits in a piece of its own).
fn cut(batch: &Batch, capacity: usize) -> Vec<Batch> {
    let stride = batch.coefficients.len() / batch.vertices.len().max(1);
    // Per original vertex: its index in the piece being built, or u32::MAX.
    let mut local = vec![u32::MAX; batch.vertices.len()];
    let mut pieces = Vec::new();
    let mut piece = empty_like(batch);
    let mut taken: Vec<usize> = Vec::new();
    for triangle in batch.indices.chunks_exact(3) {
        let fresh = triangle
            .iter()
            .enumerate()
            .filter(|&(k, &v)| local[v as usize] == u32::MAX && !triangle[..k].contains(&v))
            .count();
        if piece.vertices.len() + fresh > capacity {
            for &v in &taken {
                local[v] = u32::MAX;
            }
            taken.clear();
            pieces.push(std::mem::replace(&mut piece, empty_like(batch)));
        }
        for &v in triangle {
            let v = v as usize;
            if local[v] == u32::MAX {
                local[v] = piece.vertices.len() as u32;
                taken.push(v);
                piece.vertices.push(batch.vertices[v]);
                piece
                    .coefficients
                    .extend_from_slice(&batch.coefficients[v * stride..(v + 1) * stride]);
                if let (Some(to), Some(from)) = (&mut piece.texturing, &batch.texturing) {
                    to.vertices.push(from.vertices[v]);
                }
            }
            piece.indices.push(local[v]);
        }
    }
    if !piece.indices.is_empty() {
        pieces.push(piece);
    }
    pieces
}

/// A batch with `batch`'s representation, storage and texturing, and no vertices.
fn empty_like(batch: &Batch) -> Batch {
    Batch {
        representation: batch.representation,
        scalar: batch.scalar,
        vertices: Vec::new(),
        coefficients: Vec::new(),
        indices: Vec::new(),
        texturing: batch.texturing.as_ref().map(|t| super::Texturing {
            vertices: Vec::new(),
            ..t.clone()
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::{Representation, ScalarType, TexturedVertex, Texturing, Vertex};

    /// A grid of `n × n` vertices, two triangles per cell, SH order 2 (27
    /// coefficients per vertex, each distinct), textured when asked.
    fn grid(n: u32, textured: bool) -> Batch {
        let mut vertices = Vec::new();
        let mut coefficients = Vec::new();
        let mut uv = Vec::new();
        for y in 0..n {
            for x in 0..n {
                vertices.push(Vertex {
                    position: [x as f32, y as f32, 0.0],
                    normal: [0.0, 0.0, 1.0],
                    tangent: [1.0, 0.0, 0.0],
                });
                let id = (y * n + x) as f32;
                coefficients.extend((0..27).map(|k| id + k as f32 / 32.0));
                uv.push(TexturedVertex {
                    uv: [x as f32, y as f32],
                    irradiance_over_pi: [id, 0.0, 1.0],
                });
            }
        }
        let mut indices = Vec::new();
        for y in 0..n - 1 {
            for x in 0..n - 1 {
                let v = y * n + x;
                indices.extend([v, v + 1, v + n + 1, v, v + n + 1, v + n]);
            }
        }
        Batch {
            representation: Representation::Sh { order: 2 },
            scalar: ScalarType::F32,
            vertices,
            coefficients,
            indices,
            texturing: textured.then_some(Texturing {
                texture: 0,
                factor: [1.0; 3],
                emission: None,
                vertices: uv,
            }),
        }
    }

    /// Each triangle as its three corners' (position, coefficients, texturing):
    /// what the batch draws, whatever its vertex numbering.
    fn drawn(batches: &[Batch]) -> Vec<String> {
        let mut out: Vec<String> = batches
            .iter()
            .flat_map(|b| {
                let stride = b.coefficients.len() / b.vertices.len();
                b.indices.chunks_exact(3).map(move |t| {
                    let corner = |v: u32| {
                        let v = v as usize;
                        let tex = b.texturing.as_ref().map(|t| t.vertices[v]);
                        format!(
                            "{:?}{:?}{:?}",
                            b.vertices[v],
                            &b.coefficients[v * stride..(v + 1) * stride],
                            tex
                        )
                    };
                    format!("{}|{}|{}", corner(t[0]), corner(t[1]), corner(t[2]))
                })
            })
            .collect();
        out.sort();
        out
    }

    #[test]
    fn a_batch_over_the_range_is_cut_into_pieces_that_fit_and_draw_the_same() {
        for textured in [false, true] {
            let batch = grid(12, textured);
            // 27 coefficients × 4 bytes = 108 bytes a vertex: room for 20.
            let max = 20 * 108;
            let pieces = split_to_storage_range(vec![batch.clone()], max);
            assert!(pieces.len() > 1);
            for p in &pieces {
                assert!(p.vertices.len() <= 20 && !p.indices.is_empty());
                assert_eq!(p.coefficients.len(), 27 * p.vertices.len());
                assert!(p.indices.iter().all(|&i| (i as usize) < p.vertices.len()));
                if let Some(t) = &p.texturing {
                    assert_eq!(t.vertices.len(), p.vertices.len());
                }
            }
            assert_eq!(drawn(&pieces), drawn(&[batch]));
        }
    }

    #[test]
    fn a_batch_that_fits_or_cannot_be_cut_is_kept_as_it_is() {
        let batch = grid(4, false);
        let fits = split_to_storage_range(vec![batch.clone()], 16 * 108);
        assert_eq!(fits, vec![batch.clone()]);
        // Room for two vertices: not even one triangle would fit a piece.
        let tiny = split_to_storage_range(vec![batch.clone()], 2 * 108);
        assert_eq!(tiny, vec![batch]);
    }
}
