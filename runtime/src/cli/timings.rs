//! `--timings`: how long each stage from the command's start to the first frame
//! took, printed on stderr (docs/benchmarks.md, "Opening a solution").

use std::time::{Duration, Instant};

/// Stage durations measured from the command's start.
#[derive(Debug)]
pub struct Timings {
    start: Instant,
    last: Instant,
    stages: Vec<(&'static str, Duration)>,
}

impl Timings {
    pub fn start() -> Timings {
        let now = Instant::now();
        Timings {
            start: now,
            last: now,
            stages: Vec::new(),
        }
    }

    /// Ends stage `name` now.
    pub fn stage(&mut self, name: &'static str) {
        let now = Instant::now();
        self.stages.push((name, now - self.last));
        self.last = now;
    }

    /// Records a stage whose duration was measured elsewhere (inside a longer
    /// stage), without moving the stage boundary.
    pub fn part(&mut self, name: &'static str, duration: Duration) {
        self.stages.push((name, duration));
    }

    /// The upload inside the renderer stage, and its parts.
    pub fn upload(&mut self, total: Duration, stats: crate::render::UploadStats) {
        self.part("of which upload", total);
        self.part("(checksum", stats.checksum);
        self.part("bound", stats.bound);
        self.part("staging copy", stats.staging);
        self.part("waiting for transfers", stats.transfer);
        self.part("chunk partition)", stats.partition);
    }

    /// Time from the start to `at`.
    pub fn since_start(&self, at: Instant) -> Duration {
        at.saturating_duration_since(self.start)
    }

    /// One line: `timings: open 12.3 ms, validate 45.6 ms, ...`.
    pub fn line(&self, first_submit: Option<Instant>) -> String {
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        let mut parts: Vec<String> = self
            .stages
            .iter()
            .map(|(name, d)| format!("{name} {:.1} ms", ms(*d)))
            .collect();
        if let Some(at) = first_submit {
            parts.push(format!(
                "first frame submitted at {:.1} ms",
                ms(self.since_start(at))
            ));
        }
        format!("timings: {}", parts.join(", "))
    }
}
