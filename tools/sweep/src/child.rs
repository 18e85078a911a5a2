//! Running one child program and measuring it alone.
//!
//! `getrusage(RUSAGE_CHILDREN)` reports the largest resident set of *any*
//! waited-for child so far, so after a big reference solve every later point
//! would report the reference's peak. `wait4(2)` returns the resource usage of
//! exactly the child it reaps, which is what each sweep point needs: its own
//! peak resident set and its own CPU time. The measurement itself is
//! `bench_support::child`; this adds the log file and the error that quotes it.

use anyhow::{anyhow, bail, Context};
use bench_support::child::Measuring;
use std::fs::File;
use std::path::Path;
use std::process::{Command, Stdio};

/// What one finished child cost.
#[derive(Clone, Copy, Debug)]
pub struct Measured {
    /// Wall-clock seconds from spawn to reap.
    pub wall_seconds: f64,
    /// User + system CPU seconds of the child (and its threads).
    pub cpu_seconds: f64,
    /// Peak resident set size, bytes (Linux reports ru_maxrss in KiB).
    pub peak_rss_bytes: u64,
}

/// Runs `command` with stdout and stderr appended to `log`, waits for it and
/// returns its cost; a non-zero exit is an error that quotes the log's tail.
pub fn run_measured(command: &mut Command, log: &Path) -> anyhow::Result<Measured> {
    #[allow(clippy::disallowed_methods)] // A log the child streams into as it runs, not an output.
    let out = File::create(log).with_context(|| format!("creating {}", log.display()))?;
    let err = out
        .try_clone()
        .with_context(|| format!("duplicating {}", log.display()))?;
    let child = Measuring::spawn(command.stdin(Stdio::null()).stdout(out).stderr(err))
        .with_context(|| format!("starting {command:?}"))?;
    let reaped = child
        .wait()
        .map_err(|e| anyhow!("waiting for {command:?}: {e}"))?;
    let measured = Measured {
        wall_seconds: reaped.wall_seconds,
        cpu_seconds: reaped.cpu_seconds,
        peak_rss_bytes: reaped.peak_rss_bytes,
    };
    if !reaped.success() {
        let text = std::fs::read_to_string(log).unwrap_or_default();
        let tail: String = text
            .lines()
            .rev()
            .take(6)
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect::<Vec<_>>()
            .join("\n");
        bail!(
            "{command:?} failed (wait status {}); log {}:\n{tail}",
            reaped.status,
            log.display()
        );
    }
    Ok(measured)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_child_is_an_error_that_quotes_its_log() {
        // The measurement itself is tested in bench_support::child; here, what
        // this wrapper adds: both streams go to the log, and a non-zero exit
        // quotes the log's last lines.
        let dir = std::env::temp_dir().join(format!("sweep-child-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let log = dir.join("log");
        let ok = run_measured(
            Command::new("sh").args(["-c", "echo out; echo err >&2"]),
            &log,
        )
        .unwrap();
        assert!(ok.wall_seconds >= 0.0 && ok.cpu_seconds >= 0.0);
        let text = std::fs::read_to_string(&log).unwrap();
        assert!(text.contains("out") && text.contains("err"), "{text}");
        let failed = run_measured(
            Command::new("sh").args(["-c", "echo the last words >&2; exit 3"]),
            &log,
        )
        .unwrap_err()
        .to_string();
        assert!(
            failed.contains("failed") && failed.contains("the last words"),
            "{failed}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
