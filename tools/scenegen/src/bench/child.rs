//! Running one solve under a wall-clock limit and measuring it alone.
//!
//! `wait4(2)` returns the resource usage of exactly the child it reaps (its
//! peak resident set and CPU time, threads included), where
//! `getrusage(RUSAGE_CHILDREN)` would report the largest child so far. At the
//! limit the child gets SIGINT, which the solver treats as Ctrl-C: it finishes
//! the current shot, saves its checkpoint and stats and exits 130, so the
//! progress reached is recorded. If it has not exited after the grace period it
//! gets SIGKILL.

use anyhow::{bail, Context};
use std::fs::File;
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// How the child ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ending {
    Exited(i32),
    Signalled(i32),
}

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
    let start = Instant::now();
    let child = command
        .stdin(Stdio::null())
        .stdout(out)
        .stderr(err)
        .spawn()
        .with_context(|| format!("starting {command:?}"))?;
    let pid = child.id() as libc::pid_t;
    let mut status: libc::c_int = 0;
    // SAFETY: `rusage` is a plain C struct for which all-zero bytes are valid.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let mut hit_limit = false;
    let mut killed = false;
    let mut watched_peak_bytes = 0u64;
    let mut poll = FIRST_POLL;
    loop {
        // SAFETY: wait4 writes only through the two pointers, which point at
        // live locals; `pid` is our own child, not yet reaped (std's `Child` is
        // dropped below without waiting, so nothing else reaps it).
        let r = unsafe { libc::wait4(pid, &mut status, libc::WNOHANG, &mut usage) };
        if r == pid {
            break;
        }
        if r == -1 {
            let e = std::io::Error::last_os_error();
            if e.kind() == std::io::ErrorKind::Interrupted {
                continue;
            }
            bail!("waiting for {command:?}: {e}");
        }
        if let Ok(m) = std::fs::metadata(watched) {
            watched_peak_bytes = watched_peak_bytes.max(m.len());
        }
        let elapsed = start.elapsed();
        if !hit_limit && elapsed >= limit {
            hit_limit = true;
            // SAFETY: kill(2) on our own unreaped child: the pid cannot have
            // been reused.
            unsafe { libc::kill(pid, libc::SIGINT) };
        } else if hit_limit && !killed && elapsed >= limit + grace {
            killed = true;
            // SAFETY: as above.
            unsafe { libc::kill(pid, libc::SIGKILL) };
        }
        std::thread::sleep(poll);
        poll = (2 * poll).min(LAST_POLL);
    }
    let wall_seconds = start.elapsed().as_secs_f64();
    drop(child);
    if let Ok(m) = std::fs::metadata(watched) {
        watched_peak_bytes = watched_peak_bytes.max(m.len());
    }
    let seconds = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    let ending = if libc::WIFEXITED(status) {
        Ending::Exited(libc::WEXITSTATUS(status))
    } else {
        Ending::Signalled(libc::WTERMSIG(status))
    };
    Ok(Measured {
        wall_seconds,
        cpu_seconds: seconds(usage.ru_utime) + seconds(usage.ru_stime),
        peak_rss_bytes: (usage.ru_maxrss.max(0) as u64) * 1024,
        ending,
        hit_limit,
        watched_peak_bytes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measures_the_child_and_stops_it_at_the_limit() {
        let dir = tempfile::tempdir().unwrap();
        let log = dir.path().join("log");
        let watched = dir.path().join("watched");
        // dd reads one 64 MiB block into its buffer, touching every page, so
        // its peak resident set is at least 64 MiB.
        let big = run_limited(
            Command::new("dd").args(["if=/dev/zero", "of=/dev/null", "bs=64M", "count=1"]),
            &log,
            Duration::from_secs(60),
            Duration::from_secs(1),
            &watched,
        )
        .unwrap();
        assert!(big.peak_rss_bytes >= 64 << 20, "{big:?}");
        assert_eq!(big.ending, Ending::Exited(0));
        assert!(!big.hit_limit);
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
