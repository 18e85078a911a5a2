//! Remedies for the ringing of a truncated Legendre lobe, and their measurement.
//!
//! A truncated expansion of a peaked lobe oscillates around it and can go negative
//! (Gibbs). Remington 1992, App. G proposes (a) adding a small diffuse component so the sum is
//! positive, or (b) "fixing up" the coefficients. Here (b) is a window `w_l`
//! applied to `a_l` (σ-factors and friends smooth the truncation at the cost of a
//! wider lobe), and the renderer may also clamp negative radiance at evaluation.
//! [`ringing`] measures each remedy: minimum of the lobe, L2 and peak error against
//! the exact lobe, and the negative mass; `docs/lab/sh-ringing.md` records the figures
//! and the default chosen from them.

use super::{lobe_of_angle, sanitize_alpha, LegendreFit};
use serde::{Deserialize, Serialize};
use solution::sh;
use std::f64::consts::PI;

/// A window `w_l` (l = 0..=L) multiplying the Legendre coefficients of a lobe.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Window {
    /// Plain truncation, `w_l = 1`.
    #[default]
    None,
    /// Lanczos σ-factors, `w_l = sinc(l/(L+1)) = sin(πl/(L+1)) / (πl/(L+1))`.
    Sigma,
    /// σ-factors to the fourth power: stronger smoothing, wider lobe.
    Sinc4,
    /// Hann window, `w_l = (1 + cos(πl/(L+1)))/2`.
    Hanning,
}

impl Window {
    pub const ALL: [Window; 4] = [Window::None, Window::Sigma, Window::Sinc4, Window::Hanning];

    /// `w_l` for degree `l` of an expansion truncated at `order`; 0 above `order`.
    pub fn factor(self, l: u32, order: u32) -> f64 {
        if l > order {
            return 0.0;
        }
        let x = PI * l as f64 / (order as f64 + 1.0);
        let sinc = if l == 0 { 1.0 } else { x.sin() / x };
        match self {
            Window::None => 1.0,
            Window::Sigma => sinc,
            Window::Sinc4 => sinc.powi(4),
            Window::Hanning => 0.5 * (1.0 + x.cos()),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Window::None => "none",
            Window::Sigma => "sigma",
            Window::Sinc4 => "sinc4",
            Window::Hanning => "hanning",
        }
    }
}

/// How a windowed, truncated lobe differs from the exact one (all relative to the
/// exact lobe's peak g(1) = 1, or to its L2 norm / integral over μ0 ∈ [−1, 1]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RingingStats {
    pub alpha: f64,
    pub order: u32,
    pub window: Window,
    /// Minimum of `Σ w_l a_l P_l(μ0)` over μ0 ∈ [−1, 1] (negative: it rings below 0).
    pub min_value: f64,
    /// Where the minimum is.
    pub min_at_mu0: f64,
    /// Relative L2 error `‖g_w − g‖ / ‖g‖` (Parseval, exact).
    pub l2_error: f64,
    /// `max |g_w − g|` over μ0 (the peak is 1, so this is relative to the peak).
    pub peak_error: f64,
    /// `∫ max(0, −g_w) dμ0 / ∫ g dμ0`: the negative light, as a fraction of the lobe.
    pub negative_mass: f64,
    /// Relative L2 error of the clamped lobe `max(0, g_w)` (clamp at evaluation).
    pub clamped_l2_error: f64,
    /// Relative L2 error of `g_w − min(0, min_value)`: Remington 1992, App. G remedy (a), a
    /// constant ("small diffuse") added so that the lobe is nowhere negative.
    pub offset_l2_error: f64,
    /// That constant's share of the lobe's integral, `2·offset / ∫ g_w dμ0`: the
    /// fraction of the glossy energy turned diffuse after renormalization.
    pub offset_energy_fraction: f64,
}

/// Measures a lobe truncated at `order` under `window`: minimum, errors and
/// negative mass, on a Gauss–Legendre grid in θ0 with panels no wider than
/// min(α/2, 2/(L+1)) (20 nodes each; ≥ 10 nodes per half-period of `P_L`), so the
/// sampled minimum is within ~1e-4 of the true one and the integrals are exact to
/// rounding.
pub fn ringing(alpha: f64, order: u32, window: Window) -> RingingStats {
    let alpha = sanitize_alpha(alpha);
    let fit = LegendreFit::new(alpha, order);
    let a: Vec<f64> = (0..=order)
        .map(|l| fit.coefficients[l as usize] * window.factor(l, order))
        .collect();
    let h_max = (0.5 * alpha).min(2.0 / (order as f64 + 1.0)).min(0.05);
    let panels = (PI / h_max).ceil() as usize;
    let h = PI / panels as f64;
    let (x, w) = sh::gauss_legendre(20);
    let mut p = vec![0.0; order as usize + 1];
    let (mut min_value, mut min_at) = (f64::INFINITY, 1.0);
    let mut peak_error: f64 = 0.0;
    let (mut lobe_mass, mut windowed_mass, mut negative_mass) = (0.0, 0.0, 0.0);
    let (mut clamp_err2, mut norm2) = (0.0, 0.0);
    let mut samples = Vec::with_capacity(panels * x.len());
    for panel in 0..panels {
        let lo = panel as f64 * h;
        for (xi, wi) in x.iter().zip(&w) {
            let theta = lo + 0.5 * h * (xi + 1.0);
            let mu = theta.cos();
            let weight = 0.5 * h * wi * theta.sin();
            sh::legendre_all(order, mu, &mut p);
            let gw: f64 = a.iter().zip(&p).map(|(a, p)| a * p).sum();
            let g = lobe_of_angle(alpha, theta);
            if gw < min_value {
                min_value = gw;
                min_at = mu;
            }
            peak_error = peak_error.max((gw - g).abs());
            lobe_mass += weight * g;
            windowed_mass += weight * gw;
            negative_mass += weight * (-gw).max(0.0);
            clamp_err2 += weight * (gw.max(0.0) - g).powi(2);
            norm2 += weight * g * g;
            samples.push((weight, gw, g));
        }
    }
    // The ends μ0 = ±1 are where a Legendre series is extreme; include them.
    for (mu, g) in [(1.0, 1.0), (-1.0, 0.0)] {
        sh::legendre_all(order, mu, &mut p);
        let gw: f64 = a.iter().zip(&p).map(|(a, p)| a * p).sum();
        if gw < min_value {
            min_value = gw;
            min_at = mu;
        }
        peak_error = peak_error.max((gw - g).abs());
    }
    let offset = (-min_value).max(0.0);
    let offset_err2: f64 = samples
        .iter()
        .map(|(wt, gw, g)| wt * (gw + offset - g).powi(2))
        .sum();
    RingingStats {
        alpha,
        order,
        window,
        min_value,
        min_at_mu0: min_at,
        l2_error: fit.error(order, window),
        peak_error,
        negative_mass: negative_mass / lobe_mass,
        clamped_l2_error: (clamp_err2 / norm2).sqrt(),
        offset_l2_error: (offset_err2 / norm2).sqrt(),
        offset_energy_fraction: 2.0 * offset / (windowed_mass + 2.0 * offset),
    }
}
