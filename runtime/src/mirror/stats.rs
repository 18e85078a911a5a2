//! Frame times: the `--frames` summary (median, p99) and the on-screen figure.

use std::collections::VecDeque;
use std::time::Duration;

/// The `p`-th percentile (0..=100) of sorted values, nearest rank.
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = (p / 100.0 * (sorted.len() - 1) as f64).round() as usize;
    sorted[rank.min(sorted.len() - 1)]
}

/// Every frame interval (for the summary) and the recent ones (for the
/// overlay, averaged over about [`FrameTimes::WINDOW`]).
#[derive(Debug, Default)]
pub struct FrameTimes {
    all_ms: Vec<f64>,
    recent: VecDeque<f64>,
    recent_sum: f64,
}

impl FrameTimes {
    /// How much recent time the on-screen figure averages.
    pub const WINDOW: Duration = Duration::from_millis(500);

    pub fn push(&mut self, ms: f64) {
        self.all_ms.push(ms);
        self.recent.push_back(ms);
        self.recent_sum += ms;
        while self.recent_sum > Self::WINDOW.as_secs_f64() * 1e3 && self.recent.len() > 1 {
            if let Some(old) = self.recent.pop_front() {
                self.recent_sum -= old;
            }
        }
    }

    /// Mean of the recent intervals, ms (None before the first).
    pub fn recent_mean_ms(&self) -> Option<f64> {
        (!self.recent.is_empty()).then(|| self.recent_sum / self.recent.len() as f64)
    }

    /// (count, median ms, p99 ms) over every interval.
    pub fn summary(&self) -> (usize, f64, f64) {
        let mut sorted = self.all_ms.clone();
        sorted.sort_by(f64::total_cmp);
        (
            sorted.len(),
            percentile(&sorted, 50.0),
            percentile(&sorted, 99.0),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_and_p99_by_nearest_rank() {
        let mut t = FrameTimes::default();
        for i in (1..=100).rev() {
            t.push(f64::from(i));
        }
        let (n, median, p99) = t.summary();
        assert_eq!(n, 100);
        // Ranks round(0.5 · 99) = 50 and round(0.99 · 99) = 98 of 1..=100.
        assert_eq!((median, p99), (51.0, 99.0));
        assert_eq!(percentile(&[], 50.0), 0.0);
    }

    #[test]
    fn recent_mean_covers_about_half_a_second() {
        let mut t = FrameTimes::default();
        assert_eq!(t.recent_mean_ms(), None);
        for _ in 0..100 {
            t.push(100.0);
        }
        t.push(10.0);
        // The window keeps intervals summing to at most 500 ms: four of 100 ms
        // and the last 10 ms ones.
        let mean = t.recent_mean_ms().unwrap();
        assert!((mean - 410.0 / 5.0).abs() < 1e-9, "{mean}");
        // One long frame alone still shows.
        let mut t = FrameTimes::default();
        t.push(2000.0);
        assert_eq!(t.recent_mean_ms(), Some(2000.0));
    }
}
