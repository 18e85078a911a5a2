//! The normalization `C_R(μ_i)` that makes the lobe reflect exactly `Ks`
//! (design notes, "Directional mode"; corrects Remington 1992, eq. G.13–G.18).
//!
//! The reflected fraction for incidence μ_i is `∫_H f_s cos θ_o dω_o`, with the
//! cosine weight that Remington 1992, eq. G.13 leaves out. With `g ≈ Σ a_l P_l(ω_o·r)` and
//! `h(t) = t` for t > 0 (0 otherwise), the Funk–Hecke theorem gives
//! `∫_{S²} P_l(ω·r) h(ω·n) dω = 2π P_l(r·n) ∫₀¹ P_l(t) t dt = 2π D_l P_l(μ_i)`
//! (r·n = μ_i for the mirror direction), hence
//!
//! ```text
//! C_R(μ_i) = Ks / (2π Σ_l a_l D_l P_l(μ_i)),   D_l = ∫₀¹ P_l(t) t dt.
//! ```
//!
//! `D_0 = 1/2`, `D_1 = 1/3`, `D_l = 0` for odd l ≥ 3 (t·P_l is then even and its
//! integral over [−1, 1] vanishes), and for even l ≥ 2
//! `D_l = (−1)^{l/2−1} (l−2)! / (2^l (l/2−1)! (l/2+1)!)`, computed by the ratio
//! `D_{l+2}/D_l = −(l−1)/(l+4)` from `D_2 = 1/8` — no factorials, |D_l| ~ l^{-5/2}.

use super::sanitize_alpha;
use solution::sh;
use std::f64::consts::PI;

/// `D_l = ∫₀¹ P_l(t) t dt` (see the module comment). Exact to rounding (< 1e-15
/// relative after l/2 ratio steps of 2 roundings each) for any l.
pub fn funk_hecke_d(l: u32) -> f64 {
    match l {
        0 => 0.5,
        1 => 1.0 / 3.0,
        _ if l % 2 == 1 => 0.0,
        _ => {
            let mut d = 0.125;
            let mut k = 2;
            while k < l {
                d *= -((k as f64) - 1.0) / (k as f64 + 4.0);
                k += 2;
            }
            d
        }
    }
}

/// `D_0 … D_order` in one pass.
pub fn funk_hecke_d_all(order: u32) -> Vec<f64> {
    let mut out = Vec::with_capacity(order as usize + 1);
    let mut even = 0.125;
    for l in 0..=order {
        out.push(match l {
            0 => 0.5,
            1 => 1.0 / 3.0,
            2 => 0.125,
            _ if l % 2 == 1 => 0.0,
            _ => {
                even *= -((l as f64) - 3.0) / (l as f64 + 2.0);
                even
            }
        });
    }
    out
}

/// `2π Σ_l a_l D_l P_l(μ_i)`: the cosine-weighted hemispherical integral of the
/// expanded lobe with `C_R = 1`.
pub fn hemisphere_integral(a: &[f64], mu_i: f64) -> f64 {
    if a.is_empty() {
        return 0.0;
    }
    let order = a.len() as u32 - 1;
    let d = funk_hecke_d_all(order);
    let mut p = vec![0.0; a.len()];
    sh::legendre_all(order, mu_i.clamp(-1.0, 1.0), &mut p);
    2.0 * PI
        * a.iter()
            .zip(&d)
            .zip(&p)
            .map(|((a, d), p)| a * d * p)
            .sum::<f64>()
}

/// `C_R(μ_i) = Ks / (2π Σ_l a_l D_l P_l(μ_i))` (design notes; Remington 1992, eq. G.18 with the
/// cosine weight). `ks` is the lobe's reflectance (1 for the shape alone), `a` the
/// (windowed) Legendre coefficients actually used. μ_i is clamped to [0, 1].
///
/// Returns 0 when the denominator is not positive, which only a badly truncated
/// expansion can cause (the exact lobe's integral is positive for every μ_i ≥ 0):
/// reflecting nothing is then the safe, energy-conserving answer.
pub fn normalization(ks: f64, a: &[f64], mu_i: f64) -> f64 {
    let s = hemisphere_integral(a, mu_i.clamp(0.0, 1.0));
    if s > 0.0 && s.is_finite() {
        ks / s
    } else {
        0.0
    }
}

/// `∫_H g(ω·r) cos θ dω` for the exact lobe (not its expansion), by 2-D
/// Gauss–Legendre quadrature over the hemisphere in the normal's (θ, φ): an
/// independent check of the Funk–Hecke form and the reference for `C_R`.
///
/// The integrand is smooth on the hemisphere (the cosine factor vanishes linearly at
/// its rim), so the rule only has to resolve the narrow peak: θ runs over the band
/// within θ_cut of the mirror direction, where `g(θ_cut) = e^{−40}` (the neglected
/// rest is < 1e-17 of the total), and φ over the part of that band inside the cut;
/// both are split into panels no wider than α/2 of arc (α/(2 sin θ) in φ, at most
/// 0.1 rad) with 16 nodes each (≥ 32 nodes per width of the lobe). Relative accuracy ~1e-12 (test: doubling the panels).
pub fn exact_hemisphere_integral(alpha: f64, mu_i: f64) -> f64 {
    exact_hemisphere_integral_with(alpha, mu_i, 1)
}

pub(crate) fn exact_hemisphere_integral_with(alpha: f64, mu_i: f64, refine: usize) -> f64 {
    let alpha = sanitize_alpha(alpha);
    let mu_i = mu_i.clamp(0.0, 1.0);
    let theta_r = mu_i.acos();
    let (sin_r, cos_r) = theta_r.sin_cos();
    let theta_cut = (2.0 * (alpha * 40f64.sqrt()).atan()).min(PI);
    let cos_cut = theta_cut.cos();
    let h_max = (0.5 * alpha).min(0.1);
    let (x, w) = sh::gauss_legendre(16);
    let panel_rule = |a: f64, b: f64, h_max: f64, mut f: Box<dyn FnMut(f64) -> f64 + '_>| -> f64 {
        if b <= a {
            return 0.0;
        }
        let panels = (((b - a) / h_max).ceil() as usize).max(1) * refine;
        let h = (b - a) / panels as f64;
        let mut sum = 0.0;
        for p in 0..panels {
            let lo = a + p as f64 * h;
            for (xi, wi) in x.iter().zip(&w) {
                sum += 0.5 * h * wi * f(lo + 0.5 * h * (xi + 1.0));
            }
        }
        sum
    };
    let theta_lo = (theta_r - theta_cut).max(0.0);
    let theta_hi = (theta_r + theta_cut).min(0.5 * PI);
    // Mirror direction at φ = 0; the integrand is even in φ, so integrate [0, π] twice.
    let outer = |theta: f64| -> f64 {
        let (sin_t, cos_t) = theta.sin_cos();
        // φ where the angle to r reaches θ_cut: cos(angle) = cosθ cosθ_r + sinθ sinθ_r cosφ.
        let denom = sin_t * sin_r;
        let phi_max = if denom <= 1e-300 {
            PI
        } else {
            let c = (cos_cut - cos_t * cos_r) / denom;
            if c <= -1.0 {
                PI
            } else if c >= 1.0 {
                0.0
            } else {
                c.acos()
            }
        };
        let inner = |phi: f64| {
            let mu0 = (cos_t * cos_r + sin_t * sin_r * phi.cos()).clamp(-1.0, 1.0);
            // The angle from r by acos loses precision near 0; use the half-angle
            // form: tan²(θ0/2) = (1 − μ0)/(1 + μ0) with 1 − μ0 from a stable sum.
            let one_minus = 2.0 * ((0.5 * (theta - theta_r)).sin().powi(2))
                + sin_t * sin_r * 2.0 * (0.5 * phi).sin().powi(2);
            // The lobe g(μ0) of Remington 1992, eq. 4.2, written with the stable 1 − μ0.
            if 1.0 + mu0 <= 0.0 {
                0.0
            } else {
                (-one_minus / (alpha * alpha * (1.0 + mu0))).exp()
            }
        };
        // A step dφ moves sin θ·dφ on the sphere: panels of α/2 in arc length.
        let h_phi = if sin_t > 1e-12 {
            (h_max / sin_t).min(0.1)
        } else {
            0.1
        };
        2.0 * cos_t * sin_t * panel_rule(0.0, phi_max, h_phi, Box::new(inner))
    };
    panel_rule(theta_lo, theta_hi, h_max, Box::new(outer))
}

/// `C_R(μ_i)` tabulated on a uniform grid of μ_i ∈ [0, 1] and interpolated by
/// cubic Catmull–Rom splines of the denominator `S(μ_i) = 2π Σ a_l D_l P_l(μ_i)`
/// (a polynomial of degree L, smoother than its reciprocal). The measured
/// interpolation error (relative, of `C_R`, at every interval's midpoint and
/// quarter points against the direct sum) is kept in
/// [`NormalizationTable::interpolation_error`].
#[derive(Clone, Debug)]
pub struct NormalizationTable {
    ks: f64,
    /// `S` at `μ_j = j / (n − 1)`.
    denominators: Vec<f64>,
    interpolation_error: f64,
}

impl NormalizationTable {
    /// A table with `samples` (≥ 4) grid points.
    pub fn new(ks: f64, a: &[f64], samples: usize) -> Self {
        let n = samples.max(4);
        let denominators: Vec<f64> = (0..n)
            .map(|j| hemisphere_integral(a, j as f64 / (n - 1) as f64))
            .collect();
        let mut table = NormalizationTable {
            ks,
            denominators,
            interpolation_error: 0.0,
        };
        let mut worst: f64 = 0.0;
        for j in 0..n - 1 {
            for frac in [0.25, 0.5, 0.75] {
                let mu = (j as f64 + frac) / (n - 1) as f64;
                let exact = normalization(ks, a, mu);
                let approx = table.c_r(mu);
                let err = if exact > 0.0 {
                    (approx - exact).abs() / exact
                } else if approx == 0.0 {
                    0.0
                } else {
                    f64::INFINITY
                };
                worst = worst.max(err);
            }
        }
        table.interpolation_error = worst;
        table
    }

    /// Doubles the grid (from 8·(L+1) points) until the measured interpolation error
    /// is at most `rel_tolerance`, up to 2^16 points.
    pub fn with_tolerance(ks: f64, a: &[f64], rel_tolerance: f64) -> Self {
        let mut samples = 8 * a.len().max(1) + 1;
        loop {
            let table = Self::new(ks, a, samples);
            if table.interpolation_error <= rel_tolerance || samples >= 1 << 16 {
                return table;
            }
            samples = 2 * samples - 1;
        }
    }

    /// Largest measured relative error of [`Self::c_r`] against [`normalization`].
    pub fn interpolation_error(&self) -> f64 {
        self.interpolation_error
    }

    pub fn samples(&self) -> usize {
        self.denominators.len()
    }

    /// Interpolated `C_R(μ_i)`, μ_i clamped to [0, 1]; 0 where the interpolated
    /// denominator is not positive (see [`normalization`]).
    pub fn c_r(&self, mu_i: f64) -> f64 {
        let s = self.denominator(mu_i);
        if s > 0.0 && s.is_finite() {
            self.ks / s
        } else {
            0.0
        }
    }

    fn denominator(&self, mu_i: f64) -> f64 {
        let n = self.denominators.len();
        let t = if mu_i.is_nan() {
            0.0
        } else {
            mu_i.clamp(0.0, 1.0)
        } * (n - 1) as f64;
        let j = (t.floor() as usize).min(n - 2);
        let f = t - j as f64;
        let s = &self.denominators;
        let p1 = s[j];
        let p2 = s[j + 1];
        // Catmull–Rom with one-sided (linear) extrapolation at the ends.
        let p0 = if j > 0 { s[j - 1] } else { 2.0 * p1 - p2 };
        let p3 = if j + 2 < n { s[j + 2] } else { 2.0 * p2 - p1 };
        let f2 = f * f;
        let f3 = f2 * f;
        0.5 * (2.0 * p1
            + (p2 - p0) * f
            + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * f2
            + (3.0 * p1 - p0 - 3.0 * p2 + p3) * f3)
    }
}
