//! How far a progressive-refinement solve has come, and how long it still needs.
//!
//! Progressive refinement converges roughly geometrically: each shot removes a
//! share of the remaining unshot power, so ln(unshot fraction) falls about linearly
//! in time (Remington 1992, §3.7; Cohen et al. 1988). The estimator fits a straight line to
//! (time, ln u) over a trailing window of samples and extrapolates to
//! ln(threshold). The solve also stops at a shot budget, so the estimate is the
//! sooner of that extrapolation and the budget at the current shot rate.

use std::collections::VecDeque;

/// One observation: seconds since the start, shots so far, unshot fraction.
#[derive(Clone, Copy, Debug)]
struct Sample {
    seconds: f64,
    shots: u64,
    ln_unshot: f64,
}

/// Fits the decay of the unshot fraction and estimates the time left.
#[derive(Debug)]
pub struct EtaEstimator {
    threshold: f64,
    max_shots: u64,
    samples: VecDeque<Sample>,
    window: usize,
}

/// The smallest unshot fraction the estimator takes a logarithm of; below it the
/// solve has converged for every threshold `settings.validate` accepts.
const TINY: f64 = 1e-300;

impl EtaEstimator {
    /// `threshold` and `max_shots` are the two stopping rules of the solve.
    pub fn new(threshold: f64, max_shots: u64) -> Self {
        EtaEstimator {
            threshold: threshold.max(TINY),
            max_shots,
            samples: VecDeque::new(),
            window: 64,
        }
    }

    /// Records the state after a shot.
    pub fn observe(&mut self, seconds: f64, shots: u64, unshot_fraction: f64) {
        let ln_unshot = unshot_fraction.max(TINY).ln();
        if !seconds.is_finite() || !ln_unshot.is_finite() {
            return;
        }
        if self.samples.len() == self.window {
            self.samples.pop_front();
        }
        self.samples.push_back(Sample {
            seconds,
            shots,
            ln_unshot,
        });
    }

    /// Fraction of the way to a stop in [0, 1]: the larger of the log-distance
    /// covered from u = 1 (all emitted power unshot) toward the threshold, and the
    /// share of the shot budget spent.
    pub fn fraction_done(&self) -> f64 {
        let Some(last) = self.samples.back() else {
            return 0.0;
        };
        let ln_threshold = self.threshold.ln(); // < 0 since threshold < 1
        let by_unshot = if ln_threshold < 0.0 {
            (last.ln_unshot / ln_threshold).clamp(0.0, 1.0)
        } else {
            1.0
        };
        let by_budget = if self.max_shots == 0 {
            1.0
        } else {
            (last.shots as f64 / self.max_shots as f64).min(1.0)
        };
        by_unshot.max(by_budget)
    }

    /// Seconds left until the solve stops, or `None` before there is a trend.
    pub fn seconds_left(&self) -> Option<f64> {
        let (first, last) = (self.samples.front()?, self.samples.back()?);
        if self.samples.len() < 3 || last.seconds <= first.seconds {
            return None;
        }
        // Shot budget at the window's shot rate.
        let shot_rate = (last.shots - first.shots) as f64 / (last.seconds - first.seconds);
        let by_budget =
            (shot_rate > 0.0).then(|| self.max_shots.saturating_sub(last.shots) as f64 / shot_rate);
        // Least-squares slope of ln u against time over the window.
        let n = self.samples.len() as f64;
        let mean_t = self.samples.iter().map(|s| s.seconds).sum::<f64>() / n;
        let mean_y = self.samples.iter().map(|s| s.ln_unshot).sum::<f64>() / n;
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for s in &self.samples {
            sxy += (s.seconds - mean_t) * (s.ln_unshot - mean_y);
            sxx += (s.seconds - mean_t) * (s.seconds - mean_t);
        }
        let slope = sxy / sxx; // per second; negative while converging
        let by_unshot = (slope < 0.0 && slope.is_finite())
            .then(|| ((self.threshold.ln() - last.ln_unshot) / slope).max(0.0));
        match (by_unshot, by_budget) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

/// `1:02:03`, `4:05` or `12s`.
pub fn format_duration(seconds: f64) -> String {
    if !seconds.is_finite() || seconds < 0.0 {
        return "?".into();
    }
    let s = seconds.round() as u64;
    let (h, m, s) = (s / 3600, (s / 60) % 60, s % 60);
    if h > 0 {
        format!("{h}:{m:02}:{s:02}")
    } else if m > 0 {
        format!("{m}:{s:02}")
    } else {
        format!("{s}s")
    }
}

/// `12.3 M`, `4.5 k`, `17`: counts for humans.
pub fn format_count(value: f64) -> String {
    if value >= 1e9 {
        format!("{:.2} G", value / 1e9)
    } else if value >= 1e6 {
        format!("{:.2} M", value / 1e6)
    } else if value >= 1e4 {
        format!("{:.1} k", value / 1e3)
    } else {
        format!("{value:.0}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An exact geometric decay u = exp(-k t): the fit is exact, so the estimate
    /// must match the analytic time to reach the threshold to rounding error.
    #[test]
    fn eta_of_exact_exponential_decay_is_exact() {
        let k = 0.5; // per second
        let threshold = 1e-3;
        let mut eta = EtaEstimator::new(threshold, u64::MAX);
        for i in 0..10 {
            let t = i as f64 * 0.25;
            eta.observe(t, i, (-k * t).exp());
        }
        let t_now = 9.0 * 0.25;
        let expected = -threshold.ln() / k - t_now;
        let got = eta.seconds_left().unwrap();
        assert!(
            (got - expected).abs() < 1e-9 * expected,
            "{got} vs {expected}"
        );
    }

    /// With a shot budget that runs out first, the budget decides.
    #[test]
    fn eta_takes_the_sooner_stop() {
        let mut eta = EtaEstimator::new(1e-9, 20);
        for i in 0..10u64 {
            // One shot per second, slow decay.
            eta.observe(i as f64, i, (-0.01 * i as f64).exp());
        }
        let got = eta.seconds_left().unwrap();
        assert!((got - 11.0).abs() < 1e-9, "{got}");
        assert!((eta.fraction_done() - 9.0 / 20.0).abs() < 1e-12);
    }

    #[test]
    fn fraction_done_follows_log_distance() {
        let mut eta = EtaEstimator::new(1e-2, u64::MAX);
        eta.observe(1.0, 1, 1e-1);
        assert!((eta.fraction_done() - 0.5).abs() < 1e-12);
        eta.observe(2.0, 2, 1e-3);
        assert_eq!(eta.fraction_done(), 1.0);
    }

    #[test]
    fn no_estimate_without_trend() {
        let mut eta = EtaEstimator::new(1e-2, u64::MAX);
        assert!(eta.seconds_left().is_none());
        eta.observe(0.0, 0, 1.0);
        eta.observe(0.0, 1, 0.5);
        assert!(eta.seconds_left().is_none());
        // A zero unshot fraction (converged) must not produce NaN.
        eta.observe(1.0, 2, 0.0);
        eta.observe(2.0, 3, 0.0);
        assert!(eta.seconds_left().is_some_and(|s| s.is_finite()));
    }

    #[test]
    fn durations_and_counts_read_well() {
        assert_eq!(format_duration(3723.0), "1:02:03");
        assert_eq!(format_duration(65.0), "1:05");
        assert_eq!(format_duration(7.4), "7s");
        assert_eq!(format_duration(f64::NAN), "?");
        assert_eq!(format_count(12_345_678.0), "12.35 M");
        assert_eq!(format_count(17.0), "17");
    }
}
