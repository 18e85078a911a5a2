//! Progress on the terminal: an indicatif bar when stderr is a terminal, plain
//! lines otherwise (logs, CI), and the closing summary.
//!
//! Everything goes to stderr so that stdout stays free for what scripts read.

use super::eta::{format_count, format_duration, EtaEstimator};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// The figures of a solve at one moment (from `solve::Progress`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Snapshot {
    pub shots: u64,
    pub rays: u64,
    pub unshot_fraction: f64,
    pub elements: u64,
    pub vertices: u64,
}

/// Plain lines come at most this often…
const PLAIN_INTERVAL: Duration = Duration::from_secs(2);
/// …and also whenever the fraction done crosses a multiple of this.
const PLAIN_STEP: f64 = 0.1;
/// The bar has this many ticks for a fraction done of 1.
const BAR_TICKS: u64 = 1000;

enum Output {
    Bar(ProgressBar),
    Plain { last_line: Instant, last_step: i64 },
}

/// Reports a running solve.
pub struct Reporter {
    output: Output,
    eta: EtaEstimator,
    start: Instant,
    /// Seconds spent by earlier sessions of a resumed solve.
    seconds_before: f64,
    /// Rays traced by earlier sessions (rays/s counts this session only).
    rays_before: u64,
    threshold: f64,
}

impl Reporter {
    /// A bar when stderr is a terminal, else plain lines.
    pub fn new(threshold: f64, max_shots: u64, seconds_before: f64, start: Snapshot) -> Self {
        #[allow(clippy::disallowed_methods)] // An edge: the terminal belongs to cli/.
        let output = if std::io::stderr().is_terminal() {
            let bar = ProgressBar::with_draw_target(Some(BAR_TICKS), ProgressDrawTarget::stderr());
            let style = ProgressStyle::with_template(
                "{spinner} [{elapsed}] {wide_bar} {percent:>3}% of the way to the threshold\n  {wide_msg}",
            )
                .unwrap_or_else(|_| ProgressStyle::default_bar());
            bar.set_style(style);
            bar.enable_steady_tick(Duration::from_millis(200));
            Output::Bar(bar)
        } else {
            Output::Plain {
                last_line: Instant::now(),
                last_step: -1,
            }
        };
        let mut eta = EtaEstimator::new(threshold, max_shots);
        eta.observe(seconds_before, start.shots, start.unshot_fraction);
        Reporter {
            output,
            eta,
            start: Instant::now(),
            seconds_before,
            rays_before: start.rays,
            threshold,
        }
    }

    /// Seconds of this session plus those of earlier sessions.
    pub fn total_seconds(&self) -> f64 {
        self.seconds_before + self.start.elapsed().as_secs_f64()
    }

    fn rays_per_second(&self, now: &Snapshot) -> f64 {
        let elapsed = self.start.elapsed().as_secs_f64();
        if elapsed > 0.0 {
            now.rays.saturating_sub(self.rays_before) as f64 / elapsed
        } else {
            0.0
        }
    }

    /// Records the state after a shot and redraws (bar) or maybe prints a line.
    pub fn update(&mut self, now: &Snapshot) {
        self.eta
            .observe(self.total_seconds(), now.shots, now.unshot_fraction);
        let done = self.eta.fraction_done();
        let eta = self
            .eta
            .seconds_left()
            .map_or_else(|| "?".to_string(), format_duration);
        let message = format!(
            "shot {} | unshot {:.2}% (stop {}%) | {} rays/s | {} elements | ETA {}",
            now.shots,
            100.0 * now.unshot_fraction,
            100.0 * self.threshold,
            format_count(self.rays_per_second(now)),
            now.elements,
            eta
        );
        match &mut self.output {
            Output::Bar(bar) => {
                bar.set_position((done * BAR_TICKS as f64) as u64);
                bar.set_message(message);
            }
            Output::Plain {
                last_line,
                last_step,
            } => {
                let step = (done / PLAIN_STEP).floor() as i64;
                if last_line.elapsed() >= PLAIN_INTERVAL || step > *last_step {
                    eprintln!("solver: {:3.0}% {message}", 100.0 * done);
                    *last_line = Instant::now();
                    *last_step = step;
                }
            }
        }
    }

    /// Removes the bar (the summary follows as plain text).
    pub fn finish(&self) {
        if let Output::Bar(bar) = &self.output {
            bar.finish_and_clear();
        }
    }
}
