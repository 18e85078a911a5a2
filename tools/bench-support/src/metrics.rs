//! The relative L2 error that the benches print beside their timings.

/// `sqrt(Σ (t − r)² / Σ r²)` over the pairs `(test, reference)`, in order: the
/// L2 norm of the difference relative to the reference's own L2 norm. Summed in
/// f64 in the pairs' order, so that the same inputs give the same bits. A zero
/// reference gives NaN or infinity (there is no scale to be relative to).
pub fn relative_l2(pairs: impl IntoIterator<Item = (f64, f64)>) -> f64 {
    let (mut diff, mut norm) = (0.0f64, 0.0f64);
    for (t, r) in pairs {
        diff += (t - r) * (t - r);
        norm += r * r;
    }
    (diff / norm).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scaled_signal_is_off_by_the_scale() {
        // t = k·r: Σ(t − r)² = (k − 1)² Σr², so the error is |k − 1|.
        // 1e-12 is f64 rounding over four terms.
        let r = [0.5, 2.0, 3.0, 0.25];
        let e = relative_l2(r.iter().map(|&x| (1.25 * x, x)));
        assert!((e - 0.25).abs() < 1e-12, "{e}");
        assert_eq!(relative_l2(r.iter().map(|&x| (x, x))), 0.0);
    }

    #[test]
    fn one_bad_value_weighs_by_its_square() {
        // r = (3, 4) has norm 5; an error of 5 in one value is 100%, and of 3
        // and 4 in both is sqrt(25)/5 = 100% too.
        assert!((relative_l2([(8.0, 3.0), (4.0, 4.0)]) - 1.0).abs() < 1e-12);
        assert!((relative_l2([(6.0, 3.0), (8.0, 4.0)]) - 1.0).abs() < 1e-12);
        assert!(relative_l2([(1.0, 0.0)]).is_infinite());
    }
}
