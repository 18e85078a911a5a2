//! The BRDF of a material on the cells of a global cube:
//! `f_r(ω_i, ω_o) = Kd/π + Ks · C_i · g(ω_o · r_i)` with the thesis's lobe `g`
//! ([`brdf::lobe`], Remington 1992, eq. 4.2) evaluated exactly at the cell directions — not
//! its Legendre expansion, so the cube has no truncation and no ringing.
//!
//! ## Normalization
//!
//! The SH mode normalizes the expansion it actually uses (design notes,
//! "Directional mode"); the cube does the same with the lobe it actually uses,
//! its point values on the H upper cells. With `Q_i = Σ_o g(ω_o·r_i) cosθ_o Ω_o`
//! (Ω_o the exact cell solid angle, [`solution::cube::cell_solid_angle`]) — the
//! cube's own quadrature of `S(μ_i) = ∫_H g(ω·r_i) cosθ dω`:
//!
//! `C_i = 1 / Q_i` (the thesis's normalization), so every incident beam
//! reflects exactly `Ks` in the cube's quadrature, however coarse the cube
//! (not reciprocal).
//!
//! Normalizing by the exact `S(μ_i)` instead would keep point values exact but
//! make a lobe narrower than a cell reflect several times the light it
//! receives (at k = 2, α = 0.1 about 4×: the mirror cell's value times its
//! solid angle). As k grows `Q_i → S(μ_i)` (test
//! `cell_normalization_tends_to_the_exact_integral`), so both converge to the
//! same BRDF. The exact `S` ([`ExactLobe`]) is kept for that test and for
//! references: Funk–Hecke over the lobe's Legendre series carried into its
//! tail, where the rest is below rounding ([`brdf::LegendreFit`]), which agrees
//! with the 2-D quadrature [`brdf::exact_hemisphere_integral`] to ~1e-10 and
//! costs a few hundred terms per μ instead of ~10⁶ lobe evaluations.

use crate::brdf;
use glam::DVec3;

/// The exact (untruncated) lobe of one glossiness and its exact normalizer.
#[derive(Clone, Debug)]
pub struct ExactLobe {
    pub alpha: f64,
    /// Legendre coefficients of g into the tail (see the module documentation).
    coefficients: Vec<f64>,
}

impl ExactLobe {
    /// The lobe of glossiness `alpha` (validated by the caller with
    /// [`brdf::validate_alpha`]).
    pub fn new(alpha: f64) -> ExactLobe {
        let coefficients = brdf::LegendreFit::new(alpha, 0).coefficients;
        ExactLobe {
            alpha,
            coefficients,
        }
    }

    /// `S(μ) = ∫_H g(ω·r) cosθ dω` of the exact lobe, μ clamped to [0, 1].
    pub fn hemisphere_integral(&self, mu: f64) -> f64 {
        brdf::normalization::hemisphere_integral(&self.coefficients, mu.clamp(0.0, 1.0))
    }

    /// The exact normalizer for Ks = 1: `1 / S(μ_i)` (the thesis's C_R);
    /// 0 where `S` is not positive.
    pub fn normalizer(&self, mu_i: f64) -> f64 {
        let s = self.hemisphere_integral(mu_i);
        if s > 0.0 && s.is_finite() {
            1.0 / s
        } else {
            0.0
        }
    }

    /// The exact glossy BRDF for Ks = 1, `C(μ_i) · g(ω_o · r_i)`, for unit
    /// local directions (z = normal) pointing away from the surface; 0 when
    /// either is below the horizon.
    pub fn brdf(&self, omega_i: DVec3, omega_o: DVec3) -> f64 {
        if omega_i.z <= 0.0 || omega_o.z <= 0.0 {
            return 0.0;
        }
        self.normalizer(omega_i.z) * brdf::lobe(self.alpha, omega_o.dot(brdf::mirror(omega_i)))
    }
}

/// One glossy material's lobe on the upper cells of a cube:
/// `matrix[i · H + o] = C_i · g(ω_o · r_i)` for incoming cell i and outgoing
/// cell o (Ks = 1; one incoming cell's reflection is a contiguous row).
#[derive(Clone, Debug)]
pub struct CellBrdf {
    pub alpha: f64,
    pub matrix: Vec<f64>,
    /// `Q_i`, the cube's quadrature of `S(μ_i)` per incoming cell.
    pub quadrature: Vec<f64>,
}

impl CellBrdf {
    /// The matrix over the upper cells' unit local `directions` with their
    /// exact solid angles `solid_angles`.
    pub fn new(alpha: f64, directions: &[DVec3], solid_angles: &[f64]) -> CellBrdf {
        let h = directions.len();
        let mut matrix = vec![0.0; h * h];
        let mut quadrature = vec![0.0; h];
        for ((row, &omega_i), q) in matrix
            .chunks_exact_mut(h.max(1))
            .zip(directions)
            .zip(&mut quadrature)
        {
            let r = brdf::mirror(omega_i);
            for ((m, &omega_o), &solid) in row.iter_mut().zip(directions).zip(solid_angles) {
                *m = brdf::lobe(alpha, omega_o.dot(r));
                *q += *m * omega_o.z * solid;
            }
        }
        for (row, &q) in matrix.chunks_exact_mut(h.max(1)).zip(&quadrature) {
            let c = if q > 0.0 { 1.0 / q } else { 0.0 };
            row.iter_mut().for_each(|m| *m *= c);
        }
        CellBrdf {
            alpha,
            matrix,
            quadrature,
        }
    }
}
