//! How far a normalized lobe is from reciprocal, and what that does to a glossy
//! furnace (design notes, "Directional mode": Remington's (1992) per-incidence `C_R(μ_i)` is
//! not reciprocal, which Immel, Cohen and Greenberg 1986 requires of a BRDF).
//!
//! The BRDF is `f(ω_i, ω_o) = c(μ_i) · g_L(ω_o·r_i)` with `g_L = Σ_l w_l a_l P_l`
//! the lobe the solver stores. The lobe factor is symmetric (`ω_o·mirror(ω_i) =
//! ω_i·mirror(ω_o)`), so `f(ω_i, ω_o) − f(ω_o, ω_i) = (c(μ_i) − c(μ_o)) ·
//! g_L`, and everything here reduces to integrals over (μ_i, μ_o) of the lobe's
//! azimuthal average, which the addition theorem gives in closed form:
//!
//! ```text
//! K(μ_i, μ_o) = ∫₀^{2π} g_L(ω_o·r_i) dφ = 2π Σ_l w_l a_l P_l(μ_i) P_l(μ_o)
//! ```
//!
//! (`r_i` has polar cosine μ_i). Then, with Gauss–Legendre nodes in μ:
//!
//! * the forward albedo `∫ f cosθ_o dω_o = c(μ_i) ∫ K μ_o dμ_o` (Ks for the
//!   thesis's normalization: a check of the quadrature against Funk–Hecke);
//! * the reverse albedo `A(μ_o) = ∫ f cosθ_i dω_i = ∫ c(μ_i) K μ_i dμ_i`: the
//!   radiance a surface sends toward ω_o per unit of uniform incident radiance,
//!   i.e. one bounce of a glossy furnace. A reciprocal BRDF has `A = forward
//!   albedo`; Remington's (1992) has `A ≠ Ks`, so a furnace of uniform emission is not uniform
//!   even though every beam reflects exactly Ks. Its cosine-weighted mean is
//!   exactly Ks (`∫ A cosθ_o dω_o = ∫ Ks cosθ_i dω_i = π Ks`), checked here too.
//! * the pointwise reciprocity error `|f_io − f_oi| / ((f_io + f_oi)/2) =
//!   2|c_i − c_o| / (c_i + c_o)`: its maximum over direction pairs inside the
//!   exact lobe (`g ≥ 1e-3`, i.e. |θ_i − θ_o| within the lobe's cut), and its
//!   RMS weighted by the energy the pair exchanges, `max(K, 0) · μ_i μ_o`;
//! * the energy-weighted L1 error `∫∫ |f_io − f_oi| μ_i μ_o / ∫∫ f_io μ_i μ_o`.
//!
//! The integrand in μ is smooth (a polynomial of degree L in each μ times the
//! normalizer, which is smooth and positive), so `4(L+1) + 64` nodes per axis
//! integrate it to ~1e-12 (the checks above hold to 1e-9 in the tests).

use super::{normalization, GlossyLobe};
use solution::sh;
use std::f64::consts::PI;

/// The reciprocity figures of one lobe and normalization (see the module
/// documentation for the definitions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReciprocityStats {
    pub alpha: f64,
    pub order: u32,
    /// Max over in-lobe direction pairs of |f_io − f_oi| / mean.
    pub max_relative: f64,
    /// Energy-weighted RMS of the same.
    pub rms_relative: f64,
    /// `∫∫ |f_io − f_oi| μ_i μ_o / ∫∫ f_io μ_i μ_o`.
    pub energy_l1: f64,
    /// Smallest and largest forward albedo over μ_i ∈ [0, 1], relative to Ks.
    pub albedo_min: f64,
    pub albedo_max: f64,
    /// Smallest and largest reverse albedo `A(μ_o)` over μ_o ∈ [0, 1], relative
    /// to Ks: the one-bounce radiance of a glossy furnace in units of the
    /// uniform answer (1 for a reciprocal BRDF whose albedo is Ks everywhere).
    pub furnace_min: f64,
    pub furnace_max: f64,
    /// `∫ A cosθ_o dω_o / (π Ks)`, 1 for any normalization that reflects
    /// exactly Ks of every beam (a check of the quadrature for the thesis's).
    pub furnace_mean: f64,
}

/// The figures of `lobe` (see the module documentation).
pub fn reciprocity(lobe: &GlossyLobe) -> ReciprocityStats {
    let order = lobe.order();
    let l_count = order as usize + 1;
    let nodes = 4 * l_count + 64;
    let (mu, w) = sh::gauss_legendre_on(nodes, 0.0, 1.0);
    // P_l at every node, row per node.
    let mut p = vec![0.0; nodes * l_count];
    for (j, &m) in mu.iter().enumerate() {
        sh::legendre_all(order, m, &mut p[j * l_count..(j + 1) * l_count]);
    }
    let c: Vec<f64> = mu.iter().map(|&m| lobe.c_r(m)).collect();
    let kernel = |i: usize, o: usize| -> f64 {
        let (pi, po) = (
            &p[i * l_count..(i + 1) * l_count],
            &p[o * l_count..(o + 1) * l_count],
        );
        2.0 * PI
            * lobe
                .coefficients
                .iter()
                .zip(pi)
                .zip(po)
                .map(|((a, x), y)| a * x * y)
                .sum::<f64>()
    };
    let mut k = vec![0.0; nodes * nodes];
    for i in 0..nodes {
        for o in 0..nodes {
            k[i * nodes + o] = kernel(i, o);
        }
    }
    // The exact lobe's cut: g(θ0) = 1e-3 at tan²(θ0/2) = α² ln 1000.
    let cut = 2.0 * (lobe.alpha * 1000f64.ln().sqrt()).atan();
    let ks = lobe.ks;
    let (mut albedo_min, mut albedo_max) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut furnace_min, mut furnace_max) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut furnace_integral = 0.0;
    for o in 0..nodes {
        // Forward albedo for incidence μ_o (rows and columns are symmetric).
        let forward: f64 = (0..nodes).map(|x| k[o * nodes + x] * mu[x] * w[x]).sum();
        let forward = c[o] * forward / ks;
        albedo_min = albedo_min.min(forward);
        albedo_max = albedo_max.max(forward);
        let reverse: f64 = (0..nodes)
            .map(|i| c[i] * k[i * nodes + o] * mu[i] * w[i])
            .sum::<f64>()
            / ks;
        furnace_min = furnace_min.min(reverse);
        furnace_max = furnace_max.max(reverse);
        furnace_integral += 2.0 * PI * reverse * mu[o] * w[o];
    }
    let (mut max_relative, mut sq, mut weight) = (0.0f64, 0.0, 0.0);
    let (mut diff, mut total) = (0.0, 0.0);
    for i in 0..nodes {
        for o in 0..nodes {
            let rel = 2.0 * (c[i] - c[o]).abs() / (c[i] + c[o]).max(f64::MIN_POSITIVE);
            if (mu[i].acos() - mu[o].acos()).abs() <= cut {
                max_relative = max_relative.max(rel);
            }
            let kk = k[i * nodes + o].max(0.0);
            let e = kk * mu[i] * mu[o] * w[i] * w[o];
            sq += rel * rel * e;
            weight += e;
            diff += (c[i] - c[o]).abs() * e;
            total += c[i] * e;
        }
    }
    ReciprocityStats {
        alpha: lobe.alpha,
        order,
        max_relative,
        rms_relative: if weight > 0.0 {
            (sq / weight).sqrt()
        } else {
            0.0
        },
        energy_l1: if total > 0.0 { diff / total } else { 0.0 },
        albedo_min,
        albedo_max,
        furnace_min,
        furnace_max,
        furnace_mean: furnace_integral / PI,
    }
}

/// The forward albedo from the Funk–Hecke closed form, for cross-checks:
/// `c(μ_i) · 2π Σ a_l D_l P_l(μ_i) / Ks`.
pub fn albedo_closed_form(lobe: &GlossyLobe, mu_i: f64) -> f64 {
    lobe.c_r(mu_i) * normalization::hemisphere_integral(&lobe.coefficients, mu_i) / lobe.ks
}
