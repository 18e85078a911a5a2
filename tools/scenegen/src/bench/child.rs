//! Running one solve under a wall-clock limit and measuring it alone.
//!
//! `wait4(2)` returns the resource usage of exactly the child it reaps (its
//! peak resident set and CPU time, threads included), where
//! `getrusage(RUSAGE_CHILDREN)` would report the largest child so far. At the
//! limit the child gets SIGINT, which the solver treats as Ctrl-C: it finishes
//! the current shot, saves its checkpoint and stats and exits 130, so the
//! progress reached is recorded. If it has not exited after the grace period it
//! gets SIGKILL.

use anyhow::{anyhow, Context};
pub use bench_support::child::Ending;
use bench_support::child::Measuring;
use std::fs::File;
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

/// What one child cost.
#[derive(Clone, Copy, Debug)]
pub struct Measured {
    pub wall_seconds: f64,
    /// User + system CPU seconds of the child and its threads.
    pub cpu_seconds: f64,
    /// Peak resident set, bytes (Linux reports ru_maxrss in KiB).
    pub peak_rss_bytes: u64,
    pub ending: Ending,
    /// Whether the wall-clock limit was reached (SIGINT sent).
    pub hit_limit: bool,
    /// The largest size `watched` had while the child ran (0 if never seen).
    pub watched_peak_bytes: u64,
}

/// How often the child and the watched file are polled: every 5 ms at first,
/// doubling up to every 200 ms, so that a one-second solve's wall time is not
/// rounded up by a whole poll and a long one costs the benchmark nothing.
const FIRST_POLL: Duration = Duration::from_millis(5);
const LAST_POLL: Duration = Duration::from_millis(200);

/// Runs `command` with stdout and stderr to `log`, stops it at `limit`
/// (SIGINT, then SIGKILL after `grace`), and watches the size of `watched`
/// (the checkpoint, which the solver may write and remove during the run).
pub fn run_limited(
    command: &mut Command,
    log: &Path,
    limit: Duration,
    grace: Duration,
    watched: &Path,
) -> anyhow::Result<Measured> {
    #[allow(clippy::disallowed_methods)] // A log the child streams into as it runs, not an output.
    let out = File::create(log).with_context(|| format!("creating {}", log.display()))?;
    let err = out
        .try_clone()
        .with_context(|| format!("duplicating {}", log.display()))?;
    // A bench started in the background by a shell without job control
    // inherits SIGINT ignored, and an ignored signal stays ignored across
    // exec: the child gets the default action back, or the limit's SIGINT
    // would be lost on a child that installs no handler of its own.
    // SAFETY: the closure runs in the forked child before exec and only
    // calls signal(2), which is async-signal-safe.
    unsafe {
        command.pre_exec(|| {
            libc::signal(libc::SIGINT, libc::SIG_DFL);
            Ok(())
        });
    }
    let mut child = Measuring::spawn(command.stdin(Stdio::null()).stdout(out).stderr(err))
        .with_context(|| format!("starting {command:?}"))?;
    let mut hit_limit = false;
    let mut killed = false;
    let mut watched_peak_bytes = 0u64;
    let mut poll = FIRST_POLL;
    let waiting = |e: std::io::Error| anyhow!("waiting for {command:?}: {e}");
    let reaped = loop {
        if let Some(reaped) = child.try_wait().map_err(waiting)? {
            break reaped;
        }
        if let Ok(m) = std::fs::metadata(watched) {
            watched_peak_bytes = watched_peak_bytes.max(m.len());
        }
        let elapsed = child.elapsed();
        if !hit_limit && elapsed >= limit {
            hit_limit = true;
            // The child is not reaped yet, so this cannot fail but for a
            // vanished process, which the next wait4 reports.
            let _ = child.signal(libc::SIGINT);
        } else if hit_limit && !killed && elapsed >= limit + grace {
            killed = true;
            let _ = child.signal(libc::SIGKILL);
        }
        std::thread::sleep(poll);
        poll = (2 * poll).min(LAST_POLL);
    };
    if let Ok(m) = std::fs::metadata(watched) {
        watched_peak_bytes = watched_peak_bytes.max(m.len());
    }
    Ok(Measured {
        wall_seconds: reaped.wall_seconds,
        cpu_seconds: reaped.cpu_seconds,
        peak_rss_bytes: reaped.peak_rss_bytes,
        ending: reaped.ending(),
        hit_limit,
        watched_peak_bytes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stops_the_child_at_the_limit_and_watches_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let log = dir.path().join("log");
        let watched = dir.path().join("watched");
        // The measurement itself (CPU, peak resident set) is tested in
        // bench_support::child; here, what this wrapper adds: the limit and
        // the watched file. A child that ends in time was not stopped, and a
        // file never written has no size.
        let quick = run_limited(
            &mut Command::new("true"),
            &log,
            Duration::from_secs(60),
            Duration::from_secs(1),
            &watched,
        )
        .unwrap();
        assert_eq!(quick.ending, Ending::Exited(0));
        assert!(
            !quick.hit_limit && quick.watched_peak_bytes == 0,
            "{quick:?}"
        );
        // A shell that writes the watched file then sleeps: stopped by SIGINT
        // at the 0.5 s limit (sh's default action for SIGINT is to exit).
        let script = format!(
            "head -c 1234 /dev/zero > {}; exec sleep 30",
            watched.display()
        );
        let stopped = run_limited(
            Command::new("sh").args(["-c", &script]),
            &log,
            Duration::from_millis(500),
            Duration::from_secs(5),
            &watched,
        )
        .unwrap();
        assert!(stopped.hit_limit);
        assert_eq!(stopped.ending, Ending::Signalled(libc::SIGINT));
        assert_eq!(stopped.watched_peak_bytes, 1234);
        assert!(stopped.wall_seconds < 5.0, "{stopped:?}");
    }
}
