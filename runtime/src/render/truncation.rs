//! The cost of a runtime cap on the SH order (`--max-order`).
//!
//! The basis is orthonormal, so by Parseval the L2 norm over the sphere of a
//! vertex's radiance is the Euclidean norm of its coefficients, and dropping the
//! bands above `L` removes exactly the norm of the dropped coefficients. Per batch
//! (all vertices and channels together) the relative error is
//! `sqrt(Σ_dropped c² / Σ_all c²)`.

use solution::format::{Batch, Representation};

/// The error a cap costs one batch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Truncation {
    pub batch: usize,
    pub file_order: u32,
    pub kept_order: u32,
    /// `‖dropped‖₂ / ‖all‖₂` over all vertices and channels (0 when nothing is
    /// dropped or the batch is black).
    pub relative_l2: f64,
}

/// The relative L2 error of evaluating `batch` only up to `cap`. `None` for a
/// global-cube batch: the cap does not apply to it (its lookup reads four cells
/// whatever D is, and the renderer draws it in full).
pub fn truncation_error(index: usize, batch: &Batch, cap: u32) -> Option<Truncation> {
    let Representation::Sh { order } = batch.representation else {
        return None;
    };
    let kept = cap.min(order);
    let n = batch.representation.coefficients_per_channel() as usize;
    let kept_count = (kept as usize + 1).pow(2);
    let (mut total, mut dropped) = (0.0f64, 0.0f64);
    for (i, c) in batch.coefficients.iter().enumerate() {
        let energy = f64::from(*c).powi(2);
        total += energy;
        if (i / 3) % n >= kept_count {
            dropped += energy;
        }
    }
    let relative_l2 = if total > 0.0 {
        (dropped / total).sqrt()
    } else {
        0.0
    };
    Some(Truncation {
        batch: index,
        file_order: order,
        kept_order: kept,
        relative_l2,
    })
}

/// One line per batch whose order the cap lowers.
pub fn truncation_report(batches: &[Batch], cap: u32) -> Vec<String> {
    batches
        .iter()
        .enumerate()
        .filter_map(|(i, b)| truncation_error(i, b, cap))
        .filter(|t| t.kept_order < t.file_order)
        .map(|t| {
            format!(
                "batch {}: SH order {} capped to {}: relative L2 error {:.3e} (Parseval: norm of the dropped bands / total)",
                t.batch, t.file_order, t.kept_order, t.relative_l2
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use solution::format::{ScalarType, Vertex};

    fn batch(order: u32, coefficients: Vec<f32>) -> Batch {
        Batch {
            representation: Representation::Sh { order },
            scalar: ScalarType::F32,
            vertices: vec![
                Vertex::default();
                coefficients.len() / ((order as usize + 1).pow(2) * 3)
            ],
            coefficients,
            indices: vec![],
            texturing: None,
        }
    }

    #[test]
    fn parseval_error_of_dropped_bands() {
        // Order 1, one vertex: band 0 has energy 3·1² = 3 (RGB), band 1 has 3·3·2² = 36.
        let mut c = vec![1.0f32; 3];
        c.extend(vec![2.0f32; 9]);
        let b = batch(1, c);
        let t = truncation_error(0, &b, 0).unwrap();
        assert!((t.relative_l2 - (36.0f64 / 39.0).sqrt()).abs() < 1e-12);
        assert_eq!(t.kept_order, 0);
        // No cap below the order: nothing dropped.
        assert_eq!(truncation_error(0, &b, 1).unwrap().relative_l2, 0.0);
        assert_eq!(truncation_error(0, &b, 7).unwrap().kept_order, 1);
        assert_eq!(truncation_report(std::slice::from_ref(&b), 0).len(), 1);
        assert!(truncation_report(&[b], 1).is_empty());
    }

    #[test]
    fn cube_batches_are_left_alone_by_the_cap() {
        let cube = Batch {
            representation: Representation::Cube { directions: 24 },
            scalar: ScalarType::F32,
            vertices: vec![Vertex::default()],
            coefficients: vec![1.0; 24 * 3],
            indices: vec![],
            texturing: None,
        };
        assert_eq!(truncation_error(0, &cube, 0), None);
        assert!(truncation_report(&[cube], 0).is_empty());
    }

    #[test]
    fn parseval_matches_quadrature_of_the_dropped_function() {
        // Independent check: integrate (f_full − f_capped)² over the sphere by
        // quadrature and compare with the coefficient norm.
        let order = 4u32;
        let n = (order as usize + 1).pow(2);
        let coeffs: Vec<f32> = (0..n * 3)
            .map(|i| ((i * 37 % 11) as f32 - 5.0) * 0.1)
            .collect();
        let b = batch(order, coeffs.clone());
        let t = truncation_error(0, &b, 2).unwrap();
        let (mu, w) = solution::sh::gauss_legendre(24);
        let nphi = 48;
        let (mut diff2, mut full2) = (0.0, 0.0);
        let mut capped = coeffs.clone();
        for k in 9..n {
            for c in 0..3 {
                capped[k * 3 + c] = 0.0;
            }
        }
        for (z, wz) in mu.iter().zip(&w) {
            for j in 0..nphi {
                let phi = (j as f64 + 0.5) * std::f64::consts::TAU / nphi as f64;
                let s = (1.0 - z * z).sqrt();
                let d = glam::DVec3::new(s * phi.cos(), s * phi.sin(), *z);
                let full = solution::sh::eval_rgb(order, &coeffs, d);
                let part = solution::sh::eval_rgb(order, &capped, d);
                let dw = wz * std::f64::consts::TAU / nphi as f64;
                for c in 0..3 {
                    diff2 += (full[c] - part[c]).powi(2) * dw;
                    full2 += full[c].powi(2) * dw;
                }
            }
        }
        // Gauss–Legendre with 24 nodes and 48 azimuths integrates products of
        // order-4 harmonics (degree 8) exactly up to f64 rounding.
        assert!(((diff2 / full2).sqrt() - t.relative_l2).abs() < 1e-9);
    }
}
