//! Running one child program and measuring it alone.
//!
//! `getrusage(RUSAGE_CHILDREN)` reports the largest resident set of *any*
//! waited-for child so far, so after one big child every later one would report
//! the big one's peak. `wait4(2)` returns the resource usage of exactly the
//! child it reaps (its peak resident set and its CPU time, threads included),
//! which is what each measured run needs.
//!
//! [`Measuring`] owns the spawned child and is the only thing that reaps it:
//! std's `Child` is kept only for its pipes and is never waited on, so the pid
//! cannot be reaped twice, and a signal is refused once it has been reaped (the
//! pid could then belong to another process).

use std::io;
use std::process::{Child, ChildStderr, Command};
use std::time::{Duration, Instant};

/// How a child ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ending {
    /// It exited with this status.
    Exited(i32),
    /// A signal ended it.
    Signalled(i32),
}

/// What one finished child cost, and how it ended.
#[derive(Clone, Copy, Debug)]
pub struct Reaped {
    /// Wall-clock seconds from just before the spawn to the reap.
    pub wall_seconds: f64,
    /// User + system CPU seconds of the child (and its threads).
    pub cpu_seconds: f64,
    /// Peak resident set size, bytes (Linux reports ru_maxrss in KiB).
    pub peak_rss_bytes: u64,
    /// The raw wait status.
    pub status: libc::c_int,
}

impl Reaped {
    /// How the child ended.
    pub fn ending(&self) -> Ending {
        if libc::WIFEXITED(self.status) {
            Ending::Exited(libc::WEXITSTATUS(self.status))
        } else {
            Ending::Signalled(libc::WTERMSIG(self.status))
        }
    }

    /// Whether the child exited with status 0.
    pub fn success(&self) -> bool {
        self.ending() == Ending::Exited(0)
    }
}

/// A spawned child that only `wait4` reaps.
pub struct Measuring {
    child: Child,
    pid: libc::pid_t,
    start: Instant,
    reaped: bool,
}

impl Measuring {
    /// Spawns `command` as it is configured (its stdio included); the wall
    /// clock starts just before the spawn.
    pub fn spawn(command: &mut Command) -> io::Result<Measuring> {
        let start = Instant::now();
        let child = command.spawn()?;
        Ok(Measuring {
            pid: child.id() as libc::pid_t,
            child,
            start,
            reaped: false,
        })
    }

    /// Time since just before the spawn.
    pub fn elapsed(&self) -> Duration {
        self.start.elapsed()
    }

    /// The child's stderr pipe, if it was spawned with `Stdio::piped()`.
    pub fn take_stderr(&mut self) -> Option<ChildStderr> {
        self.child.stderr.take()
    }

    /// Sends `signal` to the child; an error once it has been reaped.
    pub fn signal(&self, signal: libc::c_int) -> io::Result<()> {
        if self.reaped {
            return Err(io::Error::other("the child has already been reaped"));
        }
        // SAFETY: kill(2) takes plain integers; the pid is our own child, not
        // yet reaped (checked above), so it cannot have been reused.
        if unsafe { libc::kill(self.pid, signal) } == -1 {
            return Err(io::Error::last_os_error());
        }
        Ok(())
    }

    /// Waits for the child to end and returns its cost.
    pub fn wait(mut self) -> io::Result<Reaped> {
        loop {
            if let Some(reaped) = self.reap(0)? {
                return Ok(reaped);
            }
        }
    }

    /// Returns the child's cost if it has ended, `None` if it still runs.
    pub fn try_wait(&mut self) -> io::Result<Option<Reaped>> {
        self.reap(libc::WNOHANG)
    }

    /// One `wait4` call with `flags`; an interrupted call counts as "not yet".
    fn reap(&mut self, flags: libc::c_int) -> io::Result<Option<Reaped>> {
        if self.reaped {
            return Err(io::Error::other("the child has already been reaped"));
        }
        let mut status: libc::c_int = 0;
        // SAFETY: `rusage` is a plain C struct for which all-zero bytes are a
        // valid value.
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        // SAFETY: wait4 writes only through the two pointers, which point at
        // live locals of the right types; `pid` is our own child, not yet
        // reaped (checked above; std's `Child` is never waited on).
        let r = unsafe { libc::wait4(self.pid, &mut status, flags, &mut usage) };
        if r == -1 {
            let e = io::Error::last_os_error();
            if e.kind() == io::ErrorKind::Interrupted {
                return Ok(None);
            }
            return Err(e);
        }
        if r != self.pid {
            return Ok(None);
        }
        self.reaped = true;
        let seconds = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
        Ok(Some(Reaped {
            wall_seconds: self.start.elapsed().as_secs_f64(),
            cpu_seconds: seconds(usage.ru_utime) + seconds(usage.ru_stime),
            peak_rss_bytes: (usage.ru_maxrss.max(0) as u64) * 1024,
            status,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::process::Stdio;

    /// The kernel's clock ticks per second, the unit of /proc's CPU times.
    fn ticks_per_second() -> f64 {
        // SAFETY: sysconf takes and returns plain integers.
        unsafe { libc::sysconf(libc::_SC_CLK_TCK) as f64 }
    }

    #[test]
    fn a_child_that_burns_cpu_reports_at_least_the_cpu_it_burnt() {
        // The shell counts to 300,000 (pure CPU, no I/O), then prints its own
        // user and system time so far (fields 14 and 15 of /proc/PID/stat, in
        // clock ticks) with a builtin, and exits. wait4 reports the shell's CPU
        // time at exit, which is at least what it had used when it printed
        // (CPU time only grows, and both come from the same per-task
        // accounting; ticks are truncated, which only lowers the printed
        // figure). No timing is assumed: a loaded machine stretches the wall
        // time, not the CPU time the count takes.
        let dir = std::env::temp_dir().join(format!("bench-support-cpu-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join("stat");
        let script = "i=0; while [ $i -lt 300000 ]; do i=$((i+1)); done; \
                      read -r stat < /proc/$$/stat; echo \"${stat##*) }\"";
        let reaped = Measuring::spawn(
            Command::new("sh")
                .args(["-c", script])
                .stdin(Stdio::null())
                .stdout(std::fs::File::create(&out).unwrap()),
        )
        .unwrap()
        .wait()
        .unwrap();
        assert!(reaped.success(), "{reaped:?}");
        // After the command name: state is field 3, so utime (14) and stime
        // (15) are at indices 11 and 12 of what follows ") ".
        let text = std::fs::read_to_string(&out).unwrap();
        let fields: Vec<&str> = text.split_whitespace().collect();
        let ticks: f64 = fields[11].parse::<f64>().unwrap() + fields[12].parse::<f64>().unwrap();
        let burnt = ticks / ticks_per_second();
        assert!(burnt > 0.0, "the count burnt no measurable CPU: {text}");
        assert!(reaped.cpu_seconds >= burnt, "{reaped:?} < {burnt} s");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_child_that_touches_memory_reports_at_least_that_peak_and_only_its_own() {
        // dd reads one 64 MiB block into its buffer, writing every page of it,
        // so its resident set reaches at least 64 MiB. The next, tiny child
        // must not inherit that peak (what RUSAGE_CHILDREN would report).
        let quiet = |c: &mut Command| {
            c.stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::null());
        };
        let mut dd = Command::new("dd");
        dd.args(["if=/dev/zero", "of=/dev/null", "bs=64M", "count=1"]);
        quiet(&mut dd);
        let big = Measuring::spawn(&mut dd).unwrap().wait().unwrap();
        assert!(big.success(), "{big:?}");
        assert!(big.peak_rss_bytes >= 64 << 20, "{big:?}");
        let mut tiny = Command::new("true");
        quiet(&mut tiny);
        let small = Measuring::spawn(&mut tiny).unwrap().wait().unwrap();
        assert!(small.peak_rss_bytes < 32 << 20, "{small:?}");
        assert!(small.wall_seconds >= 0.0 && small.cpu_seconds >= 0.0);
        let failed = Measuring::spawn(&mut Command::new("false"))
            .unwrap()
            .wait()
            .unwrap();
        assert_eq!(failed.ending(), Ending::Exited(1));
        assert!(!failed.success());
    }

    #[test]
    fn a_signalled_child_reports_the_signal_and_cannot_be_signalled_after_the_reap() {
        let mut sleeper = Measuring::spawn(
            Command::new("sleep")
                .arg("30")
                .stdin(Stdio::null())
                .stdout(Stdio::null()),
        )
        .unwrap();
        assert!(sleeper.try_wait().unwrap().is_none());
        sleeper.signal(libc::SIGKILL).unwrap();
        let reaped = loop {
            if let Some(r) = sleeper.try_wait().unwrap() {
                break r;
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        };
        assert_eq!(reaped.ending(), Ending::Signalled(libc::SIGKILL));
        assert!(sleeper.signal(libc::SIGKILL).is_err());
        assert!(sleeper.try_wait().is_err());
    }
}
