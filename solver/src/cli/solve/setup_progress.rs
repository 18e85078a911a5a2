//! The set-up's progress on the terminal: for each pass that runs long, a
//! line every few seconds with how far it has come and an ETA from its own
//! rate; at the end, one line with every pass's time, the set-up's share of
//! a solve that the benchmarks read.

use super::eta::{format_count, format_duration};
use crate::progress::{Observer, Pass};
use std::time::{Duration, Instant};

/// A pass's progress is printed at most this often, and not before it has
/// run this long (a small scene's set-up prints the summary alone).
const INTERVAL: Duration = Duration::from_secs(3);

pub struct SetupProgress {
    start: Instant,
    /// The pass running, when it started and when its last line was printed.
    current: Option<(Pass, Instant, Instant)>,
    /// Each finished pass and its seconds, in order.
    finished: Vec<(Pass, f64)>,
}

impl SetupProgress {
    pub fn new() -> SetupProgress {
        SetupProgress {
            start: Instant::now(),
            current: None,
            finished: Vec::new(),
        }
    }

    /// Seconds since the set-up began.
    pub fn seconds(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// The set-up's time and each finished pass's.
    pub fn summary(&self) -> String {
        let mut passes: Vec<String> = self
            .finished
            .iter()
            .map(|(pass, s)| format!("{} {s:.1} s", pass.name()))
            .collect();
        let total = self.seconds();
        let timed: f64 = self.finished.iter().map(|(_, s)| s).sum();
        passes.push(format!("the rest {:.1} s", (total - timed).max(0.0)));
        format!("set-up {total:.1} s ({})", passes.join(", "))
    }
}

impl Observer for SetupProgress {
    fn advance(&mut self, pass: Pass, done: u64, total: u64) {
        let now = Instant::now();
        let (started, last) = match self.current {
            Some((p, started, last)) if p == pass => (started, last),
            _ => (now, now),
        };
        if done >= total {
            self.finished
                .push((pass, now.duration_since(started).as_secs_f64()));
            self.current = None;
            return;
        }
        self.current = Some((pass, started, last));
        if now.duration_since(last) >= INTERVAL && done > 0 {
            let elapsed = now.duration_since(started).as_secs_f64();
            let left = elapsed / done as f64 * (total - done) as f64;
            eprintln!(
                "solver: set-up: {} {:.0}% ({} of {} {}) | ETA {}",
                pass.name(),
                100.0 * done as f64 / total as f64,
                format_count(done as f64),
                format_count(total as f64),
                pass.unit(),
                format_duration(left)
            );
            self.current = Some((pass, started, now));
        }
    }
}
