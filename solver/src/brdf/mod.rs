//! The glossy lobe of Remington 1992, chapter 4 and its Legendre expansion (Remington 1992, eqs. 4.2–4.4,
//! App. E–G; design notes, "Directional mode").
//!
//! The lobe about the mirror direction r is `g(μ0) = exp(−(1−μ0)/(α²(1+μ0)))`,
//! `μ0 = ω_o·r`, where α is the RMS surface slope (Remington 1992, eq. 4.2). It is expanded as
//! `g ≈ Σ_{l≤L} a_l P_l(μ0)` with `a_l = (2l+1)/2 ∫₋₁¹ g P_l dμ0` (Remington 1992, eq. 4.4),
//! which Remington 1992 computed with Mathematica (App. E) and this module computes by
//! Gauss–Legendre quadrature ([`legendre_coefficients`]). The order L follows from
//! α and a relative L2 error target ([`choose_order`]); [`fit_error`] reproduces the
//! design notes' table. The BRDF is `f_s = C_R(μ_i) · g(ω_o·r)` with `C_R` chosen so
//! that the cosine-weighted hemispherical integral is `Ks` for every incidence
//! ([`normalization`], closed form by the Funk–Hecke theorem), and its SH
//! coefficients follow from the addition theorem ([`GlossyLobe::add_lobe_sh`]).
//!
//! Submodules: [`normalization`] (`D_l`, `C_R`, its table and an independent 2-D
//! quadrature of the exact lobe), [`window`] (ringing remedies and their
//! measurement).

pub mod normalization;
pub mod window;

pub use normalization::{
    exact_hemisphere_integral, funk_hecke_d, funk_hecke_d_all, normalization, NormalizationTable,
};
pub use window::{ringing, RingingStats, Window};

use glam::DVec3;
use solution::sh;
use std::f64::consts::PI;

/// Errors of this module: bad glossiness.
#[derive(Debug, thiserror::Error)]
pub enum BrdfError {
    #[error("glossiness alpha = {0} is out of range: expected a finite value ≥ {MIN_ALPHA}")]
    InvalidAlpha(f64),
}

/// Smallest α this module accepts. At α = 0.001 the lobe is 0.1° wide and needs
/// L ≈ 6000 for a 1e-3 fit; below that the expansion is meaningless (a mirror).
pub const MIN_ALPHA: f64 = 1e-3;

/// Checks α (finite, ≥ [`MIN_ALPHA`]) and returns it.
pub fn validate_alpha(alpha: f64) -> Result<f64, BrdfError> {
    if alpha.is_finite() && alpha >= MIN_ALPHA {
        Ok(alpha)
    } else {
        Err(BrdfError::InvalidAlpha(alpha))
    }
}

/// α from an MTL `Ns` exponent: `α = √(2 / (Ns + 2))` (design notes, "Units and
/// conventions"); `Ns ≤ 0` gives α = 1.
pub fn alpha_from_ns(ns: f64) -> f64 {
    (2.0 / (ns.max(0.0) + 2.0)).sqrt()
}

/// The lobe `g(μ0) = exp(−(1−μ0)/(α²(1+μ0)))` (Remington 1992, eq. 4.2), 1 at the mirror
/// direction and 0 at μ0 = −1 (its limit). Values of μ0 outside [−1, 1] are clamped.
pub fn lobe(alpha: f64, mu0: f64) -> f64 {
    let mu0 = mu0.clamp(-1.0, 1.0);
    if mu0 <= -1.0 {
        return 0.0;
    }
    (-(1.0 - mu0) / (alpha * alpha * (1.0 + mu0))).exp()
}

/// The same lobe as a function of the angle θ0 from the mirror direction, using
/// `(1−μ0)/(1+μ0) = tan²(θ0/2)` (Remington 1992, eq. G.4), which keeps full relative precision
/// near θ0 = 0 where `1 − cos θ0` would cancel.
pub fn lobe_of_angle(alpha: f64, theta0: f64) -> f64 {
    if theta0 >= PI {
        return 0.0;
    }
    let t = (0.5 * theta0).tan();
    (-(t * t) / (alpha * alpha)).exp()
}

/// Gauss–Legendre nodes per panel of the lobe quadrature.
const NODES_PER_PANEL: usize = 20;

/// Quadrature of `∫₋₁¹ f(μ0) dμ0` for functions `g(μ0)·(polynomial of degree ≤
/// max_degree)`: returns `(μ0_j, w_j · g(μ0_j))`.
///
/// The integral is taken in θ0 (μ0 = cos θ0, dμ0 = sin θ0 dθ0) where the lobe is
/// close to a Gaussian of width ~α·√2 and `P_l(cos θ0)` oscillates uniformly with
/// period ~2π/l; θ0 runs over [0, θ_max] with `g(θ_max) = e^{−750}` (below the
/// smallest f64), split into panels no wider than α/2, 4/(max_degree+1) and 0.1 rad,
/// each with 20 Gauss–Legendre nodes. The integrand is analytic on each panel and
/// sampled at ≥ 20 nodes per half-width of the lobe and per period of `P_l`, so the
/// rule converges to rounding: doubling the panels changes `a_l` by < 1e-14 of
/// `a_0·(2l+1)` (test `lobe_quadrature_converged`).
fn lobe_quadrature(alpha: f64, max_degree: u32) -> (Vec<f64>, Vec<f64>) {
    lobe_quadrature_with(alpha, max_degree, 1)
}

fn lobe_quadrature_with(alpha: f64, max_degree: u32, refine: usize) -> (Vec<f64>, Vec<f64>) {
    let theta_max = (2.0 * (alpha * 750f64.sqrt()).atan()).min(PI);
    let h_max = (0.5 * alpha).min(4.0 / (max_degree as f64 + 1.0)).min(0.1);
    let panels = ((theta_max / h_max).ceil() as usize).max(1) * refine;
    let h = theta_max / panels as f64;
    let (x, w) = sh::gauss_legendre(NODES_PER_PANEL);
    let mut mu = Vec::with_capacity(panels * NODES_PER_PANEL);
    let mut wg = Vec::with_capacity(panels * NODES_PER_PANEL);
    for p in 0..panels {
        let a = p as f64 * h;
        for (xi, wi) in x.iter().zip(&w) {
            let theta = a + 0.5 * h * (xi + 1.0);
            let weight = 0.5 * h * wi * theta.sin();
            mu.push(theta.cos());
            wg.push(weight * lobe_of_angle(alpha, theta));
        }
    }
    (mu, wg)
}

/// `∫₋₁¹ g(μ) P_l(μ) dμ` for l = 0..=max_degree from a quadrature rule.
fn projections(mu: &[f64], wg: &[f64], max_degree: u32) -> Vec<f64> {
    let n = max_degree as usize + 1;
    let mut out = vec![0.0; n];
    for (&x, &w) in mu.iter().zip(wg) {
        // P_l by the three-term recurrence, inline to avoid a buffer per node.
        let (mut p_prev, mut p) = (0.0, 1.0);
        out[0] += w;
        for (l, slot) in out.iter_mut().enumerate().skip(1) {
            let lf = l as f64;
            let next = if l == 1 {
                x
            } else {
                ((2.0 * lf - 1.0) * x * p - (lf - 1.0) * p_prev) / lf
            };
            p_prev = p;
            p = next;
            *slot += w * p;
        }
    }
    out
}

/// Legendre coefficients `a_0 … a_order` of the lobe (Remington 1992, eq. 4.4):
/// `a_l = (2l+1)/2 ∫₋₁¹ g(μ) P_l(μ) dμ`.
///
/// Accuracy: absolute error below ~1e-14 · a_0 · (2l+1) (rounding of the quadrature
/// sum; see `lobe_quadrature`). α below [`MIN_ALPHA`] or non-finite is clamped to
/// [`MIN_ALPHA`]; callers validate with [`validate_alpha`] first.
pub fn legendre_coefficients(alpha: f64, order: u32) -> Vec<f64> {
    let alpha = sanitize_alpha(alpha);
    let (mu, wg) = lobe_quadrature(alpha, order);
    let mut a = projections(&mu, &wg, order);
    for (l, v) in a.iter_mut().enumerate() {
        *v *= (2.0 * l as f64 + 1.0) / 2.0;
    }
    a
}

fn sanitize_alpha(alpha: f64) -> f64 {
    if alpha.is_finite() {
        alpha.max(MIN_ALPHA)
    } else {
        MIN_ALPHA
    }
}

/// The lobe's Legendre coefficients far enough into the tail that the rest of the
/// series is below rounding, with suffix sums for relative L2 errors of any
/// truncation (Parseval: `‖g‖² = Σ a_l² · 2/(2l+1)` over [−1, 1]).
#[derive(Clone, Debug)]
pub struct LegendreFit {
    pub alpha: f64,
    /// `a_l` for `l = 0..=tail_order`.
    pub coefficients: Vec<f64>,
    /// `‖g‖²` over [−1, 1] (Parseval sum of all `coefficients`).
    pub norm_squared: f64,
}

impl LegendreFit {
    /// Coefficients up to at least `max_order`, and further until the series has
    /// converged. A narrow lobe is close to a heat kernel of variance 2α², whose
    /// coefficients fall like `exp(−l(l+1)α²)`: `l ≈ 7/α` puts the rest below 1e-21
    /// of `‖g‖²`. A broad lobe decays more slowly, because `g` has an essential
    /// singularity at μ0 = −1 (`exp(−2/(α²(1+μ0)))`), so its coefficients fall only
    /// like `exp(−c·l^{2/3})`: measured, α = 1 reaches 1e-13 of a_0 at l = 80 and
    /// rounding level by l = 120. The tail used is `max(10/α, 120α) + 16`.
    pub fn new(alpha: f64, max_order: u32) -> Self {
        let alpha = sanitize_alpha(alpha);
        let tail = (10.0 / alpha).max(120.0 * alpha).ceil() as u32 + 16;
        let coefficients = legendre_coefficients(alpha, max_order.max(tail));
        let norm_squared = coefficients
            .iter()
            .enumerate()
            .map(|(l, a)| a * a * 2.0 / (2.0 * l as f64 + 1.0))
            .sum();
        LegendreFit {
            alpha,
            coefficients,
            norm_squared,
        }
    }

    /// Relative L2 error over μ0 ∈ [−1, 1] of the fit truncated at `order` and
    /// multiplied by `window`: `‖g − Σ_{l≤L} w_l a_l P_l‖ / ‖g‖`, exact by Parseval.
    /// Reliable down to ~1e-13 (below that the tail terms are at rounding level).
    pub fn error(&self, order: u32, window: Window) -> f64 {
        let mut err2 = 0.0;
        for (l, a) in self.coefficients.iter().enumerate() {
            let l = l as u32;
            let w = if l <= order {
                window.factor(l, order)
            } else {
                0.0
            };
            let d = (1.0 - w) * a;
            err2 += d * d * 2.0 / (2.0 * l as f64 + 1.0);
        }
        (err2 / self.norm_squared).sqrt()
    }
}

/// Relative L2 error over μ0 ∈ [−1, 1] of the lobe's Legendre fit truncated at
/// `order` (no window): the quantity of the design notes' table.
pub fn fit_error(alpha: f64, order: u32) -> f64 {
    LegendreFit::new(alpha, order).error(order, Window::None)
}

/// The order chosen for a lobe: the smallest L meeting the error target, or the cap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrderChoice {
    pub order: u32,
    /// Relative L2 error of the fit at `order` (see [`fit_error`]).
    pub error: f64,
    /// True when no order ≤ `max_order` met the target; `order` is then `max_order`
    /// and `error` says how far off it is (the solver warns with it).
    pub capped: bool,
}

/// Smallest order whose (unwindowed) fit meets `error_target`, at most `max_order`.
pub fn choose_order(alpha: f64, error_target: f64, max_order: u32) -> OrderChoice {
    choose_order_windowed(alpha, error_target, max_order, Window::None)
}

/// [`choose_order`] for a windowed fit: the window widens the lobe, so it needs a
/// higher order to meet the same target.
pub fn choose_order_windowed(
    alpha: f64,
    error_target: f64,
    max_order: u32,
    window: Window,
) -> OrderChoice {
    let fit = LegendreFit::new(alpha, max_order);
    choose_from_fit(&fit, error_target, max_order, window)
}

fn choose_from_fit(
    fit: &LegendreFit,
    error_target: f64,
    max_order: u32,
    window: Window,
) -> OrderChoice {
    for order in 0..=max_order {
        let error = fit.error(order, window);
        if error <= error_target {
            return OrderChoice {
                order,
                error,
                capped: false,
            };
        }
    }
    OrderChoice {
        order: max_order,
        error: fit.error(max_order, window),
        capped: true,
    }
}

/// Everything the solver needs to reflect light off one glossy material: the
/// chosen order, the (windowed) coefficients, the normalization table, and the
/// SH of a lobe about any mirror direction.
#[derive(Clone, Debug)]
pub struct GlossyLobe {
    pub alpha: f64,
    pub ks: f64,
    pub window: Window,
    pub choice: OrderChoice,
    /// Windowed Legendre coefficients `w_l a_l`, l = 0..=order.
    pub coefficients: Vec<f64>,
    /// `w_l a_l · 4π/(2l+1)`: multiply by `Y_lm(r)` for the lobe's SH (addition theorem).
    pub sh_scale: Vec<f64>,
    /// `C_R(μ_i)` of the thesis's normalization, tabulated.
    pub table: NormalizationTable,
}

/// Relative interpolation error the [`GlossyLobe`]'s normalization table is built to.
pub const NORMALIZATION_TABLE_TOLERANCE: f64 = 1e-6;

impl GlossyLobe {
    /// Builds the lobe for a material: validates α, chooses the order for
    /// `error_target` (capped at `max_order`; check `choice.capped`), applies the
    /// window and tabulates `C_R` to [`NORMALIZATION_TABLE_TOLERANCE`].
    pub fn new(
        alpha: f64,
        ks: f64,
        error_target: f64,
        max_order: u32,
        window: Window,
    ) -> Result<Self, BrdfError> {
        let alpha = validate_alpha(alpha)?;
        let fit = LegendreFit::new(alpha, max_order);
        let choice = choose_from_fit(&fit, error_target, max_order, window);
        let coefficients: Vec<f64> = fit.coefficients[..=choice.order as usize]
            .iter()
            .enumerate()
            .map(|(l, a)| a * window.factor(l as u32, choice.order))
            .collect();
        let sh_scale = coefficients
            .iter()
            .enumerate()
            .map(|(l, a)| a * 4.0 * PI / (2.0 * l as f64 + 1.0))
            .collect();
        let table =
            NormalizationTable::with_tolerance(ks, &coefficients, NORMALIZATION_TABLE_TOLERANCE);
        Ok(GlossyLobe {
            alpha,
            ks,
            window,
            choice,
            coefficients,
            sh_scale,
            table,
        })
    }

    /// [`GlossyLobe::new`] with the window chosen by [`default_window`]: none when
    /// the target is met, the Hann window when the order is capped.
    pub fn with_default_window(
        alpha: f64,
        ks: f64,
        error_target: f64,
        max_order: u32,
    ) -> Result<Self, BrdfError> {
        let plain = choose_order(validate_alpha(alpha)?, error_target, max_order);
        Self::new(alpha, ks, error_target, max_order, default_window(&plain))
    }

    /// The normalizer for incidence μ_i (clamped to [0, 1]): the thesis's
    /// `C_R(μ_i)` from the table.
    pub fn c_r(&self, mu_i: f64) -> f64 {
        self.table.c_r(mu_i)
    }

    /// The directional albedo `∫_H f_s(ω_i, ω_o) cosθ_o dω_o` for incidence μ_i,
    /// by Funk–Hecke from the expansion: `c_r(μ_i) · S(μ_i)`. Ks (to the table's
    /// 1e-6) for the thesis's normalization. (Ringing clamped at evaluation is
    /// not counted.)
    pub fn albedo(&self, mu_i: f64) -> f64 {
        self.c_r(mu_i)
            * normalization::hemisphere_integral(&self.coefficients, mu_i.clamp(0.0, 1.0))
    }

    pub fn order(&self) -> u32 {
        self.choice.order
    }

    /// The BRDF `f_s(ω_i, ω_o) = C_R(μ_i) · Σ_l w_l a_l P_l(ω_o·r)` in the local frame
    /// (z = normal), with r the mirror of ω_i (both unit, pointing away from the
    /// surface). Evaluated from the expansion, so it includes the truncation, and
    /// clamped at 0 where the truncated series rings negative.
    pub fn brdf(&self, omega_i: DVec3, omega_o: DVec3) -> f64 {
        let r = mirror(omega_i);
        let mu0 = omega_o.dot(r).clamp(-1.0, 1.0);
        let mut p = vec![0.0; self.coefficients.len()];
        sh::legendre_all(self.order(), mu0, &mut p);
        let series: f64 = self.coefficients.iter().zip(&p).map(|(a, p)| a * p).sum();
        (self.c_r(omega_i.z) * series).max(0.0)
    }

    /// Adds the SH of the reflected lobe for irradiance `irradiance` (ΔE, per
    /// channel handled by the caller) arriving from local direction `omega_i`
    /// (unit, toward the source): `out[lm] += ΔE · C_R(μ_i) · w_l a_l · 4π/(2l+1) ·
    /// Y_lm(r)` (design notes, "Directional mode"). `scratch` holds
    /// `coefficient_count(order)` values. Light from below the surface adds nothing.
    pub fn add_lobe_sh(
        &self,
        omega_i: DVec3,
        irradiance: f64,
        out: &mut [f64],
        scratch: &mut [f64],
    ) {
        self.add_lobe_sh_about(omega_i.z, mirror(omega_i), irradiance, out, scratch);
    }

    /// [`GlossyLobe::add_lobe_sh`] in any frame: `mu_i` is the cosine of
    /// incidence to the reflecting (shading) normal and `mirror_dir` the mirror
    /// direction about that normal, given in the frame the coefficients are
    /// in. The lobe is zonal about the mirror direction, so its truncation to
    /// order L is one function whatever frame expresses it (each band of the
    /// SH is closed under rotation): a vertex whose shading normal is not its
    /// SH frame's axis gets exactly the coefficients of its lobe in that frame.
    pub fn add_lobe_sh_about(
        &self,
        mu_i: f64,
        mirror_dir: DVec3,
        irradiance: f64,
        out: &mut [f64],
        scratch: &mut [f64],
    ) {
        if mu_i <= 0.0 {
            return;
        }
        let order = self.order();
        sh::eval_basis(order, mirror_dir, scratch);
        let scale = irradiance * self.c_r(mu_i);
        for l in 0..=order as usize {
            let s = scale * self.sh_scale[l];
            // Degree l occupies indices l² .. (l+1)², contiguous.
            let band = l * l..(l + 1) * (l + 1);
            for (o, y) in out[band.clone()].iter_mut().zip(&scratch[band]) {
                *o += s * y;
            }
        }
    }
}

/// The window for a lobe whose plain (unwindowed) order choice is `choice`.
///
/// Measured (docs/sh-bands.md, `cargo bench --bench sh_bands`): when the target is
/// met, plain truncation rings by at most 6.6e-4 of the peak with ≤ 0.3% negative
/// mass at the default target 1e-3, while every window at the same order multiplies
/// the L2 error by 100–400 (it widens the lobe), and windowed fits cannot reach
/// 1e-3 even at L = 100. So: no window. When the order is capped the truncated lobe
/// rings across the whole sphere (α = 0.02 at L = 64: negative mass 98% of the
/// lobe's, α = 0.01: 369%), which clamping would turn into spurious light; the Hann
/// window cuts that to 0.8% / 4.6% at the cost of a wider lobe (L2 0.55 / 0.84),
/// lower ringing than σ-factors (2.5% / 14%) and a narrower lobe than sinc⁴.
pub fn default_window(choice: &OrderChoice) -> Window {
    if choice.capped {
        Window::Hanning
    } else {
        Window::None
    }
}

/// Mirror of a local direction about the normal (z): `r = 2(n·ω)n − ω`.
pub fn mirror(omega: DVec3) -> DVec3 {
    DVec3::new(-omega.x, -omega.y, omega.z)
}

#[cfg(test)]
mod tests;
