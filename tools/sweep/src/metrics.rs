//! Error metrics and the Pareto front.
//!
//! Every error is relative to the reference's own magnitude, so that the figures
//! of the Cornell box (millimetres, Ke 17) and of the glossy room (metres, Ke 40)
//! can share one scale: 0.01 means "1% of the reference's mean radiance".

/// How far a test signal is from a reference signal of the same length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorStats {
    /// `Σ|t − r| / Σ|r|`: the mean absolute error over the mean absolute
    /// reference value. Robust to a few bad pixels; the sweep's headline figure.
    pub rel_l1: f64,
    /// `sqrt(mean (t − r)²) / mean |r|`: weighs large local errors (a missing
    /// shadow, a misplaced highlight) more than `rel_l1` does.
    pub rel_rmse: f64,
    /// How many values were compared.
    pub count: usize,
}

/// Why two signals could not be compared.
#[derive(Debug, Clone, PartialEq)]
pub enum MetricError {
    Length {
        reference: usize,
        test: usize,
    },
    Empty,
    /// The reference is all zero (or not finite): there is no scale to be relative to.
    NoScale,
}

impl std::fmt::Display for MetricError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MetricError::Length { reference, test } => write!(
                f,
                "the signals differ in length: reference {reference}, test {test}"
            ),
            MetricError::Empty => write!(f, "nothing to compare"),
            MetricError::NoScale => {
                write!(f, "the reference is black (or not finite): no scale")
            }
        }
    }
}

impl std::error::Error for MetricError {}

/// Compares `test` with `reference` value by value (pixels × channels, or
/// vertices × channels), in f64. A non-finite test value makes both errors
/// infinite rather than hiding it.
pub fn relative_error(reference: &[f64], test: &[f64]) -> Result<ErrorStats, MetricError> {
    relative_error_weighted(reference, test, None)
}

/// [`relative_error`] with a weight per value (e.g. the surface area a vertex
/// stands for): `Σ w|t − r| / Σ w|r|` and `sqrt(Σ w(t − r)² / Σ w) / (Σ w|r| / Σ w)`.
/// `None` weighs every value 1. Negative or non-finite weights count as 0.
pub fn relative_error_weighted(
    reference: &[f64],
    test: &[f64],
    weights: Option<&[f64]>,
) -> Result<ErrorStats, MetricError> {
    if let Some(w) = weights {
        if w.len() != reference.len() {
            return Err(MetricError::Length {
                reference: reference.len(),
                test: w.len(),
            });
        }
    }
    if reference.len() != test.len() {
        return Err(MetricError::Length {
            reference: reference.len(),
            test: test.len(),
        });
    }
    if reference.is_empty() {
        return Err(MetricError::Empty);
    }
    let mut n = 0.0;
    let mut sum_ref = 0.0;
    let mut sum_abs = 0.0;
    let mut sum_sq = 0.0;
    for (k, (&r, &t)) in reference.iter().zip(test).enumerate() {
        let w = weights.map_or(1.0, |w| w[k]);
        let w = if w.is_finite() && w > 0.0 { w } else { 0.0 };
        n += w;
        sum_ref += w * r.abs();
        let d = t - r;
        if w > 0.0 {
            sum_abs += w * d.abs();
            sum_sq += w * d * d;
        }
    }
    if !(sum_ref > 0.0 && sum_ref.is_finite()) {
        return Err(MetricError::NoScale);
    }
    let (rel_l1, rel_rmse) = if sum_abs.is_finite() && sum_sq.is_finite() {
        (sum_abs / sum_ref, (sum_sq / n).sqrt() / (sum_ref / n))
    } else {
        (f64::INFINITY, f64::INFINITY)
    };
    Ok(ErrorStats {
        rel_l1,
        rel_rmse,
        count: reference.len(),
    })
}

/// Indices of the points on the Pareto front of (cost, error), both to be
/// minimised, in increasing cost. A point is on the front when no other point
/// is at least as cheap and at least as accurate and better in one of the two.
/// Points with a non-finite coordinate are never on it. Of exact duplicates the
/// first is kept.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].0.is_finite() && points[i].1.is_finite())
        .collect();
    // Cheapest first; among equal costs, the most accurate first, so that the
    // sweep below keeps it and drops the others.
    order.sort_by(|&a, &b| {
        points[a]
            .0
            .total_cmp(&points[b].0)
            .then(points[a].1.total_cmp(&points[b].1))
            .then(a.cmp(&b))
    });
    let mut front = Vec::new();
    let mut best_error = f64::INFINITY;
    for i in order {
        // Strictly better error than every cheaper-or-equal point so far.
        if points[i].1 < best_error {
            best_error = points[i].1;
            front.push(i);
        }
    }
    front
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_signals_have_zero_error() {
        let r = [0.5, 1.0, 2.0, 0.0, 3.5];
        let e = relative_error(&r, &r).unwrap();
        assert_eq!(e.rel_l1, 0.0);
        assert_eq!(e.rel_rmse, 0.0);
        assert_eq!(e.count, 5);
    }

    #[test]
    fn scaled_signal_has_the_scale_as_error() {
        // t = k·r gives Σ|t − r| = |k − 1| Σ|r| exactly, so rel_l1 = |k − 1|.
        // For a constant r = c: rmse = |k − 1| c and mean |r| = c, so rel_rmse
        // = |k − 1| as well. 1e-12 is f64 rounding over five terms.
        let r = [0.25, 1.0, 4.0, 2.0, 0.5];
        let t: Vec<f64> = r.iter().map(|x| 1.1 * x).collect();
        let e = relative_error(&r, &t).unwrap();
        assert!((e.rel_l1 - 0.1).abs() < 1e-12, "{e:?}");
        let c = [3.0; 4];
        let t: Vec<f64> = c.iter().map(|x| 0.8 * x).collect();
        let e = relative_error(&c, &t).unwrap();
        assert!((e.rel_l1 - 0.2).abs() < 1e-12, "{e:?}");
        assert!((e.rel_rmse - 0.2).abs() < 1e-12, "{e:?}");
    }

    #[test]
    fn one_bad_value_weighs_more_in_rmse() {
        // r = 1 everywhere; one of four values off by 1: rel_l1 = 1/4 and
        // rel_rmse = sqrt(1/4) = 1/2.
        let r = [1.0; 4];
        let t = [1.0, 1.0, 2.0, 1.0];
        let e = relative_error(&r, &t).unwrap();
        assert!((e.rel_l1 - 0.25).abs() < 1e-12);
        assert!((e.rel_rmse - 0.5).abs() < 1e-12);
    }

    #[test]
    fn weights_scale_each_value() {
        // r = 1; t = (1, 3): unweighted rel_l1 = 2/2 = 1; weights (3, 1) give
        // (3·0 + 1·2) / (3 + 1) = 0.5, and rel_rmse = sqrt(4/4) / 1 = 1. Zero
        // weight drops a value entirely.
        let r = [1.0, 1.0];
        let t = [1.0, 3.0];
        let e = relative_error_weighted(&r, &t, Some(&[3.0, 1.0])).unwrap();
        assert!((e.rel_l1 - 0.5).abs() < 1e-12, "{e:?}");
        assert!((e.rel_rmse - 1.0).abs() < 1e-12, "{e:?}");
        let e = relative_error_weighted(&r, &t, Some(&[1.0, 0.0])).unwrap();
        assert_eq!(e.rel_l1, 0.0);
        assert!(relative_error_weighted(&r, &t, Some(&[1.0])).is_err());
    }

    #[test]
    fn bad_inputs_are_refused_or_infinite() {
        assert_eq!(
            relative_error(&[1.0], &[1.0, 2.0]),
            Err(MetricError::Length {
                reference: 1,
                test: 2
            })
        );
        assert_eq!(relative_error(&[], &[]), Err(MetricError::Empty));
        assert_eq!(
            relative_error(&[0.0; 3], &[1.0; 3]),
            Err(MetricError::NoScale)
        );
        let e = relative_error(&[1.0, 1.0], &[1.0, f64::NAN]).unwrap();
        assert!(e.rel_l1.is_infinite() && e.rel_rmse.is_infinite());
    }

    #[test]
    fn pareto_front_keeps_only_undominated_points() {
        // (seconds, error). 1 dominates 3 (cheaper and better); 4 is the
        // cheapest; 2 is the most accurate; 5 ties 0 in cost but is worse;
        // 6 is NaN; 7 duplicates 0 exactly.
        let points = [
            (2.0, 0.10),       // 0: front
            (8.0, 0.01),       // 1: front
            (20.0, 0.005),     // 2: front
            (9.0, 0.02),       // 3: dominated by 1
            (1.0, 0.50),       // 4: front
            (2.0, 0.30),       // 5: dominated by 0
            (f64::NAN, 0.001), // 6: never on the front
            (2.0, 0.10),       // 7: duplicate of 0
        ];
        assert_eq!(pareto_front(&points), vec![4, 0, 1, 2]);
        assert!(pareto_front(&[]).is_empty());
        // Along the front, cost rises and error falls strictly.
        let front = pareto_front(&points);
        for w in front.windows(2) {
            assert!(points[w[0]].0 <= points[w[1]].0 && points[w[0]].1 > points[w[1]].1);
        }
    }
}
