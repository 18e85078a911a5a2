//! Tests of the lobe expansion and the normalization
//! against independent mathematics (see each test's comment for its tolerance).

use super::normalization::exact_hemisphere_integral_with;
use super::*;

#[test]
fn lobe_shape() {
    // g(1) = 1 (mirror direction), g(−1) = 0 (limit), and the half-angle form agrees
    // with the μ0 form up to the μ0 form's cancellation in 1 − cos θ0: its relative
    // error ε/(1 − cos θ0) multiplies the exponent tan²(θ0/2)/α², so the bound is
    // g · (ε/(1 − cos θ0) + ε) · exponent + 1e-15, ε = 2.2e-16.
    for alpha in [1.0, 0.3, 0.01] {
        assert_eq!(lobe(alpha, 1.0), 1.0);
        assert_eq!(lobe(alpha, -1.0), 0.0);
        for theta in [0.01, 0.3, 1.0, 2.0, 3.0] {
            let g = lobe_of_angle(alpha, theta);
            let exponent = (0.5 * theta).tan().powi(2) / (alpha * alpha);
            let tol = g * 2.2e-16 * (1.0 / (1.0 - f64::cos(theta)) + 1.0) * exponent + 1e-15;
            let d = (lobe(alpha, f64::cos(theta)) - g).abs();
            assert!(d <= tol, "alpha {alpha} theta {theta}: {d:e} > {tol:e}");
        }
    }
    // Remington 1992, eq. 4.1: g = exp(−tan²(θ0/2)/α²); at tan(θ0/2) = α it is 1/e.
    let alpha: f64 = 0.2;
    let theta = 2.0 * alpha.atan();
    assert!((lobe_of_angle(alpha, theta) - (-1.0f64).exp()).abs() < 1e-15);
    assert!(
        (alpha_from_ns(0.0) - 1.0).abs() < 1e-15
            && (alpha_from_ns(98.0) - 0.02f64.sqrt()).abs() < 1e-15
    );
    assert!(
        validate_alpha(0.0).is_err()
            && validate_alpha(f64::NAN).is_err()
            && validate_alpha(0.5).is_ok()
    );
}

#[test]
fn lobe_quadrature_converged() {
    // Doubling the panels of the lobe quadrature changes no a_l by more than
    // 1e-14 · a_0 · (2l+1): the rule has converged to rounding, which is the accuracy
    // `legendre_coefficients` states.
    for alpha in [1.0, 0.3, 0.05, 0.01] {
        let order = 200;
        let (mu1, w1) = lobe_quadrature(alpha, order);
        let (mu2, w2) = lobe_quadrature_with(alpha, order, 2);
        let p1 = projections(&mu1, &w1, order);
        let p2 = projections(&mu2, &w2, order);
        for l in 0..=order as usize {
            let scale = (2.0 * l as f64 + 1.0) / 2.0;
            let d = scale * (p1[l] - p2[l]).abs();
            assert!(
                d <= 1e-14 * p1[0] * (2 * l + 1) as f64,
                "alpha {alpha} l {l}: {d:e}"
            );
        }
    }
}

#[test]
// The references are mpmath's 17 printed digits, kept as printed.
#[allow(clippy::excessive_precision)]
fn coefficients_match_an_independent_30_digit_computation() {
    // Reference values from mpmath at 30 digits (96-point Gauss–Legendre on 40/80
    // panels in θ0; the script is in docs/sh-bands.md), printed to 17 digits.
    // Tolerance: 1e-14 · a_0 · (2l+1) absolute, the accuracy `legendre_coefficients`
    // states.
    let cases: [(f64, &[(usize, f64)]); 2] = [
        (
            0.1,
            &[
                (0, 0.0098057713266981594),
                (10, 0.070231996238803488),
                (20, 0.0060776953828916775),
                (30, 3.8241209710479888e-5),
                (40, 7.547643867295284e-9),
                (48, -2.7396525341543068e-13),
            ],
        ),
        (
            0.05,
            &[
                (0, 0.0024875928240459847),
                (10, 0.039755757015412596),
                (20, 0.035905314828588612),
                (30, 0.014963414529379065),
                (40, 0.0033484001315581565),
                (48, 0.0006650771316475003),
                (80, 2.6196898170417421e-8),
                (100, 1.9813106535483257e-12),
            ],
        ),
    ];
    for (alpha, refs) in cases {
        let a = legendre_coefficients(alpha, 100);
        for &(l, expect) in refs {
            let tol = 1e-14 * a[0] * (2 * l + 1) as f64;
            let err = (a[l] - expect).abs();
            assert!(
                err <= tol,
                "alpha {alpha} a_{l} = {:e}, reference {expect:e}, error {err:e}",
                a[l]
            );
        }
    }
}

#[test]
fn parseval_norm_matches_direct_quadrature() {
    // ‖g‖² as Σ a_l² 2/(2l+1) must equal ∫ g² dμ computed directly (same nodes,
    // different sum): 1e-12 relative covers the rounding of ~1000 terms.
    for alpha in [1.0, 0.3, 0.1, 0.02] {
        let fit = LegendreFit::new(alpha, 0);
        let (mu, wg) = lobe_quadrature(alpha, 0);
        let direct: f64 = mu.iter().zip(&wg).map(|(m, w)| w * lobe(alpha, *m)).sum();
        assert!(
            (fit.norm_squared - direct).abs() < 1e-12 * direct,
            "alpha {alpha}: {} vs {direct}",
            fit.norm_squared
        );
    }
}

#[test]
fn fit_error_reproduces_the_design_notes_table() {
    // The design notes' table ("Directional mode"), within a factor 2 as the brief
    // asks. Two entries of that table are below what the lobe actually gives: at
    // α = 0.1, L = 48 the error is 7.46e-14 (not 1e-10) and at α = 0.05, L = 100 it
    // is 2.79e-12 (not 4e-10); both confirmed by an independent 30-digit mpmath
    // computation (docs/sh-bands.md), so they are asserted at those values instead.
    let table: [(f64, &[(u32, f64)]); 5] = [
        (0.3, &[(8, 1e-3), (16, 2e-7), (25, 1e-10)]),
        (0.15, &[(8, 0.17), (16, 1e-3), (25, 4e-9)]),
        (0.1, &[(8, 0.45), (16, 0.056), (25, 1e-3), (48, 7.46e-14)]),
        (
            0.05,
            &[
                (8, 0.82),
                (16, 0.49),
                (25, 0.19),
                (48, 2e-3),
                (100, 2.79e-12),
            ],
        ),
        (
            0.02,
            &[(8, 0.97), (16, 0.89), (25, 0.76), (48, 0.38), (100, 0.017)],
        ),
    ];
    for (alpha, entries) in table {
        let fit = LegendreFit::new(alpha, 100);
        for &(order, expect) in entries {
            let e = fit.error(order, Window::None);
            assert!(
                e <= 2.0 * expect && e >= 0.5 * expect,
                "alpha {alpha} L {order}: {e:e} vs table {expect:e}"
            );
            if expect > 1e-9 {
                assert!(
                    (fit_error(alpha, order) - e).abs() <= 1e-12,
                    "fit_error agrees with LegendreFit"
                );
            }
        }
    }
}

#[test]
fn coefficients_converge_and_the_order_is_capped_for_narrow_lobes() {
    // From α = 1 down to 0.01: the coefficients decay to rounding level (beyond
    // l = max(10/α, 120α), the tail length `LegendreFit` uses, they are below 1e-12
    // of the largest), the chosen order grows as α shrinks, and when the cap is hit
    // the error is stated (and is the fit's).
    let target = 1e-3;
    let max_order = 64;
    let mut last_order = 0;
    for alpha in [1.0, 0.5, 0.3, 0.15, 0.1, 0.05, 0.03, 0.02, 0.01] {
        let fit = LegendreFit::new(alpha, max_order);
        let biggest = fit.coefficients.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        let far = (10.0 / alpha).max(120.0 * alpha) as usize;
        let tail = fit.coefficients[far..]
            .iter()
            .fold(0.0f64, |m, a| m.max(a.abs()));
        assert!(
            tail < 1e-12 * biggest,
            "alpha {alpha}: |a_l| = {tail:e} beyond l = {far}"
        );
        assert!(fit.coefficients.iter().all(|a| a.is_finite()));
        let choice = choose_order(alpha, target, max_order);
        // Below α = 0.5 a narrower lobe needs more bands. Above it the order rises
        // again (α = 1 needs 9 for 1e-3, α = 0.5 fewer): the broad lobe's essential
        // singularity at μ0 = −1 slows the decay of its coefficients.
        if alpha <= 0.5 {
            assert!(choice.order >= last_order, "order grows as alpha shrinks");
            last_order = choice.order;
        }
        if choice.capped {
            assert_eq!(choice.order, max_order);
            assert!(choice.error > target);
            assert!((choice.error - fit_error(alpha, max_order)).abs() < 1e-12);
        } else {
            assert!(choice.error <= target);
            if choice.order > 0 {
                assert!(
                    fit.error(choice.order - 1, Window::None) > target,
                    "smallest order"
                );
            }
        }
        println!(
            "alpha {alpha}: order {} error {:.2e} capped {}",
            choice.order, choice.error, choice.capped
        );
    }
    // α = 0.3 needs L = 8 for 1e-3 (table: 1e-3 at L = 8); α = 0.02 is capped at 64.
    assert_eq!(choose_order(0.3, 1.1e-3, 64).order, 8);
    let capped = choose_order(0.02, target, 64);
    assert!(capped.capped && capped.error > 0.1 && capped.error < 0.38);
    // Windows widen the lobe: they need at least as high an order.
    for w in [Window::Sigma, Window::Hanning] {
        assert!(
            choose_order_windowed(0.1, target, 100, w).order
                >= choose_order(0.1, target, 100).order
        );
    }
}

#[test]
fn funk_hecke_d_matches_quadrature() {
    // D_l = ∫₀¹ P_l(t) t dt; Gauss–Legendre with 60 nodes on [0, 1] is exact for
    // degree ≤ 119 ≥ l + 1, so only rounding separates the two: 1e-15 absolute
    // (|D_l| ≤ 1/2, and each side sums ≤ 60 terms of size ≤ 1/60).
    let (t, w) = sh::gauss_legendre_on(60, 0.0, 1.0);
    let all = funk_hecke_d_all(100);
    let mut p = vec![0.0; 101];
    let mut q = vec![0.0; 101];
    for (ti, wi) in t.iter().zip(&w) {
        sh::legendre_all(100, *ti, &mut p);
        for l in 0..=100 {
            q[l] += wi * ti * p[l];
        }
    }
    for l in 0..=100u32 {
        assert!(
            (funk_hecke_d(l) - q[l as usize]).abs() < 1e-15,
            "D_{l} = {} vs {}",
            funk_hecke_d(l),
            q[l as usize]
        );
        assert!((all[l as usize] - funk_hecke_d(l)).abs() <= 1e-17);
    }
    assert_eq!(funk_hecke_d(2), 0.125);
    assert!((funk_hecke_d(4) + 1.0 / 48.0).abs() < 1e-17);
    // Stable far out: |D_l| ~ C · l^{-5/2} (the ratio −(l−1)/(l+4) = −(1 − 5/l + …)),
    // so D_l · l^{5/2} must settle to a constant: finite and non-zero at l = 10⁴, 2·10⁴
    // and agreeing to the O(1/l) = 1e-4 of the next asymptotic term (×10 margin).
    let c1 = funk_hecke_d(10_000).abs() * 1e4f64.powf(2.5);
    let c2 = funk_hecke_d(20_000).abs() * 2e4f64.powf(2.5);
    assert!(
        c1.is_finite() && c1 > 0.0 && (c1 - c2).abs() < 1e-3 * c1,
        "{c1} vs {c2}"
    );
}

#[test]
fn exact_hemisphere_quadrature_converged() {
    // Doubling the panels in θ and φ changes the exact lobe's integral by < 1e-10
    // relative: the reference for C_R is far tighter than the 1e-6 asked of C_R.
    for alpha in [0.3, 0.1, 0.03] {
        for mu in [1.0, 0.5, 0.1, 0.01, 0.0] {
            let a = exact_hemisphere_integral(alpha, mu);
            let b = exact_hemisphere_integral_with(alpha, mu, 2);
            assert!(
                a > 0.0 && (a - b).abs() < 1e-10 * a,
                "alpha {alpha} mu {mu}: {a} vs {b}"
            );
        }
    }
    // Normal incidence, broad lobe check against 1-D: ∫ g(cos θ) cos θ 2π sin θ dθ.
    let alpha = 0.3;
    let (th, w) = sh::gauss_legendre_on(400, 0.0, 0.5 * std::f64::consts::PI);
    let one_d: f64 = th
        .iter()
        .zip(&w)
        .map(|(t, w)| w * lobe_of_angle(alpha, *t) * t.cos() * t.sin() * 2.0 * PI)
        .sum();
    let two_d = exact_hemisphere_integral(alpha, 1.0);
    assert!((one_d - two_d).abs() < 1e-12 * one_d, "{one_d} vs {two_d}");
}

#[test]
fn normalization_matches_quadrature_of_the_exact_lobe() {
    // C_R from the Funk–Hecke closed form (with a fit of relative L2 error ≤ 1e-12)
    // against 1 / (2-D quadrature of the exact lobe). The expansion's error enters
    // the integral at most at ~1e-12 × ‖g‖/∫g·cos ≲ 1e-9, the quadrature at 1e-10,
    // so 1e-6 relative (the brief's figure) holds with a wide margin.
    for alpha in [0.3, 0.1, 0.03] {
        let choice = choose_order(alpha, 1e-12, 600);
        assert!(!choice.capped);
        let a = legendre_coefficients(alpha, choice.order);
        for mu in [1.0, 0.5, 0.1, 0.01] {
            let funk_hecke = normalization(1.0, &a, mu);
            let exact = 1.0 / exact_hemisphere_integral(alpha, mu);
            let rel = (funk_hecke - exact).abs() / exact;
            assert!(
                rel < 1e-6,
                "alpha {alpha} mu {mu}: C_R {funk_hecke} vs exact {exact} ({rel:e})"
            );
        }
    }
}

#[test]
fn grazing_incidence_gives_finite_normalization() {
    // μ_i → 0: the mirror direction lies in the surface, half the lobe is below it
    // and the other half sees cos θ ≈ elevation, so for a narrow (Gaussian, variance
    // 2α²) lobe ∫ g cos θ dω falls from 4πα² at normal incidence to 4√π α³ at grazing:
    // C_R(0)/C_R(1) → √π/α (59 at α = 0.03). It must stay finite and positive, within
    // twice that ratio (or 4 for broad lobes), for the orders the default target
    // chooses and for capped ones.
    for alpha in [1.0, 0.3, 0.1, 0.03, 0.01] {
        let choice = choose_order(alpha, 1e-3, 64);
        let a = legendre_coefficients(alpha, choice.order);
        let c1 = normalization(0.5, &a, 1.0);
        for mu in [0.0, 1e-12, 1e-6, 1e-3, 0.05] {
            let c = normalization(0.5, &a, mu);
            assert!(
                c.is_finite() && c > 0.0,
                "alpha {alpha} L {} mu {mu}: C_R = {c}",
                choice.order
            );
            let ratio = 2.0 * (PI.sqrt() / alpha).max(2.0);
            assert!(
                c < ratio * c1,
                "alpha {alpha} mu {mu}: C_R {c} vs {c1} at normal incidence"
            );
        }
        // Against the exact lobe at grazing, within what the fit error allows
        // (a few times the relative L2 error of the fit).
        let exact = 0.5 / exact_hemisphere_integral(alpha, 0.0);
        let c0 = normalization(0.5, &a, 0.0);
        if !choice.capped {
            assert!(
                (c0 - exact).abs() / exact < 10.0 * choice.error.max(1e-9),
                "alpha {alpha}: {c0} vs {exact}"
            );
        }
    }
    // A degenerate expansion whose integral is not positive reflects nothing.
    assert_eq!(normalization(1.0, &[0.0, -1.0], 0.5), 0.0);
    assert_eq!(normalization(1.0, &[], 0.5), 0.0);
}

#[test]
fn normalization_table_meets_its_stated_error() {
    // The table measures its own error at three points per interval; random points
    // may fall nearer the true maximum of the cubic's error, which for a smooth
    // function lies within the measured maximum × 1.5 (the error curve of a cubic on
    // one interval is a smooth bump sampled at its quarter and mid points).
    let mut seed = 1u64;
    let mut next = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    for alpha in [1.0, 0.3, 0.1, 0.05] {
        let choice = choose_order(alpha, 1e-4, 100);
        let a = legendre_coefficients(alpha, choice.order);
        let table = NormalizationTable::with_tolerance(0.7, &a, 1e-6);
        assert!(
            table.interpolation_error() <= 1e-6,
            "alpha {alpha}: {}",
            table.interpolation_error()
        );
        for _ in 0..2000 {
            let mu = next();
            let exact = normalization(0.7, &a, mu);
            let rel = (table.c_r(mu) - exact).abs() / exact;
            assert!(rel <= 1.5e-6, "alpha {alpha} mu {mu}: {rel:e}");
        }
        // The grid points themselves are exact; the ends clamp.
        assert!((table.c_r(0.0) - normalization(0.7, &a, 0.0)).abs() < 1e-12 * table.c_r(0.0));
        assert_eq!(table.c_r(-1.0), table.c_r(0.0));
        assert_eq!(table.c_r(f64::NAN), table.c_r(0.0));
        println!(
            "alpha {alpha} L {}: {} samples, error {:.1e}",
            choice.order,
            table.samples(),
            table.interpolation_error()
        );
    }
}

/// Cosine-weighted hemispherical integral of a radiance stored as SH, by a rule
/// that is exact for it: uniform φ with more than 2L points kills every m ≠ 0 term,
/// and the m = 0 terms times cos θ are polynomials of degree ≤ L + 1 in z = cos θ,
/// which Gauss–Legendre with L/2 + 2 nodes on [0, 1] integrates exactly.
fn hemisphere_flux_of_sh(order: u32, c: &[f64]) -> f64 {
    let (zs, wz) = sh::gauss_legendre_on(order as usize / 2 + 2, 0.0, 1.0);
    let n_phi = 2 * order as usize + 2;
    let mut y = vec![0.0; sh::coefficient_count(order)];
    let mut sum = 0.0;
    for (z, w) in zs.iter().zip(&wz) {
        let s = (1.0 - z * z).sqrt();
        for j in 0..n_phi {
            let phi = 2.0 * PI * j as f64 / n_phi as f64;
            sh::eval_basis(order, DVec3::new(s * phi.cos(), s * phi.sin(), *z), &mut y);
            let radiance: f64 = c.iter().zip(&y).map(|(a, b)| a * b).sum();
            sum += w * 2.0 * PI / n_phi as f64 * radiance * z;
        }
    }
    sum
}

#[test]
fn reflected_sh_carries_exactly_ks_of_the_irradiance() {
    // Energy: the SH that `add_lobe_sh` stores for unit irradiance, evaluated and
    // integrated over the hemisphere with cos θ (independently of the Funk–Hecke
    // formula), must return Ks for every incidence and window. Tolerance 2e-6: the
    // normalization table's stated 1e-6 (×1.5, see above) plus rounding.
    for window in Window::ALL {
        // Order ≤ 24: the plain lobe meets the target at 16, windowed ones are capped
        // at 24, which is enough to test their energy.
        let lobe = GlossyLobe::new(0.15, 0.6, 1e-3, 24, window).unwrap();
        let order = lobe.order();
        let mut c = vec![0.0; sh::coefficient_count(order)];
        let mut scratch = vec![0.0; sh::coefficient_count(order)];
        for mu_i in [1.0, 0.7, 0.3, 0.05, 0.001] {
            c.iter_mut().for_each(|v| *v = 0.0);
            let s = (1.0f64 - mu_i * mu_i).sqrt();
            let omega_i = DVec3::new(s * 0.3f64.cos(), s * 0.3f64.sin(), mu_i);
            lobe.add_lobe_sh(omega_i, 1.0, &mut c, &mut scratch);
            let flux = hemisphere_flux_of_sh(order, &c);
            assert!(
                (flux - 0.6).abs() < 2e-6 * 0.6,
                "{window:?} mu_i {mu_i}: reflected {flux}"
            );
        }
        // Light from below the surface reflects nothing.
        c.iter_mut().for_each(|v| *v = 0.0);
        lobe.add_lobe_sh(DVec3::new(0.0, 0.6, -0.8), 1.0, &mut c, &mut scratch);
        assert!(c.iter().all(|v| *v == 0.0));
    }
}

#[test]
fn lobe_sh_is_the_rotated_zonal_expansion_and_brdf_peaks_at_the_mirror() {
    let lobe = GlossyLobe::new(0.2, 1.0, 1e-4, 64, Window::None).unwrap();
    let order = lobe.order();
    let omega_i = DVec3::new(0.3, -0.4, 0.866_025_403_784_438_6).normalize();
    let mut c = vec![0.0; sh::coefficient_count(order)];
    let mut scratch = c.clone();
    lobe.add_lobe_sh(omega_i, 2.0, &mut c, &mut scratch);
    let mut z = vec![0.0; sh::coefficient_count(order)];
    sh::zonal_rotated(
        order,
        &sh::zonal_from_legendre(&lobe.coefficients),
        mirror(omega_i),
        &mut z,
    );
    let scale = 2.0 * lobe.table.c_r(omega_i.z);
    for (a, b) in c.iter().zip(&z) {
        assert!((a - scale * b).abs() < 1e-12 * scale);
    }
    // Evaluated toward the mirror direction the radiance is ΔE·f_s(ω_i, r).
    let mut y = vec![0.0; sh::coefficient_count(order)];
    sh::eval_basis(order, mirror(omega_i), &mut y);
    let at_mirror: f64 = c.iter().zip(&y).map(|(a, b)| a * b).sum();
    let f = lobe.brdf(omega_i, mirror(omega_i));
    assert!((at_mirror - 2.0 * f).abs() < 1e-10 * at_mirror);
    assert!(f > lobe.brdf(omega_i, DVec3::Z));
}

#[test]
fn windows_trade_ringing_for_width() {
    for w in Window::ALL {
        assert_eq!(w.factor(0, 10), 1.0);
        assert_eq!(w.factor(11, 10), 0.0);
        let f: Vec<f64> = (0..=10).map(|l| w.factor(l, 10)).collect();
        assert!(
            f.windows(2).all(|p| p[1] <= p[0] && p[1] >= 0.0),
            "{w:?} decreasing in [0, 1]"
        );
    }
    // An under-resolved lobe (α = 0.05 at L = 25, 19% L2 error) rings negative
    // without a window; σ-factors and the Hann window cut the negative lobe mass,
    // and every window costs L2 error against the exact lobe.
    let plain = ringing(0.05, 25, Window::None);
    assert!(plain.min_value < -1e-3, "{plain:?}");
    assert!((plain.l2_error - fit_error(0.05, 25)).abs() < 1e-12);
    for w in [Window::Sigma, Window::Sinc4, Window::Hanning] {
        let r = ringing(0.05, 25, w);
        assert!(r.negative_mass < plain.negative_mass, "{w:?}: {r:?}");
        assert!(r.min_value > plain.min_value, "{w:?}");
        assert!(r.l2_error > plain.l2_error, "{w:?}");
    }
    // Clamping and the diffuse offset remove the negative part by construction.
    assert!(plain.clamped_l2_error <= plain.l2_error + 1e-12);
    assert!(plain.offset_energy_fraction > 0.0 && plain.offset_energy_fraction < 1.0);
    // A well-resolved lobe barely rings: α = 0.3 at L = 16 (2e-7) has |min| < 1e-6.
    let fine = ringing(0.3, 16, Window::None);
    assert!(fine.min_value > -1e-6 && fine.peak_error < 1e-5, "{fine:?}");
}

#[test]
fn default_window_is_plain_unless_capped() {
    // Met targets ring by < 1e-3 of the peak (docs/sh-bands.md), so no window; a
    // capped lobe gets the Hann window, which cuts its negative mass at least 10×
    // (α = 0.02 at L = 64: 0.98 → 0.008 of the lobe's mass).
    let met = GlossyLobe::with_default_window(0.15, 0.5, 1e-3, 64).unwrap();
    assert_eq!((met.window, met.choice.capped), (Window::None, false));
    let capped = GlossyLobe::with_default_window(0.02, 0.5, 1e-3, 64).unwrap();
    assert_eq!(
        (capped.window, capped.choice.capped, capped.order()),
        (Window::Hanning, true, 64)
    );
    let plain = ringing(0.02, 64, Window::None);
    let hann = ringing(0.02, 64, Window::Hanning);
    assert!(
        hann.negative_mass < 0.1 * plain.negative_mass,
        "{hann:?} vs {plain:?}"
    );
    // The stated error of the capped lobe is the windowed fit's.
    assert!((capped.choice.error - hann.l2_error).abs() < 1e-12);
}

#[test]
fn glossy_lobe_rejects_bad_alpha_and_reports_capping() {
    assert!(matches!(
        GlossyLobe::new(0.0, 0.5, 1e-3, 64, Window::None),
        Err(BrdfError::InvalidAlpha(_))
    ));
    assert!(matches!(
        GlossyLobe::new(f64::INFINITY, 0.5, 1e-3, 64, Window::None),
        Err(BrdfError::InvalidAlpha(_))
    ));
    let lobe = GlossyLobe::new(0.01, 0.5, 1e-3, 32, Window::None).unwrap();
    assert!(lobe.choice.capped && lobe.order() == 32 && lobe.choice.error > 0.5);
    // Even a badly capped lobe normalizes to finite values at every incidence.
    for mu in [0.0, 0.01, 0.5, 1.0] {
        let c = lobe.table.c_r(mu);
        assert!(c.is_finite() && c >= 0.0);
    }
}
