//! Running one child program and measuring it alone.
//!
//! `getrusage(RUSAGE_CHILDREN)` reports the largest resident set of *any*
//! waited-for child so far, so after a big reference solve every later point
//! would report the reference's peak. `wait4(2)` returns the resource usage of
//! exactly the child it reaps, which is what each sweep point needs: its own
//! peak resident set and its own CPU time.

use anyhow::{bail, Context};
use std::fs::File;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Instant;

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
    let start = Instant::now();
    let child = command
        .stdin(Stdio::null())
        .stdout(out)
        .stderr(err)
        .spawn()
        .with_context(|| format!("starting {command:?}"))?;
    let pid = child.id() as libc::pid_t;
    let mut status: libc::c_int = 0;
    // SAFETY: `rusage` is a plain C struct for which all-zero bytes are a valid
    // value; wait4 only writes through the two pointers, which point at live
    // locals; `pid` is our own child, not yet reaped (std's `Child` is dropped
    // below without waiting, so nothing else reaps it).
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let reaped = loop {
        // SAFETY: as above.
        let r = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
        if r == -1 && std::io::Error::last_os_error().kind() == std::io::ErrorKind::Interrupted {
            continue;
        }
        break r;
    };
    let wall_seconds = start.elapsed().as_secs_f64();
    drop(child);
    if reaped != pid {
        bail!(
            "waiting for {command:?}: {}",
            std::io::Error::last_os_error()
        );
    }
    let seconds = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    let measured = Measured {
        wall_seconds,
        cpu_seconds: seconds(usage.ru_utime) + seconds(usage.ru_stime),
        peak_rss_bytes: (usage.ru_maxrss.max(0) as u64) * 1024,
    };
    let exited_ok = libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0;
    if !exited_ok {
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
            "{command:?} failed (wait status {status}); log {}:\n{tail}",
            log.display()
        );
    }
    Ok(measured)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measures_only_the_child_it_reaps() {
        let dir = std::env::temp_dir().join(format!("sweep-child-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let log = dir.join("log");
        // A child that touches ~64 MiB reports a peak of at least that; the
        // next, tiny child must not inherit it (what RUSAGE_CHILDREN would do).
        let big = run_measured(
            // dd reads one 64 MiB block into its buffer, touching every page.
            Command::new("dd").args(["if=/dev/zero", "of=/dev/null", "bs=64M", "count=1"]),
            &log,
        )
        .unwrap();
        assert!(big.peak_rss_bytes >= 64 << 20, "{big:?}");
        let small = run_measured(&mut Command::new("true"), &log).unwrap();
        assert!(small.peak_rss_bytes < 32 << 20, "{small:?}");
        assert!(small.wall_seconds >= 0.0 && small.cpu_seconds >= 0.0);
        let failed = run_measured(&mut Command::new("false"), &log).unwrap_err();
        assert!(failed.to_string().contains("failed"), "{failed}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
