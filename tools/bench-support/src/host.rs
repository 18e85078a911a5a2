//! This process's own CPU time and the machine's CPU model, from Linux's /proc.
//! On a shared machine CPU time, unlike wall time, does not grow with other
//! people's load, so the benches print both.

/// CPU seconds (user + system, all threads, exited ones included) of this
/// process so far, from /proc/self/stat in clock ticks (1/100 s on Linux);
/// NaN where /proc is not available.
pub fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| stat_cpu_ticks(&s))
        .map_or(f64::NAN, |ticks| ticks / ticks_per_second())
}

/// utime + stime, in clock ticks, of a /proc/PID/stat line.
fn stat_cpu_ticks(stat: &str) -> Option<f64> {
    // Fields after the parenthesised command name (which may hold spaces and
    // parentheses, hence the last ')'); utime and stime are fields 14 and 15
    // of the whole line, 11 and 12 of what follows ") ".
    let rest = stat.get(stat.rfind(')')? + 2..)?;
    let fields: Vec<&str> = rest.split_whitespace().collect();
    Some(fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?)
}

/// The kernel's clock ticks per second, the unit of /proc's CPU times.
fn ticks_per_second() -> f64 {
    // SAFETY: sysconf takes and returns plain integers.
    let ticks = unsafe { libc::sysconf(libc::_SC_CLK_TCK) };
    // Linux's USER_HZ, should sysconf not know it.
    if ticks > 0 {
        ticks as f64
    } else {
        100.0
    }
}

/// CPU seconds of the threads of this process that are alive now, from
/// /proc/self/task/*/schedstat (nanoseconds): finer than [`cpu_seconds`]'
/// ticks, but a thread that has exited no longer counts. `None` where /proc
/// is not available.
pub fn live_threads_cpu_seconds() -> Option<f64> {
    let mut total = 0.0;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let path = task.ok()?.path().join("schedstat");
        // A thread may exit between the listing and the read: skip it.
        if let Ok(text) = std::fs::read_to_string(path) {
            let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
            total += ns;
        }
    }
    Some(total * 1e-9)
}

/// The CPU's model name from /proc/cpuinfo, or "unknown CPU".
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stat_line_is_read_past_a_command_name_with_spaces_and_parentheses() {
        // utime 7 and stime 5 (fields 14 and 15) behind a name that holds ") ".
        let line = "42 (a) b) S 1 42 42 0 -1 4194560 100 0 0 0 7 5 0 0 20 0 1 0 99";
        assert_eq!(stat_cpu_ticks(line), Some(12.0));
        assert_eq!(stat_cpu_ticks("42 (x) S 1"), None);
        assert_eq!(stat_cpu_ticks("no parenthesis"), None);
    }

    #[test]
    fn cpu_time_counts_at_least_the_work_done_on_this_thread() {
        // This thread spins until its own CPU clock has advanced 50 ms. The
        // process's CPU time (exited threads included, so it never falls when
        // another test's thread ends) grows by at least that, less the tick
        // truncation of its two readings' utime and stime (under two ticks,
        // 20 ms at 100 Hz). The live threads' sum holds this thread's whole
        // run time, at least its clock's reading less one scheduler tick that
        // schedstat may not have accounted yet (at most 10 ms at HZ ≥ 100).
        let thread_cpu = || {
            let mut t = libc::timespec {
                tv_sec: 0,
                tv_nsec: 0,
            };
            // SAFETY: clock_gettime writes one timespec through a pointer to a
            // live local.
            unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
            t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
        };
        let before = cpu_seconds();
        let start = thread_cpu();
        let mut x = 0u64;
        while thread_cpu() - start < 0.05 {
            x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
        }
        let end = thread_cpu();
        let after = cpu_seconds();
        assert!(after - before >= (end - start) - 0.02, "{before} → {after}");
        let live = live_threads_cpu_seconds().unwrap();
        assert!(
            live >= end - 0.01,
            "live threads {live} s, this one {end} s"
        );
        assert!(!cpu_model().is_empty());
    }
}
