//! Legendre polynomials and Gauss–Legendre quadrature, the one-dimensional tools of
//! the SH module and of the glossy lobe's expansion (`brdf`).
//!
//! Everything here uses the three-term recurrence of the unnormalised Legendre
//! polynomials, `l P_l = (2l−1) x P_{l−1} − (l−1) P_{l−2}`, which is stable in the
//! forward direction for |x| ≤ 1 (|P_l| ≤ 1 there), so no factorials appear.

/// Writes `P_0(x) … P_order(x)` into `out[0..=order]`.
///
/// # Panics
/// If `out` holds fewer than `order + 1` values (a programming error).
pub fn legendre_all(order: u32, x: f64, out: &mut [f64]) {
    let n = order as usize + 1;
    assert!(
        out.len() >= n,
        "legendre_all: need {n} slots, got {}",
        out.len()
    );
    out[0] = 1.0;
    if order == 0 {
        return;
    }
    out[1] = x;
    for l in 2..n {
        let lf = l as f64;
        out[l] = ((2.0 * lf - 1.0) * x * out[l - 1] - (lf - 1.0) * out[l - 2]) / lf;
    }
}

/// `P_l(x)` and its derivative `P_l'(x)` for one `l` (used by Newton's method below).
pub fn legendre_with_derivative(l: u32, x: f64) -> (f64, f64) {
    if l == 0 {
        return (1.0, 0.0);
    }
    let (mut p_prev, mut p) = (1.0, x);
    for k in 2..=l {
        let kf = k as f64;
        let next = ((2.0 * kf - 1.0) * x * p - (kf - 1.0) * p_prev) / kf;
        p_prev = p;
        p = next;
    }
    // (1 − x²) P_l' = l (P_{l−1} − x P_l); at x = ±1 use P_l'(±1) = (±1)^{l+1} l(l+1)/2.
    let lf = l as f64;
    let one_minus_x2 = 1.0 - x * x;
    let dp = if one_minus_x2 > 1e-300 {
        lf * (p_prev - x * p) / one_minus_x2
    } else {
        let sign = if x < 0.0 && l.is_multiple_of(2) {
            -1.0
        } else {
            1.0
        };
        sign * lf * (lf + 1.0) / 2.0
    };
    (p, dp)
}

/// Gauss–Legendre nodes and weights on [−1, 1] with `n` points: exact for
/// polynomials of degree ≤ 2n − 1.
///
/// Nodes are the roots of `P_n`, found by Newton's method from Tricomi's initial
/// guess `cos(π(i − ¼)/(n + ½))`; weights are `2 / ((1 − x²) P_n'(x)²)`. Newton
/// converges quadratically from that guess, so a handful of steps gives the nodes to
/// a few ulps; the weights then sum to 2 within ~1e-14 for n up to several thousand
/// (checked in the tests). Nodes are returned in increasing order.
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    if n == 0 {
        return (nodes, weights);
    }
    let nf = n as f64;
    // Only the non-negative half is computed; the rule is symmetric.
    for i in 0..n.div_ceil(2) {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
        let mut dp = 1.0;
        // Quadratic convergence: once a step is below 1e-12 the next one is at the
        // rounding level, so one more step after that and stop.
        let mut converged = false;
        for _ in 0..100 {
            let (p, d) = legendre_with_derivative(n as u32, x);
            dp = d;
            let dx = p / d;
            x -= dx;
            if converged {
                break;
            }
            converged = dx.abs() < 1e-12;
        }
        // One more derivative at the converged node for the weight.
        let (_, d) = legendre_with_derivative(n as u32, x);
        if d.is_finite() {
            dp = d;
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        // i = 0 is the largest node; place it at the top of the increasing order.
        nodes[n - 1 - i] = x;
        weights[n - 1 - i] = w;
        nodes[i] = -x;
        weights[i] = w;
    }
    if n % 2 == 1 {
        nodes[n / 2] = 0.0;
    }
    (nodes, weights)
}

/// Gauss–Legendre nodes and weights mapped onto `[a, b]`.
pub fn gauss_legendre_on(n: usize, a: f64, b: f64) -> (Vec<f64>, Vec<f64>) {
    let (mut x, mut w) = gauss_legendre(n);
    let half = 0.5 * (b - a);
    let mid = 0.5 * (a + b);
    for (xi, wi) in x.iter_mut().zip(w.iter_mut()) {
        *xi = mid + half * *xi;
        *wi *= half;
    }
    (x, w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legendre_closed_forms() {
        // P_2 = (3x² − 1)/2, P_3 = (5x³ − 3x)/2; rounding of a few operations: 1e-15.
        let mut p = [0.0; 4];
        for &x in &[-1.0, -0.3, 0.0, 0.77, 1.0] {
            legendre_all(3, x, &mut p);
            assert!((p[2] - (3.0 * x * x - 1.0) / 2.0).abs() < 1e-15);
            assert!((p[3] - (5.0 * x * x * x - 3.0 * x) / 2.0).abs() < 1e-15);
        }
        // P_l(1) = 1 and P_l(−1) = (−1)^l exactly up to l = 1000 (the recurrence keeps
        // integers there up to rounding); 1e-12 allows ~1000 rounding steps.
        let mut big = vec![0.0; 1001];
        legendre_all(1000, 1.0, &mut big);
        assert!(big.iter().all(|v| (v - 1.0).abs() < 1e-12));
        legendre_all(1000, -1.0, &mut big);
        for (l, v) in big.iter().enumerate() {
            let expect = if l.is_multiple_of(2) { 1.0 } else { -1.0 };
            assert!((v - expect).abs() < 1e-12);
        }
    }

    #[test]
    fn derivative_matches_finite_difference() {
        for l in [1u32, 2, 7, 30] {
            for &x in &[-0.9, -0.2, 0.4, 0.95] {
                let h = 1e-6;
                let fd = (legendre_with_derivative(l, x + h).0
                    - legendre_with_derivative(l, x - h).0)
                    / (2.0 * h);
                let (_, d) = legendre_with_derivative(l, x);
                // Central difference error ~h² P''' plus rounding 1e-16/h: relative 1e-6.
                assert!((fd - d).abs() <= 1e-6 * d.abs().max(1.0), "l={l} x={x}");
            }
        }
    }

    #[test]
    fn gauss_legendre_is_exact_to_degree_2n_minus_1() {
        for n in [1usize, 2, 5, 16, 65, 200, 1000] {
            let (x, w) = gauss_legendre(n);
            // ∫ x^k dx over [−1, 1] = 2/(k+1) for even k, 0 for odd k.
            for k in [0usize, 1, 2.min(2 * n - 1), 2 * n - 2, 2 * n - 1] {
                let q: f64 = x
                    .iter()
                    .zip(&w)
                    .map(|(xi, wi)| wi * xi.powi(k as i32))
                    .sum();
                let exact = if k.is_multiple_of(2) {
                    2.0 / (k as f64 + 1.0)
                } else {
                    0.0
                };
                // Sum of n positive terms each with relative rounding ~1e-16: 1e-13.
                assert!((q - exact).abs() < 1e-13, "n={n} k={k}: {q} vs {exact}");
            }
            assert!(x.windows(2).all(|p| p[0] < p[1]), "nodes sorted, n={n}");
        }
    }
}
