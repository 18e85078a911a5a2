//! Upper bounds of the radiance a batch can produce, from which the scene's
//! radiance scale keeps the half-float colour target in range: over in-memory
//! batches, and over stored coefficient bytes as the mapped upload streams them.

use solution::format::{layout, Batch, Representation, ScalarType};

/// The largest of `factor_c · E_c / π` over a textured batch's stored vertices
/// (20-byte u, v, E/π records): with ρ ≤ 1 the most its textured term can add
/// to a pixel.
pub(super) fn textured_bound(bytes: &[u8], factor: [f32; 3]) -> f64 {
    bytes
        .chunks_exact(layout::TEXTURED_VERTEX_LEN)
        .flat_map(|v| {
            (0..3).map(move |c| {
                let at = 8 + 4 * c;
                f64::from(f32::from_le_bytes([v[at], v[at + 1], v[at + 2], v[at + 3]]))
                    * f64::from(factor[c])
            })
        })
        .fold(0.0f64, f64::max)
}

/// `|Y_lm| ≤ envelope(l) = √((2l+1)/(4π))` (Unsöld) for the first `count`
/// coefficients, index `l² + l + m`.
pub(super) fn envelopes(count: usize) -> Vec<f64> {
    (0..count)
        .map(|k| solution::sh::envelope((k as f64).sqrt().floor() as u32))
        .collect()
}

/// The SH bound of [`radiance_bound`] over vertices whose `n · 3` coefficients
/// `value(v, i)` returns, only the first `envelope.len()` per channel counting.
pub(super) fn sh_bound(
    vertex_count: usize,
    n: usize,
    envelope: &[f64],
    value: impl Fn(usize) -> f32,
) -> f64 {
    let mut bound = 0.0f64;
    for v in 0..vertex_count {
        let mut sum = [0.0f64; 3];
        for (k, e) in envelope.iter().enumerate() {
            for (c, s) in sum.iter_mut().enumerate() {
                *s += f64::from(value((v * n + k) * 3 + c)).abs() * e;
            }
        }
        bound = sum.into_iter().fold(bound, f64::max);
    }
    bound
}

/// An upper bound of the radiance a batch's vertices can produce in any
/// direction: for SH `max_v Σ_k |c_vk| · envelope(l_k)`, with `|Y_lm| ≤
/// envelope(l) = √((2l+1)/(4π))` (Unsöld), only the evaluated orders counting;
/// for a cube the largest |value|, since the bilinear weights are non-negative
/// and sum to 1 (`solution::cube::bilinear`).
pub fn radiance_bound(batch: &Batch, order: u32) -> f64 {
    if let Representation::Cube { .. } = batch.representation {
        return batch
            .coefficients
            .iter()
            .fold(0.0f64, |m, &c| m.max(f64::from(c).abs()));
    }
    let n = batch.representation.coefficients_per_channel() as usize;
    let count = (order as usize + 1).pow(2).min(n);
    sh_bound(batch.vertices.len(), n, &envelopes(count), |i| {
        batch.coefficients.get(i).copied().unwrap_or(0.0)
    })
}

/// [`radiance_bound`] of stored coefficient bytes (a whole number of vertices
/// for SH): f32, or f16 times `scale`. Reads the bytes; converts nothing that
/// is uploaded.
pub(super) fn stored_radiance_bound(
    bytes: &[u8],
    representation: Representation,
    scalar: ScalarType,
    envelope: &[f64],
    half_table: &[f32],
) -> f64 {
    let f32_at = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]).abs();
    // Magnitude only: the sign bit is masked off (the bound sums |c|).
    let f16_at = |b: &[u8]| half_table[usize::from(u16::from_le_bytes([b[0], b[1]]) & 0x7FFF)];
    match (representation, scalar) {
        (Representation::Cube { .. }, ScalarType::F32) => bytes
            .chunks_exact(4)
            .fold(0.0f32, |m, b| m.max(f32_at(b)))
            .into(),
        // Finite halves without their sign order as their bit patterns do, so
        // the largest magnitude is the largest masked pattern.
        (Representation::Cube { .. }, ScalarType::F16 { scale }) => {
            let top = bytes
                .chunks_exact(2)
                .map(|b| u16::from_le_bytes([b[0], b[1]]) & 0x7FFF)
                .max()
                .unwrap_or(0);
            f64::from(half_table[usize::from(top)]) * f64::from(scale)
        }
        (Representation::Sh { .. }, ScalarType::F32) => {
            sh_bound_f32(bytes, representation, envelope)
        }
        (Representation::Sh { .. }, ScalarType::F16 { scale }) => {
            sh_bound_stored(bytes, representation, envelope, 2, f16_at) * f64::from(scale)
        }
    }
}

/// The SH bound of [`radiance_bound`] over stored f32 vertices, summed in f32
/// over twelve lanes (four RGB triples, which the compiler vectorizes) so that
/// it keeps pace with the copy. A sum of m non-negative f32 products is within
/// (m + 1)·2⁻²⁴ relative of the exact one (Higham 2002, §4.2), so scaling it up
/// by that keeps it an upper bound.
pub(super) fn sh_bound_f32(bytes: &[u8], representation: Representation, envelope: &[f64]) -> f64 {
    let n = representation.coefficients_per_channel() as usize;
    let lanes: Vec<f32> = (0..envelope.len() * 3)
        .map(|i| envelope[i / 3] as f32)
        .collect();
    let slack = 1.0 + (envelope.len() as f64 + 1.0) * 2f64.powi(-24);
    let mut bound = 0.0f64;
    for vertex in bytes.chunks_exact(n * 3 * 4) {
        let used = &vertex[..lanes.len() * 4];
        let mut acc = [0.0f32; 12];
        let mut values = used.chunks_exact(48);
        let mut weights = lanes.chunks_exact(12);
        for (v, e) in (&mut values).zip(&mut weights) {
            for j in 0..12 {
                let x = f32::from_le_bytes([v[4 * j], v[4 * j + 1], v[4 * j + 2], v[4 * j + 3]]);
                acc[j] += x.abs() * e[j];
            }
        }
        // The rest starts at a whole RGB triple, so lane j is still channel j % 3.
        for (j, (v, e)) in values
            .remainder()
            .chunks_exact(4)
            .zip(weights.remainder())
            .enumerate()
        {
            acc[j] += f32::from_le_bytes([v[0], v[1], v[2], v[3]]).abs() * e;
        }
        for c in 0..3 {
            let sum = acc[c] + acc[c + 3] + acc[c + 6] + acc[c + 9];
            bound = bound.max(f64::from(sum) * slack);
        }
    }
    bound
}

/// The SH bound of [`radiance_bound`] over stored vertices of `size`-byte
/// scalars that `magnitude` reads.
pub(super) fn sh_bound_stored(
    bytes: &[u8],
    representation: Representation,
    envelope: &[f64],
    size: usize,
    magnitude: impl Fn(&[u8]) -> f32,
) -> f64 {
    let n = representation.coefficients_per_channel() as usize;
    let mut bound = 0.0f64;
    for vertex in bytes.chunks_exact(n * 3 * size) {
        let mut sum = [0.0f64; 3];
        for (rgb, e) in vertex.chunks_exact(3 * size).zip(envelope) {
            for (c, s) in sum.iter_mut().enumerate() {
                *s += f64::from(magnitude(&rgb[c * size..(c + 1) * size])) * e;
            }
        }
        bound = sum.into_iter().fold(bound, f64::max);
    }
    bound
}

/// Every half's magnitude as f32, indexed by its bits without the sign: the
/// bound reads f16 coefficients through it (32 K entries, built once per upload).
pub(super) fn half_magnitudes() -> Vec<f32> {
    (0..0x8000u16)
        .map(|bits| half::f16::from_bits(bits).to_f32())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use solution::format::Vertex;

    /// The bound the mapped upload computes from stored bytes is the bound of
    /// the in-memory batch: for f32 an upper bound within the f32 summation's
    /// rounding (the f32 envelope rounds too, by 2⁻²⁴ per term), and for
    /// f16 the bound of the rounded values, within 2⁻¹¹ relative of the f32
    /// one (each |c| rounds by at most that, and the sum has positive terms).
    #[test]
    fn stored_bound_matches_the_in_memory_bound() {
        let order = 3u32;
        let n = (order as usize + 1).pow(2);
        let vertices = 5;
        let coefficients: Vec<f32> = (0..vertices * n * 3)
            .map(|i| ((i * 37 % 23) as f32 - 11.0) * 0.37)
            .collect();
        let batch = Batch {
            representation: Representation::Sh { order },
            scalar: ScalarType::F32,
            vertices: vec![Vertex::default(); vertices],
            coefficients: coefficients.clone(),
            indices: vec![],
            texturing: None,
        };
        let f32_bytes: Vec<u8> = coefficients.iter().flat_map(|c| c.to_le_bytes()).collect();
        let scale = solution::format::f16_scale_for(&coefficients);
        let f16_bytes: Vec<u8> = coefficients
            .iter()
            .flat_map(|c| half::f16::from_f32(c / scale).to_bits().to_le_bytes())
            .collect();
        let table = half_magnitudes();
        for cap in [order, 1] {
            let expected = radiance_bound(&batch, cap);
            let envelope = envelopes((cap as usize + 1).pow(2));
            let from_f32 = stored_radiance_bound(
                &f32_bytes,
                batch.representation,
                ScalarType::F32,
                &envelope,
                &table,
            );
            // Summed in f32 and scaled up by its rounding bound (sh_bound_f32):
            // never below the f64 bound, at most 2·(16 + 1)·2⁻²⁴ above it.
            assert!(
                from_f32 >= expected * (1.0 - 1e-15)
                    && from_f32 <= expected * (1.0 + 34.0 * 2f64.powi(-24)),
                "{from_f32} vs {expected}"
            );
            let from_f16 = stored_radiance_bound(
                &f16_bytes,
                batch.representation,
                ScalarType::F16 { scale },
                &envelope,
                &table,
            );
            assert!(
                (from_f16 - expected).abs() <= 2f64.powi(-11) * expected,
                "{from_f16} vs {expected}"
            );
        }
        // A cube: the largest magnitude, through the bit patterns for f16.
        let cube = Representation::Cube { directions: 6 };
        let largest = coefficients
            .iter()
            .fold(0.0f64, |m, c| m.max(f64::from(c.abs())));
        let from_f32 = stored_radiance_bound(&f32_bytes, cube, ScalarType::F32, &[], &table);
        assert_eq!(from_f32, largest);
        let from_f16 =
            stored_radiance_bound(&f16_bytes, cube, ScalarType::F16 { scale }, &[], &table);
        assert!((from_f16 - largest).abs() <= 2f64.powi(-11) * largest);
    }

    #[test]
    fn cube_radiance_bound_is_the_largest_value_and_bounds_every_lookup() {
        // k = 3, two vertices with values of both signs.
        let directions = 54u32;
        let coefficients: Vec<f32> = (0..2 * directions as usize * 3)
            .map(|i| ((i * 29 % 17) as f32 - 8.0) * 0.25)
            .collect();
        let largest = coefficients.iter().fold(0.0f32, |m, c| m.max(c.abs()));
        let batch = Batch {
            representation: Representation::Cube { directions },
            scalar: ScalarType::F32,
            vertices: vec![Vertex::default(); 2],
            coefficients,
            indices: vec![],
            texturing: None,
        };
        let bound = radiance_bound(&batch, 0);
        assert_eq!(bound, f64::from(largest));
        // The bilinear weights are convex, so no lookup exceeds it (checked on a
        // grid of directions over the sphere, every face and edge).
        let n = batch.representation.coefficients_per_channel() as usize * 3;
        for values in batch.coefficients.chunks_exact(n) {
            for a in 0..24 {
                for b in 0..12 {
                    let (phi, theta) = (a as f64 * 0.2618, b as f64 * 0.2618 + 0.1);
                    let dir = glam::DVec3::new(
                        theta.sin() * phi.cos(),
                        theta.sin() * phi.sin(),
                        theta.cos(),
                    );
                    for c in solution::cube::eval_rgb(3, values, dir) {
                        assert!(c.abs() <= bound * (1.0 + 1e-12), "{c} > {bound}");
                    }
                }
            }
        }
    }
}
